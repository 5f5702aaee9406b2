//! Turning loose polylines into a network: points that coincide within a tolerance become one
//! node. Polyline formats (OBJ `l`, DXF) repeat shared endpoints; this is where they meet.

use std::collections::{HashMap, HashSet};
use std::hash::BuildHasherDefault;

use glam::DVec3;

use super::{Edge, Network, Node};
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
type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<KeyHasher>>;
type FastSet<K> = HashSet<K, BuildHasherDefault<KeyHasher>>;

/// Maps each point to a node index. With cells of twice the tolerance, the ball of radius `tol`
/// around a point touches at most two cells per axis, so eight lookups find every candidate.
fn merge_points(points: &[DVec3], tol: f64) -> (Vec<u32>, Vec<DVec3>) {
    let mut map = Vec::with_capacity(points.len());
    let mut nodes: Vec<DVec3> = Vec::new();
    if tol == 0.0 {
        let mut exact: FastMap<[u64; 3], u32> = FastMap::default();
        exact.reserve(points.len());
        for p in points {
            let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            let id = *exact.entry(key).or_insert_with(|| {
                nodes.push(*p);
                nodes.len() as u32 - 1
            });
            map.push(id);
        }
        return (map, nodes);
    }
    let cell = 2.0 * tol;
    let mut grid: FastMap<[i64; 3], Vec<u32>> = FastMap::default();
    grid.reserve(points.len());
    for p in points {
        let q = *p / cell;
        let base = q.floor();
        // For each axis: this cell, and the neighbour on the side the point is nearer to.
        let step = (q - base).cmplt(glam::DVec3::splat(0.5));
        let side = [
            if step.test(0) { -1 } else { 1 },
            if step.test(1) { -1 } else { 1 },
            if step.test(2) { -1 } else { 1 },
        ];
        let key = [base.x as i64, base.y as i64, base.z as i64];
        let mut found = None;
        'search: for corner in 0..8 {
            let k = [
                key[0] + if corner & 1 != 0 { side[0] } else { 0 },
                key[1] + if corner & 2 != 0 { side[1] } else { 0 },
                key[2] + if corner & 4 != 0 { side[2] } else { 0 },
            ];
            if let Some(ids) = grid.get(&k) {
                for &id in ids {
                    if nodes[id as usize].distance_squared(*p) <= tol * tol {
                        found = Some(id);
                        break 'search;
                    }
                }
            }
        }
        let id = found.unwrap_or_else(|| {
            nodes.push(*p);
            let id = nodes.len() as u32 - 1;
            grid.entry(key).or_default().push(id);
            id
        });
        map.push(id);
    }
    (map, nodes)
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

    #[test]
    fn merge_finds_neighbours_across_cell_borders() {
        // Points straddling a cell boundary on every axis still merge.
        let tol = 0.1;
        let a = DVec3::splat(0.2 - 1e-9);
        let b = DVec3::splat(0.2 + 1e-9);
        let (map, nodes) = merge_points(&[a, b], tol);
        assert_eq!(nodes.len(), 1);
        assert_eq!(map, vec![0, 0]);
    }
}
