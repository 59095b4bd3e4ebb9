//! Kernel specification: every kernel's analytic gradient matches finite
//! differences, Gram matrices are symmetric positive semi-definite, and
//! values match closed forms.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use faer::Mat;
use gpodo_regressors::dense::frobenius_dot;
use gpodo_regressors::kernels::{GradientTargets, Kernel, KernelExpr, KernelInit};
use support::*;

const EXPRESSIONS: [&str; 13] = [
    "rbf",
    "matern52",
    "matern32",
    "linear",
    "white",
    "ratquad",
    "rbf + linear",
    "matern52 + linear",
    "rbf * linear",
    "(rbf + linear) * matern32",
    "rbf + matern32 + white",
    "ratquad + linear",
    "ratquad * matern52",
];

/// Central finite differences of `f` in each log-hyperparameter of
/// `kernel`, step `h`.
fn log_param_fd(kernel: &Kernel, h: f64, f: impl Fn(&Kernel) -> f64) -> Vec<f64> {
    let theta = kernel.log_params();
    (0..theta.len())
        .map(|p| {
            let (mut plus, mut minus) = (kernel.clone(), kernel.clone());
            let mut tp = theta.clone();
            tp[p] += h;
            plus.set_log_params(&tp);
            tp[p] -= 2.0 * h;
            minus.set_log_params(&tp);
            (f(&plus) - f(&minus)) / (2.0 * h)
        })
        .collect()
}

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
            let fd = log_param_fd(&kernel, 1e-5, |k| weighted_sum(k, &x, &w));
            for (k, (a, fd)) in analytic.iter().zip(&fd).enumerate() {
                let err = rel_err(*a, *fd, 1e-6);
                assert!(
                    err < 1e-5,
                    "{expr} trial {trial} parameter {k}: analytic {a} vs fd {fd} (rel {err:e})"
                );
            }
        }
    }
}

/// The cross-covariance gradients a sparse GP uses: with respect to the
/// hyperparameters and to the first point set, and of the diagonal,
/// against central finite differences.
#[test]
fn cross_and_diagonal_gradients_match_finite_differences() {
    let mut rng = rng(15);
    let h = 1e-5;
    for expr in EXPRESSIONS {
        let (n1, n2, d) = (5, 7, 3);
        let x1 = inputs(&mut rng, n1, d);
        let x2 = inputs(&mut rng, n2, d);
        let w = Mat::from_fn(n1, n2, |i, j| ((i * 7 + j * 3) % 5) as f64 - 2.0);
        let kernel = random_kernel(&mut rng, expr, d);
        let cache = kernel.cross_with_cache(x1.as_ref(), x2.as_ref());
        let mut analytic = vec![0.0; kernel.n_params()];
        let mut dx1 = Mat::<f64>::zeros(n1, d);
        kernel.accumulate_cross_gradient(
            x1.as_ref(),
            x2.as_ref(),
            &cache,
            w.as_ref(),
            GradientTargets {
                params: Some(&mut analytic),
                inputs: Some((&mut dx1, 1.0)),
            },
        );
        let value = |k: &Kernel, x1: &Mat<f64>| {
            frobenius_dot(w.as_ref(), k.cross(x1.as_ref(), x2.as_ref()).as_ref())
        };
        let fd = log_param_fd(&kernel, h, |k| value(k, &x1));
        for (p, (a, fd)) in analytic.iter().zip(&fd).enumerate() {
            assert!(rel_err(*a, *fd, 1e-6) < 1e-5, "{expr} θ{p}: {a} vs {fd}");
        }
        for i in 0..n1 {
            for q in 0..d {
                let (mut plus, mut minus) = (x1.clone(), x1.clone());
                plus[(i, q)] += h;
                minus[(i, q)] -= h;
                let fd = (value(&kernel, &plus) - value(&kernel, &minus)) / (2.0 * h);
                let a = dx1[(i, q)];
                assert!(
                    rel_err(a, fd, 1e-6) < 1e-5,
                    "{expr} x1[{i},{q}]: {a} vs {fd}"
                );
            }
        }
        let wd: Vec<f64> = (0..n1).map(|i| i as f64 - 1.5).collect();
        let mut diag = vec![0.0; kernel.n_params()];
        kernel.accumulate_diag_gradient(x1.as_ref(), &wd, &mut diag);
        let dvalue = |k: &Kernel| -> f64 {
            k.diag(x1.as_ref())
                .iter()
                .zip(&wd)
                .map(|(a, b)| a * b)
                .sum()
        };
        let fd = log_param_fd(&kernel, h, dvalue);
        for (p, (a, fd)) in diag.iter().zip(&fd).enumerate() {
            assert!(
                rel_err(*a, *fd, 1e-6) < 1e-5,
                "{expr} diag θ{p}: {a} vs {fd}"
            );
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
    // Rational quadratic, GPy's form: σ² (1 + r²/2)^(−α); with the
    // lengthscale scaled by √α it tends to the RBF as α → ∞.
    let alpha = 0.7_f64;
    let rq = s2 * (1.0 + r * r / 2.0).powf(-alpha);
    assert!((set("ratquad", &[s2, l, alpha]) - rq).abs() < 1e-14);
    let big = 1e8_f64;
    let far = set("ratquad", &[s2, l * big.sqrt(), big]);
    assert!((far - s2 * (-0.5 * r * r).exp()).abs() < 1e-7, "{far}");
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
