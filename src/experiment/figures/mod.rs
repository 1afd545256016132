//! The plots of a run, drawn from its CSV files and PNG images only (so `experiment plots`
//! redraws them without recomputing anything):
//!
//! - `images.png`: the figure's image grid with its numbers under each image, as in the paper
//!   (bake time, the estimate's time, RMS); the reference image opens each scene's first row; images wider
//!   than 256 pixels are shown reduced by an integer factor (box filter);
//! - `differences.png`: the same grid of |field − reference| × 5 images;
//! - `rms_vs_positional.png`: RMS against positional samples, one series per directional
//!   resolution (and per other axis the spec varies);
//! - `pareto.png`: RMS against the estimate's time for every field setting (and, with `field_sweep.csv`,
//!   each field at more rays per point) and for ray casting at several ray counts, so that at
//!   equal time one sees which wins. When the run has a converged reference, every method's RMS
//!   is `rms_vs_truth` (per point, against the converged reference, log scale) and the
//!   reference's own noise floor is drawn as a dashed line; otherwise the same-ray RMS;
//! - `times.png` (several scenes): ray-cast, bake and estimate time against caster triangles
//!   (2008 Figure 8), ray-cast and estimate time once per backend;
//! - `time_vs_rays.png` and `grain_vs_positional.png`: the 2010 per-pixel figures' plots (see
//!   [`per_pixel`]).
//!
//! Every series is labelled with the backend as soon as a run has more than one (CPU and GPU
//! rows of the same field are different points, never one series).
//!
//! The RMS shown is per image pixel when the run has images (the papers' figure), else per
//! vertex.

mod per_pixel;

use super::outputs::{read_csv, FieldSweepRow, SweepRow};
use super::plan::selection_name;
use super::plot::{image_grid, xy_plot, Axes, HLine, Series};
use super::spec::Backend;
use super::table::Row;
use super::{Error, Result};
use crate::render::image::GrayImage;
use std::path::Path;

/// The RMS to plot and its axis label.
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

/// Redraws every plot of the run in `out`.
pub fn draw_all(out: &Path, title: &str) -> Result<()> {
    let table = out.join("table.csv");
    let rows: Vec<Row> = read_table(&table)?;
    if rows.is_empty() {
        // A run writes one row per cell: a table without any is not a run's.
        return Err(Error::invalid(
            table.display().to_string(),
            "no rows: not a table written by a run, nothing to plot",
        ));
    }
    let sweep_path = out.join("raycast_sweep.csv");
    let sweep: Vec<SweepRow> = if sweep_path.exists() {
        read_table(&sweep_path)?
    } else {
        Vec::new()
    };
    let (m, m_label) = metric(&rows);
    grids(out, title, &rows, &sweep, m)?;

    // RMS against positional samples.
    let mut series: Vec<Series> = Vec::new();
    for r in &rows {
        let label = key(&rows, r, &[]);
        let Some(y) = m(r) else { continue };
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push((r.positional_samples as f64, y)),
            None => series.push(Series {
                label,
                points: vec![(r.positional_samples as f64, y)],
                line: true,
            }),
        }
    }
    let axes = Axes {
        title: format!("{title}: error against positional samples"),
        x_label: "positional samples (maps)".into(),
        y_label: m_label.into(),
        log_x: true,
        log_y: false,
    };
    xy_plot(&out.join("rms_vs_positional.png"), &axes, &series, &[])?;

    // Error against time: every field setting, and ray casting at several ray counts.
    let fs_path = out.join("field_sweep.csv");
    let field_sweep: Vec<FieldSweepRow> = if fs_path.exists() {
        read_table(&fs_path)?
    } else {
        Vec::new()
    };
    per_pixel::time_vs_rays(out, title, &rows, &field_sweep, &sweep)?;
    per_pixel::grain_vs_positional(out, title, &rows)?;
    if rows.iter().all(|r| r.rms_vs_truth.is_some()) {
        pareto_vs_truth(out, title, &rows, &sweep, &field_sweep)?;
    } else {
        pareto_same_rays(out, title, &rows, &sweep, m, m_label)?;
    }

    // Times against caster triangles, when the spec has several scenes.
    let mut names: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    names.dedup();
    if names.len() > 1 {
        let backends = distinct_backends(rows.iter().map(|r| r.backend));
        // Per backend, the first row of each scene.
        let first = |b: Backend| -> Vec<&Row> {
            names
                .iter()
                .filter_map(|n| rows.iter().find(|r| r.scene == *n && r.backend == b))
                .collect()
        };
        let pick = |rs: &[&Row], f: fn(&Row) -> Option<f64>| -> Vec<(f64, f64)> {
            rs.iter()
                .filter_map(|r| f(r).map(|y| (r.caster_triangles as f64, y)))
                .collect()
        };
        let mut s = vec![Series {
            label: "bake (preprocess)".into(),
            points: pick(&first(backends[0]), |r| r.bake_s),
            line: false,
        }];
        for &b in &backends {
            let rs = first(b);
            let on = if backends.len() > 1 {
                format!(" ({})", b.name())
            } else {
                String::new()
            };
            s.push(Series {
                label: format!("ray cast{on}"),
                points: pick(&rs, |r| r.raycast_s),
                line: false,
            });
            s.push(Series {
                label: format!("field lookup{on}"),
                points: pick(&rs, |r| Some(r.estimate_s)),
                line: false,
            });
        }
        let axes = Axes {
            title: format!("{title}: cost against caster triangles"),
            x_label: "caster triangles".into(),
            y_label: "seconds".into(),
            log_x: true,
            log_y: true,
        };
        xy_plot(&out.join("times.png"), &axes, &s, &[])?;
    }
    Ok(())
}

/// The error-against-time plot against the same-ray reference (runs without a truth).
fn pareto_same_rays(
    out: &Path,
    title: &str,
    rows: &[Row],
    sweep: &[SweepRow],
    m: fn(&Row) -> Option<f64>,
    m_label: &str,
) -> Result<()> {
    let mut series: Vec<Series> = Vec::new();
    for r in rows {
        let label = format!(
            "field {}",
            key(rows, r, &["precision", "selection", "layout"])
        );
        let Some(y) = m(r) else { continue };
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push((r.estimate_s, y)),
            None => series.push(Series {
                label,
                points: vec![(r.estimate_s, y)],
                line: false,
            }),
        }
    }
    let sm = |s: &SweepRow| {
        if m_label.contains("pixel") {
            s.rms_image
        } else {
            s.rms_vertex
        }
    };
    series.extend(raycast_series(sweep, sm));
    let rays = rows[0].rays_per_point;
    let axes = Axes {
        title: format!("{title}: error against the estimate's time"),
        x_label: format!("estimate time, s (field: {rays} rays/point)"),
        y_label: m_label.into(),
        log_x: true,
        log_y: false,
    };
    xy_plot(&out.join("pareto.png"), &axes, &series, &[])
}

/// The error-against-time plot against the converged reference: every field setting (with
/// more rays per point where `field_sweep.csv` has them), ray casting at every swept ray count,
/// and the reference's own noise floor.
fn pareto_vs_truth(
    out: &Path,
    title: &str,
    rows: &[Row],
    sweep: &[SweepRow],
    field_sweep: &[FieldSweepRow],
) -> Result<()> {
    let mut series: Vec<Series> = Vec::new();
    // One backend's fields (the first, the CPU when it ran): the others give the same errors
    // (GPU parity) at other times, and one series per cell and backend would not fit a legend.
    let first = rows[0].backend;
    for r in rows.iter().filter(|r| r.backend == first) {
        let Some(y) = r.rms_vs_truth else { continue };
        let more: Vec<&FieldSweepRow> = field_sweep.iter().filter(|f| f.cell == r.cell).collect();
        if more.is_empty() {
            let label = match key(rows, r, &[]) {
                k if k == "field" => k,
                k => format!("field {k}"),
            };
            match series.iter_mut().find(|s| s.label == label) {
                Some(s) => s.points.push((r.estimate_s, y)),
                None => series.push(Series {
                    label,
                    points: vec![(r.estimate_s, y)],
                    line: false,
                }),
            }
            continue;
        }
        let mut pts: Vec<(f64, f64)> = vec![(r.estimate_s, y)];
        let mut counts = vec![r.rays_per_point];
        for f in more {
            if f.rays_per_point != r.rays_per_point {
                pts.extend(f.rms_vs_truth.map(|y| (f.estimate_s, y)));
                counts.push(f.rays_per_point);
            }
        }
        counts.sort_unstable();
        let counts: Vec<String> = counts.iter().map(|c| c.to_string()).collect();
        let varying = key(rows, r, &["res"]);
        let extra = if varying == "field" {
            String::new()
        } else {
            format!(" {varying}")
        };
        series.push(Series {
            label: format!(
                "field {}×{}²{extra} ({} rays)",
                r.positional_samples,
                r.directional_res,
                counts.join("/")
            ),
            points: pts,
            line: true,
        });
    }
    series.extend(raycast_series(sweep, |s| s.rms_vs_truth));
    let floor = rows
        .iter()
        .filter_map(|r| r.truth_stderr)
        .fold(0.0f64, f64::max);
    let rays = rows[0].truth_rays.unwrap_or(0);
    let hlines: Vec<HLine> = (floor > 0.0)
        .then(|| HLine {
            label: format!("converged reference's noise (RMS std. error, {rays} rays)"),
            y: floor,
        })
        .into_iter()
        .collect();
    let axes = Axes {
        title: format!("{title}: error against the estimate's time, vs the converged reference"),
        x_label: "estimate time, s".into(),
        y_label: "RMS per point vs converged reference (0–255)".into(),
        log_x: true,
        log_y: true,
    };
    xy_plot(&out.join("pareto.png"), &axes, &series, &hlines)
}

/// One series per scene and backend of ray casting at the swept ray counts, with `y` as the
/// error (the backend is named as soon as the sweep has more than one).
fn raycast_series(sweep: &[SweepRow], y: impl Fn(&SweepRow) -> Option<f64>) -> Vec<Series> {
    let mut sweep = sweep.to_vec();
    sweep.sort_by_key(|s| (s.rays_per_point, s.backend));
    let mut scenes: Vec<&str> = Vec::new();
    for s in &sweep {
        if !scenes.contains(&s.scene.as_str()) {
            scenes.push(&s.scene);
        }
    }
    let backends = distinct_backends(sweep.iter().map(|s| s.backend));
    let mut series = Vec::new();
    for sc in scenes {
        for &b in &backends {
            let these: Vec<&SweepRow> = sweep
                .iter()
                .filter(|s| s.scene == sc && s.backend == b)
                .collect();
            if these.is_empty() {
                continue;
            }
            let counts: Vec<String> = these.iter().map(|s| s.rays_per_point.to_string()).collect();
            let on = if backends.len() > 1 {
                format!(" {}", b.name())
            } else {
                String::new()
            };
            series.push(Series {
                label: format!("ray cast {sc}{on} ({} rays)", counts.join("/")),
                points: these
                    .iter()
                    .filter_map(|s| y(s).map(|v| (s.raycast_s, v)))
                    .collect(),
                line: true,
            });
        }
    }
    series
}

/// The backends among `b`, each once, in order.
fn distinct_backends(b: impl Iterator<Item = Backend>) -> Vec<Backend> {
    let mut b: Vec<Backend> = b.collect();
    b.sort();
    b.dedup();
    b
}

/// The rows of one of the run's tables.
fn read_table<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    read_csv(path)
}

/// The widest a grid cell is drawn (pixels): larger images are shown box-filtered by the
/// smallest integer factor that fits, so that a figure of many 512 × 512 cells stays a
/// picture of a few MB (the full images are beside it in `images/`).
const GRID_CELL_MAX: u32 = 256;

/// A run's PNG as a grid cell (see [`GRID_CELL_MAX`]).
fn load_png(path: &Path) -> Result<GrayImage> {
    let img = image::open(path).map_err(Error::image(path))?.to_luma8();
    let full = GrayImage {
        width: img.width(),
        height: img.height(),
        data: img.pixels().map(|p| p.0[0] as f32 / 255.0).collect(),
    };
    Ok(box_down(&full, full.width.div_ceil(GRID_CELL_MAX).max(1)))
}

/// `img` reduced by the integer factor `f` (the mean of each f × f block; partial blocks at
/// the right and bottom edges are dropped).
fn box_down(img: &GrayImage, f: u32) -> GrayImage {
    if f <= 1 {
        return img.clone();
    }
    let (w, h) = (img.width / f, img.height / f);
    let mut out = GrayImage::new(w, h, 0.0);
    for y in 0..h {
        for x in 0..w {
            let mut sum = 0.0f32;
            for yy in y * f..(y + 1) * f {
                for xx in x * f..(x + 1) * f {
                    sum += img.data[(yy * img.width + xx) as usize];
                }
            }
            out.data[(y * w + x) as usize] = sum / (f * f) as f32;
        }
    }
    out
}

/// The image grid and the difference grid: per scene, rows of cells sharing every axis but
/// the one with the most values (the columns), the reference first.
fn grids(
    out: &Path,
    title: &str,
    rows: &[Row],
    sweep: &[SweepRow],
    m: fn(&Row) -> Option<f64>,
) -> Result<()> {
    let with_images: Vec<&Row> = rows.iter().filter(|r| !r.image.is_empty()).collect();
    if with_images.is_empty() {
        return Ok(());
    }
    let owned: Vec<Row> = with_images.iter().map(|r| (*r).clone()).collect();
    // Reversed, so that ties go to the earlier axis (max_by_key keeps the last maximum).
    let (col_name, col_fn) = AXES[2..]
        .iter()
        .rev()
        .copied()
        .max_by_key(|(_, f)| {
            let mut v: Vec<String> = owned.iter().map(f).collect();
            v.sort();
            v.dedup();
            v.len()
        })
        .expect("axes");
    let mut columns: Vec<String> = Vec::new();
    for r in &owned {
        let v = col_fn(r);
        if !columns.contains(&v) {
            columns.push(v);
        }
    }
    let first = load_png(&out.join(&owned[0].image))?;
    let blank = GrayImage::new(first.width, first.height, 1.0);
    let mut cells: Vec<(GrayImage, Vec<String>)> = Vec::new();
    let mut diffs: Vec<(GrayImage, Vec<String>)> = Vec::new();
    let mut scenes: Vec<&str> = owned.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for sc in scenes {
        let in_scene: Vec<&Row> = owned.iter().filter(|r| r.scene == sc).collect();
        let mut groups: Vec<String> = Vec::new();
        for r in &in_scene {
            let k = key(&owned, r, &[col_name]) + &r.positional_samples.to_string();
            if !groups.contains(&k) {
                groups.push(k);
            }
        }
        for (gi, g) in groups.iter().enumerate() {
            if gi == 0 {
                let reference = load_png(&out.join(format!("images/{sc}-reference.png")))?;
                let rc = sweep
                    .iter()
                    .filter(|s| {
                        s.scene == sc && s.backend == Backend::Cpu && s.rms_image == Some(0.0)
                    })
                    .max_by_key(|s| s.rays_per_point);
                let mut cap = vec![format!("{sc}: ray cast (reference)")];
                if let Some(s) = rc {
                    cap.push(format!("{} rays, {:.3} s", s.rays_per_point, s.raycast_s));
                }
                cells.push((reference, cap));
                diffs.push((blank.clone(), vec![format!("{sc}: differences × 5")]));
            } else {
                cells.push((blank.clone(), vec![]));
                diffs.push((blank.clone(), vec![]));
            }
            for col in &columns {
                let r = in_scene.iter().find(|r| {
                    &(key(&owned, r, &[col_name]) + &r.positional_samples.to_string()) == g
                        && &col_fn(r) == col
                });
                let Some(r) = r else {
                    cells.push((blank.clone(), vec![]));
                    diffs.push((blank.clone(), vec![]));
                    continue;
                };
                let varying = key(&owned, r, &["scene", "res"]);
                let name = if varying == "field" {
                    format!("{} × {}²", r.positional_samples, r.directional_res)
                } else {
                    format!(
                        "{} × {}² {varying}",
                        r.positional_samples, r.directional_res
                    )
                };
                let bake = r.bake_s.map_or("-".into(), |b| format!("{b:.2} s"));
                let rms = m(r).map_or("-".into(), |v| format!("{v:.3}"));
                cells.push((
                    load_png(&out.join(&r.image))?,
                    vec![
                        name.clone(),
                        format!("bake {bake}, lookup {:.3} s", r.estimate_s),
                        format!(
                            "RMS {rms}, {:.1} MiB",
                            r.field_bytes as f64 / (1u64 << 20) as f64
                        ),
                    ],
                ));
                let diff = out.join(r.image.replace(".png", "-diff_x5.png"));
                let share = r.share_pixels_off_1.unwrap_or(0.0) * 100.0;
                diffs.push((
                    load_png(&diff)?,
                    vec![
                        name,
                        format!("RMS {rms}, max {:.0}", r.max_error_image.unwrap_or(0.0)),
                        format!("{share:.1}% off by > 1/255"),
                    ],
                ));
            }
        }
    }
    let ncol = columns.len() + 1;
    let refs: Vec<(&GrayImage, Vec<String>)> = cells.iter().map(|(i, c)| (i, c.clone())).collect();
    image_grid(&out.join("images.png"), title, &refs, ncol)?;
    let refs: Vec<(&GrayImage, Vec<String>)> = diffs.iter().map(|(i, c)| (i, c.clone())).collect();
    image_grid(
        &out.join("differences.png"),
        &format!("{title}: |field − reference| × 5"),
        &refs,
        ncol,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_down_averages_blocks_and_drops_partial_ones() {
        // 5 × 2 pixels, factor 2: two full 2 × 2 blocks, the fifth column dropped.
        let img = GrayImage {
            width: 5,
            height: 2,
            data: vec![0.0, 1.0, 0.5, 0.5, 0.9, 1.0, 0.0, 0.5, 0.5, 0.9],
        };
        let d = box_down(&img, 2);
        assert_eq!((d.width, d.height), (2, 1));
        assert_eq!(d.data, vec![0.5, 0.5]);
        assert_eq!(box_down(&img, 1), img);
    }
}
