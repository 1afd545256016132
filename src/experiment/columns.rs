//! One row schema mechanism: what defines the columns of every CSV a run writes.
//!
//! - A row is a serde struct of plain fields: its fields give the header, in order, and serde
//!   the values (as the CSV serialiser writes them). `outputs::write_csv`
//!   writes it, `outputs::read_csv` reads it back by header name: a column's former name is a
//!   `#[serde(alias)]`, a column added since a `#[serde(default)]`. So are `raycast_sweep.csv`,
//!   `field_sweep.csv`, `pairs.csv`, `paper_vs_ours.csv` and the commands' tables
//!   (`backend_times.csv`, `renderings.csv`, `cases.csv`, …).
//! - Where a row has columns no struct field names (a kind's own metrics, a method's
//!   parameters), it is a [`NamedRow`]: (name, value) pairs in the order its parts add them,
//!   the header the ordered union of the rows' names ([`header`]) after the struct's
//!   ([`write_csv_with`]), a struct's columns taken with serde's bytes ([`of_serialized`]).
//!   `table.csv` is its struct, `table::Row`, whose columns are defined
//!   once in `table_columns!` (name, former name, type, meaning, value), then the kind's own
//!   columns; `frames.csv` and `sweep_frames.csv` are two views of one struct
//!   (`frame_row`: each a list of (name in the file, field));
//!   `methods.csv` is built from its parts (the cell, the method and its parameters, its
//!   times, each value's `Display`, [`Cell`]), its error columns those of `table.csv`'s list
//!   (`table::ErrorColumns::push_to`). Names say what a column holds for
//!   every kind (`estimate_s`, `rms_vs_truth`), not for AO.
//! - A file is named for what its rows hold; a folder written before a file had its name is
//!   read under the former one (`outputs::table_path`).

use super::{Error, Result};
use std::fmt::Display;
use std::path::Path;

/// One row: (column, value) pairs in order, each name once.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NamedRow(Vec<(String, String)>);

impl NamedRow {
    pub fn new() -> NamedRow {
        NamedRow::default()
    }

    /// Adds a column.
    ///
    /// # Panics
    /// If the row has a column of that name already (two parts naming one column is a bug of
    /// the parts, never of the input).
    pub fn push(&mut self, name: impl Into<String>, value: impl Display) -> &mut NamedRow {
        let name = name.into();
        assert!(
            self.get(&name).is_none(),
            "column `{name}` added twice to one row"
        );
        self.0.push((name, value.to_string()));
        self
    }

    /// Adds a column that may be empty (none: the empty cell).
    pub fn push_opt<T: Display>(
        &mut self,
        name: impl Into<String>,
        value: Option<T>,
    ) -> &mut NamedRow {
        match value {
            Some(v) => self.push(name, v),
            None => self.push(name, ""),
        }
    }

    /// The value of column `name` (empty cells are `Some("")`).
    pub fn get(&self, name: &str) -> Option<&str> {
        self.0
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }

    /// Column `name` as a number (none where it is absent, empty or not a number).
    pub fn number(&self, name: &str) -> Option<f64> {
        self.get(name).and_then(|v| v.parse().ok())
    }

    /// The columns in order.
    pub fn columns(&self) -> impl Iterator<Item = (&str, &str)> {
        self.0.iter().map(|(n, v)| (n.as_str(), v.as_str()))
    }
}

/// A typed value as a [`NamedRow`] cell: its `Display` text, none as the empty cell (what
/// [`NamedRow::push`] and [`NamedRow::push_opt`] write).
pub trait Cell {
    fn cell(&self) -> String;
}

macro_rules! display_cells {
    ($($t:ty),*) => {$(
        impl Cell for $t {
            fn cell(&self) -> String {
                self.to_string()
            }
        }
    )*};
}
display_cells!(u32, f64, String);

impl<T: Cell> Cell for Option<T> {
    fn cell(&self) -> String {
        self.as_ref().map_or_else(String::new, Cell::cell)
    }
}

/// The ordered union of the rows' column names: each row's names in its order, a name first
/// met in a later row placed after the last name it follows that is already there.
pub fn header(rows: &[NamedRow]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in rows {
        let mut at = 0;
        for (name, _) in r.columns() {
            match out.iter().position(|n| n == name) {
                Some(i) => at = i + 1,
                None => {
                    out.insert(at, name.to_string());
                    at += 1;
                }
            }
        }
    }
    out
}

/// Writes rows as CSV under their [`header`], atomically.
pub fn write_csv(path: &Path, rows: &[NamedRow]) -> Result<()> {
    write_csv_with(path, &[], rows)
}

/// [`write_csv`] under the header `first` (in order), then the rows' other names (the
/// header alone when there is no row).
pub fn write_csv_with(path: &Path, first: &[&str], rows: &[NamedRow]) -> Result<()> {
    let mut names: Vec<String> = first.iter().map(|n| n.to_string()).collect();
    for n in header(rows) {
        if !names.contains(&n) {
            names.push(n);
        }
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(&names).map_err(Error::csv(path))?;
    for r in rows {
        w.write_record(names.iter().map(|n| r.get(n).unwrap_or("")))
            .map_err(Error::csv(path))?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e.into_error(),
    })?;
    crate::io::write_atomic(path, &bytes).map_err(Error::io(path))
}

/// The named columns of a value serde writes as one CSV record (a struct of plain fields),
/// each written as the CSV serialiser writes it: so a table of such rows has the bytes
/// `experiment::outputs::write_csv` gives it.
///
/// # Panics
/// If `v` does not serialise as one record (a nested map or sequence): a bug of the type.
pub fn of_serialized<T: serde::Serialize>(v: &T) -> NamedRow {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.serialize(v).expect("a row of plain fields serialises");
    let bytes = w.into_inner().expect("writing to memory cannot fail");
    let mut r = csv::Reader::from_reader(&bytes[..]);
    let names = r.headers().expect("the header just written").clone();
    let rec = r
        .records()
        .next()
        .expect("one record")
        .expect("the record just written");
    let mut out = NamedRow::new();
    for (n, v) in names.iter().zip(rec.iter()) {
        out.push(n, v);
    }
    out
}

/// Reads rows written by [`write_csv`] (every column of the header, empty cells kept).
pub fn read_csv(path: &Path) -> Result<Vec<NamedRow>> {
    let mut r = csv::Reader::from_path(path).map_err(Error::csv(path))?;
    let names: Vec<String> = r
        .headers()
        .map_err(Error::csv(path))?
        .iter()
        .map(String::from)
        .collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(Error::csv(path))?;
        let mut row = NamedRow::new();
        for (n, v) in names.iter().zip(rec.iter()) {
            row.push(n.clone(), v);
        }
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(cols: &[(&str, &str)]) -> NamedRow {
        let mut r = NamedRow::new();
        for (n, v) in cols {
            r.push(*n, v);
        }
        r
    }

    #[test]
    fn header_is_the_ordered_union() {
        let a = row(&[("scene", "s"), ("method", "m"), ("estimate_s", "1")]);
        let b = row(&[
            ("scene", "s"),
            ("method", "m"),
            ("res", "64"),
            ("estimate_s", "2"),
        ]);
        let c = row(&[("scene", "t"), ("tail", "x")]);
        assert_eq!(
            header(&[a, b, c]),
            ["scene", "tail", "method", "res", "estimate_s"]
        );
    }

    #[test]
    fn csv_round_trip_keeps_order_and_empty_cells() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let mut a = row(&[("scene", "s,1"), ("x", "1.5")]);
        a.push_opt::<f64>("y", None);
        let b = row(&[("scene", "q\"uote"), ("z", "3")]);
        write_csv(&p, &[a.clone(), b.clone()]).unwrap();
        let back = read_csv(&p).unwrap();
        assert_eq!(back[0].get("scene"), Some("s,1"));
        assert_eq!(back[0].number("x"), Some(1.5));
        assert_eq!(back[0].get("y"), Some(""));
        assert_eq!(back[0].get("z"), Some(""));
        assert_eq!(back[1].get("scene"), Some("q\"uote"));
        assert_eq!(back[1].number("z"), Some(3.0));
        let names: Vec<&str> = back[1].columns().map(|(n, _)| n).collect();
        assert_eq!(names, ["scene", "z", "x", "y"]);
    }

    #[test]
    #[should_panic(expected = "added twice")]
    fn a_column_named_twice_is_a_bug() {
        row(&[("a", "1"), ("a", "2")]);
    }
}
