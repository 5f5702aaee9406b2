//! OBJ faces as panels, kept as polygons: `v x y z [...]`, `f a b c ...` with 1-based or
//! negative (relative) vertex references, `a/t/n` forms allowed, and the `o`/`g` name in force
//! as the face's group (the later of the two, as tobj and Blender read them). Texture
//! coordinates, normals, materials and smoothing groups are skipped silently (they say nothing
//! about a panel's shape); lines, points and curves are counted in a note. Large files are
//! parsed in pieces on every core; the result does not depend on their number.

use std::collections::BTreeMap;
use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use super::{Panel, Panels};
use crate::files::{read_nonempty, utf8_text, ReadError};

/// Files at least this large are parsed in pieces.
const PIECE_MIN_BYTES: usize = 1 << 20;

/// One face as a piece records it before vertex numbers are known across pieces.
struct Face {
    /// Its references in `Piece::refs`.
    refs: std::ops::Range<usize>,
    /// Vertices the piece had read before the face (for relative references).
    vertices_before: usize,
    /// Its group: an index into `Piece::groups`, or None for the group in force at the start
    /// of the piece.
    group: Option<usize>,
    /// Its line within the piece, from 0.
    line: usize,
}

#[derive(Default)]
struct Piece {
    vertices: Vec<DVec3>,
    refs: Vec<i64>,
    faces: Vec<Face>,
    groups: Vec<Option<String>>,
    lines: usize,
    skipped: BTreeMap<&'static str, usize>,
}

/// A parse error at a line of a piece.
struct Bad {
    line: usize,
    msg: String,
}

pub(super) fn read(path: &Path) -> Result<Panels, ReadError> {
    let text = utf8_text(path, read_nonempty(path)?)?;
    // Lines continued with `\` are joined first (rare in panel files: then one piece).
    let joined;
    let (text, continued) = if text.contains("\\\n") || text.contains("\\\r\n") {
        joined = text.replace("\\\r\n", " ").replace("\\\n", " ");
        (joined.as_str(), true)
    } else {
        (text.as_str(), false)
    };
    let threads = rayon::current_num_threads().max(1);
    let count = if continued {
        1
    } else {
        (text.len() / PIECE_MIN_BYTES).clamp(1, 4 * threads)
    };
    let parsed: Vec<Result<Piece, Bad>> = pieces(text, count)
        .into_par_iter()
        .map(parse_piece)
        .collect();
    let mut first_line = 1;
    let mut out = Vec::with_capacity(parsed.len());
    for p in parsed {
        match p {
            Ok(p) => {
                let lines = p.lines;
                out.push((p, first_line));
                first_line += lines;
            }
            Err(bad) => {
                // Line numbers of joined continuations count physical lines no more.
                return Err(ReadError::line(path, first_line + bad.line, bad.msg));
            }
        }
    }
    assemble(path, out)
}

/// The text cut after a line end into about `count` pieces.
fn pieces(text: &str, count: usize) -> Vec<&str> {
    let mut out = Vec::with_capacity(count);
    let mut start = 0;
    for k in 1..count {
        let target = (text.len() * k / count).max(start);
        let Some(nl) = text.as_bytes()[target..].iter().position(|&b| b == b'\n') else {
            break;
        };
        out.push(&text[start..target + nl + 1]);
        start = target + nl + 1;
    }
    out.push(&text[start..]);
    out
}

fn parse_piece(text: &str) -> Result<Piece, Bad> {
    let mut p = Piece::default();
    let mut group: Option<usize> = None;
    for (line, raw) in text.lines().enumerate() {
        p.lines = line + 1;
        let bad = |msg: String| Bad { line, msg };
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut c = [0.0; 3];
                for (k, slot) in c.iter_mut().enumerate() {
                    let w = words
                        .next()
                        .ok_or_else(|| bad(format!("vertex has {k} coordinates, not 3")))?;
                    *slot = w
                        .parse()
                        .map_err(|_| bad(format!("vertex coordinate \"{w}\" is not a number")))?;
                }
                p.vertices.push(DVec3::from_array(c));
            }
            Some("f") => {
                let start = p.refs.len();
                for w in words {
                    let r = w.split('/').next().unwrap_or("");
                    let r: i64 = r.parse().ok().filter(|&r| r != 0).ok_or_else(|| {
                        bad(format!("face corner \"{w}\" is not a vertex number"))
                    })?;
                    p.refs.push(r);
                }
                p.faces.push(Face {
                    refs: start..p.refs.len(),
                    vertices_before: p.vertices.len(),
                    group,
                    line,
                });
            }
            Some("o" | "g") => {
                let name = raw.trim_start()[1..].trim();
                p.groups.push((!name.is_empty()).then(|| name.to_string()));
                group = Some(p.groups.len() - 1);
            }
            Some("l") => *p.skipped.entry("l (line)").or_default() += 1,
            Some("p") => *p.skipped.entry("p (point)").or_default() += 1,
            Some("curv" | "curv2" | "surf") => *p.skipped.entry("free-form").or_default() += 1,
            _ => {}
        }
    }
    Ok(p)
}

/// The panels of the pieces in order, each with its first line in the file.
fn assemble(path: &Path, pieces: Vec<(Piece, usize)>) -> Result<Panels, ReadError> {
    let total: usize = pieces.iter().map(|(p, _)| p.vertices.len()).sum();
    let mut vertices = Vec::with_capacity(total);
    let mut bases = Vec::with_capacity(pieces.len());
    // The group in force at the start of each piece: the last one set in any piece before.
    let mut starts = Vec::with_capacity(pieces.len());
    let mut current: Option<String> = None;
    let mut skipped: BTreeMap<&'static str, usize> = BTreeMap::new();
    for (p, _) in &pieces {
        bases.push(vertices.len());
        vertices.extend_from_slice(&p.vertices);
        starts.push(current.clone());
        if let Some(last) = p.groups.last() {
            current = last.clone();
        }
        for (k, n) in &p.skipped {
            *skipped.entry(k).or_default() += n;
        }
    }
    let built: Vec<Result<Vec<Panel>, ReadError>> = pieces
        .par_iter()
        .zip(bases.par_iter().zip(starts.par_iter()))
        .map(|((p, first_line), (&base, start))| {
            p.faces
                .iter()
                .map(|f| {
                    let corners = p.refs[f.refs.clone()]
                        .iter()
                        .map(|&r| {
                            let index = if r > 0 {
                                r - 1
                            } else {
                                (base + f.vertices_before) as i64 + r
                            };
                            usize::try_from(index)
                                .ok()
                                .and_then(|i| vertices.get(i).copied())
                                .ok_or_else(|| {
                                    ReadError::line(
                                        path,
                                        first_line + f.line,
                                        format!(
                                            "face refers to vertex {r}, but {} are read by then",
                                            base + f.vertices_before
                                        ),
                                    )
                                })
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    let group = match f.group {
                        Some(g) => p.groups[g].clone(),
                        None => start.clone(),
                    };
                    Ok(Panel {
                        group,
                        ..Panel::new(corners)
                    })
                })
                .collect()
        })
        .collect();
    let mut panels = Vec::with_capacity(pieces.iter().map(|(p, _)| p.faces.len()).sum());
    for b in built {
        panels.extend(b?);
    }
    let notes = if skipped.is_empty() {
        Vec::new()
    } else {
        let list: Vec<String> = skipped.iter().map(|(k, n)| format!("{n} {k}")).collect();
        vec![format!(
            "read but not audited (not faces): {}",
            list.join(", ")
        )]
    };
    Ok(Panels { panels, notes })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_text(text: &str) -> Result<Panels, ReadError> {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("panels.obj");
        std::fs::write(&path, text).expect("write");
        read(&path)
    }

    #[test]
    fn pieces_give_the_same_panels_as_one() {
        // Groups set in one piece carry into the next; relative references count every
        // vertex read before, whichever piece it is in.
        let mut text = String::from("g first\n");
        for k in 0..3000 {
            if k == 1500 {
                text += "o second\n";
            }
            let x = k as f64;
            text += &format!(
                "v {x} 0 0\nv {x} 1 0\nv {x} 1 1\nv {x} 0 1.5\nf -4 -3/1 -2/1/1 {}\n",
                4 * k + 4
            );
        }
        let whole = parse_piece(&text).ok().expect("parses");
        let one = assemble(Path::new("t.obj"), vec![(whole, 1)]).expect("one piece");
        for count in [2, 7, 64] {
            let parts: Vec<(Piece, usize)> = pieces(&text, count)
                .into_iter()
                .map(|t| (parse_piece(t).ok().expect("parses"), 1))
                .collect();
            let many = assemble(Path::new("t.obj"), parts).expect("pieces");
            assert_eq!(many.panels, one.panels, "{count} pieces");
        }
        assert_eq!(one.panels.len(), 3000);
        assert_eq!(one.panels[1499].group.as_deref(), Some("first"));
        assert_eq!(one.panels[1500].group.as_deref(), Some("second"));
        assert_eq!(one.panels[7].corners[3], DVec3::new(7.0, 0.0, 1.5));
    }

    #[test]
    fn bad_records_name_their_line() {
        for (text, needle) in [
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 x\n",
                "line 3: vertex coordinate \"x\"",
            ),
            ("v 0 0\n", "line 1: vertex has 2 coordinates"),
            (
                "v 0 0 0\nf 1 2 3\n",
                "line 2: face refers to vertex 2, but 1 are read",
            ),
            ("v 0 0 0\nf 1 -2 1\n", "line 2: face refers to vertex -2"),
            ("v 0 0 0\nf 1 0 1\n", "line 2: face corner \"0\""),
            ("v 0 0 0\nf 1 a 1\n", "line 2: face corner \"a\""),
        ] {
            let err = read_text(text).expect_err(text).to_string();
            assert!(err.contains(needle), "{text:?}: {err}");
        }
        let read = read_text("v 0 0 0\nv 1 0 0\nl 1 2\np 1\n").expect("reads");
        assert!(read.panels.is_empty());
        assert_eq!(
            read.notes,
            ["read but not audited (not faces): 1 l (line), 1 p (point)"]
        );
    }
}
