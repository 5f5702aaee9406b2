//! `lamina nest plates.json --sheet 3000x1500 --spacing 5 -o cut/`: the plates nested on stock
//! sheets, one sheet family per thickness; a cut DXF per sheet, bom.csv, nest.json,
//! assembly.scad (rebuilt from the sheet DXFs) and sheets.svg.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use glam::DVec2;
use serde_json::json;

use lamina::fabricate::cutplan::SpeedTable;
use lamina::fabricate::nc::{self, NcFormat, Post};
use lamina::fabricate::plates_file::read_plates;
use lamina::files::write_atomic;
use lamina::stage::nest::{self, parse_rotations, parse_sheet, parse_stock, Rotations, Stock};

use super::progress::Bar;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CutOrderArg {
    Travel,
    Spread,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum NcArg {
    Gcode,
    Essi,
}

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
    /// Seed of the tries' perturbed orders: the same seed and inputs give the same sheets
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
    /// built-in table nest.json repeats) [default: typical figures for the plates' grade,
    /// stainless or carbon steel]
    #[arg(long)]
    pub speeds: Option<PathBuf>,
    /// Work spent making the sheets denser after the fill (overlap minimisation: more parts
    /// onto each sheet but the last; from 5 s a sheet, each sheet is first compressed along x
    /// then y to free room), in seconds of a 2-core reference machine; counted as work, so
    /// the same inputs give the same sheets on any machine. Then the last sheet of each
    /// thickness is packed into a strip from its origin edge (leaving one rectangle across
    /// the sheet), compressed with another S/N of work for N sheets
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub time: f64,
    /// Width of the cut, mm: the NC programs run half of it outside outer contours and inside
    /// holes (the DXFs keep the nominal contours and say so); less than the spacing
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub kerf: f64,
    /// Order of the parts on a sheet: `travel` (short rapids: nearest neighbour, 2-opt,
    /// Or-opt, pierce corners chosen for short travel) or `spread` (successive parts far apart,
    /// to spread the heat on thin sheet)
    #[arg(long, value_enum, default_value_t = CutOrderArg::Travel)]
    pub cut_order: CutOrderArg,
    /// Common-line cutting: congruent quads are paired the kerf apart along a whole side,
    /// which is cut once (less cut length, one pierce fewer a pair); needs `--kerf`, not with
    /// `--no-pairs` or `--micro-joints`
    #[arg(long)]
    pub common_line: bool,
    /// Job name, etched on every sheet's label (with sheet number, grade and thickness)
    #[arg(long)]
    pub job: Option<String>,
    /// Date (or any short text) etched on every sheet's label; none by default so that the
    /// same inputs give the same files
    #[arg(long)]
    pub date: Option<String>,
    /// NC programs beside the DXFs, one per sheet: `gcode` (.ngc) or `essi` (.esi)
    #[arg(long, value_enum)]
    pub nc: Option<NcArg>,
    /// Post-processor (docs/nc.md): linuxcnc, qtplasmac, mach3, grbl-laser for G-code; essi,
    /// essi-0.1mm for ESSI [default: linuxcnc or essi]
    #[arg(long, requires = "nc")]
    pub post: Option<String>,
    /// Replaces the post's torch-on line (G-code) or code (ESSI)
    #[arg(long, requires = "nc")]
    pub nc_on: Option<String>,
    /// Replaces the post's torch-off line or code
    #[arg(long, requires = "nc")]
    pub nc_off: Option<String>,
    /// Output folder (made if missing)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

/// The post-processor asked for, with the torch lines replaced where asked.
fn post(args: &Args) -> Result<Option<Post>> {
    let Some(format) = args.nc else {
        return Ok(None);
    };
    let format = match format {
        NcArg::Gcode => NcFormat::Gcode,
        NcArg::Essi => NcFormat::Essi,
    };
    let post = nc::post_for(
        format,
        args.post.as_deref(),
        args.nc_on.as_deref(),
        args.nc_off.as_deref(),
    )
    .map_err(|e| anyhow::anyhow!("--{}: {e}", e.field().replace('_', "-")))?;
    Ok(Some(post))
}

/// Reads the plates (and speeds), nests, writes every file into the folder.
pub fn execute(args: &Args) -> Result<nest::Nested> {
    let post = post(args)?;
    let (plates, cores, stated) = read_plates(&args.input)?;
    let material = stated
        .clone()
        .unwrap_or_else(nest::MaterialRecord::unstated);
    let stock: Vec<Stock> = match (&args.stock, args.sheet) {
        (Some(s), _) => s.clone(),
        (None, Some(size)) => vec![Stock { size, cost: 0.0 }],
        (None, None) => nest::Options::default().stock,
    };
    let speeds = args.speeds.as_deref().map(SpeedTable::read).transpose()?;
    let opts = nest::Options {
        stock,
        margin: args.margin,
        spacing: args.spacing,
        rotations: args.rotations.clone(),
        keep_groups: args.keep_groups,
        tries: args.tries,
        seed: args.seed,
        no_pairs: args.no_pairs,
        remnant_min: args.remnant_min,
        lead_in: args.lead_in,
        micro_joints: args.micro_joints,
        micro_joint_below: args.micro_joint_below,
        micro_joint_width: args.micro_joint_width,
        material,
        speeds,
        speeds_name: args.speeds.as_ref().map_or_else(
            || nest::Options::default().speeds_name,
            |p| p.display().to_string(),
        ),
        kerf: args.kerf,
        time: args.time,
        cut_order: match args.cut_order {
            CutOrderArg::Travel => nest::CutOrder::Travel,
            CutOrderArg::Spread => nest::CutOrder::Spread,
        },
        common_line: args.common_line,
        job: args.job.clone(),
        date: args.date.clone(),
    };
    let out = nest::run(plates, cores, &opts, &Bar::new()).map_err(|e| match e {
        e @ (nest::Error::TooLarge { .. } | nest::Error::Plate { .. }) => {
            anyhow::anyhow!("{}: {e}", args.input.display())
        }
        e => anyhow::Error::new(e),
    })?;
    if stated.is_none() {
        errln!(
            "lamina: {} states no material (written before plates did): taken as {} ({} g/cm³)",
            args.input.display(),
            out.material.grade,
            out.material.density
        );
    }
    if args.output.exists() && !args.output.is_dir() {
        bail!("{}: exists and is not a folder", args.output.display());
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create folder", args.output.display()))?;
    nest::write_sheets(&out, &args.output)?;
    if let Some(post) = &post {
        nest::write_nc(&out, &args.output, post)?;
    }
    // The assembly, from the sheets (not from micro-jointed ones: their outer contours are
    // open, and OpenSCAD's DXF import drops open paths).
    let scad_path = args.output.join("assembly.scad");
    if out.joints.is_some() {
        if scad_path.exists() {
            std::fs::remove_file(&scad_path).with_context(|| {
                format!("{}: cannot remove the old assembly", scad_path.display())
            })?;
        }
    } else {
        nest::write_assembly(&out, &scad_path)?;
    }
    let text = nest::bom_csv(&out);
    write_atomic(&args.output.join("bom.csv"), |w| {
        w.write_all(text.as_bytes())
    })?;
    let text = out.doc.json();
    write_atomic(&args.output.join("nest.json"), |w| {
        w.write_all(text.as_bytes())
    })?;
    let svg = nest::svg(&out);
    write_atomic(&args.output.join("sheets.svg"), |w| {
        w.write_all(svg.as_bytes())
    })?;
    Ok(out)
}

pub fn run(args: Args) -> Result<()> {
    let out = execute(&args)?;
    let cost = out.cost();
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
    for t in out.by_thickness() {
        outln!(
            "  {} mm: {} sheet(s), {:.1} % used, {} remnant(s), laser about {:.0} min",
            nest::thickness_label(t.thickness),
            t.sheets,
            100.0 * t.utilisation,
            t.remnants,
            t.laser_s / 60.0
        );
    }
    if args.common_line {
        let (lines, length) = (out.doc.total.common_lines, out.doc.total.common_mm);
        let quads = out.plates.iter().filter(|p| p.outline.len() == 4).count();
        outln!(
            "  common lines: {lines} pair(s) of congruent quads share a side the {} mm kerf apart, {:.2} m cut once, {lines} pierce(s) fewer{}",
            args.kerf,
            length / 1000.0,
            if lines == 0 {
                format!(" ({quads} quad(s), none congruent with another or all paired at the spacing)")
            } else {
                String::new()
            }
        );
    }
    if let Some(j) = out.joints {
        let small = out.plates.iter().filter(|p| j.applies(&p.outline)).count();
        let counts = out.joint_counts();
        let short = counts
            .iter()
            .zip(&out.plates)
            .filter(|(&n, p)| n < j.per_part && j.applies(&p.outline))
            .count();
        outln!(
            "  micro-joints: {} on {small} part(s) under {} mm, {} mm wide{}; no assembly.scad (OpenSCAD drops open contours: the plates folder's rebuilds from the part DXFs)",
            counts.iter().sum::<usize>(),
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
    let unlabelled: Vec<&str> = out
        .sheets
        .iter()
        .filter(|s| s.label.is_none())
        .map(|s| s.file.as_str())
        .collect();
    if !unlabelled.is_empty() {
        errln!(
            "lamina: {} sheet(s) carry no label: no free place in their scrap took it at any \
             height ({}; nest.json gives their label as null)",
            unlabelled.len(),
            unlabelled.join(", ")
        );
    }
    Ok(())
}
