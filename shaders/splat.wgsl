// Field-aligned elliptical splats (paper Figs. 4f and 12), one instanced quad per
// sample. Appended to common.wgsl. Vertex buffer 0 holds the samples at instance rate
// (layout: SAMPLE_ATTRIBUTES in systems/src/gpu/layout.rs); the four vertices of a
// triangle strip are the quad's corners.

struct SampleInput {
    @location(0) position: vec3<f32>,
    @location(1) face: u32,
    @location(2) normal: vec3<f32>,
    @location(3) segment: u32,
    @location(4) major_axis: vec3<f32>,
    @location(5) index: u32,
    @location(6) bary: vec2<f32>,
    @location(7) spacing: vec2<f32>,
}

struct SplatVarying {
    @builtin(position) clip: vec4<f32>,
    // Position in the ellipse's own frame, in semi-axes: |q| = 1 on the rim.
    @location(0) q: vec2<f32>,
    @location(1) @interpolate(flat) color: vec3<f32>,
}

fn to_sample(i: SampleInput) -> Sample {
    return Sample(i.position, i.face, i.normal, i.segment, i.major_axis, i.index, i.bary, i.spacing);
}

fn splat_color(s: Sample) -> vec3<f32> {
    switch frame.color_mode {
        case 0u: {
            let area = max(s.spacing.x * s.spacing.y, 1e-30);
            let lo = frame.log_density_range.x;
            let hi = frame.log_density_range.y;
            return viridis((-log(area) - lo) / max(hi - lo, 1e-6));
        }
        case 1u: { return segment_color(s.segment); }
        default: { return frame.base_color.rgb; }
    }
}

@vertex
fn vs_splat(@builtin(vertex_index) corner: u32, input: SampleInput) -> SplatVarying {
    let s = to_sample(input);
    var out: SplatVarying;
    // Gaussian splats reach 1.5 semi-axes, where exp(-2 q^2) has fallen to 1%.
    var extent = 1.0;
    if frame.footprint == 1u {
        extent = 1.5;
    }
    let q = vec2<f32>(f32(corner & 1u), f32(corner >> 1u)) * 2.0 - 1.0;
    out.q = q * extent;
    let n = normalize(s.normal);
    // Back-facing splats are dropped (clipped away), as a closed surface hides them.
    if dot(n, frame.eye.xyz - s.position) <= 0.0 {
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        out.color = vec3<f32>(0.0);
        return out;
    }
    // Orthonormal tangent frame from the field's major axis, made tangent to n.
    var major = s.major_axis - dot(s.major_axis, n) * n;
    if dot(major, major) < 1e-12 {
        major = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(n.x) > 0.9);
        major = major - dot(major, n) * n;
    }
    major = normalize(major);
    let minor = cross(n, major);
    let radius = 0.5 * frame.splat_scale * s.spacing;
    let lift = frame.normal_offset * min(s.spacing.x, s.spacing.y);
    let world = s.position + n * lift + major * (out.q.x * radius.x) + minor * (out.q.y * radius.y);
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    out.color = srgb_to_linear(splat_color(s)) * shade(n, s.position);
    return out;
}

@fragment
fn fs_disc(v: SplatVarying) -> @location(0) vec4<f32> {
    let r2 = dot(v.q, v.q);
    if r2 > 1.0 {
        discard;
    }
    // A darker rim outlines each ellipse, so that shape and orientation show.
    let rim = mix(1.0, 0.45, smoothstep(0.62, 1.0, r2));
    return vec4<f32>(v.color * rim, 1.0);
}

@fragment
fn fs_gaussian(v: SplatVarying) -> @location(0) vec4<f32> {
    let r2 = dot(v.q, v.q);
    if r2 > 2.25 {
        discard;
    }
    let a = exp(-2.0 * r2);
    // Premultiplied alpha.
    return vec4<f32>(v.color * a, a);
}
