//! `assembly.scad`: an OpenSCAD program that imports each part's outline from its DXF (layer
//! CUT), extrudes it by the part's thickness about its mid-plane and places it with
//! `multmatrix`. Rendering it rebuilds the sculpture from exactly what will be cut.

use std::io::Write;
use std::path::Path;

use crate::files::{write_atomic, WriteError};

/// One part for the program: its DXF (relative to the program), thickness, placement rows.
pub struct ScadPart<'a> {
    pub id: &'a str,
    pub dxf: &'a str,
    pub thickness: f64,
    pub matrix: [[f64; 4]; 4],
}

pub fn write_scad(parts: &[ScadPart], path: &Path) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        writeln!(
            w,
            "// lamina assembly: every part imported from its cut DXF (layer CUT),"
        )?;
        writeln!(
            w,
            "// extruded by its thickness about its mid-plane, placed by its matrix. mm."
        )?;
        writeln!(w, "module part(file, t, m) {{")?;
        writeln!(w, "  multmatrix(m) translate([0, 0, -t / 2])")?;
        writeln!(
            w,
            "    linear_extrude(height = t) import(file, layer = \"CUT\");"
        )?;
        writeln!(w, "}}")?;
        for p in parts {
            let m: Vec<String> = p
                .matrix
                .iter()
                .map(|r| format!("[{:?}, {:?}, {:?}, {:?}]", r[0], r[1], r[2], r[3]))
                .collect();
            writeln!(
                w,
                "part(\"{}\", {:?}, [{}]); // {}",
                p.dxf,
                p.thickness,
                m.join(", "),
                p.id
            )?;
        }
        Ok(())
    })
}
