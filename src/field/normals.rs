//! Normal fields (2010 §4.2): per map texel, the unit normal of the first hit, packed with the
//! octahedral map (Meyer et al., "On Floating-Point Normal Vectors", EGSR 2010; Cigolle et al.,
//! "A Survey of Efficient Representations for Independent Unit Vectors", JCGT 2014) into 2 × u8 or
//! 2 × u16, so that a lookup returns an approximate hit point and normal for reflections.

use glam::{Vec2, Vec3};

/// Unit vector → octahedral square [−1, 1]².
#[inline]
pub fn oct_encode(n: Vec3) -> Vec2 {
    let p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
    if n.z >= 0.0 {
        p
    } else {
        let s = Vec2::new(1.0f32.copysign(p.x), 1.0f32.copysign(p.y));
        (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * s
    }
}

/// Octahedral square [−1, 1]² → unit vector.
#[inline]
pub fn oct_decode(e: Vec2) -> Vec3 {
    let mut v = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    let t = (-v.z).max(0.0);
    v.x += if v.x >= 0.0 { -t } else { t };
    v.y += if v.y >= 0.0 { -t } else { t };
    v.normalize()
}

/// Packs a unit normal into two unsigned normalised integers of `bits` bits each.
#[inline]
pub fn pack_normal(n: Vec3, bits: u32) -> [u32; 2] {
    let levels = ((1u64 << bits) - 1) as f32;
    let e = oct_encode(n);
    let q = |x: f32| ((x.clamp(-1.0, 1.0) * 0.5 + 0.5) * levels).round() as u32;
    [q(e.x), q(e.y)]
}

/// Unpacks [`pack_normal`].
#[inline]
pub fn unpack_normal(p: [u32; 2], bits: u32) -> Vec3 {
    let levels = ((1u64 << bits) - 1) as f32;
    let d = |q: u32| q as f32 / levels * 2.0 - 1.0;
    oct_decode(Vec2::new(d(p[0]), d(p[1])))
}

/// Per-texel hit normals of every map, 2 × `bits` bits per texel in a `[u16; 2]` (row-major
/// like the distances). Misses hold the reverse of the texel's inward direction, never read.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalField {
    pub texels: usize,
    pub bits: u32,
    pub data: Vec<[u16; 2]>,
}

impl NormalField {
    /// The unpacked normal at (map, texel).
    #[inline]
    pub fn get(&self, map: usize, texel: usize) -> Vec3 {
        let [a, b] = *self.cell(map, texel);
        unpack_normal([a as u32, b as u32], self.bits)
    }

    /// The packed normal at (map, texel).
    #[inline]
    pub fn cell(&self, map: usize, texel: usize) -> &[u16; 2] {
        &self.data[map * self.texels + texel]
    }

    /// Bytes of the packed normals as a renderer stores them: 2 × `bits` / 8 per texel (the
    /// 8-bit field is held in 16-bit words here, but counts as 2 bytes a texel, as on a GPU).
    pub fn bytes(&self) -> u64 {
        self.data.len() as u64 * 2 * self.bits as u64 / 8
    }

    /// The same normals at `bits` bits: each normal unpacked and packed again. From 16 to 8
    /// bits this is within one 8-bit step of packing the exact normal (the 16-bit error is
    /// 1/257 of an 8-bit step), so a field derived this way stands for an 8-bit bake.
    pub fn requantized(&self, bits: u32) -> NormalField {
        let data = self
            .data
            .iter()
            .map(|&[a, b]| {
                let n = unpack_normal([a as u32, b as u32], self.bits);
                let [a, b] = pack_normal(n, bits);
                [a as u16, b as u16]
            })
            .collect();
        NormalField {
            texels: self.texels,
            bits,
            data,
        }
    }
}

impl super::VisibilityField {
    /// The reflection query of the 2010 paper (§4.2): the field's hit distance of the ray (the
    /// lookup of [`Self::hit_distance`], with its selection and intra-object test) and the normal
    /// field's normal there, unit, in model space, unoriented (the side a shader faces it to is
    /// the caller's). The normal is the one of the map and texel the nearest selection reads,
    /// also when the distance is interpolated.
    ///
    /// # Panics
    /// If `normals` is not this field's (another texel count or map count).
    pub fn surface_hit(
        &self,
        normals: &NormalField,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        opts: &super::lookup::LookupOptions,
    ) -> Option<(f32, Vec3)> {
        use super::lookup::{NearestRead, Reads, SphereOrigin};
        assert!(
            normals.texels == self.params.texels()
                && normals.data.len() == self.params.count * normals.texels,
            "surface_hit: the normal field is not this field's"
        );
        let from = SphereOrigin::new(origin, self.bounds.center, self.bounds.radius);
        let (t, read) = match opts.selection {
            // The nearest read gives both the distance and the normal's texel.
            super::Selection::Nearest => {
                let probe = self.probe::<NearestRead>(&from, origin, dir, tmin, tmax)?;
                (self.finish(&probe, tmin, tmax, opts)?, *probe.reads())
            }
            super::Selection::Interpolated => {
                let t = self.hit_distance(origin, dir, tmin, tmax, opts)?;
                let c = self.cross(&from, origin, dir, tmin, tmax)?;
                (t, NearestRead::of(self, c.u, c.dir))
            }
        };
        Some((t, normals.get(read.map as usize, read.texel as usize)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rays::uniform;

    fn random_unit(i: u32) -> Vec3 {
        let z = 2.0 * uniform(i, 0, 0, 9) - 1.0;
        let phi = std::f32::consts::TAU * uniform(i, 0, 1, 9);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    #[test]
    fn octahedral_round_trip_error_shrinks_with_bits() {
        // The octahedral map's worst-case angular error is about 1.5× the square's step: for 8
        // bits (step 2/255) under 1°, for 16 bits under 0.005°.
        let axes = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z];
        for (bits, max_deg) in [(8u32, 1.0f32), (16, 0.005)] {
            let worst = (0..20_000)
                .map(random_unit)
                .chain(axes)
                .map(|n| {
                    let m = unpack_normal(pack_normal(n, bits), bits);
                    // 2·asin(|n − m| / 2) in f64: acos of an f32 dot product cannot resolve
                    // angles below ~0.02°.
                    let chord = (n.as_dvec3() - m.as_dvec3()).length();
                    (2.0 * (chord / 2.0).asin()).to_degrees() as f32
                })
                .fold(0.0f32, f32::max);
            assert!(worst < max_deg, "{bits} bits: worst {worst}°");
        }
    }

    #[test]
    fn octahedral_float_round_trip_is_tight() {
        for i in 0..10_000 {
            let n = random_unit(i);
            let m = oct_decode(oct_encode(n));
            assert!((n - m).length() < 1e-5, "{n} -> {m}");
        }
    }
}
