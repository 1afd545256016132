//! Wavefront OBJ loading (through `tobj`), with file and line in every error.

use super::mesh::PartsError;
use super::mesh_file::{obj_line_too_long, MAX_OBJ_LINE};
use super::rebase::centred_positions;
use super::{GeometryError, Mesh};
use glam::{DVec3, Vec3};
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

impl Mesh {
    /// Loads an OBJ file (all objects and groups merged, polygons fan-triangulated) and validates
    /// it with [`Mesh::from_parts`].
    ///
    /// - Only positions and faces are read: materials, texture coordinates and the file's normals
    ///   are ignored (normals are recomputed, area-weighted, see [`Mesh`]); `mtllib` files are
    ///   never opened.
    /// - Positions are read in f64 and rebased next to their origin before they are rounded to
    ///   f32 (`Mesh::from_file_parts`), then welded across objects/groups by exact coordinate
    ///   equality, so vertices shared between groups stay shared; vertices used by no face and
    ///   exact duplicate faces are not kept.
    /// - A line longer than `MAX_OBJ_LINE` is an error naming it, before it is held whole.
    /// - The mesh is named by the file name.
    ///
    /// Errors name the file: an unreadable file (I/O error), a parse error with the line where
    /// parsing stopped, a non-finite vertex with its line, an out-of-range face index, or no
    /// non-degenerate triangle.
    pub fn load_obj(path: &Path) -> Result<Mesh, GeometryError> {
        Mesh::load_obj_with(path, &|_| {})
    }

    /// [`Mesh::load_obj`], calling `progress` with the bytes read so far every few MiB.
    pub fn load_obj_with(path: &Path, progress: &dyn Fn(u64)) -> Result<Mesh, GeometryError> {
        let file = std::fs::File::open(path).map_err(GeometryError::io(path))?;
        let display = path.display().to_string();
        let mut reader = LineCountingReader::new(BufReader::with_capacity(1 << 16, file));
        reader.progress = Some(progress);
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ignore_points: true,
            ignore_lines: true,
        };
        let (models, _materials) =
            tobj::load_obj_buf(&mut reader, &options, |_| Ok(Default::default())).map_err(|e| {
                if reader.too_long {
                    // The line being read, not yet ended.
                    let line = reader.newlines as u64 + 1;
                    return GeometryError::invalid(&display, obj_line_too_long(line));
                }
                let line = reader.line_number();
                let what = match e {
                    // tobj reads lines as UTF-8 text: binary data stops it here.
                    tobj::LoadError::ReadError if !reader.io_error => {
                        "not text (binary data? an OBJ file is text)".to_string()
                    }
                    e => e.to_string(),
                };
                GeometryError::invalid(
                    &display,
                    format!("OBJ parse error at or before line {line}: {what}"),
                )
            })?;
        if reader.io_error {
            return Err(GeometryError::invalid(&display, "read error"));
        }

        // Every object's positions in one list (f64, as the file holds them) and its faces
        // renumbered into it; rebased, then welded on the f32 values the mesh will hold.
        let mut positions: Vec<DVec3> = Vec::new();
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        // By value: each object's f64 arrays are freed once copied.
        for model in models {
            let m = &model.mesh;
            let base = positions.len() as u64;
            positions.extend(
                m.positions
                    .chunks_exact(3)
                    .map(|c| DVec3::new(c[0], c[1], c[2])),
            );
            let local = positions.len() as u64 - base;
            for (f, t) in m.indices.chunks_exact(3).enumerate() {
                let map = |i: u32| match (i as u64) < local {
                    true => Ok((base + i as u64) as u32),
                    false => Err(GeometryError::invalid(
                        &display,
                        format!(
                            "object `{}` face {f}: vertex index out of range",
                            model.name
                        ),
                    )),
                };
                triangles.push([map(t[0])?, map(t[1])?, map(t[2])?]);
            }
        }
        let (positions, origin) = centred_positions(&positions);
        let (positions, triangles) = weld(positions, triangles);
        Mesh::from_file_parts(path, positions, origin, triangles).map_err(|e| match e {
            PartsError::NonFinite { position, .. } => {
                let place = match first_non_finite_vertex_line(path) {
                    Some((line, k)) => format!("line {line} (vertex {k}, 1-based as in OBJ)"),
                    None => "a vertex line".to_string(),
                };
                GeometryError::invalid(
                    &display,
                    format!("non-finite vertex coordinate {position} at {place}"),
                )
            }
            other => GeometryError::invalid(&display, other.to_string()),
        })
    }
}

/// Positions welded across objects/groups by exact equality (+0 and −0 alike), so that
/// vertices shared between groups stay shared, and the faces renumbered.
fn weld(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
    let mut kept = Vec::new();
    let map: Vec<u32> = positions
        .iter()
        .map(|&p| {
            // +0.0 folds −0.0 into 0.0; NaNs stay distinct per bit pattern (and are rejected
            // later anyway).
            let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
            *weld.entry(key).or_insert_with(|| {
                kept.push(p);
                (kept.len() - 1) as u32
            })
        })
        .collect();
    let triangles = triangles
        .into_iter()
        .map(|t| t.map(|i| map[i as usize]))
        .collect();
    (kept, triangles)
}

/// Scans the `v ` lines for the first one with a non-finite coordinate as the f32 a mesh holds
/// (a value finite in f64 but past f32's range too). Returns (line number, vertex number), both
/// 1-based.
fn first_non_finite_vertex_line(path: &Path) -> Option<(usize, usize)> {
    let file = std::fs::File::open(path).ok()?;
    let mut vertex = 0usize;
    for (i, line) in BufReader::new(file).lines().enumerate() {
        let line = line.ok()?;
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        vertex += 1;
        let bad = words
            .take(3)
            .any(|w| w.parse::<f32>().map(|x| !x.is_finite()).unwrap_or(true));
        if bad {
            return Some((i + 1, vertex));
        }
    }
    None
}

/// A `BufRead` that counts the newlines consumed, so that a parse error reported by `tobj` (which
/// reads line by line) can name the line it stopped at, and fails a line longer than
/// [`MAX_OBJ_LINE`] (`tobj` holds each line whole: without this, a file with no line end is
/// read into memory whole).
struct LineCountingReader<'p, R> {
    inner: R,
    newlines: usize,
    /// Bytes consumed since the last newline.
    line_len: usize,
    io_error: bool,
    /// The read failed on a line longer than [`MAX_OBJ_LINE`].
    too_long: bool,
    /// Bytes consumed, and the last count reported to `progress`.
    bytes: u64,
    reported: u64,
    progress: Option<&'p dyn Fn(u64)>,
}

impl<R: BufRead> LineCountingReader<'_, R> {
    fn new(inner: R) -> Self {
        LineCountingReader {
            inner,
            newlines: 0,
            line_len: 0,
            io_error: false,
            too_long: false,
            bytes: 0,
            reported: 0,
            progress: None,
        }
    }

    fn advance(&mut self, n: usize) {
        self.bytes += n as u64;
        if self.bytes - self.reported >= 4 << 20 {
            self.reported = self.bytes;
            if let Some(p) = self.progress {
                p(self.bytes);
            }
        }
    }

    /// 1-based number of the last line read (completely or partly).
    fn line_number(&self) -> usize {
        self.newlines.max(1)
    }

    /// Adds the newlines in `bytes`, consumed, to `newlines`, and sets `line_len` to the
    /// length of the line they end in (fields, not `self`: `consume` holds the inner buffer).
    fn count(newlines: &mut usize, line_len: &mut usize, bytes: &[u8]) {
        match bytes.iter().rposition(|&b| b == b'\n') {
            Some(last) => {
                *newlines += bytes.iter().filter(|&&b| b == b'\n').count();
                *line_len = bytes.len() - last - 1;
            }
            None => *line_len += bytes.len(),
        }
    }

    /// The error that stops a line past [`MAX_OBJ_LINE`].
    fn check_line(&mut self) -> std::io::Result<()> {
        if self.line_len > MAX_OBJ_LINE {
            self.too_long = true;
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("a line longer than {MAX_OBJ_LINE} bytes"),
            ));
        }
        Ok(())
    }
}

impl<R: BufRead> Read for LineCountingReader<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.check_line()?;
        let n = self.inner.read(buf).inspect_err(|_| self.io_error = true)?;
        Self::count(&mut self.newlines, &mut self.line_len, &buf[..n]);
        self.advance(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for LineCountingReader<'_, R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.check_line()?;
        self.inner.fill_buf().inspect_err(|_| self.io_error = true)
    }

    fn consume(&mut self, amt: usize) {
        if let Ok(b) = self.inner.fill_buf() {
            let n = amt.min(b.len());
            Self::count(&mut self.newlines, &mut self.line_len, &b[..n]);
        }
        self.advance(amt);
        self.inner.consume(amt);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn merges_groups_welds_shared_vertices_and_triangulates_quads() {
        let dir = tempfile::tempdir().unwrap();
        // Two groups sharing the edge 2–3: a quad (2 triangles) and a triangle.
        let p = write(
            dir.path(),
            "two.obj",
            "# test\nmtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\n\
             g a\nf 1 2 3 4\ng b\nf 4 3 5\n",
        );
        let m = Mesh::load_obj(&p).unwrap();
        assert_eq!(m.name, "two.obj");
        assert_eq!(m.triangle_count(), 3);
        assert_eq!(m.vertex_count(), 5, "shared vertices must be welded");
        // Area: unit square + triangle of base 1, height 1.
        assert!((m.area() - 1.5).abs() < 1e-6);
        for n in &m.normals {
            assert!(n.distance(Vec3::Z) < 1e-6);
        }
    }

    #[test]
    fn missing_file_names_the_path() {
        let e = Mesh::load_obj(Path::new("/nonexistent/dir/x.obj")).unwrap_err();
        assert!(matches!(e, GeometryError::Io { .. }));
        assert!(e.to_string().contains("/nonexistent/dir/x.obj"), "{e}");
    }

    /// Each bad file's error names the file and what is wrong with it.
    #[test]
    fn bad_files_are_errors_naming_file_and_fault() {
        let dir = tempfile::tempdir().unwrap();
        let cases: [(&str, &str, &[&str]); 7] = [
            // A parse error names its line.
            (
                "bad.obj",
                "v 0 0 0\nv 1 0 0\nv 0 oops 1\nf 1 2 3\n",
                &["line 3"],
            ),
            // A non-finite vertex names its line and its vertex number.
            (
                "nan.obj",
                "# header\nv 0 0 0\n\nv 1 0 0\nv 0 nan 1\nf 1 2 3\n",
                &["line 5", "vertex 3"],
            ),
            (
                "oob.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
                &["out of bounds"],
            ),
            (
                "flat.obj",
                "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
                &["no triangles"],
            ),
            // No faces, an empty file, a single point.
            (
                "nofaces.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
                &["no triangles left (0 given"],
            ),
            ("empty.obj", "", &["no triangles"]),
            (
                "point.obj",
                "v 1 2 3\nv 1 2 3\nv 1 2 3\nf 1 2 3\n",
                &["radius 0"],
            ),
        ];
        for (name, text, wants) in cases {
            let e = Mesh::load_obj(&write(dir.path(), name, text))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(name) && wants.iter().all(|w| e.contains(w)),
                "{e}"
            );
        }
    }

    /// A file cut short inside a vertex or face line is an error naming the file, never a mesh
    /// with a silently missing or half-read triangle.
    #[test]
    fn truncated_file_is_an_error_or_drops_nothing_silently() {
        let dir = tempfile::tempdir().unwrap();
        let whole = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n";
        let full = Mesh::load_obj(&write(dir.path(), "whole.obj", whole)).unwrap();
        assert_eq!(full.triangle_count(), 2);
        for cut in 1..whole.len() {
            let p = write(dir.path(), "cut.obj", &whole[..cut]);
            match Mesh::load_obj(&p) {
                Err(e) => {
                    let e = e.to_string();
                    assert!(e.contains("cut.obj"), "cut at {cut}: {e}");
                }
                // A cut that still parses keeps only whole faces over whole vertices.
                Ok(m) => {
                    assert!(m.triangle_count() <= 2, "cut at {cut}");
                    for t in 0..m.triangle_count() {
                        assert!(m.triangle(t).iter().all(|v| full.positions.contains(v)));
                    }
                }
            }
        }
    }
}
