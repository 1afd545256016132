//! Finding specs by name: `experiments/NAME.json`, in `$VISFIELD_EXPERIMENTS`, else
//! `experiments/` of the project the program runs in (the nearest folder holding one, from the
//! current directory up: [`crate::io::places::project_dir`]), never the folder the binary was
//! built in.

use super::{Error, Result};
use std::path::{Path, PathBuf};

/// The environment variable naming the spec folder.
pub const EXPERIMENTS_ENV: &str = "VISFIELD_EXPERIMENTS";

/// The spec folder: `$VISFIELD_EXPERIMENTS`, else `experiments/` here (kept relative, as
/// messages show it), else the project's; outside any project, `experiments` (whose absence
/// the caller reports).
pub fn experiments_dir() -> PathBuf {
    use crate::io::places::{project_dir, PROJECT_MARK};
    if let Some(d) = std::env::var_os(EXPERIMENTS_ENV).filter(|d| !d.is_empty()) {
        return PathBuf::from(d);
    }
    let local = Path::new(PROJECT_MARK);
    if local.is_dir() {
        return local.to_path_buf();
    }
    project_dir().map_or_else(|| local.to_path_buf(), |p| p.join(PROJECT_MARK))
}

/// Every `*.json` in the spec folder, sorted by name.
pub fn spec_paths() -> Result<Vec<PathBuf>> {
    let dir = experiments_dir();
    let entries = std::fs::read_dir(&dir).map_err(Error::io(&dir))?;
    let mut v: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    v.sort();
    Ok(v)
}

/// The name of a spec file (its stem).
pub fn name_of(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The spec called `name`, or a path given as such (anything ending in `.json`); an unknown
/// name lists the known ones.
pub fn find(name: &str) -> Result<PathBuf> {
    if name.ends_with(".json") {
        return Ok(PathBuf::from(name));
    }
    let all = spec_paths()?;
    all.iter()
        .find(|p| name_of(p) == name)
        .cloned()
        .ok_or_else(|| {
            let known: Vec<String> = all.iter().map(|p| name_of(p)).collect();
            Error::invalid(
                format!("unknown experiment `{name}`"),
                format!(
                    "no {}/{name}.json; known: {}; commands: list, run, check, all, plots, \
                     quickstart",
                    experiments_dir().display(),
                    known.join(", ")
                ),
            )
        })
}
