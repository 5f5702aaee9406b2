//! Exact-area coverage of directed segments on a pixel grid: each pixel gets the area of it
//! that the closed contours enclose, so the image is anti-aliased without supersampling and its
//! grey sum is the section's area.
//!
//! Every segment adds its signed height to the cells it crosses, split between the cell it is
//! in (by how much of that cell lies to its right) and the next one; a running sum along each
//! row then gives the winding-weighted covered area of every pixel. Overlapping shells add up
//! (winding 2) and are clamped to full coverage, which is the non-zero fill rule: shells that
//! overlap need no union first.

/// A segment in pixel coordinates (x right, y down), directed along its contour.
pub type Segment = [[f64; 2]; 2];

/// An accumulation buffer over a window of the image.
pub struct Coverage {
    col0: i64,
    row0: i64,
    cols: usize,
    rows: usize,
    /// `cols + 2` cells per row: a segment at the right edge spills into the next cell.
    acc: Vec<f32>,
}

impl Coverage {
    /// A window covering pixel columns `col0..col0 + cols` and rows `row0..row0 + rows`.
    pub fn new(col0: i64, row0: i64, cols: usize, rows: usize) -> Self {
        Coverage {
            col0,
            row0,
            cols,
            rows,
            acc: vec![0.0; (cols + 2) * rows],
        }
    }

    pub fn add(&mut self, s: &Segment) {
        let [[x0, y0], [x1, y1]] = *s;
        if y0 == y1 {
            return;
        }
        let sign = if y1 > y0 { 1.0 } else { -1.0 };
        let (top, bottom) = if y0 < y1 { (s[0], s[1]) } else { (s[1], s[0]) };
        let slope = (x1 - x0) / (y1 - y0);
        let r0 = top[1].floor() as i64;
        let r1 = (bottom[1].ceil() as i64).max(r0 + 1);
        for r in r0..r1 {
            let ya = top[1].max(r as f64);
            let yb = bottom[1].min((r + 1) as f64);
            if yb <= ya {
                continue;
            }
            let xa = x0 + (ya - y0) * slope;
            let xb = x0 + (yb - y0) * slope;
            self.row_piece(r, xa, xb, sign * (yb - ya));
        }
    }

    /// One piece of a segment inside row `r`, running from x = `xa` to `xb` over height `dy`.
    fn row_piece(&mut self, r: i64, xa: f64, xb: f64, dy: f64) {
        let row = r - self.row0;
        if row < 0 || row >= self.rows as i64 {
            return;
        }
        let stride = self.cols + 2;
        let base = row as usize * stride;
        let (lo, hi) = if xa < xb { (xa, xb) } else { (xb, xa) };
        let c0 = lo.floor() as i64;
        let c1 = hi.floor() as i64;
        let width = hi - lo;
        let mut put = |c: i64, part: f64, mid: f64| {
            // Cells left of the window take everything to their right: fold them into its
            // first cell.
            let local = c - self.col0;
            if local < 0 {
                self.acc[base] += part as f32;
                return;
            }
            let local = (local as usize).min(stride - 2);
            let inside = ((c + 1) as f64 - mid).clamp(0.0, 1.0);
            self.acc[base + local] += (part * inside) as f32;
            self.acc[base + local + 1] += (part * (1.0 - inside)) as f32;
        };
        if c0 == c1 || width <= 0.0 {
            put(c0, dy, 0.5 * (lo + hi));
            return;
        }
        for c in c0..=c1 {
            let a = lo.max(c as f64);
            let b = hi.min((c + 1) as f64);
            if b > a {
                put(c, dy * (b - a) / width, 0.5 * (a + b));
            }
        }
    }

    /// Writes the 8-bit coverage into a full image of `width` columns (row-major), and returns
    /// the covered area in pixels as the image holds it (Σ grey / 255).
    pub fn write(&self, image: &mut [u8], width: usize) -> f64 {
        let stride = self.cols + 2;
        let mut area = 0u64;
        for row in 0..self.rows {
            let y = self.row0 + row as i64;
            let height = image.len() / width;
            if y < 0 || y >= height as i64 {
                continue;
            }
            let line = &mut image[y as usize * width..(y as usize + 1) * width];
            let mut sum = 0.0f32;
            for (k, &a) in self.acc[row * stride..row * stride + self.cols]
                .iter()
                .enumerate()
            {
                sum += a;
                let x = self.col0 + k as i64;
                if x < 0 || x >= width as i64 {
                    continue;
                }
                let grey = (sum.abs().min(1.0) * 255.0 + 0.5) as u8;
                line[x as usize] = grey;
                area += grey as u64;
            }
        }
        area as f64 / 255.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polygon(points: &[[f64; 2]]) -> Vec<Segment> {
        (0..points.len())
            .map(|i| [points[i], points[(i + 1) % points.len()]])
            .collect()
    }

    fn raster(segments: &[Segment], w: usize, h: usize) -> (Vec<u8>, f64) {
        let mut cov = Coverage::new(0, 0, w, h);
        for s in segments {
            cov.add(s);
        }
        let mut image = vec![0u8; w * h];
        let area = cov.write(&mut image, w);
        (image, area)
    }

    #[test]
    fn a_slanted_triangle_covers_its_area_in_either_winding() {
        let tri: [[f64; 2]; 3] = [[1.3, 2.7], [17.9, 4.1], [6.2, 15.55]];
        let want = 0.5
            * ((tri[1][0] - tri[0][0]) * (tri[2][1] - tri[0][1])
                - (tri[2][0] - tri[0][0]) * (tri[1][1] - tri[0][1]))
                .abs();
        let (_, a) = raster(&polygon(&tri), 20, 20);
        assert!((a - want).abs() < 20.0 / 255.0, "{a} vs {want}");
        let mut rev = tri;
        rev.reverse();
        let (_, b) = raster(&polygon(&rev), 20, 20);
        assert!((a - b).abs() < 1e-9);
    }

    #[test]
    fn a_square_on_pixel_edges_is_crisp_and_a_hole_is_empty() {
        let outer = polygon(&[[2.0, 2.0], [10.0, 2.0], [10.0, 10.0], [2.0, 10.0]]);
        let (image, area) = raster(&outer, 12, 12);
        assert_eq!(area, 64.0);
        assert!(image.iter().all(|&g| g == 0 || g == 255));
        // A hole wound the other way.
        let mut ring = outer.clone();
        ring.extend(polygon(&[[4.0, 4.0], [4.0, 8.0], [8.0, 8.0], [8.0, 4.0]]));
        let (image, area) = raster(&ring, 12, 12);
        assert_eq!(area, 48.0);
        assert_eq!(image[5 * 12 + 5], 0);
    }

    #[test]
    fn overlapping_shells_fill_by_the_non_zero_rule() {
        let mut two = polygon(&[[1.0, 1.0], [7.0, 1.0], [7.0, 7.0], [1.0, 7.0]]);
        two.extend(polygon(&[
            [4.0, 4.0],
            [10.0, 4.0],
            [10.0, 10.0],
            [4.0, 10.0],
        ]));
        let (_, area) = raster(&two, 12, 12);
        assert_eq!(area, 36.0 + 36.0 - 9.0);
    }

    #[test]
    fn half_covered_pixels_are_grey() {
        let (image, area) = raster(
            &polygon(&[[0.5, 0.0], [3.0, 0.0], [3.0, 1.0], [0.5, 1.0]]),
            4,
            1,
        );
        assert_eq!(image, vec![128, 255, 255, 0]);
        assert!((area - (128.0 + 510.0) / 255.0).abs() < 1e-12);
    }
}
