//! The bounded version of eq. (5): the same weighted least-squares problem
//! with box bounds on some unknowns, solved as a convex QP with Clarabel.
//!
//! `min ½ vᵀ H v − gᵀ v` subject to `lo_k ≤ v_k ≤ hi_k`, where `H` and `g`
//! are the normal-equation matrix and right-hand side of the unconstrained
//! problem (`H = ΩᵀCΩ + prior`, `g = ΩᵀCb`).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use nalgebra::{DMatrix, DVector};

use crate::KinematicsError;

/// A box bound `lo ≤ v[index] ≤ hi` (either side may be infinite).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    /// Index of the bounded unknown.
    pub index: usize,
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

/// Solves `min ½ vᵀHv − gᵀv` subject to `bounds` (H symmetric positive
/// definite).
///
/// # Errors
/// [`KinematicsError::Solve`] when Clarabel does not report a solution
/// (e.g. contradictory bounds).
pub fn solve_bounded_qp(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    bounds: &[Bound],
) -> Result<DVector<f64>, KinematicsError> {
    let n = h.nrows();
    // Clarabel takes the upper triangle of P in compressed sparse columns.
    let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..=j {
            if h[(i, j)] != 0.0 {
                rows.push(i);
                cols.push(j);
                vals.push(h[(i, j)]);
            }
        }
    }
    let p = CscMatrix::new_from_triplets(n, n, rows, cols, vals);
    let q: Vec<f64> = g.iter().map(|v| -v).collect();

    // Each finite bound is one row `±v_k + s = ±limit`, `s ≥ 0`.
    let (mut a_rows, mut a_cols, mut a_vals, mut b) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for bound in bounds {
        for (sign, limit) in [(1.0, bound.hi), (-1.0, -bound.lo)] {
            if limit.is_finite() {
                a_rows.push(b.len());
                a_cols.push(bound.index);
                a_vals.push(sign);
                b.push(limit);
            }
        }
    }
    let m = b.len();
    let a = CscMatrix::new_from_triplets(m, n, a_rows, a_cols, a_vals);
    let cones = [NonnegativeConeT(m)];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-12)
        .tol_gap_rel(1e-12)
        .tol_feas(1e-12)
        .build()
        .map_err(|e| KinematicsError::Solve(format!("Clarabel settings: {e:?}")))?;
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| KinematicsError::Solve(format!("Clarabel setup: {e:?}")))?;
    solver.solve();
    match solver.solution.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            Ok(DVector::from_vec(solver.solution.x.clone()))
        }
        status => Err(KinematicsError::Solve(format!(
            "Clarabel finished with status {status:?}"
        ))),
    }
}
