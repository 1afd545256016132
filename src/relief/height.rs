//! Displacement maps M : [0, 1]² → [0, 1] (Kolb and Rezk-Salama, VMV 2005, §2.1), sampled
//! bilinearly, and the procedural maps standing in for the paper's.

use glam::Vec2;

/// A displacement map of `width × height` texels, values in [0, 1], texel `(i, j)` centred at
/// `((i + ½)/width, (j + ½)/height)`; between centres it is bilinear, beyond the outer centres
/// it is clamped (constant), so M is continuous on the whole square.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightMap {
    pub width: usize,
    pub height: usize,
    /// Row-major (`j · width + i`).
    pub data: Vec<f32>,
}

impl HeightMap {
    /// A map from its texels.
    ///
    /// # Panics
    /// If the size does not match or a value is outside [0, 1] or not finite.
    pub fn new(width: usize, height: usize, data: Vec<f32>) -> HeightMap {
        assert!(width > 0 && height > 0 && data.len() == width * height);
        assert!(
            data.iter().all(|v| (0.0..=1.0).contains(v)),
            "displacement values must lie in [0, 1]"
        );
        HeightMap {
            width,
            height,
            data,
        }
    }

    /// A map of `n × n` texels from `f` evaluated at the texel centres (clamped to [0, 1]).
    pub fn from_fn(n: usize, f: impl Fn(Vec2) -> f32) -> HeightMap {
        let mut data = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                let s = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                data.push(f(s).clamp(0.0, 1.0));
            }
        }
        HeightMap::new(n, n, data)
    }

    /// The texel `(i, j)`, clamped to the map.
    #[inline]
    pub fn texel(&self, i: isize, j: isize) -> f32 {
        let i = i.clamp(0, self.width as isize - 1) as usize;
        let j = j.clamp(0, self.height as isize - 1) as usize;
        self.data[j * self.width + i]
    }

    /// The texel whose cell holds `s` (nearest sampling).
    #[inline]
    pub fn cell_of(&self, s: Vec2) -> (isize, isize) {
        (
            (s.x * self.width as f32).floor() as isize,
            (s.y * self.height as f32).floor() as isize,
        )
    }

    /// M(s): bilinear between texel centres.
    #[inline]
    pub fn sample(&self, s: Vec2) -> f32 {
        let x = s.x * self.width as f32 - 0.5;
        let y = s.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, j) = (x0 as isize, y0 as isize);
        let a = self.texel(i, j) * (1.0 - fx) + self.texel(i + 1, j) * fx;
        let b = self.texel(i, j + 1) * (1.0 - fx) + self.texel(i + 1, j + 1) * fx;
        a * (1.0 - fy) + b * fy
    }
}

/// The procedural displacement maps of the paper's tables.
///
/// Deviation from the paper: its "angel" map is a scanned relief we do not have; `Relief` is a
/// seeded sum of Gaussian bumps of several sizes with terraced steps, a map with the same mix
/// of smooth areas and high-frequency edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dataset {
    /// Smooth, low-frequency bumps (the paper's "simple" map).
    Simple,
    /// Bumps and terraces of mixed frequency (our stand-in for the paper's "angel").
    Relief,
    /// An 8 × 8 grid of cones 15 texels in radius at 256² on a zero floor (28.5% of the texels
    /// are 0): our "spikes", sharp-tipped but not high-frequency.
    Spikes,
    /// Thin needles: one isolated texel of height 1 in every 8 × 8 block at a seeded position
    /// on a zero floor, the bilinear surface a two-texel-wide pyramid there: the paper's
    /// thin-spike case (its Figure 12), where a linear search can step over a whole needle.
    Needles,
    /// Seeded white noise, one independent value in [0, 1) per texel: the highest frequency a
    /// map of its size holds.
    Noise,
}

impl Dataset {
    /// All datasets, in table order.
    pub const ALL: [Dataset; 5] = [
        Dataset::Simple,
        Dataset::Relief,
        Dataset::Spikes,
        Dataset::Needles,
        Dataset::Noise,
    ];

    /// The name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Dataset::Simple => "simple",
            Dataset::Relief => "relief",
            Dataset::Spikes => "spikes",
            Dataset::Needles => "needles",
            Dataset::Noise => "noise",
        }
    }

    /// The map at `n × n` texels (`n` ≥ 1).
    pub fn map(self, n: usize) -> HeightMap {
        use std::f32::consts::TAU;
        match self {
            Dataset::Simple => HeightMap::from_fn(n, |s| {
                0.5 + 0.25 * ((TAU * 2.0 * s.x).sin() * (TAU * 2.0 * s.y).sin())
            }),
            Dataset::Spikes => HeightMap::from_fn(n, |s| {
                // 8 × 8 cones of radius 0.06 and height 0.9.
                let c = (s * 8.0).fract() - Vec2::splat(0.5);
                (0.9 * (1.0 - c.length() / 0.48)).max(0.0)
            }),
            Dataset::Needles => {
                // One needle per 8 × 8 block, in the block's inner 6 × 6 so that no two touch.
                let mut rng = Lcg(0x2005_5e1e);
                let mut data = vec![0.0f32; n * n];
                for bj in (0..n).step_by(8) {
                    for bi in (0..n).step_by(8) {
                        let i = bi + 1 + (rng.next_f32() * 6.0) as usize;
                        let j = bj + 1 + (rng.next_f32() * 6.0) as usize;
                        if i < n && j < n {
                            data[j * n + i] = 1.0;
                        }
                    }
                }
                HeightMap::new(n, n, data)
            }
            Dataset::Noise => {
                let mut rng = Lcg(0x2005_0a15e);
                HeightMap::new(n, n, (0..n * n).map(|_| rng.next_f32()).collect())
            }
            Dataset::Relief => {
                let bumps = relief_bumps();
                HeightMap::from_fn(n, |s| {
                    let h: f32 = bumps
                        .iter()
                        .map(|&(c, r, a)| a * (-(s - c).length_squared() / (r * r)).exp())
                        .sum();
                    // Terraces: steps of 1/8 with a smooth tenth of the riser.
                    let t = (h.min(1.0) * 8.0).floor() / 8.0;
                    (0.8 * t + 0.2 * h).clamp(0.0, 1.0)
                })
            }
        }
    }
}

/// A 64-bit linear congruential sequence (Knuth's MMIX constants): the same numbers on every
/// machine, for the procedural maps and the seeded tests.
#[derive(Clone, Copy, Debug)]
pub struct Lcg(pub u64);

impl Lcg {
    /// The next number in [0, 1), from the state's top 24 bits.
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Seeded bumps (centre, radius, amplitude) of [`Dataset::Relief`]: a fixed linear congruential
/// sequence, so the map is the same on every machine.
fn relief_bumps() -> Vec<(Vec2, f32, f32)> {
    let mut rng = Lcg(0x2005_0b1e);
    let mut next = || rng.next_f32();
    (0..48)
        .map(|k| {
            let c = Vec2::new(next(), next());
            let r = if k < 8 { 0.12 } else { 0.03 } + 0.04 * next();
            let a = if k < 8 { 0.5 } else { 0.25 } * (0.5 + next());
            (c, r, a)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_hits_texel_centres_and_is_clamped() {
        let m = HeightMap::new(2, 2, vec![0.0, 1.0, 0.5, 0.25]);
        assert_eq!(m.sample(Vec2::new(0.25, 0.25)), 0.0);
        assert_eq!(m.sample(Vec2::new(0.75, 0.25)), 1.0);
        assert_eq!(m.sample(Vec2::new(0.25, 0.75)), 0.5);
        assert_eq!(m.sample(Vec2::new(0.5, 0.25)), 0.5);
        // Clamped beyond the outer centres.
        assert_eq!(m.sample(Vec2::new(0.0, 0.0)), 0.0);
        assert_eq!(m.sample(Vec2::new(1.0, 0.25)), 1.0);
    }

    /// Needles are isolated texels of height 1 (no two of the 8 neighbours both set), one per
    /// 8 × 8 block, on a floor of exact zeros.
    #[test]
    fn needles_are_isolated_unit_texels() {
        let n = 64;
        let m = Dataset::Needles.map(n);
        let ones: Vec<(isize, isize)> = (0..n * n)
            .filter(|&k| m.data[k] == 1.0)
            .map(|k| ((k % n) as isize, (k / n) as isize))
            .collect();
        assert_eq!(ones.len(), (n / 8) * (n / 8));
        assert!(m.data.iter().all(|&v| v == 0.0 || v == 1.0));
        for &(i, j) in &ones {
            for (di, dj) in [
                (-1, -1),
                (-1, 0),
                (-1, 1),
                (0, -1),
                (0, 1),
                (1, -1),
                (1, 0),
                (1, 1),
            ] {
                assert_eq!(m.texel(i + di, j + dj), 0.0, "needle at {i},{j}");
            }
        }
    }

    #[test]
    fn datasets_lie_in_the_unit_range_and_vary() {
        for d in Dataset::ALL {
            let m = d.map(64);
            let (lo, hi) = m
                .data
                .iter()
                .fold((1.0f32, 0.0f32), |(a, b), &v| (a.min(v), b.max(v)));
            assert!(
                (0.0..=1.0).contains(&lo) && hi <= 1.0 && hi - lo > 0.3,
                "{d:?}"
            );
            assert_eq!(d.map(64), m, "deterministic");
        }
    }
}
