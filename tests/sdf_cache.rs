//! The distance volumes' cache (`sdf::cache`): a second request hits and reads the same
//! volume bit for bit; a lower precision is derived from the cached f32 volume without a bake;
//! a truncated, corrupted, re-versioned or misplaced file is reported and rebaked, never
//! trusted; an edited mesh misses (another key, another file); nothing is left half-written.

use glam::Vec3;
use std::path::Path;
use visfield::geometry::procedural::uv_sphere;
use visfield::sdf::cache::{load, load_or_bake, save, CacheError, CacheKey, Outcome};
use visfield::sdf::{DistanceVolume, Precision};

fn tris() -> Vec<[Vec3; 3]> {
    let m = uv_sphere(1.0, 12, 24).unwrap();
    (0..m.triangle_count()).map(|i| m.triangle(i)).collect()
}

const SHA: &str = "0123456789abcdef";
const GRID: (usize, usize) = (16, 2);

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_second_request_hits_and_lower_precisions_derive_without_a_bake() {
    let dir = tempfile::tempdir().unwrap();
    let t = tris();
    let (v, o) = load_or_bake(dir.path(), &t, SHA, GRID, Precision::F32).unwrap();
    assert!(matches!(&o, Outcome::Baked { rejected, .. } if rejected.is_empty()));
    assert!(!o.cached());
    assert_eq!(v, DistanceVolume::bake(&t, GRID.0, GRID.1).unwrap());
    let (again, o) = load_or_bake(dir.path(), &t, SHA, GRID, Precision::F32).unwrap();
    assert!(matches!(o, Outcome::Hit(_)) && o.cached());
    assert_eq!(again, v);
    for p in [Precision::F16, Precision::U8] {
        let (q, o) = load_or_bake(dir.path(), &t, SHA, GRID, p).unwrap();
        assert!(
            matches!(&o, Outcome::Derived { rejected, .. } if rejected.is_empty()),
            "{o:?}"
        );
        assert_eq!(q, v.with_precision(p));
        let (q2, o) = load_or_bake(dir.path(), &t, SHA, GRID, p).unwrap();
        assert!(matches!(o, Outcome::Hit(_)));
        assert_eq!(q2, q);
    }
    // Three files, named by their axes, and no temporary left.
    let names = files(dir.path());
    assert_eq!(names.len(), 3, "{names:?}");
    for p in ["f32", "f16", "u8"] {
        assert!(
            names
                .iter()
                .any(|n| n.starts_with(&format!("sdf-16-m2-{p}-")) && n.ends_with(".vsdf")),
            "{names:?}"
        );
    }
}

#[test]
fn a_damaged_file_is_reported_and_rebaked() {
    let dir = tempfile::tempdir().unwrap();
    let t = tris();
    let key = CacheKey::new(SHA, GRID.0, GRID.1, Precision::F32);
    let path = dir.path().join(key.file_name());
    let (v, _) = load_or_bake(dir.path(), &t, SHA, GRID, Precision::F32).unwrap();
    let good = std::fs::read(&path).unwrap();
    let damage = |bytes: Vec<u8>, want: &str| {
        std::fs::write(&path, &bytes).unwrap();
        let e = load(&path, &key).unwrap_err().to_string();
        assert!(e.contains(want), "{e}");
        let (again, o) = load_or_bake(dir.path(), &t, SHA, GRID, Precision::F32).unwrap();
        match &o {
            Outcome::Baked { rejected, .. } => {
                assert!(rejected.len() == 1 && rejected[0].contains(want), "{o:?}")
            }
            other => panic!("{want}: {other:?}"),
        }
        assert_eq!(again, v);
        // Rewritten whole.
        assert_eq!(std::fs::read(&path).unwrap(), good);
    };
    // A flipped payload byte, a truncated payload, a cut header, another format version,
    // another magic.
    let mut flipped = good.clone();
    *flipped.last_mut().unwrap() ^= 0x40;
    damage(flipped, "checksum");
    damage(good[..good.len() - 3].to_vec(), "truncated payload");
    damage(good[..40].to_vec(), "truncated header");
    let mut version = good.clone();
    version[8] = 99;
    damage(version, "format version 99");
    let mut magic = good.clone();
    magic[0] = b'X';
    damage(magic, "bad magic");
    // Another key's file under this key's name: stale.
    let other = CacheKey::new(SHA, GRID.0, 3, Precision::F32);
    let w = DistanceVolume::bake(&t, GRID.0, 3).unwrap();
    save(&path, &other, &w).unwrap();
    assert!(matches!(load(&path, &key), Err(CacheError::Stale { .. })));
    let (again, o) = load_or_bake(dir.path(), &t, SHA, GRID, Precision::F32).unwrap();
    assert!(!o.cached() && o.rejected()[0].contains("key"), "{o:?}");
    assert_eq!(again, v);
    // A damaged u8 file beside a good f32 one: derived again, no bake.
    let (_, _) = load_or_bake(dir.path(), &t, SHA, GRID, Precision::U8).unwrap();
    let u8_path = dir
        .path()
        .join(CacheKey::new(SHA, GRID.0, GRID.1, Precision::U8).file_name());
    let mut bytes = std::fs::read(&u8_path).unwrap();
    bytes.truncate(bytes.len() - 1);
    std::fs::write(&u8_path, bytes).unwrap();
    let (q, o) = load_or_bake(dir.path(), &t, SHA, GRID, Precision::U8).unwrap();
    assert!(
        matches!(&o, Outcome::Derived { rejected, .. } if rejected[0].contains("truncated")),
        "{o:?}"
    );
    assert_eq!(q, v.with_precision(Precision::U8));
}

#[test]
fn an_edited_mesh_misses() {
    let dir = tempfile::tempdir().unwrap();
    let t = tris();
    load_or_bake(dir.path(), &t, SHA, GRID, Precision::U8).unwrap();
    let before = files(dir.path());
    // The harness keys by the sha256 of the model-space mesh: an edit changes it.
    let mut m = uv_sphere(1.0, 12, 24).unwrap();
    let sha = visfield::experiment::scenes::mesh_sha256(&m);
    m.positions[5] *= 1.1;
    let edited = visfield::experiment::scenes::mesh_sha256(&m);
    assert_ne!(sha, edited);
    let t2: Vec<[Vec3; 3]> = (0..m.triangle_count()).map(|i| m.triangle(i)).collect();
    let (v, o) = load_or_bake(dir.path(), &t2, &edited, GRID, Precision::U8).unwrap();
    assert!(
        matches!(&o, Outcome::Baked { rejected, .. } if rejected.is_empty()),
        "{o:?}"
    );
    assert_eq!(
        v,
        DistanceVolume::bake(&t2, GRID.0, GRID.1)
            .unwrap()
            .with_precision(Precision::U8)
    );
    // The first mesh's files untouched, two new ones beside them.
    let after = files(dir.path());
    assert_eq!(after.len(), before.len() + 2);
    assert!(before.iter().all(|f| after.contains(f)));
}
