//! Compute backends of a run: where the field lookup and the ray-cast timing run.
//!
//! The CPU backend evaluates both through the [`crate::render::Visibility`] interface on the
//! same rays ([`ao_at_points`]). A GPU backend plugs in through [`AoBackend`]; this build has
//! none yet, so asking for "gpu" fails before any work starts, and no GPU device is ever opened
//! unless a spec asks for one.

use super::spec::Backend;
use crate::field::scene::FieldScene;
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

/// A place where AO is computed.
pub trait AoBackend {
    /// Which backend this is.
    fn kind(&self) -> Backend;
    /// The device, for tables and run.json (CPU model and threads, or GPU adapter and driver).
    fn adapter(&self) -> String;
    /// AO through the fields, on `rays` (point i uses the directions of point index i).
    fn field_ao(
        &self,
        fields: &FieldScene,
        at: &Points,
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<Vec<f32>, String>;
    /// Ray-cast AO against the casters, on the same rays.
    fn raycast_ao(
        &self,
        casters: &Casters,
        at: &Points,
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<Vec<f32>, String>;
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

impl AoBackend for CpuBackend {
    fn kind(&self) -> Backend {
        Backend::Cpu
    }

    fn adapter(&self) -> String {
        self.adapter.clone()
    }

    fn field_ao(
        &self,
        fields: &FieldScene,
        at: &Points,
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<Vec<f32>, String> {
        Ok(ao_at_points(fields, at.points, at.normals, rays, opts))
    }

    fn raycast_ao(
        &self,
        casters: &Casters,
        at: &Points,
        rays: &RaySet,
        opts: &AoOptions,
    ) -> Result<Vec<f32>, String> {
        Ok(ao_at_points(
            casters.tracer,
            at.points,
            at.normals,
            rays,
            opts,
        ))
    }
}

/// Opens a backend; "gpu" is refused in this build (no device is touched).
pub fn open(kind: Backend) -> Result<Box<dyn AoBackend>, String> {
    match kind {
        Backend::Cpu => Ok(Box::new(CpuBackend::new())),
        Backend::Gpu => {
            Err("backend \"gpu\": this build has no GPU AO path yet (src/gpu); use \"cpu\"".into())
        }
    }
}
