//! Every numeric flag of every command, set to the values that broke lamina before (0, -1,
//! NaN, infinities, 1e308, 1e-300, 2³², 2⁶⁴), each run as its own process on small inputs
//! under a 4 GB address-space limit and a 20 s time limit. A run may succeed or refuse; it may
//! not panic, run out of memory, hang, refuse without exactly one error line (clap's own refusals of a
//! value that does not parse keep clap's format), or refuse and leave a file.
//!
//!     cargo build --release && cargo run --release --example fuzz_flags [-- BINARY]
//!
//! Prints every run that broke a rule and exits 1 if any did.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const VALUES: &[&str] = &[
    "0",
    "-1",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1e-300",
    "4294967296",
    "18446744073709551616",
];

/// (base command, with OUT for the output folder and ROOT for the repository; its numeric flags)
const COMMANDS: &[(&[&str], &[&str])] = &[
    (
        &["venation", "-o", "OUT/v.json", "--max-iterations", "30"],
        &[
            "--step",
            "--kill",
            "--birth",
            "--sources",
            "--sources-per-step",
            "--join-distance",
            "--join-angle",
            "--murray",
            "--tip-radius",
            "--max-iterations",
            "--seed",
        ],
    ),
    (
        &[
            "venation",
            "--blade",
            "marginal",
            "-o",
            "OUT/v.json",
            "--max-iterations",
            "30",
        ],
        &["--initial-scale", "--blade-rate", "--r"],
    ),
    (
        &[
            "venation",
            "-o",
            "OUT/v.json",
            "--max-iterations",
            "20",
            "--frames",
            "OUT/f",
        ],
        &["--every", "--frame-size"],
    ),
    (
        &[
            "venation",
            "--surface",
            "ROOT/fixtures/surfaces/sphere.obj",
            "--sources",
            "100",
            "--max-iterations",
            "20",
            "-o",
            "OUT/s.json",
        ],
        &["--reach", "--edge-tolerance", "--birth", "--step"],
    ),
    (
        &[
            "veins",
            "--surface",
            "ROOT/fixtures/surfaces/torus.obj",
            "--sources",
            "30",
            "-o",
            "OUT/v.json",
        ],
        &[
            "--sources",
            "--root",
            "--tip-radius",
            "--murray",
            "--smooth",
            "--seed",
            "--weld",
            "--weld-rel",
        ],
    ),
    (
        &[
            "lsystem",
            "--axiom",
            "X",
            "--rule",
            "X=F[-X]F[+X]-X",
            "--rule",
            "F=FF",
            "-n",
            "4",
            "-o",
            "OUT/l.json",
        ],
        &[
            "--iterations",
            "--step",
            "--length-scale",
            "--radius",
            "--radius-scale",
            "--decay",
            "--max-symbols",
            "--angle",
            "--seed",
        ],
    ),
    (
        &["bifurcate", "--depth", "4", "-o", "OUT/b.json"],
        &[
            "--depth", "--length", "--angle", "--scale", "--roll", "--seed",
        ],
    ),
    (
        &[
            "buds",
            "ROOT/fixtures/buds/line.bud",
            "--cells",
            "200",
            "-o",
            "OUT/b.stl",
        ],
        &["--cells", "--cell-mm", "--clearance", "--seed"],
    ),
    (
        &[
            "cells",
            "ROOT/fixtures/networks/ezdxf_crossings.dxf",
            "--split-crossings",
            "-o",
            "OUT/c.obj",
        ],
        &["--weld", "--weld-rel", "--chord-tolerance"],
    ),
    (
        &[
            "convert",
            "ROOT/fixtures/networks/ezdxf_curves_in.dxf",
            "OUT/c.json",
        ],
        &[
            "--weld",
            "--weld-rel",
            "--chord-tolerance",
            "--max-points",
            "--size",
        ],
    ),
    (
        &[
            "render",
            "ROOT/fixtures/networks/ezdxf_veins.dxf",
            "-o",
            "OUT/r.png",
        ],
        &["--size"],
    ),
    (
        &["plates", "ROOT/fuzz/corpus/axes/tree.json", "-o", "OUT/p"],
        &["--thickness", "--weld-gap", "--groups"],
    ),
    (
        &["nest", "ROOT/fuzz/corpus/plates/tree.json", "-o", "OUT/n"],
        &["--margin", "--spacing", "--tries", "--seed"],
    ),
    (
        &[
            "solid",
            "ROOT/fixtures/networks/small_loop.json",
            "--cell",
            "0.25",
            "-o",
            "OUT/s.stl",
        ],
        &["--cell", "--lamina", "--fit", "--radius"],
    ),
    (
        &[
            "slice",
            "ROOT/fixtures/surfaces/openscad_part.stl",
            "-o",
            "OUT/j.sl1",
        ],
        &[
            "--layer",
            "--pixel",
            "--exposure",
            "--bottom-exposure",
            "--bottom-layers",
            "--lift",
            "--lift-speed",
            "--copies",
            "--gap",
            "--resin-cost",
            "--density",
            "--speed",
            "--scale",
        ],
    ),
];

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(files_in(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

fn main() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let binary = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/release/lamina"));
    let mut broken = Vec::new();
    let mut runs = 0;
    for (base, flags) in COMMANDS {
        for flag in *flags {
            for value in VALUES {
                let dir = std::env::temp_dir().join(format!("lamina-flags-{}", std::process::id()));
                let _ = std::fs::remove_dir_all(&dir);
                std::fs::create_dir_all(&dir).expect("a temporary folder");
                let fill = |a: &str| {
                    a.replace("OUT", &dir.to_string_lossy())
                        .replace("ROOT", &root.to_string_lossy())
                };
                let mut args: Vec<String> = base.iter().map(|a| fill(a)).collect();
                args.push(format!("{flag}={value}"));
                let started = Instant::now();
                let child = Command::new("prlimit")
                    .arg("--as=4000000000")
                    .arg(&binary)
                    .args(&args)
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn();
                let Ok(mut child) = child else {
                    eprintln!("fuzz_flags: cannot run prlimit {}", binary.display());
                    std::process::exit(2);
                };
                let mut timed_out = false;
                while child.try_wait().ok().flatten().is_none() {
                    if started.elapsed() > Duration::from_secs(20) {
                        let _ = child.kill();
                        timed_out = true;
                    }
                    std::thread::sleep(Duration::from_millis(10));
                }
                let out = child.wait_with_output().expect("the child's output");
                runs += 1;
                let err = String::from_utf8_lossy(&out.stderr).into_owned();
                let code = out.status.code();
                let left = files_in(&dir);
                let what = if timed_out {
                    Some("ran over 20 s".to_string())
                } else if err.contains("panicked") {
                    Some(format!(
                        "panicked: {}",
                        err.lines().find(|l| l.contains("panicked")).unwrap_or("")
                    ))
                } else if err.contains("memory allocation") || code == Some(134) {
                    Some("ran out of memory".to_string())
                } else if code == Some(2)
                    && !err.starts_with("error: ")
                    && err.lines().filter(|l| l.contains("error:")).count() != 1
                {
                    Some(format!("refused without one error line: {}", err.trim()))
                } else if code == Some(2) && !left.is_empty() {
                    Some(format!("refused but left {} file(s)", left.len()))
                } else if !matches!(code, Some(0..=2)) {
                    Some(format!("exit {code:?}"))
                } else {
                    None
                };
                if let Some(w) = what {
                    println!("{} {flag}={value}: {w}", base[0]);
                    broken.push(w);
                }
                let _ = std::fs::remove_dir_all(&dir);
            }
        }
    }
    println!("{runs} runs, {} broke a rule", broken.len());
    std::process::exit(if broken.is_empty() { 0 } else { 1 });
}
