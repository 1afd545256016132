//! Seeded receiver ray sets. Randomness is a pure function of (point index, sample index, seed)
//! (the pbrt-v4 habit), so one thread and many threads give bit-identical results.

use super::frame::Frame;
use super::warp::square_to_cosine_hemisphere;
use crate::simd::Isa;
use glam::{Vec2, Vec3};

/// 64-bit finaliser of SplitMix64 / Murmur3 (Steele et al. 2014): a bijective mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform number in [0, 1) that depends only on its arguments.
#[inline]
pub fn uniform(point: u32, index: u32, dim: u32, seed: u64) -> f32 {
    let key = mix64(seed ^ 0x9e37_79b9_7f4a_7c15)
        ^ mix64(((point as u64) << 32) | index as u64)
        ^ mix64(0x5851_f42d_4c95_7f2d ^ dim as u64);
    let bits = mix64(key) >> 40; // 24 random bits
    bits as f32 * (1.0 / (1u64 << 24) as f32)
}

/// A uniform number in [0, 1) with 53 random bits that depends only on its arguments.
#[inline]
pub fn uniform_f64(index: u64, dim: u32, seed: u64) -> f64 {
    let key = mix64(seed ^ 0x2545_f491_4f6c_dd1d)
        ^ mix64(index)
        ^ mix64(0xd1b5_4a32_d192_ed03 ^ dim as u64);
    (mix64(key) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniformly distributed unit direction on the sphere that depends only on `(index, seed)`
/// (computed in f64, rounded to f32): the seeded query directions of tests, benches and reports.
#[inline]
pub fn seeded_sphere_direction(index: u64, seed: u64) -> Vec3 {
    let z = 1.0 - 2.0 * uniform_f64(index, 0, seed);
    let phi = std::f64::consts::TAU * uniform_f64(index, 1, seed);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
}

/// N = k² stratified cosine-distributed directions (the 2008 paper's receiver rays: 256 = 16×16
/// cells through the concentric map and Malley's method), in a local frame with z the normal.
///
/// Each cell contributes one direction, at the cell centre or jittered inside the cell. Every
/// receiver point gets its own rotation about the normal, seeded by (point index, seed), so that
/// neighbouring points do not share the same directions (banding) while the set stays stratified.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RaySet {
    /// Cells per side; N = k² rays per point.
    pub k: u32,
    pub seed: u64,
    /// Jitter inside each cell (seeded by point, cell and seed); otherwise cell centres.
    pub jitter: bool,
}

impl RaySet {
    /// The set of `k × k` stratified directions, centred cells, seeded rotation.
    pub fn new(k: u32, seed: u64) -> Self {
        RaySet {
            k,
            seed,
            jitter: false,
        }
    }

    /// Rays per point.
    pub fn len(&self) -> usize {
        (self.k * self.k) as usize
    }

    pub fn is_empty(&self) -> bool {
        self.k == 0
    }

    /// (sin, cos) of the seeded rotation about the normal of receiver point `point`.
    #[inline]
    pub fn rotation(&self, point: u32) -> (f32, f32) {
        let angle = std::f32::consts::TAU * uniform(point, u32::MAX, 0, self.seed);
        angle.sin_cos()
    }

    /// The unrotated cell-centre directions (the set of every point before its rotation; only
    /// meaningful without jitter).
    pub fn base_directions(&self) -> Vec<Vec3> {
        let k = self.k;
        let inv = 1.0 / k as f32;
        (0..k * k)
            .map(|cell| {
                let (i, j) = (cell % k, cell / k);
                let u = Vec2::new((i as f32 + 0.5) * inv, (j as f32 + 0.5) * inv);
                square_to_cosine_hemisphere(u)
            })
            .collect()
    }

    /// Precomputes what every point shares, for filling many points fast.
    pub fn prepare(&self) -> PreparedRaySet {
        PreparedRaySet {
            set: *self,
            base: (!self.jitter).then(|| self.base_directions()),
        }
    }

    /// Writes the local directions of receiver point `point` into `out` (cleared first).
    pub fn fill(&self, point: u32, out: &mut Vec<Vec3>) {
        out.clear();
        let (s, c) = self.rotation(point);
        for cell in 0..self.k * self.k {
            let d = square_to_cosine_hemisphere(self.cell_sample(point, cell));
            out.push(Vec3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z));
        }
    }

    /// Writes the `k²` stratified square samples of point `point` into `out` (cleared first),
    /// in the cell order of [`Self::fill`]: cell centres, or jittered inside each cell with the
    /// same jitter as [`Self::fill`]'s, before any warp or rotation. Estimators that map the
    /// square elsewhere than the cosine hemisphere (points on a light) start from these.
    pub fn fill_square(&self, point: u32, out: &mut Vec<Vec2>) {
        out.clear();
        out.extend((0..self.k * self.k).map(|cell| self.cell_sample(point, cell)));
    }

    /// The square sample of cell `cell` (row-major, `k` a row) of point `point`.
    #[inline]
    fn cell_sample(&self, point: u32, cell: u32) -> Vec2 {
        let (i, j) = (cell % self.k, cell / self.k);
        let (jx, jy) = if self.jitter {
            (
                uniform(point, cell, 1, self.seed),
                uniform(point, cell, 2, self.seed),
            )
        } else {
            (0.5, 0.5)
        };
        let inv = 1.0 / self.k as f32;
        Vec2::new((i as f32 + jx) * inv, (j as f32 + jy) * inv)
    }

    /// The local directions of receiver point `point`.
    pub fn directions(&self, point: u32) -> Vec<Vec3> {
        let mut v = Vec::with_capacity(self.len());
        self.fill(point, &mut v);
        v
    }
}

/// A [`RaySet`] with its shared cell directions precomputed: [`PreparedRaySet::fill`] gives
/// bit-identical directions to [`RaySet::fill`] without re-evaluating the warp per point.
#[derive(Clone, Debug)]
pub struct PreparedRaySet {
    pub set: RaySet,
    base: Option<Vec<Vec3>>,
}

impl PreparedRaySet {
    /// Writes the local directions of receiver point `point` into `out` (cleared first).
    #[inline]
    pub fn fill(&self, point: u32, out: &mut Vec<Vec3>) {
        match &self.base {
            Some(base) => {
                out.clear();
                let (s, c) = self.set.rotation(point);
                out.extend(
                    base.iter()
                        .map(|d| Vec3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z)),
                );
            }
            None => self.set.fill(point, out),
        }
    }

    /// [`Self::fill`] followed by `frame.to_world` of every direction, bit for bit: point
    /// `point`'s directions in world space. Without jitter, eight directions per step with AVX2
    /// where the CPU has it ([`Isa::detect`]), in the two steps' order of operations.
    #[inline]
    pub fn fill_world(&self, point: u32, frame: &Frame, out: &mut Vec<Vec3>) {
        self.fill_world_with(Isa::detect(), point, frame, out)
    }

    /// [`Self::fill_world`] on the instruction set `isa` (tests compare them).
    pub fn fill_world_with(&self, isa: Isa, point: u32, frame: &Frame, out: &mut Vec<Vec3>) {
        let Some(base) = &self.base else {
            self.set.fill(point, out);
            out.iter_mut().for_each(|d| *d = frame.to_world(*d));
            return;
        };
        let (s, c) = self.set.rotation(point);
        out.clear();
        out.resize(base.len(), Vec3::ZERO);
        let done = match isa {
            Isa::Portable => 0,
            // SAFETY: the CPU has AVX2 (checked here: `Isa::Avx2` is a request); the lengths
            // agree.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 if Isa::detect() == Isa::Avx2 => unsafe {
                avx2_rotate_to_world(base, (s, c), frame, out)
            },
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => 0,
        };
        for (o, d) in out[done..].iter_mut().zip(&base[done..]) {
            *o = frame.to_world(Vec3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z));
        }
    }
}

/// [`PreparedRaySet::fill_world`]'s rotation about z and `frame.to_world` of the whole groups
/// of eight in `base`, written to `out`; returns how many were done.
///
/// # Safety
/// The CPU must have AVX2; `out` as long as `base`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn avx2_rotate_to_world(
    base: &[Vec3],
    (s, c): (f32, f32),
    f: &Frame,
    out: &mut [Vec3],
) -> usize {
    use crate::simd::x86::{load3x8, store3x8};
    use std::arch::x86_64::*;
    let (mul, add, sub) = (_mm256_mul_ps, _mm256_add_ps, _mm256_sub_ps);
    let (sv, cv) = (_mm256_set1_ps(s), _mm256_set1_ps(c));
    let axis = |v: Vec3| {
        (
            _mm256_set1_ps(v.x),
            _mm256_set1_ps(v.y),
            _mm256_set1_ps(v.z),
        )
    };
    let (fx, fy, fz) = (axis(f.x), axis(f.y), axis(f.z));
    let whole = base.len() / 8 * 8;
    for i in (0..whole).step_by(8) {
        let (x, y, z) = load3x8(base.as_ptr().add(i).cast());
        // Vec3::new(c x − s y, s x + c y, z), then x·F.x + y·F.y + z·F.z.
        let (lx, ly) = (sub(mul(cv, x), mul(sv, y)), add(mul(sv, x), mul(cv, y)));
        let world = |a: __m256, b: __m256, c: __m256| add(add(mul(a, lx), mul(b, ly)), mul(c, z));
        let (wx, wy, wz) = (
            world(fx.0, fy.0, fz.0),
            world(fx.1, fy.1, fz.1),
            world(fx.2, fy.2, fz.2),
        );
        store3x8(out.as_mut_ptr().add(i).cast(), wx, wy, wz);
    }
    whole
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_depends_only_on_its_arguments_and_spans_unit_interval() {
        assert_eq!(uniform(3, 7, 1, 42), uniform(3, 7, 1, 42));
        assert_ne!(uniform(3, 7, 1, 42), uniform(3, 7, 1, 43));
        assert_ne!(uniform(3, 7, 1, 42), uniform(4, 7, 1, 42));
        let n = 100_000;
        let mean: f64 = (0..n).map(|i| uniform(i, 0, 0, 1) as f64).sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1): sqrt(1/12/n) ≈ 9.1e-4; 5 sigma.
        assert!((mean - 0.5).abs() < 5.0 * 9.2e-4, "mean {mean}");
        assert!((0..n).all(|i| (0.0..1.0).contains(&uniform(i, 1, 2, 3))));
    }

    #[test]
    fn ray_set_is_cosine_distributed_and_per_point_rotated() {
        let set = RaySet::new(16, 7);
        let a = set.directions(0);
        let b = set.directions(1);
        assert_eq!(a.len(), 256);
        assert_ne!(a, b, "points must get different rotations");
        for d in a.iter().chain(&b) {
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
        }
        // Rotation about the normal keeps z: the z multisets agree.
        let mut za: Vec<f32> = a.iter().map(|d| d.z).collect();
        let mut zb: Vec<f32> = b.iter().map(|d| d.z).collect();
        za.sort_by(f32::total_cmp);
        zb.sort_by(f32::total_cmp);
        assert_eq!(za, zb);
        // Centred strata: the concentric map sends the cell centres of square ring l
        // (8l + 4 cells, max(|a|, |b|) = (2l + 1)/16) to the circle r = (2l + 1)/16, so the mean
        // of cos θ = √(1 − r²) is Σ_l (8l + 4) √(1 − r_l²) / 256 exactly.
        let exact: f64 = (0..8)
            .map(|l| {
                let r = (2 * l + 1) as f64 / 16.0;
                (8 * l + 4) as f64 * (1.0 - r * r).sqrt()
            })
            .sum::<f64>()
            / 256.0;
        let mean = za.iter().map(|&z| z as f64).sum::<f64>() / 256.0;
        assert!(
            (mean - exact).abs() < 1e-6,
            "mean cos {mean}, expected {exact}"
        );
        // That is a midpoint rule for E[cos θ] = 2/3 under the cosine density; the √(1 − r²)
        // rim singularity limits it to O(k^−3/2) ≈ 0.016 here (0.6753 in fact).
        assert!((mean - 2.0 / 3.0).abs() < 0.016, "mean cos {mean}");
    }

    #[test]
    fn prepared_set_is_bit_identical() {
        for jitter in [false, true] {
            let set = RaySet {
                k: 9,
                seed: 3,
                jitter,
            };
            let prep = set.prepare();
            let mut a = Vec::new();
            for p in [0u32, 1, 77, 4_000_000] {
                prep.fill(p, &mut a);
                assert_eq!(a, set.directions(p), "jitter {jitter} point {p}");
            }
        }
    }

    #[test]
    fn world_directions_are_the_two_steps_bit_for_bit() {
        for (k, jitter) in [(9, false), (16, false), (3, false), (5, true)] {
            let set = RaySet { k, seed: 3, jitter };
            let prep = set.prepare();
            let (mut local, mut got) = (Vec::new(), Vec::new());
            for p in [0u32, 1, 77, 4_000_000] {
                let frame = Frame::from_normal(seeded_sphere_direction(p as u64, 2));
                prep.fill(p, &mut local);
                let want: Vec<[u32; 3]> = local
                    .iter()
                    .map(|&d| frame.to_world(d).to_array().map(f32::to_bits))
                    .collect();
                for isa in Isa::all_available() {
                    prep.fill_world_with(isa, p, &frame, &mut got);
                    let got: Vec<[u32; 3]> =
                        got.iter().map(|d| d.to_array().map(f32::to_bits)).collect();
                    assert_eq!(got, want, "k {k} jitter {jitter} point {p} {isa:?}");
                }
            }
        }
    }

    #[test]
    fn jittered_set_stays_in_its_cells() {
        let set = RaySet {
            k: 8,
            seed: 5,
            jitter: true,
        };
        let d = set.directions(9);
        let centred = RaySet::new(8, 5).directions(9);
        assert_ne!(d, centred);
        // Same rotation, so un-rotating both gives points in the same concentric cell.
        for (a, b) in d.iter().zip(&centred) {
            assert!(a.angle_between(*b) < 0.6, "{a} vs {b}");
        }
    }

    #[test]
    fn rotation_depends_only_on_point_and_seed() {
        let set = RaySet::new(8, 21);
        assert_eq!(set.directions(5), RaySet::new(8, 21).directions(5));
        assert_ne!(set.directions(5), RaySet::new(8, 22).directions(5));
        // Undoing the point's rotation gives back the k² concentric cell centres, one per cell:
        // the set stays stratified in the concentric map.
        let layout =
            crate::sampling::HemisphereLayout::new(crate::sampling::LayoutKind::Concentric, 8);
        for point in [0u32, 1, 77, 1 << 20] {
            let angle = std::f32::consts::TAU * uniform(point, u32::MAX, 0, 21);
            let (s, c) = angle.sin_cos();
            let mut cells: Vec<u32> = set
                .directions(point)
                .iter()
                .map(|d| layout.to_texel(Vec3::new(c * d.x + s * d.y, -s * d.x + c * d.y, d.z)))
                .collect();
            cells.sort_unstable();
            assert_eq!(cells, (0..64).collect::<Vec<u32>>(), "point {point}");
        }
    }

    #[test]
    fn seeded_sphere_directions_are_uniform() {
        // E[z] = 0, E[z²] = 1/3 and E[x] = 0 under the uniform density; 2·10⁵ samples give a
        // standard error of about 1.3e-3, so 5e-3 is ~4 sigma.
        let n = 200_000u64;
        let (mut z1, mut z2, mut x1) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..n {
            let d = seeded_sphere_direction(i, 3);
            assert!((d.length() - 1.0).abs() < 1e-6);
            z1 += d.z as f64;
            z2 += (d.z * d.z) as f64;
            x1 += d.x as f64;
        }
        let k = n as f64;
        assert!(
            (z1 / k).abs() < 5e-3 && (z2 / k - 1.0 / 3.0).abs() < 5e-3 && (x1 / k).abs() < 5e-3
        );
        assert_eq!(seeded_sphere_direction(9, 1), seeded_sphere_direction(9, 1));
        assert_ne!(seeded_sphere_direction(9, 1), seeded_sphere_direction(9, 2));
    }
}
