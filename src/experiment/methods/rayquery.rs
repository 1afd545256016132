//! `{"method": "rayquery", "backends": ["gpu"]}`: hardware ray queries
//! ([`crate::gpu::RayQueryScene`]: a BLAS per caster mesh, built once in model space, and a
//! TLAS of the scene's caster instances), the kind's own GPU integrand (AO, shadows,
//! reflections: src/gpu/integrand.rs) run on them on the reference's rays, as the GPU ray
//! caster runs it. What engines answer visibility with today, beside the field (Gaitatzes et
//! al., WSCG 2010, compare with no such caster: beyond the papers).
//!
//! It runs on the `gpu` backend only (the CPU has no ray-query hardware; `raycast` and
//! `embree` are the CPU's casters), and only where the adapter offers ray queries: elsewhere
//! (Mesa's lavapipe before 24.1, GPUs without ray-tracing units) it is skipped, the run's
//! output and run.json (`skipped_methods`) saying why. Its precompute (timed) gathers each
//! mesh's model-space triangles and the instances' transforms; the upload (the row's
//! `setup_s`) sorts each mesh's triangles in Morton order, builds the acceleration structures
//! and compiles the kernels.
//!
//! In a moving scene, `rayquery@gpu` ([`GpuRayQuery`], run beside `two_level`, its twin): a
//! BLAS per mesh built once before the frames, the TLAS over the frame's instances rebuilt per
//! frame and waited for (`update_s`), the kind's integrand on it apart (`query_s`).

use super::motion::{
    model_triangles, FrameCasters, FrameForm, GpuInputs, GpuMover, Mover, MoverInputs,
};
use super::{
    caster_instances, Answer, GpuMethod, Method, MethodContext, MethodEntry, ModelTriangles,
    NoRays, Prepared,
};
use crate::experiment::backend::Eval;
use crate::experiment::backend_gpu::{integrand_of, GpuQuantity, TraceEval};
use crate::experiment::kinds::Kind;
use crate::experiment::Result;
use crate::geometry::Similarity;
use crate::gpu::{GpuContext, RayQueryScene};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use glam::Mat4;

pub const ENTRY: MethodEntry = MethodEntry {
    name: "rayquery",
    about: "hardware ray queries (a BLAS per mesh, a TLAS of the instances; gpu backend, where \
            the adapter offers them)",
    read: super::read_as::<super::NoOptions<RayQuery>>,
};

/// Its per-frame forms ([`Method::frame_forms`]): `rayquery@gpu`, its TLAS rebuilt every
/// frame, run beside `two_level` (its twin).
pub const FRAME_FORMS: &[FrameForm] = &[FrameForm::gpu("rayquery@gpu", "two_level")];

/// Hardware ray queries over the scene's caster instances.
#[derive(Default)]
pub struct RayQuery;

impl Method for RayQuery {
    fn frame_forms(&self) -> &'static [FrameForm] {
        FRAME_FORMS
    }

    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn refuses_on_cpu(&self, _kind: &dyn Kind) -> Option<String> {
        Some(
            "ray queries run on the gpu backend only (`\"backends\": [\"gpu\"]`); the CPU's \
             casters are \"raycast\" and \"embree\""
                .into(),
        )
    }

    /// Every kind with GPU kernels (the runner refuses one without them, naming it).
    fn refuses_on_gpu(&self, _kind: &dyn Kind) -> Option<String> {
        None
    }

    fn unavailable_on_gpu(&self, ctx: &GpuContext) -> Option<String> {
        ctx.ray_query_support().err()
    }

    fn gpu_mover<'a>(
        &self,
        _form: &str,
        on: &MoverInputs,
        gpu: &GpuInputs<'a>,
    ) -> Result<GpuMover<'a>> {
        let meshes = model_triangles(on.meshes);
        Ok(Ok(Box::new(GpuRayQuery {
            quantity: gpu.kernels,
            scene: RayQueryScene::new(gpu.ctx, &meshes, &placements(gpu.first))?,
        })))
    }

    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        let (meshes, instances) = caster_instances(ctx.scene);
        let instances = placements(&instances);
        Ok(Prepared {
            answer: Answer::Rays(Box::new(NoRays)),
            bytes: None,
            cached: false,
            columns: Vec::new(),
            gpu: Some(Box::new(RayQueryGpu { meshes, instances })),
        })
    }
}

/// The scene's meshes and instances, ready to build on a device.
struct RayQueryGpu {
    meshes: ModelTriangles,
    instances: Vec<(usize, Mat4)>,
}

impl GpuMethod for RayQueryGpu {
    fn upload<'a>(
        &'a self,
        ctx: &'a GpuContext,
        quantity: Option<&'a dyn GpuQuantity>,
    ) -> Result<Box<dyn Eval + 'a>> {
        let quantity = integrand_of(ENTRY.name, quantity)?;
        let vis = RayQueryScene::new(ctx, &self.meshes, &self.instances)?;
        Ok(TraceEval::boxed(vis.setup_time(), vis, quantity))
    }
}

/// Hardware ray queries over the frame's instances: a BLAS per mesh built once, the TLAS
/// rebuilt per frame.
pub struct GpuRayQuery<'a> {
    quantity: &'a dyn GpuQuantity,
    scene: RayQueryScene<'a>,
}

/// Instances as (mesh, model-to-world matrix).
fn placements(instances: &[(usize, Similarity)]) -> Vec<(usize, Mat4)> {
    (instances.iter()).map(|&(m, t)| (m, t.to_mat4())).collect()
}

impl Mover for GpuRayQuery<'_> {
    fn name(&self) -> &'static str {
        FRAME_FORMS[0].name
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        Ok(self.scene.place(&placements(frame.instances))?)
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(self.quantity.trace(&self.scene, at, rays)?.values)
    }
}
