//! A fabricator's check of panels made elsewhere: read polygons (OBJ faces, kept as polygons;
//! DXF 3DFACE entities, polyface meshes and closed POLYLINE/LWPOLYLINE), and measure each one
//! with the figures of `panels.rs`: flatness, best fit and normal for every polygon; quads also
//! get the corner, diagonal and torsion figures, other polygons the deviation from their Newell
//! plane as the corner figure.

use std::path::Path;

use dxf::entities::EntityType;
use dxf::Drawing;
use glam::DVec3;

use super::panels::{polygon_metrics, QuadMetrics};
use crate::files::{extension, ReadError};
use crate::network::io::dxf::{load_drawing, lw_polyline, polyline};
use crate::network::io::units::dxf_units;

/// One audited polygon.
#[derive(Clone, Debug)]
pub struct Audited {
    pub corners: Vec<DVec3>,
    pub metrics: QuadMetrics,
}

pub fn read_polygons(path: &Path) -> Result<Vec<Vec<DVec3>>, ReadError> {
    let polygons = match extension(path).as_str() {
        "obj" => read_obj(path)?,
        "dxf" => read_dxf(path)?,
        other => {
            return Err(ReadError::file(
                path,
                format!("cannot audit .{other} files: give panels as .obj faces or .dxf 3DFACE/closed polylines"),
            ))
        }
    };
    if polygons.is_empty() {
        return Err(ReadError::file(
            path,
            "holds no panels (faces or closed polylines)",
        ));
    }
    for (k, p) in polygons.iter().enumerate() {
        if let Some(c) = p.iter().position(|c| !c.is_finite()) {
            return Err(ReadError::record(
                path,
                format!("panel {k}"),
                format!("corner {c} is not finite"),
            ));
        }
    }
    Ok(polygons)
}

pub fn audit(polygons: &[Vec<DVec3>]) -> Vec<Audited> {
    polygons
        .iter()
        .map(|p| {
            let metrics = polygon_metrics(p);
            Audited {
                corners: p.clone(),
                metrics,
            }
        })
        .collect()
}

fn read_obj(path: &Path) -> Result<Vec<Vec<DVec3>>, ReadError> {
    let opts = tobj::LoadOptions {
        triangulate: false,
        single_index: true,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj(path, &opts)
        .map_err(|e| ReadError::file(path, format!("not an OBJ lamina can read: {e}")))?;
    let mut out = Vec::new();
    for m in &models {
        let mesh = &m.mesh;
        let p = &mesh.positions;
        let corner = |i: u32| {
            let i = i as usize * 3;
            DVec3::new(p[i], p[i + 1], p[i + 2])
        };
        let mut at = 0;
        // Without arities every face is a triangle.
        let arities: Vec<u32> = if mesh.face_arities.is_empty() {
            vec![3; mesh.indices.len() / 3]
        } else {
            mesh.face_arities.clone()
        };
        for n in arities {
            let n = n as usize;
            let face = &mesh.indices[at..at + n];
            if face.iter().any(|&i| i as usize * 3 + 2 >= p.len()) {
                return Err(ReadError::record(
                    path,
                    format!("face {}", out.len()),
                    "refers to a vertex that does not exist",
                ));
            }
            out.push(face.iter().map(|&i| corner(i)).collect());
            at += n;
        }
    }
    Ok(out)
}

/// Panels from a DXF, in millimetres by its `$INSUNITS` (else `$MEASUREMENT`, else mm).
fn read_dxf(path: &Path) -> Result<Vec<Vec<DVec3>>, ReadError> {
    let bytes = crate::files::read_nonempty(path)?;
    let scale = dxf_units(&bytes, None).scale_to_mm;
    let drawing = load_drawing(path, &bytes)?;
    let mut out = read_drawing(path, &drawing)?;
    if scale != 1.0 {
        for c in out.iter_mut().flatten() {
            *c *= scale;
        }
    }
    Ok(out)
}

fn read_drawing(path: &Path, drawing: &Drawing) -> Result<Vec<Vec<DVec3>>, ReadError> {
    let v = |p: &dxf::Point| DVec3::new(p.x, p.y, p.z);
    let mut out = Vec::new();
    for e in drawing.entities() {
        match &e.specific {
            EntityType::Face3D(f) => {
                let mut c = vec![
                    v(&f.first_corner),
                    v(&f.second_corner),
                    v(&f.third_corner),
                    v(&f.fourth_corner),
                ];
                // A triangle repeats its third corner.
                if c[3] == c[2] {
                    c.pop();
                }
                out.push(c);
            }
            EntityType::Polyline(pl) if pl.is_polyface_mesh() => {
                out.extend(polyface_faces(path, e, pl)?);
            }
            EntityType::Polyline(pl) if pl.is_closed() => {
                out.push(closed_loop(path, e, polyline(pl))?);
            }
            EntityType::LwPolyline(pl) if pl.is_closed() => {
                out.push(closed_loop(path, e, lw_polyline(pl, e.common.elevation))?);
            }
            _ => {}
        }
    }
    Ok(out)
}

/// The faces of a polyface mesh (a POLYLINE with flag 64): vertex records (flags 64 + 128)
/// hold the positions, face records (flag 128 alone) up to four 1-based indices into them,
/// negative where the edge after the corner is invisible, 0 where the face has fewer.
fn polyface_faces(
    path: &Path,
    e: &dxf::entities::Entity,
    pl: &dxf::entities::Polyline,
) -> Result<Vec<Vec<DVec3>>, ReadError> {
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for v in pl.vertices() {
        if v.flags & 64 != 0 {
            let p = &v.location;
            positions.push(DVec3::new(p.x, p.y, p.z));
        } else if v.flags & 128 != 0 {
            let idx = [
                v.polyface_mesh_vertex_index1,
                v.polyface_mesh_vertex_index2,
                v.polyface_mesh_vertex_index3,
                v.polyface_mesh_vertex_index4,
            ];
            faces.push(idx);
        }
    }
    faces
        .iter()
        .enumerate()
        .map(|(f, idx)| {
            idx.iter()
                .filter(|&&i| i != 0)
                .map(|&i| {
                    positions
                        .get(i.unsigned_abs() as usize - 1)
                        .copied()
                        .ok_or_else(|| {
                            ReadError::record(
                                path,
                                format!(
                                    "polyface mesh with handle {:X}, face {f}",
                                    e.common.handle.0
                                ),
                                format!(
                                    "refers to vertex {i}, but the mesh has {}",
                                    positions.len()
                                ),
                            )
                        })
                })
                .collect()
        })
        .collect()
}

/// A closed polyline's corners in world coordinates (2D polylines through their object
/// coordinate system), without the first corner repeated at the end.
fn closed_loop(
    path: &Path,
    e: &dxf::entities::Entity,
    pts: Result<Vec<DVec3>, String>,
) -> Result<Vec<DVec3>, ReadError> {
    let mut c = pts.map_err(|msg| {
        ReadError::record(
            path,
            format!("polyline with handle {:X}", e.common.handle.0),
            msg,
        )
    })?;
    if c.len() > 1 && c.first() == c.last() {
        c.pop();
    }
    Ok(c)
}
