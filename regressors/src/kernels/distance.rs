//! Scaled squared distances `r²_ij = Σ_q (x_iq − x'_jq)² / ℓ_q²` computed as
//! `|z_i|² + |z'_j|² − 2 z_i·z'_j` with one matrix product (`z = x / ℓ`),
//! the `O(n²d)` part done by faer's GEMM. Columns are centred first
//! (distances are translation invariant), which keeps the cancellation in
//! `|z|² − 2 z·z'` small.

use faer::{Accum, Mat, MatRef};

use faer::linalg::matmul::triangular::{self, BlockStructure};

use crate::dense::{for_column_blocks, gemm, par};

/// Column means of `x`.
pub fn column_means(x: MatRef<'_, f64>) -> Vec<f64> {
    let n = x.nrows().max(1) as f64;
    (0..x.ncols())
        .map(|q| x.col(q).iter().sum::<f64>() / n)
        .collect()
}

/// Rows used by [`median_pairwise_distance`] at most (evenly strided).
const MEDIAN_ROWS: usize = 400;

/// The median Euclidean distance between distinct rows of `x` (the
/// "median heuristic" for a lengthscale), over at most 400 evenly strided
/// rows so that it stays cheap at any `n`; `None` with fewer than two rows
/// or when every distance is zero.
pub fn median_pairwise_distance(x: MatRef<'_, f64>) -> Option<f64> {
    let n = x.nrows();
    let stride = n.div_ceil(MEDIAN_ROWS).max(1);
    let rows: Vec<usize> = (0..n).step_by(stride).collect();
    let mut distances = Vec::with_capacity(rows.len() * rows.len().saturating_sub(1) / 2);
    for (a, &i) in rows.iter().enumerate() {
        for &j in &rows[a + 1..] {
            let sq: f64 = (0..x.ncols())
                .map(|q| (x[(i, q)] - x[(j, q)]).powi(2))
                .sum();
            distances.push(sq.sqrt());
        }
    }
    if distances.is_empty() {
        return None;
    }
    let mid = distances.len() / 2;
    let (_, median, _) = distances.select_nth_unstable_by(mid, f64::total_cmp);
    (median.is_finite() && *median > 0.0).then_some(*median)
}

/// `(x − shift) / scale`, column by column.
pub fn shift_scale(x: MatRef<'_, f64>, shift: &[f64], scale: &[f64]) -> Mat<f64> {
    Mat::from_fn(x.nrows(), x.ncols(), |i, q| {
        (x[(i, q)] - shift[q]) / scale[q]
    })
}

/// `r²(X1, X2)` for lengthscales `ℓ`, between two distinct point sets.
pub fn scaled_sq_dist(x1: MatRef<'_, f64>, x2: MatRef<'_, f64>, lengthscales: &[f64]) -> Mat<f64> {
    let centre = column_means(x2);
    let z1 = shift_scale(x1, &centre, lengthscales);
    let z2 = shift_scale(x2, &centre, lengthscales);
    let (n1, n2) = (row_norms(&z1), row_norms(&z2));
    // `Accum::Replace` writes every entry without reading it.
    let mut r2 = crate::dense::scratch(z1.nrows(), z2.nrows());
    gemm(
        r2.as_mut(),
        Accum::Replace,
        z1.as_ref(),
        z2.as_ref().transpose(),
        -2.0,
    );
    add_norms(&mut r2, &n1, &n2, false);
    r2
}

/// `r²(X, X)` for lengthscales `ℓ`, on and below the diagonal only (the
/// diagonal exactly zero; what is above it is unspecified): one triangular
/// GEMM, half the work of the full matrix.
pub fn scaled_sq_dist_lower(x: MatRef<'_, f64>, lengthscales: &[f64]) -> Mat<f64> {
    let centre = column_means(x);
    let z = shift_scale(x, &centre, lengthscales);
    let norms = row_norms(&z);
    let n = z.nrows();
    // `Accum::Replace` writes every entry of the lower triangle.
    let mut r2 = crate::dense::scratch(n, n);
    triangular::matmul(
        r2.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        z.as_ref(),
        BlockStructure::Rectangular,
        z.as_ref().transpose(),
        BlockStructure::Rectangular,
        -2.0,
        par(),
    );
    add_norms(&mut r2, &norms, &norms, true);
    for i in 0..n {
        r2[(i, i)] = 0.0;
    }
    r2
}

/// `|z_i|²` for every row.
fn row_norms(z: &Mat<f64>) -> Vec<f64> {
    (0..z.nrows())
        .map(|i| (0..z.ncols()).map(|q| z[(i, q)] * z[(i, q)]).sum())
        .collect()
}

/// `r²_ij = max(0, −2 z_i·z'_j + |z_i|² + |z'_j|²)` in place, on and below
/// the diagonal only when `lower`.
fn add_norms(r2: &mut Mat<f64>, n1: &[f64], n2: &[f64], lower: bool) {
    let mut unused = vec![(); r2.ncols()];
    for_column_blocks(r2, &mut unused, |j0, columns, _| {
        for (jj, (col, norm_j)) in columns.iter_mut().zip(&n2[j0..]).enumerate() {
            let first = if lower { j0 + jj } else { 0 };
            for (v, norm_i) in col[first..].iter_mut().zip(&n1[first..]) {
                *v = (*v + norm_i + norm_j).max(0.0);
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_direct_sum() {
        let x1 = Mat::from_fn(5, 3, |i, q| ((i * 7 + q * 3) % 11) as f64 * 0.3 + 100.0);
        let x2 = Mat::from_fn(4, 3, |i, q| ((i * 5 + q * 2) % 7) as f64 * 0.4 + 100.0);
        let ell = [0.5, 1.5, 3.0];
        let r2 = scaled_sq_dist(x1.as_ref(), x2.as_ref(), &ell);
        for i in 0..5 {
            for j in 0..4 {
                let direct: f64 = (0..3)
                    .map(|q| ((x1[(i, q)] - x2[(j, q)]) / ell[q]).powi(2))
                    .sum();
                assert!((r2[(i, j)] - direct).abs() < 1e-11, "{i},{j}");
            }
        }
        let full = scaled_sq_dist(x1.as_ref(), x1.as_ref(), &ell);
        let lower = scaled_sq_dist_lower(x1.as_ref(), &ell);
        for j in 0..5 {
            assert_eq!(lower[(j, j)], 0.0);
            for i in j + 1..5 {
                assert!((lower[(i, j)] - full[(i, j)]).abs() < 1e-11, "{i},{j}");
            }
        }
    }

    #[test]
    fn a_recycled_buffer_left_with_nan_does_not_leak_into_the_distances() {
        // Large enough to be recycled: the GEMM must overwrite, not read.
        let n = 300;
        let x = Mat::from_fn(n, 2, |i, q| ((i * 7 + q * 3) % 13) as f64 * 0.1);
        let clean = scaled_sq_dist(x.as_ref(), x.as_ref(), &[1.0, 2.0]);
        crate::dense::release_spare();
        let mut poisoned = crate::dense::zeros(n, n);
        poisoned.fill(f64::NAN);
        crate::dense::recycle(poisoned);
        let r2 = scaled_sq_dist(x.as_ref(), x.as_ref(), &[1.0, 2.0]);
        assert_eq!(r2, clean);
        crate::dense::release_spare();
    }
}
