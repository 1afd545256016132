//! `experiment merge OUT SHARD_DIRS…`: joins the folders of `--shard I/N` runs
//! ([`super::shard`]) into the folder one run of the whole spec writes.
//!
//! Refused, naming the folder, before anything is written: a folder that is no shard (no
//! `run.json` `shard`), shards of different `N`, a shard missing or given twice, a commit or a
//! `spec.json` (or profile) that differs from the first shard's. Then, into a staging folder
//! published only when whole ([`super::run::staging`]):
//!
//! - a CSV with a `cell` column (`table.csv`, `field_sweep.csv`): the shards' rows in the
//!   single run's plan order (the spec profile's cells, [`super::plan::cells_of`]; a cell's
//!   rows in their shard's order);
//! - `pairs.csv`: every shard's pairs (a pair's two cells share a field group, so one shard
//!   measured it: [`super::shard`]), in the single run's order of their cells (`cell_a`,
//!   `cell_b`);
//! - a per-point CSV (`values_SCENE.csv`; `ao_SCENE.csv` in runs written before): the columns
//!   every shard writes (the points, the references) from the first shard holding it, then
//!   each shard's cell columns in order;
//! - any other CSV (`raycast_sweep.csv`: per scene): a scene's rows from the first shard that
//!   ran it (the scene steps of shards sharing a scene compute the same values; only times
//!   differ);
//! - `images/`: every shard's images, the per-scene ones from the first shard holding them;
//! - `spec.json` copied; `paper_vs_ours.csv` recomputed and the plots redrawn by the code
//!   `experiment plots` runs ([`super::paper::rewrite`], [`super::figures::draw_all`]);
//! - `run.json`: the first shard's, without `shard`, with `plan.cells` summed and `shards`
//!   listing each shard's index, machine, CPU, commit, date, command and wall time.

use super::run::staging;
use super::{Error, Result};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// One shard's folder and its `run.json`.
struct ShardDir {
    dir: PathBuf,
    index: usize,
    count: usize,
    run: serde_json::Value,
}

fn read_json(path: &Path) -> Result<serde_json::Value> {
    let bytes = std::fs::read(path).map_err(Error::io(path))?;
    serde_json::from_slice(&bytes).map_err(Error::json(path))
}

/// Reads and checks the shard folders (see the module docs); sorted by index.
fn load(dirs: &[PathBuf]) -> Result<Vec<ShardDir>> {
    let refuse = |d: &Path, msg: String| Error::invalid(d.display().to_string(), msg);
    let mut shards = Vec::new();
    for d in dirs {
        let run = read_json(&d.join("run.json"))?;
        let field = |k: &str| run["shard"][k].as_u64().map(|v| v as usize);
        let (Some(index), Some(count)) = (field("index"), field("count")) else {
            return Err(refuse(
                d,
                "run.json records no shard (not a --shard run)".into(),
            ));
        };
        shards.push(ShardDir {
            dir: d.clone(),
            index,
            count,
            run,
        });
    }
    let Some(first) = shards.first() else {
        return Err(Error::invalid("merge", "no shard folders given"));
    };
    let spec0 = std::fs::read(first.dir.join("spec.json")).map_err(Error::io(&first.dir))?;
    let (n, commit, profile) = (
        first.count,
        first.run["meta"]["commit"].clone(),
        first.run["profile"].clone(),
    );
    let mut seen = HashSet::new();
    for s in &shards {
        if s.count != n {
            return Err(refuse(
                &s.dir,
                format!("shard of {} runs, the first of {n}", s.count),
            ));
        }
        if !seen.insert(s.index) {
            return Err(refuse(&s.dir, format!("shard {}/{n} given twice", s.index)));
        }
        if s.run["meta"]["commit"] != commit {
            return Err(refuse(
                &s.dir,
                format!(
                    "commit {} differs from the first shard's {commit}",
                    s.run["meta"]["commit"]
                ),
            ));
        }
        if s.run["profile"] != profile {
            return Err(refuse(
                &s.dir,
                "profile differs from the first shard's".into(),
            ));
        }
        let spec = std::fs::read(s.dir.join("spec.json")).map_err(Error::io(&s.dir))?;
        if spec != spec0 {
            return Err(refuse(
                &s.dir,
                "spec.json differs from the first shard's".into(),
            ));
        }
    }
    if let Some(missing) = (1..=n).find(|i| !seen.contains(i)) {
        return Err(Error::invalid(
            "merge",
            format!("shard {missing}/{n} is missing"),
        ));
    }
    shards.sort_by_key(|s| s.index);
    Ok(shards)
}

type Table = (Vec<String>, Vec<Vec<String>>);

fn read_table(path: &Path) -> Result<Table> {
    let bad = |e: csv::Error| Error::invalid(path.display().to_string(), e.to_string());
    let mut r = csv::Reader::from_path(path).map_err(bad)?;
    let header = r.headers().map_err(bad)?.iter().map(String::from).collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        rows.push(rec.map_err(bad)?.iter().map(String::from).collect());
    }
    Ok((header, rows))
}

fn write_table(path: &Path, (header, rows): &Table) -> Result<()> {
    let bad = |e: csv::Error| Error::invalid(path.display().to_string(), e.to_string());
    let mut w = csv::Writer::from_path(path).map_err(bad)?;
    w.write_record(header).map_err(bad)?;
    for r in rows {
        w.write_record(r).map_err(bad)?;
    }
    w.flush().map_err(Error::io(path))
}

/// Joins one CSV file present in `parts` (shard order) by the rules of the module docs.
/// Joins one CSV of every shard; `ids`: the single run's cell ids in plan order.
fn join_csv(name: &str, parts: &[(&Path, Table)], ids: &[String]) -> Result<Table> {
    let (header, _) = &parts[0].1;
    let col = |h: &[String], c: &str| h.iter().position(|x| x == c);
    // Rows keyed by cells: every shard's, in plan order of their cells.
    let keys: Vec<usize> = ["cell", "cell_a", "cell_b"]
        .iter()
        .filter_map(|c| col(header, c))
        .collect();
    if !keys.is_empty() {
        let mut rows = Vec::new();
        for (dir, (h, r)) in parts {
            if h != header {
                return Err(Error::invalid(
                    dir.join(name).display().to_string(),
                    "header differs from the first shard's",
                ));
            }
            rows.extend(r.iter().cloned());
        }
        // By the cells' plan positions (past every cell when unknown); stable, so a cell's rows
        // keep their shard's order.
        let at = |id: &str| ids.iter().position(|x| x == id).unwrap_or(ids.len());
        rows.sort_by_key(|r| keys.iter().map(|&k| at(&r[k])).collect::<Vec<_>>());
        return Ok((header.clone(), rows));
    }
    if name.starts_with("values_") || name.starts_with("ao_") {
        // Shared columns: those every shard writes; the rest are cells'.
        let shared: Vec<String> = header
            .iter()
            .filter(|c| parts.iter().all(|(_, (h, _))| h.contains(c)))
            .cloned()
            .collect();
        let mut out_h = shared.clone();
        let mut out_rows: Vec<Vec<String>> = parts[0]
            .1
             .1
            .iter()
            .map(|r| {
                shared
                    .iter()
                    .map(|c| r[col(header, c).expect("shared")].clone())
                    .collect()
            })
            .collect();
        for (dir, (h, r)) in parts {
            if r.len() != out_rows.len() {
                return Err(Error::invalid(
                    dir.join(name).display().to_string(),
                    "row count differs from the first shard's",
                ));
            }
            for (i, c) in h.iter().enumerate() {
                if shared.contains(c) {
                    continue;
                }
                out_h.push(c.clone());
                for (o, row) in out_rows.iter_mut().zip(r) {
                    o.push(row[i].clone());
                }
            }
        }
        return Ok((out_h, out_rows));
    }
    // Per scene (or per run): a scene's rows from the first shard that has it.
    let scene = col(header, "scene");
    let mut taken = HashSet::new();
    let mut rows = Vec::new();
    for (_, (h, r)) in parts {
        let mut here = HashSet::new();
        for row in r {
            let key = scene.map_or(String::new(), |i| row[i].clone());
            if !taken.contains(&key) && h == header {
                here.insert(key);
                rows.push(row.clone());
            }
        }
        taken.extend(here);
    }
    Ok((header.clone(), rows))
}

/// Files below `dir`, relative to it.
fn files_below(dir: &Path, rel: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let here = dir.join(rel);
    for e in std::fs::read_dir(&here).map_err(Error::io(&here))? {
        let e = e.map_err(Error::io(&here))?;
        let r = rel.join(e.file_name());
        if e.file_type().map_err(Error::io(&here))?.is_dir() {
            files_below(dir, &r, out)?;
        } else {
            out.push(r);
        }
    }
    Ok(())
}

/// Merges the shard folders `dirs` into `out` (see the module docs).
pub fn merge(out: &Path, dirs: &[PathBuf]) -> Result<()> {
    let shards = load(dirs)?;
    staging::check_ownership(out, false)?;
    let staged = staging::create(out)?;
    let result = write(&staged, &shards);
    if let Err(e) = result.and_then(|_| staging::publish(&staged, out)) {
        let _ = std::fs::remove_dir_all(&staged);
        return Err(e);
    }
    eprintln!("merged {} shards -> {}", shards.len(), out.display());
    Ok(())
}

fn write(staged: &Path, shards: &[ShardDir]) -> Result<()> {
    // The single run's cells in plan order, from the spec as run and its profile.
    let ls = super::run::LoadedSpec::load(&shards[0].dir.join("spec.json"))?;
    let spec = ls.spec.profile(shards[0].run["profile"] == "quick");
    let ids: Vec<String> = super::plan::cells_of(&spec)
        .iter()
        .map(|c| c.id(&spec.scenes[c.scene].name))
        .collect();
    // Every file of every shard, by relative path, in shard order.
    let mut by_name: BTreeMap<PathBuf, Vec<&Path>> = BTreeMap::new();
    for s in shards {
        let mut files = Vec::new();
        files_below(&s.dir, Path::new(""), &mut files)?;
        for f in files {
            by_name.entry(f).or_default().push(&s.dir);
        }
    }
    for (rel, dirs) in &by_name {
        let name = rel.to_string_lossy();
        let top = rel.components().count() == 1;
        let to = staged.join(rel);
        if let Some(p) = to.parent() {
            std::fs::create_dir_all(p).map_err(Error::io(p))?;
        }
        if top && name.ends_with(".csv") && name != "paper_vs_ours.csv" {
            let parts = dirs
                .iter()
                .map(|d| Ok((*d, read_table(&d.join(rel))?)))
                .collect::<Result<Vec<_>>>()?;
            write_table(&to, &join_csv(&name, &parts, &ids)?)?;
        } else if !top || name == "spec.json" {
            // Images (a scene's from the first shard holding it) and the spec.
            let from = dirs[0].join(rel);
            std::fs::copy(&from, &to).map_err(Error::io(&from))?;
        }
        // run.json, paper_vs_ours.csv and the plots are made below.
    }
    let mut run = shards[0].run.clone();
    let obj = run.as_object_mut().expect("run.json is an object");
    obj.remove("shard");
    obj.remove("files");
    let cells: u64 = shards
        .iter()
        .map(|s| s.run["plan"]["cells"].as_u64().unwrap_or(0))
        .sum();
    run["plan"]["cells"] = cells.into();
    run["shards"] = shards
        .iter()
        .map(|s| {
            let m = &s.run["meta"];
            serde_json::json!({
                "shard": format!("{}/{}", s.index, s.count),
                "folder": super::meta::portable_path(&s.dir),
                "machine": m["machine"], "cpu": m["cpu"], "threads": m["threads"],
                "commit": m["commit"], "date": m["date"], "command": m["command"],
                "wall_s": m["wall_s"],
            })
        })
        .collect();
    let p = staged.join("run.json");
    let text = serde_json::to_string_pretty(&run).expect("run.json serialises");
    crate::io::write_atomic(&p, text.as_bytes()).map_err(Error::io(&p))?;
    if let Some(paper) = &ls.spec.paper {
        super::paper::rewrite(staged, paper)?;
    }
    let title = format!(
        "{}{}",
        run["spec"].as_str().unwrap_or("merged"),
        if run["profile"] == "quick" {
            " (quick)"
        } else {
            ""
        }
    );
    super::figures::draw_all(staged, &title)
}
