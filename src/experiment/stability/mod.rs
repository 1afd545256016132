//! `experiment stability`: stiff and extreme cases, each compared against an f64 or closed-form
//! answer.
//!
//! Every case is a function returning [`StabilityRow`]s (`case, quantity, max_error, tolerance, pass`);
//! [`CASES`] lists them, [`run`] runs them all and writes `cases.csv` and `run.json`, and
//! `tests/stability.rs` runs each case as a test. The cases:
//!
//! - [`sphere`]: ray–sphere crossings from origins 1e-3 R to 1e6 R away, grazing rays (tangent
//!   ± 1 ulp), origins on and just inside the sphere, against an f64 Newton-refined reference.
//! - [`layouts`]: frames at the poles and axes; layout texels for directions on texel
//!   boundaries, the concentric map's centre and diagonals, the last row and column, the
//!   horizon; quantisation of distances 0, just under 1 and 1 and the 1-bit threshold.
//! - [`scale`]: one scene scaled by 1e-3 … 1e4, or translated by 1e4, gives the same AO.
//! - [`hard`]: receivers touching the caster, thin sheets, casters 1000× larger and smaller,
//!   concave casters, overlapping bounding spheres, a receiver inside a caster's sphere.
//! - [`determinism`]: 1 and 2 threads give bit-identical fields and images.
//! - [`lights`]: the 2010 kinds: sphere lights from r/d = 0.5 to 1e-7, a sun and point lights,
//!   unoccluded and behind an exact sphere (the caps' closed forms), lights grazing a caster's
//!   bounding sphere, a light below the
//!   receiving surface, Phong lobes by exponent decade, a mirror at grazing incidence;
//!   [`lights_gpu`], their GPU rows where an adapter runs (left out, and said so, without one).

pub mod determinism;
pub mod hard;
pub mod layouts;
pub mod lights;
pub mod lights_gpu;
pub mod scale;
pub mod scene_ao;
pub mod sphere;

use super::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One measured quantity of a case.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StabilityRow {
    /// The case (a function in [`CASES`]).
    pub case: String,
    /// What was measured, with its unit.
    pub quantity: String,
    /// The largest error over the case's inputs (same unit as `tolerance`).
    pub max_error: f64,
    /// The error allowed.
    pub tolerance: f64,
    /// `max_error <= tolerance` (and finite).
    pub pass: bool,
}

impl StabilityRow {
    /// A row; `pass` is `max_error <= tolerance` with a NaN error failing.
    pub fn new(
        case: &str,
        quantity: impl Into<String>,
        max_error: f64,
        tolerance: f64,
    ) -> StabilityRow {
        StabilityRow {
            case: case.to_string(),
            quantity: quantity.into(),
            max_error,
            tolerance,
            pass: max_error <= tolerance,
        }
    }
}

/// A case: its name and the function that measures it.
pub type Case = (&'static str, fn() -> Vec<StabilityRow>);

/// Every case of `experiment stability`, in output order.
pub const CASES: &[Case] = &[
    ("ray_sphere_far_and_near", sphere::far_and_near),
    ("ray_sphere_grazing", sphere::grazing),
    ("ray_sphere_on_and_inside", sphere::on_and_inside),
    ("frames_at_poles_and_axes", layouts::frames),
    ("layout_singular_directions", layouts::texels),
    ("quantisation_edges", layouts::quantisation),
    ("scale", scale::scale),
    ("position", scale::position),
    ("bystanders", scale::bystanders),
    ("receiver_touching_caster", hard::touching),
    ("thin_sheet", hard::thin_sheet),
    ("caster_1000x_larger_and_smaller", hard::extreme_sizes),
    ("concave_caster", hard::concave),
    ("overlapping_spheres", hard::overlapping_spheres),
    ("receiver_inside_caster_sphere", hard::inside_sphere),
    ("thread_determinism", determinism::threads),
    ("sphere_light_unoccluded", lights::unoccluded),
    ("sphere_light_behind_sphere_occluder", lights::behind_sphere),
    ("light_grazing_caster_sphere", lights::grazing_caster_sphere),
    ("light_below_receiver", lights::below_surface),
    ("phong_lobe_by_exponent", lights::phong_lobes),
    ("mirror_grazing", lights::mirror_grazing),
];

/// Runs every case and writes `out/cases.csv` and `out/run.json` (atomically). Returns the
/// rows; the error names the failing rows when any case fails (the files are written first).
pub fn run(out: &Path) -> Result<Vec<StabilityRow>> {
    crate::experiment::progress::begin_run();
    crate::experiment::run::ensure_writable(out)?;
    let meta = crate::experiment::meta::RunMeta::collect(None);
    let mut rows = Vec::new();
    for (name, case) in CASES {
        let t = std::time::Instant::now();
        rows.extend(report(name, t, case()));
    }
    // The GPU rows where an adapter runs ($VISFIELD_ADAPTER, else auto); without a Vulkan
    // driver they are left out, and said so.
    let pref = Some(crate::gpu::AdapterPreference::from_env());
    let left_out = "stability: no Vulkan adapter, the GPU rows are left out";
    if let Some(ctx) = super::relief::gpu_context(pref, "stability", left_out)? {
        let t = std::time::Instant::now();
        rows.extend(report("gpu_sphere_lights", t, lights_gpu::gpu_rows(&ctx)?));
    }
    crate::experiment::outputs::write_csv(&out.join("cases.csv"), &rows)?;
    let json = out.join("run.json");
    let meta = meta.timed();
    crate::io::write_atomic(&json, meta.to_json().as_bytes()).map_err(Error::io(&json))?;
    let failed: Vec<String> = rows
        .iter()
        .filter(|r| !r.pass)
        .map(|r| {
            format!(
                "{} / {}: {:e} > {:e}",
                r.case, r.quantity, r.max_error, r.tolerance
            )
        })
        .collect();
    println!(
        "stability: {} row(s), {} failing -> {}",
        rows.len(),
        failed.len(),
        out.join("cases.csv").display()
    );
    if failed.is_empty() {
        Ok(rows)
    } else {
        Err(Error::invalid(
            "stability",
            format!("failing cases:\n  {}", failed.join("\n  ")),
        ))
    }
}

/// Says on stderr how many rows case `name`, started at `t`, gave, how many fail and how long
/// it took; returns the rows.
fn report(name: &str, t: std::time::Instant, rows: Vec<StabilityRow>) -> Vec<StabilityRow> {
    eprintln!(
        "stability: {name}: {} row(s), {} failing ({:.2} s)",
        rows.len(),
        rows.iter().filter(|r| !r.pass).count(),
        t.elapsed().as_secs_f64()
    );
    rows
}

/// The largest of `values` (0 for none; NaN propagates as a failure).
pub fn max_of(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(0.0, |m, v| {
        if v.is_nan() || m.is_nan() {
            f64::NAN
        } else {
            m.max(v)
        }
    })
}

/// [`max_of`] as an iterator method: the largest value, NaN when any is.
pub(super) trait MaxOf: Iterator<Item = f64> + Sized {
    fn max_of(self) -> f64 {
        max_of(self)
    }
}

impl<I: Iterator<Item = f64>> MaxOf for I {}

/// The larger of two errors, NaN when either is ([`max_of`]): an error that cannot be computed
/// fails its case instead of vanishing into a running maximum.
pub(super) fn max2(a: f64, b: f64) -> f64 {
    max_of([a, b])
}
