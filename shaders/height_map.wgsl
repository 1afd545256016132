// The height map M of the relief kernels (shaders/relief.wgsl, shaders/relief_peers.wgsl),
// which declare `params.size` (width, height) and the `heights` buffer: a texel clamped to the
// map, and M(s), bilinear between texel centres, clamped beyond them (`HeightMap::texel`,
// `HeightMap::sample`, in the same f32 order).

fn texel(i: i32, j: i32) -> f32 {
    let w = i32(params.size.x);
    let h = i32(params.size.y);
    return heights[clamp(j, 0, h - 1) * w + clamp(i, 0, w - 1)];
}

fn sample_map(s: vec2<f32>) -> f32 {
    let x = s.x * f32(params.size.x) - 0.5;
    let y = s.y * f32(params.size.y) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let i = i32(x0);
    let j = i32(y0);
    let a = texel(i, j) * (1.0 - fx) + texel(i + 1, j) * fx;
    let b = texel(i, j + 1) * (1.0 - fx) + texel(i + 1, j + 1) * fx;
    return a * (1.0 - fy) + b * fy;
}
