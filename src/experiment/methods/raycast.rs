//! `{"method": "raycast"}`: our ray caster (`trace::Tracer`, watertight triangles over an
//! obvhs CWBVH) charged for what it does per frame: the world-space BVH over every caster's
//! triangles is built as its precompute (timed), then the kind's estimator runs through it on
//! the reference's rays. Its values are the reference's, ray for ray (its same-ray errors are
//! zero by construction); the row is its cost with the BVH build counted, beside the others.
//! In a moving scene it follows motion by rebuilding that BVH every frame ([`WorldRebuild`],
//! `world_rebuild`, the reference of the other per-frame methods); on the GPU
//! (`world_rebuild@gpu`, [`GpuWorldRebuild`]) the GPU ray caster (an obvhs CWBVH traversed in
//! WGSL, [`GpuTracer`]) over the frame's world triangles, its BVH built on the host and
//! uploaded every frame (`update_s`): one world BVH, no instance level, so a moving object
//! costs a rebuild and an upload of the whole scene. Skipped, with the reason, on a scene whose
//! world triangles pass one storage binding.

use super::motion::{FrameCasters, FrameForm, GpuInputs, GpuMover, Mover, MoverInputs};
use super::{Answer, Method, MethodContext, MethodEntry, Precompute, Prepared};
use crate::experiment::backend_gpu::GpuQuantity;
use crate::experiment::scenes::BuiltScene;
use crate::experiment::Result;
use crate::gpu::{GpuContext, GpuTracer};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::trace::Tracer;
use crate::visibility::Visibility;
use glam::Vec3;

pub const ENTRY: MethodEntry = MethodEntry {
    name: "raycast",
    about: "our ray caster (watertight triangles, CWBVH), the world BVH built as its precompute",
    read: super::read_as::<super::NoOptions<Raycast>>,
};

/// Its per-frame forms ([`Method::frame_forms`]): `world_rebuild`, the world BVH rebuilt every
/// frame, the moving scene's reference; on the GPU `world_rebuild@gpu`.
pub const FRAME_FORMS: &[FrameForm] = &[
    FrameForm::cpu("world_rebuild"),
    FrameForm::gpu("world_rebuild@gpu", "world_rebuild"),
];

/// Our tracer over the world triangles, rebuilt per prepare.
#[derive(Default)]
pub struct Raycast;

impl Method for Raycast {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    /// The world BVH over every caster triangle, at the planner's bytes a triangle.
    fn precompute(&self, scene: &BuiltScene) -> std::result::Result<Option<Precompute>, String> {
        Ok(Some(world_bvh(scene)))
    }

    fn frame_forms(&self) -> &'static [FrameForm] {
        FRAME_FORMS
    }

    fn mover(&self, _form: &str, _on: &MoverInputs) -> Result<Box<dyn Mover>> {
        Ok(Box::<WorldRebuild>::default())
    }

    /// Where the world's triangles, three `vec4` each, fit one storage binding of the adapter
    /// (the GPU tracer would refuse them, `GpuError::TooLarge`); skipped otherwise.
    fn gpu_mover<'a>(
        &self,
        _form: &str,
        on: &MoverInputs,
        gpu: &GpuInputs<'a>,
    ) -> Result<GpuMover<'a>> {
        let triangles: usize = (gpu.first.iter())
            .map(|&(m, _)| on.meshes[m].triangle_count())
            .sum();
        let need = triangles as u64 * 48;
        if need > gpu.ctx.max_binding() {
            return Ok(Err(format!(
                "the world's {triangles} triangles need {need} bytes in one storage binding; \
                 the adapter allows {} (two_level@gpu uploads each mesh once)",
                gpu.ctx.max_binding()
            )));
        }
        Ok(Ok(Box::new(GpuWorldRebuild {
            ctx: gpu.ctx,
            quantity: gpu.kernels,
            tracer: None,
        })))
    }

    fn world_caster(
        &self,
        triangles: &[[Vec3; 3]],
    ) -> Option<std::result::Result<Box<dyn Visibility + Send>, String>> {
        Some(Ok(Box::new(Tracer::new(triangles))))
    }

    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        let tracer = Tracer::new(ctx.triangles);
        Ok(Prepared {
            bytes: Some(tracer.bytes()),
            cached: false,
            columns: Vec::new(),
            answer: Answer::Rays(Box::new(tracer)),
            gpu: None,
        })
    }
}

/// A world BVH over every caster triangle of `scene` (ours or Embree's) as a precompute: no
/// ray, about [`crate::experiment::methods::BVH_BYTES_PER_TRIANGLE`] a triangle (the planner's
/// bound, the triangles included).
pub fn world_bvh(scene: &BuiltScene) -> Precompute {
    let triangles = scene.caster_triangles() as u64;
    let bytes = triangles.saturating_mul(crate::experiment::methods::BVH_BYTES_PER_TRIANGLE);
    Precompute {
        what: format!("build a world BVH over {triangles} caster triangles (bytes: about)"),
        rays: 0,
        bytes,
        peak_bytes: bytes,
    }
}

/// Our ray caster over the world triangles, its BVH rebuilt every frame.
#[derive(Default)]
pub struct WorldRebuild {
    tracer: Option<Tracer>,
}

impl Mover for WorldRebuild {
    fn name(&self) -> &'static str {
        "world_rebuild"
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.tracer = Some(Tracer::new(&frame.world_triangles()));
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        self.tracer.as_ref().expect("updated before the query")
    }

    fn bytes(&self) -> Option<u64> {
        self.tracer.as_ref().map(Tracer::bytes)
    }
}

/// The GPU ray caster over the world triangles, its BVH built and uploaded every frame.
pub struct GpuWorldRebuild<'a> {
    ctx: &'a GpuContext,
    quantity: &'a dyn GpuQuantity,
    tracer: Option<GpuTracer<'a>>,
}

impl Mover for GpuWorldRebuild<'_> {
    fn name(&self) -> &'static str {
        FRAME_FORMS[1].name
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.tracer = None;
        self.tracer = Some(GpuTracer::new(self.ctx, &frame.world_triangles())?);
        Ok(())
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        let tracer = self.tracer.as_ref().expect("updated before the query");
        Ok(self.quantity.trace(tracer, at, rays)?.values)
    }
}
