//! `lamina size axes.json -o sizing.json`: a frame analysis of the plate network and the gauges
//! it needs (sizing.json, an HTML report, a CalculiX deck).

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use glam::DVec3;
use serde_json::json;

use lamina::analyze::ccx::write_deck;
use lamina::analyze::frame::{local_frame, Support};
use lamina::analyze::material::Material;
use lamina::analyze::report::sizing_html;
use lamina::analyze::sizing::{size, DeflectionLimit, GroupBy, LoadSpec, Sizing, SizingOptions};
use lamina::files::write_atomic;
use lamina::rationalize::axes::read_axes;
use lamina::rationalize::planarize::Selector;

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
    #[arg(long, value_parser = parse_support)]
    pub support: Vec<(Selector, Support)>,
    /// A load: `self-weight[:FACTOR]`, `point:NODES:FX,FY,FZ` (N on each selected node),
    /// `wind:KPA:DX,DY,DZ` (pressure on the panels across the direction); repeatable, each a
    /// load case, and their sum another
    #[arg(long)]
    pub load: Vec<String>,
    /// Largest displacement under the sum of the loads: `L/N` (L the network's largest
    /// horizontal extent) or mm; gauges are raised until it holds
    #[arg(long, value_parser = DeflectionLimit::parse)]
    pub deflection_limit: Option<DeflectionLimit>,
    /// Members sized together: each `member`, each `chain` (runs through nodes with two
    /// members), or each `assembly` group of `--groups K` (the groups `plates --groups K`
    /// makes; the seam members between two groups together)
    #[arg(long, default_value = "member", value_parser = parse_group_by)]
    pub group_by: GroupBy,
    /// Assembly groups for `--group-by assembly`, as `plates --groups`
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
    /// Analyse the panels themselves as flat shells, N elements up each (even, 2 to 32),
    /// welded along the node axes, instead of beams: for deep panels (Calyx's), where beam
    /// theory is stiffer than the plates are
    #[arg(long, value_name = "N")]
    pub shells: Option<usize>,
    /// An HTML report: the structure by utilisation and by gauge, the deformed shape, tables
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// The final model as a CalculiX deck (B32 beams), loaded by the sum of the loads
    #[arg(long)]
    pub export_ccx: Option<PathBuf>,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

fn parse_support(s: &str) -> Result<(Selector, Support), String> {
    let (sel, kind) = match s.rsplit_once(':') {
        Some((a, "fixed")) => (a, Support::Fixed),
        Some((a, "pinned")) => (a, Support::Pinned),
        Some((_, k)) if !k.contains(['<', '>', '=']) => {
            return Err(format!("`{s}`: `{k}` is not fixed or pinned"))
        }
        _ => (s, Support::Fixed),
    };
    Ok((Selector::parse(sel)?, kind))
}

fn parse_group_by(s: &str) -> Result<GroupBy, String> {
    match s {
        "member" => Ok(GroupBy::Member),
        "chain" => Ok(GroupBy::Chain),
        "assembly" => Ok(GroupBy::Assembly(0)),
        _ => Err(format!("`{s}`: give member, chain or assembly")),
    }
}

/// The input's file name: outputs stay the same bytes wherever the input sits.
fn source_name(path: &std::path::Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

pub struct Outcome {
    pub sizing: Sizing,
    pub ok: bool,
}

pub fn execute(args: &Args) -> Result<Outcome> {
    let material_name = args.material.as_deref().unwrap_or("1.4404");
    let material = Material::get(material_name)?;
    if args.material.is_none() {
        errln!(
            "lamina: material 1.4404 (stainless 316L, f_y {} MPa), the default: give --material for another",
            material.fy
        );
    }
    if args.gauges.is_empty()
        || args
            .gauges
            .iter()
            .any(|g| !(g.is_finite() && *g > 0.0 && *g <= 200.0))
        || args.gauges.windows(2).any(|w| w[0] >= w[1])
    {
        bail!("--gauges must be thicknesses from 0 to 200 mm in ascending order");
    }
    if !(args.throat > 0.0 && args.throat <= 2.0) {
        bail!(
            "--throat must be more than 0 and at most 2, got {}",
            lamina::text::num(args.throat)
        );
    }
    if !(1..=200).contains(&args.max_rounds) {
        bail!(
            "--max-rounds must be from 1 to 200, got {}",
            args.max_rounds
        );
    }
    if let Some(n) = args.shells {
        if !(2..=32).contains(&n) || n % 2 == 1 {
            bail!("--shells must be an even number of elements from 2 to 32, got {n}");
        }
    }
    if args.support.is_empty() {
        bail!("no support: give --support SELECTOR[:fixed|pinned], e.g. --support 'z<1'");
    }
    if args.load.is_empty() {
        bail!("no load: give --load self-weight, --load point:NODES:FX,FY,FZ or --load wind:KPA:DX,DY,DZ");
    }
    let loads = args
        .load
        .iter()
        .map(|s| {
            LoadSpec::parse(s)
                .map(|l| (s.clone(), l))
                .map_err(|e| anyhow::anyhow!("--load {e}"))
        })
        .collect::<Result<Vec<_>>>()?;
    let axes = read_axes(&args.input)?;
    let opts = SizingOptions {
        material,
        gauges: args.gauges.clone(),
        supports: args.support.clone(),
        loads,
        deflection_limit: args.deflection_limit,
        group_by: match (args.group_by, args.groups) {
            (GroupBy::Assembly(_), Some(k)) if k >= 1 => GroupBy::Assembly(k),
            (GroupBy::Assembly(_), _) => {
                bail!("--group-by assembly needs --groups K (at least 1), the count `plates --groups` is given")
            }
            (by, None) => by,
            (_, Some(_)) => bail!("--groups applies only with --group-by assembly"),
        },
        smooth: args.smooth,
        throat_factor: args.throat,
        max_rounds: args.max_rounds,
        shells: args.shells,
    };
    let sizing = size(&axes, &opts).with_context(|| format!("{}", args.input.display()))?;
    let (max_u, max_w) = (sizing.max_utilisation(), sizing.max_weld_utilisation());
    let (_, max_d) = sizing.max_displacement();
    let deflection_ok = sizing.deflection_limit.is_none_or(|l| max_d <= l);
    let ok = max_u <= 1.0 && max_w <= 1.0 && deflection_ok;

    let doc = sizing_json(&sizing, &opts, args)?;
    let text = serde_json::to_string_pretty(&doc)? + "\n";
    write_atomic(&args.output, |w| w.write_all(text.as_bytes()))?;
    if let Some(path) = &args.html {
        let html = sizing_html(&sizing, &opts.material, &source_name(&args.input));
        write_atomic(path, |w| w.write_all(html.as_bytes()))?;
    }
    if let Some(path) = &args.export_ccx {
        let title = format!(
            "lamina size {}: {} members, {} nodes, the sum of the loads",
            source_name(&args.input),
            sizing.model.members.len(),
            sizing.model.nodes.len()
        );
        write_deck(
            &sizing.model,
            sizing.cases.last().expect("a case"),
            &title,
            opts.material.nu,
            path,
        )?;
    }
    Ok(Outcome { sizing, ok })
}

fn v3(v: DVec3) -> [f64; 3] {
    v.to_array()
}

fn sizing_json(s: &Sizing, opts: &SizingOptions, args: &Args) -> Result<serde_json::Value> {
    let total = s.total();
    let (max_u, max_w) = (s.max_utilisation(), s.max_weld_utilisation());
    let (dnode, dmax) = s.max_displacement();
    let edges: Vec<serde_json::Value> = s
        .model
        .members
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let (x, y, z, l) = local_frame(&s.model, m);
            let c = &s.checks[k];
            json!({
                "a": m.a,
                "b": m.b,
                "gauge": s.gauges[k],
                "utilisation": c.utilisation,
                "check": c.check,
                "load": s.cases[c.case].name,
                "depth": m.section.depth,
                "length": l,
                "axes": {"x": v3(x), "y": v3(y), "z": v3(z)},
                "end_forces": total.end_forces[k],
            })
        })
        .collect();
    let nodes: Vec<serde_json::Value> = s
        .model
        .nodes
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = total.displacements[i];
            let weld = s.welds[i].as_ref();
            json!({
                "position": v3(*p),
                "displacement": [d[0], d[1], d[2]],
                "rotation": [d[3], d[4], d[5]],
                "weld_utilisation": weld.map(|w| w.utilisation),
                "weld_load": weld.map(|w| s.cases[w.case].name.clone()),
                "throat": s.throats[i],
            })
        })
        .collect();
    let reactions: Vec<serde_json::Value> = total
        .reactions
        .iter()
        .map(|(node, r)| {
            json!({"node": node, "force": [r[0], r[1], r[2]], "moment": [r[3], r[4], r[5]]})
        })
        .collect();
    Ok(json!({
        "format": lamina::analyze::sizing::FORMAT,
        "version": lamina::analyze::sizing::VERSION,
        "source": source_name(&args.input),
        "units": {"length": "mm", "force": "N", "moment": "N·mm", "stress": "MPa", "mass": "kg"},
        "material": opts.material,
        "gauges": opts.gauges,
        "group_by": match opts.group_by {
            GroupBy::Member => json!("member"),
            GroupBy::Chain => json!("chain"),
            GroupBy::Assembly(k) => json!({"assembly": k}),
        },
        "smooth": opts.smooth,
        "analysis": match opts.shells {
            None => json!("frame"),
            Some(n) => json!({"shells": n}),
        },
        "supports": args.support.iter().map(|(sel, k)| format!("{sel}: {k:?}")).collect::<Vec<_>>(),
        "cases": s.cases.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        "definitions": {
            "model": match opts.shells {
                None => "a node at mid-height of each node axis (the panels' centroid line), a member per edge with a solid rectangle: depth the panel height across the member (local y, in the panel plane), thickness the gauge (local z, the panel normal); rigid joints; linear elastic, Timoshenko beams".to_string(),
                Some(n) => format!("the panels as flat shells (four-node: incompatible-mode membrane, MITC4 bending), {n} elements up each panel and square along it, the gauge as thickness, welded along the node axes they share; a node's displacement is its axis' mid-height point's, a member's end forces the resultant its panel takes along that end's axis, about the mid-height point; fixed supports hold the whole axis, pinned ones its mid-height point"),
            },
            "utilisation": lamina::analyze::report::UTILISATION,
            "weld_utilisation": lamina::analyze::report::WELD_UTILISATION,
            "end_forces": "under the sum of the loads, in the member's local axes: forces and moments the joints apply to its ends, [a: Fx Fy Fz Mx My Mz, b: ...]",
            "displacement": lamina::analyze::report::DISPLACEMENT,
            "reactions": "under the sum of the loads: force and moment each support applies",
        },
        "rounds": s.rounds,
        "converged": s.converged,
        "deflection_rounds": s.deflection_rounds,
        "edges": edges,
        "nodes": nodes,
        "reactions": reactions,
        "totals": {
            "mass_kg": s.mass_kg,
            "max_displacement": dmax,
            "max_displacement_node": dnode,
            "deflection_limit": s.deflection_limit,
            "span": s.span,
            "max_utilisation": max_u,
            "max_weld_utilisation": max_w,
            "residual": total.residual,
        },
    }))
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
    if max_u > 1.0 || max_w > 1.0 {
        outln!(
            "  NOT ENOUGH: members or welds are over-utilised even on the thickest gauge ({} mm)",
            s.gauges.iter().copied().fold(0.0, f64::max)
        );
    }
    Ok(out.ok)
}
