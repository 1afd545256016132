//! Real meshes by name, found through `$VISFIELD_MODELS`, then the per-user data folder, then
//! `data/models/`, then `../shared/models/`, each checked against the sha256 in
//! `data/models.json`.
//!
//! The registry (`data/models.json`, embedded at compile time) lists every mesh of the shared
//! model collection with its file name, sha256, size, counts, licence and source. Mesh files are
//! never committed. A model's name is its file stem (`bunny_npm`, `stanford-bunny_39k`,
//! `Tree_3`, ...), except `igea_ply` for `igea.ply`, which is listed for completeness with
//! `loadable: false` (a binary PLY of triangle strips; `igea` is the same surface as OBJ).
//!
//! Search order for a model file (first existing file wins; a file that exists but fails the
//! sha256 check is an error, never silently skipped):
//! 1. `$VISFIELD_MODELS/` (a folder), when the variable is set;
//! 2. the per-user data folder, [`user_models_dir`] (`$XDG_DATA_HOME/visfield/models`, else
//!    `~/.local/share/visfield/models`; `%APPDATA%\visfield\models` on Windows);
//! 3. `data/models/` of the project the program runs in (the nearest folder holding
//!    `experiments/`, from the current directory up: [`crate::io::places::project_dir`]), then
//!    under the current directory;
//! 4. `../shared/models/` relative to the project, then to the current directory.
//!
//! No folder comes from where the binary was built: a binary built in one checkout and run in
//! another searches the other.
//!
//! `experiment models fetch` writes into the first of 1–3 that can be named
//! ([`fetch_dir`]), so that every later search finds what it fetched.
//!
//! Verified hashes are cached in memory per (path, size, mtime), so loading a model twice hashes
//! its file once.

use super::{GeometryError, Mesh};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::SystemTime;

/// The environment variable naming an extra model folder, searched first.
pub const MODELS_ENV: &str = "VISFIELD_MODELS";

/// One registry entry.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModelEntry {
    /// Registry name: the file stem (`igea_ply` for `igea.ply`).
    pub name: String,
    /// File name inside a model folder.
    pub file: String,
    /// Lower-case hex SHA-256 of the file.
    pub sha256: String,
    /// File size in bytes.
    pub bytes: u64,
    /// Number of `v` lines (PLY: vertex count).
    pub vertices: usize,
    /// Fan-triangulated face count in the file (before dropping zero-area triangles).
    pub triangles: usize,
    /// Licence and provenance notes.
    pub licence: String,
    /// Where the file came from (repository @ commit, path).
    pub source: String,
    /// Where `experiment models fetch` downloads it: the source commit's raw file, or the zip
    /// archive holding it (`member`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub url: Option<String>,
    /// The file's name inside the zip archive at `url`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub member: Option<String>,
    /// Lower-case hex SHA-256 of the archive at `url` (with `member`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub archive_sha256: Option<String>,
    /// Size of the archive at `url` in bytes (with `member`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub archive_bytes: Option<u64>,
    /// How we made a file that no public source holds, and what of it can be made again.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub derived: Option<String>,
    /// The recipe `experiment models fetch` runs on the downloaded `member` to derive the file
    /// (`bunny-js-to-obj`: the arrays of npm bunny's index.js as OBJ).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convert: Option<String>,
    /// Whether its licence restricts use (shown before a download).
    #[serde(default)]
    pub restricted: bool,
    /// Whether [`Mesh::load_obj`] can read it (OBJ files only).
    pub loadable: bool,
    /// Why it is not loadable, or other remarks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RegistryFile {
    #[allow(dead_code)]
    comment: String,
    models: Vec<ModelEntry>,
}

/// Errors from finding, verifying or loading a registered model.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("{origin}: invalid model registry: {message}")]
    Registry { origin: String, message: String },
    #[error("unknown model `{name}`; known models: {}", known.join(", "))]
    Unknown { name: String, known: Vec<String> },
    #[error(
        "model `{name}` ({file}) not found; tried: {}. Fix: `experiment models fetch {name}` \
         (or set {MODELS_ENV} to a folder holding {file})",
        tried.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    )]
    Missing {
        name: String,
        file: String,
        tried: Vec<PathBuf>,
    },
    #[error(
        "{}: sha256 mismatch for model `{name}`: expected {expected}, found {actual} (a wrong or \
         corrupted copy; replace it with the file listed in data/models.json)",
        path.display()
    )]
    Mismatch {
        name: String,
        path: PathBuf,
        expected: String,
        actual: String,
    },
    #[error("model `{name}` ({file}) is not loadable: {reason}")]
    NotLoadable {
        name: String,
        file: String,
        reason: String,
    },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Geometry(#[from] GeometryError),
}

/// The list of known models.
#[derive(Clone, Debug)]
pub struct ModelRegistry {
    pub entries: Vec<ModelEntry>,
}

impl ModelRegistry {
    /// The registry compiled into the binary from `data/models.json`.
    pub fn embedded() -> &'static ModelRegistry {
        static REGISTRY: OnceLock<ModelRegistry> = OnceLock::new();
        REGISTRY.get_or_init(|| {
            ModelRegistry::from_json(
                include_str!("../../data/models.json"),
                "data/models.json (embedded)",
            )
            .expect("the embedded data/models.json is checked by the test suite")
        })
    }

    /// Parses a registry; `origin` names the source in errors. Rejects unknown fields, duplicate
    /// names and malformed hashes.
    pub fn from_json(text: &str, origin: &str) -> Result<ModelRegistry, ModelError> {
        let err = |message: String| ModelError::Registry {
            origin: origin.to_string(),
            message,
        };
        let file: RegistryFile = serde_json::from_str(text).map_err(|e| err(e.to_string()))?;
        let mut seen = std::collections::HashSet::new();
        for (i, e) in file.models.iter().enumerate() {
            if !seen.insert(e.name.as_str()) {
                return Err(err(format!(
                    "models[{i}].name: duplicate name `{}`",
                    e.name
                )));
            }
            let hex = e.sha256.len() == 64
                && e.sha256
                    .bytes()
                    .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b));
            if !hex {
                return Err(err(format!(
                    "models[{i}].sha256: `{}` is not 64 lower-case hex digits",
                    e.sha256
                )));
            }
            if let Some(url) = &e.url {
                if !(url.starts_with("https://") || url.starts_with("http://")) {
                    return Err(err(format!(
                        "models[{i}].url: `{url}` is not an http(s) URL"
                    )));
                }
            }
            if (e.member.is_some() || e.convert.is_some())
                && (e.archive_sha256.is_none() || e.archive_bytes.is_none())
            {
                return Err(err(format!(
                    "models[{i}]: `member` and `convert` need archive_sha256 and archive_bytes"
                )));
            }
        }
        Ok(ModelRegistry {
            entries: file.models,
        })
    }

    /// The entry called `name`, or an error listing the known names.
    pub fn get(&self, name: &str) -> Result<&ModelEntry, ModelError> {
        self.entries
            .iter()
            .find(|e| e.name == name)
            .ok_or_else(|| ModelError::Unknown {
                name: name.to_string(),
                known: self.entries.iter().map(|e| e.name.clone()).collect(),
            })
    }

    /// Finds and verifies `name` in the default [`search_dirs`].
    pub fn resolve(&self, name: &str) -> Result<PathBuf, ModelError> {
        self.resolve_in(name, &search_dirs())
    }

    /// Finds `name` in the first of `dirs` that holds its file and checks the file's sha256.
    pub fn resolve_in(&self, name: &str, dirs: &[PathBuf]) -> Result<PathBuf, ModelError> {
        let entry = self.get(name)?;
        let mut tried = Vec::with_capacity(dirs.len());
        for dir in dirs {
            let path = dir.join(&entry.file);
            if path.is_file() {
                let actual = sha256_file_cached(&path)?;
                if actual != entry.sha256 {
                    return Err(ModelError::Mismatch {
                        name: entry.name.clone(),
                        path,
                        expected: entry.sha256.clone(),
                        actual,
                    });
                }
                return Ok(path);
            }
            tried.push(path);
        }
        Err(ModelError::Missing {
            name: entry.name.clone(),
            file: entry.file.clone(),
            tried,
        })
    }

    /// Resolves, verifies and loads `name` from the default [`search_dirs`].
    pub fn load(&self, name: &str) -> Result<Mesh, ModelError> {
        self.load_in(name, &search_dirs())
    }

    /// Resolves `name` in `dirs`, verifies it and loads it as a mesh.
    pub fn load_in(&self, name: &str, dirs: &[PathBuf]) -> Result<Mesh, ModelError> {
        let entry = self.get(name)?;
        if !entry.loadable {
            return Err(ModelError::NotLoadable {
                name: entry.name.clone(),
                file: entry.file.clone(),
                reason: entry
                    .note
                    .clone()
                    .unwrap_or_else(|| "not an OBJ file".to_string()),
            });
        }
        let path = self.resolve_in(name, dirs)?;
        Ok(Mesh::load_obj(&path)?)
    }
}

/// Loads a registered model by name (embedded registry, default search folders).
pub fn load_model(name: &str) -> Result<Mesh, ModelError> {
    ModelRegistry::embedded().load(name)
}

/// The default model folders, in search order (see the module docs), without duplicates.
pub fn search_dirs() -> Vec<PathBuf> {
    let project = crate::io::places::project_dir();
    let cwd = std::env::current_dir().ok();
    let mut dirs = Vec::new();
    if let Some(d) = env_models_dir() {
        dirs.push(d);
    }
    if let Some(d) = user_models_dir() {
        dirs.push(d);
    }
    for rel in ["data/models", "../shared/models"] {
        for base in [&project, &cwd].into_iter().flatten() {
            dirs.push(base.join(rel));
        }
    }
    let mut unique: Vec<PathBuf> = Vec::new();
    for d in dirs {
        let key = std::path::absolute(&d).unwrap_or_else(|_| d.clone());
        if !unique
            .iter()
            .any(|u| std::path::absolute(u).unwrap_or_else(|_| u.clone()) == key)
        {
            unique.push(d);
        }
    }
    unique
}

/// The registered models among `names` whose file none of the default [`search_dirs`] holds
/// (unknown names count as missing; a file present with a wrong checksum is not missing:
/// loading it reports the mismatch). Looks at file names only, so it costs no hashing.
pub fn missing_models<'a>(names: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let dirs = search_dirs();
    let registry = ModelRegistry::embedded();
    let mut missing: Vec<String> = Vec::new();
    for name in names {
        let present = registry
            .get(name)
            .is_ok_and(|e| dirs.iter().any(|d| d.join(&e.file).is_file()));
        if !present && !missing.iter().any(|m| m == name) {
            missing.push(name.to_string());
        }
    }
    missing
}

/// What a user missing `missing` is told: "needs a, b: `experiment models fetch a b`".
pub fn fetch_hint(missing: &[String]) -> String {
    format!(
        "needs {}: `experiment models fetch {}`",
        missing.join(", "),
        missing.join(" ")
    )
}

/// `$VISFIELD_MODELS`, when it is set and not empty.
pub fn env_models_dir() -> Option<PathBuf> {
    std::env::var_os(MODELS_ENV)
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
}

/// The per-user model folder: `$XDG_DATA_HOME/visfield/models`, else
/// `$HOME/.local/share/visfield/models` (`%APPDATA%\visfield\models` on Windows); `None` when
/// none of those variables is set to an absolute path.
pub fn user_models_dir() -> Option<PathBuf> {
    crate::io::places::user_data_dir().map(|d| d.join("models"))
}

/// Where `experiment models fetch` writes: `$VISFIELD_MODELS`, else the per-user folder, else
/// `data/models/` of the project the program runs in (else of the current directory).
pub fn fetch_dir() -> PathBuf {
    env_models_dir()
        .or_else(user_models_dir)
        .unwrap_or_else(|| {
            crate::io::places::project_dir()
                .unwrap_or_default()
                .join("data/models")
        })
}

/// Streaming SHA-256 of a file (lower-case hex), cached per (path, size, mtime).
pub fn sha256_file_cached(path: &Path) -> Result<String, ModelError> {
    type Key = (PathBuf, u64, Option<SystemTime>);
    static CACHE: OnceLock<Mutex<HashMap<Key, String>>> = OnceLock::new();
    let io = |source| ModelError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    let key: Key = (
        std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
        meta.len(),
        meta.modified().ok(),
    );
    let cache = CACHE.get_or_init(Default::default);
    if let Some(h) = cache.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
        return Ok(h.clone());
    }
    let (hex, _) = crate::io::sha256_file(path).map_err(io)?;
    cache
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .insert(key, hex.clone());
    Ok(hex)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_registry_parses_with_unique_names_and_matching_files() {
        let r = ModelRegistry::embedded();
        // Every mesh of shared/models/MANIFEST.md: 12 OBJ files and igea.ply.
        assert_eq!(r.entries.len(), 13);
        let mut names: Vec<_> = r.entries.iter().map(|e| e.name.as_str()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), 13);
        for e in &r.entries {
            assert_eq!(e.loadable, e.file.ends_with(".obj"), "{}", e.name);
            if e.loadable {
                assert_eq!(format!("{}.obj", e.name), e.file);
            }
        }
        // Every model is either downloadable from a pinned commit or says how we derived it.
        for e in &r.entries {
            match (&e.url, &e.derived) {
                (Some(url), None) if url.starts_with("https://raw.githubusercontent.com/") => {
                    let commit = url
                        .strip_prefix("https://raw.githubusercontent.com/")
                        .and_then(|p| p.split('/').nth(2))
                        .unwrap_or_default();
                    assert!(
                        commit.len() == 40 && commit.bytes().all(|b| b.is_ascii_hexdigit()),
                        "{}: {url}",
                        e.name
                    );
                }
                // Derived again on the user's machine from a pinned download.
                (Some(url), Some(_)) => {
                    assert!(e.convert.is_some(), "{}: {url}", e.name);
                }
                // Derived by the script it names, which is in the repository.
                (None, Some(how)) => {
                    let script = "scripts/derive_decimated.py";
                    assert!(how.contains(&format!("{script} {}", e.name)), "{how}");
                    assert!(Path::new(env!("CARGO_MANIFEST_DIR")).join(script).is_file());
                    assert!(e.source.starts_with("derived by us"), "{}", e.name);
                }
                other => panic!("{}: url and derived {other:?}", e.name),
            }
        }
        assert_eq!(
            r.get("sponza").unwrap().member.as_deref(),
            Some("sponza.obj")
        );
        assert_eq!(r.get("bunny_npm").unwrap().triangles, 3674);
        assert_eq!(r.get("stanford-bunny_39k").unwrap().triangles, 38889);
    }

    #[test]
    fn registry_rejects_duplicates_and_unknown_fields() {
        let one = r#"{"name":"a","file":"a.obj","sha256":"00000000000000000000000000000000000000000000000000000000000000ff","bytes":1,"vertices":3,"triangles":1,"licence":"x","source":"y","loadable":true}"#;
        let dup = format!(r#"{{"comment":"","models":[{one},{one}]}}"#);
        let e = ModelRegistry::from_json(&dup, "dup.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("dup.json") && e.contains("models[1].name"),
            "{e}"
        );
        let extra = r#"{"comment":"","models":[{"name":"a","colour":1}]}"#;
        let e = ModelRegistry::from_json(extra, "x.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("x.json") && e.contains("colour"), "{e}");
    }

    #[test]
    fn unknown_name_lists_known_models() {
        let e = ModelRegistry::embedded()
            .resolve_in("teapot", &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("teapot") && e.contains("bunny_npm") && e.contains("dragon"),
            "{e}"
        );
    }

    #[test]
    fn missing_model_lists_every_path_tried_and_the_fix() {
        let a = tempfile::tempdir().unwrap();
        let b = tempfile::tempdir().unwrap();
        let dirs = [a.path().to_path_buf(), b.path().to_path_buf()];
        let e = ModelRegistry::embedded()
            .resolve_in("cow", &dirs)
            .unwrap_err();
        let msg = e.to_string();
        for d in &dirs {
            assert!(
                msg.contains(&d.join("cow.obj").display().to_string()),
                "{msg}"
            );
        }
        assert!(
            msg.contains("`experiment models fetch cow`") && msg.contains(MODELS_ENV),
            "{msg}"
        );
    }

    #[test]
    fn hash_cache_returns_the_streamed_hash() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.bin");
        // Far larger than a read buffer, to cover several reads.
        let bytes: Vec<u8> = (0..200_000u32).map(|i| (i * 7 % 251) as u8).collect();
        std::fs::write(&p, &bytes).unwrap();
        let first = sha256_file_cached(&p).unwrap();
        assert_eq!(first, crate::io::sha256_hex(&bytes));
        assert_eq!(sha256_file_cached(&p).unwrap(), first);
    }

    #[test]
    fn igea_ply_is_listed_but_not_loadable() {
        let e = ModelRegistry::embedded()
            .load_in("igea_ply", &[])
            .unwrap_err();
        assert!(matches!(e, ModelError::NotLoadable { .. }), "{e}");
    }
}
