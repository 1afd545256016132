//! GPU soft shadows (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010, §4.2) against
//! the CPU path, per point, on the same fields, casters, lights and rays: field lookup
//! ([`FieldShadowKernel`]) against `shadow_at_points` over a `FieldScene`, and GPU ray casting
//! (`gpu::shadows` on a [`GpuTracer`]) against it over the CPU tracer; then a shadows run on both
//! backends.
//!
//! The tolerance. A point's value is S = Σ_lit w / Σ w over its shadow rays. When GPU and CPU
//! block the same rays, S differs only by the GPU's f32 weights (about 4 roundings each: 4u,
//! u = 2⁻²⁴) and its f32 sums over the m rays of one invocation (at most (m − 1)u relative
//! each; the host adds the invocations' sums in f64): |ΔS| ≤ 2(m + 3)u, 6e-6 for m = 48
//! ([`close_tolerance`]). A ray that grazes an edge (of a triangle, of a map's texel, of a
//! bounding sphere) may be decided differently when a direction or a sphere crossing is
//! rounded differently (the GPU computes the crossing in f32, the host in f64; drivers may
//! contract multiply-adds), and then S moves by that ray's share w_i / Σ w. So the tests ask
//! that at least 99.5% of points agree within the rounding bound and that no point differ by
//! more than its two largest ray shares plus it ([`Agreement`]). A negative control (the GPU
//! on another seed's rays) must fail the same check, and the scene must cast real shadows.
//!
//! Only a missing Vulkan driver skips these tests (reported as ignored, with the reason
//! printed; the harness is `main`, through libtest-mimic); every other GPU failure fails them.

use glam::{Quat, Vec3};
use std::sync::{Arc, OnceLock};
use std::time::Instant;
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{Precision, Selection, VisibilityField};
use visfield::geometry::Similarity;
use visfield::gpu::{FieldGpuOptions, FieldLayout, FieldShadowKernel, GpuError, GpuTracer};
use visfield::render::ao::AoOptions;
use visfield::render::shadow::{shadow_at_points, LightCone, ShadowOptions, SphereLight};
use visfield::sampling::rays::RaySet;
use visfield::trace::Tracer;
use visfield::visibility::Visibility;

mod common;
use common::{
    gpu_context as context, loaded, options, slater_params, supershape_2000 as caster, tiny,
    ONE_FIELD,
};

/// Its field: 290 Slater maps × 16² concentric texels, 8-bit.
fn field() -> &'static Arc<VisibilityField> {
    static FIELD: OnceLock<Arc<VisibilityField>> = OnceLock::new();
    FIELD.get_or_init(|| {
        let p = slater_params(290, 16, Precision::U8);
        Arc::new(bake(caster(), p, &BakeOptions::default()).expect("bake").0)
    })
}

/// The caster placed with bounding radius 0.35 at (0.5, 0.45, 0.5), tilted, over the floor
/// y = 0.
fn placed() -> FieldInstance {
    let f = field();
    let s = f.bounds;
    let rotation = Quat::from_euler(glam::EulerRot::YXZ, 0.4, 0.25, 0.0);
    let scale = 0.35 / s.radius;
    let translation = Vec3::new(0.5, 0.45, 0.5) - scale * (rotation * s.center);
    FieldInstance::new(f.clone(), Similarity::new(rotation, translation, scale))
}

/// The caster's world triangles (the ray-cast scene: the floor casts no shadow on itself).
fn caster_triangles(inst: &FieldInstance) -> Vec<[Vec3; 3]> {
    let c = caster();
    (0..c.triangles.len())
        .map(|i| c.triangle(i).map(|v| inst.transform.to_world_point(v)))
        .collect()
}

/// Three lights of different sizes and radiances: overhead, oblique, low and small.
fn lights() -> ShadowOptions {
    let l = |c: [f32; 3], radius, intensity| SphereLight {
        center: Vec3::from_array(c),
        radius,
        intensity,
    };
    ShadowOptions {
        offset: AoOptions::for_scene_radius(1.0).offset,
        lights: vec![
            l([0.6, 2.2, 0.4], 0.25, 1.0),
            l([2.0, 1.6, 1.2], 0.5, 2.0),
            l([-1.0, 1.2, -0.3], 0.15, 0.7),
        ],
    }
}

/// Receivers: a 56 × 56 floor grid around the caster's shadow (inter-object lookups) and every
/// third vertex of the placed caster (intra-object lookups; some face away from every light).
fn receivers(inst: &FieldInstance) -> (Vec<Vec3>, Vec<Vec3>) {
    let n = 56;
    let mut p = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let t = |k: usize| -0.6 + 2.2 * (k as f32 + 0.5) / n as f32;
            p.push(Vec3::new(t(i), 0.0, t(j)));
        }
    }
    let mut nrm = vec![Vec3::Y; p.len()];
    let c = caster();
    for (q, m) in c.positions.iter().zip(&c.normals).step_by(3) {
        p.push(inst.transform.to_world_point(*q));
        nrm.push(inst.transform.to_world_dir(*m).normalize());
    }
    (p, nrm)
}

/// The shadow rays' weights at one point, as `render::shadow` defines them (a copy of its
/// private `shadow_rays` through the public pieces; [`the_copied_shadow_rays_are_the_cpu_path`]
/// checks it): (origin, directions, far ends, weights).
fn shadow_rays(
    i: u32,
    p: Vec3,
    n: Vec3,
    rays: &RaySet,
    opts: &ShadowOptions,
) -> (Vec3, Vec<Vec3>, Vec<f32>, Vec<f64>) {
    let origin = p + opts.offset * n;
    let (s, c) = rays.rotation(i);
    let mut squares = Vec::new();
    rays.fill_square(i, &mut squares);
    let (mut dirs, mut tmaxs, mut weights) = (Vec::new(), Vec::new(), Vec::new());
    for light in &opts.lights {
        let Some(cone) = LightCone::new(light, origin, squares.len()) else {
            continue;
        };
        let samples = if cone.point { 1 } else { squares.len() };
        for &u in &squares[..samples] {
            let dir = cone.direction(u, s, c);
            let cos_n = n.dot(dir);
            if cos_n <= 0.0 {
                continue;
            }
            dirs.push(dir);
            tmaxs.push(cone.far_end(dir));
            weights.push(cone.weight_scale * cos_n as f64);
        }
    }
    (origin, dirs, tmaxs, weights)
}

/// Per point, the sum of its two largest ray shares w_i / Σ w (0 without weight): how far two
/// flipped rays can move its value.
fn two_ray_shares(p: &[Vec3], n: &[Vec3], rays: &RaySet, opts: &ShadowOptions) -> Vec<f32> {
    p.iter()
        .zip(n)
        .enumerate()
        .map(|(i, (&p, &n))| {
            let (_, _, _, mut w) = shadow_rays(i as u32, p, n, rays, opts);
            let total: f64 = w.iter().sum();
            if total <= 0.0 {
                return 0.0;
            }
            w.sort_by(|a, b| b.total_cmp(a));
            (w.iter().take(2).sum::<f64>() / total) as f32
        })
        .collect()
}

/// The bound on |GPU − CPU| when both block the same rays, `m` rays summed in f32 per
/// invocation: 2(m + 3)u (see the module docs).
fn close_tolerance(m: u32) -> f32 {
    2.0 * (m as f32 + 3.0) * f32::EPSILON / 2.0
}

/// Per-point agreement of a GPU result with the CPU's.
#[derive(Debug)]
struct Agreement {
    /// Share of points within the rounding bound.
    close_share: f64,
    /// Largest |Δ|.
    max_diff: f32,
    /// Points farther apart than two of their rays' shares (plus the rounding bound).
    over_two_rays: usize,
}

impl Agreement {
    fn of(gpu: &[f32], cpu: &[f32], shares: &[f32], close: f32) -> Agreement {
        assert_eq!(gpu.len(), cpu.len());
        let (mut near, mut max_diff, mut over) = (0usize, 0.0f32, 0usize);
        for ((g, c), s) in gpu.iter().zip(cpu).zip(shares) {
            let d = (g - c).abs();
            near += (d <= close) as usize;
            max_diff = max_diff.max(d);
            over += (d > s + close) as usize;
        }
        Agreement {
            close_share: near as f64 / gpu.len().max(1) as f64,
            max_diff,
            over_two_rays: over,
        }
    }

    /// The parity criterion of the module docs.
    fn holds(&self) -> bool {
        self.close_share >= 0.995 && self.over_two_rays == 0
    }
}

/// The scene must cast real shadows, or agreement proves little: a good share of points in
/// partial or full shadow, some deep in it, and some fully lit.
fn assert_shadows_are_nontrivial(cpu: &[f32]) {
    let shadowed = cpu.iter().filter(|&&v| v < 1.0).count();
    let deep = cpu.iter().filter(|&&v| v < 0.5).count();
    let lit = cpu.iter().filter(|&&v| v == 1.0).count();
    assert!(
        shadowed * 10 > cpu.len() && deep * 50 > cpu.len() && lit * 10 > cpu.len(),
        "{shadowed} of {} points shadowed, {deep} below 0.5, {lit} fully lit",
        cpu.len()
    );
}

/// Checks `gpu` against `cpu` and the negative control `other` (the GPU on another seed's
/// rays) against `cpu`, printing the figures; panics naming `label` on failure.
fn check(label: &str, gpu: &[f32], cpu: &[f32], other: &[f32], shares: &[f32], m: u32) {
    let close = close_tolerance(m);
    let a = Agreement::of(gpu, cpu, shares, close);
    let neg = Agreement::of(other, cpu, shares, close);
    eprintln!(
        "{label}: {} points, {:.3}% within {close:.1e}, max |Δ| {:.2e}, {} beyond two rays' \
         share; negative control (other seed): {:.1}% within, max |Δ| {:.3}",
        gpu.len(),
        100.0 * a.close_share,
        a.max_diff,
        a.over_two_rays,
        100.0 * neg.close_share,
        neg.max_diff
    );
    assert!(a.holds(), "{label}: GPU and CPU disagree: {a:?}");
    assert!(
        !neg.holds(),
        "{label}: the check cannot fail: {neg:?} for another seed's rays"
    );
}

fn the_copied_shadow_rays_are_the_cpu_path() {
    // The test's copy of `shadow_rays` gives `shadow_at_points` bit for bit (so its weights
    // are the CPU's); no GPU needed, but it guards the tolerance the others use.
    let inst = placed();
    let tracer = Tracer::new(&caster_triangles(&inst));
    let (p, n) = receivers(&inst);
    let opts = lights();
    let rays = RaySet::new(4, 7);
    let cpu = shadow_at_points(&tracer, &p, &n, &rays, &opts);
    for (i, (&q, &m)) in p.iter().zip(&n).enumerate().step_by(7) {
        let (o, dirs, tmaxs, w) = shadow_rays(i as u32, q, m, &rays, &opts);
        let mut blocked = vec![false; dirs.len()];
        tracer.occluded_many_to(o, &dirs, 0.0, &tmaxs, &mut blocked);
        let total: f64 = w.iter().sum();
        let lit: f64 = w
            .iter()
            .zip(&blocked)
            .filter(|(_, &b)| !b)
            .map(|(w, _)| w)
            .sum();
        let v = if total > 0.0 {
            (lit / total) as f32
        } else {
            1.0
        };
        assert_eq!(v, cpu[i], "point {i}");
    }
}

fn field_shadows_match_the_cpu_for_both_selections_and_layouts() {
    let Some(ctx) = context() else { return };
    let inst = placed();
    let (p, n) = receivers(&inst);
    let opts = lights();
    let rays = RaySet::new(4, 7);
    let other = RaySet::new(4, 8);
    let shares = two_ray_shares(&p, &n, &rays, &opts);
    let m = (rays.len() * opts.lights.len()) as u32;
    for layout in [FieldLayout::StorageBuffers, FieldLayout::Texture3d] {
        let gpu_opts = FieldGpuOptions {
            layout,
            ..Default::default()
        };
        let mut kernel =
            FieldShadowKernel::new(ctx, std::slice::from_ref(&inst), &gpu_opts).unwrap();
        for selection in [Selection::Nearest, Selection::Interpolated] {
            let lookup = LookupOptions {
                selection,
                ..Default::default()
            };
            let scene = FieldScene {
                instances: vec![inst.clone()],
                options: lookup,
            };
            let t = Instant::now();
            let cpu = shadow_at_points(&scene, &p, &n, &rays, &opts);
            let cpu_s = t.elapsed();
            assert_shadows_are_nontrivial(&cpu);
            kernel.lookup = lookup;
            // The negative control first: lavapipe compiles the kernel on its first dispatch,
            // which the timed call should not include.
            let (neg, _) = visfield::gpu::shadows(&kernel, &p, &n, &other, &opts).unwrap();
            let (gpu, timing) = visfield::gpu::shadows(&kernel, &p, &n, &rays, &opts).unwrap();
            let label = format!("field {layout:?} {selection:?}");
            eprintln!(
                "{label}: {} points × {m} rays: CPU {cpu_s:?} ({} threads), GPU kernel {:?}, \
                 wall {:?}",
                p.len(),
                rayon::current_num_threads(),
                timing.kernel,
                timing.wall
            );
            check(&label, &gpu, &cpu, &neg, &shares, m);
        }
    }
}

fn ray_cast_shadows_match_the_cpu_tracer() {
    let Some(ctx) = context() else { return };
    let inst = placed();
    let tris = caster_triangles(&inst);
    let (p, n) = receivers(&inst);
    let opts = lights();
    let cpu_tracer = Tracer::new(&tris);
    let gpu_tracer = GpuTracer::new(ctx, &tris).unwrap();
    for k in [4u32, 5] {
        let rays = RaySet::new(k, 7);
        let shares = two_ray_shares(&p, &n, &rays, &opts);
        let m = (rays.len() * opts.lights.len()) as u32;
        let t = Instant::now();
        let cpu = shadow_at_points(&cpu_tracer, &p, &n, &rays, &opts);
        let cpu_s = t.elapsed();
        assert_shadows_are_nontrivial(&cpu);
        // The negative control first (lavapipe compiles on the first dispatch).
        let (neg, _) =
            visfield::gpu::shadows(&gpu_tracer, &p, &n, &RaySet::new(k, 8), &opts).unwrap();
        let (gpu, timing) = visfield::gpu::shadows(&gpu_tracer, &p, &n, &rays, &opts).unwrap();
        let label = format!("ray casting, k = {k}");
        eprintln!(
            "{label}: {} points × {m} rays: CPU {cpu_s:?} ({} threads), GPU kernel {:?}, wall {:?}",
            p.len(),
            rayon::current_num_threads(),
            timing.kernel,
            timing.wall
        );
        check(&label, &gpu, &cpu, &neg, &shares, m);
    }
}

fn many_rays_split_over_invocations_across_lights_match_the_cpu() {
    // k = 12: 144 rays per light, 432 per point. The tracer starts at 256 rays per invocation
    // (its second run starts inside the second light); the field kernel is asked for 40 (11
    // runs, most straddling no boundary, three straddling one). Every fifth receiver.
    let Some(ctx) = context() else { return };
    let inst = placed();
    let tris = caster_triangles(&inst);
    let (p, n) = receivers(&inst);
    let (p, n): (Vec<Vec3>, Vec<Vec3>) = p.into_iter().zip(n).step_by(5).unzip();
    let opts = lights();
    let rays = RaySet::new(12, 3);
    let other = RaySet::new(12, 4);
    let shares = two_ray_shares(&p, &n, &rays, &opts);

    let cpu = shadow_at_points(&Tracer::new(&tris), &p, &n, &rays, &opts);
    assert_shadows_are_nontrivial(&cpu);
    let tracer = GpuTracer::new(ctx, &tris).unwrap();
    let (gpu, _) = visfield::gpu::shadows(&tracer, &p, &n, &rays, &opts).unwrap();
    let (neg, _) = visfield::gpu::shadows(&tracer, &p, &n, &other, &opts).unwrap();
    check("ray casting, k = 12", &gpu, &cpu, &neg, &shares, 256);

    let scene = FieldScene {
        instances: vec![inst.clone()],
        options: LookupOptions::default(),
    };
    let cpu = shadow_at_points(&scene, &p, &n, &rays, &opts);
    let gpu_opts = FieldGpuOptions {
        rays_per_invocation: 40,
        ..Default::default()
    };
    let kernel = FieldShadowKernel::new(ctx, &[inst], &gpu_opts).unwrap();
    let (gpu, _) = visfield::gpu::shadows(&kernel, &p, &n, &rays, &opts).unwrap();
    let (neg, _) = visfield::gpu::shadows(&kernel, &p, &n, &other, &opts).unwrap();
    check(
        "field, k = 12, 40 rays an invocation",
        &gpu,
        &cpu,
        &neg,
        &shares,
        kernel.rays_per_invocation(),
    );
}

fn edge_cases_are_those_of_the_cpu() {
    let Some(ctx) = context() else { return };
    let inst = placed();
    let tris = caster_triangles(&inst);
    let tracer = GpuTracer::new(ctx, &tris).unwrap();
    let kernel = FieldShadowKernel::new(ctx, &[inst], &FieldGpuOptions::default()).unwrap();
    let rays = RaySet::new(4, 1);
    let opts = lights();
    // A point inside a light skips it; a point facing away from every light is lit (no
    // weight); no points, no values.
    let p = [
        opts.lights[0].center,
        Vec3::new(0.5, -1.0, 0.5),
        Vec3::new(0.5, 0.0, 0.5),
    ];
    let n = [Vec3::Y, -Vec3::Y, Vec3::Y];
    let cpu = shadow_at_points(&Tracer::new(&tris), &p, &n, &rays, &opts);
    assert_eq!(cpu[1], 1.0);
    let (g, _) = visfield::gpu::shadows(&tracer, &p, &n, &rays, &opts).unwrap();
    let (f, _) = visfield::gpu::shadows(&kernel, &p, &n, &rays, &opts).unwrap();
    for (i, c) in cpu.iter().enumerate() {
        assert!(
            (g[i] - c).abs() <= close_tolerance(48),
            "{i}: {} vs {c}",
            g[i]
        );
        assert!(
            f[i].is_finite() && (0.0..=1.0).contains(&f[i]),
            "{i}: {}",
            f[i]
        );
    }
    assert_eq!(f[1], 1.0);
    assert!(visfield::gpu::shadows(&tracer, &[], &[], &rays, &opts)
        .unwrap()
        .0
        .is_empty());
    // Jittered ray sets have no shared samples: refused, not approximated.
    let jittered = RaySet {
        jitter: true,
        ..rays
    };
    assert!(matches!(
        visfield::gpu::shadows(&kernel, &p, &n, &jittered, &opts),
        Err(GpuError::Unsupported(_))
    ));
    assert!(matches!(
        visfield::gpu::shadows(&tracer, &p, &n, &jittered, &opts),
        Err(GpuError::Unsupported(_))
    ));
}

const LIGHTS: &str = r#"[{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }, { "center": [-0.5, 3.0, 1.5], "radius": 0.5, "intensity": 2 }]"#;

/// A shadows run with `backends: ["cpu", "gpu"]`: one row per backend, the GPU row naming its
/// adapter, with the CPU row's same-ray error (the same field, lights and rays: within 0.5 on
/// the 0–255 scale, where the per-point parity above allows a few pixels to move by two rays'
/// share), and GPU ray-cast rows in the sweep at the CPU reference's error.
fn a_shadows_run_on_cpu_and_gpu_gives_matching_rows() {
    let Some(ctx) = context() else { return };
    let label = ctx.adapter_label();
    let dir = tempfile::tempdir().unwrap();
    let text = tiny(ONE_FIELD, "")
        .replace(
            r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
            &format!(
                r#""render": {{ "what": "shadows", "rays_per_point": 16, "image": {{ "width": 32, "height": 32 }}, "lights": {LIGHTS} }}"#
            ),
        )
        .replace(
            r#""reference": {"#,
            r#""backends": ["cpu", "gpu"], "reference": {"#,
        );
    let ls = loaded(dir.path(), &text);
    let report = visfield::experiment::run::run(&ls, &options(dir.path().join("out"))).unwrap();
    let rows = &report.rows;
    assert_eq!(rows.len(), 2, "one cell on two backends");
    let (cpu, gpu) = (&rows[0], &rows[1]);
    assert_eq!((cpu.backend.name(), gpu.backend.name()), ("cpu", "gpu"));
    assert_eq!(gpu.adapter, label);
    assert_eq!(gpu.rays_cast, cpu.rays_cast);
    let (c, g) = (cpu.rms_image.unwrap(), gpu.rms_image.unwrap());
    eprintln!(
        "shadows run: same-ray RMS cpu {c:.4} gpu {g:.4} (0–255); vs truth cpu {:?} gpu {:?}; \
         field time cpu {:.4} s, gpu {:.4} s (kernel {:?})",
        cpu.rms_vs_truth, gpu.rms_vs_truth, cpu.estimate_s, gpu.estimate_s, gpu.estimate_kernel_s
    );
    assert!(c > 0.0 && (c - g).abs() <= 0.5, "cpu {c} gpu {g}");
    let (ct, gt) = (cpu.rms_vs_truth.unwrap(), gpu.rms_vs_truth.unwrap());
    assert!((ct - gt).abs() <= 0.5, "vs truth: cpu {ct} gpu {gt}");
    assert!(gpu.setup_s.unwrap() > 0.0 && gpu.raycast_s.unwrap() > 0.0);
    assert_eq!(gpu.estimate_kernel_s.is_some(), ctx.has_timestamps());
    // GPU ray casting on the reference's rays reproduces the CPU reference.
    let sweep: Vec<visfield::experiment::outputs::SweepRow> =
        visfield::experiment::outputs::read_csv(&dir.path().join("out/raycast_sweep.csv")).unwrap();
    let gpu_rows: Vec<_> = sweep.iter().filter(|r| r.backend.name() == "gpu").collect();
    assert!(!gpu_rows.is_empty(), "{sweep:?}");
    for r in gpu_rows {
        if r.rays_per_point == 16 {
            let e = r.rms_image.unwrap();
            assert!(e <= 0.5, "GPU ray casting vs the CPU reference: {e}");
        }
    }
}

/// The harness: every test above, run where a Vulkan adapter exists and reported as ignored,
/// with the reason, where none does (a skipped test never shows as passed). The CPU-only check
/// runs everywhere.
fn main() {
    common::run_gpu_trials(
        "gpu_shadow",
        &[
            (
                "field_shadows_match_the_cpu_for_both_selections_and_layouts",
                field_shadows_match_the_cpu_for_both_selections_and_layouts,
            ),
            (
                "ray_cast_shadows_match_the_cpu_tracer",
                ray_cast_shadows_match_the_cpu_tracer,
            ),
            (
                "many_rays_split_over_invocations_across_lights_match_the_cpu",
                many_rays_split_over_invocations_across_lights_match_the_cpu,
            ),
            (
                "edge_cases_are_those_of_the_cpu",
                edge_cases_are_those_of_the_cpu,
            ),
            (
                "a_shadows_run_on_cpu_and_gpu_gives_matching_rows",
                a_shadows_run_on_cpu_and_gpu_gives_matching_rows,
            ),
        ],
        &[(
            "the_copied_shadow_rays_are_the_cpu_path",
            the_copied_shadow_rays_are_the_cpu_path,
        )],
    );
}
