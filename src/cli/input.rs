//! Loading "a file the user gave": a network or a mesh, told apart by extension and, for OBJ,
//! by whether it holds faces or polylines.

use std::path::Path;

use anyhow::{bail, Context, Result};
use clap::Args;

use glam::DVec3;
use lamina::files::extension;
use lamina::mesh::io::read_mesh;
use lamina::network::io::{read_network, Imported, ReadOptions};
use lamina::network::Weld;

use lamina::mesh::closest::SurfaceIndex;
use lamina::{Network, TriMesh};

/// How OBJ and DXF points become shared nodes.
#[derive(Args, Clone, Copy, Debug)]
pub struct WeldArgs {
    /// Weld points closer than this distance, in mm, into one node (OBJ and DXF input)
    #[arg(long, value_name = "MM", conflicts_with = "weld_rel")]
    pub weld: Option<f64>,
    /// Weld points closer than this fraction of the bounding-box diagonal [default: 1e-6]
    #[arg(long, value_name = "FRACTION")]
    pub weld_rel: Option<f64>,
}

impl WeldArgs {
    pub fn options(&self) -> Result<ReadOptions> {
        let weld = match (self.weld, self.weld_rel) {
            (Some(mm), _) => Weld::Absolute(mm),
            (None, Some(f)) => Weld::Relative(f),
            (None, None) => Weld::DEFAULT,
        };
        let t = match weld {
            Weld::Absolute(t) | Weld::Relative(t) => t,
        };
        if !(t.is_finite() && t >= 0.0) {
            bail!("weld tolerance must be a finite number ≥ 0, got {t}");
        }
        Ok(ReadOptions { weld })
    }
}

pub enum Loaded {
    Network(Box<Imported>),
    Mesh(TriMesh),
}

pub fn load(path: &Path, opts: &ReadOptions) -> Result<Loaded> {
    let ext = extension(path);
    let is_mesh = match ext.as_str() {
        "stl" => true,
        "json" | "dxf" => false,
        "obj" => obj_has_faces(path)?,
        _ => bail!(
            "{}: unknown file type `.{ext}` (networks: .json .obj .dxf; meshes: .obj .stl)",
            path.display()
        ),
    };
    Ok(if is_mesh {
        Loaded::Mesh(read_mesh(path)?)
    } else {
        Loaded::Network(Box::new(read_network(path, opts)?))
    })
}

/// An OBJ with `f` records and no `l` records is a mesh; anything else is read as a network.
fn obj_has_faces(path: &Path) -> Result<bool> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    let (mut faces, mut lines) = (false, false);
    for line in bytes.split(|&b| b == b'\n') {
        let line = line.trim_ascii_start();
        faces |= line.starts_with(b"f ") || line.starts_with(b"f\t");
        lines |= line.starts_with(b"l ") || line.starts_with(b"l\t");
    }
    Ok(faces && !lines)
}

/// Each node's reference direction (its surface normal): the guide surface's normal at the
/// closest point (turned to agree with a stored normal), else the stored normal, else, for a
/// flat network, the normal of its plane (+Z side, or toward +Y/+X when vertical).
pub fn reference_normals(net: &Network, surface: Option<&Path>) -> Result<Vec<DVec3>> {
    if let Some(path) = surface {
        let mesh = read_mesh(path)?;
        let index = SurfaceIndex::new(&mesh);
        return net
            .nodes
            .iter()
            .map(|n| {
                let c = index
                    .closest(n.p)
                    .with_context(|| format!("--surface {}: has no triangles", path.display()))?;
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
    let plane = flat_normal(net).with_context(|| {
        format!("node {missing} has no stored normal and the network is not flat: give --surface")
    })?;
    Ok(net
        .nodes
        .iter()
        .map(|n| n.normal.unwrap_or(plane))
        .collect())
}

/// The normal of the plane all nodes lie in (to 1e-9 of the bounding box's diagonal), if any.
fn flat_normal(net: &Network) -> Option<DVec3> {
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
