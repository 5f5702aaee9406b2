//! From plates to what a shop needs: etched tags, nested cut sheets, cut-sheet DXFs, and the
//! OpenSCAD assembly that rebuilds the design from exactly what is cut.

pub mod assembly;
pub mod cutsheet;
pub mod nest;
pub mod plates_file;
pub mod preview;
pub mod tags;
