//! The performance run's three growth plots, drawn from its rows (after the run, or from its
//! `backend_times.csv` by `experiment plots --dir results/performance`):
//!
//! - `growth_triangles.png`: each caster is another model, so its points are not joined: a
//!   line across models would read as one model's growth; the models are named under the plot;
//! - `growth_field_size.png`: one caster, a line per storage precision (fields of one
//!   precision at growing sizes), so that fields of two precisions at one size are two points,
//!   not a vertical step of one curve;
//! - `growth_entering.png`: one caster and field, a line per backend over the share of rays
//!   entering its sphere.

use super::PerfRow;
use crate::experiment::figures::facet::Family;
use crate::experiment::outputs;
use crate::experiment::plot::{distinct, figure_plot, sorted_distinct, Axes, Figure, Panel};
use crate::experiment::plot::{Series, Style, Styled};
use crate::experiment::Result;
use serde::Deserialize;
use std::path::Path;

/// The columns of a `backend_times.csv` row the plots read.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub struct PlotRow {
    pub sweep: String,
    pub caster: String,
    pub triangles: usize,
    pub field: String,
    pub field_bytes: u64,
    pub entering_share: f64,
    pub backend: String,
    pub mrays_s: f64,
}

impl PlotRow {
    pub fn of(r: &PerfRow) -> PlotRow {
        PlotRow {
            sweep: r.sweep.to_string(),
            caster: r.caster.clone(),
            triangles: r.triangles,
            field: r.field.clone(),
            field_bytes: r.field_bytes,
            entering_share: r.entering_share,
            backend: r.backend.to_string(),
            mrays_s: r.mrays_s,
        }
    }

    /// The storage precision of the row's field ("4226x32² u8" → "u8").
    fn precision(&self) -> &str {
        self.field.rsplit(' ').next().unwrap_or("")
    }
}

/// Redraws the plots of the performance run in `dir` from its `backend_times.csv` (or that
/// table under its former name, [`outputs::table_path`]).
pub fn redraw(dir: &Path) -> Result<()> {
    let rows: Vec<PlotRow> =
        outputs::read_csv(&outputs::table_path(dir, outputs::BACKEND_TIMES_CSV))?;
    draw(dir, &rows, None)
}

/// The style of a backend: ours, Embree and the field as in the comparison plots, the floors
/// in grey.
fn style(backend: &str, i: usize) -> Style {
    match backend {
        "raycast" => Family::RayCast.style(0, 0),
        "embree" => Family::Embree.style(0, 0),
        b if b.starts_with("field") => Family::Field.style(0, 0),
        "floor_sphere_cull" => Family::RayCast.style(2, 3),
        "floor_no_query" => Family::RayCast.style(1, 1),
        _ => Style::palette(i),
    }
}

/// The backends of a sweep, in order.
fn backends<'a>(rows: &'a [PlotRow], sweep: &str) -> Vec<&'a str> {
    distinct(
        rows.iter()
            .filter(|r| r.sweep == sweep)
            .map(|r| r.backend.as_str()),
    )
}

/// The kinds of ray: their sweeps' prefix, their plots' and their titles' names.
const RAYS: [(&str, &str); 3] = [
    ("", "Vertex AO rays"),
    ("shadow_", "Shadow rays"),
    ("reflection_", "Reflection rays"),
];

/// The three figures of each kind of ray, by file name (`caches`: the machine's cache sizes,
/// for the field-size plot's title, when drawn by the run).
pub fn figures(rows: &[PlotRow], caches: Option<&str>) -> Vec<(String, Figure)> {
    RAYS.iter()
        .flat_map(|&(prefix, what)| figures_of(rows, prefix, what, caches))
        .collect()
}

/// The three figures of the sweeps named `prefix` + `triangles`, `field_size`, `entering`.
fn figures_of(
    rows: &[PlotRow],
    prefix: &str,
    what: &str,
    caches: Option<&str>,
) -> Vec<(String, Figure)> {
    let named = |base: &str| format!("{prefix}{base}");
    let axes = |title: String, x: &str, log_x: bool| Axes {
        log_x,
        ..Axes::new(title, x, "Mrays/s (same rays, all threads; log)").log_y()
    };
    let mut out = Vec::new();
    // A figure of one panel, where any of its series has points.
    let mut add = |base: &str, axes: Axes, series: Vec<Styled>, notes: Vec<String>| {
        if series.iter().any(|s| !s.series.points.is_empty()) {
            let panels = vec![Panel::new("", series)];
            out.push((
                format!("growth_{prefix}{base}.png"),
                Figure {
                    axes,
                    panels,
                    notes,
                },
            ));
        }
    };
    // A series per backend of `sweep`, at `x` of its rows.
    let per_backend = |sweep: &str, x: fn(&PlotRow) -> f64, line: bool| -> Vec<Styled> {
        let backends = backends(rows, sweep);
        let of = |b: &str| -> Vec<(f64, f64)> {
            rows.iter()
                .filter(|r| r.sweep == sweep && r.backend == b)
                .map(|r| (x(r), r.mrays_s))
                .collect()
        };
        let series = |b: &str| Series {
            label: b.to_string(),
            points: of(b),
            line,
        };
        let styled = backends.iter().enumerate();
        styled
            .map(|(i, &b)| series(b).styled(style(b, i)))
            .collect()
    };

    // Caster triangles: points per backend, never joined across models.
    let sweep = &*named("triangles");
    let models = sorted_distinct(
        rows.iter()
            .filter(|r| r.sweep == sweep)
            .map(|r| (r.triangles, r.caster.as_str())),
    );
    let field = rows
        .iter()
        .find(|r| r.sweep == sweep)
        .map_or(String::new(), |r| format!(" (field {})", r.field));
    let names: Vec<String> = models.iter().map(|(t, m)| format!("{m} {t}")).collect();
    add(
        "triangles",
        axes(
            format!("{what} against caster triangles{field}"),
            "caster triangles (log; each a different model)",
            true,
        ),
        per_backend(sweep, |r| r.triangles as f64, false),
        vec![
            "points, not curves: each x is another model".into(),
            format!("models (triangles): {}", names.join(", ")),
        ],
    );

    // Field size: a line per precision for the field's lookups; the backends that read no
    // field (ray casters, floors) as points, repeats on the same rays.
    let sweep = &*named("field_size");
    let precisions = sorted_distinct(
        rows.iter()
            .filter(|r| r.sweep == sweep)
            .map(PlotRow::precision),
    );
    let mut size: Vec<Styled> = Vec::new();
    for (i, &b) in backends(rows, sweep).iter().enumerate() {
        let these = |p: Option<&str>| -> Vec<(f64, f64)> {
            rows.iter()
                .filter(|r| r.sweep == sweep && r.backend == b)
                .filter(|r| p.is_none_or(|p| r.precision() == p))
                .map(|r| (r.field_bytes as f64 / 1e6, r.mrays_s))
                .collect()
        };
        let st = style(b, i);
        if !b.starts_with("field") {
            let series = Series::scatter(format!("{b} (reads no field)"), these(None));
            size.push(series.styled(Style {
                dashed: false,
                ..st
            }));
            continue;
        }
        for (k, &p) in precisions.iter().enumerate() {
            let points = these(Some(p));
            if !points.is_empty() {
                let style = if k % 2 == 1 { st.hollow().dashed() } else { st };
                size.push(Series::line(format!("{b}, {p} fields"), points).styled(style));
            }
        }
    }
    let caster = rows
        .iter()
        .find(|r| r.sweep == sweep)
        .map_or(String::new(), |r| format!("{} ", r.caster));
    let caches = caches
        .filter(|c| !c.is_empty())
        .map_or(String::new(), |c| format!(" ({c})"));
    add(
        "field_size",
        axes(
            format!("{what} against field size{caches}"),
            &format!("{caster}field storage, MB (10⁶ bytes; log)"),
            true,
        ),
        size,
        Vec::new(),
    );

    // The share of rays entering the caster's sphere.
    add(
        "entering",
        axes(
            format!("{what} against the share entering the caster's sphere"),
            "share of rays entering the bounding sphere",
            false,
        ),
        per_backend(&named("entering"), |r| r.entering_share, true),
        Vec::new(),
    );
    out
}

/// Draws the figures into `out`.
pub fn draw(out: &Path, rows: &[PlotRow], caches: Option<&str>) -> Result<()> {
    for (name, fig) in figures(rows, caches) {
        figure_plot(&out.join(name), &fig)?;
    }
    Ok(())
}

/// "L2 512 KiB, L3 16384 KiB" from sysfs (empty where unknown).
pub fn cache_sizes() -> String {
    let read = |i: u32| {
        let d = format!("/sys/devices/system/cpu/cpu0/cache/index{i}");
        let level = std::fs::read_to_string(format!("{d}/level")).ok()?;
        let size = std::fs::read_to_string(format!("{d}/size")).ok()?;
        Some(format!("L{} {}", level.trim(), size.trim()))
    };
    (2..5).filter_map(read).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(sweep: &str, caster: &str, tris: usize, field: &str, backend: &str) -> PlotRow {
        PlotRow {
            sweep: sweep.into(),
            caster: caster.into(),
            triangles: tris,
            field: field.into(),
            field_bytes: 1000 * tris as u64,
            entering_share: 0.25,
            backend: backend.into(),
            mrays_s: 10.0,
        }
    }

    #[test]
    fn models_are_points_and_precisions_are_lines_of_their_own() {
        let rows = vec![
            row("triangles", "bunny", 3674, "4226x32² u8", "raycast"),
            row("triangles", "dragon", 100000, "4226x32² u8", "raycast"),
            row("field_size", "bunny", 10, "4226x32² u8", "field_nearest"),
            row("field_size", "bunny", 20, "4226x64² u8", "field_nearest"),
            row("field_size", "bunny", 20, "4226x32² f32", "field_nearest"),
        ];
        let figs = figures(&rows, None);
        let tri = &figs
            .iter()
            .find(|f| f.0 == "growth_triangles.png")
            .unwrap()
            .1;
        // Two models: two points of one backend, not joined.
        let s = &tri.panels[0].series;
        assert_eq!(s.len(), 1);
        assert!(!s[0].series.line);
        assert_eq!(s[0].series.points.len(), 2);
        assert!(tri
            .notes
            .iter()
            .any(|n| n.contains("bunny 3674, dragon 100000")));
        // Two precisions: two lines, neither holding both fields of 20 kB.
        let size = &figs
            .iter()
            .find(|f| f.0 == "growth_field_size.png")
            .unwrap()
            .1;
        let labels: Vec<&str> = size.panels[0]
            .series
            .iter()
            .map(|s| s.series.label.as_str())
            .collect();
        assert_eq!(
            labels,
            ["field_nearest, f32 fields", "field_nearest, u8 fields"]
        );
        assert_eq!(size.panels[0].series[1].series.points.len(), 2);
        assert!(size.panels[0].series.iter().all(|s| s.series.line));
        // No entering rows: no plot.
        assert!(!figs.iter().any(|f| f.0 == "growth_entering.png"));
    }
}
