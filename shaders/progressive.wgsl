// Progressive sampling on the GPU: appended to sample.wgsl (the same bindings, tables
// and helpers). One invocation per rank maps value `rank` of the Owen-scrambled
// sequence (engine/src/sample/progressive.rs) through the cumulative measures of all
// leaves in chain order to a leaf and a fraction of it, then to a site: a full leaf by
// the continuous Hilbert map, a boundary leaf by the exact descent through its
// sub-cells (curve/boundary.rs `descend_pieces`) run here, in f32, from the leaf's
// clipped pieces and the triangles' density planes. The same site as
// Sampler::progressive_sites_of up to f32 round-off in the point: the leaf is found in
// 64-bit fixed point, the target is carried down as a 64-bit fraction of the node, and
// only the children's shares of a node are f32 (a choice can differ from the CPU's
// where the target lies within about 1e-6 of a node's measure of a cut). A coarse
// boundary leaf (flat.rs `FlatProgressive::trees`) is descended first over its tree
// of exact measures unrolled in f64, down to a frontier square from which the f32
// descent goes on.

// Pieces of the current node of a descent, in the node's unit square: corners, corner
// counts, triangles and density planes (a, b, c: density a u + b v + c, up to a
// common factor).
const MAX_PIECES: u32 = 12u;
var<private> piece_pts: array<array<vec2<f32>, 8>, 12>;
var<private> piece_n: array<u32, 12>;
var<private> piece_tri: array<u32, 12>;
var<private> piece_plane: array<vec3<f32>, 12>;
var<private> pieces: u32;
// A polygon being clipped (`src`) and the clipped one (`cut`).
var<private> src: array<vec2<f32>, 8>;
var<private> src_n: u32;
var<private> cut: array<vec2<f32>, 8>;
var<private> cut_n: u32;
// The area of the current node's pieces in its unit square and how many have area
// (`enter_node`).
var<private> node_area: f32;
var<private> node_count: u32;

fn coord(p: vec2<f32>, axis: u32) -> f32 {
    return select(p.y, p.x, axis == 0u);
}

// `src` clipped to one side of the line `coord(axis) = at` into `cut`: the side below
// (`upper` false) or above (curve/clip.rs `Poly::split_into`).
fn clip_line(axis: u32, at: f32, upper: bool) {
    cut_n = 0u;
    let n = src_n;
    if n == 0u {
        return;
    }
    var prev = src[n - 1u];
    var dp = coord(prev, axis) - at;
    for (var k = 0u; k < n; k = k + 1u) {
        let q = src[k];
        let dq = coord(q, axis) - at;
        if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
            var x = prev + (q - prev) * (dp / (dp - dq));
            if axis == 0u {
                x.x = at;
            } else {
                x.y = at;
            }
            if cut_n < 8u {
                cut[cut_n] = x;
                cut_n = cut_n + 1u;
            }
        }
        if ((upper && dq >= 0.0) || (!upper && dq <= 0.0)) && cut_n < 8u {
            cut[cut_n] = q;
            cut_n = cut_n + 1u;
        }
        prev = q;
        dp = dq;
    }
}

// `cut` becomes `src`.
fn cut_to_src() {
    src_n = cut_n;
    for (var k = 0u; k < cut_n; k = k + 1u) {
        src[k] = cut[k];
    }
}

// Stored piece `i` clipped to one side of the midline (`axis` 0: x = 0.5, 1: y = 0.5)
// into `cut`.
fn clip_half(i: u32, axis: u32, upper: bool) {
    src_n = piece_n[i];
    for (var k = 0u; k < src_n; k = k + 1u) {
        src[k] = piece_pts[i][k];
    }
    clip_line(axis, 0.5, upper);
}

// Area and measure of `cut` under `plane` (curve/clip.rs `area_moment`, boundary.rs
// `part_measure`).
fn cut_measure(plane: vec3<f32>) -> vec2<f32> {
    if cut_n < 3u {
        return vec2<f32>(0.0, 0.0);
    }
    var a2 = 0.0;
    var c = vec2<f32>(0.0, 0.0);
    for (var k = 1u; k + 1u < cut_n; k = k + 1u) {
        let cr = cross2(cut[k] - cut[0], cut[k + 1u] - cut[0]);
        a2 = a2 + cr;
        c = c + (cut[0] + cut[k] + cut[k + 1u]) * cr;
    }
    let area = 0.5 * a2;
    if !(area > 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let moment = c * (1.0 / 6.0);
    return vec2<f32>(area, max(plane.x * moment.x + plane.y * moment.y + plane.z * area, 0.0));
}

// The measures of the pieces below and above the midline along `axis`.
fn side_measures(axis: u32) -> vec2<f32> {
    var m = vec2<f32>(0.0, 0.0);
    for (var i = 0u; i < pieces; i = i + 1u) {
        clip_half(i, axis, false);
        m.x = m.x + cut_measure(piece_plane[i]).y;
        clip_half(i, axis, true);
        m.y = m.y + cut_measure(piece_plane[i]).y;
    }
    return m;
}

// Keeps of every piece its part on one side of the midline (those with area).
fn keep_side(axis: u32, upper: bool) {
    var kept = 0u;
    for (var i = 0u; i < pieces; i = i + 1u) {
        clip_half(i, axis, upper);
        if cut_measure(piece_plane[i]).x > 0.0 {
            for (var k = 0u; k < cut_n; k = k + 1u) {
                piece_pts[kept][k] = cut[k];
            }
            piece_n[kept] = cut_n;
            piece_tri[kept] = piece_tri[i];
            piece_plane[kept] = piece_plane[i];
            kept = kept + 1u;
        }
    }
    pieces = kept;
}

// The 64-bit fraction of `s` in [0, 1] (all ones for 1).
fn share64(s: f32) -> vec2<u32> {
    if s >= 1.0 {
        return vec2<u32>(0xffffffffu, 0xffffffffu);
    }
    let x = max(s, 0.0) * 4294967296.0;
    let hi = u32(x);
    return vec2<u32>(u32((x - f32(hi)) * 4294967296.0), hi);
}

// Chooses between the first and second part of a node (curve order) with measures
// `m`, of a node of measure `whole` (their sum but at a leaf, whose measure is its
// cumulative measure's), moving the fraction `q` of the node into the chosen part
// (boundary.rs `pick`, with its clamping): 0 the first, 1 the second, 2 neither (both
// empty).
fn pick(q: ptr<function, vec2<u32>>, m: vec2<f32>, whole: f32) -> u32 {
    let ones = vec2<u32>(0xffffffffu, 0xffffffffu);
    if !(m.x > 0.0) && !(m.y > 0.0) {
        return 2u;
    }
    var a = vec2<u32>(0u, 0u);
    if m.x > 0.0 {
        a = share64(m.x / whole);
        if lt64(*q, a) || !(m.y > 0.0) {
            *q = select(ones, fraction64(*q, a), lt64(*q, a));
            return 0u;
        }
    }
    let r = sub64(*q, a);
    let b = share64(m.y / whole);
    *q = select(ones, fraction64(r, b), lt64(r, b));
    return 1u;
}

// The `f64` whose bits are `w` (low word first) as an `f32` scaled by `2^scale`
// (non-negative finite values).
fn f64_scaled(w: vec2<u32>, scale: i32) -> f32 {
    let e = i32((w.y >> 20u) & 0x7ffu);
    if e == 0 {
        return 0.0;
    }
    let mant = 1.0 + f32(w.y & 0xfffffu) * exp2(-20.0) + f32(w.x) * exp2(-52.0);
    return ldexp(mant, e - 1023 + scale);
}

// The point location of `uv` among the current pieces' triangles (point_location
// over a private list).
fn locate_among_pieces(uv: vec2<f32>) -> Located {
    var best = -3.4028235e38;
    var best_t = piece_tri[0];
    var best_b = vec3<f32>(1.0, 0.0, 0.0);
    for (var i = 0u; i < pieces; i = i + 1u) {
        let t = piece_tri[i];
        let p0 = tri_corner(t, 0u);
        let e1 = tri_corner(t, 1u) - p0;
        let e2 = tri_corner(t, 2u) - p0;
        let d = uv - p0;
        let det = cross2(e1, e2);
        let s1 = cross2(d, e2);
        let s2 = cross2(e1, d);
        if s1 >= 0.0 && s2 >= 0.0 && s1 + s2 <= det {
            let inv = 1.0 / det;
            let b = vec3<f32>(1.0 - s1 * inv - s2 * inv, s1 * inv, s2 * inv);
            if b.x >= 0.0 {
                return Located(t, b);
            }
        }
    }
    for (var i = 0u; i < pieces; i = i + 1u) {
        let t = piece_tri[i];
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

// The point at the fraction `q` of the current pieces' measure (a boundary sub-cell
// at `origin`, side `size`, where the descent ended): the piece holding it and the
// point at the rest in it by area (boundary.rs `place_in_sub_cell`).
fn place_in_current(q: vec2<u32>, origin: vec2<f32>, size: f32) -> Located {
    var total = 0.0;
    for (var i = 0u; i < pieces; i = i + 1u) {
        total = total + piece_measure(i);
    }
    var rest = (f32(q.y) + f32(q.x) * exp2(-32.0)) * exp2(-32.0) * total;
    var chosen = pieces;
    var chosen_m = 0.0;
    var chosen_rest = 0.0;
    for (var i = 0u; i < pieces; i = i + 1u) {
        let m = piece_measure(i);
        if !(m > 0.0) {
            continue;
        }
        chosen = i;
        chosen_m = m;
        chosen_rest = rest;
        if rest < m {
            break;
        }
        rest = rest - m;
    }
    if chosen < pieces {
        for (var k = 0u; k < piece_n[chosen]; k = k + 1u) {
            poly[k] = piece_pts[chosen][k];
        }
        let f = min(chosen_rest / chosen_m, 1.0);
        let p = point_at(piece_n[chosen], split_fraction(share64(f)));
        if p.z > 0.0 {
            let tri = piece_tri[chosen];
            return clamped_onto(tri, barycentric(tri, origin + p.xy * size));
        }
    }
    return locate_among_pieces(origin + vec2<f32>(0.5 * size));
}

// The measure of piece `i` as it stands.
fn piece_measure(i: u32) -> f32 {
    cut_n = piece_n[i];
    for (var k = 0u; k < cut_n; k = k + 1u) {
        cut[k] = piece_pts[i][k];
    }
    return cut_measure(piece_plane[i]).y;
}

// A boundary leaf's pieces (its descent tree's root: `n` pieces from word `first`, in
// the leaf's unit square) and the leaf's square (`origin`, side `size`, in the unit
// square of the segment).
struct Leaf {
    first: u32,
    n: u32,
    origin: vec2<f32>,
    size: f32,
}

// The density plane of piece `i` of `leaf` in the unit square of the node at `lo`,
// side `size`, of the leaf's unit square (up to a common factor), from the density at
// its triangle's first corner.
fn node_plane(leaf: Leaf, i: u32, lo: vec2<f32>, size: f32) -> vec3<f32> {
    let t = table[leaf.first + 20u * i];
    let pw = params.planes_at + 3u * t;
    let g = vec3<f32>(tf(pw), tf(pw + 1u), tf(pw + 2u));
    let d = leaf.origin + lo * leaf.size - tri_corner(t, 0u);
    let s = leaf.size * size;
    return vec3<f32>(g.x * s, g.y * s, g.z + g.x * d.x + g.y * d.y);
}

// Piece `i` of `leaf` clipped to the node at `lo`, side `size`, of the leaf's unit
// square, into `src` in the node's unit square.
fn piece_in_node(leaf: Leaf, i: u32, lo: vec2<f32>, size: f32) {
    let at = leaf.first + 20u * i;
    src_n = min(table[at + 1u], 8u);
    for (var k = 0u; k < src_n; k = k + 1u) {
        src[k] = vec2<f32>(tf(at + 4u + 2u * k), tf(at + 5u + 2u * k));
    }
    if size < 1.0 {
        clip_line(0u, lo.x, true);
        cut_to_src();
        clip_line(0u, lo.x + size, false);
        cut_to_src();
        clip_line(1u, lo.y, true);
        cut_to_src();
        clip_line(1u, lo.y + size, false);
        cut_to_src();
    }
    for (var k = 0u; k < src_n; k = k + 1u) {
        src[k] = (src[k] - lo) / size;
    }
}

// Stores the pieces of `leaf` inside its node at `lo`, side `size`, in the node's
// unit square, and their area in `node_area`. A leaf has at most MAX_PIECES pieces:
// the sampler refuses the progressive order for tables with more
// (gpu/sample/progressive.rs).
fn enter_node(leaf: Leaf, lo: vec2<f32>, size: f32) {
    pieces = 0u;
    node_area = 0.0;
    node_count = 0u;
    for (var i = 0u; i < min(leaf.n, MAX_PIECES); i = i + 1u) {
        piece_in_node(leaf, i, lo, size);
        cut_n = src_n;
        for (var k = 0u; k < src_n; k = k + 1u) {
            cut[k] = src[k];
        }
        let plane = node_plane(leaf, i, lo, size);
        let am = cut_measure(plane);
        if !(am.x > 0.0) {
            continue;
        }
        node_area = node_area + am.x;
        node_count = node_count + 1u;
        for (var k = 0u; k < cut_n; k = k + 1u) {
            piece_pts[pieces][k] = cut[k];
        }
        piece_n[pieces] = cut_n;
        piece_tri[pieces] = table[leaf.first + 20u * i];
        piece_plane[pieces] = plane;
        pieces = pieces + 1u;
    }
}

// Rescales the stored pieces into the unit square of their quarter `off`.
fn into_quarter(off: vec2<f32>) {
    for (var i = 0u; i < pieces; i = i + 1u) {
        for (var k = 0u; k < piece_n[i]; k = k + 1u) {
            piece_pts[i][k] = 2.0 * piece_pts[i][k] - off;
        }
        let p = piece_plane[i];
        piece_plane[i] = vec3<f32>(0.5 * p.x, 0.5 * p.y, p.z + 0.5 * (p.x * off.x + p.y * off.y));
    }
}

// The exact descent through the sub-cells of a boundary square for `levels` levels of
// quarters from the fraction `q` of its measure (boundary.rs `descend_pieces`), the
// node's pieces kept in private memory: the square is node `node` of a descent tree
// (a boundary leaf's root, or a frontier square of a progressive tree) whose nodes
// start at word `nodes_at` of the table and pieces at `pieces_at`. Its pieces (at most
// MAX_PIECES with area) are in its own unit square.
fn progressive_boundary_point(nodes_at: u32, pieces_at: u32, node: u32, q0: vec2<u32>, levels: u32) -> Located {
    let root = nodes_at + 13u * node;
    let info = table[root];
    let leaf_size = exp2(-f32(info & 31u));
    let leaf = Leaf(
        pieces_at + 20u * table[root + 3u],
        table[root + 4u],
        vec2<f32>(f32(table[root + 1u]), f32(table[root + 2u])) * leaf_size,
        leaf_size,
    );
    var lo = vec2<f32>(0.0, 0.0);
    var size = 1.0;
    var state = (info >> 5u) & 3u;
    enter_node(leaf, lo, size);
    var q = q0;
    for (var depth = 0u; depth < levels; depth = depth + 1u) {
        let c0 = hilbert_child(state, 0u);
        let c1 = hilbert_child(state, 1u);
        // Ranks 0 and 1 share a half: cut between the halves, then between the two
        // quarters of the chosen half along the other axis.
        let first_axis = select(1u, 0u, c0.x == c1.x);
        let upper_first = select(c0.y == 1u, c0.x == 1u, first_axis == 0u);
        var m = side_measures(first_axis);
        if upper_first {
            m = m.yx;
        }
        // At the leaf, shares of its measure (the descent tree root's), in the units
        // of the leaf's unit square.
        var whole = m.x + m.y;
        if depth == 0u {
            whole = f64_scaled(t64(root + 11u), 2 * i32(info & 31u));
        }
        let first = pick(&q, m, whole);
        if first == 2u {
            break;
        }
        let half_upper = (first == 0u) == upper_first;
        let rank0 = select(2u, 0u, first == 0u);
        let cq = hilbert_child(state, rank0);
        let second_axis = 1u - first_axis;
        let upper_second = select(cq.x == 1u, cq.y == 1u, first_axis == 0u);
        keep_side(first_axis, half_upper);
        var m2 = side_measures(second_axis);
        if upper_second {
            m2 = m2.yx;
        }
        let second = pick(&q, m2, m2.x + m2.y);
        if second == 2u {
            break;
        }
        let c = hilbert_child(state, rank0 + second);
        let off = vec2<f32>(f32(c.x), f32(c.y));
        size = 0.5 * size;
        lo = lo + off * size;
        state = c.z;
        keep_side(second_axis, (second == 0u) == upper_second);
        into_quarter(off);
        node_area = 0.0;
        node_count = pieces;
        for (var i = 0u; i < pieces; i = i + 1u) {
            cut_n = piece_n[i];
            for (var k = 0u; k < cut_n; k = k + 1u) {
                cut[k] = piece_pts[i][k];
            }
            node_area = node_area + cut_measure(piece_plane[i]).x;
        }
        // Full (boundary.rs: area at least 1 - 1e-9 of the square) within the f32
        // round-off of the pieces' areas summed.
        if node_area >= 1.0 - 2.5e-7 * f32(max(node_count, 4u)) {
            let local = hilbert_point(state, q, levels - depth - 1u);
            let uv = leaf.origin + (lo + local * size) * leaf.size;
            return locate_among_pieces(uv);
        }
    }
    return place_in_current(q, leaf.origin + lo * leaf.size, size * leaf.size);
}

// The root of leaf `leaf`'s progressive tree (a leaf with more than MAX_PIECES pieces
// or coarser than the frontier level, flat.rs `FlatProgressive::trees`), or all ones
// when it has none: a binary search of the list at `trees_at`.
fn progressive_tree(leaf: u32) -> u32 {
    let n = table[params.trees_at];
    var lo = 0u;
    var hi = n;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if table[params.trees_at + 1u + 2u * mid] < leaf {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    if lo < n && table[params.trees_at + 1u + 2u * lo] == leaf {
        return table[params.trees_at + 2u + 2u * lo];
    }
    return 0xffffffffu;
}

// A boundary leaf with a progressive tree: the descent replayed over the tree's exact
// measures (sample.wgsl `boundary_leaf_point`) down to a full square, the last level,
// or a frontier square (not full, no children), from which `progressive_boundary_point`
// descends the remaining levels in `f32`.
fn progressive_tree_point(root: u32, q0: vec2<u32>, levels: u32) -> Located {
    let nodes_at = params.prog_nodes_at;
    let pieces_at = params.prog_pieces_at;
    var node = root;
    var q = q0;
    var depth = 0u;
    for (var step = 0u; step < 2u * levels; step = step + 1u) {
        let s = tree_step(nodes_at, node, q);
        q = s.q;
        if s.child == 0xffffffffu {
            break;
        }
        node = s.child;
        let c = nodes_at + 13u * node;
        let kind = table[c];
        if (kind & 256u) != 0u {
            depth = depth + 1u;
            if (kind & 128u) != 0u {
                return full_node_point(nodes_at, pieces_at, node, q, levels - depth);
            }
            if depth < levels && table[c + 9u] == 0xffffffffu && table[c + 10u] == 0xffffffffu {
                return progressive_boundary_point(nodes_at, pieces_at, node, q, levels - depth);
            }
        }
    }
    return node_pieces_point(nodes_at, pieces_at, node, q);
}

// The 32-bit bijection P of the scramble (progressive.rs `Scramble::permute`).
fn permute(x0: u32) -> u32 {
    var x = x0 + params.add;
    x = x ^ (x * params.even0);
    x = x * params.odd;
    return x ^ (x * params.even1);
}

@compute @workgroup_size(64)
fn cs_progressive(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.y * params.row + id.x;
    if k >= params.count {
        return;
    }
    var rank = params.first + k;
    if params.listed != 0u {
        rank = request[params.first + k];
    }
    // Value `rank` as a 64-bit fraction: the scrambled radical inverse, the jitter's
    // top 32 bits below it.
    let jitter = mix64(add64(
        vec2<u32>(params.jitter_lo, params.jitter_hi),
        mul64(vec2<u32>(rank, 0u), vec2<u32>(0x7f4a7c15u, 0x9e3779b9u)),
    ));
    let v = vec2<u32>(jitter.y, reverseBits(permute(rank)));
    // The first leaf (chain order, all segments) whose end exceeds v.
    let found = leaf_at(v, 0u, params.leaves - 1u);
    let leaf = found.leaf;
    let q = found.q;
    let w = params.leaves_at + 5u * leaf;
    let info = table[w + 2u];
    let slot = info >> 8u;
    let levels = table[params.prog_levels_at + slot];
    var p: Located;
    if (info & 128u) != 0u {
        p = full_leaf_point(leaf, q, levels);
    } else {
        let tree = progressive_tree(leaf);
        if tree != 0xffffffffu {
            p = progressive_tree_point(tree, q, levels);
        } else {
            p = progressive_boundary_point(params.nodes_at, params.pieces_at, table[w + 3u], q, levels);
        }
    }
    let face = table[params.tris_at + 7u * p.tri + 6u];
    sites[params.out_at + k] = Site(face, table[params.slots_at + slot], p.bary.yz);
}
