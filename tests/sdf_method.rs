//! The `sdf` method through the harness: one row per (res, precision, query), its bytes the
//! stored samples exactly, its bakes served from the run's cache on a second run and rebaked
//! when the cache file is damaged; the cone query as a direct estimator of AO and shadows,
//! refused by name for reflections and for AO with a distance falloff.

use std::path::Path;
use visfield::experiment::columns::{read_csv, NamedRow};
use visfield::experiment::run::run;
use visfield::experiment::spec::Spec;
use visfield::sdf::DistanceVolume;

mod common;
use common::{loaded, options, supershape_2000, tiny, ONE_FIELD};

const SWEEP: &str =
    r#"[{"method": "sdf", "res": [16], "precision": ["f32", "u8"], "query": ["trace", "cone"]}]"#;

fn with_methods(spec: &str, methods: &str) -> String {
    spec.replace(
        r#""reference": {"#,
        &format!(r#""methods": {methods}, "reference": {{"#),
    )
}

/// The tiny spec's rows of `methods.csv` after a run into `out` with the cache `cache`.
fn rows(dir: &Path, text: &str, out: &str, cache: &Path) -> Vec<NamedRow> {
    let ls = loaded(dir, text);
    let out = dir.join(out);
    let mut o = options(out.clone());
    o.supply.cache = Some(cache.to_path_buf());
    run(&ls, &o).unwrap();
    read_csv(&out.join("methods.csv")).unwrap()
}

fn column<'a>(rows: &'a [NamedRow], name: &str) -> Vec<&'a str> {
    rows.iter().map(|r| r.get(name).unwrap_or("")).collect()
}

#[test]
fn an_sdf_sweep_counts_its_bytes_and_caches_its_bakes() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let text = with_methods(&tiny(ONE_FIELD, ""), SWEEP);
    let first = rows(dir.path(), &text, "a", &cache);
    assert_eq!(
        column(&first, "setting"),
        [
            "sdf-16-f32-trace",
            "sdf-16-f32-cone",
            "sdf-16-u8-trace",
            "sdf-16-u8-cone"
        ]
    );
    assert_eq!(
        column(&first, "through"),
        ["rays", "direct", "rays", "direct"]
    );
    assert_eq!(column(&first, "cones"), ["", "9", "", "9"]);
    // The first setting bakes; the others read the cache or derive from it.
    assert_eq!(
        column(&first, "precompute_cached"),
        ["false", "true", "true", "true"]
    );
    // The bytes: the caster mesh's volume, 4 and 1 bytes a sample.
    let m = supershape_2000();
    let tris: Vec<_> = (0..m.triangle_count()).map(|i| m.triangle(i)).collect();
    let samples = DistanceVolume::bake(&tris, 16, 2)
        .unwrap()
        .dims
        .iter()
        .product::<usize>() as f64;
    let bytes: Vec<f64> = first.iter().map(|r| r.number("bytes").unwrap()).collect();
    assert_eq!(bytes, [4.0 * samples, 4.0 * samples, samples, samples]);
    for r in &first {
        let e = r.number("rms_vs_raycast").unwrap();
        assert!(e.is_finite() && e >= 0.0, "{e}");
        assert!(r.number("rms_vs_truth").unwrap().is_finite());
    }
    // A second run reads every volume from the cache.
    let second = rows(dir.path(), &text, "b", &cache);
    assert_eq!(column(&second, "precompute_cached"), ["true"; 4]);
    // The same volumes, the same values: the same errors.
    assert_eq!(
        column(&second, "rms_vs_truth"),
        column(&first, "rms_vs_truth")
    );
    // A damaged f32 file is rebaked (the u8 one still derives from the new f32 volume).
    for e in std::fs::read_dir(&cache).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with("sdf-16-m2-f32-") || name.starts_with("sdf-16-m2-u8-") {
            let mut b = std::fs::read(&p).unwrap();
            let n = b.len();
            b[n - 1] ^= 1;
            std::fs::write(&p, b).unwrap();
        }
    }
    let third = rows(dir.path(), &text, "c", &cache);
    assert_eq!(
        column(&third, "precompute_cached"),
        ["false", "true", "true", "true"]
    );
    assert_eq!(
        column(&third, "rms_vs_truth"),
        column(&first, "rms_vs_truth")
    );
}

const LIGHTS: &str = r#"[{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }, { "center": [-0.5, 3.0, 1.5], "radius": 0.5, "intensity": 2 }]"#;

fn render(what: &str, extra: &str) -> String {
    tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
        &format!(
            r#""render": {{ "what": "{what}", "rays_per_point": 16, "image": {{ "width": 32, "height": 32 }}{extra} }}"#
        ),
    )
}

#[test]
fn cones_answer_shadows_directly() {
    let dir = tempfile::tempdir().unwrap();
    let text = with_methods(
        &render("shadows", &format!(r#", "lights": {LIGHTS}"#)),
        r#"[{"method": "sdf", "res": [16], "query": ["trace", "cone"], "cones": 5}]"#,
    );
    let rows = rows(dir.path(), &text, "s", &dir.path().join("cache"));
    assert_eq!(column(&rows, "through"), ["rays", "direct"]);
    // One cone per light.
    assert_eq!(column(&rows, "cones"), ["", "2"]);
    for r in &rows {
        assert!(r.number("rms_vs_raycast").unwrap().is_finite());
    }
}

#[test]
fn cones_are_refused_by_name_where_they_cannot_answer() {
    let parse = |text: &str| {
        Spec::parse(text, Path::new("specs/m.json"))
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let cone = r#"[{"method": "sdf", "res": [16], "query": ["cone"]}]"#;
    let e = parse(&with_methods(
        &render(
            "reflections",
            &format!(r#", "lights": {LIGHTS}, "gloss": "mirror""#),
        ),
        cone,
    ))
    .unwrap_err();
    assert!(
        e.contains("methods[0]") && e.contains("\"reflections\"") && e.contains("cone"),
        "{e}"
    );
    // The trace answers reflections.
    let trace = r#"[{"method": "sdf", "res": [16], "query": ["trace"]}]"#;
    parse(&with_methods(
        &render(
            "reflections",
            &format!(r#", "lights": {LIGHTS}, "gloss": "mirror""#),
        ),
        trace,
    ))
    .unwrap();
    let e = parse(&with_methods(
        &render("vertex_ao", r#", "max_distance": 0.5, "falloff": "linear""#),
        cone,
    ))
    .unwrap_err();
    assert!(e.contains("falloff") && e.contains("cone"), "{e}");
    // Bad keys, named.
    for (methods, want) in [
        (
            r#"[{"method": "sdf", "res": [16], "precision": ["f8"]}]"#,
            "f8",
        ),
        (
            r#"[{"method": "sdf", "res": [16], "query": ["beam"]}]"#,
            "beam",
        ),
        (
            r#"[{"method": "sdf", "res": [16], "precision": ["u8", "u8"]}]"#,
            "methods[0].precision[1]",
        ),
        (
            r#"[{"method": "sdf", "res": [16], "cones": 1}]"#,
            "methods[0].cones",
        ),
        (
            r#"[{"method": "sdf", "res": [16], "step": 0}]"#,
            "methods[0].step",
        ),
        (
            r#"[{"method": "sdf", "res": [16], "margin": 0}]"#,
            "methods[0].margin",
        ),
    ] {
        let e = parse(&with_methods(&tiny(ONE_FIELD, ""), methods)).unwrap_err();
        assert!(e.contains(want), "{methods}: {e}");
    }
}

/// `backends` on a method entry: the GPU refused by name where the setting has no kernel for
/// the kind (sphere-traced shadows, our ray caster), an empty list refused, and a sound entry
/// read back with its backends (the GPU rows themselves: tests/gpu_peers.rs).
#[test]
fn gpu_backends_of_methods_are_refused_by_name_where_no_kernel_answers() {
    let parse = |text: &str| {
        Spec::parse(text, Path::new("specs/m.json"))
            .map(|s| {
                s.methods
                    .iter()
                    .map(|m| m.backends.len())
                    .collect::<Vec<_>>()
            })
            .map_err(|e| e.to_string())
    };
    let shadows = render("shadows", &format!(r#", "lights": {LIGHTS}"#));
    let e = parse(&with_methods(
        &shadows,
        r#"[{"method": "sdf", "res": [16], "query": ["trace"], "backends": ["cpu", "gpu"]}]"#,
    ))
    .unwrap_err();
    assert!(
        e.contains("methods[0]") && e.contains("on backend \"gpu\"") && e.contains("trace"),
        "{e}"
    );
    // The cones answer shadows on the GPU.
    let cone = r#"[{"method": "sdf", "res": [16], "query": ["cone"], "backends": ["cpu", "gpu"]}]"#;
    assert_eq!(parse(&with_methods(&shadows, cone)), Ok(vec![2]));
    let ao = tiny(ONE_FIELD, "");
    let e = parse(&with_methods(
        &ao,
        r#"[{"method": "raycast", "backends": ["gpu"]}]"#,
    ))
    .unwrap_err();
    assert!(
        e.contains("methods[0]") && e.contains("no GPU kernel"),
        "{e}"
    );
    let e = parse(&with_methods(
        &ao,
        r#"[{"method": "aofield", "res": [8], "backends": []}]"#,
    ))
    .unwrap_err();
    assert!(e.contains("backends") && e.contains("aofield"), "{e}");
    let e = parse(&with_methods(
        &ao,
        r#"[{"method": "aofield", "res": [8], "backends": ["tpu"]}]"#,
    ))
    .unwrap_err();
    assert!(e.contains("backends") && e.contains("tpu"), "{e}");
    // The same setting twice on one backend.
    let e = parse(&with_methods(
        &ao,
        r#"[{"method": "aofield", "res": [8], "backends": ["gpu", "gpu"]}]"#,
    ))
    .unwrap_err();
    assert!(e.contains("aofield-8") && e.contains("twice"), "{e}");
}
