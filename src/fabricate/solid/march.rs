//! Marching tetrahedra over a sparse grid: the union of primitives as one closed, oriented,
//! 2-manifold triangle mesh.
//!
//! The grid has spacing `h` and is cut into bricks of 8³ cells. Only bricks that some primitive
//! (grown by a band of 2h) reaches are looked at, and of those only the ones whose centre is
//! within the brick's half-diagonal of the surface (every function is 1-Lipschitz, so the others
//! are wholly inside or outside). Each cell is split into the six Kuhn tetrahedra that share its
//! main diagonal; this split is the same in every cell, so neighbouring tetrahedra meet face to
//! face and the surface is a manifold by construction: each triangle edge lies on a tetrahedron
//! face shared by exactly two tetrahedra.
//!
//! A vertex sits on a grid edge whose ends differ in sign. It is made once, by the brick that
//! holds the edge's lower end, so neighbouring bricks share it by index. Its place on the edge is
//! found with regula falsi steps on the exact distance (not a linear guess), and kept at
//! least `h/100` from either end. Grid values within `h/100` of zero count as outside. Together
//! these keep every vertex at least about `h/100` from every other and no triangle degenerate,
//! even after rounding to the 32-bit floats of an STL file (checked again after meshing).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use glam::DVec3;
use rayon::prelude::*;

use super::quick::{QuickMap, QuickSet};
use super::sdf::Primitive;
use crate::mesh::{find, union, TriMesh};

mod adapt;

/// Cells per brick side.
const B: usize = 8;
/// Points per brick side.
const P: usize = B + 1;
/// Largest grid size along an axis: brick keys pack three 21-bit numbers.
const MAX_POINTS: usize = (1 << 21) * B;
/// The most (brick, shape) pairs: 16 bytes each, 800 MB.
const MAX_PAIRS: usize = 50_000_000;

#[derive(Debug, thiserror::Error)]
pub enum MarchError {
    #[error("a grid of {0} × {1} × {2} points at this cell size is too large; use a larger cell")]
    TooFine(usize, usize, usize),
    #[error("the mesh would have {0} vertices, more than a 32-bit index holds; use a larger cell")]
    TooManyVertices(usize),
    #[error(
        "the shapes' boxes cover {0} grid bricks at this cell size, more than {MAX_PAIRS}: a \
         node far from the rest, or a cell far too small for the network; use a larger cell"
    )]
    TooManyBricks(u128),
    #[error("internal meshing error: {0}")]
    Internal(String),
    #[error("cancelled")]
    Cancelled,
}

/// The sampling grid: point (i, j, k) is at `origin + h·(i, j, k)`.
#[derive(Clone, Copy, Debug)]
struct Grid {
    origin: DVec3,
    h: f64,
    points: [usize; 3],
}

impl Grid {
    fn at(&self, i: [usize; 3]) -> DVec3 {
        self.origin + DVec3::new(i[0] as f64, i[1] as f64, i[2] as f64) * self.h
    }
    fn bricks(&self) -> [usize; 3] {
        self.points.map(|n| (n - 1).div_ceil(B))
    }
}

/// What one brick made: which of its points are inside, and the vertices on the edges it owns
/// (those whose lower end is one of its own points), in the order of their keys.
struct Brick {
    key: u64,
    inside: [u64; (P * P * P).div_ceil(64)],
    keys: Vec<u32>,
    positions: Vec<DVec3>,
    /// Cells (local index `(i·B + j)·B + k`) that `adapt` is to look at (only when asked for):
    /// see `close_cells`.
    close: Vec<u16>,
}

impl Brick {
    fn is_inside(&self, lp: usize) -> bool {
        bit(&self.inside, lp)
    }
}

fn bit(bits: &[u64], i: usize) -> bool {
    bits[i / 64] >> (i % 64) & 1 == 1
}

fn pack(b: [usize; 3]) -> u64 {
    ((b[0] as u64) << 42) | ((b[1] as u64) << 21) | b[2] as u64
}

fn unpack(k: u64) -> [usize; 3] {
    let m = (1u64 << 21) - 1;
    [(k >> 42) as usize, (k >> 21 & m) as usize, (k & m) as usize]
}

fn local(i: usize, j: usize, k: usize) -> usize {
    (i * P + j) * P + k
}

/// A cell's number within its brick, `(i·B + j)·B + k`.
fn cell_number(i: usize, j: usize, k: usize) -> u16 {
    ((i * B + j) * B + k) as u16
}

/// The grid cell numbered `n` within the brick keyed `key`.
fn cell_at(key: u64, n: u16) -> [usize; 3] {
    let (base, n) = (unpack(key).map(|c| c * B), n as usize);
    [base[0] + n / (B * B), base[1] + n / B % B, base[2] + n % B]
}

/// Offset of a cell corner from its code: bit 0 x, bit 1 y, bit 2 z.
fn corner(code: u8) -> [usize; 3] {
    [
        (code & 1) as usize,
        (code >> 1 & 1) as usize,
        (code >> 2 & 1) as usize,
    ]
}

/// What `mesh_union` made besides the mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Marched {
    /// Grid cells split finer where veins come closer than the grid resolves.
    pub cells_refined: usize,
    /// Tetrahedra that still join two veins at the finest level (or past the budget).
    pub gaps_left: usize,
    /// Tetrahedra at the finest level still spanning the end of a crotch (where two veins
    /// meet at a sharp angle the crotch narrows to nothing) by more than half the tolerance.
    pub crotch_ends: usize,
}

/// Meshes the union of `prims` on a grid of spacing `h`; with `gaps` (a tolerance and the finest
/// split, as cells per grid cell along a side), cells where a gap between veins, or the narrow
/// crotch between two that meet at a sharp angle, may be narrower than the grid are split finer
/// until no tetrahedron bridges it by more than the tolerance allows (`adapt`). `progress`
/// counts bricks as they finish (from several threads) and stops the meshing with
/// `MarchError::Cancelled` when asked: the bricks left are skipped.
pub fn mesh_union(
    prims: &[Primitive],
    h: f64,
    gaps: Option<(f64, u32)>,
    progress: &dyn crate::stage::Progress,
) -> Result<(TriMesh, Marched), MarchError> {
    let band = 2.0 * h;
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let bounds: Vec<(DVec3, DVec3)> = prims.iter().map(Primitive::bounds).collect();
    for &(a, b) in &bounds {
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if prims.is_empty() {
        return Ok((TriMesh::default(), Marched::default()));
    }
    let origin = lo - DVec3::splat(2.0 * band);
    let size = hi - lo + DVec3::splat(4.0 * band);
    let points = [size.x, size.y, size.z].map(|s| (s / h).ceil() as usize + 1);
    if points.iter().any(|&n| n > MAX_POINTS) {
        return Err(MarchError::TooFine(points[0], points[1], points[2]));
    }
    let grid = Grid { origin, h, points };
    let nb = grid.bricks();

    // Every brick a primitive's grown box reaches, with that primitive: counted first, so a
    // long diagonal member or a tiny cell is refused before the list is allocated.
    let reach = |a: DVec3, b: DVec3| {
        point_range(&grid, a - DVec3::splat(band), b + DVec3::splat(band)).map(|(i0, i1)| {
            let (lo, hi) = (i0.saturating_sub(1) / B, i1 / B);
            (hi.saturating_sub(lo) + 1) as u128
        })
    };
    let total: u128 = bounds
        .iter()
        .map(|&(a, b)| reach(a, b).iter().product::<u128>())
        .sum();
    if total > MAX_PAIRS as u128 {
        return Err(MarchError::TooManyBricks(total));
    }
    let mut pairs: Vec<(u64, u32)> = Vec::with_capacity(total as usize);
    for (k, &(a, b)) in bounds.iter().enumerate() {
        let first = point_range(&grid, a - DVec3::splat(band), b + DVec3::splat(band));
        let [(x0, x1), (y0, y1), (z0, z1)] = first.map(|(i0, i1)| {
            // Point i lies in brick i / B, and also in brick i / B − 1 when on its lower face.
            (i0.saturating_sub(1) / B, i1 / B)
        });
        for x in x0..=x1.min(nb[0] - 1) {
            for y in y0..=y1.min(nb[1] - 1) {
                for z in z0..=z1.min(nb[2] - 1) {
                    pairs.push((pack([x, y, z]), k as u32));
                }
            }
        }
    }
    pairs.par_sort_unstable();
    let mut groups: Vec<(u64, std::ops::Range<usize>)> = Vec::new();
    let mut s = 0;
    while s < pairs.len() {
        let mut e = s;
        while e < pairs.len() && pairs[e].0 == pairs[s].0 {
            e += 1;
        }
        groups.push((pairs[s].0, s..e));
        s = e;
    }
    let members: Vec<u32> = pairs.iter().map(|&(_, p)| p).collect();
    drop(pairs);

    let total = 2 * groups.len() as u64;
    progress.begin("meshing", Some(total));
    let done = AtomicU64::new(0);
    let stopped = std::sync::atomic::AtomicBool::new(false);
    // Whether to skip the rest: asked once per brick.
    let stop = || {
        if !stopped.load(Ordering::Relaxed) && progress.cancelled() {
            stopped.store(true, Ordering::Relaxed);
        }
        stopped.load(Ordering::Relaxed)
    };
    let tick = || {
        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
        if d.is_multiple_of(256) || d == total {
            progress.set(d);
        }
    };
    let bricks: Vec<Brick> = groups
        .par_iter()
        .filter_map(|(key, range)| {
            if stop() {
                return None;
            }
            let own: Vec<&Primitive> = members[range.clone()]
                .iter()
                .map(|&p| &prims[p as usize])
                .collect();
            let b = evaluate(&grid, *key, &own, band, gaps.map(|(tol, _)| tol));
            tick();
            b
        })
        .collect();
    if stopped.load(Ordering::Relaxed) {
        return Err(MarchError::Cancelled);
    }
    done.store(groups.len() as u64, Ordering::Relaxed);

    let mut offsets = Vec::with_capacity(bricks.len() + 1);
    let mut count = 0usize;
    for b in &bricks {
        offsets.push(count);
        count += b.keys.len();
    }
    if count > u32::MAX as usize {
        return Err(MarchError::TooManyVertices(count));
    }
    let keys: Vec<u64> = bricks.iter().map(|b| b.key).collect();

    // Where veins come close: bisected tetrahedra replace those cells' own. Bisecting is
    // sequential within a cluster of close cells, two groups of clusters side by side
    // (`halves`); the bricks' own triangles are made beside it, on the other threads, each
    // cell's apart so that those of the cells it takes can be left out.
    let mut marched = Marched::default();
    let split_cells = |marched: &mut Marched| -> Result<Option<Split>, MarchError> {
        let Some(split) = gaps else {
            return Ok(None);
        };
        let field = GridField {
            groups: &groups,
            members: &members,
            bricks: &bricks,
            keys: &keys,
        };
        let looked: Vec<[usize; 3]> = bricks
            .iter()
            .flat_map(|b| b.close.iter().map(|&c| cell_at(b.key, c)))
            .collect();
        let budgets = [adapt::Budget::default(), adapt::Budget::default()];
        let setup = Setup {
            grid: &grid,
            prims,
            field: &field,
            band,
            split,
        };
        let mut parts = setup.bisect(&looked, halves(&looked), &budgets)?;
        let made = parts
            .par_iter_mut()
            .map(|refine| fine_triangles(refine, &bricks, &keys, &offsets, count))
            .collect::<Result<Vec<_>, MarchError>>()?;
        // Each part's new vertices numbered after the last part's.
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (p, t) in made {
            let shift = positions.len() as u32;
            triangles.extend(
                t.into_iter()
                    .map(|t: [u32; 3]| t.map(|v| if v as usize >= count { v + shift } else { v })),
            );
            positions.extend(p);
        }
        if count + positions.len() > u32::MAX as usize {
            return Err(MarchError::TooManyVertices(count + positions.len()));
        }
        let mut cells = QuickSet::default();
        // Only cells something was cut in count as refined.
        let mut cut: QuickSet<[usize; 3]> = QuickSet::default();
        for refine in &mut parts {
            marched.gaps_left += refine.left;
            marched.crotch_ends += refine.crotches;
            cells.extend(std::mem::take(&mut refine.cells));
            for t in refine.tets.iter().filter(|t| t.alive) {
                let v = refine.corners(t);
                if v.iter().any(|p| adapt::grid_point(*p).is_none()) {
                    let lo = [0, 1, 2].map(|a| v.iter().map(|p| p[a]).min().unwrap_or(0));
                    cut.insert(lo.map(|c| (c / adapt::SCALE) as usize));
                }
            }
        }
        marched.cells_refined = cut.len();
        Ok(Some(Split {
            positions,
            triangles,
            cells,
        }))
    };
    let own_triangles = || {
        (0..bricks.len())
            .into_par_iter()
            .map(|i| {
                if stop() {
                    return Ok(Cells::default());
                }
                let t = triangles(&bricks, &keys, &offsets, i);
                tick();
                t
            })
            .collect::<Vec<Result<Cells, MarchError>>>()
    };
    let (fine, parts) = rayon::join(|| split_cells(&mut marched), own_triangles);
    let fine = fine?;
    let mut triangles_out = Vec::new();
    for (b, part) in bricks.iter().zip(parts) {
        let part = part?;
        match &fine {
            Some(split) if !split.cells.is_empty() => {
                for (k, &(c, start)) in part.starts.iter().enumerate() {
                    if !split.cells.contains(&cell_at(b.key, c)) {
                        let end = part
                            .starts
                            .get(k + 1)
                            .map_or(part.triangles.len(), |s| s.1 as usize);
                        triangles_out.extend_from_slice(&part.triangles[start as usize..end]);
                    }
                }
            }
            _ => triangles_out.extend(part.triangles),
        }
    }
    if stopped.load(Ordering::Relaxed) {
        return Err(MarchError::Cancelled);
    }
    progress.set(total);
    let mut positions = Vec::with_capacity(count);
    for b in bricks {
        positions.extend(b.positions);
    }
    let mut mesh = TriMesh {
        positions,
        triangles: triangles_out,
        colors: None,
    };
    if let Some(split) = fine {
        mesh.positions.extend(split.positions);
        mesh.triangles.extend(split.triangles);
        // The vertices of grid edges the bisected cells cut that no triangle uses.
        mesh.drop_unused();
    }
    Ok((mesh, marched))
}

/// What `adapt` bisects with.
struct Setup<'a, F> {
    grid: &'a Grid,
    prims: &'a [Primitive],
    field: &'a F,
    band: f64,
    split: (f64, u32),
}

impl<'a, F: adapt::Field + Sync> Setup<'a, F> {
    /// Bisects where the cells `looked` at need it, all in one `Adapt`, or with `groups` (the
    /// same cells, see `halves`) each group in its own, side by side: kept when neither brought
    /// in a cell the other did and the budget never bound (what each did is then what one
    /// would have done with all); when they met, the one that made more goes on with the
    /// other's cells (bisection ends the same whatever the order it cuts in); when the budget
    /// bound (what each did then hung on the other's pace), all at once in one, anew.
    fn bisect(
        &self,
        looked: &[[usize; 3]],
        groups: Option<[Vec<[usize; 3]>; 2]>,
        [shared, alone]: &'a [adapt::Budget; 2],
    ) -> Result<Vec<adapt::Adapt<'a, F>>, MarchError> {
        let run = |cells: &[[usize; 3]], budget| {
            let mut refine = adapt::Adapt::new(
                self.grid, self.prims, self.field, budget, self.band, self.split,
            );
            for &c in cells {
                refine.look_at(c);
            }
            refine.run().map(|()| refine)
        };
        let Some([a, b]) = groups else {
            return Ok(vec![run(looked, alone)?]);
        };
        let (ra, rb) = rayon::join(|| run(&a, shared), || run(&b, shared));
        let (ra, rb) = (ra?, rb?);
        if !adapt::Budget::never_met(ra.tets.len() + rb.tets.len()) {
            drop((ra, rb));
            return Ok(vec![run(looked, alone)?]);
        }
        let (small, large) = if ra.cells.len() <= rb.cells.len() {
            (&ra, &rb)
        } else {
            (&rb, &ra)
        };
        if small.cells.iter().all(|c| !large.cells.contains(c)) {
            return Ok(vec![ra, rb]);
        }
        let (mut more, rest) = if ra.tets.len() >= rb.tets.len() {
            drop(rb);
            (ra, b)
        } else {
            drop(ra);
            (rb, a)
        };
        more.alone(alone);
        for &c in &rest {
            more.look_at(c);
        }
        more.run()?;
        Ok(vec![more])
    }
}

/// Cells per side of the blocks `halves` groups the close cells by.
const APART: usize = 3;

/// The close cells in two groups to be bisected apart, each in the order given: whole
/// clusters (close cells in blocks of `APART` cells, blocks that touch joined, so two clusters
/// are more than `APART` cells apart), the largest first, each into the group with fewer cells
/// so far. `None` when they are one cluster.
///
/// Bisection meets a neighbour only through a cut edge, and every cell around a cut grid edge
/// is brought in: two groups that brought in no cell in common left every face between them
/// whole, and bisected each what they would have together.
fn halves(cells: &[[usize; 3]]) -> Option<[Vec<[usize; 3]>; 2]> {
    let block = |c: &[usize; 3]| c.map(|x| x / APART);
    let mut blocks: Vec<[usize; 3]> = cells.iter().map(block).collect();
    blocks.sort_unstable();
    blocks.dedup();
    let index = |b: &[usize; 3]| blocks.binary_search(b).ok();
    let mut parent: Vec<u32> = (0..blocks.len() as u32).collect();
    for (i, b) in blocks.iter().enumerate() {
        for code in (0..27).filter(|&c| c != 13) {
            let d = [code % 3, code / 3 % 3, code / 9].map(|x| x as i64 - 1);
            let n = [0, 1, 2].map(|a| b[a] as i64 + d[a]);
            if n.iter().any(|&x| x < 0) {
                continue;
            }
            if let Some(j) = index(&n.map(|x| x as usize)) {
                union(&mut parent, i as u32, j as u32);
            }
        }
    }
    let cluster: Vec<u32> = cells
        .iter()
        .map(|c| index(&block(c)).map_or(0, |i| find(&mut parent, i as u32)))
        .collect();
    let mut weight = vec![0usize; blocks.len()];
    for &r in &cluster {
        weight[r as usize] += 1;
    }
    let mut order: Vec<u32> = (0..blocks.len() as u32)
        .filter(|&r| weight[r as usize] > 0)
        .collect();
    if order.len() < 2 {
        return None;
    }
    order.sort_by_key(|&r| (std::cmp::Reverse(weight[r as usize]), r));
    let mut side = vec![0usize; blocks.len()];
    let mut load = [0usize; 2];
    for r in order {
        let s = usize::from(load[1] < load[0]);
        side[r as usize] = s;
        load[s] += weight[r as usize];
    }
    let mut out = [Vec::new(), Vec::new()];
    for (c, r) in cells.iter().zip(cluster) {
        out[side[r as usize]].push(*c);
    }
    Some(out)
}

/// What the split cells make: their new vertices (numbered after the bricks'), their
/// triangles, and the cells themselves (whose own triangles are left out).
struct Split {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    cells: QuickSet<[usize; 3]>,
}

/// The grid's pieces and signs, for `adapt`.
struct GridField<'a> {
    groups: &'a [(u64, std::ops::Range<usize>)],
    members: &'a [u32],
    bricks: &'a [Brick],
    keys: &'a [u64],
}

impl adapt::Field for GridField<'_> {
    fn near(&self, cell: [usize; 3]) -> &[u32] {
        let key = pack(cell.map(|c| c / B));
        match self.groups.binary_search_by_key(&key, |g| g.0) {
            Ok(i) => &self.members[self.groups[i].1.clone()],
            Err(_) => &[],
        }
    }

    fn grid_inside(&self, g: [usize; 3]) -> Option<bool> {
        // A point on a brick's lower face is also the top face of the brick below.
        for code in 0..8u8 {
            let o = corner(code);
            if (0..3).any(|a| o[a] == 1 && (!g[a].is_multiple_of(B) || g[a] < B)) {
                continue;
            }
            let b = [0, 1, 2].map(|a| g[a] / B - o[a]);
            if let Ok(i) = self.keys.binary_search(&pack(b)) {
                let l = [0, 1, 2].map(|a| g[a] - b[a] * B);
                return Some(self.bricks[i].is_inside(local(l[0], l[1], l[2])));
            }
        }
        None
    }
}

/// The marched triangles of the bisected tetrahedra: vertices on grid edges are the bricks'
/// own (indices below `count`), the others new (numbered from `count`, returned). The new
/// vertices are numbered in one pass, in order, and placed on the surface afterwards, in
/// parallel (each is a root search along its edge).
fn fine_triangles<F: adapt::Field + Sync>(
    refine: &mut adapt::Adapt<F>,
    bricks: &[Brick],
    keys: &[u64],
    offsets: &[usize],
    count: usize,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), MarchError> {
    // The new vertices' edges: inside end, outside end, their values and the cell.
    let mut edges: Vec<(adapt::Pt, f64, adapt::Pt, f64, [usize; 3])> = Vec::new();
    let mut made: QuickMap<(adapt::Pt, adapt::Pt), u32> = QuickMap::default();
    let mut out = Vec::new();
    for id in 0..refine.tets.len() {
        let t = refine.tets[id];
        if !t.alive {
            continue;
        }
        let v = refine.corners(&t);
        let mut mask = 0usize;
        for (i, &p) in v.iter().enumerate() {
            if refine.inside(p) {
                mask |= 1 << i;
            }
        }
        if mask == 0 || mask == 15 {
            continue;
        }
        for tri in cases_at(&v, mask) {
            let mut ids = [0u32; 3];
            for (slot, &[i, j]) in ids.iter_mut().zip(&tri) {
                let (p, q) = (v[i as usize], v[j as usize]);
                *slot = if let Some((lo, dir)) = adapt::grid_edge(p, q) {
                    grid_vertex((bricks, keys, offsets), usize::MAX, lo, dir)?
                } else {
                    let key = if p <= q { (p, q) } else { (q, p) };
                    match made.get(&key) {
                        Some(&v) => v,
                        None => {
                            let (a, b) = if mask >> i & 1 == 1 { (p, q) } else { (q, p) };
                            let (fa, fb) = (refine.signed(a), refine.signed(b));
                            let cell = [0, 1, 2].map(|k| (a[k].min(b[k]) / adapt::SCALE) as usize);
                            let v = (count + edges.len()) as u32;
                            edges.push((a, fa, b, fb, cell));
                            made.insert(key, v);
                            v
                        }
                    }
                };
            }
            out.push(ids);
        }
    }
    if count + edges.len() > u32::MAX as usize {
        return Err(MarchError::TooManyVertices(count + edges.len()));
    }
    drop(made);
    let refine = &*refine;
    let positions = edges
        .par_iter()
        .map(|&(a, fa, b, fb, cell)| {
            let eps = refine.eps_at(a).min(refine.eps_at(b));
            let f = |x: DVec3| refine.value(x, cell);
            crossing(refine.position(a), fa, refine.position(b), fb, &f, eps)
        })
        .collect();
    Ok((positions, out))
}

/// The cosine of the angle between two pieces' outward directions at `x`.
fn outward_cos(p: &Primitive, q: &Primitive, x: DVec3, band: f64) -> f64 {
    let step = 1e-3 * band;
    p.gradient(x, band, step).dot(q.gradient(x, band, step))
}

/// Outward directions more than 120° apart: the surfaces face each other, across a narrow
/// crotch or gap.
const FACING: f64 = -0.5;

/// Whether two pieces face each other at `x` (`FACING`).
fn facing(p: &Primitive, q: &Primitive, x: DVec3, band: f64) -> bool {
    outward_cos(p, q, x, band) < FACING
}

/// Grid points within the box `a..b`, as an inclusive index range per axis (clamped).
fn point_range(grid: &Grid, a: DVec3, b: DVec3) -> [(usize, usize); 3] {
    let lo = (a - grid.origin) / grid.h;
    let hi = (b - grid.origin) / grid.h;
    let r = |l: f64, h: f64, n: usize| {
        let i0 = l.ceil().max(0.0) as usize;
        let i1 = (h.floor().max(0.0) as usize).min(n - 1);
        (i0.min(n - 1), i1)
    };
    [
        r(lo.x, hi.x, grid.points[0]),
        r(lo.y, hi.y, grid.points[1]),
        r(lo.z, hi.z, grid.points[2]),
    ]
}

/// Samples one brick; `None` when the surface does not pass through it (and, with `gaps`, no
/// two veins come close in it).
fn evaluate(
    grid: &Grid,
    key: u64,
    prims: &[&Primitive],
    band: f64,
    gaps: Option<f64>,
) -> Option<Brick> {
    let bk = unpack(key);
    let base = bk.map(|b| b * B);
    let h = grid.h;
    let half = 0.5 * (B as f64) * h * 3f64.sqrt();
    let centre = grid.at(base.map(|b| b + B / 2));
    let fc = prims
        .iter()
        .map(|p| p.eval(centre, 1.01 * half))
        .fold(f64::INFINITY, f64::min);
    let eps = 0.01 * h;
    // 1-Lipschitz: every point of the brick is within `half` of the centre. Values in
    // (−eps, 0) count as outside, hence the wider margin below zero.
    if fc > half || fc < -half - 2.0 * eps {
        return None;
    }

    let last = grid.points.map(|n| n - 1);
    let mut values = [f64::INFINITY; P * P * P];
    // Which piece gave each value (its index in `prims`).
    let mut which = [u32::MAX; P * P * P];
    for (n, prim) in prims.iter().enumerate() {
        let n = n as u32;
        let (a, b) = prim.bounds();
        let range = point_range(grid, a - DVec3::splat(band), b + DVec3::splat(band));
        let span = |axis: usize| {
            let (i0, i1) = range[axis];
            let top = (base[axis] + B).min(last[axis]);
            (i0.max(base[axis]), i1.min(top))
        };
        let ((x0, x1), (y0, y1), (z0, z1)) = (span(0), span(1), span(2));
        if x0 > x1 || y0 > y1 || z0 > z1 {
            continue;
        }
        for x in x0..=x1 {
            for y in y0..=y1 {
                let column = local(x - base[0], y - base[1], 0);
                match prim {
                    // The in-plane distance does not change along z: one per column.
                    Primitive::Prism(s) => {
                        let p = grid.at([x, y, z0]);
                        let across = s.outline.signed_distance(p.truncate(), band);
                        for z in z0..=z1 {
                            let v = s.with_across(across, grid.origin.z + z as f64 * h);
                            let at = column + z - base[2];
                            if v < values[at] {
                                values[at] = v;
                                which[at] = n;
                            }
                        }
                    }
                    _ => {
                        for z in z0..=z1 {
                            let at = column + z - base[2];
                            // Already deep inside: no crossing edge ends here (the surface is
                            // more than an edge away), so its exact value no longer matters.
                            if values[at] <= -band {
                                continue;
                            }
                            let v = prim.eval(grid.at([x, y, z]), band);
                            if v < values[at] {
                                values[at] = v;
                                which[at] = n;
                            }
                        }
                    }
                }
            }
        }
    }

    let mut inside = [0u64; (P * P * P).div_ceil(64)];
    let mut any_in = false;
    let mut any_out = false;
    for (lp, v) in values.iter_mut().enumerate() {
        if *v <= -eps {
            inside[lp / 64] |= 1 << (lp % 64);
            any_in = true;
        } else {
            *v = v.max(eps);
            any_out = true;
        }
    }
    let close = if let Some(tol) = gaps {
        close_cells(&values, &which, prims, (h, band, tol), grid.at(base))
    } else {
        Vec::new()
    };
    if !(any_in && any_out) && close.is_empty() {
        return None;
    }

    let f = |p: DVec3| {
        prims
            .iter()
            .map(|q| q.eval(p, band))
            .fold(f64::INFINITY, f64::min)
    };
    let mut keys = Vec::new();
    let mut positions = Vec::new();
    for i in 0..B {
        for j in 0..B {
            for k in 0..B {
                let lp = local(i, j, k);
                let p_in = bit(&inside, lp);
                for dir in 1u8..8 {
                    let d = corner(dir);
                    let lq = local(i + d[0], j + d[1], k + d[2]);
                    if p_in == bit(&inside, lq) {
                        continue;
                    }
                    let gp = grid.at([base[0] + i, base[1] + j, base[2] + k]);
                    let gq = grid.at([base[0] + i + d[0], base[1] + j + d[1], base[2] + k + d[2]]);
                    let (a, fa, b, fb) = if p_in {
                        (gp, values[lp], gq, values[lq])
                    } else {
                        (gq, values[lq], gp, values[lp])
                    };
                    keys.push((lp * 8 + dir as usize) as u32);
                    positions.push(crossing(a, fa, b, fb, &f, eps));
                }
            }
        }
    }
    Some(Brick {
        key,
        inside,
        keys,
        positions,
        close,
    })
}

/// The brick's cells near the surface where the nearest piece changes from corner to corner
/// and either the centre is more than half the tolerance on the wrong side of what marching
/// interpolates there, or one of those nearest pieces and a piece reaching into the cell do
/// not touch or face each other across it (a gap or a sharp crotch, perhaps narrower than a
/// cell): `adapt` looks closer.
fn close_cells(
    values: &[f64; P * P * P],
    which: &[u32; P * P * P],
    prims: &[&Primitive],
    (h, band, tol): (f64, f64, f64),
    origin: DVec3,
) -> Vec<u16> {
    let reach = 3f64.sqrt() * h;
    let mut out = Vec::new();
    // Pairs of pieces already told apart or not.
    let mut seen: Vec<((u32, u32), bool)> = Vec::new();
    for i in 0..B {
        for j in 0..B {
            for k in 0..B {
                let mut near = [u32::MAX; 8];
                let mut deep = false;
                for (c, slot) in near.iter_mut().enumerate() {
                    let d = corner(c as u8);
                    let lp = local(i + d[0], j + d[1], k + d[2]);
                    deep |= values[lp] <= -band;
                    if values[lp] < reach {
                        *slot = which[lp];
                    }
                }
                if deep {
                    continue;
                }
                // Where the nearest piece changes, every piece that reaches into the cell is
                // paired with those nearest pieces (a gap may open beside a third piece).
                let mut firsts: Vec<u32> =
                    near.iter().copied().filter(|&p| p != u32::MAX).collect();
                firsts.sort_unstable();
                firsts.dedup();
                if firsts.len() < 2 {
                    continue;
                }
                let centre =
                    origin + DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * h;
                let mut exact = band;
                let reaching: Vec<u32> = (0..prims.len() as u32)
                    .filter(|&q| {
                        let v = prims[q as usize].eval(centre, band);
                        exact = exact.min(v);
                        v < reach
                    })
                    .collect();
                // The Kuhn split puts the centre on the cell's main diagonal: marching there
                // interpolates its two ends.
                let linear = 0.5 * (values[local(i, j, k)] + values[local(i + 1, j + 1, k + 1)]);
                let mut apart =
                    exact > 0.5 * tol && linear < 0.0 || exact < -0.5 * tol && linear > 0.0;
                'pairs: for &p in firsts.iter().filter(|_| !apart) {
                    for &q in &reaching {
                        if p == q {
                            continue;
                        }
                        let key = (p.min(q), p.max(q));
                        let known = seen.iter().find(|s| s.0 == key).map(|s| s.1);
                        let (a, b) = (prims[p as usize], prims[q as usize]);
                        let told = known.unwrap_or_else(|| {
                            let v = a.apart(b);
                            seen.push((key, v));
                            v
                        });
                        if told || facing(a, b, centre, band) {
                            apart = true;
                            break 'pairs;
                        }
                    }
                }
                if apart {
                    out.push(cell_number(i, j, k));
                }
            }
        }
    }
    out
}

/// The most regula falsi steps to a vertex (most stop after two or three).
const CROSSING_STEPS: usize = 24;

/// Where the surface crosses the edge from `a` (inside, `fa < 0`) to `b` (outside, `fb > 0`):
/// Illinois regula falsi on `f`, kept at least `eps` from both ends.
fn crossing(a: DVec3, fa: f64, b: DVec3, fb: f64, f: &impl Fn(DVec3) -> f64, eps: f64) -> DVec3 {
    let (mut t0, mut f0, mut t1, mut f1) = (0.0, fa, 1.0, fb);
    let mut t = f0 / (f0 - f1);
    let mut side = 0i8;
    // Where veins meet, the distance has kinks and a few steps may stop short; the bracket
    // always shrinks, so more steps converge.
    for _ in 0..CROSSING_STEPS {
        let ft = f(a.lerp(b, t));
        if ft.abs() < 1e-4 * eps {
            break;
        }
        if ft < 0.0 {
            (t0, f0) = (t, ft);
            if side == -1 {
                f1 *= 0.5;
            }
            side = -1;
        } else {
            (t1, f1) = (t, ft);
            if side == 1 {
                f0 *= 0.5;
            }
            side = 1;
        }
        t = t0 + (t1 - t0) * f0 / (f0 - f1);
    }
    let margin = (eps / a.distance(b)).min(0.25);
    a.lerp(b, t.clamp(margin, 1.0 - margin))
}

/// The index of the vertex on the grid edge from point `g` along direction code `dir`: made by
/// the brick that holds `g` as one of its own points (looked up unless it is brick `hint`).
fn grid_vertex(
    (bricks, keys, offsets): (&[Brick], &[u64], &[usize]),
    hint: usize,
    g: [usize; 3],
    dir: u8,
) -> Result<u32, MarchError> {
    let nk = pack(g.map(|c| c / B));
    let owner = if bricks.get(hint).is_some_and(|b| b.key == nk) {
        hint
    } else {
        keys.binary_search(&nk).map_err(|_| {
            MarchError::Internal(format!(
                "brick {:?} missing for a shared vertex",
                unpack(nk)
            ))
        })?
    };
    let lo = g.map(|c| c % B);
    let key = (local(lo[0], lo[1], lo[2]) * 8 + dir as usize) as u32;
    let at = bricks[owner].keys.binary_search(&key).map_err(|_| {
        MarchError::Internal(format!(
            "no vertex on edge {dir} at {lo:?} of brick {:?}",
            unpack(bricks[owner].key)
        ))
    })?;
    Ok((offsets[owner] + at) as u32)
}

/// The triangles of brick `i`, with vertex indices into the concatenated vertex lists; cells in
/// `skip` are left out (bisected tetrahedra mesh them).
fn triangles(
    bricks: &[Brick],
    keys: &[u64],
    offsets: &[usize],
    i: usize,
) -> Result<Cells, MarchError> {
    let brick = &bricks[i];
    let base = unpack(brick.key).map(|c| c * B);
    let table = table();
    let mut out = Vec::new();
    let mut starts = Vec::new();
    for x in 0..B {
        for y in 0..B {
            for z in 0..B {
                let mut mask = 0u8;
                for c in 0..8u8 {
                    let d = corner(c);
                    if brick.is_inside(local(x + d[0], y + d[1], z + d[2])) {
                        mask |= 1 << c;
                    }
                }
                if mask == 0 || mask == 0xff {
                    continue;
                }
                let cell = [base[0] + x, base[1] + y, base[2] + z];
                starts.push((cell_number(x, y, z), out.len() as u32));
                for (t, tet) in TETS.iter().enumerate() {
                    let m = (0..4).fold(0usize, |m, v| m | (((mask >> tet[v]) & 1) as usize) << v);
                    for tri in &table[t * 16 + m] {
                        let mut ids = [0u32; 3];
                        for (slot, &[vi, vj]) in ids.iter_mut().zip(tri) {
                            let o = corner(tet[vi as usize]);
                            let g = [0, 1, 2].map(|a| cell[a] + o[a]);
                            *slot = grid_vertex(
                                (bricks, keys, offsets),
                                i,
                                g,
                                tet[vi as usize] ^ tet[vj as usize],
                            )?;
                        }
                        out.push(ids);
                    }
                }
            }
        }
    }
    Ok(Cells {
        triangles: out,
        starts,
    })
}

/// A brick's marched triangles, cell by cell: each cell that has any (its number in the
/// brick, x-major) with where its triangles start.
#[derive(Default)]
struct Cells {
    triangles: Vec<[u32; 3]>,
    starts: Vec<(u16, u32)>,
}

/// The six Kuhn tetrahedra of a cell as corner codes, each a monotone path from corner 0 to
/// corner 7, so every tetrahedron edge runs from a lower corner to a higher one.
const TETS: [[u8; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// For each tetrahedron and inside-mask of its four corners: triangles as pairs of tetrahedron
/// corners (the vertex sits on the edge between them), wound so their normals point outside.
type Table = Vec<Vec<[[u8; 2]; 3]>>;

fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut out = Vec::with_capacity(96);
        for tet in &TETS {
            for mask in 0..16usize {
                out.push(cases(tet, mask));
            }
        }
        out
    })
}

fn cases(tet: &[u8; 4], mask: usize) -> Vec<[[u8; 2]; 3]> {
    let at = tet.map(|code| corner(code).map(|c| c as i64));
    cases_at(&at, mask)
}

/// The marched triangles of a tetrahedron with corners `at` (integer coordinates) and
/// inside-mask `mask`, as pairs of corners, wound so their normals point outside.
fn cases_at(at: &[[i64; 3]; 4], mask: usize) -> Vec<[[u8; 2]; 3]> {
    let ins: Vec<u8> = (0..4).filter(|v| mask >> v & 1 == 1).collect();
    let outs: Vec<u8> = (0..4).filter(|v| mask >> v & 1 == 0).collect();
    let edge = |a: u8, b: u8| [a.min(b), a.max(b)];
    let polygon: Vec<[u8; 2]> = match (ins.len(), outs.len()) {
        (1, 3) => outs.iter().map(|&o| edge(ins[0], o)).collect(),
        (3, 1) => ins.iter().map(|&i| edge(i, outs[0])).collect(),
        (2, 2) => {
            let ([a, b], [c, d]) = ([ins[0], ins[1]], [outs[0], outs[1]]);
            vec![edge(a, c), edge(b, c), edge(b, d), edge(a, d)]
        }
        _ => return Vec::new(),
    };
    // Orientation from the exact midpoint geometry (doubled integer coordinates, relative to
    // the first corner): the normal must point from the inside corners to the outside ones.
    let pos = |v: u8| {
        let p = at[v as usize];
        [p[0] - at[0][0], p[1] - at[0][1], p[2] - at[0][2]]
    };
    let mid = |e: [u8; 2]| {
        let (p, q) = (pos(e[0]), pos(e[1]));
        [p[0] + q[0], p[1] + q[1], p[2] + q[2]]
    };
    let sub = |p: [i64; 3], q: [i64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let (m0, m1, m2) = (mid(polygon[0]), mid(polygon[1]), mid(polygon[2]));
    let (u, v) = (sub(m1, m0), sub(m2, m0));
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let sum = |vs: &[u8]| {
        vs.iter().fold([0i64; 3], |s, &v| {
            let p = pos(v);
            [s[0] + p[0], s[1] + p[1], s[2] + p[2]]
        })
    };
    let (si, so) = (sum(&ins), sum(&outs));
    let (ni, no) = (ins.len() as i64, outs.len() as i64);
    let away = [0, 1, 2].map(|a| so[a] * ni - si[a] * no);
    let dot = n[0] * away[0] + n[1] * away[1] + n[2] * away[2];
    debug_assert!(dot != 0, "degenerate case {at:?} {mask}");
    let mut polygon = polygon;
    if dot < 0 {
        polygon.reverse();
    }
    (1..polygon.len() - 1)
        .map(|k| [polygon[0], polygon[k], polygon[k + 1]])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fabricate::solid::sdf::RoundCone;

    #[test]
    fn every_case_is_oriented_and_covers_each_crossing_edge_once_or_twice() {
        for tet in &TETS {
            for mask in 1..15usize {
                let tris = cases(tet, mask);
                let crossing = (0..4)
                    .flat_map(|a| (a + 1..4).map(move |b| (a, b)))
                    .filter(|&(a, b)| (mask >> a & 1) != (mask >> b & 1))
                    .count();
                assert_eq!(tris.len(), crossing - 2, "tet {tet:?} mask {mask}");
            }
        }
    }

    #[test]
    fn a_ball_is_a_closed_manifold_of_the_right_volume() {
        let ball = [Primitive::Cone(RoundCone::new(
            DVec3::ZERO,
            DVec3::new(0.3, 0.0, 0.0),
            1.0,
            1.0,
        ))];
        let (mesh, _) = mesh_union(&ball, 0.05, None, &crate::stage::Quiet).unwrap();
        let topo = mesh.check_manifold();
        assert!(
            topo.is_manifold(),
            "{:?}",
            &topo.problems[..3.min(topo.problems.len())]
        );
        assert!(topo.closed);
        assert_eq!(topo.components, 1);
        assert_eq!(topo.genus, Some(0));
        // A capsule: a cylinder of length 0.3 and a ball of radius 1.
        let want = std::f64::consts::PI * (0.3 + 4.0 / 3.0);
        let got = mesh.signed_volume();
        assert!((got - want).abs() / want < 0.005, "volume {got} vs {want}");
    }

    /// Every piece near every cell; the grid's signs not known.
    struct All(Vec<u32>);

    impl adapt::Field for All {
        fn near(&self, _: [usize; 3]) -> &[u32] {
            &self.0
        }
        fn grid_inside(&self, _: [usize; 3]) -> Option<bool> {
            None
        }
    }

    #[test]
    fn bisecting_in_two_groups_ends_as_bisecting_all_at_once() {
        // Three pairs of parallel veins a fifth of a cell apart, across the middle of a cell,
        // 30 cells from pair to pair.
        let h = 0.1;
        let mut prims = Vec::new();
        for k in 0..3 {
            let x = 3.0 * k as f64;
            for (dx, r) in [(0.0, 0.24), (0.46, 0.2)] {
                let (a, b) = (DVec3::new(x + dx, -0.5, 0.0), DVec3::new(x + dx, 0.5, 0.0));
                prims.push(Primitive::Cone(RoundCone::new(a, b, r, r)));
            }
        }
        let grid = Grid {
            origin: DVec3::splat(-1.0),
            h,
            points: [100, 21, 21],
        };
        let field = All((0..prims.len() as u32).collect());
        let setup = Setup {
            grid: &grid,
            prims: &prims,
            field: &field,
            band: 2.0 * h,
            split: (0.025, 4),
        };
        // The cells along each gap.
        let mut looked = Vec::new();
        for i in 0..99 {
            for j in 0..20 {
                for k in 0..20 {
                    let c = grid.at([i, j, k]) + DVec3::splat(0.5 * h);
                    let gap = (0..3).any(|p| (c.x - (3.0 * p as f64 + 0.25)).abs() < 0.15);
                    if gap && c.y.abs() < 0.5 && c.z.abs() < 0.2 {
                        looked.push([i, j, k]);
                    }
                }
            }
        }
        let alive = |parts: &[adapt::Adapt<All>]| {
            let mut all: Vec<[adapt::Pt; 4]> = parts
                .iter()
                .flat_map(|r| {
                    r.tets.iter().filter(|t| t.alive).map(|t| {
                        let mut v = r.corners(t);
                        v.sort_unstable();
                        v
                    })
                })
                .collect();
            all.sort_unstable();
            all
        };
        let budgets = || [adapt::Budget::default(), adapt::Budget::default()];
        let b = budgets();
        let one = setup.bisect(&looked, None, &b).unwrap();
        let whole = alive(&one);
        assert!(
            whole.len() > 6 * one[0].cells.len(),
            "the gaps were bisected: {} tetrahedra in {} cells",
            whole.len(),
            one[0].cells.len()
        );
        // Whole clusters apart: two groups kept.
        let groups = halves(&looked).expect("three clusters");
        let b = budgets();
        let two = setup.bisect(&looked, Some(groups), &b).unwrap();
        assert_eq!(two.len(), 2);
        assert_eq!(alive(&two), whole);
        // One cluster cut in two: the groups meet, and one goes on with the other's cells.
        let (first, rest) = looked.split_at(looked.len() / 6);
        let b = budgets();
        let met = setup
            .bisect(&looked, Some([first.to_vec(), rest.to_vec()]), &b)
            .unwrap();
        assert_eq!(met.len(), 1);
        assert_eq!(alive(&met), whole);
    }

    #[test]
    fn a_ring_of_cones_has_genus_one() {
        let n = 12;
        let ring: Vec<Primitive> = (0..n)
            .map(|i| {
                let at = |k: usize| {
                    let a = std::f64::consts::TAU * k as f64 / n as f64;
                    DVec3::new(a.cos(), a.sin(), 0.0) * 3.0
                };
                Primitive::Cone(RoundCone::new(at(i), at((i + 1) % n), 0.3, 0.4))
            })
            .collect();
        let (mesh, _) = mesh_union(&ring, 0.07, None, &crate::stage::Quiet).unwrap();
        let topo = mesh.check_manifold();
        assert!(topo.is_manifold());
        assert_eq!((topo.components, topo.genus), (1, Some(1)));
        assert!(mesh.signed_volume() > 0.0);
    }
}
