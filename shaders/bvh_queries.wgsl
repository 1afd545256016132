// The CWBVH's closest-hit words (src/gpu/tracer.rs, `closest_hits`), after the queries every
// ray-casting visibility shares (shaders/ray_queries.wgsl); the CWBVH as group 1
// (shaders/bvh.wgsl).

fn original_index(id: u32) -> u32 {
    return bitcast<u32>(tris[3u * id].w);
}

// Two words a ray: the distance's bits, the original triangle (0xffffffff on a miss).
fn write_closest(i: u32, r: Ray) {
    let h = trace_ray(r.origin, r.direction, r.tmin, r.tmax, false);
    out[2u * i] = bitcast<u32>(h.t);
    out[2u * i + 1u] = select(0xffffffffu, original_index(h.id), h.id != 0xffffffffu);
}
