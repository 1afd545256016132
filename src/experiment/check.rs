//! `experiment check`: RMS thresholds per cell, and every row of a run against the committed
//! run of the same spec and profile.
//!
//! A spec's threshold applies to every cell matching its axes ([`Threshold::matches`], an axis
//! left out matching any value); a cell fails when its RMS exceeds the maximum ([`check_rows`]).
//! Besides, each results file's rows are compared with the committed file's
//! (`results/quick/NAME` for `--quick`, `results/NAME` for a full check) by one comparator
//! ([`check_committed`]), each row with the committed row of the same name on three values,
//! two-sided: a value more than [`COMMITTED_TOLERANCE`] times the committed one or less than
//! its inverse fails, so a doubled error fails and so does an error that drops to 0 (a silent
//! fallback to ray casting, a field that reads the reference). What differs between the files
//! is their [`Compared`]: which columns name a row, which values are compared, and whether rows
//! are per-frame methods' ([`TABLE`], a spec's cells; [`METHODS`], its other methods' rows;
//! [`FRAMES`], an animated spec's frames; [`DYNAMIC`], `experiment dynamic`'s rows).

use super::columns::NamedRow;
use super::spec::Threshold;
use super::table::Row;

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
    /// The cell id, or the row's name ([`Compared::name`]).
    pub cell: String,
    /// "rms_vertex", "rms_image" or "rms_vs_truth", or another of [`Compared::metrics`].
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

/// Every (row, threshold) where a measured RMS exceeds the threshold's maximum. A missing
/// measurement (no image) fails too: the threshold cannot be verified.
pub fn check_rows(thresholds: &[Threshold], rows: &[Row]) -> Vec<Failure> {
    let mut out = Vec::new();
    for r in rows {
        let params = r.params();
        for t in
            (thresholds.iter()).filter(|t| t.matches(&r.scene, &params, r.selection, r.backend))
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

/// What of a results file [`check_committed`] compares.
pub struct Compared {
    /// A row's name: it is compared with the committed row of the same name, and a failure
    /// names it.
    pub name: fn(&NamedRow) -> String,
    /// The three values compared.
    pub metrics: [&'static str; 3],
    /// Whether the rows are per-frame methods': then the rows of a `method` the committed run
    /// has none of (Embree's, in a build with the `embree` feature against a run without it)
    /// are left out and counted, and a committed row the run lost fails (left out and counted
    /// too where this build cannot run its method: Embree's without `--features embree`).
    pub per_method: bool,
}

const ERRORS: [&str; 3] = ["rms_vertex", "rms_image", "rms_vs_truth"];

/// A spec's `table.csv`: each cell by its id.
pub const TABLE: Compared = Compared {
    name: |r| col(r, "cell").into(),
    metrics: ERRORS,
    per_method: false,
};

/// A spec's `methods.csv`: each row by its scene and setting, `SCENE/SETTING`, and `@gpu` after
/// it for a setting on the GPU (its own row).
pub const METHODS: Compared = Compared {
    name: |r| {
        let on = match col(r, "backend") {
            "" | "cpu" => String::new(),
            b => format!("@{b}"),
        };
        format!("{}/{}{on}", col(r, "scene"), col(r, "setting"))
    },
    metrics: ERRORS,
    per_method: false,
};

/// `experiment dynamic`'s `sweep_frames.csv`: each (sweep, casters, frame, gap, method),
/// `SWEEP/N=…/frame=…/METHOD` (`/gap=…` before the method where set), on its same-ray RMS, its
/// RMS against the frame's converged reference and its mean AO.
pub const DYNAMIC: Compared = Compared {
    name: |r| {
        let (sweep, n, frame) = (col(r, "sweep"), col(r, "casters"), col(r, "frame"));
        let gap = then("/gap=", col(r, "gap_radii"));
        format!("{sweep}/N={n}/frame={frame}{gap}/{}", col(r, "method"))
    },
    metrics: ["rms_vs_raycast", "rms_vs_truth", "mean_ao"],
    per_method: true,
};

/// An animated spec's `frames.csv`: each (scene, frame, method, field cell),
/// `SCENE/frame=…/METHOD` and `/CELL` after it for a field method.
pub const FRAMES: Compared = Compared {
    name: |r| {
        let (scene, frame, method) = (col(r, "scene"), col(r, "frame"), col(r, "method"));
        let cell = then("/", col(r, "cell"));
        format!("{scene}/frame={frame}/{method}{cell}")
    },
    metrics: ["rms_vs_raycast", "rms_vs_truth", "mean_value"],
    per_method: true,
};

/// Column `name` of `r` (empty where it has none).
fn col<'r>(r: &'r NamedRow, name: &str) -> &'r str {
    r.get(name).unwrap_or("")
}

/// `prefix` then `v`, or nothing where `v` is empty.
fn then(prefix: &str, v: &str) -> String {
    format!("{}{v}", if v.is_empty() { "" } else { prefix })
}

/// Each of `rows` against the committed row of the same name (`file`'s) on `file`'s three
/// values, two-sided: a value outside `committed / COMMITTED_TOLERANCE ..= committed ×
/// COMMITTED_TOLERANCE` fails, as does a value the run measured that the committed run lacks,
/// or one it lost (NaN or missing where the committed run has one). A committed 0 admits only
/// 0. Also the rows left out and counted, for per-frame methods ([`Compared::per_method`]).
pub fn check_committed(
    file: &Compared,
    rows: &[NamedRow],
    committed: &[NamedRow],
) -> (Vec<Failure>, usize) {
    let theirs: Vec<String> = committed.iter().map(file.name).collect();
    let has = |m: &str| committed.iter().any(|c| col(c, "method") == m);
    let (ours, left): (Vec<&NamedRow>, Vec<&NamedRow>) =
        (rows.iter()).partition(|r| !file.per_method || has(col(r, "method")));
    let names: Vec<String> = ours.iter().map(|r| (file.name)(r)).collect();
    let mut out = Vec::new();
    for (r, name) in ours.iter().zip(&names) {
        let at = theirs.iter().position(|n| n == name);
        for metric in file.metrics {
            let base = at.and_then(|i| committed[i].number(metric));
            let fail = |value: f64, rule| Failure {
                cell: name.clone(),
                metric,
                value,
                rule,
            };
            match (r.number(metric), base.filter(|b| b.is_finite())) {
                (None, None) => {}
                (Some(v), None) => out.push(fail(v, Rule::NotCommitted)),
                (None, Some(b)) => out.push(fail(f64::NAN, Rule::Committed(b))),
                (Some(v), Some(b)) => {
                    if !(b / COMMITTED_TOLERANCE..=b * COMMITTED_TOLERANCE).contains(&v) {
                        out.push(fail(v, Rule::Committed(b)));
                    }
                }
            }
        }
    }
    let mut left = left.len();
    // A committed row the run lost (a method or a frame no longer run); the rows of a method
    // this build lacks (Embree's without `--features embree`) are left out and counted.
    for (c, name) in committed.iter().zip(&theirs).filter(|_| file.per_method) {
        if !cfg!(feature = "embree") && col(c, "method").starts_with("embree") {
            left += 1;
        } else if !names.contains(name) {
            let metric = file.metrics[0];
            let rule = Rule::Committed(c.number(metric).unwrap_or(f64::NAN));
            out.push(Failure {
                cell: name.clone(),
                metric,
                value: f64::NAN,
                rule,
            });
        }
    }
    (out, left)
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

    /// Table rows against committed ones, read as named columns.
    fn check_table(rows: &[Row], committed: &[Row]) -> Vec<Failure> {
        let named = |rows: &[Row]| -> Vec<NamedRow> {
            rows.iter()
                .map(crate::experiment::columns::of_serialized)
                .collect()
        };
        let (f, left) = check_committed(&TABLE, &named(rows), &named(committed));
        assert_eq!(left, 0);
        f
    }

    #[test]
    fn the_committed_run_is_a_two_sided_bound() {
        let committed = [row("a", 2.0), row("b", 0.5)];
        // The same values pass, and so does a drift inside the factor.
        assert!(check_table(&committed, &committed).is_empty());
        assert!(check_table(&[row("a", 2.4)], &committed).is_empty());
        // A doubled error fails, naming the cell, the metric and the bound.
        let f = check_table(&[row("a", 4.0)], &committed);
        assert_eq!(
            f.iter().map(|f| f.metric).collect::<Vec<_>>(),
            ["rms_image", "rms_vs_truth"]
        );
        assert!(f[0].to_string().contains("a: rms_image 4.0000"), "{}", f[0]);
        // An error that drops to 0 fails too (rms_vs_truth stays at 1 inside 1.5 / 1.25).
        let mut zero = row("b", 0.0);
        zero.rms_vs_truth = Some(1.5);
        let f = check_table(&[zero], &committed);
        assert_eq!(f.len(), 1);
        assert_eq!(
            (f[0].metric, f[0].rule),
            ("rms_image", Rule::Committed(0.5))
        );
        // A value lost, and a cell the committed run lacks.
        let mut lost = row("a", 2.0);
        lost.rms_image = None;
        assert_eq!(check_table(&[lost], &committed).len(), 1);
        let f = check_table(&[row("c", 1.0)], &committed);
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
        let (f, left) = check_committed(&DYNAMIC, &committed, &committed);
        assert!(f.is_empty() && left == 0);
        // A field error doubled on one frame fails, named by its key.
        let (f, _) = check_committed(
            &DYNAMIC,
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
        let (f, left) = check_committed(
            &DYNAMIC,
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
        let (f, left) = check_committed(&DYNAMIC, &committed, &with_embree);
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
        let (f, left) = check_committed(&FRAMES, &committed, &committed);
        assert!(f.is_empty() && left == 0);
        // The cells of one method are told apart: b's error doubled fails, named with its cell.
        let (f, _) = check_committed(
            &FRAMES,
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
        let (f, left) = check_committed(
            &FRAMES,
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

    #[test]
    fn method_rows_are_named_by_scene_setting_and_backend() {
        let mut r = NamedRow::new();
        r.push("scene", "s")
            .push("setting", "embree")
            .push("backend", "gpu")
            .push("rms_image", 1.0);
        assert_eq!((METHODS.name)(&r), "s/embree@gpu");
        let (f, left) = check_committed(&METHODS, &[r], &[]);
        assert_eq!((f.len(), left, f[0].rule), (1, 0, Rule::NotCommitted));
    }
}
