//! A fabricator's check of panels made elsewhere: read polygons with what the file calls them
//! (OBJ faces, kept as polygons, with their group or object; DXF 3DFACE entities, polyface
//! meshes, MESH entities and closed POLYLINE/LWPOLYLINE, with their layer; the panels of a
//! lamina axes file; the plates of a lamina plates file, with their tags and assembly groups),
//! and measure each one with the figures of `panels.rs`: flatness, best fit and normal for every
//! polygon; quads also get the corner, diagonal and torsion figures, other polygons the
//! deviation from their Newell plane as the corner figure.

mod obj;

use std::collections::BTreeMap;
use std::path::Path;

use dxf::entities::EntityType;
use dxf::Drawing;
use glam::{DAffine3, DVec3, DVec4};
use rayon::prelude::*;

use super::axes::{read_axes, FORMAT as AXES_FORMAT};
use super::panels::{polygon_metrics, QuadMetrics};
use crate::fabricate::plates_file::{read_plates, FORMAT as PLATES_FORMAT};
use crate::files::{extension, json_format, read_nonempty, utf8_text, ReadError};
use crate::network::io::dxf::{load_drawing, lw_polyline, placements, polyline, type_name};
use crate::network::io::units::dxf_units;

/// Polygons up to this many corners get their exact size (all pairs).
pub const EXACT_SIZE_CORNERS: usize = 4096;

/// One panel as read: its corners and what the file calls it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Panel {
    pub corners: Vec<DVec3>,
    /// The panel's own name: a plate's tag, a DXF entity's handle (hexadecimal; a mesh face's
    /// followed by `/` and its face number).
    pub name: Option<String>,
    /// The DXF layer it was drawn on.
    pub layer: Option<String>,
    /// The OBJ group or object it belongs to, or a plate's assembly group.
    pub group: Option<String>,
    /// The network edge it stands on, for the panels of an axes file.
    pub nodes: Option<[u32; 2]>,
}

impl Panel {
    fn new(corners: Vec<DVec3>) -> Panel {
        Panel {
            corners,
            ..Default::default()
        }
    }

    /// The largest distance between two corners, mm: what size rules compare. Exact up to
    /// `EXACT_SIZE_CORNERS` corners; beyond, the farthest corner from each corner extreme along
    /// x, y or z (a curve flattened into thousands of corners), which can fall short of the
    /// exact figure only when the farthest pair is extreme along no axis.
    pub fn size(&self) -> f64 {
        let c = &self.corners;
        let farthest = |p: &DVec3| c.iter().map(|q| p.distance(*q)).fold(0.0, f64::max);
        if c.len() > EXACT_SIZE_CORNERS {
            let key = |k: usize| move |a: &&DVec3, b: &&DVec3| a[k].total_cmp(&b[k]);
            return (0..3)
                .flat_map(|k| [c.iter().min_by(key(k)), c.iter().max_by(key(k))])
                .flatten()
                .map(farthest)
                .fold(0.0, f64::max);
        }
        c.iter().map(farthest).fold(0.0, f64::max)
    }
}

/// The panels of a file, and one line for each kind of thing it holds that is not a panel.
#[derive(Clone, Debug, Default)]
pub struct Panels {
    pub panels: Vec<Panel>,
    pub notes: Vec<String>,
}

pub fn read_panels(path: &Path) -> Result<Panels, ReadError> {
    let read = match extension(path).as_str() {
        "obj" => obj::read(path)?,
        "dxf" => read_dxf(path)?,
        "json" => read_json(path)?,
        other => {
            return Err(ReadError::file(
                path,
                format!(
                    "cannot audit .{other} files: give panels as .obj faces, .dxf 3DFACE / \
                     polyface meshes / MESH / closed polylines, or a lamina axes or plates .json"
                ),
            ))
        }
    };
    if read.panels.is_empty() {
        return Err(ReadError::file(
            path,
            "holds no panels (faces or closed polylines)",
        ));
    }
    for (k, p) in read.panels.iter().enumerate() {
        if let Some(c) = p.corners.iter().position(|c| !c.is_finite()) {
            return Err(ReadError::record(
                path,
                format!("panel {k}"),
                format!("corner {c} is not finite"),
            ));
        }
    }
    Ok(read)
}

/// Every figure of every panel, on all cores; the result does not depend on their number.
pub fn audit(panels: &[Panel]) -> Vec<QuadMetrics> {
    panels
        .par_iter()
        .with_min_len(1024)
        .map(|p| polygon_metrics(&p.corners))
        .collect()
}

/// Panels from a DXF, in millimetres by its `$INSUNITS` (else `$MEASUREMENT`, else mm).
fn read_dxf(path: &Path) -> Result<Panels, ReadError> {
    let bytes = read_nonempty(path)?;
    let units = dxf_units(&bytes, None);
    let drawing = load_drawing(path, &bytes)?;
    let mut read = read_drawing(path, &drawing)?;
    let (meshes, notes) = mesh_entities(path, &bytes)?;
    read.panels.extend(meshes);
    read.notes.extend(notes);
    if units.scale_to_mm != 1.0 {
        for c in read.panels.iter_mut().flat_map(|p| p.corners.iter_mut()) {
            *c *= units.scale_to_mm;
        }
    }
    if units.assumed || units.scale_to_mm != 1.0 {
        read.notes.push(format!(
            "units: {} ({}), ×{} to mm",
            units.unit, units.from, units.scale_to_mm
        ));
    }
    Ok(read)
}

/// Panels an audit takes from blocks at most (the network reader's own limit on points).
const MAX_BLOCK_PANELS: usize = 20_000_000;

/// Walks model space, expanding INSERTs (MINSERT arrays and nested blocks too) as the network
/// reader does: each panel's corners in world coordinates.
struct Walk<'a> {
    path: &'a Path,
    blocks: std::collections::HashMap<String, &'a dxf::Block>,
    out: Vec<Panel>,
    skipped: BTreeMap<String, usize>,
    paper: usize,
    inserts: usize,
    stack: Vec<String>,
}

fn read_drawing(path: &Path, drawing: &Drawing) -> Result<Panels, ReadError> {
    let mut walk = Walk {
        path,
        blocks: drawing
            .blocks()
            .map(|b| (b.name.to_ascii_uppercase(), b))
            .collect(),
        out: Vec::new(),
        skipped: BTreeMap::new(),
        paper: 0,
        inserts: 0,
        stack: Vec::new(),
    };
    for e in drawing.entities() {
        walk.entity(e, &DAffine3::IDENTITY, None)?;
    }
    let mut notes = Vec::new();
    if !walk.skipped.is_empty() {
        let list: Vec<String> = walk
            .skipped
            .iter()
            .map(|(k, n)| format!("{n} {k}"))
            .collect();
        notes.push(format!(
            "read but not audited (not a panel): {}",
            list.join(", ")
        ));
    }
    if walk.inserts > 0 {
        notes.push(format!(
            "{} block insertions expanded (panels named by the INSERT's handle, then the \
             entity's)",
            walk.inserts
        ));
    }
    if walk.paper > 0 {
        notes.push(format!(
            "{} panels in paper space not audited (model space only)",
            walk.paper
        ));
    }
    Ok(Panels {
        panels: walk.out,
        notes,
    })
}

impl Walk<'_> {
    /// One entity drawn with `xf`; `within` names the INSERT it came through (its handle).
    fn entity(
        &mut self,
        e: &dxf::entities::Entity,
        xf: &DAffine3,
        within: Option<&str>,
    ) -> Result<(), ReadError> {
        let path = self.path;
        let v = |p: &dxf::Point| DVec3::new(p.x, p.y, p.z);
        let layer = Some(e.common.layer.clone());
        let handle = match within {
            Some(outer) => format!("{outer}>{:X}", e.common.handle.0),
            None => format!("{:X}", e.common.handle.0),
        };
        let is_panel = match &e.specific {
            EntityType::Face3D(_) => true,
            EntityType::Polyline(pl) => pl.is_polyface_mesh() || pl.is_closed(),
            EntityType::LwPolyline(pl) => pl.is_closed(),
            _ => false,
        };
        if is_panel && e.common.is_in_paper_space {
            self.paper += 1;
            return Ok(());
        }
        let mut faces: Vec<(Vec<DVec3>, Option<usize>)> = Vec::new();
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
                faces.push((c, None));
            }
            EntityType::Polyline(pl) if pl.is_polyface_mesh() => {
                for (f, face) in polyface_faces(path, e, pl)?.into_iter().enumerate() {
                    faces.push((face, Some(f)));
                }
            }
            EntityType::Polyline(pl) if pl.is_closed() => {
                faces.push((closed_loop(path, e, polyline(pl))?, None));
            }
            EntityType::LwPolyline(pl) if pl.is_closed() => {
                faces.push((
                    closed_loop(path, e, lw_polyline(pl, e.common.elevation))?,
                    None,
                ));
            }
            EntityType::Polyline(_) | EntityType::LwPolyline(_) => {
                *self
                    .skipped
                    .entry(format!("open {}", type_name(&e.specific)))
                    .or_default() += 1;
            }
            EntityType::Insert(ins) if !e.common.is_in_paper_space => {
                return self.insert(e, ins, xf, &handle);
            }
            other => *self.skipped.entry(type_name(other)).or_default() += 1,
        }
        for (corners, face) in faces {
            if self.out.len() >= MAX_BLOCK_PANELS {
                return Err(ReadError::file(
                    path,
                    format!("the drawing expands to more than {MAX_BLOCK_PANELS} panels"),
                ));
            }
            let corners = corners
                .into_iter()
                .map(|c| xf.transform_point3(c))
                .collect();
            self.out.push(Panel {
                layer: layer.clone(),
                name: Some(match face {
                    Some(f) => format!("{handle}/{f}"),
                    None => handle.clone(),
                }),
                ..Panel::new(corners)
            });
        }
        Ok(())
    }

    fn insert(
        &mut self,
        e: &dxf::entities::Entity,
        ins: &dxf::entities::Insert,
        xf: &DAffine3,
        handle: &str,
    ) -> Result<(), ReadError> {
        let bad = |msg: String| {
            ReadError::record(
                self.path,
                format!("entity {handle} ({})", type_name(&e.specific)),
                msg,
            )
        };
        let name = ins.name.to_ascii_uppercase();
        let Some(block) = self.blocks.get(&name).copied() else {
            return Err(bad(format!(
                "block \"{}\" is not defined",
                ins.name.escape_debug()
            )));
        };
        if self.stack.contains(&name) || self.stack.len() >= 32 {
            return Err(bad(format!(
                "block \"{}\" inserts itself, or blocks nest deeper than 32",
                ins.name.escape_debug()
            )));
        }
        let (cells, places) = placements(ins, block).map_err(bad)?;
        if cells > MAX_BLOCK_PANELS as u64 {
            return Err(bad(format!(
                "an array of {cells} cells, more than {MAX_BLOCK_PANELS}"
            )));
        }
        self.stack.push(name);
        for place in places {
            self.inserts += 1;
            // Nested arrays of empty blocks produce no panel but cost a loop each.
            if self.inserts > MAX_BLOCK_PANELS {
                return Err(bad(format!(
                    "the drawing inserts blocks more than {MAX_BLOCK_PANELS} times"
                )));
            }
            let world = *xf * place;
            for inner in &block.entities {
                self.entity(inner, &world, Some(handle))?;
            }
        }
        self.stack.pop();
        Ok(())
    }
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

/// The control faces of the MESH entities (AcDbSubDMesh) in the ENTITIES section of an ASCII
/// DXF, which the `dxf` crate does not read, with a note for each one CAD shows smoothed.
/// Group codes: 5 handle, 8 layer, 67 paper space, 91 subdivision level, 92 vertex count then that many
/// 10/20/30 points (world coordinates), 93 face-list length then that many 90 values, each face
/// its corner count followed by its 0-based vertex indices.
fn mesh_entities(path: &Path, bytes: &[u8]) -> Result<(Vec<Panel>, Vec<String>), ReadError> {
    let mut panels = Vec::new();
    let mut notes = Vec::new();
    if memchr::memmem::find(bytes, b"AcDbSubDMesh").is_none() {
        return Ok((panels, notes));
    }
    let text = String::from_utf8_lossy(bytes);
    let mut lines = text.lines().enumerate();
    let mut section = "";
    let mut after_section = false;
    let mut mesh: Option<MeshRecord> = None;
    let (mut smoothed, mut paper) = (0, 0);
    while let (Some((at, code)), Some((_, value))) = (lines.next(), lines.next()) {
        let line = at + 1;
        let code: i32 = code
            .trim()
            .parse()
            .map_err(|_| ReadError::line(path, line, "expected a DXF group code"))?;
        let value = value.trim();
        if code == 0 {
            if let Some(m) = mesh.take() {
                let (faces, level, in_paper) = m.finish(path)?;
                if in_paper {
                    paper += 1;
                } else {
                    smoothed += usize::from(level > 0);
                    panels.extend(faces);
                }
            }
            match value {
                "SECTION" => after_section = true,
                "ENDSEC" => section = "",
                "MESH" if section == "ENTITIES" => mesh = Some(MeshRecord::new(line + 1)),
                _ => {}
            }
            continue;
        }
        if after_section && code == 2 {
            section = if value == "ENTITIES" {
                "ENTITIES"
            } else {
                "other"
            };
        }
        after_section = false;
        if let Some(m) = &mut mesh {
            m.pair(path, line, code, value, bytes.len())?;
        }
    }
    if smoothed > 0 {
        notes.push(format!(
            "{smoothed} MESH entities are smoothed in CAD (subdivision level > 0): their control faces are audited"
        ));
    }
    if paper > 0 {
        notes.push(format!(
            "{paper} MESH entities in paper space not audited (model space only)"
        ));
    }
    Ok((panels, notes))
}

/// One MESH entity as its group codes arrive.
struct MeshRecord {
    line: usize,
    handle: Option<String>,
    layer: Option<String>,
    paper: bool,
    level: i64,
    vertices: Vec<DVec3>,
    /// Vertices announced by code 92 and not yet complete.
    vertices_left: Option<usize>,
    point: [f64; 3],
    list: Vec<i64>,
    list_left: Option<usize>,
}

impl MeshRecord {
    fn new(line: usize) -> MeshRecord {
        MeshRecord {
            line,
            handle: None,
            layer: None,
            paper: false,
            level: 0,
            vertices: Vec::new(),
            vertices_left: None,
            point: [0.0; 3],
            list: Vec::new(),
            list_left: None,
        }
    }

    fn pair(
        &mut self,
        path: &Path,
        line: usize,
        code: i32,
        value: &str,
        file_len: usize,
    ) -> Result<(), ReadError> {
        let int = || {
            value.parse::<i64>().map_err(|_| {
                ReadError::line(
                    path,
                    line + 1,
                    format!("MESH: \"{value}\" is not an integer"),
                )
            })
        };
        // Each announced item takes at least two lines of text: bound counts by the file.
        let count = |n: i64| {
            usize::try_from(n)
                .ok()
                .filter(|&n| n <= file_len / 4)
                .ok_or_else(|| {
                    ReadError::line(
                        path,
                        line + 1,
                        format!("MESH: count {n} is negative or larger than the file"),
                    )
                })
        };
        let in_vertices = self.vertices_left.is_some_and(|n| n > 0);
        match code {
            5 if self.vertices_left.is_none() => self.handle = Some(value.to_ascii_uppercase()),
            8 if self.vertices_left.is_none() => self.layer = Some(value.to_string()),
            67 => self.paper = int()? == 1,
            91 if self.vertices_left.is_none() => self.level = int()?,
            92 if self.vertices_left.is_none() => self.vertices_left = Some(count(int()?)?),
            10 | 20 | 30 if in_vertices => {
                let v: f64 = value.parse().map_err(|_| {
                    ReadError::line(path, line + 1, format!("MESH: \"{value}\" is not a number"))
                })?;
                self.point[(code / 10 - 1) as usize] = v;
                if code == 30 {
                    self.vertices.push(DVec3::from_array(self.point));
                    self.vertices_left = self.vertices_left.map(|n| n - 1);
                }
            }
            93 if self.vertices_left == Some(0) && self.list_left.is_none() => {
                self.list_left = Some(count(int()?)?)
            }
            90 if self.list_left.is_some_and(|n| n > 0) => {
                self.list.push(int()?);
                self.list_left = self.list_left.map(|n| n - 1);
            }
            _ => {}
        }
        Ok(())
    }

    /// The faces, the subdivision level and whether the mesh is in paper space.
    fn finish(self, path: &Path) -> Result<(Vec<Panel>, i64, bool), ReadError> {
        let at = format!("MESH at line {}", self.line);
        if self.vertices_left.unwrap_or(0) > 0 || self.list_left.unwrap_or(0) > 0 {
            return Err(ReadError::record(
                path,
                at,
                "ends before all its vertices or faces",
            ));
        }
        let mut faces = Vec::new();
        let mut k = 0;
        while k < self.list.len() {
            let n = self.list[k];
            let idx = usize::try_from(n)
                .ok()
                .and_then(|n| self.list.get(k + 1..k + 1 + n))
                .ok_or_else(|| {
                    ReadError::record(
                        path,
                        &at,
                        format!(
                            "face {} has {n} corners, more than the list holds",
                            faces.len()
                        ),
                    )
                })?;
            let corners = idx
                .iter()
                .map(|&i| {
                    usize::try_from(i)
                        .ok()
                        .and_then(|i| self.vertices.get(i).copied())
                        .ok_or_else(|| {
                            ReadError::record(
                                path,
                                &at,
                                format!(
                                    "face {} refers to vertex {i}, but the mesh has {}",
                                    faces.len(),
                                    self.vertices.len()
                                ),
                            )
                        })
                })
                .collect::<Result<Vec<_>, _>>()?;
            faces.push(Panel {
                layer: self.layer.clone(),
                name: self.handle.as_ref().map(|h| format!("{h}/{}", faces.len())),
                ..Panel::new(corners)
            });
            k += 1 + idx.len();
        }
        Ok((faces, self.level, self.paper))
    }
}

/// The panels of a lamina axes file (one quad per edge) or the plates of a plates file.
fn read_json(path: &Path) -> Result<Panels, ReadError> {
    let text = utf8_text(path, read_nonempty(path)?)?;
    match json_format(path, &text)?.as_deref() {
        Some(AXES_FORMAT) => {
            let axes = read_axes(path)?;
            let panels = axes
                .quads()
                .into_iter()
                .zip(&axes.edges)
                .map(|(q, &e)| Panel {
                    nodes: Some(e),
                    ..Panel::new(q.to_vec())
                })
                .collect();
            Ok(Panels {
                panels,
                notes: Vec::new(),
            })
        }
        Some(PLATES_FORMAT) => {
            let (plates, cores, _) = read_plates(path)?;
            let panels = plates
                .iter()
                .map(|p| {
                    let m = p.matrix;
                    let world = |x: f64, y: f64| {
                        let v = DVec4::new(x, y, 0.0, 1.0);
                        DVec3::new(
                            DVec4::from_array(m[0]).dot(v),
                            DVec4::from_array(m[1]).dot(v),
                            DVec4::from_array(m[2]).dot(v),
                        )
                    };
                    Panel {
                        name: Some(p.id.clone()),
                        group: Some(p.group.to_string()),
                        ..Panel::new(p.outline.iter().map(|c| world(c.x, c.y)).collect())
                    }
                })
                .collect();
            let notes = if cores.is_empty() {
                Vec::new()
            } else {
                vec![format!(
                    "{} node cores (tubes, not plates) not audited",
                    cores.len()
                )]
            };
            Ok(Panels { panels, notes })
        }
        other => Err(ReadError::file(
            path,
            format!(
                "format {} is neither {AXES_FORMAT} nor {PLATES_FORMAT}: lamina audits the panels of an axes file or the plates of a plates file",
                other.map_or("(none)".into(), |f| format!("\"{f}\""))
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture() -> String {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fixtures/panels/ezdxf_panels.dxf"
        );
        std::fs::read_to_string(path).expect("the ezdxf panels fixture")
    }

    fn read_text(text: &str) -> Result<Panels, ReadError> {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("panels.dxf");
        std::fs::write(&path, text).expect("write");
        read_panels(&path)
    }

    #[test]
    fn mesh_entities_keep_their_faces_layer_and_handle() {
        let read = read_text(&fixture()).expect("reads");
        let mesh: Vec<&Panel> = read
            .panels
            .iter()
            .filter(|p| p.layer.as_deref() == Some("GLASS-MESH"))
            .collect();
        assert_eq!(mesh.len(), 2);
        // The second face (1, 4, 5, 2) of the ezdxf mesh, in inches.
        let inch = 25.4;
        assert_eq!(mesh[1].corners[1], DVec3::new(20.0, 0.0, 0.0) * inch);
        assert_eq!(mesh[1].corners[2], DVec3::new(20.0, 10.0, -0.01) * inch);
        assert!(mesh[0].name.as_deref().is_some_and(|n| n.ends_with("/0")));
    }

    #[test]
    fn broken_mesh_entities_are_named() {
        let text = fixture();
        for (from, to, needle) in [
            (
                " 93\n10\n 90\n4\n 90\n0\n",
                " 93\n10\n 90\n4\n 90\n99\n",
                "refers to vertex 99",
            ),
            (
                " 93\n10\n 90\n4\n",
                " 93\n10\n 90\n14\n",
                "more than the list holds",
            ),
            (
                " 92\n6\n",
                " 92\n2000000000\n",
                "MESH: count 2000000000 is negative or larger",
            ),
            (" 92\n6\n", " 92\n-6\n", "MESH: count -6 is negative"),
            (
                " 92\n6\n",
                " 92\n7\n",
                "MESH at line 2026: ends before all its vertices",
            ),
            // The dxf crate stops at this one first, naming the line.
            (" 92\n6\n 10\n0.0\n", " 92\n6\n 10\nx\n", "line 2047"),
        ] {
            assert!(text.contains(from), "{from:?} is in the fixture");
            let err = read_text(&text.replacen(from, to, 1))
                .expect_err(to)
                .to_string();
            assert!(err.contains(needle), "{to:?}: {err}");
        }
    }
}
