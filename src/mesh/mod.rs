//! `TriMesh`: a triangle mesh (surfaces lamina grows on, solids it prints), with optional vertex
//! colours (density maps painted on surfaces). `check_manifold` reports its topology.

mod check;
pub mod closest;
pub mod inside;
pub mod intersect;
pub mod io;
mod weld;

use glam::DVec3;

use crate::geom::Aabb;

pub(crate) use check::{find, union};
pub use check::{MeshProblem, Topology};
pub use weld::MeshWeld;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// One RGB colour per position, each channel 0..=1, when the file carried them.
    pub colors: Option<Vec<[f32; 3]>>,
}

impl TriMesh {
    /// A grid of (nx + 1) × (ny + 1) vertices, row by row (j outer), placed by `at(i, j)`; each
    /// cell split into ((i, j), (i+1, j), (i+1, j+1)) and ((i, j), (i+1, j+1), (i, j+1)).
    pub fn grid(nx: u32, ny: u32, at: impl Fn(u32, u32) -> DVec3) -> TriMesh {
        let mut positions = Vec::with_capacity(((nx + 1) * (ny + 1)) as usize);
        for j in 0..=ny {
            for i in 0..=nx {
                positions.push(at(i, j));
            }
        }
        let id = |i: u32, j: u32| j * (nx + 1) + i;
        let mut triangles = Vec::with_capacity((2 * nx * ny) as usize);
        for j in 0..ny {
            for i in 0..nx {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        TriMesh {
            positions,
            triangles,
            colors: None,
        }
    }

    /// An axis-aligned box from `lo` to `hi`: 8 corners, 12 triangles wound outwards.
    pub fn cuboid(lo: DVec3, hi: DVec3) -> TriMesh {
        let corner = |i: usize| {
            DVec3::new(
                if i & 1 == 1 { hi.x } else { lo.x },
                if i & 2 == 2 { hi.y } else { lo.y },
                if i & 4 == 4 { hi.z } else { lo.z },
            )
        };
        let quads: [[u32; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        TriMesh {
            positions: (0..8).map(corner).collect(),
            triangles: quads
                .iter()
                .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
                .collect(),
            colors: None,
        }
    }

    /// Drops the vertices no triangle uses (and their colours), keeping the others' order.
    pub fn drop_unused(&mut self) {
        let mut index = vec![u32::MAX; self.positions.len()];
        for t in &self.triangles {
            for &v in t {
                index[v as usize] = 0;
            }
        }
        let mut positions = Vec::with_capacity(self.positions.len());
        for (v, p) in self.positions.iter().enumerate() {
            if index[v] == 0 {
                index[v] = positions.len() as u32;
                positions.push(*p);
            }
        }
        for t in &mut self.triangles {
            *t = t.map(|v| index[v as usize]);
        }
        if let Some(colors) = &mut self.colors {
            let mut k = 0;
            colors.retain(|_| {
                k += 1;
                index.get(k - 1).is_some_and(|&i| i != u32::MAX)
            });
        }
        self.positions = positions;
    }

    pub fn bbox(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().filter(|p| p.is_finite()))
    }

    /// Corners of triangle `t`. Indices must be in range.
    pub fn corners(&self, t: &[u32; 3]) -> [DVec3; 3] {
        t.map(|i| self.positions[i as usize])
    }

    /// Total area in mm².
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Signed volume in mm³ (positive when the triangles wind counter-clockwise seen from
    /// outside). Meaningful only for a closed mesh.
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = self.corners(t);
                a.dot(b.cross(c))
            })
            .sum::<f64>()
            / 6.0
    }
}
