// The field visibility's closest hit (src/gpu/field_kernel.rs; Gaitatzes, Andreadis,
// Papaioannou, Chrysanthou, WSCG 2010, §4.2: a ray answered by the visibility field with a hit
// point, and by the normal field with the normal there), compiled where the normal fields are
// bound: the hit of each instance (the lookup of `instance_occludes`, keeping the map and
// texel the nearest selection reads, also when the distance is interpolated), the nearest over
// the instances, and its normal read, unpacked and turned to the world.

// The normal fields: per instance k its first texel word (word 2k) and bits per component
// (word 2k + 1), then each distinct normal field's texels, one word each (component a in the
// low 16 bits, b in the high), maps back to back as on the host.
@group(1) @binding(4) var<storage, read> normals: array<u32>;

// One instance's answer: hit, its distance (model units) and the nearest selection's read.
struct FieldHit {
    hit: bool,
    t: f32,
    map: u32,
    texel: u32,
}

// `VisibilityField::surface_hit` (src/field/normals.rs) of instance `inst`: the lookup of
// `instance_occludes` (shaders/field_lookup.wgsl: the same `instance_ray` and `segment_hit`),
// keeping the distance and the map and texel of the nearest selection at the point and
// direction read.
fn instance_surface_hit(inst: Instance, origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32,
                        selection: u32, intra_bias: f32, intra_auto: bool) -> FieldHit {
    var res: FieldHit;
    res.hit = false;
    let ir = instance_ray(inst, origin, dir, tmin, tmax);
    if !ir.met {
        return res;
    }
    let pbase = inst.point_base;
    let m = lookup_nearest(inst, ir.u);
    let texel = lookup_texel(inst, frame_to_local(frame_from_normal(-sphere_point(pbase, m)), ir.read));
    var dd = 1.0;
    if selection == SELECT_NEAREST {
        dd = load_distance(inst, m, texel);
    } else {
        dd = field_sample(inst, ir.u, ir.read, SELECT_INTERPOLATED);
    }
    let s = segment_hit(inst, ir, dd, intra_bias, intra_auto);
    if !s.hit {
        return res;
    }
    res.hit = true;
    res.t = s.t;
    res.map = m;
    res.texel = texel;
    return res;
}

// The nearest hit so far of a search over the instances: its distance, its sphere entry, the
// instance (NO_INSTANCE: none yet) and its normal texel's word.
struct Nearest {
    t: f32,
    entry: f32,
    k: u32,
    word: u32,
}

const NO_INSTANCE: u32 = 0xffffffffu;

// Instance k's closest hit along the ray kept in `best` where it is nearer: the nearer
// distance, then (ties as the host breaks them, in the order it tries instances) the nearer
// sphere entry, then the lower index. Whether it was kept.
fn keep_nearer(best: ptr<function, Nearest>, k: u32, origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> bool {
    let inst = instances[k];
    let h = instance_surface_hit(inst, origin, dir, 0.0, tmax, SELECTION,
                                 field_params.intra_bias, field_params.intra_auto != 0u);
    if !h.hit {
        return false;
    }
    let t = h.t * inst.scale;
    let entry = max(ray_sphere(origin, dir, inst.world_center, inst.world_radius).x, 0.0);
    let b = *best;
    let nearer = t < b.t || (t == b.t && (entry < b.entry || (entry == b.entry && k < b.k)));
    if b.k != NO_INSTANCE && !nearer {
        return false;
    }
    let texels = inst.resolution * inst.resolution;
    *best = Nearest(t, entry, k, normals[normals[2u * k] + h.map * texels + h.texel]);
    return true;
}

// A search's answer: no hit, or the nearest at its distance with its normal, read from the
// instance's normal field, turned to the world.
fn nearest_hit(best: Nearest) -> SurfaceHit {
    var res: SurfaceHit;
    res.hit = false;
    if best.k == NO_INSTANCE {
        return res;
    }
    let inst = instances[best.k];
    let n_model = unpack_normal(best.word, normals[2u * best.k + 1u]);
    // The instance's model -> world rotation: the conjugate of its world -> model one.
    let to_world = vec4<f32>(-inst.rotation.xyz, inst.rotation.w);
    res.hit = true;
    res.t = best.t;
    res.normal = normalize_exact(quat_rotate(to_world, n_model));
    return res;
}

// `FieldScene::surface_hit` with the normal of the hit: the nearest hit over the instances
// (every instance the ray meets is looked up and the nearest kept, since bounding spheres may
// overlap), tried in index order. The visibility's `surface_hit` where the instances have no
// top level of their own.
fn surface_hit_every_sphere(origin: vec3<f32>, dir: vec3<f32>, tmax: f32) -> SurfaceHit {
    var best = Nearest(0.0, 0.0, NO_INSTANCE, 0u);
    for (var k = 0u; k < field_params.instance_count; k++) {
        _ = keep_nearer(&best, k, origin, dir, tmax);
    }
    return nearest_hit(best);
}

// `unpack_normal` (src/field/normals.rs) of a texel word (component a in the low 16 bits, b in
// the high), `bits` bits per component: the octahedral square [-1, 1]^2 to a unit vector.
fn unpack_normal(word: u32, bits: u32) -> vec3<f32> {
    let levels = f32((1u << bits) - 1u);
    let ex = f32(word & 0xffffu) / levels * 2.0 - 1.0;
    let ey = f32(word >> 16u) / levels * 2.0 - 1.0;
    var v = vec3<f32>(ex, ey, 1.0 - abs(ex) - abs(ey));
    let t = max(-v.z, 0.0);
    v.x += select(t, -t, v.x >= 0.0);
    v.y += select(t, -t, v.y >= 0.0);
    return v * (1.0 / sqrt(dot(v, v)));
}
