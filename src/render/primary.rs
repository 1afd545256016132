//! Primary visibility: which surface each pixel sees, and vertex AO shown on it.
//!
//! Deviation from the papers: they rasterise the primary pass on the GPU; here primary rays are
//! cast with the reference tracer. Both methods see the same G-buffer, so primary visibility never
//! contributes to a field's error.

use super::camera::Camera;
use super::image::GrayImage;
use crate::geometry::Scene;
use crate::trace::Tracer;
use glam::Vec3;
use rayon::prelude::*;

/// Every instance's world triangles in one tracer, with each triangle's owner.
pub struct PrimaryScene {
    pub tracer: Tracer,
    /// Per world triangle: (instance index, triangle index in the instance's mesh).
    pub owner: Vec<(u32, u32)>,
}

impl PrimaryScene {
    pub fn new(scene: &Scene) -> PrimaryScene {
        let mut tris = Vec::new();
        let mut owner = Vec::new();
        for (i, inst) in scene.instances.iter().enumerate() {
            for (t, tri) in inst.world_triangles().enumerate() {
                tris.push(tri);
                owner.push((i as u32, t as u32));
            }
        }
        PrimaryScene {
            tracer: Tracer::new(&tris),
            owner,
        }
    }
}

/// What one pixel sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelHit {
    pub instance: u32,
    pub triangle: u32,
    /// Barycentrics (u, v) of the hit on the instance's mesh triangle.
    pub u: f32,
    pub v: f32,
    pub position: Vec3,
    /// Unit geometric normal facing the camera.
    pub normal: Vec3,
}

/// The G-buffer of a view: one optional hit per pixel, row-major, row 0 at the top.
pub fn gbuffer(
    ps: &PrimaryScene,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<Option<PixelHit>> {
    (0..width * height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let d = camera.ray_dir(x, y, width, height);
            ps.tracer
                .closest_hit(camera.eye, d, 0.0, f32::INFINITY)
                .map(|h| {
                    let (instance, triangle) = ps.owner[h.triangle as usize];
                    let n = if h.normal.dot(d) > 0.0 {
                        -h.normal
                    } else {
                        h.normal
                    };
                    PixelHit {
                        instance,
                        triangle,
                        u: h.u,
                        v: h.v,
                        position: camera.eye + h.t * d,
                        normal: n,
                    }
                })
        })
        .collect()
}

/// Shows per-vertex AO of the receivers (interpolated with the hit's barycentrics, as Gouraud
/// shading would) and shades other surfaces with a fixed diffuse light, the same in every image.
/// Returns the image and the mask of pixels that show AO (the pixels RMS is computed over).
pub fn shade_vertex_ao(
    scene: &Scene,
    gbuf: &[Option<PixelHit>],
    width: u32,
    height: u32,
    vertex_ao: &[Option<Vec<f32>>],
) -> (GrayImage, Vec<bool>) {
    let light = Vec3::new(0.4, 0.8, 0.45).normalize();
    let mut img = GrayImage::new(width, height, 1.0);
    let mut mask = vec![false; gbuf.len()];
    for (i, px) in gbuf.iter().enumerate() {
        let Some(h) = px else { continue };
        let inst = &scene.instances[h.instance as usize];
        match vertex_ao.get(h.instance as usize).and_then(|a| a.as_ref()) {
            Some(ao) => {
                let [a, b, c] = inst.mesh.triangles[h.triangle as usize];
                img.data[i] = (1.0 - h.u - h.v) * ao[a as usize]
                    + h.u * ao[b as usize]
                    + h.v * ao[c as usize];
                mask[i] = true;
            }
            None => img.data[i] = 0.25 + 0.6 * h.normal.dot(light).max(0.0),
        }
    }
    (img, mask)
}
