//! Staged outputs: a run writes its whole results folder beside the published one and swaps it in
//! only when it has finished, so that a failure at any point (a kill, a full disk, an error)
//! leaves the previous results complete and untouched.
//!
//! - The staging folder of results `PARENT/NAME` is `PARENT/.NAME.partial-PID`.
//! - Publishing: the files of the previous results that the program did not write are carried
//!   into the staging folder (hard links, or copies), then the previous folder is renamed to
//!   `PARENT/.NAME.old-PID`, the staging folder to `PARENT/NAME`, and the old folder removed.
//!   A failure before the second rename changes nothing; a kill between the two renames leaves
//!   the previous folder as `.NAME.old-PID`, which the next run puts back.
//! - Ownership: a run lists the files it wrote in its `run.json` (`files`). A file of the
//!   previous results is the program's when that list names it; any other file (the user's, or
//!   one of a run too old to list its files) is never deleted: it is carried into the new
//!   folder. An output folder that holds files but no `run.json` is not a previous run's: it is
//!   refused before any work unless the user allows it (`--allow-nonempty-out`), and its files
//!   are then kept.

use crate::experiment::{Error, Result};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Whether `out` may receive a run: absent, empty, a previous run's results (`run.json`), or
/// any folder when `allow_nonempty` (its files are kept).
pub fn check_ownership(out: &Path, allow_nonempty: bool) -> Result<()> {
    let Ok(mut entries) = std::fs::read_dir(out) else {
        return Ok(());
    };
    if allow_nonempty || out.join("run.json").is_file() || entries.next().is_none() {
        return Ok(());
    }
    Err(Error::invalid(
        format!("output folder {}", out.display()),
        "holds files but no run.json, so no earlier run wrote it; choose an empty or new \
         folder, or pass --allow-nonempty-out (its files are then kept, never deleted)",
    ))
}

fn sibling(out: &Path, what: &str, pid: u32) -> Result<PathBuf> {
    let name = out.file_name().ok_or_else(|| {
        Error::invalid(
            format!("output folder {}", out.display()),
            "has no folder name",
        )
    })?;
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok(parent.join(format!(".{}.{what}-{pid}", name.to_string_lossy())))
}

/// The staging folder of this process for results in `out` (created empty), after putting
/// back the results of a run killed mid-swap and removing the staging folders of dead runs.
pub fn create(out: &Path) -> Result<PathBuf> {
    recover(out)?;
    let dir = sibling(out, "partial", std::process::id())?;
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(Error::io(&dir))?;
    Ok(dir)
}

/// The sibling folders `.NAME.{partial,old}-PID` of dead processes: a killed run's staging
/// folder is removed; a previous results folder left by a kill between the two renames of a
/// swap is put back when `out` is missing (else removed).
fn recover(out: &Path) -> Result<()> {
    let probe = sibling(out, "partial", 0)?;
    let (parent, name) = (probe.parent().expect("a parent"), out.file_name());
    let Some(name) = name.map(|n| n.to_string_lossy().into_owned()) else {
        return Ok(());
    };
    let Ok(entries) = std::fs::read_dir(parent) else {
        return Ok(());
    };
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = file.strip_prefix(&format!(".{name}.")) else {
            continue;
        };
        let Some((what, pid)) = rest.rsplit_once('-') else {
            continue;
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        if crate::io::process_alive(pid) {
            continue;
        }
        match what {
            "old" if !out.exists() => {
                std::fs::rename(e.path(), out).map_err(Error::io(out))?;
            }
            "old" | "partial" => {
                let _ = std::fs::remove_dir_all(e.path());
            }
            _ => {}
        }
    }
    Ok(())
}

/// Every file below `dir`, relative to it, sorted.
fn files_below(dir: &Path) -> Result<BTreeSet<PathBuf>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeSet<PathBuf>) -> Result<()> {
        for e in std::fs::read_dir(dir).map_err(Error::io(dir))? {
            let e = e.map_err(Error::io(dir))?;
            let p = e.path();
            if e.file_type().map_err(Error::io(&p))?.is_dir() {
                walk(root, &p, out)?;
            } else {
                out.insert(p.strip_prefix(root).expect("below the root").to_path_buf());
            }
        }
        Ok(())
    }
    let mut out = BTreeSet::new();
    if dir.is_dir() {
        walk(dir, dir, &mut out)?;
    }
    Ok(out)
}

/// The files a previous run in `out` listed as its own (`run.json` `files`); `None` when it
/// lists none.
fn previous_files(out: &Path) -> Option<BTreeSet<PathBuf>> {
    let bytes = std::fs::read(out.join("run.json")).ok()?;
    let json: serde_json::Value = serde_json::from_slice(&bytes).ok()?;
    let files = json.get("files")?.as_array()?;
    Some(
        files
            .iter()
            .filter_map(|f| f.as_str().map(PathBuf::from))
            .collect(),
    )
}

/// Publishes the finished run in `staging` as `out` (see the module docs).
pub fn publish(staging: &Path, out: &Path) -> Result<()> {
    // The run's own files, recorded in its run.json.
    let own = files_below(staging)?;
    let run_json = staging.join("run.json");
    if let Ok(bytes) = std::fs::read(&run_json) {
        let mut json: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(Error::json(&run_json))?;
        let mut listed: Vec<String> = own.iter().map(|p| p.to_string_lossy().into()).collect();
        listed.sort();
        json["files"] = serde_json::json!(listed);
        let text = serde_json::to_string_pretty(&json).expect("run.json serialises");
        crate::io::write_atomic(&run_json, text.as_bytes()).map_err(Error::io(&run_json))?;
    }
    // Files of the previous results that are not the program's go along.
    let theirs = previous_files(out).unwrap_or_default();
    for rel in files_below(out)? {
        if own.contains(&rel) || theirs.contains(&rel) {
            continue;
        }
        let (from, to) = (out.join(&rel), staging.join(&rel));
        if let Some(d) = to.parent() {
            std::fs::create_dir_all(d).map_err(Error::io(d))?;
        }
        if std::fs::hard_link(&from, &to).is_err() {
            std::fs::copy(&from, &to).map_err(Error::io(&to))?;
        }
    }
    // The swap.
    if !out.exists() {
        return std::fs::rename(staging, out).map_err(Error::io(out));
    }
    let old = sibling(out, "old", std::process::id())?;
    std::fs::rename(out, &old).map_err(Error::io(out))?;
    if let Err(e) = std::fs::rename(staging, out) {
        let _ = std::fs::rename(&old, out);
        return Err(Error::io(out)(e));
    }
    std::fs::remove_dir_all(&old).map_err(Error::io(&old))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(p: &Path, text: &str) {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }

    #[test]
    fn publish_replaces_the_programs_files_and_keeps_everyone_elses() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        // A previous run that listed its files, and a user's files beside them.
        write(
            &out.join("run.json"),
            r#"{"files": ["run.json", "table.csv", "images/a.png", "images/stale.exr"]}"#,
        );
        for f in ["table.csv", "images/a.png", "images/stale.exr"] {
            write(&out.join(f), "old");
        }
        write(&out.join("images/holiday.png"), "mine");
        write(&out.join("notes.txt"), "mine");
        let s = create(&out).unwrap();
        assert_eq!(s.parent(), out.parent(), "the staging folder is a sibling");
        write(&s.join("run.json"), "{}");
        write(&s.join("table.csv"), "new");
        write(&s.join("images/a.png"), "new");
        publish(&s, &out).unwrap();
        assert!(!s.exists());
        let read = |p: &str| std::fs::read_to_string(out.join(p)).unwrap();
        assert_eq!(read("table.csv"), "new");
        assert_eq!(read("images/a.png"), "new");
        // The previous run's own stale file goes; the user's files stay.
        assert!(!out.join("images/stale.exr").exists());
        assert_eq!(read("images/holiday.png"), "mine");
        assert_eq!(read("notes.txt"), "mine");
        // The new run.json lists the new run's files only.
        let listed = previous_files(&out).unwrap();
        let want: BTreeSet<PathBuf> = ["images/a.png", "run.json", "table.csv"]
            .iter()
            .map(PathBuf::from)
            .collect();
        assert_eq!(listed, want);
        // Nothing hidden is left beside or inside the results.
        let hidden = |d: &Path| {
            std::fs::read_dir(d)
                .unwrap()
                .flatten()
                .any(|e| e.file_name().to_string_lossy().starts_with('.'))
        };
        assert!(!hidden(dir.path()) && !hidden(&out));
    }

    #[test]
    fn a_folder_no_run_wrote_is_refused_unless_allowed() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        check_ownership(&out, false).unwrap(); // absent
        std::fs::create_dir_all(&out).unwrap();
        check_ownership(&out, false).unwrap(); // empty
        write(&out.join("holiday.png"), "mine");
        let e = check_ownership(&out, false).unwrap_err().to_string();
        assert!(
            e.contains("no run.json") && e.contains("--allow-nonempty-out"),
            "{e}"
        );
        check_ownership(&out, true).unwrap();
        write(&out.join("run.json"), "{}");
        check_ownership(&out, false).unwrap();
    }

    #[test]
    fn killed_runs_are_cleaned_up_and_a_half_swap_is_put_back() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        // PID 0 is never a user process (no /proc/0).
        let stale = dir.path().join(".out.partial-0");
        write(&stale.join("table.csv"), "half");
        let old = dir.path().join(".out.old-0");
        write(&old.join("table.csv"), "previous");
        let s = create(&out).unwrap();
        assert!(!stale.exists() && !old.exists() && s.exists());
        assert_eq!(
            std::fs::read_to_string(out.join("table.csv")).unwrap(),
            "previous"
        );
    }

    #[test]
    fn a_failed_publish_leaves_the_previous_results_whole() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        write(
            &out.join("run.json"),
            r#"{"files": ["run.json", "table.csv"]}"#,
        );
        write(&out.join("table.csv"), "old");
        let s = create(&out).unwrap();
        write(&s.join("run.json"), "not json");
        write(&s.join("table.csv"), "new");
        assert!(publish(&s, &out).is_err());
        assert_eq!(
            std::fs::read_to_string(out.join("table.csv")).unwrap(),
            "old"
        );
    }
}
