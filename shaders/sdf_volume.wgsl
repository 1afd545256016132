// Instanced mesh distance volumes (src/sdf; the engines' per-object peer): the records, the
// stored samples decoded as the host decodes them, the trilinear read, one volume's sphere
// trace (`DistanceVolume::trace`), the scene's AO query (`SdfScene::occluded`) and one cone's
// closest-approach visibility (`sdf::cone::cone_visibility`, `SdfScene::cone_visibility`), each
// a line-by-line port in the CPU's f32 order (src/gpu/sdf_kernel.rs says what still differs).
// The SDF visibility (group 1; src/gpu/sdf_kernel.rs): its header, the volumes, the instances
// and the stored samples, and `occluded`, the sphere trace the AO integrand runs.

// Mirrors `SdfParamsGpu` (src/gpu/sdf_kernel.rs), 16 bytes.
struct SdfParams {
    // Instances.
    instance_count: u32,
    // Steps per ray, cone and volume (`SdfTrace::max_steps`, `ConeTrace::max_steps`).
    max_steps: u32,
    // Cone kernels: a cone's least step, a share of its radius (`ConeTrace::step`).
    cone_step: f32,
    // Cone AO: tan of the cones' common half-angle (`ConeSet::tan_half`).
    cone_tan: f32,
}

// Mirrors `SdfVolumeGpu` (src/gpu/sdf_data.rs), 80 bytes.
struct SdfVolume {
    lo: vec3<f32>,
    voxel: f32,
    hi: vec3<f32>,
    storage: u32,
    dims: vec3<u32>,
    offset: u32,
    center: vec3<f32>,
    radius: f32,
    decode: u32,
    hit: f32,
    start: f32,
    _pad: u32,
}

// Mirrors `SdfInstanceGpu` (src/gpu/sdf_data.rs), 48 bytes.
struct SdfInstance {
    rotation: vec4<f32>,
    translation: vec3<f32>,
    scale: f32,
    volume: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(1) @binding(0) var<uniform> sdf: SdfParams;
@group(1) @binding(1) var<storage, read> sdf_volumes: array<SdfVolume>;
@group(1) @binding(2) var<storage, read> sdf_instances: array<SdfInstance>;
@group(1) @binding(3) var<storage, read> sdf_words: array<u32>;

const SDF_F32: u32 = 0u;
const SDF_F16: u32 = 1u;

// Sample i of volume v, decoded (`Samples::get`).
fn sdf_stored(v: SdfVolume, i: u32) -> f32 {
    if v.storage == SDF_F32 {
        return bitcast<f32>(sdf_words[v.offset + i]);
    }
    if v.storage == SDF_F16 {
        let h = (sdf_words[v.offset + i / 2u] >> (16u * (i % 2u))) & 0xffffu;
        return f16_to_f32(h) * v.voxel;
    }
    let e = (sdf_words[v.offset + i / 4u] >> (8u * (i % 4u))) & 0xffu;
    return bitcast<f32>(sdf_words[v.decode + e]);
}

fn sdf_lerp(a: f32, b: f32, t: f32) -> f32 {
    return a + (b - a) * t;
}

// The read distance at model point p (`DistanceVolume::sample`): the trilinear interpolation
// of the decoded samples, clamped to the grid, plus the distance to the grid's box outside it.
fn sdf_sample(v: SdfVolume, p: vec3<f32>) -> f32 {
    let q = gmin(gmax(p, v.lo), v.hi);
    let off = p - q;
    let outside = sqrt(dot(off, off));
    let g = (q - v.lo) / v.voxel;
    let top = vec3<f32>(v.dims - vec3<u32>(2u));
    let c = gmin(g, top);
    let ijk = vec3<u32>(c);
    let f = g - vec3<f32>(ijk);
    let nx = v.dims.x;
    let sz = nx * v.dims.y;
    let n = ijk.x + nx * (ijk.y + v.dims.y * ijk.z);
    let x00 = sdf_lerp(sdf_stored(v, n), sdf_stored(v, n + 1u), f.x);
    let x10 = sdf_lerp(sdf_stored(v, n + nx), sdf_stored(v, n + nx + 1u), f.x);
    let x01 = sdf_lerp(sdf_stored(v, n + sz), sdf_stored(v, n + sz + 1u), f.x);
    let x11 = sdf_lerp(sdf_stored(v, n + nx + sz), sdf_stored(v, n + nx + sz + 1u), f.x);
    return sdf_lerp(sdf_lerp(x00, x10, f.y), sdf_lerp(x01, x11, f.y), f.z) + outside;
}

// glam's `Vec3::min`, `Vec3::max` (a < b ? a : b, a > b ? a : b: the sign of a zero as on the
// host), `min_element` and `max_element`.
fn gmin(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return select(b, a, a < b);
}

fn gmax(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return select(b, a, a > b);
}

fn max3(v: vec3<f32>) -> f32 {
    let xy = select(v.y, v.x, v.x > v.y);
    return select(v.z, xy, xy > v.z);
}

fn min3(v: vec3<f32>) -> f32 {
    let xy = select(v.y, v.x, v.x < v.y);
    return select(v.z, xy, xy < v.z);
}

// The first t in [tmin, tmax] where sphere tracing model ray o + t d (unit d) reads below the
// hit threshold, or -1 (`DistanceVolume::trace`: clipped to the grid's box, started no nearer
// than the start offset).
fn sdf_trace(v: SdfVolume, o: vec3<f32>, d: vec3<f32>, tmin_in: f32, tmax: f32) -> f32 {
    let tmin = max(tmin_in, v.start);
    let inv = 1.0 / d;
    let t0 = (v.lo - o) * inv;
    let t1 = (v.hi - o) * inv;
    let near = max(max3(gmin(t0, t1)), tmin);
    let far = min(min3(gmax(t0, t1)), tmax);
    if !(near <= far) {
        return -1.0;
    }
    var t = near;
    for (var s = 0u; s < sdf.max_steps; s++) {
        let r = sdf_sample(v, o + t * d);
        if r < v.hit {
            return t;
        }
        t += r;
        if t > far {
            return -1.0;
        }
    }
    return -1.0;
}

// Whether any instance's volume stops world ray origin + t dir, t in [tmin, tmax]
// (`SdfScene::occluded`: each instance traced in its model space along the unit direction, the
// hit's t back in units of `dir`).
fn occluded(origin: vec3<f32>, dir: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    let len = sqrt(dot(dir, dir));
    for (var k = 0u; k < sdf.instance_count; k++) {
        let inst = sdf_instances[k];
        let v = sdf_volumes[inst.volume];
        let lo = quat_rotate(inst.rotation, (origin - inst.translation) / inst.scale);
        let ld = quat_rotate(inst.rotation, dir / len);
        let lt = sdf_trace(v, lo, ld, (tmin * len) / inst.scale, (tmax * len) / inst.scale);
        if lt >= 0.0 && (lt * inst.scale) / len <= tmax {
            return true;
        }
    }
    return false;
}

// One cone's closest-approach visibility through volume v in its model space, no more than
// `upper` (`sdf::cone::cone_visibility`): the bound test first, then the march.
fn cone_volume(v: SdfVolume, o: vec3<f32>, axis: vec3<f32>, tan: f32, t0: f32, t1: f32, upper: f32) -> f32 {
    let c = v.center;
    let r = v.radius;
    let eps = v.hit;
    let oc = c - o;
    let dd = sqrt(dot(oc, oc));
    var t_star = 0.0;
    var star = true;
    if dd > r {
        let sin_a = r / dd;
        let cos_g = dot(axis, oc) / dd;
        let cos_a = sqrt(max(1.0 - sin_a * sin_a, 0.0));
        let sin_g = sqrt(max(1.0 - cos_g * cos_g, 0.0));
        let sin_ga = sin_g * cos_a - cos_g * sin_a;
        let cos_ga = cos_g * cos_a + sin_g * sin_a;
        let gap = select(dd, dd * sin_g, cos_g > 0.0) - r;
        if gap >= eps && ((cos_ga <= 0.0 && tan <= 1.0) || (cos_ga > 0.0 && sin_ga >= tan * upper)) {
            return upper;
        }
        // t* infinite (no end by the bound) where the sphere lies behind the apex.
        star = cos_ga > 0.0;
        t_star = select(0.0, dd * cos_a / cos_ga, star);
    }
    var vis = upper;
    var t = t0;
    for (var s = 0u; s < sdf.max_steps; s++) {
        if t > t1 {
            break;
        }
        let p = o + t * axis;
        let d = sdf_sample(v, p);
        if d < eps {
            return 0.0;
        }
        let radius = t * tan;
        if d < vis * radius {
            vis = d / radius;
        }
        if star && t >= t_star {
            let pc = p - c;
            let lower = sqrt(dot(pc, pc)) - r;
            if lower >= eps && lower >= vis * radius {
                break;
            }
        }
        t += max(max(d, sdf.cone_step * radius), eps);
    }
    return vis;
}

// The world cone's visibility: the least over the instances, each marched in its model space
// (`SdfScene::cone_visibility`).
fn cone_scene(o: vec3<f32>, axis: vec3<f32>, tan: f32, tmax: f32) -> f32 {
    var vis = 1.0;
    for (var k = 0u; k < sdf.instance_count; k++) {
        let inst = sdf_instances[k];
        let v = sdf_volumes[inst.volume];
        let lo = quat_rotate(inst.rotation, (o - inst.translation) / inst.scale);
        let la = quat_rotate(inst.rotation, axis);
        vis = cone_volume(v, lo, la, tan, v.start, tmax / inst.scale, vis);
        if vis <= 0.0 {
            return 0.0;
        }
    }
    return vis;
}
