//! The form as a printable mesh. Each triangle of the cell graph is cut into six about its
//! centroid and edge midpoints, so every cell owns a fan round its centre (its Voronoi-like
//! patch). A textured cell gets an inner ring in its patch and its centre and ring are lifted
//! along the cell's normal: a low dome (`bumpy`), a hollow (`dimple`), a cone (`spiky`) or a
//! thin long cone (`hair`), scaled by the cell's mean edge length. Flat cells lie exactly on
//! the cell graph's triangles.
//!
//! The mesh is then tested triangle against triangle; the textures of the cells whose
//! triangles meet are halved, and after five halvings removed, until nothing meets or only
//! flat cells do (counted in the report: the base surface itself meets).

use std::collections::HashMap;

use glam::DVec3;

use super::embed::cell_normal;
use super::program::Texture;
use super::sim::Form;
use crate::mesh::TriMesh;

#[derive(Clone, Debug)]
pub struct SkinOptions {
    /// Millimetres per unit cell size (default 2).
    pub cell_mm: f64,
    /// Turn textures into geometry (default true).
    pub textures: bool,
}

impl Default for SkinOptions {
    fn default() -> Self {
        SkinOptions {
            cell_mm: 2.0,
            textures: true,
        }
    }
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SkinReport {
    pub vertices: usize,
    pub triangles: usize,
    pub textured_cells: usize,
    /// Cells whose texture was reduced so the mesh does not meet itself.
    pub reduced_cells: usize,
    /// Of those, cells whose texture was removed altogether.
    pub flattened_cells: usize,
    /// Pairs of triangles that still meet (0 unless the base surface meets itself).
    pub self_intersections: usize,
    /// Intersection tests run.
    pub passes: usize,
}

/// The shape of a texture: inner ring at `ring` of the way out, lifted `ring_lift`, centre
/// lifted `tip`; lifts in mean edge lengths.
struct Relief {
    ring: f64,
    ring_lift: f64,
    tip: f64,
}

fn relief(t: Texture) -> Option<Relief> {
    let r = |ring, ring_lift, tip| {
        Some(Relief {
            ring,
            ring_lift,
            tip,
        })
    };
    match t {
        Texture::Flat => None,
        Texture::Bumpy => r(0.6, 0.18, 0.28),
        Texture::Dimple => r(0.6, -0.14, -0.22),
        Texture::Spiky => r(0.3, 0.08, 0.9),
        Texture::Hair => r(0.12, 0.03, 1.8),
    }
}

/// Halvings of a texture before it is removed.
const HALVINGS: u32 = 5;

pub fn skin(form: &Form, options: &SkinOptions) -> (TriMesh, SkinReport) {
    let n = form.graph.len();
    let layout = Layout::new(form, options.cell_mm);
    let textured = |v: usize| options.textures && relief(form.texture[v]).is_some();
    let mut halvings = vec![0u32; n];
    let mut passes = 0;
    loop {
        let (mesh, owner) = layout.build(form, options, &halvings);
        passes += 1;
        let pairs = mesh.self_intersections();
        let mut changed = false;
        if !pairs.is_empty() && passes <= 2 * HALVINGS as usize + 2 {
            let mut seen = vec![false; n];
            for (a, b) in &pairs {
                for t in [a, b] {
                    let v = owner[*t as usize] as usize;
                    if textured(v) && halvings[v] <= HALVINGS && !seen[v] {
                        seen[v] = true;
                        halvings[v] += 1;
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            let report = SkinReport {
                vertices: mesh.positions.len(),
                triangles: mesh.triangles.len(),
                textured_cells: (0..n).filter(|&v| textured(v)).count(),
                reduced_cells: halvings.iter().filter(|&&h| h > 0).count(),
                flattened_cells: halvings.iter().filter(|&&h| h > HALVINGS).count(),
                self_intersections: pairs.len(),
                passes,
            };
            return (mesh, report);
        }
    }
}

/// What every pass shares: the subdivided surface's points (cell centres, then face
/// centroids, then edge midpoints, in mm) and colours, each cell's patch corners, its normal
/// and its mean edge length (in cell sizes).
struct Layout {
    positions: Vec<DVec3>,
    colours: Vec<[f32; 3]>,
    /// Corners of cell v's patch, alternately edge midpoint and face centroid, counter-clockwise:
    /// `corners[start[v]..start[v + 1]]`.
    corners: Vec<u32>,
    start: Vec<usize>,
    normal: Vec<DVec3>,
    spacing: Vec<f64>,
}

impl Layout {
    fn new(form: &Form, s: f64) -> Layout {
        let g = &form.graph;
        let n = g.len();
        let faces = g.faces();
        let mut positions: Vec<DVec3> = form.pos.iter().map(|p| *p * s).collect();
        let mut colours: Vec<[f32; 3]> = form.colour.clone();
        let mut face_of: HashMap<(u32, u32), u32> = HashMap::with_capacity(3 * faces.len());
        for t in &faces {
            let id = positions.len() as u32;
            positions.push(t.iter().map(|&v| form.pos[v as usize]).sum::<DVec3>() * (s / 3.0));
            colours.push(mean_colour(t.iter().map(|&v| form.colour[v as usize])));
            for k in 0..3 {
                face_of.insert((t[k], t[(k + 1) % 3]), id);
            }
        }
        let mut mid: HashMap<(u32, u32), u32> = HashMap::with_capacity(3 * n);
        for v in 0..n as u32 {
            for &u in g.neighbours(v) {
                if v < u {
                    mid.insert((v, u), positions.len() as u32);
                    positions.push((form.pos[v as usize] + form.pos[u as usize]) * (0.5 * s));
                    colours.push(mean_colour([
                        form.colour[v as usize],
                        form.colour[u as usize],
                    ]));
                }
            }
        }
        let mut corners = Vec::with_capacity(6 * faces.len());
        let mut start = Vec::with_capacity(n + 1);
        let mut normal = Vec::with_capacity(n);
        let mut spacing = Vec::with_capacity(n);
        for v in 0..n as u32 {
            start.push(corners.len());
            let ring = g.neighbours(v);
            for &u in ring {
                corners.push(mid[&(v.min(u), v.max(u))]);
                corners.push(face_of[&(v, u)]);
            }
            let x = form.pos[v as usize];
            normal.push(cell_normal(g, &form.pos, v));
            spacing.push(
                ring.iter()
                    .map(|&u| form.pos[u as usize].distance(x))
                    .sum::<f64>()
                    / ring.len() as f64,
            );
        }
        start.push(corners.len());
        Layout {
            positions,
            colours,
            corners,
            start,
            normal,
            spacing,
        }
    }

    /// The textured mesh with each cell's relief halved `halvings[v]` times (removed past
    /// [`HALVINGS`]), and the cell owning each triangle.
    fn build(&self, form: &Form, options: &SkinOptions, halvings: &[u32]) -> (TriMesh, Vec<u32>) {
        let n = form.graph.len();
        let mut positions = self.positions.clone();
        let mut colours = self.colours.clone();
        let mut triangles = Vec::with_capacity(3 * self.corners.len());
        let mut owner = Vec::with_capacity(3 * self.corners.len());
        for v in 0..n as u32 {
            let vi = v as usize;
            let corners = &self.corners[self.start[vi]..self.start[vi + 1]];
            let shape =
                relief(form.texture[vi]).filter(|_| options.textures && halvings[vi] <= HALVINGS);
            let m = corners.len();
            match shape {
                None => {
                    for k in 0..m {
                        triangles.push([v, corners[k], corners[(k + 1) % m]]);
                        owner.push(v);
                    }
                }
                Some(r) => {
                    let amp = self.spacing[vi] * options.cell_mm * 0.5f64.powi(halvings[vi] as i32);
                    let lift = self.normal[vi];
                    let centre = positions[vi];
                    let first = positions.len() as u32;
                    for &c in corners {
                        let q = positions[c as usize];
                        positions.push(centre + (q - centre) * r.ring + lift * (r.ring_lift * amp));
                        colours.push(form.colour[vi]);
                    }
                    positions[vi] = centre + lift * (r.tip * amp);
                    for k in 0..m {
                        let (i0, i1) = (first + k as u32, first + ((k + 1) % m) as u32);
                        let (q0, q1) = (corners[k], corners[(k + 1) % m]);
                        triangles.push([v, i0, i1]);
                        triangles.push([i0, q0, q1]);
                        triangles.push([i0, q1, i1]);
                        owner.extend([v, v, v]);
                    }
                }
            }
        }
        (
            TriMesh {
                positions,
                triangles,
                colors: Some(colours),
            },
            owner,
        )
    }
}

fn mean_colour(cs: impl IntoIterator<Item = [f32; 3]>) -> [f32; 3] {
    let mut sum = [0f32; 3];
    let mut k = 0f32;
    for c in cs {
        for i in 0..3 {
            sum[i] += c[i];
        }
        k += 1.0;
    }
    sum.map(|x| x / k.max(1.0))
}
