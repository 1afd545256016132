//! The field visibility (Gaitatzes et al., WSCG 2008 Algorithm 2 and WSCG 2010 on the GPU):
//! the options ([`FieldGpuOptions`]) and [`FieldKernel`], a set of placed fields in a
//! [`FieldBinding`] (group 1) with its header ([`FieldParamsGpu`], twin of WGSL `FieldParams`
//! in shaders/field_visibility.wgsl) and the lookup's `occluded` (and, with the normal fields,
//! `surface_hit`, shaders/field_surface.wgsl), a [`GpuVisibility`] on which the integrands of
//! src/gpu/integrand.rs run: [`super::FieldAoKernel`] (AO, with the field's batched form of
//! it, src/gpu/field_ao.rs), [`super::FieldShadowKernel`] (soft shadows from spherical lights,
//! 2010 §4.2) and [`super::FieldReflectKernel`] (glossy reflections with the normal fields,
//! 2010 §4.2), each on the CPU path's rays.
//!
//! Deviations from the CPU path: the world-space ray–sphere test and the entry point are
//! computed in f32 (the host uses f64), so near-tangent rays and near-ties between maps may
//! resolve differently; the interpolated selection's walk uses an f32 edge tolerance and, when
//! it does not settle within the host's step cap, reads the nearest map alone (the host scans
//! every triangle); instances are tried in index order (the host sorts them by entry
//! distance: the boolean answer and the nearest hit are the same, ties resolved alike); the
//! shadow weights and the reflected radiance are summed in f32 within an invocation
//! (src/gpu/shadow_rays.rs, src/gpu/reflect_rays.rs); Fibonacci point sets (no GPU nearest
//! query) and jittered ray sets (no shared directions) are refused with
//! [`GpuError::Unsupported`]. Deviation from the paper: it samples "stratified points on each
//! spherical light" without saying how; we sample the cone each light subtends, as the CPU
//! path does.

use super::context::GpuContext;
use super::field_binding::{FieldBinding, FieldBindingOptions, FieldLayout};
use super::integrand::{self, Integrand, RECEIVER_WGSL};
use super::reflect_rays::normal_words;
use super::shadow_rays::check_binding;
use super::visibility::{GpuVisibility, Kernels};
use super::GpuError;
use crate::field::lookup::{IntraBias, LookupOptions};
use crate::field::scene::FieldInstance;
use crate::field::Selection;
use std::marker::PhantomData;
use std::time::{Duration, Instant};

/// Options of the field kernels ([`super::FieldAoKernel`], [`super::FieldShadowKernel`],
/// [`super::FieldReflectKernel`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldGpuOptions {
    pub lookup: LookupOptions,
    pub layout: FieldLayout,
    /// Largest window in bytes (storage layout); `None`: the adapter's binding limit. Smaller
    /// windows only serve to test the windowing.
    pub window_bytes: Option<u64>,
    /// Most rays one invocation traces (a point's rays are spread over several invocations);
    /// divided by the instance count to start with, then halved while the driver cuts
    /// invocations short (src/gpu/loop_budget.rs).
    pub rays_per_invocation: u32,
    /// Largest texture depth (texture layout); `None`: the adapter's
    /// `max_texture_dimension_3d`. Smaller depths only serve to test the tiling.
    pub max_texture_depth: Option<u32>,
    /// AO kernel: cull each round of rays against the world spheres and answer only the rays
    /// that meet one, shared over the workgroup (WGSL `ao_queue_main`, the default); `false`:
    /// every invocation answers its own rays (the AO integrand's `ao_main`, kept for
    /// comparison; the answers are the same). See docs/gpu.md, "Field kernel speed on
    /// lavapipe".
    pub queue_rays: bool,
    /// Read each field's owner table (the CPU's `SpherePoints::nearest` table) and texel table
    /// on the device before the ring search and the concentric map, which remain for the cells
    /// the tables leave open (the default); `false`: the ring search and the map alone. The
    /// same map and texel but for f32 near-ties (docs/gpu.md, "Field kernel speed on
    /// lavapipe").
    pub lookup_tables: bool,
    /// Walk the instances' own top level, a BVH over their bounding spheres (the CPU's
    /// `field::sphere_bvh`, rebuilt on the host and uploaded by [`FieldKernel::place`]),
    /// instead of testing every instance's sphere per ray: the same answers, bit for bit
    /// (shaders/field_top_level.wgsl). `false` (the default): every sphere. The AO kernel then
    /// runs the AO integrand (`ao_main`): the workgroup queue (`queue_rays`) culls against
    /// every sphere.
    pub top_level: bool,
}

impl FieldGpuOptions {
    /// The field binding of a kernel with these options and `kernel_storage_buffers` storage
    /// buffers besides the field's own.
    pub(super) fn binding_options(&self, kernel_storage_buffers: u32) -> FieldBindingOptions {
        FieldBindingOptions {
            layout: self.layout,
            window_bytes: self.window_bytes,
            max_texture_depth: self.max_texture_depth,
            kernel_storage_buffers,
            lookup_tables: self.lookup_tables,
            top_level: self.top_level,
        }
    }
}

impl Default for FieldGpuOptions {
    fn default() -> Self {
        FieldGpuOptions {
            lookup: LookupOptions::default(),
            layout: FieldLayout::StorageBuffers,
            window_bytes: None,
            rays_per_invocation: super::loop_budget::DEFAULT_RAYS_PER_INVOCATION,
            max_texture_depth: None,
            queue_rays: true,
            lookup_tables: true,
            top_level: false,
        }
    }
}

/// Twin of WGSL `FieldParams` (shaders/field_visibility.wgsl): the visibility's header.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct FieldParamsGpu {
    /// Field instances.
    instance_count: u32,
    /// Intra-object bias: a fraction of 2R, or the scale of the field's own tolerance.
    intra_bias: f32,
    /// 1 when `intra_bias` scales the field's own tolerance ([`IntraBias::Auto`]), else 0.
    intra_auto: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<FieldParamsGpu>() == 16);

/// What a field kernel answers: its integrand and whether it binds the normal fields.
pub trait FieldQuantity: Sync {
    /// The integrand it runs by default.
    const INTEGRAND: &'static Integrand;
    /// Whether the visibility binds the normal fields (`surface_hit`).
    const NORMALS: bool;
}

/// Vertex AO ([`super::FieldAoKernel`]).
pub struct Ao;
/// Soft shadows ([`FieldShadowKernel`]).
pub struct Shadows;
/// Glossy reflections ([`FieldReflectKernel`]).
pub struct Reflections;

impl FieldQuantity for Ao {
    const INTEGRAND: &'static Integrand = &integrand::AO;
    const NORMALS: bool = false;
}
impl FieldQuantity for Shadows {
    const INTEGRAND: &'static Integrand = &integrand::SHADOWS;
    const NORMALS: bool = false;
}
impl FieldQuantity for Reflections {
    const INTEGRAND: &'static Integrand = &integrand::REFLECTIONS;
    const NORMALS: bool = true;
}

/// The field's batched form of the AO integrand (shaders/field_ao.wgsl, `ao_queue_main`;
/// run by [`super::FieldAoKernel`], src/gpu/field_ao.rs).
pub(super) const AO_QUEUE: Integrand = Integrand {
    sources: &[
        RECEIVER_WGSL,
        include_str!("../../shaders/ao.wgsl"),
        include_str!("../../shaders/field_ao.wgsl"),
    ],
    entry: "ao_queue_main",
    ..integrand::AO
};

/// Field lookup over a set of field instances, uploaded once: the field visibility (see the
/// module documentation), for the quantity `Q`.
pub struct FieldKernel<'a, Q> {
    pub(super) ctx: &'a GpuContext,
    pub(super) field: FieldBinding,
    kernels: Kernels,
    /// AO: the workgroup ray queue (`FieldGpuOptions::queue_rays`).
    pub(super) queue_rays: bool,
    normal_bytes: u64,
    setup: Duration,
    /// Selection and intra-object bias of the lookups (may be changed between calls).
    pub lookup: LookupOptions,
    quantity: PhantomData<Q>,
}

/// Field-lookup soft shadows from spherical lights (2010 §4.2: every shadow ray a lookup, up
/// to the ray's own far end, the near side of its light, as `FieldScene::occluded_many_to`).
pub type FieldShadowKernel<'a> = FieldKernel<'a, Shadows>;
/// Field-lookup glossy reflections (2010 §4.2: every reflection ray answered with the nearest
/// hit over the instances, as `FieldScene::surface_hit`, its normal read from the normal field
/// of the map and texel the nearest selection reads, bound as one more storage buffer).
pub type FieldReflectKernel<'a> = FieldKernel<'a, Reflections>;

impl<'a, Q: FieldQuantity> FieldKernel<'a, Q> {
    /// Packs and uploads `instances` (their distinct fields once each; for reflections their
    /// normal fields too) and compiles the kernel.
    ///
    /// Errors: [`GpuError::Unsupported`] for fields the GPU lookup cannot read,
    /// [`GpuError::TooLarge`] past the adapter's storage bindings or texture size, and for
    /// reflections [`GpuError::Invalid`] when an instance has no normal field
    /// ([`FieldInstance::with_normals`]).
    pub fn new(
        ctx: &'a GpuContext,
        instances: &[FieldInstance],
        opts: &FieldGpuOptions,
    ) -> Result<Self, GpuError> {
        let start = Instant::now();
        let words = if Q::NORMALS {
            let words = normal_words(instances)?;
            check_binding::<u32>(ctx, "normal field words", words.len())?;
            Some(words)
        } else {
            None
        };
        // The integrand's inputs, receivers and output, and the normal fields.
        let storage = Q::INTEGRAND.own + 2 + Q::NORMALS as u32;
        let field = FieldBinding::new(
            ctx,
            instances,
            words.as_deref(),
            &opts.binding_options(storage),
        )?;
        let start_rays = (opts.rays_per_invocation / instances.len().max(1) as u32).max(1);
        let kernel = FieldKernel {
            ctx,
            field,
            kernels: Kernels::new(start_rays),
            queue_rays: opts.queue_rays && !opts.top_level,
            normal_bytes: words.map_or(0, |w| w.len() as u64 * 4),
            setup: Duration::ZERO,
            lookup: opts.lookup,
            quantity: PhantomData,
        };
        let first = match (Q::INTEGRAND.slot == integrand::AO.slot, kernel.queue_rays) {
            (true, true) => &AO_QUEUE,
            _ => Q::INTEGRAND,
        };
        kernel.kernels.compiled(&kernel, first)?;
        Ok(FieldKernel {
            setup: start.elapsed(),
            ..kernel
        })
    }

    /// Moves the instances to `instances`' transforms, the fields staying on the device (the
    /// same fields, instance by instance, as at `new`; with the top level, its tree rebuilt
    /// and uploaded), waiting for the upload: a moving rigid object's per-frame cost.
    pub fn place(&self, instances: &[FieldInstance]) -> Result<(), GpuError> {
        self.field.place(self.ctx, instances)
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Rays per invocation the next call starts with: the options' value divided by the
    /// instance count, or less where a driver cut an earlier call's invocations short.
    pub fn rays_per_invocation(&self) -> u32 {
        self.kernels.rays_per_invocation(Q::INTEGRAND.slot)
    }

    /// Bytes of stored distances on the device.
    pub fn field_bytes(&self) -> u64 {
        self.field.field_bytes()
    }

    /// Bytes of the normal fields on the device (4 a texel: both precisions are held in a
    /// 32-bit word); 0 without them.
    pub fn normal_bytes(&self) -> u64 {
        self.normal_bytes
    }

    /// Storage windows the fields occupy (storage layout), `None` for the texture layout.
    pub fn storage_windows(&self) -> Option<usize> {
        self.field.storage_windows()
    }

    /// Slices of the field texture (texture layout), `None` for the storage layout.
    pub fn texture_depth(&self) -> Option<u32> {
        self.field.texture_depth()
    }
}

impl<Q: Sync> GpuVisibility for FieldKernel<'_, Q> {
    fn context(&self) -> &GpuContext {
        self.ctx
    }

    /// The lookup's WGSL with `SELECTION` the selection code `variant`.
    fn wgsl(&self, variant: u32) -> String {
        format!("const SELECTION: u32 = {variant}u;\n") + &self.field.shader_source()
    }

    fn layout(&self) -> &wgpu::BindGroupLayout {
        self.field.layout()
    }

    fn bind_group(&self) -> wgpu::BindGroup {
        let (intra_bias, intra_auto) = intra_terms(self.lookup.intra_bias);
        let header = FieldParamsGpu {
            instance_count: self.field.instance_count(),
            intra_bias,
            intra_auto,
            _pad: 0,
        };
        self.field.bind_group(self.ctx, bytemuck::bytes_of(&header))
    }

    fn kernels(&self) -> &Kernels {
        &self.kernels
    }

    /// The selection code (`selection_code`).
    fn variant(&self) -> u32 {
        selection_code(self.lookup.selection)
    }
}

/// WGSL `intra_bias` and `intra_auto` of a lookup's intra-object bias.
fn intra_terms(b: IntraBias) -> (f32, u32) {
    match b {
        IntraBias::Auto { scale } => (scale, 1),
        IntraBias::Fixed(f) => (f, 0),
    }
}

/// WGSL `SELECTION` of a selection (SELECT_NEAREST, SELECT_INTERPOLATED).
pub(super) fn selection_code(s: Selection) -> u32 {
    match s {
        Selection::Nearest => 0,
        Selection::Interpolated => 1,
    }
}
