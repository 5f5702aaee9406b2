//! The closed cells of a network on a surface, and a triangle mesh of them.
//!
//! The faces come from the network's rotation system: around each node the edges are ordered
//! counter-clockwise in the node's tangent plane (⊥ its normal), and a face is traced by
//! arriving at a node and leaving along the edge just clockwise of the one arrived on. Every
//! directed edge lies on exactly one face, and V − E + F is the Euler characteristic of the
//! closed surface the network is drawn on, as if every hole had been capped.
//!
//! A face is a cell when its boundary turns counter-clockwise about the surface normals (its
//! vector area points the way they do). The others are holes: the outside of a flat network,
//! or the rim of an open surface, where the normals spread around the face and cancel. Each cell
//! is triangulated by spade's constrained Delaunay triangulation in the plane of its vector
//! area, its boundary (and any vein that ends inside it) held as constraints; no point is added,
//! so the mesh's vertices are the network's nodes.

use glam::DVec3;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::mesh::TriMesh;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CellError {
    #[error("node {0} has a position that is not finite")]
    NonFinite(u32),
    #[error("edge {0} refers to node {1}, which does not exist")]
    MissingNode(usize, u32),
    #[error("edge {0} joins node {1} to itself or to a node at the same place")]
    ZeroLength(usize, u32),
    #[error("edges {0} and {1} join the same two nodes")]
    Parallel(usize, usize),
    #[error("node {0} has a normal that is not a finite non-zero vector")]
    BadNormal(u32),
    #[error("{0} normals for {1} nodes")]
    NormalCount(usize, usize),
}

/// A face is a cell when its vector area and the mean of its nodes' normals agree at least this
/// well (cosine, the mean's length included, so normals that spread around a rim count less).
pub const MIN_ALIGNMENT: f64 = 0.3;

/// One face of the embedding.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Face {
    /// Nodes in boundary order (counter-clockwise about the normals for a cell). A vein that
    /// ends inside the face is walked out and back, so its nodes appear twice.
    pub nodes: Vec<u32>,
    /// Edges in the same order as `nodes`: edge k joins `nodes[k]` and `nodes[k + 1]`.
    pub edges: Vec<u32>,
    /// Edges walked in both directions: veins that end inside the face, or bridges.
    pub inner_edges: Vec<u32>,
    /// Vector area's length, mm².
    pub area: f64,
    pub alignment: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Cell {
    pub face: usize,
    pub triangles: std::ops::Range<usize>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct Untriangulated {
    pub face: usize,
    pub reason: String,
}

#[derive(Clone, Copy, Debug, serde::Serialize, PartialEq, Eq)]
pub struct Euler {
    /// Nodes with at least one edge (isolated nodes bound nothing).
    pub vertices: usize,
    pub edges: usize,
    pub faces: usize,
    /// V − E + F.
    pub chi: i64,
    pub components: usize,
}

#[derive(Clone, Debug)]
pub struct Cells {
    pub faces: Vec<Face>,
    /// Faces that are cells, with their triangles in `mesh`.
    pub cells: Vec<Cell>,
    /// Faces that are not cells (holes), by index in `faces`.
    pub holes: Vec<usize>,
    pub untriangulated: Vec<Untriangulated>,
    /// Vertices are the network's nodes, in order; triangles turn counter-clockwise about the
    /// normals.
    pub mesh: TriMesh,
    /// Per node: the area-weighted normal of its triangles, turned to agree with its reference
    /// normal; the reference where it has no triangle.
    pub normals: Vec<DVec3>,
    pub euler: Euler,
    pub open_tips: usize,
    pub isolated: usize,
}

/// Finds the faces of the network drawn on the surface whose normal at node i is `normals[i]`,
/// and triangulates the cells.
pub fn cells(
    positions: &[DVec3],
    edges: &[[u32; 2]],
    normals: &[DVec3],
) -> Result<Cells, CellError> {
    check(positions, edges, normals)?;
    let n = positions.len();
    let next = rotation_system(positions, edges, normals);

    // Trace faces: half-edge 2k runs a→b along edge k, 2k + 1 runs b→a.
    let from = |h: usize| {
        let [a, b] = edges[h / 2];
        if h.is_multiple_of(2) {
            a
        } else {
            b
        }
    };
    let mut face_of = vec![usize::MAX; 2 * edges.len()];
    let mut faces = Vec::new();
    for start in 0..2 * edges.len() {
        if face_of[start] != usize::MAX {
            continue;
        }
        let id = faces.len();
        let mut walk = Vec::new();
        let mut h = start;
        loop {
            face_of[h] = id;
            walk.push(h);
            h = next[h];
            if h == start {
                break;
            }
        }
        faces.push(face(&walk, &from, positions, normals));
    }

    let degree = degrees(n, edges);
    let euler = euler_of(edges, &degree, faces.len());

    let mut mesh = TriMesh {
        positions: positions.to_vec(),
        triangles: Vec::new(),
        colors: None,
    };
    let mut cells = Vec::new();
    let mut holes = Vec::new();
    let mut untriangulated = Vec::new();
    for (id, f) in faces.iter().enumerate() {
        if f.alignment < MIN_ALIGNMENT {
            holes.push(id);
            continue;
        }
        match triangulate(f, positions) {
            Ok(tris) => {
                let start = mesh.triangles.len();
                mesh.triangles.extend(tris);
                cells.push(Cell {
                    face: id,
                    triangles: start..mesh.triangles.len(),
                });
            }
            Err(reason) => untriangulated.push(Untriangulated { face: id, reason }),
        }
    }

    let mut sum = vec![DVec3::ZERO; n];
    for t in &mesh.triangles {
        let [a, b, c] = mesh.corners(t);
        let w = (b - a).cross(c - a); // length = twice the area
        for &v in t {
            sum[v as usize] += w;
        }
    }
    let normals = sum
        .iter()
        .zip(normals)
        .map(|(s, r)| {
            let r = r.normalize();
            match s.try_normalize() {
                Some(d) if d.dot(r) < 0.0 => -d,
                Some(d) => d,
                None => r,
            }
        })
        .collect();

    Ok(Cells {
        faces,
        cells,
        holes,
        untriangulated,
        mesh,
        normals,
        euler,
        open_tips: degree.iter().filter(|&&d| d == 1).count(),
        isolated: degree.iter().filter(|&&d| d == 0).count(),
    })
}

fn check(positions: &[DVec3], edges: &[[u32; 2]], normals: &[DVec3]) -> Result<(), CellError> {
    if normals.len() != positions.len() {
        return Err(CellError::NormalCount(normals.len(), positions.len()));
    }
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(CellError::NonFinite(i as u32));
    }
    if let Some(i) = normals
        .iter()
        .position(|d| !(d.is_finite() && d.length() > 1e-12))
    {
        return Err(CellError::BadNormal(i as u32));
    }
    let mut seen = std::collections::HashMap::new();
    for (k, &[a, b]) in edges.iter().enumerate() {
        for v in [a, b] {
            if v as usize >= positions.len() {
                return Err(CellError::MissingNode(k, v));
            }
        }
        if positions[a as usize] == positions[b as usize] {
            return Err(CellError::ZeroLength(k, a));
        }
        if let Some(first) = seen.insert((a.min(b), a.max(b)), k) {
            return Err(CellError::Parallel(first, k));
        }
    }
    Ok(())
}

/// For each half-edge u→v, the half-edge that follows it on its face: v→w, where w is the
/// neighbour of v just clockwise of u (counter-clockwise order about v's normal). At a tip,
/// w = u: the face turns back.
/// V − E + F of the network drawn on the surface whose normal at node i is `normals[i]`, the
/// faces traced as `cells` traces them, without triangulating them.
pub fn euler(
    positions: &[DVec3],
    edges: &[[u32; 2]],
    normals: &[DVec3],
) -> Result<Euler, CellError> {
    check(positions, edges, normals)?;
    let next = rotation_system(positions, edges, normals);
    let mut seen = vec![false; next.len()];
    let mut faces = 0;
    for start in 0..next.len() {
        if seen[start] {
            continue;
        }
        faces += 1;
        let mut h = start;
        while !seen[h] {
            seen[h] = true;
            h = next[h];
        }
    }
    Ok(euler_of(edges, &degrees(positions.len(), edges), faces))
}

fn degrees(n: usize, edges: &[[u32; 2]]) -> Vec<usize> {
    let mut degree = vec![0usize; n];
    for &[a, b] in edges {
        degree[a as usize] += 1;
        degree[b as usize] += 1;
    }
    degree
}

fn euler_of(edges: &[[u32; 2]], degree: &[usize], faces: usize) -> Euler {
    let vertices = degree.iter().filter(|&&d| d > 0).count();
    Euler {
        vertices,
        edges: edges.len(),
        faces,
        chi: vertices as i64 - edges.len() as i64 + faces as i64,
        components: components(degree.len(), edges, degree),
    }
}

fn rotation_system(positions: &[DVec3], edges: &[[u32; 2]], normals: &[DVec3]) -> Vec<usize> {
    let n = positions.len();
    // Outgoing half-edges of each node, sorted by angle in its tangent plane.
    let mut out: Vec<Vec<(f64, usize)>> = vec![Vec::new(); n];
    for (k, &[a, b]) in edges.iter().enumerate() {
        out[a as usize].push((0.0, 2 * k));
        out[b as usize].push((0.0, 2 * k + 1));
    }
    let to = |h: usize| {
        let [a, b] = edges[h / 2];
        if h.is_multiple_of(2) {
            b
        } else {
            a
        }
    };
    // Position of each half-edge in its origin's rotation.
    let mut slot = vec![0usize; 2 * edges.len()];
    for (v, list) in out.iter_mut().enumerate() {
        let nrm = normals[v].normalize();
        let (t0, t1) = nrm.any_orthonormal_pair();
        for (angle, h) in list.iter_mut() {
            let d = positions[to(*h) as usize] - positions[v];
            *angle = d.dot(t1).atan2(d.dot(t0));
        }
        list.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        for (i, &(_, h)) in list.iter().enumerate() {
            slot[h] = i;
        }
    }
    (0..2 * edges.len())
        .map(|h| {
            let v = to(h) as usize;
            let twin = h ^ 1; // v→u
            let list = &out[v];
            let i = slot[twin];
            list[(i + list.len() - 1) % list.len()].1
        })
        .collect()
}

fn face(
    walk: &[usize],
    from: &dyn Fn(usize) -> u32,
    positions: &[DVec3],
    normals: &[DVec3],
) -> Face {
    let nodes: Vec<u32> = walk.iter().map(|&h| from(h)).collect();
    let edges: Vec<u32> = walk.iter().map(|&h| (h / 2) as u32).collect();
    let mut sorted = edges.clone();
    sorted.sort_unstable();
    let mut inner_edges: Vec<u32> = sorted
        .windows(2)
        .filter(|w| w[0] == w[1])
        .map(|w| w[0])
        .collect();
    inner_edges.dedup();
    let centre = nodes.iter().map(|&v| positions[v as usize]).sum::<DVec3>() / nodes.len() as f64;
    let mut vector_area = DVec3::ZERO;
    for (k, &v) in nodes.iter().enumerate() {
        let w = nodes[(k + 1) % nodes.len()];
        vector_area += 0.5 * (positions[v as usize] - centre).cross(positions[w as usize] - centre);
    }
    let mut distinct = nodes.clone();
    distinct.sort_unstable();
    distinct.dedup();
    let mean_normal = distinct
        .iter()
        .map(|&v| normals[v as usize].normalize())
        .sum::<DVec3>()
        / distinct.len() as f64;
    let area = vector_area.length();
    let alignment = if area > 0.0 {
        vector_area.dot(mean_normal) / area
    } else {
        0.0
    };
    Face {
        nodes,
        edges,
        inner_edges,
        area,
        alignment,
    }
}

/// Number of connected components among nodes with an edge.
fn components(n: usize, edges: &[[u32; 2]], degree: &[usize]) -> usize {
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    for &[a, b] in edges {
        let (ra, rb) = (root(&mut parent, a as usize), root(&mut parent, b as usize));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    (0..n)
        .filter(|&v| degree[v] > 0 && root(&mut parent, v) == v)
        .count()
}

/// Triangles of one cell: a constrained Delaunay triangulation of its nodes in the plane of its
/// vector area, keeping the triangles inside its boundary (even-odd over the edges walked once),
/// turned counter-clockwise about the vector area.
fn triangulate(f: &Face, positions: &[DVec3]) -> Result<Vec<[u32; 3]>, String> {
    let nodes = &f.nodes;
    let centre = nodes.iter().map(|&v| positions[v as usize]).sum::<DVec3>() / nodes.len() as f64;
    let mut normal = DVec3::ZERO;
    for (k, &v) in nodes.iter().enumerate() {
        let w = nodes[(k + 1) % nodes.len()];
        normal += (positions[v as usize] - centre).cross(positions[w as usize] - centre);
    }
    let normal = normal
        .try_normalize()
        .ok_or_else(|| "the cell has no area".to_string())?;
    let (u, w) = normal.any_orthonormal_pair();
    let flat = |v: u32| {
        let d = positions[v as usize] - centre;
        Point2::new(d.dot(u), d.dot(w))
    };

    let mut distinct = nodes.clone();
    distinct.sort_unstable();
    distinct.dedup();
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    let mut handle = std::collections::HashMap::new();
    let mut node_of = std::collections::HashMap::new();
    for &v in &distinct {
        let h = cdt
            .insert(flat(v))
            .map_err(|e| format!("node {v} cannot be placed in the cell's plane: {e}"))?;
        if let Some(other) = node_of.insert(h, v) {
            return Err(format!(
                "nodes {other} and {v} fall on the same point of the cell's plane"
            ));
        }
        handle.insert(v, h);
    }
    let mut walked_once = Vec::new();
    for (k, &e) in f.edges.iter().enumerate() {
        let (a, b) = (nodes[k], nodes[(k + 1) % nodes.len()]);
        if !f.inner_edges.contains(&e) {
            walked_once.push((flat(a), flat(b)));
        }
        let (ha, hb) = (handle[&a], handle[&b]);
        if cdt.exists_constraint(ha, hb) {
            continue;
        }
        if cdt.try_add_constraint(ha, hb).is_empty() {
            return Err(format!(
                "edge {e} crosses another edge of the cell in the cell's plane: either the \
                 network's edges cross without a node (node it: --split-crossings) or the cell \
                 is too curved to lay flat"
            ));
        }
    }
    if cdt.num_constraints() != distinct_edges(&f.edges) {
        return Err("a node lies on an edge of the cell in the cell's plane".to_string());
    }
    let mut tris = Vec::new();
    for t in cdt.inner_faces() {
        let vs = t.vertices();
        let p = vs.map(|v| v.position());
        let c = Point2::new(
            (p[0].x + p[1].x + p[2].x) / 3.0,
            (p[0].y + p[1].y + p[2].y) / 3.0,
        );
        if !inside(c, &walked_once) {
            continue;
        }
        let [a, b, c] = vs.map(|v| node_of[&v.fix()]);
        let turn = (positions[b as usize] - positions[a as usize])
            .cross(positions[c as usize] - positions[a as usize]);
        tris.push(if turn.dot(normal) >= 0.0 {
            [a, b, c]
        } else {
            [a, c, b]
        });
    }
    if tris.is_empty() {
        return Err("no triangle lies inside the cell's boundary".to_string());
    }
    Ok(tris)
}

fn distinct_edges(edges: &[u32]) -> usize {
    let mut e = edges.to_vec();
    e.sort_unstable();
    e.dedup();
    e.len()
}

/// Even-odd point-in-polygon over a set of segments.
fn inside(p: Point2<f64>, segments: &[(Point2<f64>, Point2<f64>)]) -> bool {
    let mut odd = false;
    for (a, b) in segments {
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if x > p.x {
                odd = !odd;
            }
        }
    }
    odd
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::rationalize::planarize::synthetic::square_grid as grid;

    #[test]
    fn a_flat_grid_has_its_squares_as_cells_and_one_hole() {
        let (p, e) = grid(4, 3);
        let normals = vec![DVec3::Z; p.len()];
        let c = cells(&p, &e, &normals).unwrap();
        assert_eq!(c.cells.len(), 6);
        assert_eq!(c.holes.len(), 1);
        assert_eq!(c.euler.chi, 2);
        assert!(c.untriangulated.is_empty());
        assert_eq!(c.mesh.triangles.len(), 12);
        assert!((c.mesh.area() - 30.0 * 20.0).abs() < 1e-9);
        for t in &c.mesh.triangles {
            let [a, b, cc] = c.mesh.corners(t);
            assert!(
                (b - a).cross(cc - a).z > 0.0,
                "triangle {t:?} turns clockwise"
            );
        }
        for f in c.cells.iter().map(|cell| &c.faces[cell.face]) {
            assert_eq!(f.edges.len(), 4);
        }
    }

    #[test]
    fn flipped_normals_swap_cells_and_hole_orientation() {
        let (p, e) = grid(3, 3);
        let normals = vec![-DVec3::Z; p.len()];
        let c = cells(&p, &e, &normals).unwrap();
        assert_eq!(c.cells.len(), 4);
        for t in &c.mesh.triangles {
            let [a, b, cc] = c.mesh.corners(t);
            assert!((b - a).cross(cc - a).z < 0.0);
        }
        assert!(c.normals.iter().all(|n| (*n + DVec3::Z).length() < 1e-12));
    }

    #[test]
    fn a_vein_ending_inside_a_cell_is_kept_as_a_constraint() {
        let (mut p, mut e) = grid(2, 2); // one 10 × 10 square: 0 1 / 2 3
        p.push(DVec3::new(5.0, 4.0, 0.0));
        e.push([0, 4]);
        let normals = vec![DVec3::Z; p.len()];
        let c = cells(&p, &e, &normals).unwrap();
        assert_eq!(c.cells.len(), 1);
        assert_eq!(c.open_tips, 1);
        let f = &c.faces[c.cells[0].face];
        assert_eq!(f.inner_edges, vec![4]);
        assert_eq!(f.nodes.len(), 6);
        assert!((c.mesh.area() - 100.0).abs() < 1e-9);
        let has_edge = |a: u32, b: u32| {
            c.mesh
                .triangles
                .iter()
                .any(|t| (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b))
        };
        assert!(
            has_edge(0, 4) && has_edge(4, 0),
            "the vein is not a mesh edge"
        );
    }

    #[test]
    fn a_cube_network_has_six_cells_and_chi_two() {
        let p: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64) * 10.0
            })
            .collect();
        let mut e = Vec::new();
        for a in 0..8u32 {
            for bit in [1, 2, 4] {
                if a & bit == 0 {
                    e.push([a, a | bit]);
                }
            }
        }
        let normals: Vec<DVec3> = p.iter().map(|q| *q - DVec3::splat(5.0)).collect();
        let c = cells(&p, &e, &normals).unwrap();
        assert_eq!(c.euler.chi, 2);
        assert_eq!(c.cells.len(), 6);
        assert!(c.holes.is_empty());
        let topo = c.mesh.check_manifold();
        assert!(topo.closed, "{topo:?}");
        assert!((topo.volume.unwrap() - 1000.0).abs() < 1e-9);
    }

    #[test]
    fn parallel_edges_and_bad_normals_are_errors() {
        let p = vec![DVec3::ZERO, DVec3::X];
        assert_eq!(
            cells(&p, &[[0, 1], [1, 0]], &[DVec3::Z; 2]).unwrap_err(),
            CellError::Parallel(0, 1)
        );
        assert_eq!(
            cells(&p, &[[0, 1]], &[DVec3::Z, DVec3::ZERO]).unwrap_err(),
            CellError::BadNormal(1)
        );
    }
}
