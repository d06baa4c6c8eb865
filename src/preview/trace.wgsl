// The previewer's ray tracer: the CPU renderer's algorithm (src/render/march.rs,
// air.rs, mod.rs) in f32. One invocation per pixel writes linear RGB.
//
// A frame is traced in passes (dispatches): each pass advances every pixel's
// ray by at most P.march.y iterations of the march and keeps where it got to
// in `rays`, and the pass in which a pixel's last sample ends writes its
// colour. Mesa's software Vulkan (llvmpipe) breaks out of every loop once an
// invocation group has run 65535 loop iterations in all (its
// LP_MAX_TGSI_LOOP_ITERATIONS, one counter shared by every loop of the
// shader, inner loops included), silently: a ray that needs more (about 800
// RK4 steps of real air, a few thousand of the logistic model: 30 km at a 5 m
// step) was given up half-way and drawn as sky. Short passes stay far below that on any device, and keep each
// dispatch short on real GPUs.
//
// The medium is evaluated in δ form (δ ≈ 1e-5 keeps 7 digits; 1 + δ would keep
// three): dv/dτ = ∇δ + δ∇δ, and Snell's invariant is carried as c − 1, computed
// from δ and the elevation, never as |v_h| − 1.
//
// Over the round earth (P.profile.w = R > 0; 0: the flat ground) the medium
// takes the height above the sphere centred at (0, −R, 0) for y, the ground is
// the sphere, and the Snell decisions are Bouguer's over the profile of the
// modified refractivity M (render/air.rs, "Over the round earth").
//
// The constants shared with the Rust side (OP_*, STACK_DEPTH, WORKGROUP,
// SHADING_*, GROUND_*, MEDIUM_*, PHASE_*, BIG, STAR_CELLS, STAR_MARGIN_MAX) come from the prelude
// that src/preview/shader.rs generates and puts before this file.

struct Params {
    origin: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    size: vec4<u32>,
    flags: vec4<u32>,
    background: vec4<f32>,
    inversion: vec4<f32>,
    air: vec4<f32>,
    profile: vec4<f32>,
    tolerance: vec4<f32>,
    ground0: vec4<f32>,
    ground1: vec4<f32>,
    box_min: vec4<f32>,
    box_max: vec4<f32>,
    sun_dir: vec4<f32>,
    sun_irradiance: vec4<f32>,
    ambient: vec4<f32>,
    disc_dir: vec4<f32>,
    disc_radiance: vec4<f32>,
    counts: vec4<u32>,
    grid_min: vec4<f32>,
    grid_max: vec4<f32>,
    grid_dims: vec4<u32>,
    grid_cell: vec4<f32>,
    stars: vec4<f32>,
    medium: vec4<u32>,
    air_range: vec4<f32>,
    air_grid: vec4<f32>,
    march: vec4<u32>,
    accumulate: vec4<u32>,
}
struct Cell { empty: f32, far: f32, start: u32, len: u32 }

struct HotSpot { a: vec4<f32>, b: vec4<f32>, c: vec4<f32> }
struct Object { range: vec4<u32>, albedo: vec4<f32>, center: vec4<f32> }
struct Node { kind: vec4<u32>, row0: vec4<f32>, row1: vec4<f32>, row2: vec4<f32>, p0: vec4<f32>, p1: vec4<f32> }

@group(0) @binding(0) var<uniform> P: Params;
@group(0) @binding(1) var<storage, read> hotspots: array<HotSpot>;
@group(0) @binding(2) var<storage, read> objects: array<Object>;
@group(0) @binding(3) var<storage, read> nodes: array<Node>;
@group(0) @binding(4) var<storage, read> profile: array<vec4<f32>>;
@group(0) @binding(5) var sky: texture_2d<f32>;
@group(0) @binding(6) var out_image: texture_storage_2d<rgba32float, write>;
@group(0) @binding(7) var<storage, read> cells: array<Cell>;
@group(0) @binding(8) var<storage, read> near: array<u32>;
@group(0) @binding(9) var<storage, read> stars: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> air_table: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> rays: array<Ray>;
// The band of rows a dispatch traces: [first row, rows, 0, 0] (a frame too
// large for one buffer of rays is traced band by band).
@group(0) @binding(12) var<uniform> band: vec4<u32>;
// Per pixel of the whole image, the sum of its samples so far while the
// window accumulates a still view (P.accumulate; src/preview/accumulate.rs).
@group(0) @binding(13) var<storage, read_write> accum: array<vec4<f32>>;

const PI: f32 = 3.14159265358979;

// ---------------------------------------------------------------- the medium

// σ(x) and σ'(x), exact at both tails.
fn sigmoid(x: f32) -> vec2<f32> {
    let e = exp(-abs(x));
    let inv = 1.0 / (1.0 + e);
    let s = select(e * inv, inv, x >= 0.0);
    return vec2<f32>(s, e * inv * inv);
}

// ------------------------------------------------------- real air (real_air.rs)

// The uniform air (T_u, dT_u/dh, P, dP/dh) at height h: the cubic Hermite of
// the interval holding h (binary search; a node belongs to the interval
// below it, as real_air.rs says); held beyond the end nodes.
fn air_profile(h: f32) -> vec4<f32> {
    let n = P.medium.y;
    let hc = clamp(h, P.air_range.x, P.air_range.y);
    var lo = 0u;
    var hi = n - 1u;
    while (lo < hi) {
        let mid = (lo + hi + 1u) / 2u;
        if (air_table[3u * mid].x < hc) { lo = mid; } else { hi = mid - 1u; }
    }
    let hw = air_table[3u * lo];
    let a = air_table[3u * lo + 1u];
    let b = air_table[3u * lo + 2u];
    let w = hw.y;
    let u = clamp((hc - hw.x) / w, 0.0, 1.0);
    let u2 = u * u;
    let u3 = u2 * u;
    let h01 = 3.0 * u2 - 2.0 * u3;
    let h10 = u3 - 2.0 * u2 + u;
    let h11 = u3 - u2;
    let d01 = 6.0 * u - 6.0 * u2;
    let d10 = 3.0 * u2 - 4.0 * u + 1.0;
    let d11 = 3.0 * u2 - 2.0 * u;
    let t = a.x + h01 * b.x + w * (h10 * a.y + h11 * b.y);
    let pr = a.z + h01 * b.z + w * (h10 * a.w + h11 * b.w);
    var dt = d01 * b.x / w + d10 * a.y + d11 * b.y;
    var dp = d01 * b.z / w + d10 * a.w + d11 * b.w;
    if (h != hc) {
        dt = 0.0;
        dp = 0.0;
    }
    return vec4<f32>(t, dt, pr, dp);
}

// (δ, ∂δ/∂T, ∂δ/∂P) of the formula: the bicubic Hermite of the grid cell, or
// Gladstone–Dale in closed form.
fn air_formula(t: f32, pr: f32) -> vec3<f32> {
    if (P.air_range.z > 0.0) {
        let pp = max(pr, 1e-6);
        let d = P.air_range.z * (pp / 101325.0) / t;
        return vec3<f32>(d, -d / t, d / pp);
    }
    let nt = P.medium.z;
    let np = P.medium.w;
    let g = P.air_grid;
    let fu = clamp((t - g.x) / g.y, 0.0, f32(nt));
    let fv = clamp((pr - g.z) / g.w, 0.0, f32(np));
    let i = min(u32(floor(fu)), nt - 1u);
    let j = min(u32(floor(fv)), np - 1u);
    let u = fu - f32(i);
    let v = fv - f32(j);
    let base = 3u * P.medium.y + 4u * (i + nt * j);
    let su = 3.0 * u * u - 2.0 * u * u * u;
    let sv = 3.0 * v * v - 2.0 * v * v * v;
    let hu = array<f32, 2>(1.0 - su, su);
    let hv = array<f32, 2>(1.0 - sv, sv);
    let ku = array<f32, 2>(u * u * u - 2.0 * u * u + u, u * u * u - u * u);
    let kv = array<f32, 2>(v * v * v - 2.0 * v * v + v, v * v * v - v * v);
    let du = 6.0 * u - 6.0 * u * u;
    let dv = 6.0 * v - 6.0 * v * v;
    let hdu = array<f32, 2>(-du, du);
    let hdv = array<f32, 2>(-dv, dv);
    let kdu = array<f32, 2>(3.0 * u * u - 4.0 * u + 1.0, 3.0 * u * u - 2.0 * u);
    let kdv = array<f32, 2>(3.0 * v * v - 4.0 * v + 1.0, 3.0 * v * v - 2.0 * v);
    var f = air_table[base].x;
    var f_u = 0.0;
    var f_v = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let a = k & 1u;
        let b = k >> 1u;
        let c = air_table[base + k];
        // The first corner's value is the cell's base, the others relative to it.
        var df = c.x;
        if (k == 0u) { df = 0.0; }
        f += hu[a] * hv[b] * df + ku[a] * hv[b] * c.y + hu[a] * kv[b] * c.z + ku[a] * kv[b] * c.w;
        f_u += hdu[a] * hv[b] * df + kdu[a] * hv[b] * c.y + hdu[a] * kv[b] * c.z + kdu[a] * kv[b] * c.w;
        f_v += hu[a] * hdv[b] * df + ku[a] * hdv[b] * c.y + hu[a] * kdv[b] * c.z + ku[a] * kdv[b] * c.w;
    }
    return vec3<f32>(f, f_u / g.y, f_v / g.w);
}

// (∇δ, δ) of real air at p (AirField::delta_gradient).
fn air_medium(p: vec3<f32>) -> vec4<f32> {
    let u = air_profile(p.y);
    var t = u.x;
    var grad_t = vec3<f32>(0.0, u.y, 0.0);
    for (var j = 0u; j < P.size.z; j++) {
        let h = hotspots[j];
        let d = vec2<f32>(p.x - h.a.z, p.z - h.a.w);
        let rho = length(d);
        let sw = sigmoid(h.b.y * (h.b.x - rho));
        var r = vec2<f32>(0.0);
        if (rho > 0.0) { r = d / rho; }
        let dw = -h.b.y * sw.y;
        var e = 1.0;
        var de = 0.0;
        if (p.y > 0.0) {
            e = exp(-p.y * h.a.y);
            de = -e * h.a.y;
        }
        let amp = h.a.x * e;
        t += amp * sw.x;
        grad_t.y += h.a.x * sw.x * de;
        grad_t.x += amp * dw * r.x;
        grad_t.z += amp * dw * r.y;
    }
    // Colder than −150 °C: held at the floor, as on the CPU.
    if (t < P.air_range.w) {
        t = P.air_range.w;
        grad_t = vec3<f32>(0.0);
    }
    let f = air_formula(t, u.z);
    return vec4<f32>(f.y * grad_t + vec3<f32>(0.0, f.z * u.w, 0.0), f.x);
}

// ------------------------------------------------------------ the round earth

// (∇h, h) at p: the local vertical and the height above the ground; over the
// sphere without cancellation, h = (x² + z² + y(2R + y)) / (|p − c| + R)
// (trace/earth.rs).
fn height_up(p: vec3<f32>) -> vec4<f32> {
    let r = P.profile.w;
    if (r == 0.0) { return vec4<f32>(0.0, 1.0, 0.0, p.y); }
    let qy = p.y + r;
    let qn = length(vec3<f32>(p.x, qy, p.z));
    let h = (p.x * p.x + p.z * p.z + p.y * (p.y + 2.0 * r)) / (qn + r);
    return vec4<f32>(p.x / qn, qy / qn, p.z / qn, h);
}

// p with its height for y: the frame the medium and its zones are written in.
fn local(p: vec3<f32>) -> vec3<f32> {
    if (P.profile.w == 0.0) { return p; }
    return vec3<f32>(p.x, height_up(p).w, p.z);
}

// (∇δ, δ) at p over the ground: the flat medium at (x, h, z), its gradient by
// the chain rule (trace::OnEarth).
fn medium(p: vec3<f32>) -> vec4<f32> {
    if (P.profile.w == 0.0) { return medium_flat(p); }
    let hu = height_up(p);
    let m = medium_flat(vec3<f32>(p.x, hu.w, p.z));
    return vec4<f32>(m.x + m.y * hu.x, m.y * hu.y, m.z + m.y * hu.z, m.w);
}

// (∇δ, δ) at p over the flat ground: real air, or the logistic model.
fn medium_flat(p: vec3<f32>) -> vec4<f32> {
    if (P.medium.x == MEDIUM_AIR) { return air_medium(p); }
    var delta = 0.0;
    var grad = vec3<f32>(0.0);
    if (P.background.z > 0.5) {
        let s = sigmoid(p.y * P.background.y);
        delta += P.background.x * s.x;
        grad.y += P.background.x * s.y * P.background.y;
    }
    if (P.inversion.w > 0.5) {
        let s = sigmoid((P.inversion.z - p.y) * P.inversion.y);
        delta += P.inversion.x * s.x;
        grad.y -= P.inversion.x * s.y * P.inversion.y;
    }
    for (var j = 0u; j < P.size.z; j++) {
        let h = hotspots[j];
        let d = vec2<f32>(p.x - h.a.z, p.z - h.a.w);
        let rho = length(d);
        let sw = sigmoid(h.b.y * (h.b.x - rho));
        var u = vec2<f32>(0.0);
        if (rho > 0.0) { u = d / rho; }
        let dw = -h.b.y * sw.y;
        let s = sigmoid(p.y * h.a.y);
        let amp_s = h.a.x * s.x;
        delta += amp_s * sw.x;
        grad.y += h.a.x * sw.x * s.y * h.a.y;
        grad.x += amp_s * dw * u.x;
        grad.z += amp_s * dw * u.y;
    }
    return vec4<f32>(grad, delta);
}

fn in_zone(q: vec3<f32>) -> bool {
    let p = local(q);
    for (var j = 0u; j < P.size.z; j++) {
        let h = hotspots[j];
        if (p.y < h.b.w && length(vec2<f32>(p.x - h.a.z, p.z - h.a.w)) < h.b.z) { return true; }
    }
    return false;
}

// The RK4 step (arc length) at p: Air::step_at.
fn step_at(q: vec3<f32>) -> f32 {
    let p = local(q);
    var inside = BIG;
    var approach = BIG;
    for (var j = 0u; j < P.size.z; j++) {
        let h = hotspots[j];
        var growth = 1.0;
        if (h.c.x > 0.0) { growth = exp(min(max(p.y, 0.0) / (4.0 * h.c.x), log(32.0))); }
        let grown = P.air.y * growth;
        let dh = max(length(vec2<f32>(p.x - h.a.z, p.z - h.a.w)) - h.b.z, 0.0);
        let dv = max(p.y - h.b.w, 0.0);
        let d = length(vec2<f32>(dh, dv));
        if (d == 0.0) { inside = min(inside, grown); } else { approach = min(approach, max(grown, d)); }
    }
    return min(P.air.z, min(inside, approach));
}

// ------------------------------------------------------------ Snell decisions

fn profile_index_floor(y: f32) -> u32 {
    return min(u32(max(floor(y / P.profile.x), 0.0)), P.flags.w - 1u);
}
fn profile_index_ceil(y: f32) -> u32 {
    return min(u32(max(ceil(y / P.profile.x), 0.0)), P.flags.w - 1u);
}

fn halfline_meets_disc(o: vec2<f32>, h: vec2<f32>, c: vec2<f32>, r: f32) -> bool {
    let t = max(dot(c - o, h), 0.0);
    return length(o + h * t - c) <= r;
}

fn halfline_meets_box_xz(o: vec2<f32>, h: vec2<f32>) -> bool {
    let lo = P.box_min.xz;
    let hi = P.box_max.xz;
    var t0 = 0.0;
    var t1 = BIG;
    for (var k = 0; k < 2; k++) {
        if (h[k] == 0.0) {
            if (o[k] < lo[k] || o[k] > hi[k]) { return false; }
        } else {
            let a = (lo[k] - o[k]) / h[k];
            let b = (hi[k] - o[k]) / h[k];
            t0 = max(t0, min(a, b));
            t1 = min(t1, max(a, b));
        }
    }
    return t0 <= t1;
}

// Fate: 0 undecided, 1 sky (along `dir`), 2 bound for the ground.
struct Fate { kind: u32, dir: vec3<f32> }

// `objects`: whether the objects still count (not for a ray given up at the
// largest distance, which sees the sky along its asymptote: Air::sky_direction).
fn fate(p: vec3<f32>, v: vec3<f32>, objects: bool) -> Fate {
    if (P.profile.w > 0.0) { return fate_round(p, v, objects); }
    var f = Fate(0u, vec3<f32>(0.0));
    if (P.flags.y == 1u || p.y < 0.0 || v.y == 0.0 || in_zone(p)) { return f; }
    let vn = normalize(v);
    let se = vn.y;
    let one_minus_cos = se * se / (1.0 + sqrt(max(1.0 - se * se, 0.0)));
    let delta = medium(p).w;
    // c − 1 with c = n·cos(elevation) = |v_h|.
    let c1 = delta - (1.0 + delta) * one_minus_cos;
    let rising = v.y > 0.0;
    let escape = profile[profile_index_floor(p.y)].z - P.profile.y > c1;
    var low = 0.0;
    var high = BIG;
    var ground_bound = false;
    if (rising) {
        if (!escape) { return f; }
        low = p.y;
    } else if (P.flags.z != GROUND_NONE && profile[profile_index_ceil(p.y)].y - P.profile.y > c1) {
        high = p.y;
        ground_bound = true;
    } else if (profile[profile_index_floor(p.y)].y < c1 && escape) {
    } else {
        return f;
    }
    let vh = vec2<f32>(vn.x, vn.z);
    let lh = length(vh);
    var h = vec2<f32>(0.0);
    if (lh > 0.0) { h = vh / lh; }
    let o = p.xz;
    if (objects && P.box_min.w > 0.5 && low <= P.box_max.y && high >= P.box_min.y && halfline_meets_box_xz(o, h)) {
        return f;
    }
    for (var j = 0u; j < P.size.z; j++) {
        let z = hotspots[j];
        if (low < z.b.w && halfline_meets_disc(o, h, z.a.zw, z.b.z)) { return f; }
    }
    if (ground_bound) {
        f.kind = 2u;
        return f;
    }
    // Leaving the top of the model: n_top² − c² = (δ_top − c1)(2 + δ_top + c1).
    let dt = P.profile.z;
    let vy = sqrt(max((dt - c1) * (2.0 + dt + c1), 0.0));
    f.kind = 1u;
    f.dir = normalize(vec3<f32>(h.x * (1.0 + c1), vy, h.y * (1.0 + c1)));
    return f;
}


// ------------------------------------------- Bouguer decisions over the sphere

// Whether a ray at p (ray vector v) may meet the ball (centre c, radius r)
// while its height stays in [low, high] (render/air.rs, may_meet_ball): the
// ball must cut the ray's plane through the earth's centre, reach the
// heights, and lie ahead; everything relative to p, where f32 keeps digits.
fn may_meet_ball(p: vec3<f32>, v: vec3<f32>, c: vec3<f32>, r: f32, low: f32, high: f32) -> bool {
    let q = vec3<f32>(p.x, p.y + P.profile.w, p.z);
    let n = cross(q, v);
    let nl = length(n);
    if (!(nl > 0.0)) { return true; }
    let normal = n / nl;
    let rel = c - p;
    if (abs(dot(rel, normal)) > r) { return false; }
    let hb = height_up(c).w;
    if (hb - r > high || hb + r < low) { return false; }
    let ql = length(q);
    let e1 = q / ql;
    let e2 = cross(normal, e1);
    let bx = ql + dot(rel, e1);
    let by = dot(rel, e2);
    let dp = length(vec2<f32>(bx, by));
    if (dp <= r) { return true; }
    let beta = atan2(by, bx);
    let gamma = asin(r / dp);
    return beta + gamma >= 0.0 && beta - gamma < PI;
}

// F = (1 + M)² − c² at profile node i (c1 = c − 1).
fn bouguer_f(i: u32, c1: f32) -> f32 {
    let m = profile[i].x;
    return (m - c1) * (2.0 + m + c1);
}

// ∫ (c/R) dh / ((1 + h/R)·√F) over [ha, hb], F linear between fa and fb.
fn sweep_piece(ha: f32, fa: f32, hb: f32, fb: f32, c: f32) -> f32 {
    let r = P.profile.w;
    let s = sqrt(fa) + sqrt(fb);
    if (s > 0.0) { return c / r * 2.0 * (hb - ha) / s / (1.0 + 0.5 * (ha + hb) / r); }
    return 0.0;
}

// φ swept from height h (F = f) up to the profile's top (Air::sweep_up).
fn sweep_up(h: f32, f: f32, c1: f32) -> f32 {
    let last = P.flags.w - 1u;
    let i0 = min(u32(max(floor(h / P.profile.x), 0.0)) + 1u, last + 1u);
    let stride_max = max(u32(1e-3 * P.profile.w / P.profile.x), 1u);
    var ha = h;
    var fa = max(f, 0.0);
    var phi = 0.0;
    var i = i0;
    loop {
        if (i > last) { break; }
        let hb = f32(i) * P.profile.x;
        let fb = max(bouguer_f(i, c1), 0.0);
        phi += sweep_piece(ha, fa, hb, fb, 1.0 + c1);
        if (i == last) { break; }
        ha = hb;
        fa = fb;
        i = min(i + min(1u + (i - i0) / 32u, stride_max), last);
    }
    return phi;
}

// φ swept from height h (F = f) down to the turning height, and that height
// (Air::sweep_down).
fn sweep_down(h: f32, f: f32, c1: f32) -> vec2<f32> {
    let last = P.flags.w - 1u;
    var ha = h;
    var fa = max(f, 0.0);
    var phi = 0.0;
    var i = min(u32(max(ceil(h / P.profile.x), 0.0)), last + 1u);
    loop {
        if (i == 0u) { break; }
        i -= 1u;
        let hb = f32(i) * P.profile.x;
        if (hb >= ha) { continue; }
        let fb = bouguer_f(i, c1);
        if (fb <= 0.0) {
            let turn = ha - (ha - hb) * fa / (fa - fb);
            phi += sweep_piece(turn, 0.0, ha, fa, 1.0 + c1);
            return vec2<f32>(phi, turn);
        }
        phi += sweep_piece(hb, fb, ha, fa, 1.0 + c1);
        ha = hb;
        fa = fb;
    }
    return vec2<f32>(phi, 0.0);
}

// Air::round_fate: Bouguer's invariant c = n·r·cos(e)/R, carried as c − 1.
fn fate_round(p: vec3<f32>, v: vec3<f32>, objects: bool) -> Fate {
    var f = Fate(0u, vec3<f32>(0.0));
    let hu = height_up(p);
    let h = hu.w;
    let up = hu.xyz;
    if (P.flags.y == 1u || h < 0.0 || in_zone(p)) { return f; }
    let vn = normalize(v);
    let se = dot(vn, up);
    if (se == 0.0) { return f; }
    let one_minus_cos = se * se / (1.0 + sqrt(max(1.0 - se * se, 0.0)));
    let delta = medium_flat(vec3<f32>(p.x, h, p.z)).w;
    let k = h / P.profile.w;
    // c − 1 = (1 + h/R)(1 + δ)(1 − (1 − cos e)) − 1.
    let c1 = delta + k + delta * k - (1.0 + k) * (1.0 + delta) * one_minus_cos;
    let rising = se > 0.0;
    let above = h >= P.profile.x * f32(P.flags.w - 1u);
    let escape = (rising && above) || profile[profile_index_floor(h)].z - P.profile.y > c1;
    var low = 0.0;
    var high = BIG;
    var ground_bound = false;
    if (rising) {
        if (!escape) { return f; }
        low = h;
    } else if (P.flags.z != GROUND_NONE && profile[profile_index_ceil(h)].y - P.profile.y > c1) {
        high = h;
        ground_bound = true;
    } else if (profile[profile_index_floor(h)].y < c1 && escape) {
    } else {
        return f;
    }
    if (objects && P.box_min.w > 0.5) {
        let c = 0.5 * (P.box_min.xyz + P.box_max.xyz);
        let r = 0.5 * length(P.box_max.xyz - P.box_min.xyz);
        if (r >= 0.5 * BIG || may_meet_ball(p, v, c, r, low, high)) { return f; }
    }
    for (var j = 0u; j < P.size.z; j++) {
        let z = hotspots[j];
        if (low >= z.b.w) { continue; }
        if (z.b.w >= 0.5 * BIG) { return f; }
        let rho = length(vec2<f32>(abs(z.a.z) + z.b.z, abs(z.a.w) + z.b.z));
        let lo = vec3<f32>(z.a.z - z.b.z, -rho * rho / P.profile.w - 1.0, z.a.w - z.b.z);
        let hi = vec3<f32>(z.a.z + z.b.z, z.b.w, z.a.w + z.b.z);
        if (may_meet_ball(p, v, 0.5 * (lo + hi), 0.5 * length(hi - lo), low, high)) { return f; }
    }
    if (ground_bound) {
        f.kind = 2u;
        return f;
    }
    f.kind = 1u;
    if (rising && above) {
        f.dir = vn;
        return f;
    }
    // Round_sky: the elevation at the top from Bouguer, less the angle swept.
    let n = 1.0 + delta;
    let vt = vn - up * se;
    let vtl = length(vt);
    if (vtl == 0.0) {
        f.dir = up * sign(se);
        return f;
    }
    let forward = vt / vtl;
    let f0 = ((1.0 + k) * n * se) * ((1.0 + k) * n * se);
    var phi = 0.0;
    if (rising) {
        phi = sweep_up(h, f0, c1);
    } else {
        let d = sweep_down(h, f0, c1);
        phi = d.x + sweep_up(d.y, 0.0, c1);
    }
    let mt = P.profile.z;
    let omc = max((mt - c1) / (1.0 + mt), 0.0);
    let e = 2.0 * asin(min(sqrt(0.5 * omc), 1.0)) - phi;
    f.dir = forward * cos(e) + up * sin(e);
    return f;
}

// ---------------------------------------------------------------- the objects

fn box_distance(d: vec3<f32>, h: vec3<f32>, shrink: f32) -> f32 {
    let e = abs(d) - h + vec3<f32>(shrink);
    return length(max(e, vec3<f32>(0.0))) + min(max(e.x, max(e.y, e.z)), 0.0) - shrink;
}

fn run_program(start: u32, count: u32, p: vec3<f32>) -> f32 {
    var stack: array<f32, STACK_DEPTH>;
    var top = 0u;
    for (var i = start; i < start + count; i++) {
        let n = nodes[i];
        let kind = n.kind.x;
        if (kind < OP_FIRST_BINARY) {
            let q = vec3<f32>(dot(n.row0.xyz, p) + n.row0.w, dot(n.row1.xyz, p) + n.row1.w, dot(n.row2.xyz, p) + n.row2.w);
            var d = 0.0;
            switch kind {
                case OP_SPHERE: { d = length(q - n.p0.xyz) - n.p0.w; }
                case OP_BOX: { d = box_distance(q - n.p0.xyz, n.p1.xyz, 0.0); }
                case OP_ROUNDED_BOX: { d = box_distance(q - n.p0.xyz, n.p1.xyz, n.p0.w); }
                case OP_PLANE: { d = dot(n.p0.xyz, q) - n.p0.w; }
                case OP_TORUS: {
                    let e = q - n.p0.xyz;
                    d = length(vec2<f32>(length(e.xz) - n.p1.x, e.y)) - n.p1.y;
                }
                case OP_CYLINDER: {
                    let e = q - n.p0.xyz;
                    let w = vec2<f32>(length(e.xz) - n.p1.x, abs(e.y) - n.p1.y);
                    d = min(max(w.x, w.y), 0.0) + length(max(w, vec2<f32>(0.0)));
                }
                case OP_CAPSULE: {
                    let pa = q - n.p0.xyz;
                    let ba = n.p1.xyz - n.p0.xyz;
                    let bb = dot(ba, ba);
                    var t = 0.0;
                    if (bb > 0.0) { t = clamp(dot(pa, ba) / bb, 0.0, 1.0); }
                    d = length(pa - ba * t) - n.p0.w;
                }
                default: { d = BIG; }
            }
            stack[top] = d * n.p1.w;
            top += 1u;
        } else {
            let b = stack[top - 1u];
            let a = stack[top - 2u];
            top -= 1u;
            var r = 0.0;
            switch kind {
                case OP_MIN: { r = min(a, b); }
                case OP_MAX: { r = max(a, b); }
                case OP_DIFF: { r = max(a, -b); }
                default: {
                    // OP_SMIN
                    let k = n.p0.x;
                    let hh = max(k - abs(a - b), 0.0) / k;
                    r = min(a, b) - hh * hh * k * 0.25;
                }
            }
            stack[top - 1u] = r;
        }
    }
    if (top == 0u) { return BIG; }
    return stack[0];
}

// (distance, nearest object index as f32; −1: unknown) over every object;
// objects whose bounding sphere is farther than the best so far are skipped.
fn all_objects_distance(p: vec3<f32>) -> vec2<f32> {
    var best = BIG;
    var index = 0u;
    for (var i = 0u; i < P.size.w; i++) {
        let o = objects[i];
        if (o.albedo.w >= 0.0 && length(p - o.center.xyz) - o.albedo.w >= best) { continue; }
        let d = run_program(o.range.x, o.range.y, p);
        if (d < best) {
            best = d;
            index = i;
        }
    }
    return vec2<f32>(best, f32(index));
}

// The distance query through the grid of unbounding spheres and near lists
// (render/accel.rs, `Grid::probe_cell`).
fn scene_distance(p: vec3<f32>) -> vec2<f32> {
    if (P.grid_min.w < 0.5 || p.y < P.grid_min.y) { return all_objects_distance(p); }
    let lo = P.grid_min.xyz;
    let hi = P.grid_max.xyz;
    let outside = length(max(max(lo - p, p - hi), vec3<f32>(0.0)));
    let q = (p - lo) / P.grid_cell.xyz;
    let ijk = min(vec3<u32>(max(floor(q), vec3<f32>(0.0))), P.grid_dims.xyz - vec3<u32>(1u));
    let c = lo + (vec3<f32>(ijk) + vec3<f32>(0.5)) * P.grid_cell.xyz;
    let cell = cells[ijk.x + P.grid_dims.x * (ijk.y + P.grid_dims.y * ijk.z)];
    let cheap = max(cell.empty - length(p - c), outside);
    if (cheap >= P.grid_max.w) { return vec2<f32>(cheap, -1.0); }
    var best = cell.far - outside;
    var index = -1.0;
    for (var k = cell.start; k < cell.start + cell.len; k++) {
        let o = near[k];
        let d = run_program(objects[o].range.x, objects[o].range.y, p);
        if (d < best) {
            best = d;
            index = f32(o);
        }
    }
    if (cheap > best) { return vec2<f32>(cheap, -1.0); }
    return vec2<f32>(best, index);
}

fn object_distance(i: u32, p: vec3<f32>) -> f32 {
    return run_program(objects[i].range.x, objects[i].range.y, p);
}

// ------------------------------------------------------------- the ray path

// One RK4 step: states at both ends (position, v = n·t, dv/dτ, arc length,
// δ) and its τ length.
struct Seg {
    x0: vec3<f32>, v0: vec3<f32>, a0: vec3<f32>, s0: f32, d0: f32,
    x1: vec3<f32>, v1: vec3<f32>, a1: vec3<f32>, s1: f32, d1: f32,
    h: f32,
}

fn rate_dv(m: vec4<f32>) -> vec3<f32> {
    // n∇n = ∇δ + δ∇δ
    return m.xyz + m.w * m.xyz;
}

// Quintic Hermite position and its θ-derivative (trace/hermite.rs).
fn hermite(s: Seg, t: f32) -> array<vec3<f32>, 2> {
    let t2 = t * t;
    let t3 = t2 * t;
    let t4 = t3 * t;
    let t5 = t4 * t;
    let h5 = 10.0 * t3 - 15.0 * t4 + 6.0 * t5;
    let w0 = 1.0 - h5;
    let w1 = t - 6.0 * t3 + 8.0 * t4 - 3.0 * t5;
    let w2 = 0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5;
    let w3 = 0.5 * t3 - t4 + 0.5 * t5;
    let w4 = -4.0 * t3 + 7.0 * t4 - 3.0 * t5;
    let d5 = 30.0 * t2 - 60.0 * t3 + 30.0 * t4;
    let d1 = 1.0 - 18.0 * t2 + 32.0 * t3 - 15.0 * t4;
    let d2 = t - 4.5 * t2 + 6.0 * t3 - 2.5 * t4;
    let d3 = 1.5 * t2 - 4.0 * t3 + 2.5 * t4;
    let d4 = -12.0 * t2 + 28.0 * t3 - 15.0 * t4;
    let h = s.h;
    let h2 = h * h;
    // Relative to x0, so that f32 keeps the small displacement's digits.
    let dx = s.x1 - s.x0;
    let x = s.x0 + s.v0 * (h * w1) + s.a0 * (h2 * w2) + s.a1 * (h2 * w3) + s.v1 * (h * w4) + dx * h5;
    let dxdt = s.v0 * (h * d1) + s.a0 * (h2 * d2) + s.a1 * (h2 * d3) + s.v1 * (h * d4) + dx * d5;
    return array<vec3<f32>, 2>(x, dxdt);
}

// Cubic Hermite of v (trace/hermite.rs, `state`).
fn hermite_v(s: Seg, t: f32) -> vec3<f32> {
    let t2 = t * t;
    let t3 = t2 * t;
    let h01 = 3.0 * t2 - 2.0 * t3;
    return s.v0 * (1.0 - h01) + s.a0 * (s.h * (t - 2.0 * t2 + t3)) + s.v1 * h01 + s.a1 * (s.h * (t3 - t2));
}

// The height along the step at θ and its rate dh/dθ.
fn seg_height(s: Seg, t: f32) -> vec2<f32> {
    let e = hermite(s, t);
    let hu = height_up(e[0]);
    return vec2<f32>(hu.w, dot(e[1], hu.xyz));
}

// The root in [a, b] of the height, g(a) and g(b) of opposite signs.
fn height_root(s: Seg, a0: f32, b0: f32) -> f32 {
    var a = a0;
    var b = b0;
    let rising = seg_height(s, a).x < 0.0;
    var t = 0.5 * (a + b);
    for (var i = 0; i < 40; i++) {
        let e = seg_height(s, t);
        let g = e.x;
        if (g == 0.0) { return t; }
        if ((g < 0.0) == rising) { a = t; } else { b = t; }
        let newton = t - g / e.y;
        var next = 0.5 * (a + b);
        if (newton > a && newton < b) { next = newton; }
        if (abs(next - t) <= 1e-7 || b - a <= 1e-7) { return next; }
        t = next;
    }
    return t;
}

// The first θ where the step is below ground, or −1 (trace::first_ground_crossing).
fn ground_crossing(s: Seg) -> f32 {
    let u0 = height_up(s.x0);
    let u1 = height_up(s.x1);
    if (u0.w < 0.0) { return 0.0; }
    if (u1.w < 0.0) { return height_root(s, 0.0, 1.0); }
    if (dot(s.v0, u0.xyz) < 0.0 && dot(s.v1, u1.xyz) > 0.0) {
        // The lowest point: where the slope changes sign.
        var a = 0.0;
        var b = 1.0;
        for (var i = 0; i < 30; i++) {
            let m = 0.5 * (a + b);
            if (seg_height(s, m).y < 0.0) { a = m; } else { b = m; }
        }
        let lowest = 0.5 * (a + b);
        if (seg_height(s, lowest).x < 0.0) { return height_root(s, 0.0, lowest); }
    }
    return -1.0;
}

fn rk4(x: vec3<f32>, v: vec3<f32>, a: vec3<f32>, s: f32, d: f32, h: f32) -> Seg {
    let m2 = medium(x + v * (0.5 * h));
    let v2 = v + a * (0.5 * h);
    let a2 = rate_dv(m2);
    let m3 = medium(x + v2 * (0.5 * h));
    let v3 = v + a2 * (0.5 * h);
    let a3 = rate_dv(m3);
    let m4 = medium(x + v3 * h);
    let v4 = v + a3 * h;
    let a4 = rate_dv(m4);
    let x1 = x + (v + 2.0 * v2 + 2.0 * v3 + v4) * (h / 6.0);
    let v1 = v + (a + 2.0 * a2 + 2.0 * a3 + a4) * (h / 6.0);
    let s1 = s + ((1.0 + d) + 2.0 * (1.0 + m2.w) + 2.0 * (1.0 + m3.w) + (1.0 + m4.w)) * (h / 6.0);
    let m5 = medium(x1);
    return Seg(x, v, a, s, d, x1, v1, rate_dv(m5), s1, m5.w, h);
}

// ------------------------------------------------------------------- the sky

fn sky_texel(col: u32, row: u32) -> vec3<f32> {
    return textureLoad(sky, vec2<i32>(i32(col % P.counts.x), i32(row)), 0).xyz;
}

fn sky_radiance(dir: vec3<f32>) -> vec3<f32> {
    let d = normalize(dir);
    let elevation = asin(clamp(d.y, -1.0, 1.0));
    let v = sign(elevation) * sqrt(abs(elevation) / (0.5 * PI));
    let fy = (v + 1.0) * 0.5 * f32(P.counts.y - 1u);
    var az = atan2(d.x, d.z);
    if (az < 0.0) { az += 2.0 * PI; }
    let fx = az / (2.0 * PI) * f32(P.counts.x);
    let y0 = min(u32(floor(fy)), P.counts.y - 2u);
    let ty = clamp(fy - f32(y0), 0.0, 1.0);
    let x0 = u32(floor(fx)) % P.counts.x;
    let tx = fx - floor(fx);
    let low = mix(sky_texel(x0, y0), sky_texel(x0 + 1u, y0), tx);
    let high = mix(sky_texel(x0, y0 + 1u), sky_texel(x0 + 1u, y0 + 1u), tx);
    var c = mix(low, high, ty);
    if (P.disc_dir.w > 0.0 && dot(d, P.disc_dir.xyz) >= cos(P.disc_dir.w)) {
        c += P.disc_radiance.xyz;
    }
    // Stars fade against a bright sky, as PhysicalSky::radiance has them.
    if (P.stars.w > 0.0) {
        var fade = 1.0;
        if (P.stars.z > 0.0) { fade = exp(-(c.x + c.y + c.z) / 3.0 / P.stars.z); }
        if (fade > 1e-6) { c += star_light(d) * fade; }
    }
    return c;
}

// The star along unit `d` (PhysicalSky::star): a cube map of STAR_CELLS cells
// per face edge, each with at most one star, drawn as a disc of P.stars.x.

fn star_light(d: vec3<f32>) -> vec3<f32> {
    let a = abs(d);
    var face: u32;
    var u: f32;
    var v: f32;
    if (a.x >= a.y && a.x >= a.z) {
        face = select(1u, 0u, d.x > 0.0); u = d.y / a.x; v = d.z / a.x;
    } else if (a.y >= a.z) {
        face = select(3u, 2u, d.y > 0.0); u = d.x / a.y; v = d.z / a.y;
    } else {
        face = select(5u, 4u, d.z > 0.0); u = d.x / a.z; v = d.y / a.z;
    }
    let fu = (u + 1.0) * 0.5 * STAR_CELLS;
    let fv = (v + 1.0) * 0.5 * STAR_CELLS;
    let iu = min(floor(fu), STAR_CELLS - 1.0);
    let iv = min(floor(fv), STAR_CELLS - 1.0);
    let n = u32(STAR_CELLS);
    let s = stars[(face * n + u32(iu)) * n + u32(iv)];
    if (s.w == 0.0) { return vec3<f32>(0.0); }
    let cell = 2.0 / STAR_CELLS;
    let r = P.stars.x;
    let margin = min(r / cell, STAR_MARGIN_MAX);
    let du = (fu - (iu + margin + s.x * (1.0 - 2.0 * margin))) * cell;
    let dv = (fv - (iv + margin + s.y * (1.0 - 2.0 * margin))) * cell;
    if (du * du + dv * dv > r * r) { return vec3<f32>(0.0); }
    let radiance = P.stars.y * s.z / (PI * r * r);
    return radiance * vec3<f32>(s.w, 1.0, 2.0 - s.w);
}

// -------------------------------------------------------------- the marching

// Outcome: kind 0 sky (dir), 1 object (index, point, distance), 2 ground (point).
struct Outcome { kind: u32, index: u32, point: vec3<f32>, dir: vec3<f32>, distance: f32 }

// f32 resolves positions to ~6e-8 of their size, and distances computed from
// them no better: the hit tolerance (and the shading offsets built on it)
// never go below a few of those steps, or rays would creep toward surfaces
// through rounding noise (the CPU's f64 has no such floor).
const F32_FLOOR: f32 = 5e-7;

fn tolerance(s: f32, p: vec3<f32>) -> f32 {
    let size = max(s, max(max(abs(p.x), abs(p.y)), abs(p.z)));
    return max(max(P.tolerance.x, P.tolerance.y * s), F32_FLOOR * size);
}

// A pixel's ray between passes: where its march got to, and its samples so
// far (layout::GpuRay). The current RK4 step is kept by its start (x, v, a,
// s, δ and its τ length h; h = 0: no step yet, the next one starts there),
// and `march` takes it again from there at its one RK4 call site, so that a
// ray resumed in a later pass takes bit for bit the steps of one traced in a
// single pass.
struct Ray {
    x: vec4<f32>,       // position, arc length s
    v: vec4<f32>,       // v = n·t, δ
    a: vec4<f32>,       // dv/dτ, the step's τ length h
    at: vec4<f32>,      // θ on the step, arc per unit θ, budget, free flight (1) or not (0)
    sum: vec4<f32>,     // the pixel's finished samples' radiance
    count: vec4<u32>,   // phase (PHASE_*), sample, distance queries, iterations
}

// A camera ray from `origin` along the unit `dir`, before its first step.
fn start_ray(origin: vec3<f32>, dir: vec3<f32>) -> Ray {
    let m0 = medium(origin);
    let v0 = dir * (1.0 + m0.w);
    var free = 0.0;
    if (P.size.w == 0u) { free = 1.0; }
    return Ray(vec4<f32>(origin, 0.0), vec4<f32>(v0, m0.w), vec4<f32>(rate_dv(m0), 0.0),
        vec4<f32>(1.0, 0.0, 0.0, free), vec4<f32>(0.0), vec4<u32>(PHASE_TRACING, 0u, 0u, 0u));
}

// `march`'s result: the ray as it stands, and its outcome once `done`.
struct Marched { done: bool, ray: Ray, outcome: Outcome }

// Marches `r` on by at most P.march.y iterations (one pass). Each iteration
// ends an RK4 step or spends the budget of one distance query, so a ray
// takes at most P.march.x of them; past that (only a ray whose state went
// non-finite) it is given up to the sky along its direction.
fn march(r: Ray) -> Marched {
    var ray = r;
    let n_max = P.air.x * (1.0 + 1e-7);
    let max_distance = P.up.w;
    var seg = Seg(r.x.xyz, r.v.xyz, r.a.xyz, r.x.w, r.v.w, r.x.xyz, r.v.xyz, r.a.xyz, r.x.w, r.v.w, 0.0);
    // Resuming inside a step: take it again from its start.
    var resume = r.a.w > 0.0;
    var theta = r.at.x;
    var arc_per_theta = r.at.y;
    var budget = r.at.z;
    var free = r.at.w > 0.5;
    var queries = r.count.z;
    var iterations = r.count.w;
    var ground_theta = -1.0;
    for (var pass_iteration = 0u; pass_iteration <= P.march.y; pass_iteration++) {
        if (pass_iteration == P.march.y) {
            // The pass is over: keep the current step by its start.
            if (theta >= 1.0) {
                ray.x = vec4<f32>(seg.x1, seg.s1);
                ray.v = vec4<f32>(seg.v1, seg.d1);
                ray.a = vec4<f32>(seg.a1, 0.0);
                theta = 1.0;
            } else {
                ray.x = vec4<f32>(seg.x0, seg.s0);
                ray.v = vec4<f32>(seg.v0, seg.d0);
                ray.a = vec4<f32>(seg.a0, seg.h);
            }
            ray.at = vec4<f32>(theta, arc_per_theta, budget, select(0.0, 1.0, free));
            ray.count.z = queries;
            ray.count.w = iterations;
            break;
        }
        if (iterations >= P.march.x) {
            return Marched(true, ray, Outcome(0u, 0u, seg.x1, normalize(seg.v1), max_distance));
        }
        iterations += 1u;
        if (theta >= 1.0 || resume) {
            var h_arc = min(step_at(seg.x1), max_distance);
            var h = h_arc / n_max;
            if (resume) {
                h = r.a.w;
                h_arc = arc_per_theta;
            } else {
                theta = 0.0;
            }
            seg = rk4(seg.x1, seg.v1, seg.a1, seg.s1, seg.d1, h);
            arc_per_theta = h_arc;
            resume = false;
            ground_theta = -1.0;
            if (P.flags.z != GROUND_NONE) { ground_theta = ground_crossing(seg); }
        }
        if (!free && budget <= 0.0) {
            let e = hermite(seg, theta);
            let p = e[0];
            let v = e[1] / seg.h;
            let q = scene_distance(p);
            queries += 1u;
            let arc = seg.s0 + theta * (seg.s1 - seg.s0);
            if (q.x < tolerance(arc, p) || queries >= P.counts.w) {
                var index = q.y;
                if (index < 0.0) { index = all_objects_distance(p).y; }
                return Marched(true, ray, Outcome(1u, u32(index), p, normalize(v), arc));
            }
            let f = fate(p, v, true);
            if (f.kind == 1u) { return Marched(true, ray, Outcome(0u, 0u, p, f.dir, arc)); }
            if (f.kind == 2u) {
                free = true;
                continue;
            }
            budget = q.x;
        }
        // Advance by at most `budget` of arc (unlimited when free).
        let room = (1.0 - theta) * arc_per_theta;
        var go = room;
        if (!free) { go = min(budget, room); }
        var goal = 1.0;
        if (go < room) { goal = theta + go / arc_per_theta; }
        if (ground_theta >= 0.0 && ground_theta <= goal) {
            let e = hermite(seg, ground_theta);
            var point = vec3<f32>(e[0].x, 0.0, e[0].z);
            if (P.profile.w > 0.0) {
                // The foot of the crossing's vertical on the sphere.
                let hu = height_up(e[0]);
                point = e[0] - hu.xyz * hu.w;
            }
            let s = seg.s0 + ground_theta * (seg.s1 - seg.s0);
            return Marched(true, ray, Outcome(2u, 0u, point, normalize(hermite_v(seg, ground_theta)), s));
        }
        if (seg.s1 >= max_distance) {
            let t_max = clamp((max_distance - seg.s0) / (seg.s1 - seg.s0), 0.0, 1.0);
            if (t_max <= goal) {
                let e = hermite(seg, t_max);
                let v = hermite_v(seg, t_max);
                let f = fate(e[0], v, false);
                var dir = normalize(v);
                if (f.kind == 1u) { dir = f.dir; }
                return Marched(true, ray, Outcome(0u, 0u, e[0], dir, max_distance));
            }
        }
        theta = goal;
        budget -= go;
    }
    return Marched(false, ray, Outcome(0u, 0u, vec3<f32>(0.0), vec3<f32>(0.0), 0.0));
}

// ------------------------------------------------------------------ shading

fn ray_box(o: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    let inv = 1.0 / d;
    let a = (P.box_min.xyz - o) * inv;
    let b = (P.box_max.xyz - o) * inv;
    let lo = min(a, b);
    let hi = max(a, b);
    let t0 = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let t1 = min(min(hi.x, hi.y), hi.z);
    return vec2<f32>(t0, t1);
}

fn sunlit(p: vec3<f32>, d: vec3<f32>) -> bool {
    if (P.box_min.w < 0.5) { return true; }
    let span = ray_box(p, d);
    if (!(span.x <= span.y)) { return true; }
    var t = span.x;
    for (var i = 0; i < 512; i++) {
        let q = scene_distance(p + d * t).x;
        if (q < 1e-4 + 1e-7 * t) { return false; }
        t += q;
        if (t > span.y) { return true; }
    }
    return true;
}

fn light(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>) -> vec3<f32> {
    let sun = P.sun_dir.xyz;
    let c = dot(n, sun);
    var direct = 0.0;
    if (c > 0.0 && sun.y > 0.0 && sunlit(p, sun)) { direct = c / PI; }
    let hemi = 0.5 + 0.5 * n.y;
    return albedo * (P.sun_irradiance.xyz * direct + P.ambient.xyz * hemi);
}

fn object_normal(i: u32, p: vec3<f32>) -> vec3<f32> {
    // f32 needs a larger step than the CPU's 1e-7 relative one.
    let h = max(1e-3, 4e-6 * max(max(abs(p.x), abs(p.y)), abs(p.z)));
    let g = vec3<f32>(
        object_distance(i, p + vec3<f32>(h, 0.0, 0.0)) - object_distance(i, p - vec3<f32>(h, 0.0, 0.0)),
        object_distance(i, p + vec3<f32>(0.0, h, 0.0)) - object_distance(i, p - vec3<f32>(0.0, h, 0.0)),
        object_distance(i, p + vec3<f32>(0.0, 0.0, h)) - object_distance(i, p - vec3<f32>(0.0, 0.0, h)));
    let l = length(g);
    if (l == 0.0) { return vec3<f32>(0.0, 1.0, 0.0); }
    return g / l;
}

fn ground_albedo(x: f32, z: f32) -> vec3<f32> {
    if (P.flags.z == GROUND_CHECKER) {
        let i = i32(floor(x / P.ground0.w)) + i32(floor(z / P.ground0.w));
        if ((i & 1) != 0) { return P.ground1.xyz; }
    }
    return P.ground0.xyz;
}

fn shade(o: Outcome) -> vec3<f32> {
    let albedo_only = P.flags.x == SHADING_ALBEDO;
    if (o.kind == 0u) { return sky_radiance(o.dir); }
    if (o.kind == 1u) {
        let albedo = objects[o.index].albedo.xyz;
        if (albedo_only) { return albedo; }
        let n = object_normal(o.index, o.point);
        let eps = tolerance(o.distance, o.point);
        return light(o.point + n * (2.0 * eps + 1e-4), n, albedo);
    }
    let albedo = ground_albedo(o.point.x, o.point.z);
    if (albedo_only) { return albedo; }
    let up = height_up(o.point).xyz;
    return light(o.point + up * 1e-3, up, albedo);
}

// --------------------------------------------------------------- the camera

fn sample_offset(i: u32) -> vec2<f32> {
    let k = f32(i);
    return vec2<f32>(fract(0.5 + 0.7548776662466927 * k), fract(0.5 + 0.5698402909980533 * k));
}

fn camera_ray(id: vec2<u32>, sample: u32) -> Ray {
    let off = sample_offset(sample);
    let px = f32(id.x) + off.x;
    let py = f32(id.y) + off.y;
    let sx = (2.0 * px / f32(P.size.x) - 1.0) * P.origin.w * P.forward.w;
    let sy = (1.0 - 2.0 * py / f32(P.size.y)) * P.origin.w;
    let dir = normalize(P.forward.xyz + P.right.xyz * sx + P.up.xyz * sy);
    return start_ray(P.origin.xyz, dir);
}

// One pass over a band of the image: each pixel's ray marches on from where
// the last pass left it (the host clears `rays` to PHASE_START before a
// band's first pass); a sample that ends is shaded, and the pixel's last one
// writes its colour (the mean of this frame's samples and, when accumulating,
// of the P.accumulate.x samples before them). At most one sample ends in a pass, so that a pass shades
// at most once.
@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) local: vec3<u32>) {
    let w = P.size.x;
    let id = vec2<u32>(local.x, local.y + band.x);
    if (local.x >= w || local.y >= band.y || id.y >= P.size.y) { return; }
    let i = local.x + w * local.y;
    let phase = rays[i].count.x;
    if (phase == PHASE_DONE) { return; }
    var ray = rays[i];
    let pixel = id.x + w * id.y;
    if (phase == PHASE_START) {
        var sum = ray.sum;
        let sample = ray.count.y;
        // A frame that adds to the samples of the frames before starts from
        // their sum: the same f32 additions, in the same order, as one frame
        // that traces them all.
        if (sample == 0u && P.accumulate.x > 0u) { sum = accum[pixel]; }
        ray = camera_ray(id.xy, P.accumulate.x + sample);
        ray.sum = sum;
        ray.count.y = sample;
    }
    let m = march(ray);
    ray = m.ray;
    if (!m.done) {
        rays[i] = ray;
        return;
    }
    let sum = ray.sum.xyz + shade(m.outcome);
    let sample = ray.count.y + 1u;
    let spp = P.counts.z;
    if (sample < spp) {
        rays[i].sum = vec4<f32>(sum, 0.0);
        rays[i].count = vec4<u32>(PHASE_START, sample, 0u, 0u);
        return;
    }
    if (P.accumulate.y != 0u) { accum[pixel] = vec4<f32>(sum, 0.0); }
    textureStore(out_image, vec2<i32>(i32(id.x), i32(id.y)), vec4<f32>(sum / f32(P.accumulate.x + spp), 1.0));
    rays[i].count.x = PHASE_DONE;
}
