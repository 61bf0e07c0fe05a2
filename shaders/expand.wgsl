// Expands sample sites (face, segment, barycentric coordinates: 16 bytes each, as
// Sampler::sample_sites_into writes them) into full Sample records on the GPU, with the
// formulas of the CPU record (engine/src/sample/faces.rs) in f32. Appended to
// common.wgsl. One invocation per site; a 2-D dispatch of 64-wide workgroups (rows of
// `row` invocations) so that counts beyond 65535 workgroups fit.

// Twin of strata_engine::sample::SampleSite (16 bytes).
struct Site {
    face: u32,
    segment: u32,
    bary: vec2<f32>,
}

// Twin of strata_systems::gpu::expand::ExpandParams (32 bytes). The mesh table holds,
// as 32-bit words: vertex positions (3 f32 each) from word 0, vertex normals (3 f32)
// from `normals_at`, face normals (3 f32) from `face_normals_at`, triangles (3 u32)
// from `triangles_at`, face-frame corner tensors (9 f32) from `tensors_at`.
struct ExpandParams {
    count: u32,
    // sqrt(M / N): the spacing scale of this sample count.
    scale: f32,
    normals_at: u32,
    face_normals_at: u32,
    triangles_at: u32,
    tensors_at: u32,
    // Invocations per dispatch row.
    row: u32,
    // cs_expand_ranked: the first entry expanded (entries first..count).
    first: u32,
}

@group(1) @binding(0) var<uniform> params: ExpandParams;
@group(1) @binding(1) var<storage, read> sites: array<Site>;
@group(1) @binding(2) var<storage, read> mesh: array<u32>;
@group(1) @binding(3) var<storage, read_write> expanded: array<Sample>;
// cs_expand_ranked only: the progressive rank of each site, written as its index.
@group(1) @binding(4) var<storage, read> ranks: array<u32>;

fn word_f(i: u32) -> f32 {
    return bitcast<f32>(mesh[i]);
}

fn vec3_at(base: u32, i: u32) -> vec3<f32> {
    let w = base + 3u * i;
    return vec3<f32>(word_f(w), word_f(w + 1u), word_f(w + 2u));
}

// glam's `any_orthonormal_vector` (a unit vector orthogonal to unit `n`).
fn any_orthonormal(n: vec3<f32>) -> vec3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

// Positive and finite (the CPU's `usable`).
fn usable(len2: f32) -> bool {
    return len2 > 0.0 && len2 < 3.4028235e38;
}

@compute @workgroup_size(64)
fn cs_expand(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.y * params.row + id.x;
    if k >= params.count {
        return;
    }
    expanded[k] = expand_site(sites[k], k);
}

// Expands entries first..count of a resident pool of sites whose ranks are in
// `ranks` (systems/src/gpu/lod.rs): only the entries a pool update appended.
@compute @workgroup_size(64)
fn cs_expand_ranked(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = params.first + id.y * params.row + id.x;
    if k >= params.count {
        return;
    }
    expanded[k] = expand_site(sites[k], ranks[k]);
}

// The Sample record of `site` with index `index`.
fn expand_site(site: Site, index: u32) -> Sample {
    let face = site.face;
    let t = params.triangles_at + 3u * face;
    let i = mesh[t];
    let j = mesh[t + 1u];
    let l = mesh[t + 2u];
    let b = vec3<f32>(1.0 - site.bary.x - site.bary.y, site.bary.x, site.bary.y);
    let p0 = vec3_at(0u, i);
    let p1 = vec3_at(0u, j);
    let p2 = vec3_at(0u, l);
    let position = p0 * b.x + p1 * b.y + p2 * b.z;
    let n = vec3_at(params.face_normals_at, face);
    let vn = vec3_at(params.normals_at, i) * b.x + vec3_at(params.normals_at, j) * b.y
        + vec3_at(params.normals_at, l) * b.z;
    let vn2 = dot(vn, vn);
    var normal = n;
    if usable(vn2) {
        normal = vn * inverseSqrt(vn2);
    }
    // The tensor in the face frame, interpolated; its eigenvalues l1 >= l2.
    let w = params.tensors_at + 9u * face;
    let ta = word_f(w) * b.x + word_f(w + 3u) * b.y + word_f(w + 6u) * b.z;
    let tb = word_f(w + 1u) * b.x + word_f(w + 4u) * b.y + word_f(w + 7u) * b.z;
    let tc = word_f(w + 2u) * b.x + word_f(w + 5u) * b.y + word_f(w + 8u) * b.z;
    let mean = 0.5 * (ta + tc);
    let h = 0.5 * (ta - tc);
    let r = sqrt(h * h + tb * tb);
    let l1 = mean + r;
    let l2 = mean - r;
    var v = vec2<f32>(tb, l1 - ta);
    if ta >= tc {
        v = vec2<f32>(l1 - tc, tb);
    }
    // The major axis: v in the frame e1 = u / |u|, e2 = n x e1.
    let u = p1 - p0;
    let len2 = dot(v, v);
    let s = len2 * dot(u, u);
    var major: vec3<f32>;
    if usable(s) {
        major = (u * v.x + cross(n, u) * v.y) * inverseSqrt(s);
    } else {
        var e1 = any_orthonormal(n);
        if usable(dot(u, u)) {
            e1 = u * inverseSqrt(dot(u, u));
        }
        var vu = vec2<f32>(1.0, 0.0);
        if usable(len2) {
            vu = v * inverseSqrt(len2);
        }
        major = e1 * vu.x + cross(n, e1) * vu.y;
    }
    let spacing = vec2<f32>(
        params.scale / sqrt(l1),
        params.scale / sqrt(max(l2, 1.17549435e-38)),
    );
    return Sample(position, face, normal, site.segment, major, index, site.bary, spacing);
}
