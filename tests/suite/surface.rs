//! Venation on surfaces (`lamina venation --surface`) and geodesic veins (`lamina veins`) end to
//! end on the fixture meshes: nodes on the surface (checked by brute force over every
//! triangle, not through the BVH the growth uses), Y and I joints only in closed venation,
//! geodesic veins as a tree of mesh edges reaching every source, density from vertex colours,
//! repeatable bytes and clear errors.

use std::collections::HashSet;
use std::path::Path;

use crate::common::{expected_frames, fixture, frame_names, lamina, stderr, stdout, TestResult};
use glam::DVec3;
use lamina::mesh::closest::closest_on_triangle;
use lamina::mesh::io::read_mesh;
use lamina::network::io::{read_network, ReadOptions};
use lamina::network::Network;
use lamina::TriMesh;

fn run_ok(args: &[&str]) -> Result<String, Box<dyn std::error::Error>> {
    let o = lamina(args);
    if !o.status.success() {
        return Err(format!("lamina {args:?} failed: {}", stderr(&o)).into());
    }
    Ok(stdout(&o))
}

fn read(path: &Path) -> Result<Network, Box<dyn std::error::Error>> {
    Ok(read_network(path, &ReadOptions::default())?.network)
}

/// The distance from p to the mesh, over every triangle.
fn brute_distance(mesh: &TriMesh, p: DVec3) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            closest_on_triangle(p, a, b, c).0.distance(p)
        })
        .fold(f64::INFINITY, f64::min)
}

fn degrees(net: &Network) -> Vec<usize> {
    let mut d = vec![0; net.nodes.len()];
    for e in &net.edges {
        d[e.a as usize] += 1;
        d[e.b as usize] += 1;
    }
    d
}

#[test]
fn venation_keeps_every_node_on_open_and_closed_surfaces() -> TestResult {
    let dir = tempfile::tempdir()?;
    for name in ["sphere", "torus", "calyx"] {
        let mesh = read_mesh(&fixture(&format!("surfaces/{name}.obj")))?;
        let size = mesh.bbox().diagonal();
        for mode in ["open", "closed"] {
            let out = dir.path().join(format!("{name}-{mode}.json"));
            let text = run_ok(&[
                "venation",
                "--surface",
                fixture(&format!("surfaces/{name}.obj"))
                    .to_str()
                    .ok_or("path")?,
                "--mode",
                mode,
                "--sources",
                "600",
                "--json",
                "-o",
                out.to_str().ok_or("path")?,
            ])?;
            let summary: serde_json::Value = serde_json::from_str(&text)?;
            let net = read(&out)?;
            assert!(
                net.nodes.len() > 300,
                "{name} {mode}: {} nodes",
                net.nodes.len()
            );
            // Every node on the surface, with a unit normal (checked on a sample of nodes: the
            // brute force is slow).
            let step = net.nodes.len() / 150 + 1;
            for (i, n) in net.nodes.iter().enumerate().step_by(step) {
                let d = brute_distance(&mesh, n.p);
                assert!(d <= 1e-6 * size, "{name} {mode}: node {i} is {d} mm off");
                let normal = n.normal.ok_or("a normal on every node")?;
                assert!((normal.length() - 1.0).abs() < 1e-9);
            }
            let q = &summary["quality"];
            assert_eq!(q["nodes_off_surface"], 0, "{name} {mode}");
            assert_eq!(q["crossings"], 0, "{name} {mode}");
            assert_eq!(q["components"], 1, "{name} {mode}");
            let left = summary["sources_left"].as_u64().ok_or("count")?;
            let placed = summary["sources_placed"].as_u64().ok_or("count")?;
            assert!(left * 50 < placed, "{name} {mode}: {left} of {placed} left");
            let max_degree = degrees(&net).into_iter().max().unwrap_or(0);
            assert!(
                max_degree <= 3,
                "{name} {mode}: a node of degree {max_degree}"
            );
            if mode == "closed" {
                assert!(q["loops"].as_u64().ok_or("loops")? > 20, "{name}: loops");
                assert_eq!(q["not_y_or_i"], 0);
            } else {
                assert_eq!(net.edges.len() + 1, net.nodes.len(), "{name}: a tree");
            }
        }
    }
    Ok(())
}

/// Vein length per mm² on the dark half (x < 100) and the light half of the density plate.
fn length_per_area(net: &Network) -> (f64, f64) {
    let (mut dark, mut light) = (0.0, 0.0);
    for e in &net.edges {
        let (a, b) = (net.nodes[e.a as usize].p, net.nodes[e.b as usize].p);
        if (a.x + b.x) / 2.0 < 100.0 {
            dark += a.distance(b);
        } else {
            light += a.distance(b);
        }
    }
    (dark / 10_000.0, light / 10_000.0)
}

#[test]
fn the_dark_half_carries_more_veins_per_area() -> TestResult {
    let dir = tempfile::tempdir()?;
    let plate = fixture("surfaces/density_halves.obj");
    let plate = plate.to_str().ok_or("path")?;
    let venation = dir.path().join("venation.json");
    run_ok(&[
        "venation",
        "--surface",
        plate,
        "--density-channel",
        "luminance",
        "--mode",
        "open",
        "--birth-min",
        "2",
        "--birth-max",
        "6",
        "--root",
        "0,50,0",
        "-o",
        venation.to_str().ok_or("path")?,
    ])?;
    let (dark, light) = length_per_area(&read(&venation)?);
    assert!(dark > 1.5 * light, "venation: {dark} vs {light} mm/mm²");
    let veins = dir.path().join("veins.json");
    run_ok(&[
        "veins",
        "--surface",
        plate,
        "--density-channel",
        "luminance",
        "--sources",
        "300",
        "-o",
        veins.to_str().ok_or("path")?,
    ])?;
    let (dark, light) = length_per_area(&read(&veins)?);
    assert!(dark > light, "geodesic veins: {dark} vs {light} mm/mm²");
    // Without the channel the halves are alike.
    run_ok(&[
        "venation",
        "--surface",
        plate,
        "--mode",
        "open",
        "--birth",
        "4",
        "--root",
        "0,50,0",
        "-o",
        venation.to_str().ok_or("path")?,
    ])?;
    let (dark, light) = length_per_area(&read(&venation)?);
    assert!(
        dark < 1.3 * light && light < 1.3 * dark,
        "uniform: {dark} vs {light}"
    );
    Ok(())
}

#[test]
fn geodesic_veins_are_a_tree_of_mesh_edges_reaching_every_source() -> TestResult {
    let dir = tempfile::tempdir()?;
    for name in ["sphere", "torus", "calyx"] {
        let path = fixture(&format!("surfaces/{name}.obj"));
        let mesh = read_mesh(&path)?;
        let mut mesh_edges: HashSet<(u32, u32)> = HashSet::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                mesh_edges.insert((a.min(b), a.max(b)));
            }
        }
        let vertex_of = |p: DVec3| mesh.positions.iter().position(|q| *q == p);
        let out = dir.path().join(format!("{name}.json"));
        let text = run_ok(&[
            "veins",
            "--surface",
            path.to_str().ok_or("path")?,
            "--sources",
            "200",
            "--json",
            "-o",
            out.to_str().ok_or("path")?,
        ])?;
        let summary: serde_json::Value = serde_json::from_str(&text)?;
        let net = read(&out)?;
        assert_eq!(net.edges.len() + 1, net.nodes.len(), "{name}: E = V - 1");
        let (_, components) = net.component_labels();
        assert_eq!(components, 1, "{name}: connected, so a tree");
        let ids: Vec<u32> = net
            .nodes
            .iter()
            .map(|n| vertex_of(n.p).map(|v| v as u32))
            .collect::<Option<_>>()
            .ok_or("every node is a mesh vertex")?;
        for e in &net.edges {
            let (a, b) = (ids[e.a as usize], ids[e.b as usize]);
            assert!(
                mesh_edges.contains(&(a.min(b), a.max(b))),
                "{name}: {a}-{b} is not a mesh edge"
            );
        }
        assert!(summary["sources"].as_u64().ok_or("count")? > 150);
        // Sources given by vertex: every one is on the tree.
        let given = ["5", "77", "310", "1000"];
        let mut args = vec![
            "veins",
            "--surface",
            path.to_str().ok_or("path")?,
            "-o",
            out.to_str().ok_or("path")?,
        ];
        for s in &given {
            args.extend(["--source", s]);
        }
        run_ok(&args)?;
        let net = read(&out)?;
        let on_tree: HashSet<usize> = net.nodes.iter().filter_map(|n| vertex_of(n.p)).collect();
        for s in given {
            assert!(
                on_tree.contains(&s.parse::<usize>()?),
                "{name}: source {s} reached"
            );
        }
        assert_eq!(net.edges.len() + 1, net.nodes.len());
    }
    Ok(())
}

#[test]
fn the_same_seed_gives_the_same_bytes_and_a_render() -> TestResult {
    let dir = tempfile::tempdir()?;
    let torus = fixture("surfaces/torus.obj");
    let torus = torus.to_str().ok_or("path")?;
    for (cmd, extra) in [("venation", "--mode"), ("veins", "--smooth")] {
        let value = if cmd == "venation" { "closed" } else { "3" };
        let mut bytes = Vec::new();
        for k in 0..2 {
            let out = dir.path().join(format!("{cmd}-{k}.json"));
            let png = dir.path().join(format!("{cmd}-{k}.png"));
            run_ok(&[
                cmd,
                "--surface",
                torus,
                extra,
                value,
                "--seed",
                "9",
                "-o",
                out.to_str().ok_or("path")?,
                "--png",
                png.to_str().ok_or("path")?,
                "--size",
                "300",
            ])?;
            bytes.push((std::fs::read(&out)?, std::fs::read(&png)?));
        }
        assert!(bytes[0] == bytes[1], "{cmd}: two runs differ");
        assert!(bytes[0].1.starts_with(b"\x89PNG"));
    }
    Ok(())
}

#[test]
fn frames_on_a_surface_show_the_growth_and_end_on_the_finished_render() -> TestResult {
    let dir = tempfile::tempdir()?;
    let frames = dir.path().join("frames");
    let out = dir.path().join("torus.json");
    let png = dir.path().join("torus.png");
    let json = run_ok(&[
        "venation",
        "--surface",
        fixture("surfaces/torus.obj").to_str().ok_or("path")?,
        "--frames",
        frames.to_str().ok_or("path")?,
        "--every",
        "20",
        "--frame-size",
        "240",
        "-o",
        out.to_str().ok_or("path")?,
        "--png",
        png.to_str().ok_or("path")?,
        "--size",
        "240",
        "--json",
    ])?;
    let v: serde_json::Value = serde_json::from_str(&json)?;
    let steps = v["iterations"].as_u64().ok_or("iterations")? as usize;
    assert_eq!(v["sources_left"].as_u64(), Some(0));
    let names = frame_names(&frames)?;
    assert_eq!(names, expected_frames(steps, 20));
    let frame = |n: &String| std::fs::read(frames.join(n));
    // Every frame differs from the one before (the veins grow), and with no source left the
    // last one is the render of the finished network.
    for pair in names.windows(2) {
        assert_ne!(
            frame(&pair[0])?,
            frame(&pair[1])?,
            "{} = {}",
            pair[0],
            pair[1]
        );
    }
    let last = names.last().ok_or("no frames")?;
    assert_eq!(frame(last)?, std::fs::read(&png)?);
    Ok(())
}

#[test]
fn bad_surface_input_exits_2_and_names_the_problem() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("v.json");
    let out_s = out.to_str().ok_or("path")?;
    let sphere = fixture("surfaces/sphere.obj");
    let sphere = sphere.to_str().ok_or("path")?;
    let frames = dir.path().join("frames");
    let frames = frames.to_str().ok_or("path")?;
    let cases: [(&[&str], &str); 9] = [
        (
            &["venation", "--surface", sphere, "--root", "999999"],
            "--root 999999",
        ),
        (
            &[
                "venation",
                "--surface",
                sphere,
                "--frames",
                frames,
                "--every",
                "0",
            ],
            "--every",
        ),
        (
            &[
                "venation",
                "--surface",
                sphere,
                "--frames",
                frames,
                "--frame-size",
                "4",
            ],
            "--frame-size: render size 4 px",
        ),
        (
            &["venation", "--surface", sphere, "--root", "t99999"],
            "triangles",
        ),
        (
            &["venation", "--surface", sphere, "--step", "50"],
            "mean edge length",
        ),
        (
            &["venation", "--surface", sphere, "--density-channel", "red"],
            "no vertex colours",
        ),
        (&["venation", "--surface", "/no/such.obj"], "/no/such.obj"),
        (
            &["veins", "--surface", sphere, "--source", "999999"],
            "--source 999999",
        ),
        (
            &["veins", "--surface", sphere, "--root", "999999"],
            "--root 999999",
        ),
    ];
    for (args, needle) in cases {
        let mut a = args.to_vec();
        a.extend(["-o", out_s]);
        let o = lamina(&a);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert!(!out.exists(), "{args:?} wrote output");
    }
    Ok(())
}
