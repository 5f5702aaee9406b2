//! `buds`: a bud program (Hart, "Growth Forms", Figure 8 language) grown into a cellular
//! surface, then skinned into a closed mesh with its textures as geometry.
//!
//! ```
//! use lamina::grow::buds::parse_program;
//! use lamina::stage::{buds, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let program = parse_program(include_str!("../../fixtures/buds/split.bud"), "split.bud")?;
//! let grown = buds::run(&program, &buds::Options { cells: 300, ..Default::default() }, None, &Quiet)?;
//! assert!(grown.report.mesh.closed);
//! # Ok(()) }
//! ```

use serde::Serialize;

use crate::grow::buds::{skin, BudError, Form, Growth, GrowthOptions, Program, SkinOptions};
pub use crate::grow::buds::{GrowthReport, SkinReport};
use crate::stage::{checkpoint, Cancelled, OptionError, Progress};
use crate::TriMesh;

/// How the form grows. `Default` is the command's defaults.
#[derive(Clone, Debug)]
pub struct Options {
    /// Stop growing at this many cells. Default 10,000.
    pub cells: usize,
    /// Default 1.
    pub seed: u64,
    /// Millimetres per unit cell size. Default 2.
    pub cell_mm: f64,
    /// Distance, in cell sizes, at which parts of the form collide. Default 0.9.
    pub clearance: f64,
    /// Leave textures out of the geometry. Default false.
    pub no_textures: bool,
    /// The program's name in the report (the CLI gives its file name). Default "program".
    pub program_name: String,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            cells: 10_000,
            seed: 1,
            cell_mm: 2.0,
            clearance: 0.9,
            no_textures: false,
            program_name: "program".into(),
        }
    }
}

/// Frames of the growth: called with the cellular surface (vertex colours) every `every` cells.
pub struct Frames<'a> {
    /// Steps (or cells) between frames.
    pub every: usize,
    /// Called with each frame.
    pub call: &'a mut dyn FnMut(&TriMesh) -> Result<(), String>,
}

/// The grown form, its mesh and report.
#[derive(Clone, Debug)]
pub struct Grown {
    /// The grown form.
    pub form: Form,
    /// The mesh.
    pub mesh: TriMesh,
    /// The report, as the command writes it.
    pub report: Report,
}

/// The report. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Frames written.
    pub frames: usize,
    /// The growth's figures.
    pub growth: GrowthReport,
    /// The mesh.
    pub mesh: MeshFigures,
    /// The program's name.
    pub program: String,
    /// Random seed.
    pub seed: u64,
    /// The skin's figures.
    pub skin: SkinReport,
}

/// The skinned mesh's topology and size.
#[derive(Clone, Debug, Serialize)]
pub struct MeshFigures {
    /// Area, mm².
    pub area_mm2: f64,
    /// Whether every edge has two triangles.
    pub closed: bool,
    /// Connected components.
    pub components: usize,
    /// Genus.
    pub genus: Option<i64>,
    /// Every problem found, in words.
    pub problems: usize,
    /// Triangles.
    pub triangles: usize,
    /// Vertices.
    pub vertices: usize,
    /// Volume, mm³.
    pub volume_mm3: Option<f64>,
}

/// Why no form grew.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error("{program}: {error}")]
    /// The program refused.
    Program {
        /// The program's name.
        program: String,
        /// What is wrong with it.
        error: BudError,
    },
    #[error("frames= {0}")]
    /// A frame could not be written.
    Frame(String),
    #[error(transparent)]
    /// The caller stopped the stage.
    Cancelled(#[from] Cancelled),
}

/// Grows `program`, asking `progress` to stop between rounds of growth.
pub fn run(
    program: &Program,
    opts: &Options,
    mut frames: Option<Frames>,
    progress: &dyn Progress,
) -> Result<Grown, Error> {
    if !(1e-3..=1e4).contains(&opts.cell_mm) {
        return Err(OptionError::new(
            "cell_mm",
            format!(
                "{} must be a length from 0.001 to 10000 mm",
                crate::text::num(opts.cell_mm)
            ),
        )
        .into());
    }
    if frames.as_ref().is_some_and(|f| f.every == 0) {
        return Err(OptionError::new("every", "0: give at least 1 cell between frames").into());
    }
    let options = GrowthOptions {
        max_cells: opts.cells,
        clearance: opts.clearance,
        ..GrowthOptions::default()
    };
    let in_program = |error: BudError| Error::Program {
        program: opts.program_name.clone(),
        error,
    };
    let mut growth = Growth::new(program, options, opts.seed).map_err(in_program)?;
    progress.begin("growing", Some(opts.cells as u64));
    let mut next_frame = 0;
    let mut shown = 0;
    loop {
        if let Some(f) = frames.as_mut() {
            if growth.cells() >= next_frame {
                shown += 1;
                let mesh = TriMesh {
                    positions: growth.positions().to_vec(),
                    triangles: growth.graph().faces(),
                    colors: Some(growth.colours().to_vec()),
                };
                (f.call)(&mesh).map_err(Error::Frame)?;
                next_frame = growth.cells() + f.every;
            }
        }
        progress.set(growth.cells() as u64);
        checkpoint(progress)?;
        if !growth.round().map_err(in_program)? {
            break;
        }
    }
    let form = growth.finish();
    let (mesh, skin_report) = skin(
        &form,
        &SkinOptions {
            cell_mm: opts.cell_mm,
            textures: !opts.no_textures,
        },
    );
    let topology = mesh.check_manifold();
    let report = Report {
        frames: shown,
        growth: form.report.clone(),
        mesh: MeshFigures {
            area_mm2: topology.area,
            closed: topology.closed,
            components: topology.components,
            genus: topology.genus,
            problems: topology.problems.len(),
            triangles: mesh.triangles.len(),
            vertices: mesh.positions.len(),
            volume_mm3: topology.volume,
        },
        program: opts.program_name.clone(),
        seed: opts.seed,
        skin: skin_report,
    };
    Ok(Grown { form, mesh, report })
}
