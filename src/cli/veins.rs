//! `lamina veins --surface MESH`: geodesic veins along mesh edges (Bachman), from a root
//! vertex to given or sampled source vertices.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args as ClapArgs;
use serde_json::json;

use super::progress::Bar;
use super::surface::{read_surface, write_outputs};
use super::venation::{write_json, ChannelArg};
use lamina::grow::surface::Channel;
use lamina::stage::veins;

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

pub fn run(args: Args) -> Result<()> {
    let mesh = read_surface(&args.surface, &args.weld)?;
    let opts = veins::Options {
        source: args.source.clone(),
        sources: args.sources,
        density_channel: args.density_channel.map(Channel::from),
        root: args.root,
        tip_radius: args.tip_radius,
        murray: args.murray,
        smooth: args.smooth,
        seed: args.seed,
    };
    let grown = veins::run(&mesh, &opts, &Bar::new()).map_err(|e| match e {
        veins::Error::Option(o) => anyhow::Error::new(o),
        e => anyhow::anyhow!("--surface {}: {e}", args.surface.display()),
    })?;
    let mut net = grown.network;
    let p = &mut net.meta.parameters;
    p.insert("surface".into(), json!(args.surface.display().to_string()));
    write_outputs(
        &net,
        &mesh,
        &args.output,
        args.svg.as_deref(),
        args.png.as_deref(),
        args.size,
    )?;
    let mut r = grown.report;
    r.output = Some(args.output.display().to_string());
    r.surface = Some(args.surface.display().to_string());
    if let Some(path) = &args.report {
        write_json(path, &r)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string(&r)?);
    } else {
        let skipped = r.sources_unreachable_skipped;
        outln!(
            "wrote {}: a tree of {} vertices reaching {} sources in {} iterations ({} labels \
             updated){}",
            args.output.display(),
            r.tree_vertices,
            r.sources,
            r.iterations,
            r.relabelled,
            if skipped > 0 {
                format!("; {skipped} sampled sources skipped: no path from the root")
            } else {
                String::new()
            }
        );
    }
    Ok(())
}
