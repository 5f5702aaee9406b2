//! `lamina view FILE… -o view.html`: one offline page that shows any lamina input or output.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;

use super::input::{load, Loaded, ReadArgs};
use lamina::files::{extension, write_atomic};
use lamina::view::scene::{scene, what, Input};
use lamina::view::{page, Scene};

#[derive(ClapArgs)]
pub struct Args {
    /// Files to show together: a network (.json .obj .dxf), a mesh (.obj .stl), axes.json (its
    /// panels), plates.json (with the welds.json beside it, and sizing.json when given too),
    /// nest.json (its sheets, read from the cut DXFs beside it), an SL1 archive
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// The page to write
    #[arg(short, long, value_name = "HTML")]
    pub output: PathBuf,
    /// The page's title [default: the files' names]
    #[arg(long)]
    pub title: Option<String>,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// The `"format"` a lamina JSON file declares at its top level, if any.
fn json_format(path: &Path) -> Result<Option<String>> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    match std::str::from_utf8(&bytes) {
        Ok(text) => Ok(lamina::files::json_format(path, text).unwrap_or(None)),
        // Not text: the network reader says so, with the line.
        Err(_) => Ok(None),
    }
}

fn read(path: &Path, args: &ReadArgs) -> Result<Input> {
    let ext = extension(path);
    if ext == "sl1" {
        return Ok(Input::Print(path.to_path_buf()));
    }
    if ext == "json" {
        match json_format(path)?.as_deref() {
            Some("lamina-axes") => {
                let (axes, summary) = lamina::rationalize::axes::read_axes_and_summary(path)?;
                let tolerance = summary["tolerance"].as_f64().filter(|t| *t > 0.0);
                return Ok(Input::Axes(Box::new(axes), tolerance));
            }
            Some("lamina-plates") => {
                let (p, c, _) = lamina::fabricate::plates_file::read_plates(path)?;
                return Ok(Input::Plates(p, c));
            }
            Some("lamina-welds") => {
                let (g, t, n) = lamina::fabricate::plates_file::read_welds(path)?;
                return Ok(Input::Welds(g, t, n));
            }
            Some("lamina-sizing") => {
                return Ok(Input::Sizing(lamina::analyze::sizing::read_checks(path)?))
            }
            Some("lamina-nest") => return Ok(Input::Nest(path.to_path_buf())),
            _ => {}
        }
    }
    Ok(match load(path, args, false)? {
        Loaded::Network(imp) => Input::Network(Box::new(imp.network)),
        Loaded::Mesh(mesh, _) => Input::Mesh(mesh),
    })
}

pub fn run(args: Args) -> Result<()> {
    if extension(&args.output) != "html" {
        bail!("{}: the viewer is an .html page", args.output.display());
    }
    // Reader flags are checked whatever the files are, and refused where nothing reads them.
    args.read.options()?;
    let readers = args.files.iter().any(|p| {
        let ext = extension(p);
        ext == "obj"
            || ext == "stl"
            || ext == "dxf"
            || (ext == "json"
                && json_format(p)
                    .ok()
                    .flatten()
                    .is_none_or(|f| f == "lamina-network"))
    });
    if args.read.given() && !readers {
        bail!("the reader flags (--weld, --units, --chord-tolerance, …) apply to networks and meshes, and none is given");
    }
    let paths: Vec<&Path> = args.files.iter().map(PathBuf::as_path).collect();
    let scene = scene_with(&paths, &args.read, args.title.clone())?;
    let html = page(&scene);
    write_atomic(&args.output, |w| w.write_all(html.as_bytes()))?;
    for n in &scene.notes {
        errln!("lamina: {n}");
    }
    errln!(
        "lamina: wrote {} ({:.1} MB): {}",
        args.output.display(),
        html.len() as f64 / 1e6,
        what(&scene)
    );
    Ok(())
}

use std::io::Write as _;

/// A file's name, for notes on the page (the same page wherever the files lie).
fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Reads the files, adds the weld report beside a plates file when it was not given, and makes
/// the scene.
fn scene_with(files: &[&Path], args: &ReadArgs, title: Option<String>) -> Result<Scene> {
    let mut inputs: Vec<(PathBuf, Input)> = files
        .iter()
        .map(|p| Ok((p.to_path_buf(), read(p, args)?)))
        .collect::<Result<_>>()?;
    let mut notes = Vec::new();
    let has =
        |inputs: &[(PathBuf, Input)], f: &dyn Fn(&Input) -> bool| inputs.iter().any(|(_, i)| f(i));
    if !has(&inputs, &|i| matches!(i, Input::Welds(..))) {
        let beside = inputs.iter().find_map(|(p, i)| match i {
            Input::Plates(..) => Some(p.with_file_name("welds.json")),
            _ => None,
        });
        if let Some(w) = beside.filter(|w| w.is_file()) {
            let input = read(&w, args)?;
            notes.push("welds.json beside plates.json: its pairs are marked".to_string());
            inputs.push((w, input));
        }
    }
    let named: Vec<(String, Input)> = inputs
        .into_iter()
        .map(|(p, i)| (file_name(&p), i))
        .collect();
    let mut scene = scene(&named, title)?;
    scene.notes.splice(0..0, notes);
    Ok(scene)
}

/// The scene of `files` read with the default reader options (for the demo and the reports).
pub fn scene_of(files: &[&Path], title: &str) -> Result<Scene> {
    scene_with(files, &ReadArgs::default(), Some(title.to_string()))
}

/// Writes the viewer page of `files` to `output`.
pub fn write_view(files: &[&Path], output: &Path, title: &str) -> Result<Scene> {
    let scene = scene_of(files, title)?;
    write_atomic(output, |w| w.write_all(page(&scene).as_bytes()))?;
    Ok(scene)
}
