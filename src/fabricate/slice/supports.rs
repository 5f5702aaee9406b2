//! Supports: tree supports under every island, made of the same shapes as the solid, so the
//! supported solid is still one union (meshed as one closed 2-manifold by `solid`, sampled as one
//! by `print`).
//!
//! # Method
//! The solid is sliced at the printer's pixel and layer (no archive), with its placed origin on a
//! pixel corner as `arrange_boxes` places models, and its islands found as `slice` finds them;
//! and again on a grid half a pixel over, where a sliver may be an island that the first grid
//! holds. Under each island, at its first layer's height and at its pixel nearest its centroid,
//! a tip: a ball no wider than `tip` and never wider than the vein there, widening downwards into
//! a pillar. The pillar goes down until the solid is right below it (it then narrows onto it,
//! no wider than the vein there, ending in a ball half as wide as the vein, sunk into it:
//! nothing hangs beside the vein) or reaches the plate (it then stands on a disc, the base,
//! narrowed down to the pillar where the part is near). It keeps `clearance` from the part all
//! the way down but over the last four pillar radii above where it lands: where the column
//! straight below the tip does not, the tip leans (at most 45°, up to four pillar radii aside,
//! nearest first) to a neck whose column does, with the tip's own lower half clear too; a tip
//! with no such neck goes straight down and is counted as crowded. An island too low for a
//! pillar on a base (the pillar's neck would reach into the plate, and the print, which puts
//! the lowest point on the plate, would lift everything by that) gets a pin: a cylinder as thin
//! as the tip from the plate to the top of the island's first layer.
//!
//! Pillars bound for the plate that stand closer than `join` are joined in pairs, nearest first:
//! each leans at most 45° to a point between them, from where one pillar goes on down (and may
//! be joined again): a tree. A join whose braces would pass within a pillar's radius plus the
//! clearance of the solid, or whose column below would not keep it, is not made. Every step down
//! looks at the exact distance to the solid, so a pillar's axis never passes through it.
//!
//! Islands are found with the layers drawn as the print draws them: the solid first, then the
//! supports only where the solid leaves a pixel unlit (`shapes::image`), and the lowest point
//! on the plate.
//!
//! An island wider than `spacing` is held at more points than its anchor: one near the middle
//! of each square of that side its first layer covers, at least half a spacing apart.
//!
//! A closed mesh (`plan_mesh`, for `slice --supports`) is planned by the same code through the
//! same three questions asked of the solid: its signed distance (the nearest triangle, through
//! a box tree; inside where the mesh's winding number about the point is not zero, counted on
//! the vertical ray, as the slicer fills sections by the non-zero rule), its thickness where a
//! tip or a pillar meets it (the largest ball inside the mesh touching its surface at the point
//! nearest, by bisection: it stands for the vein's radius), and its layers (cut as `slice` cuts
//! them, the supports drawn over them where they leave a pixel unlit).
//!
//! The supported solid is sliced again on both grids and what islands are left (slivers beside
//! a tip) are held the same way, for up to three rounds. The islands left on the print's grid
//! (none, unless a pillar could not be placed) and the supports' resin are reported.

use glam::{DVec2, DVec3};

use super::islands::{Island, Islands};
use super::shapes::{image, image_onto, layer_count, Placed, Plate};
use super::{in_batches, LayerIndex, Placement, Printer};
use crate::fabricate::solid::sdf::{Cylinder, Primitive, RoundCone};
use crate::fabricate::solid::Shapes;
use crate::mesh::closest::SurfaceIndex;
use crate::mesh::inside::Winding;
use crate::mesh::TriMesh;

/// How the supports are made, mm.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SupportOptions {
    /// Tip diameter where it touches the solid (narrower where the vein is).
    pub tip: f64,
    /// Pillar diameter.
    pub pillar: f64,
    /// Base disc under each pillar on the plate: diameter and height.
    pub base: f64,
    pub base_height: f64,
    /// Pillars closer than this are joined.
    pub join: f64,
    /// Room kept between a support and the part, except where a tip holds an island and where
    /// a pillar lands on the part below.
    pub clearance: f64,
    /// An island wider than this is held by tips about this far apart over its first layer.
    pub spacing: f64,
}

impl Default for SupportOptions {
    fn default() -> Self {
        SupportOptions {
            tip: 0.4,
            pillar: 0.8,
            base: 2.0,
            base_height: 0.4,
            join: 4.0,
            clearance: 0.3,
            spacing: 2.5,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SupportError {
    #[error(
        "support_{what}= must be a positive number of mm (at most 100), got {}",
        crate::text::num(*.value)
    )]
    Option { what: &'static str, value: f64 },
    #[error(
        "the solid is {0} × {1} pixels across, more than 16384: supports need its layers at the \
         printer's pixel"
    )]
    TooWide(usize, usize),
    #[error(transparent)]
    Cancelled(#[from] crate::stage::Cancelled),
}

/// What was built.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SupportReport {
    pub options: SupportOptions,
    /// Islands of the solid alone.
    pub islands: usize,
    pub tips: usize,
    pub to_plate: usize,
    /// Tips whose pillar could not keep `clearance` from the part (it goes straight down and
    /// may touch the part beside it).
    pub crowded: usize,
    /// Of those, pins: tips too low for a pillar on a base, held by a cylinder as thin as the
    /// tip from the plate.
    pub pins: usize,
    pub to_model: usize,
    pub joins: usize,
    /// Islands of the solid with its supports (0 when every island is held).
    pub islands_left: usize,
    pub first_left: Option<Island>,
    /// Resin of the supports alone, from the layers' pixels, mL.
    pub support_ml: f64,
    pub model_ml: f64,
}

impl SupportReport {
    /// The reports of several models' supports as one: counts, resin and islands added up, the
    /// first island left of the first model that has one. `None` for no reports.
    pub fn total(reports: &[SupportReport]) -> Option<SupportReport> {
        let mut all = reports.first()?.clone();
        for r in &reports[1..] {
            all.islands += r.islands;
            all.tips += r.tips;
            all.to_plate += r.to_plate;
            all.crowded += r.crowded;
            all.pins += r.pins;
            all.to_model += r.to_model;
            all.joins += r.joins;
            all.islands_left += r.islands_left;
            all.first_left = all.first_left.or_else(|| r.first_left.clone());
            all.support_ml += r.support_ml;
            all.model_ml += r.model_ml;
        }
        Some(all)
    }
}

/// The supports' shapes, in the solid's own frame (as `Shapes::prims`), and what they are.
pub struct Supports {
    pub prims: Vec<Primitive>,
    pub report: SupportReport,
}

impl SupportOptions {
    pub fn check(&self) -> Result<(), SupportError> {
        for (what, value) in [
            ("tip", self.tip),
            ("pillar", self.pillar),
            ("base", self.base),
            ("base-height", self.base_height),
            ("join", self.join),
            ("clearance", self.clearance),
            ("spacing", self.spacing),
        ] {
            if !(value.is_finite() && value > 0.0 && value <= 100.0) {
                return Err(SupportError::Option { what, value });
            }
        }
        Ok(())
    }
}

/// A piece of support in the placed frame.
#[derive(Clone, Copy)]
enum Piece {
    Cone(DVec3, DVec3, f64, f64),
    /// A disc on the plate: centre of its bottom, radius, height.
    Base(DVec3, f64, f64),
}

impl Piece {
    /// The piece in the solid's own frame.
    fn local(&self, model: &Placed) -> Primitive {
        self.moved(&|p| model.local(p), &|v| model.local_direction(v))
    }

    /// The piece with its points moved by `point` and its directions by `direction`.
    fn moved(
        &self,
        point: &dyn Fn(DVec3) -> DVec3,
        direction: &dyn Fn(DVec3) -> DVec3,
    ) -> Primitive {
        match *self {
            Piece::Cone(a, b, ra, rb) => {
                Primitive::Cone(RoundCone::new(point(a), point(b), ra, rb))
            }
            Piece::Base(c, radius, height) => Primitive::Cylinder(Cylinder {
                base: point(c),
                axis: direction(DVec3::Z),
                height,
                radius,
            }),
        }
    }
}

/// A solid the planner holds up, placed with its lowest point on the plate, with the supports
/// made so far (part of it for every later look: a pillar of a later round may land on one).
trait Held: Sync {
    /// The placed box of the solid and its supports.
    fn bounds(&self) -> (DVec3, DVec3);
    /// Signed distance at a placed point (at least `reach` when it is farther).
    fn eval(&self, q: DVec3, reach: f64) -> f64;
    /// How thick the solid is where it holds `p` (a vein's radius there), `None` outside.
    fn vein_radius(&self, p: DVec3) -> Option<f64>;
    fn layer_count(&self, grid: &Printer) -> usize;
    /// Layer images (and their areas, mm²) on `grid`, with the solid placed by `place`; the
    /// supports drawn where the solid leaves a pixel unlit.
    fn layers<'s>(
        &'s self,
        grid: &'s Printer,
        place: &'s Placement,
    ) -> Box<dyn Fn(usize) -> (Vec<u8>, f64) + Sync + 's>;
    /// Adds supports (placed frame) and returns them in the frame the caller keeps them in.
    fn add(&mut self, pieces: &[Piece]) -> Vec<Primitive>;
}

/// A solid made of shapes: the supports join its shapes, after them.
struct HeldShapes {
    shapes: Shapes,
    upright: bool,
    current: Placed,
}

impl Held for HeldShapes {
    fn bounds(&self) -> (DVec3, DVec3) {
        self.current.bounds()
    }

    fn eval(&self, q: DVec3, reach: f64) -> f64 {
        self.current.eval(q, reach)
    }

    fn vein_radius(&self, p: DVec3) -> Option<f64> {
        self.current.vein_radius(p)
    }

    fn layer_count(&self, grid: &Printer) -> usize {
        layer_count(&self.current, grid)
    }

    fn layers<'s>(
        &'s self,
        grid: &'s Printer,
        place: &'s Placement,
    ) -> Box<dyn Fn(usize) -> (Vec<u8>, f64) + Sync + 's> {
        let plate = Plate::new(&self.current, std::slice::from_ref(place));
        Box::new(move |i| image(&plate, grid, i))
    }

    fn add(&mut self, pieces: &[Piece]) -> Vec<Primitive> {
        let made: Vec<Primitive> = pieces.iter().map(|s| s.local(&self.current)).collect();
        // Counted as supports, so the layers are drawn as the print draws them.
        self.shapes.added += made.len();
        self.shapes.prims.extend(made.iter().cloned());
        self.current = Placed::new(self.shapes.clone(), self.upright);
        made
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum End {
    Plate,
    Model(f64),
}

/// Rounds of supports at most: the islands a round leaves (slivers beside a tip, seen on the
/// other grid) are held by the next.
const ROUNDS: usize = 3;

/// What the rounds made, counted.
#[derive(Default)]
struct Tally {
    tips: usize,
    /// Tips whose pillar could not keep the clearance from the part anywhere within 45°.
    crowded: usize,
    /// Tips too low for a pillar, held by a pin from the plate.
    pins: usize,
    to_plate: usize,
    to_model: usize,
    joins: usize,
}

/// Plans the supports of `model` for `printer`. `progress(done, total)` counts layers sliced.
/// The pixels they are planned on are the print's when the placed shapes' origin lands on a
/// pixel corner (as `arrange_boxes` places it) and the supported shapes keep the model's frame
/// (`Shapes::frame`, which the caller sets to `model.shift()`).
pub fn plan(
    model: &Placed,
    printer: &Printer,
    opts: &SupportOptions,
    progress: &dyn crate::stage::Progress,
) -> Result<Supports, SupportError> {
    opts.check()?;
    let mut shapes = model.shapes().clone();
    shapes.frame = Some(model.shift());
    let current = Placed::new(shapes.clone(), model.upright());
    let mut held = HeldShapes {
        shapes,
        upright: model.upright(),
        current,
    };
    plan_held(&mut held, printer, opts, progress)
}

/// Plans the supports of a closed mesh, standing on its lowest point's height (as `slice`
/// places it on the plate), with every rule [`plan`] keeps; the supports come in the mesh's
/// frame; the mesh's thickness where a
/// tip or a pillar meets it stands for the vein's radius (the largest ball inside it that
/// touches the surface there).
pub fn plan_mesh(
    mesh: &TriMesh,
    printer: &Printer,
    opts: &SupportOptions,
    progress: &dyn crate::stage::Progress,
) -> Result<Supports, SupportError> {
    opts.check()?;
    // Planned with the lowest point on the plate; the supports go back to the mesh's frame.
    let lift = mesh.bbox().min.z;
    let mut moved = mesh.clone();
    for p in &mut moved.positions {
        p.z -= lift;
    }
    let mut held = HeldMesh::new(&moved);
    let mut planned = plan_held(&mut held, printer, opts, progress)?;
    let back = DVec3::Z * lift;
    planned.prims = held
        .pieces
        .iter()
        .map(|s| s.moved(&|p| p + back, &|v| v))
        .collect();
    Ok(planned)
}

fn plan_held(
    held: &mut dyn Held,
    printer: &Printer,
    opts: &SupportOptions,
    progress: &dyn crate::stage::Progress,
) -> Result<Supports, SupportError> {
    let islands = find_islands(held, printer, opts.spacing, DVec2::ZERO, progress)?;
    let mut left = islands.clone();
    let mut prims: Vec<Primitive> = Vec::new();
    let mut tally = Tally::default();
    for _ in 0..ROUNDS {
        // Islands are found on two pixel grids, half a pixel apart: a sliver of a few pixels
        // may be an island on one and held on the other.
        let shifted = find_islands(held, printer, opts.spacing, DVec2::splat(0.5), progress)?;
        let holds = unite(&left, &shifted, printer.pixel_mm);
        if holds.is_empty() {
            break;
        }
        let pieces = hold(held, &holds, printer, opts, &mut tally);
        prims.extend(held.add(&pieces));
        left = find_islands(held, printer, opts.spacing, DVec2::ZERO, progress)?;
    }
    let ml = |v: f64| v / 1000.0;
    Ok(Supports {
        prims,
        report: SupportReport {
            options: opts.clone(),
            islands: islands.list.len(),
            tips: tally.tips,
            to_plate: tally.to_plate,
            crowded: tally.crowded,
            pins: tally.pins,
            to_model: tally.to_model,
            joins: tally.joins,
            islands_left: left.list.len(),
            first_left: left.list.first().cloned(),
            support_ml: ml(left.volume - islands.volume),
            model_ml: ml(islands.volume),
        },
    })
}

/// The islands of both grids, each once, with the offset of the grid it was found on.
fn unite(a: &Found, b: &Found, pixel: f64) -> Vec<(Island, DVec2)> {
    let near = |i: &Island, j: &Island| {
        i.layer.abs_diff(j.layer) <= 2
            && DVec2::from(i.anchor_mm).distance(DVec2::from(j.anchor_mm)) < 4.0 * pixel
    };
    let mut holds: Vec<(Island, DVec2)> = a.list.iter().map(|i| (i.clone(), a.offset)).collect();
    for i in &b.list {
        // Compared where the first grid has it.
        let mut moved = i.clone();
        let d = b.offset - a.offset;
        moved.anchor_mm = [i.anchor_mm[0] - d.x, i.anchor_mm[1] - d.y];
        if !a.list.iter().any(|j| near(j, &moved)) {
            holds.push((i.clone(), b.offset));
        }
    }
    holds
}

/// Tips, pillars, joins and bases under `holds`, in the placed frame of `model`.
fn hold(
    model: &dyn Held,
    holds: &[(Island, DVec2)],
    printer: &Printer,
    opts: &SupportOptions,
    tally: &mut Tally,
) -> Vec<Piece> {
    let layer = printer.layer_mm;
    let rp = 0.5 * opts.pillar;
    let mut pieces: Vec<Piece> = Vec::new();
    // The room every pillar keeps from the part.
    let room = Room {
        r: rp,
        clearance: opts.clearance,
        taper: 4.0 * rp,
    };
    // The tops of pillars bound for the plate.
    let mut tops: Vec<DVec3> = Vec::new();
    let points = holds.iter().flat_map(|(island, offset)| {
        std::iter::once(island.anchor_mm)
            .chain(island.holds.iter().copied())
            .map(move |at| (island.layer, at, *offset))
    });
    for (first_layer, at, offset) in points {
        tally.tips += 1;
        let z = (first_layer as f64 + 0.5) * layer;
        let p = DVec3::new(at[0] - offset.x, at[1] - offset.y, z);
        let rt = model
            .vein_radius(p)
            .map_or(0.5 * opts.tip, |r| r.min(0.5 * opts.tip));
        // Down from the layer below, where the island is not.
        let end = descend(model, DVec3::new(p.x, p.y, z - layer));
        let bottom = match end {
            End::Plate => 0.0,
            End::Model(h) => h,
        };
        // The tip widens over up to four pillar radii, never past half the drop.
        let tip_len = (4.0 * rp).min(0.5 * (z - bottom)).max(0.0);
        let neck = p - DVec3::Z * tip_len;
        let rn = rp.max(rt);
        if end == End::Plate && neck.z - rn < opts.base_height {
            // Too low for a pillar on a base (its neck's ball would reach into the plate, and
            // everything would be lifted by that when placed): a pin as thin as the tip, from
            // the plate to the top of the island's first layer.
            let r = rt.max(printer.pixel_mm);
            pieces.push(Piece::Base(DVec3::new(p.x, p.y, 0.0), r, z + 0.5 * layer));
            tally.pins += 1;
            tally.to_plate += 1;
            continue;
        }
        // The neck under the tip where the pillar below it keeps its room from the part, the
        // nearest to straight below (the tip leans at most 45°); straight below if none does.
        let found = offsets(room.taper).find_map(|off| {
            // Leaning at most 45°: a neck `off` aside is at least as far down.
            let at = p + off.extend(-tip_len.max(off.length()));
            let end = room.column(model, at)?;
            let low_enough = end != End::Plate || at.z - rn >= opts.base_height;
            (low_enough && room.tip_clear(model, p, at, rt, rn)).then_some((at, end))
        });
        let (neck, end) = found.unwrap_or_else(|| {
            tally.crowded += 1;
            (neck, end)
        });
        pieces.push(Piece::Cone(p, neck, rt, rn));
        match end {
            End::Model(h) => {
                tally.to_model += 1;
                land(model, &mut pieces, neck, h, rp, rt);
            }
            End::Plate => tops.push(neck),
        }
    }

    // Join plate-bound pillars in pairs, nearest first.
    let mut refused: Vec<(DVec2, DVec2)> = Vec::new();
    loop {
        let mut best: Option<(f64, usize, usize)> = None;
        for i in 0..tops.len() {
            for j in i + 1..tops.len() {
                let (a, b) = (tops[i], tops[j]);
                let d = a.truncate().distance(b.truncate());
                let pair = (a.truncate(), b.truncate());
                if d < opts.join && best.is_none_or(|(bd, _, _)| d < bd) && !refused.contains(&pair)
                {
                    best = Some((d, i, j));
                }
            }
        }
        let Some((d, i, j)) = best else {
            break;
        };
        let (a, b) = (tops[i], tops[j]);
        let mid = 0.5 * (a.truncate() + b.truncate());
        let joint = mid.extend(a.z.min(b.z) - 0.5 * d);
        let below = room.column(model, joint);
        let clear = joint.z > opts.base_height + 2.0 * rp
            && clear_of(model, a, joint, rp + opts.clearance)
            && clear_of(model, b, joint, rp + opts.clearance)
            && below.is_some();
        if !clear {
            refused.push((a.truncate(), b.truncate()));
            continue;
        }
        tally.joins += 1;
        pieces.push(pillar(a, joint, rp));
        pieces.push(pillar(b, joint, rp));
        let (hi, lo) = (i.max(j), i.min(j));
        tops.swap_remove(hi);
        tops.swap_remove(lo);
        match below.unwrap_or(End::Plate) {
            End::Model(h) => {
                tally.to_model += 1;
                land(model, &mut pieces, joint, h, rp, 0.5 * opts.tip);
            }
            End::Plate => tops.push(joint),
        }
    }
    tally.to_plate += tops.len();
    for t in &tops {
        let foot = DVec3::new(t.x, t.y, opts.base_height);
        pieces.push(pillar(*t, foot, rp));
        // The base keeps the clearance from the part too (a leaf standing on its petiole is on
        // the plate beside it): narrower where the part is near, never narrower than the pillar.
        let near = model.eval(DVec3::new(t.x, t.y, 0.5 * opts.base_height), opts.base);
        let radius = (0.5 * opts.base).min(near - opts.clearance).max(rp);
        pieces.push(Piece::Base(
            DVec3::new(t.x, t.y, 0.0),
            radius,
            opts.base_height,
        ));
    }
    pieces
}

/// A pillar of radius `r` from `a` to `b`.
fn pillar(a: DVec3, b: DVec3, r: f64) -> Piece {
    Piece::Cone(a, b, r, r)
}

/// Straight down from `from` (outside the solid): the height where the solid is first right
/// below, or the plate.
fn descend(model: &dyn Held, from: DVec3) -> End {
    let mut p = from;
    // Steps are at least 5 µm, so a descent takes at most (height / 5 µm) steps.
    while p.z > 0.0 {
        let d = model.eval(p, 1.0);
        if d <= 0.0 {
            return End::Model(p.z);
        }
        p.z -= d.max(0.005);
    }
    End::Plate
}

/// A pillar of radius `r` (no wider than the vein it lands on) from `top` down onto the solid,
/// which it meets at height `h`: the pillar narrows over its last stretch to a ball half as
/// wide as the vein (and half as wide as a tip of radius `rt`), sunk into it, so no part of it
/// hangs beside the vein (it would be an island) and it touches the part over less than a
/// tip's footprint, on a slope too.
fn land(model: &dyn Held, pieces: &mut Vec<Piece>, top: DVec3, h: f64, r: f64, rt: f64) {
    let hit = DVec3::new(top.x, top.y, h);
    let inside = hit - DVec3::Z * 0.01;
    let vein = model.vein_radius(inside);
    // Never wider than the vein it stands on.
    let r = vein.map_or(r, |v| r.min(v));
    let rl = vein.map_or(0.5 * r, |v| (0.5 * v).min(r)).min(0.5 * rt);
    let taper = (4.0 * r).min(0.5 * (top.z - h)).max(0.0);
    let foot = DVec3::new(top.x, top.y, h + taper);
    if top.z > foot.z {
        pieces.push(pillar(top, foot, r));
    }
    pieces.push(Piece::Cone(foot, hit - DVec3::Z * rl, r, rl));
}

/// Whether a brace of radius `r` from `a` to `b` keeps clear of the solid.
fn clear_of(model: &dyn Held, a: DVec3, b: DVec3, r: f64) -> bool {
    let len = a.distance(b);
    let steps = (len / (0.5 * r)).ceil().max(1.0) as usize;
    (0..=steps).all(|k| model.eval(a.lerp(b, k as f64 / steps as f64), 2.0 * r) > r)
}

/// Rings of neck positions around straight below, out to `reach` (a tip of that length leans
/// at most 45°), nearest first: offsets in the plane.
fn offsets(reach: f64) -> impl Iterator<Item = DVec2> {
    const RINGS: usize = 6;
    (0..=RINGS).flat_map(move |ring| {
        let n = if ring == 0 { 1 } else { 6 * ring };
        let radius = reach * ring as f64 / RINGS as f64;
        (0..n).map(move |k| {
            let a = std::f64::consts::TAU * (k as f64 + 0.5 * (ring % 2) as f64) / n as f64;
            DVec2::new(a.cos(), a.sin()) * radius
        })
    })
}

/// The room a pillar of radius `r` keeps from the part: `clearance` everywhere but over the
/// last `taper` above where it lands.
struct Room {
    r: f64,
    clearance: f64,
    taper: f64,
}

impl Room {
    /// Straight down from `top`: where the pillar ends (the plate, or the height where the
    /// part is right below), if it keeps its room all the way.
    fn column(&self, model: &dyn Held, top: DVec3) -> Option<End> {
        let room = self.r + self.clearance;
        let mut p = top;
        let mut crowded: Option<f64> = None;
        while p.z > 0.0 {
            let d = model.eval(p, room + 1.0);
            if d <= 0.0 {
                return match crowded {
                    Some(z) if z > p.z + self.taper => None,
                    _ => Some(End::Model(p.z)),
                };
            }
            if d < room {
                let first = *crowded.get_or_insert(p.z);
                // Crowded above where it could still land tapering: no landing will do.
                if first - p.z > self.taper {
                    return None;
                }
            }
            // Never past where the room could run out (or, inside it, the part begin); at
            // least 20 µm a step (under half a layer), so a descent takes at most
            // (height / 20 µm) steps.
            p.z -= if d > room { d - room } else { d }.max(0.02);
        }
        crowded.is_none().then_some(End::Plate)
    }

    /// Whether a tip from `p` (radius `rt`) to `neck` (radius `rn`) keeps its room over its
    /// lower half (its upper half holds the island).
    fn tip_clear(&self, model: &dyn Held, p: DVec3, neck: DVec3, rt: f64, rn: f64) -> bool {
        const SAMPLES: usize = 8;
        (SAMPLES / 2..=SAMPLES).all(|k| {
            let t = k as f64 / SAMPLES as f64;
            let r = rt + (rn - rt) * t;
            model.eval(p.lerp(neck, t), r + self.clearance + 1.0) >= r + self.clearance
        })
    }
}

/// The islands of the placed solid on a display just large enough for it.
#[derive(Clone)]
struct Found {
    list: Vec<Island>,
    /// Where the placed solid's origin is on that display, mm.
    offset: DVec2,
    /// The layers' volume, mm³.
    volume: f64,
}

/// `phase` shifts the grid by that part of a pixel.
fn find_islands(
    model: &dyn Held,
    printer: &Printer,
    spacing: f64,
    phase: DVec2,
    progress: &dyn crate::stage::Progress,
) -> Result<Found, SupportError> {
    let (lo, hi) = model.bounds();
    let px = printer.pixel_mm;
    let margin = 4.0;
    // One pixel more each way: the placed origin is moved onto a pixel corner.
    let w = ((hi.x - lo.x) / px).ceil() as usize + 2 * margin as usize + 2;
    let h = ((hi.y - lo.y) / px).ceil() as usize + 2 * margin as usize + 2;
    if w > 16384 || h > 16384 {
        return Err(SupportError::TooWide(w, h));
    }
    let grid = Printer {
        pixels_x: w as u32,
        pixels_y: h as u32,
        ..printer.clone()
    };
    let offset = (DVec2::new(margin - lo.x / px, margin - lo.y / px).ceil() + phase) * px;
    // Lowest point on the plate, as the print places it: a support reaching below z = 0 would
    // lift everything, and show here as islands left.
    let place = Placement {
        model: 0,
        copy: 0,
        turned: false,
        offset: [offset.x, offset.y, -lo.z],
        min: [lo.x + offset.x, lo.y + offset.y],
        max: [hi.x + offset.x, hi.y + offset.y],
    };
    let layers = model.layer_count(&grid);
    let mut finder = Islands::new(w, h, px, grid.layer_mm).with_spread(spacing);
    let (mut list, mut area) = (Vec::new(), 0.0);
    let image = model.layers(&grid, &place);
    progress.begin("supports: slicing", Some(layers as u64));
    in_batches(layers, image, |i, (img, a)| {
        crate::stage::checkpoint(progress)?;
        area += a;
        list.extend(finder.layer_owned(i, img));
        progress.set(i as u64 + 1);
        Ok::<(), crate::stage::Cancelled>(())
    })?;
    Ok(Found {
        list,
        offset,
        volume: area * grid.layer_mm,
    })
}

/// A closed mesh (its lowest point at z = 0) and the supports made so far, which the slices
/// draw after it where it leaves a pixel unlit.
struct HeldMesh<'a> {
    mesh: &'a TriMesh,
    surface: SurfaceIndex<'a>,
    winding: Winding<'a>,
    /// +1 when the triangles face outwards (positive volume), −1 for a mesh wound inside out.
    outward: f64,
    box_lo: DVec3,
    box_hi: DVec3,
    /// The supports, in the mesh's frame (which is the placed one).
    supports: Vec<Primitive>,
    placed: Option<Placed>,
    /// The supports as planned.
    pieces: Vec<Piece>,
}

/// Supports alone as a placed solid in their own frame (every piece drawn as a support, where
/// the part leaves a pixel unlit): what `slice` draws over a mesh's layers.
pub fn supports_only(prims: Vec<Primitive>) -> Placed {
    let added = prims.len();
    Placed::new(
        Shapes {
            prims,
            scale: 1.0,
            drawn_size: 0.0,
            ends: Vec::new(),
            min_radius: 0.0,
            max_radius: 0.0,
            added,
            frame: Some(DVec3::ZERO),
        },
        false,
    )
}

impl<'a> HeldMesh<'a> {
    fn new(mesh: &'a TriMesh) -> HeldMesh<'a> {
        let b = mesh.bbox();
        HeldMesh {
            mesh,
            surface: SurfaceIndex::new(mesh),
            winding: Winding::new(mesh),
            outward: if mesh.signed_volume() < 0.0 {
                -1.0
            } else {
                1.0
            },
            box_lo: b.min,
            box_hi: b.max,
            supports: Vec::new(),
            placed: None,
            pieces: Vec::new(),
        }
    }

    /// Signed distance to the mesh alone (at least `reach` when farther).
    fn mesh_eval(&self, q: DVec3, reach: f64) -> f64 {
        let d = self
            .surface
            .closest_within(q, reach)
            .map_or(reach, |c| c.distance);
        if self.winding.inside(q) {
            -d
        } else {
            d
        }
    }

    /// The radius of the largest ball inside the mesh that touches its surface at the point
    /// nearest `p` (`p` inside): the mesh's half-thickness there, found by bisection on balls
    /// tangent at that point, which are nested.
    fn thickness(&self, p: DVec3) -> Option<f64> {
        if !self.winding.inside(p) {
            return None;
        }
        let c = self.surface.closest(p)?;
        let inward = if c.distance > 1e-9 {
            (p - c.point) / c.distance
        } else {
            -self.outward * self.surface.normal(&c)
        };
        let empty = |r: f64| {
            let centre = c.point + inward * r;
            self.surface
                .closest_within(centre, r)
                .is_none_or(|hit| hit.distance >= r * (1.0 - 1e-6))
                && self.winding.inside(centre)
        };
        let (mut lo, mut hi) = (
            c.distance.min(1e-3),
            (self.box_hi - self.box_lo).max_element(),
        );
        if !empty(lo) {
            return Some(lo);
        }
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if empty(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo < 1e-4 {
                break;
            }
        }
        Some(lo)
    }
}

impl Held for HeldMesh<'_> {
    fn bounds(&self) -> (DVec3, DVec3) {
        match &self.placed {
            Some(s) => {
                let (lo, hi) = s.bounds();
                (self.box_lo.min(lo), self.box_hi.max(hi))
            }
            None => (self.box_lo, self.box_hi),
        }
    }

    fn eval(&self, q: DVec3, reach: f64) -> f64 {
        let d = self.mesh_eval(q, reach);
        self.placed.as_ref().map_or(d, |s| d.min(s.eval(q, reach)))
    }

    fn vein_radius(&self, p: DVec3) -> Option<f64> {
        let part = self.thickness(p);
        let support = self.placed.as_ref().and_then(|s| s.vein_radius(p));
        match (part, support) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }

    fn layer_count(&self, grid: &Printer) -> usize {
        super::layers_for(self.box_hi.z - self.box_lo.z, grid.layer_mm)
    }

    fn layers<'s>(
        &'s self,
        grid: &'s Printer,
        place: &'s Placement,
    ) -> Box<dyn Fn(usize) -> (Vec<u8>, f64) + Sync + 's> {
        let layers = self.layer_count(grid);
        let index = LayerIndex::new(self.mesh, self.box_lo.z, grid.layer_mm, layers);
        let plate = self
            .placed
            .as_ref()
            .map(|s| Plate::new(s, std::slice::from_ref(place)));
        Box::new(move |i| {
            let (w, h) = (grid.pixels_x as usize, grid.pixels_y as usize);
            let mut image = vec![0u8; w * h];
            let section = std::iter::once((self.mesh, &index, place));
            let (covered, _) = super::sections_onto(section, grid, i, &mut image);
            let mut area = covered * grid.pixel_mm * grid.pixel_mm;
            if let Some(plate) = &plate {
                area += image_onto(plate, grid, i, &mut image);
            }
            (image, area)
        })
    }

    fn add(&mut self, pieces: &[Piece]) -> Vec<Primitive> {
        let made: Vec<Primitive> = pieces.iter().map(|s| s.moved(&|p| p, &|v| v)).collect();
        self.supports.extend(made.iter().cloned());
        self.pieces.extend_from_slice(pieces);
        self.placed = Some(supports_only(self.supports.clone()));
        made
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mesh_is_measured_as_the_planner_measures_shapes() {
        // A 10 × 10 × 2 mm slab: signed distance (negative inside, capped at the reach asked
        // for) and its half-thickness where a pillar would land.
        let m = TriMesh::cuboid(DVec3::ZERO, DVec3::new(10.0, 10.0, 2.0));
        let held = HeldMesh::new(&m);
        assert!((held.eval(DVec3::new(5.0, 5.0, 1.0), 5.0) + 1.0).abs() < 1e-12);
        assert!((held.eval(DVec3::new(5.0, 5.0, 3.5), 5.0) - 1.5).abs() < 1e-12);
        assert_eq!(held.eval(DVec3::new(5.0, 5.0, 30.0), 2.0), 2.0);
        let r = held
            .vein_radius(DVec3::new(4.0, 6.0, 1.99))
            .expect("inside");
        assert!((r - 1.0).abs() < 1e-3, "{r}");
        assert_eq!(held.vein_radius(DVec3::new(4.0, 6.0, 2.01)), None);
        // The same slab wound inside out is the same solid to the planner.
        let mut inv = m.clone();
        for t in &mut inv.triangles {
            t.swap(1, 2);
        }
        let held = HeldMesh::new(&inv);
        assert!((held.eval(DVec3::new(5.0, 5.0, 1.0), 5.0) + 1.0).abs() < 1e-12);
        let r = held
            .vein_radius(DVec3::new(4.0, 6.0, 0.01))
            .expect("inside");
        assert!((r - 1.0).abs() < 1e-3, "{r}");
    }
}
