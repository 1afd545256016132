//! Staged outputs: a run writes into a hidden folder beside its results and publishes them
//! only when it has finished, so that a run killed mid-way leaves the previous results intact.
//!
//! The staging folder is `OUT/.partial-PID`; publishing renames each file over its
//! counterpart in `OUT` (each rename atomic, the whole publish a few milliseconds) and removes
//! the folder. A subfolder the run wrote (such as `images/`) belongs to the run: files in it
//! that the run did not write (left by an earlier run with other settings) are removed, so a
//! folder never mixes two runs' images; top-level files other than the run's are kept. Folders
//! left by killed runs (their process gone) are removed by the next run.

use crate::experiment::{Error, Result};
use std::path::{Path, PathBuf};

const PREFIX: &str = ".partial-";

/// The staging folder of this process for results in `out` (created empty).
pub fn create(out: &Path) -> Result<PathBuf> {
    remove_stale(out);
    let dir = out.join(format!("{PREFIX}{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(Error::io(&dir))?;
    Ok(dir)
}

/// Removes staging folders in `out` whose process no longer runs.
fn remove_stale(out: &Path) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = name
            .strip_prefix(PREFIX)
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        let alive = pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists();
        if !alive {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Moves every file of `staging` (recursively) over its counterpart in `out`, removes files
/// of `out`'s subfolders that `staging` did not have, then removes `staging`.
pub fn publish(staging: &Path, out: &Path) -> Result<()> {
    move_tree(staging, out, false)?;
    std::fs::remove_dir_all(staging).map_err(Error::io(staging))
}

fn move_tree(from: &Path, to: &Path, owned: bool) -> Result<()> {
    if owned {
        // Files of the previous run that this one did not write.
        if let Ok(old) = std::fs::read_dir(to) {
            for e in old.flatten() {
                let is_file = e.file_type().map(|t| t.is_file()).unwrap_or(false);
                if is_file && !from.join(e.file_name()).exists() {
                    std::fs::remove_file(e.path()).map_err(Error::io(&e.path()))?;
                }
            }
        }
    }
    std::fs::create_dir_all(to).map_err(Error::io(to))?;
    let entries = std::fs::read_dir(from).map_err(Error::io(from))?;
    for e in entries {
        let e = e.map_err(Error::io(from))?;
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if e.file_type().map(|t| t.is_dir()).unwrap_or(false) {
            move_tree(&src, &dst, true)?;
        } else {
            std::fs::rename(&src, &dst).map_err(Error::io(&dst))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn publish_moves_nested_files_and_removes_the_staging_folder() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir_all(out.join("images")).unwrap();
        std::fs::write(out.join("table.csv"), "old").unwrap();
        std::fs::write(out.join("images/a.png"), "old").unwrap();
        std::fs::write(out.join("images/stale.exr"), "old").unwrap();
        std::fs::write(out.join("keep.txt"), "kept").unwrap();
        let s = create(&out).unwrap();
        std::fs::create_dir_all(s.join("images")).unwrap();
        std::fs::write(s.join("table.csv"), "new").unwrap();
        std::fs::write(s.join("images/a.png"), "new").unwrap();
        publish(&s, &out).unwrap();
        assert!(!s.exists());
        let read = |p: &str| std::fs::read_to_string(out.join(p)).unwrap();
        assert_eq!(read("table.csv"), "new");
        assert_eq!(read("images/a.png"), "new");
        assert_eq!(read("keep.txt"), "kept");
        // The run's own subfolder holds only this run's files.
        assert!(!out.join("images/stale.exr").exists());
    }

    #[test]
    fn stale_staging_folders_of_dead_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // PID 0 is never a user process (no /proc/0).
        let stale = dir.path().join(".partial-0");
        std::fs::create_dir_all(&stale).unwrap();
        std::fs::write(stale.join("table.csv"), "half").unwrap();
        let s = create(dir.path()).unwrap();
        assert!(!stale.exists() && s.exists());
    }
}
