//! `"vertex_ao"`, the default kind (Gaitatzes, Chrysanthou, Papaioannou, WSCG 2008): AO at the
//! receivers' vertices, shown Gouraud-interpolated in the image.

use super::ao::AoRender;
use super::{read_as, to_json_of, Columns, Kind, KindEntry, KindOptions, Needs, Setup};
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::{RenderSpec, Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::render::points::{EvalPoints, GBuffer};
use serde::{Deserialize, Serialize};

/// The registry's line for this kind.
pub const ENTRY: KindEntry = KindEntry {
    name: "vertex_ao",
    about: "AO at the receivers' vertices (2008; the default)",
    read: read_as::<VertexAoOptions>,
};

/// The options of `"vertex_ao"`: the AO kinds' ([`AoRender`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct VertexAoOptions(pub AoRender);

impl KindOptions for VertexAoOptions {
    fn to_json(&self) -> serde_json::Map<String, serde_json::Value> {
        to_json_of(self)
    }

    fn clone_box(&self) -> Box<dyn KindOptions> {
        Box::new(self.clone())
    }

    fn validate(&self, _render: &RenderSpec, spec: &Spec, v: &Validator) -> Result<(), SpecError> {
        self.0.validate(spec, v)
    }

    fn kind(&self, render: &RenderSpec) -> Box<dyn Kind> {
        Box::new(VertexAo {
            render: render.clone(),
            ao: self.0.clone(),
        })
    }
}

/// Vertex AO on one spec's `render`.
pub struct VertexAo {
    render: RenderSpec,
    ao: AoRender,
}

impl Kind for VertexAo {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn render(&self) -> &RenderSpec {
        &self.render
    }

    fn needs(&self) -> Needs {
        Needs::default()
    }

    fn columns(&self) -> Columns {
        Columns { vertex: true }
    }

    fn max_points(&self, scene: &BuiltScene) -> u64 {
        scene.receiver_vertices() as u64
    }

    fn setup(&self, scene: &BuiltScene, _view: Option<&GBuffer>) -> Setup {
        let points = EvalPoints::vertices(&scene.scene);
        Setup {
            offset: points.max_offset(),
            points,
            estimator: Box::new(self.ao.estimator()),
            gpu: Some(self.ao.gpu()),
            shading: None,
            second_reference: None,
        }
    }
}
