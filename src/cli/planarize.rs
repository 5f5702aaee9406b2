//! `lamina planarize` and `lamina audit`: node axes that make every panel planar, and a check of
//! panels made elsewhere; both write the planarity report.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Result};
use clap::{Args as ClapArgs, ValueEnum};
use glam::DVec3;
use indicatif::ProgressStyle;
use serde_json::json;

use lamina::files::write_atomic;
use lamina::rationalize::audit::{audit, read_panels, Panel};
use lamina::rationalize::axes::{write_axes, write_panels_obj, Axes};
use lamina::rationalize::panels::MAX_FLATNESS_CORNERS;
use lamina::rationalize::planarize::{
    planarize_with, Input, Method, PlanarizeOptions, Selector, Solution,
};
use lamina::rationalize::tolerance::{Allowance, Judged, Rule, Rules};
use lamina::report::planarity::{Context, Metric, PanelRow, Report};
use lamina::Network;

use super::input::{reference_normals, ReadArgs};

#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    Lbfgs,
    Projection,
    /// Gauss-Newton with a sparse Cholesky solve: iterations that do not grow with the network
    Newton,
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

/// A solved network, in memory: what `planarize` writes, before it is written.
pub struct Solved {
    pub solution: Solution,
    pub axes: Axes,
    /// The axes file's summary.
    pub summary: serde_json::Value,
    pub report: Report,
    pub seconds: f64,
}

/// The solver's options from the flags.
fn options(args: &Args) -> Result<PlanarizeOptions> {
    Ok(PlanarizeOptions {
        method: match args.method {
            MethodArg::Lbfgs => Method::Lbfgs,
            MethodArg::Projection => Method::Projection,
            MethodArg::Newton => Method::Newton,
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
    })
}

/// Solves `net` (read from `args.input`, or handed over by the Python package) as the flags
/// say; writes nothing. A spinner shows the rounds (hidden when stderr is not a terminal).
pub fn solve(args: &Args, net: &Network) -> Result<Solved> {
    let opts = options(args)?;
    let reference = reference_normals(net, args.surface.as_deref())?;
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
    let bar = super::progress::bar("node axes", None);
    bar.set_style(
        ProgressStyle::with_template("{spinner} node axes, {msg} {elapsed}").expect("template"),
    );
    bar.set_message(format!(
        "{} nodes, α {:.1e}",
        input.positions.len(),
        opts.alpha
    ));
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    let sol = planarize_with(&input, &opts, &|r| {
        bar.set_message(format!(
            "{} iterations, α {:.1e}: max deviation {:.4} mm",
            r.iterations, r.alpha, r.max_deviation
        ))
    });
    bar.finish_and_clear();
    let sol = sol?;
    let seconds = start.elapsed().as_secs_f64();
    let axes = Axes::solved(&input, &sol, net.edges.iter().map(|e| e.radius).collect());
    let summary = summary(&sol);
    let report = report_of(args, &sol, &axes.quads(), seconds);
    Ok(Solved {
        solution: sol,
        axes,
        summary,
        report,
        seconds,
    })
}

/// Solves and writes every output the arguments ask for; prints nothing.
pub fn execute(args: &Args) -> Result<Outcome> {
    options(args)?;
    let net = args.weld.network(&args.input)?.network;
    let solved = solve(args, &net)?;
    write_axes(&solved.axes, &solved.summary, &args.output)?;
    if let Some(p) = &args.panels {
        write_panels_obj(&solved.axes.quads(), p)?;
    }
    args.reports.write(&solved.report)?;
    Ok(Outcome {
        solution: solved.solution,
        summary: solved.summary,
        seconds: solved.seconds,
    })
}

pub fn run(args: Args) -> Result<bool> {
    let Outcome {
        solution: sol,
        summary,
        seconds,
    } = execute(&args)?;
    if args.reports.json {
        outln!(
            "{}",
            json!({ "output": args.output, "summary": summary, "seconds": seconds })
        );
    } else {
        outln!(
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
            outln!("  {n}");
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
            tolerance: sol.tolerance,
            metrics: p.metrics,
            ..Default::default()
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
                    Method::Newton => "Gauss-Newton (sparse Cholesky)",
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
        Some(sol.tolerance),
        Vec::new(),
        // planarize holds each panel's corner figure to the tolerance.
        Metric::Corner,
    )
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

/// The tolerance classes the arguments give: the rule file's, with --tolerance as the default.
fn audit_rules(args: &AuditArgs) -> Result<Rules> {
    if let Some(t) = args.tolerance {
        if !(t.is_finite() && t > 0.0) {
            bail!("--tolerance must be a positive distance in mm, got {t}");
        }
    }
    let mut rules = match &args.tolerance_rules {
        Some(path) => Rules::read(path)?,
        None => Rules::default(),
    };
    match (args.tolerance, rules.default) {
        (Some(_), Some(_)) => bail!(
            "{} gives a default tolerance and so does --tolerance: give it in one place",
            args.tolerance_rules
                .as_deref()
                .unwrap_or(Path::new(""))
                .display()
        ),
        (Some(t), None) => rules.default = Some(Allowance::absolute(t)),
        (None, None) if args.tolerance_rules.is_none() => {
            bail!("give the tolerance: --tolerance MM, or --tolerance-rules RULES.json")
        }
        _ => {}
    }
    Ok(rules)
}

/// Ok(true) when every panel is within its tolerance.
pub fn audit_run(args: AuditArgs) -> Result<bool> {
    let rules = audit_rules(&args)?;
    let read = read_panels(&args.input)?;
    let source = args.input.display().to_string();
    for note in &read.notes {
        errln!("lamina: {source}: {note}");
    }
    // Faces of fewer than four distinct corners are planar by construction: counted, not audited.
    let total = read.panels.len();
    let (ids, panels): (Vec<usize>, Vec<Panel>) = read
        .panels
        .into_iter()
        .enumerate()
        .filter(|(_, p)| distinct_corners(&p.corners) >= 4)
        .unzip();
    let skipped = total - panels.len();
    if skipped > 0 {
        errln!(
            "lamina: {skipped} of {total} faces have fewer than 4 distinct corners (planar by construction): skipped"
        );
    }
    if panels.is_empty() {
        bail!(
            "{source}: no face has 4 or more distinct corners: nothing to audit (a triangulated \
             export, as from STL or trimesh, has lost its panels: export quads or n-gons)"
        );
    }
    let judged = judge(&args, &rules, &ids, &panels)?;
    let metrics = audit(&panels);
    let too_many = metrics.iter().filter(|m| m.flatness.is_nan()).count();
    if too_many > 0 {
        if args.metric == Metric::Flatness {
            bail!(
                "{source}: {too_many} faces have more than {MAX_FLATNESS_CORNERS} corners, beyond the exact flatness search: give --metric best-fit"
            );
        }
        errln!(
            "lamina: {too_many} faces have more than {MAX_FLATNESS_CORNERS} corners: no flatness for them (NaN)"
        );
    }
    let (rows, corners): (Vec<PanelRow>, Vec<Vec<DVec3>>) = panels
        .into_iter()
        .zip(metrics)
        .zip(&ids)
        .zip(&judged)
        .map(|(((p, metrics), &index), j)| {
            let row = PanelRow {
                index,
                nodes: p.nodes,
                name: p.name,
                layer: p.layer,
                group: p.group,
                tolerance: j.tolerance,
                class: args
                    .tolerance_rules
                    .is_some()
                    .then(|| j.rule.unwrap_or(rules.rules.len())),
                metrics,
                ..Default::default()
            };
            (row, p.corners)
        })
        .unzip();
    let classes: Vec<(String, String)> = if args.tolerance_rules.is_some() {
        rules
            .rules
            .iter()
            .map(|r| (r.name.clone(), describe_rule(r)))
            .chain(rules.default.map(|d| {
                (
                    "default".to_string(),
                    format!("any other panel: {}", d.describe()),
                )
            }))
            .collect()
    } else {
        Vec::new()
    };
    let report = Report::new(
        Context {
            title: format!("Planarity audit of {source}"),
            source: source.clone(),
            notes: read
                .notes
                .iter()
                .cloned()
                .chain((skipped > 0).then(|| format!(
                    "{skipped} faces of fewer than 4 distinct corners skipped (planar by construction)."
                )))
                .chain((too_many > 0).then(|| format!(
                    "{too_many} faces of more than {MAX_FLATNESS_CORNERS} corners have no flatness; the largest flatness is of the others."
                )))
                .chain(args.tolerance_rules.as_ref().map(|p| format!(
                    "Tolerances from {}: the first rule a panel matches gives its tolerance; size is the panel's largest corner-to-corner distance.",
                    p.display()
                )))
                .collect(),
            ..Default::default()
        },
        rows,
        corners,
        rules.default.filter(|d| d.relative == 0.0).map(|d| d.mm),
        classes,
        args.metric,
    );
    for c in &report.summary.classes {
        if c.panels == 0 {
            errln!(
                "lamina: tolerance class \"{}\" ({}) matches no panel",
                c.name,
                c.rule
            );
        }
    }
    if let Some(path) = &args.csv {
        write_audit_csv(path, &report, args.metric)?;
    }
    args.reports.write(&report)?;
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

/// Each panel's tolerance; an error for a panel no rule matches when there is no default.
fn judge(args: &AuditArgs, rules: &Rules, ids: &[usize], panels: &[Panel]) -> Result<Vec<Judged>> {
    panels
        .iter()
        .zip(ids)
        .map(|(p, id)| {
            rules.judge(p).ok_or_else(|| {
                let label: Vec<String> = [("name", &p.name), ("layer", &p.layer), ("group", &p.group)]
                    .into_iter()
                    .filter_map(|(k, v)| v.as_ref().map(|v| format!("{k} \"{v}\"")))
                    .collect();
                anyhow::anyhow!(
                    "{}: panel {id} ({}) matches no rule of {} and there is no default: add \"default\" to the rules or give --tolerance",
                    args.input.display(),
                    if label.is_empty() { "no name, layer or group".into() } else { label.join(", ") },
                    args.tolerance_rules.as_deref().unwrap_or(Path::new("")).display()
                )
            })
        })
        .collect()
}

/// What a rule matches and allows, in words.
fn describe_rule(r: &Rule) -> String {
    let mut what = Vec::new();
    if let Some(l) = &r.layer {
        what.push(format!("layer {l}"));
    }
    if let Some(g) = &r.group {
        what.push(format!("group {g}"));
    }
    if let Some(s) = r.min_size {
        what.push(format!("size ≥ {s} mm"));
    }
    if let Some(s) = r.max_size {
        what.push(format!("size ≤ {s} mm"));
    }
    if what.is_empty() {
        what.push("every panel".into());
    }
    format!("{}: {}", what.join(", "), r.allowance().describe())
}

/// One row per panel: id, labels, every figure, class, tolerance and verdict. Rows are
/// formatted in blocks on every core and written in order.
fn write_audit_csv(path: &Path, report: &Report, metric: Metric) -> Result<()> {
    use rayon::prelude::*;
    // Names are quoted as CSV asks when they hold a comma, quote or line break.
    let field = |v: &Option<String>| match v {
        None => String::new(),
        Some(v) if v.contains([',', '"', '\n', '\r']) => format!("\"{}\"", v.replace('"', "\"\"")),
        Some(v) => v.clone(),
    };
    let row = |(r, p): (&PanelRow, &Vec<DVec3>)| {
        let m = &r.metrics;
        format!(
            "{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{},{},{},{}\n",
            r.index,
            field(&r.name),
            field(&r.layer),
            field(&r.group),
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
            metric.name(),
            field(&r.class_name),
            r.tolerance,
            if r.pass { "pass" } else { "fail" }
        )
    };
    let blocks: Vec<String> = report
        .panels
        .par_chunks(4096)
        .zip(report.quads.par_chunks(4096))
        .map(|(rows, quads)| rows.iter().zip(quads).map(row).collect())
        .collect();
    write_atomic(path, |w| {
        writeln!(
            w,
            "panel,name,layer,group,corners,flatness_mm,best_fit_mm,corner_mm,diagonal_distance_mm,warp,torsion_deg,normal_x,normal_y,normal_z,metric,class,tolerance_mm,pass"
        )?;
        for b in &blocks {
            w.write_all(b.as_bytes())?;
        }
        Ok(())
    })?;
    Ok(())
}

/// Corners more than 1e-9 of the polygon's size apart from every earlier one.
fn distinct_corners(p: &[DVec3]) -> usize {
    let size = p.iter().map(|q| q.distance(p[0])).fold(0.0, f64::max);
    let eps = 1e-9 * size.max(f64::MIN_POSITIVE);
    (0..p.len())
        .filter(|&i| p[..i].iter().all(|q| q.distance(p[i]) > eps))
        .count()
}
