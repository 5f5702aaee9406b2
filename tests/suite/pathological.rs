//! Inputs no designer means to send but exports and fuzzers do: lines drawn over and over,
//! drawings that cross almost everywhere, bud programs that never grow. Each is answered with
//! its counts or refused early by name, never searched pair by pair.

use crate::common::{lamina, stderr, TestResult};
use serde_json::{json, Value};

/// A flat network: `n` vertical and `n` horizontal lines across a square (n² crossings), the
/// first line drawn `copies` times more.
fn lattice(n: usize, copies: usize) -> Value {
    let mut nodes = Vec::new();
    let mut edges = Vec::new();
    for k in 0..n {
        let c = k as f64 + 0.5;
        let at = nodes.len();
        nodes.extend([
            json!({"p": [c, 0.0, 0.0]}),
            json!({"p": [c, n as f64, 0.0]}),
            json!({"p": [0.0, c, 0.0]}),
            json!({"p": [n as f64, c, 0.0]}),
        ]);
        edges.push(json!({"a": at, "b": at + 1}));
        edges.push(json!({"a": at + 2, "b": at + 3}));
    }
    for _ in 0..copies {
        edges.push(json!({"a": 1, "b": 0}));
    }
    json!({"format": "lamina-network", "version": 1, "nodes": nodes, "edges": edges})
}

fn write(dir: &std::path::Path, name: &str, text: &str) -> Result<String, std::io::Error> {
    let path = dir.join(name);
    std::fs::write(&path, text)?;
    Ok(path.to_string_lossy().into_owned())
}

#[test]
fn a_drawing_crossing_everywhere_is_counted_listed_in_part_and_refused_by_cells() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = write(dir.path(), "lattice.json", &lattice(110, 500).to_string())?;
    let o = lamina(&["info", "--json", &net]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout)?;
    let problems = v["problems"].as_array().ok_or("problems")?;
    let kind = |k: &str| problems.iter().filter(|p| p["kind"] == k).count();
    assert_eq!(kind("repeated_edge"), 500);
    // 12,100 crossings: the first 10,000 listed, the rest counted in one entry.
    assert_eq!(kind("crossing"), 10_000);
    let rest = problems
        .iter()
        .find(|p| p["kind"] == "unlisted_defects")
        .ok_or("the unlisted count")?;
    assert_eq!(rest["count"], 2_100);
    assert!(
        rest["message"]
            .as_str()
            .is_some_and(|m| m.contains("12100 crossings and 0 T-junctions in all")),
        "{rest}"
    );
    let cells = dir.path().join("cells.obj");
    let o = lamina(&["cells", &net, "-o", cells.to_str().ok_or("path")?]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("(and 12099 more crossings or T-junctions)"),
        "{}",
        stderr(&o)
    );
    assert!(!cells.exists());
    Ok(())
}

#[test]
fn members_drawn_twice_are_refused_before_solving_or_cutting() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = write(dir.path(), "lattice.json", &lattice(3, 2).to_string())?;
    let axes = dir.path().join("axes.json");
    let o = lamina(&["planarize", &net, "-o", axes.to_str().ok_or("path")?]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("edge 6: repeats edge 0 (same two nodes): a member drawn twice"),
        "{}",
        stderr(&o)
    );
    assert!(!axes.exists());
    // An axes file with a repeated member (edited by hand, or from an older tool).
    let net = write(dir.path(), "once.json", &lattice(3, 0).to_string())?;
    let o = lamina(&["planarize", &net, "-o", axes.to_str().ok_or("path")?]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut a: Value = serde_json::from_str(&std::fs::read_to_string(&axes)?)?;
    let first = a["edges"][2].clone();
    a["edges"].as_array_mut().ok_or("edges")?.push(first);
    std::fs::write(&axes, a.to_string())?;
    let plates = dir.path().join("plates");
    let o = lamina(&[
        "plates",
        axes.to_str().ok_or("path")?,
        "-o",
        plates.to_str().ok_or("path")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("edge 6: repeats edge 2 (nodes 4 and 5): a member drawn twice"),
        "{}",
        stderr(&o)
    );
    assert!(!plates.exists());
    Ok(())
}

#[test]
fn a_bud_program_that_only_creates_is_refused_before_growing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let program = write(
        dir.path(),
        "chain.bud",
        &format!("Base:\n{}", "create Base\n".repeat(50_000)),
    )?;
    let stl = dir.path().join("form.stl");
    let o = lamina(&["buds", &program, "-o", stl.to_str().ok_or("path")?]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("no bud type that Base can lead to divides a cell"),
        "{}",
        stderr(&o)
    );
    assert!(!stl.exists());
    Ok(())
}
