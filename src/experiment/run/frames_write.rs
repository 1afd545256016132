//! The end of an animated run ([`super::frames`]): `frames.csv`, per scene the frame time and
//! the error against the frame (`frame_time-SCENE.png`, `error-SCENE.png`), the flicker
//! against the frame (`flicker-SCENE.png`), every method, and with an image the mean FLIP
//! against the converged reference and between consecutive frames (`flip-SCENE.png`,
//! `flip_change-SCENE.png`); with an image,
//! the animation of the reference, the first field method and their difference
//! (`animation-SCENE.png`, APNG), `run.json` and the spec copy.

use super::frames::{FrameRow, FramesRun};
use super::{LoadedSpec, RunOptions};
use crate::experiment::plot::{xy_plot, Axes, Series};
use crate::experiment::scenes::Scenes;
use crate::experiment::spec::Spec;
use crate::experiment::Result;
use std::path::Path;

/// Each method's label and its rows of `scene`, in row order; a field method's label names
/// its field cell where the scene has more than one.
fn series_of<'r>(rows: &'r [FrameRow], scene: &str) -> Vec<(String, Vec<&'r FrameRow>)> {
    let rows: Vec<&FrameRow> = rows.iter().filter(|r| r.scene == scene).collect();
    let first_cell = rows.iter().map(|r| &r.cell).find(|c| !c.is_empty());
    let cells = rows
        .iter()
        .any(|r| !r.cell.is_empty() && Some(&r.cell) != first_cell);
    let mut out: Vec<(String, Vec<&FrameRow>)> = Vec::new();
    for r in rows {
        let label = if cells && !r.cell.is_empty() {
            format!("{} {}", r.method, r.cell)
        } else {
            r.method.clone()
        };
        match out.iter_mut().find(|(l, _)| *l == label) {
            Some((_, v)) => v.push(r),
            None => out.push((label, vec![r])),
        }
    }
    out
}

/// Frame time (update + query) against the frame, one line per method.
fn plot_frame_time(path: &Path, rows: &[FrameRow], scene: &str, kind: &str) -> Result<()> {
    let series = per_method(rows, scene, |r| Some(r.frame_s));
    let title = format!("{scene}: frame time (motion update + {kind}) per method");
    xy_plot(
        path,
        &frame_axes(title, "frame time (s)", true),
        &series,
        &[],
    )
}

/// Axes against the frame.
fn frame_axes(title: String, y_label: &str, log_y: bool) -> Axes {
    Axes {
        log_y,
        ..Axes::new(title, "frame", y_label)
    }
}

/// The error against the frame's converged reference per method, and the field methods'
/// error against the world rebuild on the same rays.
fn plot_error(path: &Path, rows: &[FrameRow], scene: &str) -> Result<()> {
    let mut series = Vec::new();
    for (label, rs) in series_of(rows, scene) {
        let against = |f: fn(&FrameRow) -> f64| rs.iter().map(|r| (r.frame as f64, f(r))).collect();
        series.push(Series::line(
            format!("{label}: against the converged reference"),
            against(|r| r.rms_vs_truth),
        ));
        if !rs[0].cell.is_empty() {
            series.push(Series::line(
                format!("{label}: against ray casting, same rays"),
                against(|r| r.rms_vs_raycast),
            ));
        }
    }
    let title = format!("{scene}: error per frame");
    xy_plot(path, &frame_axes(title, "RMS (0-255)", false), &series, &[])
}

/// One line per method of a per-frame column (`of`: none where the row has no value), on
/// the frames that have one; none when no row has one.
fn per_method(
    rows: &[FrameRow],
    scene: &str,
    of: impl Fn(&FrameRow) -> Option<f64>,
) -> Vec<Series> {
    series_of(rows, scene)
        .into_iter()
        .map(|(label, rs)| {
            let points = rs.iter().filter_map(|r| of(r).map(|y| (r.frame as f64, y)));
            Series::line(label, points.collect())
        })
        .filter(|s| !s.points.is_empty())
        .collect()
}

/// Flicker against the frame, every method (`world_rebuild`'s line is the same-ray ray
/// cast's): the spurious frame-to-frame change, against the converged reference's change.
/// Nothing is drawn for a run without the column.
fn plot_flicker(path: &Path, rows: &[FrameRow], scene: &str) -> Result<()> {
    let series = per_method(rows, scene, |r| r.flicker);
    if series.is_empty() {
        return Ok(());
    }
    let title = format!(
        "{scene}: flicker from the previous frame (change minus the converged reference's)"
    );
    xy_plot(
        path,
        &frame_axes(title, "flicker: RMS (0-255)", false),
        &series,
        &[],
    )
}

/// FLIP against the frame's converged reference per method, and between consecutive frames
/// per method beside the converged reference's own frame change. Nothing is drawn for a run
/// without an image.
fn plot_flip(path: &Path, change_path: &Path, rows: &[FrameRow], scene: &str) -> Result<()> {
    let series = per_method(rows, scene, |r| r.flip_mean_vs_truth);
    if series.is_empty() {
        return Ok(());
    }
    let title = format!("{scene}: mean FLIP against the converged reference (67 px/degree)");
    xy_plot(path, &frame_axes(title, "mean FLIP", false), &series, &[])?;
    let mut series = per_method(rows, scene, |r| r.flip_frame_change);
    let truth: Vec<(f64, f64)> = (rows.iter())
        .filter(|r| r.scene == scene && r.method == "world_rebuild")
        .filter_map(|r| r.truth_flip_frame_change.map(|y| (r.frame as f64, y)))
        .collect();
    if !truth.is_empty() {
        series.push(Series::line("converged reference", truth));
    }
    if series.is_empty() {
        return Ok(());
    }
    let title = format!("{scene}: mean FLIP between consecutive frames");
    let axes = frame_axes(title, "mean FLIP, frame against the previous", false);
    xy_plot(change_path, &axes, &series, &[])
}

/// The plots of every scene of `rows` in `dir` (`kind`: the render kind, for the titles).
fn draw(dir: &Path, rows: &[FrameRow], kind: &str) -> Result<()> {
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    for n in scenes {
        plot_frame_time(&dir.join(format!("frame_time-{n}.png")), rows, n, kind)?;
        plot_error(&dir.join(format!("error-{n}.png")), rows, n)?;
        plot_flicker(&dir.join(format!("flicker-{n}.png")), rows, n)?;
        let (flip, change) = (format!("flip-{n}.png"), format!("flip_change-{n}.png"));
        plot_flip(&dir.join(flip), &dir.join(change), rows, n)?;
    }
    Ok(())
}

/// Redraws the plots of the animated run in `dir` from its `frames.csv` (`kind`: its render
/// kind, for the titles).
pub fn redraw(dir: &Path, kind: &str) -> Result<()> {
    let rows: Vec<FrameRow> = crate::experiment::outputs::read_csv(&dir.join("frames.csv"))?;
    draw(dir, &rows, kind)
}

/// Writes every output of an animated run into `opts.out`.
pub(super) fn write(
    ls: &LoadedSpec,
    spec: &Spec,
    scenes: &Scenes,
    opts: &RunOptions,
    run: &FramesRun,
) -> Result<()> {
    let out = &opts.out;
    crate::experiment::frame_row::FRAMES_CSV.write(&out.join("frames.csv"), &run.rows)?;
    let kind = crate::experiment::kinds::of(&spec.render);
    draw(out, &run.rows, kind.name())?;
    for (name, size, frames) in &run.pictures {
        let p = out.join(format!("animation-{name}.png"));
        crate::experiment::dynamic::animation::write(&p, frames, *size, 250)?;
    }
    let scene_info: Vec<_> = scenes
        .scenes
        .iter()
        .map(|bs| {
            serde_json::json!({
                "name": bs.name,
                "instances": bs.scene.instances.len(),
                "frames": bs.frame_count(),
                "caster_triangles": bs.caster_triangles(),
                "origin": bs.origin,
            })
        })
        .collect();
    let meshes = super::write::meshes_json(scenes);
    let mut meta = crate::experiment::meta::RunMeta::collect(Some(&ls.text)).timed();
    // The adapter of the GPU rows, where the spec has the "gpu" backend (each scene's
    // precompute names it too).
    meta.gpu_adapter = run
        .precompute
        .iter()
        .find_map(|p| p["gpu_adapter"].as_str().map(String::from));
    let summary = serde_json::json!({
        "spec": ls.name,
        "spec_file": crate::experiment::meta::portable_path(&ls.path),
        "reproduces": spec.reproduces,
        "profile": if opts.quick { "quick" } else { "full" },
        "meta": meta,
        "render": kind.name(),
        "quantity": kind.answers().quantity(),
        "rays_per_point": spec.render.rays_per_point,
        "seed": spec.reference.seed,
        "truth": spec.reference.truth,
        "flip": crate::experiment::flip::metadata(),
        "animation": spec.animation,
        "methods": run.methods,
        "skipped_methods": run
            .skipped
            .iter()
            .map(|(m, why)| serde_json::json!({"method": m, "why": why}))
            .collect::<Vec<_>>(),
        "precompute": run.precompute,
        "timing": "each method's update and query timed once per frame, all threads",
        "cache": opts.supply.cache.as_deref().map(crate::experiment::meta::portable_path),
        "scenes": scene_info,
        "meshes": meshes,
        "effective_spec": spec,
    });
    super::write::write_summary(out, &summary, ls)
}
