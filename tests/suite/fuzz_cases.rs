//! Every input the mutation fuzzer found to crash, hang or exhaust memory (fixtures/fuzz/, one
//! folder each, as found; README.txt there lists them) now ends within a time limit and under a
//! 4 GB address-space limit: refused with one line that names the file or flag and the cause,
//! exit status 2, no panic and nothing written; or, where the input is fine, done.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common::{fixture, TestResult};

enum Outcome {
    /// Exit 2, one line, naming each of these.
    Refused(&'static [&'static str]),
    /// Exit 0, writing this file.
    Done(&'static str),
}
use Outcome::{Done, Refused};

/// (case folder, arguments run inside a copy of it, outcome)
const CASES: &[(&str, &[&str], Outcome)] = &[
    (
        "B1_solid_bug",
        &["solid", "in.json", "-o", "out/s.stl", "--cell", "0.5"],
        Refused(&["in.json", "no grid point falls inside the veins"]),
    ),
    (
        "H1_buds_selfcreate",
        &["buds", "in.bud", "-o", "out/b.stl", "--cells", "300"],
        Refused(&["in.bud", "never grows"]),
    ),
    (
        "H2_lsystem_iterations",
        &["lsystem", "--grammar", "in.txt", "--derive-only"],
        Refused(&["in.txt", "4294967295 iterations", "more than 1000"]),
    ),
    (
        "H3_lsystem_long_axiom",
        &["lsystem", "--grammar", "in.txt", "-o", "out/l.json"],
        Done("out/l.json"),
    ),
    (
        "H4_veins_far_vertex",
        &[
            "veins",
            "--surface",
            "in.obj",
            "-o",
            "out/v.json",
            "--sources",
            "30",
        ],
        Done("out/v.json"),
    ),
    (
        "L1_nest_partial",
        &["nest", "in.json", "-o", "out/nest", "--tries", "2"],
        Refused(&["in.json", "plate 32", "thickness"]),
    ),
    (
        "O1_png_dims",
        &[
            "venation",
            "--density",
            "in.png",
            "-o",
            "out/leaf.json",
            "--birth",
            "4",
        ],
        Refused(&["in.png", "65535 × 65535"]),
    ),
    (
        "O2_solid_far_node",
        &["solid", "in.json", "-o", "out/s.stl", "--cell", "0.5"],
        Refused(&["in.json", "triangles, more than"]),
    ),
    (
        "O2b_solid_cell",
        &["solid", "in.json", "-o", "out/s.stl", "--cell", "0.001"],
        Refused(&["in.json", "--cell 0.001"]),
    ),
    (
        "O4_outline_big_coord",
        &["venation", "--outline", "in.svg", "-o", "out/leaf.json"],
        Refused(&["in.svg", "outline spans"]),
    ),
    (
        "O5_slice_printer_layer",
        &[
            "slice",
            "model.stl",
            "-o",
            "out/j.sl1",
            "--printer",
            "printer.json",
        ],
        Refused(&["printer.json", "layer_mm", "8e-8"]),
    ),
    (
        "O6_frame_size",
        &[
            "venation",
            "-o",
            "out/v.json",
            "--max-iterations",
            "100",
            "--frames",
            "out/frames",
            "--frame-size",
            "100000",
        ],
        Refused(&["--frame-size", "100000"]),
    ),
    (
        "P1_outline_translate",
        &["venation", "--outline", "in.svg", "-o", "out/leaf.json"],
        Refused(&["in.svg", "outline"]),
    ),
    (
        "P2_outline_huge_path",
        &[
            "venation",
            "--outline",
            "in.svg",
            "-o",
            "out/leaf.json",
            "--sources",
            "80",
            "--max-iterations",
            "80",
        ],
        Refused(&["in.svg", "outline spans"]),
    ),
    (
        "P2b_initial_scale_inf",
        &[
            "venation",
            "-o",
            "out/v.json",
            "--initial-scale",
            "inf",
            "--blade",
            "marginal",
        ],
        Refused(&["--initial-scale", "inf"]),
    ),
    (
        "P4_surface_degenerate",
        &[
            "venation",
            "--surface",
            "in.stl",
            "-o",
            "out/leaf.json",
            "--sources",
            "80",
            "--max-iterations",
            "60",
        ],
        Done("out/leaf.json"),
    ),
    (
        "P5_nest_sheet",
        &[
            "nest",
            "plates.json",
            "-o",
            "out/n",
            "--sheet",
            "1e308x1e308",
        ],
        Refused(&["sheet", "1e308 × 1e308"]),
    ),
    (
        "P6_slice_layer_tiny",
        &["slice", "model.stl", "-o", "out/j.sl1", "--layer", "1e-300"],
        Refused(&["--layer", "1e-300"]),
    ),
    (
        "P7_dxf_julian_date",
        &["info", "in.dxf"],
        Refused(&["in.dxf", "header date"]),
    ),
];

/// Runs lamina under a 4 GB address-space limit (prlimit, from util-linux) and a time limit.
fn run_limited(dir: &Path, args: &[&str], limit: Duration) -> Result<Output, String> {
    let mut child = Command::new("prlimit")
        .arg("--as=4000000000")
        .arg(env!("CARGO_BIN_EXE_lamina"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("prlimit: {e}"))?;
    let start = Instant::now();
    loop {
        if child.try_wait().map_err(|e| e.to_string())?.is_some() {
            return child.wait_with_output().map_err(|e| e.to_string());
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            return Err(format!("{args:?} still running after {limit:?}"));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn copy_dir(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        std::fs::copy(entry.path(), to.join(entry.file_name()))?;
    }
    Ok(())
}

#[test]
fn every_fuzz_case_is_listed() -> TestResult {
    for entry in std::fs::read_dir(fixture("fuzz"))? {
        let entry = entry?;
        if entry.file_type()?.is_dir() {
            let name = entry.file_name().to_string_lossy().into_owned();
            assert!(
                CASES.iter().any(|(n, _, _)| *n == name),
                "fixtures/fuzz/{name} has no case in tests/fuzz_cases.rs"
            );
        }
    }
    Ok(())
}

#[test]
fn fuzz_cases_end_cleanly() -> TestResult {
    let mut failures = Vec::new();
    for (name, args, outcome) in CASES {
        let dir = tempfile::tempdir()?;
        copy_dir(&fixture(&format!("fuzz/{name}")), dir.path())?;
        std::fs::create_dir_all(dir.path().join("out"))?;
        let o = match run_limited(dir.path(), args, Duration::from_secs(120)) {
            Ok(o) => o,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        if err.contains("panicked") || err.contains("memory allocation") {
            failures.push(format!("{name}: crashed: {err}"));
            continue;
        }
        let written: Vec<_> = std::fs::read_dir(dir.path().join("out"))?.collect();
        match outcome {
            Refused(words) => {
                let lines = err.trim().lines().count();
                if o.status.code() != Some(2) || lines != 1 {
                    failures.push(format!("{name}: exit {:?}, {lines} lines: {err}", o.status));
                } else if let Some(w) = words.iter().find(|w| !err.contains(**w)) {
                    failures.push(format!("{name}: the error lacks `{w}`: {err}"));
                } else if !written.is_empty() {
                    failures.push(format!("{name}: refused but wrote {written:?}"));
                }
            }
            Done(file) => {
                if !o.status.success() || !dir.path().join(file).exists() {
                    failures.push(format!("{name}: exit {:?}, no {file}: {err}", o.status));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    Ok(())
}
