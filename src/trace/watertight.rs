//! Watertight ray–triangle intersection (Woop, Benthin, Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013).
//!
//! The ray is sheared and scaled so that it becomes the +z axis through the origin; the triangle is
//! transformed the same way and the test reduces to the signs of three 2D edge functions `U, V, W`
//! at the origin. Each edge function depends only on the two vertices of its edge (and the ray), so
//! two triangles that share an edge evaluate it to exactly opposite values: a ray through a shared
//! edge or vertex can never fall through the gap between them. Values exactly 0 are recomputed in
//! f64 (the products of two f32 are exact there), as in the paper, so that the sign is exact.
//!
//! Conventions: no backface culling (both windings hit); a hit counts when `tmin <= t <= tmax`
//! (both ends inclusive); `t` is in units of the direction's length (renderers pass unit
//! directions, so `t` is a distance). The barycentrics follow [`crate::trace::Hit`]:
//! `p = (1-u-v)·v0 + u·v1 + v·v2`.
//!
//! Deviation from the paper: the paper tests `0 <= t <= hit.t` without a division (scaled by the
//! determinant); here `t = T/det` is computed first and then compared with `[tmin, tmax]`, so the
//! accepted range agrees bit for bit with the `t` that is returned.

use glam::{Vec3A, Vec3Swizzles};

/// A ray prepared for [`WatertightRay::intersect`]: the per-ray part of the paper's algorithm
/// (axis permutation and shear constants), computed once per ray and reused for every triangle.
///
/// The paper's permutation (kx, ky, kz) and shear (Sx, Sy, Sz) are stored as the rows of the
/// equivalent 3×3 matrix, so that a triangle is transformed with SIMD arithmetic: row `x` is
/// `e_kx − Sx·e_kz`, row `y` is `e_ky − Sy·e_kz`, row `z` is `Sz·e_kz`. Every product with a
/// zero entry is an exact zero, so each transformed coordinate is rounded exactly as in the
/// paper (`Ax = A[kx] − Sx·A[kz]`, one product and one difference).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WatertightRay {
    pub origin: Vec3A,
    /// Column `j` holds the coefficients of input axis `j` in the three transformed
    /// coordinates: transformed = `m[0]·x + m[1]·y + m[2]·z` (lane-wise).
    m: [Vec3A; 3],
}

/// A triangle stored by coordinate (structure of arrays): `xs = (v0.x, v1.x, v2.x)` etc.,
/// the layout [`WatertightRay::intersect_packed`] transforms all three vertices with at once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PackedTriangle {
    pub xs: Vec3A,
    pub ys: Vec3A,
    pub zs: Vec3A,
}

impl PackedTriangle {
    #[inline]
    pub fn new(v0: Vec3A, v1: Vec3A, v2: Vec3A) -> PackedTriangle {
        PackedTriangle {
            xs: Vec3A::new(v0.x, v1.x, v2.x),
            ys: Vec3A::new(v0.y, v1.y, v2.y),
            zs: Vec3A::new(v0.z, v1.z, v2.z),
        }
    }

    /// The vertices `[v0, v1, v2]`.
    #[inline]
    pub fn vertices(&self) -> [Vec3A; 3] {
        [
            Vec3A::new(self.xs.x, self.ys.x, self.zs.x),
            Vec3A::new(self.xs.y, self.ys.y, self.zs.y),
            Vec3A::new(self.xs.z, self.ys.z, self.zs.z),
        ]
    }
}

/// A ray–triangle hit: ray parameter and barycentrics (`p = (1-u-v)·v0 + u·v1 + v·v2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl WatertightRay {
    /// Prepares the ray `origin + t·dir`. `dir` need not be unit but must be finite and non-zero.
    #[inline]
    pub fn new(origin: Vec3A, dir: Vec3A) -> WatertightRay {
        debug_assert!(origin.is_finite() && dir.is_finite() && dir != Vec3A::ZERO);
        let a = dir.abs();
        // The dimension where the ray direction is maximal (ties go to the lower axis).
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Swap kx and ky to preserve the winding direction of triangles.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let (sx, sy, sz) = (dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        let mut m = [Vec3A::ZERO; 3];
        m[kx].x = 1.0;
        m[kz].x = -sx;
        m[ky].y = 1.0;
        m[kz].y = -sy;
        m[kz].z = sz;
        WatertightRay { origin, m }
    }

    /// The hit with the triangle `(v0, v1, v2)` if `tmin <= t <= tmax`, either winding.
    /// Degenerate (zero-area in the ray's projection) triangles never hit.
    #[inline]
    pub fn intersect(
        &self,
        v0: Vec3A,
        v1: Vec3A,
        v2: Vec3A,
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
        self.intersect_packed(&PackedTriangle::new(v0, v1, v2), tmin, tmax)
    }

    /// [`WatertightRay::intersect`] on a [`PackedTriangle`].
    #[inline]
    pub fn intersect_packed(
        &self,
        tri: &PackedTriangle,
        tmin: f32,
        tmax: f32,
    ) -> Option<TriangleHit> {
        // Vertices relative to the ray origin, by coordinate: lanes are (A, B, C).
        let x = tri.xs - Vec3A::splat(self.origin.x);
        let y = tri.ys - Vec3A::splat(self.origin.y);
        let z = tri.zs - Vec3A::splat(self.origin.z);
        // Shear and scale: lanes of `tx` are (Ax, Bx, Cx), of `ty` (Ay, By, Cy), of `tz`
        // (Az, Bz, Cz) in the paper's notation (tz already scaled by Sz).
        let [m0, m1, m2] = self.m;
        let tx = x * m0.x + y * m1.x + z * m2.x;
        let ty = x * m0.y + y * m1.y + z * m2.y;
        // Scaled barycentric coordinates (2D edge functions at the origin), lane-wise:
        // U = Cx·By − Cy·Bx, V = Ax·Cy − Ay·Cx, W = Bx·Ay − By·Ax.
        let (x1, y1) = (tx.yzx(), ty.yzx()); // (B, C, A)
        let (x2, y2) = (tx.zxy(), ty.zxy()); // (C, A, B)
        let mut uvw = x2 * y1 - y2 * x1;
        // Fall back to f64 on edges: the products of two f32 are exact in f64, so the sign of
        // the difference is exact and the same for both triangles that share the edge.
        if uvw.cmpeq(Vec3A::ZERO).any() {
            let e = |i: usize| (x2[i] as f64 * y1[i] as f64 - y2[i] as f64 * x1[i] as f64) as f32;
            uvw = Vec3A::new(e(0), e(1), e(2));
        }
        // Mixed signs: the ray passes outside (no backface culling: all >= 0 or all <= 0 hit).
        if uvw.cmplt(Vec3A::ZERO).any() && uvw.cmpgt(Vec3A::ZERO).any() {
            return None;
        }
        let (u, v, w) = (uvw.x, uvw.y, uvw.z);
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        // Scaled z coordinates and the scaled hit distance T = U·Az + V·Bz + W·Cz.
        let tz = x * m0.z + y * m1.z + z * m2.z;
        let t_scaled = u * tz.x + v * tz.y + w * tz.z;
        let t = t_scaled / det;
        // Written so that NaN is rejected.
        if !(t >= tmin && t <= tmax) {
            return None;
        }
        let rcp_det = 1.0 / det;
        Some(TriangleHit {
            t,
            u: v * rcp_det,
            v: w * rcp_det,
        })
    }
}

/// One-shot form of [`WatertightRay::intersect`] (prepares the ray each call; for tests and
/// brute-force references).
#[inline]
pub fn intersect_triangle(
    origin: Vec3A,
    dir: Vec3A,
    tri: &[Vec3A; 3],
    tmin: f32,
    tmax: f32,
) -> Option<TriangleHit> {
    WatertightRay::new(origin, dir).intersect(tri[0], tri[1], tri[2], tmin, tmax)
}

#[cfg(test)]
#[path = "watertight_tests.rs"]
mod tests;
