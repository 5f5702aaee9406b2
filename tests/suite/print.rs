//! The print path end to end: `lamina solid` makes closed 2-manifolds with the network's genus
//! and repeatable bytes; `lamina slice` writes an SL1 archive whose layer images hold the
//! sections' areas, fills overlapping shells by the non-zero rule, reports Peele's figures, and
//! refuses open meshes and models that do not fit, leaving no output behind.

use crate::common;

use std::io::Read;
use std::path::Path;

use crate::common::{fixture, lamina, run_ok, stderr, TestResult};
use glam::DVec3;
use lamina::mesh::io::{read_mesh, write_mesh};
use lamina::TriMesh;

/// An axis-aligned box from `lo` to `hi`, outward-wound.
fn cuboid(lo: DVec3, hi: DVec3) -> TriMesh {
    TriMesh::cuboid(lo, hi)
}

fn json(path: &Path) -> Result<serde_json::Value, Box<dyn std::error::Error>> {
    Ok(serde_json::from_str(&std::fs::read_to_string(path)?)?)
}

#[test]
fn solid_of_a_looped_network_is_closed_with_genus_one_and_repeatable() -> TestResult {
    let dir = tempfile::tempdir()?;
    let (a, b) = (dir.path().join("a.stl"), dir.path().join("b.stl"));
    let report = dir.path().join("a.json");
    let net = fixture("networks/small_loop.json");
    let net = net.to_str().ok_or("path")?;
    for out in [&a, &b] {
        run_ok(&[
            "solid",
            net,
            "--cell",
            "0.15",
            "-o",
            out.to_str().ok_or("path")?,
            "--report",
            report.to_str().ok_or("path")?,
        ])?;
    }
    assert_eq!(
        std::fs::read(&a)?,
        std::fs::read(&b)?,
        "same input, same bytes"
    );
    let mesh = read_mesh(&a)?;
    let topo = mesh.check_manifold();
    assert!(topo.is_manifold() && topo.closed, "{:?}", topo.problems);
    assert_eq!((topo.components, topo.genus), (1, Some(1)));
    let r = json(&report)?;
    assert_eq!(r["genus"], 1);
    assert_eq!(r["network_cycles"], 1);
    // The exact solid sits on z = 0, centred on the z axis; the mesh's box is inside it by no
    // more than its chords cut (cell² / 8r: 9 µm here).
    let bb = mesh.bbox();
    assert!(bb.min.z.abs() < 0.01, "{bb:?}");
    assert!((bb.min.x + bb.max.x).abs() < 0.02 && (bb.min.y + bb.max.y).abs() < 0.02);
    Ok(())
}

#[test]
fn simplifying_gives_the_same_bytes_on_any_number_of_threads() -> TestResult {
    // Bricks are simplified on their own, each in one thread, and stitched in a fixed order.
    let dir = tempfile::tempdir()?;
    let net = fixture("networks/small_loop.json");
    let mut outs = Vec::new();
    for threads in ["1", "3"] {
        let out = dir.path().join(format!("t{threads}.stl"));
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_lamina"))
            .args([
                "solid",
                net.to_str().ok_or("path")?,
                "--cell",
                "0.05",
                "--tolerance",
            ])
            .arg("-o")
            .arg(&out)
            .env("RAYON_NUM_THREADS", threads)
            .output()?;
        assert!(o.status.success(), "{}", stderr(&o));
        outs.push(std::fs::read(&out)?);
    }
    assert!(outs[0].len() > 84);
    assert!(outs[0] == outs[1], "1 and 3 threads give different meshes");
    Ok(())
}

#[test]
fn simplifying_keeps_the_solid_closed_and_its_volume_with_far_fewer_triangles() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = fixture("networks/small_loop.json");
    let net = net.to_str().ok_or("path")?;
    let made_at = |cell: &str,
                   tolerance: Option<&str>,
                   name: &str|
     -> Result<(TriMesh, serde_json::Value), Box<dyn std::error::Error>> {
        let out = dir.path().join(format!("{name}.stl"));
        let report = dir.path().join(format!("{name}.json"));
        let mut args = vec![
            "solid",
            net,
            "--cell",
            cell,
            "-o",
            out.to_str().ok_or("path")?,
            "--report",
            report.to_str().ok_or("path")?,
        ];
        args.extend(tolerance);
        run_ok(&args)?;
        Ok((read_mesh(&out)?, json(&report)?))
    };
    let made = |tolerance: Option<&str>,
                name: &str|
     -> Result<(TriMesh, serde_json::Value), Box<dyn std::error::Error>> {
        made_at("0.1", tolerance, name)
    };
    let (full, rf) = made(Some("--full"), "full")?;
    let (simple, rs) = made(Some("--tolerance=0.025"), "simple")?;
    assert!(rf["simplified"].is_null());
    // The veins (0.3 mm and more) are four cells thick: the compact mesh is marched at twice
    // the cell. Cells split where veins come close only add triangles to what marching at that
    // grid makes.
    assert_eq!(rs["march_cell_mm"], 0.2);
    assert_eq!(rf["march_cell_mm"], 0.1);
    let (_, coarse) = made_at("0.2", Some("--full"), "coarse")?;
    let marched = rs["simplified"]["marched"].as_u64().ok_or("marched")?;
    assert!(marched >= coarse["triangles"].as_u64().ok_or("triangles")?);
    let topo = simple.check_manifold();
    assert!(topo.is_manifold() && topo.closed, "{:?}", topo.problems);
    assert_eq!((topo.components, topo.genus), (1, Some(1)));
    assert!(
        simple.triangles.len() * 10 <= full.triangles.len(),
        "{} triangles from {}",
        simple.triangles.len(),
        full.triangles.len()
    );
    // Both are fitted to the surface on average, not only within T of it: the volumes agree
    // to 0.1 % (a mesh with its corners on the surface and its chords under it, as simplified
    // meshes were, is 0.6 % smaller here).
    let (vf, vs) = (
        full.check_manifold().volume.ok_or("volume")?,
        topo.volume.ok_or("volume")?,
    );
    assert!((vf - vs).abs() <= 1e-3 * vf, "volume {vs} vs {vf}");
    let fitted = rs["simplified"]["fitted"].as_u64().ok_or("fitted")?;
    assert!(
        fitted as usize > simple.positions.len() / 2,
        "{fitted} fitted"
    );
    for bad in ["0", "-1", "NaN", "5"] {
        let flag = format!("--tolerance={bad}");
        let o = lamina(&[
            "solid",
            net,
            "--cell",
            "0.1",
            &flag,
            "-o",
            dir.path().join("bad.stl").to_str().ok_or("path")?,
        ]);
        assert_eq!(o.status.code(), Some(2), "--tolerance {bad}");
        assert!(stderr(&o).contains("--tolerance"), "{}", stderr(&o));
    }
    assert!(!dir.path().join("bad.stl").exists());
    Ok(())
}

/// `lamina solid NET ARGS… -o DIR/NAME.stl --report DIR/NAME.json`: the mesh and the report.
fn solid_of(
    dir: &std::path::Path,
    net: &str,
    extra: &[&str],
    name: &str,
) -> Result<(TriMesh, serde_json::Value), Box<dyn std::error::Error>> {
    let out = dir.join(format!("{name}.stl"));
    let report = dir.join(format!("{name}.json"));
    let mut args = vec![
        "solid",
        net,
        "-o",
        out.to_str().ok_or("path")?,
        "--report",
        report.to_str().ok_or("path")?,
    ];
    args.extend(extra);
    run_ok(&args)?;
    Ok((read_mesh(&out)?, json(&report)?))
}

#[test]
fn simplifying_keeps_gaps_between_veins_open() -> TestResult {
    // A hairpin whose arms are 5 to 60 µm apart and a vein 3 µm over both: marching on the
    // 35 µm grid bridges the gaps (genus 2 where the network has no cycle); with --tolerance
    // the cells there are split until nothing bridges them.
    let dir = tempfile::tempdir()?;
    let net = fixture("networks/near_miss.json");
    let net = net.to_str().ok_or("path")?;
    let (marched, rm) = solid_of(dir.path(), net, &["--full"], "marched")?;
    assert_eq!(
        marched.check_manifold().genus,
        Some(2),
        "marching alone bridges"
    );
    assert!(
        rm["warnings"].to_string().contains("touch"),
        "{}",
        rm["warnings"]
    );
    let (simple, rs) = solid_of(dir.path(), net, &["--tolerance"], "simple")?;
    let topo = simple.check_manifold();
    assert!(topo.is_manifold() && topo.closed, "{:?}", topo.problems);
    assert_eq!((topo.components, topo.genus), (1, Some(0)));
    assert!(
        rs["simplified"]["cells_split"]
            .as_u64()
            .ok_or("cells_split")?
            > 0
    );
    assert_eq!(rs["simplified"]["gaps_left"], 0);
    assert_eq!(rs["simplified"]["unheld"], 0);
    assert_eq!(
        rs["warnings"].as_array().map(Vec::len),
        Some(0),
        "{}",
        rs["warnings"]
    );
    Ok(())
}

#[test]
fn solid_refuses_what_it_cannot_build_and_writes_nothing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("x.stl");
    let bare = dir.path().join("bare.json");
    std::fs::write(
        &bare,
        r#"{"format":"lamina-network","version":1,"meta":{"units":"mm"},
            "nodes":[{"p":[0,0,0]},{"p":[5,0,0]}],"edges":[{"a":0,"b":1}]}"#,
    )?;
    let o = lamina(&[
        "solid",
        bare.to_str().ok_or("p")?,
        "-o",
        out.to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("edge 0 has no radius"),
        "{}",
        stderr(&o)
    );
    let o = lamina(&[
        "solid",
        fixture("networks/small_loop.json").to_str().ok_or("p")?,
        "--lamina",
        "0.3",
        "-o",
        out.to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("outline"), "{}", stderr(&o));
    let o = lamina(&[
        "solid",
        fixture("networks/small_loop.json").to_str().ok_or("p")?,
        "--base",
        "cone:3,4",
        "-o",
        out.to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("cylinder:DIAMETER,HEIGHT"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    Ok(())
}

#[test]
fn a_leaf_with_lamina_and_base_stands_up_as_one_part() -> TestResult {
    let dir = tempfile::tempdir()?;
    let leaf = dir.path().join("leaf.json");
    let stl = dir.path().join("leaf.stl");
    let report = dir.path().join("leaf.report.json");
    run_ok(&[
        "venation",
        "--birth",
        "4",
        "--tip-radius",
        "0.4",
        "-o",
        leaf.to_str().ok_or("p")?,
    ])?;
    run_ok(&[
        "solid",
        leaf.to_str().ok_or("p")?,
        "--fit",
        "12",
        "--lamina",
        "0.3",
        "--base",
        "cylinder:3,1",
        "--upright",
        "--cell",
        "0.08",
        // The marched mesh: simplified, this leaf takes ~40 s in a test build (its lamina's
        // proof is unit-tested in `simplify`; 10.7 s in release, BENCHMARKS.md).
        "--full",
        "-o",
        stl.to_str().ok_or("p")?,
        "--report",
        report.to_str().ok_or("p")?,
    ])?;
    let mesh = read_mesh(&stl)?;
    let topo = mesh.check_manifold();
    assert!(topo.is_manifold() && topo.closed);
    assert_eq!(topo.components, 1);
    let size = mesh.bbox().size();
    // Upright: tall in z (the leaf's 12 mm plus the base), thin in y.
    assert!(size.z > 12.0 && size.y < 4.0, "{size}");
    assert!((json(&report)?["scale"].as_f64().ok_or("scale")? - 12.0 / 98.7).abs() < 0.01);
    Ok(())
}

#[test]
fn slicing_reports_peele_figures_and_the_archive_holds_every_layer() -> TestResult {
    let dir = tempfile::tempdir()?;
    // 4 × 5 × 50 mm: 1 mL, 50 mm tall.
    let stl = dir.path().join("bar.stl");
    write_mesh(&cuboid(DVec3::ZERO, DVec3::new(4.0, 5.0, 50.0)), &stl, 256)?;
    let (a, b) = (dir.path().join("bar.sl1"), dir.path().join("again.sl1"));
    let report = dir.path().join("print.json");
    let layers = dir.path().join("layers");
    for out in [&a, &b] {
        run_ok(&[
            "slice",
            stl.to_str().ok_or("p")?,
            "--speed",
            "25",
            "-o",
            out.to_str().ok_or("p")?,
            "--report",
            report.to_str().ok_or("p")?,
            "--layers-dir",
            layers.to_str().ok_or("p")?,
        ])?;
    }
    let r = json(&report)?;
    assert_eq!(r["layers"], 1000);
    let ml = r["volume_ml"].as_f64().ok_or("volume")?;
    assert!((ml - 1.0).abs() < 1e-3, "{ml} mL");
    assert!((r["resin_cost"].as_f64().ok_or("cost")? - 0.055).abs() < 1e-4);
    assert!((r["build_time_h"].as_f64().ok_or("time")? - 2.0).abs() < 1e-9);
    // Same job, same bytes (apart from its own name inside).
    let names = |p: &Path| -> Result<Vec<String>, Box<dyn std::error::Error>> {
        let z = zip::ZipArchive::new(std::fs::File::open(p)?)?;
        let mut out = Vec::new();
        for name in z.file_names() {
            out.push(name?.into_owned());
        }
        Ok(out)
    };
    let mut za = zip::ZipArchive::new(std::fs::File::open(&a)?)?;
    let mut zb = zip::ZipArchive::new(std::fs::File::open(&b)?)?;
    let (mut la, mut lb) = (Vec::new(), Vec::new());
    za.by_name("bar00500.png")?.read_to_end(&mut la)?;
    zb.by_name("again00500.png")?.read_to_end(&mut lb)?;
    assert_eq!(la, lb);
    let n = names(&a)?;
    assert_eq!(n.iter().filter(|f| f.ends_with(".png")).count(), 1000);
    assert!(n.contains(&"config.ini".to_string()) && n.contains(&"prusaslicer.ini".to_string()));
    assert_eq!(std::fs::read_dir(&layers)?.count(), 1000);
    Ok(())
}

#[test]
fn overlapping_shells_print_as_their_union() -> TestResult {
    let dir = tempfile::tempdir()?;
    let mut two = cuboid(DVec3::ZERO, DVec3::new(6.0, 6.0, 1.0));
    let other = cuboid(DVec3::new(3.0, 3.0, 0.0), DVec3::new(9.0, 9.0, 1.0));
    two.triangles
        .extend(other.triangles.iter().map(|t| t.map(|i| i + 8)));
    two.positions.extend(other.positions);
    let stl = dir.path().join("two.stl");
    write_mesh(&two, &stl, 256)?;
    let report = dir.path().join("print.json");
    run_ok(&[
        "slice",
        stl.to_str().ok_or("p")?,
        "-o",
        dir.path().join("two.sl1").to_str().ok_or("p")?,
        "--report",
        report.to_str().ok_or("p")?,
    ])?;
    let r = json(&report)?;
    for a in r["layer_area_mm2"].as_array().ok_or("areas")? {
        let a = a.as_f64().ok_or("area")?;
        assert!((a - 63.0).abs() < 0.01, "layer area {a}, union is 63 mm²");
    }
    Ok(())
}

#[test]
fn a_model_a_hair_over_whole_layers_gets_no_empty_last_layer() -> TestResult {
    let dir = tempfile::tempdir()?;
    let stl = dir.path().join("block.stl");
    // 2 mm and 1.2 µm tall (dipping 1.2 µm below the plate, as a simplified mesh may): 40
    // layers of 0.05 mm, every one the block's full 25 mm² (a 41st would be blank).
    let block = cuboid(DVec3::new(0.0, 0.0, -0.0012), DVec3::new(5.0, 5.0, 2.0));
    write_mesh(&block, &stl, 256)?;
    let report = dir.path().join("print.json");
    run_ok(&[
        "slice",
        stl.to_str().ok_or("p")?,
        "-o",
        dir.path().join("job.sl1").to_str().ok_or("p")?,
        "--report",
        report.to_str().ok_or("p")?,
    ])?;
    let r = json(&report)?;
    let areas = r["layer_area_mm2"].as_array().ok_or("areas")?;
    assert_eq!(areas.len(), 40);
    for (i, a) in areas.iter().enumerate() {
        let a = a.as_f64().ok_or("area")?;
        assert!((a - 25.0).abs() < 0.05, "layer {i}: {a} mm²");
    }
    Ok(())
}

#[test]
fn slice_refuses_open_meshes_and_models_that_do_not_fit() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("job.sl1");
    let mut open = cuboid(DVec3::ZERO, DVec3::splat(5.0));
    open.triangles.pop();
    let open_stl = dir.path().join("open.stl");
    write_mesh(&open, &open_stl, 256)?;
    let o = lamina(&[
        "slice",
        open_stl.to_str().ok_or("p")?,
        "-o",
        out.to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a closed mesh"), "{}", stderr(&o));

    let big = dir.path().join("big.stl");
    write_mesh(&cuboid(DVec3::ZERO, DVec3::new(80.0, 50.0, 2.0)), &big, 256)?;
    let o = lamina(&[
        "slice",
        big.to_str().ok_or("p")?,
        "-o",
        out.to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    // 80 × 50 mm on 67.2 × 37.8 mm less a pixel each side: 37.73 / 50 straight, the factor
    // said; sliced at that scale it fits.
    let said = "scaled by 0.7546 or less it would (--scale)";
    assert!(
        stderr(&o).contains("does not fit") && stderr(&o).contains(said),
        "{}",
        stderr(&o)
    );
    run_ok(&[
        "slice",
        big.to_str().ok_or("p")?,
        "--scale",
        "0.7546",
        "-o",
        dir.path().join("scaled.sl1").to_str().ok_or("p")?,
    ])?;

    let bar = dir.path().join("bar.stl");
    write_mesh(&cuboid(DVec3::ZERO, DVec3::new(30.0, 10.0, 2.0)), &bar, 256)?;
    let o = lamina(&[
        "slice",
        bar.to_str().ok_or("p")?,
        "--copies",
        "12",
        "-o",
        out.to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("of 12 models fit"), "{}", stderr(&o));
    assert!(!out.exists(), "no partial archive");
    Ok(())
}

/// A 10 mm bar 2 mm above the plate on two 2 mm posts; with `hanging`, the second post stops
/// 1 mm above the plate.
fn bar_on_posts(hanging: bool) -> TriMesh {
    let parts = [
        cuboid(DVec3::new(0.0, 0.0, 2.0), DVec3::new(10.0, 2.0, 3.0)),
        cuboid(DVec3::new(0.0, 0.0, 0.0), DVec3::new(2.0, 2.0, 2.0)),
        cuboid(
            DVec3::new(8.0, 0.0, if hanging { 1.0 } else { 0.0 }),
            DVec3::new(10.0, 2.0, 2.0),
        ),
    ];
    let mut mesh = TriMesh {
        positions: Vec::new(),
        triangles: Vec::new(),
        colors: None,
    };
    for p in parts {
        let base = mesh.positions.len() as u32;
        mesh.triangles
            .extend(p.triangles.iter().map(|t| t.map(|i| i + base)));
        mesh.positions.extend(p.positions);
    }
    mesh
}

#[test]
fn a_post_that_stops_short_of_the_plate_starts_an_island() -> TestResult {
    let dir = tempfile::tempdir()?;
    for (hanging, expect) in [(false, 0), (true, 1)] {
        let stl = dir.path().join("bar.stl");
        write_mesh(&bar_on_posts(hanging), &stl, 256)?;
        let (sl1, report) = (dir.path().join("bar.sl1"), dir.path().join("print.json"));
        let o = lamina(&[
            "slice",
            stl.to_str().ok_or("p")?,
            "-o",
            sl1.to_str().ok_or("p")?,
            "--report",
            report.to_str().ok_or("p")?,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let r = json(&report)?;
        assert_eq!(r["island_count"], expect, "hanging {hanging}");
        if hanging {
            // The short post's foot at z = 1 mm: layer 20 is the first cut above it (1.025 mm).
            let i = &r["islands"][0];
            assert_eq!(i["layer"], 20);
            let area = i["area_mm2"].as_f64().ok_or("area")?;
            assert!((area - 4.0).abs() < 0.2, "the post's 2 × 2 mm: {area}");
            // Where they are listed, and what holds them.
            let said = common::stdout(&o);
            let listed = format!(
                "see \"islands\" in {}; --supports holds them",
                report.display()
            );
            assert!(
                said.contains("1 islands") && said.contains(&listed),
                "{said}"
            );
        }
        // Read back: the same islands, exit 1 when there are any.
        let o = lamina(&["sl1", "check", sl1.to_str().ok_or("p")?, "--json"]);
        assert_eq!(o.status.code(), Some(expect), "{}", stderr(&o));
        let c: serde_json::Value = serde_json::from_str(&common::stdout(&o))?;
        assert_eq!(c["islands"], r["islands"]);
        let (ours, theirs) = (
            c["volume_ml"].as_f64().ok_or("v")?,
            r["volume_ml"].as_f64().ok_or("v")?,
        );
        assert!(
            (ours - theirs).abs() <= 1e-12 * theirs,
            "{ours} vs {theirs}"
        );
    }
    Ok(())
}

#[test]
fn sl1_check_reads_prusaslicers_archive_and_refuses_what_is_no_sl1() -> TestResult {
    // Written by PrusaSlicer 2.5 (--export-sla, scripts/peers/dmp-sl.ini) from
    // fixtures/print/hanging_post.stl.
    let theirs = fixture("print/prusaslicer_hanging.sl1");
    let o = lamina(&["sl1", "check", theirs.to_str().ok_or("p")?, "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let c: serde_json::Value = serde_json::from_str(&common::stdout(&o))?;
    assert_eq!(c["layers"], 60);
    assert_eq!(c["config"]["layerHeight"], "0.05");
    assert_eq!(c["used_ml"], 0.032);
    assert_eq!(c["pixels"], serde_json::json!([1920, 1080]));
    assert_eq!(c["island_count"], 1);
    assert_eq!(c["islands"][0]["layer"], 20);
    let o = lamina(&[
        "sl1",
        "check",
        fixture("print/prusaslicer_bridge.sl1")
            .to_str()
            .ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stdout(&o));

    // Not an SL1: exit 2 naming the file and why.
    let dir = tempfile::tempdir()?;
    let stl = fixture("print/bridge.stl");
    let o = lamina(&["sl1", "check", stl.to_str().ok_or("p")?]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a zip"), "{}", stderr(&o));
    // A zip without config.ini, and one whose layer 3 is gone.
    let copy = |skip: &dyn Fn(&str) -> bool, out: &Path| -> TestResult {
        let mut src = zip::ZipArchive::new(std::fs::File::open(&theirs)?)?;
        let mut w = zip::ZipWriter::new(std::fs::File::create(out)?);
        for k in 0..src.len() {
            let mut e = src.by_index(k)?;
            let name = e.name()?.into_owned();
            if skip(&name) {
                continue;
            }
            let mut bytes = Vec::new();
            e.read_to_end(&mut bytes)?;
            w.start_file(name, zip::write::SimpleFileOptions::default())?;
            std::io::Write::write_all(&mut w, &bytes)?;
        }
        w.finish()?;
        Ok(())
    };
    let no_config = dir.path().join("no-config.sl1");
    copy(&|n| n == "config.ini", &no_config)?;
    let o = lamina(&["sl1", "check", no_config.to_str().ok_or("p")?]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no config.ini"), "{}", stderr(&o));
    let gap = dir.path().join("gap.sl1");
    copy(&|n| n == "hanging00003.png", &gap)?;
    let o = lamina(&["sl1", "check", gap.to_str().ok_or("p")?]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        common::stdout(&o).contains("1 of 60 layer images missing, the first hanging00003.png"),
        "{}",
        common::stdout(&o)
    );
    Ok(())
}

/// A network of one straight vein from `a` to `b`, radius `r` everywhere.
fn vein(
    dir: &Path,
    a: [f64; 3],
    b: [f64; 3],
    r: f64,
) -> Result<String, Box<dyn std::error::Error>> {
    let net = serde_json::json!({
        "format": "lamina-network", "version": 1, "meta": {"units": "mm", "parameters": {}},
        "nodes": [{"p": a, "radius": r}, {"p": b, "radius": r}],
        "edges": [{"a": 0, "b": 1, "radius": r}],
    });
    let path = dir.join("vein.json");
    std::fs::write(&path, net.to_string())?;
    Ok(path.to_str().ok_or("p")?.to_string())
}

#[test]
fn print_samples_the_true_sections_of_a_standing_vein_and_repeats_its_bytes() -> TestResult {
    let dir = tempfile::tempdir()?;
    // A vein standing 4 mm (balls of 0.3 mm at its ends): discs of 0.3 mm (8.6 pixels) along
    // it, spherical caps' sections at its ends.
    let net = vein(dir.path(), [0.0, 0.0, 0.0], [0.0, 0.0, 4.0], 0.3)?;
    let report = dir.path().join("print.json");
    let (a, b) = (dir.path().join("a.sl1"), dir.path().join("b.sl1"));
    for out in [&a, &b] {
        run_ok(&[
            "print",
            &net,
            "-o",
            out.to_str().ok_or("p")?,
            "--report",
            report.to_str().ok_or("p")?,
        ])?;
    }
    let r = json(&report)?;
    let areas = r["layer_area_mm2"].as_array().ok_or("areas")?;
    assert_eq!(areas.len(), 92, "4.6 mm at 0.05 mm");
    for (i, a) in areas.iter().enumerate() {
        let a = a.as_f64().ok_or("area")?;
        // The layer's middle height against the balls' centres at 0.3 and 4.3.
        let z = (i as f64 + 0.5) * 0.05;
        let off = (0.3 - z).max(z - 4.3).max(0.0);
        let want = std::f64::consts::PI * (0.09 - off * off);
        // Whole discs within 0.1 % (8-bit greys round); the small caps' sections within 1 %.
        let tol = if off == 0.0 { 1e-3 } else { 1e-2 };
        assert!(
            (a - want).abs() <= tol * want,
            "layer {i}: {a} mm², true {want}"
        );
    }
    assert_eq!(r["island_count"], 0);
    assert!(r["mesh_volume_ml"].is_null() && r["contour_volume_ml"].is_null());
    let layer = |p: &Path, name: &str| -> Result<Vec<u8>, Box<dyn std::error::Error>> {
        let mut z = zip::ZipArchive::new(std::fs::File::open(p)?)?;
        let mut out = Vec::new();
        z.by_name(name)?.read_to_end(&mut out)?;
        Ok(out)
    };
    assert_eq!(layer(&a, "a00050.png")?, layer(&b, "b00050.png")?);
    Ok(())
}

#[test]
fn print_sizes_a_network_to_the_display_and_says_so() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("job.sl1");
    let out_s = out.to_str().ok_or("p")?;
    let report = dir.path().join("print.json");
    let report_s = report.to_str().ok_or("p")?;
    // The display less a pixel at each side, mm.
    let (w, h) = (1920.0 * 0.035 - 0.07, 1080.0 * 0.035 - 0.07);

    // A vein 202 mm long (balls of 1 mm at its ends) lying flat: shrunk to the display's
    // width by default, and said.
    let long = vein(dir.path(), [0.0, 0.0, 0.0], [200.0, 0.0, 0.0], 1.0)?;
    let o = lamina(&["print", &long, "-o", out_s, "--report", report_s]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("too big for the display, scaled down to fit: × 0.3323"),
        "{}",
        stderr(&o)
    );
    let scale = json(&report)?["solid"]["scale"].as_f64().ok_or("scale")?;
    assert!((scale - w / 202.0).abs() < 1e-12, "scale {scale}");

    // As drawn on request: refused, naming the factor and the flags, nothing written.
    std::fs::remove_file(&out)?;
    let o = lamina(&["print", &long, "-o", out_s, "--fit", "keep"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("202.00 × 2.00 mm does not fit") && e.contains("scaled by 0.3323 or less"),
        "{e}"
    );
    assert!(
        e.contains("--fit auto") && e.matches("vein.json").count() == 1,
        "{e}"
    );
    assert!(!out.exists());

    // A vein 10.6 mm long fits as drawn, and `--fit auto` fills the display's width.
    let short = vein(dir.path(), [0.0, 0.0, 0.0], [10.0, 0.0, 0.0], 0.3)?;
    let o = lamina(&["print", &short, "-o", out_s, "--report", report_s]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("scaled"), "{}", stderr(&o));
    assert_eq!(json(&report)?["solid"]["scale"], 1.0);
    let o = lamina(&[
        "print", &short, "-o", out_s, "--report", report_s, "--fit", "auto",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("scaled to fill the display"),
        "{}",
        stderr(&o)
    );
    let scale = json(&report)?["solid"]["scale"].as_f64().ok_or("scale")?;
    assert!((scale - w / 10.6).abs() < 1e-12 && w / 10.6 < h / 0.6);

    // `solid` has no display to fit.
    let o = lamina(&["solid", &short, "-o", "x.stl", "--fit", "auto"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("only print sizes to its display"));

    // But it says when what it writes would not fit the printer, and the --fit that would;
    // at that fit it says nothing (`vein` writes vein.json: the long vein again, then the short).
    let long = vein(dir.path(), [0.0, 0.0, 0.0], [200.0, 0.0, 0.0], 1.0)?;
    let stl = dir.path().join("vein.stl");
    let stl_s = stl.to_str().ok_or("p")?;
    let coarse = ["--cell", "0.5", "--full", "-o", stl_s];
    let o = lamina(&[&["solid", &long][..], &coarse].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let e = stderr(&o);
    let note = "202.0 × 2.0 × 2.0 mm does not fit the DMP-SL printer (67.2 × 37.8 mm display, \
                100 mm tall): --fit ";
    let fit = e
        .split(note)
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .ok_or_else(|| format!("no note in: {e}"))?;
    let o = lamina(&[&["solid", &long, "--fit", fit][..], &coarse].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        !stderr(&o).contains("does not fit"),
        "--fit {fit}: {}",
        stderr(&o)
    );
    let short = vein(dir.path(), [0.0, 0.0, 0.0], [10.0, 0.0, 0.0], 0.3)?;
    let o = lamina(&[&["solid", &short][..], &coarse].concat());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("does not fit"), "{}", stderr(&o));
    Ok(())
}

#[test]
fn print_refuses_bad_flags_and_networks_leaving_nothing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = vein(dir.path(), [0.0, 0.0, 0.0], [0.0, 0.0, 4.0], 0.3)?;
    let out = dir.path().join("job.sl1");
    let out_s = out.to_str().ok_or("p")?;
    for (flags, says) in [
        (&["--layer", "0"][..], "--layer"),
        (&["--fit=-1"][..], "--fit"),
        (&["--fit", "NaN"][..], "--fit"),
        (&["--lamina", "0.3"][..], "outline"),
        (&["--copies", "0"][..], "--copies"),
        (&["--fit", "1e6"][..], "the printer builds at most"),
        // Bounded before anything is sized from it (it printed a 300-digit height).
        (
            &["--fit", "1e308"][..],
            "--fit 1e308 mm is more than 1000000 mm",
        ),
    ] {
        let mut args = vec!["print", &net, "-o", out_s];
        args.extend_from_slice(flags);
        let o = lamina(&args);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{flags:?}: {}", stderr(&o));
        assert!(!out.exists(), "{flags:?}: no partial archive");
    }
    let bare = dir.path().join("bare.json");
    std::fs::write(
        &bare,
        r#"{"format": "lamina-network", "version": 1, "nodes": [{"p": [0, 0, 0]}, {"p": [1, 0, 0]}],
            "edges": [{"a": 0, "b": 1}]}"#,
    )?;
    let o = lamina(&["print", bare.to_str().ok_or("p")?, "-o", out_s]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("bare.json") && stderr(&o).contains("no radius"));
    assert!(!out.exists());
    Ok(())
}

#[test]
fn supports_hold_a_floating_vein_on_the_one_below_and_leave_no_island() -> TestResult {
    let dir = tempfile::tempdir()?;
    // A vein on the plate and a second one floating 3 mm above it, crossing it.
    let net = serde_json::json!({
        "format": "lamina-network", "version": 1, "meta": {"units": "mm", "parameters": {}},
        "nodes": [{"p": [0.0, 0.0, 0.0], "radius": 0.4}, {"p": [6.0, 0.0, 0.0], "radius": 0.4},
                  {"p": [3.0, -3.0, 3.0], "radius": 0.3}, {"p": [3.0, 3.0, 3.0], "radius": 0.3}],
        "edges": [{"a": 0, "b": 1, "radius": 0.4}, {"a": 2, "b": 3, "radius": 0.3}],
    });
    let path = dir.path().join("two.json");
    std::fs::write(&path, net.to_string())?;
    let path = path.to_str().ok_or("p")?;
    let report = dir.path().join("print.json");
    let report_s = report.to_str().ok_or("p")?;
    let job = dir.path().join("job.sl1");
    let job_s = job.to_str().ok_or("p")?;
    run_ok(&["print", path, "-o", job_s, "--report", report_s])?;
    let r = json(&report)?;
    assert_eq!(
        r["island_count"], 1,
        "the floating vein starts in free resin"
    );
    run_ok(&[
        "print",
        path,
        "-o",
        job_s,
        "--report",
        report_s,
        "--supports",
    ])?;
    let r = json(&report)?;
    assert_eq!(r["island_count"], 0);
    let s = &r["supports"];
    assert_eq!(
        (s["islands"].as_u64(), s["islands_left"].as_u64()),
        (Some(1), Some(0))
    );
    assert_eq!(s["to_model"], 1, "the vein below is right under the island");
    assert!(s["support_ml"].as_f64().ok_or("ml")? > 0.0);
    // The same supports in the mesh: one closed 2-manifold shell.
    let stl = dir.path().join("two.stl");
    run_ok(&[
        "solid",
        path,
        "--cell",
        "0.05",
        "--supports",
        "-o",
        stl.to_str().ok_or("p")?,
    ])?;
    let mesh = read_mesh(&stl)?;
    let topo = mesh.check_manifold();
    assert!(topo.is_manifold() && topo.closed);
    assert_eq!(topo.components, 1, "the supports join the two veins");
    // A tolerance an eighth of the grid: the finishing steps left two pairs of vertices on one
    // point where the pillars stand on their discs, and the mesh was refused; now pushed apart.
    run_ok(&[
        "solid",
        path,
        "--cell",
        "0.1",
        "--tolerance",
        "0.0125",
        "--supports",
        "-o",
        stl.to_str().ok_or("p")?,
    ])?;
    let topo = read_mesh(&stl)?.check_manifold();
    assert!(topo.is_manifold() && topo.closed && topo.components == 1);
    Ok(())
}

#[test]
fn supports_stand_on_the_plate_and_leave_the_parts_lit_pixels_as_they_are() -> TestResult {
    // A vein on the plate and one floating beside it, crossing nothing: at 3 mm it is held by
    // a tip, a pillar and a base; at 0.6 mm (its underside 0.3 mm up) a pillar on a base would
    // reach into the plate (and lift the whole print by that when placed, as it once did), so
    // pins as thin as the tip hold it.
    let dir = tempfile::tempdir()?;
    for (height, pins) in [(3.0, false), (0.6, true)] {
        let net = serde_json::json!({
            "format": "lamina-network", "version": 1, "meta": {"units": "mm", "parameters": {}},
            "nodes": [{"p": [0.0, 0.0, 0.0], "radius": 0.4}, {"p": [6.0, 0.0, 0.0], "radius": 0.4},
                      {"p": [10.0, -3.0, height], "radius": 0.3},
                      {"p": [10.0, 3.0, height], "radius": 0.3}],
            "edges": [{"a": 0, "b": 1, "radius": 0.4}, {"a": 2, "b": 3, "radius": 0.3}],
        });
        let path = dir.path().join("two.json");
        std::fs::write(&path, net.to_string())?;
        let [(bare_sl1, bare), (held_sl1, held)] = &bare_and_held(dir.path(), "print", &path)?;
        assert_eq!(bare["island_count"], 1, "at {height} mm");
        assert_eq!(held["island_count"], 0, "at {height} mm");
        // The floating vein's first layer is a strip 6 mm long: held at points about 2.5 mm
        // apart, each by a pin when it is too low for pillars.
        let (tips, pinned) = (&held["supports"]["tips"], &held["supports"]["pins"]);
        assert!(
            tips.as_u64().ok_or("tips")? >= 2,
            "at {height} mm: {tips} tips"
        );
        let want = if pins {
            tips.clone()
        } else {
            serde_json::json!(0)
        };
        assert_eq!(pinned, &want, "at {height} mm");
        assert_eq!(
            held["layers"], bare["layers"],
            "at {height} mm: nothing lifted"
        );
        let (lit, changed, added) = compare_lit(bare_sl1, bare, held_sl1, held)?;
        assert!(lit > 1000, "at {height} mm: {lit} lit pixels");
        assert_eq!(
            changed, 0,
            "at {height} mm: {changed} of {lit} lit part pixels changed"
        );
        assert!(added > 0, "at {height} mm: the supports are in the layers");
    }
    Ok(())
}

/// `command INPUT` run into `dir` without and with `--supports`: each archive and report.
fn bare_and_held(
    dir: &Path,
    command: &str,
    input: &Path,
) -> Result<[(std::path::PathBuf, serde_json::Value); 2], Box<dyn std::error::Error>> {
    let run = |name: &str, extra: Option<&str>| -> Result<_, Box<dyn std::error::Error>> {
        let sl1 = dir.join(format!("{name}.sl1"));
        let report = dir.join(format!("{name}.json"));
        let mut args = vec![
            command,
            input.to_str().ok_or("p")?,
            "-o",
            sl1.to_str().ok_or("p")?,
            "--report",
            report.to_str().ok_or("p")?,
        ];
        args.extend(extra);
        run_ok(&args)?;
        let report = json(&report)?;
        Ok((sl1, report))
    };
    Ok([run("bare", None)?, run("held", Some("--supports"))?])
}

/// Pixels the part lights without supports (grey ≥ 128), how many of them have another grey
/// with supports, and how many pixels the supports brighten: the two prints lined up by their
/// placements, which must be a whole number of pixels apart. Layer images are named by each
/// archive's stem.
fn compare_lit(
    bare_sl1: &Path,
    bare: &serde_json::Value,
    held_sl1: &Path,
    held: &serde_json::Value,
) -> Result<(usize, usize, usize), Box<dyn std::error::Error>> {
    let pixel = bare["printer"]["pixel_mm"].as_f64().ok_or("pixel")?;
    let offset = |r: &serde_json::Value, k: usize| r["placements"][0]["offset"][k].as_f64();
    let dx = (offset(held, 0).ok_or("x")? - offset(bare, 0).ok_or("x")?) / pixel;
    let dy = (offset(held, 1).ok_or("y")? - offset(bare, 1).ok_or("y")?) / pixel;
    assert!((dx - dx.round()).abs() < 1e-6 && (dy - dy.round()).abs() < 1e-6);
    let (dx, dy) = (dx.round() as isize, dy.round() as isize);
    assert_eq!(held["layers"], bare["layers"], "nothing lifted");
    let layers = bare["layers"].as_u64().ok_or("layers")? as usize;
    let stem = |p: &Path| -> Result<String, Box<dyn std::error::Error>> {
        Ok(p.file_stem()
            .and_then(|s| s.to_str())
            .ok_or("stem")?
            .to_string())
    };
    let (bare_name, held_name) = (stem(bare_sl1)?, stem(held_sl1)?);
    let (mut lit, mut changed, mut added) = (0, 0, 0);
    for i in 0..layers {
        let (a, w) = layer_grey(bare_sl1, &format!("{bare_name}{i:05}.png"))?;
        let (b, _) = layer_grey(held_sl1, &format!("{held_name}{i:05}.png"))?;
        let h = a.len() / w;
        for r in 0..h {
            for c in 0..w {
                let (rb, cb) = (r as isize - dy, c as isize + dx);
                let other = if (0..h as isize).contains(&rb) && (0..w as isize).contains(&cb) {
                    b[rb as usize * w + cb as usize]
                } else {
                    0
                };
                if a[r * w + c] >= 128 {
                    lit += 1;
                    changed += usize::from(other != a[r * w + c]);
                } else if other > a[r * w + c] {
                    added += 1;
                }
            }
        }
    }
    Ok((lit, changed, added))
}

#[test]
fn slice_supports_any_closed_mesh_and_leaves_its_lit_pixels_as_they_are() -> TestResult {
    // Meshes lamina did not make: manifold3d's overhang piece (a rod hanging from an arm to a
    // point, a ball floating beside the post: two islands, each held by a pillar landing on the
    // base block) and two cubes touching along an edge (the upper cube's 10 x 10 mm underside
    // is one island, held at several points about 2.5 mm apart, its pillars joined to the
    // plate).
    let dir = tempfile::tempdir()?;
    for (mesh, islands, at_least_tips, landings) in [
        ("print/manifold_overhang.stl", 2, 2, 2),
        ("surfaces/touching_cubes.stl", 1, 9, 0),
    ] {
        let stl = fixture(mesh);
        let [(bare_sl1, bare), (held_sl1, held)] = &bare_and_held(dir.path(), "slice", &stl)?;
        assert_eq!(bare["island_count"], islands, "{mesh}");
        assert_eq!(held["island_count"], 0, "{mesh}");
        let s = &held["supports"];
        assert_eq!(s["islands"], islands, "{mesh}");
        assert_eq!(s["islands_left"], 0, "{mesh}");
        assert_eq!(s["to_model"], landings, "{mesh}");
        assert!(
            s["tips"].as_u64().ok_or("tips")? >= at_least_tips,
            "{mesh}: {s}"
        );
        assert!(s["support_ml"].as_f64().ok_or("ml")? > 0.0, "{mesh}");
        let (lit, changed, added) = compare_lit(bare_sl1, bare, held_sl1, held)?;
        assert!(lit > 10_000, "{mesh}: {lit} lit pixels");
        assert_eq!(
            changed, 0,
            "{mesh}: {changed} of {lit} lit part pixels changed"
        );
        assert!(added > 0, "{mesh}: the supports are in the layers");
    }
    // An open mesh is refused before any planning, naming the file.
    let open = fixture("surfaces/colored_patch.obj");
    let out = dir.path().join("open.sl1");
    let o = lamina(&[
        "slice",
        open.to_str().ok_or("p")?,
        "--supports",
        "-o",
        out.to_str().ok_or("p")?,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("colored_patch.obj"), "{}", stderr(&o));
    assert!(!out.exists());
    // A mesh too large for the printer is refused as the bare slice refuses it, with the scale
    // that would fit, before supports are planned for it.
    let big = fixture("surfaces/touching_cubes.stl");
    let refusals = [&[][..], &["--supports"][..]].map(|more| {
        let mut args = vec!["slice", big.to_str().unwrap_or("?"), "--scale", "12", "-o"];
        args.push(out.to_str().unwrap_or("?"));
        args.extend(more);
        lamina(&args)
    });
    for o in &refusals {
        assert_eq!(o.status.code(), Some(2), "{}", stderr(o));
        assert!(
            stderr(o).contains("or less it would (--scale)"),
            "{}",
            stderr(o)
        );
    }
    assert_eq!(stderr(&refusals[0]), stderr(&refusals[1]));
    assert!(!out.exists());
    Ok(())
}

/// The grey bytes of layer image `name` in an SL1 archive.
fn layer_grey(sl1: &Path, name: &str) -> Result<(Vec<u8>, usize), Box<dyn std::error::Error>> {
    let mut z = zip::ZipArchive::new(std::fs::File::open(sl1)?)?;
    let mut bytes = Vec::new();
    z.by_name(name)?.read_to_end(&mut bytes)?;
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info()?;
    let mut grey = vec![0; reader.output_buffer_size().ok_or("png size")?];
    let info = reader.next_frame(&mut grey)?;
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Eight {
        return Err(format!("{name}: not 8-bit grey").into());
    }
    grey.truncate(info.buffer_size());
    Ok((grey, info.width as usize))
}

#[test]
fn print_follows_edges_that_bend_and_meet_within_a_pixel() -> TestResult {
    // Three veins of radius 0.1 mm (2.9 pixels) lying flat and meeting at the origin, cut by
    // layers near their tops and bottoms too: sections whose edges meet at the junction and
    // pixels across which the distance is not monotone (a vein's axis between their sides).
    let dir = tempfile::tempdir()?;
    let r = 0.1;
    let arms: Vec<[f64; 3]> = [10.0f64, 137.0, 251.0]
        .iter()
        .map(|deg| [deg.to_radians().cos(), deg.to_radians().sin(), 0.0])
        .collect();
    let mut nodes = vec![serde_json::json!({"p": [0.0, 0.0, 0.0], "radius": r})];
    let mut edges = Vec::new();
    for (k, a) in arms.iter().enumerate() {
        nodes.push(serde_json::json!({"p": a, "radius": r}));
        edges.push(serde_json::json!({"a": 0, "b": k + 1, "radius": r}));
    }
    let net = dir.path().join("star.json");
    std::fs::write(
        &net,
        serde_json::json!({
            "format": "lamina-network", "version": 1, "meta": {"units": "mm", "parameters": {}},
            "nodes": nodes, "edges": edges,
        })
        .to_string(),
    )?;
    let (sl1, report) = (dir.path().join("star.sl1"), dir.path().join("print.json"));
    run_ok(&[
        "print",
        net.to_str().ok_or("p")?,
        "-o",
        sl1.to_str().ok_or("p")?,
        "--report",
        report.to_str().ok_or("p")?,
    ])?;
    let r_json = json(&report)?;
    let px = r_json["printer"]["pixel_mm"].as_f64().ok_or("pixel")?;
    let lh = r_json["printer"]["layer_mm"].as_f64().ok_or("layer")?;
    let rows = r_json["printer"]["pixels_y"].as_u64().ok_or("rows")? as f64;
    let off = &r_json["placements"][0]["offset"];
    let off = [0, 1, 2].map(|k| off[k].as_f64().unwrap_or(f64::NAN));
    // Placed as print places it: the balls' box centred on the z axis, lowest point at z = 0.
    let ends = arms.iter().chain([[0.0; 3]].iter());
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in ends {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k] - r);
            hi[k] = hi[k].max(p[k] + r);
        }
    }
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let dist = |x: f64, y: f64, z: f64| {
        arms.iter()
            .map(|a| {
                let t = ((x * a[0] + y * a[1]) / (a[0] * a[0] + a[1] * a[1])).clamp(0.0, 1.0);
                let (dx, dy) = (x - t * a[0], y - t * a[1]);
                (dx * dx + dy * dy + z * z).sqrt() - r
            })
            .fold(f64::INFINITY, f64::min)
    };
    // Each pixel's true coverage at 987 points of a Fibonacci lattice.
    let (n, step) = (987usize, 610usize);
    let layers = r_json["layers"].as_u64().ok_or("layers")? as usize;
    assert_eq!(layers, 4, "0.2 mm at 0.05 mm");
    for i in 0..layers {
        let (image, width) = layer_grey(&sl1, &format!("star{i:05}.png"))?;
        let z = (i as f64 + 0.5) * lh - off[2] - r;
        let (mut both, mut either, mut worst) = (0.0, 0.0, (0.0f64, 0usize));
        for (k, &g) in image.iter().enumerate() {
            let (row, col) = ((k / width) as f64, (k % width) as f64);
            let x = (col + 0.5) * px - off[0] + centre[0];
            let y = (rows - row - 0.5) * px - off[1] + centre[1];
            let d = dist(x, y, z);
            let truth = if d >= px {
                0.0
            } else if d <= -px {
                1.0
            } else {
                let inside = (0..n)
                    .filter(|&j| {
                        let u = (j as f64 + 0.5) / n as f64 - 0.5;
                        let v = ((j * step) % n) as f64 / n as f64 + 0.5 / n as f64 - 0.5;
                        dist(x + u * px, y + v * px, z) < 0.0
                    })
                    .count();
                inside as f64 / n as f64
            };
            let grey = g as f64 / 255.0;
            both += grey.min(truth);
            either += grey.max(truth);
            if (grey - truth).abs() > worst.0 {
                worst = ((grey - truth).abs(), k);
            }
        }
        let iou = both / either;
        // Nearly every lit pixel of these thin sections is an edge pixel, whose 8-bit grey alone
        // is up to half a level off: that costs about 0.001 of the IoU.
        assert!(
            iou >= 0.998,
            "layer {i}: grey IoU {iou:.5} with the true section"
        );
        // A pixel more than 4 grey levels off is an edge followed wrongly, not rounding (a
        // straight edge across the whole pixel was 9 levels off at the junction).
        assert!(
            worst.0 <= 4.0 / 255.0,
            "layer {i}: pixel {} is {:.3} off its true coverage",
            worst.1,
            worst.0
        );
    }
    Ok(())
}
