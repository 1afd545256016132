//! Ambient occlusion fields on the GPU (J. Kontkanen, S. Laine, "Ambient Occlusion Fields",
//! I3D 2005; the core's [`crate::aofield`]): the occluders' cube maps uploaded once at their
//! stored precision, one invocation per receiver point evaluating every instance's cap and
//! blending them multiplicatively (shaders/aofield.wgsl), as [`AoFieldScene::ao`].
//!
//! A direct estimator (no ray, no visibility) on the integrands' group 0 ([`KernelGroup`],
//! src/gpu/integrand.rs), with the field records, the instances, the stored channels and its
//! own header (the inside blend's constants and the instance count) as the kernel's own inputs.
//! Up to the cap's solid angle Ω̃ and n·Υ̃, the kernel is the CPU's f32 code operation for
//! operation: the model-space point and normal (glam's rotation), the cube map's face, texels
//! and bilinear weights (`Cube::bilinear`), the channels decoded as `Stored::texel` decodes
//! them (f16 bit-exactly, u8 as lo + code · step) and summed in the CPU's order, the hull's
//! distance and the cap's axis (glam's `try_normalize`).
//!
//! **What differs, and by how much.** The CPU evaluates the solid angle's quadratic
//! q = (a s + b) s + c and the cap's occlusion in f64 (`Quadratic::omega`, `cap::cap_occlusion`
//! with acos and atan2); WGSL has no f64 and its transcendental functions have driver-defined
//! accuracy (Vulkan allows atan 4096 ulp), so the device evaluates both in f32 with only
//! +, −, ×, ÷ and √: q by Horner's rule (within 4 cond(q) u of q, cond(q) = (|a|s² + |b|s +
//! |c|) / |q|, u = 2⁻²⁴), and the clipped cap with its terms rewritten in δ = sin²α − cos²θ,
//! πÃ = cos θ sin²α atan2(√δ, −cos α cos θ) − cos α √δ + atan2(√δ, cos α) (the same value:
//! with the CPU's x = cot α, y = −x cot θ, s = sin θ √(1 − y²) = √δ / sin α, acos y =
//! atan2(√δ, −cos α cos θ), x s sin²α = cos α √δ, atan(s / x) = atan2(√δ, cos α)), whose
//! derivative in √δ vanishes where δ is consistent with cos α and cos θ, so the rounding of δ
//! near the horizon (where the CPU's own 1 − y² cancels) costs O(u), not O(√u); the arctangent
//! is Cephes' `atanf` (range reduction and a degree-9 odd polynomial, peak relative error
//! 1.9·10⁻⁷). tests/gpu_peers.rs derives the per-point bound from these and checks it; with
//! p ≠ 1 the inside blend uses WGSL's `pow` (p = 1, the default, needs none).
//!
//! Deviation from the CPU path on the device: f16 texels take four words and u8 texels two
//! (the CPU's bytes, [`AoFieldKernel::field_bytes`], are the stored values'), and every
//! field's u8 `lo` and `step` follow its texels.

use super::context::GpuContext;
use super::field_data::push_words;
use super::integrand::{timing, IntegrandParamsGpu, KernelGroup, HEADER_WGSL, RECEIVER_WGSL};
use super::loop_budget::CUT_SHORT;
use super::rays::unrotated_receivers;
use super::{GpuError, GpuTiming};
use crate::aofield::storage::{Stored, CHANNELS};
use crate::aofield::{AoField, AoFieldScene};
use glam::Vec3;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// WGSL `AO_F32`, `AO_F16`, `AO_U8`.
const STORED_F32: u32 = 0;
const STORED_F16: u32 = 1;
const STORED_U8: u32 = 2;

/// Twin of WGSL `AoFieldRecord` (shaders/aofield.wgsl): one occluder's field, 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct AoFieldGpu {
    /// The occluder's bounding sphere (model space): the field's centre and unit.
    center: [f32; 3],
    radius: f32,
    /// Texels per face side.
    res: u32,
    /// `STORED_*`.
    storage: u32,
    /// First word of the texels.
    offset: u32,
    /// u8: first word of `lo` (7 f32), then `step` (7 f32); else 0.
    decode: u32,
}
const _: () = assert!(std::mem::size_of::<AoFieldGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(AoFieldGpu, res) == 16);

/// Twin of WGSL `AoFieldInstance` (shaders/aofield.wgsl): a field under a similarity, 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct AoFieldInstanceGpu {
    /// World → model rotation (the instance rotation's conjugate), (x, y, z, w).
    rotation: [f32; 4],
    translation: [f32; 3],
    scale: f32,
    /// Index of its field record.
    field: u32,
    _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<AoFieldInstanceGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(AoFieldInstanceGpu, field) == 32);

/// Twin of WGSL `AoInside`: A₀ and p of the blend inside the hull, 16 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct AoInsideGpu {
    ao: f32,
    power: f32,
    /// Instances.
    instance_count: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<AoInsideGpu>() == 16);

/// The kernel's own inputs: fields, instances, words, the inside blend.
const OWN_INPUTS: u32 = 4;

/// AO fields on the device and their kernel.
pub struct AoFieldKernel<'a> {
    ctx: &'a GpuContext,
    group: KernelGroup,
    pipeline: wgpu::ComputePipeline,
    own: [wgpu::Buffer; OWN_INPUTS as usize],
    instance_count: u32,
    field_bytes: u64,
    setup: Duration,
}

/// One field's texels appended to `words` at its precision; its record.
fn pack_field(f: &AoField, words: &mut Vec<u32>) -> AoFieldGpu {
    let offset = words.len() as u32;
    let mut decode = 0;
    let storage = match &f.stored {
        Stored::F32(texels) => {
            words.extend(texels.iter().flatten().map(|c| c.to_bits()));
            STORED_F32
        }
        // Each texel from a new word.
        Stored::F16(texels) => {
            for t in texels {
                push_words(words, bytemuck::cast_slice(&t.map(|h| h.to_bits())));
            }
            STORED_F16
        }
        Stored::U8 { codes, lo, step } => {
            for c in codes {
                push_words(words, c);
            }
            decode = words.len() as u32;
            words.extend(lo.iter().chain(step).map(|x| x.to_bits()));
            STORED_U8
        }
    };
    AoFieldGpu {
        center: f.bounds.center.to_array(),
        radius: f.bounds.radius,
        res: f.cube.res as u32,
        storage,
        offset,
        decode,
    }
}

impl<'a> AoFieldKernel<'a> {
    /// Packs and uploads `scene`'s fields (each distinct field once), instances and inside
    /// blend, and compiles the kernel.
    ///
    /// Errors: [`GpuError::Invalid`] for a scene without instances or a field of no texel,
    /// [`GpuError::TooLarge`] where the texels pass the adapter's storage binding limit.
    pub fn new(ctx: &'a GpuContext, scene: &AoFieldScene) -> Result<Self, GpuError> {
        let start = Instant::now();
        if scene.instances.is_empty() {
            return Err(GpuError::Invalid(
                "an AO field scene without instances".into(),
            ));
        }
        let mut seen: Vec<*const AoField> = Vec::new();
        let (mut fields, mut instances, mut words) = (Vec::new(), Vec::new(), Vec::new());
        let mut field_bytes = 0;
        for inst in &scene.instances {
            let ptr = Arc::as_ptr(&inst.field);
            let index = match seen.iter().position(|&p| p == ptr) {
                Some(i) => i,
                None => {
                    let f = &inst.field;
                    if f.cube.res == 0 || f.stored.len() != f.cube.len() {
                        return Err(GpuError::Invalid(format!(
                            "an AO field of res {} with {} texels",
                            f.cube.res,
                            f.stored.len()
                        )));
                    }
                    seen.push(ptr);
                    fields.push(pack_field(f, &mut words));
                    field_bytes += f.bytes();
                    seen.len() - 1
                }
            };
            instances.push(AoFieldInstanceGpu {
                rotation: inst.transform.rotation.inverse().to_array(),
                translation: inst.transform.translation.to_array(),
                scale: inst.transform.scale,
                field: index as u32,
                _pad: [0; 3],
            });
        }
        let need = words.len() as u64 * 4;
        let limit = ctx.max_binding();
        if need > limit || words.len() > u32::MAX as usize {
            return Err(GpuError::TooLarge {
                what: format!("{} AO fields' texels", fields.len()),
                need,
                limit,
                limit_name: "max_storage_buffer_binding_size",
            });
        }
        let inside = AoInsideGpu {
            ao: scene.inside.ao,
            power: scene.inside.power,
            instance_count: instances.len() as u32,
            _pad: 0,
        };
        let group = KernelGroup::new(ctx, "aofield", OWN_INPUTS);
        let mut parts = HEADER_WGSL.to_vec();
        parts.extend([RECEIVER_WGSL, include_str!("../../shaders/aofield.wgsl")]);
        let pipeline = group.pipeline(ctx, &parts.concat(), "aofield_main", &[])?;
        let own = [
            ctx.storage_buffer("ao fields", bytemuck::cast_slice(&fields)),
            ctx.storage_buffer("ao field instances", bytemuck::cast_slice(&instances)),
            ctx.storage_buffer("ao field texels", bytemuck::cast_slice(&words)),
            ctx.storage_buffer("ao inside", bytemuck::bytes_of(&inside)),
        ];
        Ok(AoFieldKernel {
            ctx,
            group,
            pipeline,
            own,
            instance_count: instances.len() as u32,
            field_bytes,
            setup: start.elapsed(),
        })
    }

    /// Host time of packing, uploading and compiling in [`Self::new`].
    pub fn setup_time(&self) -> Duration {
        self.setup
    }

    /// Bytes the CPU's fields take ([`AoFieldScene::bytes`]).
    pub fn field_bytes(&self) -> u64 {
        self.field_bytes
    }

    /// AO at every point (unit normals), as [`AoFieldScene::ao_at_points`].
    ///
    /// Errors: [`GpuError::Invalid`] when points and normals differ in length,
    /// [`GpuError::Unsupported`] when the driver cut an invocation short.
    pub fn ao(&self, points: &[Vec3], normals: &[Vec3]) -> Result<(Vec<f32>, GpuTiming), GpuError> {
        let start = Instant::now();
        let recv = unrotated_receivers(points, normals)?;
        let params = IntegrandParamsGpu::new(0, 0.0);
        let own: Vec<&wgpu::Buffer> = self.own.iter().collect();
        let (words, kernel, upload) =
            self.group
                .run(self.ctx, &self.pipeline, &[], params, &recv, &own, (1, 1))?;
        if words.contains(&CUT_SHORT) {
            return Err(GpuError::Unsupported(format!(
                "{} AO field instances overrun the driver's loop budget per invocation",
                self.instance_count
            )));
        }
        let ao = words.into_iter().map(f32::from_bits).collect();
        Ok((ao, timing(kernel, upload, start)))
    }
}

/// The channels a texel stores (the kernel reads `CHANNELS` of them).
const _: () = assert!(CHANNELS == 7);

#[cfg(test)]
mod tests {
    use crate::aofield::cap::cap_occlusion;

    /// shaders/aofield.wgsl's `atan_cephes`, `atan2_upper` and `cap_occlusion_f32`, in f32 on
    /// the host (the same operations; the host's division and square root are IEEE, as
    /// lavapipe's).
    #[allow(clippy::excessive_precision)]
    fn atan_cephes(x: f32) -> f32 {
        let (y0, t) = if x > 2.414213562373095 {
            (std::f32::consts::FRAC_PI_2, -1.0 / x)
        } else if x > 0.4142135623730950 {
            (std::f32::consts::FRAC_PI_4, (x - 1.0) / (x + 1.0))
        } else {
            (0.0, x)
        };
        let z = t * t;
        y0 + ((((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z
            - 3.33329491539e-1)
            * z
            * t
            + t)
    }

    fn atan2_upper(y: f32, x: f32) -> f32 {
        if x > 0.0 {
            atan_cephes(y / x)
        } else if x < 0.0 {
            std::f32::consts::PI - atan_cephes(y / -x)
        } else {
            0.5 * std::f32::consts::PI
        }
    }

    fn small_cap_f32(cos_a: f32, cos_t: f32) -> f32 {
        let sin2_a = (1.0 - cos_a * cos_a).max(0.0);
        if cos_t * cos_t >= sin2_a {
            return sin2_a * cos_t.max(0.0);
        }
        let u = (sin2_a - cos_t * cos_t).sqrt();
        let e = cos_t * sin2_a * atan2_upper(u, -cos_a * cos_t) - cos_a * u + atan2_upper(u, cos_a);
        (e / std::f32::consts::PI).clamp(0.0, 1.0)
    }

    fn cap_occlusion_f32(omega: f32, cos_theta: f32) -> f32 {
        let tau = std::f32::consts::TAU;
        let omega = omega.clamp(0.0, 2.0 * tau);
        let cos_t = cos_theta.clamp(-1.0, 1.0);
        let cos_a = 1.0 - omega / tau;
        if cos_a < 0.0 {
            1.0 - small_cap_f32(-cos_a, -cos_t)
        } else {
            small_cap_f32(cos_a, cos_t)
        }
    }

    /// The rewritten closed form in f32 against the CPU's f64 form over a dense grid of solid
    /// angles and normals (denser near the horizon cases' edges, cos θ = ±sin α), within
    /// `E_CAP` = 16 u (tests/gpu_peers.rs derives it): the bound the parity test allows per
    /// occluder for the closed form.
    #[test]
    fn the_f32_cap_is_the_f64_cap_within_sixteen_ulps_of_one() {
        let u = f32::EPSILON / 2.0;
        let mut worst = 0.0f32;
        let n = 600;
        for i in 0..=n {
            let omega = 2.0 * std::f32::consts::TAU * i as f32 / n as f32;
            let cos_a = 1.0 - omega as f64 / std::f64::consts::TAU;
            let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt() as f32;
            let mut cosines: Vec<f32> = (0..=n).map(|j| -1.0 + 2.0 * j as f32 / n as f32).collect();
            // Around the edges of the clipped case, a few ulps to a thousandth away.
            for edge in [sin_a, -sin_a] {
                for k in 0..40 {
                    let d = 1e-7 * 1.5f32.powi(k);
                    cosines.extend([
                        edge - d,
                        edge + d,
                        f32::from_bits(edge.to_bits() + k as u32),
                    ]);
                }
            }
            for c in cosines {
                let gpu = cap_occlusion_f32(omega, c);
                let cpu = cap_occlusion(omega as f64, c as f64) as f32;
                worst = worst.max((gpu - cpu).abs());
            }
        }
        eprintln!("largest |f32 cap − f64 cap| {worst:e} = {} u", worst / u);
        assert!(worst <= 16.0 * u, "{worst:e}");
        // And not exactly the same function: f32 rounding shows.
        assert!(worst > 0.0);
    }
}
