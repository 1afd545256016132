//! Hostile mesh files, OBJ and PLY: each gets one error naming the file, the line or element,
//! and what is wrong; nothing panics; a run that meets one caches nothing and leaves no output.

use std::path::Path;
use visfield::experiment::run::{run, LoadedSpec};
use visfield::geometry::Mesh;

mod common;
use common::mesh_files::{
    ascii_ply, binary_header, binary_tetra, file, refused, TETRA_BODY, TETRA_OBJ,
};
use common::options;

#[test]
fn the_well_formed_files_load() {
    for (name, bytes) in [
        ("t.obj", TETRA_OBJ.as_bytes().to_vec()),
        ("t.ply", ascii_ply(4, 4, TETRA_BODY).into_bytes()),
        ("tb.ply", binary_tetra()),
    ] {
        let (_d, p) = file(name, &bytes);
        let m = Mesh::load_file(&p, &|_| {}).unwrap();
        assert_eq!((m.vertex_count(), m.triangle_count()), (4, 4), "{name}");
        let area = 1.5 + 3f64.sqrt() / 2.0;
        assert!((m.area() - area).abs() < 1e-6, "{name}: {}", m.area());
    }
}

#[test]
fn nan_coordinates_name_the_line_or_element() {
    refused(
        "nan.obj",
        b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
        &["line 2", "non-finite"],
    );
    refused(
        "nan.ply",
        ascii_ply(4, 4, &TETRA_BODY.replacen("1 0 0", "1 nan 0", 1)).as_bytes(),
        &["vertex element 1", "non-finite"],
    );
    let mut b = binary_tetra();
    let at = binary_header(4, 4).len() + 12 * 2 + 4;
    b[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    refused("nanb.ply", &b, &["vertex element 2", "non-finite"]);
}

#[test]
fn infinite_coordinates_name_the_line_or_element() {
    refused(
        "inf.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n",
        &["line 3", "non-finite"],
    );
    // 1e39 is finite in the text but not as the f32 a mesh holds.
    refused(
        "inf.ply",
        ascii_ply(4, 4, &TETRA_BODY.replacen("0 0 1", "0 0 1e39", 1)).as_bytes(),
        &["vertex element 3", "non-finite"],
    );
}

#[test]
fn out_of_range_and_zero_indices_are_refused() {
    refused(
        "oob.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
        &["out of"],
    );
    refused(
        "zero.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        &["line 4", "out of bounds"],
    );
    refused(
        "oob.ply",
        ascii_ply(4, 4, &TETRA_BODY.replacen("3 1 2 3", "3 1 2 4", 1)).as_bytes(),
        &[
            "face element 3",
            "vertex index 4 (item 2 of its `vertex_indices`) out of range",
            "the header declares 4 vertices",
        ],
    );
    refused(
        "neg.ply",
        ascii_ply(4, 4, &TETRA_BODY.replacen("3 0 1 2", "3 0 -1 2", 1)).as_bytes(),
        &["face element 0", "vertex index -1"],
    );
    refused(
        "two.ply",
        ascii_ply(4, 4, &TETRA_BODY.replacen("3 0 1 2", "2 0 1", 1)).as_bytes(),
        &["face element 0", "at least 3"],
    );
}

#[test]
fn only_degenerate_triangles_are_refused() {
    refused(
        "flat.obj",
        b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n",
        &["no triangles"],
    );
    refused(
        "flat.ply",
        ascii_ply(3, 2, "0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n3 0 0 1\n").as_bytes(),
        &["no triangles left (2 given, 2 dropped"],
    );
}

#[test]
fn files_without_faces_are_refused() {
    refused(
        "nofaces.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\n",
        &["no triangles"],
    );
    refused(
        "nofaces.ply",
        ascii_ply(4, 0, "0 0 0\n1 0 0\n0 1 0\n0 0 1\n").as_bytes(),
        &["no triangles"],
    );
    let header_only = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n\
                       property float y\nproperty float z\nend_header\n0 0 0\n";
    refused("noface.ply", header_only.as_bytes(), &["no `face` element"]);
}

#[test]
fn binary_junk_is_refused() {
    // Deterministic junk: an xorshift stream, with a NUL and invalid UTF-8 early.
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let junk: Vec<u8> = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect();
    refused("junk.obj", &junk, &["line 1", "not text"]);
    refused("junk.ply", &junk, &["not a PLY file"]);
    // A PLY header followed by junk that is not its body.
    let mut b = ascii_ply(4, 4, "").into_bytes();
    b.extend_from_slice(&junk);
    refused("junkbody.ply", &b, &[]);
}

#[test]
fn a_ply_header_that_lies_about_its_counts_is_refused() {
    // More elements than the body holds: refused before anything is allocated for them.
    refused(
        "more.ply",
        ascii_ply(4, 1_000_000_000, TETRA_BODY).as_bytes(),
        &["1000000000 `face` elements", "bytes follow"],
    );
    let mut b = binary_tetra();
    let lie = binary_header(4, 4_000_000_000);
    b.splice(..binary_header(4, 4).len(), lie);
    refused("moreb.ply", &b, &["4000000000 `face` elements"]);
    // Fewer: the body goes on past what the header declares.
    refused(
        "fewer.ply",
        ascii_ply(4, 3, TETRA_BODY).as_bytes(),
        &["line 17", "data after the last element"],
    );
    let mut b = binary_tetra();
    b.splice(..binary_header(4, 4).len(), binary_header(4, 3));
    refused("fewerb.ply", &b, &["13 bytes after the last element"]);
}

#[test]
fn truncated_files_are_refused() {
    let whole = binary_tetra();
    for cut in [
        whole.len() - 1,
        whole.len() - 13,
        binary_header(4, 4).len() + 20,
    ] {
        refused("cut.ply", &whole[..cut], &["truncated"]);
    }
    let text = ascii_ply(4, 4, TETRA_BODY);
    refused(
        "cut_ascii.ply",
        &text.as_bytes()[..text.len() - 8],
        &["truncated"],
    );
    refused(
        "cut_line.ply",
        &text.as_bytes()[..text.len() - 3],
        &["line 17", "face element 3", "no vertex_indices"],
    );
    // An OBJ cut inside a face line: an error, or fewer whole faces (tests in geometry::obj).
    refused("cut.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2", &[]);
    refused("cut_header.ply", &whole[..30], &["end_header"]);
}

/// A hostile file named by a spec: the run fails naming the spec's field and the file, caches
/// nothing and writes no output folder.
#[test]
fn a_run_on_a_hostile_file_caches_nothing_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("bad.ply"),
        ascii_ply(4, 4, &TETRA_BODY.replacen("3 1 2 3", "3 1 2 9", 1)),
    )
    .unwrap();
    let spec = include_str!("../src/experiment/quickstart.json").replace(
        r#"{"supershape": {"triangles": 10000}}"#,
        r#"{"file": "bad.ply"}"#,
    );
    assert!(spec.contains("bad.ply"));
    let path = dir.path().join("s.json");
    std::fs::write(&path, spec).unwrap();
    let ls = LoadedSpec::load(&path).unwrap();
    let cache = dir.path().join("cache");
    let out = dir.path().join("out");
    let mut o = options(out.clone());
    o.supply.cache = Some(cache.clone());
    let e = run(&ls, &o).unwrap_err().chain();
    assert!(
        e.contains("scenes[0].instances[1].mesh")
            && e.contains("bad.ply")
            && e.contains("face element 3"),
        "{e}"
    );
    assert!(!out.exists(), "no output folder");
    let cached: Vec<_> = std::fs::read_dir(&cache).map_or(Vec::new(), |d| d.collect());
    assert!(cached.is_empty(), "cached: {cached:?}");
}

/// A file too big for the memory limit is refused from its sizes, before it is loaded.
#[test]
fn a_mesh_past_the_memory_limit_is_refused_with_its_sizes_before_loading() {
    let dir = tempfile::tempdir().unwrap();
    // The header claims 5 M faces; the body is there in size (zeros) but is never parsed.
    let mut b = binary_header(3, 5_000_000);
    b.resize(b.len() + 36 + 5_000_000, 0);
    std::fs::write(dir.path().join("big.ply"), &b).unwrap();
    let spec = include_str!("../src/experiment/quickstart.json").replace(
        r#"{"supershape": {"triangles": 10000}}"#,
        r#"{"file": "big.ply"}"#,
    );
    let path = dir.path().join("s.json");
    std::fs::write(&path, spec).unwrap();
    let ls = LoadedSpec::load(&path).unwrap();
    let mut o = options(dir.path().join("out"));
    o.supply.memory_limit = 256 << 20;
    let t = std::time::Instant::now();
    let e = run(&ls, &o).unwrap_err().chain();
    assert!(
        e.contains("big.ply") && e.contains("5000000 triangles") && e.contains("memory limit"),
        "{e}"
    );
    assert!(
        t.elapsed().as_secs_f64() < 5.0,
        "refused only after {:?}",
        t.elapsed()
    );
}

#[test]
fn a_missing_file_names_the_field_and_the_resolved_path() {
    // A missing file: the spec's field, the resolved path and the OS error.
    let dir = tempfile::tempdir().unwrap();
    let spec = include_str!("../src/experiment/quickstart.json").replace(
        r#"{"supershape": {"triangles": 10000}}"#,
        r#"{"file": "sub/missing.obj"}"#,
    );
    let path = dir.path().join("s.json");
    std::fs::write(&path, spec).unwrap();
    let ls = LoadedSpec::load(&path).unwrap();
    let e = run(&ls, &options(dir.path().join("out")))
        .unwrap_err()
        .chain();
    let resolved: &Path = &dir.path().join("sub/missing.obj");
    assert!(
        e.contains("instances[1].mesh.file") && e.contains(&resolved.display().to_string()),
        "{e}"
    );
}

/// A short mutation campaign (the properties of the `ply` and `obj` fuzz targets,
/// deterministic): byte flips, interesting bytes, deleted, repeated and cut ranges of valid
/// files; each result is a valid mesh or an error naming the file, never a panic.
#[test]
fn mutated_files_load_or_are_refused_never_panic() {
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move |n: usize| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x % n.max(1) as u64) as usize
    };
    let mut quad_be = binary_header(4, 1).replace_ascii("little", "big");
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        for c in p {
            quad_be.extend_from_slice(&c.to_be_bytes());
        }
    }
    quad_be.push(4);
    for i in 0..4i32 {
        quad_be.extend_from_slice(&i.to_be_bytes());
    }
    let seeds: Vec<(&str, Vec<u8>)> = vec![
        ("m.ply", ascii_ply(4, 4, TETRA_BODY).into_bytes()),
        ("m.ply", binary_tetra()),
        ("m.ply", quad_be),
        ("m.obj", TETRA_OBJ.as_bytes().to_vec()),
    ];
    let dir = tempfile::tempdir().unwrap();
    let (mut loaded, mut refused) = (0, 0);
    for (name, seed) in &seeds {
        let path = dir.path().join(name);
        for _ in 0..1500 {
            let mut b = seed.clone();
            for _ in 0..1 + rnd(4) {
                let at = rnd(b.len());
                match rnd(5) {
                    0 => b[at] ^= 1 << rnd(8),
                    1 => b[at] = [0, 0xff, b'\n', b' ', b'-', b'9', b'e', 0x80][rnd(8)],
                    2 => {
                        let end = (at + 1 + rnd(8)).min(b.len());
                        b.drain(at..end);
                    }
                    3 => {
                        let end = (at + 1 + rnd(8)).min(b.len());
                        let piece = b[at..end].to_vec();
                        b.splice(at..at, piece);
                    }
                    _ => b.truncate(at),
                }
                if b.is_empty() {
                    break;
                }
            }
            let result = if name.ends_with(".ply") {
                Mesh::ply_from_bytes(&b, &path)
            } else {
                std::fs::write(&path, &b).unwrap();
                Mesh::load_obj(&path)
            };
            match result {
                Ok(m) => {
                    assert!(m.triangle_count() > 0);
                    let s = m.bounding_sphere();
                    assert!(s.radius.is_finite() && s.radius > 0.0, "{s:?}");
                    assert!(m.normals.iter().all(|n| n.is_finite()));
                    loaded += 1;
                }
                Err(e) => {
                    let e = e.to_string();
                    assert!(e.starts_with(&path.display().to_string()), "{e}");
                    refused += 1;
                }
            }
        }
    }
    eprintln!("mutation campaign: {loaded} loaded, {refused} refused");
    // Both outcomes occur: the campaign reaches past the header checks.
    assert!(
        loaded > 100 && refused > 100,
        "{loaded} loaded, {refused} refused"
    );
}

trait ReplaceAscii {
    fn replace_ascii(self, from: &str, to: &str) -> Vec<u8>;
}

impl ReplaceAscii for Vec<u8> {
    fn replace_ascii(self, from: &str, to: &str) -> Vec<u8> {
        String::from_utf8(self)
            .unwrap()
            .replace(from, to)
            .into_bytes()
    }
}
