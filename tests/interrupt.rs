//! Interruption: an `experiment` run killed mid-way leaves the previous results byte-identical,
//! shows no partial file among the results, and leaves the field cache either without the
//! field or with a whole, valid file (the same bytes a finished run writes).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// A spec that bakes one field (1090 maps × 24² texels) and renders a small image: a few
/// seconds on 2 cores, long enough to be killed in every stage.
fn spec(dir: &Path) -> PathBuf {
    let text = r#"{
  "reproduces": "interruption test",
  "scenes": [{ "name": "tiny", "instances": [
    { "mesh": { "corner": { "n": 17 } }, "receiver": true },
    { "mesh": { "sphere": { "radius": 0.3, "stacks": 16, "slices": 24 } }, "caster": true,
      "transform": { "translate": [0.5, 0.45, 0.5] } } ] }],
  "fields": [{ "counts": [1090], "resolutions": [24] }],
  "render": { "rays_per_point": 64, "image": { "width": 48, "height": 48 } },
  "reference": { "rays_per_point": 64, "raycast_sweep": [4] },
  "quick": {}
}"#;
    let p = dir.join("interrupt.json");
    std::fs::write(&p, text).unwrap();
    p
}

fn command(spec: &Path, out: &Path, cache: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_experiment"));
    c.args(["run", spec.to_str().unwrap(), "--out"])
        .arg(out)
        .arg("--cache")
        .arg(cache)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    c
}

/// Every file under `dir` whose path has no hidden component, with its bytes.
fn visible_files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with('.') {
                continue;
            }
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

#[test]
fn a_killed_run_leaves_previous_results_and_the_cache_whole() {
    let dir = tempfile::tempdir().unwrap();
    let spec = spec(dir.path());
    let out = dir.path().join("out");
    let good_cache = dir.path().join("cache-good");
    let t = Instant::now();
    let status = command(&spec, &out, &good_cache).status().unwrap();
    assert!(status.success());
    let full = t.elapsed();
    let previous = visible_files(&out);
    assert!(
        previous.contains_key(Path::new("table.csv"))
            && previous.contains_key(Path::new("run.json"))
    );
    let good = fields_of(visible_files(&good_cache));
    assert_eq!(good.len(), 1, "one cached field: {:?}", good.keys());
    // The finished run's converged reference passes the wholeness check the killed runs face,
    // and a truncated copy does not.
    let truths: Vec<Vec<u8>> = visible_files(&good_cache)
        .into_iter()
        .filter(|(p, _)| p.extension().is_some_and(|e| e == "vtruth"))
        .map(|(_, b)| b)
        .collect();
    assert_eq!(truths.len(), 1, "one cached converged reference");
    assert!(truth_file_is_whole(&truths[0]));
    assert!(!truth_file_is_whole(&truths[0][..truths[0].len() - 1]));

    let mut killed_mid_way = 0;
    for fraction in [0.1, 0.25, 0.4, 0.55, 0.7] {
        let cache = dir.path().join(format!("cache-{fraction}"));
        let mut child = command(&spec, &out, &cache).spawn().unwrap();
        std::thread::sleep(full.mul_f64(fraction));
        if child.try_wait().unwrap().is_some() {
            continue; // finished before the kill (a faster machine moment): nothing to check
        }
        child.kill().unwrap();
        child.wait().unwrap();
        killed_mid_way += 1;
        assert_eq!(
            visible_files(&out),
            previous,
            "killed at {fraction} of a run: the previous results changed"
        );
        for (name, bytes) in visible_files(&cache) {
            if name.extension().is_some_and(|e| e == "vtruth") {
                // A cached converged reference: whole (its payload's checksum holds) or absent.
                assert!(
                    truth_file_is_whole(&bytes),
                    "killed at {fraction}: {} is not a whole converged reference",
                    name.display()
                );
                continue;
            }
            if !is_field(&name) {
                // The bake's sidecar (timings): whole JSON or absent.
                assert!(
                    serde_json::from_slice::<serde_json::Value>(&bytes).is_ok(),
                    "killed at {fraction}: {} is not whole JSON",
                    name.display()
                );
                continue;
            }
            assert_eq!(
                Some(&bytes),
                good.get(&name),
                "killed at {fraction}: cache file {} is not the whole field",
                name.display()
            );
        }
    }
    assert!(
        killed_mid_way >= 3,
        "only {killed_mid_way} runs were killed mid-way"
    );

    // The next run finishes, cleans the killed runs' staging folders and trusts only whole
    // cache files.
    let cache = dir.path().join("cache-0.7");
    assert!(command(&spec, &out, &cache).status().unwrap().success());
    let left: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "hidden leftovers in the results: {left:?}");
    assert_eq!(fields_of(visible_files(&cache)), good);
}

/// Whether `bytes` is a whole converged-reference file (`experiment::truth_cache`'s layout:
/// magic, version, header length, JSON header, payload): the header parses and the payload has
/// the header's length and sha256.
fn truth_file_is_whole(bytes: &[u8]) -> bool {
    let Some(rest) = bytes.strip_prefix(b"VTRUTHCA") else {
        return false;
    };
    if rest.len() < 8 {
        return false;
    }
    let hlen = u32::from_le_bytes(rest[4..8].try_into().unwrap()) as usize;
    let Some(header) = rest.get(8..8 + hlen) else {
        return false;
    };
    let Ok(h) = serde_json::from_slice::<serde_json::Value>(header) else {
        return false;
    };
    let payload = &rest[8 + hlen..];
    h["payload_len"].as_u64() == Some(payload.len() as u64)
        && h["payload_sha256"].as_str() == Some(visfield::io::sha256_hex(payload).as_str())
}

fn is_field(p: &Path) -> bool {
    p.extension().is_some_and(|e| e == "vfield")
}

/// The field files among `files` (the cache also keeps a JSON sidecar of bake timings).
fn fields_of(files: BTreeMap<PathBuf, Vec<u8>>) -> BTreeMap<PathBuf, Vec<u8>> {
    files.into_iter().filter(|(p, _)| is_field(p)).collect()
}
