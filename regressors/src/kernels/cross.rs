//! Gradients of cross-covariances `K(X1, X2)` and of the diagonal
//! `k(x_i, x_i)`, with respect to the hyperparameters and to the first
//! point set — what a sparse GP needs for `K_uf`, `K_uu` and `diag K_ff`
//! and for moving its inducing inputs `Z`.

use faer::{Mat, MatRef};

use super::{GramCache, Kernel};
use crate::dense::hadamard;

/// Where the gradient of `Σ_ij W_ij K(X1, X2)_ij` is added: to the
/// log-hyperparameters, to the first point set `X1` (scaled by a factor),
/// or to both.
#[derive(Debug, Default)]
pub struct GradientTargets<'o> {
    /// One entry per log-hyperparameter, in [`Kernel::log_params`] order.
    pub params: Option<&'o mut [f64]>,
    /// `factor · Σ_j W_ij ∂K_ij/∂X1_iq` is added to this `n1 × d` matrix.
    pub inputs: Option<(&'o mut Mat<f64>, f64)>,
}

impl<'o> GradientTargets<'o> {
    /// Only the hyperparameters' gradient, added to `params`.
    pub fn params(params: &'o mut [f64]) -> Self {
        Self {
            params: Some(params),
            inputs: None,
        }
    }

    /// Only the first point set's gradient, times `factor`, added to `dx1`.
    pub fn inputs(dx1: &'o mut Mat<f64>, factor: f64) -> Self {
        Self {
            params: None,
            inputs: Some((dx1, factor)),
        }
    }
}

impl Kernel {
    /// `K(X1, X2)` (white noise contributes 0) with what
    /// [`Kernel::accumulate_cross_gradient`] needs.
    pub fn cross_with_cache(&self, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> GramCache {
        match self {
            Self::Leaf(l) => l.cross_with_cache(x1, x2),
            Self::Sum(c) | Self::Product(c) => {
                let children: Vec<GramCache> =
                    c.iter().map(|k| k.cross_with_cache(x1, x2)).collect();
                GramCache::combine(matches!(self, Self::Sum(_)), children, false)
            }
        }
    }

    /// Adds `Σ_ij W_ij ∂K(X1, X2)_ij/∂θ_k` to `to.params` (one entry per
    /// log-hyperparameter) and `factor · Σ_j W_ij ∂K_ij/∂X1_iq` to
    /// `to.inputs`, from the cache of [`Kernel::cross_with_cache`] (or,
    /// with `factor = 2` and a symmetric `W`, of [`Kernel::gram_with_cache`]
    /// at `X1 = X2`: the input gradient of `Σ_ij W_ij K(X, X)_ij`).
    pub fn accumulate_cross_gradient(
        &self,
        x1: MatRef<'_, f64>,
        x2: MatRef<'_, f64>,
        cache: &GramCache,
        w: MatRef<'_, f64>,
        to: GradientTargets<'_>,
    ) {
        match self {
            Self::Leaf(l) => l.accumulate_cross_gradient(x1, x2, cache, w, to),
            Self::Sum(children) | Self::Product(children) => {
                let is_product = matches!(self, Self::Product(_));
                let GradientTargets {
                    params: mut out,
                    inputs: mut dx1,
                } = to;
                let mut at = 0;
                for (i, (k, c)) in children.iter().zip(&cache.children).enumerate() {
                    // ∂(K_1 ∘ … ∘ K_m) = ∂K_i ∘ Π_{j≠i} K_j.
                    let wi = if is_product {
                        let mut wi = w.to_owned();
                        for (j, cj) in cache.children.iter().enumerate() {
                            if j != i {
                                wi = hadamard(wi.as_ref(), cj.k.as_ref());
                            }
                        }
                        Some(wi)
                    } else {
                        None
                    };
                    let wi = wi.as_ref().map_or(w, |m| m.as_ref());
                    let m = k.n_params();
                    let child = GradientTargets {
                        params: out.as_deref_mut().map(|o| &mut o[at..at + m]),
                        inputs: dx1.as_mut().map(|(d, f)| (&mut **d, *f)),
                    };
                    k.accumulate_cross_gradient(x1, x2, c, wi, child);
                    at += m;
                }
            }
        }
    }

    /// Adds `Σ_i w_i ∂k(x_i, x_i)/∂θ_k` to `out`.
    pub fn accumulate_diag_gradient(&self, x: MatRef<'_, f64>, w: &[f64], out: &mut [f64]) {
        match self {
            Self::Leaf(l) => l.accumulate_diag_gradient(x, w, out),
            Self::Sum(children) | Self::Product(children) => {
                let diags: Vec<Vec<f64>> = if matches!(self, Self::Product(_)) {
                    children.iter().map(|k| k.diag(x)).collect()
                } else {
                    Vec::new()
                };
                let mut at = 0;
                for (i, k) in children.iter().enumerate() {
                    let wi: Vec<f64> = (0..w.len())
                        .map(|r| {
                            diags
                                .iter()
                                .enumerate()
                                .filter(|(j, _)| *j != i)
                                .fold(w[r], |acc, (_, d)| acc * d[r])
                        })
                        .collect();
                    let m = k.n_params();
                    k.accumulate_diag_gradient(x, &wi, &mut out[at..at + m]);
                    at += m;
                }
            }
        }
    }
}
