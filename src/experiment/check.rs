//! `experiment check`: RMS thresholds per cell. A threshold applies to every cell matching its
//! axes (an axis left out matches any value); a cell fails when its RMS exceeds the maximum.

use super::outputs::Row;
use super::plan::Cell;
use super::spec::Threshold;
use crate::field::FieldParams;

/// A cell whose RMS passed its threshold.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// The cell id.
    pub cell: String,
    /// "rms_vertex" or "rms_image".
    pub metric: &'static str,
    pub value: f64,
    pub max: f64,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: {} {:.4} exceeds its threshold {:.4}",
            self.cell, self.metric, self.value, self.max
        )
    }
}

/// Whether threshold `t` applies to `cell` of the scene called `scene`.
pub fn threshold_matches(t: &Threshold, scene: &str, cell: &Cell) -> bool {
    let p: &FieldParams = &cell.params;
    t.scene.as_ref().is_none_or(|s| s == scene)
        && t.sphere.is_none_or(|s| s == p.sphere)
        && t.positional_samples.is_none_or(|n| n == p.count)
        && t.directional_res.is_none_or(|r| r == p.res)
        && t.layout.is_none_or(|l| l == p.layout)
        && t.precision.is_none_or(|x| x == p.precision)
        && t.selection.is_none_or(|s| s == cell.selection)
        && t.backend.is_none_or(|b| b == cell.backend)
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
                        max,
                    });
                }
            }
        }
    }
    out
}
