//! The leaf blade: a simple polygon in the XY plane (mm), convex or concave, with the built-in
//! shapes the venation command offers. The constructor rejects what growth cannot use.

use glam::DVec2;

/// Length of the built-in shapes from base to tip, in mm.
pub const SHAPE_LENGTH: f64 = 100.0;

/// Vertices per built-in outline.
const SHAPE_VERTICES: usize = 160;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    Ovate,
    Lanceolate,
    Cordate,
    Circle,
    Rect,
}

impl Shape {
    pub const ALL: [Shape; 5] = [
        Shape::Ovate,
        Shape::Lanceolate,
        Shape::Cordate,
        Shape::Circle,
        Shape::Rect,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Shape::Ovate => "ovate",
            Shape::Lanceolate => "lanceolate",
            Shape::Cordate => "cordate",
            Shape::Circle => "circle",
            Shape::Rect => "rect",
        }
    }
}

/// Why an outline cannot be a leaf blade.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum OutlineError {
    #[error("outline has {0} points; a blade needs at least 3")]
    TooFewPoints(usize),
    #[error("outline point {0} is not finite")]
    NonFinite(usize),
    #[error("outline edges {0} and {1} cross: the outline must not intersect itself")]
    SelfIntersecting(usize, usize),
    #[error("outline encloses no area")]
    Degenerate,
    #[error("outline spans {0:e} mm, more than the {MAX_EXTENT:e} mm a blade may (wrong units?)")]
    TooLarge(f64),
}

/// The largest extent of a blade outline: 10 km. Past that, coordinates are surely not
/// millimetres, and grids over the blade would not fit in memory.
pub const MAX_EXTENT: f64 = 1e7;

/// A simple polygon, counter-clockwise, without a repeated closing point.
#[derive(Clone, Debug, PartialEq)]
pub struct Outline {
    points: Vec<DVec2>,
    /// Point-in-polygon index: the edges crossing each horizontal band of the bounding box.
    bands: Bands,
}

/// Horizontal bands over the outline's height, each listing the edges whose y-range meets it,
/// so a containment test looks at a few edges instead of all.
#[derive(Clone, Debug, PartialEq)]
struct Bands {
    lo: f64,
    height: f64,
    /// Edge i runs from point i to point i + 1; band b holds `edges[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    edges: Vec<u32>,
}

impl Bands {
    fn new(points: &[DVec2]) -> Bands {
        let n = points.len();
        let lo = points.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        let hi = points.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
        let count = n.clamp(1, 4096);
        let height = ((hi - lo) / count as f64).max(f64::MIN_POSITIVE);
        let band = |y: f64| (((y - lo) / height) as usize).min(count - 1);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); count];
        for i in 0..n {
            let (a, b) = (points[i].y, points[(i + 1) % n].y);
            for l in lists
                .iter_mut()
                .take(band(a.max(b)) + 1)
                .skip(band(a.min(b)))
            {
                l.push(i as u32);
            }
        }
        let mut start = Vec::with_capacity(count + 1);
        let mut edges = Vec::new();
        for l in lists {
            start.push(edges.len() as u32);
            edges.extend(l);
        }
        start.push(edges.len() as u32);
        Bands {
            lo,
            height,
            start,
            edges,
        }
    }

    /// The band holding height y, clamped to the outline's height.
    fn band(&self, y: f64) -> usize {
        let count = self.start.len() - 1;
        (((y - self.lo) / self.height).max(0.0) as usize).min(count - 1)
    }

    fn edges_of(&self, band: usize) -> &[u32] {
        &self.edges[self.start[band] as usize..self.start[band + 1] as usize]
    }

    /// The edges that may cross the horizontal line at y, or None outside the outline's height.
    fn at(&self, y: f64) -> Option<&[u32]> {
        let count = self.start.len() - 1;
        let f = (y - self.lo) / self.height;
        if !(f >= 0.0 && f <= count as f64) {
            return None;
        }
        let b = (f as usize).min(count - 1);
        Some(&self.edges[self.start[b] as usize..self.start[b + 1] as usize])
    }
}

impl Outline {
    /// Validates and normalises: drops a repeated closing point, rejects fewer than 3 points,
    /// non-finite or self-intersecting outlines, and makes the winding counter-clockwise.
    pub fn new(mut points: Vec<DVec2>) -> Result<Self, OutlineError> {
        if points.len() > 1 && points.first() == points.last() {
            points.pop();
        }
        if let Some(i) = points.iter().position(|p| !p.is_finite()) {
            return Err(OutlineError::NonFinite(i));
        }
        points.dedup();
        if points.len() < 3 {
            return Err(OutlineError::TooFewPoints(points.len()));
        }
        let (lo, hi) = points.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let extent = (hi - lo).max_element();
        if extent.is_nan() || extent > MAX_EXTENT {
            return Err(OutlineError::TooLarge(extent));
        }
        let n = points.len();
        for i in 0..n {
            for j in i + 1..n {
                if j == i + 1 || (i == 0 && j == n - 1) {
                    continue; // neighbours share a corner
                }
                if crate::geom::segments_touch(
                    points[i],
                    points[(i + 1) % n],
                    points[j],
                    points[(j + 1) % n],
                ) {
                    return Err(OutlineError::SelfIntersecting(i, j));
                }
            }
        }
        let bands = Bands::new(&points);
        let mut outline = Outline { points, bands };
        let area = outline.signed_area();
        if area.is_nan() || area.abs() < 1e-12 {
            return Err(OutlineError::Degenerate);
        }
        if area < 0.0 {
            outline.points.reverse();
            outline.bands = Bands::new(&outline.points);
        }
        Ok(outline)
    }

    /// A built-in blade, `SHAPE_LENGTH` mm from its base at the origin to its tip on +Y.
    pub fn shape(shape: Shape) -> Self {
        let l = SHAPE_LENGTH;
        let n = SHAPE_VERTICES;
        let pts: Vec<DVec2> = match shape {
            // Half-width profiles along the midrib; right side up, left side down.
            Shape::Ovate | Shape::Lanceolate => {
                let (width, bias) = match shape {
                    Shape::Ovate => (0.36 * l, 0.45),
                    _ => (0.13 * l, 0.25),
                };
                let half = n / 2;
                let profile = |t: f64| {
                    let s = (std::f64::consts::PI * t).sin().max(0.0);
                    width * s.powf(0.85) * (1.0 + bias * (0.5 - t))
                };
                let mut v = Vec::with_capacity(n);
                for k in 0..=half {
                    let t = k as f64 / half as f64;
                    v.push(DVec2::new(profile(t), l * t));
                }
                for k in (1..half).rev() {
                    let t = k as f64 / half as f64;
                    v.push(DVec2::new(-profile(t), l * t));
                }
                v
            }
            Shape::Cordate => {
                // The classic heart curve, turned so the notch is the base and scaled to l.
                let raw: Vec<DVec2> = (0..n)
                    .map(|k| {
                        let th = std::f64::consts::TAU * k as f64 / n as f64;
                        let x = 16.0 * th.sin().powi(3);
                        let y = 13.0 * th.cos()
                            - 5.0 * (2.0 * th).cos()
                            - 2.0 * (3.0 * th).cos()
                            - (4.0 * th).cos();
                        DVec2::new(x, -y)
                    })
                    .collect();
                let (lo, hi) = raw
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.y), b.max(p.y)));
                let notch = raw[0].y; // theta = 0 is the notch
                let s = l / (hi - lo);
                raw.iter()
                    .map(|p| DVec2::new(p.x * s, (p.y - notch) * s))
                    .collect()
            }
            Shape::Circle => (0..n)
                .map(|k| {
                    let th = std::f64::consts::TAU * k as f64 / n as f64;
                    DVec2::new(0.5 * l * th.sin(), 0.5 * l * (1.0 - th.cos()))
                })
                .collect(),
            Shape::Rect => vec![
                DVec2::new(-0.3 * l, 0.0),
                DVec2::new(0.3 * l, 0.0),
                DVec2::new(0.3 * l, l),
                DVec2::new(-0.3 * l, l),
            ],
        };
        Outline::new(pts).expect("built-in shapes are simple polygons")
    }

    /// Where a built-in shape's petiole meets the blade: just inside the base, the middle of
    /// the lowest vertices (one for a pointed base, the bottom edge for a flat one).
    pub fn default_root(&self) -> DVec2 {
        let size = self.size().max_element();
        let low = self
            .points
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        let bottom: Vec<f64> = self
            .points
            .iter()
            .filter(|p| p.y - low <= 1e-9 * size)
            .map(|p| p.x)
            .collect();
        let x = bottom.iter().sum::<f64>() / bottom.len() as f64;
        // Walk up from the base until inside.
        let step = 1e-3 * size;
        (1..1000)
            .map(|k| DVec2::new(x, low + step * k as f64))
            .find(|p| self.contains(*p))
            .unwrap_or(self.centroid())
    }

    pub fn points(&self) -> &[DVec2] {
        &self.points
    }

    pub fn signed_area(&self) -> f64 {
        let n = self.points.len();
        0.5 * (0..n)
            .map(|i| self.points[i].perp_dot(self.points[(i + 1) % n]))
            .sum::<f64>()
    }

    pub fn area(&self) -> f64 {
        self.signed_area().abs()
    }

    pub fn centroid(&self) -> DVec2 {
        let n = self.points.len();
        let mut c = DVec2::ZERO;
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            c += (a + b) * a.perp_dot(b);
        }
        c / (6.0 * self.signed_area())
    }

    pub fn bounds(&self) -> (DVec2, DVec2) {
        let lo = self
            .points
            .iter()
            .fold(DVec2::splat(f64::MAX), |a, p| a.min(*p));
        let hi = self
            .points
            .iter()
            .fold(DVec2::splat(f64::MIN), |a, p| a.max(*p));
        (lo, hi)
    }

    pub fn size(&self) -> DVec2 {
        let (lo, hi) = self.bounds();
        hi - lo
    }

    /// Even-odd ray test; points on the boundary may fall either way.
    pub fn contains(&self, p: DVec2) -> bool {
        let Some(edges) = self.bands.at(p.y) else {
            return false;
        };
        let n = self.points.len();
        let mut inside = false;
        for &i in edges {
            let (a, b) = (self.points[i as usize], self.points[(i as usize + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Whether segment ab lies inside: both ends inside and no outline edge crossed or touched.
    pub fn contains_segment(&self, a: DVec2, b: DVec2) -> bool {
        if !(self.contains(a) && self.contains(b)) {
            return false;
        }
        let n = self.points.len();
        let (lo, hi) = (a.y.min(b.y), a.y.max(b.y));
        let first = self.bands.band(lo);
        let last = self.bands.band(hi);
        for band in first..=last {
            for &i in self.bands.edges_of(band) {
                let (p, q) = (self.points[i as usize], self.points[(i as usize + 1) % n]);
                if crate::geom::segments_touch(a, b, p, q) {
                    return false;
                }
            }
        }
        true
    }

    /// The outline scaled by `factor` about `centre`.
    pub fn scaled(&self, centre: DVec2, factor: f64) -> Outline {
        let points: Vec<DVec2> = self
            .points
            .iter()
            .map(|p| centre + (*p - centre) * factor)
            .collect();
        Outline {
            bands: Bands::new(&points),
            points,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_shapes_are_valid_and_hold_their_root() {
        for s in Shape::ALL {
            let o = Outline::shape(s);
            assert!(o.area() > 100.0, "{}", s.name());
            assert!(o.signed_area() > 0.0, "{} is counter-clockwise", s.name());
            let r = o.default_root();
            assert!(o.contains(r), "{} root {r} inside", s.name());
            // The cordate base is its notch, a quarter of the length above the lobes.
            assert!(
                r.y < 0.3 * SHAPE_LENGTH + o.bounds().0.y,
                "{} root near the base",
                s.name()
            );
            let mid = 0.5 * (o.bounds().0.x + o.bounds().1.x);
            assert!((r.x - mid).abs() < 1e-9, "{} root on the midline", s.name());
        }
    }

    #[test]
    fn bad_outlines_are_rejected() {
        let p = |x: f64, y: f64| DVec2::new(x, y);
        assert_eq!(
            Outline::new(vec![p(0.0, 0.0), p(1.0, 0.0)]),
            Err(OutlineError::TooFewPoints(2))
        );
        let bowtie = vec![p(0.0, 0.0), p(1.0, 1.0), p(1.0, 0.0), p(0.0, 1.0)];
        assert!(matches!(
            Outline::new(bowtie),
            Err(OutlineError::SelfIntersecting(..))
        ));
        let line = vec![p(0.0, 0.0), p(1.0, 0.0), p(2.0, 0.0)];
        assert!(Outline::new(line).is_err());
    }

    #[test]
    fn concave_outline_containment() -> Result<(), OutlineError> {
        // An L shape, clockwise on input.
        let p = |x: f64, y: f64| DVec2::new(x, y);
        let l = Outline::new(vec![
            p(0.0, 0.0),
            p(0.0, 2.0),
            p(1.0, 2.0),
            p(1.0, 1.0),
            p(2.0, 1.0),
            p(2.0, 0.0),
        ])?;
        assert!(l.signed_area() > 0.0);
        assert!((l.area() - 3.0).abs() < 1e-12);
        assert!(l.contains(p(0.5, 1.5)));
        assert!(!l.contains(p(1.5, 1.5)));
        Ok(())
    }
}
