//! The shape a [`Kernel`] is saved in: one flat tagged enum, leaves and
//! combinations side by side (`{"kind": "rbf", "parameters": {...}}`,
//! `{"kind": "sum", "parameters": [...]}`), as every `.gpodo` model file
//! has stored it. The in-memory tree converts to and from it.

use serde::{Deserialize, Serialize};

use super::{Kernel, LeafKernel, Linear, RatQuad, Stationary, White};

/// A kernel as saved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "parameters", rename_all = "snake_case")]
pub enum SerializedKernel {
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
    #[serde(rename = "ratquad")]
    RatQuad(RatQuad),
    /// Sum of kernels.
    Sum(Vec<SerializedKernel>),
    /// Product of kernels.
    Product(Vec<SerializedKernel>),
}

impl From<SerializedKernel> for Kernel {
    fn from(k: SerializedKernel) -> Self {
        let children = |c: Vec<SerializedKernel>| c.into_iter().map(Kernel::from).collect();
        match k {
            SerializedKernel::Rbf(s) => Self::Leaf(LeafKernel::Rbf(s)),
            SerializedKernel::Matern52(s) => Self::Leaf(LeafKernel::Matern52(s)),
            SerializedKernel::Matern32(s) => Self::Leaf(LeafKernel::Matern32(s)),
            SerializedKernel::Linear(l) => Self::Leaf(LeafKernel::Linear(l)),
            SerializedKernel::White(w) => Self::Leaf(LeafKernel::White(w)),
            SerializedKernel::RatQuad(r) => Self::Leaf(LeafKernel::RatQuad(r)),
            SerializedKernel::Sum(c) => Self::Sum(children(c)),
            SerializedKernel::Product(c) => Self::Product(children(c)),
        }
    }
}

impl From<Kernel> for SerializedKernel {
    fn from(k: Kernel) -> Self {
        let children = |c: Vec<Kernel>| c.into_iter().map(SerializedKernel::from).collect();
        match k {
            Kernel::Leaf(LeafKernel::Rbf(s)) => Self::Rbf(s),
            Kernel::Leaf(LeafKernel::Matern52(s)) => Self::Matern52(s),
            Kernel::Leaf(LeafKernel::Matern32(s)) => Self::Matern32(s),
            Kernel::Leaf(LeafKernel::Linear(l)) => Self::Linear(l),
            Kernel::Leaf(LeafKernel::White(w)) => Self::White(w),
            Kernel::Leaf(LeafKernel::RatQuad(r)) => Self::RatQuad(r),
            Kernel::Sum(c) => Self::Sum(children(c)),
            Kernel::Product(c) => Self::Product(children(c)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_saved_shape_is_the_flat_one() {
        let k = Kernel::Sum(vec![
            Kernel::Leaf(LeafKernel::Rbf(Stationary::new(1.5, vec![0.5, 2.0]))),
            Kernel::Leaf(LeafKernel::White(White::new(0.01))),
        ]);
        let json = serde_json::to_string(&k).unwrap();
        assert_eq!(
            json,
            r#"{"kind":"sum","parameters":[{"kind":"rbf","parameters":{"variance":1.5,"lengthscales":[0.5,2.0]}},{"kind":"white","parameters":{"variance":0.01}}]}"#
        );
        let back: Kernel = serde_json::from_str(&json).unwrap();
        assert_eq!(back, k);
    }
}
