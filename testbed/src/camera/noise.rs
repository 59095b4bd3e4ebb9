//! Seeded value noise: a lattice of hashed values, interpolated with a
//! smoothstep, summed over octaves. Every value is a pure function of the
//! seed and the position, so images do not depend on the order (or the
//! thread) in which pixels are computed.

/// SplitMix64's finaliser: a well-mixed 64-bit hash.
pub(crate) fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A uniform value in `[0, 1)` for the lattice point `(i, j)` of `key`.
pub(crate) fn lattice(key: u64, i: i64, j: i64) -> f64 {
    let h = mix(key ^ mix(i as u64 ^ mix(j as u64)));
    (h >> 11) as f64 / (1u64 << 53) as f64
}

fn smooth(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// Value noise of `key` at `(x, y)` in lattice units, in `[0, 1)`.
pub(crate) fn value(key: u64, x: f64, y: f64) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (i, j) = (fx as i64, fy as i64);
    let (tx, ty) = (smooth(x - fx), smooth(y - fy));
    let a = lattice(key, i, j);
    let b = lattice(key, i + 1, j);
    let c = lattice(key, i, j + 1);
    let d = lattice(key, i + 1, j + 1);
    let top = a + (b - a) * tx;
    let bottom = c + (d - c) * tx;
    top + (bottom - top) * ty
}

/// Zero-mean multi-scale noise at `(x, y)` (m): octave `k` has cell size
/// `cell_m / 2^k` and amplitude `amplitudes[k]`, each octave centred on 0
/// (values in `[−a/2, a/2)`).
pub(crate) fn octaves(key: u64, x: f64, y: f64, cell_m: f64, amplitudes: &[f64]) -> f64 {
    let mut cell = cell_m;
    let mut sum = 0.0;
    for (k, a) in amplitudes.iter().enumerate() {
        if *a != 0.0 {
            sum += a * (value(mix(key ^ (k as u64 + 1)), x / cell, y / cell) - 0.5);
        }
        cell *= 0.5;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_a_function_of_key_and_position_within_its_range() {
        for k in 0..200 {
            let (x, y) = (k as f64 * 0.37 - 20.0, k as f64 * 0.11);
            let v = value(7, x, y);
            assert!((0.0..1.0).contains(&v));
            assert_eq!(v, value(7, x, y));
        }
        // Lattice points hold their hashed values exactly.
        assert_eq!(value(3, 4.0, -2.0), lattice(3, 4, -2));
        // Another key is another field.
        assert_ne!(value(3, 0.5, 0.5), value(4, 0.5, 0.5));
        // The mean of an octave is near 0.
        let mean: f64 = (0..10_000)
            .map(|i| {
                octaves(
                    9,
                    (i % 100) as f64 * 0.013,
                    (i / 100) as f64 * 0.017,
                    0.05,
                    &[1.0],
                )
            })
            .sum::<f64>()
            / 10_000.0;
        assert!(mean.abs() < 0.05, "{mean}");
    }
}
