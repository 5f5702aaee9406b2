//! `lamina venation`: grow an open or closed leaf venation in a built-in or given blade, with
//! optional density map, darts per step, blade growth, a Peele r sweep, and animation frames.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::{Args as ClapArgs, ValueEnum};
use glam::DVec2;
use serde_json::json;

use lamina::files::write_atomic;
use lamina::grow::density::DensityMap;
use lamina::grow::frames::{render_frame, View};
use lamina::grow::leaf::Leaf;
use lamina::grow::outline::{Outline, Shape};
use lamina::grow::outline_file::read_outline;
use lamina::grow::surface::Channel;
use lamina::grow::venation::Frame;
use lamina::mesh::io::check_render_size;
use lamina::network::io::{write_network, RenderOptions};
use lamina::stage::venation::{self, BladeGrowth, Frames, Grown, Mode, Placement};

use super::progress::Bar;

#[derive(Clone, Copy, ValueEnum)]
pub enum ShapeArg {
    Ovate,
    Lanceolate,
    Cordate,
    Circle,
    Rect,
}

impl From<ShapeArg> for Shape {
    fn from(s: ShapeArg) -> Shape {
        match s {
            ShapeArg::Ovate => Shape::Ovate,
            ShapeArg::Lanceolate => Shape::Lanceolate,
            ShapeArg::Cordate => Shape::Cordate,
            ShapeArg::Circle => Shape::Circle,
            ShapeArg::Rect => Shape::Rect,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum SweepByArg {
    Blade,
    Step,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ModeArg {
    Open,
    Closed,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum BladeArg {
    None,
    Uniform,
    Marginal,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum ChannelArg {
    Red,
    Green,
    Blue,
    Luminance,
}

impl From<ChannelArg> for Channel {
    fn from(c: ChannelArg) -> Channel {
        match c {
            ChannelArg::Red => Channel::Red,
            ChannelArg::Green => Channel::Green,
            ChannelArg::Blue => Channel::Blue,
            ChannelArg::Luminance => Channel::Luminance,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum PlacementArg {
    Poisson,
    Random,
}

#[derive(ClapArgs)]
pub struct Args {
    /// Built-in blade, 100 mm from base to tip; the root is the petiole at its base
    #[arg(long, value_enum, default_value = "ovate", conflicts_with = "outline")]
    pub shape: ShapeArg,
    /// Grow on this triangle mesh (.obj .stl) instead of in a blade (Gokmen §3.3)
    #[arg(
        long,
        value_name = "MESH",
        conflicts_with_all = ["outline", "blade", "r", "sweep_r", "density", "placement"]
    )]
    pub surface: Option<PathBuf>,
    /// On a surface: density from this vertex colour (dark = dense), from --birth-min (darkest)
    /// to --birth-max (lightest)
    #[arg(long, value_enum, requires = "surface")]
    pub density_channel: Option<ChannelArg>,
    /// On a surface: sources farther than this from a node do not pull it, mm [default: 4 ×
    /// the largest birth distance]
    #[arg(long, requires = "surface")]
    pub reach: Option<f64>,
    #[command(flatten)]
    pub surface_weld: super::surface::SurfaceWeld,
    /// On a surface: a step or loop edge whose chord leaves the surface by more than this is
    /// not made, mm [default: D / 4]
    #[arg(long, requires = "surface")]
    pub edge_tolerance: Option<f64>,
    /// Blade outline from a file: network JSON/OBJ or DXF (a closed polyline), or SVG
    /// (<polygon>, <path>); the largest closed loop is used
    #[arg(long, value_name = "FILE")]
    pub outline: Option<PathBuf>,
    /// Root node (repeat for several): X,Y in mm in a blade; on a surface a vertex index V, a
    /// triangle tT (its centroid) or a point X,Y,Z (snapped) [default: the petiole at the base;
    /// on a surface the lowest vertex of each body]
    #[arg(long, value_name = "X,Y|V|tT|X,Y,Z")]
    pub root: Vec<String>,
    /// Open venation grows trees; closed venation joins veins into loops [default: closed, or
    /// open with --sweep-r, as Peele's Figure 1]
    #[arg(long, value_enum)]
    pub mode: Option<ModeArg>,
    /// Output network (.json .obj .dxf .svg .png); with --sweep-r, a folder
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write an SVG render
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Also write a PNG render
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Write the quality report as JSON here
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Longer side of PNG renders, in pixels
    #[arg(long, default_value_t = 2048)]
    pub size: u32,
    /// Random seed: the same seed gives the same bytes
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// D, the length of each vein segment, mm [default: 0.75; on a surface min(birth / 2,
    /// 0.9 × mean edge length)]
    #[arg(long)]
    pub step: Option<f64>,
    /// Kill distance: sources this close to a vein are removed, mm [default: 1.1; on a surface
    /// 1.5 D]
    #[arg(long)]
    pub kill: Option<f64>,
    /// Birth distance: Poisson-disk radius of the sources, and the distance darts keep, mm
    /// [default: 1.5; on a surface the radius that places --sources]
    #[arg(long)]
    pub birth: Option<f64>,
    /// Density map (PNG over the blade's bounding box; dark = dense, from alpha if any pixel is
    /// transparent, else grey)
    #[arg(long, value_name = "PNG")]
    pub density: Option<PathBuf>,
    /// With --density or --density-channel: the birth distance where the map is darkest
    /// [default: --birth]
    #[arg(long)]
    pub birth_min: Option<f64>,
    /// With --density or --density-channel: the birth distance where the map is lightest
    /// [default: 2 × --birth]
    #[arg(long)]
    pub birth_max: Option<f64>,
    /// Place about this many initial sources (Poisson radius chosen to fit), or exactly this
    /// many with --placement random [on a surface, default: 3000 unless --birth is given]
    #[arg(long, value_name = "N", conflicts_with = "density")]
    pub sources: Option<usize>,
    /// How initial sources are placed [default: poisson]
    #[arg(long, value_enum)]
    pub placement: Option<PlacementArg>,
    /// Darts thrown each step (Peele §3.1.2) [default: 0, or 20 when the blade grows]
    #[arg(long, value_name = "N")]
    pub sources_per_step: Option<usize>,
    /// Blade growth during the simulation [default: none, or marginal with --r/--sweep-r]
    #[arg(long, value_enum)]
    pub blade: Option<BladeArg>,
    /// Blade size at the first step, as a fraction of the outline
    #[arg(long, default_value_t = 0.2)]
    pub initial_scale: f64,
    /// Blade size added per step, as a fraction of the outline [default: 0.005]
    #[arg(long, conflicts_with = "r")]
    pub blade_rate: Option<f64>,
    /// Peele's r = vein growth rate / leaf growth rate: sets --blade-rate from --step so the
    /// farthest margin point moves D / r per step
    #[arg(long, conflicts_with = "sweep_r")]
    pub r: Option<f64>,
    /// Grow one leaf per r (Peele Fig. 1: 0.5,1.5,3.5,5.5) into the folder -o, side by side
    #[arg(
        long,
        value_name = "R,R,…",
        value_delimiter = ',',
        conflicts_with_all = ["frames", "svg", "png", "report"]
    )]
    pub sweep_r: Vec<f64>,
    /// With --sweep-r: leaves grown per r, from --seed up; sweep.json gets each measure's mean,
    /// standard deviation, least and greatest per r
    #[arg(long, value_name = "N", default_value_t = 1, requires = "sweep_r")]
    pub seeds: usize,
    /// With --sweep-r: what sets r, the blade's growth rate (D stays --step) or D (the blade
    /// rate stays --blade-rate; Peele's way)
    #[arg(long, value_enum, default_value = "blade", requires = "sweep_r")]
    pub sweep_by: SweepByArg,
    /// Closed venation: longest loop-closing edge, mm [default: 2 × --kill]
    #[arg(long)]
    pub join_distance: Option<f64>,
    /// Closed venation: an open tip joins a node at most this many degrees off its heading
    #[arg(long, default_value_t = 60.0)]
    pub join_angle: f64,
    /// No two vein segments at a node meet at less than this many degrees: a step that would
    /// is turned to it (or not taken), a join that would is not made [default: joins only, at
    /// 25]
    #[arg(long, value_name = "DEG")]
    pub min_joint_angle: Option<f64>,
    /// A branch or join that would leave a member (the veins between two three-legged joints)
    /// shorter than this is not made, mm; 0: off
    #[arg(long, value_name = "MM", default_value_t = 0.0)]
    pub min_member: f64,
    /// Murray exponent n: r_parent^n = sum of r_child^n
    #[arg(long, default_value_t = 3.0)]
    pub murray: f64,
    /// Radius of vein tips (and loop-closing edges), mm [default: 0.1; on a surface D / 7.5]
    #[arg(long)]
    pub tip_radius: Option<f64>,
    /// Stop after this many growth steps
    #[arg(long, default_value_t = 10_000)]
    pub max_iterations: usize,
    /// Write a PNG frame of the growth into this folder every --every steps
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// Steps between frames
    #[arg(long, default_value_t = 10, requires = "frames")]
    pub every: usize,
    /// Longer side of frames, in pixels
    #[arg(long, default_value_t = 720, requires = "frames")]
    pub frame_size: u32,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

fn parse_point(s: &str) -> Result<DVec2, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [x, y] = parts[..] else {
        return Err(format!("expected X,Y in mm, got \"{s}\""));
    };
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("\"{t}\" is not a finite number"))
    };
    Ok(DVec2::new(num(x)?, num(y)?))
}

/// The stage's options from the flags (the density map read).
pub fn options(args: &Args) -> Result<venation::Options> {
    let root = if args.surface.is_some() {
        Vec::new()
    } else {
        args.root
            .iter()
            .map(|r| parse_point(r).map_err(|e| anyhow::anyhow!("--root: {e}")))
            .collect::<Result<_>>()?
    };
    Ok(venation::Options {
        mode: match args.mode {
            Some(ModeArg::Open) => Mode::Open,
            Some(ModeArg::Closed) => Mode::Closed,
            None if args.sweep_r.is_empty() => Mode::Closed,
            None => Mode::Open,
        },
        root,
        step: args.step,
        kill: args.kill,
        birth: args.birth,
        density: args.density.as_deref().map(DensityMap::read).transpose()?,
        birth_min: args.birth_min,
        birth_max: args.birth_max,
        sources: args.sources,
        placement: args.placement.map(|p| match p {
            PlacementArg::Poisson => Placement::Poisson,
            PlacementArg::Random => Placement::Random,
        }),
        sources_per_step: args.sources_per_step,
        blade: args.blade.map(|b| match b {
            BladeArg::None => BladeGrowth::None,
            BladeArg::Uniform => BladeGrowth::Uniform,
            BladeArg::Marginal => BladeGrowth::Marginal,
        }),
        initial_scale: args.initial_scale,
        blade_rate: args.blade_rate.unwrap_or(0.005),
        r: args.r,
        join_distance: args.join_distance,
        join_angle: args.join_angle,
        min_joint_angle: args.min_joint_angle,
        min_member: args.min_member,
        murray: args.murray,
        tip_radius: args.tip_radius,
        max_iterations: args.max_iterations,
        seed: args.seed,
        density_channel: args.density_channel.map(Channel::from),
        reach: args.reach,
        edge_tolerance: args.edge_tolerance,
    })
}

/// The blade: the outline file's, or the built-in shape.
fn blade(args: &Args) -> Result<Outline> {
    Ok(match &args.outline {
        Some(path) => read_outline(path)?,
        None => Outline::shape(args.shape.into()),
    })
}

/// Ok(false) when growth on a surface left a body without a root (outputs written).
pub fn run(args: Args) -> Result<bool> {
    if let Some(mesh) = &args.surface {
        return super::surface::venation(&args, mesh);
    }
    args.surface_weld.only_with("--surface")?;
    let opts = options(&args)?;
    let outline = blade(&args)?;
    if !args.sweep_r.is_empty() {
        return sweep(&args, &outline, &opts).map(|()| true);
    }
    let mut grown = grow_with_frames(&args, &outline, &opts)?;
    let render = RenderOptions { size: args.size };
    write_network(&grown.leaf.network, &args.output, &render)?;
    for extra in [&args.svg, &args.png].into_iter().flatten() {
        write_network(&grown.leaf.network, extra, &render)?;
    }
    grown.report.output = Some(args.output.display().to_string());
    if let Some(path) = &args.report {
        write_json(path, &grown.report)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string(&grown.report)?);
    } else {
        print_summary(&args.output, &grown.leaf);
    }
    Ok(true)
}

/// The folder `--frames` names, made after checking `--every` and `--frame-size`; none
/// without `--frames`. A folder this run made is removed again if the run fails (drop the guard
/// without `keep`).
pub fn frames_dir(args: &Args) -> Result<Option<FramesDir<'_>>> {
    let Some(dir) = &args.frames else {
        return Ok(None);
    };
    if args.every == 0 {
        bail!("--every must be at least 1");
    }
    check_render_size(args.frame_size).map_err(|m| anyhow::anyhow!("--frame-size: {m}"))?;
    Ok(Some(FramesDir::create(dir)?))
}

/// The frames folder of a run; removed on drop when this run made it and did not finish.
pub struct FramesDir<'a> {
    pub path: &'a Path,
    remove: bool,
}

impl FramesDir<'_> {
    /// Makes the folder (if missing) for a run that has checked all its flags.
    pub fn create(path: &Path) -> Result<FramesDir<'_>> {
        let created = !path.exists();
        std::fs::create_dir_all(path)
            .with_context(|| format!("--frames {}: cannot create the folder", path.display()))?;
        Ok(FramesDir {
            path,
            remove: created,
        })
    }

    /// The run finished: the folder stays.
    pub fn keep(mut self) {
        self.remove = false;
    }
}

impl Drop for FramesDir<'_> {
    fn drop(&mut self) {
        if self.remove {
            let _ = std::fs::remove_dir_all(self.path);
        }
    }
}

/// Writes one frame's PNG (or the render's failure) into the frames folder.
pub fn save_frame(dir: &Path, step: usize, png: Result<Vec<u8>, String>) -> Result<()> {
    let bytes = png.map_err(|m| anyhow::anyhow!("--frames: {m}"))?;
    let path = dir.join(format!("frame-{step:05}.png"));
    write_atomic(&path, |w| std::io::Write::write_all(w, &bytes))?;
    Ok(())
}

fn grow_with_frames(args: &Args, outline: &Outline, opts: &venation::Options) -> Result<Grown> {
    let Some(frames) = frames_dir(args)? else {
        return Ok(venation::run(outline, opts, None, &Bar::new())?);
    };
    let dir = frames.path;
    let (lo, hi) = outline.bounds();
    let view = View {
        lo,
        hi,
        size: args.frame_size,
    };
    let murray = opts.murray;
    let tip = opts.tip_radius.unwrap_or(0.1);
    let mut failure: Option<anyhow::Error> = None;
    let mut write = |f: &Frame| {
        if failure.is_none() {
            let png = render_frame(f, &view, murray, tip);
            failure = save_frame(dir, f.step, png).err();
        }
    };
    let grown = venation::run(
        outline,
        opts,
        Some(Frames {
            every: args.every,
            call: &mut write,
        }),
        &Bar::new(),
    )?;
    if let Some(e) = failure {
        return Err(e);
    }
    frames.keep();
    Ok(grown)
}

fn print_summary(output: &Path, leaf: &Leaf) {
    let g = &leaf.growth;
    outln!(
        "wrote {}: {} steps ({}); {} of {} sources left unreached",
        output.display(),
        g.iterations,
        serde_json::to_value(g.stop)
            .ok()
            .and_then(|v| v.as_str().map(str::to_owned))
            .unwrap_or_default(),
        g.sources_left,
        g.sources_placed
    );
    for line in leaf.quality.lines() {
        outln!("  {line}");
    }
}

pub(super) fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let text = venation::json_text(value);
    write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    Ok(())
}

/// Peele Fig. 1: one leaf per r and seed; the table of the two claims' measures per r, and a
/// figure of the leaves side by side above those measures.
fn sweep(args: &Args, outline: &Outline, opts: &venation::Options) -> Result<()> {
    let dir = &args.output;
    // Checked and grown first: a refused option leaves no folder behind.
    let by = match args.sweep_by {
        SweepByArg::Blade if args.blade_rate.is_some() => anyhow::bail!(
            "--blade-rate: a sweep by blade sets the blade rate from each r; --sweep-by step \
             keeps it and sets D instead"
        ),
        SweepByArg::Blade => venation::SweepBy::Blade,
        SweepByArg::Step if args.step.is_some() => anyhow::bail!(
            "--step: a sweep by step sets D from each r; --sweep-by blade keeps it and sets the \
             blade rate instead"
        ),
        SweepByArg::Step => venation::SweepBy::Step,
    };
    let leaves = venation::sweep(outline, opts, &args.sweep_r, by, args.seeds, &Bar::new())?;
    let table = write_sweep(dir, &leaves, args.seeds, by, args.size)?;
    if !args.json {
        let mode = match opts.mode {
            Mode::Open => "open",
            Mode::Closed => "closed",
        };
        outln!(
            "{mode} venation, r set by the {}, {} seed(s) per r from {}; per r the mean ± \
             standard deviation:",
            match by {
                venation::SweepBy::Blade => "blade's growth rate",
                venation::SweepBy::Step => "vein step D",
            },
            args.seeds,
            args.seed
        );
        let rows = venation::sweep_table(&leaves);
        for row in &rows {
            outln!(
                "r = {}: {:.1} ± {:.1} dominant veins (radius ≥ half the petiole's), their radius \
                 {:.3} ± {:.3} of the petiole's; zigzag {:.2} ± {:.2}°, turning {:.2} ± {:.2}°/mm \
                 along dominant veins",
                row.r,
                row.dominant.mean,
                row.dominant.sd,
                row.dominant_radius_ratio.mean,
                row.dominant_radius_ratio.sd,
                row.zigzag_deg.mean,
                row.zigzag_deg.sd,
                row.turning_deg_per_mm.mean,
                row.turning_deg_per_mm.sd
            );
        }
        for line in venation::sweep_verdict(&rows) {
            outln!("{line}");
        }
    }
    if args.json {
        outln!("{table}");
    } else {
        outln!("wrote {}/sweep.json and sweep.svg", dir.display());
    }
    Ok(())
}

/// Writes a sweep into the folder `dir`: each leaf's network (JSON and a PNG `size` pixels
/// long), sweep.json (each leaf's report with its r, seed, blade rate and D; the table per r;
/// the verdict) and sweep.svg (the leaves and the measures). Returns sweep.json's value.
pub fn write_sweep(
    dir: &Path,
    leaves: &[venation::SweptLeaf],
    seeds: usize,
    by: venation::SweepBy,
    size: u32,
) -> Result<serde_json::Value> {
    let render = RenderOptions { size };
    std::fs::create_dir_all(dir)
        .with_context(|| format!("-o {}: cannot create the folder", dir.display()))?;
    let mut rows = Vec::new();
    for swept in leaves {
        let (r, leaf) = (swept.r, &swept.grown.leaf);
        let name = if seeds == 1 {
            format!("r-{r}")
        } else {
            format!("r-{r}-seed-{}", swept.seed)
        };
        write_network(&leaf.network, &dir.join(format!("{name}.json")), &render)?;
        write_network(&leaf.network, &dir.join(format!("{name}.png")), &render)?;
        let mut report = swept.grown.report.clone();
        // By name: the runs sit beside sweep.json, wherever the folder is.
        report.output = Some(format!("{name}.json"));
        let mut row = serde_json::to_value(&report)?;
        row["r"] = json!(r);
        row["seed"] = json!(swept.seed);
        row["blade_rate"] = json!(swept.blade_rate);
        row["step"] = json!(swept.step);
        rows.push(row);
    }
    let table = venation::sweep_table(leaves);
    let verdict = venation::sweep_verdict(&table);
    let value =
        json!({ "sweep": "peele-r", "by": by, "leaves": rows, "table": table, "verdict": verdict });
    write_json(&dir.join("sweep.json"), &value)?;
    let svg = venation::sweep_figure(leaves);
    write_atomic(&dir.join("sweep.svg"), |w| {
        std::io::Write::write_all(w, svg.as_bytes())
    })?;
    Ok(value)
}
