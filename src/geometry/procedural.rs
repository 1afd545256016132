//! Procedural scenes built in code: corner, cube with a hole, supershape, sphere, plane.
//!
//! Conventions: right-handed, y up, model units; every closed mesh is oriented outward
//! (counter-clockwise seen from outside, so `(b − a) × (c − a)` points out). Builders return
//! `Err` naming the builder and parameter for invalid parameters.

mod supershape;

pub use supershape::{supershape, supershape_grid, Superformula, Supershape};

use super::{GeometryError, Instance, Mesh, Scene, Similarity};
use glam::{DVec3, Quat, Vec3};
use std::sync::Arc;

/// The receiver of the 2008 paper (Gaitatzes, Chrysanthou, Papaioannou, "Presampled Visibility
/// for Ambient Occlusion", WSCG 2008, Figure 6: "the tessellated corner (3x33x33)"): three
/// orthogonal unit squares meeting at the origin, the floor y = 0 and the walls x = 0 and z = 0,
/// each spanning [0, 1] in its two free coordinates.
///
/// Each face is an `n × n` vertex grid; vertices are not shared between faces (so each face keeps
/// its own normal along the shared edges): `3·n²` vertices, `6·(n − 1)²` triangles, area 3.
/// Normals point into the open octant: +y (floor), +x (wall x = 0), +z (wall z = 0).
pub fn corner(n: usize) -> Result<Mesh, GeometryError> {
    let name = format!("corner({n})");
    check_grid(&name, "n", n)?;
    let mut b = Builder::default();
    // du × dv is the face normal.
    b.grid(Vec3::ZERO, Vec3::Z, Vec3::X, n); // floor, Z × X = +Y
    b.grid(Vec3::ZERO, Vec3::Y, Vec3::Z, n); // wall x = 0, Y × Z = +X
    b.grid(Vec3::ZERO, Vec3::X, Vec3::Y, n); // wall z = 0, X × Y = +Z
    b.finish(&name)
}

/// A `size × size` square in the y = 0 plane centred at the origin, facing +y, as an `n × n`
/// vertex grid (`n²` vertices, `2·(n − 1)²` triangles).
pub fn plane(size: f32, n: usize) -> Result<Mesh, GeometryError> {
    let name = format!("plane({size}, {n})");
    check_grid(&name, "n", n)?;
    check_positive(&name, "size", size)?;
    let mut b = Builder::default();
    let h = 0.5 * size;
    b.grid(Vec3::new(-h, 0.0, -h), size * Vec3::Z, size * Vec3::X, n);
    b.finish(&name)
}

/// A closed cube of side `size` centred at the origin with a square through-hole of side `hole`
/// along the y axis (a genus-1 solid), outward oriented. 16 vertices, 32 triangles: the top and
/// bottom are square annuli of four trapezoids, the outer sides and the tunnel walls one quad
/// each, all sharing vertices so that every edge borders exactly two triangles.
///
/// Area `6s² − 2h² + 4sh`, volume `s³ − h²s`.
pub fn cube_with_hole(size: f32, hole: f32) -> Result<Mesh, GeometryError> {
    let name = format!("cube_with_hole({size}, {hole})");
    check_positive(&name, "size", size)?;
    check_positive(&name, "hole", hole)?;
    if hole >= size {
        return Err(GeometryError::invalid(
            &name,
            format!("hole ({hole}) must be smaller than size ({size})"),
        ));
    }
    let (s, h) = (0.5 * size, 0.5 * hole);
    // Square corners in xz in cyclic order; `quad_facing` sets each quad's winding from its
    // outward normal.
    let ring = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let mut b = Builder::default();
    let mut corners = |half: f32, y: f32| -> [u32; 4] {
        ring.map(|(x, z)| b.vertex(Vec3::new(x * half, y, z * half)))
    };
    let (outer_top, outer_bot) = (corners(s, s), corners(s, -s));
    let (inner_top, inner_bot) = (corners(h, s), corners(h, -s));
    for k in 0..4 {
        let k1 = (k + 1) % 4;
        let side = Vec3::new(ring[k].0 + ring[k1].0, 0.0, ring[k].1 + ring[k1].1).normalize();
        // Top and bottom annulus trapezoids.
        b.quad_facing(
            [outer_top[k], outer_top[k1], inner_top[k1], inner_top[k]],
            Vec3::Y,
        );
        b.quad_facing(
            [outer_bot[k], outer_bot[k1], inner_bot[k1], inner_bot[k]],
            -Vec3::Y,
        );
        // Outer side faces out, tunnel wall faces the axis.
        b.quad_facing(
            [outer_bot[k], outer_bot[k1], outer_top[k1], outer_top[k]],
            side,
        );
        b.quad_facing(
            [inner_bot[k], inner_bot[k1], inner_top[k1], inner_top[k]],
            -side,
        );
    }
    b.finish(&name)
}

/// A closed lat-long sphere of `radius` about the origin with `stacks ≥ 2` latitude bands and
/// `slices ≥ 3` longitudes (pole fans): `slices·(stacks − 1) + 2` vertices,
/// `2·slices·(stacks − 1)` triangles, all vertices on the sphere, outward oriented.
pub fn uv_sphere(radius: f32, stacks: usize, slices: usize) -> Result<Mesh, GeometryError> {
    let name = format!("uv_sphere({radius}, {stacks}, {slices})");
    check_positive(&name, "radius", radius)?;
    scaled_sphere(&name, DVec3::splat(f64::from(radius)), stacks, slices)
}

/// A closed lat-long ellipsoid about the origin with semi-axes `radii` (x, y, z), tessellated as
/// [`uv_sphere`] (the unit sphere's lat-long grid scaled per axis: the same counts, outward
/// oriented). With radii (10, 1, 1) it is the long thin caster of the 2010 paper's stated
/// limitation (§6, elongated models).
pub fn ellipsoid(radii: Vec3, stacks: usize, slices: usize) -> Result<Mesh, GeometryError> {
    let name = format!(
        "ellipsoid({}, {}, {}; {stacks}, {slices})",
        radii.x, radii.y, radii.z
    );
    for (field, r) in [
        ("radii.x", radii.x),
        ("radii.y", radii.y),
        ("radii.z", radii.z),
    ] {
        check_positive(&name, field, r)?;
    }
    scaled_sphere(&name, radii.as_dvec3(), stacks, slices)
}

/// The unit sphere's lat-long grid ([`latlong`]) scaled by `r` per axis, after checking
/// `stacks ≥ 2` and `slices ≥ 3`: [`uv_sphere`] and [`ellipsoid`].
fn scaled_sphere(
    name: &str,
    r: DVec3,
    stacks: usize,
    slices: usize,
) -> Result<Mesh, GeometryError> {
    if stacks < 2 || slices < 3 {
        return Err(GeometryError::invalid(
            name,
            format!("need stacks >= 2 and slices >= 3, got {stacks} and {slices}"),
        ));
    }
    latlong(name, slices, stacks, |theta, phi| {
        (r * DVec3::new(phi.cos() * theta.cos(), phi.sin(), phi.cos() * theta.sin())).as_vec3()
    })
}

/// The embedded default scene (the quickstart's, needing no files): the default [`Supershape`]
/// (10,000 triangles) as a caster floating inside the [`corner`] receiver (n = 33), scaled so
/// that its minimal bounding sphere has radius 0.35 and centred at (0.5, 0.45, 0.5), slightly
/// tilted. The sphere stays clear of the corner's three planes, so the caster's field is valid
/// everywhere on the receiver.
pub fn default_scene() -> Scene {
    let shape = supershape(&Supershape::default(), 10_000).expect("default supershape is valid");
    over_corner(shape, Quat::from_euler(glam::EulerRot::YXZ, 0.4, 0.25, 0.0))
}

/// The 2008 paper's test layout: `caster` (any mesh) rotated by `rotation`, scaled so that its
/// minimal bounding sphere has radius 0.35 and centred at (0.5, 0.45, 0.5), above the [`corner`]
/// receiver (n = 33). The caster's sphere stays clear of the corner's planes.
pub fn over_corner(caster: Mesh, rotation: Quat) -> Scene {
    let corner = corner(33).expect("corner(33) is valid");
    let sphere = caster.bounding_sphere();
    let scale = 0.35 / sphere.radius;
    let transform = Similarity::new(
        rotation,
        Vec3::new(0.5, 0.45, 0.5) - scale * (rotation * sphere.center),
        scale,
    );
    Scene {
        instances: vec![
            Instance {
                mesh: Arc::new(corner),
                transform: Similarity::default(),
                caster: false,
                receiver: true,
            },
            Instance {
                mesh: Arc::new(caster),
                transform,
                caster: true,
                receiver: false,
            },
        ],
    }
}

/// A closed lat-long surface `point(θ, φ)` over θ ∈ [−π, π) (`slices` steps, wrapping) and
/// φ ∈ [−π/2, π/2] (`stacks` bands; the two poles are single vertices closed by triangle fans).
/// Outward oriented when `point` is an orientation-preserving deformation of the unit sphere
/// `(cos φ cos θ, sin φ, cos φ sin θ)`.
fn latlong(
    name: &str,
    slices: usize,
    stacks: usize,
    point: impl Fn(f64, f64) -> Vec3,
) -> Result<Mesh, GeometryError> {
    use std::f64::consts::{FRAC_PI_2, PI};
    let mut b = Builder::default();
    let theta = |i: usize| -PI + 2.0 * PI * i as f64 / slices as f64;
    let south = b.vertex(point(0.0, -FRAC_PI_2));
    let rings: Vec<Vec<u32>> = (1..stacks)
        .map(|j| {
            let phi = -FRAC_PI_2 + PI * j as f64 / stacks as f64;
            (0..slices)
                .map(|i| b.vertex(point(theta(i), phi)))
                .collect()
        })
        .collect();
    let north = b.vertex(point(0.0, FRAC_PI_2));
    // With a = (i, j), b = (i+1, j), c = (i+1, j+1), d = (i, j+1), the triangles (a, d, c) and
    // (a, c, b) have normal ∝ ∂p/∂φ × ∂p/∂θ, outward for the sphere.
    for i in 0..slices {
        let i1 = (i + 1) % slices;
        b.triangle([south, rings[0][i], rings[0][i1]]);
        for j in 0..rings.len() - 1 {
            let (lo, hi) = (&rings[j], &rings[j + 1]);
            b.triangle([lo[i], hi[i], hi[i1]]);
            b.triangle([lo[i], hi[i1], lo[i1]]);
        }
        let top = &rings[rings.len() - 1];
        b.triangle([top[i], north, top[i1]]);
    }
    b.finish(name)
}

fn check_grid(name: &str, field: &str, n: usize) -> Result<(), GeometryError> {
    if n < 2 {
        return Err(GeometryError::invalid(
            name,
            format!("{field} must be at least 2 (vertices per side), got {n}"),
        ));
    }
    Ok(())
}

fn check_positive(name: &str, field: &str, x: f32) -> Result<(), GeometryError> {
    if !(x.is_finite() && x > 0.0) {
        return Err(GeometryError::invalid(
            name,
            format!("{field} must be finite and positive, got {x}"),
        ));
    }
    Ok(())
}

/// Accumulates vertices and triangles.
#[derive(Default)]
struct Builder {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    fn vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    fn triangle(&mut self, t: [u32; 3]) {
        self.triangles.push(t);
    }

    /// An `n × n` grid `origin + (i·du + j·dv)/(n − 1)`, triangles facing `du × dv`.
    fn grid(&mut self, origin: Vec3, du: Vec3, dv: Vec3, n: usize) {
        let base = self.positions.len() as u32;
        let step = 1.0 / (n - 1) as f32;
        for j in 0..n {
            for i in 0..n {
                self.vertex(origin + (i as f32 * step) * du + (j as f32 * step) * dv);
            }
        }
        let at = |i: usize, j: usize| base + (j * n + i) as u32;
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                // (a, b, c) with b − a ∝ du and c − a ∝ du + dv: normal ∝ du × dv.
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                self.triangle([a, b, c]);
                self.triangle([a, c, d]);
            }
        }
    }

    /// A planar quad given by its corners in cyclic order, split along a–c, wound so that its
    /// normal points along `outward`.
    fn quad_facing(&mut self, q: [u32; 4], outward: Vec3) {
        let p = q.map(|i| self.positions[i as usize]);
        let [a, b, c, d] = if (p[1] - p[0]).cross(p[2] - p[0]).dot(outward) >= 0.0 {
            q
        } else {
            [q[0], q[3], q[2], q[1]]
        };
        self.triangle([a, b, c]);
        self.triangle([a, c, d]);
    }

    fn finish(self, name: &str) -> Result<Mesh, GeometryError> {
        Mesh::from_parts(name, self.positions, self.triangles)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_matches_the_paper_tessellation() {
        let m = corner(33).unwrap();
        // 3 faces × 33² vertices, 3 × 2 × 32² triangles (the paper's 3x33x33).
        assert_eq!(m.vertex_count(), 3267);
        assert_eq!(m.triangle_count(), 6144);
        assert!((m.area() - 3.0).abs() < 1e-9);
        assert!(!m.is_closed());
        // Each third of the vertices lies on its plane with that plane's normal.
        for (k, axis) in [Vec3::Y, Vec3::X, Vec3::Z].into_iter().enumerate() {
            for v in k * 1089..(k + 1) * 1089 {
                assert_eq!(m.positions[v].dot(axis), 0.0);
                assert!(m.normals[v].distance(axis) < 1e-6);
                assert!(
                    m.positions[v].cmpge(Vec3::ZERO).all() && m.positions[v].cmple(Vec3::ONE).all()
                );
            }
        }
        // All vertices lie in [0,1]³ and include the antipodal pair (1,0,1), (0,1,0) of the unit
        // cube, so the minimal sphere is the cube's circumsphere: radius √3/2 about (½,½,½).
        let s = m.bounding_sphere();
        assert!((s.radius - 3f32.sqrt() / 2.0).abs() < 1e-6, "{s:?}");
        assert!(s.center.distance(Vec3::splat(0.5)) < 1e-6, "{s:?}");
        assert!(corner(1).is_err());
    }

    #[test]
    fn plane_counts_area_and_normals() {
        let m = plane(2.0, 5).unwrap();
        assert_eq!((m.vertex_count(), m.triangle_count()), (25, 32));
        assert!((m.area() - 4.0).abs() < 1e-9);
        assert!(m.normals.iter().all(|n| n.distance(Vec3::Y) < 1e-6));
        assert!(plane(0.0, 5).is_err());
    }

    #[test]
    fn cube_with_hole_is_closed_outward_genus_one() {
        let (s, h) = (2.0f64, 0.8f64);
        let m = cube_with_hole(s as f32, h as f32).unwrap();
        assert_eq!((m.vertex_count(), m.triangle_count()), (16, 32));
        assert!(m.is_closed() && m.is_consistently_oriented());
        // Euler characteristic V − E + F = 2 − 2g = 0: genus 1, the hole goes through.
        let edges: std::collections::HashSet<(u32, u32)> = m
            .triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        assert_eq!(16 - edges.len() as i64 + 32, 0);
        // Area: 6 faces minus two h² openings plus four h × s tunnel walls.
        let area = 6.0 * s * s - 2.0 * h * h + 4.0 * s * h;
        assert!(
            (m.area() - area).abs() < 1e-5 * area,
            "{} vs {area}",
            m.area()
        );
        // Volume (divergence theorem; positive means outward): cube minus the prism.
        let volume = s * s * s - h * h * s;
        assert!((m.signed_volume() - volume).abs() < 1e-5 * volume);
        assert!(cube_with_hole(1.0, 1.0).is_err());
    }

    #[test]
    fn ellipsoid_is_a_scaled_uv_sphere() {
        let radii = Vec3::new(10.0, 1.0, 1.0);
        let e = ellipsoid(radii, 16, 24).unwrap();
        let s = uv_sphere(1.0, 16, 24).unwrap();
        assert_eq!(e.vertex_count(), s.vertex_count());
        assert_eq!(e.triangle_count(), s.triangle_count());
        for (p, q) in e.positions.iter().zip(&s.positions) {
            assert!((*p - radii * *q).length() < 1e-5, "{p} vs {q}");
        }
        // Every vertex on the ellipsoid; the extent is the radii.
        for p in &e.positions {
            assert!(((*p / radii).length() - 1.0).abs() < 1e-5);
        }
        let b = e.bounding_sphere();
        assert!((b.radius - 10.0).abs() < 1e-3, "{b:?}");
        assert!(ellipsoid(Vec3::new(1.0, 0.0, 1.0), 4, 4).is_err());
        assert!(ellipsoid(Vec3::ONE, 1, 4).is_err());
    }

    #[test]
    fn uv_sphere_is_closed_and_area_is_within_polyhedral_bounds() {
        let r = 1.5f64;
        let mut previous_error = f64::INFINITY;
        for (stacks, slices) in [(8, 16), (16, 32), (32, 64)] {
            let m = uv_sphere(r as f32, stacks, slices).unwrap();
            assert_eq!(m.triangle_count(), 2 * slices * (stacks - 1));
            assert_eq!(m.vertex_count(), slices * (stacks - 1) + 2);
            assert!(m.is_closed() && m.is_consistently_oriented());
            // The mesh is a convex polytope inscribed in the sphere (its lat-long quads are
            // planar trapezoids), so it lies between the inscribed ball of radius r_in (the least
            // face-plane distance) and the sphere: 4π r_in² <= A < 4π r².
            let r_in = (0..m.triangle_count())
                .map(|i| {
                    let n = m.face_normal_f64(i).normalize();
                    n.dot(m.triangle(i)[0].as_dvec3())
                })
                .fold(f64::INFINITY, f64::min);
            let full = 4.0 * std::f64::consts::PI;
            let a = m.area();
            assert!(r_in > 0.0 && full * r_in * r_in <= a && a < full * r * r);
            let v = m.signed_volume();
            assert!(full / 3.0 * r_in.powi(3) <= v && v < full / 3.0 * r.powi(3));
            // Second-order convergence: halving the step cuts the area error about 4×.
            let error = full * r * r - a;
            assert!(error < previous_error / 3.0, "{error} vs {previous_error}");
            previous_error = error;
        }
    }

    #[test]
    fn default_scene_caster_clears_the_corner_planes() {
        let scene = default_scene();
        let receivers: Vec<_> = scene.receivers().collect();
        let casters: Vec<_> = scene.casters().collect();
        assert_eq!(receivers.len(), 1);
        assert_eq!(casters.len(), 1);
        assert_eq!(receivers[0].1.mesh.vertex_count(), 3267);
        let caster = casters[0].1;
        assert!(!caster.receiver && !receivers[0].1.caster);
        assert_eq!(caster.mesh.triangle_count(), 10_000);
        let s = caster.world_bounding_sphere();
        assert!((s.radius - 0.35).abs() < 1e-5, "{s:?}");
        assert!(s.center.distance(Vec3::new(0.5, 0.45, 0.5)) < 1e-5, "{s:?}");
        // The bounding sphere stays off the planes x = 0, y = 0, z = 0 (lowest point y ≈ 0.10).
        let lowest = s.center - Vec3::splat(s.radius);
        assert!(lowest.cmpgt(Vec3::ZERO).all(), "{lowest}");
        // And every world vertex lies inside it.
        for t in caster.world_triangles() {
            for p in t {
                assert!(s.contains(p, 1e-5));
            }
        }
    }
}
