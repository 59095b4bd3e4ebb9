//! Agreement of the sparse GP with an independent implementation: for fixed
//! hyperparameters and inducing inputs, the VFE bound and the FITC log
//! likelihood, their gradients with respect to every hyperparameter, the
//! noise and the inducing inputs, and the predictive mean and variances equal
//! GPy 1.13's (`VarDTC` and `FITC` inference) to 1e-8.
//! Fixture and generator: `tests/fixtures/sparse_reference.json`,
//! `tests/fixtures/make_sparse_reference.py`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use std::collections::BTreeMap;

use gpodo_regressors::sparse_gp::bound::sparse_objective;
use gpodo_regressors::sparse_gp::{Approximation, SparsePosterior};
use gpodo_regressors::{GpProblem, SparseProblem};
use serde::Deserialize;
use support::gpy_fixture::{Part, gpy_kernel_gradient, kernel, matrix};

#[derive(Deserialize)]
struct Fixture {
    x_train: Vec<Vec<f64>>,
    y_train: Vec<Vec<f64>>,
    x_test: Vec<Vec<f64>>,
    inducing: Vec<Vec<f64>>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    approximation: String,
    combine: String,
    parts: Vec<Part>,
    noise_variance: f64,
    jitter: f64,
    objective: f64,
    gradient_natural: BTreeMap<String, Vec<f64>>,
    mean: Vec<Vec<f64>>,
    variance_latent: Vec<f64>,
    variance_noisy: Vec<f64>,
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

#[test]
fn bound_gradients_and_predictions_agree_with_gpy() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/sparse_reference.json"
    ))
    .unwrap();
    let fixture: Fixture = serde_json::from_str(&text).unwrap();
    let (x, y, xs, z) = (
        matrix(&fixture.x_train),
        matrix(&fixture.y_train),
        matrix(&fixture.x_test),
        matrix(&fixture.inducing),
    );
    assert_eq!(fixture.cases.len(), 4);
    for case in &fixture.cases {
        let approximation = match case.approximation.as_str() {
            "vfe" => Approximation::Vfe,
            "fitc" => Approximation::Fitc,
            other => panic!("unknown approximation {other}"),
        };
        let k = kernel(&case.combine, &case.parts);
        let eval = sparse_objective(
            SparseProblem {
                gp: GpProblem::new(&k, case.noise_variance, x.as_ref(), y.as_ref()),
                z: z.as_ref(),
                approximation,
                jitter: case.jitter,
            },
            true,
            true,
        )
        .unwrap();
        assert_eq!(eval.extra_jitter, 0.0, "{}", case.name);
        assert!(
            close(eval.value, case.objective, 1e-8),
            "{}: objective {} vs GPy {}",
            case.name,
            eval.value,
            case.objective
        );
        // Ours is with respect to log θ: ∂/∂θ = (∂/∂ log θ) / θ.
        let mut theta: Vec<f64> = k.log_params().iter().map(|v| v.exp()).collect();
        theta.push(case.noise_variance);
        let reference = gpy_kernel_gradient(&case.combine, &case.parts, &case.gradient_natural);
        let ours = eval.gradient.unwrap();
        assert_eq!(ours.len(), reference.len(), "{}", case.name);
        for (i, ((g, t), r)) in ours.iter().zip(&theta).zip(&reference).enumerate() {
            assert!(
                close(g / t, *r, 1e-7),
                "{}: gradient {i}: {} vs GPy {r}",
                case.name,
                g / t
            );
        }
        let dz = eval.inducing_gradient.unwrap();
        let reference_dz = &case.gradient_natural["inducing_inputs"];
        for i in 0..dz.nrows() {
            for q in 0..dz.ncols() {
                let r = reference_dz[i * dz.ncols() + q];
                assert!(
                    close(dz[(i, q)], r, 1e-7),
                    "{}: ∂/∂Z[{i},{q}] {} vs GPy {r}",
                    case.name,
                    dz[(i, q)]
                );
            }
        }
        let posterior = SparsePosterior::new(SparseProblem {
            gp: GpProblem::new(&k, case.noise_variance, x.as_ref(), y.as_ref()),
            z: z.as_ref(),
            approximation,
            jitter: case.jitter,
        })
        .unwrap();
        let m = posterior.predict(xs.as_ref());
        for i in 0..xs.nrows() {
            for c in 0..y.ncols() {
                assert!(
                    close(m.mean[(i, c)], case.mean[i][c], 1e-8),
                    "{}: mean {i},{c}: {} vs GPy {}",
                    case.name,
                    m.mean[(i, c)],
                    case.mean[i][c]
                );
            }
            assert!(
                close(m.latent_variance[i], case.variance_latent[i], 1e-8),
                "{}: latent variance {i}: {} vs GPy {}",
                case.name,
                m.latent_variance[i],
                case.variance_latent[i]
            );
            let noisy = m.latent_variance[i] + m.noise_variance;
            assert!(
                close(noisy, case.variance_noisy[i], 1e-8),
                "{}: noisy variance {i}: {noisy} vs GPy {}",
                case.name,
                case.variance_noisy[i]
            );
        }
    }
}
