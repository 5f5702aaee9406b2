//! `lamina nest plates.json --sheet 3000x1500 --spacing 5 -o cut/`: the plates nested on stock
//! sheets, one sheet family per thickness; a cut DXF per sheet, bom.csv, nest.json,
//! assembly.scad (rebuilt from the sheet DXFs) and sheets.svg.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use glam::DVec2;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;

use lamina::fabricate::assembly::{write_scad_from_sheets, SheetPart};
use lamina::fabricate::cutsheet::{write_cut_dxf, Drawn};
use lamina::fabricate::nest::{
    grown_hull, nest_families, BottomLeft, NestError, NestOptions, Nesting, Rotations, SLACK,
};
use lamina::fabricate::plates_file::{read_plates, PlateRecord};
use lamina::fabricate::preview::{sheets_svg, SheetView};
use lamina::fabricate::tags::etch;
use lamina::files::write_atomic;

/// Stainless steel, g/cm³.
pub const DENSITY: f64 = 7.9;

#[derive(ClapArgs)]
pub struct Args {
    /// The plates file `lamina plates` wrote
    pub input: PathBuf,
    /// Stock sheet, width x height in mm
    #[arg(long, default_value = "3000x1500", value_parser = parse_sheet)]
    pub sheet: DVec2,
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
        .ok_or_else(|| format!("`{s}`: give the sheet as WIDTHxHEIGHT in mm, like 3000x1500"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
            .ok_or_else(|| format!("`{s}`: `{t}` is not a positive size in mm"))
    };
    Ok(DVec2::new(num(w)?, num(h)?))
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
    pub parts: Vec<usize>,
    pub area: f64,
}

pub struct Outcome {
    pub plates: Vec<PlateRecord>,
    pub nesting: Nesting,
    pub sheets: Vec<SheetInfo>,
    pub sheet_size: DVec2,
}

impl Outcome {
    pub fn utilisation(&self) -> f64 {
        let used: f64 = self.sheets.iter().map(|s| s.area).sum();
        used / (self.sheets.len() as f64 * self.sheet_size.x * self.sheet_size.y)
    }
}

/// The most seeded tries: each is a whole nesting of every part.
pub const MAX_TRIES: usize = 1000;

fn thickness_name(t: f64) -> String {
    let s = format!("{t:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

pub fn execute(args: &Args) -> Result<Outcome> {
    let plates = read_plates(&args.input)?;
    let opts = NestOptions {
        sheet: args.sheet,
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
    let outlines: Vec<Vec<DVec2>> = plates.iter().map(|p| p.outline.clone()).collect();
    let bar = progress(plates.len() as u64 * opts.tries as u64);
    let nester = BottomLeft {
        progress: Some({
            let bar = bar.clone();
            Arc::new(move |n| bar.inc(n as u64))
        }),
        ..Default::default()
    };
    let result = nest_families(&nester, &outlines, &keys, &opts);
    bar.finish_and_clear();
    let (nesting, sheet_keys) = result.map_err(|e| named(e, &plates, &opts, &args.input))?;

    if args.output.exists() && !args.output.is_dir() {
        bail!("{}: exists and is not a folder", args.output.display());
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create folder", args.output.display()))?;

    let mut sheets: Vec<SheetInfo> = sheet_keys
        .iter()
        .enumerate()
        .map(|(k, &(bits, group))| {
            let t = f64::from_bits(bits);
            SheetInfo {
                file: format!("sheet-{:02}-{}mm.dxf", k + 1, thickness_name(t)),
                thickness: t,
                group: args.keep_groups.then_some(group),
                parts: Vec::new(),
                area: 0.0,
            }
        })
        .collect();
    for (i, place) in nesting.places.iter().enumerate() {
        sheets[place.sheet].parts.push(i);
        sheets[place.sheet].area += plates[i].area();
    }
    let on_sheet: Vec<Vec<DVec2>> = plates
        .iter()
        .zip(&nesting.places)
        .map(|(p, place)| p.outline.iter().map(|q| place.apply(*q)).collect())
        .collect();

    // Cut DXFs.
    for sheet in &sheets {
        let mut strokes = Vec::with_capacity(sheet.parts.len());
        for &i in &sheet.parts {
            let lines = etch(&plates[i].id, &plates[i].outline)
                .map(|(_, l)| l)
                .unwrap_or_default();
            let place = nesting.places[i];
            strokes.push(
                lines
                    .iter()
                    .map(|[a, b]| [place.apply(*a), place.apply(*b)])
                    .collect::<Vec<_>>(),
            );
        }
        let drawn: Vec<Drawn> = sheet
            .parts
            .iter()
            .zip(&strokes)
            .map(|(&i, s)| Drawn {
                outline: &on_sheet[i],
                strokes: s,
            })
            .collect();
        write_cut_dxf(&drawn, Some(args.sheet), &args.output.join(&sheet.file))?;
    }

    // The assembly, from the sheets.
    let clip_d = 0.5 * args.spacing + SLACK;
    let scad: Vec<SheetPart> = plates
        .iter()
        .zip(&nesting.places)
        .enumerate()
        .map(|(i, (p, place))| SheetPart {
            id: &p.id,
            dxf: &sheets[place.sheet].file,
            thickness: p.thickness,
            matrix: p.matrix,
            angle: place.angle,
            offset: place.offset,
            clip: grown_hull(&on_sheet[i], clip_d),
        })
        .collect();
    write_scad_from_sheets(&scad, &args.output.join("assembly.scad"))?;

    write_bom(&plates, &nesting, &sheets, &args.output.join("bom.csv"))?;
    let outcome = Outcome {
        plates,
        nesting,
        sheets,
        sheet_size: args.sheet,
    };
    write_nest_json(&outcome, &opts, &args.output.join("nest.json"))?;
    let views: Vec<SheetView> = outcome
        .sheets
        .iter()
        .map(|s| SheetView {
            title: format!(
                "{}: {} mm, {} parts, {:.1} % used",
                s.file,
                thickness_name(s.thickness),
                s.parts.len(),
                100.0 * s.area / (args.sheet.x * args.sheet.y)
            ),
            parts: s
                .parts
                .iter()
                .map(|&i| {
                    (
                        on_sheet[i].as_slice(),
                        outcome.plates[i].id.as_str(),
                        outcome.plates[i].group,
                    )
                })
                .collect(),
        })
        .collect();
    let svg = sheets_svg(args.sheet, &views, 1000.0);
    write_atomic(&args.output.join("sheets.svg"), |w| {
        w.write_all(svg.as_bytes())
    })?;
    Ok(outcome)
}

/// Library errors with plate ids instead of indices.
fn named(e: NestError, plates: &[PlateRecord], opts: &NestOptions, path: &Path) -> anyhow::Error {
    match e {
        NestError::TooLarge(list) => {
            let usable = opts.sheet - DVec2::splat(2.0 * opts.margin);
            let names: Vec<String> = list
                .iter()
                .take(8)
                .map(|(i, s)| format!("{} ({:.1} × {:.1} mm)", plates[*i].id, s.x, s.y))
                .collect();
            anyhow::anyhow!(
                "{}: {} plate(s) fit no {} × {} mm sheet ({:.0} × {:.0} mm inside the margin) at any allowed rotation: {}{}",
                path.display(),
                list.len(),
                opts.sheet.x,
                opts.sheet.y,
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
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "nesting {bar:40} {pos}/{len} parts placed (all tries) {elapsed}",
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

fn write_bom(
    plates: &[PlateRecord],
    nesting: &Nesting,
    sheets: &[SheetInfo],
    path: &Path,
) -> Result<()> {
    write_atomic(path, |w| {
        writeln!(
            w,
            "id,group,thickness_mm,length_mm,width_mm,area_mm2,mass_kg,sheet,x_mm,y_mm,rotation_deg,bolted_to,welded_at_a,welded_at_b"
        )?;
        for (p, place) in plates.iter().zip(&nesting.places) {
            let s = size(&p.outline);
            let mass = p.area() * p.thickness * DENSITY * 1e-6;
            let ends: Vec<String> = p
                .ends
                .iter()
                .map(|(node, with)| format!("\"node {}: {}\"", node, with.join(" ")))
                .collect();
            writeln!(
                w,
                "\"{}\",{},{},{:.2},{:.2},{:.1},{:.4},\"{}\",{:.3},{:.3},{:.3},\"{}\",{},{}",
                p.id,
                p.group,
                p.thickness,
                s.x,
                s.y,
                p.area(),
                mass,
                sheets[place.sheet].file,
                place.offset.x,
                place.offset.y,
                place.angle.to_degrees(),
                p.bolted_to.as_deref().unwrap_or(""),
                ends[0],
                ends[1]
            )?;
        }
        Ok(())
    })?;
    Ok(())
}

fn write_nest_json(out: &Outcome, opts: &NestOptions, path: &Path) -> Result<()> {
    let sheet_area = out.sheet_size.x * out.sheet_size.y;
    // Positive thicknesses order as their bits do.
    let mut families: BTreeMap<u64, usize> = BTreeMap::new();
    for s in &out.sheets {
        *families.entry(s.thickness.to_bits()).or_default() += 1;
    }
    let doc = json!({
        "format": "lamina-nest",
        "version": 1,
        "units": "mm",
        "sheet": [out.sheet_size.x, out.sheet_size.y],
        "margin": opts.margin,
        "spacing": opts.spacing,
        "rotations": match &opts.rotations {
            Rotations::Any => json!("any"),
            Rotations::Listed(r) => json!(r),
        },
        "tries": opts.tries,
        "seed": opts.seed,
        "pairs": opts.pair,
        "plates": out.plates.len(),
        "sheets": out.sheets.iter().map(|s| json!({
            "file": s.file,
            "thickness": s.thickness,
            "group": s.group,
            "parts": s.parts.iter().map(|&i| &out.plates[i].id).collect::<Vec<_>>(),
            "part_area_mm2": s.area,
            "utilisation": s.area / sheet_area,
        })).collect::<Vec<_>>(),
        "families": families.iter().map(|(t, n)| json!({"thickness": f64::from_bits(*t), "sheets": n})).collect::<Vec<_>>(),
        "total": {
            "sheets": out.sheets.len(),
            "part_area_mm2": out.sheets.iter().map(|s| s.area).sum::<f64>(),
            "utilisation": out.utilisation(),
        },
        "placements": out.plates.iter().zip(&out.nesting.places).map(|(p, pl)| json!({
            "id": p.id,
            "sheet": out.sheets[pl.sheet].file,
            "rotation_deg": pl.angle.to_degrees(),
            "offset": [pl.offset.x, pl.offset.y],
        })).collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&doc)?;
    write_atomic(path, |w| writeln!(w, "{text}"))?;
    Ok(())
}

pub fn run(args: Args) -> Result<()> {
    let out = execute(&args)?;
    if args.json {
        println!(
            "{}",
            json!({
                "output": args.output,
                "plates": out.plates.len(),
                "sheets": out.sheets.len(),
                "utilisation": out.utilisation(),
            })
        );
        return Ok(());
    }
    println!(
        "{}: {} plates on {} sheet(s) of {} × {} mm, {:.1} % used",
        args.output.display(),
        out.plates.len(),
        out.sheets.len(),
        args.sheet.x,
        args.sheet.y,
        100.0 * out.utilisation()
    );
    let mut t_prev = None;
    for s in &out.sheets {
        if t_prev != Some(s.thickness.to_bits()) {
            let n = out
                .sheets
                .iter()
                .filter(|o| o.thickness == s.thickness)
                .count();
            println!("  {} mm: {n} sheet(s)", thickness_name(s.thickness));
            t_prev = Some(s.thickness.to_bits());
        }
    }
    Ok(())
}
