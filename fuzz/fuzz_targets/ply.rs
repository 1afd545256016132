//! PLY loading (ASCII and binary) on arbitrary bytes: an error naming the file or a valid mesh,
//! never a panic, and never an allocation the header's counts alone ask for.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;
use visfield::geometry::Mesh;

fuzz_target!(|data: &[u8]| {
    match Mesh::ply_from_bytes(data, Path::new("fuzz.ply")) {
        Ok(mesh) => {
            assert!(mesh.triangle_count() > 0);
            let s = mesh.bounding_sphere();
            assert!(s.radius.is_finite() && s.radius > 0.0, "sphere {s:?}");
            for n in &mesh.normals {
                assert!(n.is_finite(), "normal {n}");
            }
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.ply: "), "{e}"),
    }
});
