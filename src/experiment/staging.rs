//! Staged outputs: a run writes its whole results folder beside the published one and swaps it in
//! only when it has finished, so that a failure at any point (a kill, a full disk, an error)
//! leaves the previous results complete and untouched.
//!
//! - The staging folder of results `PARENT/NAME` is `PARENT/.NAME.partial-PID`.
//! - The output folder must be a folder (or absent): a file there is refused before any work.
//! - Publishing holds the lock `PARENT/.NAME.lock` ([`crate::io::FileLock`]) throughout, so two
//!   runs publishing into one folder take turns (the second waits, up to
//!   [`PUBLISH_WAIT`], then is refused naming the holder): the files of the previous results
//!   that the program did not write, and its empty folders, are carried into the staging
//!   folder (hard links, or copies), then the previous folder is renamed to
//!   `PARENT/.NAME.old-PID`, the staging folder to `PARENT/NAME`, and the old folder removed.
//!   A failure before the second rename changes nothing; a kill between the two renames leaves
//!   the previous folder as `.NAME.old-PID`, which the next run puts back (under the same
//!   lock). Such a folder is deleted only when nothing in it is the user's that the published
//!   folder lacks; else it is kept and named.
//! - Ownership: a run lists the files it wrote in its `run.json` (`files`). A file of the
//!   previous results is the program's when that list names it; any other file (the user's, or
//!   one of a run too old to list its files) is never deleted: it is carried into the new
//!   folder, and where the new run wrote a file of the same name, the user's is kept beside it
//!   as `NAME.kept` (the files of a run too old to list its own are replaced, as before). An
//!   output folder that holds files but no `run.json` is not a previous run's: it is refused
//!   before any work unless the user allows it (`--allow-nonempty-out`), and its files are
//!   then kept.

use crate::experiment::{Error, Result};
use crate::io::FileLock;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How long a publish waits while another run publishes into the same folder.
pub const PUBLISH_WAIT: Duration = Duration::from_secs(120);

/// Whether `out` may receive a run: absent, empty, a previous run's results (`run.json`), or
/// any folder when `allow_nonempty` (its files are kept). A file (not a folder) is refused.
pub fn check_ownership(out: &Path, allow_nonempty: bool) -> Result<()> {
    if out.exists() && !out.is_dir() {
        return Err(Error::invalid(
            format!("output folder {}", out.display()),
            "is a file, not a folder; choose a folder (the file is left as it is)",
        ));
    }
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

/// Runs `work` on a new staging folder for `out` ([`create`]) and publishes what it wrote
/// ([`publish`]); on any failure the staging folder is removed and `out` is left as it was.
/// The caller checks `out` first ([`check_ownership`]), before its expensive work.
pub fn staged<T>(out: &Path, work: impl FnOnce(&Path) -> Result<T>) -> Result<T> {
    let dir = create(out)?;
    let done = work(&dir).and_then(|t| publish(&dir, out).map(|()| t));
    if done.is_err() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    done
}

/// `PARENT/.NAME.{suffix}` for results `PARENT/NAME`.
fn hidden(out: &Path, suffix: &str) -> Result<PathBuf> {
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
    Ok(parent.join(format!(".{}.{suffix}", name.to_string_lossy())))
}

fn sibling(out: &Path, what: &str, pid: u32) -> Result<PathBuf> {
    hidden(out, &format!("{what}-{pid}"))
}

/// The publishing lock of `out` (see the module docs), waiting up to `wait`.
fn lock(out: &Path, wait: Duration) -> Result<FileLock> {
    let path = hidden(out, "lock")?;
    let parent = path.parent().expect("beside the folder");
    std::fs::create_dir_all(parent).map_err(Error::io(parent))?;
    FileLock::acquire(&path, wait).map_err(|e| {
        if e.kind() == std::io::ErrorKind::WouldBlock {
            Error::invalid(
                format!("output folder {}", out.display()),
                format!("another run is publishing into it: its lock {e}; try again"),
            )
        } else {
            Error::io(&path)(e)
        }
    })
}

/// The staging folder of this process for results in `out` (created empty), after putting
/// back the results of a run killed mid-swap and removing the staging folders of dead runs.
pub fn create(out: &Path) -> Result<PathBuf> {
    {
        let _held = lock(out, PUBLISH_WAIT)?;
        recover(out)?;
    }
    let dir = sibling(out, "partial", std::process::id())?;
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).map_err(Error::io(&dir))?;
    Ok(dir)
}

/// The sibling folders `.NAME.{partial,old}-PID` of dead processes: a killed run's staging
/// folder is removed; a previous results folder left by a kill between the two renames of a
/// swap is put back when `out` is missing, else removed unless it holds something of the
/// user's that `out` lacks ([`leftover_is_redundant`]; it is then kept and named). Called with
/// the publishing lock held.
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
            "old" if !leftover_is_redundant(&e.path(), out)? => eprintln!(
                "kept {}: the earlier results of {} from an interrupted publish, holding files \
                 that are not the program's and that {} lacks; move what you need out of it \
                 and delete it",
                e.path().display(),
                out.display(),
                out.display()
            ),
            "old" | "partial" => {
                let _ = std::fs::remove_dir_all(e.path());
            }
            _ => {}
        }
    }
    Ok(())
}

/// Whether everything of the user's in `old` (a dead run's previous results) is also in `out`:
/// each file the program did not write present with the same bytes, each empty folder present.
fn leftover_is_redundant(old: &Path, out: &Path) -> Result<bool> {
    let theirs = Theirs::of(old)?;
    for rel in &theirs.files {
        let (a, b) = (old.join(rel), out.join(rel));
        let same = match (std::fs::read(&a), std::fs::read(&b)) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        };
        let replaced = theirs.unlisted_run && previous_files(out).is_some_and(|f| f.contains(rel));
        if !same && !replaced {
            return Ok(false);
        }
    }
    Ok(theirs.empty.iter().all(|d| out.join(d).is_dir()))
}

/// Every file below `dir`, relative to it, sorted, and the folders below it that hold nothing.
pub(crate) fn entries_below(dir: &Path) -> Result<(BTreeSet<PathBuf>, BTreeSet<PathBuf>)> {
    fn walk(
        root: &Path,
        dir: &Path,
        files: &mut BTreeSet<PathBuf>,
        empty: &mut BTreeSet<PathBuf>,
    ) -> Result<()> {
        let mut any = false;
        for e in std::fs::read_dir(dir).map_err(Error::io(dir))? {
            let e = e.map_err(Error::io(dir))?;
            let p = e.path();
            any = true;
            if e.file_type().map_err(Error::io(&p))?.is_dir() {
                walk(root, &p, files, empty)?;
            } else {
                files.insert(p.strip_prefix(root).expect("below the root").to_path_buf());
            }
        }
        if !any && dir != root {
            empty.insert(
                dir.strip_prefix(root)
                    .expect("below the root")
                    .to_path_buf(),
            );
        }
        Ok(())
    }
    let (mut files, mut empty) = (BTreeSet::new(), BTreeSet::new());
    if dir.is_dir() {
        walk(dir, dir, &mut files, &mut empty)?;
    }
    Ok((files, empty))
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

/// What of a results folder is not the program's: the files its `run.json` does not list and
/// its empty folders.
struct Theirs {
    files: BTreeSet<PathBuf>,
    empty: BTreeSet<PathBuf>,
    /// A run's folder (`run.json`) that lists no files: a run from before the lists, whose
    /// files at the paths a newer run writes are that run's to replace.
    unlisted_run: bool,
}

impl Theirs {
    fn of(dir: &Path) -> Result<Theirs> {
        let (mut files, empty) = entries_below(dir)?;
        let listed = previous_files(dir);
        if let Some(own) = &listed {
            files.retain(|f| !own.contains(f));
        }
        Ok(Theirs {
            files,
            empty,
            unlisted_run: listed.is_none() && dir.join("run.json").is_file(),
        })
    }
}

/// A free name beside `rel` in `dir` for a user's file the new run's file displaces:
/// `NAME.kept`, else `NAME.kept-2`, `-3`, …
fn kept_name(dir: &Path, rel: &Path, taken: &BTreeSet<PathBuf>) -> PathBuf {
    let mut k = 1;
    loop {
        let suffix = if k == 1 {
            ".kept".to_string()
        } else {
            format!(".kept-{k}")
        };
        let mut name = rel.as_os_str().to_owned();
        name.push(suffix);
        let p = PathBuf::from(name);
        if !taken.contains(&p) && !dir.join(&p).exists() {
            return p;
        }
        k += 1;
    }
}

/// Publishes the finished run in `staging` as `out` (see the module docs).
pub fn publish(staging: &Path, out: &Path) -> Result<()> {
    let _held = lock(out, PUBLISH_WAIT)?;
    // The run's own files, recorded in its run.json.
    let (own, _) = entries_below(staging)?;
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
    // What of the previous results is not the program's goes along.
    let theirs = Theirs::of(out)?;
    let taken: BTreeSet<PathBuf> = own.union(&theirs.files).cloned().collect();
    for rel in &theirs.files {
        let to = if !own.contains(rel) {
            rel.clone()
        } else if theirs.unlisted_run {
            continue;
        } else {
            let k = kept_name(staging, rel, &taken);
            eprintln!(
                "kept your {} as {}: the run wrote a file of that name",
                out.join(rel).display(),
                out.join(&k).display()
            );
            k
        };
        let (from, to) = (out.join(rel), staging.join(to));
        if let Some(d) = to.parent() {
            std::fs::create_dir_all(d).map_err(Error::io(d))?;
        }
        if std::fs::hard_link(&from, &to).is_err() {
            std::fs::copy(&from, &to).map_err(Error::io(&to))?;
        }
    }
    for d in &theirs.empty {
        let to = staging.join(d);
        std::fs::create_dir_all(&to).map_err(Error::io(&to))?;
    }
    // The swap.
    if !out.exists() {
        return std::fs::rename(staging, out).map_err(Error::io(out));
    }
    let old = sibling(out, "old", std::process::id())?;
    std::fs::rename(out, &old).map_err(Error::io(out))?;
    #[cfg(test)]
    if let Some(between) = tests::BETWEEN_RENAMES.with(|h| h.borrow_mut().take()) {
        between();
    }
    if let Err(e) = std::fs::rename(staging, out) {
        let _ = std::fs::rename(&old, out);
        return Err(Error::io(out)(e));
    }
    std::fs::remove_dir_all(&old).map_err(Error::io(&old))
}

#[cfg(test)]
mod tests {
    use super::*;

    thread_local! {
        /// Run by [`publish`] between its two renames, once: a test's way to force another
        /// publish into that window.
        pub(super) static BETWEEN_RENAMES: std::cell::RefCell<Option<Box<dyn FnOnce()>>> =
            const { std::cell::RefCell::new(None) };
    }

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
        // A file is no folder, allowed or not (once renamed away and replaced by a folder).
        let file = dir.path().join("notes.txt");
        write(&file, "mine");
        for allow in [false, true] {
            let e = check_ownership(&file, allow).unwrap_err().to_string();
            assert!(e.contains("notes.txt") && e.contains("is a file"), "{e}");
        }
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    }

    /// `staged` into a folder whose parents do not exist yet makes them (the lock beside the
    /// folder needs its parent); a failing run leaves nothing beside it.
    #[test]
    fn staged_makes_missing_parents_and_a_failure_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a/b/out");
        let failed = staged(&out, |_| -> Result<()> {
            Err(Error::invalid("work", "failed"))
        });
        assert!(failed.is_err() && !out.exists());
        assert_eq!(
            std::fs::read_dir(dir.path().join("a/b")).unwrap().count(),
            0
        );
        staged(&out, |d| {
            write(&d.join("run.json"), "{}");
            Ok(())
        })
        .unwrap();
        assert!(out.join("run.json").is_file());
    }

    /// A previous run's `run.json` files: itself and `table.csv`.
    const LISTED: &str = r#"{"files": ["run.json", "table.csv"]}"#;

    /// `dir/out`, a previous run's results: its `run.json` ([`LISTED`]) and `table.csv` ("old").
    fn previous_run(dir: &Path) -> PathBuf {
        let out = dir.join("out");
        write(&out.join("run.json"), LISTED);
        write(&out.join("table.csv"), "old");
        out
    }

    /// A staging folder holding `run.json` and `table.csv` (`text`), named `name` beside `dir`.
    fn staged_run(dir: &Path, name: &str, text: &str) -> PathBuf {
        let s = dir.join(name);
        write(&s.join("run.json"), "{}");
        write(&s.join("table.csv"), text);
        s
    }

    /// Guards two runs publishing into one folder: a second publish in the window between the
    /// first's two renames (forced here) once found no folder, published without the user's
    /// files and left them in `.out.old-PID`, which the next run deleted. It now waits for the
    /// first (the lock) and carries the user's files and empty folders from its results.
    #[test]
    fn a_publish_waits_for_one_in_progress_and_keeps_the_users_files() {
        let dir = tempfile::tempdir().unwrap();
        let out = previous_run(dir.path());
        write(&out.join("notes.txt"), "mine");
        std::fs::create_dir_all(out.join("drafts")).unwrap();
        let a = staged_run(dir.path(), ".out.partial-a", "a");
        let b = staged_run(dir.path(), ".out.partial-b", "b");
        type Second = Option<(std::thread::JoinHandle<Result<()>>, bool)>;
        let second = std::sync::Arc::new(std::sync::Mutex::new(Second::None));
        let (out2, slot) = (out.clone(), second.clone());
        BETWEEN_RENAMES.with(|h| {
            *h.borrow_mut() = Some(Box::new(move || {
                let t = std::thread::spawn(move || publish(&b, &out2));
                std::thread::sleep(Duration::from_millis(300));
                let finished = t.is_finished();
                *slot.lock().unwrap() = Some((t, finished));
            }))
        });
        publish(&a, &out).unwrap();
        let (t, finished_inside) = second.lock().unwrap().take().expect("the hook ran");
        t.join().unwrap().unwrap();
        assert!(
            !finished_inside,
            "the second publish ran inside the first's swap"
        );
        let read = |p: &str| std::fs::read_to_string(out.join(p)).unwrap();
        assert_eq!(read("table.csv"), "b");
        assert_eq!(read("notes.txt"), "mine");
        assert!(out.join("drafts").is_dir());
        let hidden: Vec<_> = (std::fs::read_dir(dir.path()).unwrap().flatten())
            .map(|e| e.file_name())
            .filter(|n| n.to_string_lossy().starts_with('.'))
            .collect();
        assert!(hidden.is_empty(), "{hidden:?}");
    }

    /// Guards what a publish carries: the user's empty folders were dropped (only files were
    /// carried), and a user's file at a name the run writes was replaced (deleted); it is kept
    /// as `NAME.kept` (`-2` where the user has that name too), through reruns.
    #[test]
    fn empty_folders_and_a_users_file_of_a_name_the_run_writes_are_kept() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        // A folder no run wrote (allowed by the user): their table.csv and table.csv.kept.
        write(&out.join("table.csv"), "mine");
        write(&out.join("table.csv.kept"), "older");
        std::fs::create_dir_all(out.join("empty/deeper")).unwrap();
        for run in ["first", "second"] {
            let s = create(&out).unwrap();
            write(&s.join("run.json"), "{}");
            write(&s.join("table.csv"), run);
            publish(&s, &out).unwrap();
            let read = |p: &str| std::fs::read_to_string(out.join(p)).unwrap();
            assert_eq!(read("table.csv"), run);
            assert_eq!(read("table.csv.kept"), "older");
            assert_eq!(read("table.csv.kept-2"), "mine");
            assert!(out.join("empty/deeper").is_dir());
            assert!(!out.join("table.csv.kept-3").exists(), "{run}");
        }
    }

    /// Guards the previous results a kill mid-swap leaves beside published ones (`.out.old-PID`
    /// of a dead process): they were deleted by the next run, the user's files in them too. Now
    /// deleted only when `out` holds everything of the user's in them.
    #[test]
    fn a_leftover_previous_folder_is_deleted_only_when_nothing_of_the_users_is_lost() {
        let dir = tempfile::tempdir().unwrap();
        let out = previous_run(dir.path());
        write(&out.join("notes.txt"), "mine");
        // PID 0 is never a user process (no /proc/0).
        let old = dir.path().join(".out.old-0");
        write(&old.join("run.json"), LISTED);
        write(&old.join("table.csv"), "older");
        write(&old.join("notes.txt"), "mine");
        drop(create(&out).unwrap());
        assert!(
            !old.exists(),
            "the program's files and a copy of the user's"
        );
        write(&old.join("run.json"), LISTED);
        write(&old.join("photo.png"), "mine too");
        drop(create(&out).unwrap());
        assert_eq!(
            std::fs::read_to_string(old.join("photo.png")).unwrap(),
            "mine too"
        );
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
        let out = previous_run(dir.path());
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
