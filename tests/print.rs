//! The print path end to end: `lamina solid` makes closed 2-manifolds with the network's genus
//! and repeatable bytes; `lamina slice` writes an SL1 archive whose layer images hold the
//! sections' areas, fills overlapping shells by the non-zero rule, reports Peele's figures, and
//! refuses open meshes and models that do not fit, leaving no output behind.

mod common;

use std::io::Read;
use std::path::Path;

use common::{fixture, lamina, run_ok, stderr, TestResult};
use glam::DVec3;
use lamina::mesh::io::{read_mesh, write_mesh};
use lamina::TriMesh;

/// An axis-aligned box from `lo` to `hi`, outward-wound.
fn cuboid(lo: DVec3, hi: DVec3) -> TriMesh {
    let c = |i: usize| {
        DVec3::new(
            if i & 1 == 1 { hi.x } else { lo.x },
            if i & 2 == 2 { hi.y } else { lo.y },
            if i & 4 == 4 { hi.z } else { lo.z },
        )
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut triangles = Vec::new();
    for q in quads {
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    }
    TriMesh {
        positions: (0..8).map(c).collect(),
        triangles,
        colors: None,
    }
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
    // Sits on z = 0, centred on the z axis.
    let bb = mesh.bbox();
    assert!(bb.min.z.abs() < 1e-6);
    assert!((bb.min.x + bb.max.x).abs() < 1e-6 && (bb.min.y + bb.max.y).abs() < 1e-6);
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
    assert!(stderr(&o).contains("does not fit"), "{}", stderr(&o));

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
