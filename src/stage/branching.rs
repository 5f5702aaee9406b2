//! What `lsystem` and `bifurcate` share after the tree is drawn: Murray widths, fitting to a
//! façade boundary, standing up, projecting onto a surface, and the report's common sections.

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::geom::upright;
pub use crate::grow::facade::Fit;
use crate::grow::facade::{fit, FacadeError, FacadeOptions, FacadeReport};
use crate::grow::outline::Outline;
use crate::grow::project::{project, ProjectError, ProjectOptions, ProjectReport};
use crate::grow::report::Quality;
use crate::grow::tree::Tree;
use crate::stage::OptionError;
use crate::{Network, TriMesh};

/// What happens to a drawn tree. `Default`: as drawn, widths by depth.
#[derive(Clone, Debug, Default)]
pub struct Shape {
    /// Widths by Murray's law with this exponent instead of by depth. Default: none.
    pub murray: Option<f64>,
    /// Tip radius with `murray`, mm. Default: the depth radius ÷ 8.
    pub tip_radius: Option<f64>,
    /// Fit the tree to this façade boundary. Default: none.
    pub boundary: Option<Outline>,
    /// Where the root goes on the boundary. Default: the middle of its lowest points.
    pub root_at: Option<DVec2>,
    /// How the tree is sized to the boundary. Default: cover.
    pub fit: Option<Fit>,
    /// Leave out the frame (the boundary as members). Default false.
    pub no_frame: bool,
    /// Radius of the frame members, mm. Default: the trunk's.
    pub frame_radius: Option<f64>,
    /// Stand the drawing up: its +Y becomes +Z. Default false.
    pub upright: bool,
    /// Project the result onto this surface. Default: none.
    pub onto: Option<TriMesh>,
    /// Direction of projection. Default +Z, or +Y when upright.
    pub direction: Option<DVec3>,
    /// Split members whose projection bends away from the chord by more than this, mm.
    /// Default 1e-3 of the surface's size.
    pub sag: Option<f64>,
}

/// The sizes of what was made.
#[derive(Clone, Debug, Serialize)]
pub struct NetworkFigures {
    /// Bounding box size, mm.
    pub bbox_mm: [f64; 3],
    /// Edges (members).
    pub edges: usize,
    /// Longest member, mm.
    pub longest_member_mm: f64,
    /// Nodes.
    pub nodes: usize,
    /// Total member length, mm.
    pub total_length_mm: f64,
}

/// The report's common sections (the generator adds its own).
#[derive(Clone, Debug, Serialize)]
pub struct Sections {
    #[serde(skip_serializing_if = "Option::is_none")]
    /// The façade fitting.
    pub facade: Option<FacadeReport>,
    /// The network made.
    pub network: NetworkFigures,
    #[serde(skip_serializing_if = "Option::is_none")]
    /// The projection onto a surface.
    pub projection: Option<ProjectReport>,
    /// Crossings and joints in the plane (a flat drawing only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quality: Option<Quality>,
}

/// Why a tree could not be shaped.
#[derive(Debug, thiserror::Error)]
pub enum ShapeError {
    #[error(transparent)]
    /// An option out of range.
    Option(#[from] OptionError),
    #[error(transparent)]
    /// Fitting to the façade failed.
    Facade(#[from] FacadeError),
    #[error(transparent)]
    /// Projection onto the surface failed.
    Project(#[from] ProjectError),
}

/// Widths, façade, upright, projection; the network (named, with its parameters) and the
/// common report sections. `default_tip` is the Murray tip radius when none is given.
pub fn shape(
    mut tree: Tree,
    default_tip: f64,
    opts: &Shape,
) -> Result<(Network, Sections), ShapeError> {
    if let Some(n) = opts.murray {
        let tip = opts.tip_radius.unwrap_or(default_tip);
        if !(n.is_finite() && n > 0.0) {
            return Err(OptionError::new(
                "murray",
                format!("{n}: the exponent must be a positive number"),
            )
            .into());
        }
        if !(tip.is_finite() && tip > 0.0) {
            return Err(OptionError::new(
                "tip_radius",
                format!("{tip}: must be a positive distance in mm"),
            )
            .into());
        }
        tree.murray(n, tip);
    }
    let flat = {
        let size = tree.network.bbox().diagonal();
        tree.network
            .nodes
            .iter()
            .all(|n| n.p.z.abs() <= 1e-9 * size)
    };
    let mut facade = None;
    let mut net = match &opts.boundary {
        Some(boundary) => {
            let f = FacadeOptions {
                root_at: opts.root_at,
                fit: opts.fit.unwrap_or(Fit::Cover),
                frame: !opts.no_frame,
                frame_radius: opts.frame_radius,
            };
            let (net, rep) = fit(&tree.network, 0, boundary, &f)?;
            facade = Some(rep);
            net
        }
        None => tree.network,
    };
    // Crossings and joints in the plane, before standing up or projecting.
    let quality = flat.then(|| Quality::of(&net, 1));
    if opts.upright {
        for n in &mut net.nodes {
            n.p = upright(n.p);
            n.normal = n.normal.map(upright);
        }
    }
    let mut projection = None;
    if let Some(mesh) = &opts.onto {
        let direction = match opts.direction {
            Some(d) => d,
            None if opts.upright => DVec3::Y,
            None => DVec3::Z,
        };
        let (projected, rep) = project(
            &net,
            mesh,
            &ProjectOptions {
                direction,
                sag: opts.sag,
            },
        )?;
        projection = Some(rep);
        net = projected;
    }
    let lengths = net.lengths();
    let network = NetworkFigures {
        bbox_mm: net.bbox().size().to_array(),
        edges: net.edges.len(),
        longest_member_mm: lengths.map_or(0.0, |l| l.max),
        nodes: net.nodes.len(),
        total_length_mm: lengths.map_or(0.0, |l| l.total),
    };
    Ok((
        net,
        Sections {
            facade,
            network,
            projection,
            quality,
        },
    ))
}

/// `rect:W,H` (base centred on the origin) as a boundary.
pub fn rect(w: f64, h: f64) -> Result<Outline, OptionError> {
    if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
        return Err(OptionError::new(
            "boundary",
            format!("rect:{w},{h}: width and height must be positive"),
        ));
    }
    let p = DVec2::new;
    Outline::new(vec![
        p(-w / 2.0, 0.0),
        p(w / 2.0, 0.0),
        p(w / 2.0, h),
        p(-w / 2.0, h),
    ])
    .map_err(|e| OptionError::new("boundary", e.to_string()))
}
