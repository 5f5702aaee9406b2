//! Every file in fixtures/bad/ gets one clear error naming the file (and the line or record where
//! there is one), exit status 2, no panic, and no output file.

use crate::common::{fixture, lamina, stderr, TestResult};

/// (file, words the error must contain). Every file in fixtures/bad/ must be listed here.
const EXPECTED: &[(&str, &[&str])] = &[
    ("empty.json", &["file is empty"]),
    ("empty.obj", &["file is empty"]),
    ("empty.dxf", &["file is empty"]),
    ("empty.stl", &["file is empty"]),
    ("truncated.stl", &["not an STL file", "12 triangles", "259"]),
    ("garbage.stl", &["not an STL file"]),
    ("ascii_broken.stl", &["line 5", "vertex 1 0"]),
    ("garbage.dxf", &["line"]),
    (
        "obj_index_out_of_range.obj",
        &["line 5", "vertex index 7 is out of range"],
    ),
    ("mesh_index_out_of_range.obj", &["line 5", "does not exist"]),
    ("nan_coords.obj", &["line 2", "not finite"]),
    ("nan_coords.dxf", &["entity 0 (LINE", "non-finite"]),
    (
        "wrong_schema.json",
        &["line 1", "unknown field `type`", "lamina-network"],
    ),
    ("wrong_format.json", &["format is \"something-else\""]),
    (
        "edge_out_of_range.json",
        &["edge 0", "joins nodes 0 and 3", "1 nodes"],
    ),
    (
        "huge_radius.json",
        &["edge 0", "radius 1e308 mm is larger than 1000000 mm"],
    ),
    ("inf_colour.obj", &["vertex 0", "colour is not finite"]),
    ("unsupported_only.dxf", &["no LINE", "2 3DFACE", "1 TEXT"]),
    ("hatch_only.dxf", &["no LINE", "found: 1 HATCH"]),
    (
        "faces_only.dxf",
        &["found: 2 3DFACE", "a mesh of faces", "`lamina audit` reads"],
    ),
    (
        "block_cycle.dxf",
        &["entity 0 (INSERT", "block \"LOOP\" inserts itself"],
    ),
    (
        "minsert_bomb.dxf",
        &["expands to more than", "is the default for a file of"],
    ),
    (
        "one_vertex_loop.dxf",
        &["entity 0 (LWPOLYLINE", "a closed polyline of one vertex"],
    ),
    (
        "huge_bulge.dxf",
        &[
            "entity 0 (LWPOLYLINE",
            "vertex 3 starts an arc segment",
            "limit 100000 for this curve",
        ],
    ),
];

#[test]
fn every_bad_file_is_listed() -> TestResult {
    for entry in std::fs::read_dir(fixture("bad"))? {
        let name = entry?.file_name().to_string_lossy().into_owned();
        assert!(
            EXPECTED.iter().any(|(n, _)| *n == name),
            "fixtures/bad/{name} has no expectation in tests/bad_inputs.rs"
        );
    }
    Ok(())
}

#[test]
fn bad_files_fail_cleanly_in_every_command() -> TestResult {
    let dir = tempfile::tempdir()?;
    for (name, words) in EXPECTED {
        let input = fixture(&format!("bad/{name}"));
        let input = input.to_str().ok_or("utf-8 path")?;
        let out_json = dir.path().join("out.json");
        let out_png = dir.path().join("out.png");
        let runs = [
            vec!["info", input],
            vec!["info", "--json", input],
            vec!["convert", input, out_json.to_str().ok_or("path")?],
            vec!["render", input, "-o", out_png.to_str().ok_or("path")?],
        ];
        for args in runs {
            let o = lamina(&args);
            let err = stderr(&o);
            assert_eq!(
                o.status.code(),
                Some(2),
                "{args:?}: exit {:?}, {err}",
                o.status
            );
            assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
            assert!(
                err.contains(name),
                "{args:?}: error does not name the file: {err}"
            );
            for w in *words {
                assert!(err.contains(w), "{args:?}: error lacks `{w}`: {err}");
            }
            assert_eq!(err.trim().lines().count(), 1, "one clear error line: {err}");
            assert!(o.stdout.is_empty(), "{args:?} printed output");
        }
        assert!(
            !out_json.exists() && !out_png.exists(),
            "{name}: output written"
        );
        assert_eq!(
            std::fs::read_dir(dir.path())?.count(),
            0,
            "{name}: stray files"
        );
    }
    Ok(())
}

#[test]
fn a_failed_write_leaves_an_existing_output_untouched() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("keep.json");
    std::fs::write(&out, "previous result")?;
    let o = lamina(&[
        "convert",
        fixture("bad/truncated.stl").to_str().ok_or("path")?,
        out.to_str().ok_or("path")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&out)?, "previous result");
    Ok(())
}

#[test]
fn mistyped_options_are_errors_not_defaults() {
    let net = fixture("networks/ezdxf_veins.dxf");
    let net = net.to_str().expect("utf-8 path");
    for args in [
        vec!["info", net, "--weld", "abc"],
        vec!["info", net, "--weld", "-1"],
        vec!["info", net, "--weld", "0.1", "--weld-rel", "1e-3"],
        vec!["render", net, "-o", "x.png", "--size", "3"],
        vec!["convert", net, "x.stl"],
    ] {
        let o = lamina(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    assert!(!std::path::Path::new("x.png").exists());
}

/// Values that once ran for ever or exhausted memory (found by examples/fuzz_flags.rs and the
/// fuzz cases): refused at once, naming the flag.
#[test]
fn extreme_flag_values_are_refused_naming_the_flag() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let loop_json = fixture("networks/small_loop.json");
    let loop_json = loop_json.to_str().ok_or("path")?;
    let plates = fixture("../fuzz/corpus/plates/tree.json");
    let plates = plates.to_str().ok_or("path")?;
    let torus = fixture("surfaces/torus.obj");
    let torus = torus.to_str().ok_or("path")?;
    let palette = fixture("../fuzz/corpus/png/palette_plte4.png");
    let palette = palette.to_str().ok_or("path")?;
    let crc = fixture("../fuzz/corpus/png/crc_idat.png");
    let crc = crc.to_str().ok_or("path")?;
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "nest".into(),
                plates.into(),
                "-o".into(),
                out("n"),
                "--tries".into(),
                "4294967296".into(),
            ],
            "--tries",
        ),
        (
            vec![
                "solid".into(),
                loop_json.into(),
                "-o".into(),
                out("s.stl"),
                "--cell".into(),
                "1e-300".into(),
            ],
            "--cell",
        ),
        (
            vec![
                "solid".into(),
                loop_json.into(),
                "-o".into(),
                out("s.stl"),
                "--cell".into(),
                "1e308".into(),
            ],
            "--cell 1e308 mm is more than 1000000 mm",
        ),
        // A ratio refused before the sweep's folder is made.
        (
            vec![
                "venation".into(),
                "--sweep-r".into(),
                "0.5,1e308".into(),
                "-o".into(),
                out("sweep"),
            ],
            "--sweep-r must be a ratio above 0 and at most 1000, got 1e308",
        ),
        // Seeds per r: at least one, at most a thousand, checked before the folder is made.
        (
            vec![
                "venation".into(),
                "--sweep-r".into(),
                "0.5".into(),
                "--seeds".into(),
                "0".into(),
                "-o".into(),
                out("sweep"),
            ],
            "--seeds must be 1 to 1000 leaves per r, got 0",
        ),
        (
            vec![
                "venation".into(),
                "--sweep-r".into(),
                "0.5".into(),
                "--seeds".into(),
                "18446744073709551615".into(),
                "-o".into(),
                out("sweep"),
            ],
            "--seeds must be 1 to 1000 leaves per r",
        ),
        // What the sweep sets from each r is not also taken from a flag.
        (
            vec![
                "venation".into(),
                "--sweep-r".into(),
                "0.5".into(),
                "--blade-rate".into(),
                "0.01".into(),
                "-o".into(),
                out("sweep"),
            ],
            "--blade-rate: a sweep by blade sets the blade rate from each r",
        ),
        (
            vec![
                "venation".into(),
                "--sweep-r".into(),
                "0.5".into(),
                "--sweep-by".into(),
                "step".into(),
                "--step".into(),
                "0.5".into(),
                "-o".into(),
                out("sweep"),
            ],
            "--step: a sweep by step sets D from each r",
        ),
        // A palette PNG whose PLTE is 4 bytes: the png crate indexed past it and panicked.
        (
            vec![
                "venation".into(),
                "--density".into(),
                palette.into(),
                "-o".into(),
                out("v.json"),
            ],
            "its palette (PLTE) is 4 bytes",
        ),
        // A spoiled checksum: the chunk is named plainly, not as the decoder's debug struct.
        (
            vec![
                "venation".into(),
                "--density".into(),
                crc.into(),
                "-o".into(),
                out("v.json"),
            ],
            "while decoding IDAT chunk",
        ),
        (
            vec![
                "venation".into(),
                "-o".into(),
                out("v.json"),
                "--sources-per-step".into(),
                "4294967295".into(),
            ],
            "--sources-per-step",
        ),
        (
            vec![
                "veins".into(),
                "--surface".into(),
                torus.into(),
                "-o".into(),
                out("v.json"),
                "--smooth".into(),
                "100000".into(),
            ],
            "--smooth",
        ),
        (
            vec![
                "lsystem".into(),
                "--axiom".into(),
                "F".into(),
                "-n".into(),
                "4294967295".into(),
                "--derive-only".into(),
            ],
            "--iterations",
        ),
        // A print job's figures: bounded, and said in short form (not 300 digits).
        (
            vec![
                "print".into(),
                loop_json.into(),
                "-o".into(),
                out("p.sl1"),
                "--resin-cost".into(),
                "1e300".into(),
            ],
            "--resin-cost must be from 0 to 1000000 per litre, got 1e300",
        ),
        (
            vec![
                "print".into(),
                loop_json.into(),
                "-o".into(),
                out("p.sl1"),
                "--density".into(),
                "0".into(),
            ],
            "--density must be from 0.1 to 30 g/mL, got 0",
        ),
        (
            vec![
                "print".into(),
                loop_json.into(),
                "-o".into(),
                out("p.sl1"),
                "--speed".into(),
                "1e300".into(),
            ],
            "--speed must be a positive number of mm/h, at most 100000, got 1e300",
        ),
        (
            vec![
                "solid".into(),
                loop_json.into(),
                "-o".into(),
                out("s.stl"),
                "--tolerance".into(),
                "1e300".into(),
            ],
            "--tolerance 1e300 mm is more than ten cells",
        ),
    ];
    // The demo's own flags, checked before its folder is made.
    let demo = [
        ("--size", "0"),
        ("--size", "99999"),
        ("--nest-time", "0"),
        ("--nest-time", "NaN"),
        ("--nest-time", "1e9"),
    ];
    let cases = cases.into_iter().chain(demo.map(|(flag, value)| {
        let args = ["demo", "--out", &out("demo"), flag, value].map(String::from);
        (args.to_vec(), flag)
    }));
    for (args, flag) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = lamina(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(flag),
            "{args:?}: the error does not name {flag}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        // No Rust debug struct from a decoder.
        assert!(!err.contains("ChunkType"), "{args:?}: {err}");
    }
    assert_eq!(std::fs::read_dir(dir.path())?.count(), 0, "nothing written");
    Ok(())
}

#[test]
fn a_speed_table_without_a_row_for_a_thickness_writes_nothing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let table = dir.path().join("speeds.json");
    let row =
        r#"{"thickness": 0.5, "cut_mm_per_min": 1000, "pierce_s": 1, "etch_mm_per_min": 1000}"#;
    std::fs::write(
        &table,
        format!(r#"{{"material": "by hand", "laser": [{row}], "plasma": [{row}]}}"#),
    )?;
    let out = dir.path().join("cut");
    let plates = fixture("../fuzz/corpus/plates/tree.json");
    let o = lamina(&[
        "nest",
        plates.to_str().ok_or("path")?,
        "-o",
        out.to_str().ok_or("path")?,
        "--speeds",
        table.to_str().ok_or("path")?,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no row for"), "{}", stderr(&o));
    assert!(!out.exists(), "a partial cut folder was left");
    Ok(())
}
