//! Reading nest.json back (for the viewer): the sheets, their cut files and the parts placed on
//! them. `lamina nest` writes it (src/cli/nest.rs); only what the viewer shows is read.

use std::path::Path;

use serde::Deserialize;

use crate::files::{read_lamina_json, ReadError};

pub const FORMAT: &str = "lamina-nest";
pub const VERSION: u32 = 2;

/// The most sheets and placements a nest file may list.
pub const MAX_ITEMS: usize = 1_000_000;

#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct NestSheet {
    /// The cut DXF, beside nest.json.
    pub file: String,
    pub thickness: f64,
    pub size: [f64; 2],
    pub parts: Vec<String>,
    pub utilisation: f64,
    pub cut_mm: f64,
    pub pierces: u64,
    pub etch_mm: f64,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct NestPlacement {
    pub id: String,
    pub sheet: String,
    /// Lower-left corner of the part's bounding box on the sheet.
    pub bbox_min: [f64; 2],
    pub rotation_deg: f64,
    pub micro_joints: u32,
}

#[derive(Deserialize)]
struct File {
    sheets: Vec<NestSheet>,
    placements: Vec<NestPlacement>,
}

/// The sheets and placements of a nest file.
pub fn read_nest(path: &Path) -> Result<(Vec<NestSheet>, Vec<NestPlacement>), ReadError> {
    let file: File = read_lamina_json(path, FORMAT, VERSION, "the nest file `lamina nest` writes")?;
    if file.sheets.len() > MAX_ITEMS || file.placements.len() > MAX_ITEMS {
        return Err(ReadError::file(
            path,
            format!("more than {MAX_ITEMS} sheets or placements"),
        ));
    }
    for (k, s) in file.sheets.iter().enumerate() {
        let name_ok = !s.file.is_empty()
            && !s.file.contains(['/', '\\'])
            && s.file != ".."
            && s.file.to_ascii_lowercase().ends_with(".dxf");
        if !name_ok {
            return Err(ReadError::record(
                path,
                format!("sheet {k}"),
                format!(
                    "file `{}` is not the name of a DXF beside nest.json",
                    s.file
                ),
            ));
        }
        if !s.size.iter().all(|v| v.is_finite() && *v > 0.0 && *v < 1e7) {
            return Err(ReadError::record(
                path,
                format!("sheet {k} ({})", s.file),
                "its size is not two positive numbers of mm",
            ));
        }
    }
    Ok((file.sheets, file.placements))
}
