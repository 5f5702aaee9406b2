//! `lamina buds PROGRAM`: grow a bud program (Hart, "Growth Forms") into a textured, printable
//! surface.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::Args as ClapArgs;

use super::progress::Bar;
use super::venation::FramesDir;
use lamina::grow::buds::read_program;
use lamina::mesh::io::write_mesh;
use lamina::mesh::TriMesh;
use lamina::stage::buds;

#[derive(ClapArgs)]
pub struct Args {
    /// The bud program (the paper's Figure 8 language; see `lamina demo`'s buds/figure8.bud)
    pub program: PathBuf,
    /// The form (.stl binary, or .obj with vertex colours)
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write an OBJ with vertex colours
    #[arg(long)]
    pub obj: Option<PathBuf>,
    /// Also write a PNG render
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Stop growing at this many cells
    #[arg(long, default_value_t = 10_000)]
    pub cells: usize,
    /// Random seed: the same seed gives the same bytes, others give other individuals
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Millimetres per unit cell size
    #[arg(long, default_value_t = 2.0)]
    pub cell_mm: f64,
    /// Distance, in cell sizes, at which parts of the form collide and their bud freezes
    #[arg(long, default_value_t = 0.9)]
    pub clearance: f64,
    /// Leave textures out of the geometry (colours stay)
    #[arg(long)]
    pub no_textures: bool,
    /// Write a PNG frame of the growth into this folder every `--every` cells
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// Cells between frames
    #[arg(long, default_value_t = 250)]
    pub every: usize,
    /// Longer side of PNG renders, in pixels
    #[arg(long, default_value_t = 1600)]
    pub size: u32,
    /// Write the report as JSON here
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Print the report as JSON
    #[arg(long)]
    pub json: bool,
}

/// Ok(false) when the form meets itself: its outputs are written (to look at), and the exit
/// status is 1, as for a tolerance not met.
pub fn run(args: Args) -> Result<bool> {
    let report = execute(&args)?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_summary(&report);
    }
    let meets = report["skin"]["self_intersections"].as_u64().unwrap_or(0);
    if meets > 0 {
        errln!(
            "lamina: the form meets itself at {meets} triangle pairs (outputs written); try a \
             larger --clearance"
        );
    }
    Ok(meets == 0)
}

/// Grows, skins and writes; returns the report.
pub fn execute(args: &Args) -> Result<serde_json::Value> {
    if args.output.is_none() && args.obj.is_none() && args.png.is_none() {
        bail!("give -o FORM (.stl .obj), --obj or --png");
    }
    if let Some(o) = &args.output {
        let ext = lamina::files::extension(o);
        if ext != "stl" && ext != "obj" {
            bail!("-o {}: the form is written as .stl or .obj", o.display());
        }
    }
    if args.every == 0 {
        bail!("--every 0: give at least 1 cell between frames");
    }
    lamina::mesh::io::check_render_size(args.size).map_err(|m| anyhow::anyhow!("--size: {m}"))?;
    let program = read_program(&args.program)?;
    let opts = buds::Options {
        cells: args.cells,
        seed: args.seed,
        cell_mm: args.cell_mm,
        clearance: args.clearance,
        no_textures: args.no_textures,
        program_name: lamina::files::file_name(&args.program),
    };
    // Made once the flags are checked; removed again if the run fails before its outputs.
    let frames_dir = args.frames.as_deref().map(FramesDir::create).transpose()?;
    let size = args.size.min(1024);
    let mut k = 0;
    let mut write_frame = |mesh: &TriMesh| {
        k += 1;
        let dir = frames_dir
            .as_ref()
            .map(|d| d.path)
            .unwrap_or(Path::new("."));
        write_mesh(mesh, &dir.join(format!("frame-{k:05}.png")), size).map_err(|e| e.to_string())
    };
    let frames = frames_dir.is_some().then_some(buds::Frames {
        every: args.every,
        call: &mut write_frame,
    });
    let grown = buds::run(&program, &opts, frames, &Bar::new())?;
    for o in [&args.output, &args.obj, &args.png].into_iter().flatten() {
        write_mesh(&grown.mesh, o, args.size)?;
    }
    let report = serde_json::to_value(&grown.report)?;
    if let Some(path) = &args.report {
        lamina::files::write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &report)?;
            Ok(())
        })?;
    }
    if let Some(dir) = frames_dir {
        dir.keep();
    }
    Ok(report)
}

fn print_summary(r: &serde_json::Value) {
    let g = &r["growth"];
    outln!(
        "{} cells in {} rounds ({} divisions), genus {} ({} holes, {} refused), stopped by {}",
        g["cells"],
        g["rounds"],
        g["divisions"],
        g["genus"],
        g["holes"],
        g["holes_refused"],
        g["stopped_by"]
    );
    outln!(
        "buds: {} made, {} died, {} froze, {} still live",
        g["buds_made"],
        g["buds_dead"],
        g["buds_frozen"],
        g["buds_live"]
    );
    let m = &r["mesh"];
    let s = &r["skin"];
    outln!(
        "mesh: {} triangles, closed {}, genus {}, volume {} mm³; {} textured cells ({} reduced), {} self-intersections",
        m["triangles"], m["closed"], m["genus"], m["volume_mm3"], s["textured_cells"], s["reduced_cells"], s["self_intersections"]
    );
}
