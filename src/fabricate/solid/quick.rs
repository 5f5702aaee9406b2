//! A quick hash for the mesher's and simplifier's maps, keyed by vertex numbers, edge keys and
//! grid points: the std hasher resists collision attacks, which these maps do not need, at
//! several times the cost (SipHash was a fifth of the grid refinement's time on the
//! 12,700-node leaf). Fixed, not seeded, so a map's order is the same on every run.

use std::hash::{BuildHasher, Hasher};

/// Builds [`QuickHasher`]s.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quick;

impl BuildHasher for Quick {
    type Hasher = QuickHasher;
    fn build_hasher(&self) -> QuickHasher {
        QuickHasher(0)
    }
}

/// A multiply-rotate hash taking a word at a time.
#[derive(Clone, Copy, Debug)]
pub struct QuickHasher(u64);

impl QuickHasher {
    fn word(&mut self, k: u64) {
        self.0 = (self.0 ^ k)
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .rotate_left(29);
    }
}

impl Hasher for QuickHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            let mut b = [0u8; 8];
            b.copy_from_slice(w);
            self.word(u64::from_le_bytes(b));
        }
        let rest = words.remainder();
        if !rest.is_empty() {
            let mut b = [0u8; 8];
            b[..rest.len()].copy_from_slice(rest);
            // The length marks the tail, so [1] and [1, 0] differ.
            self.word(u64::from_le_bytes(b) ^ (rest.len() as u64) << 59);
        }
    }
    fn write_u8(&mut self, k: u8) {
        self.word(k as u64);
    }
    fn write_u32(&mut self, k: u32) {
        self.word(k as u64);
    }
    fn write_u64(&mut self, k: u64) {
        self.word(k);
    }
    fn write_usize(&mut self, k: usize) {
        self.word(k as u64);
    }
    fn write_i64(&mut self, k: i64) {
        self.word(k as u64);
    }
}

/// A `HashMap` with the quick hash.
pub type QuickMap<K, V> = std::collections::HashMap<K, V, Quick>;
/// A `HashSet` with the quick hash.
pub type QuickSet<K> = std::collections::HashSet<K, Quick>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_points_spread_over_the_table() {
        // Neighbouring grid points land in distinct low bits, also as the refinement stores
        // them (in fine units: multiples of 64, their low bits all zero).
        for unit in [1i64, 64] {
            let mut low = std::collections::HashSet::new();
            for x in 0..16i64 {
                for y in 0..16i64 {
                    for z in 0..16i64 {
                        low.insert(Quick.hash_one([x, y, z].map(|c| c * unit)) & 0xffff);
                    }
                }
            }
            assert!(low.len() > 3900, "{} of 4096 distinct", low.len());
        }
    }
}
