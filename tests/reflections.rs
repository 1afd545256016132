//! Glossy reflections as a render kind (Gaitatzes et al. 2010, §4.2, Figure 9): the spec's keys
//! and their errors, the normal fields planned only where reflections read them, and a tiny
//! run end to end: one cell per normal precision, the normal field's bytes counted exactly, the
//! same-ray reference computed here from the scene alone, and the mirror as second reference.

use std::path::Path;
use visfield::experiment::run::run;
use visfield::experiment::scenes::Scenes;
use visfield::experiment::spec::{Spec, SpecError};

mod common;
use common::{assert_png_is, loaded, options, tiny, ONE_FIELD};

const LIGHTS: &str = r#"[{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }, { "center": [-0.5, 3.0, 1.5], "radius": 0.5, "intensity": 2 }]"#;
const GLOSS: &str = r#""gloss": { "phong": { "exponent": 20 } }"#;

/// The tiny spec rendering reflections with 4 rays per pixel (its same-ray reference too) and
/// `extra` keys in `render` (after `lights`).
fn reflections(extra: &str) -> String {
    tiny(ONE_FIELD, "")
        .replace(
            r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
            &format!(
                r#""render": {{ "what": "reflections", "rays_per_point": 4, "image": {{ "width": 32, "height": 32 }}, "lights": {LIGHTS}{extra} }}"#
            ),
        )
        .replace(
            r#""reference": { "rays_per_point": 16,"#,
            r#""reference": { "rays_per_point": 4,"#,
        )
}

fn error_of(text: &str) -> String {
    let e: SpecError =
        Spec::parse(text, Path::new("specs/bad.json")).expect_err("the spec should be rejected");
    let e = e.to_string();
    assert!(e.starts_with("specs/bad.json: "), "{e}");
    e
}

#[test]
fn reflection_keys_are_read_and_bad_ones_refused_naming_the_field() {
    use visfield::experiment::kinds::reflections::{ReflectionRender, DEFAULT_ALBEDO, DEFAULT_SKY};
    use visfield::experiment::spec::RenderSpec;
    use visfield::render::reflect::Gloss;
    let s = Spec::parse(&reflections(&format!(", {GLOSS}")), Path::new("ok.json")).unwrap();
    assert_eq!(s.render.what, "reflections");
    let r: ReflectionRender = s.render.options_as().expect("reflection options");
    let r = &r;
    assert_eq!(r.gloss, Gloss::Phong { exponent: 20.0 });
    assert_eq!((r.albedo, r.sky), (DEFAULT_ALBEDO, DEFAULT_SKY));
    assert_eq!(r.normal_bits, vec![16]);
    // Round trip through the wire form.
    let back: RenderSpec =
        serde_json::from_str(&serde_json::to_string(&s.render).unwrap()).unwrap();
    assert_eq!(back, s.render);
    let mirror = Spec::parse(&reflections(r#", "gloss": "mirror""#), Path::new("ok.json"));
    assert!(mirror.is_ok());

    let cases: [(&str, &[&str]); 9] = [
        ("", &["gloss", "mirror"]),
        (
            r#", "gloss": { "phong": { "exponent": 0 } }"#,
            &["render.gloss.phong.exponent", "0"],
        ),
        (
            r#", "gloss": { "phong": { "exponent": -3 } }"#,
            &["render.gloss.phong.exponent", "-3"],
        ),
        (r#", "gloss": "glass""#, &["glass"]),
        (
            &format!(", {GLOSS}, \"albedo\": 1.5"),
            &["render.albedo", "1.5"],
        ),
        (
            &format!(", {GLOSS}, \"sky\": -0.1"),
            &["render.sky", "-0.1"],
        ),
        (
            &format!(", {GLOSS}, \"normal_bits\": [8, 12]"),
            &["render.normal_bits[1]", "12"],
        ),
        (
            &format!(", {GLOSS}, \"normal_bits\": [16, 16]"),
            &["render.normal_bits[1]", "at most once"],
        ),
        (
            &format!(", {GLOSS}, \"normal_bits\": []"),
            &["render.normal_bits", "empty"],
        ),
    ];
    for (extra, want) in cases {
        let e = error_of(&reflections(extra));
        assert!(want.iter().all(|w| e.contains(w)), "{extra}: {e}");
    }
    // No lights; a falloff; a reflection key on another kind.
    let e = error_of(&reflections(&format!(", {GLOSS}")).replace(LIGHTS, "[]"));
    assert!(e.contains("lights") && e.contains("reflections"), "{e}");
    let e = error_of(&reflections(&format!(", {GLOSS}, \"falloff\": \"linear\"")));
    assert!(e.contains("falloff") && e.contains("reflections"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""image": { "width": 32, "height": 32 } }"#,
        r#""image": { "width": 32, "height": 32 }, "sky": 0.5 }"#,
    ));
    assert!(e.contains("sky") && e.contains("vertex_ao"), "{e}");
    // The GPU backend is accepted (tests/gpu_reflect.rs runs it).
    let gpu = reflections(&format!(", {GLOSS}")).replace(
        r#""reference": {"#,
        r#""backends": ["cpu", "gpu"], "reference": {"#,
    );
    assert!(Spec::parse(&gpu, Path::new("ok.json")).is_ok());
}

/// The plan bakes normal fields for reflections only, and says so.
#[test]
fn normal_fields_are_planned_only_for_reflections() {
    let dir = tempfile::tempdir().unwrap();
    for (text, normals) in [
        (
            reflections(&format!(", {GLOSS}, \"normal_bits\": [8, 16]")),
            true,
        ),
        (tiny(ONE_FIELD, ""), false),
    ] {
        let ls = loaded(dir.path(), &text);
        let mut o = options(dir.path().join("out"));
        o.dry_run = true;
        let t = run(&ls, &o).unwrap().plan_text;
        let bake = t
            .lines()
            .find(|l| l.contains("bake supershape2000"))
            .expect(&t);
        if normals {
            // 290 × 16² texels: 72.50 KiB of u8 distances, and 4 bytes a texel per normal
            // precision held in memory (the 16-bit bake and the 8-bit one derived from it).
            assert!(t.contains("normal fields: yes"), "{t}");
            assert!(
                bake.contains("+ normal field") && bake.contains("652.50 KiB"),
                "{bake}"
            );
            assert!(t.contains("lookup tiny-slater-290-concentric-16-u8-nearest-cpu-n8"));
            assert!(t.contains("lookup tiny-slater-290-concentric-16-u8-nearest-cpu-n16"));
        } else {
            assert!(t.contains("normal fields: no"), "{t}");
            assert!(!bake.contains("normal"), "{bake}");
        }
    }
}

/// A tiny run: one row per normal precision, the normal field's bytes in `field_bytes`
/// (2 × bits / 8 per texel), the same-ray reference equal to the reflected radiance computed
/// here from the scene alone, and the mirror as the second reference; with a broad lobe the
/// field's image is closer to the same-ray glossy reference than to the mirror.
#[test]
fn a_reflection_run_measures_the_reflected_radiance_at_the_receiver_pixels() {
    use visfield::render::camera::Camera;
    use visfield::render::primary::{gbuffer, PrimaryScene};
    use visfield::render::reflect::{reflect_at_points, Gloss, ReflectOptions};
    use visfield::render::shadow::SphereLight;
    use visfield::sampling::rays::RaySet;
    use visfield::trace::Tracer;

    let dir = tempfile::tempdir().unwrap();
    let text = reflections(&format!(", {GLOSS}, \"normal_bits\": [8, 16]"));
    let ls = loaded(dir.path(), &text);
    let out = dir.path().join("out");
    let report = run(&ls, &options(out.clone())).unwrap();
    assert_eq!(report.rows.len(), 2);
    let (r8, r16) = (&report.rows[0], &report.rows[1]);
    assert_eq!((r8.normal_bits, r16.normal_bits), (Some(8), Some(16)));
    // 290 maps × 256 texels: the u8 distances, then 2 or 4 bytes of normal per texel.
    let texels = 290 * 256;
    assert_eq!(r8.field_bytes, texels + 2 * texels);
    assert_eq!(r16.field_bytes, texels + 4 * texels);
    for r in [r8, r16] {
        assert_eq!(r.rays_cast, r.receiver_points as u64 * 4);
        assert_eq!(r.second_reference.as_deref(), Some("mirror"));
        let (same_ray, vs_mirror) = (r.rms_image.unwrap(), r.rms_image_vs_second.unwrap());
        assert!(same_ray.is_finite() && r.rms_vs_truth.unwrap().is_finite());
        assert!(
            vs_mirror > same_ray,
            "vs mirror {vs_mirror}, same-ray {same_ray}"
        );
        assert!(out.join(&r.image).exists());
    }

    // The same pixels and reference from the scene alone.
    let scenes = Scenes::build(&ls.spec, &ls.path, "scenes").unwrap();
    let bs = &scenes.scenes[0];
    let cam = bs.camera_in_frame(&Camera::corner());
    let hits = gbuffer(&PrimaryScene::new(&bs.scene), &cam, 32, 32);
    let gbuf = visfield::render::points::GBuffer {
        hits,
        width: 32,
        height: 32,
    };
    // The points' origins carry each instance's ray offset: the estimator adds none.
    let pts = visfield::render::points::EvalPoints::pixels(&bs.scene, &gbuf);
    let offset = 0.0;
    assert_eq!(pts.len(), r8.receiver_points);
    let lights: Vec<SphereLight> = serde_json::from_str(LIGHTS).unwrap();
    let opts = ReflectOptions {
        offset,
        eye: cam.eye,
        gloss: Gloss::Phong { exponent: 20.0 },
        lights,
        albedo: 0.8,
        sky: 0.3,
    };
    let tracer = Tracer::new(&bs.scene.caster_triangles());
    let rays = RaySet::new(2, 1);
    let exact = reflect_at_points(&tracer, &pts.origins, &pts.normals, &rays, &opts);
    // Some pixels reflect the caster, some the sky.
    assert!(exact.iter().any(|&v| v != 0.3) && exact.contains(&0.3));
    let (img, _) = pts.image(&bs.scene, &gbuf, &exact);
    assert_png_is(&out.join(format!("images/{}-reference.png", bs.name)), &img);
    let mirror = reflect_at_points(&tracer, &pts.origins, &pts.normals, &rays, &opts.mirror());
    let (img, _) = pts.image(&bs.scene, &gbuf, &mirror);
    assert_png_is(
        &out.join(format!("images/{}-reference-mirror.png", bs.name)),
        &img,
    );
}
