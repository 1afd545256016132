//! Storage precisions of a field's normalised distances D ∈ [0, 1] (1 = miss).
//!
//! - `F32`: the distance as is.
//! - `U16`, `U8`: unsigned normalised integers with L = 2^bits − 1 levels, round to nearest.
//!   Deviation from the paper: the top code L is reserved for "miss", so a hit is stored as
//!   min(round(D·L), L − 1). A hit can then never read back as a miss; the price is that hits with
//!   D > (L − 1.5)/L (only at the far side of the sphere) are stored up to 1.5 steps short.
//!   Decoding is q / L, so the error of every other hit is at most half a step, 1/(2L).
//! - `Bit1`: 2008 §4 "Further Memory Optimization" (Figure 7): one bit per direction (hit or
//!   miss) and, per map, the mean normalised distance of that map's hits, returned for every hit.

use crate::hint::prefetch_line;

/// Stored precision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    F32,
    U16,
    U8,
    #[serde(rename = "bit1")]
    Bit1,
}

impl Precision {
    /// Bits per direction.
    pub fn bits(self) -> u32 {
        match self {
            Precision::F32 => 32,
            Precision::U16 => 16,
            Precision::U8 => 8,
            Precision::Bit1 => 1,
        }
    }

    /// Short name used in tables and file names.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::U16 => "u16",
            Precision::U8 => "u8",
            Precision::Bit1 => "bit1",
        }
    }
}

/// 64-bit words per map in the 1-bit variant (rows padded to whole words).
pub fn words_per_map(texels: usize) -> usize {
    texels.div_ceil(64)
}

/// Bytes of stored data for a field: maps × texels × bits / 8 (plus, for 1 bit, row padding to
/// 64-bit words and one f32 mean per map).
pub fn storage_bytes(precision: Precision, maps: usize, texels: usize) -> u64 {
    let maps = maps as u64;
    match precision {
        Precision::F32 => maps * texels as u64 * 4,
        Precision::U16 => maps * texels as u64 * 2,
        Precision::U8 => maps * texels as u64,
        Precision::Bit1 => maps * (words_per_map(texels) as u64 * 8 + 4),
    }
}

/// Encodes a normalised distance with `levels` = 2^bits − 1 (see the module docs).
#[inline]
pub fn encode_unorm(d: f32, levels: u32) -> u32 {
    if d >= 1.0 || d.is_nan() {
        return levels; // miss (and NaN, which bake never produces)
    }
    // In f64 so that the product is exact and rounding goes to the true nearest level.
    ((d.max(0.0) as f64 * levels as f64).round() as u32).min(levels - 1)
}

/// Decodes [`encode_unorm`].
#[inline]
pub fn decode_unorm(q: u32, levels: u32) -> f32 {
    q as f32 / levels as f32
}

/// [`decode_unorm`] of every u8 code, evaluated at compile time (the same IEEE division).
const U8_DECODE: [f32; 256] = {
    let mut table = [0.0f32; 256];
    let mut q = 0;
    while q < 256 {
        table[q] = q as f32 / u8::MAX as f32;
        q += 1;
    }
    table
};

/// The stored distances of every map, row-major: index = map · texels + texel.
#[derive(Clone, Debug, PartialEq)]
pub enum Storage {
    F32 {
        texels: usize,
        data: Vec<f32>,
    },
    U16 {
        texels: usize,
        data: Vec<u16>,
    },
    U8 {
        texels: usize,
        data: Vec<u8>,
    },
    Bit1 {
        texels: usize,
        /// `words_per_map(texels)` words per map; bit set = hit.
        bits: Vec<u64>,
        /// Per map: mean normalised distance of its hits (1 where the map has none).
        mean: Vec<f32>,
    },
}

impl Storage {
    /// All-miss storage for `maps` maps of `texels` texels.
    pub fn new(precision: Precision, maps: usize, texels: usize) -> Storage {
        match precision {
            Precision::F32 => Storage::F32 {
                texels,
                data: vec![1.0; maps * texels],
            },
            Precision::U16 => Storage::U16 {
                texels,
                data: vec![u16::MAX; maps * texels],
            },
            Precision::U8 => Storage::U8 {
                texels,
                data: vec![u8::MAX; maps * texels],
            },
            Precision::Bit1 => Storage::Bit1 {
                texels,
                bits: vec![0; maps * words_per_map(texels)],
                mean: vec![1.0; maps],
            },
        }
    }

    pub fn precision(&self) -> Precision {
        match self {
            Storage::F32 { .. } => Precision::F32,
            Storage::U16 { .. } => Precision::U16,
            Storage::U8 { .. } => Precision::U8,
            Storage::Bit1 { .. } => Precision::Bit1,
        }
    }

    pub fn texels(&self) -> usize {
        match self {
            Storage::F32 { texels, .. }
            | Storage::U16 { texels, .. }
            | Storage::U8 { texels, .. }
            | Storage::Bit1 { texels, .. } => *texels,
        }
    }

    pub fn maps(&self) -> usize {
        match self {
            Storage::F32 { texels, data } => data.len() / texels.max(&1),
            Storage::U16 { texels, data } => data.len() / texels.max(&1),
            Storage::U8 { texels, data } => data.len() / texels.max(&1),
            Storage::Bit1 { mean, .. } => mean.len(),
        }
    }

    /// Normalised distance stored for (map, texel); 1 = miss.
    #[inline]
    pub fn get(&self, map: usize, texel: usize) -> f32 {
        match self {
            Storage::F32 { texels, data } => data[map * texels + texel],
            Storage::U16 { texels, data } => {
                decode_unorm(data[map * texels + texel] as u32, u16::MAX as u32)
            }
            Storage::U8 { texels, data } => U8_DECODE[data[map * texels + texel] as usize],
            Storage::Bit1 { texels, bits, mean } => {
                let w = map * words_per_map(*texels) + texel / 64;
                if (bits[w] >> (texel % 64)) & 1 == 1 {
                    mean[map]
                } else {
                    1.0
                }
            }
        }
    }

    /// Hints the CPU to bring the cache line of (map, texel) into cache (x86-64 `prefetcht0`;
    /// nothing elsewhere). No effect on results; an index out of range is ignored.
    #[inline]
    pub fn prefetch(&self, map: usize, texel: usize) {
        let ptr: *const u8 = match self {
            Storage::F32 { texels, data } => {
                data.as_ptr().wrapping_add(map * texels + texel).cast()
            }
            Storage::U16 { texels, data } => {
                data.as_ptr().wrapping_add(map * texels + texel).cast()
            }
            Storage::U8 { texels, data } => data.as_ptr().wrapping_add(map * texels + texel),
            Storage::Bit1 { texels, bits, .. } => bits
                .as_ptr()
                .wrapping_add(map * words_per_map(*texels) + texel / 64)
                .cast(),
        };
        prefetch_line(ptr);
    }

    /// Mutable view of one map's slot, for filling maps in parallel.
    pub fn map_slots(&mut self) -> Vec<MapSlot<'_>> {
        match self {
            Storage::F32 { texels, data } => data.chunks_mut(*texels).map(MapSlot::F32).collect(),
            Storage::U16 { texels, data } => data.chunks_mut(*texels).map(MapSlot::U16).collect(),
            Storage::U8 { texels, data } => data.chunks_mut(*texels).map(MapSlot::U8).collect(),
            Storage::Bit1 {
                texels, bits, mean, ..
            } => bits
                .chunks_mut(words_per_map(*texels))
                .zip(mean.iter_mut())
                .map(|(b, m)| MapSlot::Bit1(b, m))
                .collect(),
        }
    }

    /// Every stored distance finite and in [0, 1].
    pub fn validate(&self) -> Result<(), String> {
        let bad = |v: f32| !(0.0..=1.0).contains(&v);
        match self {
            Storage::F32 { data, .. } => match data.iter().position(|&v| bad(v)) {
                Some(i) => Err(format!(
                    "stored distance {} at index {i} is outside [0, 1]",
                    data[i]
                )),
                None => Ok(()),
            },
            Storage::Bit1 { mean, .. } => match mean.iter().position(|&v| bad(v)) {
                Some(i) => Err(format!(
                    "mean distance {} of map {i} is outside [0, 1]",
                    mean[i]
                )),
                None => Ok(()),
            },
            Storage::U16 { .. } | Storage::U8 { .. } => Ok(()),
        }
    }
}

/// One map's storage, written by the baker.
pub enum MapSlot<'a> {
    F32(&'a mut [f32]),
    U16(&'a mut [u16]),
    U8(&'a mut [u8]),
    Bit1(&'a mut [u64], &'a mut f32),
}

impl MapSlot<'_> {
    /// Stores one map from its normalised distances (1 = miss).
    pub fn store(&mut self, row: &[f32]) {
        match self {
            MapSlot::F32(s) => s.copy_from_slice(row),
            MapSlot::U16(s) => {
                for (o, &d) in s.iter_mut().zip(row) {
                    *o = encode_unorm(d, u16::MAX as u32) as u16;
                }
            }
            MapSlot::U8(s) => {
                for (o, &d) in s.iter_mut().zip(row) {
                    *o = encode_unorm(d, u8::MAX as u32) as u8;
                }
            }
            MapSlot::Bit1(words, mean) => {
                words.fill(0);
                let (mut sum, mut hits) = (0.0f64, 0u32);
                for (t, &d) in row.iter().enumerate() {
                    if d < 1.0 {
                        words[t / 64] |= 1 << (t % 64);
                        sum += d as f64;
                        hits += 1;
                    }
                }
                **mean = if hits > 0 {
                    (sum / hits as f64) as f32
                } else {
                    1.0
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unorm_round_trip_error_is_at_most_half_a_step() {
        for levels in [u8::MAX as u32, u16::MAX as u32] {
            let half = 0.5 / levels as f32;
            for i in 0..=100_000u32 {
                let d = i as f32 / 100_000.0 * ((levels as f32 - 1.5) / levels as f32);
                let e = (decode_unorm(encode_unorm(d, levels), levels) - d).abs();
                // Half a step, plus the f32 rounding of the decoded value (half an ulp).
                let ulp = f32::EPSILON * d.max(f32::MIN_POSITIVE);
                assert!(e <= half + ulp, "d {d} levels {levels} error {e}");
            }
        }
    }

    #[test]
    fn u8_table_equals_the_decoder() {
        for q in 0..=255u32 {
            assert_eq!(U8_DECODE[q as usize], decode_unorm(q, 255));
        }
    }

    #[test]
    fn quantisation_edges_zero_just_under_one_and_one() {
        for levels in [255u32, 65535] {
            assert_eq!(encode_unorm(0.0, levels), 0);
            // A hit just under 1 stays a hit (top code reserved for misses).
            let q = encode_unorm(1.0 - f32::EPSILON, levels);
            assert_eq!(q, levels - 1);
            assert!(decode_unorm(q, levels) < 1.0);
            assert_eq!(encode_unorm(1.0, levels), levels);
            assert_eq!(decode_unorm(levels, levels), 1.0);
        }
    }

    #[test]
    fn every_precision_round_trips_within_its_bound() {
        let texels = 130; // not a multiple of 64: exercises 1-bit padding
        let rows: Vec<Vec<f32>> = (0..3)
            .map(|m| {
                (0..texels)
                    .map(|t| {
                        if (t + m) % 3 == 0 {
                            1.0
                        } else {
                            ((t * 7 + m) % 97) as f32 / 97.0
                        }
                    })
                    .collect()
            })
            .collect();
        for p in [
            Precision::F32,
            Precision::U16,
            Precision::U8,
            Precision::Bit1,
        ] {
            let mut s = Storage::new(p, 3, texels);
            for (slot, row) in s.map_slots().iter_mut().zip(&rows) {
                slot.store(row);
            }
            assert_eq!(s.maps(), 3);
            s.validate().unwrap();
            for (m, row) in rows.iter().enumerate() {
                let hits: Vec<f32> = row.iter().copied().filter(|&d| d < 1.0).collect();
                let mean = hits.iter().sum::<f32>() / hits.len() as f32;
                for (t, &d) in row.iter().enumerate() {
                    let got = s.get(m, t);
                    match p {
                        Precision::F32 => assert_eq!(got, d),
                        Precision::U16 => assert!((got - d).abs() <= 0.5 / 65535.0 + 1e-7),
                        Precision::U8 => assert!((got - d).abs() <= 0.5 / 255.0 + 1e-7),
                        Precision::Bit1 => {
                            if d < 1.0 {
                                assert!((got - mean).abs() < 1e-6);
                            } else {
                                assert_eq!(got, 1.0);
                            }
                        }
                    }
                    // A miss always reads back as a miss, a hit always as a hit.
                    assert_eq!(got < 1.0, d < 1.0, "{p:?} map {m} texel {t}");
                }
            }
        }
    }

    #[test]
    fn storage_bytes_match_the_papers_figures() {
        // 2008 §4: a 256×256 map takes 65,536 bytes as unsigned chars, 262,144 as floats.
        assert_eq!(storage_bytes(Precision::U8, 1, 256 * 256), 65_536);
        assert_eq!(storage_bytes(Precision::F32, 1, 256 * 256), 262_144);
        // 1 bit: 87.5% less than a byte per direction, plus the per-map mean.
        assert_eq!(storage_bytes(Precision::Bit1, 1, 256 * 256), 8192 + 4);
    }
}
