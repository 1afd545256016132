//! Every test that needs a real mesh of `data/models.json`, in one binary with its own harness
//! (`harness = false`, `common::run_model_trials`): each runs where its models are in a model
//! folder and is reported as ignored, the reason naming the models and the command that
//! fetches them, where one is missing (a bare clone), so `cargo test` passes there without a
//! test passing vacuously. A `#[test]` function in this file would never run: add a test to
//! the list in `main`.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use visfield::experiment::fields::FieldSupply;
use visfield::experiment::performance::{run, PerfRow};
use visfield::geometry::models::{ModelError, ModelRegistry};

/// The package root as cargo runs this test: the working directory it sets, not
/// `env!("CARGO_MANIFEST_DIR")`, which names the checkout the binary was compiled in. CI builds
/// these tests once in a bare clone and runs them again beside `../shared/models` without a
/// rebuild (same sources, shared target folder); a child started in the compiled-in folder
/// would look for the models beside the bare clone and miss them.
fn crate_root() -> PathBuf {
    std::env::current_dir().expect("the test's working directory")
}

/// The registered models that `experiment all --quick` reads: every spec's quick scenes.
fn every_quick_spec_model() -> Vec<String> {
    let dir = crate_root().join("experiments");
    let mut names: Vec<String> = Vec::new();
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    paths.sort();
    for p in paths {
        let ls = visfield::experiment::run::LoadedSpec::load(&p).unwrap();
        let quick = ls.spec.profile(true);
        for m in visfield::experiment::models_cmd::spec_models(&quick) {
            if !names.iter().any(|n| n == m) {
                names.push(m.to_string());
            }
        }
    }
    for m in visfield::experiment::performance::models(true) {
        if !names.iter().any(|n| n == m) {
            names.push(m.to_string());
        }
    }
    names
}

fn bunny_npm() -> Vec<String> {
    vec!["bunny_npm".into()]
}

/// The casters of `experiment performance --quick`.
fn performance_quick_models() -> Vec<String> {
    visfield::experiment::performance::models(true)
        .into_iter()
        .map(String::from)
        .collect()
}

/// `bunny_npm` found in the default folders, verified and loaded with the registry's counts.
fn bunny_npm_resolves_and_loads_with_registry_counts() {
    let reg = ModelRegistry::embedded();
    let path = reg.resolve("bunny_npm").unwrap();
    let empty = tempfile::tempdir().unwrap();
    // An earlier folder without the file is skipped.
    let dirs = [
        empty.path().to_path_buf(),
        path.parent().unwrap().to_path_buf(),
    ];
    assert_eq!(reg.resolve_in("bunny_npm", &dirs).unwrap(), path);
    let mesh = reg.load_in("bunny_npm", &dirs).unwrap();
    let entry = reg.get("bunny_npm").unwrap();
    assert_eq!(
        mesh.triangle_count() + mesh.dropped_degenerate,
        entry.triangles
    );
    assert_eq!(mesh.triangle_count(), 3674);
    assert_eq!(mesh.vertex_count(), entry.vertices);
    // MANIFEST: closed low-res bunny (0 boundary edges).
    assert!(mesh.is_closed());
}

/// A corrupted copy in an earlier folder is reported with both hashes, never skipped.
fn corrupted_copy_reports_expected_and_actual_hash() {
    let reg = ModelRegistry::embedded();
    let good = reg.resolve("bunny_npm").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(&good).unwrap();
    bytes[100] ^= 1;
    std::fs::write(dir.path().join("bunny_npm.obj"), &bytes).unwrap();
    let e = reg
        .resolve_in(
            "bunny_npm",
            &[
                dir.path().to_path_buf(),
                good.parent().unwrap().to_path_buf(),
            ],
        )
        .unwrap_err();
    let actual = visfield::io::sha256_hex(&bytes);
    match &e {
        ModelError::Mismatch {
            expected,
            actual: a,
            ..
        } => {
            assert_eq!(expected, &reg.get("bunny_npm").unwrap().sha256);
            assert_eq!(a, &actual);
        }
        other => panic!("expected a mismatch, got {other}"),
    }
    let msg = e.to_string();
    assert!(
        msg.contains("bunny_npm.obj") && msg.contains(&actual),
        "{msg}"
    );
}

/// `all --quick --dry-run` plans every spec and writes nothing: it prints the plans and stops
/// before the command-made results.
fn all_dry_run_plans_every_spec_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("all");
    let o = Command::new(env!("CARGO_BIN_EXE_experiment"))
        .args(["all", "--quick", "--dry-run", "--out"])
        .arg(&out)
        .current_dir(crate_root())
        .env_remove("VISFIELD_EXPERIMENTS")
        .output()
        .unwrap();
    let t = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("plan for figure6") && t.contains("not run"),
        "{t}"
    );
    let written = walk(&out);
    assert!(written.is_empty(), "a dry run wrote {written:?}");
}

/// Every file under `dir` (none when it does not exist).
fn walk(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// `experiment performance --quick`: every sweep's rows, and the answers that must agree
/// exactly whatever the timing (the floors against the measured share of entering rays).
fn the_quick_performance_run_writes_every_sweep_with_exact_shares() {
    let out = tempfile::tempdir().unwrap();
    let supply = FieldSupply {
        cache: None,
        cache_limit: 0,
        memory_limit: 1 << 30,
    };
    let rows: Vec<PerfRow> = run(&out.path().join("perf"), true, &supply).unwrap();
    for ray in ["", "shadow_", "reflection_"] {
        for sweep in ["triangles", "field_size", "entering"] {
            let f = format!("growth_{ray}{sweep}.png");
            assert!(out.path().join("perf").join(&f).is_file(), "{f}");
        }
    }
    for f in [visfield::experiment::outputs::BACKEND_TIMES_CSV, "run.json"] {
        assert!(out.path().join("perf").join(f).is_file(), "{f}");
    }
    let count = |sweep: &str| rows.iter().filter(|r| r.sweep == sweep).count();
    // Backends: raycast, field_nearest, floor_sphere_cull, floor_no_query (and embree where
    // built with it), every one on every sweep point.
    let mut backends: Vec<&str> = rows.iter().map(|r| r.backend).collect();
    backends.sort();
    backends.dedup();
    for b in [
        "raycast",
        "field_nearest",
        "floor_sphere_cull",
        "floor_no_query",
    ] {
        assert!(backends.contains(&b), "{b} missing from {backends:?}");
    }
    let per = backends.len();
    // Shadow rays on every backend; reflection rays without the sphere-cull floor (it has no
    // batched closest hit).
    for (ray, n) in [("", per), ("shadow_", per), ("reflection_", per - 1)] {
        let of = |s: &str| count(&format!("{ray}{s}"));
        assert_eq!(
            (of("triangles"), of("field_size"), of("entering")),
            (2 * n, 2 * n, 3 * n),
            "{ray}"
        );
    }
    // 3 lights × 16 shadow rays and 16 reflection rays a receiver at most (those below a
    // receiver's horizon are not cast).
    let receivers = |r: &PerfRow| {
        rows.iter()
            .find(|a| a.sweep == "triangles" && a.caster == r.caster)
            .map(|a| a.rays / 256)
            .unwrap()
    };
    for r in &rows {
        assert!(
            r.seconds > 0.0 && r.mrays_s.is_finite() && r.rays > 0,
            "{r:?}"
        );
        if r.sweep.starts_with("shadow_") && !r.sweep.ends_with("entering") {
            assert!(r.rays <= receivers(r) * 48, "{r:?}");
            assert!(r.free_share > 0.0 && r.free_share <= 1.0, "{r:?}");
        }
        if r.sweep.starts_with("reflection_") && !r.sweep.ends_with("entering") {
            assert!(r.rays <= receivers(r) * 16, "{r:?}");
        }
        // Where `free_share` is a share of rays (AO; every entering sweep): the floors' exact
        // answers. Shadow sweeps answer a light fraction, reflection sweeps a radiance.
        let ray_share =
            ["triangles", "field_size"].contains(&r.sweep) || r.sweep.ends_with("entering");
        match r.backend {
            // Nothing is ever occluded: every ray free, every point fully lit.
            "floor_no_query" if !r.sweep.starts_with("reflection_") || ray_share => {
                assert_eq!(r.free_share, 1.0, "{r:?}")
            }
            // Occluded exactly where the ray enters the sphere ahead (the entering shadow
            // rays end past the sphere).
            "floor_sphere_cull" if ray_share => {
                let entering = (r.entering_share * r.rays as f64).round();
                let free = (r.free_share * r.rays as f64).round();
                assert_eq!(entering + free, r.rays as f64, "{r:?}");
            }
            _ => {}
        }
        if r.sweep.ends_with("entering") && r.entering_share == 0.0 {
            // No ray reaches the caster: every backend answers every ray free.
            assert_eq!(r.free_share, 1.0, "{r:?}");
        }
    }
    // Ray casting is the unit of its own ratio.
    assert!(rows
        .iter()
        .filter(|r| r.backend == "raycast")
        .all(|r| r.vs_raycast == 1.0));
}

fn main() {
    common::run_model_trials(&[
        (
            "bunny_npm_resolves_and_loads_with_registry_counts",
            bunny_npm,
            bunny_npm_resolves_and_loads_with_registry_counts,
        ),
        (
            "corrupted_copy_reports_expected_and_actual_hash",
            bunny_npm,
            corrupted_copy_reports_expected_and_actual_hash,
        ),
        (
            "all_dry_run_plans_every_spec_and_writes_nothing",
            every_quick_spec_model,
            all_dry_run_plans_every_spec_and_writes_nothing,
        ),
        (
            "the_quick_performance_run_writes_every_sweep_with_exact_shares",
            performance_quick_models,
            the_quick_performance_run_writes_every_sweep_with_exact_shares,
        ),
    ]);
}
