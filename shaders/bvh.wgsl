// The GPU ray-cast reference over one world BVH (src/gpu/tracer.rs): its header, its nodes and
// triangles, and the queries, with the traversal of shaders/cwbvh.wgsl.

// The visibility's header: the CWBVH's nodes (shaders/caster_header.wgsl).
@group(1) @binding(0) var<uniform> bvh: CasterHeader;
// 80-byte obvhs `CwBvhNode`s as five vec4<u32> each.
@group(1) @binding(1) var<storage, read> nodes: array<vec4<u32>>;
// Triangles in BVH order: v0 (w: original index bits), v1, v2.
@group(1) @binding(2) var<storage, read> tris: array<vec4<f32>>;

// The world BVH's traversal from its root (none for an empty scene).
fn trace_ray(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax_in: f32, any_hit: bool) -> TraceResult {
    if bvh.node_count == 0u {
        return TraceResult(tmax_in, 0xffffffffu);
    }
    return trace_from(0u, o, d, tmin, tmax_in, any_hit);
}

// The visibility's queries (src/gpu/visibility.rs): whether any triangle meets the ray with
// tmin <= t <= tmax, and the closest one with its unit geometric normal (v1 - v0) x (v2 - v0),
// as the CPU tracer's `Hit::normal`.
fn occluded(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    return trace_ray(o, d, tmin, tmax, true).id != 0xffffffffu;
}

fn surface_hit(o: vec3<f32>, d: vec3<f32>, tmax: f32) -> SurfaceHit {
    var res: SurfaceHit;
    let h = trace_ray(o, d, 0.0, tmax, false);
    res.hit = h.id != 0xffffffffu;
    if res.hit {
        let v0 = tris[3u * h.id].xyz;
        let v1 = tris[3u * h.id + 1u].xyz;
        let v2 = tris[3u * h.id + 2u].xyz;
        let c = cross(v1 - v0, v2 - v0);
        res.t = h.t;
        res.normal = c * (1.0 / sqrt(dot(c, c)));
    }
    return res;
}
