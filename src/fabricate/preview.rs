//! A picture of nested sheets: every sheet to scale, stacked, each part filled in its assembly
//! group's colour and labelled with its tag. SVG, for the shop and for report pages.

use crate::text::html;
use std::fmt::Write as _;

use glam::DVec2;

/// One sheet as drawn.
pub struct SheetView<'a> {
    pub title: String,
    /// Width and height, mm.
    pub size: DVec2,
    /// Free rectangles kept (lower-left, upper-right), drawn hatched.
    pub remnants: Vec<[DVec2; 2]>,
    /// Outline in sheet coordinates (mm), tag, assembly group (from 1).
    pub parts: Vec<(&'a [DVec2], &'a str, u32)>,
}

const PALETTE: [&str; 10] = [
    "#4e79a7", "#f28e2b", "#59a14f", "#e15759", "#76b7b2", "#edc948", "#b07aa1", "#ff9da7",
    "#9c755f", "#bab0ac",
];

/// The sheets, the widest `width` pixels wide, one below the other, to one scale.
pub fn sheets_svg(sheets: &[SheetView], width: f64) -> String {
    let widest = sheets.iter().map(|s| s.size.x).fold(1.0, f64::max);
    let scale = width / widest;
    let title_h = 28.0;
    let gap = 16.0;
    let height: f64 = sheets
        .iter()
        .map(|s| title_h + s.size.y * scale + gap)
        .sum();
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.1} {height:.1}" font-family="sans-serif">"#
    );
    let mut top = 0.0;
    for sh in sheets {
        let sheet = sh.size;
        // Sheet y points up; the picture's y points down.
        let map = |p: DVec2| DVec2::new(p.x * scale, top + title_h + (sheet.y - p.y) * scale);
        let _ = writeln!(
            s,
            r#"<text x="2" y="{:.1}" font-size="16">{}</text>"#,
            top + 19.0,
            html(&sh.title)
        );
        let _ = writeln!(
            s,
            r##"<rect x="0" y="{:.1}" width="{:.1}" height="{:.1}" fill="#f4f4f2" stroke="#555" stroke-width="1"/>"##,
            top + title_h,
            sheet.x * scale,
            sheet.y * scale
        );
        for [lo, hi] in &sh.remnants {
            let (a, b) = (map(DVec2::new(lo.x, hi.y)), map(DVec2::new(hi.x, lo.y)));
            let _ = writeln!(
                s,
                r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#888" stroke-dasharray="6 4"><title>remnant {:.0} × {:.0} mm</title></rect>"##,
                a.x,
                a.y,
                b.x - a.x,
                b.y - a.y,
                hi.x - lo.x,
                hi.y - lo.y
            );
        }
        for (outline, id, group) in &sh.parts {
            let pts: Vec<String> = outline
                .iter()
                .map(|p| {
                    let q = map(*p);
                    format!("{:.1},{:.1}", q.x, q.y)
                })
                .collect();
            let colour = PALETTE[(*group as usize).saturating_sub(1) % PALETTE.len()];
            let _ = writeln!(
                s,
                r##"<polygon points="{}" fill="{colour}" fill-opacity="0.55" stroke="#222" stroke-width="0.6"><title>{}</title></polygon>"##,
                pts.join(" "),
                html(id)
            );
            let lo = outline.iter().fold(DVec2::INFINITY, |m, p| m.min(*p));
            let hi = outline.iter().fold(DVec2::NEG_INFINITY, |m, p| m.max(*p));
            let centre = map(outline.iter().copied().sum::<DVec2>() / outline.len() as f64);
            let size = ((hi - lo).min_element() * scale * 0.3)
                .min((hi - lo).max_element() * scale / (id.len() as f64 * 0.7));
            if size >= 4.0 {
                let _ = writeln!(
                    s,
                    r#"<text x="{:.1}" y="{:.1}" font-size="{size:.1}" text-anchor="middle" dominant-baseline="middle">{}</text>"#,
                    centre.x,
                    centre.y,
                    html(id)
                );
            }
        }
        top += title_h + sheet.y * scale + gap;
    }
    s.push_str("</svg>\n");
    s
}
