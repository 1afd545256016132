//! The ray in grid coordinates and the exact intersection inside one bilinear cell, in f32:
//! the pieces the cell walk and the max-mip leaves share (and `shaders/relief_peers.wgsl`
//! mirrors operation for operation).
//!
//! Grid coordinates: `u = s·W − ½`, `v = t·H − ½`, so texel `(i, j)` is centred on the integer
//! point `(i, j)` and cell `(i, j)` is the square `[i, i + 1] × [j, j + 1]` on which the map is
//! the bilinear patch of the texels `(i..=i+1, j..=j+1)` (clamped at the border, as
//! [`HeightMap::sample`]). The prism's base `[0, 1]²` spans `u ∈ [−½, W − ½]`: cells `−1 ..= W − 1`.

use crate::relief::height::HeightMap;
use glam::Vec3;

/// Stands for an infinite ray parameter (WGSL has no infinities): an exit this far is never
/// reached by a segment in the unit prism.
pub const HUGE: f32 = 3.0e38;

/// A segment `E → X` in grid coordinates: `P(λ) = o + λ·dir`, `λ ∈ [0, len]`, λ the distance
/// along the segment in prism coordinates (the λ of [`crate::relief::Cast`]).
#[derive(Clone, Copy, Debug)]
pub struct GridRay {
    /// `E` in grid coordinates `(u, v, z)`.
    pub o: Vec3,
    /// The unit prism direction `r̂` scaled to grid units: `(r_s·W, r_t·H, r_z)`.
    pub dir: Vec3,
    /// `|X − E|`.
    pub len: f32,
    /// The unit direction in prism coordinates.
    pub r: Vec3,
}

impl GridRay {
    /// The segment `E → X` over `map`'s grid; `None` when it has no length (or is not finite).
    pub fn new(map: &HeightMap, e: Vec3, x: Vec3) -> Option<GridRay> {
        let len = (x - e).length();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        let (w, h) = (map.width as f32, map.height as f32);
        let r = (x - e) / len;
        Some(GridRay {
            o: Vec3::new(e.x * w - 0.5, e.y * h - 0.5, e.z),
            dir: Vec3::new(r.x * w, r.y * h, r.z),
            len,
            r,
        })
    }

    /// The ray parameter where it leaves the slab `[lo, hi]` of one grid axis (origin `o`,
    /// slope `k`); [`HUGE`] when it runs parallel to it.
    #[inline]
    pub fn slab_exit(lo: f32, hi: f32, o: f32, k: f32) -> f32 {
        if k > 0.0 {
            (hi - o) / k
        } else if k < 0.0 {
            (lo - o) / k
        } else {
            HUGE
        }
    }

    /// Height of the ray at `λ`.
    #[inline]
    pub fn z(&self, l: f32) -> f32 {
        self.o.z + l * self.dir.z
    }
}

/// The four texels of cell `(i, j)` (clamped), as one gather reads them: `[c00, c10, c01, c11]`.
#[inline]
pub fn gather(map: &HeightMap, i: isize, j: isize) -> [f32; 4] {
    [
        map.texel(i, j),
        map.texel(i + 1, j),
        map.texel(i, j + 1),
        map.texel(i + 1, j + 1),
    ]
}

/// What one cell answers for the part `[lo, hi]` of a ray in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellAnswer {
    /// The first `λ ∈ [lo, hi]` with `d(λ) ≤ 0`.
    Hit(f32),
    /// `d > 0` on the whole part.
    Clear,
    /// `d(lo) < 0`: the part starts below the surface (at `λ = 0`: the entry lies inside the
    /// solid, a back face, discarded as by [`crate::relief::intersect`]).
    StartsBelow,
}

/// The exact first intersection of the ray's part `[lo, hi]` with the bilinear patch of cell
/// `(i, j)` whose texels are `c` ([`gather`]), solved in f32 relative to the part's start.
///
/// With `fx = fx0 + b·t`, `fy = fy0 + e·t` (`t = λ − lo`) and
/// `M = c00 + p·fx + q·fy + k·fx·fy`, the clearance `d(t) = z(lo) + r_z·t − M` is the quadratic
/// `A t² + B t + C`; its smallest root in `[0, hi − lo]` is taken with the cancellation-free
/// formula. Where the end of the part is at or below the surface a root exists, and rounding
/// that puts it outside the part is clamped back in.
pub fn solve_cell(ray: &GridRay, i: isize, j: isize, c: [f32; 4], lo: f32, hi: f32) -> CellAnswer {
    let (b, e) = (ray.dir.x, ray.dir.y);
    let fx0 = (ray.o.x + lo * b - i as f32).clamp(0.0, 1.0);
    let fy0 = (ray.o.y + lo * e - j as f32).clamp(0.0, 1.0);
    let z0 = ray.z(lo);
    let p = c[1] - c[0];
    let q = c[2] - c[0];
    let k = c[0] - c[1] - c[2] + c[3];
    let m0 = c[0] + p * fx0 + q * fy0 + k * fx0 * fy0;
    let qc = z0 - m0;
    if qc < 0.0 {
        return CellAnswer::StartsBelow;
    }
    if qc == 0.0 {
        return CellAnswer::Hit(lo);
    }
    let qa = -k * b * e;
    let qb = ray.dir.z - (p * b + q * e + k * (fx0 * e + b * fy0));
    let span = hi - lo;
    let end = (qa * span + qb) * span + qc;
    let crosses = end <= 0.0;
    // The smallest root t ≥ 0, or HUGE.
    let mut t = HUGE;
    if qa == 0.0 {
        if qb < 0.0 {
            t = -qc / qb;
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let sq = disc.sqrt();
            let s = if qb >= 0.0 {
                -0.5 * (qb + sq)
            } else {
                -0.5 * (qb - sq)
            };
            let r1 = s / qa;
            let r2 = if s != 0.0 { qc / s } else { HUGE };
            if r1 >= 0.0 {
                t = t.min(r1);
            }
            if r2 >= 0.0 {
                t = t.min(r2);
            }
        }
    }
    if crosses {
        CellAnswer::Hit(lo + t.min(span))
    } else if t <= span {
        CellAnswer::Hit(lo + t)
    } else {
        CellAnswer::Clear
    }
}
