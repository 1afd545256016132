//! Writes a large test mesh: an n × n height field (2(n − 1)² triangles, a gentle sine bump) as
//! a binary little-endian PLY and as an OBJ, to time `experiment try` and the loaders on
//! millions of triangles:
//!
//! ```sh
//! cargo run --release --example big_mesh -- DIR [N]     # N = 2237: 9,999,392 triangles
//! ```
//!
//! It then loads both files back through `Mesh::load_file` and prints each one's time.

use std::io::{BufWriter, Write};
use std::path::PathBuf;

fn main() -> std::io::Result<()> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| ".".into()));
    let n: u32 = args
        .next()
        .map_or(2237, |s| s.parse().expect("N is a number"));
    assert!(n >= 2, "N must be at least 2");
    let height = |i: u32, j: u32| {
        let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
        [u, 0.1 * (6.0 * u).sin() * (6.0 * v).cos(), v]
    };
    let faces = |f: &mut dyn FnMut([u32; 3]) -> std::io::Result<()>| {
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                f([a, a + n, a + 1])?;
                f([a + 1, a + n, a + n + 1])?;
            }
        }
        Ok::<(), std::io::Error>(())
    };
    let triangles = 2 * (n as u64 - 1).pow(2);
    let ply = dir.join(format!("grid{n}.ply"));
    let mut w = BufWriter::new(std::fs::File::create(&ply)?);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {triangles}\n\
         property list uchar int vertex_indices\nend_header\n",
        n * n
    )?;
    for j in 0..n {
        for i in 0..n {
            for c in height(i, j) {
                w.write_all(&c.to_le_bytes())?;
            }
        }
    }
    faces(&mut |t| {
        w.write_all(&[3])?;
        for v in t {
            w.write_all(&(v as i32).to_le_bytes())?;
        }
        Ok(())
    })?;
    w.flush()?;
    drop(w);
    let obj = dir.join(format!("grid{n}.obj"));
    let mut w = BufWriter::new(std::fs::File::create(&obj)?);
    for j in 0..n {
        for i in 0..n {
            let [x, y, z] = height(i, j);
            writeln!(w, "v {x} {y} {z}")?;
        }
    }
    faces(&mut |t| writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1))?;
    w.flush()?;
    drop(w);
    for p in [&ply, &obj] {
        let t = std::time::Instant::now();
        let m = visfield::geometry::Mesh::load_file(p, &|_| {}).expect("the mesh loads");
        println!(
            "{}: loaded {} vertices, {} triangles in {:.2} s",
            p.display(),
            m.vertex_count(),
            m.triangle_count(),
            t.elapsed().as_secs_f64()
        );
    }
    println!(
        "{} and {}: {} vertices, {triangles} triangles",
        ply.display(),
        obj.display(),
        n * n
    );
    Ok(())
}
