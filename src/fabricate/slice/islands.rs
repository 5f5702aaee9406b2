//! Islands: regions of a layer that touch nothing in the layer below. On a DMP-SL or MSLA
//! printer such a region is cured in free resin, where nothing holds it to the part, and the
//! print fails there. A region is a connected set of lit pixels (grey at least half, 8-connected);
//! it is an island when none of its pixels is lit in the previous layer. Everything in the
//! first layer stands on the plate.

/// Grey at or above this is lit.
pub const LIT: u8 = 128;

/// One island.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Island {
    /// The layer it starts in, from 0.
    pub layer: usize,
    /// Its centroid on the plate, mm (x right, y away from the viewer, as the models were
    /// placed).
    pub x_mm: f64,
    pub y_mm: f64,
    /// Its lowest point's height: the layer's top, mm.
    pub z_mm: f64,
    pub pixels: usize,
    pub area_mm2: f64,
}

/// Finds islands layer by layer; feed the layers in order.
pub struct Islands {
    width: usize,
    height: usize,
    pixel_mm: f64,
    layer_mm: f64,
    /// The previous layer's lit pixels (empty before the first layer).
    below: Vec<bool>,
    /// Scratch: the component (from 1) of each pixel of this layer; 0 for none yet.
    seen: Vec<u32>,
    stack: Vec<usize>,
}

impl Islands {
    pub fn new(width: usize, height: usize, pixel_mm: f64, layer_mm: f64) -> Islands {
        Islands {
            width,
            height,
            pixel_mm,
            layer_mm,
            below: Vec::new(),
            seen: Vec::new(),
            stack: Vec::new(),
        }
    }

    /// The islands that start in `layer` (row-major grey, `width` × `height`).
    pub fn layer(&mut self, index: usize, image: &[u8]) -> Vec<Island> {
        let (w, h) = (self.width, self.height);
        debug_assert_eq!(image.len(), w * h);
        let lit: Vec<bool> = image.iter().map(|&g| g >= LIT).collect();
        let mut out = Vec::new();
        if !self.below.is_empty() {
            self.seen.clear();
            self.seen.resize(w * h, 0);
            let mut label = 0u32;
            for start in 0..w * h {
                if !lit[start] || self.seen[start] != 0 {
                    continue;
                }
                label += 1;
                self.seen[start] = label;
                self.stack.push(start);
                let (mut count, mut sx, mut sy) = (0usize, 0.0f64, 0.0f64);
                let mut held = false;
                while let Some(p) = self.stack.pop() {
                    let (r, c) = (p / w, p % w);
                    count += 1;
                    sx += c as f64;
                    sy += r as f64;
                    held |= self.below[p];
                    for dr in [-1i64, 0, 1] {
                        for dc in [-1i64, 0, 1] {
                            let (rr, cc) = (r as i64 + dr, c as i64 + dc);
                            if (dr, dc) == (0, 0)
                                || rr < 0
                                || cc < 0
                                || rr >= h as i64
                                || cc >= w as i64
                            {
                                continue;
                            }
                            let q = rr as usize * w + cc as usize;
                            if lit[q] && self.seen[q] == 0 {
                                self.seen[q] = label;
                                self.stack.push(q);
                            }
                        }
                    }
                }
                if !held {
                    let n = count as f64;
                    out.push(Island {
                        layer: index,
                        x_mm: (sx / n + 0.5) * self.pixel_mm,
                        y_mm: (h as f64 - (sy / n + 0.5)) * self.pixel_mm,
                        z_mm: index as f64 * self.layer_mm,
                        pixels: count,
                        area_mm2: n * self.pixel_mm * self.pixel_mm,
                    });
                }
            }
        }
        self.below = lit;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A w × h layer with the given pixels lit.
    fn layer(w: usize, h: usize, lit: &[(usize, usize)]) -> Vec<u8> {
        let mut img = vec![0u8; w * h];
        for &(r, c) in lit {
            img[r * w + c] = 255;
        }
        img
    }

    #[test]
    fn a_region_touching_the_layer_below_only_at_a_corner_is_held() {
        let mut f = Islands::new(8, 8, 0.05, 0.05);
        assert!(
            f.layer(0, &layer(8, 8, &[(1, 1)])).is_empty(),
            "the plate holds layer 0"
        );
        // (2, 2) is diagonal to nothing below: its own pixel (2, 2) is not lit below.
        let next = f.layer(1, &layer(8, 8, &[(1, 1), (2, 2), (6, 6), (6, 7)]));
        // (1,1)-(2,2) is one region (8-connected) standing on (1, 1); (6, 6)-(6, 7) is new.
        assert_eq!(next.len(), 1);
        let i = &next[0];
        assert_eq!((i.layer, i.pixels), (1, 2));
        assert!((i.x_mm - 7.0 * 0.05).abs() < 1e-12, "{}", i.x_mm);
        assert!((i.y_mm - (8.0 - 6.5) * 0.05).abs() < 1e-12, "{}", i.y_mm);
    }

    #[test]
    fn grey_below_half_is_dark() {
        let mut f = Islands::new(4, 1, 1.0, 1.0);
        f.layer(0, &[127, 0, 0, 0]);
        let found = f.layer(1, &[128, 0, 0, 0]);
        assert_eq!(found.len(), 1, "127 below holds nothing");
    }
}
