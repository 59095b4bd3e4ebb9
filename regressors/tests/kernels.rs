//! Kernel specification: every kernel's analytic gradient matches finite
//! differences, Gram matrices are symmetric positive semi-definite, and
//! values match closed forms.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use faer::Mat;
use gpodo_regressors::dense::frobenius_dot;
use gpodo_regressors::kernels::{Kernel, KernelExpr, KernelInit};
use support::*;

const EXPRESSIONS: [&str; 10] = [
    "rbf",
    "matern52",
    "matern32",
    "linear",
    "white",
    "rbf + linear",
    "matern52 + linear",
    "rbf * linear",
    "(rbf + linear) * matern32",
    "rbf + matern32 + white",
];

fn weighted_sum(k: &Kernel, x: &Mat<f64>, w: &Mat<f64>) -> f64 {
    frobenius_dot(w.as_ref(), k.gram(x.as_ref()).as_ref())
}

#[test]
fn gradient_matches_finite_differences_for_every_kernel() {
    let mut rng = rng(11);
    for expr in EXPRESSIONS {
        for trial in 0..4 {
            let (n, d) = (9, 4);
            let x = inputs(&mut rng, n, d);
            let w = symmetric(&mut rng, n);
            let kernel = random_kernel(&mut rng, expr, d);
            let cache = kernel.gram_with_cache(x.as_ref());
            let mut analytic = vec![0.0; kernel.n_params()];
            kernel.accumulate_gradient(x.as_ref(), &cache, w.as_ref(), &mut analytic);
            let theta = kernel.log_params();
            let h = 1e-5;
            for (k, a) in analytic.iter().enumerate() {
                let mut plus = kernel.clone();
                let mut minus = kernel.clone();
                let mut tp = theta.clone();
                tp[k] += h;
                plus.set_log_params(&tp);
                tp[k] -= 2.0 * h;
                minus.set_log_params(&tp);
                let fd = (weighted_sum(&plus, &x, &w) - weighted_sum(&minus, &x, &w)) / (2.0 * h);
                let err = rel_err(*a, fd, 1e-6);
                assert!(
                    err < 1e-5,
                    "{expr} trial {trial} parameter {k}: analytic {a} vs fd {fd} (rel {err:e})"
                );
            }
        }
    }
}

#[test]
fn the_lower_gram_and_the_gradient_read_only_lower_triangles() {
    let mut rng = rng(14);
    for expr in EXPRESSIONS {
        // Large enough for recycled buffers (see `dense::recycle`), the
        // parallel column blocks and faer's blocking.
        let (n, d) = (260, 4);
        let x = inputs(&mut rng, n, d);
        let w = symmetric(&mut rng, n);
        let kernel = random_kernel(&mut rng, expr, d);
        // Every scratch buffer the lower Gram takes holds NaN above the
        // diagonal unless it writes there.
        gpodo_regressors::dense::release_spare();
        for _ in 0..8 {
            let mut poisoned = gpodo_regressors::dense::zeros(n, n);
            poisoned.fill(f64::NAN);
            gpodo_regressors::dense::recycle(poisoned);
        }
        let lower = kernel.gram_lower_with_cache(x.as_ref());
        gpodo_regressors::dense::release_spare();
        let full = kernel.gram_with_cache(x.as_ref());
        for j in 0..n {
            for i in j..n {
                assert_eq!(lower.k[(i, j)], full.k[(i, j)], "{expr} ({i}, {j})");
            }
        }
        let w_nan_above = Mat::from_fn(n, n, |i, j| if i >= j { w[(i, j)] } else { f64::NAN });
        let mut from_lower = vec![0.0; kernel.n_params()];
        kernel.accumulate_gradient(x.as_ref(), &lower, w_nan_above.as_ref(), &mut from_lower);
        let mut from_full = vec![0.0; kernel.n_params()];
        kernel.accumulate_gradient(x.as_ref(), &full, w.as_ref(), &mut from_full);
        assert!(
            from_lower.iter().all(|g| g.is_finite()),
            "{expr}: {from_lower:?}"
        );
        assert_eq!(from_lower, from_full, "{expr}");
    }
}

#[test]
fn gram_matrices_are_symmetric_positive_semidefinite() {
    let mut rng = rng(12);
    for expr in EXPRESSIONS {
        let x = inputs(&mut rng, 30, 3);
        let k = random_kernel(&mut rng, expr, 3).gram(x.as_ref());
        assert!(
            (&k - k.transpose()).norm_max() < 1e-12,
            "{expr} not symmetric"
        );
        let eig = k.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
        let largest = eig.iter().cloned().fold(0.0, f64::max);
        let smallest = eig.iter().cloned().fold(f64::INFINITY, f64::min);
        assert!(
            smallest > -1e-10 * largest.max(1.0),
            "{expr}: eigenvalue {smallest}"
        );
    }
}

#[test]
fn cross_covariance_agrees_with_gram_and_diag() {
    let mut rng = rng(13);
    for expr in EXPRESSIONS.iter().filter(|e| !e.contains("white")) {
        let x = inputs(&mut rng, 7, 3);
        let kernel = random_kernel(&mut rng, expr, 3);
        let gram = kernel.gram(x.as_ref());
        let cross = kernel.cross(x.as_ref(), x.as_ref());
        assert!((&gram - &cross).norm_max() < 1e-10, "{expr}");
        let diag = kernel.diag(x.as_ref());
        for (i, v) in diag.iter().enumerate() {
            assert!((gram[(i, i)] - v).abs() < 1e-12, "{expr}");
        }
    }
}

#[test]
fn values_match_closed_forms_in_one_dimension() {
    let x = Mat::from_fn(2, 1, |i, _| if i == 0 { 0.0 } else { 1.5 });
    let set = |expr: &str, p: &[f64]| {
        let mut k = KernelExpr::parse(expr)
            .unwrap()
            .build(1, &KernelInit::default());
        k.set_log_params(&p.iter().map(|v: &f64| v.ln()).collect::<Vec<_>>());
        k.gram(x.as_ref())[(0, 1)]
    };
    let (s2, l, r) = (1.7_f64, 0.8_f64, 1.5_f64 / 0.8);
    assert!((set("rbf", &[s2, l]) - s2 * (-0.5 * r * r).exp()).abs() < 1e-14);
    let m52 = s2 * (1.0 + 5f64.sqrt() * r + 5.0 / 3.0 * r * r) * (-(5f64.sqrt()) * r).exp();
    assert!((set("matern52", &[s2, l]) - m52).abs() < 1e-14);
    let m32 = s2 * (1.0 + 3f64.sqrt() * r) * (-(3f64.sqrt()) * r).exp();
    assert!((set("matern32", &[s2, l]) - m32).abs() < 1e-14);
    // Linear: v · 0 · 1.5 off the diagonal; on it, v · 1.5².
    let lin = KernelExpr::parse("linear")
        .unwrap()
        .build(1, &KernelInit::default());
    assert_eq!(lin.gram(x.as_ref())[(1, 1)], 1.0 * 1.5 * 1.5);
    let white = KernelExpr::parse("white")
        .unwrap()
        .build(1, &KernelInit::default());
    let g = white.gram(x.as_ref());
    assert_eq!((g[(0, 0)], g[(0, 1)]), (0.01, 0.0));
    assert_eq!(white.cross(x.as_ref(), x.as_ref())[(0, 0)], 0.0);
}

#[test]
fn parameters_are_named_per_input_and_round_trip_in_log_space() {
    let kernel = KernelExpr::parse("rbf + linear")
        .unwrap()
        .build(2, &KernelInit::default());
    let names = kernel.param_names(&["pitch".into(), "roll".into()]);
    assert_eq!(
        names,
        [
            "rbf.variance",
            "rbf.lengthscale[pitch]",
            "rbf.lengthscale[roll]",
            "linear.variance[pitch]",
            "linear.variance[roll]"
        ]
    );
    let mut k = kernel.clone();
    let p = vec![0.1, -0.2, 0.3, -0.4, 0.5];
    k.set_log_params(&p);
    for (a, b) in k.log_params().iter().zip(&p) {
        assert!((a - b).abs() < 1e-15);
    }
    let twice = KernelExpr::parse("rbf + rbf")
        .unwrap()
        .build(1, &KernelInit::default());
    assert_eq!(twice.param_names(&[])[0], "rbf#1.variance");
    assert_eq!(twice.param_names(&[])[2], "rbf#2.variance");
}

#[test]
fn kernels_serialise_and_deserialise() {
    let mut rng = rng(14);
    let k = random_kernel(&mut rng, "(rbf + linear) * matern32", 3);
    let json = serde_json::to_string(&k).unwrap();
    let back: Kernel = serde_json::from_str(&json).unwrap();
    assert_eq!(k, back);
}
