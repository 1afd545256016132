//! Hardware ray queries (`visfield::gpu::RayQueryScene`: a BLAS per mesh, a TLAS of the
//! instances) against our CPU ray caster (`trace::Tracer` over the same instances' world
//! triangles) on the same rays: any hits, closest-hit distances, triangles and normals, frame
//! after frame as the instances move (the TLAS rebuilt), and the integrands (AO, shadows,
//! reflections) on them against the CPU estimators; the `rayquery` method through the harness,
//! and its per-frame twin `rayquery@gpu` against `two_level` in an animated spec.
//! Where the adapter offers no ray queries (Mesa's lavapipe before 24.1, datacenter GPUs) or
//! there is no Vulkan adapter, the tests that need them are reported as ignored with that
//! reason, never as passed; the method's test then checks that its row is skipped, saying why.

use glam::{Quat, Vec3};
use visfield::geometry::procedural::{supershape, uv_sphere, Supershape};
use visfield::geometry::Similarity;
use visfield::gpu::{GpuContext, GpuError, RayQueryScene};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::reflect::{reflect_at_points, Gloss, ReflectOptions};
use visfield::render::shadow::{shadow_at_points, ShadowOptions, SphereLight};
use visfield::sampling::rays::RaySet;
use visfield::trace::{RayQuery, Tracer};

mod common;
use common::{triangles as tris, unit};

/// Two meshes (a 3000-triangle supershape, a sphere) in model space.
fn meshes() -> Vec<Vec<[Vec3; 3]>> {
    vec![
        tris(&supershape(&Supershape::default(), 3000).unwrap()),
        tris(&uv_sphere(1.0, 12, 24).unwrap()),
    ]
}

/// Nine instances on a 3 × 3 grid at `frame`, each moved, turned and scaled per frame (the
/// two-level caster's test scene, tests/two_level.rs).
fn instances(frame: u64) -> Vec<(usize, Similarity)> {
    (0..9u64)
        .map(|i| {
            let a = 0.7 * frame as f32 + unit(i);
            let pos = Vec3::new((i % 3) as f32 * 2.5, 0.3 * a.sin(), (i / 3) as f32 * 2.5);
            let rot = Quat::from_axis_angle(Vec3::new(1.0, unit(i + 9), 0.5).normalize(), a);
            (
                (i % 2) as usize,
                Similarity::new(rot, pos, 0.6 + 0.3 * unit(i + 20)),
            )
        })
        .collect()
}

fn placed(inst: &[(usize, Similarity)]) -> Vec<(usize, glam::Mat4)> {
    inst.iter().map(|&(m, t)| (m, t.to_mat4())).collect()
}

/// The instances' world triangles, instance after instance, and each instance's first index.
fn world(model: &[Vec<[Vec3; 3]>], inst: &[(usize, Similarity)]) -> (Vec<[Vec3; 3]>, Vec<u32>) {
    let (mut out, mut first) = (Vec::new(), Vec::new());
    for &(m, t) in inst {
        first.push(out.len() as u32);
        out.extend(model[m].iter().map(|tri| tri.map(|v| t.to_world_point(v))));
    }
    (out, first)
}

/// Rays from above the grid at seeded targets on it, with a [tmin, tmax] window on every
/// third (`any hit` from 0.5 to 3.5).
fn rays(frame: u64, n: u64) -> Vec<RayQuery> {
    (0..n)
        .map(|r| {
            let s = frame * 100_000 + 4 * r;
            let o = Vec3::new(-2.0 + 9.0 * unit(s), 3.0, -2.0 + 9.0 * unit(s + 1));
            let target = Vec3::new(5.0 * unit(s + 2), 0.0, 5.0 * unit(s + 3));
            let windowed = r % 3 == 2;
            RayQuery {
                origin: o,
                dir: (target - o).normalize(),
                tmin: if windowed { 0.5 } else { 0.0 },
                tmax: if windowed { 3.5 } else { 20.0 },
            }
        })
        .collect()
}

/// What one frame's comparison found.
#[derive(Default, Debug)]
struct Compared {
    rays: usize,
    cpu_hits: usize,
    /// Rays whose any-hit answers differ, and whose closest-hit existence differs.
    any_differ: usize,
    closest_differ: usize,
    /// Rays both hit on different triangles (ties at shared edges).
    other_triangle: usize,
    /// Largest relative distance difference and normal difference (same triangle).
    dist_err: f32,
    normal_err: f32,
}

fn compare(scene: &RayQueryScene, model: &[Vec<[Vec3; 3]>], frame: u64) -> Compared {
    let inst = instances(frame);
    let (world, first) = world(model, &inst);
    let cpu = Tracer::new(&world);
    let rays = rays(frame, 6000);
    let (any, _) = scene.any_hits(&rays).unwrap();
    let (closest, _) = scene.closest_hits(&rays).unwrap();
    let mut c = Compared {
        rays: rays.len(),
        ..Default::default()
    };
    for (i, r) in rays.iter().enumerate() {
        let want = cpu.closest_hit(r.origin, r.dir, r.tmin, r.tmax);
        assert_eq!(cpu.any_hit(r.origin, r.dir, r.tmin, r.tmax), want.is_some());
        c.cpu_hits += want.is_some() as usize;
        c.any_differ += (any[i] != want.is_some()) as usize;
        c.closest_differ += (closest[i].is_some() != want.is_some()) as usize;
        if let (Some(g), Some(w)) = (closest[i], want) {
            assert!(g.t >= r.tmin && g.t <= r.tmax, "ray {i}: t {} outside", g.t);
            c.dist_err = c.dist_err.max((g.t - w.t).abs() / w.t);
            if first[g.instance as usize] + g.triangle == w.triangle {
                c.normal_err = c.normal_err.max((g.normal - w.normal).length());
            } else {
                c.other_triangle += 1;
            }
        }
    }
    c
}

/// The frame's answers against the CPU caster: the rays hit often enough to mean something;
/// any hits and closest hits part on at most one ray in a thousand (edge-grazing rays, the
/// tolerance of the CPU's two-level test), distances within 1e-4 relative, the same triangle
/// but on a few ties, its normal within 1e-4.
fn assert_agrees(c: &Compared) {
    eprintln!("{c:?}");
    assert!(c.cpu_hits > c.rays / 5 && c.cpu_hits < c.rays, "{c:?}");
    assert!(c.any_differ <= c.rays / 1000, "any hit: {c:?}");
    assert!(c.closest_differ <= c.rays / 1000, "closest hit: {c:?}");
    assert!(c.other_triangle <= c.rays / 1000, "triangles: {c:?}");
    assert!(c.dist_err < 1e-4, "distances: {c:?}");
    assert!(c.normal_err < 1e-4, "normals: {c:?}");
}

/// The device with ray queries, or why the test is skipped.
fn device() -> Result<&'static GpuContext, String> {
    let ctx = common::gpu_context()
        .ok_or("no Vulkan adapter (install mesa-vulkan-drivers for lavapipe)")?;
    ctx.ray_query_support()?;
    Ok(ctx)
}

fn ray_queries_answer_as_the_cpu_caster() {
    let ctx = device().unwrap();
    let model = meshes();
    let scene = RayQueryScene::new(ctx, &model, &placed(&instances(0))).unwrap();
    assert_agrees(&compare(&scene, &model, 0));
}

/// Frame after frame the instances move: the TLAS rebuilt over the new transforms (the
/// BLASes untouched) answers as the CPU caster over the moved triangles.
fn moved_instances_answer_as_the_cpu_caster() {
    let ctx = device().unwrap();
    let model = meshes();
    let mut scene = RayQueryScene::new(ctx, &model, &placed(&instances(0))).unwrap();
    for frame in 1..4 {
        scene.place(&placed(&instances(frame))).unwrap();
        assert_agrees(&compare(&scene, &model, frame));
    }
    // Fewer instances than the TLAS holds: the rest are gone.
    let one = &instances(0)[..1];
    scene.place(&placed(one)).unwrap();
    let (world, _) = world(&model, one);
    let cpu = Tracer::new(&world);
    let rays = rays(7, 3000);
    let (any, _) = scene.any_hits(&rays).unwrap();
    let want = cpu.any_hits(&rays);
    let differ = any.iter().zip(&want).filter(|(a, b)| a != b).count();
    assert!(want.iter().any(|&h| h) && differ <= 3, "{differ} differ");
}

/// No instances: every ray misses; bad input is refused by name.
fn empty_scenes_miss_and_bad_input_is_refused() {
    let ctx = device().unwrap();
    let model = meshes();
    let scene = RayQueryScene::new(ctx, &model, &[]).unwrap();
    let r = rays(0, 64);
    assert!(scene.any_hits(&r).unwrap().0.iter().all(|&h| !h));
    assert!(scene
        .closest_hits(&r)
        .unwrap()
        .0
        .iter()
        .all(Option::is_none));
    // A mesh without triangles is left out of the TLAS.
    let with_empty = vec![Vec::new(), model[1].clone()];
    let scene = RayQueryScene::new(ctx, &with_empty, &placed(&instances(0))).unwrap();
    let hits = scene.closest_hits(&rays(0, 3000)).unwrap().0;
    assert!(hits.iter().flatten().all(|h| h.instance % 2 == 1));
    assert!(hits.iter().any(Option::is_some));
    let bad_mesh = [(2, glam::Mat4::IDENTITY)];
    match RayQueryScene::new(ctx, &model, &bad_mesh) {
        Err(GpuError::Invalid(m)) => assert!(m.contains("mesh 2"), "{m}"),
        other => panic!("expected a refusal, got {:?}", other.err()),
    }
    let nan = [(0, glam::Mat4::from_translation(Vec3::NAN))];
    assert!(matches!(
        RayQueryScene::new(ctx, &model, &nan),
        Err(GpuError::Invalid(_))
    ));
    let mut scene = RayQueryScene::new(ctx, &model, &placed(&instances(0)[..2])).unwrap();
    assert!(matches!(
        scene.place(&placed(&instances(0))),
        Err(GpuError::Invalid(_))
    ));
}

/// AO, soft shadows and mirror reflections on the ray-query visibility give the CPU
/// estimators' values through our CPU caster on the same rays: AO within one ray at 1% of
/// the points at most (a grazing ray may fall the other way), the light fractions within one
/// shadow ray's weight at 1% of the points, the radiance equal within 1e-4 but at 1% of the
/// points; and the scene is no trivial one.
fn integrands_on_ray_queries_match_the_cpu() {
    let ctx = device().unwrap();
    let model = meshes();
    let inst = instances(2);
    let scene = RayQueryScene::new(ctx, &model, &placed(&inst)).unwrap();
    let (world, _) = world(&model, &inst);
    let cpu = Tracer::new(&world);
    // Receivers on the plane y = -1.2 under the grid and around it, facing up.
    let p: Vec<Vec3> = (0..30 * 30)
        .map(|i| {
            Vec3::new(
                (i % 30) as f32 * 0.4 - 3.3,
                -1.2,
                (i / 30) as f32 * 0.4 - 3.3,
            )
        })
        .collect();
    let n = vec![Vec3::Y; p.len()];
    let rays = RaySet::new(8, 5);
    let share = |gpu: &[f32], cpu: &[f32], tol: f32| {
        gpu.iter()
            .zip(cpu)
            .filter(|(a, b)| (*a - *b).abs() > tol)
            .count()
    };
    let ao_opts = AoOptions {
        max_distance: Some(2.5),
        ..AoOptions::for_scene_radius(6.0)
    };
    let want = ao_at_points(&cpu, &p, &n, &rays, &ao_opts);
    eprintln!(
        "AO: min {}, {} unoccluded",
        want.iter().fold(1.0f32, |a, &b| a.min(b)),
        want.iter().filter(|&&a| a == 1.0).count()
    );
    let (got, _) = visfield::gpu::ao(&scene, &p, &n, &rays, &ao_opts).unwrap();
    let off = share(&got, &want, 1.0 / 64.0 + 1e-6);
    let any = share(&got, &want, 0.0);
    eprintln!("AO: {any} of {} differ, {off} by more than a ray", p.len());
    assert!(
        off == 0 && any * 100 <= p.len(),
        "AO: {any} differ, {off} by more than a ray"
    );
    assert!(want.iter().any(|&a| a < 0.7) && want.contains(&1.0));

    let light = SphereLight {
        center: Vec3::new(2.5, 6.0, 2.5),
        radius: 0.8,
        intensity: 1.0,
    };
    let shadow_opts = ShadowOptions {
        offset: 1e-4,
        lights: vec![light],
    };
    let want = shadow_at_points(&cpu, &p, &n, &rays, &shadow_opts);
    let (got, _) = visfield::gpu::shadows(&scene, &p, &n, &rays, &shadow_opts).unwrap();
    let off = share(&got, &want, 1.0 / 64.0 + 1e-5);
    let any = share(&got, &want, 1e-5);
    eprintln!(
        "shadows: {any} of {} differ, {off} by more than a ray",
        p.len()
    );
    assert!(off == 0 && any * 100 <= p.len(), "shadows: {any} differ");
    assert!(want.contains(&0.0) || want.iter().any(|&v| v < 0.5));
    assert!(want.contains(&1.0));

    let reflect_opts = ReflectOptions {
        offset: 1e-4,
        eye: Vec3::new(2.5, 4.0, -6.0),
        gloss: Gloss::Mirror,
        lights: vec![light],
        albedo: 0.8,
        sky: 0.1,
    };
    let want = reflect_at_points(&cpu, &p, &n, &rays, &reflect_opts);
    let (got, _) = visfield::gpu::reflections(&scene, &p, &n, &rays, &reflect_opts).unwrap();
    let any = share(&got, &want, 1e-4);
    eprintln!("reflections: {any} of {} differ", p.len());
    assert!(any * 100 <= p.len(), "reflections: {any} differ");
    assert!(want.iter().any(|&v| v != 0.1) && want.contains(&0.1));
}

/// The tiny spec with `methods` spliced in.
fn with_methods(methods: &str) -> String {
    common::tiny(common::ONE_FIELD, "").replace(
        r#""reference": {"#,
        &format!(r#""methods": {methods}, "reference": {{"#),
    )
}

/// `rayquery` is a method of the gpu backend alone: refused on the cpu backend by name, read
/// on the gpu's (no adapter needed).
fn rayquery_is_refused_on_the_cpu_backend() {
    use visfield::experiment::spec::Spec;
    let parse = |m: &str| {
        Spec::parse(&with_methods(m), std::path::Path::new("specs/m.json"))
            .map(|s| s.methods.len())
            .map_err(|e| e.to_string())
    };
    let e = parse(r#"[{"method": "rayquery"}]"#).unwrap_err();
    assert!(
        e.contains("methods[0]") && e.contains("gpu backend only"),
        "{e}"
    );
    assert_eq!(
        parse(r#"[{"method": "rayquery", "backends": ["gpu"]}]"#),
        Ok(1)
    );
    let e = parse(r#"[{"method": "rayquery", "backends": ["gpu"], "res": [8]}]"#).unwrap_err();
    assert!(e.contains("res"), "{e}");
}

/// The tiny spec with `rayquery` on the gpu backend: where the adapter has ray queries, its
/// row answers as our ray caster on the same rays (the GPU integrand's f32 sums apart); where
/// it has none, the row is skipped and run.json says why.
fn rayquery_method_runs_or_is_skipped_with_the_reason() {
    let Some(ctx) = common::gpu_context() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let text =
        with_methods(r#"[{"method": "raycast"}, {"method": "rayquery", "backends": ["gpu"]}]"#);
    let ls = common::loaded(dir.path(), &text);
    let out = dir.path().join("out");
    visfield::experiment::run::run(&ls, &common::options(out.clone())).unwrap();
    let rows = visfield::experiment::columns::read_csv(&out.join("methods.csv")).unwrap();
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    let skipped = run["skipped_methods"].as_array().unwrap();
    let ours: Vec<_> = rows
        .iter()
        .filter(|r| r.get("method") == Some("rayquery"))
        .collect();
    match ctx.ray_query_support() {
        Ok(()) => {
            assert!(skipped.is_empty(), "{skipped:?}");
            assert_eq!(ours.len(), 1);
            assert_eq!(ours[0].get("backend"), Some("gpu"));
            let rms = ours[0].number("rms_vs_raycast").unwrap();
            assert!(rms < 1e-3, "rms_vs_raycast {rms}");
        }
        Err(why) => {
            assert!(ours.is_empty());
            assert_eq!(skipped.len(), 1, "{skipped:?}");
            assert_eq!(skipped[0]["method"], "rayquery@gpu");
            assert_eq!(skipped[0]["why"], why.as_str());
        }
    }
}

/// An animated spec on the gpu backend: `rayquery@gpu`, the twin of `two_level`, answers as
/// it frame by frame for AO, shadows and reflections (the GPU integrand's f32 sums apart: the
/// errors against the same-ray ray cast within 0.5 of 255, the means within 0.002), its TLAS
/// rebuilt each frame (the caster lifted between the frames moves the answer); on an adapter
/// without ray queries its rows are skipped and run.json says why.
fn rayquery_twin_answers_as_two_level_every_frame() {
    let Some(ctx) = common::gpu_context() else {
        return;
    };
    let lights = r#""lights": [{ "center": [2, 3, 2.5], "radius": 0.2, "intensity": 1 }]"#;
    let dir = tempfile::tempdir().unwrap();
    let lift = r#"{ "keyframes": [{ "time": 0 }, { "time": 1, "translate": [0, 0.3, 0] }] }"#;
    for (what, own) in [
        ("vertex_ao", String::new()),
        ("shadows", lights.to_string() + ", "),
        (
            "reflections",
            format!(r#"{lights}, "gloss": "mirror", "normal_bits": [8], "#),
        ),
    ] {
        let mut text = common::animated(lift, "", r#"{ "frames": 2, "time_step": 1 }"#).replace(
            r#""quick": {}"#,
            r#""backends": ["cpu", "gpu"], "quick": {}"#,
        );
        if what != "vertex_ao" {
            text = text.replace(
                r#""render": { "#,
                &format!(r#""render": {{ "what": "{what}", {own}"#),
            );
        }
        let rows = common::frames_of(dir.path(), &text, what);
        let of = |m: &str| -> Vec<_> { rows.iter().filter(|r| r.method == m).collect() };
        let (cpu, gpu) = (of("two_level"), of("rayquery@gpu"));
        let run: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join(what).join("run.json")).unwrap())
                .unwrap();
        // The adapter of the GPU rows, named in the run's metadata.
        assert_eq!(
            run["meta"]["gpu_adapter"].as_str(),
            Some(ctx.adapter_label().as_str()),
            "{what}"
        );
        let skipped = run["skipped_methods"].as_array().unwrap().clone();
        let skipped_rq = skipped.iter().any(|m| m["method"] == "rayquery@gpu");
        if ctx.ray_query_support().is_err() {
            assert!(gpu.is_empty() && skipped_rq, "{what}: {skipped:?}");
            continue;
        }
        assert!(!skipped_rq && cpu.len() == 2 && gpu.len() == 2, "{what}");
        for (c, g) in cpu.iter().zip(&gpu) {
            assert_eq!((c.frame, c.points, c.rays), (g.frame, g.points, g.rays));
            assert!(
                (c.rms_vs_raycast - g.rms_vs_raycast).abs() < 0.5
                    && (c.mean_value - g.mean_value).abs() < 0.002
                    && g.update_s > 0.0,
                "{what} frame {}: {c:?}\n{g:?}",
                c.frame
            );
        }
        assert!(
            (gpu[0].mean_value - gpu[1].mean_value).abs() > 0.004,
            "{what}: the lift moves the answer"
        );
    }
}

fn main() {
    let args = libtest_mimic::Arguments::from_args();
    // (name, body, what it needs: 2 ray queries, 1 a Vulkan adapter, 0 nothing).
    let tests: [(&'static str, fn(), u8); 7] = [
        (
            "ray_queries_answer_as_the_cpu_caster",
            ray_queries_answer_as_the_cpu_caster,
            2,
        ),
        (
            "moved_instances_answer_as_the_cpu_caster",
            moved_instances_answer_as_the_cpu_caster,
            2,
        ),
        (
            "empty_scenes_miss_and_bad_input_is_refused",
            empty_scenes_miss_and_bad_input_is_refused,
            2,
        ),
        (
            "integrands_on_ray_queries_match_the_cpu",
            integrands_on_ray_queries_match_the_cpu,
            2,
        ),
        (
            "rayquery_method_runs_or_is_skipped_with_the_reason",
            rayquery_method_runs_or_is_skipped_with_the_reason,
            1,
        ),
        (
            "rayquery_twin_answers_as_two_level_every_frame",
            rayquery_twin_answers_as_two_level_every_frame,
            1,
        ),
        (
            "rayquery_is_refused_on_the_cpu_backend",
            rayquery_is_refused_on_the_cpu_backend,
            0,
        ),
    ];
    let trials = tests
        .into_iter()
        .map(|(name, f, needs)| {
            libtest_mimic::Trial::ignorable_test(name, move || {
                let why = match needs {
                    2 => device().err(),
                    1 => common::gpu_context()
                        .is_none()
                        .then(|| "no Vulkan adapter (install mesa-vulkan-drivers)".to_string()),
                    _ => None,
                };
                if let Some(why) = why {
                    return Ok(libtest_mimic::Completion::ignored_with(why));
                }
                f();
                Ok(libtest_mimic::Completion::Completed)
            })
        })
        .collect();
    libtest_mimic::run(&args, trials).exit()
}
