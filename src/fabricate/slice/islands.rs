//! Islands: regions of a layer that touch nothing in the layer below. On a DMP-SL or MSLA
//! printer such a region is cured in free resin, where nothing holds it to the part, and the
//! print fails there. A region is a connected set of lit pixels (grey at least half, 8-connected);
//! it is an island when none of its pixels is lit in the previous layer. Everything in the
//! first layer stands on the plate. Regions are found as runs of lit pixels along each row,
//! joined where runs of neighbouring rows touch (a union-find over the runs), so a layer costs
//! its rows and runs, not its pixels one by one.

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
    /// More points on it where supports should hold it, mm, when it is wider than the spread
    /// asked for ([`Islands::with_spread`]): one near the middle of each square of that side
    /// it covers, at least half a spread from the anchor and each other.
    #[serde(skip)]
    pub holds: Vec<[f64; 2]>,
}

/// Finds islands layer by layer; feed the layers in order.
pub struct Islands {
    width: usize,
    height: usize,
    pixel_mm: f64,
    layer_mm: f64,
    /// The previous layer's image (empty before the first layer).
    below: Vec<u8>,
    /// This layer's runs of lit pixels and their union-find parents.
    runs: Vec<Run>,
    parent: Vec<u32>,
    /// The pixels of the island being described.
    members: Vec<usize>,
    /// Spread of the points an island is held at, pixels (none when 0).
    spread_px: f64,
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
            runs: Vec::new(),
            parent: Vec::new(),
            members: Vec::new(),
            spread_px: 0.0,
        }
    }

    /// Islands wider than `mm` get more points to be held at ([`Island::holds`]), about `mm`
    /// apart.
    pub fn with_spread(mut self, mm: f64) -> Islands {
        self.spread_px = mm / self.pixel_mm;
        self
    }

    /// The island's (`members`) pixels nearest the centres of the cells of a grid `spread_px`
    /// wide, in cell order, each kept when it is at least half that far from the anchor and
    /// from those kept before it (so no part of the island is much more than a spread from a
    /// point that holds it).
    fn spread(&self, anchor: usize) -> Vec<usize> {
        let step = self.spread_px;
        if step.is_nan() || step < 1.0 || self.members.len() < 2 {
            return Vec::new();
        }
        let w = self.width;
        let at = |p: usize| ((p % w) as f64, (p / w) as f64);
        let mut best: std::collections::BTreeMap<(u64, u64), (f64, usize)> = Default::default();
        for &p in &self.members {
            let (x, y) = at(p);
            let cell = ((y / step) as u64, (x / step) as u64);
            let centre = ((cell.1 as f64 + 0.5) * step, (cell.0 as f64 + 0.5) * step);
            let d = (x - centre.0).powi(2) + (y - centre.1).powi(2);
            let e = best.entry(cell).or_insert((d, p));
            if (d, p) < *e {
                *e = (d, p);
            }
        }
        let mut kept = vec![anchor];
        for &(_, p) in best.values() {
            let (x, y) = at(p);
            let clear = kept.iter().all(|&q| {
                let (qx, qy) = at(q);
                (x - qx).powi(2) + (y - qy).powi(2) >= 0.25 * step * step
            });
            if clear {
                kept.push(p);
            }
        }
        kept.split_off(1)
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
            // Runs of lit pixels, row by row (row-major order), joined into regions where
            // runs in neighbouring rows touch (8-connected: their columns overlap once each is
            // widened by one) by a union-find over the runs.
            let mut runs = std::mem::take(&mut self.runs);
            let mut parent = std::mem::take(&mut self.parent);
            runs.clear();
            let mut row_start = Vec::with_capacity(h + 1);
            for (r, row) in image.chunks(w).enumerate() {
                row_start.push(runs.len());
                if !any_lit(row) {
                    continue;
                }
                let mut c = 0;
                while c < w {
                    // Dark pixels eight at a time.
                    while c + 8 <= w && !any_lit(&row[c..c + 8]) {
                        c += 8;
                    }
                    if c >= w {
                        break;
                    }
                    if row[c] < LIT {
                        c += 1;
                        continue;
                    }
                    let c0 = c;
                    while c < w && row[c] >= LIT {
                        c += 1;
                    }
                    runs.push(Run {
                        row: r as u32,
                        c0: c0 as u32,
                        c1: c as u32,
                    });
                }
            }
            row_start.push(runs.len());
            parent.clear();
            parent.extend(0..runs.len() as u32);
            for r in 1..h {
                let (mut i, i_end) = (row_start[r - 1], row_start[r]);
                let (mut j, j_end) = (row_start[r], row_start[r + 1]);
                while i < i_end && j < j_end {
                    let (above, here) = (runs[i], runs[j]);
                    // Touching: [c0 − 1, c1] of one meets [c0, c1) of the other.
                    if above.c0 <= here.c1 && here.c0 <= above.c1 {
                        union_runs(&mut parent, i as u32, j as u32);
                    }
                    if above.c1 < here.c1 {
                        i += 1;
                    } else {
                        j += 1;
                    }
                }
            }
            // Per region (by its root run): pixels, column and row sums, whether any pixel is
            // lit in the layer below, and its first run (the first in row-major order).
            let roots: Vec<u32> = (0..runs.len() as u32)
                .map(|k| find_run(&mut parent, k))
                .collect();
            let mut region: Vec<Option<Region>> = vec![None; runs.len()];
            for k in 0..runs.len() {
                let root = roots[k] as usize;
                let run = runs[k];
                let (r, c0, c1) = (run.row as usize, run.c0 as usize, run.c1 as usize);
                let n = (c1 - c0) as f64;
                let held = any_lit(&self.below[r * w + c0..r * w + c1]);
                let g = region[root].get_or_insert(Region {
                    first: k,
                    count: 0,
                    sx: 0.0,
                    sy: 0.0,
                    held: false,
                });
                g.count += c1 - c0;
                g.sx += n * (c0 + c1 - 1) as f64 / 2.0;
                g.sy += n * r as f64;
                g.held |= held;
            }
            let mut free: Vec<(usize, Region)> = region
                .into_iter()
                .enumerate()
                .filter_map(|(root, g)| g.filter(|g| !g.held).map(|g| (root, g)))
                .collect();
            free.sort_by_key(|(_, g)| g.first);
            for (root, g) in free {
                self.members.clear();
                for k in (g.first..runs.len()).filter(|&k| roots[k] as usize == root) {
                    {
                        let run = runs[k];
                        let base = run.row as usize * w;
                        self.members
                            .extend(base + run.c0 as usize..base + run.c1 as usize);
                    }
                }
                let start = self.members.first().copied().unwrap_or(0);
                let (count, sx, sy) = (g.count, g.sx, g.sy);
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
                let holds = self
                    .spread(anchor)
                    .into_iter()
                    .map(|p| {
                        let (x, y) = ((p % w) as f64, (p / w) as f64);
                        [
                            (x + 0.5) * self.pixel_mm,
                            (h as f64 - (y + 0.5)) * self.pixel_mm,
                        ]
                    })
                    .collect();
                out.push(Island {
                    holds,
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
            self.runs = runs;
            self.parent = parent;
        }
        self.below = image;
        out
    }
}

/// A run of lit pixels in one row: columns `c0..c1`.
#[derive(Clone, Copy)]
struct Run {
    row: u32,
    c0: u32,
    c1: u32,
}

/// A region's sums, gathered at its root run.
#[derive(Clone, Copy)]
struct Region {
    first: usize,
    count: usize,
    sx: f64,
    sy: f64,
    held: bool,
}

/// The root of run `k`, halving the path on the way.
fn find_run(parent: &mut [u32], mut k: u32) -> u32 {
    while parent[k as usize] != k {
        let up = parent[parent[k as usize] as usize];
        parent[k as usize] = up;
        k = up;
    }
    k
}

/// Joins the regions of runs `a` and `b`: the later root under the earlier, so a region's
/// root is its first run.
fn union_runs(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find_run(parent, a), find_run(parent, b));
    if ra != rb {
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
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
    fn a_wide_island_is_held_at_points_a_spread_apart_and_a_small_one_at_its_anchor() {
        // A 40 × 4 pixel bar (1 mm pixels) and a 2 × 2 dot, spread 10 mm.
        let (w, h) = (50, 12);
        let mut f = Islands::new(w, h, 1.0, 1.0).with_spread(10.0);
        f.layer(0, &layer(w, h, &[]));
        let mut lit: Vec<(usize, usize)> = (0..4)
            .flat_map(|r| (0..40).map(move |c| (r + 2, c + 5)))
            .collect();
        lit.extend([(9, 1), (9, 2), (10, 1), (10, 2)]);
        let found = f.layer(1, &layer(w, h, &lit));
        assert_eq!(found.len(), 2);
        let bar = found.iter().find(|i| i.pixels == 160).expect("the bar");
        let dot = found.iter().find(|i| i.pixels == 4).expect("the dot");
        assert!(dot.holds.is_empty(), "{:?}", dot.holds);
        // Across 40 mm at 10 mm: the anchor and three or four more, all on the bar, none
        // closer than 5 mm to another, and every pixel of the bar within 10 mm of one.
        let mut all = vec![bar.anchor_mm];
        all.extend(bar.holds.iter().copied());
        assert!((4..=5).contains(&all.len()), "{all:?}");
        for (k, p) in all.iter().enumerate() {
            assert!(
                (5.0..45.0).contains(&p[0]) && (6.0..10.0).contains(&p[1]),
                "{p:?}"
            );
            for q in &all[..k] {
                assert!(((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt() >= 5.0);
            }
        }
        for &(r, c) in &lit[..160] {
            let (x, y) = (c as f64 + 0.5, h as f64 - (r as f64 + 0.5));
            let near = all
                .iter()
                .any(|p| ((p[0] - x).powi(2) + (p[1] - y).powi(2)).sqrt() <= 10.0);
            assert!(near, "({x}, {y}) is far from every hold: {all:?}");
        }
    }

    /// Islands of `image` over `below` by a plain breadth-first fill (8-connected), in the
    /// order of each region's first pixel: (pixels, centroid column and row, anchor pixel).
    fn oracle(w: usize, h: usize, below: &[u8], image: &[u8]) -> Vec<(usize, f64, f64, usize)> {
        let mut seen = vec![false; w * h];
        let mut out = Vec::new();
        for start in 0..w * h {
            if image[start] < LIT || seen[start] {
                continue;
            }
            seen[start] = true;
            let mut queue = std::collections::VecDeque::from([start]);
            let mut members = Vec::new();
            while let Some(p) = queue.pop_front() {
                members.push(p);
                let (r, c) = ((p / w) as i64, (p % w) as i64);
                for (dr, dc) in (-1..=1).flat_map(|a| (-1..=1).map(move |b| (a, b))) {
                    let (rr, cc) = (r + dr, c + dc);
                    if rr < 0 || cc < 0 || rr >= h as i64 || cc >= w as i64 {
                        continue;
                    }
                    let q = rr as usize * w + cc as usize;
                    if image[q] >= LIT && !seen[q] {
                        seen[q] = true;
                        queue.push_back(q);
                    }
                }
            }
            if members.iter().any(|&p| below[p] >= LIT) {
                continue;
            }
            let n = members.len() as f64;
            let cx = members.iter().map(|&p| (p % w) as f64).sum::<f64>() / n;
            let cy = members.iter().map(|&p| (p / w) as f64).sum::<f64>() / n;
            let far = |p: usize| ((p % w) as f64 - cx).powi(2) + ((p / w) as f64 - cy).powi(2);
            let anchor = *members
                .iter()
                .min_by(|&&a, &&b| far(a).total_cmp(&far(b)).then(a.cmp(&b)))
                .expect("a member");
            out.push((members.len(), cx, cy, anchor));
        }
        out
    }

    #[test]
    fn runs_find_the_islands_a_plain_fill_finds() {
        let (w, h) = (37, 23);
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng
        };
        let mut total = 0;
        for density in [5u64, 20, 45, 60] {
            let mut f = Islands::new(w, h, 1.0, 1.0);
            let mut below = vec![0u8; w * h];
            for layer in 0..12 {
                let image: Vec<u8> = (0..w * h)
                    .map(|_| {
                        if next() % 100 < density {
                            200
                        } else {
                            (next() % 128) as u8
                        }
                    })
                    .collect();
                let found = f.layer(layer, &image);
                if layer > 0 {
                    let want = oracle(w, h, &below, &image);
                    assert_eq!(found.len(), want.len(), "density {density} layer {layer}");
                    total += want.len();
                    for (i, (n, cx, cy, anchor)) in found.iter().zip(want) {
                        assert_eq!(i.pixels, n);
                        assert!((i.x_mm - (cx + 0.5)).abs() < 1e-9);
                        assert!((i.y_mm - (h as f64 - (cy + 0.5))).abs() < 1e-9);
                        let (ax, ay) = (
                            (anchor % w) as f64 + 0.5,
                            h as f64 - ((anchor / w) as f64 + 0.5),
                        );
                        assert_eq!(i.anchor_mm, [ax, ay]);
                    }
                }
                below = image;
            }
        }
        assert!(total > 100, "{total} islands in all");
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
