//! Poisson-disk sampling of a blade (Bridson 2007) with a radius that may vary over the blade,
//! as Gokmen §3.2 places auxin sources from a density map: a new sample keeps at least the
//! radius at its own position from every earlier one.

use glam::DVec2;
use rand::Rng;

use super::outline::Outline;

/// Candidates tried around an active sample before it retires (Bridson's k).
pub const CANDIDATES: usize = 30;

/// Samples the blade. `radius(p)` must lie in `[r_min, r_max]`, both > 0. The result depends
/// only on the inputs and the state of `rng`.
/// The most grid cells `sample` may allocate (4 bytes each): 400 MB.
pub const MAX_GRID_CELLS: f64 = 1e8;

/// Grid cells `sample` allocates for `outline` at spacing `r_min`; callers check it against
/// `MAX_GRID_CELLS` first (a thin outline with a huge box needs far more cells than samples).
pub fn grid_cells(outline: &Outline, r_min: f64) -> f64 {
    let (lo, hi) = outline.bounds();
    let cell = r_min / std::f64::consts::SQRT_2;
    (((hi.x - lo.x) / cell).ceil() + 1.0) * (((hi.y - lo.y) / cell).ceil() + 1.0)
}

pub fn sample(
    outline: &Outline,
    r_min: f64,
    r_max: f64,
    radius: impl Fn(DVec2) -> f64,
    rng: &mut impl Rng,
) -> Vec<DVec2> {
    debug_assert!(r_min > 0.0 && r_max >= r_min);
    debug_assert!(grid_cells(outline, r_min) <= MAX_GRID_CELLS);
    let (lo, hi) = outline.bounds();
    let cell = r_min / std::f64::consts::SQRT_2;
    let cols = ((hi.x - lo.x) / cell).ceil() as usize + 1;
    let rows = ((hi.y - lo.y) / cell).ceil() as usize + 1;
    // With every pair at least r_min apart, a cell of diagonal r_min holds one sample at most.
    let mut grid: Vec<u32> = vec![u32::MAX; cols * rows];
    let cell_of = |p: DVec2| {
        let c = (((p.x - lo.x) / cell) as usize).min(cols - 1);
        let r = (((p.y - lo.y) / cell) as usize).min(rows - 1);
        (c, r)
    };
    let mut samples: Vec<DVec2> = Vec::new();
    let mut active: Vec<u32> = Vec::new();
    let fits = |p: DVec2, samples: &[DVec2], grid: &[u32]| {
        if !outline.contains(p) {
            return false;
        }
        let r = radius(p).clamp(r_min, r_max);
        let (c, w) = cell_of(p);
        let reach = (r / cell).ceil() as usize;
        for y in w.saturating_sub(reach)..(w + reach + 1).min(rows) {
            for x in c.saturating_sub(reach)..(c + reach + 1).min(cols) {
                let id = grid[y * cols + x];
                if id != u32::MAX && samples[id as usize].distance_squared(p) < r * r {
                    return false;
                }
            }
        }
        true
    };
    // A first sample anywhere inside.
    for _ in 0..10_000 {
        let p = DVec2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
        if outline.contains(p) {
            let (c, r) = cell_of(p);
            grid[r * cols + c] = 0;
            samples.push(p);
            active.push(0);
            break;
        }
    }
    while !active.is_empty() {
        let k = rng.random_range(0..active.len());
        let p = samples[active[k] as usize];
        let r = radius(p).clamp(r_min, r_max);
        let mut placed = false;
        for _ in 0..CANDIDATES {
            let angle = rng.random_range(0.0..std::f64::consts::TAU);
            let dist = r * (1.0 + rng.random_range(0.0..1.0f64));
            let q = p + DVec2::from_angle(angle) * dist;
            if q.x < lo.x || q.y < lo.y || q.x > hi.x || q.y > hi.y {
                continue;
            }
            if fits(q, &samples, &grid) {
                let (c, w) = cell_of(q);
                grid[w * cols + c] = samples.len() as u32;
                active.push(samples.len() as u32);
                samples.push(q);
                placed = true;
                break;
            }
        }
        if !placed {
            active.swap_remove(k);
        }
    }
    samples
}

#[cfg(test)]
mod tests {
    use super::super::outline::Shape;
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn samples_are_inside_and_apart() {
        let o = Outline::shape(Shape::Ovate);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let s = sample(&o, 2.0, 2.0, |_| 2.0, &mut rng);
        assert!(s.len() > 300, "{}", s.len());
        for (i, a) in s.iter().enumerate() {
            assert!(o.contains(*a));
            for b in &s[i + 1..] {
                assert!(a.distance(*b) >= 2.0 - 1e-12);
            }
        }
        // Maximal: the blade is covered, so density is near the Poisson-disk packing.
        let per_area = s.len() as f64 / o.area();
        assert!(per_area > 0.12, "{per_area} samples/mm²");
    }

    #[test]
    fn smaller_radius_where_asked_gives_more_samples_there() {
        let o = Outline::shape(Shape::Rect);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        // Dense (r = 1) on the left half, sparse (r = 3) on the right.
        let s = sample(
            &o,
            1.0,
            3.0,
            |p| if p.x < 0.0 { 1.0 } else { 3.0 },
            &mut rng,
        );
        let left = s.iter().filter(|p| p.x < 0.0).count();
        let right = s.len() - left;
        assert!(left > 5 * right, "left {left}, right {right}");
    }

    #[test]
    fn same_seed_same_samples() {
        let o = Outline::shape(Shape::Cordate);
        let run = |seed| sample(&o, 2.0, 2.0, |_| 2.0, &mut ChaCha8Rng::seed_from_u64(seed));
        assert_eq!(run(5), run(5));
        assert_ne!(run(5), run(6));
    }
}
