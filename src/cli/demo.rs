//! `lamina demo [--out DIR]`: the whole way on the embedded fixtures: read each fixture, check
//! it, convert it to every format and render it; grow two leaves; run the Calyx network through
//! cells and node axes with planarity reports, then into plates, assembly groups and nested
//! cut sheets; simplify the Calyx network and take it to cut sheets too, and simplify the
//! band's surface venation and a closed leaf; grow veins on the Calyx band, a sphere, a torus and a density plate (surface
//! venation and geodesic veins, each rendered on its surface); draw the façade paper's L-system
//! tree and fit it to a 12 m × 4 m façade; make a leaf solid and slice it for the DMP-SL
//! printer; write an index.html linking everything. Later stages add their steps here.

mod buds;
mod facade;
mod print;
mod simplify;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use indicatif::ProgressStyle;

use super::info::summary;
use super::input::{load, Loaded, ReadArgs};
use super::planarize::{MethodArg, ReportArgs};
use glam::{DVec2, DVec3};
use lamina::analyze::frame::Support;
use lamina::analyze::sizing::{DeflectionLimit, GroupBy};
use lamina::fabricate::nest::Rotations;
use lamina::files::write_atomic;
use lamina::grow::outline::{Outline, Shape};
use lamina::grow::surface::Channel;
use lamina::grow::venation::{Frame, Mode};
use lamina::mesh::io::{read_mesh, render_png_bytes_with, write_mesh, Stroke3};
use lamina::network::io::{write_network, RenderOptions};
use lamina::rationalize::planarize::Selector;
use lamina::stage::{venation, Quiet};

#[derive(ClapArgs)]
pub struct Args {
    /// Folder for every output (made if missing)
    #[arg(long, default_value = "demo-out")]
    pub out: PathBuf,
    /// Longer side of PNG renders, in pixels (16 to 16384)
    #[arg(long, default_value_t = 1600)]
    pub size: u32,
    /// Work spent making each cut sheet denser, as `nest --time` (seconds of a 2-core
    /// reference machine a sheet, counted as work: the same sheets on any machine)
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub nest_time: f64,
}

/// The fixtures the demo runs on, inside the binary so it needs no checkout.
const FIXTURES: &[(&str, &[u8], &str)] = &[
    (
        "ezdxf_veins.dxf",
        include_bytes!("../../fixtures/networks/ezdxf_veins.dxf"),
        "Leaf veins drawn as LINE, LWPOLYLINE and 2D/3D POLYLINE entities by ezdxf",
    ),
    (
        "calyx.obj",
        include_bytes!("../../fixtures/surfaces/calyx.obj"),
        "Calyx-like surface: an arc revolved about Z, a 2 m open hyperbolic band",
    ),
    (
        "calyx_veins.json",
        include_bytes!("../../fixtures/networks/calyx_veins.json"),
        "Closed venation on the Calyx-like surface (grown by lamina venation in the unrolled \
         band, mapped onto the surface by scripts/fixtures/calyx_veins.py), with a base ring at z = 0",
    ),
    (
        "colored_patch.obj",
        include_bytes!("../../fixtures/surfaces/colored_patch.obj"),
        "Wavy patch with a density map in its vertex colours",
    ),
    (
        "openscad_part.stl",
        include_bytes!("../../fixtures/surfaces/openscad_part.stl"),
        "A bracket with a bore, exported by OpenSCAD (genus 1)",
    ),
];

/// The surfaces veins grow on (besides the Calyx band above), inside the binary too.
const SURFACES: &[(&str, &[u8], &str)] = &[
    (
        "sphere.obj",
        include_bytes!("../../fixtures/surfaces/sphere.obj"),
        "an icosphere, radius 50 mm (closed)",
    ),
    (
        "torus.obj",
        include_bytes!("../../fixtures/surfaces/torus.obj"),
        "a torus, radii 60 and 20 mm (closed, genus 1)",
    ),
    (
        "density_halves.obj",
        include_bytes!("../../fixtures/surfaces/density_halves.obj"),
        "a 200 × 100 mm plate, dark (dense) on the left half, light on the right, in its vertex \
         colours",
    ),
];

pub(crate) use lamina::report::demo_index::{Entry, Headline};

pub fn run(args: Args) -> Result<()> {
    // Checked before anything is written.
    let (lo, hi) = lamina::network::io::PNG_SIZE_RANGE;
    if !(lo..=hi).contains(&args.size) {
        bail!("--size: must be {lo} to {hi} pixels, got {}", args.size);
    }
    lamina::stage::positive(
        "nest_time",
        args.nest_time,
        lamina::stage::nest::MAX_TIME,
        "s",
    )?;
    let out = &args.out;
    let inputs = out.join("inputs");
    std::fs::create_dir_all(&inputs)
        .with_context(|| format!("{}: cannot create folder", inputs.display()))?;
    let bar = super::progress::bar("demo", Some(FIXTURES.len() as u64 + 7 + 4 + 3));
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut entries = Vec::new();
    for (name, bytes, about) in FIXTURES {
        bar.set_message(name.to_string());
        let input = inputs.join(name);
        write_atomic(&input, |w| std::io::Write::write_all(w, bytes))?;
        entries.push(process(out, &input, name, about, args.size)?);
        bar.inc(1);
    }
    for mode in [Mode::Closed, Mode::Open] {
        bar.set_message("venation leaf");
        entries.push(leaf(out, args.size, mode)?);
        bar.inc(1);
    }
    bar.set_message("Peele's Figure 1: r sweep over five seeds");
    entries.push(peele(out)?);
    bar.inc(1);
    bar.set_message("calyx: cells, node axes, reports");
    entries.push(calyx(out, &inputs, args.size)?);
    bar.inc(1);
    bar.set_message("calyx: plates, groups, cut sheets");
    let (entry, steel_job) = steel(out, args.nest_time)?;
    entries.push(entry);
    bar.inc(1);
    bar.set_message("calyx: planarity audit of the panels");
    let (entry, audit_job) = audit(out)?;
    entries.push(entry);
    bar.inc(1);
    bar.set_message("simplified networks: calyx to cut sheets, band, leaf");
    entries.push(simplify::simplified(
        out,
        &inputs,
        args.size,
        args.nest_time,
    )?);
    bar.inc(1);
    for (name, bytes, _) in SURFACES {
        write_atomic(&inputs.join(name), |w| std::io::Write::write_all(w, bytes))?;
    }
    let calyx_about = "the Calyx-like band (open, 2 m)";
    let surfaces = [("calyx.obj", calyx_about)]
        .into_iter()
        .chain(SURFACES.iter().map(|(n, _, a)| (*n, *a)));
    for (name, about) in surfaces {
        bar.set_message(format!("veins on {name}"));
        entries.push(surface_veins(out, &inputs.join(name), about, args.size)?);
        bar.inc(1);
    }
    bar.set_message("façade: L-system tree, fitted, panels, on a wall");
    entries.push(facade::facade(out, args.size)?);
    bar.inc(1);
    bar.set_message("growth forms: Figure 8, split, holes");
    entries.push(buds::buds(out, args.size)?);
    bar.inc(1);
    bar.set_message("print: leaf, solid, slices");
    let (entry, print_job) = print::print_leaf(out, args.size)?;
    entries.push(entry);
    bar.inc(1);
    bar.set_message("viewers");
    let viewers = viewers(out, &entries)?;
    bar.finish_and_clear();
    let index = out.join("index.html");
    let html = lamina::report::demo_index::index_html(
        &[steel_job, print_job, audit_job],
        &entries,
        &viewers,
        FIXTURES.len(),
    );
    write_atomic(&index, |w| std::io::Write::write_all(w, html.as_bytes()))?;
    outln!("wrote {} ({} sections)", index.display(), entries.len());
    Ok(())
}

fn process(out: &Path, input: &Path, name: &str, about: &str, size: u32) -> Result<Entry> {
    let stem = Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| name.to_string());
    let loaded = load(input, &ReadArgs::default(), true)?;
    let mut info = summary(input, &loaded);
    // Named as the index links it, from the output folder: the same bytes whatever folder
    // the demo writes to.
    info["file"] = serde_json::Value::String(format!("inputs/{name}"));
    let mut outputs = vec![format!("inputs/{name}")];
    let (dir, exts, preview): (&str, &[&str], String) = match &loaded {
        Loaded::Network(_) => (
            "networks",
            &["json", "obj", "dxf", "svg", "png"],
            format!("networks/{stem}.svg"),
        ),
        Loaded::Mesh(..) => (
            "surfaces",
            &["stl", "obj", "png"],
            format!("surfaces/{stem}.png"),
        ),
    };
    std::fs::create_dir_all(out.join(dir))?;
    for ext in exts {
        let rel = format!("{dir}/{stem}.{ext}");
        let path = out.join(&rel);
        match &loaded {
            Loaded::Network(imp) => write_network(&imp.network, &path, &RenderOptions { size })?,
            Loaded::Mesh(mesh, _) => write_mesh(mesh, &path, size)?,
        }
        outputs.push(rel);
    }
    let info_rel = format!("{dir}/{stem}.info.json");
    let info_text = serde_json::to_string_pretty(&info)?;
    write_atomic(&out.join(&info_rel), |w| {
        std::io::Write::write_all(w, info_text.as_bytes())
    })?;
    outputs.push(info_rel);
    let facts = match &loaded {
        Loaded::Network(_) => format!(
            "{} nodes, {} edges, {} components, {} cycles, {} problems",
            info["nodes"],
            info["edges"],
            info["components"],
            info["cycles"],
            info["problems"].as_array().map_or(0, |a| a.len())
        ),
        Loaded::Mesh(..) => {
            let t = &info["topology"];
            format!(
                "{} vertices, {} triangles, χ = {}, genus {}, {} boundary loops, closed: {}{}",
                info["vertices"],
                info["triangles"],
                t["euler"],
                t["genus"],
                t["boundary_loops"],
                t["closed"],
                t["volume"]
                    .as_f64()
                    .map(|v| format!(", volume {v:.1} mm³"))
                    .unwrap_or_default()
            )
        }
    };
    Ok(Entry {
        name: name.to_string(),
        about: about.to_string(),
        outputs,
        preview,
        facts,
    })
}

/// Grows a leaf in the ovate blade with the default parameters and seed, in `mode`.
fn leaf(out: &Path, size: u32, mode: Mode) -> Result<Entry> {
    let opts = venation::Options {
        mode,
        ..Default::default()
    };
    let grown = venation::run(&Outline::shape(Shape::Ovate), &opts, None, &Quiet)?;
    let (net, growth) = (&grown.leaf.network, &grown.leaf.growth);
    let name = match mode {
        Mode::Open => "open",
        Mode::Closed => "closed",
    };
    std::fs::create_dir_all(out.join("venation"))?;
    let mut outputs = Vec::new();
    for ext in ["json", "svg", "png", "dxf"] {
        let rel = format!("venation/leaf-{name}.{ext}");
        write_network(net, &out.join(&rel), &RenderOptions { size })?;
        outputs.push(rel);
    }
    Ok(Entry {
        name: format!("venation leaf ({name})"),
        about: format!(
            "Grown by `lamina venation --shape ovate --mode {name}`: Runions space colonisation \
             from the petiole, Poisson-disk auxin sources, Murray widths (n = 3)"
        ),
        outputs,
        preview: format!("venation/leaf-{name}.png"),
        facts: format!(
            "{} growth steps, {} of {} sources left unreached; {}",
            growth.iterations,
            growth.sources_left,
            growth.sources_placed,
            grown.leaf.quality.lines().join("; ")
        ),
    })
}

/// Peele's Figure 1 measured: open leaves at r = 0.5, 1.5, 3.5 and 5.5, five seeds each, with
/// the table of dominant veins and chaos per r, the figure and the verdict in words.
fn peele(out: &Path) -> Result<Entry> {
    let opts = venation::Options {
        mode: Mode::Open,
        ..Default::default()
    };
    let (rs, seeds, by) = ([0.5, 1.5, 3.5, 5.5], 5, venation::SweepBy::Blade);
    let leaves = venation::sweep(&Outline::shape(Shape::Ovate), &opts, &rs, by, seeds, &Quiet)?;
    let dir = "venation/peele";
    let written = super::venation::write_sweep(&out.join(dir), &leaves, seeds, by, 512)?;
    let verdict: Vec<&str> = written["verdict"]
        .as_array()
        .map(|v| v.iter().filter_map(|l| l.as_str()).collect())
        .unwrap_or_default();
    Ok(Entry {
        name: "Peele's Figure 1: the r sweep, five seeds".into(),
        about: "Grown by `lamina venation --sweep-r 0.5,1.5,3.5,5.5 --seeds 5` (open venation, \
                r set by the blade's growth rate): the first seed's leaves side by side, and \
                under them per r the dominant veins (radius at least half the petiole's), their \
                radius, the zigzag index and the turning along dominant veins, mean and spread \
                over the seeds (table in sweep.json, checked by validators/check_peele_sweep.py)"
            .into(),
        outputs: vec![format!("{dir}/sweep.svg"), format!("{dir}/sweep.json")],
        preview: format!("{dir}/sweep.svg"),
        facts: verdict.join("; "),
    })
}

/// The optimizer path on the Calyx-like fixture: cells on the guide surface, then node axes by
/// both methods with the cells' vertex normals as references and the base plates held to +Z,
/// each with its planarity report.
fn calyx(out: &Path, inputs: &Path, size: u32) -> Result<Entry> {
    let dir = out.join("calyx");
    std::fs::create_dir_all(&dir)?;
    let net = inputs.join("calyx_veins.json");
    let weld = ReadArgs::default();
    let cells_obj = dir.join("cells.obj");
    let cells = super::cells::execute(&super::cells::Args {
        input: net.clone(),
        surface: Some(inputs.join("calyx.obj")),
        output: cells_obj.clone(),
        table: Some(dir.join("cells.json")),
        json: false,
        weld: weld.clone(),
    })?;
    let mut outputs = vec![
        "calyx/cells.obj".to_string(),
        "calyx/cells.json".to_string(),
    ];
    let mut facts = format!(
        "{} cells in {} triangles; {}. ",
        cells.cells.cells.len(),
        cells.cells.mesh.triangles.len(),
        cells.notes[1..].join("; ")
    );
    let mut axes = Vec::new();
    for (method, name) in [
        (MethodArg::Newton, "newton"),
        (MethodArg::Lbfgs, "lbfgs"),
        (MethodArg::Projection, "projection"),
    ] {
        let file = |ext: &str| dir.join(format!("{name}{ext}"));
        let done = super::planarize::execute(&super::planarize::Args {
            input: net.clone(),
            surface: Some(cells_obj.clone()),
            method,
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
            output: file("-axes.json"),
            panels: Some(file("-panels.obj")),
            reports: ReportArgs {
                report: Some(file("-report.json")),
                html: Some(file("-report.html")),
                json: false,
            },
            weld: weld.clone(),
        })?;
        let s = &done.solution;
        let _ = write!(
            facts,
            "{name}: max panel deviation {:.4} mm after {} iterations (α {:.1e}), \
             <a href=\"calyx/{name}-report.html\">report</a>. ",
            s.max_deviation, s.iterations, s.alpha_used
        );
        for ext in ["-axes.json", "-panels.obj", "-report.json", "-report.html"] {
            outputs.push(format!("calyx/{name}{ext}"));
        }
        axes.push(s.axes.clone());
    }
    let apart = |k: usize| lamina::stage::planarize::largest_axis_angle(&axes[0], &axes[k]);
    let _ = write!(
        facts,
        "L-BFGS's axes differ from Gauss-Newton's by at most {:.3}°, projection's by {:.3}°.",
        apart(1),
        apart(2)
    );
    let panels = read_mesh(&dir.join("newton-panels.obj"))?;
    write_mesh(&panels, &dir.join("panels.png"), size)?;
    outputs.push("calyx/panels.png".into());
    Ok(Entry {
        name: "Calyx: cells and planar panels".into(),
        about: "`lamina cells` on the venation network and its guide surface, then `lamina \
                planarize` by Gauss-Newton (the default), by L-BFGS and by iterative projection: 100 mm panels on every vein, \
                tolerance 0.01 mm, base plates held to +Z (`--fix-normal 'z<1:0,0,1'`)"
            .into(),
        outputs,
        preview: "calyx/panels.png".into(),
        facts,
    })
}

/// From the Gauss-Newton axes to steel: plates in seven assembly groups (base ring at 6 mm, the rest
/// by vein radius), nested on 3000 × 1500 sheets per thickness.
fn steel(out: &Path, nest_time: f64) -> Result<(Entry, Headline)> {
    let dir = out.join("calyx");
    let joints = super::plates::JointArgs {
        node_core: Some(
            lamina::rationalize::plates::CoreSize::parse("tube:60.3,4")
                .map_err(anyhow::Error::msg)?,
        ),
        ..Default::default()
    };
    let sized = super::size::execute(&super::size::Args {
        input: dir.join("newton-axes.json"),
        output: dir.join("sizing.json"),
        material: Some("1.4404".into()),
        gauges: vec![1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0],
        support: vec![(
            Selector::parse("z<1").map_err(anyhow::Error::msg)?,
            Support::Fixed,
        )],
        load: vec!["self-weight".into()],
        deflection_limit: Some(DeflectionLimit::Ratio(500.0)),
        group_by: GroupBy::Member,
        groups: Some(7),
        smooth: true,
        throat: 0.7,
        max_rounds: 20,
        shells: None,
        joints: joints.clone(),
        html: Some(dir.join("sizing.html")),
        export_ccx: Some(dir.join("sizing.inp")),
        json: false,
    })?;
    let plates = super::plates::execute(&super::plates::Args {
        input: dir.join("newton-axes.json"),
        gauges: None,
        sizing: Some(dir.join("sizing.json")),
        thickness: None,
        edge_thickness: vec![],
        joints,
        min_weld_angle: None,
        material: None,
        groups: 7,
        output: dir.join("plates"),
        json: false,
    })?;
    let sheet = DVec2::new(3000.0, 1500.0);
    let nest = super::nest::execute(&super::nest::Args {
        input: dir.join("plates/plates.json"),
        sheet: None,
        // Illustrative prices per sheet: the cheapest mix per thickness is cut.
        stock: Some(vec![
            lamina::stage::nest::Stock {
                size: sheet,
                cost: 240.0,
            },
            lamina::stage::nest::Stock {
                size: DVec2::new(2000.0, 1000.0),
                cost: 115.0,
            },
            lamina::stage::nest::Stock {
                size: DVec2::new(1000.0, 1000.0),
                cost: 62.0,
            },
        ]),
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
        kerf: 0.3,
        cut_order: super::nest::CutOrderArg::Travel,
        common_line: false,
        job: Some("CALYX".into()),
        date: None,
        nc: Some(super::nest::NcArg::Gcode),
        post: None,
        nc_on: None,
        nc_off: None,
        time: nest_time,
        output: dir.join("cut"),
        json: false,
    })?;
    let built = plates.summary();
    let mass = plates.set.mass_kg(plates.material.density);
    let sz = &sized.sizing;
    let (_, dmax) = sz.max_displacement();
    let lower_upper = sz.mean_gauges_low_high();
    let mut facts = format!(
        "Sized by `lamina size` under self-weight with the base fixed and a deflection limit of          L/500: {} stress round(s), {} deflection round(s), largest displacement {dmax:.2} mm,          utilisation at most {:.2}, welds at most {:.2}; mean gauge {:.2} mm in the lower third          of the members, {:.2} mm in the upper third. ",
        sz.rounds,
        sz.deflection_rounds,
        sz.max_utilisation(),
        sz.max_weld_utilisation(),
        lower_upper.0,
        lower_upper.1
    );
    if !sized.ok {
        facts.push_str("NOT ENOUGH: over-utilised even on the thickest gauge or over the limit. ");
    }
    let _ = write!(
        facts,
        "{} plates in {} groups, {} seams as two plies from the gauge list bolted face to face, as sized          ({} bolts), {mass:.1} kg of stainless steel. Welds: {} nodes, root gaps 1 ± 0.5 mm at {},          {} with a node core (tube 60.3 × 4); smallest dihedral angle {:.1}°. Nested on {} sheets,          one family per thickness, rotations exactly 0/90/180/270: ",
        built.plates,
        built.groups,
        built.seams,
        built.bolts,
        plates.welds.summary.nodes,
        plates.welds.summary.even_nodes,
        plates.welds.summary.cores,
        plates.welds.summary.smallest_dihedral_deg,
        nest.sheets.len()
    );
    let per: Vec<String> = nest
        .sheets
        .iter()
        .map(|s| {
            format!(
                "{} mm: {} parts on {} × {}, {:.1} %, laser {:.0} min",
                s.thickness,
                s.parts.len(),
                s.stock.size.x,
                s.stock.size.y,
                100.0 * s.utilisation(),
                s.time_s.0 / 60.0
            )
        })
        .collect();
    let _ = write!(
        facts,
        "{}. OpenSCAD rebuilds the sculpture from the sheet DXFs with          <code>openscad cut/assembly.scad</code>.",
        per.join("; ")
    );
    let mut outputs: Vec<String> = [
        "sizing.html",
        "sizing.json",
        "sizing.inp",
        "plates/welds.html",
        "plates/welds.json",
        "plates/plates.json",
        "plates/assembly.stl",
        "plates/assembly.obj",
        "plates/assembly.scad",
        "cut/sheets.svg",
        "cut/bom.csv",
        "cut/nest.json",
        "cut/assembly.scad",
    ]
    .iter()
    .map(|f| format!("calyx/{f}"))
    .collect();
    outputs.extend(nest.sheets.iter().map(|s| format!("calyx/cut/{}", s.file)));
    // The LinuxCNC programs beside each sheet (0.3 mm kerf).
    outputs.extend(
        nest.sheets
            .iter()
            .map(|s| format!("calyx/cut/{}", s.file.replace(".dxf", ".ngc"))),
    );
    let assembly = read_mesh(&dir.join("plates/assembly.stl"))?;
    write_mesh(&assembly, &dir.join("plates/assembly.png"), 1000)?;
    outputs.push("calyx/plates/assembly.png".into());
    let w = &plates.welds.summary;
    let area: f64 = nest
        .sheets
        .iter()
        .map(|s| s.stock.size.x * s.stock.size.y)
        .sum();
    let used: f64 = nest
        .sheets
        .iter()
        .map(|s| s.utilisation() * s.stock.size.x * s.stock.size.y)
        .sum();
    let job = Headline {
        job: "Steel: the Calyx in plates".into(),
        what: "A 2 m venation sculpture as flat stainless plates: sized by a frame analysis, \
               cut back for even weld gaps at every node, seams bolted, nested on sheets with \
               etched tags."
            .into(),
        figures: vec![
            (
                "plates".into(),
                format!(
                    "{} in {} groups; {} node cores",
                    built.plates,
                    built.groups,
                    plates.set.cores.len()
                ),
            ),
            (
                "mass".into(),
                format!("{mass:.1} kg (1.4404), {} bolts", built.bolts),
            ),
            (
                "worst utilisation".into(),
                format!(
                    "{:.2} (welds {:.2})",
                    sz.max_utilisation(),
                    sz.max_weld_utilisation()
                ),
            ),
            (
                "weld pairs by angle".into(),
                format!(
                    "{} below 60° · {} AWS only · {} butt · {} fillet",
                    w.pairs_below_60, w.pairs_120_135, w.pairs_over_135, w.pairs_60_120
                ),
            ),
            (
                "sheets".into(),
                format!(
                    "{} sheets, {:.1} % used",
                    nest.sheets.len(),
                    100.0 * used / area.max(f64::MIN_POSITIVE)
                ),
            ),
        ],
        preview: "calyx/plates/assembly.png".into(),
        links: vec![
            ("3D viewer".into(), "view/calyx-plates.html".into()),
            ("sheets".into(), "view/calyx-sheets.html".into()),
            ("weld report".into(), "calyx/plates/welds.html".into()),
            ("sizing report".into(), "calyx/sizing.html".into()),
        ],
    };
    let entry = Entry {
        name: "Calyx: plates, bolted seams, welds and the cut plan".into(),
        about: "`lamina size` on the Gauss-Newton axes (a 3D frame of the plates, stainless 1.4404,                 self-weight, base fixed, `--deflection-limit L/500 --smooth --groups 7 --node-core tube:60.3,4`, seams as their two plies, the self-weight the plates as cut with their bolts and node cores: sizing.html,                 sizing.json and the CalculiX deck), then `lamina plates --sizing sizing.json`                 (the analysis' gauges, weld gap 1 mm, `--groups 7`,                 `--node-core tube:60.3,4`, bolts sized by the grip), then `lamina nest` on the                 cheapest of 3000 × 1500, 2000 × 1000 and 1000 × 1000 mm stock, margin 10 mm,                 spacing 5 mm, 2 mm lead-ins: the weld report, a cut DXF per sheet in cutting order                 (all etching first, parts on a short tour pierced at corners) with etched tags,                 marks and sheet labels, remnants, cut and rapid times, a LinuxCNC G-code program per                 sheet for a 0.3 mm kerf, the BOM with bolts and cores, nest.json and the OpenSCAD                 assembly"
            .into(),
        outputs,
        preview: "calyx/cut/sheets.svg".into(),
        facts,
    };
    Ok((entry, job))
}

/// The planarity audit of the Calyx's Gauss-Newton panels, as a shop would run it on panels
/// it received: ISO flatness of every panel against 0.01 mm, the report page and a CSV.
fn audit(out: &Path) -> Result<(Entry, Headline)> {
    let dir = out.join("calyx");
    let report = super::planarize::audit_execute(&super::planarize::AuditArgs {
        input: dir.join("newton-panels.obj"),
        tolerance: Some(0.01),
        tolerance_rules: None,
        metric: lamina::report::planarity::Metric::Flatness,
        csv: Some(dir.join("audit.csv")),
        reports: ReportArgs {
            report: Some(dir.join("audit.json")),
            html: Some(dir.join("audit.html")),
            json: false,
        },
    })?;
    let s = &report.summary;
    let worst = report.worst.first().map_or_else(
        || "none".to_string(),
        |r| {
            format!(
                "P{}: {} mm ({:.0} % of the tolerance)",
                r.index,
                lamina::text::sig3(r.metrics.flatness),
                100.0 * r.metrics.flatness / r.tolerance
            )
        },
    );
    let within = s.panels - s.above_tolerance;
    let job = Headline {
        job: "Audit: are the panels flat?".into(),
        what: "The Calyx's panels as an OBJ, checked as a shop checks what it receives: ISO 1101 \
               flatness of every panel against its tolerance, the worst first."
            .into(),
        figures: vec![
            (
                "panels within 0.01 mm".into(),
                format!("{within} of {}", s.panels),
            ),
            ("worst panel (flatness)".into(), worst.clone()),
            (
                "largest torsion".into(),
                format!("{}°", lamina::text::sig3(s.max_torsion_deg)),
            ),
        ],
        preview: "calyx/panels.png".into(),
        links: vec![
            ("report and 3D view".into(), "calyx/audit.html".into()),
            ("CSV".into(), "calyx/audit.csv".into()),
        ],
    };
    let entry = Entry {
        name: "Calyx: planarity audit of the panels".into(),
        about: "`lamina audit calyx/newton-panels.obj --tolerance 0.01 --csv audit.csv --html \
                audit.html`: every panel's ISO 1101 flatness (minimum zone), best-fit and corner \
                figures and torsion, held to 0.01 mm"
            .into(),
        outputs: ["audit.html", "audit.json", "audit.csv"]
            .iter()
            .map(|f| format!("calyx/{f}"))
            .collect(),
        preview: "calyx/panels.png".into(),
        facts: format!(
            "{within} of {} panels within 0.01 mm; worst {worst}; mean flatness {} mm.",
            s.panels,
            lamina::text::sig3(s.mean_deviation)
        ),
    };
    Ok((entry, job))
}

/// Closed surface venation and smoothed geodesic veins on one mesh, each rendered on it (the
/// density plate grows open venation with its colours as the density map).
fn surface_veins(out: &Path, mesh_path: &Path, about: &str, size: u32) -> Result<Entry> {
    let mesh = read_mesh(mesh_path)?;
    let stem = mesh_path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("surface")
        .to_string();
    let dir = out.join("on-surfaces");
    std::fs::create_dir_all(&dir)?;
    let density = (stem == "density_halves").then_some(Channel::Luminance);
    let mode = if density.is_some() {
        Mode::Open
    } else {
        Mode::Closed
    };
    let opts = venation::Options {
        mode,
        sources: Some(3000),
        density_channel: density,
        ..Default::default()
    };
    // The torus's growth is also kept every 10 steps, for a strip of five moments up to the end.
    let (murray, tip) = {
        let s = venation::surface_options(&mesh, &opts)?;
        (s.murray, s.tip_radius)
    };
    let mut moments: Vec<Vec<Stroke3>> = Vec::new();
    let mut keep = |f: &Frame<DVec3>| {
        moments.push(lamina::grow::frames::surface_strokes(f, murray, tip));
    };
    let frames = (stem == "torus").then_some(venation::Frames {
        every: 10,
        call: &mut keep,
    });
    let grown = venation::on_surface(&mesh, &[], &opts, frames, &Quiet)
        .with_context(|| format!("venation on {}", mesh_path.display()))?;
    let mut outputs = Vec::new();
    let mut growth_link = String::new();
    if moments.len() >= 5 {
        let last = moments.len() - 1;
        let pngs = (1..=5)
            .map(|k| render_png_bytes_with(&mesh, &moments[k * last / 5], (size / 4).max(16)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(anyhow::Error::msg)?;
        let strip = format!("on-surfaces/{stem}-growth.png");
        let bytes = lamina::grow::frames::strip(&pngs).map_err(anyhow::Error::msg)?;
        write_atomic(&out.join(&strip), |w| std::io::Write::write_all(w, &bytes))?;
        growth_link =
            format!(" The growth in five moments (`--frames`): <a href=\"{strip}\">strip</a>.");
        outputs.push(strip);
    }
    let venation_json = format!("on-surfaces/{stem}-venation.json");
    let venation_png = format!("on-surfaces/{stem}-venation.png");
    super::surface::write_outputs(
        &grown.veins.network,
        &mesh,
        &out.join(&venation_json),
        None,
        Some(&out.join(&venation_png)),
        size,
    )?;
    outputs.extend([venation_json, venation_png.clone()]);
    let veins = lamina::stage::veins::run(
        &mesh,
        &lamina::stage::veins::Options {
            sources: Some(300),
            density_channel: density,
            smooth: 3,
            ..Default::default()
        },
        &Quiet,
    )?;
    let veins_json = format!("on-surfaces/{stem}-veins.json");
    let veins_png = format!("on-surfaces/{stem}-veins.png");
    super::surface::write_outputs(
        &veins.network,
        &mesh,
        &out.join(&veins_json),
        None,
        Some(&out.join(&veins_png)),
        size,
    )?;
    outputs.extend([veins_json, veins_png.clone()]);
    let how = match density {
        Some(_) => "open, density from the vertex luminance",
        None => "closed",
    };
    Ok(Entry {
        name: format!("veins on {stem}"),
        about: format!(
            "On {about}: surface venation ({how}, about 3,000 sources, `lamina venation --surface`) \
             and geodesic veins along mesh edges (about 300 sources, smoothed, `lamina veins \
             --smooth 3`). Second picture: <a href=\"{veins_png}\">geodesic veins</a>.{growth_link}"
        ),
        outputs,
        preview: venation_png,
        facts: format!(
            "venation: {}; geodesic veins: {} tree vertices to {} sources in {} iterations",
            grown.veins.quality.lines().join("; "),
            veins.report.tree_vertices,
            veins.report.sources,
            veins.report.iterations
        ),
    })
}

/// The viewer pages under `view/`, each listed with the entry (by name) whose outputs it shows.
const VIEWERS: &[(&str, &str, &str, &[&str])] = &[
    (
        "calyx_veins.json",
        "network",
        "calyx-network.html",
        &["inputs/calyx_veins.json"],
    ),
    (
        "venation leaf (closed)",
        "veins",
        "leaf-closed.html",
        &["venation/leaf-closed.json"],
    ),
    (
        "veins on calyx",
        "venation on the band",
        "calyx-venation.html",
        &["on-surfaces/calyx-venation.json", "inputs/calyx.obj"],
    ),
    (
        "façade (L-system tree)",
        "tree on the wall",
        "facade-on-wall.html",
        &["facade/facade-on-wall.json", "facade/wall.obj"],
    ),
    (
        "Calyx: cells and planar panels",
        "panels by deviation",
        "calyx-panels.html",
        &["calyx/newton-axes.json"],
    ),
    (
        "Calyx: plates, bolted seams, welds and the cut plan",
        "plates, welds, utilisation",
        "calyx-plates.html",
        &[
            "calyx/plates/plates.json",
            "calyx/plates/welds.json",
            "calyx/sizing.json",
        ],
    ),
    (
        "Calyx: plates, bolted seams, welds and the cut plan",
        "cut sheets",
        "calyx-sheets.html",
        &["calyx/cut/nest.json"],
    ),
    (
        "Fabrication-aware networks: simplified, then cut",
        "simplified band",
        "band-simple.html",
        &["simplify/band-simple.json"],
    ),
    (
        "growth forms (bud programs)",
        "holes (mesh)",
        "buds-holes.html",
        &["buds/holes.stl"],
    ),
    (
        "print: leaf → solid → slices",
        "print layers and islands",
        "print-layers.html",
        &["print/leaf.sl1"],
    ),
];

/// Writes the viewers; per entry, the (label, page) pairs to link.
fn viewers(out: &Path, entries: &[Entry]) -> Result<Vec<Vec<(String, String)>>> {
    let dir = out.join("view");
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("{}: cannot create folder", dir.display()))?;
    let mut links = vec![Vec::new(); entries.len()];
    for (entry, label, page, files) in VIEWERS {
        let k = entries
            .iter()
            .position(|e| e.name == *entry)
            .with_context(|| format!("the demo has no entry `{entry}` for its {label} viewer"))?;
        let paths: Vec<std::path::PathBuf> = files.iter().map(|f| out.join(f)).collect();
        let refs: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
        super::view::write_view(&refs, &dir.join(page), &format!("lamina demo: {label}"))?;
        links[k].push((label.to_string(), format!("view/{page}")));
    }
    Ok(links)
}
