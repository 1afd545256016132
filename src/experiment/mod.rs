//! The experiment harness: specs, planner, runner, metrics, outputs and the CLI.

pub mod cli;
pub mod meta;
pub mod plot;
pub mod progress;
pub mod quickstart;
