//! Compute backends of a run: where the field lookup and the ray-cast timing run.
//!
//! A backend first prepares what it reads ([`AoBackend::fields`], [`AoBackend::casters`]: on
//! the GPU the upload of the fields or of the CWBVH and the shader compilation), then evaluates
//! AO on given points and rays as many times as the timing asks ([`AoEval::ao`]), so that the
//! preparation is reported apart from the AO time. The CPU backend evaluates both through the
//! [`crate::render::Visibility`] interface on the same rays ([`ao_at_points`]); the GPU backend
//! ([`super::backend_gpu::GpuBackend`]) runs the wgpu kernels of [`crate::gpu`] on the same
//! rays. No GPU device is ever opened unless a spec asks for "gpu".

use super::backend_gpu::GpuBackend;
use super::spec::Backend;
use crate::field::scene::FieldScene;
use crate::gpu::AdapterPreference;
use crate::render::ao::{ao_at_points, AoOptions};
use crate::sampling::rays::RaySet;
use crate::trace::Tracer;
use glam::Vec3;

/// The casters of a scene, as the reference sees them.
pub struct Casters<'a> {
    /// World triangles of every caster.
    pub triangles: &'a [[Vec3; 3]],
    /// The CPU reference tracer over them.
    pub tracer: &'a Tracer,
}

/// AO points: positions and unit normals, world space.
pub struct Points<'a> {
    pub points: &'a [Vec3],
    pub normals: &'a [Vec3],
}

/// One AO evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct AoOut {
    /// AO per point, in [0, 1].
    pub ao: Vec<f32>,
    /// Kernel time from GPU timestamps (seconds); `None` on the CPU or where the adapter has
    /// no timestamp queries.
    pub kernel_s: Option<f64>,
}

/// Fields or casters prepared on a backend, evaluated on any points and rays.
pub trait AoEval {
    /// AO at `at` on `rays` (point i uses the directions of point index i).
    fn ao(&self, at: &Points, rays: &RaySet, opts: &AoOptions) -> Result<AoOut, String>;
    /// Host time of the preparation (GPU: pack, upload, BVH build, compile); `None` on the CPU,
    /// which reads the fields and the tracer in place.
    fn setup_s(&self) -> Option<f64>;
}

/// A place where AO is computed.
pub trait AoBackend {
    /// Which backend this is.
    fn kind(&self) -> Backend;
    /// The device, for tables and run.json (CPU model and threads, or GPU adapter and driver).
    fn adapter(&self) -> String;
    /// Prepares `fields` for lookups.
    fn fields<'s>(&'s self, fields: &'s FieldScene) -> Result<Box<dyn AoEval + 's>, String>;
    /// Prepares the casters for ray casting.
    fn casters<'s>(&'s self, casters: &'s Casters<'s>) -> Result<Box<dyn AoEval + 's>, String>;

    /// AO through the fields, on `rays` (point i uses the directions of point index i).
    fn field_ao(
        &self,
        fields: &FieldScene,
        at: &Points,
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<Vec<f32>, String> {
        Ok(self.fields(fields)?.ao(at, rays, opts)?.ao)
    }

    /// Ray-cast AO against the casters, on the same rays.
    fn raycast_ao(
        &self,
        casters: &Casters,
        at: &Points,
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<Vec<f32>, String> {
        Ok(self.casters(casters)?.ao(at, rays, opts)?.ao)
    }
}

/// The CPU backend (rayon over points).
pub struct CpuBackend {
    adapter: String,
}

impl CpuBackend {
    pub fn new() -> CpuBackend {
        let meta = super::meta::RunMeta::collect(None);
        CpuBackend {
            adapter: format!("{} ({} threads)", meta.cpu, meta.threads),
        }
    }
}

impl Default for CpuBackend {
    fn default() -> Self {
        Self::new()
    }
}

/// [`ao_at_points`] over any [`crate::render::Visibility`].
struct CpuEval<'a, V: crate::render::Visibility>(&'a V);

impl<V: crate::render::Visibility> AoEval for CpuEval<'_, V> {
    fn ao(&self, at: &Points, rays: &RaySet, opts: &AoOptions) -> Result<AoOut, String> {
        Ok(AoOut {
            ao: ao_at_points(self.0, at.points, at.normals, rays, opts),
            kernel_s: None,
        })
    }

    fn setup_s(&self) -> Option<f64> {
        None
    }
}

impl AoBackend for CpuBackend {
    fn kind(&self) -> Backend {
        Backend::Cpu
    }

    fn adapter(&self) -> String {
        self.adapter.clone()
    }

    fn fields<'s>(&'s self, fields: &'s FieldScene) -> Result<Box<dyn AoEval + 's>, String> {
        Ok(Box::new(CpuEval(fields)))
    }

    fn casters<'s>(&'s self, casters: &'s Casters<'s>) -> Result<Box<dyn AoEval + 's>, String> {
        Ok(Box::new(CpuEval(casters.tracer)))
    }
}

/// Opens a backend; "gpu" opens the adapter `adapter` selects ([`AdapterPreference::Auto`]:
/// hardware where there is one, else lavapipe).
pub fn open(kind: Backend, adapter: &AdapterPreference) -> Result<Box<dyn AoBackend>, String> {
    match kind {
        Backend::Cpu => Ok(Box::new(CpuBackend::new())),
        Backend::Gpu => Ok(Box::new(GpuBackend::open(adapter.clone())?)),
    }
}
