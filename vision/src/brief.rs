//! The rotated BRIEF descriptor of an oriented keypoint: 256 binary
//! intensity tests on the blurred level, the test pattern turned by the
//! keypoint's angle.

use std::sync::OnceLock;

use crate::GrayImage;

/// A 256-bit binary descriptor.
pub type Descriptor = [u8; 32];

/// Radius of the orientation disc and of the pattern (pixels).
pub(crate) const PATCH_RADIUS: isize = 15;

/// `x.round()` as an integer, by truncating `x ± ½` (no call to the C
/// library's `round` where the CPU has no rounding instruction).
fn round_half_away(x: f64) -> isize {
    (x + 0.5f64.copysign(x)) as isize
}

/// The descriptor of `(x, y)` on the blurred level, the pattern rotated by
/// `angle`.
pub(crate) fn describe(blurred: &GrayImage, x: usize, y: usize, angle: f32) -> Descriptor {
    let (sin, cos) = f64::from(angle).sin_cos();
    let at = |(u, v): (i8, i8)| {
        let (u, v) = (f64::from(u), f64::from(v));
        let ru = round_half_away(u * cos - v * sin);
        let rv = round_half_away(u * sin + v * cos);
        blurred.get(x.wrapping_add_signed(ru), y.wrapping_add_signed(rv))
    };
    let mut out = [0u8; 32];
    for (k, (p, q)) in pattern().iter().enumerate() {
        if at(*p) < at(*q) {
            out[k / 8] |= 1 << (k % 8);
        }
    }
    out
}

/// One binary test: the offsets `(u, v)` of the two pixels compared.
type TestPair = ((i8, i8), (i8, i8));

/// BRIEF's 256 test pairs: isotropic Gaussian offsets of σ = 31/5 around
/// the keypoint, rounded, inside the disc of radius 15, the two points of
/// a pair distinct; drawn once from a fixed SplitMix64 stream.
fn pattern() -> &'static [TestPair; 256] {
    static PATTERN: OnceLock<[TestPair; 256]> = OnceLock::new();
    PATTERN.get_or_init(|| {
        let mut state = 0x0b5e_55ed_c0ff_ee00u64;
        let mut uniform = || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^= z >> 31;
            ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let sigma = 31.0 / 5.0;
        let mut point = || loop {
            // Box–Muller: two independent normals.
            let (a, b) = (uniform(), uniform());
            let r = sigma * (-2.0 * a.ln()).sqrt();
            let (s, c) = (std::f64::consts::TAU * b).sin_cos();
            let (u, v) = ((r * c).round() as isize, (r * s).round() as isize);
            if u * u + v * v <= PATCH_RADIUS * PATCH_RADIUS {
                return (u as i8, v as i8);
            }
        };
        let mut pairs = [((0, 0), (0, 0)); 256];
        for pair in &mut pairs {
            *pair = loop {
                let (p, q) = (point(), point());
                if p != q {
                    break (p, q);
                }
            };
        }
        pairs
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pattern_lies_in_the_disc_and_its_pairs_are_distinct() {
        let pairs = pattern();
        for (p, q) in pairs {
            assert_ne!(p, q);
            for (u, v) in [p, q] {
                assert!(i32::from(*u).pow(2) + i32::from(*v).pow(2) <= 225);
            }
        }
        let spread = pairs
            .iter()
            .map(|(p, _)| f64::from(p.0).powi(2))
            .sum::<f64>()
            / 256.0;
        assert!((spread.sqrt() - 6.2).abs() < 1.0, "{}", spread.sqrt());
    }
}
