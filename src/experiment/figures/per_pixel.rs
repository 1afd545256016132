//! The plots of the 2010 paper's per-pixel figures, drawn when a run has what they need:
//!
//! - `time_vs_rays.png` (Figure 4): the estimate's time against rays per point, one series per field cell
//!   and backend (from `field_sweep.csv`) and one per ray-casting backend (from
//!   `raycast_sweep.csv`), when the field sweep has at least two ray counts. The paper's claim
//!   is that the field's time is flat in the map count and linear in the rays;
//! - `grain_vs_positional.png` (Figure 5 and the elongated-model limitation): the graininess of
//!   the error image ([`crate::experiment::metrics::grain`]) against positional samples, one
//!   series per scene and other varying axis, when the rows have it.

use super::{distinct_backends, key};
use crate::experiment::outputs::{FieldSweepRow, SweepRow};
use crate::experiment::plot::{xy_plot, Axes, Series};
use crate::experiment::spec::Backend;
use crate::experiment::table::Row;
use crate::experiment::Result;
use std::path::Path;

/// Draws `time_vs_rays.png` when `field_sweep` has two ray counts or more.
pub fn time_vs_rays(
    out: &Path,
    title: &str,
    rows: &[Row],
    field_sweep: &[FieldSweepRow],
    sweep: &[SweepRow],
) -> Result<()> {
    let mut counts: Vec<u32> = field_sweep.iter().map(|f| f.rays_per_point).collect();
    counts.sort_unstable();
    counts.dedup();
    if counts.len() < 2 {
        return Ok(());
    }
    let backends = distinct_backends(rows.iter().map(|r| r.backend));
    let on = |b: Backend| {
        if backends.len() > 1 {
            format!(" ({})", b.name())
        } else {
            String::new()
        }
    };
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let mut pts: Vec<(f64, f64)> = field_sweep
            .iter()
            .filter(|f| f.cell == r.cell && f.backend == r.backend)
            .map(|f| (f.rays_per_point as f64, 1e3 * f.estimate_s))
            .collect();
        if pts.is_empty() {
            continue;
        }
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let varying = key(rows, r, &["backend"]);
        let label = if varying == "field" {
            format!("field {} maps", r.positional_samples)
        } else {
            format!("field {} maps {varying}", r.positional_samples)
        };
        series.push(Series {
            label: format!("{label}{}", on(r.backend)),
            points: pts,
            line: true,
        });
    }
    for &b in &backends {
        let mut scenes: Vec<&str> = sweep
            .iter()
            .filter(|s| s.backend == b)
            .map(|s| s.scene.as_str())
            .collect();
        scenes.sort_unstable();
        scenes.dedup();
        for sc in scenes {
            let mut pts: Vec<(f64, f64)> = sweep
                .iter()
                .filter(|s| s.backend == b && s.scene == sc)
                .map(|s| (s.rays_per_point as f64, 1e3 * s.raycast_s))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let scene = if scenes_differ(rows) {
                format!(" {sc}")
            } else {
                String::new()
            };
            series.push(Series {
                label: format!("ray cast{scene}{}", on(b)),
                points: pts,
                line: true,
            });
        }
    }
    let axes = Axes {
        title: format!("{title}: estimate time against rays per point"),
        x_label: "rays per point".into(),
        y_label: "estimate time, ms (log)".into(),
        log_x: false,
        log_y: true,
    };
    xy_plot(&out.join("time_vs_rays.png"), &axes, &series, &[])
}

/// Draws `grain_vs_positional.png` when every row has a graininess.
pub fn grain_vs_positional(out: &Path, title: &str, rows: &[Row]) -> Result<()> {
    if rows.is_empty() || rows.iter().any(|r| r.grain.is_none()) {
        return Ok(());
    }
    let first = rows[0].backend;
    let mut series: Vec<Series> = Vec::new();
    // One backend (the first): GPU parity makes the others' images the same to 1/255.
    for r in rows.iter().filter(|r| r.backend == first) {
        let label = key(rows, r, &["backend"]);
        let Some(y) = r.grain else { continue };
        let p = (r.positional_samples as f64, y);
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push(p),
            None => series.push(Series {
                label,
                points: vec![p],
                line: true,
            }),
        }
    }
    let axes = Axes {
        title: format!("{title}: graininess of the error against positional samples"),
        x_label: "positional samples (maps)".into(),
        y_label: "grain: RMS of the error's 3×3 high-pass (0–255)".into(),
        log_x: true,
        log_y: false,
    };
    xy_plot(&out.join("grain_vs_positional.png"), &axes, &series, &[])
}

fn scenes_differ(rows: &[Row]) -> bool {
    rows.iter().any(|r| r.scene != rows[0].scene)
}
