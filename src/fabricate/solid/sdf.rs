//! The shapes a solid is made of, as signed distance functions (negative inside, mm): round
//! cones along the veins, a prism for the leaf lamina, a cylinder for the base.
//!
//! Every function here is 1-Lipschitz (it changes by at most the distance moved), which is what
//! the mesher relies on to skip bricks far from the surface. A round cone's value is exact
//! outside and correct in sign inside (it is the distance to the nearest of the balls the cone is
//! swept from, less that ball's radius); the prism and cylinder are exact.

use glam::{DVec2, DVec3};

/// One solid piece. Its union with the others is the solid. (The prism, one to a solid, is
/// boxed: a piece is then a cone's 128 bytes, not the prism's 200, and the pieces a query
/// looks at are fewer cache lines.)
#[derive(Clone, Debug)]
pub enum Primitive {
    Cone(RoundCone),
    Prism(Box<Prism>),
    Cylinder(Cylinder),
}

impl Primitive {
    /// The area of the shape's surface, or more (caps counted whole).
    pub fn area_bound(&self) -> f64 {
        use std::f64::consts::PI;
        match self {
            Primitive::Cone(c) => {
                let (r0, r1) = (c.ra, c.rb);
                PI * (r0 + r1) * (c.a.distance(c.b) + (r0 - r1).abs())
                    + 4.0 * PI * r0.max(r1).powi(2)
            }
            Primitive::Prism(s) => {
                let (lo, hi) = self.bounds();
                let size = hi - lo;
                // Two faces no larger than the box's, sides no longer than the outline's.
                2.0 * size.x * size.y + s.outline.perimeter() * (s.z1 - s.z0)
            }
            Primitive::Cylinder(c) => 2.0 * PI * c.radius * (c.height.abs() + c.radius),
        }
    }

    /// Half the piece's least thickness: a cone's lesser end radius, a cylinder's radius or half
    /// its height, half a prism's height (its outline may be narrower still).
    pub fn half_thickness(&self) -> f64 {
        match self {
            Primitive::Cone(c) => c.ra.min(c.rb),
            Primitive::Prism(s) => 0.5 * (s.z1 - s.z0).abs(),
            Primitive::Cylinder(c) => c.radius.min(0.5 * c.height.abs()),
        }
    }

    /// Signed distance at `p`; values beyond `reach` may be reported as `±reach` (the sign is
    /// always right).
    pub fn eval(&self, p: DVec3, reach: f64) -> f64 {
        match self {
            Primitive::Cone(c) => c.eval(p),
            Primitive::Prism(s) => s.eval(p, reach),
            Primitive::Cylinder(c) => c.eval(p),
        }
    }

    /// The direction the value grows fastest at `p`, unit length (zero where it has none):
    /// exact for a cone, central differences `step` apart for the others.
    pub fn gradient(&self, p: DVec3, reach: f64, step: f64) -> DVec3 {
        if let Primitive::Cone(c) = self {
            return c.gradient(p);
        }
        let e = |v: DVec3| self.eval(p + v * step, reach) - self.eval(p - v * step, reach);
        DVec3::new(e(DVec3::X), e(DVec3::Y), e(DVec3::Z)).normalize_or_zero()
    }

    /// Whether two pieces are veins that do not touch: a gap lies between them. Other pieces
    /// are never told apart.
    pub fn apart(&self, other: &Primitive) -> bool {
        match (self, other) {
            (Primitive::Cone(a), Primitive::Cone(b)) => a.gap(b) > 0.0,
            _ => false,
        }
    }

    /// Axis-aligned box holding the piece.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match self {
            Primitive::Cone(c) => {
                let (ra, rb) = (DVec3::splat(c.ra), DVec3::splat(c.rb));
                ((c.a - ra).min(c.b - rb), (c.a + ra).max(c.b + rb))
            }
            Primitive::Prism(s) => (s.outline.lo.extend(s.z0), s.outline.hi.extend(s.z1)),
            Primitive::Cylinder(c) => {
                // Disc extents along each axis: r·sqrt(1 − axis_i²).
                let d = c.axis;
                let ext = DVec3::new(
                    (1.0 - d.x * d.x).max(0.0).sqrt(),
                    (1.0 - d.y * d.y).max(0.0).sqrt(),
                    (1.0 - d.z * d.z).max(0.0).sqrt(),
                ) * c.radius;
                let (p, q) = (c.base, c.base + d * c.height);
                (p.min(q) - ext, p.max(q) + ext)
            }
        }
    }
}

/// The convex hull of two balls (a, ra) and (b, rb): a tapered vein with round ends.
#[derive(Clone, Debug)]
pub struct RoundCone {
    a: DVec3,
    b: DVec3,
    ra: f64,
    rb: f64,
    axis: DVec3,
    len: f64,
    sin: f64,
    cos: f64,
    /// One ball holds the other: the hull is the larger ball.
    nested: bool,
}

impl RoundCone {
    pub fn new(a: DVec3, b: DVec3, ra: f64, rb: f64) -> Self {
        let len = a.distance(b);
        let nested = len <= (ra - rb).abs();
        let axis = if len > 0.0 { (b - a) / len } else { DVec3::Z };
        let sin = if nested { 0.0 } else { (ra - rb) / len };
        RoundCone {
            a,
            b,
            ra,
            rb,
            axis,
            len,
            sin,
            cos: (1.0 - sin * sin).max(0.0).sqrt(),
            nested,
        }
    }

    /// How far apart the two cones are: the least of |A(s) − B(t)| − rA(s) − rB(t) over the
    /// balls each cone is swept from (centres and radii linear along its axis), so negative
    /// when they overlap. That function is convex in (s, t); it is minimised one parameter at a
    /// time, by golden sections.
    pub fn gap(&self, other: &RoundCone) -> f64 {
        let f = |s: f64, t: f64| {
            let p = self.a.lerp(self.b, s);
            let q = other.a.lerp(other.b, t);
            p.distance(q)
                - (self.ra + (self.rb - self.ra) * s)
                - (other.ra + (other.rb - other.ra) * t)
        };
        let (mut s, mut t) = (0.5, 0.5);
        let mut best = f(s, t);
        for _ in 0..6 {
            s = golden(&|x| f(x, t), |_| false);
            t = golden(&|x| f(s, x), |_| false);
            let now = f(s, t);
            if now < 0.0 || best - now < 1e-12 {
                return now;
            }
            best = now;
        }
        best
    }

    /// The two balls: (centre a, radius a, centre b, radius b).
    pub fn balls(&self) -> (DVec3, f64, DVec3, f64) {
        (self.a, self.ra, self.b, self.rb)
    }

    /// The gradient of `eval`: away from the nearer ball's centre at the ends, along the
    /// side's normal between them.
    pub fn gradient(&self, p: DVec3) -> DVec3 {
        let pa = p - self.a;
        let from_a = || pa.normalize_or_zero();
        let from_b = || (p - self.b).normalize_or_zero();
        if self.nested {
            return if pa.length() - self.ra <= p.distance(self.b) - self.rb {
                from_a()
            } else {
                from_b()
            };
        }
        let t = pa.dot(self.axis);
        let q = (pa.length_squared() - t * t).max(0.0).sqrt();
        let s = t * self.cos - q * self.sin;
        if s < 0.0 {
            from_a()
        } else if s > self.len * self.cos {
            from_b()
        } else if q > 0.0 {
            let radial = (pa - self.axis * t) / q;
            (self.axis * self.sin + radial * self.cos).normalize_or_zero()
        } else {
            DVec3::ZERO
        }
    }

    pub fn eval(&self, p: DVec3) -> f64 {
        let pa = p - self.a;
        if self.nested {
            return (pa.length() - self.ra).min(p.distance(self.b) - self.rb);
        }
        // In the plane through the axis: t along it, q away from it. The side is the line
        // tangent to both circles; its normal is (sin, cos).
        let t = pa.dot(self.axis);
        let q = (pa.length_squared() - t * t).max(0.0).sqrt();
        let s = t * self.cos - q * self.sin;
        if s < 0.0 {
            pa.length() - self.ra
        } else if s > self.len * self.cos {
            p.distance(self.b) - self.rb
        } else {
            t * self.sin + q * self.cos - self.ra
        }
    }
}

/// Where a function of one variable that falls then rises (a convex one) is least on [0, 1],
/// by golden sections (to about 1e-9), the ends included; the search ends early at a point
/// whose value `enough` accepts.
pub fn golden(f: &impl Fn(f64) -> f64, enough: impl Fn(f64) -> bool) -> f64 {
    let k = 0.5 * (5f64.sqrt() - 1.0);
    let (mut lo, mut hi) = (0.0, 1.0);
    let (mut x1, mut x2) = (hi - k * (hi - lo), lo + k * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..44 {
        if enough(f1) {
            return x1;
        }
        if enough(f2) {
            return x2;
        }
        if f1 <= f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - k * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + k * (hi - lo);
            f2 = f(x2);
        }
    }
    let m = 0.5 * (lo + hi);
    [0.0, m, 1.0]
        .into_iter()
        .min_by(|&a, &b| f(a).total_cmp(&f(b)))
        .unwrap_or(m)
}

/// A capped cylinder from `base` along the unit `axis` for `height`.
#[derive(Clone, Debug)]
pub struct Cylinder {
    pub base: DVec3,
    pub axis: DVec3,
    pub height: f64,
    pub radius: f64,
}

impl Cylinder {
    pub fn eval(&self, p: DVec3) -> f64 {
        let d = p - self.base;
        let t = d.dot(self.axis);
        let radial = (d.length_squared() - t * t).max(0.0).sqrt();
        let half = 0.5 * self.height;
        capped(radial - self.radius, (t - half).abs() - half)
    }
}

/// A closed polygon in the xy plane extruded over z0..z1.
#[derive(Clone, Debug)]
pub struct Prism {
    pub outline: Polygon,
    pub z0: f64,
    pub z1: f64,
}

impl Prism {
    pub fn eval(&self, p: DVec3, reach: f64) -> f64 {
        let across = self.outline.signed_distance(p.truncate(), reach);
        self.with_across(across, p.z)
    }

    /// An upper bound on the value over the triangle `t`: the value is at most the sum of its
    /// in-plane and height parts where they are positive, the first bounded by
    /// `Polygon::outside_bound` and the second, convex, by its largest at the corners.
    pub fn bound_over(&self, t: &[DVec3; 3]) -> f64 {
        let (mid, half) = (0.5 * (self.z0 + self.z1), 0.5 * (self.z1 - self.z0));
        let up = t
            .iter()
            .map(|p| ((p.z - mid).abs() - half).max(0.0))
            .fold(0.0, f64::max);
        up + self.outline.outside_bound(t.map(|p| p.truncate()))
    }

    /// The value at height `z` where the in-plane signed distance is `across` (lets a caller
    /// reuse one in-plane distance for a whole column of points).
    pub fn with_across(&self, across: f64, z: f64) -> f64 {
        let half = 0.5 * (self.z1 - self.z0);
        capped(across, (z - 0.5 * (self.z0 + self.z1)).abs() - half)
    }
}

/// Exact distance to the intersection of two slabs given each one's signed distance.
fn capped(a: f64, b: f64) -> f64 {
    a.max(b).min(0.0) + DVec2::new(a.max(0.0), b.max(0.0)).length()
}

/// A simple polygon with a bucket grid of its edges, for signed distances near its boundary.
#[derive(Clone, Debug)]
pub struct Polygon {
    points: Vec<DVec2>,
    lo: DVec2,
    hi: DVec2,
    /// Bucket size; every edge is listed in each bucket within `cell` of it.
    cell: f64,
    cols: usize,
    rows: usize,
    /// CSR: edges near bucket k are `edges[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    edges: Vec<u32>,
    /// CSR: edges whose y-range meets bucket row r are `row_edges[row_start[r]..row_start[r + 1]]`.
    row_start: Vec<u32>,
    row_edges: Vec<u32>,
}

impl Polygon {
    /// The outline's length.
    pub fn perimeter(&self) -> f64 {
        let n = self.points.len();
        (0..n)
            .map(|i| self.points[i].distance(self.points[(i + 1) % n]))
            .sum()
    }
}

impl Polygon {
    /// `cell` is the largest distance that must be exact; farther points get ±`cell`.
    pub fn new(points: Vec<DVec2>, cell: f64) -> Self {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for &p in &points {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let cols = (((hi.x - lo.x) / cell).ceil() as usize).max(1);
        let rows = (((hi.y - lo.y) / cell).ceil() as usize).max(1);
        let n = points.len();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for i in 0..n {
            let (a, b) = (points[i], points[(i + 1) % n]);
            let (c0, r0) = bucket(a.min(b) - DVec2::splat(cell), lo, cell, cols, rows);
            let (c1, r1) = bucket(a.max(b) + DVec2::splat(cell), lo, cell, cols, rows);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    pairs.push(((r * cols + c) as u32, i as u32));
                }
            }
        }
        let mut row_pairs: Vec<(u32, u32)> = Vec::new();
        for i in 0..n {
            let (a, b) = (points[i], points[(i + 1) % n]);
            let (_, r0) = bucket(a.min(b), lo, cell, cols, rows);
            let (_, r1) = bucket(a.max(b), lo, cell, cols, rows);
            row_pairs.extend((r0..=r1).map(|r| (r as u32, i as u32)));
        }
        let (start, edges) = csr(pairs, cols * rows);
        let (row_start, row_edges) = csr(row_pairs, rows);
        Polygon {
            points,
            lo,
            hi,
            cell,
            cols,
            rows,
            start,
            edges,
            row_start,
            row_edges,
        }
    }

    pub fn points(&self) -> &[DVec2] {
        &self.points
    }

    /// An upper bound on how far any point of the triangle `t` is outside the polygon (0
    /// inside). The distance to one edge is convex, so its largest value at the corners bounds
    /// it over the triangle, and the least such bound over the edges bounds the distance to the
    /// polygon (outside it is the least over the edges, inside it is 0). And it is 0 when the
    /// corners are inside and no edge meets the triangle's sides: the outline, a closed curve
    /// crossing no side, would otherwise lie wholly inside the triangle, putting its corners
    /// outside.
    pub fn outside_bound(&self, t: [DVec2; 3]) -> f64 {
        let n = self.points.len();
        let lo = t[0].min(t[1]).min(t[2]);
        let hi = t[0].max(t[1]).max(t[2]);
        let (c0, r0) = bucket(lo, self.lo, self.cell, self.cols, self.rows);
        let (c1, r1) = bucket(hi, self.lo, self.cell, self.cols, self.rows);
        // The edges listed in the buckets the triangle's box meets: every edge that meets the
        // triangle passes through one of them.
        let near: Vec<u32> = if (c1 - c0 + 1) * (r1 - r0 + 1) > n {
            (0..n as u32).collect()
        } else {
            let mut near: Vec<u32> = (r0..=r1)
                .flat_map(|r| (c0..=c1).map(move |c| r * self.cols + c))
                .flat_map(|k| &self.edges[self.start[k] as usize..self.start[k + 1] as usize])
                .copied()
                .collect();
            near.sort_unstable();
            near.dedup();
            near
        };
        let mut best = f64::INFINITY;
        let mut crossed = false;
        for e in near {
            let (a, b) = (self.points[e as usize], self.points[(e as usize + 1) % n]);
            let far = t
                .iter()
                .map(|&p| segment_distance(p, a, b))
                .fold(0.0, f64::max);
            best = best.min(far);
            crossed =
                crossed || (0..3).any(|k| crate::geom::segments_touch(t[k], t[(k + 1) % 3], a, b));
        }
        if !crossed && t.iter().all(|&p| self.contains(p)) {
            return 0.0;
        }
        best
    }

    /// Signed distance to the boundary (negative inside), exact where its size is below
    /// `reach` (at most the bucket size), `±reach` beyond.
    pub fn signed_distance(&self, p: DVec2, reach: f64) -> f64 {
        let reach = reach.min(self.cell);
        let outside_box = p.x < self.lo.x || p.y < self.lo.y || p.x > self.hi.x || p.y > self.hi.y;
        let box_gap = (self.lo - p).max(p - self.hi).max(DVec2::ZERO).length();
        if outside_box && box_gap >= reach {
            return reach;
        }
        let (c, r) = bucket(p, self.lo, self.cell, self.cols, self.rows);
        let k = r * self.cols + c;
        let n = self.points.len();
        let mut best = reach;
        for &e in &self.edges[self.start[k] as usize..self.start[k + 1] as usize] {
            let (a, b) = (self.points[e as usize], self.points[(e as usize + 1) % n]);
            best = best.min(segment_distance(p, a, b));
        }
        if !outside_box && self.contains(p) {
            -best
        } else {
            best
        }
    }

    /// Even-odd crossing test over the edges of the point's row of buckets.
    fn contains(&self, p: DVec2) -> bool {
        let n = self.points.len();
        let (_, r) = bucket(p, self.lo, self.cell, self.cols, self.rows);
        let mut inside = false;
        for &i in &self.row_edges[self.row_start[r] as usize..self.row_start[r + 1] as usize] {
            let i = i as usize;
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if x > p.x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

/// Compressed rows from (bucket, edge) pairs: `start` has one entry more than there are buckets.
fn csr(mut pairs: Vec<(u32, u32)>, buckets: usize) -> (Vec<u32>, Vec<u32>) {
    pairs.sort_unstable();
    let mut start = vec![0u32; buckets + 1];
    for &(k, _) in &pairs {
        start[k as usize + 1] += 1;
    }
    for k in 0..buckets {
        start[k + 1] += start[k];
    }
    (start, pairs.into_iter().map(|(_, e)| e).collect())
}

fn bucket(p: DVec2, lo: DVec2, cell: f64, cols: usize, rows: usize) -> (usize, usize) {
    let c = ((p.x - lo.x) / cell).floor().clamp(0.0, (cols - 1) as f64) as usize;
    let r = ((p.y - lo.y) / cell).floor().clamp(0.0, (rows - 1) as f64) as usize;
    (c, r)
}

fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed distance to the hull of two balls by brute force over the balls swept between.
    fn swept(p: DVec3, a: DVec3, b: DVec3, ra: f64, rb: f64) -> f64 {
        (0..=20000)
            .map(|i| {
                let t = i as f64 / 20000.0;
                p.distance(a.lerp(b, t)) - (ra + (rb - ra) * t)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn round_cone_is_the_union_of_swept_balls() {
        let (a, b) = (DVec3::new(0.1, -0.2, 0.3), DVec3::new(2.0, 1.0, -0.5));
        for (ra, rb) in [(0.5, 0.2), (0.2, 0.6), (0.3, 0.3), (3.0, 0.2)] {
            let cone = RoundCone::new(a, b, ra, rb);
            for i in 0..300 {
                let f = i as f64;
                let p = DVec3::new(
                    (f * 0.37).sin() * 3.0,
                    (f * 0.71).cos() * 2.5,
                    (f * 0.13).sin() * 2.0,
                );
                let want = swept(p, a, b, ra, rb);
                assert!(
                    (cone.eval(p) - want).abs() < 1e-6,
                    "radii {ra},{rb} at {p}: {} vs {want}",
                    cone.eval(p)
                );
            }
        }
    }

    #[test]
    fn prism_distance_is_exact_near_the_rim_and_signed_far() {
        let square = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(4.0, 4.0),
            DVec2::new(0.0, 4.0),
        ];
        let prism = Prism {
            outline: Polygon::new(square, 0.5),
            z0: 0.0,
            z1: 1.0,
        };
        let near = |p: DVec3| prism.eval(p, 0.5);
        assert!((near(DVec3::new(2.0, 2.0, 0.9)) + 0.1).abs() < 1e-12);
        assert!((near(DVec3::new(4.2, 2.0, 0.5)) - 0.2).abs() < 1e-12);
        assert!((near(DVec3::new(4.3, 4.4, 0.5)) - 0.5).abs() < 1e-12);
        assert!((near(DVec3::new(2.0, 2.0, 1.3)) - 0.3).abs() < 1e-12);
        assert!(near(DVec3::new(2.0, 2.0, 0.5)) < 0.0);
        assert!(near(DVec3::new(9.0, 2.0, 0.5)) > 0.0);
    }

    #[test]
    fn cylinder_is_capped() {
        let c = Cylinder {
            base: DVec3::ZERO,
            axis: DVec3::NEG_Z,
            height: 2.0,
            radius: 1.0,
        };
        assert!((c.eval(DVec3::new(0.0, 0.0, 0.5)) - 0.5).abs() < 1e-12);
        assert!((c.eval(DVec3::new(0.0, 0.0, -1.0)) + 1.0).abs() < 1e-12);
        assert!((c.eval(DVec3::new(3.0, 0.0, -1.0)) - 2.0).abs() < 1e-12);
        assert!((c.eval(DVec3::new(4.0, 0.0, -6.0)) - 5.0).abs() < 1e-12);
        let (lo, hi) = Primitive::Cylinder(c).bounds();
        assert!(lo.abs_diff_eq(DVec3::new(-1.0, -1.0, -2.0), 1e-12));
        assert!(hi.abs_diff_eq(DVec3::new(1.0, 1.0, 0.0), 1e-12));
    }
}
