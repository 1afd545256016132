// Hemisphere layouts of a directional map on the GPU: ports of src/sampling/warp.rs and
// src/sampling/layout.rs (`to_square`, `to_cell`, `to_texel` with the rejection layout's
// nearest used texel, `is_used`) and of the bilinear texel footprint of src/field/lookup.rs.
// Texel index = row * res + column; local directions have z >= 0 (z < 0 is clamped to the
// horizon as on the host).

const LAYOUT_POLAR: u32 = 0u;
const LAYOUT_REJECTION: u32 = 1u;
const LAYOUT_CONCENTRIC: u32 = 2u;
const FRAC_PI_2: f32 = 1.5707963267948966;
const FRAC_PI_4: f32 = 0.7853981633974483;

// Malley inverse: drop z; below-horizon directions are clamped onto the rim keeping their
// azimuth, straight down goes to (1, 0).
fn hemisphere_to_disk(d: vec3<f32>) -> vec2<f32> {
    let p = d.xy;
    if d.z < 0.0 {
        let l = length(p);
        if l > 0.0 {
            return p / l;
        }
        return vec2<f32>(1.0, 0.0);
    }
    return p;
}

// Shirley-Chiu concentric map inverse: unit disk -> [0, 1]^2.
fn concentric_disk_to_square(p: vec2<f32>) -> vec2<f32> {
    let r = length(p);
    if r == 0.0 {
        return vec2<f32>(0.5, 0.5);
    }
    var phi = atan2(p.y, p.x);
    if phi < -FRAC_PI_4 {
        phi += 2.0 * PI;
    }
    var ab: vec2<f32>;
    if phi < FRAC_PI_4 {
        ab = vec2<f32>(r, r * phi / FRAC_PI_4);
    } else if phi < 3.0 * FRAC_PI_4 {
        ab = vec2<f32>(r * (FRAC_PI_2 - phi) / FRAC_PI_4, r);
    } else if phi < 5.0 * FRAC_PI_4 {
        ab = vec2<f32>(-r, -r * (phi - PI) / FRAC_PI_4);
    } else {
        ab = vec2<f32>(-r * (3.0 * FRAC_PI_2 - phi) / FRAC_PI_4, -r);
    }
    return vec2<f32>(0.5 * (ab.x + 1.0), 0.5 * (ab.y + 1.0));
}

// Polar map inverse: theta = v pi/2 from the pole, phi = u 2pi wrapped into [0, 2pi).
// theta = atan2(sqrt((1 - z)(1 + z)), z) rather than acos(z): the same angle, but lavapipe's
// acos is less accurate than the host's and put ~0.1% of directions in a neighbouring row.
fn polar_hemisphere_to_square(d: vec3<f32>) -> vec2<f32> {
    let z = clamp(d.z, -1.0, 1.0);
    let theta = min(atan2(sqrt((1.0 - z) * (1.0 + z)), z), FRAC_PI_2);
    var phi = atan2(d.y, d.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let x = phi / (2.0 * PI);
    return vec2<f32>(select(x, 0.0, x >= 1.0), theta / FRAC_PI_2);
}

fn layout_to_square(kind: u32, d: vec3<f32>) -> vec2<f32> {
    if kind == LAYOUT_POLAR {
        return polar_hemisphere_to_square(d);
    }
    if kind == LAYOUT_REJECTION {
        var p = hemisphere_to_disk(d);
        if dot(p, p) > 1.0 {
            p = normalize(p);
        }
        return 0.5 * (p + vec2<f32>(1.0, 1.0));
    }
    return concentric_disk_to_square(hemisphere_to_disk(d));
}

fn texel_is_used(kind: u32, res: u32, t: u32) -> bool {
    if kind != LAYOUT_REJECTION {
        return true;
    }
    let c = i32(t % res);
    let r = i32(t / res);
    let x = 2i * c + 1i - i32(res);
    let y = 2i * r + 1i - i32(res);
    return x * x + y * y < i32(res) * i32(res);
}

// The used texel whose centre is nearest to continuous texel coordinates `p` (5 x 5
// neighbourhood of p's cell, the whole map below res 5).
fn nearest_used_texel(kind: u32, res: u32, p: vec2<f32>) -> u32 {
    let ires = i32(res);
    let pc = i32(floor(p.x));
    let pr = i32(floor(p.y));
    let reach = select(2i, ires, ires < 5i);
    var best = 0xffffffffu;
    var best_d2 = 3.0e38;
    for (var r = max(pr - reach, 0i); r <= min(pr + reach, ires - 1i); r++) {
        for (var c = max(pc - reach, 0i); c <= min(pc + reach, ires - 1i); c++) {
            let t = u32(r * ires + c);
            if !texel_is_used(kind, res, t) {
                continue;
            }
            let q = vec2<f32>(f32(c) + 0.5, f32(r) + 0.5) - p;
            let d2 = dot(q, q);
            if d2 < best_d2 {
                best = t;
                best_d2 = d2;
            }
        }
    }
    return best;
}

// The texel containing local direction `d`; always a used texel.
fn layout_to_texel(kind: u32, res: u32, d: vec3<f32>) -> u32 {
    let p = layout_to_square(kind, d) * f32(res);
    let last = res - 1u;
    let c = min(u32(max(p.x, 0.0)), last);
    let r = min(u32(max(p.y, 0.0)), last);
    let t = r * res + c;
    if kind != LAYOUT_REJECTION || texel_is_used(kind, res, t) {
        return t;
    }
    return nearest_used_texel(kind, res, p);
}

// The (up to) four texels around `d` and their bilinear weights, renormalised over used
// texels; polar maps wrap in phi, other edges clamp. `n == 0` never happens: a footprint
// without used texels falls back to `layout_to_texel` with weight 1.
struct Footprint {
    texels: vec4<u32>,
    weights: vec4<f32>,
}

fn bilinear_footprint(kind: u32, res: u32, d: vec3<f32>) -> Footprint {
    let ires = i32(res);
    let p = layout_to_square(kind, d) * f32(res) - vec2<f32>(0.5, 0.5);
    let c0 = i32(floor(p.x));
    let r0 = i32(floor(p.y));
    let fx = p.x - f32(c0);
    let fy = p.y - f32(r0);
    let wrap = kind == LAYOUT_POLAR;
    var out: Footprint;
    out.texels = vec4<u32>(0u);
    out.weights = vec4<f32>(0.0);
    var n = 0u;
    var total = 0.0;
    let dcs = vec4<i32>(0i, 1i, 0i, 1i);
    let drs = vec4<i32>(0i, 0i, 1i, 1i);
    let ws = vec4<f32>((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
    for (var k = 0u; k < 4u; k++) {
        var col = c0 + dcs[k];
        if wrap {
            col = ((col % ires) + ires) % ires;
        } else {
            col = clamp(col, 0i, ires - 1i);
        }
        let row = clamp(r0 + drs[k], 0i, ires - 1i);
        let t = u32(row * ires + col);
        let w = ws[k];
        if w > 0.0 && texel_is_used(kind, res, t) {
            out.texels[n] = t;
            out.weights[n] = w;
            n += 1u;
            total += w;
        }
    }
    if n == 0u {
        out.texels = vec4<u32>(layout_to_texel(kind, res, d), 0u, 0u, 0u);
        out.weights = vec4<f32>(1.0, 0.0, 0.0, 0.0);
        return out;
    }
    out.weights = out.weights / total;
    return out;
}
