//! Geometry: validated triangle meshes, procedural scenes, minimal bounding spheres and rigid
//! instances.

mod bounds;
mod instance;
mod mesh;
pub mod models;
pub mod procedural;

pub use bounds::{minimal_bounding_sphere, Sphere};
pub use instance::{Instance, Scene, Similarity};
pub use mesh::{GeometryError, Mesh};
