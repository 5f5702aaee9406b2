//! The `Network`: a graph of nodes and edges in 3D, millimetres. Every generator produces one,
//! every importer reads one, every later stage takes one.
//!
//! Adjacency is built on demand (`adjacency()`, CSR). `validate()` finds every problem at once.

pub mod arrangement;
pub mod io;
mod topology;
mod validate;
mod weld;

use std::collections::BTreeMap;

use glam::DVec3;

use crate::geom::Aabb;

pub use topology::{Adjacency, Chain};
pub use validate::{Problem, Validation};
pub use weld::{Weld, WeldStats};

/// A node: a position, an optional surface normal (the reference direction later stages need),
/// and a radius in mm (0 when unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    pub p: DVec3,
    pub normal: Option<DVec3>,
    pub radius: f64,
}

impl Node {
    pub fn at(p: DVec3) -> Self {
        Node {
            p,
            normal: None,
            radius: 0.0,
        }
    }
}

/// An undirected edge between nodes `a` and `b`, with a radius in mm (0 when unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    pub a: u32,
    pub b: u32,
    pub radius: f64,
}

impl Edge {
    pub fn new(a: u32, b: u32) -> Self {
        Edge { a, b, radius: 0.0 }
    }
}

/// Where a network came from: units, generator, its parameters and seed, free-form tags.
#[derive(Clone, Debug, PartialEq)]
pub struct Meta {
    /// Always "mm" for networks lamina makes; kept so a file says what it holds.
    pub units: String,
    pub generator: Option<String>,
    pub parameters: BTreeMap<String, serde_json::Value>,
    pub seed: Option<u64>,
    pub tags: BTreeMap<String, String>,
}

impl Default for Meta {
    fn default() -> Self {
        Meta {
            units: "mm".to_string(),
            generator: None,
            parameters: BTreeMap::new(),
            seed: None,
            tags: BTreeMap::new(),
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Network {
    pub nodes: Vec<Node>,
    pub edges: Vec<Edge>,
    pub meta: Meta,
}

/// Summary figures of a network's edges, in mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lengths {
    pub total: f64,
    pub min: f64,
    pub max: f64,
    pub mean: f64,
}

impl Network {
    /// Bounding box of the node positions (finite ones only).
    pub fn bbox(&self) -> Aabb {
        let mut b = Aabb::empty();
        for n in &self.nodes {
            if n.p.is_finite() {
                b.extend(n.p);
            }
        }
        b
    }

    /// Length of edge `e`. The edge must be in range.
    pub fn edge_length(&self, e: &Edge) -> f64 {
        self.nodes[e.a as usize]
            .p
            .distance(self.nodes[e.b as usize].p)
    }

    /// Edge length figures over the edges whose ends are in range; `None` with no such edge.
    pub fn lengths(&self) -> Option<Lengths> {
        let n = self.nodes.len() as u32;
        let mut count = 0usize;
        let (mut total, mut min, mut max) = (0.0, f64::INFINITY, 0.0f64);
        for e in self.edges.iter().filter(|e| e.a < n && e.b < n) {
            let l = self.edge_length(e);
            total += l;
            min = min.min(l);
            max = max.max(l);
            count += 1;
        }
        (count > 0).then(|| Lengths {
            total,
            min,
            max,
            mean: total / count as f64,
        })
    }
}
