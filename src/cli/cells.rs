//! `lamina cells`: the closed cells of a network, triangulated, with per-node normals, a cell →
//! edges table, and V − E + F checked against the guide surface.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use lamina::files::{extension, write_atomic};
use lamina::mesh::io::write_obj_with_normals;
use lamina::stage::cells;

use super::input::ReadArgs;
use super::planarize::read_surface;

#[derive(ClapArgs)]
pub struct Args {
    /// The network (.json .obj .dxf)
    pub input: PathBuf,
    /// Guide surface (.obj .stl): its normals order the edges around each node, and its Euler
    /// characteristic is compared with the network's
    #[arg(long)]
    pub surface: Option<PathBuf>,
    /// The cells as a triangle mesh (.obj, one vertex and one normal per node)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write the cell table (cell → boundary edges and nodes, holes, Euler check) as JSON
    #[arg(long)]
    pub table: Option<PathBuf>,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub weld: ReadArgs,
}

/// Finds and triangulates the cells and writes the outputs; prints nothing.
pub fn execute(args: &Args) -> Result<cells::Found> {
    if extension(&args.output) != "obj" {
        bail!(
            "{}: the cells are written as .obj (with vertex normals)",
            args.output.display()
        );
    }
    let imported = args.weld.network(&args.input)?;
    let surface = read_surface(args.surface.as_deref())?;
    let opts = cells::Options {
        point_tolerance: Some(imported.point_tolerance()),
        surface_name: args.surface.as_deref().map_or_else(String::new, |p| {
            p.file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned()
        }),
    };
    let found = cells::run(&imported.network, surface.as_ref(), &opts)
        .with_context(|| args.input.display().to_string())?;
    write_obj_with_normals(&found.cells.mesh, &found.cells.normals, &args.output)?;
    if let Some(path) = &args.table {
        let text = found.table.json();
        write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    Ok(found)
}

pub fn run(args: Args) -> Result<()> {
    let cells::Found {
        cells: c,
        expected,
        notes,
        ..
    } = execute(&args)?;
    if args.json {
        outln!(
            "{}",
            json!({
                "output": args.output,
                "cells": c.cells.len(),
                "holes": c.holes.len(),
                "triangles": c.mesh.triangles.len(),
                "untriangulated": c.untriangulated.len(),
                "euler": c.euler,
                "expected_chi": expected.chi,
                "notes": notes,
            })
        );
    } else {
        outln!(
            "{}: {} cells in {} triangles, {} hole face(s); V − E + F = {} − {} + {} = {}",
            args.output.display(),
            c.cells.len(),
            c.mesh.triangles.len(),
            c.holes.len(),
            c.euler.vertices,
            c.euler.edges,
            c.euler.faces,
            c.euler.chi
        );
        for n in &notes {
            outln!("  {n}");
        }
    }
    Ok(())
}
