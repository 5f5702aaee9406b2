//! PNG render of a mesh: orthographic view from the front-right and above, flat Lambert shading
//! (two-sided, so open surfaces read from either side), a depth buffer at twice the resolution,
//! box-filtered down for smooth edges. Vertex colours, when present, tint the faces. Fitted so
//! the longer side is `size` pixels.

use std::path::Path;

use glam::{DVec2, DVec3};
use tiny_skia::{IntSize, Pixmap};

use crate::files::{write_atomic, WriteError};
use crate::mesh::TriMesh;

const SUPERSAMPLE: usize = 2;
/// The background of renders.
pub const BACKGROUND: [u8; 3] = [0xf4, 0xf2, 0xee];
/// The colour of veins drawn on a render.
pub const VEIN: [u8; 3] = [0x1d, 0x3b, 0x2a];

pub fn write(mesh: &TriMesh, path: &Path, size: u32) -> Result<(), WriteError> {
    let bytes = render_png_bytes(mesh, size).map_err(|msg| WriteError::Content {
        path: path.to_path_buf(),
        msg,
    })?;
    write_atomic(path, |w| std::io::Write::write_all(w, &bytes))
}

/// A stroke drawn over a mesh render: a segment in space, its radius in mm and its colour (a
/// dot where the ends coincide).
#[derive(Clone, Copy, Debug)]
pub struct Stroke3 {
    pub a: DVec3,
    pub b: DVec3,
    pub radius: f64,
    pub color: [u8; 3],
}

/// The PNG bytes of a shaded render whose longer side is `size` pixels (16..=8192).
pub fn render_png_bytes(mesh: &TriMesh, size: u32) -> Result<Vec<u8>, String> {
    render_png_bytes_with(mesh, &[], size)
}

/// Renders are 16 to 8192 pixels on their longer side.
pub fn check_render_size(size: u32) -> Result<(), String> {
    if (16..=8192).contains(&size) {
        Ok(())
    } else {
        Err(format!("render size {size} px is outside 16..=8192 px"))
    }
}

/// A shaded render with strokes on it (veins on their surface). A stroke is hidden where the
/// surface lies in front of it by more than 1 % of the model's size, so veins on the far side
/// of a closed surface do not show through; vertex colours are lightened so veins show on dark
/// regions.
pub fn render_png_bytes_with(
    mesh: &TriMesh,
    strokes: &[Stroke3],
    size: u32,
) -> Result<Vec<u8>, String> {
    check_render_size(size)?;
    let eye = DVec3::new(0.55, -0.8, 0.45).normalize();
    let right = DVec3::Z.cross(eye).normalize();
    let up = eye.cross(right);
    let light = (eye + DVec3::new(-0.3, 0.0, 0.5)).normalize();
    let screen = |p: DVec3| DVec2::new(p.dot(right), -p.dot(up));
    let (mut lo, mut hi) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
    for p in &mesh.positions {
        lo = lo.min(screen(*p));
        hi = hi.max(screen(*p));
    }
    let ext = (hi - lo).max(DVec2::splat(1e-9));
    let margin = (size as f64 * 0.03).max(2.0);
    let scale = (size as f64 - 2.0 * margin) / ext.max_element();
    let (w, h) = (
        (ext.x * scale + 2.0 * margin).round().max(1.0) as usize,
        (ext.y * scale + 2.0 * margin).round().max(1.0) as usize,
    );
    let ss = SUPERSAMPLE;
    let (sw, sh) = (w * ss, h * ss);
    let mut depth = vec![f64::NEG_INFINITY; sw * sh];
    let mut color = vec![BACKGROUND; sw * sh];
    let to_px = |p: DVec3| ((screen(p) - lo) * scale + DVec2::splat(margin)) * ss as f64;
    for t in &mesh.triangles {
        let corners = mesh.corners(t);
        let n = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize_or_zero();
        let shade = 0.3 + 0.7 * n.dot(light).abs();
        let base = match &mesh.colors {
            Some(cols) => {
                let s = t.map(|k| cols[k as usize]);
                // Under strokes, colours are lightened so dark regions still show the veins.
                let lift = if strokes.is_empty() { 0.0 } else { 0.45 };
                [0, 1, 2]
                    .map(|ch| lift + (1.0 - lift) * (s[0][ch] + s[1][ch] + s[2][ch]) as f64 / 3.0)
            }
            None => [0.80, 0.76, 0.70],
        };
        let rgb = base.map(|v| (v * shade * 255.0).round().clamp(0.0, 255.0) as u8);
        let px = corners.map(to_px);
        let z = corners.map(|p| p.dot(eye));
        fill_triangle(&px, &z, sw, sh, |i, d| {
            if d > depth[i] {
                depth[i] = d;
                color[i] = rgb;
            }
        });
    }
    let bias = 0.01 * ext.max_element();
    for s in strokes {
        let (pa, pb) = (to_px(s.a), to_px(s.b));
        let (za, zb) = (s.a.dot(eye), s.b.dot(eye));
        let half = (s.radius * scale * ss as f64).max(0.6 * ss as f64);
        fill_capsule(pa, pb, half, sw, sh, |i, t| {
            let d = za + (zb - za) * t;
            if d + bias >= depth[i] {
                color[i] = s.color;
            }
        });
    }
    let mut rgba = Vec::with_capacity(w * h * 4);
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0u32; 3];
            for dy in 0..ss {
                for dx in 0..ss {
                    let c = color[(y * ss + dy) * sw + x * ss + dx];
                    for ch in 0..3 {
                        sum[ch] += c[ch] as u32;
                    }
                }
            }
            let n = (ss * ss) as u32;
            rgba.extend(sum.map(|s| ((s + n / 2) / n) as u8));
            rgba.push(0xff);
        }
    }
    let size = IntSize::from_wh(w as u32, h as u32).ok_or("render size too small")?;
    let pixmap = Pixmap::from_vec(rgba, size).ok_or("render buffer has the wrong size")?;
    pixmap
        .encode_png()
        .map_err(|e| format!("PNG encoding failed: {e}"))
}

/// Calls `plot(pixel index, depth)` for every pixel centre inside the triangle (either winding).
fn fill_triangle(
    p: &[DVec2; 3],
    z: &[f64; 3],
    w: usize,
    h: usize,
    mut plot: impl FnMut(usize, f64),
) {
    let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
    if area.abs() < 1e-12 {
        return;
    }
    let lo = p[0].min(p[1]).min(p[2]).floor().max(DVec2::ZERO);
    let hi = p[0].max(p[1]).max(p[2]).ceil();
    let (x1, y1) = ((hi.x as usize).min(w), (hi.y as usize).min(h));
    for y in lo.y as usize..y1 {
        for x in lo.x as usize..x1 {
            let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let b0 = (p[2] - p[1]).perp_dot(c - p[1]) / area;
            let b1 = (p[0] - p[2]).perp_dot(c - p[2]) / area;
            let b2 = 1.0 - b0 - b1;
            if b0 >= 0.0 && b1 >= 0.0 && b2 >= 0.0 {
                plot(y * w + x, b0 * z[0] + b1 * z[1] + b2 * z[2]);
            }
        }
    }
}

/// Calls `plot(pixel index, t)` for every pixel centre within `half` of segment ab, with t the
/// parameter of the closest point on ab.
fn fill_capsule(
    a: DVec2,
    b: DVec2,
    half: f64,
    w: usize,
    h: usize,
    mut plot: impl FnMut(usize, f64),
) {
    let lo = (a.min(b) - DVec2::splat(half)).floor().max(DVec2::ZERO);
    let hi = (a.max(b) + DVec2::splat(half)).ceil();
    let (x1, y1) = (
        (hi.x.max(0.0) as usize).min(w),
        (hi.y.max(0.0) as usize).min(h),
    );
    let ab = b - a;
    let len2 = ab.length_squared();
    for y in lo.y as usize..y1 {
        for x in lo.x as usize..x1 {
            let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let t = if len2 > 0.0 {
                ((c - a).dot(ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            if c.distance_squared(a + ab * t) <= half * half {
                plot(y * w + x, t);
            }
        }
    }
}

/// A network's edges as strokes at their radii, for a render on its surface.
pub fn network_strokes(net: &crate::Network) -> Vec<Stroke3> {
    net.edges
        .iter()
        .map(|e| Stroke3 {
            a: net.nodes[e.a as usize].p,
            b: net.nodes[e.b as usize].p,
            radius: e.radius,
            color: VEIN,
        })
        .collect()
}
