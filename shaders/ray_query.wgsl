// The hardware ray-query visibility (src/gpu/ray_query.rs): a TLAS over the instances, one
// BLAS per mesh (opaque triangles), walked by the device's ray queries. Group 1: its header,
// the TLAS, every mesh's triangles (three vec4 each, in BLAS order, the original index in the
// first's w) and, per instance (the TLAS instance's custom data), its mesh's first triangle.
// The WGSL follows the pitfalls of docs/gpu.md "Ray queries": each query's `ray_query` is a
// function variable declared outside any loop and never passed by pointer to a helper.

// The visibility's header: the instances (shaders/caster_header.wgsl).
@group(1) @binding(0) var<uniform> rq_header: CasterHeader;
@group(1) @binding(1) var rq_tlas: acceleration_structure;
@group(1) @binding(2) var<storage, read> rq_tris: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read> rq_first_triangle: array<u32>;

// Whether any triangle meets the ray with tmin <= t <= tmax (both windings): the first hit
// found ends the walk.
fn occluded(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    var rq: ray_query;
    let flags = RAY_FLAG_TERMINATE_ON_FIRST_HIT | RAY_FLAG_FORCE_OPAQUE;
    rayQueryInitialize(&rq, rq_tlas, RayDesc(flags, 0xffu, tmin, tmax, o, d));
    while rayQueryProceed(&rq) {}
    return rayQueryGetCommittedIntersection(&rq).kind != RAY_QUERY_INTERSECTION_NONE;
}

// The closest hit with tmin <= t <= tmax: its distance, the index of its triangle in
// `rq_tris` (0xffffffff: none), its instance and its unit normal in world space (the model-space normal of
// the triangle, cross(v1 - v0, v2 - v0), moved by the transpose of the instance's
// world-to-object matrix).
struct RayQueryHit {
    t: f32,
    triangle: u32,
    instance: u32,
    normal: vec3<f32>,
}

fn closest_hit(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> RayQueryHit {
    var rq: ray_query;
    rayQueryInitialize(
        &rq,
        rq_tlas,
        RayDesc(RAY_FLAG_FORCE_OPAQUE, 0xffu, tmin, tmax, o, d),
    );
    while rayQueryProceed(&rq) {}
    let h = rayQueryGetCommittedIntersection(&rq);
    var res: RayQueryHit;
    res.triangle = 0xffffffffu;
    if h.kind != RAY_QUERY_INTERSECTION_NONE {
        let tri = rq_first_triangle[h.instance_custom_data] + h.primitive_index;
        let v0 = rq_tris[3u * tri].xyz;
        let c = cross(rq_tris[3u * tri + 1u].xyz - v0, rq_tris[3u * tri + 2u].xyz - v0);
        let w = h.world_to_object;
        let n = vec3<f32>(dot(w[0], c), dot(w[1], c), dot(w[2], c));
        res.t = h.t;
        res.triangle = tri;
        res.instance = h.instance_custom_data;
        res.normal = n * (1.0 / sqrt(dot(n, n)));
    }
    return res;
}

fn surface_hit(o: vec3<f32>, d: vec3<f32>, tmax: f32) -> SurfaceHit {
    let h = closest_hit(o, d, 0.0, tmax);
    var res: SurfaceHit;
    res.hit = h.triangle != 0xffffffffu;
    res.t = h.t;
    res.normal = h.normal;
    return res;
}
