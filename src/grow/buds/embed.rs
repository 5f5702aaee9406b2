//! Positions of the cells: a spring embedder in 3D (Kamada and Kawai 1989, as Hart adapts it).
//!
//! Every pair of cells within [`HOPS`] hops is a spring whose rest length is the hop distance
//! times the pair's mean cell size, with stiffness 1/hops² (Kamada-Kawai). One cell moves at a
//! time by a Newton step on its own energy; the 3×3 Hessian is made positive definite by
//! damping when springs are compressed, and the step is capped at half a cell.
//!
//! Cells that are close in space but more than [`HOPS`] hops apart are different parts of the
//! form touching: they repel within the clearance, and [`Embedding::crowded`] reports them so
//! the bud that caused it can freeze. A spatial hash keeps both queries local.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use glam::{DMat3, DVec3};
use nalgebra::{Matrix3, Vector3};

use super::graph::CellGraph;
use crate::geom::KeyHasher;
use crate::mesh::intersect::triangles_meet;

/// Springs join cells up to this many hops apart (the paper: four).
pub const HOPS: u8 = 4;

/// A Newton step shorter than this many cell sizes is not taken.
pub const SETTLED: f64 = 5e-3;

/// Cells closer than the clearance but more hops apart than this are different parts of the
/// form colliding. Nearer in the graph, they are the two sides of a fold or a valley between
/// lumps, which the contact term keeps apart without freezing anyone.
pub const COLLIDE_HOPS: u8 = 10;

/// The cells, their positions and sizes, and the index that finds neighbours in space.
#[derive(Clone)]
pub struct Embedding {
    pub pos: Vec<DVec3>,
    pub size: Vec<f64>,
    /// Distance, in units of the pair's mean cell size, at which parts of the form collide.
    pub clearance: f64,
    grid: SpatialHash,
    stamp: Vec<u32>,
    epoch: u32,
    reach: Vec<(u32, u8)>,
    scratch: Vec<u32>,
    mark: Vec<u32>,
    mark_epoch: u32,
    /// No edge is longer than this (grown as edges are measured, renewed by `remeasure`).
    longest: f64,
}

impl Embedding {
    /// `largest` is the largest cell size the form will have: it sets the hash's bucket size.
    pub fn new(pos: Vec<DVec3>, size: Vec<f64>, clearance: f64, largest: f64) -> Embedding {
        // Buckets wide enough that the triangle check's reach spans few of them.
        let mut grid = SpatialHash::new(clearance.max(1.7) * largest);
        for (v, p) in pos.iter().enumerate() {
            grid.insert(v as u32, *p);
        }
        let n = pos.len();
        Embedding {
            pos,
            size,
            clearance,
            grid,
            stamp: vec![0; n],
            epoch: 0,
            reach: Vec::new(),
            scratch: Vec::new(),
            mark: vec![0; n],
            mark_epoch: 0,
            longest: 1.0,
        }
    }

    /// Adds or moves cell `v` to `p`.
    pub fn place(&mut self, v: u32, p: DVec3, size: f64) {
        let i = v as usize;
        if i >= self.pos.len() {
            self.pos.resize(i + 1, p);
            self.size.resize(i + 1, size);
            self.stamp.resize(i + 1, 0);
            self.mark.resize(i + 1, 0);
            self.pos[i] = p;
            self.grid.insert(v, p);
        } else {
            self.grid.relocate(v, self.pos[i], p);
            self.pos[i] = p;
        }
        self.size[i] = size;
    }

    /// Raises the bound on edge length to cover the edges of `v`.
    pub fn measure(&mut self, g: &CellGraph, v: u32) {
        let x = self.pos[v as usize];
        for &u in g.neighbours(v) {
            self.longest = self.longest.max(x.distance(self.pos[u as usize]));
        }
    }

    /// Measures every edge again: the bound on edge length falls back to the longest there is.
    pub fn remeasure(&mut self, g: &CellGraph) {
        let mut longest = 0.0f64;
        for v in 0..g.len() as u32 {
            for &u in g.neighbours(v) {
                longest = longest.max(self.pos[v as usize].distance(self.pos[u as usize]));
            }
        }
        self.longest = longest;
    }

    /// Forgets the cells from `len` on (an undone division).
    pub fn truncate(&mut self, len: usize) {
        while self.pos.len() > len {
            let v = self.pos.len() - 1;
            self.grid.remove(v as u32, self.pos[v]);
            self.pos.pop();
            self.size.pop();
            self.stamp.pop();
            self.mark.pop();
        }
    }

    /// Marks the cells within `hops` of `v` (in `reach`, with their hop counts, `v` first).
    fn explore(&mut self, g: &CellGraph, v: u32, hops: u8) {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.epoch = 1;
        }
        self.reach.clear();
        self.reach.push((v, 0));
        self.stamp[v as usize] = self.epoch;
        let mut head = 0;
        while head < self.reach.len() {
            let (u, h) = self.reach[head];
            head += 1;
            if h == hops {
                continue;
            }
            for &w in g.neighbours(u) {
                if self.stamp[w as usize] != self.epoch {
                    self.stamp[w as usize] = self.epoch;
                    self.reach.push((w, h + 1));
                }
            }
        }
    }

    /// Moves cell `v` by one damped Newton step on its spring and contact energy; returns the
    /// distance moved.
    pub fn relax(&mut self, g: &CellGraph, v: u32) -> f64 {
        self.explore(g, v, HOPS);
        let x = self.pos[v as usize];
        let sv = self.size[v as usize];
        let mut grad = DVec3::ZERO;
        let mut hess = DMat3::ZERO;
        for &(u, h) in &self.reach[1..] {
            let d = x - self.pos[u as usize];
            let len = d.length().max(1e-9);
            let h = h as f64;
            let rest = h * 0.5 * (sv + self.size[u as usize]);
            let k = 1.0 / (h * h);
            let t = 1.0 - rest / len;
            if h == 1.0 {
                self.longest = self.longest.max(len);
            }
            grad += k * t * d;
            hess +=
                k * (DMat3::from_diagonal(DVec3::splat(t)) + outer(d, d) * (rest / len.powi(3)));
        }
        let (stamp, epoch, size, pos) = (&self.stamp, self.epoch, &self.size, &self.pos);
        let clearance = self.clearance;
        self.grid.near(x, |u| {
            if stamp[u as usize] == epoch {
                return;
            }
            let c = clearance * 0.5 * (sv + size[u as usize]);
            let d = x - pos[u as usize];
            let len = d.length();
            if len < c && len > 1e-12 {
                // Contact energy (c − len)², Gauss-Newton Hessian.
                let n = d / len;
                grad -= 4.0 * (c - len) * n;
                hess += 4.0 * outer(n, n);
            }
        });
        let step = damped_newton(hess, grad);
        let cap = 0.5 * sv;
        let mut step = if step.length() > cap {
            step * (cap / step.length())
        } else {
            step
        };
        // A thousandth of a cell is not worth the check below: settled cells stay put.
        if !step.is_finite() || step.length() < SETTLED * sv {
            return 0.0;
        }
        // A move that would make the cell's triangles meet another is halved, then given up:
        // the surface never passes through itself.
        for _ in 0..3 {
            if self.star_clear(g, v, x + step) {
                self.place(v, x + step, sv);
                self.measure(g, v);
                return step.length();
            }
            step *= 0.5;
        }
        0.0
    }

    /// Whether the triangles round `v`, with `v` at `y`, meet no other triangle of the form
    /// and do not fold onto each other. Checked against the triangles of the cells within two
    /// hops and of every cell within reach in space.
    pub fn star_clear(&mut self, g: &CellGraph, v: u32, y: DVec3) -> bool {
        let ring = g.neighbours(v);
        let at = |c: u32| if c == v { y } else { self.pos[c as usize] };
        let star: Vec<([u32; 3], [DVec3; 3])> = (0..ring.len())
            .map(|k| {
                let t = [v, ring[k], ring[(k + 1) % ring.len()]];
                (t, t.map(at))
            })
            .collect();
        for k in 0..star.len() {
            for l in k + 1..star.len() {
                if triangles_meet(star[k].0, star[k].1, star[l].0, star[l].1) {
                    return false;
                }
            }
        }
        let radius = ring
            .iter()
            .map(|&r| y.distance(self.pos[r as usize]))
            .fold(0.0, f64::max);
        let mut cells = std::mem::take(&mut self.scratch);
        cells.clear();
        self.mark_epoch = self.mark_epoch.wrapping_add(1);
        if self.mark_epoch == 0 {
            self.mark.iter_mut().for_each(|m| *m = 0);
            self.mark_epoch = 1;
        }
        let (mark, epoch) = (&mut self.mark, self.mark_epoch);
        let mut add = |c: u32| {
            if mark[c as usize] != epoch {
                mark[c as usize] = epoch;
                cells.push(c);
            }
        };
        for &r in ring {
            add(r);
            g.neighbours(r).iter().for_each(|&c| add(c));
        }
        // Far triangles that reach the star have a corner within an edge of it.
        let far = radius + self.longest.max(self.size[v as usize]);
        let pos = &self.pos;
        self.grid.near_radius(y, far, |c| {
            if pos[c as usize].distance_squared(y) <= far * far {
                add(c);
            }
        });
        let (mut lo, mut hi) = (y, y);
        for (_, q) in &star {
            for p in q {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        let mut clear = true;
        'cells: for &c in &cells {
            let cr = g.neighbours(c);
            for k in 0..cr.len() {
                let (a, b) = (cr[k], cr[(k + 1) % cr.len()]);
                // Each face once, at its smallest cell; the star's own faces are done above.
                if a < c || b < c || c == v || a == v || b == v {
                    continue;
                }
                let t = [c, a, b];
                let p = t.map(at);
                let below = p[0].max(p[1]).max(p[2]).cmplt(lo);
                let above = p[0].min(p[1]).min(p[2]).cmpgt(hi);
                if (below | above).any() {
                    continue;
                }
                if star.iter().any(|(s, q)| triangles_meet(*s, *q, t, p)) {
                    clear = false;
                    break 'cells;
                }
            }
        }
        self.scratch = cells;
        clear
    }

    /// A cell within the clearance of one of `cells` (a division's children and ring, round
    /// `centre`) but more than [`COLLIDE_HOPS`] + 1 hops from `centre`: one search serves all.
    pub fn crowded(&mut self, g: &CellGraph, centre: u32, cells: &[u32]) -> Option<u32> {
        self.explore(g, centre, COLLIDE_HOPS + 1);
        let (stamp, epoch, size, pos) = (&self.stamp, self.epoch, &self.size, &self.pos);
        let clearance = self.clearance;
        let mut hit = None;
        for &v in cells {
            let x = pos[v as usize];
            let sv = size[v as usize];
            self.grid.near(x, |u| {
                if hit.is_none()
                    && stamp[u as usize] != epoch
                    && x.distance(pos[u as usize]) < clearance * 0.5 * (sv + size[u as usize])
                {
                    hit = Some(u);
                }
            });
            if hit.is_some() {
                break;
            }
        }
        hit
    }

    /// The cells within `hops` of `v`, `v` first, nearer first.
    pub fn within(&mut self, g: &CellGraph, v: u32, hops: u8) -> Vec<(u32, u8)> {
        self.explore(g, v, hops);
        self.reach.clone()
    }

    /// Cells within `radius` of a point.
    pub fn near(&self, p: DVec3, radius: f64, mut f: impl FnMut(u32)) {
        self.grid.near_radius(p, radius, |u| {
            if self.pos[u as usize].distance(p) <= radius {
                f(u);
            }
        });
    }

    /// The cell's outward normal (see [`cell_normal`]).
    pub fn normal(&self, g: &CellGraph, v: u32) -> DVec3 {
        cell_normal(g, &self.pos, v)
    }
}

/// A cell's outward normal: the area-weighted normal of its faces.
pub fn cell_normal(g: &CellGraph, pos: &[DVec3], v: u32) -> DVec3 {
    let ring = g.neighbours(v);
    let x = pos[v as usize];
    let mut n = DVec3::ZERO;
    for k in 0..ring.len() {
        let a = pos[ring[k] as usize] - x;
        let b = pos[ring[(k + 1) % ring.len()] as usize] - x;
        n += a.cross(b);
    }
    n.normalize_or_zero()
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Solves (H + μI) s = −g with the smallest μ (0, then growing) that makes the matrix positive
/// definite.
fn damped_newton(h: DMat3, g: DVec3) -> DVec3 {
    let scale = (h.x_axis.x.abs() + h.y_axis.y.abs() + h.z_axis.z.abs()).max(1e-9);
    let mut mu = 0.0;
    for _ in 0..40 {
        let m = h + DMat3::from_diagonal(DVec3::splat(mu));
        if let Some(s) = cholesky_solve(m, -g) {
            return s;
        }
        mu = if mu == 0.0 { 1e-3 * scale } else { mu * 4.0 };
    }
    -g / scale
}

/// Solves m s = b by Cholesky, refusing a matrix that is not clearly positive definite: a pivot
/// at most 1e-14 of the first (a near-singular Hessian would give a huge step).
fn cholesky_solve(m: DMat3, b: DVec3) -> Option<DVec3> {
    let m = Matrix3::from_column_slice(&m.to_cols_array());
    let chol = m.cholesky()?;
    let l = chol.l_dirty();
    let first = l[(0, 0)] * l[(0, 0)];
    if (1..3).any(|i| l[(i, i)] * l[(i, i)] <= 1e-14 * first) {
        return None;
    }
    let s = chol.solve(&Vector3::new(b.x, b.y, b.z));
    Some(DVec3::new(s[0], s[1], s[2]))
}

type Key = (i32, i32, i32);

/// Cells bucketed by a cubic grid.
#[derive(Clone)]
struct SpatialHash {
    width: f64,
    buckets: HashMap<Key, Vec<u32>, BuildHasherDefault<KeyHasher>>,
}

impl SpatialHash {
    fn new(width: f64) -> SpatialHash {
        SpatialHash {
            width: width.max(1e-9),
            buckets: HashMap::default(),
        }
    }

    fn key(&self, p: DVec3) -> Key {
        let k = (p / self.width).floor();
        (k.x as i32, k.y as i32, k.z as i32)
    }

    fn insert(&mut self, v: u32, p: DVec3) {
        let k = self.key(p);
        self.buckets.entry(k).or_default().push(v);
    }

    fn remove(&mut self, v: u32, at: DVec3) {
        if let Some(bucket) = self.buckets.get_mut(&self.key(at)) {
            if let Some(k) = bucket.iter().position(|&u| u == v) {
                bucket.swap_remove(k);
            }
        }
    }

    fn relocate(&mut self, v: u32, from: DVec3, to: DVec3) {
        let (a, b) = (self.key(from), self.key(to));
        if a == b {
            return;
        }
        if let Some(bucket) = self.buckets.get_mut(&a) {
            if let Some(k) = bucket.iter().position(|&u| u == v) {
                bucket.swap_remove(k);
            }
        }
        self.buckets.entry(b).or_default().push(v);
    }

    /// Every cell in the 27 buckets round `p` (a superset of those within one width).
    fn near(&self, p: DVec3, mut f: impl FnMut(u32)) {
        let (x, y, z) = self.key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(b) = self.buckets.get(&(x + dx, y + dy, z + dz)) {
                        b.iter().for_each(|&u| f(u));
                    }
                }
            }
        }
    }

    /// Every cell in the buckets that reach within `radius` of `p` (a superset of the cells
    /// within it): buckets wholly farther away are not looked up.
    fn near_radius(&self, p: DVec3, radius: f64, mut f: impl FnMut(u32)) {
        let lo = ((p - DVec3::splat(radius)) / self.width).floor();
        let hi = ((p + DVec3::splat(radius)) / self.width).floor();
        let r2 = radius * radius;
        let gap = |k: i32, c: f64| {
            let (a, b) = (k as f64 * self.width, (k + 1) as f64 * self.width);
            if c < a {
                a - c
            } else if c > b {
                c - b
            } else {
                0.0
            }
        };
        for x in lo.x as i32..=hi.x as i32 {
            let gx = gap(x, p.x);
            for y in lo.y as i32..=hi.y as i32 {
                let gy = gap(y, p.y);
                if gx * gx + gy * gy > r2 {
                    continue;
                }
                for z in lo.z as i32..=hi.z as i32 {
                    let gz = gap(z, p.z);
                    if gx * gx + gy * gy + gz * gz > r2 {
                        continue;
                    }
                    if let Some(b) = self.buckets.get(&(x, y, z)) {
                        b.iter().for_each(|&u| f(u));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relaxation_finds_unit_edges_on_the_tetrahedron() {
        let (g, p) = CellGraph::tetrahedron();
        let squashed: Vec<DVec3> = p.iter().map(|q| *q * DVec3::new(2.0, 0.6, 1.3)).collect();
        let mut e = Embedding::new(squashed, vec![1.0; 4], 0.8, 1.0);
        for _ in 0..30 {
            for v in 0..4 {
                e.relax(&g, v);
            }
        }
        for f in g.faces() {
            for k in 0..3 {
                let d = e.pos[f[k] as usize].distance(e.pos[f[(k + 1) % 3] as usize]);
                // Steps under `SETTLED` cell sizes are not taken.
                assert!((d - 1.0).abs() < 2e-3, "edge {d}");
            }
        }
    }

    #[test]
    fn damped_newton_descends_on_indefinite_hessians() {
        let h = DMat3::from_diagonal(DVec3::new(1.0, -2.0, 0.5));
        let g = DVec3::new(1.0, 1.0, -1.0);
        let s = damped_newton(h, g);
        assert!(s.dot(g) < 0.0);
        let spd = DMat3::from_cols(
            DVec3::new(4.0, 1.0, 0.0),
            DVec3::new(1.0, 3.0, 0.5),
            DVec3::new(0.0, 0.5, 2.0),
        );
        let s = damped_newton(spd, g);
        assert!((spd * s + g).length() < 1e-12);
    }
}
