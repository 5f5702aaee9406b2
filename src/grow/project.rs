//! Projecting a network onto a surface mesh along a direction (Hanafin et al. Figs. 5 and 9:
//! the fitted tree laid on the façade surface).
//!
//! Each node moves along the line through it in the direction to the first point of the mesh
//! that line meets (travelling along the direction), and stores the surface normal there.
//! Members are split where the surface bends: a member whose projected midpoint lies farther
//! than `sag` from the chord between its projected ends is halved, recursively, so every
//! chord stays within `sag` of the surface at its midpoints (a flat surface splits nothing).
//!
//! Lines are cast through an rstar tree of the triangles' boxes in the plane across the
//! direction: a query is a point location, then an exact barycentric test.

use glam::{DVec2, DVec3};
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::RTree;

use crate::mesh::closest::{Closest, SurfaceIndex};
use crate::mesh::TriMesh;
use crate::network::{Edge, Network, Node};

/// Halvings of one member at most (2^12 pieces).
const MAX_SPLITS: u32 = 12;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectOptions {
    /// Direction of projection (any length but zero).
    pub direction: DVec3,
    /// Largest distance, mm, of a member's projected midpoint from its chord. Default: 1e-3 of
    /// the mesh's bounding-box diagonal.
    pub sag: Option<f64>,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ProjectReport {
    pub direction: [f64; 3],
    pub sag: f64,
    /// Nodes added where members were split to follow the surface.
    pub added_nodes: usize,
    /// The largest distance a node moved, mm.
    pub max_move: f64,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProjectError {
    #[error("direction= must be a non-zero vector, got {0}")]
    Direction(DVec3),
    #[error("onto=: the mesh has no triangles")]
    EmptyMesh,
    #[error("sag= must be a positive distance in mm, got {0}")]
    Sag(f64),
    #[error(
        "onto=: {count} node(s) miss the surface along the direction, the first at \
         ({x:.3}, {y:.3}, {z:.3}): the surface must lie behind the whole structure"
    )]
    Miss {
        count: usize,
        x: f64,
        y: f64,
        z: f64,
    },
}

type FlatBox = GeomWithData<Rectangle<[f64; 2]>, u32>;

/// Casts lines of one direction onto a mesh.
struct Caster<'a> {
    mesh: &'a TriMesh,
    d: DVec3,
    e1: DVec3,
    e2: DVec3,
    tree: RTree<FlatBox>,
    surface: SurfaceIndex<'a>,
}

impl<'a> Caster<'a> {
    fn new(mesh: &'a TriMesh, d: DVec3) -> Self {
        let e1 = d.any_orthonormal_vector();
        let e2 = d.cross(e1);
        let flat = |p: DVec3| DVec2::new(p.dot(e1), p.dot(e2));
        let tree = RTree::bulk_load(
            mesh.triangles
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    let [a, b, c] = mesh.corners(t).map(flat);
                    FlatBox::new(
                        Rectangle::from_corners(
                            a.min(b).min(c).to_array(),
                            a.max(b).max(c).to_array(),
                        ),
                        i as u32,
                    )
                })
                .collect(),
        );
        Caster {
            mesh,
            d,
            e1,
            e2,
            tree,
            surface: SurfaceIndex::new(mesh),
        }
    }

    /// The first point of the mesh on the line through `p` along the direction, and the
    /// surface normal there.
    fn cast(&self, p: DVec3) -> Option<(DVec3, DVec3)> {
        let q = DVec2::new(p.dot(self.e1), p.dot(self.e2));
        let mut best: Option<(f64, Closest)> = None;
        for cand in self.tree.locate_all_at_point(&q.to_array()) {
            let t = cand.data;
            let corners = self.mesh.corners(&self.mesh.triangles[t as usize]);
            let [a, b, c] = corners.map(|v| DVec2::new(v.dot(self.e1), v.dot(self.e2)));
            let area = (b - a).perp_dot(c - a);
            if area.abs() <= f64::EPSILON * (b - a).length() * (c - a).length() {
                continue; // edge-on to the direction
            }
            let wa = (b - q).perp_dot(c - q) / area;
            let wb = (c - q).perp_dot(a - q) / area;
            let wc = 1.0 - wa - wb;
            let slack = -1e-12;
            if wa < slack || wb < slack || wc < slack {
                continue;
            }
            let hit = corners[0] * wa + corners[1] * wb + corners[2] * wc;
            let along = hit.dot(self.d);
            if best.as_ref().is_none_or(|(s, _)| along < *s) {
                best = Some((
                    along,
                    Closest {
                        point: hit,
                        distance: 0.0,
                        triangle: t,
                        bary: [wa, wb, wc],
                    },
                ));
            }
        }
        best.map(|(_, c)| (c.point, self.surface.normal(&c)))
    }
}

/// Projects `net` onto `mesh`, splitting members where the surface bends.
pub fn project(
    net: &Network,
    mesh: &TriMesh,
    opts: &ProjectOptions,
) -> Result<(Network, ProjectReport), ProjectError> {
    let d = opts
        .direction
        .try_normalize()
        .filter(|d| d.is_finite())
        .ok_or(ProjectError::Direction(opts.direction))?;
    if mesh.triangles.is_empty() {
        return Err(ProjectError::EmptyMesh);
    }
    let sag = opts.sag.unwrap_or(1e-3 * mesh.bbox().diagonal());
    if !(sag.is_finite() && sag > 0.0) {
        return Err(ProjectError::Sag(sag));
    }
    let caster = Caster::new(mesh, d);
    let mut misses: Vec<DVec3> = Vec::new();
    let mut cast = |p: DVec3| -> (DVec3, Option<DVec3>) {
        match caster.cast(p) {
            Some((q, n)) => (q, Some(n)),
            None => {
                misses.push(p);
                (p, None)
            }
        }
    };
    let mut out = Network {
        meta: net.meta.clone(),
        ..Default::default()
    };
    let mut max_move: f64 = 0.0;
    for n in &net.nodes {
        let (q, normal) = cast(n.p);
        max_move = max_move.max(q.distance(n.p));
        out.nodes.push(Node { p: q, normal, ..*n });
    }
    let mut added = 0;
    for e in &net.edges {
        // Pieces between plane points, each with its projected end; split until flat enough.
        let (pa, pb) = (net.nodes[e.a as usize].p, net.nodes[e.b as usize].p);
        let mut stack = vec![(pa, e.a, pb, e.b, 0u32)];
        while let Some((a, ka, b, kb, depth)) = stack.pop() {
            let (qa, qb) = (out.nodes[ka as usize].p, out.nodes[kb as usize].p);
            let m = 0.5 * (a + b);
            let (qm, normal) = cast(m);
            if depth < MAX_SPLITS && qm.distance(0.5 * (qa + qb)) > sag {
                out.nodes.push(Node {
                    p: qm,
                    normal,
                    radius: e.radius,
                });
                let km = out.nodes.len() as u32 - 1;
                added += 1;
                max_move = max_move.max(qm.distance(m));
                // Second half pushed first so pieces come out in order from a.
                stack.push((m, km, b, kb, depth + 1));
                stack.push((a, ka, m, km, depth + 1));
            } else {
                out.edges.push(Edge {
                    a: ka,
                    b: kb,
                    radius: e.radius,
                });
            }
        }
    }
    if let Some(first) = misses.first() {
        return Err(ProjectError::Miss {
            count: misses.len(),
            x: first.x,
            y: first.y,
            z: first.z,
        });
    }
    Ok((
        out,
        ProjectReport {
            direction: d.to_array(),
            sag,
            added_nodes: added,
            max_move,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cylinder patch z = f(x) bent about the y axis: radius 10, x in −5..5, y in 0..10.
    fn barrel() -> TriMesh {
        let (nx, ny) = (40, 10);
        TriMesh::grid(nx, ny, |i, j| {
            let x = -5.0 + 10.0 * i as f64 / nx as f64;
            let y = 10.0 * j as f64 / ny as f64;
            DVec3::new(x, y, 20.0 + (100.0 - x * x).sqrt())
        })
    }

    #[test]
    fn members_follow_a_bent_surface() -> Result<(), ProjectError> {
        let mut net = Network::default();
        net.nodes.push(Node::at(DVec3::new(-4.0, 5.0, 0.0)));
        net.nodes.push(Node::at(DVec3::new(4.0, 5.0, 0.0)));
        net.edges.push(Edge::new(0, 1));
        let mesh = barrel();
        let opts = ProjectOptions {
            direction: DVec3::Z,
            sag: Some(0.01),
        };
        let (out, rep) = project(&net, &mesh, &opts)?;
        assert!(rep.added_nodes > 4, "{}", rep.added_nodes);
        assert_eq!(out.edges.len(), rep.added_nodes + 1);
        let index = SurfaceIndex::new(&mesh);
        for n in &out.nodes {
            let c = index.closest(n.p).expect("a mesh");
            assert!(c.distance < 1e-9, "on the surface: {}", c.distance);
            let normal = n.normal.expect("projected nodes carry normals");
            assert!(normal.z.abs() > 0.5);
        }
        // A flat surface splits nothing.
        let mut flat = barrel();
        for p in &mut flat.positions {
            p.z = 3.0;
        }
        let (out, rep) = project(&net, &flat, &opts)?;
        assert_eq!((rep.added_nodes, out.edges.len()), (0, 1));
        assert_eq!(out.nodes[0].p, DVec3::new(-4.0, 5.0, 3.0));
        Ok(())
    }

    #[test]
    fn a_node_that_misses_is_an_error() {
        let mut net = Network::default();
        net.nodes.push(Node::at(DVec3::new(50.0, 5.0, 0.0)));
        let r = project(
            &net,
            &barrel(),
            &ProjectOptions {
                direction: DVec3::Z,
                sag: None,
            },
        );
        assert!(
            matches!(r, Err(ProjectError::Miss { count: 1, .. })),
            "{r:?}"
        );
        assert!(matches!(
            project(
                &net,
                &barrel(),
                &ProjectOptions {
                    direction: DVec3::ZERO,
                    sag: None
                }
            ),
            Err(ProjectError::Direction(_))
        ));
    }
}
