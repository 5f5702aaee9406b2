//! Synthetic networks with known surfaces, for tests and benchmarks.

use glam::DVec3;
use rand::{Rng, SeedableRng};

use super::Input;

/// A brick-wall network (the honeycomb's topology: degree 3 inside) of `n`×`n` nodes about
/// 10 mm apart, jittered, with the surface normals as references and every height `h`, on
/// - the paraboloid z = (x² + y²)/(400·max(1, n/16)) (curvature radius ~200 mm at the apex
///   up to 16 × 16 nodes, flatter for larger networks so the bowl keeps its shape), or
/// - the hyperboloid of one sheet (x² + y²)/150² − z²/150² = 1, z ≥ 0, like the Calyx band:
///   rows are horizontal arcs, row 0 lies at z = 0, normals are horizontal at the base.
pub fn honeycomb_on(n: usize, h: f64, seed: u64, calyx: bool) -> Input {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let half = (n as f64 - 1.0) * 5.0;
    let mut positions = Vec::new();
    let mut reference = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let u = i as f64 * 10.0 - half + rng.random_range(-2.0..2.0);
            let w = j as f64 * 10.0 + rng.random_range(-2.0..2.0);
            if calyx {
                let z = if j == 0 { 0.0 } else { w };
                let r0 = 150.0;
                let r = r0 * (1.0 + (z / r0).powi(2)).sqrt();
                let t = u / r0;
                let p = DVec3::new(r * t.cos(), r * t.sin(), z);
                positions.push(p);
                reference.push(DVec3::new(p.x, p.y, -p.z).normalize());
            } else {
                let (x, y) = (u, w - half);
                let c = 1.0 / (400.0 * (n as f64 / 16.0).max(1.0));
                positions.push(DVec3::new(x, y, c * (x * x + y * y)));
                reference.push(DVec3::new(-2.0 * c * x, -2.0 * c * y, 1.0).normalize());
            }
        }
    }
    let id = |i: usize, j: usize| (j * n + i) as u32;
    let mut edges = Vec::new();
    for j in 0..n {
        for i in 0..n {
            if i + 1 < n {
                edges.push([id(i, j), id(i + 1, j)]);
            }
            if j + 1 < n && (i + j) % 2 == 0 {
                edges.push([id(i, j), id(i, j + 1)]);
            }
        }
    }
    Input {
        heights: vec![h; positions.len()],
        positions,
        edges,
        reference,
    }
}

/// A flat `nx` × `ny` square grid, 10 mm apart in the plane z = 0, with its grid edges.
pub fn square_grid(nx: usize, ny: usize) -> (Vec<DVec3>, Vec<[u32; 2]>) {
    let mut p = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            p.push(DVec3::new(i as f64, j as f64, 0.0) * 10.0);
        }
    }
    let mut e = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let v = (j * nx + i) as u32;
            if i + 1 < nx {
                e.push([v, v + 1]);
            }
            if j + 1 < ny {
                e.push([v, v + nx as u32]);
            }
        }
    }
    (p, e)
}

pub fn honeycomb(n: usize, h: f64, seed: u64) -> Input {
    honeycomb_on(n, h, seed, false)
}
