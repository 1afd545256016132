//! Run-time choice of the instruction set for the few loops written eight lanes wide
//! ([`crate::field::lanes`], [`crate::sampling::rays::PreparedRaySet::fill_world`]), and the
//! AVX2 transposes they share. Each such loop has a plain one-ray-at-a-time twin; the AVX2
//! versions perform the same IEEE operations in the same order (no fused multiply-add), so both
//! give the same bits (each is tested against its twin).

/// The instruction set the eight-lane loops run with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// One ray at a time (any CPU).
    Portable,
    /// AVX2 intrinsics, eight f32 or four f64 lanes per instruction (a request: on a CPU
    /// without AVX2 the loops run one lane at a time).
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Isa {
    /// The widest the running CPU supports (the detection is cached by the standard library).
    #[inline]
    pub fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Isa::Avx2;
        }
        Isa::Portable
    }

    /// Whether a loop asked to run on `self` takes its AVX2 code on this CPU: an `Avx2` request
    /// on a CPU without AVX2 runs one lane at a time (the detection is a cached flag).
    #[inline]
    pub fn runs_avx2(self) -> bool {
        match self {
            Isa::Portable => false,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => Isa::detect() == Isa::Avx2,
        }
    }

    /// Every instruction set this CPU runs (for tests that compare them).
    pub fn all_available() -> Vec<Isa> {
        let mut v = vec![Isa::Portable];
        if Isa::detect() != Isa::Portable {
            v.push(Isa::detect());
        }
        v
    }
}

/// Eight packed `Vec3`s (24 f32) to and from three registers of x, y and z.
#[cfg(target_arch = "x86_64")]
pub(crate) mod x86 {
    use std::arch::x86_64::*;

    /// Eight consecutive `Vec3`s (24 packed f32) transposed into x, y and z registers, lane k
    /// holding vector k.
    ///
    /// # Safety
    /// `p` must point to 24 readable f32; the CPU must have AVX2.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub unsafe fn load3x8(p: *const f32) -> (__m256, __m256, __m256) {
        let pair = |lo: usize, hi: usize| {
            // SAFETY: within the 24 f32 the caller vouches for.
            unsafe {
                _mm256_insertf128_ps::<1>(
                    _mm256_castps128_ps256(_mm_loadu_ps(p.add(lo))),
                    _mm_loadu_ps(p.add(hi)),
                )
            }
        };
        // Vectors 0–3 in the low halves, 4–7 in the high: m03 = x0 y0 z0 x1,
        // m14 = y1 z1 x2 y2, m25 = z2 x3 y3 z3 (per half).
        let (m03, m14, m25) = (pair(0, 12), pair(4, 16), pair(8, 20));
        let xy = _mm256_shuffle_ps::<0b10_01_11_10>(m14, m25); // x2 y2 x3 y3
        let yz = _mm256_shuffle_ps::<0b01_00_10_01>(m03, m14); // y0 z0 y1 z1
        let x = _mm256_shuffle_ps::<0b10_00_11_00>(m03, xy); // x0 x1 x2 x3
        let y = _mm256_shuffle_ps::<0b11_01_10_00>(yz, xy); // y0 y1 y2 y3
        let z = _mm256_shuffle_ps::<0b11_00_11_01>(yz, m25); // z0 z1 z2 z3
        (x, y, z)
    }

    /// The inverse of [`load3x8`]: lane k of x, y and z written as the k-th `Vec3` at `p`.
    ///
    /// # Safety
    /// `p` must point to 24 writable f32; the CPU must have AVX2.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub unsafe fn store3x8(p: *mut f32, x: __m256, y: __m256, z: __m256) {
        let rxy = _mm256_shuffle_ps::<0b10_00_10_00>(x, y); // x0 x2 y0 y2
        let ryz = _mm256_shuffle_ps::<0b11_01_11_01>(y, z); // y1 y3 z1 z3
        let rzx = _mm256_shuffle_ps::<0b11_01_10_00>(z, x); // z0 z2 x1 x3
        let r03 = _mm256_shuffle_ps::<0b10_00_10_00>(rxy, rzx); // x0 y0 z0 x1
        let r14 = _mm256_shuffle_ps::<0b11_01_10_00>(ryz, rxy); // y1 z1 x2 y2
        let r25 = _mm256_shuffle_ps::<0b11_01_11_01>(rzx, ryz); // z2 x3 y3 z3
        _mm_storeu_ps(p, _mm256_castps256_ps128(r03));
        _mm_storeu_ps(p.add(4), _mm256_castps256_ps128(r14));
        _mm_storeu_ps(p.add(8), _mm256_castps256_ps128(r25));
        _mm_storeu_ps(p.add(12), _mm256_extractf128_ps::<1>(r03));
        _mm_storeu_ps(p.add(16), _mm256_extractf128_ps::<1>(r14));
        _mm_storeu_ps(p.add(20), _mm256_extractf128_ps::<1>(r25));
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn transposes_are_exact_and_inverse() {
            if !std::arch::is_x86_feature_detected!("avx2") {
                return; // the Portable twins are tested everywhere; this CPU has no AVX2 path
            }
            let v: Vec<f32> = (0..24).map(|i| i as f32 + 0.25).collect();
            let mut w = vec![0.0f32; 24];
            // SAFETY: AVX2 checked; 24 f32 each.
            let (x, y, z) = unsafe { load3x8(v.as_ptr()) };
            let lanes = |r: __m256| {
                let mut a = [0.0f32; 8];
                // SAFETY: 8 f32.
                unsafe { _mm256_storeu_ps(a.as_mut_ptr(), r) };
                a
            };
            for k in 0..8 {
                assert_eq!(
                    [lanes(x)[k], lanes(y)[k], lanes(z)[k]],
                    [v[3 * k], v[3 * k + 1], v[3 * k + 2]]
                );
            }
            unsafe { store3x8(w.as_mut_ptr(), x, y, z) };
            assert_eq!(v, w);
        }
    }
}
