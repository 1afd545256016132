//! Extreme finite numbers in every numeric field of a spec: validation either refuses the value
//! naming the field, or everything before the run's work (scenes, the plan, the reference
//! tracer over the casters) and the whole run take it without a panic, an abort or a hang.

mod common;

use common::{tiny, ONE_FIELD};
use std::path::Path;
use visfield::experiment::plan::{Plan, PlanLimits};
use visfield::experiment::run::run;
use visfield::experiment::scenes::Scenes;
use visfield::experiment::spec::Spec;
use visfield::trace::Tracer;

/// Numbers a user may type: zeros, signs, tiny and huge magnitudes, the f32 edges.
const EXTREMES: [&str; 14] = [
    "0", "-0", "1e-45", "-1e-45", "1e-30", "1e-7", "-1", "0.5", "7", "1e7", "1e30", "3e38",
    "-3.4e38", "1e300",
];

/// The tiny spec with camera, transform and render numbers made explicit, so each can be
/// replaced: `{N}` marks the slots.
fn slots() -> Vec<String> {
    let base = tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
        r#""render": { "what": "image_ao", "rays_per_point": 16, "max_distance": {N}, "image": { "width": 32, "height": 32, "camera": { "eye": [{N}, 2, 2], "target": [0.4, {N}, 0.4], "fov_y_deg": {N} } } }"#,
    );
    let fit = r#""transform": { "fit": { "center": [0.5, 0.45, 0.5], "radius": 0.35 } }"#;
    let variants = [
        r#""transform": { "fit": { "center": [{N}, 0.45, 0.5], "radius": 0.35 } }"#,
        r#""transform": { "fit": { "center": [0.5, 0.45, 0.5], "radius": {N} } }"#,
        r#""transform": { "translate": [{N}, 0, 0] }"#,
        r#""transform": { "scale": {N} }"#,
        r#""transform": { "rotate_deg": [{N}, 0, 0], "fit": { "center": [0.5, 0.45, 0.5], "radius": 0.35 } }"#,
    ];
    let mut out = Vec::new();
    // Each slot on its own, the others at a sane value.
    let sane = ["2", "0.3", "40"];
    let n_render = base.matches("{N}").count();
    for i in 0..n_render {
        let mut k = 0;
        let mut text = String::new();
        for (j, part) in base.split("{N}").enumerate() {
            text.push_str(part);
            if j < n_render {
                text.push_str(if k == i { "{N}" } else { sane[k.min(2)] });
                k += 1;
            }
        }
        out.push(text);
    }
    let render_sane = out[0].replacen("{N}", "2", 1);
    for v in variants {
        out.push(render_sane.replace(fit, v));
    }
    out
}

#[test]
fn extreme_numbers_are_refused_or_taken_without_a_panic() {
    let (mut refused, mut taken) = (0, 0);
    for template in slots() {
        for x in EXTREMES {
            let text = template.replace("{N}", x);
            let result = std::panic::catch_unwind(|| {
                let spec = match Spec::parse(&text, Path::new("extreme.json")) {
                    Ok(s) => s,
                    Err(e) => {
                        assert!(e.to_string().starts_with("extreme.json: "), "{e}");
                        return false;
                    }
                };
                let scenes = match Scenes::build(&spec, Path::new("extreme.json"), "scenes") {
                    Ok(s) => s,
                    Err(e) => {
                        assert!(e.to_string().contains("scenes[0]"), "{e}");
                        return false;
                    }
                };
                let plan = Plan::new(
                    &spec,
                    &scenes,
                    PlanLimits {
                        memory_limit: 1 << 30,
                    },
                );
                let plan = plan.expect("a validated spec plans");
                let _ = plan.describe("extreme", &scenes, &|_, _| "bake");
                for bs in &scenes.scenes {
                    let _ = Tracer::new(&bs.scene.caster_triangles());
                    let _ = bs.bounds();
                }
                // The whole run: a result or an error, never a panic.
                let dir = tempfile::tempdir().unwrap();
                let ls = common::loaded(dir.path(), &text);
                let _ = run(&ls, &common::options(dir.path().join("out")));
                true
            });
            match result {
                Ok(true) => taken += 1,
                Ok(false) => refused += 1,
                Err(_) => panic!("a panic on {x} in:\n{template}"),
            }
        }
    }
    eprintln!("extreme values: {taken} taken, {refused} refused");
    // Both outcomes occur: the sweep is not all refusals.
    assert!(
        taken > 10 && refused > 10,
        "taken {taken}, refused {refused}"
    );
}

/// The whole tiny scene translated by 1e12 or 1e15 gives the untranslated run's values bit for
/// bit (the rebased frame removes the translation exactly); by 1e20 it is refused, naming the
/// scene's instances and the ratio f64 can hold. Before the fix 1e12 changed the per-vertex
/// RMS (12.10 against 12.44) and 1e15 reported AO 1 everywhere with every RMS 0.
#[test]
fn a_translated_scene_gives_the_same_values_or_is_refused() {
    // Vertex AO without an image: a spec camera is f32 and cannot follow the scene that far.
    let base = tiny(ONE_FIELD, "").replace(r#", "image": { "width": 32, "height": 32 }"#, "");
    let fit = r#""transform": { "fit": { "center": [0.5, 0.45, 0.5], "radius": 0.35 } }"#;
    let translated = |t: &str| {
        base.replace(
            r#""receiver": true }"#,
            &format!(r#""receiver": true, "transform": {{ "translate": [{t}, {t}, {t}] }} }}"#),
        )
        .replace(
            fit,
            &format!(
                r#""transform": {{ "translate": [{t}, {t}, {t}], "fit": {{ "center": [0.5, 0.45, 0.5], "radius": 0.35 }} }}"#
            ),
        )
    };
    let values = |text: &str| {
        let dir = tempfile::tempdir().unwrap();
        let ls = common::loaded(dir.path(), text);
        let mut o = common::options(dir.path().join("out"));
        o.supply.memory_limit = 1 << 30;
        let r = run(&ls, &o).unwrap();
        let row = &r.rows[0];
        (row.rms_vertex, row.rms_vs_truth, row.crease_points)
    };
    let here = values(&base);
    assert!(here.0.unwrap() > 0.0 && here.2 > 0, "{here:?}");
    for t in ["1e12", "1e15"] {
        let text = translated(t);
        assert!(text.matches("translate").count() == 2, "{text}");
        assert_eq!(values(&text), here, "translated by {t}");
    }
    let e = Scenes::build(
        &Spec::parse(&translated("1e20"), Path::new("far.json")).unwrap(),
        Path::new("far.json"),
        "scenes",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("scenes[0].instances") && e.contains("ratio") && e.contains("1.801e16"),
        "{e}"
    );
}

/// A distant object leaves the AO where it was: a sphere of radius 0.1 placed 1000 away (a
/// caster, with its own field) changes neither the receivers' ray offsets (each point's is its
/// own instance's) nor any reference value. With the offset of the whole scene's radius it
/// rose from 8.7e-5 to 0.05 and changed the AO at 76 of 243 points by up to 0.375.
#[test]
fn a_distant_object_leaves_the_ao_unchanged() {
    let base = tiny(ONE_FIELD, "").replace(r#", "image": { "width": 32, "height": 32 }"#, "");
    let far = base.replace(
        r#""receiver": true }"#,
        r#""receiver": true },
      { "mesh": { "sphere": { "radius": 0.1, "stacks": 8, "slices": 16 } }, "caster": true,
        "transform": { "translate": [1000, 0, 0] } }"#,
    );
    assert_ne!(far, base);
    let reference = |text: &str| {
        let dir = tempfile::tempdir().unwrap();
        let ls = common::loaded(dir.path(), text);
        run(&ls, &common::options(dir.path().join("out"))).unwrap();
        let csv = std::fs::read_to_string(dir.path().join("out/values_tiny.csv")).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = header.iter().position(|&h| h == "reference").unwrap();
        lines
            .map(|l| l.split(',').nth(col).unwrap().to_string())
            .collect::<Vec<_>>()
    };
    let (here, with_far) = (reference(&base), reference(&far));
    assert_eq!(here.len(), 243);
    assert!(here.iter().any(|v| v != "1"), "some points are occluded");
    assert_eq!(here, with_far);
}

/// Found by `examples/fuzz_numbers`: a 504,600-triangle corner scaled to 1e-7 beside a caster
/// 65,536 away stalled the BVH build for minutes (every triangle in one cell of the builder's
/// Morton grid). An instance below 2⁻²¹ of its scene's radius is now refused, naming it,
/// before any BVH is built.
#[test]
fn an_instance_too_small_for_its_scene_is_refused_before_any_bvh() {
    let text = tiny(ONE_FIELD, "")
        .replace(r#""corner": { "n": 9 }"#, r#""corner": { "n": 290 }"#)
        .replace(
            r#""receiver": true }"#,
            r#""receiver": true, "transform": { "scale": 1e-7 } }"#,
        )
        .replace(
            r#""transform": { "fit""#,
            r#""transform": { "translate": [0, 65536, 0], "fit""#,
        );
    assert!(text.contains("1e-7") && text.contains("65536"), "{text}");
    let spec = Spec::parse(&text, Path::new("small.json")).unwrap();
    let t = std::time::Instant::now();
    let Err(e) = Scenes::build(&spec, Path::new("small.json"), "scenes") else {
        panic!("an instance 2.6e-12 of its scene's radius was accepted");
    };
    let e = e.to_string();
    assert!(
        e.contains("scenes[0].instances[0].transform") && e.contains("2⁻²¹"),
        "{e}"
    );
    assert!(t.elapsed().as_secs_f64() < 10.0, "{:?}", t.elapsed());
}
