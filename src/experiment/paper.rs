//! `paper_vs_ours.csv`: each cell of a paper's table ([`PaperCell`]) beside the measurement of
//! ours it names, with times also as ratios to a reference cell, the paper's to the paper's and
//! ours to ours (2008 seconds are not a target).
//!
//! Every `ours_*` value is read from one place, the one the cell's `ours` names
//! ([`OursSource`]): the first `table.csv` row matching the cell's axes (its scene and backend
//! anchor the other sources too), the ray cast of `raycast_sweep.csv` at a ray count, or the sum
//! of one row per scene. Nothing is copied from another cell. Two rules keep the numbers honest:
//! `ours_rays_cast` is the row's `rays_cast` (points × rays × lights; empty where a table
//! predates that column), and `ours_bake_s` is a bake timed in the run (empty for a field from
//! the cache, whose recorded time may come from another build or load; `ours_bake_cached` says
//! which). The runner writes the file at the end of a run and `experiment plots` rewrites it
//! from a finished run's CSV files ([`rewrite`]), with this same code.

use super::outputs::{read_csv, write_csv, PairRow, SweepRow};
use super::spec::{OursSource, PaperCell, PaperNumbers};
use super::table::Row;
use super::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A paper cell beside ours. `*_rel` columns are ratios to the reference cell's value, the
/// paper's to the paper's and ours to ours.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PaperRow {
    pub label: String,
    /// What ours come from: a cell id, `raycast_sweep:SCENE:BACKEND:RAYS`, or cell ids joined
    /// by `+` (empty when nothing of this run matches).
    pub cell: String,
    pub paper_triangles: Option<u64>,
    pub ours_triangles: Option<u64>,
    pub paper_rays_cast: Option<u64>,
    pub ours_rays_cast: Option<u64>,
    pub paper_raycast_s: Option<f64>,
    pub ours_raycast_s: Option<f64>,
    pub paper_preprocess_s: Option<f64>,
    pub ours_bake_s: Option<f64>,
    /// Some field of ours came from the cache: its bake was not timed in this run.
    pub ours_bake_cached: Option<bool>,
    /// The paper's time of the estimate through the field (AO, shadows or reflections), and
    /// ours (`table.csv`'s `estimate_s`); named `paper_ao_s`, `ours_ao_s` before.
    #[serde(alias = "paper_ao_s")]
    pub paper_estimate_s: Option<f64>,
    #[serde(alias = "ours_ao_s")]
    pub ours_estimate_s: Option<f64>,
    pub paper_rms: Option<f64>,
    pub ours_rms_image: Option<f64>,
    pub ours_rms_vertex: Option<f64>,
    pub paper_raycast_rel: Option<f64>,
    pub ours_raycast_rel: Option<f64>,
    pub paper_preprocess_rel: Option<f64>,
    pub ours_bake_rel: Option<f64>,
    #[serde(alias = "paper_ao_rel")]
    pub paper_estimate_rel: Option<f64>,
    #[serde(alias = "ours_ao_rel")]
    pub ours_estimate_rel: Option<f64>,
    pub note: String,
}

/// Our side of one paper cell.
#[derive(Clone, Debug, Default, PartialEq)]
struct Ours {
    cell: String,
    triangles: Option<u64>,
    rays_cast: Option<u64>,
    raycast_s: Option<f64>,
    bake_s: Option<f64>,
    bake_cached: Option<bool>,
    estimate_s: Option<f64>,
    rms_image: Option<f64>,
    rms_vertex: Option<f64>,
}

/// A finished run's tables, as `paper_vs_ours` reads them.
pub struct RunTables<'a> {
    pub rows: &'a [Row],
    pub sweep: &'a [SweepRow],
    pub pairs: &'a [PairRow],
}

/// The row's rays of one evaluation; none where its table predates the column (0).
fn rays_of(r: &Row) -> Option<u64> {
    (r.rays_cast > 0).then_some(r.rays_cast)
}

/// The row's bake if it was timed in the run.
fn bake_of(r: &Row) -> Option<f64> {
    r.bake_s.filter(|_| !r.bake_cached)
}

fn from_row(r: &Row) -> Ours {
    Ours {
        cell: r.cell.clone(),
        triangles: Some(r.caster_triangles as u64),
        rays_cast: rays_of(r),
        raycast_s: r.raycast_s,
        bake_s: bake_of(r),
        bake_cached: Some(r.bake_cached),
        estimate_s: Some(r.estimate_s),
        rms_image: r.rms_image,
        rms_vertex: r.rms_vertex,
    }
}

/// The RMS between `r` and the same cell at precision `v` (`pairs.csv`).
fn versus(r: &Row, v: crate::field::Precision, pairs: &[PairRow]) -> (Option<f64>, Option<f64>) {
    let pair = pairs.iter().find(|p| {
        p.scene == r.scene
            && p.sphere == r.sphere
            && p.positional_samples == r.positional_samples
            && p.directional_res == r.directional_res
            && p.layout == r.layout
            && p.selection == r.selection
            && p.backend == r.backend
            && ((p.precision_a, p.precision_b) == (r.precision, v)
                || (p.precision_a, p.precision_b) == (v, r.precision))
    });
    (
        pair.and_then(|p| p.rms_image),
        pair.and_then(|p| p.rms_vertex),
    )
}

/// Our side of `c`, from the source it names; none when this run has nothing for it.
fn ours(c: &PaperCell, t: &RunTables) -> Option<Ours> {
    let matching = |r: &&Row| c.matches(&r.scene, &r.params(), r.selection, r.backend);
    let first = || t.rows.iter().find(matching);
    match &c.ours {
        OursSource::Table => {
            let r = first()?;
            let mut o = from_row(r);
            if let Some(v) = c.versus_precision {
                (o.rms_image, o.rms_vertex) = versus(r, v, t.pairs);
            }
            Some(o)
        }
        OursSource::RaycastSweep { rays_per_point: k } => {
            let r = first()?;
            let s = t
                .sweep
                .iter()
                .find(|s| s.scene == r.scene && s.backend == r.backend && s.rays_per_point == *k)?;
            // rays_cast = points × rays × lights, so the sweep casts rays_cast / rays × k.
            let rays = rays_of(r)
                .filter(|n| r.rays_per_point > 0 && n % r.rays_per_point as u64 == 0)
                .map(|n| n / r.rays_per_point as u64 * *k as u64);
            Some(Ours {
                cell: format!("raycast_sweep:{}:{}:{k}", s.scene, s.backend.name()),
                triangles: Some(r.caster_triangles as u64),
                rays_cast: rays,
                raycast_s: Some(s.raycast_s),
                rms_image: s.rms_image,
                rms_vertex: s.rms_vertex,
                ..Ours::default()
            })
        }
        OursSource::SumOfScenes { scenes } => {
            let on = |n: &String, r: &&Row| r.scene == *n && matching(r);
            let head = (scenes.first()).and_then(|n| t.rows.iter().find(|r| on(n, r)))?;
            let rows: Vec<&Row> = (scenes.iter())
                .map(|n| {
                    t.rows
                        .iter()
                        .find(|r| r.backend == head.backend && on(n, r))
                })
                .collect::<Option<_>>()?;
            let sum_u = |f: &dyn Fn(&Row) -> Option<u64>| rows.iter().map(|r| f(r)).sum();
            let sum_f = |f: &dyn Fn(&Row) -> Option<f64>| rows.iter().map(|r| f(r)).sum();
            Some(Ours {
                cell: rows
                    .iter()
                    .map(|r| r.cell.as_str())
                    .collect::<Vec<_>>()
                    .join("+"),
                triangles: sum_u(&|r| Some(r.caster_triangles as u64)),
                rays_cast: sum_u(&rays_of),
                raycast_s: sum_f(&|r| r.raycast_s),
                bake_s: sum_f(&bake_of),
                bake_cached: Some(rows.iter().any(|r| r.bake_cached)),
                estimate_s: sum_f(&|r| Some(r.estimate_s)),
                rms_image: None,
                rms_vertex: None,
            })
        }
    }
}

fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => Some(a / b),
        _ => None,
    }
}

/// The paper's cells beside ours.
pub fn paper_vs_ours(paper: &PaperNumbers, t: &RunTables) -> Vec<PaperRow> {
    let rc = paper
        .reference_cell
        .as_ref()
        .and_then(|l| paper.cells.iter().find(|c| &c.label == l))
        .or(paper.cells.first());
    let ro = rc.and_then(|c| ours(c, t)).unwrap_or_default();
    let paper_rel = |f: fn(&PaperCell) -> Option<f64>, c: &PaperCell| ratio(f(c), rc.and_then(f));
    paper
        .cells
        .iter()
        .map(|c| {
            let o = ours(c, t).unwrap_or_default();
            PaperRow {
                label: c.label.clone(),
                cell: o.cell.clone(),
                paper_triangles: c.triangles,
                ours_triangles: o.triangles,
                paper_rays_cast: c.rays_cast,
                ours_rays_cast: o.rays_cast,
                paper_raycast_s: c.raycast_s,
                ours_raycast_s: o.raycast_s,
                paper_preprocess_s: c.preprocess_s,
                ours_bake_s: o.bake_s,
                ours_bake_cached: o.bake_cached,
                paper_estimate_s: c.estimate_s,
                ours_estimate_s: o.estimate_s,
                paper_rms: c.rms,
                ours_rms_image: o.rms_image,
                ours_rms_vertex: o.rms_vertex,
                paper_raycast_rel: paper_rel(|c| c.raycast_s, c),
                ours_raycast_rel: ratio(o.raycast_s, ro.raycast_s),
                paper_preprocess_rel: paper_rel(|c| c.preprocess_s, c),
                ours_bake_rel: ratio(o.bake_s, ro.bake_s),
                paper_estimate_rel: paper_rel(|c| c.estimate_s, c),
                ours_estimate_rel: ratio(o.estimate_s, ro.estimate_s),
                note: c.note.clone().unwrap_or_default(),
            }
        })
        .collect()
}

/// Rewrites `dir/paper_vs_ours.csv` from the run's `table.csv`, `raycast_sweep.csv` and
/// `pairs.csv` (each optional but the table) and `paper`, with the code a run writes it with.
/// Returns whether a file was written (none without a table).
pub fn rewrite(dir: &Path, paper: &PaperNumbers) -> Result<bool> {
    let table = dir.join("table.csv");
    if !table.exists() {
        return Ok(false);
    }
    let rows: Vec<Row> = read_csv(&table)?;
    fn optional<T: serde::de::DeserializeOwned>(p: &Path) -> Result<Vec<T>> {
        if p.exists() {
            read_csv(p)
        } else {
            Ok(Vec::new())
        }
    }
    let sweep: Vec<SweepRow> = optional(&dir.join("raycast_sweep.csv"))?;
    let pairs: Vec<PairRow> = optional(&dir.join("pairs.csv"))?;
    let t = RunTables {
        rows: &rows,
        sweep: &sweep,
        pairs: &pairs,
    };
    write_csv(&dir.join("paper_vs_ours.csv"), &paper_vs_ours(paper, &t))?;
    Ok(true)
}
