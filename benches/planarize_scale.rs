//! Node axes at scale: generated networks on a paraboloid, a saddle and an ellipsoid, solved
//! by each method in this process, with each result's iterations, α, deviation and its axes'
//! change against L-BFGS's on the same input.
//!
//! `cargo bench --bench planarize_scale -- [SURFACE:NODES …] [--methods newton,lbfgs]
//! [--write]`: SURFACE is paraboloid (10 mm brick wall, the bowl growing with the network),
//! scaled-saddle (the same with the curvature of both signs), saddle (a fixed 2 × 2 m saddle,
//! z = (x² − y²)/2000 mm, finer as the network grows) or ellipsoid; NODES is the size asked for (the
//! network has the nearest size its construction allows). `--write` also writes each network
//! to `target/bench-data/planarize-SURFACE-NODES.json` (stored normals as references) and the
//! scipy peer's job to `…-NODES.peer.json`, for the whole-process runs in `scripts/bench`.

use std::path::Path;
use std::time::Instant;

use glam::DVec3;
#[path = "common/network_file.rs"]
mod network_file;
use lamina::rationalize::planarize::synthetic::{ellipsoid_dual, honeycomb_shaped, saddle, Shape};
use lamina::rationalize::planarize::{planarize, Input, Method, PlanarizeOptions, Solution};
use network_file::write_network_file;

fn network(surface: &str, nodes: usize) -> Input {
    match surface {
        "ellipsoid" => {
            let f = ((nodes as f64 / 20.0).sqrt().round() as usize).max(1);
            ellipsoid_dual(f, DVec3::new(1000.0, 700.0, 500.0), 100.0)
        }
        "paraboloid" | "scaled-saddle" => {
            let n = (nodes as f64).sqrt().round() as usize;
            let shape = if surface == "scaled-saddle" {
                Shape::Saddle
            } else {
                Shape::Paraboloid
            };
            honeycomb_shaped(n, 100.0, 1, shape)
        }
        "saddle" => {
            let n = (nodes as f64).sqrt().round() as usize;
            saddle(n, 1000.0, 1000.0, 100.0, 1)
        }
        other => panic!("unknown surface {other}: paraboloid, saddle, scaled-saddle or ellipsoid"),
    }
}

fn write(input: &Input, stem: &str) {
    write_network_file(input, &format!("{stem}.json"));
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    let v = |p: &[DVec3]| p.iter().map(|q| q.to_array()).collect::<Vec<_>>();
    let job = serde_json::json!({
        "positions": v(&input.positions),
        "edges": input.edges,
        "reference": v(&input.reference),
        "heights": input.heights,
        "alpha": 0.01,
        "tolerance": 0.01,
    });
    std::fs::write(dir.join(format!("{stem}.peer.json")), job.to_string()).expect("peer job");
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    a.dot(b).clamp(-1.0, 1.0).acos().to_degrees()
}

fn main() {
    let mut jobs = Vec::new();
    let mut methods = vec![Method::Newton, Method::Lbfgs];
    let mut write_files = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--bench" => {}
            "--write" => write_files = true,
            "--methods" => {
                let list = args.next().expect("a list of methods");
                methods = list
                    .split(',')
                    .map(|m| match m {
                        "newton" => Method::Newton,
                        "lbfgs" => Method::Lbfgs,
                        "projection" => Method::Projection,
                        other => panic!("unknown method {other}"),
                    })
                    .collect();
            }
            job => {
                let (surface, nodes) = job.split_once(':').expect("SURFACE:NODES");
                jobs.push((surface.to_string(), nodes.parse::<usize>().expect("a size")));
            }
        }
    }
    if jobs.is_empty() {
        for s in ["paraboloid", "saddle", "ellipsoid"] {
            jobs.push((s.to_string(), 20_000));
        }
    }
    println!(
        "| surface | nodes | edges | method | solve | iterations | α at the end | max deviation | mean / max angle from reference | mean / max axis change against L-BFGS |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (surface, nodes) in jobs {
        let input = network(&surface, nodes);
        if write_files {
            write(&input, &format!("planarize-{surface}-{nodes}"));
        }
        let mut results: Vec<(Method, Solution, f64)> = Vec::new();
        for &method in &methods {
            let opts = PlanarizeOptions {
                method,
                ..Default::default()
            };
            let start = Instant::now();
            let s = planarize(&input, &opts).expect("valid input");
            let secs = start.elapsed().as_secs_f64();
            results.push((method, s, secs));
        }
        let lbfgs = results
            .iter()
            .find(|r| r.0 == Method::Lbfgs)
            .map(|r| r.1.axes.clone());
        for (method, s, secs) in &results {
            let n = s.axis_deviation_deg.len() as f64;
            let mean = s.axis_deviation_deg.iter().sum::<f64>() / n;
            let max = s.axis_deviation_deg.iter().fold(0.0f64, |m, &a| m.max(a));
            let change = lbfgs.as_ref().map(|l| {
                let c: Vec<f64> = l.iter().zip(&s.axes).map(|(a, b)| angle(*a, *b)).collect();
                (
                    c.iter().sum::<f64>() / n,
                    c.iter().fold(0.0f64, |m, &a| m.max(a)),
                )
            });
            println!(
                "| {surface} | {} | {} | {method:?} | {secs:.2} s | {} | {:.1e} | {:.4} mm{} | {mean:.3}° / {max:.3}° | {} |",
                input.positions.len(),
                input.edges.len(),
                s.iterations,
                s.alpha_used,
                s.max_deviation,
                if s.converged { "" } else { " (not reached)" },
                change
                    .map(|(m, x)| format!("{m:.4}° / {x:.4}°"))
                    .unwrap_or_else(|| "—".into()),
            );
        }
    }
}
