//! `lamina print NET -o job.sl1`: a network's solid sliced straight from its signed distance,
//! with no mesh in between; the same archive, print.json and islands as `solid` then `slice`.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args as ClapArgs;

use super::input::ReadArgs;
use super::progress::Bar;
use super::slice::{write_job, JobArgs};
use super::solid::{ShapeArgs, SupportArgs};
use lamina::stage::print;

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
    let job = args.job.options(&args.output)?;
    let net = args.weld.network(&args.network)?.network;
    let opts = print::Options {
        shape: args.shape.shape(args.supports.options()?)?,
        display_fit: args.shape.display_fit(),
        job,
        name: Some(args.network.display().to_string()),
    };
    let within = || format!("{}", args.network.display());
    let sliced = write_job(
        &args.output,
        args.job.layers_dir.as_deref(),
        &opts.job.name,
        |archive, _| print::run(&net, &opts, archive, &Bar::new()),
    )
    // Errors of the plate already name the network.
    .map_err(|e| match format!("{e:#}").starts_with(&within()) {
        true => e,
        false => e.context(within()),
    })?;
    args.job.finish(&sliced, &opts.job.printer, &args.output)
}
