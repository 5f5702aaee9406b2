//! Joint repair: where two members meet at less than the minimum angle, the joint's node or
//! the node at the far end of one of the two members moves, on the surface (or in the plane of
//! its normal), to the best of a ring of trial positions (`Guide::ring`) within the deviation. "Best" is the
//! smallest angle at the moved node and its neighbours, counted up to the minimum, then their
//! sum; a move is taken only when it is better and every node its members stand for stays
//! within the deviation.

use std::collections::BTreeMap;

use glam::DVec3;

use super::chains::{Leg, Work};
use super::{Guide, Options};

/// Moves per node and per sharp joint before giving up on it.
const WALKS: usize = 4;

/// Repairs the sharp joints it can; returns how many it repaired.
pub(super) fn repair(work: &mut Work, guide: &Guide, opts: &Options) -> usize {
    if opts.min_angle <= 0.0 {
        return 0;
    }
    let target = opts.min_angle;
    let legs = work.legs();
    let mut sharp: Vec<(f64, u32)> = legs
        .keys()
        .filter_map(|&v| {
            let a = smallest_angle(work, &legs, v)?;
            (a < target).then_some((a, v))
        })
        .collect();
    sharp.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut repaired = 0;
    for (_, v) in sharp {
        if smallest_angle(work, &legs, v).is_none_or(|a| a >= target) {
            continue;
        }
        let (i, j) = sharpest_pair(work, &legs[&v], v);
        let movers = [v, legs[&v][i].other, legs[&v][j].other];
        'movers: for m in movers {
            for _ in 0..WALKS {
                if !improve(work, guide, &legs, m, target, opts.max_deviation) {
                    break;
                }
                if smallest_angle(work, &legs, v).is_some_and(|a| a >= target) {
                    repaired += 1;
                    break 'movers;
                }
            }
        }
    }
    repaired
}

/// The kept nodes where two members still meet under the minimum angle, in node order.
pub(super) fn sharp(work: &Work, opts: &Options) -> Vec<u32> {
    if opts.min_angle <= 0.0 {
        return Vec::new();
    }
    let legs = work.legs();
    legs.keys()
        .copied()
        .filter(|&v| smallest_angle(work, &legs, v).is_some_and(|a| a < opts.min_angle))
        .collect()
}

fn direction(work: &Work, from: u32, to: u32) -> DVec3 {
    (work.pos[to as usize] - work.pos[from as usize]).normalize_or_zero()
}

fn angle(u: DVec3, v: DVec3) -> f64 {
    u.dot(v).clamp(-1.0, 1.0).acos().to_degrees()
}

/// The smallest angle between two members at `v`, degrees; None with fewer than two.
pub(super) fn smallest_angle(work: &Work, legs: &BTreeMap<u32, Vec<Leg>>, v: u32) -> Option<f64> {
    let list = legs.get(&v)?;
    if list.len() < 2 {
        return None;
    }
    let (i, j) = sharpest_pair(work, list, v);
    Some(angle(
        direction(work, v, list[i].other),
        direction(work, v, list[j].other),
    ))
}

fn sharpest_pair(work: &Work, list: &[Leg], v: u32) -> (usize, usize) {
    let dirs: Vec<DVec3> = list.iter().map(|l| direction(work, v, l.other)).collect();
    let mut best = (f64::INFINITY, 0, 1);
    for i in 0..dirs.len() {
        for j in i + 1..dirs.len() {
            let a = angle(dirs[i], dirs[j]);
            if a < best.0 {
                best = (a, i, j);
            }
        }
    }
    (best.1, best.2)
}

/// Moves node `m` to the best trial position if that is better than where it is. Returns
/// whether it moved.
fn improve(
    work: &mut Work,
    guide: &Guide,
    legs: &BTreeMap<u32, Vec<Leg>>,
    m: u32,
    target: f64,
    max_deviation: f64,
) -> bool {
    let Some(own) = legs.get(&m) else {
        return false;
    };
    let mut affected: Vec<u32> = own.iter().map(|l| l.other).collect();
    affected.push(m);
    affected.sort_unstable();
    affected.dedup();
    let score = |work: &Work| {
        let mut least = f64::INFINITY;
        let mut sum = 0.0;
        for &x in &affected {
            if let Some(a) = smallest_angle(work, legs, x) {
                least = least.min(a.min(target));
                sum += a.min(target);
            }
        }
        (least, sum)
    };
    let holds = |work: &Work| {
        own.iter()
            .all(|l| work.member_deviation(l.line, l.member) <= max_deviation)
    };
    let home = work.pos[m as usize];
    let mut best = (score(work), home);
    let normal = match guide.normals[m as usize] {
        n if n != DVec3::ZERO => n,
        _ => plane_of(work, own, m),
    };
    for trial in guide.ring(home, normal, max_deviation) {
        work.pos[m as usize] = trial;
        if !holds(work) {
            continue;
        }
        let s = score(work);
        let better = s.0 > best.0 .0 + 1e-9 || (s.0 >= best.0 .0 - 1e-12 && s.1 > best.0 .1 + 1e-9);
        if better {
            best = (s, trial);
        }
    }
    work.pos[m as usize] = best.1;
    best.1 != home
}

/// With no normal known: the plane of the node's two sharpest members (or +Z).
fn plane_of(work: &Work, own: &[Leg], m: u32) -> DVec3 {
    if own.len() >= 2 {
        let (i, j) = sharpest_pair(work, own, m);
        let n = direction(work, m, own[i].other).cross(direction(work, m, own[j].other));
        if let Some(n) = n.try_normalize() {
            return n;
        }
    }
    DVec3::Z
}
