//! A fine cube-map grid that answers most nearest-point queries with one table read: each cell
//! holds the point that is nearest to every direction of the cell, when one point is
//! ([`super::cube_grid::few_candidates`]: the cube grid's pruning leaves a single candidate),
//! the two candidates when it leaves two (decided by two f64 dot products, as the search does),
//! or a mark that sends the query to the exact candidate search of [`super::cube_grid`].
//!
//! This is the colour-index map that the 2008 paper's slides answer nearest queries from
//! (Gaitatzes et al.; see [`super::SphereKind::Slater`]), made exact. Deviation from the paper: a
//! cell holds an index only when one point is nearest to all of it.
//!
//! The answer is the same index as the brute-force search (and the cube grid's search) for
//! every direction: a cell is marked owned only when its owner beats every other point by a
//! margin over the whole enlarged cell, and [`super::cube_grid::cell_of`] puts each direction
//! in a cell whose enlargement contains it.

use super::cube_grid::{few_candidates, Few};
use glam::Vec3;
use std::collections::HashMap;

/// Marks a cell with more than two candidates (and every cell when the set has ≥ 2¹⁶ − 1
/// points, or a two-candidate cell once the codes for pairs run out).
const MIXED: u16 = u16::MAX;

/// Owner grid cells per point: at 32, 91–95% of the directions of the papers' sets land in a
/// cell with one or two candidates (measured by `tests/fast_lookup.rs`), at about 75 bytes per
/// point.
pub(super) const OWNER_CELLS_PER_POINT: f64 = 32.0;

/// Per cell of a g × g-per-face cube grid: the owning point (a code below n), a pair of
/// candidates (code n + k for `pairs[k]`), or [`MIXED`].
#[derive(Clone, Debug)]
pub(crate) struct OwnerGrid {
    g: u32,
    half_g: f32,
    /// The number of points n.
    n: u32,
    owner: Vec<u16>,
    /// Candidate pairs (ascending), shared by the cells that hold them.
    pairs: Vec<[u16; 2]>,
}

impl OwnerGrid {
    /// The owner grid of `points` (triangulation `tris`, `nearest` any nearest-point query, as
    /// for [`super::cube_grid::CubeGrid::new`]) at g cells per face edge.
    pub fn new(
        points: &[Vec3],
        tris: &[[u32; 3]],
        g: u32,
        nearest: impl Fn(Vec3) -> usize + Sync,
    ) -> OwnerGrid {
        let n = points.len();
        let mut pairs = Vec::new();
        let owner = if n < MIXED as usize {
            let mut code: HashMap<(u32, u32), u16> = HashMap::new();
            few_candidates(points, tris, g, nearest)
                .into_iter()
                .map(|few| match few {
                    Few::One(p) => p as u16,
                    Few::Two(p, q) => {
                        if let Some(&c) = code.get(&(p, q)) {
                            return c;
                        }
                        let c = n + pairs.len();
                        if c >= MIXED as usize {
                            return MIXED;
                        }
                        pairs.push([p as u16, q as u16]);
                        code.insert((p, q), c as u16);
                        c as u16
                    }
                    Few::Many => MIXED,
                })
                .collect()
        } else {
            vec![MIXED; 6 * g as usize * g as usize]
        };
        OwnerGrid {
            g,
            half_g: 0.5 * g as f32,
            n: n as u32,
            owner,
            pairs,
        }
    }

    /// The point of `points` (the set the grid was built for) nearest to `d` when `d`'s cell
    /// has one or two candidates (the brute-force answer itself: the owner, or the first larger
    /// f64 dot product of the pair, the same comparison as the search's), `None` otherwise,
    /// and `None` for zero, tiny (< 1e-30), infinite and NaN
    /// inputs, whose cell the f32 cell computation does not place reliably. The cell is
    /// [`super::cube_grid::cell_of`]'s, with the range checks folded into one test.
    #[inline(always)]
    pub fn owner(&self, points: &[Vec3], d: Vec3) -> Option<usize> {
        self.owner_at(self.cell(d), points, d)
    }

    /// [`Self::owner`] with `d`'s cell already found (`cell` is [`Self::prefetch`]`(d)`).
    #[inline(always)]
    pub fn owner_at(&self, cell: Option<usize>, points: &[Vec3], d: Vec3) -> Option<usize> {
        debug_assert_eq!(
            cell,
            self.cell(d),
            "owner_at: the cell of another direction"
        );
        let o = self.owner[cell?] as u32;
        if o < self.n {
            return Some(o as usize);
        }
        let [p, q] = *self.pairs.get((o - self.n) as usize)?; // None for MIXED
        let dd = d.as_dvec3();
        let better = dd.dot(points[q as usize].as_dvec3()) > dd.dot(points[p as usize].as_dvec3());
        Some(if better { q } else { p } as usize)
    }

    /// The table cell of `d` ([`super::cube_grid::cell_of`]'s, with the range checks folded
    /// into one test), `None` for zero, tiny (< 1e-30), infinite and NaN inputs, whose cell the
    /// f32 computation does not place reliably.
    #[inline(always)]
    pub fn cell(&self, d: Vec3) -> Option<usize> {
        let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
        let x_wins = (ax >= ay) & (ax >= az);
        let y_wins = !x_wins & (ay >= az);
        let (a, da, pb, pc) = if x_wins {
            (0, d.x, d.y, d.z)
        } else if y_wins {
            (1, d.y, d.z, d.x)
        } else {
            (2, d.z, d.x, d.y)
        };
        let m = da.abs();
        let k = self.half_g / m;
        let (fi, fj) = (pb * k + self.half_g, pc * k + self.half_g);
        let gf = self.g as f32;
        // False for NaN anywhere (it reaches m, fi or fj) and for infinite inputs.
        if !(m > 1e-30 && m < f32::INFINITY && fi >= 0.0 && fi <= gf && fj >= 0.0 && fj <= gf) {
            return None;
        }
        // SAFETY: fi and fj are finite and in [0, g] (checked above), so they convert.
        let (i, j) = unsafe { (fi.to_int_unchecked::<u32>(), fj.to_int_unchecked::<u32>()) };
        let last = self.g - 1;
        let f = 2 * a + (da < 0.0) as u32;
        Some(((f * self.g + j.min(last)) * self.g + i.min(last)) as usize)
    }

    /// Hints the CPU to fetch the table cell that [`Self::owner`] reads for `d`, and returns
    /// that cell for [`Self::owner_at`].
    #[inline(always)]
    pub fn prefetch(&self, d: Vec3) -> Option<usize> {
        let cell = self.cell(d);
        if let Some(cell) = cell {
            crate::hint::prefetch_value(self.owner.as_ptr().wrapping_add(cell));
        }
        cell
    }

    /// The terms of [`Self::cell`]: cells per face edge g and g/2 (for the eight-lane cell
    /// computation of `field::lanes`, which must reproduce [`Self::cell`] bit for bit).
    #[inline(always)]
    pub fn cell_scale(&self) -> (u32, f32) {
        (self.g, self.half_g)
    }

    /// Hints the CPU to fetch table cell `cell` (any value; no effect on results).
    #[inline(always)]
    pub fn prefetch_cell(&self, cell: usize) {
        crate::hint::prefetch_value(self.owner.as_ptr().wrapping_add(cell));
    }

    /// The raw table for the GPU lookup (src/gpu/field_data.rs): cells per face edge g, the
    /// per-cell codes ([`Self::new`]'s: owner < n, pair n + k, `u16::MAX` for the search) and
    /// the pairs.
    pub(crate) fn raw(&self) -> (u32, &[u16], &[[u16; 2]]) {
        (self.g, &self.owner, &self.pairs)
    }

    /// Bytes held by the table.
    pub fn bytes(&self) -> usize {
        self.owner.len() * std::mem::size_of::<u16>()
            + self.pairs.len() * std::mem::size_of::<[u16; 2]>()
    }
}
