//! `lamina view` end to end: every kind of file makes one self-contained page holding the scene
//! it should (objects, figures, sheets, layers, islands), the same bytes twice; bad input exits 2
//! and writes nothing. Headless Chromium opens the pages in scripts/test (check_viewer.py).

use std::path::Path;

use crate::common::{fixture, lamina, stderr, TestResult};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The scene a page embeds.
fn scene(page: &Path) -> Result<serde_json::Value, Box<dyn std::error::Error>> {
    let html = std::fs::read_to_string(page)?;
    let data = html
        .split("id=\"lamina-data\">")
        .nth(1)
        .and_then(|t| t.split("</script>").next())
        .ok_or("no lamina-data element")?;
    Ok(serde_json::from_str(data)?)
}

fn ids(layer: &serde_json::Value) -> Vec<String> {
    layer["objects"]
        .as_array()
        .map(|o| {
            o.iter()
                .map(|x| x["id"].as_str().unwrap_or("").to_string())
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn a_network_page_has_members_and_nodes_and_is_the_same_twice() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = fixture("networks/calyx_veins.json");
    let (a, b) = (dir.path().join("a.html"), dir.path().join("b.html"));
    for out in [&a, &b] {
        let o = lamina(&["view", s(&net), "-o", s(out)]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    assert_eq!(std::fs::read(&a)?, std::fs::read(&b)?, "deterministic");
    let sc = scene(&a)?;
    let layers = sc["layers"].as_array().ok_or("layers")?;
    assert_eq!(layers[0]["name"], "members");
    assert_eq!(layers[0]["objects"].as_array().map(Vec::len), Some(273));
    assert_eq!(layers[1]["objects"].as_array().map(Vec::len), Some(248));
    assert_eq!(ids(&layers[1])[12], "N12");
    let html = std::fs::read_to_string(&a)?;
    assert!(
        html.contains("three.js 0.185.1"),
        "the pinned version is named"
    );
    assert!(!html.contains("https://") || !html.contains("src=\"http"));
    Ok(())
}

#[test]
fn plates_with_welds_sizing_and_axes_and_their_cut_sheets() -> TestResult {
    let dir = tempfile::tempdir()?;
    let d = dir.path();
    let axes = d.join("axes.json");
    let o = lamina(&[
        "planarize",
        s(&fixture("networks/calyx_veins.json")),
        "--method",
        "newton",
        "--fix-normal",
        "z<1:0,0,1",
        "-o",
        s(&axes),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let sizing = d.join("sizing.json");
    let o = lamina(&[
        "size",
        s(&axes),
        "-o",
        s(&sizing),
        "--support",
        "z<1",
        "--load",
        "self-weight",
        "--groups",
        "5",
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let plates = d.join("plates");
    let o = lamina(&[
        "plates",
        s(&axes),
        "--sizing",
        s(&sizing),
        "--groups",
        "5",
        "-o",
        s(&plates),
    ]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    let welds_html = std::fs::read_to_string(plates.join("welds.html"))?;
    assert!(
        welds_html.contains("id=\"lamina-viewer\""),
        "welds.html embeds the viewer"
    );
    let page = d.join("plates.html");
    let o = lamina(&[
        "view",
        s(&plates.join("plates.json")),
        s(&sizing),
        "-o",
        s(&page),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let sc = scene(&page)?;
    let layers = sc["layers"].as_array().ok_or("layers")?;
    assert_eq!(layers[0]["name"], "plates");
    assert_eq!(layers[0]["colorings"][0]["name"], "utilisation");
    assert_eq!(layers[1]["name"], "welds");
    let plate_ids = ids(&layers[0]);
    assert!(plate_ids.iter().any(|i| i == "2-001"), "{plate_ids:?}");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(plates.join("welds.json"))?)?;
    assert_eq!(
        layers[1]["objects"].as_array().map(Vec::len),
        file["summary"]["pairs"].as_u64().map(|n| n as usize)
    );
    // The sheets: every placed part named on its sheet, in cut order.
    let cut = d.join("cut");
    let o = lamina(&[
        "nest",
        s(&plates.join("plates.json")),
        "--sheet",
        "3000x1500",
        "-o",
        s(&cut),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let sheets_page = d.join("sheets.html");
    let o = lamina(&["view", s(&cut.join("nest.json")), "-o", s(&sheets_page)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let sc = scene(&sheets_page)?;
    let nest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cut.join("nest.json"))?)?;
    let placed = nest["placements"].as_array().map(Vec::len).unwrap_or(0);
    let sheets = sc["sheets"].as_array().ok_or("sheets")?;
    let named: usize = sheets
        .iter()
        .map(|sh| {
            sh["parts"]
                .as_array()
                .map(|p| {
                    p.iter()
                        .filter(|x| !x["id"].as_str().unwrap_or("").starts_with("part "))
                        .count()
                })
                .unwrap_or(0)
        })
        .sum();
    assert_eq!(named, placed, "every placement found on its sheet");
    let orders: Vec<u64> = sheets[0]["parts"]
        .as_array()
        .ok_or("parts")?
        .iter()
        .filter_map(|p| p["order"].as_u64())
        .collect();
    assert_eq!(orders, (1..=orders.len() as u64).collect::<Vec<_>>());
    Ok(())
}

#[test]
fn print_layers_mark_the_island_prusaslicer_left() -> TestResult {
    let dir = tempfile::tempdir()?;
    let page = dir.path().join("p.html");
    let o = lamina(&[
        "view",
        s(&fixture("print/prusaslicer_hanging.sl1")),
        "-o",
        s(&page),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let p = &scene(&page)?["print"];
    assert_eq!(p["images"].as_array().map(Vec::len), Some(60));
    let islands = p["islands"].as_array().ok_or("islands")?;
    assert_eq!(islands.len(), 1);
    assert_eq!(islands[0]["layer"], 20);
    assert!(p["images"][30]
        .as_str()
        .is_some_and(|u| u.starts_with("data:image/png;base64,")));
    Ok(())
}

#[test]
fn bad_input_exits_2_and_writes_nothing() -> TestResult {
    let dir = tempfile::tempdir()?;
    let d = dir.path();
    let out = d.join("v.html");
    let junk = d.join("junk.sl1");
    std::fs::write(&junk, b"not a zip")?;
    let bad_plates = d.join("plates.json");
    std::fs::write(
        &bad_plates,
        br#"{"format": "lamina-plates", "version": 2, "plates": [{"id": "1-001"}]}"#,
    )?;
    let bad_nest = d.join("nest.json");
    std::fs::write(
        &bad_nest,
        br#"{"format": "lamina-nest", "version": 2, "sheets": [{"file": "../../etc/passwd", "thickness": 3, "size": [1, 1], "parts": [], "utilisation": 0, "cut_mm": 0, "pierces": 0, "etch_mm": 0}], "placements": []}"#,
    )?;
    // A cut DXF the dxf crate panics on (a header date out of its range, found by fuzzing).
    let dated = d.join("dated");
    std::fs::create_dir_all(&dated)?;
    std::fs::copy(
        fixture("fuzz/P7_dxf_julian_date/in.dxf"),
        dated.join("s.dxf"),
    )?;
    let dated_nest = dated.join("nest.json");
    std::fs::write(
        &dated_nest,
        br#"{"format": "lamina-nest", "version": 2, "sheets": [{"file": "s.dxf", "thickness": 3, "size": [100, 100], "parts": [], "utilisation": 0, "cut_mm": 0, "pierces": 0, "etch_mm": 0}], "placements": []}"#,
    )?;
    let net = fixture("networks/calyx_veins.json");
    let (missing, png, xyz) = (d.join("missing.json"), d.join("v.png"), d.join("x.xyz"));
    let cases: Vec<Vec<&str>> = vec![
        vec!["view", s(&missing), "-o", s(&out)],
        vec!["view", s(&junk), "-o", s(&out)],
        vec!["view", s(&bad_plates), "-o", s(&out)],
        vec!["view", s(&bad_nest), "-o", s(&out)],
        vec!["view", s(&net), "-o", s(&png)],
        vec!["view", s(&xyz), "-o", s(&out)],
        vec!["view", s(&net), "--weld=-1", "-o", s(&out)],
        vec!["view", s(&net), "--chord-tolerance", "nan", "-o", s(&out)],
        vec!["view", s(&dated_nest), "-o", s(&out)],
        // A reader flag where no file is read by the readers.
        vec!["view", s(&bad_nest), "--units", "in", "-o", s(&out)],
    ];
    for args in cases {
        let o = lamina(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("lamina: error:"), "{}", stderr(&o));
        assert!(!out.exists(), "{args:?} left a page");
    }
    Ok(())
}
