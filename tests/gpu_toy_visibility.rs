//! A toy GPU visibility, an analytic sphere occluder: its header and its WGSL `occluded` and
//! `surface_hit`, nothing else, run through the integrands every GPU visibility runs
//! (`visfield::gpu::{ao, shadows, reflections}`) and checked against the CPU estimators
//! through the same analytic sphere as a `Visibility`. What a new GPU visibility needs is
//! this file's `GpuVisibility` impl (src/gpu/visibility.rs).

use glam::Vec3;
use visfield::gpu::{GpuContext, GpuVisibility, Kernels, VisibilityGroup};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::render::reflect::{reflect_at_points, Gloss, ReflectOptions};
use visfield::render::shadow::{shadow_at_points, ShadowOptions, SphereLight};
use visfield::sampling::rays::RaySet;
use visfield::visibility::{SurfaceHit, Visibility};

mod common;
use common::gpu_context as context;

/// A sphere of centre `c` and radius `r`, hit from either side.
#[derive(Clone, Copy)]
struct Sphere {
    c: Vec3,
    r: f32,
}

impl Sphere {
    /// The nearest t in [tmin, tmax] where origin + t dir meets the sphere (the WGSL's order).
    fn hit(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        let oc = o - self.c;
        let b = oc.dot(d);
        let disc = b * b - (oc.dot(oc) - self.r * self.r);
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        [-b - s, -b + s]
            .into_iter()
            .find(|&t| t >= tmin && t <= tmax)
    }
}

impl Visibility for Sphere {
    fn occluded(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> bool {
        self.hit(o, d, tmin, tmax).is_some()
    }
    fn hit_distance(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.hit(o, d, tmin, tmax)
    }
    fn surface_hit(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        let t = self.hit(o, d, tmin, tmax)?;
        let normal = ((o + t * d) - self.c).normalize();
        Some(SurfaceHit { t, normal })
    }
}

/// The same sphere on the GPU: its header (centre, radius) is its whole group.
const TOY_WGSL: &str = "
struct Toy { c: vec3<f32>, r: f32 }
@group(1) @binding(0) var<uniform> toy: Toy;
fn toy_hit(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> f32 {
    let oc = o - toy.c;
    let b = dot(oc, d);
    let disc = b * b - (dot(oc, oc) - toy.r * toy.r);
    if disc < 0.0 { return -1.0; }
    let s = sqrt(disc);
    if -b - s >= tmin && -b - s <= tmax { return -b - s; }
    if -b + s >= tmin && -b + s <= tmax { return -b + s; }
    return -1.0;
}
fn occluded(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    return toy_hit(o, d, tmin, tmax) >= 0.0;
}
fn surface_hit(o: vec3<f32>, d: vec3<f32>, tmax: f32) -> SurfaceHit {
    var h: SurfaceHit;
    h.t = toy_hit(o, d, 0.0, tmax);
    h.hit = h.t >= 0.0;
    h.normal = normalize((o + h.t * d) - toy.c);
    return h;
}
";

struct ToyGpu<'a> {
    ctx: &'a GpuContext,
    sphere: Sphere,
    group: VisibilityGroup,
    kernels: Kernels,
}

impl GpuVisibility for ToyGpu<'_> {
    fn context(&self) -> &GpuContext {
        self.ctx
    }
    fn wgsl(&self, _: u32) -> String {
        TOY_WGSL.into()
    }
    fn layout(&self) -> &wgpu::BindGroupLayout {
        self.group.layout()
    }
    fn bind_group(&self) -> wgpu::BindGroup {
        let header = self.sphere.c.extend(self.sphere.r).to_array();
        self.group.bind(self.ctx, bytemuck::bytes_of(&header))
    }
    fn kernels(&self) -> &Kernels {
        &self.kernels
    }
}

/// Receivers on the floor z = 0 below and beside a sphere floating at height 1.
fn scene() -> (Sphere, Vec<Vec3>, Vec<Vec3>) {
    let sphere = Sphere {
        c: Vec3::new(0.0, 0.0, 1.0),
        r: 0.6,
    };
    let points: Vec<Vec3> = (0..15 * 15)
        .map(|i| {
            Vec3::new(
                (i % 15) as f32 * 0.25 - 1.75,
                (i / 15) as f32 * 0.25 - 1.75,
                0.0,
            )
        })
        .collect();
    let normals = vec![Vec3::Z; points.len()];
    (sphere, points, normals)
}

/// The largest difference of two value lists and how many differ at all.
fn compare(gpu: &[f32], cpu: &[f32]) -> (f32, usize) {
    assert_eq!(gpu.len(), cpu.len());
    let max = gpu
        .iter()
        .zip(cpu)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f32::max);
    (max, gpu.iter().zip(cpu).filter(|(a, b)| a != b).count())
}

/// AO, soft shadows and mirror reflections of the toy visibility on the GPU give the CPU
/// estimators' values through the same analytic sphere: AO within one ray at 1% of the points
/// at most (a near-tangent ray may round the other way in another driver's WGSL), the light
/// fractions within their f32 sums, the radiance within 1e-4, and the scene is no trivial one
/// (the sphere occludes, shadows and is seen).
#[test]
fn toy_visibility_runs_every_integrand_as_the_cpu() {
    let Some(ctx) = context() else { return };
    let (sphere, p, n) = scene();
    let toy = ToyGpu {
        ctx,
        sphere,
        group: VisibilityGroup::new(ctx, "toy sphere", &[]),
        kernels: Kernels::new(64),
    };
    let rays = RaySet::new(8, 5);
    let per_ray = 1.0 / 64.0;

    // Rays of length 1: the far corners see no sphere, the points below it much of it.
    let ao_opts = AoOptions {
        max_distance: Some(1.0),
        ..AoOptions::for_scene_radius(2.0)
    };
    let cpu = ao_at_points(&sphere, &p, &n, &rays, &ao_opts);
    let (gpu, _) = visfield::gpu::ao(&toy, &p, &n, &rays, &ao_opts).unwrap();
    let (max, differ) = compare(&gpu, &cpu);
    eprintln!("AO: max {max}, {differ} of {} differ", p.len());
    assert!(
        max <= per_ray && differ * 100 <= p.len(),
        "AO: max {max}, {differ} differ"
    );
    assert!(cpu.iter().any(|&a| a < 0.8) && cpu.contains(&1.0));

    let light = SphereLight {
        center: Vec3::new(0.3, 0.2, 3.0),
        radius: 0.5,
        intensity: 1.0,
    };
    let shadow_opts = ShadowOptions {
        offset: 1e-4,
        lights: vec![light],
    };
    let cpu = shadow_at_points(&sphere, &p, &n, &rays, &shadow_opts);
    let (gpu, _) = visfield::gpu::shadows(&toy, &p, &n, &rays, &shadow_opts).unwrap();
    let (max, differ) = compare(&gpu, &cpu);
    // The weights are summed in f32 on the device (docs/gpu.md: within 2(m + 3)·2⁻²⁴ for m
    // rays an invocation), far below one ray's share: no ray decided differently.
    assert!(
        max <= 2.0 * 67.0 * 2f32.powi(-24),
        "shadows: max {max}, {differ} differ"
    );
    assert!(cpu.contains(&0.0) && cpu.contains(&1.0));

    let reflect_opts = ReflectOptions {
        offset: 1e-4,
        eye: Vec3::new(0.0, -4.0, 2.0),
        gloss: Gloss::Mirror,
        lights: vec![light],
        albedo: 0.8,
        sky: 0.1,
    };
    let cpu = reflect_at_points(&sphere, &p, &n, &rays, &reflect_opts);
    let (gpu, _) = visfield::gpu::reflections(&toy, &p, &n, &rays, &reflect_opts).unwrap();
    let (max, differ) = compare(&gpu, &cpu);
    eprintln!("reflections: max {max}, {differ} of {} differ", p.len());
    assert!(max <= 1e-4, "reflections: max {max}");
    assert!(cpu.iter().any(|&v| v != 0.1) && cpu.contains(&0.1));
}
