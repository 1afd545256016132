//! Soft shadows as a render kind (Gaitatzes et al. 2010, §4.2): the spec's lights and their
//! errors, a light inside a caster refused before any work, and a tiny run end to end whose
//! same-ray reference is the light fraction computed here from the scene alone.

use std::path::Path;
use visfield::experiment::run::run;
use visfield::experiment::scenes::Scenes;
use visfield::experiment::spec::{Spec, SpecError};

mod common;
use common::{assert_png_is, loaded, options, tiny, ONE_FIELD};

const LIGHTS: &str = r#"[{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }, { "center": [-0.5, 3.0, 1.5], "radius": 0.5, "intensity": 2 }]"#;

/// The tiny spec rendering shadows with `lights` (JSON) and `extra` keys in `render`.
fn shadows(lights: &str, extra: &str) -> String {
    tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
        &format!(
            r#""render": {{ "what": "shadows", "rays_per_point": 16, "image": {{ "width": 32, "height": 32 }}, "lights": {lights}{extra} }}"#
        ),
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
fn lights_are_read_and_bad_ones_refused_naming_the_field() {
    let s = Spec::parse(&shadows(LIGHTS, ""), Path::new("ok.json")).unwrap();
    assert_eq!(s.render.rays_per_point, 16);
    let e = error_of(&shadows("[]", ""));
    assert!(
        e.contains("lights") && e.contains("at least one light"),
        "{e}"
    );
    let e = error_of(&shadows(LIGHTS, "").replace(r#", "lights": "#, r#", "lightz": "#));
    assert!(e.contains("lightz"), "{e}");
    let e = error_of(&shadows(
        &LIGHTS.replace("\"radius\": 0.3", "\"radius\": -0.3"),
        "",
    ));
    assert!(
        e.contains("field `render.lights[0].radius`") && e.contains("-0.3"),
        "{e}"
    );
    // Radius 0 is a point light; above the world's range, or not a number, is refused.
    Spec::parse(
        &shadows(&LIGHTS.replace("\"radius\": 0.3", "\"radius\": 0"), ""),
        Path::new("ok.json"),
    )
    .unwrap();
    let e = error_of(&shadows(
        &LIGHTS.replace("\"radius\": 0.3", "\"radius\": 2e18"),
        "",
    ));
    assert!(
        e.contains("field `render.lights[0].radius`") && e.contains("point light"),
        "{e}"
    );
    let e = error_of(&shadows(
        &LIGHTS.replace("\"intensity\": 2", "\"intensity\": 0"),
        "",
    ));
    assert!(e.contains("field `render.lights[1].intensity`"), "{e}");
    let e = error_of(&shadows(&LIGHTS.replace("2.5, 2.6", "1e39, 2.6"), ""));
    assert!(e.contains("render"), "{e}");
    // Keys of other kinds, and the other way round.
    let e = error_of(&shadows(LIGHTS, r#", "max_distance": 0.5"#));
    assert!(e.contains("max_distance") && e.contains("shadows"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""image": { "width": 32, "height": 32 } }"#,
        &format!(r#""image": {{ "width": 32, "height": 32 }}, "lights": {LIGHTS} }}"#),
    ));
    assert!(e.contains("lights") && e.contains("vertex_ao"), "{e}");
    // Both backends are accepted (the GPU's shadow kernels: tests/gpu_shadow.rs); Fibonacci
    // point sets are still refused with "gpu", as for AO.
    let both = shadows(LIGHTS, "").replace(
        r#""reference": {"#,
        r#""backends": ["cpu", "gpu"], "reference": {"#,
    );
    Spec::parse(&both, Path::new("ok.json")).unwrap();
    let e = error_of(&both.replace(
        r#""counts": [290]"#,
        r#""spheres": ["fibonacci"], "counts": [290]"#,
    ));
    assert!(e.contains("fibonacci") && e.contains("gpu"), "{e}");
    // Reflections read the lights too, but need the receiver's lobe.
    let e = error_of(&shadows(LIGHTS, "").replace("\"shadows\"", "\"reflections\""));
    assert!(e.contains("reflections") && e.contains("gloss"), "{e}");
}

#[test]
fn a_light_inside_a_casters_sphere_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    // The caster's sphere: centre (0.5, 0.45, 0.5), radius 0.35.
    let text = shadows(
        r#"[{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }, { "center": [0.5, 0.9, 0.5], "radius": 0.2, "intensity": 1 }]"#,
        "",
    );
    let ls = loaded(dir.path(), &text);
    let out = dir.path().join("out");
    let e = run(&ls, &options(out.clone())).unwrap_err().to_string();
    assert!(
        e.contains("render.lights[1]") && e.contains("caster instance 1"),
        "{e}"
    );
    assert!(!out.exists(), "nothing written for a refused spec");
}

/// A tiny run: one row with the per-pixel columns, `rays_cast` = pixels × k² × lights, a
/// same-ray reference equal to the light fraction computed here from the scene alone, and its
/// shaded picture equal to that fraction times the direct light.
#[test]
fn a_shadow_run_measures_the_light_fraction_at_the_receiver_pixels() {
    use visfield::render::camera::Camera;
    use visfield::render::primary::{gbuffer, PrimaryScene};
    use visfield::render::shadow::{direct_light, shadow_at_points, ShadowOptions, SphereLight};
    use visfield::sampling::rays::RaySet;
    use visfield::trace::Tracer;

    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &shadows(LIGHTS, ""));
    let out = dir.path().join("out");
    let report = run(&ls, &options(out.clone())).unwrap();
    let r = &report.rows[0];
    assert!(r.rms_vertex.is_none());
    assert!(r.rms_image.unwrap().is_finite() && r.rms_vs_truth.unwrap().is_finite());
    assert_eq!(r.rays_cast, r.receiver_points as u64 * 16 * 2);
    assert!(out.join(&r.image).exists());

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
    assert_eq!(pts.len(), r.receiver_points);
    let lights: Vec<SphereLight> = serde_json::from_str(LIGHTS).unwrap();
    let opts = ShadowOptions { offset, lights };
    let tracer = Tracer::new(&bs.scene.caster_triangles());
    let exact = shadow_at_points(
        &tracer,
        &pts.origins,
        &pts.normals,
        &RaySet::new(4, 1),
        &opts,
    );
    // Some pixels are in the caster's shadow, some lit.
    assert!(exact.iter().any(|&v| v < 0.5) && exact.contains(&1.0));
    let (img, _) = pts.image(&bs.scene, &gbuf, &exact);
    assert_png_is(&out.join(format!("images/{}-reference.png", bs.name)), &img);
    // The shaded picture: the light fraction times the unshadowed direct light (normalised to
    // the brightest pixel), for the reference and for the cell.
    let direct = direct_light(&pts.origins, &pts.normals, &RaySet::new(8, 1), &opts);
    assert!((direct.iter().copied().fold(0.0f32, f32::max) - 1.0).abs() < 1e-6);
    let shaded: Vec<f32> = exact.iter().zip(&direct).map(|(v, d)| v * d).collect();
    let (img, _) = pts.image(&bs.scene, &gbuf, &shaded);
    assert_png_is(
        &out.join(format!("images/{}-reference-shaded.png", bs.name)),
        &img,
    );
    let cell_shaded = r.image.replace(".png", "-shaded.png");
    assert!(out.join(cell_shaded).exists());
}
