//! Growth forms (Hart): the paper's Figure 8 program, topology after every operation, holes,
//! bud splitting, line buds, textures, determinism and bad programs.

use std::collections::{BTreeSet, VecDeque};

use crate::common::{fixture, lamina, stderr, TestResult};
use lamina::grow::buds::{
    grow, parse_program, program::FIGURE_8, read_program, skin, CellGraph, Form, GrowthOptions,
    SkinOptions,
};

fn options(cells: usize) -> GrowthOptions {
    GrowthOptions {
        max_cells: cells,
        verify: true,
        ..GrowthOptions::default()
    }
}

fn cells_of(form: &Form, rgb: [f32; 3]) -> usize {
    form.colour.iter().filter(|c| **c == rgb).count()
}

#[test]
fn figure_8_grows_a_blob_base_a_branching_stem_and_pods() -> TestResult {
    let program = parse_program(FIGURE_8, "Figure 8")?;
    // `verify` checks the cell graph after every division.
    let form = grow(&program, options(3000), 1)?;
    let r = &form.report;
    assert_eq!(r.cells, 3000);
    assert_eq!(r.stopped_by, "cap");
    assert_eq!(r.genus, 0);
    let by: Vec<(&str, usize)> = r
        .buds_by_type
        .iter()
        .map(|(n, k)| (n.as_str(), *k))
        .collect();
    assert_eq!(by[0], ("Base", 1));
    // The stem branches (each Stem makes two) and leaves pods.
    assert!(by[1].1 >= 7, "{by:?}");
    assert!(by[2].1 >= 3, "{by:?}");
    // Buds over time: one Base first, then more and more live buds.
    assert_eq!(r.timeline[0].live, 1);
    assert!(r.timeline.iter().map(|s| s.live).max().unwrap_or(0) >= 6);
    assert!(r.timeline.windows(2).all(|w| w[0].cells <= w[1].cells));
    // The blob base, the green stem and the red pods are all there.
    let yellow = [235.0 / 255.0, 200.0 / 255.0, 50.0 / 255.0];
    let green = [70.0 / 255.0, 150.0 / 255.0, 60.0 / 255.0];
    let red = [205.0 / 255.0, 45.0 / 255.0, 40.0 / 255.0];
    assert!(
        cells_of(&form, yellow) >= 200,
        "{}",
        cells_of(&form, yellow)
    );
    assert!(cells_of(&form, green) >= 200);
    assert!(cells_of(&form, red) >= 200);
    // Pods are made of larger cells.
    assert!(form.size.contains(&2.0) && form.size.contains(&1.3));
    Ok(())
}

#[test]
fn division_keeps_degrees_balanced_in_the_papers_program() -> TestResult {
    let program = parse_program(FIGURE_8, "Figure 8")?;
    let form = grow(
        &program,
        GrowthOptions {
            max_cells: 6000,
            ..GrowthOptions::default()
        },
        3,
    )?;
    let c = form.graph.check()?;
    assert!(c.min_degree >= 3 && c.max_degree <= 12, "{c:?}");
    let balanced = (0..form.graph.len() as u32)
        .filter(|&v| (5..=7).contains(&form.graph.degree(v)))
        .count();
    assert!(
        balanced as f64 >= 0.8 * form.graph.len() as f64,
        "{balanced} of {} cells have degree 5..7",
        form.graph.len()
    );
    // Euler: a sphere's mean degree is 6 − 12/V.
    let mean = 2.0 * c.edges as f64 / c.cells as f64;
    assert!((mean - (6.0 - 12.0 / c.cells as f64)).abs() < 1e-12);
    Ok(())
}

#[test]
fn every_operation_keeps_a_manifold_and_holes_add_genus() -> TestResult {
    let program = parse_program(
        "Base:
           blob 300
           hole
           create Arm 2
           blob 100
           hole
         Arm:
           head 1,0,0.5; fat 1; grow 40
           sleep 5
           split
           grow 30
           line
           hole
           grow 20",
        "mixed",
    )?;
    let form = grow(&program, options(1500), 11)?;
    let r = &form.report;
    assert!(r.holes >= 1, "{r:?}");
    assert_eq!(r.genus, r.holes);
    assert_eq!(form.graph.check()?.genus, r.holes);
    let (mesh, report) = skin(&form, &SkinOptions::default());
    let topology = mesh.check_manifold();
    assert!(topology.closed && topology.problems.is_empty());
    assert_eq!(topology.genus, Some(r.holes as i64));
    assert_eq!(report.self_intersections, 0);
    assert!(mesh.self_intersections().is_empty());
    Ok(())
}

#[test]
fn the_holes_fixture_makes_a_genus_of_its_holes() -> TestResult {
    let program = read_program(&fixture("buds/holes.bud"))?;
    let form = grow(&program, options(5000), 1)?;
    let r = &form.report;
    // A hole with no clear way through the form is refused, and counted.
    assert_eq!(r.holes + r.holes_refused, 2);
    assert!(r.holes >= 1, "{} refused", r.holes_refused);
    assert_eq!(r.genus, r.holes);
    Ok(())
}

#[test]
fn a_split_bud_grows_two_independent_branches() -> TestResult {
    let program = parse_program("A: blob 40\nsplit\nhead up, fat 0, grow 60", "split")?;
    let form = grow(&program, options(2000), 5)?;
    assert_eq!(form.report.buds_made, 2);
    assert_eq!(form.report.cells, 4 + 40 + 1 + 2 * 60);
    let [a, b] = [form.buds[0].cell, form.buds[1].cell];
    assert!(
        hops(&form.graph, a, b) >= 4,
        "the two branch tips grow apart"
    );
    Ok(())
}

#[test]
fn line_buds_keep_an_unbroken_line() -> TestResult {
    let program = parse_program(
        "Base: blob 80, create Edge 3\nEdge: line, fat 0, grow 100000",
        "line",
    )?;
    let form = grow(&program, options(1500), 2)?;
    let line: Vec<u32> = form
        .buds
        .iter()
        .filter(|b| b.kind == 1 && !b.dead)
        .map(|b| b.cell)
        .collect();
    assert!(line.len() > 3, "the line grew new buds: {}", line.len());
    // The cells holding Edge buds form one connected piece of the cell graph.
    let set: BTreeSet<u32> = line.iter().copied().collect();
    let mut seen = BTreeSet::from([line[0]]);
    let mut queue = VecDeque::from([line[0]]);
    while let Some(v) = queue.pop_front() {
        for &u in form.graph.neighbours(v) {
            if set.contains(&u) && seen.insert(u) {
                queue.push_back(u);
            }
        }
    }
    assert_eq!(seen.len(), set.len());
    Ok(())
}

#[test]
fn textures_become_geometry_without_self_intersection() -> TestResult {
    let program = parse_program(FIGURE_8, "Figure 8")?;
    let form = grow(
        &program,
        GrowthOptions {
            max_cells: 2500,
            ..GrowthOptions::default()
        },
        4,
    )?;
    let (flat, _) = skin(
        &form,
        &SkinOptions {
            textures: false,
            ..SkinOptions::default()
        },
    );
    let (rough, report) = skin(&form, &SkinOptions::default());
    assert!(
        report.textured_cells * 5 >= form.graph.len(),
        "{report:?} of {} cells",
        form.graph.len()
    );
    assert_eq!(report.self_intersections, 0);
    assert!(rough.self_intersections().is_empty());
    assert!(rough.triangles.len() > flat.triangles.len());
    let (f, r) = (flat.check_manifold(), rough.check_manifold());
    assert!(f.closed && r.closed && r.genus == Some(0));
    // Flat cells lie on the cell graph's triangles; bumps and spikes stand out of it.
    assert!(r.volume > f.volume, "{:?} {:?}", r.volume, f.volume);
    assert!(r.area > f.area * 1.1);
    Ok(())
}

#[test]
fn the_same_seed_gives_the_same_bytes_and_others_other_individuals() -> TestResult {
    let dir = tempfile::tempdir()?;
    let program = fixture("buds/figure8.bud");
    let run = |seed: &str, name: &str| -> Result<Vec<u8>, Box<dyn std::error::Error>> {
        let out = dir.path().join(name);
        let o = lamina(&[
            "buds",
            program.to_str().ok_or("path")?,
            "--cells",
            "800",
            "--seed",
            seed,
            "-o",
            out.to_str().ok_or("path")?,
        ]);
        if !o.status.success() {
            return Err(stderr(&o).into());
        }
        Ok(std::fs::read(out)?)
    };
    let a = run("7", "a.stl")?;
    assert_eq!(a, run("7", "b.stl")?);
    assert_ne!(a, run("8", "c.stl")?);
    Ok(())
}

#[test]
fn bad_programs_and_options_exit_2_without_output() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("form.stl");
    let out_s = out.to_str().ok_or("path")?;
    let bad = dir.path().join("bad.bud");
    std::fs::write(&bad, "Base:\n  blob 30\n  grwo 10\n")?;
    let bad_s = bad.to_str().ok_or("path")?;
    let o = lamina(&["buds", bad_s, "-o", out_s]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("bad.bud line 3, column 3: unknown command `grwo`"),
        "{}",
        stderr(&o)
    );
    std::fs::write(&bad, "Base: create Pod\n")?;
    let o = lamina(&["buds", bad_s, "-o", out_s]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("unknown bud type `Pod`"),
        "{}",
        stderr(&o)
    );
    let good = fixture("buds/figure8.bud");
    let good_s = good.to_str().ok_or("path")?;
    for args in [
        vec!["--cells", "3"],
        vec!["--clearance", "0"],
        vec!["--cell-mm", "-1"],
    ] {
        let mut all = vec!["buds", good_s, "-o", out_s];
        all.extend(args.iter());
        let o = lamina(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    let o = lamina(&["buds", "no-such.bud", "-o", out_s]);
    assert_eq!(o.status.code(), Some(2));
    let o = lamina(&[
        "buds",
        good_s,
        "-o",
        dir.path().join("form.ply").to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists(), "no output after an error");
    Ok(())
}

fn hops(g: &CellGraph, a: u32, b: u32) -> usize {
    let mut dist = vec![usize::MAX; g.len()];
    dist[a as usize] = 0;
    let mut queue = VecDeque::from([a]);
    while let Some(v) = queue.pop_front() {
        if v == b {
            return dist[v as usize];
        }
        for &u in g.neighbours(v) {
            if dist[u as usize] == usize::MAX {
                dist[u as usize] = dist[v as usize] + 1;
                queue.push_back(u);
            }
        }
    }
    usize::MAX
}

#[test]
fn frames_show_the_growth() -> TestResult {
    let dir = tempfile::tempdir()?;
    let frames = dir.path().join("frames");
    let png = dir.path().join("form.png");
    let program = fixture("buds/split.bud");
    let o = lamina(&[
        "buds",
        program.to_str().ok_or("path")?,
        "--png",
        png.to_str().ok_or("path")?,
        "--frames",
        frames.to_str().ok_or("path")?,
        "--every",
        "100",
        "--size",
        "200",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout)?;
    let cells = report["growth"]["cells"].as_u64().ok_or("cells")?;
    let written = std::fs::read_dir(&frames)?.count() as u64;
    assert_eq!(report["frames"].as_u64(), Some(written));
    assert!(written >= cells / 100, "{written} frames for {cells} cells");
    assert!(frames.join("frame-00001.png").exists() && png.exists());
    Ok(())
}

#[test]
fn a_refused_run_leaves_no_frames_folder() -> TestResult {
    let dir = tempfile::tempdir()?;
    let frames = dir.path().join("frames");
    let frames = frames.to_str().ok_or("path")?;
    let program = fixture("buds/split.bud");
    let program = program.to_str().ok_or("path")?;
    let form = dir.path().join("form.stl");
    let form = form.to_str().ok_or("path")?;
    let unwritable = dir.path().join("missing/form.stl");
    let unwritable = unwritable.to_str().ok_or("path")?;
    // Refused before growing (a cap below four cells, a render size of 0), and after growing
    // (the form cannot be written): the folder this run made is gone each time.
    for args in [
        vec!["--cells", "0", "-o", form],
        vec!["--size", "0", "-o", form],
        vec!["--cells", "200", "-o", unwritable],
    ] {
        let mut all = vec!["buds", program, "--frames", frames, "--every", "50"];
        all.extend(args);
        let o = lamina(&all);
        assert_eq!(o.status.code(), Some(2), "{all:?}: {}", stderr(&o));
        assert!(
            !std::path::Path::new(frames).exists(),
            "{all:?} left the frames folder"
        );
    }
    Ok(())
}
