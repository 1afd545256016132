//! Rays for the batched-query tests (`tests/shadow_batch.rs`, `tests/reflect_batch.rs`):
//! adversarial directions and origins about a field scene's first instance.

use glam::Vec3;
use visfield::field::scene::FieldScene;
use visfield::geometry::Mesh;
use visfield::sampling::rays::seeded_sphere_direction;

/// `rays` unit directions from `origin`: random ones, and toward the first instance's sphere,
/// around its outline as seen from the origin (radii 1 ± 2e-4 in steps of 1e-6) and inside it.
pub fn directions(scene: &FieldScene, origin: Vec3, seed: u64, rays: usize) -> Vec<Vec3> {
    let (c, r) = (
        scene.instances[0].world_center,
        scene.instances[0].world_radius,
    );
    let to = (c - origin).normalize_or(Vec3::Z);
    let dist = (c - origin).length();
    (0..rays as u64)
        .map(|i| {
            let side = seeded_sphere_direction(i, seed + 1)
                .reject_from_normalized(to)
                .normalize_or(to.any_orthonormal_vector());
            match i % 4 {
                0 => seeded_sphere_direction(i, seed),
                1 if dist > r => {
                    let k = 1.0 + 1e-6 * ((i / 4 % 401) as f32 - 200.0);
                    (c + k * r * side - origin).normalize()
                }
                _ => (c + r * 0.95 * seeded_sphere_direction(i, seed + 2) - origin).normalize(),
            }
        })
        .collect()
}

/// Origins around the first instance (outside and inside its sphere), far away, and on its
/// surface (the caster's vertices pushed out by 1e-3 R: intra-object rays).
pub fn origins(scene: &FieldScene, mesh: &Mesh) -> Vec<Vec3> {
    let inst = &scene.instances[0];
    let (c, r) = (inst.world_center, inst.world_radius);
    let mut v: Vec<Vec3> = (0..6u64)
        .map(|i| c + 3.0 * r * seeded_sphere_direction(i, 3) * ((1 + i % 3) as f32 / 3.0))
        .collect();
    v.push(c + 300.0 * r * seeded_sphere_direction(7, 4));
    v.extend((0..mesh.positions.len()).step_by(499).map(|j| {
        let p = inst.transform.to_world_point(mesh.positions[j]);
        p + 1e-3 * r * (p - c).normalize_or_zero()
    }));
    v
}
