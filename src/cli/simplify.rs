//! `lamina simplify NET -o simple.json [--surface guide.obj] [--max-deviation MM] …`: fewer,
//! straighter members for fabrication, with a report of the figures before and after.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args as ClapArgs;

use lamina::files::write_atomic;
use lamina::network::io::{write_network, NetworkFormat, RenderOptions};
use lamina::stage::simplify::{self, Figures, Report, Simplified};

use super::input::ReadArgs;

#[derive(ClapArgs)]
pub struct Args {
    /// The network (.json .obj .dxf)
    pub input: PathBuf,
    /// The simplified network (.json .obj .dxf .svg .png)
    #[arg(short, long)]
    pub output: PathBuf,
    /// Guide surface (.obj .stl): moved and merged nodes stay on it, and its normals order the
    /// members around each node
    #[arg(long)]
    pub surface: Option<PathBuf>,
    /// Every original node stays within this distance of the simplified network, mm [default:
    /// the input's mean edge length]
    #[arg(long, value_name = "MM")]
    pub max_deviation: Option<f64>,
    /// Members shorter than this are removed where they can be (stubs dropped, junctions
    /// merged, chain vertices skipped), mm; 0: off
    #[arg(long, value_name = "MM", default_value_t = 0.0)]
    pub min_length: f64,
    /// Junctions joined by a chain shorter than this merge (never into more legs than the input
    /// had, three where it had at most three), mm; 0: off
    #[arg(long, value_name = "MM", default_value_t = 0.0)]
    pub merge_distance: f64,
    /// Joints where two members meet at less than this are repaired by moving nodes within the
    /// deviation, or reported (exit status 1), degrees; 0: off
    #[arg(long, value_name = "DEG", default_value_t = 30.0)]
    pub min_angle: f64,
    /// Branches of Horton-Strahler order below this are removed (loops never); 0: off
    #[arg(long, value_name = "K", default_value_t = 0)]
    pub prune_order: u32,
    /// Write the report (figures before and after, what was done) as JSON here
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print the report on stdout as JSON
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub weld: ReadArgs,
}

/// Simplifies and writes the outputs; prints nothing.
pub fn execute(args: &Args) -> Result<(Simplified, Vec<String>)> {
    if NetworkFormat::from_path(&args.output).is_none() {
        bail!(
            "{}: a network is written as .json, .obj, .dxf, .svg or .png",
            args.output.display()
        );
    }
    let imported = args.weld.network(&args.input)?;
    let opts = simplify::Options {
        max_deviation: args.max_deviation,
        min_length: args.min_length,
        merge_distance: args.merge_distance,
        min_angle: args.min_angle,
        prune_order: args.prune_order,
    };
    let surface = args
        .surface
        .as_ref()
        .map(|p| super::input::mesh_file(p))
        .transpose()?;
    let done = simplify::run(&imported.network, surface.as_ref(), &opts).map_err(|e| match e {
        simplify::Error::EmptySurface => anyhow::anyhow!(
            "--surface {}: has no triangles",
            args.surface
                .as_ref()
                .map_or_else(String::new, |p| p.display().to_string())
        ),
        e => anyhow::anyhow!("{}: {e}", args.input.display()),
    })?;
    let out = done.simplified;
    write_network(&out.network, &args.output, &RenderOptions::default())?;
    if let Some(path) = &args.report {
        let text = serde_json::to_string_pretty(&out.report)? + "\n";
        write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    Ok((out, done.notes))
}

pub fn run(args: Args) -> Result<bool> {
    let (done, notes) = execute(&args)?;
    let r = &done.report;
    for n in &notes {
        errln!("lamina: {n}");
    }
    if args.json {
        outln!("{}", serde_json::to_string_pretty(r)?);
    } else {
        out!("{}", human(&args, r));
    }
    Ok(r.sharp_joints.is_empty())
}

fn human(args: &Args, r: &Report) -> String {
    let line = |name: &str, f: &Figures| {
        format!(
            "  {name:<7} {:>7} members {:>7} nodes  shortest {:>8.3} mm  smallest joint {}  cycles {}{}\n",
            f.members,
            f.nodes,
            f.shortest_member,
            f.smallest_joint_angle
                .map_or("—".to_string(), |a| format!("{a:.1}°")),
            f.cycles,
            f.faces.map_or(String::new(), |n| format!("  faces {n}")),
        )
    };
    let cut = 100.0 * (1.0 - r.after.members as f64 / r.before.members.max(1) as f64);
    let mut s = format!(
        "wrote {}: {:.1} % fewer members; every kept node within {:.3} mm (largest {:.3}, mean {:.3})\n",
        args.output.display(),
        cut,
        r.options.max_deviation,
        r.max_distance,
        r.mean_distance
    );
    s += &line("before", &r.before);
    s += &line("after", &r.after);
    let mut done = Vec::new();
    for (n, what) in [
        (r.isolated_nodes_dropped, "isolated nodes (no edge) dropped"),
        (r.pruned_members, "edges pruned"),
        (r.pruned_nodes, "nodes pruned"),
        (r.stubs_removed, "stubs removed"),
        (r.merged_junctions, "junctions merged"),
        (r.merges_refused, "merges refused"),
        (
            r.nodes_restored_for_embedding,
            "nodes kept to keep the faces",
        ),
        (r.joints_repaired, "sharp joints repaired"),
        (
            r.short_members_left,
            "members still shorter than --min-length",
        ),
    ] {
        if n > 0 {
            done.push(format!("{n} {what}"));
        }
    }
    if !done.is_empty() {
        s += &format!("  {}\n", done.join(", "));
    }
    if r.input_crossings > 0 {
        s += &format!(
            "  NOTE: {} pair(s) of edges cross or touch in the input without a node: the drawing is not \
             noded (give --split-crossings), so its faces mean little\n",
            r.input_crossings
        );
    }
    if r.options.min_angle > 0.0 {
        if r.sharp_joints.is_empty() {
            s += &format!("  no joint below {}°\n", r.options.min_angle);
        } else {
            s += &format!(
                "  NOT REPAIRED: {} joint(s) below {}°, the sharpest {:.1}° at node {}\n",
                r.sharp_joints.len(),
                r.options.min_angle,
                r.sharp_joints
                    .iter()
                    .map(|j| j.angle)
                    .fold(f64::INFINITY, f64::min),
                r.sharp_joints
                    .iter()
                    .min_by(|a, b| a.angle.total_cmp(&b.angle))
                    .map_or(0, |j| j.node)
            );
        }
    }
    if r.before.cycles != r.after.cycles || r.before.faces != r.after.faces {
        s += &format!(
            "  NOTE: cycles {} → {}, faces {:?} → {:?}\n",
            r.before.cycles, r.after.cycles, r.before.faces, r.after.faces
        );
    }
    s
}
