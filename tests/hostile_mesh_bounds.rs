//! Hostile mesh files whose work, memory or precision the file itself must bound: a PLY element
//! without properties (a count no byte pays for), a repeated element, a PLY header whose vertex
//! count disagrees with its body, an OBJ line without end, N copies of one face, a model far
//! from its file's origin; and a mutation campaign over PLY headers. Each loads as the mesh it
//! describes or is refused at once, naming the file, the element or line and the count; the
//! size precheck and the loader refuse alike.

use std::time::{Duration, Instant};
use visfield::geometry::rebase::centred_mesh;
use visfield::geometry::{Mesh, MeshFormat};
use visfield::trace::Tracer;

mod common;
use common::mesh_files::{
    ascii_ply, binary_header, binary_tetra_body, file, refused, run_on_file, TETRA_BODY, TETRA_OBJ,
};

/// `header` with `lines` inserted before its `end_header` line.
fn before_end(header: &[u8], lines: &str) -> Vec<u8> {
    let text = std::str::from_utf8(header).unwrap();
    text.replace("end_header\n", &format!("{lines}end_header\n"))
        .into_bytes()
}

/// The size precheck's error on `bytes` as `name` (a PLY's header counts).
fn precheck_refuses(name: &str, bytes: &[u8]) -> String {
    let (_dir, p) = file(name, bytes);
    MeshFormat::of(&p)
        .unwrap()
        .counts(&p)
        .expect_err("the precheck should refuse the file")
        .to_string()
}

#[test]
fn an_element_without_properties_is_refused_at_once() {
    // 303 bytes: the binary tetrahedron with a 2⁶⁴ − 1 count of nothing, which the reader
    // looped over once per instance (1.8e19 times) before.
    let junk = "element junk 18446744073709551615\n";
    let mut b = before_end(&binary_header(4, 4), junk);
    b.extend_from_slice(&binary_tetra_body());
    assert_eq!(b.len(), 303);
    let parts = [
        "header line 9",
        "element `junk`",
        "18446744073709551615 instances",
        "no properties",
    ];
    let t = Instant::now();
    refused("junk.ply", &b, &parts);
    let e = precheck_refuses("junk.ply", &b);
    assert!(parts.iter().all(|p| e.contains(p)), "{e}");
    let ascii = before_end(ascii_ply(4, 4, "").as_bytes(), junk);
    let mut ascii = ascii;
    ascii.extend_from_slice(TETRA_BODY.as_bytes());
    refused("junk_ascii.ply", &ascii, &parts);
    // A run (and its dry run: the precheck is the same) fails naming the field and the file,
    // and writes nothing.
    let dir = tempfile::tempdir().unwrap();
    let (e, out) = run_on_file(dir.path(), "junk.ply", &b, 1 << 30);
    assert!(
        e.contains("instances[1].mesh.file") && e.contains("junk.ply") && e.contains("`junk`"),
        "{e}"
    );
    assert!(!out, "no output folder");
    assert!(t.elapsed() < Duration::from_secs(10), "{:?}", t.elapsed());
    // An element without properties and a count of 0 holds nothing and is read.
    let mut zero = before_end(&binary_header(4, 4), "element junk 0\n");
    zero.extend_from_slice(&binary_tetra_body());
    let (_d, p) = file("zero.ply", &zero);
    assert_eq!(Mesh::load_file(&p, &|_| {}).unwrap().triangle_count(), 4);
}

#[test]
fn a_repeated_element_is_refused_naming_both_lines() {
    let vertex_again = "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n";
    let face_again = "element face 1\nproperty list uchar int vertex_indices\n";
    for (again, name, first, line) in [(vertex_again, "vertex", 3, 9), (face_again, "face", 7, 9)] {
        let mut b = before_end(&binary_header(4, 4), again);
        b.extend_from_slice(&binary_tetra_body());
        let parts = [
            format!("header line {line}"),
            format!("element `{name}` is declared again"),
            format!("first at header line {first}"),
        ];
        let parts: Vec<&str> = parts.iter().map(String::as_str).collect();
        refused("twice.ply", &b, &parts);
        let e = precheck_refuses("twice.ply", &b);
        assert!(parts.iter().all(|p| e.contains(p)), "{e}");
        // Before: index out of bounds in the reader (exit 101) and an empty output folder.
        let dir = tempfile::tempdir().unwrap();
        let (e, out) = run_on_file(dir.path(), "twice.ply", &b, 1 << 30);
        assert!(e.contains("declared again"), "{e}");
        assert!(!out, "no output folder");
    }
}

/// A header whose `vertex` count is short of its body's (the faces were read from vertex data:
/// "face element 0: 0 vertex indices") or past it: the error says which count the body holds.
#[test]
fn a_wrong_vertex_count_is_named_with_the_count_the_body_holds() {
    for (declared, name) in [(3, "fewer"), (5, "more")] {
        let mut b = binary_header(declared, 4);
        b.extend_from_slice(&binary_tetra_body());
        refused(
            &format!("{name}.ply"),
            &b,
            &[
                &format!("the header declares {declared} `vertex` elements (header line 3)"),
                "but the body holds 4",
            ],
        );
        refused(
            &format!("{name}_ascii.ply"),
            ascii_ply(declared, 4, TETRA_BODY).as_bytes(),
            &[
                &format!("the header declares {declared} `vertex` elements"),
                "but the body holds 4",
            ],
        );
    }
    // The first face read from vertex data names itself, its byte and what it lists.
    let mut b = binary_header(3, 4);
    b.extend_from_slice(&binary_tetra_body());
    let e = refused("fewer.ply", &b, &[]);
    let at = binary_header(3, 4).len() + 36;
    assert!(
        e.contains(&format!("face element 0 of 4 (byte {at})"))
            && e.contains("lists 0 vertex indices"),
        "{e}"
    );
    // Faces indexing past the vertex count: the face, the index, its place and the count.
    refused(
        "oob.ply",
        ascii_ply(4, 4, &TETRA_BODY.replacen("3 1 2 3", "3 1 2 4", 1)).as_bytes(),
        &[
            "face element 3 of 4 (line 17)",
            "vertex index 4 (item 2 of its `vertex_indices`) out of range",
            "the header declares 4 vertices",
        ],
    );
}

/// An OBJ line is held whole while it is parsed: a file without line ends is refused after
/// 1 MiB, by the size precheck and the loader alike, before it is read into memory (512 MiB
/// without a newline peaked at 533 MB under a 64 MiB limit; 4 GiB aborted).
#[test]
fn an_obj_line_past_one_mib_is_refused_before_it_is_held() {
    let long: Vec<u8> = b"v 1 2 3 ".iter().copied().cycle().take(3 << 20).collect();
    // The same words from both, after the file's path.
    let words = |e: String| e.split_once(".obj: ").unwrap().1.to_string();
    let e = refused("long.obj", &long, &["line 1: longer than 1048576 bytes"]);
    assert_eq!(words(precheck_refuses("long.obj", &long)), words(e));
    // Line numbers count the lines before it.
    let mut late = TETRA_OBJ.as_bytes().to_vec();
    late.extend_from_slice(&long);
    let e = refused("late.obj", &late, &["line 9: longer than"]);
    assert_eq!(words(precheck_refuses("late.obj", &late)), words(e));
    // The run fails on the line, under a limit far below the file's size.
    let dir = tempfile::tempdir().unwrap();
    let (e, out) = run_on_file(dir.path(), "long.obj", &long, 1 << 20);
    assert!(
        e.contains("long.obj") && e.contains("line 1: longer than"),
        "{e}"
    );
    assert!(!out);
    // A long line that ends is read (a face of 100,000 corners: 99,998 fan triangles).
    let mut polygon = String::new();
    for k in 0..100_000 {
        let a = k as f64 * std::f64::consts::TAU / 100_000.0;
        polygon += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    polygon += "f";
    for k in 1..=100_000 {
        polygon += &format!(" {k}");
    }
    polygon += "\n";
    let (_d, p) = file("polygon.obj", polygon.as_bytes());
    let m = Mesh::load_file(&p, &|_| {}).unwrap();
    assert_eq!(m.triangle_count() + m.dropped_degenerate, 99_998);
}

/// N copies of one face (exported meshes with duplicated faces) load as the one face: a BVH
/// over the copies took 18 s to build at N = 20,000 and its rays ran at 0.04 Mrays/s at
/// N = 5,000. A reversed copy is another face (its normal differs) and is kept.
#[test]
fn duplicate_faces_load_as_one_and_trace_as_one() {
    let one = Tracer::new(&[[glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y]]);
    for n in [20_000usize, 200_000] {
        let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
        obj += &"f 1 2 3\n".repeat(n);
        let (_d, p) = file("copies.obj", obj.as_bytes());
        let t = Instant::now();
        let m = Mesh::load_file(&p, &|_| {}).unwrap();
        assert_eq!((m.triangle_count(), m.dropped_duplicate), (1, n - 1));
        let tris: Vec<_> = (0..m.triangle_count()).map(|i| m.triangle(i)).collect();
        let tracer = Tracer::new(&tris);
        for i in 0..1000 {
            let o = glam::Vec3::new(-0.1 + 1.2 * (i % 37) as f32 / 37.0, 0.3, 1.0);
            let d = glam::Vec3::new(0.0, 0.001 * (i % 7) as f32, -1.0);
            assert_eq!(
                tracer.closest_hit(o, d, 0.0, 10.0),
                one.closest_hit(o, d, 0.0, 10.0)
            );
        }
        assert!(
            t.elapsed() < Duration::from_secs(20),
            "N = {n}: {:?}",
            t.elapsed()
        );
    }
    // A reversed copy stays; copies in other groups and rotated corners are copies.
    let (_d, p) = file(
        "both.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng b\nf 2 3 1\nf 1 3 2\nf 3 1 2\n",
    );
    let m = Mesh::load_file(&p, &|_| {}).unwrap();
    assert_eq!((m.triangle_count(), m.dropped_duplicate), (2, 2));
    // A PLY whose copies have their own vertices: compared by position, unused vertices go.
    let mut ply = String::new();
    for _ in 0..3 {
        ply += "0 0 0\n1 0 0\n0 1 0\n";
    }
    ply += "3 0 1 2\n3 3 4 5\n3 6 7 8\n";
    let (_d, p) = file("copies.ply", ascii_ply(9, 3, &ply).as_bytes());
    let m = Mesh::load_file(&p, &|_| {}).unwrap();
    assert_eq!(
        (m.triangle_count(), m.vertex_count(), m.dropped_duplicate),
        (1, 3, 2)
    );
}

/// A model far from its file's origin is read in f64 and rebased before its positions are
/// rounded to f32: a unit tetrahedron at x = 1e9 loaded as 2 triangles (f32 spacing there is
/// 64), with no word; it now loads as the tetrahedron at the origin, its offset kept.
#[test]
fn a_far_model_keeps_its_shape() {
    let near = Mesh::load_file(&file("near.obj", TETRA_OBJ.as_bytes()).1, &|_| {}).unwrap();
    // "x y z" with x moved by 1e9.
    let shift = |xyz: &str| {
        let (x, yz) = xyz.split_once(' ').unwrap();
        format!("{} {yz}", x.parse::<f64>().unwrap() + 1e9)
    };
    let far_obj: String = TETRA_OBJ
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(xyz) => format!("v {}\n", shift(xyz)),
            None => format!("{l}\n"),
        })
        .collect();
    assert!(far_obj.contains("v 1000000001 0 0"));
    let far_body: String = TETRA_BODY
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i < 4 {
                format!("{}\n", shift(l))
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let far_ascii = ascii_ply(4, 4, &far_body).replace("property float", "property double");
    for (name, bytes) in [
        ("far.obj", far_obj.into_bytes()),
        ("far.ply", far_ascii.into_bytes()),
    ] {
        let (_d, p) = file(name, &bytes);
        let m = Mesh::load_file(&p, &|_| {}).unwrap();
        assert_eq!(m.triangle_count(), 4, "{name}");
        assert_eq!(m.positions, near.positions, "{name}");
        assert_eq!(m.triangles, near.triangles, "{name}");
        assert_eq!(m.origin, glam::DVec3::new(1e9, 0.0, 0.0), "{name}");
        // Scenes place it by that offset (centring again changes nothing).
        let (centred, origin) = centred_mesh(m.clone());
        assert_eq!((centred.positions, origin), (m.positions, m.origin));
    }
}

/// A mutation campaign over PLY headers (the properties of the `ply_header` fuzz target,
/// deterministic): elements added with counts from 0 to 2⁶⁴ − 1 and none to three properties,
/// elements repeated, properties dropped, counts replaced, on ASCII and binary tetrahedra.
/// Each file loads as a valid mesh or is refused naming the file, within a second, and the
/// size precheck refuses every header the loader refuses for its header.
#[test]
fn mutated_ply_headers_load_or_are_refused_at_once() {
    let mut x = 0x853c_49e6_748f_ea9bu64;
    let mut rnd = move |n: usize| {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x % n.max(1) as u64) as usize
    };
    const COUNTS: [&str; 10] = [
        "0",
        "1",
        "3",
        "4",
        "5",
        "255",
        "4294967296",
        "9223372036854775808",
        "18446744073709551615",
        "18446744073709551616",
    ];
    const PROPERTIES: [&str; 5] = [
        "property float a\n",
        "property uchar b\n",
        "property list uchar int c\n",
        "property double x\n",
        "property list uint uchar vertex_indices\n",
    ];
    let ascii_body = TETRA_BODY.as_bytes().to_vec();
    let seeds = [
        (ascii_ply(4, 4, "").into_bytes(), ascii_body),
        (binary_header(4, 4), binary_tetra_body()),
    ];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("h.ply");
    let (mut loaded, mut refused) = (0, 0);
    for k in 0..3000 {
        let (header, body) = &seeds[k % 2];
        let mut lines: Vec<String> = std::str::from_utf8(header)
            .unwrap()
            .lines()
            .map(|l| format!("{l}\n"))
            .collect();
        // Between `format` (line 2) and `end_header` (the last).
        for _ in 0..1 + rnd(3) {
            let at = 2 + rnd(lines.len() - 2);
            match rnd(4) {
                0 => {
                    let mut e = format!(
                        "element {} {}\n",
                        ["junk", "vertex", "face", "edge"][rnd(4)],
                        COUNTS[rnd(COUNTS.len())]
                    );
                    for _ in 0..rnd(4) {
                        e += PROPERTIES[rnd(PROPERTIES.len())];
                    }
                    lines.insert(at, e);
                }
                1 => {
                    let repeated = lines[at].clone();
                    lines.insert(at, repeated);
                }
                2 if lines.len() > 4 => {
                    lines.remove(at.min(lines.len() - 2));
                }
                _ => {
                    if let Some(rest) = lines[at].strip_prefix("element ") {
                        let name = rest.split(' ').next().unwrap().to_string();
                        lines[at] = format!("element {name} {}\n", COUNTS[rnd(COUNTS.len())]);
                    }
                }
            }
        }
        let mut b: Vec<u8> = lines.concat().into_bytes();
        b.extend_from_slice(body);
        std::fs::write(&path, &b).unwrap();
        let t = Instant::now();
        let load = Mesh::load_file(&path, &|_| {});
        let counts = MeshFormat::Ply.counts(&path);
        assert!(
            t.elapsed() < Duration::from_secs(1),
            "{:?} on:\n{}",
            t.elapsed(),
            String::from_utf8_lossy(&b[..b.len() - body.len()])
        );
        // Whatever the precheck refuses, the loader refuses with the same words.
        if let Err(c) = &counts {
            assert_eq!(
                Some(c.to_string()),
                load.as_ref().err().map(|e| e.to_string())
            );
        }
        match load {
            Ok(m) => {
                assert!(m.triangle_count() > 0);
                assert!(counts.is_ok(), "{counts:?}");
                loaded += 1;
            }
            Err(e) => {
                let e = e.to_string();
                assert!(e.starts_with(&path.display().to_string()), "{e}");
                // A repeated element or one without properties: the precheck refuses it too,
                // with the same words.
                if e.contains("declared again") || e.contains("no properties") {
                    let c = counts.expect_err("the precheck should refuse it too");
                    assert_eq!(c.to_string(), e);
                }
                refused += 1;
            }
        }
    }
    eprintln!("header campaign: {loaded} loaded, {refused} refused");
    assert!(
        loaded > 100 && refused > 1000,
        "{loaded} loaded, {refused} refused"
    );
}
