//! `lamina venation`: grow an open leaf venation in a built-in blade.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args as ClapArgs, ValueEnum};
use serde_json::json;

use lamina::grow::outline::{Outline, Shape};
use lamina::grow::venation::{grow_leaf, LeafOptions, VenationOptions};
use lamina::network::io::{write_network, RenderOptions};

#[derive(Clone, Copy, ValueEnum)]
pub enum ShapeArg {
    Ovate,
    Lanceolate,
    Cordate,
    Circle,
    Rect,
}

impl From<ShapeArg> for Shape {
    fn from(s: ShapeArg) -> Shape {
        match s {
            ShapeArg::Ovate => Shape::Ovate,
            ShapeArg::Lanceolate => Shape::Lanceolate,
            ShapeArg::Cordate => Shape::Cordate,
            ShapeArg::Circle => Shape::Circle,
            ShapeArg::Rect => Shape::Rect,
        }
    }
}

#[derive(ClapArgs)]
pub struct Args {
    /// Built-in blade, 100 mm from base to tip; the root is the petiole at its base
    #[arg(long, value_enum, default_value = "ovate")]
    pub shape: ShapeArg,
    /// Output network (.json .obj .dxf .svg .png)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write an SVG render
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Also write a PNG render
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Longer side of PNG renders, in pixels
    #[arg(long, default_value_t = 2048)]
    pub size: u32,
    /// Random seed: the same seed gives the same bytes
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// D, the length of each vein segment, mm
    #[arg(long, default_value_t = 1.0)]
    pub step: f64,
    /// Sources closer than this to a vein are removed, mm
    #[arg(long, default_value_t = 1.5)]
    pub kill: f64,
    /// Poisson-disk radius of the auxin sources, mm
    #[arg(long, default_value_t = 2.0)]
    pub birth: f64,
    /// Murray exponent n: r_parent^n = sum of r_child^n
    #[arg(long, default_value_t = 3.0)]
    pub murray: f64,
    /// Radius of vein tips, mm
    #[arg(long, default_value_t = 0.1)]
    pub tip_radius: f64,
    /// Stop after this many growth steps
    #[arg(long, default_value_t = 10_000)]
    pub max_iterations: usize,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let outline = Outline::shape(args.shape.into());
    let opts = LeafOptions {
        growth: VenationOptions {
            step: args.step,
            kill: args.kill,
            max_iterations: args.max_iterations,
        },
        birth: args.birth,
        murray: args.murray,
        tip_radius: args.tip_radius,
        seed: args.seed,
    };
    let (net, growth) = grow_leaf(&outline, &[outline.default_root()], &opts)?;
    let render = RenderOptions { size: args.size };
    write_network(&net, &args.output, &render)?;
    for extra in [&args.svg, &args.png].into_iter().flatten() {
        write_network(&net, extra, &render)?;
    }
    let degrees = growth.degrees();
    let tips = degrees.iter().filter(|&&d| d == 1).count();
    let summary = json!({
        "output": args.output,
        "nodes": net.nodes.len(),
        "edges": net.edges.len(),
        "iterations": growth.iterations,
        "stop": growth.stop,
        "sources_placed": growth.sources_placed,
        "sources_left": growth.sources_left,
        "tips": tips,
        "root_radius": net.nodes.first().map(|n| n.radius),
    });
    if args.json {
        println!("{summary}");
    } else {
        println!(
            "wrote {}: {} nodes, {} edges in {} steps ({:?}); {} of {} sources left unreached",
            args.output.display(),
            net.nodes.len(),
            net.edges.len(),
            growth.iterations,
            growth.stop,
            growth.sources_left,
            growth.sources_placed
        );
    }
    Ok(())
}
