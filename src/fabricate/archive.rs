//! The `.sl1` print archive as PrusaSlicer writes it, so PrusaSlicer, UVtools and the printers
//! that take SL1 files can open it: a zip of `NAME00000.png` … (one grey image per layer),
//! `config.ini` (the job: exposure, layers, material, time) and `prusaslicer.ini` (the printer:
//! display size and pixels, layer height, exposures).
//!
//! The archive is deterministic: entries carry the zip epoch (1980-01-01) and `config.ini`
//! carries no clock time, so the same inputs give the same bytes.

use std::io::{Seek, Write};

use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipWriter};

use crate::fabricate::slice::Printer;

/// What `config.ini` says about the job, known once every layer is sliced.
pub struct Job<'a> {
    pub name: &'a str,
    pub layers: usize,
    pub print_seconds: f64,
    pub used_ml: f64,
    pub material: &'a str,
}

pub struct Sl1Writer<W: Write + Seek> {
    zip: ZipWriter<W>,
    name: String,
}

fn stored() -> SimpleFileOptions {
    SimpleFileOptions::default()
        .compression_method(CompressionMethod::Stored)
        .last_modified_time(DateTime::default())
}

fn deflated() -> SimpleFileOptions {
    SimpleFileOptions::default()
        .compression_method(CompressionMethod::Deflated)
        .last_modified_time(DateTime::default())
}

impl<W: Write + Seek> Sl1Writer<W> {
    /// `name` prefixes the layer images (PrusaSlicer uses the output file's stem).
    pub fn new(out: W, name: &str) -> Self {
        Sl1Writer {
            zip: ZipWriter::new(out),
            name: name.to_string(),
        }
    }

    /// Adds layer `index` (PNG bytes, already compressed: stored as is).
    pub fn layer(&mut self, index: usize, png: &[u8]) -> std::io::Result<()> {
        self.zip
            .start_file(format!("{}{index:05}.png", self.name), stored())?;
        self.zip.write_all(png)
    }

    /// Writes the two ini files and closes the archive.
    pub fn finish(mut self, printer: &Printer, job: &Job) -> std::io::Result<W> {
        self.zip.start_file("config.ini", deflated())?;
        self.zip.write_all(config_ini(printer, job).as_bytes())?;
        self.zip.start_file("prusaslicer.ini", deflated())?;
        self.zip.write_all(printer_ini(printer).as_bytes())?;
        self.zip.finish().map_err(std::io::Error::other)
    }
}

fn config_ini(p: &Printer, job: &Job) -> String {
    let fast = job.layers;
    format!(
        "action = print\n\
         expTime = {exp}\n\
         expTimeFirst = {first}\n\
         expUserProfile = 0\n\
         fileCreationTimestamp = 1980-01-01 at 00:00:00 UTC\n\
         hollow = 0\n\
         jobDir = {name}\n\
         layerHeight = {layer}\n\
         materialName = {material}\n\
         numFade = {fade}\n\
         numFast = {fast}\n\
         numSlow = 0\n\
         printProfile = lamina\n\
         printTime = {time:.6}\n\
         printerModel = SL1\n\
         printerProfile = {printer}\n\
         printerVariant = default\n\
         prusaSlicerVersion = lamina-{version}\n\
         usedMaterial = {used:.6}\n",
        exp = p.exposure_s,
        first = p.bottom_exposure_s,
        name = job.name,
        layer = p.layer_mm,
        material = job.material,
        fade = p.bottom_layers,
        time = job.print_seconds,
        printer = p.name,
        version = env!("CARGO_PKG_VERSION"),
        used = job.used_ml,
    )
}

/// `x` to six decimals, without trailing zeros.
fn mm(x: f64) -> String {
    let s = format!("{x:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The printer and material settings readers look for, in PrusaSlicer's names.
fn printer_ini(p: &Printer) -> String {
    // To the nanometre, as PrusaSlicer writes them: 1080 × 0.035 is 37.8, not 37.800000000000004.
    let w = mm(p.pixels_x as f64 * p.pixel_mm);
    let h = mm(p.pixels_y as f64 * p.pixel_mm);
    let orientation = if p.pixels_x >= p.pixels_y {
        "landscape"
    } else {
        "portrait"
    };
    format!(
        "bed_shape = 0x0,{w}x0,{w}x{h},0x{h}\n\
         display_height = {h}\n\
         display_mirror_x = 0\n\
         display_mirror_y = 0\n\
         display_orientation = {orientation}\n\
         display_pixels_x = {px}\n\
         display_pixels_y = {py}\n\
         display_width = {w}\n\
         exposure_time = {exp}\n\
         faded_layers = {fade}\n\
         initial_exposure_time = {first}\n\
         initial_layer_height = {layer}\n\
         layer_height = {layer}\n\
         max_print_height = {max}\n\
         pad_enable = 0\n\
         printer_model = SL1\n\
         printer_settings_id = {name}\n\
         printer_technology = SLA\n\
         printer_variant = default\n\
         slice_closing_radius = 0\n\
         supports_enable = 0\n",
        px = p.pixels_x,
        py = p.pixels_y,
        exp = p.exposure_s,
        fade = p.bottom_layers,
        first = p.bottom_exposure_s,
        layer = p.layer_mm,
        max = p.max_height_mm,
        name = p.name,
    )
}

#[cfg(test)]
mod tests {
    use super::mm;

    #[test]
    fn display_sizes_are_written_as_people_write_them() {
        assert_eq!(1080.0 * 0.035, 37.800000000000004);
        assert_eq!(mm(1080.0 * 0.035), "37.8");
        assert_eq!(mm(1920.0 * 0.035), "67.2");
        assert_eq!(mm(2560.0 * 0.0473), "121.088");
        assert_eq!(mm(100.0), "100");
        assert_eq!(mm(0.0), "0");
        assert_eq!(mm(0.0000004), "0");
    }
}
