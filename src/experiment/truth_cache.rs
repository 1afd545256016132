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
//! header   hlen bytes of JSON (TruthHeader: key, points, channels, rays, rounds, payload
//!          length and sha256)
//! payload  the values then their standard errors, points × channels each (point-major),
//!          f32 little-endian
//! ```
//!
//! A scalar estimator's file is the layout of files written before channels existed (a header
//! without `channels` reads as one), and its key is theirs: only an estimator with more than
//! one channel adds its count to the key, so cached scalar references stay valid.
//!
//! Files are written atomically; a truncated, corrupt or stale file is reported and recomputed.

use super::{Error, Result};
use crate::io::CacheError;
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
    /// Values per point (absent in files of scalar estimators written before: one).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    channels: u64,
    rays_per_point: u32,
    k: u32,
    batches: u32,
    rounds: Vec<(u32, f64)>,
    payload_len: u64,
    payload_sha256: String,
}

fn one() -> u64 {
    1
}

fn is_one(c: &u64) -> bool {
    *c == 1
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
    let channels = inputs.estimator.channels();
    if channels != 1 {
        meta.insert("channels".into(), serde_json::json!(channels));
    }
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
    let mut payload: Vec<u8> = bytemuck::cast_slice(&truth.values).to_vec();
    payload.extend_from_slice(bytemuck::cast_slice(&truth.stderr));
    let header = TruthHeader {
        key: key.to_string(),
        points: truth.points() as u64,
        channels: truth.channels as u64,
        rays_per_point: truth.rays_per_point,
        k: truth.k,
        batches: truth.batches,
        rounds: truth.rounds.clone(),
        payload_len: payload.len() as u64,
        payload_sha256: crate::io::sha256_hex(&payload),
    };
    crate::io::write_cache(path, MAGIC, FORMAT_VERSION, &header, &payload)
        .map_err(Error::cache("the truth cache"))
}

/// Reads a truth saved under `key`, verifying magic, version, key, length and checksum.
pub fn load(path: &Path, key: &str) -> std::result::Result<Truth, CacheError> {
    let file: crate::io::CacheFile<TruthHeader> =
        crate::io::read_cache(path, MAGIC, FORMAT_VERSION, "truth cache")?;
    let h = &file.header;
    if h.key != key {
        return Err(file.stale("the key differs"));
    }
    let values = h
        .points
        .checked_mul(h.channels)
        .filter(|&v| h.channels > 0 && v.checked_mul(8) == Some(h.payload_len))
        .ok_or_else(|| file.corrupt("the payload's length is not points × channels × 8"))?;
    let payload = file.payload(h.payload_len, &h.payload_sha256)?;
    let n = values as usize;
    let floats: Vec<f32> = bytemuck::pod_collect_to_vec(payload);
    Ok(Truth {
        values: floats[..n].to_vec(),
        stderr: floats[n..].to_vec(),
        channels: h.channels as usize,
        rays_per_point: h.rays_per_point,
        k: h.k,
        batches: h.batches,
        rounds: h.rounds.clone(),
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
            Ok(truth)
                if truth.points() == inputs.at.len()
                    && truth.channels == inputs.estimator.channels() =>
            {
                return Ok((truth, TruthOutcome::Hit(p.clone())))
            }
            Ok(_) => rejected = Some(format!("{}: wrong point or channel count", p.display())),
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
            values: vec![0.5, 1.0, 0.25],
            stderr: vec![0.001, 0.0, 0.002],
            channels: 1,
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

    #[test]
    fn channels_round_trip_and_a_scalar_header_stays_as_before() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.vtruth");
        // Two points of three channels.
        let rgb = Truth {
            values: vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
            stderr: vec![0.0, 0.001, 0.002, 0.003, 0.004, 0.005],
            channels: 3,
            ..sample()
        };
        save(&p, "k", &rgb).unwrap();
        assert_eq!(load(&p, "k").unwrap(), rgb);
        let header = |p: &Path| {
            let b = std::fs::read(p).unwrap();
            let hlen = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
            String::from_utf8(b[16..16 + hlen].to_vec()).unwrap()
        };
        assert!(
            header(&p).contains("\"points\":2,\"channels\":3"),
            "{}",
            header(&p)
        );
        // A scalar truth writes the header of the files before channels (no `channels`).
        save(&p, "k", &sample()).unwrap();
        assert!(!header(&p).contains("channels"), "{}", header(&p));
        assert_eq!(load(&p, "k").unwrap().channels, 1);
    }
}
