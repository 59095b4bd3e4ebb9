//! Initial placement of the inducing inputs: seeded k-means (k-means++
//! seeding, then Lloyd iterations with the distances from one GEMM) or a
//! seeded random subset of the training inputs.

use faer::{Mat, MatRef};
use rand::seq::index::sample;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::params::{InducingInit, InducingParams};
use crate::kernels::distance::scaled_sq_dist;

/// `m × d` inducing inputs for the rows of `x` (all rows, in order, when
/// there are no more than `m`).
pub fn place_inducing(x: MatRef<'_, f64>, params: &InducingParams, seed: u64) -> Mat<f64> {
    let (n, d) = (x.nrows(), x.ncols());
    let m = params.count.min(n);
    if m == n {
        return x.to_owned();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    match params.init {
        InducingInit::RandomSubset => {
            let mut rows = sample(&mut rng, n, m).into_vec();
            rows.sort_unstable();
            Mat::from_fn(m, d, |i, q| x[(rows[i], q)])
        }
        InducingInit::Kmeans => {
            let mut centres = kmeans_plus_plus(x, m, &mut rng);
            for _ in 0..params.kmeans_iters {
                if !lloyd_step(x, &mut centres) {
                    break;
                }
            }
            centres
        }
    }
}

/// k-means++ seeding: each new centre drawn with probability proportional
/// to the squared distance to the nearest centre so far.
fn kmeans_plus_plus(x: MatRef<'_, f64>, m: usize, rng: &mut ChaCha8Rng) -> Mat<f64> {
    let (n, d) = (x.nrows(), x.ncols());
    let sq = |i: usize, j: usize| -> f64 { (0..d).map(|q| (x[(i, q)] - x[(j, q)]).powi(2)).sum() };
    let mut chosen = vec![rng.random_range(0..n)];
    let mut nearest: Vec<f64> = (0..n).map(|i| sq(i, chosen[0])).collect();
    while chosen.len() < m {
        let total: f64 = nearest.iter().sum();
        let next = if total > 0.0 {
            let mut target = rng.random::<f64>() * total;
            let mut pick = n - 1;
            for (i, w) in nearest.iter().enumerate() {
                if target < *w {
                    pick = i;
                    break;
                }
                target -= w;
            }
            pick
        } else {
            // Every point coincides with a centre: any unused row will do.
            (0..n).find(|i| !chosen.contains(i)).unwrap_or(0)
        };
        chosen.push(next);
        for (i, v) in nearest.iter_mut().enumerate() {
            *v = v.min(sq(i, next));
        }
    }
    Mat::from_fn(m, d, |i, q| x[(chosen[i], q)])
}

/// One Lloyd iteration; returns whether any assignment changed a centre.
/// An empty cluster keeps its centre.
fn lloyd_step(x: MatRef<'_, f64>, centres: &mut Mat<f64>) -> bool {
    let (n, d, m) = (x.nrows(), x.ncols(), centres.nrows());
    let ones = vec![1.0; d];
    let r2 = scaled_sq_dist(x, centres.as_ref(), &ones);
    let mut sums = Mat::<f64>::zeros(m, d);
    let mut counts = vec![0usize; m];
    for i in 0..n {
        let mut best = (0, f64::INFINITY);
        for c in 0..m {
            if r2[(i, c)] < best.1 {
                best = (c, r2[(i, c)]);
            }
        }
        counts[best.0] += 1;
        for q in 0..d {
            sums[(best.0, q)] += x[(i, q)];
        }
    }
    let mut moved = false;
    for c in 0..m {
        if counts[c] == 0 {
            continue;
        }
        for q in 0..d {
            let v = sums[(c, q)] / counts[c] as f64;
            moved |= (v - centres[(c, q)]).abs() > 1e-12 * (1.0 + v.abs());
            centres[(c, q)] = v;
        }
    }
    moved
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clusters() -> Mat<f64> {
        // Three tight clusters of 20 points in 2-D.
        let centres = [[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]];
        Mat::from_fn(60, 2, |i, q| {
            centres[i / 20][q] + 0.01 * ((i * 7 + q * 3) % 5) as f64
        })
    }

    #[test]
    fn kmeans_finds_the_cluster_centres() {
        let x = clusters();
        let params = InducingParams {
            count: 3,
            ..Default::default()
        };
        let z = place_inducing(x.as_ref(), &params, 1);
        let mut found: Vec<(i64, i64)> = (0..3)
            .map(|i| (z[(i, 0)].round() as i64, z[(i, 1)].round() as i64))
            .collect();
        found.sort_unstable();
        assert_eq!(found, vec![(0, 0), (0, 10), (10, 0)], "{z:?}");
    }

    #[test]
    fn placement_is_seeded_and_subsets_are_training_rows() {
        let x = clusters();
        let params = InducingParams {
            count: 7,
            init: InducingInit::RandomSubset,
            ..Default::default()
        };
        let a = place_inducing(x.as_ref(), &params, 5);
        assert_eq!(a, place_inducing(x.as_ref(), &params, 5));
        for i in 0..7 {
            assert!((0..60).any(|r| x[(r, 0)] == a[(i, 0)] && x[(r, 1)] == a[(i, 1)]));
        }
        let all = InducingParams {
            count: 100,
            ..Default::default()
        };
        assert_eq!(place_inducing(x.as_ref(), &all, 0), x);
    }
}
