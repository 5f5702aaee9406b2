//! Weld preparation at a node: setbacks that give every pair of angularly adjacent plates the
//! same root gap, the dihedral (wedge) angle of every such pair, and node cores where no
//! setbacks can.
//!
//! The plates at a node all contain the node's axis, so in the plane ⊥ the axis (the section)
//! each is a strip leaving the axis along its direction u, as thick as the plate (a bolted seam
//! counts as its stack of two halves), starting at its setback s. Two plates' root gap is the
//! distance between their strips: the weld's root opening along the line (∥ the axis) where
//! they meet. It only grows with either setback.
//!
//! Solve, per node: start from the bisector rule (every pair at least the gap apart), then
//! retract the plates one at a time as far as the others allow (each stops at the gap from its
//! nearest neighbour, or at the axis), then Levenberg-Marquardt on the adjacent pairs' gaps
//! (n equations, n setbacks) from there; plate orders are tried until every adjacent pair is
//! within the tolerance. A node where none is (a plate branching sharply off two nearly
//! collinear ones, typically) is reported: it needs a node core, a tube on the axis the plates
//! butt against (root gap = setback − tube radius).

use glam::DVec2;

use crate::geom::convex_distance;

/// One plate at a node, in the section's 2D basis.
#[derive(Clone, Copy, Debug)]
pub struct Strip {
    /// Unit direction from the axis into the plate.
    pub u: DVec2,
    /// Across the plate (a seam's stack), mm.
    pub thickness: f64,
    /// How far the strip reaches from the axis, mm (the plate's length there).
    pub reach: f64,
    /// From the plane through the axis along u to the strip's middle, along `u.perp()`, mm: 0
    /// for a plate; for a seam's ply, half the other ply (the stack is centred on the plane).
    pub offset: f64,
}

impl Strip {
    /// A plate centred on the plane through the axis.
    pub fn centred(u: DVec2, thickness: f64, reach: f64) -> Strip {
        Strip {
            u,
            thickness,
            reach,
            offset: 0.0,
        }
    }

    fn corners(&self, s: f64) -> [DVec2; 4] {
        let side = self.u.perp();
        let (lo, hi) = (
            side * (self.offset - 0.5 * self.thickness),
            side * (self.offset + 0.5 * self.thickness),
        );
        let far = self.reach.max(s + 1.0);
        [
            self.u * s + lo,
            self.u * far + lo,
            self.u * far + hi,
            self.u * s + hi,
        ]
    }

    /// Half its width as seen from the plane through the axis: the farther face.
    fn half_width(&self) -> f64 {
        0.5 * self.thickness + self.offset.abs()
    }

    /// The least distance from the axis of its end face across the plane through the axis.
    fn off_axis(&self) -> f64 {
        (self.offset.abs() - 0.5 * self.thickness).max(0.0)
    }
}

/// Distance between strip `a` set back `sa` and strip `b` set back `sb`; negative (the depth
/// of the shallowest separating direction) when they overlap.
pub fn root_gap(a: &Strip, sa: f64, b: &Strip, sb: f64) -> f64 {
    convex_distance(&a.corners(sa), &b.corners(sb))
}

/// Weld access by the angle between two plates (0–180°), in angle order, each with the colour
/// every report and viewer gives it: below 60° there is no prequalified fillet weld (red, what a
/// shop cannot do); 60–120° is prequalified by EN 1993-1-8 §4.3.2.1 (green); 120–135° only AWS
/// D1.1 allows (amber); above, the plates meet end to end (a butt weld, blue).
pub const WELD_CLASSES: [(&str, &str); 4] = [
    ("below 60°: no prequalified fillet weld", "#d62728"),
    ("60–120°: fillet (EN 1993-1-8)", "#2ca02c"),
    ("120–135°: fillet (AWS D1.1 only)", "#e69f00"),
    ("135–180°: butt", "#1f77b4"),
];

/// The index into `WELD_CLASSES` of a pair whose plates are `angle_deg` apart.
pub fn weld_class(angle_deg: f64) -> usize {
    if angle_deg < 60.0 {
        0
    } else if angle_deg <= 120.0 {
        1
    } else if angle_deg <= 135.0 {
        2
    } else {
        3
    }
}

/// How urgent a class is for the shop, most first: no prequalified weld, AWS only, butt,
/// prequalified fillet.
pub fn weld_class_urgency(class: usize) -> usize {
    [0, 3, 1, 2].get(class).copied().unwrap_or(4)
}

/// Two plates side by side around the axis, and the wedge between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wedge {
    /// Indices into the node's strips: `b` follows `a` counter-clockwise about the axis.
    pub a: usize,
    pub b: usize,
    /// The dihedral angle between the two plates on this side, radians in (0, 2π).
    pub angle: f64,
}

/// The wedges around a node, counter-clockwise from the first plate: n for n ≥ 3 plates, both
/// sides of the one pair for 2, none for fewer.
pub fn wedges(strips: &[Strip]) -> Vec<Wedge> {
    if strips.len() < 2 {
        return Vec::new();
    }
    let angle = |k: usize| {
        let u = strips[k].u;
        let a = u.y.atan2(u.x) - strips[0].u.y.atan2(strips[0].u.x);
        a.rem_euclid(std::f64::consts::TAU)
    };
    let mut order: Vec<usize> = (0..strips.len()).collect();
    order.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)).then(a.cmp(&b)));
    (0..order.len())
        .map(|i| {
            let (a, b) = (order[i], order[(i + 1) % order.len()]);
            let mut w = (angle(b) - angle(a)).rem_euclid(std::f64::consts::TAU);
            if w == 0.0 {
                w = std::f64::consts::TAU; // two plates: the far side of the pair
            }
            Wedge { a, b, angle: w }
        })
        .collect()
}

/// The pairs whose gaps are held to the target: the distinct pairs of neighbouring wedges.
fn adjacent(strips: &[Strip]) -> Vec<(usize, usize)> {
    let mut pairs: Vec<(usize, usize)> = wedges(strips)
        .iter()
        .map(|w| (w.a.min(w.b), w.a.max(w.b)))
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// What the solve settled on at one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Cut {
    /// Setback per strip, mm.
    pub setbacks: Vec<f64>,
    /// Whether every adjacent pair's root gap is within the tolerance of the target.
    pub even: bool,
}

/// The bisector rule: every pair at least `gap` apart at the bisector of their directions. Also
/// the start of the solve. None if two plates leave the axis in the same direction.
pub fn bisector_setbacks(strips: &[Strip], gap: f64) -> Option<Vec<f64>> {
    let mut out = vec![0.0f64; strips.len()];
    for (k, a) in strips.iter().enumerate() {
        for (m, b) in strips.iter().enumerate() {
            if m == k {
                continue;
            }
            let half = 0.5 * a.u.dot(b.u).clamp(-1.0, 1.0).acos();
            if half.sin() < 1e-6 {
                return None;
            }
            let s = a.half_width() / half.tan() + gap / (2.0 * half.sin());
            out[k] = out[k].max(s);
        }
    }
    Some(out)
}

/// Most plate orders tried at one node (all of them up to five plates).
const ORDERS: usize = 120;
const LM_STEPS: usize = 40;

/// Setbacks that bring every adjacent pair's root gap within `tolerance` of `gap` (and keep
/// every other pair at least `gap − tolerance` apart), or the best found with `even` false.
pub fn even_gaps(strips: &[Strip], gap: f64, tolerance: f64) -> Option<Cut> {
    let start = bisector_setbacks(strips, gap)?;
    if strips.len() < 2 {
        return Some(Cut {
            setbacks: start,
            even: true,
        });
    }
    let pairs = adjacent(strips);
    let mut best: Option<(f64, Vec<f64>)> = None;
    // Starts: the bisector setbacks, then the plates laid in one at a time in each order (the
    // first runs to the axis, each next one stops at the gap from those before it).
    let starts = std::iter::once(Some(start.clone())).chain(
        orders(strips.len())
            .take(ORDERS)
            .map(|o| insert(strips, &o, gap)),
    );
    for s in starts.flatten() {
        let mut s = s;
        let identity: Vec<usize> = (0..strips.len()).collect();
        retract(strips, &mut s, &identity, gap);
        let mut err = worst(strips, &s, &pairs, gap, tolerance);
        if err > tolerance {
            let refined = levenberg_marquardt(strips, &s, &pairs, gap, tolerance);
            let e = worst(strips, &refined, &pairs, gap, tolerance);
            if e < err {
                (s, err) = (refined, e);
            }
        }
        if best.as_ref().is_none_or(|b| err < b.0) {
            best = Some((err, s));
        }
        if err <= tolerance {
            break;
        }
    }
    let (err, setbacks) = best.expect("at least one order");
    Some(Cut {
        setbacks,
        even: err <= tolerance,
    })
}

/// How far the worst adjacent pair is from the target gap; infinite when any pair is closer
/// than the target less the tolerance (never accepted: the plates would clash or crowd).
fn worst(strips: &[Strip], s: &[f64], pairs: &[(usize, usize)], gap: f64, tolerance: f64) -> f64 {
    let mut err = 0.0f64;
    for a in 0..strips.len() {
        for b in a + 1..strips.len() {
            let g = root_gap(&strips[a], s[a], &strips[b], s[b]);
            if g < gap - tolerance - 1e-9 {
                return f64::INFINITY;
            }
            if pairs.contains(&(a, b)) {
                err = err.max((g - gap).abs());
            } else {
                err = err.max(gap - g);
            }
        }
    }
    err
}

/// Each plate in turn moves in as far as every other plate stays `gap` away (bisection: the
/// gap only grows with the setback), sweeping until nothing moves.
fn retract(strips: &[Strip], s: &mut [f64], order: &[usize], gap: f64) {
    for _ in 0..20 {
        let mut moved = 0.0f64;
        for &k in order {
            let clear = |sk: f64, s: &[f64]| {
                (0..strips.len())
                    .all(|m| m == k || root_gap(&strips[k], sk, &strips[m], s[m]) >= gap - 1e-9)
            };
            if clear(0.0, s) {
                moved = moved.max(s[k]);
                s[k] = 0.0;
                continue;
            }
            let (mut lo, mut hi) = (0.0, s[k]);
            for _ in 0..48 {
                let mid = 0.5 * (lo + hi);
                if clear(mid, s) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            moved = moved.max(s[k] - hi);
            s[k] = hi;
        }
        if moved < 1e-9 {
            break;
        }
    }
}

/// The plates laid in one at a time in `order`, each at the least setback that keeps it `gap`
/// from those already there. None if one cannot clear them within its reach.
fn insert(strips: &[Strip], order: &[usize], gap: f64) -> Option<Vec<f64>> {
    let mut s = vec![0.0; strips.len()];
    for (i, &k) in order.iter().enumerate() {
        let placed = &order[..i];
        let clear = |sk: f64, s: &[f64]| {
            placed
                .iter()
                .all(|&m| root_gap(&strips[k], sk, &strips[m], s[m]) >= gap - 1e-9)
        };
        if clear(0.0, &s) {
            continue;
        }
        let mut hi = gap.max(strips[k].thickness).max(1e-3);
        while !clear(hi, &s) {
            hi *= 2.0;
            if hi > strips[k].reach {
                return None;
            }
        }
        let mut lo = 0.0;
        for _ in 0..48 {
            let mid = 0.5 * (lo + hi);
            if clear(mid, &s) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        s[k] = hi;
    }
    Some(s)
}

/// Least squares on the adjacent gaps (and the shortfall of any other pair), setbacks ≥ 0.
fn levenberg_marquardt(
    strips: &[Strip],
    start: &[f64],
    pairs: &[(usize, usize)],
    gap: f64,
    tolerance: f64,
) -> Vec<f64> {
    let n = strips.len();
    let residuals = |s: &[f64]| -> Vec<f64> {
        let mut r = Vec::new();
        for a in 0..n {
            for b in a + 1..n {
                let g = root_gap(&strips[a], s[a], &strips[b], s[b]);
                if pairs.contains(&(a, b)) {
                    r.push(g - gap);
                } else {
                    r.push((g - (gap - 0.5 * tolerance)).min(0.0));
                }
            }
        }
        r
    };
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut s = start.to_vec();
    let mut r = residuals(&s);
    let mut lambda = 1e-3;
    for _ in 0..LM_STEPS {
        // Jacobian by central differences (the gap is piecewise smooth in the setbacks).
        let h = 1e-6;
        let mut jac = vec![vec![0.0; n]; r.len()];
        for k in 0..n {
            let (mut up, mut down) = (s.clone(), s.clone());
            up[k] += h;
            down[k] = (down[k] - h).max(0.0);
            let (ru, rd) = (residuals(&up), residuals(&down));
            let step = up[k] - down[k];
            for (i, row) in jac.iter_mut().enumerate() {
                row[k] = (ru[i] - rd[i]) / step;
            }
        }
        let mut improved = false;
        for _ in 0..8 {
            let Some(delta) = damped_step(&jac, &r, lambda) else {
                lambda *= 10.0;
                continue;
            };
            let next: Vec<f64> = s
                .iter()
                .zip(&delta)
                .map(|(v, d)| (v - d).max(0.0))
                .collect();
            let rn = residuals(&next);
            if cost(&rn) < cost(&r) {
                (s, r) = (next, rn);
                lambda = (lambda * 0.3).max(1e-9);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved || cost(&r).sqrt() < 1e-3 * tolerance {
            break;
        }
    }
    s
}

/// (JᵀJ + λ diag(JᵀJ) + λ I) δ = Jᵀ r, by Gaussian elimination with partial pivoting.
fn damped_step(jac: &[Vec<f64>], r: &[f64], lambda: f64) -> Option<Vec<f64>> {
    let n = jac.first()?.len();
    let mut a = vec![vec![0.0; n + 1]; n];
    for (row, &ri) in jac.iter().zip(r) {
        for i in 0..n {
            for j in 0..n {
                a[i][j] += row[i] * row[j];
            }
            a[i][n] += row[i] * ri;
        }
    }
    for (i, row) in a.iter_mut().enumerate() {
        row[i] += lambda * (row[i] + 1.0);
    }
    for c in 0..n {
        let p = (c..n).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[p][c].abs() < 1e-15 {
            return None;
        }
        a.swap(c, p);
        let pivot = a[c].clone();
        for row in a.iter_mut().skip(c + 1) {
            let f = row[c] / pivot[c];
            for (x, p) in row.iter_mut().zip(&pivot).skip(c) {
                *x -= f * p;
            }
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let tail: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
        x[i] = (a[i][n] - tail) / a[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Plate orders for laying the plates in: the identity, then the rest in lexicographic order.
fn orders(n: usize) -> impl Iterator<Item = Vec<usize>> {
    let mut next = Some((0..n).collect::<Vec<usize>>());
    std::iter::from_fn(move || {
        let cur = next.take()?;
        let mut p = cur.clone();
        // Next permutation.
        if let Some(i) = (0..n.saturating_sub(1)).rev().find(|&i| p[i] < p[i + 1]) {
            let j = (i + 1..n)
                .rev()
                .find(|&j| p[j] > p[i])
                .expect("p[i+1] > p[i]");
            p.swap(i, j);
            p[i + 1..].reverse();
            next = Some(p);
        }
        Some(cur)
    })
}

/// Setbacks against a node core of outer radius `radius`: every plate's end ends `gap` from the
/// tube where it comes closest (a flat end against a round tube: at the plate's middle, or for
/// a ply beside the plane through the axis, at its face nearer the plane).
pub fn core_setbacks(strips: &[Strip], radius: f64, gap: f64) -> Vec<f64> {
    strips
        .iter()
        .map(|s| {
            ((radius + gap).powi(2) - s.off_axis().powi(2))
                .max(0.0)
                .sqrt()
        })
        .collect()
}

/// The least setback, at least `from`, at which `strip` stays `gap` from every strip of
/// `others` (each at its setback) and, with a core of outer radius `core`, `gap` from the tube;
/// None if it cannot within its reach. Bisection: the gap only grows with the setback.
pub fn clearing_setback(
    strip: &Strip,
    from: f64,
    others: &[(Strip, f64)],
    core: Option<f64>,
    gap: f64,
) -> Option<f64> {
    let clear = |s: f64| {
        others
            .iter()
            .all(|(o, so)| root_gap(strip, s, o, *so) >= gap - 1e-9)
            && core.is_none_or(|r| s.hypot(strip.off_axis()) >= r + gap - 1e-9)
    };
    if clear(from) {
        return Some(from);
    }
    if !clear(strip.reach) {
        return None;
    }
    let (mut lo, mut hi) = (from, strip.reach);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if clear(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strip(deg: f64, t: f64) -> Strip {
        Strip::centred(DVec2::from_angle(deg.to_radians()), t, 200.0)
    }

    fn gaps(strips: &[Strip], s: &[f64]) -> Vec<f64> {
        adjacent(strips)
            .iter()
            .map(|&(a, b)| root_gap(&strips[a], s[a], &strips[b], s[b]))
            .collect()
    }

    #[test]
    fn a_symmetric_y_joint_keeps_the_bisector_setbacks() {
        let y = [strip(0.0, 6.0), strip(120.0, 6.0), strip(240.0, 6.0)];
        let cut = even_gaps(&y, 1.0, 0.01).expect("distinct directions");
        assert!(cut.even);
        for g in gaps(&y, &cut.setbacks) {
            assert!((g - 1.0).abs() <= 0.01, "{g}");
        }
        let want = 3.0 / 60f64.to_radians().tan() + 1.0 / (2.0 * 60f64.to_radians().sin());
        for s in &cut.setbacks {
            assert!((s - want).abs() < 1e-6, "{s} vs {want}");
        }
    }

    #[test]
    fn uneven_joints_get_even_gaps() {
        // A T of a through pair and a branch, a Y of mixed thicknesses, a bend.
        for strips in [
            vec![strip(0.0, 5.0), strip(180.0, 5.0), strip(90.0, 3.0)],
            vec![strip(0.0, 6.0), strip(110.0, 2.0), strip(230.0, 4.0)],
            vec![strip(0.0, 4.0), strip(150.0, 4.0)],
            vec![
                strip(0.0, 3.0),
                strip(90.0, 3.0),
                strip(180.0, 3.0),
                strip(270.0, 3.0),
            ],
        ] {
            let cut = even_gaps(&strips, 1.0, 0.5).expect("distinct directions");
            assert!(cut.even, "{strips:?}: {:?}", gaps(&strips, &cut.setbacks));
            for g in gaps(&strips, &cut.setbacks) {
                assert!((g - 1.0).abs() <= 0.5, "{g}");
            }
            assert!(cut.setbacks.iter().all(|s| *s >= 0.0));
        }
    }

    #[test]
    fn a_sharp_branch_off_a_near_straight_pair_needs_a_core() {
        let strips = [strip(0.0, 6.0), strip(170.0, 6.0), strip(30.0, 6.0)];
        let cut = even_gaps(&strips, 1.0, 0.5).expect("distinct directions");
        assert!(!cut.even, "{:?}", gaps(&strips, &cut.setbacks));
        // Still no clash: every pair at least the gap less the tolerance apart.
        for a in 0..3 {
            for b in a + 1..3 {
                let g = root_gap(&strips[a], cut.setbacks[a], &strips[b], cut.setbacks[b]);
                assert!(g >= 0.5 - 1e-9, "{a}-{b}: {g}");
            }
        }
    }

    #[test]
    fn wedges_go_round_the_axis() {
        let w = wedges(&[strip(0.0, 1.0), strip(250.0, 1.0), strip(100.0, 1.0)]);
        let deg: Vec<(usize, usize, f64)> = w
            .iter()
            .map(|w| (w.a, w.b, (w.angle.to_degrees() * 1e6).round() / 1e6))
            .collect();
        assert_eq!(deg, vec![(0, 2, 100.0), (2, 1, 150.0), (1, 0, 110.0)]);
        let two = wedges(&[strip(0.0, 1.0), strip(150.0, 1.0)]);
        assert_eq!(two.len(), 2);
        assert!((two[0].angle + two[1].angle - std::f64::consts::TAU).abs() < 1e-12);
    }

    #[test]
    fn root_gap_is_the_distance_between_strips() {
        // Two collinear strips facing each other, set back 2 and 3: 5 apart.
        let (a, b) = (strip(0.0, 2.0), strip(180.0, 2.0));
        assert!((root_gap(&a, 2.0, &b, 3.0) - 5.0).abs() < 1e-12);
        // A branch at 90° set back 1 + t/2 from a through strip at 0: gap 1.
        let c = strip(90.0, 2.0);
        assert!((root_gap(&a, 0.0, &c, 2.0) - 1.0).abs() < 1e-12);
        assert!(root_gap(&a, 0.0, &c, 0.5) < 0.0);
    }
}
