//! Small test scenes as plain triangle lists: a dyadic grid, a disk fan, an icosphere with
//! shared vertices, a random soup, and seeded random directions. Shared by the `trace` and
//! `render` tests.

use crate::sampling::rays::uniform;
use glam::{Quat, Vec3};
use std::collections::HashMap;

/// An `n × n` grid of square cells of side `cell` in the plane z = 0, centred on the origin,
/// each cell split into two triangles, counter-clockwise seen from +z. The diagonal alternates
/// in a checkerboard, so vertices of valence 4 and 8 both occur. With a dyadic `cell` and even
/// `n` every vertex is exactly representable.
pub fn grid(n: u32, cell: f32) -> Vec<[Vec3; 3]> {
    let half = n as i32 / 2;
    let p = |i: u32, j: u32| {
        Vec3::new(
            (i as i32 - half) as f32 * cell,
            (j as i32 - half) as f32 * cell,
            0.0,
        )
    };
    let mut tris = Vec::with_capacity((2 * n * n) as usize);
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if (i + j) % 2 == 0 {
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            } else {
                tris.push([a, b, d]);
                tris.push([b, c, d]);
            }
        }
    }
    tris
}

/// Applies `f` to every vertex. Shared vertices stay shared (the same input gives the same
/// output), so a watertight mesh stays watertight.
pub fn map_vertices(tris: &[[Vec3; 3]], f: impl Fn(Vec3) -> Vec3) -> Vec<[Vec3; 3]> {
    tris.iter().map(|t| [f(t[0]), f(t[1]), f(t[2])]).collect()
}

/// A square of side 2·half in the plane z = h, as two triangles.
pub fn square(half: f32, h: f32) -> Vec<[Vec3; 3]> {
    let (a, b, c, d) = (
        Vec3::new(-half, -half, h),
        Vec3::new(half, -half, h),
        Vec3::new(half, half, h),
        Vec3::new(-half, half, h),
    );
    vec![[a, b, c], [a, c, d]]
}

/// A horizontal disk fan of `segments` triangles at height `h` around the z axis whose polygon
/// contains the disk of radius `r`: the rim vertices sit on the circumscribed circle
/// `r / cos(π/segments)`, so the polygon lies between radii `r` and `r / cos(π/segments)`.
pub fn disk_fan(r: f32, h: f32, segments: u32) -> Vec<[Vec3; 3]> {
    let r_vertex = r / (std::f32::consts::PI / segments as f32).cos();
    let centre = Vec3::new(0.0, 0.0, h);
    let rim = |k: u32| {
        let phi = std::f32::consts::TAU * (k % segments) as f32 / segments as f32;
        Vec3::new(r_vertex * phi.cos(), r_vertex * phi.sin(), h)
    };
    (0..segments)
        .map(|k| [centre, rim(k), rim(k + 1)])
        .collect()
}

/// An icosphere of radius `radius` around `centre`: the icosahedron subdivided `subdivisions`
/// times (20·4^s triangles), outward counter-clockwise. Edge midpoints are cached, so the mesh
/// is closed with exactly shared vertices.
pub fn icosphere(subdivisions: u32, radius: f32, centre: Vec3) -> Vec<[Vec3; 3]> {
    let phi = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        (-1.0, phi, 0.0),
        (1.0, phi, 0.0),
        (-1.0, -phi, 0.0),
        (1.0, -phi, 0.0),
        (0.0, -1.0, phi),
        (0.0, 1.0, phi),
        (0.0, -1.0, -phi),
        (0.0, 1.0, -phi),
        (phi, 0.0, -1.0),
        (phi, 0.0, 1.0),
        (-phi, 0.0, -1.0),
        (-phi, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut cache: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, verts: &mut Vec<Vec3>| {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push(((verts[a as usize] + verts[b as usize]) * 0.5).normalize());
                verts.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = mid(a, b, &mut verts);
            let bc = mid(b, c, &mut verts);
            let ca = mid(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    faces
        .iter()
        .map(|f| f.map(|i| centre + radius * verts[i as usize]))
        .collect()
}

/// A seeded uniform point in the cube `[-1, 1]³`.
pub fn random_point(index: u32, seed: u64) -> Vec3 {
    Vec3::new(
        2.0 * uniform(index, 0, 0, seed) - 1.0,
        2.0 * uniform(index, 0, 1, seed) - 1.0,
        2.0 * uniform(index, 0, 2, seed) - 1.0,
    )
}

/// A seeded uniform unit direction.
pub fn random_unit(index: u32, seed: u64) -> Vec3 {
    let z = 2.0 * uniform(index, 1, 0, seed) - 1.0;
    let phi = std::f32::consts::TAU * uniform(index, 1, 1, seed);
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// `n` seeded random triangles with vertices `centre + size·(random offsets)`, centres in
/// `[-1, 1]³`.
pub fn random_soup(n: u32, size: f32, seed: u64) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|i| {
            let c = random_point(i, seed);
            [0u64, 1, 2].map(|k| c + size * random_point(i, seed ^ (0x1234_5678 + k)))
        })
        .collect()
}

/// `n` triangles on which a PLOC build takes quadratic time, by name: copies of one triangle,
/// triangles scaled about one centroid, distinct triangles in one box, a row of equal triangles
/// equally spaced, a disk fan, a triangle turned by steps of 10⁻⁵ rad about one corner. All lie
/// in `z = 0` and cover `(0.2, 0.2)` (the row and the fan with one triangle each).
pub fn ploc_worst_cases(n: usize) -> Vec<(&'static str, Vec<[Vec3; 3]>)> {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let c = (tri[0] + tri[1] + tri[2]) / 3.0;
    vec![
        ("copies of one triangle", vec![tri; n]),
        (
            "triangles scaled about one centroid",
            (0..n)
                .map(|k| tri.map(|v| c + (v - c) * (1.0 + k as f32 * 1e-3)))
                .collect(),
        ),
        (
            "distinct triangles in one box",
            (0..n)
                .map(|k| {
                    let x = k as f32 / n as f32;
                    [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::new(x, 1.0, 0.0)]
                })
                .collect(),
        ),
        (
            "a row of equal triangles",
            (0..n)
                .map(|k| tri.map(|v| v + Vec3::X * (2 * k) as f32))
                .collect(),
        ),
        ("a disk fan", disk_fan(1.0, 0.0, n as u32)),
        (
            "a triangle turned about one corner",
            (0..n)
                .map(|k| tri.map(|v| Quat::from_rotation_z(k as f32 * 1e-5) * v))
                .collect(),
        ),
    ]
}

/// Where a test ray passes: through a mesh vertex or through the interior of an edge.
#[derive(Clone, Copy, Debug)]
pub enum Feature {
    Vertex,
    Edge,
}

impl Feature {
    /// Triangles of the checkerboard grid incident to the feature: at most 8 around a vertex,
    /// exactly 2 along an interior edge.
    pub fn max_hits(self) -> usize {
        match self {
            Feature::Vertex => 8,
            Feature::Edge => 2,
        }
    }
}

/// Test rays through grid features, in grid-local coordinates (before any transform): target
/// point, direction (dyadic, so `p - 2·d` is exact) and feature kind. Directions come from both
/// sides of the grid plane, steep and grazing, and exactly along ±z.
pub fn feature_rays(n: u32, cell: f32, count: u32) -> Vec<(Vec3, Vec3, Feature)> {
    let half = (n / 2) as f32;
    let u = |i: u32, dim: u32| crate::sampling::rays::uniform(i, 7, dim, 99);
    let vertex =
        |i: u32, j: u32| Vec3::new((i as f32 - half) * cell, (j as f32 - half) * cell, 0.0);
    let mut rays = Vec::new();
    for k in 0..count {
        // An interior vertex.
        let (i, j) = (
            1 + (u(k, 0) * (n - 1) as f32) as u32,
            1 + (u(k, 1) * (n - 1) as f32) as u32,
        );
        // A dyadic fraction f in (0, 1) along an edge.
        let f = (1 + (u(k, 2) * 1023.0) as u32) as f32 / 1024.0;
        let (p, feature) = match k % 4 {
            0 => (vertex(i, j), Feature::Vertex),
            // Horizontal and vertical interior edges.
            1 => (vertex(i - 1, j) + Vec3::X * f * cell, Feature::Edge),
            2 => (vertex(i, j - 1) + Vec3::Y * f * cell, Feature::Edge),
            // The diagonal of cell (i-1, j-1), whichever way the checkerboard cuts it.
            _ => {
                let (ci, cj) = (i - 1, j - 1);
                if (ci + cj) % 2 == 0 {
                    (vertex(ci, cj) + Vec3::new(f, f, 0.0) * cell, Feature::Edge)
                } else {
                    (
                        vertex(ci + 1, cj) + Vec3::new(-f, f, 0.0) * cell,
                        Feature::Edge,
                    )
                }
            }
        };
        let side = if k % 8 < 4 { 1.0 } else { -1.0 };
        let dz = [1.0, 0.5, 1.0 / 16.0, 1.0][(k / 8 % 4) as usize];
        let (dx, dy) = if k / 8 % 4 == 3 {
            (0.0, 0.0) // exactly along ∓z: kz = z and zero shear
        } else {
            (
                ((u(k, 3) * 7.0) as i32 - 3) as f32 / 4.0,
                ((u(k, 4) * 7.0) as i32 - 3) as f32 / 4.0,
            )
        };
        rays.push((p, Vec3::new(dx, dy, -side * dz), feature));
    }
    rays
}
