//! The flat views: cut sheets as their DXFs draw them (parts, tags, inner and outer contours,
//! in cut order), and print layers from an SL1 archive with their islands.

use std::path::Path;

use glam::DVec2;

use super::pack::{mm, ViewError};
use super::{fig, png_url, Print, PrintIsland, Sheet, SheetPart, SheetPath};
use crate::fabricate::cutsheet::{read_cut_dxf, ReadPath, CUT_INNER, CUT_OUTER, ETCH, JOINT};
use crate::fabricate::nest_file::{read_nest, NestPlacement};
use crate::fabricate::slice::encode_grey;

/// How far a part's drawn outline may lie from where nest.json says its box starts, mm.
const MATCH_MM: f64 = 0.05;
/// The widest gap between two pieces of one micro-jointed outer contour, mm (a joint is well
/// under 1 mm wide; the next part's contour starts much farther away).
const PIECE_GAP_MM: f64 = 5.0;

/// The sheets of a nest file, each read from its cut DXF beside it; notes say what was not
/// shown.
pub fn sheets(nest: &Path) -> Result<(Vec<Sheet>, Vec<String>), ViewError> {
    let (sheets, placements) = read_nest(nest)?;
    let dir = nest.parent().unwrap_or(Path::new("."));
    let mut notes = Vec::new();
    let mut out = Vec::with_capacity(sheets.len());
    for s in &sheets {
        let file = dir.join(&s.file);
        let (paths, other) = read_cut_dxf(&file)?;
        if other > 0 {
            notes.push(format!(
                "{}: {other} entities other than polylines and lines not drawn",
                s.file
            ));
        }
        let here: Vec<&NestPlacement> = placements.iter().filter(|p| p.sheet == s.file).collect();
        let (paths, parts, unmatched) = parts_of(&paths, &here);
        if unmatched > 0 {
            notes.push(format!(
                "{}: {unmatched} outer contours match no placement of nest.json (drawn, not named)",
                s.file
            ));
        }
        out.push(Sheet {
            name: s.file.clone(),
            size: s.size,
            figures: vec![
                fig("thickness", mm(s.thickness)),
                fig("size", format!("{} × {} mm", s.size[0], s.size[1])),
                fig("parts", s.parts.len().to_string()),
                fig("utilisation", format!("{:.1} %", 100.0 * s.utilisation)),
                fig("cut length", format!("{:.0} mm", s.cut_mm)),
                fig("pierces", s.pierces.to_string()),
                fig("etched length", format!("{:.0} mm", s.etch_mm)),
            ],
            paths,
            parts,
        });
    }
    Ok((out, notes))
}

fn length(p: &[DVec2], closed: bool) -> f64 {
    let open: f64 = p.windows(2).map(|w| w[0].distance(w[1])).sum();
    match (closed, p.first(), p.last()) {
        (true, Some(a), Some(b)) => open + a.distance(*b),
        _ => open,
    }
}

/// Groups a cut file's paths into parts by the file's order (each part's etching and inner
/// contours, then its outer contour, as the cut runs), and names each part by the placement
/// whose box starts where its outer contour's does. Returns the paths, the parts and how many
/// outer contours matched no placement.
fn parts_of(
    paths: &[ReadPath],
    placements: &[&NestPlacement],
) -> (Vec<SheetPath>, Vec<SheetPart>, usize) {
    let mut owner: Vec<Option<u32>> = vec![None; paths.len()];
    let mut parts: Vec<SheetPart> = Vec::new();
    let mut used = vec![false; placements.len()];
    let mut unmatched = 0;
    let mut pending: Vec<usize> = Vec::new();
    let mut k = 0;
    while k < paths.len() {
        let layer = paths[k].layer.as_str();
        if layer != CUT_OUTER {
            if [ETCH, CUT_INNER, crate::fabricate::cutsheet::LEAD].contains(&layer) {
                pending.push(k);
            }
            k += 1;
            continue;
        }
        // The outer contour: one closed polyline, or open pieces in cutting order with the
        // joints between them, each piece starting a joint's width from where the last ended.
        let mut outer = vec![k];
        k += 1;
        if !paths[outer[0]].closed {
            let mut end = paths[outer[0]].points.last().copied();
            while k < paths.len() {
                let p = &paths[k];
                let continues = match p.layer.as_str() {
                    JOINT => true,
                    CUT_OUTER => {
                        !p.closed
                            && match (end, p.points.first()) {
                                (Some(e), Some(s)) => e.distance(*s) <= PIECE_GAP_MM,
                                _ => false,
                            }
                    }
                    _ => false,
                };
                if !continues {
                    break;
                }
                if p.layer == CUT_OUTER {
                    end = p.points.last().copied();
                }
                outer.push(k);
                k += 1;
            }
        }
        let pts: Vec<DVec2> = outer
            .iter()
            .filter(|&&i| paths[i].layer == CUT_OUTER)
            .flat_map(|&i| paths[i].points.iter().copied())
            .collect();
        let lo = pts.iter().fold(DVec2::INFINITY, |m, p| m.min(*p));
        let hi = pts.iter().fold(DVec2::NEG_INFINITY, |m, p| m.max(*p));
        let found = placements
            .iter()
            .enumerate()
            .position(|(i, p)| !used[i] && DVec2::from_array(p.bbox_min).distance(lo) <= MATCH_MM);
        let index = parts.len() as u32;
        let contours: Vec<usize> = pending.iter().chain(&outer).copied().collect();
        let cut: f64 = contours
            .iter()
            .filter(|&&i| [CUT_OUTER, CUT_INNER].contains(&paths[i].layer.as_str()))
            .map(|&i| length(&paths[i].points, paths[i].closed))
            .sum();
        let etch: f64 = contours
            .iter()
            .filter(|&&i| paths[i].layer == ETCH)
            .map(|&i| length(&paths[i].points, false))
            .sum();
        let holes = contours
            .iter()
            .filter(|&&i| paths[i].layer == CUT_INNER)
            .count();
        let (id, mut figures) = match found {
            Some(i) => {
                used[i] = true;
                let p = placements[i];
                (
                    p.id.clone(),
                    vec![
                        fig("rotation", format!("{}°", p.rotation_deg)),
                        fig("micro-joints", p.micro_joints.to_string()),
                    ],
                )
            }
            None => {
                unmatched += 1;
                (format!("part {}", index + 1), Vec::new())
            }
        };
        figures.splice(
            0..0,
            [
                fig("cut order", format!("{} on this sheet", index + 1)),
                fig("box", format!("{:.1} × {:.1} mm", hi.x - lo.x, hi.y - lo.y)),
                fig("cut length", format!("{cut:.1} mm")),
                fig("holes", holes.to_string()),
                fig("etched length", format!("{etch:.1} mm")),
            ],
        );
        for &i in &contours {
            owner[i] = Some(index);
        }
        let start = paths[outer[0]].points.first().copied().unwrap_or(lo);
        parts.push(SheetPart {
            id,
            bbox: [lo.x, lo.y, hi.x, hi.y],
            start: start.to_array(),
            order: index + 1,
            figures,
        });
        pending.clear();
    }
    let drawn = paths
        .iter()
        .zip(owner)
        .map(|(p, part)| SheetPath {
            layer: p.layer.clone(),
            closed: p.closed,
            points: p.points.iter().flat_map(|q| [q.x, q.y]).collect(),
            part,
        })
        .collect();
    (drawn, parts, unmatched)
}

/// The longest side of a layer image on the page, pixels: larger lit regions are shown in
/// blocks of display pixels (the largest grey of each block, so no thin vein vanishes).
pub const MAX_SIDE: usize = 800;

/// The most bytes of layer images one page takes (a few thousand layers of a large print).
pub const MAX_IMAGE_BYTES: usize = 256 << 20;

/// The lit part of one layer: its box on the display (columns and rows, end exclusive) and the
/// grey bytes inside it.
struct Lit {
    cols: [usize; 2],
    rows: [usize; 2],
    grey: Vec<u8>,
}

/// The layers of an SL1 archive as images of the region any layer lights, with the islands
/// `sl1 check` finds.
pub fn print(sl1: &Path) -> Result<Print, ViewError> {
    let mut lit: Vec<Option<Lit>> = Vec::new();
    let check = crate::fabricate::sl1::check_layers(sl1, &mut |k, img, width| {
        if lit.len() <= k {
            lit.resize_with(k + 1, || None);
        }
        lit[k] = lit_part(img, width);
    })?;
    let [px, py] = check.pixels.map(|v| v as usize);
    lit.resize_with(check.layers, || None);
    let (mut c0, mut c1, mut r0, mut r1) = (px, 0, py, 0);
    for l in lit.iter().flatten() {
        c0 = c0.min(l.cols[0]);
        c1 = c1.max(l.cols[1]);
        r0 = r0.min(l.rows[0]);
        r1 = r1.max(l.rows[1]);
    }
    if c0 >= c1 {
        (c0, c1, r0, r1) = (0, px, 0, py);
    }
    let block = (c1 - c0).max(r1 - r0).div_ceil(MAX_SIDE).max(1);
    let (w, h) = ((c1 - c0).div_ceil(block), (r1 - r0).div_ceil(block));
    let mut total = 0usize;
    let images: Vec<Option<String>> = lit
        .iter()
        .map(|l| {
            l.as_ref().map(|l| {
                let mut out = vec![0u8; w * h];
                let lw = l.cols[1] - l.cols[0];
                for (i, row) in l.grey.chunks(lw).enumerate() {
                    let y = (l.rows[0] + i - r0) / block;
                    for (j, &g) in row.iter().enumerate() {
                        let x = (l.cols[0] + j - c0) / block;
                        let o = &mut out[y * w + x];
                        *o = (*o).max(g);
                    }
                }
                let url = png_url(&encode_grey(&out, w as u32, h as u32));
                total += url.len();
                url
            })
        })
        .collect();
    if total > MAX_IMAGE_BYTES {
        return Err(ViewError::TooLarge {
            what: sl1.display().to_string(),
            count: total,
            limit: MAX_IMAGE_BYTES,
            unit: "bytes of layer images",
            hint: "view part of the print (its layers are each a PNG in the page)",
        });
    }
    let pmm = check.pixel_mm;
    let mut figures = vec![
        fig("layers", check.layers.to_string()),
        fig("layer height", format!("{} mm", check.layer_mm)),
        fig(
            "display",
            format!("{} × {} pixels of {:.4} mm", px, py, pmm),
        ),
        fig(
            "resin",
            format!(
                "{:.3} mL (usedMaterial {:.3} mL)",
                check.volume_ml, check.used_ml
            ),
        ),
        fig("islands", check.island_count.to_string()),
    ];
    if block > 1 {
        figures.push(fig(
            "shown",
            format!("{block} × {block} display pixels per image pixel (the brightest of each)"),
        ));
    }
    for p in &check.problems {
        figures.push(fig("problem", p.clone()));
    }
    Ok(Print {
        name: sl1
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        layer_mm: check.layer_mm,
        pixel_mm: pmm * block as f64,
        region: [
            c0 as f64 * pmm,
            (py - r1) as f64 * pmm,
            c1 as f64 * pmm,
            (py - r0) as f64 * pmm,
        ],
        width: w as u32,
        height: h as u32,
        images,
        islands: check
            .islands
            .iter()
            .map(|i| PrintIsland {
                layer: i.layer,
                x_mm: i.x_mm,
                y_mm: i.y_mm,
                area_mm2: i.area_mm2,
            })
            .collect(),
        more_islands: check.island_count - check.islands.len(),
        figures,
    })
}

/// The box of a layer's non-black pixels and the grey inside it, rows `width` long; None when
/// all is black.
fn lit_part(img: &[u8], width: usize) -> Option<Lit> {
    if width == 0 {
        return None;
    }
    let (mut c0, mut c1, mut r0, mut r1) = (width, 0, usize::MAX, 0);
    for (r, row) in img.chunks(width).enumerate() {
        let Some(first) = row.iter().position(|&g| g > 0) else {
            continue;
        };
        let last = row.iter().rposition(|&g| g > 0).unwrap_or(first);
        c0 = c0.min(first);
        c1 = c1.max(last + 1);
        r0 = r0.min(r);
        r1 = r + 1;
    }
    if r0 == usize::MAX {
        return None;
    }
    let mut grey = Vec::with_capacity((c1 - c0) * (r1 - r0));
    for row in img.chunks(width).take(r1).skip(r0) {
        grey.extend_from_slice(&row[c0..c1]);
    }
    Some(Lit {
        cols: [c0, c1],
        rows: [r0, r1],
        grey,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(layer: &str, closed: bool, pts: &[(f64, f64)]) -> ReadPath {
        ReadPath {
            layer: layer.into(),
            closed,
            points: pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect(),
        }
    }

    fn placement(id: &str, at: [f64; 2]) -> NestPlacement {
        NestPlacement {
            id: id.into(),
            sheet: "s.dxf".into(),
            bbox_min: at,
            rotation_deg: 90.0,
            micro_joints: 0,
        }
    }

    #[test]
    fn parts_follow_the_file_order_and_take_their_placement_by_box() {
        let square = |x: f64| [(x, 0.0), (x + 10.0, 0.0), (x + 10.0, 10.0), (x, 10.0)];
        let paths = vec![
            path("SHEET", true, &[(0.0, 0.0), (100.0, 0.0), (100.0, 50.0)]),
            path(ETCH, false, &[(2.0, 2.0), (4.0, 4.0)]),
            path(CUT_INNER, true, &[(5.0, 5.0), (6.0, 5.0), (6.0, 6.0)]),
            path(CUT_OUTER, true, &square(0.0)),
            // A part with micro-joints: two open pieces and the joint between them.
            path(CUT_OUTER, false, &square(20.0)[..3]),
            path(JOINT, false, &[(30.0, 10.0), (29.5, 10.0)]),
            path(CUT_OUTER, false, &[(29.5, 10.0), (20.0, 10.0), (20.0, 0.5)]),
            // The next part straight after, with no etching between: its own contour.
            path(
                CUT_OUTER,
                false,
                &[(40.0, 0.0), (50.0, 0.0), (50.0, 10.0), (40.0, 10.0)],
            ),
            path(CUT_OUTER, false, &[(40.0, 9.5), (40.0, 0.5)]),
        ];
        let (b, a) = (
            placement("1-002", [20.0, 0.0]),
            placement("1-001", [0.0, 0.0]),
        );
        let (drawn, parts, unmatched) = parts_of(&paths, &[&b, &a]);
        assert_eq!(parts.len(), 3);
        assert_eq!(unmatched, 1, "the third outline has no placement");
        let named: Vec<&str> = parts.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(named, ["1-001", "1-002", "part 3"]);
        assert_eq!(parts[0].bbox, [0.0, 0.0, 10.0, 10.0]);
        assert_eq!(parts.iter().map(|p| p.order).collect::<Vec<_>>(), [1, 2, 3]);
        let owner: Vec<Option<u32>> = drawn.iter().map(|p| p.part).collect();
        assert_eq!(
            owner,
            [
                None,
                Some(0),
                Some(0),
                Some(0),
                Some(1),
                Some(1),
                Some(1),
                Some(2),
                Some(2)
            ]
        );
        assert_eq!(parts[2].bbox, [40.0, 0.0, 50.0, 10.0]);
        let holes = parts[0].figures.iter().find(|f| f[0] == "holes");
        assert_eq!(holes.map(|f| f[1].as_str()), Some("1"));
    }

    #[test]
    fn a_lit_box_holds_every_lit_pixel_and_nothing_else() {
        let (w, h) = (6, 4);
        let mut img = vec![0u8; w * h];
        img[w + 2] = 200;
        img[2 * w + 4] = 10;
        let lit = lit_part(&img, w).expect("something is lit");
        assert_eq!((lit.cols, lit.rows), ([2, 5], [1, 3]));
        assert_eq!(lit.grey, vec![200, 0, 0, 0, 0, 10]);
        assert!(lit_part(&vec![0u8; w * h], w).is_none());
    }
}
