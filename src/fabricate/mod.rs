//! From plates to what a shop needs: etched tags, cut-sheet DXFs, and the OpenSCAD assembly
//! that rebuilds the design from exactly what is cut. Nesting is still to come.

pub mod assembly;
pub mod cutsheet;
pub mod tags;
