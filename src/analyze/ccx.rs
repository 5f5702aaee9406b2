//! The frame (or the panels as shells, [`write_shell_deck`]) as a CalculiX deck (`.inp`), for
//! an independent solve. The frame: the same nodes, each member
//! split into `SPLIT` equal quadratic beams (B32: CalculiX expands them into 20-node bricks of the
//! member's rectangle), a rectangular section per member with its depth direction as the
//! section's 1-direction, the same supports, and the loads of the case summing them all as
//! nodal forces (uniform member loads as the consistent loads of each quadratic beam: 1/6, 2/3,
//! 1/6 of its share). Results requested: displacements of every node and reaction forces of
//! the supports (`.dat`), in mm, N, MPa.
//!
//! Why 32 beams a member: CalculiX's expanded beams converge slowly (about as 1/n), because
//! the section is held whole where a beam meets a support or a knot and the adjacent bricks
//! cannot contract sideways. A cantilever under an end load deflects 1.2 % too little at 8
//! beams, 0.55 % at 16, 0.3 % at 32; a planar portal frame 3.6 %, 1.7 % and 0.9 % from the
//! exact frame. Grading (short beams at the ends, long ones between) did worse than uniform.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use super::frame::{LoadCase, Model, Support};
use super::shell::{mesh_loads, ElementAreas, Mesh};
use crate::files::{write_atomic, WriteError};

/// Quadratic beams per member.
pub const SPLIT: usize = 32;

/// Node numbers: network node i is i + 1; member k's inner nodes follow them, 2·SPLIT − 1 each.
pub fn inner_node(model: &Model, k: usize, j: usize) -> usize {
    model.nodes.len() + 1 + k * (2 * SPLIT - 1) + j
}

/// A number for a deck field: CalculiX reads at most 20 characters a field, so the shortest
/// exact form where it fits, else 12 significant digits.
fn num(x: f64) -> String {
    let exact = format!("{x:?}");
    if exact.len() <= 20 {
        exact
    } else {
        format!("{x:.11e}")
    }
}

pub fn write_deck(
    model: &Model,
    case: &LoadCase,
    title: &str,
    poisson: f64,
    path: &Path,
) -> Result<(), WriteError> {
    write_atomic(path, |w| {
        writeln!(w, "*HEADING")?;
        writeln!(w, "{title}")?;
        writeln!(w, "*NODE, NSET=NALL")?;
        for (i, p) in model.nodes.iter().enumerate() {
            writeln!(w, "{}, {}, {}, {}", i + 1, num(p.x), num(p.y), num(p.z))?;
        }
        for (k, m) in model.members.iter().enumerate() {
            let (a, b) = (model.nodes[m.a], model.nodes[m.b]);
            for j in 0..2 * SPLIT - 1 {
                let p = a.lerp(b, (j + 1) as f64 / (2 * SPLIT) as f64);
                writeln!(
                    w,
                    "{}, {}, {}, {}",
                    inner_node(model, k, j),
                    num(p.x),
                    num(p.y),
                    num(p.z)
                )?;
            }
        }
        let chain = |k: usize, i: usize| -> usize {
            // The i-th of the member's 2·SPLIT + 1 nodes.
            let m = &model.members[k];
            if i == 0 {
                m.a + 1
            } else if i == 2 * SPLIT {
                m.b + 1
            } else {
                inner_node(model, k, i - 1)
            }
        };
        for (k, _) in model.members.iter().enumerate() {
            writeln!(w, "*ELEMENT, TYPE=B32, ELSET=M{}", k + 1)?;
            for e in 0..SPLIT {
                writeln!(
                    w,
                    "{}, {}, {}, {}",
                    k * SPLIT + e + 1,
                    chain(k, 2 * e),
                    chain(k, 2 * e + 1),
                    chain(k, 2 * e + 2)
                )?;
            }
        }
        writeln!(w, "*MATERIAL, NAME=STEEL")?;
        writeln!(w, "*ELASTIC")?;
        writeln!(w, "{}, {}", num(model.elastic.e), num(poisson))?;
        for (k, m) in model.members.iter().enumerate() {
            let (_, y, _, _) = super::frame::local_frame(model, m);
            writeln!(
                w,
                "*BEAM SECTION, ELSET=M{}, MATERIAL=STEEL, SECTION=RECT",
                k + 1
            )?;
            writeln!(w, "{}, {}", num(m.section.depth), num(m.section.thickness))?;
            writeln!(w, "{}, {}, {}", num(y.x), num(y.y), num(y.z))?;
        }
        writeln!(w, "*NSET, NSET=SUPPORTS")?;
        for (i, s) in model.supports.iter().enumerate() {
            if s.is_some() {
                writeln!(w, "{}", i + 1)?;
            }
        }
        writeln!(w, "*BOUNDARY")?;
        for (i, s) in model.supports.iter().enumerate() {
            match s {
                Some(Support::Fixed) => writeln!(w, "{}, 1, 6", i + 1)?,
                Some(Support::Pinned) => writeln!(w, "{}, 1, 3", i + 1)?,
                None => {}
            }
        }
        writeln!(w, "*STEP")?;
        writeln!(w, "*STATIC")?;
        writeln!(w, "*CLOAD")?;
        let mut forces: std::collections::BTreeMap<usize, DVec3> = Default::default();
        for &(node, f) in &case.nodal {
            *forces.entry(node + 1).or_default() += DVec3::new(f[0], f[1], f[2]);
            for (d, v) in f[3..].iter().enumerate() {
                if *v != 0.0 {
                    writeln!(w, "{}, {}, {}", node + 1, d + 4, num(*v))?;
                }
            }
        }
        for (k, load) in case.member_loads(model.members.len()).iter().enumerate() {
            if *load == DVec3::ZERO {
                continue;
            }
            let m = &model.members[k];
            let share = *load * (model.nodes[m.a].distance(model.nodes[m.b]) / SPLIT as f64);
            for e in 0..SPLIT {
                for (i, part) in [
                    (2 * e, 1.0 / 6.0),
                    (2 * e + 1, 4.0 / 6.0),
                    (2 * e + 2, 1.0 / 6.0),
                ] {
                    *forces.entry(chain(k, i)).or_default() += share * part;
                }
            }
        }
        for (node, f) in &forces {
            for (d, v) in f.to_array().iter().enumerate() {
                if *v != 0.0 {
                    writeln!(w, "{}, {}, {}", node, d + 1, num(*v))?;
                }
            }
        }
        writeln!(w, "*NODE PRINT, NSET=NALL")?;
        writeln!(w, "U")?;
        writeln!(w, "*NODE PRINT, NSET=SUPPORTS")?;
        writeln!(w, "RF")?;
        writeln!(w, "*END STEP")?;
        Ok(())
    })
}

/// The panels as lamina's shell analysis meshed them, as a CalculiX deck of S8R shells: each
/// four-node element with its edges' midpoints added (flat panels: the same geometry), its
/// member's gauge as thickness, the same supports (fixed: every node up the axis line, all six
/// freedoms; pinned: the mid-height node's displacements) and the loads lamina applied: its
/// nodal loads as they are, each element's share of a member's load as the element's
/// consistent loads. Node i + 1 is network node i's mid-height node, the point
/// sizing.json's displacements are of; the other mesh nodes follow, then the midside nodes.
pub fn write_shell_deck(
    model: &Model,
    mesh: &Mesh,
    case: &LoadCase,
    title: &str,
    poisson: f64,
    path: &Path,
) -> Result<(), WriteError> {
    let n = model.nodes.len();
    // Deck numbers: the mid-height nodes first.
    let mut id = vec![0usize; mesh.nodes.len()];
    for (i, line) in mesh.axis_lines.iter().enumerate() {
        id[line[line.len() / 2]] = i + 1;
    }
    let mut next = n + 1;
    for slot in id.iter_mut().filter(|v| **v == 0) {
        *slot = next;
        next += 1;
    }
    let mut order: Vec<usize> = (0..mesh.nodes.len()).collect();
    order.sort_by_key(|&m| id[m]);
    // Midside nodes, numbered as the elements first reach their edges.
    let mut midside: std::collections::HashMap<(usize, usize), usize> = Default::default();
    let mut midpoints: Vec<DVec3> = Vec::new();
    let elements: Vec<[usize; 8]> = mesh
        .elements
        .iter()
        .map(|&(q, _)| {
            let mut e = [0; 8];
            for c in 0..4 {
                let (a, b) = (q[c], q[(c + 1) % 4]);
                e[c] = id[a];
                e[4 + c] = *midside.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    midpoints.push(mesh.nodes[a].lerp(mesh.nodes[b], 0.5));
                    next + midpoints.len() - 1
                });
            }
            e
        })
        .collect();
    let areas = ElementAreas::of(mesh, model.members.len());
    let loads = mesh_loads(model, mesh, &areas, case);
    write_atomic(path, |w| {
        writeln!(w, "*HEADING")?;
        writeln!(w, "{title}")?;
        writeln!(w, "*NODE, NSET=NALL")?;
        for &m in &order {
            let p = mesh.nodes[m];
            writeln!(w, "{}, {}, {}, {}", id[m], num(p.x), num(p.y), num(p.z))?;
        }
        for (j, p) in midpoints.iter().enumerate() {
            writeln!(w, "{}, {}, {}, {}", next + j, num(p.x), num(p.y), num(p.z))?;
        }
        // One element set per gauge.
        let mut gauges: Vec<f64> = model.members.iter().map(|m| m.section.thickness).collect();
        gauges.sort_by(f64::total_cmp);
        gauges.dedup();
        let set_of = |k: usize| {
            let t = model.members[k].section.thickness;
            gauges.iter().position(|g| *g == t).unwrap_or(0) + 1
        };
        for g in 1..=gauges.len() {
            writeln!(w, "*ELEMENT, TYPE=S8R, ELSET=G{g}")?;
            for (j, (e, &(_, k))) in elements.iter().zip(&mesh.elements).enumerate() {
                if set_of(k) == g {
                    let list: Vec<String> = e.iter().map(|v| v.to_string()).collect();
                    writeln!(w, "{}, {}", j + 1, list.join(", "))?;
                }
            }
        }
        writeln!(w, "*MATERIAL, NAME=STEEL")?;
        writeln!(w, "*ELASTIC")?;
        writeln!(w, "{}, {}", num(model.elastic.e), num(poisson))?;
        for (g, t) in gauges.iter().enumerate() {
            writeln!(w, "*SHELL SECTION, ELSET=G{}, MATERIAL=STEEL", g + 1)?;
            writeln!(w, "{}", num(*t))?;
        }
        writeln!(w, "*BOUNDARY")?;
        for (i, s) in model.supports.iter().enumerate() {
            let line = &mesh.axis_lines[i];
            match s {
                Some(Support::Fixed) => {
                    for (j, &m) in line.iter().enumerate() {
                        writeln!(w, "{}, 1, 6", id[m])?;
                        // The midside node up the axis line (none on an axis no panel meets).
                        if let Some(mid) = line
                            .get(j + 1)
                            .and_then(|&up| midside.get(&(m.min(up), m.max(up))))
                        {
                            writeln!(w, "{mid}, 1, 6")?;
                        }
                    }
                }
                Some(Support::Pinned) => writeln!(w, "{}, 1, 3", i + 1)?,
                None => {}
            }
        }
        writeln!(w, "*STEP")?;
        writeln!(w, "*STATIC")?;
        writeln!(w, "*CLOAD")?;
        // The nodal loads where lamina put them; each element's share of its member's load
        // as the S8R element's consistent loads of a uniform load (−1/12 at each corner, 1/3
        // at each midside node: the same resultant, at the same point).
        let mut f: std::collections::BTreeMap<usize, [f64; 6]> = Default::default();
        for &m in &order {
            let v = &loads.point[6 * m..6 * m + 6];
            if v.iter().any(|x| *x != 0.0) {
                f.insert(id[m], v.try_into().expect("six"));
            }
        }
        for (e, corners) in elements.iter().zip(&loads.corner_load) {
            let total: DVec3 = corners.iter().copied().sum();
            if total == DVec3::ZERO {
                continue;
            }
            for (j, &node) in e.iter().enumerate() {
                let share = if j < 4 { -1.0 / 12.0 } else { 1.0 / 3.0 };
                let slot = f.entry(node).or_default();
                for d in 0..3 {
                    slot[d] += total[d] * share;
                }
            }
        }
        for (node, v) in &f {
            for (d, x) in v.iter().enumerate() {
                if *x != 0.0 {
                    writeln!(w, "{node}, {}, {}", d + 1, num(*x))?;
                }
            }
        }
        writeln!(w, "*NODE PRINT, NSET=NALL")?;
        writeln!(w, "U")?;
        writeln!(w, "*END STEP")?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn deck_numbers_fit_calculix_fields() {
        for x in [
            0.0,
            -1.0,
            1e-300,
            -3.6465070201051283e-16,
            123456.78901234567,
            -0.5000000000000002,
            f64::MAX,
        ] {
            let s = num(x);
            assert!(s.len() <= 20, "{s}");
            let back: f64 = s.parse().unwrap();
            assert!((back - x).abs() <= 1e-11 * x.abs(), "{s} for {x:?}");
        }
        assert_eq!(num(0.25), "0.25");
    }
}
