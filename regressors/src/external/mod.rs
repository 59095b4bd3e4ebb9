//! `kind: external`: a regressor that is a child process speaking a small
//! line-delimited JSON protocol (`plugins/PROTOCOL.md`), so that a model
//! written in any language — typically Python with NumPy — takes part in
//! every table, sweep, benchmark and gated scheme beside the built-in ones.
//!
//! The process is started on first use (`hello`, then `fit`, `predict`,
//! `update`), asked to `shutdown` when the regressor is dropped, and killed
//! and reaped on any failure: a crash, a reply later than `timeout_secs`,
//! a reply that is not the protocol's JSON, a matrix of the wrong shape, a
//! non-finite value. The error names the regressor, the request and the
//! plugin's last stderr lines.

pub mod process;
pub mod protocol;

use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use gpodo_traits::{
    Error, FitReport, Predictions, ResidualDataset, ResidualRegressor, SampleMatrix,
};
use serde::{Deserialize, Serialize};

use crate::RegressorError;
use process::{PluginProcess, ProcessFailure};
use protocol::{FitReply, HelloReply, PROTOCOL_VERSION, PredictReply, Reply, Request, WireMatrix};

/// How long `shutdown` may take when the regressor is dropped.
const SHUTDOWN_TIMEOUT: Duration = Duration::from_secs(2);

fn default_timeout_secs() -> f64 {
    600.0
}

/// The YAML fields of `kind: external`; every other field is passed to the
/// plugin as its `options` (in `hello`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExternalParams {
    /// The program and its arguments, e.g. `[python3, plugins/python/examples/ridge.py]`;
    /// relative paths resolve against the experiment file's folder.
    pub command: Vec<String>,
    /// The name in reports (default `external: <script file name>`).
    #[serde(default)]
    pub label: Option<String>,
    /// The longest any one request may take before the plugin is killed
    /// (seconds, default 600).
    #[serde(default = "default_timeout_secs")]
    pub timeout_secs: f64,
    /// Every other field, passed to the plugin.
    #[serde(flatten)]
    pub options: serde_json::Map<String, serde_json::Value>,
}

impl ExternalParams {
    /// The params running `command` with no options.
    pub fn new(command: Vec<String>) -> Self {
        Self {
            command,
            label: None,
            timeout_secs: default_timeout_secs(),
            options: serde_json::Map::new(),
        }
    }

    /// The name in reports, before its options.
    pub fn base_label(&self) -> String {
        if let Some(label) = &self.label {
            return label.clone();
        }
        // The script: the first argument that is not an option, else the
        // program.
        let script = self
            .command
            .iter()
            .skip(1)
            .find(|a| !a.starts_with('-'))
            .or(self.command.first())
            .map(|a| {
                std::path::Path::new(a)
                    .file_name()
                    .map_or_else(|| a.clone(), |f| f.to_string_lossy().into_owned())
            })
            .unwrap_or_default();
        format!("external: {script}")
    }

    /// Checks the fields.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] naming the field.
    pub fn check(&self) -> Result<(), RegressorError> {
        let bad = |field: &str, expected: &str| {
            Err(RegressorError::InvalidSpec {
                regressor: "external".into(),
                field: field.into(),
                expected: expected.into(),
            })
        };
        if self.command.is_empty() || self.command[0].trim().is_empty() {
            return bad(
                "command",
                "a program and its arguments, e.g. [python3, plugins/python/examples/ridge.py]",
            );
        }
        if !(self.timeout_secs.is_finite() && self.timeout_secs > 0.0) {
            return bad("timeout_secs", "a positive number of seconds");
        }
        Ok(())
    }

    /// The same params with relative paths in `command` made absolute
    /// against `base` (the experiment file's folder): the program when it
    /// contains a `/`, and every argument that names an existing file or
    /// folder under `base`.
    #[must_use]
    pub fn resolved_against(mut self, base: &std::path::Path) -> Self {
        for (i, arg) in self.command.iter_mut().enumerate() {
            let path = std::path::Path::new(arg.as_str());
            if path.is_absolute() || arg.starts_with('-') {
                continue;
            }
            let program_path = i == 0 && arg.contains('/');
            let candidate = base.join(path);
            if program_path || (i > 0 && candidate.exists()) {
                *arg = candidate.to_string_lossy().into_owned();
            }
        }
        self
    }
}

/// A running plugin and what it said in `hello`.
struct Session {
    process: PluginProcess,
    hello: HelloReply,
    next_id: u64,
}

impl Drop for Session {
    fn drop(&mut self) {
        let id = self.next_id;
        if let Ok(line) = serde_json::to_string(&Request::Shutdown { id }) {
            let _ = self.process.exchange(&line, SHUTDOWN_TIMEOUT);
        }
        self.process.close(SHUTDOWN_TIMEOUT);
    }
}

/// What the regressor has learned the shape of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Shape {
    inputs: usize,
    outputs: usize,
}

/// The regressor behind `kind: external`.
pub struct ExternalRegressor {
    params: ExternalParams,
    name: String,
    session: Mutex<Option<Session>>,
    shape: Option<Shape>,
}

impl std::fmt::Debug for ExternalRegressor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExternalRegressor")
            .field("name", &self.name)
            .field("command", &self.params.command)
            .finish()
    }
}

impl ExternalRegressor {
    /// A regressor that will run `params.command` on first use.
    ///
    /// # Errors
    /// [`RegressorError::InvalidSpec`] as [`ExternalParams::check`].
    pub fn new(params: ExternalParams) -> Result<Self, RegressorError> {
        params.check()?;
        Ok(Self {
            name: params.base_label(),
            params,
            session: Mutex::new(None),
            shape: None,
        })
    }

    /// The plugin's process id while it runs (for tests and logs).
    pub fn process_id(&self) -> Option<u32> {
        self.lock().as_ref().map(|s| s.process.id())
    }

    fn timeout(&self) -> Duration {
        Duration::from_secs_f64(self.params.timeout_secs)
    }

    fn lock(&self) -> MutexGuard<'_, Option<Session>> {
        self.session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn failure(&self, request: &str, detail: String, stderr: Vec<String>) -> RegressorError {
        RegressorError::Plugin {
            regressor: self.name.clone(),
            request: request.into(),
            detail,
            stderr,
        }
    }

    /// Starts the plugin and says `hello` unless it runs.
    fn started<'a>(
        &self,
        guard: &'a mut MutexGuard<'_, Option<Session>>,
    ) -> Result<&'a mut Session, RegressorError> {
        if guard.is_none() {
            let process = PluginProcess::spawn(&self.params.command, None)
                .map_err(|e| self.failure("hello", e.to_string(), Vec::new()))?;
            let mut session = Session {
                process,
                hello: HelloReply {
                    protocol: PROTOCOL_VERSION,
                    name: None,
                    capabilities: Vec::new(),
                },
                next_id: 0,
            };
            let options = &self.params.options;
            let body = self.exchange(&mut session, |id| Request::Hello {
                id,
                protocol: PROTOCOL_VERSION,
                options,
            })?;
            let hello: HelloReply = self.parse(&mut session, "hello", body)?;
            if hello.protocol != PROTOCOL_VERSION {
                let detail = format!(
                    "the plugin speaks protocol {}, this gpodo speaks {PROTOCOL_VERSION}",
                    hello.protocol
                );
                return Err(self.fail(&mut session, "hello", detail));
            }
            for needed in ["fit", "predict"] {
                if !hello.capabilities.iter().any(|c| c == needed) {
                    let detail = format!(
                        "the plugin's capabilities {:?} lack `{needed}`",
                        hello.capabilities
                    );
                    return Err(self.fail(&mut session, "hello", detail));
                }
            }
            tracing::debug!(regressor = %self.name, pid = session.process.id(), plugin = ?hello.name, "plugin started");
            session.hello = hello;
            **guard = Some(session);
        }
        guard
            .as_mut()
            .ok_or_else(|| self.failure("hello", "the plugin did not start".into(), Vec::new()))
    }

    /// Kills the plugin and returns the error naming `request`.
    fn fail(&self, session: &mut Session, request: &str, detail: String) -> RegressorError {
        session.process.kill();
        let stderr = session.process.stderr_tail();
        self.failure(request, detail, stderr)
    }

    /// Sends one request and returns the reply's body when it is `ok`.
    fn exchange<'r>(
        &self,
        session: &mut Session,
        request: impl FnOnce(u64) -> Request<'r>,
    ) -> Result<serde_json::Map<String, serde_json::Value>, RegressorError> {
        let id = session.next_id;
        session.next_id += 1;
        let request = request(id);
        let op = request.op();
        let line = serde_json::to_string(&request)
            .map_err(|e| self.failure(op, format!("cannot encode the request: {e}"), Vec::new()))?;
        let reply = match session.process.exchange(&line, self.timeout()) {
            Ok(reply) => reply,
            Err(failure) => {
                let detail = failure.to_string();
                if matches!(failure, ProcessFailure::Timeout(_)) {
                    tracing::warn!(regressor = %self.name, request = op, "plugin timed out");
                }
                return Err(self.fail(session, op, detail));
            }
        };
        let reply: Reply = match serde_json::from_str(&reply) {
            Ok(r) => r,
            Err(e) => {
                let shown: String = reply.chars().take(200).collect();
                let detail = format!(
                    "the reply is not the protocol's JSON ({e}); it began `{shown}` (a plugin must write nothing but replies to stdout; log to stderr)"
                );
                return Err(self.fail(session, op, detail));
            }
        };
        if reply.id != id {
            let detail = format!("the reply's id is {}, the request's {id}", reply.id);
            return Err(self.fail(session, op, detail));
        }
        if !reply.ok {
            // The plugin refused the request but is still in step: keep it.
            let stderr = session.process.settled_stderr_tail();
            let detail = format!(
                "the plugin replied with an error: {}",
                reply.error.as_deref().unwrap_or("(no message)")
            );
            return Err(self.failure(op, detail, stderr));
        }
        Ok(reply.body)
    }

    /// Reads a reply's body as `T`.
    fn parse<T: serde::de::DeserializeOwned>(
        &self,
        session: &mut Session,
        op: &str,
        body: serde_json::Map<String, serde_json::Value>,
    ) -> Result<T, RegressorError> {
        serde_json::from_value(serde_json::Value::Object(body)).map_err(|e| {
            self.fail(
                session,
                op,
                format!("the reply does not have the fields `{op}` answers with: {e}"),
            )
        })
    }

    /// Decodes a reply's matrix and checks its shape and values.
    fn matrix(
        &self,
        session: &mut Session,
        what: &str,
        wire: &WireMatrix,
        shape: (usize, usize),
        non_negative: bool,
    ) -> Result<SampleMatrix, RegressorError> {
        let m = wire
            .decode()
            .map_err(|e| self.fail(session, "predict", format!("`{what}`: {e}")))?;
        if (m.nrows(), m.ncols()) != shape {
            let detail = format!(
                "`{what}` is {} × {}, expected {} × {} (one row per input row, one column per output)",
                m.nrows(),
                m.ncols(),
                shape.0,
                shape.1
            );
            return Err(self.fail(session, "predict", detail));
        }
        let bad = m
            .as_slice()
            .iter()
            .position(|v| !v.is_finite() || (non_negative && *v < 0.0));
        if let Some(k) = bad {
            let (i, j) = (k / shape.1.max(1), k % shape.1.max(1));
            let expected = if non_negative {
                "a finite non-negative variance"
            } else {
                "a finite mean"
            };
            let detail = format!(
                "`{what}` row {i}, output {j} is {}, expected {expected}",
                m.get(i, j)
            );
            return Err(self.fail(session, "predict", detail));
        }
        Ok(m)
    }
}

impl ResidualRegressor for ExternalRegressor {
    fn name(&self) -> &str {
        &self.name
    }

    fn fit(&mut self, data: &ResidualDataset) -> Result<FitReport, Error> {
        let start = Instant::now();
        self.shape = None;
        let mut guard = self
            .session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let session = self.started(&mut guard)?;
        let body = self.exchange(session, |id| Request::Fit {
            id,
            inputs: WireMatrix::encode(&data.inputs),
            targets: WireMatrix::encode(&data.targets),
            input_names: &data.input_names,
            target_names: &data.target_names,
            inputs_standardized: data.inputs_standardized,
        });
        let body = match body {
            Ok(b) => b,
            Err(e) => {
                if session.process_reaped() {
                    *guard = None;
                }
                return Err(e.into());
            }
        };
        let reply: FitReply = self.parse(session, "fit", body)?;
        drop(guard);
        self.shape = Some(Shape {
            inputs: data.inputs.ncols(),
            outputs: data.targets.ncols(),
        });
        Ok(FitReport {
            n_samples: data.len(),
            duration_secs: start.elapsed().as_secs_f64(),
            objective: reply.objective,
            evaluations: reply.evaluations,
            jitter: None,
            parameters: reply.parameters,
            iterations: reply.iterations,
            ..FitReport::default()
        })
    }

    fn predict(&self, inputs: &SampleMatrix) -> Result<Predictions, Error> {
        let Some(shape) = self.shape else {
            return Err(Error::NotFitted {
                model: self.name.clone(),
            });
        };
        if inputs.ncols() != shape.inputs {
            return Err(Error::DimensionMismatch {
                what: "inputs".into(),
                expected: shape.inputs,
                found: inputs.ncols(),
            });
        }
        let mut guard = self.lock();
        let Some(session) = guard.as_mut() else {
            return Err(Error::NotFitted {
                model: self.name.clone(),
            });
        };
        let result = self
            .exchange(session, |id| Request::Predict {
                id,
                inputs: WireMatrix::encode(inputs),
            })
            .and_then(|body| self.parse::<PredictReply>(session, "predict", body))
            .and_then(|reply| {
                let wanted = (inputs.nrows(), shape.outputs);
                let mean = self.matrix(session, "mean", &reply.mean, wanted, false)?;
                let variance = self.matrix(session, "variance", &reply.variance, wanted, true)?;
                Ok(Predictions { mean, variance })
            });
        if result.is_err() && session.process_reaped() {
            *guard = None;
        }
        Ok(result?)
    }

    fn supports_online_update(&self) -> bool {
        let mut guard = self.lock();
        self.started(&mut guard)
            .map(|s| s.hello.capabilities.iter().any(|c| c == "update"))
            .unwrap_or(false)
    }

    fn update(&mut self, inputs: &[f64], targets: &[f64]) -> Result<(), Error> {
        if let Some(shape) = self.shape {
            for (what, expected, found) in [
                ("update inputs", shape.inputs, inputs.len()),
                ("update targets", shape.outputs, targets.len()),
            ] {
                if expected != found {
                    return Err(Error::DimensionMismatch {
                        what: what.into(),
                        expected,
                        found,
                    });
                }
            }
        }
        let mut guard = self
            .session
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let session = self.started(&mut guard)?;
        if !session.hello.capabilities.iter().any(|c| c == "update") {
            return Err(Error::OnlineUpdateUnsupported {
                model: self.name.clone(),
            });
        }
        let result = self.exchange(session, |id| Request::Update {
            id,
            inputs,
            targets,
        });
        if result.is_err() && session.process_reaped() {
            *guard = None;
        }
        result?;
        drop(guard);
        self.shape = Some(Shape {
            inputs: inputs.len(),
            outputs: targets.len(),
        });
        Ok(())
    }
}

impl Session {
    fn process_reaped(&self) -> bool {
        self.process.is_reaped()
    }
}
