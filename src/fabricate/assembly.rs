//! `assembly.scad`: an OpenSCAD program that imports each part's outline from its DXF (layer
//! CUT_OUTER, less the holes on CUT_INNER), extrudes it by the part's thickness about its
//! mid-plane and places it with `multmatrix`. Rendering it rebuilds the sculpture from exactly
//! what will be cut. Node cores are tubes; bolts (shank, head and nut as plain cylinders) are
//! drawn unless `-D bolts=false`.
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
// lamina assembly: every part imported from its cut DXF (layer CUT_OUTER
// less the holes on CUT_INNER), extruded by its thickness about its
// mid-plane, placed by its matrix. mm. Node cores are tubes; bolts are
// drawn unless rendered with -D bolts=false.
bolts = true;
$fn = 48;
module part(file, t, m) {
  multmatrix(m) translate([0, 0, -t / 2]) linear_extrude(height = t)
    difference() {
      import(file, layer = \"CUT_OUTER\");
      import(file, layer = \"CUT_INNER\");
    }
}
module bolt(d, len, grip, m) {
  if (bolts) multmatrix(m) {
    translate([0, 0, -0.7 * d]) cylinder(h = 0.7 * d, d = 1.7 * d, $fn = 6);
    cylinder(h = len, d = d);
    translate([0, 0, grip]) cylinder(h = 0.8 * d, d = 1.7 * d, $fn = 6);
  }
}
";

const SHEETS_HEADER: &str = "\
// lamina assembly from the nested sheets: each part is cut out of its
// sheet's DXF (layer CUT) by a clip polygon around it, moved back into
// its plate frame, extruded by its thickness about its mid-plane and
// placed by its matrix. mm.
$fn = 48;
module part(file, t, m, back, clip) {
  multmatrix(m) translate([0, 0, -t / 2]) linear_extrude(height = t)
    multmatrix(back) intersection() {
      difference() {
        import(file, layer = \"CUT_OUTER\");
        import(file, layer = \"CUT_INNER\");
      }
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

/// A node core: a tube from the frame's origin along its z.
pub struct ScadCore<'a> {
    pub id: &'a str,
    pub outer: f64,
    pub inner: f64,
    pub length: f64,
    pub matrix: [[f64; 4]; 4],
}

/// A bolt: its shank from the frame's origin (the stack's outer face) along z through the grip.
pub struct ScadBolt {
    pub name: &'static str,
    pub d: f64,
    pub length: f64,
    pub grip: f64,
    pub matrix: [[f64; 4]; 4],
}

pub fn write_scad(
    parts: &[ScadPart],
    cores: &[ScadCore],
    bolts: &[ScadBolt],
    path: &Path,
) -> Result<(), WriteError> {
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
        w.write_all(CORE_MODULE.as_bytes())?;
        for c in cores {
            write_core(w, c)?;
        }
        for b in bolts {
            writeln!(
                w,
                "bolt({:?}, {:?}, {:?}, [{}]); // {} x {}",
                b.d,
                b.length,
                b.grip,
                rows(&b.matrix),
                b.name,
                b.length
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
    /// Sheet point = R(angle)·plate point + offset; degrees.
    pub angle: f64,
    pub offset: DVec2,
    /// In sheet coordinates: contains the part and no other.
    pub clip: Vec<DVec2>,
}

pub fn write_scad_from_sheets(
    parts: &[SheetPart],
    cores: &[ScadCore],
    path: &Path,
) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        w.write_all(SHEETS_HEADER.as_bytes())?;
        w.write_all(CORE_MODULE.as_bytes())?;
        for c in cores {
            write_core(w, c)?;
        }
        for p in parts {
            // Inverse of q ↦ R q + o: s ↦ Rᵀ (s − o).
            let r = crate::fabricate::nest::turn(p.angle);
            let (sin, cos) = (r.y, r.x);
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

const CORE_MODULE: &str = "\
module core(od, id, len, m) {
  multmatrix(m) difference() {
    cylinder(h = len, d = od);
    translate([0, 0, -1]) cylinder(h = len + 2, d = id);
  }
}
";

fn write_core(w: &mut dyn Write, c: &ScadCore) -> std::io::Result<()> {
    writeln!(
        w,
        "core({:?}, {:?}, {:?}, [{}]); // {}",
        c.outer,
        c.inner,
        c.length,
        rows(&c.matrix),
        c.id
    )
}

/// A frame with its origin at `o` and z along `axis` (x any perpendicular, the same for the
/// same axis).
pub fn axis_frame(o: glam::DVec3, axis: glam::DVec3) -> [[f64; 4]; 4] {
    let z = axis.normalize();
    let x = z.any_orthonormal_vector();
    let y = z.cross(x);
    [
        [x.x, y.x, z.x, o.x],
        [x.y, y.y, z.y, o.y],
        [x.z, y.z, z.z, o.z],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// A 4 × 4 matrix as OpenSCAD rows, every digit kept.
fn rows(m: &[[f64; 4]; 4]) -> String {
    let r: Vec<String> = m
        .iter()
        .map(|r| format!("[{:?}, {:?}, {:?}, {:?}]", r[0], r[1], r[2], r[3]))
        .collect();
    r.join(", ")
}
