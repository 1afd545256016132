//! Rendering: one [`Visibility`] interface with ray-cast and field-lookup backends, and the
//! renderers built on it (vertex AO as in 2008; image-space AO, soft shadows, reflections as in
//! 2010).

/// A visibility oracle. Every renderer is written against this trait so that ray casting and
/// field lookup run on exactly the same rays.
pub trait Visibility: Sync {
    /// Whether the segment origin + t·dir, t in [tmin, tmax], is blocked. `dir` is unit.
    fn occluded(&self, origin: glam::Vec3, dir: glam::Vec3, tmin: f32, tmax: f32) -> bool;
}

pub mod camera;
pub mod image;
