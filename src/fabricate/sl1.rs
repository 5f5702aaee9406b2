//! Reading an SL1 archive back to check it, ours or PrusaSlicer's: `config.ini` (the job) and
//! `prusaslicer.ini` (the printer), then every layer image in order: its size against the
//! display, the islands it starts (see `slice::islands`), and the resin it cures (grey/255 ×
//! pixel area × layer height) against `usedMaterial`.
//!
//! What makes a file no SL1 at all (not a zip, no `config.ini`, a key missing or not a number,
//! an image that is not a PNG) is an error; what a printer would print wrongly (a layer
//! missing, an image of the wrong size, islands, resin far from what the job says) is a
//! problem, listed. Sizes are bounded before anything is read: entries, each entry's unpacked
//! size, and each image's pixels.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use rayon::prelude::*;
use thiserror::Error;

use super::slice::islands::{Island, Islands};

/// The most entries an archive may have (100,000 layers and a few more).
pub const MAX_ENTRIES: usize = 100_100;
/// The largest unpacked entry: a 16k × 16k grey image.
pub const MAX_ENTRY_BYTES: u64 = 1 << 28;
/// The most pixels in a layer image.
pub const MAX_PIXELS: u64 = 16_384 * 16_384;
/// The largest `config.ini` or `prusaslicer.ini`.
const MAX_INI_BYTES: u64 = 1 << 20;
/// Islands listed in full; more are counted.
pub const MAX_LISTED: usize = 10_000;
/// How far the resin from the pixels may be from `usedMaterial` before it is a problem: the
/// slicer's figure comes from the mesh, the pixels' from anti-aliased edges.
pub const RESIN_TOLERANCE: f64 = 0.02;

#[derive(Debug, Error)]
pub enum Sl1Error {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not an SL1 archive: {msg}", path.display())]
    NotSl1 {
        path: std::path::PathBuf,
        msg: String,
    },
}

/// What the check found.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Sl1Check {
    pub archive: String,
    /// `config.ini`'s keys and values as written.
    pub config: BTreeMap<String, String>,
    pub printer: BTreeMap<String, String>,
    pub layers: usize,
    pub layer_mm: f64,
    pub pixels: [u32; 2],
    pub pixel_mm: f64,
    /// Resin from the images, mL, and what `usedMaterial` says.
    pub volume_ml: f64,
    pub used_ml: f64,
    pub island_count: usize,
    /// The first `MAX_LISTED` islands.
    pub islands: Vec<Island>,
    /// Layers with no lit pixel.
    pub empty_layers: usize,
    pub problems: Vec<String>,
}

/// Reads and checks the archive at `path`.
pub fn check(path: &Path) -> Result<Sl1Check, Sl1Error> {
    check_layers(path, &mut |_, _, _| {})
}

/// Reads and checks the archive at `path`, handing each layer image that decoded (its index and
/// grey bytes, rows from the top, and the display's width in pixels) to `on_layer`, in order.
pub fn check_layers(
    path: &Path,
    on_layer: &mut dyn FnMut(usize, &[u8], usize),
) -> Result<Sl1Check, Sl1Error> {
    let not = |msg: String| Sl1Error::NotSl1 {
        path: path.to_path_buf(),
        msg,
    };
    let file = std::fs::File::open(path).map_err(|source| Sl1Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut zip =
        zip::ZipArchive::new(file).map_err(|e| not(format!("not a zip archive ({e})")))?;
    if zip.len() > MAX_ENTRIES {
        return Err(not(format!(
            "{} entries, more than {MAX_ENTRIES}",
            zip.len()
        )));
    }
    let listed: std::collections::HashSet<String> = zip
        .file_names()
        .filter_map(|n| n.ok().map(|n| n.into_owned()))
        .collect();
    let mut read = |name: &str, limit: u64| -> Result<Option<Vec<u8>>, Sl1Error> {
        let mut entry = match zip.by_name(name) {
            Ok(e) => e,
            Err(zip::result::ZipError::FileNotFound) => return Ok(None),
            Err(e) => return Err(not(format!("{name}: {e}"))),
        };
        if entry.size() > limit {
            return Err(not(format!(
                "{name} unpacks to {} bytes, more than {limit}",
                entry.size()
            )));
        }
        let mut bytes = Vec::with_capacity(entry.size() as usize);
        entry
            .by_ref()
            .take(limit)
            .read_to_end(&mut bytes)
            .map_err(|e| not(format!("{name}: {e}")))?;
        Ok(Some(bytes))
    };
    let config =
        ini(&read("config.ini", MAX_INI_BYTES)?.ok_or_else(|| not("no config.ini".into()))?);
    let printer = match read("prusaslicer.ini", MAX_INI_BYTES)? {
        Some(b) => ini(&b),
        None => BTreeMap::new(),
    };
    let number = |map: &BTreeMap<String, String>, file: &str, key: &str| -> Result<f64, Sl1Error> {
        let v = map
            .get(key)
            .ok_or_else(|| not(format!("{file} has no {key}")))?;
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite() && *x >= 0.0)
            .ok_or_else(|| not(format!("{file}: {key} = {v} is not a number ≥ 0")))
    };
    let job = config
        .get("jobDir")
        .cloned()
        .ok_or_else(|| not("config.ini has no jobDir".into()))?;
    let layer_mm = number(&config, "config.ini", "layerHeight")?;
    let fast = number(&config, "config.ini", "numFast")?;
    let slow = number(&config, "config.ini", "numSlow")?;
    let used_ml = number(&config, "config.ini", "usedMaterial")?;
    let layers = (fast + slow) as usize;
    if layers > MAX_ENTRIES {
        return Err(not(format!(
            "config.ini says {layers} layers, more than {MAX_ENTRIES}"
        )));
    }
    let px = number(&printer, "prusaslicer.ini", "display_pixels_x")? as u32;
    let py = number(&printer, "prusaslicer.ini", "display_pixels_y")? as u32;
    let width_mm = number(&printer, "prusaslicer.ini", "display_width")?;
    if px == 0 || py == 0 || u64::from(px) * u64::from(py) > MAX_PIXELS || width_mm <= 0.0 {
        return Err(not(format!(
            "prusaslicer.ini: a display of {px} × {py} pixels, {width_mm} mm wide"
        )));
    }
    let pixel_mm = width_mm / px as f64;
    let mut problems = Vec::new();
    if layer_mm <= 0.0 {
        problems.push("layerHeight is 0".to_string());
    }
    let names: Vec<String> = (0..layers).map(|k| format!("{job}{k:05}.png")).collect();
    let extra = listed
        .iter()
        .filter(|n| n.ends_with(".png") && !names.contains(n) && !is_thumbnail(n))
        .count();
    if extra > 0 {
        problems.push(format!(
            "{extra} images beyond the {layers} layers config.ini names"
        ));
    }
    // Layers in batches: read in order, decoded on every core, islands in order.
    let mut finder = Islands::new(px as usize, py as usize, pixel_mm, layer_mm);
    let (mut islands, mut island_count, mut empty, mut grey) = (Vec::new(), 0, 0, 0.0f64);
    let mut missing = Vec::new();
    let batch = 4 * rayon::current_num_threads().max(1);
    for (c, chunk) in names.chunks(batch).enumerate() {
        let packed: Vec<(usize, Option<Vec<u8>>)> = chunk
            .iter()
            .enumerate()
            .map(|(j, n)| Ok((c * batch + j, read(n, MAX_ENTRY_BYTES)?)))
            .collect::<Result<_, Sl1Error>>()?;
        let decoded: Vec<(usize, Decoded)> = packed
            .into_par_iter()
            .map(|(k, bytes)| (k, bytes.map(|b| decode(&b, px, py)).transpose()))
            .collect();
        for (k, image) in decoded {
            match image {
                Err(msg) => return Err(not(format!("{}: {msg}", names[k]))),
                Ok(None) => {
                    missing.push(k);
                    // A missing layer holds nothing up: the next starts afresh.
                    finder.layer_owned(k, vec![0; px as usize * py as usize]);
                }
                Ok(Some(Err(msg))) => {
                    problems.push(format!("{}: {msg}", names[k]));
                    finder.layer_owned(k, vec![0; px as usize * py as usize]);
                }
                Ok(Some(Ok(img))) => {
                    on_layer(k, &img, px as usize);
                    let sum: u64 = img.iter().map(|&g| u64::from(g)).sum();
                    grey += sum as f64 / 255.0;
                    if sum == 0 {
                        empty += 1;
                    }
                    for i in finder.layer_owned(k, img) {
                        island_count += 1;
                        if islands.len() < MAX_LISTED {
                            islands.push(i);
                        }
                    }
                }
            }
        }
    }
    if !missing.is_empty() {
        problems.push(format!(
            "{} of {layers} layer images missing, the first {}",
            missing.len(),
            names[missing[0]]
        ));
    }
    let volume_ml = grey * pixel_mm * pixel_mm * layer_mm / 1000.0;
    if used_ml > 0.0 && ((volume_ml - used_ml) / used_ml).abs() > RESIN_TOLERANCE {
        problems.push(format!(
            "the images cure {volume_ml:.4} mL of resin, usedMaterial says {used_ml:.4} mL"
        ));
    }
    if island_count > 0 {
        let first = &islands[0];
        problems.push(format!(
            "{island_count} islands (regions touching nothing in the layer below), the first at layer {} ({:.2}, {:.2}) mm, {:.3} mm²",
            first.layer, first.x_mm, first.y_mm, first.area_mm2
        ));
    }
    Ok(Sl1Check {
        archive: path.display().to_string(),
        config,
        printer,
        layers,
        layer_mm,
        pixels: [px, py],
        pixel_mm,
        volume_ml,
        used_ml,
        island_count,
        islands,
        empty_layers: empty,
        problems,
    })
}

/// A layer as decoded: Err when it is no PNG, None when it is missing, Some(Err) when it is a
/// PNG of the wrong size.
type Decoded = Result<Option<Result<Vec<u8>, String>>, String>;

/// PrusaSlicer adds preview thumbnails under `thumbnail/`.
fn is_thumbnail(name: &str) -> bool {
    name.starts_with("thumbnail/")
}

/// `key = value` lines (no sections in SL1's ini files).
fn ini(bytes: &[u8]) -> BTreeMap<String, String> {
    String::from_utf8_lossy(bytes)
        .lines()
        .filter_map(|l| {
            let (k, v) = l.split_once('=')?;
            Some((k.trim().to_string(), v.trim().to_string()))
        })
        .collect()
}

/// A layer image as grey bytes: Err(problem) when it is a PNG of the wrong size or kind,
/// Err of the outer result when it is no PNG at all.
fn decode(bytes: &[u8], px: u32, py: u32) -> Result<Result<Vec<u8>, String>, String> {
    if let Some(problem) = crate::files::png_palette_problem(bytes) {
        return Ok(Err(problem));
    }
    crate::files::guarded(|| decode_png(bytes, px, py))?
}

fn decode_png(bytes: &[u8], px: u32, py: u32) -> Result<Result<Vec<u8>, String>, String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    decoder.set_limits(png::Limits {
        bytes: MAX_ENTRY_BYTES as usize,
    });
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("not a PNG ({})", crate::files::png_message(&e)))?;
    let (w, h) = (reader.info().width, reader.info().height);
    if (w, h) != (px, py) {
        return Ok(Err(format!("{w} × {h} pixels, the display is {px} × {py}")));
    }
    let mut buf = vec![0; reader.output_buffer_size().ok_or("too large")?];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("a broken PNG ({})", crate::files::png_message(&e)))?;
    let channels = frame.color_type.samples();
    buf.truncate(frame.buffer_size());
    if channels == 1 {
        return Ok(Ok(buf));
    }
    // Colour images: the grey of their first channel (printers expose by one channel).
    Ok(Ok(buf.chunks(channels).map(|c| c[0]).collect()))
}
