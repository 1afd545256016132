//! Two-level ray casting on the GPU (`gpu::GpuTwoLevel`) against the CPU's two-level caster
//! (`trace::two_level::TwoLevel`) ray for ray on a moving scene, through every integrand, and
//! on a crowd that the world BVH on the GPU refuses.
//!
//! Only a missing Vulkan driver skips these tests (reported as ignored, with the reason
//! printed; the harness is `main`, through libtest-mimic); every other GPU failure fails them.

use glam::{Quat, Vec3};
use visfield::geometry::procedural::{supershape, uv_sphere, Supershape};
use visfield::geometry::Similarity;
use visfield::gpu::{GpuError, GpuTracer, GpuTwoLevel};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::reflect::{reflect_at_points, Gloss, ReflectOptions};
use visfield::render::shadow::{shadow_at_points, ShadowOptions, SphereLight};
use visfield::sampling::rays::RaySet;
use visfield::trace::two_level::TwoLevel;
use visfield::trace::RayQuery;
use visfield::visibility::Visibility;

mod common;
use common::gpu_context as context;
use common::{triangles as tris, unit};

/// Nine instances of two meshes on a 3 × 3 grid, each moved, turned and scaled per frame
/// (tests/two_level.rs's choreography).
fn frame_instances(frame: u64) -> Vec<(usize, Similarity)> {
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

/// Rays from above the grid down through it.
fn frame_rays(frame: u64, n: u64) -> Vec<RayQuery> {
    (0..n)
        .map(|r| {
            let s = frame * 10_000 + r;
            let o = Vec3::new(-2.0 + 9.0 * unit(s), 3.0, -2.0 + 9.0 * unit(s + 1));
            let target = Vec3::new(5.0 * unit(s + 2), 0.0, 5.0 * unit(s + 3));
            RayQuery {
                origin: o,
                dir: (target - o).normalize(),
                tmin: 0.0,
                tmax: 20.0,
            }
        })
        .collect()
}

/// Counts of a comparison of the GPU's answers with the CPU's on the same rays.
#[derive(Debug, Default)]
struct Agreement {
    rays: usize,
    cpu_hits: usize,
    /// Rays whose any-hit answers differ, and whose closest-hit answers differ in hit or miss.
    any_differ: usize,
    closest_differ: usize,
    /// Largest relative distance difference where both hit.
    dist_err: f32,
    /// Common hits whose normals differ (|n_gpu · n_cpu| below 0.999: another triangle).
    normal_differ: usize,
}

fn compare(tl: &TwoLevel, gpu: &GpuTwoLevel, rays: &[RayQuery], acc: &mut Agreement) {
    let (any, _) = gpu.any_hits(rays).unwrap();
    let (closest, _) = gpu.closest_hits(rays).unwrap();
    for (r, (a, c)) in rays.iter().zip(any.iter().zip(&closest)) {
        acc.rays += 1;
        let cpu = tl.surface_hit(r.origin, r.dir, r.tmin, r.tmax);
        let cpu_any = tl.occluded(r.origin, r.dir, r.tmin, r.tmax);
        acc.cpu_hits += cpu.is_some() as usize;
        acc.any_differ += (*a != cpu_any) as usize;
        acc.closest_differ += (c.is_some() != cpu.is_some()) as usize;
        if let (Some(g), Some(h)) = (c, cpu) {
            acc.dist_err = acc.dist_err.max((g.t - h.t).abs() / h.t);
            if g.normal.dot(h.normal).abs() < 0.999 {
                acc.normal_differ += 1;
            }
            assert!(
                (g.normal.length() - 1.0).abs() < 1e-5,
                "normal {:?} not unit",
                g.normal
            );
        }
    }
}

/// The tolerance of tests/two_level.rs (the CPU's two levels against its world tracer): all
/// but one ray in a thousand (edge-grazing ones) answer alike, distances within 1e-4 relative.
fn assert_agrees(acc: &Agreement) {
    eprintln!("{acc:?}");
    let n = acc.rays;
    assert!(
        acc.cpu_hits > n / 5 && acc.cpu_hits < n,
        "{} of {n} hit",
        acc.cpu_hits
    );
    assert!(acc.any_differ <= n / 1000, "any hit: {acc:?}");
    assert!(acc.closest_differ <= n / 1000, "closest hit: {acc:?}");
    assert!(acc.dist_err < 1e-4, "distances: {acc:?}");
    assert!(acc.normal_differ <= n / 1000, "normals: {acc:?}");
}

/// Every frame of a moving scene (the instances moved, turned and rescaled, the top level
/// rebuilt and uploaded each frame, the meshes' BVHs uploaded once): any hit, closest hit and
/// normal as the CPU's two levels, ray for ray.
fn gpu_two_levels_answer_as_the_cpu_two_levels_on_every_frame() {
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    let meshes = [
        supershape(&Supershape::default(), 3000).unwrap(),
        uv_sphere(1.0, 12, 24).unwrap(),
    ];
    let model: Vec<Vec<[Vec3; 3]>> = meshes.iter().map(tris).collect();
    let mut cpu = TwoLevel::new(&model);
    let mut gpu = GpuTwoLevel::new(ctx, &model).unwrap();
    let mut acc = Agreement::default();
    let mut first_frame_hits = None;
    for frame in 0..4u64 {
        let instances = frame_instances(frame);
        cpu.update(&instances);
        gpu.update(&instances).unwrap();
        let rays = frame_rays(frame, 4000);
        compare(&cpu, &gpu, &rays, &mut acc);
        // The motion reaches the device: frame 0's rays answered on this frame's placement
        // differ from frame 0's answers somewhere (and as the CPU's).
        let (hits, _) = gpu.any_hits(&frame_rays(0, 4000)).unwrap();
        match &first_frame_hits {
            None => first_frame_hits = Some(hits),
            Some(first) => assert_ne!(first, &hits, "frame {frame} answers as frame 0"),
        }
    }
    assert_agrees(&acc);
}

/// No instance: every ray misses; the same visibility placed again answers again.
fn gpu_two_levels_without_instances_miss_everything() {
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    let model = vec![tris(&uv_sphere(1.0, 8, 8).unwrap())];
    let mut gpu = GpuTwoLevel::new(ctx, &model).unwrap();
    let ray = RayQuery {
        origin: Vec3::new(0.0, -5.0, 0.0),
        dir: Vec3::Y,
        tmin: 0.0,
        tmax: 10.0,
    };
    gpu.update(&[]).unwrap();
    assert_eq!(gpu.any_hits(&[ray]).unwrap().0, vec![false]);
    assert_eq!(gpu.closest_hits(&[ray]).unwrap().0, vec![None]);
    gpu.update(&[(0, Similarity::default())]).unwrap();
    let (hit, _) = gpu.closest_hits(&[ray]).unwrap();
    // The unit sphere's polygon from 5 below: entered at 4 (its vertices on the sphere, the
    // pole a vertex).
    let t = hit[0].expect("a hit").t;
    assert!((t - 4.0).abs() < 1e-5, "{t}");
    // A mesh index that does not exist is refused by name.
    let err = gpu.update(&[(3, Similarity::default())]).unwrap_err();
    assert!(err.to_string().contains("mesh 3"), "{err}");
}

/// AO, soft shadows and mirror reflections through the GPU two levels give the CPU's values
/// through its two levels on the same rays: no ray decided differently on all but 1% of the
/// points (beyond the f32 sums' rounding), and there by about one ray's share at most;
/// the reflected radiance within 1e-3 at 99% of the points.
fn every_integrand_runs_on_the_gpu_two_levels_as_on_the_cpu() {
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    let model = vec![tris(&supershape(&Supershape::default(), 2000).unwrap())];
    // A 4 × 4 crowd floating over the floor z = 0, turned.
    let instances: Vec<(usize, Similarity)> = (0..16u64)
        .map(|i| {
            let pos = Vec3::new((i % 4) as f32 - 1.5, (i / 4) as f32 - 1.5, 0.6);
            let rot =
                Quat::from_axis_angle(Vec3::new(unit(i), 1.0, 0.3).normalize(), 3.0 * unit(i + 3));
            (0, Similarity::new(rot, pos, 0.35))
        })
        .collect();
    let mut cpu = TwoLevel::new(&model);
    cpu.update(&instances);
    let mut gpu = GpuTwoLevel::new(ctx, &model).unwrap();
    gpu.update(&instances).unwrap();
    let points: Vec<Vec3> = (0..20 * 20)
        .map(|i| {
            Vec3::new(
                (i % 20) as f32 * 0.2 - 1.9,
                (i / 20) as f32 * 0.2 - 1.9,
                0.0,
            )
        })
        .collect();
    let normals = vec![Vec3::Z; points.len()];
    let rays = RaySet::new(8, 5);
    // `rounding`: what the device's f32 sums may move a value with every ray decided alike
    // (docs/gpu.md: within 2(m + 3)·2⁻²⁴ for m rays an invocation); a point differing by
    // more had a ray decided otherwise.
    let check = |what: &str, g: &[f32], c: &[f32], rounding: f32, max_diff: f32| {
        let differ = g
            .iter()
            .zip(c)
            .filter(|(a, b)| (*a - *b).abs() > rounding)
            .count();
        let max = g
            .iter()
            .zip(c)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        eprintln!("{what}: {differ} of {} differ, max {max}", g.len());
        assert!(
            differ * 100 <= g.len() && max <= max_diff,
            "{what}: {differ} differ, max {max}"
        );
        assert!(c.iter().any(|&v| v != c[0]), "{what}: a trivial scene");
    };
    let ao = AoOptions {
        max_distance: Some(1.0),
        ..AoOptions::for_scene_radius(2.0)
    };
    let (g, _) = visfield::gpu::ao(&gpu, &points, &normals, &rays, &ao).unwrap();
    check(
        "AO",
        &g,
        &ao_at_points(&cpu, &points, &normals, &rays, &ao),
        0.0,
        1.0 / 64.0,
    );
    let light = SphereLight {
        center: Vec3::new(0.3, 0.2, 3.0),
        radius: 0.5,
        intensity: 1.0,
    };
    let sh = ShadowOptions {
        offset: 1e-4,
        lights: vec![light],
    };
    let (g, _) = visfield::gpu::shadows(&gpu, &points, &normals, &rays, &sh).unwrap();
    let c = shadow_at_points(&cpu, &points, &normals, &rays, &sh);
    check(
        "shadows",
        &g,
        &c,
        2.0 * 67.0 * 2f32.powi(-24),
        1.0 / 64.0 + 1e-3,
    );
    let refl = ReflectOptions {
        offset: 1e-4,
        eye: Vec3::new(0.0, -4.0, 2.0),
        gloss: Gloss::Mirror,
        lights: vec![light],
        albedo: 0.8,
        sky: 0.1,
    };
    let (g, _) = visfield::gpu::reflections(&gpu, &points, &normals, &rays, &refl).unwrap();
    let c = reflect_at_points(&cpu, &points, &normals, &rays, &refl);
    let close = g
        .iter()
        .zip(&c)
        .filter(|(a, b)| (*a - *b).abs() <= 1e-3)
        .count();
    eprintln!("reflections: {close} of {} within 1e-3", c.len());
    assert!(
        close * 100 >= 99 * c.len(),
        "reflections: {close} of {} close",
        c.len()
    );
    assert!(c.iter().any(|&v| v != 0.1) && c.contains(&0.1));
}

/// A crowd of 64 casters of one mesh sized so that the world's copies pass one storage binding:
/// the world BVH on the GPU is refused (`TooLarge`), the two levels (the mesh once, 64
/// placements) build and answer as the CPU's two levels. Where the adapter's binding is so
/// large that the mesh would take long to build (past 200,000 triangles), a 2,000-triangle mesh
/// shows the two levels at 64 casters alone, and the refusal is skipped with that reason.
fn a_crowd_the_world_bvh_refuses_runs_on_the_two_levels() {
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    // Three vec4 a triangle, 64 copies.
    let past_binding = (ctx.max_binding() / (48 * 64) + 1) as usize;
    let refusal = past_binding <= 200_000;
    // A little more than needed: the superformula grid rounds the count.
    let n = if refusal {
        past_binding + past_binding / 20
    } else {
        2000
    };
    let mesh = supershape(&Supershape::default(), n).unwrap();
    let model = vec![tris(&mesh)];
    let instances: Vec<(usize, Similarity)> = (0..64u64)
        .map(|i| {
            let pos = Vec3::new((i % 8) as f32, 0.0, (i / 8) as f32);
            let rot = Quat::from_axis_angle(Vec3::Y, unit(i) * 6.0);
            (0, Similarity::new(rot, pos, 0.4))
        })
        .collect();
    if refusal {
        assert!(model[0].len() * 64 * 48 > ctx.max_binding() as usize);
        let world: Vec<[Vec3; 3]> = (instances.iter())
            .flat_map(|&(_, t)| {
                model[0]
                    .iter()
                    .map(move |tri| tri.map(|v| t.to_world_point(v)))
            })
            .collect();
        match GpuTracer::new(ctx, &world) {
            Err(GpuError::TooLarge { .. }) => {}
            Err(e) => panic!("the world BVH failed otherwise: {e}"),
            Ok(_) => panic!("the world BVH of {} triangles was not refused", world.len()),
        }
    } else {
        eprintln!(
            "skipped the world BVH's refusal: the adapter's {} byte binding would take a mesh of {past_binding} triangles",
            ctx.max_binding()
        );
    }
    let mut gpu = GpuTwoLevel::new(ctx, &model).unwrap();
    gpu.update(&instances).unwrap();
    let mut cpu = TwoLevel::new(&model);
    cpu.update(&instances);
    let rays: Vec<RayQuery> = (0..3000u64)
        .map(|s| {
            let o = Vec3::new(-1.0 + 9.0 * unit(s), 2.0, -1.0 + 9.0 * unit(s + 7));
            let target = Vec3::new(7.0 * unit(s + 2), 0.0, 7.0 * unit(s + 3));
            RayQuery {
                origin: o,
                dir: (target - o).normalize(),
                tmin: 0.0,
                tmax: 20.0,
            }
        })
        .collect();
    let mut acc = Agreement::default();
    compare(&cpu, &gpu, &rays, &mut acc);
    assert_agrees(&acc);
    // The mesh once: far below the 64 copies the world BVH would hold.
    assert!(gpu.bytes() < (model[0].len() * 48 * 64 / 8) as u64);
}

/// `{"method": "two_level"}` on a still spec through the harness, on both backends (the tiny
/// spec: a supershape over a corner, vertex AO): a CPU row and a GPU row naming the adapter
/// with its upload time, both with the world ray caster's answers on the same rays (same-ray
/// error below 0.5 on the 0–255 scale) and the same error against the converged reference
/// within 0.5 of each other, that error not 0.
fn the_two_levels_run_as_a_method_on_both_backends() {
    use visfield::experiment::columns::{read_csv, NamedRow};
    let ctx = context().expect("a Vulkan adapter (the harness checked)");
    let dir = tempfile::tempdir().unwrap();
    let methods =
        r#""methods": [{"method": "two_level", "backends": ["cpu", "gpu"]}], "reference": {"#;
    let text = common::tiny(common::ONE_FIELD, "").replace(r#""reference": {"#, methods);
    let ls = common::loaded(dir.path(), &text);
    let out = dir.path().join("out");
    visfield::experiment::run::run(&ls, &common::options(out.clone())).unwrap();
    let rows: Vec<NamedRow> = read_csv(&out.join("methods.csv")).unwrap();
    let col = |name: &str| -> Vec<&str> { rows.iter().map(|r| r.get(name).unwrap()).collect() };
    assert_eq!(col("setting"), ["two_level", "two_level"]);
    assert_eq!(col("backend"), ["cpu", "gpu"]);
    let (cpu, gpu) = (&rows[0], &rows[1]);
    assert_eq!(gpu.get("adapter"), Some(ctx.adapter_label().as_str()));
    assert!(gpu.number("setup_s").unwrap() > 0.0);
    let (c, g) = (
        cpu.number("rms_vs_raycast").unwrap(),
        gpu.number("rms_vs_raycast").unwrap(),
    );
    eprintln!("rms_vs_raycast: cpu {c:.4} gpu {g:.4}");
    assert!(c < 0.5 && g < 0.5, "same-ray error: cpu {c} gpu {g}");
    let (c, g) = (
        cpu.number("rms_vs_truth").unwrap(),
        gpu.number("rms_vs_truth").unwrap(),
    );
    eprintln!("rms_vs_truth: cpu {c:.4} gpu {g:.4}");
    assert!(
        c > 0.0 && g > 0.0 && (c - g).abs() <= 0.5,
        "vs truth: cpu {c} gpu {g}"
    );
}

/// The harness: every test above, run where a Vulkan adapter exists and reported as ignored,
/// with the reason, where none does (a skipped test never shows as passed).
fn main() {
    common::run_gpu_trials(
        "gpu_two_level",
        &[
            (
                "gpu_two_levels_answer_as_the_cpu_two_levels_on_every_frame",
                gpu_two_levels_answer_as_the_cpu_two_levels_on_every_frame,
            ),
            (
                "gpu_two_levels_without_instances_miss_everything",
                gpu_two_levels_without_instances_miss_everything,
            ),
            (
                "every_integrand_runs_on_the_gpu_two_levels_as_on_the_cpu",
                every_integrand_runs_on_the_gpu_two_levels_as_on_the_cpu,
            ),
            (
                "a_crowd_the_world_bvh_refuses_runs_on_the_two_levels",
                a_crowd_the_world_bvh_refuses_runs_on_the_two_levels,
            ),
            (
                "the_two_levels_run_as_a_method_on_both_backends",
                the_two_levels_run_as_a_method_on_both_backends,
            ),
        ],
        &[],
    )
}
