//! Geometry: validated triangle meshes, procedural scenes, minimal bounding spheres and rigid
//! instances.
//!
//! Conventions: right-handed coordinates, y up (procedural scenes; loaded models keep their file
//! axes), lengths in model units. Triangles are wound counter-clockwise seen from the side their
//! normal `(b − a) × (c − a)` points to; closed procedural meshes are oriented outward. Vertex
//! normals are always area-weighted averages of face normals (see [`Mesh`]).
//!
//! - [`Mesh`]: validated indexed meshes, OBJ loading ([`Mesh::load_obj`]), PLY loading (ASCII
//!   and binary, [`Mesh::load_ply`]), either by extension ([`Mesh::load_file`], [`MeshFormat`]),
//!   area, volume, closedness.
//! - [`minimal_bounding_sphere`]: exact minimal enclosing spheres (Welzl).
//! - [`Similarity`], [`Instance`], [`Scene`]: meshes placed in the world with caster / receiver
//!   roles.
//! - [`motion`]: rigid paths of instances over the frames of an animation.
//! - [`rebase`]: scenes moved next to the origin in f64 before f32 world coordinates are formed.
//! - [`models`]: the registry of real meshes (`data/models.json`), found and sha256-checked.
//! - [`procedural`]: corner, plane, cube with a hole, UV sphere, supershapes, the default scene.

mod bounds;
mod instance;
mod mesh;
mod mesh_file;
pub mod models;
pub mod motion;
mod obj;
mod ply;
pub mod procedural;
pub mod rebase;

pub use bounds::{closest_point_on_triangle, minimal_bounding_sphere, Sphere};
pub use instance::{Instance, Scene, Similarity};
pub use mesh::{GeometryError, Mesh};
pub use mesh_file::{MeshFileCounts, MeshFormat};
