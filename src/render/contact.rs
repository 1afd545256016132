//! Receiver points at contact: where a receiver point lies on another surface (the corner's
//! creases, a caster resting on the floor), AO under a fixed offset along the normal is
//! ill-defined: the origin lies on the other surface, and whether a ray leaving it is blocked at
//! `t = 0` is an accident of rounding.
//!
//! The convention ([`separate_contacts`]): a surface *touches* a point when one of its
//! triangles lies within `tolerance` of it. Triangles whose plane is the point's own (normal
//! within 10° of the point's normal) are its own surface and ignored. Any other touching
//! triangle makes the point a *crease* point, and
//!
//! - a touching surface at an angle (a crease: |n·m| < cos 10°) moves the point by `offset`
//!   along that surface's front normal m (its winding normal), once per distinct normal, so that
//!   the ray origin (moved again by the render's offset along the point's own normal) lies in
//!   front of both surfaces: rays into the other surface hit it at a small positive t, rays away
//!   from it leave. At the corner's floor crease this gives the limit of the AO of floor points
//!   approaching the crease, not 0 or 1.
//! - a touching surface facing the point (m ≈ −n: a caster resting on the receiver) does not
//!   move it: the point is enclosed, and the render's offset along n puts the origin inside the
//!   contact, where every ray is blocked (AO 0, the limit from the contact patch).
//!
//! A surface's front is its winding normal, so meshes are expected to be consistently (outward)
//! oriented; a touching triangle of another object wound the same way as the point's own
//! surface counts as the point's own surface (a limitation: such contacts go unreported).
//!
//! `offset` and `tolerance` scale with the scene ([`super::ao::scene_epsilon`] suits both).
//! [`separate_contacts`] tells the crease points apart so that their errors can be reported
//! apart from the interior points'.

use glam::Vec3;
use std::collections::HashMap;

/// cos 10°: normals closer than this are one plane.
const SAME_PLANE_COS: f32 = 0.984_807_7;

pub use crate::geometry::closest_point_on_triangle;

/// Receiver points after the contact convention.
#[derive(Clone, Debug, PartialEq)]
pub struct Contacts {
    /// The points, moved off touching creases.
    pub points: Vec<Vec3>,
    /// Whether each point touches another surface (crease or contact).
    pub crease: Vec<bool>,
}

impl Contacts {
    /// Number of crease points.
    pub fn crease_count(&self) -> usize {
        self.crease.iter().filter(|&&c| c).count()
    }
}

/// Applies the contact convention of the module docs to `points` (unit `normals`) against
/// `triangles` (every surface of the scene, receivers included).
///
/// # Panics
/// If `points` and `normals` differ in length.
pub fn separate_contacts(
    points: &[Vec3],
    normals: &[Vec3],
    triangles: &[[Vec3; 3]],
    tolerance: f32,
    offset: f32,
) -> Contacts {
    separate(points, normals, triangles, |_| tolerance, |_| offset)
}

/// [`separate_contacts`] with each point's own tolerance and offset, `offsets[i]` for both
/// (the ray offset of the point's instance, [`super::ao::instance_epsilon`]).
///
/// # Panics
/// If `points`, `normals` and `offsets` differ in length.
pub fn separate_contacts_each(
    points: &[Vec3],
    normals: &[Vec3],
    triangles: &[[Vec3; 3]],
    offsets: &[f32],
) -> Contacts {
    assert_eq!(
        points.len(),
        offsets.len(),
        "separate_contacts_each: lengths"
    );
    separate(points, normals, triangles, |i| offsets[i], |i| offsets[i])
}

fn separate(
    points: &[Vec3],
    normals: &[Vec3],
    triangles: &[[Vec3; 3]],
    tolerance_of: impl Fn(usize) -> f32,
    offset_of: impl Fn(usize) -> f32,
) -> Contacts {
    assert_eq!(points.len(), normals.len(), "separate_contacts: lengths");
    let mut touching: Vec<Vec<Vec3>> = vec![Vec::new(); points.len()];
    if !points.is_empty() {
        // The grid and each triangle's box take the largest tolerance; each point its own.
        let tolerance = (0..points.len()).map(&tolerance_of).fold(0.0f32, f32::max);
        let grid = PointGrid::new(points, tolerance);
        for t in triangles {
            let m = (t[1] - t[0]).cross(t[2] - t[0]);
            let Some(m) = m.try_normalize() else { continue };
            let lo = t[0].min(t[1]).min(t[2]) - Vec3::splat(tolerance);
            let hi = t[0].max(t[1]).max(t[2]) + Vec3::splat(tolerance);
            grid.for_each_in(lo, hi, |i| {
                let p = points[i];
                let tol = tolerance_of(i);
                if p.distance_squared(closest_point_on_triangle(p, t)) <= tol * tol
                    && normals[i].dot(m) < SAME_PLANE_COS
                {
                    touching[i].push(m);
                }
            });
        }
    }
    let mut out = Contacts {
        points: points.to_vec(),
        crease: vec![false; points.len()],
    };
    for (i, ms) in touching.iter().enumerate() {
        if ms.is_empty() {
            continue;
        }
        out.crease[i] = true;
        let mut distinct: Vec<Vec3> = Vec::new();
        for &m in ms {
            let crease = normals[i].dot(m) > -SAME_PLANE_COS;
            if crease && !distinct.iter().any(|d| d.dot(m) >= SAME_PLANE_COS) {
                distinct.push(m);
            }
        }
        for m in distinct {
            out.points[i] += offset_of(i) * m;
        }
    }
    out
}

/// A hash grid over points, for finding the points near a box.
struct PointGrid {
    cell: f32,
    lo: Vec3,
    hi: Vec3,
    cells: HashMap<(i32, i32, i32), Vec<usize>>,
}

impl PointGrid {
    fn new(points: &[Vec3], tolerance: f32) -> PointGrid {
        let lo = points
            .iter()
            .fold(Vec3::splat(f32::INFINITY), |a, &p| a.min(p));
        let hi = points
            .iter()
            .fold(Vec3::splat(f32::NEG_INFINITY), |a, &p| a.max(p));
        // About 64 cells along the longest side, never finer than the tolerance.
        let cell = ((hi - lo).max_element() / 64.0)
            .max(4.0 * tolerance)
            .max(1e-30);
        let mut cells: HashMap<(i32, i32, i32), Vec<usize>> = HashMap::new();
        let mut g = PointGrid {
            cell,
            lo,
            hi,
            cells: HashMap::new(),
        };
        for (i, &p) in points.iter().enumerate() {
            cells.entry(g.key(p)).or_default().push(i);
        }
        g.cells = cells;
        g
    }

    fn key(&self, p: Vec3) -> (i32, i32, i32) {
        let q = ((p - self.lo) / self.cell).floor();
        (q.x as i32, q.y as i32, q.z as i32)
    }

    /// Calls `f` with every point whose cell meets the box [lo, hi] (a superset of the points in
    /// it).
    fn for_each_in(&self, lo: Vec3, hi: Vec3, mut f: impl FnMut(usize)) {
        let (lo, hi) = (lo.max(self.lo), hi.min(self.hi));
        if lo.cmpgt(hi).any() {
            return;
        }
        let (a, b) = (self.key(lo), self.key(hi));
        let span = (b.0 - a.0 + 1) as i64 * (b.1 - a.1 + 1) as i64 * (b.2 - a.2 + 1) as i64;
        if span > self.cells.len() as i64 {
            // A box larger than the occupied cells: visit the occupied cells.
            for (k, v) in &self.cells {
                let inside = (a.0..=b.0).contains(&k.0)
                    && (a.1..=b.1).contains(&k.1)
                    && (a.2..=b.2).contains(&k.2);
                if inside {
                    v.iter().for_each(|&i| f(i));
                }
            }
            return;
        }
        for x in a.0..=b.0 {
            for y in a.1..=b.1 {
                for z in a.2..=b.2 {
                    if let Some(v) = self.cells.get(&(x, y, z)) {
                        v.iter().for_each(|&i| f(i));
                    }
                }
            }
        }
    }
}

#[cfg(test)]
#[path = "contact_tests.rs"]
mod tests;
