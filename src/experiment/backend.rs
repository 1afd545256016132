//! Compute backends of a run: where the estimates through fields and by ray casting run.
//!
//! A backend first prepares what it reads ([`ComputeBackend::fields`],
//! [`ComputeBackend::casters`]: on the GPU the upload of the fields or of the CWBVH and the
//! shader compilation) for one render kind's [`Estimator`], then evaluates it on given points
//! and rays as many times as the timing asks ([`Eval::estimate`]), so that the preparation is
//! reported apart from the estimate's time. The CPU backend runs the estimator through the
//! [`crate::visibility::Visibility`] interface on the same rays; the GPU backend
//! (`backend_gpu::GpuBackend`) runs the wgpu kernel of the estimator's quantity
//! ([`crate::gpu`]) on the same rays. No GPU device is ever opened unless a spec asks for
//! "gpu".

use super::spec::Backend;
use super::{Error, Result};
use crate::field::scene::{FieldInstance, FieldScene};
use crate::gpu::{FieldGpuOptions, GpuContext, GpuVisibility};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::trace::Tracer;
use crate::visibility::Visibility;
use glam::Vec3;

/// The casters of a scene, as the reference sees them.
pub struct Casters<'a> {
    /// World triangles of every caster.
    pub triangles: &'a [[Vec3; 3]],
    /// The CPU reference tracer over them.
    pub tracer: &'a Tracer,
}

/// What a backend computes: a render kind's estimator, and its GPU kernels where it has them
/// (`kinds::Setup`).
#[derive(Clone, Copy)]
pub struct Quantity<'a> {
    /// The estimator, run through [`crate::visibility::Visibility`] on the CPU.
    pub estimator: &'a dyn Estimator,
    /// Its GPU kernels; none: the `gpu` backend refuses it, naming the estimator.
    pub gpu: Option<&'a dyn GpuQuantity>,
}

impl<'a> Quantity<'a> {
    /// An estimator without GPU kernels (the CPU backend's only need).
    pub fn cpu(estimator: &'a dyn Estimator) -> Quantity<'a> {
        Quantity {
            estimator,
            gpu: None,
        }
    }
}

/// One evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The estimate: the estimator's channels per point (point-major), each in [0, 1].
    pub values: Vec<f32>,
    /// Kernel time from GPU timestamps (seconds); `None` on the CPU or where the adapter has
    /// no timestamp queries.
    pub kernel_s: Option<f64>,
}

/// Fields or casters prepared on a backend for one estimator, evaluated on any points and rays.
pub trait Eval {
    /// The estimate at `at` on `rays` (point i uses the directions of point index i).
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate>;
    /// Host time of the preparation (GPU: pack, upload, BVH build, compile); `None` on the CPU,
    /// which reads the fields and the tracer in place.
    fn setup_s(&self) -> Option<f64>;
    /// Moves the prepared fields' instances to `instances`' transforms (the same fields, instance
    /// by instance), for the next [`Self::estimate`]: what a frame of rigid motion costs a field
    /// kernel. Refused where nothing prepared can move (a ray caster's BVH is rebuilt instead).
    fn place(&self, _instances: &[FieldInstance]) -> Result<()> {
        Err(Error::invalid(
            "place",
            "this evaluation holds no field instances to move",
        ))
    }
}

/// A place where estimates are computed.
pub trait ComputeBackend {
    /// Which backend this is.
    fn kind(&self) -> Backend;
    /// The device, for tables and run.json (CPU model and threads, or GPU adapter and driver).
    fn adapter(&self) -> String;
    /// Prepares `fields` for `q`.
    fn fields<'s>(&'s self, fields: &'s FieldScene, q: Quantity<'s>) -> Result<Box<dyn Eval + 's>>;
    /// Prepares the casters for ray casting `q`.
    fn casters<'s>(
        &'s self,
        casters: &'s Casters<'s>,
        q: Quantity<'s>,
    ) -> Result<Box<dyn Eval + 's>>;

    /// The GPU device, for the kernels of methods on the `gpu` backend; none on the CPU.
    fn gpu_context(&self) -> Option<&crate::gpu::GpuContext> {
        None
    }

    /// `q` by ray casting the casters, on the same rays.
    fn raycast_estimate(
        &self,
        casters: &Casters,
        q: Quantity,
        at: Points,
        rays: &RaySet,
    ) -> Result<Vec<f32>> {
        Ok(self.casters(casters, q)?.estimate(at, rays)?.values)
    }
}

/// The CPU backend (rayon over points).
pub struct CpuBackend {
    adapter: String,
}

impl CpuBackend {
    /// The CPU model and thread count.
    pub fn adapter(&self) -> String {
        self.adapter.clone()
    }

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

/// An estimator over any [`crate::visibility::Visibility`].
struct CpuEval<'a> {
    vis: &'a dyn crate::visibility::Visibility,
    est: &'a dyn Estimator,
}

impl Eval for CpuEval<'_> {
    fn estimate(&self, at: Points, rays: &RaySet) -> Result<Estimate> {
        Ok(Estimate {
            values: self.est.estimate(self.vis, at, rays),
            kernel_s: None,
        })
    }

    fn setup_s(&self) -> Option<f64> {
        None
    }
}

impl ComputeBackend for CpuBackend {
    fn kind(&self) -> Backend {
        Backend::Cpu
    }

    fn adapter(&self) -> String {
        self.adapter.clone()
    }

    fn fields<'s>(&'s self, fields: &'s FieldScene, q: Quantity<'s>) -> Result<Box<dyn Eval + 's>> {
        Ok(Box::new(CpuEval {
            vis: fields,
            est: q.estimator,
        }))
    }

    fn casters<'s>(
        &'s self,
        casters: &'s Casters<'s>,
        q: Quantity<'s>,
    ) -> Result<Box<dyn Eval + 's>> {
        Ok(Box::new(CpuEval {
            vis: casters.tracer,
            est: q.estimator,
        }))
    }
}

/// The GPU kernels of one estimator's quantity, supplied by its render kind
/// (in `kinds::Setup::gpu`): field lookup on the kernel of the quantity, and the
/// quantity's integrand (src/gpu/integrand.rs) on any GPU visibility (the casters' CWBVH
/// [`GpuTracer`](crate::gpu::GpuTracer) here), both on the CPU path's rays.
pub trait GpuQuantity: Send + Sync {
    /// Packs and uploads `fields` for this quantity's field kernel (`opts`: how they are bound).
    fn fields<'s>(
        &'s self,
        ctx: &'s GpuContext,
        fields: &FieldScene,
        opts: &FieldGpuOptions,
    ) -> Result<Box<dyn Eval + 's>>;
    /// This quantity at `at` by its integrand on `vis` (the GPU ray caster, or any other
    /// [`GpuVisibility`]).
    fn trace(&self, vis: &dyn GpuVisibility, at: Points, rays: &RaySet) -> Result<Estimate>;
}

/// The visibility handed to a method that casts no ray (a direct estimator, an AO field in a
/// moving scene): any query through it is a bug of the method, reported as such.
pub struct NoRays;

impl Visibility for NoRays {
    fn occluded(&self, _: Vec3, _: Vec3, _: f32, _: f32) -> bool {
        unreachable!("a method that casts no ray was asked about one")
    }

    fn hit_distance(&self, _: Vec3, _: Vec3, _: f32, _: f32) -> Option<f32> {
        unreachable!("a method that casts no ray was asked about one")
    }

    fn surface_hit(
        &self,
        _: Vec3,
        _: Vec3,
        _: f32,
        _: f32,
    ) -> Option<crate::visibility::SurfaceHit> {
        unreachable!("a method that casts no ray was asked about one")
    }
}
