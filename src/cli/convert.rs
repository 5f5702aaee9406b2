//! `lamina convert IN OUT`

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use super::input::{load, Loaded, ReadArgs};
use lamina::mesh::io::{write_mesh, MeshFormat};
use lamina::network::io::{write_network, NetworkFormat, RenderOptions};

#[derive(ClapArgs)]
pub struct Args {
    /// Input: a network (.json .obj .dxf) or a mesh (.obj .stl)
    pub input: PathBuf,
    /// Output, format by extension: networks to .json .obj .dxf .svg .png; meshes to .obj .stl .png
    pub output: PathBuf,
    /// Longer side of a PNG output, in pixels
    #[arg(long, default_value_t = 2048)]
    pub size: u32,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub weld: ReadArgs,
}

pub fn run(args: Args) -> Result<()> {
    let loaded = load(&args.input, &args.weld, false)?;
    let summary = match &loaded {
        Loaded::Network(imp) => {
            if NetworkFormat::from_path(&args.output).is_none() {
                bail!(
                    "{}: a network converts to .json, .obj, .dxf, .svg or .png",
                    args.output.display()
                );
            }
            write_network(
                &imp.network,
                &args.output,
                &RenderOptions { size: args.size },
            )?;
            json!({ "output": args.output, "kind": "network",
                    "nodes": imp.network.nodes.len(), "edges": imp.network.edges.len() })
        }
        Loaded::Mesh(mesh, _) => {
            if MeshFormat::from_path(&args.output).is_none() {
                bail!(
                    "{}: a mesh converts to .obj, .stl or .png",
                    args.output.display()
                );
            }
            write_mesh(mesh, &args.output, args.size)?;
            json!({ "output": args.output, "kind": "mesh",
                    "vertices": mesh.positions.len(), "triangles": mesh.triangles.len() })
        }
    };
    if args.json {
        outln!("{summary}");
    } else if let Some(n) = summary["nodes"].as_u64() {
        outln!(
            "wrote {}: {n} nodes, {} edges",
            args.output.display(),
            summary["edges"]
        );
    } else {
        outln!(
            "wrote {}: {} vertices, {} triangles",
            args.output.display(),
            summary["vertices"],
            summary["triangles"]
        );
    }
    Ok(())
}
