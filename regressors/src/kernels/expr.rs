//! Kernel expressions as written in YAML (`kernel: rbf + linear`,
//! `matern52 * linear + white`): leaves combined by `+` and `*` with the usual
//! precedence and parentheses. Parsed once, when the configuration is read;
//! [`KernelExpr::build`] turns an expression into a [`Kernel`] with initial
//! hyperparameters for `d` inputs.

use std::fmt;

use serde::{Deserialize, Serialize};

use super::{Kernel, LeafName};

/// A parsed kernel expression.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum KernelExpr {
    /// A leaf kernel.
    Leaf(LeafName),
    /// Sum of two or more kernels.
    Sum(Vec<KernelExpr>),
    /// Product of two or more kernels.
    Product(Vec<KernelExpr>),
}

/// Why an expression does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("kernel expression `{expression}`, at character {position}: expected {expected}")]
pub struct KernelExprError {
    /// The expression as written.
    pub expression: String,
    /// 1-based character position of the problem.
    pub position: usize,
    /// What was expected there.
    pub expected: String,
}

/// Initial hyperparameters used by [`KernelExpr::build`] (standardised
/// inputs and outputs assumed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct KernelInit {
    /// Signal variance of stationary kernels (default 1).
    pub variance: f64,
    /// Lengthscale of every input; `None` (default) uses `√d`, the typical
    /// distance between standardised points in `d` dimensions.
    pub lengthscale: Option<f64>,
    /// Per-input variance of the linear kernel; `None` (default) uses `1/d`
    /// so that `k(x, x) ≈ 1` on standardised inputs.
    pub linear_variance: Option<f64>,
    /// Variance of the white kernel (default 0.01).
    pub white_variance: f64,
    /// Power `α` of the rational quadratic kernel (default 2, GPy's).
    pub power: f64,
}

impl Default for KernelInit {
    fn default() -> Self {
        Self {
            variance: 1.0,
            lengthscale: None,
            linear_variance: None,
            white_variance: 0.01,
            power: 2.0,
        }
    }
}

impl KernelExpr {
    /// The number of additive terms, nested sums flattened: 1 for a leaf
    /// or a product, `Σ` of the children's for a sum (`rbf + linear` has
    /// 2, `(rbf + linear) + white` 3, `(rbf + linear) * white` 1).
    pub fn additive_terms(&self) -> usize {
        match self {
            Self::Leaf(_) | Self::Product(_) => 1,
            Self::Sum(children) => children.iter().map(Self::additive_terms).sum(),
        }
    }

    /// Parses an expression such as `rbf + linear` or `(rbf + linear) * matern32`.
    ///
    /// # Errors
    /// [`KernelExprError`] with the position and what was expected.
    pub fn parse(text: &str) -> Result<Self, KernelExprError> {
        let mut parser = Parser {
            text,
            chars: text.char_indices().collect(),
            at: 0,
        };
        let expr = parser.sum()?;
        parser.skip_spaces();
        if parser.at < parser.chars.len() {
            return Err(parser.error("`+`, `*` or the end of the expression"));
        }
        Ok(expr)
    }

    /// Builds the kernel for `d` inputs with initial hyperparameters
    /// ([`LeafName::build`]).
    pub fn build(&self, d: usize, init: &KernelInit) -> Kernel {
        match self {
            Self::Leaf(name) => Kernel::Leaf(name.build(d, init)),
            Self::Sum(terms) => Kernel::Sum(terms.iter().map(|t| t.build(d, init)).collect()),
            Self::Product(factors) => {
                Kernel::Product(factors.iter().map(|f| f.build(d, init)).collect())
            }
        }
    }
}

impl fmt::Display for KernelExpr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Leaf(name) => f.write_str(name.as_str()),
            Self::Sum(terms) => {
                let parts: Vec<String> = terms.iter().map(ToString::to_string).collect();
                f.write_str(&parts.join(" + "))
            }
            Self::Product(factors) => {
                let parts: Vec<String> = factors
                    .iter()
                    .map(|x| match x {
                        Self::Sum(_) => format!("({x})"),
                        Self::Leaf(_) | Self::Product(_) => x.to_string(),
                    })
                    .collect();
                f.write_str(&parts.join(" * "))
            }
        }
    }
}

impl TryFrom<String> for KernelExpr {
    type Error = KernelExprError;
    fn try_from(value: String) -> Result<Self, Self::Error> {
        Self::parse(&value)
    }
}

impl From<KernelExpr> for String {
    fn from(value: KernelExpr) -> Self {
        value.to_string()
    }
}

/// Recursive-descent parser: `sum := product ('+' product)*`,
/// `product := atom ('*' atom)*`, `atom := name | '(' sum ')'`.
struct Parser<'a> {
    text: &'a str,
    chars: Vec<(usize, char)>,
    at: usize,
}

impl Parser<'_> {
    fn error(&self, expected: &str) -> KernelExprError {
        KernelExprError {
            expression: self.text.to_string(),
            position: self.at + 1,
            expected: expected.to_string(),
        }
    }

    fn skip_spaces(&mut self) {
        while self
            .chars
            .get(self.at)
            .is_some_and(|(_, c)| c.is_whitespace())
        {
            self.at += 1;
        }
    }

    fn eat(&mut self, symbol: char) -> bool {
        self.skip_spaces();
        if self.chars.get(self.at).is_some_and(|&(_, c)| c == symbol) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn sum(&mut self) -> Result<KernelExpr, KernelExprError> {
        let mut terms = vec![self.product()?];
        while self.eat('+') {
            terms.push(self.product()?);
        }
        Ok(if terms.len() == 1 {
            terms.remove(0)
        } else {
            KernelExpr::Sum(terms)
        })
    }

    fn product(&mut self) -> Result<KernelExpr, KernelExprError> {
        let mut factors = vec![self.atom()?];
        while self.eat('*') {
            factors.push(self.atom()?);
        }
        Ok(if factors.len() == 1 {
            factors.remove(0)
        } else {
            KernelExpr::Product(factors)
        })
    }

    fn atom(&mut self) -> Result<KernelExpr, KernelExprError> {
        let expected = format!("a kernel name ({}) or `(`", LeafName::listed());
        if self.eat('(') {
            let inner = self.sum()?;
            if !self.eat(')') {
                return Err(self.error("`)`"));
            }
            return Ok(inner);
        }
        self.skip_spaces();
        let start = self.at;
        while self
            .chars
            .get(self.at)
            .is_some_and(|(_, c)| c.is_ascii_alphanumeric() || *c == '_')
        {
            self.at += 1;
        }
        if start == self.at {
            return Err(self.error(&expected));
        }
        let name: String = self.chars[start..self.at].iter().map(|(_, c)| c).collect();
        name.parse::<LeafName>().map(KernelExpr::Leaf).map_err(|_| {
            self.at = start;
            KernelExprError {
                expected: format!("a kernel name ({}), found `{name}`", LeafName::listed()),
                ..self.error("")
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_sums_products_and_parentheses_with_precedence() {
        let e = KernelExpr::parse("rbf + linear*white").unwrap();
        assert_eq!(
            e,
            KernelExpr::Sum(vec![
                KernelExpr::Leaf(LeafName::Rbf),
                KernelExpr::Product(vec![
                    KernelExpr::Leaf(LeafName::Linear),
                    KernelExpr::Leaf(LeafName::White)
                ])
            ])
        );
        let e = KernelExpr::parse("(rbf + linear) * Matern32").unwrap();
        assert_eq!(e.to_string(), "(rbf + linear) * matern32");
        assert_eq!(KernelExpr::parse(&e.to_string()).unwrap(), e);
    }

    #[test]
    fn rejects_unknown_names_and_dangling_operators_with_position() {
        let err = KernelExpr::parse("rbf + rbff").unwrap_err();
        assert_eq!(err.position, 7);
        assert!(err.expected.contains("found `rbff`"), "{err}");
        let err = KernelExpr::parse("rbf +").unwrap_err();
        assert_eq!(err.position, 6);
        let err = KernelExpr::parse("(rbf").unwrap_err();
        assert!(err.expected.contains(')'));
        let err = KernelExpr::parse("rbf linear").unwrap_err();
        assert_eq!(err.position, 5);
        assert!(KernelExpr::parse("").is_err());
    }
}
