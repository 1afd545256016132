//! The `experiment` command line.

use clap::{Parser, Subcommand};

/// visfield experiments: reproduce and extend the presampled-visibility papers.
#[derive(Parser, Debug)]
#[command(name = "experiment", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Small tour on the embedded procedural scene (no files needed).
    Quickstart {
        /// Output folder.
        #[arg(long, default_value = "results/quickstart")]
        out: std::path::PathBuf,
    },
    /// Sphere point sets and hemisphere layouts: exactness, spacing, timings and plots.
    Sampling {
        /// Output folder.
        #[arg(long, default_value = "results/sampling")]
        out: std::path::PathBuf,
    },
}

pub fn main() {
    let cli = Cli::parse();
    match cli.command {
        Command::Quickstart { out } => {
            if let Err(e) = super::quickstart::run(&out) {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        }
        Command::Sampling { out } => {
            if let Err(e) = crate::sampling::report::run(&out) {
                eprintln!("sampling: {e}");
                std::process::exit(1);
            }
        }
    }
}
