//! `lamina simplify` end to end: the Calyx network on its guide surface, then `cells`,
//! `planarize`, `size` and `plates` on the result; bad flags exit 2 and write nothing.

use std::path::Path;

use crate::common::{fixture, lamina, stderr, stdout, TestResult};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn the_calyx_network_simplifies_and_goes_on_to_cells_axes_sizing_and_plates() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("simple.json");
    let report = dir.path().join("r.json");
    let surface = fixture("surfaces/calyx.obj");
    let o = lamina(&[
        "simplify",
        s(&fixture("networks/calyx_veins.json")),
        "--surface",
        s(&surface),
        "--max-deviation",
        "10",
        "-o",
        s(&out),
        "--report",
        s(&report),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("no joint below 30°"), "{}", stdout(&o));
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report)?)?;
    let (before, after) = (&r["before"], &r["after"]);
    assert!(after["members"].as_u64() < before["members"].as_u64());
    assert_eq!(before["cycles"], after["cycles"]);
    assert_eq!(before["faces"], after["faces"]);
    assert!(r["max_distance"].as_f64().unwrap() <= 10.0);
    let cells = dir.path().join("cells.obj");
    let o = lamina(&["cells", s(&out), "--surface", s(&surface), "-o", s(&cells)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("matches the surface's capped χ = 2"),
        "{}",
        stdout(&o)
    );
    let axes = dir.path().join("axes.json");
    let o = lamina(&[
        "planarize",
        s(&out),
        "--surface",
        s(&cells),
        "--method",
        "newton",
        "-o",
        s(&axes),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let sizing = dir.path().join("sizing.json");
    let o = lamina(&[
        "size",
        s(&axes),
        "-o",
        s(&sizing),
        "--support",
        "z<1:fixed",
        "--load",
        "self-weight",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let plates = dir.path().join("plates");
    let o = lamina(&["plates", s(&axes), "--sizing", s(&sizing), "-o", s(&plates)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(plates.join("plates.json").exists());
    Ok(())
}

#[test]
fn bad_flags_exit_2_and_write_nothing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("simple.json");
    let input = fixture("networks/calyx_veins.json");
    for flags in [
        &["--max-deviation", "0"][..],
        &["--max-deviation", "nan"],
        &["--max-deviation=-1"],
        &["--max-deviation", "inf"],
        &["--min-angle", "90"],
        &["--min-angle=-5"],
        &["--min-length", "nan"],
        &["--merge-distance=-1"],
        &["--prune-order", "-1"],
        &["--max-deviation", "1e300"],
        &["--min-length", "1e9"],
    ] {
        let mut args = vec!["simplify", s(&input), "-o", s(&out)];
        args.extend_from_slice(flags);
        let o = lamina(&args);
        assert_eq!(o.status.code(), Some(2), "{flags:?}: {}", stderr(&o));
        assert!(!out.exists(), "{flags:?}: wrote an output");
    }
    let o = lamina(&[
        "simplify",
        s(&fixture("bad/edge_out_of_range.json")),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!out.exists());
    Ok(())
}
