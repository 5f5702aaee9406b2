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
    /// Plain washer outside diameter (ISO 7089).
    pub washer_od: f64,
    /// Tensile stress area A_s (ISO 898-1), mm².
    pub area: f64,
    /// Width across flats of the nut and head (ISO 4032, ISO 4017).
    pub across_flats: f64,
    /// Head height k (ISO 4017).
    pub head: f64,
}

/// (name, d, d0, thread pitch, nut m, washer h, washer OD, A_s, across flats s, head k).
type Row = (&'static str, f64, f64, f64, f64, f64, f64, f64, f64, f64);

const fn size(r: Row) -> BoltSize {
    BoltSize {
        name: r.0,
        d: r.1,
        hole: r.2,
        pitch: r.3,
        nut: r.4,
        washer: r.5,
        washer_od: r.6,
        area: r.7,
        across_flats: r.8,
        head: r.9,
    }
}

/// The sizes offered, smallest first.
pub const SIZES: [BoltSize; 10] = [
    size(("M6", 6.0, 6.6, 1.0, 5.2, 1.6, 12.0, 20.1, 10.0, 4.0)),
    size(("M8", 8.0, 9.0, 1.25, 6.8, 1.6, 16.0, 36.6, 13.0, 5.3)),
    size(("M10", 10.0, 11.0, 1.5, 8.4, 2.0, 20.0, 58.0, 16.0, 6.4)),
    size(("M12", 12.0, 13.0, 1.75, 10.8, 2.5, 24.0, 84.3, 18.0, 7.5)),
    size(("M16", 16.0, 18.0, 2.0, 14.8, 3.0, 30.0, 157.0, 24.0, 10.0)),
    size(("M20", 20.0, 22.0, 2.5, 18.0, 3.0, 37.0, 245.0, 30.0, 12.5)),
    size(("M22", 22.0, 24.0, 2.5, 19.4, 3.0, 39.0, 303.0, 34.0, 14.0)),
    size(("M24", 24.0, 26.0, 3.0, 21.5, 4.0, 44.0, 353.0, 36.0, 15.0)),
    size(("M27", 27.0, 30.0, 3.0, 23.8, 4.0, 50.0, 459.0, 41.0, 17.0)),
    size(("M30", 30.0, 33.0, 3.5, 25.6, 4.0, 56.0, 561.0, 46.0, 18.7)),
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

/// The steel of one bolt set, mm³: the shank (a cylinder of d, `length` long), the head and
/// the nut (hexagon prisms across flats s, k and m high, the nut less its hole of d) and two
/// washers (rings from d0 to their outside diameter). Nominal sizes: threads, chamfers and
/// washer faces left out.
pub fn set_volume(bolt: &BoltSize, length: f64) -> f64 {
    use std::f64::consts::FRAC_PI_4;
    let hexagon = 0.5 * 3f64.sqrt() * bolt.across_flats * bolt.across_flats;
    let shank = FRAC_PI_4 * bolt.d * bolt.d;
    let washer = FRAC_PI_4 * (bolt.washer_od * bolt.washer_od - bolt.hole * bolt.hole);
    shank * length + hexagon * bolt.head + (hexagon - shank) * bolt.nut + 2.0 * washer * bolt.washer
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
/// evenly spread over the part of the line that keeps e, or where that would bring them under
/// the least pitch, one fewer at the largest pitch, centred on it. None when no row meets Table
/// 3.3: too short for two at the least pitch, or a bolt whose 2.2 d0 is over 14 t.
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
    denser_rows(outline, from, to, bolt, thinner, least).next()
}

/// The rows [`row_with_pitch`] allows, from the fewest bolts to the most (each over the whole
/// span, down to the least pitch): more bolts share a seam's forces.
pub fn denser_rows(
    outline: &[DVec2],
    from: DVec2,
    to: DVec2,
    bolt: &BoltSize,
    thinner: f64,
    least: f64,
) -> impl Iterator<Item = Vec<DVec2>> {
    let found = chord(outline, from, to, edge_distance(bolt))
        .filter(|(_, _, span)| *span >= least && least <= max_pitch(thinner));
    let largest = max_pitch(thinner);
    found.into_iter().flat_map(move |(a, b, span)| {
        // Over the whole span at a pitch within the limits; where the span falls between two
        // counts (the even pitch of one gap more under the least), one gap fewer at the
        // largest pitch, centred. Then more gaps while the pitch keeps the least.
        let gaps = ((span / largest).ceil() as usize).max(1);
        let first = if span / gaps as f64 >= least {
            gaps
        } else {
            gaps - 1
        };
        let most = ((span / least + 1e-9).floor() as usize).max(first);
        let along = (b - a) / span;
        (first..=most).map(move |g| {
            let pitch = (span / g as f64).min(largest);
            let start = a + along * (0.5 * (span - pitch * g as f64));
            (0..=g)
                .map(|i| start + along * (pitch * i as f64))
                .collect()
        })
    })
}

/// The part of the line through `from` and `to` whose points stay `inset` or more inside the
/// convex counter-clockwise `outline`: its ends and length (None where there is none).
pub fn chord(outline: &[DVec2], from: DVec2, to: DVec2, inset: f64) -> Option<(DVec2, DVec2, f64)> {
    let dir = to - from;
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..outline.len() {
        let (p, q) = (outline[k], outline[(k + 1) % outline.len()]);
        let Some(inward) = (q - p).perp().try_normalize() else {
            continue;
        };
        // (from + λ dir − p)·inward ≥ inset
        let base = (from - p).dot(inward) - inset;
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
    Some((a, b, a.distance(b)))
}

/// A bolt's property class: 8.8 with carbon steel plates, A4-70 with stainless.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoltGrade {
    pub name: &'static str,
    /// Ultimate strength f_ub, MPa.
    pub fub: f64,
    /// α_v of the shear resistance, the shear plane through the thread (Table 3.4).
    pub alpha_v: f64,
}

/// 8.8 (f_ub 800 MPa, α_v 0.6) for carbon steel; A4-70 (f_ub 700 MPa, α_v 0.5 as EN
/// 1993-1-4 §6.2 takes for stainless bolts) for stainless.
pub fn grade(stainless: bool) -> BoltGrade {
    if stainless {
        BoltGrade {
            name: "A4-70",
            fub: 700.0,
            alpha_v: 0.5,
        }
    } else {
        BoltGrade {
            name: "8.8",
            fub: 800.0,
            alpha_v: 0.6,
        }
    }
}

/// How the bolts are installed and what the check takes them as.
pub const PRELOAD: &str = "non-preloaded, snug-tight: category A (bearing) in shear, D in \
                           tension (EN 1993-1-8 §3.4)";

/// What the plies' bolts must carry: the seam member's section forces in the plate's frame
/// [N along x, V along y, V_z across, T about x, M_y about y, M_z about z] (N, N·mm), each the
/// largest magnitude at either end over the ultimate combinations (an envelope: components
/// of different combinations together, on the safe side).
pub type SeamForces = [f64; 6];

/// The plies' steel for bearing and punching: f_u (for stainless EN 1993-1-4 §6.2's reduced
/// f_u,red = 0.5 f_y + 0.6 f_u ≤ f_u, given here), MPa, and γ_M2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlySteel {
    pub fu: f64,
    pub gamma_m2: f64,
}

impl PlySteel {
    /// For plies of `material`: stainless on f_u,red (EN 1993-1-4 §6.2).
    pub fn of(material: &crate::analyze::material::Material) -> PlySteel {
        PlySteel {
            fu: if material.is_stainless() {
                (0.5 * material.fy + 0.6 * material.fu).min(material.fu)
            } else {
                material.fu
            },
            gamma_m2: material.gamma_m2,
        }
    }
}

/// A bolt row's checks by EN 1993-1-8 Table 3.4 on its most loaded bolt: utilisations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoltChecks {
    /// F_v,Ed / F_v,Rd (one shear plane, through the thread).
    pub shear: f64,
    /// F_b,Ed / F_b,Rd on the thinner ply.
    pub bearing: f64,
    /// F_t,Ed / F_t,Rd.
    pub tension: f64,
    /// F_t,Ed / B_p,Rd (punching through the thinner ply).
    pub punching: f64,
    /// F_v,Ed / F_v,Rd + F_t,Ed / (1.4 F_t,Rd).
    pub combined: f64,
}

/// The names of [`BoltChecks`]' fields, in order.
pub const BOLT_CHECKS: [&str; 5] = [
    "shear",
    "bearing",
    "tension",
    "punching",
    "shear and tension",
];

impl BoltChecks {
    pub fn values(&self) -> [f64; 5] {
        [
            self.shear,
            self.bearing,
            self.tension,
            self.punching,
            self.combined,
        ]
    }

    /// The largest utilisation and its check's name.
    pub fn governing(&self) -> (f64, &'static str) {
        self.values()
            .into_iter()
            .zip(BOLT_CHECKS)
            .fold((0.0, BOLT_CHECKS[0]), |best, (u, n)| {
                if u > best.0 {
                    (u, n)
                } else {
                    best
                }
            })
    }
}

/// The checks of `bolt`s of `grade` at `holes` through two plies, the thinner `thinner` mm,
/// overlapping over the convex `outline` (plate frame: x along the member), under `forces`.
///
/// Shear: an elastic bolt group about the holes' centroid, N and V shared equally and M_z as
/// forces ⊥ each bolt's arm, the worst bolt with every part's magnitude adding. Tension: V_z
/// shared equally, and M_y and T each as a couple of bolt tension and contact pressure about
/// the overlap's edge on the far side (bolt forces ∝ their distance from it, the worse edge),
/// added on the worst bolt. Bearing (Table 3.4): k1 = min(2.8 e2/d0 − 1.7, 2.5), α_b =
/// min(α_d, f_ub/f_u, 1), α_d = min(e1/3d0, p1/3d0 − 1/4), with e1 = e2 the least distance of
/// a hole to the overlap's edge and p1 the least pitch (the force's direction taken as the
/// worst). Punching with d_m the mean of the nut's across-flats and across-corners.
pub fn check(
    bolt: &BoltSize,
    grade: &BoltGrade,
    holes: &[DVec2],
    outline: &[DVec2],
    thinner: f64,
    steel: &PlySteel,
    forces: &SeamForces,
) -> BoltChecks {
    let n = holes.len().max(1) as f64;
    let [fx, fy, fz, mx, my, mz] = forces.map(f64::abs);
    let centre = holes.iter().copied().sum::<DVec2>() / n;
    let polar: f64 = holes.iter().map(|h| (*h - centre).length_squared()).sum();
    let shear = holes
        .iter()
        .map(|h| {
            let r = (*h - centre).abs();
            let twist = if polar > 0.0 { mz / polar } else { 0.0 };
            (fx / n + twist * r.y).hypot(fy / n + twist * r.x)
        })
        .fold(0.0f64, f64::max);
    // Tension: a moment about an axis in the plate, pivoting on the overlap's far edge.
    let couple = |moment: f64, across: fn(DVec2) -> f64| -> f64 {
        if moment == 0.0 {
            return 0.0;
        }
        let (lo, hi) = outline
            .iter()
            .map(|p| across(*p))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        [lo, hi]
            .into_iter()
            .map(|edge| {
                let arms: Vec<f64> = holes.iter().map(|h| (across(*h) - edge).abs()).collect();
                let sum: f64 = arms.iter().map(|a| a * a).sum();
                let far = arms.iter().copied().fold(0.0, f64::max);
                if sum > 0.0 {
                    moment * far / sum
                } else {
                    f64::INFINITY
                }
            })
            .fold(0.0, f64::max)
    };
    let tension = fz / n + couple(my, |p| p.x) + couple(mx, |p| p.y);
    // Resistances, N.
    let g = steel.gamma_m2;
    let f_v = grade.alpha_v * grade.fub * bolt.area / g;
    let f_t = 0.9 * grade.fub * bolt.area / g;
    let d0 = bolt.hole;
    let edge = holes
        .iter()
        .map(|h| {
            (0..outline.len())
                .map(|k| {
                    let (p, q) = (outline[k], outline[(k + 1) % outline.len()]);
                    (q - p).normalize_or_zero().perp_dot(*h - p)
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(f64::INFINITY, f64::min);
    let pitch = holes
        .windows(2)
        .map(|w| w[0].distance(w[1]))
        .fold(f64::INFINITY, f64::min);
    let alpha_d = (edge / (3.0 * d0)).min(pitch / (3.0 * d0) - 0.25);
    let alpha_b = alpha_d.min(grade.fub / steel.fu).min(1.0);
    let k1 = (2.8 * edge / d0 - 1.7).min(2.5);
    let f_b = (k1 * alpha_b * steel.fu * bolt.d * thinner / g).max(0.0);
    let dm = 0.5 * bolt.across_flats * (1.0 + 2.0 / 3f64.sqrt());
    let b_p = 0.6 * std::f64::consts::PI * dm * thinner * steel.fu / g;
    let over = |f: f64, r: f64| if r > 0.0 { f / r } else { f64::INFINITY };
    BoltChecks {
        shear: over(shear, f_v),
        bearing: over(shear, f_b),
        tension: over(tension, f_t),
        punching: over(tension, b_p),
        combined: over(shear, f_v) + over(tension, 1.4 * f_t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bolt_set_weighs_what_the_catalogues_say() {
        // M12 × 40 with nut and two washers in steel: about 77 g by the makers' tables
        // (bolt ~48 g, nut ~17 g, washers ~6 g each); nominal prisms keep within 5 %.
        let m12 = parse("M12").unwrap();
        let grams = set_volume(&m12, 40.0) * 7.85e-3;
        assert!((grams - 77.0).abs() < 0.05 * 77.0, "{grams} g");
        // A longer bolt adds only shank.
        let more = set_volume(&m12, 50.0) - set_volume(&m12, 40.0);
        assert!((more - 10.0 * std::f64::consts::FRAC_PI_4 * 144.0).abs() < 1e-9);
    }

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
        // M6 on 1.5 mm plies, a span of 41 − 2 × 7.92 = 25.16 mm: two gaps would be 12.6 mm,
        // under 2.2 d0 = 14.52; so one gap at the largest pitch, 21 mm, centred.
        let holes = row(
            &rect(41.0, 100.0),
            DVec2::new(0.0, 50.0),
            DVec2::new(41.0, 50.0),
            &m6,
            1.5,
        )
        .expect("one gap fits");
        assert_eq!(holes.len(), 2);
        assert!((holes[1].x - holes[0].x - 21.0).abs() < 1e-9);
        assert!((holes[0].x + holes[1].x - 41.0).abs() < 1e-9, "centred");
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
