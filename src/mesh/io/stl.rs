//! STL through stl_io. Binary is recognised by its size (84 + 50 × triangle count bytes, a
//! stray byte or a few after the triangles tolerated), since some binary files also start with
//! "solid"; ASCII otherwise. Written as binary.

use std::path::Path;

use glam::DVec3;
use stl_io::{Normal, Triangle, Vertex};

use crate::files::{read_nonempty, write_atomic, ReadError, WriteError};
use crate::geom::merge::merge_points;
use crate::geom::mix64 as mix;
use crate::mesh::TriMesh;

pub fn read(path: &Path) -> Result<TriMesh, ReadError> {
    read_as(path, true)
}

/// A binary STL as a triangle soup (three vertices per triangle); ASCII is welded as by `read`.
pub fn read_soup(path: &Path) -> Result<TriMesh, ReadError> {
    read_as(path, false)
}

fn read_as(path: &Path, weld: bool) -> Result<TriMesh, ReadError> {
    let bytes = read_nonempty(path)?;
    let len = bytes.len() as u64;
    if binary_layout(&bytes[..bytes.len().min(HEAD)], len).is_some() {
        return Ok(if weld {
            read_binary(&bytes)
        } else {
            soup(&bytes)
        });
    }
    if !ascii_start(&bytes) {
        let detail = if len >= 84 {
            let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
            format!(
                "as binary STL its header counts {n} triangles, which needs {} bytes, \
                 but the file has {len} (truncated or not an STL)",
                84 + 50 * n
            )
        } else {
            format!("{len} bytes is shorter than a binary STL header (84 bytes)")
        };
        return Err(ReadError::file(
            path,
            format!("not an STL file: no ASCII \"solid\" start, and {detail}"),
        ));
    }
    read_ascii(path, &bytes)
}

/// Whether `bytes` open as an ASCII STL: `solid` in any case (older CAD exporters write
/// `SOLID … FACET NORMAL …`), after a UTF-8 byte-order mark and blank space, if any.
fn ascii_start(bytes: &[u8]) -> bool {
    let b = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let b = &b[b.iter().take_while(|c| c.is_ascii_whitespace()).count()..];
    b.len() >= 5 && b[..5].eq_ignore_ascii_case(b"solid")
}

/// The ASCII STL keywords, as `read_ascii` matches them (in any case).
const KEYWORDS: [&str; 9] = [
    "solid", "endsolid", "facet", "normal", "outer", "loop", "vertex", "endloop", "endfacet",
];

/// `word` as the keyword it spells in any case, or "" when it is none.
fn keyword(word: &str) -> &'static str {
    KEYWORDS
        .into_iter()
        .find(|k| word.eq_ignore_ascii_case(k))
        .unwrap_or("")
}

/// Bytes of a file's start that decide its layout: the 84-byte header and 1 KiB after it.
const HEAD: usize = 84 + 1024;

/// Whether a file of `len` bytes starting with `head` (its first [`HEAD`] bytes, or all of
/// it) is a binary STL, by size arithmetic before any "solid" prefix (numpy-stl and others
/// write "solid" into a binary header): the triangle count and the bytes after the
/// triangles. 84 + 50 n bytes exactly is binary; up to 49 bytes more (less than a record) are
/// tolerated unless the file reads as ASCII STL (starts with "solid" and has no NUL byte,
/// where a binary file's attribute words are almost always 0).
fn binary_layout(head: &[u8], len: u64) -> Option<(u64, u64)> {
    let count = head.get(80..84)?;
    let n = u32::from_le_bytes([count[0], count[1], count[2], count[3]]) as u64;
    let trailing = len.checked_sub(84 + 50 * n)?;
    if trailing == 0 {
        return Some((n, 0));
    }
    let text = ascii_start(head) && !head[84..].contains(&0);
    (n > 0 && trailing < 50 && !text).then_some((n, trailing))
}

/// Bytes after a binary STL's triangles, left unread (a writer's padding or stray byte); `None`
/// when there are none, or the file is not a binary STL or cannot be read.
pub fn trailing_bytes(path: &Path) -> Option<(u64, u64)> {
    use std::io::Read;
    let file = std::fs::File::open(path).ok()?;
    let len = file.metadata().ok()?.len();
    let mut head = Vec::with_capacity(HEAD);
    file.take(HEAD as u64).read_to_end(&mut head).ok()?;
    binary_layout(&head, len).filter(|&(_, t)| t > 0)
}

/// An ASCII STL: every `solid … endsolid` block (CAD programs write one per body), corners at
/// the same point (with −0 read as +0) joined. Facets with more than three vertices are fanned.
/// Keywords are read in any case.
fn read_ascii(path: &Path, bytes: &[u8]) -> Result<TriMesh, ReadError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| ReadError::file(path, format!("ASCII STL is not valid UTF-8: {e}")))?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut corners: Vec<DVec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut facet: Vec<u32> = Vec::new();
    let mut in_facet = false;
    for (i, line) in text.lines().enumerate() {
        let bad = |msg: String| ReadError::line(path, i + 1, msg);
        let words: Vec<&str> = line.split_whitespace().collect();
        let key = |k: usize| words.get(k).map_or("", |w| keyword(w));
        match (key(0), key(1), words.len()) {
            (_, _, 0) | ("solid", ..) | ("endsolid", ..) | ("outer", "loop", 2) => {}
            ("facet", "normal", _) => {
                in_facet = true;
                facet.clear();
            }
            ("vertex", _, 4) if in_facet => {
                let mut p = [0.0; 3];
                for (slot, w) in p.iter_mut().zip(&words[1..]) {
                    *slot = w
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            bad(format!(
                                "vertex: `{}` is not a finite number",
                                w.escape_debug()
                            ))
                        })?;
                }
                facet.push(corners.len() as u32);
                corners.push(DVec3::from_array(p));
            }
            ("endloop", _, 1) => {}
            ("endfacet", _, 1) => {
                if facet.len() < 3 {
                    return Err(bad(format!("a facet with {} vertices", facet.len())));
                }
                for k in 1..facet.len() - 1 {
                    triangles.push([facet[0], facet[k], facet[k + 1]]);
                }
                in_facet = false;
            }
            _ => {
                let shown: String = line.trim().chars().take(40).collect();
                return Err(bad(format!("not ASCII STL: `{}`", shown.escape_debug())));
            }
        }
        if corners.len() > u32::MAX as usize / 2 {
            return Err(bad("too many vertices".into()));
        }
    }
    let (map, positions) = merge_points(&corners, 0.0);
    Ok(TriMesh {
        positions,
        triangles: triangles
            .iter()
            .map(|t| t.map(|c| map[c as usize]))
            .collect(),
        colors: None,
    })
}

/// Bodies in an ASCII STL (its `solid` blocks); `None` for binary STL, which has no bodies.
pub fn ascii_solids(bytes: &[u8]) -> Option<usize> {
    if !ascii_start(bytes) {
        return None;
    }
    if binary_layout(&bytes[..bytes.len().min(HEAD)], bytes.len() as u64).is_some() {
        return None;
    }
    let text = String::from_utf8_lossy(bytes);
    Some(
        text.lines()
            .filter(|l| {
                let l = l.trim_start_matches('\u{feff}');
                l.split_whitespace().next().map(keyword) == Some("solid")
            })
            .count(),
    )
}

/// A binary STL whose size has been checked: corners at the same point (bit for bit, with −0
/// read as +0) become one vertex, numbered in order of first appearance. Corners are welded in
/// parallel: split into shards by a hash of the point, each shard welded with its own map.
fn read_binary(bytes: &[u8]) -> TriMesh {
    use rayon::prelude::*;
    use std::collections::HashMap;
    use std::hash::BuildHasherDefault;

    const SHARDS: usize = 256;
    let n = (bytes.len() - 84) / 50;
    let f =
        |at: usize| f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let at = |c: usize| 84 + (c / 3) * 50 + 12 + (c % 3) * 12;
    let key = |c: usize| {
        let a = at(c);
        [f(a), f(a + 4), f(a + 8)].map(|v| (v + 0.0).to_bits())
    };
    let shard = |k: &[u32; 3]| {
        let h = mix(((k[0] as u64) << 32 | k[1] as u64) ^ mix(k[2] as u64));
        (h >> 56) as usize % SHARDS
    };
    let of: Vec<u8> = (0..3 * n)
        .into_par_iter()
        .map(|c| shard(&key(c)) as u8)
        .collect();
    // Corners grouped by shard, in increasing order within each (a counting sort).
    let mut start = vec![0usize; SHARDS + 1];
    for &s in &of {
        start[s as usize + 1] += 1;
    }
    for s in 0..SHARDS {
        start[s + 1] += start[s];
    }
    let mut fill = start.clone();
    let mut order = vec![([0u32; 3], 0u32); 3 * n];
    for (c, &s) in of.iter().enumerate() {
        order[fill[s as usize]] = (key(c), c as u32);
        fill[s as usize] += 1;
    }
    drop(of);
    type Map = HashMap<[u32; 3], u32, BuildHasherDefault<MixHasher>>;
    let firsts: Vec<Vec<u32>> = (0..SHARDS)
        .into_par_iter()
        .map(|s| {
            let mine = &order[start[s]..start[s + 1]];
            let mut seen = Map::with_capacity_and_hasher(mine.len() / 2, Default::default());
            mine.iter()
                .map(|&(k, c)| *seen.entry(k).or_insert(c))
                .collect()
        })
        .collect();
    let mut first = vec![0u32; 3 * n];
    for s in 0..SHARDS {
        for (&(_, c), &f0) in order[start[s]..start[s + 1]].iter().zip(&firsts[s]) {
            first[c as usize] = f0;
        }
    }
    drop(firsts);
    drop(order);
    let mut id = vec![0u32; 3 * n];
    let mut positions = Vec::new();
    for c in 0..3 * n {
        let f0 = first[c] as usize;
        if f0 == c {
            id[c] = positions.len() as u32;
            let a = at(c);
            positions.push(DVec3::new(f(a) as f64, f(a + 4) as f64, f(a + 8) as f64));
        } else {
            id[c] = id[f0];
        }
    }
    let triangles = (0..n)
        .map(|t| [id[3 * t], id[3 * t + 1], id[3 * t + 2]])
        .collect();
    TriMesh {
        positions,
        triangles,
        colors: None,
    }
}

/// Three vertices per triangle, in file order, as stored.
fn soup(bytes: &[u8]) -> TriMesh {
    use rayon::prelude::*;
    let n = (bytes.len() - 84) / 50;
    let f =
        |at: usize| f32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let positions = (0..3 * n)
        .into_par_iter()
        .map(|c| {
            let at = 84 + (c / 3) * 50 + 12 + (c % 3) * 12;
            DVec3::new(f(at) as f64, f(at + 4) as f64, f(at + 8) as f64)
        })
        .collect();
    let triangles = (0..n as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    TriMesh {
        positions,
        triangles,
        colors: None,
    }
}

/// A fast hasher for welding keys (points as bits): no need to resist crafted collisions here.
#[derive(Default)]
struct MixHasher(u64);

impl std::hash::Hasher for MixHasher {
    fn finish(&self) -> u64 {
        mix(self.0)
    }
    fn write(&mut self, bytes: &[u8]) {
        // FxHash's step per word; `finish` mixes the whole.
        for chunk in bytes.chunks(4) {
            let mut word = [0u8; 4];
            word[..chunk.len()].copy_from_slice(chunk);
            self.0 = (self.0.rotate_left(5) ^ u32::from_le_bytes(word) as u64)
                .wrapping_mul(0x517c_c1b7_2722_0a95);
        }
    }
}

pub fn write(mesh: &TriMesh, path: &Path) -> Result<(), WriteError> {
    let vertex = |p: DVec3| Vertex::new([p.x as f32, p.y as f32, p.z as f32]);
    let triangles: Vec<Triangle> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            let n = (b - a).cross(c - a).normalize_or_zero();
            Triangle {
                normal: Normal::new([n.x as f32, n.y as f32, n.z as f32]),
                vertices: [vertex(a), vertex(b), vertex(c)],
            }
        })
        .collect();
    write_atomic(path, |w| stl_io::write_stl(w, triangles.iter()))
}
