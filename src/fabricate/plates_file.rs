//! Reading `plates.json` (format `lamina-plates`, version 2, written by `lamina plates`): what
//! nesting, the BOM and the assembly need of each plate, and the node cores.

use std::collections::HashSet;
use std::path::Path;

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::files::{check_format, read_nonempty, utf8_text, ReadError};

pub const FORMAT: &str = "lamina-plates";
pub const VERSION: u32 = 2;

/// One plate as the file holds it.
#[derive(Clone, Debug, PartialEq)]
pub struct PlateRecord {
    pub id: String,
    /// Assembly group, from 1.
    pub group: u32,
    pub thickness: f64,
    /// In the plate's own frame, mm.
    pub outline: Vec<DVec2>,
    /// Rows of the 4 × 4 placement (plate frame → world).
    pub matrix: [[f64; 4]; 4],
    /// Per end: the node and the plates welded to it there.
    pub ends: [(u32, Vec<String>); 2],
    pub bolted_to: Option<String>,
    /// Per end: the node core the plate welds to there, if any.
    pub end_cores: [Option<String>; 2],
    /// Bolt hole centres in the plate's frame.
    pub holes: Vec<DVec2>,
    /// Size, d0 and ordered length of the bolts through them.
    pub bolt: Option<BoltRecord>,
    /// The network edge it stands on (files since version 2 say it).
    pub edge: Option<u32>,
}

/// The bolts through a seam's plies. Fields in the file's order (those earlier files lack
/// default).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoltRecord {
    /// The check that governs (EN 1993-1-8 Table 3.4), when checked against a sizing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub check: Option<String>,
    /// Every check's utilisation on the most loaded bolt, when checked.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checks: Option<std::collections::BTreeMap<String, f64>>,
    /// Bolts that cannot be fitted or tightened: the hole, the envelope, what it crosses.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub clashes: Vec<String>,
    /// Property class (8.8, A4-70).
    #[serde(default)]
    pub class: String,
    pub d: f64,
    pub grip: f64,
    pub hole_diameter: f64,
    pub length: f64,
    /// Holes whose nut goes on the stack's −z face (the plies' frame; the others' on +z),
    /// where only that side has room for it and the socket.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub nut_below: Vec<usize>,
    /// How they are installed.
    #[serde(default)]
    pub preload: String,
    pub size: String,
    /// The governing check's utilisation, when checked against a sizing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub utilisation: Option<f64>,
}

/// A node core: a tube cut from tube stock, not a sheet part. Fields in the file's order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CoreRecord {
    pub axis: [f64; 3],
    pub base: [f64; 3],
    pub group: u32,
    pub id: String,
    pub length: f64,
    pub node: u32,
    pub outer_diameter: f64,
    pub wall: f64,
}

impl PlateRecord {
    pub fn hole_diameter(&self) -> f64 {
        self.bolt.as_ref().map(|b| b.hole_diameter).unwrap_or(0.0)
    }

    /// The outline's area less the holes (as the `hole_segments`-gons the file says), mm².
    pub fn area(&self) -> f64 {
        let p = &self.outline;
        let outer = 0.5
            * (0..p.len())
                .map(|k| p[k].perp_dot(p[(k + 1) % p.len()]))
                .sum::<f64>()
                .abs();
        let r = 0.5 * self.hole_diameter();
        let n = crate::rationalize::plates::HOLE_SEGMENTS as f64;
        let hole = 0.5 * n * r * r * (std::f64::consts::TAU / n).sin();
        outer - hole * self.holes.len() as f64
    }
}

/// One end of a plate in plates.json. Fields in the file's order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EndDoc {
    /// The node core it welds to there.
    #[serde(default)]
    pub core: Option<String>,
    pub node: u32,
    /// Cut back from the node's axis, mm.
    pub setback: f64,
    /// The plates welded to it there.
    pub welded_to: Vec<String>,
}

/// One plate as plates.json writes it (the fields earlier versions lack default). Fields in
/// the file's order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlateDoc {
    #[serde(default)]
    pub area_mm2: f64,
    #[serde(default)]
    pub bolt: Option<BoltRecord>,
    pub bolted_to: Option<String>,
    #[serde(default)]
    pub edge: Option<u32>,
    pub ends: [EndDoc; 2],
    #[serde(default)]
    pub flattening_mm: f64,
    /// Assembly group, from 1.
    pub group: u32,
    #[serde(default)]
    pub holes: Vec<[f64; 2]>,
    pub id: String,
    /// Rows of the 4 × 4 placement (plate frame → world).
    pub matrix: [[f64; 4]; 4],
    #[serde(default)]
    pub nodes: [u32; 2],
    /// In the plate's own frame, mm.
    pub outline: Vec<[f64; 2]>,
    pub thickness: f64,
}

/// plates.json: the plates, the node cores and the rules they were made by.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlatesDoc {
    /// `lamina-plates`.
    pub format: &'static str,
    pub version: u32,
    /// `mm`.
    pub units: &'static str,
    /// The steel.
    pub material: MaterialRecord,
    pub gauges: Vec<f64>,
    pub weld_gap: f64,
    pub weld_gap_tolerance: f64,
    pub hole_segments: usize,
    pub core_segments: usize,
    pub cores: Vec<CoreRecord>,
    pub plates: Vec<PlateDoc>,
}

impl PlatesDoc {
    /// The file's text: the header, the cores on one line, one plate a line.
    pub fn text(&self) -> String {
        use std::fmt::Write as _;
        fn json<T: Serialize + ?Sized>(v: &T) -> String {
            serde_json::to_string(v).expect("plain data serialises")
        }
        let mut w = String::new();
        let _ = writeln!(w, "{{");
        let _ = writeln!(w, "  \"format\": \"{}\",", self.format);
        let _ = writeln!(w, "  \"version\": {},", self.version);
        let _ = writeln!(w, "  \"units\": \"{}\",", self.units);
        let _ = writeln!(w, "  \"material\": {},", json(&self.material));
        let _ = writeln!(w, "  \"gauges\": {},", json(&self.gauges));
        let _ = writeln!(w, "  \"weld_gap\": {},", json(&self.weld_gap));
        let _ = writeln!(
            w,
            "  \"weld_gap_tolerance\": {},",
            json(&self.weld_gap_tolerance)
        );
        let _ = writeln!(w, "  \"hole_segments\": {},", self.hole_segments);
        let _ = writeln!(w, "  \"core_segments\": {},", self.core_segments);
        let _ = writeln!(w, "  \"cores\": {},", json(&self.cores));
        let _ = writeln!(w, "  \"plates\": [");
        for (k, p) in self.plates.iter().enumerate() {
            let sep = if k + 1 < self.plates.len() { "," } else { "" };
            let _ = writeln!(w, "    {}{sep}", json(p));
        }
        let _ = writeln!(w, "  ]");
        let _ = writeln!(w, "}}");
        w
    }

    /// The records nesting, the BOM and the assembly take (checked as the file reader checks
    /// them; `path` names the document in errors).
    pub fn records(&self, path: &Path) -> Result<PlatesRead, ReadError> {
        records(
            self.plates.clone(),
            self.cores.clone(),
            Some(self.material.clone()),
            path,
        )
    }
}

/// A plates file's steel: its grade and density (g/cm³).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialRecord {
    pub density: f64,
    pub grade: String,
}

impl MaterialRecord {
    /// What files before the material travelled meant: stainless 1.4404.
    pub fn unstated() -> MaterialRecord {
        MaterialRecord {
            density: 8.0,
            grade: "1.4404".into(),
        }
    }
}

impl Default for MaterialRecord {
    fn default() -> Self {
        MaterialRecord::unstated()
    }
}

#[derive(Deserialize)]
struct File {
    plates: Vec<PlateDoc>,
    #[serde(default)]
    cores: Vec<CoreRecord>,
    material: Option<MaterialRecord>,
}

/// The plates and node cores of a plates document held as a JSON value (`path` names it in
/// errors), checked as the file reader checks a file.
pub fn records_from_value(doc: serde_json::Value, path: &Path) -> Result<PlatesRead, ReadError> {
    let format = doc.get("format").and_then(|f| f.as_str()).unwrap_or("");
    if format != FORMAT {
        return Err(ReadError::file(
            path,
            format!(
                "format is {format:?}, expected \"{FORMAT}\" (the plates the plates stage makes)"
            ),
        ));
    }
    let file: File =
        serde_json::from_value(doc).map_err(|e| ReadError::file(path, e.to_string()))?;
    records(file.plates, file.cores, file.material, path)
}

/// The thickest plate a file may hold: 1 m of steel is no plate.
pub const MAX_THICKNESS: f64 = 1000.0;
/// The largest plate coordinate: 100 m, as for sheets.
pub const MAX_COORD: f64 = 1e5;
/// The most bolt holes in one plate.
pub const MAX_HOLES: usize = 10_000;

/// A plates file read: the plates, the node cores and the steel (None in files from before it
/// was written).
pub type PlatesRead = (Vec<PlateRecord>, Vec<CoreRecord>, Option<MaterialRecord>);

/// The plates, the node cores and the steel.
pub fn read_plates(path: &Path) -> Result<PlatesRead, ReadError> {
    let text = utf8_text(path, read_nonempty(path)?)?;
    // Version 1 (before bolts and cores) reads as plates without holes.
    let what = "the plates file `lamina plates` writes";
    check_format(path, &text, FORMAT, VERSION, what)
        .or_else(|e| check_format(path, &text, FORMAT, 1, what).map_err(|_| e))?;
    let file: File =
        serde_json::from_str(&text).map_err(|e| ReadError::line(path, e.line(), e.to_string()))?;
    records(file.plates, file.cores, file.material, path)
}

/// Plate records from the file's plates, every value checked.
fn records(
    plates: Vec<PlateDoc>,
    cores: Vec<CoreRecord>,
    material: Option<MaterialRecord>,
    path: &Path,
) -> Result<PlatesRead, ReadError> {
    if let Some(m) = &material {
        if !(m.density > 0.1 && m.density <= 30.0)
            || m.grade.trim().is_empty()
            || m.grade.len() > 64
        {
            return Err(ReadError::file(
                path,
                "material: the grade must be a name of at most 64 characters and the density \
                 from 0.1 to 30 g/cm³",
            ));
        }
    }
    if plates.is_empty() {
        return Err(ReadError::file(path, "holds no plates"));
    }
    let mut seen = HashSet::new();
    let mut out = Vec::with_capacity(plates.len());
    for (k, r) in plates.into_iter().enumerate() {
        let bad = |msg: &str| ReadError::record(path, format!("plate {k} ({})", r.id), msg);
        if r.id.is_empty() || !seen.insert(r.id.clone()) {
            return Err(bad("its id is empty or used before"));
        }
        if r.group == 0 {
            return Err(bad("groups count from 1"));
        }
        if !(r.thickness > 0.0 && r.thickness <= MAX_THICKNESS) {
            return Err(bad(&format!(
                "thickness must be a positive number of mm, at most {MAX_THICKNESS}"
            )));
        }
        if r.outline.len() < 3
            || r.outline
                .iter()
                .flatten()
                .any(|v| v.is_nan() || v.abs() > MAX_COORD)
        {
            return Err(bad(&format!(
                "the outline needs at least 3 points, all finite and within {MAX_COORD:e} mm"
            )));
        }
        if r.matrix.iter().flatten().any(|v| !v.is_finite()) {
            return Err(bad("the matrix holds a value that is not a finite number"));
        }
        if r.holes.len() > MAX_HOLES
            || r.holes
                .iter()
                .flatten()
                .any(|v| v.is_nan() || v.abs() > MAX_COORD)
        {
            return Err(bad(&format!(
                "at most {MAX_HOLES} holes, every coordinate finite and within {MAX_COORD:e} mm"
            )));
        }
        match &r.bolt {
            None if !r.holes.is_empty() => return Err(bad("it has holes but no bolt")),
            Some(b)
                if !(b.hole_diameter > 0.0
                    && b.hole_diameter <= MAX_THICKNESS
                    && b.d > 0.0
                    && b.d < b.hole_diameter
                    && b.length.is_finite()
                    && b.grip.is_finite()
                    && b.utilisation.is_none_or(|u| u.is_finite() && u >= 0.0)) =>
            {
                return Err(bad(
                    "the bolt needs a hole wider than its shank, both positive (and a utilisation, \
                     if any, a number from 0)",
                ))
            }
            _ => {}
        }
        let outline: Vec<DVec2> = r.outline.iter().map(|p| DVec2::from_array(*p)).collect();
        let [a, b] = r.ends;
        let rec = PlateRecord {
            id: r.id,
            group: r.group,
            thickness: r.thickness,
            outline,
            matrix: r.matrix,
            end_cores: [a.core, b.core],
            ends: [(a.node, a.welded_to), (b.node, b.welded_to)],
            bolted_to: r.bolted_to,
            holes: r.holes.iter().map(|p| DVec2::from_array(*p)).collect(),
            bolt: r.bolt,
            edge: r.edge,
        };
        if rec.area() < 1e-9 {
            return Err(ReadError::record(
                path,
                format!("plate {k} ({})", rec.id),
                "the outline has no area",
            ));
        }
        out.push(rec);
    }
    for (k, c) in cores.iter().enumerate() {
        let ok = !c.id.is_empty()
            && c.outer_diameter > 0.0
            && c.outer_diameter <= MAX_THICKNESS
            && c.wall > 0.0
            && 2.0 * c.wall < c.outer_diameter
            && c.length > 0.0
            && c.length <= MAX_COORD
            && c.base.iter().all(|v| v.abs() <= MAX_COORD)
            && (glam::DVec3::from_array(c.axis).length() - 1.0).abs() < 1e-6;
        if !ok {
            return Err(ReadError::record(
                path,
                format!("core {k} ({})", c.id),
                "needs an id, a wall under half its outer diameter, a positive length, a base within 1e5 mm and a unit axis",
            ));
        }
    }
    Ok((out, cores, material))
}

pub const WELDS_FORMAT: &str = "lamina-welds";
pub const WELDS_VERSION: u32 = 1;

/// Two plates side by side at a node, as welds.json says.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct WeldPair {
    /// Each side's plate tag (of a seam, its ply welded at the node; files before seams welded
    /// within their group named both, `A+B`).
    pub plates: [String; 2],
    pub dihedral_deg: f64,
    pub root_gap_mm: f64,
    pub gap_within_tolerance: bool,
    /// The access class (`60–120°: fillet (EN 1993-1-8)`, ...).
    pub access: String,
}

/// A node of welds.json: its plates, their pairs, and whether its gaps are even.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct WeldNode {
    pub node: u32,
    pub status: String,
    pub plates: Vec<String>,
    pub pairs: Vec<WeldPair>,
}

#[derive(Deserialize)]
struct WeldFile {
    weld_gap: f64,
    weld_gap_tolerance: f64,
    nodes: Vec<WeldNode>,
}

/// The weld report `lamina plates` writes beside plates.json: the target gap and its
/// tolerance, mm, and the nodes.
pub fn read_welds(path: &Path) -> Result<(f64, f64, Vec<WeldNode>), ReadError> {
    let file: WeldFile = crate::files::read_lamina_json(
        path,
        WELDS_FORMAT,
        WELDS_VERSION,
        "the weld report `lamina plates` writes",
    )?;
    for (k, n) in file.nodes.iter().enumerate() {
        if n.pairs.iter().any(|p| {
            !(p.dihedral_deg.is_finite()
                && p.root_gap_mm.is_finite()
                && p.root_gap_mm.abs() < MAX_COORD)
        }) {
            return Err(ReadError::record(
                path,
                format!("node {k} ({})", n.node),
                "a pair's dihedral angle or root gap is not a finite number",
            ));
        }
    }
    Ok((file.weld_gap, file.weld_gap_tolerance, file.nodes))
}
