//! Venation on a surface (`lamina venation --surface`) and geodesic veins (`lamina veins`):
//! reading the mesh and roots, and writing the network, its render on the surface and the
//! report.

use std::path::Path;

use anyhow::{bail, Context, Result};
use glam::DVec3;
use serde_json::json;

use super::input::{weld_mesh, ReadArgs};
use super::venation::{frames_dir, save_frame, write_json, Args, ModeArg};
use lamina::files::extension;
use lamina::grow::surface::{self, grow_on_surface, Channel, Root, SurfaceOptions};
use lamina::grow::venation::{Frame, Mode, Observer};
use lamina::grow::{frames, murray};
use lamina::mesh::io::{
    read_mesh, render_png_bytes_with, write_png_with_strokes, Stroke3, BACKGROUND, VEIN,
};
use lamina::network::io::{write_network, RenderOptions};
use lamina::network::{Network, Weld};
use lamina::TriMesh;
use tiny_skia::{Pixmap, PixmapPaint, Transform};

/// Sources placed on a surface when neither --sources nor --birth is given.
pub const DEFAULT_SOURCES: usize = 3000;

/// `V` a vertex, `tT` a triangle, `X,Y,Z` a point.
pub fn parse_root(s: &str) -> Result<Root> {
    let t = s.trim();
    if let Some(tri) = t.strip_prefix('t') {
        return tri
            .parse()
            .map(Root::Triangle)
            .with_context(|| format!("--root {s}: tT needs a triangle index"));
    }
    if !t.contains(',') {
        return t
            .parse()
            .map(Root::Vertex)
            .with_context(|| format!("--root {s}: expected a vertex index, tT or X,Y,Z"));
    }
    let parts: Vec<f64> = t
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--root {s}: X,Y,Z needs three numbers"))?;
    let [x, y, z] = parts[..] else {
        bail!("--root {s}: a point on a surface needs X,Y,Z");
    };
    Ok(Root::Point(DVec3::new(x, y, z)))
}

/// A surface to grow on, without the degenerate triangles (said on stderr) that no surface
/// query can use.
pub fn read_surface(path: &Path, weld: &SurfaceWeld) -> Result<TriMesh> {
    let tolerance = weld.weld()?;
    let mut mesh = read_mesh(path)?;
    if let Some(w) = tolerance {
        weld_mesh(path, &mut mesh, w, false);
    }
    let dropped = mesh.drop_degenerate();
    if mesh.triangles.is_empty() {
        bail!(
            "--surface {}: has no triangles with an area ({dropped} degenerate)",
            path.display()
        );
    }
    if dropped > 0 {
        errln!(
            "lamina: --surface {}: {dropped} degenerate triangles (a vertex used twice or no \
             area) left out",
            path.display()
        );
    }
    Ok(mesh)
}

/// Welding a surface mesh before anything grows on it: CAD STLs whose shared corners differ in
/// the last bits read as cracked, and growth stops at a crack.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct SurfaceWeld {
    /// Weld mesh vertices closer than this, in mm (CAD meshes whose shared corners differ in
    /// the last bits) [default: none: only equal coordinates are one vertex]
    #[arg(long, value_name = "MM", conflicts_with = "weld_rel")]
    pub weld: Option<f64>,
    /// Weld mesh vertices closer than this fraction of the bounding-box diagonal
    #[arg(long, value_name = "FRACTION")]
    pub weld_rel: Option<f64>,
}

impl SurfaceWeld {
    /// The weld asked for, checked as every reader's `--weld` is; `None` when not asked.
    pub fn weld(&self) -> Result<Option<Weld>> {
        if self.weld.is_none() && self.weld_rel.is_none() {
            return Ok(None);
        }
        let read = ReadArgs {
            weld: self.weld,
            weld_rel: self.weld_rel,
            ..ReadArgs::default()
        };
        Ok(Some(read.options()?.weld))
    }

    /// Refuses the flags where there is no mesh for them to weld.
    pub fn only_with(&self, mesh_flag: &str) -> Result<()> {
        if self.weld.is_some() || self.weld_rel.is_some() {
            bail!("--weld and --weld-rel weld the mesh given with {mesh_flag}; there is none");
        }
        Ok(())
    }
}

/// `lamina venation --surface MESH`.
pub fn venation(args: &Args, path: &Path) -> Result<()> {
    let mesh = read_surface(path, &args.surface_weld)?;
    let roots: Vec<Root> = args
        .root
        .iter()
        .map(|r| parse_root(r))
        .collect::<Result<_>>()?;
    let density = args.density_channel.map(Channel::from);
    if density.is_none() && (args.birth_min.is_some() || args.birth_max.is_some()) {
        bail!("--birth-min and --birth-max need --density-channel on a surface");
    }
    if args.sources.is_some() && args.birth.is_some() {
        bail!("--sources and --birth both set the source spacing on a surface: give one");
    }
    let mode = match args.mode {
        ModeArg::Open => Mode::Open,
        ModeArg::Closed => Mode::Closed,
    };
    let mut opts = SurfaceOptions::for_mesh(
        &mesh,
        mode,
        args.sources.unwrap_or(DEFAULT_SOURCES),
        density,
    );
    if let Some(b) = args.birth_min.or(args.birth) {
        opts.birth_min = b;
    }
    opts.birth_max = match (args.birth_max, density) {
        (Some(b), _) => b,
        (None, Some(_)) => 2.0 * opts.birth_min,
        (None, None) => opts.birth_min,
    };
    let g = &mut opts.growth;
    g.step = args
        .step
        .unwrap_or_else(|| surface::default_step(&mesh, opts.birth_min));
    g.kill = args.kill.unwrap_or(1.5 * g.step);
    g.max_iterations = args.max_iterations;
    g.sources_per_step = args.sources_per_step.unwrap_or(0);
    g.join_distance = args.join_distance;
    g.join_angle = args.join_angle;
    g.min_joint_angle = args.min_joint_angle;
    g.min_member = args.min_member;
    opts.tip_radius = args.tip_radius.unwrap_or(g.step / 7.5);
    opts.reach = args.reach;
    opts.edge_tolerance = args.edge_tolerance;
    opts.murray = args.murray;
    opts.seed = args.seed;
    let veins = grow_with_frames(args, &mesh, &roots, &opts)
        .with_context(|| format!("--surface {}", path.display()))?;
    let u = veins.quality.unrooted;
    if u.bodies_without_root > 0 {
        errln!(
            "lamina: --surface {}: {} of its {} bodies have no root, so growth cannot reach \
             them: {} sources there left out (give a --root on each body to grow on it)",
            path.display(),
            u.bodies_without_root,
            u.bodies,
            u.sources_left_out
        );
    }
    let mut net = veins.network;
    net.meta
        .parameters
        .insert("surface".into(), json!(path.display().to_string()));
    write_outputs(
        &net,
        &mesh,
        &args.output,
        args.svg.as_deref(),
        args.png.as_deref(),
        args.size,
    )?;
    let g = &veins.growth;
    let summary = json!({
        "output": args.output,
        "surface": path,
        "nodes": net.nodes.len(),
        "edges": net.edges.len(),
        "iterations": g.iterations,
        "stop": g.stop,
        "sources_placed": g.sources_placed,
        "sources_left": g.sources_left,
        "loop_edges": g.joins.len(),
        "step": opts.growth.step,
        "kill": opts.growth.kill,
        "birth_min": opts.birth_min,
        "birth_max": opts.birth_max,
        "quality": veins.quality,
    });
    if let Some(report) = &args.report {
        write_json(report, &summary)?;
    }
    if args.json {
        outln!("{summary}");
    } else {
        outln!(
            "wrote {}: {} steps, D = {:.4} mm, kill {:.4} mm, {} sources",
            args.output.display(),
            g.iterations,
            opts.growth.step,
            opts.growth.kill,
            g.sources_placed
        );
        for line in veins.quality.lines() {
            outln!("  {line}");
        }
    }
    Ok(())
}

/// Grows on the surface, writing a render of the growth so far every `--every` steps (and after
/// the last) when `--frames` is given: the veins with the Murray widths of the tree of that
/// moment, loop edges at the tip radius, live sources as blue dots. The mesh fixes the view,
/// so the frames line up.
fn grow_with_frames(
    args: &Args,
    mesh: &TriMesh,
    roots: &[Root],
    opts: &SurfaceOptions,
) -> Result<surface::SurfaceVeins> {
    let Some(frames) = frames_dir(args)? else {
        return Ok(grow_on_surface(mesh, roots, opts, None)?);
    };
    let dir = frames.path;
    let mut failure: Option<anyhow::Error> = None;
    let mut write = |f: &Frame<DVec3>| {
        if failure.is_none() {
            let strokes = frame_strokes(f, opts.murray, opts.tip_radius);
            let png = render_png_bytes_with(mesh, &strokes, args.frame_size);
            failure = save_frame(dir, f.step, png).err();
        }
    };
    let veins = grow_on_surface(
        mesh,
        roots,
        opts,
        Some(Observer {
            every: args.every,
            call: &mut write,
        }),
    )?;
    match failure {
        Some(e) => Err(e),
        None => {
            frames.keep();
            Ok(veins)
        }
    }
}

/// A growth frame as strokes: live sources first (dots), then the veins over them.
pub fn frame_strokes(f: &Frame<DVec3>, exponent: f64, tip: f64) -> Vec<Stroke3> {
    let radius = murray::radii(f.parent, exponent, tip);
    let dots = f.sources.iter().map(|&s| Stroke3 {
        a: s,
        b: s,
        radius: tip,
        color: frames::SOURCE,
    });
    let tree = f.parent.iter().enumerate().filter_map(|(c, p)| {
        p.map(|p| Stroke3 {
            a: f.positions[p as usize],
            b: f.positions[c],
            radius: radius[c],
            color: VEIN,
        })
    });
    let joins = f.joins.iter().map(|&[a, b]| Stroke3 {
        a: f.positions[a as usize],
        b: f.positions[b as usize],
        radius: tip,
        color: VEIN,
    });
    dots.chain(tree).chain(joins).collect()
}

/// PNG images side by side on one row, top aligned, on the renders' background.
pub fn strip(pngs: &[Vec<u8>]) -> Result<Vec<u8>> {
    let images = pngs
        .iter()
        .map(|p| Pixmap::decode_png(p).context("a frame that does not decode"))
        .collect::<Result<Vec<_>>>()?;
    let width = images.iter().map(Pixmap::width).sum::<u32>();
    let height = images.iter().map(Pixmap::height).max().unwrap_or(0);
    let mut row = Pixmap::new(width, height).context("a strip of no pixels")?;
    let [r, g, b] = BACKGROUND;
    row.fill(tiny_skia::Color::from_rgba8(r, g, b, 0xff));
    let mut x = 0;
    for image in &images {
        row.draw_pixmap(
            x as i32,
            0,
            image.as_ref(),
            &PixmapPaint::default(),
            Transform::identity(),
            None,
        );
        x += image.width();
    }
    row.encode_png().context("encoding the strip")
}

/// The network to `output` (a .png output is the render on the surface), plus the extra
/// renders asked for.
pub fn write_outputs(
    net: &Network,
    mesh: &TriMesh,
    output: &Path,
    svg: Option<&Path>,
    png: Option<&Path>,
    size: u32,
) -> Result<()> {
    let render = RenderOptions { size };
    for path in [Some(output), svg, png].into_iter().flatten() {
        if extension(path) == "png" {
            write_png_with_strokes(mesh, &strokes(net), path, size)?;
        } else {
            write_network(net, path, &render)?;
        }
    }
    Ok(())
}

/// The network's edges as strokes for a render on its surface.
pub fn strokes(net: &Network) -> Vec<Stroke3> {
    net.edges
        .iter()
        .map(|e| Stroke3 {
            a: net.nodes[e.a as usize].p,
            b: net.nodes[e.b as usize].p,
            radius: e.radius,
            color: VEIN,
        })
        .collect()
}
