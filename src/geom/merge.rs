//! Merging points that coincide within a tolerance: shared corners of polylines and meshes.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use glam::DVec3;

use super::KeyHasher;

// Welding hashes every point read, and the default SipHash costs a third of a large import.
type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<KeyHasher>>;

/// Maps each point to the index of the earliest kept point within `tol` (or a new index), and
/// returns the kept points in order of first appearance. -0 and 0 are one value. With cells of twice the tolerance, the ball of radius `tol`
/// around a point touches at most two cells per axis, so eight lookups find every candidate.
pub fn merge_points(points: &[DVec3], tol: f64) -> (Vec<u32>, Vec<DVec3>) {
    let mut map = Vec::with_capacity(points.len());
    let mut nodes: Vec<DVec3> = Vec::new();
    if tol == 0.0 {
        let mut exact: FastMap<[u64; 3], u32> = FastMap::default();
        exact.reserve(points.len());
        for p in points {
            // Adding +0 turns -0 into 0 and changes nothing else.
            let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
            let id = *exact.entry(key).or_insert_with(|| {
                nodes.push(*p);
                nodes.len() as u32 - 1
            });
            map.push(id);
        }
        return (map, nodes);
    }
    // Cells of four times the tolerance: a point farther than `tol` from its cell's faces can
    // only meet points of its own cell, so most points look up one to three cells, not eight.
    let cell = 4.0 * tol;
    // Each grid cell holds the newest node in it; `next` chains a node to the one before it in
    // the same cell, so cells need no list of their own (no allocation per cell).
    let mut grid: FastMap<[i64; 3], u32> = FastMap::default();
    grid.reserve(points.len());
    let mut next: Vec<u32> = Vec::with_capacity(points.len());
    for p in points {
        let q = *p / cell;
        let base = q.floor();
        let frac = q - base;
        // For each axis: the neighbour on the side the point is nearer to, if within `tol` of
        // that face (in cell units, 1/4), else none.
        let near = |f: f64| -> i64 {
            if f <= 0.2501 {
                -1
            } else if f >= 0.7499 {
                1
            } else {
                0
            }
        };
        let side = [near(frac.x), near(frac.y), near(frac.z)];
        let key = [base.x as i64, base.y as i64, base.z as i64];
        let mut found = None;
        for corner in 0..8 {
            // Corners that step along an axis with no near face are the home cell again.
            if (0..3).any(|a| corner & (1 << a) != 0 && side[a] == 0) {
                continue;
            }
            let k = [
                key[0] + if corner & 1 != 0 { side[0] } else { 0 },
                key[1] + if corner & 2 != 0 { side[1] } else { 0 },
                key[2] + if corner & 4 != 0 { side[2] } else { 0 },
            ];
            let mut at = grid.get(&k).copied().unwrap_or(u32::MAX);
            // The chain runs newest first; the earliest match is the one to keep.
            while at != u32::MAX {
                if nodes[at as usize].distance_squared(*p) <= tol * tol {
                    found = Some(found.map_or(at, |f: u32| f.min(at)));
                }
                at = next[at as usize];
            }
        }
        let id = found.unwrap_or_else(|| {
            let id = nodes.len() as u32;
            nodes.push(*p);
            next.push(grid.insert(key, id).unwrap_or(u32::MAX));
            id
        });
        map.push(id);
    }
    (map, nodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_finds_neighbours_across_cell_borders() {
        // Points straddling a cell boundary on every axis still merge.
        let tol = 0.1;
        let a = DVec3::splat(0.2 - 1e-9);
        let b = DVec3::splat(0.2 + 1e-9);
        let (map, nodes) = merge_points(&[a, b], tol);
        assert_eq!(nodes.len(), 1);
        assert_eq!(map, vec![0, 0]);
    }

    #[test]
    fn minus_zero_is_zero() {
        let (map, nodes) = merge_points(
            &[DVec3::new(-0.0, 1.0, 0.0), DVec3::new(0.0, 1.0, -0.0)],
            0.0,
        );
        assert_eq!((map, nodes.len()), (vec![0, 0], 1));
    }
}
