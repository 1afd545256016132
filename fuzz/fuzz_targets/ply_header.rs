//! PLY headers built from the input (element counts up to 2⁶⁴ − 1, repeated elements, elements
//! without properties, scalar and list properties of every type), the rest of the input as the
//! body: a valid mesh or an error naming the file, never a panic and never a hang (libFuzzer's
//! `-timeout`); whatever the size precheck refuses, the loader refuses with the same words.
#![no_main]

#[path = "valid_mesh.rs"]
mod valid_mesh;

use libfuzzer_sys::fuzz_target;
use visfield::geometry::{Mesh, MeshFormat};

const COUNTS: [&str; 12] = [
    "0",
    "1",
    "2",
    "3",
    "4",
    "5",
    "255",
    "65536",
    "4294967295",
    "4294967296",
    "9223372036854775808",
    "18446744073709551615",
];
const NAMES: [&str; 4] = ["vertex", "face", "junk", "edge"];
const TYPES: [&str; 8] = [
    "char", "uchar", "short", "ushort", "int", "uint", "float", "double",
];
const PROPERTIES: [&str; 5] = ["x", "y", "z", "vertex_indices", "red"];

/// The header the first bytes of `data` describe (up to the byte that ends it) and the body.
fn ply(data: &[u8]) -> Vec<u8> {
    let Some((&format, mut rest)) = data.split_first() else {
        return Vec::new();
    };
    let mut h = String::from("ply\n");
    h += ["format ascii 1.0\n", "format binary_little_endian 1.0\n"][(format % 2) as usize];
    if format % 3 == 2 {
        h = h.replace("little", "big");
    }
    while let Some((&op, tail)) = rest.split_first() {
        rest = tail;
        let arg = rest.first().copied().unwrap_or(0) as usize;
        match op % 8 {
            0 => h += "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n",
            1 => h += "element face 4\nproperty list uchar int vertex_indices\n",
            2 => {
                h += &format!(
                    "element {} {}\n",
                    NAMES[arg % NAMES.len()],
                    COUNTS[(arg / 4) % COUNTS.len()]
                )
            }
            3 => {
                h += &format!(
                    "property {} {}\n",
                    TYPES[arg % TYPES.len()],
                    PROPERTIES[(arg / 8) % PROPERTIES.len()]
                )
            }
            4 => {
                h += &format!(
                    "property list {} {} {}\n",
                    TYPES[arg % 6],
                    TYPES[(arg / 6) % TYPES.len()],
                    PROPERTIES[(arg / 48) % PROPERTIES.len()]
                )
            }
            5 => h += "comment fuzz\n",
            6 => {
                h += &format!("element face {}\n", COUNTS[arg % COUNTS.len()]);
            }
            _ => break,
        }
        if op % 8 >= 2 && op % 8 != 5 {
            rest = rest.get(1..).unwrap_or(&[]);
        }
    }
    h += "end_header\n";
    let mut bytes = h.into_bytes();
    bytes.extend_from_slice(rest);
    bytes
}

fuzz_target!(|data: &[u8]| {
    let bytes = ply(data);
    let path = std::env::temp_dir().join(format!("visfield-fuzz-{}.ply", std::process::id()));
    std::fs::write(&path, &bytes).expect("temp file");
    let load = Mesh::load_file(&path, &|_| {});
    if let Err(c) = MeshFormat::Ply.counts(&path) {
        assert_eq!(
            Some(c.to_string()),
            load.as_ref().err().map(|e| e.to_string())
        );
    }
    valid_mesh::check(&load, "visfield-fuzz-");
});
