//! Cholesky factorisation of kernel matrices with faer, adding a diagonal
//! jitter in growing steps when the matrix is numerically indefinite, and
//! reporting how much was used (as GPy's `jitchol`, but never silently).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::matmul::triangular::{BlockStructure, matmul};
use faer::linalg::triangular_inverse::invert_lower_triangular;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Accum, Mat, MatRef};

use crate::RegressorError;
use crate::dense::{copy_lower_triangle, par, recycle, scratch, symmetrize_from_lower};

/// Jitter steps relative to the mean diagonal: 0, then 1e-10, 1e-9, … 1e-3.
const RELATIVE_JITTERS: [f64; 9] = [0.0, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3];

/// A lower Cholesky factor `L Lᵀ = K + jitter·I`.
#[derive(Debug, Clone)]
pub struct Cholesky {
    /// The lower factor (upper triangle zero).
    pub l: Mat<f64>,
    /// The absolute diagonal jitter that was added (0 when none was needed).
    pub jitter: f64,
}

impl Cholesky {
    /// Factorises `k` (consumed: the factor overwrites it).
    ///
    /// # Errors
    /// [`RegressorError::NotPositiveDefinite`] when even the largest jitter
    /// fails, or when `k` holds NaN.
    pub fn factor(k: Mat<f64>) -> Result<Self, RegressorError> {
        Self::factor_shifted(&k, 0.0)
    }

    /// Factorises `k + shift·I` (e.g. a kernel matrix plus its noise
    /// variance) without modifying `k`, reading only its lower triangle:
    /// one copy of that is made, and made again only when a jitter has to
    /// be retried.
    ///
    /// # Errors
    /// As [`Cholesky::factor`].
    pub fn factor_shifted(k: &Mat<f64>, shift: f64) -> Result<Self, RegressorError> {
        let n = k.nrows();
        let mean_diag = (0..n).map(|i| (k[(i, i)] + shift).abs()).sum::<f64>() / n.max(1) as f64;
        let scale = if mean_diag.is_finite() && mean_diag > 0.0 {
            mean_diag
        } else {
            1.0
        };
        let mut buffer = MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(
            n,
            par(),
            Default::default(),
        ));
        // A failed attempt leaves a partly overwritten matrix (faer zeroes
        // the failing column, upper part included), so every attempt starts
        // from a fresh copy of `k`.
        let mut work = crate::dense::scratch(n, n);
        copy_lower_triangle(&mut work, k.as_ref());
        for (attempt, relative) in RELATIVE_JITTERS.iter().enumerate() {
            let jitter = relative * scale;
            if attempt > 0 {
                copy_lower_triangle(&mut work, k.as_ref());
            }
            for i in 0..n {
                work[(i, i)] += shift;
                if jitter > 0.0 {
                    work[(i, i)] += jitter;
                }
            }
            let result = llt::factor::cholesky_in_place(
                work.as_mut(),
                LltRegularization::default(),
                par(),
                MemStack::new(&mut buffer),
                Default::default(),
            );
            let finite = (0..n).all(|i| work[(i, i)].is_finite());
            if result.is_ok() && finite {
                for j in 1..n {
                    for i in 0..j {
                        work[(i, j)] = 0.0;
                    }
                }
                return Ok(Self { l: work, jitter });
            }
        }
        Err(RegressorError::NotPositiveDefinite {
            n,
            jitter_tried: RELATIVE_JITTERS[RELATIVE_JITTERS.len() - 1] * scale,
        })
    }

    /// `log |K| = 2 Σ log L_ii`.
    pub fn log_det(&self) -> f64 {
        2.0 * (0..self.l.nrows())
            .map(|i| self.l[(i, i)].ln())
            .sum::<f64>()
    }

    /// `K⁻¹ B`.
    pub fn solve(&self, b: MatRef<'_, f64>) -> Mat<f64> {
        let mut x = b.to_owned();
        let mut buffer = MemBuffer::new(llt::solve::solve_in_place_scratch::<f64>(
            self.l.nrows(),
            b.ncols(),
            par(),
        ));
        llt::solve::solve_in_place(
            self.l.as_ref(),
            x.as_mut(),
            par(),
            MemStack::new(&mut buffer),
        );
        x
    }

    /// `L⁻¹ B`.
    pub fn solve_lower(&self, b: MatRef<'_, f64>) -> Mat<f64> {
        let mut x = b.to_owned();
        solve_lower_triangular_in_place(self.l.as_ref(), x.as_mut(), par());
        x
    }

    /// `L⁻ᵀ B`.
    pub fn solve_upper(&self, b: MatRef<'_, f64>) -> Mat<f64> {
        let mut x = b.to_owned();
        solve_upper_triangular_in_place(self.l.transpose(), x.as_mut(), par());
        x
    }

    /// `K⁻¹` (full, symmetric).
    pub fn inverse(&self) -> Mat<f64> {
        let mut out = self.inverse_lower();
        symmetrize_from_lower(&mut out);
        out
    }

    /// `K⁻¹` in its lower triangle: `L⁻¹` by faer's triangular inverse,
    /// then `L⁻ᵀ L⁻¹` by its triangular product, reading and writing
    /// nothing above the diagonal. The upper triangle of the result is
    /// unspecified (a recycled buffer's old values); [`Cholesky::inverse`]
    /// mirrors the lower one into it.
    ///
    /// faer's own `llt::inverse` does the same two steps but allocates the
    /// `n × n` intermediate afresh on every call (8 MB of page faults at
    /// n = 1000); here both buffers are recycled ([`crate::dense::scratch`]).
    pub fn inverse_lower(&self) -> Mat<f64> {
        let n = self.l.nrows();
        let mut l_inv = scratch(n, n);
        invert_lower_triangular(l_inv.as_mut(), self.l.as_ref(), par());
        let mut out = scratch(n, n);
        matmul(
            out.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            l_inv.transpose(),
            BlockStructure::TriangularUpper,
            l_inv.as_ref(),
            BlockStructure::TriangularLower,
            1.0,
            par(),
        );
        recycle(l_inv);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_solves_and_inverts_a_spd_matrix() {
        let n = 6;
        let a = Mat::from_fn(n, n, |i, j| {
            1.0 / (1.0 + i as f64 + j as f64) + if i == j { 1.0 } else { 0.0 }
        });
        let c = Cholesky::factor(a.clone()).unwrap();
        assert_eq!(c.jitter, 0.0);
        let rebuilt = &c.l * c.l.transpose();
        assert!((&rebuilt - &a).norm_max() < 1e-13);
        let inv = c.inverse();
        let eye = &a * &inv;
        assert!((&eye - Mat::<f64>::identity(n, n)).norm_max() < 1e-12);
        let b = Mat::from_fn(n, 2, |i, j| (i + 3 * j) as f64);
        assert!((&a * c.solve(b.as_ref()) - &b).norm_max() < 1e-11);
        let two_step = c.solve_upper(c.solve_lower(b.as_ref()).as_ref());
        assert!((&two_step - c.solve(b.as_ref())).norm_max() < 1e-11);
    }

    #[test]
    fn reads_only_the_lower_triangle() {
        let n = 300;
        let a = Mat::from_fn(n, n, |i, j| {
            (-((i as f64 - j as f64) / 40.0).powi(2)).exp() + if i == j { 0.1 } else { 0.0 }
        });
        let upper_nan = Mat::from_fn(n, n, |i, j| if i >= j { a[(i, j)] } else { f64::NAN });
        let full = Cholesky::factor_shifted(&a, 0.5).unwrap();
        let lower = Cholesky::factor_shifted(&upper_nan, 0.5).unwrap();
        assert_eq!(lower.l, full.l);
        assert_eq!(lower.jitter, 0.0);
    }

    #[test]
    fn inverse_lower_equals_faers_inverse_from_poisoned_buffers() {
        let n = 300;
        let a = Mat::from_fn(n, n, |i, j| {
            (-((i as f64 - j as f64) / 40.0).powi(2)).exp() + if i == j { 0.1 } else { 0.0 }
        });
        let c = Cholesky::factor(a.clone()).unwrap();
        // The recycled buffers the inverse works in hold NaN everywhere.
        crate::dense::release_spare();
        for _ in 0..2 {
            recycle(Mat::from_fn(n, n, |_, _| f64::NAN));
        }
        let ours = c.inverse_lower();
        let mut reference = Mat::<f64>::zeros(n, n);
        llt::inverse::inverse(
            reference.as_mut(),
            c.l.as_ref(),
            faer::Par::Seq,
            MemStack::new(&mut MemBuffer::new(llt::inverse::inverse_scratch::<f64>(
                n,
                faer::Par::Seq,
            ))),
        );
        for j in 0..n {
            for i in j..n {
                assert_eq!(
                    ours[(i, j)].to_bits(),
                    reference[(i, j)].to_bits(),
                    "({i}, {j})"
                );
            }
        }
        // And the full inverse is symmetric with no NaN left above.
        let full = c.inverse();
        assert!((0..n).all(|j| (0..n).all(|i| full[(i, j)] == full[(j, i)])));
        crate::dense::release_spare();
    }

    #[test]
    fn adds_and_reports_jitter_for_a_singular_matrix() {
        // Rank one: v vᵀ.
        let v = [1.0, 2.0, 3.0, 4.0];
        let a = Mat::from_fn(4, 4, |i, j| v[i] * v[j]);
        let c = Cholesky::factor(a.clone()).unwrap();
        assert!(c.jitter > 0.0, "a rank-one matrix needs jitter");
        // The retry started from the original matrix: L Lᵀ = A + jitter·I.
        let rebuilt = &c.l * c.l.transpose();
        let expected = &a + Mat::<f64>::identity(4, 4) * c.jitter;
        assert!((&rebuilt - &expected).norm_max() < 1e-9);
        assert!(c.jitter < 1e-2 * 7.5);
    }

    #[test]
    fn refuses_nan_instead_of_returning_it() {
        let mut a = Mat::<f64>::identity(3, 3);
        a[(1, 1)] = f64::NAN;
        assert!(matches!(
            Cholesky::factor(a),
            Err(RegressorError::NotPositiveDefinite { .. })
        ));
    }
}
