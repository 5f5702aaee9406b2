//! One module per subcommand: an argument struct and a `run` that calls the library. The
//! command line itself (`Cli`, `Command`, `dispatch`) lives here so that the Python package can
//! run a command in-process with the same parsing, code and messages as the binary.

// What the commands print goes through `say` (stdout and stderr for the binary, a buffer when the
// Python package runs a command).
macro_rules! outln {
    () => { $crate::cli::say::out(format_args!("\n")) };
    ($($t:tt)*) => { $crate::cli::say::out(format_args!("{}\n", format_args!($($t)*))) };
}
macro_rules! out {
    ($($t:tt)*) => { $crate::cli::say::out(format_args!($($t)*)) };
}
macro_rules! errln {
    ($($t:tt)*) => { $crate::cli::say::note(format_args!($($t)*)) };
}

pub mod bifurcate;
pub mod branching;
pub mod buds;
pub mod cells;
pub mod convert;
pub mod demo;
pub mod info;
pub mod input;
pub mod lsystem;
pub mod nest;
pub mod planarize;
pub mod plates;
pub mod print;
pub mod progress;
pub mod render;
pub mod say;
pub mod simplify;
pub mod size;
pub mod sl1;
pub mod slice;
pub mod solid;
pub mod surface;
pub mod veins;
pub mod venation;
pub mod view;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "lamina",
    version,
    about = "Grow branching structures and turn polyline networks into buildable, checked parts"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Counts, bounding box, degrees, components, cycles, lengths and every problem of a network
    /// (.json .obj .dxf) or a mesh (.obj .stl).
    Info(info::Args),
    /// Convert between formats, chosen by extension (networks: json obj dxf svg png; meshes: obj
    /// stl png).
    Convert(convert::Args),
    /// Render a network (SVG or PNG) or a mesh (PNG).
    Render(render::Args),
    /// Grow leaf venation, open or closed, in a built-in or given blade (Runions et al. 2005),
    /// or on a triangle mesh with --surface (Gokmen §3.3)
    Venation(Box<venation::Args>),
    /// Geodesic veins along the edges of a mesh, from a root vertex to source vertices
    /// (Bachman), with shortest paths kept up to date incrementally
    Veins(Box<veins::Args>),
    /// Derive a bracketed L-system and draw it with a 2D/3D turtle (runs of F merged into
    /// members), or only count it; optionally fitted to a façade boundary and projected onto a
    /// surface (Hanafin et al.)
    Lsystem(Box<lsystem::Args>),
    /// A tree by recursive bifurcation (fixed or random angles and scales), optionally fitted
    /// to a façade boundary and projected onto a surface (Hanafin et al.)
    Bifurcate(Box<bifurcate::Args>),
    /// Grow a bud program into a cellular surface (Hart, "Growth Forms"): cell division, spring
    /// embedding, buds with tropism, splitting, line buds and holes; STL/OBJ with textures as
    /// geometry
    Buds(Box<buds::Args>),
    /// Fewer, straighter members for fabrication: chains of degree-2 nodes to the fewest straight
    /// members within a deviation, junctions merged, branches pruned by Horton-Strahler order,
    /// sharp joints repaired; a report before and after; exit 1 when a sharp joint is left.
    Simplify(Box<simplify::Args>),
    /// The closed cells of a network on a surface (faces of its rotation system), triangulated
    /// by constrained Delaunay, with per-node normals and V − E + F checked against the surface.
    Cells(cells::Args),
    /// Node axes that make every panel of a network planar (Gauss-Newton by default; L-BFGS or
    /// the paper's iterative projection by --method), with the panels and a planarity report.
    Planarize(Box<planarize::Args>),
    /// Frame analysis of the plate network and the gauges it needs: thinnest gauges with
    /// utilisation at most 1, a deflection limit, weld utilisation (sizing.json, HTML,
    /// a CalculiX deck); exit 1 when the thickest gauge is not enough.
    Size(Box<size::Args>),
    /// Steel plates from node axes: one flat plate per edge in its panel plane, thickness from a
    /// gauge list, cut back at the nodes so plates do not interpenetrate (plates.json,
    /// assembly.stl).
    Plates(plates::Args),
    /// Nest plates on stock sheets, one sheet family per thickness: a cut DXF per sheet,
    /// bom.csv, nest.json, assembly.scad rebuilt from the sheets, and sheets.svg.
    Nest(Box<nest::Args>),
    /// Check the planarity of panels (.obj faces, .dxf 3DFACE, polyface meshes, MESH and closed
    /// polylines, lamina axes or plates): ISO flatness, best fit and the corner figure, each
    /// panel against its tolerance class; exit 0 when all are within, 1 when some are not.
    Audit(planarize::AuditArgs),
    /// A vein network as one watertight, 2-manifold mesh for printing: tapered round veins,
    /// optional lamina and base, scaled to a print size.
    Solid(solid::Args),
    /// Slice closed meshes for a masked-SLA (DMP-SL) printer: anti-aliased layer PNGs in an
    /// SL1 archive (PrusaSlicer layout), with resin volume, cost and build time.
    Slice(Box<slice::Args>),
    /// A network's solid sliced straight from its signed distance into an SL1 archive, with no
    /// mesh in between: the same layers as `solid` then `slice`, in a fraction of the memory.
    Print(Box<print::Args>),
    /// Read an SL1 archive back and check it (ours or PrusaSlicer's).
    Sl1(sl1::Args),
    /// One offline HTML page to look before you cut: networks, meshes, panels by deviation,
    /// plates by group, gauge or utilisation with their welds, cut sheets, print layers with
    /// islands (three.js embedded; opens without a network).
    View(Box<view::Args>),
    /// Run the whole way on the embedded fixtures and write every output with an index.html.
    Demo(demo::Args),
}

/// Runs a parsed command: Ok(false) when its result missed its tolerance (exit 1).
pub fn dispatch(command: Command) -> anyhow::Result<bool> {
    match command {
        Command::Info(args) => info::run(args).map(|()| true),
        Command::Convert(args) => convert::run(args).map(|()| true),
        Command::Render(args) => render::run(args).map(|()| true),
        Command::Venation(args) => venation::run(*args),
        Command::Veins(args) => veins::run(*args).map(|()| true),
        Command::Lsystem(args) => lsystem::run(*args).map(|()| true),
        Command::Bifurcate(args) => bifurcate::run(*args).map(|()| true),
        Command::Buds(args) => buds::run(*args),
        Command::Solid(args) => solid::run(args).map(|()| true),
        Command::Slice(args) => slice::run(*args).map(|()| true),
        Command::Print(args) => print::run(*args).map(|()| true),
        Command::Sl1(args) => sl1::run(args),
        Command::View(args) => view::run(*args).map(|()| true),
        Command::Demo(args) => demo::run(args).map(|()| true),
        Command::Cells(args) => cells::run(args).map(|()| true),
        Command::Simplify(args) => simplify::run(*args),
        Command::Planarize(args) => planarize::run(*args),
        Command::Size(args) => size::run(*args),
        Command::Plates(args) => plates::run(args),
        Command::Nest(args) => nest::run(*args).map(|()| true),
        Command::Audit(args) => planarize::audit_run(args),
    }
}

/// The message of an error as the binary prints it: the chain of causes, each once (library
/// errors already quote their source), options as flags, without control characters.
pub fn error_message(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg = format!("{msg}: {c}");
        }
    }
    lamina::text::printable(&as_flags(&msg)).into_owned()
}

/// Library messages name an option as its field, `tolerance=`; the command line says
/// `--tolerance`. Only names that are flags of some command are turned.
pub fn as_flags(msg: &str) -> String {
    use clap::CommandFactory;
    use std::collections::HashMap;
    use std::sync::OnceLock;
    static FLAGS: OnceLock<HashMap<String, String>> = OnceLock::new();
    let flags = FLAGS.get_or_init(|| {
        let mut map = HashMap::new();
        fn walk(cmd: &clap::Command, map: &mut HashMap<String, String>) {
            for a in cmd.get_arguments() {
                if let Some(long) = a.get_long() {
                    map.insert(long.replace('-', "_"), long.to_string());
                }
            }
            for sub in cmd.get_subcommands() {
                walk(sub, map);
            }
        }
        walk(&Cli::command(), &mut map);
        map
    });
    let mut out = String::with_capacity(msg.len() + 8);
    let bytes = msg.as_bytes();
    let mut i = 0;
    while i < msg.len() {
        let word = |b: u8| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_';
        let starts = bytes[i].is_ascii_lowercase() && (i == 0 || !word(bytes[i - 1]));
        if starts {
            let end = (i..msg.len())
                .find(|&j| !word(bytes[j]))
                .unwrap_or(msg.len());
            if bytes.get(end) == Some(&b'=') {
                if let Some(long) = flags.get(&msg[i..end]) {
                    out.push_str("--");
                    out.push_str(long);
                    i = end + 1;
                    continue;
                }
            }
            out.push_str(&msg[i..end]);
            i = end;
            continue;
        }
        let ch = msg[i..].chars().next().expect("a character");
        out.push(ch);
        i += ch.len_utf8();
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn options_become_flags() {
        assert_eq!(
            super::as_flags("tolerance= must be positive; give tolerance_rules= or lead_in="),
            "--tolerance must be positive; give --tolerance-rules or --lead-in"
        );
        // Not flags: left as they are.
        assert_eq!(
            super::as_flags("node=3 and x=1, a= b"),
            "node=3 and x=1, a= b"
        );
    }

    /// Every flag and argument of every command says what it is: `--help` with a bare
    /// `--seed <SEED> [default: 1]` leaves a newcomer guessing.
    #[test]
    fn every_argument_of_every_command_is_described() {
        use clap::CommandFactory;
        let mut missing = Vec::new();
        let mut check = |cmd: &clap::Command, path: &str| {
            for arg in cmd.get_arguments() {
                let id = arg.get_id().as_str();
                if id == "help" || id == "version" {
                    continue;
                }
                let said = arg
                    .get_long_help()
                    .or(arg.get_help())
                    .map(|h| h.to_string())
                    .unwrap_or_default();
                // At least a few words, not only a default or a list of values.
                if said.split_whitespace().count() < 3 {
                    missing.push(format!("{path} {id}: {said:?}"));
                }
            }
        };
        let root = super::Cli::command();
        for sub in root.get_subcommands() {
            assert!(
                sub.get_about().is_some(),
                "{} has no description",
                sub.get_name()
            );
            check(sub, sub.get_name());
            for inner in sub.get_subcommands() {
                check(inner, &format!("{} {}", sub.get_name(), inner.get_name()));
            }
        }
        assert!(missing.is_empty(), "undescribed:\n{}", missing.join("\n"));
        // The list of commands names planarize's default solver (it once named two others).
        let planarize = root.find_subcommand("planarize").expect("a command");
        let about = planarize
            .get_about()
            .map(|a| a.to_string())
            .unwrap_or_default();
        let default = planarize
            .get_arguments()
            .find(|a| a.get_id() == "method")
            .and_then(|a| a.get_default_values().first().cloned())
            .expect("a default method");
        assert_eq!(default, "newton");
        assert!(about.contains("Gauss-Newton by default"), "{about}");
    }

    /// Every command's `--help`, as `docs/commands.md` holds it.
    fn commands_markdown() -> String {
        use clap::CommandFactory;
        use std::fmt::Write;
        let mut root = super::Cli::command();
        root.build();
        let mut out = String::from(
            "# lamina commands\n\n\
             Every command's `--help`, word for word. This file is written by a test \
             (`cli::tests::docs_commands_md_is_every_commands_help`), which fails when it differs \
             from the binary's help: run `LAMINA_BLESS=1 cargo test --bin lamina` after changing \
             a flag. The README's table says what each command is for.\n\n",
        );
        let _ = writeln!(out, "```text\n{}```\n", root.render_long_help());
        // A command's help under a heading, then its own commands' one level down.
        fn section(out: &mut String, depth: usize, path: &str, cmd: &mut clap::Command) {
            let path = format!("{path} {}", cmd.get_name());
            let _ = writeln!(
                out,
                "{} {path}\n\n```text\n{}```\n",
                "#".repeat(depth),
                cmd.render_long_help()
            );
            for inner in cmd.get_subcommands_mut().filter(|c| c.get_name() != "help") {
                section(out, depth + 1, &path, inner);
            }
        }
        for sub in root
            .get_subcommands_mut()
            .filter(|c| c.get_name() != "help")
        {
            section(&mut out, 2, "lamina", sub);
        }
        out
    }

    #[test]
    fn docs_commands_md_is_every_commands_help() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/commands.md");
        let want = commands_markdown();
        if std::env::var_os("LAMINA_BLESS").is_some() {
            std::fs::write(&path, &want).expect("docs/commands.md written");
        }
        let have = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            have == want,
            "docs/commands.md is not the commands' --help: LAMINA_BLESS=1 cargo test --bin lamina"
        );
    }
}
