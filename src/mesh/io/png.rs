//! PNG render of a mesh: orthographic view from the front-right and above, flat Lambert shading
//! (two-sided, so open surfaces read from either side), painter's order. Vertex colours, when
//! present, tint the faces. Fitted so the longer side is `size` pixels.

use std::path::Path;

use glam::DVec3;
use tiny_skia::{FillRule, Paint, PathBuilder, Pixmap, Transform};

use crate::files::{write_atomic, WriteError};
use crate::mesh::TriMesh;

pub fn write(mesh: &TriMesh, path: &Path, size: u32) -> Result<(), WriteError> {
    let bytes = render_png_bytes(mesh, size).map_err(|msg| WriteError::Content {
        path: path.to_path_buf(),
        msg,
    })?;
    write_atomic(path, |w| std::io::Write::write_all(w, &bytes))
}

/// The PNG bytes of a shaded render whose longer side is `size` pixels (16..=16384).
pub fn render_png_bytes(mesh: &TriMesh, size: u32) -> Result<Vec<u8>, String> {
    if !(16..=16384).contains(&size) {
        return Err(format!("render size {size} px is outside 16..=16384 px"));
    }
    let eye = DVec3::new(0.55, -0.8, 0.45).normalize();
    let right = DVec3::Z.cross(eye).normalize();
    let up = eye.cross(right);
    let light = (eye + DVec3::new(-0.3, 0.0, 0.5)).normalize();
    let screen = |p: DVec3| (p.dot(right), -p.dot(up));
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for p in &mesh.positions {
        let (x, y) = screen(*p);
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    let (w, h) = ((hi.0 - lo.0).max(1e-9), (hi.1 - lo.1).max(1e-9));
    let margin = (size as f64 * 0.03).max(2.0);
    let scale = (size as f64 - 2.0 * margin) / w.max(h);
    let pw = (w * scale + 2.0 * margin).round().max(1.0) as u32;
    let ph = (h * scale + 2.0 * margin).round().max(1.0) as u32;
    let mut pixmap = Pixmap::new(pw, ph).ok_or("render size too small")?;
    pixmap.fill(tiny_skia::Color::from_rgba8(0xf4, 0xf2, 0xee, 0xff));
    let to_px = |p: DVec3| {
        let (x, y) = screen(p);
        (((x - lo.0) * scale + margin) as f32, ((y - lo.1) * scale + margin) as f32)
    };
    let mut order: Vec<(f64, usize)> = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let [a, b, c] = mesh.corners(t);
            ((a + b + c).dot(eye), i)
        })
        .collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut paint = Paint {
        anti_alias: false,
        ..Default::default()
    };
    for (_, i) in order {
        let t = &mesh.triangles[i];
        let [a, b, c] = mesh.corners(t);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let shade = 0.3 + 0.7 * n.dot(light).abs();
        let base = match &mesh.colors {
            Some(cols) => {
                let s = t.map(|k| cols[k as usize]);
                [0, 1, 2].map(|ch| (s[0][ch] + s[1][ch] + s[2][ch]) as f64 / 3.0)
            }
            None => [0.80, 0.76, 0.70],
        };
        let rgb = base.map(|v| (v * shade * 255.0).round().clamp(0.0, 255.0) as u8);
        paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 0xff);
        let mut pb = PathBuilder::new();
        let (p0, p1, p2) = (to_px(a), to_px(b), to_px(c));
        pb.move_to(p0.0, p0.1);
        pb.line_to(p1.0, p1.1);
        pb.line_to(p2.0, p2.1);
        pb.close();
        if let Some(path) = pb.finish() {
            pixmap.fill_path(&path, &paint, FillRule::Winding, Transform::identity(), None);
        }
    }
    pixmap.encode_png().map_err(|e| format!("PNG encoding failed: {e}"))
}
