//! Rigid instances: a shared mesh placed by a similarity transform.

use super::Mesh;
use glam::{Quat, Vec3};
use std::sync::Arc;

/// world = translation + scale · (rotation · local). Uniform scale only, so distances scale by
/// `scale` and a field baked in model space stays valid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    pub rotation: Quat,
    pub translation: Vec3,
    pub scale: f32,
}

impl Default for Similarity {
    fn default() -> Self {
        Similarity {
            rotation: Quat::IDENTITY,
            translation: Vec3::ZERO,
            scale: 1.0,
        }
    }
}

/// A mesh placed in the world, with its roles in an AO scene.
#[derive(Clone, Debug)]
pub struct Instance {
    pub mesh: Arc<Mesh>,
    pub transform: Similarity,
    /// Casts occlusion onto others.
    pub caster: bool,
    /// Receives occlusion (AO is evaluated at its vertices).
    pub receiver: bool,
}

/// A scene: a list of instances.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub instances: Vec<Instance>,
}
