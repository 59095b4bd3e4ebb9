//! The sparse-spectrum GP (I-SSGP): its rank-one updates against a batch
//! solve on the same features, its features against the kernels' closed
//! forms, its mean against the exact GP's as the features grow, forgetting,
//! and saving.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use faer::Mat;
use gpodo_regressors::exact_gp::{ExactGp, ExactGpParams};
use gpodo_regressors::kernels::KernelExpr;
use gpodo_regressors::kernels::LeafName;
use gpodo_regressors::model_file::{ModelFile, Provenance};
use gpodo_regressors::sparse_spectrum::draw_frequencies;
use gpodo_regressors::{RegressorSpec, SparseSpectrumGp, SparseSpectrumParams};
use gpodo_traits::{ResidualRegressor, SampleMatrix};
use nalgebra::{DMatrix, DVector};
use support::*;

fn params(features: usize, warmup_rows: usize) -> SparseSpectrumParams {
    SparseSpectrumParams {
        features,
        warmup_rows,
        ..SparseSpectrumParams::default()
    }
}

/// The features of a scaled row, computed here from the state's
/// frequencies (independently of the model's own code), with the constant
/// `√bias` last when `bias > 0`.
fn phi_with_bias(freq: &SampleMatrix, signal: f64, bias: f64, x: &[f64]) -> DVector<f64> {
    let m = freq.nrows();
    let scale = (signal / m as f64).sqrt();
    let mut out = DVector::zeros(2 * m + usize::from(bias > 0.0));
    for i in 0..m {
        let a: f64 = freq.row(i).iter().zip(x).map(|(w, v)| w * v).sum();
        out[i] = scale * a.cos();
        out[m + i] = scale * a.sin();
    }
    if bias > 0.0 {
        out[2 * m] = bias.sqrt();
    }
    out
}

fn phi(freq: &SampleMatrix, signal: f64, x: &[f64]) -> DVector<f64> {
    phi_with_bias(freq, signal, 0.0, x)
}

fn scaled(s: &Option<gpodo_traits::Standardizer>, v: &[f64]) -> Vec<f64> {
    match s {
        Some(s) => v
            .iter()
            .zip(s.mean.iter().zip(&s.std))
            .map(|(v, (m, sd))| (v - m) / sd)
            .collect(),
        None => v.to_vec(),
    }
}

/// A and b accumulated in one batch, with forgetting `lambda`; then the
/// discounted row count and each output's discounted `Σ y²`.
fn batch(
    model: &SparseSpectrumGp,
    x: &Mat<f64>,
    y: &Mat<f64>,
    lambda: f64,
) -> (DMatrix<f64>, DMatrix<f64>, f64, Vec<f64>) {
    let s = model.state().unwrap();
    let bias = s.params.bias_variance;
    let dim = 2 * s.frequencies.nrows() + usize::from(bias > 0.0);
    let n = x.nrows();
    let mut a = DMatrix::identity(dim, dim) * s.noise_variance * lambda.powi(n as i32);
    let mut b = DMatrix::zeros(dim, y.ncols());
    let (mut rows, mut energy) = (0.0, vec![0.0; y.ncols()]);
    for i in 0..n {
        let xi: Vec<f64> = (0..x.ncols()).map(|j| x[(i, j)]).collect();
        let yi: Vec<f64> = (0..y.ncols()).map(|j| y[(i, j)]).collect();
        let f = phi_with_bias(
            &s.frequencies,
            s.signal_variance,
            bias,
            &scaled(&s.input_scaler, &xi),
        );
        let t = scaled(&s.output_scaler, &yi);
        let weight = lambda.powi((n - 1 - i) as i32);
        a += &f * f.transpose() * weight;
        for (j, tj) in t.iter().enumerate() {
            let mut col = b.column_mut(j);
            col.axpy(weight * tj, &f, 1.0);
            energy[j] += weight * tj * tj;
        }
        rows += weight;
    }
    (a, b, rows, energy)
}

#[test]
fn rank_one_updates_equal_a_batch_solve_on_the_same_features() {
    let mut r = rng(37);
    let x = inputs(&mut r, 150, 4);
    let y = targets(&mut r, &x, 0.1);
    let data = dataset(&x, &y);
    for (lambda, bias, learn_noise) in [
        (1.0, 0.0, true),
        (0.98, 0.0, true),
        (1.0, 0.7, true),
        (0.98, 0.7, false),
        (1.0, 0.0, false),
    ] {
        let mut model = SparseSpectrumGp::new(SparseSpectrumParams {
            forgetting: lambda,
            bias_variance: bias,
            learn_noise,
            ..params(60, 50)
        })
        .unwrap();
        model.fit(&data).unwrap();
        let s = model.state().unwrap();
        let (a, b, rows, energy) = batch(&model, &x, &y, lambda);
        let llt = &s.factor * s.factor.transpose();
        let err = (&llt - &a).abs().max() / a.abs().max();
        assert!(err < 1e-10, "λ = {lambda}: factor off by {err:e}");
        assert!(
            (&s.rhs - &b).abs().max() / b.abs().max() < 1e-10,
            "λ = {lambda}"
        );
        // The mean φ*ᵀ A⁻¹ b, from the batch A.
        let q = inputs(&mut r, 10, 4);
        let got = model.predict(&sample_matrix(&q)).unwrap();
        let w = a.clone().cholesky().unwrap().solve(&b);
        let out = s.output_scaler.as_ref().unwrap();
        for i in 0..q.nrows() {
            let qi: Vec<f64> = (0..q.ncols()).map(|j| q[(i, j)]).collect();
            let f = phi_with_bias(
                &s.frequencies,
                s.signal_variance,
                bias,
                &scaled(&s.input_scaler, &qi),
            );
            let leverage = f.dot(&a.clone().cholesky().unwrap().solve(&f));
            for (j, energy) in energy.iter().enumerate() {
                let expected = f.dot(&w.column(j)) * out.std[j] + out.mean[j];
                assert!(
                    rel_err(got.mean.get(i, j), expected, 1e-12) < 1e-10,
                    "λ = {lambda}"
                );
                // The Normal-inverse-Gamma posterior of σ² (prior a₀ = 2,
                // b₀ = σ_n²), its Student-t variance.
                let shape = 2.0 + rows / 2.0;
                let scale =
                    (s.noise_variance + 0.5 * (energy - b.column(j).dot(&w.column(j)))) / shape;
                let variance = if learn_noise {
                    scale * (1.0 + leverage) * shape / (shape - 1.0)
                } else {
                    s.noise_variance * (1.0 + leverage)
                };
                assert!(
                    rel_err(got.variance.get(i, j), variance * out.std[j].powi(2), 1e-12) < 1e-9,
                    "λ = {lambda}: variance {} against {}",
                    got.variance.get(i, j),
                    variance * out.std[j].powi(2)
                );
            }
        }
    }
}

#[test]
fn the_features_reproduce_each_kernel_from_its_spectral_density() {
    // E[φ(x)ᵀφ(x')] = k(x − x'): with many frequencies the inner product
    // matches the closed forms of RBF, Matérn 5/2 and Matérn 3/2.
    let ell = [0.7, 1.3];
    for leaf in [LeafName::Rbf, LeafName::Matern52, LeafName::Matern32] {
        let freq = draw_frequencies(leaf, &ell, 50_000, 1).unwrap();
        for (a, b) in [
            ([0.0, 0.0], [0.3, -0.2]),
            ([0.1, 0.5], [-0.7, 0.4]),
            ([0.0, 0.0], [1.5, 1.0]),
        ] {
            let r2: f64 = a
                .iter()
                .zip(&b)
                .zip(&ell)
                .map(|((u, v), l)| ((u - v) / l).powi(2))
                .sum();
            let rr = r2.sqrt();
            let k = match leaf {
                LeafName::Rbf => (-0.5 * r2).exp(),
                LeafName::Matern52 => {
                    let t = 5f64.sqrt() * rr;
                    (1.0 + t + t * t / 3.0) * (-t).exp()
                }
                _ => {
                    let t = 3f64.sqrt() * rr;
                    (1.0 + t) * (-t).exp()
                }
            };
            let got = phi(&freq, 1.0, &a).dot(&phi(&freq, 1.0, &b));
            // The Monte Carlo error of 50 000 frequencies is about 0.003.
            assert!(
                (got - k).abs() < 0.015,
                "{leaf:?} at r = {rr:.2}: {got} against {k}"
            );
        }
    }
}

#[test]
fn the_mean_approaches_the_exact_gps_as_the_features_grow() {
    let mut r = rng(11);
    let x = inputs(&mut r, 120, 3);
    let y = targets(&mut r, &x, 0.1);
    let data = dataset(&x, &y);
    let q = sample_matrix(&inputs(&mut r, 30, 3));
    // The warm-up on every row is the exact GP itself.
    let mut gp = ExactGp::new(ExactGpParams::default()).unwrap();
    gp.fit(&data).unwrap();
    let exact = gp.predict(&q).unwrap();
    let mut errors = Vec::new();
    for features in [20, 200, 2000] {
        let mut model = SparseSpectrumGp::new(params(features, 120)).unwrap();
        model.fit(&data).unwrap();
        let got = model.predict(&q).unwrap();
        let err = (0..q.nrows())
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| (got.mean.get(i, j) - exact.mean.get(i, j)).abs())
            .fold(0.0, f64::max);
        errors.push(err);
    }
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
    // The targets' scale is about 1: at D = 2000 the means agree closely.
    assert!(errors[2] < 0.05, "{errors:?}");
}

#[test]
fn updates_learn_on_and_a_saved_model_goes_on_learning_identically() {
    let mut r = rng(5);
    let x = inputs(&mut r, 200, 3);
    let y = targets(&mut r, &x, 0.05);
    let head: Vec<usize> = (0..80).collect();
    let data = dataset(&x, &y);
    let first = gpodo_traits::ResidualDataset::new(
        data.inputs.select_rows(&head),
        data.targets.select_rows(&head),
        data.input_names.clone(),
        data.target_names.clone(),
    )
    .unwrap();
    let spec = RegressorSpec::SparseSpectrum(params(100, 80));
    let (file, mut model, _) =
        ModelFile::fit_with_progress(&spec, &first, None, Provenance::default(), None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.gpodo");
    file.save(&path).unwrap();
    let mut loaded = ModelFile::load(&path).unwrap().predictor().unwrap();
    assert!(model.supports_online_update());
    let q = sample_matrix(&inputs(&mut r, 20, 3));
    let before = model.predict(&q).unwrap();
    for i in 80..200 {
        let xi: Vec<f64> = (0..3).map(|j| x[(i, j)]).collect();
        let yi: Vec<f64> = (0..3).map(|j| y[(i, j)]).collect();
        model.update(&xi, &yi).unwrap();
        loaded.model_mut().update(&xi, &yi).unwrap();
    }
    let (a, b) = (
        model.predict(&q).unwrap(),
        loaded.model_mut().predict(&q).unwrap(),
    );
    assert_eq!(a.mean, b.mean);
    assert_eq!(a.variance, b.variance);
    assert_ne!(a.mean, before.mean);
    // Fitting on all rows at once gives the same model as updating.
    let mut batch = SparseSpectrumGp::new(params(100, 80)).unwrap();
    batch.fit(&data).unwrap();
    let c = batch.predict(&q).unwrap();
    for (u, v) in a.mean.as_slice().iter().zip(c.mean.as_slice()) {
        assert!((u - v).abs() < 1e-10, "{u} {v}");
    }
}

#[test]
fn settings_outside_their_range_are_named() {
    for (p, field) in [
        (
            SparseSpectrumParams {
                features: 3,
                ..Default::default()
            },
            "features",
        ),
        (
            SparseSpectrumParams {
                forgetting: 1.5,
                ..Default::default()
            },
            "forgetting",
        ),
        (
            SparseSpectrumParams {
                bias_variance: -1.0,
                ..Default::default()
            },
            "bias_variance",
        ),
        (
            SparseSpectrumParams {
                kernel: KernelExpr::parse("rbf + linear").unwrap(),
                ..Default::default()
            },
            "kernel",
        ),
    ] {
        let e = SparseSpectrumGp::new(p).unwrap_err().to_string();
        assert!(e.contains(field), "{e}");
    }
}

#[test]
fn a_stream_warms_up_on_its_first_rows_and_learns_on() {
    let mut r = rng(8);
    let x = inputs(&mut r, 150, 3);
    let y = targets(&mut r, &x, 0.05);
    let data = dataset(&x, &y);
    let row = |m: &Mat<f64>, i: usize| (0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<f64>>();
    let mut stream = SparseSpectrumGp::new(params(80, 50)).unwrap();
    let q = sample_matrix(&inputs(&mut r, 5, 3));
    assert!(stream.predict(&q).is_err());
    for i in 0..150 {
        stream.update(&row(&x, i), &row(&y, i)).unwrap();
        if i == 10 {
            // Before the warm-up: the running mean of the rows so far.
            let p = stream.predict(&q).unwrap();
            let mean0: f64 = (0..=10).map(|k| y[(k, 0)]).sum::<f64>() / 11.0;
            assert!((p.mean.get(0, 0) - mean0).abs() < 1e-12);
        }
    }
    // The same model as a fit on all rows (the warm-up on the first 50).
    let mut batch = SparseSpectrumGp::new(params(80, 50)).unwrap();
    batch.fit(&data).unwrap();
    let (a, b) = (stream.predict(&q).unwrap(), batch.predict(&q).unwrap());
    for (u, v) in a.mean.as_slice().iter().zip(b.mean.as_slice()) {
        assert!((u - v).abs() < 1e-10, "{u} {v}");
    }
}
