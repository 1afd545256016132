//! Rewrites the FLIP maps of finished runs (`images/*-flip.png`, `images/*-flip_vs_truth.png`
//! under the folder given, default `results`) as the indexed PNGs the harness writes now
//! (`flip::indexed_png`: the same pixels, about a third of an RGB file's bytes), checking that
//! each file reads back to the same pixels before it replaces the old one.
//!
//! `cargo run --release --example repack_flip_maps [-- FOLDER]`

use std::path::{Path, PathBuf};
use visfield::experiment::flip::indexed_png;

fn maps(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if p.is_dir() {
            maps(&p, out);
        } else if name.ends_with("-flip.png") || name.ends_with("-flip_vs_truth.png") {
            out.push(p);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "results".into()));
    let mut found = Vec::new();
    maps(&root, &mut found);
    found.sort();
    let (mut before, mut after, mut kept) = (0u64, 0u64, 0);
    for p in &found {
        let old = std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let img = image::load_from_memory(&old)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
            .to_rgb8();
        let Some(new) = indexed_png(img.width(), img.height(), img.as_raw()) else {
            kept += 1;
            continue;
        };
        let back = image::load_from_memory(&new).unwrap().to_rgb8();
        assert_eq!(
            back.as_raw(),
            img.as_raw(),
            "{}: pixels differ",
            p.display()
        );
        if new.len() < old.len() {
            visfield::io::write_atomic(p, &new).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (before, after) = (before + old.len() as u64, after + new.len() as u64);
        } else {
            kept += 1;
        }
    }
    println!(
        "{} FLIP maps under {}: {:.1} MB -> {:.1} MB ({kept} kept as they were)",
        found.len(),
        root.display(),
        before as f64 / 1e6,
        after as f64 / 1e6
    );
}
