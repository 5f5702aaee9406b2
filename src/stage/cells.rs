//! `cells`: the closed cells of a network on a surface (faces of its rotation system),
//! triangulated by constrained Delaunay, with V − E + F checked against the guide surface.
//!
//! ```
//! use lamina::stage::cells;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/calyx_veins.json"))?;
//! let found = cells::run(&net, None, &cells::Options::default())?;
//! assert_eq!(found.table.euler.chi, found.table.expected_chi);
//! # Ok(()) }
//! ```

use serde::Serialize;

use crate::network::arrangement::defects;
use crate::rationalize::cells::{cells, CellError, Cells, Euler, Untriangulated};
use crate::rationalize::reference::{reference_normals, ReferenceError};
use crate::{Network, TriMesh};

/// How cells are found.
#[derive(Clone, Debug)]
pub struct Options {
    /// Points closer than this are one (crossings and T-junctions are found beyond it), mm.
    /// Default: 1e-9 of the network's bounding-box diagonal.
    pub point_tolerance: Option<f64>,
    /// The guide surface's name in the notes. Default "the surface".
    pub surface_name: String,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            point_tolerance: None,
            surface_name: "the surface".into(),
        }
    }
}

/// What the network's V − E + F should be, and how many faces should be holes, if it covers
/// its surface with disk-shaped cells.
#[derive(Clone, Debug)]
pub struct Expected {
    /// V − E + F.
    pub chi: i64,
    /// Hole faces expected (the surface's boundary loops).
    pub holes: usize,
    /// Where the expectation comes from.
    pub from: String,
}

/// The cells, and the table `--table` writes.
#[derive(Clone, Debug)]
pub struct Found {
    /// Cells.
    pub cells: Cells,
    /// What V − E + F should be.
    pub expected: Expected,
    /// The checks in words (χ, holes, open tips, faces left untriangulated).
    pub notes: Vec<String>,
    /// The cell table (`--table`).
    pub table: Table,
}

/// The cell table. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Table {
    /// Cells.
    pub cells: Vec<FaceRow>,
    /// V − E + F and its parts.
    pub euler: Euler,
    /// V − E + F expected.
    pub expected_chi: i64,
    /// Hole faces expected.
    pub expected_holes: usize,
    /// The file format's name.
    pub format: &'static str,
    /// Faces that are holes, not cells.
    pub holes: Vec<FaceRow>,
    /// Notes, one line each.
    pub notes: Vec<String>,
    /// Veins that end without joining.
    pub open_tips: usize,
    /// Faces not triangulated, and why.
    pub untriangulated: Vec<Untriangulated>,
    /// The format's version.
    pub version: u32,
}

/// A face: its boundary and, for a cell, its number and triangles.
#[derive(Clone, Debug, Serialize)]
pub struct FaceRow {
    /// How well the face's area vector agrees with the normals.
    pub alignment: f64,
    /// Area, mm².
    pub area_mm2: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// The cell's number.
    pub cell: Option<usize>,
    /// Edges (members).
    pub edges: Vec<u32>,
    /// The face's number.
    pub face: usize,
    /// Edges inside the face (veins ending in it).
    pub inner_edges: Vec<u32>,
    /// Nodes.
    pub nodes: Vec<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// Triangles.
    pub triangles: Option<[usize; 2]>,
}

/// Why no cells were found.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(
        "the drawing is not noded: {first}{more}; its cells cannot be found until every \
         crossing is a node: give split_crossings="
    )]
    /// Crossings without nodes.
    NotNoded {
        /// The first crossing or T-junction.
        first: String,
        /// How many more there are, in words.
        more: String,
    },
    #[error("the network has {nodes} node(s) and no edges: there are no cells to find")]
    /// Nothing to bound a cell.
    NoEdges {
        /// Its nodes.
        nodes: usize,
    },
    #[error(transparent)]
    /// No reference directions.
    Reference(#[from] ReferenceError),
    #[error(transparent)]
    /// Finding the cells failed.
    Cells(#[from] CellError),
}

/// Finds and triangulates the cells of `net`; `surface` gives the reference normals and the
/// χ to check against (else each component is taken as a disk).
pub fn run(net: &Network, surface: Option<&TriMesh>, opts: &Options) -> Result<Found, Error> {
    if net.edges.is_empty() {
        return Err(Error::NoEdges {
            nodes: net.nodes.len(),
        });
    }
    let tol = opts.point_tolerance.unwrap_or(1e-9 * net.bbox().diagonal());
    let found = defects(net, tol, 1);
    if let Some(first) = found.listed.first() {
        return Err(Error::NotNoded {
            first: first.to_string(),
            more: match found.total() {
                1 => String::new(),
                n => format!(
                    " (and {}{} more crossings or T-junctions)",
                    if found.counted_all { "" } else { "at least " },
                    n - 1
                ),
            },
        });
    }
    let reference = reference_normals(net, surface)?;
    let positions: Vec<_> = net.nodes.iter().map(|n| n.p).collect();
    let edges: Vec<[u32; 2]> = net.edges.iter().map(|e| [e.a, e.b]).collect();
    let c = cells(&positions, &edges, &reference)?;
    let expected = match surface {
        Some(mesh) => {
            let topo = mesh.check_manifold();
            Expected {
                chi: topo.euler + topo.boundary_loops as i64,
                holes: topo.boundary_loops,
                from: format!(
                    "{}: χ = {} with {} boundary loop(s), {} capped",
                    opts.surface_name,
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
    let table = table(&c, &expected, &notes);
    Ok(Found {
        cells: c,
        expected,
        notes,
        table,
    })
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
            "does not match: V − E + F = {} but the surface's capped χ is {}: some face is not a disk \
             (a vein ring that does not close around the surface, or a separate piece of network)",
            c.euler.chi, expected.chi
        ));
    }
    if c.holes.len() < expected.holes && c.euler.chi == expected.chi {
        // Fewer open faces than rims, with V − E + F right: no ring of veins runs around the
        // surface between its rims, so one open face reaches several of them. Veins grown up
        // a band from a few roots do this; every cell is still closed.
        out.push(format!(
            "{} open face(s) for the surface's {} boundary loop(s): expected where no ring of \
             veins runs around the surface between its rims, so one open face reaches several \
             (veins climbing a band from a few roots); otherwise a rim face was taken for a cell",
            c.holes.len(),
            expected.holes
        ));
    } else if c.holes.len() != expected.holes {
        out.push(format!(
            "does not match: {} hole face(s) where the surface has {} boundary loop(s): the \
             network covers only part of the surface, or a face was taken for a hole (or a hole \
             for a face) where the surface's normals turn sharply",
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

fn table(c: &Cells, expected: &Expected, notes: &[String]) -> Table {
    let face = |id: usize| {
        let f = &c.faces[id];
        FaceRow {
            alignment: f.alignment,
            area_mm2: f.area,
            cell: None,
            edges: f.edges.clone(),
            face: id,
            inner_edges: f.inner_edges.clone(),
            nodes: f.nodes.clone(),
            triangles: None,
        }
    };
    Table {
        cells: c
            .cells
            .iter()
            .enumerate()
            .map(|(k, cell)| FaceRow {
                cell: Some(k),
                triangles: Some([cell.triangles.start, cell.triangles.end]),
                ..face(cell.face)
            })
            .collect(),
        euler: c.euler,
        expected_chi: expected.chi,
        expected_holes: expected.holes,
        format: "lamina-cells",
        holes: c.holes.iter().map(|&h| face(h)).collect(),
        notes: notes.to_vec(),
        open_tips: c.open_tips,
        untriangulated: c.untriangulated.clone(),
        version: 1,
    }
}

impl Table {
    /// The table's text.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("tables serialise") + "\n"
    }
}
