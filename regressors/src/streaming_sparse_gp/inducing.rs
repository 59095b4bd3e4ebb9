//! Each later batch's first inducing inputs: the old ones kept and the
//! batch's inputs added.

use faer::{Mat, MatRef};
use rand_chacha::ChaCha8Rng;

use crate::kernels::Kernel;

/// `k` of `0..n` drawn without replacement, in increasing order.
fn draw(rng: &mut ChaCha8Rng, n: usize, k: usize) -> Vec<usize> {
    let mut picked = rand::seq::index::sample(rng, n, k.min(n)).into_vec();
    picked.sort_unstable();
    picked
}

/// Prior correlation `k(x, z)/√(k(x, x) k(z, z))` above which a batch
/// input is the same point as an inducing input already chosen, to the
/// kernel: two such inducing inputs make `K_bb` nearly singular (a robot
/// at rest repeats its input rows, up to its sensors' noise).
const SAME_POINT_CORRELATION: f64 = 0.9999;

/// A batch's first inducing inputs: the old ones kept and the batch's
/// inputs added, at most `count` in all (see the module's description).
/// A batch input that `kernel` finds the same point as one already chosen
/// is passed over.
pub(super) fn keep_and_add(
    kernel: &Kernel,
    old: MatRef<'_, f64>,
    x: MatRef<'_, f64>,
    count: usize,
    kept_share: f64,
    rng: &mut ChaCha8Rng,
) -> Mat<f64> {
    let (m_old, n, d) = (old.nrows(), x.nrows(), x.ncols());
    let fresh = count
        .saturating_sub(m_old)
        .max(count - (kept_share * count as f64).floor() as usize)
        .min(n);
    let kept = draw(rng, m_old, count.saturating_sub(fresh).min(m_old));
    let mut chosen = Mat::from_fn(kept.len(), d, |i, q| old[(kept[i], q)]);
    let mut priors = kernel.diag(chosen.as_ref());
    let order = rand::seq::index::sample(rng, n, n).into_vec();
    let mut added = 0;
    for i in order {
        if added == fresh {
            break;
        }
        let candidate = x.subrows(i, 1);
        let repeated = chosen.nrows() > 0 && {
            let prior = kernel.diag(candidate)[0];
            let cross = kernel.cross(candidate, chosen.as_ref());
            (0..chosen.nrows())
                .any(|j| cross[(0, j)] > SAME_POINT_CORRELATION * (prior * priors[j]).sqrt())
        };
        if !repeated {
            priors.extend(kernel.diag(candidate));
            let m = chosen.nrows();
            chosen.resize_with(m + 1, d, |_, q| candidate[(0, q)]);
            added += 1;
        }
    }
    chosen
}
