//! The figures a simplification report gives for a network, and the exact distance of points
//! from a network's members.

use glam::DVec3;
use rstar::{PointDistance, RTree, RTreeObject, AABB};

use crate::geom::point_segment_distance as point_segment;
use crate::network::Network;
use crate::rationalize::cells::euler;

/// A network's figures for fabrication.
#[derive(Clone, Debug, serde::Serialize, PartialEq)]
pub struct Figures {
    /// Nodes with at least one member.
    pub nodes: usize,
    pub members: usize,
    pub shortest_member: f64,
    pub longest_member: f64,
    pub total_length: f64,
    /// The smallest angle between two members at a node, degrees (none without such a node).
    pub smallest_joint_angle: Option<f64>,
    pub max_degree: usize,
    pub components: usize,
    /// Independent cycles: members − nodes + components.
    pub cycles: usize,
    /// Faces of the network drawn on its surface (from the rotation of members about each
    /// node's normal) and V − E + F; none where normals are not known.
    pub faces: Option<usize>,
    pub euler: Option<i64>,
}

impl Figures {
    pub fn of(net: &Network, normals: Option<&[DVec3]>) -> Figures {
        let adj = net.adjacency();
        let n = net.nodes.len() as u32;
        let used = (0..n).filter(|&v| adj.degree(v) > 0).count();
        let lengths = net.lengths();
        let (_, components) = net.component_labels();
        let isolated = net.nodes.len() - used;
        let components = components - isolated;
        let faces = normals.and_then(|normals| {
            let positions: Vec<DVec3> = net.nodes.iter().map(|p| p.p).collect();
            let edges: Vec<[u32; 2]> = net.edges.iter().map(|e| [e.a, e.b]).collect();
            euler(&positions, &edges, normals).ok()
        });
        Figures {
            nodes: used,
            members: net.edges.len(),
            shortest_member: lengths.map_or(0.0, |l| l.min),
            longest_member: lengths.map_or(0.0, |l| l.max),
            total_length: lengths.map_or(0.0, |l| l.total),
            smallest_joint_angle: joint_angles(net)
                .into_iter()
                .map(|(_, a)| a)
                .min_by(f64::total_cmp),
            max_degree: (0..n).map(|v| adj.degree(v)).max().unwrap_or(0),
            components,
            cycles: (net.edges.len() + components).saturating_sub(used),
            faces: faces.map(|e| e.faces),
            euler: faces.map(|e| e.chi),
        }
    }
}

/// Per node with two members or more: the smallest angle between two of them, degrees.
pub fn joint_angles(net: &Network) -> Vec<(u32, f64)> {
    let adj = net.adjacency();
    (0..net.nodes.len() as u32)
        .filter(|&v| adj.degree(v) >= 2)
        .map(|v| {
            let p = net.nodes[v as usize].p;
            let dirs: Vec<DVec3> = adj
                .neighbours(v)
                .iter()
                .map(|&(w, _)| (net.nodes[w as usize].p - p).normalize_or_zero())
                .collect();
            let mut least = 180.0f64;
            for i in 0..dirs.len() {
                for j in i + 1..dirs.len() {
                    least = least.min(dirs[i].dot(dirs[j]).clamp(-1.0, 1.0).acos().to_degrees());
                }
            }
            (v, least)
        })
        .collect()
}

struct Segment {
    a: DVec3,
    b: DVec3,
}

impl RTreeObject for Segment {
    type Envelope = AABB<[f64; 3]>;
    fn envelope(&self) -> Self::Envelope {
        AABB::from_corners(self.a.min(self.b).to_array(), self.a.max(self.b).to_array())
    }
}

impl PointDistance for Segment {
    fn distance_2(&self, p: &[f64; 3]) -> f64 {
        point_segment(DVec3::from_array(*p), self.a, self.b).powi(2)
    }
}

/// Each point's distance from the nearest member of `net` (infinite when it has none).
pub fn distance_to(net: &Network, points: &[DVec3]) -> Vec<f64> {
    let tree = RTree::bulk_load(
        net.edges
            .iter()
            .map(|e| Segment {
                a: net.nodes[e.a as usize].p,
                b: net.nodes[e.b as usize].p,
            })
            .collect(),
    );
    points
        .iter()
        .map(|p| {
            tree.nearest_neighbor(&p.to_array())
                .map_or(f64::INFINITY, |s| point_segment(*p, s.a, s.b))
        })
        .collect()
}
