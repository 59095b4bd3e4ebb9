//! One batch's streaming bound as the optimiser's objective, over
//! `(log θ, log σ², Z_b)`.

use faer::{Mat, MatRef};

use super::bound::{InducingSummary, StreamingProblem, streaming_objective};
use crate::RegressorError;
use crate::hyperopt::{Bounds, Objective, SearchSpace};
use crate::kernels::Kernel;

/// The bound of one batch over `(log θ, log σ², Z_b)` (`Z_b` only when
/// learned).
pub(super) struct BatchObjective<'a> {
    pub template: &'a Kernel,
    pub x: MatRef<'a, f64>,
    pub y: MatRef<'a, f64>,
    pub inducing: &'a Mat<f64>,
    pub learn_inducing: bool,
    pub old: Option<&'a InducingSummary>,
    pub jitter: f64,
}

impl BatchObjective<'_> {
    pub fn unpack(&self, coords: &[f64]) -> (Kernel, f64, Mat<f64>) {
        let k = self.template.n_params();
        let mut kernel = self.template.clone();
        kernel.set_log_params(&coords[..k]);
        let (m, d) = (self.inducing.nrows(), self.inducing.ncols());
        let z = if self.learn_inducing {
            Mat::from_fn(m, d, |i, q| coords[k + 1 + i * d + q])
        } else {
            self.inducing.clone()
        };
        (kernel, coords[k].exp(), z)
    }

    /// The coordinates of `kernel`, `noise` and (when learned) `Z_b`.
    pub fn pack(&self, kernel: &Kernel, noise: f64) -> Vec<f64> {
        let mut coords = kernel.log_params();
        coords.push(noise.ln());
        if self.learn_inducing {
            coords.extend(flat(self.inducing.as_ref()));
        }
        coords
    }

    pub fn problem<'b>(
        &'b self,
        kernel: &'b Kernel,
        noise: f64,
        z: &'b Mat<f64>,
    ) -> StreamingProblem<'b> {
        StreamingProblem {
            kernel,
            noise_variance: noise,
            x: self.x,
            y: self.y,
            inducing: z.as_ref(),
            old: self.old,
            jitter: self.jitter,
        }
    }

    pub fn space(&self, bounds: &Bounds) -> SearchSpace {
        let free = if self.learn_inducing {
            self.inducing.nrows() * self.inducing.ncols()
        } else {
            0
        };
        SearchSpace::kernel(self.template, bounds).with_free(free)
    }
}

impl Objective for BatchObjective<'_> {
    fn evaluate(&self, coords: &[f64]) -> Result<(f64, Vec<f64>), RegressorError> {
        let (kernel, noise, z) = self.unpack(coords);
        let eval = streaming_objective(self.problem(&kernel, noise, &z), self.learn_inducing)?;
        let mut gradient = eval.gradient.unwrap_or_default();
        if let Some(dz) = eval.inducing_gradient {
            gradient.extend(flat(dz.as_ref()));
        }
        Ok((eval.value, gradient))
    }
}

/// The rows of `m`, one after another.
pub(super) fn flat(m: MatRef<'_, f64>) -> Vec<f64> {
    (0..m.nrows())
        .flat_map(|i| (0..m.ncols()).map(move |q| m[(i, q)]))
        .collect()
}
