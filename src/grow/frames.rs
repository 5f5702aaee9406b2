//! PNG frames of a growth, for animations: the blade of the moment, the live sources, and the
//! veins with Murray widths of the tree so far. Every frame shares one view (the full blade
//! and a margin), so frames line up when played in order.

use glam::DVec2;
use tiny_skia::{Color, FillRule, LineCap, Paint, PathBuilder, Pixmap, Stroke, Transform};

use super::venation::Frame;

/// The colour of live sources in frames.
pub const SOURCE: [u8; 3] = [0x3b, 0x7d, 0xd8];

/// The fixed view of an animation: the box `lo`..`hi` in mm, `size` pixels on its longer side.
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub lo: DVec2,
    pub hi: DVec2,
    pub size: u32,
}

impl View {
    fn scale(&self) -> f64 {
        let e = (self.hi - self.lo).max_element().max(f64::MIN_POSITIVE);
        (self.size as f64 * 0.96) / e
    }

    fn pixels(&self) -> (u32, u32) {
        let s = self.scale();
        let d = (self.hi - self.lo) * s;
        let m = self.size as f64 * 0.04;
        (
            (d.x + m).ceil().max(1.0) as u32,
            (d.y + m).ceil().max(1.0) as u32,
        )
    }

    fn px(&self, p: DVec2) -> (f32, f32) {
        let s = self.scale();
        let m = self.size as f64 * 0.02;
        (
            ((p.x - self.lo.x) * s + m) as f32,
            ((self.hi.y - p.y) * s + m) as f32,
        )
    }
}

/// The PNG bytes of one frame.
pub fn render_frame(
    frame: &Frame,
    view: &View,
    murray: f64,
    tip_radius: f64,
) -> Result<Vec<u8>, String> {
    let (w, h) = view.pixels();
    let mut pm = Pixmap::new(w, h).ok_or("frame size out of range")?;
    pm.fill(Color::WHITE);
    let mut paint = Paint {
        anti_alias: true,
        ..Default::default()
    };
    // Blade.
    let mut pb = PathBuilder::new();
    for (i, p) in frame.blade.iter().flat_map(|b| b.points()).enumerate() {
        let (x, y) = view.px(*p);
        if i == 0 {
            pb.move_to(x, y);
        } else {
            pb.line_to(x, y);
        }
    }
    pb.close();
    if let Some(path) = pb.finish() {
        paint.set_color_rgba8(0xe8, 0xf2, 0xdc, 0xff);
        pm.fill_path(
            &path,
            &paint,
            FillRule::Winding,
            Transform::identity(),
            None,
        );
        paint.set_color_rgba8(0x7a, 0x9a, 0x6a, 0xff);
        let stroke = Stroke {
            width: 1.5,
            ..Default::default()
        };
        pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
    }
    // Sources.
    let dot = (view.size as f32 / 600.0).max(1.0);
    let mut pb = PathBuilder::new();
    for s in frame.sources {
        let (x, y) = view.px(*s);
        pb.push_circle(x, y, dot);
    }
    if let Some(path) = pb.finish() {
        let [r, g, b] = SOURCE;
        paint.set_color_rgba8(r, g, b, 0xff);
        pm.fill_path(
            &path,
            &paint,
            FillRule::Winding,
            Transform::identity(),
            None,
        );
    }
    // Veins, widest last so they stay on top.
    let radius = super::murray::radii(frame.parent, murray, tip_radius);
    let scale = view.scale();
    let mut edges: Vec<(f64, DVec2, DVec2)> = frame
        .parent
        .iter()
        .enumerate()
        .filter_map(|(c, p)| {
            p.map(|p| (radius[c], frame.positions[p as usize], frame.positions[c]))
        })
        .chain(frame.joins.iter().map(|&[a, b]| {
            (
                tip_radius,
                frame.positions[a as usize],
                frame.positions[b as usize],
            )
        }))
        .collect();
    edges.sort_by(|a, b| a.0.total_cmp(&b.0));
    paint.set_color_rgba8(0x1d, 0x3b, 0x2a, 0xff);
    for chunk in edges.chunk_by(|a, b| (a.0 * scale * 4.0).round() == (b.0 * scale * 4.0).round()) {
        let mut pb = PathBuilder::new();
        for (_, a, b) in chunk {
            let (x1, y1) = view.px(*a);
            let (x2, y2) = view.px(*b);
            pb.move_to(x1, y1);
            pb.line_to(x2, y2);
        }
        if let Some(path) = pb.finish() {
            let stroke = Stroke {
                width: ((2.0 * chunk[0].0 * scale) as f32).max(1.0),
                line_cap: LineCap::Round,
                ..Default::default()
            };
            pm.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
    pm.encode_png().map_err(|e| e.to_string())
}

/// A growth frame on a surface as strokes: live sources first (dots), then the veins over them
/// (Murray widths of the tree of that moment, loop edges at the tip radius).
pub fn surface_strokes(
    f: &Frame<glam::DVec3>,
    exponent: f64,
    tip: f64,
) -> Vec<crate::mesh::io::Stroke3> {
    use crate::mesh::io::{Stroke3, VEIN};
    let radius = super::murray::radii(f.parent, exponent, tip);
    let dots = f.sources.iter().map(|&s| Stroke3 {
        a: s,
        b: s,
        radius: tip,
        color: SOURCE,
    });
    let tree = f.parent.iter().enumerate().filter_map(|(c, p)| {
        p.map(|p| Stroke3 {
            a: f.positions[p as usize],
            b: f.positions[c],
            radius: radius[c],
            color: VEIN,
        })
    });
    let joins = f.joins.iter().map(|&[a, b]| Stroke3 {
        a: f.positions[a as usize],
        b: f.positions[b as usize],
        radius: tip,
        color: VEIN,
    });
    dots.chain(tree).chain(joins).collect()
}

/// PNG images side by side on one row, top aligned, on the renders' background.
pub fn strip(pngs: &[Vec<u8>]) -> Result<Vec<u8>, String> {
    use tiny_skia::PixmapPaint;
    let images = pngs
        .iter()
        .map(|p| {
            Pixmap::decode_png(p).map_err(|e| {
                format!(
                    "a frame that does not decode: {}",
                    crate::files::png_message(&e)
                )
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let width = images.iter().map(Pixmap::width).sum::<u32>();
    let height = images.iter().map(Pixmap::height).max().unwrap_or(0);
    let mut row = Pixmap::new(width, height).ok_or("a strip of no pixels")?;
    let [r, g, b] = crate::mesh::io::BACKGROUND;
    row.fill(Color::from_rgba8(r, g, b, 0xff));
    let mut x = 0;
    for image in &images {
        row.draw_pixmap(
            x as i32,
            0,
            image.as_ref(),
            &PixmapPaint::default(),
            Transform::identity(),
            None,
        );
        x += image.width();
    }
    row.encode_png()
        .map_err(|e| format!("encoding the strip: {e}"))
}
