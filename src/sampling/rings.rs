//! Ring point sets: points on circles of constant polar angle ("rings"), equally spaced in
//! azimuth on each ring. Slater's hemisphere subdivision and the latitude–longitude grid are both
//! ring sets, so they share one exact, constant-time nearest-point query and one triangulation.
//!
//! # Why `nearest` is exact
//!
//! Rings are numbered r = 0, 1, … by increasing polar angle θ_r; ring r holds m_r points at
//! azimuths 2π (j + phase_r) / m_r. Let d have polar angle θ and azimuth φ.
//!
//! 1. *Within a ring.* For points at a fixed θ_r the dot product with d is
//!    |d| (cos θ cos θ_r + sin θ sin θ_r cos Δφ), decreasing in |Δφ| ∈ [0, π]; so the closest
//!    point of ring r is the one nearest in azimuth. With u = φ m_r / 2π − phase_r it is
//!    round(u), which is always floor(u) or floor(u) + 1, even when u carries an error below ½
//!    (an error δ < ½ moves u by less than one, and round(u_exact) stays in
//!    {floor u, floor u + 1}). Both are candidates. φ comes from [`atan2_approx`], off by at most
//!    2e-5 rad, so u is off by less than 2e-5 · m / 2π < ½ for every ring of up to 1.5·10⁵
//!    points (the sets built by `SpherePoints` have at most 1024 per ring).
//! 2. *Ring bound.* For any point p of ring r, Cauchy–Schwarz on the xy parts gives
//!    d · p ≤ d_z cos θ_r + |d_xy| sin θ_r = |d| cos(θ − θ_r) =: B_r. The stored points are f32
//!    roundings, off the ideal ring by < 1e-7 per coordinate, so d · p < B_r + 1e-6 |d|.
//! 3. *Search.* We compute in O(1) the ring index a with θ_a ≤ θ < θ_{a+1} (a = −1 above the
//!    first ring, a = last ring below the last; the computation is accurate to ~1e-15 rad and
//!    only ever needs to be right to within one ring), test the two bracket rings, then walk
//!    outwards on each side while B_c + 1e-6 |d| exceeds the best dot product found. Beyond the
//!    bracket, |θ − θ_c| grows with every step away, so B_c only decreases: the first ring that
//!    fails the test proves every ring beyond it worse. The walk therefore never skips a closer
//!    point, and the candidates are compared by f64 dot products — the arithmetic a brute-force
//!    search uses — so the answer equals brute force up to exact ties.
//! 4. *Constant time.* The walk stops after at most one ring past the bracket on each side when
//!    θ_{r+2} − θ_r ≥ h_r + 2ε and θ_r − θ_{r−2} ≥ h_r + 2ε for every ring r, with
//!    h_r = sin θ_r · π / m_r half the azimuthal spacing as arc length and ε a small slack:
//!    the best bracket ring is then within angle (distance to the ring) + h_r of d, while ring
//!    a+3 (or a−2) lies at least that far away in θ alone. [`RingSet::check_gap_condition`]
//!    verifies this for every set built (a test runs it for every Slater n ≤ 256 and every
//!    lat-long grid up to 256 rows with ε = 1e-5 rad). For Slater rings h_r / (θ_{r+1} − θ_r)
//!    tends to π/4 and is at most ≈1.1 next to the pole; for an R × (R+1) lat-long grid,
//!    2π/R ≥ π/(R+1) holds trivially. So at most 4 rings × 2 azimuths = 8 dot products.

use super::approx::{atan2_approx, floor_i64};
use glam::{DVec3, Vec3};
use std::f64::consts::{PI, TAU};

/// One ring of a [`RingSet`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ring {
    /// cos θ of the ring.
    pub z: f64,
    /// sin θ of the ring (kept separately: accurate near the poles).
    pub sin_theta: f64,
    /// Points on the ring (1 for a pole point).
    pub count: u32,
    /// Point j sits at azimuth 2π (j + phase) / count.
    pub phase: f64,
    /// Index of the ring's first point in the set.
    pub first: u32,
}

impl Ring {
    pub fn theta(&self) -> f64 {
        self.sin_theta.atan2(self.z)
    }

    /// Half the azimuthal spacing as arc length (h_r in the module proof).
    pub fn half_spacing(&self) -> f64 {
        self.sin_theta * PI / self.count as f64
    }

    /// Unit point `j` of the ring, in f64.
    pub fn point(&self, j: u32) -> DVec3 {
        let phi = TAU * (j as f64 + self.phase) / self.count as f64;
        let (s, c) = phi.sin_cos();
        DVec3::new(self.sin_theta * c, self.sin_theta * s, self.z)
    }
}

/// How the bracketing ring is found from a direction in constant time.
#[derive(Clone, Copy, Debug)]
enum Bracket {
    /// Slater rings: `n` subdivisions, `h` = 2n² + 2n + 1 points per hemisphere.
    Slater { n: u32, h: f64 },
    /// Lat-long rows at θ_r = (r + ½) π / rows.
    LatLong { rows: u32 },
}

/// A set of rings ordered by increasing θ, points numbered ring by ring.
#[derive(Clone, Debug)]
pub(crate) struct RingSet {
    rings: Vec<Ring>,
    bracket: Bracket,
}

/// Points per hemisphere of Slater's subdivision with `n` steps: the lattice points (i, j) with
/// |i| + |j| ≤ n, i.e. 1 + Σ_{k=1..n} 4k = 2n² + 2n + 1.
pub(crate) fn slater_hemisphere_count(n: u64) -> u64 {
    2 * n * n + 2 * n + 1
}

impl RingSet {
    /// Slater's hemisphere triangle subdivision with `n` steps, mirrored to the full sphere.
    ///
    /// Ring k = 0..n of the upper hemisphere holds the 4k lattice points with |i| + |j| = k (one
    /// point for k = 0). Deviation from the paper: the rings are placed on an equal-area rule
    /// (see [`crate::sampling::SpherePoints`]) rather than by projecting midpoint-subdivided
    /// triangles; the lower hemisphere is the mirror image turned by half a step of ring n
    /// (π / 4n) so that the two equatorial rings interleave.
    pub fn slater(n: u32) -> Self {
        let h = slater_hemisphere_count(n as u64) as f64;
        let ring = |k: u32| -> (f64, u32) {
            // 1 − cos θ_k: the middle (in cos θ) of the band holding cumulative points
            // [N_{k−1}, N_k] with N_k = 2k² + 2k + 1: (N_{k−1} + N_k) / 2H = (2k² + 1) / H.
            let s = if k == 0 {
                0.0
            } else {
                (2.0 * (k as f64) * (k as f64) + 1.0) / h
            };
            (s, if k == 0 { 1 } else { 4 * k })
        };
        let mut first = 0u32;
        // The upper hemisphere's rings from the north pole, then the lower's up to the south.
        let lower = (0..=n).rev().map(|k| (k, true));
        let rings = (0..=n)
            .map(|k| (k, false))
            .chain(lower)
            .map(|(k, lower)| {
                let (s, count) = ring(k);
                let ring = Ring {
                    z: if lower { -(1.0 - s) } else { 1.0 - s },
                    sin_theta: (s * (2.0 - s)).sqrt(),
                    count,
                    // Lower rings: a turn of π / 4n is k / 2n steps of ring k (spacing 2π / 4k).
                    phase: if lower && k != 0 {
                        k as f64 / (2.0 * n as f64)
                    } else {
                        0.0
                    },
                    first,
                };
                first += count;
                ring
            })
            .collect();
        RingSet {
            rings,
            bracket: Bracket::Slater { n, h },
        }
    }

    /// A `rows × cols` latitude–longitude grid at cell centres: θ_r = (r + ½) π / rows,
    /// φ_c = 2π (c + ½) / cols. No point sits on a pole.
    pub fn lat_long(rows: u32, cols: u32) -> Self {
        let rings = (0..rows)
            .map(|r| {
                let theta = (r as f64 + 0.5) * PI / rows as f64;
                Ring {
                    z: theta.cos(),
                    sin_theta: theta.sin(),
                    count: cols,
                    phase: 0.5,
                    first: r * cols,
                }
            })
            .collect();
        RingSet {
            rings,
            bracket: Bracket::LatLong { rows },
        }
    }

    #[cfg(test)]
    pub fn rings(&self) -> &[Ring] {
        &self.rings
    }

    pub fn len(&self) -> usize {
        self.rings.iter().map(|r| r.count as usize).sum()
    }

    /// All points, ring by ring, rounded to f32.
    pub fn points(&self) -> Vec<Vec3> {
        let mut v = Vec::with_capacity(self.len());
        for ring in &self.rings {
            for j in 0..ring.count {
                v.push(ring.point(j).as_vec3());
            }
        }
        v
    }

    /// The index a of the ring with θ_a ≤ θ(d) < θ_{a+1} (−1 above the first ring), in O(1).
    fn bracket(&self, d: DVec3) -> i64 {
        let rho2 = d.x * d.x + d.y * d.y;
        let len = (rho2 + d.z * d.z).sqrt();
        if len == 0.0 {
            return 0;
        }
        match self.bracket {
            Bracket::Slater { n, h } => {
                // s = 1 − |z| / |d| computed without cancellation near the poles.
                let s = rho2 / (len * (len + d.z.abs()));
                let t = s * h;
                // Upper ring k precedes d iff 1 − cos θ_k = (2k² + 1) / H ≤ s (k ≥ 1).
                let k = if t < 3.0 {
                    0
                } else {
                    floor_i64(((t - 1.0) * 0.5).sqrt()).min(n as i64)
                };
                if d.z >= 0.0 {
                    k
                } else {
                    // Lower ring k is global ring 2n + 1 − k; d lies between lower rings k + 1
                    // (smaller θ) and k.
                    2 * n as i64 - k
                }
            }
            Bracket::LatLong { rows } => {
                let theta = rho2.sqrt().atan2(d.z);
                floor_i64(theta * rows as f64 / PI - 0.5).clamp(-1, rows as i64 - 1)
            }
        }
    }

    /// Index of the point of `points` (this set's points) nearest to `d`: exact, see the module
    /// proof. `d` need not be normalised; the zero vector returns some valid index.
    #[inline]
    pub fn nearest(&self, points: &[Vec3], d: Vec3) -> usize {
        self.nearest_counted(points, d).0
    }

    /// [`Self::nearest`] and the number of rings it scanned.
    #[inline]
    fn nearest_counted(&self, points: &[Vec3], d: Vec3) -> (usize, usize) {
        let dd = d.as_dvec3();
        let rho = (dd.x * dd.x + dd.y * dd.y).sqrt();
        let margin = 1e-6 * (rho * rho + dd.z * dd.z).sqrt();
        // Azimuth in turns, in [−½, ½] up to the approximation (step 1 of the proof).
        let turns = atan2_approx(dd.y, dd.x) * (1.0 / TAU);
        let mut best = (0usize, f64::NEG_INFINITY);
        let mut scanned = 0usize;
        let mut scan = |ring: &Ring, best: &mut (usize, f64)| {
            scanned += 1;
            let m = ring.count as i64;
            // u ∈ [−m/2 − 1, m/2] since phase ∈ [0, 1): one wrap each way suffices.
            let mut j0 = floor_i64(turns * m as f64 - ring.phase);
            if j0 < 0 {
                j0 += m;
            }
            if j0 >= m {
                j0 -= m;
            }
            let j1 = if j0 + 1 == m { 0 } else { j0 + 1 };
            for j in [j0 as u32, j1 as u32] {
                let i = (ring.first + j) as usize;
                let dot = dd.dot(points[i].as_dvec3());
                if dot > best.1 {
                    *best = (i, dot);
                }
            }
        };
        // Step 2: no point of `ring` beats `best` when its bound does not exceed it.
        let may_beat = |ring: &Ring, best: &(usize, f64)| {
            dd.z * ring.z + rho * ring.sin_theta + margin > best.1
        };
        let last = self.rings.len() - 1;
        let a = self.bracket(dd);
        let lo = a.max(0) as usize;
        let hi = ((a + 1).max(0) as usize).min(last);
        for ring in &self.rings[lo..=hi] {
            scan(ring, &mut best);
        }
        for ring in self.rings[..lo].iter().rev() {
            if !may_beat(ring, &best) {
                break;
            }
            scan(ring, &mut best);
        }
        for ring in &self.rings[hi + 1..] {
            if !may_beat(ring, &best) {
                break;
            }
            scan(ring, &mut best);
        }
        (best.0, scanned)
    }

    /// Checks the premise of the constant-time bound (step 4) with slack `eps` radians.
    pub fn check_gap_condition(&self, eps: f64) -> Result<(), String> {
        let theta: Vec<f64> = self.rings.iter().map(Ring::theta).collect();
        for (r, ring) in self.rings.iter().enumerate() {
            let need = ring.half_spacing() + 2.0 * eps;
            if r + 2 < theta.len() && theta[r + 2] - theta[r] < need {
                return Err(format!(
                    "ring {r}: θ[r+2] − θ[r] = {} < h + 2ε = {need}",
                    theta[r + 2] - theta[r]
                ));
            }
            if r >= 2 && theta[r] - theta[r - 2] < need {
                return Err(format!(
                    "ring {r}: θ[r] − θ[r−2] = {} < h + 2ε = {need}",
                    theta[r] - theta[r - 2]
                ));
            }
        }
        Ok(())
    }

    /// A triangulation of the sphere by this set's points: consecutive rings are zipped together
    /// in azimuth order (for Slater rings this gives exactly the lattice triangles of the
    /// subdivision), and a first or last ring of more than one point is closed by a fan.
    /// Orientation is left to [`super::mesh::SphereMesh`].
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let mut tris = Vec::new();
        for pair in self.rings.windows(2) {
            zip_rings(&pair[0], &pair[1], &mut tris);
        }
        for ring in [self.rings[0], self.rings[self.rings.len() - 1]] {
            for j in 1..ring.count.saturating_sub(1) {
                tris.push([ring.first, ring.first + j, ring.first + j + 1]);
            }
        }
        tris
    }
}

/// Triangulates the band between rings `a` and `b` by merging their azimuths in order.
fn zip_rings(a: &Ring, b: &Ring, tris: &mut Vec<[u32; 3]>) {
    // Unwrapped azimuths in turns.
    let alpha = |i: i64| (i as f64 + a.phase) / a.count as f64;
    let beta = |j: i64| (j as f64 + b.phase) / b.count as f64;
    let ia = |i: i64| a.first + i.rem_euclid(a.count as i64) as u32;
    let ib = |j: i64| b.first + j.rem_euclid(b.count as i64) as u32;
    let mut j = 0i64;
    // The last point of `a` at or before b's point 0.
    let mut i = (beta(0) * a.count as f64 - a.phase).floor() as i64;
    let (mut steps_a, mut steps_b) = (0u32, 0u32);
    while steps_a < a.count || steps_b < b.count {
        let advance_a = steps_b == b.count || (steps_a < a.count && alpha(i + 1) <= beta(j + 1));
        if advance_a {
            if a.count > 1 {
                tris.push([ia(i), ia(i + 1), ib(j)]);
            }
            i += 1;
            steps_a += 1;
        } else {
            if b.count > 1 {
                tris.push([ia(i), ib(j), ib(j + 1)]);
            }
            j += 1;
            steps_b += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slater_counts_follow_the_lattice() {
        // 2(2n² + 2n + 1): 290, 1090, 4226, 16642 for n = 8, 16, 32, 64.
        for (n, count) in [(8, 290), (16, 1090), (32, 4226), (64, 16642)] {
            let set = RingSet::slater(n);
            assert_eq!(set.len(), count);
            assert_eq!(set.points().len(), count);
        }
    }

    #[test]
    fn slater_rings_are_equal_area_and_above_the_equator() {
        for n in [1u32, 2, 8, 64] {
            let set = RingSet::slater(n);
            let h = slater_hemisphere_count(n as u64) as f64;
            let upper = &set.rings()[..=n as usize];
            // The last upper ring sits at cos θ = 2n / H > 0 (band middle, see `slater`).
            let last = upper[n as usize];
            assert!((last.z - 2.0 * n as f64 / h).abs() < 1e-12 && last.z > 0.0);
            // Band of ring k (k ≥ 1) spans 1 − cos θ ∈ [N_{k−1}, N_k] / H, holding 4k points of
            // solid angle 2π / H each; the ring sits at its middle.
            for (k, ring) in upper.iter().enumerate().skip(1) {
                let nk = slater_hemisphere_count(k as u64) as f64;
                let nk1 = slater_hemisphere_count(k as u64 - 1) as f64;
                assert!(((1.0 - ring.z) - 0.5 * (nk + nk1) / h).abs() < 1e-12);
                assert_eq!(ring.count as f64, nk - nk1);
            }
            for p in set.points() {
                assert!((p.length() - 1.0).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn gap_condition_holds_for_every_set_used() {
        for n in 1..=256 {
            RingSet::slater(n)
                .check_gap_condition(1e-5)
                .unwrap_or_else(|e| panic!("slater n = {n}: {e}"));
        }
        for rows in 2..=256 {
            RingSet::lat_long(rows, rows + 1)
                .check_gap_condition(1e-5)
                .unwrap_or_else(|e| panic!("lat-long {rows} rows: {e}"));
        }
    }

    #[test]
    fn gap_condition_can_fail() {
        // A lat-long grid with very few columns violates the premise: 10 rows, 2 columns gives
        // h = sin θ · π/2 ≈ 1.5 near the equator against 2π/10 for two row gaps.
        assert!(RingSet::lat_long(10, 2).check_gap_condition(1e-5).is_err());
    }

    #[test]
    fn bracket_is_consistent_with_ring_angles() {
        for set in [
            RingSet::slater(8),
            RingSet::slater(3),
            RingSet::lat_long(33, 34),
        ] {
            let theta: Vec<f64> = set.rings().iter().map(Ring::theta).collect();
            for i in 0..20_000 {
                let t = PI * (i as f64 + 0.5) / 20_000.0;
                let d = DVec3::new(t.sin() * 0.3, t.sin() * 0.954, t.cos());
                let a = set.bracket(d);
                let th = d.x.hypot(d.y).atan2(d.z);
                if a >= 0 {
                    assert!(theta[a as usize] <= th + 1e-12, "θ {th}, ring {a}");
                }
                if a + 1 < theta.len() as i64 {
                    assert!(
                        th < theta[(a + 1) as usize] + 1e-12,
                        "θ {th}, ring {}",
                        a + 1
                    );
                }
            }
        }
    }

    #[test]
    fn nearest_visits_at_most_four_rings() {
        // Step 4 of the module proof: two bracket rings plus at most one on each side.
        for set in [
            RingSet::slater(8),
            RingSet::slater(64),
            RingSet::lat_long(33, 34),
        ] {
            let points = set.points();
            for i in 0..100_000 {
                let d = crate::sampling::rays::seeded_sphere_direction(i, 4);
                let (_, v) = set.nearest_counted(&points, d);
                assert!(v <= 4, "{v} rings for {d}");
            }
        }
    }
}
