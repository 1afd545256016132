//! The on-disk cache of fitted AO fields, keyed by (mesh sha256, [`BakeParams`], code and format
//! version), in the caches' container ([`crate::io::write_cache`]):
//!
//! ```text
//! magic    8 bytes  "VFAOFLD1"
//! version  u32 LE   FORMAT_VERSION
//! hlen     u32 LE   length of the JSON header
//! header   JSON: key, bounds, payload length and sha256
//! payload  the f32 channels of every texel, little-endian (7 per texel)
//! ```
//!
//! The fit is cached in f32 and stored at a precision on load, so one bake serves every
//! precision. A truncated file, another version or key, or a payload whose sha256 differs is
//! reported and rebaked, never trusted.

use super::bake::{bake, BakeStats, Fitted};
use super::storage::{Texel, CHANNELS};
use super::{AoFieldError, BakeParams};
use crate::geometry::Sphere;
use crate::io::CacheError;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"VFAOFLD1";
/// Bumped whenever the payload or the bake's meaning changes.
pub const FORMAT_VERSION: u32 = 2;

/// What identifies a fitted field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CacheKey {
    pub mesh_sha256: String,
    pub params: BakeParams,
    /// Crate version and format version.
    pub code_version: String,
}

impl CacheKey {
    pub fn new(mesh_sha256: &str, params: BakeParams) -> CacheKey {
        CacheKey {
            mesh_sha256: mesh_sha256.to_string(),
            params,
            code_version: format!("{}+a{}", env!("CARGO_PKG_VERSION"), FORMAT_VERSION),
        }
    }

    /// File name: the parameters, then a short hash of the whole key.
    pub fn file_name(&self) -> String {
        let json = serde_json::to_vec(self).expect("key serialises");
        let h = crate::io::sha256_hex(&json);
        let p = &self.params;
        format!(
            "aofield-{}-{}-{}-{}-{}.vaof",
            p.res,
            p.radial_samples,
            p.rays,
            p.reach,
            &h[..16]
        )
    }
}

#[derive(Serialize, Deserialize)]
struct Header {
    key: CacheKey,
    bounds: Sphere,
    payload_len: u64,
    payload_sha256: String,
}

/// How a fitted field was obtained.
#[derive(Debug)]
pub enum Outcome {
    /// Read from a valid cache file.
    Hit(PathBuf),
    /// Baked: no cache folder, no file, or the file was rejected (the reason); saved when
    /// there is a folder.
    Baked {
        stats: BakeStats,
        rejected: Option<String>,
    },
}

/// Writes `fitted` under `key` to `path`, atomically.
pub fn save(path: &Path, key: &CacheKey, fitted: &Fitted) -> Result<(), CacheError> {
    #[cfg(not(target_endian = "little"))]
    compile_error!("the AO field cache assumes a little-endian machine");
    let payload: Vec<u8> = bytemuck::cast_slice(&fitted.texels).to_vec();
    let header = Header {
        key: key.clone(),
        bounds: fitted.bounds,
        payload_len: payload.len() as u64,
        payload_sha256: crate::io::sha256_hex(&payload),
    };
    crate::io::write_cache(path, MAGIC, FORMAT_VERSION, &header, &payload)
}

/// Reads the field saved under `key`, verifying magic, version, key, length and checksum.
pub fn load(path: &Path, key: &CacheKey) -> Result<Fitted, CacheError> {
    let file: crate::io::CacheFile<Header> =
        crate::io::read_cache(path, MAGIC, FORMAT_VERSION, "visfield AO field cache")?;
    let header = &file.header;
    if &header.key != key {
        return Err(file.stale("the key (mesh, parameters or code version) differs"));
    }
    let payload = file.payload(header.payload_len, &header.payload_sha256)?;
    let expect = 6 * key.params.res * key.params.res * CHANNELS * 4;
    if payload.len() != expect {
        return Err(file.corrupt(format!(
            "payload of {} bytes, expected {expect}",
            payload.len()
        )));
    }
    let values: Vec<f32> = bytemuck::pod_collect_to_vec(payload);
    if values.iter().any(|v| !v.is_finite())
        || header.bounds.radius.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return Err(file.corrupt("non-finite values"));
    }
    let texels: Vec<Texel> = values
        .chunks_exact(CHANNELS)
        .map(|c| std::array::from_fn(|k| c[k]))
        .collect();
    Ok(Fitted {
        params: key.params,
        bounds: header.bounds,
        texels,
    })
}

/// The fitted field of `triangles` (model space, their mesh hashing to `mesh_sha256`) from
/// `dir`, or baked (and saved there when `dir` is given).
pub fn load_or_bake(
    dir: Option<&Path>,
    mesh_sha256: &str,
    triangles: &[[Vec3; 3]],
    params: &BakeParams,
) -> Result<(Fitted, Outcome), AoFieldError> {
    params.check()?;
    let key = CacheKey::new(mesh_sha256, *params);
    let path = dir.map(|d| d.join(key.file_name()));
    let rejected = match &path {
        Some(p) if p.exists() => match load(p, &key) {
            Ok(f) => return Ok((f, Outcome::Hit(p.clone()))),
            Err(e) => Some(e.to_string()),
        },
        _ => None,
    };
    let (fitted, stats) = bake(triangles, params)?;
    if let Some(p) = &path {
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d)
                .map_err(|e| AoFieldError::Invalid(format!("{}: {e}", d.display())))?;
        }
        save(p, &key, &fitted)?;
    }
    Ok((fitted, Outcome::Baked { stats, rejected }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Vec<[Vec3; 3]> {
        let v = [
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ];
        vec![
            [v[0], v[1], v[2]],
            [v[0], v[3], v[1]],
            [v[0], v[2], v[3]],
            [v[1], v[3], v[2]],
        ]
    }

    #[test]
    fn a_saved_field_loads_bit_for_bit_and_a_damaged_one_is_rebaked() {
        let dir = tempfile::tempdir().unwrap();
        let params = BakeParams {
            res: 2,
            radial_samples: 4,
            rays: 16,
            reach: 4.0,
        };
        let (baked, first) = load_or_bake(Some(dir.path()), "abc", &tetra(), &params).unwrap();
        assert!(matches!(first, Outcome::Baked { rejected: None, .. }));
        let (again, second) = load_or_bake(Some(dir.path()), "abc", &tetra(), &params).unwrap();
        assert!(matches!(second, Outcome::Hit(_)));
        assert_eq!(baked, again);
        // Another mesh hash is another file.
        let (_, other) = load_or_bake(Some(dir.path()), "abd", &tetra(), &params).unwrap();
        assert!(matches!(other, Outcome::Baked { rejected: None, .. }));
        // A flipped payload byte fails the checksum and is rebaked, naming why.
        let path = dir.path().join(CacheKey::new("abc", params).file_name());
        let mut bytes = std::fs::read(&path).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 0x40;
        std::fs::write(&path, &bytes).unwrap();
        let (rebaked, third) = load_or_bake(Some(dir.path()), "abc", &tetra(), &params).unwrap();
        match third {
            Outcome::Baked {
                rejected: Some(why),
                ..
            } => assert!(why.contains("checksum"), "{why}"),
            other => panic!("expected a rebake, got {other:?}"),
        }
        assert_eq!(rebaked, baked);
        // A truncated file is refused too.
        std::fs::write(&path, &bytes[..20]).unwrap();
        assert!(load(&path, &CacheKey::new("abc", params)).is_err());
    }
}
