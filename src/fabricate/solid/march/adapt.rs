//! Where the grid is too coarse for the tolerance: tetrahedra bisected until marching no
//! longer misses by more than it allows.
//!
//! Two veins a few µm apart are both sampled inside at the corners of one tetrahedron, and
//! marching joins them: the mesh closes a gap the exact union has. In a sharp crotch where two
//! veins meet the chords span the crotch above its floor. A tetrahedron is bisected when
//! - two of its inside corners lie in veins that do not touch and the segment between them
//!   leaves the union between those two (each piece near the segment holds one interval of it,
//!   pieces being convex, so the holes between the intervals are exact): a gap (`Bridge::Gap`);
//! - the segment leaves the union between two veins that touch but face each other, deeper
//!   than half the tolerance times the tangent of half the crotch's angle (`crotch`);
//! - at an edge midpoint or its centre, the sign marching interpolates from the corners is
//!   wrong by more than half the tolerance (`misplaced`).
//!
//! It is bisected until none of these holds or the finest level is reached (what is left there
//! is counted: gaps apart from crotch ends, which never close).
//!
//! Bisection follows Maubach's rule on the Kuhn split: a tetrahedron is an ordered list of
//! corners x0..x3 and a tag k; it is cut at the midpoint z of x0 and xk into (x0..xk−1, z,
//! xk+1..x3) and (x1..xk, z, xk+1..x3), whose tag is k − 1 (3 after 1). A cell's six Kuhn
//! tetrahedra are monotone paths from its lowest corner to its highest, tag 3: three cuts make
//! the Kuhn tetrahedra of a grid half as fine. Before an edge is cut, every tetrahedron holding
//! it is refined until the edge is its own cut edge too, and all are cut at once (the cells
//! around a grid edge are brought in as six tetrahedra each when first needed), so tetrahedra
//! meet face to face and the marched surface stays a closed manifold: each of its edges lies on
//! a face two tetrahedra share.
//!
//! Corners on the grid keep the sign the grid gave them; finer corners count as inside at
//! `eps / FINE_EPS` below zero.

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;

use super::{corner, outward_cos, Grid, MarchError, FACING, TETS};
use crate::fabricate::solid::few::Few;
use crate::fabricate::solid::quick::{QuickMap, QuickSet};
use crate::fabricate::solid::sdf::{golden, Primitive};

/// A point in fine units: `SCALE` per grid cell.
pub(super) type Pt = [i64; 3];

/// Bisections are possible down to cells `1 / SCALE` of the grid's. Three cuts halve a cell, so
/// `3 log2(finest)` cuts reach `1 / finest` of the grid cell (16: 2.2 µm at 35 µm; 32 at 70
/// µm, as fine); `SCALE` leaves room for the few extra cuts that keeping neighbours matched can
/// ask.
pub(super) const SCALE: i64 = 256;
/// The finest split `Adapt` may be asked for, as cells per grid cell along a side.
pub const MAX_FINEST: u32 = 32;
/// Finer corners than the grid's count as inside this many times closer to zero than grid
/// corners (`eps_at`).
const FINE_EPS: f64 = 64.0;
/// The most tetrahedra made (about 120 bytes each with their edges and corners); past it no
/// more cells are brought in and no more bisected, and what is left is counted.
const MAX_TETS: usize = 6_000_000;

/// The tetrahedra made by every `Adapt` that shares it, held to `MAX_TETS` together: each
/// adds its own in steps of `PUBLISH` (a count shared by two threads, bumped millions of times,
/// would cost more than the bisection it counts).
#[derive(Debug, Default)]
pub(super) struct Budget(AtomicUsize);

/// Tetrahedra an `Adapt` makes between additions to its `Budget`.
const PUBLISH: usize = 1024;

impl Budget {
    /// Whether `Adapt`s that shared a budget and made `made` tetrahedra in all never met it
    /// (each counts no more than all have made): then each bisected what it would have alone.
    pub fn never_met(made: usize) -> bool {
        made + 6 <= MAX_TETS
    }
}

/// Why a tetrahedron is bisected.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Bridge {
    /// Its inside joins two veins that do not touch: marching would change the topology.
    Gap,
    /// A crotch or crease it spans is deeper than the tolerance allows.
    Shape,
}

/// What a corner is: its value, its side, and the pieces holding it (`Adapt::holding`).
#[derive(Clone, Copy)]
struct Sample {
    f: f64,
    inside: bool,
    /// Where its pieces start in `Adapt::holders`, and how many: millions of corners, so one
    /// pool instead of a list each (whose allocations, and freeing them, cost seconds). (A
    /// `usize` start keeps the sample 24 bytes and cannot overflow.)
    start: usize,
    len: u32,
}

/// The live tetrahedra around an edge: most edges have at most 7, kept in place.
type Around = Few<7>;

#[derive(Clone, Copy)]
pub(super) struct Tet {
    /// The corners, by number (`Adapt::corners` gives the points): 16 bytes instead of 96.
    n: [u32; 4],
    tag: u8,
    level: u8,
    pub alive: bool,
}

/// Two corner numbers as one key, the lower first.
fn pair(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

fn edge_key(a: Pt, b: Pt) -> (Pt, Pt) {
    if a <= b {
        (a, b)
    } else {
        (b, a)
    }
}

/// The field near the grid: which pieces can reach a point, and the grid's signs.
pub(super) trait Field {
    /// Indices of the pieces that may reach `cell`'s neighbourhood (all others are far outside).
    fn near(&self, cell: [usize; 3]) -> &[u32];
    /// The sign the grid gave grid point `g`, when a brick holding it was sampled.
    fn grid_inside(&self, g: [usize; 3]) -> Option<bool>;
}

pub(super) struct Adapt<'a, F: Field> {
    grid: &'a Grid,
    prims: &'a [Primitive],
    field: &'a F,
    band: f64,
    /// How far the mesh may stray from the surface, mm.
    tol: f64,
    eps: f64,
    samples: QuickMap<Pt, Sample>,
    /// The samples' pieces (`Sample::start`).
    holders: Vec<u32>,
    pub tets: Vec<Tet>,
    /// The tetrahedra made by this and every `Adapt` running beside it, and those made here
    /// not added to it yet.
    budget: &'a Budget,
    unpublished: usize,
    /// Each corner's number, and the corners by number.
    ids: QuickMap<Pt, u32>,
    pts: Vec<Pt>,
    /// The live tetrahedra around each edge, by its corners' numbers (`pair`): two u32 keys
    /// instead of two points take half the memory of the largest map here.
    edges: QuickMap<u64, Around>,
    /// Cuts down to the finest split: `3 log2(finest)`.
    levels: u8,
    pub cells: QuickSet<[usize; 3]>,
    /// Each brought-in cell's pieces (in `pool`): those of its brick that can reach a point
    /// of the cell or its neighbours within `band` (farther ones only ever give `band`).
    lists: QuickMap<[usize; 3], (u32, u32)>,
    pool: Vec<u32>,
    work: Vec<u32>,
    /// Pairs of pieces told apart (a gap between them) or not.
    apart: QuickMap<(u32, u32), bool>,
    /// Tetrahedra that still bridge a gap between veins that do not touch, at the finest level
    /// or past the budget.
    pub left: usize,
    /// Tetrahedra still too coarse there for a crotch's end or a crease (the crotch narrows
    /// to nothing, so its very end is always left).
    pub crotches: usize,
}

impl<'a, F: Field> Adapt<'a, F> {
    /// Splits down to `1 / finest` of the grid's cell (a power of two, at most `MAX_FINEST`).
    pub fn new(
        grid: &'a Grid,
        prims: &'a [Primitive],
        field: &'a F,
        budget: &'a Budget,
        band: f64,
        (tol, finest): (f64, u32),
    ) -> Self {
        let finest = finest.clamp(1, MAX_FINEST).next_power_of_two();
        Adapt {
            levels: 3 * finest.trailing_zeros() as u8,
            grid,
            tol,
            prims,
            field,
            band,
            eps: 0.01 * grid.h,
            samples: QuickMap::default(),
            holders: Vec::new(),
            tets: Vec::new(),
            budget,
            unpublished: 0,
            ids: QuickMap::default(),
            pts: Vec::new(),
            edges: QuickMap::default(),
            cells: QuickSet::default(),
            lists: QuickMap::default(),
            pool: Vec::new(),
            work: Vec::new(),
            apart: QuickMap::default(),
            left: 0,
            crotches: 0,
        }
    }

    pub fn position(&self, p: Pt) -> DVec3 {
        self.grid.origin
            + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * self.grid.h / SCALE as f64
    }

    fn cell_of(&self, p: Pt) -> [usize; 3] {
        [0, 1, 2].map(|a| {
            let c = (p[a].max(0) / SCALE) as usize;
            c.min(self.grid.points[a].saturating_sub(2))
        })
    }

    /// The pieces that can reach a point of `cell` or its neighbours within `band`: the
    /// cell's own list if it was brought in, else its brick's.
    fn pieces(&self, cell: [usize; 3]) -> &[u32] {
        match self.lists.get(&cell) {
            Some(&(start, len)) => &self.pool[start as usize..(start + len) as usize],
            None => self.field.near(cell),
        }
    }

    /// The exact value at `x`, a point of `cell`.
    pub fn value(&self, x: DVec3, cell: [usize; 3]) -> f64 {
        self.pieces(cell)
            .iter()
            .map(|&i| self.prims[i as usize].eval(x, self.band))
            .fold(self.band, f64::min)
    }

    /// The threshold below zero at which a point of fine units counts as inside.
    pub fn eps_at(&self, p: Pt) -> f64 {
        if p.iter().all(|c| c % SCALE == 0) {
            self.eps
        } else {
            self.eps / FINE_EPS
        }
    }

    fn sample(&mut self, p: Pt) -> Sample {
        if let Some(&s) = self.samples.get(&p) {
            return s;
        }
        let x = self.position(p);
        let cell = self.cell_of(p);
        let eps = self.eps_at(p);
        let mut f = self.band;
        let start = self.holders.len();
        let list = match self.lists.get(&cell) {
            Some(&(at, len)) => &self.pool[at as usize..(at + len) as usize],
            None => self.field.near(cell),
        };
        for &i in list {
            let v = self.prims[i as usize].eval(x, self.band);
            f = f.min(v);
            if v <= -eps {
                self.holders.push(i);
            }
        }
        let on_grid = p.iter().all(|c| c % SCALE == 0);
        let inside = on_grid
            .then(|| self.field.grid_inside(p.map(|c| (c / SCALE) as usize)))
            .flatten()
            .unwrap_or(f <= -eps);
        if !inside {
            self.holders.truncate(start);
        }
        let s = Sample {
            f,
            inside,
            start,
            len: (self.holders.len() - start) as u32,
        };
        self.samples.insert(p, s);
        s
    }

    /// The pieces holding sample `s` (none when it is outside).
    fn holding(&self, s: &Sample) -> &[u32] {
        &self.holders[s.start..s.start + s.len as usize]
    }

    /// Whether fine point `p` counts as inside.
    pub fn inside(&mut self, p: Pt) -> bool {
        self.sample(p).inside
    }

    /// The value the sign was taken from at `p`, pushed off zero to its side.
    pub fn signed(&mut self, p: Pt) -> f64 {
        let eps = self.eps_at(p);
        let s = self.sample(p);
        if s.inside {
            s.f.min(-eps)
        } else {
            s.f.max(eps)
        }
    }

    /// Corner `p`'s number, numbering it if new.
    fn number(&mut self, p: Pt) -> u32 {
        let next = self.pts.len() as u32;
        let n = *self.ids.entry(p).or_insert(next);
        if n == next {
            self.pts.push(p);
        }
        n
    }

    /// Tetrahedron `t`'s corners.
    pub fn corners(&self, t: &Tet) -> [Pt; 4] {
        t.n.map(|i| self.pts[i as usize])
    }

    fn add(&mut self, t: Tet) {
        let id = self.tets.len() as u32;
        for (a, b) in pairs() {
            let key = pair(t.n[a], t.n[b]);
            self.edges.entry(key).or_default().push(id);
        }
        self.tets.push(t);
        self.work.push(id);
        self.unpublished += 1;
        if self.unpublished == PUBLISH {
            self.budget.0.fetch_add(PUBLISH, Ordering::Relaxed);
            self.unpublished = 0;
        }
    }

    /// Counts against `budget` from now on, alone: it has made its own tetrahedra, no more.
    pub fn alone(&mut self, budget: &'a Budget) {
        budget.0.store(self.tets.len(), Ordering::Relaxed);
        self.budget = budget;
        self.unpublished = 0;
    }

    /// The tetrahedra made so far, here and (as far as they have said) beside it: exactly
    /// this one's when it runs alone, never more than all have made.
    fn spent(&self) -> usize {
        self.budget.0.load(Ordering::Relaxed) + self.unpublished
    }

    fn kill(&mut self, id: u32) {
        let t = &mut self.tets[id as usize];
        t.alive = false;
        let n = t.n;
        for (a, b) in pairs() {
            let key = pair(n[a], n[b]);
            if let Some(list) = self.edges.get_mut(&key) {
                list.retain(|u| u != id);
                if list.is_empty() {
                    self.edges.remove(&key);
                }
            }
        }
    }

    /// Brings in cell `c` to be looked at, unless the budget is spent (then it is counted
    /// as left).
    pub fn look_at(&mut self, c: [usize; 3]) {
        if self.spent() + 6 > MAX_TETS {
            self.left += 1;
            return;
        }
        self.bring(c);
    }

    /// Brings in cell `c` as its six Kuhn tetrahedra.
    fn bring(&mut self, c: [usize; 3]) {
        if (0..3).any(|a| c[a] + 1 >= self.grid.points[a]) || !self.cells.insert(c) {
            return;
        }
        // Every point a query of this cell looks at (its tetrahedra's, and those of a
        // neighbour's tetrahedra whose first corner lies on its faces) is within 1.5 cell
        // diagonals of its centre; the pieces are 1-Lipschitz.
        let centre = self.position(c.map(|x| x as i64 * SCALE + SCALE / 2));
        let reach = self.band + 1.5 * 3f64.sqrt() * self.grid.h * (1.0 + 1e-9);
        let start = self.pool.len() as u32;
        for &i in self.field.near(c) {
            if self.prims[i as usize].eval(centre, reach) <= reach {
                self.pool.push(i);
            }
        }
        self.lists
            .insert(c, (start, self.pool.len() as u32 - start));
        for tet in &TETS {
            let v = tet.map(|code| {
                let o = corner(code);
                [0, 1, 2].map(|a| (c[a] + o[a]) as i64 * SCALE)
            });
            let n = v.map(|p| self.number(p));
            self.add(Tet {
                n,
                tag: 3,
                level: 0,
                alive: true,
            });
        }
    }

    fn cut_edge(&self, id: u32) -> (Pt, Pt) {
        let t = &self.tets[id as usize];
        let v = self.corners(t);
        edge_key(v[0], v[t.tag as usize])
    }

    /// The live tetrahedra holding edge `e`, bringing in the cells around it if it is a grid
    /// edge.
    fn around(&mut self, e: (Pt, Pt)) -> Around {
        let (p, q) = e;
        let d = [0, 1, 2].map(|a| q[a] - p[a]);
        let on_grid = p.iter().chain(&q).all(|c| c % SCALE == 0);
        if on_grid && d.iter().all(|&x| x == 0 || x == SCALE) {
            let g = p.map(|c| (c / SCALE) as usize);
            for code in 0..8u8 {
                let o = corner(code);
                if (0..3).any(|a| o[a] == 1 && (d[a] != 0 || g[a] == 0)) {
                    continue;
                }
                self.bring([0, 1, 2].map(|a| g[a] - o[a]));
            }
        }
        match (self.ids.get(&p), self.ids.get(&q)) {
            (Some(&a), Some(&b)) => self.edges.get(&pair(a, b)).cloned().unwrap_or_default(),
            _ => Around::default(),
        }
    }

    fn bisect(&mut self, id: u32) -> Result<(), MarchError> {
        let t = self.tets[id as usize];
        let k = t.tag as usize;
        let v = self.corners(&t);
        let (a, b) = (v[0], v[k]);
        if (0..3).any(|i| (a[i] + b[i]) % 2 != 0) {
            return Err(MarchError::Internal(
                "a tetrahedron was cut finer than the fine grid".into(),
            ));
        }
        let z = [0, 1, 2].map(|i| (a[i] + b[i]) / 2);
        let tag = if k == 1 { 3 } else { t.tag - 1 };
        let zn = self.number(z);
        let mut first = t.n;
        first[k] = zn;
        let mut second = t.n;
        second[..k].copy_from_slice(&t.n[1..=k]);
        second[k] = zn;
        self.kill(id);
        for n in [first, second] {
            self.add(Tet {
                n,
                tag,
                level: t.level + 1,
                alive: true,
            });
        }
        Ok(())
    }

    /// Cuts tetrahedron `id` at its cut edge, with every tetrahedron that holds the edge.
    fn refine(&mut self, id: u32, depth: usize) -> Result<(), MarchError> {
        if depth > 64 {
            return Err(MarchError::Internal(
                "matching a bisection with its neighbours did not end".into(),
            ));
        }
        let e = self.cut_edge(id);
        loop {
            let around = self.around(e);
            if let Some(&u) = around.iter().find(|&&u| self.cut_edge(u) != e) {
                self.refine(u, depth + 1)?;
                continue;
            }
            for &u in around.iter() {
                self.bisect(u)?;
            }
            return Ok(());
        }
    }

    /// Bisects until no tetrahedron bridges a gap (or the finest level or the budget is reached).
    pub fn run(&mut self) -> Result<(), MarchError> {
        while let Some(id) = self.work.pop() {
            let t = self.tets[id as usize];
            if !t.alive {
                continue;
            }
            let Some(why) = self.bridges(id) else {
                continue;
            };
            if t.level >= self.levels || self.spent() > MAX_TETS {
                match why {
                    Bridge::Gap => self.left += 1,
                    Bridge::Shape => self.crotches += 1,
                }
                continue;
            }
            self.refine(id, 0)?;
        }
        Ok(())
    }

    /// Whether the inside of tetrahedron `id`, as marching makes it (one piece, the hull of its
    /// inside corners and crossings), holds points outside the union that matter, and why.
    fn bridges(&mut self, id: u32) -> Option<Bridge> {
        let v = self.corners(&self.tets[id as usize]);
        let s = v.map(|p| self.sample(p));
        let ins: Vec<usize> = (0..4).filter(|&i| s[i].inside).collect();
        if ins.is_empty() {
            return None;
        }
        let x = v.map(|p| self.position(p));
        let longest = pairs()
            .map(|(a, b)| x[a].distance(x[b]))
            .fold(0.0, f64::max);
        if ins.iter().any(|&i| s[i].f <= -longest) {
            return None;
        }
        if self.misplaced(&v, &x) {
            return Some(Bridge::Shape);
        }
        if ins.len() < 2 {
            return None;
        }
        let common = self
            .holding(&s[ins[0]])
            .iter()
            .any(|p| ins.iter().all(|&i| self.holding(&s[i]).contains(p)));
        if common {
            return None;
        }
        for (n, &i) in ins.iter().enumerate() {
            for &j in &ins[n + 1..] {
                let (pi, pj) = (self.holding(&s[i]), self.holding(&s[j]));
                if pi.iter().any(|p| pj.contains(p)) {
                    continue;
                }
                if self.joined(x[i], pi, x[j], pj) {
                    continue;
                }
                if let Some(why) = self.across_gap(x[i], x[j], self.cell_of(v[i])) {
                    return Some(why);
                }
            }
        }
        None
    }

    /// Whether marching this tetrahedron puts a point more than half the tolerance on the
    /// wrong side: at the midpoints of its edges and its centre, the sign of the values
    /// interpolated from its corners against the exact value (a crotch between veins that
    /// the chords span, or a vein's side they cut).
    fn misplaced(&mut self, v: &[Pt; 4], x: &[DVec3; 4]) -> bool {
        let f = v.map(|p| self.signed(p));
        let cell = self.cell_of(v[0]);
        let half = 0.5 * self.tol;
        let wrong =
            |exact: f64, linear: f64| exact > half && linear < 0.0 || exact < -half && linear > 0.0;
        let centre = (x[0] + x[1] + x[2] + x[3]) / 4.0;
        if wrong(self.value(centre, cell), (f[0] + f[1] + f[2] + f[3]) / 4.0) {
            return true;
        }
        pairs().any(|(a, b)| wrong(self.value(0.5 * (x[a] + x[b]), cell), 0.5 * (f[a] + f[b])))
    }

    /// Whether the segment from `a` to `b` (both inside) leaves the union between two pieces
    /// that do not touch (across a gap) or across a crotch too deep to leave (`crotch`).
    /// Where it leaves between pieces that touch otherwise, it crosses a crease, which the
    /// simplifier's refinement follows (bisecting there would not end). Each piece near the
    /// segment holds an interval of it (pieces are convex); the holes between the intervals
    /// are where it is outside.
    fn across_gap(&mut self, a: DVec3, b: DVec3, cell: [usize; 3]) -> Option<Bridge> {
        let half = 0.5 * a.distance(b);
        let centre = a.lerp(b, 0.5);
        let mut spans: Vec<(f64, f64, u32)> = Vec::new();
        for &i in self.pieces(cell) {
            let prim = &self.prims[i as usize];
            // 1-Lipschitz: a piece this far from the centre misses the segment.
            if prim.eval(centre, self.band) > half {
                continue;
            }
            let g = |t: f64| prim.eval(a.lerp(b, t), self.band);
            let Some(least) = inside_point(&g) else {
                continue;
            };
            spans.push((last_inside(&g, least, 0.0), last_inside(&g, least, 1.0), i));
        }
        spans.sort_by(|x, y| x.0.total_cmp(&y.0));
        // Sweep: `reach` is how far the spans so far cover, `last` the piece that reaches it.
        let (mut reach, mut last) = (0.0, None);
        for &(t0, t1, i) in &spans {
            if let Some(p) = last.filter(|_| t0 > reach) {
                if self.apart(p, i) {
                    return Some(Bridge::Gap);
                }
                if self.crotch(p, i, a.lerp(b, 0.5 * (reach + t0)), cell) {
                    return Some(Bridge::Shape);
                }
            }
            if t1 > reach || last.is_none() {
                (reach, last) = (t1.max(reach), Some(i));
            }
        }
        None
    }

    /// Whether the segment's hole at `m`, between pieces `p` and `q` that touch, crosses a
    /// crotch too narrow to leave bridged: the two surfaces face each other (more than 120°
    /// apart) and the hole is deep enough that the crotch below the bridge (about its depth
    /// over the tangent of half the crotch's angle) is more than half the tolerance deep.
    fn crotch(&self, p: u32, q: u32, m: DVec3, cell: [usize; 3]) -> bool {
        let cos = outward_cos(
            &self.prims[p as usize],
            &self.prims[q as usize],
            m,
            self.band,
        );
        if cos >= FACING {
            return false;
        }
        // The crotch's opening angle is π less the angle between the outward directions.
        let half = 0.5 * (std::f64::consts::PI - cos.clamp(-1.0, 1.0).acos());
        self.value(m, cell) > 0.5 * self.tol * half.tan()
    }

    fn apart(&mut self, p: u32, q: u32) -> bool {
        let key = (p.min(q), p.max(q));
        let prims = self.prims;
        *self
            .apart
            .entry(key)
            .or_insert_with(|| prims[p as usize].apart(&prims[q as usize]))
    }

    /// Whether the segment from `a` (in each of `pa`) to `b` (in each of `pb`) stays in the
    /// union of one piece of each: it must enter the second before it leaves the first.
    fn joined(&self, a: DVec3, pa: &[u32], b: DVec3, pb: &[u32]) -> bool {
        pa.iter().any(|&p| {
            let first = &self.prims[p as usize];
            let g = |t: f64| first.eval(a.lerp(b, t), self.band);
            let out = last_inside(&g, 0.0, 1.0);
            if out == 1.0 {
                return true;
            }
            let exit = a.lerp(b, out);
            pb.iter()
                .any(|&q| self.prims[q as usize].eval(exit, self.band) <= 0.0)
        })
    }
}

/// A point of [0, 1] where `g` is not positive, searched by golden sections toward its least
/// (`g` falls then rises along a line through a convex piece); `None` when it stays positive.
fn inside_point(g: &impl Fn(f64) -> f64) -> Option<f64> {
    let t = golden(g, |v| v <= 0.0);
    (g(t) <= 0.0).then_some(t)
}

/// The last point from `inn` (where `g` is not positive) toward `out` where it is still not
/// positive, by bisection (`out` itself when `g` is not positive there).
fn last_inside(g: &impl Fn(f64) -> f64, mut inn: f64, mut out: f64) -> f64 {
    if g(out) <= 0.0 {
        return out;
    }
    for _ in 0..30 {
        let mid = 0.5 * (inn + out);
        if g(mid) <= 0.0 {
            inn = mid;
        } else {
            out = mid;
        }
    }
    inn
}

/// A tetrahedron's six edges as corner pairs.
pub(super) fn pairs() -> impl Iterator<Item = (usize, usize)> {
    (0..4).flat_map(|a| (a + 1..4).map(move |b| (a, b)))
}

/// The cell and corner offset of fine point `p` if it lies on the grid.
pub(super) fn grid_point(p: Pt) -> Option<[usize; 3]> {
    p.iter()
        .all(|&c| c >= 0 && c % SCALE == 0)
        .then(|| p.map(|c| (c / SCALE) as usize))
}

/// For a grid edge (both ends on the grid, one cell step along a subset of axes, low to high):
/// its low end and direction code.
pub(super) fn grid_edge(p: Pt, q: Pt) -> Option<([usize; 3], u8)> {
    let (gp, gq) = (grid_point(p)?, grid_point(q)?);
    let (lo, hi) = if p <= q { (gp, gq) } else { (gq, gp) };
    let mut dir = 0u8;
    for a in 0..3 {
        match hi[a] as i64 - lo[a] as i64 {
            0 => {}
            1 => dir |= 1 << a,
            _ => return None,
        }
    }
    (dir != 0).then_some((lo, dir))
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Empty;
    impl Field for Empty {
        fn near(&self, _: [usize; 3]) -> &[u32] {
            &[]
        }
        fn grid_inside(&self, _: [usize; 3]) -> Option<bool> {
            None
        }
    }

    fn volume(v: &[Pt; 4]) -> i128 {
        let d = |i: usize| [0, 1, 2].map(|a| (v[i][a] - v[0][a]) as i128);
        let (a, b, c) = (d(1), d(2), d(3));
        (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            .abs()
    }

    /// Random local bisections leave tetrahedra that meet face to face: every face inside the
    /// brought-in cells is shared by two, and a face held by one is a face of the grid's own
    /// split (so the cells left out meet it whole).
    #[test]
    fn bisections_keep_the_tetrahedra_matched() {
        let grid = Grid {
            origin: DVec3::ZERO,
            h: 1.0,
            points: [10, 10, 10],
        };
        let budget = Budget::default();
        let mut adapt = Adapt::new(&grid, &[], &Empty, &budget, 1.0, (0.25, 16));
        adapt.bring([4, 4, 4]);
        let mut seed = 7u64;
        for _ in 0..400 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let live: Vec<u32> = (0..adapt.tets.len() as u32)
                .filter(|&i| adapt.tets[i as usize].alive && adapt.tets[i as usize].level < 9)
                .collect();
            let id = live[(seed >> 33) as usize % live.len()];
            adapt.refine(id, 0).unwrap();
        }
        let mut faces: QuickMap<[Pt; 3], usize> = QuickMap::default();
        let mut total = 0i128;
        for t in adapt.tets.iter().filter(|t| t.alive) {
            let v = adapt.corners(t);
            total += volume(&v);
            for skip in 0..4 {
                let mut f: Vec<Pt> = (0..4).filter(|&i| i != skip).map(|i| v[i]).collect();
                f.sort();
                *faces.entry([f[0], f[1], f[2]]).or_default() += 1;
            }
        }
        // Six times the volume of the brought-in cells.
        let cell = SCALE as i128;
        assert_eq!(total, 6 * cell * cell * cell * adapt.cells.len() as i128);
        assert!(adapt.cells.len() > 1, "closure brought in neighbours");
        for (f, n) in &faces {
            assert!(*n <= 2, "face {f:?} held {n} times");
            let top = 9 * SCALE;
            let on_border = (0..3).any(|a| f.iter().all(|p| p[a] == 0 || p[a] == top));
            if *n == 1 && !on_border {
                assert!(
                    f.iter().all(|p| grid_point(*p).is_some()),
                    "a lone face off the grid: {f:?}"
                );
            }
        }
    }
}
