//! Reading `plates.json` (format `lamina-plates`, version 1, written by `lamina plates`): what
//! nesting, the BOM and the assembly need of each plate.

use std::collections::HashSet;
use std::path::Path;

use glam::DVec2;
use serde::Deserialize;

use crate::files::{check_format, read_nonempty, utf8_text, ReadError};

pub const FORMAT: &str = "lamina-plates";
pub const VERSION: u32 = 1;

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
}

impl PlateRecord {
    pub fn area(&self) -> f64 {
        let p = &self.outline;
        0.5 * (0..p.len())
            .map(|k| p[k].perp_dot(p[(k + 1) % p.len()]))
            .sum::<f64>()
            .abs()
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct End {
    node: u32,
    #[allow(dead_code)]
    setback: f64,
    welded_to: Vec<String>,
}

#[derive(Deserialize)]
struct Record {
    id: String,
    group: u32,
    thickness: f64,
    ends: [End; 2],
    bolted_to: Option<String>,
    matrix: [[f64; 4]; 4],
    outline: Vec<[f64; 2]>,
}

#[derive(Deserialize)]
struct File {
    plates: Vec<Record>,
}

/// The thickest plate a file may hold: 1 m of steel is no plate.
pub const MAX_THICKNESS: f64 = 1000.0;
/// The largest plate coordinate: 100 m, as for sheets.
pub const MAX_COORD: f64 = 1e5;

pub fn read_plates(path: &Path) -> Result<Vec<PlateRecord>, ReadError> {
    let text = utf8_text(path, read_nonempty(path)?)?;
    check_format(
        path,
        &text,
        FORMAT,
        VERSION,
        "the plates file `lamina plates` writes",
    )?;
    let file: File =
        serde_json::from_str(&text).map_err(|e| ReadError::line(path, e.line(), e.to_string()))?;
    if file.plates.is_empty() {
        return Err(ReadError::file(path, "holds no plates"));
    }
    let mut seen = HashSet::new();
    let mut out = Vec::with_capacity(file.plates.len());
    for (k, r) in file.plates.into_iter().enumerate() {
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
        let outline: Vec<DVec2> = r.outline.iter().map(|p| DVec2::from_array(*p)).collect();
        let [a, b] = r.ends;
        let rec = PlateRecord {
            id: r.id,
            group: r.group,
            thickness: r.thickness,
            outline,
            matrix: r.matrix,
            ends: [(a.node, a.welded_to), (b.node, b.welded_to)],
            bolted_to: r.bolted_to,
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
    Ok(out)
}
