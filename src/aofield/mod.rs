//! Ambient occlusion fields (J. Kontkanen, S. Laine, "Ambient Occlusion Fields", ACM SIGGRAPH
//! Symposium on Interactive 3D Graphics and Games 2005), a per-object peer of the visibility
//! field for inter-object AO: per occluder, in model space, a cube map around it whose texels
//! hold radial functions from which the occluder's spherical-cap approximation at any point
//! outside it follows with no ray at all.
//!
//! **The approximation** (the spherical cap approximation). Seen from a point x, the occluder is replaced by a spherical
//! cap of the same solid angle `Ω(x) = ∫ V(x, ω) dω` about its average occluded direction
//! `Υ(x) = normalize(∫ V(x, ω) ω dω)`; the occlusion at x with normal n is the cap's
//! cosine-weighted occlusion clipped by the horizon, `Ã = 1/π ∫_cap ⌊ω·n⌋ dω` ([`cap`]).
//!
//! **The fields** (storing Ω and Υ). Along each texel direction ω, at distance r = s·R from the occluder's
//! centre (R its bounding radius: s is scale-free), the texel stores
//! `Ω̃(s) = 1 / (a s² + b s + c)` and `Υ̃(s) = normalize(C − s ω)`: seven channels `a, b, c`,
//! `C` and the hull's distance `r₀` ([`storage`]), fitted by least squares to Ω and Υ sampled
//! at `radial_samples` distances by our ray caster ([`bake`](mod@bake), [`fit`]).
//!
//! **Inside the hull** (inside the convex hull). The functions are fitted only outside the occluder's convex hull
//! ([`hull`]). Within it (s < s₀), the occlusion evaluated at the hull, `Ã(s₀)`, is blended
//! towards a constant: `Ã = t Ã(s₀) + (1 − t) A₀`, `t = (s/s₀)^p` ([`Inside`]).
//!
//! **Run time** (at run time). Per receiver point and occluder: into model space by the instance's
//! transform (Ω is invariant under a similarity, so any rigid motion and uniform scale of the
//! occluder is exact), the cube map read bilinearly, `s_c = max(s, s₀)`, Ω̃ and Υ̃ at `s_c`, Ã
//! from (Ω̃, n·Υ̃). Several occluders combine as the paper's multiplicative blending of their
//! accessibilities: `1 − A = Π (1 − Ãᵢ)` (combining occluders). This project's AO is the accessibility
//! (1 = unoccluded), so an [`AoFieldScene`] answers `Π (1 − Ãᵢ)`.
//!
//! What an AO field cannot answer: an occluder's occlusion of itself (its own surface lies on
//! or inside its hull; the paper's method is for inter-object occlusion), a ray's
//! hit (shadows, reflections), and AO within a finite radius or with a distance falloff (the
//! cap counts the whole occluder at any distance).
//!
//! Deviations from the paper, each documented where it is made:
//! - the cap's occlusion is the closed form, not a 2D texture ([`cap`]);
//! - the hull's distance comes from a fixed set of supporting planes, an outer approximation
//!   ([`hull`]);
//! - Ω and Υ are sampled by ray casting in the bounding sphere's cone instead of rasterising a
//!   cube, at sample distances of our choosing, and the cube map is not low-pass filtered
//!   ([`bake`](mod@bake));
//! - the fits are Levenberg–Marquardt from linearised starts, the solid-angle fit kept at
//!   Ω̃ ≤ 2π beyond the hull and C within two bounding radii of the centre ([`fit`]);
//! - no fade to zero between `r_near` and `r_far`: the paper's shader fades the occlusion out
//!   at a user distance for speed; an AO field here answers unbounded AO, extrapolating the
//!   fits past `reach`;
//! - `A₀` and `p` are the paper's user constants; ours default to 1 and 1 (the centre of a
//!   solid occluder is fully occluded; a linear blend).

pub mod bake;
pub mod cache;
pub mod cap;
pub mod cube;
pub mod eval;
pub mod fit;
pub mod hull;
pub mod storage;

pub use bake::{bake, BakeStats, Fitted};
pub use eval::{AoField, AoFieldInstance, AoFieldScene, Cap, Inside};
pub use storage::Precision;

use serde::{Deserialize, Serialize};

/// Why a field cannot be baked or read.
#[derive(Debug, thiserror::Error)]
pub enum AoFieldError {
    #[error("ao field: {0}")]
    Invalid(String),
    #[error("ao field cache: {0}")]
    Cache(#[from] crate::io::CacheError),
}

/// The largest cube-map side a bake accepts.
pub const MAX_RES: usize = 256;
/// The most radial samples per texel.
pub const MAX_RADIAL_SAMPLES: usize = 64;
/// The most rays per sample.
pub const MAX_RAYS: u32 = 65536;

/// What determines a bake (and its cache key).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BakeParams {
    /// Texels per cube face side.
    pub res: usize,
    /// Samples per texel along its direction (at least 3: the solid angle has 3 parameters).
    pub radial_samples: usize,
    /// Rays per sample, k² (a perfect square).
    pub rays: u32,
    /// The farthest sample, in bounding radii from the centre.
    pub reach: f32,
}

impl Default for BakeParams {
    /// 32² texels per face, 12 samples per texel, 256 rays each, out to 8 bounding radii.
    fn default() -> Self {
        BakeParams {
            res: 32,
            radial_samples: 12,
            rays: 256,
            reach: 8.0,
        }
    }
}

impl BakeParams {
    /// k, the strata per side of a sample's rays.
    pub fn rays_per_side(&self) -> u32 {
        (f64::from(self.rays).sqrt().round()) as u32
    }

    /// Refuses values outside the ranges a bake supports, naming the parameter.
    pub fn check(&self) -> Result<(), AoFieldError> {
        let bad = |what: String| Err(AoFieldError::Invalid(what));
        if !(1..=MAX_RES).contains(&self.res) {
            return bad(format!("res {} is outside 1..={MAX_RES}", self.res));
        }
        if !(3..=MAX_RADIAL_SAMPLES).contains(&self.radial_samples) {
            return bad(format!(
                "radial_samples {} is outside 3..={MAX_RADIAL_SAMPLES}",
                self.radial_samples
            ));
        }
        let k = self.rays_per_side();
        if self.rays == 0 || self.rays > MAX_RAYS || k * k != self.rays {
            return bad(format!(
                "rays {} is not a perfect square in 1..={MAX_RAYS}",
                self.rays
            ));
        }
        if !(self.reach.is_finite() && (1.5..=1000.0).contains(&self.reach)) {
            return bad(format!("reach {} is outside [1.5, 1000]", self.reach));
        }
        Ok(())
    }
}
