//! Mesh OBJ: read through tobj (polygons triangulated, vertex colours `v x y z r g b` kept);
//! written by our own few lines. tobj reports what went wrong but not where, so on an error we
//! find the offending line ourselves. Before tobj sees the text, `\` line continuations (Rhino
//! writes long faces so) are joined and material records blanked (materials are not read, and
//! tobj refuses an empty `usemtl`), keeping every line where it was. Vertices are joined by
//! value, -0 and 0 being one value.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use crate::files::{read_nonempty, utf8_text, write_atomic, ReadError, WriteError};
use crate::mesh::TriMesh;

/// Records a mesh does not use, counted by kind ("l (polylines)", 3).
pub type Skipped = Vec<(&'static str, usize)>;

/// The mesh, and the records a mesh does not use that the file holds (`l` polylines, `p`
/// points).
pub fn read_noted(path: &Path) -> Result<(TriMesh, Skipped), ReadError> {
    let text = prepare(&utf8_text(path, read_nonempty(path)?)?);
    let (mut lines, mut points) = (0, 0);
    for l in text.lines() {
        match l.split_whitespace().next() {
            Some("l") => lines += 1,
            Some("p") => points += 1,
            _ => {}
        }
    }
    let skipped: Skipped = [("l (polylines)", lines), ("p (points)", points)]
        .into_iter()
        .filter(|&(_, n)| n > 0)
        .collect();
    // tobj drops a face of fewer than three corners without a word.
    if let Some(line) = text.lines().position(|l| {
        let mut w = l.split_whitespace();
        w.next() == Some("f") && w.count() < 3
    }) {
        return Err(ReadError::line(
            path,
            line + 1,
            "a face needs at least three vertices",
        ));
    }
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| locate(path, &text, e))?;
    // tobj renumbers vertices per object; join objects again on identical positions.
    let mut mesh = TriMesh::default();
    let mut index: std::collections::HashMap<[u64; 3], u32> = Default::default();
    let with_colors = models.iter().all(|m| !m.mesh.vertex_color.is_empty()) && !models.is_empty();
    let mut colors = Vec::new();
    for m in &models {
        let local: Vec<u32> = m
            .mesh
            .positions
            .chunks_exact(3)
            .enumerate()
            .map(|(i, c)| {
                // Adding +0 turns -0 into 0 and changes nothing else.
                let p = DVec3::new(c[0] + 0.0, c[1] + 0.0, c[2] + 0.0);
                let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                *index.entry(key).or_insert_with(|| {
                    mesh.positions.push(p);
                    if with_colors {
                        let rgb = &m.mesh.vertex_color[3 * i..3 * i + 3];
                        colors.push([rgb[0] as f32, rgb[1] as f32, rgb[2] as f32]);
                    }
                    mesh.positions.len() as u32 - 1
                })
            })
            .collect();
        for t in m.mesh.indices.chunks_exact(3) {
            mesh.triangles.push([
                local[t[0] as usize],
                local[t[1] as usize],
                local[t[2] as usize],
            ]);
        }
    }
    if with_colors {
        mesh.colors = Some(colors);
    }
    Ok((mesh, skipped))
}

/// The text with `\` continuations joined onto their first line (the lines they took left
/// empty) and `mtllib`/`usemtl` records blanked, so line numbers stay those of the file.
fn prepare(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut joined = 0usize;
    for raw in text.lines() {
        let line = raw.trim_end();
        let (body, continues) = match line.strip_suffix('\\') {
            Some(b) => (b, true),
            None => (line, false),
        };
        let keyword = body.split_whitespace().next().unwrap_or("");
        if joined == 0 && matches!(keyword, "mtllib" | "usemtl") && !continues {
            out.push('\n');
            continue;
        }
        if joined > 0 {
            out.push(' ');
        }
        out.push_str(body);
        if continues {
            joined += 1;
        } else {
            out.push('\n');
            for _ in 0..joined {
                out.push('\n');
            }
            joined = 0;
        }
    }
    out
}

/// Turns a tobj error into one that names the line.
fn locate(path: &Path, text: &str, e: tobj::LoadError) -> ReadError {
    use tobj::LoadError as L;
    let total_v = text
        .lines()
        .filter(|l| l.trim_start().starts_with("v "))
        .count() as i64;
    let mut seen_v = 0i64;
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        let fields: Vec<&str> = words.collect();
        let bad = match (key, &e) {
            ("v", L::PositionParseError | L::ColorParseError) => {
                seen_v += 1;
                fields.len() < 3 || fields.iter().any(|w| w.parse::<f64>().is_err())
            }
            ("v", _) => {
                seen_v += 1;
                false
            }
            ("f", L::FaceParseError | L::FaceVertexOutOfBounds | L::InvalidPolygon) => {
                fields.len() < 3
                    || fields.iter().any(|w| {
                        let mut parts = w.split('/');
                        let head = parts.next().unwrap_or("");
                        // Texture and normal indices: empty or integers.
                        let rest_bad = parts.any(|p| !p.is_empty() && p.parse::<i64>().is_err());
                        rest_bad
                            || match head.parse::<i64>() {
                                Ok(k) if k > 0 => k > total_v,
                                Ok(k) if k < 0 => -k > seen_v,
                                _ => true,
                            }
                    })
            }
            ("vn", L::NormalParseError) => {
                fields.len() < 3 || fields.iter().any(|w| w.parse::<f64>().is_err())
            }
            ("vt", L::TexcoordParseError) => {
                fields.is_empty() || fields.iter().any(|w| w.parse::<f64>().is_err())
            }
            _ => false,
        };
        if bad {
            let what = match e {
                L::FaceVertexOutOfBounds => format!(
                    "face refers to a vertex that does not exist ({total_v} vertices in the file)"
                ),
                _ => format!("{e}"),
            };
            return ReadError::line(path, i + 1, what);
        }
    }
    ReadError::file(path, format!("not a readable OBJ mesh: {e}"))
}

/// Writes the mesh with one normal per vertex (`vn`, faces as `f a//a b//b c//c`) when given.
pub fn write_with_normals(
    mesh: &TriMesh,
    normals: Option<&[DVec3]>,
    path: &Path,
) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        writeln!(
            w,
            "# lamina mesh: {} vertices, {} triangles, units mm",
            mesh.positions.len(),
            mesh.triangles.len()
        )?;
        for (i, p) in mesh.positions.iter().enumerate() {
            match &mesh.colors {
                Some(c) => {
                    let [r, g, b] = c[i];
                    writeln!(w, "v {} {} {} {r} {g} {b}", p.x, p.y, p.z)?
                }
                None => writeln!(w, "v {} {} {}", p.x, p.y, p.z)?,
            }
        }
        if let Some(normals) = normals {
            for n in normals {
                writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
            }
            for t in &mesh.triangles {
                let [a, b, c] = t.map(|i| i + 1);
                writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
            }
        } else {
            for t in &mesh.triangles {
                writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
            }
        }
        Ok(())
    })
}
