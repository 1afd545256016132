//! One CSV file of every shard joined into the single run's (the rules of the merge module's
//! docs), each row and column checked against its shard's cells ([`Cells`]).

use super::cells::Cells;
use crate::experiment::{Error, Result};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// A CSV file: its header and rows.
pub(super) type Table = (Vec<String>, Vec<Vec<String>>);

/// One shard's copy of the file being joined.
pub(super) struct Part<'a> {
    pub dir: &'a Path,
    /// The shard's index (1-based).
    pub shard: usize,
    pub table: Table,
}

/// Reads a CSV file (an empty file: no header, no rows).
pub(super) fn read_table(path: &Path) -> Result<Table> {
    let bad = |e: csv::Error| Error::invalid(path.display().to_string(), e.to_string());
    let mut r = csv::Reader::from_path(path).map_err(bad)?;
    let header = r.headers().map_err(bad)?.iter().map(String::from).collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        rows.push(rec.map_err(bad)?.iter().map(String::from).collect());
    }
    Ok((header, rows))
}

/// Writes a CSV file atomically.
pub(super) fn write_table(path: &Path, (header, rows): &Table) -> Result<()> {
    let bad = |e: csv::Error| Error::invalid(path.display().to_string(), e.to_string());
    let mut w = csv::Writer::from_writer(Vec::new());
    if !header.is_empty() {
        w.write_record(header).map_err(bad)?;
    }
    for r in rows {
        w.write_record(r).map_err(bad)?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::io(path)(e.into_error()))?;
    crate::io::write_atomic(path, &bytes).map_err(Error::io(path))
}

/// The files whose rows are one per key (cells): a key given twice is refused.
const ONE_ROW_PER_KEY: [&str; 2] = ["table.csv", "pairs.csv"];

/// Joins the file `name` of every shard holding it (`parts`, in shard order). An empty file (an
/// empty shard's) adds nothing.
pub(super) fn join_csv(name: &str, parts: &[Part], cells: &Cells) -> Result<Table> {
    let parts: Vec<&Part> = parts.iter().filter(|p| !p.table.0.is_empty()).collect();
    let Some(first) = parts.first() else {
        return Ok((Vec::new(), Vec::new()));
    };
    let header = &first.table.0;
    let col = |c: &str| header.iter().position(|x| x == c);
    if name.starts_with("values_") || name.starts_with("ao_") {
        return join_points(name, &parts, cells);
    }
    for p in &parts {
        if p.table.0 != *header {
            return Err(Error::invalid(
                p.dir.join(name).display().to_string(),
                format!("header differs from {}'s", first.dir.join(name).display()),
            ));
        }
    }
    // Rows keyed by cells: every shard's, each cell its own shard's, in plan order.
    let keys: Vec<usize> = ["cell", "cell_a", "cell_b"]
        .iter()
        .filter_map(|c| col(c))
        .collect();
    if !keys.is_empty() {
        let mut rows: Vec<(Vec<usize>, Vec<String>)> = Vec::new();
        let mut seen = HashSet::new();
        for p in &parts {
            let file = p.dir.join(name);
            for (r, row) in p.table.1.iter().enumerate() {
                let what = format!("line {}", r + 2);
                let at = (keys.iter())
                    .map(|&k| cells.check_owner(&row[k], p.shard, &file, &what))
                    .collect::<Result<Vec<usize>>>()?;
                if ONE_ROW_PER_KEY.contains(&name) && !seen.insert(at.clone()) {
                    let ids: Vec<&str> = keys.iter().map(|&k| row[k].as_str()).collect();
                    return Err(Error::invalid(
                        file.display().to_string(),
                        format!("{what}: {} given twice", ids.join(" and ")),
                    ));
                }
                rows.push((at, row.clone()));
            }
        }
        // Stable: a cell's rows keep their shard's order.
        rows.sort_by(|a, b| a.0.cmp(&b.0));
        return Ok((header.clone(), rows.into_iter().map(|r| r.1).collect()));
    }
    // Per scene (or per run): a scene's rows from the first shard that has it.
    let scene = col("scene");
    let mut taken = HashSet::new();
    let mut rows = Vec::new();
    for p in &parts {
        let mut here = HashSet::new();
        for row in &p.table.1 {
            let key = scene.map_or(String::new(), |i| row[i].clone());
            if !taken.contains(&key) {
                here.insert(key);
                rows.push(row.clone());
            }
        }
        taken.extend(here);
    }
    Ok((header.clone(), rows))
}

/// A per-point file (`values_SCENE.csv`): rows matched by their `point`, the columns that are
/// no cell's (the points, the references) from the first shard, then every cell's columns in
/// plan order, each from the shard that runs the cell. Refused, naming the file: a cell column
/// of another shard's cell, points that differ between shards (missing, extra or repeated),
/// columns other than the cells' that differ, and a cell of the scene with no column.
fn join_points(name: &str, parts: &[&Part], cells: &Cells) -> Result<Table> {
    let bad = |p: &Part, why: String| Error::invalid(p.dir.join(name).display().to_string(), why);
    let first = parts[0];
    // Per cell column: (its cell's plan position, its name, its values by `keys` order).
    let mut columns: Vec<(usize, String, Vec<String>)> = Vec::new();
    let mut shared: Vec<String> = Vec::new();
    let mut rows: Vec<Vec<String>> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for (k, p) in parts.iter().enumerate() {
        let (header, body) = &p.table;
        let point = (header.iter().position(|c| c == "point"))
            .ok_or_else(|| bad(p, "no `point` column: not a per-point file of a run".into()))?;
        let is_cell: Vec<Option<usize>> = header.iter().map(|c| cells.of_column(c)).collect();
        let own: Vec<String> = (header.iter().zip(&is_cell))
            .filter(|(_, c)| c.is_none())
            .map(|(h, _)| h.clone())
            .collect();
        if k == 0 {
            shared = own;
            for (r, row) in body.iter().enumerate() {
                if index.insert(row[point].clone(), r).is_some() {
                    return Err(bad(
                        p,
                        format!("line {}: point {} twice", r + 2, row[point]),
                    ));
                }
                let keep = (row.iter().zip(&is_cell)).filter(|(_, c)| c.is_none());
                rows.push(keep.map(|(v, _)| v.clone()).collect());
            }
        } else if own != shared {
            return Err(bad(
                p,
                format!(
                    "columns {} differ from {}'s {}",
                    own.join(","),
                    first.dir.join(name).display(),
                    shared.join(",")
                ),
            ));
        }
        // This shard's row of each point of the first shard.
        let mut slot: Vec<Option<usize>> = vec![None; rows.len()];
        for (r, row) in body.iter().enumerate() {
            let key = &row[point];
            let Some(&i) = index.get(key) else {
                return Err(bad(
                    first,
                    format!(
                        "point {key} is missing ({} has it, line {})",
                        p.dir.join(name).display(),
                        r + 2
                    ),
                ));
            };
            if slot[i].replace(r).is_some() {
                return Err(bad(p, format!("line {}: point {key} twice", r + 2)));
            }
        }
        if let Some(i) = slot.iter().position(Option::is_none) {
            let key = (index.iter().find(|(_, &r)| r == i)).map_or("?", |(k, _)| k.as_str());
            return Err(bad(
                p,
                format!(
                    "point {key} is missing ({} has it)",
                    first.dir.join(name).display()
                ),
            ));
        }
        for (c, cell) in is_cell.iter().enumerate() {
            let Some(at) = *cell else { continue };
            let what = format!("column {}", header[c]);
            cells.check_owner(&cells.ids[at], p.shard, &p.dir.join(name), &what)?;
            let values = slot
                .iter()
                .map(|r| body[r.expect("every point")][c].clone());
            columns.push((at, header[c].clone(), values.collect()));
        }
    }
    let present: HashSet<usize> = columns.iter().map(|c| c.0).collect();
    let scene = (name
        .strip_prefix("values_")
        .or_else(|| name.strip_prefix("ao_")))
    .and_then(|s| s.strip_suffix(".csv"))
    .unwrap_or_default();
    if let Some(i) = (cells.of_scene(scene).into_iter()).find(|i| !present.contains(i)) {
        let (shard, dir) = cells.owner(i);
        return Err(Error::invalid(
            dir.join(name).display().to_string(),
            format!(
                "no column of cell {}, one of shard {shard}'s (absent or without it)",
                cells.ids[i]
            ),
        ));
    }
    // Stable: a cell's channels keep their order.
    columns.sort_by_key(|c| c.0);
    let mut header = shared;
    header.extend(columns.iter().map(|c| c.1.clone()));
    for (i, row) in rows.iter_mut().enumerate() {
        row.extend(columns.iter().map(|c| c.2[i].clone()));
    }
    // In the order of the points' numbers, as a run writes them (where they are numbers).
    let point = header.iter().position(|c| c == "point").expect("checked");
    let numbers: Option<Vec<u64>> = rows.iter().map(|r| r[point].parse().ok()).collect();
    if let Some(numbers) = numbers {
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by_key(|&i| numbers[i]);
        rows = order
            .into_iter()
            .map(|i| std::mem::take(&mut rows[i]))
            .collect();
    }
    Ok((header, rows))
}
