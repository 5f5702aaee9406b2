//! Venation on a triangulated surface (Gokmen §3.3, Figs. 5-8), with the same growth core as
//! the blade (`venation::grow_in`), open or closed.
//!
//! - Sources: Poisson-disk samples on the surface, by dart throwing: darts land on triangles
//!   in proportion to their area, and one is kept when no earlier source lies within the birth
//!   distance at its point (Euclidean, as Gokmen does). The birth distance is uniform, or read
//!   from the vertex colours (a channel or the luminance, interpolated across each triangle:
//!   dark = dense, as in the blade's density maps).
//! - Growth: a node's pull (the sum of unit vectors to the sources that pick it, those within
//!   `reach` only: Gokmen's distance threshold) is projected onto the tangent plane at the node,
//!   a step of D is taken along it, and the new node is snapped to the closest point of the
//!   surface. D stays below the mean edge length (Gokmen §3.3). A step whose chord leaves the
//!   surface by more than the edge tolerance is not taken.
//! - Closest points: `mesh::closest::SurfaceIndex`, our own bounding-volume hierarchy (an rstar
//!   tree of triangle boxes searched nearest-box first, stopping once a box lies beyond the best
//!   exact distance; tested against brute force). We chose it over parry3d-f64 to keep one
//!   spatial-index crate in the build (rstar, which jagua-rs uses too).
//! - Every node stores the surface normal at its point (interpolated vertex normals): the
//!   reference direction d⁰ that planarization takes.
//! - Edges may not cross: two edges that come within a twentieth of D of each other, away from
//!   a shared node, count as crossing on the surface.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rstar::RTree;

use super::leaf::{growth_network, MAX_SOURCES};
use super::report::Quality;
use super::space::Domain;
use super::venation::{self, BladeGrowth, Growth, Mode, Observer, VenationError, VenationOptions};
use crate::mesh::closest::SurfaceIndex;
use crate::mesh::TriMesh;
use crate::network::Network;

/// Where a root sits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Root {
    Vertex(u32),
    /// The centroid of a triangle.
    Triangle(u32),
    /// The closest point of the surface to this one.
    Point(DVec3),
}

/// Which vertex colour drives the density.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    Red,
    Green,
    Blue,
    /// Rec. 709 luminance.
    Luminance,
}

impl Channel {
    fn of(self, c: [f32; 3]) -> f64 {
        let [r, g, b] = c.map(f64::from);
        match self {
            Channel::Red => r,
            Channel::Green => g,
            Channel::Blue => b,
            Channel::Luminance => 0.2126 * r + 0.7152 * g + 0.0722 * b,
        }
    }
}

/// Dart-thrown samples fill a surface of area A with about `FILL`·A / r² points (measured);
/// turns a wanted source count into a radius.
pub const FILL: f64 = 0.60;

/// Darts thrown per source expected, when sampling the initial sources.
const DARTS_PER_SOURCE: usize = 12;

/// Edges closer than this many D, away from a shared node, cross on the surface.
const TOUCH: f64 = 0.05;

#[derive(Clone, Debug)]
pub struct SurfaceOptions {
    /// Growth parameters; the blade fields must stay at no blade growth.
    pub growth: VenationOptions,
    /// The birth distance where the surface is darkest and lightest, mm (equal without a
    /// density channel).
    pub birth_min: f64,
    pub birth_max: f64,
    /// Read density from this vertex colour.
    pub density: Option<Channel>,
    /// Sources farther than this from a node do not pull it, mm. Default 4 × birth_max.
    pub reach: Option<f64>,
    /// A growth step or loop edge whose chord leaves the surface by more than this is not
    /// made; edges farther off are reported. Default D / 4.
    pub edge_tolerance: Option<f64>,
    /// Murray exponent. Default 3.
    pub murray: f64,
    /// Radius of vein tips and of loop-closing edges, mm.
    pub tip_radius: f64,
    pub seed: u64,
}

impl SurfaceOptions {
    /// The defaults for a mesh and a wanted source count: the birth distance that places about
    /// that many (with a density channel the darkest, the lightest twice it), D = min(birth / 2,
    /// 0.9 × mean edge length), kill 1.5 D, tips D / 7.5.
    pub fn for_mesh(mesh: &TriMesh, mode: Mode, sources: usize, density: Option<Channel>) -> Self {
        let birth_min = birth_for_count(mesh, sources, density);
        let step = default_step(mesh, birth_min);
        SurfaceOptions {
            growth: VenationOptions {
                mode,
                step,
                kill: 1.5 * step,
                ..Default::default()
            },
            birth_min,
            birth_max: if density.is_some() {
                2.0 * birth_min
            } else {
                birth_min
            },
            density,
            reach: None,
            edge_tolerance: None,
            murray: 3.0,
            tip_radius: step / 7.5,
            seed: 1,
        }
    }

    pub fn reach(&self) -> f64 {
        self.reach.unwrap_or(4.0 * self.birth_max)
    }

    pub fn edge_tolerance(&self) -> f64 {
        self.edge_tolerance.unwrap_or(0.25 * self.growth.step)
    }
}

/// The default D for a birth distance: half of it, kept below the mean edge length.
pub fn default_step(mesh: &TriMesh, birth_min: f64) -> f64 {
    (0.5 * birth_min).min(0.9 * mean_edge_length(mesh))
}

/// The birth distance that places about `count` sources on the mesh. With a density channel
/// it is the darkest one, the lightest being twice it (the CLI's default range).
pub fn birth_for_count(mesh: &TriMesh, count: usize, density: Option<Channel>) -> f64 {
    let light = |v: u32| match (density, &mesh.colors) {
        (Some(ch), Some(c)) => ch.of(c[v as usize]).clamp(0.0, 1.0),
        _ => 0.0,
    };
    let weighted: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            let l = t.iter().map(|&v| light(v)).sum::<f64>() / 3.0;
            0.5 * (b - a).cross(c - a).length() / ((1.0 + l) * (1.0 + l))
        })
        .sum();
    (FILL * weighted / count.max(1) as f64).sqrt()
}

/// The mean length of the mesh's triangle sides (each shared side counted once per triangle).
pub fn mean_edge_length(mesh: &TriMesh) -> f64 {
    let mut sum = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = mesh.corners(t);
        sum += a.distance(b) + b.distance(c) + c.distance(a);
    }
    sum / (3 * mesh.triangles.len()).max(1) as f64
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SurfaceError {
    #[error(transparent)]
    Venation(#[from] VenationError),
    #[error("the surface has no triangles")]
    NoTriangles,
    #[error("the surface has no area")]
    NoArea,
    #[error("root= {0}: the mesh has {1} vertices")]
    RootVertex(u32, usize),
    #[error("root= {0}: vertex {0} is on no triangle")]
    LooseVertex(u32),
    #[error("root= t{0}: the mesh has {1} triangles")]
    RootTriangle(u32, usize),
    #[error("root=: the point {0} is not finite")]
    RootPoint(DVec3),
    #[error("density_channel=: the surface has no vertex colours")]
    NoColours,
    #[error("birth_min= {min} and birth_max= {max} must be positive with min <= max")]
    Birth { min: f64, max: f64 },
    #[error(
        "step= {step} mm is not below the mean edge length of the mesh ({edge:.4} mm): steps \
         that long leave the surface (Gokmen §3.3)"
    )]
    StepTooLong { step: f64, edge: f64 },
    #[error("reach= must be a positive distance in mm, got {0}")]
    Reach(f64),
    #[error("edge_tolerance= must be a positive distance in mm, got {0}")]
    EdgeTolerance(f64),
    #[error("venation on a surface has no blade growth (blade=, r=)")]
    BladeGrowth,
    #[error(
        "a birth distance of {birth} mm would place about {count} sources on this surface \
         (at most {MAX_SOURCES})"
    )]
    TooManySources { birth: f64, count: f64 },
}

/// The surface as the growth core's domain.
pub struct Surface<'a> {
    mesh: &'a TriMesh,
    index: SurfaceIndex<'a>,
    /// Per vertex, 0 (dark, dense) to 1 (light, sparse); None: uniform.
    lightness: Option<Vec<f64>>,
    birth: (f64, f64),
    /// Running sum of triangle areas, for darts.
    cumulative: Vec<f64>,
    reach: f64,
    touch: f64,
    edge_tolerance: f64,
    /// The body (connected piece of triangles sharing vertices) of each triangle.
    body: Vec<u32>,
    bodies: usize,
    /// The bodies growth may use (those with a root); every body until the roots are placed.
    rooted: Option<Vec<bool>>,
}

impl<'a> Surface<'a> {
    /// The surface for sampling: birth distances from `birth.0` (darkest) to `birth.1`
    /// (lightest), no growth limits yet.
    fn sampler(
        mesh: &'a TriMesh,
        birth: (f64, f64),
        density: Option<Channel>,
    ) -> Result<Self, SurfaceError> {
        check_sampling(mesh, birth.0, birth.1)?;
        let lightness = match density {
            None => None,
            Some(ch) => Some(
                mesh.colors
                    .as_ref()
                    .ok_or(SurfaceError::NoColours)?
                    .iter()
                    .map(|c| ch.of(*c).clamp(0.0, 1.0))
                    .collect(),
            ),
        };
        let mut total = 0.0;
        let cumulative = mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                total += 0.5 * (b - a).cross(c - a).length();
                total
            })
            .collect();
        let (body, bodies) = triangle_bodies(mesh);
        Ok(Surface {
            mesh,
            index: SurfaceIndex::new(mesh),
            lightness,
            birth,
            cumulative,
            reach: f64::INFINITY,
            touch: 0.0,
            edge_tolerance: f64::INFINITY,
            body,
            bodies,
            rooted: None,
        })
    }

    /// The surface for growth with `opts`' reach, crossing distance and edge tolerance.
    fn for_growth(mesh: &'a TriMesh, opts: &SurfaceOptions) -> Result<Self, SurfaceError> {
        Ok(Surface {
            reach: opts.reach(),
            touch: TOUCH * opts.growth.step,
            edge_tolerance: opts.edge_tolerance(),
            ..Surface::sampler(mesh, (opts.birth_min, opts.birth_max), opts.density)?
        })
    }

    fn area(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// The birth distance at barycentric point `bary` of triangle `t`.
    fn birth_at(&self, t: u32, bary: [f64; 3]) -> f64 {
        let (lo, hi) = self.birth;
        match &self.lightness {
            None => hi,
            Some(light) => {
                let tri = self.mesh.triangles[t as usize];
                let l: f64 = (0..3).map(|k| light[tri[k] as usize] * bary[k]).sum();
                lo + (hi - lo) * l
            }
        }
    }

    /// A point on the surface, uniform by area: its triangle and barycentric coordinates.
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> (u32, [f64; 3], DVec3) {
        let x = rng.random_range(0.0..self.area());
        let t = self
            .cumulative
            .partition_point(|&c| c <= x)
            .min(self.cumulative.len() - 1);
        let (mut u, mut v): (f64, f64) = (rng.random(), rng.random());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let bary = [1.0 - u - v, u, v];
        let [a, b, c] = self.mesh.corners(&self.mesh.triangles[t]);
        (t as u32, bary, a * bary[0] + b * bary[1] + c * bary[2])
    }

    /// The largest distance of the chord a–b from the surface, at `samples` inner points.
    fn chord_gap(&self, a: DVec3, b: DVec3, samples: usize) -> f64 {
        (1..=samples)
            .map(|k| {
                let p = a.lerp(b, k as f64 / (samples + 1) as f64);
                self.index.closest(p).map_or(f64::INFINITY, |c| c.distance)
            })
            .fold(0.0, f64::max)
    }

    /// The closest point of the surface and the normal there.
    pub fn snap(&self, p: DVec3) -> Option<(DVec3, DVec3, f64)> {
        let c = self.index.closest(p)?;
        Some((c.point, self.index.normal(&c), c.distance))
    }

    /// The body of the surface point closest to `p`.
    fn body_of(&self, p: DVec3) -> Option<u32> {
        let c = self.index.closest(p)?;
        Some(self.body[c.triangle as usize])
    }

    /// Whether growth may use body `b` (it has a root).
    fn live(&self, b: u32) -> bool {
        self.rooted.as_ref().is_none_or(|r| r[b as usize])
    }
}

impl Domain for Surface<'_> {
    type V = DVec3;

    fn reach(&self) -> f64 {
        self.reach
    }

    /// A step snapped onto another body (one passing close by) is not taken: growth stays on
    /// the body it started on.
    fn step(&self, from: DVec3, dir: DVec3, len: f64) -> Option<DVec3> {
        let here = self.index.closest(from)?;
        let n = self.index.normal(&here);
        let tangent = (dir - n * dir.dot(n)).try_normalize()?;
        let there = self.index.closest(from + tangent * len)?;
        let at = there.point;
        let same_body = self.body[here.triangle as usize] == self.body[there.triangle as usize];
        (same_body && self.chord_gap(from, at, 1) <= self.edge_tolerance).then_some(at)
    }

    fn holds_edge(&self, a: DVec3, b: DVec3) -> bool {
        self.chord_gap(a, b, 3) <= self.edge_tolerance && self.body_of(a) == self.body_of(b)
    }

    fn touch(&self, a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> bool {
        crate::geom::segment_distance(a, b, c, d) <= self.touch
    }

    fn dart<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<(DVec3, f64)> {
        let (t, bary, p) = self.sample(rng);
        self.live(self.body[t as usize])
            .then(|| (p, self.birth_at(t, bary)))
    }

    fn birth_max(&self) -> f64 {
        match &self.lightness {
            None => self.birth.1,
            Some(light) => {
                let l = light.iter().copied().fold(0.0, f64::max);
                self.birth.0 + (self.birth.1 - self.birth.0) * l
            }
        }
    }
}

/// The figures of a surface venation: the blade report's, plus how well it keeps to the
/// surface.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceQuality {
    #[serde(flatten)]
    pub quality: Quality,
    /// Bodies (connected pieces) of the mesh, and what growth left out on those without a root.
    pub unrooted: Unrooted,
    pub sources_placed: usize,
    pub sources_left: usize,
    /// The mesh's bounding-box diagonal, mm.
    pub mesh_size: f64,
    /// Nodes farther than 1e-6 × mesh size from the surface.
    pub nodes_off_surface: usize,
    pub max_node_distance: f64,
    /// Edges whose chord leaves the surface by more than `edge_tolerance` (7 points checked
    /// along each).
    pub edges_off_surface: usize,
    pub max_edge_distance: f64,
    pub edge_tolerance: f64,
}

impl SurfaceQuality {
    pub fn lines(&self) -> Vec<String> {
        let mut lines = self.quality.lines();
        lines.push(format!(
            "incomplete growth: {} of {} sources left unreached",
            self.sources_left, self.sources_placed
        ));
        lines.push(format!(
            "nodes off the surface (> {:.2e} mm): {} (farthest {:.2e} mm); edges leaving it by \
             more than {:.4} mm: {} (farthest {:.4} mm)",
            1e-6 * self.mesh_size,
            self.nodes_off_surface,
            self.max_node_distance,
            self.edge_tolerance,
            self.edges_off_surface,
            self.max_edge_distance
        ));
        lines
    }
}

#[derive(Clone, Debug)]
pub struct SurfaceVeins {
    pub network: Network,
    pub growth: Growth<DVec3>,
    pub quality: SurfaceQuality,
}

/// Places sources on the surface and grows venation from `roots` (the lowest vertex when
/// empty). The network's tree edges come first, then `meta.parameters.loop_edges` loop edges.
/// An observer sees the growth every few steps (positions and live sources in space, no blade).
pub fn grow_on_surface(
    mesh: &TriMesh,
    roots: &[Root],
    opts: &SurfaceOptions,
    observer: Option<Observer<DVec3>>,
) -> Result<SurfaceVeins, SurfaceError> {
    let mut surface = Surface::for_growth(mesh, opts)?;
    check(mesh, opts)?;
    let all = bodies(mesh, &surface.body, surface.bodies);
    let roots = root_points(mesh, &surface, &all, roots)?;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let placed = poisson(&surface, &mut rng);
    // Growth stays on the body it starts on: sources on a body without a root are left out.
    let mut rooted = vec![false; surface.bodies];
    for &(_, b) in &roots {
        rooted[b as usize] = true;
    }
    let roots: Vec<DVec3> = roots.iter().map(|r| r.0).collect();
    let unrooted = Unrooted::of(&surface, &all, &rooted, &placed);
    let sources: Vec<DVec3> = placed
        .iter()
        .filter(|(_, t)| rooted[surface.body[*t as usize] as usize])
        .map(|(p, _)| *p)
        .collect();
    surface.rooted = Some(rooted);
    let (growth, surface) =
        venation::grow_in(surface, &roots, &sources, &opts.growth, &mut rng, observer)?;
    let size = mesh.bbox().diagonal();
    let snapped: Vec<(DVec3, f64)> = growth
        .positions
        .par_iter()
        .map(|p| {
            surface
                .snap(*p)
                .map(|(_, n, d)| (n, d))
                .ok_or(SurfaceError::NoTriangles)
        })
        .collect::<Result<_, _>>()?;
    let normals: Vec<DVec3> = snapped.iter().map(|s| s.0).collect();
    let off = (
        snapped.iter().filter(|s| s.1 > 1e-6 * size).count(),
        snapped.iter().map(|s| s.1).fold(0.0, f64::max),
    );
    let network = to_network(&growth, &normals, opts);
    let gaps: Vec<f64> = network
        .edges
        .par_iter()
        .map(|e| {
            surface.chord_gap(
                network.nodes[e.a as usize].p,
                network.nodes[e.b as usize].p,
                7,
            )
        })
        .collect();
    let edge_off = (
        gaps.iter().filter(|&&g| g > surface.edge_tolerance).count(),
        gaps.iter().copied().fold(0.0, f64::max),
    );
    let mut quality = Quality::of(&network, growth.roots);
    quality.crossings = crossings(&network, surface.touch);
    let quality = SurfaceQuality {
        quality,
        unrooted,
        sources_placed: growth.sources_placed,
        sources_left: growth.sources_left,
        mesh_size: size,
        nodes_off_surface: off.0,
        max_node_distance: off.1,
        edges_off_surface: edge_off.0,
        max_edge_distance: edge_off.1,
        edge_tolerance: surface.edge_tolerance,
    };
    Ok(SurfaceVeins {
        network,
        growth,
        quality,
    })
}

/// A mesh with area, and birth distances that are positive, ordered, and place no more than
/// `MAX_SOURCES` points.
fn check_sampling(mesh: &TriMesh, birth_min: f64, birth_max: f64) -> Result<(), SurfaceError> {
    if mesh.triangles.is_empty() {
        return Err(SurfaceError::NoTriangles);
    }
    let area = mesh.area();
    if area <= 0.0 {
        return Err(SurfaceError::NoArea);
    }
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !(positive(birth_min) && positive(birth_max) && birth_min <= birth_max) {
        return Err(SurfaceError::Birth {
            min: birth_min,
            max: birth_max,
        });
    }
    let count = FILL * area / (birth_min * birth_min);
    if count > MAX_SOURCES as f64 {
        return Err(SurfaceError::TooManySources {
            birth: birth_min,
            count,
        });
    }
    Ok(())
}

/// The growth parameters (the mesh and birth distances are checked by `Surface::sampler`).
fn check(mesh: &TriMesh, opts: &SurfaceOptions) -> Result<(), SurfaceError> {
    let g = &opts.growth;
    if g.blade != BladeGrowth::None {
        return Err(SurfaceError::BladeGrowth);
    }
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !positive(g.step) {
        return Err(VenationError::Step(g.step).into());
    }
    let edge = mean_edge_length(mesh);
    if g.step >= edge {
        return Err(SurfaceError::StepTooLong { step: g.step, edge });
    }
    if !positive(opts.reach()) {
        return Err(SurfaceError::Reach(opts.reach()));
    }
    if !positive(opts.edge_tolerance()) {
        return Err(SurfaceError::EdgeTolerance(opts.edge_tolerance()));
    }
    Ok(())
}

/// Which vertices some triangle uses.
pub fn used_vertices(mesh: &TriMesh) -> Vec<bool> {
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    used
}

/// The lowest vertex of any triangle (least z, then y, then x): the default root.
pub fn lowest_vertex(mesh: &TriMesh) -> Option<u32> {
    let used = used_vertices(mesh);
    (0..mesh.positions.len())
        .filter(|&v| used[v])
        .min_by(|&a, &b| {
            let (pa, pb) = (mesh.positions[a], mesh.positions[b]);
            (pa.z, pa.y, pa.x)
                .partial_cmp(&(pb.z, pb.y, pb.x))
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .map(|v| v as u32)
}

/// How many bodies of growth can not reach, as a count. At most this many are named.
pub const BODIES_NAMED: usize = 100;

/// The mesh's bodies and the sources placed on bodies no root is on (growth cannot reach them).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Unrooted {
    pub bodies: usize,
    pub bodies_without_root: usize,
    pub sources_left_out: usize,
    /// The first `BODIES_NAMED` bodies without a root, in body order.
    pub without_root: Vec<Body>,
}

/// A body (connected piece of triangles) of a mesh, as a user can find it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Body {
    /// Bodies are numbered from 0 in the order of their first triangle.
    pub body: u32,
    pub triangles: usize,
    /// Its lowest vertex (least z, then y, then x): the root it would get by default.
    pub lowest_vertex: u32,
    pub at: [f64; 3],
    /// Sources placed on it (left out when it has no root).
    pub sources: usize,
}

impl Unrooted {
    /// From the mesh's `bodies` (as `bodies()` gives them), which have a root, and the sources
    /// placed with their triangles.
    fn of(surface: &Surface, bodies: &[Body], rooted: &[bool], placed: &[(DVec3, u32)]) -> Self {
        let mut sources = vec![0usize; surface.bodies];
        for (_, t) in placed {
            sources[surface.body[*t as usize] as usize] += 1;
        }
        let lacking: Vec<u32> = (0..surface.bodies as u32)
            .filter(|&b| !rooted[b as usize])
            .collect();
        Unrooted {
            bodies: surface.bodies,
            bodies_without_root: lacking.len(),
            sources_left_out: lacking.iter().map(|&b| sources[b as usize]).sum(),
            without_root: lacking
                .iter()
                .take(BODIES_NAMED)
                .map(|&b| Body {
                    sources: sources[b as usize],
                    ..bodies[b as usize].clone()
                })
                .collect(),
        }
    }
}

/// The body of each triangle (union of triangles sharing a vertex, numbered in the order of
/// their first triangle) and the number of bodies.
fn triangle_bodies(mesh: &TriMesh) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    for t in &mesh.triangles {
        crate::mesh::union(&mut parent, t[0], t[1]);
        crate::mesh::union(&mut parent, t[0], t[2]);
    }
    let mut number = std::collections::HashMap::new();
    let body = mesh
        .triangles
        .iter()
        .map(|t| {
            let r = crate::mesh::find(&mut parent, t[0]);
            let next = number.len() as u32;
            *number.entry(r).or_insert(next)
        })
        .collect();
    (body, number.len())
}

/// Each body's triangle count and lowest vertex (`sources` left at 0).
fn bodies(mesh: &TriMesh, body: &[u32], count: usize) -> Vec<Body> {
    let key = |v: u32| {
        let p = mesh.positions[v as usize];
        (p.z, p.y, p.x)
    };
    let mut out: Vec<Option<Body>> = vec![None; count];
    for (t, &b) in mesh.triangles.iter().zip(body) {
        let entry = out[b as usize].get_or_insert(Body {
            body: b,
            triangles: 0,
            lowest_vertex: t[0],
            at: mesh.positions[t[0] as usize].to_array(),
            sources: 0,
        });
        entry.triangles += 1;
        for &v in t {
            if key(v) < key(entry.lowest_vertex) {
                entry.lowest_vertex = v;
                entry.at = mesh.positions[v as usize].to_array();
            }
        }
    }
    out.into_iter().flatten().collect()
}

/// Root positions on the surface and their bodies; the lowest vertex of each body when none
/// are given.
fn root_points(
    mesh: &TriMesh,
    surface: &Surface,
    bodies: &[Body],
    roots: &[Root],
) -> Result<Vec<(DVec3, u32)>, SurfaceError> {
    if roots.is_empty() {
        return Ok(bodies
            .iter()
            .map(|b| (DVec3::from_array(b.at), b.body))
            .collect());
    }
    let mut vertex_body = vec![u32::MAX; mesh.positions.len()];
    for (t, &b) in mesh.triangles.iter().zip(&surface.body) {
        for &v in t {
            vertex_body[v as usize] = b;
        }
    }
    roots
        .iter()
        .map(|r| match *r {
            Root::Vertex(v) => match vertex_body.get(v as usize) {
                None => Err(SurfaceError::RootVertex(v, mesh.positions.len())),
                Some(&u32::MAX) => Err(SurfaceError::LooseVertex(v)),
                Some(&b) => Ok((mesh.positions[v as usize], b)),
            },
            Root::Triangle(t) => {
                let tri = mesh
                    .triangles
                    .get(t as usize)
                    .ok_or(SurfaceError::RootTriangle(t, mesh.triangles.len()))?;
                let [a, b, c] = mesh.corners(tri);
                Ok(((a + b + c) / 3.0, surface.body[t as usize]))
            }
            Root::Point(p) if !p.is_finite() => Err(SurfaceError::RootPoint(p)),
            Root::Point(p) => {
                let c = surface.index.closest(p).ok_or(SurfaceError::NoTriangles)?;
                Ok((c.point, surface.body[c.triangle as usize]))
            }
        })
        .collect()
}

/// Poisson-disk points on a mesh (as the venation sources are placed): the birth distance from
/// `birth_min` (darkest) to `birth_max` (lightest) by the density channel, or `birth_max`.
pub fn poisson_points(
    mesh: &TriMesh,
    birth_min: f64,
    birth_max: f64,
    density: Option<Channel>,
    rng: &mut impl Rng,
) -> Result<Vec<DVec3>, SurfaceError> {
    let surface = Surface::sampler(mesh, (birth_min, birth_max), density)?;
    Ok(poisson(&surface, rng).into_iter().map(|(p, _)| p).collect())
}

/// Poisson-disk sources on the surface by dart throwing: each dart lands uniformly by area and
/// is kept when no kept source lies within the birth distance at its point. Each comes with its
/// triangle.
fn poisson(surface: &Surface, rng: &mut impl Rng) -> Vec<(DVec3, u32)> {
    let mesh = surface.mesh;
    let expected: f64 = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let [a, b, c] = mesh.corners(t);
            let r = surface.birth_at(i as u32, [1.0 / 3.0; 3]);
            FILL * 0.5 * (b - a).cross(c - a).length() / (r * r)
        })
        .sum();
    let darts = (expected.ceil() as usize).max(1) * DARTS_PER_SOURCE;
    let mut tree: RTree<[f64; 3]> = RTree::new();
    let mut kept = Vec::new();
    for _ in 0..darts {
        let (t, bary, p) = surface.sample(rng);
        let r = surface.birth_at(t, bary);
        if tree
            .locate_within_distance(p.to_array(), r * r)
            .next()
            .is_none()
        {
            tree.insert(p.to_array());
            kept.push((p, t));
        }
    }
    kept
}

/// The growth as a network (`leaf::growth_network` with the surface normals) and the surface
/// parameters.
fn to_network(g: &Growth<DVec3>, normals: &[DVec3], opts: &SurfaceOptions) -> Network {
    let mut net = growth_network(
        g,
        |i| (g.positions[i], normals[i]),
        &opts.growth,
        (opts.murray, opts.tip_radius),
        "venation/surface",
        opts.seed,
    );
    let p = &mut net.meta.parameters;
    let mut put = |k: &str, v: serde_json::Value| {
        p.insert(k.into(), v);
    };
    put("birth_min", opts.birth_min.into());
    put("birth_max", opts.birth_max.into());
    put("density", serde_json::json!(opts.density));
    put("reach", opts.reach().into());
    put("edge_tolerance", opts.edge_tolerance().into());
    net
}

/// Edge pairs that come within `tol` of each other away from a shared node.
fn crossings(net: &Network, tol: f64) -> usize {
    use rstar::primitives::{GeomWithData, Rectangle};
    use rstar::AABB;
    type EdgeBox = GeomWithData<Rectangle<[f64; 3]>, u32>;
    let seg = |i: u32| {
        let e = &net.edges[i as usize];
        (net.nodes[e.a as usize].p, net.nodes[e.b as usize].p)
    };
    let pad = DVec3::splat(tol);
    let tree: RTree<EdgeBox> = RTree::bulk_load(
        (0..net.edges.len() as u32)
            .map(|i| {
                let (a, b) = seg(i);
                EdgeBox::new(
                    Rectangle::from_corners(
                        (a.min(b) - pad).to_array(),
                        (a.max(b) + pad).to_array(),
                    ),
                    i,
                )
            })
            .collect(),
    );
    let mut count = 0;
    for i in 0..net.edges.len() as u32 {
        let (a, b) = seg(i);
        let ei = net.edges[i as usize];
        let bx = AABB::from_corners((a.min(b) - pad).to_array(), (a.max(b) + pad).to_array());
        for other in tree.locate_in_envelope_intersecting(&bx) {
            let j = other.data;
            let ej = net.edges[j as usize];
            if j <= i || [ej.a, ej.b].iter().any(|x| *x == ei.a || *x == ei.b) {
                continue;
            }
            let (c, d) = seg(j);
            if crate::geom::segment_distance(a, b, c, d) <= tol {
                count += 1;
            }
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two 20 × 20 mm plates side by side in z = 0, `gap` apart along x, each a 20 × 20 grid:
    /// two bodies.
    fn split_plate(gap: f64) -> TriMesh {
        let left = TriMesh::grid(20, 20, |i, j| DVec3::new(i as f64 - 20.0, j as f64, 0.0));
        let right = TriMesh::grid(20, 20, |i, j| DVec3::new(i as f64 + gap, j as f64, 0.0));
        let n = left.positions.len() as u32;
        TriMesh {
            positions: [left.positions, right.positions].concat(),
            triangles: left
                .triangles
                .into_iter()
                .chain(right.triangles.into_iter().map(|t| t.map(|v| v + n)))
                .collect(),
            colors: None,
        }
    }

    #[test]
    fn growth_stays_on_each_body_across_a_gap_narrower_than_a_step() {
        let gap = 0.05;
        let mesh = split_plate(gap);
        let opts = SurfaceOptions::for_mesh(&mesh, Mode::Closed, 300, None);
        assert!(opts.growth.step > 10.0 * gap, "D = {}", opts.growth.step);
        let grown = grow_on_surface(&mesh, &[], &opts, None).unwrap();
        let u = &grown.quality.unrooted;
        assert_eq!((u.bodies, u.bodies_without_root), (2, 0));
        let net = &grown.network;
        let side = |n: u32| net.nodes[n as usize].p.x > 0.5 * gap;
        assert!(net.nodes.iter().any(|n| n.p.x > gap) && net.nodes.iter().any(|n| n.p.x < 0.0));
        let across = net.edges.iter().filter(|e| side(e.a) != side(e.b)).count();
        assert_eq!(across, 0);
        assert_eq!(net.component_labels().1, 2);
    }

    #[test]
    fn a_body_without_a_root_is_named_with_its_sources_and_lowest_vertex() {
        let mesh = split_plate(1.0);
        let opts = SurfaceOptions::for_mesh(&mesh, Mode::Open, 300, None);
        let grown = grow_on_surface(&mesh, &[Root::Vertex(0)], &opts, None).unwrap();
        let u = &grown.quality.unrooted;
        assert_eq!((u.bodies, u.bodies_without_root), (2, 1));
        let [b] = &u.without_root[..] else {
            panic!("{u:?}")
        };
        // The right plate: its first vertex (1, 0, 0) is its lowest (least z, y, x).
        assert_eq!((b.body, b.triangles, b.lowest_vertex), (1, 800, 441));
        assert_eq!(b.at, [1.0, 0.0, 0.0]);
        assert!(b.sources > 0);
        assert_eq!(u.sources_left_out, b.sources);
        assert!(grown.network.nodes.iter().all(|n| n.p.x <= 0.0));
        assert_eq!(grown.growth.sources_placed + b.sources, {
            let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
            let s = Surface::for_growth(&mesh, &opts).unwrap();
            poisson(&s, &mut rng).len()
        });
    }
}
