//! Bench meshes made in code: a torus of `around × across` vertices, two triangles per quad.

use glam::DVec3;
use lamina::TriMesh;

/// A torus with radii `big` and `small` mm, `around` × `across` vertices.
pub fn torus(big: f64, small: f64, around: usize, across: usize) -> TriMesh {
    let mut positions = Vec::with_capacity(around * across);
    for i in 0..around {
        let u = std::f64::consts::TAU * i as f64 / around as f64;
        for j in 0..across {
            let v = std::f64::consts::TAU * j as f64 / across as f64;
            let r = big + small * v.cos();
            positions.push(DVec3::new(r * u.cos(), r * u.sin(), small * v.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % around) * across + j % across) as u32;
    let mut triangles = Vec::with_capacity(2 * around * across);
    for i in 0..around {
        for j in 0..across {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    TriMesh {
        positions,
        triangles,
        colors: None,
    }
}
