//! The field cache shared by concurrent writers: eight threads save the same key over and over
//! while readers load it; every load sees either no file yet or a whole, valid field equal to
//! the one saved, and the file left at the end is valid. (Processes write through the same
//! `io::write_atomic`; their temporaries differ by process id and host as the threads' differ
//! by a counter: see `tests/shard.rs` for shards of one spec sharing a cache.)

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use visfield::field::bake::BakeOptions;
use visfield::field::cache::{load, load_or_bake, save, CacheError, CacheKey};
use visfield::field::{FieldParams, Precision};
use visfield::geometry::procedural;
use visfield::sampling::{LayoutKind, SphereKind};

#[test]
fn concurrent_writers_of_one_key_leave_every_reader_a_whole_file() {
    let params = FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 16,
        precision: Precision::U8,
    };
    let mesh = procedural::cube_with_hole(1.0, 0.4).unwrap();
    let baked = tempfile::tempdir().unwrap();
    let (field, _) = load_or_bake(
        baked.path(),
        &mesh,
        "sha-a",
        params,
        &BakeOptions::default(),
    )
    .unwrap();
    let key = CacheKey::new("sha-a", params);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(key.file_name());
    // The bytes of one whole save, to compare every read against.
    let reference = baked.path().join("reference.vfield");
    save(&reference, &key, &field).unwrap();
    let whole = std::fs::read(&reference).unwrap();
    let (done, writes, whole_reads) = (
        AtomicBool::new(false),
        AtomicUsize::new(0),
        AtomicUsize::new(0),
    );
    std::thread::scope(|s| {
        for _ in 0..8 {
            s.spawn(|| {
                for _ in 0..25 {
                    save(&path, &key, &field).expect("a concurrent save succeeds");
                    writes.fetch_add(1, Ordering::Relaxed);
                }
            });
        }
        for _ in 0..2 {
            s.spawn(|| {
                while !done.load(Ordering::Relaxed) {
                    match std::fs::read(&path) {
                        Ok(bytes) => {
                            assert!(bytes == whole, "a reader saw a partial or mixed file");
                            whole_reads.fetch_add(1, Ordering::Relaxed);
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                        Err(e) => panic!("{e}"),
                    }
                    match load(&path, &key) {
                        Ok(_) => {}
                        Err(CacheError::Io { source, .. })
                            if source.kind() == std::io::ErrorKind::NotFound => {}
                        Err(e) => panic!("a reader saw a damaged file: {e}"),
                    }
                }
            });
        }
        while writes.load(Ordering::Relaxed) < 200 {
            std::thread::yield_now();
        }
        done.store(true, Ordering::Relaxed);
    });
    assert_eq!(writes.load(Ordering::Relaxed), 200);
    assert!(
        whole_reads.load(Ordering::Relaxed) > 0,
        "no reader saw the file"
    );
    load(&path, &key).expect("the final file is valid");
    assert!(std::fs::read(&path).unwrap() == whole);
    // No temporary is left behind.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from(key.file_name())]);
}
