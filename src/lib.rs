//! visfield: a research harness for presampled visibility.
//!
//! It reproduces and measures three papers:
//! - Gaitatzes, Chrysanthou, Papaioannou, "Presampled Visibility for Ambient Occlusion",
//!   WSCG 2008 (CPU visibility / "displacement" fields),
//! - Gaitatzes, Andreadis, Papaioannou, Chrysanthou, "Fast Approximate Visibility on the GPU using
//!   Precomputed 4D Visibility Fields", WSCG 2010,
//! - Kolb, Rezk-Salama, "Efficient Empty Space Skipping for Per-Pixel Displacement Mapping",
//!   VMV 2005.
//!
//! Module map (one concept each):
//! - [`geometry`]: meshes, procedural scenes, bounding spheres, rigid instances.
//! - [`sampling`]: sphere point sets, hemisphere layouts, frames, seeded ray sets.
//! - [`trace`]: the ray-cast reference (obvhs CWBVH + watertight triangles).
//! - [`field`]: visibility fields: bake, storage, lookup, cache.
//! - [`aofield`]: ambient occlusion fields (Kontkanen & Laine 2005), a per-object peer.
//! - [`visibility`]: the `Visibility` seam that ray casting and field lookup implement.
//! - [`render`]: the AO / shadow / reflection renderers, written against `Visibility`.
//! - [`gpu`]: headless wgpu paths.
//! - [`relief`]: the 2005 height-field ray caster and its safety-zone skipping.
//! - [`experiment`]: specs, planner, runner, metrics, outputs.
//!
//! Conventions (see README): right-handed coordinates, y up for procedural scenes; distances in
//! model units; field distances normalised by 2R; AO in [0, 1] (1 = unoccluded), reported on the
//! 0–255 scale for RMS.

pub mod aofield;
pub mod experiment;
pub mod field;
pub mod geometry;
pub mod gpu;
mod hint;
pub mod io;
pub mod relief;
pub mod render;
pub mod sampling;
pub mod sdf;
pub mod simd;
pub mod trace;
pub mod visibility;
