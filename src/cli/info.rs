//! `lamina info FILE [--json]`

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args as ClapArgs;
use serde_json::Value;

use super::input::{load, Loaded, ReadArgs};
use lamina::stage::info;

#[derive(ClapArgs)]
pub struct Args {
    /// A network (.json .obj .dxf) or a mesh (.obj .stl)
    pub file: PathBuf,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub weld: ReadArgs,
}

pub fn run(args: Args) -> Result<()> {
    let loaded = load(&args.file, &args.weld, true)?;
    let summary = summary(&args.file, &loaded);
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        out!("{}", human(&summary));
    }
    Ok(())
}

/// The summary `--json` prints.
pub fn summary(path: &Path, loaded: &Loaded) -> Value {
    let file = path.display().to_string();
    let value = match loaded {
        Loaded::Network(imp) => serde_json::to_value(info::network(
            &file,
            &imp.network,
            Some(imp),
            imp.point_tolerance(),
        )),
        Loaded::Mesh(mesh, notes) => serde_json::to_value(info::mesh(&file, mesh, notes.clone())),
    };
    value.expect("summaries serialise")
}

/// The summary as a few readable lines.
fn human(s: &Value) -> String {
    let mut out = String::new();
    let line = |out: &mut String, k: &str, v: String| out.push_str(&format!("{k:>18}  {v}\n"));
    line(
        &mut out,
        "file",
        s["file"].as_str().unwrap_or("").to_string(),
    );
    if let Some(b) = s["bbox"].as_object() {
        line(&mut out, "bbox min", fmt3(&b["min"]));
        line(&mut out, "bbox max", fmt3(&b["max"]));
        line(&mut out, "size", format!("{} mm", fmt3(&b["size"])));
    }
    if s["kind"] == "network" {
        line(&mut out, "nodes", s["nodes"].to_string());
        line(&mut out, "edges", s["edges"].to_string());
        let hist: Vec<String> = s["degree_histogram"]
            .as_array()
            .map(|a| {
                a.iter()
                    .enumerate()
                    .filter(|(_, n)| n.as_u64() != Some(0))
                    .map(|(d, n)| format!("{d}:{n}"))
                    .collect()
            })
            .unwrap_or_default();
        line(&mut out, "degrees", hist.join("  "));
        line(&mut out, "components", s["components"].to_string());
        line(&mut out, "cycles", s["cycles"].to_string());
        if let Some(l) = s["lengths"].as_object() {
            line(
                &mut out,
                "edge lengths",
                format!(
                    "total {:.3}  min {:.4}  mean {:.4}  max {:.4} mm",
                    num(&l["total"]),
                    num(&l["min"]),
                    num(&l["mean"]),
                    num(&l["max"])
                ),
            );
        }
        let u = &s["import"]["source_units"];
        if u.is_object() {
            let scale = num(&u["scale_to_mm"]);
            let unit = u["unit"]
                .as_str()
                .map(str::to_string)
                .unwrap_or_else(|| u["unit"].to_string());
            let to_mm = if scale == 1.0 {
                String::new()
            } else {
                format!(", ×{scale} to mm")
            };
            line(
                &mut out,
                "source units",
                format!("{unit} ({}){to_mm}", u["from"].as_str().unwrap_or("")),
            );
        }
        if s["import"]["inserts"].as_u64().is_some_and(|n| n > 0) {
            line(
                &mut out,
                "blocks inserted",
                s["import"]["inserts"].to_string(),
            );
        }
        let w = &s["import"]["weld"];
        if w.is_object() {
            line(
                &mut out,
                "welded",
                format!(
                    "{} of {} points merged (tolerance {} mm), {} zero-length and {} repeated segments dropped",
                    w["merged"], w["points"], tolerance(num(&w["tolerance"])),
                    w["zero_length_segments"], w["duplicate_segments"]
                ),
            );
        }
        if let Some(sk) = s["import"]["skipped"].as_object().filter(|m| !m.is_empty()) {
            let parts: Vec<String> = sk
                .iter()
                .map(|(k, n)| super::input::skipped_item(k, n))
                .collect();
            line(&mut out, "skipped", parts.join(", "));
        }
    } else {
        let t = &s["topology"];
        line(&mut out, "vertices", s["vertices"].to_string());
        line(&mut out, "triangles", s["triangles"].to_string());
        line(&mut out, "vertex colours", s["vertex_colors"].to_string());
        line(
            &mut out,
            "V E F, euler",
            format!(
                "{} {} {}, {}",
                t["vertices"], t["edges"], t["faces"], t["euler"]
            ),
        );
        line(
            &mut out,
            "boundary",
            format!(
                "{} edges in {} loops",
                t["boundary_edges"], t["boundary_loops"]
            ),
        );
        line(&mut out, "components", t["components"].to_string());
        line(
            &mut out,
            "genus",
            match t["genus"].as_i64() {
                Some(g) => g.to_string(),
                None => "none: not a 2-manifold (see problems)".into(),
            },
        );
        if let Some(b) = s["import"]["bodies"].as_u64() {
            line(&mut out, "bodies (solids)", b.to_string());
        }
        let not_read: Vec<&str> = s["import"]["not_read"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|v| v.as_str())
            .collect();
        if !not_read.is_empty() {
            line(&mut out, "not read", not_read.join(", "));
        }
        let w = &s["import"]["weld"];
        if w.is_object() {
            line(
                &mut out,
                "welded",
                format!(
                    "{} vertices merged (tolerance {} mm), {} triangles collapsed",
                    w["merged"],
                    tolerance(num(&w["tolerance"])),
                    w["collapsed_triangles"]
                ),
            );
        }
        line(&mut out, "closed", t["closed"].to_string());
        line(&mut out, "area", format!("{:.3} mm²", num(&t["area"])));
        if t["volume"].is_number() {
            line(&mut out, "volume", format!("{:.3} mm³", num(&t["volume"])));
        } else {
            line(
                &mut out,
                "volume",
                format!(
                    "{:.3} mm³ signed, of an open or broken mesh: true only if each body is closed",
                    num(&t["signed_volume"])
                ),
            );
        }
    }
    let problems = s["problems"].as_array().cloned().unwrap_or_default();
    line(&mut out, "problems", problems.len().to_string());
    const SHOWN: usize = 20;
    let more = problems.len().saturating_sub(SHOWN);
    for p in problems.into_iter().take(SHOWN) {
        let msg = p["message"]
            .as_str()
            .or(p.as_str())
            .unwrap_or("")
            .to_string();
        out.push_str(&format!("{:>18}  - {msg}\n", ""));
    }
    if more > 0 {
        out.push_str(&format!("{:>18}  … and {more} more (all in --json)\n", ""));
    }
    out
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn fmt3(v: &Value) -> String {
    let a: Vec<String> = v
        .as_array()
        .map(|a| a.iter().map(|x| format!("{:.4}", num(x))).collect())
        .unwrap_or_default();
    a.join(", ")
}

/// A weld tolerance as `{:e}` writes it, 0 as 0.
fn tolerance(t: f64) -> String {
    if t == 0.0 {
        "0".into()
    } else {
        format!("{t:e}")
    }
}
