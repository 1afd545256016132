//! The on-disk cache of distance volumes, like the field's (`field::cache`).
//!
//! A volume is keyed by the mesh's sha256 (model-space positions and triangles), the
//! resolution, the margin, the precision and the code and format version ([`CacheKey`]); the
//! file name carries the first 16 hex digits of the key's sha256. A file holds
//!
//! ```text
//! magic    8 bytes  "VSDFCACH"
//! version  u32 LE   FORMAT_VERSION
//! hlen     u32 LE   length of the JSON header
//! header   hlen bytes of JSON (the key, the grid: lo, voxel, dims; payload length and sha256)
//! payload  the stored samples, little-endian, x fastest
//! ```
//!
//! written atomically (`io::write_atomic`). A truncated file, a bad magic, another format
//! version, another key, a payload whose length or sha256 differs, or a grid that does not
//! hold the payload is reported and never trusted: [`load_or_bake`] rebakes and overwrites it.
//! A precision below f32 is derived from the f32 volume (itself cached), so a sweep of
//! precisions bakes once.

use super::storage::{Precision, Samples};
use super::{DistanceVolume, SdfError};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"VSDFCACH";
/// Bumped whenever the payload layout or the bake's meaning changes.
pub const FORMAT_VERSION: u32 = 1;

/// What identifies a baked volume.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CacheKey {
    pub mesh_sha256: String,
    pub res: usize,
    pub margin: usize,
    pub precision: Precision,
    /// Crate version and format version; a new release invalidates old caches.
    pub code_version: String,
}

impl CacheKey {
    pub fn new(mesh_sha256: &str, res: usize, margin: usize, precision: Precision) -> CacheKey {
        CacheKey {
            mesh_sha256: mesh_sha256.to_string(),
            res,
            margin,
            precision,
            code_version: format!("{}+s{}", env!("CARGO_PKG_VERSION"), FORMAT_VERSION),
        }
    }

    /// File name: the readable axes, then a short hash of the whole key.
    pub fn file_name(&self) -> String {
        let json = serde_json::to_vec(self).expect("key serialises");
        let h = crate::io::sha256_hex(&json);
        format!(
            "sdf-{}-m{}-{}-{}.vsdf",
            self.res,
            self.margin,
            self.precision.name(),
            &h[..16]
        )
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct CacheHeader {
    key: CacheKey,
    lo: [f32; 3],
    voxel: f32,
    dims: [usize; 3],
    payload_len: u64,
    payload_sha256: String,
}

pub use crate::io::CacheError;

/// Writes `volume` under `key` to `path`, atomically.
///
/// # Panics
/// If the volume's precision is not the key's (a caller's bug).
pub fn save(path: &Path, key: &CacheKey, volume: &DistanceVolume) -> Result<(), CacheError> {
    assert_eq!(
        volume.precision(),
        key.precision,
        "the volume is not the key's"
    );
    let payload = volume.samples.to_bytes();
    let header = CacheHeader {
        key: key.clone(),
        lo: volume.lo.to_array(),
        voxel: volume.voxel,
        dims: volume.dims,
        payload_len: payload.len() as u64,
        payload_sha256: crate::io::sha256_hex(&payload),
    };
    crate::io::write_cache(path, MAGIC, FORMAT_VERSION, &header, &payload)
}

/// Reads a volume saved under `key`: magic, version, key, length, checksum and grid checked.
pub fn load(path: &Path, key: &CacheKey) -> Result<DistanceVolume, CacheError> {
    let file: crate::io::CacheFile<CacheHeader> =
        crate::io::read_cache(path, MAGIC, FORMAT_VERSION, "visfield SDF cache")?;
    let header = &file.header;
    if header.key != *key {
        return Err(
            file.stale("the key (mesh, resolution, margin, precision or code version) differs")
        );
    }
    let payload = file.payload(header.payload_len, &header.payload_sha256)?;
    let corrupt = |reason: String| file.corrupt(reason);
    let lo = Vec3::from_array(header.lo);
    let max = DistanceVolume::MAX_RES;
    if !(lo.is_finite() && header.voxel.is_finite() && header.voxel > 0.0)
        || header.dims.iter().any(|&n| !(2..=max).contains(&n))
    {
        return Err(corrupt(format!(
            "an impossible grid (lo {lo}, voxel {}, dims {:?})",
            header.voxel, header.dims
        )));
    }
    let count: usize = header.dims.iter().product();
    if count * key.precision.bytes_per_sample() != payload.len() {
        return Err(corrupt(format!(
            "{} payload bytes do not hold {:?} samples at {}",
            payload.len(),
            header.dims,
            key.precision.name()
        )));
    }
    let samples = Samples::from_bytes(payload, key.precision, header.voxel)
        .ok_or_else(|| corrupt("a sample is not a finite distance".into()))?;
    Ok(DistanceVolume {
        lo,
        voxel: header.voxel,
        dims: header.dims,
        samples,
    })
}

/// How a volume was obtained.
#[derive(Debug, PartialEq)]
pub enum Outcome {
    /// Read from a valid cache file at its precision.
    Hit(PathBuf),
    /// Derived from the cached f32 volume (no bake), then saved; the file at its precision,
    /// if one was met, was rejected for the reasons given.
    Derived {
        path: PathBuf,
        rejected: Vec<String>,
    },
    /// Baked (no file, or each file met was rejected for the reasons given), then saved.
    Baked {
        path: PathBuf,
        rejected: Vec<String>,
    },
}

impl Outcome {
    /// Whether no bake ran.
    pub fn cached(&self) -> bool {
        !matches!(self, Outcome::Baked { .. })
    }

    /// The files met and rejected on the way (none on a hit).
    pub fn rejected(&self) -> &[String] {
        match self {
            Outcome::Hit(_) => &[],
            Outcome::Derived { rejected, .. } | Outcome::Baked { rejected, .. } => rejected,
        }
    }
}

/// [`load_or_bake`] where there is a cache folder; without one, the volume baked (and stored
/// at `precision`), with no outcome.
pub fn load_or_bake_in(
    dir: Option<&Path>,
    triangles: &[[Vec3; 3]],
    mesh_sha256: &str,
    (res, margin): (usize, usize),
    precision: Precision,
) -> Result<(DistanceVolume, Option<Outcome>), SdfError> {
    match dir {
        Some(dir) => load_or_bake(dir, triangles, mesh_sha256, (res, margin), precision)
            .map(|(v, outcome)| (v, Some(outcome))),
        None => Ok((
            DistanceVolume::bake(triangles, res, margin)?.with_precision(precision),
            None,
        )),
    }
}

/// Loads the volume of (`triangles`, sha256 `mesh_sha256`, `res`, `margin`, `precision`) from
/// `dir`, or bakes and caches it (a lower precision from the f32 volume, cached too). A
/// rejected file is reported in the outcome and replaced; a file that cannot be written is
/// an error.
pub fn load_or_bake(
    dir: &Path,
    triangles: &[[Vec3; 3]],
    mesh_sha256: &str,
    (res, margin): (usize, usize),
    precision: Precision,
) -> Result<(DistanceVolume, Outcome), SdfError> {
    let mut rejected = Vec::new();
    let try_load = |key: &CacheKey, rejected: &mut Vec<String>| {
        let path = dir.join(key.file_name());
        if !path.exists() {
            return None;
        }
        load(&path, key)
            .inspect_err(|e| rejected.push(e.to_string()))
            .ok()
    };
    let key = CacheKey::new(mesh_sha256, res, margin, precision);
    let path = dir.join(key.file_name());
    if let Some(v) = try_load(&key, &mut rejected) {
        return Ok((v, Outcome::Hit(path)));
    }
    let save_to = |key: &CacheKey, v: &DistanceVolume| {
        save(&dir.join(key.file_name()), key, v).map_err(|e| SdfError::Invalid(e.to_string()))
    };
    let f32_key = CacheKey::new(mesh_sha256, res, margin, Precision::F32);
    let (f32_volume, baked) = match (precision != Precision::F32)
        .then(|| try_load(&f32_key, &mut rejected))
        .flatten()
    {
        Some(v) => (v, false),
        None => {
            let v = DistanceVolume::bake(triangles, res, margin)?;
            save_to(&f32_key, &v)?;
            (v, true)
        }
    };
    let volume = f32_volume.with_precision(precision);
    if precision != Precision::F32 {
        save_to(&key, &volume)?;
    }
    let outcome = if baked {
        Outcome::Baked { path, rejected }
    } else {
        Outcome::Derived { path, rejected }
    };
    Ok((volume, outcome))
}
