//! The plots of a run, drawn from its CSV files and PNG images only (so `experiment plots`
//! redraws them without recomputing anything):
//!
//! - `images.png` and `differences.png`: the figure's image grids laid out as the papers lay
//!   theirs out (see [`grids`]);
//! - `rms_vs_positional.png`: RMS against positional samples with the paper's values (see
//!   [`positional`]);
//! - `pareto.png` and `error_vs_bytes.png`: the error against the estimate's time and against
//!   stored bytes, for the field's settings, ray casting and every method of `methods.csv`
//!   (see [`compare`]). When the run has a converged reference, the error is `rms_vs_truth`
//!   (per point, against the converged reference, log scale) and the reference's own noise
//!   floor is drawn as a dashed line; otherwise the same-ray RMS;
//! - `times.png` (scenes of several caster sizes): ray-cast, bake and estimate time against
//!   caster triangles (2008 Figure 8), as points (each scene its own model);
//! - `time_vs_rays.png` and `grain_vs_positional.png`: the 2010 per-pixel figures' plots (see
//!   `per_pixel`).
//!
//! Every plot names devices as [`labels`] does (lavapipe as "lavapipe (CPU)"), the quantity as
//! the run's kind (AO, shadow, reflection), holds at most
//! [`MAX_SERIES`](crate::experiment::plot::MAX_SERIES) series a panel ([`facet`]) and labels
//! its axes across their range ([`crate::experiment::plot::ticks`]). A folder written before
//! `methods.csv`, `field_sweep.csv` or `paper_vs_ours.csv` existed draws without them.
//!
//! The RMS of the image grids and of `rms_vs_positional.png` is per image pixel when the run
//! has images (the papers' figure), else per vertex.

pub mod compare;
pub mod facet;
pub mod grids;
pub mod labels;
mod per_pixel;
pub mod positional;
#[cfg(test)]
mod tests;

use super::cells::selection_name;
use super::columns::NamedRow;
use super::outputs::{read_csv, FieldSweepRow, SweepRow};
use super::paper::PaperRow;
use super::plot::{distinct, figure_plot, sorted_distinct, Axes, Figure, Panel, Series, Style};
use super::spec::Backend;
use super::table::Row;
use super::{Error, Result};
use crate::render::estimator::Quantity;
use labels::Devices;
use std::path::Path;

/// A finished run's tables, as its plots read them.
#[derive(Clone, Debug, Default)]
pub struct RunData {
    /// The plots' title (the spec's name).
    pub title: String,
    /// What the run's kind estimates: `run.json`'s `quantity` (a run without one: other).
    pub quantity: Quantity,
    pub rows: Vec<Row>,
    pub sweep: Vec<SweepRow>,
    pub field_sweep: Vec<FieldSweepRow>,
    pub methods: Vec<MethodRow>,
    pub paper: Vec<PaperRow>,
}

impl RunData {
    /// Reads the run in `out` (`table.csv`, and the other tables where they exist).
    pub fn load(out: &Path, title: &str) -> Result<RunData> {
        let table = out.join("table.csv");
        let rows: Vec<Row> = read_csv(&table)?;
        if rows.is_empty() {
            // A run writes one row per cell: a table without any is not a run's.
            return Err(Error::invalid(
                table.display().to_string(),
                "no rows: not a table written by a run, nothing to plot",
            ));
        }
        let optional = |name: &str| out.join(name).exists().then(|| out.join(name));
        let methods = match optional("methods.csv") {
            Some(p) => super::columns::read_csv(&p)?
                .iter()
                .map(MethodRow::of)
                .collect(),
            None => Vec::new(),
        };
        let quantity = std::fs::read(out.join("run.json"))
            .ok()
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
            .and_then(|v| serde_json::from_value(v["quantity"].clone()).ok())
            .unwrap_or(Quantity::Other);
        Ok(RunData {
            title: title.to_string(),
            quantity,
            rows,
            sweep: optional("raycast_sweep.csv").map_or(Ok(Vec::new()), |p| read_csv(&p))?,
            field_sweep: optional("field_sweep.csv").map_or(Ok(Vec::new()), |p| read_csv(&p))?,
            methods,
            paper: optional("paper_vs_ours.csv").map_or(Ok(Vec::new()), |p| read_csv(&p))?,
        })
    }

    /// The scenes in row order.
    pub fn scenes(&self) -> Vec<&str> {
        distinct(self.rows.iter().map(|r| r.scene.as_str()))
    }

    /// What the run's kind estimates, as an axis names it ([`Quantity::label`]).
    pub fn quantity(&self) -> String {
        self.quantity.label().to_string()
    }
}

/// One row of `methods.csv`, as the plots read it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MethodRow {
    pub scene: String,
    pub method: String,
    pub setting: String,
    /// The setting's parameters: the columns between `setting` and `backend` that the row
    /// fills (`res`, `precision`, `query`, …).
    pub params: Vec<(String, String)>,
    pub backend: String,
    pub precompute_s: Option<f64>,
    /// Stored bytes (none where the method does not know them, as Embree).
    pub bytes: Option<f64>,
    pub estimate_s: Option<f64>,
    pub rms_vs_truth: Option<f64>,
    pub rms_image: Option<f64>,
    pub rms_vertex: Option<f64>,
    pub image: String,
}

impl MethodRow {
    pub fn of(r: &NamedRow) -> MethodRow {
        let text = |n: &str| r.get(n).unwrap_or("").to_string();
        let mut params = Vec::new();
        let mut inside = false;
        for (name, value) in r.columns() {
            match name {
                "setting" => inside = true,
                "backend" => inside = false,
                _ if inside && !value.is_empty() => params.push((name.into(), value.into())),
                _ => {}
            }
        }
        MethodRow {
            scene: text("scene"),
            method: text("method"),
            setting: text("setting"),
            params,
            backend: text("backend"),
            precompute_s: r.number("precompute_s"),
            bytes: r.number("bytes"),
            estimate_s: r.number("estimate_s"),
            rms_vs_truth: r.number("rms_vs_truth"),
            rms_image: r.number("rms_image"),
            rms_vertex: r.number("rms_vertex"),
            image: text("image"),
        }
    }

    /// The value of parameter `name`.
    pub fn param(&self, name: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

/// The error the comparison plots show: against the converged reference where every row has
/// it, else against the same-ray ray cast, per image pixel or per vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    Truth,
    Image,
    Vertex,
}

impl Metric {
    pub fn of(rows: &[Row]) -> Metric {
        if !rows.is_empty() && rows.iter().all(|r| r.rms_vs_truth.is_some()) {
            Metric::Truth
        } else if !rows.is_empty() && rows.iter().all(|r| r.rms_image.is_some()) {
            Metric::Image
        } else {
            Metric::Vertex
        }
    }

    /// The one of a row's (truth, image, vertex) errors this metric is.
    fn pick(self, (truth, image, vertex): (Option<f64>, Option<f64>, Option<f64>)) -> Option<f64> {
        match self {
            Metric::Truth => truth,
            Metric::Image => image,
            Metric::Vertex => vertex,
        }
    }

    pub fn row(self, r: &Row) -> Option<f64> {
        self.pick((r.rms_vs_truth, r.rms_image, r.rms_vertex))
    }

    pub fn sweep(self, s: &SweepRow) -> Option<f64> {
        self.pick((s.rms_vs_truth, s.rms_image, s.rms_vertex))
    }

    pub fn method(self, m: &MethodRow) -> Option<f64> {
        self.pick((m.rms_vs_truth, m.rms_image, m.rms_vertex))
    }

    /// Axes titled `title` with `x_label` on a log x axis and the metric on y: a log axis
    /// where errors against the converged reference are never 0; against the same-ray ray
    /// cast, ray casting's own is.
    pub fn axes(self, title: String, x_label: impl Into<String>) -> Axes {
        let y_label = match self {
            Metric::Truth => "RMS per point vs converged reference (0–255; log)",
            Metric::Image => "RMS per image pixel vs same-ray ray cast (0–255)",
            Metric::Vertex => "RMS per vertex vs same-ray ray cast (0–255)",
        };
        Axes {
            log_y: self == Metric::Truth,
            ..Axes::new(title, x_label, y_label).log_x()
        }
    }
}

/// The RMS of the grids and of the positional plot, and its axis label.
fn metric(rows: &[Row]) -> (fn(&Row) -> Option<f64>, &'static str) {
    if !rows.is_empty() && rows.iter().all(|r| r.rms_image.is_some()) {
        (|r| r.rms_image, "RMS per image pixel vs reference (0–255)")
    } else {
        (|r| r.rms_vertex, "RMS per vertex vs reference (0–255)")
    }
}

/// The values of one axis of a row, as text.
type AxisFn = fn(&Row) -> String;

const AXES: [(&str, AxisFn); 8] = [
    ("scene", |r| r.scene.clone()),
    ("sphere", |r| r.sphere.name().to_string()),
    ("res", |r| format!("{}²", r.directional_res)),
    ("layout", |r| r.layout.name().to_string()),
    ("precision", |r| r.precision.name().to_string()),
    ("normals", |r| {
        r.normal_bits
            .map_or(String::new(), |b| format!("normals {b} bit"))
    }),
    ("selection", |r| selection_name(r.selection).to_string()),
    ("backend", |r| r.backend.name().to_string()),
];

/// A label made of the axes (other than `skip`) that vary among `rows`.
fn key(rows: &[Row], r: &Row, skip: &[&str]) -> String {
    let mut parts = Vec::new();
    for (name, f) in AXES {
        if skip.contains(&name) {
            continue;
        }
        let first = f(&rows[0]);
        if rows.iter().any(|o| f(o) != first) {
            parts.push(f(r));
        }
    }
    if parts.is_empty() {
        "field".into()
    } else {
        parts.join(" ")
    }
}

/// [`key`] as " KEY", to follow another label; empty where no axis varies.
fn key_suffix(rows: &[Row], r: &Row, skip: &[&str]) -> String {
    match key(rows, r, skip) {
        k if k == "field" => String::new(),
        k => format!(" {k}"),
    }
}

/// Every figure of a run, by file name (without drawing them).
pub fn figures(run: &RunData) -> Vec<(&'static str, Figure)> {
    let mut out = vec![("rms_vs_positional.png", positional::figure(run))];
    out.extend(per_pixel::time_vs_rays(run).map(|f| ("time_vs_rays.png", f)));
    out.extend(per_pixel::grain_vs_positional(run).map(|f| ("grain_vs_positional.png", f)));
    out.push(("pareto.png", compare::pareto(run)));
    out.push(("error_vs_bytes.png", compare::bytes(run)));
    out.extend(times(run).map(|f| ("times.png", f)));
    out
}

/// Redraws every plot of the run in `out`.
pub fn draw_all(out: &Path, title: &str) -> Result<()> {
    let run = RunData::load(out, title)?;
    grids::grids(out, &run)?;
    for (name, fig) in figures(&run) {
        figure_plot(&out.join(name), &fig)?;
    }
    Ok(())
}

/// `times.png`: bake, ray-cast and estimate time against caster triangles, when the scenes
/// have casters of two sizes at least; points only (each x is another model, not a curve).
fn times(run: &RunData) -> Option<Figure> {
    let rows = &run.rows;
    if sorted_distinct(rows.iter().map(|r| r.caster_triangles)).len() < 2 {
        return None;
    }
    let devices = Devices::of(rows);
    let scenes = run.scenes();
    let backends = sorted_distinct(rows.iter().map(|r| r.backend));
    // Per backend, the first row of each scene.
    let first = |b: Backend| -> Vec<&Row> {
        scenes
            .iter()
            .filter_map(|n| rows.iter().find(|r| r.scene == *n && r.backend == b))
            .collect()
    };
    let pick = |rs: &[&Row], f: fn(&Row) -> Option<f64>| -> Vec<(f64, f64)> {
        rs.iter()
            .filter_map(|r| f(r).map(|y| (r.caster_triangles as f64, y)))
            .collect()
    };
    let point =
        |label: String, points, i: usize| Series::scatter(label, points).styled(Style::palette(i));
    let q = run.quantity();
    let mut s = vec![point(
        "bake (preprocess)".into(),
        pick(&first(backends[0]), |r| r.bake_s),
        0,
    )];
    for &b in &backends {
        let rs = first(b);
        let on = format!(" ({})", devices.name(b));
        s.push(point(
            format!("ray cast{on}"),
            pick(&rs, |r| r.raycast_s),
            s.len(),
        ));
        s.push(point(
            format!("field {q} estimate{on}"),
            pick(&rs, |r| Some(r.estimate_s)),
            s.len(),
        ));
    }
    Some(Figure {
        axes: Axes::new(
            format!("{}: cost against caster triangles", run.title),
            "caster triangles (log; each a scene's model)",
            "seconds (log)",
        )
        .log_x()
        .log_y(),
        panels: vec![Panel::new("", s)],
        notes: vec![format!(
            "scenes: {}",
            scenes
                .iter()
                .map(|sc| {
                    let t = rows
                        .iter()
                        .find(|r| r.scene == *sc)
                        .map_or(0, |r| r.caster_triangles);
                    format!("{sc} {t}")
                })
                .collect::<Vec<_>>()
                .join(", ")
        )],
    })
}
