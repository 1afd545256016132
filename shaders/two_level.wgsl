// Two-level ray casting on the GPU (src/gpu/two_level.rs), the twin of the CPU's
// `trace::two_level::TwoLevel`: one CWBVH per mesh in model space (the traversal of
// shaders/cwbvh.wgsl, all meshes' nodes and triangles in one pair of buffers, each mesh from its
// own root), a top level over the instances' world boxes rebuilt on the host every frame, and
// each instance's ray moved into its model space (the similarity's inverse: rotation,
// translation, distances divided by the scale) as the CPU moves it.

// One top-level node. Mirrors `TopNodeGpu` (src/gpu/two_level.rs), 32 bytes: a box over its
// instances' world boxes; a leaf holds `count` instances from `first` in `top_order`, an inner
// node its two children (`first`, `first + 1`), as the CPU's `BoxNode`.
struct TopNode {
    lo: vec3<f32>,
    first: u32,
    hi: vec3<f32>,
    count: u32,
}

// One instance this frame. Mirrors `PlacementGpu` (src/gpu/two_level.rs), 48 bytes.
struct Placement {
    // World -> model rotation as a unit quaternion (x, y, z, w).
    rotation: vec4<f32>,
    // World translation: world = translation + scale R model.
    translation: vec3<f32>,
    // Uniform scale.
    scale: f32,
    // Its mesh's root node in `nodes`.
    root: u32,
    // Its mesh's node count (0: an empty mesh).
    node_count: u32,
    _pad0: u32,
    _pad1: u32,
}

// The visibility's header: the top level's nodes, the instances (shaders/caster_header.wgsl).
@group(1) @binding(0) var<uniform> two_level: CasterHeader;
// Every mesh's CWBVH nodes, child and primitive indices absolute (80 bytes a node).
@group(1) @binding(1) var<storage, read> nodes: array<vec4<u32>>;
// Every mesh's triangles in BVH order, model space: v0 (w: the mesh's own index bits), v1, v2.
@group(1) @binding(2) var<storage, read> tris: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read> top_nodes: array<TopNode>;
@group(1) @binding(4) var<storage, read> top_order: array<u32>;
@group(1) @binding(5) var<storage, read> placements: array<Placement>;

const NO_INSTANCE: u32 = 0xffffffffu;

// Whether the segment origin + t dir, t in [tmin, tmax], may meet node `n`'s box (the CPU's
// slab test; an axis the direction does not move along keeps the box where the origin lies
// within its slab).
fn top_meets(n: TopNode, o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    var near = tmin;
    var far = tmax;
    for (var a = 0u; a < 3u; a++) {
        if d[a] == 0.0 {
            if o[a] < n.lo[a] || o[a] > n.hi[a] {
                return false;
            }
            continue;
        }
        let inv = 1.0 / d[a];
        let t0 = (n.lo[a] - o[a]) * inv;
        let t1 = (n.hi[a] - o[a]) * inv;
        near = max(near, min(t0, t1));
        far = min(far, max(t0, t1));
    }
    return near <= far;
}

// The closest hit over the instances (or, with `any_hit`, the first found): its world distance,
// its instance and its BVH-ordered triangle (NO_INSTANCE on a miss), as `TwoLevel::surface_hit`
// and `TwoLevel::occluded` walk the top level: each instance whose box the segment meets traced
// in its model space, the segment's end shrinking with every hit.
struct TwoLevelHit {
    t: f32,
    instance: u32,
    triangle: u32,
}

fn two_level_trace(origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax_in: f32, any_hit: bool) -> TwoLevelHit {
    var best = TwoLevelHit(tmax_in, NO_INSTANCE, 0xffffffffu);
    if two_level.node_count == 0u {
        return best;
    }
    var tmax = tmax_in;
    var stack: array<u32, 32>;
    stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let n = top_nodes[stack[sp]];
        if !top_meets(n, origin, dir, tmin, tmax) {
            continue;
        }
        if n.count == 0u {
            // A median-split tree of N instances is at most ceil(log2 N) + 1 deep: 32 entries
            // hold any instance count a u32 indexes (the guard is never taken).
            if sp + 2u <= 32u {
                stack[sp] = n.first;
                stack[sp + 1u] = n.first + 1u;
                sp += 2u;
            }
            continue;
        }
        for (var j = n.first; j < n.first + n.count; j++) {
            let i = top_order[j];
            let p = placements[i];
            if p.node_count == 0u {
                continue;
            }
            // `Similarity::to_local_point` and `to_local_dir`; distances times 1 / scale.
            let o = quat_rotate(p.rotation, (origin - p.translation) / p.scale);
            let d = quat_rotate(p.rotation, dir);
            let k = 1.0 / p.scale;
            let h = trace_from(p.root, o, d, tmin * k, tmax * k, any_hit);
            if h.id != 0xffffffffu {
                let t = min(h.t / k, tmax);
                best = TwoLevelHit(t, i, h.id);
                if any_hit {
                    return best;
                }
                tmax = t;
            }
        }
    }
    return best;
}

// The visibility's queries (src/gpu/visibility.rs): whether any instance's triangle meets the
// ray with tmin <= t <= tmax, and the closest one with its unit geometric normal
// (v1 - v0) x (v2 - v0) in model space turned to the world, as `TwoLevel::surface_hit`.
fn occluded(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    return two_level_trace(o, d, tmin, tmax, true).instance != NO_INSTANCE;
}

fn two_level_normal(h: TwoLevelHit) -> vec3<f32> {
    let v0 = tris[3u * h.triangle].xyz;
    let v1 = tris[3u * h.triangle + 1u].xyz;
    let v2 = tris[3u * h.triangle + 2u].xyz;
    let c = cross(v1 - v0, v2 - v0);
    let q = placements[h.instance].rotation;
    // The model -> world rotation: the conjugate of the world -> model one.
    return quat_rotate(vec4<f32>(-q.xyz, q.w), c * (1.0 / sqrt(dot(c, c))));
}

fn surface_hit(o: vec3<f32>, d: vec3<f32>, tmax: f32) -> SurfaceHit {
    var res: SurfaceHit;
    let h = two_level_trace(o, d, 0.0, tmax, false);
    res.hit = h.instance != NO_INSTANCE;
    if res.hit {
        res.t = h.t;
        res.normal = two_level_normal(h);
    }
    return res;
}
