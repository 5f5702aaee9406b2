//! `lamina cells` end to end: the Calyx-like fixture on its guide surface, a flat leaf, and the
//! cells mesh used as the guide for `planarize`.

use std::path::Path;

use crate::common::{fixture, lamina, stderr, stdout, TestResult};
use lamina::mesh::io::read_mesh;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn json(path: &Path) -> Result<serde_json::Value, Box<dyn std::error::Error>> {
    Ok(serde_json::from_str(&std::fs::read_to_string(path)?)?)
}

#[test]
fn calyx_cells_match_the_guide_surface_and_tile_without_gaps() -> TestResult {
    let dir = tempfile::tempdir()?;
    let obj = dir.path().join("cells.obj");
    let table = dir.path().join("cells.json");
    let o = lamina(&[
        "cells",
        s(&fixture("networks/calyx_veins.json")),
        "--surface",
        s(&fixture("surfaces/calyx.obj")),
        "-o",
        s(&obj),
        "--table",
        s(&table),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("matches the surface's capped χ = 2"),
        "{}",
        stdout(&o)
    );
    let t = json(&table)?;
    assert_eq!(t["euler"]["vertices"], 248);
    assert_eq!(t["euler"]["edges"], 273);
    assert_eq!(t["euler"]["chi"], 2);
    let cells = t["cells"].as_array().ok_or("cells")?;
    assert_eq!(cells.len(), 26, "one cell per loop of the fixture");
    assert!(t["untriangulated"].as_array().ok_or("untri")?.is_empty());

    // The mesh is one oriented manifold sheet with the network's outer boundary as its rim;
    // every cell boundary edge is a network edge, each used by exactly one cell per side.
    let mesh = read_mesh(&obj)?;
    let topo = mesh.check_manifold();
    assert!(topo.is_manifold(), "{:?}", topo.problems);
    assert_eq!(topo.boundary_loops, 1);
    assert_eq!(topo.euler, 1, "a disk");
    let mut sides = std::collections::HashMap::new();
    for c in cells {
        let nodes = c["nodes"].as_array().ok_or("nodes")?;
        let inner: Vec<_> = c["inner_edges"].as_array().ok_or("inner")?.to_vec();
        for (k, e) in c["edges"].as_array().ok_or("edges")?.iter().enumerate() {
            if inner.contains(e) {
                continue;
            }
            let a = nodes[k].as_u64().ok_or("node")?;
            let b = nodes[(k + 1) % nodes.len()].as_u64().ok_or("node")?;
            assert!(
                sides.insert((a, b), e.clone()).is_none(),
                "side {a}→{b} twice"
            );
        }
    }
    let network = json(&fixture("networks/calyx_veins.json"))?;
    let net_edges = network["edges"].as_array().ok_or("edges")?;
    for ((a, b), e) in &sides {
        let edge = &net_edges[e.as_u64().ok_or("edge")? as usize];
        let ends = [edge["a"].as_u64(), edge["b"].as_u64()];
        assert!(
            ends == [Some(*a), Some(*b)] || ends == [Some(*b), Some(*a)],
            "cell side {a}→{b} is not edge {e}"
        );
    }
    Ok(())
}

#[test]
fn a_flat_leaf_has_one_hole_and_its_cells_feed_planarize() -> TestResult {
    let dir = tempfile::tempdir()?;
    let leaf = dir.path().join("leaf.json");
    let o = lamina(&[
        "venation",
        "--step",
        "1.5",
        "--kill",
        "2.2",
        "--birth",
        "3",
        "-o",
        s(&leaf),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let obj = dir.path().join("cells.obj");
    let o = lamina(&["cells", s(&leaf), "-o", s(&obj), "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o))?;
    assert_eq!(v["holes"], 1, "{v}");
    assert_eq!(v["euler"]["chi"], 2, "{v}");
    assert!(v["cells"].as_u64().ok_or("cells")? > 5, "{v}");
    let mesh = read_mesh(&obj)?;
    assert!(mesh.check_manifold().is_manifold());

    // The cells' vertex normals are a guide surface for planarize.
    let axes = dir.path().join("axes.json");
    let o = lamina(&[
        "planarize",
        s(&leaf),
        "--surface",
        s(&obj),
        "--height",
        "5",
        "-o",
        s(&axes),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    Ok(())
}

#[test]
fn a_curved_network_without_normals_or_surface_is_refused() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = dir.path().join("bent.json");
    std::fs::write(
        &net,
        r#"{"format":"lamina-network","version":1,"meta":{"units":"mm"},
"nodes":[{"p":[0,0,0]},{"p":[10,0,0]},{"p":[10,10,0]},{"p":[0,10,5]}],
"edges":[{"a":0,"b":1},{"a":1,"b":2},{"a":2,"b":3},{"a":3,"b":0}]}"#,
    )?;
    let out = dir.path().join("cells.obj");
    let o = lamina(&["cells", s(&net), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not flat"), "{}", stderr(&o));
    assert!(!out.exists());
    Ok(())
}

#[test]
fn a_drawing_of_one_point_has_no_cells_and_says_why() -> TestResult {
    let dir = tempfile::tempdir()?;
    let dxf = dir.path().join("point.dxf");
    std::fs::write(
        &dxf,
        "0\nSECTION\n2\nENTITIES\n0\nPOINT\n8\n0\n10\n1\n20\n2\n30\n3\n0\nENDSEC\n0\nEOF\n",
    )?;
    let out = dir.path().join("cells.obj");
    let o = lamina(&["cells", s(&dxf), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("the network has 1 node(s) and no edges: there are no cells to find"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    Ok(())
}
