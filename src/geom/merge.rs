//! Merging points that coincide within a tolerance: shared corners of polylines and meshes.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use super::KeyHasher;

type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<KeyHasher>>;

/// Points per parallel task when looking for neighbours.
const CHUNK: usize = 1 << 14;

/// Maps each point to the index of the earliest kept point within `tol` (or a new index), and
/// returns the kept points in order of first appearance: a point is kept when no earlier kept
/// point lies within `tol`, and the first point of a cluster gives the node its position.
/// -0 and 0 are one value; `tol = 0` merges equal coordinates only.
///
/// Deterministic and independent of the number of threads: the points are bucketed by grid
/// cell (a counting sort, members of a bucket in input order), every point's earlier
/// neighbours are found in parallel, and only the few points that have any are then resolved
/// in input order. Where a cell is crowded (a point would look at more than `CROWD` others,
/// as in a thousand lines meeting at one jittered corner) the points are merged one by one
/// instead, which only ever compares a point with kept points.
pub fn merge_points(points: &[DVec3], tol: f64) -> (Vec<u32>, Vec<DVec3>) {
    if points.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let grid = Grid::new(points, tol.max(0.0));
    match earlier_neighbours(points, &grid) {
        Some(close) => resolve(points, &close),
        None => merge_in_order(points, &grid),
    }
}

/// Buckets are sorted in 2^PART_BITS parts, one thread each.
const PART_BITS: u32 = 6;

/// Points one point may be compared with before its cell counts as crowded.
const CROWD: usize = 64;

/// Every pair (point, earlier point within the tolerance), in increasing order of the first;
/// `None` if some cell is crowded.
fn earlier_neighbours(points: &[DVec3], grid: &Grid) -> Option<Vec<(u32, u32)>> {
    let buckets = Buckets::build(points, grid);
    let crowded = AtomicBool::new(false);
    // Bucket by bucket, so that the home cell's points are read in memory order.
    let mut close: Vec<(u32, u32)> = buckets
        .parts
        .par_iter()
        .flat_map(|part| part.members.par_chunks(CHUNK))
        .flat_map_iter(|chunk| {
            let mut found = Vec::new();
            if crowded.load(Ordering::Relaxed) {
                return found;
            }
            for &(p, i) in chunk {
                let mut looked = 0;
                grid.near_cells(&p, |cell| {
                    for &(q, j) in buckets.members(cell) {
                        if j >= i || looked > CROWD {
                            break; // members are in input order
                        }
                        looked += 1;
                        if grid.close(&q, &p) {
                            found.push((i, j));
                            if grid.exact() {
                                break; // the earliest equal point is always kept
                            }
                        }
                    }
                });
                if looked > CROWD {
                    crowded.store(true, Ordering::Relaxed);
                    break;
                }
            }
            found
        })
        .collect();
    if crowded.into_inner() {
        return None;
    }
    close.par_sort_unstable();
    Some(close)
}

/// A point joins the earliest kept point among its earlier neighbours. Those all come before
/// it, so in input order each is settled before it is asked about.
fn resolve(points: &[DVec3], close: &[(u32, u32)]) -> (Vec<u32>, Vec<DVec3>) {
    let mut joins: Vec<u32> = vec![u32::MAX; points.len()];
    for group in close.chunk_by(|a, b| a.0 == b.0) {
        let i = group[0].0 as usize;
        joins[i] = group
            .iter()
            .map(|&(_, j)| j)
            .filter(|&j| joins[j as usize] == u32::MAX)
            .min()
            .unwrap_or(u32::MAX);
    }
    let mut map = Vec::with_capacity(points.len());
    let mut nodes = Vec::new();
    for (i, p) in points.iter().enumerate() {
        let id = match joins[i] {
            u32::MAX => {
                nodes.push(*p);
                nodes.len() as u32 - 1
            }
            j => map[j as usize],
        };
        map.push(id);
    }
    (map, nodes)
}

/// The same rule one point at a time: each cell keeps a chain of its kept points (newest
/// first, linked through `next`), and a point is compared with the kept points of its near
/// cells only. Kept points are more than `tol` apart, so a chain stays short however many
/// points pile up in one place.
fn merge_in_order(points: &[DVec3], grid: &Grid) -> (Vec<u32>, Vec<DVec3>) {
    let mut map = Vec::with_capacity(points.len());
    let mut nodes: Vec<DVec3> = Vec::new();
    let mut newest: FastMap<u64, u32> = FastMap::default();
    let mut next: Vec<u32> = Vec::new();
    for p in points {
        let mut found = u32::MAX;
        grid.near_cells(p, |cell| {
            let mut at = newest.get(&cell).copied().unwrap_or(u32::MAX);
            while at != u32::MAX {
                if grid.close(&nodes[at as usize], p) {
                    found = found.min(at);
                }
                at = next[at as usize];
            }
        });
        if found == u32::MAX {
            found = nodes.len() as u32;
            nodes.push(*p);
            next.push(newest.insert(grid.home(p), found).unwrap_or(u32::MAX));
        }
        map.push(found);
    }
    (map, nodes)
}

/// A uniform grid over the points' bounding box. Cells are at least sixteen times the
/// tolerance, so a point farther than `tol` from its cell's faces can only meet points of its
/// own cell and most points look in one cell (a flat drawing lies mid-cell in z); at most 2³² cells per axis, so a tiny tolerance cannot turn
/// the cell index into noise. `tol = 0` keys points by their exact coordinates instead.
struct Grid {
    origin: DVec3,
    cell: f64,
    tol: f64,
    /// How near a face (in cells) a point must be for the neighbour across it to be searched.
    reach: f64,
}

impl Grid {
    fn new(points: &[DVec3], tol: f64) -> Grid {
        let (lo, hi) = points
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            });
        let span = (hi - lo).max_element();
        let cell = (16.0 * tol).max(span * 2f64.powi(-32));
        Grid {
            // Half a cell in from the box, so that a flat drawing lies mid-cell in z.
            origin: lo - 0.5 * cell,
            cell,
            tol,
            // The slack covers rounding in the cell coordinate (at most 2⁻²⁰ of a cell).
            reach: tol / cell + 1e-4,
        }
    }

    fn exact(&self) -> bool {
        self.tol == 0.0
    }

    fn close(&self, a: &DVec3, b: &DVec3) -> bool {
        if self.exact() {
            a == b // -0 == 0
        } else {
            a.distance_squared(*b) <= self.tol * self.tol
        }
    }

    /// The cell of a point, hashed.
    fn home(&self, p: &DVec3) -> u64 {
        if self.exact() {
            // Adding +0 turns -0 into 0 and changes nothing else.
            return cell_hash([p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits));
        }
        let q = ((*p - self.origin) / self.cell).floor();
        cell_hash([q.x as u64, q.y as u64, q.z as u64])
    }

    /// Calls `visit` with the hash of every cell that can hold a point within `tol` of `p`.
    fn near_cells(&self, p: &DVec3, mut visit: impl FnMut(u64)) {
        if self.exact() {
            visit(self.home(p));
            return;
        }
        let q = (*p - self.origin) / self.cell;
        let base = q.floor();
        let frac = q - base;
        let side = |f: f64| -> i64 {
            if f <= self.reach {
                -1
            } else if f >= 1.0 - self.reach {
                1
            } else {
                0
            }
        };
        let side = [side(frac.x), side(frac.y), side(frac.z)];
        let key = [base.x as i64, base.y as i64, base.z as i64];
        for corner in 0..8 {
            // Corners that step along an axis with no near face are the home cell again.
            if (0..3).any(|a| corner & (1 << a) != 0 && side[a] == 0) {
                continue;
            }
            let step = |a: usize| if corner & (1 << a) != 0 { side[a] } else { 0 };
            visit(cell_hash([0, 1, 2].map(|a| (key[a] + step(a)) as u64)));
        }
    }
}

/// Mixes a cell's three coordinates into 64 bits. Two cells may share a hash: that only adds
/// candidates, each still tested by distance.
fn cell_hash(k: [u64; 3]) -> u64 {
    let mut h = k[0].wrapping_mul(0x9e37_79b9_7f4a_7c15);
    h = (h ^ k[1]).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    h = (h ^ k[2]).wrapping_mul(0x1656_67b1_9e37_79f9);
    h ^ (h >> 29)
}

/// Points with their indices, grouped by bucket (the top bits of the cell hash), each group in
/// input order. The positions are copied so that a bucket is read from one stretch of memory.
/// Buckets are stored in `2^PART_BITS` parts, built in parallel.
struct Buckets {
    shift: u32,
    /// Buckets per part, as a power of two.
    part_shift: u32,
    parts: Vec<Part>,
}

/// A run of consecutive buckets: where each ends in `members`.
struct Part {
    ends: Vec<u32>,
    members: Vec<(DVec3, u32)>,
}

impl Buckets {
    fn build(points: &[DVec3], grid: &Grid) -> Buckets {
        // About four points per bucket: a smaller table stays in cache.
        let bits = (points.len().next_power_of_two().trailing_zeros()).clamp(3, 33) - 2;
        let shift = 64 - bits;
        let of: Vec<u32> = points
            .par_iter()
            .map(|p| (grid.home(p) >> shift) as u32)
            .collect();
        // A stable counting sort in two passes: first into parts by the bucket's top bits (a
        // handful of write streams), then each part on its own thread into its buckets, whose
        // counters then fit in cache.
        let part_shift = bits - PART_BITS.min(bits);
        let parts = 1usize << (bits - part_shift);
        let mut part_start = vec![0usize; parts + 1];
        for &b in &of {
            part_start[(b >> part_shift) as usize + 1] += 1;
        }
        for k in 1..part_start.len() {
            part_start[k] += part_start[k - 1];
        }
        let mut fill = part_start.clone();
        let mut by_part = vec![0u32; points.len()];
        for (i, &b) in of.iter().enumerate() {
            let k = (b >> part_shift) as usize;
            by_part[fill[k]] = i as u32;
            fill[k] += 1;
        }
        let parts = (0..parts)
            .into_par_iter()
            .map(|k| {
                let ids = &by_part[part_start[k]..part_start[k + 1]];
                let local = |i: u32| (of[i as usize] as usize) & ((1 << part_shift) - 1);
                let mut ends = vec![0u32; 1 << part_shift];
                for &i in ids {
                    ends[local(i)] += 1;
                }
                let mut at = 0;
                for end in &mut ends {
                    let n = *end;
                    *end = at; // the bucket's start for now
                    at += n;
                }
                let mut members = vec![(DVec3::ZERO, 0u32); ids.len()];
                for &i in ids {
                    let end = &mut ends[local(i)];
                    members[*end as usize] = (points[i as usize], i);
                    *end += 1;
                }
                Part { ends, members }
            })
            .collect();
        Buckets {
            shift,
            part_shift,
            parts,
        }
    }

    fn members(&self, hash: u64) -> &[(DVec3, u32)] {
        let b = (hash >> self.shift) as usize;
        let part = &self.parts[b >> self.part_shift];
        let local = b & ((1 << self.part_shift) - 1);
        let start = if local == 0 { 0 } else { part.ends[local - 1] };
        &part.members[start as usize..part.ends[local] as usize]
    }
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

    /// The greedy rule spelled out the slow way: each point joins the earliest kept point
    /// within the tolerance.
    fn brute(points: &[DVec3], tol: f64) -> (Vec<u32>, Vec<DVec3>) {
        let (mut map, mut kept): (Vec<u32>, Vec<DVec3>) = (Vec::new(), Vec::new());
        for p in points {
            match kept.iter().position(|k| k.distance(*p) <= tol) {
                Some(k) => map.push(k as u32),
                None => {
                    map.push(kept.len() as u32);
                    kept.push(*p);
                }
            }
        }
        (map, kept)
    }

    #[test]
    fn merge_matches_the_greedy_rule_on_clustered_points() {
        // Clusters of points spread over a few tolerances, chains of near points (where the
        // order decides), across many cells and in more than one parallel chunk.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let tol = 0.01;
        let centres: Vec<DVec3> = (0..3000)
            .map(|_| DVec3::new(rnd(), rnd(), rnd() * 0.1) * 10.0)
            .collect();
        let points: Vec<DVec3> = (0..3 * CHUNK / 2)
            .map(|k| {
                let c = centres[k % centres.len()];
                c + (DVec3::new(rnd(), rnd(), rnd()) - 0.5) * 2.0 * tol
            })
            .collect();
        let fast = merge_points(&points, tol);
        assert_eq!(fast, brute(&points, tol));
        let grid = Grid::new(&points, tol);
        assert!(
            earlier_neighbours(&points, &grid).is_some(),
            "no crowded cell here"
        );
        assert_eq!(merge_in_order(&points, &grid), fast);
        assert!(fast.1.len() > centres.len(), "chains split clusters");
        assert!(fast.1.len() < points.len() * 3 / 4, "many points merge");
    }

    #[test]
    fn a_crowded_corner_is_merged_one_point_at_a_time() {
        // Two thousand line ends meeting at a jittered corner, and a second corner near it.
        let tol = 0.01;
        let points: Vec<DVec3> = (0..4000)
            .map(|k| {
                let jitter = DVec3::new((k % 7) as f64, (k % 11) as f64, 0.0) * 1e-4;
                let corner = if k % 2 == 0 {
                    DVec3::ZERO
                } else {
                    DVec3::X * 0.015
                };
                corner + jitter
            })
            .collect();
        let grid = Grid::new(&points, tol);
        assert!(earlier_neighbours(&points, &grid).is_none());
        let merged = merge_points(&points, tol);
        assert_eq!(merged, brute(&points, tol));
        assert_eq!(merged.1.len(), 2);
    }

    #[test]
    fn a_tiny_tolerance_on_a_large_drawing_still_merges_equal_points() {
        let points = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1e6, 1.0, 0.0),
            DVec3::new(1e6, 1.0 + 1e-300, 0.0),
            DVec3::new(1e6, 1.0, 0.0),
        ];
        let (map, nodes) = merge_points(&points, 1e-300);
        assert_eq!((map, nodes.len()), (vec![0, 1, 1, 1], 2));
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
