//! Growth forms (Hart): the paper's Figure 8 program grown to 10,000 and 100,000 cells (growth
//! alone: divisions, relaxation with every move checked against nearby triangles, collision
//! tests), then the textured skin and its triangle-against-triangle test. Peak memory (VmHWM)
//! is read after each size. The paper's Java grows "about 10,000 cells in under a minute"; its
//! code is unpublished, so that figure is the only peer.
//! `harness = false`: `cargo bench --bench buds`.

use std::time::Instant;

#[path = "common/timing.rs"]
mod timing;
use timing::peak_mib;

use lamina::grow::buds::{
    grow, parse_program, program::FIGURE_8, skin, GrowthOptions, SkinOptions,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let program = parse_program(FIGURE_8, "Figure 8")?;
    let sizes: Vec<usize> = match std::env::var("BUDS_BENCH_CELLS") {
        Ok(s) => s.split(',').map(str::parse).collect::<Result<_, _>>()?,
        Err(_) => vec![10_000, 100_000],
    };
    for cells in sizes {
        let runs = if cells <= 10_000 { 3 } else { 1 };
        for seed in 1..=runs {
            let options = GrowthOptions {
                max_cells: cells,
                ..GrowthOptions::default()
            };
            let t = Instant::now();
            let form = grow(&program, options, seed)?;
            let growth = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let (mesh, report) = skin(&form, &SkinOptions::default());
            let skinning = t.elapsed().as_secs_f64();
            let r = &form.report;
            println!(
                "Figure 8, {:>6} cells (seed {seed}): grow {growth:6.2} s ({:.0} cells/s; {} buds, {} froze, {} divisions blocked, degrees {}..{}), skin {skinning:5.2} s ({} triangles, {} self-intersections), peak {:.0} MiB; ratio to the paper's ~60 s for 10,000 cells: {:.3}",
                r.cells,
                r.cells as f64 / growth,
                r.buds_made,
                r.buds_frozen,
                r.divisions_blocked,
                r.degrees.first().map_or(0, |d| d.0),
                r.degrees.last().map_or(0, |d| d.0),
                mesh.triangles.len(),
                report.self_intersections,
                peak_mib(),
                growth / (60.0 * r.cells as f64 / 10_000.0),
            );
        }
    }
    Ok(())
}
