//! `TriMesh::weld`: corners closer than a tolerance become one vertex, for CAD meshes whose
//! shared corners differ in their last bits and so read as open.

use super::TriMesh;
use crate::geom::merge::merge_points;

/// What a weld did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct MeshWeld {
    /// Tolerance used, in mm.
    pub tolerance: f64,
    /// Vertices merged into an earlier one.
    pub merged: usize,
    /// Triangles dropped because two of their corners became one vertex.
    pub collapsed_triangles: usize,
}

impl TriMesh {
    /// Joins vertices within `tol` mm of an earlier one (the earliest keeps its position and
    /// colour) and drops the triangles that collapse. Deterministic: vertices keep the order of
    /// first appearance.
    pub fn weld(&mut self, tol: f64) -> MeshWeld {
        let (map, positions) = merge_points(&self.positions, tol.max(0.0));
        let mut first = vec![u32::MAX; positions.len()];
        for (old, &new) in map.iter().enumerate() {
            if first[new as usize] == u32::MAX {
                first[new as usize] = old as u32;
            }
        }
        if let Some(colors) = &self.colors {
            self.colors = Some(first.iter().map(|&o| colors[o as usize]).collect());
        }
        let before = self.triangles.len();
        self.triangles = self
            .triangles
            .iter()
            .map(|t| t.map(|i| map[i as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        let stats = MeshWeld {
            tolerance: tol,
            merged: self.positions.len() - positions.len(),
            collapsed_triangles: before - self.triangles.len(),
        };
        self.positions = positions;
        stats
    }
}

impl TriMesh {
    /// Removes triangles that use a vertex twice or have no area (twice the area below 1e-12 of
    /// the longest side squared: three corners on a line, whatever the scale): they have no
    /// normal and no closest point, so they must not reach a surface query. Returns how many
    /// were removed.
    pub fn drop_degenerate(&mut self) -> usize {
        let before = self.triangles.len();
        let positions = &self.positions;
        self.triangles.retain(|t| {
            let distinct = t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let twice_area = (b - a).cross(c - a).length();
            let longest = (b - a)
                .length_squared()
                .max((c - b).length_squared())
                .max((a - c).length_squared());
            distinct && twice_area.is_finite() && twice_area > 1e-12 * longest
        });
        before - self.triangles.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn degenerate_triangles_are_dropped() {
        let mut m = TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X * 2.0],
            triangles: vec![[0, 1, 2], [0, 0, 1], [0, 1, 3]],
            colors: None,
        };
        assert_eq!(m.drop_degenerate(), 2);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn near_corners_join_and_collapsed_triangles_go() {
        let mut m = TriMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::Y,
                DVec3::new(1.0 + 1e-7, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1e-7, 0.0),
            ],
            triangles: vec![[0, 1, 2], [3, 4, 2], [0, 5, 1]],
            colors: None,
        };
        let w = m.weld(1e-6);
        assert_eq!((w.merged, w.collapsed_triangles), (2, 1));
        assert_eq!(m.triangles, vec![[0, 1, 2], [1, 3, 2]]);
        assert_eq!(m.check_manifold().boundary_edges, 4);
    }
}
