//! `{"method": "embree"}`: Intel Embree 3 (`trace::embree::EmbreeTracer`, the `embree` cargo
//! feature) on the reference's rays: its scene built and committed as its precompute (timed),
//! then the kind's estimator through it. Its same-ray error against our ray caster is the two
//! casters' disagreement (contact and edge rays). A build without the feature skips the row,
//! saying why ([`Method::unavailable`]); `--require-embree` makes that an error.
//!
//! Every use of Embree in the harness goes through this file: the still method's scene, its
//! two per-frame forms in a moving scene (`EmbreeRebuild`, `embree_rebuild`: the scene over
//! the moved triangles built and committed every frame; `EmbreeInstanced`,
//! `embree_instances`: one scene per mesh built once, the instances' transforms set and the top
//! scene committed every frame), and `experiment performance`'s caster ([`world`]).

#[cfg(feature = "embree")]
use super::motion::{model_triangles, FrameCasters};
use super::motion::{FrameForm, Mover, MoverInputs};
#[cfg(feature = "embree")]
use super::Answer;
use super::{Method, MethodContext, MethodEntry, Prepared};
use crate::experiment::Result;
use crate::geometry::Mesh;
#[cfg(feature = "embree")]
use crate::trace::{embree::EmbreeTracer, embree_instances::EmbreeInstances};
use crate::visibility::Visibility;
use glam::Vec3;
use std::sync::Arc;

pub const ENTRY: MethodEntry = MethodEntry {
    name: "embree",
    about: "Intel Embree 3 on the same rays (needs --features embree and libembree-dev)",
    read: super::read_as::<super::NoOptions<Embree>>,
};

/// Its per-frame forms ([`Method::frame_forms`]): `embree_rebuild` and `embree_instances`; no
/// GPU form.
pub const FRAME_FORMS: &[FrameForm] = &[
    FrameForm::cpu("embree_rebuild"),
    FrameForm::cpu("embree_instances"),
];

/// Why a build without the `embree` feature skips the still method (its rows).
pub const NO_EMBREE: &str =
    "this build has no Embree (build with --features embree; needs libembree-dev)";
/// Why it skips the per-frame methods `embree_rebuild` and `embree_instances`.
pub const NO_EMBREE_FEATURE: &str =
    "this build lacks the `embree` feature (cargo build --features embree)";

/// Embree's scene over `triangles` (world space), built and committed, as `experiment
/// performance` times it beside our ray caster: none in a build without Embree, or Embree's
/// error.
pub fn world(
    triangles: &[[Vec3; 3]],
) -> Option<std::result::Result<Box<dyn Visibility + Send>, String>> {
    #[cfg(feature = "embree")]
    return Some(match EmbreeTracer::new(triangles) {
        Ok(t) => Ok(Box::new(t)),
        Err(e) => Err(e.to_string()),
    });
    #[cfg(not(feature = "embree"))]
    {
        let _ = triangles;
        None
    }
}

/// The per-frame form `form` over `meshes` (`embree_instances` with its per-mesh scenes
/// built); an error in a build without Embree.
fn mover(form: &str, meshes: &[Arc<Mesh>]) -> Result<Box<dyn Mover>> {
    #[cfg(feature = "embree")]
    return Ok(match form {
        "embree_instances" => Box::new(EmbreeInstanced::new(meshes)?),
        _ => Box::<EmbreeRebuild>::default(),
    });
    #[cfg(not(feature = "embree"))]
    {
        let _ = meshes;
        Err(crate::experiment::Error::invalid(
            format!("animation method {form}"),
            NO_EMBREE_FEATURE,
        ))
    }
}

/// Embree's robust scene over the world triangles.
#[derive(Default)]
pub struct Embree;

impl Method for Embree {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn frame_forms(&self) -> &'static [FrameForm] {
        FRAME_FORMS
    }

    fn mover(&self, form: &str, on: &MoverInputs) -> Result<Box<dyn Mover>> {
        mover(form, on.meshes)
    }

    fn frame_unavailable(&self) -> Option<&'static str> {
        (!cfg!(feature = "embree")).then_some(NO_EMBREE_FEATURE)
    }

    fn world_caster(
        &self,
        triangles: &[[Vec3; 3]],
    ) -> Option<std::result::Result<Box<dyn Visibility + Send>, String>> {
        world(triangles)
    }

    /// Embree's scene over every caster triangle, bounded as our BVH is.
    fn precompute(
        &self,
        scene: &crate::experiment::scenes::BuiltScene,
    ) -> std::result::Result<Option<super::Precompute>, String> {
        Ok(Some(super::raycast::world_bvh(scene)))
    }

    fn unavailable(&self) -> Option<String> {
        (!cfg!(feature = "embree")).then(|| NO_EMBREE.into())
    }

    #[cfg(feature = "embree")]
    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        let tracer = EmbreeTracer::new(ctx.triangles).map_err(|e| {
            crate::experiment::Error::invalid(
                format!("scene {}: method \"embree\"", ctx.scene.name),
                e.to_string(),
            )
        })?;
        Ok(Prepared {
            bytes: None,
            cached: false,
            columns: vec![("embree_version".into(), tracer.version())],
            answer: Answer::Rays(Box::new(tracer)),
            gpu: None,
        })
    }

    #[cfg(not(feature = "embree"))]
    fn prepare(&self, _ctx: &MethodContext) -> Result<Prepared> {
        Err(crate::experiment::Error::invalid(
            "method \"embree\"",
            self.unavailable().unwrap_or_default(),
        ))
    }
}

/// Embree's scene over the world triangles, built and committed every frame.
#[cfg(feature = "embree")]
#[derive(Default)]
pub struct EmbreeRebuild {
    tracer: Option<EmbreeTracer>,
}

#[cfg(feature = "embree")]
impl Mover for EmbreeRebuild {
    fn name(&self) -> &'static str {
        "embree_rebuild"
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        let t = EmbreeTracer::new(&frame.world_triangles()).map_err(|e| {
            crate::experiment::Error::invalid("dynamic: embree_rebuild", e.to_string())
        })?;
        self.tracer = Some(t);
        Ok(())
    }

    fn vis(&self) -> &dyn Visibility {
        self.tracer.as_ref().expect("updated before the query")
    }
}

/// Embree with instance geometries: each mesh's scene built once (the crowd's precompute), the
/// transforms set and the top scene committed every frame.
#[cfg(feature = "embree")]
pub struct EmbreeInstanced {
    pub tracer: EmbreeInstances,
}

#[cfg(feature = "embree")]
impl EmbreeInstanced {
    pub fn new(meshes: &[Arc<Mesh>]) -> Result<EmbreeInstanced> {
        let tracer = EmbreeInstances::new(&model_triangles(meshes)).map_err(|e| {
            crate::experiment::Error::invalid("dynamic: embree_instances", e.to_string())
        })?;
        Ok(EmbreeInstanced { tracer })
    }
}

#[cfg(feature = "embree")]
impl Mover for EmbreeInstanced {
    fn name(&self) -> &'static str {
        "embree_instances"
    }

    fn update(&mut self, frame: &FrameCasters) -> Result<()> {
        self.tracer.update(frame.instances).map_err(|e| {
            crate::experiment::Error::invalid("dynamic: embree_instances", e.to_string())
        })
    }

    fn vis(&self) -> &dyn Visibility {
        &self.tracer
    }
}
