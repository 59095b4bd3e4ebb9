//! The gpodo experiment runner: reads a YAML experiment, runs the paper's
//! pipeline (simulate or load → motion model → residual dataset →
//! regressors → evaluation → Table II schemes) and writes `report.md`,
//! `metrics.json` and the sweep's `summary.md`.
//!
//! The crate flows one way; no module imports a later stage:
//!
//! 1. [`config`]: the experiment file's schema and its checks;
//! 2. [`plan`]: a file (with `base:`, `sweep:`, `zip:`, `seeds:`) expanded
//!    into validated runs;
//! 3. [`execute`]: the data, the fits and the schemes of those runs, each
//!    done once when runs share it, and `gpodo bench`'s timings;
//! 4. [`report`]: Markdown, JSON, CSV and SVG from the results;
//! 5. [`runner`]: drives the stages for `gpodo run`, recording each run.
//!
//! [`error`] holds the errors of the first three stages; [`util`] the
//! leaves every stage may use (atomic file writes, CPU time, memory,
//! stopping, shards); [`commands`] the other commands' domain logic
//! (`simulate`, `import`, `live`, the tracker's calibration), testable
//! without the binary. See `ARCHITECTURE.md` for the path of one `gpodo
//! run`.

pub mod commands;
pub mod config;
pub mod error;
pub mod execute;
pub mod plan;
pub mod report;
pub mod runner;
pub mod util;
