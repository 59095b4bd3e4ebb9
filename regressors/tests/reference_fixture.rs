//! Agreement with an independent implementation: for fixed hyperparameters
//! the log marginal likelihood, its gradient, the predictive mean and the
//! latent and noisy variances equal GPy 1.13's (cross-checked against
//! scikit-learn and plain NumPy when the fixture was made) to 1e-8.
//! Fixture and generator: `tests/fixtures/gp_reference.json`,
//! `tests/fixtures/make_gp_reference.py`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use gpodo_regressors::GpProblem;
use gpodo_regressors::exact_gp::likelihood::log_marginal_likelihood;
use gpodo_regressors::exact_gp::posterior::Posterior;
use serde::Deserialize;
use support::gpy_fixture::{Part, gpy_kernel_gradient, kernel, matrix};

#[derive(Deserialize)]
struct Fixture {
    x_train: Vec<Vec<f64>>,
    y_train: Vec<Vec<f64>>,
    x_test: Vec<Vec<f64>>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    combine: String,
    parts: Vec<Part>,
    noise_variance: f64,
    log_marginal_likelihood: f64,
    lml_gradient_natural: std::collections::BTreeMap<String, Vec<f64>>,
    mean: Vec<Vec<f64>>,
    variance_latent: Vec<f64>,
    variance_noisy: Vec<f64>,
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-8 * b.abs().max(1.0)
}

#[test]
fn lml_gradient_and_predictions_agree_with_gpy() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/gp_reference.json"
    ))
    .unwrap();
    let fixture: Fixture = serde_json::from_str(&text).unwrap();
    let (x, y, xs) = (
        matrix(&fixture.x_train),
        matrix(&fixture.y_train),
        matrix(&fixture.x_test),
    );
    assert_eq!(fixture.cases.len(), 10);
    for case in &fixture.cases {
        let k = kernel(&case.combine, &case.parts);
        let eval = log_marginal_likelihood(
            GpProblem::new(&k, case.noise_variance, x.as_ref(), y.as_ref()),
            true,
        )
        .unwrap();
        assert_eq!(eval.jitter, 0.0, "{}", case.name);
        assert!(
            close(eval.lml, case.log_marginal_likelihood),
            "{}: LML {} vs GPy {}",
            case.name,
            eval.lml,
            case.log_marginal_likelihood
        );
        // Ours is with respect to log θ: ∂/∂θ = (∂/∂ log θ) / θ.
        let mut theta: Vec<f64> = k.log_params().iter().map(|v| v.exp()).collect();
        theta.push(case.noise_variance);
        let ours = eval.gradient.unwrap();
        for (i, ((g, t), reference)) in ours
            .iter()
            .zip(&theta)
            .zip(gpy_kernel_gradient(
                &case.combine,
                &case.parts,
                &case.lml_gradient_natural,
            ))
            .enumerate()
        {
            assert!(
                (g / t - reference).abs() <= 1e-7 * reference.abs().max(1.0),
                "{}: gradient {i}: {} vs GPy {reference}",
                case.name,
                g / t
            );
        }
        let posterior = Posterior::new(k, case.noise_variance, x.clone(), y.clone()).unwrap();
        let m = posterior.predict(xs.as_ref());
        for i in 0..xs.nrows() {
            for c in 0..y.ncols() {
                assert!(
                    close(m.mean[(i, c)], case.mean[i][c]),
                    "{}: mean {i},{c}",
                    case.name
                );
            }
            assert!(
                close(m.latent_variance[i], case.variance_latent[i]),
                "{}: latent variance {i}",
                case.name
            );
            let noisy = m.latent_variance[i] + m.noise_variance;
            assert!(
                close(noisy, case.variance_noisy[i]),
                "{}: noisy variance {i}",
                case.name
            );
        }
    }
}
