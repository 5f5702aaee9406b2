//! `lamina info FILE [--json]`

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args as ClapArgs;
use serde_json::{json, Value};

use super::input::{load, Loaded, MeshNotes, ReadArgs};
use lamina::network::arrangement::defects;
use lamina::network::io::Imported;
use lamina::TriMesh;

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

pub fn summary(path: &Path, loaded: &Loaded) -> Value {
    match loaded {
        Loaded::Network(imp) => network_summary(path, imp),
        Loaded::Mesh(mesh, notes) => mesh_summary(path, mesh, notes),
    }
}

fn bbox_json(b: &lamina::geom::Aabb) -> Value {
    if b.is_empty() {
        return Value::Null;
    }
    json!({ "min": b.min.to_array(), "max": b.max.to_array(), "size": b.size().to_array(),
            "diagonal": b.diagonal() })
}

pub fn network_summary(path: &Path, imp: &Imported) -> Value {
    let net = &imp.network;
    let v = net.validate();
    let problems: Vec<Value> = v
        .problems
        .iter()
        .map(|p| {
            let mut o = serde_json::to_value(p).unwrap_or(Value::Null);
            if let Value::Object(m) = &mut o {
                m.insert("message".into(), p.to_string().into());
            }
            o
        })
        .collect();
    // A flat drawing that is not noded: crossings and T-junctions are problems too.
    let defects = defects(net, imp.point_tolerance());
    let problems: Vec<Value> = problems
        .into_iter()
        .chain(defects.iter().map(|d| {
            let mut o = serde_json::to_value(d).unwrap_or(Value::Null);
            if let Value::Object(m) = &mut o {
                m.insert("message".into(), d.to_string().into());
            }
            o
        }))
        .collect();
    let lengths = net
        .lengths()
        .map(|l| json!({ "total": l.total, "min": l.min, "max": l.max, "mean": l.mean }));
    json!({
        "file": path.display().to_string(),
        "kind": "network",
        "nodes": net.nodes.len(),
        "edges": net.edges.len(),
        "units": net.meta.units,
        "generator": net.meta.generator,
        "bbox": bbox_json(&net.bbox()),
        "degree_histogram": v.degree_histogram,
        "components": v.components,
        "cycles": v.cycles,
        "lengths": lengths,
        "problems": problems,
        "import": {
            "weld": imp.weld,
            "skipped": imp.skipped,
            "source_units": imp.units,
            "inserts": imp.inserts,
            "split_crossings": imp.split,
        },
    })
}

pub fn mesh_summary(path: &Path, mesh: &TriMesh, notes: &MeshNotes) -> Value {
    let t = mesh.check_manifold();
    let problems: Vec<String> = t.problems.iter().map(|p| p.to_string()).collect();
    json!({
        "file": path.display().to_string(),
        "kind": "mesh",
        "vertices": mesh.positions.len(),
        "triangles": mesh.triangles.len(),
        "vertex_colors": mesh.colors.is_some(),
        "bbox": bbox_json(&mesh.bbox()),
        "topology": {
            "vertices": t.vertices, "edges": t.edges, "faces": t.faces,
            "euler": t.euler, "components": t.components,
            "boundary_edges": t.boundary_edges, "boundary_loops": t.boundary_loops,
            "closed": t.closed, "genus": t.genus, "area": t.area, "volume": t.volume,
            "signed_volume": t.signed_volume,
        },
        "problems": problems,
        "import": { "bodies": notes.bodies, "weld": notes.weld },
    })
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
                    "{} of {} points merged (tolerance {:e} mm), {} zero-length and {} repeated segments dropped",
                    w["merged"], w["points"], num(&w["tolerance"]),
                    w["zero_length_segments"], w["duplicate_segments"]
                ),
            );
        }
        if let Some(sk) = s["import"]["skipped"].as_object().filter(|m| !m.is_empty()) {
            let parts: Vec<String> = sk.iter().map(|(k, n)| format!("{n} {k}")).collect();
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
        line(&mut out, "genus", t["genus"].to_string());
        if let Some(b) = s["import"]["bodies"].as_u64() {
            line(&mut out, "bodies (solids)", b.to_string());
        }
        let w = &s["import"]["weld"];
        if w.is_object() {
            line(
                &mut out,
                "welded",
                format!(
                    "{} vertices merged (tolerance {:e} mm), {} triangles collapsed",
                    w["merged"],
                    num(&w["tolerance"]),
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
