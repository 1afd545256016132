// The ray-query visibility's closest-hit words (src/gpu/ray_query.rs, `closest_hits`), after
// the queries every ray-casting visibility shares (shaders/ray_queries.wgsl); the acceleration
// structures as group 1 (shaders/ray_query.wgsl).

// Six words a ray: t, the triangle's index in its mesh (0xffffffff: no hit), the normal, the
// instance.
fn write_closest(i: u32, r: Ray) {
    let h = closest_hit(r.origin, r.direction, r.tmin, r.tmax);
    var original = 0xffffffffu;
    if h.triangle != 0xffffffffu {
        original = bitcast<u32>(rq_tris[3u * h.triangle].w);
    }
    out[6u * i] = bitcast<u32>(h.t);
    out[6u * i + 1u] = original;
    out[6u * i + 2u] = bitcast<u32>(h.normal.x);
    out[6u * i + 3u] = bitcast<u32>(h.normal.y);
    out[6u * i + 4u] = bitcast<u32>(h.normal.z);
    out[6u * i + 5u] = h.instance;
}
