//! The experiment harness: spec errors, the planner, an end-to-end run of a tiny spec, the
//! threshold check, and every shipped spec.

use glam::{Quat, Vec3};
use std::path::Path;
use visfield::experiment::check::check_rows;
use visfield::experiment::fields::requantize;
use visfield::experiment::outputs::read_csv;
use visfield::experiment::plan::{Plan, PlanLimits, Step};
use visfield::experiment::run::{run, LoadedSpec};
use visfield::experiment::scenes::Scenes;
use visfield::experiment::spec::{Spec, SpecError, Threshold};
use visfield::experiment::table::{Row, TABLE_COLUMNS};
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::{FieldParams, Precision};
use visfield::geometry::procedural;
use visfield::sampling::{LayoutKind, SphereKind};

mod common;
use common::{loaded, options, tiny, ONE_FIELD};

fn parse(text: &str) -> Result<Spec, SpecError> {
    Spec::parse(text, Path::new("specs/bad.json"))
}

/// The error text, asserted to name the file.
fn error_of(text: &str) -> String {
    let e = parse(text)
        .expect_err("the spec should be rejected")
        .to_string();
    assert!(e.starts_with("specs/bad.json: "), "{e}");
    e
}

#[test]
fn spec_errors_name_the_file_the_field_and_what_was_expected() {
    assert!(parse(&tiny(ONE_FIELD, "")).is_ok());

    let e =
        error_of(&tiny(ONE_FIELD, "").replace("\"reproduces\"", "\"colour\": 1, \"reproduces\""));
    assert!(
        e.contains("unknown field `colour`") && e.contains("`reproduces`"),
        "{e}"
    );

    let e = error_of(&tiny(r#"{ "counts": ["many"], "resolutions": [16] }"#, ""));
    assert!(
        e.contains("at `fields[0].counts[0]`") && e.contains("invalid type"),
        "{e}"
    );

    let e = error_of(&tiny(r#"{ "counts": [0], "resolutions": [16] }"#, ""));
    assert!(e.contains("field `fields[0].counts[0]`"), "{e}");

    // 300 is no Slater count 2(2n² + 2n + 1); its neighbours are 290 (n = 8) and 362 (n = 9).
    let e = error_of(&tiny(
        r#"{ "counts": [290, 300], "resolutions": [16] }"#,
        "",
    ));
    assert!(e.contains("field `fields[0].counts[1]`"), "{e}");
    assert!(e.contains("290") && e.contains("362"), "{e}");

    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#"{ "supershape": { "triangles": 2000 } }"#,
        r#"{ "model": "teapot" }"#,
    ));
    assert!(e.contains("scenes[0].instances[1].mesh.model"), "{e}");
    assert!(
        e.contains("unknown model `teapot`") && e.contains("stanford-bunny_39k"),
        "{e}"
    );

    // 200 rays is not k²: the nearest squares are 196 = 14² and 225 = 15².
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""rays_per_point": 16, "image""#,
        r#""rays_per_point": 200, "image""#,
    ));
    assert!(e.contains("field `render.rays_per_point`"), "{e}");
    assert!(e.contains("196") && e.contains("225"), "{e}");

    // The quick profile is checked too, under its own path.
    let e = error_of(
        &tiny(ONE_FIELD, "").replace(r#""quick": {}"#, r#""quick": { "rays_per_point": 15 }"#),
    );
    assert!(e.contains("field `quick.rays_per_point`"), "{e}");

    // The converged reference: at least two batches (their spread is the error estimate), and
    // swept ray counts are k².
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""raycast_sweep": [4, 16]"#,
        r#""raycast_sweep": [4, 16], "truth": { "batches": 1 }"#,
    ));
    assert!(e.contains("field `reference.truth.batches`"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""field_rays_sweep": [16, 64]"#,
        r#""field_rays_sweep": [16, 60]"#,
    ));
    assert!(e.contains("field `reference.field_rays_sweep[1]`"), "{e}");
    assert!(e.contains("49") && e.contains("64"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""raycast_sweep": [4, 16]"#,
        r#""raycast_sweep": [4, 16], "truth": { "colour": 1 }"#,
    ));
    assert!(e.contains("unknown field `colour`"), "{e}");

    // A threshold that matches no cell is a typo.
    let e = error_of(&tiny(
        ONE_FIELD,
        r#"{ "directional_res": 64, "rms_image_max": 1 }"#,
    ));
    assert!(
        e.contains("field `thresholds[0]`") && e.contains("matches no cell"),
        "{e}"
    );
}

/// Negative and zero counts, resolutions and sizes are rejected naming the field.
#[test]
fn negative_or_zero_counts_are_rejected_naming_the_field() {
    // Negative numbers where counts are expected are type errors at the exact path.
    let e = error_of(&tiny(r#"{ "counts": [-290], "resolutions": [16] }"#, ""));
    assert!(
        e.contains("at `fields[0].counts[0]`") && e.contains("-290"),
        "{e}"
    );
    let e = error_of(&tiny(r#"{ "counts": [290], "resolutions": [-16] }"#, ""));
    assert!(e.contains("at `fields[0].resolutions[0]`"), "{e}");
    let e = error_of(&tiny(r#"{ "counts": [290], "resolutions": [0] }"#, ""));
    assert!(e.contains("field `fields[0].resolutions[0]`"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""rays_per_point": 16, "image""#,
        r#""rays_per_point": -16, "image""#,
    ));
    assert!(e.contains("at `render.rays_per_point`"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""rays_per_point": 16, "image""#,
        r#""rays_per_point": 0, "image""#,
    ));
    assert!(e.contains("field `render.rays_per_point`"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""width": 32, "height": 32"#,
        r#""width": 0, "height": 32"#,
    ));
    assert!(e.contains("field `render.image.width`"), "{e}");
    let e = error_of(&tiny(r#"{ "counts": [], "resolutions": [16] }"#, ""));
    assert!(e.contains("field `fields[0].counts`"), "{e}");
}

#[test]
fn every_shipped_spec_parses_and_has_a_plan() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|x| x == "json") {
            let ls = LoadedSpec::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(!ls.spec.reproduces.is_empty());
            assert!(!visfield::experiment::plan::cells_of(&ls.spec.quick()).is_empty());
            names.push(ls.name);
        }
    }
    names.sort();
    for required in ["figure5", "figure6", "figure7", "figure8", "storage"] {
        assert!(
            names.iter().any(|n| n == required),
            "{required} missing: {names:?}"
        );
    }
}

#[test]
fn planner_bakes_each_field_once_and_derives_precisions() {
    // Two selections share one bake; two precisions share one f32 bake and two derivations.
    let fields = r#"{ "counts": [290], "resolutions": [16], "selections": ["nearest", "interpolated"],
                      "precisions": ["u8", "bit1"] }"#;
    let spec = parse(&tiny(fields, "")).unwrap();
    let scenes = Scenes::build(&spec, Path::new("t.json"), "scenes").unwrap();
    let plan = Plan::new(
        &spec,
        &scenes,
        PlanLimits {
            memory_limit: 1 << 30,
        },
    )
    .unwrap();
    assert_eq!(plan.cells.len(), 4);
    assert_eq!(plan.bakes(), 1);
    let derives: Vec<Precision> = plan
        .steps
        .iter()
        .filter_map(|s| match s {
            Step::Derive { to, .. } => Some(*to),
            _ => None,
        })
        .collect();
    assert_eq!(derives, vec![Precision::U8, Precision::Bit1]);
    let lookups = plan
        .steps
        .iter()
        .filter(|s| matches!(s, Step::Lookup { .. }))
        .count();
    assert_eq!(lookups, 4);
    // Peak: the f32 source (290 × 256 × 4 bytes) plus the u8 field (290 × 256 bytes).
    assert_eq!(plan.peak_field_bytes, 290 * 256 * 5);
    // The reference is planned once: 243 corner vertices × 16 rays on each of the 3 seeds.
    let refs: Vec<u64> = plan
        .steps
        .iter()
        .filter_map(|s| match s {
            Step::Reference { rays, .. } => Some(*rays),
            _ => None,
        })
        .collect();
    assert_eq!(refs, vec![243 * 16 * 3]);

    // With the f32 field over the memory limit, each precision is baked on its own.
    let small = PlanLimits {
        memory_limit: 290 * 256 * 2,
    };
    let plan = Plan::new(&spec, &scenes, small).unwrap();
    assert_eq!(plan.bakes(), 2);
    assert!(!plan.steps.iter().any(|s| matches!(s, Step::Derive { .. })));
}

#[test]
fn dry_run_lists_steps_with_rays_and_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let mut o = options(dir.path().join("out"));
    o.dry_run = true;
    let report = run(&ls, &o).unwrap();
    let t = &report.plan_text;
    // Bake: 290 maps × 16² texels, all used by the concentric layout: 74,240 rays, 72.50 KiB.
    let bake = t
        .lines()
        .find(|l| l.contains("bake supershape2000"))
        .expect(t);
    assert!(
        bake.contains("74240") && bake.contains("72.50 KiB"),
        "{bake}"
    );
    // Lookup: 243 vertices × (16 rays × 3 seeds + the field sweep's 64 once) = 27,216;
    // reference: 243 × 16 × 3 seeds = 11,664.
    let lookup = t
        .lines()
        .find(|l| l.contains("lookup tiny-slater-290"))
        .expect(t);
    assert!(lookup.contains("27216"), "{lookup}");
    let reference = t
        .lines()
        .find(|l| l.contains("ray-cast reference tiny"))
        .expect(t);
    assert!(reference.contains("11664"), "{reference}");
    assert!(t.contains("ray-cast reference tiny, 16 rays/point"), "{t}");
    assert!(
        t.contains("converged reference tiny, at most 16384 rays/point"),
        "{t}"
    );
    assert!(t.contains("GPU device: no"), "{t}");
    assert!(report.rows.is_empty());
    assert!(!dir.path().join("out").exists(), "a dry run writes nothing");
}

#[test]
fn tiny_spec_runs_end_to_end_and_check_uses_its_thresholds() {
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let out = dir.path().join("out");
    let report = run(&ls, &options(out.clone())).unwrap();
    let header = std::fs::read_to_string(out.join("table.csv")).unwrap();
    let columns: Vec<&str> = header.lines().next().unwrap().split(',').collect();
    assert_eq!(columns, TABLE_COLUMNS);
    let rows: Vec<Row> = read_csv(&out.join("table.csv")).unwrap();
    assert_eq!(rows, report.rows);
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    assert_eq!((r.positional_samples, r.directional_res), (290, 16));
    assert_eq!(
        (r.receiver_points, r.bake_rays, r.field_bytes),
        (243, 74240, 74240)
    );
    let (rv, ri) = (r.rms_vertex.unwrap(), r.rms_image.unwrap());
    assert!(rv.is_finite() && ri.is_finite() && rv >= 0.0 && ri >= 0.0);
    // Against the converged reference: present, finite, and its noise floor below what a
    // 16-ray ray cast misses by (a 16-ray AO is far noisier than the converged one).
    assert_eq!(r.seeds, 3);
    assert!(r.rms_vertex_sd.unwrap().is_finite() && r.rms_image_sd.unwrap().is_finite());
    let (t, ts) = (r.rms_vs_truth.unwrap(), r.truth_stderr.unwrap());
    assert!(
        t.is_finite() && t > 0.0 && ts.is_finite() && ts >= 0.0,
        "{t} {ts}"
    );
    assert!(r.rms_vs_truth_sd.unwrap().is_finite());
    let rc = r.raycast_rms_vs_truth.unwrap();
    assert!(
        rc.is_finite() && rc > ts,
        "ray cast {rc} vs noise floor {ts}"
    );
    // The truth doubles k from 4 × 8² rays: 256 · 4^i, at most 16,384.
    let tr = r.truth_rays.unwrap();
    assert!((0..4).any(|i| tr == 256 << (2 * i)), "{tr}");
    assert!(ts <= 0.25 || tr == 16_384, "{ts} at {tr} rays");
    // The 9 × 9 corner's creases: 2·9 − 1 vertices per face, reported apart.
    assert_eq!(r.crease_points, 3 * 17);
    let (c, i) = (
        r.rms_vs_truth_crease.unwrap(),
        r.rms_vs_truth_interior.unwrap(),
    );
    assert!(c.is_finite() && i.is_finite());
    // Both subsets together give the whole: n·rms² adds up (per seed, so only roughly for
    // the means): within 10%.
    let whole = ((51.0 * c * c + 192.0 * i * i) / 243.0).sqrt();
    assert!((whole - t).abs() < 0.1 * t, "{whole} vs {t}");
    let header = std::fs::read_to_string(out.join("table.csv")).unwrap();
    for col in [
        "rms_vs_truth",
        "truth_stderr",
        "rms_vs_truth_crease",
        "seeds",
    ] {
        assert!(
            header.lines().next().unwrap().split(',').any(|c| c == col),
            "{col}"
        );
    }
    // More rays through the field: closer to the truth (16 → 64 rays halves the ray noise).
    let fs: Vec<visfield::experiment::outputs::FieldSweepRow> =
        read_csv(&out.join("field_sweep.csv")).unwrap();
    assert_eq!(
        fs.iter().map(|f| f.rays_per_point).collect::<Vec<_>>(),
        vec![16, 64]
    );
    let (f16, f64_) = (fs[0].rms_vs_truth.unwrap(), fs[1].rms_vs_truth.unwrap());
    assert!(f64_ < f16, "64 rays {f64_} vs 16 rays {f16}");
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    for key in ["commit", "cpu", "threads", "date", "spec_sha256"] {
        assert!(!meta["meta"][key].is_null(), "run.json lacks meta.{key}");
    }
    assert_eq!(
        meta["meta"]["spec_sha256"],
        visfield::io::sha256_hex(ls.text.as_bytes())
    );
    for f in [
        "raycast_sweep.csv",
        "values_tiny.csv",
        "spec.json",
        "images.png",
        "differences.png",
        "pareto.png",
        "rms_vs_positional.png",
        "images/tiny-reference.png",
        "images/tiny-reference.exr",
        &r.image,
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    // The field row's picture is PNG only (no EXR beside it).
    assert!(!out.join(r.image.replace(".png", ".exr")).exists());

    // A threshold below the measured RMS fails, naming the cell; one above passes.
    let below = Threshold {
        rms_image_max: Some(ri - 1e-6),
        ..Threshold::default()
    };
    let failures = check_rows(&[below], &rows);
    assert_eq!(failures.len(), 1);
    assert_eq!(
        failures[0].cell,
        "tiny-slater-290-concentric-16-u8-nearest-cpu"
    );
    assert!(failures[0].to_string().contains(&failures[0].cell));
    let above = Threshold {
        rms_vertex_max: Some(rv + 1e-6),
        rms_image_max: Some(ri + 1e-6),
        positional_samples: Some(290),
        ..Threshold::default()
    };
    assert!(check_rows(std::slice::from_ref(&above), &rows).is_empty());
    // A threshold for other cells does not apply.
    let other = Threshold {
        directional_res: Some(32),
        rms_image_max: Some(0.0),
        ..Threshold::default()
    };
    assert!(check_rows(&[other, above], &rows).is_empty());
}

#[test]
fn an_unwritable_output_folder_fails_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"").unwrap();
    let t = std::time::Instant::now();
    let e = run(&ls, &options(file.join("out")))
        .unwrap_err()
        .to_string();
    assert!(e.contains("not writable") && e.contains("a-file"), "{e}");
    // Nothing was loaded or baked: the failure is immediate.
    assert!(t.elapsed().as_secs_f64() < 1.0);
}

#[test]
fn requantising_an_f32_field_equals_baking_at_that_precision() {
    let mesh = procedural::supershape(&procedural::Supershape::default(), 600).unwrap();
    let params = |precision| FieldParams {
        sphere: SphereKind::Slater,
        count: 50,
        layout: LayoutKind::Rejection,
        res: 8,
        precision,
    };
    let opts = BakeOptions::default();
    let (f32_field, _) = bake(&mesh, params(Precision::F32), &opts).unwrap();
    for p in [Precision::U16, Precision::U8, Precision::Bit1] {
        let (baked, _) = bake(&mesh, params(p), &opts).unwrap();
        let derived = requantize(&f32_field, p);
        assert_eq!(derived.params, baked.params);
        assert_eq!(derived.storage, baked.storage, "{p:?}");
    }
}

#[test]
fn fit_transform_reproduces_over_corner() {
    let spec = parse(&tiny(ONE_FIELD, "")).unwrap();
    let scenes = Scenes::build(&spec, Path::new("t.json"), "scenes").unwrap();
    let built = &scenes.scenes[0].scene.instances[1];
    let expected = procedural::over_corner((*built.mesh).clone(), Quat::IDENTITY);
    let (a, b) = (built.transform, expected.instances[1].transform);
    assert!(
        a.translation.distance(b.translation) < 1e-6,
        "{a:?} vs {b:?}"
    );
    assert!((a.scale - b.scale).abs() < 1e-6 && a.rotation.angle_between(b.rotation) < 1e-6);
    // One loaded mesh per distinct source.
    assert_eq!(scenes.meshes.len(), 2);
}

/// A spec whose instances are all translated by 1e4 builds, in its rebased frame, exactly the
/// scene of the untranslated spec, with the translation as its origin (so AO, images and
/// caches agree); without rebasing, f32 world coordinates at 1e4 would round the vertices to
/// 1e-3.
#[test]
fn translated_spec_is_rebased_to_the_untranslated_scene() {
    let text = tiny(ONE_FIELD, "");
    let far = text
        .replace(
            r#""receiver": true }"#,
            r#""receiver": true, "transform": { "translate": [10000, 10000, 10000] } }"#,
        )
        .replace(
            r#""radius": 0.35 }"#,
            r#""radius": 0.35 }, "translate": [10000, 10000, 10000]"#,
        );
    assert_eq!(far.matches("10000, 10000").count(), 2);
    let build = |t: &str| Scenes::build(&parse(t).unwrap(), Path::new("t.json"), "scenes").unwrap();
    let (near, far) = (build(&text), build(&far));
    assert_eq!(near.scenes[0].origin, glam::DVec3::ZERO);
    assert_eq!(far.scenes[0].origin, glam::DVec3::splat(1e4));
    for (a, b) in near.scenes[0]
        .scene
        .instances
        .iter()
        .zip(&far.scenes[0].scene.instances)
    {
        assert_eq!(a.transform, b.transform);
    }
    let cam = visfield::render::camera::Camera::corner();
    let moved = visfield::render::camera::Camera {
        eye: cam.eye + Vec3::splat(1e4),
        target: cam.target + Vec3::splat(1e4),
        ..cam
    };
    let back = far.scenes[0].camera_in_frame(&moved);
    assert!(back.eye.distance(cam.eye) < 2e-3 && back.target.distance(cam.target) < 2e-3);
}

#[test]
fn a_gpu_backend_with_a_fibonacci_set_is_refused_naming_the_field() {
    let text = tiny(
        r#"{ "spheres": ["slater", "fibonacci"], "counts": [290], "resolutions": [16] }"#,
        "",
    );
    // Fine on the CPU (290 is a valid count of both sets)...
    assert!(parse(&text).is_ok());
    // ...refused with "gpu", naming the entry.
    let e = error_of(&text.replace(
        r#""reference": {"#,
        r#""backends": ["cpu", "gpu"], "reference": {"#,
    ));
    assert!(
        e.contains("fields[0].spheres[1]") && e.contains("\"gpu\""),
        "{e}"
    );
}

#[test]
fn the_quick_profile_may_replace_the_backends() {
    use visfield::experiment::spec::Backend;
    let both = tiny(ONE_FIELD, "").replace(
        r#""reference": {"#,
        r#""backends": ["cpu", "gpu"], "reference": {"#,
    );
    let spec = parse(&both.replace(r#""quick": {}"#, r#""quick": {"backends": ["cpu"]}"#)).unwrap();
    assert_eq!(spec.backends, [Backend::Cpu, Backend::Gpu]);
    assert_eq!(spec.quick().backends, [Backend::Cpu]);
    assert_eq!(spec.profile(false).backends, [Backend::Cpu, Backend::Gpu]);
    let e = error_of(&both.replace(r#""quick": {}"#, r#""quick": {"backends": ["gpu", "gpu"]}"#));
    assert!(e.contains("quick.backends[1]"), "{e}");
}

/// Per-pixel AO through the estimator seam: the points are the G-buffer's receiver pixels, the
/// row has the per-pixel columns only, and the same-ray reference at each pixel is the AO
/// integral evaluated directly at that pixel's surface point (the runner adds nothing of its
/// own between the kind and the estimate).
#[test]
fn image_ao_evaluates_at_the_receiver_pixels_of_the_gbuffer() {
    use visfield::render::ao::{ao_at_points, AoOptions};
    use visfield::render::camera::Camera;
    use visfield::render::points::{EvalPoints, GBuffer};
    use visfield::render::primary::{gbuffer, PrimaryScene};
    use visfield::sampling::rays::RaySet;
    use visfield::trace::Tracer;

    let dir = tempfile::tempdir().unwrap();
    let text = tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point""#,
        r#""render": { "what": "image_ao", "rays_per_point""#,
    );
    let ls = loaded(dir.path(), &text);
    let out = dir.path().join("out");
    let report = run(&ls, &options(out.clone())).unwrap();
    let r = &report.rows[0];
    assert!(r.rms_vertex.is_none() && r.max_error_vertex.is_none());
    assert!(r.rms_image.unwrap().is_finite() && r.rms_vs_truth.unwrap().is_finite());
    // No per-vertex CSV for a per-pixel kind.
    assert!(!out.join("values_tiny.csv").exists());

    // The same points and reference, computed here from the scene alone.
    let scenes = Scenes::build(&ls.spec, &ls.path, "scenes").unwrap();
    let bs = &scenes.scenes[0];
    let cam = bs.camera_in_frame(&Camera::corner());
    let hits = gbuffer(&PrimaryScene::new(&bs.scene), &cam, 32, 32);
    let receiver_pixels = hits
        .iter()
        .filter(|h| h.is_some_and(|h| bs.scene.instances[h.instance as usize].receiver))
        .count();
    assert_eq!(r.receiver_points, receiver_pixels);
    assert!(receiver_pixels > 100 && receiver_pixels < 32 * 32);
    // The points' origins carry each instance's offset: the estimator adds none.
    let opts = AoOptions {
        offset: 0.0,
        ..AoOptions::for_scene(bs.bounds())
    };
    let view = GBuffer {
        hits,
        width: 32,
        height: 32,
    };
    let at = EvalPoints::pixels(&bs.scene, &view);
    let tracer = Tracer::new(&bs.scene.caster_triangles());
    let ao = ao_at_points(&tracer, &at.origins, &at.normals, &RaySet::new(4, 1), &opts);
    let (img, mask) = at.image(&bs.scene, &view, &ao);
    assert_eq!(mask.iter().filter(|&&m| m).count(), receiver_pixels);
    let png = image::open(out.join("images/tiny-reference.png"))
        .unwrap()
        .to_luma8();
    for (i, px) in png.pixels().enumerate() {
        assert_eq!(
            px.0[0],
            visfield::render::image::GrayImage::to_u8(img.data[i]),
            "pixel {i}"
        );
    }
}

/// The tagged `render`: each kind reads its own keys, refuses the unknown ones and the ones it
/// lacks, and writes back what it read.
#[test]
fn render_specs_are_tagged_by_kind() {
    use visfield::experiment::kinds;
    use visfield::experiment::spec::RenderSpec;
    let s = parse(&tiny(ONE_FIELD, "")).unwrap();
    // No `what`: vertex AO (the 2008 default).
    assert_eq!(s.render.what, "vertex_ao");
    let k = kinds::of(&s.render);
    assert_eq!(
        (k.name(), k.needs().view, k.columns().vertex),
        ("vertex_ao", false, true)
    );
    let image = tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point""#,
        r#""render": { "what": "image_ao", "rays_per_point""#,
    );
    let s = parse(&image).unwrap();
    let k = kinds::of(&s.render);
    assert_eq!(
        (k.name(), k.needs().view, k.columns().vertex),
        ("image_ao", true, false)
    );
    assert!(!k.needs().normal_field);
    // Round trip through the wire form.
    let json = serde_json::to_string(&s.render).unwrap();
    assert!(json.contains(r#""what":"image_ao""#), "{json}");
    let back: RenderSpec = serde_json::from_str(&json).unwrap();
    assert_eq!(back, s.render);
    // A per-pixel kind without an image, a per-vertex threshold on a per-pixel kind,
    // reflections without lights: each refused naming the field.
    let e = error_of(&image.replace(r#", "image": { "width": 32, "height": 32 }"#, ""));
    assert!(
        e.contains("field `render.image`") && e.contains("image_ao"),
        "{e}"
    );
    let e = error_of(&tiny(ONE_FIELD, r#"{ "rms_vertex_max": 9 }"#).replace(
        r#""render": { "rays_per_point""#,
        r#""render": { "what": "image_ao", "rays_per_point""#,
    ));
    assert!(
        e.contains("rms_vertex_max") && e.contains("per-vertex"),
        "{e}"
    );
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point""#,
        r#""render": { "what": "reflections", "rays_per_point""#,
    ));
    assert!(
        e.contains("at `render`") && e.contains("reflections"),
        "{e}"
    );
    // Shadows without lights (their own keys: tests/shadows.rs).
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point""#,
        r#""render": { "what": "shadows", "rays_per_point""#,
    ));
    assert!(e.contains("at `render`") && e.contains("light"), "{e}");
}

/// The quickstart is an embedded spec, planned and run by the same runner as the others.
#[test]
fn the_quickstart_is_an_embedded_spec() {
    let ls = visfield::experiment::quickstart::spec().unwrap();
    assert_eq!(ls.name, "quickstart");
    let scenes = Scenes::build(&ls.spec, &ls.path, "scenes").unwrap();
    let plan = Plan::new(
        &ls.spec,
        &scenes,
        PlanLimits {
            memory_limit: 1 << 30,
        },
    )
    .unwrap();
    assert_eq!((plan.cells.len(), plan.bakes()), (1, 1));
    assert!(plan.steps.iter().any(|s| matches!(s, Step::Truth { .. })));
    assert_eq!(scenes.scenes[0].receiver_vertices(), 3 * 33 * 33);
}

/// Cameras that cannot see are refused naming the field, and a camera that sees no receiver
/// fails the run naming the scene, before any field is baked (an error over no point would be
/// no measurement).
#[test]
fn cameras_are_validated_and_an_image_without_receivers_is_an_error() {
    let image = |camera: &str| {
        tiny(ONE_FIELD, "").replace(
            r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
            &format!(
                r#""render": {{ "what": "image_ao", "rays_per_point": 16, "image": {{ "width": 32, "height": 32, "camera": {camera} }} }}"#
            ),
        )
    };
    let cam = |eye: &str, target: &str, fov: &str| {
        format!(r#"{{ "eye": {eye}, "target": {target}, "fov_y_deg": {fov} }}"#)
    };
    let ok = image(&cam("[2, 2, 2]", "[0.4, 0.3, 0.4]", "40"));
    assert!(parse(&ok).is_ok(), "{:?}", parse(&ok).err());
    let e = error_of(&image(&cam("[1, 1, 1]", "[1, 1, 1]", "40")));
    assert!(
        e.contains("render.image.camera.target") && e.contains("nowhere"),
        "{e}"
    );
    let e = error_of(&image(&cam("[2, 2, 2]", "[0.4, 0.3, 0.4]", "180")));
    assert!(e.contains("render.image.camera.fov_y_deg"), "{e}");
    let e = error_of(&image(&cam("[0, 3, 0]", "[0, 0, 0]", "40")));
    assert!(
        e.contains("render.image.camera.up") && e.contains("along the view"),
        "{e}"
    );
    let e = error_of(&image(&cam("[1e39, 0, 0]", "[0, 0, 0]", "40")).replace("1e39", "1e300"));
    assert!(e.contains("render.image.camera"), "{e}");
    // An eye at 1e30 is beyond the coordinates' range, named so (once "up along the view").
    let e = error_of(&image(&cam("[1e30, 1e30, 1e30]", "[0, 0, 0]", "40")));
    assert!(
        e.contains("render.image.camera.eye") && e.contains("range of every spec coordinate"),
        "{e}"
    );
    // Everything moved by 1e12: the camera's f32 coordinates cannot tell eye from target.
    let e = error_of(&image(&cam(
        "[1000000000002, 1000000000002, 1000000000002]",
        "[1000000000000.4, 1000000000000.3, 1000000000000.4]",
        "40",
    )));
    assert!(
        e.contains("render.image.camera.target") && e.contains("spaced") && e.contains("1.2e5"),
        "{e}"
    );
    // At 1e7 the eye is 2 from the target but only 2 f32 steps: the precision limit, by name.
    let e = error_of(&image(&cam(
        "[10000002, 2, 2]",
        "[10000000, 0.3, 0.4]",
        "40",
    )));
    assert!(
        e.contains("render.image.camera.target") && e.contains("precision limit"),
        "{e}"
    );

    // Looking away from the scene: no receiver pixel.
    let dir = tempfile::tempdir().unwrap();
    let away = image(&cam("[5, 5, 5]", "[10, 10, 10]", "20"));
    let ls = loaded(dir.path(), &away);
    let e = run(&ls, &options(dir.path().join("out")))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("scene tiny") && e.contains("sees no receiver"),
        "{e}"
    );
    assert!(!dir.path().join("out/table.csv").exists());
}

/// Hostile spec text: a byte-order mark is skipped, text after the JSON is an error, and a
/// Fibonacci count out of range is answered with the valid end of the range, not itself.
#[test]
fn spec_text_is_read_whole_and_count_hints_are_valid() {
    let good = tiny(ONE_FIELD, "");
    assert!(parse(&format!("\u{feff}{good}")).is_ok());
    let e = error_of(&format!("{good} }}}} garbage"));
    assert!(e.contains("text after the spec"), "{e}");
    let e = error_of(&tiny(
        r#"{ "spheres": ["fibonacci"], "counts": [999999999], "resolutions": [16] }"#,
        "",
    ));
    assert!(
        e.contains("fields[0].counts[0]") && e.contains("[262144]"),
        "{e}"
    );
}

/// An unusable field cache fails before any work, naming the cache, and a failed run leaves
/// no empty output folder behind.
#[test]
fn an_unusable_cache_fails_first_and_a_failed_run_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"").unwrap();
    let mut o = options(dir.path().join("out"));
    o.supply.cache = Some(file.join("cache"));
    let t = std::time::Instant::now();
    let e = run(&ls, &o).unwrap_err().to_string();
    assert!(e.contains("field cache") && e.contains("a-file"), "{e}");
    assert!(
        t.elapsed().as_secs_f64() < 1.0,
        "no work before the refusal"
    );
    assert!(!dir.path().join("out").exists(), "an empty folder was left");
}

/// A cached field's bake time comes from its record only while the record's checksum holds:
/// an edited record leaves the time unknown instead of putting its number in the table.
#[test]
fn an_edited_bake_record_is_not_believed() {
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let mut o = options(dir.path().join("out"));
    o.supply.cache = Some(dir.path().join("cache"));
    o.supply.cache_limit = 1 << 30;
    let first = run(&ls, &o).unwrap().rows[0].clone();
    assert!(!first.bake_cached);
    let second = run(&ls, &o).unwrap().rows[0].clone();
    assert!(second.bake_cached);
    let recorded = second.bake_s.unwrap();
    assert!((recorded - first.bake_s.unwrap()).abs() < 1e-9);
    let record = std::fs::read_dir(dir.path().join("cache"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.to_string_lossy().ends_with(".bake.json"))
        .expect("a bake record beside the cached field");
    let text = std::fs::read_to_string(&record).unwrap();
    let edited = text.replacen("\"seconds\": ", "\"seconds\": 1e300, \"was\": ", 1);
    std::fs::write(&record, edited).unwrap();
    let third = run(&ls, &o).unwrap().rows[0].clone();
    assert!(third.bake_cached);
    assert_eq!(third.bake_s, None, "an edited record was believed");
    // The errors do not depend on where the field came from.
    assert_eq!(third.rms_vertex, first.rms_vertex);
}

/// Placements past f32 range are refused naming the instance, before any BVH is built (they
/// once reached the tracer as infinities and panicked).
#[test]
fn placements_past_f32_range_are_refused_naming_the_instance() {
    for transform in [
        r#""transform": { "translate": [1e39, 0, 0] }"#,
        r#""transform": { "translate": [1e300, 0, 0] }"#,
        r#""transform": { "scale": 3e38 }"#,
    ] {
        let text = tiny(ONE_FIELD, "").replace(
            r#""transform": { "fit": { "center": [0.5, 0.45, 0.5], "radius": 0.35 } }"#,
            transform,
        );
        let spec = parse(&text).expect("the values themselves are valid");
        let e = Scenes::build(&spec, Path::new("specs/bad.json"), "scenes")
            .err()
            .unwrap_or_else(|| panic!("{transform} was accepted"))
            .to_string();
        assert!(
            e.contains("scenes[0].instances[1].transform") && e.contains("f32 range"),
            "{e}"
        );
    }
}

/// `--out` ownership: a user's file among a previous run's results survives the next run (it
/// was once deleted); a folder no run wrote is refused before any work unless allowed, and
/// then its files are kept; the new run.json lists the run's own files.
#[test]
fn results_folders_keep_files_the_program_did_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let out = dir.path().join("out");
    run(&ls, &options(out.clone())).unwrap();
    std::fs::write(out.join("images/holiday.png"), b"mine").unwrap();
    run(&ls, &options(out.clone())).unwrap();
    assert_eq!(
        std::fs::read(out.join("images/holiday.png")).unwrap(),
        b"mine"
    );
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    let files: Vec<&str> = meta["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert!(
        files.contains(&"table.csv") && files.contains(&"run.json"),
        "{files:?}"
    );
    assert!(!files.contains(&"images/holiday.png"), "{files:?}");

    let theirs = dir.path().join("theirs");
    std::fs::create_dir_all(&theirs).unwrap();
    std::fs::write(theirs.join("thesis.tex"), b"mine").unwrap();
    let e = run(&ls, &options(theirs.clone())).unwrap_err().to_string();
    assert!(e.contains("no run.json"), "{e}");
    assert!(!theirs.join("table.csv").exists());
    let mut o = options(theirs.clone());
    o.allow_nonempty_out = true;
    run(&ls, &o).unwrap();
    assert!(theirs.join("table.csv").exists());
    assert_eq!(std::fs::read(theirs.join("thesis.tex")).unwrap(), b"mine");
}

/// Sizes that would abort or hang before any check are refused by validation, naming the
/// field, dry run included (a 10¹² supershape once hung `--dry-run`).
#[test]
fn sizes_past_the_limits_are_refused_before_anything_is_built() {
    let supershape = r#"{ "supershape": { "triangles": 2000 } }"#;
    for (mesh, field) in [
        (
            r#"{ "supershape": { "triangles": 1000000000000 } }"#,
            "instances[1].mesh",
        ),
        (
            r#"{ "sphere": { "radius": 1, "stacks": 1000000, "slices": 1000000 } }"#,
            "instances[1].mesh",
        ),
    ] {
        let e = error_of(&tiny(ONE_FIELD, "").replace(supershape, mesh));
        assert!(e.contains(field) && e.contains("at most"), "{e}");
    }
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#"{ "corner": { "n": 9 } }"#,
        r#"{ "corner": { "n": 100000 } }"#,
    ));
    assert!(
        e.contains("instances[0].mesh") && e.contains("at most"),
        "{e}"
    );
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""rays_per_point": 16, "image""#,
        r#""rays_per_point": 999950884, "image""#,
    ));
    assert!(
        e.contains("render.rays_per_point") && e.contains("at most"),
        "{e}"
    );
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""raycast_sweep": [4, 16]"#,
        r#""raycast_sweep": [4, 16], "seeds": 4000000000"#,
    ));
    assert!(e.contains("reference.seeds"), "{e}");
    let e = error_of(&tiny(ONE_FIELD, "").replace(
        r#""field_rays_sweep": [16, 64]"#,
        r#""field_rays_sweep": [16, 4294836225]"#,
    ));
    assert!(
        e.contains("field_rays_sweep[1]") && e.contains("at most"),
        "{e}"
    );
}

/// Sizes against the memory limit, before any work and in the dry run too: an 8192² image of
/// the tiny scene needs gigabytes of G-buffer and per-pixel state, refused under a 1 GiB limit
/// naming the scene and the flag; the same spec at 32² plans and runs.
#[test]
fn a_scene_state_over_the_memory_limit_is_refused_before_any_work() {
    let big = tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
        r#""render": { "what": "image_ao", "rays_per_point": 16, "image": { "width": 8192, "height": 8192 } }"#,
    );
    assert!(big.contains("8192"));
    for dry_run in [true, false] {
        let dir = tempfile::tempdir().unwrap();
        let ls = loaded(dir.path(), &big);
        let mut o = options(dir.path().join("out"));
        o.dry_run = dry_run;
        let t = std::time::Instant::now();
        let e = run(&ls, &o).unwrap_err().to_string();
        assert!(
            e.contains("scenes[0] (tiny)") && e.contains("--max-memory-mib") && e.contains("GiB"),
            "{e}"
        );
        assert!(
            t.elapsed().as_secs_f64() < 5.0,
            "refused after {:?}",
            t.elapsed()
        );
        assert!(!dir.path().join("out").exists());
    }
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let mut o = options(dir.path().join("out"));
    o.dry_run = true;
    assert!(run(&ls, &o).is_ok());
}

/// A spec listing the Embree method: with the `embree` feature it is a row of `methods.csv`,
/// Embree's scene build as its precompute and its estimate on the reference's rays, measured
/// against ours (the tiny scene's caster floats clear of the corner: no contact origin, so no
/// disagreement); without it the run goes on without the row, and `require_embree` refuses it
/// naming the spec field.
#[test]
fn embree_is_a_method_row_or_a_skip_with_the_reason() {
    use visfield::experiment::columns::read_csv as read_named;
    let dir = tempfile::tempdir().unwrap();
    let text = tiny(ONE_FIELD, "").replace(
        r#""reference": {"#,
        r#""methods": [{"method": "embree"}, {"method": "raycast"}], "reference": {"#,
    );
    let ls = loaded(dir.path(), &text);
    let report = run(&ls, &options(dir.path().join("out"))).unwrap();
    assert_eq!(report.rows.len(), 1);
    let rows = read_named(&dir.path().join("out/methods.csv")).unwrap();
    let methods: Vec<&str> = rows.iter().map(|r| r.get("method").unwrap()).collect();
    // Our ray caster as a method is the reference ray for ray, its BVH build charged.
    let ours = rows
        .iter()
        .find(|r| r.get("method") == Some("raycast"))
        .unwrap();
    assert_eq!(ours.number("rms_vs_raycast"), Some(0.0));
    assert!(ours.number("precompute_s").unwrap() > 0.0);
    assert!(ours.number("bytes").unwrap() > 2000.0 * 36.0, "{ours:?}");
    if cfg!(feature = "embree") {
        assert_eq!(methods, ["embree", "raycast"]);
        let r = &rows[0];
        let s = r.number("estimate_s").unwrap();
        assert!(s > 0.0, "{s}");
        let rays = r.number("rays_cast").unwrap();
        assert_eq!(rays, report.rows[0].rays_cast as f64);
        assert_eq!(r.number("estimate_mrays_s"), Some(rays / s / 1e6));
        assert_eq!(r.number("rms_vs_raycast"), Some(0.0));
        assert_eq!(r.get("rms_vertex"), ours.get("rms_vertex"));
    } else {
        assert_eq!(methods, ["raycast"]);
        let mut o = options(dir.path().join("out2"));
        o.require_embree = true;
        let e = run(&ls, &o).unwrap_err().chain();
        assert!(
            e.contains("methods \"embree\"") && e.contains("--features embree"),
            "{e}"
        );
    }
}

/// Mesh signed distance fields as a method: a row per resolution on the same rays, the volumes'
/// bytes growing with it, a same-ray error that is neither 0 nor the whole occlusion, and a
/// resolution refused by name before any work.
#[test]
fn sdf_is_a_method_with_a_row_per_resolution() {
    use visfield::experiment::columns::read_csv as read_named;
    let dir = tempfile::tempdir().unwrap();
    let text = tiny(ONE_FIELD, "").replace(
        r#""reference": {"#,
        r#""methods": [{"method": "sdf", "res": [16, 48]}], "reference": {"#,
    );
    let ls = loaded(dir.path(), &text);
    run(&ls, &options(dir.path().join("out"))).unwrap();
    let rows = read_named(&dir.path().join("out/methods.csv")).unwrap();
    let setting: Vec<&str> = rows.iter().map(|r| r.get("setting").unwrap()).collect();
    assert_eq!(setting, ["sdf-16-f32-trace", "sdf-48-f32-trace"]);
    let num = |r: usize, c: &str| rows[r].number(c).unwrap();
    // Bytes: at most res³ f32 samples, and more at the finer resolution.
    assert!(num(0, "bytes") <= 16f64.powi(3) * 4.0 && num(1, "bytes") > 8.0 * num(0, "bytes"));
    for (r, s) in setting.iter().enumerate() {
        let rms = num(r, "rms_vs_raycast");
        assert!(rms > 0.01 && rms < 30.0, "{s}: {rms}");
        assert!(num(r, "precompute_s") > 0.0);
    }
    let bad = tiny(ONE_FIELD, "").replace(
        r#""reference": {"#,
        r#""methods": [{"method": "sdf", "res": [4]}], "reference": {"#,
    );
    let path = dir.path().join("bad.json");
    std::fs::write(&path, &bad).unwrap();
    let e = LoadedSpec::load(&path).map(|_| ()).unwrap_err().to_string();
    assert!(
        e.contains("methods[0].res[0]") && e.contains("outside 8..=256"),
        "{e}"
    );
}

/// The errors split by population: a caster whose bounding sphere cuts the corner puts some
/// receiver vertices inside it; the count is the corner's vertices inside that sphere, and the
/// two parts' RMS against the truth make up the whole (a partition of the points).
#[test]
fn the_points_inside_a_caster_sphere_are_counted_and_their_error_split() {
    let dir = tempfile::tempdir().unwrap();
    // The tiny scene with its caster lowered so that its sphere (radius 0.35) cuts the floor.
    let text = tiny(ONE_FIELD, "").replace("[0.5, 0.45, 0.5]", "[0.5, 0.3, 0.5]");
    let ls = loaded(dir.path(), &text);
    let report = run(&ls, &options(dir.path().join("out"))).unwrap();
    let r = &report.rows[0];
    // The corner of n = 9: its vertices on the floor (y = 0), the back wall (z = 0) and the
    // side wall (x = 0) over the unit square; count those inside the sphere directly.
    let scenes = Scenes::build(&ls.spec, &ls.path, "scenes").unwrap();
    let bs = &scenes.scenes[0];
    let (_, caster) = bs.scene.casters().next().unwrap();
    let s = caster.world_bounding_sphere();
    let inside = bs
        .scene
        .receivers()
        .flat_map(|(_, inst)| {
            inst.mesh
                .positions
                .iter()
                .map(|&p| inst.transform.to_world_point(p))
        })
        .filter(|p| p.distance(s.center) < s.radius)
        .count();
    assert!(inside > 0);
    assert_eq!(r.points_in_spheres, Some(inside));
    let (all, a, b) = (
        r.rms_vs_truth.unwrap(),
        r.rms_vs_truth_in_spheres.unwrap(),
        r.rms_vs_truth_outside_spheres.unwrap(),
    );
    let (n, k) = (r.receiver_points as f64, inside as f64);
    // Mean over seeds of each part: the identity holds seed by seed, so within the spread.
    let whole = ((a * a * k + b * b * (n - k)) / n).sqrt();
    assert!((whole - all).abs() < 0.05 * all, "{whole} vs {all}");
    assert!(r.rms_outside_spheres.unwrap() > 0.0);
    // Lifted clear of the floor, no point is inside and the split is empty.
    let ls = loaded(dir.path(), &tiny(ONE_FIELD, ""));
    let report = run(&ls, &options(dir.path().join("out2"))).unwrap();
    let r = &report.rows[0];
    assert_eq!(r.points_in_spheres, Some(0));
    assert_eq!(r.rms_vs_truth_in_spheres, None);
    assert_eq!(r.rms_vs_truth_outside_spheres, r.rms_vs_truth);
}

/// The image RMS as the 2010 paper takes it (`rms_image_window`, over every pixel that sees a
/// surface): equal to `rms_image` when every surface is a receiver (every active pixel is
/// evaluated), below it when the caster's pixels are drawn unevaluated; and the shaded images'
/// RMS (`rms_image_shaded`) only for a kind with a shading factor, where a factor in [0, 1]
/// can only shrink a difference (up to the images' 8-bit rounding).
#[test]
fn window_and_shaded_image_errors_follow_their_pixel_sets() {
    let dir = tempfile::tempdir().unwrap();
    let run_of = |name: &str, text: &str| -> Row {
        let d = dir.path().join(name);
        std::fs::create_dir_all(&d).unwrap();
        let ls = loaded(&d, text);
        let report = run(&ls, &options(d.join("out"))).unwrap();
        assert_eq!(report.rows.len(), 1);
        report.rows[0].clone()
    };
    let image_ao = tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point": 16"#,
        r#""render": { "what": "image_ao", "rays_per_point": 16"#,
    );
    let r = run_of("caster", &image_ao);
    let (image, window) = (r.rms_image.unwrap(), r.rms_image_window.unwrap());
    assert!(0.0 < window && window < image, "{window} {image}");
    assert_eq!(r.rms_image_shaded, None);
    let both = image_ao.replace(r#""caster": true,"#, r#""caster": true, "receiver": true,"#);
    assert_ne!(both, image_ao);
    let r = run_of("both", &both);
    let (image, window) = (r.rms_image.unwrap(), r.rms_image_window.unwrap());
    assert!(
        image > 0.0 && (window - image).abs() <= 1e-12 * image,
        "{window} {image}"
    );

    let shadows = tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point": 16"#,
        r#""render": { "what": "shadows", "lights": [{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }], "rays_per_point": 16"#,
    );
    let r = run_of("shadows", &shadows);
    let (image, shaded) = (r.rms_image.unwrap(), r.rms_image_shaded.unwrap());
    assert!(0.0 < shaded && shaded <= image + 0.5, "{shaded} {image}");
}
