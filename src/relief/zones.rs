//! Safety zones (Kolb and Rezk-Salama, VMV 2005, §3.2): the dilation and erosion of the
//! displacement map over the ∞-norm neighbourhoods of radius δ, up to four of them at once
//! (§3.4, one per texture channel).
//!
//! M_dil(S) = max{M(S′) : |s − s′| < δ ∧ |t − t′| < δ}, M_ero the min. Above M_dil(S), within
//! the box around S, no part of the surface lies (the zone R_dil(S)); below M_ero(S) all of it
//! is solid (R_ero(S)).
//!
//! δ: the paper calls δ "the size of the region in s and t direction", lists its four "filter
//! box-sizes" as 3.125, 6.25, 12.5 and 25% of the map (§5) and passes those sizes as `delta` to
//! its Cg code's box-wall test `delta/maxNorm` (§4), so its δ is the box size itself: the
//! neighbourhood is `2δ` wide. [`DeltaRule::Paper`] (the default) does that;
//! [`DeltaRule::Half`] reads the sizes as full widths (δ half of them), which this crate did
//! before: smaller zones, shorter skips, the same safety.
//!
//! Deviation from the paper: it filters the texels; the surface between texels is bilinear, so
//! a box around a point can reach texels one beyond those its own extent covers. Each zone
//! value here is the max (min) over texels within `⌈δ·N⌉ + 1` of the point's cell, which bounds
//! the bilinear surface over the whole box (`zones_bound_the_bilinear_surface`), and the zone
//! maps are read with nearest sampling at the point's cell, widened by 4 f32 ulps of 1 for the
//! rounding of the bilinear filter.

use super::height::HeightMap;
use glam::Vec2;

/// Margin on the zone values: f32 bilinear interpolation of values in [0, 1] can pass the
/// largest of its four texels by an ulp or two.
const ROUNDING: f32 = 4.0 * f32::EPSILON;

/// The paper's four box sizes as fractions of the map (§5).
pub const PAPER_BOXES: [f32; 4] = [0.03125, 0.0625, 0.125, 0.25];

/// How a box size becomes the zone's half-width δ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DeltaRule {
    /// δ = the box size: the paper's |s − s′| < δ with the size passed as δ (§3.2, §4).
    Paper,
    /// δ = half the box size (the sizes read as full widths). Deviation from the paper, kept
    /// to show what the zone size is worth.
    Half,
}

impl DeltaRule {
    /// Both rules, the paper's first.
    pub const ALL: [DeltaRule; 2] = [DeltaRule::Paper, DeltaRule::Half];

    /// The name in tables.
    pub fn name(self) -> &'static str {
        match self {
            DeltaRule::Paper => "paper",
            DeltaRule::Half => "half",
        }
    }

    /// δ for a box of `size` (fraction of the map).
    pub fn delta(self, size: f32) -> f32 {
        match self {
            DeltaRule::Paper => size,
            DeltaRule::Half => 0.5 * size,
        }
    }
}

/// Dilation and erosion maps for up to four half-widths δ.
#[derive(Clone, Debug)]
pub struct SafetyZones {
    /// Half-widths δ in texture units, one per channel.
    pub deltas: Vec<f32>,
    /// How `deltas` came from the box sizes.
    pub rule: DeltaRule,
    /// Per texel, one value per channel: max over the channel's window.
    pub dilation: Vec<[f32; 4]>,
    /// Per texel, one value per channel: min over the channel's window.
    pub erosion: Vec<[f32; 4]>,
    width: usize,
    height: usize,
}

impl SafetyZones {
    /// The zones of `map` for the box sizes `boxes` (fractions of the map; at most four, each
    /// in (0, 1]) with the paper's δ ([`DeltaRule::Paper`]).
    ///
    /// # Panics
    /// With no box, more than four, or a size outside (0, 1].
    pub fn new(map: &HeightMap, boxes: &[f32]) -> SafetyZones {
        SafetyZones::with_rule(map, boxes, DeltaRule::Paper)
    }

    /// The zones of `map` for the box sizes `boxes`, δ by `rule`.
    ///
    /// # Panics
    /// With no box, more than four, or a size outside (0, 1].
    pub fn with_rule(map: &HeightMap, boxes: &[f32], rule: DeltaRule) -> SafetyZones {
        assert!(
            (1..=4).contains(&boxes.len()),
            "one to four box sizes (texture channels), got {}",
            boxes.len()
        );
        if let Some(b) = boxes.iter().find(|b| !(**b > 0.0 && **b <= 1.0)) {
            panic!("box sizes must lie in (0, 1], got {b}");
        }
        let (w, h) = (map.width, map.height);
        let mut dilation = vec![[0.0f32; 4]; w * h];
        let mut erosion = vec![[1.0f32; 4]; w * h];
        let deltas: Vec<f32> = boxes.iter().map(|&b| rule.delta(b)).collect();
        for (c, &delta) in deltas.iter().enumerate() {
            let rx = (delta * w as f32).ceil() as usize + 1;
            let ry = (delta * h as f32).ceil() as usize + 1;
            let hi = separable(&map.data, w, h, rx, ry, f32::max);
            let lo = separable(&map.data, w, h, rx, ry, f32::min);
            for k in 0..w * h {
                dilation[k][c] = hi[k] + ROUNDING;
                erosion[k][c] = lo[k] - ROUNDING;
            }
        }
        // Unused channels repeat the last one.
        for k in 0..w * h {
            for c in deltas.len()..4 {
                dilation[k][c] = dilation[k][deltas.len() - 1];
                erosion[k][c] = erosion[k][deltas.len() - 1];
            }
        }
        SafetyZones {
            deltas,
            rule,
            dilation,
            erosion,
            width: w,
            height: h,
        }
    }

    /// The zone values (dilation, erosion) at the cell holding `s` (nearest sampling).
    #[inline]
    pub fn at(&self, s: Vec2) -> (&[f32; 4], &[f32; 4]) {
        let i = ((s.x * self.width as f32).floor() as isize).clamp(0, self.width as isize - 1);
        let j = ((s.y * self.height as f32).floor() as isize).clamp(0, self.height as isize - 1);
        let k = j as usize * self.width + i as usize;
        (&self.dilation[k], &self.erosion[k])
    }

    /// The maps' width and height in texels (those of the displacement map they were made from).
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// Bytes of the two four-channel maps (f32 here; the paper's are 8-bit RGBA textures).
    pub fn bytes(&self) -> usize {
        (self.dilation.len() + self.erosion.len()) * std::mem::size_of::<[f32; 4]>()
    }
}

/// The `(2rx + 1) × (2ry + 1)` window reduction `op` of a row-major map, clamped at the borders.
fn separable(
    data: &[f32],
    w: usize,
    h: usize,
    rx: usize,
    ry: usize,
    op: fn(f32, f32) -> f32,
) -> Vec<f32> {
    let mut rows = vec![0.0f32; w * h];
    for j in 0..h {
        let row = &data[j * w..(j + 1) * w];
        for i in 0..w {
            let (a, b) = (i.saturating_sub(rx), (i + rx).min(w - 1));
            rows[j * w + i] = row[a..=b].iter().copied().reduce(op).unwrap();
        }
    }
    let mut out = vec![0.0f32; w * h];
    for i in 0..w {
        for j in 0..h {
            let (a, b) = (j.saturating_sub(ry), (j + ry).min(h - 1));
            out[j * w + i] = (a..=b).map(|jj| rows[jj * w + i]).reduce(op).unwrap();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relief::height::Dataset;

    /// For seeded points p and points q with |q − p|∞ < δ, the bilinear M(q) lies within the
    /// zone values read at p, under both δ rules.
    #[test]
    fn zones_bound_the_bilinear_surface() {
        for (d, rule) in Dataset::ALL
            .into_iter()
            .flat_map(|d| DeltaRule::ALL.map(|r| (d, r)))
        {
            let map = d.map(64);
            let zones = SafetyZones::with_rule(&map, &PAPER_BOXES, rule);
            assert_eq!(zones.deltas[3], rule.delta(0.25));
            let mut rng = crate::relief::height::Lcg(7);
            let mut rnd = || rng.next_f32();
            for _ in 0..20_000 {
                let p = Vec2::new(rnd(), rnd());
                let (dil, ero) = zones.at(p);
                for (c, &delta) in zones.deltas.iter().enumerate() {
                    let q = p + (Vec2::new(rnd(), rnd()) * 2.0 - Vec2::ONE) * delta * 0.999;
                    let q = q.clamp(Vec2::ZERO, Vec2::ONE);
                    let m = map.sample(q);
                    assert!(
                        m <= dil[c] && m >= ero[c],
                        "{d:?} {rule:?} channel {c}: {m} at {q} from {p}: dil {} ero {}",
                        dil[c],
                        ero[c]
                    );
                }
            }
        }
    }

    /// The paper's δ is twice the half rule's: its zones hold the half rule's (higher
    /// dilation, lower erosion everywhere) and are strictly larger somewhere on every map.
    #[test]
    fn paper_delta_zones_contain_the_half_rule_zones() {
        for d in Dataset::ALL {
            let map = d.map(64);
            let paper = SafetyZones::new(&map, &PAPER_BOXES);
            let half = SafetyZones::with_rule(&map, &PAPER_BOXES, DeltaRule::Half);
            assert_eq!(paper.deltas, PAPER_BOXES.to_vec());
            assert_eq!(half.deltas, PAPER_BOXES.map(|b| b / 2.0).to_vec());
            let mut wider = false;
            for k in 0..map.data.len() {
                for c in 0..4 {
                    assert!(paper.dilation[k][c] >= half.dilation[k][c], "{d:?}");
                    assert!(paper.erosion[k][c] <= half.erosion[k][c], "{d:?}");
                    wider |= paper.dilation[k][c] > half.dilation[k][c];
                }
            }
            assert!(wider, "{d:?}");
        }
    }

    #[test]
    fn window_reduction_matches_brute_force() {
        let map = Dataset::Relief.map(20);
        let out = separable(&map.data, 20, 20, 3, 2, f32::max);
        for j in 0..20isize {
            for i in 0..20isize {
                let mut m = 0.0f32;
                for jj in (j - 2).max(0)..=(j + 2).min(19) {
                    for ii in (i - 3).max(0)..=(i + 3).min(19) {
                        m = m.max(map.texel(ii, jj));
                    }
                }
                assert_eq!(out[(j * 20 + i) as usize], m);
            }
        }
    }
}
