//! GPU glossy reflections (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010, §4.2)
//! against the CPU path, per point, on the same fields, normal fields, casters, lights and
//! rays: field lookup ([`FieldReflectKernel`]) against `reflect_at_points` over a `FieldScene`,
//! and GPU ray casting (`gpu::reflections` on a [`GpuTracer`]) against it over the CPU tracer; then a
//! reflections run on both backends.
//!
//! The scene: two tilted supershape casters whose bounding spheres overlap (a ray may meet
//! both, and the nearer sphere need not hold the nearer hit), over a floor seen from an eye;
//! the receivers are floor points that reflect the casters or the sky (outside every sphere)
//! and caster vertices (inside their own sphere: intra-object lookups).
//!
//! The tolerance. A point's value is V = (1/n) Σ L_i over its n kept reflection rays, each
//! L_i in [0, max(albedo, sky)]. GPU and CPU build the same ray directions bit for bit
//! (src/gpu/reflect_rays.rs tests it) and, on lavapipe, the same normals. When both find the
//! same surface for a ray, L_i differs only through its hit distance: the GPU crosses the
//! bounding sphere in f32 (the host in f64), and the GPU tracer does not rescale the scene as
//! the CPU one does; either moves t by at most about 8 roundings of the magnitudes involved,
//! |δt| ≤ 8u·E (u = 2⁻²⁴, E the scene's extent from the origin plus the ray's reach), so the
//! hit point by 16u·E with the rounding of q = o + t·d, and each light's unit direction by
//! 2|δq| / d_min (d_min: the least distance from a light to the casters' spheres), hence
//! |δL_i| ≤ albedo · 2 · 16u·E / d_min; the device adds the m rays of one invocation in f32,
//! (m − 1)u relative, and both round the mean to f32: [`close_tolerance`]. A ray that grazes
//! an edge (of a triangle, a map's texel or Voronoi cell, a bounding sphere) may be decided
//! differently when a crossing is rounded differently, and then V moves by at most that ray's
//! share max(albedo, sky) / n. So the tests ask that at least 99.5% of points agree within
//! the rounding bound and that every other point lie within one ray's share of it
//! ([`Agreement`]). A negative control (the GPU on another seed's lobe, or for the mirror an
//! eye moved by 0.1) must fail the same check, and the scene must reflect real surfaces.
//!
//! Only a missing Vulkan driver skips these tests (reported as ignored, with the reason
//! printed; the harness is `main`, through libtest-mimic); every other GPU failure fails them.

use glam::{Quat, Vec3};
use std::sync::{Arc, OnceLock};
use std::time::Instant;
use visfield::field::bake::{bake_mesh_with_normals, BakeOptions};
use visfield::field::lookup::LookupOptions;
use visfield::field::normals::NormalField;
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::{Precision, Selection, VisibilityField};
use visfield::geometry::Similarity;
use visfield::gpu::{FieldGpuOptions, FieldLayout, FieldReflectKernel, GpuError, GpuTracer};
use visfield::render::ao::AoOptions;
use visfield::render::reflect::{reflect_at_points, reflection_rays, Gloss, ReflectOptions};
use visfield::render::shadow::SphereLight;
use visfield::sampling::rays::RaySet;
use visfield::trace::Tracer;

mod common;
use common::{
    gpu_context as context, loaded, options, slater_params, supershape_2000 as caster, tiny,
    ONE_FIELD,
};

/// Its field (290 Slater maps × 16² concentric texels, 8-bit) and its normal field at 16 bits
/// and, requantised, at 8.
fn field() -> &'static (Arc<VisibilityField>, Arc<NormalField>, Arc<NormalField>) {
    static FIELD: OnceLock<(Arc<VisibilityField>, Arc<NormalField>, Arc<NormalField>)> =
        OnceLock::new();
    FIELD.get_or_init(|| {
        let p = slater_params(290, 16, Precision::U8);
        let (f, n16, _) =
            bake_mesh_with_normals(caster(), p, 16, &BakeOptions::default()).expect("bake");
        let n8 = n16.requantized(8);
        (Arc::new(f), Arc::new(n16), Arc::new(n8))
    })
}

/// The two casters: radius 0.35 at (0.5, 0.45, 0.5) and radius 0.3 at (0.9, 0.5, 0.2), tilted
/// differently; their spheres overlap. Each carries the normal field of `bits` bits.
fn placed(bits: u32) -> Vec<FieldInstance> {
    let (f, n16, n8) = field();
    let normals = if bits == 8 { n8 } else { n16 };
    let s = f.bounds;
    let place = |yaw: f32, pitch: f32, radius: f32, at: Vec3| {
        let rotation = Quat::from_euler(glam::EulerRot::YXZ, yaw, pitch, 0.0);
        let scale = radius / s.radius;
        let translation = at - scale * (rotation * s.center);
        FieldInstance::new(f.clone(), Similarity::new(rotation, translation, scale))
            .with_normals(normals.clone())
    };
    vec![
        place(0.4, 0.25, 0.35, Vec3::new(0.5, 0.45, 0.5)),
        place(-0.9, 0.6, 0.3, Vec3::new(0.9, 0.5, 0.2)),
    ]
}

/// The casters' world triangles (the ray-cast scene: the floor reflects, it is not reflected).
fn caster_triangles(insts: &[FieldInstance]) -> Vec<[Vec3; 3]> {
    let c = caster();
    insts
        .iter()
        .flat_map(|inst| {
            (0..c.triangles.len())
                .map(move |i| c.triangle(i).map(|v| inst.transform.to_world_point(v)))
        })
        .collect()
}

/// Three lights (only their centres and intensities shade), an eye in front of the casters
/// and a little above them, the `gloss` lobe.
fn reflect_opts(gloss: Gloss) -> ReflectOptions {
    let l = |c: [f32; 3], intensity| SphereLight {
        center: Vec3::from_array(c),
        radius: 0.2,
        intensity,
    };
    ReflectOptions {
        offset: AoOptions::for_scene_radius(1.0).offset,
        eye: Vec3::new(0.5, 0.8, 2.2),
        gloss,
        lights: vec![
            l([0.6, 2.2, 1.4], 1.0),
            l([2.0, 1.6, 1.2], 2.0),
            l([-1.0, 1.2, 0.9], 0.7),
        ],
        albedo: 0.8,
        sky: 0.3,
    }
}

/// Receivers: a 40 × 40 floor grid in front of the casters (most of it reflects them; outside
/// every sphere) and every third vertex of each placed caster (inside its sphere).
fn receivers(insts: &[FieldInstance]) -> (Vec<Vec3>, Vec<Vec3>) {
    let n = 40;
    let mut p = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let t = |k: usize, lo: f32, hi: f32| lo + (hi - lo) * (k as f32 + 0.5) / n as f32;
            p.push(Vec3::new(t(i, 0.0, 1.3), 0.0, t(j, 0.6, 1.5)));
        }
    }
    let mut nrm = vec![Vec3::Y; p.len()];
    let c = caster();
    for inst in insts {
        for (q, m) in c.positions.iter().zip(&c.normals).step_by(3) {
            p.push(inst.transform.to_world_point(*q));
            nrm.push(inst.transform.to_world_dir(*m).normalize());
        }
    }
    (p, nrm)
}

/// Per point, one ray's share of its value: max(albedo, sky) / (kept rays), 0 without any.
fn one_ray_shares(p: &[Vec3], n: &[Vec3], rays: &RaySet, opts: &ReflectOptions) -> Vec<f32> {
    let (mut squares, mut dirs) = (Vec::new(), Vec::new());
    p.iter()
        .zip(n)
        .enumerate()
        .map(|(i, (&p, &n))| {
            reflection_rays(i as u32, p, n, rays, opts, &mut squares, &mut dirs);
            if dirs.is_empty() {
                0.0
            } else {
                opts.albedo.max(opts.sky) / dirs.len() as f32
            }
        })
        .collect()
}

/// The bound on |GPU − CPU| when both find the same surfaces (see the module docs): `m` rays
/// summed in f32 per invocation, the scene within `extent` of the origin (ray reach
/// included), lights at least `d_min` from the casters' spheres.
fn close_tolerance(m: u32, extent: f32, d_min: f32, opts: &ReflectOptions) -> f32 {
    let u = f32::EPSILON / 2.0;
    let shading = opts.albedo * 2.0 * 16.0 * u * extent / d_min;
    shading + (m as f32 + 1.0) * u
}

/// [`close_tolerance`] for this scene: the extent from the receivers and spheres, d_min from
/// the lights and spheres.
fn scene_tolerance(insts: &[FieldInstance], p: &[Vec3], m: u32, opts: &ReflectOptions) -> f32 {
    let reach: f32 = insts
        .iter()
        .map(|i| i.world_center.abs().max_element() + i.world_radius)
        .fold(0.0, f32::max);
    let extent = p
        .iter()
        .map(|q| q.abs().max_element())
        .fold(reach, f32::max)
        * 3.0;
    let d_min = opts
        .lights
        .iter()
        .flat_map(|l| {
            insts
                .iter()
                .map(move |i| (l.center - i.world_center).length() - i.world_radius)
        })
        .fold(f32::INFINITY, f32::min);
    assert!(d_min > 0.5, "a light inside a caster's sphere: {d_min}");
    close_tolerance(m, extent, d_min, opts)
}

/// Per-point agreement of a GPU result with the CPU's.
#[derive(Debug)]
struct Agreement {
    /// Share of points within the rounding bound.
    close_share: f64,
    /// Largest |Δ|, and the largest among the points within the bound.
    max_diff: f32,
    max_close_diff: f32,
    /// Points farther apart than one of their rays' shares (plus the rounding bound).
    over_one_ray: usize,
}

impl Agreement {
    fn of(gpu: &[f32], cpu: &[f32], shares: &[f32], close: f32) -> Agreement {
        assert_eq!(gpu.len(), cpu.len());
        let (mut near, mut max_diff, mut max_close, mut over) = (0usize, 0.0f32, 0.0f32, 0usize);
        for ((g, c), s) in gpu.iter().zip(cpu).zip(shares) {
            let d = (g - c).abs();
            if d <= close {
                near += 1;
                max_close = max_close.max(d);
            }
            max_diff = max_diff.max(d);
            over += (d > s + close || d.is_nan()) as usize;
        }
        Agreement {
            close_share: near as f64 / gpu.len().max(1) as f64,
            max_diff,
            max_close_diff: max_close,
            over_one_ray: over,
        }
    }

    /// The parity criterion of the module docs.
    fn holds(&self) -> bool {
        self.close_share >= 0.995 && self.over_one_ray == 0
    }
}

/// The scene must reflect real surfaces, or agreement proves little: at least a tenth of the
/// points see a lit caster (neither sky nor black; about a sixth for the mirror, most for broad
/// lobes), and some see the sky alone.
fn assert_reflections_are_nontrivial(cpu: &[f32], opts: &ReflectOptions) {
    let lit = cpu.iter().filter(|&&v| v != opts.sky && v > 0.0).count();
    let sky = cpu.iter().filter(|&&v| v == opts.sky).count();
    assert!(
        lit * 10 > cpu.len() && sky * 20 > cpu.len(),
        "{lit} of {} points reflect a lit caster, {sky} the sky alone",
        cpu.len()
    );
}

/// Checks `gpu` against `cpu` and the negative control `other` against `cpu`, printing the
/// figures; panics naming `label` on failure.
fn check(label: &str, gpu: &[f32], cpu: &[f32], other: &[f32], shares: &[f32], close: f32) {
    let a = Agreement::of(gpu, cpu, shares, close);
    let neg = Agreement::of(other, cpu, shares, close);
    eprintln!(
        "{label}: {} points, {:.3}% within {close:.1e} (max |Δ| there {:.1e}), max |Δ| {:.2e}, \
         {} beyond one ray's share; negative control: {:.1}% within, max |Δ| {:.3}",
        gpu.len(),
        100.0 * a.close_share,
        a.max_close_diff,
        a.max_diff,
        a.over_one_ray,
        100.0 * neg.close_share,
        neg.max_diff
    );
    assert!(a.holds(), "{label}: GPU and CPU disagree: {a:?}");
    assert!(
        !neg.holds(),
        "{label}: the check cannot fail: {neg:?} for the negative control"
    );
}

/// The lobes the tests run: the mirror, and a Phong lobe of exponent 20.
fn glosses() -> [Gloss; 2] {
    [Gloss::Mirror, Gloss::Phong { exponent: 20.0 }]
}

/// The negative control's rays and options: another seed, or for the mirror the eye moved.
fn control(rays: &RaySet, opts: &ReflectOptions) -> (RaySet, ReflectOptions) {
    match opts.gloss {
        Gloss::Mirror => (
            *rays,
            ReflectOptions {
                eye: opts.eye + Vec3::new(0.1, 0.0, 0.0),
                ..opts.clone()
            },
        ),
        Gloss::Phong { .. } => (RaySet::new(rays.k, rays.seed + 1), opts.clone()),
    }
}

fn field_reflections_match_the_cpu() {
    // Every layout, selection and normal precision, both lobes.
    let Some(ctx) = context() else { return };
    let rays = RaySet::new(4, 7);
    for bits in [8u32, 16] {
        let insts = placed(bits);
        let (p, n) = receivers(&insts);
        for layout in [FieldLayout::StorageBuffers, FieldLayout::Texture3d] {
            let gpu_opts = FieldGpuOptions {
                layout,
                ..Default::default()
            };
            let mut kernel = FieldReflectKernel::new(ctx, &insts, &gpu_opts).unwrap();
            for selection in [Selection::Nearest, Selection::Interpolated] {
                let lookup = LookupOptions {
                    selection,
                    ..Default::default()
                };
                kernel.lookup = lookup;
                let scene = FieldScene {
                    instances: insts.clone(),
                    options: lookup,
                };
                for gloss in glosses() {
                    let opts = reflect_opts(gloss);
                    let shares = one_ray_shares(&p, &n, &rays, &opts);
                    let t = Instant::now();
                    let cpu = reflect_at_points(&scene, &p, &n, &rays, &opts);
                    let cpu_s = t.elapsed();
                    assert_reflections_are_nontrivial(&cpu, &opts);
                    // The negative control first: lavapipe compiles the kernel on its first
                    // dispatch, which the timed call should not include.
                    let (other_rays, other_opts) = control(&rays, &opts);
                    let (neg, _) =
                        visfield::gpu::reflections(&kernel, &p, &n, &other_rays, &other_opts)
                            .unwrap();
                    let (gpu, timing) =
                        visfield::gpu::reflections(&kernel, &p, &n, &rays, &opts).unwrap();
                    let m = kernel.rays_per_invocation().min(rays.len() as u32);
                    let close = scene_tolerance(&insts, &p, m, &opts);
                    let label =
                        format!("field {bits}-bit normals {layout:?} {selection:?} {gloss:?}");
                    eprintln!(
                        "{label}: {} points: CPU {cpu_s:?} ({} threads), GPU kernel {:?}, wall {:?}",
                        p.len(),
                        rayon::current_num_threads(),
                        timing.kernel,
                        timing.wall
                    );
                    check(&label, &gpu, &cpu, &neg, &shares, close);
                }
            }
        }
    }
}

fn ray_cast_reflections_match_the_cpu_tracer() {
    let Some(ctx) = context() else { return };
    let insts = placed(16);
    let tris = caster_triangles(&insts);
    let (p, n) = receivers(&insts);
    let cpu_tracer = Tracer::new(&tris);
    let gpu_tracer = GpuTracer::new(ctx, &tris).unwrap();
    for (gloss, k) in [
        (Gloss::Mirror, 1u32),
        (Gloss::Phong { exponent: 20.0 }, 4),
        (Gloss::Phong { exponent: 200.0 }, 5),
    ] {
        let rays = RaySet::new(k, 7);
        let opts = reflect_opts(gloss);
        let shares = one_ray_shares(&p, &n, &rays, &opts);
        let t = Instant::now();
        let cpu = reflect_at_points(&cpu_tracer, &p, &n, &rays, &opts);
        let cpu_s = t.elapsed();
        assert_reflections_are_nontrivial(&cpu, &opts);
        let (other_rays, other_opts) = control(&rays, &opts);
        let (neg, _) =
            visfield::gpu::reflections(&gpu_tracer, &p, &n, &other_rays, &other_opts).unwrap();
        let (gpu, timing) = visfield::gpu::reflections(&gpu_tracer, &p, &n, &rays, &opts).unwrap();
        let close = scene_tolerance(&insts, &p, rays.len() as u32, &opts);
        let label = format!("ray casting {gloss:?} k = {k}");
        eprintln!(
            "{label}: {} points: CPU {cpu_s:?} ({} threads), GPU kernel {:?}, wall {:?}",
            p.len(),
            rayon::current_num_threads(),
            timing.kernel,
            timing.wall
        );
        check(&label, &gpu, &cpu, &neg, &shares, close);
    }
}

fn many_rays_split_over_invocations_match_the_cpu() {
    // k = 12: 144 lobe rays a point; the field kernel is asked for 40 an invocation (4 runs,
    // the last short), the tracer starts at 256. Every fifth receiver.
    let Some(ctx) = context() else { return };
    let insts = placed(16);
    let tris = caster_triangles(&insts);
    let (p, n) = receivers(&insts);
    let (p, n): (Vec<Vec3>, Vec<Vec3>) = p.into_iter().zip(n).step_by(5).unzip();
    let opts = reflect_opts(Gloss::Phong { exponent: 20.0 });
    let rays = RaySet::new(12, 3);
    let other = RaySet::new(12, 4);
    let shares = one_ray_shares(&p, &n, &rays, &opts);

    let cpu = reflect_at_points(&Tracer::new(&tris), &p, &n, &rays, &opts);
    assert_reflections_are_nontrivial(&cpu, &opts);
    let tracer = GpuTracer::new(ctx, &tris).unwrap();
    let (gpu, _) = visfield::gpu::reflections(&tracer, &p, &n, &rays, &opts).unwrap();
    let (neg, _) = visfield::gpu::reflections(&tracer, &p, &n, &other, &opts).unwrap();
    let close = scene_tolerance(&insts, &p, 144, &opts);
    check("ray casting, k = 12", &gpu, &cpu, &neg, &shares, close);

    let scene = FieldScene {
        instances: insts.clone(),
        options: LookupOptions::default(),
    };
    let cpu = reflect_at_points(&scene, &p, &n, &rays, &opts);
    let gpu_opts = FieldGpuOptions {
        rays_per_invocation: 80,
        ..Default::default()
    };
    let kernel = FieldReflectKernel::new(ctx, &insts, &gpu_opts).unwrap();
    assert_eq!(kernel.rays_per_invocation(), 40, "80 over two instances");
    let (gpu, _) = visfield::gpu::reflections(&kernel, &p, &n, &rays, &opts).unwrap();
    let (neg, _) = visfield::gpu::reflections(&kernel, &p, &n, &other, &opts).unwrap();
    let close = scene_tolerance(&insts, &p, kernel.rays_per_invocation(), &opts);
    check(
        "field, k = 12, 40 rays an invocation",
        &gpu,
        &cpu,
        &neg,
        &shares,
        close,
    );
}

fn overlapping_spheres_give_the_nearest_hit_not_the_first() {
    // Rays from a point beyond the second caster back through both spheres: the nearer
    // sphere's entry comes first along some rays whose nearer hit is in the other caster.
    // Both backends must keep the nearest hit; the GPU's values must be the CPU's.
    let Some(ctx) = context() else { return };
    let insts = placed(16);
    let scene = FieldScene {
        instances: insts.clone(),
        options: LookupOptions::default(),
    };
    let first_only = FieldScene {
        instances: vec![insts[0].clone()],
        options: LookupOptions::default(),
    };
    let kernel = FieldReflectKernel::new(ctx, &insts, &FieldGpuOptions::default()).unwrap();
    let kernel_first =
        FieldReflectKernel::new(ctx, &insts[..1], &FieldGpuOptions::default()).unwrap();
    let (p, n) = receivers(&insts);
    let rays = RaySet::new(4, 11);
    let opts = reflect_opts(Gloss::Phong { exponent: 5.0 });
    let cpu = reflect_at_points(&scene, &p, &n, &rays, &opts);
    let (gpu, _) = visfield::gpu::reflections(&kernel, &p, &n, &rays, &opts).unwrap();
    let shares = one_ray_shares(&p, &n, &rays, &opts);
    let close = scene_tolerance(&insts, &p, 16, &opts);
    let (neg, _) = visfield::gpu::reflections(&kernel_first, &p, &n, &rays, &opts).unwrap();
    // The second caster matters: dropping it changes many points on both backends.
    let cpu_first = reflect_at_points(&first_only, &p, &n, &rays, &opts);
    let changed = cpu.iter().zip(&cpu_first).filter(|(a, b)| a != b).count();
    assert!(
        changed * 10 > p.len(),
        "{changed} of {} points see the second caster",
        p.len()
    );
    check(
        "field, two overlapping casters",
        &gpu,
        &cpu,
        &neg,
        &shares,
        close,
    );
}

fn edge_cases_are_those_of_the_cpu() {
    let Some(ctx) = context() else { return };
    let insts = placed(8);
    let tris = caster_triangles(&insts);
    let tracer = GpuTracer::new(ctx, &tris).unwrap();
    let kernel = FieldReflectKernel::new(ctx, &insts, &FieldGpuOptions::default()).unwrap();
    let rays = RaySet::new(4, 1);
    let opts = reflect_opts(Gloss::Phong { exponent: 20.0 });
    // A point seen from behind its surface (right above the eye, facing up) keeps no ray (0),
    // a point facing up far from the casters sees the sky alone; no points, no values.
    let p = [Vec3::new(0.5, 1.5, 2.2), Vec3::new(-3.0, 0.0, 3.0)];
    let n = [Vec3::Y, Vec3::Y];
    let cpu = reflect_at_points(&Tracer::new(&tris), &p, &n, &rays, &opts);
    let (g, _) = visfield::gpu::reflections(&tracer, &p, &n, &rays, &opts).unwrap();
    let (f, _) = visfield::gpu::reflections(&kernel, &p, &n, &rays, &opts).unwrap();
    assert_eq!(cpu, vec![0.0, opts.sky]);
    // The sky's 16 rays summed in f32 on the device: within 16 roundings.
    let close = 16.0 * f32::EPSILON / 2.0;
    for (i, c) in cpu.iter().enumerate() {
        assert!(
            (g[i] - c).abs() <= close && (f[i] - c).abs() <= close,
            "{i}: {g:?} {f:?}"
        );
    }
    assert_eq!((g[0], f[0]), (0.0, 0.0));
    assert!(visfield::gpu::reflections(&tracer, &[], &[], &rays, &opts)
        .unwrap()
        .0
        .is_empty());
    assert!(visfield::gpu::reflections(&kernel, &[], &[], &rays, &opts)
        .unwrap()
        .0
        .is_empty());
    // Jittered ray sets have no shared lobe: refused for Phong lobes, not approximated.
    let jittered = RaySet {
        jitter: true,
        ..rays
    };
    assert!(matches!(
        visfield::gpu::reflections(&kernel, &p, &n, &jittered, &opts),
        Err(GpuError::Unsupported(_))
    ));
    assert!(matches!(
        visfield::gpu::reflections(&tracer, &p, &n, &jittered, &opts),
        Err(GpuError::Unsupported(_))
    ));
    // An instance without its normal field is refused, naming it.
    let bare = FieldInstance::new(insts[1].field.clone(), insts[1].transform);
    let e = FieldReflectKernel::new(ctx, &[insts[0].clone(), bare], &FieldGpuOptions::default())
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("instance 1") && e.contains("normal field"),
        "{e}"
    );
}

const LIGHTS: &str = r#"[{ "center": [2.5, 2.6, 2.2], "radius": 0.3, "intensity": 1 }, { "center": [-0.5, 3.0, 1.5], "radius": 0.5, "intensity": 2 }]"#;

/// A reflections run with `backends: ["cpu", "gpu"]` and both normal precisions: one row per
/// precision and backend, the GPU rows naming their adapter, with the CPU rows' same-ray error
/// (the same fields, normal fields, lights and rays: within 0.5 on the 0–255 scale, where the
/// per-point parity above allows a few pixels to move by one ray's share).
fn a_reflections_run_on_cpu_and_gpu_gives_matching_rows() {
    let Some(ctx) = context() else { return };
    let label = ctx.adapter_label();
    let dir = tempfile::tempdir().unwrap();
    let text = tiny(ONE_FIELD, "")
        .replace(
            r#""render": { "rays_per_point": 16, "image": { "width": 32, "height": 32 } }"#,
            &format!(
                r#""render": {{ "what": "reflections", "rays_per_point": 16, "image": {{ "width": 32, "height": 32 }}, "lights": {LIGHTS}, "gloss": {{ "phong": {{ "exponent": 20 }} }}, "normal_bits": [8, 16] }}"#
            ),
        )
        .replace(
            r#""reference": {"#,
            r#""backends": ["cpu", "gpu"], "reference": {"#,
        );
    let ls = loaded(dir.path(), &text);
    let report = visfield::experiment::run::run(&ls, &options(dir.path().join("out"))).unwrap();
    let rows = &report.rows;
    assert_eq!(rows.len(), 4, "two cells on two backends");
    for bits in [8u32, 16] {
        let of = |b: &str| {
            rows.iter()
                .find(|r| r.normal_bits == Some(bits) && r.backend.name() == b)
                .unwrap_or_else(|| panic!("no {b} row for {bits} bits"))
        };
        let (cpu, gpu) = (of("cpu"), of("gpu"));
        assert_eq!(gpu.adapter, label);
        assert_eq!(gpu.rays_cast, cpu.rays_cast);
        let (c, g) = (cpu.rms_image.unwrap(), gpu.rms_image.unwrap());
        eprintln!(
            "reflections run, {bits}-bit normals: same-ray RMS cpu {c:.4} gpu {g:.4} (0–255); \
             vs truth cpu {:?} gpu {:?}; field time cpu {:.4} s, gpu {:.4} s (kernel {:?})",
            cpu.rms_vs_truth,
            gpu.rms_vs_truth,
            cpu.estimate_s,
            gpu.estimate_s,
            gpu.estimate_kernel_s
        );
        assert!(c > 0.0 && (c - g).abs() <= 0.5, "cpu {c} gpu {g}");
        let (ct, gt) = (cpu.rms_vs_truth.unwrap(), gpu.rms_vs_truth.unwrap());
        assert!((ct - gt).abs() <= 0.5, "vs truth: cpu {ct} gpu {gt}");
        assert!(gpu.setup_s.unwrap() > 0.0);
        assert_eq!(gpu.estimate_kernel_s.is_some(), ctx.has_timestamps());
    }
}

/// The harness: every test above, run where a Vulkan adapter exists and reported as ignored,
/// with the reason, where none does (a skipped test never shows as passed).
fn main() {
    common::run_gpu_trials(
        "gpu_reflect",
        &[
            (
                "field_reflections_match_the_cpu",
                field_reflections_match_the_cpu,
            ),
            (
                "ray_cast_reflections_match_the_cpu_tracer",
                ray_cast_reflections_match_the_cpu_tracer,
            ),
            (
                "many_rays_split_over_invocations_match_the_cpu",
                many_rays_split_over_invocations_match_the_cpu,
            ),
            (
                "overlapping_spheres_give_the_nearest_hit_not_the_first",
                overlapping_spheres_give_the_nearest_hit_not_the_first,
            ),
            (
                "edge_cases_are_those_of_the_cpu",
                edge_cases_are_those_of_the_cpu,
            ),
            (
                "a_reflections_run_on_cpu_and_gpu_gives_matching_rows",
                a_reflections_run_on_cpu_and_gpu_gives_matching_rows,
            ),
        ],
        &[],
    );
}
