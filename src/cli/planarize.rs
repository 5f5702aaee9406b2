//! `lamina planarize` and `lamina audit`: node axes that make every panel planar, and a check of
//! panels made elsewhere; both write the planarity report.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use clap::{Args as ClapArgs, ValueEnum};
use glam::DVec3;
use serde_json::json;

use lamina::files::write_atomic;
use lamina::rationalize::audit::read_panels;
use lamina::rationalize::axes::{write_axes, write_panels_obj};
use lamina::rationalize::planarize::{Method, Selector};
use lamina::rationalize::tolerance::Rules;
use lamina::report::planarity::{Metric, Report};
use lamina::stage::{audit, planarize};
use lamina::TriMesh;

use super::input::ReadArgs;
use super::progress::Bar;

#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    /// L-BFGS (argmin) on the same objective: no factorisation, but iterations that grow with
    /// the network
    Lbfgs,
    /// Gokmen's iterative projection (equal pulls per panel, Anderson-accelerated;
    /// --plain-projection for the published sweep)
    Projection,
    /// Gauss-Newton with a sparse Cholesky solve: iterations that do not grow with the network,
    /// and the largest α that holds the tolerance kept
    Newton,
}

#[derive(ClapArgs)]
pub struct Args {
    /// The network (.json .obj .dxf)
    pub input: PathBuf,
    /// Guide surface (.obj .stl): reference directions are its normals at the nodes
    #[arg(long)]
    pub surface: Option<PathBuf>,
    /// How the axes are solved for
    #[arg(long, value_enum, default_value = "newton")]
    pub method: MethodArg,
    /// Panel height at every node, mm
    #[arg(long, default_value_t = 100.0)]
    pub height: f64,
    /// Heights from the node radii times this factor, instead of --height
    #[arg(long, value_name = "FACTOR")]
    pub height_from_radius: Option<f64>,
    /// Largest panel deviation accepted, mm
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f64,
    /// Weight of closeness to the reference directions (lowered as needed to reach the tolerance)
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// Projection method: how far axes move toward their projections each iteration
    #[arg(long, default_value_t = 0.5)]
    pub step: f64,
    /// Projection method: the sweep as published (toward the mean of the projections, no
    /// Anderson acceleration); slower, and lands on a different planar configuration
    #[arg(long)]
    pub plain_projection: bool,
    /// Iteration cap over all rounds
    #[arg(long, default_value_t = 10_000)]
    pub max_iterations: usize,
    /// Panels of edges whose ends both match SELECTOR lie in planes with normal X,Y,Z (repeat);
    /// SELECTOR: all, node=N, or x|y|z with < <= > >= and a number, e.g. 'z<50:0,0,1'
    #[arg(long, value_name = "SELECTOR:X,Y,Z")]
    pub fix_normal: Vec<String>,
    /// Nodes matching SELECTOR keep the axis X,Y,Z (repeat), e.g. 'node=0:0,0,1'
    #[arg(long, value_name = "SELECTOR:X,Y,Z")]
    pub fix_axis: Vec<String>,
    /// Record the solve's time in the report (without it the same inputs give the same report,
    /// byte for byte)
    #[arg(long)]
    pub timings: bool,
    /// The axes file (lamina-axes JSON: positions, axes, heights, edges)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write the panels as OBJ quads
    #[arg(long)]
    pub panels: Option<PathBuf>,
    #[command(flatten)]
    pub reports: ReportArgs,
    #[command(flatten)]
    pub weld: ReadArgs,
}

/// Where the planarity report goes, for `planarize` and `audit` alike.
#[derive(ClapArgs)]
pub struct ReportArgs {
    /// Write the planarity report as JSON
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Write the planarity report as one HTML page
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

impl ReportArgs {
    fn write(&self, report: &Report) -> Result<()> {
        if let Some(p) = &self.report {
            let text = report.json();
            write_atomic(p, |w| std::io::Write::write_all(w, text.as_bytes()))?;
        }
        if let Some(p) = &self.html {
            let text = report.html();
            write_atomic(p, |w| std::io::Write::write_all(w, text.as_bytes()))?;
        }
        Ok(())
    }
}

fn parse_override(s: &str, what: &str) -> Result<(Selector, DVec3)> {
    let Some((sel, dir)) = s.rsplit_once(':') else {
        bail!("{what} \"{s}\": expected SELECTOR:X,Y,Z");
    };
    let sel = Selector::parse(sel).map_err(|e| anyhow::anyhow!("{what} \"{s}\": {e}"))?;
    let v: Vec<f64> = dir
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("{what} \"{s}\": \"{dir}\" is not X,Y,Z"))?;
    let [x, y, z] = v[..] else {
        bail!("{what} \"{s}\": \"{dir}\" is not X,Y,Z");
    };
    Ok((sel, DVec3::new(x, y, z)))
}

/// The stage's options from the flags.
pub fn options(args: &Args) -> Result<planarize::Options> {
    Ok(planarize::Options {
        method: match args.method {
            MethodArg::Lbfgs => Method::Lbfgs,
            MethodArg::Projection => Method::Projection,
            MethodArg::Newton => Method::Newton,
        },
        height: args.height,
        height_from_radius: args.height_from_radius,
        tolerance: args.tolerance,
        alpha: args.alpha,
        step: args.step,
        plain_projection: args.plain_projection,
        max_iterations: args.max_iterations,
        fix_normal: args
            .fix_normal
            .iter()
            .map(|s| parse_override(s, "--fix-normal"))
            .collect::<Result<_>>()?,
        fix_axis: args
            .fix_axis
            .iter()
            .map(|s| parse_override(s, "--fix-axis"))
            .collect::<Result<_>>()?,
        name: lamina::files::file_name(&args.input),
        timings: args.timings,
    })
}

/// Reads the network and the guide surface, solves, writes every output asked for.
pub fn execute(args: &Args) -> Result<planarize::Planarized> {
    let opts = options(args)?;
    let net = args.weld.network(&args.input)?.network;
    let surface = read_surface(args.surface.as_deref())?;
    let solved = planarize::run(&net, surface.as_ref(), &opts, &Bar::new())
        .with_context(|| args.input.display().to_string())?;
    write_axes(
        &solved.axes,
        &serde_json::to_value(&solved.summary)?,
        &args.output,
    )?;
    if let Some(p) = &args.panels {
        write_panels_obj(&solved.axes.quads(), p)?;
    }
    args.reports.write(&solved.report)?;
    Ok(solved)
}

/// A guide surface, if given, with its path in any error.
pub fn read_surface(path: Option<&Path>) -> Result<Option<TriMesh>> {
    let Some(path) = path else { return Ok(None) };
    let mesh = super::input::mesh_file(path)?;
    if mesh.triangles.is_empty() {
        bail!("--surface {}: has no triangles", path.display());
    }
    Ok(Some(mesh))
}

pub fn run(args: Args) -> Result<bool> {
    let solved = execute(&args)?;
    let sol = &solved.solution;
    if args.reports.json {
        outln!(
            "{}",
            json!({ "output": args.output, "summary": solved.summary, "seconds": solved.seconds })
        );
    } else {
        outln!(
            "{} {}: max panel deviation {:.6} mm (tolerance {} mm) after {} iterations, α {}{}",
            if sol.converged {
                "planar:"
            } else {
                "NOT within tolerance:"
            },
            args.output.display(),
            sol.max_deviation,
            sol.tolerance,
            sol.iterations,
            lamina::text::sig3(sol.alpha_used),
            if sol.alpha_used < sol.alpha_requested {
                format!(
                    " (lowered from {} to reach the tolerance)",
                    lamina::text::num(sol.alpha_requested)
                )
            } else {
                String::new()
            }
        );
        for n in &solved.notes {
            outln!("  {n}");
        }
    }
    Ok(sol.converged)
}

#[derive(ClapArgs)]
pub struct AuditArgs {
    /// Panels: .obj faces (quads and n-gons, with their groups), .dxf 3DFACE / polyface meshes /
    /// MESH / closed polylines (with their layers), or a lamina axes or plates .json
    pub input: PathBuf,
    /// Largest figure accepted, mm (with --tolerance-rules: for the panels no rule matches)
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Tolerance classes (JSON) by DXF layer, OBJ or assembly group and panel size, absolute or
    /// relative to the size: the first rule a panel matches gives its tolerance
    #[arg(long, value_name = "RULES.json")]
    pub tolerance_rules: Option<PathBuf>,
    /// The figure held to the tolerance: ISO 1101 minimum-zone flatness, the largest distance
    /// from the least-squares plane, or the corner's distance from the plane of the other three
    #[arg(long, value_enum, default_value_t = Metric::Flatness)]
    pub metric: Metric,
    /// One row per panel (id, name, layer, group, corners, every figure, class, tolerance,
    /// pass/fail) for quality records
    #[arg(long)]
    pub csv: Option<PathBuf>,
    #[command(flatten)]
    pub reports: ReportArgs,
}

/// Ok(true) when every panel is within its tolerance.
pub fn audit_run(args: AuditArgs) -> Result<bool> {
    let report = audit_execute(&args)?;
    let source = args.input.display().to_string();
    let s = &report.summary;
    if args.reports.json {
        outln!("{}", serde_json::to_string(s)?);
    } else {
        let figure = |v: f64| {
            if v.is_nan() {
                "none".to_string()
            } else {
                format!("{v:.9}")
            }
        };
        outln!(
            "{source}: {} panels, max {} {} mm (flatness {}, best fit {}, corner {}), {} above {}",
            s.panels,
            s.metric.name(),
            figure(s.max_deviation),
            figure(s.max_flatness),
            figure(s.max_best_fit),
            figure(s.max_corner),
            s.above_tolerance,
            match (s.tolerance, s.classes.is_empty()) {
                (Some(t), true) => format!("{t} mm"),
                _ => format!("their class's tolerance ({} classes)", s.classes.len()),
            }
        );
    }
    Ok(s.within_tolerance)
}

/// Reads the panels, audits them and writes the asked-for files (CSV, report, page); the
/// report.
pub fn audit_execute(args: &AuditArgs) -> Result<Report> {
    let rules = match &args.tolerance_rules {
        Some(path) => Some(Rules::read(path)?),
        None => None,
    };
    let opts = audit::Options {
        tolerance: args.tolerance,
        tolerance_rules: rules,
        rules_name: args
            .tolerance_rules
            .as_ref()
            .map_or_else(|| "the rules".to_string(), |p| p.display().to_string()),
        metric: args.metric,
        name: lamina::files::file_name(&args.input),
    };
    let read = read_panels(&args.input)?;
    let source = args.input.display().to_string();
    for note in &read.notes {
        errln!("lamina: {source}: {note}");
    }
    let done = audit::run(read, &opts).map_err(|e| match e {
        audit::Error::Option(o) => anyhow::Error::new(o),
        e => anyhow::anyhow!("{source}: {e}"),
    })?;
    for n in &done.notes {
        errln!("lamina: {n}");
    }
    let report = &done.report;
    if let Some(path) = &args.csv {
        let text = audit::csv(report);
        write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    }
    args.reports.write(report)?;
    Ok(done.report)
}
