//! Venation on a surface (`lamina venation --surface`) and geodesic veins (`lamina veins`):
//! reading the mesh and roots, and writing the network, its render on the surface and the
//! report.

use std::path::Path;

use anyhow::{bail, Context, Result};
use glam::DVec3;
use serde_json::json;

use super::input::{weld_mesh, ReadArgs};
use super::progress::Bar;
use super::venation::{frames_dir, save_frame, write_json, Args};
use lamina::files::extension;
use lamina::grow::frames::surface_strokes;
use lamina::grow::surface::Root;
use lamina::grow::venation::Frame;
use lamina::mesh::io::{network_strokes, render_png_bytes_with, write_png_with_strokes};
use lamina::network::io::{write_network, RenderOptions};
use lamina::network::{Network, Weld};
use lamina::stage::venation::{self, Frames};
use lamina::TriMesh;

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
    let mut mesh = super::input::mesh_file(path)?;
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

/// `lamina venation --surface MESH`: Ok(false) (outputs written) when a body has no root.
pub fn venation(args: &Args, path: &Path) -> Result<bool> {
    let mesh = read_surface(path, &args.surface_weld)?;
    let roots: Vec<Root> = args
        .root
        .iter()
        .map(|r| parse_root(r))
        .collect::<Result<_>>()?;
    let opts = super::venation::options(args)?;
    let within = || format!("--surface {}", path.display());
    let grown = match frames_dir(args)? {
        None => {
            venation::on_surface(&mesh, &roots, &opts, None, &Bar::new()).with_context(within)?
        }
        Some(frames) => {
            // The mesh fixes the view, so the frames line up.
            let dir = frames.path;
            let resolved = venation::surface_options(&mesh, &opts).with_context(within)?;
            let (murray, tip) = (resolved.murray, resolved.tip_radius);
            let mut failure: Option<anyhow::Error> = None;
            let mut write = |f: &Frame<DVec3>| {
                if failure.is_none() {
                    let strokes = surface_strokes(f, murray, tip);
                    let png = render_png_bytes_with(&mesh, &strokes, args.frame_size);
                    failure = save_frame(dir, f.step, png).err();
                }
            };
            let grown = venation::on_surface(
                &mesh,
                &roots,
                &opts,
                Some(Frames {
                    every: args.every,
                    call: &mut write,
                }),
                &Bar::new(),
            )
            .with_context(within)?;
            if let Some(e) = failure {
                return Err(e);
            }
            frames.keep();
            grown
        }
    };
    for n in &grown.notes {
        errln!("lamina: --surface {}: {n}", path.display());
    }
    let mut net = grown.veins.network;
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
    let mut report = grown.report;
    report.output = Some(args.output.display().to_string());
    report.surface = Some(path.display().to_string());
    if let Some(path) = &args.report {
        write_json(path, &report)?;
    }
    if args.json {
        outln!("{}", serde_json::to_string(&report)?);
    } else {
        outln!(
            "wrote {}: {} steps, D = {:.4} mm, kill {:.4} mm, {} sources",
            args.output.display(),
            report.iterations,
            report.step,
            report.kill,
            report.sources_placed
        );
        for line in report.quality.lines() {
            outln!("  {line}");
        }
    }
    Ok(report.quality.unrooted.bodies_without_root == 0)
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
            write_png_with_strokes(mesh, &network_strokes(net), path, size)?;
        } else {
            write_network(net, path, &render)?;
        }
    }
    Ok(())
}
