//! `venation`: leaf venation by space colonisation (Runions et al. 2005), open or closed, in a
//! blade ([`run`]) or on a triangle mesh ([`on_surface`], Gokmen §3.3), and Peele's sweep over
//! r ([`sweep`]), each with its quality report.
//!
//! ```
//! use lamina::grow::outline::{Outline, Shape};
//! use lamina::stage::{venation, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let blade = Outline::shape(Shape::Ovate);
//! let grown = venation::run(&blade, &venation::Options::default(), None, &Quiet)?;
//! assert!(grown.report.quality.loops > 0);
//! assert_eq!(grown.report.nodes, grown.leaf.network.nodes.len());
//! # Ok(()) }
//! ```

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::grow::density::DensityMap;
pub use crate::grow::leaf::Placement;
use crate::grow::leaf::{grow_leaf, Leaf, LeafError, LeafOptions};
use crate::grow::outline::Outline;
use crate::grow::report::Quality;
use crate::grow::surface::{
    self, grow_on_surface, SurfaceError, SurfaceOptions, SurfaceVeins, Unrooted,
};
pub use crate::grow::surface::{Channel, Root};
pub use crate::grow::venation::{BladeGrowth, Mode};
use crate::grow::venation::{Frame, Observer, Stop, VenationOptions};
use crate::stage::{OptionError, Progress};
use crate::TriMesh;

/// Sources placed on a surface when neither `sources` nor `birth` is given.
pub const DEFAULT_SURFACE_SOURCES: usize = 3000;

/// How a leaf grows. `Default` is the command's defaults; the ones marked "on a surface"
/// differ there.
#[derive(Clone, Debug)]
pub struct Options {
    /// Default closed.
    pub mode: Mode,
    /// Root nodes in the blade, mm. Default: the petiole at the blade's base.
    pub root: Vec<DVec2>,
    /// D, the length of each vein segment, mm. Default 0.75 (on a surface min(birth / 2, 0.9 ×
    /// mean edge length)).
    pub step: Option<f64>,
    /// Kill distance, mm. Default 1.1 (on a surface 1.5 D).
    pub kill: Option<f64>,
    /// Birth distance, mm. Default 1.5 (on a surface the one that places `sources`).
    pub birth: Option<f64>,
    /// Density map over the blade's bounding box (dark = dense). Default: none.
    pub density: Option<DensityMap>,
    /// With a density: the birth distance where it is darkest. Default `birth`.
    pub birth_min: Option<f64>,
    /// With a density: the birth distance where it is lightest. Default 2 × `birth`.
    pub birth_max: Option<f64>,
    /// About this many initial sources (exactly, with random placement). Default: from the
    /// birth distance (on a surface 3,000).
    pub sources: Option<usize>,
    /// Default Poisson.
    pub placement: Option<Placement>,
    /// Darts per step (Peele §3.1.2). Default 0, or 20 when the blade grows.
    pub sources_per_step: Option<usize>,
    /// Blade growth. Default none, or marginal with `r` or a sweep.
    pub blade: Option<BladeGrowth>,
    /// Blade size at the first step, as a fraction of the outline. Default 0.2.
    pub initial_scale: f64,
    /// Blade size added per step, as a fraction of the outline. Default 0.005.
    pub blade_rate: f64,
    /// Peele's r = vein growth rate / leaf growth rate (sets `blade_rate`). Default: none.
    pub r: Option<f64>,
    /// Closed venation: longest loop-closing edge, mm. Default 2 × `kill`.
    pub join_distance: Option<f64>,
    /// Closed venation: a tip joins a node at most this many degrees off its heading. Default
    /// 60.
    pub join_angle: f64,
    /// No two segments at a node meet at less than this, degrees. Default: joins only, at 25.
    pub min_joint_angle: Option<f64>,
    /// No member shorter than this is made, mm. Default 0 (off).
    pub min_member: f64,
    /// Murray exponent n. Default 3.
    pub murray: f64,
    /// Radius of vein tips and loop edges, mm. Default 0.1 (on a surface D / 7.5).
    pub tip_radius: Option<f64>,
    /// Default 10,000.
    pub max_iterations: usize,
    /// Default 1.
    pub seed: u64,
    /// On a surface: density from this vertex colour. Default: none.
    pub density_channel: Option<Channel>,
    /// On a surface: sources farther than this do not pull a node, mm. Default 4 × the largest
    /// birth distance.
    pub reach: Option<f64>,
    /// On a surface: a step or loop edge leaving the surface by more than this is not made,
    /// mm. Default D / 4.
    pub edge_tolerance: Option<f64>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            mode: Mode::Closed,
            root: Vec::new(),
            step: None,
            kill: None,
            birth: None,
            density: None,
            birth_min: None,
            birth_max: None,
            sources: None,
            placement: None,
            sources_per_step: None,
            blade: None,
            initial_scale: 0.2,
            blade_rate: 0.005,
            r: None,
            join_distance: None,
            join_angle: 60.0,
            min_joint_angle: None,
            min_member: 0.0,
            murray: 3.0,
            tip_radius: None,
            max_iterations: 10_000,
            seed: 1,
            density_channel: None,
            reach: None,
            edge_tolerance: None,
        }
    }
}

/// A leaf grown, with its report.
#[derive(Clone, Debug)]
pub struct Grown {
    /// The leaf grown.
    pub leaf: Leaf,
    /// The report, as the command writes it.
    pub report: Report,
}

/// What a growth did: the venation report `--report` writes. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Edges (members).
    pub edges: usize,
    /// Growth steps (or solver iterations) taken.
    pub iterations: usize,
    /// Loop-closing edges.
    pub loop_edges: usize,
    /// Nodes.
    pub nodes: usize,
    /// The file the network was written to (set by the command line).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
    /// The quality report.
    pub quality: Quality,
    /// Radius at the root, mm.
    pub root_radius: Option<f64>,
    /// Sources never reached.
    pub sources_left: usize,
    /// Sources placed.
    pub sources_placed: usize,
    /// Why growth stopped.
    pub stop: Stop,
}

/// Why no leaf grew.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(transparent)]
    /// Growth in the blade failed.
    Leaf(#[from] LeafError),
    #[error(transparent)]
    /// Growth on the surface failed.
    Surface(#[from] SurfaceError),
}

impl Error {
    /// Whether the caller stopped the growth.
    pub fn is_cancelled(&self) -> bool {
        use crate::grow::venation::VenationError::Cancelled;
        matches!(self, Error::Leaf(LeafError::Growth(Cancelled)))
            || matches!(self, Error::Surface(SurfaceError::Venation(Cancelled)))
    }
}

/// Frames of the growth: called every `every` steps and after the last.
pub struct Frames<'a, V> {
    /// Steps (or cells) between frames.
    pub every: usize,
    /// Called with each frame.
    pub call: &'a mut dyn FnMut(&Frame<V>),
}

impl Options {
    /// The blade's growth options, checked; `sweeping` as for [`sweep`].
    fn leaf(&self, outline: &Outline, sweeping: bool) -> Result<(LeafOptions, Vec<DVec2>), Error> {
        if self.density.is_none() && (self.birth_min.is_some() || self.birth_max.is_some()) {
            return Err(OptionError::new("birth_min", "and birth_max= need density=").into());
        }
        let roots = if self.root.is_empty() {
            vec![outline.default_root()]
        } else {
            self.root.clone()
        };
        let step = self.step.unwrap_or(0.75);
        let blade = match self.blade {
            Some(b) => b,
            None if sweeping || self.r.is_some() => BladeGrowth::Marginal,
            None => BladeGrowth::None,
        };
        if (sweeping || self.r.is_some()) && blade == BladeGrowth::None {
            return Err(OptionError::new(
                "r",
                "and a sweep need a growing blade: blade= uniform or marginal",
            )
            .into());
        }
        let growth = VenationOptions {
            mode: self.mode,
            step,
            kill: self.kill.unwrap_or(1.1),
            max_iterations: self.max_iterations,
            blade,
            initial_scale: self.initial_scale,
            blade_rate: self.blade_rate,
            sources_per_step: self.sources_per_step.unwrap_or(match blade {
                BladeGrowth::None => 0,
                _ => 20,
            }),
            join_distance: self.join_distance,
            join_angle: self.join_angle,
            min_joint_angle: self.min_joint_angle,
            min_member: self.min_member,
        };
        let mut opts = LeafOptions {
            growth,
            birth: self.birth.unwrap_or(1.5),
            birth_min: self.birth_min,
            birth_max: self.birth_max,
            density: self.density.clone(),
            sources: self.sources,
            placement: self.placement.unwrap_or(Placement::Poisson),
            murray: self.murray,
            tip_radius: self.tip_radius.unwrap_or(0.1),
            seed: self.seed,
        };
        if let Some(r) = self.r {
            opts.growth.blade_rate = blade_rate_for(r, step, outline, roots[0])?;
        }
        Ok((opts, roots))
    }
}

/// The blade rate that makes Peele's r = D / (speed of the farthest margin point).
fn blade_rate_for(r: f64, step: f64, outline: &Outline, root: DVec2) -> Result<f64, OptionError> {
    check_r("r", r)?;
    Ok(step / (r * reach(outline, root)))
}

/// How far the blade's margin reaches from the root, mm.
fn reach(outline: &Outline, root: DVec2) -> f64 {
    outline
        .points()
        .iter()
        .map(|p| p.distance(root))
        .fold(0.0, f64::max)
}

/// The largest vein-to-blade growth ratio: Peele's leaves span 0.5 to 5.5; at 1000 the blade
/// all but stands still while the veins fill it.
pub const MAX_R: f64 = 1000.0;

/// `r` (as option `name`) a ratio above 0 and at most [`MAX_R`].
fn check_r(name: &'static str, r: f64) -> Result<(), OptionError> {
    if r.is_finite() && r > 0.0 && r <= MAX_R {
        return Ok(());
    }
    Err(OptionError::new(
        name,
        format!(
            "must be a ratio above 0 and at most {}, got {}",
            crate::text::num(MAX_R),
            crate::text::num(r)
        ),
    ))
}

/// Grows venation in `outline`. `frames` sees the growth every few steps; `progress` can stop
/// it between steps.
pub fn run(
    outline: &Outline,
    opts: &Options,
    frames: Option<Frames<DVec2>>,
    progress: &dyn Progress,
) -> Result<Grown, Error> {
    let (leaf_opts, roots) = opts.leaf(outline, false)?;
    let leaf = grow_in_blade(outline, &roots, &leaf_opts, frames, progress)?;
    let report = report(&leaf);
    Ok(Grown { leaf, report })
}

fn grow_in_blade(
    outline: &Outline,
    roots: &[DVec2],
    opts: &LeafOptions,
    frames: Option<Frames<DVec2>>,
    progress: &dyn Progress,
) -> Result<Leaf, LeafError> {
    progress.begin("growing", None);
    let stop = || progress.cancelled();
    let mut none = |_: &Frame<DVec2>| {};
    let observer = match frames {
        Some(f) => Observer {
            every: f.every,
            call: f.call,
            stop: &stop,
        },
        None => Observer::stop_only(&stop, &mut none),
    };
    grow_leaf(outline, roots, opts, Some(observer))
}

fn report(leaf: &Leaf) -> Report {
    let g = &leaf.growth;
    Report {
        edges: leaf.network.edges.len(),
        iterations: g.iterations,
        loop_edges: g.joins.len(),
        nodes: leaf.network.nodes.len(),
        output: None,
        quality: leaf.quality.clone(),
        root_radius: leaf.network.nodes.first().map(|n| n.radius),
        sources_left: g.sources_left,
        sources_placed: g.sources_placed,
        stop: g.stop,
    }
}

/// One leaf of a sweep.
#[derive(Clone, Debug)]
pub struct SweptLeaf {
    /// Peele's r.
    pub r: f64,
    /// The seed it grew from.
    pub seed: u64,
    /// Blade size added per step.
    pub blade_rate: f64,
    /// D, mm.
    pub step: f64,
    /// The leaf and its report.
    pub grown: Grown,
}

/// What a sweep varies to set r = D / (speed of the farthest margin point).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SweepBy {
    /// The blade's growth: D stays `step`, the blade rate is D / (r · reach).
    #[default]
    Blade,
    /// D, as Peele did ("all parameters are held constant except for the vein growth rate (as
    /// controlled by the vein edge length parameter)"): the blade rate stays `blade_rate`, D is
    /// r · blade rate · reach.
    Step,
}

/// The most seeds a sweep grows per r.
pub const MAX_SEEDS: usize = 1000;

/// Peele's Figure 1: one leaf per r and seed (`seeds` of them, from `opts.seed` up), each with
/// the blade rate (or, `by` [`SweepBy::Step`], the D) that makes its r, grown with the same
/// options otherwise (a marginal blade unless `blade` says otherwise). Leaves in order of r,
/// then seed.
pub fn sweep(
    outline: &Outline,
    opts: &Options,
    rs: &[f64],
    by: SweepBy,
    seeds: usize,
    progress: &dyn Progress,
) -> Result<Vec<SweptLeaf>, Error> {
    // Every ratio checked before the first leaf grows.
    if rs.is_empty() {
        return Err(OptionError::new("sweep_r", "needs at least one ratio").into());
    }
    for &r in rs {
        check_r("sweep_r", r)?;
    }
    if !(1..=MAX_SEEDS).contains(&seeds) {
        return Err(OptionError::new(
            "seeds",
            format!("must be 1 to {MAX_SEEDS} leaves per r, got {seeds}"),
        )
        .into());
    }
    let seeds: Vec<u64> = (0..seeds as u64)
        .map(|k| opts.seed.checked_add(k))
        .collect::<Option<_>>()
        .ok_or_else(|| OptionError::new("seed", "leaves no room for the seeds after it"))?;
    let (base, roots) = opts.leaf(outline, true)?;
    let mut out = Vec::with_capacity(rs.len() * seeds.len());
    for &r in rs {
        for &seed in &seeds {
            let mut leaf_opts = base.clone();
            match by {
                SweepBy::Blade => {
                    leaf_opts.growth.blade_rate =
                        blade_rate_for(r, leaf_opts.growth.step, outline, roots[0])?
                }
                SweepBy::Step => {
                    leaf_opts.growth.step =
                        r * leaf_opts.growth.blade_rate * reach(outline, roots[0])
                }
            }
            leaf_opts.seed = seed;
            let leaf = grow_in_blade(outline, &roots, &leaf_opts, None, progress)?;
            let report = report(&leaf);
            out.push(SweptLeaf {
                r,
                seed,
                blade_rate: leaf_opts.growth.blade_rate,
                step: leaf_opts.growth.step,
                grown: Grown { leaf, report },
            });
        }
    }
    Ok(out)
}

/// Mean, sample standard deviation (0 for one value), least and greatest of a measure over
/// the seeds of one r.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: f64,
    /// Least.
    pub min: f64,
    /// Greatest.
    pub max: f64,
}

impl Spread {
    fn of(values: &[f64]) -> Spread {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let sd = if values.len() > 1 {
            (values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.0
        };
        Spread {
            mean,
            sd,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// One r of a sweep over its seeds: Peele's two claims as measures (see
/// [`crate::grow::report::Veins`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepRow {
    /// Peele's r.
    pub r: f64,
    /// Leaves grown at this r.
    pub seeds: usize,
    /// Dominant veins (radius at least half the petiole's).
    pub dominant: Spread,
    /// Their mean radius over the petiole's.
    pub dominant_radius_ratio: Spread,
    /// The zigzag index, degrees.
    pub zigzag_deg: Spread,
    /// Turning along the dominant veins, degrees per mm.
    pub turning_deg_per_mm: Spread,
}

/// The sweep's table: one row per r, in the sweep's order.
pub fn sweep_table(leaves: &[SweptLeaf]) -> Vec<SweepRow> {
    let mut rows: Vec<SweepRow> = Vec::new();
    let mut start = 0;
    while start < leaves.len() {
        let r = leaves[start].r;
        let end = start + leaves[start..].iter().take_while(|l| l.r == r).count();
        let group = &leaves[start..end];
        let of = |f: &dyn Fn(&Quality) -> f64| {
            Spread::of(
                &group
                    .iter()
                    .map(|l| f(&l.grown.report.quality))
                    .collect::<Vec<_>>(),
            )
        };
        rows.push(SweepRow {
            r,
            seeds: group.len(),
            dominant: of(&|q| q.veins.dominant as f64),
            dominant_radius_ratio: of(&|q| q.veins.dominant_radius_ratio),
            zigzag_deg: of(&|q| q.zigzag_deg),
            turning_deg_per_mm: of(&|q| q.veins.dominant_turning_deg_per_mm),
        });
        start = end;
    }
    rows
}

/// Peele's two claims tested on a sweep's table, lowest r against highest, in words: "beyond
/// the spread" means the two means differ by more than the sum of their standard deviations.
/// Empty when the table has fewer than two r.
pub fn sweep_verdict(table: &[SweepRow]) -> Vec<String> {
    let (Some(lo), Some(hi)) = (table.first(), table.last()) else {
        return Vec::new();
    };
    if table.len() < 2 {
        return Vec::new();
    }
    // +1 when the lowest r's mean is above the highest's beyond the spread, -1 below, 0 not.
    let apart = |f: fn(&SweepRow) -> Spread| {
        let (a, b) = (f(lo), f(hi));
        if a.mean - a.sd > b.mean + b.sd {
            1
        } else if a.mean + a.sd < b.mean - b.sd {
            -1
        } else {
            0
        }
    };
    let said = |sign: i32, want: i32| match sign {
        0 => "not beyond the spread",
        s if s == want => "as the paper says",
        _ => "the opposite of the paper",
    };
    let (r0, r1) = (lo.r, hi.r);
    vec![
        format!(
            "fewer dominant veins at low r: {:.1} ± {:.1} at r = {r0} against {:.1} ± {:.1} at r = {r1}, {}",
            lo.dominant.mean,
            lo.dominant.sd,
            hi.dominant.mean,
            hi.dominant.sd,
            said(apart(|r| r.dominant), -1)
        ),
        format!(
            "thicker dominant veins at low r: {:.3} ± {:.3} of the petiole's radius at r = {r0} \
             against {:.3} ± {:.3} at r = {r1}, {}",
            lo.dominant_radius_ratio.mean,
            lo.dominant_radius_ratio.sd,
            hi.dominant_radius_ratio.mean,
            hi.dominant_radius_ratio.sd,
            said(apart(|r| r.dominant_radius_ratio), 1)
        ),
        format!(
            "more chaotic at high r: zigzag index {:.1} ± {:.1}° at r = {r0} against {:.1} ± {:.1}° \
             at r = {r1}, {}; turning along dominant veins {:.2} ± {:.2} against {:.2} ± {:.2}°/mm, {}",
            lo.zigzag_deg.mean,
            lo.zigzag_deg.sd,
            hi.zigzag_deg.mean,
            hi.zigzag_deg.sd,
            said(apart(|r| r.zigzag_deg), -1),
            lo.turning_deg_per_mm.mean,
            lo.turning_deg_per_mm.sd,
            hi.turning_deg_per_mm.mean,
            hi.turning_deg_per_mm.sd,
            said(apart(|r| r.turning_deg_per_mm), -1)
        ),
    ]
}

/// The sweep as one SVG: the first seed's leaf of each r side by side, each with its r, and
/// under them the four measures of the table against r (mean, a bar from least to greatest
/// over the seeds, and a tick at one standard deviation either side of the mean).
pub fn sweep_figure(leaves: &[SweptLeaf]) -> String {
    let mut body = String::new();
    let mut x = 0.0;
    let mut height: f64 = 0.0;
    let mut drawn: Vec<f64> = Vec::new();
    for leaf in leaves {
        if drawn.contains(&leaf.r) {
            continue;
        }
        drawn.push(leaf.r);
        let net = &leaf.grown.leaf.network;
        let b = net.bbox();
        let (w, h) = (b.max.x - b.min.x, b.max.y - b.min.y);
        body.push_str(&format!(
            "<g transform=\"translate({:.3} {:.3}) scale(1 -1)\">",
            x - b.min.x,
            b.max.y + 12.0
        ));
        for e in &net.edges {
            let (p, q) = (net.nodes[e.a as usize].p, net.nodes[e.b as usize].p);
            body.push_str(&format!(
                "<line x1=\"{:.3}\" y1=\"{:.3}\" x2=\"{:.3}\" y2=\"{:.3}\" stroke-width=\"{:.3}\"/>",
                p.x,
                p.y,
                q.x,
                q.y,
                2.0 * e.radius
            ));
        }
        body.push_str("</g>");
        body.push_str(&format!(
            "<text x=\"{:.3}\" y=\"8\" font-family=\"sans-serif\" font-size=\"6\" \
             stroke=\"none\" fill=\"#222\">r = {} (seed {})</text>",
            x, leaf.r, leaf.seed
        ));
        // Room for the label under a leaf that stayed small.
        x += w.max(LABEL_WIDTH) + 10.0;
        height = height.max(h + 14.0);
    }
    let width = (x - 10.0).max(4.0 * MIN_PLOT_WIDTH);
    let table = sweep_table(leaves);
    let plots = measure_plots(&table, height + 6.0, width);
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"-5 0 {:.3} {:.3}\" \
         width=\"{:.0}mm\" height=\"{:.0}mm\">\n<rect x=\"-5\" y=\"0\" width=\"100%\" \
         height=\"100%\" fill=\"white\"/>\n<g stroke=\"#1d3b2a\" stroke-linecap=\"round\">{body}</g>\n{plots}</svg>\n",
        width + 10.0,
        height + 6.0 + PLOT_HEIGHT,
        width + 10.0,
        height + 6.0 + PLOT_HEIGHT
    )
}

/// Height of the row of measure plots under the leaves, in the figure's units (mm).
const PLOT_HEIGHT: f64 = 62.0;
/// Width a leaf's label "r = … (seed …)" needs.
const LABEL_WIDTH: f64 = 52.0;
/// Narrowest a measure plot is drawn (its title fits).
const MIN_PLOT_WIDTH: f64 = 60.0;

/// Four small plots side by side at height `top`, across `width`.
fn measure_plots(table: &[SweepRow], top: f64, width: f64) -> String {
    type Pick = fn(&SweepRow) -> Spread;
    let plots: [(&str, Pick); 4] = [
        ("dominant veins", |r| r.dominant),
        ("their radius / petiole", |r| r.dominant_radius_ratio),
        ("zigzag index (°)", |r| r.zigzag_deg),
        ("turning, dominant veins (°/mm)", |r| r.turning_deg_per_mm),
    ];
    let gap = 8.0;
    let pw = (width - 3.0 * gap) / 4.0;
    let (ph, margin) = (PLOT_HEIGHT - 22.0, 10.0);
    let (r_lo, r_hi) = table
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), row| {
            (lo.min(row.r), hi.max(row.r))
        });
    let r_span = if r_hi > r_lo { r_hi - r_lo } else { 1.0 };
    let mut out = String::from("<g font-family=\"sans-serif\" font-size=\"3.2\" fill=\"#222\">");
    for (k, (title, pick)) in plots.iter().enumerate() {
        let x0 = k as f64 * (pw + gap) + margin;
        let w = pw - margin;
        let y0 = top + 6.0;
        let spreads: Vec<Spread> = table.iter().map(pick).collect();
        let lo = spreads
            .iter()
            .map(|s| s.min.min(s.mean - s.sd))
            .fold(f64::INFINITY, f64::min);
        let hi = spreads
            .iter()
            .map(|s| s.max.max(s.mean + s.sd))
            .fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 1.0, hi + 1.0)
        };
        let pad = 0.08 * (hi - lo);
        // Counts, ratios and angles are never negative: the axis stops at 0.
        let floor = if lo >= 0.0 { 0.0 } else { f64::NEG_INFINITY };
        let (lo, hi) = ((lo - pad).max(floor), hi + pad);
        let px = |r: f64| x0 + 3.0 + (w - 6.0) * (r - r_lo) / r_span;
        let py = |v: f64| y0 + ph * (hi - v) / (hi - lo);
        out.push_str(&format!(
            "<text x=\"{x0:.2}\" y=\"{:.2}\" font-weight=\"bold\">{title}</text>\
             <rect x=\"{x0:.2}\" y=\"{y0:.2}\" width=\"{w:.2}\" height=\"{ph:.2}\" fill=\"none\" \
             stroke=\"#999\" stroke-width=\"0.2\"/>\
             <text x=\"{:.2}\" y=\"{:.2}\" text-anchor=\"end\">{}</text>\
             <text x=\"{:.2}\" y=\"{:.2}\" text-anchor=\"end\">{}</text>",
            top + 3.0,
            x0 - 0.8,
            y0 + 3.0,
            tick(hi),
            x0 - 0.8,
            y0 + ph,
            tick(lo)
        ));
        let mut line = String::new();
        for (row, s) in table.iter().zip(&spreads) {
            let x = px(row.r);
            out.push_str(&format!(
                "<line x1=\"{x:.2}\" y1=\"{:.2}\" x2=\"{x:.2}\" y2=\"{:.2}\" stroke=\"#7a9a86\" \
                 stroke-width=\"0.5\"/>\
                 <line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"#1d3b2a\" stroke-width=\"0.3\"/>\
                 <line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"#1d3b2a\" stroke-width=\"0.3\"/>\
                 <circle cx=\"{x:.2}\" cy=\"{:.2}\" r=\"0.9\" fill=\"#1d3b2a\"/>\
                 <text x=\"{x:.2}\" y=\"{:.2}\" text-anchor=\"middle\">{}</text>",
                py(s.min),
                py(s.max),
                x - 1.2,
                py(s.mean + s.sd),
                x + 1.2,
                py(s.mean + s.sd),
                x - 1.2,
                py(s.mean - s.sd),
                x + 1.2,
                py(s.mean - s.sd),
                py(s.mean),
                y0 + ph + 4.0,
                row.r
            ));
            line.push_str(&format!("{x:.2},{:.2} ", py(s.mean)));
        }
        out.push_str(&format!(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"#1d3b2a\" stroke-width=\"0.3\"/>",
            line.trim_end()
        ));
        out.push_str(&format!(
            "<text x=\"{:.2}\" y=\"{:.2}\" text-anchor=\"middle\">r</text>",
            x0 + w / 2.0,
            y0 + ph + 8.0
        ));
    }
    out.push_str("</g>\n");
    out
}

/// An axis label with three significant digits.
fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (2 - v.abs().max(1e-12).log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.digits$}")
}

/// Veins grown on a surface, with the options that grew them (defaults resolved) and the
/// report.
#[derive(Clone, Debug)]
pub struct OnSurface {
    /// The veins grown.
    pub veins: SurfaceVeins,
    /// The options as resolved.
    pub options: SurfaceOptions,
    /// The report, as the command writes it.
    pub report: SurfaceReport,
    /// What the caller should hear (bodies no root reaches), one line each.
    pub notes: Vec<String>,
}

/// The report of venation on a surface. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct SurfaceReport {
    /// Birth distance where lightest, mm.
    pub birth_max: f64,
    /// Birth distance where darkest, mm.
    pub birth_min: f64,
    /// Edges (members).
    pub edges: usize,
    /// Growth steps (or solver iterations) taken.
    pub iterations: usize,
    /// Kill distance, mm.
    pub kill: f64,
    /// Loop-closing edges.
    pub loop_edges: usize,
    /// Nodes.
    pub nodes: usize,
    /// The file the network was written to (set by the command line).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
    /// The quality report.
    pub quality: surface::SurfaceQuality,
    /// Sources never reached.
    pub sources_left: usize,
    /// Sources placed.
    pub sources_placed: usize,
    /// Growth step D, mm.
    pub step: f64,
    /// Why growth stopped.
    pub stop: Stop,
    /// The surface's name (set by the command line: its path).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface: Option<String>,
}

/// The growth options on `mesh`, every default resolved (step, kill and tip radius from the
/// mesh and the source count).
pub fn surface_options(mesh: &TriMesh, opts: &Options) -> Result<SurfaceOptions, Error> {
    if opts.blade.is_some_and(|b| b != BladeGrowth::None) || opts.r.is_some() {
        return Err(OptionError::new("blade", "does not grow on a surface (nor does r=)").into());
    }
    if opts.density.is_some() {
        return Err(OptionError::new(
            "density",
            "is a map over a blade; on a surface give density_channel=",
        )
        .into());
    }
    let density = opts.density_channel;
    if density.is_none() && (opts.birth_min.is_some() || opts.birth_max.is_some()) {
        return Err(OptionError::new(
            "birth_min",
            "and birth_max= need density_channel= on a surface",
        )
        .into());
    }
    if opts.sources.is_some() && opts.birth.is_some() {
        return Err(OptionError::new(
            "sources",
            "and birth= both set the source spacing on a surface: give one",
        )
        .into());
    }
    let mut s = SurfaceOptions::for_mesh(
        mesh,
        opts.mode,
        opts.sources.unwrap_or(DEFAULT_SURFACE_SOURCES),
        density,
    );
    if let Some(b) = opts.birth_min.or(opts.birth) {
        s.birth_min = b;
    }
    s.birth_max = match (opts.birth_max, density) {
        (Some(b), _) => b,
        (None, Some(_)) => 2.0 * s.birth_min,
        (None, None) => s.birth_min,
    };
    let g = &mut s.growth;
    g.step = opts
        .step
        .unwrap_or_else(|| surface::default_step(mesh, s.birth_min));
    g.kill = opts.kill.unwrap_or(1.5 * g.step);
    g.max_iterations = opts.max_iterations;
    g.sources_per_step = opts.sources_per_step.unwrap_or(0);
    g.join_distance = opts.join_distance;
    g.join_angle = opts.join_angle;
    g.min_joint_angle = opts.min_joint_angle;
    g.min_member = opts.min_member;
    s.tip_radius = opts.tip_radius.unwrap_or(g.step / 7.5);
    s.reach = opts.reach;
    s.edge_tolerance = opts.edge_tolerance;
    s.murray = opts.murray;
    s.seed = opts.seed;
    Ok(s)
}

/// Grows venation on `mesh` from `roots` (the lowest vertex when empty).
pub fn on_surface(
    mesh: &TriMesh,
    roots: &[Root],
    opts: &Options,
    frames: Option<Frames<DVec3>>,
    progress: &dyn Progress,
) -> Result<OnSurface, Error> {
    let s = surface_options(mesh, opts)?;
    progress.begin("growing", None);
    let stop = || progress.cancelled();
    let mut none = |_: &Frame<DVec3>| {};
    let observer = match frames {
        Some(f) => Observer {
            every: f.every,
            call: f.call,
            stop: &stop,
        },
        None => Observer::stop_only(&stop, &mut none),
    };
    let veins = grow_on_surface(mesh, roots, &s, Some(observer))?;
    let u = &veins.quality.unrooted;
    let mut notes = Vec::new();
    if roots.is_empty() && u.bodies > 1 {
        notes.push(format!(
            "its {} bodies each grow from their lowest vertex (give root= to choose)",
            u.bodies
        ));
    }
    notes.extend(unrooted_lines(u));
    let g = &veins.growth;
    let report = SurfaceReport {
        birth_max: s.birth_max,
        birth_min: s.birth_min,
        edges: veins.network.edges.len(),
        iterations: g.iterations,
        kill: s.growth.kill,
        loop_edges: g.joins.len(),
        nodes: veins.network.nodes.len(),
        output: None,
        quality: veins.quality.clone(),
        sources_left: g.sources_left,
        sources_placed: g.sources_placed,
        step: s.growth.step,
        stop: g.stop,
        surface: None,
    };
    Ok(OnSurface {
        veins,
        options: s,
        report,
        notes,
    })
}

/// The bodies of a surface that no root reaches, one line each (none when every body has a
/// root): how many, then each named by its number, size and lowest vertex.
pub fn unrooted_lines(u: &Unrooted) -> Vec<String> {
    if u.bodies_without_root == 0 {
        return Vec::new();
    }
    let mut lines = vec![format!(
        "{} of its {} bodies have no root, so growth cannot reach them ({} sources there left \
         out); give a root= on each body to grow on it",
        u.bodies_without_root, u.bodies, u.sources_left_out
    )];
    for b in &u.without_root {
        let [x, y, z] = b.at;
        lines.push(format!(
            "body {}: {} triangles, {} sources, no root (its lowest vertex: {} at {x}, {y}, {z})",
            b.body, b.triangles, b.sources, b.lowest_vertex
        ));
    }
    if u.bodies_without_root > u.without_root.len() {
        lines.push(format!(
            "(and {} more bodies without a root)",
            u.bodies_without_root - u.without_root.len()
        ));
    }
    lines
}

/// A report's text as the command writes it: pretty JSON, one final line break.
pub fn json_text(value: &impl Serialize) -> String {
    serde_json::to_string_pretty(value).expect("reports serialise") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spread(mean: f64, sd: f64) -> Spread {
        Spread {
            mean,
            sd,
            min: mean - sd,
            max: mean + sd,
        }
    }

    fn row(r: f64, dominant: (f64, f64), ratio: (f64, f64), zigzag: (f64, f64)) -> SweepRow {
        SweepRow {
            r,
            seeds: 5,
            dominant: spread(dominant.0, dominant.1),
            dominant_radius_ratio: spread(ratio.0, ratio.1),
            zigzag_deg: spread(zigzag.0, zigzag.1),
            turning_deg_per_mm: spread(zigzag.0 / 10.0, zigzag.1 / 10.0),
        }
    }

    #[test]
    fn the_verdict_compares_the_ends_beyond_the_spread() {
        // Fewer at low r beyond the spread (10 + 2 < 20 - 3); thinner at low r, the opposite
        // (0.6 + 0.01 < 0.8 - 0.01); zigzag apart by exactly the spread: not beyond it.
        let table = [
            row(0.5, (10.0, 2.0), (0.6, 0.01), (10.0, 5.0)),
            row(1.5, (99.0, 0.0), (0.0, 0.0), (0.0, 0.0)),
            row(5.5, (20.0, 3.0), (0.8, 0.01), (20.0, 5.0)),
        ];
        let v = sweep_verdict(&table);
        assert_eq!(v.len(), 3);
        assert!(v[0].ends_with("as the paper says"), "{}", v[0]);
        assert!(v[1].ends_with("the opposite of the paper"), "{}", v[1]);
        assert!(
            v[2].contains("at r = 5.5, not beyond the spread;"),
            "{}",
            v[2]
        );
        assert!(sweep_verdict(&table[..1]).is_empty());
    }

    #[test]
    fn a_spread_has_the_sample_deviation() {
        let s = Spread::of(&[1.0, 2.0, 3.0, 6.0]);
        assert_eq!((s.mean, s.min, s.max), (3.0, 1.0, 6.0));
        assert!((s.sd - (14.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert_eq!(Spread::of(&[4.0]).sd, 0.0);
    }
}
