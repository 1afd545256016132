//! Mesh validation on arbitrary vertices and indices: an error or a mesh whose invariants hold
//! (finite unit normals, a bounding sphere of positive finite radius holding every vertex).
#![no_main]

use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use visfield::geometry::Mesh;

fuzz_target!(|data: &[u8]| {
    // First byte: vertex count (mod 64); then 12 bytes per vertex, then 12 bytes per triangle.
    let Some((&n, rest)) = data.split_first() else {
        return;
    };
    let n = (n % 64) as usize;
    if rest.len() < 12 * n {
        return;
    }
    let (vbytes, tbytes) = rest.split_at(12 * n);
    let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let u = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) % 80;
    let positions: Vec<Vec3> = vbytes
        .chunks_exact(12)
        .map(|c| Vec3::new(f(&c[0..4]), f(&c[4..8]), f(&c[8..12])))
        .collect();
    let triangles: Vec<[u32; 3]> = tbytes
        .chunks_exact(12)
        .map(|c| [u(&c[0..4]), u(&c[4..8]), u(&c[8..12])])
        .collect();
    if let Ok(mesh) = Mesh::from_parts("fuzz", positions, triangles) {
        visfield_fuzz_check(&mesh);
    }
});

fn visfield_fuzz_check(mesh: &Mesh) {
    assert!(mesh.triangle_count() > 0);
    for n in &mesh.normals {
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-3, "normal {n}");
    }
    let s = mesh.bounding_sphere();
    assert!(s.radius.is_finite() && s.radius > 0.0, "sphere {s:?}");
    for p in &mesh.positions {
        assert!(s.contains(*p, 1e-5), "{p} outside {s:?}");
    }
}
