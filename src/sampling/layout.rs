//! Hemisphere layouts of a directional map: polar, rejection (Malley) and concentric (Malley).

use glam::Vec3;

/// How a square map of `res × res` texels covers the hemisphere `z >= 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LayoutKind {
    /// Uniform in θ (rows) and φ (columns).
    Polar,
    /// Square → disk by rejection (texels outside the inscribed disk unused), then Malley.
    Rejection,
    /// Shirley–Chiu concentric square → disk, then Malley.
    Concentric,
}

/// A directional map layout at a resolution. Texel index = row · res + column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct HemisphereLayout {
    pub kind: LayoutKind,
    pub res: u32,
}

impl HemisphereLayout {
    pub fn new(kind: LayoutKind, res: u32) -> Self {
        HemisphereLayout { kind, res }
    }

    pub fn texel_count(&self) -> usize {
        (self.res as usize) * (self.res as usize)
    }

    /// Direction (local frame, unit, z >= 0) through the centre of texel `t`; `None` when the
    /// texel is unused by this layout.
    pub fn to_direction(&self, t: u32) -> Option<Vec3> {
        let _ = t;
        todo!("sampling helper")
    }

    /// The texel containing local direction `d` (unit; z < 0 is clamped to the horizon).
    pub fn to_texel(&self, d: Vec3) -> u32 {
        let _ = d;
        todo!("sampling helper")
    }
}
