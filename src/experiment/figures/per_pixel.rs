//! The plots of the 2010 paper's per-pixel figures, drawn when a run has what they need:
//!
//! - `time_vs_rays.png` (Figure 4): the estimate's time against rays per point, one series per
//!   field cell (from `field_sweep.csv`) and one for ray casting (from `raycast_sweep.csv`), a
//!   panel per device and positional count where they do not fit one, when the field sweep has
//!   at least two ray counts. The paper's claim is that the field's time is flat in the map
//!   count and linear in the rays;
//! - `grain_vs_positional.png` (Figure 5 and the elongated-model limitation): the graininess of
//!   the error image ([`crate::experiment::metrics::grain`]) against positional samples, one
//!   series per scene and other varying axis, when the rows have it.

use super::compare::res_ranks;
use super::facet::{one_or_pack, viridis, Family, Group};
use super::labels::Devices;
use super::{key, RunData};
use crate::experiment::plot::{sorted_distinct, Axes, Figure, Marker, Panel, Series, Style};

/// `time_vs_rays.png`, when `field_sweep.csv` has two ray counts or more.
pub fn time_vs_rays(run: &RunData) -> Option<Figure> {
    if sorted_distinct(run.field_sweep.iter().map(|f| f.rays_per_point)).len() < 2 {
        return None;
    }
    let rows = &run.rows;
    let devices = Devices::of(rows);
    let ranks = res_ranks(rows);
    let scenes = run.scenes();
    let backends = sorted_distinct(rows.iter().map(|r| r.backend));
    let mut panels: Vec<Panel> = Vec::new();
    for &b in &backends {
        let d = devices.name(b);
        // Ray casting on this device, per scene.
        let context: Vec<_> = scenes
            .iter()
            .filter_map(|sc| {
                let mut pts: Vec<(f64, f64)> = run
                    .sweep
                    .iter()
                    .filter(|s| s.backend == b && s.scene == *sc)
                    .map(|s| (s.rays_per_point as f64, 1e3 * s.raycast_s))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                let scene = if scenes.len() > 1 {
                    format!(" {sc}")
                } else {
                    String::new()
                };
                (!pts.is_empty()).then(|| {
                    Series::line(format!("ray cast{scene}, {d}"), pts)
                        .styled(Family::RayCast.style(0, 0))
                })
            })
            .collect();
        let mut groups: Vec<Group> = Vec::new();
        for r in rows.iter().filter(|r| r.backend == b) {
            let mut pts: Vec<(f64, f64)> = run
                .field_sweep
                .iter()
                .filter(|f| f.cell == r.cell)
                .map(|f| (f.rays_per_point as f64, 1e3 * f.estimate_s))
                .collect();
            if pts.is_empty() {
                continue;
            }
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let varying = key(rows, r, &["backend"]);
            let title = format!("{d}, {} maps", r.positional_samples);
            let s = Series::line(
                format!("field {} maps {varying}", r.positional_samples),
                pts,
            )
            .styled(Style::new(
                viridis(ranks.rank(r.directional_res)),
                Marker::Circle,
            ));
            match groups.iter_mut().find(|g| g.title == title) {
                Some(g) => g.series.push(s),
                None => groups.push(Group {
                    title,
                    series: vec![s],
                }),
            }
        }
        panels.extend(one_or_pack(groups, &context, d.to_string(), ""));
    }
    let q = run.quantity();
    Some(Figure {
        axes: Axes::new(
            format!("{}: {q} estimate time against rays per point", run.title),
            "rays per point",
            format!("{q} estimate time, ms (log)"),
        )
        .log_y(),
        panels,
        notes: Vec::new(),
    })
}

/// `grain_vs_positional.png`, when every row has a graininess.
pub fn grain_vs_positional(run: &RunData) -> Option<Figure> {
    let rows = &run.rows;
    if rows.is_empty() || rows.iter().any(|r| r.grain.is_none()) {
        return None;
    }
    let first = rows[0].backend;
    let devices = Devices::of(rows);
    let mut groups: Vec<Group> = Vec::new();
    // One backend (the first): GPU parity makes the others' images the same to 1/255.
    for r in rows.iter().filter(|r| r.backend == first) {
        let label = key(rows, r, &["backend"]);
        let Some(y) = r.grain else { continue };
        let p = (r.positional_samples as f64, y);
        match groups
            .iter_mut()
            .flat_map(|g| g.series.iter_mut())
            .find(|s| s.series.label == label)
        {
            Some(s) => s.series.points.push(p),
            None => {
                let n: usize = groups.iter().map(|g| g.series.len()).sum();
                let s = Series::line(label, vec![p]).styled(Style::palette(n));
                match groups.iter_mut().find(|g| g.title == r.scene) {
                    Some(g) => g.series.push(s),
                    None => groups.push(Group {
                        title: r.scene.clone(),
                        series: vec![s],
                    }),
                }
            }
        }
    }
    let panels = one_or_pack(groups, &[], String::new(), "");
    let notes = if rows.iter().any(|r| r.backend != first) {
        vec![format!(
            "{} rows (the other backends' images are the same to 1/255: GPU parity)",
            devices.name(first)
        )]
    } else {
        Vec::new()
    };
    Some(Figure {
        axes: Axes::new(
            format!(
                "{}: graininess of the error against positional samples",
                run.title
            ),
            "positional samples (maps; log)",
            "grain: RMS of the error's 3×3 high-pass (0–255)",
        )
        .log_x(),
        panels,
        notes,
    })
}
