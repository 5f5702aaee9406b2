//! `planarize`: node axes that make every edge's panel planar (torsion-free nodes), with the
//! axes file's summary and the planarity report.
//!
//! ```
//! use lamina::stage::{planarize, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/calyx_veins.json"))?;
//! let opts = planarize::Options { method: planarize::Method::Newton, ..Default::default() };
//! let solved = planarize::run(&net, None, &opts, &Quiet)?;
//! assert!(solved.solution.converged);
//! assert!(solved.report.summary.max_deviation <= opts.tolerance);
//! # Ok(()) }
//! ```

use std::time::Instant;

use glam::DVec3;
use serde::Serialize;

use crate::network::Problem;
use crate::rationalize::axes::Axes;
use crate::rationalize::planarize::{planarize_with, Input, PlanarizeError, PlanarizeOptions};
pub use crate::rationalize::planarize::{Method, Selector, Solution};
use crate::rationalize::reference::{reference_normals, ReferenceError};
use crate::report::planarity::{Context, Metric, PanelRow, Report};
use crate::stage::{OptionError, Progress};
use crate::{Network, TriMesh};

/// How to solve. `Default` is the command's defaults.
#[derive(Clone, Debug)]
pub struct Options {
    /// The solver. Default: L-BFGS.
    pub method: Method,
    /// Panel height at every node, mm. Default 100.
    pub height: f64,
    /// Heights from the node radii times this factor instead of `height`. Default: none.
    pub height_from_radius: Option<f64>,
    /// Largest panel deviation accepted, mm. Default 0.01.
    pub tolerance: f64,
    /// Weight of closeness to the reference directions, lowered as needed to reach the
    /// tolerance. Default 0.01.
    pub alpha: f64,
    /// Projection method: how far axes move toward their projections each iteration. Default
    /// 0.5.
    pub step: f64,
    /// Projection method: the sweep as published (no acceleration). Default false.
    pub plain_projection: bool,
    /// Iteration cap over all rounds. Default 10,000.
    pub max_iterations: usize,
    /// Panels of edges whose ends both match the selector lie in planes with this normal.
    pub fix_normal: Vec<(Selector, DVec3)>,
    /// Nodes matching the selector keep this axis.
    pub fix_axis: Vec<(Selector, DVec3)>,
    /// The network's name in the report's title. Default "network".
    pub name: String,
    /// Record the solve's time in the report. Default false: the same inputs give the same
    /// report, byte for byte (the time is always in [`Planarized::seconds`]).
    pub timings: bool,
}

impl Default for Options {
    fn default() -> Self {
        let solver = PlanarizeOptions::default();
        Options {
            method: solver.method,
            height: 100.0,
            height_from_radius: None,
            tolerance: solver.tolerance,
            alpha: solver.alpha,
            step: solver.step,
            plain_projection: solver.plain_projection,
            max_iterations: solver.max_iterations,
            fix_normal: Vec::new(),
            fix_axis: Vec::new(),
            name: "network".into(),
            timings: false,
        }
    }
}

/// The figures the axes file keeps beside the axes (`summary`).
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// The α asked for.
    pub alpha_requested: f64,
    /// The α the solve kept.
    pub alpha_used: f64,
    /// Whether the rounds settled before the cap.
    pub converged: bool,
    /// Edges not perpendicular to their fixed normal.
    pub impossible_normals: Vec<usize>,
    /// Growth steps (or solver iterations) taken.
    pub iterations: usize,
    /// Largest turn of an axis from its reference, degrees.
    pub max_axis_deviation_deg: f64,
    /// Largest panel deviation, mm.
    pub max_deviation: f64,
    /// The solver.
    pub method: Method,
    /// Nodes of degree > 3.
    pub over_constrained: Vec<u32>,
    /// Tolerance, mm.
    pub tolerance: f64,
}

/// A solved network: what `planarize` writes, before it is written.
#[derive(Clone, Debug)]
pub struct Planarized {
    /// The solver's solution.
    pub solution: Solution,
    /// Local axes.
    pub axes: Axes,
    /// The axes file's summary.
    pub summary: Summary,
    /// The planarity report (`--report`, `--html`).
    pub report: Report,
    /// What the solve says in words: tolerance missed, over-constrained nodes, how far axes
    /// turned.
    pub notes: Vec<String>,
    /// Wall time of the solve, s.
    pub seconds: f64,
}

/// Why no axes were found.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(transparent)]
    /// No reference directions.
    Reference(#[from] ReferenceError),
    #[error(transparent)]
    /// The solver failed.
    Solve(#[from] PlanarizeError),
    #[error("{0}: a member drawn twice, or from a node to itself, has no panel of its own")]
    /// An edge repeating another, or a loop.
    Member(Problem),
}

impl Error {
    /// Whether the caller stopped the solve.
    pub fn is_cancelled(&self) -> bool {
        matches!(self, Error::Solve(PlanarizeError::Cancelled(_)))
    }
}

impl Options {
    fn solver(&self) -> PlanarizeOptions {
        PlanarizeOptions {
            method: self.method,
            alpha: self.alpha,
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            step: self.step,
            plain_projection: self.plain_projection,
            fix_normals: self.fix_normal.clone(),
            fix_axes: self.fix_axis.clone(),
        }
    }

    fn heights(&self, net: &Network) -> Result<Vec<f64>, OptionError> {
        Ok(match self.height_from_radius {
            Some(f) => {
                if !(f.is_finite() && f > 0.0) {
                    return Err(OptionError::new(
                        "height_from_radius",
                        format!("must be a positive factor, got {}", crate::text::num(f)),
                    ));
                }
                net.nodes.iter().map(|n| n.radius * f).collect()
            }
            None => vec![self.height; net.nodes.len()],
        })
    }
}

/// The largest angle between two solutions' axes at the same node, degrees (how far apart two
/// methods' answers are).
pub fn largest_axis_angle(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.dot(*y).clamp(-1.0, 1.0).acos().to_degrees())
        .fold(0.0, f64::max)
}

/// Solves `net`: reference directions from `surface` (its normals at the nodes), else the
/// stored normals, else a flat network's plane. `progress` shows the rounds and can stop the
/// solve between iterations.
pub fn run(
    net: &Network,
    surface: Option<&TriMesh>,
    opts: &Options,
    progress: &dyn Progress,
) -> Result<Planarized, Error> {
    if let Some(p) = net
        .validate()
        .problems
        .into_iter()
        .find(|p| matches!(p, Problem::RepeatedEdge { .. } | Problem::SelfLoop { .. }))
    {
        return Err(Error::Member(p));
    }
    let solver = opts.solver();
    let reference = reference_normals(net, surface)?;
    let input = Input {
        positions: net.nodes.iter().map(|n| n.p).collect(),
        edges: net.edges.iter().map(|e| [e.a, e.b]).collect(),
        reference,
        heights: opts.heights(net)?,
    };
    let start = Instant::now();
    progress.begin("node axes", None);
    progress.message(&format!(
        "{} nodes, α {:.1e}",
        input.positions.len(),
        opts.alpha
    ));
    let sol = planarize_with(&input, &solver, progress)?;
    let seconds = start.elapsed().as_secs_f64();
    let axes = Axes::solved(&input, &sol, net.edges.iter().map(|e| e.radius).collect());
    let notes = notes(&sol);
    let timed = opts.timings.then_some(seconds);
    let report = report_of(&opts.name, &sol, &axes.quads(), timed, notes.clone());
    Ok(Planarized {
        summary: summary(&sol),
        solution: sol,
        axes,
        report,
        notes,
        seconds,
    })
}

fn summary(sol: &Solution) -> Summary {
    Summary {
        alpha_requested: sol.alpha_requested,
        alpha_used: sol.alpha_used,
        converged: sol.converged,
        impossible_normals: sol.impossible_normals.clone(),
        iterations: sol.iterations,
        max_axis_deviation_deg: sol.axis_deviation_deg.iter().copied().fold(0.0, f64::max),
        max_deviation: sol.max_deviation,
        method: sol.method,
        over_constrained: sol.over_constrained.clone(),
        tolerance: sol.tolerance,
    }
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

fn report_of(
    name: &str,
    sol: &Solution,
    quads: &[[DVec3; 4]],
    seconds: Option<f64>,
    notes: Vec<String>,
) -> Report {
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
            title: format!("Planarity of {name}"),
            source: name.to_string(),
            method: Some(
                match sol.method {
                    Method::Lbfgs => "L-BFGS (argmin)",
                    Method::Projection => "iterative projection",
                    Method::Newton => "Gauss-Newton (sparse Cholesky)",
                }
                .into(),
            ),
            iterations: Some(sol.iterations),
            seconds,
            alpha_requested: Some(sol.alpha_requested),
            alpha_used: Some(sol.alpha_used),
            history: sol.history.clone(),
            notes,
        },
        rows,
        quads.iter().map(|q| q.to_vec()).collect(),
        Some(sol.tolerance),
        Vec::new(),
        // planarize holds each panel's corner figure to the tolerance.
        Metric::Corner,
    )
}
