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
//! rim) is split at its midpoint moved onto the surface, and so is the longest edge of a
//! triangle whose centre is that far off (a corner where three veins meet); split edges are
//! split again, up to eight rounds, which walks the new vertices into the crease.
//!
//! *Simplification.* Garland and Heckbert's quadric error (planes of the triangles around each
//! vertex, weighted by area) orders the edges and places the merged vertex. The mesh is cut
//! into bricks of about `BRICK_TRIANGLES` triangles (by their centres); each brick collapses
//! its cheapest edge first, one at a time, and looks again at the edges around each collapse,
//! until no edge within the tolerance passes. A vertex with triangles in two bricks is held,
//! so bricks never touch the same triangle and run in parallel, each the same whatever the
//! thread count. The next sweep shifts the bricks by half their side, so what one sweep held
//! the next frees; sweeps go on until one makes almost no collapse. A collapse must keep:
//! - the mesh a closed 2-manifold: the link condition (the edge's ends share exactly the two
//!   neighbours across its triangles) and at least three neighbours left;
//! - every triangle turned by less than 70° and not made a sliver;
//! - the mesh within the tolerance of the surface, checked on the exact distance at the merged
//!   vertex, the midpoints of its edges and the centres of its triangles; and, outside the
//!   solid, over the whole of each new triangle: a convex piece's distance is convex, so one
//!   vein within the tolerance of all three corners holds the triangle; one no vein holds
//!   (across a crease, or along a vein's joints) is checked at its sides' quarter points and
//!   three points inside as well (a crease's ridge can pass between centre and corners).
//!   Inside the solid the union's distance is only a lower bound (where two veins overlap),
//!   so a point inside must also have a point outside within the tolerance: a step of the
//!   tolerance out of either of the two nearest pieces, or failing that a walk out of the
//!   nearest piece at each step;
//! - the surface within the tolerance of the mesh: every vertex of the refined mesh (each on the
//!   surface) is a witness, kept by a triangle that replaced the one it had; no collapse may
//!   leave a witness farther than the tolerance, less what the surface may bulge between
//!   witnesses (spacing² / 8r, spacing the longest edge marching makes, a cell's diagonal,
//!   and r the thinnest vein's radius).
//!
//! *Tidying.* Then every edge shorter than a hundredth of the tolerance is collapsed to its
//! midpoint, the longest edge of every triangle lower than that is flipped, and every vertex
//! whose neighbours all lie within that distance of one plane (or, with three neighbours, that
//! lies within ten times that of theirs: a spike) goes into its nearest neighbour, where the
//! mesh stays a closed 2-manifold, no triangle turns over and (for a flip) the two
//! triangles get higher; rounds go on until none is left that can be. An STL's 32-bit corners
//! would merge the ends of such an edge or flatten such a triangle, and a reader that merges
//! coplanar triangles (manifold3d) removes a flat vertex itself, pinching the mesh where its
//! triangles fold. The plate: no vertex is left below the solid's lowest point.
//!
//! *Fitting.* The simplified mesh has its corners on the surface and its chords under a vein by
//! up to the tolerance: left so, it is smaller than the solid (the 12,700-node leaf by 0.69 %;
//! 70 % of it lies inside). Its vertices are moved along their normals so its triangles lie on
//! the surface on average (`fit`, two passes), except where a move takes a triangle out of the
//! tolerance by the last check's own test: those triangles' vertices go back (`fit_held`).
//!
//! *Pushing apart.* What tidying could not remove (an edge whose ends have three neighbours in
//! common: collapsing it would pinch a handle; a sliver whose flip makes another) is pushed
//! apart: the ends of a short edge along it, the apex of a low triangle away from its longest
//! edge in its plane, to half as long again as a hundredth of the tolerance (`spread`). After
//! the last check, what fitting and its splits left short, low or flat is tidied and pushed
//! apart again, and checked again (up to `RETIDY_ROUNDS` times, until a round has nothing to
//! tidy, no fewer slivers to push apart and nothing split).
//!
//! *The last check* looks at every triangle whole, with a proof either way. Outside: no point
//! more than the tolerance out of the union (one convex piece within it at all three corners
//! holds the whole triangle, and so does the lamina's prism by a bound of its own: the
//! triangle's footprint inside the outline, or its corners near one edge of it; else the
//! triangle is quartered, down to 1/1024 of its side, until each quarter is so held by a piece
//! near it, or a corner is found out). Inside: no point
//! deeper than the tolerance in any one piece (a triangle lying on one vein but crossing a
//! thinner one that joins it): the tangent plane of a convex piece's distance bounds it from
//! below over the triangle, and Frank–Wolfe steps settle the few the plane does not. A
//! triangle found off, or not proven held, has its longest edge and its edges whose midpoints
//! are not near split at the surface, for up to six rounds; what is left is reported.
//!
//! A rejected edge is not tried again until something around it changes. A triangle already a
//! sliver (marching leaves many) may stay one, but no collapse makes one worse. Neither a
//! split nor a collapse puts a vertex within a hundredth of the tolerance of another, which
//! an STL's 32-bit floats could merge.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use super::few::Few;
use super::quick::{Quick, QuickSet};
use super::sdf::Primitive;
use crate::mesh::TriMesh;

/// The most grid cells of a `Field`.
const MAX_CELLS: f64 = 4e6;
/// The most (cell, piece) pairs a `Field` looks at (of its pieces' boxes), 4 bytes each.
const MAX_ENTRIES: usize = 30_000_000;
/// No two vertices closer than this fraction of the tolerance (an STL's 32-bit floats would
/// make them one).
const COINCIDENT: f64 = 0.01;
/// Rounds of crease refinement.
const REFINE_ROUNDS: usize = 8;
/// Rounds of the last check (`touch_up`).
const TOUCH_ROUNDS: usize = 6;
/// Simplification stops after this many sweeps, or when a sweep collapses fewer than
/// `SETTLED` of the vertices.
const MAX_SWEEPS: usize = 12;
const SETTLED: f64 = 0.002;
/// About this many triangles to a brick.
const BRICK_TRIANGLES: f64 = 30_000.0;
/// How many times `Field::off` may quarter a triangle, and how many quarters it may look at,
/// before it counts a triangle it cannot prove held as off.
const HELD_DEPTH: u32 = 10;
const HELD_QUARTERS: usize = 20_000;
/// Frank–Wolfe steps `Field::deep` takes on one piece before it counts the triangle as deep.
const FW_STEPS: usize = 40;
/// Least triangle quality (1 equilateral, 0 flat) a collapse may make, unless the triangle
/// was already worse.
const MIN_QUALITY: f64 = 0.05;

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
        // Cells about as wide as the reach (so a query meets little more than the pieces
        // within reach of it), unless that makes too many.
        let mut cell = reach
            .min(median)
            .max((size.x * size.y * size.z / MAX_CELLS).cbrt());
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
            let pieces: Vec<(u32, [(usize, usize); 3])> = boxes
                .iter()
                .enumerate()
                .map(|(n, &(a, b))| (n as u32, range(a, b)))
                .collect();
            return Field::build(prims, reach, lo, cell, dims, &pieces);
        }
    }

    /// The grid of cells `cell` wide from `lo`, `dims` of them, listing each of `pieces` (with
    /// the cells its grown box covers) in the cells whose centre is within `reach` of it and
    /// half the cell's diagonal (the pieces are 1-Lipschitz).
    fn build(
        prims: &'a [Primitive],
        reach: f64,
        lo: DVec3,
        cell: f64,
        dims: [usize; 3],
        pieces: &[(u32, [(usize, usize); 3])],
    ) -> Field<'a> {
        let cells = dims[0] * dims[1] * dims[2];
        let index = |i: usize, j: usize, k: usize| (i * dims[1] + j) * dims[2] + k;
        let mut count = vec![0u32; cells + 1];
        let near = reach + 0.5 * 3f64.sqrt() * cell;
        let each = |f: &mut dyn FnMut(usize, u32)| {
            for &(n, [(i0, i1), (j0, j1), (k0, k1)]) in pieces {
                for i in i0..=i1 {
                    for j in j0..=j1 {
                        for k in k0..=k1 {
                            let centre =
                                lo + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * cell;
                            if prims[n as usize].eval(centre, near) <= near {
                                f(index(i, j, k), n);
                            }
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
        let mut list = vec![0u32; count[cells] as usize];
        each(&mut |c, n| {
            list[fill[c] as usize] = n;
            fill[c] += 1;
        });
        Field {
            prims,
            reach,
            lo,
            cell,
            dims,
            start: count,
            list,
        }
    }

    /// Signed distance to the union at `p`.
    pub fn eval(&self, p: DVec3) -> f64 {
        self.two(p).0 .0
    }

    /// The two pieces least at `p`.
    fn least(&self, p: DVec3) -> [u32; 2] {
        let ((_, a), (_, b)) = self.two(p);
        [a, b]
    }

    /// The two least values of the pieces at `p` (each at most `reach`), with the pieces
    /// (`u32::MAX` for none).
    fn two(&self, p: DVec3) -> ((f64, u32), (f64, u32)) {
        let none = (self.reach, u32::MAX);
        self.pieces(p)
            .iter()
            .fold((none, none), |(first, second), &n| {
                let d = self.prims[n as usize].eval(p, self.reach);
                if d < first.0 {
                    ((d, n), first)
                } else if d < second.0 {
                    (first, (d, n))
                } else {
                    (first, second)
                }
            })
    }

    /// The pieces that may be within `reach` of `p`.
    fn pieces(&self, p: DVec3) -> &[u32] {
        let c = ((p - self.lo) / self.cell).floor();
        let outside = c.min_element() < 0.0
            || c.x >= self.dims[0] as f64
            || c.y >= self.dims[1] as f64
            || c.z >= self.dims[2] as f64;
        if outside {
            return &[];
        }
        let (i, j, k) = (c.x as usize, c.y as usize, c.z as usize);
        let at = (i * self.dims[1] + j) * self.dims[2] + k;
        &self.list[self.start[at] as usize..self.start[at + 1] as usize]
    }

    /// Piece `n`'s gradient at `p` (unit length or zero).
    fn piece_gradient(&self, n: u32, p: DVec3, step: f64) -> DVec3 {
        match self.prims.get(n as usize) {
            Some(piece) => piece.gradient(p, self.reach, step),
            None => DVec3::ZERO,
        }
    }

    /// `p` moved onto the surface along the least piece's gradient (a few Newton steps).
    fn project(&self, p: DVec3, step: f64) -> DVec3 {
        let mut q = p;
        for _ in 0..4 {
            let ((f, n), _) = self.two(q);
            if f.abs() < 1e-7 {
                break;
            }
            q -= self.piece_gradient(n, q, step) * f;
        }
        q
    }

    /// Whether one convex piece among `near` (the two pieces least at each corner) is within
    /// `tol` of all three corners of triangle `p`: a convex piece's distance is convex, and the
    /// union's is at most each piece's, so then no point of the triangle is more than `tol`
    /// outside. (The lamina's prism is left to the last check's `piece_holds`: its bound costs
    /// a walk along the outline, too slow for every collapse.)
    fn one_holds(&self, p: &[DVec3; 3], near: [[u32; 2]; 3], tol: f64) -> bool {
        let tried = near.as_flattened();
        tried.iter().enumerate().any(|(k, &n)| {
            !tried[..k].contains(&n)
                && self.prims.get(n as usize).is_some_and(|piece| {
                    !matches!(piece, Primitive::Prism(_))
                        && p.iter().all(|&v| piece.eval(v, self.reach) <= tol)
                })
        })
    }

    /// Whether no point of triangle `p` is more than `tol` outside `piece`: a convex piece's
    /// value over the triangle is at most its largest at the corners; the lamina's prism, whose
    /// outline may be concave, has a bound of its own (`Prism::bound_over`).
    fn piece_holds(&self, piece: &Primitive, p: &[DVec3; 3], tol: f64) -> bool {
        match piece {
            Primitive::Prism(s) => s.bound_over(p) <= tol,
            _ => p.iter().all(|&v| piece.eval(v, self.reach) <= tol),
        }
    }

    /// Whether the triangle `p`, whose corners and centre are within `tol` of the surface, is
    /// within it everywhere: held by one convex piece (`one_holds`), or else (a triangle
    /// across a crease, or along a vein's smooth joints) sampled at the quarter points of its
    /// sides and inside.
    /// `near` are the two pieces least at each corner.
    fn holds(&self, p: &[DVec3; 3], near: [[u32; 2]; 3], tol: f64) -> bool {
        if self.one_holds(p, near, tol) {
            return true;
        }
        // The points (i, j, k) / 4, i + j + k = 4, but the corners and midpoints.
        const QUARTERS: [[f64; 3]; 9] = [
            [3.0, 1.0, 0.0],
            [1.0, 3.0, 0.0],
            [0.0, 3.0, 1.0],
            [0.0, 1.0, 3.0],
            [1.0, 0.0, 3.0],
            [3.0, 0.0, 1.0],
            [2.0, 1.0, 1.0],
            [1.0, 2.0, 1.0],
            [1.0, 1.0, 2.0],
        ];
        QUARTERS
            .iter()
            .all(|w| self.near((p[0] * w[0] + p[1] * w[1] + p[2] * w[2]) / 4.0, tol))
    }

    /// Whether triangle `p` may have a point more than `limit` outside the surface (outside,
    /// the value is the distance), with a proof when it has none: a corner is looked at
    /// first (more than `limit` out: off); then, as in `holds`, one convex piece within
    /// `limit` of all three corners holds the whole triangle (a convex piece's distance is
    /// at most its largest value at the corners, and the union's at most each piece's); a
    /// triangle no one piece holds (across a crease, or on the lamina's prism) is cut into
    /// four, and each quarter must be held by a piece near the triangle (`piece_holds`; the
    /// whole triangle first) or cut again, down to `HELD_DEPTH` times (quarters
    /// 1/1024 of the triangle's side), at most `HELD_QUARTERS` of them; what is not held by
    /// then counts as off.
    fn off(&self, p: &[DVec3; 3], limit: f64, near: &mut Vec<u32>) -> bool {
        if p.iter().any(|&x| self.eval(x) > limit) {
            return true;
        }
        if self.one_holds(p, p.map(|x| self.least(x)), limit) {
            return false;
        }
        let lo = p[0].min(p[1]).min(p[2]);
        let hi = p[0].max(p[1]).max(p[2]);
        self.pieces_in(lo, hi, near);
        let mut stack: Vec<([DVec3; 3], u32)> = vec![(*p, 0)];
        let mut looked = 0usize;
        while let Some((t, depth)) = stack.pop() {
            looked += 1;
            if looked > HELD_QUARTERS {
                return true;
            }
            let held = near
                .iter()
                .any(|&n| self.piece_holds(&self.prims[n as usize], &t, limit));
            if held {
                continue;
            }
            if depth >= HELD_DEPTH {
                return true;
            }
            let m = [
                0.5 * (t[0] + t[1]),
                0.5 * (t[1] + t[2]),
                0.5 * (t[2] + t[0]),
            ];
            // A new corner out by more than the limit: off, for sure.
            if m.iter().any(|&x| self.eval(x) > limit) {
                return true;
            }
            stack.extend([
                ([t[0], m[0], m[2]], depth + 1),
                ([m[0], t[1], m[1]], depth + 1),
                ([m[2], m[1], t[2]], depth + 1),
                ([m[0], m[1], m[2]], depth + 1),
            ]);
        }
        false
    }

    /// The pieces listed in the cells the box `lo`..`hi` meets, each once, in order.
    fn pieces_in(&self, lo: DVec3, hi: DVec3, out: &mut Vec<u32>) {
        out.clear();
        let c0 = ((lo - self.lo) / self.cell).floor();
        let c1 = ((hi - self.lo) / self.cell).floor();
        let range = |k: usize| {
            let top = self.dims[k] as f64 - 1.0;
            (
                c0[k].clamp(0.0, top) as usize,
                c1[k].clamp(0.0, top) as usize,
            )
        };
        if c1.min_element() < 0.0 || (0..3).any(|k| c0[k] > self.dims[k] as f64 - 1.0) {
            return;
        }
        let ([i0, i1], [j0, j1], [k0, k1]) = {
            let (a, b, c) = (range(0), range(1), range(2));
            ([a.0, a.1], [b.0, b.1], [c.0, c.1])
        };
        for i in i0..=i1 {
            for j in j0..=j1 {
                for k in k0..=k1 {
                    let at = (i * self.dims[1] + j) * self.dims[2] + k;
                    out.extend_from_slice(
                        &self.list[self.start[at] as usize..self.start[at + 1] as usize],
                    );
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }

    /// Whether some point of triangle `p` is surely more than `limit` inside the surface:
    /// deeper than that in one convex piece (the union's depth at a point is at least each
    /// piece's). Decided per piece near the triangle with a proof either way, as far as
    /// `FW_STEPS` steps go: a convex piece's distance lies above its tangent plane, so the
    /// plane at the centre bounds the least value over the triangle from below and rules most
    /// pieces out at once; the others are minimised over the triangle by Frank–Wolfe steps
    /// (towards the corner the gradient points most against, with a line search), each of
    /// which bounds the least value from below (the value less the duality gap) until the
    /// bound is above −`limit` or a point is deeper. Undecided counts as deep. Prisms (the
    /// lamina, whose outline may be concave) are not looked at.
    fn deep(&self, p: &[DVec3; 3], limit: f64, near: &mut Vec<u32>) -> bool {
        let lo = p[0].min(p[1]).min(p[2]);
        let hi = p[0].max(p[1]).max(p[2]);
        self.pieces_in(lo, hi, near);
        let centre = (p[0] + p[1] + p[2]) / 3.0;
        near.iter().any(|&n| {
            let piece = &self.prims[n as usize];
            if matches!(piece, Primitive::Prism(_)) {
                return false;
            }
            let f = |x: DVec3| piece.eval(x, self.reach);
            let grad = |x: DVec3| piece.gradient(x, self.reach, 1e-3 * limit);
            // The gradient's length is 1 but where it has none (on an axis): its bound is then
            // the value less the triangle's reach from there.
            let floor = |x: DVec3, fx: f64| {
                let g = grad(x);
                if g == DVec3::ZERO {
                    fx - p.iter().map(|v| v.distance(x)).fold(0.0, f64::max)
                } else {
                    fx + p
                        .iter()
                        .map(|&v| g.dot(v - x))
                        .fold(f64::INFINITY, f64::min)
                }
            };
            let fc = f(centre);
            if fc < -limit {
                return true;
            }
            if floor(centre, fc) >= -limit {
                return false;
            }
            let mut x = centre;
            let mut fx = fc;
            for &v in p {
                let fv = f(v);
                if fv < fx {
                    (x, fx) = (v, fv);
                }
            }
            for _ in 0..FW_STEPS {
                if fx < -limit {
                    return true;
                }
                let g = grad(x);
                if g == DVec3::ZERO {
                    return floor(x, fx) < -limit;
                }
                let s = *p
                    .iter()
                    .min_by(|a, b| g.dot(**a).total_cmp(&g.dot(**b)))
                    .unwrap_or(&x);
                let gap = g.dot(x - s);
                if fx - gap >= -limit {
                    return false;
                }
                // Golden-section search along x → s (the value is convex along it).
                let (mut a, mut b) = (0.0f64, 1.0f64);
                let r = 0.5 * (5f64.sqrt() - 1.0);
                let at = |t: f64| f(x + (s - x) * t);
                let (mut t1, mut t2) = (b - r * (b - a), a + r * (b - a));
                let (mut f1, mut f2) = (at(t1), at(t2));
                for _ in 0..20 {
                    if f1 < f2 {
                        b = t2;
                        (t2, f2) = (t1, f1);
                        t1 = b - r * (b - a);
                        f1 = at(t1);
                    } else {
                        a = t1;
                        (t1, f1) = (t2, f2);
                        t2 = a + r * (b - a);
                        f2 = at(t2);
                    }
                }
                let (t, ft) = if f1 < f2 { (t1, f1) } else { (t2, f2) };
                if ft < fx {
                    x += (s - x) * t;
                    fx = ft;
                } else {
                    // No progress along the line: the gap is what is left to prove.
                    return fx - gap < -limit;
                }
            }
            true
        })
    }

    /// Whether `p` is within `tol` of the surface: outside the value is the distance; inside
    /// it is one too where one piece alone is near. Elsewhere it is only a lower bound, so a
    /// point outside the union must be found within `tol`: first a step of `tol` out of
    /// either of the two least pieces, then a walk along the least piece's gradient.
    fn near(&self, p: DVec3, tol: f64) -> bool {
        let ((mut f, first), (second, other)) = self.two(p);
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
        for n in [first, other] {
            let g = self.piece_gradient(n, p, step);
            if g != DVec3::ZERO && self.eval(p + g * tol) >= 0.0 {
                return true;
            }
        }
        let (mut q, mut walked, mut n) = (p, 0.0, first);
        for _ in 0..6 {
            if -f + walked > tol {
                return false;
            }
            let g = self.piece_gradient(n, q, step);
            if g == DVec3::ZERO {
                return false;
            }
            // Past the surface by a hair, so a step that lands on it ends the walk.
            let s = -f + 1e-7;
            q += g * s;
            walked += s;
            ((f, n), _) = self.two(q);
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
    /// Triangles as marched (with the cells split where veins come close), after refinement,
    /// and at the end.
    pub marched: usize,
    pub refined: usize,
    pub triangles: usize,
    pub sweeps: usize,
    /// Grid cells split finer before simplifying, where veins come closer than the grid
    /// resolves (so the mesh does not bridge the gap between them).
    pub cells_split: usize,
    /// Triangles the last check still finds (or cannot prove not) more than the tolerance
    /// outside the surface or deeper than it in one vein, after its rounds of splitting (0:
    /// none).
    pub unheld: usize,
    /// Edges shorter than a hundredth of the tolerance collapsed, and slivers (triangles
    /// lower than that) flipped, before the last check (`tidy`).
    pub short_edges_collapsed: usize,
    pub slivers_flipped: usize,
    /// Vertices moved to fit the mesh to the surface on average (`fit_held`), and those put
    /// back because the move took a triangle out of the tolerance.
    pub fitted: usize,
    pub fit_put_back: usize,
    /// Vertices pushed apart where an edge was still shorter than a hundredth of the
    /// tolerance, or a triangle lower, or two triangles folded onto each other closer than that
    /// (`spread`), and such triangles left at the end.
    pub pushed_apart: usize,
    pub slivers_left: usize,
    /// Tetrahedra that still bridged such a gap at the finest split
    /// (`SolidReport::finest_split_mm`).
    pub gaps_left: usize,
    /// Tetrahedra at the finest split still spanning the very end of a sharp crotch (which
    /// narrows to nothing where two veins meet) by more than half the tolerance.
    pub crotch_ends: usize,
}

/// Refines and simplifies `mesh` (closed, 2-manifold, oriented, vertices on the surface of
/// `field`, edges at most `spacing` long) so it stays within `tol` of the surface, whose least
/// radius of curvature is about `radius`, and no vertex below `floor` (coordinate `axis` at
/// least `value`: the plate the solid stands on); then fits it to the surface on average, no
/// vertex leaving `bounds` (the solid's exact box). `progress` counts passes; asked to stop, the
/// simplification ends after the pass it is in (the mesh stays within `tol`: every collapse
/// was checked), and `None` is returned.
pub fn simplify(
    mesh: &mut TriMesh,
    field: &Field,
    tol: f64,
    (spacing, radius): (f64, f64),
    floor: Option<(usize, f64)>,
    bounds: (DVec3, DVec3),
    progress: &dyn crate::stage::Progress,
) -> Option<Simplified> {
    let marched = mesh.triangles.len();
    let debug = std::env::var_os("LAMINA_DEBUG_SIMPLIFY").is_some();
    let clock = std::time::Instant::now();
    if debug {
        eprintln!("marched: {} triangles, peak {}", marched, peak_memory());
    }
    refine(mesh, field, tol);
    if debug {
        eprintln!(
            "refined: {} triangles, {:.2} s, peak {}",
            mesh.triangles.len(),
            clock.elapsed().as_secs_f64(),
            peak_memory()
        );
    }
    let refined = mesh.triangles.len();
    // Between two witnesses the surface bulges by up to about spacing² / 8r: witnesses are
    // held that much closer.
    let bulge = spacing * spacing / (8.0 * radius.max(1e-9));
    let limits = Limits {
        field,
        tol,
        witness_tol: (tol - bulge).max(0.5 * tol),
    };
    let mut whole = Whole::new(mesh);
    let mut sweeps = 0;
    progress.begin("simplifying", Some(MAX_SWEEPS as u64));
    while sweeps < MAX_SWEEPS {
        sweeps += 1;
        // Bricks of about BRICK_TRIANGLES triangles of the mesh as it is now, shifted by
        // half a brick every other sweep so each sweep frees the last one's borders.
        let area: f64 = whole
            .triangles
            .par_iter()
            .map(|t| {
                let p = t.map(|v| whole.positions[v as usize]);
                0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
            })
            .sum();
        let side = (BRICK_TRIANGLES * area / whole.triangles.len().max(1) as f64).sqrt();
        let phase = if sweeps % 2 == 0 { 0.5 } else { 0.0 };
        let made = whole.sweep(&limits, sweeps as u32, side.max(1e-9), phase);
        if debug {
            eprintln!(
                "sweep {sweeps}: {made} collapses, {} triangles, bricks of {side:.3} mm, {:.2} s, \
                 peak {}",
                whole.triangles.len(),
                clock.elapsed().as_secs_f64(),
                peak_memory()
            );
        }
        progress.set(sweeps as u64);
        if progress.cancelled() {
            return None;
        }
        if (made as f64) < SETTLED * whole.live as f64 {
            break;
        }
    }
    whole.finish(mesh);
    let (collapsed, flipped) = tidy(mesh, tol);
    let shorts = |m: &TriMesh| {
        m.triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
            .filter(|&(a, b)| {
                a < b
                    && m.positions[a as usize].distance(m.positions[b as usize]) < COINCIDENT * tol
            })
            .count()
    };
    if debug {
        eprintln!(
            "tidied: {collapsed} short edges collapsed, {flipped} slivers flipped; {} short \
             edges left, {} triangles",
            shorts(mesh),
            mesh.triangles.len()
        );
    }
    let at_floor = |mesh: &mut TriMesh| {
        if let Some((axis, value)) = floor {
            for p in &mut mesh.positions {
                p[axis] = p[axis].max(value);
            }
        }
    };
    at_floor(mesh);
    let mut proofs = Proofs::new(tol);
    let (fitted, fit_put_back) = fit_held(mesh, field, bounds, &at_floor, &mut proofs);
    if progress.cancelled() {
        return None;
    }
    let (mut pushed_apart, ..) = spread(mesh, tol);
    at_floor(mesh);
    if debug {
        eprintln!(
            "fitted: {fitted} vertices moved, {fit_put_back} put back, {pushed_apart} pushed \
             apart, {:.2} s",
            clock.elapsed().as_secs_f64()
        );
    }
    let mut unheld = touch_up(mesh, field, tol, &mut proofs);
    // What fitting and the last check's splits made short, low or flat: tidied or pushed
    // apart, and checked again.
    let (mut collapsed, mut flipped) = (collapsed, flipped);
    for _ in 0..RETIDY_ROUNDS {
        let (c, f) = tidy(mesh, tol);
        let (pushed, found, left) = spread(mesh, tol);
        if c + f + pushed == 0 {
            break;
        }
        collapsed += c;
        flipped += f;
        pushed_apart += pushed;
        at_floor(mesh);
        let triangles = mesh.triangles.len();
        unheld = touch_up(mesh, field, tol, &mut proofs);
        // Nothing to tidy, no fewer defects for the pushing, nothing split since: another
        // round would push the same ones again.
        if c + f == 0 && left >= found && mesh.triangles.len() == triangles {
            break;
        }
    }
    let slivers_left = defects(mesh, COINCIDENT * tol, &across(mesh)).1;
    // What the last check's splits put below the plate by a rounding.
    at_floor(mesh);
    if debug {
        eprintln!("after the last check: {} short edges", shorts(mesh));
    }
    if debug {
        eprintln!(
            "touched up: {} triangles, {unheld} not held, {:.2} s",
            mesh.triangles.len(),
            clock.elapsed().as_secs_f64()
        );
    }
    Some(Simplified {
        tolerance_mm: tol,
        marched,
        refined,
        triangles: mesh.triangles.len(),
        sweeps,
        unheld,
        short_edges_collapsed: collapsed,
        slivers_flipped: flipped,
        fitted,
        fit_put_back,
        pushed_apart,
        slivers_left,
        ..Simplified::default()
    })
}

/// The process's peak resident memory so far (Linux; for `LAMINA_DEBUG_SIMPLIFY`).
fn peak_memory() -> String {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .map(|v| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

fn edge_key(a: u32, b: u32) -> u64 {
    let (a, b) = (a.min(b), a.max(b));
    (a as u64) << 32 | b as u64
}

/// Splits edges whose midpoints are off the surface (see the module notes).
fn refine(mesh: &mut TriMesh, field: &Field, tol: f64) {
    let step = 0.01 * tol;
    // After the first round only edges to new vertices are looked at again, and triangles
    // with one: the pieces of those the last round cut (`cut_edges` returns them).
    let mut last: Option<(usize, Vec<u32>)> = None;
    for _ in 0..REFINE_ROUNDS {
        let cut_last: Vec<[u32; 3]>;
        let (triangles, fresh) = match &last {
            None => (&mesh.triangles, None),
            Some((first, pieces)) => {
                cut_last = pieces.iter().map(|&k| mesh.triangles[k as usize]).collect();
                (&cut_last, Some(*first))
            }
        };
        let mut edges: Vec<(u32, u32)> = triangles
            .par_iter()
            .flat_map_iter(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .filter(|&(a, b)| a < b)
            .filter(|&(_, b)| fresh.is_none_or(|first| b as usize >= first))
            .collect();
        edges.par_sort_unstable();
        let positions = &mesh.positions;
        let off = |p: DVec3| {
            let f = field.eval(p);
            f > 0.25 * tol || f < -0.5 * tol
        };
        let on_surface = |a: u32, b: u32| {
            let m = 0.5 * (positions[a as usize] + positions[b as usize]);
            (a, b, field.project(m, step))
        };
        let mut split: Vec<(u32, u32, DVec3)> = edges
            .par_iter()
            .filter(|&&(a, b)| off(0.5 * (positions[a as usize] + positions[b as usize])))
            .map(|&(a, b)| on_surface(a, b))
            .collect();
        // A triangle whose centre is off (in a corner where three veins meet) though no
        // edge's midpoint is: its longest edge is split too.
        let mut longest: Vec<(u32, u32)> = triangles
            .par_iter()
            .filter(|t| fresh.is_none_or(|first| t.iter().any(|&v| v as usize >= first)))
            .filter_map(|t| {
                let p = t.map(|v| positions[v as usize]);
                if !off((p[0] + p[1] + p[2]) / 3.0) {
                    return None;
                }
                let k = (0..3)
                    .max_by(|&i, &j| {
                        let len = |k: usize| p[k].distance_squared(p[(k + 1) % 3]);
                        len(i).total_cmp(&len(j))
                    })
                    .unwrap_or(0);
                let (a, b) = (t[k], t[(k + 1) % 3]);
                Some((a.min(b), a.max(b)))
            })
            .collect();
        longest.sort_unstable();
        longest.dedup();
        longest.retain(|&(a, b)| {
            split
                .binary_search_by(|&(x, y, _)| (x, y).cmp(&(a, b)))
                .is_err()
        });
        split.extend(
            longest
                .par_iter()
                .map(|&(a, b)| on_surface(a, b))
                .collect::<Vec<_>>(),
        );
        if split.is_empty() {
            break;
        }
        last = Some(cut_edges(mesh, split, tol));
    }
}

/// The last check, of every triangle whole: no point of it may be more than `tol` outside the
/// surface (`Field::off`) nor deeper than `tol` in one piece (`Field::deep`). A triangle that
/// is, or is not proven not to be (one left across a crease, where refinement only looked at
/// midpoints and centres; one lying on a vein across a thinner one), has its longest edge and
/// each edge whose midpoint is not near split at the surface, for up to `TOUCH_ROUNDS` rounds.
/// Returns how many triangles are still off.
fn touch_up(mesh: &mut TriMesh, field: &Field, tol: f64, proofs: &mut Proofs) -> usize {
    let step = 0.01 * tol;
    for round in 0..=TOUCH_ROUNDS {
        let bad = check_triangles(mesh, field, proofs, &|_| true);
        let limit = proofs.limit;
        let positions = &mesh.positions;
        let corners = |t: &[u32; 3]| t.map(|v| positions[v as usize]);
        if bad.is_empty() || round == TOUCH_ROUNDS {
            return bad.len();
        }
        let split: Vec<(u32, u32, DVec3)> = bad
            .par_iter()
            .flat_map_iter(|t| {
                let p = corners(t);
                let len = |k: usize| p[k].distance_squared(p[(k + 1) % 3]);
                let longest = (0..3)
                    .max_by(|&i, &j| len(i).total_cmp(&len(j)))
                    .unwrap_or(0);
                (0..3)
                    .filter(move |&k| {
                        k == longest || !field.near(0.5 * (p[k] + p[(k + 1) % 3]), limit)
                    })
                    .map(move |k| {
                        let (a, b) = (t[k], t[(k + 1) % 3]);
                        let m = field.project(0.5 * (p[k] + p[(k + 1) % 3]), step);
                        (a.min(b), a.max(b), m)
                    })
            })
            .collect();
        cut_edges(mesh, split, tol);
    }
    0
}

/// Triangles the last check has proven within its limit, by their corners' bits: one whose
/// corners have not moved since needs no second proof (`fit_held` and each round of
/// `touch_up` look only at what moved or was cut).
///
/// The limit is `tol` less room for the rounding of vertices to 32-bit floats (two units in
/// the last place) at an extent a little past the mesh's; should the mesh reach further, the
/// limit tightens to match and the proofs are dropped.
struct Proofs {
    tol: f64,
    extent: f64,
    limit: f64,
    held: QuickSet<[u64; 9]>,
}

impl Proofs {
    fn new(tol: f64) -> Proofs {
        Proofs {
            tol,
            extent: 0.0,
            limit: tol,
            held: QuickSet::default(),
        }
    }

    /// The limit for `mesh` as it is now.
    fn limit(&mut self, mesh: &TriMesh) -> f64 {
        let extent = mesh
            .positions
            .iter()
            .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
        if extent > self.extent {
            self.extent = extent * (1.0 + 1e-3);
            self.limit = self.tol - 2.0 * self.extent * f64::from(f32::EPSILON);
            self.held.clear();
        }
        self.limit
    }

    fn key(p: &[DVec3; 3]) -> [u64; 9] {
        let b = |k: usize| p[k / 3][k % 3].to_bits();
        std::array::from_fn(b)
    }

    fn proven(&self, p: &[DVec3; 3]) -> bool {
        self.held.contains(&Proofs::key(p))
    }
}

/// Whether each triangle of `mesh` that `look` picks is off or deep (`Field::off`,
/// `Field::deep`), unless proven before; those found held are added to the proofs. Returns
/// the triangles found off, in order.
fn check_triangles(
    mesh: &TriMesh,
    field: &Field,
    proofs: &mut Proofs,
    look: &(dyn Fn(&[u32; 3]) -> bool + Sync),
) -> Vec<[u32; 3]> {
    let limit = proofs.limit(mesh);
    let known = &*proofs;
    let found: Vec<Result<[u64; 9], [u32; 3]>> = mesh
        .triangles
        .par_iter()
        .map_init(Vec::new, |near, t| {
            let p = mesh.corners(t);
            if !look(t) || known.proven(&p) {
                return None;
            }
            Some(
                if field.off(&p, limit, near) || field.deep(&p, limit, near) {
                    Err(*t)
                } else {
                    Ok(Proofs::key(&p))
                },
            )
        })
        .flatten()
        .collect();
    let mut off = Vec::new();
    for r in found {
        match r {
            Ok(key) => {
                proofs.held.insert(key);
            }
            Err(t) => off.push(t),
        }
    }
    off
}

/// Passes of `fit_held`.
const FIT_PASSES: usize = 2;
/// Rounds of putting vertices back in one pass of `fit_held`.
const FIT_ROUNDS: usize = 8;

/// Fits the simplified mesh to the surface on average (`fit`: its vertices lie on the surface
/// and its chords under a vein by up to the tolerance, so it is smaller than the solid), but
/// not where that takes a triangle out of the tolerance: after each pass the last check's test
/// looks at every triangle a vertex moved in, and the vertices of one it finds off go back to
/// where they were (rounds, looking again at the triangles around those, until none is off).
/// `floor` is applied after each move. Returns (vertices moved and left moved, vertices put
/// back).
fn fit_held(
    mesh: &mut TriMesh,
    field: &Field,
    bounds: (DVec3, DVec3),
    floor: &dyn Fn(&mut TriMesh),
    proofs: &mut Proofs,
) -> (usize, usize) {
    let start = mesh.positions.clone();
    let mut back = vec![false; start.len()];
    for _ in 0..FIT_PASSES {
        let before = mesh.positions.clone();
        super::fit::fit_passes(mesh, field, bounds, 1, &|| false);
        floor(mesh);
        // The triangles to look at: first those a vertex moved in, then those a vertex was
        // put back in (the others are as they were when last found held).
        let mut changed: Vec<bool> = (0..before.len())
            .map(|v| mesh.positions[v] != before[v])
            .collect();
        for _ in 0..FIT_ROUNDS {
            let positions = &mesh.positions;
            let look = |t: &[u32; 3]| {
                t.iter().any(|&v| changed[v as usize])
                    && t.iter()
                        .any(|&v| positions[v as usize] != before[v as usize])
            };
            let off = check_triangles(mesh, field, proofs, &look);
            changed.iter_mut().for_each(|c| *c = false);
            let mut put = 0;
            for v in off.into_iter().flatten() {
                let v = v as usize;
                if mesh.positions[v] != before[v] {
                    mesh.positions[v] = before[v];
                    back[v] = true;
                    changed[v] = true;
                    put += 1;
                }
            }
            if put == 0 {
                break;
            }
        }
    }
    let moved = (0..start.len())
        .filter(|&v| mesh.positions[v] != start[v])
        .count();
    (moved, back.iter().filter(|&&b| b).count())
}

/// Rounds of `tidy`.
const TIDY_ROUNDS: usize = 40;

/// Collapses every edge shorter than `COINCIDENT · tol` to its midpoint, flips the longest edge
/// of every triangle lower than that (a sliver with no short edge), and removes every vertex
/// whose triangles all lie within that distance of one plane (`tidy_flat`), where the mesh
/// stays a closed 2-manifold and no triangle turns over: an STL's 32-bit corners would merge the
/// ends of such an edge, or flatten such a triangle, and a reader would see a mesh that is not
/// closed; a reader that merges coplanar triangles into faces (manifold3d does, to 6 nm at
/// 50 mm) removes such a vertex itself, and where its triangles fold can pinch the mesh. A
/// collapse moves the surface by less than that length; the last check follows. Returns (edges
/// collapsed and flat vertices removed, edges flipped).
fn tidy(mesh: &mut TriMesh, tol: f64) -> (usize, usize) {
    let short = COINCIDENT * tol;
    let (mut collapsed, mut flipped) = (0, 0);
    for _ in 0..TIDY_ROUNDS {
        let (c, f) = (tidy_collapse(mesh, short), tidy_flip(mesh, short));
        let c = c + tidy_flat(mesh, short);
        collapsed += c;
        flipped += f;
        if c + f == 0 {
            break;
        }
    }
    mesh.drop_unused();
    (collapsed, flipped)
}

/// A vertex with three neighbours within this many `COINCIDENT · tol` of their plane is a
/// spike `tidy_flat` removes (the last check follows).
const SPIKE: f64 = 10.0;

/// Rounds of tidying again after the last check.
const RETIDY_ROUNDS: usize = 3;

/// Rounds of `spread`.
const SPREAD_ROUNDS: usize = 8;

/// Pushes apart what `tidy` could not remove: the ends of each edge shorter than `COINCIDENT ·
/// tol` move apart along it, and the apex of each triangle lower than that moves away from its
/// longest edge in its plane, until the edge or height is half as long again (a move of at
/// most 3/4 of `COINCIDENT · tol`); the far corner of a triangle folded onto its neighbour
/// moves off the neighbour's plane to 1.5 `COINCIDENT · tol` (`defects`); unless that turns a
/// triangle around the vertex by more than 60° (one with no area must come out facing as the
/// vertex's triangles do), when half or a quarter of the move, or as far towards the middle of
/// the vertex's ring, is tried; rounds until none is left. The mesh keeps its topology (where
/// a collapse would not: ends with three neighbours in common); the last check follows.
/// Returns (moves made, triangles with a defect at the start, those left).
fn spread(mesh: &mut TriMesh, tol: f64) -> (usize, usize, usize) {
    let short = COINCIDENT * tol;
    let mut pushed = 0;
    // Only vertices move: the triangles across each edge and around each vertex stay.
    let next = across(mesh);
    let at = around(mesh);
    let (mut moves, found) = defects(mesh, short, &next);
    let mut left = found;
    for _ in 0..SPREAD_ROUNDS {
        if moves.is_empty() {
            break;
        }
        let mut step = vec![DVec3::ZERO; mesh.positions.len()];
        // A vertex asked to move by several defects takes the longest move.
        let mut listed: Vec<u32> = Vec::new();
        for (v, d) in moves.drain(..) {
            let s = &mut step[v as usize];
            if *s == DVec3::ZERO {
                listed.push(v);
            }
            if d.length_squared() > s.length_squared() {
                *s = d;
            }
        }
        listed.sort_unstable();
        let mut made = 0;
        for v in listed {
            // No triangle around it may turn by more than 60°, nor over (a sliver's own
            // normal is rough: it may turn; one with no area, two corners on one point, has
            // none: it must come out facing as the triangles around the vertex do): else half
            // the move, or a quarter.
            let facing: DVec3 = at[v as usize]
                .iter()
                .map(|&f| normal(mesh.corners(&mesh.triangles[f as usize])))
                .sum();
            let keeps = |to: DVec3| {
                at[v as usize].iter().all(|&f| {
                    let t = mesh.triangles[f as usize];
                    let p = mesh.corners(&t);
                    let q = t.map(|w| {
                        if w == v {
                            to
                        } else {
                            mesh.positions[w as usize]
                        }
                    });
                    let (before, after) = (normal(p), normal(q));
                    if before == DVec3::ZERO {
                        return after.dot(facing) > 0.0;
                    }
                    let lens = before.length() * after.length();
                    let sliver = before.length() < short * short;
                    lens > 0.0 && before.dot(after) >= if sliver { 0.0 } else { 0.5 * lens }
                })
            };
            // Else as far towards the middle of its own ring (where two vertices lie on one
            // point, the way out that keeps each one's own triangles facing out).
            let from = mesh.positions[v as usize];
            let ring: Vec<DVec3> = at[v as usize]
                .iter()
                .flat_map(|&f| mesh.triangles[f as usize])
                .filter(|&w| w != v)
                .map(|w| mesh.positions[w as usize])
                .collect();
            let middle = ring.iter().sum::<DVec3>() / ring.len().max(1) as f64;
            let inwards = (middle - from).normalize_or_zero() * step[v as usize].length();
            if let Some(to) = [1.0, 0.5, 0.25]
                .into_iter()
                .map(|f| from + f * step[v as usize])
                .chain([1.0, 0.5, 0.25].into_iter().map(|f| from + f * inwards))
                .find(|&to| to != from && keeps(to))
            {
                mesh.positions[v as usize] = to;
                made += 1;
            }
        }
        pushed += made;
        if made == 0 {
            break;
        }
        (moves, left) = defects(mesh, short, &next);
    }
    (pushed, found, left)
}

/// The moves that would push apart each edge shorter than `short` and each triangle lower than
/// it to half as long again (see `spread`), and each fold (two triangles across an edge that
/// face opposite ways, the far corner of one within `short` of the other's plane: they lie on
/// each other) open until that corner is as far off the plane, on its side; and how many
/// triangles have one (a fold counts once from each side).
fn defects(mesh: &TriMesh, short: f64, across: &[[u32; 3]]) -> (Vec<(u32, DVec3)>, usize) {
    let want = 1.5 * short;
    let mut moves = Vec::new();
    let mut count = 0;
    for t in &mesh.triangles {
        let p = mesh.corners(t);
        let len = |k: usize| p[k].distance(p[(k + 1) % 3]);
        let k = (0..3)
            .min_by(|&i, &j| len(i).total_cmp(&len(j)))
            .unwrap_or(0);
        let (a, b) = ((k + 1) % 3, k);
        if len(k) < short {
            count += 1;
            // Apart along the edge (or, where its ends coincide, along the next edge), from
            // the one of its two triangles that runs along it from the lower vertex.
            let along = (p[a] - p[b])
                .try_normalize()
                .or_else(|| (p[(k + 2) % 3] - p[b]).try_normalize());
            if let Some(d) = along.filter(|_| t[b] < t[a]) {
                let step = 0.5 * (want - len(k)) * d;
                moves.push((t[a], step));
                moves.push((t[b], -step));
            }
            continue;
        }
        let j = (0..3)
            .max_by(|&i, &j| len(i).total_cmp(&len(j)))
            .unwrap_or(0);
        let height = normal(p).length() / len(j);
        if height < short {
            count += 1;
            // The apex c of (a, b, c) moves to its side of ab, in the plane.
            let (a, b, c) = (j, (j + 1) % 3, (j + 2) % 3);
            if let Some(u) = normal(p).cross(p[b] - p[a]).try_normalize() {
                moves.push((t[c], (want - height) * u));
            }
        }
    }
    // Folds. A reader that merges coplanar triangles (manifold3d, to 6 nm at 50 mm in 32-bit
    // corners) gives the second the first's normal, finds it turned over and splits the mesh.
    for (t, next) in mesh.triangles.iter().zip(across) {
        let p = mesh.corners(t);
        let Some(n) = normal(p).try_normalize() else {
            continue;
        };
        for j in 0..3 {
            let (a, b, u) = (t[j], t[(j + 1) % 3], next[j]);
            if u == NONE {
                continue;
            }
            let other = mesh.triangles[u as usize];
            let Some(&c) = other.iter().find(|&&v| v != a && v != b) else {
                continue;
            };
            if normal(mesh.corners(&other)).dot(n) >= 0.0 {
                continue;
            }
            let off = n.dot(mesh.positions[c as usize] - p[0]);
            if off.abs() < short {
                count += 1;
                moves.push((c, (want.copysign(off) - off) * n));
            }
        }
    }
    (moves, count)
}

/// A directed edge (from, to) as one key.
fn directed(a: u32, b: u32) -> u64 {
    (a as u64) << 32 | b as u64
}

/// Directed edges (`directed`) → the triangle that runs along each.
fn directed_edges(mesh: &TriMesh) -> HashMap<u64, u32, Quick> {
    let mut runs = HashMap::with_capacity_and_hasher(mesh.triangles.len() * 3, Quick);
    for (k, t) in mesh.triangles.iter().enumerate() {
        for j in 0..3 {
            runs.insert(directed(t[j], t[(j + 1) % 3]), k as u32);
        }
    }
    runs
}

/// Each triangle's neighbours: the one across its edge from corner j to corner j + 1, or
/// `NONE`.
fn across(mesh: &TriMesh) -> Vec<[u32; 3]> {
    let runs = directed_edges(mesh);
    let next = |t: &[u32; 3], j: usize| {
        runs.get(&directed(t[(j + 1) % 3], t[j]))
            .copied()
            .unwrap_or(NONE)
    };
    mesh.triangles
        .iter()
        .map(|t| [next(t, 0), next(t, 1), next(t, 2)])
        .collect()
}

/// Each vertex's triangles, in order: vertex v's are `list[start[v]..start[v + 1]]` (one
/// list for all, not one each: the tidying passes build this for every vertex, every round).
struct Stars {
    start: Vec<u32>,
    list: Vec<u32>,
}

impl std::ops::Index<usize> for Stars {
    type Output = [u32];
    fn index(&self, v: usize) -> &[u32] {
        &self.list[self.start[v] as usize..self.start[v + 1] as usize]
    }
}

/// Each vertex's triangles.
fn around(mesh: &TriMesh) -> Stars {
    let (start, list) = group(
        mesh.positions.len(),
        mesh.triangles
            .iter()
            .enumerate()
            .flat_map(|(k, t)| t.map(|v| (v, k as u32))),
    );
    Stars { start, list }
}

/// Twice the area times the unit normal.
fn normal(p: [DVec3; 3]) -> DVec3 {
    (p[1] - p[0]).cross(p[2] - p[0])
}

/// A triangle's height over its longest side.
fn height(p: [DVec3; 3]) -> f64 {
    let longest = (0..3)
        .map(|k| p[k].distance(p[(k + 1) % 3]))
        .fold(0.0, f64::max);
    normal(p).length() / longest.max(1e-300)
}

/// One pass of short-edge collapses; returns how many were made.
fn tidy_collapse(mesh: &mut TriMesh, short: f64) -> usize {
    let at = around(mesh);
    let mut edges: Vec<(f64, u32, u32)> = Vec::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let d = mesh.positions[a as usize].distance(mesh.positions[b as usize]);
            if a < b && d < short {
                edges.push((d, a, b));
            }
        }
    }
    edges.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    let mut dead = vec![false; mesh.triangles.len()];
    // Vertices whose triangles changed this pass: their edges wait for the next.
    let mut touched = vec![false; mesh.positions.len()];
    let mut made = 0;
    for (_, a, b) in edges {
        if touched[a as usize] || touched[b as usize] {
            continue;
        }
        let faces = |v: u32| {
            at[v as usize]
                .iter()
                .copied()
                .filter(|&f| !dead[f as usize])
        };
        let shared: Vec<u32> = faces(a)
            .filter(|&f| mesh.triangles[f as usize].contains(&b))
            .collect();
        if shared.len() != 2 {
            continue;
        }
        // The link condition: a and b have exactly the two opposite corners in common.
        let ring = |v: u32| {
            let mut r: Vec<u32> = faces(v)
                .flat_map(|f| mesh.triangles[f as usize])
                .filter(|&w| w != v)
                .collect();
            r.sort_unstable();
            r.dedup();
            r
        };
        let (ra, rb) = (ring(a), ring(b));
        let common: Vec<u32> = ra
            .iter()
            .copied()
            .filter(|w| rb.binary_search(w).is_ok())
            .collect();
        // Every vertex left keeps at least three neighbours: the merged one has those of both
        // but the two ends and the two in common; those two lose one each.
        let enough = ra.len() + rb.len() >= 7 && common.iter().all(|&w| ring(w).len() >= 4);
        if common.len() != 2 || !enough {
            continue;
        }
        let mid = 0.5 * (mesh.positions[a as usize] + mesh.positions[b as usize]);
        // No triangle left around a or b may turn over or vanish.
        let moved = |t: [u32; 3]| {
            t.map(|v| {
                if v == a || v == b {
                    mid
                } else {
                    mesh.positions[v as usize]
                }
            })
        };
        let keeps = faces(a)
            .chain(faces(b))
            .filter(|f| !shared.contains(f))
            .all(|f| {
                let t = mesh.triangles[f as usize];
                let before = normal(mesh.corners(&t));
                let after = normal(moved(t));
                after.dot(before) > 0.0 && after.length() > 0.0
            });
        if !keeps {
            continue;
        }
        for &f in &shared {
            dead[f as usize] = true;
        }
        for f in at[b as usize].iter().filter(|&&f| !dead[f as usize]) {
            for v in mesh.triangles[*f as usize].iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
        }
        mesh.positions[a as usize] = mid;
        for v in ra.iter().chain(&rb).chain([&a, &b]) {
            touched[*v as usize] = true;
        }
        made += 1;
        // b's triangles are a's now (the lists are rebuilt next pass; nothing here reads
        // a's list again: a is touched).
    }
    let mut k = 0;
    mesh.triangles.retain(|_| {
        k += 1;
        !dead[k - 1]
    });
    made
}

/// One pass of removing flat vertices: a vertex whose neighbours all lie within `short` of the
/// plane of its largest triangle, or that has three neighbours and lies within `SPIKE · short`
/// of their plane (a spike, its triangles facing every way: manifold3d removes those too), goes
/// into its nearest neighbour for which the mesh stays a closed 2-manifold (the link
/// condition, three neighbours left), no triangle turns over (where the triangles fold, fewer
/// face against the largest; a spike becomes one triangle) and none vanishes. Returns how many
/// were removed.
fn tidy_flat(mesh: &mut TriMesh, short: f64) -> usize {
    let at = around(mesh);
    let mut dead = vec![false; mesh.triangles.len()];
    // Vertices whose triangles changed this pass: they wait for the next.
    let mut touched = vec![false; mesh.positions.len()];
    let mut made = 0;
    // A vertex's neighbours, in order.
    fn ring_of(at: &Stars, triangles: &[[u32; 3]], v: u32, dead: &[bool]) -> Vec<u32> {
        let mut r: Vec<u32> = at[v as usize]
            .iter()
            .filter(|&&f| !dead[f as usize])
            .flat_map(|&f| triangles[f as usize])
            .filter(|&w| w != v)
            .collect();
        r.sort_unstable();
        r.dedup();
        r
    }
    for v in 0..mesh.positions.len() as u32 {
        if touched[v as usize] || at[v as usize].is_empty() {
            continue;
        }
        // Most vertices are neither flat nor a spike: that is told first, with nothing
        // allocated (in a closed 2-manifold a vertex has as many neighbours as triangles, so
        // only one with three triangles can be a spike).
        let live = || {
            at[v as usize]
                .iter()
                .copied()
                .filter(|&f| !dead[f as usize])
        };
        let area = |k: u32| normal(mesh.corners(&mesh.triangles[k as usize])).length();
        let at_v = mesh.positions[v as usize];
        let largest = live().max_by(|&f, &g| area(f).total_cmp(&area(g)).then(g.cmp(&f)));
        let Some(n) =
            largest.and_then(|f| normal(mesh.corners(&mesh.triangles[f as usize])).try_normalize())
        else {
            continue;
        };
        let near_plane = live().all(|f| {
            let p = mesh.corners(&mesh.triangles[f as usize]);
            p.iter().all(|&x| (x - at_v).dot(n).abs() < short)
        });
        if !near_plane && live().count() != 3 {
            continue;
        }
        let faces: Vec<u32> = at[v as usize]
            .iter()
            .copied()
            .filter(|&f| !dead[f as usize])
            .collect();
        let largest = faces.iter().copied().max_by(|&f, &g| {
            let area = |k: u32| normal(mesh.corners(&mesh.triangles[k as usize])).length();
            area(f).total_cmp(&area(g)).then(g.cmp(&f))
        });
        let Some(n) =
            largest.and_then(|f| normal(mesh.corners(&mesh.triangles[f as usize])).try_normalize())
        else {
            continue;
        };
        let ring = ring_of(&at, &mesh.triangles, v, &dead);
        let flat = ring.len() >= 3
            && ring
                .iter()
                .all(|&w| ((mesh.positions[w as usize] - at_v).dot(n)).abs() < short);
        // A spike: three triangles round a vertex within SPIKE · short of its neighbours'
        // plane, replaced by the triangle of those three (which faces as the three do on the
        // whole: their area vectors add up to its own).
        let spike = ring.len() == 3 && {
            let r = [ring[0], ring[1], ring[2]].map(|w| mesh.positions[w as usize]);
            normal(r)
                .try_normalize()
                .is_some_and(|m| (at_v - r[0]).dot(m).abs() < SPIKE * short)
        };
        if !flat && !spike {
            continue;
        }
        // Its neighbours, nearest first.
        let mut order = ring.clone();
        order.sort_by(|&a, &b| {
            let d = |w: u32| mesh.positions[w as usize].distance_squared(at_v);
            d(a).total_cmp(&d(b)).then(a.cmp(&b))
        });
        // (A touched neighbour's list of triangles is out of date.)
        for w in order.into_iter().filter(|&w| !touched[w as usize]) {
            let shared: Vec<u32> = faces
                .iter()
                .copied()
                .filter(|&f| mesh.triangles[f as usize].contains(&w))
                .collect();
            let rw = ring_of(&at, &mesh.triangles, w, &dead);
            let common = ring.iter().filter(|x| rw.binary_search(x).is_ok()).count();
            if shared.len() != 2 || common != 2 || ring.len() + rw.len() < 7 {
                continue;
            }
            let opposite: Vec<u32> = shared
                .iter()
                .flat_map(|&f| mesh.triangles[f as usize])
                .filter(|&x| x != v && x != w)
                .collect();
            if opposite
                .iter()
                .any(|&x| ring_of(&at, &mesh.triangles, x, &dead).len() < 4)
            {
                continue;
            }
            let to = mesh.positions[w as usize];
            let moved = |f: u32| {
                let t = mesh.triangles[f as usize];
                t.map(|x| {
                    if x == v {
                        to
                    } else {
                        mesh.positions[x as usize]
                    }
                })
            };
            let left = || faces.iter().copied().filter(|f| !shared.contains(f));
            // (A triangle left low is pushed apart after, by `spread`.)
            if left().any(|f| height(moved(f)).is_nan() || height(moved(f)) <= 0.0) {
                continue;
            }
            // No triangle turns over; or, where the fan folds (some of it faces against its
            // largest triangle), fewer of its triangles do after than before.
            let turns = left().any(|f| {
                let before = normal(mesh.corners(&mesh.triangles[f as usize]));
                normal(moved(f)).dot(before) <= 0.0
            });
            let against = |p: [DVec3; 3]| normal(p).dot(n) < 0.0;
            let folded_before = faces
                .iter()
                .filter(|&&f| against(mesh.corners(&mesh.triangles[f as usize])))
                .count();
            let folded_after = left().filter(|&f| against(moved(f))).count();
            if turns && folded_after >= folded_before && !spike {
                continue;
            }
            for &f in &shared {
                dead[f as usize] = true;
            }
            for &f in &faces {
                if !dead[f as usize] {
                    for x in mesh.triangles[f as usize].iter_mut() {
                        if *x == v {
                            *x = w;
                        }
                    }
                }
            }
            for x in ring.iter().chain(&rw).chain([&v, &w]) {
                touched[*x as usize] = true;
            }
            made += 1;
            break;
        }
    }
    let mut k = 0;
    mesh.triangles.retain(|_| {
        k += 1;
        !dead[k - 1]
    });
    made
}

/// One pass of flips of the longest edge of triangles lower than `short`; returns how many.
fn tidy_flip(mesh: &mut TriMesh, short: f64) -> usize {
    let mut edge = directed_edges(mesh);
    let mut busy = vec![false; mesh.triangles.len()];
    let mut made = 0;
    for k in 0..mesh.triangles.len() {
        let t = mesh.triangles[k];
        let p = mesh.corners(&t);
        if busy[k] || height(p) >= short {
            continue;
        }
        // Its longest edge (a, b), c opposite.
        let j = (0..3)
            .max_by(|&i, &j| {
                p[i].distance_squared(p[(i + 1) % 3])
                    .total_cmp(&p[j].distance_squared(p[(j + 1) % 3]))
            })
            .unwrap_or(0);
        let (a, b, c) = (t[j], t[(j + 1) % 3], t[(j + 2) % 3]);
        if p[j].distance(p[(j + 1) % 3]) < short {
            continue;
        }
        // The triangle across it runs b → a.
        let Some(&o) = edge.get(&directed(b, a)) else {
            continue;
        };
        if o as usize == k || busy[o as usize] {
            continue;
        }
        let u = mesh.triangles[o as usize];
        let Some(&d) = u.iter().find(|&&v| v != a && v != b) else {
            continue;
        };
        let new_edge = mesh.positions[c as usize].distance(mesh.positions[d as usize]);
        if d == c
            || new_edge < short
            || edge.contains_key(&directed(c, d))
            || edge.contains_key(&directed(d, c))
        {
            continue;
        }
        let (new1, new2) = ([a, d, c], [d, b, c]);
        let n_old = normal(p) + normal(mesh.corners(&u));
        let (q1, q2) = (mesh.corners(&new1), mesh.corners(&new2));
        let better = height(q1).min(height(q2)) > height(p).min(height(mesh.corners(&u)));
        if !(better && normal(q1).dot(n_old) > 0.0 && normal(q2).dot(n_old) > 0.0) {
            continue;
        }
        mesh.triangles[k] = new1;
        mesh.triangles[o as usize] = new2;
        edge.remove(&directed(a, b));
        edge.remove(&directed(b, a));
        for (from, to, tri) in [(a, d, k as u32), (d, c, k as u32), (c, a, k as u32)]
            .into_iter()
            .chain([(d, b, o), (b, c, o), (c, d, o)])
        {
            edge.insert(directed(from, to), tri);
        }
        busy[k] = true;
        busy[o as usize] = true;
        made += 1;
    }
    made
}

/// Splits each edge `(a, b)` of `split` at its point (on the surface), unless that point is
/// within `COINCIDENT · tol` of a vertex; returns the index of the first new vertex and the
/// triangles cut (each piece: the first in the old one's place, the others added at the end).
fn cut_edges(mesh: &mut TriMesh, mut split: Vec<(u32, u32, DVec3)>, tol: f64) -> (usize, Vec<u32>) {
    split.sort_unstable_by_key(|&(a, b, _)| (a, b));
    split.dedup_by_key(|&mut (a, b, _)| (a, b));
    let first = mesh.positions.len();
    let mut ends = vec![false; first];
    let mut mid: HashMap<u64, u32, Quick> = HashMap::with_capacity_and_hasher(split.len(), Quick);
    // No new vertex on another (two midpoints may move onto one crease point): the new ones
    // by cells `apart` wide, each cell's last (by number) in `taken`, the one before it in
    // `before` (a chain, not a list each: most cells hold one).
    let apart = COINCIDENT * tol;
    let mut taken: HashMap<[i64; 3], u32, Quick> = HashMap::with_hasher(Quick);
    let mut before: Vec<Option<u32>> = Vec::with_capacity(split.len());
    let cell_of = |p: DVec3| (p / apart).floor().as_i64vec3().to_array();
    for (a, b, p) in split {
        let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let c = cell_of(p);
        let positions = &mesh.positions;
        let crowded = (-1..=1).any(|i| {
            (-1..=1).any(|j| {
                (-1..=1).any(|k| {
                    let mut v = taken.get(&[c[0] + i, c[1] + j, c[2] + k]).copied();
                    while let Some(n) = v {
                        if positions[n as usize].distance(p) < apart {
                            return true;
                        }
                        v = before[n as usize - first];
                    }
                    false
                })
            })
        });
        if crowded || pa.distance(p) < apart || pb.distance(p) < apart {
            continue;
        }
        let n = mesh.positions.len() as u32;
        before.push(taken.insert(c, n));
        mid.insert(edge_key(a, b), n);
        mesh.positions.push(p);
        ends[a as usize] = true;
        ends[b as usize] = true;
    }
    // Each cut triangle's first piece in its place, the others after the last triangle.
    let cuts: Vec<(usize, [[u32; 3]; 4], usize)> = mesh
        .triangles
        .par_iter()
        .enumerate()
        .filter(|(_, t)| t.iter().any(|&v| ends[v as usize]))
        .filter_map(|(k, &t)| {
            let (tris, n) = cut(
                t,
                [0, 1, 2].map(|k| mid.get(&edge_key(t[k], t[(k + 1) % 3])).copied()),
            );
            (n > 1).then_some((k, tris, n))
        })
        .collect();
    let mut pieces = Vec::with_capacity(3 * cuts.len());
    for (k, tris, n) in cuts {
        mesh.triangles[k] = tris[0];
        pieces.push(k as u32);
        for t in &tris[1..n] {
            pieces.push(mesh.triangles.len() as u32);
            mesh.triangles.push(*t);
        }
    }
    (first, pieces)
}

/// Triangle `t` cut at the midpoints `m[k]` of its edges `(t[k], t[k + 1])`, same orientation:
/// the first so many of four (no allocation: millions are cut).
fn cut(t: [u32; 3], m: [Option<u32>; 3]) -> ([[u32; 3]; 4], usize) {
    match m.iter().filter(|x| x.is_some()).count() {
        0 => ([t; 4], 1),
        3 => {
            let [m0, m1, m2] = m.map(|x| x.unwrap_or_default());
            (
                [[t[0], m0, m2], [m0, t[1], m1], [m2, m1, t[2]], [m0, m1, m2]],
                4,
            )
        }
        n => {
            // Turn the triangle so edge 0 is cut and, with two cuts, edge 1 as well.
            let r = (0..3)
                .find(|&r| m[r].is_some() && (n == 1 || m[(r + 1) % 3].is_some()))
                .unwrap_or(0);
            let v = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
            let m0 = m[r].unwrap_or_default();
            if n == 1 {
                let two = [[v[0], m0, v[2]], [m0, v[1], v[2]]];
                ([two[0], two[1], two[1], two[1]], 2)
            } else {
                let m1 = m[(r + 1) % 3].unwrap_or_default();
                let three = [[m0, v[1], m1], [v[0], m0, m1], [v[0], m1, v[2]]];
                ([three[0], three[1], three[2], three[2]], 3)
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
    /// The two pieces least at `to`.
    least: [u32; 2],
    witnesses: Vec<(u32, u32)>,
}

/// The whole mesh between sweeps.
struct Whole {
    positions: Vec<DVec3>,
    /// Each vertex's quadric; empty before the first sweep, whose bricks sum their own
    /// vertices' planes (at ~100 bytes a vertex, the marched mesh's would be most of the
    /// memory), after which the vertices left are numbered anew.
    quadrics: Vec<Quadric>,
    triangles: Vec<[u32; 3]>,
    /// Surface points the mesh must stay near, and the triangle that keeps each.
    witness: Vec<DVec3>,
    owner: Vec<u32>,
    /// The sweep in which each vertex's star last changed, and edges rejected (by the sweep).
    changed: Vec<u32>,
    rejected: HashMap<u64, u32, Quick>,
    /// Vertices in use.
    live: usize,
}

impl Whole {
    /// Takes the mesh's vertices and triangles (`finish` puts the simplified ones back).
    fn new(mesh: &mut TriMesh) -> Whole {
        let n = mesh.positions.len();
        let mut owner = vec![u32::MAX; n];
        for (k, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                if owner[v as usize] == u32::MAX {
                    owner[v as usize] = k as u32;
                }
            }
        }
        let (witness, owner): (Vec<DVec3>, Vec<u32>) = mesh
            .positions
            .iter()
            .zip(&owner)
            .filter(|(_, &o)| o != u32::MAX)
            .map(|(&p, &o)| (p, o))
            .unzip();
        Whole {
            positions: std::mem::take(&mut mesh.positions),
            quadrics: Vec::new(),
            triangles: std::mem::take(&mut mesh.triangles),
            live: witness.len(),
            witness,
            owner,
            changed: vec![0; n],
            rejected: HashMap::with_hasher(Quick),
        }
    }

    /// One sweep: the mesh cut into bricks of side `side` (shifted by `phase` of a side),
    /// each simplified on its own with its border held, in parallel; returns the collapses.
    fn sweep(&mut self, limits: &Limits, sweep: u32, side: f64, phase: f64) -> usize {
        let brick_of = |t: &[u32; 3]| {
            let c = t.iter().map(|&v| self.positions[v as usize]).sum::<DVec3>() / 3.0;
            let k = (c / side + phase).floor();
            let key = |x: f64| (x as i64).clamp(-(1 << 20), 1 << 20) + (1 << 20);
            (key(k.x) << 42 | key(k.y) << 21 | key(k.z)) as u64
        };
        let keys: Vec<u64> = self.triangles.par_iter().map(brick_of).collect();
        // A vertex whose triangles lie in two bricks is held where it is.
        let mut home = vec![u64::MAX; self.positions.len()];
        let mut held = vec![false; self.positions.len()];
        for (t, &key) in self.triangles.iter().zip(&keys) {
            for &v in t {
                let h = &mut home[v as usize];
                if *h == u64::MAX {
                    *h = key;
                } else if *h != key {
                    held[v as usize] = true;
                }
            }
        }
        let mut order: Vec<u32> = (0..self.triangles.len() as u32).collect();
        order.par_sort_unstable_by_key(|&t| (keys[t as usize], t));
        let mut bricks: Vec<&[u32]> = order
            .chunk_by(|&x, &y| keys[x as usize] == keys[y as usize])
            .collect();
        drop((keys, home));
        // The biggest first, so the last to start are short.
        bricks.sort_by_key(|b| std::cmp::Reverse(b.len()));
        let by_owner = group(
            self.triangles.len(),
            self.owner.iter().enumerate().map(|(w, &t)| (t, w as u32)),
        );
        // The first sweep: the held vertices' quadrics from all their triangles (the bricks
        // sum their free vertices' own), in triangle order as a brick sums them.
        let first = self.quadrics.is_empty();
        let mut held_quadrics: HashMap<u32, Quadric, Quick> = HashMap::with_hasher(Quick);
        if first {
            for t in &self.triangles {
                if t.iter().any(|&v| held[v as usize]) {
                    let q = plane_of(t.map(|v| self.positions[v as usize]));
                    for &v in t.iter().filter(|&&v| held[v as usize]) {
                        let e = held_quadrics.entry(v).or_default();
                        *e = e.add(&q);
                    }
                }
            }
        }
        let whole = &*self;
        let done: Vec<Done> = bricks
            .par_iter()
            .map(|tris| {
                let mut b =
                    Brick::new(whole, limits.field, tris, &held, (&by_owner.0, &by_owner.1));
                b.run(limits);
                b.done()
            })
            .collect();
        drop(by_owner);

        // Stitch: each brick's triangles, in brick order; vertices off the borders moved.
        let mut triangles = Vec::with_capacity(done.iter().map(|d| d.triangles.len()).sum());
        let mut made = 0;
        for d in done {
            made += d.made;
            let start = triangles.len() as u32;
            triangles.extend(d.triangles);
            for (g, p, q) in d.moved {
                self.positions[g as usize] = p;
                if first {
                    held_quadrics.insert(g, q);
                } else {
                    self.quadrics[g as usize] = q;
                }
            }
            for g in d.changed {
                self.changed[g as usize] = sweep;
            }
            for (w, t) in d.owners {
                self.owner[w as usize] = start + t;
            }
            for e in d.rejected {
                self.rejected.insert(e, sweep);
            }
        }
        self.triangles = triangles;
        self.live -= made;
        if first {
            self.renumber(held_quadrics);
        }
        made
    }

    /// After the first sweep: the vertices still in use numbered anew (in their order), with
    /// their quadrics (`quadrics`: every one of them, by old number).
    fn renumber(&mut self, mut quadrics: HashMap<u32, Quadric, Quick>) {
        let n = self.positions.len();
        let mut index = vec![u32::MAX; n];
        for t in &self.triangles {
            for &v in t {
                index[v as usize] = 0;
            }
        }
        for (next, i) in index.iter_mut().filter(|i| **i == 0).enumerate() {
            *i = next as u32;
        }
        let keep = |i: usize| index[i] != u32::MAX;
        self.positions = (0..n)
            .filter(|&i| keep(i))
            .map(|i| self.positions[i])
            .collect();
        self.changed = (0..n)
            .filter(|&i| keep(i))
            .map(|i| self.changed[i])
            .collect();
        self.quadrics = (0..n as u32)
            .filter(|&i| keep(i as usize))
            .map(|i| quadrics.remove(&i).unwrap_or_default())
            .collect();
        for t in &mut self.triangles {
            *t = t.map(|v| index[v as usize]);
        }
        self.rejected = std::mem::take(&mut self.rejected)
            .into_iter()
            .filter_map(|(e, when)| {
                let (a, b) = (index[(e >> 32) as usize], index[e as u32 as usize]);
                (a != u32::MAX && b != u32::MAX).then(|| (edge_key(a, b), when))
            })
            .collect();
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

/// Working space of `Brick::check`, kept between checks.
#[derive(Default)]
struct Scratch {
    ring_a: Vec<u32>,
    ring_b: Vec<u32>,
    around: Vec<u32>,
    stars: Vec<u32>,
    new: Vec<(u32, [DVec3; 3])>,
}

/// A vertex of the refined mesh, which the triangle `owner` keeps near; `next` is the
/// owner's next witness.
#[derive(Clone, Copy)]
struct Witness {
    at: DVec3,
    owner: u32,
    next: u32,
}

/// No witness.
const NONE: u32 = u32::MAX;

/// What a brick hands back: its live triangles (whole indices), the vertices it moved, the
/// stars it changed, each witness's triangle (among its live ones), the edges it rejected.
struct Done {
    triangles: Vec<[u32; 3]>,
    moved: Vec<(u32, DVec3, Quadric)>,
    changed: Vec<u32>,
    owners: Vec<(u32, u32)>,
    rejected: Vec<u64>,
    made: usize,
}

/// Counting sort of (key, item) pairs: (start, items), key k's items at start[k]..start[k + 1].
pub(super) fn group(
    n: usize,
    items: impl Iterator<Item = (u32, u32)> + Clone,
) -> (Vec<u32>, Vec<u32>) {
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

/// What a collapse must keep (see the module notes).
struct Limits<'f, 'a> {
    field: &'f Field<'a>,
    tol: f64,
    /// How near each witness must stay.
    witness_tol: f64,
}

/// One brick of the mesh, simplified on its own: its triangles, the vertices they use (those
/// also used by another brick's triangles held), and the witnesses its triangles keep.
struct Brick {
    global: Vec<u32>,
    held: Vec<bool>,
    positions: Vec<DVec3>,
    quadrics: Vec<Quadric>,
    triangles: Vec<[u32; 3]>,
    dead: Vec<bool>,
    /// Vertex -> its live triangles.
    stars: Vec<Few<8>>,
    /// Witnesses (which each is in the whole), and each triangle's first witness (`NONE`
    /// for none): a list through `Witness::next`.
    witness: Vec<Witness>,
    wglobal: Vec<u32>,
    kept: Vec<u32>,
    /// The two pieces least at each vertex.
    least: Vec<[u32; 2]>,
    /// Stars changed here; edges (whole keys) rejected here; collapses made.
    changed: Vec<bool>,
    rejected: Vec<u64>,
    made: usize,
    /// Edges the whole rejected in an earlier sweep and when, for those within this brick.
    before: HashMap<u64, u32, Quick>,
    before_changed: Vec<u32>,
    /// Quadrics summed here (the first sweep): every free vertex's is handed back.
    fresh: bool,
}

impl Brick {
    fn new(
        whole: &Whole,
        field: &Field,
        tris: &[u32],
        held: &[bool],
        by_owner: (&[u32], &[u32]),
    ) -> Brick {
        let mut local: HashMap<u32, u32, Quick> = HashMap::with_hasher(Quick);
        let mut global = Vec::new();
        let mut triangles = Vec::with_capacity(tris.len());
        for &t in tris {
            triangles.push(whole.triangles[t as usize].map(|v| {
                *local.entry(v).or_insert_with(|| {
                    global.push(v);
                    global.len() as u32 - 1
                })
            }));
        }
        let n = global.len();
        let mut stars = vec![Few::default(); n];
        for (k, t) in triangles.iter().enumerate() {
            for &v in t {
                stars[v as usize].push(k as u32);
            }
        }
        let (mut witness, mut wglobal) = (Vec::new(), Vec::new());
        let mut kept = vec![NONE; triangles.len()];
        for (k, &t) in tris.iter().enumerate() {
            let (start, list) = by_owner;
            for &w in &list[start[t as usize] as usize..start[t as usize + 1] as usize] {
                witness.push(Witness {
                    at: whole.witness[w as usize],
                    owner: k as u32,
                    next: kept[k],
                });
                kept[k] = witness.len() as u32 - 1;
                wglobal.push(w);
            }
        }
        let mut before = HashMap::with_hasher(Quick);
        for t in &triangles {
            for k in 0..3 {
                let e = edge_key(global[t[k] as usize], global[t[(k + 1) % 3] as usize]);
                if let Some(&when) = whole.rejected.get(&e) {
                    before.insert(e, when);
                }
            }
        }
        Brick {
            held: global.iter().map(|&g| held[g as usize]).collect(),
            positions: global
                .iter()
                .map(|&g| whole.positions[g as usize])
                .collect(),
            quadrics: if whole.quadrics.is_empty() {
                // The first sweep: a free vertex's triangles are all here (a held one's
                // quadric is not used).
                let mut q = vec![Quadric::default(); n];
                for t in &triangles {
                    let plane = plane_of(t.map(|v| whole.positions[global[v as usize] as usize]));
                    for &v in t {
                        q[v as usize] = q[v as usize].add(&plane);
                    }
                }
                q
            } else {
                global.iter().map(|&g| whole.quadrics[g as usize]).collect()
            },
            fresh: whole.quadrics.is_empty(),
            least: global
                .iter()
                .map(|&g| field.least(whole.positions[g as usize]))
                .collect(),
            before_changed: global.iter().map(|&g| whole.changed[g as usize]).collect(),
            global,
            dead: vec![false; triangles.len()],
            triangles,
            stars,
            witness,
            wglobal,
            kept,
            changed: vec![false; n],
            rejected: Vec::new(),
            made: 0,
            before,
        }
    }

    fn key(&self, a: u32, b: u32) -> u64 {
        edge_key(self.global[a as usize], self.global[b as usize])
    }

    /// Whether the edge is worth trying: both ends free, and not rejected before with
    /// nothing around it changed since.
    fn open(&self, a: u32, b: u32) -> bool {
        if self.held[a as usize] || self.held[b as usize] {
            return false;
        }
        self.before.get(&self.key(a, b)).is_none_or(|&when| {
            self.changed[a as usize]
                || self.changed[b as usize]
                || self.before_changed[a as usize].max(self.before_changed[b as usize]) > when
        })
    }

    /// The edge's cost (quadric error per unit weight at its best point).
    fn cost(&self, a: u32, b: u32) -> f64 {
        let q = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        q.best(self.positions[a as usize], self.positions[b as usize])
            .1
    }

    /// Greedy edge collapse, cheapest first, until no edge within the tolerance passes.
    fn run(&mut self, limits: &Limits) {
        let tol2 = limits.tol * limits.tol;
        // (cost, a, b, collapses made when pushed): the cost as a 32-bit float, whose bits
        // order it (costs are never negative). An entry one of whose ends has changed since
        // (a collapse into it, or of it) is passed over: the change pushed the edge anew.
        let entry = |s: &Brick, a: u32, b: u32, when: u32| {
            if a == b || !s.open(a, b) {
                return None;
            }
            let (a, b) = (a.min(b), a.max(b));
            let e = s.cost(a, b);
            (e <= tol2).then_some(((e as f32).to_bits(), a, b, when))
        };
        let mut first = Vec::new();
        for t in 0..self.triangles.len() {
            let tri = self.triangles[t];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a < b {
                    first.extend(entry(self, a, b, 0));
                }
            }
        }
        let mut heap = Heap::from(first);
        let push = |heap: &mut Heap, s: &Brick, a, b, when| {
            if let Some(key) = entry(s, a, b, when) {
                heap.push(key);
            }
        };
        // How many collapses had been made when each vertex last changed (`self.made`).
        let mut changed_at = vec![0u32; self.positions.len()];
        let mut tried = std::collections::HashSet::with_hasher(Quick);
        // How many of each vertex's edges are in `tried` (or were, for a vertex collapsed
        // away): an edge neither of whose ends has one is not looked up.
        let mut rejects = vec![0u32; self.positions.len()];
        let mut scratch = Scratch::default();
        let (mut ring, mut both) = (Vec::new(), Vec::new());
        while let Some((_, a, b, when)) = heap.pop() {
            if self.stars[a as usize].is_empty()
                || self.stars[b as usize].is_empty()
                || changed_at[a as usize] > when
                || changed_at[b as usize] > when
            {
                continue;
            }
            match self.check(limits, a, b, &mut scratch) {
                None => {
                    if tried.insert(edge_key(a, b)) {
                        rejects[a as usize] += 1;
                        rejects[b as usize] += 1;
                    }
                }
                Some(c) => {
                    self.apply(&c, &mut ring, &mut both);
                    let made = self.made as u32;
                    changed_at[a as usize] = made;
                    changed_at[b as usize] = made;
                    // The merged vertex's edges anew; edges rejected around it again.
                    for &v in &ring {
                        push(&mut heap, self, a, v, made);
                    }
                    for &v in &ring {
                        if rejects[v as usize] == 0 {
                            continue;
                        }
                        for &t in &self.stars[v as usize] {
                            for &w in &self.triangles[t as usize] {
                                if w != v
                                    && w != a
                                    && rejects[w as usize] > 0
                                    && tried.remove(&edge_key(v, w))
                                {
                                    rejects[v as usize] -= 1;
                                    rejects[w as usize] -= 1;
                                    push(&mut heap, self, v, w, made);
                                }
                            }
                        }
                    }
                }
            }
        }
        self.rejected = tried
            .into_iter()
            .map(|e| {
                let (a, b) = ((e >> 32) as u32, e as u32);
                self.key(a, b)
            })
            .collect();
        self.rejected.sort_unstable();
    }

    /// Checks collapsing `b` into `a` (see the module notes); `scratch` is working space.
    fn check(&self, limits: &Limits, a: u32, b: u32, scratch: &mut Scratch) -> Option<Collapse> {
        let (sa, sb) = (&self.stars[a as usize], &self.stars[b as usize]);
        let ring = |s: &[u32], me: u32, r: &mut Vec<u32>| {
            r.clear();
            r.extend(
                s.iter()
                    .flat_map(|&t| self.triangles[t as usize])
                    .filter(|&v| v != me),
            );
            r.sort_unstable();
            r.dedup();
        };
        let Scratch {
            ring_a: ra,
            ring_b: rb,
            around,
            stars,
            new,
        } = scratch;
        ring(sa, a, ra);
        ring(sb, b, rb);
        let common = ra.iter().filter(|v| rb.binary_search(v).is_ok()).count();
        // `a` is in b's ring and b in a's; the two across the edge are common.
        if common != 2 {
            return None;
        }
        around.clear();
        around.extend(ra.iter().chain(rb.iter()).filter(|&&v| v != a && v != b));
        around.sort_unstable();
        around.dedup();
        if around.len() < 3 {
            return None;
        }
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let q = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        let (to, _) = q.best(pa, pb);
        let apart = COINCIDENT * limits.tol;
        if around
            .iter()
            .any(|&v| self.positions[v as usize].distance(to) < apart)
        {
            return None;
        }

        stars.clear();
        stars.extend(sa.iter().chain(sb));
        stars.sort_unstable();
        stars.dedup();
        // The triangles that stay, as they will be.
        new.clear();
        let mut gone = 0;
        let cos_max = 70f64.to_radians().cos();
        for &t in stars.iter() {
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
            // Not turned over, and no worse a sliver than it was (marching leaves slivers).
            if c.normalize_or_zero().dot(n_old) < cos_max
                || quality(&p) < MIN_QUALITY.min(0.5 * quality(&old))
            {
                return None;
            }
            new.push((t, p));
        }
        if gone != 2 {
            return None;
        }

        // The surface near the mesh (first: in later sweeps it rejects more, and more cheaply,
        // than the field's tests).
        let mut witnesses = Vec::new();
        for &t in stars.iter() {
            let mut w = self.kept[t as usize];
            while w != NONE {
                let Witness { at: x, next, .. } = self.witness[w as usize];
                // Any triangle within the tolerance keeps it: first the one that replaces
                // its own.
                let own = new.iter().position(|(k, _)| *k == t).unwrap_or(0);
                let k = (0..new.len())
                    .map(|i| (i + own) % new.len())
                    .find(|&i| point_triangle(x, &new[i].1) <= limits.witness_tol)?;
                witnesses.push((w, new[k].0));
                w = next;
            }
        }
        // The mesh near the surface.
        let (field, tol) = (limits.field, limits.tol);
        if !field.near(to, tol) {
            return None;
        }
        for &v in around.iter() {
            if !field.near(0.5 * (to + self.positions[v as usize]), tol) {
                return None;
            }
        }
        for (_, p) in new.iter() {
            if !field.near((p[0] + p[1] + p[2]) / 3.0, tol) {
                return None;
            }
        }
        let least = field.least(to);
        let corners = |t: u32| {
            self.triangles[t as usize].map(|v| {
                if v == a || v == b {
                    least
                } else {
                    self.least[v as usize]
                }
            })
        };
        if !new.iter().all(|&(t, p)| field.holds(&p, corners(t), tol)) {
            return None;
        }
        Some(Collapse {
            a,
            b,
            to,
            least,
            witnesses,
        })
    }

    fn done(self) -> Done {
        let mut index = vec![u32::MAX; self.triangles.len()];
        let mut triangles = Vec::with_capacity(self.triangles.len());
        for (k, t) in self.triangles.iter().enumerate() {
            if !self.dead[k] {
                index[k] = triangles.len() as u32;
                triangles.push(t.map(|v| self.global[v as usize]));
            }
        }
        // Only vertices still in use: those collapsed away are no triangle's any more (in
        // the first sweep most of them, whose quadrics alone would be ~100 bytes each).
        let alive = |l: usize| !self.stars[l].is_empty();
        let moved = (0..self.global.len())
            .filter(|&l| (self.changed[l] || self.fresh) && !self.held[l] && alive(l))
            .map(|l| (self.global[l], self.positions[l], self.quadrics[l]))
            .collect();
        Done {
            triangles,
            moved,
            changed: (0..self.global.len())
                .filter(|&l| self.changed[l] && alive(l))
                .map(|l| self.global[l])
                .collect(),
            owners: self
                .wglobal
                .iter()
                .zip(&self.witness)
                .map(|(&w, x)| (w, index[x.owner as usize]))
                .collect(),
            rejected: self.rejected,
            made: self.made,
        }
    }

    /// Makes the collapse; puts the merged vertex's ring in `ring`. `both` is working space.
    fn apply(&mut self, c: &Collapse, ring: &mut Vec<u32>, both: &mut Vec<u32>) {
        let (a, b) = (c.a, c.b);
        ring.clear();
        both.clear();
        both.extend_from_slice(&self.stars[a as usize]);
        both.extend_from_slice(&self.stars[b as usize]);
        let mut star = Few::default();
        for &t in both.iter() {
            let tri = &mut self.triangles[t as usize];
            if tri.contains(&a) && tri.contains(&b) {
                if !self.dead[t as usize] {
                    self.dead[t as usize] = true;
                    for &v in tri.iter() {
                        if v != a && v != b {
                            self.stars[v as usize].retain(|x| x != t);
                        }
                    }
                }
                continue;
            }
            for v in tri.iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            star.push(t);
            ring.extend(tri.iter().copied().filter(|&v| v != a));
        }
        ring.sort_unstable();
        ring.dedup();
        for &v in ring.iter() {
            self.changed[v as usize] = true;
        }
        self.changed[a as usize] = true;
        self.stars[a as usize] = star;
        self.stars[b as usize] = Few::default();
        self.positions[a as usize] = c.to;
        self.least[a as usize] = c.least;
        self.quadrics[a as usize] = self.quadrics[a as usize].add(&self.quadrics[b as usize]);
        for &(w, t) in &c.witnesses {
            let old = self.witness[w as usize].owner;
            if old != t {
                // Out of its old triangle's list, into the front of its new one's.
                let next = self.witness[w as usize].next;
                if self.kept[old as usize] == w {
                    self.kept[old as usize] = next;
                } else {
                    let mut v = self.kept[old as usize];
                    while self.witness[v as usize].next != w {
                        v = self.witness[v as usize].next;
                    }
                    self.witness[v as usize].next = next;
                }
                let x = &mut self.witness[w as usize];
                x.owner = t;
                x.next = self.kept[t as usize];
                self.kept[t as usize] = w;
            }
        }
        self.made += 1;
    }
}

/// A heap of edges, least (cost bits, a, b, when) first: four children to a node, so a pop
/// looks at half as many levels as a binary heap's, each level's children side by side in
/// memory (a brick's heap holds ~10⁵ entries, more than a core's cache). Each is kept as one
/// 128-bit number, whose order is the four's, so a comparison is one instruction pair, not
/// four branches.
struct Heap(Vec<u128>);

/// A heap entry: four numbers, compared in order.
type Entry = (u32, u32, u32, u32);

impl Heap {
    fn pack((w, x, y, z): Entry) -> u128 {
        (u128::from(w) << 96) | (u128::from(x) << 64) | (u128::from(y) << 32) | u128::from(z)
    }

    fn unpack(k: u128) -> Entry {
        (
            (k >> 96) as u32,
            (k >> 64) as u32,
            (k >> 32) as u32,
            k as u32,
        )
    }

    fn from(items: Vec<Entry>) -> Heap {
        let mut items: Vec<u128> = items.into_iter().map(Heap::pack).collect();
        let n = items.len();
        for i in (0..n.div_ceil(4)).rev() {
            Heap::down(&mut items, i);
        }
        Heap(items)
    }

    fn push(&mut self, item: Entry) {
        let item = Heap::pack(item);
        let v = &mut self.0;
        let mut i = v.len();
        v.push(item);
        while i > 0 {
            let up = (i - 1) / 4;
            if v[up] <= item {
                break;
            }
            v[i] = v[up];
            i = up;
        }
        v[i] = item;
    }

    fn pop(&mut self) -> Option<Entry> {
        let last = self.0.pop()?;
        if self.0.is_empty() {
            return Some(Heap::unpack(last));
        }
        let top = std::mem::replace(&mut self.0[0], last);
        Heap::down(&mut self.0, 0);
        Some(Heap::unpack(top))
    }

    /// Moves the item at `i` down to where its children are no less.
    fn down(v: &mut [u128], mut i: usize) {
        let item = v[i];
        loop {
            let first = 4 * i + 1;
            if first >= v.len() {
                break;
            }
            let end = (first + 4).min(v.len());
            let mut least = first;
            for c in first + 1..end {
                if v[c] < v[least] {
                    least = c;
                }
            }
            if v[least] >= item {
                break;
            }
            v[i] = v[least];
            i = least;
        }
        v[i] = item;
    }
}

fn plane_of(p: [DVec3; 3]) -> Quadric {
    let c = (p[1] - p[0]).cross(p[2] - p[0]);
    Quadric::plane(c.normalize_or_zero(), p[0], 0.5 * c.length())
}

/// 1 for an equilateral triangle, 0 for a flat one.
fn quality(p: &[DVec3; 3]) -> f64 {
    let c = (p[1] - p[0]).cross(p[2] - p[0]);
    let len2 = (p[1] - p[0]).length_squared()
        + (p[2] - p[1]).length_squared()
        + (p[0] - p[2]).length_squared();
    2.0 * 3f64.sqrt() * c.length() / len2.max(1e-300)
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
    use crate::fabricate::solid::sdf::{Polygon, Prism, RoundCone};
    use glam::DVec2;

    /// Two veins of radius 1 crossing at right angles, along x and y.
    fn cross() -> Vec<Primitive> {
        vec![
            Primitive::Cone(RoundCone::new(DVec3::X * -5.0, DVec3::X * 5.0, 1.0, 1.0)),
            Primitive::Cone(RoundCone::new(DVec3::Y * -5.0, DVec3::Y * 5.0, 1.0, 1.0)),
        ]
    }

    #[test]
    fn a_triangle_across_a_crease_is_held_only_if_all_of_it_is_near() {
        let prims = cross();
        let field = Field::new(&prims, 0.5);
        let tol = 0.01;
        let least = |p: &[DVec3; 3]| p.map(|v| field.least(v));
        // On the top of the x vein: held by that vein alone.
        let flat = [
            DVec3::new(2.0, -0.1, 1.0),
            DVec3::new(3.0, 0.1, 1.0),
            DVec3::new(2.5, 0.1, 1.0),
        ];
        assert!(field.holds(&flat, least(&flat), tol));
        // Corners on the two veins' sides, one in the notch: the flat triangle spans the notch.
        let on = |p: DVec3| field.project(p, 1e-6);
        let notch = [
            on(DVec3::new(1.6, 0.6, 0.0)),
            on(DVec3::new(0.6, 1.6, 0.0)),
            on(DVec3::new(1.1, 1.1, 0.45)),
        ];
        let corners_near = notch.iter().all(|&v| field.eval(v).abs() < tol);
        assert!(corners_near);
        assert!(!field.holds(&notch, least(&notch), tol));
    }

    #[test]
    fn the_last_check_proves_a_triangle_on_a_concave_lamina_held_or_finds_it_off() {
        // An L-shaped lamina 0.3 thick, its top at z = 0: (2, 2)–(4, 4) cut out.
        let outline = [
            (0.0, 0.0),
            (4.0, 0.0),
            (4.0, 2.0),
            (2.0, 2.0),
            (2.0, 4.0),
            (0.0, 4.0),
        ];
        // Buckets of 8, so the value is exact out to 8 (the bound is checked against it).
        let outline = Polygon::new(outline.map(|(x, y)| DVec2::new(x, y)).to_vec(), 8.0);
        let prims = vec![Primitive::Prism(Box::new(Prism {
            outline,
            z0: -0.3,
            z1: 0.0,
        }))];
        let field = Field::new(&prims, 0.5);
        let (tol, mut near) = (0.01, Vec::new());
        let top = [
            DVec3::new(0.5, 0.5, 0.0),
            DVec3::new(3.0, 0.5, 0.0),
            DVec3::new(0.5, 3.0, 0.0),
        ];
        assert!(
            !field.off(&top, tol, &mut near),
            "on the top face, inside the outline"
        );
        let wall = [
            DVec3::new(4.0, 0.5, -0.1),
            DVec3::new(4.0, 1.5, -0.1),
            DVec3::new(4.0, 1.0, -0.25),
        ];
        assert!(
            !field.off(&wall, tol, &mut near),
            "on a side along one edge"
        );
        // Its corners inside, but its side (3.5, 1.5)–(1.5, 3.5) crosses the notch, 0.71 out at
        // (2.5, 2.5).
        let across = [
            DVec3::new(3.5, 1.5, 0.0),
            DVec3::new(1.5, 3.5, 0.0),
            DVec3::new(1.5, 1.5, 0.0),
        ];
        assert!(field.off(&across, tol, &mut near), "across the notch");
        // The bound is never below the distance at any point of a triangle.
        let Primitive::Prism(prism) = &prims[0] else {
            unreachable!()
        };
        for i in 0..12 {
            for j in 0..12 {
                let c = DVec3::new(-1.0 + 0.5 * i as f64, -1.0 + 0.5 * j as f64, 0.05);
                let t = [
                    c,
                    c + DVec3::new(1.3, 0.2, 0.0),
                    c + DVec3::new(0.4, 1.1, -0.2),
                ];
                let bound = prism.bound_over(&t);
                for a in 0..=10 {
                    for b in 0..=10 - a {
                        let (u, v) = (a as f64 / 10.0, b as f64 / 10.0);
                        let x = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                        assert!(prism.eval(x, 10.0) <= bound + 1e-12, "{t:?} at {x}");
                    }
                }
            }
        }
    }

    #[test]
    fn the_last_check_proves_a_triangle_held_or_finds_it_off_both_ways() {
        // A thick vein (radius 10, its top at z = 1) along x and a thin one (radius 0.1, its
        // axis at z = 0.95) along y across it.
        let prims = vec![
            Primitive::Cone(RoundCone::new(
                DVec3::new(-5.0, 0.0, -9.0),
                DVec3::new(5.0, 0.0, -9.0),
                10.0,
                10.0,
            )),
            Primitive::Cone(RoundCone::new(
                DVec3::new(0.0, -5.0, 0.95),
                DVec3::new(0.0, 5.0, 0.95),
                0.1,
                0.1,
            )),
        ];
        let field = Field::new(&prims, 0.5);
        let (tol, mut near) = (0.01, Vec::new());
        // Lying on the thick vein's top with its corners outside the thin vein, but across
        // it: along x = 0 it is 0.05 mm inside the thin vein.
        let across = [
            DVec3::new(0.3, -0.2, 1.0),
            DVec3::new(-0.3, -0.2, 1.0),
            DVec3::new(0.3, 0.3, 1.0),
        ];
        assert!(across.iter().all(|&v| field.eval(v).abs() < tol));
        assert!(field.deep(&across, tol, &mut near));
        assert!(!field.off(&across, tol, &mut near), "nowhere far outside");
        // Beside the thin vein: proven neither deeper nor farther out than the tolerance.
        let beside = across.map(|v| v + DVec3::X * 2.0);
        assert!(!field.deep(&beside, tol, &mut near));
        assert!(!field.off(&beside, tol, &mut near));
        // Two veins of radius 1 side by side, 0.2 apart: a chord across both tops, its corners
        // on their outer sides, is held (the half on each side by that vein) though no one vein
        // holds all its corners.
        let pair = vec![
            Primitive::Cone(RoundCone::new(
                DVec3::new(-5.0, -0.1, 0.0),
                DVec3::new(5.0, -0.1, 0.0),
                1.0,
                1.0,
            )),
            Primitive::Cone(RoundCone::new(
                DVec3::new(-5.0, 0.1, 0.0),
                DVec3::new(5.0, 0.1, 0.0),
                1.0,
                1.0,
            )),
        ];
        let field = Field::new(&pair, 0.5);
        let z = (1.0f64 - 0.04).sqrt();
        let chord = [
            DVec3::new(0.0, -0.3, z),
            DVec3::new(0.0, 0.3, z),
            DVec3::new(0.4, 0.0, z),
        ];
        assert!(!field.one_holds(&chord, chord.map(|v| field.least(v)), tol));
        assert!(!field.off(&chord, tol, &mut near));
        // Two veins of radius 1 crossing: a wide triangle over the notch between them is off.
        let prims = cross();
        let field = Field::new(&prims, 0.5);
        let on = |p: DVec3| field.project(p, 1e-6);
        let notch = [
            on(DVec3::new(1.6, 0.6, 0.0)),
            on(DVec3::new(0.6, 1.6, 0.0)),
            on(DVec3::new(1.1, 1.1, 0.45)),
        ];
        assert!(field.off(&notch, tol, &mut near));
    }

    #[test]
    fn tidy_collapses_a_short_edge_and_keeps_the_mesh_closed() {
        // A box with one face's triangle split at a point 1 nm from a corner: three short or
        // sliver triangles around an edge of 1 nm.
        let mut m = TriMesh::cuboid(DVec3::ZERO, DVec3::ONE);
        let t = m.triangles[0];
        let [a, _, _] = m.corners(&t);
        let v = m.positions.len() as u32;
        let (c0, c1, c2) = (t[0], t[1], t[2]);
        let centroid = (m.corners(&t)[0] + m.corners(&t)[1] + m.corners(&t)[2]) / 3.0;
        m.positions.push(a + (centroid - a).normalize() * 1e-6);
        m.triangles[0] = [c0, c1, v];
        m.triangles.push([c1, c2, v]);
        m.triangles.push([c2, c0, v]);
        let volume = m.signed_volume();
        let (collapsed, _) = tidy(&mut m, 1e-3);
        assert_eq!(collapsed, 1);
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.positions.len(), 8);
        let topo = m.check_manifold();
        assert!(topo.is_manifold() && topo.closed);
        assert!((m.signed_volume() - volume).abs() < 1e-6);
    }

    #[test]
    fn tidy_removes_a_vertex_whose_triangles_lie_in_one_plane() {
        // A box with one face's triangle split at its centre: a vertex in a flat fan, its
        // edges long, its triangles not low; and one at a box corner, which is not flat.
        let mut m = TriMesh::cuboid(DVec3::ZERO, DVec3::ONE);
        let t = m.triangles[0];
        let v = m.positions.len() as u32;
        let p = m.corners(&t);
        m.positions.push((p[0] + p[1] + p[2]) / 3.0);
        m.triangles[0] = [t[0], t[1], v];
        m.triangles.push([t[1], t[2], v]);
        m.triangles.push([t[2], t[0], v]);
        let volume = m.signed_volume();
        let (collapsed, _) = tidy(&mut m, 1e-3);
        assert_eq!(collapsed, 1);
        assert_eq!((m.triangles.len(), m.positions.len()), (12, 8));
        let topo = m.check_manifold();
        assert!(topo.is_manifold() && topo.closed);
        assert!((m.signed_volume() - volume).abs() < 1e-12);
        // Nothing more: no corner of a box is flat.
        assert_eq!(tidy(&mut m, 1e-3), (0, 0));
        // The centre lifted out of the face by five hundredths of the tolerance: not flat,
        // but a spike of three triangles, removed.
        let t = m.triangles[0];
        let p = m.corners(&t);
        let lift = normal(p).normalize() * 5.0 * COINCIDENT * 1e-3;
        m.positions.push((p[0] + p[1] + p[2]) / 3.0 + lift);
        m.triangles[0] = [t[0], t[1], v];
        m.triangles.push([t[1], t[2], v]);
        m.triangles.push([t[2], t[0], v]);
        assert_eq!(tidy(&mut m, 1e-3).0, 1);
        assert_eq!((m.triangles.len(), m.positions.len()), (12, 8));
        assert!(m.check_manifold().closed);
    }

    #[test]
    fn spread_pushes_a_short_edge_and_a_sliver_apart_and_keeps_the_topology() {
        let tol = 1e-3;
        let short = COINCIDENT * tol;
        // A box whose first triangle is split at a point near one of its points: three
        // triangles around it, one with a short edge or two low ones.
        let split_at = |at: &dyn Fn([DVec3; 3]) -> DVec3| {
            let mut m = TriMesh::cuboid(DVec3::ZERO, DVec3::ONE);
            let t = m.triangles[0];
            let v = m.positions.len() as u32;
            m.positions.push(at(m.corners(&t)));
            m.triangles[0] = [t[0], t[1], v];
            m.triangles.push([t[1], t[2], v]);
            m.triangles.push([t[2], t[0], v]);
            m
        };
        let near_corner =
            |p: [DVec3; 3]| p[0] + ((p[0] + p[1] + p[2]) / 3.0 - p[0]).normalize() * 1e-6;
        // 1 nm off the middle of the first edge, towards the triangle.
        let near_edge = |p: [DVec3; 3]| {
            let mid = 0.5 * (p[0] + p[1]);
            mid + ((p[0] + p[1] + p[2]) / 3.0 - mid).normalize() * 1e-6
        };
        // Exactly on a corner: two vertices on one point, two triangles with no area.
        let on_corner = |p: [DVec3; 3]| p[0];
        for (name, at) in [
            ("short edge", &near_corner as &dyn Fn([DVec3; 3]) -> DVec3),
            ("sliver", &near_edge),
            ("one point", &on_corner),
        ] {
            let mut m = split_at(at);
            let volume = m.signed_volume();
            assert!(defects(&m, short, &across(&m)).1 > 0, "{name}");
            let (pushed, _, left) = spread(&mut m, tol);
            assert!(
                pushed > 0 && left == 0,
                "{name}: {pushed} pushed, {left} left"
            );
            assert_eq!(defects(&m, short, &across(&m)).1, 0, "{name}");
            assert_eq!((m.triangles.len(), m.positions.len()), (14, 9), "{name}");
            let topo = m.check_manifold();
            assert!(topo.is_manifold() && topo.closed, "{name}");
            // No vertex moved by more than 3/4 of `short`: the volume (area 6) within that.
            assert!(
                (m.signed_volume() - volume).abs() <= 6.0 * 0.75 * short,
                "{name}"
            );
            assert!(
                m.positions[..8]
                    .iter()
                    .zip(&TriMesh::cuboid(DVec3::ZERO, DVec3::ONE).positions)
                    .all(|(p, q)| p.distance(*q) <= 0.75 * short),
                "{name}"
            );
        }
    }

    #[test]
    fn spread_opens_a_fold_and_keeps_the_topology() {
        let tol = 1e-3;
        let short = COINCIDENT * tol;
        // A tetrahedron pressed flat: its apex 1 nm over its base, so each side lies on the
        // base (they face opposite ways), though no edge is short and no triangle low.
        let flat = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.3, 0.3, 1e-9)];
        let mut m = TriMesh {
            positions: flat.to_vec(),
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
            colors: None,
        };
        assert!(m.triangles.iter().all(|t| height(m.corners(t)) > short));
        assert!(defects(&m, short, &across(&m)).1 > 0);
        let (pushed, _, left) = spread(&mut m, tol);
        assert!(pushed > 0 && left == 0, "{pushed} pushed, {left} left");
        assert_eq!((m.triangles.len(), m.positions.len()), (4, 4));
        let topo = m.check_manifold();
        assert!(topo.is_manifold() && topo.closed);
        // Opened the right way (outwards still out), each corner moved by at most 1.5 short.
        assert!(m.signed_volume() > 0.0);
        assert!(m
            .positions
            .iter()
            .zip(&flat)
            .all(|(p, q)| p.distance(*q) <= 1.5 * short + 1e-9));
    }

    #[test]
    fn a_point_over_a_triangle_is_its_height_and_beside_it_the_nearest_edge() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!((point_triangle(DVec3::new(0.2, 0.2, 0.5), &t) - 0.5).abs() < 1e-12);
        assert!((point_triangle(DVec3::new(2.0, 0.0, 0.0), &t) - 1.0).abs() < 1e-12);
        assert!((point_triangle(DVec3::new(0.5, -1.0, 0.0), &t) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_edge_heap_pops_in_order_whatever_came_in_between() {
        use rand::{Rng, SeedableRng};
        // Seeded keys, many equal; pushes and pops interleaved.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut key = || {
            (
                rng.random_range(0..97u32),
                rng.random_range(0..5u32),
                rng.random_range(0..5u32),
                rng.random_range(0..3u32),
            )
        };
        let first: Vec<Entry> = (0..1000).map(|_| key()).collect();
        let mut heap = Heap::from(first.clone());
        let mut all = first;
        let mut popped = Vec::new();
        for round in 0..3000 {
            if round % 3 == 2 {
                let k = key();
                heap.push(k);
                all.push(k);
            } else if let Some(k) = heap.pop() {
                // Nothing left in the heap is less than what it gives.
                assert!(heap.0.iter().all(|&o| Heap::unpack(o) >= k));
                popped.push(k);
            }
        }
        // Drained, it gives the rest in order.
        let mut rest = Vec::new();
        while let Some(k) = heap.pop() {
            rest.push(k);
        }
        assert!(rest.windows(2).all(|w| w[0] <= w[1]));
        popped.extend(rest);
        popped.sort_unstable();
        all.sort_unstable();
        assert_eq!(popped, all);
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
            let (made, n) = cut([0, 1, 2], m);
            let made = &made[..n];
            assert_eq!(made.len(), 1 + mask.count_ones() as usize);
            assert!(made.iter().all(|t| area(t) > 0.0));
            let total: f64 = made.iter().map(area).sum();
            assert!((total - 0.5).abs() < 1e-12);
        }
    }
}
