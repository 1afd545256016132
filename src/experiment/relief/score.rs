//! What a relief frame is measured by: its pixels split by what the exact intersection says
//! about their ray (meets the surface, leaves without meeting it, culled at the entry), the
//! fetches of each population, and the error against the exact hits.

use crate::relief::cast::culled;
use crate::relief::view::{ReliefFrame, View};
use crate::relief::HeightMap;

/// A hit more than this many texel widths from the exact one along the ray counts as missed.
pub const OFF_TEXELS: f64 = 2.0;

/// What the exact reference says about one pixel's ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Population {
    /// The ray misses the prism (no fetches).
    Outside,
    /// The ray meets the surface first at λ.
    Surface(f32),
    /// The ray crosses the prism without meeting the surface.
    NoHit,
    /// The ray enters the prism below the surface: discarded at the entry (back faces, side
    /// walls entered below the surface), one fetch.
    Culled,
}

/// Every pixel's population for `view` on `map`, from the exact frame `exact`.
pub fn populations(map: &HeightMap, view: &View, exact: &ReliefFrame) -> Vec<Population> {
    (0..view.width * view.height)
        .map(|k| match view.segment(k) {
            None => Population::Outside,
            Some((e, _)) if culled(map, e) => Population::Culled,
            Some(_) => match exact.lambda[k as usize] {
                Some(l) => Population::Surface(l),
                None => Population::NoHit,
            },
        })
        .collect()
}

/// Pixel count and mean fetches of one population (NaN mean when empty).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    pub pixels: usize,
    pub mean_fetches: f64,
}

impl Tally {
    fn of(fetches: impl Iterator<Item = u32>) -> Tally {
        let (n, sum) = fetches.fold((0usize, 0u64), |(n, s), f| (n + 1, s + f as u64));
        Tally {
            pixels: n,
            mean_fetches: if n == 0 {
                f64::NAN
            } else {
                sum as f64 / n as f64
            },
        }
    }
}

/// A frame's fetches per population and its error against the exact intersection.
#[derive(Clone, Copy, Debug)]
pub struct Scores {
    /// Every pixel whose ray enters the prism.
    pub all: Tally,
    pub surface: Tally,
    pub no_hit: Tally,
    pub culled: Tally,
    /// RMS (0–255) of the shaded image against the exact one, over pixels hit by either.
    pub rms_vs_exact: f64,
    /// Pixels hit by one of the two only.
    pub hit_mismatches: usize,
    /// Share of the surface pixels the search misses or hits more than [`OFF_TEXELS`] texel
    /// widths from the exact hit.
    pub missed_share: f64,
    /// RMS of the hit's distance from the exact one along the ray, in texel widths, over the
    /// surface pixels the search hits.
    pub hit_rms_texels: f64,
}

/// The scores of `frame` against `exact` (same view), `pops` from [`populations`], on a map
/// `texels` wide.
pub fn score(
    frame: &ReliefFrame,
    exact: &ReliefFrame,
    pops: &[Population],
    texels: usize,
) -> Scores {
    let of = |want: fn(&Population) -> bool| {
        Tally::of(
            pops.iter()
                .zip(&frame.fetches)
                .filter(|(p, _)| want(p))
                .map(|(_, &f)| f),
        )
    };
    let (hit_mismatches, rms_vs_exact) = super::compare_frames(frame, exact);
    let (mut surface, mut missed, mut sq, mut found) = (0usize, 0usize, 0.0f64, 0usize);
    for (p, got) in pops.iter().zip(&frame.lambda) {
        if let Population::Surface(want) = *p {
            surface += 1;
            match got {
                Some(l) => {
                    let off = (*l as f64 - want as f64).abs() * texels as f64;
                    sq += off * off;
                    found += 1;
                    missed += (off > OFF_TEXELS) as usize;
                }
                None => missed += 1,
            }
        }
    }
    Scores {
        all: of(|p| !matches!(p, Population::Outside)),
        surface: of(|p| matches!(p, Population::Surface(_))),
        no_hit: of(|p| matches!(p, Population::NoHit)),
        culled: of(|p| matches!(p, Population::Culled)),
        rms_vs_exact,
        hit_mismatches,
        missed_share: if surface == 0 {
            f64::NAN
        } else {
            missed as f64 / surface as f64
        },
        hit_rms_texels: if found == 0 {
            f64::NAN
        } else {
            (sq / found as f64).sqrt()
        },
    }
}
