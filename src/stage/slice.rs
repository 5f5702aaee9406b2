//! `slice`: closed meshes sliced for a masked-SLA (DMP-SL) printer into an SL1 archive, with
//! the print estimate (print.json) and the islands. The archive streams into any writer (a
//! file, or memory); the layers can be handed to the caller as they are made.
//!
//! ```
//! use lamina::stage::{slice, solid, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/small_loop.json"))?;
//! let made = solid::run(&net, &solid::Options { cell: 0.25, ..Default::default() }, &Quiet)?;
//! let models = vec![slice::Model { path: "loop.stl".into(), mesh: made.mesh }];
//! let mut archive = std::io::Cursor::new(Vec::new());
//! let job = slice::run(&models, &slice::Options::default(), &mut archive, None, &Quiet)?;
//! assert!(job.report.layers > 10 && !archive.get_ref().is_empty());
//! # Ok(()) }
//! ```

use std::io::{Seek, Write};
use std::path::Path;

use serde::Serialize;

use crate::fabricate::archive::{Job, Sl1Writer};
use crate::fabricate::estimate::{estimate, Estimate, Resin};
use crate::fabricate::sl1::MAX_LISTED;
use crate::fabricate::slice::islands::{Island, Islands};
use crate::fabricate::slice::shapes::{self, Placed};
use crate::fabricate::slice::supports::{
    plan_mesh, supports_only, SupportError, SupportOptions, SupportReport,
};
use crate::fabricate::slice::{self as slicer, arrange_held, layer_count, Layer, SliceError};
pub use crate::fabricate::slice::{Model, Placement, Printer};
use crate::stage::{OptionError, Progress};

/// Printer settings over a profile's, each named as its option.
#[derive(Clone, Debug, Default)]
pub struct PrinterOptions {
    /// Layer height, mm.
    pub layer: Option<f64>,
    /// Pixel size, mm.
    pub pixel: Option<f64>,
    /// Display resolution, pixels.
    pub resolution: Option<(u32, u32)>,
    /// Exposure per layer, s.
    pub exposure: Option<f64>,
    /// Exposure of the bottom layers, s.
    pub bottom_exposure: Option<f64>,
    /// How many bottom layers.
    pub bottom_layers: Option<u32>,
    /// Peel lift after each layer, mm.
    pub lift: Option<f64>,
    /// Lift and retract speed, mm/min.
    pub lift_speed: Option<f64>,
}

impl PrinterOptions {
    /// `base` (the DMP-SL, or a profile named `profile` in errors) with these settings over it,
    /// checked; an error names the option that set the bad value.
    pub fn apply(&self, mut p: Printer, profile: &str) -> Result<Printer, OptionError> {
        if let Some(v) = self.layer {
            p.layer_mm = v;
        }
        if let Some(v) = self.pixel {
            p.pixel_mm = v;
        }
        if let Some((w, h)) = self.resolution {
            (p.pixels_x, p.pixels_y) = (w, h);
        }
        if let Some(v) = self.exposure {
            p.exposure_s = v;
        }
        if let Some(v) = self.bottom_exposure {
            p.bottom_exposure_s = v;
        }
        if let Some(v) = self.bottom_layers {
            p.bottom_layers = v;
        }
        if let Some(v) = self.lift {
            p.lift_mm = v;
        }
        if let Some(v) = self.lift_speed {
            p.lift_speed_mm_min = v;
            p.retract_speed_mm_min = v;
        }
        p.check().map_err(|e| {
            let option = match &e {
                SliceError::Printer { field, .. } => match *field {
                    "layer_mm" if self.layer.is_some() => "layer",
                    "pixel_mm" if self.pixel.is_some() => "pixel",
                    "pixels_x" | "pixels_y" if self.resolution.is_some() => "resolution",
                    "exposure_s" if self.exposure.is_some() => "exposure",
                    "bottom_exposure_s" if self.bottom_exposure.is_some() => "bottom_exposure",
                    "bottom_layers" if self.bottom_layers.is_some() => "bottom_layers",
                    "lift_mm" if self.lift.is_some() => "lift",
                    f if self.lift_speed.is_some() && f.ends_with("speed_mm_min") => "lift_speed",
                    _ => "printer",
                },
                _ => "printer",
            };
            let problem = if option == "printer" {
                format!("{profile}: {e}")
            } else {
                e.to_string()
            };
            OptionError::new(option, problem)
        })?;
        Ok(p)
    }
}

/// The printer, the plate and the estimate: what `slice` and `print` share. `Default` is the
/// commands' defaults.
#[derive(Clone, Debug)]
pub struct JobOptions {
    /// The printer (checked). Default: the DMP-SL.
    pub printer: Printer,
    /// Copies of each model. Default 1.
    pub copies: usize,
    /// Space between models on the plate, mm. Default 2.
    pub gap: f64,
    /// Resin price per litre. Default 55.
    pub resin_cost: f64,
    /// Resin density, g/mL. Default 1.1.
    pub density: f64,
    /// Build speed, mm/h, instead of the exposure and peel model. Default: none.
    pub speed: Option<f64>,
    /// Resin name for the archive. Default "".
    pub material: String,
    /// The job's name in the archive (and print.json's `archive`). Default "lamina".
    pub name: String,
}

impl Default for JobOptions {
    fn default() -> Self {
        JobOptions {
            printer: Printer::default(),
            copies: 1,
            gap: 2.0,
            resin_cost: 55.0,
            density: 1.1,
            speed: None,
            material: String::new(),
            name: "lamina".into(),
        }
    }
}

/// The fastest build speed taken, mm/h: a hundred metres an hour, far past any resin printer.
const MAX_SPEED: f64 = 1e5;

impl JobOptions {
    /// Every job option checked.
    pub fn check(&self) -> Result<(), OptionError> {
        // A price per litre (free resin allowed), a density between foam and the densest
        // metal-filled resin, a gap between copies no wider than a printer's plate.
        super::in_range("resin_cost", self.resin_cost, 0.0, 1e6, "per litre")?;
        super::in_range("density", self.density, 0.1, 30.0, "g/mL")?;
        if let Some(v) = self.speed {
            if !(v.is_finite() && v > 0.0 && v <= MAX_SPEED) {
                return Err(OptionError::new(
                    "speed",
                    format!(
                        "must be a positive number of mm/h, at most {}, got {}",
                        crate::text::num(MAX_SPEED),
                        crate::text::num(v)
                    ),
                ));
            }
        }
        if self.copies == 0 {
            return Err(OptionError::new("copies", "must be at least 1"));
        }
        super::in_range("gap", self.gap, 0.0, 1000.0, "mm")?;
        Ok(())
    }
}

/// How meshes are sliced. `Default` is the command's defaults.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The printer, plate and estimate settings.
    pub job: JobOptions,
    /// Print the models where they are instead of arranging them. Default false.
    pub keep_position: bool,
    /// The unit the models are in: taken to mm before slicing. Default mm.
    pub units: Option<crate::network::io::units::LengthUnit>,
    /// Every model is scaled by this after `units`. Default 1.
    pub scale: Option<f64>,
    /// Weld each model's corners within this before slicing (CAD STLs whose shared corners
    /// differ in the last bits). Default none: only equal corners are one point.
    pub weld: Option<crate::network::Weld>,
    /// Tree supports under every island of each model, planned at the printer's pixel and
    /// layer (`supports::plan_mesh`). Default none.
    pub supports: Option<SupportOptions>,
}

/// A sliced job: print.json and the estimate (the archive went to the writer).
#[derive(Clone, Debug)]
pub struct Sliced {
    /// The report, as the command writes it.
    pub report: Report,
    /// Resin, cost and time.
    pub estimate: Estimate,
    /// What the caller should hear (models only a few layers tall), one line each.
    pub notes: Vec<String>,
}

/// print.json. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The archive: the job's name with `.sl1` (the command line puts its path here).
    pub archive: String,
    /// Upper corner of the bounding box, mm.
    pub bbox_max: [f64; 3],
    /// Lower corner of the bounding box, mm.
    pub bbox_min: [f64; 3],
    /// What the build time comes from.
    pub build_time_from: String,
    /// Build time, h.
    pub build_time_h: f64,
    /// Volume inside the sections' contours, mL.
    pub contour_volume_ml: Option<f64>,
    /// Copies of each model.
    pub copies: usize,
    /// Resin density, g/mL.
    pub density_g_ml: f64,
    /// Height of the print, mm.
    pub height_mm: f64,
    /// Islands in all.
    pub island_count: usize,
    /// Islands (listed up to a limit).
    pub islands: Vec<Island>,
    /// Each layer's area from its image, mm².
    pub layer_area_mm2: Vec<f64>,
    /// Layer height, mm.
    pub layer_mm: f64,
    /// Layers.
    pub layers: usize,
    /// Resin mass, g.
    pub mass_g: f64,
    /// The meshes' volume, mL.
    pub mesh_volume_ml: Option<f64>,
    /// Build time by the exposure and peel model, h.
    pub model_build_time_h: f64,
    /// The models' names.
    pub models: Vec<String>,
    /// Where each part (or model) lies.
    pub placements: Vec<Placement>,
    /// The printer.
    pub printer: Printer,
    /// Resin cost.
    pub resin_cost: f64,
    /// Resin price per litre.
    pub resin_cost_per_litre: f64,
    /// The solid sampled (`print` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solid: Option<serde_json::Value>,
    /// The supports added (`print --supports` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub supports: Option<serde_json::Value>,
    /// Resin from the layer images, mL.
    pub volume_ml: f64,
}

/// Why nothing was sliced.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(transparent)]
    /// Slicing failed.
    Slice(#[from] SliceError),
    #[error("{0}")]
    /// The archive could not be written.
    Write(#[from] std::io::Error),
    #[error("cancelled")]
    /// The caller stopped the stage.
    Cancelled,
    #[error("{path}: {source}")]
    /// Supports could not be planned for a model.
    Supports {
        /// The model's file.
        path: std::path::PathBuf,
        /// Why.
        source: SupportError,
    },
}

/// Where an archive is written: a file, or memory (`std::io::Cursor<Vec<u8>>`).
pub trait Archive: Write + Seek {}

impl<T: Write + Seek> Archive for T {}

/// A layer as it is made, for a caller that keeps the images: (index, PNG bytes, row-major
/// grey bytes).
pub type OnLayer<'a> = &'a mut dyn FnMut(usize, &[u8], &[u8]) -> std::io::Result<()>;

/// Slices `models` (taken to mm by `opts.scale`) into an SL1 archive written to `archive`.
/// `on_layer` sees every layer; `progress` counts them and can stop the job between two.
pub fn run(
    models: &[Model],
    opts: &Options,
    archive: &mut dyn Archive,
    on_layer: Option<OnLayer>,
    progress: &dyn Progress,
) -> Result<Sliced, Error> {
    if models.is_empty() {
        // An empty plate would be a job of one blank layer and a box of no extent.
        return Err(OptionError::new("models", "none given: slice needs at least one mesh").into());
    }
    let job = &opts.job;
    job.check()?;
    let printer = &job.printer;
    let scale = opts.scale.unwrap_or(1.0);
    if !(scale.is_finite() && (1e-6..=1e6).contains(&scale)) {
        return Err(OptionError::new(
            "scale",
            format!("must be a factor from 1e-6 to 1e6, got {scale}"),
        )
        .into());
    }
    if let Some(w) = opts.weld {
        let (t, field) = match w {
            crate::network::Weld::Absolute(t) => (t, "weld"),
            crate::network::Weld::Relative(t) => (t, "weld_rel"),
        };
        if !(t.is_finite() && t >= 0.0) || (field == "weld_rel" && t > 0.5) {
            return Err(OptionError::new(
                field,
                format!(
                    "must be a finite tolerance ≥ 0 (a fraction at most 0.5), got {}",
                    crate::text::num(t)
                ),
            )
            .into());
        }
    }
    let scale = scale * opts.units.map_or(1.0, |u| u.mm());
    let mut notes = Vec::new();
    let mut scaled = Vec::with_capacity(models.len());
    for m in models {
        let mut mesh = m.mesh.clone();
        if let Some(weld) = opts.weld {
            let w = mesh.weld(weld.tolerance_for(&mesh.bbox()));
            notes.push(format!(
                "{}: welded {} corners within {} mm, {} triangles collapsed and dropped",
                m.path.display(),
                w.merged,
                crate::text::num(w.tolerance),
                w.collapsed_triangles
            ));
        }
        // Triangles with two corners at one point (−0 and 0 are one value) bound nothing and
        // would leave their edges unmatched: dropped, and said.
        let before = mesh.triangles.len();
        let positions = &mesh.positions;
        mesh.triangles.retain(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            a != b && b != c && a != c
        });
        let dropped = before - mesh.triangles.len();
        if dropped > 0 {
            notes.push(format!(
                "{}: {dropped} triangles with two corners at one point dropped",
                m.path.display()
            ));
        }
        if scale != 1.0 {
            for p in &mut mesh.positions {
                *p *= scale;
            }
        }
        let height = mesh.bbox().size().z;
        if height < 10.0 * printer.layer_mm {
            notes.push(format!(
                "{}: only {:.1} layers tall ({height:.4} mm at {} mm layers): is it in metres? \
                 give units= or scale=",
                m.path.display(),
                height / printer.layer_mm,
                printer.layer_mm
            ));
        }
        scaled.push(Model {
            path: m.path.clone(),
            mesh,
        });
    }
    let mut held: Vec<Option<Placed>> = Vec::new();
    let mut reports = Vec::new();
    if let Some(s) = &opts.supports {
        // Checked once, named after the first model (with none, nothing is planned).
        if let Some(first) = scaled.first() {
            s.check().map_err(|source| Error::Supports {
                path: first.path.clone(),
                source,
            })?;
        }
        // Supports are planned on closed shells only (`arrange_held` checks each), and only
        // widen a model's box: one that does not fit bare is refused before they are planned
        // (minutes on a model far too large), as the bare slice refuses it.
        arrange_held(
            &scaled,
            &[],
            printer,
            job.copies,
            job.gap,
            opts.keep_position,
        )?;
        for m in &scaled {
            let planned = plan_mesh(&m.mesh, printer, s, progress).map_err(|e| match e {
                SupportError::Cancelled(_) => Error::Cancelled,
                source => Error::Supports {
                    path: m.path.clone(),
                    source,
                },
            })?;
            reports.push(planned.report);
            held.push(Some(supports_only(planned.prims)));
        }
    }
    let placed = arrange_held(
        &scaled,
        &held,
        printer,
        job.copies,
        job.gap,
        opts.keep_position,
    )?;
    let mut sliced = slice_job(
        Source::Held {
            models: &scaled,
            supports: &held,
        },
        &placed,
        job,
        archive,
        on_layer,
        progress,
    )?;
    sliced.report.supports =
        SupportReport::total(&reports).map(|r| serde_json::to_value(r).expect("reports serialise"));
    sliced.notes.splice(0..0, notes);
    Ok(sliced)
}

/// What a job slices: closed meshes, or a solid's shapes sampled directly (`print`).
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// Closed meshes.
    Meshes(&'a [Model]),
    /// Closed meshes and each one's supports (in its frame), drawn after the meshes where
    /// they leave a pixel unlit.
    Held {
        /// The meshes.
        models: &'a [Model],
        /// Each model's supports, if it has them.
        supports: &'a [Option<Placed>],
    },
    /// A solid's shapes sampled directly.
    Shapes {
        /// The shapes, placed as the print places them.
        model: &'a Placed,
        /// The network's name.
        path: &'a Path,
    },
}

/// Why a layer's sink stopped.
enum Stop {
    Io(std::io::Error),
    Cancelled,
}

impl From<std::io::Error> for Stop {
    fn from(e: std::io::Error) -> Self {
        Stop::Io(e)
    }
}

/// Slices placed models into the archive, and returns print.json and the estimate.
pub fn slice_job(
    source: Source,
    placed: &[Placement],
    job: &JobOptions,
    archive: &mut dyn Archive,
    mut on_layer: Option<OnLayer>,
    progress: &dyn Progress,
) -> Result<Sliced, Error> {
    let printer = &job.printer;
    let name = job.name.clone();
    let (source, supports) = match source {
        Source::Held { models, supports } => (Source::Meshes(models), supports),
        other => (other, &[][..]),
    };
    let layers_total = match source {
        Source::Held { models, .. } | Source::Meshes(models) => layer_count(models, printer),
        Source::Shapes { model, .. } => shapes::layer_count(model, printer),
    };
    progress.begin("slicing", Some(layers_total as u64));
    let mut areas = Vec::with_capacity(layers_total);
    let mut exact = Vec::with_capacity(layers_total);
    let mut finder = Islands::new(
        printer.pixels_x as usize,
        printer.pixels_y as usize,
        printer.pixel_mm,
        printer.layer_mm,
    );
    let (mut islands, mut island_count) = (Vec::new(), 0usize);
    let resin = Resin {
        cost_per_litre: job.resin_cost,
        density: job.density,
    };
    let mut sl1 = Sl1Writer::new(archive, &name);
    let mut sink = |layer: Layer| -> Result<(), Stop> {
        if progress.cancelled() {
            return Err(Stop::Cancelled);
        }
        sl1.layer(layer.index, &layer.png)?;
        if let Some(f) = on_layer.as_mut() {
            f(layer.index, &layer.png, &layer.image)?;
        }
        areas.push(layer.area_mm2);
        exact.push(layer.exact_area_mm2);
        for i in finder.layer_owned(layer.index, layer.image) {
            island_count += 1;
            if islands.len() < MAX_LISTED {
                islands.push(i);
            }
        }
        progress.set(areas.len() as u64);
        Ok(())
    };
    let done = match source {
        Source::Held { models, .. } | Source::Meshes(models) => {
            slicer::slice_held(models, supports, placed, printer, &mut sink)
        }
        Source::Shapes { model, .. } => shapes::slice(model, placed, printer, &mut sink),
    };
    match done {
        Ok(_) => {}
        Err(Stop::Io(e)) => return Err(e.into()),
        Err(Stop::Cancelled) => return Err(Error::Cancelled),
    }
    let e = estimate(printer, &resin, &areas, job.speed);
    sl1.finish(
        printer,
        &Job {
            name: &name,
            layers: areas.len(),
            print_seconds: printer.build_seconds(areas.len()),
            used_ml: e.volume_ml,
            material: &job.material,
        },
    )?;
    // Per model once; every copy has the same volume and height.
    let (paths, volumes, heights): (Vec<String>, Option<Vec<f64>>, Vec<f64>) = match source {
        Source::Held { models, .. } | Source::Meshes(models) => (
            models
                .iter()
                .map(|m| m.path.display().to_string())
                .collect(),
            Some(models.iter().map(|m| m.mesh.signed_volume()).collect()),
            models.iter().map(|m| m.mesh.bbox().size().z).collect(),
        ),
        Source::Shapes { model, path } => {
            let (lo, hi) = model.bounds();
            (vec![path.display().to_string()], None, vec![hi.z - lo.z])
        }
    };
    let mesh_volume: Option<f64> =
        volumes.map(|v| placed.iter().map(|p| v[p.model]).sum::<f64>() / 1000.0);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in placed {
        let h = heights[p.model];
        lo = [lo[0].min(p.min[0]), lo[1].min(p.min[1]), 0.0];
        hi = [hi[0].max(p.max[0]), hi[1].max(p.max[1]), hi[2].max(h)];
    }
    // The contours' volume, when the layers were cut from meshes.
    let exact_ml = exact
        .iter()
        .copied()
        .sum::<Option<f64>>()
        .map(|a| a * printer.layer_mm / 1000.0);
    let report = Report {
        archive: format!("{}.sl1", job.name),
        bbox_max: hi,
        bbox_min: lo,
        build_time_from: e.build_time_from.clone(),
        build_time_h: e.build_time_h,
        contour_volume_ml: exact_ml,
        copies: job.copies,
        density_g_ml: resin.density,
        height_mm: e.height_mm,
        island_count,
        islands,
        layer_area_mm2: areas,
        layer_mm: printer.layer_mm,
        layers: e.layers,
        mass_g: e.mass_g,
        mesh_volume_ml: mesh_volume,
        model_build_time_h: e.model_time_h,
        models: paths,
        placements: placed.to_vec(),
        printer: printer.clone(),
        resin_cost: e.resin_cost,
        resin_cost_per_litre: resin.cost_per_litre,
        solid: None,
        supports: None,
        volume_ml: e.volume_ml,
    };
    Ok(Sliced {
        report,
        estimate: e,
        notes: Vec::new(),
    })
}

/// Layer images side by side as one grey PNG, each cropped to the footprint `min`..`max` (mm
/// on the build plate, as [`Placement`] gives it) with `margin` pixels around it and `gap`
/// pixels between images. `images` are whole layers of `printer` (row 0 at the plate's far
/// edge), as [`OnLayer`] hands them out.
pub fn layer_strip(
    printer: &Printer,
    min: [f64; 2],
    max: [f64; 2],
    images: &[&[u8]],
    margin: usize,
    gap: usize,
) -> Vec<u8> {
    let px = printer.pixel_mm;
    let (w, h) = (printer.pixels_x as usize, printer.pixels_y as usize);
    let ([x0, y0], [x1, y1]) = (min, max);
    let c0 = ((x0 / px) as usize).saturating_sub(margin);
    let c1 = ((x1 / px).ceil() as usize + margin).min(w);
    let r0 = ((h as f64 - y1 / px).max(0.0) as usize).saturating_sub(margin);
    let r1 = ((h as f64 - y0 / px).ceil() as usize + margin).min(h);
    let (cw, ch) = (c1.saturating_sub(c0), r1.saturating_sub(r0));
    let sw = images.len() * cw + images.len().saturating_sub(1) * gap;
    let mut strip = vec![96u8; sw * ch];
    for (k, image) in images.iter().enumerate() {
        if image.len() < w * h {
            continue;
        }
        for r in 0..ch {
            let src = &image[(r0 + r) * w + c0..(r0 + r) * w + c1];
            let at = r * sw + k * (cw + gap);
            strip[at..at + cw].copy_from_slice(src);
        }
    }
    slicer::encode_grey(&strip, sw as u32, ch as u32)
}

impl Report {
    /// print.json's text.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("reports serialise") + "\n"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_model_is_refused_and_nothing_is_written() {
        let mut archive = std::io::Cursor::new(Vec::new());
        let got = run(
            &[],
            &Options::default(),
            &mut archive,
            None,
            &crate::stage::Quiet,
        );
        match got {
            Err(Error::Option(e)) => assert_eq!(e.option, "models"),
            other => panic!(
                "expected a refusal, got {:?}",
                other.map(|s| s.report.layers)
            ),
        }
        assert!(archive.into_inner().is_empty());
    }

    #[test]
    fn job_figures_out_of_range_are_refused_naming_the_option() {
        type Spoil = fn(&mut JobOptions);
        let bad: [(&str, Spoil); 6] = [
            ("resin_cost", |j| j.resin_cost = 1e300),
            ("resin_cost", |j| j.resin_cost = -1.0),
            ("density", |j| j.density = 0.0),
            ("speed", |j| j.speed = Some(f64::NAN)),
            ("speed", |j| j.speed = Some(1e300)),
            ("gap", |j| j.gap = f64::INFINITY),
        ];
        for (option, spoil) in bad {
            let mut job = JobOptions::default();
            spoil(&mut job);
            assert_eq!(job.check().map_err(|e| e.option), Err(option));
        }
        let mut fine = JobOptions {
            resin_cost: 0.0,
            speed: Some(25.0),
            ..JobOptions::default()
        };
        assert_eq!(fine.check(), Ok(()));
        fine.density = 30.0;
        assert_eq!(fine.check(), Ok(()));
    }
}
