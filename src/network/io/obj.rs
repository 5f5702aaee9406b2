//! Network OBJ: `v` vertices and `l` polylines, as Rhino and Blender export curves. Our own small
//! reader and writer, since tobj reads `l` records as faces.
//!
//! Read: `v x y z [w | r g b]`, `l i j k ...` (1-based, negative = relative, `i/t` allowed),
//! `p` points, `\` line continuations, and free-form curves as Rhino exports them (`cstype
//! [rat] bspline`, `deg`, `curv u0 u1 i j ...`, `parm u ...`, `end`), flattened within the chord
//! tolerance (degree 1: the control polygon). Groups, objects, materials (an empty `usemtl`
//! too), normals, texture coordinates and surfaces are skipped and counted. Faces beside
//! polylines (a mesh with loose edges) are skipped and counted; faces alone are an error: that
//! file is a mesh, not a network.

use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::Path;

use glam::DVec3;

use crate::geom::curves::Nurbs;

use super::units::{scale_to_mm, LengthUnit, SourceUnits};
use super::{Imported, ReadOptions};
use crate::files::{read_nonempty, utf8_text, write_atomic, ReadError, WriteError};
use crate::network::{weld, Network};

pub fn read(path: &Path, opts: &ReadOptions) -> Result<Imported, ReadError> {
    let text = utf8_text(path, read_nonempty(path)?)?;
    let mut points: Vec<DVec3> = Vec::new();
    let mut segments: Vec<(u32, u32)> = Vec::new();
    let mut skipped: BTreeMap<String, usize> = BTreeMap::new();
    let mut weights: Vec<f64> = Vec::new();
    let mut free = FreeForm::default();
    // Vertices that curves use as control points, and faces' corners: not nodes unless a
    // polyline uses them too.
    let mut control: BTreeSet<u32> = BTreeSet::new();
    // Flattened curves, added after every `v` is read so that vertex numbers stay the file's.
    let mut curve_points: Vec<Vec<DVec3>> = Vec::new();
    // Faces beside polylines (Blender's loose edges in a mesh): the polylines are the network
    // and the faces are skipped; faces alone make the file a mesh (an error at the first).
    let mut first_face: Option<usize> = None;
    let tol = opts.chord_tolerance / opts.units.map_or(1.0, |u| u.mm());
    for (line_no, line) in logical_lines(&text) {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let (p, w) = parse_vertex(path, line_no, words)?;
                points.push(p);
                weights.push(w);
            }
            "cstype" | "deg" | "curv" | "parm" | "end" => {
                let at = |msg: String| ReadError::line(path, line_no, msg);
                let vertices = points.len();
                let words: Vec<&str> = words.collect();
                let refs = |ws: &[&str]| {
                    ws.iter()
                        .map(|w| vertex_ref(path, line_no, w, vertices))
                        .collect::<Result<Vec<u32>, _>>()
                };
                match keyword {
                    "cstype" => free.cstype(&words).map_err(at)?,
                    "deg" => free.degree(&words).map_err(at)?,
                    "curv" => {
                        let (range, ids) = match words.as_slice() {
                            [u0, u1, ids @ ..] if ids.len() >= 2 => ((*u0, *u1), refs(ids)?),
                            _ => {
                                return Err(
                                    at("`curv` needs u0 u1 and two or more vertices".into()),
                                )
                            }
                        };
                        for &i in &ids {
                            control.insert(i);
                        }
                        free.curve(range, ids, line_no).map_err(at)?;
                    }
                    "parm" => free.parm(&words).map_err(at)?,
                    _ => {
                        if let Some(curve) = free.end().map_err(at)? {
                            let flat = curve
                                .flatten(&points, &weights, tol)
                                .map_err(|m| ReadError::line(path, curve.line, m))?;
                            curve_points.push(flat);
                        }
                    }
                }
            }
            "curv2" | "surf" | "trim" | "hole" | "scrv" | "sp" | "con" | "bmat" | "step"
            | "ctech" | "stech" | "vp" => {
                *skipped.entry(keyword.to_string()).or_default() += 1;
            }
            "l" | "p" => {
                let ids = words
                    .map(|w| vertex_ref(path, line_no, w, points.len()))
                    .collect::<Result<Vec<u32>, _>>()?;
                if keyword == "l" {
                    if ids.len() < 2 {
                        return Err(ReadError::line(
                            path,
                            line_no,
                            "polyline record `l` needs at least two vertices",
                        ));
                    }
                    segments.extend(ids.windows(2).map(|w| (w[0], w[1])));
                } else if ids.is_empty() {
                    return Err(ReadError::line(path, line_no, "point record `p` is empty"));
                }
            }
            "f" | "fo" => {
                first_face.get_or_insert(line_no);
                *skipped.entry("f (faces)".to_string()).or_default() += 1;
                // Their corners are no nodes unless a polyline uses them.
                for w in words {
                    control.extend(vertex_ref(path, line_no, w, points.len()).ok());
                }
            }
            "vn" | "vt" | "o" | "g" | "s" | "mtllib" | "usemtl" => {
                *skipped.entry(keyword.to_string()).or_default() += 1;
            }
            k if k.starts_with('#') => {}
            other => {
                return Err(ReadError::line(
                    path,
                    line_no,
                    format!(
                        "unsupported OBJ record `{}`",
                        other.chars().take(20).collect::<String>().escape_debug()
                    ),
                ))
            }
        }
    }
    if let (Some(line), true) = (first_face, segments.is_empty() && curve_points.is_empty()) {
        return Err(ReadError::line(
            path,
            line,
            "face record: this OBJ is a mesh, not a network of `v` + `l` polylines \
             (use it as a surface)",
        ));
    }
    if let Some(line) = free.open_curve() {
        return Err(ReadError::line(
            path,
            line,
            "`curv` without its closing `end`",
        ));
    }
    for flat in curve_points {
        let first = points.len() as u32;
        segments.extend((1..flat.len() as u32).map(|k| (first + k - 1, first + k)));
        points.extend(flat);
    }
    if !control.is_empty() {
        drop_control_points(&mut points, &mut segments, &control);
    }
    if points.is_empty() {
        return Err(ReadError::file(
            path,
            "no vertices (`v` records): nothing to read",
        ));
    }
    let units = match opts.units {
        Some(u) => SourceUnits::new(u, "--units", false),
        None => SourceUnits::new(
            LengthUnit::Mm,
            "assumed: OBJ has no units; --units to say otherwise",
            true,
        ),
    };
    if let Err(bad) = scale_to_mm(&mut points, &units) {
        return Err(ReadError::file(
            path,
            format!(
                "vertex {} is out of range once taken from {} to mm",
                bad + 1,
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
        inserts: 0,
        split: None,
    })
}

/// Lines joined across `\` continuations, each with the number of its first physical line.
fn logical_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let trimmed = raw.trim_end();
        let (body, continues) = match trimmed.strip_suffix('\\') {
            Some(b) => (b, true),
            None => (trimmed, false),
        };
        let entry = pending.get_or_insert_with(|| (i + 1, String::new()));
        entry.1.push(' ');
        entry.1.push_str(body);
        if !continues {
            out.extend(pending.take());
        }
    }
    out.extend(pending);
    out
}

/// Removes the curves' control points that no segment uses, renumbering the rest.
fn drop_control_points(
    points: &mut Vec<DVec3>,
    segments: &mut [(u32, u32)],
    control: &BTreeSet<u32>,
) {
    let mut used = vec![false; points.len()];
    for &(a, b) in segments.iter() {
        used[a as usize] = true;
        used[b as usize] = true;
    }
    let mut new_id = vec![u32::MAX; points.len()];
    let mut kept = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        if used[i] || !control.contains(&(i as u32)) {
            new_id[i] = kept.len() as u32;
            kept.push(*p);
        }
    }
    for s in segments.iter_mut() {
        *s = (new_id[s.0 as usize], new_id[s.1 as usize]);
    }
    *points = kept;
}

/// A vertex and its weight (the fourth value when there are exactly four, else 1).
fn parse_vertex<'a>(
    path: &Path,
    line: usize,
    words: impl Iterator<Item = &'a str>,
) -> Result<(DVec3, f64), ReadError> {
    let mut xyz = [0.0f64; 3];
    let mut count = 0;
    let mut w4 = 1.0;
    for (i, w) in words.enumerate() {
        let v: f64 = w.parse().map_err(|_| {
            ReadError::line(
                path,
                line,
                format!("vertex: `{}` is not a number", w.escape_debug()),
            )
        })?;
        if i == 3 {
            w4 = v;
        }
        if i < 3 {
            if !v.is_finite() {
                return Err(ReadError::line(
                    path,
                    line,
                    format!("vertex: coordinate `{}` is not finite", w.escape_debug()),
                ));
            }
            xyz[i] = v;
        }
        count += 1;
    }
    if count < 3 {
        return Err(ReadError::line(
            path,
            line,
            format!("vertex needs three coordinates, found {count}"),
        ));
    }
    Ok((DVec3::from_array(xyz), if count == 4 { w4 } else { 1.0 }))
}

/// The free-form curve state of an OBJ file: `cstype` and `deg` hold until changed; `curv`
/// opens a curve that `parm u` gives knots and `end` closes.
#[derive(Default)]
struct FreeForm {
    rational: bool,
    bspline: bool,
    degree: Option<usize>,
    open: Option<Curve>,
}

struct Curve {
    rational: bool,
    degree: usize,
    range: (f64, f64),
    ids: Vec<u32>,
    knots: Vec<f64>,
    line: usize,
}

fn number(w: &str) -> Result<f64, String> {
    w.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("`{}` is not a finite number", w.escape_debug()))
}

impl FreeForm {
    fn cstype(&mut self, words: &[&str]) -> Result<(), String> {
        let (rational, kind) = match words {
            ["rat", kind] => (true, *kind),
            [kind] => (false, *kind),
            _ => return Err("`cstype` needs a type (`bspline` or `rat bspline`)".into()),
        };
        if kind != "bspline" {
            return Err(format!(
                "curve type `{}` is not read (only `bspline` and `rat bspline`, as Rhino writes)",
                kind.escape_debug()
            ));
        }
        self.rational = rational;
        self.bspline = true;
        Ok(())
    }

    fn degree(&mut self, words: &[&str]) -> Result<(), String> {
        let d = words
            .first()
            .and_then(|w| w.parse::<usize>().ok())
            .filter(|d| (1..=32).contains(d))
            .ok_or("`deg` needs a degree from 1 to 32")?;
        self.degree = Some(d);
        Ok(())
    }

    fn curve(&mut self, range: (&str, &str), ids: Vec<u32>, line: usize) -> Result<(), String> {
        if self.open.is_some() {
            return Err("`curv` inside another curve (no `end` before it)".into());
        }
        if !self.bspline {
            return Err("`curv` before `cstype bspline`".into());
        }
        let degree = self.degree.ok_or("`curv` before `deg`")?;
        self.open = Some(Curve {
            rational: self.rational,
            degree,
            range: (number(range.0)?, number(range.1)?),
            ids,
            knots: Vec::new(),
            line,
        });
        Ok(())
    }

    fn parm(&mut self, words: &[&str]) -> Result<(), String> {
        let curve = self.open.as_mut().ok_or("`parm` outside a curve")?;
        match words {
            ["u", knots @ ..] => {
                curve.knots = knots.iter().map(|w| number(w)).collect::<Result<_, _>>()?;
                Ok(())
            }
            _ => Err("`parm` needs `u` and the knots".into()),
        }
    }

    fn end(&mut self) -> Result<Option<Curve>, String> {
        Ok(self.open.take())
    }

    fn open_curve(&self) -> Option<usize> {
        self.open.as_ref().map(|c| c.line)
    }
}

impl Curve {
    fn flatten(&self, points: &[DVec3], weights: &[f64], tol: f64) -> Result<Vec<DVec3>, String> {
        let control: Vec<DVec3> = self.ids.iter().map(|&i| points[i as usize]).collect();
        let w: Vec<f64> = self.ids.iter().map(|&i| weights[i as usize]).collect();
        let curve = Nurbs {
            degree: self.degree,
            knots: &self.knots,
            control: &control,
            weights: self.rational.then_some(w.as_slice()),
        };
        let (lo, hi) = self.range;
        let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        let mut flat = curve
            .flatten_range(tol, lo, hi)
            .map_err(|e| format!("curve: {e}"))?;
        if self.range.0 > self.range.1 {
            flat.reverse();
        }
        Ok(flat)
    }
}

/// Resolves an OBJ vertex reference (1-based, or negative from the end; `i/t` forms allowed)
/// against the `count` vertices read so far.
fn vertex_ref(path: &Path, line: usize, word: &str, count: usize) -> Result<u32, ReadError> {
    let head = word.split('/').next().unwrap_or(word);
    let i: i64 = head
        .parse()
        .map_err(|_| ReadError::line(path, line, format!("`{word}` is not a vertex index")))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(ReadError::line(
            path,
            line,
            format!(
                "vertex index {i} is out of range: {count} vertices are defined before this line"
            ),
        ));
    }
    Ok(resolved as u32)
}

pub fn write(net: &Network, path: &Path) -> Result<(), WriteError> {
    let chains = net.chains();
    write_atomic(path, |w| {
        writeln!(
            w,
            "# lamina network: {} nodes, {} edges, units mm",
            net.nodes.len(),
            net.edges.len()
        )?;
        for n in &net.nodes {
            writeln!(w, "v {} {} {}", n.p.x, n.p.y, n.p.z)?;
        }
        for c in &chains {
            w.write_all(b"l")?;
            for &id in &c.nodes {
                write!(w, " {}", id + 1)?;
            }
            w.write_all(b"\n")?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn continuation_lines_join() {
        let lines = logical_lines("v 0 0 0\nl 1 \\\n 2 3\n# end\n");
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[1].0, 2);
        assert_eq!(
            lines[1].1.split_whitespace().collect::<Vec<_>>(),
            ["l", "1", "2", "3"]
        );
    }

    #[test]
    fn relative_and_slashed_refs() -> Result<(), ReadError> {
        let p = Path::new("x.obj");
        assert_eq!(vertex_ref(p, 1, "-1", 4)?, 3);
        assert_eq!(vertex_ref(p, 1, "2/7", 4)?, 1);
        assert!(vertex_ref(p, 1, "5", 4).is_err());
        assert!(vertex_ref(p, 1, "0", 4).is_err());
        Ok(())
    }
}
