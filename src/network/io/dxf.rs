//! Network DXF through the `dxf` crate. Read: model-space LINE, POINT, LWPOLYLINE, POLYLINE (2D
//! and 3D; bulges flattened), ARC, CIRCLE, ELLIPSE, SPLINE (flattened within the chord
//! tolerance) and INSERT/MINSERT (blocks expanded), taken to millimetres from the file's units
//! (see `units`); everything else is counted by its DXF name as skipped (`dxf_entities`). A file
//! with nothing to read is an error. Write: R2000, layer NETWORK, millimetres; one LINE per lone
//! edge, one LWPOLYLINE per chain that lies at one height, one 3D POLYLINE per other chain, one
//! POINT per isolated node.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use dxf::entities::{Entity, EntityType, Line, LwPolyline, ModelPoint, Polyline, Vertex};
use dxf::enums::{AcadVersion, DrawingUnits, Units};
use dxf::tables::Layer;
use dxf::{Drawing, DxfError, LwPolylineVertex, Point};
use glam::DVec3;

use super::dxf_entities::{
    collect, default_max_points, from_ocs, ocs_axes, Collected, Context, MAX_POINTS,
};
pub(crate) use super::dxf_entities::{placements, type_name};
use super::dxf_groups::{walk_groups, Place};
use super::dxf_hatch::{read_hatches, Hatch, Hatches};
use super::dxf_split::Part;
use super::units::{dxf_units, scale_to_mm};
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
    let units = dxf_units(bytes, opts.units);
    let parts = match super::dxf_split::split(bytes, parts) {
        Some(parts) => parts,
        None => vec![Part::whole(bytes)],
    };
    let budget = opts
        .max_points
        .unwrap_or_else(|| default_max_points(bytes.len()))
        .min(MAX_POINTS);
    let tol = opts.chord_tolerance / units.scale_to_mm;
    let hatches = if opts.hatch_boundaries {
        read_hatches(bytes)
    } else {
        Ok(Hatches::default())
    };
    let none = HashMap::new();
    let block_hatches = hatches.as_ref().map_or(&none, |h| &h.blocks);
    // A file the parser refuses is reported as such before any HATCH in it.
    let (pieces, block_parsed) = parse_and_collect(path, &parts, tol, budget, block_hatches)?;
    let hatches =
        hatches.map_err(|e| ReadError::record(path, format!("line {} (HATCH)", e.line), e.msg))?;
    let mut points: Vec<DVec3> = Vec::new();
    let mut segments: Vec<(u32, u32)> = Vec::new();
    let mut skipped: BTreeMap<String, usize> = BTreeMap::new();
    let mut inserts = 0;
    let mut base = 0usize;
    let mut parsed: BTreeMap<String, usize> = BTreeMap::new();
    let mut expanded: BTreeSet<String> = BTreeSet::new();
    let total: usize = pieces.iter().map(|p| p.points.len()).sum();
    // Model-space HATCH boundaries, flattened within what the budget leaves.
    let mut loops: Vec<Vec<DVec3>> = Vec::new();
    let mut hatch_points = 0usize;
    let mut hatches_over = false;
    for (line, h) in &hatches.model {
        let left = budget.saturating_sub(total + hatch_points);
        let Some(these) = h
            .loops(tol, left)
            .map_err(|m| ReadError::record(path, format!("line {line} (HATCH)"), m))?
        else {
            hatches_over = true;
            break;
        };
        for l in these {
            hatch_points += l.len();
            loops.push(l);
        }
    }
    if hatches_over || pieces.iter().any(|p| p.over_budget) || total + hatch_points > budget {
        return Err(ReadError::file(
            path,
            format!(
                "the drawing expands to more than {budget} points (curves flattened at {} mm, \
                 blocks inserted): raise --chord-tolerance, explode the arrays, or allow more \
                 with --max-points (at most {MAX_POINTS}){}",
                opts.chord_tolerance,
                if opts.max_points.is_none() && budget < MAX_POINTS {
                    format!(
                        "; {budget} is the default for a file of {} bytes",
                        bytes.len()
                    )
                } else {
                    String::new()
                }
            ),
        ));
    }
    points.reserve_exact(total);
    segments.reserve_exact(pieces.iter().map(|p| p.segments.len()).sum());
    for piece in pieces {
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
        inserts += piece.inserts;
        base += piece.entities;
        for (k, n) in piece.parsed {
            *parsed.entry(k).or_default() += n;
        }
        expanded.extend(piece.expanded);
    }
    points.reserve_exact(hatch_points);
    for l in &loops {
        let first = points.len() as u32;
        points.extend(l);
        segments.extend((1..l.len() as u32).map(|k| (first + k - 1, first + k)));
    }
    let hatch_count = hatches.model.len() + hatches.paper;
    if hatch_count > 0 {
        *parsed.entry("HATCH".into()).or_default() += hatch_count;
    }
    if hatches.paper > 0 {
        *skipped.entry("paper-space entity".into()).or_default() += hatches.paper;
    }
    // Entities the dxf crate drops without a trace (HATCH, MULTILEADER, MESH, ARC_DIMENSION,
    // some DIMENSION subtypes…): the file's own count of each name, less what was parsed, in
    // model space and in the blocks the drawing inserts.
    let census = entity_census(bytes);
    for (name, n) in &census.model {
        let dropped = n.saturating_sub(parsed.get(name).copied().unwrap_or(0));
        if dropped > 0 {
            *skipped.entry(name.clone()).or_default() += dropped;
        }
    }
    for block in &expanded {
        let (Some(held), Some(read)) = (census.blocks.get(block), block_parsed.get(block)) else {
            continue;
        };
        for (name, n) in held {
            let dropped = n.saturating_sub(read.get(name).copied().unwrap_or(0));
            if dropped > 0 {
                *skipped
                    .entry(format!("{name} (in block definitions)"))
                    .or_default() += dropped;
            }
        }
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
        let faces = ["3DFACE", "POLYLINE (mesh)", "MESH"];
        let only_faces = !skipped.is_empty() && skipped.keys().all(|k| faces.contains(&k.as_str()));
        let hint = if only_faces {
            ": it is a mesh of faces, not a network of lines; `lamina audit` reads its panels"
        } else if skipped.contains_key("HATCH") {
            "; hatch_boundaries= reads the boundaries of its HATCH fills as loops"
        } else {
            ""
        };
        return Err(ReadError::file(
            path,
            format!(
                "no LINE, POLYLINE, ARC, CIRCLE, ELLIPSE, SPLINE, POINT or block geometry in \
                 model space to read (found: {found}){hint}"
            ),
        ));
    }
    if let Err(bad) = scale_to_mm(&mut points, &units) {
        return Err(ReadError::file(
            path,
            format!(
                "point {bad} is out of range once taken from {} to mm",
                units.unit
            ),
        ));
    }
    let (network, stats) = weld::assemble(&points, &segments, opts.weld);
    Ok(Imported {
        network,
        weld: Some(stats),
        skipped,
        units: Some(units),
        inserts,
        split: None,
    })
}

/// Entity names (group code 0) in the ENTITIES section of an ASCII DXF, counted, and in each
/// block definition of the BLOCKS section: what the file holds, whatever the parser reads.
/// Lines are split on `\n` with surrounding whitespace (and `\r`) trimmed.
pub(crate) struct EntityCensus {
    pub model: BTreeMap<String, usize>,
    /// Per block name (upper case): its entities' names, counted.
    pub blocks: BTreeMap<String, BTreeMap<String, usize>>,
}

pub(crate) fn entity_census(bytes: &[u8]) -> EntityCensus {
    let mut census = EntityCensus {
        model: BTreeMap::new(),
        blocks: BTreeMap::new(),
    };
    walk_groups(bytes, |place, g| {
        // Records that belong to the entity before them, as the parser folds them.
        if g.code != 0 || matches!(g.value, b"VERTEX" | b"SEQEND" | b"ATTRIB") {
            return;
        }
        let name = String::from_utf8_lossy(g.value).into_owned();
        match place {
            Place::Entities => *census.model.entry(name).or_default() += 1,
            Place::Block(b) => {
                *census
                    .blocks
                    .entry(b.to_string())
                    .or_default()
                    .entry(name)
                    .or_default() += 1
            }
            Place::Other => {}
        }
    });
    census
}

/// Parses the first part (the header and the blocks: the whole file, or its skeleton), then
/// every other part on its own thread, each walked into points as soon as it is parsed and
/// dropped. The whole file fails to parse if any part does, whatever records come before; the
/// parser stops at the first error in the file, so report the one on the earliest line.
fn parse_and_collect(
    path: &Path,
    parts: &[Part],
    chord_tolerance: f64,
    budget: usize,
    block_hatches: &HashMap<String, Vec<(usize, Hatch)>>,
) -> Result<(Vec<Collected>, BlockCounts), ReadError> {
    let first = match parse_part(path, &parts[0]) {
        Ok(d) => d,
        // An error after the entities can be later in the file than one inside them.
        Err(e) if parts.len() == 1 => return Err(e.1),
        Err(_) => {
            return Err(first_error(
                path,
                parts.iter().map(|p| parse_part(path, p).err()),
            ))
        }
    };
    let ctx = Context::new(&first, chord_tolerance, block_hatches);
    let blocks: BlockCounts = ctx
        .blocks
        .iter()
        .map(|(name, b)| {
            let mut counts = BTreeMap::new();
            for e in &b.entities {
                *counts.entry(type_name(&e.specific)).or_default() += 1;
            }
            if let Some(h) = block_hatches.get(name) {
                *counts.entry("HATCH".into()).or_default() += h.len();
            }
            (name.clone(), counts)
        })
        .collect();
    let rest: Vec<Result<Collected, (Option<usize>, ReadError)>> = std::thread::scope(|scope| {
        let handles: Vec<_> = parts[1..]
            .iter()
            .map(|part| {
                let ctx = &ctx;
                scope.spawn(move || parse_part(path, part).map(|d| collect(&d, ctx, budget)))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err((None, ReadError::file(path, "DXF reader thread failed")))
                })
            })
            .collect()
    });
    if rest.iter().any(|r| r.is_err()) {
        return Err(first_error(path, rest.into_iter().map(|r| r.err())));
    }
    let mut pieces = vec![collect(&first, &ctx, budget)];
    pieces.extend(rest.into_iter().flatten());
    Ok((pieces, blocks))
}

/// Entity names counted per block definition (upper-case block names).
type BlockCounts = BTreeMap<String, BTreeMap<String, usize>>;

/// Parses one part on a parser thread, the crate's panics turned into errors.
fn parse_part(path: &Path, part: &Part) -> Result<Drawing, (Option<usize>, ReadError)> {
    std::thread::scope(|scope| {
        let handle = std::thread::Builder::new()
            .name(PARSER_THREAD.into())
            .spawn_scoped(scope, || {
                Drawing::load(&mut &part.text[..]).map_err(|e| load_error(path, e, part))
            })
            .map_err(|e| (None, ReadError::io(path, e)))?;
        handle
            .join()
            .unwrap_or_else(|panic| Err((None, parser_panic(path, panic))))
    })
}

/// Of the parts' errors, the one on the earliest file line (one without a line counts as
/// later than any with one, and the first of those is kept).
fn first_error(
    path: &Path,
    errors: impl Iterator<Item = Option<(Option<usize>, ReadError)>>,
) -> ReadError {
    let mut first: Option<(Option<usize>, ReadError)> = None;
    for (line, e) in errors.flatten() {
        let earlier = match (&first, line) {
            (None, _) => true,
            (Some((Some(best), _)), Some(l)) => l < *best,
            (Some((None, _)), Some(_)) => true,
            _ => false,
        };
        if earlier {
            first = Some((line, e));
        }
    }
    first.map_or_else(
        || ReadError::file(path, "DXF reader thread failed"),
        |(_, e)| e,
    )
}

/// The name of the threads that run the `dxf` crate's parser. A value it cannot take (a header
/// date of 1e12 days overflows its date arithmetic) makes it panic; the panic is caught and
/// reported as this file's error, and the CLI's panic hook keeps quiet for threads of this name.
pub const PARSER_THREAD: &str = "lamina-dxf-parser";

/// Loads a whole drawing on a parser thread, the crate's panics turned into errors.
pub(crate) fn load_drawing(path: &Path, bytes: &[u8]) -> Result<Drawing, ReadError> {
    let part = Part::whole(bytes);
    std::thread::scope(|scope| {
        let handle = std::thread::Builder::new()
            .name(PARSER_THREAD.into())
            .spawn_scoped(scope, || {
                Drawing::load(&mut &part.text[..]).map_err(|e| load_error(path, e, &part).1)
            })
            .map_err(|e| ReadError::io(path, e))?;
        handle.join().map_err(|panic| parser_panic(path, panic))?
    })
}

/// The error for a panic inside the `dxf` crate, with its message.
fn parser_panic(path: &Path, panic: Box<dyn std::any::Any + Send>) -> ReadError {
    let what = panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into());
    let hint = if what.contains("TimeDelta") || what.contains("date") {
        " (a header date such as $TDUPDATE is out of range)"
    } else {
        ""
    };
    ReadError::file(
        path,
        format!(
            "not a readable DXF: the parser failed on a value: {}{hint}",
            what.escape_debug()
        ),
    )
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

fn wcs(p: &Point) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

/// A straight-segment LWPOLYLINE's corners in world coordinates (for panels, where an arc
/// segment has no meaning): a bulge is refused.
pub(crate) fn lw_polyline(pl: &LwPolyline, elevation: f64) -> Result<Vec<DVec3>, String> {
    let axes = ocs_axes(&pl.extrusion_direction)?;
    check_bulges(pl.vertices.iter().map(|v| v.bulge))?;
    let mut pts: Vec<DVec3> = pl
        .vertices
        .iter()
        .map(|v| from_ocs(&axes, v.x, v.y, elevation))
        .collect();
    close_if(&mut pts, pl.is_closed());
    Ok(pts)
}

/// A straight-segment POLYLINE's corners in world coordinates; a bulge is refused.
pub(crate) fn polyline(pl: &Polyline) -> Result<Vec<DVec3>, String> {
    let vertices: Vec<&Vertex> = pl
        .vertices()
        .filter(|v| !v.is_spline_frame_control_point())
        .collect();
    let mut pts = if pl.is_3d_polyline() {
        vertices.iter().map(|v| wcs(&v.location)).collect()
    } else {
        check_bulges(vertices.iter().map(|v| v.bulge))?;
        let axes = ocs_axes(&pl.normal)?;
        let elevation = pl.location.z;
        vertices
            .iter()
            .map(|v| from_ocs(&axes, v.location.x, v.location.y, elevation))
            .collect()
    };
    close_if(&mut pts, pl.is_closed());
    Ok(pts)
}

/// A panel's outline is straight-sided; an arc segment is refused rather than guessed at.
fn check_bulges(bulges: impl Iterator<Item = f64>) -> Result<(), String> {
    for (i, b) in bulges.enumerate() {
        if b != 0.0 {
            return Err(format!(
                "vertex {i} starts an arc segment (bulge {b}); a panel has straight sides"
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

/// An empty R2000 drawing in millimetres whose header holds no clock and no random GUIDs (the
/// crate stamps both; they are set to the epoch and the nil GUID) so the same content gives the
/// same bytes.
pub(crate) fn fixed_drawing() -> Drawing {
    let mut drawing = Drawing::new();
    drawing.header.version = AcadVersion::R2000;
    drawing.header.creation_date = Default::default();
    drawing.header.creation_date_universal = Default::default();
    drawing.header.update_date = Default::default();
    drawing.header.update_date_universal = Default::default();
    drawing.header.fingerprint_guid = Default::default();
    drawing.header.version_guid = Default::default();
    // Millimetres, said both ways: $INSUNITS = 4 and $MEASUREMENT = 1 (metric).
    drawing.header.default_drawing_units = Units::Millimeters;
    drawing.header.drawing_units = DrawingUnits::Metric;
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
    write_atomic(path, |w| super::dxf_write::save(&mut drawing, w))
}

fn add(drawing: &mut Drawing, specific: EntityType) {
    let mut e = Entity::new(specific);
    e.common.layer = LAYER.into();
    drawing.add_entity(e);
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
