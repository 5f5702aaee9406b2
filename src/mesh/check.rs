//! `TriMesh::check_manifold`: topology counts (V, E, F, boundary loops, components, genus) and
//! every problem that stops a mesh from being a manifold surface.

use std::collections::BTreeMap;

use rayon::prelude::*;
use std::fmt;

use super::TriMesh;

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum MeshProblem {
    NonFiniteVertex {
        vertex: u32,
    },
    IndexOutOfRange {
        triangle: u32,
        index: u32,
        vertices: usize,
    },
    RepeatedCorner {
        triangle: u32,
    },
    /// An edge shared by more than two triangles.
    NonManifoldEdge {
        a: u32,
        b: u32,
        triangles: usize,
    },
    /// Two triangles that share an edge run it the same way: their normals disagree.
    FlippedNeighbours {
        a: u32,
        b: u32,
    },
    /// A vertex where separate fans of triangles meet at one point (two bodies touching at a
    /// corner, a cone pinched to a point): the surface is not a manifold there.
    PinchedVertex {
        vertex: u32,
        /// Fans of triangles (groups joined across edges at the vertex) that meet there.
        fans: usize,
        at: [f64; 3],
    },
}

impl fmt::Display for MeshProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            MeshProblem::NonFiniteVertex { vertex } => {
                write!(f, "vertex {vertex}: coordinate is not finite")
            }
            MeshProblem::IndexOutOfRange {
                triangle,
                index,
                vertices,
            } => write!(
                f,
                "triangle {triangle}: vertex index {index} out of range ({vertices} vertices)"
            ),
            MeshProblem::RepeatedCorner { triangle } => {
                write!(f, "triangle {triangle}: uses one vertex twice")
            }
            MeshProblem::NonManifoldEdge { a, b, triangles } => {
                write!(f, "edge {a}-{b}: shared by {triangles} triangles")
            }
            MeshProblem::FlippedNeighbours { a, b } => write!(
                f,
                "edge {a}-{b}: its two triangles are oriented inconsistently"
            ),
            MeshProblem::PinchedVertex { vertex, fans, at } => write!(
                f,
                "vertex {vertex} at ({:.4}, {:.4}, {:.4}): {fans} fans of triangles meet only \
                 at this point (pinched: not a manifold)",
                at[0], at[1], at[2]
            ),
        }
    }
}

/// Topology of a mesh. Counts use only vertices that some triangle references.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Topology {
    pub vertices: usize,
    pub edges: usize,
    pub faces: usize,
    pub boundary_edges: usize,
    pub boundary_loops: usize,
    pub components: usize,
    /// V − E + F.
    pub euler: i64,
    /// Every edge has exactly two triangles, consistently oriented (bodies touching at a
    /// pinched vertex included).
    pub closed: bool,
    /// Sum over components of (2 − χ − b) / 2; `None` unless the mesh is an oriented manifold.
    pub genus: Option<i64>,
    /// Area of every triangle with three distinct, in-range corners, whatever other problems
    /// the mesh has.
    pub area: f64,
    /// Enclosed volume in mm³, for a closed oriented manifold.
    pub volume: Option<f64>,
    /// The signed volume of the same triangles as `area`, about the origin: the enclosed volume
    /// when every body is closed and outward-oriented (touching bodies included), meaningless
    /// for an open mesh.
    pub signed_volume: f64,
    pub problems: Vec<MeshProblem>,
}

impl Topology {
    pub fn is_manifold(&self) -> bool {
        self.problems.is_empty()
    }
}

impl TriMesh {
    /// Counts V, E, F, boundary loops and components, and finds every problem. Genus and volume
    /// are given only when there is no problem.
    pub fn check_manifold(&self) -> Topology {
        let nv = self.positions.len();
        let mut problems = Vec::new();
        for (i, p) in self.positions.iter().enumerate() {
            if !p.is_finite() {
                problems.push(MeshProblem::NonFiniteVertex { vertex: i as u32 });
            }
        }
        let mut good = Vec::with_capacity(self.triangles.len());
        for (k, t) in self.triangles.iter().enumerate() {
            let triangle = k as u32;
            if let Some(&index) = t.iter().find(|&&i| i as usize >= nv) {
                problems.push(MeshProblem::IndexOutOfRange {
                    triangle,
                    index,
                    vertices: nv,
                });
            } else if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                problems.push(MeshProblem::RepeatedCorner { triangle });
            } else {
                good.push(*t);
            }
        }
        // Every half-edge as (low end, high end, direction), sorted: the uses of an undirected
        // edge sit side by side, forward (low → high) ones first. Vertex indices fit in 31 bits
        // (a mesh with 2³¹ vertices would not fit in memory here).
        let mut half: Vec<u64> = good
            .par_iter()
            .flat_map_iter(|t| {
                (0..3).map(move |j| {
                    let (a, b) = (t[j] as u64, t[(j + 1) % 3] as u64);
                    (a.min(b) << 32) | (a.max(b) << 1) | u64::from(a > b)
                })
            })
            .collect();
        half.par_sort_unstable();
        let mut parent: Vec<u32> = (0..nv as u32).collect();
        let mut used = vec![false; nv];
        for t in &good {
            for &v in t {
                used[v as usize] = true;
            }
            union(&mut parent, t[0], t[1]);
            union(&mut parent, t[0], t[2]);
        }
        let mut boundary_parent: Vec<u32> = (0..nv as u32).collect();
        let mut boundary_edges = 0;
        let mut boundary_vertex = vec![false; nv];
        let mut edge_count = 0usize;
        let mut s = 0;
        while s < half.len() {
            let key = half[s] >> 1;
            let mut e = s;
            let mut forward = 0u32;
            while e < half.len() && half[e] >> 1 == key {
                forward += u32::from(half[e] & 1 == 0);
                e += 1;
            }
            let n = (e - s) as u32;
            let (a, b) = ((key >> 31) as u32, (key & 0x7fff_ffff) as u32);
            edge_count += 1;
            if n == 1 {
                boundary_edges += 1;
                boundary_vertex[a as usize] = true;
                boundary_vertex[b as usize] = true;
                union(&mut boundary_parent, a, b);
            } else if n > 2 {
                problems.push(MeshProblem::NonManifoldEdge {
                    a,
                    b,
                    triangles: n as usize,
                });
            } else if forward != 1 {
                problems.push(MeshProblem::FlippedNeighbours { a, b });
            }
            s = e;
        }
        // Every edge with two triangles, consistently turned: closed, with a volume, even where
        // bodies touch at a point; a genus only for a manifold, pinches included.
        let edge_manifold = problems.is_empty();
        problems.extend(pinched(&good, nv).into_iter().map(|(vertex, fans)| {
            MeshProblem::PinchedVertex {
                vertex,
                fans,
                at: self.positions[vertex as usize].to_array(),
            }
        }));
        let vertices = used.iter().filter(|&&u| u).count();
        // Per component root: (V − E + F, boundary loops).
        let mut comp_euler: BTreeMap<u32, (i64, i64)> = BTreeMap::new();
        let mut chi = vec![0i64; nv];
        for v in 0..nv as u32 {
            if used[v as usize] {
                chi[find(&mut parent, v) as usize] += 1;
            }
        }
        let mut s = 0;
        while s < half.len() {
            let key = half[s] >> 1;
            chi[find(&mut parent, (key >> 31) as u32) as usize] -= 1;
            while s < half.len() && half[s] >> 1 == key {
                s += 1;
            }
        }
        for t in &good {
            chi[find(&mut parent, t[0]) as usize] += 1;
        }
        for v in 0..nv as u32 {
            if used[v as usize] && find(&mut parent, v) == v {
                comp_euler.insert(v, (chi[v as usize], 0));
            }
        }
        let mut boundary_loops = 0;
        for v in 0..nv as u32 {
            if boundary_vertex[v as usize] && find(&mut boundary_parent, v) == v {
                boundary_loops += 1;
                comp_euler.entry(find(&mut parent, v)).or_default().1 += 1;
            }
        }
        let euler = vertices as i64 - edge_count as i64 + good.len() as i64;
        let manifold = problems.is_empty();
        let closed = edge_manifold && boundary_edges == 0 && !good.is_empty();
        let genus = manifold.then(|| {
            comp_euler
                .values()
                .map(|&(chi, loops)| (2 - chi - loops) / 2)
                .sum()
        });
        Topology {
            vertices,
            edges: edge_count,
            faces: good.len(),
            boundary_edges,
            boundary_loops,
            components: comp_euler.len(),
            euler,
            closed,
            genus,
            area: good
                .iter()
                .map(|t| {
                    let [a, b, c] = self.corners(t);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum(),
            volume: closed.then(|| self.signed_volume()),
            signed_volume: good
                .iter()
                .map(|t| {
                    let [a, b, c] = self.corners(t);
                    a.dot(b.cross(c))
                })
                .sum::<f64>()
                / 6.0,
            problems,
        }
    }
}

/// Vertices where the triangles around them fall into more than one fan (groups of triangles
/// joined across the edges that meet at the vertex), with the number of fans, in vertex order.
/// Each vertex's triangles are grouped on their own, in parallel: O(F log d) for degree d.
fn pinched(triangles: &[[u32; 3]], nv: usize) -> Vec<(u32, usize)> {
    // The triangles at each vertex (CSR).
    let mut start = vec![0u32; nv + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut at = vec![0u32; 3 * triangles.len()];
    for (k, t) in triangles.iter().enumerate() {
        for &v in t {
            at[fill[v as usize] as usize] = k as u32;
            fill[v as usize] += 1;
        }
    }
    drop(fill);
    (0..nv as u32)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(ends, parent): &mut (Vec<(u32, u32)>, Vec<u32>), v| {
                let around = &at[start[v as usize] as usize..start[v as usize + 1] as usize];
                if around.len() < 2 {
                    return None;
                }
                // Each triangle's two other corners: triangles sharing one share an edge at v.
                ends.clear();
                for (i, &k) in around.iter().enumerate() {
                    let t = triangles[k as usize];
                    ends.extend(t.iter().filter(|&&w| w != v).map(|&w| (w, i as u32)));
                }
                ends.sort_unstable();
                parent.clear();
                parent.extend(0..around.len() as u32);
                for pair in ends.windows(2) {
                    if pair[0].0 == pair[1].0 {
                        union(parent, pair[0].1, pair[1].1);
                    }
                }
                let fans = (0..around.len() as u32)
                    .filter(|&i| find(parent, i) == i)
                    .count();
                (fans > 1).then_some((v, fans))
            },
        )
        .flatten()
        .collect()
}

/// Union-find over vertex indices: the root of `v`, halving the path on the way.
pub(crate) fn find(parent: &mut [u32], mut v: u32) -> u32 {
    while parent[v as usize] != v {
        parent[v as usize] = parent[parent[v as usize] as usize];
        v = parent[v as usize];
    }
    v
}

/// Union-find: joins the sets of `a` and `b` under the smaller root.
pub(crate) fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn tetra() -> TriMesh {
        TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
            colors: None,
        }
    }

    #[test]
    fn tetrahedron_is_a_closed_sphere() {
        let t = tetra().check_manifold();
        assert!(t.is_manifold(), "{:?}", t.problems);
        assert_eq!((t.vertices, t.edges, t.faces), (4, 6, 4));
        assert_eq!(t.euler, 2);
        assert_eq!(t.genus, Some(0));
        assert!(t.closed);
        assert!((t.volume.unwrap_or(0.0) - 1.0 / 6.0).abs() < 1e-12);
    }

    /// Two tetrahedra sharing one vertex (χ = 3): every edge has two triangles (closed, with a
    /// volume), but the shared vertex is pinched, so no genus is claimed.
    #[test]
    fn two_tetrahedra_touching_at_a_corner_are_pinched() {
        let mut m = tetra();
        // The first one mirrored through the origin (vertex 0): 4, 5, 6 at −X, −Y, −Z.
        m.positions.extend([-DVec3::X, -DVec3::Y, -DVec3::Z]);
        m.triangles
            .extend([[0, 4, 5], [0, 6, 4], [4, 6, 5], [0, 5, 6]]);
        let t = m.check_manifold();
        assert_eq!(t.euler, 3);
        assert_eq!(t.boundary_edges, 0);
        assert_eq!(
            t.problems,
            vec![MeshProblem::PinchedVertex {
                vertex: 0,
                fans: 2,
                at: [0.0; 3]
            }]
        );
        assert_eq!(t.genus, None);
        assert!(t.closed, "every edge has its two triangles");
        assert!((t.volume.unwrap_or(0.0) - 2.0 / 6.0).abs() < 1e-12);
        // One tetrahedron alone has no pinch, and a bow-tie of two triangles does.
        assert!(tetra().check_manifold().problems.is_empty());
        let bowtie = TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y],
            triangles: vec![[0, 1, 2], [0, 3, 4]],
            colors: None,
        };
        let t = bowtie.check_manifold();
        assert!(matches!(
            t.problems[..],
            [MeshProblem::PinchedVertex {
                vertex: 0,
                fans: 2,
                ..
            }]
        ));
    }

    #[test]
    fn open_disc_has_one_boundary_loop() {
        let mut m = tetra();
        m.triangles.pop();
        let t = m.check_manifold();
        assert!(!t.closed);
        assert_eq!(t.boundary_loops, 1);
        assert_eq!(t.boundary_edges, 3);
        assert_eq!(t.genus, Some(0));
        assert_eq!(t.volume, None);
    }

    #[test]
    fn flipped_face_is_found() {
        let mut m = tetra();
        m.triangles[0] = [0, 1, 2];
        let t = m.check_manifold();
        assert_eq!(t.problems.len(), 3);
        assert!(t
            .problems
            .iter()
            .all(|p| matches!(p, MeshProblem::FlippedNeighbours { .. })));
        assert_eq!(t.genus, None);
    }
}
