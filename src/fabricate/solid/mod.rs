//! A vein network as one printable solid: a closed, oriented, 2-manifold triangle mesh.
//!
//! # Method
//! Each edge becomes a round cone: the convex hull of a ball at each end, whose radii come from
//! the network (below). The optional lamina is the blade outline extruded by a thickness; the
//! optional base is a cylinder under the root. The solid is the union of these pieces, meshed
//! as the zero set of their signed distance (the minimum over the pieces) by marching
//! tetrahedra on a sparse grid (`march`). That mesh is a manifold by construction, whatever the
//! pieces do (overlap, touch, nest): no Boolean operation on meshes is ever attempted. It is
//! checked anyway (edges, orientation, 32-bit vertex rounding) and the command fails rather
//! than write a mesh that is not closed.
//!
//! # Radii
//! At a node, the vein runs on through its two thickest edges: those take the node's radius at
//! that end, so a vein tapers smoothly from node to node. Other edges (side branches, loop
//! closers) keep their own radius, and meet the vein inside its ball. With Murray widths this
//! is a tapered tree whose joints are round.
//!
//! # Accuracy
//! Marching puts the vertices on the exact surface (to ~1e-7 mm along each grid edge); between
//! vertices the mesh cuts chords, so a vein of radius r meshed with cell h would lose roughly
//! h²/(6r²) of its volume (1 % at r = 4h) and every section a little of its area. The marched
//! mesh is therefore fitted (`fit`): each vertex moves along its normal by the mean depth of
//! the chords around it, twice (the longest move 11 µm on the 12,700-node leaf at the 35 µm
//! pixel; never out of the solid's exact box, never turning a triangle over), so the mesh lies
//! on the surface on average and a slicer lights what `print` lights from the exact distance:
//! on the demo's print leaf at 35 µm each layer's area within 0.04 % on average (0.34 %
//! before), on the 12,700-node leaf 0.03 % (0.26 %). Against manifold3d's union of the same
//! sphere hulls at 256 segments, the small fixture network (radii 0.3–1 mm) at h = 0.1 mm is
//! 0.015 % apart in volume, its symmetric difference 0.12 % (marched alone: 0.18 % and 0.28 %;
//! at 64 segments the polygons themselves are 0.29 % small). Creases between veins are rounded
//! within one cell. The default cell is the printer's pixel (35 µm): finer than that cannot be
//! printed. A vein thinner than about h may break into pieces or vanish. With `tolerance` the
//! mesh is not fitted: the simplifier holds it within the tolerance of the surface instead.
//!
//! Two veins closer than a cell's diagonal can both be sampled inside at the corners of one
//! tetrahedron: the marched mesh bridges the gap between them (the report's genus says so).
//!
//! The mesh is as fine as the cell everywhere, flat lamina included: a 50 mm leaf with its
//! lamina is millions of triangles. With `tolerance` the grid is twice the cell when every
//! piece is at least four cells thick and no supports are added (`COARSE`), and it is first
//! split finer where the marched mesh would miss by more than the tolerance allows: gaps
//! between veins that do not touch, sharp crotches where veins meet, chords on the wrong side
//! (`march::adapt`, down to 1/16 of the cell whatever the grid); then the mesh is refined where
//! chords cut creases, simplified by edge collapse within that distance of the exact surface
//! (`simplify`), and every triangle is checked whole at the end, with a proof either way
//! (`simplify`'s last check). The 12,700-node leaf at 50 mm: 4.59 M marched triangles → 282 k
//! in 45 s, 68 CPU-s and 0.91 GB, against 14.4 M → 257 k in 67 s, 115 CPU-s and 1.37 GB
//! marched at the cell, side by side (BENCHMARKS.md); with the bricks' own triangles marched
//! beside the bisection, the same mesh in 37.8 s at best (a quiet host) and 0.99 GB; with
//! fewer allocations and more of refinement and bisection's last step in parallel, the same
//! mesh in 37.0 s at best and 0.95 GB (12 % less time than before, side by side); with the
//! close cells bisected in two groups side by side (`march::halves`), crease refinement
//! looking again only at what it cut, stale collapse candidates told by when they were pushed
//! and the tidying allocating less, 281,724 triangles in 28.8–29.6 s, 53–54 CPU-s and 0.99 GB
//! (36.1–37.4 s, 58–60 CPU-s and 0.95 GB before, side by side).
//!
//! The mesh is placed by the exact box of its pieces (`placing_shift`), as `print` places them,
//! so both put the solid on the same pixels.

mod few;
mod fit;
mod march;
mod quick;
pub mod sdf;
pub mod simplify;

use glam::{DVec2, DVec3};

pub use march::MarchError;
use sdf::{Cylinder, Polygon, Primitive, Prism, RoundCone};

use crate::mesh::{find, union, TriMesh};
use crate::network::Network;

/// Triangles marching tetrahedra make per cell² of surface, an upper estimate. Measured against
/// the summed areas of the shapes (which overlap, so count more than the union's surface):
/// 7.2 for small_loop.json at --cell 0.1 and 0.02, 2.6–3.3 for the demo leaf.
const TRIANGLES_PER_CELL: f64 = 8.0;
/// The most triangles `solid` will mesh, as estimated: the 50 mm print leaf at the 35 µm pixel
/// (13.4 M triangles, 1.3 GB) estimates 32 M; at this limit the worst case is about 6 GB.
const MAX_TRIANGLES: f64 = 6e7;

/// The default cell: the DMP-SL printer's pixel, mm.
pub const DEFAULT_CELL: f64 = 0.035;
/// The compact mesh (`tolerance`) is marched on a grid `COARSE` times the cell when every piece
/// is at least twice that grid's cell thick (`Primitive::half_thickness`), and `march::adapt`
/// splits it as much finer where it must (`FINEST` · `COARSE` cells per marched cell), so the
/// narrowest gap told apart is the same: a third of the triangles to march and simplify (the
/// 12,700-node leaf at 50 mm: 115 → 68 CPU-s side by side), the tolerance held as before. Not
/// with supports: where a tree's pillars stood on their discs on the plate, the finishing steps
/// left pairs of vertices on one point that an STL's 32-bit floats merge (as they did at `cell`
/// 0.1 mm and `tolerance` 0.0125 mm, an eighth of the grid, without this). `spread` now
/// separates such pairs, but supported solids marched coarser have not been validated yet.
const COARSE: u32 = 2;
/// How much finer than the cell `march::adapt` splits, along a side.
const FINEST: u32 = 16;

#[derive(Clone, Debug)]
pub struct SolidOptions {
    /// Grid spacing, mm.
    pub cell: f64,
    /// Lamina thickness, mm (after `fit`); `None` for veins only.
    pub lamina: Option<f64>,
    /// Base cylinder under the root (node 0).
    pub base: Option<Base>,
    /// Scale so the solid's longest side is this many mm (before lamina and base are added).
    pub fit: Option<f64>,
    /// Stand the leaf up: the network's +y becomes +z (Peele prints leaves upright).
    pub upright: bool,
    /// Radius for edges the network gives none, mm (after `fit`).
    pub radius: Option<f64>,
    /// Simplify the mesh to within this distance of the exact surface, mm; `None` keeps the
    /// marched mesh.
    pub tolerance: Option<f64>,
}

impl Default for SolidOptions {
    fn default() -> Self {
        SolidOptions {
            cell: DEFAULT_CELL,
            lamina: None,
            base: None,
            fit: None,
            upright: false,
            radius: None,
            tolerance: None,
        }
    }
}

/// A disc of `diameter` and `height` mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Base {
    pub diameter: f64,
    pub height: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum SolidError {
    #[error(
        "tolerance= {} mm is more than ten cells ({} mm): the mesh would lose the veins' \
         shape; use a smaller tolerance= or a larger cell=",
        crate::text::num(*.tolerance), crate::text::num(*.cell)
    )]
    ToleranceTooLarge { tolerance: f64, cell: f64 },
    #[error(
        "at cell= {} mm no grid point falls inside the veins (the thickest is {thickest:.4} \
         mm in radius): the solid vanishes; use a cell= below the vein radius, or a larger fit=",
        crate::text::num(*.cell)
    )]
    Vanished { thickest: f64, cell: f64 },
    #[error(
        "at cell= {} mm the shapes' surface ({area:.0} mm²) would take about \
         {triangles:.2e} triangles, more than {MAX_TRIANGLES:e}: use a larger cell= or a \
         smaller fit= (or is a node far from the others?)",
        crate::text::num(*.cell)
    )]
    TooManyTriangles {
        triangles: f64,
        area: f64,
        cell: f64,
    },
    #[error("the network has no edges: nothing to make solid")]
    NoEdges,
    #[error("edge {edge}: node {node} is out of range ({nodes} nodes)")]
    EdgeOutOfRange {
        edge: usize,
        node: u32,
        nodes: usize,
    },
    #[error("node {0}: position is not finite")]
    NotFinite(usize),
    #[error(
        "edge {0} has no radius (nor have its nodes); give one with radius=, or use a network \
         with widths (venation and veins write Murray widths)"
    )]
    NoRadius(usize),
    #[error("{what} must be a positive number of mm, got {}", crate::text::num(*.value))]
    NotPositive { what: &'static str, value: f64 },
    #[error(
        "cell= {} mm is more than {} mm: give a grid cell below the veins' radius",
        crate::text::num(*.0), crate::text::num(MAX_CELL)
    )]
    CellTooLarge(f64),
    #[error(
        "fit= {} mm is more than {} mm: give the longest side of the print in mm",
        crate::text::num(*.0), crate::text::num(MAX_FIT)
    )]
    FitTooLarge(f64),
    #[error(
        "lamina= needs the blade outline, which venation stores in meta.parameters.outline; \
         this network has {0}"
    )]
    NoOutline(String),
    #[error(
        "lamina= needs a flat network (all nodes at one z); node {node} is at z = {}",
        crate::text::num(*.z)
    )]
    NotFlat { node: usize, z: f64 },
    #[error(transparent)]
    March(#[from] MarchError),
    #[error("the mesh is not a closed 2-manifold ({0}); this is a bug, please report it")]
    NotManifold(String),
    #[error(
        "vertices {0} and {1} fall on the same point in 32-bit floats; use a larger cell= or \
         a smaller model"
    )]
    Coincident(u32, u32),
}

/// The solid and what it is.
#[derive(Clone, Debug)]
pub struct Solid {
    pub mesh: TriMesh,
    pub report: SolidReport,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct SolidReport {
    pub cell_mm: f64,
    /// The grid the mesh was marched on: the cell, or `COARSE` times it for the compact mesh
    /// where every vein is that thick, split down to `finest_split_mm` where veins come close.
    pub march_cell_mm: f64,
    /// The finest split of the marching grid where veins come close, mm (0 for the full mesh,
    /// which is not split).
    pub finest_split_mm: f64,
    /// Factor the network was scaled by (`--fit`), 1 otherwise.
    pub scale: f64,
    pub vertices: usize,
    pub triangles: usize,
    pub volume_mm3: f64,
    pub area_mm2: f64,
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
    /// Connected shells of the mesh.
    pub parts: usize,
    /// Closed voids inside the solid (where pieces touch around a pocket), removed so no resin
    /// is trapped.
    pub cavities_filled: usize,
    pub genus: i64,
    /// Independent cycles of the network (E − V + components): the genus the veins alone
    /// should have when every loop stays open.
    pub network_cycles: usize,
    pub network_parts: usize,
    /// Thinnest and thickest vein radius after scaling, mm.
    pub min_radius: f64,
    pub max_radius: f64,
    pub lamina_mm: Option<f64>,
    pub base: Option<[f64; 2]>,
    pub upright: bool,
    /// What fitting the marched mesh to the surface did (`fit`; not when simplified).
    pub fitted: Option<fit::Fitted>,
    /// What simplifying did, when asked (`tolerance`).
    pub simplified: Option<simplify::Simplified>,
    pub warnings: Vec<String>,
}

/// The solid before meshing: its pieces, in the network's frame scaled by `--fit`.
#[derive(Clone, Debug)]
pub struct Shapes {
    pub prims: Vec<Primitive>,
    /// Factor the network was scaled by (`--fit`), 1 otherwise.
    pub scale: f64,
    /// The longest side of the veins' box (and the blade's) as drawn, mm: `fit` makes it
    /// `fit` mm.
    pub drawn_size: f64,
    /// Radius at each end of each edge, after scaling.
    pub ends: Vec<[f64; 2]>,
    pub min_radius: f64,
    pub max_radius: f64,
    /// Pieces added after the network's (supports): the network's genus no longer tells the
    /// solid's.
    pub added: usize,
    /// Where placing puts the shapes' origin (after standing them up), fixed once supports are
    /// planned on that placement so the print's pixels are the ones they were planned on;
    /// `None`: the shapes are centred on their own box.
    pub frame: Option<DVec3>,
}

impl Shapes {
    /// The exact box of the union: every piece's box is exact (a round cone's is its balls').
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.prims.iter().map(Primitive::bounds).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
        )
    }

    /// Signed distance to the union at `p` (in the shapes' frame), exact outside within
    /// `reach`, correct in sign everywhere.
    pub fn eval(&self, p: DVec3, reach: f64) -> f64 {
        self.prims
            .iter()
            .fold(f64::INFINITY, |d, s| d.min(s.eval(p, reach)))
    }
}

/// The largest grid cell, mm: a kilometre, far past any vein (the solid would vanish) and
/// within the grid arithmetic.
pub const MAX_CELL: f64 = 1e6;

/// The largest `fit=`, mm (a kilometre: what any printer or mill takes, with room).
pub const MAX_FIT: f64 = 1e6;

/// Checks the network and the options and builds the pieces of its solid.
pub fn shapes(net: &Network, opts: &SolidOptions) -> Result<Shapes, SolidError> {
    positive("cell=", opts.cell)?;
    // Bounded before any grid is sized from it (1e308 overflowed the grid arithmetic).
    if opts.cell > MAX_CELL {
        return Err(SolidError::CellTooLarge(opts.cell));
    }
    for (what, v) in [
        ("lamina=", opts.lamina),
        ("fit=", opts.fit),
        ("radius=", opts.radius),
        ("tolerance=", opts.tolerance),
        ("base= diameter", opts.base.map(|b| b.diameter)),
        ("base= height", opts.base.map(|b| b.height)),
    ] {
        if let Some(v) = v {
            positive(what, v)?;
        }
    }
    if let Some(fit) = opts.fit.filter(|&f| f > MAX_FIT) {
        return Err(SolidError::FitTooLarge(fit));
    }
    if let Some(t) = opts.tolerance {
        if t > 10.0 * opts.cell {
            return Err(SolidError::ToleranceTooLarge {
                tolerance: t,
                cell: opts.cell,
            });
        }
    }
    if net.edges.is_empty() {
        return Err(SolidError::NoEdges);
    }
    let n = net.nodes.len();
    for (k, e) in net.edges.iter().enumerate() {
        if let Some(&node) = [e.a, e.b].iter().find(|&&i| i as usize >= n) {
            return Err(SolidError::EdgeOutOfRange {
                edge: k,
                node,
                nodes: n,
            });
        }
    }
    if let Some(i) = net.nodes.iter().position(|v| !v.p.is_finite()) {
        return Err(SolidError::NotFinite(i));
    }

    let ends = end_radii(net, opts.radius)?;
    let outline = match opts.lamina {
        Some(_) => Some(outline(net)?),
        None => None,
    };
    // The longest side of the veins (and blade) as drawn: what `fit` sets.
    let drawn_size = {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for (e, r) in net.edges.iter().zip(&ends) {
            for (i, r) in [(e.a, r[0]), (e.b, r[1])] {
                let p = net.nodes[i as usize].p;
                lo = lo.min(p - DVec3::splat(r));
                hi = hi.max(p + DVec3::splat(r));
            }
        }
        for p in outline.iter().flatten() {
            lo = lo.min(p.extend(lo.z));
            hi = hi.max(p.extend(hi.z));
        }
        (hi - lo).max_element()
    };
    let scale = opts.fit.map_or(1.0, |size| size / drawn_size);
    let points: Vec<DVec3> = net.nodes.iter().map(|v| v.p * scale).collect();
    let ends: Vec<[f64; 2]> = ends.iter().map(|r| r.map(|r| r * scale)).collect();
    let (min_radius, max_radius) = ends
        .iter()
        .flatten()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| {
            (lo.min(r), hi.max(r))
        });

    let mut prims = Vec::with_capacity(net.edges.len() + 2);
    // Veins stand on the lamina: each end of a vein rises so that its ball sinks min(r, T)/2
    // into the sheet, never through it.
    let lift = |r: f64| opts.lamina.map_or(0.0, |t| r - r.min(t) / 2.0);
    if let (Some(t), Some(outline)) = (opts.lamina, &outline) {
        let z = points.first().map_or(0.0, |p| p.z);
        if let Some(i) = points
            .iter()
            .position(|p| (p.z - z).abs() > 1e-9 * (1.0 + z.abs()))
        {
            return Err(SolidError::NotFlat {
                node: i,
                z: net.nodes[i].p.z,
            });
        }
        let bucket = 8.0 * opts.cell;
        prims.push(Primitive::Prism(Box::new(Prism {
            outline: Polygon::new(outline.iter().map(|p| *p * scale).collect(), bucket),
            z0: z - t,
            z1: z,
        })));
    }
    let mut widest = vec![0.0f64; n];
    for (e, r) in net.edges.iter().zip(&ends) {
        let (a, b) = (e.a as usize, e.b as usize);
        widest[a] = widest[a].max(r[0]);
        widest[b] = widest[b].max(r[1]);
        prims.push(Primitive::Cone(RoundCone::new(
            points[a] + DVec3::Z * lift(r[0]),
            points[b] + DVec3::Z * lift(r[1]),
            r[0],
            r[1],
        )));
    }
    if let Some(base) = opts.base {
        // Under the root, from its centre down past the lowest point of everything else.
        let down = if opts.upright {
            DVec3::NEG_Y
        } else {
            DVec3::NEG_Z
        };
        let root = points[0] + DVec3::Z * lift(widest[0]);
        let deepest = prims
            .iter()
            .map(|p| {
                let (lo, hi) = p.bounds();
                lo.dot(down).max(hi.dot(down))
            })
            .fold(f64::NEG_INFINITY, f64::max);
        prims.push(Primitive::Cylinder(Cylinder {
            base: root,
            axis: down,
            height: deepest - root.dot(down) + base.height,
            radius: base.diameter / 2.0,
        }));
    }
    Ok(Shapes {
        prims,
        scale,
        drawn_size,
        ends,
        min_radius,
        max_radius,
        added: 0,
        frame: None,
    })
}

/// Builds the solid. `progress` follows the meshing (and simplification) and can stop it.
pub fn solid(
    net: &Network,
    opts: &SolidOptions,
    progress: &dyn crate::stage::Progress,
) -> Result<Solid, SolidError> {
    solid_of(net, opts, shapes(net, opts)?, progress)
}

/// Meshes shapes built by `shapes(net, opts)`, perhaps with pieces added (supports).
pub fn solid_of(
    net: &Network,
    opts: &SolidOptions,
    shapes: Shapes,
    progress: &dyn crate::stage::Progress,
) -> Result<Solid, SolidError> {
    let bounds = shapes.bounds();
    let Shapes {
        prims,
        scale,
        drawn_size: _,
        ends,
        min_radius,
        max_radius,
        added,
        frame,
    } = shapes;
    let n = net.nodes.len();

    // The surface the mesh will have, bounded from above (every shape's own area), in cells:
    // refused before meshing when the mesh would not fit in memory.
    let area: f64 = prims.iter().map(Primitive::area_bound).sum();
    let triangles = TRIANGLES_PER_CELL * area / (opts.cell * opts.cell);
    if triangles.is_nan() || triangles > MAX_TRIANGLES {
        return Err(SolidError::TooManyTriangles {
            triangles,
            area,
            cell: opts.cell,
        });
    }
    // Every piece counts: a lamina or a base may be thinner than the veins.
    let thinnest = prims
        .iter()
        .map(Primitive::half_thickness)
        .fold(f64::INFINITY, f64::min);
    let coarse =
        opts.tolerance.is_some() && added == 0 && thinnest >= f64::from(COARSE) * opts.cell;
    let (march_cell, finest) = if coarse {
        (f64::from(COARSE) * opts.cell, COARSE * FINEST)
    } else {
        (opts.cell, FINEST)
    };
    let gaps = opts.tolerance.map(|tol| (tol, finest));
    let (mut mesh, marched) = march::mesh_union(&prims, march_cell, gaps, progress)?;
    if mesh.triangles.is_empty() {
        let thickest = ends.iter().flatten().copied().fold(0.0, f64::max);
        return Err(SolidError::Vanished {
            thickest,
            cell: opts.cell,
        });
    }
    let cancelled = || SolidError::March(MarchError::Cancelled);
    crate::stage::checkpoint(progress).map_err(|_| cancelled())?;
    let cavities = fill_cavities(&mut mesh);
    crate::stage::checkpoint(progress).map_err(|_| cancelled())?;
    // Marched vertices lie on the surface and the chords under it: fitted so the mesh lies on it
    // on average, unless the simplifier is to hold it within a tolerance.
    let fitted = match opts.tolerance {
        Some(_) => None,
        None => {
            // Chords lie within 3/8 of a cell of the surface where veins are a cell or more
            // thick.
            let field = simplify::Field::new(&prims, opts.cell);
            Some(fit::fit(&mut mesh, &field, bounds, progress).ok_or_else(cancelled)?)
        }
    };
    // Placed as `print` places the shapes: the exact box, not the mesh's, is centred.
    let shift = frame.unwrap_or_else(|| placing_shift(&prims, opts.upright));
    let simplified = match opts.tolerance {
        None => None,
        Some(tol) => {
            let field = simplify::Field::new(&prims, march_cell + 4.0 * tol);
            // A marched edge spans at most a cell's diagonal.
            let spacing = 3f64.sqrt() * march_cell;
            // The plate, in the shapes' frame: placed z = 0 (+y stands up when upright).
            let floor = (if opts.upright { 1 } else { 2 }, -shift.z);
            let mut done = simplify::simplify(
                &mut mesh,
                &field,
                tol,
                (spacing, min_radius),
                Some(floor),
                bounds,
                progress,
            )
            .ok_or(SolidError::March(MarchError::Cancelled))?;
            done.cells_split = marched.cells_refined;
            done.gaps_left = marched.gaps_left;
            done.crotch_ends = marched.crotch_ends;
            Some(done)
        }
    };
    crate::stage::checkpoint(progress).map_err(|_| cancelled())?;
    place(&mut mesh, opts.upright, shift);
    let topo = mesh.check_manifold();
    if !topo.is_manifold() || !topo.closed {
        let first = topo
            .problems
            .first()
            .map_or("open edges".to_string(), |p| p.to_string());
        return Err(SolidError::NotManifold(first));
    }
    check_f32(&mesh)?;

    // The network's own counts: its cycles (E − V + C of the simple graph), and its parts
    // without the nodes no edge uses (they make no solid).
    let checked = net.validate();
    let adj = net.adjacency();
    let isolated = (0..n as u32).filter(|&v| adj.degree(v) == 0).count();
    let network_parts = checked.components - isolated;
    let network_cycles = checked.cycles;
    let bbox = mesh.bbox();
    let mut warnings = Vec::new();
    if min_radius < opts.cell {
        warnings.push(format!(
            "the thinnest vein (radius {min_radius:.4} mm) is thinner than the cell \
             ({:.4} mm): it may break up; use a smaller cell= or a larger fit=",
            opts.cell
        ));
    }
    if let Some(s) = simplified.as_ref().filter(|s| s.gaps_left > 0) {
        warnings.push(format!(
            "{} places still join veins that do not touch (tetrahedra at the finest split, {:.2} \
             µm, or cells past the splitting budget): there the mesh bridges a gap narrower \
             than about that or one not looked at",
            s.gaps_left,
            1000.0 * march_cell / f64::from(finest)
        ));
    }
    let genus = topo.genus.unwrap_or(0);
    if opts.lamina.is_none() && opts.base.is_none() && added == 0 {
        if (genus as usize) < network_cycles {
            warnings.push(format!(
                "genus {genus} is below the network's {network_cycles} cycles: veins thick \
                 enough to fill {} loop(s)",
                network_cycles - genus as usize
            ));
        } else if genus as usize > network_cycles {
            warnings.push(format!(
                "genus {genus} is above the network's {network_cycles} cycles: veins that are \
                 not joined in the network touch"
            ));
        }
    }
    if topo.components > network_parts.max(1) {
        warnings.push(format!(
            "{} separate shells where the network has {network_parts} part(s): thin veins broke \
             up at this cell size",
            topo.components
        ));
    }
    let report = SolidReport {
        cell_mm: opts.cell,
        march_cell_mm: march_cell,
        finest_split_mm: match opts.tolerance {
            Some(_) => march_cell / f64::from(finest),
            None => 0.0,
        },
        cavities_filled: cavities,
        scale,
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        volume_mm3: topo.volume.unwrap_or(0.0),
        area_mm2: topo.area,
        bbox_min: bbox.min.to_array(),
        bbox_max: bbox.max.to_array(),
        parts: topo.components,
        genus,
        network_cycles,
        network_parts,
        min_radius,
        max_radius,
        lamina_mm: opts.lamina,
        base: opts.base.map(|b| [b.diameter, b.height]),
        upright: opts.upright,
        fitted,
        simplified,
        warnings,
    };
    Ok(Solid { mesh, report })
}

fn positive(what: &'static str, value: f64) -> Result<(), SolidError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SolidError::NotPositive { what, value })
    }
}

/// Radius at each end of each edge (see the module doc).
fn end_radii(net: &Network, fallback: Option<f64>) -> Result<Vec<[f64; 2]>, SolidError> {
    let mut radius = Vec::with_capacity(net.edges.len());
    for (k, e) in net.edges.iter().enumerate() {
        let nodes = net.nodes[e.a as usize]
            .radius
            .max(net.nodes[e.b as usize].radius);
        let r = [e.radius, nodes, fallback.unwrap_or(0.0)]
            .into_iter()
            .find(|r| r.is_finite() && *r > 0.0)
            .ok_or(SolidError::NoRadius(k))?;
        radius.push(r);
    }
    let adj = net.adjacency();
    let mut ends: Vec<[f64; 2]> = radius.iter().map(|&r| [r, r]).collect();
    let mut around: Vec<(f64, u32)> = Vec::new();
    for v in 0..net.nodes.len() as u32 {
        let node_r = net.nodes[v as usize].radius;
        if !(node_r.is_finite() && node_r > 0.0) {
            continue;
        }
        around.clear();
        around.extend(
            adj.neighbours(v)
                .iter()
                .map(|&(_, e)| (radius[e as usize], e)),
        );
        // Thickest first; ties by edge index, so the choice is deterministic.
        around.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        for &(_, e) in around.iter().take(2) {
            let edge = &net.edges[e as usize];
            let side = usize::from(edge.a != v);
            ends[e as usize][side] = node_r;
        }
    }
    Ok(ends)
}

/// The blade outline venation stores in `meta.parameters.outline`.
fn outline(net: &Network) -> Result<Vec<DVec2>, SolidError> {
    let value = net
        .meta
        .parameters
        .get("outline")
        .ok_or_else(|| SolidError::NoOutline("none".into()))?;
    let bad = |why: String| SolidError::NoOutline(why);
    let list = value
        .as_array()
        .ok_or_else(|| bad("an outline that is not a list of [x, y] points".into()))?;
    let mut points = Vec::with_capacity(list.len());
    for (i, p) in list.iter().enumerate() {
        let xy = p
            .as_array()
            .filter(|a| a.len() == 2)
            .and_then(|a| Some(DVec2::new(a[0].as_f64()?, a[1].as_f64()?)))
            .filter(|p| p.is_finite())
            .ok_or_else(|| bad(format!("outline point {i} that is not a finite [x, y]")))?;
        points.push(xy);
    }
    if points.len() < 3 {
        return Err(bad(format!("an outline of {} point(s)", points.len())));
    }
    Ok(points)
}

/// Where placing puts the origin of `prims` (stood up when `upright`, +y becoming +z): their
/// exact box centred on the z axis, its bottom on z = 0.
pub fn placing_shift(prims: &[Primitive], upright: bool) -> DVec3 {
    let (lo, hi) = prims.iter().map(Primitive::bounds).fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), (a, b)| {
            let (a, b) = if upright {
                (crate::geom::upright(a), crate::geom::upright(b))
            } else {
                (a, b)
            };
            (lo.min(a.min(b)), hi.max(a.max(b)))
        },
    );
    DVec3::new(-0.5 * (lo.x + hi.x), -0.5 * (lo.y + hi.y), -lo.z)
}

/// Turns the mesh upright if asked (exactly: +y becomes +z), then moves it by `shift`.
fn place(mesh: &mut TriMesh, upright: bool, shift: DVec3) {
    for p in &mut mesh.positions {
        if upright {
            *p = crate::geom::upright(*p);
        }
        *p += shift;
    }
}

/// Removes the shells that enclose negative volume: voids sealed inside the solid. Returns how
/// many there were. The rest is untouched (vertex order kept, unused vertices dropped).
fn fill_cavities(mesh: &mut TriMesh) -> usize {
    let n = mesh.positions.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    for t in &mesh.triangles {
        union(&mut parent, t[0], t[1]);
        union(&mut parent, t[0], t[2]);
    }
    let mut volume = vec![0.0f64; n];
    for t in &mesh.triangles {
        let [a, b, c] = mesh.corners(t);
        volume[find(&mut parent, t[0]) as usize] += a.dot(b.cross(c)) / 6.0;
    }
    let voids = (0..n as u32)
        .filter(|&v| find(&mut parent, v) == v && volume[v as usize] < 0.0)
        .count();
    if voids == 0 {
        return 0;
    }
    let keep: Vec<bool> = (0..n as u32)
        .map(|v| volume[find(&mut parent, v) as usize] >= 0.0)
        .collect();
    let mut index = vec![u32::MAX; n];
    let mut positions = Vec::with_capacity(n);
    for (v, p) in mesh.positions.iter().enumerate() {
        if keep[v] {
            index[v] = positions.len() as u32;
            positions.push(*p);
        }
    }
    mesh.triangles.retain(|t| keep[t[0] as usize]);
    for t in &mut mesh.triangles {
        *t = t.map(|v| index[v as usize]);
    }
    mesh.positions = positions;
    voids
}

/// STL stores 32-bit floats and readers weld equal positions: no two vertices may round to one.
fn check_f32(mesh: &TriMesh) -> Result<(), SolidError> {
    use rayon::prelude::*;
    let mut keyed: Vec<([u32; 3], u32)> = mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            (
                p.as_vec3().to_array().map(|c| (c + 0.0).to_bits()),
                i as u32,
            )
        })
        .collect();
    keyed.par_sort_unstable();
    for w in keyed.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(SolidError::Coincident(
                w[0].1.min(w[1].1),
                w[0].1.max(w[1].1),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::network::{Edge, Node};

    fn bar_at(z: f64) -> Network {
        let node = |x: f64| Node {
            p: DVec3::new(x, 0.0, z),
            normal: None,
            radius: 1.0,
        };
        Network {
            nodes: vec![node(0.0), node(5.0)],
            edges: vec![Edge {
                a: 0,
                b: 1,
                radius: 1.0,
            }],
            meta: Default::default(),
        }
    }

    #[test]
    fn the_base_reaches_its_height_below_the_lowest_point_wherever_the_network_is() {
        for z in [10.0, -4.0] {
            let opts = SolidOptions {
                cell: 0.1,
                base: Some(Base {
                    diameter: 2.0,
                    height: 3.0,
                }),
                ..Default::default()
            };
            let made = solid(&bar_at(z), &opts, &crate::stage::Quiet).unwrap();
            // The bar spans z ± 1; the base goes 3 below that.
            let height = made.mesh.bbox().size().z;
            assert!((height - 5.0).abs() < 0.1, "z {z}: height {height}");
            assert_eq!((made.report.parts, made.report.genus), (1, 0));
        }
    }

    /// Seven pairs of bars of radius `r` along x, each pair's two `gap` mm apart, the pairs
    /// 1 mm apart in z and shifted in y by sevenths of 0.1 mm, so that grid points of cells up
    /// to that size fall on both sides of some of the gaps.
    fn bar_pairs(r: f64, gap: f64) -> Network {
        let node = |x: f64, y: f64, z: f64| Node {
            p: DVec3::new(x, y, z),
            normal: None,
            radius: r,
        };
        let mut net = Network::default();
        for k in 0..7 {
            let (y, z) = (0.1 * k as f64 / 7.0, (2.0 * r + 1.0) * k as f64);
            for y in [y, y + 2.0 * r + gap] {
                let a = net.nodes.len() as u32;
                net.nodes.push(node(0.0, y, z));
                net.nodes.push(node(3.0, y, z));
                net.edges.push(Edge {
                    a,
                    b: a + 1,
                    radius: r,
                });
            }
        }
        net
    }

    #[test]
    fn the_compact_mesh_is_marched_coarser_where_the_veins_allow_and_tells_gaps_apart_as_finely() {
        let cell = 0.05;
        let at = |net: &Network, tolerance: Option<f64>| {
            let opts = SolidOptions {
                cell,
                tolerance,
                ..Default::default()
            };
            solid(net, &opts, &crate::stage::Quiet).unwrap().report
        };
        // Veins 0.2 mm in radius, 5 µm apart: the compact mesh marches at 0.1 mm and splits
        // down to 0.1 / 32 mm, so every pair stays apart; marching at 0.05 mm unsplit
        // (`--full`) bridges some of the gaps.
        let bars = bar_pairs(0.2, 0.005);
        let compact = at(&bars, Some(cell / 4.0));
        assert_eq!(compact.march_cell_mm, 2.0 * cell);
        assert!((compact.finest_split_mm - cell / 16.0).abs() < 1e-12);
        assert_eq!((compact.parts, compact.network_parts), (14, 14));
        let full = at(&bars, None);
        assert_eq!((full.march_cell_mm, full.finest_split_mm), (cell, 0.0));
        assert!(full.parts < 14, "marching at the cell bridges 5 µm gaps");
        // Veins thinner than twice the cell: marched at the cell.
        let thin = at(&bar_pairs(0.08, 0.005), Some(cell / 4.0));
        assert_eq!(thin.march_cell_mm, cell);
        assert!((thin.finest_split_mm - cell / 16.0).abs() < 1e-12);
        assert_eq!(thin.parts, 14);
    }

    #[test]
    fn bad_options_and_networks_are_named() {
        let bare = Network {
            edges: vec![Edge::new(0, 1)],
            ..bar_at(0.0)
        };
        let mut bare = bare;
        bare.nodes.iter_mut().for_each(|n| n.radius = 0.0);
        let err = solid(&bare, &SolidOptions::default(), &crate::stage::Quiet).unwrap_err();
        assert!(matches!(err, SolidError::NoRadius(0)));
        let opts = SolidOptions {
            cell: -1.0,
            ..Default::default()
        };
        assert!(matches!(
            solid(&bar_at(0.0), &opts, &crate::stage::Quiet).unwrap_err(),
            SolidError::NotPositive { what: "cell=", .. }
        ));
        let mut far = bar_at(0.0);
        far.edges.push(Edge::new(0, 7));
        assert!(matches!(
            solid(&far, &SolidOptions::default(), &crate::stage::Quiet).unwrap_err(),
            SolidError::EdgeOutOfRange {
                edge: 1,
                node: 7,
                ..
            }
        ));
    }
}
