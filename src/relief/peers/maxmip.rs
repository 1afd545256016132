//! Maximum mipmaps: A. Tevs, I. Ihrke, H.-P. Seidel, "Maximum Mipmaps for Fast, Accurate, and
//! Scalable Dynamic Height Field Rendering", I3D 2008.
//!
//! A quadtree of maxima over the bilinear cells: a leaf is the maximum of a cell's four corner
//! texels, which bounds the bilinear patch from above (it is a convex combination of them), a
//! node the maximum of its four children. The ray descends while it is not above a node's
//! maximum over the part of the ray inside the node, skips the node when it is, and ascends
//! one level after each skip; at a leaf the patch is intersected exactly ([`solve_cell`]), so
//! the answers are those of the cell walk ([`super::cellwalk`]), with fewer reads.
//!
//! Deviation from the paper: the leaves are the cells between texel centres of the bilinear
//! surface (the paper intersects the two triangles or the bilinear patch of four texels the
//! same way; its quadtree is over texels); the tree is padded to a power of two with empty
//! nodes; a leaf is not read from the tree but gathered (its maximum is that of the gather,
//! the read the intersection needs anyway).

use super::grid::{gather, solve_cell, CellAnswer, GridRay};
use crate::relief::cast::{hit, miss, Cast};
use crate::relief::height::HeightMap;
use glam::Vec3;

/// Maximum of a padding node: below every ray in the prism.
const EMPTY: f32 = -1.0;

/// The max quadtree of a map: level 0 has one entry per cell, `size × size`, cell `(i, j)`
/// (i, j ∈ −1 ..= W − 1) at `(i + 1, j + 1)`; level `L` has `size >> L` entries a side.
#[derive(Clone, Debug, PartialEq)]
pub struct MaxMip {
    /// Entries a side of level 0: the next power of two of `max(W, H) + 1`.
    pub size: usize,
    /// Levels 0 (cells) to the root (one entry), concatenated, each row-major.
    pub data: Vec<f32>,
    /// Offset of each level in `data`.
    pub offsets: Vec<usize>,
}

impl MaxMip {
    /// The tree of `map`.
    pub fn new(map: &HeightMap) -> MaxMip {
        let size = (map.width.max(map.height) + 1).next_power_of_two();
        let mut level = vec![EMPTY; size * size];
        for cj in 0..=map.height {
            for ci in 0..=map.width {
                let c = gather(map, ci as isize - 1, cj as isize - 1);
                level[cj * size + ci] = c[0].max(c[1]).max(c[2]).max(c[3]);
            }
        }
        let (mut data, mut offsets) = (Vec::new(), Vec::new());
        let mut n = size;
        loop {
            offsets.push(data.len());
            data.extend_from_slice(&level);
            if n == 1 {
                break;
            }
            let m = n / 2;
            level = (0..m * m)
                .map(|k| {
                    let (x, y) = (2 * (k % m), 2 * (k / m));
                    let at = |x: usize, y: usize| level[y * n + x];
                    at(x, y)
                        .max(at(x + 1, y))
                        .max(at(x, y + 1))
                        .max(at(x + 1, y + 1))
                })
                .collect();
            n = m;
        }
        MaxMip {
            size,
            data,
            offsets,
        }
    }

    /// The index of the root level.
    pub fn top(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The maximum of node `(ni, nj)` of `level`.
    #[inline]
    pub fn at(&self, level: usize, ni: usize, nj: usize) -> f32 {
        self.data[self.offsets[level] + nj * (self.size >> level) + ni]
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.data.len() * 4
    }

    /// The first intersection of `E → X` with the bilinear surface of `map` (the map this tree
    /// was built from), as [`super::cellwalk::cast`]: one fetch per node read (a tree texel)
    /// and per leaf cell reached (a gather).
    pub fn cast(&self, map: &HeightMap, e: Vec3, x: Vec3) -> Cast {
        let Some(ray) = GridRay::new(map, e, x) else {
            return miss(0);
        };
        let top = self.top();
        // Shifted cell indices c = i + 1 ∈ [0, W].
        let (wmax, hmax) = (map.width as i64, map.height as i64);
        let mut ci = (ray.o.x.floor() as i64 + 1).clamp(0, wmax);
        let mut cj = (ray.o.y.floor() as i64 + 1).clamp(0, hmax);
        let mut level = top;
        let mut lam = 0.0f32;
        let mut fetches = 0;
        loop {
            let s = 1i64 << level;
            let (ni, nj) = (ci >> level, cj >> level);
            let eu = GridRay::slab_exit(
                (ni * s - 1) as f32,
                ((ni + 1) * s - 1) as f32,
                ray.o.x,
                ray.dir.x,
            );
            let ev = GridRay::slab_exit(
                (nj * s - 1) as f32,
                ((nj + 1) * s - 1) as f32,
                ray.o.y,
                ray.dir.y,
            );
            let out = eu.min(ev).min(ray.len);
            let zmin = ray.z(lam).min(ray.z(out));
            fetches += 1;
            if level == 0 {
                let (i, j) = (ci as isize - 1, cj as isize - 1);
                let c = gather(map, i, j);
                if zmin <= c[0].max(c[1]).max(c[2]).max(c[3]) {
                    match solve_cell(&ray, i, j, c, lam, out) {
                        CellAnswer::Hit(l) => return hit(l, fetches),
                        CellAnswer::StartsBelow if lam == 0.0 => return miss(fetches),
                        CellAnswer::StartsBelow => return hit(lam, fetches),
                        CellAnswer::Clear => {}
                    }
                }
            } else if zmin <= self.at(level, ni as usize, nj as usize) {
                level -= 1;
                continue;
            }
            // The ray is above the node: past it, one level up.
            if out >= ray.len {
                return miss(fetches);
            }
            ci = next_cell(eu <= ev, ci, ni, s, ray.o.x + out * ray.dir.x, ray.dir.x);
            cj = next_cell(ev <= eu, cj, nj, s, ray.o.y + out * ray.dir.y, ray.dir.y);
            ci = ci.clamp(0, self.size as i64 - 1);
            cj = cj.clamp(0, self.size as i64 - 1);
            lam = out;
            level = (level + 1).min(top);
        }
    }
}

/// The shifted cell index along one axis after leaving node `n` (`s` cells a side) at grid
/// coordinate `at`: the first cell of the next node where the ray left through this axis'
/// face, else the cell holding `at`, kept inside the node (which the ray has not left along
/// this axis).
#[inline]
fn next_cell(crossed: bool, c: i64, n: i64, s: i64, at: f32, k: f32) -> i64 {
    if crossed {
        if k > 0.0 {
            (n + 1) * s
        } else {
            n * s - 1
        }
    } else if s == 1 {
        c
    } else {
        (at.floor() as i64 + 1).clamp(n * s, (n + 1) * s - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_hold_the_maxima_of_their_cells() {
        let map = HeightMap::from_fn(5, |s| s.x * s.y);
        let mip = MaxMip::new(&map);
        assert_eq!(mip.size, 8);
        assert_eq!(mip.top(), 3);
        assert_eq!(
            mip.at(3, 0, 0),
            *map.data.iter().fold(&0.0, |a, b| if b > a { b } else { a })
        );
        for cj in 0..8 {
            for ci in 0..8 {
                let want = if ci <= 5 && cj <= 5 {
                    let c = gather(&map, ci as isize - 1, cj as isize - 1);
                    c.iter().cloned().fold(0.0, f32::max)
                } else {
                    EMPTY
                };
                assert_eq!(mip.at(0, ci, cj), want);
            }
        }
        for l in 1..=3 {
            let n = 8 >> l;
            for nj in 0..n {
                for ni in 0..n {
                    let kids = [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .map(|(a, b)| mip.at(l - 1, 2 * ni + a, 2 * nj + b));
                    assert_eq!(
                        mip.at(l, ni, nj),
                        kids.iter().cloned().fold(EMPTY, f32::max)
                    );
                }
            }
        }
    }

    /// Over an empty floor the ray reads the root and a few nodes, not every cell.
    #[test]
    fn a_ray_above_everything_reads_few_nodes() {
        let map = HeightMap::new(64, 64, vec![0.0; 64 * 64]);
        let mip = MaxMip::new(&map);
        let (e, x) = (Vec3::new(0.0, 0.3, 0.9), Vec3::new(1.0, 0.7, 0.5));
        let c = mip.cast(&map, e, x);
        assert_eq!(c.hit, None);
        assert!(c.fetches <= 4, "{c:?}");
        let walk = super::super::cellwalk::cast(&map, e, x);
        assert_eq!(walk.hit, None);
        assert!(walk.fetches >= 64, "{walk:?}");
    }
}
