//! The cube map an AO field stores its radial functions in (Kontkanen & Laine 2005, storing Ω
//! and Υ: radial functions in a cube map around the occluder).
//!
//! Face `f` = 2·axis + (0 for +, 1 for −); on face (axis a, sign σ) a direction d with
//! |d_a| its largest component maps to (u, v) = (d_b, d_c) / |d_a| ∈ [−1, 1]², b and c the other
//! two axes in cyclic order. Each face holds `res × res` texels uniform in (u, v), texel (i, j)
//! centred at u = (2i + 1)/res − 1, v = (2j + 1)/res − 1, index `f·res² + j·res + i`.
//!
//! Lookups are bilinear within a face and clamped at its edges, as the 2005 hardware filtered a
//! cube map (no filtering across faces).

use glam::Vec3;

/// The texel grid of a cube map of `res × res` texels per face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cube {
    pub res: usize,
}

/// Four texels and their bilinear weights (summing to 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bilinear {
    pub texels: [usize; 4],
    pub weights: [f32; 4],
}

impl Cube {
    /// Texels over the six faces.
    pub fn len(&self) -> usize {
        6 * self.res * self.res
    }

    /// Whether the map has no texel (`res` 0).
    pub fn is_empty(&self) -> bool {
        self.res == 0
    }

    /// The face and face coordinates (u, v) ∈ [−1, 1]² of a non-zero direction.
    #[inline]
    pub fn face_uv(d: Vec3) -> (usize, f32, f32) {
        let a = d.abs();
        let (axis, major) = if a.x >= a.y && a.x >= a.z {
            (0, d.x)
        } else if a.y >= a.z {
            (1, d.y)
        } else {
            (2, d.z)
        };
        let b = d[(axis + 1) % 3];
        let c = d[(axis + 2) % 3];
        let m = major.abs();
        let face = 2 * axis + usize::from(major < 0.0);
        (face, b / m, c / m)
    }

    /// The unit direction of face `face` at (u, v).
    #[inline]
    pub fn direction(face: usize, u: f32, v: f32) -> Vec3 {
        let axis = face / 2;
        let sign = if face.is_multiple_of(2) { 1.0 } else { -1.0 };
        let mut d = Vec3::ZERO;
        d[axis] = sign;
        d[(axis + 1) % 3] = u;
        d[(axis + 2) % 3] = v;
        d.normalize()
    }

    /// The centre of texel `i` along a face side, in [−1, 1].
    #[inline]
    pub fn centre_coord(&self, i: usize) -> f32 {
        (2 * i + 1) as f32 / self.res as f32 - 1.0
    }

    /// The unit direction through the centre of texel `t`.
    pub fn texel_direction(&self, t: usize) -> Vec3 {
        let r2 = self.res * self.res;
        let face = t / r2;
        let j = (t % r2) / self.res;
        let i = t % self.res;
        Cube::direction(face, self.centre_coord(i), self.centre_coord(j))
    }

    /// The texels and bilinear weights of a non-zero direction, clamped at the face's edges.
    #[inline]
    pub fn bilinear(&self, d: Vec3) -> Bilinear {
        let (face, u, v) = Cube::face_uv(d);
        let n = self.res;
        let last = (n - 1) as f32;
        let fu = ((u + 1.0) * 0.5 * n as f32 - 0.5).clamp(0.0, last);
        let fv = ((v + 1.0) * 0.5 * n as f32 - 0.5).clamp(0.0, last);
        let i0 = (fu as usize).min(n - 1);
        let j0 = (fv as usize).min(n - 1);
        let i1 = (i0 + 1).min(n - 1);
        let j1 = (j0 + 1).min(n - 1);
        let wx = fu - i0 as f32;
        let wy = fv - j0 as f32;
        let base = face * n * n;
        Bilinear {
            texels: [
                base + j0 * n + i0,
                base + j0 * n + i1,
                base + j1 * n + i0,
                base + j1 * n + i1,
            ],
            weights: [
                (1.0 - wx) * (1.0 - wy),
                wx * (1.0 - wy),
                (1.0 - wx) * wy,
                wx * wy,
            ],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_centres_round_trip_to_their_own_texel_with_weight_one() {
        let cube = Cube { res: 7 };
        for t in 0..cube.len() {
            let d = cube.texel_direction(t);
            assert!((d.length() - 1.0).abs() < 1e-6);
            let b = cube.bilinear(d);
            // The texel's own weight is 1 up to the rounding of u, v (a few ulps of res).
            let own = b
                .texels
                .iter()
                .zip(b.weights)
                .filter(|(&x, _)| x == t)
                .map(|(_, w)| w)
                .sum::<f32>();
            assert!(own > 1.0 - 1e-5, "texel {t}: own weight {own}");
        }
    }

    #[test]
    fn every_direction_lands_on_the_face_of_its_largest_component() {
        let dirs = [
            (Vec3::X, 0),
            (-Vec3::X, 1),
            (Vec3::Y, 2),
            (-Vec3::Y, 3),
            (Vec3::Z, 4),
            (-Vec3::Z, 5),
            (Vec3::new(0.3, -0.9, 0.2), 3),
            (Vec3::new(-0.1, 0.2, 0.95), 4),
        ];
        for (d, face) in dirs {
            let (f, u, v) = Cube::face_uv(d);
            assert_eq!(f, face, "{d}");
            assert!(u.abs() <= 1.0 && v.abs() <= 1.0);
            let back = Cube::direction(f, u, v);
            assert!(back.distance(d.normalize()) < 1e-6, "{d} → {back}");
        }
    }

    #[test]
    fn weights_sum_to_one_and_clamp_at_face_edges() {
        let cube = Cube { res: 4 };
        for k in 0..500 {
            let t = k as f32 * 0.618_034;
            let d = Vec3::new(t.sin(), (1.7 * t).cos(), (0.3 * t).sin() - 0.2);
            if d.length() < 1e-3 {
                continue;
            }
            let b = cube.bilinear(d);
            let sum: f32 = b.weights.iter().sum();
            assert!((sum - 1.0).abs() < 1e-6);
            assert!(b.weights.iter().all(|&w| (0.0..=1.0).contains(&w)));
            let face = Cube::face_uv(d).0;
            assert!(
                b.texels.iter().all(|&x| x / 16 == face),
                "no texel of another face"
            );
        }
    }
}
