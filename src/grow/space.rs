//! Where venation grows: the vector type and the domain the growth core (`venation.rs`) runs
//! in. A blade in the plane (`Blade`, with its growth) and a triangulated surface
//! (`surface::Surface`) are the two domains; the core is written once against `Domain`.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, Sub};

use glam::{DVec2, DVec3};
use rand::Rng;

use super::outline::Outline;
use super::venation::{BladeGrowth, VenationOptions};

/// The vectors growth runs on: `DVec2` in a blade, `DVec3` on a surface.
pub trait Vector:
    Copy
    + Send
    + Sync
    + Debug
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + AddAssign
{
    /// The same point as rstar stores it.
    type Array: rstar::Point<Scalar = f64> + Copy + Send + Sync;
    const ZERO: Self;
    fn to_array(self) -> Self::Array;
    fn from_array(a: Self::Array) -> Self;
    fn dot(self, o: Self) -> f64;

    fn length(self) -> f64 {
        self.dot(self).sqrt()
    }
    fn distance_squared(self, o: Self) -> f64 {
        (self - o).dot(self - o)
    }
    fn distance(self, o: Self) -> f64 {
        self.distance_squared(o).sqrt()
    }
    fn try_normalize(self) -> Option<Self> {
        let l = self.length();
        (l.is_finite() && l > 0.0).then(|| self / l)
    }
}

impl Vector for DVec2 {
    type Array = [f64; 2];
    const ZERO: Self = DVec2::ZERO;
    fn to_array(self) -> [f64; 2] {
        DVec2::to_array(&self)
    }
    fn from_array(a: [f64; 2]) -> Self {
        DVec2::from_array(a)
    }
    fn dot(self, o: Self) -> f64 {
        DVec2::dot(self, o)
    }
    fn try_normalize(self) -> Option<Self> {
        DVec2::try_normalize(self)
    }
}

impl Vector for DVec3 {
    type Array = [f64; 3];
    const ZERO: Self = DVec3::ZERO;
    fn to_array(self) -> [f64; 3] {
        DVec3::to_array(&self)
    }
    fn from_array(a: [f64; 3]) -> Self {
        DVec3::from_array(a)
    }
    fn dot(self, o: Self) -> f64 {
        DVec3::dot(self, o)
    }
    fn try_normalize(self) -> Option<Self> {
        DVec3::try_normalize(self)
    }
}

/// The space venation grows in: how a node steps, which edges it may hold, where darts land.
/// Positions the core sees are in the domain's working frame (`to_work`), which differs from
/// millimetres only while a blade grows uniformly.
pub trait Domain: Sync {
    type V: Vector;

    /// Called once at the start of every step; true while the domain itself still changes.
    fn grow(&mut self, _step: usize) -> bool {
        false
    }
    /// A distance in mm, in the working frame.
    fn eff(&self, d: f64) -> f64 {
        d
    }
    fn to_work(&self, real: Self::V) -> Self::V {
        real
    }
    fn to_real(&self, work: Self::V) -> Self::V {
        work
    }
    /// Sources farther than this from a node do not pull it (working frame).
    fn reach(&self) -> f64 {
        f64::INFINITY
    }
    /// Where a node at `from` lands when it grows a step of `len` along the unit pull `dir`,
    /// or None when the step would leave the domain.
    fn step(&self, from: Self::V, dir: Self::V, len: f64) -> Option<Self::V>;
    /// Whether a straight edge between nodes at `a` and `b` stays in the domain.
    fn holds_edge(&self, a: Self::V, b: Self::V) -> bool;
    /// Whether the edges a–b and c–d cross or touch.
    fn touch(&self, a: Self::V, b: Self::V, c: Self::V, d: Self::V) -> bool;
    /// A dart: a point in the domain and the birth distance there (working frame), or None
    /// when the throw missed.
    fn dart<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<(Self::V, f64)>;
    /// The largest birth distance anywhere (mm), to check the kill distance against.
    fn birth_max(&self) -> f64;
    /// The blade outline of this moment, for frames.
    fn outline_now(&self) -> Option<Outline> {
        None
    }
}

/// A leaf blade in the plane, full size or growing about a centre (the first root).
pub struct Blade<'a> {
    outline: &'a Outline,
    birth: &'a (dyn Fn(DVec2) -> f64 + Sync),
    growth: BladeGrowth,
    initial_scale: f64,
    rate: f64,
    centre: DVec2,
    /// Blade size as a fraction of the full outline.
    scale: f64,
}

impl<'a> Blade<'a> {
    /// `birth(p)` gives the birth distance of darts at point `p` of the full-size outline.
    pub fn new(
        outline: &'a Outline,
        centre: DVec2,
        birth: &'a (dyn Fn(DVec2) -> f64 + Sync),
        opts: &VenationOptions,
    ) -> Self {
        Blade {
            outline,
            birth,
            growth: opts.blade,
            initial_scale: opts.initial_scale,
            rate: opts.blade_rate,
            centre,
            scale: match opts.blade {
                BladeGrowth::None => 1.0,
                _ => opts.initial_scale,
            },
        }
    }

    /// Blade size as a fraction of the full outline.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Where a working point sits on the full-size outline.
    fn blade_coord(&self, p: DVec2) -> DVec2 {
        match self.growth {
            BladeGrowth::Marginal => self.centre + (p - self.centre) / self.scale,
            _ => p,
        }
    }
}

impl Domain for Blade<'_> {
    type V = DVec2;

    fn grow(&mut self, step: usize) -> bool {
        if self.growth == BladeGrowth::None || self.scale >= 1.0 {
            return false;
        }
        self.scale = (self.initial_scale + self.rate * step as f64).min(1.0);
        true
    }

    /// Under uniform growth the working frame is the full-size blade, so veins stretch with it.
    fn eff(&self, d: f64) -> f64 {
        match self.growth {
            BladeGrowth::Uniform => d / self.scale,
            _ => d,
        }
    }

    fn to_work(&self, real: DVec2) -> DVec2 {
        match self.growth {
            BladeGrowth::Uniform => self.centre + (real - self.centre) / self.scale,
            _ => real,
        }
    }

    fn to_real(&self, work: DVec2) -> DVec2 {
        match self.growth {
            BladeGrowth::Uniform => self.centre + (work - self.centre) * self.scale,
            _ => work,
        }
    }

    fn step(&self, from: DVec2, dir: DVec2, len: f64) -> Option<DVec2> {
        let at = from + dir * len;
        self.holds_edge(from, at).then_some(at)
    }

    fn holds_edge(&self, a: DVec2, b: DVec2) -> bool {
        self.outline
            .contains_segment(self.blade_coord(a), self.blade_coord(b))
    }

    fn touch(&self, a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
        crate::geom::segments_touch(a, b, c, d)
    }

    fn dart<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<(DVec2, f64)> {
        let (lo, hi) = self.outline.bounds();
        let (lo, hi) = match self.growth {
            BladeGrowth::Marginal => (
                self.centre + (lo - self.centre) * self.scale,
                self.centre + (hi - self.centre) * self.scale,
            ),
            _ => (lo, hi),
        };
        let p = DVec2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
        let at = self.blade_coord(p);
        self.outline
            .contains(at)
            .then(|| (p, self.eff((self.birth)(at))))
    }

    /// Sampled at the outline's corners and a 16 × 16 grid over the blade.
    fn birth_max(&self) -> f64 {
        let (lo, hi) = self.outline.bounds();
        let grid = (0..=16 * 16).map(|k| {
            let (i, j) = ((k % 17) as f64 / 16.0, (k / 17) as f64 / 16.0);
            lo + (hi - lo) * DVec2::new(i, j)
        });
        self.outline
            .points()
            .iter()
            .copied()
            .chain(grid.filter(|p| self.outline.contains(*p)))
            .map(self.birth)
            .fold(0.0, f64::max)
    }

    fn outline_now(&self) -> Option<Outline> {
        Some(match self.growth {
            BladeGrowth::None => self.outline.clone(),
            _ => self.outline.scaled(self.centre, self.scale),
        })
    }
}
