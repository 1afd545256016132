//! A pinhole camera (right-handed, looking down −z in camera space, y up).

use glam::Vec3;

/// A look-at pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position (world).
    pub eye: Vec3,
    /// Point looked at (world).
    pub target: Vec3,
    /// Up hint (world).
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
}

fn default_up() -> Vec3 {
    Vec3::Y
}

impl Camera {
    /// The corner scenes' camera (the 2008 paper's corner receiver, a caster over it): looking
    /// into the corner from the open octant. The default of a spec's image and the
    /// quickstart's view.
    pub fn corner() -> Camera {
        Camera {
            eye: Vec3::new(2.3, 1.9, 2.3),
            target: Vec3::new(0.35, 0.3, 0.35),
            up: Vec3::Y,
            fov_y_deg: 38.0,
        }
    }

    /// Unit direction through the centre of pixel (x, y) of a `width × height` image; row 0 is
    /// the top.
    pub fn ray_dir(&self, x: u32, y: u32, width: u32, height: u32) -> Vec3 {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan = (self.fov_y_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let sx = ((x as f32 + 0.5) / width as f32 * 2.0 - 1.0) * tan * aspect;
        let sy = (1.0 - (y as f32 + 0.5) / height as f32 * 2.0) * tan;
        (forward + sx * right + sy * up).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_pixel_looks_at_the_target_and_corners_are_symmetric() {
        let cam = Camera {
            eye: Vec3::new(1.0, 2.0, 3.0),
            target: Vec3::new(-1.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y_deg: 40.0,
        };
        let d = cam.ray_dir(50, 50, 101, 101);
        let f = (cam.target - cam.eye).normalize();
        assert!(d.dot(f) > 1.0 - 1e-6);
        // Opposite corners are mirror images about the forward axis.
        let a = cam.ray_dir(0, 0, 101, 101);
        let b = cam.ray_dir(100, 100, 101, 101);
        assert!((a.dot(f) - b.dot(f)).abs() < 1e-6);
        // The vertical half-angle of the top-centre pixel is just under fov/2.
        let top = cam.ray_dir(50, 0, 101, 101);
        let ang = top.dot(f).acos().to_degrees();
        assert!(ang < 20.0 && ang > 19.5, "{ang}");
    }
}
