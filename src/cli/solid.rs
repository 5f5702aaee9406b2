//! `lamina solid NET -o leaf.stl`: a vein network as one closed, 2-manifold, outward-oriented
//! triangle mesh, with an optional lamina and base, scaled to a print size.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;

use super::input::ReadArgs;
use super::progress::Bar;
use super::venation::write_json;
use lamina::mesh::io::write_mesh;
use lamina::stage::print::DisplayFit;
use lamina::stage::solid::{self, Base, Shape, SupportOptions, DEFAULT_CELL};

#[derive(ClapArgs)]
pub struct Args {
    /// The vein network (.json .obj .dxf); radii from its nodes and edges
    pub network: PathBuf,
    /// Output mesh (.stl binary, .obj)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Grid cell of the mesher, mm (default: the DMP-SL pixel). The compact mesh is marched at
    /// twice the cell when every piece (veins, lamina, base) is at least four cells thick and
    /// no supports are added, split as fine where veins come close
    #[arg(long, default_value_t = DEFAULT_CELL)]
    pub cell: f64,
    /// The mesh written is simplified to within this distance of the exact surface, mm
    /// (default, and the flag without a value: a quarter of the cell, a quarter pixel by
    /// default)
    #[arg(long, value_name = "MM", num_args = 0..=1)]
    pub tolerance: Option<Option<f64>>,
    /// Write every marched triangle (fitted to the surface on average) instead of the
    /// simplified mesh: many more triangles, made faster
    #[arg(long, conflicts_with = "tolerance")]
    pub full: bool,
    #[command(flatten)]
    pub shape: ShapeArgs,
    #[command(flatten)]
    pub supports: SupportArgs,
    #[command(flatten)]
    pub weld: ReadArgs,
    /// Write the report as JSON here
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print the report as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// What the solid is made of: what `solid` and `print` share.
#[derive(ClapArgs)]
pub struct ShapeArgs {
    /// Add the leaf lamina: the blade outline extruded this thick, mm, veins standing on it
    #[arg(long, value_name = "MM")]
    pub lamina: Option<f64>,
    /// Add a base under the root: cylinder:DIAMETER,HEIGHT in mm
    #[arg(long, value_name = "cylinder:D,H")]
    pub base: Option<String>,
    /// Scale so the longest side of the veins (and blade) is this many mm. `print` also takes
    /// `auto` (the largest size the display takes) and `keep` (as drawn; refused when too
    /// big), and without it shrinks a network too big for the display to fit
    #[arg(long, value_name = "MM")]
    pub fit: Option<String>,
    /// Stand the leaf up for printing: its +y becomes +z
    #[arg(long)]
    pub upright: bool,
    /// Radius for edges the network gives none, mm
    #[arg(long, value_name = "MM")]
    pub radius: Option<f64>,
}

impl ShapeArgs {
    /// The stage's shape options, with the supports asked for.
    pub fn shape(&self, supports: Option<SupportOptions>) -> Result<Shape> {
        let fit = match self.fit.as_deref() {
            None | Some("auto" | "keep") => None,
            Some(mm) => Some(mm.parse::<f64>().map_err(|_| {
                anyhow::anyhow!(
                    "--fit {mm}: expected the longest side in mm (or, for print, auto or keep)"
                )
            })?),
        };
        Ok(Shape {
            lamina: self.lamina,
            base: self.base.as_deref().map(parse_base).transpose()?,
            fit,
            upright: self.upright,
            radius: self.radius,
            supports,
        })
    }
}

impl ShapeArgs {
    /// How `print` sizes the network for the display (`--fit auto`, `--fit keep`, or shrunk
    /// when too big).
    pub fn display_fit(&self) -> DisplayFit {
        match self.fit.as_deref() {
            Some("auto") => DisplayFit::Fill,
            Some("keep") => DisplayFit::Keep,
            _ => DisplayFit::Shrink,
        }
    }

    /// Refuses the words only `print` knows (`solid` does not know the display).
    pub fn fit_in_mm(&self) -> Result<()> {
        if let Some(word @ ("auto" | "keep")) = self.fit.as_deref() {
            bail!(
                "--fit {word}: only print sizes to its display; give the longest side in mm \
                 (the DMP-SL's display is 67.2 × 37.8 mm, 100 mm tall)"
            );
        }
        Ok(())
    }
}

/// Supports under the islands: what `solid` and `print` share.
#[derive(ClapArgs)]
pub struct SupportArgs {
    /// Add tree supports under every island (a region that would start in free resin), at the
    /// printer's pixel and layer (solid: the DMP-SL's)
    #[arg(long)]
    pub supports: bool,
    /// Support tip diameter where it touches the model, mm (narrower on a thinner vein)
    #[arg(long, value_name = "MM", default_value_t = 0.4)]
    pub support_tip: f64,
    /// Support pillar diameter, mm
    #[arg(long, value_name = "MM", default_value_t = 0.8)]
    pub support_pillar: f64,
    /// Join pillars standing closer than this, mm
    #[arg(long, value_name = "MM", default_value_t = 4.0)]
    pub support_join: f64,
    /// Room kept between the supports and the part except at tips and landings, mm
    #[arg(long, value_name = "MM", default_value_t = 0.3)]
    pub support_clearance: f64,
    /// An island wider than this is held by tips about this far apart, mm
    #[arg(long, value_name = "MM", default_value_t = 2.5)]
    pub support_spacing: f64,
    /// Base disc under each pillar on the plate: DIAMETER,HEIGHT in mm
    #[arg(long, value_name = "D,H", default_value = "2,0.4")]
    pub support_base: String,
}

impl SupportArgs {
    /// The supports asked for, if any.
    pub fn options(&self) -> Result<Option<SupportOptions>> {
        if !self.supports {
            return Ok(None);
        }
        let base: Vec<f64> = self
            .support_base
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()
            .filter(|v: &Vec<f64>| v.len() == 2)
            .with_context(|| {
                format!(
                    "--support-base {}: expected DIAMETER,HEIGHT in mm, e.g. 2,0.4",
                    self.support_base
                )
            })?;
        Ok(Some(SupportOptions {
            tip: self.support_tip,
            pillar: self.support_pillar,
            base: base[0],
            base_height: base[1],
            join: self.support_join,
            clearance: self.support_clearance,
            spacing: self.support_spacing,
        }))
    }
}

pub fn parse_base(text: &str) -> Result<Base> {
    let Some(rest) = text.strip_prefix("cylinder:") else {
        bail!("--base {text}: expected cylinder:DIAMETER,HEIGHT (mm), e.g. cylinder:6,2");
    };
    let nums: Vec<f64> = rest
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--base {text}: DIAMETER and HEIGHT must be numbers"))?;
    match nums[..] {
        [diameter, height] => Ok(Base { diameter, height }),
        _ => bail!("--base {text}: expected two numbers, cylinder:DIAMETER,HEIGHT"),
    }
}

pub fn run(args: Args) -> Result<()> {
    args.shape.fit_in_mm()?;
    let net = args.weld.network(&args.network)?.network;
    let opts = solid::Options {
        cell: args.cell,
        tolerance: (!args.full).then(|| args.tolerance.flatten().unwrap_or(0.25 * args.cell)),
        shape: args.shape.shape(args.supports.options()?)?,
    };
    let made = solid::run(&net, &opts, &Bar::new())
        .with_context(|| format!("{}", args.network.display()))?;
    for n in &made.notes {
        errln!("lamina: {n}");
    }
    write_mesh(&made.mesh, &args.output, 1024)?;
    if let Some(path) = &args.report {
        write_json(path, &made.report)?;
    }
    let r = &made.report.solid;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(r)?);
    } else {
        let size = [0, 1, 2].map(|a| r.bbox_max[a] - r.bbox_min[a]);
        outln!(
            "wrote {}: {} triangles, {} vertices, closed 2-manifold, {} part(s), genus {}",
            args.output.display(),
            r.triangles,
            r.vertices,
            r.parts,
            r.genus
        );
        let marched = if r.march_cell_mm != r.cell_mm {
            format!(" (marched at {} mm)", lamina::text::num(r.march_cell_mm))
        } else {
            String::new()
        };
        outln!(
            "  {:.1} × {:.1} × {:.1} mm, volume {:.1} mm³ ({:.3} mL), cell {} mm{marched}, scale \
             {:.4}",
            size[0],
            size[1],
            size[2],
            r.volume_mm3,
            r.volume_mm3 / 1000.0,
            r.cell_mm,
            r.scale
        );
        outln!(
            "  network: {} cycle(s), {} part(s); vein radius {:.4}..{:.4} mm",
            r.network_cycles,
            r.network_parts,
            r.min_radius,
            r.max_radius
        );
        if let Some(s) = &r.simplified {
            outln!(
                "  within {} mm of the exact surface: {} triangles as marched, {:.1}× fewer; {} \
                 cell(s) split where veins come closer than the grid resolves",
                s.tolerance_mm,
                s.marched,
                s.marched as f64 / r.triangles.max(1) as f64,
                s.cells_split
            );
        }
    }
    for w in &made.warnings {
        errln!("lamina: warning: {w}");
    }
    Ok(())
}
