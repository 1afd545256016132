//! Rendering, written against the [`crate::visibility::Visibility`] seam (ray casting or field
//! lookup behind it): the [`estimator`] seam (what a render kind computes per point: AO, the soft
//! shadows and the glossy reflections of the 2010 paper), the evaluation [`points`] (vertices
//! as in 2008, G-buffer pixels as in 2010) and the images.

pub mod ao;

use glam::Vec3;

/// `f(scratch, point index, point, normal)` at every point (rayon over points, a scratch per
/// worker; the same bits on any thread count).
///
/// # Panics
/// If `points` and `normals` differ in length (`what` names the caller).
pub(crate) fn per_point<S: Default + Send, T: Send>(
    what: &str,
    points: &[Vec3],
    normals: &[Vec3],
    f: impl Fn(&mut S, u32, Vec3, Vec3) -> T + Sync,
) -> Vec<T> {
    use rayon::prelude::*;
    assert_eq!(points.len(), normals.len(), "{what}: one normal per point");
    points
        .par_iter()
        .zip(normals.par_iter())
        .enumerate()
        .map_init(S::default, |sc, (i, (&p, &n))| f(sc, i as u32, p, n))
        .collect()
}

pub mod camera;
pub mod contact;
pub mod estimator;
pub mod image;
pub mod points;
pub mod primary;
pub mod ray_lanes;
pub mod receivers;
pub mod reflect;
pub mod shadow;
pub mod truth;
