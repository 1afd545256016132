//! The reflection rays of [`crate::render::reflect`] as the GPU kernels consume them
//! (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010, §4.2 and Figure 9: glossy
//! reflections whose rays the fields answer with a hit point and, through the normal fields, a
//! normal): the lobe directions, the shading, and the packed normal fields.
//!
//! The host maps the ray set's k² cell centres to the Phong lobe about +z with the CPU's own
//! arithmetic (`square_to_phong`: the GPU's `pow`, `cos` and `sin` are not the host's), shared
//! by every point; the kernels turn them by the point's rotation and take them to the world by
//! the frame of the point's mirror direction (shaders/reflect_rays.wgsl, a port of
//! `reflection_rays` and `shade` in the same f32 order).
//!
//! Deviation from the CPU path: a point's radiance is summed in f32 over the rays of one
//! invocation on the device (the host sums in f64); the host adds the invocations' sums in
//! f64 and divides by the kept rays, so the same hits give means within (m − 1)·2⁻²⁴ of each
//! other (m rays an invocation, radiances at most 1) plus the shading's own rounding.
//! Deviation from the paper: it does not give its lobe, shading or lights; these are the CPU
//! path's (`render::reflect`).

use super::GpuError;
use crate::field::normals::NormalField;
use crate::field::scene::FieldInstance;
use crate::render::reflect::{square_to_phong, Gloss, ReflectOptions};
use crate::sampling::rays::RaySet;
use std::collections::HashMap;
use std::sync::Arc;

/// Twin of WGSL `Shading` (shaders/reflect_rays.wgsl): the eye and the shading of the hits of
/// reflection rays (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010, §4.2).
/// Deviation from the paper: it gives no shading for the reflected surfaces; this is
/// `render::reflect::shade`'s (a diffuse hit lit by the lights' centres, a constant sky).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ShadingGpu {
    /// The eye the receivers are seen from (world).
    pub eye: [f32; 3],
    /// Diffuse albedo of the reflected surfaces.
    pub albedo: f32,
    /// Radiance of a ray that meets nothing.
    pub sky: f32,
    /// Σ intensity over the lights, added as `shade` adds it.
    pub light_total: f32,
    /// Lights.
    pub light_count: u32,
    /// 1: the mirror lobe, 0: the lobe directions.
    pub mirror: u32,
}
const _: () = assert!(std::mem::size_of::<ShadingGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(ShadingGpu, sky) == 16);

/// The shading of `opts`.
pub(crate) fn shading(opts: &ReflectOptions) -> ShadingGpu {
    ShadingGpu {
        eye: opts.eye.to_array(),
        albedo: opts.albedo,
        sky: opts.sky,
        light_total: opts.lights.iter().map(|l| l.intensity).sum(),
        light_count: opts.lights.len() as u32,
        mirror: matches!(opts.gloss, Gloss::Mirror) as u32,
    }
}

/// The lobe directions about +z every point shares, padded to vec4: for the mirror one
/// placeholder (the kernels trace the mirror direction itself), for a Phong lobe
/// `square_to_phong` of the cell-centre squares of `rays` ([`RaySet::fill_square`]). Jittered
/// sets differ per point and are refused for Phong lobes.
pub(crate) fn lobe_directions(rays: &RaySet, gloss: Gloss) -> Result<Vec<[f32; 4]>, GpuError> {
    match gloss {
        Gloss::Mirror => Ok(vec![[0.0, 0.0, 1.0, 0.0]]),
        Gloss::Phong { exponent } => {
            if rays.jitter {
                return Err(GpuError::Unsupported(
                    "jittered ray sets (the GPU kernels share one set of cell centres)".into(),
                ));
            }
            let mut squares = Vec::new();
            rays.fill_square(0, &mut squares);
            Ok(squares
                .iter()
                .map(|&u| square_to_phong(u, exponent).extend(0.0).to_array())
                .collect())
        }
    }
}

/// The normal fields of `instances` as the field kernel reads them (WGSL `normals`,
/// shaders/field_surface.wgsl): per instance its first texel word and its bits per component,
/// then every distinct normal field once, a texel a word (a | b << 16).
///
/// Errors: [`GpuError::Invalid`] naming the first instance without a normal field.
pub(crate) fn normal_words(instances: &[FieldInstance]) -> Result<Vec<u32>, GpuError> {
    let mut words = vec![0u32; 2 * instances.len()];
    let mut placed: HashMap<*const NormalField, u32> = HashMap::new();
    for (k, inst) in instances.iter().enumerate() {
        let normals: &Arc<NormalField> = inst.normals.as_ref().ok_or_else(|| {
            GpuError::Invalid(format!(
                "field instance {k} has no normal field: reflections read the hit's normal \
                 from it (FieldInstance::with_normals)"
            ))
        })?;
        let key = Arc::as_ptr(normals);
        let base = match placed.get(&key) {
            Some(&b) => b,
            None => {
                let b = u32::try_from(words.len())
                    .map_err(|_| GpuError::Invalid("normal fields pass 2³² words".to_string()))?;
                words.extend(
                    normals
                        .data
                        .iter()
                        .map(|&[a, b]| a as u32 | (b as u32) << 16),
                );
                placed.insert(key, b);
                b
            }
        };
        words[2 * k] = base;
        words[2 * k + 1] = normals.bits;
    }
    Ok(words)
}

/// Rays per point of `gloss` with `rays`: 1 for the mirror, k² for a Phong lobe.
pub(crate) fn rays_per_point(rays: &RaySet, gloss: Gloss) -> u32 {
    match gloss {
        Gloss::Mirror => 1,
        Gloss::Phong { .. } => rays.len() as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::normals::unpack_normal;
    use crate::render::reflect::reflection_rays;
    use crate::sampling::Frame;
    use glam::Vec3;

    #[test]
    fn lobe_directions_give_the_cpu_reflection_rays_bit_for_bit() {
        // The kernels compute r, the rotation, the frame and the normalisation as below,
        // reflection_rays' expressions in its order.
        let opts = ReflectOptions {
            offset: 1e-3,
            eye: Vec3::new(0.3, 1.2, 2.5),
            gloss: Gloss::Phong { exponent: 20.0 },
            lights: vec![],
            albedo: 0.8,
            sky: 0.3,
        };
        let set = RaySet::new(5, 3);
        let lobe = lobe_directions(&set, opts.gloss).unwrap();
        assert_eq!(lobe.len(), 25);
        let (mut squares, mut dirs) = (Vec::new(), Vec::new());
        for (i, (p, n)) in [
            (Vec3::new(0.1, 0.0, 0.2), Vec3::Y),
            (Vec3::new(-0.4, 0.3, 0.9), Vec3::new(0.6, 0.0, 0.8)),
        ]
        .into_iter()
        .enumerate()
        {
            reflection_rays(i as u32, p, n, &set, &opts, &mut squares, &mut dirs);
            let v = (p - opts.eye).normalize_or_zero();
            let r = (v - 2.0 * v.dot(n) * n).normalize_or_zero();
            let frame = Frame::from_normal(r);
            let (c, s) = super::super::rays::rotation(&set, i as u32);
            let gpu: Vec<Vec3> = lobe
                .iter()
                .map(|l| {
                    let local = Vec3::new(c * l[0] - s * l[1], s * l[0] + c * l[1], l[2]);
                    let w = frame.to_world(local);
                    w * (1.0 / w.dot(w).sqrt())
                })
                .filter(|d| n.dot(*d) > 0.0)
                .collect();
            assert_eq!(gpu, dirs, "point {i}");
        }
        let jittered = RaySet {
            jitter: true,
            ..set
        };
        assert!(lobe_directions(&jittered, opts.gloss).is_err());
        assert_eq!(lobe_directions(&jittered, Gloss::Mirror).unwrap().len(), 1);
    }

    #[test]
    fn normal_words_pack_each_field_once_and_refuse_instances_without() {
        use crate::field::scene::FieldInstance;
        use crate::field::{bake::bake_mesh_with_normals, bake::BakeOptions};
        use crate::field::{FieldParams, Precision};
        use crate::geometry::{procedural, Similarity};
        use crate::sampling::{LayoutKind, SphereKind};
        let mesh = procedural::supershape(&procedural::Supershape::default(), 200).unwrap();
        let p = FieldParams {
            sphere: SphereKind::Slater,
            count: 10,
            layout: LayoutKind::Concentric,
            res: 4,
            precision: Precision::U8,
        };
        let (f, nf, _) = bake_mesh_with_normals(&mesh, p, 16, &BakeOptions::default()).unwrap();
        let (f, nf) = (Arc::new(f), Arc::new(nf));
        let a = FieldInstance::new(f.clone(), Similarity::default()).with_normals(nf.clone());
        let b = FieldInstance::new(f.clone(), Similarity::default()).with_normals(nf.clone());
        let w = normal_words(&[a.clone(), b]).unwrap();
        assert_eq!(w.len(), 4 + nf.data.len());
        assert_eq!((w[0], w[1], w[2], w[3]), (4, 16, 4, 16));
        for (t, &[x, y]) in nf.data.iter().enumerate() {
            let word = w[4 + t];
            assert_eq!(
                unpack_normal([word & 0xffff, word >> 16], 16),
                unpack_normal([x as u32, y as u32], 16)
            );
        }
        let bare = FieldInstance::new(f, Similarity::default());
        let e = normal_words(&[a, bare]).unwrap_err().to_string();
        assert!(
            e.contains("instance 1") && e.contains("normal field"),
            "{e}"
        );
    }
}
