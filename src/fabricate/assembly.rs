//! `assembly.scad`: an OpenSCAD program that imports each part's outline from its DXF (layer
//! CUT), extrudes it by the part's thickness about its mid-plane and places it with
//! `multmatrix`. Rendering it rebuilds the sculpture from exactly what will be cut.
//!
//! From nested sheets ([`write_scad_from_sheets`]), each part is cut out of its sheet's DXF:
//! the sheet's CUT layer is intersected with a clip polygon around the part (its hull grown
//! halfway to its neighbours), moved back into the plate's frame by the inverse of its nesting
//! placement, then extruded and placed as above.

use std::io::Write;
use std::path::Path;

use glam::DVec2;

use crate::files::{write_atomic, WriteError};

const PARTS_HEADER: &str = "\
// lamina assembly: every part imported from its cut DXF (layer CUT),
// extruded by its thickness about its mid-plane, placed by its matrix. mm.
module part(file, t, m) {
  multmatrix(m) translate([0, 0, -t / 2])
    linear_extrude(height = t) import(file, layer = \"CUT\");
}
";

const SHEETS_HEADER: &str = "\
// lamina assembly from the nested sheets: each part is cut out of its
// sheet's DXF (layer CUT) by a clip polygon around it, moved back into
// its plate frame, extruded by its thickness about its mid-plane and
// placed by its matrix. mm.
module part(file, t, m, back, clip) {
  multmatrix(m) translate([0, 0, -t / 2]) linear_extrude(height = t)
    multmatrix(back) intersection() {
      import(file, layer = \"CUT\");
      polygon(clip);
    }
}
";

/// One part for the program: its DXF (relative to the program), thickness, placement rows.
pub struct ScadPart<'a> {
    pub id: &'a str,
    pub dxf: &'a str,
    pub thickness: f64,
    pub matrix: [[f64; 4]; 4],
}

pub fn write_scad(parts: &[ScadPart], path: &Path) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        w.write_all(PARTS_HEADER.as_bytes())?;
        for p in parts {
            writeln!(
                w,
                "part(\"{}\", {:?}, [{}]); // {}",
                p.dxf,
                p.thickness,
                rows(&p.matrix),
                p.id
            )?;
        }
        Ok(())
    })
}

/// A part cut from a nested sheet: where it sits on the sheet and the region that holds only it.
pub struct SheetPart<'a> {
    pub id: &'a str,
    /// The sheet's DXF, relative to the program.
    pub dxf: &'a str,
    pub thickness: f64,
    pub matrix: [[f64; 4]; 4],
    /// Sheet point = R(angle)·plate point + offset.
    pub angle: f64,
    pub offset: DVec2,
    /// In sheet coordinates: contains the part and no other.
    pub clip: Vec<DVec2>,
}

pub fn write_scad_from_sheets(parts: &[SheetPart], path: &Path) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        w.write_all(SHEETS_HEADER.as_bytes())?;
        for p in parts {
            // Inverse of q ↦ R q + o: s ↦ Rᵀ (s − o).
            let (sin, cos) = p.angle.sin_cos();
            let t = DVec2::new(
                -(cos * p.offset.x + sin * p.offset.y),
                -(-sin * p.offset.x + cos * p.offset.y),
            );
            let back = format!(
                "[[{cos:?}, {sin:?}, 0, {:?}], [{:?}, {cos:?}, 0, {:?}], [0, 0, 1, 0], [0, 0, 0, 1]]",
                t.x, -sin, t.y
            );
            let clip: Vec<String> = p
                .clip
                .iter()
                .map(|q| format!("[{:?}, {:?}]", q.x, q.y))
                .collect();
            writeln!(
                w,
                "part(\"{}\", {:?}, [{}], {back}, [{}]); // {}",
                p.dxf,
                p.thickness,
                rows(&p.matrix),
                clip.join(", "),
                p.id
            )?;
        }
        Ok(())
    })
}

/// A 4 × 4 matrix as OpenSCAD rows, every digit kept.
fn rows(m: &[[f64; 4]; 4]) -> String {
    let r: Vec<String> = m
        .iter()
        .map(|r| format!("[{:?}, {:?}, {:?}, {:?}]", r[0], r[1], r[2], r[3]))
        .collect();
    r.join(", ")
}
