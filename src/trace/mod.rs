//! The ray-cast reference: an obvhs CWBVH over world-space triangles with watertight
//! ray–triangle tests (Woop, Benthin, Wald, "Watertight Ray/Triangle Intersection", JCGT 2013).

mod tracer;
pub mod watertight;

#[cfg(test)]
pub(crate) mod test_scenes;

pub use tracer::{Hit, RayQuery, Tracer};
