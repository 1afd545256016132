// Two-level ray casting's closest-hit words (src/gpu/two_level.rs, `closest_hits`), after the
// queries every ray-casting visibility shares (shaders/ray_queries.wgsl); the instances as
// group 1 (shaders/two_level.wgsl).

// Five words a ray: the distance's bits, the instance (0xffffffff on a miss), the world normal.
fn write_closest(i: u32, r: Ray) {
    let h = two_level_trace(r.origin, r.direction, r.tmin, r.tmax, false);
    var n = vec3<f32>(0.0);
    if h.instance != NO_INSTANCE {
        n = two_level_normal(h);
    }
    out[5u * i] = bitcast<u32>(h.t);
    out[5u * i + 1u] = h.instance;
    out[5u * i + 2u] = bitcast<u32>(n.x);
    out[5u * i + 3u] = bitcast<u32>(n.y);
    out[5u * i + 4u] = bitcast<u32>(n.z);
}
