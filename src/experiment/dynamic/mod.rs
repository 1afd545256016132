//! `experiment dynamic`: rigid casters moving every frame, the papers' premise ("dynamic scenes
//! composed of rigid, non-penetrating objects", 2008 and 2010 abstracts), measured per frame
//! with what motion costs each method (`results/dynamic/`).
//!
//! The crowd: N rigid casters (N = 1, 4, 16, … from the profile) over a receiver plane, one per
//! cell of a √N × √N grid, each orbiting its cell's centre and tumbling about its own seeded
//! axis, the meshes taken in turn from the profile's list. Every frame, every method answers
//! vertex AO at the plane's vertices on the same seeded rays ([`crowd::Crowd`]):
//! - `world_rebuild`: our ray caster with its world-space BVH over every caster's triangles
//!   rebuilt (the triangles moved and the CWBVH built: `update_s`), the reference every other
//!   method's same-ray error is measured against;
//! - `two_level`: our ray caster in two levels ([`crate::trace::two_level`]): each mesh's BVH
//!   built once in model space (before the frames, not timed per frame), the top level over
//!   the instances rebuilt per frame (`update_s`), rays moved into each instance's space;
//! - `embree_rebuild` (with `--features embree`): Embree's scene over the moved triangles built
//!   and committed per frame;
//! - `embree_instances` (the same): Embree with instance geometries
//!   (`trace::embree_instances`): one scene per mesh built once, the instances'
//!   transforms set and the top scene committed per frame;
//! - `field_every_sphere`: the casters' fields (one per mesh, baked once, shared by its
//!   instances) placed by the frame's transforms, every ray testing every caster's sphere
//!   (`update_s` is making the instance list);
//! - `field`: the same with the BVH over the casters' bounding spheres
//!   ([`crate::field::sphere_bvh`]) rebuilt per frame (in `update_s`); the same answers;
//! - `sdf`: the per-object peer engines use, mesh signed distance fields ([`crate::sdf`], one
//!   f32 volume per mesh, shared by its instances) placed by the frame's transforms and sphere
//!   traced on the same rays;
//! - `aofield`: ambient occlusion fields (Kontkanen and Laine 2005, [`crate::aofield`], one per
//!   mesh) placed likewise, AO with no rays.
//!
//! Each row is one (N, frame, method): `update_s` (what the motion costs), `query_s` (the AO
//! pass, all threads), `frame_s` = both, Mrays/s, `rms_vs_raycast` (0–255, unquantised, against
//! `world_rebuild` on the same rays), `rms_vs_truth` (against the frame's converged reference,
//! cached by frame: its key covers the frame's world triangles), and the frame's overlap
//! counts: caster pairs whose bounding spheres overlap and receiver points inside a caster's
//! sphere (where the papers' non-penetrating assumption no longer holds). `frame_time.png` plots the mean frame time
//! against N per method.
//!
//! The approach: one caster lowered onto the middle of the plane frame by frame, its bounding
//! sphere's gap to the plane going from above it to cutting it (`gap_radii`, in sphere radii;
//! `mesh_clearance`, the mesh's own lowest point): the error against the gap, where the
//! papers' non-penetrating assumption stops holding (`error_vs_gap.png`).
//!
//! `crowd.png` and `approach.png` are animated PNGs of the plane seen from above, frame by frame:
//! the ray-cast reference, the field and their difference ×5 ([`animation`]).

pub mod animation;
pub mod crowd;

use super::fields::FieldSupply;
use super::plot::{distinct, sorted_distinct, xy_plot, Axes, Series};
use super::staging;
use super::{Error, Result};
use std::path::Path;

/// One method on one frame of one crowd (its view: [`super::frame_row::DYNAMIC_CSV`]).
pub use super::frame_row::FrameRow;

/// Runs the crowd sweep into `out` (`sweep_frames.csv`, `run.json`, `frame_time.png`, …), written in
/// a staging folder beside it and published only when whole, as a spec's run is
/// (`super::staging`): a file at `out`, or a folder that holds files no run wrote, is
/// refused before any work unless `allow_nonempty_out` (the folder's files are then kept).
pub fn run(
    out: &Path,
    quick: bool,
    supply: &FieldSupply,
    allow_nonempty_out: bool,
) -> Result<Vec<FrameRow>> {
    staging::check_ownership(out, allow_nonempty_out)?;
    super::progress::begin_run();
    let profile = crowd::Profile::new(quick);
    super::models_cmd::require("dynamic", profile.registered())?;
    staging::staged(out, |dir| write(dir, &profile, quick, supply))
}

/// The sweep's outputs, written into `out` (the staging folder).
fn write(
    out: &Path,
    profile: &crowd::Profile,
    quick: bool,
    supply: &FieldSupply,
) -> Result<Vec<FrameRow>> {
    let mut rows = Vec::new();
    let cache = supply.cache.as_deref();
    for &n in &profile.counts {
        let crowd = crowd::Crowd::new(profile, n, supply)?;
        let (r, pictures) = crowd.frames(profile, cache)?;
        rows.extend(r);
        animation::write(
            &out.join("crowd.png"),
            &pictures,
            (crowd.plane_side, crowd.plane_side),
            250,
        )?;
    }
    let approach = crowd::Crowd::approach(profile, supply, profile.gaps.clone())?;
    let (r, pictures) = approach.frames(profile, cache)?;
    rows.extend(r);
    animation::write(
        &out.join("approach.png"),
        &pictures,
        (approach.plane_side, approach.plane_side),
        500,
    )?;
    super::frame_row::DYNAMIC_CSV.write(&out.join(super::outputs::SWEEP_FRAMES_CSV), &rows)?;
    let crowd_rows: Vec<FrameRow> = rows
        .iter()
        .filter(|r| r.scene == "crowd")
        .cloned()
        .collect();
    plot_frame_time(&out.join("frame_time.png"), &crowd_rows)?;
    plot_approach(&out.join("error_vs_gap.png"), &rows)?;
    plot_flicker(&out.join("flicker_vs_casters.png"), &crowd_rows)?;
    let meta = super::meta::RunMeta::collect(None).timed();
    let summary = serde_json::json!({
        "experiment": "dynamic",
        "profile": if quick { "quick" } else { "full" },
        "meta": meta,
        "crowd": profile.describe(),
        "field": crowd::field_label(profile),
        "rows": rows.len(),
    });
    let p = out.join("run.json");
    let json = serde_json::to_string_pretty(&summary).expect("run summary serialises");
    crate::io::write_atomic(&p, json.as_bytes()).map_err(Error::io(&p))?;
    Ok(rows)
}

/// The approach: each method's error against the gap, on the same rays and against the truth.
fn plot_approach(path: &Path, rows: &[FrameRow]) -> Result<()> {
    // One method's column against the gap.
    let pick = |m: &str, f: fn(&FrameRow) -> f64| -> Vec<(f64, f64)> {
        (rows.iter())
            .filter(|r| r.scene == "approach" && r.method == m)
            .map(|r| (r.gap_radii.unwrap_or(f64::NAN), f(r)))
            .collect()
    };
    let series = [
        Series::line(
            "field: RMS against ray casting, same rays",
            pick("field", |r| r.rms_vs_raycast),
        ),
        Series::line(
            "field: RMS against the converged reference",
            pick("field", |r| r.rms_vs_truth),
        ),
        Series::line(
            "ray casting: RMS against the converged reference",
            pick("world_rebuild", |r| r.rms_vs_truth),
        ),
    ];
    let axes = Axes::new(
        "a caster lowered onto the receiver: error against the gap",
        "gap between the caster's bounding sphere and the plane (sphere radii)",
        "RMS (0-255)",
    );
    xy_plot(path, &axes, &series, &[])
}

/// Mean flicker over the frame pairs against the caster count, one line per method
/// (`world_rebuild`'s is the same-ray ray cast's).
fn plot_flicker(path: &Path, rows: &[FrameRow]) -> Result<()> {
    let methods = distinct(rows.iter().map(|r| r.method.as_str()));
    let series = mean_against_count(rows, &methods, |r| r.flicker);
    if series.is_empty() {
        return Ok(());
    }
    let axes = Axes::new(
        "moving casters: flicker (change minus the converged reference's) against their count",
        "casters",
        "flicker: RMS (0-255), mean over frame pairs",
    )
    .log_x();
    xy_plot(path, &axes, &series, &[])
}

/// Mean frame time against the caster count, one line per method.
fn plot_frame_time(path: &Path, rows: &[FrameRow]) -> Result<()> {
    let methods = sorted_distinct(rows.iter().map(|r| r.method.as_str()));
    let series = mean_against_count(rows, &methods, |r| Some(r.frame_s));
    let axes = Axes::new(
        "moving casters: frame time (update + vertex AO) against their count",
        "casters",
        "frame time (s), mean over frames",
    )
    .log_x()
    .log_y();
    xy_plot(path, &axes, &series, &[])
}

/// One line per method of `methods`: per caster count (in row order), the mean of `of` over
/// its rows that have a value; counts without one, and methods without any, left out.
fn mean_against_count(
    rows: &[FrameRow],
    methods: &[&str],
    of: impl Fn(&FrameRow) -> Option<f64>,
) -> Vec<Series> {
    (methods.iter())
        .map(|&m| {
            let mut counts: Vec<usize> = Vec::new();
            for n in rows
                .iter()
                .filter(|r| r.method == m)
                .filter_map(|r| r.casters)
            {
                if !counts.contains(&n) {
                    counts.push(n);
                }
            }
            let points = counts
                .iter()
                .filter_map(|&n| {
                    let v: Vec<f64> = (rows.iter())
                        .filter(|r| r.method == m && r.casters == Some(n))
                        .filter_map(&of)
                        .collect();
                    (!v.is_empty()).then(|| (n as f64, v.iter().sum::<f64>() / v.len() as f64))
                })
                .collect();
            Series::line(m, points)
        })
        .filter(|s: &Series| !s.points.is_empty())
        .collect()
}
