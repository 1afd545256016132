// Constants and the orthonormal frame shared by every kernel.

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

