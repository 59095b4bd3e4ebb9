//! Hamming distances between 256-bit binary descriptors: one pair
//! ([`hamming`]), and each query's two nearest neighbours among many
//! ([`two_nearest_each`]), the brute-force loop compiled
//! for the processor's instruction set at run time (`pulp`'s dispatch:
//! with AVX2 the compiler counts a descriptor's bits with byte shuffles on
//! one 256-bit vector, without it with 128-bit arithmetic). Distances are
//! integers, so every path gives the same answer.

use pulp::{Arch, Simd, WithSimd};

use crate::brief::Descriptor;

/// The descriptor's bits as four 64-bit words.
#[inline(always)]
fn words(d: &Descriptor) -> [u64; 4] {
    std::array::from_fn(|k| {
        let mut w = [0u8; 8];
        w.copy_from_slice(&d[8 * k..8 * k + 8]);
        u64::from_le_bytes(w)
    })
}

/// The number of bits in which two descriptors differ.
#[inline]
pub fn hamming(a: &Descriptor, b: &Descriptor) -> u32 {
    distance(&words(a), &words(b))
}

#[inline(always)]
fn distance(a: &[u64; 4], b: &[u64; 4]) -> u32 {
    (a[0] ^ b[0]).count_ones()
        + (a[1] ^ b[1]).count_ones()
        + (a[2] ^ b[2]).count_ones()
        + (a[3] ^ b[3]).count_ones()
}

/// A query's nearest and second-nearest distances among some descriptors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TwoNearest {
    /// The smallest distance (`u32::MAX` among none).
    pub best: u32,
    /// The index of the first descriptor at `best` (`usize::MAX` among
    /// none).
    pub index: usize,
    /// The smallest distance of the others (`u32::MAX` among fewer than
    /// two).
    pub second: u32,
}

impl TwoNearest {
    const NONE: Self = Self {
        best: u32::MAX,
        index: usize::MAX,
        second: u32::MAX,
    };

    #[inline(always)]
    fn offer(&mut self, d: u32, k: usize) {
        if d < self.best {
            self.second = self.best;
            self.best = d;
            self.index = k;
        } else if d < self.second {
            self.second = d;
        }
    }
}

/// The two nearest of `train` to each of `queries`, in order.
pub fn two_nearest_each(queries: &[Descriptor], train: &[Descriptor]) -> Vec<TwoNearest> {
    Arch::new().dispatch(BruteForce { queries, train })
}

/// [`two_nearest_each`] as a `pulp` operation (inlined into a function
/// compiled for the detected instruction set).
struct BruteForce<'a> {
    queries: &'a [Descriptor],
    train: &'a [Descriptor],
}

impl WithSimd for BruteForce<'_> {
    type Output = Vec<TwoNearest>;

    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) -> Self::Output {
        // Plain loops, not closures: a closure handed to an iterator
        // adapter is compiled on its own, without the target's features
        // (here AVX2), and the distances then take twice as long.
        let mut train = Vec::with_capacity(self.train.len());
        for t in self.train {
            train.push(words(t));
        }
        let mut nearest = Vec::with_capacity(self.queries.len());
        for q in self.queries {
            let q = words(q);
            let mut found = TwoNearest::NONE;
            for (k, t) in train.iter().enumerate() {
                found.offer(distance(&q, t), k);
            }
            nearest.push(found);
        }
        nearest
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit by bit, as the definition says.
    fn reference(a: &Descriptor, b: &Descriptor) -> u32 {
        (0..256)
            .filter(|&k| (a[k / 8] >> (k % 8)) & 1 != (b[k / 8] >> (k % 8)) & 1)
            .count() as u32
    }

    fn descriptors(n: usize, seed: u64) -> Vec<Descriptor> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                std::array::from_fn(|_| {
                    state = state
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    (state >> 56) as u8
                })
            })
            .collect()
    }

    #[test]
    fn the_distance_counts_the_differing_bits() {
        let d = descriptors(40, 1);
        for a in &d {
            for b in &d {
                assert_eq!(hamming(a, b), reference(a, b));
            }
        }
        assert_eq!(hamming(&[0; 32], &[0xff; 32]), 256);
    }

    #[test]
    fn the_two_nearest_are_those_of_a_full_sort() {
        let (queries, train) = (descriptors(30, 2), descriptors(57, 3));
        for (q, found) in queries.iter().zip(two_nearest_each(&queries, &train)) {
            let mut all: Vec<(u32, usize)> = train
                .iter()
                .enumerate()
                .map(|(k, t)| (reference(q, t), k))
                .collect();
            all.sort_unstable();
            assert_eq!((found.best, found.index), all[0]);
            assert_eq!(found.second, all[1].0);
        }
        // A tie: the second equals the best; the first index is kept.
        let twice = [train[5], train[5]];
        let found = two_nearest_each(&[train[5]], &twice)[0];
        assert_eq!((found.best, found.index, found.second), (0, 0, 0));
        assert_eq!(two_nearest_each(&[train[0]], &[]), [TwoNearest::NONE]);
    }
}
