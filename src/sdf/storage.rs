//! How a distance volume stores its samples, as engines store mesh distance fields:
//!
//! - **f32**: the baked distances themselves (4 bytes a sample).
//! - **f16**: IEEE half floats (2 bytes), as Unreal Engine 4 stored mesh distance fields (a
//!   `PF_R16F` volume texture; `r.DistanceFieldBuild.EightBit` off, its default). Stored in
//!   units of the volume's voxel (d / voxel), so that the relative precision, 2⁻¹¹, does not
//!   depend on the mesh's units. Deviation from the source: UE4 stores local-space units
//!   (centimetres, where meshes are tens to thousands of units across).
//! - **u8**: a signed distance normalised to a band about the surface, as Unreal Engine 5's
//!   mesh distance fields (`DistanceField::DistanceFieldFormat = PF_G8`,
//!   `BandSizeInVoxels = 4` in `DistanceFieldAtlas.h`; the encoding in
//!   `MeshDistanceFieldUtilities.cpp`): the band is M = 4 × the voxel's diagonal
//!   (`MaxDistanceForEncoding = |VoxelSize| · BandSizeInVoxels`, √3 · 4 voxels for our cubic
//!   voxels), a distance d is stored as `clamp(⌊(d + M) / 2M · 255 + ½⌋, 0, 255)` and read as
//!   `e · 2M / 255 − M` (`DistanceFieldToVolumeScaleBias = (2M, −M)`). Deviation from the
//!   source: UE5 keeps only the 8³ bricks within the band (a sparse volume with an indirection
//!   table) and three mips; we store every sample of one mip, so our bytes are the dense
//!   volume's.
//!
//! Reading errors (the bounds tests/sdf.rs holds): an f16 sample is within 2⁻¹¹ |d| + 2⁻²⁵
//! voxel of the f32 one (round to nearest, 11 significant bits; the subnormal spacing below
//! 2⁻¹⁴); a u8 sample is within M/255 (half a step) of the f32 distance clamped to [−M, M].
//! Trilinear interpolation is a convex combination, so an interpolated read keeps its samples'
//! bound.
//!
//! What it does to sphere tracing: a step is the read distance. With u8, a far read is capped at
//! M (about 6.9 voxels), so far steps are short but never longer than the true distance; a near
//! read may exceed it by M/255 (about 0.027 voxel), a step's overshoot at most that. With f16 a
//! step may exceed the true distance by 2⁻¹¹ of itself. Both are far below the hit threshold
//! (a quarter voxel by default), so a trace cannot step through a surface that f32 would hit
//! unless it grazes it within that overshoot.
//!
//! What it does to cone tracing (`super::cone`): a cone's step visibility is d / (t tan θ);
//! past the band a u8 read is M however far the surface is, so wherever the cone's radius
//! t tan θ exceeds M the step reads at most M / (t tan θ) < 1: cones darken away from the
//! surfaces, the more the finer the volume (M is four voxel diagonals). Not conservative for
//! AO, and stated as such: the engines trace far occlusion through a coarser representation
//! (UE5's global distance field) rather than a mesh's u8 band.

use half::f16;
use serde::{Deserialize, Serialize};

/// A volume's storage precision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    F32,
    F16,
    U8,
}

impl Precision {
    /// Every precision, widest first.
    pub const ALL: [Precision; 3] = [Precision::F32, Precision::F16, Precision::U8];

    /// Its name in specs and tables.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
            Precision::U8 => "u8",
        }
    }

    /// The precision named `s`.
    pub fn parse(s: &str) -> Option<Precision> {
        Precision::ALL.into_iter().find(|p| p.name() == s)
    }

    /// Bytes of one sample.
    pub fn bytes_per_sample(self) -> usize {
        match self {
            Precision::F32 => 4,
            Precision::F16 => 2,
            Precision::U8 => 1,
        }
    }
}

/// UE5's band of the u8 encoding, in voxel diagonals (`BandSizeInVoxels`).
pub const BAND_VOXELS: f32 = 4.0;

/// The u8 band M of a volume of cubic voxels of side `voxel`: 4 voxel diagonals.
#[inline]
pub fn band(voxel: f32) -> f32 {
    BAND_VOXELS * 3f32.sqrt() * voxel
}

/// The u8 code of distance `d` in the band `m` (UE5's `QuantizeDistance`).
#[inline]
pub fn encode_u8(d: f32, m: f32) -> u8 {
    ((d + m) / (2.0 * m) * 255.0 + 0.5)
        .floor()
        .clamp(0.0, 255.0) as u8
}

/// The distance of u8 code `e` in the band `m`: (e / 255) · 2m − m (UE5's
/// `DistanceFieldToVolumeScaleBias` applied to the normalised texel; the codes 0 and 255 read
/// −m and m exactly).
#[inline]
pub fn decode_u8(e: u8, m: f32) -> f32 {
    e as f32 / 255.0 * (2.0 * m) - m
}

/// The samples of a volume, x fastest.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    F32(Vec<f32>),
    /// Half-float bits of d / `voxel`.
    F16 {
        bits: Vec<u16>,
        voxel: f32,
    },
    /// Codes of d in the band `band` ([`encode_u8`]).
    U8 {
        codes: Vec<u8>,
        band: f32,
    },
}

impl Samples {
    /// `values` (f32 distances of a volume of voxel side `voxel`) stored at `precision`.
    pub fn encode(values: &[f32], precision: Precision, voxel: f32) -> Samples {
        match precision {
            Precision::F32 => Samples::F32(values.to_vec()),
            Precision::F16 => Samples::F16 {
                bits: values
                    .iter()
                    .map(|&d| f16::from_f32(d / voxel).to_bits())
                    .collect(),
                voxel,
            },
            Precision::U8 => {
                let m = band(voxel);
                Samples::U8 {
                    codes: values.iter().map(|&d| encode_u8(d, m)).collect(),
                    band: m,
                }
            }
        }
    }

    /// The precision they are stored at.
    pub fn precision(&self) -> Precision {
        match self {
            Samples::F32(_) => Precision::F32,
            Samples::F16 { .. } => Precision::F16,
            Samples::U8 { .. } => Precision::U8,
        }
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        match self {
            Samples::F32(v) => v.len(),
            Samples::F16 { bits, .. } => bits.len(),
            Samples::U8 { codes, .. } => codes.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes of the stored samples (exactly: samples × bytes per sample).
    pub fn bytes(&self) -> u64 {
        (self.len() * self.precision().bytes_per_sample()) as u64
    }

    /// Sample `i`, decoded to a distance.
    #[inline]
    pub fn get(&self, i: usize) -> f32 {
        match self {
            Samples::F32(v) => v[i],
            Samples::F16 { bits, voxel } => f16::from_bits(bits[i]).to_f32() * voxel,
            Samples::U8 { codes, band } => decode_u8(codes[i], *band),
        }
    }

    /// The stored bytes, little-endian (the cache's payload).
    pub fn to_bytes(&self) -> Vec<u8> {
        #[cfg(not(target_endian = "little"))]
        compile_error!("the SDF cache assumes a little-endian machine");
        match self {
            Samples::F32(v) => bytemuck::cast_slice(v).to_vec(),
            Samples::F16 { bits, .. } => bytemuck::cast_slice(bits).to_vec(),
            Samples::U8 { codes, .. } => codes.clone(),
        }
    }

    /// Samples at `precision` from their stored bytes (a volume of voxel side `voxel`); none
    /// when the length is not a whole number of samples or an f32 sample is not finite.
    pub fn from_bytes(bytes: &[u8], precision: Precision, voxel: f32) -> Option<Samples> {
        if !bytes.len().is_multiple_of(precision.bytes_per_sample()) {
            return None;
        }
        Some(match precision {
            Precision::F32 => {
                let v: Vec<f32> = bytemuck::pod_collect_to_vec(bytes);
                if !v.iter().all(|d| d.is_finite()) {
                    return None;
                }
                Samples::F32(v)
            }
            Precision::F16 => Samples::F16 {
                bits: bytemuck::pod_collect_to_vec(bytes),
                voxel,
            },
            Precision::U8 => Samples::U8 {
                codes: bytes.to_vec(),
                band: band(voxel),
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn u8_codes_round_trip_within_half_a_step_and_clamp_to_the_band() {
        let m = band(0.1);
        // Every code decodes to a distance that encodes back to it.
        for e in 0..=255u8 {
            assert_eq!(encode_u8(decode_u8(e, m), m), e);
        }
        assert_eq!(encode_u8(-10.0 * m, m), 0);
        assert_eq!(encode_u8(10.0 * m, m), 255);
        assert_eq!(decode_u8(255, m), m);
        let mut worst = 0.0f32;
        for i in 0..=10_000 {
            let d = -1.2 * m + 2.4 * m * i as f32 / 10_000.0;
            worst = worst.max((decode_u8(encode_u8(d, m), m) - d.clamp(-m, m)).abs());
        }
        // Half a step, 2m/255 / 2, up to f32 rounding of the code's arithmetic; and reached.
        let half = m / 255.0;
        assert!(
            worst <= half * (1.0 + 1e-4) && worst > 0.99 * half,
            "{worst} {half}"
        );
    }

    #[test]
    fn f16_keeps_eleven_bits_in_voxel_units() {
        let voxel = 1e-3f32; // a mesh in metres at a millimetre voxel: no f16 trouble
        let values: Vec<f32> = (0..2000).map(|i| (i as f32 - 1000.0) * 0.37e-3).collect();
        let s = Samples::encode(&values, Precision::F16, voxel);
        for (i, &d) in values.iter().enumerate() {
            let bound = 2f32.powi(-11) * d.abs() + 2f32.powi(-25) * voxel;
            assert!((s.get(i) - d).abs() <= bound * 1.0001, "{d}: {}", s.get(i));
        }
        assert_eq!(s.bytes(), 4000);
    }

    #[test]
    fn stored_bytes_read_back_as_the_same_samples() {
        let values: Vec<f32> = (0..100).map(|i| (i as f32 - 50.0) * 0.01).collect();
        for p in Precision::ALL {
            let s = Samples::encode(&values, p, 0.02);
            let bytes = s.to_bytes();
            assert_eq!(bytes.len() as u64, s.bytes());
            assert_eq!(Samples::from_bytes(&bytes, p, 0.02), Some(s));
            assert_eq!(Precision::parse(p.name()), Some(p));
        }
        assert!(Samples::from_bytes(&[0; 7], Precision::F32, 0.02).is_none());
        let nan = f32::NAN.to_le_bytes();
        assert!(Samples::from_bytes(&nan, Precision::F32, 0.02).is_none());
    }
}
