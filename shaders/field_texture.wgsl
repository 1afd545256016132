// Field layout 2: maps as tiles of the slices of a 3D texture (the 2010 paper's packing). The
// host prepends the `field_tex` binding and `load_element(coords) -> u32`, the raw bits of one
// element: an f32 distance, a u16 or u8 code, or a 32-bit word of a 1-bit map.
// Instance fields: `data_base` is the first slice; `tiles_per_row`, `tiles_per_slice`,
// `tile_width` and `tile_height` place the maps in it.

// Element `e` of map `m`'s tile.
fn load_tile(inst: Instance, m: u32, e: u32) -> u32 {
    let per_slice = inst.tiles_per_slice;
    let tile_w = inst.tile_width;
    let tile_h = inst.tile_height;
    let tiles_x = inst.tiles_per_row;
    let k = m % per_slice;
    let x = (k % tiles_x) * tile_w + e % tile_w;
    let y = (k / tiles_x) * tile_h + e / tile_w;
    return load_element(vec3<u32>(x, y, inst.data_base + m / per_slice));
}

fn load_distance(inst: Instance, m: u32, t: u32) -> f32 {
    let prec = fixed_or(FIXED_PRECISION, inst.storage_precision);
    if prec == PRECISION_F32 {
        return bitcast<f32>(load_tile(inst, m, t));
    }
    if prec == PRECISION_U16 {
        return f32(load_tile(inst, m, t)) / 65535.0;
    }
    if prec == PRECISION_U8 {
        return f32(load_tile(inst, m, t)) / 255.0;
    }
    let w = load_tile(inst, m, t / 32u);
    if ((w >> (t % 32u)) & 1u) == 1u {
        return bit1_mean(inst, m);
    }
    return 1.0;
}
