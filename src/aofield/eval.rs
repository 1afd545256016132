//! Evaluating AO fields at run time (Kontkanen & Laine 2005): one occluder's cap
//! and occlusion at a model-space point ([`AoField`]), an instance under a similarity
//! ([`AoFieldInstance`]), and several occluders blended multiplicatively ([`AoFieldScene`]).

use super::bake::Fitted;
use super::cap::cap_occlusion;
use super::cube::Cube;
use super::fit::Quadratic;
use super::storage::{Precision, Stored, CHANNELS};
use crate::geometry::{Similarity, Sphere};
use glam::Vec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::Arc;

/// The blend inside the hull: `Ã = t Ã(s₀) + (1 − t) A₀`, `t = (s/s₀)^p`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Inside {
    /// A₀, the occlusion at the centre, in [0, 1].
    pub ao: f32,
    /// p > 0: larger keeps the hull's value deeper inside.
    pub power: f32,
}

impl Default for Inside {
    /// A₀ = 1 (the centre of a solid occluder sees only the occluder), p = 1.
    fn default() -> Self {
        Inside {
            ao: 1.0,
            power: 1.0,
        }
    }
}

/// An occluder's AO field, stored at a precision.
#[derive(Clone, Debug)]
pub struct AoField {
    /// The occluder's bounding sphere in model space (centre and unit of the field).
    pub bounds: Sphere,
    pub cube: Cube,
    pub stored: Stored,
}

/// The cap an occluder subtends at a point, as the field models it (model space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cap {
    /// Ω̃ at `max(s, s₀)`, steradians.
    pub omega: f64,
    /// Υ̃, the cap's unit axis.
    pub axis: Vec3,
    /// The point's distance from the centre, in bounding radii.
    pub s: f32,
    /// The hull's distance along the point's direction, interpolated.
    pub s0: f32,
}

impl AoField {
    /// The fitted channels stored at `precision`.
    pub fn new(fitted: &Fitted, precision: Precision) -> AoField {
        AoField {
            bounds: fitted.bounds,
            cube: Cube {
                res: fitted.params.res,
            },
            stored: Stored::encode(&fitted.texels, precision),
        }
    }

    /// Exact bytes the evaluation reads: the stored channels (with u8's ranges) and the
    /// bounding sphere (4 f32).
    pub fn bytes(&self) -> u64 {
        self.stored.bytes() + 16
    }

    /// [`Self::bytes`] of a field of `res`² texels a cube face stored at `precision`, before
    /// any bake.
    pub fn bytes_for(res: usize, precision: Precision) -> u64 {
        Stored::bytes_for(Cube { res }.len(), precision) + 16
    }

    /// The cap at model-space point `p`.
    #[inline]
    pub fn cap_at(&self, p: Vec3) -> Cap {
        let x = (p - self.bounds.center) / self.bounds.radius;
        let s = x.length();
        let w = if s > 0.0 { x / s } else { Vec3::Z };
        let b = self.cube.bilinear(w);
        let mut ch = [0.0f32; CHANNELS];
        for (&t, &wt) in b.texels.iter().zip(&b.weights) {
            if wt == 0.0 {
                continue;
            }
            let texel = self.stored.texel(t);
            for k in 0..CHANNELS {
                ch[k] += wt * texel[k];
            }
        }
        let s0 = ch[3].max(0.0);
        let sc = s.max(s0);
        let q = Quadratic {
            a: f64::from(ch[0]),
            b: f64::from(ch[1]),
            c: f64::from(ch[2]),
        };
        // Beyond the hull an occluder fills at most a half-space.
        let omega = q.omega(f64::from(sc)).min(2.0 * PI);
        let centre = Vec3::new(ch[4], ch[5], ch[6]);
        let axis = (centre - sc * w).try_normalize().unwrap_or(-w);
        Cap { omega, axis, s, s0 }
    }

    /// The occlusion Ã at model-space point `p` with unit normal `n`, in [0, 1].
    #[inline]
    pub fn occlusion(&self, p: Vec3, n: Vec3, inside: &Inside) -> f32 {
        let cap = self.cap_at(p);
        let a = cap_occlusion(cap.omega, f64::from(n.dot(cap.axis))) as f32;
        if cap.s < cap.s0 {
            let t = (cap.s / cap.s0).powf(inside.power);
            t * a + (1.0 - t) * inside.ao
        } else {
            a
        }
    }
}

/// A field placed in the world by a similarity (the occluder's instance transform).
#[derive(Clone, Debug)]
pub struct AoFieldInstance {
    pub field: Arc<AoField>,
    pub transform: Similarity,
}

impl AoFieldInstance {
    /// The occlusion at world point `p` with unit normal `n`.
    #[inline]
    pub fn occlusion(&self, p: Vec3, n: Vec3, inside: &Inside) -> f32 {
        self.field.occlusion(
            self.transform.to_local_point(p),
            self.transform.to_local_dir(n),
            inside,
        )
    }
}

/// Several occluders' fields answering AO together.
#[derive(Clone, Debug, Default)]
pub struct AoFieldScene {
    pub instances: Vec<AoFieldInstance>,
    pub inside: Inside,
}

impl AoFieldScene {
    /// AO at world point `p` with unit normal `n` (1 = unoccluded): the paper's multiplicative
    /// blending, `Π (1 − Ãᵢ)` over the occluders.
    #[inline]
    pub fn ao(&self, p: Vec3, n: Vec3) -> f32 {
        self.instances
            .iter()
            .map(|i| 1.0 - i.occlusion(p, n, &self.inside))
            .product()
    }

    /// [`Self::ao`] at every point, in parallel; the result does not depend on the thread count.
    ///
    /// # Panics
    /// If `points` and `normals` differ in length.
    pub fn ao_at_points(&self, points: &[Vec3], normals: &[Vec3]) -> Vec<f32> {
        assert_eq!(points.len(), normals.len(), "one normal per point");
        points
            .par_iter()
            .zip(normals)
            .map(|(&p, &n)| self.ao(p, n))
            .collect()
    }

    /// Bytes of the distinct fields (an instanced field counted once).
    pub fn bytes(&self) -> u64 {
        let mut seen: Vec<*const AoField> = Vec::new();
        let mut total = 0;
        for i in &self.instances {
            let p = Arc::as_ptr(&i.field);
            if !seen.contains(&p) {
                seen.push(p);
                total += i.field.bytes();
            }
        }
        total
    }
}
