//! `veins`: geodesic veins along the edges of a mesh (Bachman), from a root vertex to given or
//! sampled source vertices, with radii from the sources each edge carries.
//!
//! ```
//! use lamina::stage::{veins, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/surfaces/torus.obj");
//! let mesh = lamina::mesh::io::read_mesh(std::path::Path::new(path))?;
//! let grown = veins::run(&mesh, &veins::Options { sources: Some(50), ..Default::default() }, &Quiet)?;
//! // About 50 sources, Poisson-disk on the torus, each reached along mesh edges.
//! assert!((40..=60).contains(&grown.report.sources));
//! assert!(grown.report.tree_vertices > grown.report.sources);
//! # Ok(()) }
//! ```

use serde::Serialize;

use crate::grow::geodesic::{self, grow_veins, Incremental, MeshGraph, VeinError, VeinOptions};
pub use crate::grow::surface::Channel;
use crate::grow::surface::{self as on_surface, SurfaceError};
use crate::stage::{checkpoint, Cancelled, OptionError, Progress};
use crate::{Network, TriMesh};

/// Sources sampled when none are given.
pub const DEFAULT_SOURCES: usize = 300;

/// The most points `smooth` adds per mesh edge of a vein.
pub const MAX_SMOOTH: usize = 64;

/// How the veins grow. `Default` is the command's defaults.
#[derive(Clone, Debug)]
pub struct Options {
    /// Source vertices. Default: sampled.
    pub source: Vec<u32>,
    /// Sample about this many sources, Poisson-disk on the surface. Default 300.
    pub sources: Option<usize>,
    /// Sample sources by this vertex colour (dark = dense). Default: none.
    pub density_channel: Option<Channel>,
    /// Root vertex. Default: the lowest vertex.
    pub root: Option<u32>,
    /// Radius of a vein carrying one source, mm. Default 0.08 × the mean edge length.
    pub tip_radius: Option<f64>,
    /// Taper exponent n: r = tip × (sources carried)^(1/n). Default 3.
    pub murray: f64,
    /// Catmull-Rom points added between neighbouring vertices of a branch. Default 0.
    pub smooth: usize,
    /// Seed of the sampled sources. Default 1.
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            source: Vec::new(),
            sources: None,
            density_channel: None,
            root: None,
            tip_radius: None,
            murray: 3.0,
            smooth: 0,
            seed: 1,
        }
    }
}

/// The veins and their report.
#[derive(Clone, Debug)]
pub struct Grown {
    /// The network made.
    pub network: Network,
    /// The report, as the command writes it.
    pub report: Report,
}

/// The veins' report. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Edges (members).
    pub edges: usize,
    /// Growth steps (or solver iterations) taken.
    pub iterations: usize,
    /// Nodes.
    pub nodes: usize,
    /// The file the network was written to (set by the command line).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
    /// Shortest-path labels updated.
    pub relabelled: usize,
    /// Root vertex.
    pub root: u32,
    /// Radius at the root, mm.
    pub root_radius: Option<f64>,
    /// Sources reached.
    pub sources: usize,
    /// Sampled sources no mesh edge path reaches from the root.
    pub sources_unreachable_skipped: usize,
    /// The surface's name (set by the command line: its path).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface: Option<String>,
    /// Vertices on the tree.
    pub tree_vertices: usize,
}

/// Why no veins grew.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(transparent)]
    /// The veins failed.
    Veins(#[from] VeinError),
    #[error(transparent)]
    /// Growth on the surface failed.
    Surface(#[from] SurfaceError),
    #[error(transparent)]
    /// The caller stopped the stage.
    Cancelled(#[from] Cancelled),
}

/// Grows the veins on `mesh`. `progress` can stop it before the tree is grown and before it is
/// made a network.
pub fn run(mesh: &TriMesh, opts: &Options, progress: &dyn Progress) -> Result<Grown, Error> {
    if opts.smooth > MAX_SMOOTH {
        return Err(OptionError::new(
            "smooth",
            format!("{}: at most {MAX_SMOOTH} points per span", opts.smooth),
        )
        .into());
    }
    progress.begin("veins", None);
    let graph = MeshGraph::new(mesh);
    let root = match opts.root {
        Some(r) => r,
        None => on_surface::lowest_vertex(mesh).ok_or(SurfaceError::NoTriangles)?,
    };
    if root as usize >= mesh.positions.len() {
        return Err(OptionError::new(
            "root",
            format!("{root}: the mesh has {} vertices", mesh.positions.len()),
        )
        .into());
    }
    let (sources, skipped) = if opts.source.is_empty() {
        let want = opts.sources.unwrap_or(DEFAULT_SOURCES);
        if want == 0 {
            return Err(OptionError::new("sources", "must be at least 1").into());
        }
        // Sources are vertices: more than the mesh has only repeats them, at a cost.
        if want > mesh.positions.len() {
            return Err(OptionError::new(
                "sources",
                format!(
                    "{want}: the mesh has only {} vertices to be sources",
                    mesh.positions.len()
                ),
            )
            .into());
        }
        let sampled =
            geodesic::sample_sources(mesh, &graph, root, want, opts.density_channel, opts.seed)?;
        (sampled.vertices, sampled.skipped)
    } else {
        (opts.source.clone(), 0)
    };
    checkpoint(progress)?;
    let tree = grow_veins(&graph, &mesh.positions, root, &sources, &mut Incremental)?;
    checkpoint(progress)?;
    let tip = opts
        .tip_radius
        .unwrap_or_else(|| 0.08 * on_surface::mean_edge_length(mesh));
    let vein_opts = VeinOptions {
        tip_radius: tip,
        murray: opts.murray,
        smooth: opts.smooth,
    };
    let mut network = geodesic::to_network(mesh, &tree, &vein_opts)?;
    network.meta.parameters.insert("root".into(), root.into());
    network.meta.seed = Some(opts.seed);
    let report = Report {
        edges: network.edges.len(),
        iterations: tree.iterations,
        nodes: network.nodes.len(),
        output: None,
        relabelled: tree.relabelled,
        root,
        root_radius: network.nodes.first().map(|n| n.radius),
        sources: tree.sources.len(),
        sources_unreachable_skipped: skipped,
        surface: None,
        tree_vertices: tree.order.len(),
    };
    Ok(Grown { network, report })
}
