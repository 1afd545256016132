//! The visibility layer of every GPU kernel, the GPU twin of [`crate::visibility::Visibility`]
//! (as [`crate::render::estimator::Estimator`]s ask a `Visibility`, the integrands of
//! src/gpu/integrand.rs ask a [`GpuVisibility`]): a visibility's group (bind group 1: its own
//! header and data) and its WGSL, which defines the queries every integrand needs:
//!
//! - `occluded(origin, dir, tmin, tmax) -> bool`: whether anything meets the ray with
//!   `tmin <= t <= tmax` (AO, shadows);
//! - `surface_hit(origin, dir, tmax) -> SurfaceHit`: the closest hit from `t = 0`, its distance
//!   and unoriented unit normal (reflections; a visibility without normals leaves it out).
//!
//! A pipeline is an integrand's WGSL joined with a visibility's ([`Kernels::compiled`]): the
//! CWBVH ray caster ([`super::GpuTracer`]), the field lookup (src/gpu/field_kernel.rs) and the
//! SDF sphere trace ([`super::SdfKernel`]) are three visibilities, and any other (a test's
//! analytic sphere, tests/gpu_toy_visibility.rs) runs the same integrands.

use super::context::{entry, layout_entry, storage_layout_entry, uniform_layout_entry, GpuContext};
use super::kernel_group::{Integrand, KernelGroup, HEADER_WGSL};
use super::GpuError;
use std::collections::HashMap;
use std::sync::atomic::AtomicU32;
use std::sync::{Arc, Mutex};

/// A GPU visibility: what answers the integrands' rays (see the module documentation).
pub trait GpuVisibility: Sync {
    /// The device its data lives on.
    fn context(&self) -> &GpuContext;
    /// Its WGSL for pipeline variant `variant` ([`Self::variant`]): the declarations of its
    /// group (`@group(1)`), its header and `occluded` (and `surface_hit` where it has one),
    /// after the header (`Frame`, `quat_rotate`, `SurfaceHit`: shaders/frame.wgsl,
    /// shaders/integrand.wgsl).
    fn wgsl(&self, variant: u32) -> String;
    /// The layout of its group.
    fn layout(&self) -> &wgpu::BindGroupLayout;
    /// Its group for one call: its header and data.
    fn bind_group(&self) -> wgpu::BindGroup;
    /// The pipelines compiled against it and the integrands' rays-per-invocation budgets.
    fn kernels(&self) -> &Kernels;
    /// The pipeline variant the next call runs (a shader constant of its WGSL); 0 by default.
    fn variant(&self) -> u32 {
        0
    }
    /// WGSL directives its queries need (`enable wgpu_ray_query;`), put before every
    /// declaration of the pipeline's source, as WGSL requires; none by default.
    fn directives(&self) -> &'static str {
        ""
    }
}

/// An integrand compiled against a visibility: its group 0 and the pipeline.
pub(crate) struct Compiled {
    pub group: KernelGroup,
    pub pipeline: wgpu::ComputePipeline,
}

/// The pipelines a visibility's integrands were compiled to (by entry point and variant, on
/// first use) and each integrand's rays per invocation, as last found to fit
/// (src/gpu/loop_budget.rs).
pub struct Kernels {
    compiled: Mutex<HashMap<(&'static str, u32), Arc<Compiled>>>,
    budgets: [AtomicU32; 3],
}

impl Kernels {
    /// No pipeline yet; every integrand starts at `rays_per_invocation` rays per invocation.
    pub fn new(rays_per_invocation: u32) -> Kernels {
        Kernels {
            compiled: Mutex::default(),
            budgets: std::array::from_fn(|_| AtomicU32::new(rays_per_invocation)),
        }
    }

    /// The rays-per-invocation budget of the integrand in `slot`.
    pub(crate) fn budget(&self, slot: usize) -> &AtomicU32 {
        &self.budgets[slot]
    }

    /// Rays per invocation the integrand in `slot` starts with next.
    pub(crate) fn rays_per_invocation(&self, slot: usize) -> u32 {
        self.budgets[slot].load(std::sync::atomic::Ordering::Relaxed)
    }

    /// `integrand` joined with `vis` for its current variant: the header's WGSL, the
    /// visibility's, then the integrand's, compiled on first use.
    pub(crate) fn compiled(
        &self,
        vis: &dyn GpuVisibility,
        integrand: &Integrand,
    ) -> Result<Arc<Compiled>, GpuError> {
        let variant = vis.variant();
        let key = (integrand.entry, variant);
        let mut cache = self.compiled.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(c) = cache.get(&key) {
            return Ok(c.clone());
        }
        let ctx = vis.context();
        let mut source = vis.directives().to_string() + &HEADER_WGSL.concat() + &vis.wgsl(variant);
        source.extend(integrand.sources.iter().copied());
        let group = KernelGroup::new(ctx, integrand.entry, integrand.own);
        let pipeline = group.pipeline(ctx, &source, integrand.entry, &[vis.layout()])?;
        let c = Arc::new(Compiled { group, pipeline });
        cache.insert(key, c.clone());
        Ok(c)
    }
}

/// The usual shape of a visibility's group: its header (a uniform at binding 0), read-only
/// storage buffers uploaded once at bindings 1, 2, … (the CWBVH's nodes and triangles; the
/// SDF's volumes, instances and samples), then any bindings the visibility binds itself at each
/// call ([`Self::with_bindings`]: buffers it rewrites or replaces, an acceleration structure).
pub struct VisibilityGroup {
    layout: wgpu::BindGroupLayout,
    buffers: Vec<wgpu::Buffer>,
    label: &'static str,
}

/// A read-only storage buffer's binding type, as [`VisibilityGroup::new`] binds its data.
pub const READ_ONLY_STORAGE: wgpu::BindingType = wgpu::BindingType::Buffer {
    ty: wgpu::BufferBindingType::Storage { read_only: true },
    has_dynamic_offset: false,
    min_binding_size: None,
};

impl VisibilityGroup {
    /// Uploads `data` (one storage buffer each, binding 1 on) and makes the group's layout.
    pub fn new(ctx: &GpuContext, label: &'static str, data: &[&[u8]]) -> VisibilityGroup {
        VisibilityGroup::with_bindings(ctx, label, data, &[])
    }

    /// As [`Self::new`], with `more` bindings after `data`'s, whose resources each call hands
    /// to [`Self::bind_with`].
    pub fn with_bindings(
        ctx: &GpuContext,
        label: &'static str,
        data: &[&[u8]],
        more: &[wgpu::BindingType],
    ) -> VisibilityGroup {
        let mut entries = vec![uniform_layout_entry(0)];
        entries.extend((1..=data.len() as u32).map(|b| storage_layout_entry(b, true)));
        entries.extend(
            (data.len() as u32 + 1..)
                .zip(more)
                .map(|(b, &ty)| layout_entry(b, ty)),
        );
        let layout = ctx.group_layout(label, &entries);
        let buffers = data.iter().map(|d| ctx.storage_buffer(label, d)).collect();
        VisibilityGroup {
            layout,
            buffers,
            label,
        }
    }

    /// The layout ([`GpuVisibility::layout`]).
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The group with `header` as its uniform ([`GpuVisibility::bind_group`]).
    pub fn bind(&self, ctx: &GpuContext, header: &[u8]) -> wgpu::BindGroup {
        self.bind_with(ctx, header, &[])
    }

    /// The group with `header` as its uniform, its uploaded buffers, then `more`, the
    /// resources of the bindings [`Self::with_bindings`] was given, in order.
    pub fn bind_with(
        &self,
        ctx: &GpuContext,
        header: &[u8],
        more: &[wgpu::BindingResource],
    ) -> wgpu::BindGroup {
        let uniform = ctx.uniform_buffer(self.label, header);
        let mut entries = vec![entry(0, uniform.as_entire_binding())];
        entries.extend(
            self.buffers
                .iter()
                .map(|b| b.as_entire_binding())
                .chain(more.iter().cloned())
                .zip(1..)
                .map(|(r, i)| entry(i, r)),
        );
        ctx.bind_group(self.label, &self.layout, &entries)
    }
}
