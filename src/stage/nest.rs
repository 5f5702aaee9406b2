//! `nest`: plates on stock sheets, one sheet family per thickness (and group, if asked), each
//! part drawn as it is cut (pierce point, holes, tag upright, leads, micro-joints), with
//! remnants and machine time; nest.json as a typed document. The writers (sheet DXFs,
//! bom.csv, assembly.scad, sheets.svg) are separate calls.
//!
//! ```
//! use lamina::stage::{nest, planarize, plates, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/calyx_veins.json"))?;
//! let solved = planarize::run(&net, None, &planarize::Options::default(), &Quiet)?;
//! let made = plates::run(&solved.axes, &plates::Options::default())?;
//! let opts = nest::Options { tries: Some(1), ..Default::default() };
//! let cut = nest::run(made.records(), made.core_records(), &opts, &Quiet)?;
//! assert_eq!(cut.places.len(), made.set.plates.len());
//! assert!(cut.doc.placements.iter().all(|p| p.sheet.starts_with("sheet-")));
//! # Ok(()) }
//! ```

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::analyze::material::is_stainless;
use crate::fabricate::assembly::{axis_frame, write_scad_from_sheets, ScadCore, SheetPart};
pub use crate::fabricate::cutpath::CutOrder;
use crate::fabricate::cutpath::{common_lines, order_parts, plan_sheet, PartShape, SheetPlan};
use crate::fabricate::cutplan::{free_box, remnants, times, SpeedError, SpeedTable};
use crate::fabricate::cutsheet::{chain, place_joints, write_sheet_dxf, Drawn, Hole};
use crate::fabricate::nc::{self, Heading, Machine, NcFormat, Post};
use crate::fabricate::nest::{
    grown_hull, nest_families, BottomLeft, NestError, NestOptions, COMMON_FIT, SLACK,
};
pub use crate::fabricate::nest::{Place, Rotations, Stock};
pub use crate::fabricate::plates_file::MaterialRecord;
use crate::fabricate::plates_file::{CoreRecord, PlateRecord};
use crate::fabricate::preview::{sheets_svg, SheetView};
use crate::fabricate::tags::part_marks;
use crate::fabricate::tags::{strokes, text_width};
use crate::files::WriteError;
use crate::stage::{OptionError, Progress};

/// The most seeded tries: each is a whole nesting of every part.
pub const MAX_TRIES: usize = 1000;

/// How to nest. `Default` is the command's defaults.
#[derive(Clone, Debug)]
pub struct Options {
    /// Stock sheets to choose from per thickness, each with its cost; the cheapest mix is
    /// cut. Default: one 3000 × 1500 mm sheet at no cost.
    pub stock: Vec<Stock>,
    /// Kept clear along every sheet edge, mm. Default 10.
    pub margin: f64,
    /// Least distance between parts (kerf plus clearance), mm. Default 5.
    pub spacing: f64,
    /// Allowed rotations. Default 0, 90, 180, 270.
    pub rotations: Rotations,
    /// Each assembly group on sheets of its own. Default false.
    pub keep_groups: bool,
    /// Seeded tries, the best kept. Default: 8 up to 250 plates, fewer above, 1 from 2,000.
    pub tries: Option<usize>,
    /// Default 1.
    pub seed: u64,
    /// Do not pair congruent quads turned 180°. Default false.
    pub no_pairs: bool,
    /// Free rectangles at least this big (either way round) are remnants, mm. Default 300 ×
    /// 300.
    pub remnant_min: DVec2,
    /// Lead-in and lead-out lines this long in the scrap, mm (at most half the spacing).
    /// Default: none.
    pub lead_in: Option<f64>,
    /// Uncut bridges (1 to 8) on the outer contour of parts smaller than
    /// `micro_joint_below`. Default: none.
    pub micro_joints: Option<usize>,
    /// Parts whose bounding box's longer side is under this get micro-joints, mm. Default
    /// 200.
    pub micro_joint_below: f64,
    /// Width of a micro-joint along the contour, mm. Default 0.5.
    pub micro_joint_width: f64,
    /// The plates' steel (plates.json's). Default: 1.4404, 8.0 g/cm³.
    pub material: MaterialRecord,
    /// Cutting, pierce and marking speeds by thickness. Default: typical figures for the
    /// material (stainless or carbon steel).
    pub speeds: Option<SpeedTable>,
    /// Where the speeds came from, for errors. Default "the built-in speed table".
    pub speeds_name: String,
    /// Width of the cut, mm: NC paths run half of it outside outer contours and inside holes
    /// (the DXFs keep the nominal contours). Less than the spacing. Default 0.
    pub kerf: f64,
    /// How parts follow one another on a sheet. Default [`CutOrder::Travel`].
    pub cut_order: CutOrder,
    /// Common-line cutting: congruent quads (each its own hull) are paired the kerf apart along
    /// a whole side, which is cut once; the second part's contour starts in that kerf. Needs a
    /// kerf, pairs, and no micro-joints. Default false.
    pub common_line: bool,
    /// The job's name, etched on each sheet's label. Default: none (the label has the sheet
    /// number, grade and thickness).
    pub job: Option<String>,
    /// A date (or any short text) etched on each sheet's label. Default: none, so that the
    /// same inputs give the same bytes.
    pub date: Option<String>,
    /// Work spent making the sheets denser after the fill, in seconds of the reference
    /// machine (counted as work: the result does not depend on the machine's speed), from more
    /// than 0 to [`MAX_TIME`]; the last sheet of each family is then packed into a strip from
    /// its origin edge with another `time / N` for N sheets. Default 2.
    pub time: f64,
}

/// The most `time`, s.
pub const MAX_TIME: f64 = 600.0;

impl Default for Options {
    fn default() -> Self {
        Options {
            stock: vec![Stock {
                size: DVec2::new(3000.0, 1500.0),
                cost: 0.0,
            }],
            margin: 10.0,
            spacing: 5.0,
            rotations: Rotations::Listed(vec![0.0, 90.0, 180.0, 270.0]),
            keep_groups: false,
            tries: None,
            seed: 1,
            no_pairs: false,
            remnant_min: DVec2::new(300.0, 300.0),
            lead_in: None,
            micro_joints: None,
            micro_joint_below: 200.0,
            micro_joint_width: 0.5,
            material: MaterialRecord::unstated(),
            speeds: None,
            speeds_name: "the built-in speed table".into(),
            kerf: 0.0,
            cut_order: CutOrder::Travel,
            common_line: false,
            job: None,
            date: None,
            time: 2.0,
        }
    }
}

/// `WIDTHxHEIGHT` in mm.
pub fn parse_sheet(s: &str) -> Result<DVec2, String> {
    let (w, h) = s
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("`{s}`: give the size as WIDTHxHEIGHT in mm, like 3000x1500"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
            .ok_or_else(|| format!("`{s}`: `{t}` is not a positive size in mm"))
    };
    Ok(DVec2::new(num(w)?, num(h)?))
}

/// `WIDTHxHEIGHT:COST`.
pub fn parse_stock(s: &str) -> Result<Stock, String> {
    let (size, cost) = s.split_once(':').ok_or_else(|| {
        format!("`{s}`: give a stock sheet as WIDTHxHEIGHT:COST, like 3000x1500:120")
    })?;
    let cost: f64 = cost
        .trim()
        .parse()
        .ok()
        .filter(|c: &f64| c.is_finite() && *c >= 0.0 && *c <= 1e12)
        .ok_or_else(|| format!("`{s}`: `{cost}` is not a cost from 0 to 1e12"))?;
    Ok(Stock {
        size: parse_sheet(size)?,
        cost,
    })
}

/// Angles in degrees, comma-separated, or `any`.
pub fn parse_rotations(s: &str) -> Result<Rotations, String> {
    if s.trim().eq_ignore_ascii_case("any") {
        return Ok(Rotations::Any);
    }
    s.split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("`{t}` is not an angle in degrees (or give `any`)"))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Rotations::Listed)
}

/// One sheet of the result.
#[derive(Clone, Debug)]
pub struct SheetInfo {
    /// The file's name.
    pub file: String,
    /// Thickness, mm.
    pub thickness: f64,
    /// Set with `keep_groups`.
    pub group: Option<u32>,
    /// The stock sheet.
    pub stock: Stock,
    /// The plates on it, by index.
    pub parts: Vec<usize>,
    /// Area of the parts on it, mm².
    pub area: f64,
    /// Free rectangles [lower-left, upper-right] left for later jobs.
    pub remnants: Vec<[DVec2; 2]>,
    /// Cut length, mm (contours and leads, less micro-joints and common lines' second sides).
    pub cut_mm: f64,
    /// Pierces: one per contour, one after each micro-joint, none for a common line's second part.
    pub pierces: usize,
    /// Etched length, mm.
    pub etch_mm: f64,
    /// Lead-in and lead-out length, mm.
    pub lead_mm: f64,
    /// Micro-joints.
    pub joints: usize,
    /// Seconds: laser, plasma.
    pub time_s: (f64, f64),
    /// Rapid travel, mm (from the origin through every contour, as the NC program runs).
    pub rapid_mm: f64,
    /// The label etched on the sheet, None when no free place was found for it.
    pub label: Option<String>,
    /// Common lines: the two plates (the first cut first) and the line cut once, mm.
    pub common: Vec<([usize; 2], DVec2, DVec2)>,
}

/// Micro-joints as asked for.
#[derive(Clone, Copy, Debug)]
pub struct Joints {
    /// Micro-joints per part.
    pub per_part: usize,
    /// Parts smaller than this get micro-joints, mm.
    pub below: f64,
    /// Width, mm.
    pub width: f64,
}

impl Joints {
    /// Whether a plate (its outline in its own frame) is small enough to get joints.
    pub fn applies(&self, outline: &[DVec2]) -> bool {
        size(outline).max_element() < self.below
    }

    /// Kept from corners, the pierce point and each other, mm.
    pub fn clear(&self) -> f64 {
        (2.0 * self.width).max(2.0)
    }
}

/// The nest: every plate's place and drawing, the sheets, and nest.json.
#[derive(Clone, Debug)]
pub struct Nested {
    /// Plates.
    pub plates: Vec<PlateRecord>,
    /// Node cores (tubes).
    pub cores: Vec<CoreRecord>,
    /// One per plate, in plate order.
    pub places: Vec<Place>,
    /// Each plate as cut on its sheet, in plate order.
    pub drawn: Vec<Drawn>,
    /// Sheets.
    pub sheets: Vec<SheetInfo>,
    /// Micro-joints.
    pub joints: Option<Joints>,
    /// nest.json.
    pub doc: NestDoc,
    /// The spacing parts keep, mm (for the assembly's clip polygons).
    pub spacing: f64,
    /// The plates' steel.
    pub material: MaterialRecord,
    /// Each sheet's cut path, in sheet order.
    pub plans: Vec<SheetPlan>,
    /// The speeds the times (and NC feeds) come from.
    pub speeds: SpeedTable,
    /// Width of the cut, mm.
    pub kerf: f64,
}

impl SheetInfo {
    /// Part area over this sheet's stock area.
    pub fn utilisation(&self) -> f64 {
        self.area / (self.stock.size.x * self.stock.size.y)
    }
}

impl Nested {
    /// Part area over stock area, all sheets together.
    pub fn utilisation(&self) -> f64 {
        let used: f64 = self.sheets.iter().map(|s| s.area).sum();
        let stock: f64 = self
            .sheets
            .iter()
            .map(|s| s.stock.size.x * s.stock.size.y)
            .sum();
        used / stock
    }

    /// Micro-joints per plate (fewer than asked where its sides are too short).
    pub fn joint_counts(&self) -> Vec<usize> {
        self.drawn.iter().map(|d| d.joints.len()).collect()
    }

    /// The stock's cost over all sheets (0 when no costs were given).
    pub fn cost(&self) -> f64 {
        self.sheets.iter().map(|s| s.stock.cost).sum()
    }

    /// Per thickness, in the order the thicknesses first appear among the sheets: sheets, part
    /// area, use, cost, remnants and laser time.
    pub fn by_thickness(&self) -> Vec<ThicknessSummary> {
        let mut out: Vec<ThicknessSummary> = Vec::new();
        let mut stock_area: Vec<f64> = Vec::new();
        for s in &self.sheets {
            let k = match out.iter().position(|t| t.thickness == s.thickness) {
                Some(k) => k,
                None => {
                    out.push(ThicknessSummary {
                        thickness: s.thickness,
                        sheets: 0,
                        part_area_mm2: 0.0,
                        utilisation: 0.0,
                        cost: 0.0,
                        remnants: 0,
                        laser_s: 0.0,
                    });
                    stock_area.push(0.0);
                    out.len() - 1
                }
            };
            let t = &mut out[k];
            t.sheets += 1;
            t.part_area_mm2 += s.area;
            t.cost += s.stock.cost;
            t.remnants += s.remnants.len();
            t.laser_s += s.time_s.0;
            stock_area[k] += s.stock.size.x * s.stock.size.y;
        }
        for (t, stock) in out.iter_mut().zip(stock_area) {
            t.utilisation = t.part_area_mm2 / stock;
        }
        out
    }
}

/// The sheets of one thickness.
#[derive(Clone, Debug, Serialize)]
pub struct ThicknessSummary {
    /// Plate thickness, mm.
    pub thickness: f64,
    /// Sheets cut.
    pub sheets: usize,
    /// Area of the parts, mm².
    pub part_area_mm2: f64,
    /// Part area over stock area.
    pub utilisation: f64,
    /// Stock cost.
    pub cost: f64,
    /// Remnants kept.
    pub remnants: usize,
    /// Estimated laser time, s.
    pub laser_s: f64,
}

/// Why no nest was made.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(
        "{count} plate(s) fit no {sheet_w} × {sheet_h} mm sheet ({usable_w:.0} × {usable_h:.0} mm inside the margin) at any allowed rotation: {names}"
    )]
    /// Parts that fit no sheet.
    TooLarge {
        /// How many plates fit no sheet.
        count: usize,
        /// The largest sheet's width, mm.
        sheet_w: f64,
        /// The largest sheet's height, mm.
        sheet_h: f64,
        /// Usable width inside the margin, mm.
        usable_w: f64,
        /// Usable height inside the margin, mm.
        usable_h: f64,
        /// The parts that fit nowhere.
        names: String,
    },
    #[error("plate {id}: {source}")]
    /// A plate the nester refused.
    Plate {
        /// The plate's tag.
        id: String,
        /// What the nester said.
        source: NestError,
    },
    #[error(transparent)]
    /// The nester failed.
    Nest(NestError),
    #[error(transparent)]
    /// A file could not be written.
    Write(#[from] WriteError),
    #[error("{table}: the time estimate for {sheet}: {source}")]
    /// The speed table has no row for a thickness.
    Speeds {
        /// The speed table's name.
        table: String,
        /// The sheet file.
        sheet: String,
        /// Where the input came from.
        source: SpeedError,
    },
}

impl Error {
    /// Whether the caller stopped the nest.
    pub fn is_cancelled(&self) -> bool {
        matches!(self, Error::Nest(NestError::Cancelled(_)))
    }
}

fn thickness_name(t: f64) -> String {
    let s = format!("{t:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

impl Options {
    fn check(&self, plates: usize) -> Result<(NestOptions, Option<Joints>), OptionError> {
        if self.stock.is_empty() {
            return Err(OptionError::new(
                "stock",
                "is empty: give one sheet size or more",
            ));
        }
        if let Some(l) = self.lead_in {
            if !(l > 0.0 && l <= 0.5 * self.spacing) {
                return Err(OptionError::new(
                    "lead_in",
                    format!(
                        "must be more than 0 and at most half the spacing ({} mm), so that it stays in the scrap between parts; got {}",
                        0.5 * self.spacing,
                        crate::text::num(l)
                    ),
                ));
            }
        }
        if !(self.kerf.is_finite() && self.kerf >= 0.0 && self.kerf < self.spacing) {
            return Err(OptionError::new(
                "kerf",
                format!(
                    "must be at least 0 and less than the spacing ({} mm), so that the cuts of neighbouring parts never meet; got {}",
                    crate::text::num(self.spacing),
                    crate::text::num(self.kerf)
                ),
            ));
        }
        if self.common_line {
            let why = if self.kerf == 0.0 {
                Some("needs a kerf (the gap cut once between the two parts)")
            } else if self.no_pairs {
                Some("pairs congruent quads, so it cannot go with no pairs")
            } else if self.micro_joints.is_some() {
                Some("cannot go with micro-joints (a common line's second part is cut from the first one's kerf)")
            } else {
                None
            };
            if let Some(why) = why {
                return Err(OptionError::new("common_line", why.to_string()));
            }
        }
        for (name, text, most) in [("job", &self.job, 40), ("date", &self.date, 20)] {
            if let Some(t) = text {
                if t.trim().is_empty()
                    || t.chars().count() > most
                    || t.chars().any(char::is_control)
                {
                    return Err(OptionError::new(
                        name,
                        format!("must be 1 to {most} printable characters, got {t:?}"),
                    ));
                }
            }
        }
        super::positive("time", self.time, MAX_TIME, "s")?;
        super::positive("micro_joint_below", self.micro_joint_below, 1e6, "mm")?;
        super::positive("micro_joint_width", self.micro_joint_width, 10.0, "mm")?;
        let joints = match self.micro_joints {
            None => None,
            Some(n @ 1..=8) => Some(Joints {
                per_part: n,
                below: self.micro_joint_below,
                width: self.micro_joint_width,
            }),
            Some(n) => {
                return Err(OptionError::new(
                    "micro_joints",
                    format!("must be from 1 to 8, got {n}"),
                ))
            }
        };
        let opts = NestOptions {
            sheet: self.stock[0].size,
            margin: self.margin,
            spacing: self.spacing,
            rotations: self.rotations.clone(),
            tries: self.tries.unwrap_or_else(|| NestOptions::tries_for(plates)),
            seed: self.seed,
            pair: !self.no_pairs,
            common_gap: self.common_line.then_some(self.kerf),
            time: self.time,
            pack_last: true,
        };
        if !(1..=MAX_TRIES).contains(&opts.tries) {
            return Err(OptionError::new(
                "tries",
                format!("must be from 1 to {MAX_TRIES}, got {}", opts.tries),
            ));
        }
        Ok((opts, joints))
    }
}

/// Nests `plates` (as plates.json holds them; `cores` are tubes, not nested, but listed).
/// `progress` counts the parts placed over all tries and stock sizes and can stop the nest
/// between parts.
pub fn run(
    plates: Vec<PlateRecord>,
    cores: Vec<CoreRecord>,
    opts: &Options,
    progress: &dyn Progress,
) -> Result<Nested, Error> {
    let (nest_opts, joints) = opts.check(plates.len())?;
    let speeds = opts
        .speeds
        .clone()
        .unwrap_or_else(|| SpeedTable::typical(is_stainless(&opts.material.grade)));
    let stock = &opts.stock;
    // Families: thickness (as its bits: positive floats order as their bits do), then group.
    let keys: Vec<(u64, u32)> = plates
        .iter()
        .map(|p| {
            (
                p.thickness.to_bits(),
                if opts.keep_groups { p.group } else { 0 },
            )
        })
        .collect();
    progress.begin(
        "nesting",
        Some(plates.len() as u64 * nest_opts.tries as u64 * stock.len() as u64),
    );
    let placed = std::sync::atomic::AtomicU64::new(0);
    let nester = BottomLeft::with_progress(progress, &placed);
    let outlines: Vec<Vec<DVec2>> = plates.iter().map(|p| p.outline.clone()).collect();
    let (nesting, sheet_keys) = nest_families(&nester, &outlines, &keys, stock, &nest_opts)
        .map_err(|e| named(e, &plates, stock, opts.margin))?;
    let places = nesting.places;
    let mut sheets: Vec<SheetInfo> = sheet_keys
        .iter()
        .enumerate()
        .map(|(k, &((bits, group), st))| {
            let t = f64::from_bits(bits);
            SheetInfo {
                file: format!("sheet-{:02}-{}mm.dxf", k + 1, thickness_name(t)),
                thickness: t,
                group: opts.keep_groups.then_some(group),
                stock: st,
                parts: Vec::new(),
                area: 0.0,
                remnants: Vec::new(),
                cut_mm: 0.0,
                pierces: 0,
                etch_mm: 0.0,
                lead_mm: 0.0,
                joints: 0,
                time_s: (0.0, 0.0),
                rapid_mm: 0.0,
                label: None,
                common: Vec::new(),
            }
        })
        .collect();
    for (i, place) in places.iter().enumerate() {
        sheets[place.sheet].parts.push(i);
        sheets[place.sheet].area += plates[i].area();
    }
    if opts.kerf > 0.0 {
        if let Some(p) = plates
            .iter()
            .filter(|p| !p.holes.is_empty())
            .min_by(|a, b| a.hole_diameter().total_cmp(&b.hole_diameter()))
        {
            if opts.kerf > KERF_IN_HOLE * p.hole_diameter() {
                return Err(OptionError::new(
                    "kerf",
                    format!(
                        "must be at most {} of the smallest hole's diameter ({} mm, plate {}), so that the cut runs inside the hole; got {}",
                        KERF_IN_HOLE,
                        crate::text::num(p.hole_diameter()),
                        p.id,
                        crate::text::num(opts.kerf)
                    ),
                )
                .into());
            }
        }
    }
    // Per sheet: the cut order, each part's pierce corner and hole order, then the parts as
    // drawn, the remnants and labels, and the program.
    let mut drawn: Vec<Drawn> = vec![Drawn::default(); plates.len()];
    let mut plans = Vec::with_capacity(sheets.len());
    let count = sheets.len();
    for (n, sheet) in sheets.iter_mut().enumerate() {
        let placed: Vec<(Vec<DVec2>, Vec<DVec2>)> = sheet
            .parts
            .iter()
            .map(|&i| {
                let at = |q: &DVec2| places[i].apply(*q);
                (
                    plates[i].outline.iter().map(at).collect(),
                    plates[i].holes.iter().map(at).collect(),
                )
            })
            .collect();
        // Common lines: the first part of a pair is pierced at the corner before the shared
        // side (off it, and one side from where the second part's cut starts), the second at
        // the shared side's end (its cut starts in the first one's kerf).
        let common = if opts.common_line {
            let outlines: Vec<Vec<DVec2>> = placed.iter().map(|(o, _)| o.clone()).collect();
            common_lines(&outlines, opts.kerf, COMMON_FIT + 1e-9)
        } else {
            Vec::new()
        };
        let mut pierce_at: Vec<Option<Vec<usize>>> = vec![None; placed.len()];
        for c in &common {
            let n = placed[c.first].0.len();
            pierce_at[c.first] = Some(vec![(c.edge + n - 1) % n]);
            pierce_at[c.second] = Some(vec![(c.other_edge + 1) % placed[c.second].0.len()]);
        }
        let shapes: Vec<PartShape> = placed
            .iter()
            .zip(&pierce_at)
            .map(|((o, h), at)| PartShape {
                outline: o,
                holes: h,
                pierce_at: at.as_deref(),
            })
            .collect();
        let order = order_parts(&shapes, DVec2::ZERO, opts.cut_order);
        for (k, &i) in sheet.parts.iter().enumerate() {
            drawn[i] = on_sheet(
                &plates[i],
                &places[i],
                order.pierce[k],
                &order.holes[k],
                opts.lead_in,
                joints,
                common.iter().any(|c| c.second == k),
            );
        }
        let proposed: Vec<usize> = order.parts.iter().map(|&k| sheet.parts[k]).collect();
        let position = |k: usize| {
            order
                .parts
                .iter()
                .position(|&m| m == k)
                .expect("every part is in the order")
        };
        let pairs: Vec<(usize, usize)> = common
            .iter()
            .map(|c| (position(c.first), position(c.second)))
            .collect();
        sheet.common = common
            .iter()
            .map(|c| ([sheet.parts[c.first], sheet.parts[c.second]], c.from, c.to))
            .collect();
        let hulls: Vec<Vec<DVec2>> = proposed.iter().map(|&i| drawn[i].outline.clone()).collect();
        sheet.remnants = remnants(sheet.stock.size, &hulls, opts.spacing, opts.remnant_min);
        // Labels: each remnant's in its lower-left corner, the sheet's in the lowest free place.
        let mut etch: Vec<(Option<usize>, Vec<DVec2>)> = proposed
            .iter()
            .flat_map(|&i| drawn[i].etch.iter().map(move |l| (Some(i), l.clone())))
            .collect();
        let mut taken: Vec<[DVec2; 2]> = Vec::new();
        let spec = |t: f64| format!("{} {}MM", opts.material.grade, thickness_name(t));
        for [lo, hi] in &sheet.remnants {
            let text = format!(
                "REMNANT {}X{} {}",
                thickness_name(hi.x - lo.x),
                thickness_name(hi.y - lo.y),
                spec(sheet.thickness)
            );
            let inset = DVec2::splat(opts.margin.max(LABEL_INSET));
            let room = *hi - *lo - 2.0 * inset;
            if let Some(h) = label_height(&text, room) {
                let at = *lo + inset;
                taken.push([at, at + label_size(&text, h)]);
                etch.extend(chain(&strokes(&text, at, h)).into_iter().map(|l| (None, l)));
            }
        }
        let mut text = format!("SHEET {}/{count} {}", n + 1, spec(sheet.thickness));
        if let Some(j) = &opts.job {
            text = format!("{j} {text}");
        }
        if opts.kerf > 0.0 {
            // The contours drawn are nominal; the programs cut them offset by half of this.
            text = format!("{text} KERF {}", crate::text::num(opts.kerf));
        }
        if let Some(d) = &opts.date {
            text = format!("{text} {d}");
        }
        let text = text.to_uppercase();
        sheet.label = LABEL_HEIGHTS.iter().find_map(|&h| {
            let at = free_box(
                sheet.stock.size,
                &hulls,
                opts.spacing,
                opts.margin,
                &taken,
                label_size(&text, h),
            )?;
            etch.extend(chain(&strokes(&text, at, h)).into_iter().map(|l| (None, l)));
            Some(text.clone())
        });
        let parts: Vec<(usize, &Drawn)> = proposed.iter().map(|&i| (i, &drawn[i])).collect();
        let plan = plan_sheet(&parts, &pairs, &etch, 0.5 * opts.kerf, opts.cut_order);
        sheet.parts.clone_from(&plan.parts);
        sheet.rapid_mm = plan.rapid_mm;
        plans.push(plan);
    }
    // Machine time.
    for (sheet, plan) in sheets.iter_mut().zip(&plans) {
        let parts: Vec<&Drawn> = sheet.parts.iter().map(|&i| &drawn[i]).collect();
        sheet.cut_mm = parts.iter().map(|d| d.cut_length()).sum();
        sheet.pierces = parts.iter().map(|d| d.pierces()).sum();
        sheet.joints = parts.iter().map(|d| d.joints.len()).sum();
        sheet.etch_mm = plan
            .etch
            .iter()
            .map(|l| l.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>())
            .sum();
        sheet.lead_mm = parts
            .iter()
            .flat_map(|d| d.leads.iter())
            .map(|[a, b]| a.distance(*b))
            .sum();
        sheet.time_s = times(
            &speeds,
            sheet.thickness,
            sheet.cut_mm + sheet.lead_mm,
            sheet.pierces,
            sheet.etch_mm,
            sheet.rapid_mm,
        )
        .map_err(|source| Error::Speeds {
            table: opts.speeds_name.clone(),
            sheet: sheet.file.clone(),
            source,
        })?;
    }
    let mut out = Nested {
        plates,
        cores,
        places,
        drawn,
        sheets,
        joints,
        doc: NestDoc::default(),
        spacing: opts.spacing,
        material: opts.material.clone(),
        plans,
        speeds: speeds.clone(),
        kerf: opts.kerf,
    };
    out.doc = nest_doc(&out, &nest_opts, opts);
    Ok(out)
}

/// Kerf at most this fraction of the smallest hole's diameter.
pub const KERF_IN_HOLE: f64 = 0.2;
/// Label character heights tried, largest first, mm.
const LABEL_HEIGHTS: [f64; 3] = [10.0, 6.0, 4.0];
/// A remnant's label lies at least this far inside it, mm.
const LABEL_INSET: f64 = 5.0;

/// A label's box at character height `h`.
fn label_size(text: &str, h: f64) -> DVec2 {
    DVec2::new(text_width(text.chars().count()) * 0.5 * h, h)
}

/// The largest label height that fits `room`.
fn label_height(text: &str, room: DVec2) -> Option<f64> {
    LABEL_HEIGHTS.iter().copied().find(|&h| {
        let s = label_size(text, h);
        s.x <= room.x && s.y <= room.y
    })
}

/// A plate as cut on its sheet: the outline counter-clockwise from its pierce point (outline
/// vertex `pierce`, a corner), holes in the order given, marks upright on the sheet, and leads
/// and micro-joints when asked for. The outline's lead-in runs along its first side's line into
/// the corner from the scrap, the lead-out along its last side's line out of it.
fn on_sheet(
    p: &PlateRecord,
    place: &Place,
    pierce: usize,
    hole_order: &[usize],
    lead: Option<f64>,
    joints: Option<Joints>,
    common: bool,
) -> Drawn {
    let mut outline: Vec<DVec2> = p.outline.iter().map(|q| place.apply(*q)).collect();
    let n = outline.len();
    outline.rotate_left(pierce % n);
    let holes: Vec<Hole> = hole_order
        .iter()
        .map(|&k| Hole {
            centre: place.apply(p.holes[k]),
            diameter: p.hole_diameter(),
        })
        .collect();
    let r = 0.5 * p.hole_diameter();
    let keep: Vec<(DVec2, f64)> = p.holes.iter().map(|c| (*c, r)).collect();
    let nodes = [p.ends[0].0, p.ends[1].0];
    let marks = part_marks(&p.id, &p.outline, &keep, nodes, &|q| place.apply(q));
    let mut leads = Vec::new();
    if let Some(l) = lead {
        // Holes: from inside the hole to its pierce point (+x), and back in.
        for h in &holes {
            let rr = 0.5 * h.diameter;
            let len = l.min(0.8 * rr);
            let start = h.centre + DVec2::X * rr;
            leads.push([start - DVec2::X * len, start]);
            leads.push([start, start - DVec2::new(len, len).normalize() * len]);
        }
        // The outline: along its first side into the corner, along its last side out. None
        // on a common line's second part: its cut starts and ends in the first one's kerf.
        if !common {
            let corner = outline[0];
            let first = (outline[1] - corner).normalize();
            let last = (corner - outline[n - 1]).normalize();
            leads.push([corner - first * l, corner]);
            leads.push([corner, corner + last * l]);
        }
    }
    let joints = match joints {
        Some(j) if j.applies(&p.outline) => place_joints(&outline, j.per_part, j.width, j.clear()),
        _ => Vec::new(),
    };
    Drawn {
        outline,
        holes,
        etch: marks.etch,
        leads,
        joints,
        common,
    }
}

/// Nester errors with plate ids instead of indices.
fn named(e: NestError, plates: &[PlateRecord], stock: &[Stock], margin: f64) -> Error {
    match e {
        NestError::TooLarge(list) => {
            let biggest = stock
                .iter()
                .map(|s| s.size)
                .max_by(|a, b| (a.x * a.y).total_cmp(&(b.x * b.y)))
                .unwrap_or(DVec2::ZERO);
            let usable = biggest - DVec2::splat(2.0 * margin);
            let names: Vec<String> = list
                .iter()
                .take(8)
                .map(|(i, s)| format!("{} ({:.1} × {:.1} mm)", plates[*i].id, s.x, s.y))
                .collect();
            Error::TooLarge {
                count: list.len(),
                sheet_w: biggest.x,
                sheet_h: biggest.y,
                usable_w: usable.x,
                usable_h: usable.y,
                names: names.join(", ") + if list.len() > 8 { ", …" } else { "" },
            }
        }
        NestError::Degenerate(i) | NestError::NotFinite(i) | NestError::Engine(i, _) => {
            Error::Plate {
                id: plates[i].id.clone(),
                source: e,
            }
        }
        NestError::Margin(_) | NestError::Spacing(_) => Error::Nest(e),
        e => Error::Nest(e),
    }
}

/// Size of an outline in its own frame: along x, along y.
fn size(p: &[DVec2]) -> DVec2 {
    let lo = p.iter().fold(DVec2::INFINITY, |m, q| m.min(*q));
    let hi = p.iter().fold(DVec2::NEG_INFINITY, |m, q| m.max(*q));
    hi - lo
}

/// nest.json: the rules, every sheet with its parts, remnants and times, totals per thickness
/// and overall, and every plate's placement. Fields in the file's order.
#[derive(Clone, Debug, Default, Serialize)]
pub struct NestDoc {
    /// How parts follow one another on a sheet: `travel` or `spread`.
    pub cut_order: &'static str,
    /// What the figures mean.
    pub definitions: BTreeMap<&'static str, &'static str>,
    /// Sheets by thickness.
    pub families: Vec<Family>,
    /// The file format's name.
    pub format: &'static str,
    /// The job's name on the sheet labels.
    pub job: Option<String>,
    /// Width of the cut, mm: NC paths are offset by half of it; the DXFs are nominal.
    pub kerf_mm: f64,
    /// Kept clear along every sheet edge, mm.
    pub margin: f64,
    /// The plates' steel.
    pub material: MaterialRecord,
    /// Micro-joints.
    pub micro_joints: Option<JointsDoc>,
    /// Parts not nested (tubes).
    pub not_nested: Vec<NotNested>,
    /// Pairs of plates side by side at a node.
    pub pairs: bool,
    /// Where each part (or model) lies.
    pub placements: Vec<Placement>,
    /// Plates.
    pub plates: usize,
    /// Allowed rotations.
    pub rotations: serde_json::Value,
    /// Random seed.
    pub seed: u64,
    /// Sheets.
    pub sheets: Vec<SheetDoc>,
    /// Least distance between parts, mm.
    pub spacing: f64,
    /// The speeds the times were computed with.
    pub speed_table: SpeedTable,
    /// Every sheet together.
    pub total: Total,
    /// Seeded tries.
    pub tries: usize,
    /// The unit of lengths.
    pub units: &'static str,
    /// The format's version.
    pub version: u32,
}

/// The sheets of one thickness together.
#[derive(Clone, Debug, Serialize)]
pub struct Family {
    /// Stock cost.
    pub cost: f64,
    /// Area of the parts, mm².
    pub part_area_mm2: f64,
    /// Sheets.
    pub sheets: usize,
    /// Thickness, mm.
    pub thickness: f64,
    /// Part area over stock area.
    pub utilisation: f64,
}

/// Micro-joints as nest.json states them.
#[derive(Clone, Debug, Serialize)]
pub struct JointsDoc {
    /// Parts smaller than this get micro-joints, mm.
    pub below_mm: f64,
    /// Kept clear of corners, the pierce point and each other, mm.
    pub clear_mm: f64,
    /// Micro-joints per part.
    pub per_part: usize,
    /// Width of a micro-joint along the contour, mm.
    pub width_mm: f64,
}

/// A node core: tube stock, not nested.
#[derive(Clone, Debug, Serialize)]
pub struct NotNested {
    /// Its tag.
    pub id: String,
    /// What it is.
    pub kind: &'static str,
    /// Length, mm.
    pub length: f64,
    /// Tube outer diameter, mm.
    pub outer_diameter: f64,
    /// Tube wall, mm.
    pub wall: f64,
}

/// Where a plate lies.
#[derive(Clone, Debug, Serialize)]
pub struct Placement {
    /// Lower corner of the bounding box, mm.
    pub bbox_min: [f64; 2],
    /// Its tag.
    pub id: String,
    /// Micro-joints.
    pub micro_joints: usize,
    /// Offset after the rotation, mm.
    pub offset: [f64; 2],
    /// Rotation from the plate's own frame, degrees.
    pub rotation_deg: f64,
    /// The sheet file.
    pub sheet: String,
}

/// Laser and plasma seconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Seconds {
    /// Laser, s.
    pub laser: f64,
    /// Plasma, s.
    pub plasma: f64,
}

/// A line cut once between two parts (common-line cutting).
#[derive(Clone, Debug, Serialize)]
pub struct CommonDoc {
    /// The line cut, half the kerf off each part's side.
    pub from: [f64; 2],
    /// Its length, mm: cut once instead of twice.
    pub length_mm: f64,
    /// The two plates: the first cut whole, the second from the line's end round to its start.
    pub parts: [String; 2],
    /// The line's other end.
    pub to: [f64; 2],
}

/// One sheet.
#[derive(Clone, Debug, Serialize)]
pub struct SheetDoc {
    /// Common lines on the sheet.
    pub common_lines: Vec<CommonDoc>,
    /// Stock cost.
    pub cost: f64,
    /// Cut length, mm (contours and leads, less micro-joints and common lines' second sides).
    pub cut_mm: f64,
    /// Etched length, mm.
    pub etch_mm: f64,
    /// The file's name.
    pub file: String,
    /// Assembly group (from 1).
    pub group: Option<u32>,
    /// The label etched on it.
    pub label: Option<String>,
    /// Micro-joints.
    pub micro_joints: usize,
    /// Area of the parts, mm².
    pub part_area_mm2: f64,
    /// The plates on it, by tag, in cutting order.
    pub parts: Vec<String>,
    /// Pierces: one per contour, one after each micro-joint, none for a common line's second part.
    pub pierces: usize,
    /// Rapid travel, mm.
    pub rapid_mm: f64,
    /// Free rectangles [lower-left, upper-right] left for later jobs.
    pub remnants: Vec<[[f64; 2]; 2]>,
    /// Size, mm.
    pub size: [f64; 2],
    /// When the first remnant runs right across the sheet: the strip the parts use.
    pub strip: Option<StripDoc>,
    /// Thickness, mm.
    pub thickness: f64,
    /// Machine time, s.
    pub time_s: Seconds,
    /// Part area over stock area.
    pub utilisation: f64,
}

/// The part of a sheet its parts use, when its first remnant runs right across it.
#[derive(Clone, Debug, Serialize)]
pub struct StripDoc {
    /// "x" or "y": the direction the strip runs from the sheet's edge.
    pub along: &'static str,
    /// From the sheet's edge to the first remnant, mm.
    pub length_mm: f64,
    /// Part area over the strip's area.
    pub utilisation: f64,
}

impl SheetInfo {
    /// The strip left of (or below, or right of, or above) a first remnant that runs right
    /// across the sheet.
    pub fn strip(&self) -> Option<StripDoc> {
        let [lo, hi] = *self.remnants.first()?;
        let size = self.stock.size;
        let (along, length, across) = if lo.x <= 0.0 && hi.x >= size.x {
            ("y", size.y - (hi.y - lo.y), size.x)
        } else if lo.y <= 0.0 && hi.y >= size.y {
            ("x", size.x - (hi.x - lo.x), size.y)
        } else {
            return None;
        };
        (length > 0.0).then(|| StripDoc {
            along,
            length_mm: length,
            utilisation: self.area / (length * across),
        })
    }
}

/// Every sheet together.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Total {
    /// Common lines.
    pub common_lines: usize,
    /// Their length (cut once instead of twice), mm.
    pub common_mm: f64,
    /// Stock cost.
    pub cost: f64,
    /// Cut length, mm (contours and leads, less micro-joints and common lines' second sides).
    pub cut_mm: f64,
    /// Etched length, mm.
    pub etch_mm: f64,
    /// Area of the parts, mm².
    pub part_area_mm2: f64,
    /// Pierces: one per contour, one after each micro-joint, none for a common line's second part.
    pub pierces: usize,
    /// Rapid travel, mm.
    pub rapid_mm: f64,
    /// Sheets.
    pub sheets: usize,
    /// Machine time, s.
    pub time_s: Seconds,
    /// Part area over stock area.
    pub utilisation: f64,
}

fn nest_doc(out: &Nested, opts: &NestOptions, asked: &Options) -> NestDoc {
    // Per thickness, thinnest first (positive thicknesses order as their bits do).
    let mut families = out.by_thickness();
    families.sort_by_key(|t| t.thickness.to_bits());
    let placed = |i: usize| {
        let lo = out.plates[i]
            .outline
            .iter()
            .map(|q| out.places[i].apply(*q))
            .fold(DVec2::INFINITY, |m, q| m.min(q));
        [lo.x, lo.y]
    };
    NestDoc {
        cut_order: asked.cut_order.name(),
        definitions: [
            ("bbox_min", "lower-left corner of the part's bounding box on the sheet"),
            ("common_lines", "a side shared by two parts set the kerf apart (--common-line), cut once along the line half the kerf off both: the first part is cut whole, the second from the line's end round to its start, beginning in the first one's kerf (no pierce)"),
            ("cut_mm", "outer and inner contours less micro-joints and less each common line's second side (and lead lines when asked for)"),
            ("micro_joints", "uncut bridges on the outer contour (gaps between its open pieces on CUT_OUTER, drawn across on JOINT), on parts whose bounding box's longer side is under below_mm"),
            ("offset", "sheet point = R(rotation_deg) · plate point + offset, the plate point in the plate's own frame (plates.json)"),
            ("pierces", "one per contour, and one after each micro-joint; none for a common line's second part, whose cut starts in a kerf"),
            ("remnants", "free rectangles [lower-left, upper-right] at least remnant_min, the spacing clear of every part"),
            ("strip", "when the first remnant runs right across the sheet: the rest of the sheet (from the edge it starts at, along x or y), its length and the part area over its area"),
            ("rapid_mm", "rapid travel of the NC program: from the sheet's origin to the first path, then from the end of each path (etching first, then each part's holes and outer contour, with leads, offset by half the kerf) to the start of the next; the return home is not counted"),
            ("time_s", "cut length over the cutting speed, a pierce time per contour, etched length over the marking speed, rapid travel over the rapid speed (speed_table)"),
        ]
        .into_iter()
        .collect(),
        families: families
            .iter()
            .map(|t| Family {
                cost: t.cost,
                part_area_mm2: t.part_area_mm2,
                sheets: t.sheets,
                thickness: t.thickness,
                utilisation: t.utilisation,
            })
            .collect(),
        format: "lamina-nest",
        job: asked.job.clone(),
        kerf_mm: asked.kerf,
        margin: opts.margin,
        material: out.material.clone(),
        micro_joints: out.joints.map(|j| JointsDoc {
            below_mm: j.below,
            clear_mm: j.clear(),
            per_part: j.per_part,
            width_mm: j.width,
        }),
        not_nested: out
            .cores
            .iter()
            .map(|c| NotNested {
                id: c.id.clone(),
                kind: "tube",
                length: c.length,
                outer_diameter: c.outer_diameter,
                wall: c.wall,
            })
            .collect(),
        pairs: opts.pair,
        placements: out
            .plates
            .iter()
            .zip(&out.places)
            .enumerate()
            .map(|(i, (p, pl))| Placement {
                bbox_min: placed(i),
                id: p.id.clone(),
                micro_joints: out.drawn[i].joints.len(),
                offset: [pl.offset.x, pl.offset.y],
                rotation_deg: pl.angle,
                sheet: out.sheets[pl.sheet].file.clone(),
            })
            .collect(),
        plates: out.plates.len(),
        rotations: match &opts.rotations {
            Rotations::Any => serde_json::json!("any"),
            Rotations::Listed(r) => serde_json::json!(r),
        },
        seed: opts.seed,
        sheets: out
            .sheets
            .iter()
            .map(|s| SheetDoc {
                common_lines: s
                    .common
                    .iter()
                    .map(|([a, b], from, to)| CommonDoc {
                        from: [from.x, from.y],
                        length_mm: from.distance(*to),
                        parts: [out.plates[*a].id.clone(), out.plates[*b].id.clone()],
                        to: [to.x, to.y],
                    })
                    .collect(),
                cost: s.stock.cost,
                cut_mm: s.cut_mm + s.lead_mm,
                etch_mm: s.etch_mm,
                file: s.file.clone(),
                group: s.group,
                label: s.label.clone(),
                micro_joints: s.joints,
                part_area_mm2: s.area,
                parts: s.parts.iter().map(|&i| out.plates[i].id.clone()).collect(),
                pierces: s.pierces,
                rapid_mm: s.rapid_mm,
                remnants: s
                    .remnants
                    .iter()
                    .map(|[a, b]| [[a.x, a.y], [b.x, b.y]])
                    .collect(),
                size: [s.stock.size.x, s.stock.size.y],
                strip: s.strip(),
                thickness: s.thickness,
                time_s: Seconds {
                    laser: s.time_s.0,
                    plasma: s.time_s.1,
                },
                utilisation: s.utilisation(),
            })
            .collect(),
        spacing: opts.spacing,
        speed_table: out.speeds.clone(),
        total: Total {
            common_lines: out.sheets.iter().map(|s| s.common.len()).sum(),
            common_mm: out
                .sheets
                .iter()
                .flat_map(|s| s.common.iter())
                .fold(0.0, |sum, (_, a, b)| sum + a.distance(*b)),
            cost: out.sheets.iter().map(|s| s.stock.cost).sum(),
            cut_mm: out.sheets.iter().map(|s| s.cut_mm + s.lead_mm).sum(),
            etch_mm: out.sheets.iter().map(|s| s.etch_mm).sum(),
            part_area_mm2: out.sheets.iter().map(|s| s.area).sum(),
            pierces: out.sheets.iter().map(|s| s.pierces).sum(),
            rapid_mm: out.sheets.iter().map(|s| s.rapid_mm).sum(),
            sheets: out.sheets.len(),
            time_s: Seconds {
                laser: out.sheets.iter().map(|s| s.time_s.0).sum(),
                plasma: out.sheets.iter().map(|s| s.time_s.1).sum(),
            },
            utilisation: out.utilisation(),
        },
        tries: opts.tries,
        units: "mm",
        version: 2,
    }
}

impl NestDoc {
    /// nest.json's text.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("reports serialise") + "\n"
    }
}

/// bom.csv: a row per plate (kind `plate`), per bolted seam (kind `bolts`, its bolt sets'
/// mass) and per node core (kind `tube`). A plate's position is the lower-left corner of its bounding box on the
/// sheet (`bbox_x_mm`, `bbox_y_mm`), its rotation the turn from its own frame.
pub fn bom_csv(out: &Nested) -> String {
    let mut w = String::from(
        "kind,id,group,grade,thickness_mm,length_mm,width_mm,area_mm2,mass_kg,sheet,bbox_x_mm,bbox_y_mm,rotation_deg,holes,bolted_to,bolts,welded_at_a,welded_at_b\n",
    );
    for (i, (p, place)) in out.plates.iter().zip(&out.places).enumerate() {
        let s = size(&p.outline);
        let mass = p.area() * p.thickness * out.material.density * 1e-6;
        let ends: Vec<String> = p
            .ends
            .iter()
            .zip(&p.end_cores)
            .map(|((node, with), core)| match core {
                Some(c) => format!("\"node {node}: core {c}\""),
                // A tip, or a seam's ply at the other group's node.
                None if with.is_empty() => format!("\"node {node}: not welded\""),
                None => format!("\"node {}: {}\"", node, with.join(" ")),
            })
            .collect();
        let lo = out.drawn[i]
            .outline
            .iter()
            .fold(DVec2::INFINITY, |m, q| m.min(*q));
        let bolts = p
            .bolt
            .as_ref()
            .map(|b| format!("{} x {}x{}", p.holes.len(), b.size, b.length))
            .unwrap_or_default();
        let _ = writeln!(
            w,
            "plate,\"{}\",{},\"{}\",{},{:.2},{:.2},{:.1},{:.4},\"{}\",{:.3},{:.3},{},{},\"{}\",\"{}\",{},{}",
            p.id,
            p.group,
            out.material.grade,
            p.thickness,
            s.x,
            s.y,
            p.area(),
            mass,
            out.sheets[place.sheet].file,
            lo.x,
            lo.y,
            place.angle,
            p.holes.len(),
            p.bolted_to.as_deref().unwrap_or(""),
            bolts,
            ends[0],
            ends[1]
        );
    }
    // One row per seam: the bolts to order for it.
    for p in &out.plates {
        let (Some(b), Some(other)) = (&p.bolt, &p.bolted_to) else {
            continue;
        };
        if other.as_str() < p.id.as_str() {
            continue;
        }
        // The grade column holds the bolts' property class; the description their check.
        let checked = match (b.utilisation, &b.check) {
            (Some(u), Some(c)) => format!("; utilisation {u:.3} ({c}, EN 1993-1-8 Table 3.4)"),
            _ => String::new(),
        };
        // Their steel: bolt, nut and two washers each, nominal (what `size` weighed).
        let mass = crate::rationalize::bolts::parse(&b.size).map_or(0.0, |size| {
            crate::rationalize::bolts::set_volume(&size, b.length)
                * p.holes.len() as f64
                * out.material.density
                * 1e-6
        });
        let _ = writeln!(
            w,
            "bolts,\"{}+{}\",{},\"{}\",{},,,,{:.4},,,,,{},,\"{} x {}x{} {} with 2 washers and a nut, grip {} mm, {}{}\",,",
            p.id,
            other,
            p.group,
            b.class,
            b.grip,
            mass,
            p.holes.len(),
            p.holes.len(),
            b.size,
            b.length,
            b.class,
            b.grip,
            b.preload,
            checked
        );
    }
    for c in &out.cores {
        let area = std::f64::consts::PI * (c.outer_diameter - c.wall) * c.wall;
        let _ = writeln!(
            w,
            "tube,\"{}\",{},\"{}\",{},{:.2},{},{:.1},{:.4},,,,,,,\"tube {} x {} at node {}\",,",
            c.id,
            c.group,
            out.material.grade,
            c.wall,
            c.length,
            c.outer_diameter,
            area,
            area * c.length * out.material.density * 1e-6,
            c.outer_diameter,
            c.wall,
            c.node
        );
    }
    w
}

/// Each sheet's cut DXF into `dir` (named as `SheetInfo::file`).
pub fn write_sheets(out: &Nested, dir: &Path) -> Result<(), WriteError> {
    let count = out.sheets.len();
    for (n, sheet) in out.sheets.iter().enumerate() {
        let parts: Vec<&Drawn> = sheet.parts.iter().map(|&i| &out.drawn[i]).collect();
        let label = format!(
            "{} {} mm, sheet {} of {} ({}, {} x {} mm, {} parts)",
            out.material.grade,
            sheet.thickness,
            n + 1,
            count,
            sheet.file,
            sheet.stock.size.x,
            sheet.stock.size.y,
            sheet.parts.len()
        );
        let label = if out.kerf > 0.0 {
            format!(
                "{label}; nominal contours: the NC programs offset them by half the {} mm kerf",
                out.kerf
            )
        } else {
            label
        };
        write_sheet_dxf(
            &out.plans[n].etch,
            &parts,
            sheet.stock.size,
            &sheet.remnants,
            &label,
            &dir.join(&sheet.file),
        )?;
    }
    Ok(())
}

/// NC programs for every sheet, `sheet-NN-Tmm.ngc` (G-code) or `.esi` (ESSI) beside its DXF,
/// by the post-processor given; returns the files' names.
pub fn write_nc(out: &Nested, dir: &Path, post: &Post) -> Result<Vec<String>, Error> {
    let programs = nc_programs(out, post)?;
    write_programs(&programs, dir)?;
    Ok(programs.into_iter().map(|(name, _)| name).collect())
}

/// Programs made by `nc_programs`, each into its file in `dir`.
pub fn write_programs(programs: &[(String, String)], dir: &Path) -> Result<(), Error> {
    for (name, text) in programs {
        crate::files::write_atomic(&dir.join(name), |w| {
            std::io::Write::write_all(w, text.as_bytes())
        })
        .map_err(Error::Write)?;
    }
    Ok(())
}

/// Every sheet's NC program by the post-processor given, in memory: (file name, as
/// `write_nc` names it; the program).
pub fn nc_programs(out: &Nested, post: &Post) -> Result<Vec<(String, String)>, Error> {
    let count = out.sheets.len();
    let mut files = Vec::with_capacity(count);
    for (n, (sheet, plan)) in out.sheets.iter().zip(&out.plans).enumerate() {
        let heading = Heading {
            lines: vec![
                format!(
                    "lamina nest: {}, sheet {} of {count}, {} x {} mm",
                    sheet.file,
                    n + 1,
                    sheet.stock.size.x,
                    sheet.stock.size.y
                ),
                format!(
                    "{} {} mm, {} parts, cut order {}",
                    out.material.grade,
                    thickness_name(sheet.thickness),
                    sheet.parts.len(),
                    out.doc.cut_order
                ),
                format!("kerf {} mm", out.kerf),
            ],
            names: out.plates.iter().map(|p| p.id.clone()).collect(),
        };
        let name = sheet.file.trim_end_matches(".dxf").to_string() + "." + post.format.extension();
        let text = match post.format {
            NcFormat::Gcode => {
                let row = out
                    .speeds
                    .row(post.machine == Machine::Laser, sheet.thickness)
                    .map_err(|source| Error::Speeds {
                        table: "the speed table".into(),
                        sheet: sheet.file.clone(),
                        source,
                    })?;
                nc::gcode(plan, post, row, &heading)
            }
            NcFormat::Essi => nc::essi(plan, post, &heading),
        };
        files.push((name, text));
    }
    Ok(files)
}

/// assembly.scad: every part cut out of its sheet's DXF by a clip polygon around it, placed
/// in the structure (not for micro-jointed sheets: OpenSCAD's DXF import drops their open
/// outer contours).
pub fn write_assembly(out: &Nested, path: &Path) -> Result<(), WriteError> {
    let clip_d = 0.5 * out.spacing + SLACK;
    let scad: Vec<SheetPart> = out
        .plates
        .iter()
        .zip(&out.places)
        .zip(&out.drawn)
        .map(|((p, place), d)| SheetPart {
            id: &p.id,
            dxf: &out.sheets[place.sheet].file,
            thickness: p.thickness,
            matrix: p.matrix,
            angle: place.angle,
            offset: place.offset,
            clip: grown_hull(&d.outline, clip_d),
        })
        .collect();
    let scad_cores: Vec<ScadCore> = out
        .cores
        .iter()
        .map(|c| ScadCore {
            id: &c.id,
            outer: c.outer_diameter,
            inner: c.outer_diameter - 2.0 * c.wall,
            length: c.length,
            matrix: axis_frame(DVec3::from_array(c.base), DVec3::from_array(c.axis)),
        })
        .collect();
    write_scad_from_sheets(&scad, &scad_cores, path)
}

/// sheets.svg: every sheet with its parts by group and its remnants, 1000 px wide.
pub fn svg(out: &Nested) -> String {
    let views: Vec<SheetView> = out
        .sheets
        .iter()
        .map(|s| SheetView {
            title: format!(
                "{}: {} mm, {} × {} mm, {} parts, {:.1} % used",
                s.file,
                thickness_name(s.thickness),
                s.stock.size.x,
                s.stock.size.y,
                s.parts.len(),
                100.0 * s.utilisation()
            ),
            size: s.stock.size,
            remnants: s.remnants.clone(),
            parts: s
                .parts
                .iter()
                .map(|&i| {
                    (
                        out.drawn[i].outline.as_slice(),
                        out.plates[i].id.as_str(),
                        out.plates[i].group,
                    )
                })
                .collect(),
        })
        .collect();
    sheets_svg(&views, 1000.0)
}

/// A thickness as sheet file names and summaries write it (`1.5`, `3`).
pub fn thickness_label(t: f64) -> String {
    thickness_name(t)
}
