//! `lamina slice MODEL.stl... -o job.sl1`: layer images of closed meshes for a masked-SLA
//! printer, as an SL1 archive (and a folder of PNGs), with a print estimate.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;

use super::progress::Bar;
use super::venation::write_json;
use lamina::fabricate::estimate::Estimate;
use lamina::files::write_atomic;
use lamina::mesh::io::read_triangles;
use lamina::network::io::units::LengthUnit;
use lamina::stage::slice::{
    self, Archive, JobOptions, Model, OnLayer, Printer, PrinterOptions, Sliced,
};

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
    #[command(flatten)]
    pub weld: super::surface::SurfaceWeld,
    #[command(flatten)]
    pub supports: super::solid::SupportArgs,
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

/// The unit `--units` names.
fn units(args: &Args) -> Result<Option<LengthUnit>> {
    args.units
        .as_deref()
        .map(|name| {
            LengthUnit::parse(name).with_context(|| {
                format!(
                    "--units: `{}` is not a unit lamina knows ({})",
                    name.escape_debug(),
                    LengthUnit::NAMES
                )
            })
        })
        .transpose()
}

/// The printer: the built-in DMP-SL or a profile file, with the flags over it.
pub fn printer(args: &JobArgs) -> Result<Printer> {
    let base = if args.printer == "dmp-sl" {
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
    let resolution = match &args.resolution {
        None => None,
        Some(r) => {
            let parsed = r
                .split_once(['x', 'X'])
                .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)));
            let Some(wh) = parsed else {
                bail!("--resolution {r}: expected WIDTHxHEIGHT in pixels, e.g. 1920x1080");
            };
            Some(wh)
        }
    };
    let overrides = PrinterOptions {
        layer: args.layer,
        pixel: args.pixel,
        resolution,
        exposure: args.exposure,
        bottom_exposure: args.bottom_exposure,
        bottom_layers: args.bottom_layers,
        lift: args.lift,
        lift_speed: args.lift_speed,
    };
    let profile = if args.printer == "dmp-sl" {
        "dmp-sl".to_string()
    } else {
        args.printer.clone()
    };
    Ok(overrides.apply(base, &profile)?)
}

impl JobArgs {
    /// The job's options, every flag checked; the archive named by `output`'s stem.
    pub fn options(&self, output: &Path) -> Result<JobOptions> {
        let opts = JobOptions {
            printer: printer(self)?,
            copies: self.copies,
            gap: self.gap,
            resin_cost: self.resin_cost,
            density: self.density,
            speed: self.speed,
            material: self.material.clone(),
            name: output
                .file_stem()
                .and_then(|s| s.to_str())
                .filter(|s| !s.is_empty())
                .unwrap_or("lamina")
                .to_string(),
        };
        opts.check()?;
        Ok(opts)
    }

    /// Writes print.json where asked and says what the job is.
    pub fn finish(&self, sliced: &Sliced, printer: &Printer, output: &Path) -> Result<()> {
        for n in &sliced.notes {
            errln!("lamina: {n}");
        }
        let mut report = sliced.report.clone();
        report.archive = output.display().to_string();
        if let Some(path) = &self.report {
            write_json(path, &report)?;
        }
        let e = &sliced.estimate;
        tell(
            &report,
            e,
            printer,
            output,
            self.json,
            self.report.as_deref(),
        )
    }
}

/// Runs `job` into the archive at `output` (and the layers into `layers_dir`, named by the
/// job's `name`): an error leaves neither.
pub fn write_job<E: Into<anyhow::Error>>(
    output: &Path,
    layers_dir: Option<&Path>,
    name: &str,
    job: impl FnOnce(&mut dyn Archive, Option<OnLayer>) -> Result<Sliced, E>,
) -> Result<Sliced> {
    let staging = layers_dir.map(Staging::new).transpose()?;
    let mut save = |index: usize, png: &[u8], _: &[u8]| -> std::io::Result<()> {
        match &staging {
            Some(s) => std::fs::write(s.tmp.join(format!("{name}{index:05}.png")), png),
            None => Ok(()),
        }
    };
    let mut result = None;
    let written = write_atomic(output, |w| {
        let on_layer: Option<OnLayer> = staging.is_some().then_some(&mut save);
        match job(w, on_layer) {
            Ok(s) => {
                result = Some(Ok(s));
                Ok(())
            }
            Err(e) => {
                result = Some(Err(e.into()));
                Err(std::io::Error::other("the job stopped"))
            }
        }
    });
    let sliced = match result {
        Some(r) => r?,
        None => {
            written?;
            bail!("internal: the job did not run");
        }
    };
    written?;
    if let Some(s) = staging {
        s.commit()?;
    }
    Ok(sliced)
}

pub fn run(args: Args) -> Result<()> {
    let models = args
        .models
        .iter()
        .map(|path| {
            let (mesh, not_read) = read_triangles(path)?;
            super::input::say_not_read(path, &not_read);
            Ok(Model {
                path: path.clone(),
                mesh,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let job = args.job.options(&args.output)?;
    let opts = slice::Options {
        job,
        keep_position: args.keep_position,
        units: units(&args)?,
        scale: args.scale,
        weld: args.weld.weld()?,
        supports: args.supports.options()?,
    };
    let sliced = write_job(
        &args.output,
        args.job.layers_dir.as_deref(),
        &opts.job.name,
        |archive, on_layer| slice::run(&models, &opts, archive, on_layer, &Bar::new()),
    )?;
    args.job.finish(&sliced, &opts.job.printer, &args.output)
}

/// Says what a sliced job is: the summary (or print.json with `json`) on stdout, and its
/// islands, with where they are listed (`report_path`, where print.json was written) and, when
/// the job had no supports, that `--supports` holds them.
pub fn tell(
    report: &slice::Report,
    e: &Estimate,
    printer: &Printer,
    output: &Path,
    json: bool,
    report_path: Option<&Path>,
) -> Result<()> {
    if json {
        outln!("{}", serde_json::to_string_pretty(report)?);
    } else {
        outln!(
            "wrote {}: {} layers of {} mm ({:.2} mm), {} model(s) on the plate",
            output.display(),
            e.layers,
            printer.layer_mm,
            e.height_mm,
            report.placements.len()
        );
        let mesh = match report.mesh_volume_ml {
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
    let count = report.island_count;
    let listed = match (json, report_path) {
        (true, _) => "see \"islands\" in the JSON".to_string(),
        (false, Some(path)) => format!("see \"islands\" in {}", path.display()),
        (false, None) => "--report FILE lists them".to_string(),
    };
    let hold = if report.supports.is_none() {
        "; --supports holds them"
    } else {
        ""
    };
    let line = match report.islands.first() {
        None => "no islands: every region of every layer stands on the one below".to_string(),
        Some(i) => format!(
            "{count} islands (regions cured in free resin, touching nothing in the layer below): \
             the first at layer {} ({:.2}, {:.2}) mm, {:.3} mm²; {listed}{hold}",
            i.layer, i.x_mm, i.y_mm, i.area_mm2
        ),
    };
    if json {
        errln!("lamina: {line}");
    } else {
        outln!("  {line}");
    }
    Ok(())
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
