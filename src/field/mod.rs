//! Visibility ("displacement") fields: Gaitatzes, Chrysanthou, Papaioannou, "Presampled
//! Visibility for Ambient Occlusion", WSCG 2008 (Algorithms 1–2), and Gaitatzes et al., "Fast
//! Approximate Visibility on the GPU using Precomputed 4D Visibility Fields", WSCG 2010 (§3).
//!
//! Around a rigid object with minimal bounding sphere (c, R), a field holds one directional map
//! per positional sample p on the sphere. Map texel t of the map at p stores the distance from p
//! to the first hit along the inward direction of t, divided by 2R; a miss stores 1 (= 2R).
//!
//! - [`bake`]: Algorithm 1, parallel over maps.
//! - [`storage`]: f32 / u16 / u8 / 1-bit precisions.
//! - [`lookup`]: Algorithm 2 (inter-object) and the 2010 intra-object test, nearest or
//!   interpolated map selection.
//! - [`normals`]: normal fields for reflections (2010 §4.2).
//! - [`cache`]: the versioned on-disk cache.
//! - [`scene`]: several instanced fields answering one [`crate::visibility::Visibility`].

pub mod bake;
pub mod cache;
pub mod lanes;
pub mod lookup;
pub mod normals;
pub mod scene;
pub mod sphere_bvh;
pub mod storage;
mod surface_batch;

use crate::geometry::Sphere;
use crate::sampling::{Frame, HemisphereLayout, LayoutKind, SphereKind, SpherePoints, TexelTable};
pub use storage::{Precision, Storage};

/// Errors from building, loading or sizing a field.
#[derive(Debug, thiserror::Error)]
pub enum FieldError {
    #[error("{0}")]
    Sampling(#[from] crate::sampling::SamplingError),
    #[error(
        "a field of {maps} maps × {res}² texels at {precision:?} needs {need} but the memory \
         limit is {limit} (raise it with --max-memory-mib, or lower the counts)"
    )]
    TooLarge {
        maps: usize,
        res: u32,
        precision: Precision,
        need: ByteSize,
        limit: ByteSize,
    },
    #[error("invalid field parameters: {0}")]
    Invalid(String),
}

/// A byte count printed with a binary unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct ByteSize(pub u64);

impl std::fmt::Display for ByteSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let b = self.0 as f64;
        let (v, u) = if b >= (1u64 << 30) as f64 {
            (b / (1u64 << 30) as f64, "GiB")
        } else if b >= (1u64 << 20) as f64 {
            (b / (1u64 << 20) as f64, "MiB")
        } else if b >= 1024.0 {
            (b / 1024.0, "KiB")
        } else {
            return write!(f, "{} B", self.0);
        };
        write!(f, "{v:.2} {u}")
    }
}

/// How maps are chosen at lookup time.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Selection {
    /// The map of the nearest positional sample and the texel containing the direction (the
    /// papers' method).
    #[default]
    Nearest,
    /// Beyond the papers: the three surrounding maps blended with barycentric weights, each read
    /// bilinearly.
    Interpolated,
}

/// The axes that define a field (everything but the mesh).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct FieldParams {
    /// Positional sample set on the bounding sphere.
    pub sphere: SphereKind,
    /// Number of positional samples (maps).
    pub count: usize,
    /// Directional map layout.
    pub layout: LayoutKind,
    /// Directional map resolution (res × res texels).
    pub res: u32,
    /// Stored precision.
    pub precision: Precision,
}

impl FieldParams {
    /// Bytes the stored distances take: maps × texels × bits / 8, plus the 1-bit variant's
    /// per-map mean distances.
    pub fn storage_bytes(&self) -> u64 {
        storage::storage_bytes(self.precision, self.count, self.texels())
    }

    /// Texels per map.
    pub fn texels(&self) -> usize {
        (self.res as usize) * (self.res as usize)
    }

    /// Refuses, before any allocation, a field whose storage would pass `limit` bytes.
    pub fn check_memory(&self, limit: u64) -> Result<(), FieldError> {
        let need = self.storage_bytes();
        if need > limit {
            return Err(FieldError::TooLarge {
                maps: self.count,
                res: self.res,
                precision: self.precision,
                need: ByteSize(need),
                limit: ByteSize(limit),
            });
        }
        Ok(())
    }
}

/// Half of the machine's physical memory (`MemTotal` in /proc/meminfo), the default limit for
/// a field's size; 8 GiB where it cannot be read.
pub fn default_memory_limit() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("MemTotal:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map(|kb| kb * 1024 / 2)
        .unwrap_or(8 << 30)
}

/// A baked visibility field in the object's model space.
#[derive(Clone, Debug)]
pub struct VisibilityField {
    pub params: FieldParams,
    /// The object's minimal bounding sphere (model space).
    pub bounds: Sphere,
    pub points: SpherePoints,
    pub layout: HemisphereLayout,
    /// `layout`'s texel table ([`TexelTable::new`]`(layout)`): most nearest lookups' texel in
    /// one read, the same texel as `layout.to_texel`.
    pub texels: TexelTable,
    /// Per map: frame whose z is the inward normal −point(i).
    pub frames: Vec<Frame>,
    pub storage: Storage,
    /// The discretisation scales of the intra-object test's tolerance
    /// ([`IntraTolerance`]), derived from the sphere set and the layout.
    pub intra: IntraTolerance,
}

/// How far a self-hit read from the field can land from the surface the origin lies on, per
/// field: the intra-object test (2010 Figure 2) accepts an occluder only beyond
/// `positional + directional · d1` from the origin (model units; `d1` = distance from the origin
/// to the exit point p1), scaled by the lookup's
/// [`IntraBias::Auto`](lookup::IntraBias::Auto) factor.
///
/// The stored d2 is measured from the map's sample point, up to the set's covering radius away
/// from p1 (a lateral error of `positional` = covering angle × R), along the texel's central
/// direction, up to half a texel away from p1→p0 (a lateral error growing with the distance
/// travelled, `directional` = half the mean texel width in radians), plus half a storage step.
/// Deviation from the paper: the 2010 paper compares d1 > d2 without a tolerance; on the objects
/// of figure8 that test marks most self-rays occluded. `examples/intra_bias.rs` measures the
/// error against the tolerance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntraTolerance {
    /// Model units: the sphere set's covering angle × R.
    pub covering: f32,
    /// Radians: half the mean texel width, √(2π / used texels) / 2.
    pub directional: f32,
    /// Model units: half a storage step of 2R (0 for f32 and 1 bit).
    pub quantisation: f32,
}

impl IntraTolerance {
    /// The tolerance of a field with these parts.
    pub fn of(
        points: &SpherePoints,
        layout: &HemisphereLayout,
        precision: storage::Precision,
        radius: f32,
    ) -> Result<Self, FieldError> {
        let gap = points.spacing()?.max_gap;
        let texel = (2.0 * std::f64::consts::PI / layout.used_count() as f64).sqrt();
        Ok(IntraTolerance {
            covering: (gap * radius as f64) as f32,
            directional: (0.5 * texel) as f32,
            quantisation: 0.0,
        }
        .with_precision(precision, radius))
    }

    /// The same tolerance for the field stored at `precision`.
    pub fn with_precision(self, precision: storage::Precision, radius: f32) -> Self {
        let half_step = match precision {
            storage::Precision::U8 => 0.5 / 255.0,
            storage::Precision::U16 => 0.5 / 65535.0,
            storage::Precision::F32 | storage::Precision::Bit1 => 0.0,
        };
        IntraTolerance {
            quantisation: (half_step * 2.0 * radius as f64) as f32,
            ..self
        }
    }

    /// The positional part in model units (covering + quantisation).
    #[inline]
    pub fn positional(&self) -> f32 {
        self.covering + self.quantisation
    }
}

impl VisibilityField {
    /// Assembles a field from its parts, building the sphere set and frames.
    pub fn from_storage(
        params: FieldParams,
        bounds: Sphere,
        storage: Storage,
    ) -> Result<Self, FieldError> {
        let points = SpherePoints::new(params.sphere, params.count)?;
        let layout = HemisphereLayout::new(params.layout, params.res);
        if storage.maps() != params.count || storage.texels() != params.texels() {
            return Err(FieldError::Invalid(format!(
                "storage holds {} maps × {} texels, parameters say {} × {}",
                storage.maps(),
                storage.texels(),
                params.count,
                params.texels()
            )));
        }
        let frames = frames_for(&points);
        let intra = IntraTolerance::of(&points, &layout, params.precision, bounds.radius)?;
        Ok(VisibilityField {
            params,
            bounds,
            points,
            layout,
            texels: TexelTable::new(layout),
            frames,
            storage,
            intra,
        })
    }

    /// Checks the invariants of a baked field: every stored distance in [0, 1], finite.
    pub fn validate(&self) -> Result<(), FieldError> {
        self.storage.validate().map_err(FieldError::Invalid)
    }

    /// Bytes of stored data (the papers' storage figure).
    pub fn bytes(&self) -> u64 {
        self.params.storage_bytes()
    }
}

/// The inward frame of every map: z = −point(i).
pub fn frames_for(points: &SpherePoints) -> Vec<Frame> {
    (0..points.len())
        .map(|i| Frame::from_normal(-points.point(i)))
        .collect()
}

/// A field of 290 Slater maps of 8² concentric f32 texels around `bounds`, every texel storing
/// the normalised distance `d` (1 = miss): for tests whose answers follow from the sphere alone.
#[cfg(test)]
pub(crate) fn constant_field(d: f32, bounds: crate::geometry::Sphere) -> VisibilityField {
    let params = FieldParams {
        sphere: crate::sampling::SphereKind::Slater,
        count: 290,
        layout: crate::sampling::LayoutKind::Concentric,
        res: 8,
        precision: Precision::F32,
    };
    let storage = Storage::F32 {
        texels: 64,
        data: vec![d; 290 * 64],
    };
    VisibilityField::from_storage(params, bounds, storage).unwrap()
}
