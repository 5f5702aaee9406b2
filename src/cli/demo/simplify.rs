//! Fabrication-aware networks in the demo (Calyx W4): the Calyx venation simplified, then
//! cells, node axes, plates and nested sheets from the simplified network; the closed surface
//! venation of the Calyx band and a closed 2D leaf simplified, each beside its original.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use glam::DVec2;

use super::Entry;
use crate::cli::input::ReadArgs;
use crate::cli::planarize::{MethodArg, ReportArgs};
use lamina::fabricate::nest::Rotations;
use lamina::files::write_atomic;
use lamina::grow::outline::{Outline, Shape};
use lamina::mesh::io::read_mesh;
use lamina::network::io::{render_png_bytes, write_network, RenderOptions};
use lamina::network::Network;
use lamina::rationalize::simplify::{Figures, Report};
use lamina::stage::{venation, Quiet};

pub fn simplified(out: &Path, inputs: &Path, size: u32, nest_time: f64) -> Result<Entry> {
    let dir = out.join("simplify");
    std::fs::create_dir_all(&dir)?;
    let surface = inputs.join("calyx.obj");
    let mesh = read_mesh(&surface)?;
    let weld = ReadArgs::default();
    let mut outputs = Vec::new();
    let mut facts = String::new();

    // The Calyx network: simplify, then the whole way to cut sheets.
    let simplify = |input: &Path, output: &Path, deviation: f64, surface: Option<&Path>| {
        crate::cli::simplify::execute(&crate::cli::simplify::Args {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
            surface: surface.map(Path::to_path_buf),
            max_deviation: Some(deviation),
            min_length: 0.0,
            merge_distance: 0.0,
            min_angle: 30.0,
            prune_order: 0,
            report: Some(output.with_extension("report.json")),
            json: false,
            weld: ReadArgs::default(),
        })
        .map(|(done, _)| done)
    };
    let calyx = dir.join("calyx.json");
    let done = simplify(
        &inputs.join("calyx_veins.json"),
        &calyx,
        10.0,
        Some(&surface),
    )?;
    let _ = write!(facts, "Calyx network: {}. ", figures(&done.report));
    let cells_obj = dir.join("calyx-cells.obj");
    let cells = crate::cli::cells::execute(&crate::cli::cells::Args {
        input: calyx.clone(),
        surface: Some(surface.clone()),
        output: cells_obj.clone(),
        table: None,
        json: false,
        weld: weld.clone(),
    })?;
    let axes = crate::cli::planarize::execute(&crate::cli::planarize::Args {
        input: calyx.clone(),
        surface: Some(cells_obj.clone()),
        method: MethodArg::Newton,
        height: 100.0,
        height_from_radius: None,
        tolerance: 0.01,
        alpha: 0.01,
        step: 0.5,
        plain_projection: false,
        max_iterations: 10_000,
        fix_normal: vec!["z<1:0,0,1".into()],
        fix_axis: Vec::new(),
        timings: false,
        output: dir.join("calyx-axes.json"),
        panels: Some(dir.join("calyx-panels.obj")),
        reports: ReportArgs {
            report: None,
            html: Some(dir.join("calyx-planarity.html")),
            json: false,
        },
        weld: weld.clone(),
    })?;
    let plates = crate::cli::plates::execute(&crate::cli::plates::Args {
        input: dir.join("calyx-axes.json"),
        gauges: None,
        sizing: None,
        thickness: Some(6.0),
        edge_thickness: vec![],
        joints: crate::cli::plates::JointArgs {
            node_core: Some(
                lamina::rationalize::plates::CoreSize::parse("tube:60.3,4")
                    .map_err(anyhow::Error::msg)?,
            ),
            ..Default::default()
        },
        min_weld_angle: None,
        material: None,
        groups: 7,
        output: dir.join("plates"),
        json: false,
    })?;
    let nest = crate::cli::nest::execute(&crate::cli::nest::Args {
        input: dir.join("plates/plates.json"),
        sheet: Some(DVec2::new(3000.0, 1500.0)),
        stock: None,
        remnant_min: DVec2::new(300.0, 300.0),
        lead_in: Some(2.0),
        micro_joints: None,
        micro_joint_below: 200.0,
        micro_joint_width: 0.5,
        speeds: None,
        margin: 10.0,
        spacing: 5.0,
        rotations: Rotations::Listed(vec![0.0, 90.0, 180.0, 270.0]),
        keep_groups: false,
        tries: None,
        seed: 1,
        no_pairs: false,
        kerf: 0.0,
        cut_order: crate::cli::nest::CutOrderArg::Travel,
        common_line: false,
        job: None,
        date: None,
        nc: None,
        post: None,
        nc_on: None,
        nc_off: None,
        time: nest_time,
        output: dir.join("cut"),
        json: false,
    })?;
    let _ = write!(
        facts,
        "From it: {} cells (V − E + F = {}), node axes by Gauss-Newton to {:.4} mm, {} plates of \
         6 mm, nested on {} sheet(s) of 3000 × 1500 (from {} members before). ",
        cells.cells.cells.len(),
        cells.cells.euler.chi,
        axes.solution.max_deviation,
        plates.set.plates.len(),
        nest.sheets.len(),
        done.report.before.members
    );
    let original = crate::cli::input::load(&inputs.join("calyx_veins.json"), &weld, true)?;
    let crate::cli::input::Loaded::Network(original) = original else {
        anyhow::bail!("calyx_veins.json is a network");
    };
    outputs.push(side_by_side(
        out,
        "simplify/calyx-side-by-side.png",
        &[&original.network, &done.network],
        Some(&mesh),
        size,
    )?);
    for f in [
        "calyx.json",
        "calyx.report.json",
        "calyx-cells.obj",
        "calyx-axes.json",
        "calyx-panels.obj",
        "calyx-planarity.html",
        "plates/plates.json",
        "plates/welds.html",
        "cut/nest.json",
        "cut/sheets.svg",
    ] {
        outputs.push(format!("simplify/{f}"));
    }

    // The closed surface venation of the band, as the veins-on-surfaces entry grows it.
    let opts = venation::Options {
        sources: Some(3000),
        ..Default::default()
    };
    let band = venation::on_surface(&mesh, &[], &opts, None, &Quiet)
        .context("venation on the Calyx band")?
        .veins;
    let band_in = dir.join("band.json");
    write_network(&band.network, &band_in, &RenderOptions { size })?;
    let band_out = dir.join("band-simple.json");
    let done = simplify(&band_in, &band_out, 5.0, Some(&surface))?;
    let _ = write!(facts, "Band venation (5 mm): {}. ", figures(&done.report));
    outputs.push(side_by_side(
        out,
        "simplify/band-side-by-side.png",
        &[&band.network, &done.network],
        Some(&mesh),
        size,
    )?);
    outputs.extend(
        ["band.json", "band-simple.json", "band-simple.report.json"]
            .map(|f| format!("simplify/{f}")),
    );

    // A closed leaf in the plane, as the venation entry grows it.
    let leaf_opts = venation::Options::default();
    let leaf = venation::run(&Outline::shape(Shape::Ovate), &leaf_opts, None, &Quiet)?.leaf;
    let leaf_in = dir.join("leaf.json");
    write_network(&leaf.network, &leaf_in, &RenderOptions { size })?;
    let leaf_out = dir.join("leaf-simple.json");
    let done = simplify(&leaf_in, &leaf_out, 0.5, None)?;
    let _ = write!(facts, "Closed leaf (0.5 mm): {}.", figures(&done.report));
    let preview = side_by_side(
        out,
        "simplify/leaf-side-by-side.png",
        &[&leaf.network, &done.network],
        None,
        size,
    )?;
    outputs.push(preview);
    outputs.extend(
        ["leaf.json", "leaf-simple.json", "leaf-simple.report.json"]
            .map(|f| format!("simplify/{f}")),
    );
    Ok(Entry {
        name: "Fabrication-aware networks: simplified, then cut".into(),
        about: "`lamina simplify` (Calyx W4, by hand in Rhino there): chains of degree-2 nodes to \
                the fewest straight members within a deviation (Douglas-Peucker; junctions and \
                tips moved within it where that saves members), no joint under 30° (nodes moved \
                within the deviation), the same cycles and faces. The Calyx network at 10 mm goes \
                on through `cells`, `planarize --method newton`, `plates` and `nest`; the band's \
                closed surface venation at 5 mm and a closed leaf at 0.5 mm are shown beside \
                their originals (left: grown, right: simplified)."
            .into(),
        outputs,
        preview: "simplify/band-side-by-side.png".into(),
        facts,
    })
}

fn figures(r: &Report) -> String {
    let f = |x: &Figures| {
        format!(
            "{} members, shortest {:.1} mm, smallest joint {:.1}°, {} cycles",
            x.members,
            x.shortest_member,
            x.smallest_joint_angle.unwrap_or(180.0),
            x.cycles
        )
    };
    format!(
        "{} → {} ({:.0} % fewer), every node within {:.2} mm",
        f(&r.before),
        f(&r.after),
        100.0 * (1.0 - r.after.members as f64 / r.before.members.max(1) as f64),
        r.max_distance
    )
}

/// The networks rendered side by side (on the mesh when given) into one PNG at `rel`.
fn side_by_side(
    out: &Path,
    rel: &str,
    nets: &[&Network],
    mesh: Option<&lamina::TriMesh>,
    size: u32,
) -> Result<String> {
    let pngs = nets
        .iter()
        .map(|n| match mesh {
            Some(m) => lamina::mesh::io::render_png_bytes_with(
                m,
                &lamina::mesh::io::network_strokes(n),
                size / 2,
            )
            .map_err(anyhow::Error::msg),
            None => render_png_bytes(n, size / 2).map_err(anyhow::Error::msg),
        })
        .collect::<Result<Vec<_>>>()?;
    let bytes = lamina::grow::frames::strip(&pngs).map_err(anyhow::Error::msg)?;
    write_atomic(&out.join(rel), |w| std::io::Write::write_all(w, &bytes))?;
    Ok(rel.to_string())
}
