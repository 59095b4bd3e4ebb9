//! Conversions between pixel or cell indices and floats in the renderer's
//! inner loops, through `i64`: x86-64 converts signed integers in one
//! instruction and unsigned ones in several. Indices are far below 2⁶³,
//! so the values are those of the plain `as` conversions.

/// An index as a float: `k as f64`.
#[inline(always)]
pub(super) fn as_f64(k: usize) -> f64 {
    k as i64 as f64
}

/// The index below a coordinate `x ≥ 0` (or NaN, giving 0): `x as usize`,
/// which truncates and saturates, for any `x` below 2⁶³.
#[inline(always)]
pub(super) fn truncate(x: f64) -> usize {
    x as i64 as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_conversions_are_the_plain_ones() {
        for x in [
            0.0,
            0.25,
            0.999_999,
            1.0,
            7.5,
            1023.999,
            4.0e9,
            1.0e15,
            f64::NAN,
        ] {
            assert_eq!(truncate(x), x as usize, "{x}");
        }
        for k in [0usize, 1, 2, 511, 1 << 40] {
            assert_eq!(as_f64(k).to_bits(), (k as f64).to_bits());
        }
    }
}
