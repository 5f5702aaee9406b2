//! `lamina._lamina`: the commands of the lamina binary, run in-process for the Python package.
//!
//! The command-line modules are compiled here as they are in the binary (`cli` below is
//! `src/cli`), so a command parses its flags, computes, writes its files and words its errors
//! with the same code: the package's results and reports are the binary's. What a command
//! prints is captured (`cli::say`), its notes handed back, its progress bar read by a watcher
//! that calls the Python callback. `planarize`, `solid` and `slice` take their input from
//! memory and hand their results back without a file (but slice's archive); for the other commands the Python side (`python/lamina/`)
//! moves arrays in and out of files in a private folder.

#[allow(dead_code, clippy::all)]
#[path = "../../src/cli/mod.rs"]
mod cli;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use clap::Parser;
use glam::DVec3;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use lamina::mesh::io::{read_mesh as read_mesh_file, write_mesh as write_mesh_file};
use lamina::network::io::{read_network as read_network_file, ReadOptions, RenderOptions};
use lamina::{Edge, Meta, Network, Node, ReadError, TriMesh};

pyo3::create_exception!(
    _lamina,
    LaminaError,
    PyValueError,
    "An error of a lamina command: bad input, a bad option or a failed write; the message is \
     the one the lamina binary prints."
);

/// How often the progress callback is called while a command runs.
const PROGRESS_EVERY: Duration = Duration::from_millis(100);

/// Runs `lamina ARGV…` in-process with the GIL released. Returns (within, stdout, notes):
/// within is False where the binary exits 1 (a tolerance not met). Raises LaminaError with the
/// binary's message where it exits 2. `progress(stage, message, done, total)` is called about
/// ten times a second while a progress bar runs (total None for a spinner).
#[pyfunction]
#[pyo3(signature = (argv, progress=None))]
fn run(
    py: Python<'_>,
    argv: Vec<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(bool, String, Vec<String>)> {
    let parsed = match cli::Cli::try_parse_from(std::iter::once("lamina".to_string()).chain(argv)) {
        Ok(parsed) => parsed,
        // `--help` and `--version` are what the command prints, not errors.
        Err(e) if !e.use_stderr() => return Ok((true, e.render().to_string(), Vec::new())),
        Err(e) => return Err(clap_error(&e)),
    };
    let (within, captured) = in_process(py, progress.as_ref(), || cli::dispatch(parsed.command))?;
    Ok((within, captured.out, captured.notes))
}

/// Runs `work` with the GIL released and its printing captured, the progress watcher beside
/// it; its error becomes LaminaError with the binary's message.
fn in_process<T: Send>(
    py: Python<'_>,
    progress: Option<&Py<PyAny>>,
    work: impl FnOnce() -> anyhow::Result<T> + Send,
) -> PyResult<(T, cli::say::Captured)> {
    let mut callback_error: Option<PyErr> = None;
    let (result, captured) = py.detach(|| {
        std::thread::scope(|scope| {
            // Dropping `done` (when the command returns) wakes the watcher at once.
            let (done, finished) = mpsc::channel::<()>();
            let worker = std::thread::current().id();
            if let Some(callback) = progress {
                let callback_error = &mut callback_error;
                scope.spawn(move || watch(callback, worker, finished, callback_error));
            }
            cli::progress::reset();
            let out = cli::say::capture(work);
            cli::progress::reset();
            drop(done);
            out
        })
    });
    if let Some(e) = callback_error {
        return Err(e);
    }
    match result {
        Ok(value) => Ok((value, captured)),
        Err(e) => Err(LaminaError::new_err(cli::error_message(&e))),
    }
}

/// `lamina planarize ARGV…` on a network in memory (a `NetworkBytes` tuple;
/// ARGV's input names it in the report, and no file is read or written but a `--surface`).
/// Returns (within, axes file text, report text, summary text, axes N×3 and heights N as
/// float64 bytes, notes).
#[pyfunction]
#[pyo3(signature = (argv, network, progress=None))]
fn planarize<'py>(
    py: Python<'py>,
    argv: Vec<String>,
    network: NetworkBytes<'py>,
    progress: Option<Py<PyAny>>,
) -> PyResult<PlanarizeResult<'py>> {
    let cli::Command::Planarize(args) = parse("planarize", argv)? else {
        unreachable!("parsed as planarize");
    };
    no_reader_flags(&args.weld)?;
    let net = network.build(&args.input)?;
    let (solved, captured) =
        in_process(py, progress.as_ref(), || cli::planarize::solve(&args, &net))?;
    let mut axes_text = Vec::new();
    lamina::rationalize::axes::write_axes_to(&mut axes_text, &solved.axes, &solved.summary)
        .map_err(|e| LaminaError::new_err(e.to_string()))?;
    Ok((
        solved.solution.converged,
        String::from_utf8(axes_text).expect("JSON is UTF-8"),
        solved.report.json(),
        solved.summary.to_string(),
        f64_bytes(py, solved.axes.axes.iter().flat_map(|a| a.to_array())),
        f64_bytes(py, solved.axes.heights.iter().copied()),
        captured.notes,
    ))
}

/// `lamina COMMAND ARGV…` parsed as the binary parses it (clap's message on a bad flag).
fn parse(command: &str, argv: Vec<String>) -> PyResult<cli::Command> {
    let parsed = cli::Cli::try_parse_from(
        ["lamina", command]
            .map(String::from)
            .into_iter()
            .chain(argv),
    )
    .map_err(|e| clap_error(&e))?;
    Ok(parsed.command)
}

/// clap's message for bad arguments, as the binary prints it (without colours).
fn clap_error(e: &clap::Error) -> PyErr {
    LaminaError::new_err(e.render().to_string().trim_end().to_string())
}

/// A network from memory is taken as it is: the reader flags have no file to act on.
fn no_reader_flags(flags: &cli::input::ReadArgs) -> PyResult<()> {
    if flags.given() {
        return Err(LaminaError::new_err(
            "the reader flags (--weld, --units, --chord-tolerance, …) apply to files; a network \
             from memory is taken as it is",
        ));
    }
    Ok(())
}

/// `lamina solid ARGV…` on a network in memory (as `planarize`): no file is read or written.
/// Returns (report text as `--report` writes it, vertices V×3 float64 and faces F×3 uint32
/// bytes, notes).
#[pyfunction]
#[pyo3(signature = (argv, network, progress=None))]
fn solid<'py>(
    py: Python<'py>,
    argv: Vec<String>,
    network: NetworkBytes<'py>,
    progress: Option<Py<PyAny>>,
) -> PyResult<SolidResult<'py>> {
    let cli::Command::Solid(args) = parse("solid", argv)? else {
        unreachable!("parsed as solid");
    };
    no_reader_flags(&args.weld)?;
    let net = network.build(&args.network)?;
    let (made, captured) = in_process(py, progress.as_ref(), || {
        let made = cli::solid::solve(&args, &net)?;
        let text = cli::venation::json_text(&made.value)?;
        Ok((made.mesh, text))
    })?;
    let (mesh, text) = made;
    Ok((
        text,
        f64_bytes(py, mesh.positions.iter().flat_map(|p| p.to_array())),
        u32_bytes(py, mesh.triangles.iter().flatten().copied()),
        captured.notes,
    ))
}

/// `lamina slice ARGV…` on meshes in memory: each model a (name, vertices V×3 float64 bytes,
/// faces F×3 uint32 bytes), the names standing for ARGV's model files (checked as a mesh file
/// is). The archive is written where ARGV's `-o` says. Returns (print.json's text, notes).
#[pyfunction]
#[pyo3(signature = (argv, models, progress=None))]
fn slice(
    py: Python<'_>,
    argv: Vec<String>,
    models: Vec<(String, Bound<'_, PyBytes>, Bound<'_, PyBytes>)>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, Vec<String>)> {
    let names: Vec<String> = models.iter().map(|(name, ..)| name.clone()).collect();
    let cli::Command::Slice(args) = parse("slice", names.iter().cloned().chain(argv).collect())?
    else {
        unreachable!("parsed as slice");
    };
    let meshes = models
        .iter()
        .map(|(name, v, f)| {
            let path = PathBuf::from(name);
            mesh_from(&path, v.as_bytes(), f.as_bytes()).map(|mesh| (path, mesh))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let (text, captured) = in_process(py, progress.as_ref(), || {
        let (report, ..) = cli::slice::slice_models(&args, meshes)?;
        cli::venation::json_text(&report)
    })?;
    Ok((text, captured.notes))
}

/// A triangle mesh from little-endian bytes, checked as the mesh readers check a file (`source`
/// names it): triangles there, corners among the vertices, finite coordinates.
fn mesh_from(source: &Path, vertices: &[u8], faces: &[u8]) -> PyResult<TriMesh> {
    let positions = points(&f64s(vertices, "vertices")?);
    let corners = u32s(faces, "faces")?;
    let bad = |e: ReadError| LaminaError::new_err(e.to_string());
    if corners.len() < 3 {
        return Err(bad(ReadError::file(
            source,
            "no triangles: nothing to read",
        )));
    }
    if let Some(k) = corners.iter().position(|&i| i as usize >= positions.len()) {
        return Err(bad(ReadError::record(
            source,
            format!("triangle {}", k / 3),
            format!(
                "corner {} is not one of the {} vertices",
                corners[k],
                positions.len()
            ),
        )));
    }
    if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
        return Err(bad(ReadError::record(
            source,
            format!("vertex {v}"),
            "coordinate is not finite",
        )));
    }
    Ok(TriMesh {
        positions,
        triangles: corners
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        colors: None,
    })
}

/// What `solid` hands back to Python.
type SolidResult<'py> = (
    String,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Vec<String>,
);

/// What `planarize` hands back to Python.
type PlanarizeResult<'py> = (
    bool,
    String,
    String,
    String,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Vec<String>,
);

/// Calls the progress callback with the worker thread's bar until the command is done; a callback that
/// raises is not called again and its exception is raised when the command returns.
fn watch(
    callback: &Py<PyAny>,
    worker: std::thread::ThreadId,
    finished: mpsc::Receiver<()>,
    error: &mut Option<PyErr>,
) {
    while let Err(mpsc::RecvTimeoutError::Timeout) = finished.recv_timeout(PROGRESS_EVERY) {
        let Some(p) = cli::progress::active(worker) else {
            continue;
        };
        let called = Python::attach(|py| {
            callback
                .call1(py, (p.stage, p.message, p.done, p.total))
                .map(drop)
        });
        if let Err(e) = called {
            *error = Some(e);
            return;
        }
    }
}

fn f64s(bytes: &[u8], what: &str) -> PyResult<Vec<f64>> {
    if !bytes.len().is_multiple_of(8) {
        return Err(LaminaError::new_err(format!(
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
        return Err(LaminaError::new_err(format!(
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

fn f64_bytes<'py>(py: Python<'py>, values: impl Iterator<Item = f64>) -> Bound<'py, PyBytes> {
    let bytes: Vec<u8> = values.flat_map(f64::to_le_bytes).collect();
    PyBytes::new(py, &bytes)
}

fn u32_bytes<'py>(py: Python<'py>, values: impl Iterator<Item = u32>) -> Bound<'py, PyBytes> {
    let bytes: Vec<u8> = values.flat_map(u32::to_le_bytes).collect();
    PyBytes::new(py, &bytes)
}

/// A network as Python hands it over: a tuple of little-endian bytes (positions N×3 float64,
/// edges E×2 uint32, node radii N and edge radii E float64, normals N×3 float64 or empty for
/// none) and its meta as JSON text (empty for none).
#[derive(FromPyObject)]
struct NetworkBytes<'py>(
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    String,
);

impl NetworkBytes<'_> {
    /// The network, checked as the JSON reader checks a file (`source` names it in errors):
    /// finite positions and normals, edges between existing nodes.
    fn build(&self, source: &Path) -> PyResult<Network> {
        let NetworkBytes(positions, edges, node_radius, edge_radius, normals, meta) = self;
        let p = points(&f64s(positions.as_bytes(), "positions")?);
        let e = u32s(edges.as_bytes(), "edges")?;
        let nr = f64s(node_radius.as_bytes(), "node_radius")?;
        let er = f64s(edge_radius.as_bytes(), "edge_radius")?;
        let n = points(&f64s(normals.as_bytes(), "normals")?);
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
            return Err(LaminaError::new_err(format!(
                "{what}: {got} rows for {want} (one per node or edge)"
            )));
        }
        let bad = |record: String, message: String| {
            LaminaError::new_err(ReadError::record(source, record, message).to_string())
        };
        let mut nodes = Vec::with_capacity(p.len());
        for (i, &p) in p.iter().enumerate() {
            if !p.is_finite() {
                return Err(bad(format!("node {i}"), "position is not finite".into()));
            }
            let normal = n.get(i).copied();
            if normal.is_some_and(|v| !v.is_finite()) {
                return Err(bad(format!("node {i}"), "normal is not finite".into()));
            }
            nodes.push(Node {
                p,
                normal,
                radius: nr[i],
            });
        }
        let mut out = Vec::with_capacity(er.len());
        for (k, (ab, &radius)) in e.chunks_exact(2).zip(&er).enumerate() {
            if ab[0] as usize >= nodes.len() || ab[1] as usize >= nodes.len() {
                return Err(bad(
                    format!("edge {k}"),
                    format!(
                        "joins nodes {} and {}, but the file has {} nodes (numbered from 0)",
                        ab[0],
                        ab[1],
                        nodes.len()
                    ),
                ));
            }
            out.push(Edge {
                a: ab[0],
                b: ab[1],
                radius,
            });
        }
        Ok(Network {
            nodes,
            edges: out,
            meta: meta_of(meta)?,
        })
    }
}

/// A network's meta from the JSON text of the Python dict's `meta` (empty: the defaults).
fn meta_of(text: &str) -> PyResult<Meta> {
    let mut meta = Meta::default();
    if text.is_empty() {
        return Ok(meta);
    }
    let bad = |what: &str| LaminaError::new_err(format!("meta: {what}"));
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| bad(&format!("not JSON ({e})")))?;
    let Some(map) = value.as_object() else {
        return Err(bad("expected a dict"));
    };
    for (key, v) in map {
        match (key.as_str(), v) {
            (_, serde_json::Value::Null) => {}
            ("units", serde_json::Value::String(u)) => meta.units = u.clone(),
            ("generator", serde_json::Value::String(g)) => meta.generator = Some(g.clone()),
            ("seed", v) if v.as_u64().is_some() => meta.seed = v.as_u64(),
            ("parameters", serde_json::Value::Object(p)) => {
                meta.parameters = p.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
            }
            ("tags", serde_json::Value::Object(t)) => {
                for (k, v) in t {
                    let serde_json::Value::String(v) = v else {
                        return Err(bad(&format!("tag {k:?} is not a string")));
                    };
                    meta.tags.insert(k.clone(), v.clone());
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

/// Writes a network (the tuple `NetworkBytes` describes) as lamina JSON (exact: shortest
/// round-trip numbers), OBJ, DXF or SVG by extension.
#[pyfunction]
fn write_network(path: &str, network: NetworkBytes<'_>) -> PyResult<()> {
    let path = Path::new(path);
    let net = network.build(path)?;
    lamina::network::io::write_network(&net, path, &RenderOptions::default())
        .map_err(|e| LaminaError::new_err(e.to_string()))
}

/// Reads a network file (.json .obj .dxf) into a dict of little-endian arrays: positions,
/// edges, node_radius, edge_radius, normals (None when no node has one), meta (JSON text).
#[pyfunction]
fn read_network<'py>(py: Python<'py>, path: &str) -> PyResult<Bound<'py, PyDict>> {
    let net = read_network_file(Path::new(path), &ReadOptions::default())
        .map_err(|e| LaminaError::new_err(e.to_string()))?
        .network;
    let d = PyDict::new(py);
    d.set_item(
        "positions",
        f64_bytes(py, net.nodes.iter().flat_map(|n| n.p.to_array())),
    )?;
    d.set_item(
        "edges",
        u32_bytes(py, net.edges.iter().flat_map(|e| [e.a, e.b])),
    )?;
    d.set_item(
        "node_radius",
        f64_bytes(py, net.nodes.iter().map(|n| n.radius)),
    )?;
    d.set_item(
        "edge_radius",
        f64_bytes(py, net.edges.iter().map(|e| e.radius)),
    )?;
    if net.nodes.iter().any(|n| n.normal.is_some()) {
        d.set_item(
            "normals",
            f64_bytes(
                py,
                net.nodes
                    .iter()
                    .flat_map(|n| n.normal.unwrap_or(DVec3::NAN).to_array()),
            ),
        )?;
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
    d.set_item("meta", meta.to_string())?;
    Ok(d)
}

/// Writes a triangle mesh (.obj .stl by extension): vertices V×3 float64, faces F×3 uint32,
/// colours V×3 float32 in 0..=1 or empty, all little-endian bytes.
#[pyfunction]
fn write_mesh(path: &str, vertices: &[u8], faces: &[u8], colors: &[u8]) -> PyResult<()> {
    let positions = points(&f64s(vertices, "vertices")?);
    let triangles = u32s(faces, "faces")?
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let colors = (!colors.is_empty()).then(|| {
        f64s(colors, "colors").map(|c| {
            c.chunks_exact(3)
                .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
                .collect()
        })
    });
    let mesh = TriMesh {
        positions,
        triangles,
        colors: colors.transpose()?,
    };
    write_mesh_file(&mesh, Path::new(path), 0).map_err(|e| LaminaError::new_err(e.to_string()))
}

/// Vertices, faces and colours (or None) as little-endian bytes.
type MeshBytes<'py> = (
    Bound<'py, PyBytes>,
    Bound<'py, PyBytes>,
    Option<Bound<'py, PyBytes>>,
);

/// Reads a triangle mesh (.obj .stl): (vertices, faces, colours or None) as little-endian
/// float64, uint32 and float64 bytes.
#[pyfunction]
fn read_mesh<'py>(py: Python<'py>, path: &str) -> PyResult<MeshBytes<'py>> {
    let mesh = read_mesh_file(Path::new(path)).map_err(|e| LaminaError::new_err(e.to_string()))?;
    Ok((
        f64_bytes(py, mesh.positions.iter().flat_map(|p| p.to_array())),
        u32_bytes(py, mesh.triangles.iter().flatten().copied()),
        mesh.colors
            .as_ref()
            .map(|c| f64_bytes(py, c.iter().flatten().map(|&v| f64::from(v)))),
    ))
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
    m.add("LaminaError", m.py().get_type::<LaminaError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(planarize, m)?)?;
    m.add_function(wrap_pyfunction!(solid, m)?)?;
    m.add_function(wrap_pyfunction!(slice, m)?)?;
    m.add_function(wrap_pyfunction!(write_network, m)?)?;
    m.add_function(wrap_pyfunction!(read_network, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    Ok(())
}
