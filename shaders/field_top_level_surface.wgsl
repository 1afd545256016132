// The field visibility's closest hit through its own top level (shaders/field_top_level.wgsl),
// compiled where the normal fields are bound: `surface_hit_every_sphere`
// (shaders/field_surface.wgsl) with the instances found by the tree walk, the walk's far end
// the nearest hit so far (an instance entered beyond it cannot hit nearer: its hit lies past its
// sphere's entry, and its box's entry is before that), ties broken as the loop over every
// instance breaks them: the nearer sphere entry, then the lower index.
fn surface_hit_top_level(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> SurfaceHit {
    var res: SurfaceHit;
    res.hit = false;
    if field_params.instance_count == 0u {
        return res;
    }
    var best_t = 0.0;
    var best_entry = 0.0;
    var best_k = 0xffffffffu;
    var best_word = 0u;
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
        let k = n.index;
        let inst = instances[k];
        let h = instance_surface_hit(inst, origin, dir, 0.0, tmax, SELECTION,
                                     field_params.intra_bias, field_params.intra_auto != 0u);
        if !h.hit {
            continue;
        }
        let t = h.t * inst.scale;
        let entry = max(ray_sphere(origin, dir, inst.world_center, inst.world_radius).x, 0.0);
        let nearer = t < best_t || (t == best_t && (entry < best_entry || (entry == best_entry && k < best_k)));
        if best_k == 0xffffffffu || nearer {
            best_t = t;
            best_entry = entry;
            best_k = k;
            let texels = inst.resolution * inst.resolution;
            best_word = normals[normals[2u * k] + h.map * texels + h.texel];
            far = min(far, t);
        }
    }
    if best_k == 0xffffffffu {
        return res;
    }
    let inst = instances[best_k];
    let n_model = unpack_normal(best_word, normals[2u * best_k + 1u]);
    // The instance's model -> world rotation: the conjugate of its world -> model one.
    let to_world = vec4<f32>(-inst.rotation.xyz, inst.rotation.w);
    res.hit = true;
    res.t = best_t;
    res.normal = normalize_exact(quat_rotate(to_world, n_model));
    return res;
}
