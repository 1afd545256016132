//! Determinism: the same bake, ray-cast AO, field AO and rendered image on 1 and on 2 threads
//! are bit-identical (all randomness is a function of point, sample index and seed).

use super::scene_ao::{bake_fields, field_ao, raycast_ao, scene};
use super::StabilityRow;
use crate::geometry::Similarity;
use crate::render::primary::{gbuffer, shade_vertex_ao, PrimaryScene};
use crate::render::receivers::Receivers;

/// Everything one run produces, as bytes.
fn outputs() -> Vec<(&'static str, Vec<u8>)> {
    let placed = super::scale::unit_scene();
    let sc = scene(&placed, Similarity::default());
    let fields = bake_fields(&placed);
    let storage: Vec<u8> = fields
        .iter()
        .flat_map(|f| match &f.storage {
            crate::field::Storage::U8 { data, .. } => data.clone(),
            other => format!("{other:?}").into_bytes(),
        })
        .collect();
    let ray = raycast_ao(&sc, 8);
    let field = field_ao(&sc, &fields, 8);
    let cam = crate::render::camera::Camera::corner();
    let g = gbuffer(&PrimaryScene::new(&sc), &cam, 64, 64);
    let recv = Receivers::of(&sc);
    let (img, _) = shade_vertex_ao(&sc, &g, 64, 64, &recv.split(&sc, &field));
    let bits =
        |v: &[f32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_bits().to_le_bytes()).collect() };
    vec![
        ("baked fields (u8 bytes)", storage),
        ("ray-cast AO (f32 bits)", bits(&ray)),
        ("field AO (f32 bits)", bits(&field)),
        ("field AO image (PNG bytes)", img.png_bytes()),
    ]
}

/// Runs `outputs` on pools of 1 and 2 threads and counts differing bytes per output.
pub fn threads() -> Vec<StabilityRow> {
    let on = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("a thread pool")
            .install(outputs)
    };
    let (one, two) = (on(1), on(2));
    one.iter()
        .zip(&two)
        .map(|((what, a), (_, b))| {
            let differ =
                a.len().abs_diff(b.len()) + a.iter().zip(b).filter(|(x, y)| x != y).count();
            StabilityRow::new(
                "thread_determinism",
                format!(
                    "{what}: bytes differing between 1 and 2 threads (of {})",
                    a.len()
                ),
                differ as f64,
                0.0,
            )
        })
        .collect()
}
