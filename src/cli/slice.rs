//! `lamina slice MODEL.stl... -o job.sl1`: layer images of closed meshes for a masked-SLA
//! printer, as an SL1 archive (and a folder of PNGs), with a print estimate.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use indicatif::ProgressStyle;
use serde_json::json;

use super::venation::write_json;
use lamina::fabricate::archive::{Job, Sl1Writer};
use lamina::fabricate::estimate::{estimate, Estimate, Resin};
use lamina::fabricate::sl1::MAX_LISTED;
use lamina::fabricate::slice::islands::Islands;
use lamina::fabricate::slice::shapes::{self, Placed};
use lamina::fabricate::slice::{
    self, arrange, layer_count, Layer, Model, Placement, Printer, SliceError,
};
use lamina::files::write_atomic;
use lamina::mesh::io::read_triangles;
use lamina::network::io::units::LengthUnit;
use lamina::TriMesh;

#[derive(ClapArgs)]
pub struct Args {
    /// Closed meshes to print (.stl .obj); overlapping shells are fine
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// The SL1 archive to write
    #[arg(short, long)]
    pub output: PathBuf,
    #[command(flatten)]
    pub job: JobArgs,
    /// Print the models where they are (x, y in the display's mm) instead of arranging them
    #[arg(long, conflicts_with = "copies")]
    pub keep_position: bool,
    /// Scale every model by this factor before slicing (after --units)
    #[arg(long, value_name = "F")]
    pub scale: Option<f64>,
    /// The unit the models are in (mm, cm, m, in, ft): taken to mm before slicing [default: mm]
    #[arg(long, value_name = "UNIT")]
    pub units: Option<String>,
}

/// The printer, the plate and the report: what `slice` and `print` share.
#[derive(ClapArgs)]
pub struct JobArgs {
    /// Printer: `dmp-sl` (built in) or a JSON profile whose fields override it
    #[arg(long, default_value = "dmp-sl")]
    pub printer: String,
    /// Layer height, mm
    #[arg(long, value_name = "MM")]
    pub layer: Option<f64>,
    /// Pixel size, mm
    #[arg(long, value_name = "MM")]
    pub pixel: Option<f64>,
    /// Display resolution, WIDTHxHEIGHT pixels
    #[arg(long, value_name = "WxH")]
    pub resolution: Option<String>,
    /// Exposure per layer, s
    #[arg(long, value_name = "S")]
    pub exposure: Option<f64>,
    /// Exposure of the bottom layers, s
    #[arg(long, value_name = "S")]
    pub bottom_exposure: Option<f64>,
    /// How many bottom layers
    #[arg(long, value_name = "N")]
    pub bottom_layers: Option<u32>,
    /// Peel lift after each layer, mm
    #[arg(long, value_name = "MM")]
    pub lift: Option<f64>,
    /// Lift and retract speed, mm/min
    #[arg(long, value_name = "MM_MIN")]
    pub lift_speed: Option<f64>,
    /// Print this many copies of each model
    #[arg(long, default_value_t = 1)]
    pub copies: usize,
    /// Space between models on the plate, mm
    #[arg(long, default_value_t = 2.0)]
    pub gap: f64,
    /// Also write the layer images into this folder
    #[arg(long, value_name = "DIR")]
    pub layers_dir: Option<PathBuf>,
    /// Write the print estimate (print.json) here
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Resin price per litre
    #[arg(long, default_value_t = 55.0)]
    pub resin_cost: f64,
    /// Resin density, g/mL
    #[arg(long, default_value_t = 1.1)]
    pub density: f64,
    /// Build speed, mm/h, instead of the exposure and peel model (Peele: 25)
    #[arg(long, value_name = "MM_H")]
    pub speed: Option<f64>,
    /// Resin name for the archive
    #[arg(long, default_value = "")]
    pub material: String,
    /// Print the estimate as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// The factor every model is scaled by: `--units` to mm, then `--scale`.
fn model_scale(args: &Args) -> Result<f64> {
    let unit = match &args.units {
        None => 1.0,
        Some(name) => LengthUnit::parse(name)
            .with_context(|| {
                format!(
                    "--units: `{}` is not a unit lamina knows ({})",
                    name.escape_debug(),
                    LengthUnit::NAMES
                )
            })?
            .mm(),
    };
    let scale = args.scale.unwrap_or(1.0);
    if !(scale.is_finite() && (1e-6..=1e6).contains(&scale)) {
        bail!("--scale must be a factor from 1e-6 to 1e6, got {scale}");
    }
    Ok(unit * scale)
}

pub fn printer(args: &JobArgs) -> Result<Printer> {
    let mut p = if args.printer == "dmp-sl" {
        Printer::default()
    } else {
        let path = Path::new(&args.printer);
        let text = std::fs::read_to_string(path).with_context(|| {
            format!(
                "--printer {}: not `dmp-sl` and not a readable JSON profile",
                path.display()
            )
        })?;
        serde_json::from_str::<Printer>(&text)
            .with_context(|| format!("{}: not a printer profile", path.display()))?
    };
    if let Some(v) = args.layer {
        p.layer_mm = v;
    }
    if let Some(v) = args.pixel {
        p.pixel_mm = v;
    }
    if let Some(r) = &args.resolution {
        let parsed = r
            .split_once(['x', 'X'])
            .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)));
        let Some((w, h)) = parsed else {
            bail!("--resolution {r}: expected WIDTHxHEIGHT in pixels, e.g. 1920x1080");
        };
        (p.pixels_x, p.pixels_y) = (w, h);
    }
    if let Some(v) = args.exposure {
        p.exposure_s = v;
    }
    if let Some(v) = args.bottom_exposure {
        p.bottom_exposure_s = v;
    }
    if let Some(v) = args.bottom_layers {
        p.bottom_layers = v;
    }
    if let Some(v) = args.lift {
        p.lift_mm = v;
    }
    if let Some(v) = args.lift_speed {
        p.lift_speed_mm_min = v;
        p.retract_speed_mm_min = v;
    }
    p.check().map_err(|e| {
        let given = |flag: &str| anyhow::anyhow!("{flag}: {e}");
        match (&e, &args) {
            (
                SliceError::Printer {
                    field: "layer_mm", ..
                },
                a,
            ) if a.layer.is_some() => given("--layer"),
            (
                SliceError::Printer {
                    field: "pixel_mm", ..
                },
                a,
            ) if a.pixel.is_some() => given("--pixel"),
            (
                SliceError::Printer {
                    field: "pixels_x", ..
                },
                a,
            ) if a.resolution.is_some() => given("--resolution"),
            (
                SliceError::Printer {
                    field: "exposure_s",
                    ..
                },
                a,
            ) if a.exposure.is_some() => given("--exposure"),
            (
                SliceError::Printer {
                    field: "bottom_exposure_s",
                    ..
                },
                a,
            ) if a.bottom_exposure.is_some() => given("--bottom-exposure"),
            (
                SliceError::Printer {
                    field: "bottom_layers",
                    ..
                },
                a,
            ) if a.bottom_layers.is_some() => given("--bottom-layers"),
            (
                SliceError::Printer {
                    field: "lift_mm", ..
                },
                a,
            ) if a.lift.is_some() => given("--lift"),
            (SliceError::Printer { field: f, .. }, a)
                if a.lift_speed.is_some() && f.ends_with("speed_mm_min") =>
            {
                given("--lift-speed")
            }
            _ if args.printer == "dmp-sl" => given("--printer dmp-sl"),
            _ => given(&args.printer),
        }
    })?;
    Ok(p)
}

impl JobArgs {
    /// The printer, with every job flag checked.
    pub fn checked_printer(&self) -> Result<Printer> {
        let printer = printer(self)?;
        for (what, v) in [
            ("--resin-cost", self.resin_cost),
            ("--density", self.density),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                bail!("{what} must be a number ≥ 0, got {v}");
            }
        }
        if let Some(v) = self.speed {
            if !(v.is_finite() && v > 0.0) {
                bail!("--speed must be a positive number of mm/h, got {v}");
            }
        }
        if self.copies == 0 {
            bail!("--copies must be at least 1");
        }
        if !(self.gap.is_finite() && self.gap >= 0.0) {
            bail!("--gap must be a number of mm ≥ 0, got {}", self.gap);
        }
        Ok(printer)
    }

    pub fn spec<'a>(&'a self, output: &'a Path) -> Spec<'a> {
        Spec {
            output,
            layers_dir: self.layers_dir.as_deref(),
            resin: Resin {
                cost_per_litre: self.resin_cost,
                density: self.density,
            },
            speed: self.speed,
            material: &self.material,
            copies: self.copies,
        }
    }

    /// Writes print.json where asked and says what the job is.
    pub fn finish(
        &self,
        report: &serde_json::Value,
        e: &Estimate,
        printer: &Printer,
        output: &Path,
    ) -> Result<()> {
        if let Some(path) = &self.report {
            write_json(path, report)?;
        }
        tell(report, e, printer, output, self.json)
    }
}

pub fn run(args: Args) -> Result<()> {
    let meshes = args
        .models
        .iter()
        .map(|path| Ok((path.clone(), read_triangles(path)?)))
        .collect::<Result<Vec<_>>>()?;
    let (report, e, printer) = slice_models(&args, meshes)?;
    args.job.finish(&report, &e, &printer, &args.output)
}

/// Slices the models (each named by its path, read from it or handed over by the Python
/// package; in the units `--units` gives, before `--scale`) and writes the archive (and the
/// layers folder). Returns print.json, the estimate and the printer.
pub fn slice_models(
    args: &Args,
    meshes: Vec<(PathBuf, TriMesh)>,
) -> Result<(serde_json::Value, Estimate, Printer)> {
    let job = &args.job;
    let printer = job.checked_printer()?;
    let scale = model_scale(args)?;
    let mut models = Vec::with_capacity(meshes.len());
    for (path, mut mesh) in meshes {
        if scale != 1.0 {
            for p in &mut mesh.positions {
                *p *= scale;
            }
        }
        let height = mesh.bbox().size().z;
        if height < 10.0 * printer.layer_mm {
            errln!(
                "lamina: {}: only {:.1} layers tall ({height:.4} mm at {} mm layers): is it in \
                 metres? give --units or --scale",
                path.display(),
                height / printer.layer_mm,
                printer.layer_mm
            );
        }
        models.push(Model { path, mesh });
    }
    let placed = arrange(&models, &printer, job.copies, job.gap, args.keep_position)?;
    let spec = job.spec(&args.output);
    let (report, e, _) = slice_job(Source::Meshes(&models), &placed, &printer, &spec, &[])?;
    Ok((report, e, printer))
}

/// Says what a sliced job is: the summary (or print.json with `json`) on stdout, and its islands.
pub fn tell(
    report: &serde_json::Value,
    e: &Estimate,
    printer: &Printer,
    output: &Path,
    json: bool,
) -> Result<()> {
    if json {
        outln!("{}", serde_json::to_string_pretty(report)?);
    } else {
        let placed = report["placements"].as_array().map_or(0, |p| p.len());
        outln!(
            "wrote {}: {} layers of {} mm ({:.2} mm), {placed} model(s) on the plate",
            output.display(),
            e.layers,
            printer.layer_mm,
            e.height_mm,
        );
        let mesh = match report["mesh_volume_ml"].as_f64() {
            Some(v) => format!(" (mesh {v:.4} mL)"),
            None => String::new(),
        };
        outln!(
            "  resin {:.4} mL{mesh}, cost {:.4}, {:.3} g; build {:.2} h ({})",
            e.volume_ml,
            e.resin_cost,
            e.mass_g,
            e.build_time_h,
            e.build_time_from
        );
    }
    // Islands are said even with --json (on stderr then): a print fails at each.
    let count = report["island_count"].as_u64().unwrap_or(0);
    let line = match report["islands"].get(0) {
        None => "no islands: every region of every layer stands on the one below".to_string(),
        Some(i) => format!(
            "{count} islands (regions cured in free resin, touching nothing in the layer below): \
             the first at layer {} ({:.2}, {:.2}) mm, {:.3} mm²; see \"islands\" in the report",
            i["layer"],
            i["x_mm"].as_f64().unwrap_or(0.0),
            i["y_mm"].as_f64().unwrap_or(0.0),
            i["area_mm2"].as_f64().unwrap_or(0.0)
        ),
    };
    if json {
        errln!("lamina: {line}");
    } else {
        outln!("  {line}");
    }
    Ok(())
}

/// What a job slices: closed meshes, or a solid's shapes sampled directly (`lamina print`).
#[derive(Clone, Copy)]
pub enum Source<'a> {
    Meshes(&'a [Model]),
    Shapes { model: &'a Placed, path: &'a Path },
}

/// Raw images of chosen layers: (index, row-major grey bytes).
pub type Kept = Vec<(usize, Vec<u8>)>;

/// Where and how to write a sliced job.
pub struct Spec<'a> {
    pub output: &'a Path,
    pub layers_dir: Option<&'a Path>,
    pub resin: Resin,
    pub speed: Option<f64>,
    pub material: &'a str,
    pub copies: usize,
}

/// Slices placed models into the SL1 archive (and the layers folder), and returns print.json,
/// the estimate, and the raw images of the layers listed in `keep`.
pub fn slice_job(
    source: Source,
    placed: &[Placement],
    printer: &Printer,
    spec: &Spec,
    keep: &[usize],
) -> Result<(serde_json::Value, Estimate, Kept)> {
    let name = spec
        .output
        .file_stem()
        .and_then(|s| s.to_str())
        .filter(|s| !s.is_empty())
        .unwrap_or("lamina")
        .to_string();
    let layers_total = match source {
        Source::Meshes(models) => layer_count(models, printer),
        Source::Shapes { model, .. } => shapes::layer_count(model, printer),
    };
    let bar = super::progress::bar("slicing", Some(layers_total as u64));
    bar.set_style(ProgressStyle::with_template(
        "slicing {bar:40} {pos}/{len} layers {elapsed}",
    )?);
    let staging = match spec.layers_dir {
        Some(dir) => Some(Staging::new(dir)?),
        None => None,
    };
    let mut areas = Vec::with_capacity(layers_total);
    let mut exact = Vec::with_capacity(layers_total);
    let mut finder = Islands::new(
        printer.pixels_x as usize,
        printer.pixels_y as usize,
        printer.pixel_mm,
        printer.layer_mm,
    );
    let (mut islands, mut island_count) = (Vec::new(), 0usize);
    let mut kept = Vec::new();
    let mut est = None;
    write_atomic(spec.output, |w| {
        let mut sl1 = Sl1Writer::new(w, &name);
        let mut on_layer = |layer: Layer| {
            sl1.layer(layer.index, &layer.png)?;
            if let Some(s) = &staging {
                std::fs::write(
                    s.tmp.join(format!("{name}{:05}.png", layer.index)),
                    &layer.png,
                )?;
            }
            areas.push(layer.area_mm2);
            exact.push(layer.exact_area_mm2);
            if keep.contains(&layer.index) {
                kept.push((layer.index, layer.image.clone()));
            }
            for i in finder.layer_owned(layer.index, layer.image) {
                island_count += 1;
                if islands.len() < MAX_LISTED {
                    islands.push(i);
                }
            }
            bar.inc(1);
            Ok::<(), std::io::Error>(())
        };
        match source {
            Source::Meshes(models) => slice::slice(models, placed, printer, &mut on_layer)?,
            Source::Shapes { model, .. } => shapes::slice(model, placed, printer, &mut on_layer)?,
        };
        let e = est.insert(estimate(printer, &spec.resin, &areas, spec.speed));
        sl1.finish(
            printer,
            &Job {
                name: &name,
                layers: areas.len(),
                print_seconds: printer.build_seconds(areas.len()),
                used_ml: e.volume_ml,
                material: spec.material,
            },
        )?;
        Ok(())
    })?;
    bar.finish_and_clear();
    if let Some(s) = staging {
        s.commit()?;
    }
    let e = est.ok_or_else(|| anyhow::anyhow!("internal: slicing finished without an estimate"))?;
    // Per model once; every copy has the same volume and height.
    let (paths, volumes, heights): (Vec<&Path>, Option<Vec<f64>>, Vec<f64>) = match source {
        Source::Meshes(models) => (
            models.iter().map(|m| m.path.as_path()).collect(),
            Some(models.iter().map(|m| m.mesh.signed_volume()).collect()),
            models.iter().map(|m| m.mesh.bbox().size().z).collect(),
        ),
        Source::Shapes { model, path } => {
            let (lo, hi) = model.bounds();
            (vec![path], None, vec![hi.z - lo.z])
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
    let report = json!({
        "archive": spec.output,
        "printer": printer,
        "models": paths,
        "copies": spec.copies,
        "placements": placed,
        "layers": e.layers,
        "layer_mm": printer.layer_mm,
        "height_mm": e.height_mm,
        "volume_ml": e.volume_ml,
        "contour_volume_ml": exact_ml,
        "mesh_volume_ml": mesh_volume,
        "resin_cost": e.resin_cost,
        "resin_cost_per_litre": spec.resin.cost_per_litre,
        "density_g_ml": spec.resin.density,
        "mass_g": e.mass_g,
        "build_time_h": e.build_time_h,
        "build_time_from": e.build_time_from,
        "model_build_time_h": e.model_time_h,
        "bbox_min": lo,
        "bbox_max": hi,
        "layer_area_mm2": areas,
        "island_count": island_count,
        "islands": islands,
    });
    Ok((report, e, kept))
}

/// A layers folder written beside its final place and renamed into it at the end, so an error
/// never leaves half a stack.
struct Staging {
    tmp: PathBuf,
    dir: PathBuf,
}

impl Staging {
    fn new(dir: &Path) -> Result<Self> {
        let parent = match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("--layers-dir {}: cannot create its parent", dir.display()))?;
        let tmp = tempfile::Builder::new()
            .prefix(".lamina-layers-")
            .tempdir_in(&parent)
            .with_context(|| format!("--layers-dir {}: cannot write beside it", dir.display()))?
            .keep();
        Ok(Staging {
            tmp,
            dir: dir.to_path_buf(),
        })
    }

    fn commit(self) -> Result<()> {
        if self.dir.exists() {
            std::fs::remove_dir_all(&self.dir).with_context(|| {
                format!("--layers-dir {}: cannot replace it", self.dir.display())
            })?;
        }
        std::fs::rename(&self.tmp, &self.dir).with_context(|| {
            format!(
                "--layers-dir {}: cannot move the layers in",
                self.dir.display()
            )
        })?;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        // After a successful commit the folder is gone from here; otherwise clean up.
        let _ = std::fs::remove_dir_all(&self.tmp);
    }
}
