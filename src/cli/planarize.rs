//! `lamina planarize` and `lamina audit`: node axes that make every panel planar, and a check of
//! panels made elsewhere; both write the planarity report.

use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Result};
use clap::{Args as ClapArgs, ValueEnum};
use glam::DVec3;
use serde_json::json;

use lamina::files::write_atomic;
use lamina::rationalize::audit::{audit, read_polygons};
use lamina::rationalize::axes::{write_axes, write_panels_obj, Axes};
use lamina::rationalize::panels::MAX_FLATNESS_CORNERS;
use lamina::rationalize::planarize::{
    planarize, Input, Method, PlanarizeOptions, Selector, Solution,
};
use lamina::report::planarity::{Context, Metric, PanelRow, Report};

use super::input::{reference_normals, ReadArgs};

#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    Lbfgs,
    Projection,
}

#[derive(ClapArgs)]
pub struct Args {
    /// The network (.json .obj .dxf)
    pub input: PathBuf,
    /// Guide surface (.obj .stl): reference directions are its normals at the nodes
    #[arg(long)]
    pub surface: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "lbfgs")]
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

/// What `planarize` did, for the caller to print.
pub struct Outcome {
    pub solution: Solution,
    pub summary: serde_json::Value,
    pub seconds: f64,
}

/// Solves and writes every output the arguments ask for; prints nothing.
pub fn execute(args: &Args) -> Result<Outcome> {
    let opts = PlanarizeOptions {
        method: match args.method {
            MethodArg::Lbfgs => Method::Lbfgs,
            MethodArg::Projection => Method::Projection,
        },
        alpha: args.alpha,
        tolerance: args.tolerance,
        max_iterations: args.max_iterations,
        step: args.step,
        plain_projection: args.plain_projection,
        fix_normals: args
            .fix_normal
            .iter()
            .map(|s| parse_override(s, "--fix-normal"))
            .collect::<Result<_>>()?,
        fix_axes: args
            .fix_axis
            .iter()
            .map(|s| parse_override(s, "--fix-axis"))
            .collect::<Result<_>>()?,
    };
    let net = args.weld.network(&args.input)?.network;
    let reference = reference_normals(&net, args.surface.as_deref())?;
    let heights: Vec<f64> = match args.height_from_radius {
        Some(f) => net.nodes.iter().map(|n| n.radius * f).collect(),
        None => vec![args.height; net.nodes.len()],
    };
    let input = Input {
        positions: net.nodes.iter().map(|n| n.p).collect(),
        edges: net.edges.iter().map(|e| [e.a, e.b]).collect(),
        reference,
        heights,
    };
    let start = Instant::now();
    let sol = planarize(&input, &opts)?;
    let seconds = start.elapsed().as_secs_f64();
    let axes = Axes::solved(&input, &sol, net.edges.iter().map(|e| e.radius).collect());
    let summary = summary(&sol);
    write_axes(&axes, &summary, &args.output)?;
    let quads = axes.quads();
    if let Some(p) = &args.panels {
        write_panels_obj(&quads, p)?;
    }
    let report = report_of(args, &sol, &quads, seconds);
    args.reports.write(&report)?;
    Ok(Outcome {
        solution: sol,
        summary,
        seconds,
    })
}

pub fn run(args: Args) -> Result<bool> {
    let Outcome {
        solution: sol,
        summary,
        seconds,
    } = execute(&args)?;
    if args.reports.json {
        println!(
            "{}",
            json!({ "output": args.output, "summary": summary, "seconds": seconds })
        );
    } else {
        println!(
            "{} {}: max panel deviation {:.6} mm (tolerance {} mm) after {} iterations, α {:e}{}",
            if sol.converged {
                "planar:"
            } else {
                "NOT within tolerance:"
            },
            args.output.display(),
            sol.max_deviation,
            sol.tolerance,
            sol.iterations,
            sol.alpha_used,
            if sol.alpha_used < sol.alpha_requested {
                format!(
                    " (lowered from {:e} to reach the tolerance)",
                    sol.alpha_requested
                )
            } else {
                String::new()
            }
        );
        for n in notes(&sol) {
            println!("  {n}");
        }
    }
    Ok(sol.converged)
}

fn summary(sol: &Solution) -> serde_json::Value {
    let worst_axis = sol.axis_deviation_deg.iter().copied().fold(0.0, f64::max);
    json!({
        "method": sol.method,
        "converged": sol.converged,
        "max_deviation": sol.max_deviation,
        "tolerance": sol.tolerance,
        "iterations": sol.iterations,
        "alpha_requested": sol.alpha_requested,
        "alpha_used": sol.alpha_used,
        "max_axis_deviation_deg": worst_axis,
        "over_constrained": sol.over_constrained,
        "impossible_normals": sol.impossible_normals,
    })
}

fn notes(sol: &Solution) -> Vec<String> {
    let mut out = Vec::new();
    if !sol.converged {
        out.push(format!(
            "the tolerance of {} mm was NOT reached: the worst panel is {:.6} mm off plane",
            sol.tolerance, sol.max_deviation
        ));
    }
    if !sol.over_constrained.is_empty() {
        out.push(format!(
            "{} node(s) of degree > 3 are over-constrained: {:?}",
            sol.over_constrained.len(),
            sol.over_constrained
        ));
    }
    if !sol.impossible_normals.is_empty() {
        out.push(format!(
            "{} edge(s) are not perpendicular to their fixed normal, so no panel through them can have it: {:?}",
            sol.impossible_normals.len(),
            sol.impossible_normals
        ));
    }
    let worst = sol.axis_deviation_deg.iter().copied().fold(0.0, f64::max);
    out.push(format!(
        "axes moved at most {worst:.3}° from their references"
    ));
    out
}

fn report_of(args: &Args, sol: &Solution, quads: &[[DVec3; 4]], seconds: f64) -> Report {
    let rows = sol
        .panels
        .iter()
        .map(|p| PanelRow {
            index: p.edge,
            nodes: Some([p.a, p.b]),
            metrics: p.metrics,
        })
        .collect();
    Report::new(
        Context {
            title: format!("Planarity of {}", args.input.display()),
            source: args.input.display().to_string(),
            method: Some(
                match sol.method {
                    Method::Lbfgs => "L-BFGS (argmin)",
                    Method::Projection => "iterative projection",
                }
                .into(),
            ),
            iterations: Some(sol.iterations),
            seconds: Some(seconds),
            alpha_requested: Some(sol.alpha_requested),
            alpha_used: Some(sol.alpha_used),
            history: sol.history.clone(),
            notes: notes(sol),
        },
        rows,
        quads.iter().map(|q| q.to_vec()).collect(),
        sol.tolerance,
        // planarize holds each panel's corner figure to the tolerance.
        Metric::Corner,
    )
}

#[derive(ClapArgs)]
pub struct AuditArgs {
    /// Panels: .obj faces (quads and n-gons) or .dxf 3DFACE / polyface meshes / closed polylines
    pub input: PathBuf,
    /// Largest figure accepted, mm
    #[arg(long)]
    pub tolerance: f64,
    /// The figure held to the tolerance: ISO 1101 minimum-zone flatness, the largest distance
    /// from the least-squares plane, or the corner's distance from the plane of the other three
    #[arg(long, value_enum, default_value_t = Metric::Flatness)]
    pub metric: Metric,
    /// One row per panel (id, corners, every figure, tolerance, pass/fail) for quality records
    #[arg(long)]
    pub csv: Option<PathBuf>,
    #[command(flatten)]
    pub reports: ReportArgs,
}

/// Ok(true) when every panel is within the tolerance.
pub fn audit_run(args: AuditArgs) -> Result<bool> {
    if !(args.tolerance.is_finite() && args.tolerance > 0.0) {
        bail!(
            "--tolerance must be a positive distance in mm, got {}",
            args.tolerance
        );
    }
    let read = read_polygons(&args.input)?;
    // Faces of fewer than four distinct corners are planar by construction: counted, not audited.
    let (polygons, skipped): (Vec<_>, Vec<_>) = read
        .into_iter()
        .enumerate()
        .partition(|(_, p)| distinct_corners(p) >= 4);
    if !skipped.is_empty() {
        eprintln!(
            "lamina: {} of {} faces have fewer than 4 distinct corners (planar by construction): skipped",
            skipped.len(),
            skipped.len() + polygons.len()
        );
    }
    if polygons.is_empty() {
        bail!(
            "{}: no face has 4 or more distinct corners: nothing to audit",
            args.input.display()
        );
    }
    let ids: Vec<usize> = polygons.iter().map(|(k, _)| *k).collect();
    let polygons: Vec<Vec<DVec3>> = polygons.into_iter().map(|(_, p)| p).collect();
    let audited = audit(&polygons);
    let too_many = audited
        .iter()
        .filter(|a| a.metrics.flatness.is_nan())
        .count();
    if too_many > 0 {
        if args.metric == Metric::Flatness {
            bail!(
                "{}: {too_many} faces have more than {MAX_FLATNESS_CORNERS} corners, beyond the exact flatness search: give --metric best-fit",
                args.input.display()
            );
        }
        eprintln!(
            "lamina: {too_many} faces have more than {MAX_FLATNESS_CORNERS} corners: no flatness for them (NaN)"
        );
    }
    let rows: Vec<PanelRow> = audited
        .iter()
        .zip(&ids)
        .map(|(a, &k)| PanelRow {
            index: k,
            nodes: None,
            metrics: a.metrics,
        })
        .collect();
    if let Some(path) = &args.csv {
        write_atomic(path, |w| {
            writeln!(
                w,
                "panel,corners,flatness_mm,best_fit_mm,corner_mm,diagonal_distance_mm,warp,torsion_deg,normal_x,normal_y,normal_z,metric,tolerance_mm,pass"
            )?;
            for (r, p) in rows.iter().zip(&polygons) {
                let m = &r.metrics;
                writeln!(
                    w,
                    "{},{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{},{},{}",
                    r.index,
                    p.len(),
                    m.flatness,
                    m.best_fit,
                    m.deviation,
                    m.diagonal_distance,
                    m.diagonal_rel_diagonal,
                    m.torsion_deg,
                    m.normal[0],
                    m.normal[1],
                    m.normal[2],
                    args.metric.name(),
                    args.tolerance,
                    if args.metric.of(m) <= args.tolerance {
                        "pass"
                    } else {
                        "fail"
                    }
                )?;
            }
            Ok(())
        })?;
    }
    let report = Report::new(
        Context {
            title: format!("Planarity audit of {}", args.input.display()),
            source: args.input.display().to_string(),
            notes: [
                (!skipped.is_empty()).then(|| format!(
                    "{} faces of fewer than 4 distinct corners skipped (planar by construction).",
                    skipped.len()
                )),
                (too_many > 0).then(|| format!(
                    "{too_many} faces of more than {MAX_FLATNESS_CORNERS} corners have no flatness; the largest flatness is of the others."
                )),
            ]
            .into_iter()
            .flatten()
            .collect(),
            ..Default::default()
        },
        rows,
        polygons,
        args.tolerance,
        args.metric,
    );
    args.reports.write(&report)?;
    let s = &report.summary;
    if args.reports.json {
        println!("{}", serde_json::to_string(s)?);
    } else {
        println!(
            "{}: {} panels, max {} {:.9} mm (flatness {:.9}, best fit {:.9}, corner {:.9}), {} above {} mm",
            args.input.display(),
            s.panels,
            s.metric.name(),
            s.max_deviation,
            s.max_flatness,
            s.max_best_fit,
            s.max_corner,
            s.above_tolerance,
            s.tolerance
        );
    }
    Ok(s.within_tolerance)
}

/// Corners more than 1e-9 of the polygon's size apart from every earlier one.
fn distinct_corners(p: &[DVec3]) -> usize {
    let size = p.iter().map(|q| q.distance(p[0])).fold(0.0, f64::max);
    let eps = 1e-9 * size.max(f64::MIN_POSITIVE);
    (0..p.len())
        .filter(|&i| p[..i].iter().all(|q| q.distance(p[i]) > eps))
        .count()
}
