//! Cells, the unit every table row, threshold and shard is about: a field on a scene, read
//! with a selection, on a backend ([`Cell`]); a spec profile's cells in plan order
//! ([`cells_of`]: scenes × field settings × backends, × the normal field precisions of a kind
//! that reads them); the field geometry cells share a bake by ([`Geometry`]). A threshold and a
//! paper cell say which cells they are about by their axes
//! ([`super::spec::Threshold::matches`]).

use super::spec::{Backend, Spec};
use crate::field::{FieldParams, Precision, Selection};
use crate::sampling::{LayoutKind, SphereKind};
use std::collections::HashSet;

/// One evaluated setting: a field on a scene, read with a selection, on a backend (and, for a
/// kind that reads normal fields, at a normal field precision).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Cell {
    /// Index into the profile's scenes.
    pub scene: usize,
    pub params: FieldParams,
    pub selection: Selection,
    pub backend: Backend,
    /// Bits per component of the normal field read (none: the kind reads no normals).
    pub normal_bits: Option<u32>,
}

impl Cell {
    /// A file-name-safe id: `scene-sphere-count-layout-res-precision-selection-backend`, with
    /// `-n8` / `-n16` after it where the cell reads a normal field.
    pub fn id(&self, scene_name: &str) -> String {
        let p = &self.params;
        let normals = self.normal_bits.map_or(String::new(), |b| format!("-n{b}"));
        format!(
            "{scene_name}-{}-{}-{}-{}-{}-{}-{}{normals}",
            p.sphere.name(),
            p.count,
            p.layout.name(),
            p.res,
            p.precision.name(),
            selection_name(self.selection),
            self.backend.name()
        )
    }

    /// The field geometry (everything but the precision).
    pub fn geometry(&self) -> Geometry {
        Geometry::of(&self.params)
    }
}

/// The snake-case name of a selection.
pub fn selection_name(s: Selection) -> &'static str {
    match s {
        Selection::Nearest => "nearest",
        Selection::Interpolated => "interpolated",
    }
}

/// A field's parameters without its precision: what one bake of f32 distances determines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Geometry {
    pub sphere: SphereKind,
    pub count: usize,
    pub layout: LayoutKind,
    pub res: u32,
}

impl Geometry {
    pub fn of(p: &FieldParams) -> Geometry {
        Geometry {
            sphere: p.sphere,
            count: p.count,
            layout: p.layout,
            res: p.res,
        }
    }

    pub fn with(&self, precision: Precision) -> FieldParams {
        FieldParams {
            sphere: self.sphere,
            count: self.count,
            layout: self.layout,
            res: self.res,
            precision,
        }
    }
}

/// The cells of a spec profile: scenes × field settings × backends (× the normal field
/// precisions of a kind that reads them), duplicates dropped, in spec order.
pub fn cells_of(spec: &Spec) -> Vec<Cell> {
    let bits = super::kinds::of(&spec.render).normal_bits();
    let normal_bits: Vec<Option<u32>> = if bits.is_empty() {
        vec![None]
    } else {
        bits.into_iter().map(Some).collect()
    };
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for scene in 0..spec.scenes.len() {
        for axes in &spec.fields {
            for (params, selection) in axes.settings() {
                for &backend in &spec.backends {
                    for &nb in &normal_bits {
                        let c = Cell {
                            scene,
                            params,
                            selection,
                            backend,
                            normal_bits: nb,
                        };
                        if seen.insert(c) {
                            out.push(c);
                        }
                    }
                }
            }
        }
    }
    out
}
