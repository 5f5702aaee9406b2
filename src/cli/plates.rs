//! `lamina plates axes.json -o DIR`: steel plates from node axes (plates.json, assembly.stl).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use glam::DVec2;
use lamina::fabricate::assembly::{write_scad, ScadPart};
use lamina::fabricate::cutsheet::{write_cut_dxf, Drawn};
use lamina::fabricate::tags::{fit, strokes, TAG_HEIGHT, TAG_MARGIN};
use lamina::files::write_atomic;
use lamina::mesh::io::write_mesh;
use lamina::rationalize::axes::read_axes;
use lamina::rationalize::plates::{plates, EdgeSelector, Plate, PlateOptions, Thickness};
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
    /// Thickness for some edges, over the rule: `SELECTOR:MM`, where SELECTOR is `edge=K` or a
    /// node selector both ends must match (`all`, `node=N`, `x|y|z` `<` `<=` `>` `>=` value),
    /// e.g. `z<1:6` for a 6 mm base ring; repeatable, a later match wins
    #[arg(long, value_parser = parse_override)]
    pub edge_thickness: Vec<(EdgeSelector, f64)>,
    /// Gap left between plates meeting at a node, for the weld, mm
    #[arg(long, default_value_t = 1.0)]
    pub weld_gap: f64,
    /// Assembly groups: connected, balanced by plate count, few seams; a seam plate becomes two
    /// half-thickness plates bolted face to face
    #[arg(long, default_value_t = 1)]
    pub groups: usize,
    /// Output folder (made if missing): plates.json, assembly.stl, assembly.obj (one object per
    /// plate), parts/ID.dxf (outline on CUT, etched tag on ETCH), assembly.scad
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print a machine-readable summary on stdout
    #[arg(long)]
    pub json: bool,
}

fn parse_override(s: &str) -> Result<(EdgeSelector, f64), String> {
    let (sel, t) = s
        .rsplit_once(':')
        .ok_or_else(|| format!("`{s}`: expected SELECTOR:MM, like z<1:6 or edge=12:4"))?;
    let t: f64 = t
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: `{t}` is not a thickness in mm"))?;
    Ok((EdgeSelector::parse(sel)?, t))
}

pub struct Outcome {
    pub plates: Vec<Plate>,
    /// Per plate: the etched tag's character height and lower-left corner, if it fits.
    pub tags: Vec<Option<(f64, DVec2)>>,
}

/// One DXF per plate in `parts/` (outline on CUT, tag on ETCH, in the plate's own frame) and
/// `assembly.scad` placing them.
fn write_parts(plates: &[Plate], dir: &Path) -> Result<Vec<Option<(f64, DVec2)>>> {
    let parts = dir.join("parts");
    std::fs::create_dir_all(&parts)
        .with_context(|| format!("{}: cannot create folder", parts.display()))?;
    let mut tags = Vec::with_capacity(plates.len());
    let mut names = Vec::with_capacity(plates.len());
    for p in plates {
        let tag = fit(&p.id, &p.outline, TAG_MARGIN, TAG_HEIGHT.0, TAG_HEIGHT.1);
        let lines = tag.map(|(h, o)| strokes(&p.id, o, h)).unwrap_or_default();
        let name = format!("parts/{}.dxf", p.id);
        write_cut_dxf(
            &[Drawn {
                outline: &p.outline,
                strokes: &lines,
            }],
            None,
            &dir.join(&name),
        )?;
        tags.push(tag);
        names.push(name);
    }
    let scad: Vec<ScadPart> = plates
        .iter()
        .zip(&names)
        .map(|(p, name)| ScadPart {
            id: &p.id,
            dxf: name,
            thickness: p.thickness,
            matrix: p.placement.matrix(),
        })
        .collect();
    write_scad(&scad, &dir.join("assembly.scad"))?;
    Ok(tags)
}

pub fn execute(args: &Args) -> Result<Outcome> {
    let axes = read_axes(&args.input)?;
    let opts = PlateOptions {
        gauges: args.gauges.clone(),
        thickness: match args.thickness {
            Some(t) => Thickness::Constant(t),
            None => Thickness::FromRadius,
        },
        overrides: args.edge_thickness.clone(),
        weld_gap: args.weld_gap,
        groups: args.groups,
    };
    let plates = plates(&axes, &opts).with_context(|| format!("{}", args.input.display()))?;
    if args.output.exists() && !args.output.is_dir() {
        bail!("{}: exists and is not a folder", args.output.display());
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create folder", args.output.display()))?;
    write_plates_json(&plates, &opts, &args.output.join("plates.json"))?;
    write_mesh(&assembly(&plates), &args.output.join("assembly.stl"), 0)?;
    write_assembly_obj(&plates, &args.output.join("assembly.obj"))?;
    let tags = write_parts(&plates, &args.output)?;
    Ok(Outcome { plates, tags })
}

pub fn run(args: Args) -> Result<()> {
    let Outcome { plates, tags } = execute(&args)?;
    let untagged = tags.iter().filter(|t| t.is_none()).count();
    let area: f64 = plates.iter().map(|p| p.area()).sum();
    let volume: f64 = plates.iter().map(|p| p.area() * p.thickness).sum();
    let flattening = plates.iter().map(|p| p.flattening).fold(0.0, f64::max);
    let seams = plates.iter().filter(|p| p.bolted_to.is_some()).count() / 2;
    let groups = plates.iter().map(|p| p.group + 1).max().unwrap_or(0);
    if args.json {
        println!(
            "{}",
            json!({
                "output": args.output,
                "plates": plates.len(),
                "area_mm2": area,
                "volume_mm3": volume,
                "max_flattening_mm": flattening,
                "groups": groups,
                "seams": seams,
                "untagged": untagged,
            })
        );
    } else {
        println!(
            "{}: {} plates in {groups} group(s), {seams} seam(s) split in half-thickness pairs, {:.3} m² of plate, {:.1} kg of stainless steel; panels flattened by at most {:.4} mm",
            args.output.display(),
            plates.len(),
            area * 1e-6,
            volume * 7.9e-6,
            flattening
        );
        if untagged > 0 {
            println!(
                "  {untagged} plate(s) too small for a {} mm tag {} mm inside the outline: not etched",
                TAG_HEIGHT.0, TAG_MARGIN
            );
        }
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

/// Every plate as its own closed object `o ID` (the halves of a seam plate touch face to face,
/// so in the STL they share a face; here they stay apart).
fn write_assembly_obj(plates: &[Plate], path: &Path) -> Result<()> {
    write_atomic(path, |w| {
        writeln!(w, "# lamina plates: one closed prism per plate, units mm")?;
        let mut base = 1;
        for p in plates {
            let (v, t) = p.prism();
            writeln!(w, "o {}", p.id)?;
            for q in &v {
                writeln!(w, "v {:?} {:?} {:?}", q.x, q.y, q.z)?;
            }
            for tri in &t {
                writeln!(w, "f {} {} {}", tri[0] + base, tri[1] + base, tri[2] + base)?;
            }
            base += v.len() as u32;
        }
        Ok(())
    })?;
    Ok(())
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
            let ends: Vec<_> = (0..2)
                .map(|e| {
                    json!({
                        "node": p.nodes[e],
                        "setback": p.setback[e],
                        "welded_to": p.partners[e].iter().map(|&j| &plates[j].id).collect::<Vec<_>>(),
                    })
                })
                .collect();
            let rec = json!({
                "id": p.id,
                "group": p.group + 1,
                "edge": p.edge,
                "nodes": p.nodes,
                "thickness": p.thickness,
                "ends": ends,
                "bolted_to": p.bolted_to.map(|j| &plates[j].id),
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
