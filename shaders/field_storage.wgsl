// Field layout 1: every field's stored words in storage buffers ("windows" of at most the
// adapter's max_storage_buffer_binding_size), exactly as the host stores them: F32 one word per
// texel, U16 two and U8 four texels per word (little-endian, maps back to back), Bit1 one bit
// per texel with each map padded to 64-bit words and the per-map mean in `tables`.
// The host prepends `WINDOW_WORDS`, the `win*` bindings and `load_word(address)`.

fn load_distance(inst: Instance, m: u32, t: u32) -> f32 {
    let res = inst.resolution;
    let texels = res * res;
    let base = inst.data_base;
    let prec = fixed_or(FIXED_PRECISION, inst.storage_precision);
    if prec == PRECISION_F32 {
        return bitcast<f32>(load_word(base + m * texels + t));
    }
    if prec == PRECISION_U16 {
        let g = m * texels + t;
        let q = (load_word(base + g / 2u) >> (16u * (g % 2u))) & 0xffffu;
        return f32(q) / 65535.0;
    }
    if prec == PRECISION_U8 {
        let g = m * texels + t;
        let q = (load_word(base + g / 4u) >> (8u * (g % 4u))) & 0xffu;
        return f32(q) / 255.0;
    }
    // Bit1: words_per_map(texels) 64-bit words per map = twice as many 32-bit words.
    let words = 2u * ((texels + 63u) / 64u);
    let w = load_word(base + m * words + t / 32u);
    if ((w >> (t % 32u)) & 1u) == 1u {
        return bit1_mean(inst, m);
    }
    return 1.0;
}
