//! The radial profiles `κ(r)` of the stationary kernels and the slope
//! `−κ'(r)/r` their gradients need, evaluated from `r²` over whole columns.
//!
//! The exponential is most of a Gram matrix's cost once the distances come
//! from a GEMM (about half of an RBF Gram at n = 1200, d = 28, with the C
//! library's scalar `exp`). Here it is a branch-free polynomial
//! ([`exp_kernel`]: Cody–Waite reduction by `ln 2`, the degree-13 Taylor
//! polynomial on `|x| ≤ ln 2 / 2` as in Agner Fog's vector class library,
//! then the power of two from the exponent bits), written as scalar code
//! that the compiler vectorises: the column loops run under `pulp`'s
//! run-time dispatch, with AVX2 and FMA where the processor has them. Every
//! step is an IEEE operation with one rounding (`mul_add` is fused on every
//! path), so a value is the same bits with or without AVX2, wherever in a
//! column it falls and however the columns are split between threads.

use pulp::{Arch, Simd, WithSimd};

/// Which stationary profile `κ(r)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// Squared exponential (RBF).
    Rbf,
    /// Matérn ν = 5/2.
    Matern52,
    /// Matérn ν = 3/2.
    Matern32,
}

/// Below this the result is 0 (the true value is below 2⁻¹⁰²², and the
/// exponent construction needs a normal power of two).
const EXP_UNDERFLOW: f64 = -708.39;

/// `1 / k!` for `k = 0..=13`, each `k!` exact in a double and divided
/// once.
const INV_FACTORIAL: [f64; 14] = {
    let mut out = [1.0; 14];
    let mut factorial = 1.0;
    let mut k = 1;
    while k < 14 {
        factorial *= k as f64;
        out[k] = 1.0 / factorial;
        k += 1;
    }
    out
};

/// `exp(a)` for the arguments a kernel produces (`a ≤ 0`), within 1 ulp of
/// the correctly rounded value (see the tests); 0 below −708.39, NaN for
/// NaN. Branch-free, so that a loop over it vectorises.
#[inline(always)]
pub fn exp_kernel(a: f64) -> f64 {
    const LOG2_E: f64 = std::f64::consts::LOG2_E;
    // ln 2 split so that `r · LN2_HI` is exact for |r| < 2¹⁰.
    const LN2_HI: f64 = 0.693_145_751_953_125;
    const LN2_LO: f64 = 1.428_606_820_309_417_3e-6;
    // 2⁵² + 1023: adding it puts `r + 1023` in the low mantissa bits.
    const EXPONENT_SHIFT: f64 = 4_503_599_627_371_519.0;
    let r = (a * LOG2_E).round_ties_even();
    let x = (-r).mul_add(LN2_HI, a);
    let x = (-r).mul_add(LN2_LO, x);
    // Σ_{k=1}^{13} x^k / k!, Estrin's scheme.
    let (x2, x4) = (x * x, x * x * (x * x));
    let x8 = x4 * x4;
    let p = x8.mul_add(
        x4.mul_add(
            x.mul_add(INV_FACTORIAL[13], INV_FACTORIAL[12]),
            x2.mul_add(
                x.mul_add(INV_FACTORIAL[11], INV_FACTORIAL[10]),
                x.mul_add(INV_FACTORIAL[9], INV_FACTORIAL[8]),
            ),
        ),
        x4.mul_add(
            x2.mul_add(
                x.mul_add(INV_FACTORIAL[7], INV_FACTORIAL[6]),
                x.mul_add(INV_FACTORIAL[5], INV_FACTORIAL[4]),
            ),
            x2.mul_add(x.mul_add(INV_FACTORIAL[3], INV_FACTORIAL[2]), x),
        ),
    );
    let two_r = f64::from_bits((r + EXPONENT_SHIFT).to_bits() << 52);
    let z = (p + 1.0) * two_r;
    if a < EXP_UNDERFLOW { 0.0 } else { z }
}

/// `(κ, −κ'/r)` of the squared exponential at `r²`.
#[inline(always)]
fn rbf(r2: f64) -> (f64, f64) {
    let k = exp_kernel(-0.5 * r2);
    (k, k)
}

/// `(κ, −κ'/r)` of the Matérn 5/2 at `r²`.
#[inline(always)]
fn matern52(r2: f64) -> (f64, f64) {
    let sr = (5.0 * r2).sqrt();
    let e = exp_kernel(-sr);
    ((1.0 + sr + 5.0 / 3.0 * r2) * e, 5.0 / 3.0 * (1.0 + sr) * e)
}

/// `(κ, −κ'/r)` of the Matérn 3/2 at `r²`.
#[inline(always)]
fn matern32(r2: f64) -> (f64, f64) {
    let sr = (3.0 * r2).sqrt();
    let e = exp_kernel(-sr);
    ((1.0 + sr) * e, 3.0 * e)
}

/// One column's profile, as a `pulp` operation (inlined into a function
/// compiled for the detected instruction set).
struct ApplyProfile<'a, F> {
    profile: F,
    variance: f64,
    r2: &'a mut [f64],
    slope: Option<&'a mut [f64]>,
}

impl<F: Fn(f64) -> (f64, f64)> WithSimd for ApplyProfile<'_, F> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) {
        let (profile, var) = (self.profile, self.variance);
        match self.slope {
            Some(slope) => {
                for (v, s) in self.r2.iter_mut().zip(slope.iter_mut()) {
                    let (k, sl) = profile(*v);
                    *v = var * k;
                    *s = var * sl;
                }
            }
            None => {
                for v in self.r2.iter_mut() {
                    *v = var * profile(*v).0;
                }
            }
        }
    }
}

impl Family {
    /// Replaces each `r²` of `r2` by `σ² κ(r)`, writing `σ²(−κ'(r)/r)` to
    /// the same position of `slope` when given (of the same length).
    pub fn apply(self, variance: f64, r2: &mut [f64], slope: Option<&mut [f64]>) {
        debug_assert!(slope.as_ref().is_none_or(|s| s.len() == r2.len()));
        let arch = Arch::new();
        match self {
            Self::Rbf => arch.dispatch(ApplyProfile {
                profile: rbf,
                variance,
                r2,
                slope,
            }),
            Self::Matern52 => arch.dispatch(ApplyProfile {
                profile: matern52,
                variance,
                r2,
                slope,
            }),
            Self::Matern32 => arch.dispatch(ApplyProfile {
                profile: matern32,
                variance,
                r2,
                slope,
            }),
        }
    }

    /// `(κ(r), −κ'(r)/r)` at one `r²` (the same arithmetic as
    /// [`Family::apply`]).
    pub fn profile(self, r2: f64) -> (f64, f64) {
        match self {
            Self::Rbf => rbf(r2),
            Self::Matern52 => matern52(r2),
            Self::Matern32 => matern32(r2),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place between two positive doubles.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    /// The scalar formulas with the C library's `exp`.
    fn reference(family: Family, r2: f64) -> (f64, f64) {
        match family {
            Family::Rbf => {
                let k = (-0.5 * r2).exp();
                (k, k)
            }
            Family::Matern52 => {
                let sr = (5.0 * r2).sqrt();
                let e = (-sr).exp();
                ((1.0 + sr + 5.0 / 3.0 * r2) * e, 5.0 / 3.0 * (1.0 + sr) * e)
            }
            Family::Matern32 => {
                let sr = (3.0 * r2).sqrt();
                let e = (-sr).exp();
                ((1.0 + sr) * e, 3.0 * e)
            }
        }
    }

    #[test]
    fn the_polynomial_exp_is_within_one_ulp_of_the_c_library_on_kernel_arguments() {
        // exp(a) for a in [−700, 0], the range of −r²/2 and −√5 r.
        let mut worst = 0;
        for i in 0..=200_000 {
            let a = -700.0 * (i as f64 / 200_000.0).powi(3);
            let got = exp_kernel(a);
            worst = worst.max(ulps(got, a.exp()));
        }
        assert!(worst <= 1, "worst {worst} ulp");
    }

    #[test]
    fn every_family_matches_its_scalar_formula() {
        for family in [Family::Rbf, Family::Matern52, Family::Matern32] {
            // 4·k + 3 values: full chunks and a partial one.
            let r2: Vec<f64> = (0..4003).map(|i| (i as f64 * 0.011).powi(2)).collect();
            let mut k = r2.clone();
            let mut s = vec![f64::NAN; r2.len()];
            family.apply(2.5, &mut k, Some(&mut s));
            for (i, &r2) in r2.iter().enumerate() {
                let (rk, rs) = reference(family, r2);
                let tol = |x: f64| 1e-14 * x.abs() + 1e-300;
                assert!(
                    (k[i] - 2.5 * rk).abs() <= tol(2.5 * rk),
                    "{family:?} κ at {r2}"
                );
                assert!(
                    (s[i] - 2.5 * rs).abs() <= tol(2.5 * rs),
                    "{family:?} slope at {r2}"
                );
                let (pk, ps) = family.profile(r2);
                assert_eq!((2.5 * pk, 2.5 * ps), (k[i], s[i]), "{family:?} {r2}");
            }
        }
    }

    #[test]
    fn a_value_does_not_depend_on_its_position_in_the_column() {
        let r2: Vec<f64> = (0..11).map(|i| i as f64 * 0.37).collect();
        let mut whole = r2.clone();
        Family::Matern52.apply(1.0, &mut whole, None);
        for start in 0..r2.len() {
            let mut tail = r2[start..].to_vec();
            Family::Matern52.apply(1.0, &mut tail, None);
            assert_eq!(tail, whole[start..]);
        }
    }

    #[test]
    fn nan_stays_nan_and_r_zero_gives_the_variance() {
        let mut v = [f64::NAN, 0.0, 1.0];
        Family::Rbf.apply(3.0, &mut v, None);
        assert!(v[0].is_nan());
        assert_eq!(v[1], 3.0);
        for family in [Family::Matern52, Family::Matern32] {
            let mut v = [0.0, f64::NAN];
            let mut s = [0.0; 2];
            family.apply(2.0, &mut v, Some(&mut s));
            assert_eq!(v[0], 2.0);
            assert!(v[1].is_nan() && s[1].is_nan(), "{family:?}");
        }
    }
}
