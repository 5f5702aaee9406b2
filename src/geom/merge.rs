//! Merging points that coincide within a tolerance: shared corners of polylines and meshes.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use glam::DVec3;

use super::KeyHasher;

// Welding hashes every point read, and the default SipHash costs a third of a large import.
type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<KeyHasher>>;

/// Maps each point to the index of the first earlier point within `tol` (or a new index), and
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
    let cell = 2.0 * tol;
    let mut grid: FastMap<[i64; 3], Vec<u32>> = FastMap::default();
    grid.reserve(points.len());
    for p in points {
        let q = *p / cell;
        let base = q.floor();
        // For each axis: this cell, and the neighbour on the side the point is nearer to.
        let step = (q - base).cmplt(glam::DVec3::splat(0.5));
        let side = [
            if step.test(0) { -1 } else { 1 },
            if step.test(1) { -1 } else { 1 },
            if step.test(2) { -1 } else { 1 },
        ];
        let key = [base.x as i64, base.y as i64, base.z as i64];
        let mut found = None;
        'search: for corner in 0..8 {
            let k = [
                key[0] + if corner & 1 != 0 { side[0] } else { 0 },
                key[1] + if corner & 2 != 0 { side[1] } else { 0 },
                key[2] + if corner & 4 != 0 { side[2] } else { 0 },
            ];
            if let Some(ids) = grid.get(&k) {
                for &id in ids {
                    if nodes[id as usize].distance_squared(*p) <= tol * tol {
                        found = Some(id);
                        break 'search;
                    }
                }
            }
        }
        let id = found.unwrap_or_else(|| {
            nodes.push(*p);
            let id = nodes.len() as u32 - 1;
            grid.entry(key).or_default().push(id);
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
