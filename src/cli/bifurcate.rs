//! `lamina bifurcate`: a tree by recursive bifurcation, optionally fitted to a façade and
//! projected onto a surface.

use anyhow::Result;
use clap::Args as ClapArgs;
use serde_json::json;

use super::branching::{check_outputs, finish, print, FacadeArgs, Made, OutputArgs, WidthArgs};
use lamina::grow::bifurcation::{bifurcate, BifurcationOptions};
use lamina::grow::tree::Span;

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

/// Grows, fits and writes; returns the report.
pub fn execute(args: &Args) -> Result<serde_json::Value> {
    check_outputs(&args.out)?;
    let opts = BifurcationOptions {
        depth: args.depth,
        length: args.length,
        angle: args.angle,
        scale: args.scale,
        radius: args.radius,
        radius_scale: args.radius_scale,
        roll: args.roll,
    };
    let tree = bifurcate(&opts, args.seed)?;
    let report = json!({
        "depth": opts.depth,
        "branches": tree.network.edges.len(),
    });
    let made = Made {
        tree,
        generator: "bifurcation",
        parameters: vec![
            ("depth", json!(opts.depth)),
            ("length", json!(opts.length)),
            ("angle_deg", json!([opts.angle.min, opts.angle.max])),
            ("scale", json!([opts.scale.min, opts.scale.max])),
            ("roll_deg", json!(opts.roll)),
        ],
        seed: args.seed,
        report,
        default_tip: opts.radius / 8.0,
    };
    finish(made, &args.widths, &args.facade, &args.out)
}
