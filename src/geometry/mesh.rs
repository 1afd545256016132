//! Validated triangle meshes.

use super::{minimal_bounding_sphere, Similarity, Sphere};
use glam::{DVec3, Vec3};
use std::collections::HashMap;
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

impl GeometryError {
    pub(crate) fn invalid(file: impl Into<String>, message: impl Into<String>) -> GeometryError {
        GeometryError::Invalid {
            file: file.into(),
            message: message.into(),
        }
    }

    /// The error of reading `path` that failed with `source`, for `map_err`.
    pub(crate) fn io(path: &Path) -> impl Fn(std::io::Error) -> GeometryError + Copy + '_ {
        move |source| GeometryError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Problems found by [`Mesh::from_parts`], kept structured so that a loader can add the source
/// line of a bad vertex before turning it into a [`GeometryError`].
#[derive(Debug, thiserror::Error)]
pub(crate) enum PartsError {
    #[error("vertex {vertex} has a non-finite coordinate {position}")]
    NonFinite { vertex: usize, position: Vec3 },
    #[error("triangle {triangle} has vertex index {index} out of range")]
    IndexOutOfRange { triangle: usize, index: u32 },
    #[error("no triangles left ({given} given, {dropped} dropped as zero-area)")]
    NoTriangles { given: usize, dropped: usize },
    #[error("vertex {vertex} at {position} is outside ±{MAX_COORDINATE:e} (rescale the model)")]
    OutOfBounds { vertex: usize, position: Vec3 },
    #[error("every vertex is the same point {position}: the bounding sphere has radius 0")]
    SinglePoint { position: Vec3 },
    #[error("the vertices span {extent:e}, below {MIN_EXTENT:e} (rescale the model)")]
    TooSmall { extent: f64 },
}

/// Largest coordinate magnitude a mesh may have: squared distances stay far inside f32
/// (1e30 ≪ 3.4e38), so f32 geometry (bounds, frames, lookups) cannot overflow.
pub const MAX_COORDINATE: f32 = 1e15;

/// Smallest extent (bounding-box diagonal) a mesh may have: squared distances stay normal f32
/// numbers (1e-30 ≫ 1.2e-38), so ray offsets and normalisations do not underflow.
pub const MIN_EXTENT: f64 = 1e-15;

/// An indexed triangle mesh in model space.
///
/// Invariants (checked by [`Mesh::from_parts`]): every coordinate finite, every index in range,
/// no zero-area triangle, at least one triangle; `normals.len() == positions.len()`, each unit
/// length.
///
/// Normals are always the area-weighted vertex normals computed from the triangles (the sum of
/// the unnormalised face normals `(b − a) × (c − a)` of the incident triangles, normalised), also
/// for OBJ files that carry their own normals, so that every source is shaded the same way. A
/// vertex whose sum cancels takes the unit normal of its largest incident triangle; a vertex used
/// by no triangle gets +Y (the up axis).
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Name used in messages (file name or procedural scene name).
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Zero-area triangles dropped during validation.
    pub dropped_degenerate: usize,
    /// Faces of a mesh file dropped as exact duplicates of another (the same corners in the
    /// same cyclic order: `Mesh::from_file_parts`); 0 for meshes built otherwise.
    pub dropped_duplicate: usize,
    /// Where the positions were moved from: the model's own coordinates are `origin +
    /// position` (in f64). Zero unless the mesh was centred ([`super::rebase::centred_mesh`],
    /// or a file far from its origin, rebased as it was read).
    pub origin: DVec3,
}

impl Mesh {
    /// Validates and builds a mesh; computes area-weighted vertex normals.
    ///
    /// Errors (naming the mesh): a non-finite coordinate (with the vertex index), a coordinate
    /// beyond ±`MAX_COORDINATE`, every vertex at one point (a zero-radius bounding sphere),
    /// vertices spanning less than `MIN_EXTENT`, an index out of range (with the triangle
    /// index), or no triangle left after dropping zero-area ones. A
    /// triangle is zero-area when `|e1 × e2| <= 1e-12 · (|e1|² + |e2|²)` (computed in f64), which
    /// also catches repeated indices and collinear corners.
    pub fn from_parts(
        name: &str,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Mesh, GeometryError> {
        Mesh::try_from_parts(name, positions, triangles)
            .map_err(|e| GeometryError::invalid(name, e.to_string()))
    }

    pub(crate) fn try_from_parts(
        name: &str,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Mesh, PartsError> {
        if let Some((vertex, &position)) =
            positions.iter().enumerate().find(|(_, p)| !p.is_finite())
        {
            return Err(PartsError::NonFinite { vertex, position });
        }
        if let Some((vertex, &position)) = positions
            .iter()
            .enumerate()
            .find(|(_, p)| p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(PartsError::OutOfBounds { vertex, position });
        }
        if let Some(&first) = positions.first() {
            let (lo, hi) = positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            let extent = (hi.as_dvec3() - lo.as_dvec3()).length();
            if extent == 0.0 {
                return Err(PartsError::SinglePoint { position: first });
            }
            if extent < MIN_EXTENT {
                return Err(PartsError::TooSmall { extent });
            }
        }
        let n = positions.len();
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(PartsError::IndexOutOfRange { triangle: t, index });
            }
        }
        let given = triangles.len();
        let mut kept = Vec::with_capacity(given);
        let mut face_normals = Vec::with_capacity(given);
        for tri in triangles {
            let [a, b, c] = tri.map(|i| positions[i as usize].as_dvec3());
            let (e1, e2) = (b - a, c - a);
            let cross = e1.cross(e2);
            if cross.length() <= 1e-12 * (e1.length_squared() + e2.length_squared()) {
                continue;
            }
            kept.push(tri);
            face_normals.push(cross);
        }
        let dropped = given - kept.len();
        if kept.is_empty() {
            return Err(PartsError::NoTriangles { given, dropped });
        }
        let normals = area_weighted_normals(n, &kept, &face_normals);
        Ok(Mesh {
            name: name.to_string(),
            positions,
            normals,
            triangles: kept,
            dropped_degenerate: dropped,
            dropped_duplicate: 0,
            origin: DVec3::ZERO,
        })
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i].map(|v| self.positions[v as usize])
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Unnormalised normal `(b − a) × (c − a)` of triangle `i` in f64 (length = twice its area).
    pub fn face_normal_f64(&self, i: usize) -> DVec3 {
        let [a, b, c] = self.triangle(i).map(|p| p.as_dvec3());
        (b - a).cross(c - a)
    }

    /// Total surface area (f64 sum).
    pub fn area(&self) -> f64 {
        (0..self.triangle_count())
            .map(|i| 0.5 * self.face_normal_f64(i).length())
            .sum()
    }

    /// Signed enclosed volume by the divergence theorem, `Σ a · (b × c) / 6`: the volume for a
    /// closed, outward-oriented mesh, negative when oriented inward, meaningless when open.
    pub fn signed_volume(&self) -> f64 {
        (0..self.triangle_count())
            .map(|i| {
                let [a, b, c] = self.triangle(i).map(|p| p.as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// The minimal bounding sphere of all positions (recomputed on each call: expected linear
    /// time).
    pub fn bounding_sphere(&self) -> Sphere {
        minimal_bounding_sphere(&self.positions)
    }

    /// Every undirected edge is shared by exactly two triangles (a closed 2-manifold edge
    /// structure, the condition for a well-defined inside).
    pub fn is_closed(&self) -> bool {
        let mut count: HashMap<(u32, u32), u32> = HashMap::new();
        for e in self.directed_edges() {
            *count.entry((e.0.min(e.1), e.0.max(e.1))).or_insert(0) += 1;
        }
        count.values().all(|&c| c == 2)
    }

    /// Every directed edge occurs once and its reverse occurs too: adjacent triangles agree on
    /// orientation and there is no boundary.
    pub fn is_consistently_oriented(&self) -> bool {
        let mut seen: HashMap<(u32, u32), u32> = HashMap::new();
        for e in self.directed_edges() {
            *seen.entry(e).or_insert(0) += 1;
        }
        seen.iter()
            .all(|(&(a, b), &c)| c == 1 && seen.get(&(b, a)) == Some(&1))
    }

    fn directed_edges(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
    }

    /// A copy placed by `t`: positions mapped to world space, normals rotated (a similarity keeps
    /// them unit and perpendicular).
    pub fn transformed(&self, t: &Similarity) -> Mesh {
        Mesh {
            name: self.name.clone(),
            positions: self
                .positions
                .iter()
                .map(|&p| t.to_world_point(p))
                .collect(),
            normals: self.normals.iter().map(|&n| t.to_world_dir(n)).collect(),
            triangles: self.triangles.clone(),
            dropped_degenerate: self.dropped_degenerate,
            dropped_duplicate: self.dropped_duplicate,
            // World positions: the model's coordinates are no longer a shift away.
            origin: DVec3::ZERO,
        }
    }
}

/// Sum of incident unnormalised face normals, normalised; see [`Mesh`] for the fallbacks.
fn area_weighted_normals(n: usize, triangles: &[[u32; 3]], face: &[DVec3]) -> Vec<Vec3> {
    let mut sum = vec![DVec3::ZERO; n];
    let mut largest = vec![DVec3::ZERO; n];
    for (tri, &f) in triangles.iter().zip(face) {
        for &v in tri {
            let v = v as usize;
            sum[v] += f;
            if f.length_squared() > largest[v].length_squared() {
                largest[v] = f;
            }
        }
    }
    sum.iter()
        .zip(&largest)
        .map(|(s, l)| {
            s.try_normalize()
                .filter(|_| s.length() > 1e-9 * l.length())
                .or_else(|| l.try_normalize())
                .unwrap_or(DVec3::Y)
                .as_vec3()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        // Unit square in the y = 0 plane, both triangles facing +y.
        let p = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        (p, vec![[0, 1, 2], [0, 2, 3]])
    }

    /// The error [`Mesh::from_parts`] refuses these parts with.
    fn refusal(name: &str, p: Vec<Vec3>, t: Vec<[u32; 3]>) -> String {
        Mesh::from_parts(name, p, t).unwrap_err().to_string()
    }

    #[test]
    fn builds_normals_and_area() {
        let (p, t) = quad();
        let m = Mesh::from_parts("quad", p, t).unwrap();
        assert_eq!(m.triangle_count(), 2);
        assert_eq!(m.dropped_degenerate, 0);
        assert!((m.area() - 1.0).abs() < 1e-12);
        for n in &m.normals {
            assert!(n.distance(Vec3::Y) < 1e-6, "{n}");
        }
        assert!(!m.is_closed());
    }

    #[test]
    fn area_weighting_favours_the_larger_face() {
        // Vertex 0 is shared by a unit right triangle facing +y (area ½) and a right triangle
        // facing +x with legs 2 and 1 (area 1): normal ∝ ½·(0,1,0)·2 + 1·(1,0,0)·2 → (2, 1, 0)/√5.
        let p = vec![
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ];
        let m = Mesh::from_parts("two", p, vec![[0, 1, 2], [0, 3, 1]]).unwrap();
        let expected = Vec3::new(2.0, 1.0, 0.0).normalize();
        assert!(m.normals[0].distance(expected) < 1e-6, "{}", m.normals[0]);
    }

    #[test]
    fn rejects_non_finite_naming_mesh_and_vertex() {
        let (mut p, t) = quad();
        p[2].y = f32::NAN;
        let e = refusal("bad-quad", p, t);
        assert!(e.contains("bad-quad") && e.contains("vertex 2"), "{e}");
        let (mut p, t) = quad();
        p[3].x = f32::INFINITY;
        let e = refusal("m", p, t);
        assert!(e.contains("vertex 3"), "{e}");
    }

    #[test]
    fn rejects_out_of_range_index_naming_triangle() {
        let (p, mut t) = quad();
        t[1][2] = 4;
        let e = refusal("m", p, t);
        assert!(e.contains("triangle 1") && e.contains("index 4"), "{e}");
    }

    #[test]
    fn drops_degenerate_triangles_and_counts_them() {
        let (mut p, mut t) = quad();
        p.push(Vec3::new(2.0, 0.0, 0.0)); // collinear with 0 and 3
        t.push([0, 3, 4]); // collinear corners
        t.push([1, 1, 2]); // repeated index
        let m = Mesh::from_parts("m", p, t).unwrap();
        assert_eq!(m.triangle_count(), 2);
        assert_eq!(m.dropped_degenerate, 2);
        // Vertex 4 is unused now: it gets the documented +Y.
        assert_eq!(m.normals[4], Vec3::Y);
        let line = vec![Vec3::ZERO, Vec3::X, 2.0 * Vec3::X];
        let e = refusal("flat", line, vec![[0, 1, 2]]);
        assert!(e.contains("flat") && e.contains("no triangles"), "{e}");
    }

    #[test]
    fn rejects_empty_single_point_and_out_of_range_scales() {
        let e = refusal("empty", vec![], vec![]);
        assert!(
            e.contains("empty") && e.contains("no triangles left (0 given"),
            "{e}"
        );
        let (p, _) = quad();
        let e = refusal("no-faces", p, vec![]);
        assert!(
            e.contains("no-faces") && e.contains("no triangles left (0 given"),
            "{e}"
        );
        // A single point, alone or repeated: a zero-radius bounding sphere.
        for p in [vec![Vec3::ONE], vec![Vec3::ONE; 3]] {
            let e = refusal("point", p, vec![[0, 0, 0]]);
            assert!(e.contains("point") && e.contains("radius 0"), "{e}");
        }
        let (mut p, t) = quad();
        p[1].z = -2e15;
        let e = refusal("huge", p, t);
        assert!(e.contains("vertex 1") && e.contains("outside ±1e15"), "{e}");
        let (p, t) = quad();
        let p = p.into_iter().map(|v| v * 1e-20).collect();
        let e = refusal("tiny", p, t);
        assert!(e.contains("tiny") && e.contains("below 1e-15"), "{e}");
        // Small and large but representable scales are fine.
        for s in [1e-12f32, 1e12] {
            let (p, t) = quad();
            let m = Mesh::from_parts("ok", p.into_iter().map(|v| v * s).collect(), t).unwrap();
            assert!(m.bounding_sphere().radius > 0.0);
        }
    }

    #[test]
    fn tetrahedron_is_closed_oriented_with_volume() {
        // Corners 0, x, y, z: volume 1/6; area 3·½ + √3/2.
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let m = Mesh::from_parts("tet", p, t).unwrap();
        assert!(m.is_closed() && m.is_consistently_oriented());
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-12);
        assert!((m.area() - (1.5 + 3f64.sqrt() / 2.0)).abs() < 1e-9);
        // Flipping one triangle keeps it closed but breaks orientation.
        let mut flipped = m.clone();
        flipped.triangles[0].swap(1, 2);
        assert!(flipped.is_closed() && !flipped.is_consistently_oriented());
        // Removing one leaves it open.
        let mut open = m.clone();
        open.triangles.pop();
        assert!(!open.is_closed());
    }

    #[test]
    fn transformed_scales_area_and_rotates_normals() {
        let (p, t) = quad();
        let m = Mesh::from_parts("quad", p, t).unwrap();
        let s = Similarity {
            rotation: glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            translation: Vec3::new(1.0, 2.0, 3.0),
            scale: 3.0,
        };
        let w = m.transformed(&s);
        // Area scales by s² = 9; +y rotated by +90° about x is +z.
        assert!((w.area() - 9.0).abs() < 1e-5);
        for n in &w.normals {
            assert!(n.distance(Vec3::Z) < 1e-6, "{n}");
        }
    }
}
