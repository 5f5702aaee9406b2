//! `lamina venation` end to end: deterministic bytes, Murray's law in the written network,
//! clear errors for bad parameters.

mod common;

use common::{lamina, stderr, TestResult};
use lamina::network::io::{read_network, ReadOptions};

#[test]
fn same_seed_gives_identical_json_and_murray_holds() -> TestResult {
    let dir = tempfile::tempdir()?;
    let (a, b, c) = (
        dir.path().join("a.json"),
        dir.path().join("b.json"),
        dir.path().join("c.json"),
    );
    for (out, seed) in [(&a, "7"), (&b, "7"), (&c, "8")] {
        let o = lamina(&[
            "venation",
            "--mode",
            "open",
            "--shape",
            "cordate",
            "--seed",
            seed,
            "-o",
            out.to_str().ok_or("path")?,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    assert_eq!(std::fs::read(&a)?, std::fs::read(&b)?);
    assert_ne!(std::fs::read(&a)?, std::fs::read(&c)?);
    let net = read_network(&a, &ReadOptions::default())?.network;
    assert_eq!(net.meta.seed, Some(7));
    let v = net.validate();
    assert!(v.is_ok(), "{:?}", v.problems);
    assert_eq!(
        (v.components, v.cycles),
        (1, 0),
        "open venation is one tree"
    );
    assert!(
        v.degree_histogram.len() <= 4,
        "degree ≤ 3: {:?}",
        v.degree_histogram
    );
    // Murray's law at every node with children: edges are written parent -> child.
    let mut child_sum = vec![0.0f64; net.nodes.len()];
    for e in &net.edges {
        child_sum[e.a as usize] += net.nodes[e.b as usize].radius.powi(3);
    }
    for (i, n) in net.nodes.iter().enumerate() {
        if child_sum[i] > 0.0 {
            let r3 = n.radius.powi(3);
            assert!((r3 - child_sum[i]).abs() <= 1e-9 * r3.max(1.0), "node {i}");
        }
    }
    Ok(())
}

#[test]
fn bad_parameters_exit_2_naming_the_option() {
    for (flag, value) in [
        ("--step", "0"),
        ("--kill", "-1"),
        ("--birth", "0"),
        ("--murray", "0.5"),
    ] {
        let arg = format!("{flag}={value}");
        let o = lamina(&["venation", &arg, "-o", "never.json"]);
        assert_eq!(o.status.code(), Some(2), "{flag}");
        assert!(stderr(&o).contains(flag), "{flag}: {}", stderr(&o));
    }
    assert!(!std::path::Path::new("never.json").exists());
}
