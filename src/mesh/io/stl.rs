//! STL through stl_io. Binary is recognised by its size (84 + 50 × triangle count bytes), since
//! some binary files also start with "solid"; ASCII otherwise. Written as binary.

use std::io::Cursor;
use std::path::Path;

use glam::DVec3;
use stl_io::{Normal, Triangle, Vertex};

use crate::files::{read_nonempty, write_atomic, ReadError, WriteError};
use crate::mesh::TriMesh;

pub fn read(path: &Path) -> Result<TriMesh, ReadError> {
    let bytes = read_nonempty(path)?;
    let len = bytes.len() as u64;
    let is_binary = len >= 84 && {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
        84 + 50 * n == len
    };
    if !is_binary && !bytes.starts_with(b"solid") {
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
    let indexed = stl_io::read_stl(&mut Cursor::new(&bytes)).map_err(|e| {
        if is_binary {
            ReadError::file(path, format!("cannot read binary STL: {e}"))
        } else {
            // stl_io does not say where; find the first line that is not ASCII STL.
            match first_bad_ascii_line(&bytes) {
                Some((line, msg)) => ReadError::line(path, line, msg),
                None => ReadError::file(path, format!("cannot read ASCII STL: {e}")),
            }
        }
    })?;
    let positions = indexed
        .vertices
        .iter()
        .map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
        .collect();
    let mut triangles = Vec::with_capacity(indexed.faces.len());
    for (k, f) in indexed.faces.iter().enumerate() {
        let mut t = [0u32; 3];
        for (slot, &i) in t.iter_mut().zip(&f.vertices) {
            *slot = u32::try_from(i).map_err(|_| {
                ReadError::record(path, format!("triangle {k}"), "too many vertices")
            })?;
        }
        triangles.push(t);
    }
    Ok(TriMesh {
        positions,
        triangles,
        colors: None,
    })
}

/// The first line of an ASCII STL that breaks its grammar, with what is wrong.
fn first_bad_ascii_line(bytes: &[u8]) -> Option<(usize, String)> {
    let text = String::from_utf8_lossy(bytes);
    let numbers = |words: &[&str], n: usize| {
        words.len() == n
            && words
                .iter()
                .all(|w| w.parse::<f32>().is_ok_and(|v| v.is_finite()))
    };
    for (i, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let ok = match words.as_slice() {
            [] => true,
            ["solid", ..] | ["endsolid", ..] | ["endloop"] | ["endfacet"] => true,
            ["outer", "loop"] => true,
            ["facet", "normal", rest @ ..] => numbers(rest, 3),
            ["vertex", rest @ ..] => numbers(rest, 3),
            _ => false,
        };
        if !ok {
            let shown: String = line.trim().chars().take(40).collect();
            return Some((i + 1, format!("not ASCII STL: `{shown}`")));
        }
    }
    None
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
