//! Hemisphere layouts of a directional map: polar, rejection (Malley) and concentric (Malley).
//!
//! Each layout maps the square [0, 1]² of the map to the hemisphere z ≥ 0 (the 2008 paper,
//! "Sampling a Hemisphere of Directions", Figure 3): texel (column c, row r) is the cell
//! [c, c+1]/res × [r, r+1]/res and its sample direction is the image of the cell centre.
//! Forward map, inverse and measures sit side by side:
//!
//! | layout | square → hemisphere | used texels | solid angle / projected solid angle |
//! |---|---|---|---|
//! | polar | θ = v·π/2, φ = u·2π | all | Δφ (cos θ₀ − cos θ₁) / ½Δφ (sin²θ₁ − sin²θ₀) |
//! | rejection | disk point 2u − 1, Malley lift | centre in the disk: π/4 of them | closed form ([`super::texel_measure`]) / disk area of cell ∩ disk |
//! | concentric | Shirley–Chiu disk, Malley lift | all | closed form / π/res² for every texel |
//!
//! Rejection layout rim rule: a texel is used when its centre lies in the unit disk (never on
//! the circle: for any res the centre coordinates are odd multiples of 1/res, and two odd squares
//! never sum to res²). A direction whose disk point falls in an unused texel's cell (a sliver
//! near the rim, or a below-horizon direction clamped onto the rim) maps to the used texel whose
//! centre is nearest to that disk point. Proof that a 5 × 5 neighbourhood holds it (h = 2/res
//! the texel size in disk units): if |p| ≥ √2 h, the point q = p (1 − √2 h/|p|) lies in a cell
//! whose centre c has |c| ≤ |q| + h/√2 < 1, a used texel with |c − p| ≤ √2 h + h/√2 < 2.13 h;
//! a centre k cells away along an axis is at least (|k| − ½) h from p, so |k| ≤ 2. If
//! |p| < √2 h, p's own cell has |centre| < √2 h + h/√2 < 1 for res ≥ 5 (smaller maps are
//! searched whole). [`HemisphereLayout::solid_angle`] measures each texel's own cell; the rim
//! slivers of unused cells ([`HemisphereLayout::rim_solid_angle`]) are what `to_texel` hands to
//! neighbouring used texels.

use super::layout_fast;
use super::texel_measure::{concentric_rect_solid_angle, disk_rect_area, malley_rect_solid_angle};
use super::warp::{
    concentric_disk_to_square, disk_to_hemisphere, hemisphere_to_disk, polar_hemisphere_to_square,
    square_to_concentric_disk, square_to_polar_hemisphere,
};
use super::SamplingError;
use glam::{Vec2, Vec3};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// How a square map of `res × res` texels covers the hemisphere `z >= 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LayoutKind {
    /// Uniform in θ (rows) and φ (columns).
    Polar,
    /// Square → disk by rejection (texels outside the inscribed disk unused), then Malley.
    Rejection,
    /// Shirley–Chiu concentric square → disk, then Malley.
    Concentric,
}

impl LayoutKind {
    pub const ALL: [LayoutKind; 3] = [
        LayoutKind::Polar,
        LayoutKind::Rejection,
        LayoutKind::Concentric,
    ];

    /// The snake-case name used in specs and CSV files.
    pub fn name(self) -> &'static str {
        match self {
            LayoutKind::Polar => "polar",
            LayoutKind::Rejection => "rejection",
            LayoutKind::Concentric => "concentric",
        }
    }
}

/// Largest resolution accepted by [`HemisphereLayout::try_new`] (texel indices stay in u32).
pub const MAX_LAYOUT_RES: u32 = 1 << 15;

/// A directional map layout at a resolution. Texel index = row · res + column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct HemisphereLayout {
    pub kind: LayoutKind,
    pub res: u32,
}

impl HemisphereLayout {
    /// # Panics
    /// If `res` is 0 or above `MAX_LAYOUT_RES`; use [`Self::try_new`] for user input.
    pub fn new(kind: LayoutKind, res: u32) -> Self {
        Self::try_new(kind, res).unwrap_or_else(|e| panic!("{e}"))
    }

    pub fn try_new(kind: LayoutKind, res: u32) -> Result<Self, SamplingError> {
        if res == 0 || res > MAX_LAYOUT_RES {
            return Err(SamplingError::Invalid(format!(
                "{} layout: resolution {res} is outside 1..={MAX_LAYOUT_RES}",
                kind.name()
            )));
        }
        Ok(HemisphereLayout { kind, res })
    }

    pub fn texel_count(&self) -> usize {
        (self.res as usize) * (self.res as usize)
    }

    /// (column, row) of texel `t`.
    #[inline]
    pub fn col_row(&self, t: u32) -> (u32, u32) {
        (t % self.res, t / self.res)
    }

    /// Centre of texel `t` in the square [0, 1]².
    #[inline]
    pub fn texel_centre(&self, t: u32) -> Vec2 {
        let (c, r) = self.col_row(t);
        Vec2::new(
            (c as f32 + 0.5) / self.res as f32,
            (r as f32 + 0.5) / self.res as f32,
        )
    }

    /// Whether texel `t` holds a direction (false only for rejection texels whose centre lies
    /// outside the disk).
    #[inline]
    pub fn is_used(&self, t: u32) -> bool {
        match self.kind {
            LayoutKind::Rejection => {
                let (c, r) = self.col_row(t);
                // Centre in disk units: (2c + 1 − res)/res; compare in integers.
                let (x, y) = (
                    2 * c as i64 + 1 - self.res as i64,
                    2 * r as i64 + 1 - self.res as i64,
                );
                x * x + y * y < (self.res as i64) * (self.res as i64)
            }
            LayoutKind::Polar | LayoutKind::Concentric => true,
        }
    }

    /// Number of used texels.
    pub fn used_count(&self) -> usize {
        match self.kind {
            LayoutKind::Rejection => (0..self.texel_count() as u32)
                .filter(|&t| self.is_used(t))
                .count(),
            LayoutKind::Polar | LayoutKind::Concentric => self.texel_count(),
        }
    }

    /// Direction (local frame, unit, z >= 0) through the centre of texel `t`; `None` when the
    /// texel is unused by this layout.
    pub fn to_direction(&self, t: u32) -> Option<Vec3> {
        if t as usize >= self.texel_count() || !self.is_used(t) {
            return None;
        }
        let u = self.texel_centre(t);
        Some(match self.kind {
            LayoutKind::Polar => square_to_polar_hemisphere(u),
            LayoutKind::Rejection => disk_to_hemisphere(2.0 * u - Vec2::ONE),
            LayoutKind::Concentric => disk_to_hemisphere(square_to_concentric_disk(u)),
        })
    }

    /// The square coordinates [0, 1]² of local direction `d` (unit; z < 0 clamped to the
    /// horizon): the inverse of the layout's square → hemisphere map. Polar and concentric use a
    /// polynomial atan (`super::layout_fast`) within 4e-6 of [`Self::to_square_libm`].
    #[inline]
    pub fn to_square(&self, d: Vec3) -> Vec2 {
        self.fast_square(d)
            .unwrap_or_else(|| self.to_square_libm(d))
    }

    /// The polynomial-atan square coordinates of [`super::layout_fast`] (polar and concentric).
    #[inline]
    fn fast_square(&self, d: Vec3) -> Option<Vec2> {
        match self.kind {
            LayoutKind::Polar => layout_fast::polar_square(d),
            LayoutKind::Rejection => None,
            LayoutKind::Concentric => layout_fast::concentric_square(d),
        }
    }

    /// [`Self::to_square`] through the libm inverses of [`super::warp`] (the reference that
    /// [`Self::to_cell`] and [`Self::to_texel`] reproduce exactly).
    pub fn to_square_libm(&self, d: Vec3) -> Vec2 {
        match self.kind {
            LayoutKind::Polar => polar_hemisphere_to_square(d),
            LayoutKind::Rejection => {
                // A unit d gives |p| ≤ 1; clamp longer inputs onto the rim.
                let p = hemisphere_to_disk(d);
                let p = if p.length_squared() > 1.0 {
                    p.normalize()
                } else {
                    p
                };
                0.5 * (p + Vec2::ONE)
            }
            LayoutKind::Concentric => concentric_disk_to_square(hemisphere_to_disk(d)),
        }
    }

    /// Continuous texel coordinates of `d`: texel (c, r) spans [c, c+1) × [r, r+1), its centre
    /// at (c + ½, r + ½). Subtract ½ for bilinear lookups.
    #[inline]
    pub fn to_texel_continuous(&self, d: Vec3) -> Vec2 {
        self.to_square(d) * self.res as f32
    }

    /// The texel whose cell contains `d`'s square point through the libm inverse (for the
    /// rejection layout this may be an unused texel near the rim; see [`Self::to_texel`]). The
    /// fast coordinates decide it whenever they lie clearly inside a cell
    /// (`super::layout_fast::certified_cell`), so the answer is always the libm one.
    #[inline]
    pub fn to_cell(&self, d: Vec3) -> u32 {
        if let Some((c, r)) = self
            .fast_square(d)
            .and_then(|q| layout_fast::certified_cell(q * self.res as f32, self.res))
        {
            return r * self.res + c;
        }
        self.cell_of(self.to_square_libm(d) * self.res as f32)
    }

    /// The cell of continuous texel coordinates `p`, clamped to the map.
    #[inline]
    fn cell_of(&self, p: Vec2) -> u32 {
        let last = self.res - 1;
        let c = (p.x.max(0.0) as u32).min(last);
        let r = (p.y.max(0.0) as u32).min(last);
        r * self.res + c
    }

    /// The texel containing local direction `d` (unit; z < 0 is clamped to the horizon). Always
    /// a used texel: for the rejection layout, a disk point in an unused cell goes to the used
    /// texel with the nearest centre (module doc).
    #[inline]
    pub fn to_texel(&self, d: Vec3) -> u32 {
        let t = self.to_cell(d);
        if self.kind != LayoutKind::Rejection || self.is_used(t) {
            return t;
        }
        self.nearest_used(self.to_texel_continuous(d))
    }

    /// The used texel whose centre is nearest to continuous texel coordinates `p` (5 × 5
    /// neighbourhood of p's cell, the whole map when res < 5).
    fn nearest_used(&self, p: Vec2) -> u32 {
        let res = self.res as i64;
        let (pc, pr) = (p.x.floor() as i64, p.y.floor() as i64);
        let reach = if res < 5 { res } else { 2 };
        let mut best = (u32::MAX, f32::INFINITY);
        for r in (pr - reach).max(0)..=(pr + reach).min(res - 1) {
            for c in (pc - reach).max(0)..=(pc + reach).min(res - 1) {
                let t = (r * res + c) as u32;
                if !self.is_used(t) {
                    continue;
                }
                let d2 = (Vec2::new(c as f32 + 0.5, r as f32 + 0.5) - p).length_squared();
                if d2 < best.1 {
                    best = (t, d2);
                }
            }
        }
        best.0
    }

    /// Cell bounds of texel `t` in the square [0, 1]², as (u0, u1, v0, v1) in f64.
    fn cell(&self, t: u32) -> (f64, f64, f64, f64) {
        let (c, r) = self.col_row(t);
        let h = 1.0 / self.res as f64;
        (
            c as f64 * h,
            (c + 1) as f64 * h,
            r as f64 * h,
            (r + 1) as f64 * h,
        )
    }

    /// Solid angle (sr) of the hemisphere region whose square point lies in texel `t`'s cell:
    /// exact (closed forms, f64). Summed over all texels it is 2π for every layout; for the
    /// rejection layout the unused texels' share is [`Self::rim_solid_angle`].
    pub fn solid_angle(&self, t: u32) -> f64 {
        let (u0, u1, v0, v1) = self.cell(t);
        // The cell in disk units, for the Malley layouts.
        let [x0, x1, y0, y1] = [u0, u1, v0, v1].map(|u| 2.0 * u - 1.0);
        match self.kind {
            LayoutKind::Polar => {
                let (t0, t1) = (v0 * FRAC_PI_2, v1 * FRAC_PI_2);
                (u1 - u0) * TAU * (t0.cos() - t1.cos())
            }
            LayoutKind::Rejection => malley_rect_solid_angle(x0, x1, y0, y1),
            LayoutKind::Concentric => concentric_rect_solid_angle(x0, x1, y0, y1),
        }
    }

    /// Projected solid angle ∫ cos θ dω (sr) of texel `t`'s cell: exact. Divided by π it is the
    /// probability that a cosine-distributed direction falls in the cell. For the Malley layouts
    /// it is the cell's disk area: π/res² for every concentric texel.
    pub fn projected_solid_angle(&self, t: u32) -> f64 {
        let (u0, u1, v0, v1) = self.cell(t);
        // The cell in disk units, for the Malley layouts.
        let [x0, x1, y0, y1] = [u0, u1, v0, v1].map(|u| 2.0 * u - 1.0);
        match self.kind {
            LayoutKind::Polar => {
                let (s0, s1) = ((v0 * FRAC_PI_2).sin(), (v1 * FRAC_PI_2).sin());
                (u1 - u0) * TAU * 0.5 * (s1 * s1 - s0 * s0)
            }
            LayoutKind::Rejection => disk_rect_area(x0, x1, y0, y1),
            LayoutKind::Concentric => PI / self.texel_count() as f64,
        }
    }

    /// Probability that a cosine-distributed direction falls in texel `t`'s cell.
    pub fn cosine_probability(&self, t: u32) -> f64 {
        self.projected_solid_angle(t) / PI
    }

    /// Solid angle (sr) of the unused texels' cells inside the disk: the rim slivers that
    /// [`Self::to_texel`] assigns to neighbouring used texels (0 except for rejection).
    pub fn rim_solid_angle(&self) -> f64 {
        (0..self.texel_count() as u32)
            .filter(|&t| !self.is_used(t))
            .map(|t| self.solid_angle(t))
            .fold(0.0, |a, b| a + b)
    }
}

#[cfg(test)]
#[path = "layout_tests.rs"]
mod tests;
