//! Build script: the commit this binary is built from, captured once at build time, so that a
//! result's `run.json` names the code that made it wherever the binary runs (another checkout,
//! an installed copy, a machine without the source tree).
//!
//! Sets `VISFIELD_BUILD_COMMIT` for `env!`: `git rev-parse HEAD`, with `-dirty` where `git
//! status --porcelain` lists a change to a tracked file the binary is built from ([`INPUTS`]:
//! the sources, the shaders and the files they embed); without git, `$VISFIELD_COMMIT` at
//! build time, else "unknown". Cargo reruns it when HEAD, the index, the checked-out branch's
//! ref or any of [`INPUTS`] changes, so the stamp follows commits and edits (an edit to the
//! docs, tests or results neither changes the binary nor reruns this).

use std::path::{Path, PathBuf};
use std::process::Command;

/// What the binary is compiled from or embeds (`include_str!`, `include_bytes!`).
const INPUTS: [&str; 7] = [
    "src",
    "shaders",
    "assets",
    "data",
    "Cargo.toml",
    "Cargo.lock",
    "build.rs",
];

/// `git ARGS` in the crate's folder: its trimmed output, or none where git fails or is absent.
/// `--no-optional-locks` keeps `git status` from refreshing the index, which would mark it
/// changed and rerun this script on the next build.
fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("--no-optional-locks")
        .args(args)
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    Some(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    println!("cargo:rerun-if-env-changed=VISFIELD_COMMIT");
    for input in INPUTS {
        watch(Path::new(input));
    }
    let commit = match git(&["rev-parse", "HEAD"]) {
        Some(head) => {
            watch_git();
            let mut status = vec!["status", "--porcelain", "--untracked-files=no", "--"];
            status.extend(INPUTS);
            let dirty = git(&status).is_some_and(|s| !s.is_empty());
            if dirty {
                format!("{head}-dirty")
            } else {
                head
            }
        }
        None => std::env::var("VISFIELD_COMMIT").unwrap_or_else(|_| "unknown".into()),
    };
    println!("cargo:rustc-env=VISFIELD_BUILD_COMMIT={commit}");
}

/// Reruns this script where the commit may have changed: HEAD (a checkout), the index (a
/// staged change) and the checked-out branch's ref, loose or packed (a commit). Only that
/// branch's: a commit on another branch changes nothing here.
fn watch_git() {
    let dir = |flag: &str| git(&["rev-parse", flag]).map(PathBuf::from);
    if let Some(own) = dir("--git-dir") {
        watch(&own.join("HEAD"));
        watch(&own.join("index"));
    }
    if let (Some(common), Some(branch)) = (
        dir("--git-common-dir"),
        git(&["symbolic-ref", "-q", "HEAD"]),
    ) {
        watch(&common.join(branch));
        watch(&common.join("packed-refs"));
    }
}

/// A path cargo watches (a folder: every file below it); only one that exists, since cargo
/// reruns a script whose watched path is missing on every build.
fn watch(path: &Path) {
    if path.exists() {
        println!("cargo:rerun-if-changed={}", path.display());
    }
}
