//! Network DXF through the `dxf` crate. Read: LINE, LWPOLYLINE, POLYLINE (2D and 3D) and POINT,
//! in any layer, model space; 2D entities are taken from their object coordinate system (OCS)
//! to world coordinates. Everything else is counted as skipped; a file with nothing to read is an
//! error. Write: R2000, layer NETWORK; one LINE per lone edge, one LWPOLYLINE per chain that lies
//! at one height, one 3D POLYLINE per other chain, one POINT per isolated node.

use std::collections::BTreeMap;
use std::path::Path;

use dxf::entities::{Entity, EntityType, Line, LwPolyline, ModelPoint, Polyline, Vertex};
use dxf::enums::AcadVersion;
use dxf::tables::Layer;
use dxf::{Drawing, DxfError, LwPolylineVertex, Point};
use glam::DVec3;

use super::dxf_split::Part;
use super::{Imported, ReadOptions};
use crate::files::{read_nonempty, write_atomic, ReadError, WriteError};
use crate::network::{weld, Network};

pub const LAYER: &str = "NETWORK";

/// Files at least this large are split and parsed on several cores (see `dxf_split`).
const SPLIT_MIN_BYTES: usize = 4 << 20;

pub fn read(path: &Path, opts: &ReadOptions) -> Result<Imported, ReadError> {
    let bytes = read_nonempty(path)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let parts = threads.min(bytes.len() / SPLIT_MIN_BYTES);
    read_bytes(path, &bytes, parts, opts)
}

/// Reads DXF bytes, in up to `parts` pieces parsed in parallel; the result does not depend on
/// `parts`.
pub(super) fn read_bytes(
    path: &Path,
    bytes: &[u8],
    parts: usize,
    opts: &ReadOptions,
) -> Result<Imported, ReadError> {
    let parts = match super::dxf_split::split(bytes, parts) {
        Some(parts) => parts,
        None => vec![Part::whole(bytes)],
    };
    let pieces: Vec<Result<Collected, (Option<usize>, ReadError)>> = std::thread::scope(|scope| {
        let handles: Vec<_> = parts
            .iter()
            .map(|part| scope.spawn(|| load_and_collect(path, part)))
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err((None, ReadError::file(path, "DXF parser thread failed")))
                })
            })
            .collect()
    });
    // The whole file fails to parse if any part does, whatever records come before; the
    // parser stops at the first error in the file, so report the one on the earliest line.
    let mut all = Vec::with_capacity(pieces.len());
    let mut first_error: Option<(Option<usize>, ReadError)> = None;
    for piece in pieces {
        match piece {
            Ok(c) => all.push(c),
            Err((line, e)) => {
                let earlier = match (&first_error, line) {
                    (None, _) => true,
                    (Some((Some(best), _)), Some(l)) => l < *best,
                    (Some((None, _)), Some(_)) => true,
                    _ => false,
                };
                if earlier {
                    first_error = Some((line, e));
                }
            }
        }
    }
    if let Some((_, e)) = first_error {
        return Err(e);
    }
    let mut points: Vec<DVec3> = Vec::new();
    let mut segments: Vec<(u32, u32)> = Vec::new();
    let mut skipped: BTreeMap<String, usize> = BTreeMap::new();
    let mut base = 0usize;
    for piece in all {
        if let Some(bad) = piece.bad {
            return Err(ReadError::record(
                path,
                format!("entity {} ({})", base + bad.index, bad.what),
                bad.msg,
            ));
        }
        let shift = points.len() as u32;
        segments.extend(piece.segments.iter().map(|&(a, b)| (a + shift, b + shift)));
        points.extend(piece.points);
        for (k, n) in piece.skipped {
            *skipped.entry(k).or_default() += n;
        }
        base += piece.entities;
    }
    if points.is_empty() {
        let found = if skipped.is_empty() {
            "no entities at all".to_string()
        } else {
            skipped
                .iter()
                .map(|(k, n)| format!("{n} {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        return Err(ReadError::file(
            path,
            format!("no LINE, LWPOLYLINE, POLYLINE or POINT entities to read (found: {found})"),
        ));
    }
    let (network, stats) = weld::assemble(&points, &segments, opts.weld);
    Ok(Imported {
        network,
        weld: Some(stats),
        skipped,
    })
}

/// What one drawing (or part of one) holds for a network.
struct Collected {
    points: Vec<DVec3>,
    segments: Vec<(u32, u32)>,
    skipped: BTreeMap<String, usize>,
    entities: usize,
    /// The first entity that cannot be read; the rest of the piece is not collected.
    bad: Option<BadEntity>,
}

struct BadEntity {
    index: usize,
    what: String,
    msg: String,
}

fn load_and_collect(path: &Path, part: &Part) -> Result<Collected, (Option<usize>, ReadError)> {
    let drawing = Drawing::load(&mut &part.text[..]).map_err(|e| load_error(path, e, part))?;
    Ok(collect(&drawing))
}

fn collect(drawing: &Drawing) -> Collected {
    let mut c = Collected {
        points: Vec::new(),
        segments: Vec::new(),
        skipped: BTreeMap::new(),
        entities: 0,
        bad: None,
    };
    for (index, entity) in drawing.entities().enumerate() {
        c.entities = index + 1;
        let fail = |msg: String| {
            Some(BadEntity {
                index,
                what: format!(
                    "{}, handle {:X}, layer \"{}\"",
                    type_name(&entity.specific),
                    entity.common.handle.0,
                    entity.common.layer
                ),
                msg,
            })
        };
        if entity.common.is_in_paper_space {
            *c.skipped.entry("paper-space entity".into()).or_default() += 1;
            continue;
        }
        let polyline: Vec<DVec3> = match &entity.specific {
            EntityType::Line(l) => vec![wcs(&l.p1), wcs(&l.p2)],
            EntityType::LwPolyline(pl) => match lw_polyline(pl, entity.common.elevation) {
                Ok(p) => p,
                Err(msg) => {
                    c.bad = fail(msg);
                    return c;
                }
            },
            EntityType::Polyline(pl) if pl.is_polyface_mesh() || pl.is_3d_polygon_mesh() => {
                *c.skipped.entry("POLYLINE mesh".into()).or_default() += 1;
                continue;
            }
            EntityType::Polyline(pl) => match polyline(pl) {
                Ok(p) => p,
                Err(msg) => {
                    c.bad = fail(msg);
                    return c;
                }
            },
            EntityType::ModelPoint(p) => vec![wcs(&p.location)],
            other => {
                *c.skipped.entry(type_name(other)).or_default() += 1;
                continue;
            }
        };
        if let Some(bad) = polyline.iter().position(|p| !p.is_finite()) {
            c.bad = fail(format!("vertex {bad} has a non-finite coordinate"));
            return c;
        }
        let first = c.points.len() as u32;
        c.segments
            .extend((1..polyline.len() as u32).map(|k| (first + k - 1, first + k)));
        c.points.extend(polyline);
    }
    c
}

/// The error for the file, with the file line it is on (when the parser gave one).
fn load_error(path: &Path, e: DxfError, part: &Part) -> (Option<usize>, ReadError) {
    let err = describe_load_error(path, e, part);
    let line = match &err {
        ReadError::Line { line, .. } => Some(*line),
        _ => None,
    };
    (line, err)
}

fn describe_load_error(path: &Path, e: DxfError, part: &Part) -> ReadError {
    let at = |o: usize| part.file_line(o);
    match e {
        DxfError::IoError(io) => ReadError::io(path, io),
        DxfError::ParseFloatError(ref err, o) => {
            ReadError::line(path, at(o), format!("not a number: {err}"))
        }
        DxfError::ParseIntError(ref err, o) => {
            ReadError::line(path, at(o), format!("not an integer: {err}"))
        }
        DxfError::ParseError(o) => ReadError::line(path, at(o), "not valid DXF"),
        DxfError::UnexpectedCode(c, o) => {
            ReadError::line(path, at(o), format!("unexpected group code {c}"))
        }
        DxfError::UnexpectedCodePair(pair, expected) => ReadError::line(
            path,
            at(pair.offset),
            format!("unexpected group code {} here ({expected})", pair.code),
        ),
        DxfError::UnexpectedByte(b, o) => {
            ReadError::line(path, at(o), format!("unexpected byte 0x{b:02x}: not DXF"))
        }
        DxfError::UnexpectedEnumValue(o) => {
            ReadError::line(path, at(o), "value out of range for its group code")
        }
        DxfError::ExpectedTableType(o) => {
            ReadError::line(path, at(o), "expected a table type after TABLE")
        }
        DxfError::WrongValueType(o) => {
            ReadError::line(path, at(o), "wrong value type for its group code")
        }
        DxfError::UnexpectedEndOfInput => ReadError::file(
            path,
            "the file ends before the drawing is complete (truncated?)",
        ),
        other => ReadError::file(path, format!("not a readable DXF: {other}")),
    }
}

/// DXF name of an entity type, e.g. "CIRCLE", from the variant name.
fn type_name(t: &EntityType) -> String {
    let dbg = format!("{t:?}");
    let name = dbg.split(['(', ' ', '{']).next().unwrap_or("ENTITY");
    match name {
        "ModelPoint" => "POINT".into(),
        "LwPolyline" => "LWPOLYLINE".into(),
        n => n.to_ascii_uppercase(),
    }
}

fn wcs(p: &Point) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

/// World axes of the object coordinate system with normal `n` (the DXF "arbitrary axis
/// algorithm"): a 2D entity's (x, y, elevation) are coordinates along these axes.
fn ocs_axes(n: DVec3) -> Result<[DVec3; 3], String> {
    let n = n
        .try_normalize()
        .ok_or("extrusion direction has zero length")?;
    let limit = 1.0 / 64.0;
    let ax = if n.x.abs() < limit && n.y.abs() < limit {
        DVec3::Y.cross(n)
    } else {
        DVec3::Z.cross(n)
    }
    .normalize();
    Ok([ax, n.cross(ax), n])
}

fn from_ocs(axes: &[DVec3; 3], x: f64, y: f64, z: f64) -> DVec3 {
    axes[0] * x + axes[1] * y + axes[2] * z
}

pub(crate) fn lw_polyline(pl: &LwPolyline, elevation: f64) -> Result<Vec<DVec3>, String> {
    let ex = &pl.extrusion_direction;
    let axes = ocs_axes(DVec3::new(ex.x, ex.y, ex.z))?;
    check_bulges(pl.vertices.iter().map(|v| v.bulge))?;
    let mut pts: Vec<DVec3> = pl
        .vertices
        .iter()
        .map(|v| from_ocs(&axes, v.x, v.y, elevation))
        .collect();
    close_if(&mut pts, pl.is_closed());
    Ok(pts)
}

pub(crate) fn polyline(pl: &Polyline) -> Result<Vec<DVec3>, String> {
    // Spline-fit polylines list their frame control points too; the curve is the other vertices.
    let vertices: Vec<&Vertex> = pl
        .vertices()
        .filter(|v| !v.is_spline_frame_control_point())
        .collect();
    let mut pts = if pl.is_3d_polyline() {
        vertices.iter().map(|v| wcs(&v.location)).collect()
    } else {
        check_bulges(vertices.iter().map(|v| v.bulge))?;
        let n = &pl.normal;
        let axes = ocs_axes(DVec3::new(n.x, n.y, n.z))?;
        let elevation = pl.location.z;
        vertices
            .iter()
            .map(|v| from_ocs(&axes, v.location.x, v.location.y, elevation))
            .collect()
    };
    close_if(&mut pts, pl.is_closed());
    Ok(pts)
}

/// Arc segments would need a chord tolerance we have no basis to choose; ask for polylines.
fn check_bulges(bulges: impl Iterator<Item = f64>) -> Result<(), String> {
    for (i, b) in bulges.enumerate() {
        if b != 0.0 {
            return Err(format!(
                "vertex {i} starts an arc segment (bulge {b}); lamina reads straight segments \
                 only: convert arcs to polylines in your CAD program"
            ));
        }
    }
    Ok(())
}

fn close_if(pts: &mut Vec<DVec3>, closed: bool) {
    if closed && pts.len() > 2 {
        pts.push(pts[0]);
    }
}

/// An empty R2000 drawing whose header holds no clock and no random GUIDs (the crate stamps
/// both; they are set to the epoch and the nil GUID) so the same content gives the same bytes.
pub(crate) fn fixed_drawing() -> Drawing {
    let mut drawing = Drawing::new();
    drawing.header.version = AcadVersion::R2000;
    drawing.header.creation_date = Default::default();
    drawing.header.creation_date_universal = Default::default();
    drawing.header.update_date = Default::default();
    drawing.header.update_date_universal = Default::default();
    drawing.header.fingerprint_guid = Default::default();
    drawing.header.version_guid = Default::default();
    drawing
}

/// A flat LWPOLYLINE through (x, y) points on `layer`.
pub(crate) fn lw_polyline_entity(
    pts: impl Iterator<Item = (f64, f64)>,
    closed: bool,
    layer: &str,
) -> Entity {
    let mut pl = LwPolyline::default();
    pl.set_is_closed(closed);
    pl.vertices = pts
        .map(|(x, y)| LwPolylineVertex {
            x,
            y,
            ..Default::default()
        })
        .collect();
    let mut e = Entity::new(EntityType::LwPolyline(pl));
    e.common.layer = layer.into();
    e
}

pub fn write(net: &Network, path: &Path) -> Result<(), WriteError> {
    let mut drawing = fixed_drawing();
    drawing.add_layer(Layer {
        name: LAYER.into(),
        ..Default::default()
    });
    let point = |p: DVec3| Point::new(p.x, p.y, p.z);
    let adj = net.adjacency();
    for (i, n) in net.nodes.iter().enumerate() {
        if adj.degree(i as u32) == 0 {
            add(
                &mut drawing,
                EntityType::ModelPoint(ModelPoint::new(point(n.p))),
            );
        }
    }
    for chain in net.chains() {
        let mut pts: Vec<DVec3> = chain
            .nodes
            .iter()
            .map(|&i| net.nodes[i as usize].p)
            .collect();
        let closed = chain.is_closed();
        if closed {
            pts.pop();
        }
        if pts.len() == 2 && !closed {
            add(
                &mut drawing,
                EntityType::Line(Line::new(point(pts[0]), point(pts[1]))),
            );
        } else if pts.iter().all(|p| p.z == pts[0].z) {
            let mut e = lw_polyline_entity(pts.iter().map(|p| (p.x, p.y)), closed, LAYER);
            e.common.elevation = pts[0].z;
            drawing.add_entity(e);
        } else {
            let mut pl = Polyline::default();
            pl.set_is_3d_polyline(true);
            pl.set_is_closed(closed);
            for p in &pts {
                let mut v = Vertex::new(point(*p));
                v.set_is_3d_polyline_vertex(true);
                pl.add_vertex(&mut drawing, v);
            }
            add(&mut drawing, EntityType::Polyline(pl));
        }
    }
    write_atomic(path, |w| {
        drawing
            .save(w)
            .map_err(|e| std::io::Error::other(e.to_string()))
    })
}

fn add(drawing: &mut Drawing, specific: EntityType) {
    let mut e = Entity::new(specific);
    e.common.layer = LAYER.into();
    drawing.add_entity(e);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ocs_of_world_z_is_identity() -> Result<(), String> {
        let axes = ocs_axes(DVec3::Z)?;
        assert_eq!(axes, [DVec3::X, DVec3::Y, DVec3::Z]);
        Ok(())
    }

    #[test]
    fn ocs_of_flipped_z_mirrors_x() -> Result<(), String> {
        // A 2D entity drawn with extrusion (0,0,-1), as mirrored CAD geometry often is.
        let axes = ocs_axes(-DVec3::Z)?;
        assert_eq!(from_ocs(&axes, 1.0, 2.0, 3.0), DVec3::new(-1.0, 2.0, -3.0));
        Ok(())
    }
}

#[cfg(test)]
mod split_tests {
    use super::*;

    fn fixture() -> Vec<u8> {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/networks/ezdxf_veins.dxf");
        std::fs::read(p).expect("fixture present")
    }

    fn outcome(bytes: &[u8], parts: usize) -> Result<(Network, BTreeMap<String, usize>), String> {
        read_bytes(Path::new("f.dxf"), bytes, parts, &ReadOptions::default())
            .map(|i| (i.network, i.skipped))
            .map_err(|e| e.to_string())
    }

    #[test]
    fn parts_give_the_same_network_as_the_whole_file() {
        let bytes = fixture();
        assert!(super::super::dxf_split::split(&bytes, 5).is_some_and(|p| p.len() == 6));
        let whole = outcome(&bytes, 1);
        assert!(whole.is_ok(), "{whole:?}");
        for parts in 2..=7 {
            assert_eq!(outcome(&bytes, parts), whole, "{parts} parts");
        }
    }

    #[test]
    fn parts_report_the_same_errors_as_the_whole_file() {
        let text = String::from_utf8(fixture()).expect("ASCII fixture");
        let lines: Vec<&str> = text.lines().collect();
        let entities = lines
            .iter()
            .position(|l| l.trim() == "ENTITIES")
            .expect("has ENTITIES");
        let endsec = (entities..lines.len())
            .find(|&i| lines[i].trim() == "ENDSEC")
            .expect("ENTITIES ends");
        // x coordinates (value lines after a " 10" code line): one in the middle of the
        // entities, and the last in the file, which lies past them (in OBJECTS).
        let xs: Vec<usize> = (entities..lines.len())
            .filter(|&i| i % 2 == 0 && lines[i].trim() == "10")
            .map(|i| i + 1)
            .collect();
        let middle = *xs
            .iter()
            .find(|&&i| i > (entities + endsec) / 2)
            .expect("an x");
        let last = *xs.last().expect("an x");
        assert!(last > endsec);
        let mut broken: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        for victim in [middle, last] {
            broken[victim] = "abc".into();
            let bad = broken.join("\n").into_bytes();
            let whole = outcome(&bad, 1).expect_err("parse error");
            // The crate notices a few lines on, where the pairs stop making sense.
            let line: usize = whole
                .split("line ")
                .nth(1)
                .and_then(|r| r.split(':').next())
                .and_then(|n| n.parse().ok())
                .expect("the error names a line");
            assert!(
                (victim + 1..victim + 12).contains(&line),
                "line {} broken: {whole}",
                victim + 1
            );
            for parts in 2..=6 {
                assert_eq!(outcome(&bad, parts).expect_err("parse error"), whole);
            }
            broken[victim] = lines[victim].to_string();
        }
        let victim = middle;
        // A non-finite coordinate: a record error naming the same entity however it is split.
        broken[victim] = "nan".into();
        let nan = broken.join("\n").into_bytes();
        let whole = outcome(&nan, 1).expect_err("record error");
        assert!(whole.contains("non-finite"), "{whole}");
        for parts in 2..=6 {
            assert_eq!(outcome(&nan, parts).expect_err("record error"), whole);
        }
    }
}
