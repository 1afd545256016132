//! The experiment harness: specs, planner, runner, metrics, outputs and the CLI.
//!
//! `experiments/NAME.json` ([`spec`]) and its render kind ([`kinds`]: the points and the
//! estimator) → built scenes ([`scenes`]) → a [`plan`] of steps (each field baked once, the
//! reference once per scene and ray set, fields released as soon as their cells are done) → the
//! runner ([`run`]) with fields from the cache or the bake ([`fields`]) on a backend
//! ([`backend`]) → metrics ([`metrics`]), tables ([`table`], [`outputs`], [`columns`]), plots ([`figures`]) and
//! thresholds ([`check`]). Every failure is an [`Error`] naming what it was about. `experiment sampling` measures the sampling patterns alone
//! ([`sampling_report`]).

pub mod backend;
pub mod backend_gpu;
pub mod cells;
pub mod check;
pub mod cli;
pub mod columns;
pub mod discover;
pub mod dynamic;
pub mod error;
pub mod fields;
pub mod figures;
pub mod flip;
pub mod frame_row;
pub mod kinds;
pub mod merge;
pub mod meta;
pub mod methods;
pub mod metrics;
pub mod models_cmd;
pub mod models_fetch;
pub mod outputs;
pub mod paper;
pub mod performance;
pub mod plan;
pub mod plot;
pub mod progress;
pub mod quickstart;
pub mod registry;
pub mod relief;
pub mod run;
pub mod sampling_report;
pub mod scenes;
pub mod shard;
pub mod spec;
pub mod spec_load;
pub mod stability;
pub(crate) mod staging;
pub mod table;
pub mod truth_cache;
pub mod try_mesh;
pub mod user_mesh;
pub mod validate;

pub use error::{Error, Result, ResultExt};
