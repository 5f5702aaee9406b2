//! `lamina cells`: the closed cells of a network, triangulated, with per-node normals, a cell →
//! edges table, and V − E + F checked against the guide surface.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use lamina::files::{extension, write_atomic};
use lamina::mesh::io::{read_mesh, write_obj_with_normals};
use lamina::rationalize::cells::{cells, Cells};

use super::input::{reference_normals, ReadArgs};
use lamina::network::arrangement::defects;

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

/// What the network's V − E + F should be, and how many faces should be holes, if it covers
/// its surface with disk-shaped cells.
pub struct Expected {
    pub chi: i64,
    pub holes: usize,
    pub from: String,
}

/// What `cells` found, for the caller to print.
pub struct Outcome {
    pub cells: Cells,
    pub expected: Expected,
    pub notes: Vec<String>,
}

/// Finds and triangulates the cells and writes the outputs; prints nothing.
pub fn execute(args: &Args) -> Result<Outcome> {
    if extension(&args.output) != "obj" {
        bail!(
            "{}: the cells are written as .obj (with vertex normals)",
            args.output.display()
        );
    }
    let imported = args.weld.network(&args.input)?;
    let found = defects(&imported.network, imported.point_tolerance());
    if let Some(first) = found.first() {
        bail!(
            "{}: the drawing is not noded: {first}{}; its cells cannot be found until every \
             crossing is a node: give --split-crossings",
            args.input.display(),
            match found.len() {
                1 => String::new(),
                n => format!(" (and {} more crossings or T-junctions)", n - 1),
            }
        );
    }
    let net = imported.network;
    let reference = reference_normals(&net, args.surface.as_deref())?;
    let positions: Vec<_> = net.nodes.iter().map(|n| n.p).collect();
    let edges: Vec<[u32; 2]> = net.edges.iter().map(|e| [e.a, e.b]).collect();
    let c = cells(&positions, &edges, &reference)?;
    let expected = match &args.surface {
        Some(path) => {
            let topo = read_mesh(path)?.check_manifold();
            Expected {
                chi: topo.euler + topo.boundary_loops as i64,
                holes: topo.boundary_loops,
                from: format!(
                    "{}: χ = {} with {} boundary loop(s), {} capped",
                    path.file_name().unwrap_or_default().to_string_lossy(),
                    topo.euler,
                    topo.boundary_loops,
                    topo.euler + topo.boundary_loops as i64
                ),
            }
        }
        None => Expected {
            chi: 2 * c.euler.components as i64,
            holes: c.euler.components,
            from: format!(
                "no guide surface: each of {} component(s) taken as a disk (χ = 1, 1 hole)",
                c.euler.components
            ),
        },
    };
    let notes = notes(&c, &expected);
    write_obj_with_normals(&c.mesh, &c.normals, &args.output)?;
    if let Some(path) = &args.table {
        let text = serde_json::to_string_pretty(&table(&c, &expected, &notes))? + "\n";
        write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    Ok(Outcome {
        cells: c,
        expected,
        notes,
    })
}

pub fn run(args: Args) -> Result<()> {
    let Outcome {
        cells: c,
        expected,
        notes,
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

fn notes(c: &Cells, expected: &Expected) -> Vec<String> {
    let mut out = vec![expected.from.clone()];
    if c.euler.chi == expected.chi {
        out.push(format!(
            "V − E + F matches the surface's capped χ = {}",
            expected.chi
        ));
    } else {
        out.push(format!(
            "MISMATCH: V − E + F = {} but the surface's capped χ is {}: some face is not a disk \
             (a vein ring that does not close around the surface, or a separate piece of network)",
            c.euler.chi, expected.chi
        ));
    }
    if c.holes.len() != expected.holes {
        out.push(format!(
            "MISMATCH: {} hole face(s) where the surface has {} boundary loop(s): the network \
             covers only part of the surface, or one face holds several of its boundaries",
            c.holes.len(),
            expected.holes
        ));
    }
    if c.open_tips > 0 {
        out.push(format!(
            "{} open tip(s): veins that end without joining leave their cells merged, so there \
             are fewer cells than a fully closed network would have",
            c.open_tips
        ));
    }
    if c.isolated > 0 {
        out.push(format!(
            "{} isolated node(s) bound no cell and are left out",
            c.isolated
        ));
    }
    for u in &c.untriangulated {
        out.push(format!(
            "face {} was not triangulated: {}",
            u.face, u.reason
        ));
    }
    out
}

fn table(c: &Cells, expected: &Expected, notes: &[String]) -> serde_json::Value {
    let face = |id: usize| {
        let f = &c.faces[id];
        json!({
            "face": id,
            "nodes": f.nodes,
            "edges": f.edges,
            "inner_edges": f.inner_edges,
            "area_mm2": f.area,
            "alignment": f.alignment,
        })
    };
    json!({
        "format": "lamina-cells",
        "version": 1,
        "euler": c.euler,
        "expected_chi": expected.chi,
        "expected_holes": expected.holes,
        "open_tips": c.open_tips,
        "cells": c.cells.iter().enumerate().map(|(k, cell)| {
            let mut v = face(cell.face);
            v["cell"] = json!(k);
            v["triangles"] = json!([cell.triangles.start, cell.triangles.end]);
            v
        }).collect::<Vec<_>>(),
        "holes": c.holes.iter().map(|&h| face(h)).collect::<Vec<_>>(),
        "untriangulated": c.untriangulated,
        "notes": notes,
    })
}
