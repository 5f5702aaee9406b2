//! `plates`: one flat steel plate per edge in its panel plane, cut back at the nodes for even
//! weld gaps, seams between assembly groups as bolted pairs, node cores where gaps cannot be
//! evened; with plates.json and the weld report as typed documents. The writers (part DXFs,
//! assembly STL/OBJ/SCAD, welds.json and its page) are separate calls.
//!
//! ```
//! use lamina::stage::{planarize, plates, Quiet};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let net = lamina::network::io::json::from_str(include_str!("../../fixtures/networks/calyx_veins.json"))?;
//! let solved = planarize::run(&net, None, &planarize::Options::default(), &Quiet)?;
//! let core = plates::CoreSize { diameter: 60.3, wall: 4.0 };
//! let opts = plates::Options { groups: 7, node_core: Some(core), ..Default::default() };
//! let made = plates::run(&solved.axes, &opts)?;
//! // Every node's gaps are even, or it has a tube the plates weld to.
//! assert!(made.welds.summary.nodes_needing_a_core.is_empty());
//! let mesh = plates::assembly(&made.set);
//! assert!(mesh.triangles.len() > made.set.plates.len() * 8);
//! # Ok(()) }
//! ```

use std::io::Write as _;
use std::path::Path;

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;

pub use crate::analyze::material::Material;
use crate::fabricate::assembly::{axis_frame, write_scad, ScadBolt, ScadCore, ScadPart};
use crate::fabricate::cutsheet::{write_cut_dxf, Drawn, Hole};
use crate::fabricate::plates_file::{
    BoltRecord, CoreRecord, EndDoc, MaterialRecord, PlateDoc, PlateRecord, PlatesDoc, PlatesRead,
    WeldNode, WeldPair,
};
use crate::fabricate::tags::part_marks;
use crate::files::{write_atomic, ReadError, WriteError};
use crate::rationalize::axes::Axes;
pub use crate::rationalize::bolts::BoltSize;
use crate::rationalize::plates::{
    plates, Core, Plate, PlateError, PlateOptions, PlateSet, Thickness, HOLE_SEGMENTS,
};
pub use crate::rationalize::plates::{CoreSize, EdgeSelector, Joints};
use crate::rationalize::welds;
use crate::stage::OptionError;
use crate::TriMesh;

/// How the plates are made. `Default` is the command's defaults (which need radii on the
/// edges, or `thickness`, `sizing` or `edge_thickness`).
#[derive(Clone, Debug)]
pub struct Options {
    /// Sheet thicknesses available, mm, ascending. Default 1.5, 2, 3, 4, 5, 6 (or the
    /// sizing's list).
    pub gauges: Option<Vec<f64>>,
    /// Every plate this thick, mm. Default: from the vein radii.
    pub thickness: Option<f64>,
    /// Gauges from a sizing of these axes. Default: none.
    pub sizing: Option<Gauges>,
    /// Thickness for some edges over the rule; a later match wins.
    pub edge_thickness: Vec<(EdgeSelector, f64)>,
    /// Root gap between plates meeting at a node, mm: above 0, or 0 with `node_core`. Default 1.
    pub weld_gap: f64,
    /// How far a root gap may be from `weld_gap`, mm, at most `weld_gap`. Default 0.5.
    pub weld_gap_tolerance: f64,
    /// A tube at nodes whose gaps setbacks cannot even. Default: such nodes are reported.
    pub node_core: Option<CoreSize>,
    /// Plates meeting at less than this dihedral angle, degrees, make the result not ok.
    /// Default: none.
    pub min_weld_angle: Option<f64>,
    /// Assembly groups; seams between them become bolted pairs. Default 1.
    pub groups: usize,
    /// Bolts through the seam plates. Default: by the grip.
    pub bolt: Option<BoltSize>,
    /// The socket that must fit over every bolt's head and nut (radius, reach). Default: one
    /// for each size (the nut's corners and a 3 mm wall, 40 mm long).
    pub bolt_clearance: Option<crate::rationalize::clearance::Socket>,
    /// The steel: its grade and density go into plates.json, the mass, the BOM and the cut
    /// files. Default: the sizing's, else 1.4404 (stainless 316L) with a note saying so.
    pub material: Option<Material>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            gauges: None,
            thickness: None,
            sizing: None,
            edge_thickness: Vec::new(),
            weld_gap: 1.0,
            weld_gap_tolerance: 0.5,
            node_core: None,
            min_weld_angle: None,
            groups: 1,
            bolt: None,
            bolt_clearance: None,
            material: None,
        }
    }
}

impl Default for Joints {
    fn default() -> Self {
        Joints::of(&Options::default())
    }
}

impl Joints {
    /// The joints of `opts`.
    pub fn of(opts: &Options) -> Joints {
        Joints {
            weld_gap: opts.weld_gap,
            weld_gap_tolerance: opts.weld_gap_tolerance,
            node_core: opts.node_core,
            bolt: opts.bolt,
            bolt_clearance: opts.bolt_clearance,
        }
    }

    /// Plate options with these joints over `opts`'s.
    pub fn apply(&self, opts: &mut Options) {
        opts.weld_gap = self.weld_gap;
        opts.weld_gap_tolerance = self.weld_gap_tolerance;
        opts.node_core = self.node_core;
        opts.bolt = self.bolt;
        opts.bolt_clearance = self.bolt_clearance;
    }

    /// The first option of `other` that differs from these, its name and both values as the
    /// command line writes them.
    fn differs(&self, other: &Joints) -> Option<(&'static str, String, String)> {
        let num = |v: f64| crate::text::num(v);
        let core = |c: Option<CoreSize>| match c {
            Some(c) => format!("tube:{},{}", num(c.diameter), num(c.wall)),
            None => "none".into(),
        };
        let bolt = |b: Option<BoltSize>| b.map_or("by the grip".into(), |b| b.name.to_string());
        let socket = |s: Option<crate::rationalize::clearance::Socket>| match s {
            Some(s) => format!("{}:{}", num(s.radius), num(s.height)),
            None => "one for each size".into(),
        };
        let both = [
            ("weld_gap", num(self.weld_gap), num(other.weld_gap)),
            (
                "weld_gap_tolerance",
                num(self.weld_gap_tolerance),
                num(other.weld_gap_tolerance),
            ),
            ("node_core", core(self.node_core), core(other.node_core)),
            ("bolt", bolt(self.bolt), bolt(other.bolt)),
            (
                "bolt_clearance",
                socket(self.bolt_clearance),
                socket(other.bolt_clearance),
            ),
        ];
        both.into_iter().find(|(_, a, b)| a != b)
    }
}

/// A sizing's gauges: one per edge, and the list they were chosen from.
#[derive(Clone, Debug, PartialEq)]
pub struct Gauges {
    /// The gauge of each edge, mm.
    pub per_edge: Vec<f64>,
    /// The gauges to choose from, mm.
    pub list: Vec<f64>,
    /// The steel the sizing was made for.
    pub material: Option<Material>,
    /// The assembly groups its seams were sized for, as stacks of two plies (None: no seams).
    pub seam_groups: Option<usize>,
    /// Per edge, what a seam's bolts carry (see `bolts::SeamForces`); None for other edges.
    pub seam_forces: Vec<Option<crate::rationalize::bolts::SeamForces>>,
    /// The joints the sizing weighed the plates with (None: files from before, or a sizing
    /// of the uncut panels).
    pub joints: Option<Joints>,
}

impl From<crate::analyze::sizing::SizedGauges> for Gauges {
    /// A sizing file's, as `analyze::sizing::read_gauges` reads it.
    fn from(g: crate::analyze::sizing::SizedGauges) -> Gauges {
        Gauges {
            per_edge: g.per_edge,
            list: g.list,
            material: g.material,
            seam_groups: g.seam_groups,
            seam_forces: g.seam_forces,
            joints: g.joints,
        }
    }
}

impl Gauges {
    /// The gauges of a sizing (`stage::size`).
    pub fn of(report: &super::size::Report) -> Gauges {
        Gauges {
            per_edge: report.edges.iter().map(|e| e.gauge).collect(),
            list: report.gauges.clone(),
            material: Some(report.material.clone()),
            seam_groups: report.seam_groups,
            seam_forces: report.edges.iter().map(|e| e.seam_forces).collect(),
            joints: report.joints.as_ref().map(|j| j.joints),
        }
    }
}

/// Why no plates were made.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(
        "no vein radii to take thicknesses from: give sizing= (from size), thickness= or edge_thickness="
    )]
    /// No way to choose thicknesses.
    NoThickness,
    #[error(transparent)]
    /// The plates failed.
    Plates(#[from] PlateError),
}

/// The plates made: the set, the documents the command writes, and the weld summary.
#[derive(Clone, Debug)]
pub struct Plated {
    /// The plates.
    pub set: PlateSet,
    /// The options as resolved.
    pub options: PlateOptions,
    /// plates.json.
    pub file: PlatesDoc,
    /// welds.json.
    pub welds: Welds,
    /// Per plate: the part as its DXF draws it (in its own frame), and its tag's height (None
    /// when the part is too small for a tag).
    pub parts: Vec<(Drawn, Option<f64>)>,
    /// No pair of plates meets below `min_weld_angle`, and every bolt can be fitted and
    /// tightened.
    pub ok: bool,
    /// The steel.
    pub material: Material,
    /// Defaults taken that change the result (the material), one line each.
    pub notes: Vec<String>,
}

impl Plated {
    /// The plates as `nest` takes them (what plates.json reads back as).
    pub fn records(&self) -> Vec<PlateRecord> {
        self.file
            .records(Path::new("plates"))
            .expect("plates made here are valid records")
            .0
    }

    /// The node cores as records.
    pub fn core_records(&self) -> Vec<CoreRecord> {
        self.file.cores.clone()
    }

    /// The figures the command prints (and gives with `--json`).
    pub fn summary(&self) -> Summary {
        let plates = &self.set.plates;
        let weld = &self.welds.summary;
        let density = self.material.density;
        Summary {
            plates: plates.len(),
            area_mm2: plates.iter().map(|p| p.area()).sum(),
            volume_mm3: plates.iter().map(|p| p.area() * p.thickness).sum(),
            bolt_sets_kg: (plates.iter().enumerate())
                .filter(|(i, p)| p.bolted_to.is_some_and(|o| o > *i))
                .filter_map(|(_, p)| p.bolt.map(|b| (b, p.holes.len())))
                .map(|(b, n)| crate::rationalize::bolts::set_volume(&b.size, b.length) * n as f64)
                .fold(0.0, |s, v| s + v * density * 1e-6),
            cores_kg: (self.set.cores.iter()).fold(0.0, |s, c| s + c.mass_kg(density)),
            mass_kg: self.set.mass_kg(density),
            max_flattening_mm: plates.iter().map(|p| p.flattening).fold(0.0, f64::max),
            groups: plates.iter().map(|p| p.group + 1).max().unwrap_or(0),
            seams: plates.iter().filter(|p| p.bolted_to.is_some()).count() / 2,
            bolts: plates
                .iter()
                .enumerate()
                .filter(|(i, p)| p.bolted_to.is_some_and(|o| o > *i))
                .map(|(_, p)| p.holes.len())
                .sum(),
            bolts_moved: self.set.room.moved.len(),
            bolts_dropped: self.set.room.dropped.len(),
            largest_bolt_move_mm: self.set.room.moved.iter().map(|m| m.2).fold(0.0, f64::max),
            bolt_clashes: self.set.room.clashes.len(),
            max_bolt_utilisation: plates
                .iter()
                .filter_map(|p| p.bolt.and_then(|b| b.checks))
                .map(|c| c.governing().0)
                .reduce(f64::max),
            untagged: self.parts.iter().filter(|(_, t)| t.is_none()).count(),
            weld_nodes: weld.nodes,
            uneven_nodes: weld.nodes_needing_a_core.clone(),
            cores: weld.cores,
            smallest_weld_angle_deg: weld.smallest_dihedral_deg,
            below_min_weld_angle: weld.pairs_below_min_weld_angle,
        }
    }
}

/// What a plates run made, in figures. Fields in the order `--json` prints them.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Plates (a seam's two plies count as two).
    pub plates: usize,
    /// Plate area, one face, mm².
    pub area_mm2: f64,
    /// Plate volume, mm³.
    pub volume_mm3: f64,
    /// The seams' bolt sets (bolt, nut, two washers; nominal), kg.
    pub bolt_sets_kg: f64,
    /// The node cores, kg.
    pub cores_kg: f64,
    /// The plates, kg.
    pub mass_kg: f64,
    /// The most any panel was moved to make it flat, mm.
    pub max_flattening_mm: f64,
    /// Assembly groups.
    pub groups: u32,
    /// Seams made as two bolted plies.
    pub seams: usize,
    /// Bolts through the seams.
    pub bolts: usize,
    /// Bolts moved along their rows to make room to fit and tighten them.
    pub bolts_moved: usize,
    /// The farthest any moved, mm.
    pub largest_bolt_move_mm: f64,
    /// Bolts left out for want of room (their rows keep Table 3.3 without them).
    pub bolts_dropped: usize,
    /// Bolts whose washer, head, nut or socket crosses a plate or core wherever the row allows.
    pub bolt_clashes: usize,
    /// The largest bolt utilisation (EN 1993-1-8 Table 3.4) under the sizing's forces; None
    /// when not checked (no sizing).
    pub max_bolt_utilisation: Option<f64>,
    /// Plates too small for their tag.
    pub untagged: usize,
    /// Nodes where plates are welded.
    pub weld_nodes: usize,
    /// Nodes whose root gaps no setback evens (they need a node core).
    pub uneven_nodes: Vec<u32>,
    /// Node cores made.
    pub cores: usize,
    /// The smallest dihedral angle between welded plates, degrees.
    pub smallest_weld_angle_deg: f64,
    /// Pairs of plates meeting below `min_weld_angle`.
    pub below_min_weld_angle: usize,
}

/// Makes the plates of `axes`.
pub fn run(axes: &Axes, opts: &Options) -> Result<Plated, Error> {
    let (options, material, notes) = plate_options(axes, opts)?;
    let set = plates(axes, &options)?;
    let file = plates_doc(&set, &options, &material);
    let welds = welds(&set, &options, opts.min_weld_angle);
    let ok = (opts.min_weld_angle.is_none() || welds.summary.pairs_below_min_weld_angle == 0)
        && set.room.clashes.is_empty();
    let parts = set.plates.iter().map(drawn).collect();
    Ok(Plated {
        set,
        options,
        file,
        welds,
        parts,
        ok,
        material,
        notes,
    })
}

/// The options of `opts` checked and resolved: what `rationalize::plates::plates` takes, the
/// steel, and the notes on defaults taken.
pub fn plate_options(
    axes: &Axes,
    opts: &Options,
) -> Result<(PlateOptions, Material, Vec<String>), Error> {
    if let Some(a) = opts.min_weld_angle {
        if !(0.0..=180.0).contains(&a) {
            return Err(OptionError::new(
                "min_weld_angle",
                format!("must be from 0 to 180 degrees, got {}", crate::text::num(a)),
            )
            .into());
        }
    }
    if let Some(g) = &opts.sizing {
        if let Some((name, sized, here)) = g.joints.and_then(|j| j.differs(&Joints::of(opts))) {
            return Err(OptionError::new(
                name,
                format!(
                    "is {here} but the sizing weighed the plates as cut with {sized}: give \
                     {name}= {sized}, or size again with {name}= {here}"
                ),
            )
            .into());
        }
        let sized_for = g.seam_groups.unwrap_or(1);
        if sized_for != opts.groups {
            return Err(OptionError::new(
                "groups",
                format!(
                    "is {} but the sizing was made for {sized_for} group(s): size with groups= {} \
                     so that each seam is analysed as the two plies it is cut from",
                    opts.groups, opts.groups
                ),
            )
            .into());
        }
    }
    let thickness = match (opts.thickness, &opts.sizing) {
        (Some(_), Some(_)) => {
            return Err(OptionError::new("thickness", "and sizing= exclude each other").into())
        }
        (Some(t), None) => Thickness::Constant(t),
        (None, Some(g)) => Thickness::PerEdge(g.per_edge.clone()),
        (None, None) => {
            if axes.edge_radii.iter().all(|r| *r <= 0.0) && opts.edge_thickness.is_empty() {
                return Err(Error::NoThickness);
            }
            Thickness::FromRadius
        }
    };
    let gauges = match (&opts.gauges, &opts.sizing) {
        (Some(g), _) => g.clone(),
        (None, Some(g)) => g.list.clone(),
        (None, None) => vec![1.5, 2.0, 3.0, 4.0, 5.0, 6.0],
    };
    let mut notes = Vec::new();
    let material = match (
        &opts.material,
        opts.sizing.as_ref().and_then(|g| g.material.as_ref()),
    ) {
        (Some(m), Some(sized)) if m.name != sized.name => {
            return Err(OptionError::new(
                "material",
                format!(
                    "is {} but the sizing was made for {}: size again, or leave material= out",
                    m.name, sized.name
                ),
            )
            .into())
        }
        (Some(m), _) | (None, Some(m)) => m.clone(),
        (None, None) => {
            notes.push(
                "material 1.4404 (stainless 316L, 8.0 g/cm³), the default: give material= for another"
                    .into(),
            );
            Material::get("1.4404").expect("a built-in material")
        }
    };
    let options = PlateOptions {
        gauges,
        thickness,
        overrides: opts.edge_thickness.clone(),
        weld_gap: opts.weld_gap,
        weld_gap_tolerance: opts.weld_gap_tolerance,
        groups: opts.groups,
        bolt: opts.bolt,
        node_core: opts.node_core,
        socket: opts.bolt_clearance,
        bolt_grade: crate::rationalize::bolts::grade(material.is_stainless()),
        ply_steel: crate::rationalize::bolts::PlySteel::of(&material),
        seam_forces: opts.sizing.as_ref().map(|g| g.seam_forces.clone()),
    };
    Ok((options, material, notes))
}

/// A part as its DXF draws it, in the plate's own frame, and its tag's height.
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
        common: false,
    };
    (part, marks.tag_height)
}

fn plates_doc(set: &PlateSet, opts: &PlateOptions, material: &Material) -> PlatesDoc {
    let plates = &set.plates;
    let cores = set
        .cores
        .iter()
        .map(|c| CoreRecord {
            axis: c.axis.to_array(),
            base: c.base.to_array(),
            group: c.group + 1,
            id: c.id.clone(),
            length: c.length,
            node: c.node,
            outer_diameter: c.size.diameter,
            wall: c.size.wall,
        })
        .collect();
    let docs = plates
        .iter()
        .enumerate()
        .map(|(i, p)| PlateDoc {
            area_mm2: p.area(),
            bolt: p.bolt.map(|b| BoltRecord {
                clashes: set
                    .room
                    .clashes
                    .iter()
                    .filter(|c| c.plies.contains(&i))
                    .map(|c| {
                        let with = match c.with {
                            Ok(j) => format!("plate {}", plates[j].id),
                            Err(k) => format!("core {}", set.cores[k].id),
                        };
                        format!("hole {}: the {} crosses {with}", c.hole, c.envelope)
                    })
                    .collect(),
                check: b.checks.map(|c| c.governing().1.to_string()),
                checks: b.checks.map(|c| {
                    crate::rationalize::bolts::BOLT_CHECKS
                        .iter()
                        .zip(c.values())
                        .map(|(n, u)| (n.to_string(), u))
                        .collect()
                }),
                class: b.grade.name.to_string(),
                d: b.size.d,
                grip: b.grip,
                hole_diameter: b.size.hole,
                length: b.length,
                nut_below: set
                    .room
                    .nut_below
                    .iter()
                    .filter(|(plies, _)| plies.contains(&i))
                    .map(|(_, h)| *h)
                    .collect(),
                preload: crate::rationalize::bolts::PRELOAD.to_string(),
                size: b.size.name.to_string(),
                utilisation: b.checks.map(|c| c.governing().0),
            }),
            bolted_to: p.bolted_to.map(|j| plates[j].id.clone()),
            edge: Some(p.edge as u32),
            ends: [0, 1].map(|e| EndDoc {
                core: p.core[e].map(|c| set.cores[c].id.clone()),
                node: p.nodes[e],
                setback: p.setback[e],
                welded_to: p.partners[e]
                    .iter()
                    .map(|&j| plates[j].id.clone())
                    .collect(),
            }),
            flattening_mm: p.flattening,
            group: p.group + 1,
            holes: p.holes.iter().map(|q| [q.x, q.y]).collect(),
            id: p.id.clone(),
            matrix: p.placement.matrix(),
            nodes: p.nodes,
            outline: p.outline.iter().map(|q| [q.x, q.y]).collect(),
            thickness: p.thickness,
        })
        .collect();
    PlatesDoc {
        format: crate::fabricate::plates_file::FORMAT,
        version: crate::fabricate::plates_file::VERSION,
        units: "mm",
        material: MaterialRecord {
            density: material.density,
            grade: material.name.clone(),
        },
        gauges: opts.gauges.clone(),
        weld_gap: opts.weld_gap,
        weld_gap_tolerance: opts.weld_gap_tolerance,
        hole_segments: HOLE_SEGMENTS,
        core_segments: CORE_SEGMENTS,
        cores,
        plates: docs,
    }
}

/// welds.json: per node its plates, the pairs side by side with their root gaps and dihedral
/// angles, whether the gaps are even, and its core. Fields in the file's order.
#[derive(Clone, Debug, Serialize)]
pub struct Welds {
    /// What the figures mean.
    pub definitions: WeldDefinitions,
    /// The file format's name.
    pub format: &'static str,
    /// The minimum weld angle asked for, degrees.
    pub min_weld_angle: Option<f64>,
    /// Nodes.
    pub nodes: Vec<WeldNodeDoc>,
    /// Summary figures.
    pub summary: WeldSummary,
    /// The unit of lengths.
    pub units: &'static str,
    /// The format's version.
    pub version: u32,
    /// Target root gap, mm.
    pub weld_gap: f64,
    /// How far a root gap may be from the target, mm.
    pub weld_gap_tolerance: f64,
}

/// What welds.json's figures mean.
#[derive(Clone, Debug, Serialize)]
pub struct WeldDefinitions {
    /// The weld access class.
    pub access: &'static str,
    /// Dihedral angle between the two plates about the node axis, degrees.
    pub dihedral_deg: &'static str,
    /// Root gap of the weld, mm.
    pub root_gap_mm: &'static str,
}

/// One node's welds.
#[derive(Clone, Debug, Serialize)]
pub struct WeldNodeDoc {
    /// The node's core.
    pub core: Option<WeldCore>,
    /// Edges (members).
    pub edges: Vec<usize>,
    /// The node.
    pub node: u32,
    /// Pairs of plates side by side at a node.
    pub pairs: Vec<WeldPairDoc>,
    /// The seams' plies of the other group, which pass the node unwelded.
    pub passing: Vec<PassingDoc>,
    /// The plate each edge welds with here (a seam's ply of the node's group).
    pub plates: Vec<String>,
    /// Each plate's setback from the node axis, mm.
    pub setbacks_mm: Vec<f64>,
    /// `even`, `needs a node core` or `core`.
    pub status: &'static str,
}

/// A seam's ply at the other group's node: not welded there, set back clear of the welds.
#[derive(Clone, Debug, Serialize)]
pub struct PassingDoc {
    /// Its least distance from the plates welded at the node (and the core), mm.
    pub clearance_mm: f64,
    /// The seam's edge.
    pub edge: usize,
    /// The ply's tag.
    pub plate: String,
    /// Its setback from the node axis, mm.
    pub setback_mm: f64,
}

/// A node's core as the weld report gives it.
#[derive(Clone, Debug, Serialize)]
pub struct WeldCore {
    /// Its tag.
    pub id: String,
    /// Length, mm.
    pub length: f64,
    /// Tube outer diameter, mm.
    pub outer_diameter: f64,
    /// Root gap of the weld, mm.
    pub root_gap_mm: Vec<f64>,
    /// Tube wall, mm.
    pub wall: f64,
}

/// Two plates side by side at a node.
#[derive(Clone, Debug, Serialize)]
pub struct WeldPairDoc {
    /// The weld access class.
    pub access: &'static str,
    /// Dihedral angle between the two plates about the node axis, degrees.
    pub dihedral_deg: f64,
    /// Edges (members).
    pub edges: [usize; 2],
    /// Whether the root gap is within its tolerance.
    pub gap_within_tolerance: bool,
    /// Plates.
    pub plates: [String; 2],
    /// Root gap of the weld, mm.
    pub root_gap_mm: f64,
}

/// The weld report's totals.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WeldSummary {
    /// Node cores (tubes).
    pub cores: usize,
    /// Nodes whose gaps are even.
    pub even_nodes: usize,
    /// Nodes.
    pub nodes: usize,
    /// Nodes whose gaps setbacks cannot even.
    pub nodes_needing_a_core: Vec<u32>,
    /// Pairs of plates side by side at a node.
    pub pairs: usize,
    /// Pairs at 120–135° (AWS D1.1 only).
    pub pairs_120_135: usize,
    /// Pairs at 60–120° (prequalified fillet).
    pub pairs_60_120: usize,
    /// Pairs below 60° (no prequalified fillet).
    pub pairs_below_60: usize,
    /// Pairs below the minimum weld angle.
    pub pairs_below_min_weld_angle: usize,
    /// Pairs at 135–180° (butt).
    pub pairs_over_135: usize,
    /// The smallest dihedral angle, degrees.
    pub smallest_dihedral_deg: f64,
}

fn welds(set: &PlateSet, opts: &PlateOptions, min_angle: Option<f64>) -> Welds {
    // The plate edge k welds with in group g: a seam's ply of that group.
    let id = |k: usize, g: u32| -> String {
        let mine = set.by_edge[k]
            .iter()
            .find(|&&i| set.plates[i].group == g)
            .unwrap_or(&set.by_edge[k][0]);
        set.plates[*mine].id.clone()
    };
    let mut sum = WeldSummary {
        smallest_dihedral_deg: f64::INFINITY,
        ..Default::default()
    };
    let mut nodes = Vec::with_capacity(set.welds.len());
    for w in &set.welds {
        sum.nodes += 1;
        if w.core.is_some() {
            sum.cores += 1;
        } else if !w.even {
            sum.nodes_needing_a_core.push(w.node);
        }
        let status = match (w.core, w.even) {
            (Some(_), _) => "core",
            (None, true) => "even",
            (None, false) => "needs a node core",
        };
        let mut pairs = Vec::new();
        for p in &w.pairs {
            sum.pairs += 1;
            let class = welds::weld_class(p.angle_deg);
            let name = welds::WELD_CLASSES[class].0;
            *[
                &mut sum.pairs_below_60,
                &mut sum.pairs_60_120,
                &mut sum.pairs_120_135,
                &mut sum.pairs_over_135,
            ][class] += 1;
            sum.smallest_dihedral_deg = sum.smallest_dihedral_deg.min(p.angle_deg);
            if min_angle.is_some_and(|a| p.angle_deg < a) {
                sum.pairs_below_min_weld_angle += 1;
            }
            pairs.push(WeldPairDoc {
                access: name,
                dihedral_deg: p.angle_deg,
                edges: p.edges,
                gap_within_tolerance: (p.gap - opts.weld_gap).abs()
                    <= opts.weld_gap_tolerance + 1e-9,
                plates: [id(p.edges[0], w.group), id(p.edges[1], w.group)],
                root_gap_mm: p.gap,
            });
        }
        let core = w.core.map(|c| {
            let c = &set.cores[c];
            WeldCore {
                id: c.id.clone(),
                length: c.length,
                outer_diameter: c.size.diameter,
                root_gap_mm: w
                    .setbacks
                    .iter()
                    .map(|s| s - 0.5 * c.size.diameter)
                    .collect(),
                wall: c.size.wall,
            }
        });
        nodes.push(WeldNodeDoc {
            core,
            edges: w.edges.clone(),
            node: w.node,
            pairs,
            passing: w
                .passing
                .iter()
                .map(|p| PassingDoc {
                    clearance_mm: p.clearance,
                    edge: p.edge,
                    plate: set.by_edge[p.edge]
                        .iter()
                        .map(|&i| &set.plates[i])
                        .find(|q| q.group != w.group)
                        .map(|q| q.id.clone())
                        .unwrap_or_default(),
                    setback_mm: p.setback,
                })
                .collect(),
            plates: w.edges.iter().map(|&k| id(k, w.group)).collect(),
            setbacks_mm: w.setbacks.clone(),
            status,
        });
    }
    if sum.pairs == 0 {
        sum.smallest_dihedral_deg = 0.0;
    }
    sum.even_nodes = sum.nodes - sum.nodes_needing_a_core.len() - sum.cores;
    Welds {
        definitions: WeldDefinitions {
            access: "by the dihedral angle: below 60°: no prequalified fillet weld; 60–120°: fillet (EN 1993-1-8 §4.3.2.1); 120–135°: fillet under AWS D1.1 only; 135–180°: the plates meet end to end (butt weld)",
            dihedral_deg: "the angle between the two plates about the node axis, 0–180°, one per pair of plates side by side (a two-plate node's pair is listed once, though welded on both sides; where the wedge between two neighbours opens beyond 180°, the outside of a corner, the angle is the one measured the other way round, through the other plates)",
            root_gap_mm: "distance between the two plates (of a bolted seam, its ply in the node's group, which welds there) in the plane perpendicular to the node axis: the weld's root opening along the line where they meet",
        },
        format: crate::fabricate::plates_file::WELDS_FORMAT,
        min_weld_angle: min_angle,
        nodes,
        summary: sum,
        units: "mm",
        version: crate::fabricate::plates_file::WELDS_VERSION,
        weld_gap: opts.weld_gap,
        weld_gap_tolerance: opts.weld_gap_tolerance,
    }
}

impl Welds {
    /// welds.json's text.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).expect("reports serialise") + "\n"
    }

    /// The nodes as the viewer takes them (what welds.json reads back as).
    pub fn nodes(&self) -> Vec<WeldNode> {
        self.nodes
            .iter()
            .map(|n| WeldNode {
                node: n.node,
                status: n.status.to_string(),
                plates: n.plates.clone(),
                pairs: n
                    .pairs
                    .iter()
                    .map(|p| WeldPair {
                        plates: p.plates.clone(),
                        dihedral_deg: p.dihedral_deg,
                        root_gap_mm: p.root_gap_mm,
                        gap_within_tolerance: p.gap_within_tolerance,
                        access: p.access.to_string(),
                    })
                    .collect(),
            })
            .collect()
    }
}

/// Sides of the polygon standing for a core's circles in meshes.
pub const CORE_SEGMENTS: usize = 48;

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
    // Plates triangulated side by side (each on its own); added in order.
    let prisms: Vec<_> = set.plates.par_iter().map(|p| p.prism()).collect();
    for prism in prisms {
        add(prism);
    }
    for c in &set.cores {
        add(tube(c));
    }
    mesh
}

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
    let quad = |t: &mut Vec<[u32; 3]>, a: u32, b: u32, c: u32, d: u32| {
        t.push([a, b, c]);
        t.push([a, c, d]);
    };
    for k in 0..n {
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
pub fn write_assembly_obj(set: &PlateSet, path: &Path) -> Result<(), WriteError> {
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
    })
}

/// One DXF per plate in `dir/parts/` (CUT_OUTER, CUT_INNER, ETCH, in the plate's own frame)
/// and `dir/assembly.scad` placing them, with the cores and the bolts.
pub fn write_parts(made: &Plated, dir: &Path) -> Result<(), WriteError> {
    let parts = dir.join("parts");
    std::fs::create_dir_all(&parts).map_err(|source| WriteError::Io {
        path: parts.clone(),
        source,
    })?;
    let set = &made.set;
    let mut names = Vec::with_capacity(set.plates.len());
    for (p, (part, _)) in set.plates.iter().zip(&made.parts) {
        let name = format!("parts/{}.dxf", p.id);
        let label = format!("{} {} mm, part {}", made.material.name, p.thickness, p.id);
        write_cut_dxf(&[part], None, &[], &label, &dir.join(&name))?;
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
    let cores: Vec<ScadCore> = set
        .cores
        .iter()
        .map(|c| ScadCore {
            id: &c.id,
            outer: c.size.diameter,
            inner: c.size.diameter - 2.0 * c.size.wall,
            length: c.length,
            matrix: axis_frame(c.base, c.axis),
        })
        .collect();
    write_scad(&scad, &cores, &scad_bolts(set), &dir.join("assembly.scad"))
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

/// The weld page (see [`welds_html`]) with the plates and welds in the viewer beside `inputs`
/// (the axes, a sizing); a model too large for the viewer gets the page without its 3D view,
/// and the second value says so.
pub fn weld_page(
    made: &Plated,
    inputs: Vec<(String, crate::view::scene::Input)>,
    with_sizing: bool,
) -> Result<(String, Option<String>), crate::view::pack::ViewError> {
    use crate::view::scene::{scene, Input};
    let mut all = vec![
        (
            "plates.json".to_string(),
            Input::Plates(made.records(), made.core_records()),
        ),
        (
            "welds.json".to_string(),
            Input::Welds(
                made.welds.weld_gap,
                made.welds.weld_gap_tolerance,
                made.welds.nodes(),
            ),
        ),
    ];
    all.extend(inputs);
    let (viewer, note) = match scene(&all, Some("plates and welds".to_string())) {
        Ok(scene) => (crate::view::embed(&scene, "70vh"), None),
        Err(e @ crate::view::pack::ViewError::TooLarge { .. }) => (
            format!("<p>No 3D view: {}.</p>", crate::text::html(&e.to_string())),
            Some(format!("welds.html without its 3D view: {e}")),
        ),
        Err(e) => return Err(e),
    };
    Ok((welds_html(made, &viewer, with_sizing), note))
}

/// The files `plates` writes, by name, into `dir` (made if missing): plates.json, assembly.stl,
/// assembly.obj, welds.json, welds.html (`page`, from [`weld_page`]), parts/ID.dxf and
/// assembly.scad (see [`write_parts`]).
pub fn write_folder(made: &Plated, dir: &Path, page: &str) -> Result<(), WriteError> {
    let folder_error = |msg: String| WriteError::Content {
        path: dir.to_path_buf(),
        msg,
    };
    if dir.exists() && !dir.is_dir() {
        return Err(folder_error("exists and is not a folder".into()));
    }
    std::fs::create_dir_all(dir).map_err(|e| folder_error(format!("cannot create folder: {e}")))?;
    let text = made.file.text();
    write_atomic(&dir.join("plates.json"), |w| w.write_all(text.as_bytes()))?;
    crate::mesh::io::write_mesh(&assembly(&made.set), &dir.join("assembly.stl"), 0)?;
    write_assembly_obj(&made.set, &dir.join("assembly.obj"))?;
    write_parts(made, dir)?;
    let text = made.welds.json();
    write_atomic(&dir.join("welds.json"), |w| w.write_all(text.as_bytes()))?;
    write_atomic(&dir.join("welds.html"), |w| w.write_all(page.as_bytes()))
}

/// welds.html: the summary by class, the definitions, the viewer (`viewer`: an embedded scene
/// of the plates and their welds, see `view::embed`) and every pair in a table, the shop's
/// problems first: pairs below 60°, root gaps out of tolerance, AWS-only, butt, then the
/// prequalified fillets; within a class the sharpest (or, of AWS-only, the widest) first.
pub fn welds_html(made: &Plated, viewer: &str, with_sizing: bool) -> String {
    let w = &made.welds;
    let s = &w.summary;
    let mut pairs: Vec<(&WeldNodeDoc, &WeldPairDoc, usize, bool)> = Vec::new();
    for n in &w.nodes {
        for p in &n.pairs {
            let off = !p.gap_within_tolerance && n.core.is_none();
            pairs.push((n, p, welds::weld_class(p.dihedral_deg), off));
        }
    }
    let urgency = |&(_, _, class, off): &(&WeldNodeDoc, &WeldPairDoc, usize, bool)| {
        let u = welds::weld_class_urgency(class);
        // Out-of-tolerance gaps come right after the pairs no fillet can weld.
        if u == 0 {
            0
        } else if off {
            1
        } else {
            u + 1
        }
    };
    pairs.sort_by(|x, y| {
        let key = |t: &(&WeldNodeDoc, &WeldPairDoc, usize, bool)| {
            // AWS-only: widest first; every other class: sharpest first.
            if t.2 == 2 {
                -t.1.dihedral_deg
            } else {
                t.1.dihedral_deg
            }
        };
        urgency(x)
            .cmp(&urgency(y))
            .then(key(x).total_cmp(&key(y)))
            .then(x.0.node.cmp(&y.0.node))
    });
    let mut rows = String::new();
    for (n, p, class, off) in &pairs {
        let k = n
            .pairs
            .iter()
            .position(|q| std::ptr::eq(q, *p))
            .unwrap_or(0);
        rows.push_str(&format!(
            "<tr><td>W{}-{}</td><td>{}</td><td>{}</td><td>{} / {}</td><td{}>{:.3}</td><td>{:.2}</td><td><span class=\"sw\" style=\"background:{}\"></span>{}</td></tr>\n",
            n.node,
            k + 1,
            n.node,
            n.status,
            p.plates[0],
            p.plates[1],
            if *off { " class=\"bad\"" } else { "" },
            p.root_gap_mm,
            p.dihedral_deg,
            welds::WELD_CLASSES[*class].1,
            p.access
        ));
    }
    let counts = [
        s.pairs_below_60,
        s.pairs_60_120,
        s.pairs_120_135,
        s.pairs_over_135,
    ];
    let mut order: Vec<usize> = (0..welds::WELD_CLASSES.len()).collect();
    order.sort_by_key(|&c| welds::weld_class_urgency(c));
    let mut classes = String::new();
    for c in order {
        let (label, colour) = welds::WELD_CLASSES[c];
        classes.push_str(&format!(
            "<tr><td><span class=\"sw\" style=\"background:{colour}\"></span>{label}</td><td>{}</td></tr>\n",
            counts[c]
        ));
    }
    let off_gaps = pairs.iter().filter(|t| t.3).count();
    let viewer = format!(
        "<h2>Look around</h2>\n<p>Plates coloured by group, gauge{} (the menu beside them); each pair of plates side by side at a node is a dot between their edges there (mid-height of the seam), coloured by its access class or root gap. Hover or click for figures; find a plate by its tag or a pair as W, its node and its number (W12-2).</p>\n{viewer}",
        if with_sizing { " or utilisation" } else { "" },
    );
    format!(
        "<!doctype html><meta charset=\"utf-8\"><title>lamina weld report</title>\n\
<style>body{{font:14px system-ui,sans-serif;margin:2em}}table{{border-collapse:collapse}}\
td,th{{border:1px solid #ccc;padding:2px 8px;text-align:left}}td.bad{{background:#fdd}}\
.sw{{display:inline-block;width:.9em;height:.9em;margin-right:.4em;vertical-align:-.1em;border-radius:2px}}</style>\n\
<h1>Welds at the nodes</h1>\n\
<p>{} nodes, {} pairs of plates side by side. Root gap target {} ± {} mm: {} nodes even, {} need a node core{}{}. \
Smallest angle between welded plates {:.2}°.</p>\n\
<table><tr><th>access, by the angle between the plates</th><th>pairs</th></tr>\n{classes}</table>\n\
<dl><dt>Root gap</dt><dd>the distance between the two plates (of a bolted seam, its ply of the node's group, which welds there; the other ply stops clear) \
in the plane perpendicular to the node axis: the weld's root opening along the line where they meet, mm.</dd>\
<dt>Dihedral angle</dt><dd>the angle between the two plates about the node axis, 0–180°, one per pair of plates side by side \
(a two-plate node's pair is listed once, though it is welded on both sides; where the wedge between two neighbours opens beyond 180°, \
the outside of a corner, the angle is measured the other way round). Below 60° there is no prequalified fillet weld; 60–120° is \
prequalified by EN 1993-1-8 §4.3.2.1; AWS D1.1 allows up to 135°; above that the plates meet end to end \
(a butt weld).</dd></dl>\n\
{viewer}\n\
<h2>Pairs, the shop's problems first</h2>\n\
<p>Below 60° first (sharpest first), then root gaps out of tolerance, AWS D1.1 only (widest first), butt welds, and the prequalified fillets.</p>\n\
<table><tr><th>pair</th><th>node</th><th>status</th><th>plates</th><th>root gap, mm</th><th>dihedral, °</th><th>access</th></tr>\n{rows}</table>\n",
        s.nodes,
        s.pairs,
        w.weld_gap,
        w.weld_gap_tolerance,
        s.even_nodes,
        s.nodes_needing_a_core.len(),
        if s.cores > 0 {
            format!(", {} have one", s.cores)
        } else {
            String::new()
        },
        if off_gaps > 0 {
            format!("; {off_gaps} pair(s) with the root gap out of tolerance")
        } else {
            String::new()
        },
        s.smallest_dihedral_deg,
    )
}

/// plates.json read back from its text in memory (for a caller that holds the document).
pub fn records_of(doc: &PlatesDoc) -> Result<PlatesRead, ReadError> {
    doc.records(Path::new("plates"))
}
