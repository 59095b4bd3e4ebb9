//! Covariance functions (paper §IV-A, eq. 10–13) with ARD and analytic
//! gradients with respect to every hyperparameter in log space.
//!
//! [`Kernel`] is a closed tree of leaves ([`LeafKernel`]: [`Stationary`]
//! RBF / Matérn 5/2 / Matérn 3/2, [`Linear`], [`White`]) combined by sums
//! and products, so the composite kernels of Table I (`rbf + linear`,
//! `matern52 + linear`) are configurations ([`KernelExpr`]), not code.
//! Every per-leaf operation is dispatched in `leaf.rs`. Hyperparameters
//! are exposed as one flat vector of logarithms, leaf by leaf in
//! expression order.

mod cross;
pub(crate) mod distance;
pub mod expr;
mod leaf;
mod linear;
mod profile;
mod ratquad;
mod serialized;
mod stationary;

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

pub use cross::GradientTargets;
pub use distance::median_pairwise_distance;
pub use expr::{KernelExpr, KernelExprError, KernelInit};
pub use leaf::{LeafKernel, LeafName, UnknownLeaf};
pub use linear::{Linear, White};
pub use profile::Family;
pub use ratquad::RatQuad;
pub use stationary::Stationary;

use crate::dense::{
    column, column_mut, copy_lower_triangle, hadamard, lower_hadamard_in_place,
    symmetrize_from_lower,
};

/// A kernel with its current hyperparameters. Serialised in the flat
/// shape saved models have always used (`{"kind": "rbf", "parameters":
/// …}`, `{"kind": "sum", "parameters": [...]}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(
    from = "serialized::SerializedKernel",
    into = "serialized::SerializedKernel"
)]
pub enum Kernel {
    /// One covariance function.
    Leaf(LeafKernel),
    /// Sum of kernels.
    Sum(Vec<Kernel>),
    /// Product of kernels.
    Product(Vec<Kernel>),
}

/// What a hyperparameter is, for bounds and reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    /// A signal variance (stationary or white kernel).
    Variance,
    /// A lengthscale.
    Lengthscale,
    /// A per-input variance of the linear kernel.
    LinearVariance,
    /// The power `α` of the rational quadratic kernel.
    Power,
}

/// A Gram evaluation kept for the gradient: this node's own `K`, the
/// stationary derivative matrix, and the children's caches.
#[derive(Debug, Clone)]
pub struct GramCache {
    /// `K(X, X)` of this node.
    pub k: Mat<f64>,
    /// `σ²(−κ'(r)/r)` for Matérn leaves (`−2 ∂K/∂r²` for the rational
    /// quadratic).
    s: Option<Mat<f64>>,
    /// `∂K/∂log α` for the rational quadratic.
    a: Option<Mat<f64>>,
    /// One cache per child of a sum or product.
    children: Vec<GramCache>,
}

impl GramCache {
    fn leaf(k: Mat<f64>, s: Option<Mat<f64>>) -> Self {
        Self {
            k,
            s,
            a: None,
            children: Vec::new(),
        }
    }

    /// A rational quadratic leaf's cache.
    fn rational_quadratic(m: ratquad::RatQuadMatrices) -> Self {
        Self {
            k: m.k,
            s: Some(m.s),
            a: Some(m.a),
            children: Vec::new(),
        }
    }

    /// A sum or product node over its children's caches (on and below the
    /// diagonal only when `lower`).
    fn combine(is_sum: bool, children: Vec<GramCache>, lower: bool) -> Self {
        let (n1, n2) = children
            .first()
            .map_or((0, 0), |c| (c.k.nrows(), c.k.ncols()));
        // The first child's values start the node (`0 + c` and `1 · c` are
        // `c` exactly), the others are added or multiplied in.
        let mut k = crate::dense::scratch(n1, n2);
        if let Some(first) = children.first() {
            if lower {
                copy_lower_triangle(&mut k, first.k.as_ref());
            } else {
                k.copy_from(&first.k);
            }
        }
        for child in children.iter().skip(1) {
            for j in 0..n2 {
                let i0 = if lower { j.min(n1) } else { 0 };
                let c = column(child.k.as_ref(), j);
                for (v, c) in column_mut(&mut k, j)[i0..].iter_mut().zip(c[i0..].iter()) {
                    *v = if is_sum { *v + c } else { *v * c };
                }
            }
        }
        Self {
            k,
            s: None,
            a: None,
            children,
        }
    }

    /// Copies every matrix's lower triangle onto its upper one (a cache of
    /// [`Kernel::gram_lower_with_cache`] made whole).
    fn symmetrize(&mut self) {
        symmetrize_from_lower(&mut self.k);
        for m in [self.s.as_mut(), self.a.as_mut()].into_iter().flatten() {
            symmetrize_from_lower(m);
        }
        for child in &mut self.children {
            child.symmetrize();
        }
    }

    /// Hands this cache's matrices back for reuse (see
    /// [`crate::dense::recycle`]).
    pub fn recycle(self) {
        crate::dense::recycle(self.k);
        for m in [self.s, self.a].into_iter().flatten() {
            crate::dense::recycle(m);
        }
        for child in self.children {
            child.recycle();
        }
    }
}

impl Kernel {
    /// Number of hyperparameters.
    pub fn n_params(&self) -> usize {
        match self {
            Self::Leaf(l) => l.n_params(),
            Self::Sum(c) | Self::Product(c) => c.iter().map(Self::n_params).sum(),
        }
    }

    /// The number of inputs the kernel was built for (`None` for white noise alone).
    pub fn input_dim(&self) -> Option<usize> {
        match self {
            Self::Leaf(l) => l.input_dim(),
            Self::Sum(c) | Self::Product(c) => c.iter().find_map(Self::input_dim),
        }
    }

    /// The leaves, in expression order.
    pub fn leaves(&self) -> Vec<&LeafKernel> {
        match self {
            Self::Leaf(l) => vec![l],
            Self::Sum(c) | Self::Product(c) => c.iter().flat_map(Self::leaves).collect(),
        }
    }

    fn leaves_mut(&mut self) -> Vec<&mut LeafKernel> {
        match self {
            Self::Leaf(l) => vec![l],
            Self::Sum(c) | Self::Product(c) => c.iter_mut().flat_map(Self::leaves_mut).collect(),
        }
    }

    /// Hyperparameters as logarithms, leaf by leaf.
    pub fn log_params(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.n_params());
        for leaf in self.leaves() {
            leaf.push_log_params(&mut out);
        }
        out
    }

    /// Sets the hyperparameters from logarithms (the order of [`Kernel::log_params`]).
    ///
    /// # Panics
    /// Never for `p.len() == n_params()`; shorter slices panic (internal use).
    pub fn set_log_params(&mut self, p: &[f64]) {
        let mut at = 0;
        for leaf in self.leaves_mut() {
            let m = leaf.n_params();
            leaf.set_log_params(&p[at..at + m]);
            at += m;
        }
    }

    /// Kind of each hyperparameter, in [`Kernel::log_params`] order.
    pub fn param_kinds(&self) -> Vec<ParamKind> {
        let mut out = Vec::new();
        for leaf in self.leaves() {
            leaf.push_param_kinds(&mut out);
        }
        out
    }

    /// A readable name per hyperparameter (`rbf.lengthscale[pitch]`), in
    /// [`Kernel::log_params`] order; leaves of the same kind are numbered.
    pub fn param_names(&self, input_names: &[String]) -> Vec<String> {
        let leaves = self.leaves();
        let names: Vec<LeafName> = leaves.iter().map(|l| l.name()).collect();
        let mut seen = std::collections::HashMap::<LeafName, usize>::new();
        let input = |q: usize| {
            input_names
                .get(q)
                .cloned()
                .unwrap_or_else(|| format!("x{q}"))
        };
        let mut out = Vec::new();
        for leaf in leaves {
            let name = leaf.name();
            let count = names.iter().filter(|n| **n == name).count();
            let index = seen.entry(name).or_insert(0);
            *index += 1;
            let prefix = if count > 1 {
                format!("{name}#{index}")
            } else {
                name.to_string()
            };
            leaf.push_param_names(&prefix, &input, &mut out);
        }
        out
    }

    /// `K(X1, X2)` between two distinct point sets (white noise contributes 0).
    pub fn cross(&self, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> Mat<f64> {
        match self {
            Self::Leaf(l) => l.cross(x1, x2),
            Self::Sum(c) => {
                let mut total = Mat::zeros(x1.nrows(), x2.nrows());
                for k in c {
                    total += k.cross(x1, x2);
                }
                total
            }
            Self::Product(c) => {
                let mut total = Mat::from_fn(x1.nrows(), x2.nrows(), |_, _| 1.0);
                for k in c {
                    total = hadamard(total.as_ref(), k.cross(x1, x2).as_ref());
                }
                total
            }
        }
    }

    /// `k(x_i, x_i)` for every row (white noise included: a test point is
    /// its own point set).
    pub fn diag(&self, x: MatRef<'_, f64>) -> Vec<f64> {
        let n = x.nrows();
        match self {
            Self::Leaf(l) => l.diag(x),
            Self::Sum(c) => c.iter().fold(vec![0.0; n], |acc, k| {
                acc.iter().zip(k.diag(x)).map(|(a, b)| a + b).collect()
            }),
            Self::Product(c) => c.iter().fold(vec![1.0; n], |acc, k| {
                acc.iter().zip(k.diag(x)).map(|(a, b)| a * b).collect()
            }),
        }
    }

    /// `K(X, X)`.
    pub fn gram(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        self.gram_with_cache(x).k
    }

    /// `K(X, X)` with what [`Kernel::accumulate_gradient`] needs, in full
    /// (the lower triangles of [`Kernel::gram_lower_with_cache`], mirrored).
    pub fn gram_with_cache(&self, x: MatRef<'_, f64>) -> GramCache {
        let mut cache = self.gram_lower_with_cache(x);
        cache.symmetrize();
        cache
    }

    /// `K(X, X)` with what [`Kernel::accumulate_gradient`] needs, every
    /// matrix on and below its diagonal only (what is above it is
    /// unspecified): all an exact GP's likelihood and gradient read, at
    /// half the cost of the full matrices.
    pub fn gram_lower_with_cache(&self, x: MatRef<'_, f64>) -> GramCache {
        match self {
            Self::Leaf(l) => l.gram_lower_with_cache(x),
            Self::Sum(c) | Self::Product(c) => {
                let children: Vec<GramCache> =
                    c.iter().map(|k| k.gram_lower_with_cache(x)).collect();
                GramCache::combine(matches!(self, Self::Sum(_)), children, true)
            }
        }
    }

    /// Adds `Σ_ij W_ij ∂K_ij/∂θ_k` for every log-hyperparameter `θ_k` to `out`
    /// (length [`Kernel::n_params`]) for a symmetric `W`, from the cache of
    /// [`Kernel::gram_lower_with_cache`] (or [`Kernel::gram_with_cache`]) at
    /// the same `X`. Only the lower triangles of `W` and of the cache are
    /// read.
    pub fn accumulate_gradient(
        &self,
        x: MatRef<'_, f64>,
        cache: &GramCache,
        w: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        match self {
            Self::Leaf(l) => l.accumulate_gradient(x, cache, w, out),
            Self::Sum(children) => {
                let mut at = 0;
                for (k, c) in children.iter().zip(&cache.children) {
                    let m = k.n_params();
                    k.accumulate_gradient(x, c, w, &mut out[at..at + m]);
                    at += m;
                }
            }
            Self::Product(children) => {
                let mut at = 0;
                for (i, (k, c)) in children.iter().zip(&cache.children).enumerate() {
                    // ∂(K_1 ∘ … ∘ K_m)/∂θ_i = ∂K_i/∂θ_i ∘ Π_{j≠i} K_j.
                    let mut wi = crate::dense::scratch(w.nrows(), w.ncols());
                    copy_lower_triangle(&mut wi, w);
                    for (j, cj) in cache.children.iter().enumerate() {
                        if j != i {
                            lower_hadamard_in_place(&mut wi, cj.k.as_ref());
                        }
                    }
                    let m = k.n_params();
                    k.accumulate_gradient(x, c, wi.as_ref(), &mut out[at..at + m]);
                    at += m;
                }
            }
        }
    }
}
