//! Vertex ambient occlusion through the [`Visibility`] interface (Gaitatzes, Chrysanthou,
//! Papaioannou, "Presampled Visibility for Ambient Occlusion", WSCG 2008, the integral of its
//! introduction):
//!
//! `A(x, n) = 1/π ∫_Ω V(x, ω) (ω·n) dω`,
//!
//! estimated with the paper's receiver rays: `N = k²` stratified cosine-distributed directions
//! (concentric map + Malley's method, [`RaySet`]), so that the estimate is the plain fraction of
//! unoccluded rays. 1 = unoccluded, 0 = fully occluded.
//!
//! `V` is chosen by [`Falloff`]: binary (1 when no surface is hit within `max_distance`, else 0;
//! the default), or a linear falloff of the hit distance `t` within `max_distance` `d`
//! (`V = t/d`). Deviation from the paper: its falloff is an unspecified empirical function of
//! the hit distance; ours is named and applied identically to every visibility (ray cast: the
//! closest hit; field: `t_entry + 2R·D`).

use crate::sampling::rays::{PreparedRaySet, RaySet};
use crate::sampling::Frame;
use crate::visibility::Visibility;
use glam::Vec3;

/// The ray-origin offset for a scene of bounding radius `scene_radius`: `1e-4 · radius`.
///
/// Self-intersection is avoided by moving the origin along the normal by this much and tracing
/// from `t = 0`; it scales with the scene, so no absolute epsilon enters the results. At
/// `1e-4 R` it is about 1000 f32 ulps of the coordinates (`≈ 6e-8 R`), yet far below any
/// feature the papers' 8-bit distance maps resolve (`2R / 255`).
pub fn scene_epsilon(scene_radius: f32) -> f32 {
    1e-4 * scene_radius
}

/// How a hit at distance `t` occludes, within the AO radius `d` (`max_distance`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Falloff {
    /// Any hit within `d` occludes fully (`V = 0`); the papers' binary visibility.
    #[default]
    Step,
    /// A hit at `t ≤ d` occludes by `1 − t/d` (`V = t/d`): near hits count more. Needs a finite
    /// `max_distance`.
    Linear,
}

/// The ray-origin offset for a scene bounded by `bounds`: the larger of [`scene_epsilon`]`(R)`
/// and `2⁻²¹ · M`, where `M = |c|∞ + R` bounds the magnitude of every coordinate.
///
/// `2⁻²¹ · M` is 4 f32 ulps of the largest coordinate: a scene far from the origin (translated
/// by 1e4 with R ≈ 1, where an ulp is 1e-3 R) would otherwise see `point + 1e-4 R · normal` round
/// back onto the surface and hit itself. Near the origin (`M` within 200 R) the first term rules
/// and the offset is that of [`scene_epsilon`].
pub fn scene_epsilon_for(bounds: crate::geometry::Sphere) -> f32 {
    let magnitude = bounds.center.abs().max_element() + bounds.radius;
    scene_epsilon(bounds.radius).max(magnitude * 2f32.powi(-21))
}

/// The ray-origin offset of the points on one instance: [`scene_epsilon_for`] of the
/// instance's own world bounding sphere. Local geometry only: an object elsewhere in the scene,
/// however large or far, changes nothing (the harness moves each evaluation point off its
/// surface by its instance's offset, [`super::points::EvalPoints`]).
pub fn instance_epsilon(inst: &crate::geometry::Instance) -> f32 {
    scene_epsilon_for(inst.world_bounding_sphere())
}

/// Options of [`ao_at_points`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AoOptions {
    /// Hits farther than this (model units) do not occlude; `None`: any hit occludes.
    pub max_distance: Option<f32>,
    /// How far the ray origin is moved along the normal (model units); see [`scene_epsilon`].
    pub offset: f32,
    /// How a hit within `max_distance` occludes.
    pub falloff: Falloff,
}

impl AoOptions {
    /// Unbounded rays, origin offset [`scene_epsilon_for`]`(bounds)` (scale and position
    /// aware: use this for scenes read from user input), binary visibility.
    pub fn for_scene(bounds: crate::geometry::Sphere) -> AoOptions {
        AoOptions {
            max_distance: None,
            offset: scene_epsilon_for(bounds),
            falloff: Falloff::Step,
        }
    }

    /// Unbounded rays, origin offset [`scene_epsilon`]`(scene_radius)` (for scenes near the
    /// origin), binary visibility.
    pub fn for_scene_radius(scene_radius: f32) -> AoOptions {
        AoOptions {
            max_distance: None,
            offset: scene_epsilon(scene_radius),
            falloff: Falloff::Step,
        }
    }
}

/// Ambient occlusion at one receiver point: the fraction of the `rays.len()` directions of
/// point `point_index` (in the frame of the unit normal `normal`) that leave
/// `point + offset·normal` without hitting anything within `max_distance`.
/// `scratch` holds the directions (reused between calls). An empty ray set gives 1. The rays
/// go to [`Visibility::occluded_many`] in blocks of 256.
pub fn ao_at_point<V: Visibility + ?Sized>(
    vis: &V,
    point_index: u32,
    point: Vec3,
    normal: Vec3,
    rays: &PreparedRaySet,
    opts: &AoOptions,
    scratch: &mut Vec<Vec3>,
) -> f32 {
    debug_assert!(
        (normal.length() - 1.0).abs() < 1e-3,
        "normal must be unit, got {normal}"
    );
    if rays.set.is_empty() {
        return 1.0;
    }
    let frame = Frame::from_normal(normal);
    let origin = point + opts.offset * normal;
    let tmax = opts.max_distance.unwrap_or(f32::INFINITY);
    match opts.falloff {
        Falloff::Step => {
            rays.fill_world(point_index, &frame, scratch);
            // All rays share the origin: one batched query per block of directions.
            let mut blocked = [false; 256];
            let mut free = 0;
            for dirs in scratch.chunks(blocked.len()) {
                let out = &mut blocked[..dirs.len()];
                vis.occluded_many(origin, dirs, 0.0, tmax, out);
                free += out.iter().filter(|&&b| !b).count();
            }
            free as f32 / scratch.len() as f32
        }
        Falloff::Linear => {
            debug_assert!(tmax.is_finite(), "a linear falloff needs a max distance");
            rays.fill(point_index, scratch);
            let visible: f32 = scratch
                .iter()
                .map(|&local| {
                    vis.hit_distance(origin, frame.to_world(local), 0.0, tmax)
                        .map_or(1.0, |t| (t / tmax).clamp(0.0, 1.0))
                })
                .sum();
            visible / scratch.len() as f32
        }
    }
}

/// Ambient occlusion at every point (point `i` uses the directions of point index `i`), in
/// parallel over points. The result depends only on the inputs, not on the thread count.
///
/// # Panics
/// If `points` and `normals` differ in length.
pub fn ao_at_points<V: Visibility + ?Sized>(
    vis: &V,
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
    opts: &AoOptions,
) -> Vec<f32> {
    let prepared = rays.prepare();
    super::per_point(
        "ao_at_points",
        points,
        normals,
        |scratch: &mut Vec<Vec3>, i, p, n| ao_at_point(vis, i, p, n, &prepared, opts, scratch),
    )
}

#[cfg(test)]
#[path = "ao_tests.rs"]
mod tests;
