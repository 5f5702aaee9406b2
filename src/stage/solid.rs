//! `solid`: a vein network as one closed, 2-manifold, outward-oriented triangle mesh (tapered
//! round veins, an optional lamina and base), optionally simplified within a tolerance of the
//! exact surface and given tree supports under its islands.
//!
//! ```
//! use lamina::stage::{solid, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/small_loop.json"))?;
//! let made = solid::run(&net, &solid::Options { cell: 0.25, ..Default::default() }, &Quiet)?;
//! assert_eq!(made.report.solid.genus, made.report.solid.network_cycles as i64);
//! # Ok(()) }
//! ```

use serde::Serialize;

use crate::fabricate::slice::shapes::Placed;
pub use crate::fabricate::slice::supports::SupportOptions;
use crate::fabricate::slice::supports::{plan, SupportError, SupportReport};
use crate::fabricate::slice::{fitting_scale, Printer};
use crate::fabricate::solid::{shapes, solid_of, Shapes, SolidError, SolidOptions};
pub use crate::fabricate::solid::{Base, SolidReport, DEFAULT_CELL};
use crate::stage::Progress;
use crate::{Network, TriMesh};

/// What the solid is made of: what `solid` and `print` share. `Default` is the commands'
/// defaults.
#[derive(Clone, Debug, Default)]
pub struct Shape {
    /// The leaf lamina: the blade outline extruded this thick, mm. Default: none.
    pub lamina: Option<f64>,
    /// A base cylinder under the root. Default: none.
    pub base: Option<Base>,
    /// Scale so the longest side is this many mm. Default: as drawn.
    pub fit: Option<f64>,
    /// Stand the leaf up: its +y becomes +z. Default false.
    pub upright: bool,
    /// Radius for edges the network gives none, mm. Default: none (such edges are refused).
    pub radius: Option<f64>,
    /// Tree supports under every island. Default: none.
    pub supports: Option<SupportOptions>,
}

/// How the solid is meshed. `Default` is the command's defaults.
#[derive(Clone, Debug)]
pub struct Options {
    /// Grid cell of the mesher, mm. Default: the DMP-SL pixel, 0.035. With `tolerance` the mesh
    /// is marched at twice the cell when every piece is at least four cells thick and no supports
    /// are added (split as fine where veins come close; the report's `march_cell_mm`).
    pub cell: f64,
    /// Simplify to within this of the exact surface, mm. Default: every marched triangle kept.
    pub tolerance: Option<f64>,
    /// What the solid or tree is made of.
    pub shape: Shape,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            cell: DEFAULT_CELL,
            tolerance: None,
            shape: Shape::default(),
        }
    }
}

/// The solid: its mesh and its report.
#[derive(Clone, Debug)]
pub struct Made {
    /// The mesh.
    pub mesh: TriMesh,
    /// The report, as the command writes it.
    pub report: Report,
    /// Warnings (veins thinner than the cell, gaps left bridged, islands left), one line each.
    pub warnings: Vec<String>,
    /// Notes, one line each: that the solid does not fit the DMP-SL printer (and the `fit` that
    /// would), what the supports did (when asked for).
    pub notes: Vec<String>,
}

/// The report `--report` writes: the solid's figures and, with supports, theirs.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    #[serde(flatten)]
    /// The solid's figures.
    pub solid: SolidReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// The supports added.
    pub supports: Option<SupportReport>,
}

/// Why no solid was made.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// Meshing failed.
    Solid(#[from] SolidError),
    #[error(transparent)]
    /// Support planning failed.
    Supports(#[from] SupportError),
}

impl Error {
    /// Whether the caller stopped the meshing.
    pub fn is_cancelled(&self) -> bool {
        use crate::fabricate::solid::MarchError;
        matches!(self, Error::Solid(SolidError::March(MarchError::Cancelled)))
            || matches!(self, Error::Supports(SupportError::Cancelled(_)))
    }
}

impl Shape {
    /// The mesher's options at grid cell `cell`.
    pub fn solid_options(&self, cell: f64) -> SolidOptions {
        SolidOptions {
            cell,
            lamina: self.lamina,
            base: self.base,
            fit: self.fit,
            upright: self.upright,
            radius: self.radius,
            tolerance: None,
        }
    }
}

/// The shapes of `net`, with supports planned on `printer`'s pixels and layers when asked;
/// the supports' report and a line on what they did.
pub fn shapes_with_supports(
    net: &Network,
    opts: &SolidOptions,
    shape: &Shape,
    printer: &Printer,
    progress: &dyn Progress,
) -> Result<(Shapes, Option<SupportReport>, Vec<String>), Error> {
    let mut pieces = shapes(net, opts)?;
    let Some(s) = &shape.supports else {
        return Ok((pieces, None, Vec::new()));
    };
    let model = Placed::new(pieces.clone(), opts.upright);
    let made = plan(&model, printer, s, progress)?;
    pieces.added += made.prims.len();
    pieces.prims.extend(made.prims);
    // Placed where they were planned, so the print's pixels are the planned ones.
    pieces.frame = Some(model.shift());
    let r = made.report;
    let mut notes = vec![format!(
        "supports: {} island(s) held by {} tip(s); {} pillar(s) on the plate, {} on the model, \
         {} join(s); {:.4} mL of supports for {:.4} mL of model",
        r.islands, r.tips, r.to_plate, r.to_model, r.joins, r.support_ml, r.model_ml
    )];
    if let Some(i) = &r.first_left {
        notes.push(format!(
            "warning: {} island(s) left with supports, the first at layer {} ({:.2}, {:.2}) mm",
            r.islands_left, i.layer, i.x_mm, i.y_mm
        ));
    }
    Ok((pieces, Some(r), notes))
}

/// A line saying that the solid does not fit `printer` (the DMP-SL, whose pixel is the default
/// cell) and the `fit` that would, when it does not: `print` shrinks such a network itself, but
/// a mesh written at this size would be refused by `slice`.
fn too_big_to_print(pieces: &Shapes, upright: bool, printer: &Printer) -> Option<String> {
    let longest = pieces.scale * pieces.drawn_size;
    let (lo, hi) = Placed::new(pieces.clone(), upright).bounds();
    let size = hi - lo;
    let factor = fitting_scale(size, printer);
    if !(factor.is_finite() && factor < 1.0 && longest > 0.0) {
        return None;
    }
    let area = printer.area();
    // Rounded down to 0.1 mm: a lamina or a base does not scale with `fit`, so it is a guide.
    let fit = (10.0 * factor * longest).floor() / 10.0;
    Some(format!(
        "{:.1} × {:.1} × {:.1} mm does not fit the DMP-SL printer ({:.1} × {:.1} mm display, \
         {} mm tall): fit= {} would (`print` scales a network to fit by itself)",
        size.x,
        size.y,
        size.z,
        area.x,
        area.y,
        crate::text::num(printer.max_height_mm),
        crate::text::num(fit)
    ))
}

/// Meshes `net`. `progress` follows the meshing and simplification and stops them between
/// bricks and passes.
pub fn run(net: &Network, opts: &Options, progress: &dyn Progress) -> Result<Made, Error> {
    let mut solid_opts = opts.shape.solid_options(opts.cell);
    solid_opts.tolerance = opts.tolerance;
    // Supports are planned at the DMP-SL's pixel and layer.
    let printer = Printer::default();
    let (pieces, supports, mut notes) =
        shapes_with_supports(net, &solid_opts, &opts.shape, &printer, progress)?;
    if let Some(note) = too_big_to_print(&pieces, opts.shape.upright, &printer) {
        notes.insert(0, note);
    }
    let made = solid_of(net, &solid_opts, pieces, progress)?;
    let warnings = made.report.warnings.clone();
    Ok(Made {
        mesh: made.mesh,
        report: Report {
            solid: made.report,
            supports,
        },
        warnings,
        notes,
    })
}
