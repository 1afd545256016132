// The field visibility's closest hit through its own top level (shaders/field_top_level.wgsl),
// compiled where the normal fields are bound: `surface_hit_every_sphere`
// (shaders/field_surface.wgsl) with the instances found by the tree walk, the walk's far end
// the nearest hit so far (an instance entered beyond it cannot hit nearer: its hit lies past its
// sphere's entry, and its box's entry is before that), ties broken as the loop over every
// instance breaks them: the nearer sphere entry, then the lower index.
fn surface_hit_top_level(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> SurfaceHit {
    var best = Nearest(0.0, 0.0, NO_INSTANCE, 0u);
    if field_params.instance_count == 0u {
        return nearest_hit(best);
    }
    let pad = sphere_pad(origin);
    var far = tmax;
    var stack: array<u32, SPHERE_STACK>;
    stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let n = sphere_nodes[stack[sp]];
        if !sphere_node_meets(n, origin, dir, 0.0, far, pad) {
            continue;
        }
        if n.leaf == 0u {
            if sp + 2u <= SPHERE_STACK {
                stack[sp] = n.index + 1u;
                stack[sp + 1u] = n.index;
                sp += 2u;
            }
            continue;
        }
        if keep_nearer(&best, n.index, origin, dir, tmax) {
            far = min(far, best.t);
        }
    }
    return nearest_hit(best);
}
