//! `simplify`: fewer, straighter members for fabrication (chains to the fewest straight
//! members within a deviation, junctions merged, branches pruned, sharp joints repaired), with
//! a report before and after.
//!
//! ```
//! use lamina::stage::simplify;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/calyx_veins.json"))?;
//! let done = simplify::run(&net, None, &simplify::Options { max_deviation: Some(10.0), ..Default::default() })?;
//! assert!(done.simplified.report.after.members < done.simplified.report.before.members);
//! # Ok(()) }
//! ```

use crate::rationalize::simplify::{self as algorithm, SimplifyError};
pub use crate::rationalize::simplify::{Figures, Report, Simplified};
use crate::{Network, TriMesh};

/// How far to simplify. `Default` is the command's defaults.
#[derive(Clone, Debug)]
pub struct Options {
    /// Every original node stays within this of the simplified network, mm. Default: the
    /// input's mean edge length (said in the notes).
    pub max_deviation: Option<f64>,
    /// Members shorter than this are removed where they can be, mm. Default 0 (off).
    pub min_length: f64,
    /// Junctions joined by a chain shorter than this merge, mm. Default 0 (off).
    pub merge_distance: f64,
    /// Joints under this angle are repaired or reported, degrees. Default 30.
    pub min_angle: f64,
    /// Branches of Horton-Strahler order below this are removed. Default 0 (off).
    pub prune_order: u32,
}

impl Default for Options {
    fn default() -> Self {
        let d = algorithm::Options::default();
        Options {
            max_deviation: None,
            min_length: d.min_length,
            merge_distance: d.merge_distance,
            min_angle: 30.0,
            prune_order: d.prune_order,
        }
    }
}

/// The simplified network and what was defaulted.
#[derive(Clone, Debug)]
pub struct Done {
    /// The simplified network.
    pub simplified: Simplified,
    /// Defaults taken that change the result, one line each.
    pub notes: Vec<String>,
}

/// Why nothing was simplified.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("surface= has no triangles")]
    /// The surface has no triangles.
    EmptySurface,
    #[error(transparent)]
    /// Simplification failed.
    Simplify(#[from] SimplifyError),
}

/// Simplifies `net`; moved and merged nodes stay on `surface` when given, and its normals
/// order the members around each node.
pub fn run(net: &Network, surface: Option<&TriMesh>, opts: &Options) -> Result<Done, Error> {
    let mut notes = Vec::new();
    let max_deviation = match opts.max_deviation {
        Some(d) => d,
        None => {
            let mean = net.lengths().map_or(1.0, |l| l.mean);
            notes.push(format!(
                "max_deviation= not given: {mean:.4} mm, the input's mean edge length"
            ));
            mean
        }
    };
    let o = algorithm::Options {
        max_deviation,
        min_length: opts.min_length,
        merge_distance: opts.merge_distance,
        min_angle: opts.min_angle,
        prune_order: opts.prune_order,
    };
    o.check()?;
    if surface.is_some_and(|m| m.triangles.is_empty()) {
        return Err(Error::EmptySurface);
    }
    let simplified = algorithm::simplify(net, surface, &o)?;
    Ok(Done { simplified, notes })
}
