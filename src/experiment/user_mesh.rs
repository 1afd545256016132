//! A user's mesh file named by a spec (`{"mesh": {"file": "PATH", "sha256": "…"}}`): the path
//! resolved against the spec file's folder, the sizes checked against the memory limit before
//! anything is loaded, the bytes hashed and checked against the pin, the mesh loaded with a
//! progress bar, and what `run.json` records of it ([`FileRecord`]: the name as given, never an
//! absolute path).
//!
//! The field cache keys on the loaded mesh's model-space positions and triangles
//! (`scenes::mesh_sha256`), not on the file: a renamed or moved file reuses its fields,
//! an edited one bakes again.

use super::spec::mesh::MeshFile;
use super::spec::{MeshSource, Spec, SpecError};
use crate::field::ByteSize;
use crate::geometry::{Mesh, MeshFormat};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What a run records of a mesh file (`run.json` `meshes`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct FileRecord {
    /// The path as the spec gives it.
    pub file: String,
    /// sha256 of the file's bytes.
    pub sha256: String,
    pub bytes: u64,
    /// Vertices and triangles of the loaded mesh (after dropping unused vertices and zero-area
    /// triangles).
    pub vertices: usize,
    pub triangles: usize,
}

/// Bytes a mesh of these sizes takes while it is loaded and traced: the file's bytes, the mesh
/// (positions and normals, 24 bytes a vertex; triangles, 12 bytes) three times (the parsed
/// parts, the validated mesh, its centred copy), and three BVHs over its triangles at 128 bytes
/// a triangle (the scene's two, as `plan::scene_state_bytes` counts them, and the
/// bake's). For the 10 M-triangle binary PLY of `examples/big_mesh.rs` this is 4.4 GiB; its
/// `experiment try --quick` peaked at 4.5 GiB resident (rays and images besides).
pub fn load_bytes(file_bytes: u64, vertices: u64, triangles: u64) -> u64 {
    let mesh = vertices
        .saturating_mul(24)
        .saturating_add(triangles.saturating_mul(12));
    file_bytes
        .saturating_add(mesh.saturating_mul(3))
        .saturating_add(triangles.saturating_mul(3 * 128))
}

/// The file `f` names, relative to the folder of `spec_file` unless absolute.
pub fn resolve(spec_file: &Path, f: &MeshFile) -> PathBuf {
    let p = Path::new(&f.file);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    spec_file
        .parent()
        .map_or_else(|| p.to_path_buf(), |d| d.join(p))
}

/// Checks every mesh file of `spec`'s scenes before any is loaded: it exists, its extension is
/// read, and its sizes (the PLY header, or the OBJ file's `v` and `f` lines) fit `memory_limit`.
/// Errors name the spec file, the field and the mesh file.
pub fn precheck(
    spec: &Spec,
    spec_file: &Path,
    path: &str,
    memory_limit: u64,
) -> Result<(), SpecError> {
    for (si, sc) in spec.scenes.iter().enumerate() {
        for (ii, inst) in sc.instances.iter().enumerate() {
            let MeshSource::File(f) = &inst.mesh else {
                continue;
            };
            let err = |message: String| SpecError::Invalid {
                file: spec_file.to_path_buf(),
                field: format!("{path}[{si}].instances[{ii}].mesh.file"),
                message,
            };
            let p = resolve(spec_file, f);
            let format = MeshFormat::of(&p).map_err(|e| err(e.to_string()))?;
            let meta = std::fs::metadata(&p).map_err(|e| err(format!("{}: {e}", p.display())))?;
            if !meta.is_file() {
                return Err(err(format!("{}: not a file", p.display())));
            }
            let c = format.counts(&p).map_err(|e| err(e.to_string()))?;
            let need = load_bytes(meta.len(), c.vertices, c.triangles);
            if need > memory_limit {
                return Err(err(format!(
                    "{}: {} bytes, {} vertices and {} triangles need about {} to load and trace \
                     (the file, the mesh three times, three BVHs at 128 bytes a triangle), over the \
                     memory limit of {} (--max-memory-mib)",
                    p.display(),
                    meta.len(),
                    c.vertices,
                    c.triangles,
                    ByteSize(need),
                    ByteSize(memory_limit)
                )));
            }
        }
    }
    Ok(())
}

/// Loads the mesh file `f` of a spec at `spec_file`: hashes its bytes, checks the pin, loads it
/// by extension under a progress bar. The error names the file (and both sums on a mismatch).
pub fn load(spec_file: &Path, f: &MeshFile) -> super::Result<(Mesh, FileRecord)> {
    let p = resolve(spec_file, f);
    let label = f.label();
    let (sha256, bytes) = sha256_file(&p).map_err(super::Error::io(&p))?;
    if let Some(pin) = &f.sha256 {
        if !pin.eq_ignore_ascii_case(&sha256) {
            return Err(super::Error::invalid(
                p.display().to_string(),
                format!("sha256 {sha256}, but the spec pins {pin} (the file changed?)"),
            ));
        }
    }
    let pb = super::progress::bar(bytes, &format!("load {label}"));
    let mesh = Mesh::load_file(&p, &|read| pb.set_position(read.min(bytes)));
    pb.finish_and_clear();
    let mesh = mesh.map_err(super::Error::geometry(label))?;
    let record = FileRecord {
        file: f.file.clone(),
        sha256,
        bytes,
        vertices: mesh.vertex_count(),
        triangles: mesh.triangle_count(),
    };
    Ok((mesh, record))
}

/// sha256 (lowercase hex) and length of a file's bytes, streamed.
pub use crate::io::sha256_file;
