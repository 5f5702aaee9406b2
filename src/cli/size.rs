//! `lamina size axes.json -o sizing.json`: a frame analysis of the plate network and the gauges
//! it needs (sizing.json, an HTML report, a CalculiX deck).

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args as ClapArgs;
use serde_json::json;

use lamina::analyze::ccx::{write_deck, write_shell_deck};
use lamina::analyze::report::sizing_html;
use lamina::files::write_atomic;
use lamina::rationalize::axes::read_axes;
use lamina::rationalize::planarize::Selector;
use lamina::stage::size::{self, DeflectionLimit, GroupBy, Material, Support};

use super::progress::Bar;

#[derive(ClapArgs)]
pub struct Args {
    /// The axes file `lamina planarize` wrote
    pub input: PathBuf,
    /// The sizing file (gauges, utilisation, displacements, reactions)
    #[arg(short, long, visible_alias = "report")]
    pub output: PathBuf,
    /// s235, s355, 1.4404 (stainless 316L) or a JSON file (see the README) [default: 1.4404]
    #[arg(long)]
    pub material: Option<String>,
    /// Sheet thicknesses to choose from, mm, ascending
    #[arg(long, value_delimiter = ',', default_value = "1.5,2,3,4,5,6,8,10")]
    pub gauges: Vec<f64>,
    /// Supported nodes: a selector (`all`, `node=N`, `x|y|z` `<` `<=` `>` `>=` value) and
    /// `:fixed` (default) or `:pinned`; repeatable
    #[arg(long, value_parser = size::support)]
    pub support: Vec<(Selector, Support)>,
    /// A load: `self-weight[:FACTOR]`, `point:NODES:FX,FY,FZ` (N on each selected node),
    /// `wind:KPA:DX,DY,DZ` (pressure on the panels across the direction); repeatable. Self-weight
    /// is permanent (G), point and wind variable (Q) unless ending in `:G`; members and welds
    /// are checked under EN 1990's ULS combinations (6.10), the deflection under the SLS ones
    #[arg(long)]
    pub load: Vec<String>,
    /// Largest displacement under the sum of the loads: `L/N` (L the network's largest
    /// horizontal extent) or mm; gauges are raised until it holds
    #[arg(long, value_parser = DeflectionLimit::parse)]
    pub deflection_limit: Option<DeflectionLimit>,
    /// Members sized together: each `member`, each `chain` (runs through nodes with two
    /// members), or each `assembly` group of `--groups K` (the groups `plates --groups K`
    /// makes; the seam members between two groups together)
    #[arg(long, default_value = "member", value_parser = size::group_by)]
    pub group_by: GroupBy,
    /// The assembly groups `plates --groups K` will cut: members between two groups are
    /// bolted seams, sized as the two plies they are cut from (gauges that are sums of two on
    /// the list, each ply's own bending and torsion); also the groups of `--group-by assembly`
    #[arg(long)]
    pub groups: Option<usize>,
    /// Neighbouring members within one gauge step (thinner ones raised)
    #[arg(long)]
    pub smooth: bool,
    /// Fillet weld throat over the thinner plate at a node
    #[arg(long, default_value_t = 0.7, allow_negative_numbers = true)]
    pub throat: f64,
    /// Rounds of analysis and gauge choice at most
    #[arg(long, default_value_t = 20)]
    pub max_rounds: usize,
    /// Analyse the panels themselves as flat shells, N elements up each (even, 4 to 32),
    /// welded along the node axes, instead of beams: for deep panels (Calyx's), where beam
    /// theory is stiffer than the plates are
    #[arg(long, value_name = "N")]
    pub shells: Option<usize>,
    /// An HTML report: the structure by utilisation and by gauge, the deformed shape, tables
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// The final model as a CalculiX deck loaded by the sum of the loads: B32 beams, or with
    /// --shells the panels as S8R shells on the mesh analysed
    #[arg(long)]
    pub export_ccx: Option<PathBuf>,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
    /// The joints `plates` will cut with (the same flags and defaults): the self-weight and
    /// mass are the plates as cut (setbacks at the nodes, bolt holes, bolt sets, node cores),
    /// and `plates --sizing` refuses other joints
    #[command(
        flatten,
        next_help_heading = "Joints, as `plates` will cut them (the self-weight is the plates as cut; `plates --sizing` refuses other joints)"
    )]
    pub joints: super::plates::JointArgs,
}

/// Reads the axes, sizes, writes sizing.json and what else is asked for.
pub fn execute(args: &Args) -> Result<size::Sized> {
    let material = args.material.as_deref().map(Material::get).transpose()?;
    let opts = size::Options {
        material,
        gauges: args.gauges.clone(),
        support: args.support.clone(),
        load: args.load.clone(),
        deflection_limit: args.deflection_limit,
        group_by: args.group_by,
        groups: args.groups,
        smooth: args.smooth,
        throat: args.throat,
        max_rounds: args.max_rounds,
        shells: args.shells,
        joints: args.joints.joints(),
        name: lamina::files::file_name(&args.input),
    };
    let axes = read_axes(&args.input)?;
    let sized = size::run(&axes, &opts, &Bar::new()).map_err(|e| match e {
        size::Error::Sizing(e) => anyhow::anyhow!("{}: {e}", args.input.display()),
        e => anyhow::Error::new(e),
    })?;
    for n in &sized.notes {
        errln!("lamina: {n}");
    }
    let sizing = &sized.sizing;
    write_atomic(&args.output, |w| {
        w.write_all(sized.report.json().as_bytes())
    })?;
    if let Some(path) = &args.html {
        let html = sizing_html(
            sizing,
            &sized.report.material,
            &lamina::files::file_name(&args.input),
        );
        write_atomic(path, |w| w.write_all(html.as_bytes()))?;
    }
    if let Some(path) = &args.export_ccx {
        let model = &sizing.model;
        let title = format!(
            "lamina size {}: {} members, {} nodes, the sum of the loads{}",
            lamina::files::file_name(&args.input),
            model.members.len(),
            model.nodes.len(),
            match sizing.shells {
                Some(n) => format!(", the panels as shells ({n} up each)"),
                None => String::new(),
            }
        );
        let nu = sized.report.material.nu;
        match sizing.shells {
            None => write_deck(model, sizing.total_case(), &title, nu, path)?,
            Some(per_height) => {
                let mesh = lamina::analyze::sizing::shell_mesh(&axes, model, per_height);
                write_shell_deck(model, &mesh, sizing.total_case(), &title, nu, path)?
            }
        }
    }
    Ok(sized)
}

pub fn run(args: Args) -> Result<bool> {
    let out = execute(&args)?;
    let s = &out.sizing;
    let (max_u, max_w) = (s.max_utilisation(), s.max_weld_utilisation());
    let (node, d) = s.max_displacement();
    if args.json {
        outln!(
            "{}",
            json!({
                "output": args.output,
                "members": s.model.members.len(),
                "mass_kg": s.mass_kg,
                "max_utilisation": max_u,
                "max_weld_utilisation": max_w,
                "max_displacement": d,
                "rounds": s.rounds,
                "ok": out.ok,
            })
        );
        return Ok(out.ok);
    }
    let mut counts: std::collections::BTreeMap<u64, usize> = Default::default();
    for g in &s.gauges {
        *counts.entry(g.to_bits()).or_default() += 1;
    }
    let mix: Vec<String> = counts
        .iter()
        .map(|(g, n)| format!("{n} × {} mm", f64::from_bits(*g)))
        .collect();
    outln!(
        "{}: {} members sized in {} round(s){}: {}; {:.1} kg",
        args.output.display(),
        s.model.members.len(),
        s.rounds,
        if s.converged {
            ""
        } else {
            " (not settled: the cap)"
        },
        mix.join(", "),
        s.mass_kg
    );
    outln!(
        "  utilisation at most {max_u:.3}, welds at most {max_w:.3}; largest displacement {d:.3} mm at node {node}{}",
        match s.deflection_limit {
            Some(l) => format!(
                " (limit {l:.3} mm{}, {} round(s) of stiffening)",
                if d <= l { "" } else { ", NOT met" },
                s.deflection_rounds
            ),
            None => String::new(),
        }
    );
    let totals = &out.report.totals;
    if out.report.joints.is_some() {
        let seams = out
            .report
            .edges
            .iter()
            .filter(|e| e.bolts.is_some())
            .count();
        outln!(
            "  the self-weight is the plates as `plates` cuts them ({:.1} kg){}{}{}",
            s.mass_kg - totals.bolts_kg - totals.cores_kg,
            if seams > 0 {
                format!(", the bolt sets of {seams} seam(s) ({:.1} kg)", totals.bolts_kg)
            } else {
                String::new()
            },
            if totals.cores_kg > 0.0 {
                format!(", the node cores ({:.1} kg)", totals.cores_kg)
            } else {
                String::new()
            },
            match totals.max_bolt_utilisation {
                Some(u) => format!(
                    "; bolts at most {u:.3} utilised (EN 1993-1-8 Table 3.4, sizing.json edges' bolts)"
                ),
                None => String::new(),
            }
        );
    }
    let thin = &out.report.totals.thin_sheet_welds;
    if !thin.is_empty() {
        outln!(
            "  {} of {} welded nodes have a throat below 3 mm (EN 1993-1-8 4.5.2(2)): a thin-sheet \
             procedure; sizing.json names them (totals.thin_sheet_welds)",
            thin.len(),
            s.welds.iter().flatten().count()
        );
    }
    if max_u > 1.0 {
        // The member that falls shortest, what governs it and the gauge it ran out on.
        let (k, c) = s
            .checks
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.utilisation.total_cmp(&b.1.utilisation))
            .expect("a member");
        let m = &s.model.members[k];
        outln!(
            "  NOT ENOUGH: member {k} (nodes {}–{}) is utilised {:.3} by {} under {} on {} mm{}",
            m.a,
            m.b,
            c.utilisation,
            c.check,
            s.cases[c.case].name,
            s.gauges[k],
            if s.gauges[k] >= args.gauges.iter().copied().fold(0.0, f64::max) {
                ", the thickest gauge on --gauges"
            } else {
                " (the rounds stopped at --max-rounds)"
            }
        );
    }
    if max_w > 1.0 {
        let (node, w) = s
            .welds
            .iter()
            .enumerate()
            .filter_map(|(i, w)| Some((i, w.as_ref()?)))
            .max_by(|a, b| a.1.utilisation.total_cmp(&b.1.utilisation))
            .expect("a weld");
        outln!(
            "  NOT ENOUGH: the weld at node {node} is utilised {:.3} under {} (throat {:.2} mm; \
             the rounds stopped at --max-rounds)",
            w.utilisation,
            s.cases[w.case].name,
            s.throats[node]
        );
    }
    Ok(out.ok)
}
