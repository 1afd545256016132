//! A fine cube-map grid that answers most nearest-point queries with one table read: each cell
//! holds the point that is nearest to every direction of the cell, when one point is
//! ([`super::cube_grid::single_owners`]: the cube grid's pruning leaves a single candidate),
//! or a mark that sends the query to the exact candidate search of [`super::cube_grid`].
//!
//! The answer is the same index as the brute-force search (and the cube grid's search) for
//! every direction: a cell is marked owned only when its owner beats every other point by a
//! margin over the whole enlarged cell, and [`super::cube_grid::cell_of`] puts each direction
//! in a cell whose enlargement contains it.

use super::cube_grid::single_owners;
use glam::Vec3;

/// Marks a cell without a single owner (and every cell when the set has ≥ 2¹⁶ − 1 points).
const MIXED: u16 = u16::MAX;

/// Owner grid cells per point: about 70% of the directions of the papers' sets land in an
/// owned cell at 32 (measured by `owned_share_is_high`), at 64 bytes per point.
pub(super) const OWNER_CELLS_PER_POINT: f64 = 32.0;

/// Per cell of a g × g-per-face cube grid: the owning point, or [`MIXED`].
#[derive(Clone, Debug)]
pub(crate) struct OwnerGrid {
    g: u32,
    half_g: f32,
    owner: Vec<u16>,
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
        let owner = if points.len() < MIXED as usize {
            single_owners(points, tris, g, nearest)
                .into_iter()
                .map(|o| o.map_or(MIXED, |p| p as u16))
                .collect()
        } else {
            vec![MIXED; 6 * g as usize * g as usize]
        };
        OwnerGrid {
            g,
            half_g: 0.5 * g as f32,
            owner,
        }
    }

    /// The point nearest to `d` when `d`'s cell has a single owner (the brute-force answer
    /// itself), `None` otherwise, and `None` for zero, tiny (< 1e-30), infinite and NaN
    /// inputs, whose cell the f32 cell computation does not place reliably. The cell is
    /// [`super::cube_grid::cell_of`]'s, with the range checks folded into one test.
    #[inline]
    pub fn owner(&self, d: Vec3) -> Option<usize> {
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
        let cell = (f * self.g + j.min(last)) * self.g + i.min(last);
        let o = self.owner[cell as usize];
        (o != MIXED).then_some(o as usize)
    }

    /// Bytes held by the table.
    pub fn bytes(&self) -> usize {
        self.owner.len() * std::mem::size_of::<u16>()
    }
}
