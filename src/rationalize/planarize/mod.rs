//! Node axes for torsion-free nodes with planar panels (Gokmen §4.3–4.4): find a unit axis d_i
//! per node, near its reference direction d⁰_i, such that every edge's panel
//! (v_i, v_j, v_j + h_j d_j, v_i + h_i d_i) is planar: det(ê_ij, d_i, d_j) = 0. One equation per
//! network edge against two unknowns per node, so with degree ≤ 3 exact solutions near d⁰
//! exist; nodes of degree > 3 are over-constrained and reported.
//!
//! Three solvers behind one interface: Gauss-Newton through a sparse Cholesky factorisation
//! (`newton.rs`, the default: iterations that do not grow with the network), L-BFGS (argmin)
//! on the objective in `objective.rs`, and the paper's iterative projection (`projection.rs`).
//! All keep α, the weight of closeness to d⁰, only as long as the tolerance allows: when a
//! solve ends above the tolerance, α is cut (by the ratio of deviation to tolerance, since the
//! deviation left falls about in proportion to α) and the solve resumes from where it stopped
//! (continuation), until the tolerance holds or α is negligible. Gauss-Newton, which converges
//! exactly at each α, then narrows α between one that held and one that did not, keeping the
//! largest that holds (see `newton_alpha`). The α finally used is reported, and so is a
//! tolerance not reached.
//!
//! Overrides: edges with a fixed panel normal n hold both end axes in the plane ⊥ n (Calyx's
//! base plates); nodes with a fixed axis do not move. A node on two fixed planes keeps the
//! axis along their intersection.

mod lbfgs;
mod newton;
pub mod objective;
mod projection;
pub mod synthetic;

use glam::DVec3;

use super::panels::{panel_quad, quad_deviation, quad_metrics, QuadMetrics};
use objective::{Frame, Objective};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    Lbfgs,
    Projection,
    /// Gauss-Newton through a sparse Cholesky factorisation of the edges' system (`newton.rs`).
    Newton,
}

/// Which nodes or edges an override applies to: `x<V`, `y>=V`, `z<=V`, … (an edge when both its
/// ends match), `node=N`, or `all`.
#[derive(Clone, Debug, PartialEq)]
pub enum Selector {
    All,
    Node(u32),
    Coord { axis: usize, op: Cmp, value: f64 },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cmp {
    Lt,
    Le,
    Gt,
    Ge,
}

impl Selector {
    pub fn parse(s: &str) -> Result<Selector, String> {
        let s = s.trim();
        if s == "all" {
            return Ok(Selector::All);
        }
        if let Some(n) = s.strip_prefix("node=") {
            return n
                .trim()
                .parse()
                .map(Selector::Node)
                .map_err(|_| format!("\"{n}\" is not a node number"));
        }
        let axis = match s.chars().next() {
            Some('x') => 0,
            Some('y') => 1,
            Some('z') => 2,
            _ => {
                return Err(format!(
                    "\"{s}\": expected all, node=N, or x|y|z followed by < <= > >= and a number"
                ))
            }
        };
        let rest = &s[1..];
        let (op, num) = if let Some(r) = rest.strip_prefix("<=") {
            (Cmp::Le, r)
        } else if let Some(r) = rest.strip_prefix(">=") {
            (Cmp::Ge, r)
        } else if let Some(r) = rest.strip_prefix('<') {
            (Cmp::Lt, r)
        } else if let Some(r) = rest.strip_prefix('>') {
            (Cmp::Gt, r)
        } else {
            return Err(format!("\"{s}\": expected < <= > or >= after the axis"));
        };
        let value: f64 = num
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| format!("\"{num}\" is not a finite number"))?;
        Ok(Selector::Coord { axis, op, value })
    }

    pub fn matches(&self, id: u32, p: DVec3) -> bool {
        match *self {
            Selector::All => true,
            Selector::Node(n) => n == id,
            Selector::Coord { axis, op, value } => {
                let c = p.to_array()[axis];
                match op {
                    Cmp::Lt => c < value,
                    Cmp::Le => c <= value,
                    Cmp::Gt => c > value,
                    Cmp::Ge => c >= value,
                }
            }
        }
    }
}

/// As it is written on the command line.
impl std::fmt::Display for Selector {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Selector::All => write!(f, "all"),
            Selector::Node(n) => write!(f, "node={n}"),
            Selector::Coord { axis, op, value } => {
                let op = match op {
                    Cmp::Lt => "<",
                    Cmp::Le => "<=",
                    Cmp::Gt => ">",
                    Cmp::Ge => ">=",
                };
                write!(f, "{}{op}{value}", ["x", "y", "z"][*axis])
            }
        }
    }
}

#[derive(Clone, Debug)]
pub struct PlanarizeOptions {
    pub method: Method,
    /// Weight of closeness to the reference directions. Default 0.01 (Calyx's value).
    pub alpha: f64,
    /// Largest panel deviation accepted, mm. Default 0.01.
    pub tolerance: f64,
    /// Iteration cap over all continuation rounds. Default 10,000.
    pub max_iterations: usize,
    /// Projection: how far each axis moves toward the average of its projections. Default 0.5.
    pub step: f64,
    /// Projection: the sweep as published (each axis moves toward the mean of its projections,
    /// no acceleration) instead of equal pulls with Anderson acceleration. Slower, and it lands
    /// on a different planar configuration than L-BFGS; kept to compare with the paper.
    pub plain_projection: bool,
    /// Edges (both ends selected) whose panels lie in planes with this normal.
    pub fix_normals: Vec<(Selector, DVec3)>,
    /// Nodes whose axis is given.
    pub fix_axes: Vec<(Selector, DVec3)>,
}

impl Default for PlanarizeOptions {
    fn default() -> Self {
        PlanarizeOptions {
            method: Method::Newton,
            alpha: 0.01,
            tolerance: 0.01,
            max_iterations: 10_000,
            step: 0.5,
            plain_projection: false,
            fix_normals: Vec::new(),
            fix_axes: Vec::new(),
        }
    }
}

/// The tallest panel accepted, mm: far beyond any plate. Far taller ones overflow the panel
/// figures (at 1e300 mm a solve was reported planar at zero deviation).
pub const MAX_HEIGHT: f64 = 1e6;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlanarizeError {
    #[error("node {0} has a position that is not finite")]
    NonFinite(u32),
    #[error("edge {0} joins node {1} to itself or to a node at the same place: a zero-length edge has no panel")]
    ZeroLength(usize, u32),
    #[error("edge {0} refers to node {1}, which does not exist")]
    MissingNode(usize, u32),
    #[error("node {0} has no reference direction (no stored normal): give surface=")]
    NoReference(u32),
    #[error("node {0} has a reference direction that is not a finite non-zero vector")]
    BadReference(u32),
    #[error(
        "node {node} has height {height}; heights must be positive mm, at most {MAX_HEIGHT} (1 km)",
        node = .0,
        height = crate::text::num(*.1)
    )]
    Height(u32, f64),
    #[error("alpha= must be ≥ 0, got {0}")]
    Alpha(f64),
    #[error("tolerance= must be a positive distance in mm, got {0}")]
    Tolerance(f64),
    #[error("step= must be in (0, 1], got {0}")]
    Step(f64),
    #[error("a fixed direction must be a finite non-zero vector, got {0}")]
    Direction(DVec3),
    #[error("node {0} lies on edges with three or more different fixed panel normals: no axis fits them all")]
    ConflictingNormals(u32),
    #[error("the sparse factorisation could not allocate its memory")]
    OutOfMemory,
    #[error(transparent)]
    Cancelled(#[from] crate::stage::Cancelled),
}

/// What planarize needs: positions, edges, reference directions d⁰ (unit), heights.
#[derive(Clone, Debug)]
pub struct Input {
    pub positions: Vec<DVec3>,
    pub edges: Vec<[u32; 2]>,
    pub reference: Vec<DVec3>,
    pub heights: Vec<f64>,
}

/// One panel of the result.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Panel {
    pub edge: usize,
    pub a: u32,
    pub b: u32,
    #[serde(flatten)]
    pub metrics: QuadMetrics,
    /// The panel's fixed normal, if any, and the angle of its actual normal from it, degrees.
    pub fixed_normal: Option<[f64; 3]>,
    pub fixed_normal_error_deg: Option<f64>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Solution {
    pub method: Method,
    pub axes: Vec<DVec3>,
    pub panels: Vec<Panel>,
    /// Angle of each axis from its reference, degrees.
    pub axis_deviation_deg: Vec<f64>,
    pub alpha_requested: f64,
    pub alpha_used: f64,
    pub iterations: usize,
    /// Objective (L-BFGS) or largest deviation in mm (projection) after each iteration.
    pub history: Vec<f64>,
    pub max_deviation: f64,
    pub tolerance: f64,
    pub converged: bool,
    /// Nodes of degree > 3: over-constrained, may keep the tolerance from being reached.
    pub over_constrained: Vec<u32>,
    /// Fixed-normal edges that are not perpendicular to their normal: no panel through them can
    /// have it.
    pub impossible_normals: Vec<usize>,
}

/// α is not cut below this fraction of the requested value.
const ALPHA_FLOOR: f64 = 1e-10;

pub fn planarize(input: &Input, opts: &PlanarizeOptions) -> Result<Solution, PlanarizeError> {
    planarize_with(input, opts, &crate::stage::Quiet)
}

/// Where a solve stands after a round at one α.
#[derive(Clone, Copy, Debug)]
pub struct Round {
    pub iterations: usize,
    pub alpha: f64,
    pub max_deviation: f64,
}

/// "120 iterations, α 1.0e-2: max deviation 0.0123 mm".
impl std::fmt::Display for Round {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} iterations, α {:.1e}: max deviation {:.4} mm",
            self.iterations, self.alpha, self.max_deviation
        )
    }
}

/// [`planarize`], telling `progress` after every round (each α tried) and stopping with
/// [`PlanarizeError::Cancelled`] within an iteration of its asking.
pub fn planarize_with(
    input: &Input,
    opts: &PlanarizeOptions,
    progress: &dyn crate::stage::Progress,
) -> Result<Solution, PlanarizeError> {
    let stop = || progress.cancelled();
    check(input, opts)?;
    let n = input.positions.len();
    let (frames, dims, edge_normal) = frames(input, opts)?;
    let edges: Vec<(u32, u32, DVec3, f64)> = input
        .edges
        .iter()
        .map(|&[a, b]| {
            let e = (input.positions[b as usize] - input.positions[a as usize]).normalize();
            (a, b, e, 1.0)
        })
        .collect();
    let max_dev = |axes: &[DVec3]| {
        input
            .edges
            .iter()
            .map(|&[a, b]| quad_deviation(quad(input, axes, a, b)))
            .fold(0.0, f64::max)
    };
    let mut degree = vec![0usize; n];
    for &[a, b] in &input.edges {
        degree[a as usize] += 1;
        degree[b as usize] += 1;
    }
    let plain = opts.plain_projection;
    let top = degree.iter().copied().max().unwrap_or(1).max(1);
    let scale: Vec<f64> = degree
        .iter()
        .map(|&d| {
            if plain {
                1.0 / d.max(1) as f64
            } else {
                1.0 / top as f64
            }
        })
        .collect();
    let mut alpha = opts.alpha;
    let mut history = Vec::new();
    let mut iterations = 0;
    let mut x = vec![0.0; dims];
    let mut axes: Vec<DVec3> = frames.iter().map(|f| f.base).collect();
    let mut pattern = match opts.method {
        Method::Newton => {
            Some(newton::Pattern::new(&frames, &edges).map_err(|_| PlanarizeError::OutOfMemory)?)
        }
        _ => None,
    };
    let mut schedule = Schedule::default();
    loop {
        let budget = opts.max_iterations.saturating_sub(iterations);
        if budget == 0 {
            break;
        }
        let obj = Objective {
            frames: &frames,
            edges: &edges,
            alpha,
            dims,
        };
        let used = match opts.method {
            Method::Lbfgs => {
                let run = lbfgs::solve(&obj, x.clone(), budget, opts.tolerance, &max_dev, &stop);
                x = run.x;
                axes = obj.axes(&x);
                history.extend(run.history);
                run.iterations
            }
            Method::Projection => {
                let sweep = projection::Sweep {
                    frames: &frames,
                    edges: &edges,
                    edge_normal: &edge_normal,
                    alpha,
                    step: opts.step,
                    scale: &scale,
                    accelerate: !plain,
                };
                let run =
                    projection::solve(&sweep, &mut axes, budget, opts.tolerance, &max_dev, &stop);
                history.extend(run.history);
                run.iterations
            }
            Method::Newton => {
                let pattern = pattern.as_mut().expect("built for this method");
                let run = newton::solve(&obj, pattern, x.clone(), budget, &stop);
                x = run.x;
                axes = obj.axes(&x);
                history.extend(run.history);
                run.iterations
            }
        };
        iterations += used;
        crate::stage::checkpoint(progress)?;
        let dev = max_dev(&axes);
        progress.message(
            &Round {
                iterations,
                alpha,
                max_deviation: dev,
            }
            .to_string(),
        );
        let floor = alpha <= opts.alpha * ALPHA_FLOOR || alpha == 0.0;
        if opts.method == Method::Newton {
            match newton_alpha(&mut schedule, alpha, dev, opts.tolerance, &axes) {
                Next::Try(a) if !floor => alpha = a,
                Next::Try(_) | Next::Stop => break,
                Next::Return(a, saved_axes) => {
                    (alpha, axes) = (a, saved_axes);
                    break;
                }
            }
            continue;
        }
        if dev <= opts.tolerance || floor {
            break;
        }
        // The deviation left at a converged α falls about in proportion to α: aim at half the
        // tolerance, cutting α by 10 to 10,000 times.
        alpha *= (0.5 * opts.tolerance / dev).clamp(1e-4, 0.1);
    }
    let max_deviation = max_dev(&axes);
    let panels: Vec<Panel> = input
        .edges
        .iter()
        .enumerate()
        .map(|(k, &[a, b])| {
            let metrics = panel(input, &axes, a, b);
            let fixed = edge_normal[k];
            let err = fixed.map(|nrm| {
                let e = input.positions[b as usize] - input.positions[a as usize];
                let actual = e.cross(axes[a as usize]).normalize_or_zero();
                actual.dot(nrm).abs().clamp(0.0, 1.0).acos().to_degrees()
            });
            Panel {
                edge: k,
                a,
                b,
                metrics,
                fixed_normal: fixed.map(|v| v.to_array()),
                fixed_normal_error_deg: err,
            }
        })
        .collect();
    let impossible_normals = input
        .edges
        .iter()
        .enumerate()
        .filter_map(|(k, &[a, b])| {
            let nrm = edge_normal[k]?;
            let e = (input.positions[b as usize] - input.positions[a as usize]).normalize();
            (e.dot(nrm).abs() > 1e-9).then_some(k)
        })
        .collect();
    Ok(Solution {
        method: opts.method,
        axis_deviation_deg: axes
            .iter()
            .zip(&input.reference)
            .map(|(d, r)| d.dot(*r).clamp(-1.0, 1.0).acos().to_degrees())
            .collect(),
        axes,
        panels,
        alpha_requested: opts.alpha,
        alpha_used: alpha,
        iterations,
        history,
        max_deviation,
        tolerance: opts.tolerance,
        converged: max_deviation <= opts.tolerance,
        over_constrained: (0..n as u32).filter(|&v| degree[v as usize] > 3).collect(),
        impossible_normals,
    })
}

fn panel(input: &Input, axes: &[DVec3], a: u32, b: u32) -> QuadMetrics {
    quad_metrics(quad(input, axes, a, b))
}

/// The panel of edge (a, b) with these axes.
fn quad(input: &Input, axes: &[DVec3], a: u32, b: u32) -> [DVec3; 4] {
    let (a, b) = (a as usize, b as usize);
    panel_quad(
        input.positions[a],
        input.positions[b],
        axes[a],
        axes[b],
        input.heights[a],
        input.heights[b],
    )
}

fn check(input: &Input, opts: &PlanarizeOptions) -> Result<(), PlanarizeError> {
    let n = input.positions.len() as u32;
    if let Some(i) = input.positions.iter().position(|p| !p.is_finite()) {
        return Err(PlanarizeError::NonFinite(i as u32));
    }
    for (k, &[a, b]) in input.edges.iter().enumerate() {
        for v in [a, b] {
            if v >= n {
                return Err(PlanarizeError::MissingNode(k, v));
            }
        }
        if input.positions[a as usize] == input.positions[b as usize] {
            return Err(PlanarizeError::ZeroLength(k, a));
        }
    }
    if let Some(i) = input
        .reference
        .iter()
        .position(|r| !(r.is_finite() && r.length() > 1e-12))
    {
        return Err(PlanarizeError::BadReference(i as u32));
    }
    if let Some(i) = input
        .heights
        .iter()
        .position(|h| !(h.is_finite() && *h > 0.0 && *h <= MAX_HEIGHT))
    {
        return Err(PlanarizeError::Height(i as u32, input.heights[i]));
    }
    if !(opts.alpha.is_finite() && opts.alpha >= 0.0) {
        return Err(PlanarizeError::Alpha(opts.alpha));
    }
    if !(opts.tolerance.is_finite() && opts.tolerance > 0.0) {
        return Err(PlanarizeError::Tolerance(opts.tolerance));
    }
    if !(opts.step > 0.0 && opts.step <= 1.0) {
        return Err(PlanarizeError::Step(opts.step));
    }
    for (_, d) in opts.fix_normals.iter().chain(&opts.fix_axes) {
        if !(d.is_finite() && d.length() > 1e-12) {
            return Err(PlanarizeError::Direction(*d));
        }
    }
    Ok(())
}

/// Each node's frame (how its axis may move), the number of coordinates, and each edge's fixed
/// normal if it has one.
#[allow(clippy::type_complexity)]
fn frames(
    input: &Input,
    opts: &PlanarizeOptions,
) -> Result<(Vec<Frame>, usize, Vec<Option<DVec3>>), PlanarizeError> {
    let n = input.positions.len();
    let edge_normal: Vec<Option<DVec3>> = input
        .edges
        .iter()
        .map(|&[a, b]| {
            opts.fix_normals.iter().find_map(|(sel, nrm)| {
                (sel.matches(a, input.positions[a as usize])
                    && sel.matches(b, input.positions[b as usize]))
                .then(|| nrm.normalize())
            })
        })
        .collect();
    let mut planes: Vec<Vec<DVec3>> = vec![Vec::new(); n];
    for (k, &[a, b]) in input.edges.iter().enumerate() {
        if let Some(nrm) = edge_normal[k] {
            for v in [a, b] {
                let p = &mut planes[v as usize];
                if !p.iter().any(|q| q.cross(nrm).length() < 1e-9) {
                    p.push(nrm);
                }
            }
        }
    }
    let mut frames = Vec::with_capacity(n);
    let mut offset = 0;
    for (i, on) in planes.iter().enumerate() {
        let r = input.reference[i].normalize();
        let fixed = opts
            .fix_axes
            .iter()
            .find(|(sel, _)| sel.matches(i as u32, input.positions[i]))
            .map(|(_, d)| d.normalize());
        let (base, t, dof) = match (fixed, on.as_slice()) {
            (Some(d), _) => (d, [DVec3::ZERO; 2], 0),
            (None, []) => {
                let (t0, t1) = r.any_orthonormal_pair();
                (r, [t0, t1], 2)
            }
            (None, [nrm]) => {
                let in_plane = (r - *nrm * r.dot(*nrm))
                    .try_normalize()
                    .unwrap_or_else(|| nrm.any_orthonormal_vector());
                (in_plane, [nrm.cross(in_plane), DVec3::ZERO], 1)
            }
            (None, [n1, n2]) => {
                let line = n1.cross(*n2).normalize();
                let d = if line.dot(r) < 0.0 { -line } else { line };
                (d, [DVec3::ZERO; 2], 0)
            }
            (None, _) => return Err(PlanarizeError::ConflictingNormals(i as u32)),
        };
        frames.push(Frame {
            base,
            t,
            dof,
            offset,
        });
        offset += dof;
    }
    Ok((frames, offset, edge_normal))
}

/// What the Gauss-Newton solve has learnt of α: the smallest α tried that left the tolerance
/// unmet, the largest that met it (with its axes), the α before, and how many α were tried
/// between the two.
#[derive(Default)]
struct Schedule {
    over: Option<(f64, f64)>,
    under: Option<(f64, f64, Vec<DVec3>)>,
    last: Option<(f64, f64)>,
    between: usize,
}

/// The α kept is within this factor of the largest that holds the tolerance: between one α
/// that met it and one that did not, α are tried until the two are this close…
const BRACKET: f64 = 1.4;
/// …or one that met it left at least this fraction of the tolerance (α is then within 1.4 of
/// the largest that holds wherever the deviation grows at least as fast as α^0.3 below it)…
const CLOSE: f64 = 0.9;
/// …or this many have been tried between them.
const REFINEMENTS: usize = 10;
/// From above, α is cut by at most this factor a round: the power law through two α where the
/// deviation has barely begun to fall (exponent 0.25 and less) overshoots by decades, and every
/// round below the largest α that holds is one more to climb back.
const CUT: f64 = 0.1;

enum Next {
    Try(f64),
    Stop,
    /// Go back to this α and its axes.
    Return(f64, Vec<DVec3>),
}

/// Gauss-Newton converges exactly at each α, so the α to keep is the largest whose solution
/// meets the tolerance (the axes as close to their references as the tolerance allows). The
/// deviation left goes as about α^p, p taken from the last two α tried (1 at first): from
/// above, α is cut aiming at 0.9 × tolerance. Once one α has met the tolerance and a larger
/// one has not, the largest that holds lies between them: unless the one that held is already
/// close to the tolerance ([`CLOSE`]), the next α aims at 0.95 × tolerance on the power law
/// through the two, kept within the middle half of the bracket (in log α) so the bracket
/// shrinks by a quarter at least whatever the law says, until it is narrower than
/// [`BRACKET`]. The largest α that held is kept. (The power law alone, trusted,
/// stopped a 1.31 M-node network at α 6.9e-6, a tenth of the 7.7e-5 that held.)
fn newton_alpha(s: &mut Schedule, alpha: f64, dev: f64, tolerance: f64, axes: &[DVec3]) -> Next {
    // α for a deviation `target` on the power law through (a0, d0) and (alpha, dev).
    let aim = |(a0, d0): (f64, f64), target: f64| -> f64 {
        let p = if a0 != alpha && d0 != dev && d0 > 0.0 && dev > 0.0 {
            ((d0 / dev).ln() / (a0 / alpha).ln()).clamp(0.25, 4.0)
        } else {
            1.0
        };
        alpha * (target / dev.max(f64::MIN_POSITIVE)).powf(1.0 / p)
    };
    // Within the middle half of (lo, hi), geometrically.
    let inside =
        |a: f64, lo: f64, hi: f64| a.clamp(lo * (hi / lo).powf(0.25), lo * (hi / lo).powf(0.75));
    let last = s.last.replace((alpha, dev));
    if dev <= tolerance {
        s.under = Some((alpha, dev, axes.to_vec()));
    } else {
        s.over = Some((alpha, dev));
    }
    match (&s.under, s.over) {
        // The α asked for holds: nothing larger is wanted.
        (Some(_), None) => Next::Stop,
        // Still above the tolerance: cut α.
        (None, _) => {
            let p_from = last.unwrap_or((alpha, dev));
            Next::Try(alpha * (aim(p_from, 0.9 * tolerance) / alpha).clamp(CUT, 0.9))
        }
        (Some((lo, lo_dev, _)), Some((hi, hi_dev))) => {
            if hi / lo > BRACKET && *lo_dev < CLOSE * tolerance && s.between < REFINEMENTS {
                s.between += 1;
                // The law through the bracket's two ends, from the end just tried.
                let other = if dev <= tolerance {
                    (hi, hi_dev)
                } else {
                    (*lo, *lo_dev)
                };
                Next::Try(inside(aim(other, 0.95 * tolerance), *lo, hi))
            } else if dev <= tolerance {
                Next::Stop
            } else {
                let (lo, _, lo_axes) = s.under.take().expect("just matched");
                Next::Return(lo, lo_axes)
            }
        }
    }
}

#[cfg(test)]
mod tests;
