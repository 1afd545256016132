//! Packing fields for the GPU: per-instance records, the shared tables (sphere points, 1-bit
//! means), the sphere triangulations for the interpolated selection, and the
//! stored words of every distinct field.

use super::texture::map_bytes;
use super::GpuError;
use crate::field::scene::FieldInstance;
use crate::field::{Storage, VisibilityField};
use crate::sampling::{LayoutKind, SphereKind};
use std::collections::HashMap;
use std::sync::Arc;

/// Twin of WGSL `Instance` (shaders/field_lookup.wgsl). One placed field.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FieldInstanceGpu {
    /// World → model rotation (the instance rotation's conjugate), (x, y, z, w).
    pub rotation: [f32; 4],
    /// World translation: world = translation + scale · R · model.
    pub translation: [f32; 3],
    /// Uniform scale.
    pub scale: f32,
    /// Centre of the world-space bounding sphere.
    pub world_center: [f32; 3],
    /// Radius of the world-space bounding sphere.
    pub world_radius: f32,
    /// Centre of the model-space bounding sphere.
    pub model_center: [f32; 3],
    /// Radius of the model-space bounding sphere.
    pub model_radius: f32,
    /// Sphere kind (0 Slater, 1 lat-long).
    pub sphere_kind: u32,
    /// Number of maps (sphere points).
    pub map_count: u32,
    /// Ring parameter: Slater n or lat-long rows.
    pub ring_param: u32,
    /// Layout kind (0 polar, 1 rejection, 2 concentric).
    pub layout_kind: u32,
    /// Map resolution (texels a side).
    pub resolution: u32,
    /// Precision (0 f32, 1 u16, 2 u8, 3 bit1).
    pub storage_precision: u32,
    /// First data word (storage layout) or first texture slice (texture layout); set by the
    /// layout (`PackedFields::set_data_base`).
    pub data_base: u32,
    /// First 1-bit mean entry in the tables (four means an entry).
    pub mean_base: u32,
    /// First sphere point entry in the tables.
    pub point_base: u32,
    /// First triangle entry in the mesh.
    pub mesh_base: u32,
    /// Step cap of the interpolated selection's triangle walk.
    pub walk_steps: u32,
    /// Tiles per row of a texture slice (texture layout).
    pub tiles_per_row: u32,
    /// Tiles per texture slice (texture layout).
    pub tiles_per_slice: u32,
    /// Tile width in elements (texture layout).
    pub tile_width: u32,
    /// Tile height in elements (texture layout).
    pub tile_height: u32,
    /// Owner table ([`crate::sampling::SpherePoints::nearest`]'s): cells per cube face edge, 0
    /// for none.
    pub owner_grid: u32,
    /// The intra-object tolerance ([`crate::field::IntraTolerance`]): positional part (model
    /// units).
    pub intra_positional: f32,
    /// The intra-object tolerance's directional part (radians).
    pub intra_directional: f32,
    /// First owner-table code in the mesh buffer, in 16-bit halves of its words.
    pub owner_base: u32,
    /// First owner-table pair in the mesh buffer, in words (low half p, high half q).
    pub pair_base: u32,
    /// Texel table ([`crate::sampling::TexelTable`]): cells per side, 0 for none.
    pub texel_grid: u32,
    /// First texel-table cell in the mesh buffer, in 16-bit halves of its words.
    pub texel_base: u32,
    /// Candidate grid (the cube grid of [`crate::sampling::SpherePoints::nearest`]'s search,
    /// read for the owner table's MIXED cells): cells per face edge, 0 for none.
    pub cand_grid: u32,
    /// First candidate-grid cell in the mesh buffer, in entries (four candidates each).
    pub cand_base: u32,
}
const _: () = assert!(std::mem::size_of::<FieldInstanceGpu>() == 160);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, scale) == 28);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, model_center) == 48);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, sphere_kind) == 64);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, resolution) == 80);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, point_base) == 96);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, tiles_per_slice) == 112);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, intra_positional) == 128);
const _: () = assert!(std::mem::offset_of!(FieldInstanceGpu, texel_grid) == 144);

/// Precision code shared with the shaders.
pub(crate) fn precision_code(s: &Storage) -> u32 {
    match s {
        Storage::F32 { .. } => 0,
        Storage::U16 { .. } => 1,
        Storage::U8 { .. } => 2,
        Storage::Bit1 { .. } => 3,
    }
}

fn layout_code(k: LayoutKind) -> u32 {
    match k {
        LayoutKind::Polar => 0,
        LayoutKind::Rejection => 1,
        LayoutKind::Concentric => 2,
    }
}

/// The sphere kind code and ring parameter (Slater n, lat-long rows).
fn sphere_code(field: &VisibilityField) -> Result<(u32, u32), GpuError> {
    let count = field.params.count as u64;
    match field.params.sphere {
        SphereKind::Slater => (1..=1024u64)
            .find(|&n| 2 * (2 * n * n + 2 * n + 1) == count)
            .map(|n| (0, n as u32))
            .ok_or_else(|| GpuError::Unsupported(format!("slater set of {count} points"))),
        SphereKind::LatLong => (2..=4096u64)
            .find(|&r| r * (r + 1) == count)
            .map(|r| (1, r as u32))
            .ok_or_else(|| GpuError::Unsupported(format!("lat-long set of {count} points"))),
        SphereKind::Fibonacci => Err(GpuError::Unsupported(
            "fibonacci point sets have no GPU nearest-point query (use slater or lat_long)"
                .to_string(),
        )),
    }
}

/// Everything but the stored distances, plus each distinct field once.
pub(crate) struct PackedFields {
    pub instances: Vec<FieldInstanceGpu>,
    /// Per field its points (w: bits of an incident triangle) and its 1-bit means (four per
    /// entry).
    pub tables: Vec<[f32; 4]>,
    /// Per triangle: vertices, then the triangles across the edges opposite them; then each
    /// field's lookup tables ([`lookup_tables`]).
    pub mesh: Vec<[u32; 4]>,
    /// The distinct fields, and which one each instance uses.
    pub fields: Vec<Arc<VisibilityField>>,
    pub field_of_instance: Vec<usize>,
}

impl PackedFields {
    /// Packs `instances`. The data references (`data_base`) and the texture tiles are left for
    /// the layout to fill.
    /// `lookup_tables`: also pack each field's owner and texel tables (the lookup reads them
    /// first).
    pub fn new(instances: &[FieldInstance], with_tables: bool) -> Result<Self, GpuError> {
        let mut tables: Vec<[f32; 4]> = Vec::new();
        let mut mesh: Vec<[u32; 4]> = Vec::new();
        let mut fields: Vec<Arc<VisibilityField>> = Vec::new();
        let mut field_of_instance = Vec::with_capacity(instances.len());
        // Per distinct field: its record with the placement left at zero.
        let mut records: Vec<FieldInstanceGpu> = Vec::new();
        let mut index: HashMap<*const VisibilityField, usize> = HashMap::new();
        for inst in instances {
            let key = Arc::as_ptr(&inst.field);
            let fi = match index.get(&key) {
                Some(&fi) => fi,
                None => {
                    let f = &inst.field;
                    let (sphere, ring) = sphere_code(f)?;
                    let point_base = tables.len() as u32;
                    let (incident, adj) = adjacency(f.points.triangles(), f.points.len())?;
                    for (i, p) in f.points.points().iter().enumerate() {
                        tables.push([p.x, p.y, p.z, f32::from_bits(incident[i])]);
                    }
                    let mean_base = tables.len() as u32;
                    if let Storage::Bit1 { mean, .. } = &f.storage {
                        for c in mean.chunks(4) {
                            let mut e = [1.0f32; 4];
                            e[..c.len()].copy_from_slice(c);
                            tables.push(e);
                        }
                    }
                    let mesh_base = mesh.len() as u32;
                    for (t, a) in f.points.triangles().iter().zip(&adj) {
                        mesh.push([t[0], t[1], t[2], 0]);
                        mesh.push([a[0], a[1], a[2], 0]);
                    }
                    let steps = 64 + 4 * (f.points.len() as f64).sqrt() as u32;
                    let lookup = if with_tables {
                        lookup_tables(f, &mut mesh)
                    } else {
                        LookupTables::default()
                    };
                    records.push(FieldInstanceGpu {
                        owner_grid: lookup.owner_grid,
                        owner_base: lookup.owner_base,
                        pair_base: lookup.pair_base,
                        texel_grid: lookup.texel_grid,
                        texel_base: lookup.texel_base,
                        cand_grid: lookup.cand_grid,
                        cand_base: lookup.cand_base,
                        sphere_kind: sphere,
                        map_count: f.params.count as u32,
                        ring_param: ring,
                        layout_kind: layout_code(f.params.layout),
                        resolution: f.params.res,
                        storage_precision: precision_code(&f.storage),
                        mean_base,
                        point_base,
                        mesh_base,
                        walk_steps: steps,
                        intra_positional: f.intra.positional(),
                        intra_directional: f.intra.directional,
                        ..Default::default()
                    });
                    fields.push(inst.field.clone());
                    index.insert(key, fields.len() - 1);
                    fields.len() - 1
                }
            };
            field_of_instance.push(fi);
        }
        let instances = instances
            .iter()
            .zip(&field_of_instance)
            .map(|(inst, &fi)| placed(inst, records[fi]))
            .collect();
        Ok(PackedFields {
            instances,
            tables,
            mesh,
            fields,
            field_of_instance,
        })
    }

    /// Sets `data_base` of every instance from a per-field value.
    pub fn set_data_base(&mut self, base_of_field: &[u32]) {
        for (inst, &fi) in self.instances.iter_mut().zip(&self.field_of_instance) {
            inst.data_base = base_of_field[fi];
        }
    }
}

/// `record` (a field's instance record) placed by `inst`'s transform: the world-to-model
/// rotation, translation, scale and the world and model bounding spheres; the field's own
/// entries kept.
pub(super) fn placed(inst: &FieldInstance, record: FieldInstanceGpu) -> FieldInstanceGpu {
    let tr = &inst.transform;
    let b = &inst.field.bounds;
    FieldInstanceGpu {
        rotation: tr.rotation.inverse().to_array(),
        translation: tr.translation.to_array(),
        scale: tr.scale,
        world_center: inst.world_center.to_array(),
        world_radius: inst.world_radius,
        model_center: b.center.to_array(),
        model_radius: b.radius,
        ..record
    }
}

/// Where a field's lookup tables lie in the mesh buffer (0 cells: no table).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct LookupTables {
    owner_grid: u32,
    owner_base: u32,
    pair_base: u32,
    texel_grid: u32,
    texel_base: u32,
    cand_grid: u32,
    cand_base: u32,
}

/// Appends `f`'s owner table (codes, then pairs), candidate grid and texel table to `mesh`,
/// each starting on an entry (16-byte) boundary, u16 codes two to a word, low half first, a
/// candidate cell one entry. The owner table and the candidate grid are left out when the set
/// has ≥ 2¹⁶ − 1 points (every owner cell would send the query to the search); the texel table
/// is empty but for concentric maps of res ≤ 255.
fn lookup_tables(f: &VisibilityField, mesh: &mut Vec<[u32; 4]>) -> LookupTables {
    // u16 values packed into whole entries; returns the first half's index.
    fn push_halves(mesh: &mut Vec<[u32; 4]>, halves: impl ExactSizeIterator<Item = u16>) -> u32 {
        let first = mesh.len() as u32 * 8;
        let n = halves.len();
        let start = mesh.len();
        mesh.resize(start + n.div_ceil(8), [0; 4]);
        for (k, h) in halves.enumerate() {
            mesh[start + k / 8][(k / 2) % 4] |= (h as u32) << (16 * (k % 2));
        }
        first
    }
    let mut out = LookupTables::default();
    let (g, codes, pairs) = f.points.owner_table_raw();
    if f.points.len() < u16::MAX as usize && !codes.is_empty() {
        out.owner_grid = g;
        out.owner_base = push_halves(mesh, codes.iter().copied());
        out.pair_base = mesh.len() as u32 * 4;
        push_halves(
            mesh,
            pairs
                .iter()
                .flat_map(|&[p, q]| [p, q])
                .collect::<Vec<_>>()
                .into_iter(),
        );
        let (cg, slots) = f.points.candidate_slots_raw();
        out.cand_grid = cg;
        out.cand_base = mesh.len() as u32;
        mesh.extend_from_slice(slots);
    }
    let cells = f.texels.raw_cells();
    if f.texels.cells_per_side() > 0 && f.texels.layout() == f.layout {
        out.texel_grid = f.texels.cells_per_side();
        out.texel_base = push_halves(mesh, cells.iter().copied());
    }
    out
}

/// The triangle incident to each vertex (the last one listing it, as on the host) and, per
/// triangle, the triangles across the edges opposite its vertices.
fn adjacency(tris: &[[u32; 3]], points: usize) -> Result<(Vec<u32>, Vec<[u32; 3]>), GpuError> {
    let mut half: HashMap<(u32, u32), u32> = HashMap::with_capacity(tris.len() * 3);
    for (ti, t) in tris.iter().enumerate() {
        for e in 0..3 {
            half.insert((t[(e + 1) % 3], t[(e + 2) % 3]), ti as u32);
        }
    }
    let mut adj = vec![[0u32; 3]; tris.len()];
    for (ti, t) in tris.iter().enumerate() {
        for (e, slot) in adj[ti].iter_mut().enumerate() {
            let (a, b) = (t[(e + 1) % 3], t[(e + 2) % 3]);
            *slot = *half.get(&(b, a)).ok_or_else(|| {
                GpuError::Unsupported(format!("sphere triangulation edge ({a}, {b}) has no twin"))
            })?;
        }
    }
    let mut incident = vec![u32::MAX; points];
    for (ti, t) in tris.iter().enumerate() {
        for &v in t {
            incident[v as usize] = ti as u32;
        }
    }
    Ok((incident, adj))
}

/// Every distinct field's stored words, concatenated; returns the words and each field's first
/// word. F32: one word per texel; U16 / U8: the bytes as stored, little-endian, padded to a
/// word; Bit1: the 64-bit words as pairs of 32-bit words (low half first).
pub(crate) fn field_words(fields: &[Arc<VisibilityField>]) -> (Vec<u32>, Vec<u32>) {
    let mut words: Vec<u32> = Vec::new();
    let mut bases = Vec::with_capacity(fields.len());
    for f in fields {
        bases.push(words.len() as u32);
        push_words(&mut words, map_bytes(&f.storage).1);
    }
    (words, bases)
}

/// Appends `bytes` to `words` as the WGSL reads them back: four bytes a word, the first in the
/// low bits (two 16-bit halves a word, the first low), the last word padded with zeros.
pub(crate) fn push_words(words: &mut Vec<u32>, bytes: &[u8]) {
    let start = words.len();
    words.resize(start + bytes.len().div_ceil(4), 0);
    bytemuck::cast_slice_mut::<u32, u8>(&mut words[start..])[..bytes.len()].copy_from_slice(bytes);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{FieldParams, Precision};
    use crate::geometry::Sphere;
    use crate::sampling::rays::uniform;

    /// Host twin of `load_distance` in shaders/field_storage.wgsl.
    fn decode(
        words: &[u32],
        base: u32,
        precision: u32,
        res: u32,
        mean: &[f32],
        m: u32,
        t: u32,
    ) -> f32 {
        let texels = res * res;
        match precision {
            0 => f32::from_bits(words[(base + m * texels + t) as usize]),
            1 => {
                let g = m * texels + t;
                let q = (words[(base + g / 2) as usize] >> (16 * (g % 2))) & 0xffff;
                q as f32 / 65535.0
            }
            2 => {
                let g = m * texels + t;
                let q = (words[(base + g / 4) as usize] >> (8 * (g % 4))) & 0xff;
                q as f32 / 255.0
            }
            _ => {
                let per_map = 2 * texels.div_ceil(64);
                let w = words[(base + m * per_map + t / 32) as usize];
                if (w >> (t % 32)) & 1 == 1 {
                    mean[m as usize]
                } else {
                    1.0
                }
            }
        }
    }

    fn field(precision: Precision, res: u32, seed: u64) -> Arc<VisibilityField> {
        let count = 26; // Slater n = 2
        let texels = (res * res) as usize;
        let mut storage = Storage::new(precision, count, texels);
        for (m, slot) in storage.map_slots().iter_mut().enumerate() {
            let row: Vec<f32> = (0..texels)
                .map(|t| {
                    let u = uniform(m as u32, t as u32, 0, seed);
                    if u < 0.3 {
                        1.0
                    } else {
                        u
                    }
                })
                .collect();
            slot.store(&row);
        }
        let params = FieldParams {
            sphere: SphereKind::Slater,
            count,
            layout: LayoutKind::Concentric,
            res,
            precision,
        };
        let sphere = Sphere {
            center: glam::Vec3::ZERO,
            radius: 1.0,
        };
        Arc::new(VisibilityField::from_storage(params, sphere, storage).unwrap())
    }

    #[test]
    fn packed_words_decode_to_the_stored_distances_bit_for_bit() {
        // Odd resolutions leave u8 / u16 maps straddling words and 1-bit maps padded.
        let fields: Vec<Arc<VisibilityField>> = [
            (Precision::F32, 5),
            (Precision::U16, 5),
            (Precision::U8, 7),
            (Precision::Bit1, 9),
            (Precision::U8, 16),
        ]
        .iter()
        .enumerate()
        .map(|(i, &(p, r))| field(p, r, i as u64))
        .collect();
        let (words, bases) = field_words(&fields);
        for (f, &base) in fields.iter().zip(&bases) {
            let mean: Vec<f32> = match &f.storage {
                Storage::Bit1 { mean, .. } => mean.clone(),
                _ => Vec::new(),
            };
            let code = precision_code(&f.storage);
            for m in 0..f.params.count {
                for t in 0..f.params.texels() {
                    let got = decode(&words, base, code, f.params.res, &mean, m as u32, t as u32);
                    let want = f.storage.get(m, t);
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "{:?} map {m} texel {t}",
                        f.params.precision
                    );
                }
            }
        }
    }

    #[test]
    fn lookup_tables_decode_to_the_hosts_tables() {
        use crate::field::scene::FieldInstance;
        use crate::geometry::Similarity;
        // Two fields: the second's tables follow the first's mesh and tables.
        let (a, b) = (field(Precision::U8, 16, 3), field(Precision::U8, 7, 4));
        let insts = [a.clone(), b.clone()].map(|f| FieldInstance::new(f, Similarity::default()));
        let packed = PackedFields::new(&insts, true).unwrap();
        let half = |h: u32| {
            (packed.mesh[(h / 8) as usize][((h / 2) % 4) as usize] >> (16 * (h % 2))) & 0xffff
        };
        for (f, inst) in [a, b].iter().zip(&packed.instances) {
            let (g, codes, pairs) = f.points.owner_table_raw();
            assert_eq!(inst.owner_grid, g);
            assert!(g > 0 && codes.len() == 6 * (g * g) as usize);
            for (k, &c) in codes.iter().enumerate() {
                assert_eq!(half(inst.owner_base + k as u32), c as u32, "owner cell {k}");
            }
            for (k, &[p, q]) in pairs.iter().enumerate() {
                let w = packed.mesh[((inst.pair_base + k as u32) / 4) as usize]
                    [((inst.pair_base + k as u32) % 4) as usize];
                assert_eq!((w & 0xffff, w >> 16), (p as u32, q as u32), "pair {k}");
            }
            let (cg, slots) = f.points.candidate_slots_raw();
            assert_eq!(inst.cand_grid, cg);
            let base = inst.cand_base as usize;
            assert_eq!(&packed.mesh[base..base + slots.len()], slots);
            let cells = f.texels.raw_cells();
            assert_eq!(inst.texel_grid, f.texels.cells_per_side());
            assert_eq!(cells.len(), (inst.texel_grid * inst.texel_grid) as usize);
            for (k, &t) in cells.iter().enumerate() {
                assert_eq!(half(inst.texel_base + k as u32), t as u32, "texel cell {k}");
            }
        }
        // Without tables: no cells, nothing appended after the triangulations.
        let bare = PackedFields::new(&insts, false).unwrap();
        assert!(bare
            .instances
            .iter()
            .all(|i| i.owner_grid == 0 && i.texel_grid == 0 && i.cand_grid == 0));
        let tris: usize = insts
            .iter()
            .map(|i| 2 * i.field.points.triangles().len())
            .sum();
        assert_eq!(bare.mesh.len(), tris);
    }

    #[test]
    fn adjacency_matches_a_brute_force_edge_search() {
        let f = field(Precision::U8, 4, 0);
        let tris = f.points.triangles();
        let (incident, adj) = adjacency(tris, f.points.len()).unwrap();
        for (ti, t) in tris.iter().enumerate() {
            for e in 0..3 {
                let (a, b) = (t[(e + 1) % 3], t[(e + 2) % 3]);
                // The one other triangle holding both a and b.
                let other: Vec<usize> = (0..tris.len())
                    .filter(|&u| u != ti && tris[u].contains(&a) && tris[u].contains(&b))
                    .collect();
                assert_eq!(other, vec![adj[ti][e] as usize]);
            }
        }
        for (v, &t) in incident.iter().enumerate() {
            assert!(tris[t as usize].contains(&(v as u32)));
        }
    }

    #[test]
    fn instances_carry_their_field_and_transform() {
        use crate::geometry::Similarity;
        let a = field(Precision::U8, 4, 1);
        let b = field(Precision::Bit1, 4, 2);
        let tr = Similarity::new(glam::Quat::from_rotation_z(0.3), glam::Vec3::X, 2.0);
        let insts = [
            FieldInstance::new(a.clone(), tr),
            FieldInstance::new(b.clone(), Similarity::default()),
            FieldInstance::new(a.clone(), Similarity::default()),
        ];
        let packed = PackedFields::new(&insts, false).unwrap();
        // Two distinct fields; the third instance reuses the first.
        assert_eq!(packed.fields.len(), 2);
        assert_eq!(packed.field_of_instance, vec![0, 1, 0]);
        let i0 = packed.instances[0];
        // Slater, 26 maps, n = 2, concentric.
        assert_eq!(
            (i0.sphere_kind, i0.map_count, i0.ring_param, i0.layout_kind),
            (0, 26, 2, 2)
        );
        assert_eq!((i0.translation, i0.scale), ([1.0, 0.0, 0.0], 2.0));
        // The rotation is world → model: its conjugate maps model X to world.
        let q = glam::Quat::from_array(i0.rotation).inverse();
        assert!((q * glam::Vec3::X - tr.rotation * glam::Vec3::X).length() < 1e-6);
        // The first field's points come first; the 1-bit field's means follow its points (26
        // means in 7 entries).
        assert_eq!(i0.point_base, 0);
        let i1 = packed.instances[1];
        assert_eq!(i1.storage_precision, 3);
        assert_eq!(i1.mean_base, i1.point_base + 26);
        assert_eq!(packed.tables.len(), 26 + 26 + 7);
    }
}
