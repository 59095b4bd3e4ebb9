//! The few dense kernels of an ILGR step on `K × K` column-major blocks
//! (`K = d + 1 ≈ 29`), written as loops over contiguous columns so that the
//! compiler vectorises them: at this size nalgebra's generic dynamic-size
//! routines (and its Cholesky inverse through triangular solves) cost
//! several times more. Matrices are symmetric and stored in full.

/// `x · y` with four partial sums (a plain fold does not vectorise).
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    let (xc, yc) = (x[..n].chunks_exact(4), y[..n].chunks_exact(4));
    let (xr, yr) = (xc.remainder(), yc.remainder());
    let mut acc = [0.0; 4];
    for (a, b) in xc.zip(yc) {
        acc[0] += a[0] * b[0];
        acc[1] += a[1] * b[1];
        acc[2] += a[2] * b[2];
        acc[3] += a[3] * b[3];
    }
    let tail: f64 = xr.iter().zip(yr).map(|(a, b)| a * b).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `y ← a x + y`.
pub fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// `out ← scale · M x` for a `k × k` column-major `m`.
pub fn matvec(m: &[f64], k: usize, x: &[f64], scale: f64, out: &mut [f64]) {
    out.fill(0.0);
    for (j, column) in m.chunks_exact(k).enumerate() {
        axpy(scale * x[j], column, out);
    }
}

/// `xᵀ M x` for a symmetric `k × k` column-major `m`.
pub fn quadratic_form(m: &[f64], k: usize, x: &[f64]) -> f64 {
    m.chunks_exact(k)
        .zip(x)
        .map(|(column, xj)| xj * dot(column, x))
        .sum()
}

/// `M ← beta · M + alpha · u uᵀ` for a `k × k` column-major `m`.
pub fn rank_one_update(m: &mut [f64], k: usize, alpha: f64, u: &[f64], beta: f64) {
    for (column, uj) in m.chunks_exact_mut(k).zip(u) {
        let s = alpha * uj;
        for (mij, ui) in column.iter_mut().zip(u) {
            *mij = beta * *mij + s * ui;
        }
    }
}

/// The inverse of a symmetric positive definite `k × k` column-major
/// matrix, through its Cholesky factor `L` (`M⁻¹ = L⁻ᵀ L⁻¹`), in about
/// `k³/2` multiply-adds. `None` when a pivot is not positive.
pub fn spd_inverse(m: &[f64], k: usize) -> Option<Vec<f64>> {
    // Lower Cholesky factor, column-major, left-looking: column j of L is
    // (M_j − Σ_{p<j} L_jp L_p) / L_jj over rows j.., all contiguous.
    let mut l = m.to_vec();
    for j in 0..k {
        let (done, rest) = l.split_at_mut(j * k);
        let column = &mut rest[j..k];
        for p in 0..j {
            let l_jp = done[p * k + j];
            axpy(-l_jp, &done[p * k + j..(p + 1) * k], column);
        }
        let pivot = column[0];
        if !(pivot > 0.0 && pivot.is_finite()) {
            return None;
        }
        let l_jj = pivot.sqrt();
        column[0] = l_jj;
        for v in &mut column[1..] {
            *v /= l_jj;
        }
    }
    // W = L⁻¹ (lower), column by column by forward substitution
    // L w_j = e_j, eliminating with contiguous columns of L.
    let mut w = vec![0.0; k * k];
    for j in 0..k {
        let column = &mut w[j * k..(j + 1) * k];
        column[j] = 1.0;
        for p in j..k {
            let wp = column[p] / l[p * k + p];
            column[p] = wp;
            axpy(-wp, &l[p * k + p + 1..(p + 1) * k], &mut column[p + 1..]);
        }
    }
    // M⁻¹ = Wᵀ W: (i, j) = Σ_{p ≥ max(i, j)} W_pi W_pj, a dot of the tails
    // of columns i and j of W.
    let mut inv = vec![0.0; k * k];
    for j in 0..k {
        for i in j..k {
            let v = dot(&w[j * k + i..(j + 1) * k], &w[i * k + i..(i + 1) * k]);
            inv[j * k + i] = v;
            inv[i * k + j] = v;
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    fn spd(k: usize) -> DMatrix<f64> {
        let a = DMatrix::from_fn(k, k, |i, j| ((i * 7 + j * 3) % 11) as f64 / 11.0 - 0.4);
        a.transpose() * &a + DMatrix::identity(k, k) * 0.5
    }

    #[test]
    fn kernels_match_nalgebra() {
        let k = 29;
        let m = spd(k);
        let x = DVector::from_fn(k, |i, _| (i as f64 * 0.7).sin());
        let mut out = vec![0.0; k];
        matvec(m.as_slice(), k, x.as_slice(), 0.5, &mut out);
        assert!((DVector::from_vec(out) - &m * &x * 0.5).amax() < 1e-12);
        let q = quadratic_form(m.as_slice(), k, x.as_slice());
        assert!((q - x.dot(&(&m * &x))).abs() < 1e-10);
        let mut r = m.clone();
        rank_one_update(r.as_mut_slice(), k, -0.3, x.as_slice(), 2.0);
        assert!((r - (&m * 2.0 - &x * x.transpose() * 0.3)).amax() < 1e-12);
        assert!((dot(x.as_slice(), x.as_slice()) - x.norm_squared()).abs() < 1e-12);
    }

    #[test]
    fn the_inverse_of_a_positive_definite_matrix_is_its_inverse() {
        for k in [1, 2, 5, 29] {
            let m = spd(k);
            let inv = DMatrix::from_vec(k, k, spd_inverse(m.as_slice(), k).unwrap());
            assert!(
                (&m * inv - DMatrix::identity(k, k)).amax() < 1e-10,
                "k = {k}"
            );
        }
        let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(spd_inverse(indefinite.as_slice(), 2).is_none());
    }
}
