//! A table over the disk that answers most concentric [`HemisphereLayout::to_texel`] queries
//! with one read, exactly: the disk [−1, 1]² of the Malley projection (local x, y) is split into
//! G × G square cells, and a cell stores the texel of every direction above it when it is
//! certified to hold one, else a mark that sends the query to `to_texel`.
//!
//! **Certificate.** Cell (i, j) is enlarged by [`DELTA`] on every side (the f32 cell computation
//! `(x + 1)·G/2` is off by less than 3e-7 in x). The concentric inverse (Shirley–Chiu, in each
//! of the eight pieces cut by the axes and the diagonals: a = ±r, b = ±r·(4/π)·atan(|y|/|x|) or
//! the same with x and y swapped) is monotone in x and in y within a piece: with θ = atan(y/x)
//! ∈ [0, π/4] in the first piece, ∂b/∂y = (4/π)(θy + x)/r > 0 and ∂b/∂x = (4/π)(θx − y)/r ≤ 0
//! (θ ≤ tan θ), and r is monotone in |x| and |y| within a quadrant; the other pieces are its
//! mirror images. So over an enlarged cell inside one piece, each square coordinate ranges
//! between its values at the four corners (computed in f64). The libm inverse that `to_texel`
//! reproduces ([`HemisphereLayout::to_square_libm`]) is within [`SQUARE_MAX_DEVIATION`] of that
//! exact map in square units (measured near 3e-7 by `libm_is_near_the_exact_map`), and the
//! texel coordinate square · res adds an f32 rounding; when the whole range, widened by that
//! margin, floors (after the clamp to the map) to one column and one row, every direction of
//! the cell has that texel. Cells meeting an axis or a diagonal (widened by DELTA) are not
//! certified, nor is any direction below the horizon (z < 0, which the libm path moves to the
//! rim) or with a coordinate outside [−1, 1] or NaN.
//!
//! Only the concentric layout at res ≤ 255 has a table (u16 texels); for the others it is empty
//! and every query goes to `to_texel`.

use super::layout_fast::SQUARE_MAX_DEVIATION;
use super::{HemisphereLayout, LayoutKind};
use glam::Vec3;
use std::f64::consts::FRAC_PI_4;

/// Enlargement of every cell (disk units): over thirty times the cell computation's rounding.
const DELTA: f64 = 1e-5;
/// Marks an uncertified cell.
const MIXED: u16 = u16::MAX;
/// Table cells per texel along each axis (G = this × res, at most [`MAX_CELLS`]): about 70% of
/// the directions of a concentric map land in a certified cell, at 128 KiB for res = 32.
pub const CELLS_PER_TEXEL: u32 = 8;
/// Largest G: the table stays within 512 KiB (fewer cells per texel above res = 64).
pub const MAX_CELLS: u32 = 512;

/// The texel of concentric layout directions by table ([`Self::texel`]).
#[derive(Clone, Debug, PartialEq)]
pub struct TexelTable {
    layout: HemisphereLayout,
    g: u32,
    half_g: f32,
    texel: Vec<u16>,
}

/// Square coordinates in [−1, 1]² (a, b) of disk point (x, y) through the concentric inverse,
/// in f64 (the exact map of the module doc; `warp::concentric_disk_to_square` in f64).
fn concentric_exact(x: f64, y: f64) -> (f64, f64) {
    let r = x.hypot(y);
    if r == 0.0 {
        return (0.0, 0.0);
    }
    let mut phi = y.atan2(x);
    if phi < -FRAC_PI_4 {
        phi += 2.0 * std::f64::consts::PI;
    }
    if phi < FRAC_PI_4 {
        (r, r * phi / FRAC_PI_4)
    } else if phi < 3.0 * FRAC_PI_4 {
        (r * (2.0 * FRAC_PI_4 - phi) / FRAC_PI_4, r)
    } else if phi < 5.0 * FRAC_PI_4 {
        (-r, -r * (phi - 4.0 * FRAC_PI_4) / FRAC_PI_4)
    } else {
        (-r * (6.0 * FRAC_PI_4 - phi) / FRAC_PI_4, -r)
    }
}

/// The table cell of a direction, found once by [`TexelTable::prefetch`] and read by
/// [`TexelTable::texel_at`] (for the same direction).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TexelCell(Option<usize>);

impl TexelTable {
    /// The table of `layout` (empty unless concentric with res ≤ 255).
    pub fn new(layout: HemisphereLayout) -> TexelTable {
        let g = if layout.kind == LayoutKind::Concentric && layout.res <= 255 {
            (CELLS_PER_TEXEL * layout.res).min(MAX_CELLS)
        } else {
            0
        };
        let texel = (0..g * g)
            .map(|k| Self::certify(layout, g, k % g, k / g).map_or(MIXED, |t| t as u16))
            .collect();
        TexelTable {
            layout,
            g,
            half_g: 0.5 * g as f32,
            texel,
        }
    }

    /// The texel of every direction of enlarged cell (i, j) when the certificate holds.
    fn certify(layout: HemisphereLayout, g: u32, i: u32, j: u32) -> Option<u32> {
        let ((x0, x1), (y0, y1)) = super::cube_grid::enlarged_cell(g, i, j, DELTA);
        // Inside one piece: no axis and no diagonal crosses the cell.
        let abs_range = |a: f64, b: f64| {
            if a > 0.0 {
                Some((a, b))
            } else if b < 0.0 {
                Some((-b, -a))
            } else {
                None
            }
        };
        let (ax, ay) = (abs_range(x0, x1)?, abs_range(y0, y1)?);
        if !(ax.0 > ay.1 || ay.0 > ax.1) {
            return None;
        }
        let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)].map(|(x, y)| concentric_exact(x, y));
        let res = layout.res as f64;
        let margin = (SQUARE_MAX_DEVIATION as f64 + 2.0 * f32::EPSILON as f64) * res;
        let cell = |v: f64| (v.floor().max(0.0) as u32).min(layout.res - 1);
        let axis = |pick: fn(&(f64, f64)) -> f64| {
            let (lo, hi) = corners
                .iter()
                .map(pick)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                });
            let (lo, hi) = (
                0.5 * (lo + 1.0) * res - margin,
                0.5 * (hi + 1.0) * res + margin,
            );
            (cell(lo) == cell(hi)).then(|| cell(lo))
        };
        let (c, r) = (axis(|p| p.0)?, axis(|p| p.1)?);
        Some(r * layout.res + c)
    }

    /// The layout the table serves.
    pub fn layout(&self) -> HemisphereLayout {
        self.layout
    }

    /// `layout.to_texel(d)` for a local direction `d` (unit; z < 0 goes to the horizon as
    /// there): from the table when `d` lies in a certified cell, else from `to_texel`.
    #[inline]
    pub fn texel(&self, d: Vec3) -> u32 {
        self.texel_at(TexelCell(self.cell(d)), d)
    }

    /// [`Self::texel`] with `d`'s cell already found (`cell` is [`Self::prefetch`]`(d)`).
    #[inline]
    pub fn texel_at(&self, cell: TexelCell, d: Vec3) -> u32 {
        debug_assert_eq!(
            cell.0,
            self.cell(d),
            "texel_at: the cell of another direction"
        );
        self.certified_in(cell.0)
            .unwrap_or_else(|| self.layout.to_texel(d))
    }

    /// The table's texel of `d`, `None` when `d` is not in a certified cell.
    #[inline]
    pub fn certified(&self, d: Vec3) -> Option<u32> {
        self.certified_in(self.cell(d))
    }

    /// The texel stored in `cell`, `None` outside the table or where the cell is not certified.
    #[inline(always)]
    fn certified_in(&self, cell: Option<usize>) -> Option<u32> {
        let t = self.texel[cell?];
        (t != MIXED).then_some(t as u32)
    }

    /// The table cell of `d`, `None` outside the table (and always when it is empty).
    #[inline(always)]
    fn cell(&self, d: Vec3) -> Option<usize> {
        let gf = self.g as f32;
        let (fx, fy) = ((d.x + 1.0) * self.half_g, (d.y + 1.0) * self.half_g);
        // Also false for NaN, and always when the table is empty (g = 0).
        if !(d.z >= 0.0 && fx >= 0.0 && fx < gf && fy >= 0.0 && fy < gf) {
            return None;
        }
        // SAFETY: fx and fy are finite and in [0, g) (checked above), so they convert.
        let (i, j) = unsafe { (fx.to_int_unchecked::<u32>(), fy.to_int_unchecked::<u32>()) };
        Some((j * self.g + i) as usize)
    }

    /// Hints the CPU to fetch the table cell that [`Self::texel`] reads for `d`, and returns
    /// that cell for [`Self::texel_at`].
    #[inline(always)]
    pub fn prefetch(&self, d: Vec3) -> TexelCell {
        let cell = self.cell(d);
        if let Some(cell) = cell {
            crate::hint::prefetch_value(self.texel.as_ptr().wrapping_add(cell));
        }
        TexelCell(cell)
    }

    /// Cells per side of the table (G; 0 for an empty table).
    pub fn cells_per_side(&self) -> u32 {
        self.g
    }

    /// The raw cells for the GPU lookup (src/gpu/field_data.rs), row-major, G × G: a texel,
    /// or `u16::MAX` for `to_texel`.
    pub(crate) fn raw_cells(&self) -> &[u16] {
        &self.texel
    }

    /// Bytes held by the table.
    pub fn bytes(&self) -> usize {
        self.texel.len() * std::mem::size_of::<u16>()
    }
}
