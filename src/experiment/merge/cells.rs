//! What the shards of a spec must hold: the single run's cells in plan order, each shard's
//! share ([`crate::experiment::shard::cells`]), and the check of every shard's `table.csv`
//! against them before anything is written.

use super::join::{read_table, Table};
use super::ShardDir;
use crate::experiment::shard::{self, Shard};
use crate::experiment::spec::Spec;
use crate::experiment::{Error, Result};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The single run's cells and which shard runs each.
pub(super) struct Cells {
    /// Cell ids in plan order.
    pub ids: Vec<String>,
    /// Each cell's scene name (by position in `ids`).
    scenes: Vec<String>,
    /// Each cell's shard index (1-based; by position in `ids`).
    owner: Vec<usize>,
    /// Position in `ids` of each id.
    at: HashMap<String, usize>,
    count: usize,
    /// Each shard's folder (by index − 1).
    dirs: Vec<PathBuf>,
}

impl Cells {
    /// The cells of `spec` (the profile as run) cut into the `shards` (every index once, sorted).
    pub fn of(spec: &Spec, shards: &[ShardDir]) -> Cells {
        let count = shards.len();
        let all = shard::cells(spec, None);
        let id = |c: &crate::experiment::plan::Cell| c.id(&spec.scenes[c.scene].name);
        let ids: Vec<String> = all.iter().map(id).collect();
        let at: HashMap<String, usize> = ids.iter().cloned().zip(0..).collect();
        let mut owner = vec![0; ids.len()];
        for index in 1..=count {
            for c in shard::cells(spec, Some(Shard { index, count })) {
                owner[at[&id(&c)]] = index;
            }
        }
        Cells {
            scenes: all
                .iter()
                .map(|c| spec.scenes[c.scene].name.clone())
                .collect(),
            ids,
            owner,
            at,
            count,
            dirs: shards.iter().map(|s| s.dir.clone()).collect(),
        }
    }

    /// Cell `i`'s shard, as `I/N` and its folder.
    pub fn owner(&self, i: usize) -> (String, &Path) {
        let k = self.owner[i];
        (format!("{k}/{}", self.count), &self.dirs[k - 1])
    }

    /// The plan position of cell `id`, if it is one of the spec's cells.
    pub fn position(&self, id: &str) -> Option<usize> {
        self.at.get(id).copied()
    }

    /// The cell a per-point column holds (`ID`, or `ID_cK` for channel K), if any.
    pub fn of_column(&self, column: &str) -> Option<usize> {
        self.position(column).or_else(|| {
            let (id, k) = column.rsplit_once("_c")?;
            k.parse::<u32>().ok().and_then(|_| self.position(id))
        })
    }

    /// The positions of the cells of scene `name`.
    pub fn of_scene(&self, name: &str) -> Vec<usize> {
        (0..self.ids.len())
            .filter(|&i| self.scenes[i] == name)
            .collect()
    }

    /// Refuses cell `id` in a file of shard `shard` (`file`, `what`: the row or column) unless
    /// it is one of that shard's cells.
    pub fn check_owner(&self, id: &str, shard: usize, file: &Path, what: &str) -> Result<usize> {
        let bad =
            |why: String| Error::invalid(file.display().to_string(), format!("{what}: {why}"));
        let Some(i) = self.position(id) else {
            return Err(bad(format!("cell {id} is not a cell of the spec as run")));
        };
        if self.owner[i] != shard {
            return Err(bad(format!(
                "cell {id} is shard {}/{}'s, not this shard's ({shard}/{})",
                self.owner[i], self.count, self.count
            )));
        }
        Ok(i)
    }
}

/// Every shard's `table.csv`, checked: present, each row's cell one of its shard's, no cell
/// twice, and every cell of the spec given by its shard. The first failure, naming the shard's
/// file and the row (its line in the file) or the missing cell.
pub(super) fn check_tables(shards: &[ShardDir], cells: &Cells) -> Result<()> {
    let mut given: Vec<Option<usize>> = vec![None; cells.ids.len()];
    for s in shards {
        let path = s.dir.join("table.csv");
        if !path.is_file() {
            return Err(Error::invalid(
                s.dir.display().to_string(),
                format!(
                    "shard {}/{} has no table.csv (an unfinished or edited shard folder); \
                     rerun the shard",
                    s.index, s.count
                ),
            ));
        }
        let (header, rows): Table = read_table(&path)?;
        let Some(col) = header.iter().position(|h| h == "cell") else {
            return Err(Error::invalid(
                path.display().to_string(),
                "no `cell` column: not a table written by a run",
            ));
        };
        for (r, row) in rows.iter().enumerate() {
            // Line 1 is the header.
            let what = format!("line {}", r + 2);
            let i = cells.check_owner(&row[col], s.index, &path, &what)?;
            if given[i].replace(s.index).is_some() {
                return Err(Error::invalid(
                    path.display().to_string(),
                    format!("{what}: cell {} given twice", row[col]),
                ));
            }
        }
    }
    if let Some(i) = given.iter().position(Option::is_none) {
        let (shard, dir) = cells.owner(i);
        return Err(Error::invalid(
            dir.join("table.csv").display().to_string(),
            format!(
                "no row for cell {}, one of shard {shard}'s cells",
                cells.ids[i]
            ),
        ));
    }
    Ok(())
}
