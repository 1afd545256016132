//! The 2010 paper's secondary rays (Gaitatzes et al., WSCG 2010, §4.2) generated from terms
//! shared by every point of a ray set, eight rays per step with AVX2 where the CPU has it
//! ([`Isa::detect`]; `ray_lanes_avx2.rs`), one at a time elsewhere: shadow rays in a light's
//! cone ([`cone_rays`], for [`super::shadow`]) and reflection rays in a glossy lobe
//! ([`lobe_rays`], for [`super::reflect`]).
//!
//! What does not depend on the point is made once per ray set: the concentric disk's points
//! of the stratified squares ([`DiskSamples`]: their sine and cosine, the costliest part of a
//! cone direction), and for reflections each square's direction in the lobe's own frame. Per
//! point (and light) remain the point's rotation, the cone's opening or the lobe's frame, the
//! rotation into the world, the renormalisation, the cosine with the normal and, for shadows,
//! the far end on the light. Every step performs the one-ray code's IEEE operations in its
//! order ([`super::shadow::LightCone::direction`] and [`super::shadow::LightCone::far_end`],
//! `reflect::reflection_rays`' lobe), lane by lane, without fused multiply-add, so the rays are
//! the same bits (tests in `ray_lanes_tests.rs`, on both instruction sets).

use super::shadow::LightCone;
use crate::sampling::warp::square_to_concentric_disk;
use crate::sampling::Frame;
pub use crate::simd::Isa;
use glam::{Vec2, Vec3};

/// Rays per step of the AVX2 loops.
pub const LANES: usize = 8;

/// The concentric disk points d of square samples as [`super::shadow::square_to_cone`] uses
/// them, one array per term: x / ρ and y / ρ (ρ = |d|) and ρ² = |d|², all three 0 where
/// ρ² is 0 (the disk's centre, whose cone direction is the axis).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiskSamples {
    pub cos: Vec<f32>,
    pub sin: Vec<f32>,
    pub r2: Vec<f32>,
}

impl DiskSamples {
    /// The disk points of `squares`, replacing these.
    pub fn fill(&mut self, squares: &[Vec2]) {
        self.cos.clear();
        self.sin.clear();
        self.r2.clear();
        for &u in squares {
            let d = square_to_concentric_disk(u);
            let r2 = d.length_squared();
            let (c, s, r2) = if r2 == 0.0 {
                (0.0, 0.0, 0.0)
            } else {
                let r = r2.sqrt();
                (d.x / r, d.y / r, r2)
            };
            self.cos.push(c);
            self.sin.push(s);
            self.r2.push(r2);
        }
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        self.r2.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.r2.is_empty()
    }
}

/// Shadow rays from one origin, the kept ones of every light in turn: unit directions, far ends
/// (on the light's near side) and weights.
#[derive(Clone, Debug, Default)]
pub struct ShadowRays {
    pub dirs: Vec<Vec3>,
    pub tmaxs: Vec<f32>,
    pub weights: Vec<f64>,
}

impl ShadowRays {
    /// Empties the three arrays.
    pub fn clear(&mut self) {
        self.dirs.clear();
        self.tmaxs.clear();
        self.weights.clear();
    }

    #[inline]
    fn push(&mut self, dir: Vec3, tmax: f32, weight: f64) {
        self.dirs.push(dir);
        self.tmaxs.push(tmax);
        self.weights.push(weight);
    }
}

/// Appends to `out` the shadow rays of the sphere light `cone` (not a point light) through the
/// disk samples `disk`, turned by the point's rotation (sin `s`, cos `c`): for each sample its
/// direction ([`LightCone::direction`] of the sample's square), kept unless its cosine with
/// `normal` is ≤ 0, with its far end ([`LightCone::far_end`]) and the weight
/// `cone.weight_scale · cosine`; bit for bit those, in sample order.
///
/// # Panics
/// If `cone` is a point light's (one ray along the axis: the caller's), or the disk's three
/// arrays differ in length.
pub fn cone_rays(
    isa: Isa,
    disk: &DiskSamples,
    cone: &LightCone,
    (s, c): (f32, f32),
    normal: Vec3,
    out: &mut ShadowRays,
) {
    assert!(
        !cone.point,
        "cone_rays: a point light has one ray, along its axis"
    );
    let n = disk.len();
    assert!(
        disk.cos.len() == n && disk.sin.len() == n,
        "cone_rays: the disk's arrays differ in length"
    );
    out.dirs.reserve(n);
    out.tmaxs.reserve(n);
    out.weights.reserve(n);
    let mut done = 0;
    if isa.runs_avx2() {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: the CPU has AVX2 (`Isa::runs_avx2`); the arrays agree in length.
            done = unsafe { avx2::cone_rays(disk, cone, (s, c), normal, out) };
        }
    }
    for k in done..n {
        let dir = cone_direction(cone, disk.cos[k], disk.sin[k], disk.r2[k], (s, c));
        let cos_n = normal.dot(dir);
        if cos_n <= 0.0 {
            continue;
        }
        out.push(dir, cone.far_end(dir), cone.weight_scale * cos_n as f64);
    }
}

/// [`LightCone::direction`] of the square whose disk terms are (`cos`, `sin`, `r2`):
/// [`super::shadow::square_to_cone`]'s expressions from its disk point on, in its order.
#[inline]
pub fn cone_direction(cone: &LightCone, cos: f32, sin: f32, r2: f32, (s, c): (f32, f32)) -> Vec3 {
    let t = r2 * cone.one_minus_cos;
    let st = (t * (2.0 - t)).max(0.0).sqrt();
    lobe_direction(Vec3::new(cos * st, sin * st, 1.0 - t), (s, c), &cone.frame)
}

/// Appends to `dirs` the reflection rays of the lobe directions `base` (in the lobe's frame,
/// its axis +z), turned by the point's rotation (sin `s`, cos `c`), taken to the world by
/// `frame` and renormalised, keeping those whose cosine with `normal` is > 0; bit for bit
/// `reflect::reflection_rays`' per-ray expressions, in order.
pub fn lobe_rays(
    isa: Isa,
    base: &[Vec3],
    (s, c): (f32, f32),
    frame: &Frame,
    normal: Vec3,
    dirs: &mut Vec<Vec3>,
) {
    dirs.reserve(base.len());
    let mut done = 0;
    if isa.runs_avx2() {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: the CPU has AVX2 (`Isa::runs_avx2`).
            done = unsafe { avx2::lobe_rays(base, (s, c), frame, normal, dirs) };
        }
    }
    for &l in &base[done..] {
        let dir = lobe_direction(l, (s, c), frame);
        if normal.dot(dir) > 0.0 {
            dirs.push(dir);
        }
    }
}

/// One lobe (or cone) direction `l` turned by (sin `s`, cos `c`) about +z, taken to the world
/// by `frame` and renormalised.
#[inline]
pub fn lobe_direction(l: Vec3, (s, c): (f32, f32), frame: &Frame) -> Vec3 {
    let l = Vec3::new(c * l.x - s * l.y, s * l.x + c * l.y, l.z);
    frame.to_world(l).normalize()
}

#[cfg(target_arch = "x86_64")]
#[path = "ray_lanes_avx2.rs"]
mod avx2;

#[cfg(test)]
#[path = "ray_lanes_tests.rs"]
mod tests;
