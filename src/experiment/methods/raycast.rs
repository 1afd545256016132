//! `{"method": "raycast"}`: our ray caster (`trace::Tracer`, watertight triangles over an
//! obvhs CWBVH) charged for what it does per frame: the world-space BVH over every caster's
//! triangles is built as its precompute (timed), then the kind's estimator runs through it on
//! the reference's rays. Its values are the reference's, ray for ray (its same-ray errors are
//! zero by construction); the row is its cost with the BVH build counted, beside the others.

use super::{Answer, Method, MethodContext, MethodEntry, MethodOptions, Prepared};
use crate::experiment::spec::{Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::experiment::Result;
use crate::trace::Tracer;
use serde::{Deserialize, Serialize};

pub const ENTRY: MethodEntry = MethodEntry {
    name: "raycast",
    about: "our ray caster (watertight triangles, CWBVH), the world BVH built as its precompute",
    read: super::read_as::<RaycastOptions>,
};

/// `raycast` has no parameters.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RaycastOptions {}

impl MethodOptions for RaycastOptions {
    fn validate(&self, _at: &str, _spec: &Spec, _v: &Validator) -> Result<(), SpecError> {
        Ok(())
    }

    fn settings(&self) -> Vec<Box<dyn Method>> {
        vec![Box::new(Raycast)]
    }
}

/// Our tracer over the world triangles, rebuilt per prepare.
pub struct Raycast;

impl Method for Raycast {
    fn name(&self) -> &'static str {
        ENTRY.name
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
