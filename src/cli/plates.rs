//! `lamina plates axes.json -o DIR`: steel plates from node axes (plates.json, assembly.stl).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args as ClapArgs;
use serde_json::json;

use glam::{DVec2, DVec3};
use lamina::fabricate::assembly::{axis_frame, write_scad, ScadBolt, ScadCore, ScadPart};
use lamina::fabricate::cutsheet::{write_cut_dxf, Drawn, Hole};
use lamina::fabricate::tags::{part_marks, TAG_HEIGHT, TAG_MARGIN};
use lamina::files::write_atomic;
use lamina::mesh::io::write_mesh;
use lamina::rationalize::axes::read_axes;
use lamina::rationalize::bolts::{self, BoltSize};
use lamina::rationalize::plates::{
    plates, Core, CoreSize, EdgeSelector, Plate, PlateOptions, PlateSet, Thickness,
};
use lamina::TriMesh;

#[derive(ClapArgs)]
pub struct Args {
    /// The axes file `lamina planarize` wrote
    pub input: PathBuf,
    /// Sheet thicknesses available, mm, ascending; every plate is one of them [default:
    /// 1.5,2,3,4,5,6, or the sizing's list with --sizing]
    #[arg(long, value_delimiter = ',')]
    pub gauges: Option<Vec<f64>>,
    /// Every plate this thick, mm (a gauge) [default: from the vein radii, thicker veins on
    /// thicker gauges]
    #[arg(long, conflicts_with = "sizing")]
    pub thickness: Option<f64>,
    /// Gauges from `lamina size` (sizing.json for these axes): each edge's plate as sized
    #[arg(long)]
    pub sizing: Option<PathBuf>,
    /// Thickness for some edges, over the rule: `SELECTOR:MM`, where SELECTOR is `edge=K` or a
    /// node selector both ends must match (`all`, `node=N`, `x|y|z` `<` `<=` `>` `>=` value),
    /// e.g. `z<1:6` for a 6 mm base ring; repeatable, a later match wins
    #[arg(long, value_parser = parse_override)]
    pub edge_thickness: Vec<(EdgeSelector, f64)>,
    /// Root gap between plates meeting at a node, for the weld, mm
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub weld_gap: f64,
    /// How far a root gap may be from --weld-gap, mm
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub weld_gap_tolerance: f64,
    /// Nodes whose gaps setbacks cannot even get a tube on their axis the plates weld to:
    /// `tube:DIAMETER,WALL` in mm [default: such nodes are only reported]
    #[arg(long, value_parser = CoreSize::parse)]
    pub node_core: Option<CoreSize>,
    /// Exit 1 when two plates at a node meet at less than this dihedral angle, degrees (weld
    /// access; prequalified fillet welds need 60°)
    #[arg(long, allow_negative_numbers = true)]
    pub min_weld_angle: Option<f64>,
    /// Assembly groups: connected, balanced by plate count, few seams; a seam plate becomes two
    /// plates from the gauge list bolted face to face
    #[arg(long, default_value_t = 1)]
    pub groups: usize,
    /// Bolts through the seam plates: M6, M8, M10, M12, M16, M20, M22, M24, M27, M30
    /// [default: by the grip (Unwin's rule), smaller where a plate is too small]
    #[arg(long, value_parser = bolts::parse)]
    pub bolt: Option<BoltSize>,
    /// Output folder (made if missing): plates.json, welds.json, welds.html, assembly.stl,
    /// assembly.obj (one object per plate and core), parts/ID.dxf, assembly.scad
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
    pub set: PlateSet,
    /// Per plate: the etched tag's character height, if it fits.
    pub tags: Vec<Option<f64>>,
    pub weld: WeldSummary,
}

/// A part as its DXF draws it, in the plate's own frame.
fn drawn(p: &Plate) -> (Drawn, Option<f64>) {
    let r = 0.5 * p.hole_diameter();
    let holes: Vec<(DVec2, f64)> = p.holes.iter().map(|c| (*c, r)).collect();
    let marks = part_marks(&p.id, &p.outline, &holes, p.nodes, &|q| q);
    let part = Drawn {
        outline: p.outline.clone(),
        holes: p
            .holes
            .iter()
            .map(|c| Hole {
                centre: *c,
                diameter: p.hole_diameter(),
            })
            .collect(),
        etch: marks.etch,
        leads: Vec::new(),
        joints: Vec::new(),
    };
    (part, marks.tag_height)
}

/// One DXF per plate in `parts/` (CUT_OUTER, CUT_INNER, ETCH, in the plate's own frame) and
/// `assembly.scad` placing them, with the cores and (optionally) the bolts.
fn write_parts(set: &PlateSet, dir: &Path) -> Result<Vec<Option<f64>>> {
    let parts = dir.join("parts");
    std::fs::create_dir_all(&parts)
        .with_context(|| format!("{}: cannot create folder", parts.display()))?;
    let mut tags = Vec::with_capacity(set.plates.len());
    let mut names = Vec::with_capacity(set.plates.len());
    for p in &set.plates {
        let (part, tag) = drawn(p);
        let name = format!("parts/{}.dxf", p.id);
        write_cut_dxf(&[&part], None, &[], &dir.join(&name))?;
        tags.push(tag);
        names.push(name);
    }
    let scad: Vec<ScadPart> = set
        .plates
        .iter()
        .zip(&names)
        .map(|(p, name)| ScadPart {
            id: &p.id,
            dxf: name,
            thickness: p.thickness,
            matrix: p.placement.matrix(),
        })
        .collect();
    let cores: Vec<ScadCore> = set.cores.iter().map(scad_core).collect();
    write_scad(&scad, &cores, &scad_bolts(set), &dir.join("assembly.scad"))?;
    Ok(tags)
}

fn scad_core(c: &Core) -> ScadCore<'_> {
    ScadCore {
        id: &c.id,
        outer: c.size.diameter,
        inner: c.size.diameter - 2.0 * c.size.wall,
        length: c.length,
        matrix: axis_frame(c.base, c.axis),
    }
}

/// Every bolt once (from the ply on the −z side of each seam), as a shank through both plies.
fn scad_bolts(set: &PlateSet) -> Vec<ScadBolt> {
    let mut out = Vec::new();
    for (i, p) in set.plates.iter().enumerate() {
        let (Some(b), Some(other)) = (p.bolt, p.bolted_to) else {
            continue;
        };
        if other < i {
            continue;
        }
        // The first ply lies on the stack's −z side: the bolt starts at its outer face.
        for c in &p.holes {
            let bottom = p.placement.world(*c, -0.5 * p.thickness);
            out.push(ScadBolt {
                name: b.size.name,
                d: b.size.d,
                length: b.length,
                grip: b.grip,
                matrix: axis_frame(bottom, p.placement.z),
            });
        }
    }
    out
}

/// What the weld report found, for the summary and the exit status.
#[derive(Default)]
pub struct WeldSummary {
    pub nodes: usize,
    pub pairs: usize,
    pub uneven: Vec<u32>,
    pub cores: usize,
    pub smallest_angle: f64,
    pub below_min: usize,
    pub classes: [usize; 4],
}

/// Weld access by the dihedral angle, degrees: below 60° no prequalified fillet weld; 60–120°
/// prequalified (EN 1993-1-8 §4.3.2.1); 120–135° AWS D1.1 only; above, the plates meet end to
/// end (a butt weld).
fn weld_class(angle: f64) -> (usize, &'static str) {
    if angle < 60.0 {
        (0, "below 60°: no prequalified fillet weld")
    } else if angle <= 120.0 {
        (1, "60–120°: fillet (EN 1993-1-8)")
    } else if angle <= 135.0 {
        (2, "120–135°: fillet (AWS D1.1 only)")
    } else {
        (3, "over 135°: butt")
    }
}

pub fn execute(args: &Args) -> Result<Outcome> {
    let axes = read_axes(&args.input)?;
    if let Some(a) = args.min_weld_angle {
        if !(0.0..=180.0).contains(&a) {
            bail!(
                "--min-weld-angle must be from 0 to 180 degrees, got {}",
                lamina::text::num(a)
            );
        }
    }
    let sized = match &args.sizing {
        Some(p) => Some(lamina::analyze::sizing::read_gauges(p)?),
        None => None,
    };
    let thickness = match (args.thickness, &sized) {
        (Some(t), _) => Thickness::Constant(t),
        (None, Some((list, _))) => Thickness::PerEdge(list.clone()),
        (None, None) => {
            if axes.edge_radii.iter().all(|r| *r <= 0.0) && args.edge_thickness.is_empty() {
                bail!(
                    "{}: no vein radii to take thicknesses from: give --sizing sizing.json (from `lamina size`), --thickness MM or --edge-thickness",
                    args.input.display()
                );
            }
            Thickness::FromRadius
        }
    };
    let gauges = match (&args.gauges, &sized) {
        (Some(g), _) => g.clone(),
        (None, Some((_, g))) => g.clone(),
        (None, None) => vec![1.5, 2.0, 3.0, 4.0, 5.0, 6.0],
    };
    let opts = PlateOptions {
        gauges,
        thickness,
        overrides: args.edge_thickness.clone(),
        weld_gap: args.weld_gap,
        weld_gap_tolerance: args.weld_gap_tolerance,
        groups: args.groups,
        bolt: args.bolt,
        node_core: args.node_core,
    };
    let set = plates(&axes, &opts).with_context(|| format!("{}", args.input.display()))?;
    if args.output.exists() && !args.output.is_dir() {
        bail!("{}: exists and is not a folder", args.output.display());
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create folder", args.output.display()))?;
    write_plates_json(&set, &opts, &args.output.join("plates.json"))?;
    write_mesh(&assembly(&set), &args.output.join("assembly.stl"), 0)?;
    write_assembly_obj(&set, &args.output.join("assembly.obj"))?;
    let tags = write_parts(&set, &args.output)?;
    let weld = write_weld_report(&set, &opts, args, &args.output)?;
    Ok(Outcome { set, tags, weld })
}

/// Writes everything; false when a weld angle is below --min-weld-angle (exit 1).
pub fn run(args: Args) -> Result<bool> {
    let Outcome { set, tags, weld } = execute(&args)?;
    let plates = &set.plates;
    let untagged = tags.iter().filter(|t| t.is_none()).count();
    let area: f64 = plates.iter().map(|p| p.area()).sum();
    let volume: f64 = plates.iter().map(|p| p.area() * p.thickness).sum();
    let flattening = plates.iter().map(|p| p.flattening).fold(0.0, f64::max);
    let seams = plates.iter().filter(|p| p.bolted_to.is_some()).count() / 2;
    let bolts: usize = plates
        .iter()
        .enumerate()
        .filter(|(i, p)| p.bolted_to.is_some_and(|o| o > *i))
        .map(|(_, p)| p.holes.len())
        .sum();
    let groups = plates.iter().map(|p| p.group + 1).max().unwrap_or(0);
    let ok = args.min_weld_angle.is_none_or(|_| weld.below_min == 0);
    if args.json {
        outln!(
            "{}",
            json!({
                "output": args.output,
                "plates": plates.len(),
                "area_mm2": area,
                "volume_mm3": volume,
                "max_flattening_mm": flattening,
                "groups": groups,
                "seams": seams,
                "bolts": bolts,
                "untagged": untagged,
                "weld_nodes": weld.nodes,
                "uneven_nodes": weld.uneven,
                "cores": weld.cores,
                "smallest_weld_angle_deg": weld.smallest_angle,
                "below_min_weld_angle": weld.below_min,
            })
        );
    } else {
        outln!(
            "{}: {} plates in {groups} group(s), {seams} seam(s) as bolted pairs ({bolts} bolts), {:.3} m² of plate, {:.1} kg of stainless steel; panels flattened by at most {:.4} mm",
            args.output.display(),
            plates.len(),
            area * 1e-6,
            volume * 7.9e-6,
            flattening
        );
        outln!(
            "  welds: {} node(s), {} pair(s); root gap {} ± {} mm at {} node(s){}; dihedral angles from {:.1}°: {} below 60°, {} 60–120°, {} 120–135°, {} over 135° (welds.html)",
            weld.nodes,
            weld.pairs,
            args.weld_gap,
            args.weld_gap_tolerance,
            weld.nodes - weld.uneven.len() - weld.cores,
            if weld.cores > 0 {
                format!(", {} with a node core", weld.cores)
            } else {
                String::new()
            },
            weld.smallest_angle,
            weld.classes[0],
            weld.classes[1],
            weld.classes[2],
            weld.classes[3],
        );
        if !weld.uneven.is_empty() {
            let list: Vec<String> = weld.uneven.iter().take(10).map(|n| n.to_string()).collect();
            outln!(
                "  {} node(s) need a node core (no setbacks even their gaps; --node-core tube:D,T): {}{}",
                weld.uneven.len(),
                list.join(", "),
                if weld.uneven.len() > 10 { ", …" } else { "" }
            );
        }
        if untagged > 0 {
            outln!(
                "  {untagged} plate(s) too small for a {} mm tag {} mm inside the outline: not etched",
                TAG_HEIGHT.0, TAG_MARGIN
            );
        }
    }
    if let (false, Some(a)) = (ok, args.min_weld_angle) {
        errln!(
            "lamina: {} pair(s) of plates meet at less than --min-weld-angle {a}° (the smallest {:.2}°): see welds.html",
            weld.below_min, weld.smallest_angle
        );
    }
    Ok(ok)
}

/// Every plate as a closed prism (holes through it) and every core as a closed tube, in one
/// mesh (disjoint shells).
pub fn assembly(set: &PlateSet) -> TriMesh {
    let mut mesh = TriMesh::default();
    let mut add = |(v, t): (Vec<DVec3>, Vec<[u32; 3]>)| {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(v);
        mesh.triangles
            .extend(t.iter().map(|tri| tri.map(|i| i + base)));
    };
    for p in &set.plates {
        add(p.prism());
    }
    for c in &set.cores {
        add(tube(c));
    }
    mesh
}

/// Sides of the polygon standing for a core's circles in meshes.
pub const CORE_SEGMENTS: usize = 48;

/// A core as a closed tube: outer and inner `CORE_SEGMENTS`-gons from its base along its axis.
fn tube(c: &Core) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let m = axis_frame(c.base, c.axis);
    let (x, y) = (
        DVec3::new(m[0][0], m[1][0], m[2][0]),
        DVec3::new(m[0][1], m[1][1], m[2][1]),
    );
    let n = CORE_SEGMENTS as u32;
    let (ro, ri) = (0.5 * c.size.diameter, 0.5 * c.size.diameter - c.size.wall);
    let mut v = Vec::with_capacity(4 * CORE_SEGMENTS);
    // Rings: outer bottom, outer top, inner bottom, inner top.
    for (r, h) in [(ro, 0.0), (ro, c.length), (ri, 0.0), (ri, c.length)] {
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            v.push(c.base + (x * a.cos() + y * a.sin()) * r + c.axis * h);
        }
    }
    let ring = |r: u32, k: u32| r * n + k % n;
    let mut t = Vec::new();
    for k in 0..n {
        let quad = |t: &mut Vec<[u32; 3]>, a: u32, b: u32, c: u32, d: u32| {
            t.push([a, b, c]);
            t.push([a, c, d]);
        };
        // Outer wall faces out, inner wall in, bottom down, top up.
        quad(
            &mut t,
            ring(0, k),
            ring(0, k + 1),
            ring(1, k + 1),
            ring(1, k),
        );
        quad(
            &mut t,
            ring(2, k + 1),
            ring(2, k),
            ring(3, k),
            ring(3, k + 1),
        );
        quad(
            &mut t,
            ring(0, k + 1),
            ring(0, k),
            ring(2, k),
            ring(2, k + 1),
        );
        quad(
            &mut t,
            ring(1, k),
            ring(1, k + 1),
            ring(3, k + 1),
            ring(3, k),
        );
    }
    (v, t)
}

/// Every plate and core as its own closed object `o ID` (the plies of a seam touch face to
/// face, so in the STL they share a face; here they stay apart).
fn write_assembly_obj(set: &PlateSet, path: &Path) -> Result<()> {
    write_atomic(path, |w| {
        writeln!(
            w,
            "# lamina plates: one closed prism per plate, one tube per node core, units mm"
        )?;
        let mut base = 1;
        let shapes = set
            .plates
            .iter()
            .map(|p| (p.id.as_str(), p.prism()))
            .chain(set.cores.iter().map(|c| (c.id.as_str(), tube(c))));
        for (id, (v, t)) in shapes {
            writeln!(w, "o {id}")?;
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

fn write_plates_json(set: &PlateSet, opts: &PlateOptions, path: &Path) -> Result<()> {
    let plates = &set.plates;
    write_atomic(path, |w| {
        writeln!(w, "{{")?;
        writeln!(w, "  \"format\": \"lamina-plates\",")?;
        writeln!(w, "  \"version\": 2,")?;
        writeln!(w, "  \"units\": \"mm\",")?;
        writeln!(w, "  \"gauges\": {},", json!(opts.gauges))?;
        writeln!(w, "  \"weld_gap\": {},", json!(opts.weld_gap))?;
        writeln!(
            w,
            "  \"weld_gap_tolerance\": {},",
            json!(opts.weld_gap_tolerance)
        )?;
        writeln!(
            w,
            "  \"hole_segments\": {},",
            lamina::rationalize::plates::HOLE_SEGMENTS
        )?;
        writeln!(w, "  \"core_segments\": {CORE_SEGMENTS},")?;
        let cores: Vec<_> = set
            .cores
            .iter()
            .map(|c| {
                json!({
                    "id": c.id,
                    "node": c.node,
                    "group": c.group + 1,
                    "outer_diameter": c.size.diameter,
                    "wall": c.size.wall,
                    "base": c.base.to_array(),
                    "axis": c.axis.to_array(),
                    "length": c.length,
                })
            })
            .collect();
        writeln!(w, "  \"cores\": {},", json!(cores))?;
        writeln!(w, "  \"plates\": [")?;
        for (k, p) in plates.iter().enumerate() {
            let ends: Vec<_> = (0..2)
                .map(|e| {
                    json!({
                        "node": p.nodes[e],
                        "setback": p.setback[e],
                        "welded_to": p.partners[e].iter().map(|&j| &plates[j].id).collect::<Vec<_>>(),
                        "core": p.core[e].map(|c| &set.cores[c].id),
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
                "bolt": p.bolt.map(|b| json!({
                    "size": b.size.name,
                    "d": b.size.d,
                    "hole_diameter": b.size.hole,
                    "grip": b.grip,
                    "length": b.length,
                })),
                "holes": p.holes.iter().map(|q| [q.x, q.y]).collect::<Vec<_>>(),
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

/// welds.json and welds.html: per node its plates, the pairs side by side with their root gaps
/// and dihedral angles, whether the gaps are even, and its core.
fn write_weld_report(
    set: &PlateSet,
    opts: &PlateOptions,
    args: &Args,
    dir: &Path,
) -> Result<WeldSummary> {
    let min_angle = args.min_weld_angle;
    let ids = |k: usize| -> String {
        let v: Vec<&str> = set.by_edge[k]
            .iter()
            .map(|&i| set.plates[i].id.as_str())
            .collect();
        v.join("+")
    };
    let mut sum = WeldSummary {
        smallest_angle: f64::INFINITY,
        ..Default::default()
    };
    let mut nodes = Vec::with_capacity(set.welds.len());
    let mut rows = String::new();
    for w in &set.welds {
        sum.nodes += 1;
        if w.core.is_some() {
            sum.cores += 1;
        } else if !w.even {
            sum.uneven.push(w.node);
        }
        let status = match (w.core, w.even) {
            (Some(_), _) => "core",
            (None, true) => "even",
            (None, false) => "needs a node core",
        };
        let mut pairs = Vec::new();
        for p in &w.pairs {
            sum.pairs += 1;
            let (class, name) = weld_class(p.angle_deg);
            sum.classes[class] += 1;
            sum.smallest_angle = sum.smallest_angle.min(p.angle_deg);
            if min_angle.is_some_and(|a| p.angle_deg < a) {
                sum.below_min += 1;
            }
            let within = (p.gap - opts.weld_gap).abs() <= opts.weld_gap_tolerance + 1e-9;
            pairs.push(json!({
                "plates": [ids(p.edges[0]), ids(p.edges[1])],
                "edges": p.edges,
                "dihedral_deg": p.angle_deg,
                "root_gap_mm": p.gap,
                "gap_within_tolerance": within,
                "access": name,
            }));
            rows.push_str(&format!(
                "<tr class=\"{}\"><td>{}</td><td>{}</td><td>{} / {}</td><td>{:.3}</td><td>{:.2}</td><td>{}</td></tr>\n",
                if !within && w.core.is_none() { "bad" } else if class == 0 { "warn" } else { "" },
                w.node,
                status,
                ids(p.edges[0]),
                ids(p.edges[1]),
                p.gap,
                p.angle_deg,
                name
            ));
        }
        let core = w.core.map(|c| {
            let c = &set.cores[c];
            json!({
                "id": c.id,
                "outer_diameter": c.size.diameter,
                "wall": c.size.wall,
                "length": c.length,
                "root_gap_mm": w.setbacks.iter().map(|s| s - 0.5 * c.size.diameter).collect::<Vec<_>>(),
            })
        });
        nodes.push(json!({
            "node": w.node,
            "plates": w.edges.iter().map(|&k| ids(k)).collect::<Vec<_>>(),
            "edges": w.edges,
            "setbacks_mm": w.setbacks,
            "status": status,
            "pairs": pairs,
            "core": core,
        }));
    }
    if sum.pairs == 0 {
        sum.smallest_angle = 0.0;
    }
    let doc = json!({
        "format": "lamina-welds",
        "version": 1,
        "units": "mm",
        "definitions": {
            "root_gap_mm": "distance between the two plates (a bolted seam as its stack of two plies) in the plane perpendicular to the node axis: the weld's root opening along the line where they meet",
            "dihedral_deg": "angle between the two plates about the node axis on the side where they are neighbours (the wedge a fillet weld fills)",
            "access": "below 60°: no prequalified fillet weld; 60–120°: fillet (EN 1993-1-8 §4.3.2.1); 120–135°: fillet under AWS D1.1 only; over 135°: the plates meet end to end (butt weld)",
        },
        "weld_gap": opts.weld_gap,
        "weld_gap_tolerance": opts.weld_gap_tolerance,
        "min_weld_angle": min_angle,
        "summary": {
            "nodes": sum.nodes,
            "pairs": sum.pairs,
            "even_nodes": sum.nodes - sum.uneven.len() - sum.cores,
            "nodes_needing_a_core": sum.uneven,
            "cores": sum.cores,
            "smallest_dihedral_deg": sum.smallest_angle,
            "pairs_below_60": sum.classes[0],
            "pairs_60_120": sum.classes[1],
            "pairs_120_135": sum.classes[2],
            "pairs_over_135": sum.classes[3],
            "pairs_below_min_weld_angle": sum.below_min,
        },
        "nodes": nodes,
    });
    let text = serde_json::to_string_pretty(&doc)?;
    write_atomic(&dir.join("welds.json"), |w| writeln!(w, "{text}"))?;
    // The plates and their welds in the viewer, read back from the files just written.
    let (plates_file, welds_file) = (dir.join("plates.json"), dir.join("welds.json"));
    let mut files = vec![
        plates_file.as_path(),
        welds_file.as_path(),
        args.input.as_path(),
    ];
    if let Some(s) = &args.sizing {
        files.push(s.as_path());
    }
    let scene = super::view::scene_of(&files, "plates and welds")?;
    let viewer = format!(
        "<h2>Look around</h2>\n<p>Plates coloured by group, gauge{} (the menu beside them); each pair of plates side by side at a node is a dot between their edges there (mid-height of the seam), coloured by its access class or root gap. Hover or click for figures; find a plate by its tag or a pair as W, its node and its number (W12-2).</p>\n{}",
        if args.sizing.is_some() { " or utilisation" } else { "" },
        lamina::view::embed(&scene, "70vh")
    );
    let html = format!(
        "<!doctype html><meta charset=\"utf-8\"><title>lamina weld report</title>\n\
<style>body{{font:14px system-ui,sans-serif;margin:2em}}table{{border-collapse:collapse}}\
td,th{{border:1px solid #ccc;padding:2px 8px;text-align:left}}tr.bad{{background:#fdd}}\
tr.warn{{background:#ffe9c6}}</style>\n\
<h1>Welds at the nodes</h1>\n\
<p>{} nodes, {} pairs of plates side by side. Root gap target {} ± {} mm: {} nodes even, {} need a node core{}. \
Smallest dihedral angle {:.2}°: {} pairs below 60°, {} at 60–120°, {} at 120–135°, {} over 135°.</p>\n\
<dl><dt>Root gap</dt><dd>the distance between the two plates (a bolted seam counts as its two plies together) \
in the plane perpendicular to the node axis: the weld's root opening along the line where they meet, mm.</dd>\
<dt>Dihedral angle</dt><dd>the angle between the two plates about the node axis on the side where they are \
neighbours: the wedge a fillet weld fills. Below 60° there is no prequalified fillet weld; 60–120° is \
prequalified by EN 1993-1-8 §4.3.2.1; AWS D1.1 allows up to 135°; above that the plates meet end to end \
(a butt weld).</dd></dl>\n\
{viewer}\n\
<h2>Pairs</h2>\n\
<table><tr><th>node</th><th>status</th><th>plates</th><th>root gap, mm</th><th>dihedral, °</th><th>access</th></tr>\n{rows}</table>\n",
        sum.nodes,
        sum.pairs,
        opts.weld_gap,
        opts.weld_gap_tolerance,
        sum.nodes - sum.uneven.len() - sum.cores,
        sum.uneven.len(),
        if sum.cores > 0 {
            format!(", {} have one", sum.cores)
        } else {
            String::new()
        },
        sum.smallest_angle,
        sum.classes[0],
        sum.classes[1],
        sum.classes[2],
        sum.classes[3],
    );
    write_atomic(&dir.join("welds.html"), |w| w.write_all(html.as_bytes()))?;
    Ok(sum)
}
