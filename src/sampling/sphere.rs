//! Point sets on the unit sphere: where a field's positional samples (maps) sit.

use super::cube_grid::{first_nearest, CubeGrid};
use super::fibonacci::{self, FibonacciIndex};
use super::mesh::SphereMesh;
use super::owner_grid::{OwnerGrid, OWNER_CELLS_PER_POINT};
use super::rings::{slater_hemisphere_count, RingSet};
use super::SamplingError;
use glam::Vec3;
use rayon::prelude::*;

/// Which point set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SphereKind {
    /// Slater's hemisphere triangle subdivision (2008 paper): 2(2n²+2n+1) points.
    Slater,
    /// Latitude–longitude grid.
    LatLong,
    /// Spherical Fibonacci (Keinert et al. 2015).
    Fibonacci,
}

impl SphereKind {
    pub const ALL: [SphereKind; 3] = [
        SphereKind::Slater,
        SphereKind::LatLong,
        SphereKind::Fibonacci,
    ];

    /// The snake-case name used in specs and CSV files.
    pub fn name(self) -> &'static str {
        match self {
            SphereKind::Slater => "slater",
            SphereKind::LatLong => "lat_long",
            SphereKind::Fibonacci => "fibonacci",
        }
    }
}

// Size limits: about 2.6·10⁵ points for every kind, which keeps the triangulation (built once
// per set, in O(N) for ring sets and O(N^1.5) for Fibonacci sets) within seconds.
/// Largest Slater subdivision accepted (263 170 points).
const MAX_SLATER_N: u64 = 256;
/// Largest lat-long row count accepted (262 656 points).
const MAX_LAT_LONG_ROWS: u64 = 512;
/// Fibonacci sets accept 4 ≤ N ≤ 2¹⁸: the smallest count.
pub const MIN_FIBONACCI: usize = 4;
/// The largest Fibonacci count.
pub const MAX_FIBONACCI: usize = 1 << 18;

#[derive(Clone, Debug)]
enum Index {
    Rings(RingSet),
    Fibonacci(FibonacciIndex),
}

/// The owner-table cell of a direction, found once by [`SpherePoints::prefetch_nearest`] and
/// read by [`SpherePoints::nearest_at`] (for the same direction).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OwnerCell(Option<usize>);

impl OwnerCell {
    /// The cell `cell` of the owner table (`None`: no cell, the query goes to the search), as
    /// computed outside [`SpherePoints::prefetch_nearest`] (eight at a time by
    /// `field::lanes`); [`SpherePoints::nearest_at`] requires it to be that function's cell.
    #[inline(always)]
    pub(crate) fn new(cell: Option<usize>) -> OwnerCell {
        OwnerCell(cell)
    }
}

/// A point set on the unit sphere with exact nearest-point and interpolation queries.
///
/// The 2008 paper (Gaitatzes, Chrysanthou, Papaioannou, WSCG 2008, "Selecting Samples around the
/// Object") places its maps at points of Slater's method [M. Slater, "Constant time queries on
/// uniformly distributed points on a hemisphere", JGT 7(1), 2002, pp. 33–44]: a triangle
/// subdivision of the hemisphere, mirrored to cover the sphere, with a constant-time inverse; the
/// paper's slides describe it as bisecting triangle sides, projecting the new vertices onto the
/// sphere, and answering queries from a rendered colour-index map. The paper's counts 290 / 1090 /
/// 4226 / 16642 are 2(2n² + 2n + 1) for n = 8 / 16 / 32 / 64: twice the lattice points (i, j) with
/// |i| + |j| ≤ n. It compares them with spherical coordinates (1122 maps in its Figure 5).
///
/// - [`SphereKind::Slater`]: ring k = 0..n of each hemisphere holds the 4k lattice points with
///   |i| + |j| = k (one pole point for k = 0), equally spaced in azimuth; ring k is centred (in
///   cos θ) in the band of solid angle that holds the cumulative points N_{k−1} … N_k,
///   N_k = 2k² + 2k + 1, so every point gets solid angle 2π/H, H = N_n, and even the last ring
///   sits at cos θ = 2n/H > 0. The lower hemisphere is the mirror image turned by half a step of
///   ring n. Points are numbered ring by ring from the north pole. Deviation from the paper: this
///   equal-area ring placement replaces projecting subdivided triangles, and `nearest` is
///   analytic (no colour-index map); the triangles of [`Self::surrounding`] are still the
///   lattice triangles.
/// - [`SphereKind::LatLong`]: R rows × (R + 1) columns at cell centres, θ_r = (r + ½)π/R,
///   φ_c = 2π(c + ½)/(R + 1); no point on a pole. 1122 = 33 × 34 is the Figure 5 set.
/// - [`SphereKind::Fibonacci`]: Keinert et al., "Spherical Fibonacci Mapping", TOG 2015 (any
///   N ≥ 4): their inverse plus a certificate that guarantees exactness (beyond the paper, for
///   comparison).
///
/// `nearest` is exact: it equals a brute-force search over f64 dot products up to exact ties.
#[derive(Clone, Debug)]
pub struct SpherePoints {
    pub kind: SphereKind,
    points: Vec<Vec3>,
    index: Index,
    mesh: SphereMesh,
    grid: CubeGrid,
    owners: OwnerGrid,
}

/// Spacing of a point set, in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spacing {
    /// Covering radius: the largest angle from any direction to its nearest point (the largest
    /// Delaunay circumradius).
    pub max_gap: f64,
    /// Smallest angle between two points (the shortest Delaunay edge).
    pub min_separation: f64,
}

impl SpherePoints {
    /// Builds `count` points of `kind`; an error lists valid counts when `count` is impossible.
    pub fn new(kind: SphereKind, count: usize) -> Result<Self, SamplingError> {
        let index = match kind {
            SphereKind::Slater => {
                let n = (1..=MAX_SLATER_N)
                    .find(|&n| 2 * slater_hemisphere_count(n) == count as u64)
                    .ok_or_else(|| invalid_count(kind, count))?;
                Index::Rings(RingSet::slater(n as u32))
            }
            SphereKind::LatLong => {
                let rows = (2..=MAX_LAT_LONG_ROWS)
                    .find(|&r| r * (r + 1) == count as u64)
                    .ok_or_else(|| invalid_count(kind, count))?;
                Index::Rings(RingSet::lat_long(rows as u32, rows as u32 + 1))
            }
            SphereKind::Fibonacci => {
                if !(MIN_FIBONACCI..=MAX_FIBONACCI).contains(&count) {
                    return Err(invalid_count(kind, count));
                }
                Index::Fibonacci(FibonacciIndex::new(count as u64))
            }
        };
        let (points, tris) = match &index {
            Index::Rings(r) => (r.points(), r.triangles()),
            Index::Fibonacci(f) => {
                let p = f.points();
                let t = fibonacci::triangulate(&p).map_err(SamplingError::Invalid)?;
                (p, t)
            }
        };
        // Invariants that the exactness arguments rely on, checked once per set (cheap):
        // the ring premise of `rings::RingSet::nearest` and a triangulation covering the sphere.
        let broken =
            |e: String| SamplingError::Invalid(format!("{} set of {count}: {e}", kind.name()));
        if let Index::Rings(r) = &index {
            r.check_gap_condition(1e-5).map_err(broken)?;
        }
        let mesh = SphereMesh::new(&points, tris).map_err(broken)?;
        mesh.validate(&points, 1e-6).map_err(broken)?;
        let g = CubeGrid::resolution_for(points.len(), GRID_CELLS_PER_POINT);
        let grid = CubeGrid::new(&points, mesh.triangles(), g, |d| {
            analytic_nearest(&index, &points, d)
        });
        let owners = OwnerGrid::new(
            &points,
            mesh.triangles(),
            CubeGrid::resolution_for(points.len(), OWNER_CELLS_PER_POINT),
            |d| analytic_nearest(&index, &points, d),
        );
        Ok(SpherePoints {
            kind,
            points,
            index,
            mesh,
            grid,
            owners,
        })
    }

    /// The valid counts of `kind`, smallest first, up to `limit` of them.
    pub fn valid_counts(kind: SphereKind, limit: usize) -> Vec<usize> {
        match kind {
            SphereKind::Slater => (1..=MAX_SLATER_N)
                .map(|n| 2 * slater_hemisphere_count(n) as usize)
                .take(limit)
                .collect(),
            SphereKind::LatLong => (2..=MAX_LAT_LONG_ROWS)
                .map(|r| (r * (r + 1)) as usize)
                .take(limit)
                .collect(),
            SphereKind::Fibonacci => (MIN_FIBONACCI..=MAX_FIBONACCI).take(limit).collect(),
        }
    }

    /// Whether [`Self::new`] accepts `count` for `kind`, without building the set; the error
    /// is the one `new` gives.
    pub fn check_count(kind: SphereKind, count: usize) -> Result<(), SamplingError> {
        let ok = match kind {
            SphereKind::Slater => {
                (1..=MAX_SLATER_N).any(|n| 2 * slater_hemisphere_count(n) == count as u64)
            }
            SphereKind::LatLong => (2..=MAX_LAT_LONG_ROWS).any(|r| r * (r + 1) == count as u64),
            SphereKind::Fibonacci => (MIN_FIBONACCI..=MAX_FIBONACCI).contains(&count),
        };
        ok.then_some(()).ok_or_else(|| invalid_count(kind, count))
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Unit point `i`.
    pub fn point(&self, i: usize) -> Vec3 {
        self.points[i]
    }

    /// All points (unit, f32).
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// Index of the point nearest to unit direction `d` (largest dot product). Exact and
    /// constant-time; `d` need not be normalised. Answered from a cube-map grid of candidate
    /// lists (`super::cube_grid`): the first largest f64 dot product, the same index as
    /// [`Self::nearest_brute_force`]. Most directions are answered by one read of a finer
    /// table of cells with a single owner (`super::owner_grid`), the rest by the candidate
    /// search ([`Self::nearest_searched`]).
    #[inline]
    pub fn nearest(&self, d: Vec3) -> usize {
        self.nearest_at(OwnerCell(self.owners.cell(d)), d)
    }

    /// [`Self::nearest`] with `d`'s owner-table cell already found (`cell` is
    /// [`Self::prefetch_nearest`]`(d)`).
    #[inline]
    pub fn nearest_at(&self, cell: OwnerCell, d: Vec3) -> usize {
        self.owners
            .owner_at(cell.0, &self.points, d)
            .unwrap_or_else(|| self.nearest_searched(d))
    }

    /// The owner table's cells per cube-face edge g and g/2, the terms of its cell computation
    /// (for `field::lanes`, which computes the cells of eight directions at a time).
    #[inline(always)]
    pub(crate) fn owner_cell_scale(&self) -> (u32, f32) {
        self.owners.cell_scale()
    }

    /// Hints the CPU to fetch owner-table cell `cell` (no effect on results).
    #[inline(always)]
    pub(crate) fn prefetch_owner_cell(&self, cell: OwnerCell) {
        if let Some(c) = cell.0 {
            self.owners.prefetch_cell(c);
        }
    }

    /// Hints the CPU to fetch the owner-table cell that [`Self::nearest`] reads for `d` (no
    /// effect on results), and returns that cell for [`Self::nearest_at`].
    #[inline]
    pub fn prefetch_nearest(&self, d: Vec3) -> OwnerCell {
        OwnerCell(self.owners.prefetch(d))
    }

    /// [`Self::nearest`] without the owner table: always the cube grid's candidate search (the
    /// reference the table is tested against).
    #[inline(never)]
    pub fn nearest_searched(&self, d: Vec3) -> usize {
        self.grid.nearest(&self.points, d)
    }

    /// The owner table's answer alone: `Some(`[`Self::nearest`]`(d))` when `d` lies in a cell
    /// with one or two candidates, `None` when the query goes to the candidate search.
    pub fn nearest_owned(&self, d: Vec3) -> Option<usize> {
        self.owners.owner(&self.points, d)
    }

    /// The owner table of [`Self::nearest`] as stored (the GPU lookup uploads it): cells per
    /// face edge, per-cell codes (owner < len, pair len + k, `u16::MAX` for the search), pairs.
    pub(crate) fn owner_table_raw(&self) -> (u32, &[u16], &[[u16; 2]]) {
        self.owners.raw()
    }

    /// The candidate slots of the cube grid that [`Self::nearest`] searches where the owner
    /// table leaves a cell open (the GPU lookup uploads them): cells per face edge, per cell
    /// four candidates or `u32::MAX` first when it has more.
    pub(crate) fn candidate_slots_raw(&self) -> (u32, &[[u32; 4]]) {
        self.grid.raw_slots()
    }

    /// Bytes of the owner table that answers most [`Self::nearest`] queries.
    pub fn owner_table_bytes(&self) -> usize {
        self.owners.bytes()
    }

    /// The analytic nearest-point query of the set (Slater and lat-long rings, Keinert et al.
    /// plus a certificate for Fibonacci): exact up to ties within 1e-12, constant-time, without
    /// the grid; it builds the grid and serves as a second oracle in tests.
    pub fn nearest_analytic(&self, d: Vec3) -> usize {
        analytic_nearest(&self.index, &self.points, d)
    }

    /// Keinert et al.'s published four-candidate inverse for Fibonacci sets, without our
    /// exactness certificate (it agreed with [`Self::nearest`] on every direction tested);
    /// `None` for other kinds.
    pub fn nearest_keinert(&self, d: Vec3) -> Option<usize> {
        match &self.index {
            Index::Fibonacci(f) => Some(f.nearest_keinert(&self.points, d)),
            Index::Rings(_) => None,
        }
    }

    /// Brute-force nearest point by f64 dot products (O(N); the reference for tests).
    pub fn nearest_brute_force(&self, d: Vec3) -> usize {
        first_nearest(&self.points, d.as_dvec3(), 0..self.points.len())
    }

    /// How many of `dirs` get a [`Self::nearest`] answer worse than brute force by more than
    /// 1e-12 in f64 dot product (exact ties are not mismatches). Parallel; a vectorised f32
    /// pre-pass skips the exact f64 scan unless another point comes within 1e-5 in dot product.
    pub fn nearest_mismatches(&self, dirs: &[Vec3]) -> usize {
        self.mismatches_of(dirs, |d| self.nearest(d))
    }

    /// [`Self::nearest_mismatches`] of [`Self::nearest_analytic`].
    pub fn nearest_analytic_mismatches(&self, dirs: &[Vec3]) -> usize {
        self.mismatches_of(dirs, |d| self.nearest_analytic(d))
    }

    fn mismatches_of(&self, dirs: &[Vec3], query: impl Fn(Vec3) -> usize + Sync) -> usize {
        let xs: Vec<f32> = self.points.iter().map(|p| p.x).collect();
        let ys: Vec<f32> = self.points.iter().map(|p| p.y).collect();
        let zs: Vec<f32> = self.points.iter().map(|p| p.z).collect();
        dirs.par_iter()
            .filter(|&&d| {
                let ours = query(d);
                let dd = d.as_dvec3();
                let ours_dot = dd.dot(self.points[ours].as_dvec3());
                // f32 dots of unit vectors are within 1e-6 of the f64 ones.
                let others = max_dot(&xs[..ours], &ys[..ours], &zs[..ours], d).max(max_dot(
                    &xs[ours + 1..],
                    &ys[ours + 1..],
                    &zs[ours + 1..],
                    d,
                ));
                if (others as f64) < ours_dot - 1e-5 {
                    return false;
                }
                self.points
                    .iter()
                    .any(|p| dd.dot(p.as_dvec3()) - ours_dot > 1e-12)
            })
            .count()
    }

    /// Three points around unit direction `d` and barycentric weights (non-negative, summing to
    /// 1): the triangle of this set's triangulation containing `d` (Slater: lattice triangles;
    /// lat-long: grid quads split in two, fans at the polar caps; Fibonacci: Delaunay), found by
    /// walking from the nearest point. The weights are the planar barycentrics of the point where
    /// the ray along `d` meets the triangle's plane, so Σ wᵢ pᵢ is parallel to `d`.
    #[inline]
    pub fn surrounding(&self, d: Vec3) -> ([usize; 3], [f32; 3]) {
        let tris = self.mesh.triangles();
        let (t, w) = self.grid.locate(&self.points, tris, d).unwrap_or_else(|| {
            self.mesh
                .locate(&self.points, d.as_dvec3(), self.nearest(d))
        });
        let tri = tris[t];
        (tri.map(|v| v as usize), w.map(|x| x as f32))
    }

    /// The triangles used by [`Self::surrounding`] (counter-clockwise seen from outside).
    pub fn triangles(&self) -> &[[u32; 3]] {
        self.mesh.triangles()
    }

    /// Covering radius and smallest separation, from the Delaunay triangulation (Lawson flips
    /// of this set's triangulation, to a 1e-9 tolerance).
    pub fn spacing(&self) -> Result<Spacing, SamplingError> {
        let del = self
            .mesh
            .delaunay(&self.points, 1e-9)
            .map_err(SamplingError::Invalid)?;
        let max_gap = del
            .circumradii(&self.points)
            .map(|(_, r)| r)
            .fold(0.0, f64::max);
        Ok(Spacing {
            max_gap,
            min_separation: del.min_edge(&self.points),
        })
    }

    #[cfg(test)]
    pub(crate) fn mesh(&self) -> &SphereMesh {
        &self.mesh
    }

    #[cfg(test)]
    pub(crate) fn grid(&self) -> &CubeGrid {
        &self.grid
    }
}

/// Cube-map grid cells per point: a candidate list holds two points on average.
const GRID_CELLS_PER_POINT: f64 = 4.0;

fn analytic_nearest(index: &Index, points: &[Vec3], d: Vec3) -> usize {
    match index {
        Index::Rings(r) => r.nearest(points, d),
        Index::Fibonacci(f) => f.nearest(points, d),
    }
}

/// Largest f32 dot product of `d` with the points (xs, ys, zs); written to vectorise.
fn max_dot(xs: &[f32], ys: &[f32], zs: &[f32], d: Vec3) -> f32 {
    const L: usize = 8;
    let (cx, rx) = xs.as_chunks::<L>();
    let (cy, ry) = ys.as_chunks::<L>();
    let (cz, rz) = zs.as_chunks::<L>();
    let mut m = [f32::NEG_INFINITY; L];
    for ((x, y), z) in cx.iter().zip(cy).zip(cz) {
        for l in 0..L {
            let v = x[l] * d.x + y[l] * d.y + z[l] * d.z;
            m[l] = if v > m[l] { v } else { m[l] };
        }
    }
    let mut best = m.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    for ((x, y), z) in rx.iter().zip(ry).zip(rz) {
        best = best.max(x * d.x + y * d.y + z * d.z);
    }
    best
}

fn invalid_count(kind: SphereKind, count: usize) -> SamplingError {
    let msg = match kind {
        SphereKind::Slater => format!(
            "slater: {count} points is impossible; counts are 2(2n²+2n+1) for n = 1..={MAX_SLATER_N}: \
             {:?}, …, 290 (n = 8), 1090 (16), 4226 (32), 16642 (64), …",
            SpherePoints::valid_counts(kind, 8)
        ),
        SphereKind::LatLong => format!(
            "lat_long: {count} points is impossible; counts are R·(R+1) (R rows × R+1 columns) for \
             R = 2..={MAX_LAT_LONG_ROWS}: {:?}, …, 1122 (33 × 34), …",
            SpherePoints::valid_counts(kind, 8)
        ),
        SphereKind::Fibonacci => format!(
            "fibonacci: {count} points is impossible; any count in {MIN_FIBONACCI}..={MAX_FIBONACCI}"
        ),
    };
    SamplingError::Invalid(msg)
}

/// Normalised weighted sum of three points (for checking interpolation weights).
#[cfg(test)]
fn blend(set: &SpherePoints, idx: [usize; 3], w: [f32; 3]) -> glam::DVec3 {
    (0..3)
        .map(|k| set.point(idx[k]).as_dvec3() * w[k] as f64)
        .sum::<glam::DVec3>()
        .normalize()
}

#[cfg(test)]
#[path = "sphere_tests.rs"]
mod tests;
