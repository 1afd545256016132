//! The tables a run writes (CSV, atomically) and reads back for `experiment plots`:
//!
//! - `table.csv`: one [`Row`] per cell and backend;
//! - `raycast_sweep.csv`: ray-cast AO at several ray counts ([`SweepRow`]), the ray-casting
//!   curve of the error-against-time plot;
//! - `field_sweep.csv`: field lookup of every cell at more ray counts ([`FieldSweepRow`]),
//!   against the converged reference;
//! - `pairs.csv`: RMS between cells that differ only in precision ([`PairRow`]; the slides'
//!   8 vs 16 bit);
//! - `paper_vs_ours.csv`: the paper's numbers beside ours, written by [`super::paper`].

use super::spec::Backend;
use super::{Error, Result};
use crate::field::{Precision, Selection};
use crate::sampling::{LayoutKind, SphereKind};
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::path::Path;

/// One cell on one backend. The first 15 columns are the table's contract; the rest add
/// context. Times in seconds, RMS and errors on the 0–255 scale (see [`super::metrics`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub positional_samples: usize,
    pub directional_res: u32,
    pub layout: LayoutKind,
    pub precision: Precision,
    pub selection: Selection,
    pub backend: Backend,
    /// The device that ran the AO (CPU model and threads, or GPU adapter).
    pub adapter: String,
    /// Preprocessing: the bake of every caster's field (BVH build included); for a derived
    /// precision the f32 bake plus the requantisation; from the bake record on a cache hit.
    pub bake_s: Option<f64>,
    /// Field-lookup AO time (best of 3 when short).
    pub ao_s: f64,
    /// Ray-cast AO time on the same rays and backend.
    pub raycast_s: Option<f64>,
    /// Per receiver vertex RMS against the reference (none for image AO).
    pub rms_vertex: Option<f64>,
    /// Per image pixel RMS against the reference image (none without an image).
    pub rms_image: Option<f64>,
    /// Stored bytes of every caster's field.
    pub field_bytes: u64,
    /// RMS over the AO points (receiver vertices, or pixels for image AO), unquantised, 0–255,
    /// of the field's AO against the converged reference (see [`super::truth_cache`]); mean over
    /// seeds. It includes the reference's own noise: E\[rms²\] = error² + `truth_stderr`².
    #[serde(default)]
    pub rms_vs_truth: Option<f64>,
    /// RMS over points of the converged reference's standard error (0–255): its noise floor.
    #[serde(default)]
    pub truth_stderr: Option<f64>,
    pub scene: String,
    pub sphere: SphereKind,
    pub rays_per_point: u32,
    /// AO points (receiver vertices, or receiver pixels for image AO).
    pub receiver_points: usize,
    pub caster_triangles: usize,
    pub max_error_vertex: Option<f64>,
    pub max_error_image: Option<f64>,
    /// Share of receiver pixels whose 8-bit value differs from the reference by more than 1.
    pub share_pixels_off_1: Option<f64>,
    /// Rays the bakes traced.
    pub bake_rays: u64,
    /// Every field came from the cache.
    pub bake_cached: bool,
    /// The image, relative to the output folder (empty without an image).
    pub image: String,
    /// The cell id.
    pub cell: String,
    /// Field-lookup kernel time from GPU timestamps (best over the timed runs); empty on the
    /// CPU and on adapters without timestamp queries. `ao_s` is the call's wall time
    /// (upload of the receivers, dispatch, wait, read-back).
    #[serde(default)]
    pub ao_kernel_s: Option<f64>,
    /// Ray-cast kernel time from GPU timestamps on the same rays; `raycast_s` is its wall time.
    #[serde(default)]
    pub raycast_kernel_s: Option<f64>,
    /// GPU only: packing and uploading the fields and compiling the kernel, once per cell
    /// (not in `ao_s`); empty on the CPU, which reads the fields in place.
    #[serde(default)]
    pub setup_s: Option<f64>,
    /// Seeds (per-point ray rotations) the RMS columns are averaged over.
    #[serde(default)]
    pub seeds: u32,
    /// Standard deviation over seeds of `rms_vertex`.
    #[serde(default)]
    pub rms_vertex_sd: Option<f64>,
    /// Standard deviation over seeds of `rms_image`.
    #[serde(default)]
    pub rms_image_sd: Option<f64>,
    /// Standard deviation over seeds of `rms_vs_truth`.
    #[serde(default)]
    pub rms_vs_truth_sd: Option<f64>,
    /// The same-ray ray-cast reference against the converged one (mean over seeds): the
    /// error a ray cast with the cell's rays makes.
    #[serde(default)]
    pub raycast_rms_vs_truth: Option<f64>,
    /// Rays per point of the converged reference.
    #[serde(default)]
    pub truth_rays: Option<u32>,
    /// AO points that touch another surface (see `render::contact`).
    #[serde(default)]
    pub crease_points: usize,
    /// `rms_vs_truth` over the crease points only (none without crease points).
    #[serde(default)]
    pub rms_vs_truth_crease: Option<f64>,
    /// `rms_vs_truth` over the other points.
    #[serde(default)]
    pub rms_vs_truth_interior: Option<f64>,
    /// AO points inside some caster's world bounding sphere (where the lookup starts inside a
    /// sphere: the intra-object test, or a receiver the sphere cuts).
    #[serde(default)]
    pub points_in_spheres: Option<usize>,
    /// `rms_vs_truth` over the points inside some caster's sphere (none when there are none).
    #[serde(default)]
    pub rms_vs_truth_in_spheres: Option<f64>,
    /// `rms_vs_truth` over the points outside every caster's sphere.
    #[serde(default)]
    pub rms_vs_truth_outside_spheres: Option<f64>,
    /// RMS over the points outside every caster's sphere (0–255, unquantised, first seed) of
    /// the values against the same-ray reference: the error where the lookup is the papers'
    /// inter-object case.
    #[serde(default)]
    pub rms_outside_spheres: Option<f64>,
    /// RMS over the points of the same-ray reference's occlusion, 255 · (1 − value): the
    /// signal the errors are measured against (a caster that shades little gives small errors
    /// whatever the method; `rms_vertex` or `rms_image` over this compares casters).
    #[serde(default)]
    pub occlusion_rms: Option<f64>,
    /// Graininess of the image's error against the reference image, first seed (see
    /// [`super::metrics::grain`]; none without an image).
    #[serde(default)]
    pub grain: Option<f64>,
    /// Rays of one evaluation: points × rays per point (× lights for shadows; every ray, those
    /// that miss a caster's sphere too, as the 2010 paper counts).
    #[serde(default)]
    pub rays_cast: u64,
    /// Rays per second of the field estimate, millions: `rays_cast` / `ao_s`.
    #[serde(default)]
    pub ao_mrays_s: Option<f64>,
    /// The same for ray casting on the same rays (`raycast_s`).
    #[serde(default)]
    pub raycast_mrays_s: Option<f64>,
    /// Bits per component of the normal field the cell read (reflections; `field_bytes`
    /// includes it); empty for kinds that read none.
    #[serde(default)]
    pub normal_bits: Option<u32>,
    /// The name of the kind's second reference (reflections with a glossy lobe: "mirror");
    /// empty without one.
    #[serde(default)]
    pub second_reference: Option<String>,
    /// RMS per pixel (0–255, as `rms_image`) of the first seed's image against the second
    /// reference's image, ray cast on the same points.
    #[serde(default)]
    pub rms_image_vs_second: Option<f64>,
}

/// The columns `table.csv` starts with, in order.
pub const TABLE_COLUMNS: [&str; 15] = [
    "positional_samples",
    "directional_res",
    "layout",
    "precision",
    "selection",
    "backend",
    "adapter",
    "bake_s",
    "ao_s",
    "raycast_s",
    "rms_vertex",
    "rms_image",
    "field_bytes",
    "rms_vs_truth",
    "truth_stderr",
];

/// A row's identity: the cell, its axes and its scene.
#[derive(Clone, Debug, PartialEq)]
pub struct CellColumns {
    pub cell: String,
    pub scene: String,
    pub sphere: SphereKind,
    pub positional_samples: usize,
    pub directional_res: u32,
    pub layout: LayoutKind,
    pub precision: Precision,
    pub selection: Selection,
    pub backend: Backend,
    pub adapter: String,
    pub rays_per_point: u32,
    pub normal_bits: Option<u32>,
    /// Rays of one evaluation: points × rays per point (× lights for shadows).
    pub rays_cast: u64,
    pub receiver_points: usize,
    pub crease_points: usize,
    pub points_in_spheres: usize,
    pub caster_triangles: usize,
}

/// A row's times (seconds).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimeColumns {
    pub bake_s: Option<f64>,
    pub ao_s: f64,
    pub raycast_s: Option<f64>,
    pub ao_kernel_s: Option<f64>,
    pub raycast_kernel_s: Option<f64>,
    pub setup_s: Option<f64>,
}

/// A row's fields: their bytes and bakes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FieldColumns {
    pub field_bytes: u64,
    pub bake_rays: u64,
    pub bake_cached: bool,
}

/// A row's errors (0–255): against the same-ray reference (the kind's metric columns) and
/// against the converged reference.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErrorColumns {
    pub seeds: u32,
    pub rms_vertex: Option<(f64, Option<f64>)>,
    pub rms_image: Option<(f64, Option<f64>)>,
    pub max_error_vertex: Option<f64>,
    pub max_error_image: Option<f64>,
    pub share_pixels_off_1: Option<f64>,
    pub rms_vs_truth: Option<(f64, Option<f64>)>,
    pub rms_vs_truth_crease: Option<f64>,
    pub rms_vs_truth_interior: Option<f64>,
    pub rms_vs_truth_in_spheres: Option<f64>,
    pub rms_vs_truth_outside_spheres: Option<f64>,
    pub rms_outside_spheres: Option<f64>,
    pub truth_stderr: Option<f64>,
    pub truth_rays: Option<u32>,
    pub raycast_rms_vs_truth: Option<f64>,
    pub occlusion_rms: Option<f64>,
    pub grain: Option<f64>,
    pub second_reference: Option<String>,
    pub rms_image_vs_second: Option<f64>,
    /// The image, relative to the output folder (empty without an image).
    pub image: String,
}

impl Row {
    /// The row of its typed parts.
    pub fn from_parts(c: CellColumns, t: TimeColumns, f: FieldColumns, e: ErrorColumns) -> Row {
        let rays = c.rays_cast as f64;
        Row {
            positional_samples: c.positional_samples,
            directional_res: c.directional_res,
            layout: c.layout,
            precision: c.precision,
            selection: c.selection,
            backend: c.backend,
            adapter: c.adapter,
            bake_s: t.bake_s,
            ao_s: t.ao_s,
            raycast_s: t.raycast_s,
            rms_vertex: e.rms_vertex.map(|m| m.0),
            rms_image: e.rms_image.map(|m| m.0),
            field_bytes: f.field_bytes,
            rms_vs_truth: e.rms_vs_truth.map(|m| m.0),
            truth_stderr: e.truth_stderr,
            scene: c.scene,
            sphere: c.sphere,
            rays_per_point: c.rays_per_point,
            receiver_points: c.receiver_points,
            caster_triangles: c.caster_triangles,
            max_error_vertex: e.max_error_vertex,
            max_error_image: e.max_error_image,
            share_pixels_off_1: e.share_pixels_off_1,
            bake_rays: f.bake_rays,
            bake_cached: f.bake_cached,
            image: e.image,
            cell: c.cell,
            ao_kernel_s: t.ao_kernel_s,
            raycast_kernel_s: t.raycast_kernel_s,
            setup_s: t.setup_s,
            seeds: e.seeds,
            rms_vertex_sd: e.rms_vertex.and_then(|m| m.1),
            rms_image_sd: e.rms_image.and_then(|m| m.1),
            rms_vs_truth_sd: e.rms_vs_truth.and_then(|m| m.1),
            raycast_rms_vs_truth: e.raycast_rms_vs_truth,
            truth_rays: e.truth_rays,
            crease_points: c.crease_points,
            rms_vs_truth_crease: e.rms_vs_truth_crease,
            rms_vs_truth_interior: e.rms_vs_truth_interior,
            points_in_spheres: Some(c.points_in_spheres),
            rms_vs_truth_in_spheres: e.rms_vs_truth_in_spheres,
            rms_vs_truth_outside_spheres: e.rms_vs_truth_outside_spheres,
            rms_outside_spheres: e.rms_outside_spheres,
            occlusion_rms: e.occlusion_rms,
            grain: e.grain,
            rays_cast: c.rays_cast,
            ao_mrays_s: mrays_per_s(rays, Some(t.ao_s)),
            raycast_mrays_s: mrays_per_s(rays, t.raycast_s),
            normal_bits: c.normal_bits,
            second_reference: e.second_reference,
            rms_image_vs_second: e.rms_image_vs_second,
        }
    }
}

/// Millions of rays per second; none without a time or a positive one.
fn mrays_per_s(rays: f64, s: Option<f64>) -> Option<f64> {
    s.filter(|&s| s > 0.0).map(|s| rays / s / 1e6)
}

/// Ray-cast AO at one ray count, against the reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    pub scene: String,
    pub backend: Backend,
    pub rays_per_point: u32,
    pub ao_s: f64,
    pub rms_vertex: Option<f64>,
    pub rms_image: Option<f64>,
    /// Kernel time from GPU timestamps (`ao_s` is the wall time); empty on the CPU.
    #[serde(default)]
    pub kernel_s: Option<f64>,
    /// RMS over points against the converged reference (0–255), mean over seeds.
    #[serde(default)]
    pub rms_vs_truth: Option<f64>,
    /// Its standard deviation over seeds.
    #[serde(default)]
    pub rms_vs_truth_sd: Option<f64>,
    /// The converged reference's RMS standard error (0–255).
    #[serde(default)]
    pub truth_stderr: Option<f64>,
}

/// Field lookup of one cell with another ray count, against the converged reference only.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldSweepRow {
    pub scene: String,
    pub cell: String,
    pub positional_samples: usize,
    pub directional_res: u32,
    pub precision: Precision,
    pub selection: Selection,
    pub backend: Backend,
    pub rays_per_point: u32,
    pub ao_s: f64,
    /// RMS over points against the converged reference (0–255), first seed.
    pub rms_vs_truth: Option<f64>,
    pub truth_stderr: Option<f64>,
}

/// RMS between two cells that differ only in precision.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairRow {
    pub scene: String,
    pub sphere: SphereKind,
    pub positional_samples: usize,
    pub directional_res: u32,
    pub layout: LayoutKind,
    pub selection: Selection,
    pub backend: Backend,
    pub precision_a: Precision,
    pub precision_b: Precision,
    pub rms_vertex: Option<f64>,
    pub rms_image: Option<f64>,
    /// The two cells' ids (`table.csv`'s `cell`), precision `a`'s first; empty in tables
    /// written before the column.
    #[serde(default)]
    pub cell_a: String,
    #[serde(default)]
    pub cell_b: String,
}

/// Writes rows as CSV (header from the struct), atomically.
pub fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(Error::csv(path))?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e.into_error(),
    })?;
    crate::io::write_atomic(path, &bytes).map_err(Error::io(path))
}

/// Reads rows written by [`write_csv`].
pub fn read_csv<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    let mut r = csv::Reader::from_path(path).map_err(Error::csv(path))?;
    r.deserialize()
        .collect::<std::result::Result<Vec<T>, _>>()
        .map_err(Error::csv(path))
}
