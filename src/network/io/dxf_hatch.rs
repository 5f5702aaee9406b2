//! HATCH boundaries as closed loops (`ReadOptions::hatch_boundaries`). The `dxf` crate drops
//! HATCH entities, so their group codes are read here from the file's text: those of the
//! ENTITIES section, and those of each block definition (placed where the block is inserted).
//!
//! A HATCH holds a count of boundary paths (code 91), each either a polyline path (flag 92 bit
//! 2: codes 72 has-bulge, 73 closed, 93 vertex count, then 10/20 and 42 per vertex) or an edge
//! path (93 edge count, then per edge 72 = 1 line 10/20 11/21, 2 circular arc 10/20 40 50 51
//! 73, 3 elliptic arc 10/20 11/21 40 50 51 73, 4 spline 94 73 74 95 96, knots 40, control
//! points 10/20 with 42 weights, fit data 97 11/21, tangents 12/22 13/23), then 97 and its 330
//! references. The counts drive the reading; nothing is allocated from a count.
//!
//! Each path becomes one closed polyline in the HATCH's object coordinate system (elevation
//! from code 30, extrusion 210/220/230) taken to world coordinates: bulges, arcs, elliptic arcs
//! and splines flattened within the chord tolerance, edges chained end to start (an edge drawn
//! the other way is reversed; a gap between edges is closed by a straight segment, as the fill
//! closes it). Clockwise arc and ellipse edges store their angles as 360° less the angle, start
//! and end swapped (as ezdxf reads them); ellipse angles are taken to parameters.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use super::dxf_entities::{bulged, from_ocs, ocs_axes};
use super::dxf_groups::{walk_groups, Group as Tag, Place};
use crate::geom::curves::{self, Nurbs, MAX_CONTROL_POINTS, MAX_DEGREE};

/// The HATCH entities of a file, read but not yet flattened: those of model space, and those of
/// each block definition (by upper-case block name), each with the line of its code 0.
#[derive(Debug, Default)]
pub(super) struct Hatches {
    pub model: Vec<(usize, Hatch)>,
    /// HATCH entities in paper space (left out).
    pub paper: usize,
    pub blocks: HashMap<String, Vec<(usize, Hatch)>>,
}

/// A HATCH that cannot be read: the line of its code 0, then what is wrong.
#[derive(Debug, PartialEq)]
pub(super) struct HatchError {
    pub line: usize,
    pub msg: String,
}

/// One HATCH's boundary paths in its object coordinate system.
#[derive(Debug)]
pub(super) struct Hatch {
    axes: [DVec3; 3],
    elevation: f64,
    paths: Vec<Path>,
}

#[derive(Debug)]
enum Path {
    /// Vertices and the bulge of the segment each starts.
    Polyline(Vec<(DVec2, f64)>),
    Edges(Vec<Edge>),
}

#[derive(Debug)]
enum Edge {
    Line(DVec2, DVec2),
    /// Start angle and counter-clockwise sweep, radians.
    Arc {
        center: DVec2,
        radius: f64,
        start: f64,
        sweep: f64,
    },
    /// Parameters t0 < t1 of `center + major cos t + minor sin t`.
    Ellipse {
        center: DVec2,
        major: DVec2,
        minor: DVec2,
        t0: f64,
        t1: f64,
    },
    Spline {
        degree: usize,
        knots: Vec<f64>,
        control: Vec<DVec3>,
        weights: Vec<f64>,
        fit: Vec<DVec3>,
    },
}

/// Reads every HATCH of the ENTITIES and BLOCKS sections.
pub(super) fn read_hatches(bytes: &[u8]) -> Result<Hatches, HatchError> {
    let mut out = Hatches::default();
    let mut failure = None;
    // The HATCH being gathered: where it is, the line of its code 0, and its groups.
    let mut open: Option<(Option<String>, usize, Vec<Tag>)> = None;
    let mut finish = |open: Option<(Option<String>, usize, Vec<Tag>)>, out: &mut Hatches| {
        let Some((block, line, tags)) = open else {
            return;
        };
        match read_hatch(&tags) {
            Err(msg) => {
                failure.get_or_insert(HatchError { line, msg });
            }
            Ok((h, paper)) => match block {
                Some(b) => out.blocks.entry(b).or_default().push((line, h)),
                None if paper => out.paper += 1,
                None => out.model.push((line, h)),
            },
        }
    };
    walk_groups(bytes, |place, g| {
        if g.code == 0 {
            finish(open.take(), &mut out);
            if g.value == b"HATCH" {
                open = match place {
                    Place::Entities => Some((None, g.line, Vec::new())),
                    Place::Block(b) => Some((Some(b.to_string()), g.line, Vec::new())),
                    Place::Other => None,
                };
            }
        } else if let Some((_, _, tags)) = &mut open {
            tags.push(g);
        }
    });
    finish(open.take(), &mut out);
    match failure {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

impl Hatch {
    /// Each boundary path as a closed polyline in world coordinates, curves within `tol`;
    /// None once they hold more than `limit` points.
    pub fn loops(&self, tol: f64, limit: usize) -> Result<Option<Vec<Vec<DVec3>>>, String> {
        let mut loops = Vec::new();
        let mut count = 0usize;
        for (k, path) in self.paths.iter().enumerate() {
            let within = |m: String| format!("boundary path {}: {m}", k + 1);
            let mut pts = match path {
                Path::Polyline(v) => bulged(v, true, tol).map_err(within)?,
                Path::Edges(edges) => {
                    // Counted edge by edge, so an edge path never holds more than the limit.
                    let mut flat = Vec::new();
                    let mut held = count;
                    for (i, e) in edges.iter().enumerate() {
                        let f = e
                            .flatten(tol)
                            .map_err(|m| within(format!("edge {}: {m}", i + 1)))?;
                        held += f.len();
                        if held > limit {
                            return Ok(None);
                        }
                        flat.push(f);
                    }
                    chained(flat)
                }
            };
            if let (Some(&first), Some(&last)) = (pts.first(), pts.last()) {
                if first != last && pts.len() > 2 {
                    pts.push(first);
                }
            }
            count += pts.len();
            if count > limit {
                return Ok(None);
            }
            if pts.len() >= 2 {
                loops.push(
                    pts.iter()
                        .map(|p| from_ocs(&self.axes, p.x, p.y, self.elevation))
                        .collect(),
                );
            }
        }
        Ok(Some(loops))
    }
}

impl Edge {
    fn flatten(&self, tol: f64) -> Result<Vec<DVec2>, String> {
        let curve = |e: curves::CurveError| e.to_string();
        let flat = |pts: Vec<DVec3>| pts.iter().map(|p| p.truncate()).collect();
        match self {
            Edge::Line(a, b) => Ok(vec![*a, *b]),
            Edge::Arc {
                center,
                radius,
                start,
                sweep,
            } => curves::arc(*center, *radius, *start, *sweep, tol).map_err(curve),
            Edge::Ellipse {
                center,
                major,
                minor,
                t0,
                t1,
            } => curves::ellipse(
                center.extend(0.0),
                major.extend(0.0),
                minor.extend(0.0),
                *t0,
                *t1,
                tol,
            )
            .map(flat)
            .map_err(curve),
            Edge::Spline {
                degree,
                knots,
                control,
                weights,
                fit,
            } => {
                if control.is_empty() {
                    return curves::through_points(fit, false, tol)
                        .map(flat)
                        .map_err(curve);
                }
                Nurbs {
                    degree: *degree,
                    knots,
                    control,
                    weights: (!weights.is_empty()).then_some(weights.as_slice()),
                }
                .flatten(tol)
                .map(flat)
                .map_err(|e| format!("spline: {e}"))
            }
        }
    }
}

/// One HATCH from its groups (after its code 0), and whether it is in paper space.
fn read_hatch(tags: &[Tag]) -> Result<(Hatch, bool), String> {
    let mut c = Cursor { tags, at: 0 };
    let (mut elevation, mut normal, mut paper) = (0.0, dxf::Vector::z_axis(), false);
    // The header, up to the path count.
    loop {
        let Some(t) = c.peek(0) else {
            return Err("has no boundary path count (group code 91)".into());
        };
        match t.code {
            91 => break,
            30 => elevation = number(t)?,
            210 => normal.x = number(t)?,
            220 => normal.y = number(t)?,
            230 => normal.z = number(t)?,
            67 => paper = integer(t)? == 1,
            _ => {}
        }
        c.at += 1;
    }
    let axes = ocs_axes(&normal)?;
    let n = c.count(91, "boundary paths")?;
    let paths = (0..n)
        .map(|k| path(&mut c).map_err(|m| format!("boundary path {}: {m}", k + 1)))
        .collect::<Result<_, _>>()?;
    let hatch = Hatch {
        axes,
        elevation,
        paths,
    };
    Ok((hatch, paper))
}

/// One boundary path's groups.
fn path(c: &mut Cursor) -> Result<Path, String> {
    let flag = c.integer(92)?;
    let path = if flag & 2 != 0 {
        polyline_path(c)?
    } else {
        let n = c.count(93, "edges")?;
        Path::Edges(
            (0..n)
                .map(|k| edge(c).map_err(|m| format!("edge {}: {m}", k + 1)))
                .collect::<Result<_, _>>()?,
        )
    };
    // Source boundary objects: a count and as many references.
    if c.peek(0).is_some_and(|t| t.code == 97) {
        c.at += 1;
        while c.peek(0).is_some_and(|t| t.code == 330) {
            c.at += 1;
        }
    }
    Ok(path)
}

fn polyline_path(c: &mut Cursor) -> Result<Path, String> {
    let mut has_bulge = false;
    while let Some(t) = c.peek(0) {
        match t.code {
            72 => has_bulge = integer(t)? != 0,
            73 => {} // "is closed": a boundary is closed whatever it says
            93 => break,
            _ => return Err(unexpected(t, "a polyline path's vertex count (93)")),
        }
        c.at += 1;
    }
    let n = c.count(93, "vertices")?;
    let mut v = Vec::new();
    for _ in 0..n {
        let p = c.point(10)?;
        let bulge = match c.peek(0) {
            Some(t) if t.code == 42 => {
                c.at += 1;
                number(t)?
            }
            _ => 0.0,
        };
        v.push((p, if has_bulge { bulge } else { 0.0 }));
    }
    Ok(Path::Polyline(v))
}

/// One edge of an edge path.
fn edge(c: &mut Cursor) -> Result<Edge, String> {
    match c.integer(72)? {
        1 => {
            let f = c.fields(&[10, 20, 11, 21])?;
            Ok(Edge::Line(DVec2::new(f[0], f[1]), DVec2::new(f[2], f[3])))
        }
        2 => {
            let f = c.fields(&[10, 20, 40, 50, 51, 73])?;
            let (start, sweep) = ccw_span(f[3], f[4], f[5]);
            Ok(Edge::Arc {
                center: DVec2::new(f[0], f[1]),
                radius: f[2],
                start,
                sweep,
            })
        }
        3 => {
            let f = c.fields(&[10, 20, 11, 21, 40, 50, 51, 73])?;
            let (center, major, ratio) = (DVec2::new(f[0], f[1]), DVec2::new(f[2], f[3]), f[4]);
            if ratio <= 0.0 || major.length() == 0.0 {
                return Err(format!(
                    "an ellipse with minor-to-major ratio {ratio} and a major axis of length {}",
                    major.length()
                ));
            }
            let (start, sweep) = ccw_span(f[5], f[6], f[7]);
            // Angles from the major axis, taken to the ellipse's parameter.
            let param = |a: f64| (a.sin() / ratio).atan2(a.cos());
            let t0 = param(start);
            let mut t1 = param(start + sweep);
            if t1 <= t0 {
                t1 += std::f64::consts::TAU;
            }
            Ok(Edge::Ellipse {
                center,
                major,
                minor: major.perp() * ratio,
                t0,
                t1,
            })
        }
        4 => spline_edge(c),
        other => Err(format!(
            "edge type {other} (72): 1 line, 2 arc, 3 ellipse or 4 spline"
        )),
    }
}

/// A hatch arc's start angle and counter-clockwise sweep in radians from its 50, 51 and 73
/// (counter-clockwise flag); a sweep of 0 is a whole turn.
fn ccw_span(start: f64, end: f64, ccw: f64) -> (f64, f64) {
    let (a0, a1) = if ccw != 0.0 {
        (start, end)
    } else {
        (360.0 - end, 360.0 - start)
    };
    let sweep = (a1 - a0).rem_euclid(360.0);
    let sweep = if sweep == 0.0 { 360.0 } else { sweep };
    (a0.to_radians(), sweep.to_radians())
}

fn spline_edge(c: &mut Cursor) -> Result<Edge, String> {
    let (mut degree, mut knots_n, mut control_n) = (None, None, None);
    while let Some(t) = c.peek(0) {
        match t.code {
            94 => degree = Some(c.count(94, "degree")?),
            95 => knots_n = Some(c.count(95, "knots")?),
            96 => control_n = Some(c.count(96, "control points")?),
            73 | 74 => c.at += 1, // rational, periodic: the weights say the first
            _ => break,
        }
    }
    let (Some(degree), Some(knots_n), Some(control_n)) = (degree, knots_n, control_n) else {
        return Err(
            "a spline edge without its degree (94), knot count (95) and control point count (96)"
                .into(),
        );
    };
    if degree > MAX_DEGREE || control_n > MAX_CONTROL_POINTS {
        return Err(format!(
            "a spline of degree {degree} with {control_n} control points (at most degree \
             {MAX_DEGREE} and {MAX_CONTROL_POINTS} points)"
        ));
    }
    let knots = (0..knots_n)
        .map(|_| c.number(40))
        .collect::<Result<Vec<_>, _>>()?;
    let mut control = Vec::new();
    let mut weights = Vec::new();
    for _ in 0..control_n {
        control.push(c.point(10)?.extend(0.0));
        if let Some(t) = c.peek(0).filter(|t| t.code == 42) {
            c.at += 1;
            weights.push(number(t)?);
        }
    }
    if !weights.is_empty() && weights.len() != control.len() {
        return Err(format!(
            "{} weights for {} control points",
            weights.len(),
            control.len()
        ));
    }
    // Fit data (a count, then points), told from the path's own 97 by what follows it.
    let mut fit = Vec::new();
    if let (Some(t), next) = (c.peek(0), c.peek(1)) {
        let fits = matches!(next.map(|n| n.code), Some(11..=13))
            || (t.value == b"0" && matches!(next.map(|n| n.code), Some(72 | 97)));
        if t.code == 97 && fits {
            let n = c.count(97, "fit points")?;
            for _ in 0..n {
                fit.push(c.point(11)?.extend(0.0));
            }
        }
    }
    for code in [12, 13] {
        if c.peek(0).is_some_and(|t| t.code == code) {
            c.point(code)?;
        }
    }
    if control.is_empty() && fit.len() < 2 {
        return Err("a spline edge with neither control points nor two fit points".into());
    }
    Ok(Edge::Spline {
        degree,
        knots,
        control,
        weights,
        fit,
    })
}

/// The edges of a path as one polyline: each edge turned to start at the end nearer the last
/// one's end (the first turned to end nearer the second), gaps bridged by a straight segment.
fn chained(mut edges: Vec<Vec<DVec2>>) -> Vec<DVec2> {
    edges.retain(|e| !e.is_empty());
    let ends = |e: &Vec<DVec2>| (e[0], e[e.len() - 1]);
    if edges.len() >= 2 {
        let (a, b) = ends(&edges[1]);
        let (s, e) = ends(&edges[0]);
        let gap = |p: DVec2| p.distance(a).min(p.distance(b));
        if gap(s) < gap(e) {
            edges[0].reverse();
        }
    }
    let mut out: Vec<DVec2> = Vec::new();
    for mut e in edges {
        if let Some(&last) = out.last() {
            let (s, t) = ends(&e);
            if last.distance(t) < last.distance(s) {
                e.reverse();
            }
            if e[0] == last {
                e.remove(0);
            }
        }
        out.extend(e);
    }
    out
}

struct Cursor<'a, 'b> {
    tags: &'b [Tag<'a>],
    at: usize,
}

impl<'a> Cursor<'a, '_> {
    fn peek(&self, k: usize) -> Option<Tag<'a>> {
        self.tags.get(self.at + k).copied()
    }

    /// The next group, which must have `code`.
    fn take(&mut self, code: i32) -> Result<Tag<'a>, String> {
        match self.peek(0) {
            Some(t) if t.code == code => {
                self.at += 1;
                Ok(t)
            }
            Some(t) => Err(unexpected(t, &format!("group code {code}"))),
            None => Err(format!("the HATCH ends where group code {code} was due")),
        }
    }

    fn number(&mut self, code: i32) -> Result<f64, String> {
        number(self.take(code)?)
    }

    fn integer(&mut self, code: i32) -> Result<i64, String> {
        integer(self.take(code)?)
    }

    /// A count, at most the groups left (each counted item takes at least one).
    fn count(&mut self, code: i32, what: &str) -> Result<usize, String> {
        let t = self.take(code)?;
        let n = integer(t)?;
        let left = self.tags.len() - self.at;
        usize::try_from(n)
            .ok()
            .filter(|&n| n <= left)
            .ok_or_else(|| {
                format!(
                    "line {}: {n} {what} (group code {code}), but {left} groups follow",
                    t.line
                )
            })
    }

    /// A point from `code` (x) and `code + 10` (y).
    fn point(&mut self, code: i32) -> Result<DVec2, String> {
        Ok(DVec2::new(self.number(code)?, self.number(code + 10)?))
    }

    /// The values of `codes`, each once, in any order, as long as the groups have one of them.
    fn fields(&mut self, codes: &[i32]) -> Result<Vec<f64>, String> {
        let mut values = vec![None; codes.len()];
        while let Some(t) = self.peek(0) {
            let Some(k) = codes.iter().position(|&c| c == t.code) else {
                break;
            };
            if values[k].is_some() {
                break;
            }
            values[k] = Some(number(t)?);
            self.at += 1;
        }
        values
            .iter()
            .zip(codes)
            .map(|(v, code)| v.ok_or_else(|| format!("group code {code} is missing")))
            .collect()
    }
}

fn unexpected(t: Tag, wanted: &str) -> String {
    format!(
        "line {}: group code {} where {wanted} was due",
        t.line, t.code
    )
}

fn number(t: Tag) -> Result<f64, String> {
    std::str::from_utf8(t.value)
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            format!(
                "line {}: group code {} holds \"{}\", not a finite number",
                t.line,
                t.code,
                crate::text::printable(&String::from_utf8_lossy(t.value))
            )
        })
}

fn integer(t: Tag) -> Result<i64, String> {
    let v = number(t)?;
    if v.fract() != 0.0 || v.abs() > 1e15 {
        return Err(format!(
            "line {}: group code {} holds {v}, not a whole number",
            t.line, t.code
        ));
    }
    Ok(v as i64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A DXF of an ENTITIES section holding `body` (group lines, one per line).
    fn dxf(body: &str) -> String {
        format!("0\nSECTION\n2\nENTITIES\n{body}0\nENDSEC\n0\nEOF\n")
    }

    /// The loops of the model-space hatches of `d`.
    fn loops(d: &str, tol: f64) -> Vec<Vec<DVec3>> {
        let h = read_hatches(d.as_bytes()).unwrap();
        h.model
            .iter()
            .flat_map(|(_, h)| h.loops(tol, usize::MAX).unwrap().unwrap())
            .collect()
    }

    fn length(l: &[DVec3]) -> f64 {
        l.windows(2).map(|w| w[0].distance(w[1])).sum()
    }

    #[test]
    fn a_polyline_path_with_bulges_is_a_closed_circle() {
        // Two vertices with bulge 1: a circle of radius 5 about (5, 0); seed points after.
        let d = dxf("0\nHATCH\n8\n0\n30\n0\n91\n1\n92\n2\n72\n1\n73\n1\n93\n2\n10\n0\n20\n0\n42\n1\n10\n10\n20\n0\n42\n1\n97\n0\n75\n1\n98\n1\n10\n5\n20\n0\n");
        let l = loops(&d, 0.01);
        let [l] = &l[..] else { panic!("{l:?}") };
        assert_eq!(l.first(), l.last());
        assert!((length(l) - 10.0 * std::f64::consts::PI).abs() < 0.05);
        assert!(l
            .iter()
            .all(|p| (p.distance(DVec3::new(5.0, 0.0, 0.0)) - 5.0).abs() < 1e-9));
    }

    #[test]
    fn an_edge_path_chains_lines_and_a_clockwise_arc_into_one_loop() {
        // A slot: two lines and two half circles, the right one stored clockwise, the second
        // line drawn backwards.
        let d = dxf("0\nHATCH\n91\n1\n92\n1\n93\n4\n\
             72\n1\n10\n0\n20\n0\n11\n10\n21\n0\n\
             72\n2\n10\n10\n20\n2\n40\n2\n50\n270\n51\n90\n73\n0\n\
             72\n1\n10\n0\n20\n4\n11\n10\n21\n4\n\
             72\n2\n10\n0\n20\n2\n40\n2\n50\n90\n51\n270\n73\n1\n\
             97\n0\n");
        let l = loops(&d, 0.001);
        let l = &l[0];
        assert_eq!(l.first(), l.last());
        let slot = 20.0 + 4.0 * std::f64::consts::PI;
        assert!(
            (length(l) - slot).abs() < 0.01,
            "{} against {slot}",
            length(l)
        );
        for p in l {
            let on_line =
                (p.y.abs() < 1e-9 || (p.y - 4.0).abs() < 1e-9) && (0.0..=10.0).contains(&p.x);
            let on_arc = [0.0, 10.0]
                .iter()
                .any(|&x| (p.distance(DVec3::new(x, 2.0, 0.0)) - 2.0).abs() < 1e-9);
            assert!(on_line || on_arc, "{p}");
        }
        // The clockwise arc from 90° down to -90° lies right of x = 10 (stored as 360° less
        // each angle: 270, 90).
        assert!(l.iter().any(|p| p.x > 11.9));
    }

    #[test]
    fn hatches_in_blocks_and_paper_space_are_told_apart() {
        let d = "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n8\n0\n2\nHb\n70\n0\n\
                 0\nHATCH\n91\n1\n92\n2\n93\n3\n10\n0\n20\n0\n10\n1\n20\n0\n10\n1\n20\n1\n\
                 0\nENDBLK\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n\
                 0\nHATCH\n67\n1\n91\n1\n92\n2\n93\n3\n10\n0\n20\n0\n10\n1\n20\n0\n10\n1\n20\n1\n\
                 0\nENDSEC\n0\nEOF\n";
        let h = read_hatches(d.as_bytes()).unwrap();
        assert_eq!((h.model.len(), h.paper), (0, 1));
        let block = &h.blocks["HB"];
        assert_eq!(block.len(), 1);
        assert_eq!(block[0].0, 13);
        assert_eq!(block[0].1.loops(0.1, 100).unwrap().unwrap()[0].len(), 4);
        assert_eq!(block[0].1.loops(0.1, 3).unwrap(), None);
    }

    #[test]
    fn bad_counts_and_values_name_the_line() {
        let huge = dxf("0\nHATCH\n91\n1\n92\n2\n93\n1000000000\n10\n0\n20\n0\n");
        let e = read_hatches(huge.as_bytes()).unwrap_err();
        assert_eq!(e.line, 5);
        assert!(
            e.msg
                .contains("line 11: 1000000000 vertices (group code 93), but 2 groups follow"),
            "{}",
            e.msg
        );
        let nan = dxf("0\nHATCH\n91\n1\n92\n2\n93\n1\n10\nnan\n20\n0\n");
        let e = read_hatches(nan.as_bytes()).unwrap_err();
        assert!(
            e.msg
                .contains("line 13: group code 10 holds \"nan\", not a finite number"),
            "{}",
            e.msg
        );
        let none = dxf("0\nHATCH\n8\n0\n");
        assert!(read_hatches(none.as_bytes()).is_err());
        let ellipse = dxf("0\nHATCH\n91\n1\n92\n1\n93\n1\n72\n3\n10\n0\n20\n0\n11\n0\n21\n0\n40\n0.5\n50\n0\n51\n360\n73\n1\n");
        let e = read_hatches(ellipse.as_bytes()).unwrap_err();
        assert!(e.msg.contains("edge 1: an ellipse with"), "{}", e.msg);
    }
}
