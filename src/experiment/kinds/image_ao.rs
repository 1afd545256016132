//! `"image_ao"` (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010): AO at the surface
//! point of every pixel that sees a receiver (image-space AO); needs `image`.

use super::ao::AoRender;
use super::{read_as, to_json_of, Columns, Kind, KindEntry, KindOptions, Needs, Setup};
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::{RenderSpec, Spec, SpecError};
use crate::experiment::validate::Validator;
use crate::render::points::{EvalPoints, GBuffer};
use serde::{Deserialize, Serialize};

/// The registry's line for this kind.
pub const ENTRY: KindEntry = KindEntry {
    name: "image_ao",
    about: "AO at every receiver pixel of the image (2010)",
    read: read_as::<ImageAoOptions>,
};

/// The options of `"image_ao"`: the AO kinds' ([`AoRender`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct ImageAoOptions(pub AoRender);

impl KindOptions for ImageAoOptions {
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
        Box::new(ImageAo {
            render: render.clone(),
            ao: self.0.clone(),
        })
    }
}

/// Per-pixel AO on one spec's `render`.
pub struct ImageAo {
    render: RenderSpec,
    ao: AoRender,
}

impl Kind for ImageAo {
    fn name(&self) -> &'static str {
        ENTRY.name
    }

    fn render(&self) -> &RenderSpec {
        &self.render
    }

    fn needs(&self) -> Needs {
        Needs {
            view: true,
            ..Needs::default()
        }
    }

    fn columns(&self) -> Columns {
        Columns { vertex: false }
    }

    fn max_points(&self, _scene: &BuiltScene) -> u64 {
        super::pixels(self.render.image.as_ref())
    }

    fn setup(&self, scene: &BuiltScene, view: Option<&GBuffer>) -> Setup {
        let view = view.expect("image_ao: validation guarantees an image, and so a G-buffer");
        let points = EvalPoints::pixels(&scene.scene, view);
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
