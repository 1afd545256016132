//! PLY loading (ASCII and binary) on arbitrary bytes: an error naming the file or a valid mesh,
//! never a panic, and never an allocation the header's counts alone ask for.
#![no_main]

#[path = "valid_mesh.rs"]
mod valid_mesh;

use libfuzzer_sys::fuzz_target;
use std::path::Path;
use visfield::geometry::Mesh;

fuzz_target!(|data: &[u8]| {
    valid_mesh::check(
        &Mesh::ply_from_bytes(data, Path::new("fuzz.ply")),
        "fuzz.ply: ",
    );
});
