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
use crate::fabricate::slice::arrange_boxes;
use crate::fabricate::slice::shapes::Placed;
use crate::stage::Progress;
use crate::Network;

/// The solid and the job. `Default` is the command's defaults.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// What the solid or tree is made of.
    pub shape: Shape,
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
    let solid_opts = opts.shape.solid_options(printer.pixel_mm);
    let (made, supports, mut notes) =
        shapes_with_supports(net, &solid_opts, &opts.shape, printer, progress)?;
    let (scale, min_radius, max_radius) = (made.scale, made.min_radius, made.max_radius);
    if min_radius < printer.pixel_mm {
        notes.push(format!(
            "warning: the thinnest vein (radius {min_radius:.4} mm) is thinner than a pixel ({} \
             mm): it may print broken or not at all; use a larger fit=",
            printer.pixel_mm
        ));
    }
    let name = opts.name.clone().unwrap_or_else(|| "network".into());
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
    .map_err(SliceJobError::from)?;
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
