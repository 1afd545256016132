//! Mesh signed distance fields on the GPU (the engines' per-object peer, `crate::sdf`; D.
//! Wright, "Dynamic Occlusion with Signed Distance Fields", SIGGRAPH 2015 course *Advances in
//! Real-Time Rendering*): instanced distance volumes uploaded once (src/gpu/sdf_data.rs) and
//! three kernels on them (shaders/sdf_volume.wgsl, shaders/sdf_kernel.wgsl):
//!
//! - [`SdfKernel::ao`]: AO by sphere tracing the CPU path's rays, as
//!   [`crate::render::ao::ao_at_points`] computes it through an [`SdfScene`] (its `Visibility`);
//! - [`SdfKernel::cone_ao`]: cone-traced AO, as [`SdfScene::cone_ao`];
//! - [`SdfKernel::cone_light_fractions`]: the cone-traced light fraction of spherical lights,
//!   as [`SdfScene::cone_light_fraction`].
//!
//! The volumes, the instances and the stored samples are a visibility (group 1,
//! [`GpuVisibility`]: its header `SdfParamsGpu` and `occluded`, the sphere trace), so that AO
//! is the AO integrand (src/gpu/integrand.rs); the cone kernels are direct estimators on the
//! same two groups, the directions (cone axes or lights) their own input. The per-ray and per-cone
//! arithmetic is a line-by-line port in the CPU's f32 order: the trilinear read with every
//! precision decoded as the host decodes it (u8 through the host's table of the codes'
//! distances), glam's rotation, `min`, `max` and normalisation, the sphere trace's box clip and
//! steps, the cone's bound test and march. What the host computes instead: the rotated base
//! directions' cos and sin (src/gpu/rays.rs), the cone axes, `hi`, the bounding spheres, the hit
//! threshold and start offset in each volume's units, and the lights' weights (f64, with the
//! transcendental functions of `sdf::cone::cap_irradiance`), which only multiply the device's
//! visibilities on the host. The cones' means are taken on the host in the CPU's order
//! (`sdf::cone::cone_ao_mean`, `sdf::cone::light_fraction`), so a point whose cones read the
//! same visibilities gets the CPU's value bit for bit.
//!
//! What may still differ: WGSL's division and square root, which Vulkan allows 2.5 ulp (on
//! lavapipe they are IEEE, as on the host), and multiply-adds a driver may fuse. A sphere
//! trace or a cone march is a sequence of comparisons (a read below the hit threshold, a step
//! past the box), so a rounding difference may end one ray or cone at a different step:
//! the parity test (tests/gpu_peers.rs) counts such rays and cones and bounds their effect.
//!
//! Deviations from the CPU path: jittered ray sets are refused (no shared directions), as a
//! distance falloff for AO (the kernel counts free rays; the CPU weighs hit distances); an
//! unbounded AO or cone is traced to `f32::MAX` (the CPU's infinity: every trace is clipped to
//! a volume's box first, so the far end never binds); a cone of a light the host drops (the
//! point inside the light or below its horizon) is still marched, and its value unused.

use super::context::GpuContext;
use super::integrand::{self, dispatcher, timing, Integrand, IntegrandParamsGpu, RECEIVER_WGSL};
use super::loop_budget::ray_words;
use super::rays::unrotated_receivers;
use super::sdf_data::pack;
use super::shadow_rays::{check_binding, check_bytes};
use super::visibility::{GpuVisibility, Kernels, VisibilityGroup};
use super::{GpuError, GpuTiming};
use crate::render::ao::{AoOptions, Falloff};
use crate::sampling::rays::RaySet;
use crate::sdf::cone::{cone_ao_mean, light_fraction};
use crate::sdf::{ConeLight, ConeSet, ConeTrace, LightCone, SdfScene};
use glam::Vec3;
use std::sync::atomic::AtomicU32;
use std::time::{Duration, Instant};

/// Twin of WGSL `SdfParams` (shaders/sdf_volume.wgsl): the visibility's header.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct SdfParamsGpu {
    /// Instances.
    instance_count: u32,
    /// Steps per ray, cone and volume.
    max_steps: u32,
    /// Cone kernels: a cone's least step, a share of its radius (`ConeTrace::step`).
    cone_step: f32,
    /// Cone AO: tan of the cones' common half-angle (`ConeSet::tan_half`).
    cone_tan: f32,
}
const _: () = assert!(std::mem::size_of::<SdfParamsGpu>() == 16);

/// The cone kernels (shaders/sdf_kernel.wgsl), the cones' axes or lights at binding 3.
const CONE_AO: Integrand = Integrand {
    sources: &[RECEIVER_WGSL, include_str!("../../shaders/sdf_kernel.wgsl")],
    entry: "cone_ao_main",
    own: 1,
    slot: 0,
};
const CONE_SHADOW: Integrand = Integrand {
    entry: "cone_shadow_main",
    ..CONE_AO
};

/// Rays one invocation of the sphere tracer starts with: a ray may take `max_steps` (256 by
/// default) steps per volume, against lavapipe's 65,535 loop iterations per invocation; the
/// host halves it where a driver cuts invocations short (src/gpu/loop_budget.rs).
pub const SDF_RAYS_PER_INVOCATION: u32 = 64;
/// Cones one invocation of a cone kernel starts with (likewise).
pub const SDF_CONES_PER_INVOCATION: u32 = 16;

/// Instanced distance volumes on the device and the SDF kernels over them.
pub struct SdfKernel<'a> {
    ctx: &'a GpuContext,
    /// The header, volumes, instances and samples, as group 1.
    group: VisibilityGroup,
    kernels: Kernels,
    instance_count: u32,
    max_steps: u32,
    sample_bytes: u64,
    setup: Duration,
    /// Cones per invocation, as last found to fit.
    cones_per_invocation: AtomicU32,
}

impl<'a> SdfKernel<'a> {
    /// Packs and uploads `scene`'s volumes (each distinct volume once) and instances, with its
    /// trace options (hit threshold, start offset, steps), and compiles the kernels.
    ///
    /// Errors: [`GpuError::Invalid`] for a scene without instances, [`GpuError::TooLarge`]
    /// where the samples pass the adapter's storage binding limit.
    pub fn new(ctx: &'a GpuContext, scene: &SdfScene) -> Result<Self, GpuError> {
        let start = Instant::now();
        let packed = pack(scene)?;
        let what = format!("{} distance volumes' samples", packed.volumes.len());
        check_bytes(ctx, what, packed.words.len() as u64 * 4)?;
        let kernel = SdfKernel {
            ctx,
            group: VisibilityGroup::new(
                ctx,
                "sdf",
                &[
                    bytemuck::cast_slice(&packed.volumes),
                    bytemuck::cast_slice(&packed.instances),
                    bytemuck::cast_slice(&packed.words),
                ],
            ),
            kernels: Kernels::new(SDF_RAYS_PER_INVOCATION),
            instance_count: packed.instances.len() as u32,
            max_steps: scene.trace.max_steps,
            sample_bytes: packed.sample_bytes,
            setup: Duration::ZERO,
            cones_per_invocation: AtomicU32::new(SDF_CONES_PER_INVOCATION),
        };
        for i in [&integrand::AO, &CONE_AO, &CONE_SHADOW] {
            kernel.kernels.compiled(&kernel, i)?;
        }
        Ok(SdfKernel {
            setup: start.elapsed(),
            ..kernel
        })
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Bytes of the stored samples (each distinct volume once), as the host stores them; the
    /// device's words add the u8 volumes' 256-entry tables and round each volume up to a word.
    pub fn sample_bytes(&self) -> u64 {
        self.sample_bytes
    }

    /// Rays per invocation the next sphere-traced AO call starts with.
    pub fn rays_per_invocation(&self) -> u32 {
        self.kernels.rays_per_invocation(integrand::AO.slot)
    }

    /// The visibility's header with `cone`'s least step and tan (zero for the sphere trace)
    /// and `max_steps` steps.
    fn header(&self, max_steps: u32, (cone_step, cone_tan): (f32, f32)) -> wgpu::BindGroup {
        let header = SdfParamsGpu {
            instance_count: self.instance_count,
            max_steps,
            cone_step,
            cone_tan,
        };
        self.group.bind(self.ctx, bytemuck::bytes_of(&header))
    }

    /// AO at every point by sphere tracing (point `i` uses the directions of point index `i`
    /// of `rays`), as [`crate::render::ao::ao_at_points`] computes it over the [`SdfScene`]
    /// this kernel was made from.
    ///
    /// Errors: [`GpuError::Unsupported`] for a jittered ray set or a linear falloff.
    pub fn ao(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        if opts.falloff != Falloff::Step {
            return Err(GpuError::Unsupported(
                "SDF AO with a distance falloff (the kernel counts free rays)".into(),
            ));
        }
        integrand::ao(self, points, normals, rays, opts)
    }

    /// Each point's cones' visibilities, point-major (`dirs`: the cones' axes or lights).
    #[allow(clippy::too_many_arguments)]
    fn cones(
        &self,
        integrand: &Integrand,
        points: &[Vec3],
        normals: &[Vec3],
        dirs: &[[f32; 4]],
        offset: f32,
        tmax: f32,
        tan: f32,
        trace: &ConeTrace,
    ) -> Result<(Vec<f32>, Option<Duration>, Duration), GpuError> {
        let recv = unrotated_receivers(points, normals)?;
        check_binding::<[f32; 4]>(self.ctx, "cones", dirs.len())?;
        let buf = self.ctx.storage_buffer("cones", bytemuck::cast_slice(dirs));
        let params = IntegrandParamsGpu {
            tmax: tmax.min(f32::MAX),
            ..IntegrandParamsGpu::new(dirs.len() as u32, offset)
        };
        let group = self.header(trace.max_steps, (trace.step, tan));
        let own = [&buf];
        let each = dispatcher(self, integrand, Some(group), params, &recv, &own, None)?;
        let (words, kernel, upload) = ray_words(
            &self.cones_per_invocation,
            dirs.len() as u32,
            recv.len(),
            each,
        )?;
        Ok((
            words.into_iter().map(f32::from_bits).collect(),
            kernel,
            upload,
        ))
    }

    /// Cone-traced AO at every point (`cones` about each normal, from `point + offset ·
    /// normal`, each to `tmax`), as [`SdfScene::cone_ao`]; the scene's hit threshold and start
    /// offset, `trace`'s least step and steps.
    pub fn cone_ao(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        cones: &ConeSet,
        (offset, tmax): (f32, f32),
        trace: &ConeTrace,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let axes: Vec<[f32; 4]> = cones
            .axes
            .iter()
            .map(|a| a.extend(0.0).to_array())
            .collect();
        let (v, kernel, upload) = self.cones(
            &CONE_AO,
            points,
            normals,
            &axes,
            offset,
            tmax,
            cones.tan_half,
            trace,
        )?;
        let ao = if axes.is_empty() {
            vec![f32::NAN; points.len()]
        } else {
            v.chunks_exact(axes.len())
                .map(|c| cone_ao_mean(cones, c.iter().copied()))
                .collect()
        };
        Ok((ao, timing(kernel, upload, start)))
    }

    /// The cone-traced light fraction of `lights` at every point (from `point + offset ·
    /// normal`), as [`SdfScene::cone_light_fraction`]: the device marches each light's cone,
    /// the host weighs them ([`LightCone`]).
    pub fn cone_light_fractions(
        &self,
        points: &[Vec3],
        normals: &[Vec3],
        lights: &[ConeLight],
        offset: f32,
        trace: &ConeTrace,
    ) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let records: Vec<[f32; 4]> = lights
            .iter()
            .map(|l| l.center.extend(l.radius).to_array())
            .collect();
        let (v, kernel, upload) = self.cones(
            &CONE_SHADOW,
            points,
            normals,
            &records,
            offset,
            f32::MAX,
            0.0,
            trace,
        )?;
        let fractions = points
            .iter()
            .zip(normals)
            .enumerate()
            .map(|(i, (&p, &n))| {
                let origin = p + offset * n;
                light_fraction(lights.iter().enumerate().map(|(k, l)| {
                    LightCone::new(origin, n, l).map(|c| (c.weight, v[i * lights.len() + k]))
                }))
            })
            .collect();
        Ok((fractions, timing(kernel, upload, start)))
    }
}

impl GpuVisibility for SdfKernel<'_> {
    fn context(&self) -> &GpuContext {
        self.ctx
    }

    fn wgsl(&self, _: u32) -> String {
        include_str!("../../shaders/sdf_volume.wgsl").into()
    }

    fn layout(&self) -> &wgpu::BindGroupLayout {
        self.group.layout()
    }

    fn bind_group(&self) -> wgpu::BindGroup {
        self.header(self.max_steps, (0.0, 0.0))
    }

    fn kernels(&self) -> &Kernels {
        &self.kernels
    }
}
