//! Small shared geometry on glam's `DVec2`/`DVec3`. Uses nothing else of lamina.

use glam::{DVec2, DVec3};
pub mod curves;
pub mod merge;

/// The part of a convex polygon on the side of the line through `p` that `normal` points to
/// (the line itself included); repeated points a cut exactly through a corner leaves are
/// dropped.
pub fn clip_convex(poly: &[DVec2], p: DVec2, normal: DVec2) -> Vec<DVec2> {
    let side = |q: DVec2| (q - p).dot(normal);
    let mut out = Vec::new();
    for (k, &q) in poly.iter().enumerate() {
        let r = poly[(k + 1) % poly.len()];
        let (sq, sr) = (side(q), side(r));
        if sq >= 0.0 {
            out.push(q);
        }
        if (sq >= 0.0) != (sr >= 0.0) {
            out.push(q + (r - q) * (sq / (sq - sr)));
        }
    }
    out.dedup_by(|a, b| a.distance(*b) < 1e-12);
    if out.len() > 1 && out[0].distance(out[out.len() - 1]) < 1e-12 {
        out.pop();
    }
    out
}

/// Distance between two convex counter-clockwise polygons, or, when they overlap, minus the
/// least overlap along an edge normal (a separating-axis depth).
pub fn convex_distance(a: &[DVec2], b: &[DVec2]) -> f64 {
    let mut separation = f64::NEG_INFINITY;
    for (p, q) in [(a, b), (b, a)] {
        for k in 0..p.len() {
            let e = p[(k + 1) % p.len()] - p[k];
            let Some(n) = DVec2::new(e.y, -e.x).try_normalize() else {
                continue;
            };
            let lo = q
                .iter()
                .map(|x| (*x - p[k]).dot(n))
                .fold(f64::INFINITY, f64::min);
            separation = separation.max(lo);
        }
    }
    if separation <= 0.0 {
        return separation;
    }
    let to_segment = |x: DVec2, s: DVec2, t: DVec2| {
        let e = t - s;
        let u = ((x - s).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        x.distance(s + e * u)
    };
    let mut d = f64::INFINITY;
    for (p, q) in [(a, b), (b, a)] {
        for x in q {
            for k in 0..p.len() {
                d = d.min(to_segment(*x, p[k], p[(k + 1) % p.len()]));
            }
        }
    }
    d
}

/// An axis-aligned bounding box. `empty()` holds no point; extending it with one makes it that point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub fn empty() -> Self {
        Aabb {
            min: DVec3::splat(f64::INFINITY),
            max: DVec3::splat(f64::NEG_INFINITY),
        }
    }

    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a DVec3>) -> Self {
        let mut b = Aabb::empty();
        for p in points {
            b.extend(*p);
        }
        b
    }

    pub fn extend(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    pub fn size(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// Length of the diagonal; 0 for an empty box or a single point.
    pub fn diagonal(&self) -> f64 {
        self.size().length()
    }
}

/// True when `a` and `b` differ by at most `tol` (absolute). Named for what it is, so no float
/// type gets an approximate `PartialEq`.
/// SplitMix64's finaliser: a bijective mix of all 64 bits, for hashing points and edges.
pub fn mix64(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// A multiply-rotate hasher for small integer keys (grid cells, indices): far cheaper than
/// SipHash and deterministic. Keys may come from a file, but a collision only slows a lookup.
#[derive(Default)]
pub struct KeyHasher(u64);

impl std::hash::Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(v as u64);
    }
    fn write_i32(&mut self, v: i32) {
        self.write_u64(v as u32 as u64);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
}

/// A quarter turn about +X that takes +Y to +Z, exactly: what stands a drawing or a leaf up.
pub fn upright(v: DVec3) -> DVec3 {
    DVec3::new(v.x, -v.z, v.y)
}

/// An f64 with a total order (`total_cmp`), for binary heaps of distances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ordered(pub f64);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

pub fn approx_eq(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// True when every coordinate of `a` and `b` differs by at most `tol`.
pub fn approx_eq3(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

/// Whether segments ab and cd cross or touch (a shared point counts, collinear overlap too).
pub fn segments_touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: DVec2, q: DVec2, r: DVec2| {
        o(p, q, r) == 0.0
            && r.x >= p.x.min(q.x)
            && r.x <= p.x.max(q.x)
            && r.y >= p.y.min(q.y)
            && r.y <= p.y.max(q.y)
    };
    on(c, d, a) || on(c, d, b) || on(a, b, c) || on(a, b, d)
}

/// The distance from `p` to the segment ab in space.
pub fn point_segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + t * ab)
}

/// The distance between segments ab and cd in space (Ericson, Real-Time Collision Detection
/// §5.1.9: the closest points by clamped parameters).
pub fn segment_distance(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let (d1, d2, r) = (b - a, d - c, a - c);
    let (aa, ee, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (s, t) = if aa <= f64::EPSILON && ee <= f64::EPSILON {
        (0.0, 0.0)
    } else if aa <= f64::EPSILON {
        (0.0, (f / ee).clamp(0.0, 1.0))
    } else {
        let cc = d1.dot(r);
        if ee <= f64::EPSILON {
            ((-cc / aa).clamp(0.0, 1.0), 0.0)
        } else {
            let bb = d1.dot(d2);
            let denom = aa * ee - bb * bb;
            let mut s = if denom > 0.0 {
                ((bb * f - cc * ee) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (bb * s + f) / ee;
            if t < 0.0 {
                t = 0.0;
                s = (-cc / aa).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((bb - cc) / aa).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (a + d1 * s).distance(c + d2 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aabb_of_points() {
        let b = Aabb::from_points(&[DVec3::new(1.0, 2.0, 3.0), DVec3::new(-1.0, 5.0, 3.0)]);
        assert_eq!(b.min, DVec3::new(-1.0, 2.0, 3.0));
        assert_eq!(b.max, DVec3::new(1.0, 5.0, 3.0));
        assert!(approx_eq(b.diagonal(), 13f64.sqrt(), 1e-12));
        assert!(Aabb::empty().is_empty());
        assert_eq!(Aabb::empty().diagonal(), 0.0);
    }

    #[test]
    fn segment_distances_in_space() {
        let v = DVec3::new;
        // Skew lines one apart, crossing in plan.
        let d = segment_distance(
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, -1.0, 1.0),
            v(0.0, 1.0, 1.0),
        );
        assert!(approx_eq(d, 1.0, 1e-12));
        // Parallel, end to end with a gap of 2.
        let d = segment_distance(
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, 0.0, 0.0),
            v(4.0, 0.0, 0.0),
        );
        assert!(approx_eq(d, 2.0, 1e-12));
        // A point against a segment, and crossing segments.
        let d = segment_distance(
            v(0.5, 2.0, 0.0),
            v(0.5, 2.0, 0.0),
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        );
        assert!(approx_eq(d, 2.0, 1e-12));
        let d = segment_distance(
            v(0.0, 0.0, 0.0),
            v(2.0, 2.0, 0.0),
            v(0.0, 2.0, 0.0),
            v(2.0, 0.0, 0.0),
        );
        assert!(d < 1e-12);
    }
}
