//! `lamina nest plates.json --sheet 3000x1500 --spacing 5 -o cut/`: the plates nested on stock
//! sheets, one sheet family per thickness; a cut DXF per sheet, bom.csv, nest.json,
//! assembly.scad (rebuilt from the sheet DXFs) and sheets.svg.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use glam::{DVec2, DVec3};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use lamina::fabricate::assembly::{axis_frame, write_scad_from_sheets, ScadCore, SheetPart};
use lamina::fabricate::cutplan::{remnants, times, SpeedTable};
use lamina::fabricate::cutsheet::{place_joints, write_cut_dxf, Drawn, Hole};
pub use lamina::fabricate::nest::Stock;
use lamina::fabricate::nest::{
    grown_hull, nest_families, BottomLeft, NestError, NestOptions, Place, Rotations, SLACK,
};
use lamina::fabricate::plates_file::{read_plates, CoreRecord, PlateRecord};
use lamina::fabricate::preview::{sheets_svg, SheetView};
use lamina::fabricate::tags::part_marks;
use lamina::files::write_atomic;

/// Stainless steel, g/cm³.
pub const DENSITY: f64 = 7.9;

#[derive(ClapArgs)]
pub struct Args {
    /// The plates file `lamina plates` wrote
    pub input: PathBuf,
    /// Stock sheet, width x height in mm [default: 3000x1500]
    #[arg(long, value_parser = parse_sheet, conflicts_with = "stock")]
    pub sheet: Option<DVec2>,
    /// Stock sheets to choose from per thickness, with the cost of one:
    /// `3000x1500:120,2500x1250:85`; the cheapest mix per thickness is cut
    #[arg(long, value_parser = parse_stock, value_delimiter = ',')]
    pub stock: Option<Vec<Stock>>,
    /// Kept clear along every sheet edge, mm
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub margin: f64,
    /// Least distance between parts (kerf plus clearance), mm
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true)]
    pub spacing: f64,
    /// Allowed rotations in degrees, comma-separated, or `any`
    #[arg(long, default_value = "0,90,180,270", value_parser = parse_rotations)]
    pub rotations: Rotations,
    /// Each assembly group on sheets of its own (still one family per thickness)
    #[arg(long)]
    pub keep_groups: bool,
    /// Seeded tries, the best kept [default: 8 up to 250 plates, fewer above, 1 from 2,000]
    #[arg(long)]
    pub tries: Option<usize>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Do not pair congruent quads turned 180°
    #[arg(long)]
    pub no_pairs: bool,
    /// Free rectangles at least this big are reported as remnants (either way round), mm
    #[arg(long, default_value = "300x300", value_parser = parse_sheet)]
    pub remnant_min: DVec2,
    /// Lead-in and lead-out lines this long in the scrap (LEAD layer), mm; at most half the
    /// spacing, and shortened inside small holes
    #[arg(long, allow_negative_numbers = true)]
    pub lead_in: Option<f64>,
    /// Micro-joints: this many uncut bridges (from 1 to 8) on the outer contour of each part
    /// smaller than --micro-joint-below, so that it stays in the sheet; the sheets then get no
    /// assembly.scad (OpenSCAD drops open contours) [default: none]
    #[arg(long)]
    pub micro_joints: Option<usize>,
    /// Parts whose bounding box's longer side is under this get micro-joints, mm
    #[arg(long, default_value_t = 200.0, allow_negative_numbers = true)]
    pub micro_joint_below: f64,
    /// Width of a micro-joint along the contour, mm
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub micro_joint_width: f64,
    /// Cutting, pierce and marking speeds by thickness for the time estimate (JSON like the
    /// built-in table nest.json repeats) [default: typical stainless steel figures]
    #[arg(long)]
    pub speeds: Option<PathBuf>,
    /// Output folder (made if missing)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

fn parse_sheet(s: &str) -> Result<DVec2, String> {
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

fn parse_stock(s: &str) -> Result<Stock, String> {
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

fn parse_rotations(s: &str) -> Result<Rotations, String> {
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
pub struct SheetInfo {
    pub file: String,
    pub thickness: f64,
    /// Set with --keep-groups.
    pub group: Option<u32>,
    pub stock: Stock,
    pub parts: Vec<usize>,
    pub area: f64,
    pub remnants: Vec<[DVec2; 2]>,
    pub cut_mm: f64,
    pub pierces: usize,
    pub etch_mm: f64,
    pub lead_mm: f64,
    pub joints: usize,
    /// Seconds: laser, plasma.
    pub time_s: (f64, f64),
}

/// Micro-joints as asked for.
#[derive(Clone, Copy)]
pub struct Joints {
    pub per_part: usize,
    pub below: f64,
    pub width: f64,
}

impl Joints {
    /// Whether a plate (its outline in its own frame) is small enough to get joints.
    fn applies(&self, outline: &[DVec2]) -> bool {
        size(outline).max_element() < self.below
    }

    /// Kept from corners, the pierce point and each other, mm.
    fn clear(&self) -> f64 {
        (2.0 * self.width).max(2.0)
    }
}

pub struct Outcome {
    pub plates: Vec<PlateRecord>,
    pub cores: Vec<CoreRecord>,
    pub places: Vec<Place>,
    pub sheets: Vec<SheetInfo>,
    pub joints: Option<Joints>,
    /// Micro-joints per plate (fewer than asked where its sides are too short).
    pub joint_counts: Vec<usize>,
}

impl Outcome {
    pub fn utilisation(&self) -> f64 {
        let used: f64 = self.sheets.iter().map(|s| s.area).sum();
        let stock: f64 = self
            .sheets
            .iter()
            .map(|s| s.stock.size.x * s.stock.size.y)
            .sum();
        used / stock
    }
}

/// The most seeded tries: each is a whole nesting of every part.
pub const MAX_TRIES: usize = 1000;

fn thickness_name(t: f64) -> String {
    let s = format!("{t:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

pub fn execute(args: &Args) -> Result<Outcome> {
    let (plates, cores) = read_plates(&args.input)?;
    let stock: Vec<Stock> = match (&args.stock, args.sheet) {
        (Some(s), _) => s.clone(),
        (None, Some(size)) => vec![Stock { size, cost: 0.0 }],
        (None, None) => vec![Stock {
            size: DVec2::new(3000.0, 1500.0),
            cost: 0.0,
        }],
    };
    let speeds = match &args.speeds {
        Some(p) => SpeedTable::read(p)?,
        None => SpeedTable::default(),
    };
    if let Some(l) = args.lead_in {
        if !(l > 0.0 && l <= 0.5 * args.spacing) {
            bail!(
                "--lead-in must be more than 0 and at most half the spacing ({} mm), so that it stays in the scrap between parts; got {}",
                0.5 * args.spacing,
                lamina::text::num(l)
            );
        }
    }
    if !(args.micro_joint_below > 0.0 && args.micro_joint_below <= 1e6) {
        bail!(
            "--micro-joint-below must be more than 0 and at most 1e6 mm, got {}",
            lamina::text::num(args.micro_joint_below)
        );
    }
    if !(args.micro_joint_width > 0.0 && args.micro_joint_width <= 10.0) {
        bail!(
            "--micro-joint-width must be more than 0 and at most 10 mm, got {}",
            lamina::text::num(args.micro_joint_width)
        );
    }
    let joints = match args.micro_joints {
        None => None,
        Some(n @ 1..=8) => Some(Joints {
            per_part: n,
            below: args.micro_joint_below,
            width: args.micro_joint_width,
        }),
        Some(n) => bail!("--micro-joints must be from 1 to 8, got {n}"),
    };
    let opts = NestOptions {
        sheet: stock[0].size,
        margin: args.margin,
        spacing: args.spacing,
        rotations: args.rotations.clone(),
        tries: args
            .tries
            .unwrap_or_else(|| NestOptions::tries_for(plates.len())),
        seed: args.seed,
        pair: !args.no_pairs,
    };
    if !(1..=MAX_TRIES).contains(&opts.tries) {
        bail!("--tries must be from 1 to {MAX_TRIES}, got {}", opts.tries);
    }
    // Families: thickness (as its bits: positive floats order as their bits do), then group.
    let keys: Vec<(u64, u32)> = plates
        .iter()
        .map(|p| {
            (
                p.thickness.to_bits(),
                if args.keep_groups { p.group } else { 0 },
            )
        })
        .collect();
    let bar = progress(plates.len() as u64 * opts.tries as u64 * stock.len() as u64);
    let nester = BottomLeft {
        progress: Some({
            let bar = bar.clone();
            Arc::new(move |n| bar.inc(n as u64))
        }),
        ..Default::default()
    };
    let outlines: Vec<Vec<DVec2>> = plates.iter().map(|p| p.outline.clone()).collect();
    let result = nest_families(&nester, &outlines, &keys, &stock, &opts);
    bar.finish_and_clear();
    let (nesting, sheet_keys) =
        result.map_err(|e| named(e, &plates, &stock, args.margin, &args.input))?;
    let places = nesting.places;
    let mut sheets: Vec<SheetInfo> = sheet_keys
        .iter()
        .enumerate()
        .map(|(k, &((bits, group), st))| {
            let t = f64::from_bits(bits);
            SheetInfo {
                file: format!("sheet-{:02}-{}mm.dxf", k + 1, thickness_name(t)),
                thickness: t,
                group: args.keep_groups.then_some(group),
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
            }
        })
        .collect();

    if args.output.exists() && !args.output.is_dir() {
        bail!("{}: exists and is not a folder", args.output.display());
    }

    for (i, place) in places.iter().enumerate() {
        sheets[place.sheet].parts.push(i);
        sheets[place.sheet].area += plates[i].area();
    }
    let drawn: Vec<Drawn> = plates
        .iter()
        .zip(&places)
        .map(|(p, place)| on_sheet(p, place, args.lead_in, joints))
        .collect();

    // Remnants and machine time, all before anything is written (a speed table without a row
    // for some thickness leaves no partial output).
    for sheet in &mut sheets {
        let parts: Vec<&Drawn> = sheet.parts.iter().map(|&i| &drawn[i]).collect();
        let hulls: Vec<Vec<DVec2>> = parts.iter().map(|d| d.outline.clone()).collect();
        sheet.remnants = remnants(sheet.stock.size, &hulls, args.spacing, args.remnant_min);
        sheet.cut_mm = parts.iter().map(|d| d.cut_length()).sum();
        sheet.pierces = parts.iter().map(|d| d.pierces()).sum();
        sheet.joints = parts.iter().map(|d| d.joints.len()).sum();
        sheet.etch_mm = parts.iter().map(|d| d.etch_length()).sum();
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
        )
        .with_context(|| {
            format!(
                "{}: the time estimate for {}",
                args.speeds
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_else(|| "the built-in speed table".into()),
                sheet.file
            )
        })?;
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create folder", args.output.display()))?;
    for sheet in &sheets {
        let parts: Vec<&Drawn> = sheet.parts.iter().map(|&i| &drawn[i]).collect();
        write_cut_dxf(
            &parts,
            Some(sheet.stock.size),
            &sheet.remnants,
            &args.output.join(&sheet.file),
        )?;
    }

    // The assembly, from the sheets (not from micro-jointed ones: their outer contours are
    // open, and OpenSCAD's DXF import drops open paths).
    let scad_path = args.output.join("assembly.scad");
    if joints.is_some() {
        if scad_path.exists() {
            std::fs::remove_file(&scad_path).with_context(|| {
                format!("{}: cannot remove the old assembly", scad_path.display())
            })?;
        }
    } else {
        write_assembly(
            &plates,
            &cores,
            &places,
            &sheets,
            &drawn,
            args.spacing,
            &scad_path,
        )?;
    }

    let outcome = Outcome {
        plates,
        cores,
        places,
        sheets,
        joints,
        joint_counts: drawn.iter().map(|d| d.joints.len()).collect(),
    };
    write_bom(&outcome, &drawn, &args.output.join("bom.csv"))?;
    write_nest_json(
        &outcome,
        &drawn,
        &opts,
        &speeds,
        &args.output.join("nest.json"),
    )?;
    let views: Vec<SheetView> = outcome
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
                100.0 * s.area / (s.stock.size.x * s.stock.size.y)
            ),
            size: s.stock.size,
            remnants: s.remnants.clone(),
            parts: s
                .parts
                .iter()
                .map(|&i| {
                    (
                        drawn[i].outline.as_slice(),
                        outcome.plates[i].id.as_str(),
                        outcome.plates[i].group,
                    )
                })
                .collect(),
        })
        .collect();
    let svg = sheets_svg(&views, 1000.0);
    write_atomic(&args.output.join("sheets.svg"), |w| {
        w.write_all(svg.as_bytes())
    })?;
    Ok(outcome)
}

/// assembly.scad: every part cut out of its sheet's DXF by a clip polygon around it.
fn write_assembly(
    plates: &[PlateRecord],
    cores: &[CoreRecord],
    places: &[Place],
    sheets: &[SheetInfo],
    drawn: &[Drawn],
    spacing: f64,
    path: &Path,
) -> Result<()> {
    let clip_d = 0.5 * spacing + SLACK;
    let scad: Vec<SheetPart> = plates
        .iter()
        .zip(places)
        .zip(drawn)
        .map(|((p, place), d)| SheetPart {
            id: &p.id,
            dxf: &sheets[place.sheet].file,
            thickness: p.thickness,
            matrix: p.matrix,
            angle: place.angle,
            offset: place.offset,
            clip: grown_hull(&d.outline, clip_d),
        })
        .collect();
    let scad_cores: Vec<ScadCore> = cores
        .iter()
        .map(|c| ScadCore {
            id: &c.id,
            outer: c.outer_diameter,
            inner: c.outer_diameter - 2.0 * c.wall,
            length: c.length,
            matrix: axis_frame(DVec3::from_array(c.base), DVec3::from_array(c.axis)),
        })
        .collect();
    write_scad_from_sheets(&scad, &scad_cores, path)?;
    Ok(())
}

/// A plate as cut on its sheet: the outline counter-clockwise from its pierce point (the middle
/// of its longest side), holes, marks upright on the sheet, and leads and micro-joints when
/// asked for.
fn on_sheet(p: &PlateRecord, place: &Place, lead: Option<f64>, joints: Option<Joints>) -> Drawn {
    let mut outline: Vec<DVec2> = p.outline.iter().map(|q| place.apply(*q)).collect();
    let n = outline.len();
    let longest = (0..n)
        .max_by(|&a, &b| {
            let la = outline[a].distance(outline[(a + 1) % n]);
            let lb = outline[b].distance(outline[(b + 1) % n]);
            la.total_cmp(&lb).then(b.cmp(&a))
        })
        .expect("an outline has points");
    let (a, b) = (outline[longest], outline[(longest + 1) % n]);
    let pierce = 0.5 * (a + b);
    outline.rotate_left((longest + 1) % n);
    outline.insert(0, pierce);
    let r = 0.5 * p.hole_diameter();
    let holes: Vec<Hole> = p
        .holes
        .iter()
        .map(|c| Hole {
            centre: place.apply(*c),
            diameter: p.hole_diameter(),
        })
        .collect();
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
        // The outline: square in from the scrap, out at 45° ahead.
        let along = (b - a).normalize();
        let out = DVec2::new(along.y, -along.x);
        leads.push([pierce + out * l, pierce]);
        leads.push([pierce, pierce + (out + along).normalize() * l]);
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
    }
}

/// Library errors with plate ids instead of indices.
fn named(
    e: NestError,
    plates: &[PlateRecord],
    stock: &[Stock],
    margin: f64,
    path: &Path,
) -> anyhow::Error {
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
            anyhow::anyhow!(
                "{}: {} plate(s) fit no {} × {} mm sheet ({:.0} × {:.0} mm inside the margin) at any allowed rotation: {}{}",
                path.display(),
                list.len(),
                biggest.x,
                biggest.y,
                usable.x,
                usable.y,
                names.join(", "),
                if list.len() > 8 { ", …" } else { "" }
            )
        }
        NestError::Degenerate(i) | NestError::NotFinite(i) | NestError::Engine(i, _) => {
            anyhow::anyhow!("{}: plate {}: {e}", path.display(), plates[i].id)
        }
        e => anyhow::Error::new(e),
    }
}

fn progress(len: u64) -> ProgressBar {
    let bar = super::progress::bar("nesting", Some(len));
    bar.set_style(
        ProgressStyle::with_template(
            "nesting {bar:40} {pos}/{len} parts placed (all tries and stock sizes) {elapsed}",
        )
        .expect("template"),
    );
    bar
}

/// Size of an outline in its own frame: along x, along y.
fn size(p: &[DVec2]) -> DVec2 {
    let lo = p.iter().fold(DVec2::INFINITY, |m, q| m.min(*q));
    let hi = p.iter().fold(DVec2::NEG_INFINITY, |m, q| m.max(*q));
    hi - lo
}

/// bom.csv: a row per plate (kind `plate`), per bolted seam (kind `bolts`) and per node core
/// (kind `tube`). A plate's position is the lower-left corner of its bounding box on the
/// sheet (`bbox_x_mm`, `bbox_y_mm`), its rotation the turn from its own frame.
fn write_bom(out: &Outcome, drawn: &[Drawn], path: &Path) -> Result<()> {
    write_atomic(path, |w| {
        writeln!(
            w,
            "kind,id,group,thickness_mm,length_mm,width_mm,area_mm2,mass_kg,sheet,bbox_x_mm,bbox_y_mm,rotation_deg,holes,bolted_to,bolts,welded_at_a,welded_at_b"
        )?;
        for (i, (p, place)) in out.plates.iter().zip(&out.places).enumerate() {
            let s = size(&p.outline);
            let mass = p.area() * p.thickness * DENSITY * 1e-6;
            let ends: Vec<String> = p
                .ends
                .iter()
                .zip(&p.end_cores)
                .map(|((node, with), core)| match core {
                    Some(c) => format!("\"node {node}: core {c}\""),
                    None => format!("\"node {}: {}\"", node, with.join(" ")),
                })
                .collect();
            let lo = drawn[i]
                .outline
                .iter()
                .fold(DVec2::INFINITY, |m, q| m.min(*q));
            let bolts = p
                .bolt
                .as_ref()
                .map(|b| format!("{} x {}x{}", p.holes.len(), b.size, b.length))
                .unwrap_or_default();
            writeln!(
                w,
                "plate,\"{}\",{},{},{:.2},{:.2},{:.1},{:.4},\"{}\",{:.3},{:.3},{},{},\"{}\",\"{}\",{},{}",
                p.id,
                p.group,
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
            )?;
        }
        // One row per seam: the bolts to order for it.
        for p in &out.plates {
            let (Some(b), Some(other)) = (&p.bolt, &p.bolted_to) else {
                continue;
            };
            if other.as_str() < p.id.as_str() {
                continue;
            }
            writeln!(
                w,
                "bolts,\"{}+{}\",{},{},,,,,,,,,{},,\"{} x {}x{} with 2 washers and a nut, grip {} mm\",,",
                p.id, other, p.group, b.grip, p.holes.len(), p.holes.len(), b.size, b.length, b.grip
            )?;
        }
        for c in &out.cores {
            let area = std::f64::consts::PI * (c.outer_diameter - c.wall) * c.wall;
            writeln!(
                w,
                "tube,\"{}\",{},{},{:.2},{},{:.1},{:.4},,,,,,,\"tube {} x {} at node {}\",,",
                c.id,
                c.group,
                c.wall,
                c.length,
                c.outer_diameter,
                area,
                area * c.length * DENSITY * 1e-6,
                c.outer_diameter,
                c.wall,
                c.node
            )?;
        }
        Ok(())
    })?;
    Ok(())
}

fn write_nest_json(
    out: &Outcome,
    drawn: &[Drawn],
    opts: &NestOptions,
    speeds: &SpeedTable,
    path: &Path,
) -> Result<()> {
    // Per thickness (positive thicknesses order as their bits do).
    let mut families: BTreeMap<u64, (usize, f64, f64, f64)> = BTreeMap::new();
    for s in &out.sheets {
        let f = families.entry(s.thickness.to_bits()).or_default();
        f.0 += 1;
        f.1 += s.area;
        f.2 += s.stock.size.x * s.stock.size.y;
        f.3 += s.stock.cost;
    }
    let placed = |i: usize| {
        let lo = out.plates[i]
            .outline
            .iter()
            .map(|q| out.places[i].apply(*q))
            .fold(DVec2::INFINITY, |m, q| m.min(q));
        [lo.x, lo.y]
    };
    let doc = json!({
        "format": "lamina-nest",
        "version": 2,
        "units": "mm",
        "margin": opts.margin,
        "spacing": opts.spacing,
        "rotations": match &opts.rotations {
            Rotations::Any => json!("any"),
            Rotations::Listed(r) => json!(r),
        },
        "tries": opts.tries,
        "seed": opts.seed,
        "pairs": opts.pair,
        "micro_joints": out.joints.map(|j| json!({
            "per_part": j.per_part,
            "below_mm": j.below,
            "width_mm": j.width,
            "clear_mm": j.clear(),
        })),
        "plates": out.plates.len(),
        "definitions": {
            "offset": "sheet point = R(rotation_deg) · plate point + offset, the plate point in the plate's own frame (plates.json)",
            "bbox_min": "lower-left corner of the part's bounding box on the sheet",
            "cut_mm": "outer and inner contours less micro-joints (and lead lines when asked for)",
            "pierces": "one per contour, and one after each micro-joint",
            "micro_joints": "uncut bridges on the outer contour (gaps between its open pieces on CUT_OUTER, drawn across on JOINT), on parts whose bounding box's longer side is under below_mm",
            "time_s": "cut length over the cutting speed, a pierce time per contour, etched length over the marking speed (speed_table)",
            "remnants": "free rectangles [lower-left, upper-right] at least remnant_min, the spacing clear of every part",
        },
        "sheets": out.sheets.iter().map(|s| json!({
            "file": s.file,
            "thickness": s.thickness,
            "group": s.group,
            "size": [s.stock.size.x, s.stock.size.y],
            "cost": s.stock.cost,
            "parts": s.parts.iter().map(|&i| &out.plates[i].id).collect::<Vec<_>>(),
            "part_area_mm2": s.area,
            "utilisation": s.area / (s.stock.size.x * s.stock.size.y),
            "remnants": s.remnants.iter().map(|[a, b]| [[a.x, a.y], [b.x, b.y]]).collect::<Vec<_>>(),
            "cut_mm": s.cut_mm + s.lead_mm,
            "pierces": s.pierces,
            "micro_joints": s.joints,
            "etch_mm": s.etch_mm,
            "time_s": {"laser": s.time_s.0, "plasma": s.time_s.1},
        })).collect::<Vec<_>>(),
        "families": families.iter().map(|(t, f)| json!({
            "thickness": f64::from_bits(*t),
            "sheets": f.0,
            "part_area_mm2": f.1,
            "utilisation": f.1 / f.2,
            "cost": f.3,
        })).collect::<Vec<_>>(),
        "total": {
            "sheets": out.sheets.len(),
            "part_area_mm2": out.sheets.iter().map(|s| s.area).sum::<f64>(),
            "utilisation": out.utilisation(),
            "cost": out.sheets.iter().map(|s| s.stock.cost).sum::<f64>(),
            "cut_mm": out.sheets.iter().map(|s| s.cut_mm + s.lead_mm).sum::<f64>(),
            "pierces": out.sheets.iter().map(|s| s.pierces).sum::<usize>(),
            "etch_mm": out.sheets.iter().map(|s| s.etch_mm).sum::<f64>(),
            "time_s": {
                "laser": out.sheets.iter().map(|s| s.time_s.0).sum::<f64>(),
                "plasma": out.sheets.iter().map(|s| s.time_s.1).sum::<f64>(),
            },
        },
        "not_nested": out.cores.iter().map(|c| json!({
            "id": c.id,
            "kind": "tube",
            "outer_diameter": c.outer_diameter,
            "wall": c.wall,
            "length": c.length,
        })).collect::<Vec<_>>(),
        "placements": out.plates.iter().zip(&out.places).enumerate().map(|(i, (p, pl))| json!({
            "id": p.id,
            "sheet": out.sheets[pl.sheet].file,
            "rotation_deg": pl.angle,
            "offset": [pl.offset.x, pl.offset.y],
            "bbox_min": placed(i),
            "micro_joints": drawn[i].joints.len(),
        })).collect::<Vec<_>>(),
        "speed_table": speeds,
    });
    let text = serde_json::to_string_pretty(&doc)?;
    write_atomic(path, |w| writeln!(w, "{text}"))?;
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let out = execute(&args)?;
    let cost: f64 = out.sheets.iter().map(|s| s.stock.cost).sum();
    if args.json {
        outln!(
            "{}",
            json!({
                "output": args.output,
                "plates": out.plates.len(),
                "sheets": out.sheets.len(),
                "utilisation": out.utilisation(),
                "cost": cost,
            })
        );
        return Ok(());
    }
    outln!(
        "{}: {} plates on {} sheet(s), {:.1} % used{}",
        args.output.display(),
        out.plates.len(),
        out.sheets.len(),
        100.0 * out.utilisation(),
        if cost > 0.0 {
            format!(", stock cost {cost}")
        } else {
            String::new()
        }
    );
    let mut t_prev = None;
    for s in &out.sheets {
        if t_prev != Some(s.thickness.to_bits()) {
            let these: Vec<&SheetInfo> = out
                .sheets
                .iter()
                .filter(|o| o.thickness == s.thickness)
                .collect();
            let used: f64 = these.iter().map(|o| o.area).sum();
            let stock: f64 = these.iter().map(|o| o.stock.size.x * o.stock.size.y).sum();
            let remnants: usize = these.iter().map(|o| o.remnants.len()).sum();
            let laser: f64 = these.iter().map(|o| o.time_s.0).sum();
            outln!(
                "  {} mm: {} sheet(s), {:.1} % used, {remnants} remnant(s), laser about {:.0} min",
                thickness_name(s.thickness),
                these.len(),
                100.0 * used / stock,
                laser / 60.0
            );
            t_prev = Some(s.thickness.to_bits());
        }
    }
    if let Some(j) = out.joints {
        let small = out.plates.iter().filter(|p| j.applies(&p.outline)).count();
        let short = out
            .joint_counts
            .iter()
            .zip(&out.plates)
            .filter(|(&n, p)| n < j.per_part && j.applies(&p.outline))
            .count();
        outln!(
            "  micro-joints: {} on {small} part(s) under {} mm, {} mm wide{}; no assembly.scad (OpenSCAD drops open contours: the plates folder's rebuilds from the part DXFs)",
            out.joint_counts.iter().sum::<usize>(),
            j.below,
            j.width,
            if short > 0 {
                format!(", {short} part(s) with fewer than {} (sides too short)", j.per_part)
            } else {
                String::new()
            }
        );
    }
    if !out.cores.is_empty() {
        outln!(
            "  {} node core(s) are tubes, not nested: cut from tube stock (rows `tube` in bom.csv)",
            out.cores.len()
        );
    }
    Ok(())
}
