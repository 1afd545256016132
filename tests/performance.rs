//! `experiment performance --quick`: every sweep's rows, and the answers that must agree
//! exactly whatever the timing (the floors against the measured share of entering rays).

use visfield::experiment::fields::FieldSupply;
use visfield::experiment::performance::{plan, run, PerfRow};

#[test]
fn the_quick_run_writes_every_sweep_with_exact_shares() {
    let out = tempfile::tempdir().unwrap();
    let supply = FieldSupply {
        cache: None,
        cache_limit: 0,
        memory_limit: 1 << 30,
    };
    let rows: Vec<PerfRow> = run(&out.path().join("perf"), true, &supply).unwrap();
    for f in [
        "table.csv",
        "run.json",
        "growth_triangles.png",
        "growth_field_size.png",
        "growth_entering.png",
    ] {
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
    assert_eq!(
        (count("triangles"), count("field_size"), count("entering")),
        (2 * per, 2 * per, 3 * per)
    );
    for r in &rows {
        assert!(
            r.seconds > 0.0 && r.mrays_s.is_finite() && r.rays > 0,
            "{r:?}"
        );
        match r.backend {
            // Nothing is ever occluded.
            "floor_no_query" => assert_eq!(r.free_share, 1.0, "{r:?}"),
            // Occluded exactly where the ray enters the sphere ahead.
            "floor_sphere_cull" => {
                let entering = (r.entering_share * r.rays as f64).round();
                let free = (r.free_share * r.rays as f64).round();
                assert_eq!(entering + free, r.rays as f64, "{r:?}");
            }
            _ => {}
        }
        if r.sweep == "entering" && r.entering_share == 0.0 {
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

#[test]
fn the_dry_run_names_every_caster_and_field_without_running() {
    let full = plan(false);
    for m in [
        "bunny_npm",
        "dragon",
        "supershape",
        "igea",
        "4226x64² f32",
        "0.25",
    ] {
        assert!(full.contains(m), "{m} missing from {full}");
    }
    assert!(
        plan(true).contains("every 16th corner vertex"),
        "{}",
        plan(true)
    );
}
