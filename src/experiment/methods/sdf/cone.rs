//! The `cone` query: the engines' cone-traced estimators (`crate::sdf::cone`) as a direct
//! [`Estimator`] on the kind's points. What they answer is read from the kind's estimator, by
//! its name and its key (the options that determine its values, [`Estimator::key`]): `ao` (its
//! `offset`, `max_distance`, `falloff`) and `shadow` (its `offset`, `lights`). Anything else is
//! refused by name: a reflection needs a surface per ray, which a cone does not give; a distance
//! falloff weighs each ray's hit distance, which the closest approach does not give.

use crate::experiment::kinds::Kind;
use crate::render::ao::Falloff;
use crate::render::estimator::{Estimator, Points};
use crate::render::shadow::SphereLight;
use crate::render::truth::{Truth, TruthOptions};
use crate::sampling::rays::RaySet;
use crate::sdf::{ConeLight, ConeSet, ConeTrace, SdfScene};
use crate::visibility::Visibility;
use rayon::prelude::*;

/// The kinds the cones answer: the AO kinds and shadows.
pub(super) const AO_KINDS: [&str; 2] = ["vertex_ao", "image_ao"];
const LIGHT_KINDS: [&str; 1] = ["shadows"];

/// Why the cones cannot answer `kind`, or none.
pub(super) fn refusal(kind: &dyn Kind) -> Option<String> {
    let name = kind.name();
    if AO_KINDS.contains(&name) {
        let falloff = kind.render().options.to_json().get("falloff").cloned();
        if falloff.is_some_and(|f| f != serde_json::json!("step")) {
            return Some(
                "query \"cone\" answers binary AO (falloff \"step\"): the closest approach \
                 gives no hit distance to weigh"
                    .into(),
            );
        }
        return None;
    }
    if LIGHT_KINDS.contains(&name) {
        return None;
    }
    Some(format!(
        "query \"cone\" answers ambient occlusion ({}) and soft shadows ({}) only, not \
         \"{name}\" (a cone gives no surface per ray); use query \"trace\"",
        AO_KINDS.join(", "),
        LIGHT_KINDS.join(", ")
    ))
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
    let key = est.key();
    let field = |k: &str| {
        key.get(k).cloned().ok_or_else(|| {
            format!(
                "query \"cone\": estimator \"{}\" has no `{k}` in its key",
                est.name()
            )
        })
    };
    let offset = |v: serde_json::Value| {
        v.as_f64()
            .map(|x| x as f32)
            .ok_or_else(|| format!("query \"cone\": `offset` {v} is not a number"))
    };
    match est.name() {
        "ao" => {
            let falloff: Falloff = serde_json::from_value(field("falloff")?)
                .map_err(|e| format!("query \"cone\": `falloff`: {e}"))?;
            if falloff != Falloff::Step {
                return Err("query \"cone\" answers binary AO (falloff \"step\") only".to_string());
            }
            let tmax: Option<f32> = serde_json::from_value(field("max_distance")?)
                .map_err(|e| format!("query \"cone\": `max_distance`: {e}"))?;
            Ok(Quantity::Ao {
                offset: offset(field("offset")?)?,
                tmax: tmax.unwrap_or(f32::INFINITY),
            })
        }
        "shadow" => {
            let lights: Vec<SphereLight> = serde_json::from_value(field("lights")?)
                .map_err(|e| format!("query \"cone\": `lights`: {e}"))?;
            Ok(Quantity::Light {
                offset: offset(field("offset")?)?,
                lights: lights
                    .iter()
                    .map(|l| ConeLight {
                        center: l.center,
                        radius: l.radius,
                        intensity: l.intensity,
                    })
                    .collect(),
            })
        }
        other => Err(format!(
            "query \"cone\" answers the estimators \"ao\" and \"shadow\", not \"{other}\""
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
