//! Turning loose polylines into a network: points that coincide within a tolerance become one
//! node. Polyline formats (OBJ `l`, DXF) repeat shared endpoints; this is where they meet.

use glam::DVec3;
use rayon::prelude::*;

use super::{Edge, Network, Node};
use crate::geom::merge::merge_points;
use crate::geom::Aabb;

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
    // Node pairs in the direction drawn.
    let ends: Vec<(u32, u32)> = segments
        .par_iter()
        .map(|&(a, b)| (map[a as usize], map[b as usize]))
        .collect();
    let repeated = repeated_segments(&ends, nodes.len());
    let mut edges = Vec::with_capacity(segments.len());
    for (k, &(a, b)) in ends.iter().enumerate() {
        if a == b {
            stats.zero_length_segments += 1;
        } else if repeated[k] {
            stats.duplicate_segments += 1;
        } else {
            edges.push(Edge::new(a, b)); // in the direction drawn
        }
    }
    let network = Network {
        nodes: nodes.into_par_iter().map(Node::at).collect(),
        edges,
        ..Default::default()
    };
    (network, stats)
}

/// Marks every segment whose two nodes, in either order, an earlier segment already joins.
/// Segments are grouped by their lower end with a counting sort (node order follows the
/// drawing, so this reads memory nearly in order); a group is sorted only when it has more
/// than one member.
fn repeated_segments(ends: &[(u32, u32)], nodes: usize) -> Vec<bool> {
    let lower = |&(a, b): &(u32, u32)| (a.min(b), a.max(b));
    let mut start = vec![0u32; nodes + 1];
    for (a, b) in ends.iter().map(lower) {
        if a != b {
            start[a as usize + 1] += 1;
        }
    }
    for k in 1..start.len() {
        start[k] += start[k - 1];
    }
    let mut fill = start.clone();
    let mut by_lower = vec![0u32; start[nodes] as usize];
    for (k, (a, b)) in ends.iter().map(lower).enumerate() {
        if a != b {
            by_lower[fill[a as usize] as usize] = k as u32;
            fill[a as usize] += 1;
        }
    }
    let mut repeated = vec![false; ends.len()];
    let mut group: Vec<(u32, u32)> = Vec::new();
    for a in 0..nodes {
        let members = &by_lower[start[a] as usize..start[a + 1] as usize];
        if members.len() < 2 {
            continue;
        }
        group.clear();
        group.extend(members.iter().map(|&k| (lower(&ends[k as usize]).1, k)));
        group.sort_unstable();
        for pair in group.windows(2) {
            if pair[0].0 == pair[1].0 {
                repeated[pair[1].1 as usize] = true;
            }
        }
    }
    repeated
}

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
