//! lamina's own network JSON: `{"format": "lamina-network", "version": 1, ...}`.
//!
//! One node or edge per line, so files diff well. Numbers are written in the shortest form that
//! reads back to the same f64, so a round trip is exact.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::Imported;
use crate::files::{read_nonempty, write_atomic, ReadError, WriteError};
use crate::network::{Edge, Meta, Network, Node};

pub const FORMAT: &str = "lamina-network";
pub const VERSION: u32 = 1;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileRecord {
    format: String,
    version: u32,
    #[serde(default)]
    meta: Option<MetaRecord>,
    nodes: Vec<NodeRecord>,
    edges: Vec<EdgeRecord>,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct MetaRecord {
    #[serde(default = "mm")]
    units: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    generator: Option<String>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    parameters: BTreeMap<String, serde_json::Value>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    tags: BTreeMap<String, String>,
}

fn mm() -> String {
    "mm".into()
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct NodeRecord {
    p: [f64; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normal: Option<[f64; 3]>,
    #[serde(default)]
    radius: f64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EdgeRecord {
    a: u32,
    b: u32,
    #[serde(default)]
    radius: f64,
}

pub fn read(path: &Path) -> Result<Imported, ReadError> {
    let bytes = read_nonempty(path)?;
    parse(&bytes, path)
}

/// A network from lamina JSON text in memory (errors name it "network").
pub fn from_str(text: &str) -> Result<Network, ReadError> {
    parse(text.as_bytes(), Path::new("network")).map(|imported| imported.network)
}

/// The network of a file's bytes; `path` names it in errors.
fn parse(bytes: &[u8], path: &Path) -> Result<Imported, ReadError> {
    let file: FileRecord = serde_json::from_slice(bytes).map_err(|e| {
        let hint = if e.is_data() {
            " (expected a lamina-network JSON file: format, version, nodes, edges)"
        } else {
            ""
        };
        ReadError::line(
            path,
            e.line(),
            format!("column {}: {}{hint}", e.column(), strip_position(&e)),
        )
    })?;
    if file.format != FORMAT {
        return Err(ReadError::file(
            path,
            format!("format is \"{}\", expected \"{FORMAT}\"", file.format),
        ));
    }
    if file.version != VERSION {
        return Err(ReadError::file(
            path,
            format!(
                "version {} is not one this lamina reads (it reads {VERSION})",
                file.version
            ),
        ));
    }
    let mut nodes = Vec::with_capacity(file.nodes.len());
    for (i, n) in file.nodes.iter().enumerate() {
        let p = DVec3::from_array(n.p);
        if !p.is_finite() {
            return Err(ReadError::record(
                path,
                format!("node {i}"),
                "position is not finite",
            ));
        }
        let normal = n.normal.map(DVec3::from_array);
        if normal.is_some_and(|v| !v.is_finite()) {
            return Err(ReadError::record(
                path,
                format!("node {i}"),
                "normal is not finite",
            ));
        }
        check_radius(path, || format!("node {i}"), n.radius)?;
        nodes.push(Node {
            p,
            normal,
            radius: n.radius,
        });
    }
    let mut edges = Vec::with_capacity(file.edges.len());
    for (k, e) in file.edges.iter().enumerate() {
        if e.a as usize >= nodes.len() || e.b as usize >= nodes.len() {
            return Err(ReadError::record(
                path,
                format!("edge {k}"),
                format!(
                    "joins nodes {} and {}, but the file has {} nodes (numbered from 0)",
                    e.a,
                    e.b,
                    nodes.len()
                ),
            ));
        }
        check_radius(path, || format!("edge {k}"), e.radius)?;
        edges.push(Edge {
            a: e.a,
            b: e.b,
            radius: e.radius,
        });
    }
    let meta = file.meta.unwrap_or_default();
    Ok(Imported {
        network: Network {
            nodes,
            edges,
            meta: Meta {
                units: meta.units,
                generator: meta.generator,
                parameters: meta.parameters,
                seed: meta.seed,
                tags: meta.tags,
            },
        },
        weld: None,
        skipped: BTreeMap::new(),
        units: None,
        inserts: 0,
        split: None,
    })
}

/// serde_json appends " at line L column C" to its messages; we report those ourselves.
fn strip_position(e: &serde_json::Error) -> String {
    let s = e.to_string();
    match s.rfind(" at line ") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

pub fn write(net: &Network, path: &Path) -> Result<(), WriteError> {
    let meta = MetaRecord {
        units: net.meta.units.clone(),
        generator: net.meta.generator.clone(),
        parameters: net.meta.parameters.clone(),
        seed: net.meta.seed,
        tags: net.meta.tags.clone(),
    };
    write_atomic(path, |w| {
        writeln!(w, "{{")?;
        writeln!(w, "  \"format\": \"{FORMAT}\",")?;
        writeln!(w, "  \"version\": {VERSION},")?;
        write!(w, "  \"meta\": ")?;
        serde_json::to_writer(&mut *w, &meta)?;
        writeln!(w, ",")?;
        write_list(w, "nodes", &net.nodes, |n| NodeRecord {
            p: n.p.to_array(),
            normal: n.normal.map(|v| v.to_array()),
            radius: n.radius,
        })?;
        writeln!(w, ",")?;
        write_list(w, "edges", &net.edges, |e| EdgeRecord {
            a: e.a,
            b: e.b,
            radius: e.radius,
        })?;
        writeln!(w, "\n}}")
    })
}

fn write_list<T, R: Serialize>(
    w: &mut impl Write,
    key: &str,
    items: &[T],
    record: impl Fn(&T) -> R,
) -> std::io::Result<()> {
    write!(w, "  \"{key}\": [")?;
    for (i, item) in items.iter().enumerate() {
        w.write_all(if i == 0 { b"\n    " } else { b",\n    " })?;
        serde_json::to_writer(&mut *w, &record(item))?;
    }
    if !items.is_empty() {
        write!(w, "\n  ")?;
    }
    write!(w, "]")
}

/// The largest vein radius a network file may give, mm: a kilometre.
pub const MAX_RADIUS: f64 = 1e6;

/// A radius of at most [`MAX_RADIUS`] in size (1e308 overflowed the drawings made from it; a
/// negative one is read, and `validate` names it).
fn check_radius(path: &Path, record: impl Fn() -> String, r: f64) -> Result<(), ReadError> {
    if r.abs() <= MAX_RADIUS {
        return Ok(());
    }
    Err(ReadError::record(
        path,
        record(),
        format!(
            "radius {} mm is larger than {} mm",
            crate::text::num(r),
            crate::text::num(MAX_RADIUS)
        ),
    ))
}
