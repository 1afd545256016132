//! The precision an AO field's seven channels are stored at (Kontkanen & Laine 2005,
//! preprocessing: two cube maps, `a, b, c, r₀` in one and `C` in the other): f32, f16 or u8, and the exact
//! bytes each takes. The evaluation reads the stored values and decodes them per fetch, as a
//! texture unit does.
//!
//! u8 maps each channel linearly between its least and greatest value over the whole map
//! (`lo + k·step`, k = 0…255, rounded to nearest); its 7 `lo` and 7 `step` (f32) are part of
//! the bytes. f16 rounds to nearest even (IEEE binary16, the `half` crate).

use half::f16;
use serde::{Deserialize, Serialize};

/// The channels of a texel: `a, b, c` of `q(s)`, `r₀` (the hull's distance), `C` (x, y, z);
/// lengths in bounding radii.
pub const CHANNELS: usize = 7;

/// One texel's channels.
pub type Texel = [f32; CHANNELS];

/// How the channels are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    #[default]
    F32,
    F16,
    U8,
}

impl Precision {
    /// Its name in specs and tables.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
            Precision::U8 => "u8",
        }
    }

    /// Bytes per stored channel value.
    pub fn bytes_per_value(self) -> u64 {
        match self {
            Precision::F32 => 4,
            Precision::F16 => 2,
            Precision::U8 => 1,
        }
    }
}

/// The stored channels of every texel.
#[derive(Clone, Debug)]
pub enum Stored {
    F32(Vec<Texel>),
    F16(Vec<[f16; CHANNELS]>),
    U8 {
        codes: Vec<[u8; CHANNELS]>,
        lo: Texel,
        step: Texel,
    },
}

impl Stored {
    /// The texels stored at `precision`.
    pub fn encode(texels: &[Texel], precision: Precision) -> Stored {
        match precision {
            Precision::F32 => Stored::F32(texels.to_vec()),
            Precision::F16 => Stored::F16(texels.iter().map(|t| t.map(f16::from_f32)).collect()),
            Precision::U8 => {
                let mut lo = [f32::INFINITY; CHANNELS];
                let mut hi = [f32::NEG_INFINITY; CHANNELS];
                for t in texels {
                    for k in 0..CHANNELS {
                        lo[k] = lo[k].min(t[k]);
                        hi[k] = hi[k].max(t[k]);
                    }
                }
                let mut step = [0.0; CHANNELS];
                for k in 0..CHANNELS {
                    if !lo[k].is_finite() {
                        lo[k] = 0.0;
                        hi[k] = 0.0;
                    }
                    step[k] = (hi[k] - lo[k]) / 255.0;
                }
                let codes = texels
                    .iter()
                    .map(|t| {
                        let mut c = [0u8; CHANNELS];
                        for k in 0..CHANNELS {
                            c[k] = if step[k] > 0.0 {
                                ((t[k] - lo[k]) / step[k]).round().clamp(0.0, 255.0) as u8
                            } else {
                                0
                            };
                        }
                        c
                    })
                    .collect();
                Stored::U8 { codes, lo, step }
            }
        }
    }

    /// The precision it is stored at.
    pub fn precision(&self) -> Precision {
        match self {
            Stored::F32(_) => Precision::F32,
            Stored::F16(_) => Precision::F16,
            Stored::U8 { .. } => Precision::U8,
        }
    }

    /// Texels stored.
    pub fn len(&self) -> usize {
        match self {
            Stored::F32(v) => v.len(),
            Stored::F16(v) => v.len(),
            Stored::U8 { codes, .. } => codes.len(),
        }
    }

    /// Whether no texel is stored.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Texel `t`, decoded.
    #[inline]
    pub fn texel(&self, t: usize) -> Texel {
        match self {
            Stored::F32(v) => v[t],
            Stored::F16(v) => v[t].map(f16::to_f32),
            Stored::U8 { codes, lo, step } => {
                let c = &codes[t];
                std::array::from_fn(|k| lo[k] + f32::from(c[k]) * step[k])
            }
        }
    }

    /// Exact bytes of the stored values and of what decodes them (u8: `lo` and `step`).
    pub fn bytes(&self) -> u64 {
        Stored::bytes_for(self.len(), self.precision())
    }

    /// [`Self::bytes`] of `texels` texels stored at `precision`, before any is encoded.
    pub fn bytes_for(texels: usize, precision: Precision) -> u64 {
        let values = (texels * CHANNELS) as u64 * precision.bytes_per_value();
        match precision {
            Precision::U8 => values + 2 * CHANNELS as u64 * 4,
            _ => values,
        }
    }

    /// The largest error of a decoded value of channel `k` (0 for f32): half a step for u8;
    /// for f16, half an ulp of the largest magnitude (2⁻¹¹ relative, normal range).
    pub fn max_error(&self, k: usize, largest_magnitude: f32) -> f32 {
        match self {
            Stored::F32(_) => 0.0,
            Stored::F16(_) => largest_magnitude * 2f32.powi(-11),
            Stored::U8 { step, .. } => 0.5 * step[k],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<Texel> {
        (0..97)
            .map(|i| {
                let x = i as f32 * 0.37;
                [
                    x.sin() * 3.0,
                    x.cos(),
                    -0.5 + 0.01 * x,
                    0.4 + 0.5 * (0.3 * x).sin().abs(),
                    0.1 * x.cos(),
                    -0.2,
                    7.5,
                ]
            })
            .collect()
    }

    #[test]
    fn round_trips_within_each_precisions_step_and_bytes_are_exact() {
        let texels = sample();
        for (p, per_texel, extra) in [
            (Precision::F32, 28, 0),
            (Precision::F16, 14, 0),
            (Precision::U8, 7, 56),
        ] {
            let s = Stored::encode(&texels, p);
            assert_eq!(s.precision(), p);
            assert_eq!(s.bytes(), 97 * per_texel + extra);
            for k in 0..CHANNELS {
                let largest = texels.iter().map(|t| t[k].abs()).fold(0.0, f32::max);
                let bound = s.max_error(k, largest);
                let mut worst = 0.0f32;
                for (i, t) in texels.iter().enumerate() {
                    worst = worst.max((s.texel(i)[k] - t[k]).abs());
                }
                // The bound plus the f32 rounding of lo + k·step.
                assert!(
                    worst <= bound * 1.0001 + largest * 1e-6,
                    "{p:?} channel {k}: error {worst} above {bound}"
                );
                if p == Precision::U8 && k == 0 {
                    // A spread channel cannot round-trip exactly through 256 levels.
                    assert!(worst > 0.0);
                }
            }
        }
    }

    #[test]
    fn constant_channels_decode_exactly_in_u8() {
        let texels = sample();
        let s = Stored::encode(&texels, Precision::U8);
        for i in 0..texels.len() {
            assert_eq!(s.texel(i)[5], -0.2);
            assert_eq!(s.texel(i)[6], 7.5);
        }
    }
}
