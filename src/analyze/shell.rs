//! The panels themselves as flat shells, for networks whose plates are too deep for beams
//! (Calyx's panels are about as deep as they are long). Each edge's quad from the node axes is
//! meshed `per_height` elements up and square-ish along; panels meeting at a node share the
//! nodes of its axis line, so they are welded along it, as built.
//!
//! The element is a flat four-node shell with six freedoms per node: membrane by Wilson and
//! Taylor's incompatible modes (QM6: the bilinear quad plus two bubble modes per direction,
//! condensed, with Taylor's constant-Jacobian correction so that it passes the patch test; it
//! bends in its plane without shear locking), Reissner–Mindlin bending with Bathe and
//! Dvorkin's MITC4 transverse shear (assumed covariant shear strains tied at the edge
//! midpoints; no shear locking in thin plates), and a weak spring on the rotation about the
//! normal that resists only differences between the element's corners (zero for rigid motion).
//!
//! What the frame model needs back comes out the same way: per network node the displacement
//! of the mesh node at mid-height of its axis (where the frame has its node), per member the
//! resultant of the forces its panel's elements take at the nodes of each end's axis line,
//! about that end's mid-height point, in the member's local axes: the end forces of a beam.
//! Supports hold a fixed node's whole axis line (six freedoms at every node of it) and a pinned
//! node's mid-height point (translations), loads on a node act at its mid-height point, and a
//! member's uniform load is spread over its panel by area.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;
use glam::{DMat3, DVec3};
use nalgebra::{Matrix2, Matrix3, SMatrix, SVector};
use rayon::prelude::*;

use super::frame::{factor, local_frame, CaseResult, FrameError, LoadCase, Model, Support};

/// An element's stiffness over its 24 freedoms (u, v, w, θx, θy, θz at each corner in turn).
pub type Stiffness = SMatrix<f64, 24, 24>;

/// The most elements a mesh may have: each costs about 12 kB while the stiffness is assembled.
pub const MAX_ELEMENTS: usize = 100_000;

/// Material and thickness of one element.
#[derive(Clone, Copy, Debug)]
pub struct Plate {
    pub e: f64,
    pub nu: f64,
    /// In its plane and in shear, mm.
    pub thickness: f64,
    /// The thickness whose t³/12 is its bending stiffness: the thickness, or for a seam's two
    /// plies bending each on its own (Σ tᵢ³)^(1/3), mm.
    pub bending: f64,
}

/// The panels as a shell mesh.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub nodes: Vec<DVec3>,
    /// Corners counter-clockwise seen from the panel's side, and the member it belongs to.
    pub elements: Vec<([usize; 4], usize)>,
    /// Per network node: the mesh nodes up its axis line, bottom to top.
    pub axis_lines: Vec<Vec<usize>>,
}

/// The mesh of the panels of `model`: node i's axis runs from `base[i]` along `axis[i]` for
/// `height[i]`; `per_height` elements up each panel (even, so that a node sits at mid-height).
pub fn mesh(
    model: &Model,
    base: &[DVec3],
    axis: &[DVec3],
    height: &[f64],
    per_height: usize,
) -> Mesh {
    let rows = per_height + 1;
    let mut nodes = Vec::new();
    let axis_lines: Vec<Vec<usize>> = (0..model.nodes.len())
        .map(|i| {
            (0..rows)
                .map(|j| {
                    nodes.push(base[i] + axis[i] * (height[i] * j as f64 / per_height as f64));
                    nodes.len() - 1
                })
                .collect()
        })
        .collect();
    let mut elements = Vec::new();
    for (k, m) in model.members.iter().enumerate() {
        let (a, b) = (m.a, m.b);
        let along = columns(base, height, per_height, a, b);
        // Columns of node numbers: the axis lines at the ends, new nodes between.
        let mut columns = vec![axis_lines[a].clone()];
        for c in 1..along {
            let u = c as f64 / along as f64;
            columns.push(
                (0..rows)
                    .map(|j| {
                        let v = j as f64 / per_height as f64;
                        let pa = base[a] + axis[a] * (height[a] * v);
                        let pb = base[b] + axis[b] * (height[b] * v);
                        nodes.push(pa.lerp(pb, u));
                        nodes.len() - 1
                    })
                    .collect(),
            );
        }
        columns.push(axis_lines[b].clone());
        for c in 0..along {
            for j in 0..per_height {
                let q = [
                    columns[c][j],
                    columns[c + 1][j],
                    columns[c + 1][j + 1],
                    columns[c][j + 1],
                ];
                elements.push((q, k));
            }
        }
    }
    Mesh {
        nodes,
        elements,
        axis_lines,
    }
}

/// Elements along the panel of edge (a, b): as many as make them square-ish, at least one.
fn columns(base: &[DVec3], height: &[f64], per_height: usize, a: usize, b: usize) -> usize {
    let cell = 0.5 * (height[a] + height[b]) / per_height as f64;
    // Saturates for absurd proportions, which `element_count` then refuses.
    ((base[a].distance(base[b]) / cell).round() as usize).max(1)
}

/// How many elements `mesh` would make, without making them.
pub fn element_count(model: &Model, base: &[DVec3], height: &[f64], per_height: usize) -> usize {
    model.members.iter().fold(0usize, |n, m| {
        n.saturating_add(columns(base, height, per_height, m.a, m.b).saturating_mul(per_height))
    })
}

/// Gauss points of the 2 × 2 rule.
const GAUSS: f64 = 0.577_350_269_189_625_8;
const CORNERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];

/// Shape functions and their derivatives in ξ and η at (ξ, η).
fn shape(xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let mut n = [0.0; 4];
    let mut dxi = [0.0; 4];
    let mut deta = [0.0; 4];
    for (i, &(a, b)) in CORNERS.iter().enumerate() {
        n[i] = 0.25 * (1.0 + a * xi) * (1.0 + b * eta);
        dxi[i] = 0.25 * a * (1.0 + b * eta);
        deta[i] = 0.25 * b * (1.0 + a * xi);
    }
    (n, dxi, deta)
}

/// The Jacobian [[x,ξ, y,ξ], [x,η, y,η]] at (ξ, η).
fn jacobian(xy: &[[f64; 2]; 4], dxi: &[f64; 4], deta: &[f64; 4]) -> Matrix2<f64> {
    let mut j = Matrix2::zeros();
    for i in 0..4 {
        j[(0, 0)] += dxi[i] * xy[i][0];
        j[(0, 1)] += dxi[i] * xy[i][1];
        j[(1, 0)] += deta[i] * xy[i][0];
        j[(1, 1)] += deta[i] * xy[i][1];
    }
    j
}

/// J⁻¹ and det J (J⁻¹ not finite where the element is folded flat, which the factorisation
/// then refuses).
fn inverse_and_determinant(j: Matrix2<f64>) -> (Matrix2<f64>, f64) {
    let inverse = j
        .try_inverse()
        .unwrap_or_else(|| Matrix2::from_element(f64::NAN));
    (inverse, j.determinant())
}

/// Plane-stress elasticity times a factor.
fn plane_stress(e: f64, nu: f64, factor: f64) -> Matrix3<f64> {
    let c = factor * e / (1.0 - nu * nu);
    Matrix3::new(
        c,
        c * nu,
        0.0,
        c * nu,
        c,
        0.0,
        0.0,
        0.0,
        c * 0.5 * (1.0 - nu),
    )
}

/// The element's local frame: rows e1, e2 (in its plane) and n, and its corners' local
/// coordinates about their centroid.
pub fn element_frame(x: &[DVec3; 4]) -> (DMat3, [[f64; 2]; 4]) {
    let n = (x[2] - x[0]).cross(x[3] - x[1]).normalize();
    let e1 = (x[1] - x[0]) + (x[2] - x[3]);
    let e1 = (e1 - n * e1.dot(n)).normalize();
    let e2 = n.cross(e1);
    let c = (x[0] + x[1] + x[2] + x[3]) * 0.25;
    let mut xy = [[0.0; 2]; 4];
    for i in 0..4 {
        xy[i] = [(x[i] - c).dot(e1), (x[i] - c).dot(e2)];
    }
    (DMat3::from_cols(e1, e2, n).transpose(), xy)
}

/// Local stiffness (freedoms per corner: u, v, w, θx, θy, θz in the element's axes).
pub fn local_stiffness(xy: &[[f64; 2]; 4], p: Plate) -> Stiffness {
    let t = p.thickness;
    let g = p.e / (2.0 * (1.0 + p.nu));
    let dm = plane_stress(p.e, p.nu, t);
    let db = plane_stress(p.e, p.nu, p.bending.powi(3) / 12.0);
    let ds = Matrix2::from_diagonal_element(5.0 / 6.0 * g * t);
    // Membrane with incompatible modes: compatible (c) and bubble (i) parts, condensed.
    let (_, dxi0, deta0) = shape(0.0, 0.0);
    let (j0inv, det0) = inverse_and_determinant(jacobian(xy, &dxi0, &deta0));
    let mut kcc = SMatrix::<f64, 8, 8>::zeros();
    let mut kci = SMatrix::<f64, 8, 4>::zeros();
    let mut kii = SMatrix::<f64, 4, 4>::zeros();
    // Bending and transverse shear over w, θx, θy per corner.
    let mut kb = SMatrix::<f64, 12, 12>::zeros();
    let points = [
        (-GAUSS, -GAUSS),
        (GAUSS, -GAUSS),
        (GAUSS, GAUSS),
        (-GAUSS, GAUSS),
    ];
    for &(xi, eta) in &points {
        let (_, dxi, deta) = shape(xi, eta);
        let (jinv, det) = inverse_and_determinant(jacobian(xy, &dxi, &deta));
        let dx: [f64; 4] = std::array::from_fn(|i| jinv[(0, 0)] * dxi[i] + jinv[(0, 1)] * deta[i]);
        let dy: [f64; 4] = std::array::from_fn(|i| jinv[(1, 0)] * dxi[i] + jinv[(1, 1)] * deta[i]);
        let mut bc = SMatrix::<f64, 3, 8>::zeros();
        for i in 0..4 {
            bc[(0, 2 * i)] = dx[i];
            bc[(1, 2 * i + 1)] = dy[i];
            bc[(2, 2 * i)] = dy[i];
            bc[(2, 2 * i + 1)] = dx[i];
        }
        // Bubbles 1 − ξ² and 1 − η², by the centre's Jacobian scaled by det J0 / det J.
        let s = det0 / det;
        let (p1, p2) = (-2.0 * xi, -2.0 * eta);
        let bx = [s * j0inv[(0, 0)] * p1, s * j0inv[(0, 1)] * p2];
        let by = [s * j0inv[(1, 0)] * p1, s * j0inv[(1, 1)] * p2];
        #[rustfmt::skip]
        let bi = SMatrix::<f64, 3, 4>::new(
            bx[0], bx[1], 0.0, 0.0,
            0.0, 0.0, by[0], by[1],
            by[0], by[1], bx[0], bx[1],
        );
        let dm_bc = dm * bc;
        kcc += det * bc.transpose() * dm_bc;
        kci += det * (dm_bc.transpose() * bi);
        kii += det * bi.transpose() * (dm * bi);
        // Bending: freedoms w, θx, θy; βx = θy, βy = −θx.
        let mut bb = SMatrix::<f64, 3, 12>::zeros();
        for i in 0..4 {
            bb[(0, 3 * i + 2)] = dx[i];
            bb[(1, 3 * i + 1)] = -dy[i];
            bb[(2, 3 * i + 2)] = dy[i];
            bb[(2, 3 * i + 1)] = -dx[i];
        }
        kb += det * bb.transpose() * (db * bb);
        // MITC4 shear: covariant strains tied at the edge midpoints, to Cartesian by J⁻¹.
        let tie_xi_a = covariant_shear(xy, 0.0, -1.0, 0);
        let tie_xi_c = covariant_shear(xy, 0.0, 1.0, 0);
        let tie_eta_b = covariant_shear(xy, -1.0, 0.0, 1);
        let tie_eta_d = covariant_shear(xy, 1.0, 0.0, 1);
        let mut cov = SMatrix::<f64, 2, 12>::zeros();
        for q in 0..12 {
            cov[(0, q)] = 0.5 * (1.0 - eta) * tie_xi_a[q] + 0.5 * (1.0 + eta) * tie_xi_c[q];
            cov[(1, q)] = 0.5 * (1.0 - xi) * tie_eta_b[q] + 0.5 * (1.0 + xi) * tie_eta_d[q];
        }
        let bs = jinv * cov;
        kb += det * bs.transpose() * (ds * bs);
    }
    // Condense the bubbles: K = Kcc − Kci Kii⁻¹ Kic (Kii is positive definite for an element
    // that is not folded; LU where rounding says otherwise).
    let kic = kci.transpose();
    let x = kii
        .cholesky()
        .map(|c| c.solve(&kic))
        .or_else(|| kii.lu().solve(&kic))
        .unwrap_or_else(|| SMatrix::from_element(f64::NAN));
    let km = kcc - kci * x;
    let mut k = Stiffness::zeros();
    let membrane = |q: usize| 6 * (q / 2) + q % 2;
    let bending = |q: usize| 6 * (q / 3) + 2 + q % 3;
    for p in 0..8 {
        for q in 0..8 {
            k[(membrane(p), membrane(q))] += km[(p, q)];
        }
    }
    for p in 0..12 {
        for q in 0..12 {
            k[(bending(p), bending(q))] += kb[(p, q)];
        }
    }
    // Drilling: a weak spring against differences between the corners' θz.
    let kd = 1e-5 * p.e * t * t * t;
    for i in 0..4 {
        for j in 0..4 {
            let v = if i == j { 0.75 } else { -0.25 };
            k[(6 * i + 5, 6 * j + 5)] += kd * v;
        }
    }
    k
}

/// The covariant transverse shear strain along ξ (`dir` 0) or η (1) at (ξ, η), over the
/// bending freedoms (w, θx, θy per corner): w,ξ + x,ξ βx + y,ξ βy, with βx = θy, βy = −θx.
fn covariant_shear(xy: &[[f64; 2]; 4], xi: f64, eta: f64, dir: usize) -> [f64; 12] {
    let (n, dxi, deta) = shape(xi, eta);
    let dn = if dir == 0 { dxi } else { deta };
    let (mut xd, mut yd) = (0.0, 0.0);
    for i in 0..4 {
        xd += dn[i] * xy[i][0];
        yd += dn[i] * xy[i][1];
    }
    let mut row = [0.0; 12];
    for i in 0..4 {
        row[3 * i] = dn[i];
        row[3 * i + 1] = -yd * n[i];
        row[3 * i + 2] = xd * n[i];
    }
    row
}

/// ∫ N_i dA for each corner (2 × 2 Gauss, exact for the bilinear quad).
fn corner_areas(xy: &[[f64; 2]; 4]) -> [f64; 4] {
    let mut out = [0.0; 4];
    for (xi, eta) in [
        (-GAUSS, -GAUSS),
        (GAUSS, -GAUSS),
        (GAUSS, GAUSS),
        (-GAUSS, GAUSS),
    ] {
        let (n, dxi, deta) = shape(xi, eta);
        let det = jacobian(xy, &dxi, &deta).determinant();
        for i in 0..4 {
            out[i] += n[i] * det;
        }
    }
    out
}

/// The element stiffness in global axes.
fn global_stiffness(x: &[DVec3; 4], p: Plate) -> Stiffness {
    let (r, xy) = element_frame(x);
    let mut kl = local_stiffness(&xy, p);
    // A panel is planar only to planarize's tolerance: each corner sits h off the element's
    // plane. The flat element acts at the corners projected onto it, joined to the real ones
    // by rigid offsets (u_p = u − h θy, v_p = v + h θx), so that it stays in balance about
    // the real corners: K = Wᵀ K W.
    let centre = (x[0] + x[1] + x[2] + x[3]) * 0.25;
    let offsets: [f64; 4] = std::array::from_fn(|c| (x[c] - centre).dot(r.row(2)));
    if offsets.iter().any(|&h| h != 0.0) {
        // K W: column 6c+4 gains −h K[:, 6c], column 6c+3 gains h K[:, 6c+1].
        for (c, &h) in offsets.iter().enumerate() {
            let (ku, kv) = (
                kl.column(6 * c).clone_owned(),
                kl.column(6 * c + 1).clone_owned(),
            );
            let mut col = kl.column_mut(6 * c + 4);
            col -= ku * h;
            let mut col = kl.column_mut(6 * c + 3);
            col += kv * h;
        }
        // Wᵀ (K W): the same on rows.
        for (c, &h) in offsets.iter().enumerate() {
            let (ku, kv) = (kl.row(6 * c).clone_owned(), kl.row(6 * c + 1).clone_owned());
            let mut row = kl.row_mut(6 * c + 4);
            row -= ku * h;
            let mut row = kl.row_mut(6 * c + 3);
            row += kv * h;
        }
    }
    // K = Tᵀ K_l T, T block-diagonal with R (local = R · global): block by block, Rᵀ K_ij R.
    let r = Matrix3::from_fn(|i, j| r.row(i)[j]);
    let rt = r.transpose();
    let mut k = Stiffness::zeros();
    for i in 0..8 {
        for j in 0..8 {
            let block = rt * kl.fixed_view::<3, 3>(3 * i, 3 * j) * r;
            k.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&block);
        }
    }
    k
}

/// Each corner's share of its element's area (∫ N_i dA: a uniform load's consistent nodal
/// loads, whose resultant acts at the element's centroid), each element's area and each
/// panel's.
pub struct ElementAreas {
    shares: Vec<[f64; 4]>,
    areas: Vec<f64>,
    panels: Vec<f64>,
}

impl ElementAreas {
    pub fn of(mesh: &Mesh, members: usize) -> ElementAreas {
        let shares: Vec<[f64; 4]> = mesh
            .elements
            .iter()
            .map(|&(q, _)| corner_areas(&element_frame(&q.map(|i| mesh.nodes[i])).1))
            .collect();
        let areas: Vec<f64> = shares.iter().map(|s| s.iter().sum()).collect();
        let mut panels = vec![0.0; members];
        for (&(_, k), a) in mesh.elements.iter().zip(&areas) {
            panels[k] += a;
        }
        ElementAreas {
            shares,
            areas,
            panels,
        }
    }
}

/// A case's loads on the mesh, global, six per mesh node.
pub struct MeshLoads {
    /// The case's nodal loads alone (at the mid-height nodes of the axes).
    pub point: Vec<f64>,
    /// Everything: the nodal loads and the members' loads spread over their panels.
    pub f: Vec<f64>,
    /// Per element and corner: its part of the element's share of its member's load.
    pub corner_load: Vec<[DVec3; 4]>,
}

/// The loads of `case` on the mesh: a node's load at its axis' mid-height node, a member's
/// uniform load over its panel by area, each element's part at its corners by their shares.
pub fn mesh_loads(model: &Model, mesh: &Mesh, areas: &ElementAreas, case: &LoadCase) -> MeshLoads {
    let n = mesh.nodes.len();
    let mid = |i: usize| mesh.axis_lines[i][mesh.axis_lines[i].len() / 2];
    let w = case.member_loads(model.members.len());
    let mut point = vec![0.0; 6 * n];
    for &(node, v) in &case.nodal {
        for (d, x) in v.iter().enumerate() {
            point[6 * mid(node) + d] += x;
        }
    }
    let mut f = point.clone();
    let corner_load: Vec<[DVec3; 4]> = mesh
        .elements
        .iter()
        .zip(areas.shares.iter().zip(&areas.areas))
        .map(|(&(_, k), (s, a))| {
            let m = &model.members[k];
            let length = model.nodes[m.a].distance(model.nodes[m.b]);
            let load = w[k] * (length * a / areas.panels[k]);
            s.map(|si| load * (si / a))
        })
        .collect();
    for (&(q, _), loads) in mesh.elements.iter().zip(&corner_load) {
        for (&i, l) in q.iter().zip(loads) {
            for d in 0..3 {
                f[6 * i + d] += l[d];
            }
        }
    }
    MeshLoads {
        point,
        f,
        corner_load,
    }
}

/// Solves every case on the shell mesh of `model`'s panels and gives back what the frame
/// solve gives: node displacements, member end forces, reactions and the residual.
pub fn solve(
    model: &Model,
    mesh: &Mesh,
    poisson: f64,
    cases: &[LoadCase],
) -> Result<Vec<CaseResult>, FrameError> {
    super::frame::check_cases(model, cases)?;
    let n = mesh.nodes.len();
    let mid = |i: usize| mesh.axis_lines[i][mesh.axis_lines[i].len() / 2];
    // Held freedoms.
    let mut held = vec![false; 6 * n];
    for (i, s) in model.supports.iter().enumerate() {
        match s {
            Some(Support::Fixed) => {
                for &m in &mesh.axis_lines[i] {
                    held[6 * m..6 * m + 6].fill(true);
                }
            }
            Some(Support::Pinned) => held[6 * mid(i)..6 * mid(i) + 3].fill(true),
            None => {}
        }
    }
    let mut dof = vec![usize::MAX; 6 * n];
    let mut free = 0;
    for (d, h) in held.iter().enumerate() {
        if !h {
            dof[d] = free;
            free += 1;
        }
    }
    let owner = |r: usize| {
        let d = dof.iter().position(|&x| x == r).unwrap_or(0);
        let m = d / 6;
        // The network node whose axis line or panel holds mesh node m.
        mesh.axis_lines
            .iter()
            .position(|line| line.contains(&m))
            .or_else(|| {
                mesh.elements
                    .iter()
                    .find(|(q, _)| q.contains(&m))
                    .map(|&(_, k)| model.members[k].a)
            })
            .unwrap_or(0)
    };
    let stiffness: Vec<Stiffness> = mesh
        .elements
        .par_iter()
        .map(|&(q, k)| {
            let x = q.map(|i| mesh.nodes[i]);
            global_stiffness(
                &x,
                Plate {
                    e: model.elastic.e,
                    nu: poisson,
                    thickness: model.members[k].section.thickness,
                    bending: model.members[k].section.bending_thickness(),
                },
            )
        })
        .collect();
    let mut triplets = Vec::new();
    triplets
        .try_reserve(mesh.elements.len() * 300)
        .map_err(|_| FrameError::OutOfMemory)?;
    for (&(q, _), ke) in mesh.elements.iter().zip(&stiffness) {
        for i in 0..24 {
            let r = dof[6 * q[i / 6] + i % 6];
            if r == usize::MAX {
                continue;
            }
            for j in 0..24 {
                let c = dof[6 * q[j / 6] + j % 6];
                if c == usize::MAX || r < c {
                    continue;
                }
                triplets.push(Triplet::new(r, c, ke[(i, j)]));
            }
        }
    }
    let k = SparseColMat::<usize, f64>::try_new_from_triplets(free, free, &triplets)
        .map_err(|_| FrameError::OutOfMemory)?;
    drop(triplets);
    let llt = factor(&k, owner)?;
    let areas = ElementAreas::of(mesh, model.members.len());
    let mut out = Vec::with_capacity(cases.len());
    for case in cases {
        let MeshLoads {
            point,
            f,
            corner_load,
        } = mesh_loads(model, mesh, &areas, case);
        // Solved, then refined twice (r = f − K u, K du = r): the weak drilling springs
        // cost the factorisation a few digits that one refinement gives back.
        let mut u = vec![0.0; 6 * n];
        let mut residual = f.clone();
        for _ in 0..3 {
            let mut rhs = Mat::<f64>::zeros(free, 1);
            for (d, &r) in dof.iter().enumerate() {
                if r != usize::MAX {
                    rhs[(r, 0)] = residual[d];
                }
            }
            llt.solve_in_place(rhs.as_mut());
            for (d, &r) in dof.iter().enumerate() {
                if r != usize::MAX {
                    u[d] += rhs[(r, 0)];
                }
            }
            let ku = internal(mesh, &stiffness, &u);
            for d in 0..6 * n {
                residual[d] = f[d] - ku[d];
            }
        }
        let state = State { u, point, f };
        out.push(results(
            model,
            mesh,
            &stiffness,
            &corner_load,
            &state,
            &held,
        ));
    }
    Ok(out)
}

/// K u, element by element (global, every freedom).
fn internal(mesh: &Mesh, stiffness: &[Stiffness], u: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; u.len()];
    for (&(q, _), ke) in mesh.elements.iter().zip(stiffness) {
        let fe = element_forces(&q, ke, &[DVec3::ZERO; 4], u);
        for (i, v) in fe.iter().enumerate() {
            out[6 * q[i / 6] + i % 6] += v;
        }
    }
    out
}

/// What each element takes at its corners: K u less its share of the load (global).
fn element_forces(q: &[usize; 4], ke: &Stiffness, load: &[DVec3; 4], u: &[f64]) -> [f64; 24] {
    let ue = SVector::<f64, 24>::from_fn(|i, _| u[6 * q[i / 6] + i % 6]);
    let mut fe: [f64; 24] = (ke * ue).into();
    for c in 0..4 {
        for d in 0..3 {
            fe[6 * c + d] -= load[c][d];
        }
    }
    fe
}

/// A solved case: the mesh's displacements, its point loads, and every load.
struct State {
    u: Vec<f64>,
    point: Vec<f64>,
    f: Vec<f64>,
}

/// Element corner forces summed at each mesh node less the point loads there are the reactions
/// where held and out of balance where free (over the largest load in `f`, all loads).
fn results(
    model: &Model,
    mesh: &Mesh,
    stiffness: &[Stiffness],
    corner_load: &[[DVec3; 4]],
    state: &State,
    held: &[bool],
) -> CaseResult {
    let State { u, point, f } = state;
    let n = mesh.nodes.len();
    let mid = |i: usize| mesh.axis_lines[i][mesh.axis_lines[i].len() / 2];
    // Which network node's axis line a mesh node is on.
    let mut line_of = vec![usize::MAX; n];
    for (i, line) in mesh.axis_lines.iter().enumerate() {
        for &m in line {
            line_of[m] = i;
        }
    }
    let mut at_node = vec![0.0; 6 * n];
    // Per member and end: force and moment about the end's mid-height point, global.
    let mut ends = vec![[DVec3::ZERO; 4]; model.members.len()];
    for (e, &(q, k)) in mesh.elements.iter().enumerate() {
        let fe = element_forces(&q, &stiffness[e], &corner_load[e], u);
        let m = &model.members[k];
        for (c, &node) in q.iter().enumerate() {
            for d in 0..6 {
                at_node[6 * node + d] += fe[6 * c + d];
            }
            let line = line_of[node];
            let end = if line == m.a {
                0
            } else if line == m.b {
                1
            } else {
                continue;
            };
            let force = DVec3::new(fe[6 * c], fe[6 * c + 1], fe[6 * c + 2]);
            let moment = DVec3::new(fe[6 * c + 3], fe[6 * c + 4], fe[6 * c + 5]);
            let arm = mesh.nodes[node] - model.nodes[line];
            ends[k][2 * end] += force;
            ends[k][2 * end + 1] += moment + arm.cross(force);
        }
    }
    let end_forces = model
        .members
        .iter()
        .zip(&ends)
        .map(|(m, e)| {
            let (x, y, z, _) = local_frame(model, m);
            let local = |v: DVec3| [v.dot(x), v.dot(y), v.dot(z)];
            let mut out = [0.0; 12];
            for (s, v) in e.iter().enumerate() {
                out[3 * s..3 * s + 3].copy_from_slice(&local(*v));
            }
            out
        })
        .collect();
    let scale = f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut unbalanced = 0.0f64;
    let mut reaction = vec![[DVec3::ZERO; 2]; model.nodes.len()];
    for m in 0..n {
        for d in 0..6 {
            let r = at_node[6 * m + d] - point[6 * m + d];
            if !held[6 * m + d] {
                unbalanced = unbalanced.max(r.abs());
            }
        }
        let line = line_of[m];
        if line != usize::MAX && model.supports[line].is_some() {
            let r: [f64; 6] = std::array::from_fn(|d| at_node[6 * m + d] - point[6 * m + d]);
            let force = DVec3::new(r[0], r[1], r[2]);
            let arm = mesh.nodes[m] - model.nodes[line];
            reaction[line][0] += force;
            reaction[line][1] += DVec3::new(r[3], r[4], r[5]) + arm.cross(force);
        }
    }
    let reactions = (0..model.nodes.len())
        .filter(|&i| model.supports[i].is_some())
        .map(|i| {
            let [fo, mo] = reaction[i];
            (i, [fo.x, fo.y, fo.z, mo.x, mo.y, mo.z])
        })
        .collect();
    let displacements = (0..model.nodes.len())
        .map(|i| std::array::from_fn(|d| u[6 * mid(i) + d]))
        .collect();
    CaseResult {
        displacements,
        end_forces,
        reactions,
        residual: unbalanced / scale.max(1e-300),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyze::frame::{Elastic, Member, Section};

    const STEEL: Plate = Plate {
        e: 210_000.0,
        nu: 0.3,
        thickness: 4.0,
        bending: 4.0,
    };

    fn times(k: &Stiffness, u: &[f64; 24]) -> [f64; 24] {
        (k * SVector::<f64, 24>::from_column_slice(u)).into()
    }

    #[test]
    fn rigid_motions_take_no_force() {
        // A skewed, tilted element: three translations and three rotations cost nothing.
        let x = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(30.0, 2.0, 1.0),
            DVec3::new(34.0, 25.0, 3.0),
            DVec3::new(-3.0, 20.0, 2.0),
        ];
        // Flatten it (the element is flat): project onto the plane of its first three corners.
        let n = (x[1] - x[0]).cross(x[2] - x[0]).normalize();
        let x = x.map(|p| p - n * (p - x[0]).dot(n));
        let k = global_stiffness(&x, STEEL);
        let scale = k.diagonal().amax();
        for mode in 0..6 {
            let mut u = [0.0; 24];
            for (c, p) in x.iter().enumerate() {
                let (t, r) = if mode < 3 {
                    (DVec3::AXES[mode], DVec3::ZERO)
                } else {
                    (DVec3::AXES[mode - 3].cross(*p), DVec3::AXES[mode - 3])
                };
                u[6 * c..6 * c + 3].copy_from_slice(&t.to_array());
                u[6 * c + 3..6 * c + 6].copy_from_slice(&r.to_array());
            }
            let f = times(&k, &u);
            let worst = f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(worst < 1e-9 * scale * 40.0, "mode {mode}: {worst}");
        }
    }

    /// A cantilever strip along x (length l, width b), clamped at x = 0, as one row of
    /// `along` × `across` elements of a frame-less model; the tip's mean displacement under
    /// a total force `p` along `dir` spread over the tip nodes.
    fn strip(l: f64, b: f64, along: usize, across: usize, dir: usize, p: f64) -> f64 {
        let mut nodes = Vec::new();
        for i in 0..=along {
            for j in 0..=across {
                nodes.push(DVec3::new(
                    l * i as f64 / along as f64,
                    b * j as f64 / across as f64,
                    0.0,
                ));
            }
        }
        let id = |i: usize, j: usize| i * (across + 1) + j;
        let mut k = vec![vec![0.0; 6 * nodes.len()]; 6 * nodes.len()];
        for i in 0..along {
            for j in 0..across {
                let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                let ke = global_stiffness(&q.map(|m| nodes[m]), STEEL);
                for a in 0..24 {
                    for c in 0..24 {
                        k[6 * q[a / 6] + a % 6][6 * q[c / 6] + c % 6] += ke[(a, c)];
                    }
                }
            }
        }
        // Free freedoms: all but the clamped end's.
        let free: Vec<usize> = (0..6 * nodes.len()).filter(|&d| d / 6 > across).collect();
        let m = free.len();
        let mut a = Mat::<f64>::zeros(m, m);
        let mut rhs = Mat::<f64>::zeros(m, 1);
        for (r, &dr) in free.iter().enumerate() {
            for (c, &dc) in free.iter().enumerate() {
                a[(r, c)] = k[dr][dc];
            }
        }
        // Consistent loads of a linear edge: ends 1/2 share, inner nodes 1.
        let tip: Vec<usize> = (0..=across).map(|j| id(along, j)).collect();
        for (j, &t) in tip.iter().enumerate() {
            let share = if j == 0 || j == across { 0.5 } else { 1.0 } / across as f64;
            let r = free.iter().position(|&d| d == 6 * t + dir).unwrap();
            rhs[(r, 0)] = p * share;
        }
        let u = a
            .llt(faer::Side::Lower)
            .expect("positive definite")
            .solve(&rhs);
        tip.iter()
            .map(|&t| u[(free.iter().position(|&d| d == 6 * t + dir).unwrap(), 0)])
            .sum::<f64>()
            / tip.len() as f64
    }

    #[test]
    fn a_deep_cantilever_bends_in_its_plane_without_locking() {
        // 600 × 100 mm, four elements deep and twelve long: Timoshenko's PL³/3EI + PL/(κGA)
        // (a beam's answer; the plate's clamped end and the spread load shift it by a little).
        let (l, b, p, t) = (600.0, 100.0, 1000.0, STEEL.thickness);
        let u = strip(l, b, 12, 4, 1, p);
        let i = t * b.powi(3) / 12.0;
        let g = STEEL.e / (2.0 * (1.0 + STEEL.nu));
        let beam = p * l.powi(3) / (3.0 * STEEL.e * i) + p * l / (5.0 / 6.0 * g * b * t);
        assert!((u / beam - 1.0).abs() < 0.02, "{u} vs {beam}");
    }

    #[test]
    fn a_plate_strip_bends_out_of_its_plane_between_beam_and_plate() {
        // 400 × 50 mm: between E (free anticlastic curvature, a beam) and E/(1 − ν²).
        let (l, b, p, t) = (400.0, 50.0, 10.0, STEEL.thickness);
        let u = strip(l, b, 16, 2, 2, p);
        let beam = p * l.powi(3) / (3.0 * STEEL.e * b * t.powi(3) / 12.0);
        let plate = beam * (1.0 - STEEL.nu * STEEL.nu);
        assert!(
            u <= beam * 1.005 && u >= plate * 0.995,
            "{u}: {plate}..{beam}"
        );
    }

    #[test]
    fn a_shell_cantilever_balances_and_matches_its_end_forces() {
        // Two nodes, one panel 500 long and 100 deep, clamped at node 0, pulled down at node 1.
        let model = Model {
            nodes: vec![DVec3::new(0.0, 0.0, 50.0), DVec3::new(500.0, 0.0, 50.0)],
            members: vec![Member {
                a: 0,
                b: 1,
                y: DVec3::Z,
                section: Section::solid(100.0, 4.0),
            }],
            supports: vec![Some(Support::Fixed), None],
            elastic: Elastic {
                e: STEEL.e,
                g: STEEL.e / 2.6,
            },
        };
        let base = [DVec3::ZERO, DVec3::new(500.0, 0.0, 0.0)];
        let mesh = mesh(&model, &base, &[DVec3::Z; 2], &[100.0; 2], 4);
        let case = LoadCase {
            name: "tip".into(),
            nodal: vec![(1, [0.0, 0.0, -1000.0, 0.0, 0.0, 0.0])],
            member: vec![(0, DVec3::new(0.0, 0.0, -0.5))],
        };
        let r = &solve(&model, &mesh, 0.3, &[case]).expect("solves")[0];
        assert!(r.residual < 1e-9, "{}", r.residual);
        // The reaction carries the tip load and the member's 250 N.
        let (_, react) = r.reactions[0];
        assert!((react[2] - 1250.0).abs() < 1e-6, "{react:?}");
        // About the clamp's mid-height: 1000 · 500 + 250 · 250 N·mm.
        assert!(
            (react[4].abs() - (500_000.0 + 62_500.0)).abs() < 1e-3,
            "{react:?}"
        );
        // The joint at node 1 hands the tip load to the member: 1000 N down.
        let f = r.end_forces[0];
        let (x, y, z, _) = local_frame(&model, &model.members[0]);
        let shear = x * f[6] + y * f[7] + z * f[8];
        assert!((shear.z + 1000.0).abs() < 1e-6, "{shear}");
        // It bends as a deep beam: within 3 % of Timoshenko's tip deflection.
        let i = 4.0 * 100f64.powi(3) / 12.0;
        let g = STEEL.e / 2.6;
        let tip = 1000.0 * 500f64.powi(3) / (3.0 * STEEL.e * i)
            + 1000.0 * 500.0 / (5.0 / 6.0 * g * 400.0)
            + 0.5 * 500f64.powi(4) / (8.0 * STEEL.e * i);
        assert!(
            (-r.displacements[1][2] / tip - 1.0).abs() < 0.03,
            "{:?} vs {tip}",
            r.displacements[1]
        );
    }
}
