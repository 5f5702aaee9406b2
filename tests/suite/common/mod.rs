//! Helpers shared by the integration tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use lamina::network::Network;

pub type TestResult = Result<(), Box<dyn std::error::Error>>;

pub fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(rel)
}

pub fn lamina(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lamina"))
        .args(args)
        .output()
        .expect("the lamina binary runs")
}

/// Runs lamina and returns its stdout, or an error with its stderr when it fails.
pub fn run_ok(args: &[&str]) -> Result<String, Box<dyn std::error::Error>> {
    let o = lamina(args);
    if !o.status.success() {
        return Err(format!("lamina {args:?} failed: {}", stderr(&o)).into());
    }
    Ok(stdout(&o))
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The files in a frames folder, sorted.
pub fn frame_names(dir: &Path) -> Result<Vec<String>, Box<dyn std::error::Error>> {
    let mut names: Vec<String> = std::fs::read_dir(dir)?
        .map(|e| e.map(|e| e.file_name().to_string_lossy().into_owned()))
        .collect::<Result<_, _>>()?;
    names.sort();
    Ok(names)
}

/// The frames a growth of `steps` steps writes every `every` steps: each multiple of `every`,
/// and the last step.
pub fn expected_frames(steps: usize, every: usize) -> Vec<String> {
    let mut names: Vec<String> = (1..=steps / every)
        .map(|k| format!("frame-{:05}.png", every * k))
        .collect();
    names.push(format!("frame-{steps:05}.png"));
    names.dedup();
    names
}

/// Every edge as its two end positions, ordered, then all edges sorted: a form that ignores node
/// numbering and edge direction, for comparing topology across formats.
pub fn canonical_edges(net: &Network) -> Vec<[[f64; 3]; 2]> {
    let mut v: Vec<[[f64; 3]; 2]> = net
        .edges
        .iter()
        .map(|e| {
            let a = net.nodes[e.a as usize].p.to_array();
            let b = net.nodes[e.b as usize].p.to_array();
            if a.partial_cmp(&b) == Some(std::cmp::Ordering::Greater) {
                [b, a]
            } else {
                [a, b]
            }
        })
        .collect();
    v.sort_by(|x, y| x.partial_cmp(y).expect("finite coordinates"));
    v
}

/// Asserts that `a` and `b` have the same nodes and edges, up to numbering, with every
/// coordinate within `tol` mm.
pub fn assert_same_topology(a: &Network, b: &Network, tol: f64) {
    assert_eq!(a.nodes.len(), b.nodes.len(), "node counts differ");
    assert_eq!(a.edges.len(), b.edges.len(), "edge counts differ");
    let (ea, eb) = (canonical_edges(a), canonical_edges(b));
    for (x, y) in ea.iter().zip(&eb) {
        for k in 0..2 {
            for c in 0..3 {
                assert!(
                    (x[k][c] - y[k][c]).abs() <= tol,
                    "edge {x:?} vs {y:?} differ by more than {tol}"
                );
            }
        }
    }
    // Degree sequences by position must agree too (catches two nodes merged into one).
    let degrees = |n: &Network| {
        let adj = n.adjacency();
        let mut d: Vec<usize> = (0..n.nodes.len() as u32).map(|i| adj.degree(i)).collect();
        d.sort();
        d
    };
    assert_eq!(degrees(a), degrees(b), "degree sequences differ");
}
