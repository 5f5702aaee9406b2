//! `bifurcate`: a tree by recursive bifurcation (two scaled, turned copies at every branch
//! end), then shaped (widths, façade, projection: [`branching::Shape`](super::branching)).
//!
//! ```
//! use lamina::stage::bifurcate;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let drawn = bifurcate::run(&bifurcate::Options { depth: 4, ..Default::default() })?;
//! assert_eq!(drawn.report.bifurcation.branches, 31);
//! # Ok(()) }
//! ```

use serde::Serialize;
use serde_json::json;

use super::branching::{shape, Sections, Shape, ShapeError};
use crate::grow::bifurcation::{bifurcate, BifurcationError, BifurcationOptions};
pub use crate::grow::tree::Span;
use crate::Network;

/// The tree. `Default` is the command's defaults.
#[derive(Clone, Debug)]
pub struct Options {
    /// Generations of forks after the trunk. Default 6.
    pub depth: u32,
    /// Trunk length, mm. Default 2000.
    pub length: f64,
    /// Angle of each branch from its parent, degrees (or a range drawn per branch). Default
    /// 25.
    pub angle: Span,
    /// Length of a branch over its parent's (or a range). Default 0.75.
    pub scale: Span,
    /// Trunk radius, mm. Default 60.
    pub radius: f64,
    /// Radius factor per generation. Default 0.8.
    pub radius_scale: f64,
    /// Grow in 3D: each fork's plane turns this many degrees about its parent. Default: flat.
    pub roll: Option<f64>,
    /// Default 1.
    pub seed: u64,
    /// What happens to the drawn tree.
    pub shape: Shape,
}

impl Default for Options {
    fn default() -> Self {
        let b = BifurcationOptions::default();
        Options {
            depth: b.depth,
            length: b.length,
            angle: b.angle,
            scale: b.scale,
            radius: b.radius,
            radius_scale: b.radius_scale,
            roll: b.roll,
            seed: 1,
            shape: Shape::default(),
        }
    }
}

/// Why nothing was drawn.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// The tree refused.
    Bifurcation(#[from] BifurcationError),
    #[error(transparent)]
    /// Shaping failed.
    Shape(#[from] ShapeError),
}

/// The tree's own figures.
#[derive(Clone, Debug, Serialize)]
pub struct Figures {
    /// Branches.
    pub branches: usize,
    /// Section depth (the panel height across the member), mm.
    pub depth: u32,
}

/// The report: the tree's figures and the common sections. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The tree's figures.
    pub bifurcation: Figures,
    #[serde(flatten)]
    /// The sections shared with the other generators.
    pub sections: Sections,
}

/// The drawn tree and its report.
#[derive(Clone, Debug)]
pub struct Drawn {
    /// The network made.
    pub network: Network,
    /// The report, as the command writes it.
    pub report: Report,
}

/// Grows and shapes the tree.
pub fn run(opts: &Options) -> Result<Drawn, Error> {
    let b = BifurcationOptions {
        depth: opts.depth,
        length: opts.length,
        angle: opts.angle,
        scale: opts.scale,
        radius: opts.radius,
        radius_scale: opts.radius_scale,
        roll: opts.roll,
    };
    let tree = bifurcate(&b, opts.seed)?;
    let figures = Figures {
        branches: tree.network.edges.len(),
        depth: b.depth,
    };
    let (mut network, sections) = shape(tree, b.radius / 8.0, &opts.shape)?;
    network.meta.generator = Some("bifurcation".into());
    network.meta.seed = Some(opts.seed);

    for (k, v) in [
        ("depth", json!(b.depth)),
        ("length", json!(b.length)),
        ("angle_deg", json!([b.angle.min, b.angle.max])),
        ("scale", json!([b.scale.min, b.scale.max])),
        ("roll_deg", json!(b.roll)),
    ] {
        network.meta.parameters.insert(k.into(), v);
    }
    Ok(Drawn {
        network,
        report: Report {
            bifurcation: figures,
            sections,
        },
    })
}
