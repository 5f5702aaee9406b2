//! Each node's reference direction (the surface normal an axis stays near, and the order of
//! edges around a node): a guide surface's normal at the closest point, else the normal the
//! network stores, else, for a flat network, the normal of its plane.

use glam::DVec3;

use crate::mesh::closest::SurfaceIndex;
use crate::{Network, TriMesh};

/// Why a network has no reference directions.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReferenceError {
    #[error("surface= has no triangles")]
    EmptySurface,
    #[error("node {0} has no stored normal and the network is not flat: give surface=")]
    NotFlat(usize),
}

/// Each node's reference direction: the guide surface's normal at the closest point (turned to
/// agree with a stored normal), else the stored normal, else, for a flat network, the normal of
/// its plane (+Z side, or toward +Y/+X when vertical).
pub fn reference_normals(
    net: &Network,
    surface: Option<&TriMesh>,
) -> Result<Vec<DVec3>, ReferenceError> {
    if let Some(mesh) = surface {
        let index = SurfaceIndex::new(mesh);
        return net
            .nodes
            .iter()
            .map(|n| {
                let c = index.closest(n.p).ok_or(ReferenceError::EmptySurface)?;
                let d = index.normal(&c);
                Ok(match n.normal {
                    Some(stored) if stored.dot(d) < 0.0 => -d,
                    _ => d,
                })
            })
            .collect();
    }
    if let Some(stored) = net
        .nodes
        .iter()
        .map(|n| n.normal)
        .collect::<Option<Vec<_>>>()
    {
        return Ok(stored);
    }
    let missing = net
        .nodes
        .iter()
        .position(|n| n.normal.is_none())
        .unwrap_or(0);
    let plane = flat_normal(net).ok_or(ReferenceError::NotFlat(missing))?;
    Ok(net
        .nodes
        .iter()
        .map(|n| n.normal.unwrap_or(plane))
        .collect())
}

/// The normal of the plane all nodes lie in (to 1e-9 of the bounding box's diagonal), if any.
pub fn flat_normal(net: &Network) -> Option<DVec3> {
    let p: Vec<DVec3> = net.nodes.iter().map(|n| n.p).collect();
    let first = *p.first()?;
    let far = *p.iter().max_by(|a, b| {
        a.distance_squared(first)
            .total_cmp(&b.distance_squared(first))
    })?;
    let axis = (far - first).try_normalize()?;
    let off = |q: &DVec3| (*q - first) - axis * (*q - first).dot(axis);
    let third = p
        .iter()
        .max_by(|a, b| off(a).length_squared().total_cmp(&off(b).length_squared()))?;
    let diag = net.bbox().diagonal().max(f64::MIN_POSITIVE);
    let normal = match axis.cross(off(third)).try_normalize() {
        Some(n) if off(third).length() > 1e-9 * diag => n,
        // All on one line: any plane through it; prefer the one facing +Z.
        _ => {
            let n = axis.cross(DVec3::Z).cross(axis);
            n.try_normalize().unwrap_or(DVec3::Z)
        }
    };
    if p.iter()
        .any(|q| (*q - first).dot(normal).abs() > 1e-9 * diag)
    {
        return None;
    }
    let up = [DVec3::Z, DVec3::Y, DVec3::X]
        .into_iter()
        .find(|a| normal.dot(*a).abs() > 1e-9)
        .unwrap_or(DVec3::Z);
    Some(if normal.dot(up) < 0.0 {
        -normal
    } else {
        normal
    })
}
