//! Robust orthonormal frames (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 2017).

use glam::Vec3;

/// An orthonormal frame; `z` is the normal. Local directions have `z >= 0` in the hemisphere.
/// Laid out as nine f32 (x, y, z in turn), which the eight-lane lookup gathers from.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// Frame around unit normal `n` (Duff et al. 2017, branchless).
    #[inline]
    pub fn from_normal(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            x: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            y: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            z: n,
        }
    }

    #[inline]
    pub fn to_world(&self, local: Vec3) -> Vec3 {
        self.x * local.x + self.y * local.y + self.z * local.z
    }

    #[inline]
    pub fn to_local(&self, world: Vec3) -> Vec3 {
        Vec3::new(world.dot(self.x), world.dot(self.y), world.dot(self.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rays::seeded_sphere_direction;

    fn assert_orthonormal(n: Vec3) {
        let f = Frame::from_normal(n);
        let err = [
            (f.x.length() - 1.0).abs(),
            (f.y.length() - 1.0).abs(),
            (f.z.length() - 1.0).abs(),
            f.x.dot(f.y).abs(),
            f.y.dot(f.z).abs(),
            f.z.dot(f.x).abs(),
            // Right-handed: x × y = z.
            (f.x.cross(f.y) - f.z).length(),
        ]
        .into_iter()
        .fold(0.0f32, f32::max);
        assert!(err < 1e-6, "normal {n:?}: error {err}, frame {f:?}");
        // Round trip through the frame.
        let v = Vec3::new(0.3, -0.5, 0.8);
        assert!((f.to_local(f.to_world(v)) - v).length() < 1e-6);
        assert!((f.to_world(Vec3::Z) - n).length() < 1e-6);
    }

    #[test]
    fn frames_are_orthonormal_at_poles_and_axes() {
        for n in [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ] {
            assert_orthonormal(n);
        }
        // −0.0 picks the negative branch of copysign; it must still work.
        assert_orthonormal(Vec3::new(0.0, 0.0, -0.0).normalize_or(Vec3::new(0.0, 0.0, -1.0)));
        assert_orthonormal(Vec3::new(1e-7, 0.0, -1.0).normalize());
    }

    #[test]
    fn frames_are_orthonormal_near_axes() {
        // n.z = ±(1 − ε) and n.z ≈ ±ε, the cases where Frisvad's original method broke down.
        for eps in [1e-7f32, 1e-6, 1e-5, 1e-4, 1e-3] {
            for (s, c) in [(1.0f32, 0.0f32), (0.6, 0.8), (-0.8, 0.6), (0.0, -1.0)] {
                let r = (1.0 - (1.0 - eps) * (1.0 - eps)).sqrt();
                for z in [-1.0 + eps, 1.0 - eps, eps, -eps] {
                    let rr = if z.abs() > 0.5 {
                        r
                    } else {
                        (1.0 - z * z).sqrt()
                    };
                    assert_orthonormal(Vec3::new(rr * c, rr * s, z).normalize());
                }
            }
        }
    }

    #[test]
    fn frames_are_orthonormal_for_random_normals() {
        for i in 0..100_000 {
            assert_orthonormal(seeded_sphere_direction(i, 17));
        }
    }
}
