// Constants, the orthonormal frame, glam's rotation by a quaternion and normalisation, and
// the f16 decode of stored samples, shared by every kernel.

const TAU: f32 = 6.283185307179586;
const PI: f32 = 3.141592653589793;

// Duff, Burgess, Christensen, Hery, Kensler, Liani, Villemin, "Building an Orthonormal Basis,
// Revisited", JCGT 6(1), 2017: the frame around unit normal `nrm` (src/sampling/frame.rs).
// copysign(1, z) reads the sign bit, so -0.0 takes the negative branch as on the host.
struct Frame {
    x: vec3<f32>,
    y: vec3<f32>,
    z: vec3<f32>,
}

fn frame_from_normal(nrm: vec3<f32>) -> Frame {
    let sgn = select(1.0, -1.0, (bitcast<u32>(nrm.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sgn + nrm.z);
    let b = nrm.x * nrm.y * a;
    let x = vec3<f32>(1.0 + sgn * nrm.x * nrm.x * a, sgn * b, -sgn * nrm.x);
    let y = vec3<f32>(b, sgn + nrm.y * nrm.y * a, -nrm.y);
    return Frame(x, y, nrm);
}

fn frame_to_local(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(v, f.x), dot(v, f.y), dot(v, f.z));
}

fn frame_to_world(f: Frame, v: vec3<f32>) -> vec3<f32> {
    return f.x * v.x + f.y * v.y + f.z * v.z;
}


// glam's `Quat::mul_vec3a`: v (w^2 - b.b) + b 2(v.b) + (b x v) 2w.
fn quat_rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let b = q.xyz;
    let w = q.w;
    let b2 = dot(b, b);
    return v * (w * w - b2) + b * (dot(v, b) * 2.0) + cross(b, v) * (w * 2.0);
}

// glam's `normalize`: v * (1 / |v|).
fn normalize_exact(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / sqrt(dot(v, v)));
}

// IEEE binary16 bits to f32, exactly (`half::f16::to_f32`): normals by their bits, subnormals
// as m 2^-24 (exact), infinities and NaNs kept.
fn f16_to_f32(h: u32) -> f32 {
    let sign = (h & 0x8000u) << 16u;
    let e = (h >> 10u) & 0x1fu;
    let m = h & 0x3ffu;
    if e == 0u {
        let mag = f32(m) * 5.9604644775390625e-8;
        return select(mag, -mag, sign != 0u);
    }
    if e == 31u {
        return bitcast<f32>(sign | 0x7f800000u | (m << 13u));
    }
    return bitcast<f32>(sign | ((e + 112u) << 23u) | (m << 13u));
}
