//! `lamina lsystem` and `lamina bifurcate` end to end: the paper's counts and words from the
//! command line, mirror images, angle ranges and seeds, façade fitting (nothing outside the
//! boundary, one piece holding the root), projection onto a surface, and bad input refused
//! with exit 2 and no output.

use std::path::Path;

use crate::common::{lamina, run_ok, stderr, TestResult};
use glam::{DVec2, DVec3};
use lamina::grow::outline::Outline;
use lamina::mesh::io::write_mesh;
use lamina::mesh::TriMesh;
use lamina::network::io::{read_network, ReadOptions};
use lamina::network::Network;

const PAPER: [&str; 6] = ["--axiom", "X", "--rule", "X=F[-X]F[+X]-X", "--rule", "F=FF"];

fn args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec!["lsystem"];
    v.extend_from_slice(&PAPER);
    v.extend_from_slice(extra);
    v
}

fn read(path: &Path) -> Result<Network, Box<dyn std::error::Error>> {
    Ok(read_network(path, &ReadOptions::default())?.network)
}

#[test]
fn derive_only_prints_the_papers_counts_as_json() -> TestResult {
    let out = run_ok(&args(&[
        "--iterations",
        "7",
        "--angle",
        "22",
        "--derive-only",
        "--json",
    ]))?;
    let v: serde_json::Value = serde_json::from_str(&out)?;
    assert_eq!(v["symbols"], 13_956);
    assert_eq!(v["segments"], 4_118);
    assert_eq!(v["simplified_segments"], 2_186);
    let n1 = run_ok(&args(&["-n", "1", "--derive-only", "--string"]))?;
    assert_eq!(n1.trim(), "F[-X]F[+X]-X");
    let n2 = run_ok(&args(&["-n", "2", "--derive-only", "--string"]))?;
    let printed = "FF[-F[-X]F[+X]-X]FF[+F[-X]F[+X]-X]- F[X]F[+X]-X";
    assert_eq!(n2.trim(), printed.replace("- F[X]", "-F[-X]"));
    Ok(())
}

#[test]
fn a_grammar_file_gives_the_same_drawing_as_the_command_line() -> TestResult {
    let dir = tempfile::tempdir()?;
    let file = dir.path().join("tree.txt");
    std::fs::write(
        &file,
        "# Hanafin et al. 5.3\naxiom: X\nX -> F[-X]F[+X]-X\nF -> FF\niterations: 5\nangle: 22\n",
    )?;
    let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
    run_ok(&args(&["-n", "5", "-o", a.to_str().ok_or("path")?]))?;
    let f = file.to_str().ok_or("path")?;
    run_ok(&["lsystem", "--grammar", f, "-o", b.to_str().ok_or("path")?])?;
    assert_eq!(std::fs::read(&a)?, std::fs::read(&b)?);
    Ok(())
}

#[test]
fn swapping_plus_and_minus_mirrors_the_drawing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let (a, b) = (dir.path().join("a.json"), dir.path().join("b.json"));
    run_ok(&args(&["-n", "6", "-o", a.to_str().ok_or("path")?]))?;
    run_ok(&[
        "lsystem",
        "--axiom",
        "X",
        "--rule",
        "X=F[+X]F[-X]+X",
        "--rule",
        "F=FF",
        "-n",
        "6",
        "-o",
        b.to_str().ok_or("path")?,
    ])?;
    let (na, nb) = (read(&a)?, read(&b)?);
    assert_eq!(na.edges, nb.edges);
    for (p, q) in na.nodes.iter().zip(&nb.nodes) {
        assert_eq!((p.p.x, p.p.y), (-q.p.x, q.p.y));
    }
    Ok(())
}

#[test]
fn an_angle_range_repeats_by_seed_and_stays_in_range() -> TestResult {
    let dir = tempfile::tempdir()?;
    let run = |seed: &str,
               name: &str|
     -> Result<(Vec<u8>, serde_json::Value), Box<dyn std::error::Error>> {
        let p = dir.path().join(name);
        let out = run_ok(&args(&[
            "-n",
            "6",
            "--angle",
            "15..30",
            "--seed",
            seed,
            "-o",
            p.to_str().ok_or("path")?,
            "--json",
        ]))?;
        Ok((std::fs::read(&p)?, serde_json::from_str(&out)?))
    };
    let (a, ra) = run("3", "a.json")?;
    let (b, _) = run("3", "b.json")?;
    let (c, _) = run("4", "c.json")?;
    assert_eq!(a, b, "same seed, same bytes");
    assert_ne!(a, c);
    let (lo, hi) = (
        ra["lsystem"]["turn_min_deg"].as_f64().ok_or("min")?,
        ra["lsystem"]["turn_max_deg"].as_f64().ok_or("max")?,
    );
    assert!(15.0 <= lo && hi <= 30.0 && hi - lo > 10.0, "{lo}..{hi}");
    Ok(())
}

/// Every member inside the polygon (within `tol`), one connected piece, holding the root.
fn assert_fitted(net: &Network, boundary: &Outline, tol: f64) -> TestResult {
    let pts = boundary.points();
    let near = |p: DVec2| {
        (0..pts.len()).any(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
            let d = b - a;
            let u = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
            (a + d * u).distance(p) <= tol
        })
    };
    for e in &net.edges {
        let (p, q) = (
            net.nodes[e.a as usize].p.truncate(),
            net.nodes[e.b as usize].p.truncate(),
        );
        for k in 0..=8 {
            let x = p.lerp(q, k as f64 / 8.0);
            assert!(boundary.contains(x) || near(x), "{x} outside");
        }
    }
    let (labels, parts) = net.component_labels();
    assert_eq!(parts, 1);
    let root = net.meta.parameters["root_node"]
        .as_u64()
        .ok_or("root_node")? as usize;
    assert!(root < labels.len());
    assert!(net.validate().is_ok());
    Ok(())
}

#[test]
fn the_papers_tree_fits_a_twelve_by_four_metre_facade() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("facade.json");
    let o = out.to_str().ok_or("path")?;
    let report = run_ok(&args(&[
        "-n",
        "7",
        "--boundary",
        "rect:12000,4000",
        "--root-at=0,-12000",
        "-o",
        o,
        "--json",
    ]))?;
    let v: serde_json::Value = serde_json::from_str(&report)?;
    assert!(v["facade"]["root_on_boundary"].as_bool().ok_or("flag")?);
    let net = read(&out)?;
    let rect = Outline::new(vec![
        DVec2::new(-6000.0, 0.0),
        DVec2::new(6000.0, 0.0),
        DVec2::new(6000.0, 4000.0),
        DVec2::new(-6000.0, 4000.0),
    ])?;
    assert_fitted(&net, &rect, 1e-6)?;
    assert!(
        net.edges.len() > 300,
        "a section of the crown: {}",
        net.edges.len()
    );
    assert_eq!(v["quality"]["crossings"], 0, "crossing members are joined");
    Ok(())
}

#[test]
fn a_concave_boundary_from_a_file_and_a_random_bifurcation() -> TestResult {
    let dir = tempfile::tempdir()?;
    // An L-shaped façade, as a closed loop in our network JSON.
    let pts = [
        (-3000.0, 0.0),
        (3000.0, 0.0),
        (3000.0, 2000.0),
        (0.0, 2000.0),
        (0.0, 5000.0),
        (-3000.0, 5000.0),
    ];
    let nodes: Vec<String> = pts
        .iter()
        .map(|(x, y)| format!("{{\"p\":[{x},{y},0]}}"))
        .collect();
    let edges: Vec<String> = (0..pts.len())
        .map(|i| format!("{{\"a\":{i},\"b\":{}}}", (i + 1) % pts.len()))
        .collect();
    let file = dir.path().join("l.json");
    std::fs::write(
        &file,
        format!(
            "{{\"format\":\"lamina-network\",\"version\":1,\"nodes\":[{}],\"edges\":[{}]}}",
            nodes.join(","),
            edges.join(",")
        ),
    )?;
    let out = dir.path().join("tree.json");
    run_ok(&[
        "bifurcate",
        "--depth",
        "8",
        "--angle",
        "15..40",
        "--scale",
        "0.6..0.85",
        "--seed",
        "2",
        "--boundary",
        file.to_str().ok_or("path")?,
        "--root-at=-1500,0",
        "-o",
        out.to_str().ok_or("path")?,
    ])?;
    let net = read(&out)?;
    let l = Outline::new(pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect())?;
    assert_fitted(&net, &l, 1e-6)?;
    Ok(())
}

#[test]
fn projection_puts_every_node_on_the_surface() -> TestResult {
    let dir = tempfile::tempdir()?;
    // A barrel-vaulted wall: the 12 × 4 m façade bent about a vertical axis, 300 mm deep.
    let (nx, nz) = (48, 8);
    let wall = TriMesh::grid(nx, nz, |i, j| {
        let x = -6500.0 + 13000.0 * i as f64 / nx as f64;
        let z = -500.0 + 5000.0 * j as f64 / nz as f64;
        DVec3::new(x, 2000.0 + 300.0 * (1.0 - (x / 6500.0) * (x / 6500.0)), z)
    });
    let mesh = dir.path().join("wall.obj");
    write_mesh(&wall, &mesh, 0)?;
    let out = dir.path().join("onto.json");
    let report = run_ok(&args(&[
        "-n",
        "6",
        "--boundary",
        "rect:12000,4000",
        "--root-at=0,-6000",
        "--upright",
        "--onto",
        mesh.to_str().ok_or("path")?,
        "--sag",
        "1",
        "-o",
        out.to_str().ok_or("path")?,
        "--json",
    ]))?;
    let v: serde_json::Value = serde_json::from_str(&report)?;
    assert!(v["projection"]["added_nodes"].as_u64().ok_or("added")? > 0);
    let net = read(&out)?;
    for n in &net.nodes {
        let want = 2000.0 + 300.0 * (1.0 - (n.p.x / 6500.0).powi(2));
        // The mesh is a polyline across x: within its chord error of the exact vault.
        assert!((n.p.y - want).abs() < 1.0, "{} vs {want}", n.p.y);
        assert!(n.normal.is_some());
    }
    assert_eq!(net.component_labels().1, 1);
    Ok(())
}

#[test]
fn bad_input_exits_2_and_writes_nothing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("out.json");
    let o = out.to_str().ok_or("path")?;
    let missing = dir.path().join("missing.dxf");
    let m = missing.to_str().ok_or("path")?;
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "lsystem", "--axiom", "X", "--rule", "X=F[-X", "-n", "3", "-o", o,
            ],
            "--rule 1, column 4",
        ),
        (
            vec![
                "lsystem", "--axiom", "X", "--rule", "X F", "-n", "3", "-o", o,
            ],
            "not a production",
        ),
        (
            vec!["lsystem", "--axiom", "X", "--rule", "X=F", "-o", o],
            "--iterations",
        ),
        (
            vec!["lsystem", "--rule", "X=F", "-n", "2", "-o", o],
            "axiom",
        ),
        (args(&["-n", "20", "-o", o]), "--max-symbols"),
        (
            args(&["-n", "3", "--angle", "30..15", "-o", o]),
            "min ≤ max",
        ),
        (args(&["-n", "3", "--step=-1", "-o", o]), "--step"),
        (args(&["-n", "3", "--boundary", m, "-o", o]), "--boundary"),
        (
            args(&["-n", "3", "--boundary", "rect:0,5", "-o", o]),
            "positive",
        ),
        (
            args(&[
                "-n",
                "3",
                "--boundary",
                "rect:10,10",
                "--fit",
                "huge",
                "-o",
                o,
            ]),
            "--fit huge",
        ),
        (
            args(&["-n", "3", "--derive-only", "-o", o]),
            "--derive-only",
        ),
        (args(&["-n", "3", "-o", "/tmp/x.stl"]), ".json"),
        (
            vec!["lsystem", "--axiom", "X", "-n", "2", "-o", o],
            "draws nothing",
        ),
        (vec!["bifurcate", "--depth", "30", "-o", o], "--depth 30"),
        (vec!["bifurcate", "--scale", "0", "-o", o], "--scale"),
    ];
    for (argv, want) in cases {
        let r = lamina(&argv);
        assert_eq!(r.status.code(), Some(2), "{argv:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(want), "{argv:?}: {}", stderr(&r));
        assert!(!stderr(&r).contains("panicked"), "{argv:?}");
        assert!(!out.exists(), "{argv:?} left an output");
    }
    Ok(())
}
