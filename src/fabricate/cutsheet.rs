//! Cut DXFs for CAM: R2000, millimetres ($INSUNITS = 4). Layers:
//!
//! - CUT_OUTER: each part's outline, a closed LWPOLYLINE, counter-clockwise, starting at its
//!   pierce point.
//! - CUT_INNER: holes, closed clockwise LWPOLYLINEs (64-gons on the circle), starting at
//!   their pierce point.
//! - ETCH: tags and marks in our single-stroke font, strokes chained into open LWPOLYLINEs
//!   (never live TEXT).
//! - LEAD: lead-in and lead-out lines in the scrap, when asked for.
//! - Micro-joints, when asked for: the outer contour of a small part is cut as open
//!   LWPOLYLINEs (counter-clockwise, in cutting order) with a gap of the joint's width between
//!   them, the uncut bridge that holds the part in the sheet; each bridge is also drawn as a line
//!   across its gap on JOINT, for the operator (reference, not cut).
//! - SHEET, REMNANT: the stock outline and the free rectangles worth keeping; reference only,
//!   not to be cut (the layers are also marked not to plot).
//!
//! File order is the order a cut should follow: on a sheet, all etching first (while every part
//! is held by the sheet), then part by part in cutting order its inner contours, then its outer
//! contour; a single part's file has its etching, inner contours, outer contour. The header's clock and
//! GUIDs are fixed (as for network DXFs) so the same parts give the same bytes.

use std::path::Path;

use dxf::entities::Entity;
use dxf::tables::Layer;
use glam::DVec2;

use crate::files::{write_atomic, WriteError};
use crate::network::io::dxf::{fixed_drawing, lw_polyline_entity};

pub const CUT_OUTER: &str = "CUT_OUTER";
pub const CUT_INNER: &str = "CUT_INNER";
pub const ETCH: &str = "ETCH";
pub const LEAD: &str = "LEAD";
pub const JOINT: &str = "JOINT";
pub const SHEET: &str = "SHEET";
pub const REMNANT: &str = "REMNANT";

/// A round hole: centre and diameter, mm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hole {
    pub centre: DVec2,
    pub diameter: f64,
}

/// One part as drawn on a cut file, in drawing coordinates.
#[derive(Clone, Debug, Default)]
pub struct Drawn {
    /// Counter-clockwise; the first point is where the cut starts.
    pub outline: Vec<DVec2>,
    pub holes: Vec<Hole>,
    /// Etched polylines (open).
    pub etch: Vec<Vec<DVec2>>,
    /// Lead-in and lead-out lines.
    pub leads: Vec<[DVec2; 2]>,
    /// Micro-joints: uncut stretches of the outline, as arc lengths from its first point,
    /// increasing and apart.
    pub joints: Vec<[f64; 2]>,
    /// Common-line cutting: the outline's last side (back into its first point) is cut by a
    /// neighbour's contour, the kerf apart; this contour starts in that kerf (no pierce) and
    /// stops where the side begins.
    pub common: bool,
}

impl Drawn {
    /// Cut length: the outline's perimeter less its micro-joints, and the perimeters of the
    /// holes as cut (`HOLE_SEGMENTS`-gons on their circles), mm.
    pub fn cut_length(&self) -> f64 {
        let n = self.outline.len();
        let outer: f64 = (0..n)
            .map(|k| self.outline[k].distance(self.outline[(k + 1) % n]))
            .sum::<f64>()
            - self.joints.iter().map(|[a, b]| b - a).sum::<f64>()
            - self.common_side();
        // Holes as the DXF cuts them: `HOLE_SEGMENTS`-gons on their circles.
        let n = crate::rationalize::plates::HOLE_SEGMENTS as f64;
        let inner: f64 = self
            .holes
            .iter()
            .map(|h| n * h.diameter * (std::f64::consts::PI / n).sin())
            .sum();
        outer + inner
    }

    /// Etched length, mm.
    pub fn etch_length(&self) -> f64 {
        self.etch
            .iter()
            .map(|l| l.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>())
            .sum()
    }

    /// Pierces: one per contour, and one more after each micro-joint (the cut starts again
    /// in solid metal on its far side); none for an outer contour that starts in a common
    /// line's kerf.
    pub fn pierces(&self) -> usize {
        usize::from(!self.common) + self.holes.len() + self.joints.len()
    }

    /// The length of the side a neighbour cuts (common-line cutting), else 0, mm.
    pub fn common_side(&self) -> f64 {
        match (self.common, self.outline.first(), self.outline.last()) {
            (true, Some(a), Some(b)) => a.distance(*b),
            _ => 0.0,
        }
    }

    /// The outer contour as cut: the closed outline, or with micro-joints the open pieces
    /// between them in cutting order (from the first point round to it again).
    pub fn outer_pieces(&self) -> Vec<Vec<DVec2>> {
        if self.joints.is_empty() {
            return vec![self.outline.clone()];
        }
        let mut ring = self.outline.clone();
        ring.push(self.outline[0]);
        let mut cuts = vec![0.0];
        for [a, b] in &self.joints {
            cuts.extend([*a, *b]);
        }
        cuts.push(arc_length(&ring));
        cuts.chunks(2)
            .map(|c| sub_path(&ring, c[0], c[1]))
            .collect()
    }

    /// Each micro-joint as the line across its gap.
    pub fn joint_lines(&self) -> Vec<[DVec2; 2]> {
        let mut ring = self.outline.clone();
        ring.push(self.outline[0]);
        self.joints
            .iter()
            .map(|&[a, b]| [point_at(&ring, a), point_at(&ring, b)])
            .collect()
    }
}

fn arc_length(path: &[DVec2]) -> f64 {
    path.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// The point at arc length `s` along an open path.
fn point_at(path: &[DVec2], s: f64) -> DVec2 {
    let mut run = 0.0;
    for w in path.windows(2) {
        let l = w[0].distance(w[1]);
        if s <= run + l && l > 0.0 {
            return w[0].lerp(w[1], ((s - run) / l).clamp(0.0, 1.0));
        }
        run += l;
    }
    *path.last().expect("a path has points")
}

/// The stretch of an open path from arc length `s0` to `s1`, with the vertices between.
fn sub_path(path: &[DVec2], s0: f64, s1: f64) -> Vec<DVec2> {
    let mut out = vec![point_at(path, s0)];
    let mut run = 0.0;
    for w in path.windows(2) {
        run += w[0].distance(w[1]);
        if run > s0 && run < s1 {
            out.push(w[1]);
        }
    }
    out.push(point_at(path, s1));
    out
}

/// Up to `n` micro-joints `width` wide on a closed outline (its first point is the pierce
/// point): each within one straight side, at least `clear` from its corners and from the pierce
/// point, as near as that allows to `n` points spread evenly round the perimeter, and at least
/// `clear` apart. Fewer where the sides are too short.
pub fn place_joints(outline: &[DVec2], n: usize, width: f64, clear: f64) -> Vec<[f64; 2]> {
    let mut ring = outline.to_vec();
    ring.push(outline[0]);
    let perimeter = arc_length(&ring);
    // Where a joint's centre may go: an interval per side.
    let mut room = Vec::new();
    let mut run = 0.0;
    for w in ring.windows(2) {
        let l = w[0].distance(w[1]);
        let half = clear + 0.5 * width;
        if l > 2.0 * half {
            room.push([run + half, run + l - half]);
        }
        run += l;
    }
    let mut centres: Vec<f64> = Vec::new();
    for k in 0..n {
        let target = perimeter * (k as f64 + 0.5) / n as f64;
        let apart = |c: f64| centres.iter().all(|&o| (c - o).abs() >= width + clear);
        let best = room
            .iter()
            .map(|&[lo, hi]| target.clamp(lo, hi))
            .filter(|&c| apart(c))
            .min_by(|a, b| (a - target).abs().total_cmp(&(b - target).abs()));
        if let Some(c) = best {
            centres.push(c);
        }
    }
    centres.sort_by(f64::total_cmp);
    centres
        .iter()
        .map(|c| [c - 0.5 * width, c + 0.5 * width])
        .collect()
}

/// Writes the parts, and the sheet rectangle from the origin and remnant rectangles if given;
/// `label` (the grade, thickness and what the file holds) as a comment (group 999) heading
/// the file: no entity a CAM import could cut.
pub fn write_cut_dxf(
    parts: &[&Drawn],
    sheet: Option<DVec2>,
    remnants: &[[DVec2; 2]],
    label: &str,
    path: &Path,
) -> Result<(), WriteError> {
    write_dxf(None, parts, sheet, remnants, label, path)
}

/// A sheet as it is cut: `etch` (every etched polyline of the sheet, in marking order) first,
/// then the parts in cutting order without their own etching, each part's inner contours
/// before its outer one.
pub fn write_sheet_dxf(
    etch: &[Vec<DVec2>],
    parts: &[&Drawn],
    sheet: DVec2,
    remnants: &[[DVec2; 2]],
    label: &str,
    path: &Path,
) -> Result<(), WriteError> {
    write_dxf(Some(etch), parts, Some(sheet), remnants, label, path)
}

fn write_dxf(
    etch: Option<&[Vec<DVec2>]>,
    parts: &[&Drawn],
    sheet: Option<DVec2>,
    remnants: &[[DVec2; 2]],
    label: &str,
    path: &Path,
) -> Result<(), WriteError> {
    let mut drawing = fixed_drawing();
    for (name, colour, plotted) in [
        (CUT_OUTER, 1u8, true),
        (CUT_INNER, 6, true),
        (ETCH, 5, true),
        (LEAD, 3, true),
        (JOINT, 4, false),
        (SHEET, 8, false),
        (REMNANT, 9, false),
    ] {
        drawing.add_layer(Layer {
            name: name.into(),
            color: dxf::Color::from_index(colour),
            is_layer_plotted: plotted,
            ..Default::default()
        });
    }
    let rect = |lo: DVec2, hi: DVec2| [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    if let Some(s) = sheet {
        let r = rect(DVec2::ZERO, s);
        drawing.add_entity(lw_polyline_entity(
            r.iter().map(|p| (p.x, p.y)),
            true,
            SHEET,
        ));
    }
    for [lo, hi] in remnants {
        let r = rect(*lo, *hi);
        drawing.add_entity(lw_polyline_entity(
            r.iter().map(|p| (p.x, p.y)),
            true,
            REMNANT,
        ));
    }
    let etch_line = |drawing: &mut dxf::Drawing, line: &[DVec2]| {
        drawing.add_entity(lw_polyline_entity(
            line.iter().map(|p| (p.x, p.y)),
            false,
            ETCH,
        ));
    };
    for line in etch.unwrap_or_default() {
        etch_line(&mut drawing, line);
    }
    for part in parts {
        if etch.is_none() {
            for line in &part.etch {
                etch_line(&mut drawing, line);
            }
        }
        let mut leads = part.leads.iter();
        // Leads come in pairs per contour (in, out): holes first, then the outline.
        let mut lead = |drawing: &mut dxf::Drawing| {
            if let Some([a, b]) = leads.next() {
                drawing.add_entity(lw_polyline_entity(
                    [(a.x, a.y), (b.x, b.y)].into_iter(),
                    false,
                    LEAD,
                ));
            }
        };
        for h in &part.holes {
            lead(&mut drawing);
            drawing.add_entity(hole_entity(h));
            lead(&mut drawing);
        }
        lead(&mut drawing);
        let closed = part.joints.is_empty();
        for piece in part.outer_pieces() {
            drawing.add_entity(lw_polyline_entity(
                piece.iter().map(|p| (p.x, p.y)),
                closed,
                CUT_OUTER,
            ));
        }
        lead(&mut drawing);
        for [a, b] in part.joint_lines() {
            drawing.add_entity(lw_polyline_entity(
                [(a.x, a.y), (b.x, b.y)].into_iter(),
                false,
                JOINT,
            ));
        }
    }
    write_atomic(path, |w| {
        crate::network::io::dxf_write::save_with_comment(&mut drawing, label, w)
    })
}

/// A hole as a clockwise `HOLE_SEGMENTS`-gon on its circle, starting (and pierced into) at its
/// +x point. Not bulge arcs: OpenSCAD's DXF import drops bulges, and the assembly rebuilt from
/// the cut files must have its holes (the chord error is r·(1 − cos(π/64)), 0.008 mm for M12).
fn hole_entity(h: &Hole) -> Entity {
    let mut pts = crate::rationalize::plates::hole_polygon(h.centre, h.diameter);
    pts[1..].reverse();
    lw_polyline_entity(pts.iter().map(|p| (p.x, p.y)), true, CUT_INNER)
}

/// Segments chained into polylines: each walk starts at a point with an odd number of
/// segments where there is one, follows unused segments while it can; points match exactly
/// (strokes from one glyph grid share their end points bit for bit).
pub fn chain(segments: &[[DVec2; 2]]) -> Vec<Vec<DVec2>> {
    use std::collections::BTreeMap;
    let key = |p: DVec2| (p.x.to_bits(), p.y.to_bits());
    let mut at: BTreeMap<(u64, u64), Vec<usize>> = BTreeMap::new();
    for (i, [a, b]) in segments.iter().enumerate() {
        at.entry(key(*a)).or_default().push(i);
        at.entry(key(*b)).or_default().push(i);
    }
    let mut used = vec![false; segments.len()];
    let mut out = Vec::new();
    // Odd points first (a path must start or end there), then anything left (loops).
    let mut starts: Vec<(usize, DVec2)> = Vec::new();
    for (i, [a, b]) in segments.iter().enumerate() {
        for p in [a, b] {
            if at[&key(*p)].len() % 2 == 1 {
                starts.push((i, *p));
            }
        }
    }
    for (i, [a, _]) in segments.iter().enumerate() {
        starts.push((i, *a));
    }
    for (first, from) in starts {
        if used[first] {
            continue;
        }
        let mut line = vec![from];
        let mut here = from;
        let mut next = Some(first);
        while let Some(i) = next {
            used[i] = true;
            let [a, b] = segments[i];
            here = if key(a) == key(here) { b } else { a };
            line.push(here);
            next = at[&key(here)].iter().copied().find(|&j| !used[j]);
        }
        out.push(line);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strokes_chain_into_few_polylines() {
        let p = |x: f64, y: f64| DVec2::new(x, y);
        // An "8": two squares sharing the middle bar; one walk covers it (two odd corners).
        let segs = [
            [p(0., 0.), p(1., 0.)],
            [p(1., 0.), p(1., 1.)],
            [p(1., 1.), p(0., 1.)],
            [p(0., 1.), p(0., 0.)],
            [p(0., 1.), p(0., 2.)],
            [p(0., 2.), p(1., 2.)],
            [p(1., 2.), p(1., 1.)],
        ];
        let lines = chain(&segs);
        let total: usize = lines.iter().map(|l| l.len() - 1).sum();
        assert_eq!(total, segs.len());
        assert_eq!(lines.len(), 1, "{lines:?}");
        // A "-" and a separate "1": two.
        let two = chain(&[[p(0., 0.), p(1., 0.)], [p(3., 0.), p(3., 2.)]]);
        assert_eq!(two.len(), 2);
    }

    #[test]
    fn micro_joints_sit_on_straight_sides_and_leave_the_cut_short_by_their_width() {
        let p = |x: f64, y: f64| DVec2::new(x, y);
        // A 100 × 40 rectangle pierced in the middle of its bottom side.
        let outline = vec![p(50., 0.), p(100., 0.), p(100., 40.), p(0., 40.), p(0., 0.)];
        let joints = place_joints(&outline, 3, 0.5, 2.0);
        assert_eq!(joints.len(), 3);
        let corners = [0.0, 50.0, 90.0, 190.0, 230.0, 280.0];
        for [a, b] in &joints {
            assert!((b - a - 0.5).abs() < 1e-12);
            for c in corners {
                assert!(
                    *a >= c + 2.0 - 1e-9 || *b <= c - 2.0 + 1e-9,
                    "{a}..{b} near {c}"
                );
            }
        }
        let drawn = Drawn {
            outline: outline.clone(),
            joints: joints.clone(),
            ..Default::default()
        };
        let pieces = drawn.outer_pieces();
        assert_eq!(pieces.len(), 4);
        assert_eq!(pieces[0][0], outline[0]);
        assert_eq!(*pieces[3].last().unwrap(), outline[0]);
        let cut: f64 = pieces.iter().map(|q| arc_length(q)).sum();
        assert!((cut - (280.0 - 1.5)).abs() < 1e-9, "{cut}");
        assert!((drawn.cut_length() - cut).abs() < 1e-9);
        assert_eq!(drawn.pierces(), 4);
        // Each gap is a stretch of a side: its ends the joint's width apart.
        for [a, b] in drawn.joint_lines() {
            assert!((a.distance(b) - 0.5).abs() < 1e-9);
        }
        // A triangle too small for clearances gets none rather than joints on its corners.
        let tiny = vec![p(0., 0.), p(3., 0.), p(0., 3.)];
        assert!(place_joints(&tiny, 2, 0.5, 2.0).is_empty());
    }
}

/// A polyline read back from a cut file, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadPath {
    pub layer: String,
    pub closed: bool,
    pub points: Vec<DVec2>,
}

/// The largest cut file read back (a sheet of a few thousand parts is a few megabytes).
pub const MAX_SHEET_BYTES: u64 = 256 << 20;

/// A cut file's LWPOLYLINEs and LINEs (as two-point paths), in file order, and how many other
/// entities it holds (not read).
pub fn read_cut_dxf(path: &Path) -> Result<(Vec<ReadPath>, usize), crate::files::ReadError> {
    use crate::files::ReadError;
    use dxf::entities::EntityType;
    let size = std::fs::metadata(path)
        .map_err(|e| ReadError::io(path, e))?
        .len();
    if size > MAX_SHEET_BYTES {
        return Err(ReadError::file(
            path,
            format!("{size} bytes, more than a cut file may have ({MAX_SHEET_BYTES})"),
        ));
    }
    // On the parser thread: a value the dxf crate cannot take is this file's error, no panic.
    let bytes = std::fs::read(path).map_err(|e| ReadError::io(path, e))?;
    let drawing = crate::network::io::dxf::load_drawing(path, &bytes)?;
    let (mut paths, mut other) = (Vec::new(), 0);
    for e in drawing.entities() {
        let layer = e.common.layer.clone();
        match &e.specific {
            EntityType::LwPolyline(p) => paths.push(ReadPath {
                layer,
                closed: p.is_closed(),
                points: p.vertices.iter().map(|v| DVec2::new(v.x, v.y)).collect(),
            }),
            EntityType::Line(l) => paths.push(ReadPath {
                layer,
                closed: false,
                points: vec![DVec2::new(l.p1.x, l.p1.y), DVec2::new(l.p2.x, l.p2.y)],
            }),
            _ => other += 1,
        }
    }
    if let Some(k) = paths.iter().position(|p| {
        p.points
            .iter()
            .any(|q| !(q.is_finite() && q.abs().max_element() < 1e7))
    }) {
        return Err(ReadError::record(
            path,
            format!("polyline {k}"),
            "a point is not a finite number within 1e7 mm",
        ));
    }
    Ok((paths, other))
}
