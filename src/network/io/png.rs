//! PNG render of a network with tiny-skia: anti-aliased, stroke width from edge radius, fitted
//! so the longer side is `RenderOptions::size` pixels.

use std::collections::BTreeMap;
use std::path::Path;

use tiny_skia::{Color, LineCap, Paint, PathBuilder, Pixmap, Stroke, Transform};

use super::{Projection, RenderOptions};
use crate::files::{write_atomic, WriteError};
use crate::network::Network;

/// Renders need at least this many pixels on the longer side, and at most this many.
pub const SIZE_RANGE: (u32, u32) = (16, 16384);

pub fn write(net: &Network, path: &Path, opts: &RenderOptions) -> Result<(), WriteError> {
    let bytes = render_png_bytes(net, opts.size).map_err(|msg| WriteError::Content {
        path: path.to_path_buf(),
        msg,
    })?;
    write_atomic(path, |w| std::io::Write::write_all(w, &bytes))
}

/// The PNG bytes of a network render whose longer side is `size` pixels.
pub fn render_png_bytes(net: &Network, size: u32) -> Result<Vec<u8>, String> {
    if !(SIZE_RANGE.0..=SIZE_RANGE.1).contains(&size) {
        return Err(format!(
            "render size {size} px is outside {}..={} px",
            SIZE_RANGE.0, SIZE_RANGE.1
        ));
    }
    let proj = Projection::fit(net);
    let [w, h] = proj.extent();
    let margin_px = (size as f64 * 0.02).max(2.0);
    let scale = (size as f64 - 2.0 * margin_px) / w.max(h);
    let px = |mm: f64| (mm * scale + 2.0 * margin_px).round().max(1.0) as u32;
    let (pw, ph) = (px(w), px(h));
    let mut pixmap = Pixmap::new(pw, ph).ok_or("render size too small")?;
    pixmap.fill(Color::WHITE);
    let mut paint = Paint::default();
    paint.set_color_rgba8(0x1d, 0x3b, 0x2a, 0xff);
    paint.anti_alias = true;
    let to_px = |p: glam::DVec3| {
        let [x, y] = proj.page(p);
        (
            (x * scale + margin_px) as f32,
            (y * scale + margin_px) as f32,
        )
    };
    // One path per stroke width (in quarter pixels), so a large network draws in a few calls.
    let mut by_width: BTreeMap<u32, PathBuilder> = BTreeMap::new();
    // Edges to missing nodes cannot be drawn; writers refuse such networks before this.
    let n = net.nodes.len() as u32;
    for e in net.edges.iter().filter(|e| e.a < n && e.b < n) {
        let width = (2.0 * e.radius * scale).max(1.0);
        let key = (width * 4.0).round().min(u32::MAX as f64) as u32;
        let (x1, y1) = to_px(net.nodes[e.a as usize].p);
        let (x2, y2) = to_px(net.nodes[e.b as usize].p);
        let pb = by_width.entry(key).or_default();
        pb.move_to(x1, y1);
        pb.line_to(x2, y2);
    }
    let adj = net.adjacency();
    let mut dots = PathBuilder::new();
    for (i, n) in net.nodes.iter().enumerate() {
        if adj.degree(i as u32) == 0 {
            let (x, y) = to_px(n.p);
            dots.push_circle(x, y, (n.radius * scale).max(1.5) as f32);
        }
    }
    for (key, pb) in by_width {
        if let Some(path) = pb.finish() {
            let stroke = Stroke {
                width: key as f32 / 4.0,
                line_cap: LineCap::Round,
                ..Default::default()
            };
            pixmap.stroke_path(&path, &paint, &stroke, Transform::identity(), None);
        }
    }
    if let Some(path) = dots.finish() {
        pixmap.fill_path(
            &path,
            &paint,
            tiny_skia::FillRule::Winding,
            Transform::identity(),
            None,
        );
    }
    pixmap
        .encode_png()
        .map_err(|e| format!("PNG encoding failed: {e}"))
}
