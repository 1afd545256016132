//! A user's mesh file: its format by extension, its sizes read cheaply before it is loaded (to
//! refuse what cannot fit a memory limit before any work), and loading with progress.

use super::{GeometryError, Mesh};
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// The mesh file formats read, by extension (case-insensitive).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`), through [`Mesh::load_obj`].
    Obj,
    /// Stanford PLY (`.ply`), ASCII or binary, through [`Mesh::load_ply`].
    Ply,
}

/// The sizes of a mesh file, read without building the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshFileCounts {
    /// Vertices the file declares (OBJ: `v` lines; PLY: the `vertex` element's count).
    pub vertices: u64,
    /// Triangles after fan triangulation (OBJ: from every `f` line's corners), or, for a PLY
    /// file, its faces (a lower bound when some are polygons).
    pub triangles: u64,
}

impl MeshFormat {
    /// The extensions read, as the error on any other names them.
    pub const EXTENSIONS: &'static str = ".obj, .ply";

    /// The format of `path` by its extension, or the error naming the file, its extension and
    /// the extensions read.
    pub fn of(path: &Path) -> Result<MeshFormat, GeometryError> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("obj") => Ok(MeshFormat::Obj),
            Some("ply") => Ok(MeshFormat::Ply),
            other => Err(GeometryError::invalid(
                path.display().to_string(),
                format!(
                    "{}: the mesh formats read are {} (by extension)",
                    match other {
                        Some(e) => format!("extension `.{e}`"),
                        None => "no extension".to_string(),
                    },
                    Self::EXTENSIONS
                ),
            )),
        }
    }

    /// The file's sizes: the PLY header's counts, or one streaming pass over an OBJ file's
    /// `v` and `f` lines (far cheaper than parsing it).
    pub fn counts(self, path: &Path) -> Result<MeshFileCounts, GeometryError> {
        match self {
            MeshFormat::Ply => {
                let (vertices, triangles) = super::ply::ply_header_counts(path)?;
                Ok(MeshFileCounts {
                    vertices,
                    triangles,
                })
            }
            MeshFormat::Obj => obj_counts(path),
        }
    }
}

impl Mesh {
    /// Loads an OBJ or PLY file by its extension ([`MeshFormat::of`]), calling `progress` with
    /// the bytes read so far every few MiB.
    pub fn load_file(path: &Path, progress: &dyn Fn(u64)) -> Result<Mesh, GeometryError> {
        match MeshFormat::of(path)? {
            MeshFormat::Obj => Mesh::load_obj_with(path, progress),
            MeshFormat::Ply => {
                let io = |source| GeometryError::Io {
                    path: path.to_path_buf(),
                    source,
                };
                let mut file = std::fs::File::open(path).map_err(io)?;
                let mut bytes = Vec::new();
                let mut chunk = vec![0u8; 4 << 20];
                loop {
                    let n = file.read(&mut chunk).map_err(io)?;
                    if n == 0 {
                        break;
                    }
                    bytes.extend_from_slice(&chunk[..n]);
                    progress(bytes.len() as u64);
                }
                Mesh::ply_from_bytes(&bytes, path)
            }
        }
    }
}

fn obj_counts(path: &Path) -> Result<MeshFileCounts, GeometryError> {
    let io = |source| GeometryError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut reader = BufReader::with_capacity(1 << 20, std::fs::File::open(path).map_err(io)?);
    let mut line = Vec::new();
    let (mut vertices, mut triangles) = (0u64, 0u64);
    loop {
        line.clear();
        if reader.read_until(b'\n', &mut line).map_err(io)? == 0 {
            break;
        }
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => vertices += 1,
            Some(b"f") => triangles += (words.count() as u64).saturating_sub(2),
            _ => {}
        }
    }
    Ok(MeshFileCounts {
        vertices,
        triangles,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_by_extension_or_refused_naming_the_extensions_read() {
        assert_eq!(
            MeshFormat::of(Path::new("a/b.OBJ")).unwrap(),
            MeshFormat::Obj
        );
        assert_eq!(MeshFormat::of(Path::new("b.ply")).unwrap(), MeshFormat::Ply);
        let e = MeshFormat::of(Path::new("dir/mesh.stl"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("dir/mesh.stl") && e.contains("`.stl`") && e.contains(".obj, .ply"),
            "{e}"
        );
        let e = MeshFormat::of(Path::new("mesh")).unwrap_err().to_string();
        assert!(
            e.contains("no extension") && e.contains(".obj, .ply"),
            "{e}"
        );
    }

    #[test]
    fn obj_counts_are_the_v_lines_and_the_fan_triangles() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("q.obj");
        // 5 vertices, a quad (2 triangles), a pentagon (3) and a triangle (1); `vn` and `vt`
        // lines are not vertices.
        std::fs::write(
            &p,
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\nvn 0 0 1\nvt 0 0\n\
             f 1 2 3 4\nf 1 2 3 4 5\nf 4 3 5\n",
        )
        .unwrap();
        let c = MeshFormat::Obj.counts(&p).unwrap();
        assert_eq!((c.vertices, c.triangles), (5, 6));
        let m = Mesh::load_file(&p, &|_| {}).unwrap();
        assert_eq!(m.triangle_count() as u64 + m.dropped_degenerate as u64, 6);
    }
}
