//! `lamina planarize` and `lamina audit` end to end on the Calyx-like venation fixture.

use std::path::Path;

use crate::common::{fixture, lamina, stderr, stdout, TestResult};
use glam::DVec3;
use lamina::rationalize::axes::read_axes;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn report(path: &Path) -> Result<serde_json::Value, Box<dyn std::error::Error>> {
    Ok(serde_json::from_str(&std::fs::read_to_string(path)?)?)
}

#[test]
fn every_method_planarizes_the_calyx_fixture_with_flat_base_plates() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = fixture("networks/calyx_veins.json");
    let mut axes = Vec::new();
    for method in ["lbfgs", "projection", "newton"] {
        let out = dir.path().join(format!("{method}.json"));
        let rep = dir.path().join(format!("{method}.report.json"));
        let html = dir.path().join(format!("{method}.html"));
        let o = lamina(&[
            "planarize",
            s(&net),
            "--method",
            method,
            "--height",
            "100",
            "--tolerance",
            "0.01",
            "--fix-normal",
            "z<1:0,0,1",
            "-o",
            s(&out),
            "--report",
            s(&rep),
            "--html",
            s(&html),
        ]);
        assert_eq!(o.status.code(), Some(0), "{method}: {}", stderr(&o));
        let r = report(&rep)?;
        let max = r["summary"]["max_deviation"].as_f64().ok_or("max")?;
        assert!(max < 0.01, "{method}: {max} mm");
        assert_eq!(r["summary"]["panels"], 273);
        let a = read_axes(&out)?;
        // Base plates: edges with both ends on z = 0 hold panels whose normal is +Z.
        let mut base = 0;
        for (k, &[i, j]) in a.edges.iter().enumerate() {
            if a.fixed_normals[k].is_none() {
                continue;
            }
            base += 1;
            let e = a.positions[j as usize] - a.positions[i as usize];
            let n = e.cross(a.axes[i as usize]).normalize();
            let off = n.dot(DVec3::Z).abs().min(1.0).acos().to_degrees();
            assert!(off < 0.01, "{method}: base panel {k} is {off}° off +Z");
        }
        assert_eq!(base, 4, "the base ring");
        let page = std::fs::read_to_string(&html)?;
        assert!(page.contains("<svg") && page.contains("All 273 panels are within"));
        axes.push(a.axes);
    }
    // All land on the planar configuration nearest the references (measured: projection 0.08°
    // from L-BFGS; the paper's plain sweep, moving to the mean of the projections, lands 1.5°
    // away).
    for other in &axes[1..] {
        let worst = axes[0]
            .iter()
            .zip(other)
            .map(|(a, b)| a.dot(*b).clamp(-1.0, 1.0).acos().to_degrees())
            .fold(0.0, f64::max);
        assert!(worst < 1.0, "the methods' axes differ by {worst}°");
    }
    Ok(())
}

#[test]
fn audit_reproduces_the_deviation_and_sets_the_exit_status() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = fixture("networks/calyx_veins.json");
    let (out, panels, rep) = (
        dir.path().join("axes.json"),
        dir.path().join("panels.obj"),
        dir.path().join("report.json"),
    );
    let o = lamina(&[
        "planarize",
        s(&net),
        "-o",
        s(&out),
        "--panels",
        s(&panels),
        "--report",
        s(&rep),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let planarized = report(&rep)?["summary"]["max_deviation"]
        .as_f64()
        .ok_or("max")?;
    let audit_rep = dir.path().join("audit.json");
    let o = lamina(&[
        "audit",
        s(&panels),
        "--tolerance",
        "0.01",
        "--report",
        s(&audit_rep),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // audit holds flatness by default; the corner figure is planarize's.
    let audited = report(&audit_rep)?["summary"]["max_corner"]
        .as_f64()
        .ok_or("max")?;
    assert!(
        (audited - planarized).abs() <= 1e-9,
        "{audited} vs {planarized}"
    );
    // A tighter tolerance than the panels meet: exit 1, with the report still written.
    let o = lamina(&["audit", s(&panels), "--tolerance", "0.0001", "--json"]);
    assert_eq!(o.status.code(), Some(1));
    let summary: serde_json::Value = serde_json::from_str(&stdout(&o))?;
    assert!(summary["above_tolerance"].as_u64().ok_or("count")? > 0);
    // Not a panels file: exit 2.
    let o = lamina(&["audit", s(&fixture("bad/garbage.dxf")), "--tolerance", "1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("garbage.dxf"));
    Ok(())
}

#[test]
fn a_guide_surface_gives_the_references() -> TestResult {
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("axes.json");
    let o = lamina(&[
        "planarize",
        s(&fixture("networks/calyx_veins.json")),
        "--surface",
        s(&fixture("surfaces/calyx.obj")),
        "-o",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let a = read_axes(&out)?;
    // The mesh's normals are close to the analytic ones the fixture stores (25 × 100 facets).
    let net = lamina::network::io::read_network(
        &fixture("networks/calyx_veins.json"),
        &Default::default(),
    )?
    .network;
    for (r, n) in a.reference.iter().zip(&net.nodes) {
        let stored = n.normal.ok_or("normal")?;
        assert!(r.dot(stored) > 0.99, "reference {r} vs stored {stored}");
    }
    Ok(())
}

#[test]
fn bad_networks_exit_2_naming_the_problem() -> TestResult {
    let dir = tempfile::tempdir()?;
    let write = |name: &str, text: &str| -> std::io::Result<std::path::PathBuf> {
        let p = dir.path().join(name);
        std::fs::write(&p, text)?;
        Ok(p)
    };
    let head = "{\"format\": \"lamina-network\", \"version\": 1, ";
    let zero = write(
        "zero.json",
        &format!("{head}\"nodes\": [{{\"p\": [0,0,0], \"normal\": [0,0,1]}}, {{\"p\": [0,0,0], \"normal\": [0,0,1]}}], \"edges\": [{{\"a\": 0, \"b\": 1}}]}}"),
    )?;
    let bare = write(
        "bare.json",
        &format!("{head}\"nodes\": [{{\"p\": [0,0,0]}}, {{\"p\": [1,0,0]}}, {{\"p\": [0,1,0]}}, {{\"p\": [0,0,1]}}], \"edges\": [{{\"a\": 0, \"b\": 1}}, {{\"a\": 1, \"b\": 2}}, {{\"a\": 2, \"b\": 3}}]}}"),
    )?;
    let ok = write(
        "ok.json",
        &format!("{head}\"nodes\": [{{\"p\": [0,0,0], \"normal\": [0,0,1]}}, {{\"p\": [1,0,0], \"normal\": [0,0,1]}}], \"edges\": [{{\"a\": 0, \"b\": 1}}]}}"),
    )?;
    let out = dir.path().join("never.json");
    for (input, args, words) in [
        (&zero, vec![], vec!["edge 0", "zero-length"]),
        // No normals and not flat (a flat network takes its plane's normal).
        (&bare, vec![], vec!["node 0", "not flat", "--surface"]),
        (&ok, vec!["--fix-normal", "z<:0,0,1"], vec!["--fix-normal"]),
        (&ok, vec!["--fix-axis", "node=0:0,0"], vec!["--fix-axis"]),
        (&ok, vec!["--tolerance", "0"], vec!["--tolerance"]),
        (&ok, vec!["--height=-5"], vec!["height"]),
        // So tall the panel figures overflow (it was reported planar at zero deviation).
        (
            &ok,
            vec!["--height", "1e300"],
            vec!["height 1e300", "at most"],
        ),
        (&ok, vec!["--height", "nan"], vec!["height NaN"]),
    ] {
        let mut all = vec!["planarize", s(input), "-o", s(&out)];
        all.extend(args.iter().copied());
        let o = lamina(&all);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        for w in words {
            assert!(e.contains(w), "expected \"{w}\" in: {e}");
        }
        assert!(!out.exists());
    }
    Ok(())
}

#[test]
fn a_degree_four_node_is_reported() -> TestResult {
    let dir = tempfile::tempdir()?;
    // A star: node 0 with four legs.
    let text = "{\"format\": \"lamina-network\", \"version\": 1, \"nodes\": [\
        {\"p\": [0,0,0], \"normal\": [0,0,1]}, {\"p\": [10,0,1], \"normal\": [0,0,1]},\
        {\"p\": [0,10,-1], \"normal\": [0,0,1]}, {\"p\": [-10,0,2], \"normal\": [0,0,1]},\
        {\"p\": [0,-10,0.5], \"normal\": [0,0,1]}], \"edges\": [\
        {\"a\": 0, \"b\": 1}, {\"a\": 0, \"b\": 2}, {\"a\": 0, \"b\": 3}, {\"a\": 0, \"b\": 4}]}";
    let input = dir.path().join("star.json");
    std::fs::write(&input, text)?;
    let out = dir.path().join("axes.json");
    let o = lamina(&["planarize", s(&input), "-o", s(&out), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout(&o))?;
    assert_eq!(v["summary"]["over_constrained"], serde_json::json!([0]));
    Ok(())
}

/// DXF panels as other programs draw them: a 3DFACE, a closed 3D POLYLINE, and a closed
/// LWPOLYLINE in a tilted object coordinate system (a planar quad, so deviation 0, whose corners
/// must come out in world coordinates).
#[test]
fn audit_reads_dxf_faces_and_closed_polylines() -> TestResult {
    use dxf::entities::{Entity, EntityType, Face3D, LwPolyline, Polyline, Vertex};
    use dxf::{LwPolylineVertex, Point, Vector};
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("panels.dxf");
    let warped = [
        Point::new(0.0, 0.0, 0.0),
        Point::new(10.0, 0.0, 0.0),
        Point::new(10.0, 10.0, 0.5),
        Point::new(0.0, 10.0, 0.0),
    ];
    let mut drawing = dxf::Drawing::new();
    drawing.header.version = dxf::enums::AcadVersion::R2000;
    // The crate's default header says imperial ($MEASUREMENT 0, no $INSUNITS): say mm.
    drawing.header.default_drawing_units = dxf::enums::Units::Millimeters;
    drawing.add_entity(Entity::new(EntityType::Face3D(Face3D::new(
        warped[0].clone(),
        warped[1].clone(),
        warped[2].clone(),
        warped[3].clone(),
    ))));
    let mut pl = Polyline::default();
    pl.set_is_3d_polyline(true);
    pl.set_is_closed(true);
    for p in &warped {
        pl.add_vertex(&mut drawing, Vertex::new(p.clone()));
    }
    drawing.add_entity(Entity::new(EntityType::Polyline(pl)));
    let mut lw = LwPolyline::default();
    lw.set_is_closed(true);
    lw.extrusion_direction = Vector::new(1.0, 1.0, 1.0);
    for (x, y) in [(0.0, 0.0), (20.0, 0.0), (20.0, 5.0), (0.0, 5.0)] {
        lw.vertices.push(LwPolylineVertex {
            x,
            y,
            ..Default::default()
        });
    }
    let mut e = Entity::new(EntityType::LwPolyline(lw));
    e.common.elevation = 3.0;
    drawing.add_entity(e);
    drawing.save_file(&path)?;

    let rep = dir.path().join("audit.json");
    let o = lamina(&[
        "audit",
        s(&path),
        "--tolerance",
        "0.01",
        "--report",
        s(&rep),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "the warped quads exceed 0.01 mm: {}",
        stderr(&o)
    );
    let r = report(&rep)?;
    let panels = r["panels"].as_array().ok_or("panels")?;
    assert_eq!(panels.len(), 3);
    // The fourth corner's distance from the plane of the other three (q0, q1, q3 span z = 0).
    for p in &panels[..2] {
        let d = p["deviation"].as_f64().ok_or("deviation")?;
        assert!((d - 0.5).abs() < 1e-12, "{d}");
    }
    assert!(panels[2]["deviation"].as_f64().ok_or("deviation")? < 1e-12);
    // The LWPOLYLINE's corners lie 3 mm along its extrusion direction from the origin.
    let n = DVec3::ONE.normalize();
    let html = dir.path().join("audit.html");
    let o = lamina(&["audit", s(&path), "--tolerance", "1", "--html", s(&html)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let read = lamina::rationalize::audit::read_panels(&path)?;
    let polygons: Vec<_> = read.panels.iter().map(|p| &p.corners).collect();
    for c in polygons[2] {
        assert!(
            (c.dot(n) - 3.0).abs() < 1e-12,
            "{c} is not on the plane 3 mm along n"
        );
    }
    assert!(((polygons[2][1] - polygons[2][0]).length() - 20.0).abs() < 1e-12);
    Ok(())
}

#[test]
fn audit_holds_iso_flatness_by_default_and_writes_a_row_per_panel() -> TestResult {
    let dir = tempfile::tempdir()?;
    let obj = dir.path().join("mixed.obj");
    // A square 1000 mm twisted by w = 0.4 mm (corners alternate ±w/2), a planar hexagon, a
    // triangle and a quad with a repeated corner (both skipped, counted), CRLF line ends.
    let w = 0.4;
    let mut text = String::new();
    for (x, y, z) in [
        (0.0, 0.0, w / 2.0),
        (1000.0, 0.0, -w / 2.0),
        (1000.0, 1000.0, w / 2.0),
        (0.0, 1000.0, -w / 2.0),
    ] {
        text += &format!("v {x} {y} {z}\r\n");
    }
    for k in 0..6 {
        let t = std::f64::consts::TAU * k as f64 / 6.0;
        text += &format!(
            "v {} {} {}\r\n",
            100.0 * t.cos(),
            0.5 * t.sin(),
            100.0 * t.sin()
        );
    }
    text += "v 5 5 5\r\nv 6 5 5\r\nv 5 6 9\r\n";
    text += "f 1 2 3 4\r\nf 5 6 7 8 9 10\r\nf 11 12 13\r\nf 11 12 12 13\r\n";
    std::fs::write(&obj, text)?;
    let csv = dir.path().join("panels.csv");
    let json = dir.path().join("audit.json");
    let o = lamina(&[
        "audit",
        s(&obj),
        "--tolerance",
        "0.5",
        "--csv",
        s(&csv),
        "--report",
        s(&json),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("2 of 4 faces have fewer than 4 distinct corners"));
    assert!(stdout(&o).contains("max flatness 0.4"), "{}", stdout(&o));
    let r = report(&json)?;
    assert_eq!(r["summary"]["metric"], "flatness");
    assert_eq!(r["summary"]["panels"], 2);
    let rows = r["panels"].as_array().ok_or("panels")?;
    assert!((rows[0]["flatness"].as_f64().ok_or("f")? - w).abs() < 1e-9);
    assert!(rows[1]["flatness"].as_f64().ok_or("f")? < 1e-9);
    assert!(r["definitions"]["flatness"]
        .as_str()
        .ok_or("def")?
        .contains("ISO 1101"));
    let table = std::fs::read_to_string(&csv)?;
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 3);
    assert!(lines[0].starts_with("panel,name,layer,group,corners,flatness_mm"));
    assert!(lines[1].starts_with("0,,,,4,") && lines[1].ends_with(",flatness,,0.5,pass"));
    assert!(lines[2].starts_with("1,,,,6,"));
    // The corner figure is about 2w: over 0.5 mm, so held to it the audit fails.
    let o = lamina(&["audit", s(&obj), "--tolerance", "0.5", "--metric", "corner"]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    let o = lamina(&[
        "audit",
        s(&obj),
        "--tolerance",
        "0.5",
        "--metric",
        "best-fit",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    Ok(())
}

#[test]
fn audit_holds_each_panel_to_its_tolerance_class() -> TestResult {
    let dir = tempfile::tempdir()?;
    let rules = fixture("panels/glass_rules.json");
    // ezdxf's MESH (2 faces, GLASS-MESH), polyface (STEEL), 3DFACE (GLASS-N), a closed
    // LWPOLYLINE hexagon (STEEL), an open LWPOLYLINE and a TEXT; in inches.
    let dxf = fixture("panels/ezdxf_panels.dxf");
    let (json, csv) = (dir.path().join("dxf.json"), dir.path().join("dxf.csv"));
    let o = lamina(&[
        "audit",
        s(&dxf),
        "--tolerance-rules",
        s(&rules),
        "--report",
        s(&json),
        "--csv",
        s(&csv),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("1 TEXT, 1 open LWPOLYLINE"), "{err}");
    assert!(err.contains("in ($INSUNITS = 1), ×25.4 to mm"), "{err}");
    let r = report(&json)?;
    let rows = r["panels"].as_array().ok_or("panels")?;
    assert_eq!(rows.len(), 5);
    let by_layer = |layer: &'static str| rows.iter().filter(move |p| p["layer"] == layer);
    // The 3DFACE: a 10 in square with one corner 0.04 in up. Its zone is h/2 thick along a
    // normal tilted from z: w = (h/2) / sqrt(1 + 2 (h / 2s)²); held to 0.0003 × its diagonal.
    let (h, side): (f64, f64) = (0.04 * 25.4, 10.0 * 25.4);
    let face = by_layer("GLASS-N").next().ok_or("3DFACE")?;
    let w = (h / 2.0) / (1.0 + 2.0 * (h / (2.0 * side)).powi(2)).sqrt();
    assert!(
        (face["flatness"].as_f64().ok_or("f")? - w).abs() < 1e-12,
        "{face}"
    );
    let diagonal = (2.0 * side * side + h * h).sqrt();
    assert!((face["tolerance"].as_f64().ok_or("t")? - 3e-4 * diagonal).abs() < 1e-12);
    assert_eq!(face["class"], "glass (layer)");
    assert_eq!(face["pass"], false);
    // The MESH's two faces keep its layer and are named by its handle and face number.
    let mesh: Vec<_> = by_layer("GLASS-MESH").collect();
    assert_eq!(mesh.len(), 2);
    assert!(mesh[0]["name"].as_str().ok_or("name")?.ends_with("/0"));
    assert!(mesh[1]["name"].as_str().ok_or("name")?.ends_with("/1"));
    // STEEL: the polyface face within the default 0.5 mm, the hexagon exactly planar.
    let steel: Vec<_> = by_layer("STEEL").collect();
    assert_eq!(steel.len(), 2);
    assert!(steel
        .iter()
        .all(|p| p["class"] == "default" && p["pass"] == true));
    assert!(steel.iter().any(|p| p["flatness"] == 0.0));
    let classes = r["summary"]["classes"].as_array().ok_or("classes")?;
    let counts: Vec<(&str, u64)> = classes
        .iter()
        .map(|c| {
            (
                c["name"].as_str().unwrap_or(""),
                c["panels"].as_u64().unwrap_or(0),
            )
        })
        .collect();
    assert_eq!(
        counts,
        [
            ("glass (layer)", 3),
            ("glass (group)", 0),
            ("large steel", 0),
            ("default", 2)
        ]
    );
    assert_eq!(r["summary"]["above_tolerance"], 3);
    assert!(
        err.contains("\"large steel\""),
        "an unused class is said: {err}"
    );
    let table = std::fs::read_to_string(&csv)?;
    assert_eq!(table.lines().count(), 6);
    assert_eq!(table.matches(",glass (layer),").count(), 3);

    // Rhino's groups: the quad is glass by its group, the pentagon (721 mm across) large steel;
    // the triangle is skipped.
    let obj = fixture("panels/rhino_ngons.obj");
    let o = lamina(&[
        "audit",
        s(&obj),
        "--tolerance-rules",
        s(&rules),
        "--report",
        s(&json),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let r = report(&json)?;
    let classes: Vec<&str> = r["panels"]
        .as_array()
        .ok_or("panels")?
        .iter()
        .map(|p| p["class"].as_str().unwrap_or(""))
        .collect();
    assert_eq!(classes, ["glass (group)", "large steel"]);
    assert_eq!(r["panels"][0]["group"], "glass");

    // Errors, exit 2, nothing written: two defaults, no tolerance at all, a panel no rule
    // matches without a default, a bad rule.
    let none = dir.path().join("none.csv");
    let o = lamina(&[
        "audit",
        s(&dxf),
        "--tolerance-rules",
        s(&rules),
        "--tolerance",
        "1",
        "--csv",
        s(&none),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("give it in one place"),
        "{}",
        stderr(&o)
    );
    let o = lamina(&["audit", s(&dxf), "--csv", s(&none)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--tolerance-rules"), "{}", stderr(&o));
    let only_glass = dir.path().join("glass.json");
    for (rules, needle) in [
        (
            r#"{"rules":[{"layer":"GLASS*","mm":1}]}"#,
            "layer \"STEEL\"",
        ),
        (r#"{"rules":[{"layer":"GLASS*","relative":-1}]}"#, "rule 1"),
    ] {
        std::fs::write(&only_glass, rules)?;
        let o = lamina(&[
            "audit",
            s(&dxf),
            "--tolerance-rules",
            s(&only_glass),
            "--csv",
            s(&none),
        ]);
        assert_eq!(o.status.code(), Some(2), "{rules}");
        assert!(stderr(&o).contains(needle), "{rules}: {}", stderr(&o));
    }
    assert!(!none.exists());
    Ok(())
}

#[test]
fn audit_reads_lamina_axes_and_plates() -> TestResult {
    let dir = tempfile::tempdir()?;
    let net = fixture("networks/calyx_veins.json");
    let (axes, panels) = (dir.path().join("axes.json"), dir.path().join("panels.obj"));
    let o = lamina(&["planarize", s(&net), "-o", s(&axes), "--panels", s(&panels)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (from_obj, from_axes) = (
        dir.path().join("obj.json"),
        dir.path().join("axes.audit.json"),
    );
    for (input, rep) in [(&panels, &from_obj), (&axes, &from_axes)] {
        let o = lamina(&["audit", s(input), "--tolerance", "0.01", "--report", s(rep)]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    let (a, b) = (report(&from_obj)?, report(&from_axes)?);
    let (a, b) = (
        a["panels"].as_array().ok_or("a")?,
        b["panels"].as_array().ok_or("b")?,
    );
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(b) {
        let (x, y) = (
            p["flatness"].as_f64().ok_or("x")?,
            q["flatness"].as_f64().ok_or("y")?,
        );
        assert!((x - y).abs() <= 1e-9 * x.max(1e-3), "{x} vs {y}");
        assert!(q["nodes"].is_array(), "axes panels name their edge's nodes");
    }
    let plates = dir.path().join("plates");
    let o = lamina(&["plates", s(&axes), "--groups", "3", "-o", s(&plates)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rep = dir.path().join("plates.audit.json");
    let o = lamina(&[
        "audit",
        s(&plates.join("plates.json")),
        "--tolerance",
        "0.001",
        "--report",
        s(&rep),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let r = report(&rep)?;
    let rows = r["panels"].as_array().ok_or("panels")?;
    // Cut plates are flat by construction: only rounding in their placement.
    assert!(r["summary"]["max_flatness"].as_f64().ok_or("max")? < 1e-9);
    assert!(rows
        .iter()
        .all(|p| p["name"].is_string() && p["group"].is_string()));
    Ok(())
}
