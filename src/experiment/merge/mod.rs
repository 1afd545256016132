//! `experiment merge OUT SHARD_DIRS…`: joins the folders of `--shard I/N` runs
//! ([`super::shard`]) into the folder one run of the whole spec writes.
//!
//! Refused, naming the folder, before anything is written: an `OUT` that is a file (left as it
//! is) or a folder no run wrote (`staging::check_ownership`), an `OUT` that is one of the
//! shard folders or lies inside one (or holds one), a folder given twice, a folder that is no
//! shard (no `run.json` `shard`), shards of different `N`, a shard missing or given twice, a
//! commit or a `spec.json` (or profile) that differs from the first shard's. Then the rows
//! (`cells`): every shard's `table.csv` present, each row's cell one of that shard's cells
//! (those [`super::shard::cells`] gives it for the spec as run), no cell twice, and every cell
//! of the spec given; refused otherwise naming the shard's file and the line or the cell. An
//! empty shard (no cells: more shards than field groups) holds a header-only `table.csv`.
//! Then, into a staging folder published only when whole (`super::run::staging`):
//!
//! - a CSV with a `cell` column (`table.csv`, `field_sweep.csv`): the shards' rows in the
//!   single run's plan order (the spec profile's cells, [`super::plan::cells_of`]; a cell's
//!   rows in their shard's order), each row's cell checked to be its shard's;
//! - `pairs.csv`: every shard's pairs (a pair's two cells share a field group, so one shard
//!   measured it: [`super::shard`]), in the single run's order of their cells (`cell_a`,
//!   `cell_b`), each pair once;
//! - a per-point CSV (`values_SCENE.csv`; `ao_SCENE.csv` in runs written before): rows matched
//!   by their `point`, the columns that are no cell's (the points, the references) from the
//!   first shard holding it, then every cell's columns in plan order, each from its own shard
//!   (`join`);
//! - any other CSV (`raycast_sweep.csv`: per scene): a scene's rows from the first shard that
//!   ran it (the scene steps of shards sharing a scene compute the same values; only times
//!   differ);
//! - `images/`: every shard's images, the per-scene ones from the first shard holding them;
//! - `spec.json` copied; `paper_vs_ours.csv` recomputed and the plots redrawn by the code
//!   `experiment plots` runs ([`super::paper::rewrite`], [`super::figures::draw_all`]);
//! - `run.json`: the first shard's, without `shard`, with `plan.cells` summed and `shards`
//!   listing each shard's index, machine, CPU, commit, date, command and wall time.

mod cells;
mod join;

use super::run::{staging, LoadedSpec};
use super::{Error, Result};
use cells::Cells;
use join::{join_csv, read_table, write_table, Part};
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

/// Merges the shard folders `dirs` into `out` (see the module docs).
pub fn merge(out: &Path, dirs: &[PathBuf]) -> Result<()> {
    staging::check_ownership(out, false)?;
    distinct(out, dirs)?;
    let shards = load(dirs)?;
    // The single run's cells in plan order, from the spec as run and its profile.
    let ls = super::run::LoadedSpec::load(&shards[0].dir.join("spec.json"))?;
    let spec = ls.spec.profile(shards[0].run["profile"] == "quick");
    let cells = Cells::of(&spec, &shards);
    cells::check_tables(&shards, &cells)?;
    staging::staged(out, |staged| write(staged, &shards, &ls, &cells))?;
    eprintln!("merged {} shards -> {}", shards.len(), out.display());
    Ok(())
}

/// Refuses a folder given twice and an `out` that is, holds or lies inside a shard folder
/// (its publishing would replace the shard's folder), naming both.
fn distinct(out: &Path, dirs: &[PathBuf]) -> Result<()> {
    let real = |p: &Path| -> Result<PathBuf> {
        if p.exists() {
            return p.canonicalize().map_err(Error::io(p));
        }
        // An `out` still to be made: its parent's real path and its name.
        let abs = std::path::absolute(p).map_err(Error::io(p))?;
        match (abs.parent(), abs.file_name()) {
            (Some(parent), Some(name)) if parent.exists() => {
                Ok(parent.canonicalize().map_err(Error::io(parent))?.join(name))
            }
            _ => Ok(abs),
        }
    };
    let out_real = real(out)?;
    let mut seen: Vec<(PathBuf, &Path)> = Vec::new();
    for d in dirs {
        let r = real(d)?;
        if let Some((_, first)) = seen.iter().find(|(s, _)| *s == r) {
            return Err(Error::invalid(
                d.display().to_string(),
                format!("the same folder as {} given twice", first.display()),
            ));
        }
        if r.starts_with(&out_real) || out_real.starts_with(&r) {
            return Err(Error::invalid(
                format!("output folder {}", out.display()),
                format!(
                    "is, holds or lies inside the shard folder {}, which the merge would \
                     replace; choose another output folder",
                    d.display()
                ),
            ));
        }
        seen.push((r, d));
    }
    Ok(())
}

fn write(staged: &Path, shards: &[ShardDir], ls: &LoadedSpec, cells: &Cells) -> Result<()> {
    // Every file of every shard, by relative path, in shard order.
    let mut by_name: BTreeMap<PathBuf, Vec<&ShardDir>> = BTreeMap::new();
    for s in shards {
        for f in staging::entries_below(&s.dir)?.0 {
            by_name.entry(f).or_default().push(s);
        }
    }
    for (rel, holders) in &by_name {
        let name = rel.to_string_lossy();
        let top = rel.components().count() == 1;
        let to = staged.join(rel);
        if let Some(p) = to.parent() {
            std::fs::create_dir_all(p).map_err(Error::io(p))?;
        }
        if top && name.ends_with(".csv") && name != "paper_vs_ours.csv" {
            let parts = (holders.iter())
                .map(|s| {
                    Ok(Part {
                        dir: &s.dir,
                        shard: s.index,
                        table: read_table(&s.dir.join(rel))?,
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            write_table(&to, &join_csv(&name, &parts, cells)?)?;
        } else if !top || name == "spec.json" {
            // Images (a scene's from the first shard holding it) and the spec.
            let from = holders[0].dir.join(rel);
            std::fs::copy(&from, &to).map_err(Error::io(&from))?;
        }
        // run.json, paper_vs_ours.csv and the plots are made below.
    }
    let mut run = shards[0].run.clone();
    let obj = run.as_object_mut().expect("run.json is an object");
    obj.remove("shard");
    obj.remove("files");
    run["plan"]["cells"] = cells.ids.len().into();
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
