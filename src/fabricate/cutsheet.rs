//! Cut DXFs for CAM: R2000, millimetres ($INSUNITS = 4). Layers:
//!
//! - CUT_OUTER: each part's outline, a closed LWPOLYLINE, counter-clockwise, starting at its
//!   pierce point.
//! - CUT_INNER: holes, closed clockwise LWPOLYLINEs (64-gons on the circle), starting at
//!   their pierce point.
//! - ETCH: tags and marks in our single-stroke font, strokes chained into open LWPOLYLINEs
//!   (never live TEXT).
//! - LEAD: lead-in and lead-out lines in the scrap, when asked for.
//! - SHEET, REMNANT: the stock outline and the free rectangles worth keeping; reference only,
//!   not to be cut (the layers are also marked not to plot).
//!
//! File order per part is the order a cut should follow: etching first (while the part is held
//! by the sheet), then the inner contours, then the outer contour. The header's clock and
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
}

impl Drawn {
    /// Cut length: the outline's perimeter and the holes' circumferences, mm.
    pub fn cut_length(&self) -> f64 {
        let n = self.outline.len();
        let outer: f64 = (0..n)
            .map(|k| self.outline[k].distance(self.outline[(k + 1) % n]))
            .sum();
        let inner: f64 = self
            .holes
            .iter()
            .map(|h| std::f64::consts::PI * h.diameter)
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

    /// Pierces: one per contour.
    pub fn pierces(&self) -> usize {
        1 + self.holes.len()
    }
}

/// Writes the parts, and the sheet rectangle from the origin and remnant rectangles if given.
pub fn write_cut_dxf(
    parts: &[&Drawn],
    sheet: Option<DVec2>,
    remnants: &[[DVec2; 2]],
    path: &Path,
) -> Result<(), WriteError> {
    let mut drawing = fixed_drawing();
    for (name, colour, plotted) in [
        (CUT_OUTER, 1u8, true),
        (CUT_INNER, 6, true),
        (ETCH, 5, true),
        (LEAD, 3, true),
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
    for part in parts {
        for line in &part.etch {
            drawing.add_entity(lw_polyline_entity(
                line.iter().map(|p| (p.x, p.y)),
                false,
                ETCH,
            ));
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
        drawing.add_entity(lw_polyline_entity(
            part.outline.iter().map(|p| (p.x, p.y)),
            true,
            CUT_OUTER,
        ));
        lead(&mut drawing);
    }
    write_atomic(path, |w| {
        crate::network::io::dxf_write::save(&mut drawing, w)
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
}
