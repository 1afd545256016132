//! Validated triangle meshes.

use glam::Vec3;
use std::path::{Path, PathBuf};

/// Errors from loading or validating geometry. Each names the file (or mesh) and the place.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    #[error("{file}: {message}")]
    Invalid { file: String, message: String },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// An indexed triangle mesh in model space.
///
/// Invariants (checked by [`Mesh::from_parts`]): every coordinate finite, every index in range,
/// no zero-area triangle, at least one triangle; `normals.len() == positions.len()`, each unit
/// length (area-weighted vertex normals when the source has none).
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Name used in messages (file name or procedural scene name).
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Zero-area triangles dropped during validation.
    pub dropped_degenerate: usize,
}

impl Mesh {
    /// Validates and builds a mesh; computes area-weighted vertex normals.
    pub fn from_parts(
        name: &str,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Mesh, GeometryError> {
        let _ = (name, positions, triangles);
        todo!("geometry helper")
    }

    /// Loads an OBJ file (all groups merged, polygons triangulated) and validates it.
    pub fn load_obj(path: &Path) -> Result<Mesh, GeometryError> {
        let _ = path;
        todo!("geometry helper")
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
}
