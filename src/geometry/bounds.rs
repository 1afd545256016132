//! Minimal bounding spheres.

use glam::Vec3;

/// A sphere (centre, radius).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

/// The exact minimal enclosing sphere of `points` (Welzl 1991).
pub fn minimal_bounding_sphere(points: &[Vec3]) -> Sphere {
    let _ = points;
    todo!("geometry helper")
}
