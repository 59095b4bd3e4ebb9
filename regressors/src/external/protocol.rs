//! The wire format of `kind: external` (plugins/PROTOCOL.md): one JSON
//! object per line, requests on the plugin's stdin, replies on its stdout.
//! Matrices travel as `{"rows": n, "cols": d, "f64le": "<base64>"}`: the
//! row-major little-endian `f64` bytes, base64-encoded (NumPy reads them
//! with `np.frombuffer(base64.b64decode(s), "<f8").reshape(n, d)`).

use base64::Engine;
use base64::engine::general_purpose::STANDARD;
use gpodo_traits::SampleMatrix;
use serde::{Deserialize, Serialize};

/// The protocol version this build speaks.
pub const PROTOCOL_VERSION: u32 = 1;

/// A matrix on the wire.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WireMatrix {
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// Base64 of the row-major little-endian `f64` values.
    pub f64le: String,
}

impl WireMatrix {
    /// Encodes a matrix.
    pub fn encode(m: &SampleMatrix) -> Self {
        let mut bytes = Vec::with_capacity(m.as_slice().len() * 8);
        for v in m.as_slice() {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        Self {
            rows: m.nrows(),
            cols: m.ncols(),
            f64le: STANDARD.encode(bytes),
        }
    }

    /// Decodes the matrix, checking that it holds `rows × cols` values.
    ///
    /// # Errors
    /// A message saying what is wrong with the bytes or the shape.
    pub fn decode(&self) -> Result<SampleMatrix, String> {
        let bytes = STANDARD
            .decode(self.f64le.as_bytes())
            .map_err(|e| format!("`f64le` is not valid base64: {e}"))?;
        let expected = self.rows.saturating_mul(self.cols).saturating_mul(8);
        if bytes.len() != expected {
            return Err(format!(
                "`f64le` holds {} bytes, but {} × {} f64 values need {expected}",
                bytes.len(),
                self.rows,
                self.cols
            ));
        }
        let values = bytes
            .chunks_exact(8)
            .map(|c| {
                let mut b = [0u8; 8];
                b.copy_from_slice(c);
                f64::from_le_bytes(b)
            })
            .collect();
        SampleMatrix::from_row_major(self.rows, self.cols, values).map_err(|e| e.to_string())
    }
}

/// A request to the plugin.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "op", rename_all = "snake_case")]
pub enum Request<'a> {
    /// The first request: protocol version and the experiment's options.
    Hello {
        /// The request's number (echoed in the reply).
        id: u64,
        /// [`PROTOCOL_VERSION`].
        protocol: u32,
        /// The regressor's extra YAML fields.
        options: &'a serde_json::Map<String, serde_json::Value>,
    },
    /// Learn from a batch, replacing what was learned before.
    Fit {
        /// The request's number.
        id: u64,
        /// `n × d` inputs.
        inputs: WireMatrix,
        /// `n × o` targets.
        targets: WireMatrix,
        /// The `d` input names.
        input_names: &'a [String],
        /// The `o` target names.
        target_names: &'a [String],
        /// Whether the inputs are already z-scored.
        inputs_standardized: bool,
    },
    /// Predict mean and variance for each row.
    Predict {
        /// The request's number.
        id: u64,
        /// `m × d` inputs.
        inputs: WireMatrix,
    },
    /// Learn one more sample (online learning).
    Update {
        /// The request's number.
        id: u64,
        /// The sample's `d` inputs.
        inputs: &'a [f64],
        /// Its `o` targets.
        targets: &'a [f64],
    },
    /// Exit after replying.
    Shutdown {
        /// The request's number.
        id: u64,
    },
}

impl Request<'_> {
    /// The request's name (`hello`, `fit`, ...) for error messages.
    pub fn op(&self) -> &'static str {
        match self {
            Self::Hello { .. } => "hello",
            Self::Fit { .. } => "fit",
            Self::Predict { .. } => "predict",
            Self::Update { .. } => "update",
            Self::Shutdown { .. } => "shutdown",
        }
    }
}

/// Every reply: `ok`, the request's `id`, and either `error` or the fields
/// of the request's answer.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct Reply {
    /// The request's number.
    pub id: u64,
    /// Whether the request succeeded.
    pub ok: bool,
    /// Why it failed (when `ok` is false).
    #[serde(default)]
    pub error: Option<String>,
    /// The rest of the reply.
    #[serde(flatten)]
    pub body: serde_json::Map<String, serde_json::Value>,
}

/// The answer to `hello`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct HelloReply {
    /// The protocol version the plugin speaks.
    pub protocol: u32,
    /// The model's name, for logs.
    #[serde(default)]
    pub name: Option<String>,
    /// What it can do: `fit`, `predict`, and optionally `update`.
    pub capabilities: Vec<String>,
}

/// The answer to `fit` (every field optional).
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
pub struct FitReply {
    /// The objective the fit optimised (e.g. a log marginal likelihood).
    #[serde(default)]
    pub objective: Option<f64>,
    /// Objective evaluations.
    #[serde(default)]
    pub evaluations: Option<usize>,
    /// Optimiser iterations.
    #[serde(default)]
    pub iterations: Option<u64>,
    /// Learned hyperparameters by name.
    #[serde(default)]
    pub parameters: Vec<(String, f64)>,
}

/// The answer to `predict`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct PredictReply {
    /// `m × o` predictive means.
    pub mean: WireMatrix,
    /// `m × o` predictive variances.
    pub variance: WireMatrix,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_matrix_round_trips_bit_exactly() {
        let m = SampleMatrix::from_rows(3, &[[1.0, -0.0, f64::MIN_POSITIVE], [1e300, 0.1, -2.5]])
            .unwrap();
        let wire = WireMatrix::encode(&m);
        assert_eq!((wire.rows, wire.cols), (2, 3));
        let back = wire.decode().unwrap();
        for (a, b) in m.as_slice().iter().zip(back.as_slice()) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }

    #[test]
    fn a_matrix_with_the_wrong_byte_count_is_refused() {
        let mut wire = WireMatrix::encode(&SampleMatrix::zeros(2, 2));
        wire.rows = 3;
        let e = wire.decode().unwrap_err();
        assert!(e.contains("32 bytes") && e.contains("48"), "{e}");
        wire.f64le = "not base64!".into();
        assert!(wire.decode().unwrap_err().contains("base64"));
    }

    #[test]
    fn the_bytes_are_little_endian_row_major() {
        let m = SampleMatrix::from_rows(2, &[[1.0, 2.0]]).unwrap();
        let wire = WireMatrix::encode(&m);
        let bytes = STANDARD.decode(wire.f64le).unwrap();
        assert_eq!(&bytes[..8], &1.0f64.to_le_bytes());
        assert_eq!(&bytes[8..], &2.0f64.to_le_bytes());
    }
}
