//! The relief experiment's plots and image grids, among them the paper's quality figures
//! (Kolb and Rezk-Salama, VMV 2005, Figures 10 and 12: samples per unit and bisections side by
//! side) with skips added and difference images against the exact intersection.

use super::{ReliefRow, QUALITY_ANGLE, QUALITY_DATASETS};
use crate::experiment::plot::{distinct, image_grid, xy_plot, Axes, Series};
use crate::experiment::Result;
use crate::relief::view::{render, View};
use crate::relief::{CastParams, Dataset, SafetyZones, PAPER_BOXES};
use crate::render::image::GrayImage;
use std::path::Path;

/// Difference images are scaled by this (a shading difference of ¼ shows white).
const DIFFERENCE_GAIN: f32 = 4.0;

/// Draws `series` against the viewing angle to `path`, titled `title`, `y` on the y axis.
fn angle_plot(path: &Path, title: &str, y: &str, series: &[Series]) -> Result<()> {
    let axes = Axes::new(title, "viewing angle from the normal (degrees)", y);
    xy_plot(path, &axes, series, &[])
}

/// `f` against the viewing angle over the `angles` table's rows of map `d` at `skips` and δ
/// `rule`.
fn at_angles(
    rows: &[ReliefRow],
    d: Dataset,
    skips: u32,
    rule: &str,
    f: &dyn Fn(&ReliefRow) -> f64,
) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| {
            r.table == "angles" && r.delta_rule == rule && r.dataset == d.name() && r.skips == skips
        })
        .map(|r| (r.view_deg as f64, f(r)))
        .collect()
}

/// One series per map and skip count over the `angles` table (paper's δ).
fn by_angle(rows: &[ReliefRow], skips: &[u32], f: &dyn Fn(&ReliefRow) -> f64) -> Vec<Series> {
    let mut s = Vec::new();
    for d in Dataset::ALL {
        for &k in skips {
            let label = format!("{} · {k} skip(s)", d.name());
            s.push(Series::line(label, at_angles(rows, d, k, "paper", f)));
        }
    }
    s
}

/// The plots of `renderings.csv`'s rows; `size` is the image side.
pub fn plots(out: &Path, rows: &[ReliefRow], size: u32) -> Result<()> {
    angle_plot(
        &out.join("fetches_vs_angle.png"),
        "Fetches per pixel whose ray meets the surface (75 samples/unit, 2 bisections, paper's δ)",
        "mean fetches over surface pixels",
        &by_angle(rows, &[0, 1, 2], &|r| r.surface_fetches),
    )?;
    let mut gains = Vec::new();
    for rule in ["paper", "half"] {
        for d in Dataset::ALL {
            let points = at_angles(rows, d, 2, rule, &|r| r.surface_fetch_reduction);
            gains.push(Series::line(
                format!("{} · 2 skips · δ {rule}", d.name()),
                points,
            ));
        }
    }
    angle_plot(
        &out.join("fetch_gain_vs_angle.png"),
        "Fetch reduction from 2 skips over surface pixels: paper's δ and half of it",
        "fetches without skips / with",
        &gains,
    )?;
    angle_plot(
        &out.join("time_vs_angle.png"),
        &format!("CPU time per {size}² frame (all pixels)"),
        "seconds",
        &by_angle(rows, &[0, 1, 2], &|r| r.time_s),
    )?;
    angle_plot(
        &out.join("missed_vs_angle.png"),
        "Surface pixels missed or > 2 texels off (75 samples/unit, 2 bisections)",
        "share of surface pixels",
        &by_angle(rows, &[0, 2], &|r| r.missed_share),
    )?;
    let mut missed = Vec::new();
    for d in QUALITY_DATASETS {
        for k in [0u32, 2] {
            let points = rows
                .iter()
                .filter(|r| r.table == "quality" && r.dataset == d.name() && r.skips == k)
                .map(|r| (r.samples_per_unit as f64, r.missed_share))
                .collect();
            missed.push(Series::line(format!("{} · {k} skip(s)", d.name()), points));
        }
    }
    xy_plot(
        &out.join("missed_vs_rate.png"),
        &Axes::new(
            format!("Surface pixels missed or > 2 texels off at {QUALITY_ANGLE}° (2 bisections)"),
            "samples per unit length",
            "share of surface pixels",
        )
        .log_x(),
        &missed,
        &[],
    )?;
    gpu_plot(out, rows, size)?;
    let pareto: Vec<Series> = (0..=2u32)
        .map(|skips| {
            let points = rows
                .iter()
                .filter(|r| r.table == "rates" && r.skips == skips)
                .map(|r| (r.time_s, r.rms_vs_exact))
                .collect();
            Series::scatter(format!("relief 45° close-up · {skips} skip(s)"), points)
        })
        .collect();
    xy_plot(
        &out.join("pareto.png"),
        &Axes::new(
            "Error against time (Table 3's settings; RMS vs the exact intersection)",
            "seconds per frame",
            "RMS (0–255)",
        )
        .log_x(),
        &pareto,
        &[],
    )?;
    methods_plots(out, rows)
}

/// Every method's error against its fetches and its time, over the `angles` table's maps at
/// the grazing views (45°–75°): the paper's search (paper's δ, 0–2 skips) and the peers.
fn methods_plots(out: &Path, rows: &[ReliefRow]) -> Result<()> {
    let of = |r: &ReliefRow| {
        if r.method == super::METHOD {
            (r.delta_rule == "paper").then(|| format!("paper · {} skip(s)", r.skips))
        } else {
            Some(r.method.to_string())
        }
    };
    let picked: Vec<(String, &ReliefRow)> = rows
        .iter()
        .filter(|r| r.table == "angles" && r.view_deg >= 45.0)
        .filter_map(|r| of(r).map(|m| (m, r)))
        .collect();
    let names = distinct(picked.iter().map(|(m, _)| m));
    let series = |x: &dyn Fn(&ReliefRow) -> f64| -> Vec<Series> {
        let points = |n: &String| {
            let of_n = picked.iter().filter(|(m, _)| m == n);
            of_n.map(|(_, r)| (x(r), r.rms_vs_exact)).collect()
        };
        names
            .iter()
            .map(|&n| Series::scatter(n.clone(), points(n)))
            .collect()
    };
    let axes = |x: &str| {
        Axes::new(
            "Every method on every map at 45°, 60° and 75° (75 samples/unit for the paper's search)",
            x,
            "RMS vs the exact intersection (0–255)",
        )
        .log_x()
    };
    if names.is_empty() {
        return Ok(());
    }
    xy_plot(
        &out.join("methods_error_vs_fetches.png"),
        &axes("mean fetches per surface pixel"),
        &series(&|r| r.surface_fetches),
        &[],
    )?;
    xy_plot(
        &out.join("methods_error_vs_time.png"),
        &axes("CPU seconds per frame"),
        &series(&|r| r.time_s),
        &[],
    )
}

/// GPU kernel time against angle, where every `angles` row has one.
fn gpu_plot(out: &Path, rows: &[ReliefRow], size: u32) -> Result<()> {
    let angle_rows = rows.iter().filter(|r| r.table == "angles");
    let Some(adapter) = angle_rows.clone().find_map(|r| r.gpu_adapter.as_deref()) else {
        return Ok(());
    };
    if !angle_rows.clone().all(|r| r.gpu_kernel_s.is_some()) {
        return Ok(());
    }
    let name = adapter.split(" | ").next().unwrap_or(adapter);
    let note = if name.contains("llvmpipe") {
        ": a CPU, parity not speed"
    } else {
        ""
    };
    angle_plot(
        &out.join("gpu_time_vs_angle.png"),
        &format!("GPU kernel time per {size}² frame ({name}{note})"),
        "seconds",
        &by_angle(rows, &[0, 1, 2], &|r| r.gpu_kernel_s.unwrap_or(f64::NAN)),
    )
}

/// The exact images at 60°, one per map.
pub fn exact_grid(path: &Path, images: &[(GrayImage, Dataset)]) -> Result<()> {
    let cells: Vec<(&GrayImage, Vec<String>)> = images
        .iter()
        .map(|(i, d)| (i, vec![format!("{} 60°: exact", d.name())]))
        .collect();
    image_grid(path, "exact intersection, 60°", &cells, 3)
}

/// `|a − b|` times [`DIFFERENCE_GAIN`], clamped to 1.
pub fn difference(a: &GrayImage, b: &GrayImage) -> GrayImage {
    GrayImage {
        width: a.width,
        height: a.height,
        data: a
            .data
            .iter()
            .zip(&b.data)
            .map(|(x, y)| ((x - y).abs() * DIFFERENCE_GAIN).min(1.0))
            .collect(),
    }
}

/// The paper's quality figures at [`QUALITY_ANGLE`]: one row per (samples per unit,
/// bisections) of its Figure 12 (`needles`, the whole lid) and Figure 10 (`relief`'s close-up),
/// the exact image, then for 0, 1 and 2 skips the image and its difference from the exact one.
pub fn quality_grids(out: &Path, size: u32) -> Result<()> {
    /// File, map, close-up, (samples per unit, bisections) per row.
    type Figure<'a> = (&'a str, Dataset, bool, &'a [(f32, u32)]);
    let figures: [Figure; 2] = [
        (
            "quality_needles.png",
            Dataset::Needles,
            false,
            &[(10.0, 0), (10.0, 2), (75.0, 2)],
        ),
        (
            "quality_relief.png",
            Dataset::Relief,
            true,
            &[(10.0, 0), (10.0, 2), (40.0, 2), (75.0, 2)],
        ),
    ];
    for (file, dset, close_up, settings) in figures {
        let map = dset.map(super::MAP_RES);
        let zones = SafetyZones::new(&map, &PAPER_BOXES);
        let view = if close_up {
            View::close_up(QUALITY_ANGLE, size)
        } else {
            View::lid(QUALITY_ANGLE, size)
        };
        let exact = render(&map, None, &view, None).image;
        let mut cells: Vec<(GrayImage, Vec<String>)> = Vec::new();
        for &(rate, bisections) in settings {
            cells.push((exact.clone(), vec!["exact".into(), String::new()]));
            for skips in 0..=2 {
                let p = CastParams {
                    samples_per_unit: rate,
                    bisections,
                    skips,
                };
                let image = render(&map, Some(&zones), &view, Some(&p)).image;
                let diff = difference(&image, &exact);
                let label = format!("{rate} samples, {bisections} bisections");
                cells.push((image, vec![label, format!("{skips} skip(s)")]));
                cells.push((
                    diff,
                    vec![format!("|difference| × {DIFFERENCE_GAIN}"), String::new()],
                ));
            }
        }
        let refs: Vec<(&GrayImage, Vec<String>)> =
            cells.iter().map(|(i, c)| (i, c.clone())).collect();
        let what = if close_up { "close-up" } else { "whole lid" };
        image_grid(
            &out.join(file),
            &format!(
                "{} ({what}) {QUALITY_ANGLE}°: samples/unit × skips vs exact",
                dset.name()
            ),
            &refs,
            7,
        )?;
    }
    Ok(())
}
