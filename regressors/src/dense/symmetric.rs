//! Symmetric `n × n` matrices stored by their lower triangle (what is above
//! the diagonal is never read): an exact-GP evaluation computes `K`, `S`,
//! `W` and `W ∘ S` only on and below the diagonal, which halves the
//! distance GEMM, the kernel profile's `exp`, and every pass over `n²`.

use faer::linalg::matmul::triangular::{BlockStructure, matmul};
use faer::{Accum, Mat, MatRef};

use super::{column, column_mut, par};

/// Copies the lower triangle onto the upper one.
pub fn symmetrize_from_lower(a: &mut Mat<f64>) {
    let n = a.nrows();
    for j in 0..n {
        for i in 0..j {
            a[(i, j)] = a[(j, i)];
        }
    }
}

/// Copies the lower triangle of `src` (diagonal included) into `dst`, one
/// slice copy per column; what is above the diagonal of `dst` is left as
/// it was (faer's `copy_from_triangular_lower`, an element-wise zip, was
/// 1.4 % of a `paper.yaml` profile).
pub fn copy_lower_triangle(dst: &mut Mat<f64>, src: MatRef<'_, f64>) {
    for j in 0..src.ncols() {
        let source = column(src, j);
        column_mut(dst, j)[j..].copy_from_slice(&source[j..]);
    }
}

/// `A B` for a symmetric `A` given by its lower triangle: `tril(A) B +
/// stril(A)ᵀ B`, two triangular products by faer (the same flops as one
/// full GEMM, reading half of `A`).
pub fn symmetric_times(a_lower: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a_lower.nrows(), b.ncols());
    matmul(
        out.as_mut(),
        BlockStructure::Rectangular,
        Accum::Replace,
        a_lower,
        BlockStructure::TriangularLower,
        b,
        BlockStructure::Rectangular,
        1.0,
        par(),
    );
    matmul(
        out.as_mut(),
        BlockStructure::Rectangular,
        Accum::Add,
        a_lower.transpose(),
        BlockStructure::StrictTriangularUpper,
        b,
        BlockStructure::Rectangular,
        1.0,
        par(),
    );
    out
}

/// `A ← A ∘ B` on and below the diagonal.
pub fn lower_hadamard_in_place(a: &mut Mat<f64>, b_lower: MatRef<'_, f64>) {
    for j in 0..a.ncols() {
        let cb = column(b_lower, j);
        for (x, y) in column_mut(a, j)[j..].iter_mut().zip(&cb[j..]) {
            *x *= y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric matrix, and a copy of its lower triangle with NaN above.
    fn symmetric_and_lower(n: usize) -> (Mat<f64>, Mat<f64>) {
        let full = Mat::from_fn(n, n, |i, j| ((i * j + i + j) % 7) as f64 - 2.5);
        let lower = Mat::from_fn(n, n, |i, j| if i >= j { full[(i, j)] } else { f64::NAN });
        (full, lower)
    }

    #[test]
    fn the_symmetric_product_reads_only_the_lower_triangle() {
        let (full, lower) = symmetric_and_lower(37);
        let b = Mat::from_fn(37, 5, |i, q| (i as f64 * 0.3 - q as f64).sin());
        let expected = &full * &b;
        let got = symmetric_times(lower.as_ref(), b.as_ref());
        assert!((&got - &expected).norm_max() < 1e-12);
    }

    #[test]
    fn the_lower_hadamard_reads_only_the_lower_triangle() {
        let (full_a, lower_a) = symmetric_and_lower(23);
        let full_b = Mat::from_fn(23, 23, |i, j| 1.0 + (i + j) as f64 * 0.1);
        let mut product = lower_a.clone();
        lower_hadamard_in_place(&mut product, full_b.as_ref());
        for j in 0..23 {
            for i in j..23 {
                assert_eq!(product[(i, j)], full_a[(i, j)] * full_b[(i, j)]);
            }
        }
    }

    #[test]
    fn the_lower_copy_leaves_the_upper_triangle_alone() {
        let (full, lower) = symmetric_and_lower(9);
        let mut dst = Mat::from_fn(9, 9, |_, _| 7.0);
        copy_lower_triangle(&mut dst, lower.as_ref());
        for j in 0..9 {
            for i in 0..9 {
                let expected = if i >= j { full[(i, j)] } else { 7.0 };
                assert_eq!(dst[(i, j)], expected, "({i}, {j})");
            }
        }
    }

    #[test]
    fn symmetrize_copies_the_lower_triangle_up() {
        let (full, mut lower) = symmetric_and_lower(9);
        symmetrize_from_lower(&mut lower);
        assert_eq!(lower, full);
    }
}
