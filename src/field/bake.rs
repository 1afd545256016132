//! Baking a field: 2008 Algorithm 1.
//!
//! For each positional sample p = c + R·s on the bounding sphere (c, R), every used texel's
//! direction in the map's inward frame is traced from p; the closest hit distance over 2R is
//! stored, a miss (no hit within 2R) stores 1. Unused texels (rejection layout) store 1.

use super::normals::{pack_normal, NormalField};
use super::{frames_for, FieldError, FieldParams, Storage, VisibilityField};
use crate::geometry::{Mesh, Sphere};
use crate::sampling::{HemisphereLayout, SpherePoints};
use crate::trace::{ClosestHit, Tracer};
use rayon::prelude::*;
use std::time::Instant;

/// What a bake cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeStats {
    /// Rays traced (used texels × maps).
    pub rays: u64,
    /// Wall time of tracing and storing, seconds (BVH build excluded; see `bvh_seconds`).
    pub seconds: f64,
    /// Wall time of the BVH build, seconds.
    pub bvh_seconds: f64,
}

impl BakeStats {
    /// Millions of rays per second.
    pub fn mrays_per_second(&self) -> f64 {
        self.rays as f64 / self.seconds.max(1e-12) / 1e6
    }
}

/// Options of a bake.
pub struct BakeOptions<'a> {
    /// Refuse fields whose storage passes this many bytes.
    pub memory_limit: u64,
    /// Advanced by one per finished map.
    pub progress: Option<&'a indicatif::ProgressBar>,
}

impl Default for BakeOptions<'_> {
    fn default() -> Self {
        BakeOptions {
            memory_limit: super::default_memory_limit(),
            progress: None,
        }
    }
}

/// Bakes a field of `mesh` (model space), building the reference tracer over it.
pub fn bake(
    mesh: &Mesh,
    params: FieldParams,
    opts: &BakeOptions,
) -> Result<(VisibilityField, BakeStats), FieldError> {
    params.check_memory(opts.memory_limit)?;
    let (tracer, bounds, bvh_seconds) = mesh_tracer(mesh);
    let (field, mut stats) = bake_with(&tracer, bounds, params, opts)?;
    stats.bvh_seconds = bvh_seconds;
    Ok((field, stats))
}

/// [`bake`] with the normal field beside the distances ([`bake_with_normals`]): the same
/// distances, bit for bit, and per texel the hit's normal in 2 × `normal_bits` bits.
pub fn bake_mesh_with_normals(
    mesh: &Mesh,
    params: FieldParams,
    normal_bits: u32,
    opts: &BakeOptions,
) -> Result<(VisibilityField, NormalField, BakeStats), FieldError> {
    params.check_memory(opts.memory_limit)?;
    let (tracer, bounds, bvh_seconds) = mesh_tracer(mesh);
    let (field, normals, mut stats) =
        bake_with_normals(&tracer, bounds, params, normal_bits, opts)?;
    stats.bvh_seconds = bvh_seconds;
    Ok((field, normals, stats))
}

/// The reference tracer over `mesh` (model space), its minimal bounding sphere, and the BVH
/// build time in seconds.
fn mesh_tracer(mesh: &Mesh) -> (Tracer, Sphere, f64) {
    let t = Instant::now();
    let tris: Vec<_> = (0..mesh.triangles.len())
        .map(|i| mesh.triangle(i))
        .collect();
    let tracer = Tracer::new(&tris);
    let bvh_seconds = t.elapsed().as_secs_f64();
    let bounds = crate::geometry::minimal_bounding_sphere(&mesh.positions);
    (tracer, bounds, bvh_seconds)
}

/// Bakes a field of the geometry behind `tracer` (our [`Tracer`], or with the `embree` feature
/// `trace::embree::EmbreeTracer`: the same rays, each caster's own hits), bounded by `bounds`
/// (which must contain it).
pub fn bake_with<T: ClosestHit + ?Sized>(
    tracer: &T,
    bounds: Sphere,
    params: FieldParams,
    opts: &BakeOptions,
) -> Result<(VisibilityField, BakeStats), FieldError> {
    bake_maps(tracer, bounds, params, opts, None)
}

/// Bakes a distance field and its normal field (2010 §4.2) in one pass over the same rays: per
/// texel, the hit's unit geometric normal packed octahedrally in 2 × `normal_bits` bits
/// (8 or 16); misses store the inward direction's reverse (unused by lookups).
pub fn bake_with_normals<T: ClosestHit + ?Sized>(
    tracer: &T,
    bounds: Sphere,
    params: FieldParams,
    normal_bits: u32,
    opts: &BakeOptions,
) -> Result<(VisibilityField, NormalField, BakeStats), FieldError> {
    if !(normal_bits == 8 || normal_bits == 16) {
        return Err(FieldError::Invalid(format!(
            "normal fields pack 8 or 16 bits per component, not {normal_bits}"
        )));
    }
    let normal_bytes = (params.count * params.texels()) as u64 * 4;
    params.check_memory(opts.memory_limit.saturating_sub(normal_bytes))?;
    let mut normals = NormalField {
        texels: params.texels(),
        bits: normal_bits,
        data: vec![[0, 0]; params.count * params.texels()],
    };
    let (field, stats) = bake_maps(tracer, bounds, params, opts, Some(&mut normals))?;
    Ok((field, normals, stats))
}

fn bake_maps<T: ClosestHit + ?Sized>(
    tracer: &T,
    bounds: Sphere,
    params: FieldParams,
    opts: &BakeOptions,
    normals: Option<&mut NormalField>,
) -> Result<(VisibilityField, BakeStats), FieldError> {
    params.check_memory(opts.memory_limit)?;
    if !(bounds.radius > 0.0 && bounds.radius.is_finite() && bounds.center.is_finite()) {
        return Err(FieldError::Invalid(format!(
            "bounding sphere radius {} (centre {}): the object must have extent",
            bounds.radius, bounds.center
        )));
    }
    let points = SpherePoints::new(params.sphere, params.count)?;
    let layout = HemisphereLayout::new(params.layout, params.res);
    let frames = frames_for(&points);
    // Local directions of the used texels, shared by every map.
    let texel_dirs: Vec<(usize, glam::Vec3)> = (0..layout.texel_count())
        .filter_map(|t| layout.to_direction(t as u32).map(|d| (t, d)))
        .collect();
    let diameter = 2.0 * bounds.radius;
    let texels = params.texels();
    let mut storage = Storage::new(params.precision, params.count, texels);
    let normal_bits = normals.as_ref().map_or(0, |n| n.bits);
    let mut normal_rows: Vec<Option<&mut [[u16; 2]]>> = match normals {
        Some(n) => n.data.chunks_mut(texels).map(Some).collect(),
        None => (0..params.count).map(|_| None).collect(),
    };
    let start = Instant::now();
    storage
        .map_slots()
        .into_par_iter()
        .zip(normal_rows.par_iter_mut())
        .enumerate()
        .for_each_init(
            || vec![1.0f32; texels],
            |row, (m, (mut slot, normal_row))| {
                let origin = bounds.center + bounds.radius * points.point(m);
                let frame = frames[m];
                for &(t, local) in &texel_dirs {
                    let dir = frame.to_world(local);
                    let hit = tracer.closest_hit(origin, dir, 0.0, diameter);
                    row[t] = match hit {
                        Some(h) => (h.t / diameter).clamp(0.0, 1.0),
                        None => 1.0,
                    };
                    if let Some(nr) = normal_row.as_deref_mut() {
                        let n = hit.map_or(-dir, |h| h.normal);
                        let [a, b] = pack_normal(n, normal_bits);
                        nr[t] = [a as u16, b as u16];
                    }
                }
                slot.store(row);
                if let Some(pb) = opts.progress {
                    pb.inc(1);
                }
            },
        );
    let stats = BakeStats {
        rays: (texel_dirs.len() * params.count) as u64,
        seconds: start.elapsed().as_secs_f64(),
        bvh_seconds: 0.0,
    };
    let intra = super::IntraTolerance::of(&points, &layout, params.precision, bounds.radius)?;
    let field = VisibilityField {
        params,
        bounds,
        points,
        layout,
        texels: crate::sampling::TexelTable::new(layout),
        frames,
        storage,
        intra,
    };
    Ok((field, stats))
}
