//! One mesh's distance volume: the bake (exact closest-point magnitudes, the sign by three rays'
//! crossing parities), the trilinear read at any precision ([`super::storage`]), the gradient,
//! and sphere tracing one ray through it.

use super::closest::ClosestPoints;
use super::storage::{Precision, Samples};
use super::{SdfError, SdfTrace};
use crate::trace::Tracer;
use glam::Vec3;
use rayon::prelude::*;

/// Signed distances on a regular grid: sample (i, j, k) at `lo + voxel · (i, j, k)`, stored
/// x fastest at a [`Precision`]; negative inside the mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceVolume {
    pub lo: Vec3,
    pub voxel: f32,
    pub dims: [usize; 3],
    pub samples: Samples,
}

/// The three sign rays' directions: off every axis, so that a grid of points does not send
/// them along a mesh's axis-aligned faces or edges.
const SIGN_RAYS: [Vec3; 3] = [
    Vec3::new(0.989_426, 0.135_551, 0.051_883),
    Vec3::new(0.110_853, 0.983_264, 0.144_669),
    Vec3::new(0.098_134, 0.149_164, 0.983_930),
];

impl DistanceVolume {
    /// The most samples along the longest side.
    pub const MAX_RES: usize = 512;

    /// The bake's grid for `triangles` at `res` and `margin`, without baking: its first
    /// sample's position, its voxel and its samples per axis (the volume's size is known
    /// before any work: [`Self::samples_for`]).
    ///
    /// # Errors
    /// As [`Self::bake`].
    pub fn grid(
        triangles: &[[Vec3; 3]],
        res: usize,
        margin: usize,
    ) -> Result<(Vec3, f32, [usize; 3]), SdfError> {
        if triangles.is_empty() {
            return Err(SdfError::Invalid("no triangles to bake".into()));
        }
        if !triangles.iter().flatten().all(|v| v.is_finite()) {
            return Err(SdfError::Invalid("a vertex is not finite".into()));
        }
        if !(4..=Self::MAX_RES).contains(&res) || margin >= res / 2 {
            return Err(SdfError::Invalid(format!(
                "res must be 4..={} and margin below res / 2, got res {res}, margin {margin}",
                Self::MAX_RES
            )));
        }
        let (lo, hi) = triangles.iter().flatten().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        let extent = (hi - lo).max_element();
        if extent <= 0.0 {
            return Err(SdfError::Invalid("the triangles span no volume".into()));
        }
        // `res - 1 - 2 margin` voxels across the longest side, `margin` more on each side.
        let voxel = extent / (res - 1 - 2 * margin) as f32;
        let lo = lo - Vec3::splat(voxel * margin as f32);
        // Voxels to cover the box (a thousandth of a voxel of rounding forgiven), then the
        // far margin; at least two samples per axis.
        let dims = ((hi - lo) / voxel - Vec3::splat(1e-3))
            .ceil()
            .max(Vec3::ZERO)
            .as_uvec3()
            .to_array()
            .map(|n| (n as usize + 1 + margin).clamp(2, Self::MAX_RES));
        Ok((lo, voxel, dims))
    }

    /// The samples a bake of `triangles` at `res` and `margin` holds ([`Self::grid`]).
    ///
    /// # Errors
    /// As [`Self::bake`].
    pub fn samples_for(
        triangles: &[[Vec3; 3]],
        res: usize,
        margin: usize,
    ) -> Result<u64, SdfError> {
        let (_, _, dims) = Self::grid(triangles, res, margin)?;
        Ok(dims.iter().map(|&n| n as u64).product())
    }

    /// Sign rays each sample casts in a bake.
    pub const SIGN_RAYS_PER_SAMPLE: u64 = SIGN_RAYS.len() as u64;

    /// Bakes `triangles` at `res` samples along the longest side of their box grown by
    /// `margin` voxels on every side ([`Self::grid`]), in f32.
    ///
    /// # Errors
    /// No triangles, a non-finite vertex, `res` outside 4..=[`Self::MAX_RES`], or a flat box.
    pub fn bake(triangles: &[[Vec3; 3]], res: usize, margin: usize) -> Result<Self, SdfError> {
        let (lo, voxel, dims) = Self::grid(triangles, res, margin)?;
        let closest = ClosestPoints::new(triangles);
        let tracer = Tracer::new(triangles);
        let [nx, ny, _] = dims;
        let dist: Vec<f32> = (0..dims.iter().product::<usize>())
            .into_par_iter()
            .map(|n| {
                let p = lo
                    + voxel
                        * Vec3::new(
                            (n % nx) as f32,
                            (n / nx % ny) as f32,
                            (n / (nx * ny)) as f32,
                        );
                let (_, d2) = closest.nearest(p).expect("triangles");
                let inside = SIGN_RAYS
                    .iter()
                    .filter(|&&d| crossings(&tracer, p, d) % 2 == 1)
                    .count()
                    >= 2;
                if inside {
                    -d2.sqrt()
                } else {
                    d2.sqrt()
                }
            })
            .collect();
        Ok(DistanceVolume {
            lo,
            voxel,
            dims,
            samples: Samples::F32(dist),
        })
    }

    /// The same volume stored at `precision` ([`super::storage`]); from an f32 volume the
    /// baked distances are encoded once, from another precision its decoded values are.
    pub fn with_precision(&self, precision: Precision) -> DistanceVolume {
        let samples = if precision == self.samples.precision() {
            self.samples.clone()
        } else {
            let values: Vec<f32> = (0..self.samples.len())
                .map(|i| self.samples.get(i))
                .collect();
            Samples::encode(&values, precision, self.voxel)
        };
        DistanceVolume {
            samples,
            ..self.clone()
        }
    }

    /// Its storage precision.
    pub fn precision(&self) -> Precision {
        self.samples.precision()
    }

    /// Sample `n` (x fastest), decoded.
    pub fn value(&self, n: usize) -> f32 {
        self.samples.get(n)
    }

    /// The position of sample `n`.
    pub fn position(&self, n: usize) -> Vec3 {
        let [nx, ny, _] = self.dims;
        self.lo
            + self.voxel
                * Vec3::new(
                    (n % nx) as f32,
                    (n / nx % ny) as f32,
                    (n / (nx * ny)) as f32,
                )
    }

    /// The far corner of the grid.
    pub fn hi(&self) -> Vec3 {
        self.lo
            + self.voxel
                * Vec3::new(
                    (self.dims[0] - 1) as f32,
                    (self.dims[1] - 1) as f32,
                    (self.dims[2] - 1) as f32,
                )
    }

    /// A sphere holding the grid's box grown by a voxel: outside it every read is at least the
    /// distance to it (the read outside the box adds the distance to the box to a sample on
    /// its face, and the face's samples, a margin away from the mesh, are not negative).
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let (lo, hi) = (self.lo, self.hi());
        ((lo + hi) * 0.5, (hi - lo).length() * 0.5 + self.voxel)
    }

    /// Bytes of the stored samples.
    pub fn bytes(&self) -> u64 {
        self.samples.bytes()
    }

    /// The trilinear interpolation of the samples at `p` (read through `at`), clamped to the
    /// grid; outside it, the distance to the grid's box is added to the read at the nearest
    /// point of the box (the engines' rule, UE's `DistanceToClamped`): at least the distance to
    /// the box and at least the true distance less the read's error there (the triangle
    /// inequality through that point), but it may exceed the true distance, by less than the
    /// read on the box. Sphere tracing clips rays to the box and never reads there; cones do.
    #[inline]
    fn trilinear(&self, p: Vec3, at: impl Fn(usize) -> f32) -> f32 {
        let q = p.clamp(self.lo, self.hi());
        let outside = p.distance(q);
        let g = (q - self.lo) / self.voxel;
        let [nx, ny, nz] = self.dims;
        let top = |n: usize| (n - 2) as f32;
        let c = g.min(Vec3::new(top(nx), top(ny), top(nz)));
        let (i, j, k) = (c.x as usize, c.y as usize, c.z as usize);
        let f = g - Vec3::new(i as f32, j as f32, k as f32);
        let n = i + nx * (j + ny * k);
        let (sy, sz) = (nx, nx * ny);
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let x00 = lerp(at(n), at(n + 1), f.x);
        let x10 = lerp(at(n + sy), at(n + sy + 1), f.x);
        let x01 = lerp(at(n + sz), at(n + sz + 1), f.x);
        let x11 = lerp(at(n + sy + sz), at(n + sy + sz + 1), f.x);
        lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z) + outside
    }

    /// The read distance at `p`: the trilinear interpolation of the decoded samples, clamped to
    /// the grid, plus the distance to the grid's box outside it (see `Self::trilinear`).
    pub fn sample(&self, p: Vec3) -> f32 {
        match &self.samples {
            Samples::F32(v) => self.trilinear(p, |i| v[i]),
            Samples::F16 { bits, voxel } => {
                self.trilinear(p, |i| half::f16::from_bits(bits[i]).to_f32() * voxel)
            }
            Samples::U8 { codes, band } => {
                self.trilinear(p, |i| super::storage::decode_u8(codes[i], *band))
            }
        }
    }

    /// The normalised gradient at `p` by central differences of a voxel (of the stored,
    /// possibly quantised, values).
    pub fn normal(&self, p: Vec3) -> Vec3 {
        let h = self.voxel;
        let d = |e: Vec3| self.sample(p + e) - self.sample(p - e);
        Vec3::new(d(h * Vec3::X), d(h * Vec3::Y), d(h * Vec3::Z)).normalize_or(Vec3::Y)
    }

    /// The entry and exit of the ray (unit `dir`) through the grid's box, within [tmin, tmax].
    fn clip(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<(f32, f32)> {
        let inv = d.recip();
        let (t0, t1) = ((self.lo - o) * inv, (self.hi() - o) * inv);
        let near = t0.min(t1).max_element().max(tmin);
        let far = t0.max(t1).min_element().min(tmax);
        (near <= far).then_some((near, far))
    }

    /// The first `t` in [tmin, tmax] where sphere tracing from `o` along unit `d` reads a
    /// distance below the hit threshold; the trace starts no nearer than `start_voxels`.
    pub(super) fn trace(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        opts: &SdfTrace,
    ) -> Option<f32> {
        let tmin = tmin.max(opts.start_voxels * self.voxel);
        let (mut t, far) = self.clip(o, d, tmin, tmax)?;
        let eps = opts.hit_voxels * self.voxel;
        for _ in 0..opts.max_steps {
            let s = self.sample(o + t * d);
            if s < eps {
                return Some(t);
            }
            t += s;
            if t > far {
                return None;
            }
        }
        None
    }
}

/// The number of surface crossings along the ray from `p` along `d` (closest hits, each next
/// search starting just past the last).
fn crossings(tracer: &Tracer, p: Vec3, d: Vec3) -> usize {
    let mut n = 0;
    let mut t = 0.0f32;
    while let Some(h) = tracer.closest_hit(p, d, t, f32::INFINITY) {
        n += 1;
        // Past the hit by a relative step far above f32 rounding at this distance.
        t = h.t + 1e-5 * (1.0 + h.t);
        if n > 10_000 {
            break;
        }
    }
    n
}
