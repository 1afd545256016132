//! `experiment check`: RMS thresholds per cell, and every cell against the committed run of the
//! same spec and profile.
//!
//! A spec's threshold applies to every cell matching its axes (an axis left out matches any
//! value); a cell fails when its RMS exceeds the maximum ([`check_rows`]). Besides, every cell's
//! errors (`rms_vertex`, `rms_image`, `rms_vs_truth`) are compared with the same cell of the
//! committed `table.csv` (`results/quick/NAME` for `--quick`, `results/NAME` for a full check):
//! two-sided, a value more than [`COMMITTED_TOLERANCE`] times the committed one or less than
//! its inverse fails, so a doubled error fails and so does an error that drops to 0 (a silent
//! fallback to ray casting, a field that reads the reference) ([`check_committed`]). The rows
//! of the spec's other methods (`methods.csv`) are compared the same way, each by its scene
//! and setting ([`check_committed_methods`]), and an animated spec's frames (`frames.csv`)
//! by scene, frame, method and field cell ([`check_committed_frames`]).

pub use super::cells::threshold_matches;
use super::cells::Cell;
use super::columns::NamedRow;
use super::spec::Threshold;
use super::table::Row;
use crate::field::FieldParams;

/// How far a cell's error may move from the committed run's, as a factor either way.
pub const COMMITTED_TOLERANCE: f64 = 1.25;

/// What a failing cell broke.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rule {
    /// The spec's threshold: at most this.
    Max(f64),
    /// The committed run's value: within [`COMMITTED_TOLERANCE`] of it either way.
    Committed(f64),
    /// The committed run has no such cell (or no such value).
    NotCommitted,
}

/// A cell whose RMS broke a rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// The cell id.
    pub cell: String,
    /// "rms_vertex", "rms_image" or "rms_vs_truth" (for `experiment dynamic`'s rows:
    /// "rms_vs_raycast", "rms_vs_truth" or "mean_ao"; for an animated spec's frames:
    /// "rms_vs_raycast", "rms_vs_truth" or "mean_value").
    pub metric: &'static str,
    pub value: f64,
    pub rule: Rule,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (cell, metric, v) = (&self.cell, self.metric, self.value);
        match self.rule {
            Rule::Max(max) => write!(f, "{cell}: {metric} {v:.4} exceeds its threshold {max:.4}"),
            Rule::Committed(c) => write!(
                f,
                "{cell}: {metric} {v:.4} is outside {:.4} ..= {:.4}, the committed {c:.4} within \
                 a factor {COMMITTED_TOLERANCE} either way",
                c / COMMITTED_TOLERANCE,
                c * COMMITTED_TOLERANCE
            ),
            Rule::NotCommitted => write!(
                f,
                "{cell}: {metric} {v:.4} has no committed value to compare with (regenerate and \
                 commit the run: `experiment all`, or `experiment all --quick` for results/quick)"
            ),
        }
    }
}

fn row_cell(r: &Row) -> Cell {
    Cell {
        scene: 0,
        params: FieldParams {
            sphere: r.sphere,
            count: r.positional_samples,
            layout: r.layout,
            res: r.directional_res,
            precision: r.precision,
        },
        selection: r.selection,
        backend: r.backend,
        normal_bits: r.normal_bits,
    }
}

/// Every (row, threshold) where a measured RMS exceeds the threshold's maximum. A missing
/// measurement (no image) fails too: the threshold cannot be verified.
pub fn check_rows(thresholds: &[Threshold], rows: &[Row]) -> Vec<Failure> {
    let mut out = Vec::new();
    for r in rows {
        let cell = row_cell(r);
        for t in thresholds
            .iter()
            .filter(|t| threshold_matches(t, &r.scene, &cell))
        {
            for (metric, max, value) in [
                ("rms_vertex", t.rms_vertex_max, r.rms_vertex),
                ("rms_image", t.rms_image_max, r.rms_image),
            ] {
                let Some(max) = max else { continue };
                let v = value.unwrap_or(f64::INFINITY);
                if v.is_nan() || v > max {
                    out.push(Failure {
                        cell: r.cell.clone(),
                        metric,
                        value: v,
                        rule: Rule::Max(max),
                    });
                }
            }
        }
    }
    out
}

/// The errors of a row that the committed run is compared on.
fn compared(r: &Row) -> Compared {
    [
        ("rms_vertex", r.rms_vertex),
        ("rms_image", r.rms_image),
        ("rms_vs_truth", r.rms_vs_truth),
    ]
}

/// Every row's errors against the same cell (scene and cell id) of `committed`, two-sided:
/// a value outside `committed / COMMITTED_TOLERANCE ..= committed × COMMITTED_TOLERANCE` fails,
/// as does a value the run measured that the committed run lacks, or one it lost (NaN or
/// missing where the committed run has one). A committed 0 admits only 0.
pub fn check_committed(rows: &[Row], committed: &[Row]) -> Vec<Failure> {
    let keyed = |rows: &[Row]| -> Vec<(String, String, Compared)> {
        rows.iter()
            .map(|r| (r.scene.clone(), r.cell.clone(), compared(r)))
            .collect()
    };
    against_committed(&keyed(rows), &keyed(committed))
}

/// [`check_committed`] for the rows of `methods.csv`: each row against the committed row of
/// the same scene, setting and backend, on the same three errors (named `SCENE/SETTING`, with
/// `@gpu` for a setting on the GPU).
pub fn check_committed_methods(rows: &[NamedRow], committed: &[NamedRow]) -> Vec<Failure> {
    let keyed = |rows: &[NamedRow]| -> Vec<(String, String, Compared)> {
        rows.iter()
            .map(|r| {
                let (scene, setting) =
                    (r.get("scene").unwrap_or(""), r.get("setting").unwrap_or(""));
                // A setting on the GPU is its own row (`SCENE/SETTING@gpu`).
                let on = match r.get("backend") {
                    None | Some("") | Some("cpu") => String::new(),
                    Some(b) => format!("@{b}"),
                };
                let metric = |m: &'static str| (m, r.number(m));
                (
                    scene.to_string(),
                    format!("{scene}/{setting}{on}"),
                    [
                        metric("rms_vertex"),
                        metric("rms_image"),
                        metric("rms_vs_truth"),
                    ],
                )
            })
            .collect()
    };
    against_committed(&keyed(rows), &keyed(committed))
}

/// [`check_committed`] for the rows of `experiment dynamic`'s `sweep_frames.csv`: each (sweep,
/// casters, frame, gap, method) on its same-ray RMS, its RMS against the frame's converged
/// reference and its mean AO, against the committed row with the same key (named
/// `SWEEP/N=…/frame=…/METHOD`). Rows of methods the committed run has none of (Embree's, in a
/// build with the `embree` feature against a run without it) are left out and counted in the
/// second value returned.
pub fn check_committed_dynamic(rows: &[NamedRow], committed: &[NamedRow]) -> (Vec<Failure>, usize) {
    let id = |r: &NamedRow| {
        let g = |k: &str| r.get(k).unwrap_or("");
        let gap = match g("gap_radii") {
            "" => String::new(),
            v => format!("/gap={v}"),
        };
        (
            g("sweep").to_string(),
            format!(
                "{}/N={}/frame={}{gap}/{}",
                g("sweep"),
                g("casters"),
                g("frame"),
                g("method")
            ),
        )
    };
    check_committed_per_method(
        rows,
        committed,
        id,
        ["rms_vs_raycast", "rms_vs_truth", "mean_ao"],
    )
}

/// [`check_committed`] for an animated spec's `frames.csv`: each (scene, frame, method, field
/// cell) on `rms_vs_raycast`, `rms_vs_truth` and `mean_value` against the committed row with
/// the same key (named `SCENE/frame=…/METHOD` and `/CELL` for a field method); rows of
/// methods the committed run has none of are left out and counted, as in
/// [`check_committed_dynamic`].
pub fn check_committed_frames(rows: &[NamedRow], committed: &[NamedRow]) -> (Vec<Failure>, usize) {
    let id = |r: &NamedRow| {
        let g = |k: &str| r.get(k).unwrap_or("");
        let cell = match g("cell") {
            "" => String::new(),
            c => format!("/{c}"),
        };
        (
            g("scene").to_string(),
            format!("{}/frame={}/{}{cell}", g("scene"), g("frame"), g("method")),
        )
    };
    check_committed_per_method(
        rows,
        committed,
        id,
        ["rms_vs_raycast", "rms_vs_truth", "mean_value"],
    )
}

/// Rows of per-frame methods against the committed ones by `id` ((group, name)) on `metrics`:
/// a committed row the run lost fails; rows of a `method` the committed run has none of are
/// left out and counted.
fn check_committed_per_method(
    rows: &[NamedRow],
    committed: &[NamedRow],
    id: impl Fn(&NamedRow) -> (String, String),
    metrics: [&'static str; 3],
) -> (Vec<Failure>, usize) {
    let has = |m: &str| committed.iter().any(|r| r.get("method") == Some(m));
    let keyed = |rows: &[NamedRow]| -> Vec<(String, String, Compared)> {
        rows.iter()
            .map(|r| {
                let (group, name) = id(r);
                (group, name, metrics.map(|m| (m, r.number(m))))
            })
            .collect()
    };
    let (kept, left): (Vec<NamedRow>, Vec<NamedRow>) = rows
        .iter()
        .cloned()
        .partition(|r| has(r.get("method").unwrap_or("")));
    let (ours, theirs) = (keyed(&kept), keyed(committed));
    let mut failures = against_committed(&ours, &theirs);
    // A committed row the run lost (a method or a frame no longer run); the rows of a method
    // this build lacks (Embree's without `--features embree`) are left out and counted.
    let mut missing_here = 0;
    for ((_, id, t), r) in theirs.iter().zip(committed) {
        if !built(r.get("method").unwrap_or("")) {
            missing_here += 1;
            continue;
        }
        if !ours.iter().any(|(_, i, _)| i == id) {
            failures.push(Failure {
                cell: id.clone(),
                metric: t[0].0,
                value: f64::NAN,
                rule: Rule::Committed(t[0].1.unwrap_or(f64::NAN)),
            });
        }
    }
    (failures, left.len() + missing_here)
}

/// Whether this build can run the per-frame method `method`: Embree's need `--features embree`.
fn built(method: &str) -> bool {
    cfg!(feature = "embree") || !method.starts_with("embree")
}

/// The errors a row is compared on, by name.
type Compared = [(&'static str, Option<f64>); 3];

/// Each (scene, id, errors) against the committed one of the same scene and id.
fn against_committed(
    rows: &[(String, String, Compared)],
    committed: &[(String, String, Compared)],
) -> Vec<Failure> {
    let mut out = Vec::new();
    for (scene, id, ours) in rows {
        let theirs = committed
            .iter()
            .find(|(s, i, _)| s == scene && i == id)
            .map(|(_, _, t)| t);
        for (i, &(metric, value)) in ours.iter().enumerate() {
            let base = theirs.and_then(|t| t[i].1).filter(|b| b.is_finite());
            let fail = |value: f64, rule| Failure {
                cell: id.clone(),
                metric,
                value,
                rule,
            };
            match (value, base) {
                (None, None) => {}
                (Some(v), None) => out.push(fail(v, Rule::NotCommitted)),
                (None, Some(b)) => out.push(fail(f64::NAN, Rule::Committed(b))),
                (Some(v), Some(b)) => {
                    let inside = v >= b / COMMITTED_TOLERANCE && v <= b * COMMITTED_TOLERANCE;
                    if !inside {
                        out.push(fail(v, Rule::Committed(b)));
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of the committed quickstart run, renamed and given these errors.
    fn row(cell: &str, rms: f64) -> Row {
        let rows: Vec<Row> = crate::experiment::outputs::read_csv(std::path::Path::new(
            "results/quickstart/table.csv",
        ))
        .expect("the committed quickstart table");
        let mut r = rows[0].clone();
        r.scene = "s".into();
        r.cell = cell.into();
        r.rms_image = Some(rms);
        r.rms_vertex = None;
        r.rms_vs_truth = Some(rms + 1.0);
        r
    }

    #[test]
    fn the_committed_run_is_a_two_sided_bound() {
        let committed = [row("a", 2.0), row("b", 0.5)];
        // The same values pass, and so does a drift inside the factor.
        assert!(check_committed(&committed, &committed).is_empty());
        assert!(check_committed(&[row("a", 2.4)], &committed).is_empty());
        // A doubled error fails, naming the cell, the metric and the bound.
        let f = check_committed(&[row("a", 4.0)], &committed);
        assert_eq!(
            f.iter().map(|f| f.metric).collect::<Vec<_>>(),
            ["rms_image", "rms_vs_truth"]
        );
        assert!(f[0].to_string().contains("a: rms_image 4.0000"), "{}", f[0]);
        // An error that drops to 0 fails too (rms_vs_truth stays at 1 inside 1.5 / 1.25).
        let mut zero = row("b", 0.0);
        zero.rms_vs_truth = Some(1.5);
        let f = check_committed(&[zero], &committed);
        assert_eq!(f.len(), 1);
        assert_eq!(
            (f[0].metric, f[0].rule),
            ("rms_image", Rule::Committed(0.5))
        );
        // A value lost, and a cell the committed run lacks.
        let mut lost = row("a", 2.0);
        lost.rms_image = None;
        assert_eq!(check_committed(&[lost], &committed).len(), 1);
        let f = check_committed(&[row("c", 1.0)], &committed);
        assert!(f.iter().all(|f| f.rule == Rule::NotCommitted) && f.len() == 2);
    }

    fn frame(method: &str, frame: usize, rms: f64) -> NamedRow {
        let mut r = NamedRow::new();
        r.push("sweep", "crowd")
            .push("gap_radii", "")
            .push("casters", 4)
            .push("frame", frame)
            .push("method", method)
            .push("rms_vs_raycast", rms)
            .push("rms_vs_truth", 5.0)
            .push("mean_ao", 0.8);
        r
    }

    #[test]
    fn dynamic_rows_are_compared_by_frame_and_method() {
        let committed = [
            frame("world_rebuild", 0, 0.0),
            frame("field", 0, 4.0),
            frame("field", 1, 4.2),
        ];
        let (f, left) = check_committed_dynamic(&committed, &committed);
        assert!(f.is_empty() && left == 0);
        // A field error doubled on one frame fails, named by its key.
        let (f, _) = check_committed_dynamic(
            &[
                frame("world_rebuild", 0, 0.0),
                frame("field", 0, 8.0),
                frame("field", 1, 4.2),
            ],
            &committed,
        );
        assert_eq!(f.len(), 1);
        assert_eq!(
            (f[0].cell.as_str(), f[0].metric),
            ("crowd/N=4/frame=0/field", "rms_vs_raycast")
        );
        // The reference's own 0 admits only 0; a lost frame fails; a method the committed run
        // has none of is left out and counted.
        let (f, left) = check_committed_dynamic(
            &[
                frame("world_rebuild", 0, 0.1),
                frame("field", 0, 4.0),
                frame("embree_instances", 0, 0.0),
            ],
            &committed,
        );
        assert_eq!(left, 1);
        assert_eq!(
            f.iter().map(|f| f.cell.as_str()).collect::<Vec<_>>(),
            ["crowd/N=4/frame=0/world_rebuild", "crowd/N=4/frame=1/field"]
        );
        // A committed Embree row the run lacks: lost in a build with Embree, left out and
        // counted in one without it.
        let with_embree = [committed.to_vec(), vec![frame("embree_instances", 0, 0.0)]].concat();
        let (f, left) = check_committed_dynamic(&committed, &with_embree);
        if cfg!(feature = "embree") {
            assert_eq!((f.len(), left), (1, 0));
            assert_eq!(f[0].cell, "crowd/N=4/frame=0/embree_instances");
        } else {
            assert!(f.is_empty() && left == 1, "{f:?}");
        }
    }

    fn frame_row(method: &str, cell: &str, frame: usize, rms: f64) -> NamedRow {
        let mut r = NamedRow::new();
        r.push("scene", "multi")
            .push("frame", frame)
            .push("method", method)
            .push("cell", cell)
            .push("rms_vs_raycast", rms)
            .push("rms_vs_truth", 6.0)
            .push("mean_value", 0.7);
        r
    }

    #[test]
    fn frames_are_compared_by_scene_frame_method_and_cell() {
        let committed = [
            frame_row("world_rebuild", "", 0, 0.0),
            frame_row("field", "a", 0, 4.0),
            frame_row("field", "b", 0, 2.0),
        ];
        let (f, left) = check_committed_frames(&committed, &committed);
        assert!(f.is_empty() && left == 0);
        // The cells of one method are told apart: b's error doubled fails, named with its cell.
        let (f, _) = check_committed_frames(
            &[
                frame_row("world_rebuild", "", 0, 0.0),
                frame_row("field", "a", 0, 4.0),
                frame_row("field", "b", 0, 4.0),
            ],
            &committed,
        );
        assert_eq!(f.len(), 1);
        assert_eq!(
            (f[0].cell.as_str(), f[0].metric),
            ("multi/frame=0/field/b", "rms_vs_raycast")
        );
        // A lost cell fails; a method the committed run lacks is counted, not compared.
        let (f, left) = check_committed_frames(
            &[
                frame_row("world_rebuild", "", 0, 0.0),
                frame_row("field", "a", 0, 4.0),
                frame_row("two_level", "", 0, 0.0),
            ],
            &committed,
        );
        assert_eq!(left, 1);
        assert_eq!(
            f.iter().map(|f| f.cell.as_str()).collect::<Vec<_>>(),
            ["multi/frame=0/field/b"]
        );
    }
}
