//! Field supply for a run: bake, or read from the on-disk cache, and derive precisions.
//!
//! The cache ([`crate::field::cache`]) holds only fields up to a size limit (default 256 MiB;
//! the large cells of Figure 6 would fill a disk), in `$VISFIELD_CACHE`, else `cache/` of the
//! project the program runs in, else of the per-user data folder ([`crate::io::places`]). Beside each cached field a `.bake.json` records what its bake cost, so a cache hit
//! still reports the bake time it saved.

use super::progress;
use super::scenes::LoadedMesh;
use super::{Error, Result};
use crate::field::bake::{bake, bake_mesh_with_normals, BakeOptions, BakeStats};
use crate::field::cache::{self, CacheKey};
use crate::field::normals::NormalField;
use crate::field::{FieldParams, Precision, Storage, VisibilityField};
use crate::io::CacheError;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// The environment variable naming the cache folder.
pub const CACHE_ENV: &str = "VISFIELD_CACHE";

/// The default cache folder: `$VISFIELD_CACHE`, else `cache/` of the project the program runs
/// in (the nearest folder holding `experiments/`, from the current directory up), else
/// `cache/` of the per-user data folder ([`crate::io::places::project_or_user`]); never the
/// folder the binary was built in.
pub fn default_cache_dir() -> PathBuf {
    match std::env::var_os(CACHE_ENV).filter(|v| !v.is_empty()) {
        Some(d) => PathBuf::from(d),
        None => crate::io::places::project_or_user("cache"),
    }
}

/// A field ready for lookups, with what it cost.
#[derive(Clone, Debug)]
pub struct Supplied {
    pub field: Arc<VisibilityField>,
    /// Bake wall time (BVH build included), seconds; for a derived precision, the f32 bake plus
    /// the requantisation. `None` when read from a cache entry without a bake record.
    pub bake_s: Option<f64>,
    /// Rays the bake traced.
    pub rays: u64,
    /// Read from the cache.
    pub cached: bool,
}

/// What a cached bake cost, stored beside the field, with a checksum that ties it to its field's
/// cache key: a damaged, edited or misplaced record is not read (the bake time is then unknown,
/// never a made-up number).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct BakeRecord {
    seconds: f64,
    bvh_seconds: f64,
    rays: u64,
    threads: usize,
    date: String,
    /// sha256 of the fields above and the field's cache file name.
    #[serde(default)]
    sha256: String,
}

impl BakeRecord {
    fn digest(&self, key: &CacheKey) -> String {
        let text = format!(
            "{:016x}|{:016x}|{}|{}|{}|{}",
            self.seconds.to_bits(),
            self.bvh_seconds.to_bits(),
            self.rays,
            self.threads,
            self.date,
            key.file_name()
        );
        crate::io::sha256_hex(text.as_bytes())
    }

    /// The record of `path`'s field under `key`, or why it is not used.
    fn load(path: &std::path::Path, key: &CacheKey) -> std::result::Result<BakeRecord, CacheError> {
        let rp = record_path(path);
        let corrupt = |reason: String| CacheError::corrupt(&rp, reason);
        let bytes = std::fs::read(&rp).map_err(CacheError::io(&rp))?;
        let r: BakeRecord = serde_json::from_slice(&bytes).map_err(|e| corrupt(e.to_string()))?;
        let finite = |v: f64| v.is_finite() && v >= 0.0;
        if r.sha256 != r.digest(key) || !finite(r.seconds) || !finite(r.bvh_seconds) {
            return Err(corrupt("checksum or values do not hold".into()));
        }
        Ok(r)
    }
}

/// Where fields come from.
#[derive(Clone, Debug)]
pub struct FieldSupply {
    /// Cache folder; `None`: no cache.
    pub cache: Option<PathBuf>,
    /// Fields larger than this are never cached (bytes).
    pub cache_limit: u64,
    /// Fields larger than this are refused (bytes).
    pub memory_limit: u64,
}

impl FieldSupply {
    fn cache_path(&self, mesh: &LoadedMesh, params: &FieldParams) -> Option<(PathBuf, CacheKey)> {
        let dir = self.cache.as_ref()?;
        if params.storage_bytes() > self.cache_limit {
            return None;
        }
        let key = CacheKey::new(&mesh.sha256, *params);
        Some((dir.join(key.file_name()), key))
    }

    /// How a bake would be served, for the plan: "cached", "bake, cache", "bake".
    pub fn state(&self, mesh: &LoadedMesh, params: &FieldParams) -> &'static str {
        match self.cache_path(mesh, params) {
            Some((p, _)) if p.exists() => "cached",
            Some(_) => "bake, cache",
            None => "bake",
        }
    }

    /// The field of `mesh` with `params`: from the cache when a valid entry exists, else baked
    /// (with a progress bar) and cached when small enough.
    pub fn obtain(&self, mesh: &LoadedMesh, params: FieldParams) -> Result<Supplied> {
        let label = bake_label(mesh, &params);
        let entry = self.cache_path(mesh, &params);
        if let Some((path, key)) = &entry {
            if path.exists() {
                match cache::load(path, key) {
                    Ok(field) => {
                        let record = BakeRecord::load(path, key)
                            .inspect_err(|e| {
                                eprintln!("  bake record not used, bake time unknown: {e}")
                            })
                            .ok();
                        eprintln!("  {label:<40} cached ({})", path.display());
                        return Ok(Supplied {
                            bake_s: record.as_ref().map(|r| r.seconds + r.bvh_seconds),
                            rays: record.map_or(0, |r| r.rays),
                            field: Arc::new(field),
                            cached: true,
                        });
                    }
                    Err(e) => eprintln!("  cache entry rejected, rebaking: {e}"),
                }
            }
        }
        let (field, stats) =
            self.with_progress(&label, params.count, |opts| bake(&mesh.mesh, params, opts))?;
        let supplied = baked(&label, field, &stats, stats.seconds + stats.bvh_seconds);
        if let Some((path, key)) = &entry {
            save(path, key, &supplied.field, &stats)
                .unwrap_or_else(|e| eprintln!("  warning: not cached: {e}"));
        }
        Ok(supplied)
    }
}

/// A mesh's normal fields at each precision a run reads, beside its distance field.
pub type NormalFields = Vec<(u32, Arc<NormalField>)>;

impl FieldSupply {
    /// The field of `mesh` with `params` and its normal fields at each of `bits` (2010 §4.2),
    /// baked in one pass over the same rays (the distances bit-identical to [`Self::obtain`]'s
    /// bake): 16-bit normals, the 8-bit ones derived from them
    /// ([`NormalField::requantized`]). Not read from nor written to the cache (the cache holds
    /// distances only), so the bake time is always measured.
    pub fn obtain_with_normals(
        &self,
        mesh: &LoadedMesh,
        params: FieldParams,
        bits: &[u32],
    ) -> Result<(Supplied, NormalFields)> {
        let label = format!("{} + normals", bake_label(mesh, &params));
        let (field, normals16, stats) = self.with_progress(&label, params.count, |opts| {
            bake_mesh_with_normals(&mesh.mesh, params, 16, opts)
        })?;
        let t = Instant::now();
        let normals16 = Arc::new(normals16);
        let normals = bits
            .iter()
            .map(|&b| {
                let n = if b == 16 {
                    normals16.clone()
                } else {
                    Arc::new(normals16.requantized(b))
                };
                (b, n)
            })
            .collect();
        let seconds = stats.seconds + stats.bvh_seconds + t.elapsed().as_secs_f64();
        Ok((baked(&label, field, &stats, seconds), normals))
    }
}

/// A field baked in `seconds` (`stats` its bake's), logged under `label` with its rays per
/// second.
fn baked(label: &str, field: VisibilityField, stats: &BakeStats, seconds: f64) -> Supplied {
    eprintln!(
        "  {label:<40} {seconds:>9.3} s  ({:.2} Mrays/s)",
        stats.mrays_per_second()
    );
    Supplied {
        field: Arc::new(field),
        bake_s: Some(seconds),
        rays: stats.rays,
        cached: false,
    }
}

impl FieldSupply {
    /// `bake` under the supply's memory limit with a progress bar of `maps` steps labelled
    /// `label`; its error names the label.
    fn with_progress<T>(
        &self,
        label: &str,
        maps: usize,
        bake: impl FnOnce(&BakeOptions) -> std::result::Result<T, crate::field::FieldError>,
    ) -> Result<T> {
        let pb = progress::bar(maps as u64, label);
        let opts = BakeOptions {
            memory_limit: self.memory_limit,
            progress: Some(&pb),
        };
        let out = bake(&opts).map_err(Error::field(label))?;
        pb.finish_and_clear();
        Ok(out)
    }
}

/// The progress and log label of a bake: "bake MESH COUNT × RES² PRECISION".
fn bake_label(mesh: &LoadedMesh, params: &FieldParams) -> String {
    format!(
        "bake {} {} × {}² {}",
        mesh.label,
        params.count,
        params.res,
        params.precision.name()
    )
}

fn record_path(path: &std::path::Path) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(".bake.json");
    PathBuf::from(p)
}

fn save(
    path: &std::path::Path,
    key: &CacheKey,
    field: &VisibilityField,
    stats: &BakeStats,
) -> Result<()> {
    cache::save(path, key, field).map_err(Error::cache("field cache"))?;
    let mut record = BakeRecord {
        seconds: stats.seconds,
        bvh_seconds: stats.bvh_seconds,
        rays: stats.rays,
        threads: rayon::current_num_threads(),
        date: super::meta::utc_now_iso8601(),
        sha256: String::new(),
    };
    record.sha256 = record.digest(key);
    let rp = record_path(path);
    let json = serde_json::to_vec_pretty(&record).expect("record serialises");
    crate::io::write_atomic(&rp, &json).map_err(Error::io(&rp))
}

/// The field `f32` stored at precision `to`. Bit-identical to baking at `to`: the bake stores
/// each map from its f32 row of distances, and an f32 field holds exactly those rows.
///
/// # Panics
/// If `f32` is not stored at f32 precision.
pub fn requantize(f32_field: &VisibilityField, to: Precision) -> VisibilityField {
    assert_eq!(
        f32_field.params.precision,
        Precision::F32,
        "requantize needs an f32 field"
    );
    let params = FieldParams {
        precision: to,
        ..f32_field.params
    };
    let texels = params.texels();
    let mut storage = Storage::new(to, params.count, texels);
    storage
        .map_slots()
        .into_par_iter()
        .enumerate()
        .for_each_init(
            || vec![1.0f32; texels],
            |row, (m, mut slot)| {
                for (t, v) in row.iter_mut().enumerate() {
                    *v = f32_field.storage.get(m, t);
                }
                slot.store(row);
            },
        );
    VisibilityField {
        params,
        bounds: f32_field.bounds,
        points: f32_field.points.clone(),
        layout: f32_field.layout,
        texels: f32_field.texels.clone(),
        frames: f32_field.frames.clone(),
        storage,
        intra: f32_field.intra.with_precision(to, f32_field.bounds.radius),
    }
}

/// A derived field and the time the derivation took.
pub fn derive(source: &Supplied, to: Precision) -> Supplied {
    let t = Instant::now();
    let field = requantize(&source.field, to);
    let s = t.elapsed().as_secs_f64();
    Supplied {
        field: Arc::new(field),
        bake_s: source.bake_s.map(|b| b + s),
        rays: source.rays,
        cached: source.cached,
    }
}
