//! Tags etched on parts: our own single-stroke font (0-9, A-Z, '-') on a segment display's
//! grid, and the largest tag that fits inside a convex outline away from its edges.
//!
//! A glyph lives in a cell 1 wide and 2 tall (y up) and is a set of straight strokes between
//! grid points: the box's four sides split at mid-height and mid-width, the centre lines, and
//! diagonals to the centre. Characters advance 1.5 cells; a tag of n characters is 1.5n − 0.5
//! cells wide. Stroke lines cut nothing: a laser or plasma marks them on the ETCH layer.

use glam::DVec2;

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

/// A plate's etched tag in the plate's frame: character height and strokes, or None when the
/// plate is too small for the smallest tag.
pub fn etch(id: &str, outline: &[DVec2]) -> Option<(f64, Vec<[DVec2; 2]>)> {
    let (h, origin) = fit(id, outline, TAG_MARGIN, TAG_HEIGHT.0, TAG_HEIGHT.1)?;
    Some((h, strokes(id, origin, h)))
}

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
    let n = text.chars().count();
    let centre = outline.iter().copied().sum::<DVec2>() / outline.len() as f64;
    let place = |h: f64| {
        let (w, hh) = (text_width(n) * h / 2.0, h);
        centre - DVec2::new(w, hh) / 2.0
    };
    let fits = |h: f64| {
        let o = place(h);
        let w = text_width(n) * h / 2.0;
        let corners = [
            o,
            o + DVec2::new(w, 0.0),
            o + DVec2::new(w, h),
            o + DVec2::new(0.0, h),
        ];
        corners.iter().all(|&c| inside_by(outline, c, margin))
    };
    if !fits(min_height) {
        return None;
    }
    let (mut lo, mut hi) = (min_height, max_height);
    if fits(hi) {
        return Some((hi, place(hi)));
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some((lo, place(lo)))
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
