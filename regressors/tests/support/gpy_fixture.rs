//! Reading the GPy reference fixtures (`tests/fixtures/*.json`): matrices,
//! and kernels described leaf by leaf as the generator scripts write them.

use faer::Mat;
use gpodo_regressors::kernels::{Kernel, LeafKernel, Linear, RatQuad, Stationary, White};
use serde::Deserialize;

/// One leaf kernel of a fixture case.
#[derive(Debug, Deserialize)]
pub struct Part {
    /// `rbf`, `matern52`, `matern32`, `linear`, `white` or `ratquad`.
    pub kind: String,
    /// Signal variance (stationary and white kernels).
    #[serde(default)]
    pub variance: Option<f64>,
    /// ARD lengthscales (stationary kernels).
    #[serde(default)]
    pub lengthscales: Option<Vec<f64>>,
    /// Per-input variances (linear kernel).
    #[serde(default)]
    pub variances: Option<Vec<f64>>,
    /// The power `α` (rational quadratic kernel).
    #[serde(default)]
    pub power: Option<f64>,
}

/// A fixture's rows as a faer matrix.
pub fn matrix(rows: &[Vec<f64>]) -> Mat<f64> {
    Mat::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

fn leaf(part: &Part) -> Kernel {
    let stationary = || Stationary::new(part.variance.unwrap(), part.lengthscales.clone().unwrap());
    match part.kind.as_str() {
        "rbf" => Kernel::Leaf(LeafKernel::Rbf(stationary())),
        "matern52" => Kernel::Leaf(LeafKernel::Matern52(stationary())),
        "matern32" => Kernel::Leaf(LeafKernel::Matern32(stationary())),
        "linear" => Kernel::Leaf(LeafKernel::Linear(Linear::new(
            part.variances.clone().unwrap(),
        ))),
        "white" => Kernel::Leaf(LeafKernel::White(White::new(part.variance.unwrap()))),
        "ratquad" => Kernel::Leaf(LeafKernel::RatQuad(RatQuad::new(
            part.variance.unwrap(),
            part.lengthscales.clone().unwrap(),
            part.power.unwrap(),
        ))),
        other => panic!("unknown kind {other}"),
    }
}

/// The kernel of `parts` combined by `combine` (`single`, `sum`, `product`).
pub fn kernel(combine: &str, parts: &[Part]) -> Kernel {
    let leaves: Vec<Kernel> = parts.iter().map(leaf).collect();
    match combine {
        "single" => leaves.into_iter().next().unwrap(),
        "sum" => Kernel::Sum(leaves),
        "product" => Kernel::Product(leaves),
        other => panic!("unknown combination {other}"),
    }
}

/// GPy's name of a leaf kind (`Mat52` for `matern52`, ...).
pub fn gpy_name(kind: &str) -> &str {
    match kind {
        "matern52" => "Mat52",
        "matern32" => "Mat32",
        "ratquad" => "RatQuad",
        other => other,
    }
}

/// GPy's prefix of the leaves of a combination (`sum.`, `mul.` or none).
pub fn gpy_prefix(combine: &str) -> &'static str {
    match combine {
        "sum" => "sum.",
        "product" => "mul.",
        _ => "",
    }
}

/// GPy's gradient (natural units) in gpodo's kernel parameter order: leaf
/// by leaf, variance before lengthscales; then the noise variance.
pub fn gpy_kernel_gradient(
    combine: &str,
    parts: &[Part],
    gradients: &std::collections::BTreeMap<String, Vec<f64>>,
) -> Vec<f64> {
    let prefix = gpy_prefix(combine);
    let mut out = Vec::new();
    for part in parts {
        let name = gpy_name(&part.kind);
        let get = |suffix: &str| gradients[&format!("{prefix}{name}.{suffix}")].clone();
        match part.kind.as_str() {
            "linear" => out.extend(get("variances")),
            "white" => out.extend(get("variance")),
            "ratquad" => {
                out.extend(get("variance"));
                out.extend(get("lengthscale"));
                out.extend(get("power"));
            }
            _ => {
                out.extend(get("variance"));
                out.extend(get("lengthscale"));
            }
        }
    }
    out.extend(gradients["Gaussian_noise.variance"].clone());
    out
}
