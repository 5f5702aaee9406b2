//! Saving a drawing so that a strict reader (ezdxf's audit, AutoCAD) finds nothing to fix.
//!
//! The `dxf` crate writes table heads without a handle and owner, and DIMSTYLE records with
//! their handle under group 5 where R2000 and later use 105. This pass gives every table head a
//! fresh handle (owner 0) and moves DIMSTYLE handles to 105, then sets `$HANDSEED` past the
//! largest handle. `$EXTMIN`/`$EXTMAX` are set from the entities before saving.

use dxf::entities::EntityType;
use dxf::{Drawing, Point};
use glam::DVec3;

use crate::geom::Aabb;

/// Writes `drawing` (with its extents set) to `w`, audit-clean.
pub(crate) fn save(drawing: &mut Drawing, w: &mut impl std::io::Write) -> std::io::Result<()> {
    set_extents(drawing);
    let mut raw = Vec::new();
    drawing
        .save(&mut raw)
        .map_err(|e| std::io::Error::other(e.to_string()))?;
    let text = String::from_utf8(raw).map_err(std::io::Error::other)?;
    w.write_all(fix_handles(&text).as_bytes())
}

/// As [`save`], the file headed by `comment` as DXF comments (group 999, one per line; readers
/// skip them).
pub(crate) fn save_with_comment(
    drawing: &mut Drawing,
    comment: &str,
    w: &mut impl std::io::Write,
) -> std::io::Result<()> {
    let mut body = Vec::new();
    save(drawing, &mut body)?;
    let eol = if body.windows(2).any(|p| p == b"\r\n") {
        "\r\n"
    } else {
        "\n"
    };
    for line in comment.lines() {
        // A comment line holds no control characters.
        let clean: String = line.chars().filter(|c| !c.is_control()).collect();
        write!(w, "999{eol}{clean}{eol}")?;
    }
    w.write_all(&body)
}

/// `$EXTMIN`/`$EXTMAX`: the box of every point the drawing's entities hold (LINE, LWPOLYLINE
/// at its elevation, POLYLINE vertices, POINT); the origin for an empty drawing.
fn set_extents(drawing: &mut Drawing) {
    let mut b = Aabb::empty();
    let v = |p: &Point| DVec3::new(p.x, p.y, p.z);
    for e in drawing.entities() {
        match &e.specific {
            EntityType::Line(l) => {
                b.extend(v(&l.p1));
                b.extend(v(&l.p2));
            }
            EntityType::LwPolyline(pl) => {
                for q in &pl.vertices {
                    b.extend(DVec3::new(q.x, q.y, e.common.elevation));
                }
            }
            EntityType::Polyline(pl) => {
                for q in pl.vertices() {
                    b.extend(v(&q.location));
                }
            }
            EntityType::ModelPoint(p) => b.extend(v(&p.location)),
            _ => {}
        }
    }
    let (lo, hi) = if b.is_empty() {
        (DVec3::ZERO, DVec3::ZERO)
    } else {
        (b.min, b.max)
    };
    drawing.header.minimum_drawing_extents = Point::new(lo.x, lo.y, lo.z);
    drawing.header.maximum_drawing_extents = Point::new(hi.x, hi.y, hi.z);
}

/// The text with table-head handles added, DIMSTYLE handles under 105 and `$HANDSEED` updated.
fn fix_handles(text: &str) -> String {
    let eol = if text.contains("\r\n") { "\r\n" } else { "\n" };
    let lines: Vec<&str> = text.split(eol).collect();
    let pairs = lines.len() / 2;
    let code = |i: usize| lines[2 * i].trim();
    let value = |i: usize| lines[2 * i + 1].trim();
    // The largest handle in use.
    let mut top = 0u64;
    for i in 0..pairs {
        if matches!(code(i), "5" | "105") {
            if let Ok(h) = u64::from_str_radix(value(i), 16) {
                top = top.max(h);
            }
        }
    }
    let mut out: Vec<String> = Vec::with_capacity(lines.len() + 64);
    let mut table = "";
    let mut next = top + 1;
    let mut i = 0;
    while i < pairs {
        let (c, v) = (code(i), value(i));
        out.push(lines[2 * i].to_string());
        if c == "5"
            && table == "DIMSTYLE"
            && i > 0
            && code(i - 1) == "0"
            && value(i - 1) == "DIMSTYLE"
        {
            out.pop();
            out.push("105".to_string());
        }
        out.push(lines[2 * i + 1].to_string());
        if c == "2" && i > 0 && code(i - 1) == "0" && value(i - 1) == "TABLE" {
            table = lines[2 * i + 1].trim();
            // A head already carrying a handle is left as it is.
            if i + 1 < pairs && code(i + 1) != "5" {
                out.push("  5".into());
                out.push(format!("{next:X}"));
                out.push("330".into());
                out.push("0".into());
                next += 1;
            }
        }
        if c == "0" && v == "ENDTAB" {
            table = "";
        }
        i += 1;
    }
    out.extend(lines[2 * pairs..].iter().map(|s| s.to_string()));
    // $HANDSEED: the next free handle.
    for k in 0..out.len().saturating_sub(3) {
        if out[k].trim() == "$HANDSEED" && out[k + 1].trim() == "5" {
            out[k + 2] = format!("{next:X}");
            break;
        }
    }
    out.join(eol)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_heads_get_handles_and_dimstyles_use_105() {
        let text = "  0\nSECTION\n  2\nHEADER\n  9\n$HANDSEED\n  5\n20\n  0\nENDSEC\n\
                    0\nTABLE\n  2\nLAYER\n100\nAcDbSymbolTable\n 70\n1\n\
                    0\nLAYER\n  5\n1F\n  0\nENDTAB\n\
                    0\nTABLE\n  2\nDIMSTYLE\n100\nAcDbSymbolTable\n 70\n1\n\
                    0\nDIMSTYLE\n  5\n1A\n  0\nENDTAB\n  0\nEOF\n";
        let fixed = fix_handles(text);
        // Fresh handles start past the largest in the file (the old $HANDSEED, 20, included).
        assert!(
            fixed.contains("  2\nLAYER\n  5\n21\n330\n0\n100"),
            "{fixed}"
        );
        assert!(
            fixed.contains("  2\nDIMSTYLE\n  5\n22\n330\n0\n100"),
            "{fixed}"
        );
        assert!(fixed.contains("DIMSTYLE\n105\n1A"), "{fixed}");
        assert!(fixed.contains("$HANDSEED\n  5\n23\n"), "{fixed}");
        assert!(
            fixed.contains("0\nLAYER\n  5\n1F"),
            "other records keep group 5"
        );
    }
}
