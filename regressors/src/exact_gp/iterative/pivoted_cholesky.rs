//! The partial pivoted Cholesky factor of a kernel matrix (Harbrecht,
//! Peters & Schneider, *Appl. Numer. Math.* 2012; the preconditioner of
//! Gardner et al., NeurIPS 2018): `K ≈ L Lᵀ` with `L` of rank `k`, built
//! greedily on the largest remaining diagonal in `O(n k²)`, reading `k`
//! columns of `K` and never the rest.

use faer::{Accum, Mat, MatRef};

use crate::dense::gemm;

/// `L` (`n × rank`, rows in the original order) of the rank-`rank`
/// pivoted Cholesky factor of the symmetric positive semi-definite `K`,
/// given by its lower triangle. It stops early, with fewer columns, once
/// the trace of what is left, `tr(K − L Lᵀ)`, is below `tolerance` times
/// `tr(K)`.
pub fn pivoted_cholesky(k_lower: MatRef<'_, f64>, rank: usize, tolerance: f64) -> Mat<f64> {
    let n = k_lower.nrows();
    let rank = rank.min(n);
    let entry = |i: usize, j: usize| {
        if i >= j {
            k_lower[(i, j)]
        } else {
            k_lower[(j, i)]
        }
    };
    let mut residual: Vec<f64> = (0..n).map(|i| k_lower[(i, i)]).collect();
    let total: f64 = residual.iter().sum();
    let mut order: Vec<usize> = (0..n).collect();
    let mut l = Mat::<f64>::zeros(n, rank);
    let mut built = 0;
    for m in 0..rank {
        // The largest remaining diagonal (the first of equals).
        let (at, &pivot_row) = order[m..]
            .iter()
            .enumerate()
            .max_by(|a, b| {
                residual[*a.1]
                    .total_cmp(&residual[*b.1])
                    .then(b.0.cmp(&a.0))
            })
            .map(|(i, r)| (i + m, r))
            .unwrap_or((m, &order[m]));
        let remaining: f64 = order[m..].iter().map(|&i| residual[i]).sum();
        if remaining <= tolerance * total || residual[pivot_row] <= 0.0 {
            break;
        }
        order.swap(m, at);
        let pivot = residual[pivot_row].sqrt();
        // K's pivot column minus what the first m columns explain, one GEMV.
        let mut column = Mat::from_fn(n, 1, |i, _| entry(i, pivot_row));
        if m > 0 {
            let explained = l.as_ref().subcols(0, m);
            let at_pivot = l.as_ref().submatrix(pivot_row, 0, 1, m).transpose();
            gemm(column.as_mut(), Accum::Add, explained, at_pivot, -1.0);
        }
        l[(pivot_row, m)] = pivot;
        for &i in &order[m + 1..] {
            let lim = column[(i, 0)] / pivot;
            l[(i, m)] = lim;
            residual[i] -= lim * lim;
        }
        residual[pivot_row] = 0.0;
        built = m + 1;
    }
    if built < rank {
        l = l.subcols(0, built).to_owned();
    }
    l
}
