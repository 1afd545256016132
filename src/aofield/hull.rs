//! The distance r₀(ω) from an occluder's centre to its convex hull along each texel's direction
//! (Kontkanen & Laine 2005, inside the convex hull: the fields are modelled only outside the hull, and `r₀` is
//! stored per direction).
//!
//! For a centre c inside the hull of the vertices V, the hull's boundary along ω is at
//! `r₀(ω) = min over unit m with m·ω > 0 of (h(m) − m·c) / (m·ω)`, `h(m) = max_v m·v` the
//! support function (linear-programming duality: each supporting plane bounds the ray, and a
//! facet's plane meets it at the boundary). Deviation from the paper (which computes the hull
//! itself): we take the minimum over a fixed set of normals, the texel directions of a
//! `HULL_RES²`-per-face cube map and the six axes, so the hull is approximated from outside by
//! the intersection of those supporting half-spaces: r₀ is never below the true distance (no
//! sample point enters the hull). Every unit vector is within chord δ = √2/`HULL_RES` (0.029 at
//! 48) of a normal of the set, and the support function is `max|v − c|`-Lipschitz, so where the
//! ray leaves the hull through a face of normal n with `n·ω = cos γ` and offset h, the
//! approximation leaves by `(h + δ·max|v − c|)/(cos γ − δ)` at the latest (tested on a rotated
//! box); axis-aligned faces are exact. r₀ is at most the bounding radius (the hull lies in the
//! bounding ball), and clamped to it.

use super::cube::Cube;
use glam::DVec3;
use rayon::prelude::*;

/// Texels per face side of the cube map of supporting normals.
pub const HULL_RES: usize = 48;

/// Supporting planes of a point set: unit normals and `h(m) − m·c`, the plane's distance from
/// the centre.
pub struct SupportPlanes {
    normals: Vec<DVec3>,
    offsets: Vec<f64>,
}

impl SupportPlanes {
    /// The planes of `points` around `centre` along [`HULL_RES`]'s normals and the six axes.
    pub fn new(points: &[DVec3], centre: DVec3) -> SupportPlanes {
        let cube = Cube { res: HULL_RES };
        let mut normals: Vec<DVec3> = (0..cube.len())
            .map(|t| cube.texel_direction(t).as_dvec3().normalize())
            .collect();
        for a in 0..3 {
            let mut e = DVec3::ZERO;
            e[a] = 1.0;
            normals.push(e);
            normals.push(-e);
        }
        let rel: Vec<DVec3> = points.iter().map(|&p| p - centre).collect();
        let offsets = normals
            .par_iter()
            .map(|m| rel.iter().fold(f64::NEG_INFINITY, |h, p| h.max(m.dot(*p))))
            .collect();
        SupportPlanes { normals, offsets }
    }

    /// r₀ along the unit direction `w`, clamped to `[0, max]` (`max`: the bounding radius).
    pub fn distance(&self, w: DVec3, max: f64) -> f64 {
        let mut best = max;
        for (m, &h) in self.normals.iter().zip(&self.offsets) {
            let cos = m.dot(w);
            if cos > 1e-12 {
                best = best.min(h.max(0.0) / cos);
            }
        }
        best.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_corners(half: f64) -> Vec<DVec3> {
        let mut v = Vec::new();
        for x in [-half, half] {
            for y in [-half, half] {
                for z in [-half, half] {
                    v.push(DVec3::new(x, y, z));
                }
            }
        }
        v
    }

    #[test]
    fn a_box_is_exact_along_its_axes_and_never_inside_elsewhere() {
        let planes = SupportPlanes::new(&cube_corners(0.5), DVec3::ZERO);
        let r = 3f64.sqrt() * 0.5;
        for a in 0..3 {
            let mut e = DVec3::ZERO;
            e[a] = 1.0;
            assert!((planes.distance(e, r) - 0.5).abs() < 1e-12);
            assert!((planes.distance(-e, r) - 0.5).abs() < 1e-12);
        }
        // Along any direction the box's exit is 0.5 / max|wᵢ|: the approximation is never
        // below it, and an axis-aligned box's faces are among the planes, so it is exact.
        for k in 0..200 {
            let t = k as f64 * 0.731;
            let w = DVec3::new(t.sin(), (2.3 * t).cos(), (0.7 * t).sin() + 0.1).normalize();
            let exact = 0.5 / w.abs().max_element();
            let got = planes.distance(w, r);
            assert!((got - exact).abs() < 1e-12, "{w}: {got} vs {exact}");
        }
    }

    #[test]
    fn a_rotated_box_is_approximated_from_outside_within_the_derived_bound() {
        let q = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.5, 0.9);
        let corners: Vec<DVec3> = cube_corners(0.5).into_iter().map(|p| q * p).collect();
        let planes = SupportPlanes::new(&corners, DVec3::ZERO);
        // δ: every unit vector lies within chord δ = √2/48 of the nearest normal of the set
        // (within a face, half a texel's diagonal in (u, v), and projecting the face's plane
        // onto the sphere is 1-Lipschitz). The exit face (normal n, h(n) = 0.5) meets w at
        // cos c = max|local wᵢ|; the nearest normal m has |m − n| ≤ δ, so h(m) ≤ h(n) + δ·|v|max
        // (the support function is |v|max-Lipschitz) and m·w ≥ c − δ: the approximation exits
        // by (0.5 + δ·√3/2)/(c − δ) at the latest.
        let delta = 2f64.sqrt() / HULL_RES as f64;
        let far = 3f64.sqrt() / 2.0;
        for k in 0..300 {
            let t = k as f64 * 0.377;
            let w = DVec3::new(t.cos(), (1.9 * t).sin(), (0.4 * t).cos() - 0.3).normalize();
            let local = q.inverse() * w;
            let c = local.abs().max_element();
            let exact = 0.5 / c;
            let bound = (0.5 + delta * far) / (c - delta) - exact;
            let got = planes.distance(w, 1.0);
            assert!(got >= exact - 1e-12, "{w}: {got} inside the hull ({exact})");
            assert!(got - exact <= bound, "{w}: {got} vs {exact} + {bound}");
        }
    }
}
