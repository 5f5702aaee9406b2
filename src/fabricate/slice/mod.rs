//! Slicing closed meshes into the anti-aliased layer images a masked-SLA (DMP-SL) printer
//! shows, one per layer.
//!
//! Models sit on the build plate (their lowest point at z = 0) and are arranged side by side on
//! the display without overlap, or kept where they are (`keep_position`). Layer i is cut at
//! its middle height, (i + ½)·layer. Each triangle that crosses the plane gives one directed
//! segment (the solid on its left seen from above, from the triangle's winding), the segments of
//! all models are rasterised by exact area coverage (`raster`), and the non-zero rule fills the
//! image: overlapping closed shells need no union. Image row 0 is the far edge of the plate
//! (largest y), column 0 its left edge, as PrusaSlicer draws them. The layers, in order, are
//! where `islands` looks for regions that start in free resin.

mod grey;
pub mod islands;
mod raster;
pub mod shapes;
pub mod supports;

use std::ops::Range;
use std::path::PathBuf;

use crate::text::num;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::geom::mix64 as mix;
use crate::mesh::TriMesh;
use shapes::{Placed, Plate};

pub use grey::encode_grey;
pub use raster::Coverage;

/// A masked-SLA printer: its display and its motion.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Printer {
    pub name: String,
    /// Display resolution, pixels.
    pub pixels_x: u32,
    pub pixels_y: u32,
    /// Pixel size, mm (square pixels).
    pub pixel_mm: f64,
    pub layer_mm: f64,
    pub exposure_s: f64,
    pub bottom_exposure_s: f64,
    pub bottom_layers: u32,
    /// Peel: the plate rises this far after each layer and comes back down.
    pub lift_mm: f64,
    pub lift_speed_mm_min: f64,
    pub retract_speed_mm_min: f64,
    /// Wait before each exposure, s.
    pub settle_s: f64,
    pub max_height_mm: f64,
}

impl Default for Printer {
    /// The DMP-SL printer Peele used (§3.2.1): 1920 × 1080 pixels of 35 µm, 50 µm layers; the
    /// motion is set so the model gives his 25 mm/h (7.2 s a layer).
    fn default() -> Self {
        Printer {
            name: "dmp-sl".into(),
            pixels_x: 1920,
            pixels_y: 1080,
            pixel_mm: 0.035,
            layer_mm: 0.05,
            exposure_s: 3.0,
            bottom_exposure_s: 20.0,
            bottom_layers: 3,
            lift_mm: 4.0,
            lift_speed_mm_min: 120.0,
            retract_speed_mm_min: 120.0,
            settle_s: 0.2,
            max_height_mm: 100.0,
        }
    }
}

/// The largest factor a model `size` mm across can be scaled by and still print on
/// `printer`: on the display either way round, a pixel clear of each side, and under the
/// printer's height. Infinite for a model of no size.
pub fn fitting_scale(size: DVec3, printer: &Printer) -> f64 {
    let area = printer.area() - DVec2::splat(2.0 * printer.pixel_mm);
    let within = |w: f64, h: f64| (area.x / w).min(area.y / h);
    let flat = within(size.x, size.y).max(within(size.y, size.x));
    flat.min(printer.max_height_mm / size.z)
}

impl Printer {
    /// The display, mm.
    pub fn area(&self) -> DVec2 {
        DVec2::new(self.pixels_x as f64, self.pixels_y as f64) * self.pixel_mm
    }

    /// Every field in its range; an error names the field (`layer_mm`, …).
    pub fn check(&self) -> Result<(), SliceError> {
        let bad = |field: &'static str, msg: String| Err(SliceError::Printer { field, msg });
        // (field, value, least, most): lengths from 1 µm, no machine needs more than the most.
        let ranged = [
            ("pixel_mm", self.pixel_mm, 1e-3, 10.0),
            ("layer_mm", self.layer_mm, 1e-3, 10.0),
            ("lift_speed_mm_min", self.lift_speed_mm_min, 1e-3, 1e5),
            ("retract_speed_mm_min", self.retract_speed_mm_min, 1e-3, 1e5),
            ("max_height_mm", self.max_height_mm, 1e-3, 1e4),
            ("exposure_s", self.exposure_s, 0.0, 3600.0),
            ("bottom_exposure_s", self.bottom_exposure_s, 0.0, 3600.0),
            ("lift_mm", self.lift_mm, 0.0, 1000.0),
            ("settle_s", self.settle_s, 0.0, 3600.0),
        ];
        for (field, v, least, most) in ranged {
            if !(least..=most).contains(&v) {
                return bad(
                    field,
                    format!(
                        "must be from {} to {}, got {}",
                        num(least),
                        num(most),
                        num(v)
                    ),
                );
            }
        }
        if self.pixels_x == 0
            || self.pixels_y == 0
            || self.pixels_x > 16384
            || self.pixels_y > 16384
        {
            return bad(
                "pixels_x",
                format!(
                    "the display must be 1..16384 pixels each way, got {} × {}",
                    self.pixels_x, self.pixels_y
                ),
            );
        }
        if self.bottom_layers > MAX_LAYERS as u32 {
            return bad(
                "bottom_layers",
                format!("must be at most {MAX_LAYERS}, got {}", self.bottom_layers),
            );
        }
        Ok(())
    }

    /// Seconds to print `layers` layers by the exposure and peel model.
    pub fn build_seconds(&self, layers: usize) -> f64 {
        let bottom = (self.bottom_layers as usize).min(layers);
        let peel = 60.0
            * (self.lift_mm / self.lift_speed_mm_min + self.lift_mm / self.retract_speed_mm_min);
        bottom as f64 * self.bottom_exposure_s
            + (layers - bottom) as f64 * self.exposure_s
            + layers as f64 * (peel + self.settle_s)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SliceError {
    #[error("printer {field}: {msg}")]
    Printer { field: &'static str, msg: String },
    #[error("{}: {height:.2} mm tall at {layer} mm layers is {layers} layers, more than {MAX_LAYERS}", path.display())]
    TooManyLayers {
        path: PathBuf,
        height: f64,
        layer: f64,
        layers: f64,
    },
    #[error("{}: the mesh has no triangles", .0.display())]
    Empty(PathBuf),
    #[error(
        "{}: not a closed mesh: {count} edge(s) are not matched by an edge running the other \
         way (one from {a:?} to {b:?}); the slicer needs closed shells (corners a hair apart, \
         as CAD exports leave them, are joined by weld= MM)",
        path.display()
    )]
    Open {
        path: PathBuf,
        count: usize,
        a: [f64; 3],
        b: [f64; 3],
    },
    #[error(
        "{}: {size_x:.2} × {size_y:.2} mm does not fit the {area_x:.2} × {area_y:.2} mm \
         display; scaled by {fits_at:.4} or less it would ({hint})",
        path.display()
    )]
    TooBig {
        path: PathBuf,
        size_x: f64,
        size_y: f64,
        area_x: f64,
        area_y: f64,
        /// The largest factor at which it fits ([`fitting_scale`]).
        fits_at: f64,
        /// The option that scales it (`scale=` for meshes).
        hint: &'static str,
    },
    #[error(
        "{}: {height:.2} mm tall; the printer builds at most {max:.2} mm; scaled by \
         {fits_at:.4} or less it would ({hint})",
        path.display()
    )]
    TooTall {
        path: PathBuf,
        height: f64,
        max: f64,
        /// The largest factor at which it fits ([`fitting_scale`]).
        fits_at: f64,
        /// The option that scales it (`scale=` for meshes).
        hint: &'static str,
    },
    #[error(
        "{placed} of {wanted} models fit side by side on the {area_x:.2} × {area_y:.2} mm \
         display ({gap} mm apart); ask for fewer copies or a smaller gap"
    )]
    Crowded {
        placed: usize,
        wanted: usize,
        area_x: f64,
        area_y: f64,
        gap: f64,
    },
    #[error("{}: lies outside the display at its own position (x {x0:.2}..{x1:.2}, y {y0:.2}..{y1:.2} mm)", path.display())]
    Outside {
        path: PathBuf,
        x0: f64,
        x1: f64,
        y0: f64,
        y1: f64,
    },
}

/// A model to print and where its file came from (for messages and the report).
pub struct Model {
    pub path: PathBuf,
    pub mesh: TriMesh,
}

/// One copy of a model on the plate: turn it a quarter turn about z if `turned` ((x, y) →
/// (−y, x)), then add `offset` to its vertices.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Placement {
    pub model: usize,
    pub copy: usize,
    pub turned: bool,
    pub offset: [f64; 3],
    /// Footprint on the plate, mm.
    pub min: [f64; 2],
    pub max: [f64; 2],
}

/// Checks every model is a closed shell and fits, and places `copies` of each on the plate:
/// in rows, left to right, `gap` mm apart, the whole group centred (all turned a quarter turn
/// when only that fits them all); or each where it is.
pub fn arrange(
    models: &[Model],
    printer: &Printer,
    copies: usize,
    gap: f64,
    keep_position: bool,
) -> Result<Vec<Placement>, SliceError> {
    arrange_held(models, &[], printer, copies, gap, keep_position)
}

/// [`arrange`] with each model's supports: `supports[k]`, when there, widens model k's box.
pub fn arrange_held(
    models: &[Model],
    supports: &[Option<Placed>],
    printer: &Printer,
    copies: usize,
    gap: f64,
    keep_position: bool,
) -> Result<Vec<Placement>, SliceError> {
    let mut boxes = Vec::with_capacity(models.len());
    for (k, m) in models.iter().enumerate() {
        check_closed(m)?;
        let b = m.mesh.bbox();
        let (lo, hi) = match supports.get(k) {
            Some(Some(s)) => {
                let (lo, hi) = s.bounds();
                (b.min.min(lo), b.max.max(hi))
            }
            _ => (b.min, b.max),
        };
        boxes.push((m.path.as_path(), lo, hi));
    }
    arrange_boxes(&boxes, printer, copies, gap, keep_position)
}

/// Checks a model has triangles and is a closed shell.
pub fn check_closed(m: &Model) -> Result<(), SliceError> {
    if m.mesh.triangles.is_empty() {
        return Err(SliceError::Empty(m.path.clone()));
    }
    closed(m)
}

/// The same for models known by their boxes: (file, lowest corner, highest corner).
pub fn arrange_boxes(
    boxes: &[(&std::path::Path, DVec3, DVec3)],
    printer: &Printer,
    copies: usize,
    gap: f64,
    keep_position: bool,
) -> Result<Vec<Placement>, SliceError> {
    let area = printer.area();
    for &(path, lo, hi) in boxes {
        let size = hi - lo;
        if size.z > printer.max_height_mm {
            return Err(SliceError::TooTall {
                path: path.to_path_buf(),
                height: size.z,
                max: printer.max_height_mm,
                fits_at: fitting_scale(size, printer),
                hint: "scale=",
            });
        }
        let layers = size.z / printer.layer_mm;
        if layers > MAX_LAYERS as f64 {
            return Err(SliceError::TooManyLayers {
                path: path.to_path_buf(),
                height: size.z,
                layer: printer.layer_mm,
                layers: layers.ceil(),
            });
        }
        let fits = |w: f64, h: f64| w <= area.x && h <= area.y;
        if !fits(size.x, size.y) && (keep_position || !fits(size.y, size.x)) {
            return Err(SliceError::TooBig {
                path: path.to_path_buf(),
                size_x: size.x,
                size_y: size.y,
                area_x: area.x,
                area_y: area.y,
                fits_at: fitting_scale(size, printer),
                hint: "scale=",
            });
        }
    }
    if keep_position {
        let mut placed = Vec::new();
        for (k, &(path, lo, hi)) in boxes.iter().enumerate() {
            if lo.x < 0.0 || lo.y < 0.0 || hi.x > area.x || hi.y > area.y {
                return Err(SliceError::Outside {
                    path: path.to_path_buf(),
                    x0: lo.x,
                    x1: hi.x,
                    y0: lo.y,
                    y1: hi.y,
                });
            }
            placed.push(Placement {
                model: k,
                copy: 0,
                turned: false,
                offset: [0.0, 0.0, -lo.z],
                min: [lo.x, lo.y],
                max: [hi.x, hi.y],
            });
        }
        return Ok(placed);
    }
    let boxes: Vec<(DVec3, DVec3)> = boxes.iter().map(|&(_, lo, hi)| (lo, hi)).collect();
    match shelves(&boxes, copies, gap, area, printer.pixel_mm, false) {
        Ok(p) => Ok(p),
        Err(straight) => {
            shelves(&boxes, copies, gap, area, printer.pixel_mm, true).map_err(|turned| {
                {
                    // Report the way that placed more.
                    if turned.0 > straight.0 {
                        turned
                    } else {
                        straight
                    }
                }
                .into_error(boxes.len() * copies, area, gap)
            })
        }
    }
}

/// How many models had been placed when the plate ran out.
struct Short(usize);

impl Short {
    fn into_error(self, wanted: usize, area: DVec2, gap: f64) -> SliceError {
        SliceError::Crowded {
            placed: self.0,
            wanted,
            area_x: area.x,
            area_y: area.y,
            gap,
        }
    }
}

/// Rows of footprints, left to right, then the whole group centred on the display.
fn shelves(
    boxes: &[(DVec3, DVec3)],
    copies: usize,
    gap: f64,
    area: DVec2,
    pixel: f64,
    turned: bool,
) -> Result<Vec<Placement>, Short> {
    let mut placed = Vec::new();
    let (mut x, mut y, mut row) = (0.0f64, 0.0f64, 0.0f64);
    let mut used = DVec2::ZERO;
    for (k, &(lo, hi)) in boxes.iter().enumerate() {
        // The footprint's corner and size as placed: a quarter turn maps (x, y) to (−y, x).
        let (corner, size) = if turned {
            (
                DVec2::new(-hi.y, lo.x),
                DVec2::new(hi.y - lo.y, hi.x - lo.x),
            )
        } else {
            (lo.truncate(), (hi - lo).truncate())
        };
        for copy in 0..copies {
            if x > 0.0 && x + size.x > area.x {
                (x, y, row) = (0.0, y + row + gap, 0.0);
            }
            if x + size.x > area.x || y + size.y > area.y {
                return Err(Short(placed.len()));
            }
            placed.push(Placement {
                model: k,
                copy,
                turned,
                offset: [x - corner.x, y - corner.y, -lo.z],
                min: [x, y],
                max: [x + size.x, y + size.y],
            });
            used = used.max(DVec2::new(x + size.x, y + size.y));
            x += size.x + gap;
            row = row.max(size.y);
        }
    }
    let shift = (area - used) / 2.0;
    for p in &mut placed {
        // Each model's origin on a pixel corner, where the supports were planned, unless that
        // would push it off the display.
        let mut at = DVec2::new(p.offset[0], p.offset[1]) + shift;
        let snapped = (at / pixel).round() * pixel;
        let moved = snapped - at;
        let (lo, hi) = (
            DVec2::from(p.min) + shift + moved,
            DVec2::from(p.max) + shift + moved,
        );
        let d = if lo.min_element() >= 0.0 && hi.x <= area.x && hi.y <= area.y {
            at = snapped;
            shift + moved
        } else {
            shift
        };
        p.offset[0] = at.x;
        p.offset[1] = at.y;
        p.min = [p.min[0] + d.x, p.min[1] + d.y];
        p.max = [p.max[0] + d.x, p.max[1] + d.y];
    }
    Ok(placed)
}

/// Every edge must be used as often in one direction as in the other, edges being told apart by
/// where their ends are (so a triangle soup from an STL needs no welding). First a one-pass
/// test: the sum over half-edges of ±hash(edge) is zero when every edge is balanced, and a
/// nonzero balance leaves it zero only by a 64-bit hash coincidence. Only when it is not zero are
/// the half-edges sorted to name an open edge.
fn closed(m: &Model) -> Result<(), SliceError> {
    let key = |i: u32| point_key(m.mesh.positions[i as usize]);
    let signature = m
        .mesh
        .triangles
        .par_iter()
        .map(|t| {
            (0..3).fold(0u64, |sum, j| {
                let (a, b) = (key(t[j]), key(t[(j + 1) % 3]));
                let h = mix(mix(a.min(b)) ^ a.max(b).rotate_left(17));
                if a < b {
                    sum.wrapping_add(h)
                } else {
                    sum.wrapping_sub(h)
                }
            })
        })
        .reduce(|| 0, u64::wrapping_add);
    if signature == 0 {
        return Ok(());
    }
    open_edge(m)
}

/// A point as one 64-bit number that equal points share: a mix of its coordinates' bits.
fn point_key(p: DVec3) -> u64 {
    let bits = |v: f64| (v + 0.0).to_bits();
    mix(bits(p.x) ^ mix(bits(p.y) ^ mix(bits(p.z))))
}

/// The open edges, found by sorting the half-edges by their ends' coordinates: how many, and
/// one of them.
fn open_edge(m: &Model) -> Result<(), SliceError> {
    type Point = [u64; 3];
    let point = |i: u32| {
        m.mesh.positions[i as usize]
            .to_array()
            .map(|v| (v + 0.0).to_bits())
    };
    let mut half: Vec<(Point, Point, i8)> = m
        .mesh
        .triangles
        .par_iter()
        .flat_map_iter(|t| {
            (0..3).map(move |j| {
                let (a, b) = (point(t[j]), point(t[(j + 1) % 3]));
                if a < b {
                    (a, b, 1)
                } else {
                    (b, a, -1)
                }
            })
        })
        .collect();
    half.par_sort_unstable();
    let mut open = 0usize;
    let mut first = None;
    let mut s = 0;
    while s < half.len() {
        let (a, b) = (half[s].0, half[s].1);
        let mut balance = 0i64;
        while s < half.len() && half[s].0 == a && half[s].1 == b {
            balance += half[s].2 as i64;
            s += 1;
        }
        if balance != 0 {
            open += 1;
            first.get_or_insert((a, b));
        }
    }
    let at = |p: Point| DVec3::from_array(p.map(f64::from_bits)).to_array();
    match first {
        None => Ok(()),
        Some((a, b)) => Err(SliceError::Open {
            path: m.path.clone(),
            count: open,
            a: at(a),
            b: at(b),
        }),
    }
}

/// A finished layer.
pub struct Layer {
    pub index: usize,
    /// Grey PNG, display-sized.
    pub png: Vec<u8>,
    /// The same image, row-major, one byte a pixel.
    pub image: Vec<u8>,
    /// Area as the image shows it (Σ grey/255 × pixel area), mm².
    pub area_mm2: f64,
    /// Area enclosed by the section's contours, mm², when the layer was cut from a mesh.
    pub exact_area_mm2: Option<f64>,
}

/// Which triangles cross each layer plane, per model.
pub(super) struct LayerIndex {
    start: Vec<u32>,
    triangles: Vec<u32>,
}

impl LayerIndex {
    pub(super) fn new(mesh: &TriMesh, z0: f64, layer: f64, layers: usize) -> Self {
        // Layer i is cut at (i + ½)·layer; a triangle crosses it when min z ≤ cut < max z.
        let range = |t: &[u32; 3]| {
            let zs = t.map(|i| mesh.positions[i as usize].z - z0);
            let lo = zs[0].min(zs[1]).min(zs[2]);
            let hi = zs[0].max(zs[1]).max(zs[2]);
            // One layer wider each way than the arithmetic says: `cut` decides exactly, and a
            // rounding here must not drop a triangle that crosses.
            let first = ((lo / layer - 0.5).ceil() - 1.0).max(0.0) as usize;
            let last = ((hi / layer - 0.5).ceil() as i64).min(layers as i64 - 1);
            (first, last)
        };
        let mut start = vec![0u32; layers + 1];
        for t in &mesh.triangles {
            let (a, b) = range(t);
            for i in a as i64..=b {
                start[i as usize + 1] += 1;
            }
        }
        for i in 0..layers {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut triangles = vec![0u32; start[layers] as usize];
        for (k, t) in mesh.triangles.iter().enumerate() {
            let (a, b) = range(t);
            for i in a as i64..=b {
                triangles[fill[i as usize] as usize] = k as u32;
                fill[i as usize] += 1;
            }
        }
        LayerIndex { start, triangles }
    }

    fn layer(&self, i: usize) -> &[u32] {
        &self.triangles[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// The most layers a job may have: 5 m at 0.05 mm. Each layer is a full display image.
pub const MAX_LAYERS: usize = 100_000;

/// How many layers the placed models need.
pub fn layer_count(models: &[Model], printer: &Printer) -> usize {
    let height = models
        .iter()
        .map(|m| m.mesh.bbox().size().z)
        .fold(0.0, f64::max);
    layers_for(height, printer.layer_mm)
}

/// Layers a model `height` mm tall takes at `layer` mm: those whose middle, where each layer
/// is sampled, lies below its top (at least one). A layer above that would be empty: a mesh
/// 1.2 µm over a whole number of layers gets no blank last layer.
pub fn layers_for(height: f64, layer: f64) -> usize {
    (height / layer - 0.5).ceil().max(1.0) as usize
}

/// Slices the placed models and hands each layer, in order, to `sink`. Layers are made in
/// parallel batches, so memory stays at a few dozen images.
pub fn slice<E>(
    models: &[Model],
    placed: &[Placement],
    printer: &Printer,
    sink: impl FnMut(Layer) -> Result<(), E>,
) -> Result<usize, E> {
    slice_held(models, &[], placed, printer, sink)
}

/// [`slice()`] with each model's supports (`supports[k]` for model k, in its frame with its
/// lowest point at z = 0, as [`supports::plan_mesh`] plans them), drawn after the meshes where
/// they leave pixels unlit.
pub fn slice_held<E>(
    models: &[Model],
    supports: &[Option<Placed>],
    placed: &[Placement],
    printer: &Printer,
    mut sink: impl FnMut(Layer) -> Result<(), E>,
) -> Result<usize, E> {
    let layers = layer_count(models, printer);
    let indices: Vec<LayerIndex> = models
        .par_iter()
        .map(|m| LayerIndex::new(&m.mesh, m.mesh.bbox().min.z, printer.layer_mm, layers))
        .collect();
    // Each model's supports where its copies stand, made once for every layer.
    let copies: Vec<Vec<Placement>> = (0..supports.len())
        .map(|k| placed.iter().filter(|p| p.model == k).copied().collect())
        .collect();
    let plates: Vec<Plate> = supports
        .iter()
        .zip(&copies)
        .filter_map(|(held, copies)| held.as_ref().map(|h| Plate::new(h, copies)))
        .collect();
    in_batches(
        layers,
        |i| layer(models, &plates, placed, &indices, printer, i),
        |_, l| sink(l),
    )?;
    Ok(layers)
}

/// Makes items `0..count` in parallel batches of a few per thread and hands each, in order, to
/// `sink`: layers are made on every core while memory stays at a few dozen images. The next
/// batch is made while `sink` takes the last one, so a slow sink (islands, the archive) does
/// not leave the cores idle.
pub fn in_batches<T: Send, E>(
    count: usize,
    make: impl Fn(usize) -> T + Sync,
    mut sink: impl FnMut(usize, T) -> Result<(), E>,
) -> Result<(), E> {
    let batch = 4 * rayon::current_num_threads().max(1);
    let make = &make;
    let run = |items: Range<usize>| -> Vec<T> { items.into_par_iter().map(make).collect() };
    std::thread::scope(|scope| {
        let mut start = 0;
        let mut done = run(0..batch.min(count));
        while !done.is_empty() {
            let next = start + done.len();
            let making = (next < count).then(|| {
                let items = next..(next + batch).min(count);
                scope.spawn(move || run(items))
            });
            for (k, item) in done.into_iter().enumerate() {
                sink(start + k, item)?;
            }
            start = next;
            done = match making {
                Some(thread) => thread
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
                None => Vec::new(),
            };
        }
        Ok(())
    })
}

fn layer(
    models: &[Model],
    supports: &[Plate],
    placed: &[Placement],
    indices: &[LayerIndex],
    printer: &Printer,
    i: usize,
) -> Layer {
    let px = printer.pixel_mm;
    let (w, h) = (printer.pixels_x as usize, printer.pixels_y as usize);
    let mut image = vec![0u8; w * h];
    let sections = placed
        .iter()
        .map(|p| (&models[p.model].mesh, &indices[p.model], p));
    let (area_px, exact) = sections_onto(sections, printer, i, &mut image);
    let mut area_mm2 = area_px * px * px;
    // Supports after the parts, where they leave pixels unlit.
    for plate in supports {
        area_mm2 += shapes::image_onto(plate, printer, i, &mut image);
    }
    Layer {
        index: i,
        png: encode_grey(&image, w as u32, h as u32),
        image,
        area_mm2,
        exact_area_mm2: Some(exact),
    }
}

/// Draws layer `i`'s sections of placed meshes onto `image` (a whole display's, row-major; its
/// pixels are set, not added to): (covered pixels, area inside the contours in mm²).
pub(super) fn sections_onto<'m>(
    sections: impl Iterator<Item = (&'m TriMesh, &'m LayerIndex, &'m Placement)>,
    printer: &Printer,
    i: usize,
    image: &mut [u8],
) -> (f64, f64) {
    let z = (i as f64 + 0.5) * printer.layer_mm;
    let px = printer.pixel_mm;
    let (w, h) = (printer.pixels_x as usize, printer.pixels_y as usize);
    let mut segments: Vec<[[f64; 2]; 2]> = Vec::new();
    let mut exact = 0.0;
    for (mesh, index, p) in sections {
        let off = DVec3::from_array(p.offset);
        let z_model = z - off.z;
        for &t in index.layer(i) {
            if let Some([a, b]) = cut(mesh, mesh.triangles[t as usize], z_model) {
                let turn = |q: DVec2| if p.turned { q.perp() } else { q };
                let (a, b) = (turn(a) + off.truncate(), turn(b) + off.truncate());
                exact += 0.5 * a.perp_dot(b);
                // Pixels: x right from the left edge, y down from the far edge.
                let pix = |q: DVec2| [q.x / px, h as f64 - q.y / px];
                segments.push([pix(a), pix(b)]);
            }
        }
    }
    let mut area_px = 0.0;
    if !segments.is_empty() {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for s in &segments {
            for q in s {
                lo = [lo[0].min(q[0]), lo[1].min(q[1])];
                hi = [hi[0].max(q[0]), hi[1].max(q[1])];
            }
        }
        let c0 = (lo[0].floor() as i64).max(0);
        let r0 = (lo[1].floor() as i64).max(0);
        let c1 = (hi[0].ceil() as i64).min(w as i64);
        let r1 = (hi[1].ceil() as i64).min(h as i64);
        let mut cov = Coverage::new(c0, r0, (c1 - c0).max(1) as usize, (r1 - r0).max(1) as usize);
        for s in &segments {
            cov.add(s);
        }
        area_px = cov.write(image, w);
    }
    (area_px, exact.abs())
}

/// The segment where triangle `t` crosses the plane at height `z`, directed so the solid is on
/// its left seen from above: from where the boundary a → b → c goes down through the plane to
/// where it goes up. A vertex exactly on the plane counts as below, in every triangle alike, so
/// segments meet end to end.
fn cut(mesh: &TriMesh, t: [u32; 3], z: f64) -> Option<[DVec2; 2]> {
    let above = t.map(|i| mesh.positions[i as usize].z > z);
    if above[0] == above[1] && above[1] == above[2] {
        return None;
    }
    let (mut down, mut up) = (None, None);
    for j in 0..3 {
        let (a, b) = (t[j], t[(j + 1) % 3]);
        match (above[j], above[(j + 1) % 3]) {
            (true, false) => down = Some(crossing(mesh, a, b, z)),
            (false, true) => up = Some(crossing(mesh, a, b, z)),
            _ => {}
        }
    }
    Some([down?, up?])
}

/// Where edge a–b crosses height `z`, computed the same way from either triangle that shares
/// the edge (ends in coordinate order, so welded or not), so neighbouring segments meet exactly.
fn crossing(mesh: &TriMesh, a: u32, b: u32, z: f64) -> DVec2 {
    let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
    let (p, q) = if pa.to_array() < pb.to_array() {
        (pa, pb)
    } else {
        (pb, pa)
    };
    let t = (z - p.z) / (q.z - p.z);
    p.truncate().lerp(q.truncate(), t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_layer_is_counted_only_when_its_middle_is_below_the_top() {
        // 20 layers and 1.2 µm: the 21st layer's middle (1.025) is above the top.
        assert_eq!(layers_for(1.0012, 0.05), 20);
        assert_eq!(layers_for(1.0, 0.05), 20);
        assert_eq!(layers_for(1.026, 0.05), 21);
        assert_eq!(layers_for(4.6, 0.05), 92);
        assert_eq!(layers_for(0.01, 0.05), 1);
    }

    #[test]
    fn batches_reach_the_sink_in_order_and_stop_at_its_first_error() {
        for count in [0, 1, 7, 8, 9, 50] {
            let mut seen = Vec::new();
            in_batches(
                count,
                |i| i * i,
                |i, item| {
                    seen.push((i, item));
                    Ok::<(), ()>(())
                },
            )
            .expect("no error");
            assert_eq!(seen, (0..count).map(|i| (i, i * i)).collect::<Vec<_>>());
        }
        let mut taken = 0;
        let stopped = in_batches(
            100,
            |i| i,
            |i, _| {
                taken += 1;
                if i == 20 {
                    Err(i)
                } else {
                    Ok(())
                }
            },
        );
        assert_eq!(stopped, Err(20));
        assert_eq!(taken, 21, "nothing after the error reaches the sink");
    }
}
