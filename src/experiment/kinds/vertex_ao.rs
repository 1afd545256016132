//! `"vertex_ao"`, the default kind (Gaitatzes, Chrysanthou, Papaioannou, WSCG 2008): AO at the
//! receivers' vertices, shown Gouraud-interpolated in the image.

use super::ao::{AoKindOptions, AoPoints};
use super::{read_as, Columns, KindEntry, Needs};
use crate::experiment::scenes::BuiltScene;
use crate::experiment::spec::RenderSpec;
use crate::render::points::{EvalPoints, GBuffer};

/// The registry's line for this kind.
pub const ENTRY: KindEntry = KindEntry {
    name: Vertices::NAME,
    about: "AO at the receivers' vertices (2008; the default)",
    read: read_as::<AoKindOptions<Vertices>>,
};

/// The receivers' vertices.
#[derive(Clone, Debug)]
pub struct Vertices;

impl AoPoints for Vertices {
    const NAME: &'static str = "vertex_ao";

    fn needs() -> Needs {
        Needs::default()
    }

    fn columns() -> Columns {
        Columns { vertex: true }
    }

    fn max_points(_render: &RenderSpec, scene: &BuiltScene) -> u64 {
        scene.receiver_vertices() as u64
    }

    fn points(scene: &BuiltScene, _view: Option<&GBuffer>) -> EvalPoints {
        EvalPoints::vertices(&scene.scene)
    }
}
