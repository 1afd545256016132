//! `--shard I/N`: a deterministic share of a spec's cells, for running one spec's cells on
//! several machines (or processes) at once.
//!
//! The assignment: the spec profile's cells in plan order ([`super::cells::cells_of`]: scenes ×
//! field settings × backends, duplicates dropped) are cut into `N` contiguous blocks, positions
//! `⌊(I−1)·n/N⌋ .. ⌊I·n/N⌋` for shard `I` (1-based); then each field group (a scene's cells
//! that read one bake: the same scene and field geometry, every precision, selection, backend
//! and normal-field precision) goes whole to the shard whose block holds its first cell
//! ([`Shard::select_groups`]). So no bake is repeated across shards, and every pair of
//! `pairs.csv` (cells that differ only in precision, always in one group) is measured in one
//! shard. It depends only on the spec and the profile, never on the thread count or the
//! machine, and every cell lies in exactly one shard (some shards are empty when `N` exceeds
//! the groups). Where a group's cells are contiguous in plan order (one `fields` entry holds
//! them all), shards stay contiguous blocks of it.
//!
//! A shard plans only its cells: the planner bakes the fields those cells read and nothing
//! else. The per-scene steps (the ray-cast reference, its sweep, the converged reference) run
//! in every shard that holds one of the scene's cells; the converged reference is served from
//! the same on-disk cache under the same key (`truth_cache`: the points, the casters, the
//! estimator's options; no shard enters the key), so shards sharing a cache folder compute it
//! once where they do not race, and identically where they do.

use super::cells::{cells_of, Cell};
use super::spec::Spec;
use super::{Error, Result};
use serde::Serialize;

/// Shard `index` of `count` (1 ≤ index ≤ count).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Parses `I/N` as given to `flag`; refuses non-numbers, `N = 0`, `I = 0` and `I > N`,
    /// naming the flag and the value.
    pub fn parse(value: &str, flag: &str) -> Result<Shard> {
        let bad = |why: &str| {
            Error::invalid(
                flag,
                format!("`{value}`: {why} (expected I/N with 1 ≤ I ≤ N, e.g. 2/3)"),
            )
        };
        let (i, n) = value.split_once('/').ok_or_else(|| bad("no `/`"))?;
        let number = |s: &str, what: &str| {
            s.trim()
                .parse::<usize>()
                .map_err(|_| bad(&format!("{what} `{s}` is not a whole number")))
        };
        let (index, count) = (number(i, "I")?, number(n, "N")?);
        if count == 0 {
            return Err(bad("N is 0"));
        }
        if index == 0 || index > count {
            return Err(bad(&format!("I must lie in 1..={count}")));
        }
        Ok(Shard { index, count })
    }

    /// The range of plan-order positions this shard takes out of `n` cells.
    pub fn range(&self, n: usize) -> std::ops::Range<usize> {
        let at = |k: usize| (k as u128 * n as u128 / self.count as u128) as usize;
        at(self.index - 1)..at(self.index)
    }

    /// Keeps this shard's share of `cells` (in plan order), a group at a time: a group (the
    /// cells with one `group` key) goes whole to the shard whose block of positions
    /// ([`Self::range`]) holds its first cell. The cells keep their plan order.
    pub fn select_groups<T, K: PartialEq>(&self, cells: Vec<T>, group: impl Fn(&T) -> K) -> Vec<T> {
        let r = self.range(cells.len());
        let keys: Vec<K> = cells.iter().map(&group).collect();
        let first = |i: usize| keys.iter().position(|k| *k == keys[i]).expect("own key");
        cells
            .into_iter()
            .enumerate()
            .filter(|(i, _)| r.contains(&first(*i)))
            .map(|(_, c)| c)
            .collect()
    }

    /// `I/N`, as the flag takes it.
    pub fn label(&self) -> String {
        format!("{}/{}", self.index, self.count)
    }
}

/// `cells` unchanged without a shard, else the shard's share, a `group` at a time
/// ([`Shard::select_groups`]).
pub fn select<T, K: PartialEq>(
    cells: Vec<T>,
    shard: Option<Shard>,
    group: impl Fn(&T) -> K,
) -> Vec<T> {
    match shard {
        Some(s) => s.select_groups(cells, group),
        None => cells,
    }
}

/// The cells of `spec` (a profile's) that `shard` runs, in plan order (every cell without a
/// shard): the field groups, a scene's cells of one field geometry, whose first cell lies in
/// the shard's block. The planner's selection (`Plan::new_shard`), and what `experiment merge`
/// checks each shard's rows against.
pub fn cells(spec: &Spec, shard: Option<Shard>) -> Vec<Cell> {
    select(cells_of(spec), shard, |c| (c.scene, c.geometry()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_cell_lies_in_exactly_one_shard_in_plan_order() {
        for n in 0..40usize {
            for count in 1..12usize {
                let cells: Vec<usize> = (0..n).collect();
                let mut joined = Vec::new();
                for index in 1..=count {
                    let share = Shard { index, count }.select_groups(cells.clone(), |c| *c);
                    // Block sizes differ by at most one.
                    assert!(share.len() == n / count || share.len() == n.div_ceil(count));
                    joined.extend(share);
                }
                assert_eq!(joined, cells, "n = {n}, N = {count}");
            }
        }
    }

    #[test]
    fn the_blocks_are_the_closed_form() {
        // 10 cells in 3 shards: ⌊10k/3⌋ = 0, 3, 6, 10.
        let s = |index| Shard { index, count: 3 }.range(10);
        assert_eq!((s(1), s(2), s(3)), (0..3, 3..6, 6..10));
        assert_eq!(select(vec![1, 2, 3], None, |c| *c), vec![1, 2, 3]);
    }

    #[test]
    fn groups_go_whole_to_the_shard_of_their_first_cell() {
        // Groups of 1–4 cells, contiguous or interleaved, over 1–9 shards.
        let layouts: [&[u8]; 5] = [
            b"aabbbccccd",
            b"abababcc",
            b"aaaaaaa",
            b"abcdefgh",
            b"abcabcddda",
        ];
        for keys in layouts {
            let cells: Vec<(usize, u8)> = keys.iter().copied().enumerate().collect();
            for count in 1..10usize {
                let mut joined = Vec::new();
                let mut owner = std::collections::HashMap::new();
                for index in 1..=count {
                    let sh = Shard { index, count };
                    let share = sh.select_groups(cells.clone(), |c| c.1);
                    // Plan order kept within a shard.
                    assert!(share.windows(2).all(|w| w[0].0 < w[1].0));
                    for c in &share {
                        // A group lies in one shard, the one whose block holds its first cell.
                        assert_eq!(*owner.entry(c.1).or_insert(index), index, "{keys:?}");
                        let first = keys.iter().position(|k| *k == c.1).unwrap();
                        assert!(sh.range(cells.len()).contains(&first));
                    }
                    joined.extend(share);
                }
                joined.sort();
                assert_eq!(joined, cells, "{keys:?}, N = {count}");
            }
        }
        // Contiguous groups: "aabbbccccd" in 3 blocks 0..3, 3..6, 6..10 → a, b | c | d.
        let cells: Vec<(usize, u8)> = b"aabbbccccd".iter().copied().enumerate().collect();
        let share = |index| {
            Shard { index, count: 3 }
                .select_groups(cells.clone(), |c| c.1)
                .iter()
                .map(|c| c.0)
                .collect::<Vec<_>>()
        };
        assert_eq!(share(1), vec![0, 1, 2, 3, 4]);
        assert_eq!(share(2), vec![5, 6, 7, 8]);
        assert_eq!(share(3), vec![9]);
    }

    #[test]
    fn parse_accepts_i_of_n_and_refuses_the_rest_naming_flag_and_value() {
        assert_eq!(
            Shard::parse("2/3", "--shard").unwrap(),
            Shard { index: 2, count: 3 }
        );
        assert_eq!(
            Shard::parse("1/1", "--shard").unwrap().label(),
            "1/1".to_string()
        );
        for bad in [
            "0/3", "4/3", "1/0", "0/0", "a/3", "1/b", "3", "", "-1/3", "1.5/3",
        ] {
            let e = Shard::parse(bad, "--shard").unwrap_err().chain();
            assert!(e.contains("--shard"), "{bad}: {e}");
            assert!(e.contains(&format!("`{bad}`")), "{bad}: {e}");
        }
    }
}
