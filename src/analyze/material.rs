//! Steels for sizing: elastic constants, strengths and the partial factors of the Eurocodes.
//! Built in: `s235`, `s355` (EN 10025-2, t ≤ 40 mm; EN 1993-1-1 Table 3.1, EN 1993-1-8
//! Table 4.1) and `1.4404` (stainless 316L, cold-rolled strip; EN 1993-1-4 Table 2.1 and
//! §2.1.3, β_w = 1 by §6.3). Or a JSON file with the same fields:
//!
//! ```json
//! {"name": "S275", "E": 210000, "nu": 0.3, "fy": 275, "fu": 430, "density": 7.85,
//!  "gamma_M0": 1.0, "gamma_M1": 1.0, "gamma_M2": 1.25, "beta_w": 0.85}
//! ```
//!
//! E, fy, fu in MPa, density in g/cm³ (EN 1993-1-1 §3.2.6: 7.85 for carbon steels; EN 10088-1:
//! 8.0 for 1.4404). A name of the EN stainless series (1.40xx to 1.46xx) is stainless: its plates
//! are cut with the stainless speed table.

use std::path::Path;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A steel's figures (fields in the order sizing.json writes them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    #[serde(rename = "E")]
    pub e: f64,
    pub beta_w: f64,
    pub density: f64,
    pub fu: f64,
    pub fy: f64,
    #[serde(rename = "gamma_M0")]
    pub gamma_m0: f64,
    #[serde(rename = "gamma_M1")]
    pub gamma_m1: f64,
    #[serde(rename = "gamma_M2")]
    pub gamma_m2: f64,
    pub name: String,
    pub nu: f64,
}

/// Whether a grade's name is one of EN 10088's stainless steels (1.40xx to 1.46xx).
pub fn is_stainless(grade: &str) -> bool {
    let g = grade.trim();
    ["1.40", "1.41", "1.42", "1.43", "1.44", "1.45", "1.46"]
        .iter()
        .any(|p| g.starts_with(p))
}

#[derive(Debug, Error)]
pub enum MaterialError {
    #[error("unknown material `{0}`: give s235, s355, 1.4404 or a JSON file")]
    Unknown(String),
    #[error("{path}: {message}")]
    File { path: String, message: String },
}

impl Material {
    /// Whether the grade is a stainless steel (an EN number 1.40xx to 1.46xx).
    pub fn is_stainless(&self) -> bool {
        is_stainless(&self.name)
    }

    pub fn shear_modulus(&self) -> f64 {
        self.e / (2.0 * (1.0 + self.nu))
    }

    /// By name, or from a JSON file when `spec` names one.
    pub fn get(spec: &str) -> Result<Material, MaterialError> {
        let steel = |name: &str, fy: f64, fu: f64, beta_w: f64| Material {
            name: name.into(),
            e: 210_000.0,
            nu: 0.3,
            fy,
            fu,
            density: 7.85,
            gamma_m0: 1.0,
            gamma_m1: 1.0,
            gamma_m2: 1.25,
            beta_w,
        };
        match spec.trim().to_ascii_lowercase().as_str() {
            "s235" => Ok(steel("S235", 235.0, 360.0, 0.8)),
            "s355" => Ok(steel("S355", 355.0, 490.0, 0.9)),
            "1.4404" | "316l" => Ok(Material {
                name: "1.4404".into(),
                e: 200_000.0,
                nu: 0.3,
                fy: 240.0,
                fu: 530.0,
                density: 8.0,
                gamma_m0: 1.1,
                gamma_m1: 1.1,
                gamma_m2: 1.25,
                beta_w: 1.0,
            }),
            _ if Path::new(spec).is_file() => Material::read(Path::new(spec)),
            _ => Err(MaterialError::Unknown(spec.into())),
        }
    }

    fn read(path: &Path) -> Result<Material, MaterialError> {
        let err = |message: String| MaterialError::File {
            path: path.display().to_string(),
            message,
        };
        let meta = std::fs::metadata(path).map_err(|e| err(e.to_string()))?;
        if meta.len() > 1 << 20 {
            return Err(err("larger than 1 MiB: not a material file".into()));
        }
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        let m: Material = serde_json::from_str(&text).map_err(|e| err(e.to_string()))?;
        let checks = [
            ("E", m.e, 1e3, 1e7),
            ("nu", m.nu, 0.0, 0.499),
            ("fy", m.fy, 1.0, 1e4),
            ("fu", m.fu, 1.0, 1e4),
            ("density", m.density, 0.1, 30.0),
            ("gamma_M0", m.gamma_m0, 0.5, 5.0),
            ("gamma_M1", m.gamma_m1, 0.5, 5.0),
            ("gamma_M2", m.gamma_m2, 0.5, 5.0),
            ("beta_w", m.beta_w, 0.1, 5.0),
        ];
        for (name, v, lo, hi) in checks {
            if !(v >= lo && v <= hi) {
                return Err(err(format!(
                    "{name} must be from {lo} to {hi}, got {}",
                    crate::text::num(v)
                )));
            }
        }
        if m.fu < m.fy {
            return Err(err(format!("fu ({}) is below fy ({})", m.fu, m.fy)));
        }
        Ok(m)
    }
}
