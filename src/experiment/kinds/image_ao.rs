//! `"image_ao"` (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG 2010): AO at the surface
//! point of every pixel that sees a receiver (image-space AO); needs `image`.

use super::ao::{AoKindOptions, AoPoints};
use super::{read_as, Columns, KindEntry, Needs};
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::RenderSpec;
use crate::render::points::{EvalPoints, GBuffer};

/// The registry's line for this kind.
pub const ENTRY: KindEntry = KindEntry {
    name: Pixels::NAME,
    about: "AO at every receiver pixel of the image (2010)",
    read: read_as::<AoKindOptions<Pixels>>,
};

/// The receiver pixels of the spec's image (its G-buffer).
#[derive(Clone, Debug)]
pub struct Pixels;

impl AoPoints for Pixels {
    const NAME: &'static str = "image_ao";

    fn needs() -> Needs {
        Needs {
            view: true,
            ..Needs::default()
        }
    }

    fn columns() -> Columns {
        Columns { vertex: false }
    }

    fn max_points(render: &RenderSpec, _scene: &BuiltScene) -> u64 {
        super::pixels(render.image.as_ref())
    }

    fn points(scene: &BuiltScene, view: Option<&GBuffer>) -> EvalPoints {
        let view = view.expect("image_ao: validation guarantees an image, and so a G-buffer");
        EvalPoints::pixels(&scene.scene, view)
    }
}
