//! `lamina._lamina`: every stage of the lamina library, called in memory for the Python package
//! (`python/lamina/`). Arrays cross as little-endian bytes one way and numpy arrays the other;
//! reports become dicts (numeric arrays as numpy arrays, large tables as columns) without
//! JSON text; no file is read or written but those a caller names. Options arrive as a dict
//! of the stage's option names; the Python side has checked the names, converted units and
//! left out what was not given.

mod convert;
mod options;
mod run;

use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use convert::{f64_array, from_py, i64_array, report, to_py};
use lamina::mesh::io::{read_mesh as read_mesh_file, write_mesh as write_mesh_file};
use lamina::network::io::{read_network as read_network_file, ReadOptions, RenderOptions};
use lamina::rationalize::axes::Axes;
use lamina::stage;
use lamina::{Edge, Meta, Network, Node, TriMesh};
use options::Opts;

/// `lamina.LaminaError(message)`: the package's own class (importable and picklable from
/// `lamina`), made here with the stage's message.
pub fn error(message: String) -> PyErr {
    Python::attach(|py| {
        match py
            .import("lamina._errors")
            .and_then(|m| m.getattr("LaminaError"))
            .and_then(|c| c.call1((message.clone(),)))
        {
            Ok(e) => PyErr::from_value(e),
            Err(e) => e,
        }
    })
}

/// `lamina.Cancelled(message)`.
pub fn cancelled(message: &str) -> PyErr {
    Python::attach(|py| {
        match py
            .import("lamina._errors")
            .and_then(|m| m.getattr("Cancelled"))
            .and_then(|c| c.call1((message,)))
        {
            Ok(e) => PyErr::from_value(e),
            Err(e) => e,
        }
    })
}

fn f64s(bytes: &[u8], what: &str) -> PyResult<Vec<f64>> {
    if !bytes.len().is_multiple_of(8) {
        return Err(error(format!(
            "{what}: {} bytes is not a whole number of float64 values",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

fn u32s(bytes: &[u8], what: &str) -> PyResult<Vec<u32>> {
    if !bytes.len().is_multiple_of(4) {
        return Err(error(format!(
            "{what}: {} bytes is not a whole number of uint32 values",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect())
}

fn points(v: &[f64]) -> Vec<DVec3> {
    v.chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect()
}

/// Coordinates beyond this are refused: 1000 km is no model, and far beyond it products of
/// coordinates overflow.
pub const MAX_COORD: f64 = 1e9;

/// The index and value of the first coordinate that is not finite or beyond `MAX_COORD`.
fn first_bad(p: &[DVec3]) -> Option<(usize, String)> {
    p.iter().enumerate().find_map(|(i, q)| {
        if !q.is_finite() {
            Some((i, "is not finite (NaN or infinite)".to_string()))
        } else if q.abs().max_element() > MAX_COORD {
            Some((
                i,
                format!(
                    "{} is beyond ±{MAX_COORD:e} mm (is the model in another unit? give units=)",
                    lamina::text::num(q.abs().max_element())
                ),
            ))
        } else {
            None
        }
    })
}

/// A network as Python hands it over: positions N×3 float64, edges E×2 uint32, node radii N
/// and edge radii E float64, normals N×3 float64 or empty for none (all little-endian bytes),
/// and its meta as a dict (or None).
#[derive(FromPyObject)]
struct NetworkBytes<'py>(
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyAny>,
);

impl NetworkBytes<'_> {
    /// The network, checked as strictly as the readers check a file, each problem naming the
    /// argument and index: no nodes or no edges, coordinates not finite or huge, edges out of
    /// range, repeated or of no length, radii not finite or negative.
    fn build(&self) -> PyResult<Network> {
        let NetworkBytes(positions, edges, node_radius, edge_radius, normals, meta) = self;
        let p = points(&f64s(positions.as_bytes(), "positions")?);
        let e = u32s(edges.as_bytes(), "edges")?;
        let nr = f64s(node_radius.as_bytes(), "node_radius")?;
        let er = f64s(edge_radius.as_bytes(), "edge_radius")?;
        let n = points(&f64s(normals.as_bytes(), "normals")?);
        if p.is_empty() {
            return Err(error(
                "positions: the network has no nodes: nothing to work on".into(),
            ));
        }
        if e.is_empty() {
            return Err(error(
                "edges: the network has no edges: nothing to work on".into(),
            ));
        }
        let counts = [
            ("node_radius", nr.len(), p.len()),
            ("edge_radius", er.len(), e.len() / 2),
            (
                "normals",
                if n.is_empty() { p.len() } else { n.len() },
                p.len(),
            ),
        ];
        if let Some((what, got, want)) = counts.into_iter().find(|(_, got, want)| got != want) {
            return Err(error(format!(
                "{what}: {got} rows for {want} (one per node or edge)"
            )));
        }
        if let Some((i, why)) = first_bad(&p) {
            return Err(error(format!("positions[{i}]: {why}")));
        }
        let net = Network {
            nodes: p
                .iter()
                .enumerate()
                .map(|(i, &p)| Node {
                    p,
                    // A row of NaN is "no normal" (as `read_network` gives nodes without one).
                    normal: n
                        .get(i)
                        .copied()
                        .filter(|v| !v.to_array().iter().all(|c| c.is_nan())),
                    radius: nr[i],
                })
                .collect(),
            edges: e
                .chunks_exact(2)
                .zip(&er)
                .map(|(ab, &radius)| Edge {
                    a: ab[0],
                    b: ab[1],
                    radius,
                })
                .collect(),
            meta: meta_of(meta)?,
        };
        use lamina::network::Problem;
        if let Some(problem) = net.validate().problems.first() {
            let (arg, k) = match *problem {
                Problem::NonFinitePosition { node } => ("positions", node),
                Problem::NonFiniteNormal { node } => ("normals", node),
                Problem::BadNodeRadius { node, .. } => ("node_radius", node),
                Problem::BadEdgeRadius { edge, .. } => ("edge_radius", edge),
                Problem::EdgeOutOfRange { edge, .. }
                | Problem::SelfLoop { edge, .. }
                | Problem::RepeatedEdge { edge, .. }
                | Problem::ZeroLength { edge, .. } => ("edges", edge),
            };
            return Err(error(format!("{arg}[{k}]: {problem}")));
        }
        Ok(net)
    }
}

/// A network's meta from the dict (None: the defaults).
fn meta_of(value: &Bound<'_, PyAny>) -> PyResult<Meta> {
    let mut meta = Meta::default();
    if value.is_none() {
        return Ok(meta);
    }
    let bad = |what: &str| error(format!("meta: {what}"));
    let serde_json::Value::Object(map) = from_py(value, "meta")? else {
        return Err(bad("expected a dict"));
    };
    for (key, v) in map {
        match (key.as_str(), v) {
            (_, serde_json::Value::Null) => {}
            ("units", serde_json::Value::String(u)) => meta.units = u,
            ("generator", serde_json::Value::String(g)) => meta.generator = Some(g),
            ("seed", v) if v.as_u64().is_some() => meta.seed = v.as_u64(),
            ("parameters", serde_json::Value::Object(p)) => {
                meta.parameters = p.into_iter().collect()
            }
            ("tags", serde_json::Value::Object(t)) => {
                for (k, v) in t {
                    let serde_json::Value::String(v) = v else {
                        return Err(bad(&format!("tag {k:?} is not a string")));
                    };
                    meta.tags.insert(k, v);
                }
            }
            (key, _) => {
                return Err(bad(&format!(
                    "{key:?} is not one of units, generator, parameters, seed, tags (or has the \
                     wrong type)"
                )))
            }
        }
    }
    Ok(meta)
}

/// A network as a dict of numpy arrays and its meta.
fn network_dict<'py>(py: Python<'py>, net: &Network) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let n = net.nodes.len();
    let p: Vec<f64> = net.nodes.iter().flat_map(|n| n.p.to_array()).collect();
    d.set_item("positions", f64_array(py, &p, &[n, 3])?)?;
    let e: Vec<i64> = net
        .edges
        .iter()
        .flat_map(|e| [i64::from(e.a), i64::from(e.b)])
        .collect();
    d.set_item("edges", i64_array(py, &e, &[net.edges.len(), 2])?)?;
    let nr: Vec<f64> = net.nodes.iter().map(|n| n.radius).collect();
    d.set_item("node_radius", f64_array(py, &nr, &[n])?)?;
    let er: Vec<f64> = net.edges.iter().map(|e| e.radius).collect();
    d.set_item("edge_radius", f64_array(py, &er, &[net.edges.len()])?)?;
    if net.nodes.iter().any(|n| n.normal.is_some()) {
        let v: Vec<f64> = net
            .nodes
            .iter()
            .flat_map(|n| n.normal.unwrap_or(DVec3::NAN).to_array())
            .collect();
        d.set_item("normals", f64_array(py, &v, &[n, 3])?)?;
    } else {
        d.set_item("normals", py.None())?;
    }
    let m = &net.meta;
    let meta = serde_json::json!({
        "units": m.units,
        "generator": m.generator,
        "parameters": m.parameters,
        "seed": m.seed,
        "tags": m.tags,
    });
    d.set_item("meta", to_py(py, &meta, &[])?)?;
    Ok(d)
}

/// A triangle mesh from bytes (vertices V×3 float64, faces F×3 uint32, colours V×3 float64 or
/// empty), checked as the mesh readers check a file; `what` names the argument.
fn mesh_from(what: &str, vertices: &[u8], faces: &[u8], colors: &[u8]) -> PyResult<TriMesh> {
    let positions = points(&f64s(vertices, &format!("{what}: vertices"))?);
    let corners = u32s(faces, &format!("{what}: faces"))?;
    if corners.len() < 3 {
        return Err(error(format!(
            "{what}: faces: no triangles: nothing to work on"
        )));
    }
    if let Some(k) = corners.iter().position(|&i| i as usize >= positions.len()) {
        return Err(error(format!(
            "{what}: faces[{}]: corner {} is not one of the {} vertices",
            k / 3,
            corners[k],
            positions.len()
        )));
    }
    if let Some((i, why)) = first_bad(&positions) {
        return Err(error(format!("{what}: vertices[{i}]: {why}")));
    }
    let colors = if colors.is_empty() {
        None
    } else {
        let c = f64s(colors, &format!("{what}: colors"))?;
        if c.len() != positions.len() * 3 {
            return Err(error(format!(
                "{what}: colors: {} rows for {} vertices",
                c.len() / 3,
                positions.len()
            )));
        }
        Some(
            c.chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                .collect(),
        )
    };
    Ok(TriMesh {
        positions,
        triangles: corners
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        colors,
    })
}

/// A mesh as Python hands it over: vertices, faces, colours (bytes; colours may be empty).
type MeshBytes<'py> = (
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
);

fn mesh_of(what: &str, m: &MeshBytes<'_>) -> PyResult<TriMesh> {
    mesh_from(what, m.0.as_bytes(), m.1.as_bytes(), m.2.as_bytes())
}

/// A mesh as a dict: vertices V×3, faces F×3 (int64), colors V×3 or None.
fn mesh_dict<'py>(py: Python<'py>, mesh: &TriMesh) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let v: Vec<f64> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
    d.set_item("vertices", f64_array(py, &v, &[mesh.positions.len(), 3])?)?;
    let f: Vec<i64> = mesh
        .triangles
        .iter()
        .flatten()
        .map(|&i| i64::from(i))
        .collect();
    d.set_item("faces", i64_array(py, &f, &[mesh.triangles.len(), 3])?)?;
    match &mesh.colors {
        Some(c) => {
            let c: Vec<f64> = c.iter().flatten().map(|&x| f64::from(x)).collect();
            d.set_item("colors", f64_array(py, &c, &[mesh.positions.len(), 3])?)?;
        }
        None => d.set_item("colors", py.None())?,
    }
    Ok(d)
}

/// Notes (defaults taken, things left out) for the Python side to warn with.
fn notes<'py>(py: Python<'py>, notes: &[String]) -> PyResult<Bound<'py, PyList>> {
    PyList::new(py, notes)
}

// Growing.

/// Leaf venation in a blade: `outline` (N×3 float64 bytes, z ignored) or a built-in `shape`.
#[pyfunction]
#[pyo3(signature = (shape, outline, options, progress=None))]
fn venation<'py>(
    py: Python<'py>,
    shape: &str,
    outline: Option<Bound<'py, PyBytes>>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use lamina::grow::outline::{Outline, Shape};
    let blade = match outline {
        Some(b) => {
            let p = points(&f64s(b.as_bytes(), "outline")?);
            if let Some((i, why)) = first_bad(&p) {
                return Err(error(format!("outline[{i}]: {why}")));
            }
            Outline::new(p.iter().map(|q| DVec2::new(q.x, q.y)).collect())
                .map_err(|e| error(format!("outline: {e}")))?
        }
        None => Outline::shape(match shape {
            "ovate" => Shape::Ovate,
            "lanceolate" => Shape::Lanceolate,
            "cordate" => Shape::Cordate,
            "circle" => Shape::Circle,
            "rect" => Shape::Rect,
            s => {
                return Err(error(format!(
                    "shape= {s:?}: give ovate, lanceolate, cordate, circle or rect"
                )))
            }
        }),
    };
    let mut o = Opts::new(&options, "venation");
    let opts = options::venation(&mut o)?;
    o.finish()?;
    let grown = run::run(py, progress.as_ref(), |h| {
        stage::venation::run(&blade, &opts, None, h)
    })?;
    let d = PyDict::new(py);
    d.set_item("network", network_dict(py, &grown.leaf.network)?)?;
    d.set_item("report", report(py, &grown.report, &[])?)?;
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

/// A root on a surface: a vertex index, `"tK"` for a triangle, or an (x, y, z) point.
fn surface_root(v: &Bound<'_, PyAny>) -> PyResult<stage::venation::Root> {
    use stage::venation::Root;
    if let Ok(i) = v.extract::<u32>() {
        return Ok(Root::Vertex(i));
    }
    if let Ok(s) = v.extract::<String>() {
        if let Some(t) = s.strip_prefix('t').and_then(|t| t.parse().ok()) {
            return Ok(Root::Triangle(t));
        }
        return Err(error(format!(
            "root= {s:?}: give a vertex index, \"tK\" for a triangle, or (x, y, z)"
        )));
    }
    if let Ok([x, y, z]) = v.extract::<[f64; 3]>() {
        return Ok(Root::Point(DVec3::new(x, y, z)));
    }
    Err(error(
        "root=: give a vertex index, \"tK\" for a triangle, or (x, y, z)".into(),
    ))
}

/// Leaf venation on a triangle mesh.
#[pyfunction]
#[pyo3(signature = (mesh, roots, options, progress=None))]
fn venation_on_surface<'py>(
    py: Python<'py>,
    mesh: MeshBytes<'py>,
    roots: Vec<Bound<'py, PyAny>>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut surface = mesh_of("surface", &mesh)?;
    let dropped = surface.drop_degenerate();
    if surface.triangles.is_empty() {
        return Err(error(format!(
            "surface: has no triangles with an area ({dropped} degenerate)"
        )));
    }
    let roots = roots
        .iter()
        .map(surface_root)
        .collect::<PyResult<Vec<_>>>()?;
    let mut o = Opts::new(&options, "venation_on_surface");
    let opts = options::venation(&mut o)?;
    o.finish()?;
    let grown = run::run(py, progress.as_ref(), |h| {
        stage::venation::on_surface(&surface, &roots, &opts, None, h)
    })?;
    let mut said = grown.notes.clone();
    if dropped > 0 {
        said.insert(
            0,
            format!(
                "surface: {dropped} degenerate triangles (a vertex used twice or no area) left out"
            ),
        );
    }
    let d = PyDict::new(py);
    d.set_item("network", network_dict(py, &grown.veins.network)?)?;
    d.set_item("report", report(py, &grown.report, &[])?)?;
    d.set_item("notes", notes(py, &said)?)?;
    Ok(d)
}

/// Geodesic veins along mesh edges.
#[pyfunction]
#[pyo3(signature = (mesh, options, progress=None))]
fn veins<'py>(
    py: Python<'py>,
    mesh: MeshBytes<'py>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut surface = mesh_of("surface", &mesh)?;
    surface.drop_degenerate();
    let mut o = Opts::new(&options, "veins");
    let opts = options::veins(&mut o)?;
    o.finish()?;
    let grown = run::run(py, progress.as_ref(), |h| {
        stage::veins::run(&surface, &opts, h)
    })?;
    let d = PyDict::new(py);
    d.set_item("network", network_dict(py, &grown.network)?)?;
    d.set_item("report", report(py, &grown.report, &[])?)?;
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

/// A bracketed L-system (a grammar file's text and name optional), drawn or only counted.
#[pyfunction]
#[pyo3(signature = (grammar, options, derive_only, progress=None))]
fn lsystem<'py>(
    py: Python<'py>,
    grammar: Option<(String, String)>,
    options: Bound<'py, PyDict>,
    derive_only: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut o = Opts::new(&options, "lsystem");
    let mut opts = options::lsystem(&mut o)?;
    opts.shape = options::shape(&mut o)?;
    o.finish()?;
    if let Some((text, name)) = grammar {
        let parsed = if name.ends_with(".json") {
            lamina::grow::lsystem::parse_json(&text, &name)
        } else {
            lamina::grow::lsystem::parse_text(&text, &name)
        };
        opts.grammar = Some(parsed.map_err(|e| error(e.to_string()))?);
        opts.grammar_name = name;
    }
    let d = PyDict::new(py);
    if derive_only {
        let counts = run::run(py, progress.as_ref(), |h| stage::lsystem::count(&opts, h))?;
        let r = serde_json::json!({
            "symbols": counts.symbols,
            "segments": counts.segments,
            "simplified_segments": counts.simplified_segments,
        });
        d.set_item("report", to_py(py, &r, &[])?)?;
    } else {
        let drawn = run::run(py, progress.as_ref(), |h| stage::lsystem::run(&opts, h))?;
        d.set_item("network", network_dict(py, &drawn.network)?)?;
        d.set_item("report", report(py, &drawn.report, &[])?)?;
    }
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

/// A tree by recursive bifurcation.
#[pyfunction]
fn bifurcate<'py>(py: Python<'py>, options: Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let mut o = Opts::new(&options, "bifurcate");
    let mut opts = options::bifurcate(&mut o)?;
    opts.shape = options::shape(&mut o)?;
    o.finish()?;
    let drawn = run::run(py, None, |_| stage::bifurcate::run(&opts))?;
    let d = PyDict::new(py);
    d.set_item("network", network_dict(py, &drawn.network)?)?;
    d.set_item("report", report(py, &drawn.report, &[])?)?;
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

/// A bud program (its text and name) grown into a form.
#[pyfunction]
#[pyo3(signature = (program, name, options, progress=None))]
fn buds<'py>(
    py: Python<'py>,
    program: &str,
    name: &str,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let program =
        lamina::grow::buds::parse_program(program, name).map_err(|e| error(e.to_string()))?;
    let mut o = Opts::new(&options, "buds");
    let mut opts = options::buds(&mut o)?;
    // By file name, as the CLI's report names it (errors above keep the whole path).
    opts.program_name = lamina::files::file_name(std::path::Path::new(name));
    o.finish()?;
    let grown = run::run(py, progress.as_ref(), |h| {
        stage::buds::run(&program, &opts, None, h)
    })?;
    let d = PyDict::new(py);
    d.set_item("mesh", mesh_dict(py, &grown.mesh)?)?;
    d.set_item("report", report(py, &grown.report, &[])?)?;
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

// Rationalizing.

/// The closed cells of a network, triangulated.
#[pyfunction]
#[pyo3(signature = (network, surface, options))]
fn cells<'py>(
    py: Python<'py>,
    network: NetworkBytes<'py>,
    surface: Option<MeshBytes<'py>>,
    options: Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    let net = network.build()?;
    let surface = surface.map(|m| mesh_of("surface", &m)).transpose()?;
    let mut o = Opts::new(&options, "cells");
    let tolerance = o.f64("point_tolerance")?;
    o.finish()?;
    let opts = stage::cells::Options {
        point_tolerance: tolerance,
        surface_name: "surface".into(),
    };
    let found = run::run(py, None, |_| {
        stage::cells::run(&net, surface.as_ref(), &opts)
    })?;
    let d = PyDict::new(py);
    d.set_item("mesh", mesh_dict(py, &found.cells.mesh)?)?;
    let n: Vec<f64> = found
        .cells
        .normals
        .iter()
        .flat_map(|v| v.to_array())
        .collect();
    d.set_item(
        "normals",
        f64_array(py, &n, &[found.cells.normals.len(), 3])?,
    )?;
    d.set_item("table", report(py, &found.table, &["cells", "holes"])?)?;
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

/// Fewer, straighter members.
#[pyfunction]
#[pyo3(signature = (network, surface, options))]
fn simplify<'py>(
    py: Python<'py>,
    network: NetworkBytes<'py>,
    surface: Option<MeshBytes<'py>>,
    options: Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    let net = network.build()?;
    let surface = surface.map(|m| mesh_of("surface", &m)).transpose()?;
    let mut o = Opts::new(&options, "simplify");
    let opts = options::simplify(&mut o)?;
    o.finish()?;
    let done = run::run(py, None, |_| {
        stage::simplify::run(&net, surface.as_ref(), &opts)
    })?;
    let d = PyDict::new(py);
    d.set_item("network", network_dict(py, &done.simplified.network)?)?;
    d.set_item("report", report(py, &done.simplified.report, &[])?)?;
    d.set_item("notes", notes(py, &done.notes)?)?;
    Ok(d)
}

/// A planarity report as a dict, its `panels` and `worst` as columns built straight from the
/// rows (a report of 100,000 panels would otherwise pass through a tree of 1.5 M values).
fn planarity<'py>(
    py: Python<'py>,
    r: &lamina::report::planarity::Report,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if let serde_json::Value::Object(context) =
        serde_json::to_value(&r.context).map_err(|e| error(e.to_string()))?
    {
        for (k, v) in context {
            d.set_item(k, to_py(py, &v, &[])?)?;
        }
    }
    d.set_item("summary", report(py, &r.summary, &[])?)?;
    d.set_item("definitions", report(py, &r.definitions, &[])?)?;
    d.set_item("histogram", report(py, &r.histogram, &[])?)?;
    d.set_item("worst", panel_columns(py, &r.worst)?)?;
    d.set_item("panels", panel_columns(py, &r.panels)?)?;
    Ok(d)
}

/// Panel rows as columns (the keys a row of the report file has).
fn panel_columns<'py>(
    py: Python<'py>,
    rows: &[lamina::report::planarity::PanelRow],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let n = rows.len();
    let f = |get: &dyn Fn(&lamina::report::planarity::PanelRow) -> f64| -> Vec<f64> {
        rows.iter().map(get).collect()
    };
    let index: Vec<i64> = rows.iter().map(|r| r.index as i64).collect();
    d.set_item("index", i64_array(py, &index, &[n])?)?;
    if rows.iter().all(|r| r.nodes.is_some()) {
        let nodes: Vec<i64> = rows
            .iter()
            .flat_map(|r| r.nodes.unwrap_or_default().map(i64::from))
            .collect();
        d.set_item("nodes", i64_array(py, &nodes, &[n, 2])?)?;
    } else {
        let list = PyList::empty(py);
        for r in rows {
            list.append(r.nodes.map(|v| v.to_vec()))?;
        }
        d.set_item("nodes", list)?;
    }
    for (key, get) in [
        (
            "name",
            &(|r: &lamina::report::planarity::PanelRow| r.name.clone()) as &dyn Fn(_) -> _,
        ),
        ("layer", &|r: &lamina::report::planarity::PanelRow| {
            r.layer.clone()
        }),
        ("group", &|r: &lamina::report::planarity::PanelRow| {
            r.group.clone()
        }),
        ("class", &|r: &lamina::report::planarity::PanelRow| {
            r.class_name.clone()
        }),
    ] {
        let values: Vec<Option<String>> = rows.iter().map(get).collect();
        if values.iter().any(Option::is_some) {
            d.set_item(key, PyList::new(py, values)?)?;
        }
    }
    d.set_item("tolerance", f64_array(py, &f(&|r| r.tolerance), &[n])?)?;
    let pass: Vec<bool> = rows.iter().map(|r| r.pass).collect();
    d.set_item("pass", convert::bool_array(py, &pass)?)?;
    let m =
        |get: &dyn Fn(&lamina::rationalize::panels::QuadMetrics) -> f64| f(&|r| get(&r.metrics));
    d.set_item("flatness", f64_array(py, &m(&|q| q.flatness), &[n])?)?;
    d.set_item("best_fit", f64_array(py, &m(&|q| q.best_fit), &[n])?)?;
    let normal: Vec<f64> = rows.iter().flat_map(|r| r.metrics.normal).collect();
    d.set_item("normal", f64_array(py, &normal, &[n, 3])?)?;
    d.set_item("deviation", f64_array(py, &m(&|q| q.deviation), &[n])?)?;
    d.set_item(
        "diagonal_distance",
        f64_array(py, &m(&|q| q.diagonal_distance), &[n])?,
    )?;
    d.set_item(
        "diagonal_rel_edge",
        f64_array(py, &m(&|q| q.diagonal_rel_edge), &[n])?,
    )?;
    d.set_item(
        "diagonal_rel_diagonal",
        f64_array(py, &m(&|q| q.diagonal_rel_diagonal), &[n])?,
    )?;
    d.set_item("torsion_deg", f64_array(py, &m(&|q| q.torsion_deg), &[n])?)?;
    Ok(d)
}

/// Node axes that make every panel planar.
#[pyfunction]
#[pyo3(signature = (network, surface, options, progress=None))]
fn planarize<'py>(
    py: Python<'py>,
    network: NetworkBytes<'py>,
    surface: Option<MeshBytes<'py>>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let net = network.build()?;
    let surface = surface.map(|m| mesh_of("surface", &m)).transpose()?;
    let mut o = Opts::new(&options, "planarize");
    let opts = options::planarize(&mut o)?;
    o.finish()?;
    let solved = run::run(py, progress.as_ref(), |h| {
        stage::planarize::run(&net, surface.as_ref(), &opts, h)
    })?;
    let d = axes_dict(py, &solved.axes)?;
    d.set_item("within", solved.solution.converged)?;
    d.set_item("summary", report(py, &solved.summary, &[])?)?;
    d.set_item("report", planarity(py, &solved.report)?)?;
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

/// Axes as a dict: what `size` and `plates` take back (positions, edges, axes, heights,
/// reference, fixed_normals with NaN rows for none, edge_radius) and the panels P×4×3.
fn axes_dict<'py>(py: Python<'py>, a: &Axes) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let n = a.positions.len();
    let flat = |v: &[DVec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f64>>();
    d.set_item("positions", f64_array(py, &flat(&a.positions), &[n, 3])?)?;
    let e: Vec<i64> = a.edges.iter().flatten().map(|&i| i64::from(i)).collect();
    d.set_item("edges", i64_array(py, &e, &[a.edges.len(), 2])?)?;
    d.set_item("axes", f64_array(py, &flat(&a.axes), &[n, 3])?)?;
    d.set_item("heights", f64_array(py, &a.heights, &[n])?)?;
    d.set_item("reference", f64_array(py, &flat(&a.reference), &[n, 3])?)?;
    let fixed: Vec<DVec3> = a
        .fixed_normals
        .iter()
        .map(|f| f.unwrap_or(DVec3::NAN))
        .collect();
    d.set_item(
        "fixed_normals",
        f64_array(py, &flat(&fixed), &[a.edges.len(), 3])?,
    )?;
    d.set_item(
        "edge_radius",
        f64_array(py, &a.edge_radii, &[a.edges.len()])?,
    )?;
    let quads: Vec<f64> = a
        .quads()
        .iter()
        .flat_map(|q| q.iter().flat_map(|p| p.to_array()))
        .collect();
    d.set_item("panels", f64_array(py, &quads, &[a.edges.len(), 4, 3])?)?;
    Ok(d)
}

/// Axes from the dict `planarize` returns (or one built the same way).
#[derive(FromPyObject)]
struct AxesBytes<'py>(
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
);

impl AxesBytes<'_> {
    fn build(&self) -> PyResult<Axes> {
        let AxesBytes(p, e, a, h, r, f, er) = self;
        let positions = points(&f64s(p.as_bytes(), "axes: positions")?);
        let edges: Vec<[u32; 2]> = u32s(e.as_bytes(), "axes: edges")?
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
            .collect();
        let axes = points(&f64s(a.as_bytes(), "axes: axes")?);
        let heights = f64s(h.as_bytes(), "axes: heights")?;
        let reference = points(&f64s(r.as_bytes(), "axes: reference")?);
        let fixed: Vec<Option<DVec3>> = points(&f64s(f.as_bytes(), "axes: fixed_normals")?)
            .into_iter()
            .map(|v| v.is_finite().then_some(v))
            .collect();
        let edge_radii = f64s(er.as_bytes(), "axes: edge_radius")?;
        let n = positions.len();
        for (what, got, want) in [
            ("axes", axes.len(), n),
            ("heights", heights.len(), n),
            ("reference", reference.len(), n),
            ("fixed_normals", fixed.len(), edges.len()),
            ("edge_radius", edge_radii.len(), edges.len()),
        ] {
            if got != want {
                return Err(error(format!("axes: {what}: {got} rows for {want}")));
            }
        }
        if n == 0 || edges.is_empty() {
            return Err(error(
                "axes: no nodes or no edges: nothing to work on".into(),
            ));
        }
        if let Some((i, why)) = first_bad(&positions) {
            return Err(error(format!("axes: positions[{i}]: {why}")));
        }
        if let Some(k) = edges
            .iter()
            .position(|&[a, b]| a as usize >= n || b as usize >= n || a == b)
        {
            return Err(error(format!(
                "axes: edges[{k}]: joins nodes {} and {} of {n}",
                edges[k][0], edges[k][1]
            )));
        }
        if let Some(i) = axes
            .iter()
            .position(|v| !(v.is_finite() && (v.length() - 1.0).abs() < 1e-6))
        {
            return Err(error(format!("axes: axes[{i}]: not a unit vector")));
        }
        if let Some(i) = heights.iter().position(|h| !(h.is_finite() && *h > 0.0)) {
            return Err(error(format!("axes: heights[{i}]: not a positive height")));
        }
        Ok(Axes {
            positions,
            edges,
            axes,
            heights,
            reference,
            fixed_normals: fixed,
            edge_radii,
        })
    }
}

/// Names, layers and groups of panels, one each (or None).
type Labels = (
    Vec<Option<String>>,
    Vec<Option<String>>,
    Vec<Option<String>>,
);

/// The planarity audit of panels: polygons (corners as float64 bytes, a count per polygon),
/// with optional names, layers and groups.
#[pyfunction]
#[pyo3(signature = (corners, counts, labels, options))]
fn audit<'py>(
    py: Python<'py>,
    corners: Bound<'py, PyBytes>,
    counts: Vec<usize>,
    labels: Option<Labels>,
    options: Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    use lamina::rationalize::audit::{Panel, Panels};
    let p = points(&f64s(corners.as_bytes(), "panels")?);
    if counts.iter().sum::<usize>() != p.len() {
        return Err(error(
            "panels: corner counts do not add up to the corners".into(),
        ));
    }
    if let Some((i, why)) = first_bad(&p) {
        return Err(error(format!("panels: corner {i}: {why}")));
    }
    let mut panels = Vec::with_capacity(counts.len());
    let mut at = 0;
    for (k, &c) in counts.iter().enumerate() {
        let label = |v: &Vec<Option<String>>| v.get(k).cloned().flatten();
        let (name, layer, group) = match &labels {
            Some((n, l, g)) => (label(n), label(l), label(g)),
            None => (None, None, None),
        };
        panels.push(Panel {
            corners: p[at..at + c].to_vec(),
            name,
            layer,
            group,
            ..Default::default()
        });
        at += c;
    }
    let mut o = Opts::new(&options, "audit");
    let opts = options::audit(&mut o)?;
    o.finish()?;
    audited(
        py,
        Panels {
            panels,
            notes: Vec::new(),
        },
        &opts,
    )
}

/// The planarity audit of a panel file (.obj .dxf .json).
#[pyfunction]
fn audit_file<'py>(
    py: Python<'py>,
    path: PathBuf,
    options: Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut o = Opts::new(&options, "audit");
    let mut opts = options::audit(&mut o)?;
    o.finish()?;
    opts.name = path.display().to_string();
    let read = py
        .detach(|| lamina::rationalize::audit::read_panels(&path))
        .map_err(|e| error(e.to_string()))?;
    audited(py, read, &opts)
}

fn audited<'py>(
    py: Python<'py>,
    panels: lamina::rationalize::audit::Panels,
    opts: &stage::audit::Options,
) -> PyResult<Bound<'py, PyDict>> {
    let read_notes = panels.notes.clone();
    let done = run::run(py, None, |_| stage::audit::run(panels, opts))?;
    let d = PyDict::new(py);
    d.set_item("within", done.report.summary.within_tolerance)?;
    d.set_item("report", planarity(py, &done.report)?)?;
    let said: Vec<String> = read_notes.into_iter().chain(done.notes).collect();
    d.set_item("notes", notes(py, &said)?)?;
    Ok(d)
}

// Steel.

/// Frame analysis of the plate network and the gauges it needs.
#[pyfunction]
#[pyo3(signature = (axes, options, progress=None))]
fn size<'py>(
    py: Python<'py>,
    axes: AxesBytes<'py>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let axes = axes.build()?;
    let mut o = Opts::new(&options, "size");
    let opts = options::size(&mut o)?;
    o.finish()?;
    let sized = run::run(py, progress.as_ref(), |h| stage::size::run(&axes, &opts, h))?;
    let d = PyDict::new(py);
    d.set_item("within", sized.ok)?;
    d.set_item("sizing", report(py, &sized.report, &["edges", "nodes"])?)?;
    let gauges: Vec<f64> = sized.report.edges.iter().map(|e| e.gauge).collect();
    d.set_item("gauges", f64_array(py, &gauges, &[gauges.len()])?)?;
    d.set_item(
        "gauge_list",
        f64_array(py, &sized.report.gauges, &[sized.report.gauges.len()])?,
    )?;
    d.set_item("notes", notes(py, &sized.notes)?)?;
    Ok(d)
}

/// A sizing as the Python side hands it over: the gauges per edge and the list (little-endian
/// f64), the material as JSON, the assembly groups its seams were sized for, and per edge
/// what a seam's bolts carry (JSON: null or six numbers), and the joints it weighed the plates
/// with (JSON: sizing.json's `joints`, null when it weighed the uncut panels).
type SizingArg<'py> = (
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    String,
    Option<usize>,
    String,
    String,
);

/// Steel plates from node axes; with `out`, the command's files written into that folder.
#[pyfunction]
#[pyo3(signature = (axes, sizing, options, out=None))]
fn plates<'py>(
    py: Python<'py>,
    axes: AxesBytes<'py>,
    sizing: Option<SizingArg<'py>>,
    options: Bound<'py, PyDict>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let axes = axes.build()?;
    let mut o = Opts::new(&options, "plates");
    let mut opts = options::plates(&mut o)?;
    o.finish()?;
    if let Some((per_edge, list, material, seam_groups, seam_forces, joints)) = sizing {
        let joints = lamina::analyze::sizing::joints_from_json(&joints)
            .map_err(|e| error(format!("sizing: its joints: {e}")))?;
        let seam_forces: Vec<Option<[f64; 6]>> = serde_json::from_str(&seam_forces)
            .map_err(|e| error(format!("sizing: its edges' seam_forces: {e}")))?;
        if seam_forces
            .iter()
            .flatten()
            .flatten()
            .any(|v| !(v.is_finite() && v.abs() < 1e15))
        {
            return Err(error(
                "sizing: seam_forces must be six finite numbers (N, N·mm) per seam".into(),
            ));
        }
        opts.sizing = Some(stage::plates::Gauges {
            per_edge: f64s(per_edge.as_bytes(), "sizing: gauges")?,
            list: f64s(list.as_bytes(), "sizing: gauge_list")?,
            material: Some(
                serde_json::from_str(&material)
                    .map_err(|e| error(format!("sizing: its material: {e}")))?,
            ),
            seam_groups,
            seam_forces,
            joints,
        });
    }
    let made = run::run(py, None, |_| stage::plates::run(&axes, &opts))?;
    let mut files = Vec::new();
    if let Some(dir) = &out {
        files = py
            .detach(|| write_plates(&made, &axes, dir))
            .map_err(|e| error(e.to_string()))?;
    }
    // The assembly mesh on the pool (its plates side by side) while this thread turns the
    // reports into dicts.
    let d = PyDict::new(py);
    let (assembly, ()) = run::beside(
        py,
        || stage::plates::assembly(&made.set),
        || {
            d.set_item("within", made.ok)?;
            d.set_item("plates", report(py, &made.file, &[])?)?;
            d.set_item("welds", report(py, &made.welds, &[])?)
        },
    )?;
    d.set_item("assembly", mesh_dict(py, &assembly)?)?;
    d.set_item("files", PyList::new(py, files)?)?;
    d.set_item("notes", notes(py, &made.notes)?)?;
    Ok(d)
}

/// What `lamina plates` writes, into `dir`.
fn write_plates(
    made: &stage::plates::Plated,
    axes: &Axes,
    dir: &Path,
) -> Result<Vec<String>, Box<dyn std::error::Error + Send + Sync>> {
    use lamina::view::scene::Input;
    let inputs = vec![(
        "axes".to_string(),
        Input::Axes(Box::new(axes.clone()), None),
    )];
    let (page, _) = stage::plates::weld_page(made, inputs, false)?;
    stage::plates::write_folder(made, dir, &page)?;
    let mut files: Vec<String> = ["plates.json", "assembly.stl", "assembly.obj", "welds.json"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    files.extend(
        made.set
            .plates
            .iter()
            .map(|p| format!("parts/{}.dxf", p.id)),
    );
    files.extend(["assembly.scad".to_string(), "welds.html".to_string()]);
    Ok(files)
}

/// Plates nested on stock sheets; with `out`, the cut files written into that folder.
#[pyfunction]
#[pyo3(signature = (plates, options, out=None, progress=None))]
fn nest<'py>(
    py: Python<'py>,
    plates: Bound<'py, PyAny>,
    options: Bound<'py, PyDict>,
    out: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let doc = from_py(&plates, "plates")?;
    let (records, cores, material) =
        lamina::fabricate::plates_file::records_from_value(doc, Path::new("plates"))
            .map_err(|e| error(e.to_string()))?;
    let mut o = Opts::new(&options, "nest");
    let mut opts = options::nest(&mut o)?;
    let post = options::nc_post(&mut o)?;
    o.finish()?;
    if let Some(m) = material {
        opts.material = m;
    }
    let cut = run::run(py, progress.as_ref(), |h| {
        stage::nest::run(records, cores, &opts, h)
    })?;
    let bom = stage::nest::bom_csv(&cut);
    let programs = match &post {
        Some(post) => stage::nest::nc_programs(&cut, post).map_err(|e| error(e.to_string()))?,
        None => Vec::new(),
    };
    let mut files = Vec::new();
    if let Some(dir) = &out {
        files = py
            .detach(|| write_nest(&cut, &bom, &programs, dir))
            .map_err(|e| error(e.to_string()))?;
    }
    let d = PyDict::new(py);
    d.set_item("nest", report(py, &cut.doc, &["placements"])?)?;
    d.set_item("bom", bom)?;
    d.set_item("svg", stage::nest::svg(&cut))?;
    let outlines = PyDict::new(py);
    for (p, drawn) in cut.plates.iter().zip(&cut.drawn) {
        let xy: Vec<f64> = drawn.outline.iter().flat_map(|q| [q.x, q.y]).collect();
        outlines.set_item(&p.id, f64_array(py, &xy, &[drawn.outline.len(), 2])?)?;
    }
    d.set_item("outlines", outlines)?;
    let nc = PyDict::new(py);
    for (name, text) in &programs {
        nc.set_item(name, text)?;
    }
    d.set_item("nc", nc)?;
    d.set_item("files", PyList::new(py, files)?)?;
    d.set_item("notes", notes(py, &[])?)?;
    Ok(d)
}

/// What `lamina nest` writes, into `dir` (with the NC programs made, if any).
fn write_nest(
    cut: &stage::nest::Nested,
    bom: &str,
    programs: &[(String, String)],
    dir: &Path,
) -> Result<Vec<String>, Box<dyn std::error::Error + Send + Sync>> {
    use lamina::files::write_atomic;
    use std::io::Write as _;
    std::fs::create_dir_all(dir)?;
    stage::nest::write_sheets(cut, dir)?;
    let mut files: Vec<String> = cut.sheets.iter().map(|s| s.file.clone()).collect();
    stage::nest::write_programs(programs, dir)?;
    files.extend(programs.iter().map(|(name, _)| name.clone()));
    if cut.joints.is_none() {
        stage::nest::write_assembly(cut, &dir.join("assembly.scad"))?;
        files.push("assembly.scad".into());
    }
    write_atomic(&dir.join("bom.csv"), |w| w.write_all(bom.as_bytes()))?;
    let text = cut.doc.json();
    write_atomic(&dir.join("nest.json"), |w| w.write_all(text.as_bytes()))?;
    let svg = stage::nest::svg(cut);
    write_atomic(&dir.join("sheets.svg"), |w| w.write_all(svg.as_bytes()))?;
    files.extend(["bom.csv", "nest.json", "sheets.svg"].map(String::from));
    Ok(files)
}

// Printing.

/// The network's veins as one closed mesh.
#[pyfunction]
#[pyo3(signature = (network, options, progress=None))]
fn solid<'py>(
    py: Python<'py>,
    network: NetworkBytes<'py>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let net = network.build()?;
    let mut o = Opts::new(&options, "solid");
    let opts = options::solid(&mut o)?;
    o.finish()?;
    let made = run::run(py, progress.as_ref(), |h| stage::solid::run(&net, &opts, h))?;
    let d = PyDict::new(py);
    d.set_item("mesh", mesh_dict(py, &made.mesh)?)?;
    d.set_item("report", report(py, &made.report, &[])?)?;
    let said: Vec<String> = made
        .notes
        .iter()
        .cloned()
        .chain(made.warnings.iter().map(|w| format!("warning: {w}")))
        .collect();
    d.set_item("notes", notes(py, &said)?)?;
    Ok(d)
}

/// Closed meshes sliced into an SL1 archive (its bytes), each model (name, vertices, faces).
#[pyfunction]
#[pyo3(signature = (models, options, progress=None))]
fn slice<'py>(
    py: Python<'py>,
    models: Vec<(String, Bound<'py, PyBytes>, Bound<'py, PyBytes>)>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let models = models
        .iter()
        .enumerate()
        .map(|(k, (name, v, f))| {
            Ok(stage::slice::Model {
                path: PathBuf::from(name),
                mesh: mesh_from(&format!("models[{k}]"), v.as_bytes(), f.as_bytes(), &[])?,
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let mut o = Opts::new(&options, "slice");
    let opts = options::slice(&mut o)?;
    o.finish()?;
    let mut archive = std::io::Cursor::new(Vec::new());
    let sliced = run::run(py, progress.as_ref(), |h| {
        stage::slice::run(&models, &opts, &mut archive, None, h)
    })?;
    sliced_dict(py, &sliced, archive.into_inner())
}

fn sliced_dict<'py>(
    py: Python<'py>,
    sliced: &stage::slice::Sliced,
    archive: Vec<u8>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("sl1", PyBytes::new(py, &archive))?;
    d.set_item(
        "report",
        report(py, &sliced.report, &["islands", "placements"])?,
    )?;
    d.set_item("notes", notes(py, &sliced.notes)?)?;
    Ok(d)
}

/// The network's solid sliced straight from its distance, into an SL1 archive.
#[pyfunction]
#[pyo3(signature = (network, options, progress=None))]
fn print<'py>(
    py: Python<'py>,
    network: NetworkBytes<'py>,
    options: Bound<'py, PyDict>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let net = network.build()?;
    let mut o = Opts::new(&options, "print");
    let opts = options::print(&mut o)?;
    o.finish()?;
    let mut archive = std::io::Cursor::new(Vec::new());
    let sliced = run::run(py, progress.as_ref(), |h| {
        stage::print::run(&net, &opts, &mut archive, h)
    })?;
    sliced_dict(py, &sliced, archive.into_inner())
}

// Files.

/// Reads a network file (.json .obj .dxf) as the commands read it with their default flags
/// (and `units` for an OBJ or DXF, `hatch_boundaries` for a DXF's HATCH fills); the notes say
/// what was assumed or left out.
#[pyfunction]
#[pyo3(signature = (path, units=None, hatch_boundaries=false))]
fn read_network<'py>(
    py: Python<'py>,
    path: PathBuf,
    units: Option<String>,
    hatch_boundaries: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let mut opts = ReadOptions {
        hatch_boundaries,
        ..ReadOptions::default()
    };
    if let Some(u) = units {
        opts.units = Some(
            lamina::network::io::units::LengthUnit::parse(&u).ok_or_else(|| {
                error(format!(
                    "units= {u:?} is not a unit lamina knows ({})",
                    lamina::network::io::units::LengthUnit::NAMES
                ))
            })?,
        );
    }
    let imported = py
        .detach(|| read_network_file(&path, &opts))
        .map_err(|e| error(e.to_string()))?;
    let mut said = Vec::new();
    if let Some(u) = imported
        .units
        .as_ref()
        .filter(|u| u.assumed || u.scale_to_mm != 1.0)
    {
        said.push(format!("{}: units {}", path.display(), u.describe()));
    }
    if !imported.skipped.is_empty() {
        let list: Vec<String> = imported
            .skipped
            .iter()
            .map(|(k, n)| format!("{n} {k}"))
            .collect();
        said.push(format!("{}: not read: {}", path.display(), list.join(", ")));
    }
    let d = network_dict(py, &imported.network)?;
    d.set_item("notes", notes(py, &said)?)?;
    Ok(d)
}

/// Writes a network as lamina JSON, OBJ, DXF or SVG (by extension).
#[pyfunction]
fn write_network(py: Python<'_>, path: PathBuf, network: NetworkBytes<'_>) -> PyResult<()> {
    let net = network.build()?;
    py.detach(|| lamina::network::io::write_network(&net, &path, &RenderOptions::default()))
        .map_err(|e| error(e.to_string()))
}

/// Reads a triangle mesh (.obj .stl) as a dict.
#[pyfunction]
fn read_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let mesh = py
        .detach(|| read_mesh_file(&path))
        .map_err(|e| error(e.to_string()))?;
    mesh_dict(py, &mesh)
}

/// Writes a triangle mesh (.obj .stl .png by extension).
#[pyfunction]
fn write_mesh(py: Python<'_>, path: PathBuf, mesh: MeshBytes<'_>) -> PyResult<()> {
    let m = mesh_of("mesh", &mesh)?;
    py.detach(|| write_mesh_file(&m, &path, 1024))
        .map_err(|e| error(e.to_string()))
}

/// The option names each function takes (the Python side checks keyword arguments against
/// them, and suggests the closest).
#[pyfunction]
fn option_names(function: &str) -> Vec<&'static str> {
    options::names(function).to_vec()
}

#[pymodule]
fn _lamina(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // As in the binary: the DXF parser's panics are caught and reported as the file's error, so
    // they print nothing.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().name() != Some(lamina::network::io::dxf::PARSER_THREAD) {
            default_hook(info);
        }
    }));
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MAX_COORD", MAX_COORD)?;
    for f in [
        wrap_pyfunction!(venation, m)?,
        wrap_pyfunction!(venation_on_surface, m)?,
        wrap_pyfunction!(veins, m)?,
        wrap_pyfunction!(lsystem, m)?,
        wrap_pyfunction!(bifurcate, m)?,
        wrap_pyfunction!(buds, m)?,
        wrap_pyfunction!(cells, m)?,
        wrap_pyfunction!(simplify, m)?,
        wrap_pyfunction!(planarize, m)?,
        wrap_pyfunction!(audit, m)?,
        wrap_pyfunction!(audit_file, m)?,
        wrap_pyfunction!(size, m)?,
        wrap_pyfunction!(plates, m)?,
        wrap_pyfunction!(nest, m)?,
        wrap_pyfunction!(solid, m)?,
        wrap_pyfunction!(slice, m)?,
        wrap_pyfunction!(print, m)?,
        wrap_pyfunction!(read_network, m)?,
        wrap_pyfunction!(write_network, m)?,
        wrap_pyfunction!(read_mesh, m)?,
        wrap_pyfunction!(write_mesh, m)?,
        wrap_pyfunction!(option_names, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
