//! Field layout 2: the 2010 paper's packing of a field's maps into a 3D texture (Gaitatzes et
//! al., WSCG 2010, §3.1: each directional map a slice, several maps tiled per slice when their
//! number passes the depth limit). Formats by precision: r32float (f32), r16uint (u16), r8uint
//! (u8; integer reads are exact, the shader decodes q / L as the host does), r32uint words for
//! 1-bit maps (their per-map means stay in the tables). Deviation from the paper: u8 maps use
//! r8uint rather than r8unorm, so that every read is bit-identical to the host's decode.

use super::context::GpuContext;
use super::GpuError;
use crate::field::{storage::words_per_map, Storage, VisibilityField};
use std::sync::Arc;

/// Tile geometry of one field inside the texture.
#[derive(Clone, Copy, Debug)]
struct FieldTiles {
    tile_w: u32,
    tile_h: u32,
    tiles_x: u32,
    per_slice: u32,
    first_slice: u32,
}

impl FieldTiles {
    /// Texel (x, y, slice) of element `e` of map `m`: the host twin of `load_tile` in
    /// shaders/field_texture.wgsl.
    fn texel_of(&self, m: u32, e: u32) -> (u32, u32, u32) {
        let k = m % self.per_slice;
        (
            (k % self.tiles_x) * self.tile_w + e % self.tile_w,
            (k / self.tiles_x) * self.tile_h + e / self.tile_w,
            self.first_slice + m / self.per_slice,
        )
    }
}

/// Texture size and each field's tiles.
#[derive(Clone, Debug)]
struct TexturePlan {
    width: u32,
    height: u32,
    depth: u32,
    tiles: Vec<FieldTiles>,
}

/// Places fields of `counts` maps with tiles of `shapes` (width, height) in square grids of
/// n × n of the largest tile per slice, n growing from 1 until the slices fit `max_depth`;
/// `None` when the slice would pass `max_dim` first. One map per slice whenever that fits.
fn plan_tiles(
    shapes: &[(u32, u32)],
    counts: &[u32],
    max_dim: u32,
    max_depth: u32,
) -> Option<TexturePlan> {
    let tw = shapes.iter().map(|s| s.0).max().unwrap_or(1);
    let th = shapes.iter().map(|s| s.1).max().unwrap_or(1);
    let mut n = 1u32;
    loop {
        let (width, height) = (n * tw, n * th);
        if width > max_dim || height > max_dim {
            return None;
        }
        let mut first = 0u32;
        let tiles: Vec<FieldTiles> = shapes
            .iter()
            .zip(counts)
            .map(|(&(tile_w, tile_h), &count)| {
                let tiles_x = width / tile_w;
                let per_slice = tiles_x * (height / tile_h);
                let t = FieldTiles {
                    tile_w,
                    tile_h,
                    tiles_x,
                    per_slice,
                    first_slice: first,
                };
                first += count.div_ceil(per_slice);
                t
            })
            .collect();
        if first <= max_depth {
            return Some(TexturePlan {
                width,
                height,
                depth: first.max(1),
                tiles,
            });
        }
        n += 1;
    }
}

/// The texture holding every field of a kernel (all of one precision).
pub(crate) struct FieldTexture {
    texture: wgpu::Texture,
    tiles: Vec<FieldTiles>,
    first_slices: Vec<u32>,
    format: wgpu::TextureFormat,
    bytes: u64,
}

/// Elements of one map's tile: texels, or 32-bit words for 1-bit maps.
fn tile_shape(f: &VisibilityField) -> (u32, u32) {
    let res = f.params.res;
    match &f.storage {
        Storage::Bit1 { texels, .. } => {
            let words = 2 * words_per_map(*texels) as u32;
            let w = words.min(res);
            (w, words.div_ceil(w))
        }
        _ => (res, res),
    }
}

impl FieldTexture {
    /// Packs `fields` (all of one precision) with at most `max_depth` slices (the adapter's
    /// limit when `None` or larger).
    pub fn new(
        ctx: &GpuContext,
        fields: &[Arc<VisibilityField>],
        max_depth: Option<u32>,
    ) -> Result<Self, GpuError> {
        let precision = fields
            .first()
            .map(|f| f.storage.precision())
            .ok_or_else(|| GpuError::Invalid("no field instances".into()))?;
        if fields.iter().any(|f| f.storage.precision() != precision) {
            return Err(GpuError::Unsupported(
                "fields of different precisions in one 3D texture (use the storage layout)".into(),
            ));
        }
        let (format, bpp) = match precision {
            crate::field::Precision::F32 => (wgpu::TextureFormat::R32Float, 4),
            crate::field::Precision::U16 => (wgpu::TextureFormat::R16Uint, 2),
            crate::field::Precision::U8 => (wgpu::TextureFormat::R8Uint, 1),
            crate::field::Precision::Bit1 => (wgpu::TextureFormat::R32Uint, 4),
        };
        let max_dim = ctx.limits().max_texture_dimension_3d;
        let max_depth = max_depth.unwrap_or(max_dim).clamp(1, max_dim);
        let shapes: Vec<(u32, u32)> = fields.iter().map(|f| tile_shape(f)).collect();
        let counts: Vec<u32> = fields.iter().map(|f| f.params.count as u32).collect();
        let plan =
            plan_tiles(&shapes, &counts, max_dim, max_depth).ok_or_else(|| GpuError::TooLarge {
                what: "field maps in one 3D texture".into(),
                need: fields.iter().map(|f| f.bytes()).sum(),
                limit: max_dim as u64 * max_dim as u64 * max_depth as u64 * bpp,
                limit_name: "max_texture_dimension_3d",
            })?;
        let TexturePlan {
            width,
            height,
            depth,
            tiles,
        } = plan;
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("field maps"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: depth,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        // Fill slice by slice on the host, then one upload per slice.
        let slice_bytes = (width * height) as usize * bpp as usize;
        let mut slices = vec![0u8; slice_bytes * depth as usize];
        for (f, t) in fields.iter().zip(&tiles) {
            let (per_map, bytes) = map_bytes(&f.storage);
            let bpe = bpp as usize;
            for m in 0..f.params.count {
                let src = &bytes[m * per_map..(m + 1) * per_map];
                for e in 0..per_map / bpe {
                    let (x, y, z) = t.texel_of(m as u32, e as u32);
                    let dst = z as usize * slice_bytes + ((y * width + x) as usize) * bpe;
                    slices[dst..dst + bpe].copy_from_slice(&src[e * bpe..(e + 1) * bpe]);
                }
            }
        }
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &slices,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(width * bpp as u32),
                rows_per_image: Some(height),
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: depth,
            },
        );
        let first_slices = tiles.iter().map(|t| t.first_slice).collect();
        Ok(FieldTexture {
            texture,
            tiles,
            first_slices,
            format,
            bytes: slices.len() as u64,
        })
    }

    /// Slices of the texture.
    pub fn depth(&self) -> u32 {
        self.texture.depth_or_array_layers()
    }

    /// Each field's first slice (the instances' `data[2]`).
    pub fn first_tiles(&self) -> &[u32] {
        &self.first_slices
    }

    /// (tiles per row, tiles per slice) of field `fi`.
    pub fn tiles(&self, fi: usize) -> (u32, u32) {
        (self.tiles[fi].tiles_x, self.tiles[fi].per_slice)
    }

    /// (tile width, tile height) of field `fi` in elements.
    pub fn tile_shape(&self, fi: usize) -> (u32, u32) {
        (self.tiles[fi].tile_w, self.tiles[fi].tile_h)
    }

    /// Bytes of the texture (padding of partly filled slices included).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    pub fn view(&self) -> wgpu::TextureView {
        self.texture
            .create_view(&wgpu::TextureViewDescriptor::default())
    }

    /// The texture binding (`@group(group) @binding(binding)`) and
    /// `load_element(coords) -> u32` (raw bits of one element).
    pub fn prelude(&self, group: u32, binding: u32) -> String {
        let (ty, load) = if self.format == wgpu::TextureFormat::R32Float {
            ("f32", "bitcast<u32>(textureLoad(field_tex, c, 0).x)")
        } else {
            ("u32", "textureLoad(field_tex, c, 0).x")
        };
        format!(
            "@group({group}) @binding({binding}) var field_tex: texture_3d<{ty}>;\n\
             fn load_element(c: vec3<u32>) -> u32 {{ return {load}; }}\n"
        )
    }

    /// The sample type of the texture binding: unfilterable float for r32float (read with
    /// `textureLoad` only), unsigned integer otherwise.
    pub fn sample_type(&self) -> wgpu::TextureSampleType {
        if self.format == wgpu::TextureFormat::R32Float {
            wgpu::TextureSampleType::Float { filterable: false }
        } else {
            wgpu::TextureSampleType::Uint
        }
    }
}

/// (bytes per map, all bytes) of a storage as the texture elements take them: texels for
/// f32 / u16 / u8, 32-bit words for 1-bit maps (the storage windows take the bytes as they
/// are: [`super::field_data::field_words`]).
pub(super) fn map_bytes(s: &Storage) -> (usize, &[u8]) {
    match s {
        Storage::F32 { texels, data } => (texels * 4, bytemuck::cast_slice(data)),
        Storage::U16 { texels, data } => (texels * 2, bytemuck::cast_slice(data)),
        Storage::U8 { texels, data } => (*texels, data),
        Storage::Bit1 { texels, bits, .. } => {
            (words_per_map(*texels) * 8, bytemuck::cast_slice(bits))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn tiles_never_overlap_and_stay_inside_the_texture() {
        // Two fields of different tile shapes, depth limits that force 1, 2 and 3 tiles a side.
        let shapes = [(16, 16), (8, 1)];
        let counts = [290, 100];
        for (max_depth, side) in [(4096, 1), (100, 2), (40, 3)] {
            let plan = plan_tiles(&shapes, &counts, 4096, max_depth).unwrap();
            assert_eq!(plan.width, 16 * side, "depth limit {max_depth}");
            assert!(plan.depth <= max_depth);
            let mut seen = HashSet::new();
            for (t, (&(w, h), &count)) in plan.tiles.iter().zip(shapes.iter().zip(&counts)) {
                for m in 0..count {
                    for e in 0..w * h {
                        let (x, y, z) = t.texel_of(m, e);
                        assert!(x < plan.width && y < plan.height && z < plan.depth);
                        assert!(seen.insert((x, y, z)), "texel ({x}, {y}, {z}) used twice");
                    }
                }
            }
        }
        // One 16² map per slice when the depth allows; the 8 × 1 tiles of the second field
        // still share a 16 × 16 slice 32 at a time: 290 + ⌈100 / 32⌉ = 294 slices.
        assert_eq!(plan_tiles(&shapes, &counts, 4096, 4096).unwrap().depth, 294);
        // Slices wider than the dimension limit: refused.
        assert!(plan_tiles(&shapes, &counts, 32, 10).is_none());
    }

    #[test]
    fn tile_shapes_hold_a_whole_map() {
        use crate::field::{FieldParams, Precision};
        use crate::geometry::Sphere;
        use crate::sampling::{LayoutKind, SphereKind};
        // Value maps: res × res texels. 1-bit maps: res 16 has 256 bits = 8 words in one row;
        // res 64: 4096 bits = 128 words in 2 rows of 64; res 5: 25 bits pad to one u64 = 2
        // words.
        for (precision, res, shape) in [
            (Precision::U8, 16, (16, 16)),
            (Precision::F32, 5, (5, 5)),
            (Precision::Bit1, 16, (8, 1)),
            (Precision::Bit1, 64, (64, 2)),
            (Precision::Bit1, 5, (2, 1)),
        ] {
            let params = FieldParams {
                sphere: SphereKind::Slater,
                count: 10,
                layout: LayoutKind::Concentric,
                res,
                precision,
            };
            let storage = Storage::new(precision, 10, (res * res) as usize);
            let sphere = Sphere {
                center: glam::Vec3::ZERO,
                radius: 1.0,
            };
            let f = VisibilityField::from_storage(params, sphere, storage).unwrap();
            assert_eq!(tile_shape(&f), shape, "{precision:?} res {res}");
            assert_eq!(
                map_bytes(&f.storage).0,
                (shape.0 * shape.1) as usize * if precision == Precision::U8 { 1 } else { 4 }
            );
        }
    }
}
