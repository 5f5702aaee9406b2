//! DXF entities as polylines: LINE, POINT, LWPOLYLINE and POLYLINE (bulges flattened), ARC,
//! CIRCLE, ELLIPSE and SPLINE (flattened within the chord tolerance), INSERT and MINSERT
//! (blocks expanded, nested, with scale, rotation and arrays). 2D entities are taken from their
//! object coordinate system (OCS) to world coordinates. Anything else, and paper space, is
//! counted by its DXF name and skipped.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use dxf::entities::{Entity, EntityType, Insert, LwPolyline, Polyline, Spline, Vertex};
use dxf::{Block, Drawing, Point};
use glam::{DAffine3, DMat3, DVec2, DVec3};

use super::dxf_hatch::Hatch;
use crate::geom::curves::{self, Nurbs};

/// Blocks nest at most this deep (AutoCAD allows far less in practice); deeper is refused as a
/// likely cycle.
const MAX_NESTING: usize = 32;

/// The most points a drawing may expand to (curves flattened, blocks inserted) when asked to
/// (`ReadOptions::max_points`): about 4 GB of working memory through welding.
pub const MAX_POINTS: usize = 20_000_000;

/// The expansion a drawing gets unless asked for more: a million points, plus 20 per byte of
/// the file, up to `MAX_POINTS`. A MINSERT array of nested arrays reaches millions of points
/// from a few bytes, and the work that follows (welding, the crossing search) costs about a
/// second per million: a small file stays quick, a large drawing still reads whole (the 52 MB
/// benchmark drawing expands to 4.8 M points, under its 1 G).
pub fn default_max_points(file_bytes: usize) -> usize {
    file_bytes
        .saturating_mul(20)
        .saturating_add(1_000_000)
        .min(MAX_POINTS)
}

/// What the whole file shares while its entities are collected.
pub(super) struct Context<'a> {
    /// Chord tolerance in drawing units.
    pub tol: f64,
    /// Block definitions by upper-case name.
    pub blocks: HashMap<String, &'a Block>,
    /// The HATCH entities of each block definition whose boundaries are read (none unless
    /// asked), with the line each starts on.
    pub hatches: &'a HashMap<String, Vec<(usize, Hatch)>>,
}

impl<'a> Context<'a> {
    pub fn new(
        drawing: &'a Drawing,
        tol: f64,
        hatches: &'a HashMap<String, Vec<(usize, Hatch)>>,
    ) -> Self {
        let blocks = drawing
            .blocks()
            .map(|b| (b.name.to_ascii_uppercase(), b))
            .collect();
        Context {
            tol,
            blocks,
            hatches,
        }
    }
}

/// What one drawing (or part of one) holds for a network.
pub(super) struct Collected {
    pub points: Vec<DVec3>,
    pub segments: Vec<(u32, u32)>,
    pub skipped: BTreeMap<String, usize>,
    /// Blocks expanded (INSERT and each MINSERT cell, nested ones included).
    pub inserts: usize,
    pub entities: usize,
    /// The piece's top-level entities as the parser read them, by DXF name.
    pub parsed: BTreeMap<String, usize>,
    /// Blocks inserted (upper-case names), nested ones included.
    pub expanded: BTreeSet<String>,
    /// The first entity that cannot be read; the rest of the piece is not collected.
    pub bad: Option<BadEntity>,
    /// The piece went over its budget of points and was not collected further.
    pub over_budget: bool,
}

pub(super) struct BadEntity {
    pub index: usize,
    pub what: String,
    pub msg: String,
}

/// Collects the model-space entities of `drawing`, at most `budget` points.
pub(super) fn collect(drawing: &Drawing, ctx: &Context, budget: usize) -> Collected {
    let mut c = Collected {
        points: Vec::new(),
        segments: Vec::new(),
        skipped: BTreeMap::new(),
        inserts: 0,
        entities: 0,
        parsed: BTreeMap::new(),
        expanded: BTreeSet::new(),
        bad: None,
        over_budget: false,
    };
    let mut walk = Walk {
        ctx,
        out: &mut c,
        budget,
        stack: Vec::new(),
    };
    let mut failure = None;
    for entity in drawing.entities() {
        *walk
            .out
            .parsed
            .entry(type_name(&entity.specific))
            .or_default() += 1;
    }
    for (index, entity) in drawing.entities().enumerate() {
        walk.out.entities = index + 1;
        if entity.common.is_in_paper_space {
            walk.skip("paper-space entity");
            continue;
        }
        match walk.entity(entity, &DAffine3::IDENTITY, 0) {
            Ok(()) => {}
            Err(Stop::OverBudget) => {
                walk.out.over_budget = true;
                break;
            }
            Err(Stop::Bad(msg)) => {
                failure = Some(BadEntity {
                    index,
                    what: describe(entity),
                    msg,
                });
                break;
            }
        }
    }
    c.bad = failure;
    c
}

/// "LINE, handle 2F, layer "0"".
fn describe(e: &Entity) -> String {
    format!(
        "{}, handle {:X}, layer \"{}\"",
        type_name(&e.specific),
        e.common.handle.0,
        e.common.layer.escape_debug()
    )
}

/// Why a walk stopped: an entity that cannot be read, or the point budget spent. The budget is
/// reported for the whole file, never for the entity where it ran out: which one that is
/// depends on how the file was split.
enum Stop {
    Bad(String),
    OverBudget,
}

impl From<String> for Stop {
    fn from(msg: String) -> Self {
        Stop::Bad(msg)
    }
}

impl From<&str> for Stop {
    fn from(msg: &str) -> Self {
        Stop::Bad(msg.into())
    }
}

struct Walk<'a, 'c> {
    ctx: &'a Context<'a>,
    out: &'c mut Collected,
    budget: usize,
    /// Upper-case names of the blocks being expanded, outermost first.
    stack: Vec<String>,
}

impl Walk<'_, '_> {
    /// The blocks being expanded, "\"A\" → \"B\"".
    fn chain(&self) -> String {
        self.stack
            .iter()
            .map(|b| format!("\"{}\"", b.escape_debug()))
            .collect::<Vec<_>>()
            .join(" → ")
    }

    fn skip(&mut self, what: &str) {
        *self.out.skipped.entry(what.to_string()).or_default() += 1;
    }

    /// Adds one polyline (in the entity's own coordinates) taken to the world by `xf`.
    fn emit(&mut self, pts: &[DVec3], xf: &DAffine3) -> Result<(), Stop> {
        if pts.len() > self.budget {
            return Err(Stop::OverBudget);
        }
        self.budget -= pts.len();
        let first = self.out.points.len() as u32;
        for (k, p) in pts.iter().enumerate() {
            let w = xf.transform_point3(*p);
            if !w.is_finite() {
                return Err(format!("vertex {k} has a non-finite coordinate").into());
            }
            self.out.points.push(w);
        }
        self.out
            .segments
            .extend((1..pts.len() as u32).map(|k| (first + k - 1, first + k)));
        Ok(())
    }

    fn entity(&mut self, entity: &Entity, xf: &DAffine3, depth: usize) -> Result<(), Stop> {
        // Chords are judged after the transform: a block scaled up by s gets 1/s the tolerance.
        let tol = self.ctx.tol / stretch(xf);
        let pts: Vec<DVec3> = match &entity.specific {
            EntityType::Line(l) => vec![wcs(&l.p1), wcs(&l.p2)],
            EntityType::ModelPoint(p) => vec![wcs(&p.location)],
            EntityType::LwPolyline(pl) => lw_polyline(pl, entity.common.elevation, tol)?,
            EntityType::Polyline(pl) if pl.is_polyface_mesh() || pl.is_3d_polygon_mesh() => {
                self.skip("POLYLINE (mesh)");
                return Ok(());
            }
            EntityType::Polyline(pl) => polyline(pl, tol)?,
            EntityType::Arc(a) => {
                let sweep = (a.end_angle - a.start_angle).rem_euclid(360.0);
                let sweep = if sweep == 0.0 { 360.0 } else { sweep };
                let axes = ocs_axes(&a.normal)?;
                let c = wcs(&a.center);
                let pts = curves::arc(
                    DVec2::new(c.x, c.y),
                    a.radius,
                    a.start_angle.to_radians(),
                    sweep.to_radians(),
                    tol,
                )
                .map_err(|e| format!("ARC: {e}"))?;
                pts.iter().map(|p| from_ocs(&axes, p.x, p.y, c.z)).collect()
            }
            EntityType::Circle(ci) => {
                let axes = ocs_axes(&ci.normal)?;
                let c = wcs(&ci.center);
                let mut pts: Vec<DVec3> = curves::arc(
                    DVec2::new(c.x, c.y),
                    ci.radius,
                    0.0,
                    std::f64::consts::TAU,
                    tol,
                )
                .map_err(|e| format!("CIRCLE: {e}"))?
                .iter()
                .map(|p| from_ocs(&axes, p.x, p.y, c.z))
                .collect();
                close_exactly(&mut pts);
                pts
            }
            EntityType::Ellipse(el) => {
                let major = DVec3::new(el.major_axis.x, el.major_axis.y, el.major_axis.z);
                let n = DVec3::new(el.normal.x, el.normal.y, el.normal.z)
                    .try_normalize()
                    .ok_or("ELLIPSE: the normal has zero length")?;
                let minor = n.cross(major) * el.minor_axis_ratio;
                let (t0, mut t1) = (el.start_parameter, el.end_parameter);
                if t1 <= t0 {
                    t1 += std::f64::consts::TAU;
                }
                let full = (t1 - t0 - std::f64::consts::TAU).abs() < 1e-12;
                let mut pts = curves::ellipse(wcs(&el.center), major, minor, t0, t1, tol)
                    .map_err(|e| format!("ELLIPSE: {e}"))?;
                if full {
                    close_exactly(&mut pts);
                }
                pts
            }
            EntityType::Spline(s) => spline(s, tol)?,
            EntityType::Insert(ins) => return self.insert(ins, xf, depth),
            other => {
                self.skip(&type_name(other));
                return Ok(());
            }
        };
        self.emit(&pts, xf)
    }

    fn insert(&mut self, ins: &Insert, xf: &DAffine3, depth: usize) -> Result<(), Stop> {
        let attributes = ins.attributes().count();
        if attributes > 0 {
            *self.out.skipped.entry("ATTRIB".into()).or_default() += attributes;
        }
        let block = self
            .ctx
            .blocks
            .get(&ins.name.to_ascii_uppercase())
            .ok_or_else(|| format!("block \"{}\" is not defined", ins.name.escape_debug()))?;
        let name = block.name.to_ascii_uppercase();
        if !self.out.expanded.contains(&name) {
            self.out.expanded.insert(name.clone());
        }
        if self.stack.contains(&name) {
            return Err(format!(
                "block \"{}\" inserts itself (through {})",
                block.name.escape_debug(),
                self.stack.join(" → ").escape_debug()
            )
            .into());
        }
        if depth >= MAX_NESTING {
            return Err(format!("blocks nest deeper than {MAX_NESTING} levels").into());
        }
        let (cells, places) = placements(ins, block)?;
        // Each cell costs at least one unit of the budget: refuse a huge array before looping.
        if cells > self.budget as u64 {
            return Err(Stop::OverBudget);
        }
        self.stack.push(name);
        for place in places {
            let world = *xf * place;
            self.out.inserts += 1;
            // An empty block costs nothing but time; count each cell against the budget.
            if self.budget == 0 {
                return Err(Stop::OverBudget);
            }
            self.budget -= 1;
            for (k, e) in block.entities.iter().enumerate() {
                // The innermost failure names the chain of blocks it sits in, once.
                self.entity(e, &world, depth + 1)
                    .map_err(|stop| match stop {
                        Stop::Bad(msg) if !msg.starts_with("in block ") => Stop::Bad(format!(
                            "in block {}, entity {k} ({}): {msg}",
                            self.chain(),
                            describe(e)
                        )),
                        other => other,
                    })?;
            }
            let name = self.stack.last().cloned().unwrap_or_default();
            for (line, hatch) in self.ctx.hatches.get(&name).into_iter().flatten() {
                let loops = hatch
                    .loops(self.ctx.tol / stretch(&world), self.budget)
                    .map_err(|msg| {
                        format!("in block {}, HATCH at line {line}: {msg}", self.chain())
                    })?
                    .ok_or(Stop::OverBudget)?;
                for l in loops {
                    self.emit(&l, &world)?;
                }
            }
        }
        self.stack.pop();
        Ok(())
    }
}

/// Where an INSERT puts its block: the number of cells (1, or a MINSERT's rows × columns) and
/// each cell's transform from block coordinates to the coordinates the INSERT is drawn in.
pub(crate) fn placements<'a>(
    ins: &'a Insert,
    block: &Block,
) -> Result<(u64, impl Iterator<Item = DAffine3> + 'a), String> {
    let base = wcs(&block.base_point);
    let scale = DVec3::new(ins.x_scale_factor, ins.y_scale_factor, ins.z_scale_factor);
    let values = [scale.x, scale.y, scale.z, ins.rotation];
    if values.iter().any(|v| !v.is_finite()) || !wcs(&ins.location).is_finite() {
        return Err("INSERT: a non-finite location, scale or rotation".into());
    }
    let axes = ocs_axes(&ins.extrusion_direction)?;
    let ocs = DAffine3::from_mat3(DMat3::from_cols(axes[0], axes[1], axes[2]));
    let rotation = DAffine3::from_rotation_z(ins.rotation.to_radians());
    let local = DAffine3::from_scale(scale) * DAffine3::from_translation(-base);
    let (rows, cols) = (ins.row_count.max(1), ins.column_count.max(1));
    let cells = rows as u64 * cols as u64;
    let places = (0..rows).flat_map(move |r| {
        (0..cols).map(move |c| {
            let cell = DVec3::new(
                f64::from(c) * ins.column_spacing,
                f64::from(r) * ins.row_spacing,
                0.0,
            );
            ocs * DAffine3::from_translation(wcs(&ins.location))
                * rotation
                * DAffine3::from_translation(cell)
                * local
        })
    });
    Ok((cells, places))
}

/// The largest factor by which `xf` can lengthen a vector (σ_max of its linear part), bounded
/// from above by the largest absolute row sum of MᵀM; exact for rotations and axis scales.
fn stretch(xf: &DAffine3) -> f64 {
    let m = xf.matrix3;
    let g = m.transpose() * m;
    let rows = [g.row(0), g.row(1), g.row(2)];
    let bound = rows
        .iter()
        .map(|r| r.x.abs() + r.y.abs() + r.z.abs())
        .fold(0.0, f64::max)
        .sqrt();
    if bound > 0.0 && bound.is_finite() {
        bound
    } else {
        1.0
    }
}

fn close_exactly(pts: &mut [DVec3]) {
    if let Some(first) = pts.first().copied() {
        if let Some(last) = pts.last_mut() {
            *last = first;
        }
    }
}

/// DXF name of an entity type ("3DFACE", "DIMENSION").
pub(crate) fn type_name(t: &EntityType) -> String {
    let name = match t {
        EntityType::Face3D(_) => "3DFACE",
        EntityType::Solid3D(_) => "3DSOLID",
        EntityType::ProxyEntity(_) => "ACAD_PROXY_ENTITY",
        EntityType::AttributeDefinition(_) => "ATTDEF",
        EntityType::Attribute(_) => "ATTRIB",
        EntityType::RotatedDimension(_)
        | EntityType::RadialDimension(_)
        | EntityType::DiameterDimension(_)
        | EntityType::AngularThreePointDimension(_)
        | EntityType::OrdinateDimension(_) => "DIMENSION",
        EntityType::ModelPoint(_) => "POINT",
        EntityType::LwPolyline(_) => "LWPOLYLINE",
        EntityType::MText(_) => "MTEXT",
        EntityType::MLine(_) => "MLINE",
        EntityType::XLine(_) => "XLINE",
        EntityType::RText(_) => "RTEXT",
        EntityType::ArcAlignedText(_) => "ARCALIGNEDTEXT",
        EntityType::OleFrame(_) => "OLEFRAME",
        EntityType::Ole2Frame(_) => "OLE2FRAME",
        EntityType::DgnUnderlay(_) => "DGNUNDERLAY",
        EntityType::DwfUnderlay(_) => "DWFUNDERLAY",
        EntityType::PdfUnderlay(_) => "PDFUNDERLAY",
        other => {
            let dbg = format!("{other:?}");
            return dbg
                .split(['(', ' ', '{'])
                .next()
                .unwrap_or("ENTITY")
                .to_ascii_uppercase();
        }
    };
    name.into()
}

fn wcs(p: &Point) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

/// World axes of the object coordinate system with normal `n` (the DXF "arbitrary axis
/// algorithm"): a 2D entity's (x, y, elevation) are coordinates along these axes.
pub(super) fn ocs_axes(n: &dxf::Vector) -> Result<[DVec3; 3], String> {
    let n = DVec3::new(n.x, n.y, n.z)
        .try_normalize()
        .ok_or("extrusion direction has zero length")?;
    let limit = 1.0 / 64.0;
    let ax = if n.x.abs() < limit && n.y.abs() < limit {
        DVec3::Y.cross(n)
    } else {
        DVec3::Z.cross(n)
    }
    .normalize();
    Ok([ax, n.cross(ax), n])
}

pub(super) fn from_ocs(axes: &[DVec3; 3], x: f64, y: f64, z: f64) -> DVec3 {
    axes[0] * x + axes[1] * y + axes[2] * z
}

/// Flat 2D vertices with bulges (arc segments) into points, closing the loop when asked.
pub(super) fn bulged(
    vertices: &[(DVec2, f64)],
    closed: bool,
    tol: f64,
) -> Result<Vec<DVec2>, String> {
    let Some(&(first, _)) = vertices.first() else {
        return Ok(Vec::new());
    };
    if closed && vertices.len() == 1 {
        return Err("a closed polyline of one vertex is a point, not a loop".into());
    }
    let mut pts = vec![first];
    // Closed, the last vertex starts a segment back to the first: with two vertices that is
    // the second half of a round hole (AutoCAD's DONUT) when it is an arc, and the same line
    // again when it is straight (then left out).
    let closing = closed && (vertices.len() > 2 || vertices[vertices.len() - 1].1 != 0.0);
    let segments = if closing {
        vertices.len()
    } else {
        vertices.len() - 1
    };
    for i in 0..segments {
        let (p0, bulge) = vertices[i];
        let p1 = vertices[(i + 1) % vertices.len()].0;
        let arc = curves::bulge_arc(p0, p1, bulge, tol).map_err(|e| {
            format!("vertex {i} starts an arc segment that cannot be flattened: {e}")
        })?;
        pts.extend(arc);
    }
    Ok(pts)
}

fn lw_polyline(pl: &LwPolyline, elevation: f64, tol: f64) -> Result<Vec<DVec3>, String> {
    let axes = ocs_axes(&pl.extrusion_direction)?;
    let v: Vec<(DVec2, f64)> = pl
        .vertices
        .iter()
        .map(|v| (DVec2::new(v.x, v.y), v.bulge))
        .collect();
    in_world(&v, pl.is_closed(), tol, &axes, elevation)
}

/// Bulged OCS vertices at `elevation`, flattened and taken to world coordinates.
fn in_world(
    v: &[(DVec2, f64)],
    closed: bool,
    tol: f64,
    axes: &[DVec3; 3],
    elevation: f64,
) -> Result<Vec<DVec3>, String> {
    let flat = bulged(v, closed, tol)?;
    Ok(flat
        .iter()
        .map(|p| from_ocs(axes, p.x, p.y, elevation))
        .collect())
}

fn polyline(pl: &Polyline, tol: f64) -> Result<Vec<DVec3>, String> {
    // Spline-fit polylines list their frame control points too; the curve is the other vertices.
    let vertices: Vec<&Vertex> = pl
        .vertices()
        .filter(|v| !v.is_spline_frame_control_point())
        .collect();
    if pl.is_3d_polyline() {
        let mut pts: Vec<DVec3> = vertices.iter().map(|v| wcs(&v.location)).collect();
        if pl.is_closed() && pts.len() > 2 {
            pts.push(pts[0]);
        }
        return Ok(pts);
    }
    let axes = ocs_axes(&pl.normal)?;
    let elevation = pl.location.z;
    let v: Vec<(DVec2, f64)> = vertices
        .iter()
        .map(|v| (DVec2::new(v.location.x, v.location.y), v.bulge))
        .collect();
    in_world(&v, pl.is_closed(), tol, &axes, elevation)
}

fn spline(s: &Spline, tol: f64) -> Result<Vec<DVec3>, String> {
    let closed = s.flags & 1 != 0;
    let control: Vec<DVec3> = s.control_points.iter().map(wcs).collect();
    let mut pts = if control.is_empty() {
        let fit: Vec<DVec3> = s.fit_points.iter().map(wcs).collect();
        if fit.len() < 2 {
            return Err("SPLINE has neither control points nor two fit points".into());
        }
        curves::through_points(&fit, closed, tol).map_err(|e| format!("SPLINE: {e}"))?
    } else {
        let degree = usize::try_from(s.degree_of_curve)
            .map_err(|_| format!("SPLINE: degree {}", s.degree_of_curve))?;
        let weights = (!s.weight_values.is_empty()).then_some(s.weight_values.as_slice());
        Nurbs {
            degree,
            knots: &s.knot_values,
            control: &control,
            weights,
        }
        .flatten(tol)
        .map_err(|e| format!("SPLINE: {e}"))?
    };
    if closed && pts.len() > 2 && pts[0].distance(pts[pts.len() - 1]) <= tol {
        close_exactly(&mut pts);
    }
    Ok(pts)
}
