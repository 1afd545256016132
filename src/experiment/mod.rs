//! The experiment harness: specs, planner, runner, metrics, outputs and the CLI.

pub mod cli;
