//! `{"method": "embree"}`: Intel Embree 3 (`trace::embree::EmbreeTracer`, the `embree` cargo
//! feature) on the reference's rays: its scene built and committed as its precompute (timed),
//! then the kind's estimator through it. Its same-ray error against our ray caster is the two
//! casters' disagreement (contact and edge rays). A build without the feature skips the row,
//! saying why ([`Method::unavailable`]); `--require-embree` makes that an error.

#[cfg(feature = "embree")]
use super::Answer;
use super::{Method, MethodContext, MethodEntry, MethodOptions, Prepared};
use crate::experiment::spec::{Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::experiment::Result;
use serde::{Deserialize, Serialize};

pub const ENTRY: MethodEntry = MethodEntry {
    name: "embree",
    about: "Intel Embree 3 on the same rays (needs --features embree and libembree-dev)",
    read: super::read_as::<EmbreeOptions>,
};

/// `embree` has no parameters.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmbreeOptions {}

impl MethodOptions for EmbreeOptions {
    fn validate(&self, _at: &str, _spec: &Spec, _v: &Validator) -> Result<(), SpecError> {
        Ok(())
    }

    fn settings(&self) -> Vec<Box<dyn Method>> {
        vec![Box::new(Embree)]
    }
}

/// Embree's robust scene over the world triangles.
pub struct Embree;

impl Method for Embree {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    /// Embree's scene over every caster triangle, bounded as our BVH is.
    fn precompute(
        &self,
        scene: &crate::experiment::scenes::BuiltScene,
    ) -> std::result::Result<Option<super::Precompute>, String> {
        Ok(Some(super::raycast::world_bvh(scene)))
    }

    fn unavailable(&self) -> Option<String> {
        (!cfg!(feature = "embree")).then(|| {
            "this build has no Embree (build with --features embree; needs libembree-dev)".into()
        })
    }

    #[cfg(feature = "embree")]
    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        use crate::trace::embree::EmbreeTracer;
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
