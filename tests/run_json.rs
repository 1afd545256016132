//! `run.json` names no machine's folders: a run with its spec, output and cache in absolute
//! temporary folders records them relative to the crate (or `~`), and records its wall time and
//! each stage's.

mod common;

use std::process::Command;

/// Every string in `v` (keys' values, arrays), with its JSON path.
fn strings(v: &serde_json::Value, at: &str, out: &mut Vec<(String, String)>) {
    match v {
        serde_json::Value::String(s) => out.push((at.to_string(), s.clone())),
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                strings(x, &format!("{at}[{i}]"), out);
            }
        }
        serde_json::Value::Object(o) => {
            for (k, x) in o {
                strings(x, &format!("{at}.{k}"), out);
            }
        }
        _ => {}
    }
}

/// Runs `spec` into `out` with `cache` and returns its `run.json`.
fn run(
    spec: &std::path::Path,
    out: &std::path::Path,
    cache: &std::path::Path,
) -> serde_json::Value {
    let o = Command::new(env!("CARGO_BIN_EXE_experiment"))
        .arg("run")
        .arg(spec)
        .arg("--quick")
        .arg("--out")
        .arg(out)
        .arg(format!("--cache={}", cache.display()))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap()
}

/// Whether `s` holds an absolute path: a `/` that starts a word (at the start, after a space,
/// `=` or `(`) and is followed by a name, so that "/work/x" and "--cache=/tmp/c" count and a
/// ratio written "290 / 1090" does not.
fn holds_absolute_path(s: &str) -> bool {
    let b = s.as_bytes();
    (0..b.len()).any(|i| {
        b[i] == b'/'
            && (i == 0 || matches!(b[i - 1], b' ' | b'=' | b'('))
            && b.get(i + 1)
                .is_some_and(|c| c.is_ascii_alphanumeric() || b"_.~".contains(c))
    })
}

#[test]
fn absolute_paths_are_told_from_ratios() {
    for s in [
        "/work/main",
        "cache /tmp/x.vtruth",
        "--cache=/c",
        "(/home/a)",
    ] {
        assert!(holds_absolute_path(s), "{s}");
    }
    for s in [
        "290 / 1090 / 4226 maps",
        "32² / 64²",
        "../cache",
        "~/cache",
        "a/b",
        "1/2",
    ] {
        assert!(!holds_absolute_path(s), "{s}");
    }
}

/// Fails naming the JSON path of any string of `run` that holds an absolute path.
fn assert_no_absolute_path(run: &serde_json::Value, what: &str) {
    let mut all = Vec::new();
    strings(run, "", &mut all);
    let root = env!("CARGO_MANIFEST_DIR");
    for (at, s) in &all {
        assert!(!holds_absolute_path(s), "{what} {at}: {s}");
        assert!(!s.contains(root), "{what} {at}: {s}");
    }
}

#[test]
fn a_runs_run_json_holds_no_absolute_path_and_its_wall_times() {
    let dir = tempfile::tempdir().unwrap();
    let spec = dir.path().join("tiny.json");
    std::fs::write(&spec, common::tiny(common::ONE_FIELD, "")).unwrap();
    let cache = dir.path().join("cache");
    let run1 = run(&spec, &dir.path().join("out"), &cache);
    assert_no_absolute_path(&run1, "first run");
    // A second run reads the field and the converged reference from the cache, and names the
    // cache file it read the reference from, relative to the crate.
    let run2 = run(&spec, &dir.path().join("out2"), &cache);
    assert_no_absolute_path(&run2, "second run");
    let source = run2["scenes"][0]["truth"]["source"].as_str().unwrap();
    assert!(
        source.starts_with("cache ..") && source.ends_with(".vtruth"),
        "{source}"
    );
    // The folders are still named, relative to the crate.
    let cache_rec = run1["cache"].as_str().unwrap();
    assert!(
        cache_rec.ends_with("/cache") && cache_rec.starts_with(".."),
        "{cache_rec}"
    );
    // What the kind estimates, typed: the plots' axis label reads it.
    assert_eq!(run1["quantity"], "ao");
    let command = run1["meta"]["command"].as_str().unwrap();
    assert!(command.starts_with("experiment run "), "{command}");
    // The run's wall time and each stage's: the stages are timed inside the run.
    let wall = run1["meta"]["wall_s"].as_f64().unwrap();
    let stages = run1["meta"]["stages"].as_array().unwrap();
    assert!(
        stages.iter().any(|s| s["stage"] == "load scenes"),
        "{stages:?}"
    );
    let sum: f64 = stages.iter().map(|s| s["wall_s"].as_f64().unwrap()).sum();
    assert!(wall > 0.0 && sum > 0.0 && sum <= wall, "{sum} of {wall}");
}

/// Every committed `run.json` under `results/` names no machine's folders, and a commit whose
/// tree was clean when it ran (no `-dirty`: the code that made it is that commit's).
#[test]
fn committed_run_jsons_hold_no_absolute_path_and_a_clean_commit() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("results");
    let mut stack = vec![root];
    let mut seen = 0;
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().is_some_and(|n| n == "run.json") {
                let v: serde_json::Value =
                    serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
                assert_no_absolute_path(&v, &p.display().to_string());
                let commit = v["meta"]["commit"]
                    .as_str()
                    .or(v["commit"].as_str())
                    .unwrap_or_else(|| panic!("{}: no commit", p.display()));
                assert!(
                    commit.len() >= 40 && !commit.ends_with("-dirty"),
                    "{}: commit {commit}",
                    p.display()
                );
                seen += 1;
            }
        }
    }
    assert!(seen >= 20, "only {seen} run.json files under results/");
}

/// A binary run outside the tree it was built in finds its specs in the project it runs in
/// (the nearest folder holding `experiments/`, from a folder below it), writes its field cache
/// into that project's `cache/` (outside any project, into the per-user data folder), and
/// stamps `run.json` with the commit it was built from, captured by the build script (before,
/// the spec was looked for and the cache written in the build tree, and the commit and dirty
/// state were read from the build tree at run time).
#[test]
fn a_binary_run_elsewhere_uses_that_project_and_its_build_commit() {
    let dir = tempfile::tempdir().unwrap();
    let project = dir.path().join("project");
    let below = project.join("runs/here");
    std::fs::create_dir_all(project.join("experiments")).unwrap();
    std::fs::create_dir_all(&below).unwrap();
    let spec = common::tiny(common::ONE_FIELD, "");
    std::fs::write(project.join("experiments/tinyrun.json"), &spec).unwrap();
    let (data, home) = (dir.path().join("xdg"), dir.path().join("home"));
    // `experiment NAME` (a spec of the project) or `experiment run PATH`.
    let experiment = |cwd: &std::path::Path, spec: &[&str], out: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_experiment"))
            .args(spec)
            .args(["--quick", "--out", out])
            .current_dir(cwd)
            .env_remove("VISFIELD_CACHE")
            .env_remove("VISFIELD_EXPERIMENTS")
            .env_remove("VISFIELD_COMMIT")
            .env("XDG_DATA_HOME", &data)
            .env("HOME", &home)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let run: serde_json::Value =
            serde_json::from_slice(&std::fs::read(cwd.join(out).join("run.json")).unwrap())
                .unwrap();
        run
    };
    let files = |d: &std::path::Path| std::fs::read_dir(d).map_or(0, |r| r.count());
    let run = experiment(&below, &["tinyrun"], "out");
    assert!(files(&project.join("cache")) > 0, "the project's cache");
    assert_eq!(files(&data), 0, "nothing in the per-user folder");
    // Recorded relative to the project: its cache and its spec.
    assert_eq!(run["cache"], "cache", "{run}");
    let commit = run["meta"]["commit"].as_str().unwrap();
    assert_eq!(commit, visfield::experiment::meta::BUILD_COMMIT);
    let hex = commit.strip_suffix("-dirty").unwrap_or(commit);
    assert!(
        commit == "unknown" || (hex.len() == 40 && hex.bytes().all(|b| b.is_ascii_hexdigit())),
        "{commit}"
    );
    // Outside any project: the per-user data folder's cache.
    let outside = dir.path().join("elsewhere");
    std::fs::create_dir_all(&outside).unwrap();
    let spec_path = project.join("experiments/tinyrun.json");
    experiment(&outside, &["run", spec_path.to_str().unwrap()], "out");
    assert!(
        files(&data.join("visfield/cache")) > 0,
        "the per-user cache"
    );
}
