//! The per-frame methods on the GPU (an animated spec with `"backends": ["cpu", "gpu"]`), each
//! charged for what a frame's motion costs it as the CPU's are ([`super::movers`]):
//!
//! - `world_rebuild@gpu`: the GPU ray caster (an obvhs CWBVH traversed in WGSL,
//!   [`GpuTracer`]) over the frame's world triangles, its BVH built on the host and uploaded
//!   every frame (`update_s`): one world BVH, no instance level, so a moving object costs a
//!   rebuild and an upload of the whole scene. Skipped, with the reason, on a scene whose
//!   world triangles pass one storage binding ([`world_fits`]).
//! - `two_level@gpu`: two-level ray casting on the GPU ([`GpuTwoLevel`], the twin of
//!   `two_level`): each mesh's CWBVH uploaded once before the frames, the top level over the
//!   instances' world boxes rebuilt on the host and uploaded every frame (`update_s`, which
//!   waits for the upload), rays moved into each instance's space on the device (`query_s`).
//! - `field_every_sphere@gpu`: the render kind's field kernel (Gaitatzes et al., WSCG 2010: field
//!   lookup on the GPU), its fields packed and uploaded once before the frames; per frame the
//!   instance records (transform and world bounding sphere) are rewritten on the device
//!   ([`Eval::place`], waiting for the upload: `update_s`) and nothing else moves. The kernel
//!   tests every instance's sphere per ray, the twin of `field_every_sphere`.
//! - `field@gpu`: the same kernel walking the instances' own top level, the BVH over their
//!   spheres (`FieldGpuOptions::top_level`, the GPU twin of `field`'s `field::sphere_bvh`),
//!   rebuilt on the host and uploaded with the records every frame (`update_s`): the same
//!   answers as testing every sphere, bit for bit.
//!
//! - `rayquery@gpu`: hardware ray queries ([`RayQueryScene`]), where the adapter offers them:
//!   a BLAS per mesh built once before the frames (as `two_level`'s per-mesh BVHs, its
//!   twin), the TLAS over the frame's instances rebuilt per frame and waited for (`update_s`),
//!   the kind's integrand on it apart (`query_s`). Skipped, saying why, on an adapter without
//!   ray queries.
//!
//! Their names and the CPU forms they run beside are the registry's
//! ([`crate::experiment::methods::motion::gpu_twins`]: each method's `frame_forms`, the field's
//! `FIELD_FORMS`); this file builds them. All answer the kind through its GPU kernels on the
//! CPU path's rays, so their values match
//! the CPU twins' within the kernels' parity bounds (the GPU path's tests).

use super::movers::{field_instances, FrameCasters, Mover};
use crate::experiment::backend::Eval;
use crate::experiment::backend_gpu::GpuQuantity;
use crate::experiment::Result;
use crate::field::normals::NormalField;
use crate::field::VisibilityField;
use crate::gpu::{GpuContext, GpuTracer, GpuTwoLevel, RayQueryScene};
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::visibility::Visibility;
use std::sync::Arc;

/// [`GpuRayQuery`]'s name.
pub const RAYQUERY: &str = crate::experiment::methods::rayquery::FRAME_FORMS[0].name;
/// Why [`GpuRayQuery`] is skipped on an adapter without ray queries (the run's output names
/// the adapter too).
pub const RAYQUERY_SKIPPED: &str = "the adapter offers no ray queries (wgpu \
    EXPERIMENTAL_RAY_QUERY: Mesa's lavapipe before 24.1, GPUs without ray-tracing units)";
/// [`GpuWorldRebuild`]'s name.
pub const WORLD_REBUILD: &str = crate::experiment::methods::raycast::FRAME_FORMS[1].name;
/// [`GpuTwoLevelMover`]'s name.
pub const TWO_LEVEL: &str = crate::experiment::methods::two_level::FRAME_FORMS[1].name;
/// [`GpuFields`]' name testing every sphere.
pub const FIELD_EVERY_SPHERE: &str = crate::experiment::methods::motion::FIELD_FORMS[1].name;
/// [`GpuFields`]' name with the instances' own top level.
pub const FIELD_TOP_LEVEL: &str = crate::experiment::methods::motion::FIELD_FORMS[3].name;

/// Why `world_rebuild@gpu` cannot run on a world of `triangles` triangles, if it cannot: its
/// triangles, three `vec4` each, pass one storage binding of the adapter (the GPU tracer would
/// refuse them with `GpuError::TooLarge`).
pub fn world_fits(ctx: &GpuContext, triangles: usize) -> std::result::Result<(), String> {
    let need = triangles as u64 * 48;
    if need > ctx.max_binding() {
        return Err(format!(
            "the world's {triangles} triangles need {need} bytes in one storage binding; the \
             adapter allows {} (two_level@gpu uploads each mesh once)",
            ctx.max_binding()
        ));
    }
    Ok(())
}

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
        &crate::experiment::backend::NoRays
    }

    fn bytes(&self) -> Option<u64> {
        None
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        let tracer = self.tracer.as_ref().expect("updated before the query");
        Ok(self.quantity.trace(tracer, at, rays)?.values)
    }
}

/// Two-level ray casting on the GPU: each mesh's BVH uploaded once, the top level rebuilt and
/// uploaded every frame.
pub struct GpuTwoLevelMover<'a> {
    quantity: &'a dyn GpuQuantity,
    caster: GpuTwoLevel<'a>,
}

impl<'a> GpuTwoLevelMover<'a> {
    /// Builds and uploads every mesh's CWBVH (model space) and compiles the integrands.
    pub fn new(
        ctx: &'a GpuContext,
        quantity: &'a dyn GpuQuantity,
        meshes: &[Arc<crate::geometry::Mesh>],
    ) -> Result<Self> {
        let model: Vec<Vec<[glam::Vec3; 3]>> = meshes
            .iter()
            .map(|m| {
                m.triangles
                    .iter()
                    .map(|t| t.map(|i| m.positions[i as usize]))
                    .collect()
            })
            .collect();
        Ok(GpuTwoLevelMover {
            quantity,
            caster: GpuTwoLevel::new(ctx, &model)?,
        })
    }
}

impl Mover for GpuTwoLevelMover<'_> {
    fn name(&self) -> &'static str {
        TWO_LEVEL
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        Ok(self.caster.update(frame.instances)?)
    }

    fn vis(&self) -> &dyn Visibility {
        &crate::experiment::backend::NoRays
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.caster.bytes())
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(self.quantity.trace(&self.caster, at, rays)?.values)
    }
}

/// The kind's field kernel over one field per mesh (shared by its instances), uploaded once;
/// per frame the instances are moved on the device (with the top level, its tree too).
pub struct GpuFields<'a> {
    name: &'static str,
    eval: Box<dyn Eval + 'a>,
    fields: Vec<Arc<VisibilityField>>,
    normals: Vec<Option<Arc<NormalField>>>,
}

impl<'a> GpuFields<'a> {
    /// `eval`: the kind's field kernel prepared on instances of `fields` (and `normals`), in
    /// the order every frame lists them; `name`: [`FIELD_EVERY_SPHERE`] or, for a kernel with
    /// the instances' own top level, [`FIELD_TOP_LEVEL`].
    pub fn new(
        name: &'static str,
        eval: Box<dyn Eval + 'a>,
        fields: Vec<Arc<VisibilityField>>,
        normals: Vec<Option<Arc<NormalField>>>,
    ) -> Self {
        GpuFields {
            name,
            eval,
            fields,
            normals,
        }
    }
}

impl Mover for GpuFields<'_> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.eval
            .place(&field_instances(&self.fields, &self.normals, frame))
    }

    fn vis(&self) -> &dyn Visibility {
        &crate::experiment::backend::NoRays
    }

    fn bytes(&self) -> Option<u64> {
        let normals: u64 = self.normals.iter().flatten().map(|n| n.bytes()).sum();
        Some(self.fields.iter().map(|f| f.bytes()).sum::<u64>() + normals)
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(self.eval.estimate(at, rays)?.values)
    }
}

/// Hardware ray queries over the frame's instances: a BLAS per mesh built once, the TLAS
/// rebuilt per frame.
pub struct GpuRayQuery<'a> {
    quantity: &'a dyn GpuQuantity,
    scene: RayQueryScene<'a>,
}

/// A frame's instances as (mesh, model-to-world matrix).
fn placements(frame: &FrameCasters) -> Vec<(usize, glam::Mat4)> {
    (frame.instances.iter())
        .map(|&(m, t)| (m, t.to_mat4()))
        .collect()
}

impl<'a> GpuRayQuery<'a> {
    /// Builds every mesh's BLAS and the TLAS of `first` (the first frame), before the frames.
    pub fn new(
        ctx: &'a GpuContext,
        quantity: &'a dyn GpuQuantity,
        first: &FrameCasters,
    ) -> Result<Self> {
        let meshes: Vec<Vec<[glam::Vec3; 3]>> = (first.meshes.iter())
            .map(|m| {
                (m.triangles.iter())
                    .map(|t| t.map(|i| m.positions[i as usize]))
                    .collect()
            })
            .collect();
        let scene = RayQueryScene::new(ctx, &meshes, &placements(first))?;
        Ok(GpuRayQuery { quantity, scene })
    }
}

impl Mover for GpuRayQuery<'_> {
    fn name(&self) -> &'static str {
        RAYQUERY
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        Ok(self.scene.place(&placements(frame))?)
    }

    fn vis(&self) -> &dyn Visibility {
        &crate::experiment::backend::NoRays
    }

    fn bytes(&self) -> Option<u64> {
        None
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(self.quantity.trace(&self.scene, at, rays)?.values)
    }
}
