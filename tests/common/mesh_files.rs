//! Mesh files for the hostile-input tests: a unit tetrahedron as OBJ, ASCII and binary PLY,
//! headers to splice, the loader's error on a file, and a spec run on a file.

use std::path::PathBuf;
use visfield::experiment::run::{run, LoadedSpec};
use visfield::geometry::Mesh;

/// `bytes` written to a fresh folder as `name`; the folder lives as long as the guard.
pub fn file(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    (dir, p)
}

/// The loader's error on `bytes` as `name`, asserted to name the file and every `parts`.
pub fn refused(name: &str, bytes: &[u8], parts: &[&str]) -> String {
    let (_dir, p) = file(name, bytes);
    let e = Mesh::load_file(&p, &|_| {})
        .expect_err("the file should be refused")
        .to_string();
    assert!(e.contains(&p.display().to_string()), "{e}");
    for part in parts {
        assert!(e.contains(part), "`{part}` missing from: {e}");
    }
    eprintln!("{name}: {e}");
    e
}

pub const TETRA_OBJ: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";

/// An ASCII PLY of a tetrahedron; `vertices` and `faces` replace the header's counts and
/// `body` the data.
pub fn ascii_ply(vertices: usize, faces: usize, body: &str) -> String {
    format!(
        "ply\nformat ascii 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\n\
         property float z\nelement face {faces}\nproperty list uchar int vertex_indices\n\
         end_header\n{body}"
    )
}

pub const TETRA_BODY: &str = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 2 3\n3 1 2 3\n";

/// A binary little-endian PLY header for `v` vertices and `f` faces.
pub fn binary_header(v: usize, f: usize) -> Vec<u8> {
    format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {v}\nproperty float x\n\
         property float y\nproperty float z\nelement face {f}\n\
         property list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes()
}

/// The binary tetrahedron's body: 4 vertices (12 bytes each), 4 faces (13 bytes each).
pub fn binary_tetra_body() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in [[0i32, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
        b.push(3);
        for i in t {
            b.extend_from_slice(&i.to_le_bytes());
        }
    }
    b
}

pub fn binary_tetra() -> Vec<u8> {
    let mut b = binary_header(4, 4);
    b.extend_from_slice(&binary_tetra_body());
    b
}

/// The quickstart spec with its caster replaced by the mesh file `name` (written with
/// `bytes` beside the spec), run with `memory_limit` into `dir/out`: the error's chain, and
/// whether the run left an output folder.
pub fn run_on_file(
    dir: &std::path::Path,
    name: &str,
    bytes: &[u8],
    memory_limit: u64,
) -> (String, bool) {
    std::fs::write(dir.join(name), bytes).unwrap();
    let spec = include_str!("../../src/experiment/quickstart.json").replace(
        r#"{"supershape": {"triangles": 10000}}"#,
        &format!(r#"{{"file": "{name}"}}"#),
    );
    assert!(spec.contains(name));
    let path = dir.join("s.json");
    std::fs::write(&path, spec).unwrap();
    let ls = LoadedSpec::load(&path).unwrap();
    let out = dir.join("out");
    let mut o = super::options(out.clone());
    o.supply.memory_limit = memory_limit;
    let e = run(&ls, &o).expect_err("the run should fail").chain();
    (e, out.exists())
}
