//! Rigid instances: a shared mesh placed by a similarity transform.

use super::{Mesh, Sphere};
use glam::{Mat4, Quat, Vec3};
use std::sync::Arc;

/// world = translation + scale · (rotation · local). Uniform scale only, so distances scale by
/// `scale` and a field baked in model space stays valid.
///
/// `rotation` must be a unit quaternion and `scale` finite and positive ([`Similarity::new`]
/// checks both).
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

impl Similarity {
    /// # Panics
    /// If `scale` is not finite and positive or `rotation` is not normalised.
    pub fn new(rotation: Quat, translation: Vec3, scale: f32) -> Similarity {
        assert!(
            scale.is_finite() && scale > 0.0,
            "similarity scale must be finite and positive, got {scale}"
        );
        assert!(
            rotation.is_normalized(),
            "similarity rotation must be a unit quaternion, got {rotation}"
        );
        Similarity {
            rotation,
            translation,
            scale,
        }
    }

    /// Model-space point to world space.
    #[inline]
    pub fn to_world_point(&self, p: Vec3) -> Vec3 {
        self.translation + self.scale * (self.rotation * p)
    }

    /// Model-space direction to world space: rotation only, so unit stays unit.
    #[inline]
    pub fn to_world_dir(&self, d: Vec3) -> Vec3 {
        self.rotation * d
    }

    /// World-space point to model space (inverse of [`Similarity::to_world_point`]).
    #[inline]
    pub fn to_local_point(&self, p: Vec3) -> Vec3 {
        self.rotation.inverse() * ((p - self.translation) / self.scale)
    }

    /// World-space direction to model space: rotation only.
    #[inline]
    pub fn to_local_dir(&self, d: Vec3) -> Vec3 {
        self.rotation.inverse() * d
    }

    /// World-space distance to model space.
    #[inline]
    pub fn to_local_distance(&self, t: f32) -> f32 {
        t / self.scale
    }

    /// The inverse transform: `s.inverse().to_world_point(s.to_world_point(p)) == p`.
    pub fn inverse(&self) -> Similarity {
        let rotation = self.rotation.inverse();
        let scale = 1.0 / self.scale;
        Similarity {
            rotation,
            translation: -(scale * (rotation * self.translation)),
            scale,
        }
    }

    /// `self ∘ inner`: applies `inner` first, then `self`.
    pub fn compose(&self, inner: &Similarity) -> Similarity {
        Similarity {
            rotation: (self.rotation * inner.rotation).normalize(),
            translation: self.to_world_point(inner.translation),
            scale: self.scale * inner.scale,
        }
    }

    /// The 4×4 matrix (column vectors) of the same map.
    pub fn to_mat4(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(
            Vec3::splat(self.scale),
            self.rotation,
            self.translation,
        )
    }

    /// The sphere's image: centre mapped, radius scaled.
    pub fn to_world_sphere(&self, s: &Sphere) -> Sphere {
        Sphere {
            center: self.to_world_point(s.center),
            radius: s.radius * self.scale,
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

impl Instance {
    /// The mesh's triangles in world space, in mesh order.
    pub fn world_triangles(&self) -> impl ExactSizeIterator<Item = [Vec3; 3]> + '_ {
        (0..self.mesh.triangle_count()).map(move |i| {
            self.mesh
                .triangle(i)
                .map(|p| self.transform.to_world_point(p))
        })
    }

    /// The world image of the mesh's minimal bounding sphere (itself minimal, since a similarity
    /// maps balls to balls). Recomputes the model-space sphere on each call.
    pub fn world_bounding_sphere(&self) -> Sphere {
        self.transform.to_world_sphere(&self.mesh.bounding_sphere())
    }
}

/// A scene: a list of instances.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub instances: Vec<Instance>,
}

impl Scene {
    /// Triangles over every instance.
    pub fn triangle_count(&self) -> usize {
        self.instances.iter().map(|i| i.mesh.triangle_count()).sum()
    }

    /// Instances that cast occlusion, with their index in `instances`.
    pub fn casters(&self) -> impl Iterator<Item = (usize, &Instance)> + '_ {
        self.instances.iter().enumerate().filter(|(_, i)| i.caster)
    }

    /// Instances that receive occlusion, with their index in `instances`.
    pub fn receivers(&self) -> impl Iterator<Item = (usize, &Instance)> + '_ {
        self.instances
            .iter()
            .enumerate()
            .filter(|(_, i)| i.receiver)
    }

    /// The minimal bounding sphere of every instance's world vertices (the scale of a scene's
    /// ray offset, `render::ao::AoOptions::for_scene`).
    pub fn bounding_sphere(&self) -> Sphere {
        let pts: Vec<Vec3> = self
            .instances
            .iter()
            .flat_map(|i| i.world_triangles().flatten())
            .collect();
        super::minimal_bounding_sphere(&pts)
    }

    /// All casters' world triangles, in instance order (the input of a ray-cast reference).
    pub fn caster_triangles(&self) -> Vec<[Vec3; 3]> {
        self.casters()
            .flat_map(|(_, inst)| inst.world_triangles())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Similarity {
        Similarity::new(
            Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 1.1),
            Vec3::new(0.5, -2.0, 3.0),
            2.5,
        )
    }

    fn probe() -> [Vec3; 4] {
        [
            Vec3::ZERO,
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-0.3, 0.1, 4.0),
            Vec3::new(7.0, -5.0, 0.25),
        ]
    }

    #[test]
    fn local_world_round_trips() {
        let s = sample();
        for p in probe() {
            let back = s.to_local_point(s.to_world_point(p));
            assert!(back.distance(p) < 1e-5, "{p} -> {back}");
            let d = p.normalize_or(Vec3::X);
            assert!(s.to_local_dir(s.to_world_dir(d)).distance(d) < 1e-6);
            assert!((s.to_world_dir(d).length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn inverse_and_matrix_agree_with_point_maps() {
        let s = sample();
        let inv = s.inverse();
        let m = s.to_mat4();
        for p in probe() {
            let w = s.to_world_point(p);
            assert!(m.transform_point3(p).distance(w) < 1e-5);
            assert!(inv.to_world_point(w).distance(p) < 1e-5);
            assert!(inv.to_world_point(p).distance(s.to_local_point(p)) < 1e-5);
            assert!(
                m.transform_vector3(Vec3::Y)
                    .distance(s.scale * s.to_world_dir(Vec3::Y))
                    < 1e-5
            );
        }
        // Distances scale by `scale`.
        let (a, b) = (probe()[1], probe()[3]);
        let ratio = s.to_world_point(a).distance(s.to_world_point(b)) / a.distance(b);
        assert!((ratio - s.scale).abs() < 1e-5);
    }

    #[test]
    fn compose_applies_inner_first() {
        let (a, b) = (sample(), sample().inverse().compose(&Similarity::default()));
        let c = a.compose(&b);
        for p in probe() {
            let expected = a.to_world_point(b.to_world_point(p));
            assert!(c.to_world_point(p).distance(expected) < 1e-4);
        }
    }

    #[test]
    #[should_panic(expected = "finite and positive")]
    fn rejects_zero_scale() {
        Similarity::new(Quat::IDENTITY, Vec3::ZERO, 0.0);
    }

    #[test]
    fn world_sphere_and_roles() {
        let mesh = Arc::new(
            Mesh::from_parts(
                "tet",
                vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
                vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            )
            .unwrap(),
        );
        let t = sample();
        let inst = Instance {
            mesh: mesh.clone(),
            transform: t,
            caster: true,
            receiver: false,
        };
        let ws = inst.world_bounding_sphere();
        // The world sphere equals the minimal sphere of the world vertices.
        let direct = super::super::minimal_bounding_sphere(
            &mesh
                .positions
                .iter()
                .map(|&p| t.to_world_point(p))
                .collect::<Vec<_>>(),
        );
        assert!((ws.radius - direct.radius).abs() < 1e-5 * direct.radius);
        assert!(ws.center.distance(direct.center) < 1e-5);
        assert_eq!(inst.world_triangles().len(), 4);
        let scene = Scene {
            instances: vec![
                inst.clone(),
                Instance {
                    caster: false,
                    receiver: true,
                    ..inst.clone()
                },
                Instance {
                    caster: true,
                    receiver: true,
                    ..inst
                },
            ],
        };
        let idx = |it: Vec<(usize, &Instance)>| it.into_iter().map(|(i, _)| i).collect::<Vec<_>>();
        assert_eq!(idx(scene.casters().collect()), vec![0, 2]);
        assert_eq!(idx(scene.receivers().collect()), vec![1, 2]);
        assert_eq!(scene.caster_triangles().len(), 8);
    }
}
