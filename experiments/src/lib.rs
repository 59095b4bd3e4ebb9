//! The gpodo experiment runner: reads a YAML experiment, runs the paper's
//! pipeline (simulate or load → motion model → residual dataset →
//! regressors → evaluation) and writes `report.md` and `metrics.json`.
//!
//! * [`config`]: the experiment file schema, with errors naming file, line
//!   and column;
//! * [`pipeline`]: the run itself;
//! * [`calibration`]: statistics of residual tables, to compare the
//!   simulator with the real ExoTeR data;
//! * [`odometry`]: dead reckoning with the motion model;
//! * [`schemes`] and [`table_two`]: the SLAM schemes of Table II run
//!   through the visual front end, with [`plots`] (Fig. 3 and Fig. 5);
//! * [`report`]: the Markdown and JSON outputs;
//! * [`bench`](mod@bench) and [`bench_report`]: `gpodo bench`, every regressor timed
//!   and scored on the same splits against the exact-GP baseline.

pub mod bench;
pub mod bench_report;
pub mod calibration;
pub mod config;
pub mod odometry;
pub mod pipeline;
pub mod plots;
pub mod records;
pub mod report;
pub mod runner;
pub mod schemes;
pub mod shared;
pub mod sweep;
pub mod sweep_report;
pub mod table_two;
