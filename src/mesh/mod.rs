//! `TriMesh`: a triangle mesh (surfaces lamina grows on, solids it prints), with optional vertex
//! colours (density maps painted on surfaces). `check_manifold` reports its topology.

mod check;
pub mod closest;
pub mod intersect;
pub mod io;

use glam::DVec3;

use crate::geom::Aabb;

pub(crate) use check::{find, union};
pub use check::{MeshProblem, Topology};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// One RGB colour per position, each channel 0..=1, when the file carried them.
    pub colors: Option<Vec<[f32; 3]>>,
}

impl TriMesh {
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
