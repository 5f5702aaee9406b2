//! A drawn tree (from an L-system or recursive bifurcation): a network whose every edge runs
//! from a parent node to the child it created (`parent[e.b] == Some(e.a)`), nodes in the order
//! drawn, so parents come before their children.

use std::str::FromStr;

use glam::DVec3;
use rand::Rng;

use crate::network::{Edge, Network, Node};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tree {
    pub network: Network,
    /// Each node's parent; None for a node a segment started from without one (the root, and
    /// the start of a segment after a move without drawing).
    pub parent: Vec<Option<u32>>,
}

impl Tree {
    /// Widths by Murray's law instead of by depth: tips take `tip`, a parent r^n = Σ r_child^n;
    /// an edge takes its child's radius.
    pub fn murray(&mut self, exponent: f64, tip: f64) {
        let radius = super::murray::radii(&self.parent, exponent, tip);
        for (node, r) in self.network.nodes.iter_mut().zip(&radius) {
            node.radius = *r;
        }
        for e in &mut self.network.edges {
            e.radius = radius[e.b as usize];
        }
    }

    /// Adds a node at `p`, and the edge to it from `parent` when there is one, both of
    /// `radius`; returns the node.
    pub fn add(&mut self, p: DVec3, parent: Option<u32>, radius: f64) -> u32 {
        let n = self.network.nodes.len() as u32;
        self.network.nodes.push(Node {
            p,
            normal: None,
            radius,
        });
        self.parent.push(parent);
        if let Some(a) = parent {
            self.network.edges.push(Edge { a, b: n, radius });
        }
        n
    }

    /// Checks the tree invariant: edges run parent to child. For tests.
    pub fn is_consistent(&self) -> bool {
        self.parent.len() == self.network.nodes.len()
            && self
                .network
                .edges
                .iter()
                .all(|e| self.parent.get(e.b as usize) == Some(&Some(e.a)) && e.a < e.b)
    }
}

/// A number, fixed (`min == max`) or drawn uniformly from `min..=max` each time it is used.
/// Written `22` or `15..30`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Span {
    pub min: f64,
    pub max: f64,
}

impl Span {
    pub fn fixed(v: f64) -> Span {
        Span { min: v, max: v }
    }

    pub fn is_range(&self) -> bool {
        self.min != self.max
    }

    /// The fixed value, or a uniform draw (a fixed value draws nothing from `rng`).
    pub fn draw(&self, rng: &mut impl Rng) -> f64 {
        if self.is_range() {
            rng.random_range(self.min..=self.max)
        } else {
            self.min
        }
    }
}

impl FromStr for Span {
    type Err = String;

    fn from_str(s: &str) -> Result<Span, String> {
        let num = |t: &str| -> Result<f64, String> {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("`{}` is not a number", t.trim()))
        };
        let span = match s.split_once("..") {
            Some((lo, hi)) => Span {
                min: num(lo)?,
                max: num(hi)?,
            },
            None => Span::fixed(num(s)?),
        };
        if span.min > span.max {
            return Err(format!("`{s}`: a range is written min..max with min ≤ max"));
        }
        Ok(span)
    }
}
