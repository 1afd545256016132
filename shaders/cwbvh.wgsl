// The CWBVH traversal shared by the GPU ray casters (src/gpu/tracer.rs over one world BVH,
// src/gpu/two_level.rs over one BVH per mesh): an obvhs compressed wide BVH (Ylitie, Karras,
// Laine, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017;
// obvhs's `traverse!` macro and `CwBvhNode::intersect_ray`) with the watertight ray-triangle
// test (Woop, Benthin, Wald, JCGT 2013; src/trace/watertight.rs). Reads `nodes` (80-byte obvhs
// `CwBvhNode`s as five vec4<u32>) and `tris` (v0 with the original index bits in w, v1, v2),
// which the visibility including it declares.
//
// Deviation from the host test: an edge function that is exactly 0 in f32 is not recomputed in
// f64 (WGSL has no f64); both triangles sharing the edge then accept the ray, so no ray falls
// through, but the reported triangle may differ from the host's on exact edge hits.
// Node test: box entry from the ray's tmin (obvhs uses a fixed 1e-4), boxes padded on the host.

fn safe_inverse(x: f32) -> f32 {
    let eps = 1.1920929e-7;
    if abs(x) <= eps {
        return select(-1.0, 1.0, x >= 0.0) / eps;
    }
    return 1.0 / x;
}

fn byte_of(lo: u32, hi: u32, c: u32) -> u32 {
    return (select(lo, hi, c >= 4u) >> (8u * (c % 4u))) & 0xffu;
}

// Child hit mask of node `ni` (obvhs `intersect_ray_basic` + `get_child_and_index_bits`):
// internal children set bits 24..31 by traversal priority, leaves their primitives' bits.
fn intersect_node(ni: u32, o: vec3<f32>, d: vec3<f32>, inv_d: vec3<f32>, tmin: f32, tmax: f32,
                  oct_inv: u32) -> u32 {
    let w0 = nodes[5u * ni];
    let w1 = nodes[5u * ni + 1u];
    let wx = nodes[5u * ni + 2u];
    let wy = nodes[5u * ni + 3u];
    let wz = nodes[5u * ni + 4u];
    let p = bitcast<vec3<f32>>(w0.xyz);
    let e = vec3<u32>(w0.w & 0xffu, (w0.w >> 8u) & 0xffu, (w0.w >> 16u) & 0xffu);
    let extent = bitcast<vec3<f32>>(e << vec3<u32>(23u));
    let adj_inv = extent * inv_d;
    let adj_o = (p - o) * inv_d;
    var hit = 0u;
    for (var c = 0u; c < 8u; c++) {
        let meta_c = byte_of(w1.z, w1.w, c);
        if meta_c == 0u {
            continue;
        }
        let lo = vec3<f32>(f32(byte_of(wx.x, wx.y, c)), f32(byte_of(wy.x, wy.y, c)), f32(byte_of(wz.x, wz.y, c)));
        let hi = vec3<f32>(f32(byte_of(wx.z, wx.w, c)), f32(byte_of(wy.z, wy.w, c)), f32(byte_of(wz.z, wz.w, c)));
        let neg = d < vec3<f32>(0.0);
        let near = select(lo, hi, neg) * adj_inv + adj_o;
        let far = select(hi, lo, neg) * adj_inv + adj_o;
        let tn = max(max(near.x, near.y), max(near.z, tmin));
        let tf = min(min(far.x, far.y), min(far.z, tmax));
        if tn <= tf {
            let inner = (meta_c & 0x18u) == 0x18u;
            let bit_index = (meta_c ^ select(0u, oct_inv, inner)) & 0x1fu;
            let child_bits = (meta_c >> 5u) & 7u;
            hit |= child_bits << bit_index;
        }
    }
    return hit;
}

struct Shear {
    k: vec3<u32>,
    s: vec3<f32>,
}

fn shear_of(d: vec3<f32>) -> Shear {
    let a = abs(d);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if d[kz] < 0.0 {
        let tmp = kx;
        kx = ky;
        ky = tmp;
    }
    return Shear(vec3<u32>(kx, ky, kz), vec3<f32>(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]));
}

// Watertight test of BVH-ordered triangle `id`; x = 1 on a hit with t in [tmin, tmax], y = t.
fn hit_triangle(id: u32, o: vec3<f32>, sh: Shear, tmin: f32, tmax: f32) -> vec2<f32> {
    let a = tris[3u * id].xyz - o;
    let b = tris[3u * id + 1u].xyz - o;
    let c = tris[3u * id + 2u].xyz - o;
    let kx = sh.k.x;
    let ky = sh.k.y;
    let kz = sh.k.z;
    let ax = a[kx] - sh.s.x * a[kz];
    let ay = a[ky] - sh.s.y * a[kz];
    let bx = b[kx] - sh.s.x * b[kz];
    let by = b[ky] - sh.s.y * b[kz];
    let cx = c[kx] - sh.s.x * c[kz];
    let cy = c[ky] - sh.s.y * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let det = u + v + w;
    if det == 0.0 {
        return vec2<f32>(0.0, 0.0);
    }
    let t_scaled = u * (sh.s.z * a[kz]) + v * (sh.s.z * b[kz]) + w * (sh.s.z * c[kz]);
    let t = t_scaled / det;
    if !(t >= tmin && t <= tmax) {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(1.0, t);
}

// Closest (any_hit = false) or first found (any_hit = true) hit: (t, BVH-ordered triangle),
// triangle 0xffffffff on a miss.
struct TraceResult {
    t: f32,
    id: u32,
}

// The traversal of the CWBVH whose root is node `root` (its nodes' child and primitive
// indices absolute in `nodes` and `tris`).
fn trace_from(root: u32, o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax_in: f32, any_hit: bool) -> TraceResult {
    var res = TraceResult(tmax_in, 0xffffffffu);
    if tmin > tmax_in {
        return res;
    }
    let inv_d = vec3<f32>(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z));
    let oct_inv = select(0u, 4u, d.x >= 0.0) | select(0u, 2u, d.y >= 0.0) | select(0u, 1u, d.z >= 0.0);
    let sh = shear_of(d);
    var tmax = tmax_in;
    var stack: array<vec2<u32>, 32>;
    var sp = 0u;
    var current = vec2<u32>(root, 0x80000000u);
    var prims = vec2<u32>(0u, 0u);
    loop {
        while prims.y != 0u {
            let local = firstLeadingBit(prims.y);
            prims.y &= ~(1u << local);
            let id = prims.x + local;
            let h = hit_triangle(id, o, sh, tmin, tmax);
            if h.x != 0.0 && (any_hit || h.y < tmax || res.id == 0xffffffffu) {
                res = TraceResult(h.y, id);
                if any_hit {
                    return res;
                }
                tmax = h.y;
            }
        }
        prims = vec2<u32>(0u, 0u);
        if (current.y & 0xff000000u) != 0u {
            let hits_imask = current.y;
            let child_offset = firstLeadingBit(hits_imask);
            let child_base = current.x;
            current.y &= ~(1u << child_offset);
            if (current.y & 0xff000000u) != 0u && sp < 32u {
                stack[sp] = current;
                sp += 1u;
            }
            let slot = (child_offset - 24u) ^ (oct_inv & 0xffu);
            let relative = countOneBits(hits_imask & ~(0xffffffffu << slot));
            let ni = child_base + relative;
            let hitmask = intersect_node(ni, o, d, inv_d, tmin, tmax, oct_inv);
            let w0 = nodes[5u * ni];
            let w1 = nodes[5u * ni + 1u];
            current = vec2<u32>(w1.x, (hitmask & 0xff000000u) | (w0.w >> 24u));
            prims = vec2<u32>(w1.y, hitmask & 0x00ffffffu);
        } else {
            current = vec2<u32>(0u, 0u);
        }
        if prims.y == 0u && (current.y & 0xff000000u) == 0u {
            if sp == 0u {
                break;
            }
            sp -= 1u;
            current = stack[sp];
        }
    }
    return res;
}
