//! Network OBJ: `v` vertices and `l` polylines, as Rhino and Blender export curves. Our own small
//! reader and writer, since tobj reads `l` records as faces.
//!
//! Read: `v x y z [w | r g b]`, `l i j k ...` (1-based, negative = relative, `i/t` allowed),
//! `p` points, `\` line continuations. Groups, objects, materials, normals and texture
//! coordinates are skipped. A face record is an error: that file is a mesh, not a network.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use glam::DVec3;

use super::{Imported, ReadOptions};
use crate::files::{read_nonempty, utf8_text, write_atomic, ReadError, WriteError};
use crate::network::{weld, Network};

pub fn read(path: &Path, opts: &ReadOptions) -> Result<Imported, ReadError> {
    let text = utf8_text(path, read_nonempty(path)?)?;
    let mut points: Vec<DVec3> = Vec::new();
    let mut segments: Vec<(u32, u32)> = Vec::new();
    let mut skipped: BTreeMap<String, usize> = BTreeMap::new();
    for (line_no, line) in logical_lines(&text) {
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => points.push(parse_vertex(path, line_no, words)?),
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
                return Err(ReadError::line(
                    path,
                    line_no,
                    "face record: this OBJ is a mesh, not a network of `v` + `l` polylines \
                     (use it as a surface)",
                ))
            }
            "vn" | "vt" | "vp" | "o" | "g" | "s" | "mtllib" | "usemtl" => {
                *skipped.entry(keyword.to_string()).or_default() += 1;
            }
            k if k.starts_with('#') => {}
            other => {
                return Err(ReadError::line(
                    path,
                    line_no,
                    format!(
                        "unsupported OBJ record `{}`",
                        other.chars().take(20).collect::<String>()
                    ),
                ))
            }
        }
    }
    if points.is_empty() {
        return Err(ReadError::file(
            path,
            "no vertices (`v` records): nothing to read",
        ));
    }
    let (network, stats) = weld::assemble(&points, &segments, opts.weld);
    Ok(Imported {
        network,
        weld: Some(stats),
        skipped,
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

fn parse_vertex<'a>(
    path: &Path,
    line: usize,
    words: impl Iterator<Item = &'a str>,
) -> Result<DVec3, ReadError> {
    let mut xyz = [0.0f64; 3];
    let mut count = 0;
    for (i, w) in words.enumerate() {
        let v: f64 = w
            .parse()
            .map_err(|_| ReadError::line(path, line, format!("vertex: `{w}` is not a number")))?;
        if i < 3 {
            if !v.is_finite() {
                return Err(ReadError::line(
                    path,
                    line,
                    format!("vertex: coordinate `{w}` is not finite"),
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
    Ok(DVec3::from_array(xyz))
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
