//! `lamina print NET -o job.sl1`: a network's solid sliced straight from its signed distance,
//! with no mesh in between; the same archive, print.json and islands as `solid` then `slice`.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use super::input::ReadArgs;
use super::slice::{slice_job, JobArgs, Source};
use super::solid::{ShapeArgs, SupportArgs};
use lamina::fabricate::slice::arrange_boxes;
use lamina::fabricate::slice::shapes::Placed;
use lamina::fabricate::solid::shapes;

#[derive(ClapArgs)]
pub struct Args {
    /// The vein network (.json .obj .dxf); radii from its nodes and edges
    pub network: PathBuf,
    /// The SL1 archive to write
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub shape: ShapeArgs,
    #[command(flatten)]
    pub supports: SupportArgs,
    #[command(flatten)]
    pub weld: ReadArgs,
    #[command(flatten)]
    pub job: JobArgs,
}

pub fn run(args: Args) -> Result<()> {
    let printer = args.job.checked_printer()?;
    let net = args.weld.network(&args.network)?.network;
    // The outline's distance buckets are sized by the cell; the pixel is the cell here.
    let opts = args.shape.options(printer.pixel_mm)?;
    let within = || format!("{}", args.network.display());
    let mut made = shapes(&net, &opts).with_context(within)?;
    let supports = args
        .supports
        .add(&mut made, opts.upright, &printer)
        .with_context(within)?;
    let (scale, min_radius, max_radius) = (made.scale, made.min_radius, made.max_radius);
    if min_radius < printer.pixel_mm {
        errln!(
            "lamina: warning: the thinnest vein (radius {min_radius:.4} mm) is thinner than a \
             pixel ({} mm): it may print broken or not at all; use a larger --fit",
            printer.pixel_mm
        );
    }
    let model = Placed::new(made, opts.upright);
    let (lo, hi) = model.bounds();
    let placed = arrange_boxes(
        &[(args.network.as_path(), lo, hi)],
        &printer,
        args.job.copies,
        args.job.gap,
        false,
    )?;
    let spec = args.job.spec(&args.output);
    let source = Source::Shapes {
        model: &model,
        path: &args.network,
    };
    let (mut report, e, _) = slice_job(source, &placed, &printer, &spec, &[])?;
    report["solid"] = json!({
        "sampled_from": "signed distance",
        "scale": scale,
        "min_radius": min_radius,
        "max_radius": max_radius,
        "lamina_mm": opts.lamina,
        "base": opts.base.map(|b| [b.diameter, b.height]),
        "upright": opts.upright,
        "size_mm": (hi - lo).to_array(),
    });
    if let Some(s) = supports {
        report["supports"] = serde_json::to_value(s)?;
    }
    args.job.finish(&report, &e, &printer, &args.output)
}
