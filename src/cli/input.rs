//! Loading "a file the user gave": a network or a mesh, told apart by extension and, for OBJ,
//! by whether it holds faces or polylines.

use std::path::Path;

use anyhow::{bail, Context, Result};
use clap::Args;

use lamina::files::extension;
use lamina::mesh::io::read_mesh;
use lamina::network::io::{read_network, Imported, ReadOptions};
use lamina::network::Weld;
use lamina::TriMesh;

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
