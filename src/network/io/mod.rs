//! Network files: our JSON, OBJ polylines, DXF; SVG and PNG renders (write only).
//!
//! Readers validate into a `Network` and reject what cannot be a network (an edge to a node that
//! does not exist, a non-finite coordinate) with an error naming the file and the line or record.
//! Softer problems (repeated edges, self-loops) are kept for `Network::validate` to report.
//! Writers refuse a network with such hard problems and write through `files::write_atomic`.

pub mod dxf;
mod dxf_entities;
mod dxf_groups;
mod dxf_hatch;
pub use dxf_entities::{default_max_points, MAX_POINTS as MAX_DXF_POINTS};
mod dxf_split;
pub(crate) mod dxf_write;
pub mod json;
mod obj;
mod png;
mod svg;
pub mod units;

use std::collections::BTreeMap;
use std::path::Path;

use super::arrangement::SplitStats;
use super::{Network, Problem, Weld, WeldStats};
use crate::files::{extension, ReadError, WriteError};
use units::{LengthUnit, SourceUnits};

pub use png::{render_png_bytes, SIZE_RANGE as PNG_SIZE_RANGE};
pub use svg::render_svg_string;

/// The network formats lamina knows, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NetworkFormat {
    Json,
    Obj,
    Dxf,
    Svg,
    Png,
}

impl NetworkFormat {
    pub fn from_path(path: &Path) -> Option<Self> {
        match extension(path).as_str() {
            "json" => Some(Self::Json),
            "obj" => Some(Self::Obj),
            "dxf" => Some(Self::Dxf),
            "svg" => Some(Self::Svg),
            "png" => Some(Self::Png),
            _ => None,
        }
    }

    pub fn can_read(self) -> bool {
        matches!(self, Self::Json | Self::Obj | Self::Dxf)
    }
}

/// Options for reading polyline formats.
#[derive(Clone, Copy, Debug)]
pub struct ReadOptions {
    /// Tolerance under which OBJ and DXF points become one node. Default: 1e-6 of the bounding
    /// box diagonal. JSON stores its nodes explicitly and is never welded.
    pub weld: Weld,
    /// The unit the file is drawn in, overriding what a DXF header says (OBJ has no unit of its
    /// own: millimetres unless given). Default: none.
    pub units: Option<LengthUnit>,
    /// Largest distance, in mm, between a curve (arc, bulge, ellipse, spline) and the chords
    /// it is read as. Default 0.05 mm.
    pub chord_tolerance: f64,
    /// The most points a DXF may expand to (curves flattened, blocks inserted), at most
    /// `dxf_entities::MAX_POINTS`. Default: `default_max_points` of the file's size.
    pub max_points: Option<usize>,
    /// Read the boundary paths of model-space HATCH entities as closed loops (else a HATCH is
    /// skipped and named). Default: false.
    pub hatch_boundaries: bool,
}

impl ReadOptions {
    pub const DEFAULT_CHORD_TOLERANCE: f64 = 0.05;
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            weld: Weld::DEFAULT,
            units: None,
            chord_tolerance: Self::DEFAULT_CHORD_TOLERANCE,
            max_points: None,
            hatch_boundaries: false,
        }
    }
}

/// Options for renders (SVG, PNG). Ignored by the other formats.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Longer side of a PNG render, in pixels. Default 2048.
    pub size: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions { size: 2048 }
    }
}

/// A network read from a file, with what the import did to get there.
#[derive(Clone, Debug)]
pub struct Imported {
    pub network: Network,
    /// Welding figures, for formats that weld (OBJ, DXF).
    pub weld: Option<WeldStats>,
    /// Records read but not part of a network, by kind (e.g. DXF "3DFACE" → 3).
    pub skipped: BTreeMap<String, usize>,
    /// The unit the file was read in (DXF and OBJ), taken to millimetres.
    pub units: Option<SourceUnits>,
    /// Blocks inserted (DXF INSERT, each MINSERT cell and nested inserts counted).
    pub inserts: usize,
    /// What `--split-crossings` did, when asked.
    pub split: Option<SplitStats>,
}

impl Imported {
    /// The distance under which two points of this network are one: the weld tolerance used
    /// when the format welds, never below 1e-9 of the bounding-box diagonal.
    pub fn point_tolerance(&self) -> f64 {
        let floor = 1e-9 * self.network.bbox().diagonal();
        self.weld.map_or(floor, |w| w.tolerance.max(floor))
    }
}

/// Reads a network, choosing the format by extension.
pub fn read_network(path: &Path, opts: &ReadOptions) -> Result<Imported, ReadError> {
    match NetworkFormat::from_path(path) {
        Some(NetworkFormat::Json) => json::read(path),
        Some(NetworkFormat::Obj) => obj::read(path, opts),
        Some(NetworkFormat::Dxf) => dxf::read(path, opts),
        _ => Err(ReadError::file(
            path,
            "not a network file lamina reads (expected .json, .obj or .dxf)",
        )),
    }
}

/// Writes a network, choosing the format by extension.
pub fn write_network(net: &Network, path: &Path, opts: &RenderOptions) -> Result<(), WriteError> {
    check_writable(net, path)?;
    match NetworkFormat::from_path(path) {
        Some(NetworkFormat::Json) => json::write(net, path),
        Some(NetworkFormat::Obj) => obj::write(net, path),
        Some(NetworkFormat::Dxf) => dxf::write(net, path),
        Some(NetworkFormat::Svg) => svg::write(net, path),
        Some(NetworkFormat::Png) => png::write(net, path, opts),
        None => Err(WriteError::Content {
            path: path.to_path_buf(),
            msg: "unknown network format (expected .json, .obj, .dxf, .svg or .png)".into(),
        }),
    }
}

/// Writers take only networks whose every edge joins two existing nodes at finite positions.
fn check_writable(net: &Network, path: &Path) -> Result<(), WriteError> {
    // Only the two problems no format can hold; the rest of `validate` is not needed here.
    let nodes = net.nodes.len();
    let non_finite = net
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.p.is_finite())
        .map(|(i, _)| Problem::NonFinitePosition { node: i as u32 });
    let out_of_range = net
        .edges
        .iter()
        .enumerate()
        .filter(|(_, e)| e.a as usize >= nodes || e.b as usize >= nodes)
        .map(|(k, e)| Problem::EdgeOutOfRange {
            edge: k as u32,
            a: e.a,
            b: e.b,
            nodes,
        });
    let hard: Vec<String> = non_finite
        .chain(out_of_range)
        .map(|p| p.to_string())
        .collect();
    if hard.is_empty() {
        Ok(())
    } else {
        Err(WriteError::Content {
            path: path.to_path_buf(),
            msg: format!("network cannot be written: {}", hard.join("; ")),
        })
    }
}

/// How a render lays the network flat: it looks along the axis of least extent (top view for a
/// flat leaf, front view for a tall surface), with "up" on the page being +Y or +Z.
pub(crate) struct Projection {
    u: usize,
    v: usize,
    min: [f64; 2],
    max: [f64; 2],
}

impl Projection {
    pub(crate) fn fit(net: &Network) -> Self {
        let b = net.bbox();
        let size = b.size().to_array();
        let look = (0..3)
            .min_by(|&i, &j| size[i].total_cmp(&size[j]).then(j.cmp(&i)))
            .unwrap_or(2);
        let (u, v) = match look {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let (lo, hi) = if b.is_empty() {
            ([0.0; 3], [1.0; 3])
        } else {
            (b.min.to_array(), b.max.to_array())
        };
        Projection {
            u,
            v,
            min: [lo[u], lo[v]],
            max: [hi[u], hi[v]],
        }
    }

    /// Width and height of the projected box, in mm (never zero).
    pub(crate) fn extent(&self) -> [f64; 2] {
        let w = (self.max[0] - self.min[0]).max(0.0);
        let h = (self.max[1] - self.min[1]).max(0.0);
        let s = w.max(h).max(1e-9);
        [w.max(s * 1e-3), h.max(s * 1e-3)]
    }

    /// Page coordinates in mm from the top-left corner of the box, y down.
    pub(crate) fn page(&self, p: glam::DVec3) -> [f64; 2] {
        let a = p.to_array();
        [a[self.u] - self.min[0], self.max[1] - a[self.v]]
    }
}
