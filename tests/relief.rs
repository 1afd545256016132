//! The 2005 relief caster in the harness: `experiment relief --quick` writes its tables, and
//! the properties the paper's Tables 1–3 rest on hold in them; where a Vulkan adapter exists
//! (lavapipe in CI) its GPU columns are filled and its frames match the CPU's.

use visfield::experiment::relief::{run, ANGLES};
use visfield::gpu::AdapterPreference;

#[test]
fn relief_quick_writes_tables_where_skipping_removes_fetches() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("relief");
    let rows = run(&out, true, Some(AdapterPreference::from_env())).unwrap();
    for f in [
        "table.csv",
        "paper_vs_ours.csv",
        "fetches_vs_angle.png",
        "time_vs_angle.png",
        "pareto.png",
        "images.png",
        "run.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // Three datasets × six angles × three skip counts, plus the sample-rate table.
    let angles = rows.iter().filter(|r| r.table == "angles").count();
    assert_eq!(angles, 3 * ANGLES.len() * 3);
    assert_eq!(rows.iter().filter(|r| r.table == "rates").count(), 5 * 3);
    for r in &rows {
        assert!(r.pixels > 0 && r.fetches_per_pixel >= 1.0, "{r:?}");
        assert!(r.rms_vs_exact.is_finite() && r.rms_vs_exact >= 0.0, "{r:?}");
        if r.skips == 0 {
            assert_eq!(r.fetch_reduction, 1.0);
        }
    }
    // Looking straight down on the smooth maps, skipping removes most of the empty space
    // above them (the paper's largest gains are at perpendicular views).
    for d in ["simple", "relief"] {
        let r = rows
            .iter()
            .find(|r| r.table == "angles" && r.dataset == d && r.view_deg == 0.0 && r.skips == 2)
            .unwrap();
        assert!(r.fetch_reduction > 1.5, "{d}: {r:?}");
    }
    // More samples per unit cost more fetches and do not lose accuracy against the exact
    // intersection (Table 3's trade-off).
    let rate = |s: f32| {
        rows.iter()
            .find(|r| {
                r.table == "rates" && r.samples_per_unit == s && r.bisections == 2 && r.skips == 0
            })
            .unwrap()
    };
    assert!(rate(75.0).fetches_per_pixel > rate(10.0).fetches_per_pixel);
    assert!(rate(75.0).rms_vs_exact <= rate(10.0).rms_vs_exact);
    let csv = std::fs::read_to_string(out.join("paper_vs_ours.csv")).unwrap();
    assert!(csv.lines().count() > 20, "{csv}");
    // The GPU columns: all rows or none (no Vulkan driver); the GPU frames are the CPU's but
    // for rays whose samples fall within a rounding of the surface.
    let gpu = rows.iter().filter(|r| r.gpu_adapter.is_some()).count();
    assert!(
        gpu == 0 || gpu == rows.len(),
        "{gpu} of {} rows",
        rows.len()
    );
    if gpu == 0 {
        eprintln!("no Vulkan adapter: GPU columns not checked");
        return;
    }
    assert!(out.join("gpu_time_vs_angle.png").is_file() || rows[0].gpu_kernel_s.is_none());
    for r in &rows {
        let differ = r.gpu_hit_mismatches_vs_cpu.unwrap();
        assert!(
            differ * 200 <= r.pixels,
            "{differ} of {} pixels: {r:?}",
            r.pixels
        );
        let fetches = r.gpu_fetches_per_pixel.unwrap();
        assert!(
            (fetches - r.fetches_per_pixel).abs() <= 0.01 * r.fetches_per_pixel,
            "{r:?}"
        );
        assert!(r.gpu_rms_vs_cpu.unwrap() <= 0.5, "{r:?}");
        assert!(r.gpu_wall_s.unwrap() > 0.0);
    }
}
