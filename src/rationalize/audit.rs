//! A fabricator's check of panels made elsewhere: read polygons (OBJ faces, kept as polygons;
//! DXF 3DFACE entities and closed POLYLINE/LWPOLYLINE), and measure each one with the metrics
//! of `panels.rs`. Quads get every metric; triangles are planar; polygons of five or more
//! corners get the deviation from their Newell plane and no diagonal or torsion figures.

use std::path::Path;

use dxf::entities::EntityType;
use dxf::Drawing;
use glam::DVec3;

use super::panels::{polygon_deviation, quad_metrics, QuadMetrics};
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
            let metrics = match p.len() {
                4 => quad_metrics([p[0], p[1], p[2], p[3]]),
                _ => QuadMetrics {
                    deviation: polygon_deviation(p),
                    diagonal_distance: 0.0,
                    diagonal_rel_edge: 0.0,
                    diagonal_rel_diagonal: 0.0,
                    torsion_deg: 0.0,
                },
            };
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
            EntityType::Polyline(pl) if pl.is_closed() && !pl.is_polyface_mesh() => {
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
