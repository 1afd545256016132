//! The ray-cast reference: an obvhs CWBVH over world-space triangles with watertight
//! ray–triangle tests (Woop, Benthin, Wald, "Watertight Ray/Triangle Intersection", JCGT 2013).

mod tracer;
pub mod watertight;

pub use tracer::{Hit, Tracer};
