//! One row per (moving scene, frame, per-frame method): what a frame's motion cost the method
//! and how its answer compares, the one record of an animated spec's `frames.csv`
//! (`experiment::run::frames`) and of `experiment dynamic`'s `sweep_frames.csv`
//! (`experiment::dynamic`). The two files are views of it ([`FrameView`]: [`FRAMES_CSV`],
//! [`DYNAMIC_CSV`]), each its own columns in its own order under its own names, written with
//! the bytes serde gives the row ([`crate::experiment::columns::of_serialized`]); a column of
//! one view that the other's runs cannot fill is an `Option`, empty in their rows. Either file
//! reads back into it by header name (`sweep` as `scene`, `mean_ao` as `mean_value`).

use super::columns::{self, NamedRow};
use super::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One per-frame method on one frame of one moving scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRow {
    /// The moving scene: an animated spec's scene; `experiment dynamic`'s sweep, `crowd` (of
    /// [`Self::casters`] casters) or `approach` (one caster lowered onto the plane), its
    /// column `sweep`.
    #[serde(alias = "sweep")]
    pub scene: String,
    pub frame: usize,
    /// The frame's time, `frame × animation.time_step` (seconds); an animated spec's.
    #[serde(default)]
    pub time_s: Option<f64>,
    /// `world_rebuild` (the reference), `two_level`, `embree_rebuild`, `embree_instances`,
    /// `field_every_sphere`, `field`, their GPU twins (`field@gpu`, …), and `experiment
    /// dynamic`'s per-object peers `sdf`, `aofield`.
    pub method: String,
    /// The field cell of a field method (`Cell::id`); empty for the ray casters and in
    /// `experiment dynamic`'s rows (one field shape, named in its run.json).
    #[serde(default)]
    pub cell: String,
    /// Evaluation points this frame.
    #[serde(default)]
    pub points: usize,
    /// Those touching another surface (an animated spec's; none where not counted).
    #[serde(default)]
    pub crease_points: Option<usize>,
    /// Rays of one evaluation: points × the kind's rays per point.
    pub rays: u64,
    pub caster_triangles: usize,
    /// The frame's points (the kind's setup on the moved scene, with its G-buffer where there
    /// is an image), the same for every method and in no method's `frame_s`; an animated
    /// spec's.
    #[serde(default)]
    pub points_s: Option<f64>,
    /// What the frame's motion costs the method (seconds): a BVH rebuilt, a top level
    /// rebuilt, a scene committed, an instance list.
    pub update_s: f64,
    /// The kind's estimate on the frame's rays (seconds, all threads).
    pub query_s: f64,
    pub frame_s: f64,
    /// rays / query_s, millions.
    pub mrays_s: f64,
    /// RMS over the points (0–255, unquantised) against `world_rebuild` on the same rays.
    pub rms_vs_raycast: f64,
    /// RMS over the points (0–255, unquantised) against the frame's converged reference.
    pub rms_vs_truth: f64,
    /// The converged reference's RMS standard error (0–255): the floor of `rms_vs_truth`.
    pub truth_stderr: f64,
    /// Mean value over the points (the answer's size, for reading the RMS); `experiment
    /// dynamic`'s column `mean_ao`.
    #[serde(alias = "mean_ao")]
    pub mean_value: f64,
    /// Bytes the method keeps for the scene, where it can say.
    pub bytes: Option<u64>,
    /// Caster pairs whose world bounding spheres overlap this frame.
    pub sphere_overlaps: usize,
    /// Points inside the bounding sphere of a caster other than their own instance.
    pub points_in_spheres: usize,
    /// Mean FLIP ([`crate::experiment::flip`]: 0–1, 67 pixels per degree) of the method's
    /// image against `world_rebuild`'s on the same rays, over the pixels that show values;
    /// none without an image (and in tables written before the column).
    #[serde(default)]
    pub flip_mean_vs_raycast: Option<f64>,
    /// The FLIP pooling's weighted median of the same map.
    #[serde(default)]
    pub flip_weighted_median_vs_raycast: Option<f64>,
    /// Mean FLIP against the frame's converged reference's image.
    #[serde(default)]
    pub flip_mean_vs_truth: Option<f64>,
    /// Its weighted median.
    #[serde(default)]
    pub flip_weighted_median_vs_truth: Option<f64>,
    /// Flicker from the previous frame ([`crate::experiment::metrics::flicker`], 0–255,
    /// unquantised): the RMS of the method's frame-to-frame change minus the converged
    /// reference's, over the pixels that show values on the same instance in both frames
    /// (the camera is fixed), or without an image over the points (the same points in both
    /// frames); none on the first frame.
    #[serde(default)]
    pub flicker: Option<f64>,
    /// The same of `world_rebuild` (the same-ray ray cast) on the same frame pair.
    #[serde(default)]
    pub raycast_flicker: Option<f64>,
    /// Pixels (or points) the flicker is taken over (an animated spec's).
    #[serde(default)]
    pub flicker_points: Option<usize>,
    /// Mean FLIP of the method's image at this frame against its image at the previous one,
    /// over the flicker's pixels; none on the first frame and without an image.
    #[serde(default)]
    pub flip_frame_change: Option<f64>,
    /// The same of the converged reference's images: the change the motion itself shows.
    #[serde(default)]
    pub truth_flip_frame_change: Option<f64>,
    /// `experiment dynamic`'s approach: the gap between the caster's sphere and the plane, in
    /// sphere radii (negative: the sphere cuts the plane).
    #[serde(default)]
    pub gap_radii: Option<f64>,
    /// The approach: the moved mesh's lowest point over the plane, in sphere radii (negative:
    /// the mesh goes through it).
    #[serde(default)]
    pub mesh_clearance: Option<f64>,
    /// `experiment dynamic`'s casters in the scene.
    #[serde(default)]
    pub casters: Option<usize>,
}

/// A file's view of [`FrameRow`]: its columns in order, each (its name in the file, the
/// row's field).
pub struct FrameView(pub &'static [(&'static str, &'static str)]);

/// An animated spec's `frames.csv`.
pub const FRAMES_CSV: FrameView = FrameView(&[
    ("scene", "scene"),
    ("frame", "frame"),
    ("time_s", "time_s"),
    ("method", "method"),
    ("cell", "cell"),
    ("points", "points"),
    ("crease_points", "crease_points"),
    ("rays", "rays"),
    ("caster_triangles", "caster_triangles"),
    ("points_s", "points_s"),
    ("update_s", "update_s"),
    ("query_s", "query_s"),
    ("frame_s", "frame_s"),
    ("mrays_s", "mrays_s"),
    ("rms_vs_raycast", "rms_vs_raycast"),
    ("rms_vs_truth", "rms_vs_truth"),
    ("truth_stderr", "truth_stderr"),
    ("mean_value", "mean_value"),
    ("bytes", "bytes"),
    ("sphere_overlaps", "sphere_overlaps"),
    ("points_in_spheres", "points_in_spheres"),
    ("flip_mean_vs_raycast", "flip_mean_vs_raycast"),
    (
        "flip_weighted_median_vs_raycast",
        "flip_weighted_median_vs_raycast",
    ),
    ("flip_mean_vs_truth", "flip_mean_vs_truth"),
    (
        "flip_weighted_median_vs_truth",
        "flip_weighted_median_vs_truth",
    ),
    ("flicker", "flicker"),
    ("raycast_flicker", "raycast_flicker"),
    ("flicker_points", "flicker_points"),
    ("flip_frame_change", "flip_frame_change"),
    ("truth_flip_frame_change", "truth_flip_frame_change"),
]);

/// `experiment dynamic`'s `sweep_frames.csv`.
pub const DYNAMIC_CSV: FrameView = FrameView(&[
    ("sweep", "scene"),
    ("gap_radii", "gap_radii"),
    ("mesh_clearance", "mesh_clearance"),
    ("casters", "casters"),
    ("caster_triangles", "caster_triangles"),
    ("frame", "frame"),
    ("method", "method"),
    ("update_s", "update_s"),
    ("query_s", "query_s"),
    ("frame_s", "frame_s"),
    ("rays", "rays"),
    ("mrays_s", "mrays_s"),
    ("rms_vs_raycast", "rms_vs_raycast"),
    ("rms_vs_truth", "rms_vs_truth"),
    ("truth_stderr", "truth_stderr"),
    ("mean_ao", "mean_value"),
    ("bytes", "bytes"),
    ("sphere_overlaps", "sphere_overlaps"),
    ("points_in_spheres", "points_in_spheres"),
    ("flicker", "flicker"),
    ("raycast_flicker", "raycast_flicker"),
]);

impl FrameView {
    /// The header.
    pub fn names(&self) -> Vec<&'static str> {
        self.0.iter().map(|c| c.0).collect()
    }

    /// `row`'s columns of this view, in order, each as serde writes the field.
    pub fn named(&self, row: &FrameRow) -> NamedRow {
        let all = columns::of_serialized(row);
        let mut out = NamedRow::new();
        for &(name, field) in self.0 {
            let v = all
                .get(field)
                .unwrap_or_else(|| panic!("FrameRow has no field `{field}`"));
            out.push(name, v);
        }
        out
    }

    /// Writes `rows` as this view's CSV (the header alone without rows), atomically.
    pub fn write(&self, path: &Path, rows: &[FrameRow]) -> Result<()> {
        let named: Vec<NamedRow> = rows.iter().map(|r| self.named(r)).collect();
        columns::write_csv_with(path, &self.names(), &named)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row() -> FrameRow {
        FrameRow {
            scene: "crowd".into(),
            frame: 2,
            time_s: Some(0.5),
            method: "field".into(),
            cell: "c".into(),
            points: 4,
            crease_points: Some(1),
            rays: 64,
            caster_triangles: 10,
            points_s: Some(0.25),
            update_s: 0.0,
            query_s: 1.5,
            frame_s: 1.5,
            mrays_s: 3.0,
            rms_vs_raycast: 1.0,
            rms_vs_truth: 2.0,
            truth_stderr: 0.1,
            mean_value: 0.75,
            bytes: None,
            sphere_overlaps: 0,
            points_in_spheres: 3,
            flip_mean_vs_raycast: None,
            flip_weighted_median_vs_raycast: None,
            flip_mean_vs_truth: Some(0.2),
            flip_weighted_median_vs_truth: None,
            flicker: Some(0.3),
            raycast_flicker: None,
            flicker_points: Some(4),
            flip_frame_change: None,
            truth_flip_frame_change: None,
            gap_radii: Some(-0.5),
            mesh_clearance: None,
            casters: Some(16),
        }
    }

    #[test]
    fn every_field_is_in_a_view_and_every_view_names_fields() {
        let all = columns::of_serialized(&row());
        let fields: Vec<&str> = all.columns().map(|c| c.0).collect();
        for view in [&FRAMES_CSV, &DYNAMIC_CSV] {
            for &(_, f) in view.0 {
                assert!(fields.contains(&f), "{f}");
            }
        }
        for f in fields {
            assert!(
                [&FRAMES_CSV, &DYNAMIC_CSV]
                    .iter()
                    .any(|v| v.0.iter().any(|c| c.1 == f)),
                "field {f} is in no view"
            );
        }
    }

    #[test]
    fn each_view_reads_back_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let r = row();
        for (view, keep) in [
            (&FRAMES_CSV, "frames.csv"),
            (&DYNAMIC_CSV, "sweep_frames.csv"),
        ] {
            let p = dir.path().join(keep);
            view.write(&p, std::slice::from_ref(&r)).unwrap();
            let text = std::fs::read_to_string(&p).unwrap();
            assert_eq!(text.lines().next().unwrap(), view.names().join(","));
            let back: Vec<FrameRow> = crate::experiment::outputs::read_csv(&p).unwrap();
            for &(_, field) in view.0 {
                let (a, b) = (columns::of_serialized(&back[0]), columns::of_serialized(&r));
                assert_eq!(a.get(field), b.get(field), "{keep}: {field}");
            }
        }
        assert_eq!(
            FRAMES_CSV.named(&r).get("mean_value"),
            DYNAMIC_CSV.named(&r).get("mean_ao")
        );
        assert_eq!(DYNAMIC_CSV.named(&r).get("sweep"), Some("crowd"));
    }
}
