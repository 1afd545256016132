// Glossy reflections by field lookup (Gaitatzes, Andreadis, Papaioannou, Chrysanthou, WSCG
// 2010, §4.2: each reflection ray answered by the visibility field with a hit point, and by
// the normal field with the normal there): each invocation takes one receiver point and a run
// of its reflection rays (shaders/reflect_rays.wgsl), finds each ray's nearest hit over the
// field instances (as `FieldScene::surface_hit`: every instance the ray meets is looked up and
// the nearest hit kept, since bounding spheres may overlap), reads the normal of the map and
// texel the nearest selection reads (also when the distance is interpolated), turns it to the
// world, shades it, and writes the f32 sum of its kept rays' radiance and their count; the host
// adds up a point's runs in f64 and divides. An invocation whose loops the driver cut short
// writes CUT_SHORT first instead (shaders/loop_budget.wgsl).

// `params`, `receivers` and `out` are the field kernels' shared header (shaders/field_kernel.wgsl);
// the kernel's own bindings follow (src/gpu/field_reflect.rs).
@group(0) @binding(3) var<storage, read> lobe: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> lights: array<Light>;
@group(0) @binding(5) var<storage, read> shading: Shading;
// The normal fields: per instance k its first texel word (word 2k) and bits per component
// (word 2k + 1), then each distinct normal field's texels, one word each (component a in the
// low 16 bits, b in the high), maps back to back as on the host.
@group(0) @binding(6) var<storage, read> normals: array<u32>;

// One instance's answer: hit, its distance (model units) and the nearest selection's read.
struct FieldHit {
    hit: bool,
    t: f32,
    map: u32,
    texel: u32,
}

// `VisibilityField::surface_hit` (src/field/normals.rs) of instance `inst`: the lookup of
// `instance_occludes` (shaders/field_lookup.wgsl) line for line, keeping the distance and the
// map and texel of the nearest selection at the point and direction read.
fn instance_surface_hit(inst: Instance, origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32,
                        selection: u32, intra_bias: f32, intra_auto: bool) -> FieldHit {
    var res: FieldHit;
    res.hit = false;
    let ws = ray_sphere(origin, dir, inst.world_center, inst.world_radius);
    if ws.z == 0.0 || !(ws.y >= tmin && ws.x <= tmax) {
        return res;
    }
    let scale = inst.scale;
    let o = quat_rotate(inst.rotation, (origin - inst.translation) / scale);
    let d = normalize_exact(quat_rotate(inst.rotation, dir));
    let lmin = tmin / scale;
    let lmax = tmax / scale;
    let c = inst.model_center;
    let r = inst.model_radius;
    let rs = ray_sphere(o, d, c, r);
    if rs.z == 0.0 {
        return res;
    }
    let t0 = rs.x;
    let t1 = rs.y;
    let diameter = 2.0 * r;
    if t1 < lmin {
        return res;
    }
    let inside = t0 < 0.0;
    var u = vec3<f32>(0.0);
    var dread = d;
    if !inside {
        // Outside: inter-object lookup at the entry point.
        if t0 > lmax {
            return res;
        }
        let f = o - c;
        let l = f - dot(f, d) * d;
        let ll = length(l);
        let disc = (r - ll) * (r + ll);
        if disc < 0.0 {
            return res;
        }
        u = (l - sqrt(disc) * d) / r;
    } else {
        // Inside: intra-object test from the exit point back towards the origin.
        let p1 = (o - c) + t1 * d;
        let len = sqrt(dot(p1, p1));
        if len > 0.0 {
            u = p1 * (1.0 / len);
        }
        dread = -d;
    }
    let pbase = inst.point_base;
    let m = lookup_nearest(inst, u);
    let texel = lookup_texel(inst, frame_to_local(frame_from_normal(-sphere_point(pbase, m)), dread));
    var dd = 1.0;
    if selection == SELECT_NEAREST {
        dd = load_distance(inst, m, texel);
    } else {
        dd = field_sample(inst, u, dread, SELECT_INTERPOLATED);
    }
    if dd >= 1.0 {
        return res;
    }
    var t = 0.0;
    if !inside {
        t = t0 + diameter * dd;
        if !(t >= lmin && t <= lmax) {
            return res;
        }
    } else {
        t = t1 - diameter * dd;
        var tol = intra_bias * diameter;
        if intra_auto {
            tol = intra_bias * (inst.intra_positional + inst.intra_directional * t1);
        }
        if !(t > lmin + tol && t <= lmax) {
            return res;
        }
    }
    res.hit = true;
    res.t = t;
    res.map = m;
    res.texel = texel;
    return res;
}

// The radiance ray origin + t dir brings back: the nearest hit over the instances (ties go to
// the instance the host tries first: the nearer sphere entry, then the lower index), its
// normal from the instance's normal field turned to the world, shaded; `sky` on a miss.
fn field_radiance(origin: vec3<f32>, dir: vec3<f32>) -> f32 {
    var best_t = 0.0;
    var best_entry = 0.0;
    var best_k = 0xffffffffu;
    var best_word = 0u;
    for (var k = 0u; k < params.instance_count; k++) {
        let inst = instances[k];
        let h = instance_surface_hit(inst, origin, dir, 0.0, 3.4028235e38, params.selection,
                                     params.intra_bias, params.intra_auto != 0u);
        if !h.hit {
            continue;
        }
        let t = h.t * inst.scale;
        let entry = max(ray_sphere(origin, dir, inst.world_center, inst.world_radius).x, 0.0);
        if best_k == 0xffffffffu || t < best_t || (t == best_t && entry < best_entry) {
            best_t = t;
            best_entry = entry;
            best_k = k;
            let texels = inst.resolution * inst.resolution;
            best_word = normals[normals[2u * k] + h.map * texels + h.texel];
        }
    }
    if best_k == 0xffffffffu {
        return shading.sky;
    }
    let inst = instances[best_k];
    let n_model = unpack_normal(best_word, normals[2u * best_k + 1u]);
    // The instance's model -> world rotation: the conjugate of its world -> model one.
    let to_world = vec4<f32>(-inst.rotation.xyz, inst.rotation.w);
    let n = normalize_exact(quat_rotate(to_world, n_model));
    return shade_hit(origin, dir, best_t, n);
}

@compute @workgroup_size(64)
fn reflect_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    let per_point = params.invocations_per_point;
    if i >= params.point_count * per_point {
        return;
    }
    let first = (i % per_point) * params.rays_per_invocation;
    let last = min(first + params.rays_per_invocation, params.rays_per_point);
    let rc = receivers[i / per_point];
    let b = reflect_base(rc.position, rc.normal, params.origin_offset, shading.eye);
    let mirror = shading.mirror != 0u;
    var sum = 0.0;
    var kept = 0.0;
    for (var r = first; r < last; r++) {
        let ray = reflection_ray(b, lobe[r].xyz, rc.rotation_cos, rc.rotation_sin, mirror);
        if ray.w == 0.0 {
            continue;
        }
        kept += 1.0;
        sum += field_radiance(b.origin, ray.xyz);
    }
    let done = loops_completed(params.completion_trips);
    out[2u * i] = select(CUT_SHORT, bitcast<u32>(sum), done);
    out[2u * i + 1u] = bitcast<u32>(kept);
}
