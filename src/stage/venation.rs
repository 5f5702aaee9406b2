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
    let reach = outline
        .points()
        .iter()
        .map(|p| p.distance(root))
        .fold(0.0, f64::max);
    Ok(step / (r * reach))
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
    /// Blade size added per step.
    pub blade_rate: f64,
    /// The leaf and its report.
    pub grown: Grown,
}

/// Peele's Figure 1: one leaf per r, each with the blade rate that makes it, grown with the
/// same options otherwise (a marginal blade unless `blade` says otherwise).
pub fn sweep(
    outline: &Outline,
    opts: &Options,
    rs: &[f64],
    progress: &dyn Progress,
) -> Result<Vec<SweptLeaf>, Error> {
    // Every ratio checked before the first leaf grows.
    if rs.is_empty() {
        return Err(OptionError::new("sweep_r", "needs at least one ratio").into());
    }
    for &r in rs {
        check_r("sweep_r", r)?;
    }
    let (base, roots) = opts.leaf(outline, true)?;
    let mut out = Vec::with_capacity(rs.len());
    for &r in rs {
        let mut leaf_opts = base.clone();
        leaf_opts.growth.blade_rate = blade_rate_for(r, leaf_opts.growth.step, outline, roots[0])?;
        let leaf = grow_in_blade(outline, &roots, &leaf_opts, None, progress)?;
        let report = report(&leaf);
        out.push(SweptLeaf {
            r,
            blade_rate: leaf_opts.growth.blade_rate,
            grown: Grown { leaf, report },
        });
    }
    Ok(out)
}

/// The leaves of a sweep side by side in one SVG, each with its r.
pub fn contact_sheet(leaves: &[SweptLeaf]) -> String {
    let mut body = String::new();
    let mut x = 0.0;
    let mut height: f64 = 0.0;
    for leaf in leaves {
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
            "<text x=\"{:.3}\" y=\"8\" font-family=\"sans-serif\" font-size=\"6\">r = {}</text>",
            x, leaf.r
        ));
        x += w + 10.0;
        height = height.max(h + 14.0);
    }
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"-5 0 {:.3} {:.3}\" \
         width=\"{:.0}mm\" height=\"{:.0}mm\">\n<g stroke=\"#1d3b2a\" stroke-linecap=\"round\">{body}</g>\n</svg>\n",
        x + 5.0,
        height,
        x + 5.0,
        height
    )
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
