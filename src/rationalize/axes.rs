//! The result of planarize as files: the axes file (`lamina-axes` JSON: every node's position,
//! axis d_i, height h_i and reference d⁰_i, and the edges with any fixed panel normal; all the
//! plates stage needs) and the panels as OBJ quads (one `f` of four corners per edge, corners
//! not shared, so `lamina audit` and other tools read each panel as built).
//!
//! Numbers are written in the shortest form that reads back to the same f64.

use std::io::Write;
use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::panels::panel_quad;
use super::planarize::{Input, Solution};
use crate::files::{check_format, read_nonempty, utf8_text, write_atomic, ReadError, WriteError};

pub const FORMAT: &str = "lamina-axes";
pub const VERSION: u32 = 1;

/// Node axes and heights of a network.
#[derive(Clone, Debug, PartialEq)]
pub struct Axes {
    pub positions: Vec<DVec3>,
    pub edges: Vec<[u32; 2]>,
    pub axes: Vec<DVec3>,
    pub heights: Vec<f64>,
    pub reference: Vec<DVec3>,
    /// Per edge: the panel normal it was held to, if any.
    pub fixed_normals: Vec<Option<DVec3>>,
    /// Per edge: the vein radius in mm from the network (0 when unknown); plates can take
    /// their thickness from it.
    pub edge_radii: Vec<f64>,
}

impl Axes {
    /// The axes planarize found for `input`, with each edge's vein radius.
    pub fn solved(input: &Input, sol: &Solution, edge_radii: Vec<f64>) -> Axes {
        Axes {
            positions: input.positions.clone(),
            edges: input.edges.clone(),
            axes: sol.axes.clone(),
            heights: input.heights.clone(),
            reference: input.reference.clone(),
            fixed_normals: sol
                .panels
                .iter()
                .map(|p| p.fixed_normal.map(DVec3::from_array))
                .collect(),
            edge_radii,
        }
    }

    /// The panel quad of every edge, in edge order.
    pub fn quads(&self) -> Vec<[DVec3; 4]> {
        self.edges
            .iter()
            .map(|&[a, b]| {
                let (a, b) = (a as usize, b as usize);
                panel_quad(
                    self.positions[a],
                    self.positions[b],
                    self.axes[a],
                    self.axes[b],
                    self.heights[a],
                    self.heights[b],
                )
            })
            .collect()
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct NodeRecord {
    p: [f64; 3],
    axis: [f64; 3],
    height: f64,
    reference: [f64; 3],
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EdgeRecord {
    a: u32,
    b: u32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    fixed_normal: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "is_zero")]
    radius: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileRecord {
    /// Checked by `check_format` before the rest is read.
    #[allow(dead_code)]
    format: String,
    #[allow(dead_code)]
    version: u32,
    /// The solve's figures (method, tolerance, deviation); not needed to rebuild the axes.
    #[serde(default)]
    summary: serde_json::Value,
    nodes: Vec<NodeRecord>,
    edges: Vec<EdgeRecord>,
}

/// Writes the axes file; `summary` (method, α used, deviation, …) goes in as it is.
pub fn write_axes(axes: &Axes, summary: &serde_json::Value, path: &Path) -> Result<(), WriteError> {
    write_atomic(path, |w| write_axes_to(w, axes, summary))
}

/// The axes file's text, written to `w` (what `write_axes` puts in the file).
pub fn write_axes_to(
    w: &mut impl std::io::Write,
    axes: &Axes,
    summary: &serde_json::Value,
) -> std::io::Result<()> {
    writeln!(w, "{{")?;
    writeln!(w, "  \"format\": \"{FORMAT}\",")?;
    writeln!(w, "  \"version\": {VERSION},")?;
    writeln!(w, "  \"summary\": {summary},")?;
    writeln!(w, "  \"nodes\": [")?;
    for (i, p) in axes.positions.iter().enumerate() {
        let rec = NodeRecord {
            p: p.to_array(),
            axis: axes.axes[i].to_array(),
            height: axes.heights[i],
            reference: axes.reference[i].to_array(),
        };
        let sep = if i + 1 < axes.positions.len() {
            ","
        } else {
            ""
        };
        writeln!(w, "    {}{sep}", serde_json::to_string(&rec)?)?;
    }
    writeln!(w, "  ],")?;
    writeln!(w, "  \"edges\": [")?;
    for (k, &[a, b]) in axes.edges.iter().enumerate() {
        let rec = EdgeRecord {
            a,
            b,
            fixed_normal: axes.fixed_normals[k].map(|n| n.to_array()),
            radius: axes.edge_radii[k],
        };
        let sep = if k + 1 < axes.edges.len() { "," } else { "" };
        writeln!(w, "    {}{sep}", serde_json::to_string(&rec)?)?;
    }
    writeln!(w, "  ]")?;
    writeln!(w, "}}")?;
    Ok(())
}

pub fn read_axes(path: &Path) -> Result<Axes, ReadError> {
    read_axes_and_summary(path).map(|(axes, _)| axes)
}

/// The axes and the summary the solve wrote beside them (its tolerance, method, figures).
pub fn read_axes_and_summary(path: &Path) -> Result<(Axes, serde_json::Value), ReadError> {
    let bytes = read_nonempty(path)?;
    let text = utf8_text(path, bytes)?;
    check_format(
        path,
        &text,
        FORMAT,
        VERSION,
        "the axes file `lamina planarize` writes",
    )?;
    let rec: FileRecord =
        serde_json::from_str(&text).map_err(|e| ReadError::line(path, e.line(), e.to_string()))?;
    let n = rec.nodes.len() as u32;
    for (k, e) in rec.edges.iter().enumerate() {
        if e.a >= n || e.b >= n {
            return Err(ReadError::record(
                path,
                format!("edge {k}"),
                format!("refers to a node beyond the {n} nodes"),
            ));
        }
    }
    // A member drawn twice, or from a node to itself, has no plate of its own: said here, by
    // record, rather than as two plates 0° apart at a node.
    let mut first: std::collections::HashMap<(u32, u32), usize> =
        std::collections::HashMap::with_capacity(rec.edges.len());
    for (k, e) in rec.edges.iter().enumerate() {
        if e.a == e.b {
            return Err(ReadError::record(
                path,
                format!("edge {k}"),
                format!("joins node {} to itself", e.a),
            ));
        }
        if let Some(j) = first.insert((e.a.min(e.b), e.a.max(e.b)), k) {
            return Err(ReadError::record(
                path,
                format!("edge {k}"),
                format!(
                    "repeats edge {j} (nodes {} and {}): a member drawn twice",
                    e.a, e.b
                ),
            ));
        }
    }
    if let Some(k) = rec
        .edges
        .iter()
        .position(|e| !(e.radius.is_finite() && e.radius >= 0.0))
    {
        return Err(ReadError::record(
            path,
            format!("edge {k}"),
            "radius must be a finite number ≥ 0",
        ));
    }
    let v = |a: [f64; 3]| DVec3::from_array(a);
    let axes = Axes {
        positions: rec.nodes.iter().map(|r| v(r.p)).collect(),
        axes: rec.nodes.iter().map(|r| v(r.axis)).collect(),
        heights: rec.nodes.iter().map(|r| r.height).collect(),
        reference: rec.nodes.iter().map(|r| v(r.reference)).collect(),
        edges: rec.edges.iter().map(|e| [e.a, e.b]).collect(),
        fixed_normals: rec.edges.iter().map(|e| e.fixed_normal.map(v)).collect(),
        edge_radii: rec.edges.iter().map(|e| e.radius).collect(),
    };
    Ok((axes, rec.summary))
}

/// The panels as OBJ: four `v` per panel and one quad `f`, panel k named `o panel-k`.
pub fn write_panels_obj(quads: &[[DVec3; 4]], path: &Path) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        writeln!(w, "# lamina panels: one planar quad per network edge")?;
        for (k, q) in quads.iter().enumerate() {
            writeln!(w, "o panel-{k}")?;
            for c in q {
                writeln!(w, "v {:?} {:?} {:?}", c.x, c.y, c.z)?;
            }
            let base = 4 * k + 1;
            writeln!(w, "f {} {} {} {}", base, base + 1, base + 2, base + 3)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_files_read_back_exactly() -> Result<(), Box<dyn std::error::Error>> {
        let axes = Axes {
            positions: vec![DVec3::ZERO, DVec3::new(1.0 / 3.0, 2.0, 0.1)],
            edges: vec![[0, 1]],
            axes: vec![DVec3::Z, DVec3::new(0.1, 0.2, 0.3).normalize()],
            heights: vec![100.0, 0.7],
            reference: vec![DVec3::Z, DVec3::Y],
            fixed_normals: vec![Some(DVec3::X)],
            edge_radii: vec![0.25],
        };
        let dir = tempfile::tempdir()?;
        let path = dir.path().join("axes.json");
        write_axes(&axes, &serde_json::json!({"method": "lbfgs"}), &path)?;
        assert_eq!(read_axes(&path)?, axes);
        Ok(())
    }
}
