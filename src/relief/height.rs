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
    /// A grid of sharp cones (the paper's "spikes"): the high-frequency case.
    Spikes,
}

impl Dataset {
    /// All datasets, in table order.
    pub const ALL: [Dataset; 3] = [Dataset::Simple, Dataset::Relief, Dataset::Spikes];

    /// The name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Dataset::Simple => "simple",
            Dataset::Relief => "relief",
            Dataset::Spikes => "spikes",
        }
    }

    /// The map at `n × n` texels.
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
