//! End to end through the binary: info, convert, render, demo.

use crate::common::{fixture, lamina, stderr, stdout, TestResult};
use serde_json::Value;

fn info_json(path: &str) -> Result<Value, Box<dyn std::error::Error>> {
    let o = lamina(&["info", "--json", path]);
    assert!(o.status.success(), "{}", stderr(&o));
    Ok(serde_json::from_slice(&o.stdout)?)
}

#[test]
fn info_reports_the_ezdxf_fixture() -> TestResult {
    let v = info_json(fixture("networks/ezdxf_veins.dxf").to_str().ok_or("path")?)?;
    // 13 midrib vertices, 6 secondary veins of 2 new nodes each, 5 tertiary veins of 2, and a
    // loop adding 2: 13 + 12 + 10 + 2 = 37 nodes. Edges: 12 + 12 + 10 + 3 = 37.
    assert_eq!(v["nodes"], 37);
    assert_eq!(v["edges"], 37);
    assert_eq!(v["components"], 1);
    assert_eq!(v["cycles"], 1);
    assert_eq!(v["problems"].as_array().map(|a| a.len()), Some(0));
    assert_eq!(v["import"]["skipped"]["DIMENSION"], 1);
    assert_eq!(v["import"]["skipped"]["TEXT"], 1);
    assert_eq!(v["bbox"]["max"][2], 5.0);
    Ok(())
}

#[test]
fn info_lists_every_validation_problem() -> TestResult {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("n.json");
    std::fs::write(
        &path,
        r#"{"format":"lamina-network","version":1,
            "nodes":[{"p":[0,0,0]},{"p":[1,0,0]},{"p":[1,0,0]}],
            "edges":[{"a":0,"b":1},{"a":1,"b":0},{"a":2,"b":2},{"a":1,"b":2}]}"#,
    )?;
    let v = info_json(path.to_str().ok_or("path")?)?;
    let kinds: Vec<&str> = v["problems"]
        .as_array()
        .ok_or("problems")?
        .iter()
        .filter_map(|p| p["kind"].as_str())
        .collect();
    assert_eq!(kinds, ["repeated_edge", "self_loop", "zero_length"]);
    let human = stdout(&lamina(&["info", path.to_str().ok_or("path")?]));
    assert!(human.contains("edge 2: self-loop at node 2"), "{human}");
    Ok(())
}

#[test]
fn info_on_meshes_gives_topology() -> TestResult {
    let v = info_json(
        fixture("surfaces/openscad_part.stl")
            .to_str()
            .ok_or("path")?,
    )?;
    assert_eq!(v["kind"], "mesh");
    assert_eq!(v["topology"]["genus"], 1);
    assert_eq!(v["topology"]["closed"], true);
    let v = info_json(
        fixture("surfaces/colored_patch.obj")
            .to_str()
            .ok_or("path")?,
    )?;
    assert_eq!(v["vertex_colors"], true);
    assert_eq!(v["topology"]["boundary_loops"], 1);
    Ok(())
}

#[test]
fn weld_option_changes_what_joins() -> TestResult {
    let dir = tempfile::tempdir()?;
    let path = dir.path().join("gap.obj");
    // Two polylines whose ends miss each other by 0.01 mm.
    std::fs::write(
        &path,
        "v 0 0 0\nv 10 0 0\nv 10.01 0 0\nv 20 0 0\nl 1 2\nl 3 4\n",
    )?;
    let p = path.to_str().ok_or("path")?;
    let apart = info_json(p)?;
    assert_eq!(apart["components"], 2);
    let o = lamina(&["info", "--json", "--weld", "0.02", p]);
    let joined: Value = serde_json::from_slice(&o.stdout)?;
    assert_eq!(joined["components"], 1);
    assert_eq!(joined["nodes"], 3);
    Ok(())
}

#[test]
fn convert_and_render_write_what_they_say() -> TestResult {
    let dir = tempfile::tempdir()?;
    let src = fixture("networks/ezdxf_veins.dxf");
    for ext in ["json", "obj", "dxf", "svg", "png"] {
        let out = dir.path().join(format!("veins.{ext}"));
        let o = lamina(&[
            "convert",
            src.to_str().ok_or("path")?,
            out.to_str().ok_or("path")?,
        ]);
        assert!(o.status.success(), "{ext}: {}", stderr(&o));
        assert!(std::fs::metadata(&out)?.len() > 0);
    }
    let svg = std::fs::read_to_string(dir.path().join("veins.svg"))?;
    assert_eq!(svg.matches("<line ").count(), 37);
    let png = dir.path().join("r.png");
    let o = lamina(&[
        "render",
        src.to_str().ok_or("path")?,
        "-o",
        png.to_str().ok_or("path")?,
        "--size",
        "300",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&png)?;
    assert_eq!(&bytes[1..4], b"PNG");
    let (w, h) = (
        u32::from_be_bytes(bytes[16..20].try_into()?),
        u32::from_be_bytes(bytes[20..24].try_into()?),
    );
    assert_eq!(w.max(h), 300, "longer side fits --size: {w}x{h}");
    Ok(())
}

/// The demo's index links only what exists, and its main figures hold.
fn demo_writes_every_output_and_an_index(out: &std::path::Path) -> TestResult {
    let index = std::fs::read_to_string(out.join("index.html"))?;
    let mut links = 0;
    for part in index.split("href=\"").skip(1) {
        let target = part.split('"').next().ok_or("link")?;
        assert!(out.join(target).exists(), "index links to missing {target}");
        links += 1;
    }
    assert!(links >= 20, "{links} links");
    let calyx: Value = serde_json::from_str(&std::fs::read_to_string(
        out.join("surfaces/calyx.info.json"),
    )?)?;
    assert_eq!(calyx["topology"]["genus"], 0);
    // The optimizer path: cells, then every method within 0.01 mm, their reports linked.
    for method in ["lbfgs", "projection", "newton"] {
        assert!(index.contains(&format!("href=\"calyx/{method}-report.html\"")));
        let r: Value = serde_json::from_str(&std::fs::read_to_string(
            out.join(format!("calyx/{method}-report.json")),
        )?)?;
        let max = r["summary"]["max_deviation"].as_f64().ok_or("max")?;
        assert!(max < 0.01, "{method}: {max} mm");
    }
    let cells: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calyx/cells.json"))?)?;
    assert_eq!(cells["cells"].as_array().map(Vec::len), Some(26));
    // Steel: plates in seven groups, every one nested, the preview, BOM and assembly linked.
    for link in [
        "calyx/cut/sheets.svg",
        "calyx/cut/bom.csv",
        "calyx/cut/assembly.scad",
    ] {
        assert!(index.contains(&format!("href=\"{link}\"")), "{link}");
    }
    let nest: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calyx/cut/nest.json"))?)?;
    let plates: Value = serde_json::from_str(&std::fs::read_to_string(
        out.join("calyx/plates/plates.json"),
    )?)?;
    let list = plates["plates"].as_array().ok_or("plates")?;
    let placed: usize = nest["sheets"]
        .as_array()
        .ok_or("sheets")?
        .iter()
        .map(|s| s["parts"].as_array().map_or(0, Vec::len))
        .sum();
    assert_eq!(placed, list.len());
    assert!(list
        .iter()
        .filter(|p| p["group"].as_u64().is_some())
        .all(|p| p["group"].as_u64() <= Some(7)));
    Ok(())
}

/// Two runs of the demo (the longest test: run twice, not three times): every output and the
/// index in the first, and the second byte for byte the same.
#[test]
fn demo_writes_every_output_and_is_deterministic() -> TestResult {
    let dir = tempfile::tempdir()?;
    // scripts/test keeps the first run for its validators (LAMINA_TEST_DEMO_OUT, a folder that
    // does not exist yet) instead of running the demo a third time.
    let a = match std::env::var_os("LAMINA_TEST_DEMO_OUT") {
        Some(keep) => std::path::PathBuf::from(keep),
        None => dir.path().join("a"),
    };
    let b = dir.path().join("b");
    // Both at once, as separate processes.
    let runs = std::thread::scope(|s| {
        let spawn = |d: &std::path::Path| {
            let d = d.to_path_buf();
            // Less nesting work than the default 2 s a sheet (the demo's CPU was mostly
            // nesting): the same stages and files, and their bytes still compared.
            s.spawn(move || {
                lamina(&[
                    "demo",
                    "--out",
                    d.to_str().unwrap_or("?"),
                    "--size",
                    "200",
                    "--nest-time",
                    "0.5",
                ])
            })
        };
        let (x, y) = (spawn(&a), spawn(&b));
        [x.join(), y.join()]
    });
    for o in runs {
        let o = o.map_err(|_| "a demo thread panicked")?;
        assert!(o.status.success(), "{}", stderr(&o));
    }
    demo_writes_every_output_and_an_index(&a)?;
    // Every file in every folder of the first run, and the same list in the second.
    let mut stack = vec![std::path::PathBuf::new()];
    let mut compared = 0;
    while let Some(sub) = stack.pop() {
        let mut names: Vec<_> = std::fs::read_dir(a.join(&sub))?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<Result<_, _>>()?;
        let mut others: Vec<_> = std::fs::read_dir(b.join(&sub))?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<Result<_, _>>()?;
        names.sort();
        others.sort();
        assert_eq!(names, others, "{} lists other files", sub.display());
        for name in names {
            let rel = sub.join(&name);
            if a.join(&rel).is_dir() {
                stack.push(rel);
                continue;
            }
            let (x, y) = (std::fs::read(a.join(&rel))?, std::fs::read(b.join(&rel))?);
            assert!(x == y, "{} differs between runs", rel.display());
            compared += 1;
        }
    }
    assert!(compared > 500, "only {compared} files compared");
    Ok(())
}
