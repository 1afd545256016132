//! The per-frame methods on the GPU (an animated spec with `"backends": ["cpu", "gpu"]`), each
//! charged for what a frame's motion costs it as the CPU's are ([`super::movers`]):
//!
//! - `world_rebuild@gpu`: the GPU ray caster (an obvhs CWBVH traversed in WGSL,
//!   [`GpuTracer`]) over the frame's world triangles, its BVH built on the host and uploaded
//!   every frame (`update_s`). The only scheme the GPU tracer has: it holds one world BVH, no
//!   instance level, so a moving object costs a rebuild and an upload of the whole scene.
//! - `field_every_sphere@gpu`: the render kind's field kernel (Gaitatzes et al., WSCG 2010: field
//!   lookup on the GPU), its fields packed and uploaded once before the frames; per frame the
//!   instance records (transform and world bounding sphere) are rewritten on the device
//!   ([`Eval::place`]) and nothing else moves. The kernel tests every instance's sphere per
//!   ray (no sphere BVH on the GPU), so it is the twin of `field_every_sphere`. The instance
//!   upload is queued by `update_s` and carried out by the next dispatch, inside `query_s`.
//!
//! Both answer the kind through its GPU kernels on the CPU path's rays, so their values match
//! the CPU twins' within the kernels' parity bounds (the GPU path's tests).

use super::movers::{field_instances, FrameCasters, Mover};
use crate::experiment::backend::Eval;
use crate::experiment::backend_gpu::GpuQuantity;
use crate::experiment::Result;
use crate::field::normals::NormalField;
use crate::field::VisibilityField;
use crate::gpu::{GpuContext, GpuTracer};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::visibility::Visibility;
use std::sync::Arc;

/// Each CPU per-frame method with a GPU twin, and the twin's name, in the order their rows are
/// written.
pub const TWINS: [(&str, &str); 2] = [
    ("world_rebuild", WORLD_REBUILD),
    ("field_every_sphere", FIELD_EVERY_SPHERE),
];
/// [`GpuWorldRebuild`]'s name.
pub const WORLD_REBUILD: &str = "world_rebuild@gpu";
/// [`GpuFields`]' name.
pub const FIELD_EVERY_SPHERE: &str = "field_every_sphere@gpu";

/// The GPU ray caster over the world triangles, its BVH built and uploaded every frame.
pub struct GpuWorldRebuild<'a> {
    ctx: &'a GpuContext,
    quantity: &'a dyn GpuQuantity,
    tracer: Option<GpuTracer<'a>>,
}

impl<'a> GpuWorldRebuild<'a> {
    pub fn new(ctx: &'a GpuContext, quantity: &'a dyn GpuQuantity) -> Self {
        GpuWorldRebuild {
            ctx,
            quantity,
            tracer: None,
        }
    }
}

impl Mover for GpuWorldRebuild<'_> {
    fn name(&self) -> &'static str {
        WORLD_REBUILD
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.tracer = None;
        self.tracer = Some(GpuTracer::new(self.ctx, &frame.world_triangles())?);
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        &crate::experiment::methods::NoRays
    }

    fn bytes(&self) -> Option<u64> {
        None
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        let tracer = self.tracer.as_ref().expect("updated before the query");
        Ok(self.quantity.trace(tracer, at, rays)?.values)
    }
}

/// The kind's field kernel over one field per mesh (shared by its instances), uploaded once;
/// per frame the instances are moved on the device.
pub struct GpuFields<'a> {
    eval: Box<dyn Eval + 'a>,
    fields: Vec<Arc<VisibilityField>>,
    normals: Vec<Option<Arc<NormalField>>>,
}

impl<'a> GpuFields<'a> {
    /// `eval`: the kind's field kernel prepared on instances of `fields` (and `normals`), in
    /// the order every frame lists them.
    pub fn new(
        eval: Box<dyn Eval + 'a>,
        fields: Vec<Arc<VisibilityField>>,
        normals: Vec<Option<Arc<NormalField>>>,
    ) -> Self {
        GpuFields {
            eval,
            fields,
            normals,
        }
    }
}

impl Mover for GpuFields<'_> {
    fn name(&self) -> &'static str {
        FIELD_EVERY_SPHERE
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.eval
            .place(&field_instances(&self.fields, &self.normals, frame))
    }

    fn vis(&self) -> &dyn Visibility {
        &crate::experiment::methods::NoRays
    }

    fn bytes(&self) -> Option<u64> {
        let normals: u64 = self.normals.iter().flatten().map(|n| n.bytes()).sum();
        Some(self.fields.iter().map(|f| f.bytes()).sum::<u64>() + normals)
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(self.eval.estimate(at, rays)?.values)
    }
}
