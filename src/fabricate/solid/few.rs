//! A short list of numbers kept in place, spilling to the heap only when it outgrows `N`: the
//! mesher and simplifier keep one per edge or per vertex, millions of them, and a `Vec` each
//! costs an allocation each and, freeing them all, seconds (1.8 s for the bisection's lists on
//! the 12,700-node leaf).

use std::ops::Deref;

/// Up to `N` numbers in place, more in a `Vec`; derefs to the slice of them, in the order
/// pushed.
#[derive(Clone, Debug)]
pub enum Few<const N: usize> {
    In(u8, [u32; N]),
    Spilled(Vec<u32>),
}

impl<const N: usize> Default for Few<N> {
    fn default() -> Self {
        let () = Self::COUNTED;
        Few::In(0, [0; N])
    }
}

impl<const N: usize> Deref for Few<N> {
    type Target = [u32];
    fn deref(&self) -> &[u32] {
        match self {
            Few::In(n, items) => &items[..*n as usize],
            Few::Spilled(items) => items,
        }
    }
}

impl<'a, const N: usize> IntoIterator for &'a Few<N> {
    type Item = &'a u32;
    type IntoIter = std::slice::Iter<'a, u32>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl<const N: usize> Few<N> {
    /// The count in place is a `u8` (checked when the type is used).
    const COUNTED: () = assert!(N <= u8::MAX as usize, "Few keeps at most 255 in place");

    pub fn push(&mut self, x: u32) {
        match self {
            Few::In(n, items) if (*n as usize) < N => {
                items[*n as usize] = x;
                *n += 1;
            }
            Few::In(_, items) => {
                let mut all = Vec::with_capacity(2 * N);
                all.extend_from_slice(items);
                all.push(x);
                *self = Few::Spilled(all);
            }
            Few::Spilled(items) => items.push(x),
        }
    }

    /// Keeps the numbers `keep` accepts, in their order.
    pub fn retain(&mut self, mut keep: impl FnMut(u32) -> bool) {
        match self {
            Few::In(n, items) => {
                let mut kept = 0;
                for k in 0..*n as usize {
                    if keep(items[k]) {
                        items[kept] = items[k];
                        kept += 1;
                    }
                }
                *n = kept as u8;
            }
            Few::Spilled(items) => items.retain(|&x| keep(x)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_few_keeps_order_through_spilling_and_retaining() {
        let mut few: Few<3> = Few::default();
        assert!(few.is_empty());
        let mut plain = Vec::new();
        for x in [5, 1, 9, 1, 7, 3, 1] {
            few.push(x);
            plain.push(x);
            assert_eq!(&*few, &plain[..]);
        }
        assert!(matches!(few, Few::Spilled(_)));
        few.retain(|x| x != 1);
        plain.retain(|&x| x != 1);
        assert_eq!(&*few, &plain[..]);
        let mut small: Few<4> = Few::default();
        for x in [2, 4, 2] {
            small.push(x);
        }
        small.retain(|x| x != 2);
        assert_eq!(&*small, &[4]);
        assert!(matches!(small, Few::In(1, _)));
        assert_eq!(small.iter().copied().sum::<u32>(), 4);
    }
}
