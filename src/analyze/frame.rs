//! A linear elastic 3D frame: two-node beams with six degrees of freedom per node (three
//! displacements, three rotations), rigid joints, Timoshenko shear deformation, solved by a
//! sparse Cholesky factorisation (faer, with its fill-reducing ordering).
//!
//! Each member has a local frame: x from its first node to its second, y the section's depth
//! direction (in the panel plane), z = x × y (the panel normal, the plate's thickness
//! direction). Sections are solid rectangles, `depth` along y and `thickness` along z.
//!
//! Loads come as cases, each a set of nodal forces and moments and uniform member loads (force
//! per length, global directions); one factorisation solves every case.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Llt;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Side};
use glam::DVec3;
use thiserror::Error;

/// Elastic constants, MPa.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elastic {
    pub e: f64,
    pub g: f64,
}

/// A solid rectangle, mm: `depth` along the member's local y, `thickness` along z; or, for a
/// bolted seam, two plies face to face (`plies`, adding up to `thickness`) that bend out of
/// their plane and twist each on its own (no shear connection between them) and act as one
/// in their plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    pub depth: f64,
    pub thickness: f64,
    pub plies: Option<[f64; 2]>,
}

impl Section {
    /// A solid rectangle.
    pub fn solid(depth: f64, thickness: f64) -> Section {
        Section {
            depth,
            thickness,
            plies: None,
        }
    }

    /// The plates across the section: the plies, or the one plate.
    fn layers(&self) -> Vec<f64> {
        match self.plies {
            Some(p) => p.to_vec(),
            None => vec![self.thickness],
        }
    }

    pub fn area(&self) -> f64 {
        self.depth * self.thickness
    }

    /// Second moment about local y (bending out of the panel plane: the weak axis), mm⁴: the
    /// plies' own, summed.
    pub fn iy(&self) -> f64 {
        self.layers()
            .iter()
            .map(|t| self.depth * t.powi(3) / 12.0)
            .sum()
    }

    /// Second moment about local z (bending in the panel plane: the strong axis), mm⁴.
    pub fn iz(&self) -> f64 {
        self.thickness * self.depth.powi(3) / 12.0
    }

    /// Elastic modulus about local y, mm³: the plies share a moment by their stiffness, so
    /// the thickest sees the largest stress.
    pub fn w_weak(&self) -> f64 {
        let thickest = self.layers().into_iter().fold(0.0, f64::max);
        2.0 * self.iy() / thickest
    }

    /// Elastic modulus about local z, mm³.
    pub fn w_strong(&self) -> f64 {
        self.thickness * self.depth * self.depth / 6.0
    }

    /// The thickness of one plate as stiff in bending out of its plane: (Σ tᵢ³)^(1/3).
    pub fn bending_thickness(&self) -> f64 {
        self.layers().iter().map(|t| t.powi(3)).sum::<f64>().cbrt()
    }

    /// St Venant torsion constant (Roark, Table 10.7 case 4), the plies' summed, mm⁴.
    pub fn torsion_constant(&self) -> f64 {
        self.layers()
            .iter()
            .map(|&t| rect_torsion(self.depth, t).0)
            .sum()
    }

    /// Torsional section modulus: the largest shear stress is T over this (Roark), mm³. Plies
    /// share a torque by their torsion constants.
    pub fn torsion_modulus(&self) -> f64 {
        let j = self.torsion_constant();
        self.layers()
            .iter()
            .map(|&t| {
                let (ji, wi) = rect_torsion(self.depth, t);
                wi * j / ji
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Shear area of a rectangle, either direction.
    pub fn shear_area(&self) -> f64 {
        5.0 / 6.0 * self.area()
    }
}

/// A rectangle's torsion constant and torsional modulus (Roark, Table 10.7 case 4), mm⁴, mm³.
fn rect_torsion(depth: f64, thickness: f64) -> (f64, f64) {
    let (a, b) = (0.5 * depth.max(thickness), 0.5 * depth.min(thickness));
    let r = b / a;
    let j = a * b.powi(3) * (16.0 / 3.0 - 3.36 * r * (1.0 - r.powi(4) / 12.0));
    let k = 1.0 + 0.6095 * r + 0.8865 * r * r - 1.8023 * r.powi(3) + 0.9100 * r.powi(4);
    (j, 8.0 * a * b * b / (3.0 * k))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    /// All six freedoms held.
    Fixed,
    /// Displacements held, rotations free.
    Pinned,
}

#[derive(Clone, Debug)]
pub struct Member {
    pub a: usize,
    pub b: usize,
    /// Unit vector perpendicular to the member: the section's depth direction.
    pub y: DVec3,
    pub section: Section,
}

#[derive(Clone, Debug)]
pub struct Model {
    pub nodes: Vec<DVec3>,
    pub members: Vec<Member>,
    pub supports: Vec<Option<Support>>,
    pub elastic: Elastic,
}

/// One load case: forces (N) and moments (N·mm) at nodes, uniform loads on members (N/mm,
/// global directions).
#[derive(Clone, Debug, Default)]
pub struct LoadCase {
    pub name: String,
    pub nodal: Vec<(usize, [f64; 6])>,
    pub member: Vec<(usize, DVec3)>,
}

impl LoadCase {
    /// The uniform load on each member, summed.
    pub fn member_loads(&self, members: usize) -> Vec<DVec3> {
        let mut w = vec![DVec3::ZERO; members];
        for &(k, v) in &self.member {
            if let Some(slot) = w.get_mut(k) {
                *slot += v;
            }
        }
        w
    }
}

#[derive(Debug, Error, PartialEq)]
pub enum FrameError {
    #[error("member {0} has zero length (its nodes coincide)")]
    ZeroLength(usize),
    #[error("member {0}: its depth direction is not perpendicular to it or not finite")]
    BadOrientation(usize),
    #[error("member {0}: the section must have a positive depth and thickness")]
    BadSection(usize),
    #[error("member {member} joins node {node}, and there are only {nodes} nodes")]
    MissingNode {
        member: usize,
        node: usize,
        nodes: usize,
    },
    #[error("{case}: a load on node {node}, and there are only {nodes} nodes")]
    LoadOnMissingNode {
        case: String,
        node: usize,
        nodes: usize,
    },
    #[error("no support: give at least one")]
    NoSupport,
    #[error("a mechanism: {} can move freely ({reason}): nodes {}", if nodes.len() == 1 { "1 node" } else { "these nodes" }, list(nodes))]
    Mechanism { nodes: Vec<usize>, reason: String },
    #[error("the stiffness is singular at node {node} (a mechanism or a member far too weak)")]
    Singular { node: usize },
    #[error("out of memory for the stiffness factorisation")]
    OutOfMemory,
}

fn list(nodes: &[usize]) -> String {
    let mut s: Vec<String> = nodes.iter().take(12).map(|n| n.to_string()).collect();
    if nodes.len() > 12 {
        s.push(format!("… ({} in all)", nodes.len()));
    }
    s.join(", ")
}

/// Results of one case.
#[derive(Clone, Debug)]
pub struct CaseResult {
    /// Per node: dx, dy, dz (mm), rx, ry, rz (rad).
    pub displacements: Vec<[f64; 6]>,
    /// Per member, in its local frame: forces and moments the joints apply to the member's
    /// ends, [end a: Fx Fy Fz Mx My Mz, end b: …] (N, N·mm).
    pub end_forces: Vec<[f64; 12]>,
    /// Per supported node: reaction force and moment (N, N·mm), global.
    pub reactions: Vec<(usize, [f64; 6])>,
    /// The largest out-of-balance force (N) or moment (N·mm) at any free freedom, over the
    /// largest load: a measure of the solve's accuracy.
    pub residual: f64,
}

/// A member's local axes (x, y, z), length and local stiffness.
type Prepared = (DVec3, DVec3, DVec3, f64, [[f64; 12]; 12]);

/// A member's local axes as rows (x, y, z) and length.
pub fn local_frame(model: &Model, m: &Member) -> (DVec3, DVec3, DVec3, f64) {
    let d = model.nodes[m.b] - model.nodes[m.a];
    let l = d.length();
    let x = d / l;
    let y = (m.y - x * m.y.dot(x)).normalize();
    (x, y, x.cross(y), l)
}

/// The 12 × 12 stiffness of a member in its local frame.
pub fn local_stiffness(el: Elastic, s: Section, l: f64) -> [[f64; 12]; 12] {
    let mut k = [[0.0; 12]; 12];
    let (a, iy, iz, j, asv) = (
        s.area(),
        s.iy(),
        s.iz(),
        s.torsion_constant(),
        s.shear_area(),
    );
    let axial = el.e * a / l;
    let torsion = el.g * j / l;
    for (i0, v) in [(0, axial), (3, torsion)] {
        k[i0][i0] = v;
        k[i0 + 6][i0 + 6] = v;
        k[i0][i0 + 6] = -v;
        k[i0 + 6][i0] = -v;
    }
    // Bending in x–y (displacement y, rotation z; about the strong axis), then in x–z
    // (displacement z, rotation y; the sign of the coupling turns since θy = −dw/dx).
    for (dof_v, dof_r, inertia, sign) in [(1usize, 5usize, iz, 1.0), (2, 4, iy, -1.0)] {
        let phi = 12.0 * el.e * inertia / (el.g * asv * l * l);
        let c = el.e * inertia / (l.powi(3) * (1.0 + phi));
        let idx = [dof_v, dof_r, dof_v + 6, dof_r + 6];
        let sl = sign * 6.0 * l;
        let m = [
            [12.0, sl, -12.0, sl],
            [sl, (4.0 + phi) * l * l, -sl, (2.0 - phi) * l * l],
            [-12.0, -sl, 12.0, -sl],
            [sl, (2.0 - phi) * l * l, -sl, (4.0 + phi) * l * l],
        ];
        for r in 0..4 {
            for q in 0..4 {
                k[idx[r]][idx[q]] = c * m[r][q];
            }
        }
    }
    k
}

/// Fixed-end forces of a uniform load `w` (local components, N/mm) on a member of length `l`:
/// the forces the joints apply to hold the loaded member's ends still, negated (the equivalent
/// nodal loads).
pub fn equivalent_loads(w: DVec3, l: f64) -> [f64; 12] {
    let mut f = [0.0; 12];
    f[0] = w.x * l / 2.0;
    f[6] = w.x * l / 2.0;
    f[1] = w.y * l / 2.0;
    f[7] = w.y * l / 2.0;
    f[5] = w.y * l * l / 12.0;
    f[11] = -w.y * l * l / 12.0;
    f[2] = w.z * l / 2.0;
    f[8] = w.z * l / 2.0;
    f[4] = -w.z * l * l / 12.0;
    f[10] = w.z * l * l / 12.0;
    f
}

fn to_local(x: DVec3, y: DVec3, z: DVec3, v: DVec3) -> DVec3 {
    DVec3::new(x.dot(v), y.dot(v), z.dot(v))
}

fn to_global(x: DVec3, y: DVec3, z: DVec3, v: DVec3) -> DVec3 {
    x * v.x + y * v.y + z * v.z
}

/// The member stiffness in global axes (T̀ k T).
fn global_stiffness(k: &[[f64; 12]; 12], x: DVec3, y: DVec3, z: DVec3) -> [[f64; 12]; 12] {
    rotate_stiffness(k, [x.to_array(), y.to_array(), z.to_array()])
}

/// Tᵀ k T for a stiffness over blocks of three freedoms (translations, rotations), T block-
/// diagonal with `r`, whose rows are the local axes in global coordinates (local = r · global).
fn rotate_stiffness<const N: usize>(k: &[[f64; N]; N], r: [[f64; 3]; 3]) -> [[f64; N]; N] {
    // kt = k T, then Tᵀ kt.
    let mut kt = [[0.0; N]; N];
    for i in 0..N {
        for jb in 0..N / 3 {
            for j in 0..3 {
                let mut s = 0.0;
                for q in 0..3 {
                    s += k[i][jb * 3 + q] * r[q][j];
                }
                kt[i][jb * 3 + j] = s;
            }
        }
    }
    let mut g = [[0.0; N]; N];
    for ib in 0..N / 3 {
        for i in 0..3 {
            for j in 0..N {
                let mut s = 0.0;
                for q in 0..3 {
                    s += r[q][i] * kt[ib * 3 + q][j];
                }
                g[ib * 3 + i][j] = s;
            }
        }
    }
    g
}

/// Checks the model and finds mechanisms before any factorisation: every member between two
/// distinct existing nodes with a proper section, every node on a member or fixed, and each
/// connected part held by a fixed support or by pins at three points not on one line.
pub fn check(model: &Model) -> Result<(), FrameError> {
    let n = model.nodes.len();
    for (k, m) in model.members.iter().enumerate() {
        for node in [m.a, m.b] {
            if node >= n {
                return Err(FrameError::MissingNode {
                    member: k,
                    node,
                    nodes: n,
                });
            }
        }
        let d = model.nodes[m.b] - model.nodes[m.a];
        if d.length().is_nan() || d.length() <= 1e-9 {
            return Err(FrameError::ZeroLength(k));
        }
        let perp = m.y - d.normalize() * m.y.dot(d.normalize());
        if !perp.is_finite() || perp.length() < 1e-6 {
            return Err(FrameError::BadOrientation(k));
        }
        let s = m.section;
        if !(s.depth > 0.0 && s.thickness > 0.0 && s.depth.is_finite() && s.thickness.is_finite()) {
            return Err(FrameError::BadSection(k));
        }
    }
    if model.supports.iter().all(Option::is_none) {
        return Err(FrameError::NoSupport);
    }
    // Connected parts.
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut on_member = vec![false; n];
    for m in &model.members {
        let (ra, rb) = (root(&mut parent, m.a), root(&mut parent, m.b));
        parent[ra.max(rb)] = ra.min(rb);
        on_member[m.a] = true;
        on_member[m.b] = true;
    }
    let loose: Vec<usize> = (0..n)
        .filter(|&i| !on_member[i] && model.supports[i] != Some(Support::Fixed))
        .collect();
    if !loose.is_empty() {
        return Err(FrameError::Mechanism {
            nodes: loose,
            reason: "on no member".into(),
        });
    }
    let mut parts: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for (i, &on) in on_member.iter().enumerate() {
        if on {
            let r = root(&mut parent, i);
            parts.entry(r).or_default().push(i);
        }
    }
    for nodes in parts.values() {
        let fixed = nodes
            .iter()
            .any(|&i| model.supports[i] == Some(Support::Fixed));
        if fixed {
            continue;
        }
        let pins: Vec<DVec3> = nodes
            .iter()
            .filter(|&&i| model.supports[i] == Some(Support::Pinned))
            .map(|&i| model.nodes[i])
            .collect();
        if !spans_a_plane(&pins) {
            let reason = match pins.len() {
                0 => "no support on this part of the network".to_string(),
                1 | 2 => format!(
                    "held by {} pinned support(s) only: it can turn about them",
                    pins.len()
                ),
                _ => "its pinned supports are on one line: it can turn about it".to_string(),
            };
            return Err(FrameError::Mechanism {
                nodes: nodes.clone(),
                reason,
            });
        }
    }
    Ok(())
}

fn spans_a_plane(points: &[DVec3]) -> bool {
    let Some(&p0) = points.first() else {
        return false;
    };
    let Some(far) = points
        .iter()
        .max_by(|a, b| a.distance(p0).total_cmp(&b.distance(p0)))
    else {
        return false;
    };
    let size = far.distance(p0);
    if size <= 0.0 {
        return false;
    }
    let dir = (*far - p0) / size;
    points
        .iter()
        .any(|p| (*p - p0).cross(dir).length() > 1e-6 * size)
}

/// The lower triangle of the stiffness in compressed columns, summed in place (no triplets to
/// sort: on 100,000 members sorting 7.8 million of them took a quarter of the analysis).
/// Freedoms are numbered node by node, so a free freedom's column holds its own node's later
/// freedoms, then every free freedom of each neighbour with a higher number, in node order.
fn assemble(
    model: &Model,
    members: &[Prepared],
    dof: &[usize],
    free: usize,
) -> Result<SparseColMat<usize, f64>, FrameError> {
    let n = model.nodes.len();
    // Each node's free freedoms: how many, and the first (the rest follow it).
    let counts: Vec<usize> = (0..n)
        .map(|i| (0..6).filter(|&d| dof[6 * i + d] != usize::MAX).count())
        .collect();
    let firsts: Vec<Option<usize>> = (0..n)
        .map(|i| (0..6).map(|d| dof[6 * i + d]).find(|&d| d != usize::MAX))
        .collect();
    let count = |i: usize| counts[i];
    let first = |i: usize| firsts[i];
    // Each node's higher neighbours, sorted, as one list with a start per node.
    let mut pairs: Vec<(usize, usize)> = model
        .members
        .iter()
        .map(|m| (m.a.min(m.b), m.a.max(m.b)))
        .filter(|&(i, j)| count(i) > 0 && count(j) > 0)
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut start = vec![0usize; n + 1];
    for &(i, _) in &pairs {
        start[i + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    // Where each neighbour's rows begin within its node's columns, after the node's own rows.
    let mut offset = vec![0usize; pairs.len()];
    let mut below = vec![0usize; n];
    for i in 0..n {
        let mut o = 0;
        for p in start[i]..start[i + 1] {
            offset[p] = o;
            o += count(pairs[p].1);
        }
        below[i] = o;
    }
    let mut col_ptr = Vec::new();
    col_ptr
        .try_reserve(free + 1)
        .map_err(|_| FrameError::OutOfMemory)?;
    col_ptr.push(0usize);
    for (i, rest) in below.iter().enumerate() {
        let own = count(i);
        for q in 0..own {
            let last = *col_ptr.last().expect("a start");
            col_ptr.push(last + (own - q) + rest);
        }
    }
    let nnz = col_ptr[free];
    let mut row_idx = Vec::new();
    let mut values = Vec::new();
    row_idx
        .try_reserve_exact(nnz)
        .map_err(|_| FrameError::OutOfMemory)?;
    values
        .try_reserve_exact(nnz)
        .map_err(|_| FrameError::OutOfMemory)?;
    for i in 0..n {
        let (own, Some(f)) = (count(i), first(i)) else {
            continue;
        };
        for q in 0..own {
            row_idx.extend(f + q..f + own);
            for &(_, j) in &pairs[start[i]..start[i + 1]] {
                let fj = first(j).expect("a free neighbour");
                row_idx.extend(fj..fj + count(j));
            }
        }
    }
    values.resize(nnz, 0.0);
    // Entry (r, c), r ≥ c: in column c (a freedom of node nj), below nj's own rows when r is
    // a neighbour ni's.
    for (m, (x, y, z, _, k)) in model.members.iter().zip(members) {
        let g = global_stiffness(k, *x, *y, *z);
        let ends = [m.a, m.b];
        for (i, row) in g.iter().enumerate() {
            let (ni, ri) = (ends[i / 6], dof[6 * ends[i / 6] + i % 6]);
            if ri == usize::MAX {
                continue;
            }
            for (j, gij) in row.iter().enumerate() {
                let (nj, cj) = (ends[j / 6], dof[6 * ends[j / 6] + j % 6]);
                if cj == usize::MAX || ri < cj {
                    continue;
                }
                let base = first(nj).expect("a free freedom");
                let col_start = col_ptr[cj];
                let at = if ni == nj {
                    ri - cj
                } else {
                    let p = start[nj]
                        + pairs[start[nj]..start[nj + 1]]
                            .binary_search(&(nj, ni))
                            .expect("a neighbour");
                    let own_rest = count(nj) - (cj - base);
                    own_rest + offset[p] + (ri - first(ni).expect("a free freedom"))
                };
                values[col_start + at] += gij;
            }
        }
    }
    let symbolic = SymbolicSparseColMat::new_checked(free, free, col_ptr, None, row_idx);
    Ok(SparseColMat::new(symbolic, values))
}

/// The model's own checks, and every case's loads on nodes that exist.
pub fn check_cases(model: &Model, cases: &[LoadCase]) -> Result<(), FrameError> {
    check(model)?;
    let n = model.nodes.len();
    for case in cases {
        for &(node, _) in &case.nodal {
            if node >= n {
                return Err(FrameError::LoadOnMissingNode {
                    case: case.name.clone(),
                    node,
                    nodes: n,
                });
            }
        }
    }
    Ok(())
}

/// The sparse Cholesky factor of a stiffness (lower triangle); a pivot that is not positive is
/// a singular stiffness at the node `owner` gives for that freedom.
pub fn factor(
    k: &SparseColMat<usize, f64>,
    owner: impl Fn(usize) -> usize,
) -> Result<Llt<usize, f64>, FrameError> {
    let last = k.nrows().saturating_sub(1);
    k.sp_cholesky(Side::Lower).map_err(|e| match e {
        faer::sparse::linalg::LltError::Numeric(
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index },
        ) => FrameError::Singular {
            node: owner(index.min(last)),
        },
        faer::sparse::linalg::LltError::Generic(_) => FrameError::OutOfMemory,
    })
}

/// Solves every case with one factorisation.
pub fn solve(model: &Model, cases: &[LoadCase]) -> Result<Vec<CaseResult>, FrameError> {
    check_cases(model, cases)?;
    let n = model.nodes.len();
    // Freedom numbers: held ones get none.
    let mut dof = vec![usize::MAX; 6 * n];
    let mut free = 0usize;
    for i in 0..n {
        let held = match model.supports[i] {
            Some(Support::Fixed) => 6,
            Some(Support::Pinned) => 3,
            None => 0,
        };
        for d in held..6 {
            dof[6 * i + d] = free;
            free += 1;
        }
    }
    // Member frames and global stiffness blocks.
    let members: Vec<Prepared> = model
        .members
        .iter()
        .map(|m| {
            let (x, y, z, l) = local_frame(model, m);
            let k = local_stiffness(model.elastic, m.section, l);
            (x, y, z, l, k)
        })
        .collect();
    let owner: Vec<usize> = {
        let mut o = vec![0; free];
        for (k, &d) in dof.iter().enumerate() {
            if d != usize::MAX {
                o[d] = k / 6;
            }
        }
        o
    };
    if free == 0 {
        // Everything held: no displacement.
        return Ok(cases
            .iter()
            .map(|c| {
                let w = c.member_loads(model.members.len());
                results(model, &members, c, &w, &vec![[0.0; 6]; n], &dof, 0.0)
            })
            .collect());
    }
    let k = assemble(model, &members, &dof, free)?;
    let llt = factor(&k, |r| owner[r])?;
    // Right-hand sides, one column per case.
    let mut rhs = Mat::<f64>::zeros(free, cases.len());
    for (c, case) in cases.iter().enumerate() {
        for &(node, f) in &case.nodal {
            for (d, v) in f.iter().enumerate() {
                let r = dof[6 * node + d];
                if r != usize::MAX {
                    rhs[(r, c)] += v;
                }
            }
        }
        for &(mi, w) in &case.member {
            let m = &model.members[mi];
            let (x, y, z, l, _) = members[mi];
            let f = equivalent_loads(to_local(x, y, z, w), l);
            for end in 0..2 {
                let node = if end == 0 { m.a } else { m.b };
                for part in 0..2 {
                    let v = to_global(
                        x,
                        y,
                        z,
                        DVec3::new(
                            f[end * 6 + part * 3],
                            f[end * 6 + part * 3 + 1],
                            f[end * 6 + part * 3 + 2],
                        ),
                    );
                    for (q, val) in v.to_array().iter().enumerate() {
                        let r = dof[6 * node + part * 3 + q];
                        if r != usize::MAX {
                            rhs[(r, c)] += val;
                        }
                    }
                }
            }
        }
    }
    let loads = rhs.clone();
    llt.solve_in_place(rhs.as_mut());
    let mut out = Vec::with_capacity(cases.len());
    for (c, case) in cases.iter().enumerate() {
        let w = case.member_loads(model.members.len());
        let mut u = vec![[0.0; 6]; n];
        for i in 0..n {
            for d in 0..6 {
                let r = dof[6 * i + d];
                if r != usize::MAX {
                    u[i][d] = rhs[(r, c)];
                }
            }
        }
        let scale = (0..free).fold(0.0f64, |a, r| a.max(loads[(r, c)].abs()));
        out.push(results(model, &members, case, &w, &u, &dof, scale));
    }
    Ok(out)
}

/// End forces (k u − equivalent loads, local), reactions and the residual for one case: at
/// each joint Σ f − F is the reaction where a freedom is held and is out of balance (over
/// `scale`, the largest load) where it is free.
fn results(
    model: &Model,
    members: &[Prepared],
    case: &LoadCase,
    w: &[DVec3],
    u: &[[f64; 6]],
    dof: &[usize],
    scale: f64,
) -> CaseResult {
    let n = model.nodes.len();
    let mut end_forces = Vec::with_capacity(model.members.len());
    // Sum at each node of the forces the members' ends take: the reaction where held.
    let mut at_node = vec![[0.0; 6]; n];
    for (mi, m) in model.members.iter().enumerate() {
        let (x, y, z, l, k) = &members[mi];
        let mut ul = [0.0; 12];
        for (end, node) in [m.a, m.b].into_iter().enumerate() {
            for part in 0..2 {
                let g = DVec3::new(
                    u[node][part * 3],
                    u[node][part * 3 + 1],
                    u[node][part * 3 + 2],
                );
                let l3 = to_local(*x, *y, *z, g);
                ul[end * 6 + part * 3] = l3.x;
                ul[end * 6 + part * 3 + 1] = l3.y;
                ul[end * 6 + part * 3 + 2] = l3.z;
            }
        }
        let fixed = equivalent_loads(to_local(*x, *y, *z, w[mi]), *l);
        let mut f = [0.0; 12];
        for i in 0..12 {
            let mut s = 0.0;
            for j in 0..12 {
                s += k[i][j] * ul[j];
            }
            f[i] = s - fixed[i];
        }
        // Joint equilibrium: a joint holds each member end with f; with the nodal load F and
        // the reaction R, R = Σ f − F.
        for (end, node) in [m.a, m.b].into_iter().enumerate() {
            for part in 0..2 {
                let o = end * 6 + part * 3;
                let v = to_global(*x, *y, *z, DVec3::new(f[o], f[o + 1], f[o + 2]));
                for q in 0..3 {
                    at_node[node][part * 3 + q] += v[q];
                }
            }
        }
        end_forces.push(f);
    }
    let mut nodal = vec![[0.0; 6]; n];
    debug_assert_eq!(w.len(), model.members.len());
    for &(node, f) in &case.nodal {
        for d in 0..6 {
            nodal[node][d] += f[d];
        }
    }
    // Joint equilibrium: reaction + nodal load = what the members take at the joint.
    let mut unbalanced = 0.0f64;
    let mut reactions = Vec::new();
    for i in 0..n {
        let mut r = [0.0; 6];
        for d in 0..6 {
            r[d] = at_node[i][d] - nodal[i][d];
            if dof[6 * i + d] != usize::MAX {
                unbalanced = unbalanced.max(r[d].abs());
            }
        }
        if model.supports[i].is_some() {
            reactions.push((i, r));
        }
    }
    CaseResult {
        displacements: u.to_vec(),
        end_forces,
        reactions,
        residual: unbalanced / scale.max(1e-300),
    }
}

/// Internal forces at `s` along a member (0 at end a) from its end forces and its uniform
/// load (local, N/mm): [N, Vy, Vz, T, My, Mz], N tension positive.
pub fn internal_forces(end: &[f64; 12], w: DVec3, s: f64) -> [f64; 6] {
    let (fx, fy, fz) = (end[0], end[1], end[2]);
    let (mx, my, mz) = (end[3], end[4], end[5]);
    [
        -(fx + w.x * s),
        -(fy + w.y * s),
        -(fz + w.z * s),
        -mx,
        -(my + s * fz + 0.5 * s * s * w.z),
        -(mz - s * fy - 0.5 * s * s * w.y),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    const STEEL: Elastic = Elastic {
        e: 200_000.0,
        g: 200_000.0 / 2.6,
    };

    fn cantilever(depth: f64, thickness: f64, l: f64, parts: usize) -> Model {
        let nodes: Vec<DVec3> = (0..=parts)
            .map(|i| DVec3::new(l * i as f64 / parts as f64, 0.0, 0.0))
            .collect();
        let members = (0..parts)
            .map(|i| Member {
                a: i,
                b: i + 1,
                y: DVec3::Y,
                section: Section::solid(depth, thickness),
            })
            .collect();
        let mut supports = vec![None; parts + 1];
        supports[0] = Some(Support::Fixed);
        Model {
            nodes,
            members,
            supports,
            elastic: STEEL,
        }
    }

    #[test]
    fn cantilever_tip_deflection_is_bending_plus_shear() -> Result<(), FrameError> {
        // P in −y at the tip bends about the strong axis (z): δ = PL³/3EI + PL/(κGA),
        // θ = PL²/2EI.
        let (d, t, l, p) = (100.0, 5.0, 400.0, 1000.0);
        let model = cantilever(d, t, l, 1);
        let case = LoadCase {
            name: "P".into(),
            nodal: vec![(1, [0.0, -p, 0.0, 0.0, 0.0, 0.0])],
            member: vec![],
        };
        let r = &solve(&model, &[case])?[0];
        let s = Section::solid(d, t);
        let bend = p * l.powi(3) / (3.0 * STEEL.e * s.iz());
        let shear = p * l / (STEEL.g * s.shear_area());
        let tip = r.displacements[1];
        assert!(((-tip[1]) - (bend + shear)).abs() < 1e-9 * bend, "{tip:?}");
        let rot = p * l * l / (2.0 * STEEL.e * s.iz());
        assert!((-tip[5] - rot).abs() < 1e-9 * rot, "{tip:?}");
        // Weak axis: P in z.
        let case = LoadCase {
            name: "Pz".into(),
            nodal: vec![(1, [0.0, 0.0, p, 0.0, 0.0, 0.0])],
            member: vec![],
        };
        let r = &solve(&model, &[case])?[0];
        let bend = p * l.powi(3) / (3.0 * STEEL.e * s.iy());
        let shear = p * l / (STEEL.g * s.shear_area());
        assert!((r.displacements[1][2] - (bend + shear)).abs() < 1e-9 * bend);
        let reaction = r.reactions[0].1;
        assert!((reaction[2] + p).abs() < 1e-9 * p);
        assert!((reaction[4] - p * l).abs() < 1e-9 * p * l, "{reaction:?}");
        Ok(())
    }

    #[test]
    fn uniform_load_gives_wl4_over_8ei_at_the_tip_in_any_subdivision() -> Result<(), FrameError> {
        let (d, t, l, w) = (60.0, 8.0, 1000.0, 0.5);
        let s = Section::solid(d, t);
        for parts in [1, 3, 10] {
            let model = cantilever(d, t, l, parts);
            let case = LoadCase {
                name: "w".into(),
                nodal: vec![],
                member: (0..parts).map(|i| (i, DVec3::new(0.0, -w, 0.0))).collect(),
            };
            let r = &solve(&model, &[case])?[0];
            let bend = w * l.powi(4) / (8.0 * STEEL.e * s.iz());
            let shear = w * l * l / (2.0 * STEEL.g * s.shear_area());
            let tip = -r.displacements[parts][1];
            assert!((tip - (bend + shear)).abs() < 1e-9 * bend, "{parts}: {tip}");
            // The support takes the whole load and its moment.
            let re = r.reactions[0].1;
            assert!((re[1] - w * l).abs() < 1e-9 * w * l, "{re:?}");
            assert!((re[5] - w * l * l / 2.0).abs() < 1e-9 * w * l * l);
            // The root moment from the first member's end forces.
            let m0 = internal_forces(&r.end_forces[0], DVec3::new(0.0, -w, 0.0), 0.0);
            assert!((m0[5].abs() - w * l * l / 2.0).abs() < 1e-6 * w * l * l);
            assert!(r.residual < 1e-9, "{}", r.residual);
        }
        Ok(())
    }

    #[test]
    fn torsion_twists_by_tl_over_gj() -> Result<(), FrameError> {
        let (d, t, l, torque) = (100.0, 10.0, 500.0, 2.0e5);
        let model = cantilever(d, t, l, 2);
        let case = LoadCase {
            name: "T".into(),
            nodal: vec![(2, [0.0, 0.0, 0.0, torque, 0.0, 0.0])],
            member: vec![],
        };
        let r = &solve(&model, &[case])?[0];
        let s = Section::solid(d, t);
        let want = torque * l / (STEEL.g * s.torsion_constant());
        assert!((r.displacements[2][3] - want).abs() < 1e-9 * want);
        // Roark's J for a 10:1 rectangle: β = 0.312 of d t³ (tabulated 0.312 at 10).
        assert!((s.torsion_constant() / (d * t.powi(3)) - 0.312).abs() < 0.002);
        Ok(())
    }

    /// A fixed-base portal (columns h, beam L, rigid joints) swayed by H at beam level:
    /// slope-deflection gives Δ = H h³ (2 + 3k) / (12 E I_c (1 + 6k)), k = (I_b/L)/(I_c/h),
    /// neglecting axial and shear strain; slender members make those small.
    #[test]
    fn portal_frame_sways_as_slope_deflection_says() -> Result<(), FrameError> {
        let (h, l, force) = (3000.0, 4000.0, 500.0);
        let col = Section::solid(60.0, 40.0);
        let beam = Section::solid(80.0, 40.0);
        let model = Model {
            nodes: vec![
                DVec3::ZERO,
                DVec3::new(0.0, 0.0, h),
                DVec3::new(l, 0.0, h),
                DVec3::new(l, 0.0, 0.0),
            ],
            // Depth along x for the columns and z for the beam: all bend about their strong
            // axis in the x–z plane.
            members: vec![
                Member {
                    a: 0,
                    b: 1,
                    y: DVec3::X,
                    section: col,
                },
                Member {
                    a: 1,
                    b: 2,
                    y: DVec3::Z,
                    section: beam,
                },
                Member {
                    a: 3,
                    b: 2,
                    y: DVec3::X,
                    section: col,
                },
            ],
            supports: vec![Some(Support::Fixed), None, None, Some(Support::Fixed)],
            elastic: STEEL,
        };
        let case = LoadCase {
            name: "H".into(),
            nodal: vec![(1, [force, 0.0, 0.0, 0.0, 0.0, 0.0])],
            member: vec![],
        };
        let r = &solve(&model, &[case])?[0];
        let k = (beam.iz() / l) / (col.iz() / h);
        let want =
            force * h.powi(3) * (2.0 + 3.0 * k) / (12.0 * STEEL.e * col.iz() * (1.0 + 6.0 * k));
        for node in [1, 2] {
            let got = r.displacements[node][0];
            assert!(
                (got / want - 1.0).abs() < 0.005,
                "node {node}: {got} vs {want}"
            );
        }
        // The supports share H and hold the overturning moment H·h.
        let fx: f64 = r.reactions.iter().map(|(_, f)| f[0]).sum();
        assert!((fx + force).abs() < 1e-9 * force);
        let my: f64 = r
            .reactions
            .iter()
            .map(|(i, f)| f[4] + (model.nodes[*i].z * f[0] - model.nodes[*i].x * f[2]))
            .sum();
        assert!((my + force * h).abs() < 1e-9 * force * h, "{my}");
        Ok(())
    }

    /// A horizontal L (a along x from a fixed end, then b along y) with P down at its tip:
    /// δ = P b³/3EI + P a³/3EI + P b² a/GJ, with each leg's shear strain P L/κGA added; the
    /// tip turns by P b²/2EI + P a b/EI about x… checked through the deflection alone.
    #[test]
    fn bent_cantilever_in_space_deflects_by_bending_torsion_and_shear() -> Result<(), FrameError> {
        let (a, b, p) = (800.0, 500.0, 200.0);
        let s = Section::solid(20.0, 20.0);
        let model = Model {
            nodes: vec![DVec3::ZERO, DVec3::new(a, 0.0, 0.0), DVec3::new(a, b, 0.0)],
            members: vec![
                Member {
                    a: 0,
                    b: 1,
                    y: DVec3::Y,
                    section: s,
                },
                Member {
                    a: 1,
                    b: 2,
                    y: DVec3::X,
                    section: s,
                },
            ],
            supports: vec![Some(Support::Fixed), None, None],
            elastic: STEEL,
        };
        let case = LoadCase {
            name: "P".into(),
            nodal: vec![(2, [0.0, 0.0, -p, 0.0, 0.0, 0.0])],
            member: vec![],
        };
        let r = &solve(&model, &[case])?[0];
        let ei = STEEL.e * s.iy();
        let want = p * b.powi(3) / (3.0 * ei)
            + p * a.powi(3) / (3.0 * ei)
            + p * b * b * a / (STEEL.g * s.torsion_constant())
            + p * (a + b) / (STEEL.g * s.shear_area());
        let got = -r.displacements[2][2];
        assert!((got / want - 1.0).abs() < 1e-9, "{got} vs {want}");
        // The fixed end holds P, the torque P·b about x and the moment P·a about y.
        let re = r.reactions[0].1;
        assert!((re[2] - p).abs() < 1e-9 * p);
        assert!((re[3] - p * b).abs() < 1e-9 * p * b, "{re:?}");
        assert!((re[4] + p * a).abs() < 1e-9 * p * a, "{re:?}");
        Ok(())
    }

    #[test]
    fn mechanisms_and_bad_members_are_named() {
        let mut m = cantilever(100.0, 5.0, 400.0, 2);
        m.supports[0] = Some(Support::Pinned);
        m.supports[2] = Some(Support::Pinned);
        let e = solve(&m, &[]).unwrap_err();
        assert!(matches!(e, FrameError::Mechanism { .. }), "{e}");
        m.supports = vec![None; 3];
        assert_eq!(solve(&m, &[]).unwrap_err(), FrameError::NoSupport);
        let mut z = cantilever(100.0, 5.0, 400.0, 2);
        z.nodes[2] = z.nodes[1];
        assert_eq!(solve(&z, &[]).unwrap_err(), FrameError::ZeroLength(1));
        let c = cantilever(100.0, 5.0, 400.0, 2);
        let case = LoadCase {
            name: "p".into(),
            nodal: vec![(7, [0.0; 6])],
            member: vec![],
        };
        assert!(matches!(
            solve(&c, &[case]).unwrap_err(),
            FrameError::LoadOnMissingNode { node: 7, .. }
        ));
    }
}
