//! Images of the displaced unit square: a pinhole camera looking at the square's centre from a
//! given angle to its normal, each pixel's ray clipped to the prism box and searched with
//! [`intersect`] (or [`exact`] for the reference; [`render_gpu`] for the GPU caster), the hit
//! shaded with the map's normal.

use super::cast::{exact, intersect, CastParams};
use super::height::HeightMap;
use super::zones::SafetyZones;
use crate::gpu::{GpuError, GpuTiming, ReliefKernel};
use crate::render::image::GrayImage;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// A view of the square `[0, 1]²` (z up), from `angle_deg` off its normal at `distance` from
/// its centre (0°: perpendicular, towards 90°: tangential), with a `fov_deg` vertical field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub angle_deg: f32,
    pub distance: f32,
    pub fov_deg: f32,
    pub width: u32,
    pub height: u32,
}

impl View {
    /// The eye and the unit ray of pixel `(x, y)`.
    pub fn ray(&self, x: u32, y: u32) -> (Vec3, Vec3) {
        let a = self.angle_deg.to_radians();
        let target = Vec3::new(0.5, 0.5, 0.25);
        let eye = target + self.distance * Vec3::new(0.0, -a.sin(), a.cos());
        let fwd = (target - eye).normalize();
        let right = Vec3::X;
        let up = right.cross(fwd).normalize();
        let th = (0.5 * self.fov_deg.to_radians()).tan();
        let aspect = self.width as f32 / self.height as f32;
        let px = ((x as f32 + 0.5) / self.width as f32 * 2.0 - 1.0) * th * aspect;
        let py = (1.0 - (y as f32 + 0.5) / self.height as f32 * 2.0) * th;
        (eye, (fwd + px * right + py * up).normalize())
    }

    /// The segment `(E, X)` of pixel `k` (row-major) through the prism, `None` where its ray
    /// misses the prism.
    pub fn segment(&self, k: u32) -> Option<(Vec3, Vec3)> {
        let (eye, d) = self.ray(k % self.width, k / self.width);
        clip_to_prism(eye, d)
    }
}

/// The entry and exit of `o + t·d` through the box `[0, 1]² × [0, 1]` (slabs).
pub fn clip_to_prism(o: Vec3, d: Vec3) -> Option<(Vec3, Vec3)> {
    let inv = d.recip();
    let (t0, t1) = (-o * inv, (Vec3::ONE - o) * inv);
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element();
    (near < far).then(|| (o + near * d, o + far * d))
}

/// One rendered image: shading (0 background), hit mask, and fetches per pixel.
pub struct ReliefFrame {
    pub image: GrayImage,
    pub hit: Vec<bool>,
    pub fetches: Vec<u32>,
}

/// Lambert shading of the surface at `(s, t)`: the map's normal from central differences one
/// texel apart, under a fixed light.
pub fn shade(map: &HeightMap, s: Vec2) -> f32 {
    let (hx, hy) = (1.0 / map.width as f32, 1.0 / map.height as f32);
    let dx = map.sample(s + Vec2::new(hx, 0.0)) - map.sample(s - Vec2::new(hx, 0.0));
    let dy = map.sample(s + Vec2::new(0.0, hy)) - map.sample(s - Vec2::new(0.0, hy));
    let n = Vec3::new(-dx / (2.0 * hx), -dy / (2.0 * hy), 1.0).normalize();
    let light = Vec3::new(-0.4, -0.5, 0.77).normalize();
    0.15 + 0.85 * n.dot(light).max(0.0)
}

/// Renders `view`: with `params` the paper's search (zones used when given and
/// `params.skips > 0`), without it the exact reference (fetches 0).
pub fn render(
    map: &HeightMap,
    zones: Option<&SafetyZones>,
    view: &View,
    params: Option<&CastParams>,
) -> ReliefFrame {
    let (w, h) = (view.width, view.height);
    let px: Vec<(f32, bool, u32)> = (0..w * h)
        .into_par_iter()
        .map(|k| {
            let Some((e, x)) = view.segment(k) else {
                return (0.0, false, 0);
            };
            let (hit, fetches) = match params {
                Some(p) => {
                    let c = intersect(map, zones, e, x, p);
                    (c.hit, c.fetches)
                }
                None => (exact(map, e, x), 0),
            };
            shade_pixel(map, e, x, hit, fetches)
        })
        .collect();
    assemble(view, px)
}

/// Renders `view` with the GPU caster (`kernel`, made for `map`); the hits are shaded on the
/// host as in [`render`].
pub fn render_gpu(
    kernel: &ReliefKernel,
    map: &HeightMap,
    view: &View,
    params: &CastParams,
) -> Result<(ReliefFrame, GpuTiming), GpuError> {
    let (w, h) = (view.width, view.height);
    let pixels: Vec<(u32, (Vec3, Vec3))> = (0..w * h)
        .filter_map(|k| view.segment(k).map(|s| (k, s)))
        .collect();
    let segments: Vec<(Vec3, Vec3)> = pixels.iter().map(|p| p.1).collect();
    let (casts, timing) = kernel.cast(&segments, params)?;
    let mut px = vec![(0.0, false, 0); (w * h) as usize];
    for (&(k, (e, x)), c) in pixels.iter().zip(&casts) {
        px[k as usize] = shade_pixel(map, e, x, c.hit, c.fetches);
    }
    Ok((assemble(view, px), timing))
}

/// A pixel's (shade, hit, fetches) for the answer `hit` on its segment `E → X`.
pub(crate) fn shade_pixel(
    map: &HeightMap,
    e: Vec3,
    x: Vec3,
    hit: Option<f32>,
    fetches: u32,
) -> (f32, bool, u32) {
    match hit {
        Some(l) => {
            let p = e + l * (x - e).normalize();
            (shade(map, Vec2::new(p.x, p.y)), true, fetches)
        }
        None => (0.0, false, fetches),
    }
}

pub(crate) fn assemble(view: &View, px: Vec<(f32, bool, u32)>) -> ReliefFrame {
    ReliefFrame {
        image: GrayImage {
            width: view.width,
            height: view.height,
            data: px.iter().map(|p| p.0).collect(),
        },
        hit: px.iter().map(|p| p.1).collect(),
        fetches: px.iter().map(|p| p.2).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prism_clipping_enters_and_leaves_the_box() {
        let (e, x) = clip_to_prism(Vec3::new(0.5, 0.5, 3.0), Vec3::NEG_Z).unwrap();
        assert!((e - Vec3::new(0.5, 0.5, 1.0)).length() < 1e-6);
        assert!((x - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        assert!(clip_to_prism(Vec3::new(2.0, 2.0, 3.0), Vec3::NEG_Z).is_none());
    }

    #[test]
    fn perpendicular_view_of_a_flat_map_is_all_hits_of_one_shade() {
        let map = HeightMap::new(4, 4, vec![0.3; 16]);
        let view = View {
            angle_deg: 0.0,
            distance: 1.5,
            fov_deg: 20.0,
            width: 16,
            height: 16,
        };
        let f = render(&map, None, &view, None);
        assert!(f.hit.iter().all(|h| *h));
        let s = shade(&map, Vec2::splat(0.5));
        assert!(f.image.data.iter().all(|v| (v - s).abs() < 1e-6));
    }
}
