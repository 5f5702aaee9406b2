//! Reading a large DXF the way every command does before its own work: parse, flatten curves
//! within the chord tolerance, expand blocks, take to mm, weld into a network. `scripts/bench dxf`
//! runs this on the 52 MB drawing of curves and nested blocks (`scripts/fixtures/curves_dxf.py`)
//! next to ezdxf's `readfile` of the same file. Prints the wall time of each of three reads and
//! the process's peak resident memory (one read at a time, so the peak of one read).
//!
//! `cargo bench --bench dxf_read [-- FILE]`

use std::path::PathBuf;
use std::time::Instant;

use lamina::network::io::{read_network, ReadOptions};

fn main() {
    let path = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-data/curves-50mb.dxf")
        });
    if !path.exists() {
        eprintln!(
            "{} is missing: `scripts/bench dxf` writes it (scripts/fixtures/curves_dxf.py)",
            path.display()
        );
        return;
    }
    let size = std::fs::metadata(&path).map_or(0, |m| m.len());
    println!("{} ({:.1} MB)", path.display(), size as f64 / 1e6);
    for run in 1..=3 {
        let start = Instant::now();
        let imported = match read_network(&path, &ReadOptions::default()) {
            Ok(imported) => imported,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(2);
            }
        };
        let secs = start.elapsed().as_secs_f64();
        println!(
            "read {run}: {secs:.3} s, {} nodes, {} edges, {} blocks inserted",
            imported.network.nodes.len(),
            imported.network.edges.len(),
            imported.inserts
        );
    }
    println!("peak RSS {}", peak_rss());
}

/// VmHWM from /proc (Linux), or a dash.
fn peak_rss() -> String {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .map(|l| l["VmHWM:".len()..].trim().to_string())
        })
        .unwrap_or_else(|| "-".into())
}
