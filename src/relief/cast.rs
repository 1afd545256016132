//! Ray–displacement-surface intersection: the 2005 paper's linear search with bisection and
//! empty-space skipping (Kolb and Rezk-Salama, VMV 2005, §3.1–3.4), and an exact reference.
//!
//! Prism coordinates: `(s, t, z)`, the base square `[0, 1]²` and heights `z ∈ [0, 1]`; the
//! surface is `z = M(s, t)` and the solid lies below it. A ray enters the prism at `E` and
//! leaves it at `X`; `P(λ) = E + λ·r̂`, `λ ∈ [0, |X − E|]`, and `d(P) = p_z − M(p_s, p_t)`.

use super::height::HeightMap;
use super::zones::SafetyZones;
use glam::{Vec2, Vec3};

/// Settings of the intersection search (the paper's Tables 1–3 vary all three).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CastParams {
    /// Linear-search samples per unit length of the ray in prism coordinates.
    pub samples_per_unit: f32,
    /// Bisection steps after the linear search.
    pub bisections: u32,
    /// Forward and backward safety-zone skips before the linear search (0: none).
    pub skips: u32,
}

/// The answer of one ray: the hit parameter λ and the texture reads it took (one per height
/// sample, one per four-channel zone map read: a skip round reads the dilation going forward
/// and the dilation and the erosion going backward, three reads).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cast {
    pub hit: Option<f32>,
    pub fetches: u32,
}

/// A hit at `l` after `fetches` reads.
pub(crate) fn hit(l: f32, fetches: u32) -> Cast {
    Cast {
        hit: Some(l),
        fetches,
    }
}

/// A miss after `fetches` reads.
pub(crate) fn miss(fetches: u32) -> Cast {
    Cast { hit: None, fetches }
}

/// Zone-map reads per round of skips: the dilation forward, dilation and erosion backward.
pub const FETCHES_PER_SKIP_ROUND: u32 = 3;

#[inline]
fn d(map: &HeightMap, p: Vec3) -> f32 {
    p.z - map.sample(Vec2::new(p.x, p.y))
}

/// Whether `p` (the entry of a segment) lies strictly below the surface: the paper discards
/// such a pixel (§3.1 step 1, back faces and side walls entered below the surface).
pub fn culled(map: &HeightMap, p: Vec3) -> bool {
    d(map, p) < 0.0
}

/// The paper's search along `E → X` (§3.1): discard when `E` is strictly below the surface
/// (back faces), `skips` rounds of forward and backward empty-space skips (§3.3), linear search
/// within the remaining segment `[λ1, λ2]` (its end sample included), then `bisections`
/// interpolating bisection steps (§3.1) on the first interval with a sign change. With no
/// bisection the hit is the first sample on or below the surface.
///
/// The hit rule is `d ≤ 0` (on or below the surface), the same as [`exact`]'s, and the segment's
/// last sample is `X` itself, so a ray that ends on a surface at height 0 (the prism's floor
/// under a zero texel) is a hit. Deviation from the paper: its test is `d < 0`, under which such
/// a ray hits or misses by the rounding of its last sample's height.
///
/// The linear search samples the lattice `λ_k = k / samples_per_unit` from the last lattice
/// point at or before `λ1`: with and without skips the samples it takes are the same points, so
/// skipping can only drop samples in empty space. Deviation from the paper: its regular
/// sampling starts at `λ1` itself.
pub fn intersect(
    map: &HeightMap,
    zones: Option<&SafetyZones>,
    e: Vec3,
    x: Vec3,
    params: &CastParams,
) -> Cast {
    let len = (x - e).length();
    let mut fetches = 1;
    let de = d(map, e);
    if de < 0.0 || len.is_nan() || len <= 0.0 {
        return miss(fetches);
    }
    if de <= 0.0 {
        return hit(0.0, fetches);
    }
    let r = (x - e) / len;
    let at = |l: f32| if l >= len { x } else { e + l * r };
    let (l1, l2) = match zones {
        Some(z) => match skip(z, e, r, len, params.skips, &mut fetches) {
            Some(seg) => seg,
            None => return miss(fetches),
        },
        None => (0.0, len),
    };
    let (rate, step) = (params.samples_per_unit, 1.0 / params.samples_per_unit);
    // The last lattice point at or before λ1 (the product's rounding corrected).
    let mut k = (l1 * rate).floor() as u32;
    if k as f32 * step > l1 {
        k -= 1;
    }
    // The entry's sample is read once; a skip past the first lattice step starts at a new one.
    let (mut la, mut da) = if k > 0 {
        fetches += 1;
        let l = k as f32 * step;
        (l, d(map, at(l)))
    } else {
        (0.0, de)
    };
    if da <= 0.0 {
        // Every point before λ1 lies in a zone above the surface; only rounding lands here.
        return hit(la, fetches);
    }
    loop {
        k += 1;
        let lb = (k as f32 * step).min(l2);
        let db = d(map, at(lb));
        fetches += 1;
        if db <= 0.0 {
            let l = bisect(map, at, (la, da), (lb, db), params.bisections, &mut fetches);
            return hit(l, fetches);
        }
        if lb >= l2 {
            return miss(fetches);
        }
        (la, da) = (lb, db);
    }
}

/// `rounds` of forward and backward skips (§3.3) on the segment `[0, len]` of the ray from `e`
/// along the unit `r`: the remaining segment `[λ1, λ2]`, or `None` when the skips cross (no
/// intersection). Each round reads the zone maps [`FETCHES_PER_SKIP_ROUND`] times (counted in
/// `fetches`).
pub fn skip(
    z: &SafetyZones,
    e: Vec3,
    r: Vec3,
    len: f32,
    rounds: u32,
    fetches: &mut u32,
) -> Option<(f32, f32)> {
    // ‖(r_s, r_t)‖∞: the box bound in λ is δ over it.
    let norm = r.x.abs().max(r.y.abs());
    let (mut l1, mut l2) = (0.0f32, len);
    for _ in 0..rounds {
        *fetches += FETCHES_PER_SKIP_ROUND;
        l1 += forward_skip(z, e + l1 * r, r, norm);
        l2 -= backward_skip(z, e + l2 * r, r, norm);
        if l1 > l2 {
            return None;
        }
    }
    Some((l1, l2))
}

/// The paper's bisection: λ = λa + d_a/(d_a − d_b)·(λb − λa), keeping the sign change
/// (`d_a > 0 ≥ d_b`).
fn bisect(
    map: &HeightMap,
    at: impl Fn(f32) -> Vec3,
    (mut la, mut da): (f32, f32),
    (mut lb, mut db): (f32, f32),
    steps: u32,
    fetches: &mut u32,
) -> f32 {
    let mut l = lb;
    for _ in 0..steps {
        l = la + da / (da - db) * (lb - la);
        let dl = d(map, at(l));
        *fetches += 1;
        if dl > 0.0 {
            (la, da) = (l, dl);
        } else {
            (lb, db) = (l, dl);
        }
    }
    l
}

/// §3.3 forward skip from `p` (above the surface): the largest step that stays inside the
/// union of the channels' zones R_dil around `p` — down to M_dil (r_z < 0) or up to the
/// ceiling z = 1 (r_z > 0), and at most δ/‖r_st‖∞ sideways; 0 where `p` is in no zone.
fn forward_skip(z: &SafetyZones, p: Vec3, r: Vec3, norm: f32) -> f32 {
    let (dil, _) = z.at(Vec2::new(p.x, p.y));
    let mut best = 0.0f32;
    for (c, &delta) in z.deltas.iter().enumerate() {
        if p.z <= dil[c] {
            continue;
        }
        let vertical = if r.z < 0.0 {
            (dil[c] - p.z) / r.z
        } else if r.z > 0.0 {
            (1.0 - p.z) / r.z
        } else {
            f32::INFINITY
        };
        best = best.max(vertical.min(delta / norm));
    }
    best
}

/// §3.3 backward skip from `p` (the segment's end) along −r̂: above the surface within the
/// R_dil zones, or below it within the R_ero zones (the paper's two cases for X), bounded by
/// the zone's height, the prism's ceiling or floor, and δ/‖r_st‖∞ sideways.
fn backward_skip(z: &SafetyZones, p: Vec3, r: Vec3, norm: f32) -> f32 {
    let (dil, ero) = z.at(Vec2::new(p.x, p.y));
    let mut best = 0.0f32;
    for (c, &delta) in z.deltas.iter().enumerate() {
        // Going backward the height changes by −r_z per unit of λ.
        let vertical = if p.z > dil[c] {
            if r.z > 0.0 {
                (p.z - dil[c]) / r.z
            } else if r.z < 0.0 {
                (1.0 - p.z) / -r.z
            } else {
                f32::INFINITY
            }
        } else if p.z < ero[c] {
            if r.z < 0.0 {
                (ero[c] - p.z) / -r.z
            } else if r.z > 0.0 {
                p.z / r.z
            } else {
                f32::INFINITY
            }
        } else {
            continue;
        };
        best = best.max(vertical.min(delta / norm));
    }
    best
}

/// The exact first intersection of `E → X` with the bilinear surface (the reference): the ray
/// is walked cell by cell over the grid of texel centres, where `d(λ)` is a quadratic, solved
/// in f64, for the first point where `d ≤ 0` ([`intersect`]'s rule). `None` for a miss and,
/// as [`intersect`], where `E` lies strictly below the surface; where the walk finds no root
/// but `X` is on or below the surface in f32 (a ray ending on a zero floor, the root lost to
/// rounding), the hit is `X`, as the search's last sample finds it.
pub fn exact(map: &HeightMap, e: Vec3, x: Vec3) -> Option<f32> {
    let len32 = (x - e).length();
    let len = len32 as f64;
    if len.is_nan() || len <= 0.0 || d(map, e) < 0.0 {
        return None;
    }
    walk(map, e, x, len).or_else(|| (d(map, x) <= 0.0).then_some(len32))
}

/// The cell walk of [`exact`] over `[0, len]`.
fn walk(map: &HeightMap, e: Vec3, x: Vec3, len: f64) -> Option<f32> {
    let (w, h) = (map.width as f64, map.height as f64);
    // Grid coordinates u = s·N − ½: cell i spans [i, i + 1] and is bilinear there.
    let o = [e.x as f64 * w - 0.5, e.y as f64 * h - 0.5, e.z as f64];
    let r = (x - e).as_dvec3() / len;
    let dir = [r.x * w, r.y * h, r.z];
    let mut l = 0.0f64;
    while l < len {
        let (u, v) = (o[0] + l * dir[0], o[1] + l * dir[1]);
        // The cell the ray is in just after λ.
        let eps = 1e-9;
        let ci = (u + eps * dir[0].signum()).floor();
        let cj = (v + eps * dir[1].signum()).floor();
        let exit = |c: f64, o: f64, k: f64| {
            if k > 0.0 {
                (c + 1.0 - o) / k
            } else if k < 0.0 {
                (c - o) / k
            } else {
                f64::INFINITY
            }
        };
        let l_out = exit(ci, o[0], dir[0]).min(exit(cj, o[1], dir[1])).min(len);
        let (i, j) = (ci as isize, cj as isize);
        let c00 = map.texel(i, j) as f64;
        let c10 = map.texel(i + 1, j) as f64;
        let c01 = map.texel(i, j + 1) as f64;
        let c11 = map.texel(i + 1, j + 1) as f64;
        // fx = a + bλ, fy = c + dλ; M = c00 + p·fx + q·fy + k·fx·fy; height z = z0 + r_z λ.
        let (a, b) = (o[0] - ci, dir[0]);
        let (c, dd) = (o[1] - cj, dir[1]);
        let (p, q, k) = (c10 - c00, c01 - c00, c00 - c10 - c01 + c11);
        // d(λ) = z0 + r_z λ − M(λ) = A λ² + B λ + C.
        let qa = -k * b * dd;
        let qb = dir[2] - p * b - q * dd - k * (a * dd + b * c);
        let qc = o[2] - c00 - p * a - q * c - k * a * c;
        let f = |t: f64| (qa * t + qb) * t + qc;
        if let Some(t) = first_nonpositive(f, qa, qb, qc, l, l_out) {
            return Some(t as f32);
        }
        if l_out <= l {
            break;
        }
        l = l_out;
    }
    None
}

/// The smallest `t ∈ [lo, hi]` with `A t² + B t + C ≤ 0`, given `f` the same polynomial.
fn first_nonpositive(
    f: impl Fn(f64) -> f64,
    qa: f64,
    qb: f64,
    qc: f64,
    lo: f64,
    hi: f64,
) -> Option<f64> {
    if f(lo) <= 0.0 {
        return Some(lo);
    }
    let mut roots = [f64::NAN; 2];
    if qa.abs() < 1e-14 * (qb.abs() + qc.abs()).max(1e-300) {
        if qb != 0.0 {
            roots[0] = -qc / qb;
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            // Stable roots (no cancellation).
            let s = -0.5 * (qb + qb.signum() * disc.sqrt());
            roots = [s / qa, if s != 0.0 { qc / s } else { f64::NAN }];
        }
    }
    roots
        .into_iter()
        .filter(|t| t.is_finite() && *t >= lo && *t <= hi)
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))))
        .filter(|&t| f(t) <= 1e-12 || f((t + 1e-12).min(hi)) <= 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relief::height::Dataset;
    use crate::relief::zones::{SafetyZones, PAPER_BOXES};

    fn flat(h: f32) -> HeightMap {
        HeightMap::new(4, 4, vec![h; 16])
    }

    #[test]
    fn flat_map_hits_in_closed_form() {
        let map = flat(0.25);
        let zones = SafetyZones::new(&map, &PAPER_BOXES);
        let (e, x) = (Vec3::new(0.1, 0.2, 1.0), Vec3::new(0.9, 0.6, 0.0));
        let len = (x - e).length();
        // z = 1 − λ/len reaches 0.25 at λ = 0.75 len.
        let want = 0.75 * len;
        assert!((exact(&map, e, x).unwrap() - want).abs() < 1e-6);
        for skips in 0..3 {
            let p = CastParams {
                samples_per_unit: 10.0,
                bisections: 2,
                skips,
            };
            let c = intersect(&map, Some(&zones), e, x, &p);
            // On a plane the interpolating bisection is exact after one step.
            assert!((c.hit.unwrap() - want).abs() < 1e-5, "{skips}: {c:?}");
        }
    }

    #[test]
    fn ramp_matches_the_quadratic_solution() {
        // M(s, t) = s on texel centres (bilinear: exact between them).
        let n = 8;
        let map = HeightMap::from_fn(n, |s| s.x);
        // A horizontal ray at z = 0.5 in t: hits where s = 0.5.
        let (e, x) = (Vec3::new(0.1, 0.3, 0.5), Vec3::new(0.9, 0.3, 0.5));
        let got = exact(&map, e, x).unwrap();
        // The bilinear ramp follows the centres: M = s exactly between 1/16 and 15/16.
        assert!((got - 0.4).abs() < 1e-6, "{got}");
    }

    /// A round of skips reads the dilation going forward and the dilation and the erosion
    /// going backward: three fetches, counted.
    #[test]
    fn a_round_of_skips_reads_three_zone_maps() {
        let map = flat(0.25);
        let zones = SafetyZones::new(&map, &PAPER_BOXES);
        let (e, x) = (Vec3::new(0.1, 0.2, 1.0), Vec3::new(0.9, 0.6, 0.0));
        let len = (x - e).length();
        for rounds in 0..4 {
            let mut fetches = 0;
            assert!(skip(&zones, e, (x - e) / len, len, rounds, &mut fetches).is_some());
            assert_eq!(fetches, FETCHES_PER_SKIP_ROUND * rounds);
        }
    }

    /// A ray ending on a zero floor is a hit at its end, for the search (at any sample rate,
    /// with or without bisection) and the reference alike; a ray touching the surface only at
    /// its entry is a hit at 0.
    #[test]
    fn a_ray_ending_on_a_zero_floor_hits_it() {
        let map = flat(0.0);
        let zones = SafetyZones::new(&map, &PAPER_BOXES);
        let (e, x) = (Vec3::new(0.1, 0.2, 1.0), Vec3::new(0.7, 0.9, 0.0));
        let len = (x - e).length();
        assert_eq!(exact(&map, e, x), Some(len));
        for (rate, bisections, skips) in [(10.0, 0, 0), (75.0, 2, 0), (75.0, 2, 2), (7.3, 3, 1)] {
            let p = CastParams {
                samples_per_unit: rate,
                bisections,
                skips,
            };
            let c = intersect(&map, Some(&zones), e, x, &p);
            let hit = c.hit.expect("the floor");
            assert!(
                (hit - len).abs() <= 2.0 * f32::EPSILON * len,
                "{p:?}: {hit} vs {len}"
            );
        }
        let top = flat(1.0);
        let p = CastParams {
            samples_per_unit: 10.0,
            bisections: 2,
            skips: 0,
        };
        assert_eq!(intersect(&top, None, e, x, &p).hit, Some(0.0));
        assert_eq!(exact(&top, e, x), Some(0.0));
    }

    #[test]
    fn entry_below_the_surface_is_discarded() {
        let map = flat(0.5);
        let c = intersect(
            &map,
            None,
            Vec3::new(0.0, 0.5, 0.3),
            Vec3::new(1.0, 0.5, 0.3),
            &CastParams {
                samples_per_unit: 10.0,
                bisections: 0,
                skips: 0,
            },
        );
        assert_eq!(c.hit, None);
        assert_eq!(exact(&map, Vec3::new(0.0, 0.5, 0.3), Vec3::ONE), None);
    }

    /// Skipping only removes empty space: on every dataset, over rays of all slopes, the exact
    /// first hit lies inside the segment left by 1–3 rounds of skips (and a ray whose skips
    /// cross has no hit); at a fine sample rate the search finds the exact hit with and without
    /// skips, while reading fewer texels with them.
    #[test]
    fn skipping_keeps_the_exact_hit() {
        for dset in Dataset::ALL {
            let map = dset.map(64);
            let zones = SafetyZones::new(&map, &PAPER_BOXES);
            let mut rng = crate::relief::height::Lcg(11);
            let mut rnd = || rng.next_f32();
            let mut fetches = [0u64; 3];
            let mut agree = [0usize; 3];
            let n = 3000;
            for _ in 0..n {
                let e = Vec3::new(rnd(), rnd(), 1.0);
                let x = Vec3::new(rnd(), rnd(), rnd() * 0.3);
                let want = exact(&map, e, x);
                let len = (x - e).length();
                for rounds in 1..=3 {
                    let seg = skip(&zones, e, (x - e) / len, len, rounds, &mut 0);
                    match (want, seg) {
                        (Some(h), Some((a, b))) => {
                            assert!(a <= h + 1e-5 && h <= b + 1e-5, "{dset:?}: {h} in {a}..{b}")
                        }
                        (Some(h), None) => panic!("{dset:?}: skips crossed over the hit {h}"),
                        (None, _) => {}
                    }
                }
                for skips in 0..3u32 {
                    let p = CastParams {
                        samples_per_unit: 2000.0,
                        bisections: 8,
                        skips,
                    };
                    let c = intersect(&map, Some(&zones), e, x, &p);
                    fetches[skips as usize] += c.fetches as u64;
                    agree[skips as usize] += match (want, c.hit) {
                        (None, None) => 1,
                        (Some(a), Some(b)) => ((a - b).abs() < 1e-4) as usize,
                        _ => 0,
                    };
                }
            }
            // Grazing rays can dip below the surface for less than a sample step.
            for a in agree {
                assert!(a as f64 >= 0.995 * n as f64, "{dset:?}: {agree:?} of {n}");
            }
            assert!(
                fetches[1] < fetches[0] && fetches[2] <= fetches[1],
                "{fetches:?}"
            );
        }
    }
}
