//! Tags etched on parts: our own single-stroke font (0-9, A-Z, '-', '.', '/') on a segment display's
//! grid, and the largest tag that fits inside a convex outline away from its edges.
//!
//! A glyph lives in a cell 1 wide and 2 tall (y up) and is a set of straight strokes between
//! grid points: the box's four sides split at mid-height and mid-width, the centre lines, and
//! diagonals to the centre. Characters advance 1.5 cells; a tag of n characters is 1.5n − 0.5
//! cells wide. Stroke lines cut nothing: a laser or plasma marks them on the ETCH layer.

use glam::DVec2;

use crate::geom::clip_convex;

type Seg = ((f64, f64), (f64, f64));

// The segments, by name.
const T1: Seg = ((0.0, 2.0), (0.5, 2.0));
const T2: Seg = ((0.5, 2.0), (1.0, 2.0));
const UR: Seg = ((1.0, 2.0), (1.0, 1.0));
const LR: Seg = ((1.0, 1.0), (1.0, 0.0));
const B2: Seg = ((1.0, 0.0), (0.5, 0.0));
const B1: Seg = ((0.5, 0.0), (0.0, 0.0));
const LL: Seg = ((0.0, 0.0), (0.0, 1.0));
const UL: Seg = ((0.0, 1.0), (0.0, 2.0));
const M1: Seg = ((0.0, 1.0), (0.5, 1.0));
const M2: Seg = ((0.5, 1.0), (1.0, 1.0));
const UC: Seg = ((0.5, 2.0), (0.5, 1.0));
const LC: Seg = ((0.5, 1.0), (0.5, 0.0));
const DUL: Seg = ((0.0, 2.0), (0.5, 1.0));
const DUR: Seg = ((1.0, 2.0), (0.5, 1.0));
const DLL: Seg = ((0.0, 0.0), (0.5, 1.0));
const DLR: Seg = ((1.0, 0.0), (0.5, 1.0));
const VL: Seg = ((0.0, 1.0), (0.5, 0.0));
const VR: Seg = ((1.0, 1.0), (0.5, 0.0));

/// The strokes of one character, or None when the font has no glyph for it.
pub fn glyph(c: char) -> Option<&'static [Seg]> {
    Some(match c.to_ascii_uppercase() {
        '0' => &[T1, T2, UR, LR, B2, B1, LL, UL, DUR, DLL],
        '1' => &[UR, LR],
        '2' => &[T1, T2, UR, M2, M1, LL, B1, B2],
        '3' => &[T1, T2, UR, M1, M2, LR, B2, B1],
        '4' => &[UL, M1, M2, UR, LR],
        '5' => &[T2, T1, UL, M1, M2, LR, B2, B1],
        '6' => &[T2, T1, UL, LL, B1, B2, LR, M2, M1],
        '7' => &[T1, T2, UR, LR],
        '8' => &[T1, T2, UR, LR, B2, B1, LL, UL, M1, M2],
        '9' => &[M2, M1, UL, T1, T2, UR, LR, B2, B1],
        '-' => &[M1, M2],
        '.' => &[((0.5, 0.0), (0.5, 0.25))],
        '/' => &[((0.0, 0.0), (1.0, 2.0))],
        'A' => &[LL, UL, T1, T2, UR, LR, M1, M2],
        'B' => &[T1, T2, UR, M2, LR, B2, B1, UC, LC],
        'C' => &[T2, T1, UL, LL, B1, B2],
        'D' => &[T1, T2, UR, LR, B2, B1, UC, LC],
        'E' => &[T2, T1, UL, LL, B1, B2, M1],
        'F' => &[T2, T1, UL, LL, M1],
        'G' => &[T2, T1, UL, LL, B1, B2, LR, M2],
        'H' => &[UL, LL, UR, LR, M1, M2],
        'I' => &[T1, T2, B1, B2, UC, LC],
        'J' => &[UR, LR, B2, B1, LL],
        'K' => &[UL, LL, M1, DUR, DLR],
        'L' => &[UL, LL, B1, B2],
        'M' => &[LL, UL, DUL, DUR, UR, LR],
        'N' => &[LL, UL, DUL, DLR, LR, UR],
        'O' => &[T1, T2, UR, LR, B2, B1, LL, UL],
        'P' => &[LL, UL, T1, T2, UR, M2, M1],
        'Q' => &[T1, T2, UR, LR, B2, B1, LL, UL, DLR],
        'R' => &[LL, UL, T1, T2, UR, M2, M1, DLR],
        'S' => &[T2, T1, DUL, M2, LR, B2, B1],
        'T' => &[T1, T2, UC, LC],
        'U' => &[UL, LL, B1, B2, LR, UR],
        'V' => &[UL, VL, VR, UR],
        'W' => &[UL, LL, DLL, DLR, LR, UR],
        'X' => &[DUL, DUR, DLL, DLR],
        'Y' => &[DUL, DUR, LC],
        'Z' => &[T1, T2, DUR, DLL, B1, B2],
        _ => return None,
    })
}

/// Width of a tag of `n` characters in cells (height 2).
pub fn text_width(n: usize) -> f64 {
    if n == 0 {
        0.0
    } else {
        1.5 * n as f64 - 0.5
    }
}

/// The strokes of `text` with its box's lower-left corner at `origin`, characters `height`
/// tall. Characters without a glyph are left as spaces.
pub fn strokes(text: &str, origin: DVec2, height: f64) -> Vec<[DVec2; 2]> {
    let unit = height / 2.0;
    let mut out = Vec::new();
    for (k, c) in text.chars().enumerate() {
        let x0 = origin.x + 1.5 * unit * k as f64;
        for &((ax, ay), (bx, by)) in glyph(c).unwrap_or(&[]) {
            out.push([
                DVec2::new(x0 + ax * unit, origin.y + ay * unit),
                DVec2::new(x0 + bx * unit, origin.y + by * unit),
            ]);
        }
    }
    out
}

/// Tags stay this far inside a plate's outline, mm.
pub const TAG_MARGIN: f64 = 5.0;
/// Tag character heights tried, mm.
pub const TAG_HEIGHT: (f64, f64) = (3.0, 25.0);

/// The largest character height, up to `max_height`, at which `text` (left to right along +x)
/// fits inside the convex counter-clockwise `outline` with `margin` to every edge, centred on
/// the outline's centroid; with the box's lower-left corner. None when not even
/// `min_height` fits.
pub fn fit(
    text: &str,
    outline: &[DVec2],
    margin: f64,
    min_height: f64,
    max_height: f64,
) -> Option<(f64, DVec2)> {
    fit_clear(text, outline, &[], margin, min_height, max_height)
}

/// What is etched on a part, in drawing coordinates.
pub struct Marks {
    /// The tag's character height, None when the part is too small for it.
    pub tag_height: Option<f64>,
    /// Strokes chained into polylines: the tag, then the arrow to the outer edge, then the
    /// node at each end.
    pub etch: Vec<Vec<DVec2>>,
}

/// A part's marks: its tag upright in the drawing (read left to right along +x whatever the
/// part's rotation), followed by an arrow pointing to the part's outer edge (`out`, its
/// frame's +y in the drawing), and `N<node>` at each end where there is room (so a welder
/// knows which end meets which node). Holes are kept clear by the margin.
///
/// `outline` is counter-clockwise in the plate's frame (x from its first node to its second);
/// `to_drawing` places plate points in the drawing by a rotation and a shift.
pub fn part_marks(
    id: &str,
    outline: &[DVec2],
    holes: &[(DVec2, f64)],
    nodes: [u32; 2],
    to_drawing: &dyn Fn(DVec2) -> DVec2,
) -> Marks {
    let lo = outline.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let hi = outline
        .iter()
        .map(|p| p.x)
        .fold(f64::NEG_INFINITY, f64::max);
    let quarter = 0.25 * (hi - lo);
    let band = |a: f64, b: f64| -> Vec<DVec2> {
        let p = clip_convex(outline, DVec2::new(a, 0.0), DVec2::X);
        clip_convex(&p, DVec2::new(b, 0.0), DVec2::NEG_X)
            .iter()
            .map(|q| to_drawing(*q))
            .collect()
    };
    let keep: Vec<(DVec2, f64)> = holes.iter().map(|(c, r)| (to_drawing(*c), *r)).collect();
    let out = (to_drawing(DVec2::Y) - to_drawing(DVec2::ZERO)).normalize();
    // The tag and two cells for the arrow.
    let text = format!("{id}  ");
    let middle = band(lo + quarter, hi - quarter);
    let whole: Vec<DVec2> = outline.iter().map(|q| to_drawing(*q)).collect();
    let mut segments = Vec::new();
    let mut ends_free = true;
    let mut placed = None;
    if middle.len() >= 3 {
        placed = fit_clear(
            &text,
            &middle,
            &keep,
            TAG_MARGIN,
            TAG_HEIGHT.0,
            TAG_HEIGHT.1,
        );
    }
    if placed.is_none() {
        placed = fit_clear(&text, &whole, &keep, TAG_MARGIN, TAG_HEIGHT.0, TAG_HEIGHT.1);
        ends_free = false;
    }
    if placed.is_none() {
        // Small parts: the tag alone.
        let tag = fit_clear(id, &whole, &keep, TAG_MARGIN, TAG_HEIGHT.0, TAG_HEIGHT.1);
        if let Some((h, o)) = tag {
            segments.extend(strokes(id, o, h));
        }
        return Marks {
            tag_height: tag.map(|(h, _)| h),
            etch: crate::fabricate::cutsheet::chain(&segments),
        };
    }
    if let Some((h, o)) = placed {
        segments.extend(strokes(id, o, h));
        // The arrow in the last cell: a stem and a head, pointing along `out`.
        let unit = h / 2.0;
        let centre = o + DVec2::new(
            1.5 * unit * (text.chars().count() - 1) as f64 + 0.5 * unit,
            h / 2.0,
        );
        let (tip, tail) = (centre + out * (0.45 * h), centre - out * (0.45 * h));
        let side = out.perp() * (0.25 * h);
        let back = tip - out * (0.3 * h);
        segments.extend([[tail, tip], [back + side, tip], [back - side, tip]]);
    }
    if ends_free && placed.is_some() {
        for (end, region) in [(0, band(lo, lo + quarter)), (1, band(hi - quarter, hi))] {
            if region.len() < 3 {
                continue;
            }
            let label = format!("N{}", nodes[end]);
            let height = placed.map(|(h, _)| 0.6 * h).unwrap_or(TAG_HEIGHT.0);
            if let Some((h, o)) = fit_clear(
                &label,
                &region,
                &keep,
                TAG_MARGIN,
                TAG_HEIGHT.0,
                height.max(TAG_HEIGHT.0),
            ) {
                segments.extend(strokes(&label, o, h));
            }
        }
    }
    Marks {
        tag_height: placed.map(|(h, _)| h),
        etch: crate::fabricate::cutsheet::chain(&segments),
    }
}

/// As [`fit`], but also `margin` clear of round holes (centre, radius), trying the centroid
/// and the points between neighbouring holes as the tag's centre; the largest height wins.
pub fn fit_clear(
    text: &str,
    outline: &[DVec2],
    holes: &[(DVec2, f64)],
    margin: f64,
    min_height: f64,
    max_height: f64,
) -> Option<(f64, DVec2)> {
    let n = text.chars().count();
    let centroid = outline.iter().copied().sum::<DVec2>() / outline.len() as f64;
    let mut centres = vec![centroid];
    centres.extend(holes.windows(2).map(|w| 0.5 * (w[0].0 + w[1].0)));
    // Beside a row of holes: off the centroid across the row, either side.
    if let (Some(first), Some(last)) = (holes.first(), holes.last()) {
        let along = (last.0 - first.0).try_normalize().unwrap_or(DVec2::X);
        let across = along.perp();
        let (lo, hi) = outline
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                let d = (*p - centroid).dot(across);
                (l.min(d), h.max(d))
            });
        for f in [0.3, 0.25, 0.2] {
            centres.push(centroid + across * (f * (hi - lo)));
            centres.push(centroid - across * (f * (hi - lo)));
        }
    }
    let mut best: Option<(f64, DVec2)> = None;
    for centre in centres {
        let place = |h: f64| centre - DVec2::new(text_width(n) * h / 2.0, h) / 2.0;
        let fits = |h: f64| {
            let o = place(h);
            let size = DVec2::new(text_width(n) * h / 2.0, h);
            let corners = [
                o,
                o + DVec2::new(size.x, 0.0),
                o + size,
                o + DVec2::new(0.0, size.y),
            ];
            corners.iter().all(|&c| inside_by(outline, c, margin))
                && holes.iter().all(|(c, r)| {
                    let nearest = c.clamp(o, o + size);
                    nearest.distance(*c) >= r + margin
                })
        };
        if !fits(min_height) {
            continue;
        }
        let (mut lo, mut hi) = (min_height, max_height);
        let h = if fits(hi) {
            hi
        } else {
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if fits(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        if best.is_none_or(|b| h > b.0 + 1e-9) {
            best = Some((h, place(h)));
        }
    }
    best
}

/// Whether `p` lies inside the convex counter-clockwise polygon at least `margin` from every
/// edge.
fn inside_by(poly: &[DVec2], p: DVec2, margin: f64) -> bool {
    (0..poly.len()).all(|k| {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let e = (b - a).normalize();
        e.perp_dot(p - a) >= margin
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_tag_character_has_a_glyph_on_the_grid() {
        for c in "0123456789-ABCDEFGHIJKLMNOPQRSTUVWXYZ".chars() {
            let g = glyph(c).unwrap_or_else(|| panic!("no glyph for {c}"));
            assert!(!g.is_empty());
            for &((ax, ay), (bx, by)) in g {
                for v in [ax, bx] {
                    assert!((0.0..=1.0).contains(&v));
                }
                for v in [ay, by] {
                    assert!((0.0..=2.0).contains(&v));
                }
            }
        }
        // No two characters look the same.
        let chars: Vec<char> = "0123456789-ABCDEFGHIJKLMNOPQRSTUVWXYZ".chars().collect();
        for (i, a) in chars.iter().enumerate() {
            for b in &chars[i + 1..] {
                let key = |c: &char| {
                    let mut s: Vec<String> = glyph(*c)
                        .unwrap_or(&[])
                        .iter()
                        .map(|s| format!("{s:?}"))
                        .collect();
                    s.sort();
                    s
                };
                assert_ne!(key(a), key(b), "{a} and {b} share their strokes");
            }
        }
    }

    #[test]
    fn a_tag_fits_a_rectangle_with_its_margin() {
        let rect = [
            DVec2::new(0.0, 0.0),
            DVec2::new(200.0, 0.0),
            DVec2::new(200.0, 50.0),
            DVec2::new(0.0, 50.0),
        ];
        let (h, o) = fit("3-017", &rect, 5.0, 2.0, 100.0).expect("fits");
        // Height-bound: 50 − 2·5 = 40.
        assert!((h - 40.0).abs() < 1e-6, "{h}");
        let s = strokes("3-017", o, h);
        for [a, b] in s {
            for p in [a, b] {
                assert!(p.y >= 5.0 - 1e-9 && p.y <= 45.0 + 1e-9 && p.x >= 5.0 && p.x <= 195.0);
            }
        }
        assert!(fit("3-017", &rect, 24.5, 2.0, 100.0).is_none());
    }
}
