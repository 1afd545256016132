//! Study: the intra-object test's tolerance against the field's resolution. Self-occlusion AO of
//! a model at about 4000 of its own vertices, field lookup against ray casting on the same 256
//! rays per point, for fixed tolerances (fractions of 2R) and the field's own tolerance
//! (`IntraBias::Auto`) at several scales.
//!
//! `cargo run --release --example intra_bias` writes `results/intra_bias/table.csv` and
//! `run.json` (Igea, the bunny and the tree; pass model names to choose others).
use std::sync::Arc;
use visfield::experiment::metrics::rms_unquantised;
use visfield::field::bake::{bake, BakeOptions};
use visfield::field::lookup::{IntraBias, LookupOptions};
use visfield::field::scene::{FieldInstance, FieldScene};
use visfield::field::storage::Precision;
use visfield::field::{FieldParams, Selection};
use visfield::geometry::{models::load_model, Similarity};
use visfield::render::ao::{ao_at_points, AoOptions};
use visfield::sampling::rays::RaySet;
use visfield::sampling::{LayoutKind, SphereKind};

fn main() {
    let mut names: Vec<String> = std::env::args().skip(1).collect();
    if names.is_empty() {
        names = ["igea_67k", "stanford-bunny_39k", "Tree_3"]
            .map(String::from)
            .to_vec();
    }
    let mut csv = String::from(
        "model,points,positional_samples,directional_res,selection,tolerance,scale,\
         rms_vertex,mean_ao,mean_reference_ao\n",
    );
    for name in &names {
        study(name, &mut csv);
    }
    let out = std::path::Path::new("results/intra_bias");
    std::fs::create_dir_all(out).expect("results/intra_bias");
    visfield::io::write_atomic(&out.join("table.csv"), csv.as_bytes()).expect("table.csv");
    let meta = visfield::experiment::meta::RunMeta::collect(None);
    visfield::io::write_atomic(&out.join("run.json"), meta.to_json().as_bytes()).expect("run.json");
    println!("wrote {}", out.display());
}

fn study(name: &str, csv: &mut String) {
    let mesh = load_model(name).expect("model");
    let step = (mesh.positions.len() / 4000).max(1);
    let pts: Vec<_> = mesh.positions.iter().step_by(step).copied().collect();
    let nrm: Vec<_> = mesh.normals.iter().step_by(step).copied().collect();
    let bounds = mesh.bounding_sphere();
    let tris: Vec<_> = (0..mesh.triangles.len())
        .map(|i| mesh.triangle(i))
        .collect();
    let tracer = visfield::trace::Tracer::new(&tris);
    let rays = RaySet::new(16, 1);
    let opts = AoOptions::for_scene_radius(bounds.radius);
    let reference = ao_at_points(&tracer, &pts, &nrm, &rays, &opts);
    let mean_ref = reference.iter().sum::<f32>() / reference.len() as f32;
    println!(
        "{name}: {} points, mean reference AO {mean_ref:.3}",
        pts.len()
    );
    for count in [1090, 4226] {
        for res in [32, 64] {
            let params = FieldParams {
                sphere: SphereKind::Slater,
                count,
                layout: LayoutKind::Concentric,
                res,
                precision: Precision::U8,
            };
            let (field, _) = bake(&mesh, params, &BakeOptions::default()).expect("bake");
            let field = Arc::new(field);
            println!(
                "{count:>6} x {res:>3}: tolerance {:.4} + {:.4} d1 (fractions of 2R)",
                field.intra.positional() / (2.0 * field.bounds.radius),
                field.intra.directional / 2.0,
            );
            let biases = [0.01f32, 0.02, 0.04]
                .map(IntraBias::Fixed)
                .into_iter()
                .chain([0.5f32, 0.75, 1.0, 1.5, 2.0].map(|scale| IntraBias::Auto { scale }));
            for sel in [Selection::Nearest, Selection::Interpolated] {
                for bias in biases.clone() {
                    let fs = FieldScene {
                        instances: vec![FieldInstance::new(field.clone(), Similarity::default())],
                        options: LookupOptions {
                            selection: sel,
                            intra_bias: bias,
                        },
                    };
                    let ao = ao_at_points(&fs, &pts, &nrm, &rays, &opts);
                    let mean = ao.iter().sum::<f32>() / ao.len() as f32;
                    let rms = rms_unquantised(&ao, &reference);
                    println!("{count:>6} x {res:>3} {sel:?} {bias:?}: rms {rms:.2} mean {mean:.3}");
                    let (kind, scale) = match bias {
                        IntraBias::Auto { scale } => ("auto", scale),
                        IntraBias::Fixed(f) => ("fixed", f),
                    };
                    csv.push_str(&format!(
                        "{name},{},{count},{res},{sel:?},{kind},{scale},{rms:.3},{mean:.4},\
                         {mean_ref:.4}\n",
                        pts.len()
                    ));
                }
            }
        }
    }
}
