// Positional samples of a field on the GPU: the constant-time nearest point of a ring set
// (Slater's hemisphere subdivision and the latitude-longitude grid) and the triangle walk of
// the interpolated selection.
//
// Ports of src/sampling/rings.rs (`RingSet::bracket`, `RingSet::nearest`) and
// src/sampling/mesh.rs (`SphereMesh::try_locate`), in f32. The ring parameters are analytic
// (no table); the points come from the host's f32 table, so candidates are compared on the
// same coordinates.
// Needs: `tables` (array<vec4<f32>>: every field's points with the incident triangle's index in
// w) and `mesh` (array<vec4<u32>>: per triangle, its vertices then its neighbours across the
// edges opposite them).

const SPHERE_SLATER: u32 = 0u;
const SPHERE_LAT_LONG: u32 = 1u;

struct Ring {
    count: u32,
    first: u32,
    phase: f32,
}

// Ring `g` (0-based from the north pole) of a Slater set with `n` subdivisions: upper ring k
// holds max(1, 4k) points starting at N_{k-1} = 2k^2 - 2k + 1; lower ring k (global index
// 2n + 1 - k) starts at 2H - N_k and is turned by k / 2n steps.
fn slater_ring(g: u32, n: u32) -> Ring {
    let h = 2u * n * n + 2u * n + 1u;
    if g <= n {
        let k = g;
        if k == 0u {
            return Ring(1u, 0u, 0.0);
        }
        return Ring(4u * k, 2u * k * k - 2u * k + 1u, 0.0);
    }
    let k = 2u * n + 1u - g;
    let nk = 2u * k * k + 2u * k + 1u;
    if k == 0u {
        return Ring(1u, 2u * h - nk, 0.0);
    }
    return Ring(4u * k, 2u * h - nk, f32(k) / (2.0 * f32(n)));
}

// The ring a with theta_a <= theta(d) < theta_{a+1} (-1 above the first ring), as an i32.
fn ring_bracket(d: vec3<f32>, kind: u32, n: u32) -> i32 {
    let rho2 = d.x * d.x + d.y * d.y;
    let len = sqrt(rho2 + d.z * d.z);
    if len == 0.0 {
        return 0;
    }
    if kind == SPHERE_SLATER {
        let h = f32(2u * n * n + 2u * n + 1u);
        let s = rho2 / (len * (len + abs(d.z)));
        let t = s * h;
        var k = 0i;
        if t >= 3.0 {
            k = min(i32(floor(sqrt((t - 1.0) * 0.5))), i32(n));
        }
        if d.z >= 0.0 {
            return k;
        }
        return 2i * i32(n) - k;
    }
    // Lat-long rows at theta_r = (r + 1/2) pi / rows.
    let theta = atan2(sqrt(rho2), d.z);
    return clamp(i32(floor(theta * f32(n) / PI - 0.5)), -1i, i32(n) - 1i);
}

fn ring_of(g: u32, kind: u32, n: u32) -> Ring {
    if kind == SPHERE_SLATER {
        return slater_ring(g, n);
    }
    // Lat-long: `n` rows of n + 1 columns at phase 1/2.
    return Ring(n + 1u, g * (n + 1u), 0.5);
}

fn ring_count(kind: u32, n: u32) -> u32 {
    if kind == SPHERE_SLATER {
        return 2u * n + 2u;
    }
    return n;
}

// Unit point `i` of the set whose table starts at `base`.
fn sphere_point(base: u32, i: u32) -> vec3<f32> {
    return tables[base + i].xyz;
}

// Index of the point nearest to `d` (largest dot product) among the two azimuth neighbours on
// each of the four rings around d's polar angle (src/sampling/rings.rs, proof in its docs).
fn nearest_point(d: vec3<f32>, kind: u32, n: u32, base: u32) -> u32 {
    let a = ring_bracket(d, kind, n);
    let last = i32(ring_count(kind, n)) - 1i;
    let lo = u32(clamp(a - 1i, 0i, last));
    let hi = u32(clamp(a + 2i, 0i, last));
    let turns = atan2(d.y, d.x) * (1.0 / TAU);
    var best = 0u;
    var best_dot = -3.0e38;
    for (var g = lo; g <= hi; g++) {
        let ring = ring_of(g, kind, n);
        let m = ring.count;
        let u = turns * f32(m) - ring.phase;
        // floor(u) mod m without an integer division (scalar on a CPU driver): |turns| <= 1/2
        // and 0 <= phase <= 1/2 put floor(u) in [-m/2 - 1, m/2], so one wrap suffices for
        // m >= 2, and the pole ring (m = 1, phase 0) has floor(u) in {-1, 0}.
        let fl = i32(floor(u));
        let mi = i32(m);
        let j0 = u32(select(fl, fl + mi, fl < 0i));
        let j1 = select(j0 + 1u, 0u, j0 + 1u == m);
        for (var c = 0u; c < 2u; c++) {
            let i = ring.first + select(j0, j1, c == 1u);
            let dot_p = dot(d, sphere_point(base, i));
            if dot_p > best_dot {
                best_dot = dot_p;
                best = i;
            }
        }
    }
    return best;
}

// The three points around `d` and their planar barycentric weights: the triangle containing d
// found by walking from a triangle incident to the nearest point across the edge with the most
// negative numerator (src/sampling/mesh.rs). Returns the maps in `maps` and the weights in the
// returned vector; when the walk does not settle within `max_steps` the nearest map alone is
// used (weight 1).
struct Surrounding {
    maps: vec3<u32>,
    weights: vec3<f32>,
}

fn det3(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    return dot(a, cross(b, c));
}

fn surrounding(d: vec3<f32>, nearest: u32, base: u32, mesh_base: u32, max_steps: u32) -> Surrounding {
    var t = bitcast<u32>(tables[base + nearest].w);
    for (var step = 0u; step < max_steps; step++) {
        let tri = mesh[mesh_base + 2u * t].xyz;
        let pa = sphere_point(base, tri.x);
        let pb = sphere_point(base, tri.y);
        let pc = sphere_point(base, tri.z);
        let w = vec3<f32>(det3(d, pb, pc), det3(pa, d, pc), det3(pa, pb, d));
        let scale = abs(w.x) + abs(w.y) + abs(w.z);
        var imin = 0u;
        var wmin = w.x;
        if w.y < wmin {
            imin = 1u;
            wmin = w.y;
        }
        if w.z < wmin {
            imin = 2u;
            wmin = w.z;
        }
        // f32 tolerance for d on an edge (the host uses 1e-14 in f64).
        if wmin >= -1e-6 * scale {
            let wc = max(w, vec3<f32>(0.0));
            let sum = wc.x + wc.y + wc.z;
            if sum > 0.0 {
                return Surrounding(tri, wc / sum);
            }
        }
        t = mesh[mesh_base + 2u * t + 1u][imin];
    }
    return Surrounding(vec3<u32>(nearest, nearest, nearest), vec3<f32>(1.0, 0.0, 0.0));
}
