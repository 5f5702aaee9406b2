//! The library's own compute for the jobs `scripts/bench_python.py` gives the Python package:
//! the stage functions the command and the package both call, on the files that script wrote
//! into `LAMINA_BENCH_WORK` (no reading or writing timed). `plates::run` on Calyx's axes with
//! the sizing's gauges and 7 groups; `audit::run` on 90,000 quads read from `quads.obj`.
//! Each also with the outputs the Python call hands back made in memory (the assembly mesh and
//! plates.json/welds.json text; the report's text). Prints one JSON line: the median seconds.
//! `harness = false`: `LAMINA_BENCH_WORK=DIR cargo bench --bench stages`.

use std::path::PathBuf;
use std::time::Instant;

use lamina::rationalize::audit::read_panels;
use lamina::rationalize::axes::read_axes;
use lamina::stage::{audit, plates};

/// The median time of `f` over the inputs, each made before its run (not timed).
fn median<I, T>(inputs: impl Iterator<Item = I>, mut f: impl FnMut(I) -> T) -> f64 {
    let mut times: Vec<f64> = inputs
        .map(|input| {
            let t = Instant::now();
            std::hint::black_box(f(input));
            t.elapsed().as_secs_f64()
        })
        .collect();
    let runs = times.len();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(work) = std::env::var_os("LAMINA_BENCH_WORK").map(PathBuf::from) else {
        eprintln!("stages: set LAMINA_BENCH_WORK to the folder scripts/bench_python.py wrote");
        return Ok(());
    };
    let axes = read_axes(&work.join("axes.json"))?;
    let g = lamina::analyze::sizing::read_gauges(&work.join("sizing.json"))?;
    let opts = plates::Options {
        sizing: Some(g.into()),
        groups: 7,
        ..Default::default()
    };
    let plates_s = median(0..11, |_| {
        plates::run(&axes, &opts).map(|m| m.set.plates.len())
    });
    // With what the Python call also hands back: the assembly mesh, and plates.json and
    // welds.json as the command writes them (text here, dicts there).
    let plates_out_s = median(0..11, |_| {
        plates::run(&axes, &opts).map(|m| {
            let mesh = plates::assembly(&m.set);
            (
                mesh.triangles.len(),
                m.file.text().len(),
                m.welds.json().len(),
            )
        })
    });
    let panels = read_panels(&work.join("quads.obj"))?;
    let opts = audit::Options {
        tolerance: Some(0.05),
        ..Default::default()
    };
    let copies: Vec<_> = (0..5).map(|_| panels.clone()).collect();
    let audit_s = median(copies.into_iter(), |p| {
        audit::run(p, &opts).map(|a| a.report.summary.within_tolerance)
    });
    // With the report as the command writes it.
    let copies: Vec<_> = (0..5).map(|_| panels.clone()).collect();
    let audit_out_s = median(copies.into_iter(), |p| {
        audit::run(p, &opts).map(|a| a.report.json().len())
    });
    println!(
        "{{\"plates_s\": {plates_s}, \"plates_out_s\": {plates_out_s}, \"audit_s\": {audit_s}, \"audit_out_s\": {audit_out_s}}}"
    );
    Ok(())
}
