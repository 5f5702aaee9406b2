//! `lamina plates` end to end on the Calyx-like fixture's axes.

use std::path::Path;

use crate::common::{fixture, lamina, stderr, TestResult};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The Calyx fixture's axes (planarize with `extra` arguments) in `dir`/axes.json.
fn calyx_axes(
    dir: &Path,
    extra: &[&str],
) -> Result<std::path::PathBuf, Box<dyn std::error::Error>> {
    let axes = dir.join("axes.json");
    let net = fixture("networks/calyx_veins.json");
    let mut args = vec!["planarize", s(&net), "-o", s(&axes)];
    args.extend_from_slice(extra);
    let o = lamina(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    Ok(axes)
}

/// Runs `lamina plates` on `axes` into `dir`/plates and reads its plates.json.
fn plates_of(
    dir: &Path,
    axes: &Path,
    extra: &[&str],
) -> Result<(std::path::PathBuf, serde_json::Value), Box<dyn std::error::Error>> {
    let out = dir.join("plates");
    let mut args = vec!["plates", s(axes), "-o", s(&out)];
    args.extend_from_slice(extra);
    let o = lamina(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let doc = serde_json::from_str(&std::fs::read_to_string(out.join("plates.json"))?)?;
    Ok((out, doc))
}

#[test]
fn calyx_axes_become_closed_non_overlapping_plates() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &["--fix-normal", "z<1:0,0,1"])?;
    let (out, doc) = plates_of(dir.path(), &axes, &[])?;
    let plates = doc["plates"].as_array().ok_or("plates")?;
    assert_eq!(plates.len(), 273);
    // Thicker veins get thicker gauges: more than one gauge is used, all from the list.
    let mut gauges: Vec<f64> = plates
        .iter()
        .filter_map(|p| p["thickness"].as_f64())
        .collect();
    gauges.sort_by(f64::total_cmp);
    gauges.dedup();
    assert!(gauges.len() > 2, "{gauges:?}");
    assert!(gauges
        .iter()
        .all(|g| [1.5, 2.0, 3.0, 4.0, 5.0, 6.0].contains(g)));
    let mesh = lamina::mesh::io::read_mesh(&out.join("assembly.stl"))?;
    let topo = mesh.check_manifold();
    assert!(topo.closed && topo.is_manifold(), "{:?}", topo.problems);
    assert_eq!(topo.components, 273);
    let volume: f64 = plates
        .iter()
        .map(|p| p["area_mm2"].as_f64().unwrap_or(0.0) * p["thickness"].as_f64().unwrap_or(0.0))
        .sum();
    let stl = topo.volume.ok_or("volume")?;
    assert!((stl - volume).abs() < 1e-4 * volume, "{stl} vs {volume}");
    // One cut DXF per plate, in mm, its tag etched inside its outline; the OpenSCAD program
    // places every one of them.
    let scad = std::fs::read_to_string(out.join("assembly.scad"))?;
    assert_eq!(scad.matches("\npart(").count(), 273);
    let first = &plates[0];
    let id = first["id"].as_str().ok_or("id")?;
    let drawing = dxf::Drawing::load_file(out.join(format!("parts/{id}.dxf")))?;
    assert_eq!(
        drawing.header.default_drawing_units,
        dxf::enums::Units::Millimeters
    );
    let outline: Vec<[f64; 2]> = serde_json::from_value(first["outline"].clone())?;
    let inside = |x: f64, y: f64| {
        (0..outline.len()).all(|k| {
            let (a, b) = (outline[k], outline[(k + 1) % outline.len()]);
            (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]) > 0.0
        })
    };
    let mut etched = 0;
    for e in drawing.entities() {
        if let dxf::entities::EntityType::LwPolyline(l) = &e.specific {
            if e.common.layer != "ETCH" {
                continue;
            }
            assert!(l.vertices.iter().all(|v| inside(v.x, v.y)));
            etched += 1;
        }
    }
    assert!(etched > 5, "{etched} etched polylines");
    Ok(())
}

#[test]
fn bad_gauges_and_missing_axes_exit_2_with_nothing_written() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &[])?;
    let out = dir.path().join("plates");
    for (args, words) in [
        (vec!["--gauges", "3,2"], "ascending"),
        (vec!["--weld-gap=-1"], "--weld-gap"),
        (vec!["--weld-gap", "0"], "--weld-gap 0"),
        (
            vec!["--weld-gap", "0.2"],
            "--weld-gap-tolerance 0.5 mm is more than --weld-gap 0.2 mm",
        ),
        (
            vec!["--weld-gap", "0", "--node-core", "tube:60.3,4"],
            "--weld-gap-tolerance 0.5 mm is more than --weld-gap 0 mm",
        ),
        (vec!["--groups", "1000"], "--groups 1000"),
        (vec!["--thickness", "0"], "--thickness"),
        (vec!["--bolt-clearance", "0:40"], "--bolt-clearance"),
        (vec!["--bolt-clearance", "16:-1"], "--bolt-clearance"),
        (vec!["--bolt-clearance", "nan:40"], "--bolt-clearance"),
        (vec!["--bolt-clearance", "16:1e9"], "--bolt-clearance"),
        (vec!["--bolt-clearance", "16"], "--bolt-clearance"),
    ] {
        let mut all = vec!["plates", s(&axes), "-o", s(&out)];
        all.extend(args.iter().copied());
        let o = lamina(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(words), "{}", stderr(&o));
        assert!(!out.join("plates.json").exists());
    }
    // A gauge the sizing chose and the list lacks: the sizing file is named, not the axes.
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
    ]);
    assert!(sizing.exists(), "{}", stderr(&o));
    let o = lamina(&[
        "plates",
        s(&axes),
        "--sizing",
        s(&sizing),
        "--gauges",
        "7,9",
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let said = stderr(&o);
    assert!(
        said.contains(&format!("{}: the sizing's gauge", sizing.display())),
        "{said}"
    );
    assert!(!out.join("plates.json").exists());
    let network = fixture("networks/calyx_veins.json");
    let o = lamina(&["plates", s(&network), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("lamina-axes"), "{}", stderr(&o));
    Ok(())
}

#[test]
fn seven_groups_tag_every_plate_and_split_seams_in_half() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &[])?;
    let (_, doc) = plates_of(dir.path(), &axes, &["--groups", "7"])?;
    let plates = doc["plates"].as_array().ok_or("plates")?;
    let id = |p: &serde_json::Value| p["id"].as_str().unwrap_or("").to_string();
    let mut ids: Vec<String> = plates.iter().map(id).collect();
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), plates.len(), "tags are not unique");
    let mut per_group = [0usize; 7];
    let mut halves = 0;
    for p in plates {
        let g = p["group"].as_u64().ok_or("group")? as usize;
        assert!(
            id(p).starts_with(&format!("{g}-")),
            "{} in group {g}",
            id(p)
        );
        per_group[g - 1] += 1;
        if let Some(other) = p["bolted_to"].as_str() {
            halves += 1;
            let q = plates.iter().find(|q| id(q) == other).ok_or("partner")?;
            assert_eq!(q["bolted_to"].as_str(), Some(id(p).as_str()));
            assert_eq!(q["edge"], p["edge"]);
            assert_ne!(q["group"], p["group"]);
            // Welded at one end only, its own group's node; it passes the other unwelded.
            let welded = p["ends"]
                .as_array()
                .ok_or("ends")?
                .iter()
                .filter(|e| {
                    e["welded_to"].as_array().is_some_and(|w| !w.is_empty()) || !e["core"].is_null()
                })
                .count();
            assert_eq!(welded, 1, "{} is welded at {welded} ends", id(p));
        }
        // No weld joins two groups.
        for e in p["ends"].as_array().ok_or("ends")? {
            for w in e["welded_to"].as_array().ok_or("welded_to")? {
                let q = plates.iter().find(|q| q["id"] == *w).ok_or("partner")?;
                assert_eq!(q["group"], p["group"], "{} welded to {w}", id(p));
            }
        }
    }
    assert_eq!(plates.len(), 273 + halves / 2);
    let mean = plates.len() as f64 / 7.0;
    for (g, &n) in per_group.iter().enumerate() {
        assert!(
            (n as f64 - mean).abs() <= 0.25 * mean,
            "group {}: {n} plates, mean {mean:.1}",
            g + 1
        );
    }
    Ok(())
}

/// `lamina nest` on `plates` into `dir`/`name`; returns the folder and nest.json.
fn nest_of(
    dir: &Path,
    plates: &Path,
    name: &str,
    extra: &[&str],
) -> Result<(std::path::PathBuf, serde_json::Value), Box<dyn std::error::Error>> {
    let out = dir.join(name);
    let mut args = vec!["nest", s(plates), "-o", s(&out)];
    args.extend_from_slice(extra);
    let o = lamina(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let doc = serde_json::from_str(&std::fs::read_to_string(out.join("nest.json"))?)?;
    Ok((out, doc))
}

#[test]
fn nesting_puts_each_thickness_on_its_own_sheets_and_repeats_exactly() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &["--fix-normal", "z<1:0,0,1"])?;
    let (plates_dir, plates) = plates_of(dir.path(), &axes, &["--groups", "7"])?;
    let file = plates_dir.join("plates.json");
    let (cut, nest) = nest_of(dir.path(), &file, "cut", &["--tries", "2"])?;
    let list = plates["plates"].as_array().ok_or("plates")?;
    let thickness: std::collections::HashMap<&str, f64> = list
        .iter()
        .map(|p| {
            (
                p["id"].as_str().unwrap_or(""),
                p["thickness"].as_f64().unwrap_or(0.0),
            )
        })
        .collect();
    let mut gauges: Vec<f64> = thickness.values().copied().collect();
    gauges.sort_by(f64::total_cmp);
    gauges.dedup();
    let sheets = nest["sheets"].as_array().ok_or("sheets")?;
    // Calyx fits one sheet per thickness.
    assert_eq!(sheets.len(), gauges.len());
    let mut count = 0;
    for sheet in sheets {
        let t = sheet["thickness"].as_f64().ok_or("thickness")?;
        for id in sheet["parts"].as_array().ok_or("parts")? {
            assert_eq!(thickness[id.as_str().ok_or("id")?], t);
            count += 1;
        }
        assert!(cut.join(sheet["file"].as_str().ok_or("file")?).exists());
    }
    assert_eq!(count, list.len());
    let bom = std::fs::read_to_string(cut.join("bom.csv"))?;
    let plate_rows = bom.lines().filter(|l| l.starts_with("plate,")).count();
    assert_eq!(plate_rows, list.len());
    let scad = std::fs::read_to_string(cut.join("assembly.scad"))?;
    assert_eq!(scad.matches("\npart(").count(), list.len());
    // The same input and seed give the same bytes.
    let (again, _) = nest_of(dir.path(), &file, "again", &["--tries", "2"])?;
    for name in ["nest.json", "bom.csv", "assembly.scad", "sheets.svg"] {
        assert_eq!(
            std::fs::read(cut.join(name))?,
            std::fs::read(again.join(name))?,
            "{name}"
        );
    }
    for sheet in sheets {
        let f = sheet["file"].as_str().ok_or("file")?;
        assert_eq!(
            std::fs::read(cut.join(f))?,
            std::fs::read(again.join(f))?,
            "{f}"
        );
    }
    // Groups kept together: every sheet holds one group.
    let (_, grouped) = nest_of(
        dir.path(),
        &file,
        "grouped",
        &["--keep-groups", "--tries", "1"],
    )?;
    for sheet in grouped["sheets"].as_array().ok_or("sheets")? {
        let g = sheet["group"].as_u64().ok_or("group")?;
        for id in sheet["parts"].as_array().ok_or("parts")? {
            assert!(id.as_str().ok_or("id")?.starts_with(&format!("{g}-")));
        }
    }
    Ok(())
}

#[test]
fn a_plate_larger_than_the_sheet_and_bad_spacing_exit_2_with_nothing_written() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &["--fix-normal", "z<1:0,0,1"])?;
    let (plates_dir, plates) = plates_of(dir.path(), &axes, &[])?;
    let file = plates_dir.join("plates.json");
    let out = dir.path().join("cut");
    // The longest plate is over 600 mm: a 500 × 400 sheet cannot take it.
    let o = lamina(&["nest", s(&file), "--sheet", "500x400", "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("fit no 500 × 400 mm sheet"), "{err}");
    // Narrow sheets full of long plates leave some no room for a long label: it says which.
    let narrow = dir.path().join("narrow");
    let job = [
        "--job",
        "A JOB NAME TOO LONG FOR A NARROW SHEET",
        "--tries",
        "1",
        "--time",
        "0.1",
    ];
    let o = lamina(
        &[
            &["nest", s(&file), "--sheet", "700x300", "-o", s(&narrow)],
            &job[..],
        ]
        .concat(),
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(narrow.join("nest.json"))?)?;
    let bare: Vec<&str> = doc["sheets"]
        .as_array()
        .ok_or("sheets")?
        .iter()
        .filter(|s| s["label"].is_null())
        .filter_map(|s| s["file"].as_str())
        .collect();
    let said = stderr(&o);
    assert!(!bare.is_empty(), "every sheet took the label");
    assert!(
        said.contains(&format!("{} sheet(s) carry no label", bare.len()))
            && bare.iter().all(|f| said.contains(f)),
        "{said}"
    );
    let long = plates["plates"]
        .as_array()
        .ok_or("plates")?
        .iter()
        .find(|p| {
            let xs: Vec<f64> = p["outline"]
                .as_array()
                .map(|o| o.iter().filter_map(|q| q[0].as_f64()).collect())
                .unwrap_or_default();
            xs.iter().cloned().fold(f64::MIN, f64::max)
                - xs.iter().cloned().fold(f64::MAX, f64::min)
                > 500.0
        })
        .ok_or("a long plate")?;
    assert!(err.contains(long["id"].as_str().ok_or("id")?), "{err}");
    assert!(!out.exists(), "nothing is written");
    for bad in [
        vec!["--spacing", "-1"],
        vec!["--sheet", "3000"],
        vec!["--margin", "800"],
        vec!["--rotations", "0,ninety"],
        vec!["--micro-joints", "0"],
        vec!["--micro-joints", "9"],
        vec!["--micro-joints", "2", "--micro-joint-width", "NaN"],
        vec!["--micro-joints", "2", "--micro-joint-width", "0"],
        vec!["--micro-joint-below", "-5"],
        vec!["--micro-joint-below", "1e300"],
        vec!["--kerf", "5"],
        vec!["--kerf", "7", "--spacing", "5"],
        vec!["--kerf", "NaN"],
        vec!["--kerf", "-0.1"],
        vec!["--nc", "gcode", "--post", "fanuc"],
        vec!["--nc", "essi", "--post", "linuxcnc"],
        vec!["--post", "linuxcnc"],
        vec!["--nc", "gcode", "--nc-on", ""],
        vec!["--nc", "lasercut"],
        vec!["--cut-order", "random"],
        vec!["--common-line"],
        vec!["--common-line", "--kerf", "0.3", "--no-pairs"],
        vec!["--common-line", "--kerf", "0.3", "--micro-joints", "2"],
        vec!["--job", ""],
        vec!["--date", "a date far too long for a label"],
        vec!["--time", "0"],
        vec!["--time", "NaN"],
        vec!["--time", "1e9"],
    ] {
        let mut args = vec!["nest", s(&file), "-o", s(&out)];
        args.extend_from_slice(&bad);
        let o = lamina(&args);
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
        assert!(!out.exists(), "{bad:?}: nothing is written");
    }
    // Not a plates file: named as such.
    let o = lamina(&["nest", s(&axes), "-o", s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not lamina-plates"), "{}", stderr(&o));
    Ok(())
}

#[test]
fn nc_programs_cut_what_the_sheets_draw_in_a_shorter_order() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &["--fix-normal", "z<1:0,0,1"])?;
    let (plates_dir, _) = plates_of(dir.path(), &axes, &["--groups", "7"])?;
    let file = plates_dir.join("plates.json");
    let args = [
        "--tries",
        "1",
        "--lead-in",
        "2",
        "--kerf",
        "0.4",
        "--job",
        "T1",
    ];
    let mut gcode = args.to_vec();
    gcode.extend(["--nc", "gcode", "--nc-on", "M3 S77"]);
    let (cut, travel) = nest_of(dir.path(), &file, "gcode", &gcode)?;
    let mut spread_args = args.to_vec();
    spread_args.extend(["--cut-order", "spread", "--nc", "essi"]);
    let (spread_dir, spread) = nest_of(dir.path(), &file, "essi", &spread_args)?;
    let sheets = travel["sheets"].as_array().ok_or("sheets")?;
    for (k, sheet) in sheets.iter().enumerate() {
        let name = sheet["file"].as_str().ok_or("file")?.replace(".dxf", "");
        let text = std::fs::read_to_string(cut.join(format!("{name}.ngc")))?;
        // Every contour pierced once with the torch line asked for, after all the marking.
        let pierces = sheet["pierces"].as_u64().ok_or("pierces")? as usize;
        assert_eq!(text.lines().filter(|l| *l == "M3 S77").count(), pierces);
        let lines: Vec<&str> = text.lines().collect();
        let last_mark = lines.iter().rposition(|l| *l == "M7").ok_or("marking")?;
        let first_cut = lines.iter().position(|l| *l == "M3 S77").ok_or("cutting")?;
        assert!(last_mark < first_cut, "{name}: marking after cutting began");
        assert!(text.contains("(contours offset 0.200 mm for the kerf"));
        let label = sheet["label"].as_str().ok_or("label")?;
        assert!(
            label.starts_with(&format!("T1 SHEET {}/{}", k + 1, sheets.len())),
            "{label}"
        );
        assert!(spread_dir.join(format!("{name}.esi")).exists());
    }
    // Spreading the heat costs travel.
    let rapid = |d: &serde_json::Value| d["total"]["rapid_mm"].as_f64().unwrap_or(f64::NAN);
    assert!(
        rapid(&spread) > 1.5 * rapid(&travel),
        "{} vs {}",
        rapid(&spread),
        rapid(&travel)
    );
    // The DXFs stay nominal and say so.
    let dxf = std::fs::read_to_string(cut.join(sheets[0]["file"].as_str().ok_or("file")?))?;
    assert!(dxf.contains("nominal contours: the NC programs offset them by half the 0.4 mm kerf"));
    Ok(())
}

#[test]
fn common_lines_cut_a_shared_side_once_from_the_first_parts_kerf() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &["--fix-normal", "z<1:0,0,1"])?;
    let (plates_dir, _) = plates_of(dir.path(), &axes, &["--groups", "7"])?;
    // Every quad twice: a congruent copy, as a symmetric structure's plates come.
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(plates_dir.join("plates.json"))?)?;
    let list = doc["plates"].as_array().ok_or("plates")?.clone();
    let mut twins = Vec::new();
    for p in list {
        let quad = p["outline"].as_array().is_some_and(|o| o.len() == 4);
        twins.push(p.clone());
        if quad {
            let mut q = p;
            q["id"] = format!("{}b", q["id"].as_str().ok_or("id")?).into();
            twins.push(q);
        }
    }
    doc["plates"] = twins.into();
    let file = dir.path().join("twins.json");
    std::fs::write(&file, serde_json::to_string(&doc)?)?;
    let base = ["--tries", "1", "--kerf", "0.3", "--nc", "gcode"];
    let (_, apart) = nest_of(dir.path(), &file, "apart", &base)?;
    let mut args = base.to_vec();
    args.push("--common-line");
    let (cut, common) = nest_of(dir.path(), &file, "common", &args)?;
    let total = |d: &serde_json::Value, k: &str| d["total"][k].as_f64().unwrap_or(f64::NAN);
    let lines = total(&common, "common_lines");
    assert!(lines >= 100.0, "{lines} common lines");
    assert_eq!(total(&apart, "common_lines"), 0.0);
    // The same contours less each shared side, one pierce fewer a pair.
    let saved = total(&apart, "cut_mm") - total(&common, "cut_mm");
    assert!(
        (saved - total(&common, "common_mm")).abs() < 1e-6 * total(&apart, "cut_mm"),
        "{saved} vs {}",
        total(&common, "common_mm")
    );
    assert_eq!(total(&apart, "pierces") - total(&common, "pierces"), lines);
    let mut from_kerf = 0;
    for sheet in common["sheets"].as_array().ok_or("sheets")? {
        let name = sheet["file"]
            .as_str()
            .ok_or("file")?
            .replace(".dxf", ".ngc");
        let text = std::fs::read_to_string(cut.join(name))?;
        from_kerf += text
            .lines()
            .filter(|l| l.starts_with("(outer contour from the common line's kerf, no pierce"))
            .count();
        for c in sheet["common_lines"].as_array().ok_or("common_lines")? {
            let len = c["length_mm"].as_f64().unwrap_or(0.0);
            assert!(len > 10.0, "{c}");
        }
    }
    assert_eq!(from_kerf as f64, lines);
    Ok(())
}

#[test]
fn micro_joints_shorten_the_cut_add_pierces_and_leave_no_assembly_to_rebuild() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &["--fix-normal", "z<1:0,0,1"])?;
    let (plates_dir, _) = plates_of(dir.path(), &axes, &["--groups", "7"])?;
    let file = plates_dir.join("plates.json");
    let (plain_dir, plain) = nest_of(dir.path(), &file, "cut", &["--tries", "1"])?;
    assert!(plain_dir.join("assembly.scad").exists());
    // Into the same folder: the old assembly (of closed contours) must not survive.
    let (cut, jointed) = nest_of(
        dir.path(),
        &file,
        "cut",
        &[
            "--tries",
            "1",
            "--micro-joints",
            "3",
            "--micro-joint-width",
            "0.8",
        ],
    )?;
    assert!(!cut.join("assembly.scad").exists());
    let total = |d: &serde_json::Value, k: &str| d["total"][k].as_f64().unwrap_or(f64::NAN);
    let joints: u64 = jointed["placements"]
        .as_array()
        .ok_or("placements")?
        .iter()
        .filter_map(|p| p["micro_joints"].as_u64())
        .sum();
    assert!(joints > 0, "some Calyx plates are under 200 mm");
    let shorter = total(&plain, "cut_mm") - total(&jointed, "cut_mm");
    assert!(
        (shorter - 0.8 * joints as f64).abs() < 1e-6,
        "{shorter} for {joints} joints"
    );
    assert_eq!(
        total(&jointed, "pierces") - total(&plain, "pierces"),
        joints as f64
    );
    Ok(())
}

#[test]
fn the_material_travels_from_the_sizing_to_the_cut_files() -> TestResult {
    let dir = tempfile::tempdir()?;
    let axes = calyx_axes(dir.path(), &[])?;
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
        "--material",
        "s355",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // A plates grade other than the sizing's is refused, naming the flag; nothing written.
    let wrong = dir.path().join("wrong");
    let o = lamina(&[
        "plates",
        s(&axes),
        "--sizing",
        s(&sizing),
        "--material",
        "1.4404",
        "-o",
        s(&wrong),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--material"), "{}", stderr(&o));
    assert!(!wrong.exists());
    let (out, doc) = plates_of(dir.path(), &axes, &["--sizing", s(&sizing)])?;
    assert_eq!(doc["material"]["grade"], "S355");
    assert_eq!(doc["material"]["density"], 7.85);
    let cut = dir.path().join("cut");
    let o = lamina(&[
        "nest",
        s(&out.join("plates.json")),
        "--sheet",
        "3000x1500",
        "-o",
        s(&cut),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let nest: serde_json::Value = serde_json::from_slice(&std::fs::read(cut.join("nest.json"))?)?;
    assert_eq!(nest["material"]["grade"], "S355");
    assert!(nest["speed_table"]["material"]
        .as_str()
        .is_some_and(|m| m.starts_with("carbon steel")));
    let bom = std::fs::read_to_string(cut.join("bom.csv"))?;
    let header: Vec<&str> = bom.lines().next().ok_or("a header")?.split(',').collect();
    let grade = header
        .iter()
        .position(|h| *h == "grade")
        .ok_or("a grade column")?;
    for row in bom.lines().skip(1).filter(|r| r.starts_with("plate,")) {
        assert_eq!(row.split(',').nth(grade), Some("\"S355\""), "{row}");
    }
    let sheet = nest["sheets"][0]["file"].as_str().ok_or("a sheet")?;
    let dxf = std::fs::read_to_string(cut.join(sheet))?;
    let mut lines = dxf.lines();
    assert_eq!(lines.next(), Some("999"));
    assert!(
        lines.next().is_some_and(|l| l.starts_with("S355 ")),
        "{dxf:.80}"
    );
    Ok(())
}
