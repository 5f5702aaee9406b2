//! The `lamina` command: parse, call the library, print. No algorithms here.

mod cli;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "lamina",
    version,
    about = "Grow branching structures and turn polyline networks into buildable, checked parts"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Counts, bounding box, degrees, components, cycles, lengths and every problem of a network
    /// (.json .obj .dxf) or a mesh (.obj .stl).
    Info(cli::info::Args),
    /// Convert between formats, chosen by extension (networks: json obj dxf svg png; meshes: obj
    /// stl png).
    Convert(cli::convert::Args),
    /// Render a network (SVG or PNG) or a mesh (PNG).
    Render(cli::render::Args),
    /// Grow leaf venation, open or closed, in a built-in or given blade (Runions et al. 2005),
    /// or on a triangle mesh with --surface (Gokmen §3.3)
    Venation(Box<cli::venation::Args>),
    /// Geodesic veins along the edges of a mesh, from a root vertex to source vertices
    /// (Bachman), with shortest paths kept up to date incrementally
    Veins(Box<cli::veins::Args>),
    /// Derive a bracketed L-system and draw it with a 2D/3D turtle (runs of F merged into
    /// members), or only count it; optionally fitted to a façade boundary and projected onto a
    /// surface (Hanafin et al.)
    Lsystem(Box<cli::lsystem::Args>),
    /// A tree by recursive bifurcation (fixed or random angles and scales), optionally fitted
    /// to a façade boundary and projected onto a surface (Hanafin et al.)
    Bifurcate(Box<cli::bifurcate::Args>),
    /// Grow a bud program into a cellular surface (Hart, "Growth Forms"): cell division, spring
    /// embedding, buds with tropism, splitting, line buds and holes; STL/OBJ with textures as
    /// geometry
    Buds(Box<cli::buds::Args>),
    /// Fewer, straighter members for fabrication: chains of degree-2 nodes to the fewest straight
    /// members within a deviation, junctions merged, branches pruned by Horton-Strahler order,
    /// sharp joints repaired; a report before and after; exit 1 when a sharp joint is left.
    Simplify(Box<cli::simplify::Args>),
    /// The closed cells of a network on a surface (faces of its rotation system), triangulated
    /// by constrained Delaunay, with per-node normals and V − E + F checked against the surface.
    Cells(cli::cells::Args),
    /// Node axes that make every panel of a network planar (L-BFGS or iterative projection),
    /// with the panels and a planarity report.
    Planarize(Box<cli::planarize::Args>),
    /// Frame analysis of the plate network and the gauges it needs: thinnest gauges with
    /// utilisation at most 1, a deflection limit, weld utilisation (sizing.json, HTML,
    /// a CalculiX deck); exit 1 when the thickest gauge is not enough.
    Size(Box<cli::size::Args>),
    /// Steel plates from node axes: one flat plate per edge in its panel plane, thickness from a
    /// gauge list, cut back at the nodes so plates do not interpenetrate (plates.json,
    /// assembly.stl).
    Plates(cli::plates::Args),
    /// Nest plates on stock sheets, one sheet family per thickness: a cut DXF per sheet,
    /// bom.csv, nest.json, assembly.scad rebuilt from the sheets, and sheets.svg.
    Nest(Box<cli::nest::Args>),
    /// Check the planarity of panels (.obj faces, .dxf 3DFACE, polyface meshes, MESH and closed
    /// polylines, lamina axes or plates): ISO flatness, best fit and the corner figure, each
    /// panel against its tolerance class; exit 0 when all are within, 1 when some are not.
    Audit(cli::planarize::AuditArgs),
    /// A vein network as one watertight, 2-manifold mesh for printing: tapered round veins,
    /// optional lamina and base, scaled to a print size.
    Solid(cli::solid::Args),
    /// Slice closed meshes for a masked-SLA (DMP-SL) printer: anti-aliased layer PNGs in an
    /// SL1 archive (PrusaSlicer layout), with resin volume, cost and build time.
    Slice(Box<cli::slice::Args>),
    /// A network's solid sliced straight from its signed distance into an SL1 archive, with no
    /// mesh in between: the same layers as `solid` then `slice`, in a fraction of the memory.
    Print(Box<cli::print::Args>),
    /// Read an SL1 archive back and check it (ours or PrusaSlicer's).
    Sl1(cli::sl1::Args),
    /// One offline HTML page to look before you cut: networks, meshes, panels by deviation,
    /// plates by group, gauge or utilisation with their welds, cut sheets, print layers with
    /// islands (three.js embedded; opens without a network).
    View(Box<cli::view::Args>),
    /// Run the whole way on the embedded fixtures and write every output with an index.html.
    Demo(cli::demo::Args),
}

/// Whether a command's result met its tolerance (commands without one always do).
struct Within(bool);

fn within(ok: bool) -> Within {
    Within(ok)
}

impl From<()> for Within {
    fn from(_: ()) -> Within {
        Within(true)
    }
}

fn main() -> ExitCode {
    // The DXF parser's panics on values it cannot take are caught and reported as the file's
    // error; print nothing for them here. Every other panic is a bug and prints as usual.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().name() != Some(lamina::network::io::dxf::PARSER_THREAD) {
            default_hook(info);
        }
    }));
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(args) => cli::info::run(args).map(Within::from),
        Command::Convert(args) => cli::convert::run(args).map(Within::from),
        Command::Render(args) => cli::render::run(args).map(Within::from),
        Command::Venation(args) => cli::venation::run(*args).map(Within::from),
        Command::Veins(args) => cli::veins::run(*args).map(Within::from),
        Command::Lsystem(args) => cli::lsystem::run(*args).map(Within::from),
        Command::Bifurcate(args) => cli::bifurcate::run(*args).map(Within::from),
        Command::Buds(args) => cli::buds::run(*args).map(within),
        Command::Solid(args) => cli::solid::run(args).map(Within::from),
        Command::Slice(args) => cli::slice::run(*args).map(Within::from),
        Command::Print(args) => cli::print::run(*args).map(Within::from),
        Command::Sl1(args) => cli::sl1::run(args).map(within),
        Command::View(args) => cli::view::run(*args).map(Within::from),
        Command::Demo(args) => cli::demo::run(args).map(Within::from),
        Command::Cells(args) => cli::cells::run(args).map(Within::from),
        Command::Simplify(args) => cli::simplify::run(*args).map(within),
        Command::Planarize(args) => cli::planarize::run(*args).map(within),
        Command::Size(args) => cli::size::run(*args).map(within),
        Command::Plates(args) => cli::plates::run(args).map(within),
        Command::Nest(args) => cli::nest::run(*args).map(Within::from),
        Command::Audit(args) => cli::planarize::audit_run(args).map(within),
    };
    match result {
        Ok(Within(true)) => ExitCode::SUCCESS,
        // Outputs are written, but the tolerance was not met: 1, for scripts.
        Ok(Within(false)) => ExitCode::from(1),
        Err(e) => {
            // The chain of causes, each once: library errors already quote their source.
            let mut msg = e.to_string();
            for cause in e.chain().skip(1) {
                let c = cause.to_string();
                if !msg.contains(&c) {
                    msg = format!("{msg}: {c}");
                }
            }
            eprintln!("lamina: error: {}", lamina::text::printable(&msg));
            // Bad input and failed writes alike: 2, as clap uses for bad arguments.
            ExitCode::from(2)
        }
    }
}
