//! What a cut sheet costs in machine time, and what is left of it.
//!
//! Time: cut length over the cutting speed, a pierce time per contour and the etched length
//! over the marking speed, from a table by thickness for a laser and a plasma cutter. The
//! table is JSON the user can replace (`--speeds FILE`); the built-in one holds typical figures
//! for stainless steel (a 3 kW fibre laser with nitrogen, an 85 A air plasma), to be replaced
//! by the shop's own. A thickness between rows takes the next thicker row (the slower one).
//!
//! Remnants: the largest empty rectangles of a sheet, `spacing` clear of every part (a cut
//! there leaves them whole), found on a grid of `REMNANT_CELL` mm: a cell is taken when any
//! part's hull grown by the spacing touches it, so a reported rectangle is free in exact
//! arithmetic. The largest is taken, its cells marked used, and again, while one is at least
//! the minimum size.

use std::path::Path;

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::files::{read_nonempty, utf8_text, ReadError};

/// One thickness's speeds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedRow {
    /// Cutting speed, mm/min.
    pub cut_mm_per_min: f64,
    /// Marking speed, mm/min.
    pub etch_mm_per_min: f64,
    /// Per contour, s.
    pub pierce_s: f64,
    /// mm.
    pub thickness: f64,
}

/// Fields in the order nest.json writes them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedTable {
    pub laser: Vec<SpeedRow>,
    pub material: String,
    pub plasma: Vec<SpeedRow>,
    /// Rapid traverse between contours; tables written before it take the typical figures.
    #[serde(default)]
    pub rapid_mm_per_min: Rapid,
}

/// Rapid traverse speeds, mm/min.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rapid {
    pub laser: f64,
    pub plasma: f64,
}

impl Default for Rapid {
    /// Typical figures: 60 m/min for a fibre laser's gantry, 20 m/min for a plasma table
    /// (acceleration left out).
    fn default() -> Self {
        Rapid {
            laser: 60000.0,
            plasma: 20000.0,
        }
    }
}

const fn row(thickness: f64, cut: f64, pierce: f64, etch: f64) -> SpeedRow {
    SpeedRow {
        thickness,
        cut_mm_per_min: cut,
        pierce_s: pierce,
        etch_mm_per_min: etch,
    }
}

impl Default for SpeedTable {
    fn default() -> Self {
        SpeedTable::typical(true)
    }
}

impl SpeedTable {
    /// Typical figures for stainless steel (a 3 kW fibre laser with nitrogen, an 85 A air
    /// plasma) or carbon steel (the same laser with oxygen from 3 mm, the plasma on mild
    /// steel), to be replaced by the shop's own.
    pub fn typical(stainless: bool) -> SpeedTable {
        if stainless {
            SpeedTable::stainless()
        } else {
            SpeedTable::carbon()
        }
    }

    fn carbon() -> SpeedTable {
        SpeedTable {
            material: "carbon steel (typical figures: replace with the shop's table)".into(),
            laser: vec![
                row(1.0, 32000.0, 0.1, 15000.0),
                row(1.5, 24000.0, 0.2, 15000.0),
                row(2.0, 18000.0, 0.3, 15000.0),
                row(3.0, 4200.0, 0.6, 12000.0),
                row(4.0, 3600.0, 0.8, 12000.0),
                row(5.0, 3100.0, 1.0, 12000.0),
                row(6.0, 2700.0, 1.4, 10000.0),
                row(8.0, 2100.0, 2.0, 10000.0),
                row(10.0, 1500.0, 3.0, 10000.0),
                row(12.0, 1100.0, 4.0, 10000.0),
            ],
            rapid_mm_per_min: Rapid::default(),
            plasma: vec![
                row(1.5, 7500.0, 0.2, 8000.0),
                row(2.0, 7000.0, 0.3, 8000.0),
                row(3.0, 5700.0, 0.3, 8000.0),
                row(4.0, 4800.0, 0.4, 8000.0),
                row(5.0, 4100.0, 0.5, 8000.0),
                row(6.0, 3400.0, 0.6, 8000.0),
                row(8.0, 2600.0, 0.8, 8000.0),
                row(10.0, 1900.0, 1.0, 8000.0),
                row(12.0, 1500.0, 1.2, 8000.0),
                row(20.0, 750.0, 1.8, 8000.0),
            ],
        }
    }

    fn stainless() -> SpeedTable {
        SpeedTable {
            material: "stainless steel (typical figures: replace with the shop's table)".into(),
            laser: vec![
                row(1.0, 30000.0, 0.1, 15000.0),
                row(1.5, 22000.0, 0.2, 15000.0),
                row(2.0, 16000.0, 0.3, 15000.0),
                row(3.0, 8500.0, 0.5, 12000.0),
                row(4.0, 5500.0, 0.8, 12000.0),
                row(5.0, 3800.0, 1.0, 12000.0),
                row(6.0, 2800.0, 1.5, 10000.0),
                row(8.0, 1500.0, 2.5, 10000.0),
                row(10.0, 900.0, 3.5, 10000.0),
                row(12.0, 600.0, 5.0, 10000.0),
            ],
            rapid_mm_per_min: Rapid::default(),
            plasma: vec![
                row(1.5, 6500.0, 0.3, 8000.0),
                row(2.0, 6000.0, 0.3, 8000.0),
                row(3.0, 5000.0, 0.4, 8000.0),
                row(4.0, 4200.0, 0.5, 8000.0),
                row(5.0, 3600.0, 0.6, 8000.0),
                row(6.0, 3000.0, 0.7, 8000.0),
                row(8.0, 2300.0, 0.9, 8000.0),
                row(10.0, 1800.0, 1.1, 8000.0),
                row(12.0, 1400.0, 1.4, 8000.0),
                row(20.0, 700.0, 2.0, 8000.0),
            ],
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SpeedError {
    #[error("the {machine} table has no row for {t} mm or thicker")]
    NoRow { machine: &'static str, t: f64 },
}

impl SpeedTable {
    pub fn read(path: &Path) -> Result<SpeedTable, ReadError> {
        let text = utf8_text(path, read_nonempty(path)?)?;
        let table: SpeedTable = serde_json::from_str(&text)
            .map_err(|e| ReadError::line(path, e.line(), e.to_string()))?;
        let rapid = table.rapid_mm_per_min;
        if !(rapid.laser > 0.0 && rapid.laser <= 1e7 && rapid.plasma > 0.0 && rapid.plasma <= 1e7) {
            return Err(ReadError::record(
                path,
                "rapid_mm_per_min",
                "the rapid speeds must be positive, at most 1e7 mm/min",
            ));
        }
        for (machine, rows) in [("laser", &table.laser), ("plasma", &table.plasma)] {
            if rows.is_empty() {
                return Err(ReadError::file(
                    path,
                    format!("the {machine} table is empty"),
                ));
            }
            for (k, r) in rows.iter().enumerate() {
                let positive = |v: f64| v > 0.0 && v <= 1e7;
                if !(positive(r.thickness)
                    && positive(r.cut_mm_per_min)
                    && positive(r.etch_mm_per_min)
                    && r.pierce_s >= 0.0
                    && r.pierce_s <= 1e4)
                {
                    return Err(ReadError::record(
                        path,
                        format!("{machine} row {k}"),
                        "thickness and speeds must be positive (at most 1e7), the pierce time from 0 to 10,000 s",
                    ));
                }
                if k > 0 && rows[k - 1].thickness >= r.thickness {
                    return Err(ReadError::record(
                        path,
                        format!("{machine} row {k}"),
                        "rows must go by increasing thickness",
                    ));
                }
            }
        }
        Ok(table)
    }
}

impl SpeedTable {
    /// The row for thickness `t` (the next thicker one) of the laser or plasma table.
    pub fn row(&self, laser: bool, t: f64) -> Result<&SpeedRow, SpeedError> {
        let (rows, machine) = if laser {
            (&self.laser, "laser")
        } else {
            (&self.plasma, "plasma")
        };
        rows.iter()
            .find(|r| r.thickness >= t - 1e-9)
            .ok_or(SpeedError::NoRow { machine, t })
    }
}

/// Machine time for one sheet, s: (laser, plasma): cutting, pierces, marking and rapid travel.
pub fn times(
    table: &SpeedTable,
    t: f64,
    cut_mm: f64,
    pierces: usize,
    etch_mm: f64,
    rapid_mm: f64,
) -> Result<(f64, f64), SpeedError> {
    let time = |laser: bool, rapid: f64| {
        let r = table.row(laser, t)?;
        Ok(60.0 * cut_mm / r.cut_mm_per_min
            + pierces as f64 * r.pierce_s
            + 60.0 * etch_mm / r.etch_mm_per_min
            + 60.0 * rapid_mm / rapid)
    };
    Ok((
        time(true, table.rapid_mm_per_min.laser)?,
        time(false, table.rapid_mm_per_min.plasma)?,
    ))
}

/// Grid cell for remnants, mm.
pub const REMNANT_CELL: f64 = 5.0;
/// Most remnants reported per sheet.
pub const MAX_REMNANTS: usize = 4;

/// Free rectangles (lower-left, upper-right) of a `size` sheet holding `parts` (convex,
/// counter-clockwise), each `spacing` clear of every part and at least `min` in both
/// directions (either way round), largest first.
pub fn remnants(size: DVec2, parts: &[Vec<DVec2>], spacing: f64, min: DVec2) -> Vec<[DVec2; 2]> {
    let (mut taken, nx, ny) = taken_cells(size, parts, spacing);
    if nx == 0 || ny == 0 {
        return Vec::new();
    }
    let (short, long) = (min.min_element(), min.max_element());
    let mut out = Vec::new();
    while out.len() < MAX_REMNANTS {
        let Some((c0, r0, c1, r1)) = largest_free(&taken, nx, ny) else {
            break;
        };
        let lo = DVec2::new(c0 as f64, r0 as f64) * REMNANT_CELL;
        let hi = DVec2::new(c1 as f64, r1 as f64) * REMNANT_CELL;
        let d = hi - lo;
        if d.min_element() < short - 1e-9 || d.max_element() < long - 1e-9 {
            break;
        }
        for r in r0..r1 {
            for c in c0..c1 {
                taken[r * nx + c] = true;
            }
        }
        out.push([lo, hi]);
    }
    out
}

/// The grid of `REMNANT_CELL` cells over a sheet, a cell taken when a part's hull grown by
/// `spacing` touches it; with its columns and rows.
fn taken_cells(size: DVec2, parts: &[Vec<DVec2>], spacing: f64) -> (Vec<bool>, usize, usize) {
    let nx = (size.x / REMNANT_CELL).floor() as usize;
    let ny = (size.y / REMNANT_CELL).floor() as usize;
    let mut taken = vec![false; nx * ny];
    for p in parts {
        let grown = crate::fabricate::nest::grown_hull(p, spacing);
        let lo = grown.iter().fold(DVec2::INFINITY, |m, q| m.min(*q));
        let hi = grown.iter().fold(DVec2::NEG_INFINITY, |m, q| m.max(*q));
        let row0 = ((lo.y / REMNANT_CELL).floor().max(0.0) as usize).min(ny);
        let row1 = ((hi.y / REMNANT_CELL).ceil().max(0.0) as usize).min(ny);
        for r in row0..row1 {
            // The hull's x-extent over the row's band.
            let (y0, y1) = (r as f64 * REMNANT_CELL, (r + 1) as f64 * REMNANT_CELL);
            let Some((x0, x1)) = band_extent(&grown, y0, y1) else {
                continue;
            };
            let c0 = ((x0 / REMNANT_CELL).floor().max(0.0) as usize).min(nx);
            let c1 = ((x1 / REMNANT_CELL).ceil().max(0.0) as usize).min(nx);
            for c in c0..c1 {
                taken[r * nx + c] = true;
            }
        }
    }
    (taken, nx, ny)
}

/// The most grid cells a sheet may have for [`free_box`] to look for a label.
pub const LABEL_CELLS: f64 = 16.0e6;

/// Where a `want`-sized box (a label) fits on a sheet: `spacing` clear of every part, clear of
/// the `avoid` rectangles, inside the `margin`; the lowest such place, then the leftmost, on the
/// cell grid. Its lower-left corner, or None (also for a sheet of more than [`LABEL_CELLS`]
/// cells).
pub fn free_box(
    size: DVec2,
    parts: &[Vec<DVec2>],
    spacing: f64,
    margin: f64,
    avoid: &[[DVec2; 2]],
    want: DVec2,
) -> Option<DVec2> {
    // Sheets past 20 × 20 m (16 M cells) get no label: the summed table would take 64 MB.
    let cells = (size.x / REMNANT_CELL).floor() * (size.y / REMNANT_CELL).floor();
    if !(1.0..=LABEL_CELLS).contains(&cells) {
        return None;
    }
    let (mut taken, nx, ny) = taken_cells(size, parts, spacing);
    if nx == 0 || ny == 0 {
        return None;
    }
    for [lo, hi] in avoid {
        let c0 = ((lo.x / REMNANT_CELL).floor().max(0.0) as usize).min(nx);
        let c1 = ((hi.x / REMNANT_CELL).ceil().max(0.0) as usize).min(nx);
        let r0 = ((lo.y / REMNANT_CELL).floor().max(0.0) as usize).min(ny);
        let r1 = ((hi.y / REMNANT_CELL).ceil().max(0.0) as usize).min(ny);
        for r in r0..r1 {
            for c in c0..c1 {
                taken[r * nx + c] = true;
            }
        }
    }
    // Cells inside the margin, and a box's size in cells.
    let first = (margin / REMNANT_CELL).ceil().max(0.0) as usize;
    let last_x = ((size.x - margin) / REMNANT_CELL).floor().max(0.0) as usize;
    let last_y = ((size.y - margin) / REMNANT_CELL).floor().max(0.0) as usize;
    let w = (want.x / REMNANT_CELL).ceil() as usize;
    let h = (want.y / REMNANT_CELL).ceil() as usize;
    if w == 0 || h == 0 || first + w > last_x.min(nx) || first + h > last_y.min(ny) {
        return None;
    }
    // Summed counts of taken cells.
    let mut sum = vec![0u32; (nx + 1) * (ny + 1)];
    for r in 0..ny {
        for c in 0..nx {
            sum[(r + 1) * (nx + 1) + c + 1] =
                sum[r * (nx + 1) + c + 1] + sum[(r + 1) * (nx + 1) + c] - sum[r * (nx + 1) + c]
                    + u32::from(taken[r * nx + c]);
        }
    }
    let count = |c0: usize, r0: usize, c1: usize, r1: usize| {
        sum[r1 * (nx + 1) + c1] + sum[r0 * (nx + 1) + c0]
            - sum[r0 * (nx + 1) + c1]
            - sum[r1 * (nx + 1) + c0]
    };
    for r in first..=last_y.min(ny) - h {
        for c in first..=last_x.min(nx) - w {
            if count(c, r, c + w, r + h) == 0 {
                return Some(DVec2::new(c as f64, r as f64) * REMNANT_CELL);
            }
        }
    }
    None
}

/// The x-range of a convex polygon within the band y0 ≤ y ≤ y1, if it reaches the band.
fn band_extent(poly: &[DVec2], y0: f64, y1: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let n = poly.len();
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        // The part of the edge inside the band.
        let (ya, yb) = (a.y, b.y);
        let t_in = |y: f64| {
            if (yb - ya).abs() < 1e-15 {
                None
            } else {
                Some((y - ya) / (yb - ya))
            }
        };
        let mut ts = vec![0.0, 1.0];
        for y in [y0, y1] {
            if let Some(t) = t_in(y) {
                if (0.0..=1.0).contains(&t) {
                    ts.push(t);
                }
            }
        }
        for t in ts {
            let p = a + (b - a) * t;
            if p.y >= y0 - 1e-9 && p.y <= y1 + 1e-9 {
                lo = lo.min(p.x);
                hi = hi.max(p.x);
            }
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// The largest all-free rectangle of cells (columns c0..c1, rows r0..r1), by the histogram
/// method: for each row the free run heights, and the largest rectangle under them.
fn largest_free(taken: &[bool], nx: usize, ny: usize) -> Option<(usize, usize, usize, usize)> {
    let mut height = vec![0usize; nx];
    let mut best: Option<(usize, (usize, usize, usize, usize))> = None;
    for r in 0..ny {
        for c in 0..nx {
            height[c] = if taken[r * nx + c] { 0 } else { height[c] + 1 };
        }
        let mut stack: Vec<usize> = Vec::new();
        for c in 0..=nx {
            let h = if c < nx { height[c] } else { 0 };
            while let Some(&top) = stack.last() {
                if height[top] <= h {
                    break;
                }
                stack.pop();
                let left = stack.last().map(|&s| s + 1).unwrap_or(0);
                let area = height[top] * (c - left);
                if area > 0 && best.is_none_or(|b| area > b.0) {
                    best = Some((area, (left, r + 1 - height[top], c, r + 1)));
                }
            }
            stack.push(c);
        }
    }
    best.map(|b| b.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_free_end_of_a_sheet_is_a_remnant() {
        // A part filling the left 1000 mm of a 3000 × 1500 sheet.
        let part = vec![
            DVec2::new(10.0, 10.0),
            DVec2::new(1000.0, 10.0),
            DVec2::new(1000.0, 1490.0),
            DVec2::new(10.0, 1490.0),
        ];
        let r = remnants(
            DVec2::new(3000.0, 1500.0),
            &[part],
            5.0,
            DVec2::new(300.0, 300.0),
        );
        assert_eq!(r.len(), 1, "{r:?}");
        assert_eq!(r[0], [DVec2::new(1005.0, 0.0), DVec2::new(3000.0, 1500.0)]);
    }

    #[test]
    fn times_come_from_the_next_thicker_row() {
        let t = SpeedTable::default();
        let (laser, plasma) = times(&t, 2.5, 8500.0, 10, 0.0, 0.0).expect("rows");
        assert!((laser - (60.0 + 5.0)).abs() < 1e-9, "{laser}");
        assert!((plasma - (60.0 * 8500.0 / 5000.0 + 4.0)).abs() < 1e-9);
        assert!(times(&t, 50.0, 1.0, 1, 0.0, 0.0).is_err());
    }
}
