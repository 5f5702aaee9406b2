//! Open leaf venation by space colonisation (Runions et al. 2005, as Gokmen §3.2 and Peele §3.1
//! use it). Each auxin source pulls on its closest vein node that can still branch; a pulled node
//! grows one new node at v + D·n/|n|, n the sum of unit vectors to its sources; sources within
//! the kill distance of a vein node are removed. Growth stops when no source is left, nothing
//! grows, or the iteration cap is reached.
//!
//! Guarantees: every node lies inside the blade; every edge has length D; no node has degree
//! above 3 (a node at degree 3 no longer attracts sources, which then pull on their next-closest
//! node); no two nodes closer than `CROWDING`·D (a node whose step would land there retires, so
//! its sources pull on another node); the result is a tree per root. Not guaranteed: that every source is reached (a source
//! may sit where no node can step without leaving a concave blade); those are counted.
//!
//! Spatial queries use rstar: one tree of nodes that may still branch, one of live sources.

use glam::DVec2;
use rstar::primitives::GeomWithData;
use rstar::RTree;

use super::outline::Outline;

type Indexed = GeomWithData<[f64; 2], u32>;

/// The growth parameters, in mm.
#[derive(Clone, Copy, Debug)]
pub struct VenationOptions {
    /// D, the length of every new vein segment. Default 1.0 mm.
    pub step: f64,
    /// Sources closer than this to any vein node are removed. Default 1.5 mm.
    pub kill: f64,
    /// Stop after this many growth steps. Default 10,000.
    pub max_iterations: usize,
}

impl Default for VenationOptions {
    fn default() -> Self {
        VenationOptions {
            step: 1.0,
            kill: 1.5,
            max_iterations: 10_000,
        }
    }
}

/// A step that would land closer than this many D to an existing node is not taken.
pub const CROWDING: f64 = 0.5;

/// Joints allowed in a vein network: Y (3 legs) and I (2 legs), Gokmen §3.2 step g.
pub const MAX_DEGREE: usize = 3;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum VenationError {
    #[error("--step must be a positive distance in mm, got {0}")]
    Step(f64),
    #[error("--kill must be a positive distance in mm, got {0}")]
    Kill(f64),
    #[error("root {0} ({1}, {2}) is not inside the blade outline")]
    RootOutside(usize, f64, f64),
    #[error("no root given")]
    NoRoot,
}

/// A grown vein tree.
#[derive(Clone, Debug)]
pub struct Growth {
    pub positions: Vec<DVec2>,
    /// Parent of each node; `None` for roots. Edges are (parent, child) in node order.
    pub parent: Vec<Option<u32>>,
    pub iterations: usize,
    pub sources_placed: usize,
    pub sources_left: usize,
    /// Why growth stopped.
    pub stop: Stop,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    NoSourcesLeft,
    NothingGrew,
    IterationCap,
}

impl Growth {
    pub fn edges(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.parent
            .iter()
            .enumerate()
            .filter_map(|(c, p)| p.map(|p| (p, c as u32)))
    }

    pub fn degrees(&self) -> Vec<usize> {
        let mut d = vec![0usize; self.positions.len()];
        for (p, c) in self.edges() {
            d[p as usize] += 1;
            d[c as usize] += 1;
        }
        d
    }
}

/// Grows open venation from `roots` towards `sources` inside `outline`.
pub fn grow_open(
    outline: &Outline,
    roots: &[DVec2],
    sources: &[DVec2],
    opts: &VenationOptions,
) -> Result<Growth, VenationError> {
    if !(opts.step.is_finite() && opts.step > 0.0) {
        return Err(VenationError::Step(opts.step));
    }
    if !(opts.kill.is_finite() && opts.kill > 0.0) {
        return Err(VenationError::Kill(opts.kill));
    }
    if roots.is_empty() {
        return Err(VenationError::NoRoot);
    }
    if let Some((i, r)) = roots
        .iter()
        .enumerate()
        .find(|(_, r)| !outline.contains(**r))
    {
        return Err(VenationError::RootOutside(i, r.x, r.y));
    }
    let mut g = Growth {
        positions: roots.to_vec(),
        parent: vec![None; roots.len()],
        iterations: 0,
        sources_placed: sources.len(),
        sources_left: 0,
        stop: Stop::NothingGrew,
    };
    let mut degree = vec![0usize; roots.len()];
    let mut open: RTree<Indexed> = RTree::bulk_load(
        roots
            .iter()
            .enumerate()
            .map(|(i, r)| Indexed::new(r.to_array(), i as u32))
            .collect(),
    );
    let mut live: RTree<Indexed> = RTree::bulk_load(
        sources
            .iter()
            .enumerate()
            .map(|(i, s)| Indexed::new(s.to_array(), i as u32))
            .collect(),
    );
    // Every node, to refuse a step onto an existing node: a node whose sources have not moved
    // would otherwise grow a second child onto its first.
    let mut all: RTree<[f64; 2]> = RTree::bulk_load(roots.iter().map(|r| r.to_array()).collect());
    let crowd2 = (CROWDING * opts.step).powi(2);
    let kill2 = opts.kill * opts.kill;
    for r in roots {
        kill_near(&mut live, *r, kill2);
    }
    let mut pull = vec![DVec2::ZERO; g.positions.len()];
    let mut pulled: Vec<u32> = Vec::new();
    loop {
        if live.size() == 0 {
            g.stop = Stop::NoSourcesLeft;
            break;
        }
        if g.iterations >= opts.max_iterations {
            g.stop = Stop::IterationCap;
            break;
        }
        g.iterations += 1;
        // Each source pulls its closest node that may still branch.
        for s in live.iter() {
            let sp = DVec2::from_array(*s.geom());
            let Some(n) = open.nearest_neighbor(s.geom()) else {
                break;
            };
            let v = n.data as usize;
            let d = sp - g.positions[v];
            if let Some(u) = d.try_normalize() {
                if pull[v] == DVec2::ZERO {
                    pulled.push(v as u32);
                }
                pull[v] += u;
            }
        }
        // Grow in node order so the result does not depend on the tree's iteration order.
        pulled.sort_unstable();
        let mut grown = 0;
        for &v in &pulled {
            let dir = std::mem::take(&mut pull[v as usize]);
            let Some(dir) = dir.try_normalize() else {
                continue;
            };
            let at = g.positions[v as usize] + dir * opts.step;
            if !outline.contains(at) || degree[v as usize] >= MAX_DEGREE {
                continue;
            }
            if all
                .locate_within_distance(at.to_array(), crowd2)
                .next()
                .is_some()
            {
                // Its sources sit around it with nothing new to reach: retire the node so they
                // pull on their next-closest node instead.
                open.remove(&Indexed::new(g.positions[v as usize].to_array(), v));
                continue;
            }
            let child = g.positions.len() as u32;
            g.positions.push(at);
            g.parent.push(Some(v));
            degree.push(1);
            pull.push(DVec2::ZERO);
            degree[v as usize] += 1;
            if degree[v as usize] >= MAX_DEGREE {
                open.remove(&Indexed::new(g.positions[v as usize].to_array(), v));
            }
            open.insert(Indexed::new(at.to_array(), child));
            all.insert(at.to_array());
            kill_near(&mut live, at, kill2);
            grown += 1;
        }
        pulled.clear();
        if grown == 0 {
            g.stop = Stop::NothingGrew;
            break;
        }
    }
    g.sources_left = live.size();
    Ok(g)
}

fn kill_near(live: &mut RTree<Indexed>, p: DVec2, kill2: f64) {
    let doomed: Vec<Indexed> = live
        .locate_within_distance(p.to_array(), kill2)
        .cloned()
        .collect();
    for s in doomed {
        live.remove(&s);
    }
}

#[cfg(test)]
mod tests {
    use super::super::outline::Shape;
    use super::super::poisson;
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn grow(shape: Shape, seed: u64) -> (Outline, Growth) {
        let o = Outline::shape(shape);
        let sources = poisson::sample(&o, 2.0, 2.0, |_| 2.0, &mut ChaCha8Rng::seed_from_u64(seed));
        let g = grow_open(
            &o,
            &[o.default_root()],
            &sources,
            &VenationOptions::default(),
        )
        .expect("valid parameters");
        (o, g)
    }

    #[test]
    fn open_venation_invariants_hold_on_every_shape() {
        for shape in Shape::ALL {
            let (o, g) = grow(shape, 11);
            let n = g.positions.len();
            assert!(n > 300, "{}: {n} nodes", shape.name());
            assert!(g.positions.iter().all(|p| o.contains(*p)), "inside");
            for (p, c) in g.edges() {
                let l = g.positions[p as usize].distance(g.positions[c as usize]);
                assert!((l - 1.0).abs() <= 1e-9, "edge length {l}");
            }
            assert!(g.degrees().iter().all(|&d| d <= MAX_DEGREE));
            let tree = RTree::bulk_load(g.positions.iter().map(|p| p.to_array()).collect());
            for p in &g.positions {
                let close = tree
                    .locate_within_distance(p.to_array(), CROWDING * CROWDING * 0.99)
                    .count();
                assert_eq!(
                    close,
                    1,
                    "{}: another node within 0.5 D of {p}",
                    shape.name()
                );
            }
            assert_eq!(g.edges().count(), n - 1, "a tree");
            assert!(
                g.sources_left * 20 < g.sources_placed,
                "{}: {} of {} sources unreached",
                shape.name(),
                g.sources_left,
                g.sources_placed
            );
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let o = Outline::shape(Shape::Circle);
        let r = [o.default_root()];
        let bad_step = VenationOptions {
            step: 0.0,
            ..Default::default()
        };
        assert_eq!(
            grow_open(&o, &r, &[], &bad_step).err(),
            Some(VenationError::Step(0.0))
        );
        let bad_kill = VenationOptions {
            kill: -1.0,
            ..Default::default()
        };
        assert_eq!(
            grow_open(&o, &r, &[], &bad_kill).err(),
            Some(VenationError::Kill(-1.0))
        );
        let outside = [DVec2::new(1e3, 1e3)];
        assert!(matches!(
            grow_open(&o, &outside, &[], &VenationOptions::default()),
            Err(VenationError::RootOutside(0, ..))
        ));
    }

    #[test]
    fn same_seed_same_growth() {
        let (_, a) = grow(Shape::Ovate, 4);
        let (_, b) = grow(Shape::Ovate, 4);
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.parent, b.parent);
    }
}

/// Everything `lamina venation` needs for an open leaf: blade, sources, growth, widths.
#[derive(Clone, Debug)]
pub struct LeafOptions {
    pub growth: VenationOptions,
    /// Poisson-disk radius of the auxin sources, mm. Default 2.0.
    pub birth: f64,
    /// Murray exponent n in r_parent^n = Σ r_child^n. Default 3.
    pub murray: f64,
    /// Radius of vein tips, mm. Default 0.1.
    pub tip_radius: f64,
    pub seed: u64,
}

impl Default for LeafOptions {
    fn default() -> Self {
        LeafOptions {
            growth: VenationOptions::default(),
            birth: 2.0,
            murray: 3.0,
            tip_radius: 0.1,
            seed: 1,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LeafError {
    #[error("--birth must be a positive distance in mm, got {0}")]
    Birth(f64),
    #[error("--murray must be a finite exponent ≥ 1, got {0}")]
    Murray(f64),
    #[error("--tip-radius must be a positive distance in mm, got {0}")]
    TipRadius(f64),
    #[error(transparent)]
    Growth(#[from] VenationError),
}

/// Samples sources, grows open venation from `roots`, and returns the network with Murray
/// widths (edge radius = radius of its downstream node) and the growth record.
pub fn grow_leaf(
    outline: &Outline,
    roots: &[DVec2],
    opts: &LeafOptions,
) -> Result<(crate::network::Network, Growth), LeafError> {
    use rand::SeedableRng;
    if !(opts.birth.is_finite() && opts.birth > 0.0) {
        return Err(LeafError::Birth(opts.birth));
    }
    if !(opts.murray.is_finite() && opts.murray >= 1.0) {
        return Err(LeafError::Murray(opts.murray));
    }
    if !(opts.tip_radius.is_finite() && opts.tip_radius > 0.0) {
        return Err(LeafError::TipRadius(opts.tip_radius));
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    let b = opts.birth;
    let sources = super::poisson::sample(outline, b, b, |_| b, &mut rng);
    let g = grow_open(outline, roots, &sources, &opts.growth)?;
    let radius = super::murray::radii(&g.parent, opts.murray, opts.tip_radius);
    let mut net = crate::network::Network {
        nodes: g
            .positions
            .iter()
            .zip(&radius)
            .map(|(p, r)| crate::network::Node {
                p: p.extend(0.0),
                normal: Some(glam::DVec3::Z),
                radius: *r,
            })
            .collect(),
        edges: g
            .edges()
            .map(|(p, c)| crate::network::Edge {
                a: p,
                b: c,
                radius: radius[c as usize],
            })
            .collect(),
        ..Default::default()
    };
    net.meta.generator = Some("venation/open".into());
    net.meta.seed = Some(opts.seed);
    let params = [
        ("step", opts.growth.step),
        ("kill", opts.growth.kill),
        ("birth", opts.birth),
        ("murray", opts.murray),
        ("tip_radius", opts.tip_radius),
        ("max_iterations", opts.growth.max_iterations as f64),
    ];
    for (k, v) in params {
        net.meta.parameters.insert(k.into(), serde_json::json!(v));
    }
    Ok((net, g))
}
