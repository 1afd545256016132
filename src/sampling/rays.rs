//! Seeded receiver ray sets: randomness is a pure function of (point index, sample index, seed).
