//! OBJ loading on arbitrary text: an error naming the file or a valid mesh, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use visfield::geometry::Mesh;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("visfield-fuzz-{}.obj", std::process::id()));
    std::fs::write(&path, data).expect("temp file");
    match Mesh::load_obj(&path) {
        Ok(mesh) => {
            assert!(mesh.triangle_count() > 0);
            let s = mesh.bounding_sphere();
            assert!(s.radius.is_finite() && s.radius > 0.0, "sphere {s:?}");
            for n in &mesh.normals {
                assert!(n.is_finite(), "normal {n}");
            }
        }
        Err(e) => assert!(e.to_string().contains("visfield-fuzz-")),
    }
});
