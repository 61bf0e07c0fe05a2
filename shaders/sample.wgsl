// Stratified sampling on the GPU: one invocation per sample maps its stratified value
// through the flattened cells (engine/src/sample/flat.rs) to a site (face, segment,
// barycentric coordinates), the same site as Sampler::sample_sites_into up to f32
// round-off in the point. A module of its own (no common.wgsl). Portable: 32-bit
// integers and f32 only (64-bit values are vec2<u32>, low word first), no subgroup
// operations, no atomics. A 2-D dispatch of 64-wide workgroups (rows of `row`
// invocations).

// Twin of strata_engine::sample::SampleSite (16 bytes).
struct Site {
    face: u32,
    segment: u32,
    bary: vec2<f32>,
}

// Twin of strata_systems::gpu::sample::SampleParams (112 bytes). The table holds, as
// 32-bit words: cumulative measures (2 words per leaf, and one more) from `cum_at`,
// leaves (5 words) from `leaves_at`, candidates (1) from `cands_at`, pieces (20) from
// `pieces_at`, triangles (7) from `tris_at`, segment ids per slot from `slots_at`,
// descent-tree nodes (13) from `nodes_at`, density planes (3 per triangle) from
// `planes_at`, progressive levels per slot from `prog_levels_at`, the progressive
// order's descent-tree nodes (13) from `prog_nodes_at` with their pieces (20) from
// `prog_pieces_at`, and its list of leaves with such a tree (a count, then `[leaf,
// root]` pairs in increasing leaf order) from `trees_at`. A stratified
// request holds its groups (10 words each) from word 0, the levels per slot from
// `levels_at` and `depth` descent thresholds per group (2 words each) from
// `thresholds_at`. A progressive request (progressive.wgsl) draws ranks `first +
// k`, or the ranks listed from word `first` of the request when `listed` is set,
// over `leaves` leaves with the scramble `add` .. `jitter_hi`, and writes site
// `out_at + k`.
struct SampleParams {
    count: u32,
    groups: u32,
    row: u32,
    levels_at: u32,
    cum_at: u32,
    leaves_at: u32,
    cands_at: u32,
    pieces_at: u32,
    tris_at: u32,
    slots_at: u32,
    nodes_at: u32,
    thresholds_at: u32,
    depth: u32,
    first: u32,
    listed: u32,
    out_at: u32,
    leaves: u32,
    add: u32,
    even0: u32,
    even1: u32,
    odd: u32,
    jitter_lo: u32,
    jitter_hi: u32,
    planes_at: u32,
    prog_levels_at: u32,
    prog_nodes_at: u32,
    prog_pieces_at: u32,
    trees_at: u32,
}

@group(0) @binding(0) var<uniform> params: SampleParams;
@group(0) @binding(1) var<storage, read> table: array<u32>;
@group(0) @binding(2) var<storage, read> request: array<u32>;
@group(0) @binding(3) var<storage, read_write> sites: array<Site>;

// ---- 64-bit integers as vec2<u32> (x: low word, y: high word) ----

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn sub64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    return vec2<u32>(a.x - b.x, a.y - b.y - select(0u, 1u, a.x < b.x));
}

fn lt64(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.y < b.y || (a.y == b.y && a.x < b.x);
}

fn shl1(a: vec2<u32>) -> vec2<u32> {
    return vec2<u32>(a.x << 1u, (a.y << 1u) | (a.x >> 31u));
}

// a >> s for 0 < s < 32.
fn shr64(a: vec2<u32>, s: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> s) | (a.y << (32u - s)), a.y >> s);
}

// The full 64-bit product of two 32-bit values.
fn mul32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let mid = a0 * b1 + (p00 >> 16u);
    let mid2 = (mid & 0xffffu) + a1 * b0;
    let lo = (mid2 << 16u) | (p00 & 0xffffu);
    let hi = a1 * b1 + (mid >> 16u) + (mid2 >> 16u);
    return vec2<u32>(lo, hi);
}

// The low 64 bits of a * b.
fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let p = mul32(a.x, b.x);
    return vec2<u32>(p.x, p.y + a.x * b.y + a.y * b.x);
}

// The high 64 bits of the 128-bit product a * b.
fn mulhi64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let p00 = mul32(a.x, b.x);
    let p01 = mul32(a.x, b.y);
    let p10 = mul32(a.y, b.x);
    let p11 = mul32(a.y, b.y);
    var w1 = p00.y + p01.x;
    var c = select(0u, 1u, w1 < p01.x);
    w1 = w1 + p10.x;
    c = c + select(0u, 1u, w1 < p10.x);
    var w2 = p11.x + p01.y;
    var c2 = select(0u, 1u, w2 < p01.y);
    w2 = w2 + p10.y;
    c2 = c2 + select(0u, 1u, w2 < p10.y);
    w2 = w2 + c;
    c2 = c2 + select(0u, 1u, w2 < c);
    return vec2<u32>(w2, p11.y + c2);
}

// SplitMix64's finaliser (engine/src/rng.rs `mix64`).
fn mix64(z0: vec2<u32>) -> vec2<u32> {
    var z = z0;
    z = mul64(z ^ shr64(z, 30u), vec2<u32>(0x1ce4e5b9u, 0xbf58476du));
    z = mul64(z ^ shr64(z, 27u), vec2<u32>(0x133111ebu, 0x94d049bbu));
    return z ^ shr64(z, 31u);
}

// floor(n 2^64 / d) for n < d (d > 0): the 64-bit fraction n / d.
fn fraction64(n: vec2<u32>, d: vec2<u32>) -> vec2<u32> {
    var r = n;
    var q = vec2<u32>(0u, 0u);
    for (var i = 0u; i < 64u; i = i + 1u) {
        let carry = r.y >> 31u;
        r = shl1(r);
        q = shl1(q);
        if carry == 1u || !lt64(r, d) {
            r = sub64(r, d);
            q.x = q.x | 1u;
        }
    }
    return q;
}

// floor((j 2^64 + low) / count) for j < count: the stratified value (j + U) / count
// as a 64-bit fraction, with U's 53 bits as the top of `low`.
fn value64(j: u32, low: vec2<u32>, count: u32) -> vec2<u32> {
    var r = j;
    var q = vec2<u32>(0u, 0u);
    var bits = low;
    for (var i = 0u; i < 64u; i = i + 1u) {
        let carry = r >> 31u;
        r = (r << 1u) | (bits.y >> 31u);
        bits = shl1(bits);
        q = shl1(q);
        if carry == 1u || r >= count {
            r = r - count;
            q.x = q.x | 1u;
        }
    }
    return q;
}

// ---- tables ----

fn t64(at: u32) -> vec2<u32> {
    return vec2<u32>(table[at], table[at + 1u]);
}

fn cum(l: u32) -> vec2<u32> {
    return t64(params.cum_at + 2u * l);
}

fn tf(at: u32) -> f32 {
    return bitcast<f32>(table[at]);
}

fn tri_corner(t: u32, k: u32) -> vec2<f32> {
    let w = params.tris_at + 7u * t + 2u * k;
    return vec2<f32>(tf(w), tf(w + 1u));
}

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// Barycentric coordinates of `p` in triangle `t`.
fn barycentric(t: u32, p: vec2<f32>) -> vec3<f32> {
    let p0 = tri_corner(t, 0u);
    let e1 = tri_corner(t, 1u) - p0;
    let e2 = tri_corner(t, 2u) - p0;
    let d = p - p0;
    let inv = 1.0 / cross2(e1, e2);
    let b1 = cross2(d, e2) * inv;
    let b2 = cross2(e1, d) * inv;
    return vec3<f32>(1.0 - b1 - b2, b1, b2);
}

// A located point: triangle and barycentric coordinates.
struct Located {
    tri: u32,
    bary: vec3<f32>,
}

fn clamped_onto(tri: u32, b0: vec3<f32>) -> Located {
    let b = max(b0, vec3<f32>(0.0));
    return Located(tri, b / (b.x + b.y + b.z));
}

// The candidate containing `uv` (`n` triangles from word `at`; `stride` words apart,
// the triangle index first), else the most-inside one clamped onto
// (curve/locate.rs `point_location`).
fn point_location(at: u32, n: u32, stride: u32, uv: vec2<f32>) -> Located {
    for (var i = 0u; i < n; i = i + 1u) {
        let t = table[at + stride * i];
        let p0 = tri_corner(t, 0u);
        let e1 = tri_corner(t, 1u) - p0;
        let e2 = tri_corner(t, 2u) - p0;
        let d = uv - p0;
        let det = cross2(e1, e2);
        let s1 = cross2(d, e2);
        let s2 = cross2(e1, d);
        if s1 >= 0.0 && s2 >= 0.0 && s1 + s2 <= det {
            let inv = 1.0 / det;
            let b1 = s1 * inv;
            let b2 = s2 * inv;
            let b = vec3<f32>(1.0 - b1 - b2, b1, b2);
            if b.x >= 0.0 {
                return Located(t, b);
            }
        }
    }
    var best = -3.4028235e38;
    var best_t = table[at];
    var best_b = vec3<f32>(1.0, 0.0, 0.0);
    for (var i = 0u; i < n; i = i + 1u) {
        let t = table[at + stride * i];
        let b = barycentric(t, uv);
        let m = min(b.x, min(b.y, b.z));
        if m >= 0.0 {
            return Located(t, b);
        }
        if m > best {
            best = m;
            best_t = t;
            best_b = b;
        }
    }
    return clamped_onto(best_t, best_b);
}

// ---- Hilbert curve (curve/hilbert.rs) ----

// Quadrant (x, y) and child state of the child at `rank` of a node in `state`.
fn hilbert_child(state: u32, rank: u32) -> vec3<u32> {
    // The state-0 pattern (0,0), (0,1), (1,1), (1,0); child states 1, 0, 0, 2 (xor).
    let px = select(0u, 1u, rank == 2u || rank == 3u);
    let py = select(0u, 1u, rank == 1u || rank == 2u);
    var q: vec2<u32>;
    switch state {
        case 0u: { q = vec2<u32>(px, py); }
        case 1u: { q = vec2<u32>(py, px); }
        case 2u: { q = vec2<u32>(1u - py, 1u - px); }
        default: { q = vec2<u32>(1u - px, 1u - py); }
    }
    var child = 0u;
    if rank == 0u {
        child = 1u;
    } else if rank == 3u {
        child = 2u;
    }
    return vec3<u32>(q, state ^ child);
}

// ---- points in leaves ----

// The centre of the sub-cell, in the unit square of a cell whose Hilbert curve starts
// in `start`, that the top `2 levels` bits of the 64-bit `q` (hi, lo as y, x) reach.
fn hilbert_point(start: u32, q: vec2<u32>, levels: u32) -> vec2<f32> {
    var state = start;
    var x = 0u;
    var y = 0u;
    for (var i = 0u; i < levels; i = i + 1u) {
        // Bits 63 - 2i and 62 - 2i of q.
        let p = 62u - 2u * i;
        var rank: u32;
        if p >= 32u {
            rank = (q.y >> (p - 32u)) & 3u;
        } else {
            rank = (q.x >> p) & 3u;
        }
        let c = hilbert_child(state, rank);
        x = 2u * x + c.x;
        y = 2u * y + c.y;
        state = c.z;
    }
    return (vec2<f32>(f32(x), f32(y)) + 0.5) * exp2(-f32(levels));
}

// A full leaf: the centre of the sub-cell `levels` levels down that the continuous
// Hilbert map reaches at the fraction `q` (curve/locate.rs `FullLeaf::point`).
fn full_leaf_point(leaf: u32, q: vec2<u32>, levels: u32) -> Located {
    let w = params.leaves_at + 5u * leaf;
    let info = table[w + 2u];
    let level = info & 31u;
    let state = (info >> 5u) & 3u;
    let local = hilbert_point(state, q, levels);
    let uv = (vec2<f32>(f32(table[w]), f32(table[w + 1u])) + local) * exp2(-f32(level));
    return point_location(params.cands_at + table[w + 3u], table[w + 4u], 1u, uv);
}

// Every second bit of a 32-bit value (bit 2i to bit i).
fn compact(v0: u32) -> u32 {
    var v = v0 & 0x55555555u;
    v = (v | (v >> 1u)) & 0x33333333u;
    v = (v | (v >> 2u)) & 0x0f0f0f0fu;
    v = (v | (v >> 4u)) & 0x00ff00ffu;
    return (v | (v >> 8u)) & 0xffffu;
}

// The two values of curve/clip.rs `split_fraction` for the 64-bit fraction `f`: the
// odd and the even bits of its top 52 bits, to 24 bits each.
fn split_fraction(f: vec2<u32>) -> vec2<f32> {
    let odd = (compact(f.y >> 1u) << 8u) | compact(f.x >> 17u);
    let even = (compact(f.y) << 8u) | compact(f.x >> 16u);
    return vec2<f32>(f32(odd), f32(even)) * exp2(-24.0) + exp2(-27.0);
}

// The corners of piece `at` (`n` of them) in its leaf's unit square.
var<private> poly: array<vec2<f32>, 8>;

fn y_on(e0: u32, e1: u32, x: f32) -> f32 {
    let u = poly[e0];
    let v = poly[e1];
    if v.x > u.x {
        return u.y + (x - u.x) / (v.x - u.x) * (v.y - u.y);
    }
    return v.y;
}

// The point of the convex polygon `poly` (n corners) at the fraction split into `g`,
// uniform in area (curve/clip.rs `Poly::point_at`); z = 0 when it has no area.
fn point_at(n: u32, g: vec2<f32>) -> vec3<f32> {
    var a2 = 0.0;
    for (var k = 1u; k + 1u < n; k = k + 1u) {
        a2 = a2 + cross2(poly[k] - poly[0], poly[k + 1u] - poly[0]);
    }
    let total = abs(0.5 * a2);
    if n < 3u || !(total > 0.0) {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    let g1 = g.x;
    let g2 = g.y;
    var lo = 0u;
    var hi = 0u;
    for (var k = 1u; k < n; k = k + 1u) {
        if poly[k].x < poly[lo].x {
            lo = k;
        }
        if poly[k].x > poly[hi].x {
            hi = k;
        }
    }
    var a0 = lo;
    var a1 = (lo + 1u) % n;
    var b0 = lo;
    var b1 = (lo + n - 1u) % n;
    var x = poly[lo].x;
    for (var s = 0u; s < n && a0 != hi && poly[a1].x <= x; s = s + 1u) {
        a0 = a1;
        a1 = (a1 + 1u) % n;
    }
    for (var s = 0u; s < n && b0 != hi && poly[b1].x <= x; s = s + 1u) {
        b0 = b1;
        b1 = (b1 + n - 1u) % n;
    }
    var c0 = abs(y_on(a0, a1, x) - y_on(b0, b1, x));
    var rest = g1 * total;
    for (var pass_ = 0u; pass_ < n; pass_ = pass_ + 1u) {
        let next = max(min(min(poly[a1].x, poly[b1].x), poly[hi].x), x);
        let c1 = abs(y_on(a0, a1, next) - y_on(b0, b1, next));
        let area = 0.5 * (c0 + c1) * (next - x);
        if rest < area || next >= poly[hi].x || a0 == hi || b0 == hi {
            let dx = next - x;
            if dx > 0.0 {
                let k = (c1 - c0) / dx;
                let denom = c0 + sqrt(max(c0 * c0 + 2.0 * k * rest, 0.0));
                var t = 0.0;
                if denom > 0.0 {
                    t = 2.0 * rest / denom;
                }
                x = x + clamp(t, 0.0, dx);
            }
            break;
        }
        rest = rest - area;
        x = next;
        c0 = c1;
        for (var s = 0u; s < n && a0 != hi && poly[a1].x <= x; s = s + 1u) {
            a0 = a1;
            a1 = (a1 + 1u) % n;
        }
        for (var s = 0u; s < n && b0 != hi && poly[b1].x <= x; s = s + 1u) {
            b0 = b1;
            b1 = (b1 + n - 1u) % n;
        }
    }
    let ya = y_on(a0, a1, x);
    let yb = y_on(b0, b1, x);
    return vec3<f32>(x, min(ya, yb) + g2 * abs(ya - yb), 1.0);
}

// The point at the fraction `q` of descent-tree node `node`'s measure in its pieces:
// the piece holding it and the point at the rest of it, by area
// (curve/boundary.rs `place_in_pieces`); the square's centre located among the
// pieces' triangles when no piece has measure. Measures in 2^62 fixed point. The
// nodes start at word `nodes_at` of the table, their pieces at `pieces_at`.
fn node_pieces_point(nodes_at: u32, pieces_at: u32, node: u32, q: vec2<u32>) -> Located {
    let w = nodes_at + 13u * node;
    let level = table[w] & 31u;
    let size = exp2(-f32(level));
    let origin = vec2<f32>(f32(table[w + 1u]), f32(table[w + 2u])) * size;
    let first = pieces_at + 20u * table[w + 3u];
    let n = table[w + 4u];
    var want = shr64(q, 2u);
    var chosen = n;
    var rest = vec2<u32>(0u, 0u);
    for (var i = 0u; i < n; i = i + 1u) {
        let m = t64(first + 20u * i + 2u);
        if m.x == 0u && m.y == 0u {
            continue;
        }
        chosen = i;
        rest = want;
        if lt64(want, m) {
            break;
        }
        want = sub64(want, m);
    }
    if chosen < n {
        let at = first + 20u * chosen;
        let corners = min(table[at + 1u], 8u);
        for (var k = 0u; k < corners; k = k + 1u) {
            poly[k] = vec2<f32>(tf(at + 4u + 2u * k), tf(at + 5u + 2u * k));
        }
        let m = t64(at + 2u);
        var f = vec2<u32>(0xffffffffu, 0xffffffffu);
        if lt64(rest, m) {
            f = fraction64(rest, m);
        }
        let p = point_at(corners, split_fraction(f));
        if p.z > 0.0 {
            let tri = table[at];
            return clamped_onto(tri, barycentric(tri, origin + p.xy * size));
        }
    }
    return point_location(first, max(n, 1u), 20u, origin + vec2<f32>(0.5 * size));
}

// A full quarter of a descent: the centre of the sub-cell `levels` levels down that
// the continuous Hilbert map reaches at the fraction `q`, located among the node's
// pieces' triangles (curve/boundary.rs, `point_in_node` in a full sub-cell). Tables
// as in `node_pieces_point`.
fn full_node_point(nodes_at: u32, pieces_at: u32, node: u32, q: vec2<u32>, levels: u32) -> Located {
    let w = nodes_at + 13u * node;
    let info = table[w];
    let level = info & 31u;
    let state = (info >> 5u) & 3u;
    let local = hilbert_point(state, q, levels);
    let uv = (vec2<f32>(f32(table[w + 1u]), f32(table[w + 2u])) + local) * exp2(-f32(level));
    return point_location(pieces_at + 20u * table[w + 3u], table[w + 4u], 20u, uv);
}

// One step down a descent tree whose nodes start at word `nodes_at`: the child of
// `node` holding the fraction `q` of its measure (a half, or a quarter), and `q` as a
// fraction of that child's measure, with the sequential `pick`'s clamping; child
// 0xffffffff where the node has none there (then `q` as it is after the step).
struct TreeStep {
    child: u32,
    q: vec2<u32>,
}

fn tree_step(nodes_at: u32, node: u32, q: vec2<u32>) -> TreeStep {
    let w = nodes_at + 13u * node;
    let a = t64(w + 5u);
    let b = t64(w + 7u);
    let a_empty = a.x == 0u && a.y == 0u;
    let b_empty = b.x == 0u && b.y == 0u;
    let ones = vec2<u32>(0xffffffffu, 0xffffffffu);
    if !a_empty && (lt64(q, a) || b_empty) {
        return TreeStep(table[w + 9u], select(ones, fraction64(q, a), lt64(q, a)));
    }
    if !b_empty {
        let r = sub64(q, a);
        return TreeStep(table[w + 10u], select(ones, fraction64(r, b), lt64(r, b)));
    }
    return TreeStep(0xffffffffu, q);
}

// A boundary leaf: the sequential descent (curve/boundary.rs `descend_pieces`)
// replayed over the leaf's tree from node `root` for `levels` levels of quarters.
// `q` is carried as a 64-bit fraction of the current node's measure; each node holds
// its two children's measures as fractions of its own, so a step is a comparison and
// one division, with the sequential `pick`'s clamping.
fn boundary_leaf_point(root: u32, q0: vec2<u32>, levels: u32) -> Located {
    var node = root;
    var q = q0;
    var depth = 0u;
    // Two steps (a half, then a quarter) per level.
    for (var step = 0u; step < 2u * levels; step = step + 1u) {
        let s = tree_step(params.nodes_at, node, q);
        q = s.q;
        if s.child == 0xffffffffu {
            break;
        }
        node = s.child;
        let kind = table[params.nodes_at + 13u * node];
        if (kind & 256u) != 0u {
            depth = depth + 1u;
            if (kind & 128u) != 0u {
                return full_node_point(params.nodes_at, params.pieces_at, node, q, levels - depth);
            }
        }
    }
    return node_pieces_point(params.nodes_at, params.pieces_at, node, q);
}

// The levels of descent through a boundary leaf whose tree starts at node `root`, in
// group `group`: how many of the group's thresholds its measure (`f64` bits, compared
// as integers) reaches.
fn descent_levels(root: u32, group: u32) -> u32 {
    let w = t64(params.nodes_at + 13u * root + 11u);
    var levels = 0u;
    for (var k = 0u; k < params.depth; k = k + 1u) {
        let at = params.thresholds_at + 2u * (params.depth * group + k);
        if !lt64(w, vec2<u32>(request[at], request[at + 1u])) {
            levels = k + 1u;
        }
    }
    return levels;
}

// ---- the pass ----

// A leaf found by `leaf_at` and the fraction of its measure below the value.
struct LeafAt {
    leaf: u32,
    q: vec2<u32>,
}

// The first leaf in `first..=last` whose end in the cumulative measures exceeds the
// 64-bit value `m` (`last` if none), and the fraction of that leaf's measure below `m`
// as a 64-bit fraction (0 below the leaf, all ones past its end).
fn leaf_at(m: vec2<u32>, first: u32, last: u32) -> LeafAt {
    var a = first;
    var b = last;
    while a < b {
        let mid = (a + b) / 2u;
        if lt64(m, cum(mid + 1u)) {
            b = mid;
        } else {
            a = mid + 1u;
        }
    }
    let w0 = cum(a);
    let span = sub64(cum(a + 1u), w0);
    var inside = sub64(m, w0);
    if lt64(m, w0) {
        inside = vec2<u32>(0u, 0u);
    }
    var q = vec2<u32>(0u, 0u);
    if lt64(inside, span) {
        q = fraction64(inside, span);
    } else if span.x != 0u || span.y != 0u {
        q = vec2<u32>(0xffffffffu, 0xffffffffu);
    }
    return LeafAt(a, q);
}


@compute @workgroup_size(64)
fn cs_sample(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.y * params.row + id.x;
    if k >= params.count {
        return;
    }
    // The group holding output k: the last whose first output is at most k.
    var lo = 0u;
    var hi = params.groups - 1u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if request[10u * mid] <= k {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    let g = 10u * lo;
    let j = k - request[g];
    let count = request[g + 1u];
    let key = vec2<u32>(request[g + 4u], request[g + 5u]);
    // keyed_hash(key, j) and its top 53 bits (rng.rs).
    let bits = mix64(add64(key, mul64(vec2<u32>(j, 0u), vec2<u32>(0x7f4a7c15u, 0x9e3779b9u))));
    let v = value64(j, vec2<u32>(bits.x & 0xfffff800u, bits.y), count);
    let m = add64(
        vec2<u32>(request[g + 6u], request[g + 7u]),
        mulhi64(v, vec2<u32>(request[g + 8u], request[g + 9u])),
    );
    // The first leaf of the group whose end exceeds m (the last if none).
    let found = leaf_at(m, request[g + 2u], request[g + 3u] - 1u);
    let leaf = found.leaf;
    let q = found.q;
    let info = table[params.leaves_at + 5u * leaf + 2u];
    let slot = info >> 8u;
    var p: Located;
    if (info & 128u) != 0u {
        p = full_leaf_point(leaf, q, request[params.levels_at + slot]);
    } else {
        let root = table[params.leaves_at + 5u * leaf + 3u];
        p = boundary_leaf_point(root, q, descent_levels(root, lo));
    }
    let face = table[params.tris_at + 7u * p.tri + 6u];
    sites[k] = Site(face, table[params.slots_at + slot], p.bary.yz);
}
