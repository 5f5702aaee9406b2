//! Files as CAD, modelling and scanning tools write them (fixtures made by ezdxf, trimesh and
//! by hand in Rhino's style): units, curves, blocks, Rhino OBJ quirks, multi-body and jittered
//! STLs. Each with the outcome a designer would expect, in counts, millimetres and topology.

use crate::common::{fixture, lamina, stderr, TestResult};
use serde_json::Value;

fn info(args: &[&str]) -> Result<Value, Box<dyn std::error::Error>> {
    let mut all = vec!["info", "--json"];
    all.extend_from_slice(args);
    let o = lamina(&all);
    assert!(o.status.success(), "{all:?}: {}", stderr(&o));
    Ok(serde_json::from_slice(&o.stdout)?)
}

fn path(rel: &str) -> Result<String, Box<dyn std::error::Error>> {
    Ok(fixture(rel).to_str().ok_or("utf-8 path")?.to_string())
}

fn close(a: &Value, b: f64, tol: f64) -> bool {
    a.as_f64().is_some_and(|a| (a - b).abs() <= tol)
}

#[test]
fn an_inch_drawing_comes_in_at_its_size_in_mm() -> TestResult {
    let dxf = path("networks/ezdxf_curves_in.dxf")?;
    let v = info(&[&dxf])?;
    assert_eq!(v["import"]["source_units"]["unit"], "in");
    assert_eq!(v["import"]["source_units"]["from"], "$INSUNITS = 1");
    // The ellipse reaches x = 12 in; the plate starts at 0; the flange circle (radius 1.5 in
    // about y = 6 in) tops out at 7.5 in, its polygon within the chord tolerance below.
    assert!(close(&v["bbox"]["min"][0], 0.0, 1e-9), "{}", v["bbox"]);
    assert!(
        close(&v["bbox"]["max"][0], 12.0 * 25.4, 1e-9),
        "{}",
        v["bbox"]
    );
    assert!(
        close(&v["bbox"]["max"][1], 7.5 * 25.4 - 0.025, 0.025),
        "{}",
        v["bbox"]
    );
    // --units overrides the header: the same numbers, read as millimetres.
    let mm = info(&["--units", "mm", &dxf])?;
    assert!(close(&mm["bbox"]["max"][0], 12.0, 1e-12), "{}", mm["bbox"]);
    assert_eq!(mm["import"]["source_units"]["from"], "--units");
    Ok(())
}

#[test]
fn curves_and_blocks_become_polylines_with_their_topology() -> TestResult {
    let v = info(&[&path("networks/ezdxf_curves_in.dxf")?])?;
    // Plate, arc, circle, ellipse, two splines, the flange (its circle and four nested bolts),
    // and a 2 x 3 MINSERT of bolts: 17 pieces; every closed curve is one cycle (14).
    assert_eq!(v["components"], 17);
    assert_eq!(v["cycles"], 14);
    assert_eq!(v["import"]["inserts"], 1 + 4 + 6);
    assert_eq!(v["import"]["skipped"]["TEXT"], 1);
    assert_eq!(v["import"]["skipped"]["paper-space entity"], 1);
    assert_eq!(v["problems"].as_array().map(Vec::len), Some(0));
    // Every degree is 2, but for the three open curves' (arc, two splines) six ends.
    assert_eq!(v["degree_histogram"][1], 6);
    Ok(())
}

#[test]
fn a_finer_chord_tolerance_gives_more_points_and_a_bad_one_is_refused() -> TestResult {
    let dxf = path("networks/ezdxf_curves_in.dxf")?;
    let coarse = info(&["--chord-tolerance", "0.5", &dxf])?;
    let fine = info(&["--chord-tolerance", "0.005", &dxf])?;
    let (c, f) = (coarse["nodes"].as_u64(), fine["nodes"].as_u64());
    assert!(c.zip(f).is_some_and(|(c, f)| f > 2 * c), "{c:?} {f:?}");
    assert_eq!(coarse["components"], fine["components"]);
    for bad in ["0", "-1", "nan", "inf", "1e-300"] {
        let o = lamina(&["info", &format!("--chord-tolerance={bad}"), &dxf]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
        assert!(stderr(&o).contains("--chord-tolerance"), "{}", stderr(&o));
    }
    let o = lamina(&["info", "--units", "furlong", &dxf]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("`furlong` is not a unit"),
        "{}",
        stderr(&o)
    );
    Ok(())
}

#[test]
fn convert_says_what_it_dropped_and_strict_refuses_it() -> TestResult {
    let dir = tempfile::tempdir()?;
    let dxf = path("networks/ezdxf_curves_in.dxf")?;
    let out = dir.path().join("plate.json");
    let out = out.to_str().ok_or("path")?;
    let o = lamina(&["convert", &dxf, out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("not read: 1 TEXT, 1 paper-space entity"),
        "{err}"
    );
    assert!(
        err.contains("units in ($INSUNITS = 1), ×25.4 to mm"),
        "{err}"
    );
    std::fs::remove_file(out)?;
    let o = lamina(&["convert", "--strict", &dxf, out]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--strict"), "{}", stderr(&o));
    assert!(!std::path::Path::new(out).exists(), "no output on refusal");
    Ok(())
}

#[test]
fn a_drawing_without_units_is_read_as_mm_and_says_so() -> TestResult {
    let dir = tempfile::tempdir()?;
    let bare = dir.path().join("bare.dxf");
    // The smallest DXF many tools write: no header at all.
    std::fs::write(
        &bare,
        "  0\nSECTION\n  2\nENTITIES\n  0\nLINE\n  8\n0\n 10\n0\n 20\n0\n 30\n0\n 11\n2\n 21\n0\n 31\n0\n  0\nENDSEC\n  0\nEOF\n",
    )?;
    let bare = bare.to_str().ok_or("path")?;
    let v = info(&[bare])?;
    assert_eq!(v["import"]["source_units"]["assumed"], true);
    assert!(close(&v["bbox"]["max"][0], 2.0, 0.0));
    let o = lamina(&["convert", bare, &format!("{bare}.json")]);
    assert!(stderr(&o).contains("assumed"), "{}", stderr(&o));
    Ok(())
}

#[test]
fn rhino_curves_in_obj_are_read_as_polylines() -> TestResult {
    let v = info(&[&path("networks/rhino_curves.obj")?])?;
    // A degree-1 curve (3 segments), a cubic and a rational quarter circle: three pieces; the
    // cubic's inner control points are not nodes.
    assert_eq!(v["components"], 3);
    assert_eq!(v["cycles"], 0);
    assert_eq!(v["degree_histogram"][1], 6);
    assert_eq!(v["import"]["skipped"]["usemtl"], 1);
    assert!(close(&v["bbox"]["max"][0], 40.0, 1e-12));
    Ok(())
}

#[test]
fn a_rhino_box_written_face_by_face_is_one_closed_body() -> TestResult {
    let obj = path("surfaces/rhino_box.obj")?;
    let v = info(&[&obj])?;
    assert_eq!(v["topology"]["vertices"], 8);
    assert_eq!(v["topology"]["closed"], true);
    assert_eq!(v["topology"]["genus"], 0);
    assert!(close(&v["topology"]["volume"], 8000.0, 1e-9));
    // Converting keeps the topology.
    let dir = tempfile::tempdir()?;
    let stl = dir.path().join("box.stl");
    let stl = stl.to_str().ok_or("path")?;
    let o = lamina(&["convert", &obj, stl]);
    assert!(o.status.success(), "{}", stderr(&o));
    let back = info(&[stl])?;
    assert_eq!(back["topology"], v["topology"]);
    Ok(())
}

#[test]
fn every_solid_of_an_ascii_stl_is_read() -> TestResult {
    let v = info(&[&path("surfaces/two_bodies.stl")?])?;
    assert_eq!(v["import"]["bodies"], 2);
    assert_eq!(v["topology"]["components"], 2);
    assert_eq!(v["topology"]["closed"], true);
    assert!(close(&v["topology"]["volume"], 2000.0, 1e-6));
    Ok(())
}

#[test]
fn an_ascii_stl_in_capitals_after_a_byte_order_mark_is_read() -> TestResult {
    // `SOLID … FACET NORMAL …` in E notation with CRLF ends, as admesh's sample block.stl and
    // older CAD exporters write it.
    let v = info(&[&path("surfaces/upper_case.stl")?])?;
    assert_eq!(v["triangles"], 12);
    assert_eq!(v["import"]["bodies"], 1);
    assert_eq!(v["topology"]["closed"], true);
    assert_eq!(v["topology"]["genus"], 0);
    assert!(close(&v["topology"]["volume"], 1000.0, 1e-6));
    Ok(())
}

#[test]
fn jittered_cad_corners_read_open_and_weld_closed() -> TestResult {
    let stl = path("surfaces/cad_jitter.stl")?;
    let raw = info(&[&stl])?;
    assert_eq!(raw["topology"]["closed"], false);
    assert_eq!(raw["topology"]["boundary_edges"], 36);
    // Area and volume are given whatever the mesh's problems.
    assert!(close(&raw["topology"]["area"], 600.0, 0.01));
    assert!(close(&raw["topology"]["signed_volume"], 1000.0, 0.01));
    let welded = info(&["--weld", "1e-3", &stl])?;
    assert_eq!(welded["topology"]["closed"], true);
    assert_eq!(welded["topology"]["vertices"], 8);
    assert_eq!(welded["topology"]["genus"], 0);
    assert_eq!(welded["import"]["weld"]["merged"], 28);
    // The slicer refuses it as it is, naming the flag that closes it, and slices it welded.
    let dir = tempfile::tempdir()?;
    let sl1 = dir.path().join("jitter.sl1");
    let sl1 = sl1.to_str().ok_or("path")?;
    let o = lamina(&["slice", &stl, "-o", sl1]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("36 edge(s) are not matched") && e.contains("--weld MM"),
        "{e}"
    );
    let o = lamina(&["slice", &stl, "--weld", "1e-3", "-o", sl1]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    Ok(())
}

#[test]
fn veins_on_a_jittered_cad_mesh_need_the_weld_and_grow_with_it() -> TestResult {
    let dir = tempfile::tempdir()?;
    let stl = path("surfaces/cad_jitter.stl")?;
    let out = dir.path().join("veins.json");
    let out = out.to_str().ok_or("path")?;
    let base = ["veins", "--surface", &stl, "--sources", "6", "-o", out];
    // Cracked at every edge: twelve loose triangles, and nothing to grow to from the root's.
    let o = lamina(&base);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        !std::path::Path::new(out).exists(),
        "no output on a refusal"
    );
    let mut welded = base.to_vec();
    welded.extend(["--weld", "1e-3"]);
    let o = lamina(&welded);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("welded 28 vertices"), "{}", stderr(&o));
    let net = info(&[out])?;
    assert_eq!(net["nodes"], 6);
    assert_eq!(net["components"], 1);
    // The flag is checked like every reader's --weld, and refused where there is no mesh.
    let mut bad = base.to_vec();
    bad.extend(["--weld", "-1"]);
    assert_eq!(lamina(&bad).status.code(), Some(2));
    let o = lamina(&["venation", "--weld", "1", "-o", out]);
    assert!(stderr(&o).contains("there is none"), "{}", stderr(&o));
    Ok(())
}

#[test]
fn growth_on_several_bodies_needs_a_root_on_each_and_says_so() -> TestResult {
    let dir = tempfile::tempdir()?;
    let stl = path("surfaces/two_bodies.stl")?;
    // No --root: each body grows from its lowest vertex, and that is said.
    let each = dir.path().join("each.json");
    let each = each.to_str().ok_or("path")?;
    let o = lamina(&[
        "venation",
        "--surface",
        &stl,
        "--sources",
        "200",
        "-o",
        each,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("its 2 bodies each grow from their lowest vertex (give --root"),
        "{}",
        stderr(&o)
    );
    assert_eq!(info(&[each])?["components"], 2);
    // A root on the first cube only: the outputs are written, the second cube is named with
    // its lowest vertex, and the exit status is 1.
    let one = dir.path().join("one.json");
    let one = one.to_str().ok_or("path")?;
    let report = dir.path().join("one_report.json");
    let report = report.to_str().ok_or("path")?;
    let o = lamina(&[
        "venation",
        "--surface",
        &stl,
        "--sources",
        "200",
        "--root",
        "0,0,-5",
        "-o",
        one,
        "--report",
        report,
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("1 of its 2 bodies have no root"), "{err}");
    assert!(
        err.contains("body 1: 12 triangles, ")
            && err.contains("(its lowest vertex: 10 at 25, -5, -5)"),
        "{err}"
    );
    assert_eq!(info(&[one])?["components"], 1);
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report)?)?;
    let u = &r["quality"]["unrooted"];
    assert_eq!(
        (u["bodies"].as_u64(), u["bodies_without_root"].as_u64()),
        (Some(2), Some(1))
    );
    assert_eq!(u["without_root"][0]["lowest_vertex"], 10);
    assert_eq!(u["without_root"][0]["sources"], u["sources_left_out"]);
    // A root on each: both grow, nothing said.
    let both = dir.path().join("both.json");
    let both = both.to_str().ok_or("path")?;
    let o = lamina(&[
        "venation",
        "--surface",
        &stl,
        "--sources",
        "200",
        "--root",
        "0,0,-5",
        "--root",
        "10",
        "-o",
        both,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("no root"), "{}", stderr(&o));
    assert_eq!(info(&[both])?["components"], 2);
    Ok(())
}

#[test]
fn a_small_file_that_means_millions_of_points_says_how_to_read_it() -> TestResult {
    // 16 KB: an outline and a MINSERT of 180,000 holes, about 2 M points at 0.05 mm.
    let dir = tempfile::tempdir()?;
    let dxf = path("networks/perforated_panel.dxf")?;
    let out = dir.path().join("panel.json");
    let out = out.to_str().ok_or("path")?;
    let o = lamina(&["convert", &dxf, out]);
    assert_eq!(o.status.code(), Some(2));
    for part in [
        "expands to more than",
        "--max-points",
        "is the default for a file of",
    ] {
        assert!(stderr(&o).contains(part), "{}", stderr(&o));
    }
    assert!(!std::path::Path::new(out).exists());
    // Coarser curves fit the default budget: four chords a hole.
    let o = lamina(&["convert", "--chord-tolerance", "0.5", &dxf, out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let net: Value = serde_json::from_slice(&std::fs::read(out)?)?;
    assert_eq!(net["nodes"].as_array().map(Vec::len), Some(180_000 * 4 + 4));
    // The flag is checked, and a budget given is the one held.
    for bad in ["0", "-5", "NaN", "1.5", "1e300"] {
        let flag = format!("--max-points={bad}");
        let o = lamina(&["convert", &flag, &dxf, out]);
        assert!(
            stderr(&o).contains("--max-points: must be"),
            "{bad}: {}",
            stderr(&o)
        );
    }
    let o = lamina(&[
        "convert",
        "--max-points",
        "1000",
        "--chord-tolerance",
        "0.5",
        &dxf,
        out,
    ]);
    assert!(
        stderr(&o).contains("more than 1000 points"),
        "{}",
        stderr(&o)
    );
    Ok(())
}

#[test]
fn mesh_entities_the_dxf_crate_drops_are_said_as_not_read() -> TestResult {
    // ezdxf's panels: a MESH, a polyface mesh, a 3DFACE and a TEXT beside the polylines that
    // make the network; the dxf crate skips MESH without a trace, lamina counts it.
    let d = info(&[&path("panels/ezdxf_panels.dxf")?])?;
    let skipped = &d["import"]["skipped"];
    assert_eq!(skipped["MESH"], 1, "{skipped}");
    assert_eq!(skipped["3DFACE"], 1, "{skipped}");
    assert_eq!(skipped["TEXT"], 1, "{skipped}");
    Ok(())
}

#[test]
fn round_holes_drawn_as_two_bulged_vertices_are_whole_circles() -> TestResult {
    // AutoCAD's DONUT (a closed LWPOLYLINE of two vertices, bulges 1), a two-arc hole as a
    // closed 2D POLYLINE, and a slot: three loops, their lengths those of the circles (less
    // the chords' shortfall at the default tolerance).
    let v = info(&[&path("networks/ezdxf_round_holes.dxf")?])?;
    assert_eq!(v["components"], 3);
    assert_eq!(v["cycles"], 3);
    let pi = std::f64::consts::PI;
    let exact = 10.0 * pi + 8.0 * pi + (40.0 + 10.0 * pi);
    let total = v["lengths"]["total"].as_f64().ok_or("total")?;
    assert!(
        total <= exact && total > 0.995 * exact,
        "{total} of {exact}"
    );
    assert!(close(&v["bbox"]["min"][1], -5.0, 1e-9), "{}", v["bbox"]);
    assert!(close(&v["bbox"]["max"][1], 10.0, 1e-9), "{}", v["bbox"]);
    // One vertex closed on itself is no loop: refused by name.
    let o = lamina(&["info", &path("bad/one_vertex_loop.dxf")?]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("LWPOLYLINE, handle") && stderr(&o).contains("one vertex"),
        "{}",
        stderr(&o)
    );
    Ok(())
}

/// Length of the plane curve `f` over [0, 1] by the midpoint rule on `n` pieces.
fn curve_length(f: impl Fn(f64) -> (f64, f64), n: usize) -> f64 {
    (0..n)
        .map(|k| {
            let (a, b) = (f(k as f64 / n as f64), f((k + 1) as f64 / n as f64));
            (b.0 - a.0).hypot(b.1 - a.1)
        })
        .sum()
}

#[test]
fn hatch_boundaries_are_closed_loops_when_asked_and_named_otherwise() -> TestResult {
    let dxf = path("networks/ezdxf_hatches.dxf")?;
    // Not asked: the line alone, the hatches named with the flag that reads them.
    let v = info(&[&dxf])?;
    let skipped = &v["import"]["skipped"];
    assert_eq!(skipped["HATCH"], 8, "{skipped}");
    assert_eq!(skipped["HATCH (in block definitions)"], 1, "{skipped}");
    let o = lamina(&["info", "--strict", &dxf]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("8 HATCH (--hatch-boundaries reads their boundaries)"),
        "{}",
        stderr(&o)
    );
    // Asked: ten closed loops (the plate and its hole, two slots, two ellipses, the spline,
    // the mirrored square, the block's triangle twice) and the line; the paper-space hatch is
    // named.
    let v = info(&["--hatch-boundaries", "--chord-tolerance", "0.005", &dxf])?;
    assert_eq!(v["cycles"], 10);
    assert_eq!(v["components"], 11);
    let skipped = v["import"]["skipped"].as_object().ok_or("skipped")?;
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert_eq!(skipped["paper-space entity"], 1);
    // The mirrored square (extrusion -Z) lies at x = -20..-10; the scaled triangle reaches 420.
    assert!(close(&v["bbox"]["min"][0], -20.0, 1e-9), "{}", v["bbox"]);
    assert!(close(&v["bbox"]["max"][0], 420.0, 1e-9), "{}", v["bbox"]);
    let pi = std::f64::consts::PI;
    let ellipse = |a: f64, b: f64, turn: f64| {
        curve_length(|t| (a * (turn * t).cos(), b * (turn * t).sin()), 200_000)
    };
    let bezier = curve_length(
        |t| {
            let u = 1.0 - t;
            let (b0, b1, b2, b3) = (u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t);
            (
                300.0 * b0 + 310.0 * b1 + 330.0 * b2 + 340.0 * b3,
                30.0 * (b1 + b2),
            )
        },
        200_000,
    );
    let exact = (300.0 + 20.0 * pi) // plate and hole
        + (60.0 + 10.0 * pi) // slot, counter-clockwise
        + (70.0 + 5.0 * pi) // slot with clockwise corners
        + ellipse(20.0, 10.0, 2.0 * pi)
        + (ellipse(15.0, 9.0, pi) + 30.0)
        + (bezier + 40.0)
        + 40.0 // mirrored square
        + (40.0 + 20.0 * 2f64.sqrt()) // triangle scaled 2
        + (20.0 + 10.0 * 2f64.sqrt()) // triangle turned
        + 100.0; // the line
    let total = v["lengths"]["total"].as_f64().ok_or("total")?;
    // Chords are never longer than their arcs, and with a sagitta of 0.005 mm fall short by
    // about s / 3r per unit length: 0.04 mm on these radii of 5 to 20 mm.
    assert!(
        total <= exact + 1e-6 && total > exact - 0.06,
        "{total} against {exact}"
    );
    // Their points count against --max-points like any curve's: 200 in all at 0.05 mm.
    let budget = |n: &str| lamina(&["info", "--hatch-boundaries", "--max-points", n, &dxf]);
    assert!(budget("200").status.success());
    let o = budget("199");
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("expands to more than 199 points"),
        "{}",
        stderr(&o)
    );
    // A HATCH that cannot be read is named by its line, nothing written.
    let dir = tempfile::tempdir()?;
    let bad = dir.path().join("bad.dxf");
    std::fs::write(
        &bad,
        "0\nSECTION\n2\nENTITIES\n0\nLINE\n10\n0\n20\n0\n11\n1\n21\n0\n\
         0\nHATCH\n91\n1\n92\n1\n93\n1\n72\n9\n0\nENDSEC\n0\nEOF\n",
    )?;
    let out = dir.path().join("out.json");
    let o = lamina(&[
        "convert",
        "--hatch-boundaries",
        bad.to_str().ok_or("path")?,
        out.to_str().ok_or("path")?,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("line 15 (HATCH): boundary path 1: edge 1: edge type 9 (72)"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    Ok(())
}

#[test]
fn strokes_drawn_over_each_other_are_noded_only_where_they_end() -> TestResult {
    // Three collinear strokes along x = 0 and a line ending on them; a frame drawn in
    // overlapping pieces; a square turned 30° the same way. Noded, each line is drawn once:
    // 492 + 380 + 200 + 50√2 mm, no node where nothing ends, no problem left, four faces.
    let v = info(&["--split-crossings", &path("networks/ezdxf_overlaps.dxf")?])?;
    let split = &v["import"]["split_crossings"];
    assert_eq!(split["crossings"], 0, "{split}");
    assert_eq!(split["nodes_added"], 0, "{split}");
    assert_eq!(v["nodes"], 33);
    assert_eq!(v["edges"], 34);
    assert_eq!(v["cycles"], 4);
    assert_eq!(v["problems"].as_array().map(Vec::len), Some(0));
    let want = 492.0 + 380.0 + 200.0 + 50.0 * 2f64.sqrt();
    assert!(
        close(&v["lengths"]["total"], want, 1e-9),
        "{}",
        v["lengths"]
    );
    Ok(())
}

#[test]
fn an_obj_with_faces_and_loose_edges_is_read_as_its_polylines() -> TestResult {
    // Blender's export of a square face with a three-edge polyline leaving it: the polyline is
    // the network, the face is skipped and said; --strict refuses it; faces alone stay a mesh.
    let obj = path("networks/blender_loose_edges.obj")?;
    let v = info(&[&obj])?;
    assert_eq!(v["nodes"], 4);
    assert_eq!(v["edges"], 3);
    assert_eq!(v["import"]["skipped"]["f (faces)"], 1);
    let want = 1.0 + 2f64.sqrt() + 1.25f64.sqrt();
    assert!(
        close(&v["lengths"]["total"], want, 1e-9),
        "{}",
        v["lengths"]
    );
    let o = lamina(&["info", "--strict", &obj]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("1 f (faces)"), "{}", stderr(&o));
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("net.json");
    let o = lamina(&[
        "convert",
        &path("surfaces/rhino_box.obj")?,
        &out.to_string_lossy(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("a mesh"), "{}", stderr(&o));
    Ok(())
}

#[test]
fn a_binary_stl_with_a_solid_header_and_a_stray_byte_is_read_as_binary() -> TestResult {
    // numpy-stl style: "solid" in the 80-byte header, one byte after the 12 triangles.
    let v = info(&[&path("surfaces/solid_header_trailing.stl")?])?;
    assert_eq!(v["triangles"], 12);
    assert_eq!(v["topology"]["closed"], true);
    assert_eq!(v["topology"]["genus"], 0);
    assert_eq!(
        v["import"]["not_read"],
        serde_json::json!(["1 byte(s) after the binary STL's 12 triangles"])
    );
    Ok(())
}

#[test]
fn slice_drops_triangles_that_collapse_when_minus_zero_is_zero() -> TestResult {
    // A closed cube and 200 slivers whose corners differ only in the sign of zero: sliced,
    // with the slivers dropped and counted; --weld joins near corners as info's does.
    let stl = path("surfaces/signed_zero_slivers.stl")?;
    let dir = tempfile::tempdir()?;
    let out = dir.path().join("z.sl1");
    let out = out.to_str().ok_or("path")?;
    let small = ["--layer", "1", "--pixel", "0.1", "--resolution", "400x300"];
    let slice = |file: &str, more: &[&str]| {
        let mut args = vec!["slice", file, "-o", out];
        args.extend_from_slice(&small);
        args.extend_from_slice(more);
        lamina(&args)
    };
    let o = slice(&stl, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("200 triangles with two corners at one point dropped"),
        "{}",
        stderr(&o)
    );
    let o = slice(&stl, &["--weld", "0.001"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("200 triangles collapsed and dropped"),
        "{}",
        stderr(&o)
    );
    let o = slice(&stl, &["--weld=-1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--weld"), "{}", stderr(&o));
    // An OBJ of faces and loose edges read as a mesh names the edges it leaves out.
    let obj = path("networks/blender_loose_edges.obj")?;
    let o = slice(&obj, &[]);
    assert!(
        stderr(&o).contains("not read as the mesh: 3 l (polylines)"),
        "{}",
        stderr(&o)
    );
    Ok(())
}

#[test]
fn bodies_touching_at_a_corner_are_closed_but_claim_no_genus() -> TestResult {
    // trimesh: two cubes sharing the corner (10, 10, 10), vertices merged: V − E + F = 3, every
    // edge with two triangles, and a pinched vertex reported with its position.
    let v = info(&[&path("surfaces/touching_cubes.stl")?])?;
    let t = &v["topology"];
    assert_eq!(t["euler"], 3);
    assert_eq!(t["closed"], true);
    assert_eq!(t["genus"], Value::Null);
    assert!(close(&t["volume"], 2000.0, 1e-9), "{t}");
    let problems = v["problems"].as_array().ok_or("problems")?;
    assert_eq!(problems.len(), 1, "{problems:?}");
    let p = problems[0].as_str().ok_or("problem text")?;
    assert!(
        p.contains("at (10.0000, 10.0000, 10.0000): 2 fans of triangles meet only at this point"),
        "{p}"
    );
    Ok(())
}

#[test]
fn entities_the_parser_drops_are_named_and_refused_under_strict() -> TestResult {
    // ezdxf: a LINE, a HATCH, a MULTILEADER, three DIMENSIONs and a block holding a LINE and a
    // HATCH, inserted once. The dxf crate drops HATCH and MULTILEADER without a trace; the
    // file's own records are counted so each one is named.
    let dxf = path("networks/ezdxf_unread_entities.dxf")?;
    let v = info(&[&dxf])?;
    let skipped = &v["import"]["skipped"];
    assert_eq!(skipped["HATCH"], 1, "{skipped}");
    assert_eq!(skipped["MULTILEADER"], 1, "{skipped}");
    assert_eq!(skipped["DIMENSION"], 3, "{skipped}");
    assert_eq!(skipped["HATCH (in block definitions)"], 1, "{skipped}");
    assert_eq!(v["edges"], 2);
    let o = lamina(&["info", "--strict", &dxf]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("1 HATCH") && stderr(&o).contains("1 MULTILEADER"),
        "{}",
        stderr(&o)
    );
    Ok(())
}

#[test]
fn audit_expands_blocks_of_panels() -> TestResult {
    // A polyface of two quads (one with a corner 2 mm off) in a block inserted twice: four
    // panels, two of them warped, named through their INSERT.
    let dxf = path("panels/ezdxf_polyface_block.dxf")?;
    let o = lamina(&["audit", &dxf, "--tolerance", "0.1", "--json"]);
    // Exit 1: panels above the tolerance.
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout)?;
    assert_eq!(v["panels"], 4, "{v}");
    assert_eq!(v["above_tolerance"], 2, "{v}");
    assert!(close(&v["max_corner"], 2.0, 1e-12), "{v}");
    assert!(
        stderr(&o).contains("2 block insertions expanded"),
        "{}",
        stderr(&o)
    );
    Ok(())
}
