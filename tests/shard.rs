//! `--shard I/N` and `experiment merge`: a two-scene spec of procedural meshes (no model file)
//! run whole and as three concurrent shards (sharing one field cache) merges into the single
//! run's folder, every non-time value equal (`pairs.csv`'s 8- against 16-bit pairs too), and so
//! do five shards, one of them empty; merges of inconsistent shard sets, of shards whose rows
//! are not their cells, and into a file or a shard's folder are refused naming the folder or
//! the file; bad `--shard` values are refused naming the flag and the value.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SPEC: &str = r#"{
  "reproduces": "test: shards and merge",
  "description": "Two small scenes, two field sizes each in two precisions: eight cells in four field groups (one bake and its 16-bit twin each), cut 2 + 4 + 2 by three shards (blocks of 2, 3, 3 positions, each group going whole to the shard of its first cell), so the first scene's cells are split over shards 1 and 2.",
  "scenes": [
    {"name": "shape", "instances": [
      {"mesh": {"corner": {"n": 9}}, "receiver": true},
      {"mesh": {"supershape": {"triangles": 2000}}, "caster": true, "transform": {"fit": {"center": [0.5, 0.45, 0.5], "radius": 0.35}}}
    ]},
    {"name": "low", "instances": [
      {"mesh": {"corner": {"n": 9}}, "receiver": true},
      {"mesh": {"supershape": {"triangles": 1000}}, "caster": true, "transform": {"fit": {"center": [0.5, 0.3, 0.5], "radius": 0.25}}}
    ]}
  ],
  "fields": [{"counts": [290, 1090], "resolutions": [16], "precisions": ["u8", "u16"]}],
  "render": {"what": "vertex_ao", "rays_per_point": 64, "image": {"width": 48, "height": 48}},
  "backends": ["cpu"],
  "reference": {"rays_per_point": 64, "seed": 1, "seeds": 2, "truth": {"max_rays": 1024}, "raycast_sweep": [16, 64], "field_rays_sweep": [16, 64]},
  "quick": {}
}"#;

fn experiment(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_experiment"));
    c.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn ok(o: Output, what: &str) -> String {
    let t = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{what} failed:\n{t}");
    t
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let h = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    (h, rows)
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// Runs the spec whole and as shards 1/N..N/N (concurrently); returns (whole, shards).
fn run_all(root: &Path, n: usize) -> (PathBuf, Vec<PathBuf>) {
    let spec = root.join("spec.json");
    std::fs::write(&spec, SPEC).unwrap();
    let cache = root.join("cache");
    let run = |out: &Path, cache: &Path, shard: Option<&str>| {
        let mut args = vec![
            "run",
            spec.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(["--cache", cache.to_str().unwrap()]);
        if let Some(s) = shard {
            args.extend(["--shard", s]);
        }
        experiment(&args)
            .spawn()
            .expect("the experiment binary starts")
    };
    let shards: Vec<PathBuf> = (1..=n).map(|i| root.join(format!("s{i}"))).collect();
    let children: Vec<_> = shards
        .iter()
        .enumerate()
        .map(|(i, d)| run(d, &cache, Some(&format!("{}/{n}", i + 1))))
        .collect();
    for c in children {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "a shard failed");
    }
    let whole = root.join("whole");
    let o = run(&whole, &root.join("cache_whole"), None)
        .wait_with_output()
        .unwrap();
    assert!(o.status.success(), "the whole run failed");
    (whole, shards)
}

/// `experiment merge OUT DIRS…`, its output.
fn merge(out: &Path, dirs: &[&Path]) -> Output {
    let mut args = vec!["merge".to_string(), out.to_string_lossy().into_owned()];
    args.extend(dirs.iter().map(|d| d.to_string_lossy().into_owned()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    experiment(&args).output().unwrap()
}

/// The merged folder holds the whole run's files, every non-time CSV value and image equal.
fn assert_same_run(whole: &Path, merged: &Path) {
    assert_eq!(files(merged), files(whole), "the same files");
    let mut compared = 0;
    for f in files(whole) {
        let name = f.to_string_lossy().into_owned();
        if name.ends_with(".csv") {
            let (ha, ra) = read_csv(&whole.join(&f));
            let (hb, rb) = read_csv(&merged.join(&f));
            assert_eq!(ha, hb, "{name}: header");
            assert_eq!(ra.len(), rb.len(), "{name}: rows");
            for (x, y) in ra.iter().zip(&rb) {
                for ((h, a), b) in ha.iter().zip(x).zip(y) {
                    // Times (`*_s`, `*_rel` ratios of times, `*_mrays_s`) differ from run to run.
                    if !(h.ends_with("_s") || h.ends_with("_rel")) {
                        assert_eq!(a, b, "{name}: column {h}");
                        compared += 1;
                    }
                }
            }
        } else if f.starts_with("images") {
            let a = std::fs::read(whole.join(&f)).unwrap();
            assert!(
                a == std::fs::read(merged.join(&f)).unwrap(),
                "{name} differs"
            );
        }
    }
    assert!(compared > 1000, "only {compared} values compared");
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(merged.join("run.json")).unwrap()).unwrap();
    assert!(run.get("shard").is_none());
    assert_eq!(run["plan"]["cells"], 8);
}

/// A copy of the folder `from` (recursively) at `to`.
fn copy_dir(from: &Path, to: &Path) {
    for f in files(from) {
        std::fs::create_dir_all(to.join(&f).parent().unwrap()).unwrap();
        std::fs::copy(from.join(&f), to.join(&f)).unwrap();
    }
}

#[test]
fn three_concurrent_shards_merge_into_the_single_run() {
    let tmp = tempfile::tempdir().unwrap();
    let (whole, shards) = run_all(tmp.path(), 3);
    // Field groups whole, in contiguous blocks: 2, 4 and 2 of the 8 cells (2 scenes × 2 field
    // sizes × 2 precisions), and each shard's pairs those of its groups: 1, 2 and 1.
    let count = |d: &PathBuf, f: &str| read_csv(&d.join(f)).1.len();
    let cells: Vec<usize> = shards.iter().map(|d| count(d, "table.csv")).collect();
    assert_eq!(cells, vec![2, 4, 2]);
    let pairs: Vec<usize> = shards.iter().map(|d| count(d, "pairs.csv")).collect();
    assert_eq!(pairs, vec![1, 2, 1]);
    assert_eq!(count(&whole, "pairs.csv"), 4);
    let merged = tmp.path().join("merged");
    let dirs: Vec<&str> = [2, 0, 1]
        .iter()
        .map(|&i| shards[i].to_str().unwrap())
        .collect();
    let mut args = vec!["merge", merged.to_str().unwrap()];
    args.extend(dirs);
    ok(experiment(&args).output().unwrap(), "merge");
    assert_same_run(&whole, &merged);
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(merged.join("run.json")).unwrap()).unwrap();
    let listed = run["shards"].as_array().unwrap();
    let order: Vec<&str> = listed
        .iter()
        .map(|s| s["shard"].as_str().unwrap())
        .collect();
    assert_eq!(order, ["1/3", "2/3", "3/3"]);
    for s in listed {
        assert!(s["machine"].is_string() && s["commit"].is_string() && s["wall_s"].is_number());
    }

    // Refusals, each naming the offending folder, and no output folder left behind.
    let refused = |dirs: &[&Path], expect: &str, named: &Path| {
        let out = tmp.path().join("refused");
        let o = merge(&out, dirs);
        let t = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success(), "merge of {dirs:?} accepted");
        assert!(t.contains(expect), "{t}");
        assert!(t.contains(&named.display().to_string()), "{t}");
        assert!(!out.exists(), "a refused merge wrote {}", out.display());
    };
    let (s1, s2, s3) = (&shards[0], &shards[1], &shards[2]);
    refused(&[s1, s2], "shard 3/3 is missing", Path::new("merge"));
    refused(&[s1, s2, s2, s3], "given twice", s2);
    refused(&[s1, &whole, s3], "records no shard", &whole);
    // A copy of shard 3 with an edited spec, commit or shard count.
    let edit = |name: &str, file: &str, from: &str, to: &str| {
        let d = tmp.path().join(name);
        std::fs::create_dir_all(&d).unwrap();
        for f in ["run.json", "spec.json", "table.csv"] {
            std::fs::copy(s3.join(f), d.join(f)).unwrap();
        }
        let text = std::fs::read_to_string(d.join(file)).unwrap();
        assert!(text.contains(from), "{file} has no {from}");
        std::fs::write(d.join(file), text.replacen(from, to, 1)).unwrap();
        d
    };
    let spec = edit("spec_edit", "spec.json", "\"seeds\": 2", "\"seeds\": 3");
    refused(&[s1, s2, &spec], "spec.json differs", &spec);
    let commit = edit(
        "commit_edit",
        "run.json",
        "\"commit\": \"",
        "\"commit\": \"0",
    );
    refused(&[s1, s2, &commit], "commit", &commit);
    let count = edit("count_edit", "run.json", "\"count\": 3", "\"count\": 4");
    refused(&[s1, s2, &count], "shard of 4 runs", &count);
    merge_checks_its_output_folder_and_the_rows(tmp.path(), &whole, &merged, &shards);
}

/// Guards the output folder and the rows of a merge. A file as OUT was renamed away and the
/// merge failed ("Not a directory"); a shard's folder as OUT was replaced by the merge; the
/// user's empty folders in OUT were dropped. And merge trusted the shards' rows: a shard
/// without `table.csv`, a row of another shard's cell, a repeated row or a missing one merged
/// into a wrong table with exit 0, and per-point files were joined by row position. Each is now
/// refused naming the shard's file and the line or the cell, and points are joined by their
/// `point`.
fn merge_checks_its_output_folder_and_the_rows(
    root: &Path,
    whole: &Path,
    merged: &Path,
    shards: &[PathBuf],
) {
    let (s1, s2, s3) = (
        shards[0].as_path(),
        shards[1].as_path(),
        shards[2].as_path(),
    );
    let refused = |out: &Path, dirs: &[&Path], expect: &str, named: &Path| {
        let o = merge(out, dirs);
        let t = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(
            !o.status.success(),
            "merge of {dirs:?} into {out:?} accepted"
        );
        assert!(t.contains(expect), "{t}");
        assert!(t.contains(&named.display().to_string()), "{t}");
    };
    let file = root.join("notes.txt");
    std::fs::write(&file, "mine").unwrap();
    refused(&file, &[s1, s2, s3], "is a file", &file);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    let before = files(s1);
    refused(s1, &[s1, s2, s3], "shard folder", s1);
    refused(&s2.join("inner"), &[s1, s2, s3], "shard folder", s2);
    assert_eq!(files(s1), before);
    let again = root.join(".").join("s2");
    refused(merged, &[s1, s2, &again, s3], "given twice", &again);
    // The user's empty folder in a merged folder survives a merge into it.
    std::fs::create_dir_all(merged.join("drafts/empty")).unwrap();
    ok(merge(merged, &[s1, s2, s3]), "merge again");
    assert!(merged.join("drafts/empty").is_dir());
    assert_same_run(whole, merged);

    // Shard 2 edited: its table.csv (8 cells: 2, 4, 2 in shards 1, 2, 3) and values file.
    let edited = |name: &str, edit: &dyn Fn(&Path)| {
        let d = root.join(name);
        copy_dir(s2, &d);
        edit(&d);
        d
    };
    let lines = |p: &Path| -> Vec<String> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .map(String::from)
            .collect()
    };
    let put = |p: &Path, l: &[String]| std::fs::write(p, l.join("\n") + "\n").unwrap();
    let out = root.join("refused_rows");
    let d = edited("no_table", &|d| {
        std::fs::remove_file(d.join("table.csv")).unwrap()
    });
    refused(&out, &[s1, &d, s3], "has no table.csv", &d);
    let d = edited("foreign_row", &|d| {
        let mut l = lines(&d.join("table.csv"));
        l.push(lines(&s1.join("table.csv"))[1].clone());
        put(&d.join("table.csv"), &l);
    });
    let t = d.join("table.csv");
    refused(&out, &[s1, &d, s3], "line 6: cell shape-", &t);
    refused(
        &out,
        &[s1, &d, s3],
        "is shard 1/3's, not this shard's (2/3)",
        &t,
    );
    let d = edited("repeated_row", &|d| {
        let mut l = lines(&d.join("table.csv"));
        l.push(l[2].clone());
        put(&d.join("table.csv"), &l);
    });
    refused(&out, &[s1, &d, s3], "given twice", &d.join("table.csv"));
    let d = edited("missing_row", &|d| {
        let mut l = lines(&d.join("table.csv"));
        l.pop();
        put(&d.join("table.csv"), &l);
    });
    refused(&out, &[s1, &d, s3], "no row for cell", &d.join("table.csv"));
    assert!(!out.exists(), "a refused merge wrote {}", out.display());
    // Per-point rows in another order merge to the same file; a point missing is refused.
    let values = files(s2)
        .into_iter()
        .find(|f| f.to_string_lossy().starts_with("values_"))
        .expect("shard 2 writes per-point values");
    let d = edited("reordered_points", &|d| {
        let mut l = lines(&d.join(&values));
        l[1..].reverse();
        put(&d.join(&values), &l);
    });
    let reordered = root.join("reordered");
    ok(
        merge(&reordered, &[s1, &d, s3]),
        "merge of reordered points",
    );
    assert_eq!(
        std::fs::read(reordered.join(&values)).unwrap(),
        std::fs::read(merged.join(&values)).unwrap()
    );
    let d = edited("missing_point", &|d| {
        let mut l = lines(&d.join(&values));
        l.remove(3);
        put(&d.join(&values), &l);
    });
    refused(&out, &[s1, &d, s3], "is missing", &d.join(&values));
}

/// Guards more shards than field groups: the empty shards failed ("no rows: not a table
/// written by a run", naming a staging folder already gone) and no merge could then be whole.
/// Five shards of four field groups: shard 3 holds none and writes its `run.json` and a
/// header-only `table.csv`; the five merge into the single run's folder.
#[test]
fn more_shards_than_field_groups_merge_with_the_empty_ones() {
    let tmp = tempfile::tempdir().unwrap();
    let (whole, shards) = run_all(tmp.path(), 5);
    let count = |d: &PathBuf| read_csv(&d.join("table.csv")).1.len();
    let cells: Vec<usize> = shards.iter().map(count).collect();
    assert_eq!(cells, vec![2, 2, 0, 2, 2]);
    let (header, _) = read_csv(&shards[2].join("table.csv"));
    assert!(header.iter().any(|h| h == "cell"), "{header:?}");
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(shards[2].join("run.json")).unwrap()).unwrap();
    assert_eq!(run["shard"]["index"], 3);
    let merged = tmp.path().join("merged");
    let dirs: Vec<&Path> = shards.iter().map(PathBuf::as_path).collect();
    ok(merge(&merged, &dirs), "merge of five shards");
    assert_same_run(&whole, &merged);
}

#[test]
fn bad_shard_values_are_refused_naming_the_flag_and_the_value() {
    let tmp = tempfile::tempdir().unwrap();
    let spec = tmp.path().join("spec.json");
    std::fs::write(&spec, SPEC).unwrap();
    for bad in ["0/3", "4/3", "1/0", "x/3", "2", "1/3/3"] {
        let o = experiment(&["run", spec.to_str().unwrap(), "--dry-run", "--shard", bad])
            .output()
            .unwrap();
        let t = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success(), "--shard {bad} accepted");
        assert!(
            t.contains("--shard") && t.contains(&format!("`{bad}`")),
            "{t}"
        );
    }
    // A good value plans only the shard's cells: 2 of 8 in shard 3/3 (one field group and its
    // 16-bit twin, derived from the one bake), of the second scene only.
    let o = experiment(&["run", spec.to_str().unwrap(), "--dry-run", "--shard", "3/3"])
        .output()
        .unwrap();
    let t = ok(o, "dry run of 3/3");
    assert!(t.contains("2 cell(s), 1 bake(s)"), "{t}");
    assert!(
        t.contains("ray-cast reference low") && !t.contains("ray-cast reference shape"),
        "{t}"
    );
}
