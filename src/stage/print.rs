//! `print`: a network's solid sliced straight from its signed distance into an SL1 archive,
//! with no mesh in between (the same layers as `solid` then `slice`, in a fraction of the time
//! and memory).
//!
//! ```
//! use lamina::stage::{print, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/small_loop.json"))?;
//! let mut archive = std::io::Cursor::new(Vec::new());
//! let job = print::run(&net, &print::Options::default(), &mut archive, &Quiet)?;
//! assert!(job.report.layers > 10);
//! # Ok(()) }
//! ```

use glam::DVec3;
use serde_json::json;

use super::slice::{slice_job, Archive, Error as SliceJobError, JobOptions, Sliced, Source};
use super::solid::{shapes_with_supports, Error as SolidStageError, Shape};
use crate::fabricate::slice::shapes::Placed;
use crate::fabricate::slice::{arrange_boxes, fitting_scale, SliceError};
use crate::fabricate::solid::shapes;
use crate::stage::Progress;
use crate::Network;

/// How a network that `Shape::fit` does not size is sized for the display.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DisplayFit {
    /// As drawn when it fits; scaled down to the largest size that fits when it does not
    /// (said in a note).
    #[default]
    Shrink,
    /// Scaled, up or down, to the largest size that fits (`--fit auto`).
    Fill,
    /// As drawn: a network too big for the display is refused, with the factor that would fit.
    Keep,
}

/// The solid and the job. `Default` is the command's defaults.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// What the solid or tree is made of.
    pub shape: Shape,
    /// How the network is sized when `shape.fit` is `None`.
    pub display_fit: DisplayFit,
    /// The printer, plate and estimate settings.
    pub job: JobOptions,
    /// The network's name in print.json (its path). Default "network".
    pub name: Option<String>,
}

/// Why nothing was printed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// Meshing failed.
    Solid(#[from] SolidStageError),
    #[error(transparent)]
    /// Slicing failed.
    Slice(#[from] SliceJobError),
}

impl Error {
    /// Whether the caller stopped the job.
    pub fn is_cancelled(&self) -> bool {
        match self {
            Error::Solid(e) => e.is_cancelled(),
            Error::Slice(e) => matches!(e, SliceJobError::Cancelled),
        }
    }
}

/// Samples `net`'s solid layer by layer into the archive written to `archive`. `progress`
/// counts layers and can stop the job between two.
pub fn run(
    net: &Network,
    opts: &Options,
    archive: &mut dyn Archive,
    progress: &dyn Progress,
) -> Result<Sliced, Error> {
    opts.job.check().map_err(SliceJobError::from)?;
    let printer = &opts.job.printer;
    // The outline's distance buckets are sized by the cell; the pixel is the cell here.
    let name = opts.name.clone().unwrap_or_else(|| "network".into());
    let mut shape = opts.shape.clone();
    let mut sized = None;
    if shape.fit.is_none() && opts.display_fit != DisplayFit::Keep {
        // The model as drawn (supports follow its size, and stay under it): the factor that
        // fits its box, as the longest side `fit` sets.
        let drawn =
            shapes(net, &shape.solid_options(printer.pixel_mm)).map_err(SolidStageError::from)?;
        let drawn_size = drawn.drawn_size;
        let (lo, hi) = Placed::new(drawn, shape.upright).bounds();
        let factor = fitting_scale(hi - lo, printer);
        if factor.is_finite() && (factor < 1.0 || opts.display_fit == DisplayFit::Fill) {
            shape.fit = Some(factor * drawn_size);
            sized = Some(hi - lo);
        }
    }
    let mut solid_opts = shape.solid_options(printer.pixel_mm);
    let (mut made, mut supports, mut notes) =
        shapes_with_supports(net, &solid_opts, &shape, printer, progress)?;
    // A base or a lamina does not scale with the veins, nor do the supports' feet exactly:
    // where the sized model still does not fit, shrink it by what is left (a few times). The
    // veins alone come out at a factor of 1 to rounding (the margin of a pixel absorbs that).
    for _ in 0..3 {
        let Some(fit) = shape.fit.filter(|_| sized.is_some()) else {
            break;
        };
        let (lo, hi) = Placed::new(made.clone(), shape.upright).bounds();
        let factor = fitting_scale(hi - lo, printer);
        if factor >= 1.0 - 1e-9 {
            break;
        }
        shape.fit = Some(fit * factor);
        solid_opts = shape.solid_options(printer.pixel_mm);
        (made, supports, notes) =
            shapes_with_supports(net, &solid_opts, &shape, printer, progress)?;
    }
    if let (Some(size), Some(fit)) = (sized, shape.fit) {
        let how = match opts.display_fit {
            DisplayFit::Fill => "scaled to fill the display",
            _ => "too big for the display, scaled down to fit",
        };
        notes.insert(
            0,
            format!(
                "{name}: {:.2} × {:.2} × {:.2} mm as drawn, {how}: × {:.4}, its longest side \
                 {fit:.2} mm (give fit= in mm for another size)",
                size.x, size.y, size.z, made.scale
            ),
        );
    }
    let (scale, min_radius, max_radius) = (made.scale, made.min_radius, made.max_radius);
    if min_radius < printer.pixel_mm {
        notes.push(format!(
            "warning: the thinnest vein (radius {min_radius:.4} mm) is thinner than a pixel ({} \
             mm): it may print broken or not at all; use a larger fit=",
            printer.pixel_mm
        ));
    }
    let path = std::path::PathBuf::from(&name);
    let model = Placed::new(made, opts.shape.upright);
    let (lo, hi) = model.bounds();
    let placed = arrange_boxes(
        &[(path.as_path(), lo, hi)],
        printer,
        opts.job.copies,
        opts.job.gap,
        false,
    )
    .map_err(|mut e| {
        // A network is scaled by fit=, not scale=.
        if let SliceError::TooBig { hint, .. } | SliceError::TooTall { hint, .. } = &mut e {
            *hint = "fit= auto, or fit= in mm";
        }
        SliceJobError::from(e)
    })?;
    let source = Source::Shapes {
        model: &model,
        path: &path,
    };
    let mut sliced = slice_job(source, &placed, &opts.job, archive, None, progress)?;
    let size: DVec3 = hi - lo;
    sliced.report.solid = Some(json!({
        "sampled_from": "signed distance",
        "scale": scale,
        "min_radius": min_radius,
        "max_radius": max_radius,
        "lamina_mm": solid_opts.lamina,
        "base": solid_opts.base.map(|b| [b.diameter, b.height]),
        "upright": solid_opts.upright,
        "size_mm": size.to_array(),
    }));
    sliced.report.supports = supports.map(|s| serde_json::to_value(s).expect("reports serialise"));
    sliced.notes = notes;
    Ok(sliced)
}
