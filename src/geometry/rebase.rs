//! World coordinates rebased on the scene.
//!
//! Every renderer works in f32. A scene placed far from the origin (translated by 1e4, or a
//! model whose file coordinates are large) loses precision in f32 world coordinates: at 1e4
//! their spacing is 2⁻¹⁰ ≈ 1e-3, so hit points, ray offsets and sphere entries are rounded by
//! an amount that no longer scales with the geometry. AO does not depend on where the scene
//! is, so the scene is moved next to the origin before any f32 world coordinate is formed:
//! placements are composed in f64 ([`Placement`]), an origin near the scene's centre is chosen
//! ([`rebase_origin`]), and each instance's f32 [`Similarity`] is taken relative to it, rounded
//! once. World coordinates in a [`Rebased`] scene are `true world − origin`.
//!
//! The origin is a multiple of a power-of-two step at least four times the scene's radius, so
//! a scene within two radii of the origin keeps origin 0 (and its exact coordinates), and a
//! translation by a multiple of the step is removed exactly. A placement keeps its large
//! translation (the spec's) apart from the small offsets composed onto it (fits, model
//! offsets), so that `translation − origin` is exact and the offsets are added after it: a
//! scene translated by any multiple of the step (1e4, 1e12, 1e15, 1e20 for a unit scene) gets
//! the untranslated scene's f32 coordinates bit for bit. f64 resolves a scene's instances
//! relative to each other only while its distance from the spec's origin is at most
//! [`MAX_DISTANCE_TO_EXTENT`] times its half-extent: [`extent_problem`] names a scene past it.

use super::{Instance, Mesh, Scene, Similarity};
use glam::{DVec3, Quat, Vec3};
use std::sync::Arc;

/// A placement whose translation is kept in f64 until the scene's origin is known:
/// world = (translation + offset) + scale · (rotation · local), as [`Similarity`].
/// `translation` is the large part (a spec's translate), `offset` the sum of the small ones
/// composed onto it; they are added only relative to the rebased origin ([`Self::relative_to`]),
/// where `translation − origin` is exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub rotation: Quat,
    pub translation: DVec3,
    pub scale: f32,
    /// The offsets composed after `translation` (f64, exact sums of f32 products).
    pub offset: DVec3,
}

impl From<Similarity> for Placement {
    fn from(s: Similarity) -> Placement {
        Placement::new(s.rotation, s.translation.as_dvec3(), s.scale)
    }
}

impl Placement {
    /// world = translation + scale · (rotation · local), no offset yet.
    pub fn new(rotation: Quat, translation: DVec3, scale: f32) -> Placement {
        Placement {
            rotation,
            translation,
            scale,
            offset: DVec3::ZERO,
        }
    }

    /// `self ∘ inner` (applies `inner` first): the rotated inner translation, an f32 vector of
    /// the inner placement's size whose scaled value is exact in f64, joins the offset; the
    /// large translation is left as it is until the placement is rebased.
    pub fn compose(&self, inner: &Similarity) -> Placement {
        Placement {
            rotation: (self.rotation * inner.rotation).normalize(),
            translation: self.translation,
            offset: self.offset
                + self.scale as f64 * (self.rotation * inner.translation).as_dvec3(),
            scale: self.scale * inner.scale,
        }
    }

    /// `self ∘ T(offset)`: the placement of a mesh whose model-space points were moved by
    /// `−offset` ([`centred_mesh`]), so that it places them where `self` placed the original.
    pub fn after_model_offset(&self, offset: DVec3) -> Placement {
        Placement {
            offset: self.offset + self.scale as f64 * (self.rotation.as_dquat() * offset),
            ..*self
        }
    }

    /// A model-space point in true world coordinates (f64).
    pub fn to_world_point(&self, p: Vec3) -> DVec3 {
        self.translation + (self.offset + self.scale as f64 * (self.rotation * p).as_dvec3())
    }

    /// The f32 similarity of this placement in the frame whose origin is `origin` (true world
    /// coordinates): `(translation − origin) + offset`, formed in f64 (the difference exact when
    /// `origin` is a multiple of a step no finer than the translation's f64 spacing, as
    /// [`rebase_origin`]'s) and rounded once.
    pub fn relative_to(&self, origin: DVec3) -> Similarity {
        Similarity::new(
            self.rotation,
            ((self.translation - origin) + self.offset).as_vec3(),
            self.scale,
        )
    }
}

/// The origin of a rebased frame around spheres `(centre, radius)` in true world coordinates:
/// the centre of their bounding box rounded to a multiple of the power-of-two step
/// `2^⌈log₂(4·r)⌉`, `r` the box's half-diagonal. The step is exact in f32 and f64, so the
/// origin and every shift by it are too. Zero when there are no spheres.
pub fn rebase_origin(spheres: &[(DVec3, f64)]) -> DVec3 {
    let Some(&(c0, r0)) = spheres.first() else {
        return DVec3::ZERO;
    };
    let (mut lo, mut hi) = (c0 - r0, c0 + r0);
    for &(c, r) in &spheres[1..] {
        lo = lo.min(c - r);
        hi = hi.max(c + r);
    }
    let centre = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo).length();
    if !centre.is_finite() || !half.is_finite() {
        return DVec3::ZERO;
    }
    // At least the f64 spacing at the centre, so a single-point scene far out still rebases
    // (and the origin is a multiple of the translation's own spacing: see `relative_to`).
    let floor = centre.abs().max_element() * f64::EPSILON;
    let step = (4.0 * half)
        .max(floor)
        .max(f64::MIN_POSITIVE)
        .log2()
        .ceil()
        .exp2();
    (centre / step).round() * step
}

/// The largest distance from the spec's origin, in half-widths of the scene's box, at which f64
/// places its instances relative to each other as finely as f32 resolves the scene itself:
/// 2⁵⁴ (the rebasing step, four half-extents, is then still the f64 spacing there or coarser).
pub const MAX_DISTANCE_TO_EXTENT: f64 = 18_014_398_509_481_984.0;

/// Why the placed meshes cannot be rebased faithfully, if they cannot: their distance from the
/// spec's origin over their half-extent passes [`MAX_DISTANCE_TO_EXTENT`], or a coordinate is
/// not finite.
pub fn extent_problem(placed: &[PlacedMesh]) -> Option<String> {
    spheres_extent_problem(&world_spheres(placed))
}

/// [`extent_problem`] of bounding spheres `(centre, radius)` in true world coordinates (the
/// placed meshes' of every frame of an animation, say).
pub fn spheres_extent_problem(spheres: &[(DVec3, f64)]) -> Option<String> {
    let &(c0, _) = spheres.first()?;
    // The extent relative to the first centre: exact differences, where the absolute bounds
    // would round the scene away at large distances.
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &(c, r) in spheres {
        lo = lo.min(c - c0 - r);
        hi = hi.max(c - c0 + r);
    }
    // The box's largest half-width (within √3 of its half-diagonal, and finite wherever the
    // box is: the diagonal's square would overflow past 1e154).
    let half = 0.5 * (hi - lo).max_element();
    let centre = c0 + 0.5 * (lo + hi);
    if !centre.is_finite() || !half.is_finite() {
        return Some(format!(
            "the scene's placed bounds are not finite (centre [{:e}, {:e}, {:e}], half-extent \
             {half:e})",
            centre.x, centre.y, centre.z
        ));
    }
    let distance = centre.abs().max_element();
    (distance > MAX_DISTANCE_TO_EXTENT * half).then(|| {
        format!(
            "the scene lies {distance:e} from the origin with a half-extent of {half:e}, a \
             ratio of {:.3e}: past {MAX_DISTANCE_TO_EXTENT:.3e}, the most at which f64 places \
             its instances relative to each other as finely as f32 resolves the scene",
            distance / half
        )
    })
}

/// Each placed mesh's bounding sphere in true world coordinates.
fn world_spheres(placed: &[PlacedMesh]) -> Vec<(DVec3, f64)> {
    placed
        .iter()
        .map(|p| {
            let s = p.mesh.bounding_sphere();
            (
                p.placement.to_world_point(s.center),
                s.radius as f64 * p.placement.scale as f64,
            )
        })
        .collect()
}

/// `mesh` moved next to its model-space origin, and the offset removed: where
/// [`rebase_origin`] of its bounding sphere is not zero (a model whose file coordinates lie far
/// from the origin), the positions minus that origin, formed in f64 and rounded once, so that
/// fields are baked and looked up at the precision of the model's size; otherwise the mesh as
/// it is and zero. Normals are kept (a translation leaves them unchanged). A mesh already
/// centred (a file rebased as it was read, [`centred_positions`]) comes back as it is, with its
/// [`Mesh::origin`]; the offset returned is always the mesh's `origin`.
pub fn centred_mesh(mut mesh: Mesh) -> (Mesh, DVec3) {
    if mesh.origin != DVec3::ZERO {
        let origin = mesh.origin;
        return (mesh, origin);
    }
    let s = mesh.bounding_sphere();
    let origin = rebase_origin(&[(s.center.as_dvec3(), s.radius as f64)]);
    if origin != DVec3::ZERO {
        for p in &mut mesh.positions {
            *p = (p.as_dvec3() - origin).as_vec3();
        }
    }
    mesh.origin = origin;
    (mesh, origin)
}

/// A mesh file's positions, read in f64, in the frame of [`rebase_origin`] of their bounding
/// box, each rounded once to f32, and that origin: a model whose coordinates lie far from its
/// file's origin keeps its shape (read as f32 first, a unit tetrahedron at x = 1e9 collapses
/// to two triangles). Positions that are not finite or lie past ±`MAX_COORDINATE` keep origin
/// zero, so that validation refuses them as it would their file coordinates.
pub fn centred_positions(positions: &[DVec3]) -> (Vec<Vec3>, DVec3) {
    let limit = super::mesh::MAX_COORDINATE as f64;
    let (lo, hi) = positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let sane = positions
        .iter()
        .all(|p| p.is_finite() && p.abs().max_element() <= limit);
    let origin = if sane && !positions.is_empty() {
        rebase_origin(&[(0.5 * (lo + hi), 0.5 * (hi - lo).length())])
    } else {
        DVec3::ZERO
    };
    let moved = positions.iter().map(|&p| (p - origin).as_vec3()).collect();
    (moved, origin)
}

/// A mesh placed in true world coordinates, with its roles (see [`Instance`]).
#[derive(Clone, Debug)]
pub struct PlacedMesh {
    pub mesh: Arc<Mesh>,
    pub placement: Placement,
    pub caster: bool,
    pub receiver: bool,
}

/// A scene in a rebased frame: `scene`'s world coordinates are true world − `origin`.
#[derive(Clone, Debug)]
pub struct Rebased {
    pub scene: Scene,
    /// The true world position of the scene's origin.
    pub origin: DVec3,
}

/// A true world point in the frame whose origin is `origin` (formed in f64, rounded once).
pub fn to_frame(origin: DVec3, p: Vec3) -> Vec3 {
    (p.as_dvec3() - origin).as_vec3()
}

/// The placed meshes as a scene in the frame of [`rebase_origin`] of their world bounding
/// spheres.
pub fn rebase(placed: &[PlacedMesh]) -> Rebased {
    let origin = rebase_origin(&world_spheres(placed));
    let instances = placed
        .iter()
        .map(|p| Instance {
            mesh: p.mesh.clone(),
            transform: p.placement.relative_to(origin),
            caster: p.caster,
            receiver: p.receiver,
        })
        .collect();
    Rebased {
        scene: Scene { instances },
        origin,
    }
}

impl Scene {
    /// This scene in a rebased frame ([`rebase`] of its instances, their transforms read as
    /// exact true-world placements).
    pub fn rebased(&self) -> Rebased {
        let placed: Vec<PlacedMesh> = self
            .instances
            .iter()
            .map(|i| PlacedMesh {
                mesh: i.mesh.clone(),
                placement: i.transform.into(),
                caster: i.caster,
                receiver: i.receiver,
            })
            .collect();
        rebase(&placed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::procedural;

    #[test]
    fn scenes_near_the_origin_keep_origin_zero() {
        assert_eq!(rebase_origin(&[(DVec3::splat(0.5), 0.87)]), DVec3::ZERO);
        assert_eq!(
            rebase_origin(&[(DVec3::new(-3.0, 2.0, 1.0), 2.0)]),
            DVec3::ZERO
        );
        assert_eq!(rebase_origin(&[]), DVec3::ZERO);
    }

    #[test]
    fn a_translation_by_a_step_multiple_is_removed_exactly() {
        let o = rebase_origin(&[(DVec3::splat(1e4 + 0.5), 0.87)]);
        assert_eq!(o, DVec3::splat(1e4));
        let o = rebase_origin(&[(DVec3::new(1048576.0, -2097152.0, 3.0), 10.0)]);
        assert_eq!(o, DVec3::new(1048576.0, -2097152.0, 0.0));
    }

    #[test]
    fn a_far_point_rebases_to_itself() {
        // A zero-radius scene at 1e7: the step is the f32 spacing there.
        let p = DVec3::new(1e7, 3.0, -1e7);
        let o = rebase_origin(&[(p, 0.0)]);
        assert!((o - p).abs().max_element() <= 1.0, "{o}");
    }

    #[test]
    fn rebased_scene_equals_the_untranslated_one() {
        let mesh = Arc::new(procedural::cube_with_hole(1.0, 0.4).unwrap());
        let inner = Similarity::new(Quat::from_rotation_y(0.7), Vec3::new(0.3, 0.2, 0.1), 0.3);
        let place = |t: f64| PlacedMesh {
            mesh: mesh.clone(),
            placement: Placement::new(Quat::IDENTITY, DVec3::splat(t), 1.0).compose(&inner),
            caster: true,
            receiver: true,
        };
        let near = rebase(&[place(0.0)]);
        let far = rebase(&[place(1e4)]);
        assert_eq!(near.origin, DVec3::ZERO);
        assert_eq!(far.origin, DVec3::splat(1e4));
        let tri = |r: &Rebased| r.scene.instances[0].world_triangles().collect::<Vec<_>>();
        assert_eq!(tri(&near), tri(&far));
        // The f32 composition at 1e4 rounds the translation; the rebased one does not.
        let f32_far = Similarity::new(Quat::IDENTITY, Vec3::splat(1e4), 1.0).compose(&inner);
        assert_ne!(f32_far.translation - Vec3::splat(1e4), inner.translation);
    }

    /// A two-instance scene (a corner and a fitted box inside it) translated as a whole by up
    /// to 1e20 keeps the untranslated scene's f32 world triangles bit for bit, as long as the
    /// translation is a multiple of the rebasing step (these are); before the large translation
    /// was kept apart from the fit's offsets, 1e12 moved the scene 61,440 away from its origin
    /// and 1e15 collapsed it. Past 2⁵⁴ half-extents from the origin the scene is refused.
    #[test]
    fn far_translations_are_removed_exactly_or_refused() {
        let corner = Arc::new(procedural::corner(3).unwrap());
        let cube = Arc::new(procedural::cube_with_hole(1.0, 0.4).unwrap());
        let fit = Similarity::new(Quat::from_rotation_y(0.7), Vec3::new(0.5, 0.45, 0.5), 0.3);
        let placed = |t: f64| {
            let outer = Placement::new(Quat::IDENTITY, DVec3::splat(t), 1.0);
            vec![
                PlacedMesh {
                    mesh: corner.clone(),
                    placement: outer.compose(&Similarity::default()),
                    caster: false,
                    receiver: true,
                },
                PlacedMesh {
                    mesh: cube.clone(),
                    placement: outer.compose(&fit),
                    caster: true,
                    receiver: false,
                },
            ]
        };
        let tris = |r: &Rebased| {
            r.scene
                .instances
                .iter()
                .flat_map(|i| i.world_triangles())
                .collect::<Vec<_>>()
        };
        let near = rebase(&placed(0.0));
        assert_eq!(near.origin, DVec3::ZERO);
        for t in [1e4, 1e9, 1e12, 1e15, 1e16] {
            assert!(extent_problem(&placed(t)).is_none(), "{t}");
            let far = rebase(&placed(t));
            assert_eq!(far.origin, DVec3::splat(t), "{t}");
            assert_eq!(tris(&far), tris(&near), "translated by {t}");
        }
        for t in [1e17, 1e20, 1e300] {
            let e = extent_problem(&placed(t)).expect("refused");
            assert!(e.contains("ratio") && e.contains("1.801e16"), "{e}");
        }
        let inf = extent_problem(&placed(f64::INFINITY)).expect("refused");
        assert!(inf.contains("not finite"), "{inf}");
    }

    #[test]
    fn centred_far_mesh_is_placed_where_it_was() {
        let near = procedural::cube_with_hole(1.0, 0.4).unwrap();
        let far_at = DVec3::new(1e4, -3e4, 0.0);
        let mut far = near.clone();
        for p in &mut far.positions {
            *p = (p.as_dvec3() + far_at).as_vec3();
        }
        let (centred, origin) = centred_mesh(far.clone());
        assert_eq!(origin, far_at);
        // The far vertices are the input (rounded to 2⁻¹⁰ at 1e4): centring removes the offset
        // exactly, leaving them within that rounding of the near mesh.
        for (c, n) in centred.positions.iter().zip(&near.positions) {
            assert!(c.distance(*n) <= 2e-3, "{c} vs {n}");
        }
        let place = Placement::from(Similarity::new(Quat::from_rotation_x(0.4), Vec3::ONE, 2.0));
        let moved = place.after_model_offset(origin);
        // Where the original placement puts the far vertices, in exact f64 arithmetic.
        let exact = |p: Vec3| {
            place.translation + place.scale as f64 * (place.rotation.as_dquat() * p.as_dvec3())
        };
        for (c, f) in centred.positions.iter().zip(&far.positions) {
            let (a, b) = (moved.to_world_point(*c), exact(*f));
            assert!((a - b).length() < 1e-5, "{a} vs {b}");
        }
        let (same, zero) = centred_mesh(near.clone());
        assert_eq!(zero, DVec3::ZERO);
        assert_eq!(same.positions, near.positions);
    }

    #[test]
    fn to_frame_and_scene_rebased_agree() {
        let mesh = Arc::new(procedural::corner(3).unwrap());
        let far = Scene {
            instances: vec![Instance {
                mesh,
                transform: Similarity::new(Quat::IDENTITY, Vec3::new(2048.0, 0.0, -4096.0), 1.0),
                caster: true,
                receiver: true,
            }],
        };
        let r = far.rebased();
        assert_eq!(r.origin, DVec3::new(2048.0, 0.0, -4096.0));
        assert_eq!(
            to_frame(r.origin, Vec3::new(2048.5, 1.0, -4096.0)),
            Vec3::new(0.5, 1.0, 0.0)
        );
    }
}
