//! `lamina veins --surface MESH`: geodesic veins along mesh edges (Bachman), from a root
//! vertex to given or sampled source vertices.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use super::surface::{read_surface, write_outputs};
use super::venation::{write_json, ChannelArg};
use lamina::grow::geodesic::{self, grow_veins, Incremental, MeshGraph, VeinOptions};
use lamina::grow::surface::{self, Channel};

#[derive(ClapArgs)]
pub struct Args {
    /// The mesh (.obj .stl) the veins follow
    #[arg(long, value_name = "MESH")]
    pub surface: PathBuf,
    #[command(flatten)]
    pub weld: super::surface::SurfaceWeld,
    /// Output network (.json .obj .dxf .svg; .png renders the veins on the surface)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Source vertex (repeat for several)
    #[arg(long = "source", value_name = "V", conflicts_with = "sources")]
    pub source: Vec<u32>,
    /// Sample about this many source vertices, Poisson-disk on the surface [default: 300]
    #[arg(long, value_name = "N")]
    pub sources: Option<usize>,
    /// Sample sources by this vertex colour (dark = dense: the lightest spacing is twice the
    /// darkest)
    #[arg(long, value_enum, conflicts_with = "source")]
    pub density_channel: Option<ChannelArg>,
    /// Root vertex [default: the lowest vertex]
    #[arg(long, value_name = "V")]
    pub root: Option<u32>,
    /// Radius of a vein carrying one source, mm [default: 0.08 × the mean edge length]
    #[arg(long)]
    pub tip_radius: Option<f64>,
    /// Taper: r = tip × (sources carried)^(1/n)
    #[arg(long, default_value_t = 3.0)]
    pub murray: f64,
    /// Catmull-Rom points added between neighbouring vertices of a branch, snapped to the
    /// surface (0: the mesh edges themselves)
    #[arg(long, default_value_t = 0)]
    pub smooth: usize,
    /// Random seed for sampled sources: the same seed gives the same bytes
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also write an SVG render
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Also write a PNG render on the surface
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Longer side of PNG renders, in pixels
    #[arg(long, default_value_t = 2048)]
    pub size: u32,
    /// Write the summary as JSON here
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

/// Sources sampled when none are given.
pub const DEFAULT_SOURCES: usize = 300;

/// The most points `--smooth` adds per mesh edge of a vein.
pub const MAX_SMOOTH: usize = 64;

pub fn run(args: Args) -> Result<()> {
    if args.smooth > MAX_SMOOTH {
        bail!(
            "--smooth {}: at most {MAX_SMOOTH} points per span",
            args.smooth
        );
    }
    let mesh = read_surface(&args.surface, &args.weld)?;
    let ctx = || format!("--surface {}", args.surface.display());
    let graph = MeshGraph::new(&mesh);
    let root = match args.root {
        Some(r) => r,
        None => surface::lowest_vertex(&mesh).with_context(ctx)?,
    };
    if root as usize >= mesh.positions.len() {
        bail!(
            "--root {root}: {} has {} vertices",
            args.surface.display(),
            mesh.positions.len()
        );
    }
    let (sources, skipped) = if args.source.is_empty() {
        let density = args.density_channel.map(Channel::from);
        let want = args.sources.unwrap_or(DEFAULT_SOURCES);
        if want == 0 {
            bail!("--sources must be at least 1");
        }
        // Sources are vertices: more than the mesh has only repeats them, at a cost.
        if want > mesh.positions.len() {
            bail!(
                "--sources {want}: {} has only {} vertices to be sources",
                args.surface.display(),
                mesh.positions.len()
            );
        }
        let sampled = geodesic::sample_sources(&mesh, &graph, root, want, density, args.seed)
            .with_context(ctx)?;
        (sampled.vertices, sampled.skipped)
    } else {
        (args.source.clone(), 0)
    };
    let tree =
        grow_veins(&graph, &mesh.positions, root, &sources, &mut Incremental).with_context(ctx)?;
    let tip = args
        .tip_radius
        .unwrap_or_else(|| 0.08 * surface::mean_edge_length(&mesh));
    let opts = VeinOptions {
        tip_radius: tip,
        murray: args.murray,
        smooth: args.smooth,
    };
    let mut net = geodesic::to_network(&mesh, &tree, &opts)?;
    let p = &mut net.meta.parameters;
    p.insert("surface".into(), json!(args.surface.display().to_string()));
    p.insert("root".into(), root.into());
    net.meta.seed = Some(args.seed);
    write_outputs(
        &net,
        &mesh,
        &args.output,
        args.svg.as_deref(),
        args.png.as_deref(),
        args.size,
    )?;
    let summary = json!({
        "output": args.output,
        "surface": args.surface,
        "root": root,
        "sources": tree.sources.len(),
        "sources_unreachable_skipped": skipped,
        "iterations": tree.iterations,
        "tree_vertices": tree.order.len(),
        "relabelled": tree.relabelled,
        "nodes": net.nodes.len(),
        "edges": net.edges.len(),
        "root_radius": net.nodes.first().map(|n| n.radius),
    });
    if let Some(path) = &args.report {
        write_json(path, &summary)?;
    }
    if args.json {
        outln!("{summary}");
    } else {
        outln!(
            "wrote {}: a tree of {} vertices reaching {} sources in {} iterations ({} labels \
             updated){}",
            args.output.display(),
            tree.order.len(),
            tree.sources.len(),
            tree.iterations,
            tree.relabelled,
            if skipped > 0 {
                format!("; {skipped} sampled sources skipped: no path from the root")
            } else {
                String::new()
            }
        );
    }
    Ok(())
}
