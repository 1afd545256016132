//! The tables a run writes (CSV, atomically) and reads back for `experiment plots`:
//!
//! - `table.csv`: one row per cell and backend (`experiment::table`);
//! - `raycast_sweep.csv`: the kind's estimate by ray casting at several ray counts
//!   ([`SweepRow`]), the ray-casting curve of the error-against-time plot;
//! - `field_sweep.csv`: the estimate through every cell's fields at more ray counts
//!   ([`FieldSweepRow`]), against the converged reference;
//! - `pairs.csv`: RMS between cells that differ only in precision ([`PairRow`]; the slides'
//!   8 vs 16 bit);
//! - `paper_vs_ours.csv`: the paper's numbers beside ours, written by `experiment::paper`;
//!
//! and the commands' tables, each named for what its rows hold: [`BACKEND_TIMES_CSV`],
//! [`SWEEP_FRAMES_CSV`], [`RENDERINGS_CSV`] (read under their former name by [`table_path`]).
//! What defines each file's columns: [`super::columns`].

use super::spec::Backend;
use super::{Error, Result};
use crate::field::{Precision, Selection};
use crate::sampling::{LayoutKind, SphereKind};
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The kind's estimate by ray casting at one ray count, against the reference. Column names
/// as in `table.csv` (the same measurement at the render's ray count); tables written before
/// named `raycast_s` `ao_s` and `raycast_kernel_s` `kernel_s`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    pub scene: String,
    pub backend: Backend,
    pub rays_per_point: u32,
    /// The ray cast's time (best of 3 when short; on the GPU the call's wall time).
    #[serde(alias = "ao_s")]
    pub raycast_s: f64,
    pub rms_vertex: Option<f64>,
    pub rms_image: Option<f64>,
    /// Kernel time from GPU timestamps (`raycast_s` is the wall time); empty on the CPU.
    #[serde(default, alias = "kernel_s")]
    pub raycast_kernel_s: Option<f64>,
    /// RMS over points against the converged reference (0–255), mean over seeds.
    #[serde(default)]
    pub rms_vs_truth: Option<f64>,
    /// Its standard deviation over seeds.
    #[serde(default)]
    pub rms_vs_truth_sd: Option<f64>,
    /// The converged reference's RMS standard error (0–255).
    #[serde(default)]
    pub truth_stderr: Option<f64>,
    /// Mean FLIP of the first seed's image against the same-ray reference's image (0 for the
    /// reference itself), over the pixels the image RMS is taken over; empty without an image.
    #[serde(default)]
    pub flip_mean: Option<f64>,
    /// Mean FLIP of the first seed's image against the converged reference's image.
    #[serde(default)]
    pub flip_mean_vs_truth: Option<f64>,
}

/// The estimate through one cell's fields with another ray count, against the converged
/// reference only.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldSweepRow {
    pub scene: String,
    pub cell: String,
    pub positional_samples: usize,
    pub directional_res: u32,
    pub precision: Precision,
    pub selection: Selection,
    pub backend: Backend,
    pub rays_per_point: u32,
    /// The estimate's time, as `table.csv`'s `estimate_s` (named `ao_s` before).
    #[serde(alias = "ao_s")]
    pub estimate_s: f64,
    /// RMS over points against the converged reference (0–255), first seed.
    pub rms_vs_truth: Option<f64>,
    pub truth_stderr: Option<f64>,
}

/// RMS between two cells that differ only in precision.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairRow {
    pub scene: String,
    pub sphere: SphereKind,
    pub positional_samples: usize,
    pub directional_res: u32,
    pub layout: LayoutKind,
    pub selection: Selection,
    pub backend: Backend,
    pub precision_a: Precision,
    pub precision_b: Precision,
    pub rms_vertex: Option<f64>,
    pub rms_image: Option<f64>,
    /// The two cells' ids (`table.csv`'s `cell`), precision `a`'s first; empty in tables
    /// written before the column.
    #[serde(default)]
    pub cell_a: String,
    #[serde(default)]
    pub cell_b: String,
}

/// `experiment performance`'s table: one row per sweep point and backend, its time on the
/// point's rays (`performance::PerfRow`).
pub const BACKEND_TIMES_CSV: &str = "backend_times.csv";
/// `experiment dynamic`'s table: one row per sweep (a crowd or the approach), frame and method
/// (`frame_row::DYNAMIC_CSV`).
pub const SWEEP_FRAMES_CSV: &str = "sweep_frames.csv";
/// `experiment relief`'s table: one row per rendering (table, map, view, setting and caster;
/// `relief::ReliefRow`).
pub const RENDERINGS_CSV: &str = "renderings.csv";

/// The file `name` in `dir`, or for a command's table in a folder written before the tables
/// were named for what they hold, the file under its former name, `table.csv`, as a table's
/// columns are read under their former names (`table::FORMER_NAMES`): where `name`
/// is one of the command tables above and absent, and the folder is a command's run (its
/// `run.json` and no `spec.json`: a spec's run writes `table.csv` of its own). The former name
/// does not say which command wrote it: `experiment plots` reads it as performance's, the one
/// command table it redraws.
pub fn table_path(dir: &Path, name: &str) -> PathBuf {
    let now = dir.join(name);
    let former = dir.join("table.csv");
    let command = [BACKEND_TIMES_CSV, SWEEP_FRAMES_CSV, RENDERINGS_CSV].contains(&name)
        && dir.join("run.json").is_file()
        && !dir.join("spec.json").exists();
    if command && !now.exists() && former.is_file() {
        former
    } else {
        now
    }
}

/// Writes rows as CSV (header from the struct), atomically.
pub fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(Error::csv(path))?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e.into_error(),
    })?;
    crate::io::write_atomic(path, &bytes).map_err(Error::io(path))
}

/// Reads rows written by [`write_csv`].
pub fn read_csv<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    let mut r = csv::Reader::from_path(path).map_err(Error::csv(path))?;
    r.deserialize()
        .collect::<std::result::Result<Vec<T>, _>>()
        .map_err(Error::csv(path))
}
