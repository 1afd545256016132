//! Images of the displaced unit square: a distant (orthographic) eye above the prism's lid
//! looking down at a given angle from the normal, one ray per pixel from the lid `z = 1` clipped
//! to the prism and searched with [`intersect`] (or [`exact`] for the reference; [`render_gpu`]
//! for the GPU caster), the hit shaded with the map's normal.

use super::cast::{exact, intersect, Cast, CastParams};
use super::height::HeightMap;
use super::zones::SafetyZones;
use crate::render::image::GrayImage;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// The prism's height relative to the square's side in the world (the displacement scale):
/// a view's angle is taken in the world, where the relief is this thin.
///
/// Deviation from the paper: it does not state its displacement scale; with a prism as high as
/// it is wide (1) no ray from the lid reaches the `simple` map (heights 0.25–0.75) at 75°
/// before leaving through a side wall, while at ¼ a 75° ray crosses 0.93 of the square per unit
/// of height, so the tangential views look across the surface.
pub const DEPTH: f32 = 0.25;

/// The azimuth of every view (degrees from the t axis towards s): off the texel grid's axes,
/// so that no column of pixels runs along a row of texel centres.
pub const AZIMUTH_DEG: f32 = 20.0;

/// A view of the square `[0, 1]²` (z up) from a distant eye at `angle_deg` off its normal (0°:
/// perpendicular, towards 90°: tangential; in the world, where the prism is `depth` high for a
/// side of 1), looking along +t turned [`AZIMUTH_DEG`] towards +s.
/// Pixel `(x, y)` is the ray that enters the prism through the lid at the point
/// `lo + ((x + ½)/width, 1 − (y + ½)/height)·(hi − lo)` of the window `[lo, hi]` (the whole lid,
/// or a part of it for a close-up), so every ray enters through the lid going down, as the
/// paper's views from above the surface do (§5: perpendicular to nearly tangential).
///
/// Deviation from the paper: its views are perspective images of the rasterised prism; here
/// the eye is at infinity (parallel rays) and the image is the lid's window resampled on a
/// regular grid, i.e. the orthographic image stretched by 1/cos θ along the view's tilt, so
/// every pixel stands for the same area of the lid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub angle_deg: f32,
    /// The lid window the image covers, `(s, t)` corners.
    pub lo: Vec2,
    pub hi: Vec2,
    /// The prism's world height over its side ([`DEPTH`] in the experiment).
    pub depth: f32,
    pub width: u32,
    pub height: u32,
}

impl View {
    /// The whole lid at `size × size` pixels, the prism [`DEPTH`] high.
    pub fn lid(angle_deg: f32, size: u32) -> View {
        View {
            angle_deg,
            lo: Vec2::ZERO,
            hi: Vec2::ONE,
            depth: DEPTH,
            width: size,
            height: size,
        }
    }

    /// A close-up: the lid's central quarter `[¼, ¾]²` at `size × size` pixels.
    pub fn close_up(angle_deg: f32, size: u32) -> View {
        View {
            lo: Vec2::splat(0.25),
            hi: Vec2::splat(0.75),
            ..View::lid(angle_deg, size)
        }
    }

    /// The unit direction of every ray in prism coordinates (the world direction with its
    /// height divided by `depth`).
    pub fn direction(&self) -> Vec3 {
        let (a, z) = (self.angle_deg.to_radians(), AZIMUTH_DEG.to_radians());
        Vec3::new(a.sin() * z.sin(), a.sin() * z.cos(), -a.cos() / self.depth).normalize()
    }

    /// The lid point (z = 1) and the unit ray of pixel `(x, y)`.
    pub fn ray(&self, x: u32, y: u32) -> (Vec3, Vec3) {
        let u = Vec2::new(
            (x as f32 + 0.5) / self.width as f32,
            1.0 - (y as f32 + 0.5) / self.height as f32,
        );
        let s = self.lo + u * (self.hi - self.lo);
        (s.extend(1.0), self.direction())
    }

    /// The segment `(E, X)` of pixel `k` (row-major) through the prism, `None` where its ray
    /// misses the prism (a view at 90° or more, or a window outside the lid).
    pub fn segment(&self, k: u32) -> Option<(Vec3, Vec3)> {
        let (eye, d) = self.ray(k % self.width, k / self.width);
        clip_to_prism(eye, d)
    }
}

/// The entry and exit of `o + t·d` (t ≥ 0) through the box `[0, 1]² × [0, 1]` (slabs). The
/// coordinate of the face each point lies on is set to exactly 0 or 1, not a rounding of it.
pub fn clip_to_prism(o: Vec3, d: Vec3) -> Option<(Vec3, Vec3)> {
    let inv = d.recip();
    let (t0, t1) = (-o * inv, (Vec3::ONE - o) * inv);
    let (lo, hi) = (t0.min(t1), t0.max(t1));
    let near = lo.max_element().max(0.0);
    let far = hi.min_element();
    if near.partial_cmp(&far) != Some(std::cmp::Ordering::Less) {
        return None;
    }
    let (mut e, mut x) = (o + near * d, o + far * d);
    for k in 0..3 {
        if hi[k] == far {
            x[k] = if d[k] > 0.0 { 1.0 } else { 0.0 };
        }
        if near > 0.0 && lo[k] == near {
            e[k] = if d[k] > 0.0 { 0.0 } else { 1.0 };
        }
    }
    Some((
        e.clamp(Vec3::ZERO, Vec3::ONE),
        x.clamp(Vec3::ZERO, Vec3::ONE),
    ))
}

/// One rendered image: shading (0 background), hit mask, the hit's λ along the pixel's
/// segment, and fetches per pixel.
pub struct ReliefFrame {
    pub image: GrayImage,
    pub hit: Vec<bool>,
    pub lambda: Vec<Option<f32>>,
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
    render_with(map, view, |e, x| match params {
        Some(p) => intersect(map, zones, e, x, p),
        None => Cast {
            hit: exact(map, e, x),
            fetches: 0,
        },
    })
}

/// Renders `view` with `cast` answering each pixel's segment `(E, X)` (in parallel), the hits
/// shaded.
pub(crate) fn render_with(
    map: &HeightMap,
    view: &View,
    cast: impl Fn(Vec3, Vec3) -> Cast + Sync,
) -> ReliefFrame {
    let px: Vec<Pixel> = (0..view.width * view.height)
        .into_par_iter()
        .map(|k| match view.segment(k) {
            Some((e, x)) => shade_pixel(map, e, x, &cast(e, x)),
            None => (0.0, None, 0),
        })
        .collect();
    assemble(view, px)
}

/// A caster of a whole view's segments in one call (the GPU's relief caster and its peers,
/// src/gpu/relief.rs and src/gpu/relief_peers.rs, implement it for their parameters `P`), so
/// that `relief` needs nothing of `gpu`.
pub trait SegmentCaster<P: ?Sized> {
    /// What a call's cost is reported as.
    type Timing;
    /// Why a call failed.
    type Error;
    /// The answer on every segment `(E, X)` (prism coordinates).
    fn cast_segments(
        &self,
        segments: &[(Vec3, Vec3)],
        params: &P,
    ) -> Result<(Vec<Cast>, Self::Timing), Self::Error>;
}

/// Renders `view` with a caster of whole views (`kernel`, made for `map`, with `params`: the
/// GPU caster's [`CastParams`] or a peer); the hits are shaded on the host as in [`render`].
pub fn render_gpu<P: ?Sized, K: SegmentCaster<P>>(
    kernel: &K,
    map: &HeightMap,
    view: &View,
    params: &P,
) -> Result<(ReliefFrame, K::Timing), K::Error> {
    let (w, h) = (view.width, view.height);
    let pixels: Vec<(u32, (Vec3, Vec3))> = (0..w * h)
        .filter_map(|k| view.segment(k).map(|s| (k, s)))
        .collect();
    let segments: Vec<(Vec3, Vec3)> = pixels.iter().map(|p| p.1).collect();
    let (casts, timing) = kernel.cast_segments(&segments, params)?;
    let mut px = vec![(0.0, None, 0); (w * h) as usize];
    for (&(k, (e, x)), c) in pixels.iter().zip(&casts) {
        px[k as usize] = shade_pixel(map, e, x, c);
    }
    Ok((assemble(view, px), timing))
}

/// A pixel's shade, hit λ and fetches.
type Pixel = (f32, Option<f32>, u32);

/// A pixel's (shade, hit, fetches) for the answer `c` on its segment `E → X`.
fn shade_pixel(map: &HeightMap, e: Vec3, x: Vec3, c: &Cast) -> Pixel {
    match c.hit {
        Some(l) => {
            let p = e + l * (x - e).normalize();
            (shade(map, Vec2::new(p.x, p.y)), c.hit, c.fetches)
        }
        None => (0.0, None, c.fetches),
    }
}

fn assemble(view: &View, px: Vec<Pixel>) -> ReliefFrame {
    ReliefFrame {
        image: GrayImage {
            width: view.width,
            height: view.height,
            data: px.iter().map(|p| p.0).collect(),
        },
        hit: px.iter().map(|p| p.1.is_some()).collect(),
        lambda: px.iter().map(|p| p.1).collect(),
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
        let view = View::lid(0.0, 16);
        let f = render(&map, None, &view, None);
        assert!(f.hit.iter().all(|h| *h));
        let s = shade(&map, Vec2::splat(0.5));
        assert!(f.image.data.iter().all(|v| (v - s).abs() < 1e-6));
    }
}
