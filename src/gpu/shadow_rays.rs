//! The shadow rays of [`crate::render::shadow`] as the GPU kernels consume them (Gaitatzes,
//! Andreadis, Papaioannou, Chrysanthou, WSCG 2010, §4.2: soft shadows from spherical lights,
//! every shadow ray a visibility query): the lights, and the point set's square samples mapped
//! to the unit disk on the host with the CPU's own arithmetic (the concentric map's sine and
//! cosine are not the GPU's), shared by every point and light. The kernels place them in each
//! light's cone, turn them by the point's rotation (src/gpu/rays.rs) and take them to the world
//! (shaders/shadow_rays.wgsl, a port of `shadow_rays` in the same f32 order).
//!
//! Deviation from the CPU path: the ray weights (intensity · n·ω · Ω / k²) are computed and
//! summed in f32 on the device (the host uses f64); the host adds up the partial sums of a
//! point's invocations in f64. The light fraction differs from the host's by a few f32
//! roundings relative (about 1e-7 per ray added) when the same rays are blocked. The f32
//! weights hold while r²/d² stays in f32's normal range, an angular radius r/d above about
//! 1e-19 (the host's f64 weights reach r/d ≈ 1e-150); a smaller light weighs 0 on the device,
//! and a point lit by it alone reads 1. Use radius 0 (a point light) for such lights.

use super::context::GpuContext;
use super::GpuError;
use crate::render::shadow::SphereLight;
use crate::sampling::rays::RaySet;
use crate::sampling::warp::square_to_concentric_disk;

/// Twin of WGSL `Light` (shaders/shadow_rays.wgsl): one spherical light
/// ([`SphereLight`]; radius 0, a point light).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LightGpu {
    /// Centre (world space).
    pub center: [f32; 3],
    /// Radius.
    pub radius: f32,
    /// Radiance.
    pub intensity: f32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}
const _: () = assert!(std::mem::size_of::<LightGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(LightGpu, intensity) == 16);

/// Twin of WGSL `ConeSample` (shaders/shadow_rays.wgsl): one square sample on the unit disk,
/// as `render::shadow::square_to_cone` uses it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ConeSampleGpu {
    /// x / ρ of the disk point (0 at the centre).
    pub azimuth_cos: f32,
    /// y / ρ of the disk point (0 at the centre).
    pub azimuth_sin: f32,
    /// ρ².
    pub radius_sq: f32,
    pub _pad0: u32,
}
const _: () = assert!(std::mem::size_of::<ConeSampleGpu>() == 16);
const _: () = assert!(std::mem::offset_of!(ConeSampleGpu, radius_sq) == 8);

/// `lights` as the kernels read them.
pub(crate) fn light_records(lights: &[SphereLight]) -> Vec<LightGpu> {
    lights
        .iter()
        .map(|l: &SphereLight| LightGpu {
            center: l.center.to_array(),
            radius: l.radius,
            intensity: l.intensity,
            ..Default::default()
        })
        .collect()
}

/// The cell-centre square samples of `rays` ([`RaySet::fill_square`], the same for every point
/// without jitter) on the unit disk: `d = square_to_concentric_disk(u)`, ρ² = |d|², and
/// d / ρ, as `square_to_cone` computes them. Jittered sets differ per point and are refused.
pub(crate) fn cone_samples(rays: &RaySet) -> Result<Vec<ConeSampleGpu>, GpuError> {
    if rays.jitter {
        return Err(GpuError::Unsupported(
            "jittered ray sets (the GPU kernels share one set of cell centres)".into(),
        ));
    }
    let mut squares = Vec::new();
    rays.fill_square(0, &mut squares);
    Ok(squares
        .iter()
        .map(|&u| {
            let d = square_to_concentric_disk(u);
            let r2 = d.length_squared();
            if r2 == 0.0 {
                // `square_to_cone` returns +z; zero azimuth terms give the kernels +z too.
                return ConeSampleGpu::default();
            }
            let r = r2.sqrt();
            ConeSampleGpu {
                azimuth_cos: d.x / r,
                azimuth_sin: d.y / r,
                radius_sq: r2,
                _pad0: 0,
            }
        })
        .collect())
}

/// [`GpuError::TooLarge`] unless `count` records of `T` fit one storage binding.
pub(crate) fn check_binding<T>(ctx: &GpuContext, what: &str, count: usize) -> Result<(), GpuError> {
    let need = (count * std::mem::size_of::<T>()) as u64;
    check_bytes(ctx, format!("{count} {what}"), need)
}

/// [`GpuError::TooLarge`] unless `need` bytes (`what`) fit one storage binding.
pub(crate) fn check_bytes(ctx: &GpuContext, what: String, need: u64) -> Result<(), GpuError> {
    let limit = ctx.max_binding();
    if need > limit {
        return Err(GpuError::TooLarge {
            what,
            need,
            limit,
            limit_name: "max_storage_buffer_binding_size",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::shadow::square_to_cone;
    use glam::Vec3;

    #[test]
    fn disk_samples_give_the_cpu_cone_directions_bit_for_bit() {
        // The kernels compute t = ρ²(1 − cos θ_max), sin θ = √max(t(2 − t), 0) and
        // (c_φ sin θ, s_φ sin θ, 1 − t): square_to_cone's expressions in its order, down to
        // the point-light limit.
        for k in [1u32, 3, 4, 7] {
            let set = RaySet::new(k, 5);
            let samples = cone_samples(&set).unwrap();
            let mut squares = Vec::new();
            set.fill_square(1234, &mut squares);
            assert_eq!(samples.len(), squares.len());
            for omc in [1.0f32, 0.7, 0.1, 1e-5, 3e-9, 1e-30, 0.0] {
                for (s, &u) in samples.iter().zip(&squares) {
                    let t = s.radius_sq * omc;
                    let sin = (t * (2.0 - t)).max(0.0).sqrt();
                    let g = Vec3::new(s.azimuth_cos * sin, s.azimuth_sin * sin, 1.0 - t);
                    assert_eq!(g, square_to_cone(u, omc), "k {k}, 1 − cos θ_max {omc}");
                }
            }
        }
        let jittered = RaySet {
            jitter: true,
            ..RaySet::new(4, 1)
        };
        assert!(cone_samples(&jittered).is_err());
    }
}
