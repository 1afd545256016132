//! Point sets on the unit sphere: where a field's positional samples (maps) sit.

use super::SamplingError;
use glam::Vec3;

/// Which point set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SphereKind {
    /// Slater's hemisphere triangle subdivision (2008 paper): 2(2n²+2n+1) points.
    Slater,
    /// Latitude–longitude grid.
    LatLong,
    /// Spherical Fibonacci (Keinert et al. 2015).
    Fibonacci,
}

/// A point set on the unit sphere with exact nearest-point and interpolation queries.
#[derive(Clone, Debug)]
pub struct SpherePoints {
    pub kind: SphereKind,
    points: Vec<Vec3>,
}

impl SpherePoints {
    /// Builds `count` points of `kind`; an error lists valid counts when `count` is impossible.
    pub fn new(kind: SphereKind, count: usize) -> Result<Self, SamplingError> {
        let _ = (kind, count);
        todo!("sampling helper")
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Unit point `i`.
    pub fn point(&self, i: usize) -> Vec3 {
        self.points[i]
    }

    /// Index of the point nearest to unit direction `d` (largest dot product).
    pub fn nearest(&self, d: Vec3) -> usize {
        let _ = d;
        todo!("sampling helper")
    }

    /// Three points around `d` and barycentric weights (non-negative, summing to 1).
    pub fn surrounding(&self, d: Vec3) -> ([usize; 3], [f32; 3]) {
        let _ = d;
        todo!("sampling helper")
    }
}
