//! The on-disk field cache.
//!
//! A cache file is keyed by (mesh sha256, field parameters, code version) and holds:
//!
//! ```text
//! magic    8 bytes  "VFLDCACH"
//! version  u32 LE   FORMAT_VERSION
//! hlen     u32 LE   length of the JSON header
//! header   hlen bytes of JSON (CacheHeader: key, bounds, payload length and sha256)
//! payload  the stored distances, little-endian (1 bit: words, then per-map means)
//! ```
//!
//! Files are written to a temporary name and renamed. A truncated file, a bad magic, another
//! format version, a key that does not match (stale) or a payload whose sha256 differs is
//! reported and never trusted: [`load_or_bake`] rebakes and overwrites it.

use super::bake::{bake, BakeOptions, BakeStats};
use super::{FieldError, FieldParams, Storage, VisibilityField};
use crate::geometry::{Mesh, Sphere};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"VFLDCACH";
/// Bumped whenever the payload layout or the bake's semantics change.
pub const FORMAT_VERSION: u32 = 1;

/// What identifies a baked field.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CacheKey {
    pub mesh_sha256: String,
    pub params: FieldParams,
    /// Crate version and format version; a new release invalidates old caches.
    pub code_version: String,
}

impl CacheKey {
    pub fn new(mesh_sha256: &str, params: FieldParams) -> Self {
        CacheKey {
            mesh_sha256: mesh_sha256.to_string(),
            params,
            code_version: format!("{}+f{}", env!("CARGO_PKG_VERSION"), FORMAT_VERSION),
        }
    }

    /// File name: a short hash of the key, plus readable axes.
    pub fn file_name(&self) -> String {
        let json = serde_json::to_vec(self).expect("key serialises");
        let h = crate::io::sha256_hex(&json);
        let p = &self.params;
        format!(
            "{:?}-{}-{:?}-{}-{}-{}.vfield",
            p.sphere,
            p.count,
            p.layout,
            p.res,
            p.precision.name(),
            &h[..16]
        )
        .to_lowercase()
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct CacheHeader {
    key: CacheKey,
    bounds: Sphere,
    payload_len: u64,
    payload_sha256: String,
}

pub use crate::io::CacheError;

fn payload_bytes(storage: &Storage) -> Vec<u8> {
    #[cfg(not(target_endian = "little"))]
    compile_error!("the field cache assumes a little-endian machine");
    match storage {
        Storage::F32 { data, .. } => bytemuck::cast_slice(data).to_vec(),
        Storage::U16 { data, .. } => bytemuck::cast_slice(data).to_vec(),
        Storage::U8 { data, .. } => data.clone(),
        Storage::Bit1 { bits, mean, .. } => {
            let mut v = bytemuck::cast_slice(bits).to_vec();
            v.extend_from_slice(bytemuck::cast_slice(mean));
            v
        }
    }
}

fn storage_from_payload(params: &FieldParams, bytes: &[u8]) -> Option<Storage> {
    let texels = params.texels();
    let maps = params.count;
    let expect = params.storage_bytes() as usize;
    if bytes.len() != expect {
        return None;
    }
    Some(match params.precision {
        super::Precision::F32 => Storage::F32 {
            texels,
            data: bytemuck::pod_collect_to_vec(bytes),
        },
        super::Precision::U16 => Storage::U16 {
            texels,
            data: bytemuck::pod_collect_to_vec(bytes),
        },
        super::Precision::U8 => Storage::U8 {
            texels,
            data: bytes.to_vec(),
        },
        super::Precision::Bit1 => {
            let words = maps * super::storage::words_per_map(texels) * 8;
            Storage::Bit1 {
                texels,
                bits: bytemuck::pod_collect_to_vec(&bytes[..words]),
                mean: bytemuck::pod_collect_to_vec(&bytes[words..]),
            }
        }
    })
}

/// Writes `field` under `key` to `path`, atomically.
pub fn save(path: &Path, key: &CacheKey, field: &VisibilityField) -> Result<(), CacheError> {
    let payload = payload_bytes(&field.storage);
    let header = CacheHeader {
        key: key.clone(),
        bounds: field.bounds,
        payload_len: payload.len() as u64,
        payload_sha256: crate::io::sha256_hex(&payload),
    };
    crate::io::write_cache(path, MAGIC, FORMAT_VERSION, &header, &payload)
}

/// Reads a field saved under `key`, verifying magic, version, key, length and checksum.
pub fn load(path: &Path, key: &CacheKey) -> Result<VisibilityField, CacheError> {
    let file: crate::io::CacheFile<CacheHeader> =
        crate::io::read_cache(path, MAGIC, FORMAT_VERSION, "visfield cache")?;
    let header = &file.header;
    if &header.key != key {
        return Err(file.stale("the key (mesh, parameters or code version) differs"));
    }
    let payload = file.payload(header.payload_len, &header.payload_sha256)?;
    let corrupt = |reason: String| file.corrupt(reason);
    let storage = storage_from_payload(&key.params, payload)
        .ok_or_else(|| corrupt("payload size does not match the parameters".into()))?;
    let field = VisibilityField::from_storage(key.params, header.bounds, storage)
        .map_err(|e| corrupt(e.to_string()))?;
    field.validate().map_err(|e| corrupt(e.to_string()))?;
    Ok(field)
}

/// How a field was obtained.
#[derive(Debug)]
pub enum CacheOutcome {
    /// Read from a valid cache file.
    Hit(PathBuf),
    /// Baked (no file, or the file was rejected for the given reason) and saved.
    Baked {
        path: PathBuf,
        stats: BakeStats,
        rejected: Option<String>,
    },
}

/// Loads the field of (`mesh`, `params`) from `dir`, or bakes and caches it. A rejected file is
/// reported in the outcome and replaced.
pub fn load_or_bake(
    dir: &Path,
    mesh: &Mesh,
    mesh_sha256: &str,
    params: FieldParams,
    opts: &BakeOptions,
) -> Result<(VisibilityField, CacheOutcome), FieldError> {
    params.check_memory(opts.memory_limit)?;
    let key = CacheKey::new(mesh_sha256, params);
    let path = dir.join(key.file_name());
    let rejected = if path.exists() {
        match load(&path, &key) {
            Ok(field) => return Ok((field, CacheOutcome::Hit(path))),
            Err(e) => Some(e.to_string()),
        }
    } else {
        None
    };
    let (field, stats) = bake(mesh, params, opts)?;
    save(&path, &key, &field).map_err(|e| FieldError::Invalid(e.to_string()))?;
    Ok((
        field,
        CacheOutcome::Baked {
            path,
            stats,
            rejected,
        },
    ))
}
