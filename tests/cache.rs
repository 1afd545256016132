//! The on-disk field cache: round trip, and every kind of damage detected and rebaked.

use visfield::field::bake::BakeOptions;
use visfield::field::cache::{load, load_or_bake, save, CacheKey, CacheOutcome, FORMAT_VERSION};
use visfield::field::{FieldParams, Precision};
use visfield::geometry::procedural;
use visfield::sampling::{LayoutKind, SphereKind};

fn params(precision: Precision) -> FieldParams {
    FieldParams {
        sphere: SphereKind::Slater,
        count: 290,
        layout: LayoutKind::Concentric,
        res: 16,
        precision,
    }
}

#[test]
fn every_precision_round_trips_through_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = procedural::cube_with_hole(1.0, 0.4).unwrap();
    for p in [
        Precision::F32,
        Precision::U16,
        Precision::U8,
        Precision::Bit1,
    ] {
        let (field, outcome) = load_or_bake(
            dir.path(),
            &mesh,
            "sha-a",
            params(p),
            &BakeOptions::default(),
        )
        .unwrap();
        assert!(matches!(
            outcome,
            CacheOutcome::Baked { rejected: None, .. }
        ));
        let (again, outcome) = load_or_bake(
            dir.path(),
            &mesh,
            "sha-a",
            params(p),
            &BakeOptions::default(),
        )
        .unwrap();
        assert!(
            matches!(outcome, CacheOutcome::Hit(_)),
            "{p:?}: {outcome:?}"
        );
        assert_eq!(again.storage, field.storage, "{p:?}");
        assert_eq!(again.bounds, field.bounds);
    }
}

/// Truncation, a flipped payload byte, a wrong magic, another format version and a key for
/// another mesh are each detected, reported, and the field rebaked and rewritten.
#[test]
fn damaged_cache_files_are_detected_and_rebaked() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = procedural::cube_with_hole(1.0, 0.4).unwrap();
    let p = params(Precision::U8);
    let (field, outcome) =
        load_or_bake(dir.path(), &mesh, "sha-a", p, &BakeOptions::default()).unwrap();
    let CacheOutcome::Baked { path, .. } = outcome else {
        panic!("first call must bake")
    };
    let good = std::fs::read(&path).unwrap();
    type Damage = Box<dyn Fn(&mut Vec<u8>)>;
    let damages: Vec<(&str, Damage)> = vec![
        ("truncated payload", Box::new(|b| b.truncate(b.len() - 10))),
        ("truncated header", Box::new(|b| b.truncate(20))),
        (
            "checksum mismatch",
            Box::new(|b| *b.last_mut().unwrap() ^= 0x40),
        ),
        ("bad magic", Box::new(|b| b[0] = b'X')),
        (
            "format version",
            Box::new(|b| b[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes())),
        ),
    ];
    for (what, damage) in &damages {
        let mut bytes = good.clone();
        damage(&mut bytes);
        std::fs::write(&path, &bytes).unwrap();
        let key = CacheKey::new("sha-a", p);
        let err = load(&path, &key).expect_err(what).to_string();
        assert!(err.contains(&path.display().to_string()), "{what}: {err}");
        let (rebaked, outcome) =
            load_or_bake(dir.path(), &mesh, "sha-a", p, &BakeOptions::default()).unwrap();
        match outcome {
            CacheOutcome::Baked {
                rejected: Some(reason),
                ..
            } => assert!(!reason.is_empty(), "{what}"),
            other => panic!("{what}: expected a rebake, got {other:?}"),
        }
        assert_eq!(rebaked.storage, field.storage, "{what}");
        // The rewritten file is whole again.
        assert_eq!(std::fs::read(&path).unwrap(), good, "{what}");
    }
    // A file saved under another key (another mesh) at this path is stale.
    let other = CacheKey::new("sha-b", p);
    save(&path, &other, &field).unwrap();
    let err = load(&path, &CacheKey::new("sha-a", p))
        .unwrap_err()
        .to_string();
    assert!(err.contains("stale"), "{err}");
}
