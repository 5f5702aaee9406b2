//! Nesting Calyx-like plates on 3000 × 1500 mm sheets (margin 10, spacing 5, rotations 0, 90,
//! 180, 270): 300, 1,000, 3,000 and 10,000 plates, all on one sheet family.
//!
//! The plates come from the Calyx fixture through the real pipeline (planarize, then plates at
//! 3 mm, one group: 273 plates); past those, each further plate is one of them stretched by a
//! seeded random factor (0.85–1.15 along, 0.9–1.1 across), so no two are congruent by accident.
//! Each job prints sheets, utilisation and time, and writes the instance to
//! `target/bench-data/nest-N.json` for the peer (`scripts/peers/nest_packingsolver.py`, run by
//! `scripts/bench` with the time we took) and as `nest-N.plates.json` for whole-process runs.

use std::path::{Path, PathBuf};
use std::time::Instant;

#[path = "common/calyx.rs"]
mod common_calyx;

use common_calyx::calyx;
use glam::{DVec2, DVec3};
use lamina::fabricate::nest::{BottomLeft, NestOptions, Nester};
use lamina::rationalize::axes::Axes;
use lamina::rationalize::planarize::{planarize, PlanarizeOptions, Selector};
use lamina::rationalize::plates::{plates, PlateOptions, Thickness};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::json;

fn calyx_plates() -> Vec<Vec<DVec2>> {
    let input = calyx();
    let opts = PlanarizeOptions {
        fix_normals: vec![(Selector::parse("z<1").expect("selector"), DVec3::Z)],
        ..Default::default()
    };
    let sol = planarize(&input, &opts).expect("planarize");
    let axes = Axes::solved(&input, &sol, vec![0.0; input.edges.len()]);
    let p = plates(
        &axes,
        &PlateOptions {
            thickness: Thickness::Constant(3.0),
            ..Default::default()
        },
    )
    .expect("plates");
    p.plates.into_iter().map(|p| p.outline).collect()
}

fn job(base: &[Vec<DVec2>], n: usize) -> Vec<Vec<DVec2>> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    (0..n)
        .map(|k| {
            let p = &base[k % base.len()];
            if k < base.len() {
                return p.clone();
            }
            let s = DVec2::new(rng.random_range(0.85..1.15), rng.random_range(0.9..1.1));
            p.iter().map(|q| *q * s).collect()
        })
        .collect()
}

fn data_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    std::fs::create_dir_all(&dir).expect("bench-data folder");
    dir
}

/// The job for the peer, and as a plates file for `lamina nest`.
fn write_job(parts: &[Vec<DVec2>], opts: &NestOptions, ours: serde_json::Value) {
    let n = parts.len();
    let outline = |p: &Vec<DVec2>| p.iter().map(|q| [q.x, q.y]).collect::<Vec<_>>();
    let peer = json!({
        "sheet": [opts.sheet.x, opts.sheet.y],
        "margin": opts.margin,
        "spacing": opts.spacing,
        "rotations": [0, 90, 180, 270],
        "parts": parts.iter().map(outline).collect::<Vec<_>>(),
        "lamina": ours,
    });
    std::fs::write(data_dir().join(format!("nest-{n}.json")), peer.to_string()).expect("job");
    let records: Vec<_> = parts
        .iter()
        .enumerate()
        .map(|(k, p)| {
            json!({
                "id": format!("1-{:05}", k + 1),
                "group": 1,
                "edge": k,
                "nodes": [2 * k, 2 * k + 1],
                "thickness": 3.0,
                "ends": [{"node": 2 * k, "setback": 0.0, "welded_to": []},
                         {"node": 2 * k + 1, "setback": 0.0, "welded_to": []}],
                "bolted_to": null,
                "matrix": [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0],
                           [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
                "outline": outline(p),
            })
        })
        .collect();
    let file = json!({"format": "lamina-plates", "version": 1, "units": "mm", "plates": records});
    std::fs::write(
        data_dir().join(format!("nest-{n}.plates.json")),
        file.to_string(),
    )
    .expect("plates file");
}

fn area(p: &[DVec2]) -> f64 {
    0.5 * (0..p.len())
        .map(|k| p[k].perp_dot(p[(k + 1) % p.len()]))
        .sum::<f64>()
}

fn main() {
    // `cargo bench` passes --bench; a filter argument picks jobs by size.
    let filter: Option<usize> = std::env::args().skip(1).find_map(|a| a.parse().ok());
    let base = calyx_plates();
    println!("nest: {} Calyx plates as the base set", base.len());
    for n in [300, 1000, 3000, 10000] {
        if filter.is_some_and(|f| f != n) {
            continue;
        }
        let parts = job(&base, n);
        let opts = NestOptions {
            tries: NestOptions::tries_for(n),
            ..Default::default()
        };
        let nester = BottomLeft::default();
        let runs = if n <= 1000 { 3 } else { 1 };
        let mut best = f64::INFINITY;
        let mut result = None;
        for _ in 0..runs {
            let t = Instant::now();
            let r = nester.nest(&parts, &opts).expect("nest");
            best = best.min(t.elapsed().as_secs_f64());
            result = Some(r);
        }
        let r = result.expect("one run");
        let total: f64 = parts.iter().map(|p| area(p)).sum();
        let util = total / (r.sheets as f64 * opts.sheet.x * opts.sheet.y);
        println!(
            "nest/{n}: {} sheets, utilisation {:.1} %, {:.3} s (best of {runs}, {} tries)",
            r.sheets,
            100.0 * util,
            best,
            opts.tries
        );
        write_job(
            &parts,
            &opts,
            json!({"sheets": r.sheets, "utilisation": util, "seconds": best}),
        );
    }
}
