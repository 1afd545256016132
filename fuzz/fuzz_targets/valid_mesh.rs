//! What every mesh-loading target asserts of a result: a valid mesh (triangles, a finite
//! bounding sphere of positive radius, finite normals) or an error naming the file (`marker`).

use visfield::geometry::{GeometryError, Mesh};

pub fn check(result: &Result<Mesh, GeometryError>, marker: &str) {
    match result {
        Ok(mesh) => {
            assert!(mesh.triangle_count() > 0);
            let s = mesh.bounding_sphere();
            assert!(s.radius.is_finite() && s.radius > 0.0, "sphere {s:?}");
            for n in &mesh.normals {
                assert!(n.is_finite(), "normal {n}");
            }
        }
        Err(e) => assert!(e.to_string().contains(marker), "{e}"),
    }
}
