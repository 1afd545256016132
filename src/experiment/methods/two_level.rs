//! `{"method": "two_level"}`: our ray caster in two levels (`trace::two_level::TwoLevel`: one
//! model-space BVH per distinct caster mesh, shared by its instances, and a top level over the
//! instances' world boxes), the way engines cast rays over instanced objects; on the `gpu`
//! backend its twin, two-level GPU ray casting (`gpu::GpuTwoLevel`: each mesh's CWBVH uploaded
//! once, the top level built on the host and uploaded), through the kind's own integrand. Its
//! precompute is the per-mesh BVHs and the top level; its values are the world ray caster's up
//! to moving the ray instead of the triangles (f32), so its same-ray error is near 0. In a
//! moving scene it follows motion by rebuilding its top level every frame ([`TwoLevelRebuild`],
//! `two_level`); on the GPU (`two_level@gpu`, [`GpuTwoLevelMover`]) each mesh's CWBVH is
//! uploaded once before the frames, the top level over the instances' world boxes rebuilt on
//! the host and uploaded every frame (`update_s`, which waits for the upload), rays moved into
//! each instance's space on the device (`query_s`).

use super::motion::{
    model_triangles, FrameCasters, FrameForm, GpuInputs, GpuMover, Mover, MoverInputs,
};
use super::{
    caster_instances, Answer, GpuMethod, Method, MethodContext, MethodEntry, ModelTriangles,
    Precompute, Prepared,
};
use crate::experiment::backend::Eval;
use crate::experiment::backend_gpu::{integrand_of, GpuQuantity, TraceEval};
use crate::experiment::kinds::Kind;
use crate::experiment::scenes::BuiltScene;
use crate::experiment::Result;
use crate::geometry::Similarity;
use crate::gpu::{GpuContext, GpuTwoLevel};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::trace::two_level::TwoLevel;
use crate::visibility::Visibility;

pub const ENTRY: MethodEntry = MethodEntry {
    name: "two_level",
    about: "our ray caster in two levels: a BVH per distinct mesh, a top level over the instances (on the gpu backend: two-level GPU ray casting)",
    read: super::read_as::<super::NoOptions<TwoLevelMethod>>,
};

/// Its per-frame forms ([`Method::frame_forms`]): `two_level`, its top level rebuilt every
/// frame; on the GPU `two_level@gpu`.
pub const FRAME_FORMS: &[FrameForm] = &[
    FrameForm::cpu("two_level"),
    FrameForm::gpu("two_level@gpu", "two_level"),
];

/// The scene's casters in two levels.
#[derive(Default)]
pub struct TwoLevelMethod;

impl Method for TwoLevelMethod {
    fn frame_forms(&self) -> &'static [FrameForm] {
        FRAME_FORMS
    }

    fn mover(&self, _form: &str, on: &MoverInputs) -> Result<Box<dyn Mover>> {
        Ok(Box::new(TwoLevelRebuild {
            tracer: TwoLevel::new(&model_triangles(on.meshes)),
        }))
    }

    fn gpu_mover<'a>(
        &self,
        _form: &str,
        on: &MoverInputs,
        gpu: &GpuInputs<'a>,
    ) -> Result<GpuMover<'a>> {
        Ok(Ok(Box::new(GpuTwoLevelMover {
            quantity: gpu.kernels,
            caster: GpuTwoLevel::new(gpu.ctx, &model_triangles(on.meshes))?,
        })))
    }

    fn name(&self) -> &'static str {
        ENTRY.name
    }

    /// The kind's integrand on the GPU two levels, where the kind has GPU kernels (refused by
    /// the run, naming the kind, where it has none).
    fn refuses_on_gpu(&self, _kind: &dyn Kind) -> Option<String> {
        None
    }

    /// A BVH per distinct caster mesh, at the planner's bytes a triangle.
    fn precompute(&self, scene: &BuiltScene) -> std::result::Result<Option<Precompute>, String> {
        let (model, instances) = caster_instances(scene);
        let triangles: u64 = model.iter().map(|m| m.len() as u64).sum();
        let bytes = triangles.saturating_mul(crate::experiment::methods::BVH_BYTES_PER_TRIANGLE);
        Ok(Some(Precompute {
            what: format!(
                "build a BVH per mesh over {triangles} triangles of {} mesh(es), a top level over {} instance(s) (bytes: about)",
                model.len(),
                instances.len()
            ),
            rays: 0,
            bytes,
            peak_bytes: bytes,
        }))
    }

    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        let (model, instances) = caster_instances(ctx.scene);
        let mut tl = TwoLevel::new(&model);
        tl.update(&instances);
        Ok(Prepared {
            bytes: Some(tl.bytes()),
            cached: false,
            columns: Vec::new(),
            answer: Answer::Rays(Box::new(tl)),
            gpu: Some(Box::new(TwoLevelGpu { model, instances })),
        })
    }
}

/// What the GPU two levels upload: the meshes and the placements.
struct TwoLevelGpu {
    model: ModelTriangles,
    instances: Vec<(usize, Similarity)>,
}

impl GpuMethod for TwoLevelGpu {
    fn upload<'a>(
        &'a self,
        ctx: &'a GpuContext,
        quantity: Option<&'a dyn GpuQuantity>,
    ) -> Result<Box<dyn Eval + 'a>> {
        let quantity = integrand_of(ENTRY.name, quantity)?;
        let mut vis = GpuTwoLevel::new(ctx, &self.model)?;
        vis.update(&self.instances)?;
        Ok(TraceEval::boxed(vis.setup_time(), vis, quantity))
    }
}

/// Our ray caster in two levels: each mesh's BVH built once in model space (the crowd's
/// precompute), the top level over the instances rebuilt every frame.
pub struct TwoLevelRebuild {
    pub tracer: TwoLevel,
}

impl Mover for TwoLevelRebuild {
    fn name(&self) -> &'static str {
        "two_level"
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.tracer.update(frame.instances);
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        &self.tracer
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.tracer.bytes())
    }
}

/// Two-level ray casting on the GPU: each mesh's BVH uploaded once, the top level rebuilt and
/// uploaded every frame.
pub struct GpuTwoLevelMover<'a> {
    quantity: &'a dyn GpuQuantity,
    caster: GpuTwoLevel<'a>,
}

impl Mover for GpuTwoLevelMover<'_> {
    fn name(&self) -> &'static str {
        FRAME_FORMS[1].name
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        Ok(self.caster.update(frame.instances)?)
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.caster.bytes())
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(self.quantity.trace(&self.caster, at, rays)?.values)
    }
}
