//! Mesh files: OBJ (read through tobj, vertex colours kept; our own writer) and STL (ASCII or
//! binary in, binary out, through stl_io); PNG renders (write only).

mod obj;
mod png;
mod stl;

use std::path::Path;

use glam::DVec3;

use super::TriMesh;
use crate::files::{extension, ReadError, WriteError};

pub use png::{
    check_render_size, network_strokes, render_png_bytes, render_png_bytes_with, Stroke3,
    BACKGROUND, VEIN,
};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Stl,
    Png,
}

impl MeshFormat {
    pub fn from_path(path: &Path) -> Option<Self> {
        match extension(path).as_str() {
            "obj" => Some(Self::Obj),
            "stl" => Some(Self::Stl),
            "png" => Some(Self::Png),
            _ => None,
        }
    }
}

/// Bodies in an STL file: the `solid` blocks of an ASCII STL (CAD programs write one per body);
/// `None` for binary STL, OBJ, or a file that cannot be read.
pub fn stl_bodies(path: &Path) -> Option<usize> {
    if MeshFormat::from_path(path) != Some(MeshFormat::Stl) {
        return None;
    }
    stl::ascii_solids(&std::fs::read(path).ok()?)
}

/// Reads a mesh, choosing the format by extension. The result has in-range indices and finite
/// coordinates; whether it is a manifold is for `check_manifold` to say.
pub fn read_mesh(path: &Path) -> Result<TriMesh, ReadError> {
    read_with(path, stl::read).map(|(mesh, _)| mesh)
}

/// Like `read_mesh`, with what the file held that was not read, one phrase each ("2 l
/// (polylines)", "1 byte after the binary STL's 12 triangles"), for the caller to say.
pub fn read_mesh_noted(path: &Path) -> Result<(TriMesh, Vec<String>), ReadError> {
    read_with(path, stl::read)
}

/// Like `read_mesh_noted`, but a binary STL's corners are not welded: three vertices per
/// triangle, in file order. For callers that only need the triangles (the slicer): reading is
/// then little more than parsing.
pub fn read_triangles(path: &Path) -> Result<(TriMesh, Vec<String>), ReadError> {
    read_with(path, stl::read_soup)
}

fn read_with(
    path: &Path,
    read_stl: fn(&Path) -> Result<TriMesh, ReadError>,
) -> Result<(TriMesh, Vec<String>), ReadError> {
    let mut not_read = Vec::new();
    let mesh = match MeshFormat::from_path(path) {
        Some(MeshFormat::Obj) => {
            let (mesh, skipped) = obj::read_noted(path)?;
            not_read.extend(skipped.iter().map(|(what, n)| format!("{n} {what}")));
            mesh
        }
        Some(MeshFormat::Stl) => {
            let mesh = read_stl(path)?;
            if let Some((n, t)) = stl::trailing_bytes(path) {
                not_read.push(format!("{t} byte(s) after the binary STL's {n} triangles"));
            }
            mesh
        }
        _ => {
            return Err(ReadError::file(
                path,
                "not a mesh file lamina reads (expected .obj or .stl)",
            ))
        }
    };
    if mesh.triangles.is_empty() {
        return Err(ReadError::file(path, "no triangles: nothing to read"));
    }
    if let Some(v) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(ReadError::record(
            path,
            format!("vertex {v}"),
            "coordinate is not finite",
        ));
    }
    if let Some(v) = (mesh.colors.iter().flatten()).position(|c| c.iter().any(|x| !x.is_finite())) {
        return Err(ReadError::record(
            path,
            format!("vertex {v}"),
            "colour is not finite",
        ));
    }
    Ok((mesh, not_read))
}

/// Writes a mesh, choosing the format by extension (`size` is the PNG render's longer side).
pub fn write_mesh(mesh: &TriMesh, path: &Path, size: u32) -> Result<(), WriteError> {
    write_checked(mesh, None, path, size)
}

/// Writes a PNG render of a mesh with strokes on it (veins on their surface).
pub fn write_png_with_strokes(
    mesh: &TriMesh,
    strokes: &[Stroke3],
    path: &Path,
    size: u32,
) -> Result<(), WriteError> {
    let bytes = render_png_bytes_with(mesh, strokes, size).map_err(|msg| WriteError::Content {
        path: path.to_path_buf(),
        msg,
    })?;
    crate::files::write_atomic(path, |w| std::io::Write::write_all(w, &bytes))
}

/// Writes an OBJ mesh with one normal per vertex.
pub fn write_obj_with_normals(
    mesh: &TriMesh,
    normals: &[DVec3],
    path: &Path,
) -> Result<(), WriteError> {
    if normals.len() != mesh.positions.len() || normals.iter().any(|n| !n.is_finite()) {
        return Err(WriteError::Content {
            path: path.to_path_buf(),
            msg: format!(
                "{} finite normals needed for {} vertices",
                mesh.positions.len(),
                mesh.positions.len()
            ),
        });
    }
    write_checked(mesh, Some(normals), path, 0)
}

fn write_checked(
    mesh: &TriMesh,
    normals: Option<&[DVec3]>,
    path: &Path,
    size: u32,
) -> Result<(), WriteError> {
    let nv = mesh.positions.len();
    let bad_index = mesh
        .triangles
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= nv));
    let bad_point = mesh.positions.iter().position(|p| !p.is_finite());
    let content = |msg: String| WriteError::Content {
        path: path.to_path_buf(),
        msg,
    };
    if let Some(t) = bad_index {
        return Err(content(format!(
            "triangle {t} has a vertex index out of range"
        )));
    }
    if let Some(c) = mesh.colors.as_ref().filter(|c| c.len() != nv) {
        return Err(content(format!(
            "{} vertex colours for {nv} vertices",
            c.len()
        )));
    }
    if let Some(v) = bad_point {
        return Err(content(format!("vertex {v} is not finite")));
    }
    match MeshFormat::from_path(path) {
        Some(MeshFormat::Obj) => obj::write_with_normals(mesh, normals, path),
        _ if normals.is_some() => Err(content("normals are written to .obj only".into())),
        Some(MeshFormat::Stl) => stl::write(mesh, path),
        Some(MeshFormat::Png) => png::write(mesh, path, size),
        None => Err(content(
            "unknown mesh format (expected .obj, .stl or .png)".into(),
        )),
    }
}
