//! The per-object peers on the GPU against the CPU, per point, on the same volumes, fields,
//! casters, points and rays: mesh signed distance fields sphere traced ([`SdfKernel::ao`]
//! against `ao_at_points` through an `SdfScene`), cone-traced AO and cone-traced sphere-light
//! shadows ([`SdfKernel::cone_ao`], [`SdfKernel::cone_light_fractions`] against
//! `SdfScene::cone_ao` and `cone_light_fraction`), and AO fields ([`AoFieldKernel`] against
//! `AoFieldScene::ao`), each at f32, f16 and u8. The scene: two instances of a bunny-sized
//! superformula shape (2,000 triangles, one volume or field shared by both), tilted over a
//! floor; the points: a floor grid under and around them and (for the SDF) the casters' own
//! vertices.
//!
//! **The tolerances, SDF.** The kernels port the CPU's f32 arithmetic operation for operation
//! (src/gpu/sdf_kernel.rs) and the host takes each point's mean in the CPU's order, so a point
//! whose rays (or cones) all end as on the CPU gets the CPU's value bit for bit: that is what
//! the tests ask of at least 99.5% of the points. A ray is a sequence of comparisons (a read
//! below the hit threshold, a step past the box); where a driver rounds a division or a square
//! root differently (Vulkan allows 2.5 ulp) or fuses a multiply-add, one may end otherwise, and
//! then the point's AO moves by one ray's share 1/k² (a cone's visibility by at most 1, the
//! point by that cone's weight cos β_i / Σ cos β_j; a light's by at most its weight's share).
//! No point may move by more than two of its rays' (cones', lights') shares. A negative control
//! (the GPU on another seed's rays; for the cones, on the volume at another precision) must fail
//! the same check, and the CPU's values must show real occlusion (not constant, not 1).
//!
//! **The tolerance, AO fields.** The CPU evaluates the solid angle's quadratic and the cap's
//! occlusion in f64 (`aofield::fit::Quadratic::omega`, `aofield::cap::cap_occlusion`, with
//! acos and atan2); the device in f32, the cap's closed form rewritten without cancellation and
//! its arctangent Cephes' polynomial (src/gpu/aofield_kernel.rs). Everything before that (the
//! model-space point, the cube map's bilinear read of the decoded channels, the cap's axis and
//! n·Υ̃) is the CPU's f32 code and is the same. Per occluder, |ΔÃ| ≤ ΔΩ/π + E_cap, where
//! ΔΩ ≤ Ω(4 cond(q) + 3)u (Horner's bound on q = (as + b)s + c in f32, cond(q) =
//! (|a|s² + |b|s + |c|)/|q|, then the reciprocal; u = 2⁻²⁴; ∂Ã/∂Ω ≤ 1/π since a cap grown by
//! dΩ adds at most dΩ of cos⁺ ≤ 1) and E_cap the f32 evaluation of the closed form
//! ([`E_CAP`]); the product over the occluders adds its own roundings. The bound is computed
//! per point from the stored channels ([`aofield_bound`]).
//!
//! Only a missing Vulkan driver skips these tests (reported as ignored, with the reason
//! printed; the harness is `main`, through libtest-mimic); every other GPU failure fails them.

use glam::{Quat, Vec3};
use std::sync::{Arc, OnceLock};
use std::time::Instant;
use visfield::aofield::{bake, AoField, AoFieldInstance, AoFieldScene, BakeParams, Inside};
use visfield::geometry::{Mesh, Similarity};
use visfield::gpu::{AoFieldKernel, SdfKernel};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::sampling::rays::RaySet;
use visfield::sdf::{
    ConeLight, ConeSet, ConeTrace, DistanceVolume, Precision, SdfInstance, SdfScene, SdfTrace,
};

mod common;
use common::{gpu_context as context, supershape_2000 as caster};

/// The two placements of the caster: bounding radius 0.35 at (0.5, 0.45, 0.5), tilted, and
/// 0.25 at (1.15, 0.3, 0.85), turned the other way; over the floor y = 0.
fn placements(center: Vec3, radius: f32) -> [Similarity; 2] {
    let place = |rotation: Quat, at: Vec3, r: f32| {
        let scale = r / radius;
        Similarity::new(rotation, at - scale * (rotation * center), scale)
    };
    [
        place(
            Quat::from_euler(glam::EulerRot::YXZ, 0.4, 0.25, 0.0),
            Vec3::new(0.5, 0.45, 0.5),
            0.35,
        ),
        place(
            Quat::from_euler(glam::EulerRot::YXZ, -1.1, 0.0, 0.5),
            Vec3::new(1.15, 0.3, 0.85),
            0.25,
        ),
    ]
}

fn mesh_triangles(m: &Mesh) -> Vec<[Vec3; 3]> {
    (0..m.triangle_count()).map(|t| m.triangle(t)).collect()
}

/// The caster's f32 volume at 40 samples along its longest side (margin 2), baked once.
fn volume_f32() -> &'static DistanceVolume {
    static V: OnceLock<DistanceVolume> = OnceLock::new();
    V.get_or_init(|| DistanceVolume::bake(&mesh_triangles(caster()), 40, 2).expect("bake"))
}

/// The two instances over one volume at `precision`.
fn sdf_scene(precision: Precision) -> SdfScene {
    let v = Arc::new(volume_f32().with_precision(precision));
    let (c, r) = v.bounding_sphere();
    SdfScene {
        instances: placements(c, r)
            .into_iter()
            .map(|transform| SdfInstance {
                volume: v.clone(),
                transform,
            })
            .collect(),
        trace: SdfTrace::default(),
    }
}

/// Floor points: a 48 × 48 grid over [−0.4, 1.8] × [−0.4, 1.6] with normal +y.
fn floor_points() -> (Vec<Vec3>, Vec<Vec3>) {
    let n = 48;
    let mut p = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let x = -0.4 + 2.2 * (i as f32 + 0.5) / n as f32;
            let z = -0.4 + 2.0 * (j as f32 + 0.5) / n as f32;
            p.push(Vec3::new(x, 0.0, z));
        }
    }
    let normals = vec![Vec3::Y; p.len()];
    (p, normals)
}

/// The floor points and every fourth vertex of each placed caster (SDF self-occlusion).
fn floor_and_caster_points(scene: &SdfScene) -> (Vec<Vec3>, Vec<Vec3>) {
    let (mut p, mut n) = floor_points();
    let c = caster();
    for inst in &scene.instances {
        for (q, m) in c.positions.iter().zip(&c.normals).step_by(4) {
            p.push(inst.transform.to_world_point(*q));
            n.push(inst.transform.to_world_dir(*m).normalize());
        }
    }
    (p, n)
}

/// Per-point agreement of a GPU result with the CPU's.
#[derive(Debug)]
struct Agreement {
    /// Share of points whose values are equal.
    equal_share: f64,
    /// Largest |Δ|.
    max_diff: f32,
    /// Points farther apart than their allowance.
    over: usize,
}

impl Agreement {
    /// `allow[i]`: how far point i may move (two of its rays', cones' or lights' shares).
    fn of(gpu: &[f32], cpu: &[f32], allow: &[f32]) -> Agreement {
        assert_eq!(gpu.len(), cpu.len());
        let (mut equal, mut max_diff, mut over) = (0usize, 0.0f32, 0usize);
        for ((g, c), a) in gpu.iter().zip(cpu).zip(allow) {
            let d = (g - c).abs();
            equal += (g.to_bits() == c.to_bits()) as usize;
            max_diff = max_diff.max(d);
            over += (d.is_nan() || d > *a) as usize;
        }
        Agreement {
            equal_share: equal as f64 / gpu.len().max(1) as f64,
            max_diff,
            over,
        }
    }

    /// The SDF criterion of the module docs.
    fn holds(&self) -> bool {
        self.equal_share >= 0.995 && self.over == 0
    }
}

/// The CPU's values must show real occlusion, not a constant: at least a fifth of the points
/// occluded, some below 0.8, the values spread over at least 0.2.
fn assert_occlusion_is_nontrivial(label: &str, cpu: &[f32]) {
    let occluded = cpu.iter().filter(|&&v| v < 1.0).count();
    let (lo, hi) = cpu
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    assert!(
        occluded * 5 > cpu.len() && lo < 0.8 && hi - lo >= 0.2,
        "{label}: {occluded} of {} points occluded, range [{lo}, {hi}]",
        cpu.len()
    );
}

/// Checks `gpu` against `cpu` and the negative control `other` against `cpu`, printing the
/// figures; panics naming `label` on failure.
fn check(label: &str, gpu: &[f32], cpu: &[f32], other: &[f32], allow: &[f32]) {
    let a = Agreement::of(gpu, cpu, allow);
    let neg = Agreement::of(other, cpu, allow);
    eprintln!(
        "{label}: {} points, {:.3}% equal, max |Δ| {:.2e}, {} beyond their allowance; \
         negative control: {:.1}% equal, max |Δ| {:.3}, {} beyond",
        gpu.len(),
        100.0 * a.equal_share,
        a.max_diff,
        a.over,
        100.0 * neg.equal_share,
        neg.max_diff,
        neg.over
    );
    assert!(a.holds(), "{label}: GPU and CPU disagree: {a:?}");
    assert!(
        !neg.holds(),
        "{label}: the check cannot fail: {neg:?} for the negative control"
    );
}

fn sphere_traced_ao_matches_the_cpu_at_every_precision() {
    let Some(ctx) = context() else { return };
    for precision in Precision::ALL {
        let scene = sdf_scene(precision);
        let (p, n) = floor_and_caster_points(&scene);
        let opts = AoOptions::for_scene_radius(1.0);
        let rays = RaySet::new(6, 7);
        let other = RaySet::new(6, 8);
        let t = Instant::now();
        let cpu = ao_at_points(&scene, &p, &n, &rays, &opts);
        let cpu_s = t.elapsed();
        let label = format!("sdf trace AO {}", precision.name());
        assert_occlusion_is_nontrivial(&label, &cpu);
        let kernel = SdfKernel::new(ctx, &scene).unwrap();
        // The negative control first: lavapipe compiles on the first dispatch.
        let (neg, _) = kernel.ao(&p, &n, &other, &opts).unwrap();
        let (gpu, timing) = kernel.ao(&p, &n, &rays, &opts).unwrap();
        eprintln!(
            "{label}: {} points × {} rays: CPU {cpu_s:?} ({} threads), GPU kernel {:?}, wall \
             {:?}, {} rays an invocation",
            p.len(),
            rays.len(),
            rayon::current_num_threads(),
            timing.kernel,
            timing.wall,
            kernel.rays_per_invocation()
        );
        let allow = vec![2.0 / rays.len() as f32; p.len()];
        check(&label, &gpu, &cpu, &neg, &allow);
    }
}

fn cone_traced_ao_and_shadows_match_the_cpu_at_every_precision() {
    let Some(ctx) = context() else { return };
    let cones = ConeSet::hemisphere(9);
    let trace = ConeTrace::default();
    let offset = AoOptions::for_scene_radius(1.0).offset;
    let lights = [
        ConeLight {
            center: Vec3::new(0.6, 2.2, 0.4),
            radius: 0.25,
            intensity: 1.0,
        },
        ConeLight {
            center: Vec3::new(2.0, 1.6, 1.2),
            radius: 0.5,
            intensity: 2.0,
        },
        ConeLight {
            center: Vec3::new(-1.0, 1.2, -0.3),
            radius: 0.0,
            intensity: 0.7,
        },
    ];
    // A cone moves the AO by at most its weight; two cones by the two largest.
    let mut w: Vec<f32> = cones.axes.iter().map(|a| a.z).collect();
    let total: f32 = w.iter().sum();
    w.sort_by(|a, b| b.total_cmp(a));
    let ao_allow = (w[0] + w[1]) / total * 1.0001;
    for precision in Precision::ALL {
        let scene = sdf_scene(precision);
        // The negative control: the same points through the volume at another precision.
        let control = sdf_scene(if precision == Precision::U8 {
            Precision::F32
        } else {
            Precision::U8
        });
        let (p, n) = floor_and_caster_points(&scene);
        let label = format!("sdf cone AO {}", precision.name());
        let t = Instant::now();
        let cpu: Vec<f32> = p
            .iter()
            .zip(&n)
            .map(|(&q, &m)| scene.cone_ao(q + offset * m, m, &cones, f32::INFINITY, &trace))
            .collect();
        let cpu_s = t.elapsed();
        assert_occlusion_is_nontrivial(&label, &cpu);
        let kernel = SdfKernel::new(ctx, &scene).unwrap();
        let (neg, _) = SdfKernel::new(ctx, &control)
            .unwrap()
            .cone_ao(&p, &n, &cones, (offset, f32::INFINITY), &trace)
            .unwrap();
        let (gpu, timing) = kernel
            .cone_ao(&p, &n, &cones, (offset, f32::INFINITY), &trace)
            .unwrap();
        eprintln!(
            "{label}: {} points × {} cones: CPU {cpu_s:?} (1 thread), GPU kernel {:?}, wall {:?}",
            p.len(),
            cones.axes.len(),
            timing.kernel,
            timing.wall
        );
        check(&label, &gpu, &cpu, &neg, &vec![ao_allow; p.len()]);

        let label = format!("sdf cone shadows {}", precision.name());
        let t = Instant::now();
        let cpu: Vec<f32> = p
            .iter()
            .zip(&n)
            .map(|(&q, &m)| scene.cone_light_fraction(q + offset * m, m, &lights, &trace))
            .collect();
        let cpu_s = t.elapsed();
        assert_occlusion_is_nontrivial(&label, &cpu);
        // Two lights' shares of the point's weight.
        let allow: Vec<f32> = p
            .iter()
            .zip(&n)
            .map(|(&q, &m)| {
                let mut w: Vec<f64> = lights
                    .iter()
                    .filter_map(|l| visfield::sdf::LightCone::new(q + offset * m, m, l))
                    .map(|c| c.weight)
                    .collect();
                let total: f64 = w.iter().sum();
                w.sort_by(|a, b| b.total_cmp(a));
                if total > 0.0 {
                    (w.iter().take(2).sum::<f64>() / total) as f32 * 1.0001
                } else {
                    0.0
                }
            })
            .collect();
        let (neg, _) = SdfKernel::new(ctx, &control)
            .unwrap()
            .cone_light_fractions(&p, &n, &lights, offset, &trace)
            .unwrap();
        let (gpu, timing) = kernel
            .cone_light_fractions(&p, &n, &lights, offset, &trace)
            .unwrap();
        eprintln!(
            "{label}: {} points × {} lights: CPU {cpu_s:?} (1 thread), GPU kernel {:?}, wall \
             {:?}",
            p.len(),
            lights.len(),
            timing.kernel,
            timing.wall
        );
        check(&label, &gpu, &cpu, &neg, &allow);
    }
}

/// The caster's AO field fit: 16² texels a face, 12 radial samples of 64 rays, baked once.
fn ao_fit() -> &'static visfield::aofield::Fitted {
    static F: OnceLock<visfield::aofield::Fitted> = OnceLock::new();
    F.get_or_init(|| {
        let params = BakeParams {
            res: 16,
            radial_samples: 12,
            rays: 64,
            reach: 8.0,
        };
        bake(&mesh_triangles(caster()), &params).expect("bake").0
    })
}

/// The two instances over one AO field at `precision`.
fn ao_scene(precision: visfield::aofield::Precision) -> AoFieldScene {
    let fit = ao_fit();
    let f = Arc::new(AoField::new(fit, precision));
    AoFieldScene {
        instances: placements(fit.bounds.center, fit.bounds.radius)
            .into_iter()
            .map(|transform| AoFieldInstance {
                field: f.clone(),
                transform,
            })
            .collect(),
        inside: Inside::default(),
    }
}

/// u = 2⁻²⁴, the unit roundoff of f32.
const U: f64 = f32::EPSILON as f64 / 2.0;

/// The f32 closed form's error (shaders/aofield.wgsl, `small_cap_f32`), per occluder: the
/// three terms' roundings and two arctangents (each within about 8u: the ratio, the range
/// reduction, Cephes' 1.9·10⁻⁷ relative, the offsets), sin²α's 2u times ∂(πÃ)/∂sin²α ≤ π, the
/// two sums and the division by π, about 15u in all; the rounding of √δ costs O(u) only, its
/// first-order effect vanishing (src/gpu/aofield_kernel.rs). The CPU's own f64 error (its
/// acos near ±1 loses half of f64's digits) is below 0.1u. `gpu::aofield_kernel`'s unit test
/// checks the f32 form against the f64 one within it over a dense grid.
const E_CAP: f64 = 16.0 * U;

/// Per point, the bound on |GPU − CPU| of the module docs: per occluder i, Ω_i (4 cond(q_i) +
/// 6)u / π (Horner's 4 cond(q) u on q, the reciprocal's rounding, and 2π's and Ω/2π's in
/// cos α) + E_CAP + 3u (the f64 result's rounding to f32, the inside blend's two), and (n + 1)u
/// for the product over the n occluders.
fn aofield_bound(scene: &AoFieldScene, p: Vec3) -> f32 {
    let mut bound = (scene.instances.len() as f64 + 1.0) * U;
    for inst in &scene.instances {
        let f = &inst.field;
        let lp = inst.transform.to_local_point(p);
        let cap = f.cap_at(lp);
        // The quadratic's coefficients, read as `cap_at` reads them.
        let x = (lp - f.bounds.center) / f.bounds.radius;
        let w = if cap.s > 0.0 { x / cap.s } else { Vec3::Z };
        let b = f.cube.bilinear(w);
        let mut ch = [0.0f32; 3];
        for (&t, &wt) in b.texels.iter().zip(&b.weights) {
            let texel = f.stored.texel(t);
            for k in 0..3 {
                ch[k] += wt * texel[k];
            }
        }
        let sc = cap.s.max(cap.s0) as f64;
        let [a, bb, c] = ch.map(f64::from);
        let q = (a * sc + bb) * sc + c;
        let cond = (a.abs() * sc * sc + bb.abs() * sc + c.abs()) / q.abs();
        bound += cap.omega * (4.0 * cond + 6.0) * U / std::f64::consts::PI + E_CAP + 3.0 * U;
    }
    bound as f32
}

fn ao_fields_match_the_cpu_at_every_precision_within_the_derived_bound() {
    use visfield::aofield::Precision;
    let Some(ctx) = context() else { return };
    // Floor points, and points inside the casters' hulls (every fourth vertex moved halfway
    // to the bounding sphere's centre, its normal kept): the inside blend.
    let (mut p, mut n) = floor_points();
    let fit = ao_fit();
    let c = caster();
    for t in placements(fit.bounds.center, fit.bounds.radius) {
        for (q, m) in c.positions.iter().zip(&c.normals).step_by(4) {
            p.push(t.to_world_point(0.5 * (*q + fit.bounds.center)));
            n.push(t.to_world_dir(*m).normalize());
        }
    }
    for precision in [Precision::F32, Precision::F16, Precision::U8] {
        let scene = ao_scene(precision);
        let control = ao_scene(if precision == Precision::U8 {
            Precision::F32
        } else {
            Precision::U8
        });
        let label = format!("aofield {}", precision.name());
        let t = Instant::now();
        let cpu = scene.ao_at_points(&p, &n);
        let cpu_s = t.elapsed();
        assert_occlusion_is_nontrivial(&label, &cpu[..floor_points().0.len()]);
        let inside = p
            .iter()
            .filter(|&&q| {
                scene.instances.iter().any(|i| {
                    let cap = i.field.cap_at(i.transform.to_local_point(q));
                    cap.s < cap.s0
                })
            })
            .count();
        assert!(
            inside * 10 > p.len(),
            "{label}: {inside} points inside a hull"
        );
        let kernel = AoFieldKernel::new(ctx, &scene).unwrap();
        let (neg, _) = AoFieldKernel::new(ctx, &control)
            .unwrap()
            .ao(&p, &n)
            .unwrap();
        let (gpu, timing) = kernel.ao(&p, &n).unwrap();
        eprintln!(
            "{label}: {} points ({inside} inside a hull) × 2 occluders: CPU {cpu_s:?} ({} \
             threads), GPU kernel {:?}, wall {:?}",
            p.len(),
            rayon::current_num_threads(),
            timing.kernel,
            timing.wall
        );
        let bounds: Vec<f32> = p.iter().map(|&q| aofield_bound(&scene, q)).collect();
        let within = |v: &[f32]| {
            v.iter()
                .zip(&cpu)
                .zip(&bounds)
                .filter(|((g, c), b)| (*g - *c).abs() <= **b)
                .count() as f64
                / p.len() as f64
        };
        let (mut max_diff, mut max_ratio, mut max_bound) = (0.0f32, 0.0f32, 0.0f32);
        for ((g, c), b) in gpu.iter().zip(&cpu).zip(&bounds) {
            max_diff = max_diff.max((g - c).abs());
            max_ratio = max_ratio.max((g - c).abs() / b);
            max_bound = max_bound.max(*b);
        }
        let (share, neg_share) = (within(&gpu), within(&neg));
        eprintln!(
            "{label}: {:.3}% within the bound (largest bound {max_bound:.2e}), max |Δ| \
             {max_diff:.2e}, max |Δ| / bound {max_ratio:.3}; negative control {:.1}% within",
            100.0 * share,
            100.0 * neg_share
        );
        assert!(
            share >= 0.995,
            "{label}: {share} of points within the bound"
        );
        // f32 against f64: a difference of exactly 0 everywhere would mean the device did not
        // evaluate what the bound is about.
        assert!(
            max_diff > 0.0,
            "{label}: the device's f32 evaluation is the CPU's f64 one"
        );
        assert!(
            neg_share < 0.995,
            "{label}: the check cannot fail ({neg_share})"
        );
    }
}

/// The peers through the harness with `"backends": ["cpu", "gpu"]` (the tiny spec: a supershape
/// over a corner, vertex AO): each setting a CPU row and then a GPU row naming the adapter, with
/// its upload time, and the GPU row's same-ray error and error against the converged reference
/// those of the CPU row (the kernels' per-point parity above allows a few points to move by a
/// ray's share: within 0.5 on the 0–255 scale), neither of them 0.
fn the_peers_run_on_the_gpu_backend_beside_the_cpu() {
    use visfield::experiment::columns::{read_csv, NamedRow};
    let Some(ctx) = context() else { return };
    let dir = tempfile::tempdir().unwrap();
    let methods = r#""methods": [
        {"method": "sdf", "res": [24], "query": ["trace", "cone"], "backends": ["cpu", "gpu"]},
        {"method": "aofield", "res": [8], "radial_samples": 6, "rays": 64, "backends": ["cpu", "gpu"]}
    ], "reference": {"#;
    let text = common::tiny(common::ONE_FIELD, "").replace(r#""reference": {"#, methods);
    let ls = common::loaded(dir.path(), &text);
    let out = dir.path().join("out");
    visfield::experiment::run::run(&ls, &common::options(out.clone())).unwrap();
    let rows: Vec<NamedRow> = read_csv(&out.join("methods.csv")).unwrap();
    let col = |name: &str| -> Vec<&str> { rows.iter().map(|r| r.get(name).unwrap()).collect() };
    assert_eq!(
        col("setting"),
        [
            "sdf-24-f32-trace",
            "sdf-24-f32-trace",
            "sdf-24-f32-cone",
            "sdf-24-f32-cone",
            "aofield-8-6-f32",
            "aofield-8-6-f32"
        ]
    );
    assert_eq!(col("backend"), ["cpu", "gpu", "cpu", "gpu", "cpu", "gpu"]);
    for pair in rows.chunks(2) {
        let (cpu, gpu) = (&pair[0], &pair[1]);
        let setting = cpu.get("setting").unwrap();
        assert_eq!(gpu.get("adapter"), Some(ctx.adapter_label().as_str()));
        assert!(gpu.number("setup_s").unwrap() > 0.0, "{setting}");
        assert_eq!(gpu.get("bytes"), cpu.get("bytes"), "{setting}");
        for m in ["rms_vs_raycast", "rms_vs_truth"] {
            let (c, g) = (cpu.number(m).unwrap(), gpu.number(m).unwrap());
            eprintln!("{setting} {m}: cpu {c:.4} gpu {g:.4}");
            assert!(
                c > 0.0 && g > 0.0 && (c - g).abs() <= 0.5,
                "{setting} {m}: {c} {g}"
            );
        }
    }
}

/// The harness: every test above, run where a Vulkan adapter exists and reported as ignored,
/// with the reason, where none does (a skipped test never shows as passed).
fn main() {
    common::run_gpu_trials(
        "gpu_peers",
        &[
            (
                "sphere_traced_ao_matches_the_cpu_at_every_precision",
                sphere_traced_ao_matches_the_cpu_at_every_precision,
            ),
            (
                "cone_traced_ao_and_shadows_match_the_cpu_at_every_precision",
                cone_traced_ao_and_shadows_match_the_cpu_at_every_precision,
            ),
            (
                "ao_fields_match_the_cpu_at_every_precision_within_the_derived_bound",
                ao_fields_match_the_cpu_at_every_precision_within_the_derived_bound,
            ),
            (
                "the_peers_run_on_the_gpu_backend_beside_the_cpu",
                the_peers_run_on_the_gpu_backend_beside_the_cpu,
            ),
        ],
        &[],
    );
}
