//! Glossy reflections by field lookup on the GPU (Gaitatzes, Andreadis, Papaioannou,
//! Chrysanthou, WSCG 2010, §4.2 and Figure 9: every reflection ray answered by the visibility
//! fields with an approximate hit point, and by the normal fields with the normal there), with
//! the CPU path's reflection rays ([`crate::render::reflect::reflect_at_points`]).
//!
//! One invocation takes a receiver point and a run of its reflection rays (the mirror ray, or
//! the k² rays of a Phong lobe), builds each from the host's lobe directions and the point's
//! rotation as the CPU does (src/gpu/reflect_rays.rs, shaders/reflect_rays.wgsl), answers it
//! with the lookup WGSL of [`super::FieldAoKernel`] (inter- and intra-object, nearest or
//! interpolated) over every instance the ray meets, keeping the nearest hit as
//! `FieldScene::surface_hit` does, reads the normal of the map and texel the nearest selection
//! reads from the instance's normal field (bound as one extra storage buffer, a texel a word,
//! unpacked as `unpack_normal`), turns it to the world, shades the hit as `shade`, and writes
//! the sum of its kept rays' radiance and their count; the host adds up a point's runs and
//! divides (src/gpu/loop_budget.rs).
//!
//! Deviations from the CPU path: those of [`super::FieldAoKernel`] (f32 sphere tests and entry
//! point, Fibonacci point sets and jittered ray sets refused), instances tried in index order
//! (the host sorts them by entry; the nearest hit is the same, ties resolved alike), and the
//! radiance summed in f32 within an invocation (src/gpu/reflect_rays.rs). Deviation from the
//! paper: it does not give its lobe, shading or lights; ours are the CPU path's
//! (`render::reflect`).

use super::context::GpuContext;
use super::field_kernel::{FieldGpuOptions, FieldKernel};
use super::loop_budget::weighted_means;
use super::rays::receivers;
use super::reflect_rays::{lobe_directions, normal_words, rays_per_point, shading};
use super::shadow_rays::{check_binding, light_records, LightGpu};
use super::{GpuError, GpuTiming};
use crate::field::lookup::LookupOptions;
use crate::field::scene::FieldInstance;
use crate::render::reflect::ReflectOptions;
use crate::sampling::rays::RaySet;
use glam::Vec3;
use std::time::{Duration, Instant};

/// The kernel's own inputs (after the shared header's bindings): lobe directions, lights,
/// shading, normal fields.
const OWN_INPUTS: u32 = 4;

/// Field-lookup glossy reflections over a set of field instances and their normal fields,
/// uploaded once (Gaitatzes et al., WSCG 2010, §4.2): its own bindings in group 0 (the normal
/// fields among them), the fields in a `FieldBinding` (src/gpu/field_binding.rs), as
/// [`super::FieldShadowKernel`].
pub struct FieldReflectKernel<'a> {
    core: FieldKernel<'a>,
    pipeline: wgpu::ComputePipeline,
    normals: wgpu::Buffer,
    normal_bytes: u64,
    setup: Duration,
    /// Selection and intra-object bias of the lookups (may be changed between calls).
    pub lookup: LookupOptions,
}

impl<'a> FieldReflectKernel<'a> {
    /// Packs and uploads `instances` (their distinct fields and normal fields once each) and
    /// compiles the kernel; `opts` as for [`super::FieldAoKernel::new`].
    ///
    /// Errors: [`GpuError::Invalid`] when an instance has no normal field
    /// ([`FieldInstance::with_normals`]), [`GpuError::TooLarge`] when the normal fields pass
    /// one storage binding, and those of [`super::FieldAoKernel::new`].
    pub fn new(
        ctx: &'a GpuContext,
        instances: &[FieldInstance],
        opts: &FieldGpuOptions,
    ) -> Result<Self, GpuError> {
        let start = Instant::now();
        let words = normal_words(instances)?;
        check_binding::<u32>(ctx, "normal field words", words.len())?;
        let core = FieldKernel::new(ctx, instances, opts, "field reflect", OWN_INPUTS)?;
        let source = core.source(&[
            include_str!("../../shaders/shadow_rays.wgsl"),
            include_str!("../../shaders/reflect_rays.wgsl"),
            include_str!("../../shaders/field_reflect.wgsl"),
        ]);
        let pipeline = core.pipeline("field_reflect", &source, "reflect_main")?;
        let normals = ctx.storage_buffer("normal fields", bytemuck::cast_slice(&words));
        Ok(FieldReflectKernel {
            core,
            pipeline,
            normals,
            normal_bytes: words.len() as u64 * 4,
            setup: start.elapsed(),
            lookup: opts.lookup,
        })
    }

    /// Moves the instances to `instances`' transforms, the fields staying on the device (the
    /// same fields, instance by instance, as at `new`): a moving rigid object's per-frame cost.
    pub fn place(&self, instances: &[FieldInstance]) -> Result<(), GpuError> {
        self.core.place(instances)
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Bytes of the normal fields on the device (4 a texel: both precisions are held in a
    /// 32-bit word).
    pub fn normal_bytes(&self) -> u64 {
        self.normal_bytes
    }

    /// Rays per invocation the next call starts with (see
    /// [`super::FieldAoKernel::rays_per_invocation`]).
    pub fn rays_per_invocation(&self) -> u32 {
        self.core.rays_per_invocation()
    }

    /// The reflected radiance at every point (point `i` uses the square samples and rotation
    /// of point index `i` of `rays`), as [`crate::render::reflect::reflect_at_points`]
    /// computes it over a [`crate::field::scene::FieldScene`] of the same instances and lookup
    /// options.
    pub fn reflections(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        rays: &RaySet,
        opts: &ReflectOptions,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let lobe = lobe_directions(rays, opts.gloss)?;
        let light_records = light_records(&opts.lights);
        let recv = receivers(points, normals, rays)?;
        let ctx = self.core.ctx;
        check_binding::<[f32; 4]>(ctx, "lobe directions", lobe.len())?;
        check_binding::<LightGpu>(ctx, "lights", light_records.len())?;
        let lobe_buf = ctx.storage_buffer("lobe directions", bytemuck::cast_slice(&lobe));
        let lights_buf = ctx.storage_buffer("lights", bytemuck::cast_slice(&light_records));
        let shading_buf = ctx.storage_buffer("shading", bytemuck::bytes_of(&shading(opts)));
        let rays_n = rays_per_point(rays, opts.gloss);
        let mut params = self.core.params(&self.lookup, rays_n, opts.offset);
        let (values, kernel, upload) = weighted_means(
            &self.core.rays_per_invocation,
            rays_n,
            recv.len(),
            0.0,
            |per_invocation, per_point| {
                params.rays_per_invocation = per_invocation;
                params.invocations_per_point = per_point;
                let own = [&lobe_buf, &lights_buf, &shading_buf, &self.normals];
                self.core
                    .run(&self.pipeline, params, &recv, &own, (per_point, 2))
            },
        )?;
        Ok((
            values,
            GpuTiming {
                kernel,
                upload,
                wall: start.elapsed(),
            },
        ))
    }
}
