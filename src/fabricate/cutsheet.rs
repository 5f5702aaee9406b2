//! Cut DXFs: R2000, millimetres ($INSUNITS = 4), layers CUT (closed LWPOLYLINE outlines), ETCH
//! (tag strokes as LINEs; live TEXT is never used on a cut file) and SHEET (the stock outline).
//! The header's clock and GUIDs are fixed (as for network DXFs) so the same parts give the same
//! bytes.

use std::path::Path;

use dxf::entities::{Entity, EntityType, Line};
use dxf::tables::Layer;
use dxf::Point;
use glam::DVec2;

use crate::files::{write_atomic, WriteError};
use crate::network::io::dxf::{fixed_drawing, lw_polyline_entity};

pub const CUT: &str = "CUT";
pub const ETCH: &str = "ETCH";
pub const SHEET: &str = "SHEET";

/// One part as drawn on a cut file: its outline and its etched strokes, in drawing coordinates.
pub struct Drawn<'a> {
    pub outline: &'a [DVec2],
    pub strokes: &'a [[DVec2; 2]],
}

/// Writes the parts (and the sheet rectangle from the origin, if given) to `path`.
pub fn write_cut_dxf(parts: &[Drawn], sheet: Option<DVec2>, path: &Path) -> Result<(), WriteError> {
    let mut drawing = fixed_drawing();
    for (name, colour) in [(CUT, 1u8), (ETCH, 5), (SHEET, 8)] {
        drawing.add_layer(Layer {
            name: name.into(),
            color: dxf::Color::from_index(colour),
            ..Default::default()
        });
    }
    let closed = |pts: &[DVec2], layer: &str| {
        lw_polyline_entity(pts.iter().map(|p| (p.x, p.y)), true, layer)
    };
    if let Some(s) = sheet {
        let rect = [DVec2::ZERO, DVec2::new(s.x, 0.0), s, DVec2::new(0.0, s.y)];
        drawing.add_entity(closed(&rect, SHEET));
    }
    for part in parts {
        drawing.add_entity(closed(part.outline, CUT));
        for [a, b] in part.strokes {
            let mut e = Entity::new(EntityType::Line(Line::new(
                Point::new(a.x, a.y, 0.0),
                Point::new(b.x, b.y, 0.0),
            )));
            e.common.layer = ETCH.into();
            drawing.add_entity(e);
        }
    }
    write_atomic(path, |w| {
        crate::network::io::dxf_write::save(&mut drawing, w)
    })
}
