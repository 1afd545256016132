//! Robust orthonormal frames (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 2017).

use glam::Vec3;

/// An orthonormal frame; `z` is the normal. Local directions have `z >= 0` in the hemisphere.
#[derive(Clone, Copy, Debug, PartialEq)]
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
