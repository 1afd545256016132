//! The CPU ray set ([`RaySet`]) as the GPU kernels consume it: the k² local base directions,
//! identical for every point, and each point's rotation about the normal as (cos, sin),
//! computed on the host with the CPU's own arithmetic so that the kernels rotate exactly the
//! directions the CPU path traces.

use super::GpuError;
use crate::sampling::rays::RaySet;
use glam::Vec3;

/// Twin of WGSL `Receiver` (shaders/receiver.wgsl): a receiver point of the AO kernels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ReceiverGpu {
    /// Position (world space); the probe kernel's unit sphere position.
    pub position: [f32; 3],
    /// Cos of the point's rotation of the shared base directions about its normal.
    pub rotation_cos: f32,
    /// Unit normal (world space); the probe kernel's model direction.
    pub normal: [f32; 3],
    /// Sin of the point's rotation.
    pub rotation_sin: f32,
}
const _: () = assert!(std::mem::size_of::<ReceiverGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(ReceiverGpu, normal) == 16);

/// The unrotated cell-centre directions of `rays` ([`RaySet::base_directions`]), padded to
/// vec4. Jittered sets differ per point and are refused.
pub(crate) fn base_directions(rays: &RaySet) -> Result<Vec<[f32; 4]>, GpuError> {
    if rays.jitter {
        return Err(GpuError::Unsupported(
            "jittered ray sets (the GPU kernels rotate one shared set of cell centres)".into(),
        ));
    }
    Ok(rays
        .base_directions()
        .into_iter()
        .map(|d| d.extend(0.0).to_array())
        .collect())
}

/// (cos, sin) of point `point`'s rotation ([`RaySet::rotation`]).
pub(crate) fn rotation(rays: &RaySet, point: u32) -> (f32, f32) {
    let (s, c) = rays.rotation(point);
    (c, s)
}

/// Receiver records for `points` / `normals` (point i uses the rotation of index i).
pub(crate) fn receivers(
    points: &[Vec3],
    normals: &[Vec3],
    rays: &RaySet,
) -> Result<Vec<ReceiverGpu>, GpuError> {
    records(points, normals, ("points", "normals"), |i| {
        rotation(rays, i)
    })
}

/// Receiver records without a rotation (the direct estimators, which read no ray set).
pub(crate) fn unrotated_receivers(
    points: &[Vec3],
    normals: &[Vec3],
) -> Result<Vec<ReceiverGpu>, GpuError> {
    records(points, normals, ("points", "normals"), |_| (0.0, 0.0))
}

/// Receiver records for `points` and `normals` (the probe's positions and directions), the
/// lists named by `names` in the error when their lengths differ, point i turned by
/// `rotation(i)`, (cos, sin).
pub(crate) fn records(
    points: &[Vec3],
    normals: &[Vec3],
    names: (&str, &str),
    rotation: impl Fn(u32) -> (f32, f32),
) -> Result<Vec<ReceiverGpu>, GpuError> {
    if points.len() != normals.len() {
        return Err(GpuError::Invalid(format!(
            "{} {} but {} {}",
            points.len(),
            names.0,
            normals.len(),
            names.1
        )));
    }
    Ok(points
        .iter()
        .zip(normals)
        .enumerate()
        .map(|(i, (p, n))| {
            let (c, s) = rotation(i as u32);
            ReceiverGpu {
                position: p.to_array(),
                rotation_cos: c,
                normal: n.to_array(),
                rotation_sin: s,
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotated_base_directions_are_the_cpu_directions_bit_for_bit() {
        // The kernels compute (c·x − s·y, s·x + c·y, z) from these, the same expression as
        // RaySet::fill, so the f32 results are identical.
        let set = RaySet::new(8, 99);
        let base = base_directions(&set).unwrap();
        for point in [0u32, 5, 1234] {
            let (c, s) = rotation(&set, point);
            let cpu = set.directions(point);
            for (b, d) in base.iter().zip(&cpu) {
                let g = Vec3::new(c * b[0] - s * b[1], s * b[0] + c * b[1], b[2]);
                assert_eq!(g, *d, "point {point}");
            }
        }
        let jittered = RaySet {
            jitter: true,
            ..set
        };
        assert!(base_directions(&jittered).is_err());
    }
}
