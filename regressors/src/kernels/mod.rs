//! Covariance functions (paper §IV-A, eq. 10–13) with ARD and analytic
//! gradients with respect to every hyperparameter in log space.
//!
//! [`Kernel`] is a closed tree of leaves ([`Stationary`] RBF / Matérn 5/2 /
//! Matérn 3/2, [`Linear`], [`White`]) combined by sums and products, so the
//! composite kernels of Table I (`rbf + linear`, `matern52 + linear`) are
//! configurations ([`KernelExpr`]), not code. Hyperparameters are exposed as
//! one flat vector of logarithms, leaf by leaf in expression order.

mod cross;
pub(crate) mod distance;
pub mod expr;
mod linear;
mod profile;
mod stationary;

use faer::{Mat, MatRef};
use serde::{Deserialize, Serialize};

pub use distance::median_pairwise_distance;
pub use expr::{KernelExpr, KernelExprError, KernelInit};
pub use linear::{Linear, White};
pub use profile::Family;
pub use stationary::Stationary;

use crate::dense::{
    column, column_mut, copy_lower_triangle, hadamard, lower_hadamard_in_place,
    symmetrize_from_lower, trace,
};

/// A kernel with its current hyperparameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "parameters", rename_all = "snake_case")]
pub enum Kernel {
    /// Squared exponential with ARD.
    Rbf(Stationary),
    /// Matérn 5/2 with ARD.
    Matern52(Stationary),
    /// Matérn 3/2 with ARD.
    Matern32(Stationary),
    /// Linear with per-input variances.
    Linear(Linear),
    /// White noise.
    White(White),
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
}

/// A Gram evaluation kept for the gradient: this node's own `K`, the
/// stationary derivative matrix, and the children's caches.
#[derive(Debug, Clone)]
pub struct GramCache {
    /// `K(X, X)` of this node.
    pub k: Mat<f64>,
    /// `σ²(−κ'(r)/r)` for Matérn leaves.
    s: Option<Mat<f64>>,
    /// One cache per child of a sum or product.
    children: Vec<GramCache>,
}

impl GramCache {
    fn leaf(k: Mat<f64>, s: Option<Mat<f64>>) -> Self {
        Self {
            k,
            s,
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
            children,
        }
    }

    /// Copies every matrix's lower triangle onto its upper one (a cache of
    /// [`Kernel::gram_lower_with_cache`] made whole).
    fn symmetrize(&mut self) {
        symmetrize_from_lower(&mut self.k);
        if let Some(s) = self.s.as_mut() {
            symmetrize_from_lower(s);
        }
        for child in &mut self.children {
            child.symmetrize();
        }
    }

    /// Hands this cache's matrices back for reuse (see
    /// [`crate::dense::recycle`]).
    pub fn recycle(self) {
        crate::dense::recycle(self.k);
        if let Some(s) = self.s {
            crate::dense::recycle(s);
        }
        for child in self.children {
            child.recycle();
        }
    }
}

impl Kernel {
    fn family(&self) -> Option<(Family, &Stationary)> {
        match self {
            Self::Rbf(s) => Some((Family::Rbf, s)),
            Self::Matern52(s) => Some((Family::Matern52, s)),
            Self::Matern32(s) => Some((Family::Matern32, s)),
            _ => None,
        }
    }

    /// Number of hyperparameters.
    pub fn n_params(&self) -> usize {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => s.n_params(),
            Self::Linear(l) => l.variances.len(),
            Self::White(_) => 1,
            Self::Sum(c) | Self::Product(c) => c.iter().map(Self::n_params).sum(),
        }
    }

    /// The number of inputs the kernel was built for (`None` for white noise alone).
    pub fn input_dim(&self) -> Option<usize> {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => Some(s.lengthscales.len()),
            Self::Linear(l) => Some(l.variances.len()),
            Self::White(_) => None,
            Self::Sum(c) | Self::Product(c) => c.iter().find_map(Self::input_dim),
        }
    }

    /// Hyperparameters as logarithms, leaf by leaf.
    pub fn log_params(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.n_params());
        self.visit(&mut |k| match k {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                out.push(s.variance.ln());
                out.extend(s.lengthscales.iter().map(|l| l.ln()));
            }
            Self::Linear(l) => out.extend(l.variances.iter().map(|v| v.ln())),
            Self::White(w) => out.push(w.variance.ln()),
            Self::Sum(_) | Self::Product(_) => {}
        });
        out
    }

    /// Sets the hyperparameters from logarithms (the order of [`Kernel::log_params`]).
    ///
    /// # Panics
    /// Never for `p.len() == n_params()`; shorter slices panic (internal use).
    pub fn set_log_params(&mut self, p: &[f64]) {
        let mut at = 0;
        self.visit_mut(&mut |k| match k {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                s.variance = p[at].exp();
                for (l, v) in s.lengthscales.iter_mut().zip(&p[at + 1..]) {
                    *l = v.exp();
                }
                at += s.n_params();
            }
            Self::Linear(l) => {
                for (x, v) in l.variances.iter_mut().zip(&p[at..]) {
                    *x = v.exp();
                }
                at += l.variances.len();
            }
            Self::White(w) => {
                w.variance = p[at].exp();
                at += 1;
            }
            Self::Sum(_) | Self::Product(_) => {}
        });
    }

    /// Kind of each hyperparameter, in [`Kernel::log_params`] order.
    pub fn param_kinds(&self) -> Vec<ParamKind> {
        let mut out = Vec::new();
        self.visit(&mut |k| match k {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                out.push(ParamKind::Variance);
                out.extend(std::iter::repeat_n(
                    ParamKind::Lengthscale,
                    s.lengthscales.len(),
                ));
            }
            Self::Linear(l) => out.extend(std::iter::repeat_n(
                ParamKind::LinearVariance,
                l.variances.len(),
            )),
            Self::White(_) => out.push(ParamKind::Variance),
            Self::Sum(_) | Self::Product(_) => {}
        });
        out
    }

    /// A readable name per hyperparameter (`rbf.lengthscale[pitch]`), in
    /// [`Kernel::log_params`] order; leaves of the same kind are numbered.
    pub fn param_names(&self, input_names: &[String]) -> Vec<String> {
        let mut leaves = Vec::new();
        self.visit(&mut |k| {
            if let Some(name) = k.leaf_name() {
                leaves.push(name);
            }
        });
        let mut seen = std::collections::HashMap::<&str, usize>::new();
        let mut out = Vec::new();
        for leaf in &leaves {
            let count = leaves.iter().filter(|l| *l == leaf).count();
            let index = seen.entry(leaf).or_insert(0);
            *index += 1;
            let prefix = if count > 1 {
                format!("{leaf}#{index}")
            } else {
                (*leaf).to_string()
            };
            let input = |q: usize| {
                input_names
                    .get(q)
                    .cloned()
                    .unwrap_or_else(|| format!("x{q}"))
            };
            match *leaf {
                "linear" => {
                    let d = self.input_dim().unwrap_or(0);
                    out.extend((0..d).map(|q| format!("{prefix}.variance[{}]", input(q))));
                }
                "white" => out.push(format!("{prefix}.variance")),
                _ => {
                    let d = self.input_dim().unwrap_or(0);
                    out.push(format!("{prefix}.variance"));
                    out.extend((0..d).map(|q| format!("{prefix}.lengthscale[{}]", input(q))));
                }
            }
        }
        out
    }

    fn leaf_name(&self) -> Option<&'static str> {
        match self {
            Self::Rbf(_) => Some("rbf"),
            Self::Matern52(_) => Some("matern52"),
            Self::Matern32(_) => Some("matern32"),
            Self::Linear(_) => Some("linear"),
            Self::White(_) => Some("white"),
            Self::Sum(_) | Self::Product(_) => None,
        }
    }

    fn visit<'a>(&'a self, f: &mut impl FnMut(&'a Kernel)) {
        f(self);
        if let Self::Sum(c) | Self::Product(c) = self {
            for k in c {
                k.visit(f);
            }
        }
    }

    fn visit_mut(&mut self, f: &mut impl FnMut(&mut Kernel)) {
        f(self);
        if let Self::Sum(c) | Self::Product(c) = self {
            for k in c {
                k.visit_mut(f);
            }
        }
    }

    /// `K(X1, X2)` between two distinct point sets (white noise contributes 0).
    pub fn cross(&self, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> Mat<f64> {
        if let Some((family, s)) = self.family() {
            return s.cross(family, x1, x2);
        }
        match self {
            Self::Linear(l) => l.cross(x1, x2),
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
            _ => Mat::zeros(x1.nrows(), x2.nrows()),
        }
    }

    /// `k(x_i, x_i)` for every row (white noise included: a test point is
    /// its own point set).
    pub fn diag(&self, x: MatRef<'_, f64>) -> Vec<f64> {
        let n = x.nrows();
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => vec![s.variance; n],
            Self::Linear(l) => (0..n)
                .map(|i| {
                    (0..x.ncols())
                        .map(|q| l.variances[q] * x[(i, q)].powi(2))
                        .sum()
                })
                .collect(),
            Self::White(w) => vec![w.variance; n],
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
        let n = x.nrows();
        if let Some((family, s)) = self.family() {
            let (k, s) = s.gram_lower(family, x);
            return GramCache::leaf(k, s);
        }
        match self {
            Self::Linear(l) => GramCache::leaf(l.gram_lower(x), None),
            Self::White(w) => GramCache::leaf(
                Mat::from_fn(n, n, |i, j| if i == j { w.variance } else { 0.0 }),
                None,
            ),
            Self::Sum(c) | Self::Product(c) => {
                let children: Vec<GramCache> =
                    c.iter().map(|k| k.gram_lower_with_cache(x)).collect();
                GramCache::combine(matches!(self, Self::Sum(_)), children, true)
            }
            _ => GramCache::leaf(Mat::zeros(n, n), None),
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
        if let Some((_, s)) = self.family() {
            s.accumulate_gradient(x, &cache.k, cache.s.as_ref(), w, out);
            return;
        }
        match self {
            Self::Linear(l) => l.accumulate_gradient(x, w, out),
            Self::White(wk) => out[0] += wk.variance * trace(w),
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
            _ => {}
        }
    }
}
