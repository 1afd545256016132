// Ambient occlusion fields (Kontkanen & Laine, I3D 2005; src/aofield) on the GPU: per receiver
// point, each occluder instance's cap from its cube map of radial functions and the cap's
// horizon-clipped cosine-weighted occlusion, blended multiplicatively, `Π (1 − Ã_i)`
// (`AoFieldScene::ao`). Everything up to the cap's solid angle and n·Υ̃ is the CPU's f32 code,
// operation for operation (`AoField::cap_at`, `Cube::bilinear`, `Stored::texel`); the solid
// angle's quadratic and the cap's occlusion, which the CPU evaluates in f64 with acos and atan2,
// are evaluated in f32 in a form without cancellation and with Cephes' arctangent
// (src/gpu/aofield_kernel.rs derives what that costs). One invocation per point writes the f32
// bits of its AO, or CUT_SHORT where the driver cut its loops short.
// The kernel's own bindings follow the shared header's (shaders/field_kernel.wgsl).

// Mirrors `AoFieldGpu` (src/gpu/aofield_kernel.rs), 32 bytes.
struct AoFieldRecord {
    center: vec3<f32>,
    radius: f32,
    res: u32,
    storage: u32,
    offset: u32,
    decode: u32,
}

// Mirrors `AoFieldInstanceGpu` (src/gpu/aofield_kernel.rs), 48 bytes.
struct AoFieldInstance {
    rotation: vec4<f32>,
    translation: vec3<f32>,
    scale: f32,
    field: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// The kernel's own header. Mirrors `AoInsideGpu` (src/gpu/aofield_kernel.rs): A₀ and p inside
// the hull, and the instances.
struct AoInside {
    ao: f32,
    power: f32,
    instance_count: u32,
    _pad: u32,
}

@group(0) @binding(3) var<storage, read> ao_fields: array<AoFieldRecord>;
@group(0) @binding(4) var<storage, read> ao_instances: array<AoFieldInstance>;
@group(0) @binding(5) var<storage, read> ao_words: array<u32>;
@group(0) @binding(6) var<storage, read> ao_inside: AoInside;

const AO_F32: u32 = 0u;
const AO_F16: u32 = 1u;

// Channel k of texel t, decoded (`Stored::texel`): f32 seven words a texel; f16 four words
// (halves 2j, 2j + 1 in word j); u8 two words (bytes 4j … 4j + 3 in word j), read as
// lo[k] + code · step[k] with lo and step at `decode`.
fn ao_channel(f: AoFieldRecord, t: u32, k: u32) -> f32 {
    if f.storage == AO_F32 {
        return bitcast<f32>(ao_words[f.offset + 7u * t + k]);
    }
    if f.storage == AO_F16 {
        return f16_to_f32((ao_words[f.offset + 4u * t + k / 2u] >> (16u * (k % 2u))) & 0xffffu);
    }
    let code = (ao_words[f.offset + 2u * t + k / 4u] >> (8u * (k % 4u))) & 0xffu;
    return bitcast<f32>(ao_words[f.decode + k]) + f32(code) * bitcast<f32>(ao_words[f.decode + 7u + k]);
}

// Rust's f32::clamp.
fn clamp_rs(x: f32, lo: f32, hi: f32) -> f32 {
    var y = x;
    if y < lo {
        y = lo;
    }
    if y > hi {
        y = hi;
    }
    return y;
}

// Cephes' atanf (S. L. Moshier, Cephes Math Library, atanf.c: range reduction by tan(3π/8)
// and tan(π/8), then an odd polynomial of degree 9; peak relative error 1.9e-7 in IEEE
// single precision) for x ≥ 0, with only +, −, ×, ÷.
fn atan_cephes(x: f32) -> f32 {
    var y0 = 0.0;
    var t = x;
    if x > 2.414213562373095 {
        y0 = 1.5707963267948966;
        t = -1.0 / x;
    } else if x > 0.4142135623730950 {
        y0 = 0.7853981633974483;
        t = (x - 1.0) / (x + 1.0);
    }
    let z = t * t;
    return y0 + ((((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1) * z * t + t);
}

// atan2(y, x) for y > 0.
fn atan2_upper(y: f32, x: f32) -> f32 {
    if x > 0.0 {
        return atan_cephes(y / x);
    }
    if x < 0.0 {
        return PI - atan_cephes(y / -x);
    }
    return 0.5 * PI;
}

// `aofield::cap::small_cap` (a cap no larger than a hemisphere, cos α = cos_a ≥ 0, its axis at
// cos θ = cos_t from the normal), with the clipped case's terms rewritten in
// δ = sin²α − cos²θ > 0: with x = cot α, y = −x cot θ, s = sin θ √(1 − y²) = √δ / sin α,
// acos y = atan2(√δ, −cos α cos θ), x s sin²α = cos α √δ and atan(s / x) = atan2(√δ, cos α):
// πÃ = cos θ sin²α atan2(√δ, −cos α cos θ) − cos α √δ + atan2(√δ, cos α). The same value,
// without the cancellation of 1 − y² near y = ±1.
fn small_cap_f32(cos_a: f32, cos_t: f32) -> f32 {
    let sin2_a = max(1.0 - cos_a * cos_a, 0.0);
    if cos_t * cos_t >= sin2_a {
        return sin2_a * max(cos_t, 0.0);
    }
    let u = sqrt(sin2_a - cos_t * cos_t);
    let e = cos_t * sin2_a * atan2_upper(u, -cos_a * cos_t) - cos_a * u + atan2_upper(u, cos_a);
    return clamp_rs(e / PI, 0.0, 1.0);
}

// `aofield::cap::cap_occlusion` in f32.
fn cap_occlusion_f32(omega_in: f32, cos_theta: f32) -> f32 {
    let omega = clamp_rs(omega_in, 0.0, 2.0 * TAU);
    let cos_t = clamp_rs(cos_theta, -1.0, 1.0);
    let cos_a = 1.0 - omega / TAU;
    if cos_a < 0.0 {
        return 1.0 - small_cap_f32(-cos_a, -cos_t);
    }
    return small_cap_f32(cos_a, cos_t);
}

// The occlusion Ã of field f at model point p with unit normal n (`AoField::occlusion`).
fn ao_occlusion(f: AoFieldRecord, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let x = (p - f.center) / f.radius;
    let s = sqrt(dot(x, x));
    var w = vec3<f32>(0.0, 0.0, 1.0);
    if s > 0.0 {
        w = x / s;
    }
    // `Cube::face_uv` and `Cube::bilinear`.
    let a = abs(w);
    var axis = 2u;
    var major = w.z;
    var b = w.x;
    var c = w.y;
    if a.x >= a.y && a.x >= a.z {
        axis = 0u;
        major = w.x;
        b = w.y;
        c = w.z;
    } else if a.y >= a.z {
        axis = 1u;
        major = w.y;
        b = w.z;
        c = w.x;
    }
    let m = abs(major);
    let face = 2u * axis + select(0u, 1u, major < 0.0);
    let u = b / m;
    let v = c / m;
    let res = f.res;
    let last = f32(res - 1u);
    let fu = clamp_rs((u + 1.0) * 0.5 * f32(res) - 0.5, 0.0, last);
    let fv = clamp_rs((v + 1.0) * 0.5 * f32(res) - 0.5, 0.0, last);
    let i0 = min(u32(fu), res - 1u);
    let j0 = min(u32(fv), res - 1u);
    let i1 = min(i0 + 1u, res - 1u);
    let j1 = min(j0 + 1u, res - 1u);
    let wx = fu - f32(i0);
    let wy = fv - f32(j0);
    let base = face * res * res;
    let texels = array<u32, 4>(base + j0 * res + i0, base + j0 * res + i1, base + j1 * res + i0, base + j1 * res + i1);
    let weights = array<f32, 4>((1.0 - wx) * (1.0 - wy), wx * (1.0 - wy), (1.0 - wx) * wy, wx * wy);
    var ch = array<f32, 7>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (var q = 0u; q < 4u; q++) {
        let wt = weights[q];
        if wt == 0.0 {
            continue;
        }
        for (var k = 0u; k < 7u; k++) {
            ch[k] += wt * ao_channel(f, texels[q], k);
        }
    }
    let s0 = max(ch[3], 0.0);
    let sc = max(s, s0);
    // `Quadratic::omega` (f64 on the CPU): 1/q, the whole sphere at q ≤ 1/4π; at most 2π.
    let qv = (ch[0] * sc + ch[1]) * sc + ch[2];
    var omega = 2.0 * TAU;
    if qv > 1.0 / (2.0 * TAU) {
        omega = 1.0 / qv;
    }
    omega = min(omega, TAU);
    // glam's try_normalize, else −w.
    let toward = vec3<f32>(ch[4], ch[5], ch[6]) - sc * w;
    let rcp = 1.0 / sqrt(dot(toward, toward));
    var cap_axis = -w;
    if rcp > 0.0 && rcp <= 3.4028235e38 {
        cap_axis = toward * rcp;
    }
    let occ = cap_occlusion_f32(omega, dot(n, cap_axis));
    if s < s0 {
        let ratio = s / s0;
        var t = ratio;
        if ao_inside.power != 1.0 {
            t = pow(ratio, ao_inside.power);
        }
        return t * occ + (1.0 - t) * ao_inside.ao;
    }
    return occ;
}

@compute @workgroup_size(64)
fn aofield_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_stride;
    if i >= params.point_count {
        return;
    }
    let rc = receivers[i];
    var ao = 1.0;
    for (var k = 0u; k < ao_inside.instance_count; k++) {
        let inst = ao_instances[k];
        let p = quat_rotate(inst.rotation, (rc.position - inst.translation) / inst.scale);
        let n = quat_rotate(inst.rotation, rc.normal);
        ao = ao * (1.0 - ao_occlusion(ao_fields[inst.field], p, n));
    }
    out[i] = select(CUT_SHORT, bitcast<u32>(ao), loops_completed(params.completion_trips));
}
