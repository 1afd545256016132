// The field visibility's own top level (src/gpu/field_binding.rs, `FieldGpuOptions::top_level`;
// the GPU twin of the CPU's `field::sphere_bvh`): a BVH over the instances' bounding spheres,
// box nodes, rebuilt on the host whenever the instances move and walked here with a stack, so
// that a ray runs the lookup of the instances whose spheres it may meet instead of testing
// every instance's sphere (2008 Algorithm 2's loop over every occluder). Deviation from the
// paper: the loop over the occluders becomes a tree walk; the answers are those of testing
// every sphere (shaders/field_visibility.wgsl), bit for bit: a node's box holds its instances'
// spheres with a margin far above the f32 rounding of the slab test and of the instance's own
// world-sphere test (the CPU tree's boxes, with its origin-dependent pad), so every instance
// whose world-sphere test passes is still looked up, and neither whether a ray is occluded nor
// its nearest hit (ties broken by the instance index) depends on the order they are tried in.

// One node. Mirrors `SphereNodeGpu` (src/gpu/field_binding.rs), 32 bytes: its box; a leaf's
// instance, or an inner node's first child (the second follows it).
struct SphereNode {
    lo: vec3<f32>,
    index: u32,
    hi: vec3<f32>,
    // 1 for a leaf, 0 for an inner node.
    leaf: u32,
}

// Whether the segment origin + t dir, t in [tmin, tmax], may meet node `n`'s box widened by
// `pad` (the CPU's `BoxFrom::test`; an axis the direction does not, or all but does not, move
// along keeps the box where the origin lies within its slab).
fn sphere_node_meets(n: SphereNode, origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32,
                     pad: f32) -> bool {
    var near = tmin;
    var far = tmax;
    for (var a = 0u; a < 3u; a++) {
        let lo = n.lo[a] - origin[a] - pad;
        let hi = n.hi[a] - origin[a] + pad;
        if abs(dir[a]) < 1e-20 {
            if lo > 0.0 || hi < 0.0 {
                return false;
            }
            continue;
        }
        let inv = 1.0 / dir[a];
        let t0 = lo * inv;
        let t1 = hi * inv;
        near = max(near, min(t0, t1));
        far = min(far, max(t0, t1));
    }
    return near <= far;
}

// The origin's share of the rounding margin (`FieldInstance::may_meet_from`).
fn sphere_pad(origin: vec3<f32>) -> f32 {
    let a = abs(origin);
    return MAY_MEET_SLACK * max(a.x, max(a.y, a.z));
}

// A median-split tree of N instances is at most ceil(log2 N) + 1 deep: 32 entries hold any
// instance count a u32 indexes.
const SPHERE_STACK: u32 = 32u;

// `occluded` through the tree: whether any instance blocks origin + t dir, t in [tmin, tmax].
fn occluded_top_level(origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    if field_params.instance_count == 0u {
        return false;
    }
    let pad = sphere_pad(origin);
    var stack: array<u32, SPHERE_STACK>;
    stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let n = sphere_nodes[stack[sp]];
        if !sphere_node_meets(n, origin, dir, tmin, tmax, pad) {
            continue;
        }
        if n.leaf != 0u {
            if instance_occludes(instances[n.index], origin, dir, tmin, tmax, SELECTION, field_params.intra_bias, field_params.intra_auto != 0u) {
                return true;
            }
        } else if sp + 2u <= SPHERE_STACK {
            stack[sp] = n.index + 1u;
            stack[sp + 1u] = n.index;
            sp += 2u;
        }
    }
    return false;
}
