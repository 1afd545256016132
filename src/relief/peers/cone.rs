//! Cone step mapping: J. Dummer, "Cone Step Mapping: An Iterative Ray-Heightfield Intersection
//! Algorithm", 2006; and relaxed cone stepping: F. Policarpo, M. M. Oliveira, "Relaxed Cone
//! Stepping for Relief Mapping", GPU Gems 3, ch. 18, 2007.
//!
//! Each texel stores a cone ratio `c` (horizontal over vertical extent, prism units). From a
//! ray point `P = (p, z)` above the surface the ray advances to where it leaves the cone of
//! apex `(p, M(p))` and ratio `c` of the texel under `p`: with `h = z − M(p)`, `ρ = |r̂_st|`,
//! the step is `c·h / (ρ − c·r̂_z)` (no end where `ρ ≤ c·r̂_z`: the rest of the ray stays in
//! the cone, a miss). [`Cone`](super::Peer::Cone) takes `steps` such steps; a point at or below
//! the surface (`d ≤ 0`) ends the walk there.
//!
//! **Conservative** ratios ([`ConeMaps::conservative`]) are valid for every apex in the
//! texel's footprint: `c ≤ |q − p| / (M(q) − M(p))` for all `p` in the footprint and all `q`
//! with `M(q) > M(p)`, so the cone above any surface point of the footprint holds no solid and
//! a step never passes the first hit. They are bounded from below per footprint `F`: within
//! the box of cells around `F` by `1 / L`, `L` the largest gradient of the bilinear patches
//! there (the gradient of a patch is largest at a corner), and beyond it by
//! `dist(F, G) / (max_G M − min_F M)` over the cells and max-mip nodes `G` (a depth-first
//! search of the max quadtree that prunes nodes no higher than `min_F M` or too far to lower
//! the bound), rounded down to f32 with a relative margin of 10⁻⁶, and capped at [`CONE_CAP`].
//!
//! **Relaxed** ratios ([`ConeMaps::relaxed`], Policarpo and Oliveira): the widest cone such that
//! a viewing ray from the top of the prism down to the texel's surface point, within the cone,
//! enters the solid at most once (once in, it stays in up to the apex). A relaxed step may
//! land below the surface; it then crossed it exactly once, and
//! [`RelaxedCone`](super::Peer::RelaxedCone) bisects the last step `bisections` times, keeping
//! the sign change, and answers its lower end's successor below the surface: within
//! `step / 2^bisections` after a crossing. As in the paper the property is sampled, not
//! guaranteed: the height profile under [`RELAXED_AZIMUTHS`] azimuths from the texel centre,
//! every half texel up to [`RELAXED_RINGS`] texels, gives in one pass per azimuth the nearest
//! reach `D` whose ray from the top enters twice (the ratio is `D / (1 − h)`); a ratio is
//! never below the conservative one (a conservative cone holds no solid, so it is relaxed
//! too).
//!
//! Fetches: a cone step reads two texels, the bilinear height `M(p)` and the cone ratio of the
//! nearest texel; a bisection step reads the height.
//!
//! Deviation from the papers: their surface is the nearest-texel (box) reconstruction, whose
//! height and cone ratio one RGBA texel read gives; here the surface is bilinear, so the apex
//! is the bilinear height under the ray point (its own read), and conservative ratios hold
//! for every apex in the footprint, not only the texel's top; ratios are f32, not 8-bit
//! square roots; relaxed stepping bisects only when a step lands below the surface (the
//! paper bisects the last step always), and a walk that never lands below answers its last
//! point, as cone step mapping does.

use super::maxmip::MaxMip;
use crate::relief::cast::{hit, miss, Cast};
use crate::relief::height::HeightMap;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// The widest cone ratio stored: a step of `CONE_CAP·h` sideways already crosses the prism for
/// any clearance `h ≥ 10⁻⁴`.
pub const CONE_CAP: f32 = 1.0e4;

/// Radius, in texels, searched for the relaxed ratio; beyond it the ratio is capped at the
/// radius over the height left above the apex, as if a violation lay there.
pub const RELAXED_RINGS: usize = 24;

/// Azimuths of the rays searched for the relaxed ratio.
pub const RELAXED_AZIMUTHS: usize = 128;

/// Per-texel cone ratios of one map (row-major, as the map).
#[derive(Clone, Debug, PartialEq)]
pub struct ConeMaps {
    pub width: usize,
    pub height: usize,
    /// Conservative ratios (Dummer): the cone above any surface point of the footprint is empty.
    pub conservative: Vec<f32>,
    /// Relaxed ratios (Policarpo and Oliveira), sampled.
    pub relaxed: Vec<f32>,
}

impl ConeMaps {
    /// Bytes of one ratio map.
    pub fn bytes_each(&self) -> usize {
        self.conservative.len() * 4
    }
}

/// The conservative ratios of every texel footprint (see the module doc).
pub fn conservative_ratios(map: &HeightMap, mip: &MaxMip) -> Vec<f32> {
    (0..map.width * map.height)
        .into_par_iter()
        .map(|k| conservative_ratio(map, mip, (k % map.width) as isize, (k / map.width) as isize))
        .collect()
}

fn conservative_ratio(map: &HeightMap, mip: &MaxMip, ti: isize, tj: isize) -> f32 {
    let (w, h) = (map.width as f64, map.height as f64);
    let (wi, hi) = (map.width as isize, map.height as isize);
    // Footprint F in grid coordinates and the lowest height on it (the cells it overlaps).
    let f = [
        ti as f64 - 0.5,
        ti as f64 + 0.5,
        tj as f64 - 0.5,
        tj as f64 + 0.5,
    ];
    let mut min_f = f32::INFINITY;
    for j in tj - 1..=tj + 1 {
        for i in ti - 1..=ti + 1 {
            min_f = min_f.min(map.texel(i, j));
        }
    }
    let min_f = min_f as f64;
    // Near box: cells ti−2 ..= ti+1 (u ∈ [ti − 2, ti + 2]), clamped to the map's cells.
    let near =
        |i: isize, j: isize| (ti - 2..=ti + 1).contains(&i) && (tj - 2..=tj + 1).contains(&j);
    let mut lip = 0.0f64;
    for j in (tj - 2).max(-1)..=(tj + 1).min(hi - 1) {
        for i in (ti - 2).max(-1)..=(ti + 1).min(wi - 1) {
            let c = super::grid::gather(map, i, j).map(|v| v as f64);
            let (p, q, kk) = (c[1] - c[0], c[2] - c[0], c[0] - c[1] - c[2] + c[3]);
            for (gx, gy) in [(p, q), (p + kk, q), (p, q + kk), (p + kk, q + kk)] {
                lip = lip.max((gx * w).hypot(gy * h));
            }
        }
    }
    let mut best = if lip > 0.0 {
        (1.0 / lip).min(CONE_CAP as f64)
    } else {
        CONE_CAP as f64
    };
    // Far nodes: depth-first over the max quadtree (shifted cells c = i + 1).
    let mut stack = vec![(mip.top(), 0usize, 0usize)];
    while let Some((level, ni, nj)) = stack.pop() {
        let top = mip.at(level, ni, nj) as f64;
        if top <= min_f {
            continue;
        }
        let s = 1isize << level;
        let (c0i, c0j) = (ni as isize * s - 1, nj as isize * s - 1);
        let (c1i, c1j) = (c0i + s - 1, c0j + s - 1);
        if c0i >= ti - 2 && c1i <= ti + 1 && c0j >= tj - 2 && c1j <= tj + 1 {
            continue; // inside the near box
        }
        let gap = |lo: f64, hi: f64, flo: f64, fhi: f64| (lo - fhi).max(flo - hi).max(0.0);
        let dx = gap(c0i as f64, (c1i + 1) as f64, f[0], f[1]) / w;
        let dy = gap(c0j as f64, (c1j + 1) as f64, f[2], f[3]) / h;
        let bound = dx.hypot(dy) / (top - min_f);
        if bound >= best {
            continue;
        }
        if level == 0 {
            if !near(c0i, c0j) {
                best = bound;
            }
            continue;
        }
        for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            stack.push((level - 1, 2 * ni + a, 2 * nj + b));
        }
    }
    (best * (1.0 - 1e-6)) as f32
}

/// The relaxed ratios (see the module doc), never below `conservative`.
pub fn relaxed_ratios(map: &HeightMap, conservative: &[f32]) -> Vec<f32> {
    let global_max = map.data.iter().cloned().fold(0.0f32, f32::max);
    (0..map.width * map.height)
        .into_par_iter()
        .map(|k| {
            let (ti, tj) = ((k % map.width) as isize, (k / map.width) as isize);
            relaxed_ratio(map, ti, tj, global_max).max(conservative[k])
        })
        .collect()
}

fn relaxed_ratio(map: &HeightMap, ti: isize, tj: isize, global_max: f32) -> f32 {
    let (w, h) = (map.width as f32, map.height as f32);
    let a = Vec2::new((ti as f32 + 0.5) / w, (tj as f32 + 0.5) / h);
    let ha = map.texel(ti, tj);
    if ha >= global_max {
        return CONE_CAP; // nothing is higher: no ray can enter before the apex
    }
    let above = 1.0 - ha;
    let step = 0.5 * (1.0 / w).min(1.0 / h);
    let samples = 2 * RELAXED_RINGS;
    let mut best = CONE_CAP;
    for az in 0..RELAXED_AZIMUTHS {
        let phi = std::f32::consts::TAU * az as f32 / RELAXED_AZIMUTHS as f32;
        let dir = Vec2::new(phi.cos(), phi.sin());
        // The ray of horizontal reach D from (a + D·dir, 1) down to the apex has slope
        // s = (1 − h_a)/D; at sample x it is inside the solid iff g(x) = (M − h_a)/x ≥ s. It
        // enters twice iff some sample x_b < D is inside and an earlier one x_a < x_b outside:
        // g(x_a) < s ≤ g(x_b), i.e. D ∈ [above/g(x_b), above/min g(x_a)) and D > x_b.
        let mut gmin = f32::INFINITY;
        for k in 1..=samples {
            let x = k as f32 * step;
            if x / above >= best {
                break;
            }
            let p = a + x * dir;
            if p.x < 0.0 || p.y < 0.0 || p.x > 1.0 || p.y > 1.0 {
                break;
            }
            let g = (map.sample(p) - ha) / x;
            if g > 0.0 && g > gmin {
                let d = (above / g).max(x);
                if gmin <= 0.0 || d < above / gmin {
                    best = best.min(d / above);
                }
            }
            gmin = gmin.min(g);
        }
    }
    best.min(samples as f32 * step / above)
}

/// How a cone walk ended, for tests of the relaxed bisection bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeTrace {
    pub cast: Cast,
    /// The last step `[λa, λb]` that landed at or below the surface, before bisection.
    pub bracket: Option<(f32, f32)>,
}

/// Cone stepping along `E → X`: `steps` steps with the ratios `cones` (row-major per texel);
/// with `bisections` (relaxed cones) a step landing at or below the surface is bisected.
pub fn cast(
    map: &HeightMap,
    cones: &[f32],
    e: Vec3,
    x: Vec3,
    steps: u32,
    bisections: Option<u32>,
) -> ConeTrace {
    let done = |cast| ConeTrace {
        cast,
        bracket: None,
    };
    let len = (x - e).length();
    if !(len > 0.0 && len.is_finite()) {
        return done(miss(0));
    }
    let r = (x - e) / len;
    let rho = (r.x * r.x + r.y * r.y).sqrt();
    let (mut lam, mut prev) = (0.0f32, 0.0f32);
    let mut fetches = 0;
    for _ in 0..steps {
        let p = e + lam * r;
        fetches += 2;
        let s = Vec2::new(p.x, p.y);
        let d = p.z - map.sample(s);
        let (i, j) = map.cell_of(s);
        let i = i.clamp(0, map.width as isize - 1) as usize;
        let j = j.clamp(0, map.height as isize - 1) as usize;
        let c = cones[j * map.width + i];
        if d <= 0.0 {
            if lam == 0.0 {
                return done(if d < 0.0 {
                    miss(fetches)
                } else {
                    hit(0.0, fetches)
                });
            }
            let Some(b) = bisections else {
                return done(hit(lam, fetches));
            };
            let (mut la, mut lb) = (prev, lam);
            for _ in 0..b {
                let mid = 0.5 * (la + lb);
                let pm = e + mid * r;
                fetches += 1;
                if pm.z - map.sample(Vec2::new(pm.x, pm.y)) <= 0.0 {
                    lb = mid;
                } else {
                    la = mid;
                }
            }
            return ConeTrace {
                cast: hit(lb, fetches),
                bracket: Some((prev, lam)),
            };
        }
        if lam >= len {
            return done(miss(fetches));
        }
        let denom = rho - c * r.z;
        if denom <= 0.0 {
            return done(miss(fetches));
        }
        prev = lam;
        lam = (lam + c * d / denom).min(len);
    }
    done(if lam >= len {
        miss(fetches)
    } else {
        hit(lam, fetches)
    })
}
