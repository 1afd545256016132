//! The converged reference of a scene ([`crate::render::truth`]), computed once and cached like
//! fields.
//!
//! A cache file is keyed by the sha256 of everything that determines the answer: the evaluation
//! points and normals (after the contact convention), the casters' world triangles, the
//! estimator's options ([`Estimator::key`]: for AO the offset, radius and falloff), the truth
//! options and the code version. It holds:
//!
//! ```text
//! magic    8 bytes  "VTRUTHCA"
//! version  u32 LE   FORMAT_VERSION
//! hlen     u32 LE   length of the JSON header
//! header   hlen bytes of JSON (TruthHeader: key, rays, rounds, payload length and sha256)
//! payload  AO then standard error per point, f32 little-endian
//! ```
//!
//! Files are written atomically; a truncated, corrupt or stale file is reported and recomputed.

use super::{Error, Result};
use crate::field::cache::CacheError;
use crate::render::estimator::{Estimator, Points};
use crate::render::truth::{Truth, TruthOptions};
use crate::visibility::Visibility;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

const MAGIC: &[u8; 8] = b"VTRUTHCA";
/// Bumped whenever the payload layout or the estimator changes (2: the shadow rays' cone
/// without cancellation, where small lights read 1 before).
pub const FORMAT_VERSION: u32 = 2;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct TruthHeader {
    key: String,
    points: u64,
    rays_per_point: u32,
    k: u32,
    batches: u32,
    rounds: Vec<(u32, f64)>,
    payload_len: u64,
    payload_sha256: String,
}

/// What a converged reference is computed from.
pub struct TruthInputs<'a> {
    /// The render kind's estimator (its options are part of the key).
    pub estimator: &'a dyn Estimator,
    /// The visibility of `casters` (the reference tracer).
    pub tracer: &'a dyn Visibility,
    /// The casters' world triangles.
    pub casters: &'a [[Vec3; 3]],
    /// The evaluation points.
    pub at: Points<'a>,
}

/// The cache key of a truth: sha256 over its inputs (the points and normals, the casters, the
/// estimator's options, the truth options and the code version).
pub fn truth_key(inputs: &TruthInputs, t: &TruthOptions) -> String {
    let mut bytes: Vec<u8> = bytemuck::cast_slice(inputs.at.points).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(inputs.at.normals));
    bytes.extend_from_slice(bytemuck::cast_slice(inputs.casters));
    let mut meta = inputs.estimator.key();
    meta.insert("truth".into(), serde_json::json!(t));
    meta.insert(
        "code".into(),
        serde_json::json!(format!("{}+t{}", env!("CARGO_PKG_VERSION"), FORMAT_VERSION)),
    );
    bytes.extend_from_slice(serde_json::Value::Object(meta).to_string().as_bytes());
    crate::io::sha256_hex(&bytes)
}

/// The file of a truth in `dir`.
pub fn truth_path(dir: &Path, scene: &str, key: &str) -> PathBuf {
    dir.join(format!("truth-{scene}-{}.vtruth", &key[..16]))
}

/// Writes `truth` under `key`, atomically.
pub fn save(path: &Path, key: &str, truth: &Truth) -> Result<()> {
    let mut payload: Vec<u8> = bytemuck::cast_slice(&truth.ao).to_vec();
    payload.extend_from_slice(bytemuck::cast_slice(&truth.stderr));
    let header = TruthHeader {
        key: key.to_string(),
        points: truth.ao.len() as u64,
        rays_per_point: truth.rays_per_point,
        k: truth.k,
        batches: truth.batches,
        rounds: truth.rounds.clone(),
        payload_len: payload.len() as u64,
        payload_sha256: crate::io::sha256_hex(&payload),
    };
    let h = serde_json::to_vec(&header).expect("header serialises");
    let out = crate::io::framed(MAGIC, FORMAT_VERSION, &h, &payload);
    crate::io::write_atomic(path, &out).map_err(Error::io(path))
}

/// Reads a truth saved under `key`, verifying magic, version, key, length and checksum.
pub fn load(path: &Path, key: &str) -> std::result::Result<Truth, CacheError> {
    let bytes = std::fs::read(path).map_err(|source| CacheError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |why: &str| CacheError::Corrupt {
        path: path.to_path_buf(),
        reason: why.to_string(),
    };
    let stale = |why: String| CacheError::Stale {
        path: path.to_path_buf(),
        reason: why,
    };
    if bytes.len() < 16 || &bytes[..8] != MAGIC {
        return Err(bad("not a truth cache file (bad magic or truncated)"));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(stale(format!(
            "format version {version}, this build reads {FORMAT_VERSION}"
        )));
    }
    let hlen = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
    let end = 16usize
        .checked_add(hlen)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| bad("truncated header"))?;
    let h: TruthHeader =
        serde_json::from_slice(&bytes[16..end]).map_err(|e| bad(&format!("header: {e}")))?;
    if h.key != key {
        return Err(stale("the key differs".into()));
    }
    let payload = &bytes[end..];
    if payload.len() as u64 != h.payload_len || h.payload_len != h.points * 8 {
        return Err(bad("truncated payload"));
    }
    if crate::io::sha256_hex(payload) != h.payload_sha256 {
        return Err(bad("payload checksum mismatch"));
    }
    let n = h.points as usize;
    let floats: Vec<f32> = bytemuck::pod_collect_to_vec(payload);
    Ok(Truth {
        ao: floats[..n].to_vec(),
        stderr: floats[n..].to_vec(),
        rays_per_point: h.rays_per_point,
        k: h.k,
        batches: h.batches,
        rounds: h.rounds,
    })
}

/// How a truth was obtained.
#[derive(Clone, Debug, PartialEq)]
pub enum TruthOutcome {
    /// Read from this cache file.
    Hit(PathBuf),
    /// Computed (and saved when there is a cache; `rejected`: why a file there was not used).
    Computed {
        path: Option<PathBuf>,
        rejected: Option<String>,
    },
}

/// The truth of `inputs`, from the cache in `dir` or computed (and cached).
pub fn load_or_compute(
    dir: Option<&Path>,
    scene: &str,
    inputs: &TruthInputs,
    t: &TruthOptions,
) -> Result<(Truth, TruthOutcome)> {
    let key = truth_key(inputs, t);
    let path = dir.map(|d| truth_path(d, scene, &key));
    let mut rejected = None;
    if let Some(p) = path.as_ref().filter(|p| p.exists()) {
        match load(p, &key) {
            Ok(truth) if truth.ao.len() == inputs.at.len() => {
                return Ok((truth, TruthOutcome::Hit(p.clone())))
            }
            Ok(_) => rejected = Some(format!("{}: wrong point count", p.display())),
            Err(e) => rejected = Some(e.to_string()),
        }
    }
    let truth = inputs.estimator.converged(inputs.tracer, inputs.at, t);
    if let Some(p) = &path {
        if let Some(d) = p.parent() {
            std::fs::create_dir_all(d).map_err(Error::io(d))?;
        }
        save(p, &key, &truth)?;
    }
    Ok((truth, TruthOutcome::Computed { path, rejected }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Truth {
        Truth {
            ao: vec![0.5, 1.0, 0.25],
            stderr: vec![0.001, 0.0, 0.002],
            rays_per_point: 1024,
            k: 16,
            batches: 4,
            rounds: vec![(256, 0.5), (1024, 0.2)],
        }
    }

    #[test]
    fn round_trip_and_every_corruption_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.vtruth");
        save(&p, "abc", &sample()).unwrap();
        assert_eq!(load(&p, "abc").unwrap(), sample());
        let err = |p: &Path, key: &str| load(p, key).unwrap_err().to_string();
        assert!(err(&p, "abd").contains("stale"));
        let good = std::fs::read(&p).unwrap();
        let mut flipped = good.clone();
        *flipped.last_mut().unwrap() ^= 1;
        std::fs::write(&p, &flipped).unwrap();
        assert!(err(&p, "abc").contains("checksum"));
        std::fs::write(&p, &good[..good.len() - 4]).unwrap();
        assert!(err(&p, "abc").contains("truncated"));
        std::fs::write(&p, b"nonsense").unwrap();
        assert!(err(&p, "abc").contains("magic"));
    }
}
