//! The `cone` query: the engines' cone-traced estimators (`crate::sdf::cone`) as a direct
//! [`Estimator`] on the kind's points. What they answer is the kind's typed answer
//! ([`Kind::answers`]) and its estimator's options ([`Estimator::estimates`]): binary AO (its
//! `offset`, `max_distance`) and soft shadows (its `offset`, `lights`). Anything else is refused:
//! a reflection needs a surface per ray, which a cone does not give; a distance falloff weighs
//! each ray's hit distance, which the closest approach does not give.

use crate::experiment::kinds::{Answers, Kind};
use crate::render::ao::Falloff;
use crate::render::estimator::{Estimates, Estimator, Points};
use crate::render::truth::{Truth, TruthOptions};
use crate::sampling::rays::RaySet;
use crate::sdf::{ConeLight, ConeSet, ConeTrace, SdfScene};
use crate::visibility::Visibility;
use rayon::prelude::*;

/// Why the cones cannot answer `kind`, or none.
pub(super) fn refusal(kind: &dyn Kind) -> Option<String> {
    match kind.answers() {
        Answers::Ao(_) if !kind.answers().binary_ao() => Some(
            "query \"cone\" answers binary AO (falloff \"step\"): the closest approach \
             gives no hit distance to weigh"
                .into(),
        ),
        Answers::Ao(_) | Answers::Shadow => None,
        Answers::Reflection | Answers::Other => Some(format!(
            "query \"cone\" answers ambient occlusion and soft shadows only, not \"{}\" (a \
             cone gives no surface per ray); use query \"trace\"",
            kind.name()
        )),
    }
}

/// What the cones estimate.
pub(super) enum Quantity {
    /// AO at `origin = point + offset · normal`, each cone to `tmax`.
    Ao { offset: f32, tmax: f32 },
    /// The light fraction of `lights`.
    Light { offset: f32, lights: Vec<ConeLight> },
}

/// The kind's estimator as a [`Quantity`], or why not.
pub(super) fn quantity_of(est: &dyn Estimator) -> Result<Quantity, String> {
    match est.estimates() {
        Estimates::Ao(o) => {
            if o.falloff != Falloff::Step {
                return Err("query \"cone\" answers binary AO (falloff \"step\") only".to_string());
            }
            Ok(Quantity::Ao {
                offset: o.offset,
                tmax: o.max_distance.unwrap_or(f32::INFINITY),
            })
        }
        Estimates::Shadow(o) => Ok(Quantity::Light {
            offset: o.offset,
            lights: (o.lights.iter())
                .map(|l| ConeLight {
                    center: l.center,
                    radius: l.radius,
                    intensity: l.intensity,
                })
                .collect(),
        }),
        Estimates::Reflection(_) | Estimates::Other => Err(format!(
            "query \"cone\" answers ambient occlusion and soft shadows, not the estimator \"{}\"",
            est.name()
        )),
    }
}

/// Cone-traced AO or light fraction at every point, through the volumes only.
pub(super) struct ConeEstimator {
    pub scene: SdfScene,
    pub cones: ConeSet,
    pub trace: ConeTrace,
    pub quantity: Quantity,
}

impl ConeEstimator {
    fn values(&self, at: Points) -> Vec<f32> {
        at.points
            .par_iter()
            .zip(at.normals)
            .map(|(&p, &n)| match &self.quantity {
                Quantity::Ao { offset, tmax } => {
                    self.scene
                        .cone_ao(p + *offset * n, n, &self.cones, *tmax, &self.trace)
                }
                Quantity::Light { offset, lights } => {
                    self.scene
                        .cone_light_fraction(p + *offset * n, n, lights, &self.trace)
                }
            })
            .collect()
    }
}

impl Estimator for ConeEstimator {
    fn name(&self) -> &'static str {
        match self.quantity {
            Quantity::Ao { .. } => "sdf_cone_ao",
            Quantity::Light { .. } => "sdf_cone_shadow",
        }
    }

    /// The cones' values; the rays are not read (the same values on every seed).
    fn estimate(&self, _vis: &dyn Visibility, at: Points, _rays: &RaySet) -> Vec<f32> {
        self.values(at)
    }

    /// The same values, exact for this estimator (no rays, no standard error).
    fn converged(&self, _vis: &dyn Visibility, at: Points, _t: &TruthOptions) -> Truth {
        Truth::exact(self.values(at))
    }

    fn key(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        m.insert("quantity".into(), serde_json::json!(self.name()));
        m.insert("cones".into(), serde_json::json!(self.cones.axes.len()));
        m.insert("step".into(), serde_json::json!(self.trace.step));
        m.insert("max_steps".into(), serde_json::json!(self.trace.max_steps));
        m
    }
}
