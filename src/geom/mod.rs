//! Small shared geometry on glam's `DVec2`/`DVec3`. Uses nothing else of lamina.

use glam::DVec3;

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
pub fn approx_eq(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// True when every coordinate of `a` and `b` differs by at most `tol`.
pub fn approx_eq3(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
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
}
