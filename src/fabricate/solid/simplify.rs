//! Fewer triangles within a tolerance of the exact surface: the marched mesh, refined where its
//! chords cut creases, then simplified by edge collapse.
//!
//! # Method
//! The distance to the union (`Field`) is looked up through a grid of the pieces' boxes, so a
//! point costs a few pieces, not all of them.
//!
//! *Refinement.* Marching tetrahedra puts every vertex on the surface, but a triangle across a
//! crease (where two veins meet) bridges it, and one across a sharp rim (the lamina's, the
//! base's) cuts it off: there the surface is farther from the mesh than the tolerance. An edge
//! whose midpoint is off the surface by more than a quarter of the tolerance outside (a bridge:
//! the crease below it is up to four times farther at a 30° notch) or half of it inside (a cut
//! rim) is split at its midpoint moved onto the surface; split edges are split again, up to
//! eight rounds, which walks the new vertices into the crease.
//!
//! *Simplification.* Garland and Heckbert's quadric error (planes of the triangles around each
//! vertex, weighted by area) orders the edges and places the merged vertex. Edges are collapsed
//! in passes: each pass takes the cheapest edges whose stars share no triangle, so their
//! collapses are independent, checks them all (in parallel) and applies those that pass. A
//! collapse must keep:
//! - the mesh a closed 2-manifold: the link condition (the edge's ends share exactly the two
//!   neighbours across its triangles) and at least three neighbours left;
//! - every triangle turned by less than 70° and not a sliver;
//! - the mesh within the tolerance of the surface, checked on the exact distance at the merged
//!   vertex, the midpoints of its edges and the centres of its triangles. Inside the solid the
//!   union's distance is only a lower bound (where two veins overlap), so a point inside must
//!   also reach the surface along the distance's gradient within the tolerance;
//! - the surface within the tolerance of the mesh: every vertex of the refined mesh (each on the
//!   surface) is a witness, kept by a triangle that replaced the one it had; no collapse may
//!   leave a witness farther than the tolerance, less what the surface may bulge between
//!   witnesses (spacing² / 8r, r the thinnest vein's radius).
//!
//! A rejected edge is not tried again until something around it changes. Collapses go on until
//! a pass makes almost none.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use super::sdf::Primitive;
use crate::mesh::TriMesh;

/// The most grid cells of a `Field`.
const MAX_CELLS: f64 = 4e6;
/// The most (cell, piece) entries of a `Field`: 4 bytes each.
const MAX_ENTRIES: usize = 100_000_000;
/// Rounds of crease refinement.
const REFINE_ROUNDS: usize = 8;
/// Simplification stops after this many passes, or when a pass collapses fewer than
/// `SETTLED` of the vertices.
const MAX_PASSES: usize = 80;
const SETTLED: f64 = 0.002;

/// The signed distance to a union of pieces, through a grid of their boxes: exact where the
/// union's value is within `reach`, at least `reach` (with the right sign) elsewhere.
pub struct Field<'a> {
    prims: &'a [Primitive],
    reach: f64,
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Cell `c`'s pieces are `list[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    list: Vec<u32>,
}

impl<'a> Field<'a> {
    pub fn new(prims: &'a [Primitive], reach: f64) -> Field<'a> {
        let grow = DVec3::splat(reach);
        let boxes: Vec<(DVec3, DVec3)> = prims
            .iter()
            .map(|p| {
                let (a, b) = p.bounds();
                (a - grow, b + grow)
            })
            .collect();
        let (lo, hi) = boxes.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &(a, b)| (lo.min(a), hi.max(b)),
        );
        let size = (hi - lo).max(DVec3::splat(1e-9));
        let mut sides: Vec<f64> = boxes.iter().map(|(a, b)| (*b - *a).max_element()).collect();
        sides.sort_by(f64::total_cmp);
        let median = sides.get(sides.len() / 2).copied().unwrap_or(1.0);
        let mut cell = median.max((size.x * size.y * size.z / MAX_CELLS).cbrt());
        loop {
            let dims = (size / cell).ceil().as_uvec3().max(glam::UVec3::ONE);
            let dims = [dims.x as usize, dims.y as usize, dims.z as usize];
            let range = |a: DVec3, b: DVec3| {
                let c0 = ((a - lo) / cell).floor();
                let c1 = ((b - lo) / cell).floor();
                let r = |k: usize| {
                    let top = dims[k] as f64 - 1.0;
                    (
                        c0[k].clamp(0.0, top) as usize,
                        c1[k].clamp(0.0, top) as usize,
                    )
                };
                [r(0), r(1), r(2)]
            };
            let entries: usize = boxes
                .iter()
                .map(|&(a, b)| {
                    range(a, b)
                        .iter()
                        .map(|(s, e)| e - s + 1)
                        .product::<usize>()
                })
                .sum();
            if entries > MAX_ENTRIES {
                cell *= 2.0;
                continue;
            }
            let cells = dims[0] * dims[1] * dims[2];
            let index = |i: usize, j: usize, k: usize| (i * dims[1] + j) * dims[2] + k;
            let mut count = vec![0u32; cells + 1];
            let each = |f: &mut dyn FnMut(usize, usize)| {
                for (n, &(a, b)) in boxes.iter().enumerate() {
                    let [(i0, i1), (j0, j1), (k0, k1)] = range(a, b);
                    for i in i0..=i1 {
                        for j in j0..=j1 {
                            for k in k0..=k1 {
                                f(index(i, j, k), n);
                            }
                        }
                    }
                }
            };
            each(&mut |c, _| count[c + 1] += 1);
            for c in 0..cells {
                count[c + 1] += count[c];
            }
            let mut fill = count.clone();
            let mut list = vec![0u32; entries];
            each(&mut |c, n| {
                list[fill[c] as usize] = n as u32;
                fill[c] += 1;
            });
            return Field {
                prims,
                reach,
                lo,
                cell,
                dims,
                start: count,
                list,
            };
        }
    }

    /// Signed distance to the union at `p`.
    pub fn eval(&self, p: DVec3) -> f64 {
        self.two(p).0
    }

    /// The two least values of the pieces at `p` (each at most `reach`).
    fn two(&self, p: DVec3) -> (f64, f64) {
        self.pieces(p)
            .iter()
            .fold((self.reach, self.reach), |(d1, d2), &n| {
                let d = self.prims[n as usize].eval(p, self.reach);
                if d < d1 {
                    (d, d1)
                } else {
                    (d1, d2.min(d))
                }
            })
    }

    /// The pieces that may be within `reach` of `p`.
    fn pieces(&self, p: DVec3) -> &[u32] {
        let c = ((p - self.lo) / self.cell).floor();
        if c.min_element() < 0.0 {
            return &[];
        }
        let (i, j, k) = (c.x as usize, c.y as usize, c.z as usize);
        if i >= self.dims[0] || j >= self.dims[1] || k >= self.dims[2] {
            return &[];
        }
        let at = (i * self.dims[1] + j) * self.dims[2] + k;
        &self.list[self.start[at] as usize..self.start[at + 1] as usize]
    }

    /// The distance's gradient at `p` (central differences), unit length or zero.
    fn gradient(&self, p: DVec3, step: f64) -> DVec3 {
        let e = |v: DVec3| self.eval(p + v * step) - self.eval(p - v * step);
        DVec3::new(e(DVec3::X), e(DVec3::Y), e(DVec3::Z)).normalize_or_zero()
    }

    /// `p` moved onto the surface along the gradient (a few Newton steps).
    fn project(&self, p: DVec3, step: f64) -> DVec3 {
        let mut q = p;
        for _ in 0..4 {
            let f = self.eval(q);
            if f.abs() < 1e-7 {
                break;
            }
            q -= self.gradient(q, step) * f;
        }
        q
    }

    /// Whether `p` is within `tol` of the surface: outside the value is the distance; inside
    /// it is one too where one piece alone is near; elsewhere it is only a lower bound, so the
    /// surface must be reached along the gradient within `tol`.
    fn near(&self, p: DVec3, tol: f64) -> bool {
        let (mut f, second) = self.two(p);
        if f >= 0.0 {
            return f <= tol;
        }
        if f < -tol {
            return false;
        }
        // Inside one piece only, the others farther than its surface: the nearest point of
        // that surface is the union's, and the value is the distance.
        if second > -f {
            return true;
        }
        let step = 0.01 * tol;
        let (mut q, mut walked) = (p, 0.0);
        for _ in 0..6 {
            if -f + walked > tol {
                return false;
            }
            let g = self.gradient(q, step);
            if g == DVec3::ZERO {
                return false;
            }
            // Past the surface by a hair, so a step that lands on it ends the walk.
            let s = -f + 1e-7;
            q += g * s;
            walked += s;
            f = self.eval(q);
            if f >= 0.0 {
                return walked <= tol;
            }
        }
        false
    }
}

/// What simplifying did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Simplified {
    pub tolerance_mm: f64,
    /// Triangles as marched, after refinement, and at the end.
    pub marched: usize,
    pub refined: usize,
    pub triangles: usize,
    pub passes: usize,
}

/// Refines and simplifies `mesh` (closed, 2-manifold, oriented, vertices on the surface of
/// `field`, edges about `spacing` long) so it stays within `tol` of the surface, whose least
/// radius of curvature is about `radius`. `progress(done, total)` counts passes.
pub fn simplify(
    mesh: &mut TriMesh,
    field: &Field,
    tol: f64,
    (spacing, radius): (f64, f64),
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Simplified {
    let marched = mesh.triangles.len();
    refine(mesh, field, tol);
    let refined = mesh.triangles.len();
    // Between two witnesses the surface bulges by up to about spacing² / 8r: witnesses are
    // held that much closer.
    let bulge = spacing * spacing / (8.0 * radius.max(1e-9));
    let mut s = Simplifier::new(mesh, field, tol, (tol - bulge).max(0.5 * tol));
    let mut passes = 0;
    while passes < MAX_PASSES {
        passes += 1;
        let made = s.pass(passes as u32);
        if std::env::var_os("LAMINA_DEBUG_SIMPLIFY").is_some() {
            eprintln!(
                "pass {passes}: {made} collapses, {} triangles",
                s.triangles.len()
            );
        }
        progress(passes as u64, MAX_PASSES as u64);
        if (made as f64) < SETTLED * s.live as f64 {
            break;
        }
    }
    s.finish(mesh);
    Simplified {
        tolerance_mm: tol,
        marched,
        refined,
        triangles: mesh.triangles.len(),
        passes,
    }
}

fn edge_key(a: u32, b: u32) -> u64 {
    let (a, b) = (a.min(b), a.max(b));
    (a as u64) << 32 | b as u64
}

/// Splits edges whose midpoints are off the surface (see the module notes).
fn refine(mesh: &mut TriMesh, field: &Field, tol: f64) {
    let step = 0.01 * tol;
    // After the first round only edges to new vertices are looked at again.
    let mut fresh: Option<usize> = None;
    for _ in 0..REFINE_ROUNDS {
        let mut edges: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .filter(|&(a, b)| a < b)
            .filter(|&(_, b)| fresh.is_none_or(|first| b as usize >= first))
            .collect();
        edges.sort_unstable();
        let positions = &mesh.positions;
        let split: Vec<(u32, u32, DVec3)> = edges
            .par_iter()
            .filter_map(|&(a, b)| {
                let m = 0.5 * (positions[a as usize] + positions[b as usize]);
                let f = field.eval(m);
                (f > 0.25 * tol || f < -0.5 * tol).then(|| (a, b, field.project(m, step)))
            })
            .collect();
        if split.is_empty() {
            break;
        }
        let first = mesh.positions.len();
        let mut ends = vec![false; first];
        let mut mid: HashMap<u64, u32, Quick> =
            HashMap::with_capacity_and_hasher(split.len(), Quick);
        for (a, b, p) in split {
            mid.insert(edge_key(a, b), mesh.positions.len() as u32);
            mesh.positions.push(p);
            ends[a as usize] = true;
            ends[b as usize] = true;
        }
        let mut out = Vec::with_capacity(mesh.triangles.len() + 3 * mid.len());
        for &t in &mesh.triangles {
            if !t.iter().any(|&v| ends[v as usize]) {
                out.push(t);
                continue;
            }
            let m = [0, 1, 2].map(|k| mid.get(&edge_key(t[k], t[(k + 1) % 3])).copied());
            out.extend(cut(t, m));
        }
        mesh.triangles = out;
        fresh = Some(first);
    }
}

/// A quick hash for edge keys (the std hasher resists attacks this does not need).
#[derive(Clone, Copy, Default)]
struct Quick;

impl std::hash::BuildHasher for Quick {
    type Hasher = QuickHasher;
    fn build_hasher(&self) -> QuickHasher {
        QuickHasher(0)
    }
}

struct QuickHasher(u64);

impl std::hash::Hasher for QuickHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ b as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        }
    }
    fn write_u64(&mut self, k: u64) {
        self.0 = (self.0 ^ k)
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .rotate_left(29);
    }
}

/// Triangle `t` cut at the midpoints `m[k]` of its edges `(t[k], t[k + 1])`, same orientation.
fn cut(t: [u32; 3], m: [Option<u32>; 3]) -> Vec<[u32; 3]> {
    match m.iter().filter(|x| x.is_some()).count() {
        0 => vec![t],
        3 => {
            let [m0, m1, m2] = m.map(|x| x.unwrap_or_default());
            vec![[t[0], m0, m2], [m0, t[1], m1], [m2, m1, t[2]], [m0, m1, m2]]
        }
        n => {
            // Turn the triangle so edge 0 is cut and, with two cuts, edge 1 as well.
            let r = (0..3)
                .find(|&r| m[r].is_some() && (n == 1 || m[(r + 1) % 3].is_some()))
                .unwrap_or(0);
            let v = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
            let m0 = m[r].unwrap_or_default();
            if n == 1 {
                vec![[v[0], m0, v[2]], [m0, v[1], v[2]]]
            } else {
                let m1 = m[(r + 1) % 3].unwrap_or_default();
                vec![[m0, v[1], m1], [v[0], m0, m1], [v[0], m1, v[2]]]
            }
        }
    }
}

/// A symmetric 4×4 quadric: the sum of squared distances to weighted planes.
#[derive(Clone, Copy, Default)]
struct Quadric {
    a: [f64; 6],
    b: [f64; 3],
    c: f64,
    /// The planes' total weight (area).
    w: f64,
}

impl Quadric {
    fn plane(n: DVec3, p: DVec3, w: f64) -> Quadric {
        let d = -n.dot(p);
        Quadric {
            a: [
                w * n.x * n.x,
                w * n.x * n.y,
                w * n.x * n.z,
                w * n.y * n.y,
                w * n.y * n.z,
                w * n.z * n.z,
            ],
            b: (n * (w * d)).to_array(),
            c: w * d * d,
            w,
        }
    }

    fn add(&self, o: &Quadric) -> Quadric {
        let mut q = *self;
        for k in 0..6 {
            q.a[k] += o.a[k];
        }
        for k in 0..3 {
            q.b[k] += o.b[k];
        }
        q.c += o.c;
        q.w += o.w;
        q
    }

    fn error(&self, v: DVec3) -> f64 {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let av = DVec3::new(
            xx * v.x + xy * v.y + xz * v.z,
            xy * v.x + yy * v.y + yz * v.z,
            xz * v.x + yz * v.y + zz * v.z,
        );
        (v.dot(av) + 2.0 * DVec3::from(self.b).dot(v) + self.c).max(0.0)
    }

    /// The point of least error near the edge `p`–`q`, and that error per unit weight.
    fn best(&self, p: DVec3, q: DVec3) -> (DVec3, f64) {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let m = glam::DMat3::from_cols(
            DVec3::new(xx, xy, xz),
            DVec3::new(xy, yy, yz),
            DVec3::new(xz, yz, zz),
        );
        let det = m.determinant();
        let scale = (xx + yy + zz) / 3.0;
        let mut free = None;
        if det.abs() > 1e-6 * scale.powi(3) {
            let v = m.inverse() * -DVec3::from(self.b);
            // Not far from the edge: a free optimum far away is a flat spot's noise.
            if v.distance(0.5 * (p + q)) <= p.distance(q) {
                free = Some(v);
            }
        }
        let w = self.w.max(1e-300);
        [p, q, 0.5 * (p + q)]
            .into_iter()
            .chain(free)
            .map(|v| (v, self.error(v) / w))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((p, 0.0))
    }
}

/// A checked collapse: `b` into `a`, which moves to `to`; witnesses handed to triangles.
struct Collapse {
    a: u32,
    b: u32,
    to: DVec3,
    witnesses: Vec<(u32, u32)>,
}

struct Simplifier<'f, 'a> {
    field: &'f Field<'a>,
    tol: f64,
    /// How near each witness must stay.
    witness_tol: f64,
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    quadrics: Vec<Quadric>,
    /// Surface points the mesh must stay near, and the triangle that keeps each.
    witness: Vec<DVec3>,
    owner: Vec<u32>,
    /// The pass in which each vertex's star last changed, and edges rejected (by the pass).
    changed: Vec<u32>,
    rejected: HashMap<u64, u32, Quick>,
    /// Vertices in use.
    live: usize,
    // Per pass: vertex -> triangles, triangle -> witnesses.
    vt_start: Vec<u32>,
    vt: Vec<u32>,
    tw_start: Vec<u32>,
    tw: Vec<u32>,
}

impl<'f, 'a> Simplifier<'f, 'a> {
    fn new(mesh: &TriMesh, field: &'f Field<'a>, tol: f64, witness_tol: f64) -> Self {
        let n = mesh.positions.len();
        let mut quadrics = vec![Quadric::default(); n];
        let mut owner = vec![u32::MAX; n];
        for (k, t) in mesh.triangles.iter().enumerate() {
            let p = t.map(|v| mesh.positions[v as usize]);
            let c = (p[1] - p[0]).cross(p[2] - p[0]);
            let area = 0.5 * c.length();
            let q = Quadric::plane(c.normalize_or_zero(), p[0], area);
            for &v in t {
                quadrics[v as usize] = quadrics[v as usize].add(&q);
                if owner[v as usize] == u32::MAX {
                    owner[v as usize] = k as u32;
                }
            }
        }
        let used = owner.iter().filter(|&&o| o != u32::MAX).count();
        let (witness, owner) = mesh
            .positions
            .iter()
            .zip(&owner)
            .filter(|(_, &o)| o != u32::MAX)
            .map(|(&p, &o)| (p, o))
            .unzip();
        Simplifier {
            field,
            tol,
            witness_tol,
            positions: mesh.positions.clone(),
            triangles: mesh.triangles.clone(),
            quadrics,
            witness,
            owner,
            changed: vec![0; n],
            rejected: HashMap::with_hasher(Quick),
            live: used,
            vt_start: Vec::new(),
            vt: Vec::new(),
            tw_start: Vec::new(),
            tw: Vec::new(),
        }
    }

    fn star(&self, v: u32) -> &[u32] {
        &self.vt[self.vt_start[v as usize] as usize..self.vt_start[v as usize + 1] as usize]
    }

    fn witnesses(&self, t: u32) -> &[u32] {
        &self.tw[self.tw_start[t as usize] as usize..self.tw_start[t as usize + 1] as usize]
    }

    /// Counting sort of `keys` into (start, items).
    fn group(n: usize, items: impl Iterator<Item = (u32, u32)> + Clone) -> (Vec<u32>, Vec<u32>) {
        let mut start = vec![0u32; n + 1];
        for (k, _) in items.clone() {
            start[k as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut out = vec![0u32; start[n] as usize];
        for (k, v) in items {
            out[fill[k as usize] as usize] = v;
            fill[k as usize] += 1;
        }
        (start, out)
    }

    /// One pass; returns how many edges collapsed.
    fn pass(&mut self, pass: u32) -> usize {
        let tris = &self.triangles;
        (self.vt_start, self.vt) = Self::group(
            self.positions.len(),
            tris.iter()
                .enumerate()
                .flat_map(|(k, t)| t.map(|v| (v, k as u32))),
        );
        (self.tw_start, self.tw) = Self::group(
            tris.len(),
            self.owner.iter().enumerate().map(|(w, &t)| (t, w as u32)),
        );

        // Candidates, cheapest first.
        let tol2 = self.tol * self.tol;
        let mut edges: Vec<(f64, u32, u32)> = self
            .triangles
            .par_iter()
            .flat_map_iter(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .filter(|&(a, b)| a < b)
            .filter(|&(a, b)| {
                self.rejected.get(&edge_key(a, b)).is_none_or(|&when| {
                    self.changed[a as usize].max(self.changed[b as usize]) >= when
                })
            })
            .filter_map(|(a, b)| {
                let q = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
                let (_, e) = q.best(self.positions[a as usize], self.positions[b as usize]);
                (e <= tol2).then_some((e, a, b))
            })
            .collect();
        edges.par_sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));

        // Rounds of independent ones (stars that share no triangle), checked in parallel;
        // what a failed check held is free for the next round. A triangle changed this pass
        // is not touched again until the next.
        const CHANGED: u32 = u32::MAX;
        let mut claim = vec![0u32; self.triangles.len()];
        let mut dead = vec![false; self.triangles.len()];
        let mut open: Vec<(u32, u32)> = edges.iter().map(|&(_, a, b)| (a, b)).collect();
        let mut made = 0;
        for round in 1..=4u32 {
            let mut chosen = Vec::new();
            let mut later = Vec::new();
            for &(a, b) in &open {
                let stars = || self.star(a).iter().chain(self.star(b));
                if stars().any(|&t| claim[t as usize] == CHANGED) {
                    continue;
                }
                if stars().any(|&t| claim[t as usize] == round) {
                    later.push((a, b));
                    continue;
                }
                for &t in stars() {
                    claim[t as usize] = round;
                }
                chosen.push((a, b));
            }
            if chosen.is_empty() {
                break;
            }
            let checked: Vec<Result<Collapse, (u32, u32)>> = chosen
                .par_iter()
                .map(|&(a, b)| self.check(a, b).ok_or((a, b)))
                .collect();
            for c in checked {
                match c {
                    Ok(c) => {
                        made += 1;
                        for &t in self.star(c.a).iter().chain(self.star(c.b)) {
                            claim[t as usize] = CHANGED;
                        }
                        self.apply(&c, pass, &mut dead);
                    }
                    Err((a, b)) => {
                        self.rejected.insert(edge_key(a, b), pass);
                    }
                }
            }
            open = later;
        }
        // Compact the triangles; witnesses follow theirs.
        let mut remap = vec![u32::MAX; self.triangles.len()];
        let mut kept = Vec::with_capacity(self.triangles.len());
        for (k, t) in self.triangles.iter().enumerate() {
            if !dead[k] {
                remap[k] = kept.len() as u32;
                kept.push(*t);
            }
        }
        self.triangles = kept;
        for o in &mut self.owner {
            *o = remap[*o as usize];
        }
        made
    }

    /// Checks collapsing `b` into `a` (see the module notes).
    fn check(&self, a: u32, b: u32) -> Option<Collapse> {
        let (sa, sb) = (self.star(a), self.star(b));
        let ring = |s: &[u32], me: u32| {
            let mut r: Vec<u32> = s
                .iter()
                .flat_map(|&t| self.triangles[t as usize])
                .filter(|&v| v != me)
                .collect();
            r.sort_unstable();
            r.dedup();
            r
        };
        let (ra, rb) = (ring(sa, a), ring(sb, b));
        let common = ra.iter().filter(|v| rb.binary_search(v).is_ok()).count();
        // `a` is in b's ring and b in a's; the two across the edge are common.
        if common != 2 {
            return None;
        }
        let mut around: Vec<u32> = ra.iter().chain(&rb).copied().collect();
        around.sort_unstable();
        around.dedup();
        around.retain(|&v| v != a && v != b);
        if around.len() < 3 {
            return None;
        }
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let q = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        let (to, _) = q.best(pa, pb);

        let mut stars: Vec<u32> = sa.iter().chain(sb).copied().collect();
        stars.sort_unstable();
        stars.dedup();
        // The triangles that stay, as they will be.
        let mut new: Vec<(u32, [DVec3; 3])> = Vec::with_capacity(stars.len());
        let mut gone = 0;
        let cos_max = 70f64.to_radians().cos();
        for &t in &stars {
            let tri = self.triangles[t as usize];
            if tri.contains(&a) && tri.contains(&b) {
                gone += 1;
                continue;
            }
            let old = tri.map(|v| self.positions[v as usize]);
            let p = tri.map(|v| {
                if v == a || v == b {
                    to
                } else {
                    self.positions[v as usize]
                }
            });
            let n_old = (old[1] - old[0]).cross(old[2] - old[0]).normalize_or_zero();
            let c = (p[1] - p[0]).cross(p[2] - p[0]);
            let len2 = (p[1] - p[0]).length_squared()
                + (p[2] - p[1]).length_squared()
                + (p[0] - p[2]).length_squared();
            // 1 for an equilateral triangle, 0 for a flat one.
            let quality = 2.0 * 3f64.sqrt() * c.length() / len2.max(1e-300);
            if c.normalize_or_zero().dot(n_old) < cos_max || quality < 0.05 {
                return None;
            }
            new.push((t, p));
        }
        if gone != 2 {
            return None;
        }

        // The mesh near the surface.
        let tol = self.tol;
        if !self.field.near(to, tol) {
            return None;
        }
        for &v in &around {
            if !self
                .field
                .near(0.5 * (to + self.positions[v as usize]), tol)
            {
                return None;
            }
        }
        for (_, p) in &new {
            if !self.field.near((p[0] + p[1] + p[2]) / 3.0, tol) {
                return None;
            }
        }
        // The surface near the mesh.
        let mut witnesses = Vec::new();
        for &t in &stars {
            for &w in self.witnesses(t) {
                let x = self.witness[w as usize];
                // Any triangle within the tolerance keeps it: first the one that replaces
                // its own.
                let own = new.iter().position(|(k, _)| *k == t).unwrap_or(0);
                let k = (0..new.len())
                    .map(|i| (i + own) % new.len())
                    .find(|&i| point_triangle(x, &new[i].1) <= self.witness_tol)?;
                witnesses.push((w, new[k].0));
            }
        }
        Some(Collapse {
            a,
            b,
            to,
            witnesses,
        })
    }

    fn apply(&mut self, c: &Collapse, pass: u32, dead: &mut [bool]) {
        let (a, b) = (c.a, c.b);
        let stars: Vec<u32> = self.star(a).iter().chain(self.star(b)).copied().collect();
        for &t in &stars {
            let tri = &mut self.triangles[t as usize];
            if tri.contains(&a) && tri.contains(&b) {
                dead[t as usize] = true;
                continue;
            }
            for v in tri.iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            for &v in tri.iter() {
                self.changed[v as usize] = pass;
            }
        }
        self.positions[a as usize] = c.to;
        self.quadrics[a as usize] = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        self.live -= 1;
        for &(w, t) in &c.witnesses {
            self.owner[w as usize] = t;
        }
    }

    /// The simplified mesh, its unused vertices dropped.
    fn finish(self, mesh: &mut TriMesh) {
        let mut index = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::new();
        let mut triangles = self.triangles;
        for t in &mut triangles {
            for v in t.iter_mut() {
                if index[*v as usize] == u32::MAX {
                    index[*v as usize] = positions.len() as u32;
                    positions.push(self.positions[*v as usize]);
                }
                *v = index[*v as usize];
            }
        }
        mesh.positions = positions;
        mesh.triangles = triangles;
        mesh.colors = None;
    }
}

/// Distance from `x` to the triangle `p`.
fn point_triangle(x: DVec3, p: &[DVec3; 3]) -> f64 {
    let (a, b, c) = (p[0], p[1], p[2]);
    let (ab, ac, ax) = (b - a, c - a, x - a);
    let n = ab.cross(ac);
    let nn = n.length_squared();
    if nn > 0.0 {
        // Inside the prism over the triangle: the distance to its plane.
        let inside = |u: DVec3, v: DVec3, w: DVec3| n.dot((v - u).cross(w - u)) >= 0.0;
        if inside(a, b, x) && inside(b, c, x) && inside(c, a, x) {
            return n.dot(ax).abs() / nn.sqrt();
        }
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(u, v)| {
            let e = v - u;
            let t = if e.length_squared() > 0.0 {
                ((x - u).dot(e) / e.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            x.distance(u + e * t)
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_over_a_triangle_is_its_height_and_beside_it_the_nearest_edge() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!((point_triangle(DVec3::new(0.2, 0.2, 0.5), &t) - 0.5).abs() < 1e-12);
        assert!((point_triangle(DVec3::new(2.0, 0.0, 0.0), &t) - 1.0).abs() < 1e-12);
        assert!((point_triangle(DVec3::new(0.5, -1.0, 0.0), &t) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn cut_triangles_keep_their_orientation_and_area() {
        let p = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::new(0.5, 0.0, 0.0),
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(0.0, 0.5, 0.0),
        ];
        let area = |t: &[u32; 3]| {
            let q = t.map(|v| p[v as usize]);
            0.5 * (q[1] - q[0]).cross(q[2] - q[0]).z
        };
        for mask in 0..8u32 {
            let m = [0, 1, 2].map(|k| (mask >> k & 1 == 1).then_some(3 + k as u32));
            let made = cut([0, 1, 2], m);
            assert_eq!(made.len(), 1 + mask.count_ones() as usize);
            assert!(made.iter().all(|t| area(t) > 0.0));
            let total: f64 = made.iter().map(area).sum();
            assert!((total - 0.5).abs() < 1e-12);
        }
    }
}
