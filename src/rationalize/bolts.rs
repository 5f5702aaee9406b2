//! Bolts through the seam plates: metric sizes with their normal-clearance holes, a default
//! size for the grip, and a row of bolts along a seam plate that keeps the end, edge and pitch
//! distances of EN 1993-1-8 Table 3.3.
//!
//! Holes: EN 1090-2 Table 11 normal round holes (M12, M14: d + 1 mm; M16–M24: d + 2 mm; M27
//! and up: d + 3 mm); below M12, which EN 1090-2 does not cover, ISO 273's medium series. Every
//! hole centre stays at least 1.2 d0 from every edge of the plate (e1 along the member and e2
//! across it have the same minimum), neighbouring holes at least 2.2 d0 apart (p1) and at
//! most min(14 t, 200 mm) apart for the thinner ply t.

use glam::DVec2;

/// A metric bolt with what the shop needs to order and drill for it, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoltSize {
    pub name: &'static str,
    /// Shank diameter.
    pub d: f64,
    /// Hole diameter d0 (normal clearance).
    pub hole: f64,
    /// Thread pitch.
    pub pitch: f64,
    /// Hexagon nut height (ISO 4032).
    pub nut: f64,
    /// Plain washer thickness (ISO 7089).
    pub washer: f64,
}

const fn size(
    name: &'static str,
    d: f64,
    hole: f64,
    pitch: f64,
    nut: f64,
    washer: f64,
) -> BoltSize {
    BoltSize {
        name,
        d,
        hole,
        pitch,
        nut,
        washer,
    }
}

/// The sizes offered, smallest first.
pub const SIZES: [BoltSize; 10] = [
    size("M6", 6.0, 6.6, 1.0, 5.2, 1.6),
    size("M8", 8.0, 9.0, 1.25, 6.8, 1.6),
    size("M10", 10.0, 11.0, 1.5, 8.4, 2.0),
    size("M12", 12.0, 13.0, 1.75, 10.8, 2.5),
    size("M16", 16.0, 18.0, 2.0, 14.8, 3.0),
    size("M20", 20.0, 22.0, 2.5, 18.0, 3.0),
    size("M22", 22.0, 24.0, 2.5, 19.4, 3.0),
    size("M24", 24.0, 26.0, 3.0, 21.5, 4.0),
    size("M27", 27.0, 30.0, 3.0, 23.8, 4.0),
    size("M30", 30.0, 33.0, 3.5, 25.6, 4.0),
];

/// Standard bolt lengths (ISO 4017/4014), mm.
const LENGTHS: [f64; 25] = [
    8.0, 10.0, 12.0, 16.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0, 60.0, 65.0, 70.0, 80.0,
    90.0, 100.0, 110.0, 120.0, 130.0, 140.0, 150.0, 160.0, 180.0,
];

/// `M12`, `m16`, …: one of [`SIZES`].
pub fn parse(s: &str) -> Result<BoltSize, String> {
    let t = s.trim();
    SIZES
        .iter()
        .find(|b| b.name.eq_ignore_ascii_case(t))
        .copied()
        .ok_or_else(|| {
            let names: Vec<&str> = SIZES.iter().map(|b| b.name).collect();
            format!("`{t}` is not a bolt size; give one of {}", names.join(", "))
        })
}

/// The size a steelwork rule of thumb gives for a grip of `grip` mm (Unwin: d = √(5t) − 0.2,
/// d and t in cm), the nearest offered; later reduced if the plate is too small for it.
pub fn for_grip(grip: f64) -> BoltSize {
    let d = 10.0 * ((5.0 * grip / 10.0).sqrt() - 0.2);
    *SIZES
        .iter()
        .min_by(|a, b| (a.d - d).abs().total_cmp(&(b.d - d).abs()))
        .expect("sizes are listed")
}

/// Bolt length to order: the grip, a washer under head and nut, the nut and two threads
/// beyond it, rounded up to a standard length (None past the longest).
pub fn length(bolt: &BoltSize, grip: f64) -> Option<f64> {
    let need = grip + 2.0 * bolt.washer + bolt.nut + 2.0 * bolt.pitch;
    LENGTHS.iter().copied().find(|&l| l >= need - 1e-9)
}

/// Least end and edge distance e1 = e2 = 1.2 d0.
pub fn edge_distance(bolt: &BoltSize) -> f64 {
    1.2 * bolt.hole
}

/// Least pitch p1 = 2.2 d0.
pub fn min_pitch(bolt: &BoltSize) -> f64 {
    2.2 * bolt.hole
}

/// Largest pitch min(14 t, 200 mm) for the thinner ply `t`.
pub fn max_pitch(t: f64) -> f64 {
    (14.0 * t).min(200.0)
}

/// Hole centres along the line through `from` and `to` (the plate's mid-height line) inside the
/// convex counter-clockwise `outline`, every centre at least e = 1.2 d0 from every edge: as
/// many as the largest pitch needs and at least two (one bolt lets the plies turn about it),
/// evenly spread over the part of the line that keeps e. None when no such row meets Table
/// 3.3: too short for two at the least pitch, or too long for the pitch to stay between the
/// least and the largest (a bolt whose 2.2 d0 is over 14 t never does).
pub fn row(
    outline: &[DVec2],
    from: DVec2,
    to: DVec2,
    bolt: &BoltSize,
    thinner: f64,
) -> Option<Vec<DVec2>> {
    row_with_pitch(outline, from, to, bolt, thinner, min_pitch(bolt))
}

/// Least pitch across the force, p2 = 2.4 d0: a row up a short seam plate (its bolts side by
/// side across the member's axis).
pub fn min_pitch_across(bolt: &BoltSize) -> f64 {
    2.4 * bolt.hole
}

/// As [`row`], with the least pitch given.
pub fn row_with_pitch(
    outline: &[DVec2],
    from: DVec2,
    to: DVec2,
    bolt: &BoltSize,
    thinner: f64,
    least: f64,
) -> Option<Vec<DVec2>> {
    let e = edge_distance(bolt);
    let dir = to - from;
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..outline.len() {
        let (p, q) = (outline[k], outline[(k + 1) % outline.len()]);
        let Some(inward) = (q - p).perp().try_normalize() else {
            continue;
        };
        // (from + λ dir − p)·inward ≥ e
        let base = (from - p).dot(inward) - e;
        let rate = dir.dot(inward);
        if rate.abs() < 1e-15 {
            if base < 0.0 {
                return None;
            }
        } else if rate > 0.0 {
            lo = lo.max(-base / rate);
        } else {
            hi = hi.min(-base / rate);
        }
    }
    if lo > hi || !lo.is_finite() || !hi.is_finite() {
        return None;
    }
    let (a, b) = (from + dir * lo, from + dir * hi);
    let span = a.distance(b);
    let most = (span / least).floor() as usize + 1;
    let wanted = ((span / max_pitch(thinner)).ceil() as usize + 1).max(2);
    if wanted > most {
        return None;
    }
    let n = wanted;
    Some(
        (0..n)
            .map(|i| a + (b - a) * (i as f64 / (n - 1) as f64))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(w: f64, h: f64) -> Vec<DVec2> {
        vec![
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w, h),
            DVec2::new(0.0, h),
        ]
    }

    #[test]
    fn holes_keep_the_end_edge_and_pitch_distances() {
        let m12 = parse("m12").expect("listed");
        assert_eq!(m12.hole, 13.0);
        let plate = rect(300.0, 100.0);
        let holes = row(
            &plate,
            DVec2::new(0.0, 50.0),
            DVec2::new(300.0, 50.0),
            &m12,
            3.0,
        )
        .expect("fits");
        // Span 300 − 2·15.6 = 268.8; max pitch 42 → 7 gaps, 8 bolts, pitch 38.4 ≥ 28.6.
        assert_eq!(holes.len(), 8);
        assert!((holes[0].x - 15.6).abs() < 1e-9 && (holes[7].x - 284.4).abs() < 1e-9);
        let pitch = holes[1].x - holes[0].x;
        assert!(pitch >= min_pitch(&m12) && pitch <= max_pitch(3.0));
        // Too short for two at the least pitch: no row (one bolt would let the plies turn).
        let short = rect(40.0, 100.0);
        let one = row(
            &short,
            DVec2::new(0.0, 50.0),
            DVec2::new(40.0, 50.0),
            &m12,
            3.0,
        );
        assert_eq!(one, None);
        // Up the middle of that short plate instead, across the member: M8's p2 = 2.4 × 9 =
        // 21.6 mm is over 14 t = 21 mm on 1.5 mm plies, so no row; two M6 at least 2.4 d0 and
        // at most 14 t apart.
        let (m6, m8) = (parse("M6").expect("listed"), parse("M8").expect("listed"));
        let (lo, hi) = (DVec2::new(20.0, -1e4), DVec2::new(20.0, 1e4));
        assert_eq!(
            row_with_pitch(&short, lo, hi, &m8, 1.5, min_pitch_across(&m8)),
            None
        );
        let up =
            row_with_pitch(&short, lo, hi, &m6, 1.5, min_pitch_across(&m6)).expect("fits across");
        assert!(up.len() >= 2 && up.iter().all(|h| (h.x - 20.0).abs() < 1e-9));
        for w in up.windows(2) {
            let p = w[0].distance(w[1]);
            assert!((2.4 * 6.6 - 1e-9..=21.0 + 1e-9).contains(&p), "{p}");
        }
        // 1.5 mm plies: 14 t = 21 mm is under M12's least pitch 28.6 mm, so no M12 row; M8's
        // 2.2 × 9 = 19.8 mm fits, every pitch within both limits.
        let long = rect(300.0, 100.0);
        let line = (DVec2::new(0.0, 50.0), DVec2::new(300.0, 50.0));
        assert_eq!(row(&long, line.0, line.1, &m12, 1.5), None);
        let m8 = parse("M8").expect("listed");
        let holes = row(&long, line.0, line.1, &m8, 1.5).expect("M8 fits");
        for w in holes.windows(2) {
            let p = w[0].distance(w[1]);
            assert!(
                p >= min_pitch(&m8) - 1e-9 && p <= max_pitch(1.5) + 1e-9,
                "{p}"
            );
        }
        // Too low for e2 on both sides: 2·15.6 > 30.
        let low = rect(300.0, 30.0);
        assert_eq!(
            row(
                &low,
                DVec2::new(0.0, 15.0),
                DVec2::new(300.0, 15.0),
                &m12,
                3.0
            ),
            None
        );
    }

    #[test]
    fn sizes_lengths_and_the_default() {
        assert_eq!(for_grip(3.0).name, "M10");
        assert_eq!(for_grip(6.0).name, "M16");
        // M12 through 6 mm: 6 + 5 + 10.8 + 3.5 = 25.3 → 30.
        assert_eq!(length(&parse("M12").expect("listed"), 6.0), Some(30.0));
        assert!(parse("M13").is_err());
    }
}
