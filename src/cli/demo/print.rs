//! The print path in the demo: a leaf grown for printing, made solid (lamina, base, standing
//! up), sliced for the DMP-SL printer five at a time as Peele printed them, with print.json and
//! a strip of layer images.

use std::path::Path;

use anyhow::Result;

use super::{Entry, Headline};
use crate::cli::slice::write_job;
use crate::cli::venation::write_json;
use lamina::fabricate::slice::{arrange, layer_count, Model, Printer};
use lamina::fabricate::solid::{solid, Base, SolidOptions};
use lamina::files::write_atomic;
use lamina::grow::outline::{Outline, Shape};
use lamina::mesh::io::write_mesh;
use lamina::network::io::{write_network, RenderOptions};
use lamina::stage::slice::{layer_strip, slice_job, JobOptions, OnLayer, Source};
use lamina::stage::{venation, Quiet};

/// Leaves printed at once, as in Peele §4.2.
const COPIES: usize = 5;

/// lamina's slicing time as a share of PrusaSlicer's on a 50 mm leaf, as BENCHMARKS.md
/// measured it side by side (a test keeps the two the same).
pub const AGAINST_PRUSASLICER: &str = "0.16 and 0.17";

pub fn print_leaf(out: &Path, size: u32) -> Result<(Entry, Headline)> {
    let dir = out.join("print");
    std::fs::create_dir_all(&dir)?;
    // Sparser sources and thicker tips than the venation demo: veins a printer can make once
    // the leaf is 20 mm tall (tips 80 µm), and areoles wide enough to stay open.
    let opts = venation::Options {
        birth: Some(4.0),
        tip_radius: Some(0.4),
        ..Default::default()
    };
    let leaf = venation::run(&Outline::shape(Shape::Ovate), &opts, None, &Quiet)?.leaf;
    write_network(
        &leaf.network,
        &dir.join("leaf.json"),
        &RenderOptions { size },
    )?;

    let solid_opts = SolidOptions {
        cell: 0.05,
        lamina: Some(0.3),
        base: Some(Base {
            diameter: 4.0,
            height: 1.5,
        }),
        fit: Some(20.0),
        upright: true,
        radius: None,
        tolerance: None,
    };
    let made = solid(&leaf.network, &solid_opts, &Quiet)?;
    write_mesh(&made.mesh, &dir.join("leaf.stl"), size)?;
    write_mesh(&made.mesh, &dir.join("leaf.png"), size)?;
    write_json(
        &dir.join("solid.json"),
        &serde_json::to_value(&made.report)?,
    )?;

    let printer = Printer::default();
    // Named from the report's folder (leaf.stl and leaf.sl1 sit beside print.json).
    let models = [Model {
        path: "leaf.stl".into(),
        mesh: made.mesh,
    }];
    let placed = arrange(&models, &printer, COPIES, 2.0, false)?;
    let layers = layer_count(&models, &printer);
    let keep: Vec<usize> = (1..=6).map(|k| k * layers / 7).collect();
    let job = JobOptions {
        printer: printer.clone(),
        copies: COPIES,
        material: "MakerJuice G+".into(),
        name: "leaf".into(),
        ..Default::default()
    };
    let mut kept = Vec::new();
    let output = dir.join("leaf.sl1");
    let sliced = write_job(
        &output,
        Some(&dir.join("layers")),
        "leaf",
        |archive, mut on_layer| {
            let mut each = |index: usize, png: &[u8], image: &[u8]| {
                if keep.contains(&index) {
                    kept.push((index, image.to_vec()));
                }
                match on_layer {
                    Some(ref mut f) => f(index, png, image),
                    None => Ok(()),
                }
            };
            let each: OnLayer = &mut each;
            slice_job(
                Source::Meshes(&models),
                &placed,
                &job,
                archive,
                Some(each),
                &Quiet,
            )
        },
    )?;
    let mut report = sliced.report;
    report.archive = "leaf.sl1".into();
    let e = sliced.estimate;
    write_json(&dir.join("print.json"), &report)?;

    // The strip: each kept layer cropped to the first leaf's footprint, side by side.
    let images: Vec<&[u8]> = kept.iter().map(|(_, image)| image.as_slice()).collect();
    let strip_png = layer_strip(&printer, placed[0].min, placed[0].max, &images, 8, 6);
    write_atomic(&dir.join("layers-strip.png"), |w| {
        std::io::Write::write_all(w, &strip_png)
    })?;

    let r = &made.report;
    let layer_names: Vec<String> = kept.iter().map(|(i, _)| i.to_string()).collect();
    let job = Headline {
        job: "Print: leaves in resin".into(),
        what: format!(
            "A leaf grown for printing, made a watertight solid standing on a base, and sliced \
             {COPIES} at a time for the DMP-SL printer: an SL1 archive PrusaSlicer's printers read."
        ),
        figures: vec![
            ("layers".into(), format!("{} of 50 µm", e.layers)),
            (
                "resin".into(),
                format!(
                    "{:.3} mL for {COPIES} leaves, {:.2} h",
                    e.volume_ml, e.build_time_h
                ),
            ),
            (
                "solid".into(),
                format!(
                    "{:.2} M triangles, {} part(s), genus {}, watertight",
                    made.report.triangles as f64 / 1e6,
                    made.report.parts,
                    made.report.genus
                ),
            ),
            (
                "islands (no supports)".into(),
                if report.island_count == 0 {
                    "none: every region rests on the one below".to_string()
                } else {
                    format!(
                        "{}: they start in free resin; `lamina print --supports` holds them",
                        report.island_count
                    )
                },
            ),
            (
                "slicing time".into(),
                format!("{AGAINST_PRUSASLICER} of PrusaSlicer's (50 mm leaf, BENCHMARKS.md)"),
            ),
        ],
        preview: "print/leaf.png".into(),
        links: vec![
            ("layer viewer".into(), "view/print-layers.html".into()),
            ("print.json".into(), "print/print.json".into()),
            ("archive".into(), "print/leaf.sl1".into()),
        ],
    };
    let entry = Entry {
        name: "print: leaf → solid → slices".into(),
        about: format!(
            "A closed leaf grown for printing (`lamina venation --birth 4 --tip-radius 0.4`), made \
             solid by `lamina solid --fit 20 --lamina 0.3 --base cylinder:4,1.5 --upright --cell \
             0.05` and sliced {COPIES} at a time by `lamina slice --copies {COPIES}` for the \
             DMP-SL printer (1920 × 1080 pixels of 35 µm, 50 µm layers). Layers {} of {}:<br>\
             <img src=\"print/layers-strip.png\" alt=\"layer images\" style=\"width:100%;max-height:none\">",
            layer_names.join(", "),
            e.layers
        ),
        outputs: [
            "leaf.json",
            "leaf.stl",
            "solid.json",
            "leaf.sl1",
            "print.json",
            "layers-strip.png",
            "layers/",
        ]
        .iter()
        .map(|f| format!("print/{f}"))
        .collect(),
        preview: "print/leaf.png".into(),
        facts: format!(
            "solid: {} triangles, closed 2-manifold, {} part(s), genus {}, {:.1} mm³, \
             {:.1} × {:.1} × {:.1} mm; print: {} layers, {:.3} mL of resin for {COPIES} \
             leaves, cost {:.3} at 55/L, {:.1} g, {:.2} h ({}); {}",
            r.triangles,
            r.parts,
            r.genus,
            r.volume_mm3,
            r.bbox_max[0] - r.bbox_min[0],
            r.bbox_max[1] - r.bbox_min[1],
            r.bbox_max[2] - r.bbox_min[2],
            e.layers,
            e.volume_ml,
            e.resin_cost,
            e.mass_g,
            e.build_time_h,
            e.build_time_from,
            match report.islands.first() {
                None => "no islands".to_string(),
                Some(i) => format!(
                    "{} islands (regions that start in free resin; supports would hold them), the first at layer {}",
                    report.island_count, i.layer
                ),
            }
        ),
    };
    Ok((entry, job))
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_figure_against_prusaslicer_is_the_benchmarks() {
        let benchmarks = include_str!("../../../BENCHMARKS.md");
        assert!(
            benchmarks.contains(&format!("**{}**", super::AGAINST_PRUSASLICER)),
            "BENCHMARKS.md no longer says {}",
            super::AGAINST_PRUSASLICER
        );
    }
}
