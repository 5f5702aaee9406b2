//! Slicing a solid straight from its shapes: every layer's pixels are sampled from the signed
//! distance to the union, so no mesh is made, stored or cut.
//!
//! # Method
//! The solid is placed as `solid` places its mesh (stood up if asked, centred on the z axis,
//! lowest point at z = 0), but from the shapes' exact box. A layer is cut at its middle height,
//! as `slice` cuts meshes. The display is cut into tiles of 8 × 8 pixels; each piece that
//! crosses the layer's plane lists itself in the tiles its cross-section can reach (a round
//! cone's from the stretch of its axis within its larger radius of the plane). A tile whose
//! centre is farther from the surface than the tile's half-diagonal is wholly dark or wholly lit
//! (the distance is 1-Lipschitz); the others are sampled pixel by pixel. Round cones (the veins)
//! are moved onto the plate once, where each copy stands, so a sample is measured where it is;
//! other pieces get the sample moved back into their own frame.
//!
//! # Anti-aliasing
//! A pixel's grey is the area of it the section covers, as `slice` computes exactly for a
//! mesh's contours. A pixel whose centre is at least half its diagonal (√½ pixel) from the
//! surface in 3D is wholly in or out: the section's edge, on the surface, is at least as far in
//! the plane.
//! Each of the others is cut into 4 × 4 sub-pixels, and in each the section's edge is taken as
//! straight: the 3D distance d at the sub-pixel's centre and the in-plane gradient g of the
//! distance (second-order differences of the neighbouring centres' values) give the edge's
//! distance in the plane, d / |g| (the surface leans away from the plane by that factor), and
//! its direction, g / |g|; the area of a square cut by a straight line is exact. An edge that
//! bends, or meets another edge where two pieces join, within the pixel is so followed to a
//! quarter pixel: a straight edge across the whole pixel from its centre alone missed such
//! pixels by up to 6 % of their area, and left a pixel whose centre lies between a vein's axis
//! and a neighbouring piece dark where it was wholly inside.

use std::f64::consts::FRAC_1_SQRT_2;
use std::ops::Range;

use glam::{DVec2, DVec3};

use super::islands::LIT;
use super::{encode_grey, in_batches, Layer, Placement, Printer};
use crate::fabricate::solid::sdf::{Primitive, RoundCone};
use crate::fabricate::solid::{placing_shift, Shapes};

/// Pixels per tile side.
const TILE: usize = 8;

/// Pixels per side of a quarter tile.
const HALF: usize = TILE / 2;

/// The solid placed for printing, ready to be sampled.
pub struct Placed {
    shapes: Shapes,
    upright: bool,
    /// Added to a stood-up point of the shapes to place it.
    shift: DVec3,
    /// Each piece's box, placed.
    boxes: Vec<(DVec3, DVec3)>,
    /// Each round cone's balls, placed: (a, ra, b, rb).
    balls: Vec<Option<(DVec3, f64, DVec3, f64)>>,
}

impl Placed {
    /// Stands the shapes up if asked (+y becomes +z), centres them on the z axis and sets their
    /// lowest point on z = 0; or moves them by their `frame` when they have one.
    pub fn new(shapes: Shapes, upright: bool) -> Placed {
        let turn = |p: DVec3| {
            if upright {
                crate::geom::upright(p)
            } else {
                p
            }
        };
        let mut boxes: Vec<(DVec3, DVec3)> = shapes
            .prims
            .iter()
            .map(|s| {
                let (a, b) = s.bounds();
                let (a, b) = (turn(a), turn(b));
                (a.min(b), a.max(b))
            })
            .collect();
        let shift = shapes
            .frame
            .unwrap_or_else(|| placing_shift(&shapes.prims, upright));
        for b in &mut boxes {
            *b = (b.0 + shift, b.1 + shift);
        }
        let balls = shapes
            .prims
            .iter()
            .map(|s| match s {
                Primitive::Cone(c) => {
                    let (a, ra, b, rb) = c.balls();
                    Some((turn(a) + shift, ra, turn(b) + shift, rb))
                }
                _ => None,
            })
            .collect();
        Placed {
            shapes,
            upright,
            shift,
            boxes,
            balls,
        }
    }

    /// The placed solid's exact box.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.boxes.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &(a, b)| (lo.min(a), hi.max(b)),
        )
    }

    pub fn shapes(&self) -> &Shapes {
        &self.shapes
    }

    /// A placed point in the shapes' own frame.
    pub fn local(&self, q: DVec3) -> DVec3 {
        self.local_direction(q - self.shift)
    }

    /// A placed direction in the shapes' own frame.
    pub fn local_direction(&self, v: DVec3) -> DVec3 {
        if self.upright {
            DVec3::new(v.x, v.z, -v.y)
        } else {
            v
        }
    }

    pub fn upright(&self) -> bool {
        self.upright
    }

    /// Where the shapes' origin is placed.
    pub fn shift(&self) -> DVec3 {
        self.shift
    }

    /// The radius of the thickest vein holding the placed point `p`, where it is: a round cone's
    /// radius at `p`'s place along its axis. `None` when no vein holds it.
    pub fn vein_radius(&self, p: DVec3) -> Option<f64> {
        let mut best: Option<f64> = None;
        for (k, balls) in self.balls.iter().enumerate() {
            let Some((a, ra, b, rb)) = *balls else {
                continue;
            };
            if self.eval_piece(k as u32, p, 1.0) >= 0.0 {
                continue;
            }
            let ab = b - a;
            let t = if ab.length_squared() > 0.0 {
                ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let r = ra + (rb - ra) * t;
            best = Some(best.map_or(r, |x: f64| x.max(r)));
        }
        best
    }

    /// Signed distance to piece `k` at the placed point `q`.
    fn eval_piece(&self, k: u32, q: DVec3, reach: f64) -> f64 {
        self.shapes.prims[k as usize].eval(self.local(q), reach)
    }

    /// Signed distance to the placed union at `q`.
    pub fn eval(&self, q: DVec3, reach: f64) -> f64 {
        self.shapes.eval(self.local(q), reach)
    }

    /// The xy box piece `k`'s section at height `z` lies in, or `None` when it misses the plane.
    fn footprint(&self, k: usize, z: f64) -> Option<(DVec2, DVec2)> {
        let (lo, hi) = self.boxes[k];
        if z < lo.z || z > hi.z {
            return None;
        }
        let Some((a, ra, b, rb)) = self.balls[k] else {
            return Some((lo.truncate(), hi.truncate()));
        };
        // Points of the section are within r of an axis point within r of the plane.
        let r = ra.max(rb);
        let (t0, t1) = if (b.z - a.z).abs() < 1e-12 {
            (0.0, 1.0)
        } else {
            let s0 = (z - r - a.z) / (b.z - a.z);
            let s1 = (z + r - a.z) / (b.z - a.z);
            (s0.min(s1).max(0.0), s0.max(s1).min(1.0))
        };
        if t0 > t1 {
            return None;
        }
        let (p, q) = (a.lerp(b, t0).truncate(), a.lerp(b, t1).truncate());
        Some((p.min(q) - DVec2::splat(r), p.max(q) + DVec2::splat(r)))
    }

    /// Each round cone as copy `p` stands on the plate, so a point of the plate is measured
    /// without being moved back into the shapes' frame (`None` for other pieces).
    fn on_plate(&self, p: &Placement) -> Vec<Option<RoundCone>> {
        let off = DVec3::from(p.offset);
        let put = |v: DVec3| turn(v.truncate(), p.turned).extend(v.z) + off;
        self.balls
            .iter()
            .map(|balls| balls.map(|(a, ra, b, rb)| RoundCone::new(put(a), put(b), ra, rb)))
            .collect()
    }
}

/// How many layers the placed solid needs.
pub fn layer_count(model: &Placed, printer: &Printer) -> usize {
    let (lo, hi) = model.bounds();
    super::layers_for(hi.z - lo.z, printer.layer_mm)
}

/// Slices the placed copies of the solid and hands each layer, in order, to `sink`; layers are
/// made in parallel batches, as `slice` makes them.
pub fn slice<E>(
    model: &Placed,
    placed: &[Placement],
    printer: &Printer,
    mut sink: impl FnMut(Layer) -> Result<(), E>,
) -> Result<usize, E> {
    let layers = layer_count(model, printer);
    let plate = Plate::new(model, placed);
    in_batches(
        layers,
        |i| {
            let (image, area) = image(&plate, printer, i);
            Layer {
                index: i,
                png: encode_grey(&image, printer.pixels_x, printer.pixels_y),
                image,
                area_mm2: area,
                exact_area_mm2: None,
            }
        },
        |_, l| sink(l),
    )?;
    Ok(layers)
}

/// One piece of one copy that may reach a tile.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct Entry {
    tile: u32,
    copy: u32,
    piece: u32,
}

/// Copies of a placed solid on the plate, ready to be sliced.
pub struct Plate<'a> {
    model: &'a Placed,
    placed: &'a [Placement],
    /// Each copy's round cones where the copy stands (`Placed::on_plate`).
    cones: Vec<Vec<Option<RoundCone>>>,
}

impl<'a> Plate<'a> {
    pub fn new(model: &'a Placed, placed: &'a [Placement]) -> Plate<'a> {
        let cones = placed.iter().map(|p| model.on_plate(p)).collect();
        Plate {
            model,
            placed,
            cones,
        }
    }
}

/// Layer `i`'s grey image and its area (Σ grey / 255 × pixel area, mm²).
pub fn image(plate: &Plate, printer: &Printer, i: usize) -> (Vec<u8>, f64) {
    let (w, h) = (printer.pixels_x as usize, printer.pixels_y as usize);
    let mut image = vec![0u8; w * h];
    let area = image_onto(plate, printer, i, &mut image);
    (image, area)
}

/// Draws layer `i` onto `image` (a whole display's, row-major), the supports only where it is
/// unlit; returns the area it added (Σ added grey / 255 × pixel area, mm²). On an image of
/// another solid's layer (a mesh's), a plate of supports alone draws them as the print does.
pub fn image_onto(plate: &Plate, printer: &Printer, i: usize, image: &mut [u8]) -> f64 {
    let (model, placed, cones) = (plate.model, plate.placed, &plate.cones);
    let z = (i as f64 + 0.5) * printer.layer_mm;
    let px = printer.pixel_mm;
    let (w, h) = (printer.pixels_x as usize, printer.pixels_y as usize);
    let (tw, th) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let mut entries = Vec::new();
    for (c, p) in placed.iter().enumerate() {
        let off = DVec2::new(p.offset[0], p.offset[1]);
        for k in 0..model.boxes.len() {
            let Some((lo, hi)) = model.footprint(k, z - p.offset[2]) else {
                continue;
            };
            let (a, b) = (turn(lo, p.turned) + off, turn(hi, p.turned) + off);
            let (lo, hi) = (a.min(b) - DVec2::splat(px), a.max(b) + DVec2::splat(px));
            // Columns from x, rows from the far edge (y down).
            let c0 = (lo.x / px).floor().max(0.0) as usize;
            let c1 = ((hi.x / px).ceil().max(0.0) as usize).min(w);
            let r0 = (h as f64 - hi.y / px).floor().max(0.0) as usize;
            let r1 = ((h as f64 - lo.y / px).ceil().max(0.0) as usize).min(h);
            if c0 >= c1 || r0 >= r1 {
                continue;
            }
            for ty in r0 / TILE..=(r1 - 1) / TILE {
                for tx in c0 / TILE..=(c1 - 1) / TILE {
                    entries.push(Entry {
                        tile: (ty * tw + tx) as u32,
                        copy: c as u32,
                        piece: k as u32,
                    });
                }
            }
        }
    }
    entries.sort_unstable();
    let mut total = 0u64;
    let reach_tile = TILE as f64 * px * FRAC_1_SQRT_2 + px;
    let (mut values, mut near) = (Vec::new(), Vec::new());
    let (mut part, mut held) = (Vec::new(), Vec::new());
    // Pieces from here on are supports.
    let first_support = (model.shapes().prims.len() - model.shapes().added) as u32;
    let mut s = 0;
    while s < entries.len() {
        let tile = entries[s].tile;
        let mut e = s;
        while e < entries.len() && entries[e].tile == tile {
            e += 1;
        }
        let group = &entries[s..e];
        s = e;
        // The part's pixels first, then the supports' where the part leaves a pixel unlit: the
        // part's lit pixels are the same with supports or without (supports are added to its
        // layer, not blended into its edges), and a support still meets the part's faint edge.
        part.clear();
        held.clear();
        for en in group {
            if en.piece < first_support {
                part.push(*en);
            } else {
                held.push(*en);
            }
        }
        let mut paint = |group: &[Entry], only_unlit: bool| {
            let (ty, tx) = (tile as usize / tw, tile as usize % tw);
            debug_assert!(ty < th);
            let (c0, r0) = (tx * TILE, ty * TILE);
            let (c1, r1) = ((c0 + TILE).min(w), (r0 + TILE).min(h));
            let at = |col: f64, row: f64| DVec3::new(col * px, (h as f64 - row) * px, z);
            let piece = |en: &Entry, q: DVec3, reach: f64| {
                if let Some(cone) = &cones[en.copy as usize][en.piece as usize] {
                    return cone.eval(q);
                }
                let p = &placed[en.copy as usize];
                let local = turn_back(
                    q.truncate() - DVec2::new(p.offset[0], p.offset[1]),
                    p.turned,
                );
                model.eval_piece(en.piece, local.extend(q.z - p.offset[2]), reach)
            };
            let dist = |among: &[Entry], q: DVec3, reach: f64| {
                among
                    .iter()
                    .fold(f64::INFINITY, |d, en| d.min(piece(en, q, reach)))
            };
            let centre = dist(
                group,
                at(0.5 * (c0 + c1) as f64, 0.5 * (r0 + r1) as f64),
                reach_tile,
            );
            if centre > reach_tile {
                return;
            }
            if centre < -reach_tile {
                total += light(image, w, r0..r1, c0..c1, only_unlit);
                return;
            }
            // Quarters of the tile (4 × 4 pixels) far from the surface are wholly dark or lit the
            // same way, without a look at each pixel: every pixel centre of a quarter lies within
            // 1.5·√2 pixels of the quarter's centre.
            let reach_quarter = (1.5 * std::f64::consts::SQRT_2 + FRAC_1_SQRT_2) * px;
            for (qr0, qc0) in [
                (r0, c0),
                (r0, c0 + HALF),
                (r0 + HALF, c0),
                (r0 + HALF, c0 + HALF),
            ] {
                let (qr1, qc1) = ((qr0 + HALF).min(r1), (qc0 + HALF).min(c1));
                if qr0 >= qr1 || qc0 >= qc1 {
                    continue;
                }
                if qr1 - qr0 == HALF && qc1 - qc0 == HALF {
                    // Values beyond the reach asked for may come back as ±reach: ask for more.
                    let d = dist(
                        group,
                        at((qc0 + HALF / 2) as f64, (qr0 + HALF / 2) as f64),
                        reach_tile,
                    );
                    if d > reach_quarter {
                        continue;
                    }
                    if d < -reach_quarter {
                        total += light(image, w, qr0..qr1, qc0..qc1, only_unlit);
                        continue;
                    }
                }
                for r in qr0..qr1 {
                    for c in qc0..qc1 {
                        let before = image[r * w + c];
                        if only_unlit && before >= LIT {
                            continue;
                        }
                        let q = at(c as f64 + 0.5, r as f64 + 0.5);
                        values.clear();
                        values.extend(group.iter().map(|en| piece(en, q, px)));
                        let d = values.iter().copied().fold(f64::INFINITY, f64::min);
                        let grey = if d >= FRAC_1_SQRT_2 * px {
                            0
                        } else if d <= -FRAC_1_SQRT_2 * px {
                            255
                        } else {
                            // The sub-pixel centres lie within 0.375·√2 < 0.55 pixel of the pixel's:
                            // a piece more than 1.1 pixels farther than the nearest at the centre is
                            // never the nearest at one of them.
                            near.clear();
                            near.extend(
                                group
                                    .iter()
                                    .zip(&values)
                                    .filter(|&(_, &v)| v <= d + 1.1 * px)
                                    .map(|(en, _)| *en),
                            );
                            (255.0 * fine(&|p| dist(&near, p, px), q, px)).round() as u8
                        };
                        // A support only brightens what the part leaves unlit.
                        if grey > before {
                            image[r * w + c] = grey;
                            total += (grey - before) as u64;
                        }
                    }
                }
            }
        };
        if !part.is_empty() {
            paint(&part, false);
        }
        if !held.is_empty() {
            paint(&held, true);
        }
    }
    total as f64 / 255.0 * px * px
}

/// Lights the block of `rows` × `cols` of an image `width` wide (`only_unlit`: only its pixels
/// under `LIT`); returns the grey added.
fn light(
    image: &mut [u8],
    width: usize,
    rows: Range<usize>,
    cols: Range<usize>,
    only_unlit: bool,
) -> u64 {
    let mut added = 0u64;
    for r in rows {
        for v in &mut image[r * width + cols.start..r * width + cols.end] {
            if !only_unlit || *v < LIT {
                added += 255 - *v as u64;
                *v = 255;
            }
        }
    }
    added
}

/// Sub-pixels per pixel side in `fine`.
const SUB: usize = 4;

/// The part of the pixel inside, from the distance at the centres of its 4 × 4 sub-pixels: each
/// sub-pixel's edge is straight, at its centre's distance over the gradient there (second-order
/// differences of the neighbouring centres' values), so an edge that bends or meets another
/// within the pixel is followed to a quarter pixel.
fn fine(dist: &dyn Fn(DVec3) -> f64, q: DVec3, side: f64) -> f64 {
    let mut at = [[0.0f64; SUB]; SUB];
    for (i, row) in at.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            let u = DVec3::new(
                ((i as f64 + 0.5) / SUB as f64 - 0.5) * side,
                ((j as f64 + 0.5) / SUB as f64 - 0.5) * side,
                0.0,
            );
            // In sub-pixels.
            *v = dist(q + u) / side * SUB as f64;
        }
    }
    // The derivative at k of values f along a row of SUB, one sub-pixel apart.
    let slope = |f: [f64; SUB], k: usize| match k {
        0 => 0.5 * (-3.0 * f[0] + 4.0 * f[1] - f[2]),
        k if k == SUB - 1 => 0.5 * (3.0 * f[k] - 4.0 * f[k - 1] + f[k - 2]),
        k => 0.5 * (f[k + 1] - f[k - 1]),
    };
    let mut sum = 0.0;
    for i in 0..SUB {
        for j in 0..SUB {
            let g = DVec2::new(slope(at.map(|r| r[j]), i), slope(at[i], j));
            sum += covered(at[i][j], g);
        }
    }
    sum / (SUB * SUB) as f64
}

/// A quarter turn about z, (x, y) → (−y, x), when `turned`.
fn turn(v: DVec2, turned: bool) -> DVec2 {
    if turned {
        v.perp()
    } else {
        v
    }
}

/// The turn undone.
fn turn_back(v: DVec2, turned: bool) -> DVec2 {
    if turned {
        DVec2::new(v.y, -v.x)
    } else {
        v
    }
}

/// The part of a unit pixel covered by the solid when its centre is `d` pixels from the surface
/// (3D, positive outside) and the distance's in-plane gradient is `g`: the section's edge taken
/// as a straight line `d / |g|` pixels from the centre, normal to `g`.
fn covered(d: f64, g: DVec2) -> f64 {
    let len = g.length();
    if len.is_nan() || len <= 1e-9 {
        // The surface lies in the plane here: the pixel is on the side its centre is.
        return if d < 0.0 { 1.0 } else { 0.0 };
    }
    // The covered part is {u : n·u ≤ t} of the square [−½, ½]², n the unit edge normal.
    let t = -d / len;
    let (a, b) = ((g.x / len).abs(), (g.y / len).abs());
    let (big, small) = (a.max(b), a.min(b));
    let (inner, outer) = (0.5 * (big - small), 0.5 * (big + small));
    if t >= outer {
        1.0
    } else if t <= -outer {
        0.0
    } else if t.abs() <= inner {
        0.5 + t / big
    } else if t > 0.0 {
        1.0 - (outer - t).powi(2) / (2.0 * big * small)
    } else {
        (outer + t).powi(2) / (2.0 * big * small)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Area of the unit pixel under {u : n·u ≤ t} by fine sampling.
    fn sampled(n: DVec2, t: f64) -> f64 {
        let k = 400;
        let mut inside = 0;
        for i in 0..k {
            for j in 0..k {
                let u = DVec2::new(
                    (i as f64 + 0.5) / k as f64 - 0.5,
                    (j as f64 + 0.5) / k as f64 - 0.5,
                );
                if n.dot(u) <= t {
                    inside += 1;
                }
            }
        }
        inside as f64 / (k * k) as f64
    }

    #[test]
    fn a_straight_edge_covers_its_exact_area_at_any_angle() {
        for deg in [0.0f64, 10.0, 30.0, 45.0, 63.0, 90.0, 200.0] {
            let n = DVec2::new(deg.to_radians().cos(), deg.to_radians().sin());
            for t in [-0.8, -0.6, -0.3, 0.0, 0.2, 0.45, 0.7] {
                // d = −t with a unit gradient; halving the gradient doubles the in-plane distance.
                let want = sampled(n, t);
                assert!((covered(-t, n) - want).abs() < 3e-3, "{deg}° t {t}");
                assert!((covered(-t * 0.5, n * 0.5) - want).abs() < 3e-3);
            }
        }
    }
}
