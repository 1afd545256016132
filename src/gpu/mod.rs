//! Headless wgpu paths: the same experiments as the CPU path, on lavapipe (Mesa's Vulkan on the
//! CPU) or on a real GPU (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, "Fast Approximate
//! Visibility on the GPU using Precomputed 4D Visibility Fields", WSCG 2010).
//!
//! - [`GpuContext`]: adapter choice ([`AdapterPreference`], `VISFIELD_ADAPTER`), the device
//!   with the adapter's own limits, and [`GpuContext::adapter_label`] for result rows.
//! - One kernel skeleton, integrand × visibility: a render kind's per-point loop written once
//!   in WGSL ([`ao`], [`shadows`], [`reflections`]; src/gpu/integrand.rs) against the queries
//!   of any [`GpuVisibility`] (`occluded`, `surface_hit`; src/gpu/visibility.rs), joined by
//!   WGSL concatenation into one pipeline per pair ([`Kernels`]).
//! - [`FieldKernel`]: the field-lookup visibility (inter- and intra-object, nearest or
//!   interpolated selection, the CPU path's map selection), with the fields bound as
//!   storage-buffer windows or as slices of a 3D texture ([`FieldLayout`]; src/gpu/
//!   field_binding.rs): vertex AO ([`FieldAoKernel`], with its workgroup ray queue), soft
//!   shadows from spherical lights ([`FieldShadowKernel`], 2010 §4.2) and glossy reflections
//!   with the normal fields ([`FieldReflectKernel`], 2010 §4.2).
//! - [`GpuTracer`]: the GPU ray-cast reference, an obvhs CWBVH traversed in WGSL with the
//!   watertight triangle test, a visibility (and its own any / closest hit queries), so that
//!   GPU lookup is compared with GPU ray casting on the same device.
//! - [`GpuTwoLevel`]: two-level ray casting for moving rigid instances, each mesh's CWBVH
//!   uploaded once and a top level over the instances' world boxes rebuilt and uploaded per
//!   frame (the twin of the CPU's `trace::two_level`), a visibility.
//! - [`RayQueryScene`]: hardware ray queries (wgpu's `EXPERIMENTAL_RAY_QUERY`) as a
//!   visibility, a BLAS per mesh and a TLAS of the instances rebuilt as they move, where the
//!   adapter offers them ([`GpuContext::ray_query_support`]).
//! - [`SdfKernel`]: mesh signed distance fields, a visibility by sphere tracing, with
//!   cone-traced AO and shadows; [`AoFieldKernel`]: AO fields, a direct estimator.
//! - [`ReliefKernel`]: the 2005 relief caster (linear search, bisection, safety-zone skips)
//!   over segments through the prism, for the relief experiment's GPU columns.
//! - [`ReliefPeersKernel`]: the relief search's modern peers (cell walk, maximum mipmaps,
//!   cone and relaxed cone stepping), the CPU's f32 operations in WGSL.
//! - [`GpuTiming`]: GPU timestamps (where the adapter has them) and wall time, separately.
//!
//! WGSL lives in `shaders/` and is included at compile time; every uniform and storage struct
//! has a `#[repr(C)]`, `Pod` twin with the same named fields (padding spelled out as `_pad*`)
//! and compile-time size and offset assertions.

mod aofield_kernel;
mod context;
mod field_ao;
mod field_binding;
mod field_data;
mod field_kernel;
mod integrand;
mod kernel_group;
mod loop_budget;
mod ray_query;
mod rays;
mod reflect_rays;
mod relief;
mod relief_peers;
mod sdf_data;
mod sdf_kernel;
mod shadow_rays;
mod texture;
mod tracer;
mod two_level;
mod visibility;

pub use aofield_kernel::AoFieldKernel;
pub use context::{AdapterPreference, GpuContext, ADAPTER_ENV};
pub use field_ao::{FieldAoKernel, LookupProbe};
pub use field_binding::FieldLayout;
pub use field_data::FieldInstanceGpu;
pub use field_kernel::{FieldGpuOptions, FieldKernel, FieldReflectKernel, FieldShadowKernel};
pub use integrand::{ao, reflections, shadows};
pub use ray_query::{morton_order, RayQueryHit, RayQueryScene};
pub use relief::ReliefKernel;
pub use relief_peers::ReliefPeersKernel;
pub use sdf_kernel::{SdfKernel, SDF_CONES_PER_INVOCATION, SDF_RAYS_PER_INVOCATION};
pub use tracer::{GpuHit, GpuTracer};
pub use two_level::{GpuTwoLevel, TwoLevelHit};
pub use visibility::{GpuVisibility, Kernels, VisibilityGroup, READ_ONLY_STORAGE};

use std::time::Duration;

/// Errors of the GPU paths.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// The Vulkan backend lists no adapter at all: no Vulkan driver is installed.
    #[error("no Vulkan adapter (install mesa-vulkan-drivers for lavapipe)")]
    NoAdapter,
    #[error("no Vulkan adapter matches {requested}; available: {available}")]
    AdapterNotFound {
        requested: String,
        available: String,
    },
    /// The adapter refused to open a device with its own limits and features.
    #[error("{what}: {source}")]
    RequestDevice {
        /// The request, with the adapter named.
        what: String,
        #[source]
        source: wgpu::RequestDeviceError,
    },
    /// Waiting for the device (`Device::poll`) failed.
    #[error("{what}: {source}")]
    Poll {
        /// What was waited for.
        what: &'static str,
        #[source]
        source: wgpu::PollError,
    },
    /// Mapping a read-back buffer failed.
    #[error("{what}: {source}")]
    Map {
        /// The buffer and the operation.
        what: &'static str,
        #[source]
        source: wgpu::BufferAsyncError,
    },
    /// The map callback was dropped without answering (the device was lost).
    #[error("{what}: {source}")]
    MapCallback {
        /// The buffer and the operation.
        what: &'static str,
        #[source]
        source: std::sync::mpsc::RecvError,
    },
    /// Reading the mapped range of a read-back buffer failed.
    #[error("{what}: {source}")]
    MappedRange {
        /// The buffer and the operation.
        what: &'static str,
        #[source]
        source: wgpu::MapRangeError,
    },
    #[error("shader {shader}: {message}")]
    Shader { shader: String, message: String },
    #[error("unsupported on the GPU path: {0}")]
    Unsupported(String),
    #[error("{what} needs {need} bytes but the adapter allows {limit} ({limit_name})")]
    TooLarge {
        what: String,
        need: u64,
        limit: u64,
        limit_name: &'static str,
    },
    #[error("invalid input: {0}")]
    Invalid(String),
}

/// What a GPU call cost: the kernel alone (GPU timestamps) and the whole call on the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuTiming {
    /// Kernel execution from GPU timestamps; `None` where the adapter has no timestamp queries.
    pub kernel: Option<Duration>,
    /// Host time spent creating and filling the per-call buffers.
    pub upload: Duration,
    /// Wall time of the whole call: upload, dispatch, wait and read-back.
    pub wall: Duration,
}
