//! A whole leaf: auxin sources (Poisson disks from a uniform radius or a density map, or
//! uniform random points), venation growth, Murray widths, and the result as a `Network` with
//! its quality report.

use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::density::DensityMap;
use super::outline::Outline;
use super::report::Quality;
use super::venation::{self, Growth, Mode, Observer, VenationError, VenationOptions};
use crate::network::{Edge, Network, Node};

/// How the initial sources are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// Bridson Poisson-disk sampling at the birth distance (from the density map if given).
    Poisson,
    /// `count` points uniformly at random (needs a count).
    Random,
}

/// More initial sources than this is an error, not an attempt to allocate for them.
pub const MAX_SOURCES: usize = 10_000_000;

/// Bridson's samples fill a blade of area A with about `POISSON_FILL`·A / r² points; used to
/// turn a wanted source count into a radius.
pub const POISSON_FILL: f64 = 0.628;

#[derive(Clone, Debug)]
pub struct LeafOptions {
    pub growth: VenationOptions,
    /// Birth distance, mm: the Poisson-disk radius of the sources and of darts. Default 1.5.
    pub birth: f64,
    /// With a density map: the radius where it is darkest and lightest. Default birth, 2 × birth.
    pub birth_min: Option<f64>,
    pub birth_max: Option<f64>,
    pub density: Option<DensityMap>,
    /// How many initial sources: Poisson picks its radius to give about this many; random
    /// places exactly this many. None: Poisson at the birth distance.
    pub sources: Option<usize>,
    pub placement: Placement,
    /// Murray exponent n in r_parent^n = Σ r_child^n. Default 3.
    pub murray: f64,
    /// Radius of vein tips and of loop-closing edges, mm. Default 0.1.
    pub tip_radius: f64,
    pub seed: u64,
}

impl Default for LeafOptions {
    fn default() -> Self {
        LeafOptions {
            growth: VenationOptions {
                mode: Mode::Closed,
                ..Default::default()
            },
            birth: 1.5,
            birth_min: None,
            birth_max: None,
            density: None,
            sources: None,
            placement: Placement::Poisson,
            murray: 3.0,
            tip_radius: 0.1,
            seed: 1,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LeafError {
    #[error("birth= must be a positive distance in mm, got {0}")]
    Birth(f64),
    #[error("birth_min= and birth_max= must be positive with min ≤ max, got {0} and {1}")]
    BirthRange(f64, f64),
    #[error("sources= must be at least 1, got {0}")]
    Sources(usize),
    #[error(
        "{what} would place about {count} sources, more than {MAX_SOURCES}: use a larger \
         distance or fewer sources"
    )]
    TooManySources { what: String, count: u64 },
    #[error(
        "sources {spacing} mm apart on this blade's bounding box need {cells} grid cells, more \
         than {max}: the blade is too large (or too thin) for that spacing",
        max = super::poisson::MAX_GRID_CELLS
    )]
    TooFineForBlade { spacing: f64, cells: u64 },
    #[error("placement= random needs sources= N")]
    RandomNeedsCount,
    #[error("murray= must be a finite exponent ≥ 1, got {0}")]
    Murray(f64),
    #[error("tip_radius= must be a positive distance in mm, got {0}")]
    TipRadius(f64),
    #[error(transparent)]
    Growth(#[from] VenationError),
}

/// A grown leaf.
#[derive(Clone, Debug)]
pub struct Leaf {
    pub network: Network,
    pub growth: Growth,
    pub quality: Quality,
}

impl LeafOptions {
    /// The birth distance at blade point `p` of the full-size outline.
    fn birth_fn<'a>(&'a self, outline: &Outline) -> Box<dyn Fn(DVec2) -> f64 + Sync + 'a> {
        match &self.density {
            None => {
                let b = self.birth;
                Box::new(move |_| b)
            }
            Some(map) => {
                let (lo, hi) = outline.bounds();
                let (min, max) = self.birth_range();
                Box::new(move |p| map.radius(p, lo, hi, min, max))
            }
        }
    }

    fn birth_range(&self) -> (f64, f64) {
        match &self.density {
            None => (self.birth, self.birth),
            Some(_) => (
                self.birth_min.unwrap_or(self.birth),
                self.birth_max.unwrap_or(2.0 * self.birth),
            ),
        }
    }

    fn check(&self, outline: &Outline) -> Result<(), LeafError> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(self.birth) {
            return Err(LeafError::Birth(self.birth));
        }
        let (min, max) = self.birth_range();
        if !(positive(min) && positive(max) && min <= max) {
            return Err(LeafError::BirthRange(min, max));
        }
        if self.sources == Some(0) {
            return Err(LeafError::Sources(0));
        }
        let count = match self.sources {
            Some(n) => n as f64,
            None => POISSON_FILL * outline.area() / (min * min),
        };
        if count > MAX_SOURCES as f64 {
            return Err(LeafError::TooManySources {
                what: match self.sources {
                    Some(_) => "sources=".into(),
                    None if self.density.is_some() => format!("birth_min= {min}"),
                    None => format!("birth= {min}"),
                },
                count: count as u64,
            });
        }
        let spacing = match self.sources {
            Some(n) => (POISSON_FILL * outline.area() / n as f64).sqrt(),
            None => min,
        };
        let cells = super::poisson::grid_cells(outline, spacing);
        if cells.is_nan() || cells > super::poisson::MAX_GRID_CELLS {
            return Err(LeafError::TooFineForBlade {
                spacing,
                cells: cells as u64,
            });
        }
        if self.placement == Placement::Random && self.sources.is_none() {
            return Err(LeafError::RandomNeedsCount);
        }
        if !(self.murray.is_finite() && self.murray >= 1.0) {
            return Err(LeafError::Murray(self.murray));
        }
        if !positive(self.tip_radius) {
            return Err(LeafError::TipRadius(self.tip_radius));
        }
        Ok(())
    }
}

/// The initial sources in `blade`, in mm.
pub fn place_sources(
    blade: &Outline,
    full: &Outline,
    opts: &LeafOptions,
    rng: &mut impl Rng,
) -> Vec<DVec2> {
    match (opts.placement, opts.sources) {
        (Placement::Random, Some(n)) => {
            let (lo, hi) = blade.bounds();
            let mut out = Vec::with_capacity(n);
            // A blade has positive area, so this ends.
            while out.len() < n {
                let p = DVec2::new(rng.random_range(lo.x..=hi.x), rng.random_range(lo.y..=hi.y));
                if blade.contains(p) {
                    out.push(p);
                }
            }
            out
        }
        (_, Some(n)) => {
            let r = (POISSON_FILL * blade.area() / n as f64).sqrt();
            super::poisson::sample(blade, r, r, |_| r, rng)
        }
        (_, None) => {
            // The blade may be the full outline scaled about a root: read the density map at
            // the matching point of the full outline.
            let birth = opts.birth_fn(full);
            let (min, max) = opts.birth_range();
            let (blo, bhi) = blade.bounds();
            let (flo, fhi) = full.bounds();
            let to_full = |p: DVec2| flo + (p - blo) / (bhi - blo) * (fhi - flo);
            super::poisson::sample(blade, min, max, |p| birth(to_full(p)), rng)
        }
    }
}

/// Places sources, grows venation from `roots`, and returns the network with Murray widths
/// (edge radius = radius of its downstream node; loop-closing edges take the tip radius).
pub fn grow_leaf(
    outline: &Outline,
    roots: &[DVec2],
    opts: &LeafOptions,
    observer: Option<Observer>,
) -> Result<Leaf, LeafError> {
    // The growth options first: the initial blade that sources are placed in depends on them.
    venation::check(&opts.growth)?;
    opts.check(outline)?;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let first = *roots.first().ok_or(VenationError::NoRoot)?;
    let blade = venation::initial_blade(outline, first, &opts.growth);
    let sources = place_sources(&blade, outline, opts, &mut rng);
    let birth = opts.birth_fn(outline);
    let growth = venation::grow(
        outline,
        roots,
        &sources,
        &*birth,
        &opts.growth,
        &mut rng,
        observer,
    )?;
    let network = to_network(&growth, opts, outline);
    let quality = Quality::of(&network, growth.roots);
    Ok(Leaf {
        network,
        growth,
        quality,
    })
}

/// A growth as a network with Murray widths (edge radius = radius of its downstream node;
/// loop-closing edges take the tip radius): tree edges (parent → child) first, then the
/// loop-closing edges, whose count is `meta.parameters["loop_edges"]`. `place(i)` gives node
/// i's position and normal. The growth parameters go into the meta; callers add their own.
/// Shared by the blade and the surface.
pub fn growth_network<V>(
    g: &Growth<V>,
    place: impl Fn(usize) -> (DVec3, DVec3),
    o: &VenationOptions,
    (murray, tip): (f64, f64),
    generator: &str,
    seed: u64,
) -> Network {
    let radius = super::murray::radii(&g.parent, murray, tip);
    let mut net = Network {
        nodes: radius
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let (p, n) = place(i);
                Node {
                    p,
                    normal: Some(n),
                    radius: *r,
                }
            })
            .collect(),
        edges: g
            .tree_edges()
            .map(|(p, c)| Edge {
                a: p,
                b: c,
                radius: radius[c as usize],
            })
            .chain(g.joins.iter().map(|&[a, b]| Edge { a, b, radius: tip }))
            .collect(),
        ..Default::default()
    };
    let mode = match o.mode {
        Mode::Open => "open",
        Mode::Closed => "closed",
    };
    net.meta.generator = Some(format!("{generator}/{mode}"));
    net.meta.seed = Some(seed);
    let p = &mut net.meta.parameters;
    let mut put = |k: &str, v: serde_json::Value| {
        p.insert(k.into(), v);
    };
    put("mode", serde_json::json!(o.mode));
    put("step", o.step.into());
    put("kill", o.kill.into());
    put("sources_per_step", o.sources_per_step.into());
    put("murray", murray.into());
    put("tip_radius", tip.into());
    put("max_iterations", o.max_iterations.into());
    put("roots", g.roots.into());
    put("loop_edges", g.joins.len().into());
    if o.mode == Mode::Closed {
        put("join_distance", o.join_distance().into());
        put("join_angle", o.join_angle.into());
    }
    if let Some(a) = o.min_joint_angle {
        put("min_joint_angle", a.into());
    }
    if o.min_member > 0.0 {
        put("min_member", o.min_member.into());
    }
    net
}

/// The leaf as a network (`growth_network` in the plane, normals +Z). The full-size blade is
/// kept as `meta.parameters["outline"]` ([[x, y], …], counter-clockwise) for later stages (the
/// leaf lamina of a print) and for checks.
pub fn to_network(g: &Growth, opts: &LeafOptions, outline: &Outline) -> Network {
    let o = &opts.growth;
    let mut net = growth_network(
        g,
        |i| (g.positions[i].extend(0.0), DVec3::Z),
        o,
        (opts.murray, opts.tip_radius),
        "venation",
        opts.seed,
    );
    let (bmin, bmax) = opts.birth_range();
    let p = &mut net.meta.parameters;
    let mut put = |k: &str, v: serde_json::Value| {
        p.insert(k.into(), v);
    };
    put("birth_min", bmin.into());
    put("birth_max", bmax.into());
    put("blade", serde_json::json!(o.blade));
    if o.blade != venation::BladeGrowth::None {
        put("initial_scale", o.initial_scale.into());
        put("blade_rate", o.blade_rate.into());
    }
    put(
        "outline",
        serde_json::json!(outline
            .points()
            .iter()
            .map(|p| [p.x, p.y])
            .collect::<Vec<_>>()),
    );
    net
}
