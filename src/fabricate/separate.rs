//! Denser sheets by overlap minimisation: an item is put on a sheet where it overlaps the least,
//! then the overlaps are driven to zero by moving the items in collision one at a time to the
//! place (and rotation) where their weighted overlap is least, raising the weights of pairs that
//! stay in collision and letting the others decay (guided local search), going back to the least
//! overlapping arrangement after rounds without progress (strikes), as the best open
//! strip-packing heuristics do (Gardeyn and Vanden Berghe's sparrow; Egeblad et al. before it).
//! If the overlaps reach zero the sheet holds one more item; if not within the attempt's work,
//! the sheet is left as it was.
//! The same search compresses a sheet: its room made a little shorter, the items over the new
//! wall separated back inside (sparrow's exploration, on a sheet of fixed width).
//!
//! Items are convex polygons (the nester's grown hulls), so the overlap of two is exact and
//! cheap: the penetration depth along the separating axes (the edge normals of both, each
//! polygon's extent along its own known in advance); two items are clear when an axis
//! separates them by at least [`GAP`]. An item's neighbours are found in a uniform grid of
//! cells about an item wide, and a place's loss stops being summed once it exceeds the best
//! place found so far (sparrow's early exit). Box tests against every item were most of the
//! work counted before the grid. The container is a rectangle; an
//! item's excess over its walls counts as overlap too. A collision's loss is its depth plus a
//! small floor (`EPSILON` of the larger item), times a size penalty (sparrow's: the geometric
//! mean of the square roots of the two areas), so that large items are moved apart first and
//! small ones fill in around them: with depth alone the Calyx plates' strip came out 7 % longer
//! (2,440 mm against 2,280 with the penalty, before decay and strikes; BENCHMARKS.md).
//!
//! Work is counted in pair evaluations, not seconds, so that the same inputs and seed give the
//! same sheets on any machine; [`EVALS_PER_SECOND`] converts a time budget into work.

use glam::DVec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::ops::ControlFlow;

/// Two items are clear when an axis separates them by at least this, mm (the nester's slide
/// backoff; jagua-rs confirms every result in its own arithmetic).
pub const GAP: f64 = 0.005;
/// Pair evaluations per second of budget: what the 2-core machine of BENCHMARKS.md (2026-11-29)
/// does with both cores, the two workers of a round counted; a budget is work, so results do
/// not depend on the machine.
pub const EVALS_PER_SECOND: f64 = 5.0e6;
/// Each round of moves is made by this many workers at once (on as many threads), from the
/// same arrangement in different orders; the one with the least weighted loss is kept
/// (sparrow's). Work counts every worker's, so a budget buys the same evaluations on any
/// number of cores.
const WORKERS: usize = 2;
/// Rounds without a new (substantially) least total overlap that make a strike.
const STALL: usize = 40;
/// Strikes in a row after which a separation gives up.
const STRIKES: usize = 3;
/// A new least overlap below this fraction of the last counts as progress.
const SUBSTANTIAL: f64 = 0.98;
/// What a pair's weight is multiplied by in a round it is not in collision (down to 1).
const DECAY: f64 = 0.95;
/// Every collision costs at least this fraction of the larger item's box diagonal (times the
/// pair's size penalty): a slight overlap is not left for later.
const EPSILON: f64 = 0.01;
/// Positions sampled over the whole container per move (per rotation).
const GLOBAL: usize = 24;
/// Positions sampled near the current one per move.
const LOCAL: usize = 24;

/// One rotation of an item: its convex polygon with its bounding box's corner at the origin.
#[derive(Clone, Debug)]
pub struct Form {
    pub pts: Vec<DVec2>,
    pub size: DVec2,
    /// Unit edge normals, one per direction (an edge parallel to an earlier one adds none: the
    /// overlap of two projections on −n is their overlap on n), with the polygon's extent
    /// along each.
    axes: Vec<Axis>,
    /// The square root of its area's square root (the size penalty's factor), and its box's
    /// diagonal.
    root: f64,
    diameter: f64,
}

impl Form {
    pub fn new(pts: Vec<DVec2>) -> Form {
        let lo = pts.iter().fold(DVec2::INFINITY, |m, q| m.min(*q));
        let hi = pts.iter().fold(DVec2::NEG_INFINITY, |m, q| m.max(*q));
        let n = pts.len();
        let mut axes: Vec<Axis> = Vec::with_capacity(n);
        for k in 0..n {
            let e = pts[(k + 1) % n] - pts[k];
            if e.length() <= 1e-12 {
                continue;
            }
            let normal = DVec2::new(e.y, -e.x).normalize();
            if axes.iter().any(|a| a.normal.perp_dot(normal).abs() < 1e-12) {
                continue;
            }
            let (lo, hi) = extent(&pts, normal);
            axes.push(Axis { normal, lo, hi });
        }
        let area = crate::rationalize::plates::polygon_area(&pts).abs();
        Form {
            pts,
            size: hi - lo,
            axes,
            root: area.sqrt().sqrt(),
            diameter: (hi - lo).length(),
        }
    }
}

/// An item on a sheet: which form (rotation) and where its box's corner is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    pub item: usize,
    pub form: usize,
    pub at: DVec2,
}

/// A separating axis of a form: an edge normal and the form's extent along it.
#[derive(Clone, Copy, Debug)]
struct Axis {
    normal: DVec2,
    lo: f64,
    hi: f64,
}

/// The least and greatest of `pts` projected on `n`.
fn extent(pts: &[DVec2], n: DVec2) -> (f64, f64) {
    pts.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let t = p.dot(n);
            (lo.min(t), hi.max(t))
        })
}

/// How deep `a` at `pa` and `b` at `pb` overlap (least projection overlap over both polygons'
/// edge normals), less [`GAP`]: ≤ 0 when they are clear. Each form's extent along its own
/// axes is known; only the other one is projected.
fn depth(a: &Form, pa: DVec2, b: &Form, pb: DVec2) -> f64 {
    // In a's frame: b is at `d`.
    let d = pb - pa;
    let mut least = f64::INFINITY;
    for axis in &a.axes {
        let (b0, b1) = extent(&b.pts, axis.normal);
        let off = d.dot(axis.normal);
        let o = (axis.hi - b0 - off).min(b1 + off - axis.lo);
        if o < least {
            least = o;
            if least + GAP <= 0.0 {
                return least + GAP;
            }
        }
    }
    for axis in &b.axes {
        let (a0, a1) = extent(&a.pts, axis.normal);
        let off = d.dot(axis.normal);
        let o = (a1 - axis.lo - off).min(axis.hi + off - a0);
        if o < least {
            least = o;
            if least + GAP <= 0.0 {
                return least + GAP;
            }
        }
    }
    least + GAP
}

/// The loss of two forms `d` deep in each other (`d` > 0): the depth plus [`EPSILON`] of the
/// larger, times the geometric mean of the square roots of their areas, so that two large items
/// in collision cost more than two small ones (sparrow's shape penalty).
fn loss(d: f64, f: &Form, g: &Form) -> f64 {
    (d + EPSILON * f.diameter.max(g.diameter)) * (f.root * g.root).sqrt()
}

/// Pairs in collision and their unweighted loss: (i, j, loss), a wall excess as (i, i).
type Pairs = Vec<(usize, usize, f64)>;

/// The spots by the cells of a uniform grid over the room that their boxes (grown by [`GAP`])
/// cover, so that a form's neighbours are looked for in the cells its box covers, not among all
/// the spots. Boxes beyond the room count in its edge cells.
#[derive(Clone)]
struct Grid {
    cell: f64,
    cols: u32,
    rows: u32,
    cells: Vec<Vec<u32>>,
    /// Each spot's cells: [x0, y0, x1, y1], inclusive.
    range: Vec<[u32; 4]>,
}

/// The most cells a grid has along either side.
const GRID_MOST: u32 = 256;

impl Grid {
    /// A grid over `room` whose cells are about as large as the spots' boxes on average.
    fn new(forms: &[Vec<Form>], room: DVec2, spots: &[Spot]) -> Grid {
        let mean = spots
            .iter()
            .map(|s| forms[s.item][s.form].size.max_element())
            .sum::<f64>()
            / spots.len().max(1) as f64;
        let cell = mean.max(room.max_element() / GRID_MOST as f64).max(1e-6);
        let count = |v: f64| ((v / cell).ceil() as u32).clamp(1, GRID_MOST);
        let (cols, rows) = (count(room.x), count(room.y));
        let mut grid = Grid {
            cell,
            cols,
            rows,
            cells: vec![Vec::new(); (cols * rows) as usize],
            range: vec![[0; 4]; spots.len()],
        };
        for (k, s) in spots.iter().enumerate() {
            grid.insert(k, s.at, s.at + forms[s.item][s.form].size);
        }
        grid
    }

    /// The cells a box from `lo` to `hi` (grown by [`GAP`]) covers.
    fn cover(&self, lo: DVec2, hi: DVec2) -> [u32; 4] {
        let at = |v: f64, most: u32| ((v / self.cell).floor().max(0.0) as u32).min(most - 1);
        [
            at(lo.x - GAP, self.cols),
            at(lo.y - GAP, self.rows),
            at(hi.x + GAP, self.cols),
            at(hi.y + GAP, self.rows),
        ]
    }

    fn insert(&mut self, k: usize, lo: DVec2, hi: DVec2) {
        let r = self.cover(lo, hi);
        self.range[k] = r;
        for y in r[1]..=r[3] {
            for x in r[0]..=r[2] {
                self.cells[(y * self.cols + x) as usize].push(k as u32);
            }
        }
    }

    fn remove(&mut self, k: usize) {
        let r = self.range[k];
        for y in r[1]..=r[3] {
            for x in r[0]..=r[2] {
                let cell = &mut self.cells[(y * self.cols + x) as usize];
                if let Some(at) = cell.iter().position(|&j| j as usize == k) {
                    cell.swap_remove(at);
                }
            }
        }
    }

    /// Calls `f` on each spot whose cells meet those of the box from `lo` to `hi`, once (in
    /// the first cell both cover), until `f` breaks; returns how many entries were looked at.
    fn visit(&self, lo: DVec2, hi: DVec2, mut f: impl FnMut(usize) -> ControlFlow<()>) -> u64 {
        let q = self.cover(lo, hi);
        let mut looked = 0;
        for y in q[1]..=q[3] {
            for x in q[0]..=q[2] {
                let cell = &self.cells[(y * self.cols + x) as usize];
                looked += cell.len() as u64;
                for &j in cell {
                    let r = self.range[j as usize];
                    if x == r[0].max(q[0]) && y == r[1].max(q[1]) && f(j as usize).is_break() {
                        return looked;
                    }
                }
            }
        }
        looked
    }
}

/// Whether the box from `lo` to `hi` and a form's box at `at` are apart by more than [`GAP`].
fn boxes_apart(lo: DVec2, hi: DVec2, at: DVec2, g: &Form) -> bool {
    at.x > hi.x + GAP
        || at.y > hi.y + GAP
        || at.x + g.size.x < lo.x - GAP
        || at.y + g.size.y < lo.y - GAP
}

/// A sheet being separated.
#[derive(Clone)]
pub struct Separation<'a> {
    forms: &'a [Vec<Form>],
    /// The container's size; items keep `clear` off its walls.
    room: DVec2,
    clear: f64,
    pub spots: Vec<Spot>,
    /// Pair weights, by position in `spots` (upper triangle; the diagonal weighs a spot's
    /// excess over the walls).
    /// (Shared with the round's workers, who only read them.)
    weights: std::sync::Arc<Vec<f64>>,
    /// Pair evaluations spent.
    pub work: u64,
    /// Whether a spot has left where it was given (the new item has): pairs of spots that
    /// have not are clear by the caller's word (jagua-rs checked them), whatever their gap.
    moved: Vec<bool>,
    /// The keys of the weights above 1 (the pairs that have been in collision).
    heavy: Vec<usize>,
    grid: Grid,
    /// Neighbours found in the grid (kept to spare an allocation per look).
    near: Vec<usize>,
    rng: ChaCha8Rng,
}

impl<'a> Separation<'a> {
    /// `spots[..known]` are clear of each other and of the walls (checked by the caller) while
    /// they stay where they are; the rest are new.
    pub fn new(
        forms: &'a [Vec<Form>],
        room: DVec2,
        clear: f64,
        spots: Vec<Spot>,
        known: usize,
        seed: u64,
    ) -> Separation<'a> {
        let n = spots.len();
        let moved = (0..n).map(|k| k >= known).collect();
        let grid = Grid::new(forms, room, &spots);
        Separation {
            grid,
            near: Vec::with_capacity(n),
            moved,
            heavy: (0..n).map(|k| k * (n + 1)).collect(),
            forms,
            room,
            clear,
            spots,
            weights: std::sync::Arc::new(
                (0..n * n)
                    .map(|k| if k % (n + 1) == 0 { 2.0 } else { 1.0 })
                    .collect(),
            ),
            work: 0,
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    fn form(&self, s: &Spot) -> &'a Form {
        &self.forms[s.item][s.form]
    }

    /// How far a form at `at` leaves the container (kept `clear` off its walls).
    fn wall_by(&self, f: &Form, at: DVec2, clear: f64) -> f64 {
        let lo = DVec2::splat(clear);
        let hi = self.room - DVec2::splat(clear) - f.size;
        let excess =
            (lo - at).max(DVec2::ZERO).element_sum() + (at - hi).max(DVec2::ZERO).element_sum();
        // A room that holds a form exactly leaves rounding's excess: none.
        if excess > 1e-9 {
            (excess + EPSILON * f.diameter) * f.root
        } else {
            0.0
        }
    }

    fn wall(&self, f: &Form, at: DVec2) -> f64 {
        self.wall_by(f, at, self.clear)
    }

    /// Weighted loss of spot `k` moved to (form, at) with every other spot, and of its wall
    /// excess (weighted as a pair is, 2 at first: the walls of a room made shorter push as
    /// hard as the neighbours they push against); once it reaches `bound` the rest is not
    /// looked at (sparrow's early exit: a place worse than the best so far needs no exact
    /// loss), and what is returned is at least `bound`.
    fn cost(&mut self, k: usize, form: usize, at: DVec2, bound: f64) -> f64 {
        let f = &self.forms[self.spots[k].item][form];
        let unmoved = !self.moved[k] && form == self.spots[k].form && at == self.spots[k].at;
        // A spot where it was given is clear of the walls the caller checked, not of a room
        // made shorter since.
        let n = self.spots.len();
        let mut sum = self.weights[k * n + k]
            * if unmoved {
                self.wall_by(f, at, 0.0)
            } else {
                self.wall(f, at)
            };
        if sum >= bound {
            return sum;
        }
        let (lo, hi) = (at, at + f.size);
        let mut evaluated = 0u64;
        let looked = self.grid.visit(lo, hi, |j| {
            if j == k || (unmoved && !self.moved[j]) {
                return ControlFlow::Continue(());
            }
            let s = self.spots[j];
            let g = self.form(&s);
            if boxes_apart(lo, hi, s.at, g) {
                return ControlFlow::Continue(());
            }
            evaluated += 1;
            let d = depth(f, at, g, s.at);
            if d > 0.0 {
                sum += self.weights[k.min(j) * n + k.max(j)] * loss(d, f, g);
                if sum >= bound {
                    return ControlFlow::Break(());
                }
            }
            ControlFlow::Continue(())
        });
        // Entries looked at in the grid count a sixteenth of a pair evaluation each.
        self.work += evaluated + looked.div_ceil(16);
        sum
    }

    /// The unweighted loss of every pair in collision and every wall excess: their sum, and
    /// the pairs (a wall excess as (i, i)) in order of i then j.
    fn overlaps(&mut self) -> (f64, Pairs) {
        let n = self.spots.len();
        let mut total = 0.0;
        let mut pairs = Vec::new();
        let mut near = std::mem::take(&mut self.near);
        for i in 0..n {
            let a = self.spots[i];
            let fa = self.form(&a);
            let w = if self.moved[i] {
                self.wall(fa, a.at)
            } else {
                self.wall_by(fa, a.at, 0.0)
            };
            if w > 0.0 {
                total += w;
                pairs.push((i, i, w));
            }
            near.clear();
            let looked = self.grid.visit(a.at, a.at + fa.size, |j| {
                near.push(j);
                ControlFlow::Continue(())
            });
            // Entries looked at and box tests count a sixteenth of a pair evaluation each.
            self.work += (looked + near.len() as u64).div_ceil(16);
            near.sort_unstable();
            for &j in near.iter().filter(|&&j| j > i) {
                if !self.moved[i] && !self.moved[j] {
                    continue;
                }
                let b = self.spots[j];
                let fb = self.form(&b);
                if boxes_apart(a.at, a.at + fa.size, b.at, fb) {
                    continue;
                }
                self.work += 1;
                let d = depth(fa, a.at, fb, b.at);
                if d > 0.0 {
                    let l = loss(d, fa, fb);
                    total += l;
                    pairs.push((i, j, l));
                }
            }
        }
        self.near = near;
        (total, pairs)
    }

    /// The least weighted overlap place for spot `k`: sampled over the container and near where
    /// it is, in every form, then refined by halving steps along x and y.
    fn relocate(&mut self, k: usize) {
        let item = self.spots[k].item;
        let forms = self.forms[item].len();
        let here = self.spots[k];
        let mut best = (
            self.cost(k, here.form, here.at, f64::INFINITY),
            here.form,
            here.at,
        );
        let mut tries: Vec<(usize, DVec2)> = Vec::with_capacity(forms * GLOBAL + LOCAL);
        for form in 0..forms {
            let span =
                (self.room - self.forms[item][form].size - 2.0 * self.clear).max(DVec2::ZERO);
            for _ in 0..GLOBAL {
                let u = DVec2::new(self.rng.random::<f64>(), self.rng.random::<f64>());
                tries.push((form, DVec2::splat(self.clear) + span * u));
            }
        }
        let size = self.forms[item][here.form].size;
        for j in 0..LOCAL {
            let scale = [0.5, 0.1, 0.02][j % 3] * size.max_element();
            let u = DVec2::new(
                self.rng.random::<f64>() - 0.5,
                self.rng.random::<f64>() - 0.5,
            );
            let form = if j % 4 == 3 {
                self.rng.random_range(0..forms)
            } else {
                here.form
            };
            tries.push((form, here.at + u * 2.0 * scale));
        }
        for (form, at) in tries {
            let c = self.cost(k, form, at, best.0);
            if c < best.0 {
                best = (c, form, at);
            }
        }
        // Refine: coordinate descent with halving steps.
        let mut step = 0.1 * self.forms[item][best.1].size.min_element();
        while step > 0.001 && best.0 > 0.0 {
            let mut moved = false;
            for dir in [DVec2::X, DVec2::NEG_X, DVec2::Y, DVec2::NEG_Y] {
                let at = best.2 + dir * step;
                let c = self.cost(k, best.1, at, best.0);
                if c < best.0 {
                    best = (c, best.1, at);
                    moved = true;
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        if best.1 != here.form || best.2 != here.at {
            self.moved[k] = true;
            self.spots[k].form = best.1;
            self.spots[k].at = best.2;
            self.grid.remove(k);
            let size = self.forms[item][best.1].size;
            self.grid.insert(k, best.2, best.2 + size);
        }
    }

    /// Moves items until nothing overlaps (true), or the work runs out or the search gives up
    /// (false). Rounds move every item in collision (in a seeded random order) to its least
    /// weighted overlap place; after each, the weights of pairs still in collision grow (the
    /// deepest the most) and the others decay towards 1. A strike is `STALL` rounds without
    /// a new least overlap (a new least that is not `SUBSTANTIAL` does not reset the count);
    /// after each the items go back to the least overlapping arrangement seen, weights kept, and
    /// `STRIKES` strikes in a row without a substantial gain end the search (sparrow's
    /// separator).
    pub fn run(&mut self, budget: u64) -> bool {
        let (mut total, mut pairs) = self.overlaps();
        let mut least = total;
        let mut best = (self.spots.clone(), self.moved.clone());
        let mut strikes = 0;
        loop {
            let start = total;
            let mut stalled = 0;
            while stalled < STALL {
                if pairs.is_empty() {
                    return true;
                }
                if self.work > budget {
                    return false;
                }
                (total, pairs) = self.round(&pairs);
                if pairs.is_empty() {
                    return true;
                }
                if total < least {
                    if total >= SUBSTANTIAL * least {
                        stalled += 1;
                    } else {
                        stalled = 0;
                    }
                    least = total;
                    best.0.clone_from(&self.spots);
                    best.1.clone_from(&self.moved);
                } else {
                    stalled += 1;
                }
                self.reweigh(&pairs);
            }
            if SUBSTANTIAL * start <= least {
                strikes += 1;
                if strikes >= STRIKES {
                    return false;
                }
            } else {
                strikes = 0;
            }
            self.spots.clone_from(&best.0);
            self.moved.clone_from(&best.1);
            self.grid = Grid::new(self.forms, self.room, &self.spots);
            (total, pairs) = self.overlaps();
        }
    }

    /// One round: every item in collision (in `pairs`) moved, by each of [`WORKERS`] from
    /// here in its own seeded order; the arrangement of least weighted loss kept. Returns its
    /// loss and pairs in collision, as `overlaps` does.
    fn round(&mut self, pairs: &[(usize, usize, f64)]) -> (f64, Pairs) {
        let n = self.spots.len();
        let mut moving: Vec<usize> = pairs.iter().flat_map(|&(i, j, _)| [i, j]).collect();
        moving.sort_unstable();
        moving.dedup();
        let seeds: Vec<u64> = (0..WORKERS).map(|_| self.rng.random()).collect();
        let done: Vec<(f64, f64, Pairs, Separation)> = seeds
            .into_par_iter()
            .map(|seed| {
                let mut w = self.clone();
                w.rng = ChaCha8Rng::seed_from_u64(seed);
                w.work = 0;
                let mut order = moving.clone();
                // A fixed-seed shuffle.
                for k in (1..order.len()).rev() {
                    let j = w.rng.random_range(0..=k);
                    order.swap(k, j);
                }
                for k in order {
                    if w.cost(k, w.spots[k].form, w.spots[k].at, f64::MIN_POSITIVE) > 0.0 {
                        w.relocate(k);
                    }
                }
                let (total, pairs) = w.overlaps();
                let weighted = pairs
                    .iter()
                    .map(|&(i, j, l)| w.weights[i * n + j] * l)
                    .sum::<f64>();
                (weighted, total, pairs, w)
            })
            .collect();
        self.work += done.iter().map(|d| d.3.work).sum::<u64>();
        // The least weighted loss, the first worker on a tie.
        let best = done
            .into_iter()
            .reduce(|a, b| if b.0 < a.0 { b } else { a })
            .expect("a worker");
        let (_, total, pairs, w) = best;
        self.spots = w.spots;
        self.moved = w.moved;
        self.grid = w.grid;
        (total, pairs)
    }

    /// Guided local search: pairs in collision weigh more, the deepest the most (× 1.2 to 2);
    /// the others decay towards 1 (× [`DECAY`]).
    fn reweigh(&mut self, pairs: &[(usize, usize, f64)]) {
        let n = self.spots.len();
        // `pairs` come in order of i, then j: their keys are sorted.
        let hit: Vec<usize> = pairs.iter().map(|&(i, j, _)| i * n + j).collect();
        self.work += (self.heavy.len() as u64).div_ceil(16);
        // The workers are gone: no copy is made.
        let weights = std::sync::Arc::make_mut(&mut self.weights);
        self.heavy.retain(|&k| {
            if hit.binary_search(&k).is_ok() {
                return true;
            }
            weights[k] = (weights[k] * DECAY).max(1.0);
            weights[k] > 1.0
        });
        let deepest = pairs.iter().map(|p| p.2).fold(0.0, f64::max);
        for (&k, &(_, _, d)) in hit.iter().zip(pairs) {
            if weights[k] <= 1.0 {
                self.heavy.push(k);
            }
            weights[k] = (weights[k] * (1.2 + 0.8 * d / deepest)).min(1e6);
        }
    }
}

/// Where a new item (forms given) overlaps the spots least: sampled over the container.
pub fn entry(
    forms: &[Vec<Form>],
    room: DVec2,
    clear: f64,
    spots: &[Spot],
    item: usize,
    seed: u64,
) -> Spot {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut best: Option<(f64, Spot)> = None;
    for (form, f) in forms[item].iter().enumerate() {
        let span = (room - f.size - 2.0 * clear).max(DVec2::ZERO);
        for _ in 0..4 * GLOBAL {
            let at =
                DVec2::splat(clear) + span * DVec2::new(rng.random::<f64>(), rng.random::<f64>());
            let mut sum = 0.0;
            for s in spots {
                let g = &forms[s.item][s.form];
                let d = depth(f, at, g, s.at);
                if d > 0.0 {
                    sum += d;
                }
            }
            if best.as_ref().is_none_or(|b| sum < b.0) {
                best = Some((sum, Spot { item, form, at }));
            }
        }
    }
    best.expect("an item has a form").1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(s: f64) -> Form {
        Form::new(vec![
            DVec2::ZERO,
            DVec2::new(s, 0.0),
            DVec2::new(s, s),
            DVec2::new(0.0, s),
        ])
    }

    #[test]
    fn depth_is_the_least_projection_overlap() {
        let a = square(10.0);
        assert!((depth(&a, DVec2::ZERO, &a, DVec2::new(7.0, 2.0)) - (3.0 + GAP)).abs() < 1e-12);
        assert!(depth(&a, DVec2::ZERO, &a, DVec2::new(10.0 + 2.0 * GAP, 0.0)) < 0.0);
    }

    #[test]
    fn the_grid_finds_every_box_within_the_gap_once() {
        // Boxes of several sizes scattered over and past a room, some touching within the
        // gap: the grid's neighbours of each box are exactly those a test against every box
        // finds (each once), also after boxes move.
        let forms: Vec<Vec<Form>> = [3.0, 7.5, 12.0, 40.0]
            .iter()
            .map(|&s| vec![square(s)])
            .collect();
        let room = DVec2::new(100.0, 60.0);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut spots: Vec<Spot> = (0..120)
            .map(|k| Spot {
                item: k % 4,
                form: 0,
                at: DVec2::new(
                    rng.random_range(-20.0..110.0),
                    rng.random_range(-20.0..70.0),
                ),
            })
            .collect();
        // Two boxes GAP / 2 apart: neighbours.
        spots[0].at = DVec2::new(10.0, 10.0);
        spots[1].at = DVec2::new(13.0 + 0.5 * GAP, 10.0);
        let mut grid = Grid::new(&forms, room, &spots);
        let size = |s: &Spot| forms[s.item][s.form].size;
        for round in 0..2 {
            for (i, a) in spots.iter().enumerate() {
                let (lo, hi) = (a.at, a.at + size(a));
                let mut near = Vec::new();
                grid.visit(lo, hi, |j| {
                    near.push(j);
                    ControlFlow::Continue(())
                });
                near.sort_unstable();
                let mut all: Vec<usize> = spots
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| {
                        b.at.x <= hi.x + GAP
                            && b.at.y <= hi.y + GAP
                            && b.at.x + size(b).x >= lo.x - GAP
                            && b.at.y + size(b).y >= lo.y - GAP
                    })
                    .map(|(j, _)| j)
                    .collect();
                all.sort_unstable();
                // The grid may offer boxes a little further off (its cells), never miss one,
                // and never offer one twice.
                assert!(near.windows(2).all(|w| w[0] < w[1]), "{i}: {near:?}");
                for j in &all {
                    assert!(
                        near.binary_search(j).is_ok(),
                        "round {round}, {i} misses {j}"
                    );
                }
            }
            assert!(grid.range.len() == spots.len());
            // Move every third box and update the grid as a move does.
            for k in (0..spots.len()).step_by(3) {
                spots[k].at += DVec2::new(17.0, -9.0);
                grid.remove(k);
                grid.insert(k, spots[k].at, spots[k].at + size(&spots[k]));
            }
        }
    }

    #[test]
    fn a_row_of_squares_is_compressed_into_a_shorter_room() {
        // Four squares 1 apart in a row (clear, as the caller says), then a room 2 shorter:
        // the last one is over the new wall, and the row closes up to make room.
        let forms = vec![vec![square(10.0)]; 4];
        let spots: Vec<Spot> = (0..4)
            .map(|item| Spot {
                item,
                form: 0,
                at: DVec2::new(0.01 + 11.0 * item as f64, 0.01),
            })
            .collect();
        let room = DVec2::new(43.02 - 2.0, 10.02);
        let mut sep = Separation::new(&forms, room, 0.01, spots, 4, 5);
        let (total, pairs) = sep.overlaps();
        assert_eq!(pairs.len(), 1, "only the wall: {pairs:?}");
        // Measured to the wall itself (1.99 over it: a spot the caller placed keeps no
        // clearance of its own), plus the floor, times the square's penalty √√100.
        let expected = (1.99 + EPSILON * 200f64.sqrt()) * 10f64.sqrt();
        assert!(
            (total - expected).abs() < 1e-9,
            "{total} against {expected}"
        );
        let done = sep.run(10_000_000);
        let (total, pairs) = sep.overlaps();
        assert!(
            done,
            "{} evaluations, {total} left in {pairs:?}: {:?}",
            sep.work, sep.spots
        );
        assert!(pairs.is_empty() && total == 0.0);
        for s in &sep.spots {
            assert!(s.at.x + 10.0 <= room.x - 0.01 + 1e-9, "{s:?}");
        }
    }

    #[test]
    fn four_squares_piled_up_are_separated_into_a_room_that_just_holds_them() {
        let forms = vec![vec![square(10.0)]; 4];
        // A 20.1 × 20.1 room: the four fit only as a 2 × 2 grid.
        let spots: Vec<Spot> = (0..4)
            .map(|item| Spot {
                item,
                form: 0,
                at: DVec2::splat(5.0),
            })
            .collect();
        let mut sep = Separation::new(&forms, DVec2::splat(20.05), 0.01, spots, 0, 3);
        assert!(sep.run(10_000_000), "separated in {} evaluations", sep.work);
        let (total, pairs) = sep.overlaps();
        assert!(pairs.is_empty() && total == 0.0);
    }
}
