//! OBJ loading on arbitrary text: an error naming the file or a valid mesh, never a panic.
#![no_main]

#[path = "valid_mesh.rs"]
mod valid_mesh;

use libfuzzer_sys::fuzz_target;
use visfield::geometry::Mesh;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("visfield-fuzz-{}.obj", std::process::id()));
    std::fs::write(&path, data).expect("temp file");
    valid_mesh::check(&Mesh::load_obj(&path), "visfield-fuzz-");
});
