//! The visibility field in a moving scene. The field is not a registered method: its cells are
//! the spec's `fields` axes (the papers', in `table.csv`). Its per-frame forms are given here,
//! by [`FIELD`], an unregistered [`Method`] that [`super::motion::frame_forms`] lists after the
//! registry's, so that animated specs and `experiment dynamic` build them as they build every
//! method's:
//!
//! - `field_every_sphere`: the casters' fields (one per mesh, baked once, shared by its
//!   instances) placed by the frame's transforms, every ray testing every caster's sphere
//!   (2008 Algorithm 2; `update_s` is making the instance list);
//! - `field`: the same with the BVH over the instances' bounding spheres
//!   ([`crate::field::sphere_bvh`]) rebuilt per frame (in `update_s`); the same answers;
//! - `field_every_sphere@gpu`: the render kind's field kernel (Gaitatzes et al., WSCG 2010:
//!   field lookup on the GPU), its fields packed and uploaded once before the frames; per frame
//!   the instance records (transform and world bounding sphere) are rewritten on the device
//!   ([`Eval::place`], waiting for the upload: `update_s`) and nothing else moves;
//! - `field@gpu`: the same kernel walking the instances' own top level, the BVH over their
//!   spheres (`FieldGpuOptions::top_level`), rebuilt on the host and uploaded with the records
//!   every frame: the same answers as testing every sphere, bit for bit.
//!
//! Each reads the field ([`FrameForm::reading_field`]): an animated spec builds it once per
//! field cell, over the cell's fields ([`MeshFields`]).

use super::motion::{FrameCasters, FrameForm, GpuInputs, GpuMover, Mover, MoverInputs};
use super::{Method, MethodContext, Prepared};
use crate::experiment::backend::Eval;
use crate::experiment::{Error, Result};
use crate::field::lookup::LookupOptions;
use crate::field::normals::NormalField;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::sphere_bvh::SphereBvhScene;
use crate::field::VisibilityField;
use crate::gpu::FieldGpuOptions;
use crate::render::estimator::{Estimator, Points};
use crate::sampling::rays::RaySet;
use crate::visibility::Visibility;
use std::sync::Arc;

/// The field's per-frame forms ([`Method::frame_forms`]), each with its GPU twin.
pub const FIELD_FORMS: &[FrameForm] = &[
    FrameForm::cpu("field_every_sphere").reading_field(),
    FrameForm::gpu("field_every_sphere@gpu", "field_every_sphere").reading_field(),
    FrameForm::cpu("field").reading_field(),
    FrameForm::gpu("field@gpu", "field").reading_field(),
];

/// The field among the methods that follow motion (unregistered: see the module docs).
pub const FIELD: FieldForms = FieldForms;

/// The field's per-frame forms as a [`Method`] ([`FIELD`]).
pub struct FieldForms;

/// One field per caster mesh (shared by its instances), with its normal field where the kind
/// reads them, and how they are looked up: a field cell's, or the crowd's.
#[derive(Clone)]
pub struct MeshFields {
    pub fields: Vec<Arc<VisibilityField>>,
    /// Per mesh, its normal field (reflections read them; empty or `None`: none).
    pub normals: Vec<Option<Arc<NormalField>>>,
    pub options: LookupOptions,
}

impl MeshFields {
    /// Each instance's field placed by its transform (`instances`: each (mesh, transform)).
    pub fn placed(&self, instances: &[(usize, crate::geometry::Similarity)]) -> FieldScene {
        let instances = (instances.iter())
            .map(|&(m, t)| {
                let f = FieldInstance::new(self.fields[m].clone(), t);
                match self.normals.get(m).cloned().flatten() {
                    Some(n) => f.with_normals(n),
                    None => f,
                }
            })
            .collect();
        FieldScene {
            instances,
            options: self.options,
        }
    }

    /// The fields' and normal fields' bytes.
    fn bytes(&self) -> u64 {
        let normals: u64 = self.normals.iter().flatten().map(|n| n.bytes()).sum();
        self.fields.iter().map(|f| f.bytes()).sum::<u64>() + normals
    }
}

/// The fields of `on`, which [`super::motion::movers`] gives a form that reads the field.
fn fields_of<'a>(on: &MoverInputs<'a>) -> &'a MeshFields {
    on.fields
        .expect("a form that reads the field is built with the fields")
}

impl Method for FieldForms {
    fn name(&self) -> &'static str {
        "field"
    }

    fn prepare(&self, _ctx: &MethodContext) -> Result<Prepared> {
        Err(Error::invalid(
            "method \"field\"",
            "the field is a spec's `fields` axes, not a `methods` entry",
        ))
    }

    fn frame_forms(&self) -> &'static [FrameForm] {
        FIELD_FORMS
    }

    fn mover(&self, form: &str, on: &MoverInputs) -> Result<Box<dyn Mover>> {
        Ok(Box::new(Fields {
            fields: fields_of(on).clone(),
            sphere_bvh: form == "field",
            plain: FieldScene::default(),
            tree: SphereBvhScene::default(),
        }))
    }

    fn gpu_mover<'a>(
        &self,
        form: &str,
        on: &MoverInputs,
        gpu: &GpuInputs<'a>,
    ) -> Result<GpuMover<'a>> {
        let (fields, name) = (fields_of(on), FIELD_FORMS.iter().find(|f| f.name == form));
        let name = name.expect("one of the field's forms").name;
        let opts = FieldGpuOptions {
            lookup: fields.options,
            top_level: name == "field@gpu",
            ..Default::default()
        };
        let eval = (gpu.kernels).fields(gpu.ctx, &fields.placed(gpu.first), &opts)?;
        Ok(Ok(Box::new(GpuFields {
            name,
            eval,
            fields: fields.clone(),
        })))
    }
}

/// The casters' fields placed by the frame's transforms; nothing is rebuilt but, with
/// `sphere_bvh`, the BVH over the instances' bounding spheres ([`SphereBvhScene`]; without it
/// every ray tests every sphere, as 2008 Algorithm 2).
pub struct Fields {
    pub fields: MeshFields,
    pub sphere_bvh: bool,
    /// The frame's scene: without the tree, or with it.
    plain: FieldScene,
    tree: SphereBvhScene,
}

impl Mover for Fields {
    fn name(&self) -> &'static str {
        if self.sphere_bvh {
            "field"
        } else {
            "field_every_sphere"
        }
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        let scene = self.fields.placed(frame.instances);
        if self.sphere_bvh {
            self.tree = SphereBvhScene::new(scene);
        } else {
            self.plain = scene;
        }
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        if self.sphere_bvh {
            &self.tree
        } else {
            &self.plain
        }
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.fields.bytes() + self.tree.bvh().bytes())
    }
}

/// The kind's field kernel over one field per mesh, uploaded once; per frame the instances are
/// moved on the device (with the top level, its tree too).
struct GpuFields<'a> {
    name: &'static str,
    eval: Box<dyn Eval + 'a>,
    fields: MeshFields,
}

impl Mover for GpuFields<'_> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.eval
            .place(&self.fields.placed(frame.instances).instances)
    }

    fn bytes(&self) -> Option<u64> {
        Some(self.fields.bytes())
    }

    fn estimate(&self, _: &dyn Estimator, at: Points, rays: &RaySet) -> Result<Vec<f32>> {
        Ok(self.eval.estimate(at, rays)?.values)
    }
}
