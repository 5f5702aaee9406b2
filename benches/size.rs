//! One linear analysis of a large plate frame: a square grid of N × N nodes on a shallow dome
//! (300 mm spacing, 60 × 3 mm plates, the boundary fixed, self-weight as uniform member loads),
//! 2 N (N − 1) members; N = 224 gives 99,904. Times `frame::solve` alone (assembly in place,
//! faer's sparse Cholesky with its AMD ordering, two right-hand sides, member end forces and
//! reactions), best of three, and the process's peak memory (VmHWM) after it. Whole-process
//! figures and CalculiX on the same deck are in `scripts/bench size`.
//! `harness = false`: `cargo bench --bench size` (SIZE_BENCH_N=224 by default).

#[path = "common/timing.rs"]
mod timing;
use timing::{best_of, peak_mib};

use glam::DVec3;
use lamina::analyze::frame::{solve, Elastic, LoadCase, Member, Model, Section, Support};
use lamina::analyze::sizing::max_displacement;

fn grid(n: usize) -> Model {
    let step = 300.0;
    let span = step * (n - 1) as f64;
    let r2 = (span / 2.0).powi(2);
    let rise = 0.15 * span;
    let at = |i: usize, j: usize| {
        let (x, y) = (i as f64 * step - span / 2.0, j as f64 * step - span / 2.0);
        let z = rise * (1.0 - (x * x + y * y) / (2.0 * r2));
        let normal = DVec3::new(rise * x / r2, rise * y / r2, 1.0).normalize();
        (DVec3::new(x, y, z), normal)
    };
    let mut nodes = Vec::with_capacity(n * n);
    let mut normals = Vec::with_capacity(n * n);
    let mut supports = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (p, normal) = at(i, j);
            nodes.push(p);
            normals.push(normal);
            let edge = i == 0 || j == 0 || i == n - 1 || j == n - 1;
            supports.push(edge.then_some(Support::Fixed));
        }
    }
    let section = Section::solid(60.0, 3.0);
    let mut members = Vec::with_capacity(2 * n * (n - 1));
    for i in 0..n {
        for j in 0..n {
            let k = i * n + j;
            for (ok, other) in [(j + 1 < n, k + 1), (i + 1 < n, k + n)] {
                if ok {
                    members.push(Member {
                        a: k,
                        b: other,
                        y: normals[k] + normals[other],
                        section,
                    });
                }
            }
        }
    }
    Model {
        nodes,
        members,
        supports,
        elastic: Elastic {
            e: 200_000.0,
            g: 200_000.0 / 2.6,
        },
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::var("SIZE_BENCH_N").map_or(Ok(224), |s| s.parse())?;
    let model = grid(n);
    let weight = 7.9e-6 * 9.80665 * 60.0 * 3.0; // N/mm
    let load = LoadCase {
        name: "self-weight".into(),
        nodal: vec![],
        member: (0..model.members.len())
            .map(|k| (k, DVec3::new(0.0, 0.0, -weight)))
            .collect(),
    };
    let cases = [load.clone(), load];
    let before = peak_mib();
    let (secs, results) = best_of(3, || solve(&model, &cases));
    let results = results?;
    let (_, worst) = max_displacement(&results[0]);
    println!(
        "frame {n} x {n}: {} nodes, {} members, one analysis (two load cases) {secs:.2} s, largest displacement {worst:.3} mm, residual {:.1e}, peak {:.0} MiB (model alone {before:.0} MiB)",
        model.nodes.len(),
        model.members.len(),
        results[0].residual,
        peak_mib(),
    );
    Ok(())
}
