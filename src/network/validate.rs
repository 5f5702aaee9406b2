//! `Network::validate`: every problem at once, plus the figures a designer checks first
//! (degree histogram, connected components, independent cycles).

use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::fmt;
use std::hash::BuildHasherDefault;

use super::Network;
use crate::geom::KeyHasher;

/// Edges shorter than this fraction of the bounding-box diagonal count as zero-length.
pub const ZERO_LENGTH_FRACTION: f64 = 1e-12;

/// One thing wrong with a network, naming the node or edge.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Problem {
    NonFinitePosition {
        node: u32,
    },
    NonFiniteNormal {
        node: u32,
    },
    BadNodeRadius {
        node: u32,
        radius: f64,
    },
    EdgeOutOfRange {
        edge: u32,
        a: u32,
        b: u32,
        nodes: usize,
    },
    SelfLoop {
        edge: u32,
        node: u32,
    },
    RepeatedEdge {
        edge: u32,
        first: u32,
    },
    ZeroLength {
        edge: u32,
        length: f64,
    },
    BadEdgeRadius {
        edge: u32,
        radius: f64,
    },
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Problem::NonFinitePosition { node } => {
                write!(f, "node {node}: position is not finite (NaN or infinite)")
            }
            Problem::NonFiniteNormal { node } => {
                write!(f, "node {node}: normal is not finite or has zero length")
            }
            Problem::BadNodeRadius { node, radius } => {
                write!(f, "node {node}: radius {radius} is negative or not finite")
            }
            Problem::EdgeOutOfRange { edge, a, b, nodes } => write!(
                f,
                "edge {edge}: joins nodes {a} and {b}, but there are only {nodes} nodes"
            ),
            Problem::SelfLoop { edge, node } => {
                write!(f, "edge {edge}: self-loop at node {node}")
            }
            Problem::RepeatedEdge { edge, first } => {
                write!(f, "edge {edge}: repeats edge {first} (same two nodes)")
            }
            Problem::ZeroLength { edge, length } => {
                write!(f, "edge {edge}: zero length ({length:e} mm)")
            }
            Problem::BadEdgeRadius { edge, radius } => {
                write!(f, "edge {edge}: radius {radius} is negative or not finite")
            }
        }
    }
}

/// The result of `Network::validate`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Validation {
    /// Every problem found, in node then edge order.
    pub problems: Vec<Problem>,
    /// `degree_histogram[d]` = number of nodes of degree d (over in-range edges).
    pub degree_histogram: Vec<usize>,
    /// Connected components, isolated nodes included.
    pub components: usize,
    /// Independent cycles (cyclomatic number E − V + C) of the simple graph: self-loops and
    /// repeated edges are left out, so this counts the loops a designer sees.
    pub cycles: usize,
}

impl Validation {
    pub fn is_ok(&self) -> bool {
        self.problems.is_empty()
    }
}

impl Network {
    /// Checks the network and returns every problem found (not only the first) with the
    /// degree histogram, components and independent cycles.
    pub fn validate(&self) -> Validation {
        let mut problems = Vec::new();
        for (i, n) in self.nodes.iter().enumerate() {
            let node = i as u32;
            if !n.p.is_finite() {
                problems.push(Problem::NonFinitePosition { node });
            }
            if let Some(nm) = n.normal {
                if !nm.is_finite() || nm.length_squared() == 0.0 {
                    problems.push(Problem::NonFiniteNormal { node });
                }
            }
            if !(n.radius.is_finite() && n.radius >= 0.0) {
                problems.push(Problem::BadNodeRadius {
                    node,
                    radius: n.radius,
                });
            }
        }
        let nodes = self.nodes.len();
        let min_length = ZERO_LENGTH_FRACTION * self.bbox().diagonal();
        // Keyed by the edge's two nodes, lower first, in one word.
        let mut first_seen: HashMap<u64, u32, BuildHasherDefault<KeyHasher>> =
            HashMap::with_capacity_and_hasher(self.edges.len(), Default::default());
        let mut simple_edges = 0usize;
        for (k, e) in self.edges.iter().enumerate() {
            let edge = k as u32;
            if !(e.radius.is_finite() && e.radius >= 0.0) {
                problems.push(Problem::BadEdgeRadius {
                    edge,
                    radius: e.radius,
                });
            }
            if e.a as usize >= nodes || e.b as usize >= nodes {
                problems.push(Problem::EdgeOutOfRange {
                    edge,
                    a: e.a,
                    b: e.b,
                    nodes,
                });
                continue;
            }
            if e.a == e.b {
                problems.push(Problem::SelfLoop { edge, node: e.a });
                continue;
            }
            let key = (e.a.min(e.b) as u64) << 32 | e.a.max(e.b) as u64;
            match first_seen.entry(key) {
                Entry::Occupied(first) => {
                    problems.push(Problem::RepeatedEdge {
                        edge,
                        first: *first.get(),
                    });
                    continue;
                }
                Entry::Vacant(slot) => {
                    slot.insert(edge);
                }
            }
            simple_edges += 1;
            let length = self.edge_length(e);
            if length <= min_length {
                problems.push(Problem::ZeroLength { edge, length });
            }
        }
        let adj = self.adjacency();
        let mut degree_histogram = Vec::new();
        for v in 0..nodes as u32 {
            let d = adj.degree(v);
            if degree_histogram.len() <= d {
                degree_histogram.resize(d + 1, 0);
            }
            degree_histogram[d] += 1;
        }
        let (_, components) = self.component_labels();
        // Self-loops and repeats never join components, so C is the same for the simple graph.
        let cycles = (simple_edges + components).saturating_sub(nodes);
        Validation {
            problems,
            degree_histogram,
            components,
            cycles,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Edge, Network, Node};
    use super::*;
    use glam::DVec3;

    #[test]
    fn finds_every_problem_not_only_the_first() {
        let mut net = Network {
            nodes: vec![
                Node::at(DVec3::ZERO),
                Node::at(DVec3::X),
                Node::at(DVec3::Y),
                Node::at(DVec3::new(f64::NAN, 0.0, 0.0)),
                Node::at(DVec3::Y),
            ],
            edges: vec![
                Edge::new(0, 1),
                Edge::new(1, 2),
                Edge::new(2, 0),
                Edge::new(1, 0),
                Edge::new(2, 2),
                Edge::new(0, 9),
                Edge::new(2, 4),
            ],
            ..Default::default()
        };
        net.edges[1].radius = -1.0;
        let v = net.validate();
        assert_eq!(
            v.problems,
            vec![
                Problem::NonFinitePosition { node: 3 },
                Problem::BadEdgeRadius {
                    edge: 1,
                    radius: -1.0
                },
                Problem::RepeatedEdge { edge: 3, first: 0 },
                Problem::SelfLoop { edge: 4, node: 2 },
                Problem::EdgeOutOfRange {
                    edge: 5,
                    a: 0,
                    b: 9,
                    nodes: 5
                },
                Problem::ZeroLength {
                    edge: 6,
                    length: 0.0
                },
            ]
        );
        // Triangle 0-1-2 plus 2-4: one cycle; node 3 isolated: two components.
        assert_eq!(v.cycles, 1);
        assert_eq!(v.components, 2);
        // degrees: 0:3 (0-1,2-0,1-0), 1:3, 2:5 (1-2,2-0,self-loop twice,2-4), 3:0, 4:1
        assert_eq!(v.degree_histogram, vec![1, 1, 0, 2, 0, 1]);
    }

    #[test]
    fn a_tree_has_no_cycles() {
        let net = Network {
            nodes: (0..4)
                .map(|i| Node::at(DVec3::new(i as f64, 0.0, 0.0)))
                .collect(),
            edges: vec![Edge::new(0, 1), Edge::new(1, 2), Edge::new(1, 3)],
            ..Default::default()
        };
        let v = net.validate();
        assert!(v.is_ok());
        assert_eq!(v.cycles, 0);
        assert_eq!(v.components, 1);
    }
}
