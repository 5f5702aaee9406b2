//! What a print costs: resin volume (from the layer images: Σ area × layer height), its price
//! and mass, and the build time (from the printer's exposure and peel model, or from a build
//! speed in mm/h as Peele quotes it).

use crate::fabricate::slice::Printer;

/// Material and pricing.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Resin {
    /// Price per litre (currency of the user's choosing).
    pub cost_per_litre: f64,
    /// g/mL.
    pub density: f64,
}

impl Default for Resin {
    /// MakerJuice G+ as Peele bought it: 55 per litre; 1.1 g/mL is typical of such resins.
    fn default() -> Self {
        Resin {
            cost_per_litre: 55.0,
            density: 1.1,
        }
    }
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    pub layers: usize,
    pub height_mm: f64,
    /// From the images: Σ (grey / 255 × pixel area) × layer height.
    pub volume_ml: f64,
    pub resin_cost: f64,
    pub mass_g: f64,
    pub build_time_h: f64,
    /// "exposure and peel model" or "N mm/h".
    pub build_time_from: String,
    /// The exposure and peel model's figure, whichever is reported above.
    pub model_time_h: f64,
}

/// `areas_mm2` are the layers' areas as their images show them.
pub fn estimate(
    printer: &Printer,
    resin: &Resin,
    areas_mm2: &[f64],
    speed_mm_h: Option<f64>,
) -> Estimate {
    let layers = areas_mm2.len();
    let height_mm = layers as f64 * printer.layer_mm;
    let volume_ml = areas_mm2.iter().sum::<f64>() * printer.layer_mm / 1000.0;
    let model_time_h = printer.build_seconds(layers) / 3600.0;
    let (build_time_h, build_time_from) = match speed_mm_h {
        Some(v) => (height_mm / v, format!("{v} mm/h")),
        None => (model_time_h, "exposure and peel model".to_string()),
    };
    Estimate {
        layers,
        height_mm,
        volume_ml,
        resin_cost: volume_ml / 1000.0 * resin.cost_per_litre,
        mass_g: volume_ml * resin.density,
        build_time_h,
        build_time_from,
        model_time_h,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peele_figures() {
        let printer = Printer::default();
        // 1 mL: 1000 layers of 50 µm, each 20 mm².
        let areas = vec![20.0; 1000];
        let e = estimate(&printer, &Resin::default(), &areas, Some(25.0));
        assert!((e.volume_ml - 1.0).abs() < 1e-12);
        assert!((e.resin_cost - 0.055).abs() < 1e-12);
        assert!((e.height_mm - 50.0).abs() < 1e-9);
        assert!((e.build_time_h - 2.0).abs() < 1e-12);
        assert!((e.mass_g - 1.1).abs() < 1e-12);
        // The built-in printer's motion gives his 25 mm/h, less the longer first layers.
        let model = estimate(&printer, &Resin::default(), &areas, None);
        let bottom_extra = 3.0 * (20.0 - 3.0) / 3600.0;
        assert!(
            (model.build_time_h - (2.0 + bottom_extra)).abs() < 1e-9,
            "{}",
            model.build_time_h
        );
    }
}
