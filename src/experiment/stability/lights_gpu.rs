//! The GPU rows of the 2010 kinds' light cases (Gaitatzes, Andreadis, Papaioannou, Chrysanthou,
//! WSCG 2010, §4.2), beside the CPU rows of [`super::lights`]: the GPU's ray caster and field
//! kernel on the same shadow rays, run by [`super::run`] where an adapter exists (and by
//! `tests/small_lights.rs`, ignored without one).

use super::lights::{at_origin, opts, SIZES};
use super::scene_ao::max_diff;
use super::{max2, MaxOf, StabilityRow};
use crate::render::shadow::shadow_at_points;
use crate::sampling::rays::RaySet;
use glam::{DVec3, Vec3};

/// The GPU rows: the GPU's ray caster and field kernel on the same shadow rays, at every size down to the point light.
/// Occluded light cannot hide behind the "no light" value: a coaxial UV sphere (24 × 48)
/// covering the whole light gives exactly 0 at every size, and one covering part
/// of it the CPU tracer's fraction within two rays' share (2/k² per ray with the weights about
/// equal, n on the axis) plus the f32 sums' 1e-5; the grazing case's GPU field matches the CPU
/// field within the same.
pub fn gpu_rows(ctx: &crate::gpu::GpuContext) -> crate::experiment::Result<Vec<StabilityRow>> {
    use crate::experiment::Error;
    use crate::field::scene::FieldInstance;
    use crate::geometry::{procedural, Similarity};
    use crate::gpu::{FieldGpuOptions, FieldShadowKernel, GpuTracer};
    use crate::trace::Tracer;
    let case = "gpu_sphere_lights";
    let unit = procedural::uv_sphere(1.0, 24, 48).expect("uv sphere");
    let icosphere = |radius: f32, centre: Vec3| -> Vec<[Vec3; 3]> {
        (0..unit.triangle_count())
            .map(|i| unit.triangle(i).map(|v| centre + radius * v))
            .collect()
    };
    let gpu = |e| Error::Gpu(e).context("stability: gpu_sphere_lights");
    let k = 8u32;
    let rays = RaySet::new(k, 5);
    let two_rays = 2.2 / (k * k) as f64 + 1e-5;
    let (p, n) = at_origin(16);
    let (dl, d_o) = (10.0f64, 5.0f64);
    let mut sizes: Vec<f64> = SIZES.to_vec();
    sizes.push(0.0);
    let (mut covered, mut parity) = (0.0f64, 0.0f64);
    for &s in &sizes {
        let o = opts(DVec3::new(0.0, 0.0, dl), s * dl);
        // Covering: an occluder of angular radius 1.5 α (α at least 1e-3, so that it is solid).
        let cover = icosphere(
            (1.5 * s.max(1e-3) * d_o) as f32,
            Vec3::new(0.0, 0.0, d_o as f32),
        );
        let t = GpuTracer::new(ctx, &cover).map_err(gpu)?;
        let (v, _) = crate::gpu::shadows(&t, &p, &n, &rays, &o).map_err(gpu)?;
        covered = max2(covered, v.iter().map(|&x| x as f64).max_of());
        // Partly: radius 0.6 α, 0.5 α off the axis; the point light's ray passes beside it.
        let off = Vec3::new((0.5 * s * d_o) as f32, 0.0, d_o as f32);
        let part = icosphere((0.6 * s.max(1e-7) * d_o) as f32, off);
        let t = GpuTracer::new(ctx, &part).map_err(gpu)?;
        let (g, _) = crate::gpu::shadows(&t, &p, &n, &rays, &o).map_err(gpu)?;
        let c = shadow_at_points(&Tracer::new(&part), &p, &n, &rays, &o);
        parity = max2(parity, max_diff(&g, &c));
    }
    // The grazing case's field on the GPU against the CPU's.
    let mesh = procedural::uv_sphere(1.0, 32, 64).expect("uv sphere");
    let field = super::scene_ao::bake_field(&mesh);
    let b = field.bounds;
    let inst = FieldInstance::new(field.clone(), Similarity::default());
    let fs = crate::field::scene::FieldScene {
        instances: vec![inst.clone()],
        options: Default::default(),
    };
    let kernel = FieldShadowKernel::new(ctx, &[inst], &FieldGpuOptions::default()).map_err(gpu)?;
    let mut field_parity = 0.0f64;
    for (o, pts, nrm) in super::lights::grazing_lights(&b) {
        let (g, _) = crate::gpu::shadows(&kernel, &pts, &nrm, &rays, &o).map_err(gpu)?;
        let c = shadow_at_points(&fs, &pts, &nrm, &rays, &o);
        field_parity = max2(field_parity, max_diff(&g, &c));
    }
    Ok(vec![
        StabilityRow::new(
            case,
            format!("GPU ray casting, a sphere covering the light: light fraction at r/d = 0.5 … 1e-7 and 0 ({})", ctx.adapter_label()),
            covered,
            0.0,
        ),
        StabilityRow::new(
            case,
            "GPU ray casting against the CPU tracer, a sphere covering part of the light, r/d = 0.5 … 1e-7 and 0 (light fraction)",
            parity,
            two_rays,
        ),
        StabilityRow::new(
            case,
            "GPU field against the CPU field, lights grazing the caster's bounding sphere (light fraction)",
            field_parity,
            two_rays,
        ),
    ])
}
