//! The `hole` operation (Hart, Figure 9): two cells are removed, one at the bud and one on the
//! wall opposite it, and their rings are joined by a tube of antiprism rings through the
//! inside of the form. The genus grows by one.
//!
//! The opposite cell is where the ray from the bud's cell along the mean inward normal of the
//! cells within three hops first meets the form. A start is rejected when the ray meets
//! nothing, meets the wall from the wrong side, lands within five hops, when the straight way
//! passes within the clearance of another part of the form, or when a tube triangle would meet
//! the form (the tube is then undone). Each cell within two hops of the bud is tried in turn;
//! if none works the hole is refused (and counted).

use glam::DVec3;

use super::embed::Embedding;
use super::graph::{zip_loops, CellGraph, GraphError};

pub enum HoleOutcome {
    Made { new_cells: usize },
    Refused,
}

pub fn grow(
    graph: &mut CellGraph,
    embed: &mut Embedding,
    bud: u32,
    size: f64,
) -> Result<HoleOutcome, GraphError> {
    // From the bud's cell, or failing that from a cell within two hops of it.
    let tries: Vec<u32> = embed
        .within(graph, bud, 2)
        .iter()
        .map(|&(c, _)| c)
        .collect();
    for p in tries {
        if let Some(plan) = plan(graph, embed, p, size) {
            if let Some(made) = dig(graph, embed, p, plan, size)? {
                return Ok(made);
            }
        }
    }
    Ok(HoleOutcome::Refused)
}

/// Makes the planned tube, or undoes it and says None if it would meet the form.
fn dig(
    graph: &mut CellGraph,
    embed: &mut Embedding,
    p: u32,
    plan: Plan,
    size: f64,
) -> Result<Option<HoleOutcome>, GraphError> {
    let Plan {
        q,
        axis,
        length,
        radius,
        sides,
        rings: k,
    } = plan;
    let xp = embed.pos[p as usize];
    let before = graph.len();
    let (at_p, at_q) = (xp, embed.pos[q as usize]);
    let (size_p, size_q) = (embed.size[p as usize], embed.size[q as usize]);
    let u = axis.any_orthonormal_vector();
    let w = axis.cross(u);
    let mut next = graph.len() as u32;
    let mut rings = Vec::with_capacity(k);
    for r in 1..=k {
        let centre = xp + axis * (length * r as f64 / (k + 1) as f64);
        let mut ring = Vec::with_capacity(sides);
        for i in 0..sides {
            let id = if r == 1 && i == 0 {
                p
            } else if r == k && i == sides / 2 {
                q
            } else {
                next += 1;
                next - 1
            };
            // Positive turns about the axis: q's rotational sense as seen from p.
            let theta = std::f64::consts::TAU * i as f64 / sides as f64;
            embed.place(
                id,
                centre + radius * (u * theta.cos() + w * theta.sin()),
                size,
            );
            ring.push(id);
        }
        rings.push(ring);
    }
    let ring_p = graph.neighbours(p).to_vec();
    let ring_q = graph.neighbours(q).to_vec();
    let mut touched = vec![p, q];
    touched.extend(&ring_p);
    touched.extend(&ring_q);
    let saved = graph.save(&touched);
    let pos = &embed.pos;
    let dist = |a: u32, b: u32| pos[a as usize].distance(pos[b as usize]);
    graph.tunnel(p, q, &rings, |x, y| {
        let j = (0..y.len())
            .min_by(|&a, &b| dist(x[0], y[a]).total_cmp(&dist(x[0], y[b])))
            .unwrap_or(0);
        let y: Vec<u32> = y[j..].iter().chain(&y[..j]).copied().collect();
        zip_loops(x, &y)
    })?;
    let mut moved: Vec<u32> = rings.into_iter().flatten().collect();
    for &v in &moved {
        embed.measure(graph, v);
    }
    moved.extend(ring_p);
    moved.extend(ring_q);
    // The tube must meet nothing; if it would, the hole is not made here.
    if !moved
        .iter()
        .all(|&v| embed.star_clear(graph, v, embed.pos[v as usize]))
    {
        graph.restore(saved);
        embed.truncate(before);
        embed.place(p, at_p, size_p);
        embed.place(q, at_q, size_q);
        return Ok(None);
    }
    for _ in 0..4 {
        for &v in &moved {
            embed.relax(graph, v);
        }
    }
    Ok(Some(HoleOutcome::Made {
        new_cells: next as usize - before,
    }))
}

struct Plan {
    q: u32,
    axis: DVec3,
    length: f64,
    radius: f64,
    sides: usize,
    rings: usize,
}

fn plan(graph: &CellGraph, embed: &mut Embedding, p: u32, size: f64) -> Option<Plan> {
    let xp = embed.pos[p as usize];
    // The surface round one cell may be a small lump facing anywhere: the inward direction is
    // the mean normal of the cells within three hops.
    let inward = -embed
        .within(graph, p, 3)
        .iter()
        .map(|&(v, _)| embed.normal(graph, v))
        .sum::<DVec3>()
        .normalize_or_zero();
    if inward == DVec3::ZERO {
        return None;
    }
    let near: Vec<u32> = embed
        .within(graph, p, 5)
        .into_iter()
        .map(|(v, _)| v)
        .collect();
    let mut skip = vec![false; graph.len()];
    for &v in &near {
        skip[v as usize] = true;
    }
    let mut best: Option<(f64, [u32; 3])> = None;
    for f in graph.faces() {
        if f.iter().all(|&v| skip[v as usize]) {
            continue;
        }
        let c = f.map(|v| embed.pos[v as usize]);
        if let Some(t) = ray_triangle(xp, inward, c) {
            if best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, f));
            }
        }
    }
    let (t, face) = best?;
    let hit = xp + inward * t;
    let q = *face
        .iter()
        .min_by(|&&a, &&b| {
            embed.pos[a as usize]
                .distance(hit)
                .total_cmp(&embed.pos[b as usize].distance(hit))
        })
        .expect("a face has three cells");
    if skip[q as usize] {
        return None;
    }
    let xq = embed.pos[q as usize];
    let length = xp.distance(xq);
    let axis = (xq - xp) / length;
    // The ray must meet the wall from inside: q's outward normal points away from p.
    if embed.normal(graph, q).dot(axis) < 0.3 {
        return None;
    }
    let ring_radius = |v: u32| {
        let x = embed.pos[v as usize];
        let ns = graph.neighbours(v);
        ns.iter()
            .map(|&u| {
                let d = embed.pos[u as usize] - x;
                (d - axis * d.dot(axis)).length()
            })
            .sum::<f64>()
            / ns.len() as f64
    };
    // Narrower than the rings it joins, so it leaves the wall cleanly; the springs widen it.
    let radius = 0.25 * (ring_radius(p) + ring_radius(q));
    let sides = graph.degree(p).min(graph.degree(q)).max(3);
    let rings = ((length / size).round() as usize).saturating_sub(1).max(1);
    // The tube's way must be clear of everything but the two walls it joins.
    let mut ends: Vec<u32> = embed
        .within(graph, q, 3)
        .into_iter()
        .map(|(v, _)| v)
        .collect();
    ends.extend(embed.within(graph, p, 3).into_iter().map(|(v, _)| v));
    let reach = radius + embed.clearance * size;
    let samples = (length / (0.5 * size)).ceil() as usize;
    let mut blocked = false;
    for s in 0..=samples {
        let along = length * s as f64 / samples as f64;
        if along < size || along > length - size {
            continue;
        }
        let at = xp + axis * along;
        embed.near(at, reach, |v| {
            if !ends.contains(&v) {
                blocked = true;
            }
        });
        if blocked {
            return None;
        }
    }
    Some(Plan {
        q,
        axis,
        length,
        radius,
        sides,
        rings,
    })
}

/// Distance along the ray to the triangle (Möller-Trumbore), if it is hit ahead.
fn ray_triangle(o: DVec3, d: DVec3, c: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (c[1] - c[0], c[2] - c[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-14 {
        return None;
    }
    let s = o - c[0];
    let u = s.dot(p) / det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) / det;
    (t > 1e-9).then_some(t)
}
