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

#[test]
fn a_runs_run_json_holds_no_absolute_path_and_its_wall_times() {
    let dir = tempfile::tempdir().unwrap();
    let spec = dir.path().join("tiny.json");
    std::fs::write(&spec, common::tiny(common::ONE_FIELD, "")).unwrap();
    let (out, cache) = (dir.path().join("out"), dir.path().join("cache"));
    let o = Command::new(env!("CARGO_BIN_EXE_experiment"))
        .arg("run")
        .arg(&spec)
        .arg("--quick")
        .arg("--out")
        .arg(&out)
        .arg(format!("--cache={}", cache.display()))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    let mut all = Vec::new();
    strings(&run, "", &mut all);
    let root = env!("CARGO_MANIFEST_DIR");
    for (at, s) in &all {
        assert!(
            !s.starts_with('/') && !s.contains(" /") && !s.contains("=/"),
            "{at}: {s}"
        );
        assert!(!s.contains(root), "{at}: {s}");
    }
    // The folders are still named, relative to the crate.
    let cache_rec = run["cache"].as_str().unwrap();
    assert!(
        cache_rec.ends_with("/cache") && cache_rec.starts_with(".."),
        "{cache_rec}"
    );
    let command = run["meta"]["command"].as_str().unwrap();
    assert!(command.starts_with("experiment run "), "{command}");
    // The run's wall time and each stage's: the stages are timed inside the run.
    let wall = run["meta"]["wall_s"].as_f64().unwrap();
    let stages = run["meta"]["stages"].as_array().unwrap();
    assert!(
        stages.iter().any(|s| s["stage"] == "load scenes"),
        "{stages:?}"
    );
    let sum: f64 = stages.iter().map(|s| s["wall_s"].as_f64().unwrap()).sum();
    assert!(wall > 0.0 && sum > 0.0 && sum <= wall, "{sum} of {wall}");
}
