//! The leaf kernels, dispatched in one place: every per-leaf operation is
//! one exhaustive `match` over [`LeafKernel`] (no wildcard arm), so a new
//! kernel is one variant here, one [`LeafName`], and the compiler names
//! every method that must learn it.

use std::fmt;
use std::str::FromStr;

use faer::{Mat, MatRef};

use super::expr::KernelInit;
use super::{GradientTargets, GramCache, Linear, ParamKind, RatQuad, Stationary, White};
use crate::dense::trace;
use crate::kernels::profile::Family;

/// Declares [`LeafName`], its written names and [`LeafName::ALL`] from one
/// list, so that `ALL` cannot miss a variant.
macro_rules! leaf_names {
    ($($(#[doc = $doc:literal])* $variant:ident => $name:literal,)+) => {
        /// The name of a leaf kernel, as a kernel expression writes it.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum LeafName {
            $($(#[doc = $doc])* $variant,)+
        }

        impl LeafName {
            /// Every leaf, in the order error messages list them.
            pub const ALL: [Self; [$(stringify!($variant)),+].len()] = [$(Self::$variant),+];

            /// The name as written.
            pub fn as_str(self) -> &'static str {
                match self {
                    $(Self::$variant => $name,)+
                }
            }
        }
    };
}

leaf_names! {
    /// `rbf`: squared exponential with ARD.
    Rbf => "rbf",
    /// `matern52`: Matérn 5/2 with ARD.
    Matern52 => "matern52",
    /// `matern32`: Matérn 3/2 with ARD.
    Matern32 => "matern32",
    /// `linear`: linear with one variance per input.
    Linear => "linear",
    /// `white`: white noise.
    White => "white",
    /// `ratquad`: rational quadratic with ARD (GPy's `RatQuad`).
    RatQuad => "ratquad",
}

impl LeafName {
    /// The names, comma-separated (for messages).
    pub fn listed() -> String {
        Self::ALL
            .iter()
            .map(|n| n.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The leaf for `d` inputs with initial hyperparameters: stationary
    /// kernels at `init.variance` and a lengthscale of `init.lengthscale`
    /// (default `√d`), the linear kernel at `init.linear_variance` per input
    /// (default `1/d`), white noise at `init.white_variance`, the rational
    /// quadratic's power at `init.power`.
    pub fn build(self, d: usize, init: &KernelInit) -> LeafKernel {
        let lengthscale = init.lengthscale.unwrap_or((d.max(1) as f64).sqrt());
        let linear_variance = init.linear_variance.unwrap_or(1.0 / d.max(1) as f64);
        let stationary = || Stationary::new(init.variance, vec![lengthscale; d]);
        match self {
            Self::Rbf => LeafKernel::Rbf(stationary()),
            Self::Matern52 => LeafKernel::Matern52(stationary()),
            Self::Matern32 => LeafKernel::Matern32(stationary()),
            Self::Linear => LeafKernel::Linear(Linear::new(vec![linear_variance; d])),
            Self::White => LeafKernel::White(White::new(init.white_variance)),
            Self::RatQuad => LeafKernel::RatQuad(RatQuad::new(
                init.variance,
                vec![lengthscale; d],
                init.power,
            )),
        }
    }
}

impl fmt::Display for LeafName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// An unknown leaf name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown kernel `{name}`; expected one of {}", LeafName::listed())]
pub struct UnknownLeaf {
    /// The name as written.
    pub name: String,
}

impl FromStr for LeafName {
    type Err = UnknownLeaf;

    /// Case-insensitive.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|n| n.as_str() == lower)
            .ok_or_else(|| UnknownLeaf {
                name: s.to_string(),
            })
    }
}

/// A leaf kernel with its hyperparameters.
#[derive(Debug, Clone, PartialEq)]
pub enum LeafKernel {
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
    /// Rational quadratic with ARD.
    RatQuad(RatQuad),
}

impl LeafKernel {
    /// Its name.
    pub fn name(&self) -> LeafName {
        match self {
            Self::Rbf(_) => LeafName::Rbf,
            Self::Matern52(_) => LeafName::Matern52,
            Self::Matern32(_) => LeafName::Matern32,
            Self::Linear(_) => LeafName::Linear,
            Self::White(_) => LeafName::White,
            Self::RatQuad(_) => LeafName::RatQuad,
        }
    }

    /// Number of hyperparameters.
    pub fn n_params(&self) -> usize {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => s.n_params(),
            Self::Linear(l) => l.variances.len(),
            Self::White(_) => 1,
            Self::RatQuad(r) => r.n_params(),
        }
    }

    /// The number of inputs it was built for (`None` for white noise).
    pub fn input_dim(&self) -> Option<usize> {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => Some(s.lengthscales.len()),
            Self::Linear(l) => Some(l.variances.len()),
            Self::White(_) => None,
            Self::RatQuad(r) => Some(r.lengthscales.len()),
        }
    }

    /// Appends its hyperparameters as logarithms.
    pub fn push_log_params(&self, out: &mut Vec<f64>) {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                out.push(s.variance.ln());
                out.extend(s.lengthscales.iter().map(|l| l.ln()));
            }
            Self::Linear(l) => out.extend(l.variances.iter().map(|v| v.ln())),
            Self::White(w) => out.push(w.variance.ln()),
            Self::RatQuad(r) => {
                out.push(r.variance.ln());
                out.extend(r.lengthscales.iter().map(|l| l.ln()));
                out.push(r.power.ln());
            }
        }
    }

    /// Sets its hyperparameters from the logarithms at the start of `p`
    /// (the order of [`LeafKernel::push_log_params`]).
    ///
    /// # Panics
    /// When `p` is shorter than [`LeafKernel::n_params`] (internal use).
    pub fn set_log_params(&mut self, p: &[f64]) {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                s.variance = p[0].exp();
                for (l, v) in s.lengthscales.iter_mut().zip(&p[1..]) {
                    *l = v.exp();
                }
            }
            Self::Linear(l) => {
                for (x, v) in l.variances.iter_mut().zip(p) {
                    *x = v.exp();
                }
            }
            Self::White(w) => w.variance = p[0].exp(),
            Self::RatQuad(r) => {
                let d = r.lengthscales.len();
                r.variance = p[0].exp();
                for (l, v) in r.lengthscales.iter_mut().zip(&p[1..=d]) {
                    *l = v.exp();
                }
                r.power = p[d + 1].exp();
            }
        }
    }

    /// Appends the kind of each hyperparameter.
    pub fn push_param_kinds(&self, out: &mut Vec<ParamKind>) {
        match self {
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
            Self::RatQuad(r) => {
                out.push(ParamKind::Variance);
                out.extend(std::iter::repeat_n(
                    ParamKind::Lengthscale,
                    r.lengthscales.len(),
                ));
                out.push(ParamKind::Power);
            }
        }
    }

    /// Appends a name per hyperparameter, each prefixed by `prefix`
    /// (`rbf`, `rbf#2`), inputs named by `input`.
    pub fn push_param_names(
        &self,
        prefix: &str,
        input: &dyn Fn(usize) -> String,
        out: &mut Vec<String>,
    ) {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                out.push(format!("{prefix}.variance"));
                out.extend(
                    (0..s.lengthscales.len())
                        .map(|q| format!("{prefix}.lengthscale[{}]", input(q))),
                );
            }
            Self::Linear(l) => out
                .extend((0..l.variances.len()).map(|q| format!("{prefix}.variance[{}]", input(q)))),
            Self::White(_) => out.push(format!("{prefix}.variance")),
            Self::RatQuad(r) => {
                out.push(format!("{prefix}.variance"));
                out.extend(
                    (0..r.lengthscales.len())
                        .map(|q| format!("{prefix}.lengthscale[{}]", input(q))),
                );
                out.push(format!("{prefix}.power"));
            }
        }
    }

    /// `K(X1, X2)` between two distinct point sets (white noise gives 0).
    pub fn cross(&self, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> Mat<f64> {
        match self {
            Self::Rbf(s) => s.cross(Family::Rbf, x1, x2),
            Self::Matern52(s) => s.cross(Family::Matern52, x1, x2),
            Self::Matern32(s) => s.cross(Family::Matern32, x1, x2),
            Self::Linear(l) => l.cross(x1, x2),
            Self::White(_) => Mat::zeros(x1.nrows(), x2.nrows()),
            Self::RatQuad(r) => r.cross(x1, x2),
        }
    }

    /// `k(x_i, x_i)` for every row (white noise included).
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
            Self::RatQuad(r) => vec![r.variance; n],
        }
    }

    /// `K(X, X)` on and below the diagonal, with what the gradient needs.
    pub fn gram_lower_with_cache(&self, x: MatRef<'_, f64>) -> GramCache {
        let n = x.nrows();
        let stationary = |family, s: &Stationary| {
            let (k, derivative) = s.gram_lower(family, x);
            GramCache::leaf(k, derivative)
        };
        match self {
            Self::Rbf(s) => stationary(Family::Rbf, s),
            Self::Matern52(s) => stationary(Family::Matern52, s),
            Self::Matern32(s) => stationary(Family::Matern32, s),
            Self::Linear(l) => GramCache::leaf(l.gram_lower(x), None),
            Self::White(w) => GramCache::leaf(
                Mat::from_fn(n, n, |i, j| if i == j { w.variance } else { 0.0 }),
                None,
            ),
            Self::RatQuad(r) => GramCache::rational_quadratic(r.gram_lower(x)),
        }
    }

    /// Adds `Σ_ij W_ij ∂K_ij/∂θ_k` for each of its log-hyperparameters to
    /// `out`, from its cache at the same `X` (lower triangles read).
    pub fn accumulate_gradient(
        &self,
        x: MatRef<'_, f64>,
        cache: &GramCache,
        w: MatRef<'_, f64>,
        out: &mut [f64],
    ) {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                s.accumulate_gradient(x, &cache.k, cache.s.as_ref(), w, out);
            }
            Self::Linear(l) => l.accumulate_gradient(x, w, out),
            Self::White(wk) => out[0] += wk.variance * trace(w),
            Self::RatQuad(r) => {
                if let (Some(s), Some(a)) = (cache.s.as_ref(), cache.a.as_ref()) {
                    r.accumulate_gradient(x, &cache.k, s, a, w, out);
                }
            }
        }
    }

    /// `K(X1, X2)` with what the cross gradient needs.
    pub fn cross_with_cache(&self, x1: MatRef<'_, f64>, x2: MatRef<'_, f64>) -> GramCache {
        let stationary = |family, s: &Stationary| {
            let (k, derivative) = s.cross_with_s(family, x1, x2);
            GramCache::leaf(k, derivative)
        };
        match self {
            Self::Rbf(s) => stationary(Family::Rbf, s),
            Self::Matern52(s) => stationary(Family::Matern52, s),
            Self::Matern32(s) => stationary(Family::Matern32, s),
            Self::Linear(l) => GramCache::leaf(l.cross(x1, x2), None),
            Self::White(_) => GramCache::leaf(Mat::zeros(x1.nrows(), x2.nrows()), None),
            Self::RatQuad(r) => GramCache::rational_quadratic(r.cross_with_derivatives(x1, x2)),
        }
    }

    /// Adds the hyperparameter and first-input gradients of
    /// `Σ_ij W_ij K(X1, X2)_ij` (see [`super::Kernel::accumulate_cross_gradient`]).
    pub fn accumulate_cross_gradient(
        &self,
        x1: MatRef<'_, f64>,
        x2: MatRef<'_, f64>,
        cache: &GramCache,
        w: MatRef<'_, f64>,
        to: GradientTargets<'_>,
    ) {
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => {
                s.accumulate_cross_gradient(x1, x2, cache, w, to);
            }
            Self::Linear(l) => l.accumulate_cross_gradient(x1, x2, w, to),
            // White noise has no cross-covariance.
            Self::White(_) => {}
            Self::RatQuad(r) => r.accumulate_cross_gradient(x1, x2, cache, w, to),
        }
    }

    /// Adds `Σ_i w_i ∂k(x_i, x_i)/∂θ_k` to `out`.
    pub fn accumulate_diag_gradient(&self, x: MatRef<'_, f64>, w: &[f64], out: &mut [f64]) {
        let total: f64 = w.iter().sum();
        match self {
            Self::Rbf(s) | Self::Matern52(s) | Self::Matern32(s) => out[0] += s.variance * total,
            Self::White(wk) => out[0] += wk.variance * total,
            // k(x, x) = σ²: no lengthscale or power enters it.
            Self::RatQuad(r) => out[0] += r.variance * total,
            Self::Linear(l) => {
                for (q, o) in out.iter_mut().enumerate().take(x.ncols()) {
                    let quad: f64 = (0..x.nrows()).map(|i| w[i] * x[(i, q)].powi(2)).sum();
                    *o += l.variances[q] * quad;
                }
            }
        }
    }
}
