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
    /// The island's pixel nearest its centroid, mm: a point surely on it, where a support can
    /// hold it (the centroid of a crescent lies off it).
    pub anchor_mm: [f64; 2],
}

/// Finds islands layer by layer; feed the layers in order.
pub struct Islands {
    width: usize,
    height: usize,
    pixel_mm: f64,
    layer_mm: f64,
    /// The previous layer's image (empty before the first layer).
    below: Vec<u8>,
    /// Per pixel: the last component (numbered across all layers, from 1) that took it. A
    /// pixel is free in this layer when its number is at most `first`, the count before it.
    seen: Vec<u32>,
    next: u32,
    stack: Vec<usize>,
    members: Vec<usize>,
}

/// Whether any grey byte of `row` is lit (≥ 128: its top bit set); eight at a time.
fn any_lit(row: &[u8]) -> bool {
    let chunks = row.chunks_exact(8);
    let tail = chunks.remainder().iter().fold(0u8, |a, &b| a | b);
    let bits = chunks.fold(0u64, |a, c| {
        a | u64::from_le_bytes(c.try_into().expect("eight bytes"))
    });
    bits & 0x8080_8080_8080_8080 != 0 || tail & 0x80 != 0
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
            next: 0,
            stack: Vec::new(),
            members: Vec::new(),
        }
    }

    /// The islands that start in `layer` (row-major grey, `width` × `height`).
    pub fn layer(&mut self, index: usize, image: &[u8]) -> Vec<Island> {
        self.layer_owned(index, image.to_vec())
    }

    /// The same, keeping the image (as the next layer's below) without copying it.
    pub fn layer_owned(&mut self, index: usize, image: Vec<u8>) -> Vec<Island> {
        let (w, h) = (self.width, self.height);
        debug_assert_eq!(image.len(), w * h);
        let mut out = Vec::new();
        if !self.below.is_empty() {
            if self.seen.len() != w * h || self.next > u32::MAX - (w * h) as u32 {
                self.seen = vec![0; w * h];
                self.next = 0;
            }
            let first = self.next;
            let lit = |p: usize| image[p] >= LIT;
            // Dark rows are skipped whole.
            for (r, row) in image.chunks(w).enumerate() {
                if !any_lit(row) {
                    continue;
                }
                for start in r * w..(r + 1) * w {
                    if !lit(start) || self.seen[start] > first {
                        continue;
                    }
                    self.next += 1;
                    let label = self.next;
                    self.seen[start] = label;
                    self.stack.push(start);
                    let (mut count, mut sx, mut sy) = (0usize, 0.0f64, 0.0f64);
                    let mut held = false;
                    self.members.clear();
                    while let Some(p) = self.stack.pop() {
                        self.members.push(p);
                        let (r, col) = (p / w, p % w);
                        count += 1;
                        sx += col as f64;
                        sy += r as f64;
                        held |= self.below[p] >= LIT;
                        for rr in r.saturating_sub(1)..(r + 2).min(h) {
                            for cc in col.saturating_sub(1)..(col + 2).min(w) {
                                let q = rr * w + cc;
                                if lit(q) && self.seen[q] <= first {
                                    self.seen[q] = label;
                                    self.stack.push(q);
                                }
                            }
                        }
                    }
                    if !held {
                        let n = count as f64;
                        let (cx, cy) = (sx / n, sy / n);
                        let far = |p: usize| {
                            let (x, y) = ((p % w) as f64 - cx, (p / w) as f64 - cy);
                            x * x + y * y
                        };
                        let anchor = self
                            .members
                            .iter()
                            .copied()
                            .min_by(|&a, &b| far(a).total_cmp(&far(b)).then(a.cmp(&b)))
                            .unwrap_or(start);
                        let (ax, ay) = ((anchor % w) as f64, (anchor / w) as f64);
                        out.push(Island {
                            anchor_mm: [
                                (ax + 0.5) * self.pixel_mm,
                                (h as f64 - (ay + 0.5)) * self.pixel_mm,
                            ],
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
        }
        self.below = image;
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
    fn labels_carry_across_layers_without_mixing() {
        // Two separate dots in one layer, then a bar over both: one region, held.
        let mut f = Islands::new(9, 3, 1.0, 1.0);
        f.layer(0, &layer(9, 3, &[(1, 1), (1, 7)]));
        let bar: Vec<(usize, usize)> = (0..9).map(|c| (1, c)).collect();
        assert!(f.layer(1, &layer(9, 3, &bar)).is_empty());
        // The next layer: the same bar and a new dot far from it in the last row.
        let mut next = bar.clone();
        next.push((2, 0));
        assert!(
            f.layer(2, &layer(9, 3, &next)).is_empty(),
            "(2,0) touches (1,0)"
        );
        // Pixel (0, 4) was dark in layer 2 (the bar is row 1): an island, though its label
        // space is shared with the layers before.
        let found = f.layer(3, &layer(9, 3, &[(0, 4), (1, 4)]));
        assert!(
            found.is_empty(),
            "(1, 4) stands on the bar, and (0, 4) with it"
        );
        let found = f.layer(4, &layer(9, 3, &[(2, 8)]));
        assert_eq!(found.len(), 1, "(2, 8) was dark in layer 3");
    }

    #[test]
    fn grey_below_half_is_dark() {
        let mut f = Islands::new(4, 1, 1.0, 1.0);
        f.layer(0, &[127, 0, 0, 0]);
        let found = f.layer(1, &[128, 0, 0, 0]);
        assert_eq!(found.len(), 1, "127 below holds nothing");
    }
}
