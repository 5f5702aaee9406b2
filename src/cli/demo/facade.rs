//! The façade in the demo (Hanafin et al.): the paper's L-system tree (n = 7, 22°, 500 mm)
//! drawn whole, fitted to a 12 m × 4 m boundary over a section of its crown, its infill panels
//! found by `cells`, and the same façade projected onto a bowed wall; a random bifurcation
//! beside it (their Fig. 4).

use std::path::Path;

use anyhow::{Context, Result};
use clap::Parser;

use super::Entry;
use crate::cli::input::ReadArgs;
use lamina::files::write_atomic;
use lamina::network::io::{read_network, write_network, ReadOptions, RenderOptions};

/// The paper's grammar, as the demo's commands spell it.
const GRAMMAR: [&str; 8] = [
    "--axiom",
    "X",
    "--rule",
    "X=F[-X]F[+X]-X",
    "--rule",
    "F=FF",
    "--iterations",
    "7",
];

#[derive(Parser)]
struct Lsystem {
    #[command(flatten)]
    args: crate::cli::lsystem::Args,
}

#[derive(Parser)]
struct Bifurcate {
    #[command(flatten)]
    args: crate::cli::bifurcate::Args,
}

fn lsystem(extra: &[&str]) -> Result<serde_json::Value> {
    let argv = ["lsystem"].iter().chain(&GRAMMAR).chain(extra);
    let cmd = Lsystem::try_parse_from(argv).context("the demo's lsystem arguments")?;
    crate::cli::lsystem::execute(&cmd.args)
}

/// A wall bowed 400 mm out over its 13 m width, standing in the XZ plane behind the façade
/// (y from 2000 mm at the edges to 2400 mm in the middle), 0.5 m wider and taller all round: a
/// 52 × 10 grid (fixtures/surfaces/bowed_wall.obj).
const BOWED_WALL: &[u8] = include_bytes!("../../../fixtures/surfaces/bowed_wall.obj");

pub fn facade(out: &Path, size: u32) -> Result<Entry> {
    let dir = out.join("facade");
    std::fs::create_dir_all(&dir)?;
    let p = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let px = size.to_string();

    let tree = lsystem(&[
        "-o",
        &p("tree.json"),
        "--png",
        &p("tree.png"),
        "--size",
        &px,
    ])?;
    let fitted = [
        "--boundary",
        "rect:12000,4000",
        "--root-at=0,-12000",
        "--fit",
        "cover",
    ];
    let mut args = fitted.to_vec();
    let (json, png, svg, dxf, report) = (
        p("facade.json"),
        p("facade.png"),
        p("facade.svg"),
        p("facade.dxf"),
        p("facade.report.json"),
    );
    args.extend([
        "-o", &json, "--png", &png, "--svg", &svg, "--size", &px, "--report", &report,
    ]);
    let rep = lsystem(&args)?;
    let net = read_network(&dir.join("facade.json"), &ReadOptions::default())?.network;
    write_network(&net, Path::new(&dxf), &RenderOptions { size })?;

    // The infill panels: the cells of the fitted structure.
    let cells = crate::cli::cells::execute(&crate::cli::cells::Args {
        input: dir.join("facade.json"),
        surface: None,
        output: dir.join("panels.obj"),
        table: Some(dir.join("panels.json")),
        json: false,
        weld: ReadArgs::default(),
    })?;

    // The same façade stood up and projected onto a bowed wall.
    write_atomic(&dir.join("wall.obj"), |w| {
        std::io::Write::write_all(w, BOWED_WALL)
    })?;
    let mut onto = fitted.to_vec();
    let (vault_json, vault_png, wall_obj) = (
        p("facade-on-wall.json"),
        p("facade-on-wall.png"),
        p("wall.obj"),
    );
    onto.extend([
        "--upright",
        "--onto",
        &wall_obj,
        "--direction",
        "0,1,0",
        "--sag",
        "5",
        "-o",
        &vault_json,
        "--png",
        &vault_png,
        "--size",
        &px,
    ]);
    let projected = lsystem(&onto)?;

    // Recursive bifurcation with random angles and scales (the paper's Fig. 4).
    let bif = Bifurcate::try_parse_from([
        "bifurcate",
        "--depth",
        "9",
        "--angle",
        "15..40",
        "--scale",
        "0.65..0.85",
        "--seed",
        "4",
        "-o",
        &p("bifurcation.json"),
        "--png",
        &p("bifurcation.png"),
        "--size",
        &px,
    ])?;
    crate::cli::bifurcate::execute(&bif.args)?;

    let f = &rep["facade"];
    let q = &rep["quality"];
    Ok(Entry {
        name: "façade (L-system tree)".into(),
        about: "Hanafin, Datta and Rolfe's façade grammar (X → F[-X]F[+X]-X, F → FF, n = 7, \
                22°, 500 mm steps), drawn by `lamina lsystem` with runs of F merged into members, \
                fitted by `--boundary rect:12000,4000 --root-at=0,-12000 --fit cover` to a \
                12 m × 4 m façade over a section of the crown (cut at the boundary, the boundary \
                added as the frame, crossing members joined); its infill panels found by `lamina \
                cells`; the same façade stood up and projected onto a bowed wall (`--upright \
                --onto wall.obj`); and a random recursive bifurcation (`lamina bifurcate --angle \
                15..40 --scale 0.65..0.85`)."
            .into(),
        outputs: [
            "tree.json",
            "tree.png",
            "facade.json",
            "facade.svg",
            "facade.png",
            "facade.dxf",
            "facade.report.json",
            "panels.obj",
            "panels.json",
            "wall.obj",
            "facade-on-wall.json",
            "facade-on-wall.png",
            "bifurcation.json",
            "bifurcation.png",
        ]
        .iter()
        .map(|n| format!("facade/{n}"))
        .collect(),
        preview: "facade/facade.png".into(),
        facts: format!(
            "whole tree: {} symbols, {} segments, {} members after simplification; façade: \
             scale {:.4}, {} members kept whole and {} cut at the boundary, {} joints where \
             members crossed, {} frame joints, {} nodes and {} members in one piece, {} \
             infill panels; on the wall: {} nodes added to follow the bow",
            tree["lsystem"]["symbols"],
            tree["lsystem"]["segments"],
            tree["lsystem"]["simplified_segments"],
            f["scale"].as_f64().unwrap_or(f64::NAN),
            f["kept_whole"],
            f["cut"],
            f["joints_at_crossings"],
            f["frame_joints"],
            q["nodes"],
            q["edges"],
            cells.cells.cells.len(),
            projected["projection"]["added_nodes"],
        ),
    })
}
