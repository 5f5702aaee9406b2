//! `lamina plates axes.json -o DIR`: steel plates from node axes (plates.json, assembly.stl).

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args as ClapArgs;
use serde_json::json;

use lamina::fabricate::tags::{TAG_HEIGHT, TAG_MARGIN};
use lamina::rationalize::axes::read_axes;
use lamina::rationalize::bolts;
use lamina::rationalize::clearance::Socket;
use lamina::stage::plates::{self, BoltSize, CoreSize, EdgeSelector, Joints};
use lamina::view::scene::Input;

#[derive(ClapArgs)]
pub struct Args {
    /// The axes file `lamina planarize` wrote
    pub input: PathBuf,
    /// Sheet thicknesses available, mm, ascending; every plate is one of them [default:
    /// 1.5,2,3,4,5,6, or the sizing's list with --sizing]
    #[arg(long, value_delimiter = ',')]
    pub gauges: Option<Vec<f64>>,
    /// Every plate this thick, mm (a gauge) [default: from the vein radii, thicker veins on
    /// thicker gauges]
    #[arg(long, conflicts_with = "sizing")]
    pub thickness: Option<f64>,
    /// Gauges from `lamina size` (sizing.json for these axes): each edge's plate as sized
    #[arg(long)]
    pub sizing: Option<PathBuf>,
    /// Thickness for some edges, over the rule: `SELECTOR:MM`, where SELECTOR is `edge=K` or a
    /// node selector both ends must match (`all`, `node=N`, `x|y|z` `<` `<=` `>` `>=` value),
    /// e.g. `z<1:6` for a 6 mm base ring; repeatable, a later match wins
    #[arg(long, value_parser = parse_override)]
    pub edge_thickness: Vec<(EdgeSelector, f64)>,
    #[command(flatten)]
    pub joints: JointArgs,
    /// Exit 1 when two plates at a node meet at less than this dihedral angle, degrees (weld
    /// access; prequalified fillet welds need 60°)
    #[arg(long, allow_negative_numbers = true)]
    pub min_weld_angle: Option<f64>,
    /// Assembly groups: connected, balanced by plate count, few seams; a seam plate becomes two
    /// plates from the gauge list bolted face to face
    #[arg(long, default_value_t = 1)]
    pub groups: usize,
    /// The steel: s235, s355, 1.4404 or a JSON file as `size` takes; its grade and density go
    /// into plates.json, the mass and the cut files [default: the sizing's with --sizing, else
    /// 1.4404]
    #[arg(long)]
    pub material: Option<String>,
    /// Output folder (made if missing): plates.json, welds.json, welds.html, assembly.stl,
    /// assembly.obj (one object per plate and core), parts/ID.dxf, assembly.scad
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

/// How the plates are joined: `plates` cuts with these, and `size` weighs the plates as cut
/// with them.
#[derive(ClapArgs, Clone, Debug)]
pub struct JointArgs {
    /// Root gap between plates meeting at a node, for the weld, mm (above 0; 0 only with
    /// --node-core)
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub weld_gap: f64,
    /// How far a root gap may be from --weld-gap, mm (at most --weld-gap)
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub weld_gap_tolerance: f64,
    /// A tube on the node's axis for the plates to weld to, at nodes where setting the plates
    /// back cannot open the weld gap: `tube:DIAMETER,WALL` in mm [default: such nodes are only
    /// reported]
    #[arg(long, value_parser = CoreSize::parse)]
    pub node_core: Option<CoreSize>,
    /// Bolts through the seam plates: M6, M8, M10, M12, M16, M20, M22, M24, M27, M30
    /// [default: by the grip (Unwin's rule), smaller where a plate is too small, the first
    /// whose row holds the seam's forces]
    #[arg(long, value_parser = bolts::parse)]
    pub bolt: Option<BoltSize>,
    /// The socket that tightens the bolts, RADIUS:REACH in mm (it must fit over every head and
    /// nut without crossing a plate, as must the washers, head and nut themselves) [default:
    /// one per size, the nut's corners and a 3 mm wall, 40 mm long]
    #[arg(long, value_parser = Socket::parse)]
    pub bolt_clearance: Option<Socket>,
}

impl JointArgs {
    /// The joints these flags give.
    pub fn joints(&self) -> Joints {
        Joints {
            weld_gap: self.weld_gap,
            weld_gap_tolerance: self.weld_gap_tolerance,
            node_core: self.node_core,
            bolt: self.bolt,
            bolt_clearance: self.bolt_clearance,
        }
    }
}

impl Default for JointArgs {
    fn default() -> Self {
        let j = Joints::default();
        JointArgs {
            weld_gap: j.weld_gap,
            weld_gap_tolerance: j.weld_gap_tolerance,
            node_core: j.node_core,
            bolt: j.bolt,
            bolt_clearance: j.bolt_clearance,
        }
    }
}

fn parse_override(s: &str) -> Result<(EdgeSelector, f64), String> {
    let (sel, t) = s
        .rsplit_once(':')
        .ok_or_else(|| format!("`{s}`: expected SELECTOR:MM, like z<1:6 or edge=12:4"))?;
    let t: f64 = t
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: `{t}` is not a thickness in mm"))?;
    Ok((EdgeSelector::parse(sel)?, t))
}

/// Reads the axes (and sizing), makes the plates, writes every file into the folder.
pub fn execute(args: &Args) -> Result<plates::Plated> {
    let axes = read_axes(&args.input)?;
    let sizing = match &args.sizing {
        Some(p) => Some(lamina::analyze::sizing::read_gauges(p)?.into()),
        None => None,
    };
    let opts = plates::Options {
        gauges: args.gauges.clone(),
        thickness: args.thickness,
        sizing,
        edge_thickness: args.edge_thickness.clone(),
        weld_gap: args.joints.weld_gap,
        weld_gap_tolerance: args.joints.weld_gap_tolerance,
        node_core: args.joints.node_core,
        min_weld_angle: args.min_weld_angle,
        groups: args.groups,
        bolt: args.joints.bolt,
        bolt_clearance: args.joints.bolt_clearance,
        material: args
            .material
            .as_deref()
            .map(plates::Material::get)
            .transpose()?,
    };
    let made = plates::run(&axes, &opts).map_err(|e| match (e, &args.sizing) {
        (plates::Error::Option(o), _) => anyhow::Error::new(o),
        (plates::Error::Plates(e), Some(sizing)) if e.is_the_sizings() => {
            anyhow::anyhow!("{}: {e}", sizing.display())
        }
        (e, _) => anyhow::anyhow!("{}: {e}", args.input.display()),
    })?;
    for n in &made.notes {
        errln!("lamina: {n}");
    }
    // The page before any file: a model too large for the viewer gets its files all the same.
    let (summary_axes, summary) = lamina::rationalize::axes::read_axes_and_summary(&args.input)?;
    let tolerance = summary["tolerance"].as_f64().filter(|t| *t > 0.0);
    let mut inputs = vec![(
        file_name(&args.input),
        Input::Axes(Box::new(summary_axes), tolerance),
    )];
    if let Some(s) = &args.sizing {
        let checks = lamina::analyze::sizing::read_checks(s)?;
        inputs.push((file_name(s), Input::Sizing(checks)));
    }
    let (page, note) = plates::weld_page(&made, inputs, args.sizing.is_some())?;
    if let Some(n) = note {
        errln!("lamina: {n}");
    }
    plates::write_folder(&made, &args.output, &page)?;
    Ok(made)
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Writes everything; false when a weld angle is below --min-weld-angle or a bolt cannot be
/// fitted or tightened (exit 1).
pub fn run(args: Args) -> Result<bool> {
    let made = execute(&args)?;
    let weld = &made.welds.summary;
    let sum = made.summary();
    let ok = made.ok;
    if args.json {
        let mut value = serde_json::to_value(&sum)?;
        value["output"] = json!(args.output);
        outln!("{value}");
    } else {
        outln!(
            "{}: {} plates in {} group(s), {} seam(s) as bolted pairs ({} bolts), {:.3} m² of plate, {:.1} kg of {} ({} g/cm³){}; panels flattened by at most {:.4} mm",
            args.output.display(),
            sum.plates,
            sum.groups,
            sum.seams,
            sum.bolts,
            sum.area_mm2 * 1e-6,
            sum.mass_kg,
            made.material.name,
            made.material.density,
            match (sum.bolt_sets_kg > 0.0, sum.cores_kg > 0.0) {
                (false, false) => String::new(),
                (b, c) => format!(
                    ", {:.1} kg with the {}{}{}",
                    sum.mass_kg + sum.bolt_sets_kg + sum.cores_kg,
                    if b { "bolt sets" } else { "" },
                    if b && c { " and " } else { "" },
                    if c { "node cores" } else { "" },
                ),
            },
            sum.max_flattening_mm
        );
        outln!(
            "  welds: {} node(s), {} pair(s); root gap {} ± {} mm at {} node(s){}; dihedral angles from {:.1}°: {} below 60°, {} 60–120°, {} 120–135°, {} 135–180° (welds.html)",
            weld.nodes,
            weld.pairs,
            args.joints.weld_gap,
            args.joints.weld_gap_tolerance,
            weld.even_nodes,
            if weld.cores > 0 {
                format!(", {} with a node core", weld.cores)
            } else {
                String::new()
            },
            weld.smallest_dihedral_deg,
            weld.pairs_below_60,
            weld.pairs_60_120,
            weld.pairs_120_135,
            weld.pairs_over_135,
        );
        if sum.seams > 0 {
            let class = made.options.bolt_grade.name;
            match sum.max_bolt_utilisation {
                Some(u) => outln!(
                    "  bolts: {class}, {}; the most loaded at utilisation {:.3} under the sizing's ultimate forces (EN 1993-1-8 Table 3.4: shear, bearing, tension, punching)",
                    lamina::rationalize::bolts::PRELOAD,
                    u
                ),
                None => outln!(
                    "  bolts: {class}, {}; not checked against forces: give --sizing (from `size --groups`) for the shear, bearing and tension checks",
                    lamina::rationalize::bolts::PRELOAD
                ),
            }
        }
        if sum.bolts_moved > 0 {
            outln!(
                "  {} bolt(s) moved along their rows (at most {:.1} mm) to clear the plates for washer, head, nut and socket",
                sum.bolts_moved,
                sum.largest_bolt_move_mm
            );
        }
        if sum.bolts_dropped > 0 {
            outln!(
                "  {} bolt(s) left out for want of room to fit or tighten them (their rows keep two bolts and EN 1993-1-8 Table 3.3 without them; the bolt checks are made on what is left)",
                sum.bolts_dropped
            );
        }
        if sum.bolt_clashes > 0 {
            let list: Vec<String> = made
                .file
                .plates
                .iter()
                .filter(|p| p.bolted_to.as_deref().is_some_and(|o| p.id.as_str() < o))
                .filter_map(|p| p.bolt.as_ref().map(|b| (p, b)))
                .flat_map(|(p, b)| b.clashes.iter().map(move |c| format!("{} {c}", p.id)))
                .take(5)
                .collect();
            outln!(
                "  {} bolt(s) cannot be fitted or tightened anywhere their row allows (plates.json bolt.clashes; --bolt-clearance for another socket): {}{}",
                sum.bolt_clashes,
                list.join("; "),
                if sum.bolt_clashes > 5 { "; …" } else { "" }
            );
        }
        let uneven = &weld.nodes_needing_a_core;
        if !uneven.is_empty() {
            let list: Vec<String> = uneven.iter().take(10).map(|n| n.to_string()).collect();
            outln!(
                "  {} node(s) need a node core (no setbacks even their gaps; --node-core tube:D,T): {}{}",
                uneven.len(),
                list.join(", "),
                if uneven.len() > 10 { ", …" } else { "" }
            );
        }
        if sum.untagged > 0 {
            outln!(
                "  {} plate(s) too small for a {} mm tag {} mm inside the outline: not etched",
                sum.untagged,
                TAG_HEIGHT.0,
                TAG_MARGIN
            );
        }
    }
    if let (false, Some(a)) = (ok, args.min_weld_angle) {
        errln!(
            "lamina: {} pair(s) of plates meet at less than --min-weld-angle {a}° (the smallest {:.2}°): see welds.html",
            weld.pairs_below_min_weld_angle, weld.smallest_dihedral_deg
        );
    }
    Ok(ok)
}
