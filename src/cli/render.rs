//! `lamina render IN -o OUT.svg|OUT.png [--size 2048]`

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args as ClapArgs;

use super::input::{load, Loaded, ReadArgs};
use lamina::files::extension;
use lamina::mesh::io::write_mesh;
use lamina::network::io::{write_network, RenderOptions};

#[derive(ClapArgs)]
pub struct Args {
    /// A network (.json .obj .dxf) or a mesh (.obj .stl)
    pub input: PathBuf,
    /// The picture: .svg or .png for a network, .png for a mesh
    #[arg(short, long)]
    pub output: PathBuf,
    /// Longer side of a PNG, in pixels
    #[arg(long, default_value_t = 2048)]
    pub size: u32,
    #[command(flatten)]
    pub weld: ReadArgs,
}

pub fn run(args: Args) -> Result<()> {
    let ext = extension(&args.output);
    let loaded = load(&args.input, &args.weld, false)?;
    match (&loaded, ext.as_str()) {
        (Loaded::Network(imp), "svg" | "png") => write_network(
            &imp.network,
            &args.output,
            &RenderOptions { size: args.size },
        )?,
        (Loaded::Mesh(mesh, _), "png") => write_mesh(mesh, &args.output, args.size)?,
        (Loaded::Network(_), _) => bail!(
            "{}: a network renders to .svg or .png",
            args.output.display()
        ),
        (Loaded::Mesh(..), _) => bail!("{}: a mesh renders to .png", args.output.display()),
    }
    outln!("wrote {}", args.output.display());
    Ok(())
}
