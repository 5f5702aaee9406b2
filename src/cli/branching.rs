//! What `lamina lsystem` and `lamina bifurcate` share: Murray widths, fitting to a façade
//! boundary, standing up, projecting onto a surface, and writing the network, renders and
//! report.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use glam::{DVec2, DVec3};
use serde_json::Value;

use super::surface::read_surface;
use super::venation::write_json;
use lamina::grow::outline::Outline;
use lamina::grow::outline_file::read_polygon;
use lamina::mesh::io::network_strokes as strokes;
use lamina::mesh::io::write_png_with_strokes;
use lamina::mesh::TriMesh;
use lamina::network::io::{write_network, RenderOptions};
use lamina::network::Network;
use lamina::stage::branching::{rect, Fit, Shape};

#[derive(ClapArgs)]
pub struct WidthArgs {
    /// Widths by Murray's law with this exponent instead of by depth (tips take --tip-radius)
    #[arg(long, value_name = "N")]
    pub murray: Option<f64>,
    /// Tip radius for --murray, mm [default: the depth radius ÷ 8]
    #[arg(long, value_name = "MM", requires = "murray")]
    pub tip_radius: Option<f64>,
}

#[derive(ClapArgs)]
pub struct FacadeArgs {
    /// Fit the tree to a façade boundary: a closed polygon in a file (.json .obj .dxf .svg, the
    /// largest loop) or `rect:W,H` (mm, base centred on the origin)
    #[arg(long, value_name = "FILE|rect:W,H")]
    pub boundary: Option<String>,
    /// Where the tree's root goes on the boundary [default: the middle of its lowest points]
    #[arg(
        long,
        value_name = "X,Y",
        requires = "boundary",
        allow_hyphen_values = true
    )]
    pub root_at: Option<String>,
    /// Size the tree: `cover` (smallest scale that spans the boundary from the root),
    /// `contain` (largest that stays inside), or a scale factor
    #[arg(long, default_value = "cover", requires = "boundary")]
    pub fit: String,
    /// Leave out the frame (the boundary as members, split where branches meet it)
    #[arg(long, requires = "boundary")]
    pub no_frame: bool,
    /// Radius of the frame members, mm [default: the trunk's]
    #[arg(long, value_name = "MM", requires = "boundary")]
    pub frame_radius: Option<f64>,
    /// Stand the drawing up: its +Y becomes +Z (after fitting, before projecting)
    #[arg(long)]
    pub upright: bool,
    /// Project the result onto this surface (.obj .stl) along --direction
    #[arg(long, value_name = "MESH")]
    pub onto: Option<PathBuf>,
    #[command(flatten)]
    pub onto_weld: super::surface::SurfaceWeld,
    /// Direction of projection [default: +Z, or +Y with --upright]
    #[arg(
        long,
        value_name = "X,Y,Z",
        requires = "onto",
        allow_hyphen_values = true
    )]
    pub direction: Option<String>,
    /// Split members whose projection bends away from the chord by more than this, mm
    /// [default: 1e-3 of the surface's size]
    #[arg(long, value_name = "MM", requires = "onto")]
    pub sag: Option<f64>,
}

#[derive(ClapArgs)]
pub struct OutputArgs {
    /// Output network (.json .obj .dxf .svg .png)
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write an SVG render
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Also write a PNG render
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Longer side of PNG renders, in pixels
    #[arg(long, default_value_t = 2048)]
    pub size: u32,
    /// Write the report as JSON here
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print the report as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// Numbers separated by commas, exactly `n` of them.
pub fn parse_numbers(option: &str, text: &str, n: usize) -> Result<Vec<f64>> {
    let nums: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .ok()
        .filter(|v: &Vec<f64>| v.len() == n && v.iter().all(|x| x.is_finite()))
        .with_context(|| format!("{option} {text}: expected {n} numbers separated by commas"))?;
    Ok(nums)
}

/// The boundary polygon: `rect:W,H` or a file.
pub fn read_boundary(spec: &str) -> Result<Outline> {
    if let Some(rest) = spec.strip_prefix("rect:") {
        let wh = parse_numbers("--boundary rect:", rest, 2)?;
        return Ok(rect(wh[0], wh[1])?);
    }
    match read_polygon(Path::new(spec), "--boundary") {
        Ok(o) => Ok(o),
        // Errors from the network readers name the file but not the option.
        Err(e @ lamina::grow::outline_file::OutlineFileError::Read(_)) => {
            Err(anyhow::Error::new(e).context("--boundary"))
        }
        Err(e) => Err(e.into()),
    }
}

impl FacadeArgs {
    fn fit_rule(&self) -> Result<Fit> {
        Ok(match self.fit.as_str() {
            "cover" => Fit::Cover,
            "contain" => Fit::Contain,
            s => match s.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Fit::Scale(v),
                _ => bail!("--fit {s}: expected cover, contain or a positive scale factor"),
            },
        })
    }

    /// The stage's shape options from the flags (the boundary and the surface read).
    pub fn shape(&self, widths: &WidthArgs) -> Result<Shape> {
        if self.onto.is_none() {
            self.onto_weld.only_with("--onto")?;
        }
        let onto = match &self.onto {
            Some(mesh_path) => Some(
                read_surface(mesh_path, &self.onto_weld)
                    .map_err(|e| anyhow::anyhow!("{e}"))
                    .with_context(|| format!("--onto {}", mesh_path.display()))?,
            ),
            None => None,
        };
        Ok(Shape {
            murray: widths.murray,
            tip_radius: widths.tip_radius,
            boundary: self.boundary.as_deref().map(read_boundary).transpose()?,
            root_at: self
                .root_at
                .as_deref()
                .map(|t| parse_numbers("--root-at", t, 2).map(|v| DVec2::new(v[0], v[1])))
                .transpose()?,
            fit: Some(self.fit_rule()?),
            no_frame: self.no_frame,
            frame_radius: self.frame_radius,
            upright: self.upright,
            onto,
            direction: self
                .direction
                .as_deref()
                .map(|t| parse_numbers("--direction", t, 3).map(|v| DVec3::new(v[0], v[1], v[2])))
                .transpose()?,
            sag: self.sag,
        })
    }
}

/// Writes the network and the report where asked.
pub fn write(
    net: &Network,
    report: &impl serde::Serialize,
    onto: Option<&TriMesh>,
    out: &OutputArgs,
) -> Result<Value> {
    write_all(net, onto, out)?;
    let report = serde_json::to_value(report)?;
    if let Some(path) = &out.report {
        write_json(path, &report)?;
    }
    Ok(report)
}

/// Prints the report: as JSON with --json, else one line per section and the files written.
pub fn print(report: &Value, out: &OutputArgs) -> Result<()> {
    if out.json {
        outln!("{}", serde_json::to_string_pretty(report)?);
    } else {
        print_summary(report);
        for p in [&out.output, &out.svg, &out.png].into_iter().flatten() {
            outln!("wrote {}", p.display());
        }
    }
    Ok(())
}

/// The network in every format asked for; a PNG of a projected network shows it on its surface.
fn write_all(net: &Network, surface: Option<&TriMesh>, out: &OutputArgs) -> Result<()> {
    let render = RenderOptions { size: out.size };
    let write = |p: &Path| -> Result<()> {
        match surface {
            Some(mesh) if lamina::files::extension(p) == "png" => {
                write_png_with_strokes(mesh, &strokes(net), p, out.size)?
            }
            _ => write_network(net, p, &render)?,
        }
        Ok(())
    };
    if let Some(p) = &out.output {
        write(p)?;
    }
    for (p, ext) in [(&out.svg, "svg"), (&out.png, "png")] {
        if let Some(p) = p {
            if lamina::files::extension(p) != ext {
                bail!("--{ext} {}: expected a .{ext} file", p.display());
            }
            write(p)?;
        }
    }
    Ok(())
}

/// One line per section of the report.
fn print_summary(report: &Value) {
    let Some(map) = report.as_object() else {
        return;
    };
    for (section, v) in map {
        if let Some(fields) = v.as_object() {
            let parts: Vec<String> = fields
                .iter()
                .filter(|(_, x)| !x.is_object() && !x.is_null())
                .map(|(k, x)| format!("{k} {x}"))
                .collect();
            outln!("{section}: {}", parts.join(", "));
        }
    }
}

/// Checks the outputs can be written where asked before any work is done.
pub fn check_outputs(out: &OutputArgs) -> Result<()> {
    if out.output.is_none() && out.svg.is_none() && out.png.is_none() {
        bail!("give -o OUT (.json .obj .dxf .svg .png), --svg or --png");
    }
    if let Some(p) = &out.output {
        let ext = lamina::files::extension(p);
        if !["json", "obj", "dxf", "svg", "png"].contains(&ext.as_str()) {
            bail!(
                "-o {}: the network is written as .json, .obj, .dxf, .svg or .png",
                p.display()
            );
        }
    }
    Ok(())
}
