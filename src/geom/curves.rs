//! Curves flattened into polylines within a chord tolerance: circular arcs (also given by a DXF
//! bulge), ellipse arcs and NURBS curves.
//!
//! Guarantee: every returned point lies on the curve (up to rounding), and every chord between
//! two consecutive points stays within `tol` of the curve piece it replaces. Arcs and ellipses
//! get that from a closed-form step; NURBS curves from the convex-hull property of their Bézier
//! pieces (subdivided until every control point lies within `tol` of the piece's chord), which
//! holds for any positive weights. A curve that would need more points than its budget (see
//! `MAX_ARC_POINTS`, `POINTS_PER_CONTROL_POINT`) is refused rather than flattened coarser than
//! asked.

use glam::{DVec2, DVec3, DVec4};

/// The most points one curve may flatten to. A circle of radius 1 km at the default 0.05 mm
/// tolerance takes about 22,000; a million points means a tolerance the drawing cannot mean.
pub const MAX_CURVE_POINTS: usize = 1_000_000;

/// The most points one circular or elliptic arc may flatten to: a whole circle of radius 100 km
/// at the default 0.05 mm takes about 99,000. More means a radius no drawing means (a bulge of
/// 2³² on a 9 mm chord is a circle of radius 10⁴ km), and a million such points in an 18 KB file
/// cost a second to read.
pub const MAX_ARC_POINTS: usize = 100_000;

/// Points a spline may flatten to per control (or fit) point, at least `MAX_ARC_POINTS` and at
/// most `MAX_CURVE_POINTS` in all: a span of a CAD spline takes a few to a few hundred at 0.05 mm.
pub const POINTS_PER_CONTROL_POINT: usize = 1_000;

/// The point budget of a spline of `n` control or fit points.
fn spline_budget(n: usize) -> usize {
    n.saturating_mul(POINTS_PER_CONTROL_POINT)
        .clamp(MAX_ARC_POINTS, MAX_CURVE_POINTS)
}

/// The most control points of one NURBS curve: splitting it into Bézier pieces costs about the
/// square of this, a fraction of a second at the limit. CAD splines hold tens to thousands.
pub const MAX_CONTROL_POINTS: usize = 10_000;
/// The highest NURBS degree read; CAD writes 1 to 5 (the DXF limit is 25).
pub const MAX_DEGREE: usize = 32;

/// Why a curve could not be flattened.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CurveError {
    #[error("a non-finite value ({0})")]
    NonFinite(&'static str),
    // The tolerance is in the drawing's units, which this message cannot say: left out.
    #[error("needs {needed} points within the chord tolerance (limit {limit} for this curve): raise --chord-tolerance")]
    TooManyPoints {
        /// A count, or "more than N" where subdivision stopped at the limit.
        needed: String,
        limit: usize,
    },
    #[error("{0}")]
    Invalid(String),
}

/// Number of chords for a circular arc of `radius` and `sweep` radians so that each chord's
/// sagitta `r (1 - cos(θ/2))` stays within `tol`; at least one per quarter turn.
fn arc_segments(radius: f64, sweep: f64, tol: f64) -> Result<usize, CurveError> {
    let quarter = (sweep.abs() / std::f64::consts::FRAC_PI_2).ceil().max(1.0);
    let n = if tol >= radius {
        quarter
    } else {
        let step = 2.0 * (1.0 - tol / radius).acos();
        (sweep.abs() / step).ceil().max(quarter)
    };
    if n.is_nan() || n > MAX_ARC_POINTS as f64 {
        return Err(CurveError::TooManyPoints {
            needed: format!("{n}"),
            limit: MAX_ARC_POINTS,
        });
    }
    Ok(n as usize)
}

/// Points of the arc about `center` of `radius` from angle `start` through `sweep` radians
/// (counter-clockwise when positive), both ends included.
pub fn arc(
    center: DVec2,
    radius: f64,
    start: f64,
    sweep: f64,
    tol: f64,
) -> Result<Vec<DVec2>, CurveError> {
    if !(center.is_finite() && radius.is_finite() && start.is_finite() && sweep.is_finite()) {
        return Err(CurveError::NonFinite("arc centre, radius or angles"));
    }
    let n = arc_segments(radius.abs(), sweep, tol)?;
    Ok((0..=n)
        .map(|k| {
            let a = start + sweep * k as f64 / n as f64;
            center + radius * DVec2::new(a.cos(), a.sin())
        })
        .collect())
}

/// The arc segment from `p0` to `p1` that a DXF bulge describes (bulge = tan(sweep / 4),
/// positive counter-clockwise). Returns the points after `p0`, ending exactly on `p1`; a bulge
/// of 0 (or coincident ends) gives the straight segment.
pub fn bulge_arc(p0: DVec2, p1: DVec2, bulge: f64, tol: f64) -> Result<Vec<DVec2>, CurveError> {
    if !bulge.is_finite() {
        return Err(CurveError::NonFinite("bulge"));
    }
    let d = p1 - p0;
    let c = d.length();
    if bulge == 0.0 || c == 0.0 {
        return Ok(vec![p1]);
    }
    let sweep = 4.0 * bulge.atan();
    let left = DVec2::new(-d.y, d.x) / c;
    let center = (p0 + p1) * 0.5 + left * (c * 0.5 / (sweep * 0.5).tan());
    let radius = (p0 - center).length();
    let v = p0 - center;
    let mut pts = arc(center, radius, v.y.atan2(v.x), sweep, tol)?;
    pts.remove(0);
    if let Some(last) = pts.last_mut() {
        *last = p1;
    }
    Ok(pts)
}

/// Points of the ellipse arc `center + major cos t + minor sin t` for t from `t0` to `t1`
/// (t1 > t0), both ends included. The chord error of a parameter step h is at most
/// h²/8 · max|r''| and |r''| ≤ |major| (the semi-major length), which sets the step.
pub fn ellipse(
    center: DVec3,
    major: DVec3,
    minor: DVec3,
    t0: f64,
    t1: f64,
    tol: f64,
) -> Result<Vec<DVec3>, CurveError> {
    if !(center.is_finite() && major.is_finite() && minor.is_finite()) {
        return Err(CurveError::NonFinite("ellipse centre or axes"));
    }
    if !(t0.is_finite() && t1.is_finite()) {
        return Err(CurveError::NonFinite("ellipse parameters"));
    }
    let a = major.length().max(minor.length());
    let sweep = t1 - t0;
    let step = if a > 0.0 {
        (8.0 * tol / a).sqrt()
    } else {
        f64::INFINITY
    };
    let quarter = (sweep.abs() / std::f64::consts::FRAC_PI_2).ceil().max(1.0);
    let n = (sweep.abs() / step).ceil().max(quarter);
    if n.is_nan() || n > MAX_ARC_POINTS as f64 {
        return Err(CurveError::TooManyPoints {
            needed: format!("{n}"),
            limit: MAX_ARC_POINTS,
        });
    }
    let n = n as usize;
    Ok((0..=n)
        .map(|k| {
            let t = t0 + sweep * k as f64 / n as f64;
            center + major * t.cos() + minor * t.sin()
        })
        .collect())
}

/// A NURBS curve: `degree`, knot vector of `control.len() + degree + 1` non-decreasing values,
/// control points and optional positive weights (one per control point).
pub struct Nurbs<'a> {
    pub degree: usize,
    pub knots: &'a [f64],
    pub control: &'a [DVec3],
    pub weights: Option<&'a [f64]>,
}

impl Nurbs<'_> {
    fn check(&self) -> Result<(), CurveError> {
        let (p, n) = (self.degree, self.control.len());
        let bad = |m: String| Err(CurveError::Invalid(m));
        if p == 0 {
            return bad("degree 0".into());
        }
        if n < p + 1 {
            return bad(format!(
                "{n} control points for degree {p} (needs {})",
                p + 1
            ));
        }
        if self.knots.len() != n + p + 1 {
            return bad(format!(
                "{} knots for {n} control points of degree {p} (needs {})",
                self.knots.len(),
                n + p + 1
            ));
        }
        if self.control.iter().any(|c| !c.is_finite()) {
            return Err(CurveError::NonFinite("control point"));
        }
        if self.knots.iter().any(|k| !k.is_finite()) {
            return Err(CurveError::NonFinite("knot"));
        }
        if self.knots.windows(2).any(|w| w[1] < w[0]) {
            return bad("knots decrease".into());
        }
        if self.knots[p] >= self.knots[n] {
            return bad("the knots leave the curve no parameter range".into());
        }
        if let Some(w) = self.weights {
            if w.len() != n {
                return bad(format!("{} weights for {n} control points", w.len()));
            }
            if w.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
                return bad("a weight that is not a positive number".into());
            }
        }
        Ok(())
    }

    /// The curve over its parameter range `[knots[degree], knots[n]]`, both ends included.
    pub fn flatten(&self, tol: f64) -> Result<Vec<DVec3>, CurveError> {
        let (p, n) = (self.degree, self.control.len());
        self.check()?;
        self.flatten_range(tol, self.knots[p], self.knots[n])
    }

    /// The piece of the curve over [lo, hi], which must lie in its parameter range.
    pub fn flatten_range(&self, tol: f64, lo: f64, hi: f64) -> Result<Vec<DVec3>, CurveError> {
        self.check()?;
        let p = self.degree;
        let (first, last) = (self.knots[p], self.knots[self.control.len()]);
        if !(first <= lo && lo < hi && hi <= last) {
            return Err(CurveError::Invalid(format!(
                "parameter range {lo}..{hi} is not inside the knots' {first}..{last}"
            )));
        }
        let mut knots = self.knots.to_vec();
        let mut ctrl: Vec<DVec4> = self
            .control
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let w = self.weights.map_or(1.0, |w| w[i]);
                (*c * w).extend(w)
            })
            .collect();
        // Every distinct knot in the range gets multiplicity p: the control points of each
        // non-empty span are then that span's Bézier piece.
        let mut values: Vec<f64> = knots
            .iter()
            .copied()
            .filter(|&u| lo < u && u < hi)
            .collect();
        values.insert(0, lo);
        values.push(hi);
        values.dedup();
        for u in values {
            while knots.iter().filter(|&&k| k == u).count() < p {
                insert_knot(&mut knots, &mut ctrl, p, u, lo);
            }
        }
        let mut out = vec![project(ctrl[p_start(&knots, p, lo)])];
        let limit = spline_budget(self.control.len());
        let mut budget = limit;
        for i in p..knots.len() - p - 1 {
            if knots[i] < knots[i + 1] && lo <= knots[i] && knots[i + 1] <= hi {
                subdivide(&ctrl[i - p..=i], tol, 0, &mut out, &mut budget)
                    .map_err(|Exhausted| too_many(limit))?;
            }
        }
        Ok(out)
    }
}

/// Index of the control point where the curve starts once the range start has multiplicity p.
fn p_start(knots: &[f64], p: usize, lo: f64) -> usize {
    let first_span = (p..knots.len() - 1)
        .find(|&i| knots[i] <= lo && lo < knots[i + 1])
        .unwrap_or(p);
    first_span - p
}

fn project(h: DVec4) -> DVec3 {
    h.truncate() / h.w
}

/// Boehm's knot insertion of `u` (once), in homogeneous coordinates, for `u` in the curve's
/// range. The span used is one whose closed interval holds `u` and whose control points exist:
/// the last knot at or below the range start, the last knot below any other value.
fn insert_knot(knots: &mut Vec<f64>, ctrl: &mut Vec<DVec4>, p: usize, u: f64, lo: f64) {
    let k = if u <= lo {
        knots.partition_point(|&x| x <= u) - 1
    } else {
        knots.partition_point(|&x| x < u) - 1
    };
    let mut fresh = Vec::with_capacity(p);
    for i in k + 1 - p..=k {
        let a = (u - knots[i]) / (knots[i + p] - knots[i]);
        fresh.push(ctrl[i] * a + ctrl[i - 1] * (1.0 - a));
    }
    ctrl.splice(k + 1 - p..k, fresh);
    knots.insert(k + 1, u);
}

/// Appends the end points of a Bézier piece's chords (not its first point), halving it by de
/// Casteljau until its control points all lie within `tol` of the chord.
fn subdivide(
    b: &[DVec4],
    tol: f64,
    depth: u32,
    out: &mut Vec<DVec3>,
    budget: &mut usize,
) -> Result<(), Exhausted> {
    let (a, z) = (project(b[0]), project(b[b.len() - 1]));
    let flat = b[1..b.len() - 1]
        .iter()
        .all(|c| super::point_segment_distance(project(*c), a, z) <= tol);
    if flat || depth >= 48 {
        if *budget == 0 {
            return Err(Exhausted);
        }
        *budget -= 1;
        out.push(z);
        return Ok(());
    }
    let mut work = b.to_vec();
    let mut left = Vec::with_capacity(b.len());
    let mut right = Vec::with_capacity(b.len());
    left.push(work[0]);
    right.push(work[work.len() - 1]);
    for level in 1..b.len() {
        for i in 0..b.len() - level {
            work[i] = (work[i] + work[i + 1]) * 0.5;
        }
        left.push(work[0]);
        right.push(work[b.len() - level - 1]);
    }
    right.reverse();
    subdivide(&left, tol, depth + 1, out, budget)?;
    subdivide(&right, tol, depth + 1, out, budget)
}

/// Subdivision spent the curve's point budget.
struct Exhausted;

fn too_many(limit: usize) -> CurveError {
    CurveError::TooManyPoints {
        needed: format!("more than {limit}"),
        limit,
    }
}

/// A curve through `points` (a centripetal Catmull-Rom spline, as cubic Béziers) flattened
/// within `tol`: for a SPLINE given by fit points alone. CAD programs interpolate fit points
/// with their own end conditions, so between fit points the two curves can differ slightly.
pub fn through_points(points: &[DVec3], closed: bool, tol: f64) -> Result<Vec<DVec3>, CurveError> {
    if points.iter().any(|p| !p.is_finite()) {
        return Err(CurveError::NonFinite("fit point"));
    }
    let mut pts: Vec<DVec3> = points.to_vec();
    pts.dedup();
    if pts.len() < 3 {
        return Ok(pts);
    }
    let n = pts.len();
    let at = |i: isize| -> DVec3 {
        if closed {
            pts[i.rem_euclid(n as isize) as usize]
        } else if i < 0 {
            pts[0] * 2.0 - pts[1]
        } else if i as usize >= n {
            pts[n - 1] * 2.0 - pts[n - 2]
        } else {
            pts[i as usize]
        }
    };
    let spans = if closed { n } else { n - 1 };
    let mut out = vec![pts[0]];
    let limit = spline_budget(n);
    let mut budget = limit;
    for s in 0..spans as isize {
        let (p0, p1, p2, p3) = (at(s - 1), at(s), at(s + 1), at(s + 2));
        // Centripetal parametrisation (alpha 1/2): no cusps or self-loops within a span.
        let d = |a: DVec3, b: DVec3| (a.distance(b)).sqrt().max(1e-300);
        let (d0, d1, d2) = (d(p0, p1), d(p1, p2), d(p2, p3));
        let m1 = (p1 - p0) / d0 - (p2 - p0) / (d0 + d1) + (p2 - p1) / d1;
        let m2 = (p2 - p1) / d1 - (p3 - p1) / (d1 + d2) + (p3 - p2) / d2;
        let (t1, t2) = (m1 * d1, m2 * d1);
        let bez = [p1, p1 + t1 / 3.0, p2 - t2 / 3.0, p2].map(|c| c.extend(1.0));
        subdivide(&bez, tol, 0, &mut out, &mut budget).map_err(|Exhausted| too_many(limit))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn max_radial_error(pts: &[DVec2], c: DVec2, r: f64) -> f64 {
        // The chord's midpoint is its farthest point from the arc.
        pts.windows(2)
            .map(|w| (r - ((w[0] + w[1]) * 0.5 - c).length()).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn arcs_stay_within_the_tolerance_and_use_few_points() -> Result<(), CurveError> {
        for (r, tol) in [(10.0, 0.05), (1000.0, 0.05), (0.01, 0.05), (5.0, 1e-4)] {
            let pts = arc(DVec2::ZERO, r, 0.3, 2.0 * PI, tol)?;
            assert!(max_radial_error(&pts, DVec2::ZERO, r) <= tol * (1.0 + 1e-9));
            // Twice the segments would also do: no more than needed (within one).
            let step = 2.0 * (1.0 - (tol / r).min(1.0)).acos();
            assert!(pts.len() - 1 <= ((2.0 * PI / step).ceil() as usize).max(4));
            assert!(pts.iter().all(|p| (p.length() - r).abs() < 1e-9 * r));
        }
        Ok(())
    }

    #[test]
    fn a_bulge_of_one_is_a_half_circle_counter_clockwise() -> Result<(), CurveError> {
        let pts = bulge_arc(DVec2::ZERO, DVec2::new(2.0, 0.0), 1.0, 0.001)?;
        assert_eq!(*pts.last().expect("points"), DVec2::new(2.0, 0.0));
        // Counter-clockwise from (0,0) to (2,0) about (1,0) passes below: y < 0.
        assert!(pts.iter().all(|p| p.y <= 1e-12));
        let low = pts.iter().map(|p| p.y).fold(0.0, f64::min);
        assert!((low + 1.0).abs() < 0.001);
        let back = bulge_arc(DVec2::ZERO, DVec2::new(2.0, 0.0), -1.0, 0.001)?;
        assert!(back.iter().all(|p| p.y >= -1e-12));
        Ok(())
    }

    #[test]
    fn a_degree_one_nurbs_is_its_control_polygon() -> Result<(), CurveError> {
        let control = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0)];
        let knots = [0.0, 0.0, 1.0, 2.0, 2.0];
        let c = Nurbs {
            degree: 1,
            knots: &knots,
            control: &control,
            weights: None,
        };
        assert_eq!(c.flatten(0.01)?, control.to_vec());
        Ok(())
    }

    #[test]
    fn a_rational_quadratic_quarter_circle_stays_on_the_circle() -> Result<(), CurveError> {
        let control = [DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let weights = [1.0, w, 1.0];
        let knots = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let c = Nurbs {
            degree: 2,
            knots: &knots,
            control: &control,
            weights: Some(&weights),
        };
        let pts = c.flatten(1e-4)?;
        assert!(pts.len() > 5);
        for p in &pts {
            assert!((p.length() - 1.0).abs() < 1e-12, "{p}");
        }
        let flat: Vec<DVec2> = pts.iter().map(|p| p.truncate()).collect();
        assert!(max_radial_error(&flat, DVec2::ZERO, 1.0) <= 1e-4);
        Ok(())
    }

    #[test]
    fn an_unclamped_cubic_starts_at_its_parameter_range() -> Result<(), CurveError> {
        // Uniform knots: the curve runs over [3, 4] and starts at (P0 + 4 P1 + P2) / 6.
        let control = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::Y * 3.0,
        ];
        let knots: Vec<f64> = (0..8).map(f64::from).collect();
        let c = Nurbs {
            degree: 3,
            knots: &knots,
            control: &control,
            weights: None,
        };
        let pts = c.flatten(1e-3)?;
        let start = (control[0] + control[1] * 4.0 + control[2]) / 6.0;
        let end = (control[1] + control[2] * 4.0 + control[3]) / 6.0;
        assert!(pts[0].distance(start) < 1e-12);
        assert!(pts[pts.len() - 1].distance(end) < 1e-12);
        Ok(())
    }

    #[test]
    fn a_range_of_a_curve_starts_and_ends_on_it() -> Result<(), CurveError> {
        // The quadratic Bézier (0,0) (1,2) (2,0): at t = 1/4, (0.5, 0.75); at 3/4, (1.5, 0.75).
        let control = [
            DVec3::ZERO,
            DVec3::new(1.0, 2.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
        ];
        let knots = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let c = Nurbs {
            degree: 2,
            knots: &knots,
            control: &control,
            weights: None,
        };
        let pts = c.flatten_range(1e-4, 0.25, 0.75)?;
        assert!(pts[0].distance(DVec3::new(0.5, 0.75, 0.0)) < 1e-12);
        assert!(pts[pts.len() - 1].distance(DVec3::new(1.5, 0.75, 0.0)) < 1e-12);
        assert!(c.flatten_range(1e-4, 0.5, 1.5).is_err());
        Ok(())
    }

    #[test]
    fn bad_curves_are_refused() {
        let control = [DVec3::ZERO, DVec3::X];
        let short = [0.0, 1.0];
        let c = Nurbs {
            degree: 1,
            knots: &short,
            control: &control,
            weights: None,
        };
        assert!(matches!(c.flatten(0.1), Err(CurveError::Invalid(_))));
        assert!(matches!(
            arc(DVec2::ZERO, 1e300, 0.0, 6.0, 1e-3),
            Err(CurveError::TooManyPoints { .. })
        ));
        assert!(bulge_arc(DVec2::ZERO, DVec2::X, f64::NAN, 0.1).is_err());
    }

    #[test]
    fn budgets_follow_what_a_curve_can_mean() {
        // A whole circle of radius 100 km flattens at 0.05 mm; a bulge of 2^32 on a 9 mm
        // chord (a circle of radius 10,000 km, found by the fuzzer) does not.
        assert!(arc(DVec2::ZERO, 1e8, 0.0, std::f64::consts::TAU, 0.05).is_ok());
        let Err(CurveError::TooManyPoints { limit, .. }) =
            bulge_arc(DVec2::ZERO, DVec2::new(9.0, 0.0), 2f64.powi(32), 0.05)
        else {
            panic!("a bulge of 2^32 is flattened");
        };
        assert_eq!(limit, MAX_ARC_POINTS);
        // A spline's budget grows with its control points, between the two limits.
        assert_eq!(spline_budget(3), MAX_ARC_POINTS);
        assert_eq!(spline_budget(500), 500_000);
        assert_eq!(spline_budget(5_000), MAX_CURVE_POINTS);
        // A quarter circle of radius 10,000 km as a rational spline of three control points
        // spends its budget and is refused.
        let r = 1e10;
        let control = [
            DVec3::new(r, 0.0, 0.0),
            DVec3::new(r, r, 0.0),
            DVec3::new(0.0, r, 0.0),
        ];
        let knots = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let weights = [1.0, std::f64::consts::FRAC_1_SQRT_2, 1.0];
        let c = Nurbs {
            degree: 2,
            knots: &knots,
            control: &control,
            weights: Some(&weights),
        };
        let got = c.flatten(0.05).map(|p| p.len());
        assert!(
            matches!(
                got,
                Err(CurveError::TooManyPoints {
                    limit: MAX_ARC_POINTS,
                    ..
                })
            ),
            "{got:?}"
        );
    }

    #[test]
    fn fit_points_are_passed_through() -> Result<(), CurveError> {
        let fit = [
            DVec3::ZERO,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
        ];
        let pts = through_points(&fit, false, 1e-3)?;
        for f in &fit {
            assert!(pts.iter().any(|p| p.distance(*f) < 1e-12));
        }
        Ok(())
    }
}
