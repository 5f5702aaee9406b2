//! From plates to what a shop needs: etched tags, nested cut sheets, cut-sheet DXFs, and the
//! OpenSCAD assembly that rebuilds the design from exactly what is cut; and the print path: the
//! watertight solid, its slices and the print archive.

pub mod archive;
pub mod assembly;
pub mod cutpath;
pub mod cutplan;
pub mod cutsheet;
pub mod estimate;
pub mod nc;
pub mod nest;
pub mod nest_file;
pub mod plates_file;
pub mod preview;
pub mod separate;
pub mod sl1;
pub mod slice;
pub mod solid;
pub mod tags;
