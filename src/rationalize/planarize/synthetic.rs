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
    honeycomb_shaped(
        n,
        h,
        seed,
        if calyx {
            Shape::Hyperboloid
        } else {
            Shape::Paraboloid
        },
    )
}

/// The surface a brick-wall network is laid on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    Paraboloid,
    /// The saddle z = (x² − y²)/(400·max(1, n/16)): the paraboloid's curvature, of both signs.
    Saddle,
    Hyperboloid,
}

/// [`honeycomb_on`] on any [`Shape`].
pub fn honeycomb_shaped(n: usize, h: f64, seed: u64, shape: Shape) -> Input {
    let calyx = shape == Shape::Hyperboloid;
    let sign = if shape == Shape::Saddle { -1.0 } else { 1.0 };
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
                positions.push(DVec3::new(x, y, c * (x * x + sign * y * y)));
                reference.push(DVec3::new(-2.0 * c * x, -2.0 * c * sign * y, 1.0).normalize());
            }
        }
    }
    Input {
        heights: vec![h; positions.len()],
        positions,
        edges: brick_edges(n),
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

/// The dual of a frequency-`f` geodesic icosphere (every face cut into f² triangles; a node per
/// triangle, an edge per pair of triangles sharing a side: degree 3 everywhere, 20·f² nodes,
/// hexagonal faces and twelve pentagons), mapped onto the ellipsoid with semi-axes `axes`, with
/// its surface normals as references and every height `h`.
pub fn ellipsoid_dual(f: usize, axes: DVec3, h: f64) -> Input {
    use std::collections::HashMap;
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let ico: Vec<DVec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let faces: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let f = f.max(1);
    // Grid points keyed so that faces sharing a side or corner share them exactly.
    #[derive(Hash, PartialEq, Eq)]
    enum Key {
        Corner(usize),
        Side(usize, usize, usize),
        Inner(usize, usize, usize),
    }
    let mut ids: HashMap<Key, u32> = HashMap::new();
    let mut sphere: Vec<DVec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for (fi, &[a, b, c]) in faces.iter().enumerate() {
        let mut point = |i: usize, j: usize| -> u32 {
            let k = f - i - j;
            let weights = [(a, k), (b, i), (c, j)];
            let nonzero: Vec<(usize, usize)> =
                weights.iter().copied().filter(|w| w.1 > 0).collect();
            let key = match nonzero.as_slice() {
                [(v, _)] => Key::Corner(*v),
                [(u, wu), (v, _)] => {
                    if u < v {
                        Key::Side(*u, *v, *wu)
                    } else {
                        Key::Side(*v, *u, f - wu)
                    }
                }
                _ => Key::Inner(fi, i, j),
            };
            let next = sphere.len() as u32;
            *ids.entry(key).or_insert_with(|| {
                let p = ico[a] * k as f64 + ico[b] * i as f64 + ico[c] * j as f64;
                sphere.push(p.normalize());
                next
            })
        };
        for j in 0..f {
            for i in 0..f - j {
                let (p, q, r) = (point(i, j), point(i + 1, j), point(i, j + 1));
                triangles.push([p, q, r]);
                if i + j + 2 <= f {
                    let s = point(i + 1, j + 1);
                    triangles.push([q, s, r]);
                }
            }
        }
    }
    let mut positions = Vec::with_capacity(triangles.len());
    let mut reference = Vec::with_capacity(triangles.len());
    for t in &triangles {
        let u = (sphere[t[0] as usize] + sphere[t[1] as usize] + sphere[t[2] as usize]).normalize();
        let p = u * axes;
        positions.push(p);
        reference.push((p / (axes * axes)).normalize());
    }
    let mut sides: HashMap<(u32, u32), u32> = HashMap::new();
    let mut edges = Vec::with_capacity(triangles.len() * 3 / 2);
    for (ti, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            let key = (u.min(v), u.max(v));
            if let Some(other) = sides.remove(&key) {
                edges.push([other, ti as u32]);
            } else {
                sides.insert(key, ti as u32);
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

/// A brick-wall network (degree 3 inside) of `n` × `n` nodes over the square |x|, |y| ≤ `half`
/// mm, jittered by up to a fifth of the spacing, on the saddle z = (x² − y²)/(2·`radius`), with
/// its surface normals as references and every height `h`. Unlike [`honeycomb_shaped`], the
/// surface stays the same as `n` grows: more nodes make shorter, narrower panels on it.
pub fn saddle(n: usize, half: f64, radius: f64, h: f64, seed: u64) -> Input {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let n = n.max(2);
    let step = 2.0 * half / (n - 1) as f64;
    let jitter = 0.2 * step;
    let mut positions = Vec::with_capacity(n * n);
    let mut reference = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let x = -half + i as f64 * step + rng.random_range(-jitter..jitter);
            let y = -half + j as f64 * step + rng.random_range(-jitter..jitter);
            positions.push(DVec3::new(x, y, (x * x - y * y) / (2.0 * radius)));
            reference.push(DVec3::new(-x / radius, y / radius, 1.0).normalize());
        }
    }
    Input {
        heights: vec![h; positions.len()],
        positions,
        edges: brick_edges(n),
        reference,
    }
}

/// The brick wall's edges on an `n` × `n` grid numbered row by row.
fn brick_edges(n: usize) -> Vec<[u32; 2]> {
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
    edges
}
