//! `experiment quickstart`: the small tour on the embedded default scene (a supershape floating
//! over the 2008 paper's corner receiver; no file needed). It is a spec like every other
//! (`quickstart.json`, embedded in the binary) run by the same runner: ray-cast vertex AO at the
//! corner's vertices, one small visibility field of the supershape, AO through the field on the
//! same rays, both against the converged reference, and the usual tables, images and plots.

use super::run::{self, LoadedSpec, RunOptions};
use super::spec::Spec;
use super::Result;
use std::path::{Path, PathBuf};

/// The quickstart's spec text.
pub const SPEC: &str = include_str!("quickstart.json");

/// The quickstart's spec, as loaded from a file.
pub fn spec() -> Result<LoadedSpec> {
    let path = PathBuf::from("quickstart (embedded)");
    Ok(LoadedSpec {
        name: "quickstart".into(),
        spec: Spec::parse(SPEC, &path)?,
        path,
        text: SPEC.to_string(),
    })
}

/// Runs the tour into `out` (the field from the cache when there), in the quick profile where
/// `quick`, and prints its summary.
pub fn run(out: &Path, quick: bool) -> Result<()> {
    let ls = spec()?;
    let mut options = RunOptions::new(out.to_path_buf());
    options.quick = quick;
    let report = run::run(&ls, &options)?;
    let r = &report.rows[0];
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    println!();
    println!("visfield quickstart: {}", r.adapter);
    println!(
        "  receiver: corner, {} vertices; caster: supershape, {} triangles",
        r.receiver_points, r.caster_triangles
    );
    println!(
        "  ray-cast AO ({} rays/vertex):   {:>8} s",
        r.rays_per_point,
        opt(r.raycast_s)
    );
    println!(
        "  field {} × {}² {} ({} KiB): bake {} s{}",
        r.positional_samples,
        r.directional_res,
        r.precision.name(),
        r.field_bytes / 1024,
        opt(r.bake_s),
        if r.bake_cached { " (cached)" } else { "" }
    );
    println!(
        "  field-lookup AO (same rays):     {:>8.3} s  ({}× faster)",
        r.estimate_s,
        opt(r.raycast_s.map(|s| s / r.estimate_s.max(1e-12)))
    );
    println!(
        "  RMS vs the same-ray ray cast (0–255): per vertex {}, per image pixel {}",
        opt(r.rms_vertex),
        opt(r.rms_image)
    );
    println!(
        "  RMS vs the converged reference: field {}, ray cast {} (its noise floor {})",
        opt(r.rms_vs_truth),
        opt(r.raycast_rms_vs_truth),
        opt(r.truth_stderr)
    );
    println!("  outputs: {}", out.display());
    Ok(())
}
