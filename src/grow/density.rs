//! Density maps (Gokmen §3.2, Fig. 2): a PNG stretched over the blade's bounding box whose dark
//! parts ask for dense auxin sources. The Poisson-disk radius at a point interpolates between
//! `birth_min` (darkest) and `birth_max` (lightest).
//!
//! Darkness is read from the alpha channel when the image has any transparent pixel (opaque =
//! dark, as Gokmen reads the alpha of his gradient maps), else from the grey level (black =
//! dark). Samples are bilinear between pixel centres.

use std::path::{Path, PathBuf};

use glam::DVec2;

#[derive(Debug, thiserror::Error)]
pub enum DensityError {
    #[error("density= {path}: cannot read the file: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("density= {path}: not a PNG image lamina can read: {msg}")]
    Decode { path: PathBuf, msg: String },
}

/// Which channel a map's darkness came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    Alpha,
    Grey,
}

#[derive(Clone, Debug)]
pub struct DensityMap {
    width: usize,
    height: usize,
    /// 0 = lightest (sparse) … 1 = darkest (dense), row 0 at the top.
    darkness: Vec<f32>,
    pub channel: Channel,
}

/// The largest side of a density map, in pixels: 8192 × 8192 decodes to 256 MiB.
pub const MAX_SIDE: u32 = 8192;

impl DensityMap {
    pub fn read(path: &Path) -> Result<Self, DensityError> {
        let bytes = std::fs::read(path).map_err(|source| DensityError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_png(&bytes).map_err(|msg| DensityError::Decode {
            path: path.to_path_buf(),
            msg,
        })
    }

    pub fn from_png(bytes: &[u8]) -> Result<Self, String> {
        // The header's size, checked before the decoder allocates for it (a 65535 × 65535
        // header, or a small zlib stream that inflates to gigabytes).
        if bytes.len() >= 24 && bytes.starts_with(b"\x89PNG\r\n\x1a\n") && &bytes[12..16] == b"IHDR"
        {
            let w = u32::from_be_bytes([bytes[16], bytes[17], bytes[18], bytes[19]]);
            let h = u32::from_be_bytes([bytes[20], bytes[21], bytes[22], bytes[23]]);
            if w > MAX_SIDE || h > MAX_SIDE {
                return Err(format!(
                    "the image is {w} × {h} pixels; a density map may be at most {MAX_SIDE} a side"
                ));
            }
        }
        if let Some(problem) = crate::files::png_palette_problem(bytes) {
            return Err(problem);
        }
        let pixmap = crate::files::guarded(|| tiny_skia::Pixmap::decode_png(bytes))?
            .map_err(|e| crate::files::png_message(&e))?;
        let (width, height) = (pixmap.width() as usize, pixmap.height() as usize);
        let pixels = pixmap.pixels();
        let transparent = pixels.iter().any(|p| p.alpha() < 255);
        let darkness = pixels
            .iter()
            .map(|p| {
                if transparent {
                    p.alpha() as f32 / 255.0
                } else {
                    // Opaque, so premultiplied = straight. Rec. 709 luma of the stored values.
                    let luma = 0.2126 * p.red() as f32
                        + 0.7152 * p.green() as f32
                        + 0.0722 * p.blue() as f32;
                    1.0 - luma / 255.0
                }
            })
            .collect();
        Ok(DensityMap {
            width,
            height,
            darkness,
            channel: if transparent {
                Channel::Alpha
            } else {
                Channel::Grey
            },
        })
    }

    /// Darkness in [0, 1] at (u, v) in [0, 1]², u to the right, v up (image bottom = v 0).
    pub fn darkness(&self, u: f64, v: f64) -> f64 {
        let x = (u.clamp(0.0, 1.0) * self.width as f64 - 0.5).clamp(0.0, self.width as f64 - 1.0);
        let y = ((1.0 - v.clamp(0.0, 1.0)) * self.height as f64 - 0.5)
            .clamp(0.0, self.height as f64 - 1.0);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let at = |x: usize, y: usize| self.darkness[y * self.width + x] as f64;
        let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
        let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The birth radius at blade point `p`, the map stretched over the box `lo`..`hi`.
    pub fn radius(&self, p: DVec2, lo: DVec2, hi: DVec2, birth_min: f64, birth_max: f64) -> f64 {
        let size = (hi - lo).max(DVec2::splat(f64::MIN_POSITIVE));
        let uv = (p - lo) / size;
        birth_max - (birth_max - birth_min) * self.darkness(uv.x, uv.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(width: u32, height: u32, rgba: impl Fn(u32, u32) -> [u8; 4]) -> Vec<u8> {
        let mut pm = tiny_skia::Pixmap::new(width, height).expect("size");
        for y in 0..height {
            for x in 0..width {
                let [r, g, b, a] = rgba(x, y);
                let c = tiny_skia::ColorU8::from_rgba(r, g, b, a).premultiply();
                pm.pixels_mut()[(y * width + x) as usize] = c;
            }
        }
        pm.encode_png().expect("encode")
    }

    #[test]
    fn a_broken_chunk_is_named_plainly() {
        let mut bytes = png(4, 4, |x, _| [(60 * x) as u8, 0, 0, 255]);
        // The IDAT chunk's CRC (after its length, type and data), spoiled.
        let at = bytes.windows(4).position(|w| w == b"IDAT").expect("IDAT") - 4;
        let len = u32::from_be_bytes(bytes[at..at + 4].try_into().expect("4 bytes")) as usize;
        bytes[at + 8 + len] ^= 0xff;
        let msg = DensityMap::from_png(&bytes).expect_err("a CRC error");
        assert!(msg.contains("IDAT chunk"), "{msg}");
        assert!(!msg.contains("ChunkType") && !msg.contains('{'), "{msg}");
    }

    #[test]
    fn grey_maps_read_dark_as_dense_and_put_the_top_row_up() {
        // Left half black, right half white; top row grey.
        let bytes = png(4, 4, |x, y| {
            if y == 0 {
                [128, 128, 128, 255]
            } else if x < 2 {
                [0, 0, 0, 255]
            } else {
                [255, 255, 255, 255]
            }
        });
        let m = DensityMap::from_png(&bytes).expect("decodes");
        assert_eq!(m.channel, Channel::Grey);
        assert!((m.darkness(0.0, 0.0) - 1.0).abs() < 1e-9);
        assert!(m.darkness(1.0, 0.0).abs() < 1e-9);
        assert!((m.darkness(0.0, 1.0) - (1.0 - 128.0 / 255.0)).abs() < 1e-6);
        let (lo, hi) = (DVec2::ZERO, DVec2::splat(10.0));
        assert!((m.radius(DVec2::new(0.0, 0.0), lo, hi, 1.0, 4.0) - 1.0).abs() < 1e-9);
        assert!((m.radius(DVec2::new(10.0, 0.0), lo, hi, 1.0, 4.0) - 4.0).abs() < 1e-9);
    }

    #[test]
    fn alpha_maps_read_opaque_as_dense() {
        let bytes = png(2, 1, |x, _| [255, 255, 255, if x == 0 { 255 } else { 0 }]);
        let m = DensityMap::from_png(&bytes).expect("decodes");
        assert_eq!(m.channel, Channel::Alpha);
        assert!((m.darkness(0.0, 0.5) - 1.0).abs() < 1e-9);
        assert!(m.darkness(1.0, 0.5).abs() < 1e-9);
    }

    #[test]
    fn bad_images_are_errors() {
        assert!(DensityMap::from_png(b"not a png").is_err());
        let e = DensityMap::read(Path::new("/no/such/map.png")).expect_err("missing");
        assert!(e.to_string().contains("density= /no/such/map.png"));
    }
}
