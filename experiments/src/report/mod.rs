//! The fourth stage: what the results say, as files. [`files`] writes a
//! single run's folder (`report.md` from [`run`], `metrics.json`, residual
//! rows, trajectories, figures from [`plots`] and the frames around each
//! loss of track); [`sweep`] merges the
//! records of a results folder into `summary.md` and its CSV tables;
//! [`bench`](mod@bench) writes `bench.md`. Every Table I and Table II is a
//! [`table::Table`].

mod aggregate;
pub mod bench;
pub mod bootstrap;
pub mod controls;
pub mod curve_plot;
pub mod curves;
pub mod curves_section;
pub mod exact;
pub mod files;
pub mod floor;
pub mod hindsight;
mod loss_strips;
mod oracle_table;
mod pairing;
pub mod plots;
pub mod prequential_plot;
pub mod run;
pub mod sensitivity;
pub mod sensitivity_plot;
pub mod sweep;
pub mod table;
pub mod tradeoff_plot;
mod twin_table;
pub mod verdict;
pub mod verdict_section;

pub use files::write_report;
