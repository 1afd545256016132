//! `table.csv`: one row per cell and backend, an ordered set of named columns.
//!
//! A row is built from its parts ([`Parts`]), each filled by the step of the run that knows it:
//! the cell ([`CellColumns`]: its axes, scene, points), the field ([`FieldColumns`]: bytes and
//! bakes), the times ([`TimeColumns`]) and the kind's metrics ([`ErrorColumns`]: against the
//! same-ray reference and the converged one). Every column is defined once, in the list of
//! `table_columns!` below: its name, the names tables written before it used (read back as
//! aliases), its type as readers read it, what it holds, its value from the parts, and for an
//! error column its place in `methods.csv`. That one list gives the header order
//! ([`TABLE_COLUMNS`]), the typed reader's view ([`Row`], serde by header name, so `experiment
//! plots`, `check` and `paper::rewrite` read the committed tables of either naming), the writer
//! ([`write_table`]) and `methods.csv`'s error columns ([`ErrorColumns::push_to`]). A kind's own
//! metric columns ([`crate::experiment::kinds::Kind::own_metrics`]) follow the standard ones,
//! read back by name ([`crate::experiment::columns::read_csv`]). The mechanism every CSV
//! follows: [`crate::experiment::columns`].
//!
//! Names say what a column holds for every kind: `estimate_s` is the estimate's time through
//! the fields (AO, light fractions or reflected radiance), `signal_rms` the RMS of the
//! reference's distance from 1. The header order is the order of the tables committed before
//! the names changed, new columns at the end, so that a regenerated table differs only by the
//! renames ([`FORMER_NAMES`]) and the new columns.

use super::columns::{self, NamedRow};
use super::spec::Backend;
use super::Result;
use crate::field::{FieldParams, Precision, Selection};
use crate::sampling::{LayoutKind, SphereKind};
use serde::{Deserialize, Serialize};
use std::path::Path;

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
    /// Values per point (1: a scalar kind).
    pub channels: u32,
}

/// A row's times (seconds).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimeColumns {
    pub bake_s: Option<f64>,
    /// The estimate through the fields.
    pub estimate_s: f64,
    pub raycast_s: Option<f64>,
    /// The estimate's kernel alone (GPU timestamps).
    pub estimate_kernel_s: Option<f64>,
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
/// against the converged reference. Their columns are the `(errors N)` ones of
/// `table_columns!`; `methods.csv` writes the same ([`ErrorColumns::push_to`]).
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
    /// The signal: RMS over the values of 255 · (1 − value) of the same-ray reference.
    pub signal_rms: Option<f64>,
    pub grain: Option<f64>,
    pub second_reference: Option<String>,
    pub rms_image_vs_second: Option<f64>,
    /// `rms_image` over the window's active pixels (the 2010 paper's pixel set).
    pub rms_image_window: Option<f64>,
    /// The same-ray RMS of the shaded images, mean over seeds (kinds with a shading factor).
    pub rms_image_shaded: Option<f64>,
    /// FLIP of the first seed's image against the same-ray reference's image, and against
    /// the converged reference's image, pooled over the pixels that show values
    /// ([`crate::experiment::flip`]); none without an image (or without a converged
    /// reference).
    pub flip: Option<crate::experiment::flip::FlipStats>,
    pub flip_vs_truth: Option<crate::experiment::flip::FlipStats>,
    /// The image, relative to the output folder (empty without an image).
    pub image: String,
}

/// Everything a row is built from.
#[derive(Clone, Debug, PartialEq)]
pub struct Parts {
    pub cell: CellColumns,
    pub times: TimeColumns,
    pub fields: FieldColumns,
    pub errors: ErrorColumns,
}

/// Millions of rays per second; none without a time or a positive one.
fn mrays_per_s(rays: u64, s: Option<f64>) -> Option<f64> {
    s.filter(|&s| s > 0.0).map(|s| rays as f64 / s / 1e6)
}

fn one() -> u32 {
    1
}

/// Defines the table's columns once, in header order: each `NAME (was OLD) (errors N): TYPE =
/// |p| VALUE;` with its doc comment and serde attributes. Gives [`Row`] (serde by name, `OLD`
/// read as an alias), [`TABLE_COLUMNS`], [`FORMER_NAMES`] and [`Row::from_parts`]. A column
/// marked `(errors N)` is one of the [`ErrorColumns`] (`p` is then the row's errors, not its
/// parts): `methods.csv` writes those too, at place `N` of its error block
/// ([`ErrorColumns::push_to`]).
macro_rules! table_columns {
    // What a column's `p` is: the row's parts, or an error column's errors.
    (@of $parts:ident) => { $parts };
    (@of $parts:ident $n:literal) => { &$parts.errors };
    ($(
        $(#[$attr:meta])*
        $name:ident $((was $old:literal))? $((errors $n:literal))?: $ty:ty =
            |$p:ident| $value:expr;
    )*) => {
        /// One row of `table.csv` as its readers see it: every standard column, by header
        /// name (the names of older tables too, [`FORMER_NAMES`]). Times in seconds, RMS and
        /// errors on the 0–255 scale (see [`super::metrics`]); for a kind with channels every
        /// error is over all of a point's channels.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        pub struct Row {
            $(
                $(#[$attr])*
                $(#[serde(alias = $old)])?
                pub $name: $ty,
            )*
        }

        /// The standard columns of `table.csv`, in header order (a kind's own metric columns
        /// follow them).
        pub const TABLE_COLUMNS: &[&str] = &[$(stringify!($name)),*];

        /// (the name in tables written before, the column's name now).
        pub const FORMER_NAMES: &[(&str, &str)] = &[$($(($old, stringify!($name)),)?)*];

        impl Row {
            /// The row of its parts: each column as its definition computes it.
            pub fn from_parts(parts: &Parts) -> Row {
                Row {
                    $($name: {
                        let $p = table_columns!(@of parts $($n)?);
                        $value
                    },)*
                }
            }
        }

        impl ErrorColumns {
            /// Adds the error columns (those marked `errors N` in `table.csv`'s list, valued
            /// as there) to a `methods.csv` row, in the order of their `N`, each as
            /// [`NamedRow`] writes a value.
            pub fn push_to(&self, row: &mut NamedRow) {
                let mut cols: Vec<(u32, &str, String)> = vec![$($(
                    ($n, stringify!($name), columns::Cell::cell(&{
                        let $p = self;
                        $value
                    })),
                )?)*];
                cols.sort_by_key(|c| c.0);
                for (_, name, value) in cols {
                    row.push(name, value);
                }
            }
        }
    };
}

table_columns! {
    // The cell's axes and where it ran.
    positional_samples: usize = |p| p.cell.positional_samples;
    directional_res: u32 = |p| p.cell.directional_res;
    layout: LayoutKind = |p| p.cell.layout;
    precision: Precision = |p| p.cell.precision;
    selection: Selection = |p| p.cell.selection;
    backend: Backend = |p| p.cell.backend;
    /// The device that ran the estimate (CPU model and threads, or GPU adapter).
    adapter: String = |p| p.cell.adapter.clone();
    /// Preprocessing: the bake of every caster's field (BVH build included); for a derived
    /// precision the f32 bake plus the requantisation; from the bake record on a cache hit.
    bake_s: Option<f64> = |p| p.times.bake_s;
    /// The estimate through the fields (the kind's values at every point: AO, light
    /// fractions, reflected radiance), best of 3 when short; on the GPU the call's wall time
    /// (upload of the points, dispatch, wait, read-back).
    estimate_s (was "ao_s"): f64 = |p| p.times.estimate_s;
    /// Ray casting the same estimate on the same rays and backend.
    raycast_s: Option<f64> = |p| p.times.raycast_s;
    /// Per receiver vertex RMS against the same-ray reference (none for the per-pixel kinds).
    rms_vertex (errors 1): Option<f64> = |e| e.rms_vertex.map(|m| m.0);
    /// Per image pixel RMS against the reference image (none without an image).
    rms_image (errors 3): Option<f64> = |e| e.rms_image.map(|m| m.0);
    /// Stored bytes of every caster's field (normal fields included).
    field_bytes: u64 = |p| p.fields.field_bytes;
    /// RMS over the evaluation points (receiver vertices, or pixels), unquantised, 0–255, of
    /// the field's values against the converged reference (see [`super::truth_cache`]); mean
    /// over seeds. It includes the reference's own noise: E\[rms²\] = error² +
    /// `truth_stderr`².
    #[serde(default)]
    rms_vs_truth (errors 8): Option<f64> = |e| e.rms_vs_truth.map(|m| m.0);
    /// RMS over points of the converged reference's standard error (0–255): its noise floor.
    #[serde(default)]
    truth_stderr (errors 15): Option<f64> = |e| e.truth_stderr;
    // Context.
    scene: String = |p| p.cell.scene.clone();
    sphere: SphereKind = |p| p.cell.sphere;
    rays_per_point: u32 = |p| p.cell.rays_per_point;
    /// Evaluation points (receiver vertices, or receiver pixels).
    receiver_points: usize = |p| p.cell.receiver_points;
    caster_triangles: usize = |p| p.cell.caster_triangles;
    max_error_vertex (errors 5): Option<f64> = |e| e.max_error_vertex;
    max_error_image (errors 6): Option<f64> = |e| e.max_error_image;
    /// Share of receiver pixel values whose 8-bit level differs from the reference's by more
    /// than 1.
    share_pixels_off_1 (errors 7): Option<f64> = |e| e.share_pixels_off_1;
    /// Rays the bakes traced.
    bake_rays: u64 = |p| p.fields.bake_rays;
    /// Every field came from the cache.
    bake_cached: bool = |p| p.fields.bake_cached;
    /// The image, relative to the output folder (empty without an image).
    image: String = |p| p.errors.image.clone();
    /// The cell id.
    cell: String = |p| p.cell.cell.clone();
    /// The estimate's kernel time from GPU timestamps (best over the timed runs); empty on
    /// the CPU and on adapters without timestamp queries.
    #[serde(default)]
    estimate_kernel_s (was "ao_kernel_s"): Option<f64> = |p| p.times.estimate_kernel_s;
    /// Ray-cast kernel time from GPU timestamps on the same rays; `raycast_s` is its wall time.
    #[serde(default)]
    raycast_kernel_s: Option<f64> = |p| p.times.raycast_kernel_s;
    /// GPU only: packing and uploading the fields and compiling the kernel, once per cell
    /// (not in `estimate_s`); empty on the CPU, which reads the fields in place.
    #[serde(default)]
    setup_s: Option<f64> = |p| p.times.setup_s;
    /// Seeds (per-point ray rotations) the RMS columns are averaged over.
    #[serde(default)]
    seeds (errors 0): u32 = |e| e.seeds;
    /// Standard deviation over seeds of `rms_vertex`.
    #[serde(default)]
    rms_vertex_sd (errors 2): Option<f64> = |e| e.rms_vertex.and_then(|m| m.1);
    /// Standard deviation over seeds of `rms_image`.
    #[serde(default)]
    rms_image_sd (errors 4): Option<f64> = |e| e.rms_image.and_then(|m| m.1);
    /// Standard deviation over seeds of `rms_vs_truth`.
    #[serde(default)]
    rms_vs_truth_sd (errors 9): Option<f64> = |e| e.rms_vs_truth.and_then(|m| m.1);
    /// The same-ray ray-cast reference against the converged one (mean over seeds): the
    /// error a ray cast with the cell's rays makes.
    #[serde(default)]
    raycast_rms_vs_truth (errors 17): Option<f64> = |e| e.raycast_rms_vs_truth;
    /// Rays per point of the converged reference.
    #[serde(default)]
    truth_rays (errors 16): Option<u32> = |e| e.truth_rays;
    /// Evaluation points that touch another surface (see `render::contact`).
    #[serde(default)]
    crease_points: usize = |p| p.cell.crease_points;
    /// `rms_vs_truth` over the crease points only (none without crease points).
    #[serde(default)]
    rms_vs_truth_crease (errors 10): Option<f64> = |e| e.rms_vs_truth_crease;
    /// `rms_vs_truth` over the other points.
    #[serde(default)]
    rms_vs_truth_interior (errors 11): Option<f64> = |e| e.rms_vs_truth_interior;
    /// Evaluation points inside some caster's world bounding sphere (where the lookup starts
    /// inside a sphere: the intra-object test, or a receiver the sphere cuts).
    #[serde(default)]
    points_in_spheres: Option<usize> = |p| Some(p.cell.points_in_spheres);
    /// `rms_vs_truth` over the points inside some caster's sphere (none when there are none).
    #[serde(default)]
    rms_vs_truth_in_spheres (errors 12): Option<f64> = |e| e.rms_vs_truth_in_spheres;
    /// `rms_vs_truth` over the points outside every caster's sphere.
    #[serde(default)]
    rms_vs_truth_outside_spheres (errors 13): Option<f64> = |e| e.rms_vs_truth_outside_spheres;
    /// RMS over the points outside every caster's sphere (0–255, unquantised, first seed) of
    /// the values against the same-ray reference: the error where the lookup is the papers'
    /// inter-object case.
    #[serde(default)]
    rms_outside_spheres (errors 14): Option<f64> = |e| e.rms_outside_spheres;
    /// The signal the errors are measured against: RMS over the points (and channels) of
    /// 255 · (1 − value) of the same-ray reference (for AO its occlusion; for shadows the
    /// light the casters take away). A caster that shades little gives small errors whatever
    /// the method; `rms_vertex` or `rms_image` over this compares casters.
    #[serde(default)]
    signal_rms (was "occlusion_rms") (errors 18): Option<f64> = |e| e.signal_rms;
    /// Graininess of the image's error against the reference image, first seed (see
    /// [`super::metrics::grain`]; none without an image).
    #[serde(default)]
    grain (errors 19): Option<f64> = |e| e.grain;
    /// Rays of one evaluation: points × rays per point (× lights for shadows; every ray, those
    /// that miss a caster's sphere too, as the 2010 paper counts).
    #[serde(default)]
    rays_cast: u64 = |p| p.cell.rays_cast;
    /// Rays per second of the estimate through the fields, millions: `rays_cast` /
    /// `estimate_s`.
    #[serde(default)]
    estimate_mrays_s (was "ao_mrays_s"): Option<f64> =
        |p| mrays_per_s(p.cell.rays_cast, Some(p.times.estimate_s));
    /// The same for ray casting on the same rays (`raycast_s`).
    #[serde(default)]
    raycast_mrays_s: Option<f64> = |p| mrays_per_s(p.cell.rays_cast, p.times.raycast_s);
    /// Bits per component of the normal field the cell read (reflections; `field_bytes`
    /// includes it); empty for kinds that read none.
    #[serde(default)]
    normal_bits: Option<u32> = |p| p.cell.normal_bits;
    /// The name of the kind's second reference (reflections with a glossy lobe: "mirror");
    /// empty without one.
    #[serde(default)]
    second_reference (errors 20): Option<String> = |e| e.second_reference.clone();
    /// RMS per pixel (0–255, as `rms_image`) of the first seed's image against the second
    /// reference's image, ray cast on the same points.
    #[serde(default)]
    rms_image_vs_second (errors 21): Option<f64> = |e| e.rms_image_vs_second;
    /// Values per point: 1 for a scalar kind (every kind of the papers), 3 for an RGB or a
    /// direction; 1 in tables written before the column.
    #[serde(default = "one")]
    channels: u32 = |p| p.cell.channels;
    /// `rms_image` as the 2010 paper takes an image's RMS: over every pixel of the window that
    /// sees a surface (its "active pixels"), the pixels no value is evaluated at (a caster
    /// drawn with its own shading, the same in both images) counting as exact, so
    /// `rms_image` × √(evaluated pixels / active pixels). None without an image.
    #[serde(default)]
    rms_image_window (errors 22): Option<f64> = |e| e.rms_image_window;
    /// RMS per pixel (0–255) of the shaded image (each value × the kind's shading factor, the
    /// `-shaded.png` pictures: shadows × the unshadowed direct light) against the same-ray
    /// reference's shaded image, over the evaluated pixels, mean over seeds: the images the
    /// 2010 paper compares. None for a kind without shading.
    #[serde(default)]
    rms_image_shaded (errors 23): Option<f64> = |e| e.rms_image_shaded;
    /// Mean FLIP (Andersson et al., HPG 2020: the perceptual error, 0–1,
    /// [`crate::experiment::flip`]) of the first seed's image against the same-ray
    /// reference's image, both read as their 8-bit PNGs (grey as equal RGB), at 67 pixels per
    /// degree, pooled over the pixels `rms_image` is taken over. None without an image.
    #[serde(default)]
    flip_mean (errors 24): Option<f64> = |e| e.flip.map(|f| f.mean);
    /// The FLIP pooling's weighted median of the same map: half of the pooled pixels' total
    /// FLIP error lies at or below it.
    #[serde(default)]
    flip_weighted_median (errors 25): Option<f64> = |e| e.flip.map(|f| f.weighted_median);
    /// `flip_mean` against the converged reference's image (none without one).
    #[serde(default)]
    flip_mean_vs_truth (errors 26): Option<f64> = |e| e.flip_vs_truth.map(|f| f.mean);
    /// `flip_weighted_median` against the converged reference's image.
    #[serde(default)]
    flip_weighted_median_vs_truth (errors 27): Option<f64> =
        |e| e.flip_vs_truth.map(|f| f.weighted_median);
}

/// A row as written: the standard columns, then the kind's own metric columns (name, value).
#[derive(Clone, Debug, PartialEq)]
pub struct TableRow {
    pub row: Row,
    pub own: Vec<(String, f64)>,
}

impl TableRow {
    /// The row's named columns in header order.
    pub fn named(&self) -> NamedRow {
        let mut out = columns::of_serialized(&self.row);
        for (name, v) in &self.own {
            out.push(name.clone(), v);
        }
        out
    }
}

impl Row {
    /// The row's field.
    pub fn params(&self) -> FieldParams {
        FieldParams {
            sphere: self.sphere,
            count: self.positional_samples,
            layout: self.layout,
            res: self.directional_res,
            precision: self.precision,
        }
    }
}

/// Writes `table.csv` (the header: [`TABLE_COLUMNS`], then the kinds' own columns), atomically.
/// Without rows, the header alone.
pub fn write_table(path: &Path, rows: &[TableRow]) -> Result<()> {
    let named: Vec<NamedRow> = rows.iter().map(TableRow::named).collect();
    columns::write_csv_with(path, TABLE_COLUMNS, &named)
}

#[cfg(test)]
#[path = "table_tests.rs"]
mod tests;
