//! Nesting parts on stock sheets, fewest sheets first.
//!
//! [`Nester`] is the interface: parts (outlines in their own frames) in, a sheet, rotation and
//! offset per part out. [`BottomLeft`] is our heuristic on top of jagua-rs's collision engine
//! (jagua-rs detects collisions; it does not decide where anything goes):
//!
//! - Each part is nested as its convex hull (always safe), grown by half the spacing (plus
//!   [`SLACK`]) with bevelled corners, so that grown hulls that do not overlap keep the parts at
//!   least the spacing apart. The sheet, less the margin, grown by half the spacing, is the
//!   container.
//! - Congruent quads are paired first: two copies, the second turned 180°, joined along the edge
//!   that leaves the least waste (a trapezoid and its turned copy make a parallelogram). A pair
//!   is kept only if its hull wastes under `PAIR_WASTE` of its area.
//! - Items go largest first onto the first sheet that takes them (first fit decreasing); a
//!   sheet that refused an item is not offered anything at least as large in both dimensions. On a
//!   sheet, each allowed rotation is tried from sampled starts: next to the box corners of
//!   placed items (where the item's box is clear of theirs), dropped from the top edge, pushed
//!   in from the right edge, and at random free points. From each start the item slides down,
//!   then left, and again, until it rests; the resting place with the lowest top (then the
//!   leftmost) wins. A slide's length is exact: the nearest wall, or the nearest contact with a
//!   placed item along the direction (vertex-to-edge ray casts between convex polygons, the
//!   items found by an rstar query on the swept box). jagua-rs's quadtree confirms that every
//!   start and every resting place is free.
//! - Several seeded tries (the first in plain area order, the others with the order perturbed)
//!   keep the nesting with the fewest sheets, then the emptiest last sheet.
//! - Given work (`time`), sheets are made denser ([`crate::fabricate::separate`]) and the last
//!   sheet is packed towards its origin edge: its items filled again into the shortest room
//!   along y, and along x, that still takes them (bisection), the strip of least area kept and
//!   compressed further with the work left, so that what it leaves is one rectangle across the
//!   sheet.
//!
//! Rotations are a list of angles or `Any`, which tries the angles that lay one of the item's
//! two longest hull edges along a sheet side.

use std::sync::Arc;

use glam::DVec2;
use jagua_rs::collision_detection::hazards::filter::NoFilter;
use jagua_rs::collision_detection::hazards::{Hazard, HazardEntity};
use jagua_rs::collision_detection::{CDEConfig, CDEngine};
use jagua_rs::geometry::fail_fast::SPSurrogateConfig;
use jagua_rs::geometry::geo_enums::GeoPosition;
use jagua_rs::geometry::geo_traits::Transformable;
use jagua_rs::geometry::primitives::{Point, Rect, SPolygon};
use jagua_rs::geometry::Transformation;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use crate::fabricate::separate::Spot;
use crate::geom::convex_distance;
use crate::text::num;

/// Extra clearance added to half the spacing, mm: it absorbs jagua-rs's f32 arithmetic, so parts
/// end up at least the spacing apart in exact arithmetic.
pub const SLACK: f64 = 0.01;
/// A slide stops this short of contact, mm.
const BACKOFF: f64 = 0.005;
/// Starts keep this far off the container's walls, mm.
const CLEAR: f64 = 2.0 * BACKOFF;
/// A compression step: this fraction of the container's length at first, halved after each
/// step that does not separate, down to [`COMPRESS_LEAST`] mm.
const COMPRESS_STEP: f64 = 0.002;
const COMPRESS_LEAST: f64 = 1.0;
/// Seeds tried at a step before it is halved.
const COMPRESS_TRIES: usize = 3;
/// Compression runs on a sheet whose share of the work is at least this many pair
/// evaluations (5 s of `time`).
const COMPRESS_WORK: u64 = (5.0 * crate::fabricate::separate::EVALS_PER_SECOND) as u64;
/// Bisection steps for the last sheet's strip, each way (one fill each).
const STRIP_STEPS: usize = 8;

/// A pair of quads is kept if its hull wastes less than this fraction of its area.
const PAIR_WASTE: f64 = 0.04;
/// Congruent: side lengths and diagonals equal within this, mm.
const CONGRUENT: f64 = 0.05;
/// A pair cut on a common line: the copy's edge ends lie this close to where the first quad's
/// edge, moved by the gap, puts them, mm (well inside an NC check's 0.01 mm).
pub const COMMON_FIT: f64 = 0.002;

#[derive(Clone, Debug, PartialEq)]
pub enum Rotations {
    /// These angles, degrees counter-clockwise.
    Listed(Vec<f64>),
    /// Any angle: the ones that lay one of the item's two longest hull edges along a sheet side.
    Any,
}

#[derive(Clone, Debug)]
pub struct NestOptions {
    /// Sheet width (x) and height (y), mm.
    pub sheet: DVec2,
    /// Kept clear along every sheet edge, mm.
    pub margin: f64,
    /// Least distance between two parts (kerf plus clearance), mm.
    pub spacing: f64,
    pub rotations: Rotations,
    /// Seeded tries; the best is kept.
    pub tries: usize,
    pub seed: u64,
    /// Pair congruent quads turned 180°.
    pub pair: bool,
    /// Common-line cutting: pairs of quads that are their own hulls are set this far apart
    /// (the kerf) along a whole shared edge, which is then cut once; pairs whose edges do not
    /// meet within [`COMMON_FIT`] keep the spacing. None: every pair keeps the spacing.
    pub common_gap: Option<f64>,
    /// Work for making sheets denser after the fill, in seconds of the reference machine
    /// (counted as work, so the result does not depend on the machine); 0 skips it.
    pub time: f64,
    /// With `time`: the last sheet packed towards its origin edge (a strip, leaving one
    /// rectangle across the sheet). [`nest_families`] turns it off while it compares stock
    /// sizes and packs only the last sheet of the one it keeps.
    pub pack_last: bool,
}

impl NestOptions {
    /// Tries worth their time for this many parts: several for a few hundred, one for thousands.
    pub fn tries_for(parts: usize) -> usize {
        (2000 / parts.max(1)).clamp(1, 8)
    }
}

impl Default for NestOptions {
    fn default() -> Self {
        NestOptions {
            sheet: DVec2::new(3000.0, 1500.0),
            margin: 10.0,
            spacing: 5.0,
            rotations: Rotations::Listed(vec![0.0, 90.0, 180.0, 270.0]),
            tries: 4,
            seed: 1,
            pair: true,
            common_gap: None,
            time: 0.0,
            pack_last: true,
        }
    }
}

/// Where a part goes: sheet point = R(angle)·p + offset for a point p of its outline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Place {
    pub sheet: usize,
    /// Degrees counter-clockwise in [0, 360): exactly one of the listed rotations when a list
    /// was given (sums of listed angles and the 180° of a pair are formed in degrees, exact
    /// for whole degrees).
    pub angle: f64,
    pub offset: DVec2,
}

impl Place {
    const ORIGIN: Place = Place {
        sheet: 0,
        angle: 0.0,
        offset: DVec2::ZERO,
    };

    pub fn apply(&self, p: DVec2) -> DVec2 {
        turn(self.angle).rotate(p) + self.offset
    }
}

/// (cos, sin) of an angle in degrees, exact for quarter turns.
pub fn turn(deg: f64) -> DVec2 {
    let d = deg.rem_euclid(360.0);
    if d == 0.0 {
        DVec2::X
    } else if d == 90.0 {
        DVec2::Y
    } else if d == 180.0 {
        DVec2::NEG_X
    } else if d == 270.0 {
        DVec2::NEG_Y
    } else {
        DVec2::from_angle(d.to_radians())
    }
}

#[derive(Clone, Debug)]
pub struct Nesting {
    /// One per part, in input order.
    pub places: Vec<Place>,
    pub sheets: usize,
}

/// The largest sheet side, margin or spacing: 100 m. jagua-rs works in f32, whose step at this
/// size is 8 µm; far larger sizes lose the part shapes or overflow.
pub const MAX_SHEET_MM: f64 = 1e5;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NestError {
    #[error("the sheet must be a positive size of at most {MAX_SHEET_MM} mm a side, got {} × {} mm", num(*.0), num(*.1))]
    Sheet(f64, f64),
    #[error("margin= must be from 0 to {MAX_SHEET_MM} mm, got {}", num(*.0))]
    Margin(f64),
    #[error("spacing= must be from 0 to {MAX_SHEET_MM} mm, got {}", num(*.0))]
    Spacing(f64),
    #[error("a margin of {0} mm leaves nothing of the sheet")]
    NoRoom(f64),
    #[error("a common line's gap (the kerf) must be above 0 and below the spacing ({} mm), got {}", num(*.1), num(*.0))]
    CommonGap(f64, f64),
    #[error("rotation {0}° is not a finite angle")]
    Rotation(f64),
    #[error("the rotation list is empty")]
    NoRotations,
    #[error("part {0} has no area (fewer than 3 distinct points, or all on a line)")]
    Degenerate(usize),
    #[error("part {0}: a coordinate is not a finite number")]
    NotFinite(usize),
    /// Parts (index, size of the hull at the best allowed rotation) that fit no sheet.
    #[error("{} part(s) fit no sheet at any allowed rotation, the first is part {} ({:.1} × {:.1} mm)", .0.len(), .0[0].0, .0[0].1.x, .0[0].1.y)]
    TooLarge(Vec<(usize, DVec2)>),
    #[error("part {0}: jagua-rs refused its shape: {1}")]
    Engine(usize, String),
    #[error(transparent)]
    Cancelled(#[from] crate::stage::Cancelled),
}

impl NestError {
    /// The error of one family's nesting with its parts named by their indices in the whole
    /// (`family[k]` for the family's part `k`).
    fn of(self, family: &[usize]) -> NestError {
        match self {
            NestError::Degenerate(k) => NestError::Degenerate(family[k]),
            NestError::NotFinite(k) => NestError::NotFinite(family[k]),
            NestError::Engine(k, m) => NestError::Engine(family[k], m),
            NestError::TooLarge(list) => {
                NestError::TooLarge(list.into_iter().map(|(k, s)| (family[k], s)).collect())
            }
            e => e,
        }
    }
}

/// Parts that fit no sheet: each one's index and the size of its hull at its best allowed
/// rotation.
pub type Misfits = Vec<(usize, DVec2)>;

pub trait Nester {
    /// Places every part on sheets of one family (same stock); sheets are numbered from 0.
    fn nest(&self, parts: &[Vec<DVec2>], opts: &NestOptions) -> Result<Nesting, NestError>;

    /// The parts `nest` would report as fitting no sheet of `opts` (index, size of the hull
    /// at its best allowed rotation), found without nesting anything; the errors `nest`
    /// gives before it nests (bad options, a degenerate or non-finite part) alike.
    fn too_large(&self, parts: &[Vec<DVec2>], opts: &NestOptions) -> Result<Misfits, NestError>;
}

/// A stock sheet size and what one costs (any currency; 0 when only sizes matter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stock {
    pub size: DVec2,
    pub cost: f64,
}

/// Sheets per family: parts with equal keys share sheets (one stock thickness, or one
/// assembly group), families take sheets in key order. Each family is nested on every stock
/// size (`opts.sheet` is not used) and the cheapest result kept, then the least stock area;
/// its last sheet goes to the cheapest size that takes all that sheet's parts. Parts too large
/// for every size are reported together, over all families. Returns the nesting and each
/// sheet's key and stock.
pub fn nest_families<K: Ord + Clone>(
    nester: &dyn Nester,
    parts: &[Vec<DVec2>],
    keys: &[K],
    stock: &[Stock],
    opts: &NestOptions,
) -> Result<(Nesting, Vec<(K, Stock)>), NestError> {
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by(|&a, &b| keys[a].cmp(&keys[b]).then(a.cmp(&b)));
    // Each family's indices into `parts`, and its parts.
    let groups: Vec<&[usize]> = order.chunk_by(|&a, &b| keys[a] == keys[b]).collect();
    let families: Vec<Vec<Vec<DVec2>>> = groups
        .iter()
        .map(|family| family.iter().map(|&i| parts[i].clone()).collect())
        .collect();
    // Parts too large are found before any family is nested, so that a refusal does not wait
    // for the other families' nesting. A family that no stock size takes whole names the parts
    // that fit no size (or, if each size takes each part but none takes them all, the first
    // size's misfits).
    let mut too_large = Vec::new();
    for (&family, these) in groups.iter().zip(&families) {
        let mut lists = Vec::new();
        for st in stock {
            let on = NestOptions {
                sheet: st.size,
                pack_last: false,
                ..opts.clone()
            };
            let list = nester.too_large(these, &on).map_err(|e| e.of(family))?;
            if list.is_empty() {
                lists.clear();
                break;
            }
            lists.push(list);
        }
        let Some((first, others)) = lists.split_first() else {
            continue;
        };
        let nowhere: Vec<(usize, DVec2)> = first
            .iter()
            .filter(|(k, _)| others.iter().all(|l| l.iter().any(|t| t.0 == *k)))
            .copied()
            .collect();
        let named = if nowhere.is_empty() { first } else { &nowhere };
        too_large.extend(named.iter().map(|&(k, s)| (family[k], s)));
    }
    if !too_large.is_empty() {
        too_large.sort_by_key(|t| t.0);
        return Err(NestError::TooLarge(too_large));
    }
    let mut places = vec![Place::ORIGIN; parts.len()];
    let mut sheets: Vec<(K, Stock)> = Vec::new();
    for (&family, these) in groups.iter().zip(&families) {
        match cheapest(nester, these, stock, opts) {
            Ok((local, stocks)) => {
                for (&i, p) in family.iter().zip(local) {
                    places[i] = Place {
                        sheet: p.sheet + sheets.len(),
                        ..p
                    };
                }
                let key = &keys[family[0]];
                sheets.extend(stocks.into_iter().map(|st| (key.clone(), st)));
            }
            Err(e) => return Err(e.of(family)),
        }
    }
    Ok((
        Nesting {
            places,
            sheets: sheets.len(),
        },
        sheets,
    ))
}

/// One family on the cheapest stock (see [`nest_families`]): places with family-local sheets,
/// and each sheet's stock.
fn cheapest(
    nester: &dyn Nester,
    parts: &[Vec<DVec2>],
    stock: &[Stock],
    opts: &NestOptions,
) -> Result<(Vec<Place>, Vec<Stock>), NestError> {
    // Stock sizes are compared on their sheet counts and costs, which packing the last sheet
    // does not change: it is packed once, on the stock kept.
    let on = |st: &Stock| NestOptions {
        sheet: st.size,
        pack_last: false,
        ..opts.clone()
    };
    let mut cheapest_first: Vec<&Stock> = stock.iter().collect();
    cheapest_first.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    // (cost, stock area), places, stock per sheet.
    type Choice = ((f64, f64), Vec<Place>, Vec<Stock>);
    let mut best: Option<Choice> = None;
    let mut too_large = None;
    for st in stock {
        let n = match nester.nest(parts, &on(st)) {
            Ok(n) => n,
            Err(NestError::TooLarge(list)) => {
                too_large.get_or_insert(NestError::TooLarge(list));
                continue;
            }
            Err(e) => return Err(e),
        };
        let mut sheets = vec![*st; n.sheets];
        let mut places = n.places;
        let last = n.sheets - 1;
        let on_last: Vec<usize> = (0..places.len())
            .filter(|&i| places[i].sheet == last)
            .collect();
        let these: Vec<Vec<DVec2>> = on_last.iter().map(|&i| parts[i].clone()).collect();
        for cheaper in cheapest_first.iter().take_while(|c| c.cost < st.cost) {
            if let Ok(m) = nester.nest(&these, &on(cheaper)) {
                if m.sheets == 1 {
                    for (&i, p) in on_last.iter().zip(m.places) {
                        places[i] = Place { sheet: last, ..p };
                    }
                    sheets[last] = **cheaper;
                    break;
                }
            }
        }
        // Cheapest, then least stock area.
        let key = (
            sheets.iter().map(|s| s.cost).sum::<f64>(),
            sheets.iter().map(|s| s.size.x * s.size.y).sum::<f64>(),
        );
        if best.as_ref().is_none_or(|b| key < b.0) {
            best = Some((key, places, sheets));
        }
    }
    let Some((_, mut places, sheets)) = best else {
        return Err(too_large.unwrap_or(NestError::NoRotations));
    };
    if opts.pack_last && opts.time > 0.0 {
        // The last sheet's parts nested again alone on its stock, packed towards its origin
        // edge, with the last sheet's share of the work.
        let last = sheets.len() - 1;
        let on_last: Vec<usize> = (0..places.len())
            .filter(|&i| places[i].sheet == last)
            .collect();
        let these: Vec<Vec<DVec2>> = on_last.iter().map(|&i| parts[i].clone()).collect();
        let packed = NestOptions {
            sheet: sheets[last].size,
            time: opts.time / sheets.len() as f64,
            ..opts.clone()
        };
        match nester.nest(&these, &packed) {
            Ok(m) if m.sheets == 1 => {
                for (&i, p) in on_last.iter().zip(m.places) {
                    places[i] = Place { sheet: last, ..p };
                }
            }
            Err(NestError::Cancelled(c)) => return Err(NestError::Cancelled(c)),
            // Nested as it was.
            _ => {}
        }
    }
    Ok((places, sheets))
}

/// Sampled bottom-left fill with sliding on jagua-rs's collision engine (see the module doc).
#[derive(Clone, Copy)]
pub struct BottomLeft<'a> {
    /// Starts dropped from the top edge per rotation; half as many come in from the right edge
    /// and half as many at random free points.
    pub drops: usize,
    /// Told the parts placed (every try places all of them: `set` counts them over all tries
    /// and stock sizes), and asked between parts whether to stop.
    pub progress: &'a dyn crate::stage::Progress,
    /// Parts placed so far, for `progress`.
    placed: &'a std::sync::atomic::AtomicU64,
}

static NONE_PLACED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

impl Default for BottomLeft<'_> {
    fn default() -> Self {
        BottomLeft {
            drops: 6,
            progress: &crate::stage::Quiet,
            placed: &NONE_PLACED,
        }
    }
}

impl<'a> BottomLeft<'a> {
    /// The nester, telling `progress` of the parts placed (counted in `placed`).
    pub fn with_progress(
        progress: &'a dyn crate::stage::Progress,
        placed: &'a std::sync::atomic::AtomicU64,
    ) -> Self {
        BottomLeft {
            progress,
            placed,
            ..Default::default()
        }
    }
}

/// The convex hull of `outline` grown by `d` (bevelled corners): every point within `d` of the
/// outline is inside.
pub fn grown_hull(outline: &[DVec2], d: f64) -> Vec<DVec2> {
    grow(&convex_hull(outline), d)
}

fn check(opts: &NestOptions) -> Result<(), NestError> {
    let s = opts.sheet;
    let size = |v: f64| v > 0.0 && v <= MAX_SHEET_MM;
    if !(size(s.x) && size(s.y)) {
        return Err(NestError::Sheet(s.x, s.y));
    }
    if !(opts.margin >= 0.0 && opts.margin <= MAX_SHEET_MM) {
        return Err(NestError::Margin(opts.margin));
    }
    if !(opts.spacing >= 0.0 && opts.spacing <= MAX_SHEET_MM) {
        return Err(NestError::Spacing(opts.spacing));
    }
    if 2.0 * opts.margin >= s.x.min(s.y) {
        return Err(NestError::NoRoom(opts.margin));
    }
    if let Some(w) = opts.common_gap {
        if !(w > 0.0 && w < opts.spacing) {
            return Err(NestError::CommonGap(w, opts.spacing));
        }
    }
    if let Rotations::Listed(r) = &opts.rotations {
        if r.is_empty() {
            return Err(NestError::NoRotations);
        }
        if let Some(bad) = r.iter().find(|a| !a.is_finite()) {
            return Err(NestError::Rotation(*bad));
        }
    }
    Ok(())
}

/// A part as placed within an item: item point = R(angle)·p + offset (degrees).
#[derive(Clone, Copy, Debug)]
struct Member {
    part: usize,
    angle: f64,
    offset: DVec2,
}

/// What is placed: one part, or a pair of congruent quads.
struct Item {
    members: Vec<Member>,
    /// The members' hulls' area, mm².
    area: f64,
    /// Area of the item's hull grown by half the spacing, mm².
    grown_area: f64,
    shapes: Vec<Shape>,
}

/// An item at one rotation, its grown hull moved so that its bounding box starts at the origin.
struct Shape {
    /// Degrees.
    angle: f64,
    /// Container point = R(angle)·item point − shift + position.
    shift: DVec2,
    pts: Vec<DVec2>,
    size: DVec2,
    poly: SPolygon,
}

/// Per item: sheet, shape (rotation) and position in the container.
type Spots = Vec<(usize, usize, DVec2)>;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Occupant {
    Item(u32),
    Outside,
}

impl HazardEntity for Occupant {
    fn scope(&self) -> GeoPosition {
        match self {
            Occupant::Item(_) => GeoPosition::Interior,
            Occupant::Outside => GeoPosition::Exterior,
        }
    }

    fn is_dynamic(&self) -> bool {
        matches!(self, Occupant::Item(_))
    }
}

/// One sheet being filled, in container coordinates (origin at the container's corner).
struct Sheet {
    cde: CDEngine<Occupant>,
    boxes: RTree<GeomWithData<Rectangle<[f64; 2]>, u32>>,
    placed: Vec<Vec<DVec2>>,
    free: f64,
    /// Sorted bounding-box sizes of items this sheet refused: anything at least as large in both
    /// is not tried again.
    refused: Vec<DVec2>,
    /// Bounding-box corners (right-bottom and left-top) of placed items that no placed box
    /// covers: starts next to what is there.
    corners: Vec<DVec2>,
}

/// The usable area for grown hulls, and where its corner sits on the sheet.
struct Container {
    size: DVec2,
    corner: DVec2,
    config: CDEConfig,
}

impl Container {
    fn new(opts: &NestOptions) -> Self {
        let inset = opts.margin - 0.5 * opts.spacing;
        Container {
            size: opts.sheet - DVec2::splat(2.0 * inset),
            corner: DVec2::splat(inset),
            config: CDEConfig {
                quadtree_depth: 6,
                cd_threshold: 16,
                item_surrogate_config: SPSurrogateConfig::none(),
            },
        }
    }

    fn sheet(&self) -> Sheet {
        let outline = polygon(&[
            DVec2::ZERO,
            DVec2::new(self.size.x, 0.0),
            self.size,
            DVec2::new(0.0, self.size.y),
        ])
        .expect("a positive rectangle is a polygon");
        let bbox = Rect::try_new(
            -1.0,
            -1.0,
            self.size.x as f32 + 1.0,
            self.size.y as f32 + 1.0,
        )
        .expect("a positive rectangle")
        .inflate_to_square();
        let cde = CDEngine::new(
            bbox,
            vec![Hazard::new(Occupant::Outside, Arc::new(outline))],
            self.config,
        );
        Sheet {
            cde,
            boxes: RTree::new(),
            placed: Vec::new(),
            free: self.size.x * self.size.y,
            refused: Vec::new(),
            corners: Vec::new(),
        }
    }
}

fn polygon(pts: &[DVec2]) -> Result<SPolygon, String> {
    SPolygon::new(pts.iter().map(|p| Point(p.x as f32, p.y as f32)).collect())
        .map_err(|e| e.to_string())
}

impl Sheet {
    fn collides(&self, shape: &Shape, at: DVec2) -> bool {
        let t = Transformation::from_translation((at.x as f32, at.y as f32));
        self.cde
            .detect_poly_collision(&shape.poly.transform_clone(&t), &NoFilter)
    }

    /// Whether a box of `size` at `at` (shrunk by a hair) meets no placed item's box.
    fn box_clear(&self, at: DVec2, size: DVec2) -> bool {
        let (lo, hi) = (at + 1e-6, at + size - 1e-6);
        self.boxes
            .locate_in_envelope_intersecting(&AABB::from_corners([lo.x, lo.y], [hi.x, hi.y]))
            .next()
            .is_none()
    }

    /// How far the shape at `at` can move along `dir` (−x or −y) before it meets a wall or a
    /// placed item.
    fn slide(&self, shape: &Shape, at: DVec2, dir: DVec2) -> f64 {
        let wall = if dir.x < 0.0 { at.x } else { at.y };
        if wall <= BACKOFF {
            return 0.0;
        }
        let lo = at + dir * wall;
        let swept = AABB::from_corners([lo.x, lo.y], [at.x + shape.size.x, at.y + shape.size.y]);
        let moved: Vec<DVec2> = shape.pts.iter().map(|p| *p + at).collect();
        // Nearest boxes first: the gap between boxes along the slide bounds the contact
        // distance from below, so the scan stops once that gap passes the reach.
        let axis = if dir.x < 0.0 { 0 } else { 1 };
        let from = if dir.x < 0.0 { at.x } else { at.y };
        let mut near: Vec<(f64, u32)> = self
            .boxes
            .locate_in_envelope_intersecting(&swept)
            .map(|b| ((from - b.geom().upper()[axis]).max(0.0), b.data))
            .collect();
        near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut reach = wall;
        for (gap, k) in near {
            if gap >= reach {
                break;
            }
            reach = reach.min(contact(&moved, &self.placed[k as usize], dir));
            if reach <= BACKOFF {
                return 0.0;
            }
        }
        reach - BACKOFF
    }

    /// Slides down and left in turn until the shape rests; each resting place is confirmed free.
    fn settle(&self, shape: &Shape, start: DVec2) -> DVec2 {
        let mut at = start;
        for _ in 0..16 {
            let mut moved = 0.0;
            for dir in [DVec2::NEG_Y, DVec2::NEG_X] {
                let d = self.slide(shape, at, dir);
                if d > 0.0 {
                    // The exact slide is checked in jagua-rs's f32 arithmetic; on a (rare)
                    // disagreement the move is shortened, or dropped.
                    for step in [d, d - 0.05, 0.5 * d] {
                        let next = at + dir * step;
                        if step > 0.0 && !self.collides(shape, next) {
                            at = next;
                            moved += step;
                            break;
                        }
                    }
                }
            }
            if moved < 0.05 {
                break;
            }
        }
        at
    }

    fn place(&mut self, shape: &Shape, at: DVec2, id: u32) -> Result<(), String> {
        let pts: Vec<DVec2> = shape.pts.iter().map(|p| *p + at).collect();
        let poly = polygon(&pts)?;
        self.cde
            .register_hazard(Hazard::new(Occupant::Item(id), Arc::new(poly)));
        let hi = at + shape.size;
        let inside = |c: DVec2, lo: DVec2, hi: DVec2| {
            c.x > lo.x + 1e-6 && c.x < hi.x - 1e-6 && c.y > lo.y + 1e-6 && c.y < hi.y - 1e-6
        };
        self.corners.retain(|c| !inside(*c, at, hi));
        // Just clear of the item, so that a start there does not touch it.
        for c in [
            DVec2::new(hi.x + CLEAR, at.y),
            DVec2::new(at.x, hi.y + CLEAR),
        ] {
            let covered = self
                .boxes
                .locate_in_envelope_intersecting(&AABB::from_point([c.x, c.y]))
                .any(|b| {
                    let (lo, hi) = (b.geom().lower(), b.geom().upper());
                    inside(c, DVec2::from(lo), DVec2::from(hi))
                });
            if !covered {
                self.corners.push(c);
            }
        }
        self.boxes.insert(GeomWithData::new(
            Rectangle::from_corners([at.x, at.y], [hi.x, hi.y]),
            self.placed.len() as u32,
        ));
        self.free -= area(&pts);
        self.placed.push(pts);
        Ok(())
    }
}

/// Distance `a` can travel along `dir` before touching `b` (both convex, counter-clockwise):
/// the nearest hit of a ray from a vertex of one entering an edge of the other. Infinite if
/// they never meet.
fn contact(a: &[DVec2], b: &[DVec2], dir: DVec2) -> f64 {
    let mut best = f64::INFINITY;
    let mut cast = |from: &[DVec2], into: &[DVec2], u: DVec2| {
        for (k, &q) in into.iter().enumerate() {
            let e = into[(k + 1) % into.len()] - q;
            let denom = u.perp_dot(e);
            // Counter-clockwise: the outward normal is (e.y, −e.x); the ray enters only
            // against it, where u·normal = denom < 0.
            if denom >= -1e-12 {
                continue;
            }
            for &p in from {
                let w = q - p;
                let s = w.perp_dot(u) / denom;
                if !(-1e-9..=1.0 + 1e-9).contains(&s) {
                    continue;
                }
                let t = w.perp_dot(e) / denom;
                if t >= -1e-6 {
                    best = best.min(t.max(0.0));
                }
            }
        }
    };
    cast(a, b, dir);
    cast(b, a, -dir);
    best
}

fn area(p: &[DVec2]) -> f64 {
    0.5 * (0..p.len())
        .map(|k| p[k].perp_dot(p[(k + 1) % p.len()]))
        .sum::<f64>()
}

/// Convex hull, counter-clockwise, without collinear points (monotone chain).
pub fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup_by(|a, b| a.distance(*b) < 1e-9);
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let it: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in it {
            while hull.len() >= start + 2 {
                let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
                // A left turn, beyond rounding (relative to the edge lengths).
                if (b - a).perp_dot(q - b) > 1e-12 * (b - a).length() * (q - b).length() {
                    break;
                }
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// A convex counter-clockwise polygon grown by `d`: each edge moves out by d; a corner sharper
/// than about 83° is bevelled by the line tangent to the circle of radius d about it, so the
/// result still holds every point within d of the polygon.
fn grow(hull: &[DVec2], d: f64) -> Vec<DVec2> {
    let n = hull.len();
    let mut out = Vec::with_capacity(2 * n);
    for k in 0..n {
        let prev = hull[(k + n - 1) % n];
        let p = hull[k];
        let next = hull[(k + 1) % n];
        let n1 = outward(p - prev);
        let n2 = outward(next - p);
        let bisector = (n1 + n2).normalize();
        let cos_half = bisector.dot(n1);
        if cos_half > 0.75 {
            out.push(p + bisector * (d / cos_half));
        } else {
            // The bevel line: points x with (x − p)·bisector = d; meet each moved edge.
            for (nrm, along) in [(n1, (p - prev).normalize()), (n2, (next - p).normalize())] {
                let base = p + nrm * d;
                let t = (d - (base - p).dot(bisector)) / along.dot(bisector);
                out.push(base + along * t);
            }
        }
    }
    out.dedup_by(|a, b| a.distance(*b) < 1e-3);
    if out.len() > 1 && out[0].distance(out[out.len() - 1]) < 1e-3 {
        out.pop();
    }
    out
}

fn outward(e: DVec2) -> DVec2 {
    DVec2::new(e.y, -e.x).normalize()
}

/// The angles (degrees) tried for an item.
fn angles(grown: &[DVec2], rotations: &Rotations) -> Vec<f64> {
    let mut out: Vec<f64> = match rotations {
        Rotations::Listed(r) => r.clone(),
        Rotations::Any => {
            let mut edges: Vec<(f64, f64)> = (0..grown.len())
                .map(|k| {
                    let e = grown[(k + 1) % grown.len()] - grown[k];
                    (e.length(), e.y.atan2(e.x))
                })
                .collect();
            edges.sort_by(|a, b| b.0.total_cmp(&a.0));
            let mut a = vec![0.0];
            for &(_, phi) in edges.iter().take(2) {
                for k in 0..4 {
                    a.push(-phi.to_degrees() + 90.0 * k as f64);
                }
            }
            a
        }
    };
    for a in &mut out {
        *a = a.rem_euclid(360.0);
    }
    out.sort_by(f64::total_cmp);
    out.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    out
}

fn shape(grown: &[DVec2], angle: f64) -> Result<Shape, String> {
    let r = turn(angle);
    let turned: Vec<DVec2> = grown.iter().map(|p| r.rotate(*p)).collect();
    let lo = turned.iter().fold(DVec2::INFINITY, |m, p| m.min(*p));
    let hi = turned.iter().fold(DVec2::NEG_INFINITY, |m, p| m.max(*p));
    let pts: Vec<DVec2> = turned.iter().map(|p| *p - lo).collect();
    let poly = polygon(&pts)?;
    Ok(Shape {
        angle,
        shift: lo,
        size: hi - lo,
        pts,
        poly,
    })
}

/// Side lengths and both diagonals of a quad, starting at corner `k`.
fn quad_key(q: &[DVec2], k: usize) -> [f64; 6] {
    let v = |i: usize| q[(k + i) % 4];
    [
        v(0).distance(v(1)),
        v(1).distance(v(2)),
        v(2).distance(v(3)),
        v(3).distance(v(0)),
        v(0).distance(v(2)),
        v(1).distance(v(3)),
    ]
}

/// The same quad up to a rotation (not a reflection): the corner of `b` that matches corner 0
/// of `a`.
fn congruent(a: &[DVec2], b: &[DVec2]) -> Option<usize> {
    let ka = quad_key(a, 0);
    (0..4).find(|&k| {
        quad_key(b, k)
            .iter()
            .zip(&ka)
            .all(|(x, y)| (x - y).abs() < CONGRUENT)
    })
}

/// Two congruent quads, the second turned 180° and set against the edge of the first that
/// wastes least, at least `gap` apart. With `exact`, the second quad's rotation is exactly
/// 180° (the quads' frames may differ by a hair, or by a listed rotation too far to pair);
/// otherwise whatever lays it exactly against the first. With `common`, the copy is pushed
/// straight off the edge only, and kept only where its edge's ends lie within [`COMMON_FIT`] of
/// the first quad's, moved by the gap (a whole edge shared, to be cut once). Returns the
/// members and the pair's hull, if it wastes little.
fn pair(
    i: usize,
    a: &[DVec2],
    j: usize,
    b: &[DVec2],
    gap: f64,
    exact: bool,
    common: bool,
) -> Option<(Vec<Member>, Vec<DVec2>)> {
    let k = congruent(a, b)?;
    // Rigid motion taking b's corner k.. onto a's corners 0..: rotation by the edge angles.
    let ea = a[1] - a[0];
    let eb = b[(k + 1) % 4] - b[k];
    let rot = eb.y.atan2(eb.x);
    let to_a = ea.y.atan2(ea.x) - rot;
    let onto = |p: DVec2| DVec2::from_angle(to_a).rotate(p - b[k]) + a[0];
    let ideal = (to_a + std::f64::consts::PI).to_degrees().rem_euclid(360.0);
    let angle = if exact {
        if (ideal - 180.0).abs() > 1.0 {
            return None;
        }
        180.0
    } else {
        ideal
    };
    let centroid_b = b.iter().copied().sum::<DVec2>() / b.len() as f64;
    let mut best: Option<(f64, Vec<Member>, Vec<DVec2>)> = None;
    for e in 0..4 {
        // Turn the copy 180° about the midpoint of edge e, then push it off the edge's line by
        // the gap: along the normal, or along a neighbouring edge (which keeps a trapezoid's
        // parallel sides in line, so the pair stays a parallelogram).
        let (p, q) = (a[e], a[(e + 1) % 4]);
        let mid = 0.5 * (p + q);
        let normal = outward(q - p);
        let before = (p - a[(e + 3) % 4]).normalize();
        let after = (a[(e + 2) % 4] - q).normalize();
        let dirs = if common {
            vec![normal]
        } else {
            vec![normal, before, -before, after, -after]
        };
        for dir in dirs {
            let along = dir.dot(normal);
            if along < 0.2 {
                continue;
            }
            // Where the ideal motion (b → a's frame → half turn about mid → pushed) puts b's
            // centroid; the copy at the chosen angle is centred there.
            let ideal_centroid = 2.0 * mid - onto(centroid_b) + dir * (gap / along);
            let r = turn(angle);
            let mut offset = ideal_centroid - r.rotate(centroid_b);
            let place =
                |offset: DVec2| -> Vec<DVec2> { b.iter().map(|p| r.rotate(*p) + offset).collect() };
            let mut placed = place(offset);
            // Near-congruent quads, or the exact angle, can bring the copy closer than the gap:
            // push it on along the same direction until it is not.
            for _ in 0..4 {
                let d = convex_distance(a, &placed);
                if d >= gap {
                    break;
                }
                offset += dir * ((gap - d) / along + 1e-9 * gap.max(1.0));
                placed = place(offset);
            }
            if convex_distance(a, &placed) < gap {
                continue;
            }
            let meets = |target: DVec2| placed.iter().any(|q| q.distance(target) < COMMON_FIT);
            if common && !(meets(p + normal * gap) && meets(q + normal * gap)) {
                continue;
            }
            let mut all = a.to_vec();
            all.extend(&placed);
            let hull = convex_hull(&all);
            let waste = area(&hull) / (area(a) + area(&placed)) - 1.0;
            if best.as_ref().is_none_or(|b| waste < b.0) {
                let first = Member {
                    part: i,
                    angle: 0.0,
                    offset: DVec2::ZERO,
                };
                let member = Member {
                    part: j,
                    angle,
                    offset,
                };
                best = Some((waste, vec![first, member], hull));
            }
        }
    }
    let (waste, members, hull) = best?;
    (waste < PAIR_WASTE).then_some((members, hull))
}

impl BottomLeft<'_> {
    /// What is placed: pairs of congruent quads (on a common line where `own[i]` says part i
    /// is its own hull and `opts.common_gap` asks for it), and single parts.
    fn items(
        &self,
        hulls: &[Vec<DVec2>],
        own: &[bool],
        opts: &NestOptions,
    ) -> Vec<(Vec<Member>, Vec<DVec2>)> {
        let single = |i: usize| {
            (
                vec![Member {
                    part: i,
                    angle: 0.0,
                    offset: DVec2::ZERO,
                }],
                hulls[i].clone(),
            )
        };
        // A pair turns as one item, so its second part's rotation is a listed angle plus 180°:
        // pairs only where the list holds each angle's half turn too.
        let exact = matches!(opts.rotations, Rotations::Listed(_));
        let closed = match &opts.rotations {
            Rotations::Any => true,
            Rotations::Listed(r) => r.iter().all(|a| {
                let h = (a + 180.0).rem_euclid(360.0);
                r.iter().any(|b| b.rem_euclid(360.0) == h)
            }),
        };
        if !opts.pair || !closed {
            return (0..hulls.len()).map(single).collect();
        }
        // Quads bucketed by rounded perimeter; each pairs with the next congruent one.
        let mut waiting: std::collections::BTreeMap<i64, Vec<usize>> = Default::default();
        let mut out = Vec::new();
        for (i, h) in hulls.iter().enumerate() {
            if h.len() != 4 {
                out.push(single(i));
                continue;
            }
            let key = (quad_key(h, 0)[..4].iter().sum::<f64>() / (4.0 * CONGRUENT)).round() as i64;
            let gap = opts.spacing + 2.0 * SLACK;
            let mut paired = None;
            for bucket in [key - 1, key, key + 1] {
                let Some(list) = waiting.get_mut(&bucket) else {
                    continue;
                };
                let found = list.iter().enumerate().find_map(|(pos, &j)| {
                    let common = opts.common_gap.filter(|_| own[i] && own[j]);
                    common
                        .and_then(|w| pair(j, &hulls[j], i, h, w, exact, true))
                        .or_else(|| pair(j, &hulls[j], i, h, gap, exact, false))
                        .map(|p| (pos, p))
                });
                if let Some((pos, p)) = found {
                    list.remove(pos);
                    paired = Some(p);
                    break;
                }
            }
            match paired {
                Some(p) => out.push(p),
                None => waiting.entry(key).or_default().push(i),
            }
        }
        for list in waiting.into_values() {
            out.extend(list.into_iter().map(single));
        }
        out
    }

    /// Items in `order`, each onto the first sheet that takes it (a new one if none does, up
    /// to `most` sheets: `None` as soon as an item needs one more); `counted`: the parts told
    /// to the progress bar (which counts each try's).
    fn fill(
        &self,
        items: &[Item],
        order: &[usize],
        container: &Container,
        seed: u64,
        counted: bool,
        most: usize,
    ) -> Result<Option<(Spots, Vec<Sheet>)>, NestError> {
        let mut sheets: Vec<Sheet> = Vec::new();
        let mut at = vec![(0, 0, DVec2::ZERO); items.len()];
        for (n, &i) in order.iter().enumerate() {
            let item = &items[i];
            crate::stage::checkpoint(self.progress)?;
            if counted {
                let done = self.placed.fetch_add(
                    item.members.len() as u64,
                    std::sync::atomic::Ordering::Relaxed,
                );
                self.progress.set(done + item.members.len() as u64);
            }
            let grown_area = item.grown_area;
            let dims = {
                let s = item.shapes[0].size;
                DVec2::new(s.x.min(s.y), s.x.max(s.y))
            };
            let mut done = false;
            for (k, sheet) in sheets.iter_mut().enumerate() {
                if sheet.free < grown_area
                    || sheet
                        .refused
                        .iter()
                        .any(|r| r.x <= dims.x + 1e-9 && r.y <= dims.y + 1e-9)
                {
                    continue;
                }
                let mut rng = ChaCha8Rng::seed_from_u64(seed ^ ((n as u64) << 20) ^ k as u64);
                match self.best(sheet, item, container, &mut rng) {
                    Some((s, pos)) => {
                        sheet
                            .place(&item.shapes[s], pos, i as u32)
                            .map_err(|m| NestError::Engine(item.members[0].part, m))?;
                        at[i] = (k, s, pos);
                        done = true;
                        break;
                    }
                    None => {
                        // Keep only the smallest refusals (a Pareto front): the list stays short.
                        sheet.refused.retain(|r| !(dims.x <= r.x && dims.y <= r.y));
                        sheet.refused.push(dims);
                    }
                }
            }
            if !done {
                if sheets.len() >= most {
                    return Ok(None);
                }
                let mut sheet = container.sheet();
                let mut rng = ChaCha8Rng::seed_from_u64(seed ^ ((n as u64) << 20));
                let (s, pos) = self
                    .best(&sheet, item, container, &mut rng)
                    .ok_or_else(|| {
                        NestError::Engine(
                            item.members[0].part,
                            "no free start on an empty sheet".into(),
                        )
                    })?;
                sheet
                    .place(&item.shapes[s], pos, i as u32)
                    .map_err(|m| NestError::Engine(item.members[0].part, m))?;
                at[i] = (sheets.len(), s, pos);
                sheets.push(sheet);
            }
        }
        Ok(Some((at, sheets)))
    }

    /// The best resting place on this sheet over rotations and starts: (shape, position).
    fn best(
        &self,
        sheet: &Sheet,
        item: &Item,
        container: &Container,
        rng: &mut ChaCha8Rng,
    ) -> Option<(usize, DVec2)> {
        let c = container.size;
        let mut starts: Vec<(usize, DVec2)> = Vec::new();
        for (s, shape) in item.shapes.iter().enumerate() {
            let room = c - shape.size;
            if room.x < 2.0 * CLEAR || room.y < 2.0 * CLEAR {
                continue;
            }
            starts.push((s, DVec2::ZERO));
            // Corners only where the item's box is clear of every placed box: a cheap rstar test
            // that keeps full sheets from costing a collision query per corner.
            starts.extend(
                sheet
                    .corners
                    .iter()
                    .map(|c| c.min(room))
                    .filter(|c| sheet.box_clear(*c, shape.size))
                    .map(|c| (s, c)),
            );
            let k = self.drops.max(1);
            for j in 0..k {
                let u = (j as f64 + rng.random::<f64>()) / k as f64;
                starts.push((s, DVec2::new(room.x * u, room.y)));
            }
            for j in 0..k.div_ceil(2) {
                let u = (j as f64 + rng.random::<f64>()) / k.div_ceil(2) as f64;
                starts.push((s, DVec2::new(room.x, room.y * u)));
            }
            for _ in 0..k.div_ceil(2) {
                starts.push((
                    s,
                    DVec2::new(room.x * rng.random::<f64>(), room.y * rng.random::<f64>()),
                ));
            }
        }
        starts
            .par_iter()
            .enumerate()
            .filter_map(|(n, &(s, start))| {
                let shape = &item.shapes[s];
                // Off the walls: a start touching one would count as a collision.
                let start = start.clamp(DVec2::splat(CLEAR), c - shape.size - CLEAR);
                if sheet.collides(shape, start) {
                    return None;
                }
                let at = sheet.settle(shape, start);
                let top = at.y + shape.size.y;
                let right = at.x + shape.size.x;
                Some(((top, right, n), (s, at)))
            })
            .min_by(|a, b| {
                a.0 .0
                    .total_cmp(&b.0 .0)
                    .then(a.0 .1.total_cmp(&b.0 .1))
                    .then(a.0 .2.cmp(&b.0 .2))
            })
            .map(|x| x.1)
    }
}

impl Nester for BottomLeft<'_> {
    fn too_large(&self, parts: &[Vec<DVec2>], opts: &NestOptions) -> Result<Misfits, NestError> {
        self.prepare(parts, opts).map(|(_, too_large)| too_large)
    }

    fn nest(&self, parts: &[Vec<DVec2>], opts: &NestOptions) -> Result<Nesting, NestError> {
        let (items, too_large) = self.prepare(parts, opts)?;
        if !too_large.is_empty() {
            return Err(NestError::TooLarge(too_large));
        }
        let container = Container::new(opts);
        let mut best: Option<(usize, f64, Spots)> = None;
        for t in 0..opts.tries.max(1) {
            let mut rng = ChaCha8Rng::seed_from_u64(opts.seed.wrapping_add(t as u64));
            let keys: Vec<f64> = items
                .iter()
                .map(|it| {
                    let noise = if t == 0 {
                        0.0
                    } else {
                        0.4 * rng.random::<f64>()
                    };
                    it.area * (1.0 + noise)
                })
                .collect();
            let mut order: Vec<usize> = (0..items.len()).collect();
            order.sort_by(|&a, &b| keys[b].total_cmp(&keys[a]).then(a.cmp(&b)));
            let (at, sheets) = self
                .fill(
                    &items,
                    &order,
                    &container,
                    opts.seed ^ (t as u64) << 40,
                    true,
                    usize::MAX,
                )?
                .expect("no limit on the sheets");
            let last = sheets
                .iter()
                .map(|s| container.size.x * container.size.y - s.free)
                .fold(f64::INFINITY, f64::min);
            let better = match &best {
                None => true,
                Some((n, l, _)) => sheets.len() < *n || (sheets.len() == *n && last < *l - 1e-6),
            };
            if better {
                best = Some((sheets.len(), last, at));
            }
        }
        let (sheets, _, mut at) = best.expect("at least one try");
        let sheets = if opts.time > 0.0 {
            self.densify(&items, &mut at, &container, opts)?
        } else {
            sheets
        };
        let mut places = vec![Place::ORIGIN; parts.len()];
        for (item, &(sheet, s, pos)) in items.iter().zip(&at) {
            let shape = &item.shapes[s];
            let r = turn(shape.angle);
            for m in &item.members {
                places[m.part] = Place {
                    sheet,
                    angle: (shape.angle + m.angle).rem_euclid(360.0),
                    offset: r.rotate(m.offset) - shape.shift + pos + container.corner,
                };
            }
        }
        Ok(Nesting { places, sheets })
    }
}

impl BottomLeft<'_> {
    /// What `nest` does before nesting: the options checked, each part's hull, the items
    /// (parts alone or paired) with the shapes they take at the allowed rotations that fit the
    /// sheet, and the parts that fit it at none (index, smallest box), in index order.
    fn prepare(
        &self,
        parts: &[Vec<DVec2>],
        opts: &NestOptions,
    ) -> Result<(Vec<Item>, Misfits), NestError> {
        check(opts)?;
        let container = Container::new(opts);
        let mut hulls = Vec::with_capacity(parts.len());
        for (i, p) in parts.iter().enumerate() {
            if p.iter().any(|q| !q.is_finite()) {
                return Err(NestError::NotFinite(i));
            }
            let h = convex_hull(p);
            if h.len() < 3 || area(&h) < 1e-9 {
                return Err(NestError::Degenerate(i));
            }
            hulls.push(h);
        }
        let d = 0.5 * opts.spacing + SLACK;
        let mut items = Vec::new();
        let mut too_large = Vec::new();
        // A quad is its own hull when its outline has just the hull's four corners.
        let own: Vec<bool> = parts
            .iter()
            .zip(&hulls)
            .map(|(p, h)| {
                h.len() == 4 && h.iter().all(|c| p.contains(c)) && {
                    let mut distinct = p.clone();
                    distinct.dedup();
                    if distinct.len() > 1 && distinct.first() == distinct.last() {
                        distinct.pop();
                    }
                    distinct.len() == 4
                }
            })
            .collect();
        for (members, hull) in self.items(&hulls, &own, opts) {
            if let Some(item) = make_item(members.clone(), &hull, &hulls, d, opts, &container)? {
                items.push(item);
                continue;
            }
            // Too big: a pair's parts go alone; a part alone is reported.
            for m in members {
                let single = Member {
                    angle: 0.0,
                    offset: DVec2::ZERO,
                    ..m
                };
                let hull = &hulls[m.part];
                match make_item(vec![single], hull, &hulls, d, opts, &container)? {
                    Some(item) => items.push(item),
                    None => too_large.push((m.part, smallest(hull, &opts.rotations))),
                }
            }
        }
        too_large.sort_by_key(|t| t.0);
        Ok((items, too_large))
    }

    /// Denser sheets (see [`crate::fabricate::separate`]): for each sheet but the last, given
    /// work enough, the sheet is first compressed (its items separated into a room shorter
    /// along x by a step at a time, the step shrinking while that fails and growing while it
    /// succeeds), then items from later sheets (the last sheet's first, smallest first) are put onto it where they
    /// overlap least and the overlaps separated; an item that cannot be taken is not offered
    /// again, nor anything at least as large both ways. Sheets left empty are dropped, and the
    /// last sheet is packed towards its origin edge ([`Self::pack_last`], with
    /// `opts.pack_last`). Every sheet changed is checked in jagua-rs's arithmetic before it is
    /// kept. Returns the number of sheets.
    fn densify(
        &self,
        items: &[Item],
        at: &mut Spots,
        container: &Container,
        opts: &NestOptions,
    ) -> Result<usize, NestError> {
        use crate::fabricate::separate::{entry, Form, Separation, EVALS_PER_SECOND};
        let forms: Vec<Vec<Form>> = items
            .iter()
            .map(|it| it.shapes.iter().map(|s| Form::new(s.pts.clone())).collect())
            .collect();
        let budget = (opts.time * EVALS_PER_SECOND) as u64;
        let per_try = budget / 8;
        let mut used = 0u64;
        let mut sheets = at.iter().map(|a| a.0).max().map_or(0, |m| m + 1);
        let dims = |i: usize| {
            let s = items[i].shapes[0].size;
            DVec2::new(s.x.min(s.y), s.x.max(s.y))
        };
        let mut attempt = 0u64;
        for k in 0..sheets.saturating_sub(1) {
            // Compression first: the sheet's items pushed into a shorter room, a step at a
            // time, while the separation clears every overlap (the room's far end freed).
            // Half of this sheet's share of the work at most, the rest to fill the room freed;
            // none when the share is too small to compress (under 5 s of work), so that short
            // budgets go to filling alone. Along x first, then y.
            let sheets_left = (sheets - 1 - k) as u64;
            let share = (budget - used.min(budget)) / sheets_left.max(1);
            let stop = if share >= COMPRESS_WORK {
                used + share / 2
            } else {
                used
            };
            let work = Work {
                stop,
                per_try,
                seed: opts.seed,
            };
            for axis in [DVec2::X, DVec2::Y] {
                self.compress(
                    items,
                    &forms,
                    at,
                    container,
                    (k, axis),
                    work,
                    &mut used,
                    &mut attempt,
                )?;
            }
            let mut refused: Vec<DVec2> = Vec::new();
            loop {
                crate::stage::checkpoint(self.progress)?;
                if used >= budget {
                    break;
                }
                let mut later: Vec<usize> = (0..items.len())
                    .filter(|&i| at[i].0 > k)
                    .filter(|&i| {
                        let d = dims(i);
                        !refused
                            .iter()
                            .any(|r| r.x <= d.x + 1e-9 && r.y <= d.y + 1e-9)
                    })
                    .collect();
                later.sort_by(|&a, &b| {
                    at[b]
                        .0
                        .cmp(&at[a].0)
                        .then(items[a].area.total_cmp(&items[b].area))
                        .then(a.cmp(&b))
                });
                let Some(&c) = later.first() else { break };
                let spots = sheet_spots(at, k);
                attempt += 1;
                let seed = attempt_seed(opts.seed, attempt);
                let new = entry(&forms, container.size, CLEAR, &spots, c, seed);
                let mut all = spots;
                all.push(new);
                let fresh = all.len() - 1;
                let mut sep = Separation::new(&forms, container.size, CLEAR, all, fresh, seed);
                let done = sep.run(per_try.min(budget - used));
                used += sep.work;
                let checked = done && confirmed(items, container, at, &sep.spots, Some(c));
                if checked {
                    for s in &sep.spots {
                        at[s.item] = (k, s.form, s.at);
                    }
                } else {
                    refused.retain(|r| !(dims(c).x <= r.x && dims(c).y <= r.y));
                    refused.push(dims(c));
                }
            }
        }
        // Drop empty sheets.
        let mut count = vec![0usize; sheets];
        for a in at.iter() {
            count[a.0] += 1;
        }
        let mut renumber = vec![0usize; sheets];
        let mut next = 0;
        for (k, &c) in count.iter().enumerate() {
            renumber[k] = next;
            if c > 0 {
                next += 1;
            }
        }
        for a in at.iter_mut() {
            a.0 = renumber[a.0];
        }
        sheets = next;
        if opts.pack_last {
            let work = Work {
                stop: budget,
                per_try,
                seed: opts.seed,
            };
            self.pack_last(
                items,
                &forms,
                at,
                container,
                sheets,
                work,
                &mut used,
                &mut attempt,
            )?;
        }
        Ok(sheets)
    }

    /// Separates sheet `k`'s items into a room made shorter along `axis` by a step at a time
    /// while the separation clears every overlap (the room's far end freed): the step starts
    /// at [`COMPRESS_STEP`] of the container's length, grows by half after two successes in a
    /// row and halves after [`COMPRESS_TRIES`] seeds fail, down to [`COMPRESS_LEAST`]; until
    /// `used` reaches `work.stop`. Every compressed sheet is confirmed by jagua-rs.
    #[allow(clippy::too_many_arguments)]
    fn compress(
        &self,
        items: &[Item],
        forms: &[Vec<crate::fabricate::separate::Form>],
        at: &mut Spots,
        container: &Container,
        (k, axis): (usize, DVec2),
        work: Work,
        used: &mut u64,
        attempt: &mut u64,
    ) -> Result<(), NestError> {
        use crate::fabricate::separate::Separation;
        let longest = COMPRESS_STEP * container.size.dot(axis);
        let mut step = longest;
        let mut failed = 0;
        let mut gained = 0;
        while step >= COMPRESS_LEAST && *used < work.stop {
            crate::stage::checkpoint(self.progress)?;
            let spots = sheet_spots(at, k);
            let extent = spots
                .iter()
                .map(|s| (s.at + forms[s.item][s.form].size).dot(axis))
                .fold(0.0, f64::max)
                + CLEAR;
            *attempt += 1;
            let seed = attempt_seed(work.seed, *attempt);
            let room = container.size - axis * (container.size.dot(axis) - extent + step);
            let known = spots.len();
            let mut sep = Separation::new(forms, room, CLEAR, spots, known, seed);
            let done = sep.run((4 * work.per_try).min(work.stop.saturating_sub(*used)));
            *used += sep.work;
            let checked = done && confirmed(items, container, at, &sep.spots, None);
            if checked {
                for s in &sep.spots {
                    at[s.item] = (k, s.form, s.at);
                }
                failed = 0;
                // Two steps in a row: a longer one.
                gained += 1;
                if gained % 2 == 0 {
                    step = (1.5 * step).min(longest);
                }
            } else {
                gained = 0;
                // Another seed first, then a smaller step.
                failed += 1;
                if failed == COMPRESS_TRIES {
                    step *= 0.5;
                    failed = 0;
                }
            }
        }
        Ok(())
    }

    /// The last sheet (`sheets - 1`) packed towards its origin edge, so that what it leaves is
    /// one rectangle right across the sheet: its items filled again (largest first) into rooms
    /// cut short along y, and along x, the shortest room that still takes them all found by
    /// bisection ([`STRIP_STEPS`] fills each way); the strip of least area is kept (the fill
    /// as it was if that is smaller), then compressed along its length with the work left
    /// (none below [`COMPRESS_WORK`]).
    #[allow(clippy::too_many_arguments)]
    fn pack_last(
        &self,
        items: &[Item],
        forms: &[Vec<crate::fabricate::separate::Form>],
        at: &mut Spots,
        container: &Container,
        sheets: usize,
        work: Work,
        used: &mut u64,
        attempt: &mut u64,
    ) -> Result<(), NestError> {
        let Some(k) = sheets.checked_sub(1) else {
            return Ok(());
        };
        let last: Vec<usize> = (0..items.len()).filter(|&i| at[i].0 == k).collect();
        if last.is_empty() {
            return Ok(());
        }
        let mut order = last.clone();
        order.sort_by(|&a, &b| items[b].area.total_cmp(&items[a].area).then(a.cmp(&b)));
        // How far along `axis` the items reach where `at` has them, and the strip's area.
        let reach = |at: &Spots, axis: DVec2| {
            last.iter()
                .map(|&i| (at[i].2 + items[i].shapes[at[i].1].size).dot(axis))
                .fold(0.0, f64::max)
        };
        let cross = |axis: DVec2| container.size.dot(DVec2::ONE - axis);
        let area_of = |at: &Spots, axis: DVec2| reach(at, axis) * cross(axis);
        let mut best: (f64, DVec2, Option<Spots>) = [DVec2::Y, DVec2::X]
            .into_iter()
            .map(|axis| (area_of(at, axis), axis, None))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("two axes");
        let grown: f64 = last.iter().map(|&i| items[i].grown_area).sum();
        // Each way on its own thread: the shortest room found and the spots it gave.
        let search = |axis: DVec2| -> Result<Option<(f64, DVec2, Spots)>, NestError> {
            let mut found: Option<(f64, DVec2, Spots)> = None;
            let full = container.size.dot(axis);
            // No room shorter than the thinnest way each item can lie, nor than its items'
            // area over the sheet's width.
            let thinnest = last
                .iter()
                .map(|&i| {
                    items[i]
                        .shapes
                        .iter()
                        .map(|s| s.size.dot(axis))
                        .fold(f64::INFINITY, f64::min)
                })
                .fold(0.0, f64::max)
                + 2.0 * CLEAR;
            let (mut lo, mut hi) = (thinnest.max(grown / cross(axis)), reach(at, axis));
            for _ in 0..STRIP_STEPS {
                if hi - lo < COMPRESS_LEAST {
                    break;
                }
                let mid = 0.5 * (lo + hi);
                let room = Container {
                    size: container.size - axis * (full - mid),
                    corner: container.corner,
                    config: container.config,
                };
                let seed = work.seed ^ 0x5eed;
                // A fill that needs a second sheet stops there: the room is too short.
                let filled = match self.fill(items, &order, &room, seed, false, 1) {
                    Ok(filled) => filled.map(|(spots, _)| spots),
                    // An item that lies on no start of the empty room: too short.
                    Err(NestError::Engine(..)) => None,
                    Err(e) => return Err(e),
                };
                match filled {
                    Some(spots) => {
                        let mut moved = at.clone();
                        for &i in &last {
                            moved[i] = (k, spots[i].1, spots[i].2);
                        }
                        let area = area_of(&moved, axis);
                        if found.as_ref().is_none_or(|f| area < f.0) {
                            found = Some((area, axis, moved));
                        }
                        hi = mid;
                    }
                    None => lo = mid,
                }
            }
            Ok(found)
        };
        let (along_y, along_x) = rayon::join(|| search(DVec2::Y), || search(DVec2::X));
        for (area, axis, moved) in [along_y?, along_x?].into_iter().flatten() {
            if area < best.0 {
                best = (area, axis, Some(moved));
            }
        }
        // The fill checked every item against those before it in jagua-rs's arithmetic.
        let (_, axis, moved) = best;
        if let Some(moved) = moved {
            *at = moved;
        }
        if work.stop.saturating_sub(*used) >= COMPRESS_WORK {
            self.compress(items, forms, at, container, (k, axis), work, used, attempt)?;
        }
        Ok(())
    }
}

/// A densifying search's limits: where its work stops, each separation's share, the seed.
#[derive(Clone, Copy)]
struct Work {
    stop: u64,
    per_try: u64,
    seed: u64,
}

/// The items on sheet `k` where `at` has them.
fn sheet_spots(at: &Spots, k: usize) -> Vec<Spot> {
    at.iter()
        .enumerate()
        .filter(|(_, a)| a.0 == k)
        .map(|(i, a)| Spot {
            item: i,
            form: a.1,
            at: a.2,
        })
        .collect()
}

/// A separation attempt's own seed.
fn attempt_seed(seed: u64, attempt: u64) -> u64 {
    seed ^ attempt.wrapping_mul(0x9e37_79b9_7f4a_7c15)
}

/// Whether jagua-rs agrees that every spot moved from where `at` has it (or the new item
/// `new`) is clear of the rest, as the fill checks each item against those placed before it
/// (the spots that stayed were checked when placed).
fn confirmed(
    items: &[Item],
    container: &Container,
    at: &Spots,
    spots: &[Spot],
    new: Option<usize>,
) -> bool {
    let mut sheet = container.sheet();
    let stayed = |s: &&Spot| Some(s.item) != new && (at[s.item].1, at[s.item].2) == (s.form, s.at);
    let mut ok = true;
    for s in spots.iter().filter(stayed) {
        let shape = &items[s.item].shapes[s.form];
        ok &= sheet.place(shape, s.at, s.item as u32).is_ok();
    }
    for s in spots.iter().filter(|s| !stayed(s)) {
        let shape = &items[s.item].shapes[s.form];
        ok = ok && !sheet.collides(shape, s.at) && sheet.place(shape, s.at, s.item as u32).is_ok();
    }
    ok
}

/// An item of these members (their hull `hull`) grown by `d`, at every allowed rotation that
/// fits the container; None if none fits.
fn make_item(
    members: Vec<Member>,
    hull: &[DVec2],
    hulls: &[Vec<DVec2>],
    d: f64,
    opts: &NestOptions,
    container: &Container,
) -> Result<Option<Item>, NestError> {
    let grown = grow(hull, d);
    let mut shapes = Vec::new();
    for a in angles(&grown, &opts.rotations) {
        let s = shape(&grown, a).map_err(|m| NestError::Engine(members[0].part, m))?;
        if s.size.x <= container.size.x - 2.0 * CLEAR && s.size.y <= container.size.y - 2.0 * CLEAR
        {
            shapes.push(s);
        }
    }
    if shapes.is_empty() {
        return Ok(None);
    }
    Ok(Some(Item {
        area: members.iter().map(|m| area(&hulls[m.part])).sum(),
        members,
        grown_area: area(&grown),
        shapes,
    }))
}

/// The hull's bounding box at the allowed rotation that makes it smallest (for messages).
fn smallest(hull: &[DVec2], rotations: &Rotations) -> DVec2 {
    angles(hull, rotations)
        .into_iter()
        .filter_map(|a| shape(hull, a).ok())
        .map(|s| s.size)
        .min_by(|a, b| a.max_element().total_cmp(&b.max_element()))
        .unwrap_or(DVec2::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(w: f64, h: f64) -> Vec<DVec2> {
        vec![
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w, h),
            DVec2::new(0.0, h),
        ]
    }

    fn trapezoid(w: f64, h: f64, lean: f64) -> Vec<DVec2> {
        vec![
            DVec2::ZERO,
            DVec2::new(w, 0.0),
            DVec2::new(w - lean, h),
            DVec2::new(lean, h),
        ]
    }

    fn gap(a: &[DVec2], b: &[DVec2]) -> f64 {
        convex_distance(a, b)
    }

    fn placed(parts: &[Vec<DVec2>], n: &Nesting) -> Vec<Vec<DVec2>> {
        parts
            .iter()
            .zip(&n.places)
            .map(|(p, pl)| p.iter().map(|q| pl.apply(*q)).collect())
            .collect()
    }

    fn assert_valid(parts: &[Vec<DVec2>], n: &Nesting, opts: &NestOptions) {
        let out = placed(parts, n);
        for (i, p) in out.iter().enumerate() {
            for q in p {
                assert!(
                    q.x >= opts.margin - 1e-9 && q.y >= opts.margin - 1e-9,
                    "{i}: {q}"
                );
                assert!(q.x <= opts.sheet.x - opts.margin + 1e-9, "{i}: {q}");
                assert!(q.y <= opts.sheet.y - opts.margin + 1e-9, "{i}: {q}");
            }
            for (j, other) in out.iter().enumerate().take(i) {
                if n.places[i].sheet == n.places[j].sheet {
                    let g = gap(p, other);
                    assert!(g >= opts.spacing, "parts {i} and {j} are {g} apart");
                }
            }
        }
    }

    #[test]
    fn contact_distance_is_exact_for_boxes_and_slopes() {
        let a = rect(10.0, 10.0);
        let b: Vec<DVec2> = rect(10.0, 10.0)
            .iter()
            .map(|p| *p + DVec2::new(-30.0, 0.0))
            .collect();
        assert!((contact(&a, &b, DVec2::NEG_X) - 20.0).abs() < 1e-12);
        assert_eq!(contact(&a, &b, DVec2::NEG_Y), f64::INFINITY);
        // A box over a slope rising to the left: its lower-left corner lands on it.
        let slope = vec![
            DVec2::new(-20.0, -20.0),
            DVec2::new(20.0, -20.0),
            DVec2::new(-20.0, 0.0),
        ];
        let d = contact(&a, &slope, DVec2::NEG_Y);
        assert!((d - 10.0).abs() < 1e-12, "{d}");
    }

    #[test]
    fn grown_hull_holds_every_point_within_the_distance() {
        let t = trapezoid(100.0, 20.0, 30.0); // sharp corners (34°), bevelled
        let g = grow(&t, 3.0);
        for (k, corner) in t.iter().enumerate() {
            for a in 0..36 {
                let q = *corner + DVec2::from_angle(a as f64 * 10f64.to_radians()) * 3.0;
                assert!(
                    gap(&g, &[q, q + DVec2::X * 1e-9, q + DVec2::Y * 1e-9]) <= 1e-9,
                    "corner {k} at {a}0°: {g:?}"
                );
            }
        }
        assert!(area(&g) < area(&grow(&t, 0.0)) + 3.0 * 300.0);
    }

    #[test]
    fn the_last_sheet_is_packed_into_a_strip_across_it() {
        // Eighty trapezoids of assorted sizes and leans on one sheet: packed, every part is
        // still the spacing apart and inside the margins, the strip no larger than the fill
        // alone leaves either way (here 0.8 % smaller), and the same on every run.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let parts: Vec<Vec<DVec2>> = (0..80)
            .map(|_| {
                let w = rng.random_range(80.0..300.0);
                trapezoid(
                    w,
                    rng.random_range(40.0..160.0),
                    rng.random_range(0.0..0.3) * w,
                )
            })
            .collect();
        let opts = NestOptions {
            sheet: DVec2::new(3000.0, 1500.0),
            time: 0.05,
            tries: 2,
            ..Default::default()
        };
        let strip = |n: &Nesting| {
            let out = placed(&parts, n);
            let reach = |axis: DVec2| {
                out.iter()
                    .flatten()
                    .map(|q| q.dot(axis))
                    .fold(0.0, f64::max)
            };
            (reach(DVec2::X) * opts.sheet.y).min(reach(DVec2::Y) * opts.sheet.x)
        };
        let packed = BottomLeft::default().nest(&parts, &opts).expect("fits");
        assert_valid(&parts, &packed, &opts);
        assert_eq!(packed.sheets, 1);
        let filled = BottomLeft::default()
            .nest(
                &parts,
                &NestOptions {
                    pack_last: false,
                    ..opts.clone()
                },
            )
            .expect("fits");
        let (a, b) = (strip(&packed), strip(&filled));
        assert!(a < b, "strip {a} mm² packed, {b} mm² filled");
        let again = BottomLeft::default().nest(&parts, &opts).expect("fits");
        assert_eq!(again.places, packed.places);
    }

    #[test]
    fn a_fill_held_to_one_sheet_stops_where_it_needs_a_second_and_is_otherwise_the_same() {
        // 900 × 700 blocks, 10 mm apart: six to a 3000 × 1500 sheet, so eight need two.
        let opts = NestOptions {
            sheet: DVec2::new(3000.0, 1500.0),
            margin: 0.0,
            spacing: 10.0,
            ..Default::default()
        };
        let container = Container::new(&opts);
        let hulls = vec![rect(900.0, 700.0); 8];
        let d = 0.5 * opts.spacing + SLACK;
        let items: Vec<Item> = (0..hulls.len())
            .map(|part| {
                let member = Member {
                    part,
                    angle: 0.0,
                    offset: DVec2::ZERO,
                };
                make_item(vec![member], &hulls[part], &hulls, d, &opts, &container)
                    .expect("a shape")
                    .expect("fits the sheet")
            })
            .collect();
        let nester = BottomLeft::default();
        let fill = |order: &[usize], most| {
            nester
                .fill(&items, order, &container, 1, false, most)
                .expect("no engine error")
        };
        let all: Vec<usize> = (0..8).collect();
        let (_, sheets) = fill(&all, usize::MAX).expect("no limit");
        assert_eq!(sheets.len(), 2);
        assert!(fill(&all, 1).is_none());
        let (free, _) = fill(&all[..6], usize::MAX).expect("no limit");
        let (held, sheets) = fill(&all[..6], 1).expect("six fit one sheet");
        assert_eq!(sheets.len(), 1);
        assert_eq!(held, free);
    }

    #[test]
    fn identical_rectangles_fill_a_sheet_in_rows() {
        let parts = vec![rect(290.0, 140.0); 100];
        let opts = NestOptions {
            sheet: DVec2::new(3000.0, 1500.0),
            margin: 0.0,
            spacing: 10.0,
            ..Default::default()
        };
        let n = BottomLeft::default().nest(&parts, &opts).expect("fits");
        assert_valid(&parts, &n, &opts);
        // 10 × 10 of 300 × 150 (with spacing) fill the sheet exactly.
        assert_eq!(n.sheets, 1);
    }

    #[test]
    fn trapezoids_pair_into_parallelograms() {
        // A trapezoid and its copy turned 180° against a leg, `gap` apart: a parallelogram of
        // twice the area plus gap × leg.
        let t = convex_hull(&trapezoid(400.0, 100.0, 80.0));
        let gap = 5.0;
        let (members, hull) = pair(0, &t, 1, &t, gap, true, false).expect("congruent quads pair");
        assert_eq!(members.len(), 2);
        assert_eq!(hull.len(), 4, "{hull:?}");
        let leg = DVec2::new(80.0, 100.0).length();
        assert!((area(&hull) - (2.0 * area(&t) + gap * leg)).abs() < 1e-6);
        assert!(pair(
            0,
            &t,
            1,
            &convex_hull(&rect(400.0, 100.0)),
            gap,
            true,
            false
        )
        .is_none());
        let parts = vec![trapezoid(400.0, 100.0, 80.0); 40];
        let opts = NestOptions {
            sheet: DVec2::new(1500.0, 1000.0),
            ..Default::default()
        };
        let paired = BottomLeft::default().nest(&parts, &opts).expect("fits");
        assert_valid(&parts, &paired, &opts);
        let alone = BottomLeft::default()
            .nest(
                &parts,
                &NestOptions {
                    pair: false,
                    ..opts.clone()
                },
            )
            .expect("fits");
        assert_valid(&parts, &alone, &opts);
        assert!(
            paired.sheets <= alone.sheets,
            "{} vs {}",
            paired.sheets,
            alone.sheets
        );
    }

    #[test]
    fn trapezoids_on_common_lines_share_a_whole_side_the_kerf_apart() {
        let parts = vec![trapezoid(400.0, 100.0, 80.0); 40];
        let opts = NestOptions {
            sheet: DVec2::new(1500.0, 1000.0),
            common_gap: Some(0.3),
            ..Default::default()
        };
        let n = BottomLeft::default().nest(&parts, &opts).expect("fits");
        let out = placed(&parts, &n);
        let mut lines = 0;
        for sheet in 0..n.sheets {
            let on: Vec<usize> = (0..parts.len())
                .filter(|&i| n.places[i].sheet == sheet)
                .collect();
            let outlines: Vec<Vec<DVec2>> = on.iter().map(|&i| out[i].clone()).collect();
            let found = crate::fabricate::cutpath::common_lines(&outlines, 0.3, COMMON_FIT);
            for (a, &i) in on.iter().enumerate() {
                for (b, &j) in on.iter().enumerate().take(a) {
                    let paired = found
                        .iter()
                        .any(|c| (c.first, c.second) == (b, a) || (c.first, c.second) == (a, b));
                    let g = gap(&out[i], &out[j]);
                    let least = if paired { 0.3 } else { opts.spacing };
                    assert!(g >= least - 1e-9, "parts {i} and {j} are {g} apart");
                }
            }
            for c in &found {
                // The line cut runs half the kerf off the first part's side, as long as it.
                let side = outlines[c.first][c.edge].distance(outlines[c.first][(c.edge + 1) % 4]);
                assert!((c.from.distance(c.to) - side).abs() < 1e-9);
            }
            lines += found.len();
        }
        assert_eq!(lines, 20, "every trapezoid paired on a common line");
        // A gap at or above the spacing is refused.
        let wide = NestOptions {
            common_gap: Some(5.0),
            ..opts
        };
        assert_eq!(
            BottomLeft::default().nest(&parts, &wide).unwrap_err(),
            NestError::CommonGap(5.0, 5.0)
        );
    }

    #[test]
    fn a_part_longer_than_the_sheet_is_named() {
        let parts = vec![rect(100.0, 50.0), rect(3500.0, 50.0), rect(10.0, 10.0)];
        let err = BottomLeft::default()
            .nest(&parts, &NestOptions::default())
            .unwrap_err();
        match err {
            NestError::TooLarge(list) => {
                assert_eq!(list.len(), 1);
                assert_eq!(list[0].0, 1);
            }
            e => panic!("{e}"),
        }
        let bad = NestOptions {
            spacing: -1.0,
            ..Default::default()
        };
        assert_eq!(
            BottomLeft::default().nest(&parts[..1], &bad).unwrap_err(),
            NestError::Spacing(-1.0)
        );
    }

    #[test]
    fn parts_too_large_for_every_stock_are_named_before_anything_is_nested() {
        /// Counts the nestings asked of the engine.
        struct Counting(std::cell::Cell<usize>);
        impl Nester for Counting {
            fn nest(&self, parts: &[Vec<DVec2>], opts: &NestOptions) -> Result<Nesting, NestError> {
                self.0.set(self.0.get() + 1);
                BottomLeft::default().nest(parts, opts)
            }
            fn too_large(
                &self,
                parts: &[Vec<DVec2>],
                opts: &NestOptions,
            ) -> Result<Misfits, NestError> {
                BottomLeft::default().too_large(parts, opts)
            }
        }
        // Family 0 fits; family 1's part 3 fits the larger stock only, part 4 neither; family
        // 2's part 5 neither.
        let parts = vec![
            rect(100.0, 50.0),
            rect(120.0, 60.0),
            rect(80.0, 80.0),
            rect(900.0, 50.0),
            rect(1500.0, 40.0),
            rect(1400.0, 30.0),
        ];
        let keys = [0, 0, 1, 1, 1, 2];
        let stock = [
            Stock {
                size: DVec2::new(600.0, 400.0),
                cost: 1.0,
            },
            Stock {
                size: DVec2::new(1000.0, 500.0),
                cost: 2.0,
            },
        ];
        let engine = Counting(Default::default());
        let err =
            nest_families(&engine, &parts, &keys, &stock, &NestOptions::default()).unwrap_err();
        let NestError::TooLarge(list) = err else {
            panic!("{err}");
        };
        // Part 3 fits the larger stock: not named.
        let named: Vec<usize> = list.iter().map(|t| t.0).collect();
        assert_eq!(named, [4, 5]);
        assert_eq!(engine.0.get(), 0, "no family was nested");
        // Without the parts that fit nowhere, every family is nested.
        let (n, _) = nest_families(
            &engine,
            &parts[..4],
            &keys[..4],
            &stock,
            &NestOptions::default(),
        )
        .expect("fits");
        assert_eq!(n.places.len(), 4);
        assert!(engine.0.get() > 0);
    }

    #[test]
    fn families_get_their_own_sheets_and_results_repeat() {
        let parts: Vec<Vec<DVec2>> = (0..60)
            .map(|k| {
                trapezoid(
                    150.0 + (k % 7) as f64 * 20.0,
                    60.0 + (k % 3) as f64 * 15.0,
                    20.0,
                )
            })
            .collect();
        let keys: Vec<u32> = (0..60).map(|k| (k % 2) as u32).collect();
        let opts = NestOptions {
            sheet: DVec2::new(800.0, 600.0),
            rotations: Rotations::Any,
            ..Default::default()
        };
        let stock = [Stock {
            size: opts.sheet,
            cost: 0.0,
        }];
        let (n, sheet_keys) =
            nest_families(&BottomLeft::default(), &parts, &keys, &stock, &opts).expect("fits");
        assert_valid(&parts, &n, &opts);
        for (p, k) in n.places.iter().zip(&keys) {
            assert_eq!(sheet_keys[p.sheet].0, *k);
        }
        let (again, _) =
            nest_families(&BottomLeft::default(), &parts, &keys, &stock, &opts).expect("fits");
        assert_eq!(n.places, again.places);
    }

    #[test]
    fn the_result_does_not_depend_on_the_thread_count() {
        let parts: Vec<Vec<DVec2>> = (0..80)
            .map(|k| {
                trapezoid(
                    120.0 + (k % 5) as f64 * 30.0,
                    50.0 + (k % 4) as f64 * 10.0,
                    15.0,
                )
            })
            .collect();
        let opts = NestOptions {
            sheet: DVec2::new(900.0, 600.0),
            tries: 2,
            ..Default::default()
        };
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool")
                .install(|| BottomLeft::default().nest(&parts, &opts).expect("fits"))
        };
        let (one, three) = (run(1), run(3));
        assert_valid(&parts, &one, &opts);
        assert_eq!(one.places, three.places);
    }

    #[test]
    fn a_part_the_size_of_the_usable_sheet_is_placed_or_reported_never_a_panic() {
        let opts = NestOptions {
            sheet: DVec2::new(1000.0, 500.0),
            ..Default::default()
        };
        // Usable: 980 × 480; the grown part needs 0.04 mm more than the part.
        let snug = vec![rect(979.9, 479.9)];
        let n = BottomLeft::default().nest(&snug, &opts).expect("fits");
        assert_valid(&snug, &n, &opts);
        let full = vec![rect(980.0, 480.0)];
        assert!(matches!(
            BottomLeft::default().nest(&full, &opts),
            Err(NestError::TooLarge(_))
        ));
    }
}
