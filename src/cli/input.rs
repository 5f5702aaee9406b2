//! Loading "a file the user gave": a network or a mesh, told apart by extension and, for OBJ,
//! by whether it holds faces or polylines.

use std::path::Path;

use anyhow::{bail, Context, Result};
use clap::Args;

use lamina::files::extension;
use lamina::mesh::io::{read_mesh_noted, stl_bodies};
use lamina::mesh::MeshWeld;
use lamina::network::arrangement::split_crossings;
use lamina::network::io::units::LengthUnit;
use lamina::network::io::{read_network, Imported, ReadOptions, MAX_DXF_POINTS};
use lamina::network::Weld;

use lamina::TriMesh;

/// How OBJ and DXF input is read: units, curves, and which points become shared nodes.
#[derive(Args, Clone, Debug)]
pub struct ReadArgs {
    /// Weld points closer than this distance, in mm, into one node (OBJ and DXF input)
    #[arg(long, value_name = "MM", conflicts_with = "weld_rel")]
    pub weld: Option<f64>,
    /// Weld points closer than this fraction of the bounding-box diagonal [default: 1e-6]
    #[arg(long, value_name = "FRACTION")]
    pub weld_rel: Option<f64>,
    /// The unit a DXF or OBJ is drawn in (mm, cm, m, in, ft), overriding the DXF header
    /// [default: the DXF's $INSUNITS, else $MEASUREMENT, else mm]
    #[arg(long, value_name = "UNIT")]
    pub units: Option<String>,
    /// Largest distance, in mm, between a DXF arc, bulge, circle, ellipse or spline and the
    /// straight segments it is read as
    #[arg(long, value_name = "MM", default_value_t = ReadOptions::DEFAULT_CHORD_TOLERANCE)]
    pub chord_tolerance: f64,
    /// Refuse a file that holds anything not read (an entity kind, paper space)
    #[arg(long)]
    pub strict: bool,
    /// Node a flat drawing: every crossing and T-junction becomes a shared node, edges split
    #[arg(long)]
    pub split_crossings: bool,
    /// The most points a DXF may expand to, curves flattened and blocks inserted [default: a
    /// million plus 20 per byte of the file, at most 20 million]
    #[arg(long, value_name = "N")]
    pub max_points: Option<f64>,
    /// Read the boundaries of a DXF's HATCH fills as closed loops [default: a HATCH is
    /// skipped and named]
    #[arg(long)]
    pub hatch_boundaries: bool,
}

impl Default for ReadArgs {
    fn default() -> Self {
        ReadArgs {
            weld: None,
            weld_rel: None,
            units: None,
            chord_tolerance: ReadOptions::DEFAULT_CHORD_TOLERANCE,
            strict: false,
            split_crossings: false,
            max_points: None,
            hatch_boundaries: false,
        }
    }
}

/// Chord tolerances below this are refused: 1 nm is finer than any machine or printer, and a
/// smaller one only multiplies points.
const MIN_CHORD_TOLERANCE: f64 = 1e-6;

impl ReadArgs {
    pub fn options(&self) -> Result<ReadOptions> {
        let weld = match (self.weld, self.weld_rel) {
            (Some(mm), _) => Weld::Absolute(mm),
            (None, Some(f)) => Weld::Relative(f),
            (None, None) => Weld::DEFAULT,
        };
        let (t, flag) = match weld {
            Weld::Absolute(t) => (t, "--weld"),
            Weld::Relative(t) => (t, "--weld-rel"),
        };
        if !(t.is_finite() && t >= 0.0) {
            bail!("{flag}: the weld tolerance must be a finite number ≥ 0, got {t}");
        }
        if matches!(weld, Weld::Relative(f) if f > 0.5) {
            bail!("--weld-rel: {t} of the diagonal would weld the whole drawing into a point (at most 0.5)");
        }
        let c = self.chord_tolerance;
        if !(c.is_finite() && c >= MIN_CHORD_TOLERANCE) {
            bail!("--chord-tolerance: must be a finite length of at least {MIN_CHORD_TOLERANCE} mm, got {c}");
        }
        let units = match &self.units {
            None => None,
            Some(name) => Some(LengthUnit::parse(name).with_context(|| {
                format!(
                    "--units: `{}` is not a unit lamina knows ({})",
                    name.escape_debug(),
                    LengthUnit::NAMES
                )
            })?),
        };
        let max_points = match self.max_points {
            None => None,
            Some(n) if n.fract() == 0.0 && (1.0..=MAX_DXF_POINTS as f64).contains(&n) => {
                Some(n as usize)
            }
            Some(n) => bail!(
                "--max-points: must be a whole number from 1 to {MAX_DXF_POINTS}, got {}",
                lamina::text::num(n)
            ),
        };
        Ok(ReadOptions {
            weld,
            units,
            chord_tolerance: c,
            max_points,
            hatch_boundaries: self.hatch_boundaries,
        })
    }

    /// Whether any reader flag differs from its default.
    pub fn given(&self) -> bool {
        self.weld.is_some()
            || self.weld_rel.is_some()
            || self.units.is_some()
            || self.chord_tolerance != ReadArgs::default().chord_tolerance
            || self.strict
            || self.split_crossings
            || self.max_points.is_some()
            || self.hatch_boundaries
    }

    /// Reads a network, says on stderr what was assumed or left out (one line each), and
    /// with `--strict` refuses a file that held anything not read.
    pub fn network(&self, path: &Path) -> Result<Imported> {
        self.check_units_flag(path)?;
        let mut imported = read_network(path, &self.options()?)?;
        say_import(path, &imported);
        self.check_strict(path, &imported)?;
        self.split(path, &mut imported, false)?;
        Ok(imported)
    }

    /// With `--split-crossings`, nodes a flat network (and says what it did).
    fn split(&self, path: &Path, imported: &mut Imported, quiet: bool) -> Result<()> {
        // Nothing to node without edges (a drawing of one POINT): the next step says what is
        // missing.
        if !self.split_crossings || imported.network.edges.is_empty() {
            return Ok(());
        }
        let tol = imported.point_tolerance();
        let (net, stats) = split_crossings(&imported.network, tol)
            .map_err(|e| anyhow::anyhow!("{}: --split-crossings: {e}", path.display()))?;
        imported.network = net;
        if !quiet {
            errln!(
                "lamina: {}: noded {} crossings and {} T-junctions: {} nodes and {} edges added",
                path.display(),
                stats.crossings,
                stats.t_junctions,
                stats.nodes_added,
                stats.edges_added
            );
        }
        imported.split = Some(stats);
        Ok(())
    }

    fn check_units_flag(&self, path: &Path) -> Result<()> {
        if self.units.is_some() && extension(path) == "json" {
            bail!(
                "{}: --units applies to DXF and OBJ input; a lamina JSON network is in mm",
                path.display()
            );
        }
        Ok(())
    }

    fn check_strict(&self, path: &Path, imported: &Imported) -> Result<()> {
        if self.strict && !imported.skipped.is_empty() {
            bail!(
                "{}: --strict: the file holds what lamina does not read: {}",
                path.display(),
                skipped_list(imported)
            );
        }
        Ok(())
    }
}

/// "3 TEXT, 1 DIMENSION".
pub fn skipped_list(imported: &Imported) -> String {
    imported
        .skipped
        .iter()
        .map(|(k, n)| skipped_item(k, n))
        .collect::<Vec<_>>()
        .join(", ")
}

/// "3 TEXT"; a model-space HATCH says which flag reads it.
pub fn skipped_item(name: &str, n: impl std::fmt::Display) -> String {
    if name == "HATCH" {
        format!("{n} {name} (--hatch-boundaries reads their boundaries)")
    } else {
        format!("{n} {name}")
    }
}

/// One line on stderr for units that were assumed or converted, one for what was skipped.
pub fn say_import(path: &Path, imported: &Imported) {
    if let Some(u) = imported
        .units
        .as_ref()
        .filter(|u| u.assumed || u.scale_to_mm != 1.0)
    {
        errln!("lamina: {}: units {}", path.display(), u.describe());
    }
    if !imported.skipped.is_empty() {
        errln!(
            "lamina: {}: not read: {}",
            path.display(),
            skipped_list(imported)
        );
    }
}

pub enum Loaded {
    Network(Box<Imported>),
    Mesh(TriMesh, MeshNotes),
}

/// What reading a mesh found or did besides the triangles.
pub use lamina::stage::info::MeshImport as MeshNotes;

/// Reads a network or a mesh; `quiet` leaves the notes on units and skipped records to the
/// caller (`info` prints them in its summary).
pub fn load(path: &Path, args: &ReadArgs, quiet: bool) -> Result<Loaded> {
    // Every reader flag is checked, whichever kind of file this turns out to be.
    let opts = args.options()?;
    let ext = extension(path);
    let is_mesh = match ext.as_str() {
        "stl" => true,
        "json" | "dxf" => false,
        "obj" => obj_has_faces(path)?,
        _ => bail!(
            "{}: unknown file type `.{ext}` (networks: .json .obj .dxf; meshes: .obj .stl)",
            path.display()
        ),
    };
    Ok(if is_mesh {
        if args.units.is_some() {
            bail!(
                "{}: --units applies to DXF and OBJ networks; a mesh is read in mm",
                path.display()
            );
        }
        let (mut mesh, not_read) = read_mesh_noted(path)?;
        if !quiet {
            say_not_read(path, &not_read);
        }
        let weld = match (args.weld, args.weld_rel) {
            (None, None) => None,
            _ => Some(weld_mesh(path, &mut mesh, opts.weld, quiet)),
        };
        let notes = MeshNotes {
            bodies: stl_bodies(path),
            not_read,
            weld,
        };
        Loaded::Mesh(mesh, notes)
    } else {
        args.check_units_flag(path)?;
        let mut imported = read_network(path, &opts)?;
        if !quiet {
            say_import(path, &imported);
        }
        args.check_strict(path, &imported)?;
        args.split(path, &mut imported, quiet)?;
        Loaded::Network(Box::new(imported))
    })
}

/// Reads a mesh and says on stderr what it left unread.
pub fn mesh_file(path: &Path) -> Result<TriMesh> {
    let (mesh, not_read) = read_mesh_noted(path)?;
    say_not_read(path, &not_read);
    Ok(mesh)
}

/// One line on stderr for what a mesh file held that was not read.
pub fn say_not_read(path: &Path, not_read: &[String]) {
    if !not_read.is_empty() {
        errln!(
            "lamina: {}: not read as the mesh: {}",
            path.display(),
            not_read.join(", ")
        );
    }
}

/// Welds a mesh read from `path` and says what it joined (unless `quiet`).
pub fn weld_mesh(path: &Path, mesh: &mut TriMesh, weld: Weld, quiet: bool) -> MeshWeld {
    let w = mesh.weld(weld.tolerance_for(&mesh.bbox()));
    if !quiet {
        errln!(
            "lamina: {}: welded {} vertices within {} mm, {} triangles collapsed and dropped",
            path.display(),
            w.merged,
            lamina::text::num(w.tolerance),
            w.collapsed_triangles
        );
    }
    w
}

/// An OBJ with `f` records and no `l` records is a mesh; anything else is read as a network.
fn obj_has_faces(path: &Path) -> Result<bool> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let (mut faces, mut lines) = (false, false);
    for line in bytes.split(|&b| b == b'\n') {
        let line = line.trim_ascii_start();
        faces |= line.starts_with(b"f ") || line.starts_with(b"f\t");
        lines |= line.starts_with(b"l ") || line.starts_with(b"l\t");
    }
    Ok(faces && !lines)
}
