//! The GPU backend of a run (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010: field
//! lookup on the GPU, compared there with a GPU BVH ray caster): field-lookup AO through
//! [`crate::gpu::FieldAoKernel`], field-lookup soft shadows (§4.2) through [`crate::gpu::FieldShadowKernel`],
//! field-lookup glossy reflections (§4.2, with the normal fields) through
//! [`crate::gpu::FieldReflectKernel`], and ray-cast AO, shadows and reflections on a [`GpuTracer`] (an
//! obvhs CWBVH in WGSL; the kinds' integrands run on any [`crate::gpu::GpuVisibility`]), on the rays of the CPU path (the same seeded k² cell centres, rotated
//! per point by the same angles, from the same offset origins; for shadows mapped into each
//! light's cone, for reflections into the Phong lobe about the mirror direction, as on the
//! CPU).
//!
//! Each estimator runs on the kernels of its quantity, which its render kind supplies
//! ([`GpuQuantity`], in `Setup::gpu`; the AO kinds' in `kinds/ao.rs`, the shadows' in
//! `kinds/shadows.rs`, the reflections' in `kinds/reflections.rs`, whose field kernel needs
//! every instance's normal field, which the run attaches for reflections); an estimator without
//! kernels is refused with [`GpuError::Unsupported`], naming it.
//!
//! Times: the runner times [`Eval::estimate`] on the host, which is the call's wall time
//! (receiver upload, dispatch, wait and read-back); the kernel alone, from GPU timestamps, comes
//! back in [`Estimate::kernel_s`]; packing and uploading the fields (or building and uploading
//! the CWBVH) and compiling the shaders is [`Eval::setup_s`], reported apart.

pub use super::backend::GpuQuantity;
use super::backend::{Casters, ComputeBackend, CpuBackend, Estimate, Eval, Quantity};
use super::spec::Backend;
use super::Result;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::gpu::{
    AdapterPreference, FieldGpuOptions, FieldLayout, GpuContext, GpuError, GpuTiming, GpuTracer,
    GpuVisibility,
};
use crate::render::estimator::Points;
use crate::sampling::rays::RaySet;
use std::time::Duration;

/// The wgpu device a run's "gpu" cells use, opened once per run.
pub struct GpuBackend {
    ctx: GpuContext,
    /// How the fields are bound (the faster on our measurements is the default, see
    /// [`FieldGpuOptions::default`]).
    pub layout: FieldLayout,
}

impl GpuBackend {
    /// Opens the adapter `pref` selects; the error says which adapters exist.
    pub fn open(pref: AdapterPreference) -> Result<GpuBackend> {
        let ctx = GpuContext::new(pref)?;
        Ok(GpuBackend {
            ctx,
            layout: FieldGpuOptions::default().layout,
        })
    }

    /// The device.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }
}

/// A field kernel prepared for one quantity: the kernel, the quantity's options and the
/// kernel's entry (each kind's [`GpuQuantity::fields`] builds one).
pub struct KernelEval<K, O> {
    pub kernel: K,
    pub opts: O,
    /// The kernel's entry: the values at the points and the timing.
    pub run: KernelEntry<K, O>,
    /// The kernel's preparation time (pack, upload, compile).
    pub setup: fn(&K) -> std::time::Duration,
    /// Moves the kernel's instances (its `place`).
    pub place: fn(&K, &[FieldInstance]) -> std::result::Result<(), GpuError>,
}

/// A field kernel's entry point, as [`KernelEval`] calls it.
pub type KernelEntry<K, O> =
    fn(&K, Points, &RaySet, &O) -> std::result::Result<(Vec<f32>, GpuTiming), GpuError>;

impl<K, O> Eval for KernelEval<K, O> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        traced((self.run)(&self.kernel, at, rays, &self.opts))
    }

    fn setup_s(&self) -> Option<f64> {
        Some((self.setup)(&self.kernel).as_secs_f64())
    }

    fn place(&self, instances: &[FieldInstance]) -> Result<()> {
        Ok((self.place)(&self.kernel, instances)?)
    }
}

/// [`GpuQuantity::trace`] (and a field kernel's estimate) from an integrand's result.
pub fn traced(r: std::result::Result<(Vec<f32>, GpuTiming), GpuError>) -> Result<Estimate> {
    let (values, t) = r?;
    Ok(Estimate {
        values,
        kernel_s: t.kernel.map(|d| d.as_secs_f64()),
    })
}

/// The GPU quantity of an estimator, or the refusal naming it: one without kernels, or one
/// with channels (the kernels give one value per point).
fn quantity(q: Quantity<'_>) -> Result<&dyn GpuQuantity> {
    let name = q.estimator.name();
    let channels = q.estimator.channels();
    if channels != 1 {
        return Err(GpuError::Unsupported(format!(
            "\"{name}\" has {channels} values per point; the GPU kernels give one"
        ))
        .into());
    }
    q.gpu
        .ok_or_else(|| GpuError::Unsupported(format!("no GPU kernel computes \"{name}\"")).into())
}

/// A GPU visibility running the kind's integrand ([`GpuQuantity::trace`]): the evaluation of
/// every GPU ray caster (the CWBVH, the two levels, ray queries), charged `setup` (its build,
/// uploads and compilation).
pub struct TraceEval<'a, V> {
    pub vis: V,
    pub quantity: &'a dyn GpuQuantity,
    pub setup: Duration,
}

impl<'a, V: GpuVisibility + 'a> TraceEval<'a, V> {
    /// `vis`, built and uploaded in `setup`, running `quantity`, as the run's evaluation.
    pub fn boxed(setup: Duration, vis: V, quantity: &'a dyn GpuQuantity) -> Box<dyn Eval + 'a> {
        Box::new(TraceEval {
            vis,
            quantity,
            setup,
        })
    }
}

impl<V: GpuVisibility> Eval for TraceEval<'_, V> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        self.quantity.trace(&self.vis, at, rays)
    }

    fn setup_s(&self) -> Option<f64> {
        Some(self.setup.as_secs_f64())
    }
}

/// The kind's GPU kernels a ray-casting `method` runs on its visibility, or the refusal
/// naming the method where the kind has none.
pub fn integrand_of<'a>(
    method: &str,
    quantity: Option<&'a dyn GpuQuantity>,
) -> Result<&'a dyn GpuQuantity> {
    quantity.ok_or_else(|| {
        super::Error::invalid(
            format!("methods \"{method}\""),
            "casts the kind's rays through its GPU integrand: needs the kind's GPU kernels",
        )
    })
}

impl ComputeBackend for GpuBackend {
    fn kind(&self) -> Backend {
        Backend::Gpu
    }

    /// "name | driver driver_info | Vulkan" ([`GpuContext::adapter_label`]).
    fn adapter(&self) -> String {
        self.ctx.adapter_label()
    }

    fn gpu_context(&self) -> Option<&GpuContext> {
        Some(&self.ctx)
    }

    fn fields<'s>(&'s self, fields: &'s FieldScene, q: Quantity<'s>) -> Result<Box<dyn Eval + 's>> {
        let opts = FieldGpuOptions {
            lookup: fields.options,
            layout: self.layout,
            ..Default::default()
        };
        quantity(q)?.fields(&self.ctx, fields, &opts)
    }

    fn casters<'s>(
        &'s self,
        casters: &'s Casters<'s>,
        q: Quantity<'s>,
    ) -> Result<Box<dyn Eval + 's>> {
        let quantity = quantity(q)?;
        let vis = GpuTracer::new(&self.ctx, casters.triangles)?;
        Ok(TraceEval::boxed(vis.setup_time(), vis, quantity))
    }
}

/// Opens a backend; "gpu" opens the adapter `adapter` selects ([`AdapterPreference::Auto`]:
/// hardware where there is one, else lavapipe).
pub fn open(kind: Backend, adapter: &AdapterPreference) -> Result<Box<dyn ComputeBackend>> {
    match kind {
        Backend::Cpu => Ok(Box::new(CpuBackend::new())),
        Backend::Gpu => Ok(Box::new(GpuBackend::open(adapter.clone())?)),
    }
}
