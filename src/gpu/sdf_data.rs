//! Instanced distance volumes (`crate::sdf`) as the SDF kernels read them
//! (shaders/sdf_volume.wgsl): one record per distinct volume, one per instance, and every
//! volume's stored samples in one word buffer, at their stored precision (f32 samples one a
//! word, f16 two, u8 four, low bits first), decoded on the device as
//! [`crate::sdf::Samples::get`] decodes them: f32 as stored; f16 bit-exactly to f32, then times
//! the voxel; u8 through a table of the 256 codes' distances computed on the host with
//! [`crate::sdf::storage::decode_u8`] (its division by 255 is then the host's, not the driver's).

use super::field_data::push_words;
use super::GpuError;
use crate::sdf::{DistanceVolume, Samples, SdfScene};
use std::sync::Arc;

/// WGSL `SDF_F32`, `SDF_F16`, `SDF_U8`: a volume's storage precision.
const PRECISION_F32: u32 = 0;
const PRECISION_F16: u32 = 1;
const PRECISION_U8: u32 = 2;

/// Twin of WGSL `SdfVolume` (shaders/sdf_volume.wgsl): one distance volume, 80 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct SdfVolumeGpu {
    /// The grid's first sample (model space).
    pub lo: [f32; 3],
    /// The voxel's side.
    pub voxel: f32,
    /// The grid's last sample ([`DistanceVolume::hi`], computed on the host).
    pub hi: [f32; 3],
    /// The storage precision, `PRECISION_*` (WGSL `SDF_*`; `precision` is a WGSL keyword).
    pub storage: u32,
    /// Samples per axis.
    pub dims: [u32; 3],
    /// First word of the samples in the word buffer.
    pub offset: u32,
    /// The bounding sphere ([`DistanceVolume::bounding_sphere`]): centre, radius.
    pub center: [f32; 3],
    pub radius: f32,
    /// u8: first word of the 256 codes' distances (f32 bits); else 0.
    pub decode: u32,
    /// The hit threshold, `hit_voxels · voxel` (as `DistanceVolume::trace` computes it).
    pub hit: f32,
    /// Where each trace and cone starts, `start_voxels · voxel`.
    pub start: f32,
    pub _pad: u32,
}
const _: () = assert!(std::mem::size_of::<SdfVolumeGpu>() == 80);
const _: () = assert!(std::mem::offset_of!(SdfVolumeGpu, hi) == 16);
const _: () = assert!(std::mem::offset_of!(SdfVolumeGpu, dims) == 32);
const _: () = assert!(std::mem::offset_of!(SdfVolumeGpu, center) == 48);
const _: () = assert!(std::mem::offset_of!(SdfVolumeGpu, decode) == 64);

/// Twin of WGSL `SdfInstance` (shaders/sdf_volume.wgsl): a volume under a similarity, 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct SdfInstanceGpu {
    /// World → model rotation (the instance rotation's conjugate), (x, y, z, w).
    pub rotation: [f32; 4],
    pub translation: [f32; 3],
    pub scale: f32,
    /// Index of its volume record.
    pub volume: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<SdfInstanceGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(SdfInstanceGpu, translation) == 16);
const _: () = assert!(std::mem::offset_of!(SdfInstanceGpu, volume) == 32);

/// A scene's volumes packed for upload.
pub(super) struct PackedSdf {
    pub volumes: Vec<SdfVolumeGpu>,
    pub instances: Vec<SdfInstanceGpu>,
    pub words: Vec<u32>,
    /// Bytes of the stored samples (each distinct volume once), as on the host.
    pub sample_bytes: u64,
}

/// Packs `scene`'s instances, each distinct volume (by pointer) once.
///
/// Errors: [`GpuError::Invalid`] for a scene without instances, a volume of fewer than two
/// samples along an axis, or more words than a u32 index reaches.
pub(super) fn pack(scene: &SdfScene) -> Result<PackedSdf, GpuError> {
    if scene.instances.is_empty() {
        return Err(GpuError::Invalid("an SDF scene without instances".into()));
    }
    let mut seen: Vec<*const DistanceVolume> = Vec::new();
    let mut packed = PackedSdf {
        volumes: Vec::new(),
        instances: Vec::with_capacity(scene.instances.len()),
        words: Vec::new(),
        sample_bytes: 0,
    };
    for inst in &scene.instances {
        let ptr = Arc::as_ptr(&inst.volume);
        let index = match seen.iter().position(|&p| p == ptr) {
            Some(i) => i,
            None => {
                seen.push(ptr);
                packed
                    .volumes
                    .push(pack_volume(&inst.volume, scene, &mut packed.words)?);
                packed.sample_bytes += inst.volume.bytes();
                seen.len() - 1
            }
        };
        packed.instances.push(SdfInstanceGpu {
            rotation: inst.transform.rotation.inverse().to_array(),
            translation: inst.transform.translation.to_array(),
            scale: inst.transform.scale,
            volume: index as u32,
            ..Default::default()
        });
    }
    if packed.words.len() > u32::MAX as usize {
        return Err(GpuError::Invalid(format!(
            "{} words of distance samples pass a u32 index",
            packed.words.len()
        )));
    }
    Ok(packed)
}

/// One volume's record, its samples appended to `words`.
fn pack_volume(
    v: &DistanceVolume,
    scene: &SdfScene,
    words: &mut Vec<u32>,
) -> Result<SdfVolumeGpu, GpuError> {
    if v.dims.iter().any(|&n| n < 2) || v.samples.len() != v.dims.iter().product::<usize>() {
        return Err(GpuError::Invalid(format!(
            "a distance volume of dims {:?} with {} samples",
            v.dims,
            v.samples.len()
        )));
    }
    let offset = words.len() as u32;
    let mut decode = 0;
    let precision = match &v.samples {
        Samples::F32(s) => {
            words.extend(s.iter().map(|d| d.to_bits()));
            PRECISION_F32
        }
        Samples::F16 { bits, .. } => {
            push_words(words, bytemuck::cast_slice(bits));
            PRECISION_F16
        }
        Samples::U8 { codes, band } => {
            push_words(words, codes);
            decode = words.len() as u32;
            words.extend((0..=255u8).map(|e| crate::sdf::storage::decode_u8(e, *band).to_bits()));
            PRECISION_U8
        }
    };
    let (center, radius) = v.bounding_sphere();
    Ok(SdfVolumeGpu {
        lo: v.lo.to_array(),
        voxel: v.voxel,
        hi: v.hi().to_array(),
        storage: precision,
        dims: v.dims.map(|n| n as u32),
        offset,
        center: center.to_array(),
        radius,
        decode,
        hit: scene.trace.hit_voxels * v.voxel,
        start: scene.trace.start_voxels * v.voxel,
        _pad: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Similarity;
    use crate::sdf::{Precision, SdfInstance};
    use glam::{Quat, Vec3};

    /// The words decode to the host's samples at every precision, the way the WGSL reads
    /// them (`sdf_stored`): an f16 half by its bits, a u8 code through the table.
    #[test]
    fn packed_words_decode_to_the_hosts_samples() {
        let values: Vec<f32> = (0..(3 * 4 * 5))
            .map(|i| (i as f32 - 23.0) * 0.037)
            .collect();
        let base = DistanceVolume {
            lo: Vec3::new(-0.1, 0.2, 0.3),
            voxel: 0.05,
            dims: [3, 4, 5],
            samples: Samples::F32(values),
        };
        for p in Precision::ALL {
            let v = Arc::new(base.with_precision(p));
            let scene = SdfScene {
                instances: vec![
                    SdfInstance {
                        volume: v.clone(),
                        transform: Similarity::new(Quat::from_rotation_y(0.3), Vec3::X, 2.0),
                    },
                    SdfInstance {
                        volume: v.clone(),
                        transform: Similarity::default(),
                    },
                ],
                ..Default::default()
            };
            let packed = pack(&scene).unwrap();
            assert_eq!(packed.volumes.len(), 1, "one volume for two instances");
            assert_eq!(packed.sample_bytes, v.bytes());
            let rec = packed.volumes[0];
            for i in 0..v.samples.len() {
                let o = rec.offset as usize;
                let got = match rec.storage {
                    PRECISION_F32 => f32::from_bits(packed.words[o + i]),
                    PRECISION_F16 => {
                        let h = (packed.words[o + i / 2] >> (16 * (i % 2))) & 0xffff;
                        half::f16::from_bits(h as u16).to_f32() * rec.voxel
                    }
                    _ => {
                        let e = (packed.words[o + i / 4] >> (8 * (i % 4))) & 0xff;
                        f32::from_bits(packed.words[rec.decode as usize + e as usize])
                    }
                };
                assert_eq!(got.to_bits(), v.value(i).to_bits(), "{p:?} sample {i}");
            }
            assert_eq!(rec.hi, v.hi().to_array());
            assert_eq!(packed.instances[0].volume, 0);
            assert_eq!(packed.instances[1].rotation, [0.0, 0.0, 0.0, 1.0]);
        }
        assert!(pack(&SdfScene::default()).is_err());
    }
}
