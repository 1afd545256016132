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
        let tw = shapes.iter().map(|s| s.0).max().unwrap_or(1);
        let th = shapes.iter().map(|s| s.1).max().unwrap_or(1);
        // Square grids of n × n tiles per slice, n growing until the slices fit the depth limit.
        let mut n = 1u32;
        let (tiles, depth) = loop {
            let (w, h) = (n * tw, n * th);
            if w > max_dim || h > max_dim {
                return Err(GpuError::TooLarge {
                    what: "field maps in one 3D texture".into(),
                    need: fields.iter().map(|f| f.bytes()).sum(),
                    limit: max_dim as u64 * max_dim as u64 * max_dim as u64 * bpp,
                    limit_name: "max_texture_dimension_3d",
                });
            }
            let mut first = 0u32;
            let tiles: Vec<FieldTiles> = fields
                .iter()
                .zip(&shapes)
                .map(|(f, &(tile_w, tile_h))| {
                    let tiles_x = w / tile_w;
                    let per_slice = tiles_x * (h / tile_h);
                    let t = FieldTiles {
                        tile_w,
                        tile_h,
                        tiles_x,
                        per_slice,
                        first_slice: first,
                    };
                    first += (f.params.count as u32).div_ceil(per_slice);
                    t
                })
                .collect();
            if first <= max_depth {
                break (tiles, first.max(1));
            }
            n += 1;
        };
        let (width, height) = (n * tw, n * th);
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
            let elements = (t.tile_w * t.tile_h) as usize;
            let per_map = map_bytes(&f.storage);
            for m in 0..f.params.count {
                let m32 = m as u32;
                let slice = (t.first_slice + m32 / t.per_slice) as usize;
                let k = m32 % t.per_slice;
                let (x0, y0) = ((k % t.tiles_x) * t.tile_w, (k / t.tiles_x) * t.tile_h);
                let src = &per_map.1[m * per_map.0..(m + 1) * per_map.0];
                let bpe = bpp as usize;
                for e in 0..elements.min(per_map.0 / bpe) {
                    let (x, y) = (x0 + e as u32 % t.tile_w, y0 + e as u32 / t.tile_w);
                    let dst = slice * slice_bytes + ((y * width + x) as usize) * bpe;
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
        self.texture.create_view(&wgpu::TextureViewDescriptor::default())
    }

    /// The texture binding and `load_element(coords) -> u32` (raw bits of one element).
    pub fn prelude(&self, binding: u32) -> String {
        if self.format == wgpu::TextureFormat::R32Float {
            format!(
                "@group(0) @binding({binding}) var field_tex: texture_3d<f32>;\n\
                 fn load_element(c: vec3<u32>) -> u32 {{ return bitcast<u32>(textureLoad(field_tex, c, 0).x); }}\n"
            )
        } else {
            format!(
                "@group(0) @binding({binding}) var field_tex: texture_3d<u32>;\n\
                 fn load_element(c: vec3<u32>) -> u32 {{ return textureLoad(field_tex, c, 0).x; }}\n"
            )
        }
    }
}

/// (bytes per map, all bytes) of a storage as the texture elements take them: texels for
/// f32 / u16 / u8, 32-bit words for 1-bit maps.
fn map_bytes(s: &Storage) -> (usize, &[u8]) {
    match s {
        Storage::F32 { texels, data } => (texels * 4, bytemuck::cast_slice(data)),
        Storage::U16 { texels, data } => (texels * 2, bytemuck::cast_slice(data)),
        Storage::U8 { texels, data } => (*texels, data),
        Storage::Bit1 { texels, bits, .. } => {
            (words_per_map(*texels) * 8, bytemuck::cast_slice(bits))
        }
    }
}
