//! `{"method": "sdf", "res": [32, 64]}`: mesh signed distance fields (`sdf`), one volume per
//! caster mesh baked in model space and instanced with the caster's transform, as engines keep
//! them, answering the kind's rays by sphere tracing. Its precompute is the bakes (timed, not
//! cached); its bytes the volumes'. Keys: `res`, samples along each mesh box's longest side
//! (an axis: one row per value, 8–256); `margin`, voxels of padding around the box (default 2);
//! `hit_voxels`, the hit threshold in voxels (default 0.25).

use super::{Answer, Method, MethodContext, MethodEntry, MethodOptions, Prepared};
use crate::experiment::spec::{Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::experiment::{Error, Result};
use crate::sdf::{DistanceVolume, SdfInstance, SdfScene, SdfTrace};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

pub const ENTRY: MethodEntry = MethodEntry {
    name: "sdf",
    about: "mesh signed distance fields, sphere traced (one volume per caster mesh, instanced)",
    read: super::read_as::<SdfOptions>,
};

/// The largest `res` a spec may ask for (256³ f32 samples: 64 MiB per mesh).
const MAX_RES: usize = 256;

/// `sdf`'s keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SdfOptions {
    /// Samples along each mesh box's longest side; one setting per value.
    pub res: Vec<usize>,
    #[serde(default = "default_margin")]
    pub margin: usize,
    #[serde(default = "default_hit_voxels")]
    pub hit_voxels: f32,
}

fn default_margin() -> usize {
    2
}

fn default_hit_voxels() -> f32 {
    SdfTrace::default().hit_voxels
}

impl MethodOptions for SdfOptions {
    fn validate(&self, at: &str, _spec: &Spec, v: &Validator) -> Result<(), SpecError> {
        if self.res.is_empty() {
            return Err(v.err(&format!("{at}.res"), "needs at least one value".into()));
        }
        for (i, &r) in self.res.iter().enumerate() {
            if !(8..=MAX_RES).contains(&r) {
                return Err(v.err(
                    &format!("{at}.res[{i}]"),
                    format!("{r} is outside 8..={MAX_RES}"),
                ));
            }
            if self.margin >= r / 4 {
                return Err(v.err(
                    &format!("{at}.margin"),
                    format!("{} voxels is not below a quarter of res {r}", self.margin),
                ));
            }
        }
        if !(self.hit_voxels.is_finite() && self.hit_voxels > 0.0 && self.hit_voxels <= 2.0) {
            return Err(v.err(
                &format!("{at}.hit_voxels"),
                format!("{} is not in (0, 2]", self.hit_voxels),
            ));
        }
        Ok(())
    }

    fn settings(&self) -> Vec<Box<dyn Method>> {
        self.res
            .iter()
            .map(|&res| {
                Box::new(Sdf {
                    res,
                    margin: self.margin,
                    trace: SdfTrace {
                        hit_voxels: self.hit_voxels,
                        ..SdfTrace::default()
                    },
                }) as Box<dyn Method>
            })
            .collect()
    }
}

/// One resolution's volumes.
pub struct Sdf {
    res: usize,
    margin: usize,
    trace: SdfTrace,
}

impl Method for Sdf {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn params(&self) -> Vec<(&'static str, String)> {
        vec![("res", self.res.to_string())]
    }

    fn prepare(&self, ctx: &MethodContext) -> Result<Prepared> {
        let scene = ctx.scene;
        let most = (self.res as u64).pow(3) * 4;
        if most > ctx.memory_limit {
            return Err(Error::invalid(
                format!("scene {}: method \"sdf\" (res {})", scene.name, self.res),
                format!(
                    "a volume may take {most} bytes, above the run's memory limit of {}",
                    ctx.memory_limit
                ),
            ));
        }
        // One volume per mesh, shared by its instances.
        let mut volumes: Vec<(usize, Arc<DistanceVolume>)> = Vec::new();
        let mut instances = Vec::new();
        for (i, inst) in scene.scene.casters() {
            let mesh = scene.mesh_of[i];
            let volume = match volumes.iter().find(|(m, _)| *m == mesh) {
                Some((_, v)) => v.clone(),
                None => {
                    let tris: Vec<_> = (0..inst.mesh.triangle_count())
                        .map(|t| inst.mesh.triangle(t))
                        .collect();
                    let v = DistanceVolume::bake(&tris, self.res, self.margin).map_err(|e| {
                        Error::invalid(
                            format!("scene {}: method \"sdf\" (res {})", scene.name, self.res),
                            e.to_string(),
                        )
                    })?;
                    let v = Arc::new(v);
                    volumes.push((mesh, v.clone()));
                    v
                }
            };
            instances.push(SdfInstance {
                volume,
                transform: inst.transform,
            });
        }
        Ok(Prepared {
            bytes: Some(volumes.iter().map(|(_, v)| v.bytes()).sum()),
            cached: false,
            columns: Vec::new(),
            answer: Answer::Rays(Box::new(SdfScene {
                instances,
                trace: self.trace,
            })),
        })
    }
}
