//! Format round trips: JSON -> DXF -> OBJ -> JSON keeps topology and coordinates (1e-9 mm), and
//! STL written by lamina keeps the volume of the original.

use crate::common::{assert_same_topology, fixture, TestResult};
use glam::DVec3;
use lamina::mesh::io::{read_mesh, write_mesh};
use lamina::network::io::{read_network, write_network, ReadOptions, RenderOptions};
use lamina::network::{Edge, Network, Node};
use proptest::prelude::*;

fn roundtrip_json_dxf_obj_json(net: &Network) -> Result<Network, Box<dyn std::error::Error>> {
    let dir = tempfile::tempdir()?;
    let (json, dxf, obj, back) = (
        dir.path().join("a.json"),
        dir.path().join("b.dxf"),
        dir.path().join("c.obj"),
        dir.path().join("d.json"),
    );
    let opts = ReadOptions::default();
    let render = RenderOptions::default();
    write_network(net, &json, &render)?;
    let n1 = read_network(&json, &opts)?.network;
    write_network(&n1, &dxf, &render)?;
    let n2 = read_network(&dxf, &opts)?.network;
    write_network(&n2, &obj, &render)?;
    let n3 = read_network(&obj, &opts)?.network;
    write_network(&n3, &back, &render)?;
    Ok(read_network(&back, &opts)?.network)
}

#[test]
fn fixture_network_survives_json_dxf_obj_json() -> TestResult {
    let net = read_network(
        &fixture("networks/ezdxf_veins.dxf"),
        &ReadOptions::default(),
    )?
    .network;
    let back = roundtrip_json_dxf_obj_json(&net)?;
    assert_same_topology(&net, &back, 1e-9);
    Ok(())
}

#[test]
fn json_roundtrip_is_exact_and_keeps_meta() -> TestResult {
    let mut net = Network {
        nodes: vec![
            Node {
                p: DVec3::new(0.1, 1.0 / 3.0, -2e-7),
                normal: Some(DVec3::Z),
                radius: 0.25,
            },
            Node::at(DVec3::new(1e6, 2.5, 3.0)),
        ],
        edges: vec![Edge {
            a: 0,
            b: 1,
            radius: 0.125,
        }],
        ..Default::default()
    };
    net.meta.generator = Some("test".into());
    net.meta.seed = Some(42);
    net.meta
        .parameters
        .insert("d".into(), serde_json::json!(0.5));
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("n.json");
    write_network(&net, &path, &RenderOptions::default())?;
    let back = read_network(&path, &ReadOptions::default())?.network;
    assert_eq!(back, net);
    Ok(())
}

#[test]
fn writing_twice_gives_identical_bytes() -> TestResult {
    let net = read_network(
        &fixture("networks/ezdxf_veins.dxf"),
        &ReadOptions::default(),
    )?
    .network;
    let dir = tempfile::tempdir()?;
    for ext in ["json", "obj", "dxf", "svg", "png"] {
        let (a, b) = (
            dir.path().join(format!("a.{ext}")),
            dir.path().join(format!("b.{ext}")),
        );
        write_network(&net, &a, &RenderOptions { size: 256 })?;
        write_network(&net, &b, &RenderOptions { size: 256 })?;
        assert_eq!(
            std::fs::read(&a)?,
            std::fs::read(&b)?,
            "{ext} output differs"
        );
    }
    Ok(())
}

#[test]
fn openscad_stl_written_back_keeps_volume_and_topology() -> TestResult {
    let original = read_mesh(&fixture("surfaces/openscad_part.stl"))?;
    let t0 = original.check_manifold();
    assert!(t0.closed && t0.is_manifold(), "{:?}", t0.problems);
    assert_eq!(t0.genus, Some(1));
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("part.stl");
    write_mesh(&original, &out, 512)?;
    let back = read_mesh(&out)?;
    let t1 = back.check_manifold();
    let (v0, v1) = (t0.volume.unwrap_or(0.0), t1.volume.unwrap_or(f64::NAN));
    assert!(((v1 - v0) / v0).abs() < 1e-6, "volume {v0} became {v1}");
    assert_eq!(
        (t0.vertices, t0.edges, t0.faces),
        (t1.vertices, t1.edges, t1.faces)
    );
    Ok(())
}

#[test]
fn calyx_surface_is_an_open_genus_zero_band() -> TestResult {
    let m = read_mesh(&fixture("surfaces/calyx.obj"))?;
    let t = m.check_manifold();
    assert!(t.is_manifold(), "{:?}", t.problems);
    assert_eq!(t.faces, 5000);
    assert_eq!(t.boundary_loops, 2);
    assert_eq!(t.euler, 0);
    assert_eq!(t.genus, Some(0));
    let size = m.bbox().size();
    assert!((size.z - 2000.0).abs() < 1e-9, "about 2 m tall: {size}");
    Ok(())
}

#[test]
fn obj_vertex_colours_survive_a_roundtrip() -> TestResult {
    let m = read_mesh(&fixture("surfaces/colored_patch.obj"))?;
    let colors = m.colors.clone().ok_or("the fixture has vertex colours")?;
    assert_eq!(colors.len(), m.positions.len());
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("patch.obj");
    write_mesh(&m, &out, 512)?;
    let back = read_mesh(&out)?;
    assert_eq!(back.positions, m.positions);
    assert_eq!(back.triangles, m.triangles);
    assert_eq!(back.colors, Some(colors));
    Ok(())
}

/// Random networks with distinct node positions (so welding has nothing to merge), some
/// isolated nodes, loops and branches.
fn arb_network() -> impl Strategy<Value = Network> {
    (2usize..40).prop_flat_map(|n| {
        let pts = proptest::collection::vec(
            (
                -1e3f64..1e3,
                -1e3f64..1e3,
                prop_oneof![Just(0.0), -50f64..50.0],
            ),
            n,
        );
        let edges = proptest::collection::vec((0..n as u32, 0..n as u32), 0..(2 * n));
        (pts, edges).prop_map(|(pts, edges)| {
            let nodes: Vec<Node> = pts
                .iter()
                .map(|&(x, y, z)| Node::at(DVec3::new(x, y, z)))
                .collect();
            let mut seen = std::collections::HashSet::new();
            let edges = edges
                .into_iter()
                .filter(|&(a, b)| a != b && seen.insert((a.min(b), a.max(b))))
                .map(|(a, b)| Edge::new(a, b))
                .collect();
            Network {
                nodes,
                edges,
                ..Default::default()
            }
        })
    })
}

fn min_separation(net: &Network) -> f64 {
    let mut best = f64::INFINITY;
    for (i, a) in net.nodes.iter().enumerate() {
        for b in &net.nodes[i + 1..] {
            best = best.min(a.p.distance(b.p));
        }
    }
    best
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_networks_survive_json_dxf_obj_json(net in arb_network()) {
        prop_assume!(min_separation(&net) > 1e-2);
        let back = roundtrip_json_dxf_obj_json(&net).map_err(|e| TestCaseError::fail(e.to_string()))?;
        assert_same_topology(&net, &back, 1e-9);
    }
}

#[test]
fn flat_network_off_the_ground_keeps_its_height_through_dxf() -> TestResult {
    // All nodes at z = 5: written as LWPOLYLINE with an elevation, which must come back.
    let nodes = [
        (0.0, 0.0),
        (10.0, 0.0),
        (10.0, 10.0),
        (0.0, 10.0),
        (20.0, 5.0),
    ]
    .iter()
    .map(|&(x, y)| Node::at(DVec3::new(x, y, 5.0)))
    .collect();
    let edges = [(0, 1), (1, 2), (2, 3), (3, 0), (1, 4)]
        .iter()
        .map(|&(a, b)| Edge::new(a, b))
        .collect();
    let net = Network {
        nodes,
        edges,
        ..Default::default()
    };
    let back = roundtrip_json_dxf_obj_json(&net)?;
    assert_same_topology(&net, &back, 1e-9);
    Ok(())
}

#[test]
fn renders_survive_a_network_with_a_dangling_edge() {
    // The public render functions draw what they can instead of indexing out of range.
    let net = Network {
        nodes: vec![Node::at(DVec3::ZERO), Node::at(DVec3::X)],
        edges: vec![Edge::new(0, 1), Edge::new(1, 7)],
        ..Default::default()
    };
    let svg = lamina::network::io::render_svg_string(&net);
    assert_eq!(svg.matches("<line ").count(), 1);
    assert!(lamina::network::io::render_png_bytes(&net, 64).is_ok());
}

#[test]
fn writers_refuse_networks_no_format_can_hold() -> TestResult {
    let net = Network {
        nodes: vec![
            Node::at(DVec3::ZERO),
            Node::at(DVec3::new(f64::NAN, 0.0, 0.0)),
        ],
        edges: vec![Edge::new(0, 1), Edge::new(0, 5)],
        ..Default::default()
    };
    let dir = tempfile::tempdir()?;
    for ext in ["json", "obj", "dxf", "svg", "png"] {
        let path = dir.path().join(format!("bad.{ext}"));
        let err = write_network(&net, &path, &RenderOptions::default())
            .expect_err("hard problems are refused")
            .to_string();
        assert!(err.contains("node 1: position is not finite"), "{err}");
        assert!(err.contains("edge 1: joins nodes 0 and 5"), "{err}");
        assert!(!path.exists());
    }
    assert_eq!(std::fs::read_dir(dir.path())?.count(), 0);
    Ok(())
}
