// Field lookup on the GPU: 2008 Algorithm 2 (inter-object) and the 2010 intra-object test, a
// port of src/field/lookup.rs (`ray_sphere`, `entry_point_relative`, `sample`,
// `sample_interpolated`, `hit_distance`) and src/field/scene.rs (`FieldInstance`), in f32.
// Needs `load_distance(inst, map, texel)` from the field layout (storage windows or 3D texture)
// and the sphere-point and layout functions.

const SELECT_NEAREST: u32 = 0u;
const SELECT_INTERPOLATED: u32 = 1u;

// One placed field. Mirrors `FieldInstanceGpu` (src/gpu/field_data.rs), 160 bytes.
struct Instance {
    // World -> model rotation as a unit quaternion (x, y, z, w).
    rotation: vec4<f32>,
    // World translation: world = translation + scale R model.
    translation: vec3<f32>,
    // Uniform scale.
    scale: f32,
    // Centre of the world-space bounding sphere.
    world_center: vec3<f32>,
    // Radius of the world-space bounding sphere.
    world_radius: f32,
    // Centre of the model-space bounding sphere.
    model_center: vec3<f32>,
    // Radius of the model-space bounding sphere.
    model_radius: f32,
    // Sphere kind (SPHERE_SLATER, SPHERE_LAT_LONG).
    sphere_kind: u32,
    // Number of maps (sphere points).
    map_count: u32,
    // Ring parameter: Slater n or lat-long rows.
    ring_param: u32,
    // Layout kind (LAYOUT_POLAR, LAYOUT_REJECTION, LAYOUT_CONCENTRIC).
    layout_kind: u32,
    // Map resolution (texels a side).
    resolution: u32,
    // Precision (PRECISION_F32, _U16, _U8, _BIT1).
    storage_precision: u32,
    // First data word (storage layout) or first texture slice (texture layout).
    data_base: u32,
    // First 1-bit mean entry in `tables` (four means an entry).
    mean_base: u32,
    // First sphere point entry in `tables`.
    point_base: u32,
    // First triangle entry in `mesh`.
    mesh_base: u32,
    // Step cap of the interpolated selection's triangle walk.
    walk_steps: u32,
    // Tiles per row of a texture slice (texture layout).
    tiles_per_row: u32,
    // Tiles per texture slice (texture layout).
    tiles_per_slice: u32,
    // Tile width in elements (texture layout).
    tile_width: u32,
    // Tile height in elements (texture layout).
    tile_height: u32,
    // Owner table: cells per cube face edge, 0 for none (shaders/lookup_tables.wgsl).
    owner_grid: u32,
    // Intra-object tolerance, positional part (model units).
    intra_positional: f32,
    // Intra-object tolerance, directional part (radians).
    intra_directional: f32,
    // First owner-table code in `mesh`, in 16-bit halves.
    owner_base: u32,
    // First owner-table pair in `mesh`, in words.
    pair_base: u32,
    // Texel table: cells per side, 0 for none.
    texel_grid: u32,
    // First texel-table cell in `mesh`, in 16-bit halves.
    texel_base: u32,
    // Candidate grid (the CPU's cube grid, for MIXED owner cells): cells per face edge, 0 for
    // none.
    cand_grid: u32,
    // First candidate-grid cell in `mesh`, in entries.
    cand_base: u32,
}

// Storage precisions (`Instance::storage_precision`), as the layouts' `load_distance` reads them.
const PRECISION_F32: u32 = 0u;
const PRECISION_U16: u32 = 1u;
const PRECISION_U8: u32 = 2u;
const PRECISION_BIT1: u32 = 3u;

// Per-map mean of a 1-bit field: four means per table entry.
fn bit1_mean(inst: Instance, m: u32) -> f32 {
    return tables[inst.mean_base + m / 4u][m % 4u];
}

// Near and far roots of a unit-direction ray against a sphere (Haines et al., Ray Tracing
// Gems ch. 7, in f32); z = 1 when it hits, 0 when it misses.
fn ray_sphere(o: vec3<f32>, d: vec3<f32>, c: vec3<f32>, r: f32) -> vec3<f32> {
    let f = o - c;
    let b = -dot(f, d);
    let l = f + b * d;
    let ll = length(l);
    let disc = (r - ll) * (r + ll);
    if disc < 0.0 {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    let fl = length(f);
    let cc = (fl - r) * (fl + r);
    let s = sqrt(disc);
    let q = select(b - s, b + s, b >= 0.0);
    var t0 = 0.0;
    var t1 = 0.0;
    if q != 0.0 {
        t0 = cc / q;
        t1 = q;
    }
    return vec3<f32>(min(t0, t1), max(t0, t1), 1.0);
}

// Normalised distance D stored for a ray crossing the sphere at unit `u` with model direction
// `dir` pointing into the sphere.
fn field_sample(inst: Instance, u: vec3<f32>, dir: vec3<f32>, selection: u32) -> f32 {
    let kind = fixed_or(FIXED_SPHERE, inst.sphere_kind);
    let n = inst.ring_param;
    let lay = fixed_or(FIXED_LAYOUT, inst.layout_kind);
    let res = inst.resolution;
    let pbase = inst.point_base;
    let m = lookup_nearest(inst, u);
    if selection == SELECT_NEAREST {
        let local = frame_to_local(frame_from_normal(-sphere_point(pbase, m)), dir);
        return load_distance(inst, m, lookup_texel(inst, local));
    }
    // Interpolated: hits and misses blended as an occupancy (src/field/lookup.rs).
    let s = surrounding(u, m, pbase, inst.mesh_base, inst.walk_steps);
    var occ = 0.0;
    var dist = 0.0;
    for (var k = 0u; k < 3u; k++) {
        let w = s.weights[k];
        if w <= 0.0 {
            continue;
        }
        let mk = s.maps[k];
        let local = frame_to_local(frame_from_normal(-sphere_point(pbase, mk)), dir);
        let fp = bilinear_footprint(lay, res, local);
        for (var j = 0u; j < 4u; j++) {
            let tw = fp.weights[j];
            if tw <= 0.0 {
                continue;
            }
            let dj = load_distance(inst, mk, fp.texels[j]);
            if dj < 1.0 {
                occ += w * tw;
                dist += w * tw * dj;
            }
        }
    }
    if occ >= 0.5 {
        return dist / occ;
    }
    return 1.0;
}

// Instance `inst`'s part of the world segment origin + t dir, t in [tmin, tmax], where every
// query of one instance starts (`instance_occludes`; `instance_surface_hit` in
// shaders/field_surface.wgsl): the segment in model space (`o`, `d`, `lmin`, `lmax`), where
// it crosses the model sphere (`t0`, `t1`) and where the lookup reads (`u` on the unit sphere,
// direction `read`): outside, the inter-object lookup at the entry point along `d`; `inside`
// (t0 < 0), the intra-object test from the exit point back towards the origin, along `-d`.
// `met` is false where the world sphere test, the model sphere, the segment's span or (outside)
// the entry point leaves the instance out before any lookup.
struct InstanceRay {
    met: bool,
    o: vec3<f32>,
    d: vec3<f32>,
    lmin: f32,
    lmax: f32,
    t0: f32,
    t1: f32,
    inside: bool,
    u: vec3<f32>,
    read: vec3<f32>,
}

fn instance_ray(inst: Instance, origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32) -> InstanceRay {
    var ir: InstanceRay;
    ir.met = false;
    // World-space sphere test first (src/field/scene.rs).
    let ws = ray_sphere(origin, dir, inst.world_center, inst.world_radius);
    if ws.z == 0.0 || !(ws.y >= tmin && ws.x <= tmax) {
        return ir;
    }
    let scale = inst.scale;
    ir.o = quat_rotate(inst.rotation, (origin - inst.translation) / scale);
    ir.d = normalize_exact(quat_rotate(inst.rotation, dir));
    ir.lmin = tmin / scale;
    ir.lmax = tmax / scale;
    let rs = ray_sphere(ir.o, ir.d, inst.model_center, inst.model_radius);
    if rs.z == 0.0 {
        return ir;
    }
    ir.t0 = rs.x;
    ir.t1 = rs.y;
    if ir.t1 < ir.lmin {
        return ir;
    }
    let c = inst.model_center;
    let r = inst.model_radius;
    ir.inside = ir.t0 < 0.0;
    ir.u = vec3<f32>(0.0);
    ir.read = ir.d;
    if !ir.inside {
        // Outside: inter-object lookup at the entry point.
        if ir.t0 > ir.lmax {
            return ir;
        }
        let f = ir.o - c;
        let l = f - dot(f, ir.d) * ir.d;
        let ll = length(l);
        let disc = (r - ll) * (r + ll);
        if disc < 0.0 {
            return ir;
        }
        ir.u = (l - sqrt(disc) * ir.d) / r;
    } else {
        // Inside: intra-object test from the exit point back towards the origin.
        let p1 = (ir.o - c) + ir.t1 * ir.d;
        let len = sqrt(dot(p1, p1));
        if len > 0.0 {
            ir.u = p1 * (1.0 / len);
        }
        ir.read = -ir.d;
    }
    ir.met = true;
    return ir;
}

// A stored distance `dd` read at `ir` as a hit: its model distance from the entry point, or
// back from the exit point inside, and whether it lies in the segment (inside, beyond the
// intra-object tolerance). No hit where `dd` is 1 or more.
struct SegmentHit {
    hit: bool,
    t: f32,
}

fn segment_hit(inst: Instance, ir: InstanceRay, dd: f32, intra_bias: f32, intra_auto: bool) -> SegmentHit {
    var res = SegmentHit(false, 0.0);
    if dd >= 1.0 {
        return res;
    }
    let diameter = 2.0 * inst.model_radius;
    if !ir.inside {
        res.t = ir.t0 + diameter * dd;
        res.hit = res.t >= ir.lmin && res.t <= ir.lmax;
        return res;
    }
    res.t = ir.t1 - diameter * dd;
    // `IntraBias::model_units` (src/field/lookup.rs): Auto scales the field's own tolerance.
    var tol = intra_bias * diameter;
    if intra_auto {
        tol = intra_bias * (inst.intra_positional + inst.intra_directional * ir.t1);
    }
    res.hit = res.t > ir.lmin + tol && res.t <= ir.lmax;
    return res;
}

// Whether instance `inst` blocks the world segment origin + t dir, t in [tmin, tmax].
fn instance_occludes(inst: Instance, origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32,
                     selection: u32, intra_bias: f32, intra_auto: bool) -> bool {
    let ir = instance_ray(inst, origin, dir, tmin, tmax);
    if !ir.met {
        return false;
    }
    let dd = field_sample(inst, ir.u, ir.read, selection);
    return segment_hit(inst, ir, dd, intra_bias, intra_auto).hit;
}
