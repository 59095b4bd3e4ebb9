//! `kernel:` of an exact GP: one kernel expression, or `auto`, which fits
//! each candidate kernel and keeps the one of highest log marginal
//! likelihood.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::kernels::{KernelExpr, KernelExprError, LeafName};

/// The kernel an exact GP fits.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum KernelChoice {
    /// This kernel.
    Expr(KernelExpr),
    /// Each of the candidates (`kernel_candidates`, by default
    /// [`KernelChoice::default_candidates`]), the highest log marginal
    /// likelihood kept.
    Auto,
}

impl KernelChoice {
    /// The word that selects [`KernelChoice::Auto`].
    pub const AUTO: &'static str = "auto";

    /// The kernels `auto` tries unless told otherwise: RBF and Matérn 5/2
    /// ARD, each alone and plus a linear kernel (a wheel radius or a scale
    /// error is linear in the inputs, which a stationary kernel fits
    /// poorly).
    pub fn default_candidates() -> Vec<KernelExpr> {
        let leaf = KernelExpr::Leaf;
        vec![
            leaf(LeafName::Rbf),
            leaf(LeafName::Matern52),
            KernelExpr::Sum(vec![leaf(LeafName::Rbf), leaf(LeafName::Linear)]),
            KernelExpr::Sum(vec![leaf(LeafName::Matern52), leaf(LeafName::Linear)]),
        ]
    }

    /// The expression, unless `auto`.
    pub fn expr(&self) -> Option<&KernelExpr> {
        match self {
            Self::Expr(e) => Some(e),
            Self::Auto => None,
        }
    }
}

impl Default for KernelChoice {
    fn default() -> Self {
        Self::Expr(KernelExpr::Leaf(LeafName::Rbf))
    }
}

impl From<KernelExpr> for KernelChoice {
    fn from(e: KernelExpr) -> Self {
        Self::Expr(e)
    }
}

impl fmt::Display for KernelChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Expr(e) => e.fmt(f),
            Self::Auto => f.write_str(Self::AUTO),
        }
    }
}

impl TryFrom<String> for KernelChoice {
    type Error = KernelExprError;

    fn try_from(text: String) -> Result<Self, Self::Error> {
        if text.trim().eq_ignore_ascii_case(Self::AUTO) {
            Ok(Self::Auto)
        } else {
            KernelExpr::parse(&text).map(Self::Expr)
        }
    }
}

impl From<KernelChoice> for String {
    fn from(c: KernelChoice) -> Self {
        c.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_and_expressions_parse_and_print_back() {
        for text in ["auto", "rbf", "matern52 + linear"] {
            let c = KernelChoice::try_from(text.to_string()).unwrap();
            assert_eq!(c.to_string(), text);
        }
        assert_eq!(
            KernelChoice::try_from(" Auto ".to_string()).unwrap(),
            KernelChoice::Auto
        );
        let e = KernelChoice::try_from("rbf +".to_string()).unwrap_err();
        assert!(e.to_string().contains("rbf +"), "{e}");
        let names: Vec<String> = KernelChoice::default_candidates()
            .iter()
            .map(|k| k.to_string())
            .collect();
        assert_eq!(
            names,
            ["rbf", "matern52", "rbf + linear", "matern52 + linear"]
        );
    }
}
