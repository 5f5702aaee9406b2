//! `lamina bifurcate`: a tree by recursive bifurcation, optionally fitted to a façade and
//! projected onto a surface.

use anyhow::Result;
use clap::Args as ClapArgs;

use super::branching::{check_outputs, print, write, FacadeArgs, OutputArgs, WidthArgs};
use lamina::stage::bifurcate::{self, Span};

#[derive(ClapArgs)]
pub struct Args {
    /// Generations of forks after the trunk (the tree has 2^(depth+1) − 1 branches)
    #[arg(long, default_value_t = 6)]
    pub depth: u32,
    /// Trunk length, mm
    #[arg(long, default_value_t = 2000.0)]
    pub length: f64,
    /// Angle of each branch from its parent, degrees, or a range `15..35` drawn per branch
    #[arg(long, default_value = "25")]
    pub angle: Span,
    /// Length of a branch over its parent's, or a range `0.6..0.8` drawn per branch
    #[arg(long, default_value = "0.75")]
    pub scale: Span,
    /// Trunk radius, mm
    #[arg(long, default_value_t = 60.0)]
    pub radius: f64,
    /// Radius factor per generation
    #[arg(long, default_value_t = 0.8)]
    pub radius_scale: f64,
    /// Grow in 3D: each fork's plane turns this many degrees about its parent branch
    #[arg(long, value_name = "DEG")]
    pub roll: Option<f64>,
    #[command(flatten)]
    pub widths: WidthArgs,
    /// Random seed (ranges): the same seed gives the same bytes
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub facade: FacadeArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

pub fn run(args: Args) -> Result<()> {
    let report = execute(&args)?;
    print(&report, &args.out)
}

/// Grows, shapes and writes; returns the report.
pub fn execute(args: &Args) -> Result<serde_json::Value> {
    check_outputs(&args.out)?;
    let shape = args.facade.shape(&args.widths)?;
    let opts = bifurcate::Options {
        depth: args.depth,
        length: args.length,
        angle: args.angle,
        scale: args.scale,
        radius: args.radius,
        radius_scale: args.radius_scale,
        roll: args.roll,
        seed: args.seed,
        shape,
    };
    let drawn = bifurcate::run(&opts)?;
    write(
        &drawn.network,
        &drawn.report,
        opts.shape.onto.as_ref(),
        &args.out,
    )
}
