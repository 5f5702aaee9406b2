//! `info`: what a network or a mesh is (counts, bounding box, degrees, components, cycles,
//! lengths, every problem; a mesh's topology, area and volume), as a typed summary.
//!
//! ```
//! use lamina::stage::info;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/small_loop.json"))?;
//! let s = info::network("small_loop.json", &net, None, 1e-9);
//! assert_eq!(s.cycles, 1);
//! # Ok(()) }
//! ```

use serde::Serialize;
use serde_json::Value;

use crate::geom::Aabb;
use crate::mesh::MeshWeld;
use crate::network::arrangement::defects;
use crate::network::io::Imported;
use crate::{Network, TriMesh};

/// A bounding box's corners, size and diagonal (None when empty).
#[derive(Clone, Debug, Serialize)]
pub struct Bbox {
    /// Diagonal, mm.
    pub diagonal: f64,
    /// Largest.
    pub max: [f64; 3],
    /// Smallest.
    pub min: [f64; 3],
    /// Size, mm.
    pub size: [f64; 3],
}

fn bbox(b: &Aabb) -> Option<Bbox> {
    (!b.is_empty()).then(|| Bbox {
        diagonal: b.diagonal(),
        max: b.max.to_array(),
        min: b.min.to_array(),
        size: b.size().to_array(),
    })
}

/// Edge lengths, mm.
#[derive(Clone, Debug, Serialize)]
pub struct Lengths {
    /// Largest.
    pub max: f64,
    /// Mean.
    pub mean: f64,
    /// Smallest.
    pub min: f64,
    /// Every sheet together.
    pub total: f64,
}

/// What a network is. Fields in the command's order.
#[derive(Clone, Debug, Serialize)]
pub struct NetworkInfo {
    /// Bounding box.
    pub bbox: Option<Bbox>,
    /// Connected components.
    pub components: usize,
    /// Independent cycles.
    pub cycles: usize,
    /// Nodes by degree.
    pub degree_histogram: Vec<usize>,
    /// Edges (members).
    pub edges: usize,
    /// The file's name.
    pub file: String,
    /// What made the network.
    pub generator: Option<String>,
    /// What reading the file did (null when the network came from memory).
    pub import: Option<Value>,
    /// What it is.
    pub kind: &'static str,
    /// Edge lengths.
    pub lengths: Option<Lengths>,
    /// Nodes.
    pub nodes: usize,
    /// Every problem, each with its `kind`, where, and a `message`.
    pub problems: Vec<Value>,
    /// The unit of lengths.
    pub units: String,
}

/// Crossings and T-junctions listed one by one among the problems; the rest are counted.
pub const LISTED_DEFECTS: usize = 10_000;

/// The summary of `net` (named `file`); `imported` says what reading its file did, and
/// crossings and T-junctions closer than `point_tolerance` (mm) are not problems.
pub fn network(
    file: &str,
    net: &Network,
    imported: Option<&Imported>,
    point_tolerance: f64,
) -> NetworkInfo {
    let v = net.validate();
    let with_message = |value: Result<Value, serde_json::Error>, message: String| {
        let mut o = value.unwrap_or(Value::Null);
        if let Value::Object(m) = &mut o {
            m.insert("message".into(), message.into());
        }
        o
    };
    let mut problems: Vec<Value> = v
        .problems
        .iter()
        .map(|p| with_message(serde_json::to_value(p), p.to_string()))
        .collect();
    // A flat drawing that is not noded: crossings and T-junctions are problems too.
    let found = defects(net, point_tolerance, LISTED_DEFECTS);
    problems.extend(
        found
            .listed
            .iter()
            .map(|d| with_message(serde_json::to_value(d), d.to_string())),
    );
    if found.total() > found.listed.len() {
        let more = found.total() - found.listed.len();
        problems.push(serde_json::json!({
            "kind": "unlisted_defects",
            "count": more,
            "counted_all": found.counted_all,
            "message": format!(
                "{}{more} more crossings or T-junctions not listed ({} in all)",
                if found.counted_all { "" } else { "at least " },
                found.counted()
            ),
        }));
    }
    NetworkInfo {
        bbox: bbox(&net.bbox()),
        components: v.components,
        cycles: v.cycles,
        degree_histogram: v.degree_histogram,
        edges: net.edges.len(),
        file: file.to_string(),
        generator: net.meta.generator.clone(),
        import: imported.map(|imp| {
            serde_json::json!({
                "weld": imp.weld,
                "skipped": imp.skipped,
                "source_units": imp.units,
                "inserts": imp.inserts,
                "split_crossings": imp.split,
            })
        }),
        kind: "network",
        lengths: net.lengths().map(|l| Lengths {
            max: l.max,
            mean: l.mean,
            min: l.min,
            total: l.total,
        }),
        nodes: net.nodes.len(),
        problems,
        units: net.meta.units.clone(),
    }
}

/// A mesh's topology and size.
#[derive(Clone, Debug, Serialize)]
pub struct Topology {
    /// Area, mm².
    pub area: f64,
    /// Edges with one triangle.
    pub boundary_edges: usize,
    /// Boundary loops.
    pub boundary_loops: usize,
    /// Whether every edge has two triangles.
    pub closed: bool,
    /// Connected components.
    pub components: usize,
    /// Edges (members).
    pub edges: usize,
    /// V − E + F and its parts.
    pub euler: i64,
    /// Faces.
    pub faces: usize,
    /// Genus.
    pub genus: Option<i64>,
    /// Signed volume (negative when inside out), mm³.
    pub signed_volume: f64,
    /// Vertices.
    pub vertices: usize,
    /// Volume, mm³.
    pub volume: Option<f64>,
}

/// What reading a mesh found besides its triangles.
#[derive(Clone, Debug, Default, Serialize)]
pub struct MeshImport {
    /// `solid` blocks of an ASCII STL.
    pub bodies: Option<usize>,
    /// What the file held that is not read as the mesh (`l` records, bytes after a binary
    /// STL's triangles), one phrase each.
    pub not_read: Vec<String>,
    /// What welding near corners did, when asked.
    pub weld: Option<MeshWeld>,
}

/// What a mesh is. Fields in the command's order.
#[derive(Clone, Debug, Serialize)]
pub struct MeshInfo {
    /// Bounding box.
    pub bbox: Option<Bbox>,
    /// The file's name.
    pub file: String,
    /// What reading the file did.
    pub import: MeshImport,
    /// What it is.
    pub kind: &'static str,
    /// Every problem found, in words.
    pub problems: Vec<String>,
    /// Topology.
    pub topology: Topology,
    /// Triangles.
    pub triangles: usize,
    /// Whether vertices have colours.
    pub vertex_colors: bool,
    /// Vertices.
    pub vertices: usize,
}

/// The summary of `mesh` (named `file`).
pub fn mesh(file: &str, mesh: &TriMesh, import: MeshImport) -> MeshInfo {
    let t = mesh.check_manifold();
    MeshInfo {
        bbox: bbox(&mesh.bbox()),
        file: file.to_string(),
        import,
        kind: "mesh",
        problems: t.problems.iter().map(|p| p.to_string()).collect(),
        topology: Topology {
            area: t.area,
            boundary_edges: t.boundary_edges,
            boundary_loops: t.boundary_loops,
            closed: t.closed,
            components: t.components,
            edges: t.edges,
            euler: t.euler,
            faces: t.faces,
            genus: t.genus,
            signed_volume: t.signed_volume,
            vertices: t.vertices,
            volume: t.volume,
        },
        triangles: mesh.triangles.len(),
        vertex_colors: mesh.colors.is_some(),
        vertices: mesh.positions.len(),
    }
}
