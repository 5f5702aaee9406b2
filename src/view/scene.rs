//! A scene from what a page is to show together, each input named: plates take the welds,
//! sizing and axes given beside them; axes alone are shown as panels.

use std::path::PathBuf;

use glam::DVec3;

use super::pack::{self, PlateExtras, ViewError};
use super::{flat, Scene};
use crate::analyze::sizing::CheckEdge;
use crate::fabricate::plates_file::{CoreRecord, PlateRecord, WeldNode};
use crate::rationalize::axes::Axes;
use crate::report::planarity::Metric;

/// One thing a page shows.
#[derive(Clone, Debug)]
pub enum Input {
    Network(Box<crate::Network>),
    Mesh(crate::TriMesh),
    /// Axes, with the tolerance the solve held them to (from the axes file's summary).
    Axes(Box<Axes>, Option<f64>),
    Plates(Vec<PlateRecord>, Vec<CoreRecord>),
    /// The weld report: target gap, its tolerance, the nodes.
    Welds(f64, f64, Vec<WeldNode>),
    /// The sizing's result per edge.
    Sizing(Vec<CheckEdge>),
    /// A nest.json, its sheets read from the cut DXFs beside it.
    Nest(PathBuf),
    /// An SL1 archive.
    Print(PathBuf),
}

/// The scene of `inputs` (each with a name for the page's notes); `title` defaults to the
/// names.
pub fn scene(inputs: &[(String, Input)], title: Option<String>) -> Result<Scene, ViewError> {
    let names: Vec<&str> = inputs.iter().map(|(n, _)| n.as_str()).collect();
    let mut scene = Scene {
        title: title.unwrap_or_else(|| format!("lamina: {}", names.join(", "))),
        ..Scene::default()
    };
    let mut points: Vec<DVec3> = Vec::new();
    for (_, input) in inputs {
        match input {
            Input::Network(n) => points.extend(n.nodes.iter().map(|n| n.p)),
            Input::Mesh(m) => points.extend(m.positions.iter().copied()),
            Input::Axes(a, _) => points.extend(a.positions.iter().copied()),
            Input::Plates(p, _) => points.extend(
                p.iter()
                    .map(|p| DVec3::new(p.matrix[0][3], p.matrix[1][3], p.matrix[2][3])),
            ),
            _ => {}
        }
    }
    let origin = pack::middle(points);
    scene.origin = origin.to_array();
    let find = |f: &dyn Fn(&Input) -> bool| inputs.iter().find(|(_, i)| f(i));
    let has_plates = find(&|i| matches!(i, Input::Plates(..))).is_some();
    for (name, input) in inputs {
        match input {
            Input::Network(n) => scene.layers.extend(pack::network(n, origin)?),
            Input::Mesh(m) => {
                scene.layers.push(pack::mesh(m, name, origin)?);
            }
            Input::Axes(a, tolerance) => {
                if has_plates {
                    // The panels would hide the plates standing in them.
                    scene.notes.push(format!(
                        "{name}: its panels are not drawn beside the plates that stand in them"
                    ));
                    continue;
                }
                let t = tolerance.unwrap_or_else(|| {
                    scene.notes.push(format!(
                        "{name}: no tolerance in its summary; panels held to 0.01 mm"
                    ));
                    0.01
                });
                let (quads, rows) = pack::axes_rows(a, t);
                scene
                    .layers
                    .push(pack::panels(&quads, &rows, Metric::Corner, origin)?);
                scene.layers.push(pack::node_axes(a, origin)?);
            }
            Input::Plates(p, c) => {
                let welds = find(&|i| matches!(i, Input::Welds(..))).and_then(|(_, i)| match i {
                    Input::Welds(g, t, n) => Some((*g, *t, n.as_slice())),
                    _ => None,
                });
                let checks = find(&|i| matches!(i, Input::Sizing(..))).and_then(|(_, i)| match i {
                    Input::Sizing(c) => Some(c.as_slice()),
                    _ => None,
                });
                let extras = PlateExtras { welds, checks };
                let (layers, notes) = pack::plates(p, c, extras, origin)?;
                scene.layers.extend(layers);
                scene.notes.extend(notes);
            }
            Input::Welds(..) | Input::Sizing(_) if !has_plates => scene
                .notes
                .push(format!("{name}: shown with plates.json only; give it too")),
            Input::Welds(..) | Input::Sizing(_) => {}
            Input::Nest(path) => {
                let (sheets, notes) = flat::sheets(path)?;
                scene.sheets.extend(sheets);
                scene.notes.extend(notes);
            }
            Input::Print(path) => {
                if scene.print.is_some() {
                    return Err(ViewError::Input {
                        path: path.clone(),
                        msg: "one SL1 archive per page".into(),
                    });
                }
                scene.print = Some(flat::print(path)?);
            }
        }
    }
    Ok(scene)
}

/// One line on what a scene shows.
pub fn what(scene: &Scene) -> String {
    let mut parts: Vec<String> = scene
        .layers
        .iter()
        .map(|l| format!("{} {}", l.objects.len(), l.name))
        .collect();
    if !scene.sheets.is_empty() {
        parts.push(format!("{} sheets", scene.sheets.len()));
    }
    if let Some(p) = &scene.print {
        parts.push(format!(
            "{} print layers, {} islands",
            p.images.len(),
            p.islands.len() + p.more_islands
        ));
    }
    parts.join(", ")
}
