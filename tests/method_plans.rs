//! Each method's precompute in the plan: an AO field's bake with its rays as configured, a
//! distance volume's samples, a world BVH, each with the bytes it keeps (those the run then
//! reports), and held against `--max-memory-mib` when the plan is made, before any work and
//! in the dry run; an animated spec's fields, kept for all its frames, checked the same way.

use std::path::Path;
use visfield::experiment::columns::read_csv;
use visfield::experiment::plan::{Plan, PlanLimits, Step};
use visfield::experiment::run::run;
use visfield::experiment::scenes::Scenes;
use visfield::experiment::spec::Spec;

mod common;
use common::{animated, loaded, options, tiny, ONE_FIELD};

/// The tiny spec with `methods` (JSON) listed.
fn with_methods(methods: &str) -> String {
    tiny(ONE_FIELD, "").replace(
        r#""reference": {"#,
        &format!(r#""methods": {methods}, "reference": {{"#),
    )
}

/// The plan's precompute steps: (method label, rays, bytes).
fn precomputes(text: &str) -> Vec<(String, u64, u64)> {
    let spec = Spec::parse(text, Path::new("t.json")).unwrap();
    let scenes = Scenes::build(&spec, Path::new("t.json"), "scenes").unwrap();
    let plan = Plan::new(
        &spec,
        &scenes,
        PlanLimits {
            memory_limit: 1 << 30,
        },
    )
    .unwrap();
    plan.steps
        .iter()
        .filter_map(|s| match s {
            Step::Precompute {
                setting,
                rays,
                bytes,
                ..
            } => Some((plan.methods[*setting].clone(), *rays, *bytes)),
            _ => None,
        })
        .collect()
}

/// The plan lists each setting's precompute with its rays, and its bytes are the ones the run
/// reports in `methods.csv`: exactly for the distance volumes and the AO fields (f32 and u8),
/// a bound for our world BVH.
#[test]
fn precomputes_are_planned_with_the_bytes_the_run_reports() {
    let text = with_methods(
        r#"[{"method": "sdf", "res": [16], "precision": ["f32", "u8"]},
            {"method": "aofield", "res": [4], "precision": ["f32", "u8"], "radial_samples": 3, "rays": 4},
            {"method": "raycast"}]"#,
    );
    let planned = precomputes(&text);
    let labels: Vec<&str> = planned.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(
        labels,
        [
            "sdf-16-f32-trace",
            "sdf-16-u8-trace",
            "aofield-4-3-f32",
            "aofield-4-3-u8",
            "raycast"
        ]
    );
    // One caster mesh: 6 × 4² texels × 3 samples × 4 rays; 3 sign rays a volume sample.
    assert_eq!(
        (planned[2].1, planned[3].1),
        (6 * 16 * 3 * 4, 6 * 16 * 3 * 4)
    );
    assert_eq!(planned[0].1, 3 * planned[0].2 / 4);
    assert_eq!(planned[4].1, 0);
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &text);
    let out = dir.path().join("out");
    run(&ls, &options(out.clone())).unwrap();
    let rows = read_csv(&out.join("methods.csv")).unwrap();
    assert_eq!(rows.len(), 5);
    for (r, (label, _, bytes)) in rows.iter().zip(&planned) {
        assert_eq!(r.get("setting"), Some(label.as_str()));
        let reported = r.number("bytes").unwrap() as u64;
        if label == "raycast" {
            assert!(reported > 0 && reported <= *bytes, "{reported} of {bytes}");
        } else {
            assert_eq!(reported, *bytes, "{label}");
        }
    }
}

/// An AO field with `rays: 65536` is planned with those rays (6 × 32² texels × 12 samples ×
/// 65,536 rays), the dry run listing them and returning at once; before, the plan showed no
/// bake and the run spent minutes in it.
#[test]
fn an_ao_field_bake_is_planned_with_its_configured_rays() {
    let text = with_methods(r#"[{"method": "aofield", "res": [32], "rays": 65536}]"#);
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &text);
    let mut o = options(dir.path().join("out"));
    o.dry_run = true;
    let t = std::time::Instant::now();
    let report = run(&ls, &o).unwrap();
    assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
    let line = report
        .plan_text
        .lines()
        .find(|l| l.contains("precompute aofield-32-12-f32 on tiny"))
        .unwrap_or_else(|| panic!("{}", report.plan_text));
    let rays = 6u64 * 32 * 32 * 12 * 65536;
    assert!(
        line.contains("6 × 32² texels × 12 samples × 65536 rays")
            && line.contains(&rays.to_string()),
        "{line}"
    );
    // The plan's total counts the bake beside the field's (290 maps × 16² texels).
    let bakes = format!("({} in bakes)", rays + 290 * 256);
    assert!(report.plan_text.contains(&bakes), "{}", report.plan_text);
    assert!(!dir.path().join("out").exists());
}

/// A 256³ distance volume (64 MiB in f32) and a 256² AO field (10.5 MiB stored) under an
/// 8 MiB limit are refused when the plan is made, naming the setting, the scene and the flag,
/// in the dry run and in a real run alike, before any step runs and with nothing written
/// (before, the volume passed the dry run and failed only after the reference steps, and the
/// AO field was never checked).
#[test]
fn precomputes_over_the_memory_limit_are_refused_before_any_work() {
    for (methods, label) in [
        (r#"[{"method": "sdf", "res": [256]}]"#, "sdf-256-f32-trace"),
        (
            r#"[{"method": "aofield", "res": [256]}]"#,
            "aofield-256-12-f32",
        ),
        (
            r#"[{"method": "aofield", "res": [256], "precision": ["u8"]}]"#,
            "aofield-256-12-u8",
        ),
    ] {
        for dry_run in [true, false] {
            let dir = tempfile::tempdir().unwrap();
            let ls = loaded(dir.path(), &with_methods(methods));
            let mut o = options(dir.path().join("out"));
            o.dry_run = dry_run;
            o.supply.memory_limit = 8 << 20;
            let t = std::time::Instant::now();
            let e = run(&ls, &o).unwrap_err().to_string();
            assert!(
                e.contains(&format!("methods \"{label}\" on scene tiny"))
                    && e.contains("its precompute")
                    && e.contains("over the memory limit of 8.00 MiB (--max-memory-mib)"),
                "{e}"
            );
            assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
            assert!(!dir.path().join("out").exists());
        }
    }
    // At 128² the AO field fits (2.6 MiB kept, 7.9 MiB at its peak).
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(
        dir.path(),
        &with_methods(r#"[{"method": "aofield", "res": [128]}]"#),
    );
    let mut o = options(dir.path().join("out"));
    o.dry_run = true;
    o.supply.memory_limit = 8 << 20;
    run(&ls, &o).unwrap();
}

/// An animated spec keeps every field cell's fields for all its frames: over the limit, the
/// dry run and the run refuse it before any work, naming the scene (before, the dry run
/// passed and the run failed only once the scene's frames began); the plan names the bytes.
#[test]
fn an_animated_specs_fields_are_held_against_the_limit_in_the_dry_run() {
    // 290 maps × 64² texels of 1 byte (u8, the default) = 1.13 MiB, over a 1 MiB limit.
    let text = animated(common::ORBIT, "", common::TWO_FRAMES)
        .replace(r#""resolutions": [16]"#, r#""resolutions": [64]"#);
    assert!(text.contains("[64]"));
    for dry_run in [true, false] {
        let dir = tempfile::tempdir().unwrap();
        let ls = loaded(dir.path(), &text);
        let mut o = options(dir.path().join("out"));
        o.dry_run = dry_run;
        o.supply.memory_limit = 1 << 20;
        let e = run(&ls, &o).unwrap_err().to_string();
        assert!(
            e.contains("scenes[0] (tiny)")
                && e.contains("1.13 MiB")
                && e.contains("--max-memory-mib"),
            "{e}"
        );
        assert!(!dir.path().join("out").exists());
    }
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &text);
    let mut o = options(dir.path().join("out"));
    o.dry_run = true;
    let report = run(&ls, &o).unwrap();
    assert!(
        report
            .plan_text
            .contains("fields kept for every frame: tiny 1.13 MiB"),
        "{}",
        report.plan_text
    );
}
