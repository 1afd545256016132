//! A user's mesh file: its format by extension, its sizes read cheaply before it is loaded (to
//! refuse what cannot fit a memory limit before any work), loading with progress, and what
//! every loader does to the parts it read ([`Mesh::from_file_parts`]).

use super::mesh::PartsError;
use super::{GeometryError, Mesh};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// The longest line an OBJ file may have: a line is held whole while it is parsed, so its
/// length bounds the memory a file without line ends takes before any size check.
pub const MAX_OBJ_LINE: usize = 1 << 20;

/// The error on OBJ line `line` (1-based) past [`MAX_OBJ_LINE`], from the size precheck and the
/// loader alike.
pub(crate) fn obj_line_too_long(line: u64) -> String {
    format!(
        "line {line}: longer than {MAX_OBJ_LINE} bytes (an OBJ line is a vertex, a face or a \
         statement: is this an OBJ file?)"
    )
}

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
                let io = GeometryError::io(path);
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

impl Mesh {
    /// A mesh from the positions and triangles a loader read from `path`, the positions
    /// already rebased on `origin` ([`super::rebase::centred_positions`]; kept in
    /// [`Mesh::origin`]): exact duplicate faces dropped (counted in
    /// [`Mesh::dropped_duplicate`]: N copies of one face change no visibility answer, but make
    /// a BVH's build and traversal quadratic), vertices used by no face dropped, then validated
    /// by [`Mesh::from_parts`]; named by the file name.
    pub(crate) fn from_file_parts(
        path: &Path,
        positions: Vec<Vec3>,
        origin: DVec3,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Mesh, PartsError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        let (triangles, duplicates) = drop_duplicate_faces(&positions, triangles);
        let (positions, triangles) = drop_unused(positions, triangles);
        let mut mesh = Mesh::try_from_parts(&name, positions, triangles)?;
        mesh.dropped_duplicate = duplicates;
        mesh.origin = origin;
        Ok(mesh)
    }
}

/// `triangles` without the exact duplicates of an earlier one (the same three corner
/// positions, compared bit for bit with −0 as 0, in the same cyclic order: a face and its
/// reverse are both kept, as their normals differ), in their order, and how many were dropped.
/// Triangles are grouped by a hash of their corners, sorted, so this takes O(n log n) time and
/// 16 bytes a triangle, whatever the input.
fn drop_duplicate_faces(positions: &[Vec3], triangles: Vec<[u32; 3]>) -> (Vec<[u32; 3]>, usize) {
    // Corner bits, rotated so that the smallest corner comes first (keeps the cyclic order).
    let key = |t: &[u32; 3]| -> [[u32; 3]; 3] {
        let c = t.map(|i| {
            positions.get(i as usize).map_or([u32::MAX; 3], |p| {
                (*p + Vec3::ZERO).to_array().map(f32::to_bits)
            })
        });
        let first = (0..3).min_by_key(|&k| c[k]).unwrap_or(0);
        [c[first], c[(first + 1) % 3], c[(first + 2) % 3]]
    };
    let hash = |t: &[u32; 3]| {
        use std::hash::{Hash, Hasher};
        let mut h = std::hash::DefaultHasher::new();
        key(t).hash(&mut h);
        h.finish()
    };
    let mut order: Vec<(u64, u32)> = triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| (hash(t), i as u32))
        .collect();
    order.par_sort_unstable();
    let mut keep = vec![true; triangles.len()];
    let mut kept_keys: Vec<[[u32; 3]; 3]> = Vec::new();
    for run in order.chunk_by(|a, b| a.0 == b.0) {
        // Within a run of equal hashes (in index order), keep the first of each key.
        kept_keys.clear();
        for &(_, i) in run {
            let k = key(&triangles[i as usize]);
            if kept_keys.contains(&k) {
                keep[i as usize] = false;
            } else {
                kept_keys.push(k);
            }
        }
    }
    let dropped = keep.iter().filter(|&&k| !k).count();
    if dropped == 0 {
        return (triangles, 0);
    }
    let kept = triangles
        .into_iter()
        .zip(&keep)
        .filter_map(|(t, &k)| k.then_some(t))
        .collect();
    (kept, dropped)
}

/// Keeps only the vertices some triangle uses, in their order, and renumbers the triangles
/// (an index out of range is left as it is, for validation to name).
fn drop_unused(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut map = vec![u32::MAX; positions.len()];
    for t in &triangles {
        for &i in t {
            if let Some(m) = map.get_mut(i as usize) {
                *m = 0;
            }
        }
    }
    let mut kept = Vec::new();
    for (i, m) in map.iter_mut().enumerate() {
        if *m == 0 {
            *m = kept.len() as u32;
            kept.push(positions[i]);
        }
    }
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|i| map.get(i as usize).copied().unwrap_or(i)))
        .collect();
    (kept, triangles)
}

fn obj_counts(path: &Path) -> Result<MeshFileCounts, GeometryError> {
    let io = GeometryError::io(path);
    let mut reader = BufReader::with_capacity(1 << 20, std::fs::File::open(path).map_err(io)?);
    let mut line = Vec::new();
    let (mut vertices, mut triangles) = (0u64, 0u64);
    for number in 1u64.. {
        line.clear();
        // At most one byte past the longest line held: a file without line ends is refused
        // after MAX_OBJ_LINE bytes, not read into memory whole.
        let n = (&mut reader)
            .take(MAX_OBJ_LINE as u64 + 1)
            .read_until(b'\n', &mut line)
            .map_err(io)?;
        if n == 0 {
            break;
        }
        if line.len() > MAX_OBJ_LINE && line.last() != Some(&b'\n') {
            return Err(GeometryError::invalid(
                path.display().to_string(),
                obj_line_too_long(number),
            ));
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
        // The pentagon's fan repeats the quad's two triangles: dropped as duplicates.
        assert_eq!((m.dropped_duplicate, m.dropped_degenerate), (2, 0));
        assert_eq!(m.triangle_count() + m.dropped_duplicate, 6);
    }
}
