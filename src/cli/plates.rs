//! `lamina plates axes.json -o DIR`: steel plates from node axes (plates.json, assembly.stl).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use lamina::files::write_atomic;
use lamina::mesh::io::write_mesh;
use lamina::rationalize::axes::read_axes;
use lamina::rationalize::plates::{plates, Plate, PlateOptions, Thickness};
use lamina::TriMesh;

#[derive(ClapArgs)]
pub struct Args {
    /// The axes file `lamina planarize` wrote
    pub input: PathBuf,
    /// Sheet thicknesses available, mm, ascending
    #[arg(long, value_delimiter = ',', default_value = "1.5,2,3,4,5,6")]
    pub gauges: Vec<f64>,
    /// Every plate this thick, mm [default: from the vein radii, thicker veins on thicker gauges]
    #[arg(long)]
    pub thickness: Option<f64>,
    /// Gap left between plates meeting at a node, for the weld, mm
    #[arg(long, default_value_t = 1.0)]
    pub weld_gap: f64,
    /// Output folder (made if missing): plates.json, assembly.stl
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

pub struct Outcome {
    pub plates: Vec<Plate>,
}

pub fn execute(args: &Args) -> Result<Outcome> {
    let axes = read_axes(&args.input)?;
    let opts = PlateOptions {
        gauges: args.gauges.clone(),
        thickness: match args.thickness {
            Some(t) => Thickness::Constant(t),
            None => Thickness::FromRadius,
        },
        weld_gap: args.weld_gap,
    };
    let plates = plates(&axes, &opts).with_context(|| format!("{}", args.input.display()))?;
    if args.output.exists() && !args.output.is_dir() {
        bail!("{}: exists and is not a folder", args.output.display());
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create folder", args.output.display()))?;
    write_plates_json(&plates, &opts, &args.output.join("plates.json"))?;
    write_mesh(&assembly(&plates), &args.output.join("assembly.stl"), 0)?;
    Ok(Outcome { plates })
}

pub fn run(args: Args) -> Result<()> {
    let Outcome { plates } = execute(&args)?;
    let area: f64 = plates.iter().map(|p| p.area()).sum();
    let volume: f64 = plates.iter().map(|p| p.area() * p.thickness).sum();
    let flattening = plates.iter().map(|p| p.flattening).fold(0.0, f64::max);
    if args.json {
        println!(
            "{}",
            json!({
                "output": args.output,
                "plates": plates.len(),
                "area_mm2": area,
                "volume_mm3": volume,
                "max_flattening_mm": flattening,
            })
        );
    } else {
        println!(
            "{}: {} plates, {:.3} m² of plate, {:.1} kg of stainless steel; panels flattened by at most {:.4} mm",
            args.output.display(),
            plates.len(),
            area * 1e-6,
            volume * 7.9e-6,
            flattening
        );
    }
    Ok(())
}

/// Every plate as a closed prism, in one mesh (disjoint shells).
pub fn assembly(plates: &[Plate]) -> TriMesh {
    let mut mesh = TriMesh::default();
    for p in plates {
        let (v, t) = p.prism();
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(v);
        mesh.triangles
            .extend(t.iter().map(|tri| tri.map(|i| i + base)));
    }
    mesh
}

fn write_plates_json(plates: &[Plate], opts: &PlateOptions, path: &Path) -> Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "{{")?;
        writeln!(w, "  \"format\": \"lamina-plates\",")?;
        writeln!(w, "  \"version\": 1,")?;
        writeln!(w, "  \"units\": \"mm\",")?;
        writeln!(w, "  \"gauges\": {},", json!(opts.gauges))?;
        writeln!(w, "  \"weld_gap\": {},", json!(opts.weld_gap))?;
        writeln!(w, "  \"plates\": [")?;
        for (k, p) in plates.iter().enumerate() {
            let rec = json!({
                "edge": p.edge,
                "nodes": p.nodes,
                "thickness": p.thickness,
                "setback": p.setback,
                "partners": p.partners,
                "area_mm2": p.area(),
                "flattening_mm": p.flattening,
                "matrix": p.placement.matrix(),
                "outline": p.outline.iter().map(|q| [q.x, q.y]).collect::<Vec<_>>(),
            });
            let sep = if k + 1 < plates.len() { "," } else { "" };
            writeln!(w, "    {rec}{sep}")?;
        }
        writeln!(w, "  ]")?;
        writeln!(w, "}}")
    })?;
    Ok(())
}
