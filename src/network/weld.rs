//! Turning loose polylines into a network: points that coincide within a tolerance become one
//! node. Polyline formats (OBJ `l`, DXF) repeat shared endpoints; this is where they meet.

use std::collections::HashSet;
use std::hash::BuildHasherDefault;

use glam::DVec3;

use super::{Edge, Network, Node};
use crate::geom::merge::merge_points;
use crate::geom::{Aabb, KeyHasher};

/// How close two points must be to become one node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Weld {
    /// A distance in mm. 0 merges only identical points.
    Absolute(f64),
    /// A fraction of the bounding-box diagonal of all points read.
    Relative(f64),
}

impl Weld {
    /// The default: 1e-6 of the bounding-box diagonal.
    pub const DEFAULT: Weld = Weld::Relative(1e-6);

    pub fn tolerance_for(&self, bbox: &Aabb) -> f64 {
        match *self {
            Weld::Absolute(t) => t,
            Weld::Relative(f) => f * bbox.diagonal(),
        }
    }
}

impl Default for Weld {
    fn default() -> Self {
        Weld::DEFAULT
    }
}

/// What welding did, so an importer can report it rather than change topology silently.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct WeldStats {
    /// Tolerance used, in mm.
    pub tolerance: f64,
    /// Points read (vertices, polyline corners).
    pub points: usize,
    /// Points that landed on an earlier point and were merged into it.
    pub merged: usize,
    /// Segments whose two ends became one node (dropped).
    pub zero_length_segments: usize,
    /// Segments that repeat one already read between the same two nodes (dropped).
    pub duplicate_segments: usize,
}

/// Builds a network from points and segments between them (indices into `points`), merging
/// points within the weld tolerance. Nodes keep the order of first appearance; the first point
/// of a cluster gives the node its position. Deterministic.
pub fn assemble(points: &[DVec3], segments: &[(u32, u32)], weld: Weld) -> (Network, WeldStats) {
    let tol = weld.tolerance_for(&Aabb::from_points(points)).max(0.0);
    let (map, nodes) = merge_points(points, tol);
    let mut stats = WeldStats {
        tolerance: tol,
        points: points.len(),
        merged: points.len() - nodes.len(),
        ..Default::default()
    };
    let mut seen: FastSet<(u32, u32)> = FastSet::default();
    seen.reserve(segments.len());
    let mut edges = Vec::with_capacity(segments.len());
    for &(a, b) in segments {
        let (a, b) = (map[a as usize], map[b as usize]);
        if a == b {
            stats.zero_length_segments += 1;
        } else if !seen.insert((a.min(b), a.max(b))) {
            stats.duplicate_segments += 1;
        } else {
            edges.push(Edge::new(a, b));
        }
    }
    let network = Network {
        nodes: nodes.into_iter().map(Node::at).collect(),
        edges,
        ..Default::default()
    };
    (network, stats)
}

// Welding hashes every point read, and the default SipHash costs a third of a large import.
type FastSet<K> = HashSet<K, BuildHasherDefault<KeyHasher>>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_points_merge_far_points_stay() {
        let pts = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(10.0 + 5e-6, 0.0, 0.0), // within 1e-6 * diag
            DVec3::new(10.0, 10.0, 0.0),
            DVec3::new(10.0, 1e-3, 0.0), // far
        ];
        let (net, stats) = assemble(&pts, &[(0, 1), (2, 3), (3, 4)], Weld::DEFAULT);
        assert_eq!(net.nodes.len(), 4);
        assert_eq!(stats.merged, 1);
        assert_eq!(
            net.edges[1].a, 1,
            "second polyline starts on the first one's end"
        );
    }

    #[test]
    fn welding_drops_degenerate_and_repeated_segments() {
        let pts = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::X,
            DVec3::ZERO,
            DVec3::new(1.0, 1e-9, 0.0),
        ];
        let (net, stats) = assemble(
            &pts,
            &[(0, 1), (1, 2), (2, 3), (1, 4)],
            Weld::Absolute(1e-6),
        );
        assert_eq!(net.edges.len(), 1);
        assert_eq!(stats.zero_length_segments, 2);
        assert_eq!(stats.duplicate_segments, 1);
    }
}
