//! `lamina size` end to end on the Calyx fixture, `plates --sizing`, and bad input.

use crate::common::{fixture, lamina, stderr, TestResult};

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap_or("")
}

fn calyx_axes(dir: &std::path::Path) -> Result<std::path::PathBuf, Box<dyn std::error::Error>> {
    let axes = dir.join("axes.json");
    let net = fixture("networks/calyx_veins.json");
    let o = lamina(&[
        "planarize",
        s(&net),
        "--fix-normal",
        "z<1:0,0,1",
        "-o",
        s(&axes),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    Ok(axes)
}

#[test]
fn calyx_is_sized_repeatably_and_plates_take_the_gauges() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path())?;
    let sizing = dir.path().join("sizing.json");
    let args = [
        "size",
        s(&axes),
        "-o",
        s(&sizing),
        "--support",
        "z<1",
        "--load",
        "self-weight",
        "--deflection-limit",
        "L/500",
        "--material",
        "1.4404",
    ];
    let o = lamina(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let first = std::fs::read(&sizing)?;
    let o = lamina(&args);
    assert_eq!(o.status.code(), Some(0));
    assert_eq!(
        first,
        std::fs::read(&sizing)?,
        "the same inputs give the same bytes"
    );
    let doc: serde_json::Value = serde_json::from_slice(&first)?;
    let totals = &doc["totals"];
    let limit = totals["deflection_limit"].as_f64().ok_or("limit")?;
    assert!(totals["max_displacement"].as_f64().ok_or("d")? <= limit);
    assert!(totals["residual"].as_f64().ok_or("residual")? < 1e-9);
    let gauges: Vec<f64> = doc["edges"]
        .as_array()
        .ok_or("edges")?
        .iter()
        .filter_map(|e| e["gauge"].as_f64())
        .collect();
    assert_eq!(gauges.len(), 273);
    assert!(
        gauges.iter().any(|g| *g > 1.5),
        "the deflection limit raised some"
    );

    // plates --sizing: every plate as sized (seam halves from the list adding up to it).
    let out = dir.path().join("plates");
    let o = lamina(&["plates", s(&axes), "--sizing", s(&sizing), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let plates: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plates.json"))?)?;
    for p in plates["plates"].as_array().ok_or("plates")? {
        let edge = p["edge"].as_u64().ok_or("edge")? as usize;
        let t = p["thickness"].as_f64().ok_or("t")?;
        if p["bolted_to"].is_null() {
            assert_eq!(t, gauges[edge], "plate {}", p["id"]);
        }
    }
    Ok(())
}

#[test]
fn assembly_groups_get_one_gauge_each_as_plates_groups_them() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path())?;
    let sizing = dir.path().join("sizing.json");
    let o = lamina(&[
        "size",
        s(&axes),
        "-o",
        s(&sizing),
        "--support",
        "z<1",
        "--load",
        "self-weight",
        "--deflection-limit",
        "L/500",
        "--material",
        "s355",
        "--group-by",
        "assembly",
        "--groups",
        "5",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&sizing)?)?;
    assert_eq!(doc["group_by"]["assembly"], 5);
    let gauges: Vec<f64> = doc["edges"]
        .as_array()
        .ok_or("edges")?
        .iter()
        .filter_map(|e| e["gauge"].as_f64())
        .collect();
    // plates --groups 5 makes the same groups: inside each, one gauge; seams by pair of groups.
    let out = dir.path().join("plates");
    let o = lamina(&[
        "plates",
        s(&axes),
        "--sizing",
        s(&sizing),
        "--groups",
        "5",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let plates: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plates.json"))?)?;
    let mut by_group: std::collections::BTreeMap<u64, f64> = Default::default();
    let mut inner = 0;
    for p in plates["plates"].as_array().ok_or("plates")? {
        if !p["bolted_to"].is_null() {
            continue;
        }
        inner += 1;
        let g = gauges[p["edge"].as_u64().ok_or("edge")? as usize];
        let group = p["group"].as_u64().ok_or("group")?;
        let first = *by_group.entry(group).or_insert(g);
        assert_eq!(first, g, "group {group} has gauges {first} and {g}");
    }
    assert!(
        inner > 200 && by_group.len() == 5,
        "{inner} plates in {} groups",
        by_group.len()
    );
    let distinct: std::collections::BTreeSet<u64> = gauges.iter().map(|g| g.to_bits()).collect();
    assert!(distinct.len() > 1, "the analysis told the groups apart");
    Ok(())
}

#[test]
fn plates_without_radii_or_a_thickness_refuse_and_say_what_to_give() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path())?;
    // The same axes without their radii.
    let mut doc: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&axes)?)?;
    for e in doc["edges"].as_array_mut().ok_or("edges")? {
        e.as_object_mut().ok_or("edge")?.remove("radius");
    }
    let bare = dir.path().join("bare.json");
    std::fs::write(&bare, serde_json::to_string(&doc)?)?;
    let out = dir.path().join("p");
    let o = lamina(&["plates", s(&bare), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--sizing"), "{}", stderr(&o));
    assert!(!out.exists());
    Ok(())
}

#[test]
fn bad_sizing_input_exits_2_with_the_reason() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path())?;
    let out = dir.path().join("s.json");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--load", "self-weight"], "--support is needed"),
        (vec!["--support", "z<1"], "--load is needed"),
        (
            vec!["--support", "z<-5000", "--load", "self-weight"],
            "no node matches",
        ),
        (
            vec!["--support", "node=0:pinned", "--load", "self-weight"],
            "mechanism",
        ),
        (
            vec!["--support", "z<1", "--load", "point:node=99999:0,0,-1"],
            "no node matches",
        ),
        (
            vec![
                "--support",
                "z<1",
                "--load",
                "self-weight",
                "--material",
                "s999",
            ],
            "unknown material",
        ),
        (
            vec!["--support", "z<1", "--load", "wind:-1:1,0,0"],
            "pressure",
        ),
        (
            vec![
                "--support",
                "z<1",
                "--load",
                "self-weight",
                "--gauges",
                "3,2",
            ],
            "ascending",
        ),
        (
            vec![
                "--support",
                "z<1",
                "--load",
                "self-weight",
                "--deflection-limit",
                "L/0",
            ],
            "L/N",
        ),
        (
            vec!["--support", "z<1", "--load", "self-weight", "--shells", "3"],
            "even number",
        ),
        (
            vec!["--support", "z<1", "--load", "self-weight", "--shells", "0"],
            "even number",
        ),
        (
            vec!["--support", "z<1", "--load", "self-weight", "--shells", "2"],
            "--shells must be an even number of elements from 4 to 32 (2 is not converged)",
        ),
        (
            vec![
                "--support",
                "z<1",
                "--load",
                "self-weight",
                "--shells",
                "64",
            ],
            "even number",
        ),
        (
            vec![
                "--support",
                "z<1",
                "--load",
                "self-weight",
                "--weld-gap",
                "0",
            ],
            "--weld-gap 0: the plates at a node would meet with no root gap",
        ),
        (
            vec![
                "--support",
                "z<1",
                "--load",
                "self-weight",
                "--weld-gap-tolerance",
                "nan",
            ],
            "--weld-gap-tolerance must be from 0 to 100 mm",
        ),
        // A bolt no row takes even on the thickest plies.
        (
            vec![
                "--support",
                "z<1",
                "--load",
                "self-weight",
                "--groups",
                "7",
                "--bolt",
                "M30",
            ],
            "give a smaller --bolt or thicker gauges",
        ),
    ];
    for (extra, want) in cases {
        let mut args = vec!["size", s(&axes), "-o", s(&out)];
        args.extend_from_slice(&extra);
        let o = lamina(&args);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{extra:?}: {}", stderr(&o));
        assert!(!out.exists(), "{extra:?}: nothing written");
    }
    Ok(())
}

#[test]
fn calyx_as_shells_balances_and_deflects_like_the_frame() -> TestResult {
    // The panels as shells (4 up each) against the frame: the same loads and supports. Deep
    // panels welded along whole axes are not beams joined at points, but not far from them
    // (10 % stiffer here at the time of writing).
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path())?;
    let mut docs = Vec::new();
    for shells in [None, Some("4")] {
        let sizing = dir.path().join("sizing.json");
        let mut args = vec![
            "size",
            s(&axes),
            "-o",
            s(&sizing),
            "--support",
            "z<1",
            "--load",
            "self-weight",
            "--gauges",
            "2",
        ];
        let deck = dir.path().join("model.inp");
        if let Some(n) = shells {
            args.extend(["--shells", n, "--export-ccx", s(&deck)]);
        }
        let o = lamina(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        docs.push(serde_json::from_slice::<serde_json::Value>(
            &std::fs::read(&sizing)?,
        )?);
    }
    let (frame, shells) = (&docs[0], &docs[1]);
    assert_eq!(shells["analysis"]["shells"], 4);
    assert_eq!(frame["analysis"], "frame");
    // Equilibrium: the vertical reactions carry the same weight (one gauge everywhere).
    let lift = |d: &serde_json::Value| -> f64 {
        d["reactions"]
            .as_array()
            .map(|r| r.iter().filter_map(|x| x["force"][2].as_f64()).sum())
            .unwrap_or(0.0)
    };
    assert!((lift(frame) / lift(shells) - 1.0).abs() < 1e-9);
    // The deck of the shells is the shell model: S8R elements, node i + 1 at network node i's
    // mid-height, loads adding up to the weight the reactions carry.
    let deck = std::fs::read_to_string(dir.path().join("model.inp"))?;
    assert!(deck.contains("*ELEMENT, TYPE=S8R") && !deck.contains("B32"));
    let first = shells["nodes"][0]["position"]
        .as_array()
        .ok_or("position")?;
    let line = deck
        .lines()
        .find(|l| l.starts_with("1, "))
        .ok_or("node 1")?;
    let xyz: Vec<f64> = line
        .split(", ")
        .skip(1)
        .map(|v| v.parse().unwrap())
        .collect();
    for (a, b) in xyz.iter().zip(first) {
        assert!(
            (a - b.as_f64().ok_or("x")?).abs() < 1e-9,
            "{line} against {first:?}"
        );
    }
    let mut in_cload = false;
    let mut down = 0.0;
    for l in deck.lines() {
        if l.starts_with('*') {
            in_cload = l == "*CLOAD";
        } else if in_cload {
            let v: Vec<&str> = l.split(", ").collect();
            if v[1] == "3" {
                down += v[2].parse::<f64>()?;
            }
        }
    }
    assert!(
        (down + lift(shells)).abs() < 1e-9 * lift(shells).abs(),
        "{down} {}",
        lift(shells)
    );
    let (df, ds) = (
        frame["totals"]["max_displacement"].as_f64().ok_or("d")?,
        shells["totals"]["max_displacement"].as_f64().ok_or("d")?,
    );
    assert!(
        (ds / df - 1.0).abs() < 0.25,
        "shells {ds} mm, frame {df} mm"
    );
    Ok(())
}

#[test]
fn the_steel_analysed_is_the_steel_cut_with_the_joints_the_sizing_names() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path())?;
    let sizing = dir.path().join("sizing.json");
    let o = lamina(&[
        "size",
        s(&axes),
        "-o",
        s(&sizing),
        "--support",
        "z<1",
        "--load",
        "self-weight",
        "--load",
        "wind:0.8:1,0.5,0",
        "--material",
        "s355",
        "--groups",
        "7",
        "--weld-gap",
        "1.5",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = std::fs::read_to_string(&sizing)?;
    let doc: serde_json::Value = serde_json::from_str(&text)?;
    assert_eq!(doc["joints"]["weld_gap"], 1.5);
    // Other joints than the sizing weighed are refused, naming the flag; nothing written.
    let out = dir.path().join("plates");
    let o = lamina(&[
        "plates",
        s(&axes),
        "--sizing",
        s(&sizing),
        "--groups",
        "7",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--weld-gap"), "{}", stderr(&o));
    assert!(!out.exists());
    let o = lamina(&[
        "plates",
        s(&axes),
        "--sizing",
        s(&sizing),
        "--groups",
        "7",
        "--weld-gap",
        "1.5",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // Each edge's plates weigh what the analysis carried; the total adds the bolt sets.
    let plates: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plates.json"))?)?;
    let edges = doc["edges"].as_array().ok_or("edges")?;
    let mut cut = vec![0.0f64; edges.len()];
    for p in plates["plates"].as_array().ok_or("plates")? {
        let k = p["edge"].as_u64().ok_or("edge")? as usize;
        let volume = p["area_mm2"].as_f64().ok_or("area")? * p["thickness"].as_f64().ok_or("t")?;
        cut[k] += volume * 7.85e-6;
    }
    let mut total = 0.0;
    let mut bolts = 0.0;
    for (k, e) in edges.iter().enumerate() {
        let analysed = e["mass_kg"].as_f64().ok_or("mass_kg")?;
        assert!(
            (analysed - cut[k]).abs() <= 1e-9 * cut[k],
            "edge {k}: {analysed} against {}",
            cut[k]
        );
        total += analysed;
        bolts += e["bolts_kg"].as_f64().unwrap_or(0.0);
    }
    assert!(bolts > 0.0, "the seams' bolts are weighed");
    let mass = doc["totals"]["mass_kg"].as_f64().ok_or("mass")?;
    assert!(
        (mass - total - bolts).abs() < 1e-9 * mass,
        "{mass} against {total} + {bolts}"
    );
    // A seam whose bolts cannot hold the sizing's forces: plates stops (exit 2), naming it.
    let mut heavy: serde_json::Value = serde_json::from_str(&text)?;
    for e in heavy["edges"].as_array_mut().ok_or("edges")? {
        if let Some(f) = e["seam_forces"].as_array_mut() {
            for v in f.iter_mut() {
                *v = serde_json::json!(v.as_f64().unwrap_or(0.0) * 1e4 + 1e5);
            }
        }
    }
    let heavy_path = dir.path().join("heavy.json");
    std::fs::write(&heavy_path, serde_json::to_string(&heavy)?)?;
    let out = dir.path().join("heavy");
    let o = lamina(&[
        "plates",
        s(&axes),
        "--sizing",
        s(&heavy_path),
        "--groups",
        "7",
        "--weld-gap",
        "1.5",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("bolts do not hold its forces"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    Ok(())
}
