// Field-aligned elliptical splats (paper Figs. 4f and 12), one instanced quad per
// sample, or line glyphs along the field (hatching). Appended to common.wgsl. Vertex buffer 0 holds the samples at instance rate
// (layout: SAMPLE_ATTRIBUTES in systems/src/gpu/layout.rs); the four vertices of a
// triangle strip are the quad's corners.

struct SplatVarying {
    @builtin(position) clip: vec4<f32>,
    // Position in the ellipse's own frame, in semi-axes: |q| = 1 on the rim.
    @location(0) q: vec2<f32>,
    @location(1) @interpolate(flat) color: vec3<f32>,
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

// Level of detail (systems/src/gpu/splat.rs, SplatLod; engine/src/sample/lod.rs for
// the formula): the camera's projected area per unit surface area at p over the
// reference, clamped; 0 outside the frustum and, when asked, on back faces.
fn lod_multiplier(p: vec3<f32>, n: vec3<f32>) -> f32 {
    let clip = frame.view_proj * vec4<f32>(p, 1.0);
    let w = clip.w;
    if !(w > 0.0 && abs(clip.x) <= w && abs(clip.y) <= w && clip.z >= 0.0 && clip.z <= w) {
        return 0.0;
    }
    let to_eye = frame.eye.xyz - p;
    let d = length(to_eye);
    if !(d > 0.0) {
        return 0.0;
    }
    let c = dot(n, to_eye) / d;
    if (frame.lod_flags & 2u) != 0u && c < 0.0 {
        return 0.0;
    }
    let f = frame.lod.w;
    let area = f * f * abs(c) * d / (w * w * w);
    return min(area / frame.lod.y, frame.lod.z);
}

// A sample's fade weight clamp(N lod - rank, 0, 1) and its multiplier; (1, 1) when
// level of detail is off.
fn lod_fade(s: Sample, n: vec3<f32>) -> vec2<f32> {
    if (frame.lod_flags & 1u) == 0u {
        return vec2<f32>(1.0, 1.0);
    }
    let m = lod_multiplier(s.position, n);
    return vec2<f32>(clamp(frame.lod.x * m - f32(s.index), 0.0, 1.0), m);
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
    let lod = lod_fade(s, n);
    // Back-facing splats are dropped (clipped away), as a closed surface hides them;
    // so are those the level of detail leaves out.
    if faces_away(s, n) || lod.x <= 0.0 {
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        out.color = vec3<f32>(0.0);
        return out;
    }
    let major = tangent_major(s.major_axis, n);
    let minor = cross(n, major);
    // Spacings at the local density (lod times the base); splats grow in as they fade.
    let spacing = s.spacing * frame.lod_spacing / sqrt(lod.y);
    let radius = 0.5 * frame.splat_scale * spacing * lod.x;
    let lift = frame.normal_offset * min(spacing.x, spacing.y);
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

// Line glyphs: per sample a thin stroke through the sample along its major axis, of
// length splat_scale times the larger of its two spacings (the distance between rows
// across the field), lifted off the mesh like the splats. With the spacing along the
// field (the shorter one on anisotropic fields) strokes were dashes too short to show
// a direction; this length makes neighbouring strokes overlap into streamlines. The stroke is a quad whose width is fixed in pixels
// (GLYPH_WIDTH_PX up to a 960-pixel-high target, in proportion above), so that strokes
// stay thin lines at any distance: its two ends are projected and the quad is widened
// across their screen-space direction.
const GLYPH_WIDTH_PX: f32 = 1.6;

struct GlyphVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) color: vec3<f32>,
}

@vertex
fn vs_glyph(@builtin(vertex_index) corner: u32, input: SampleInput) -> GlyphVarying {
    let s = to_sample(input);
    var out: GlyphVarying;
    let n = normalize(s.normal);
    let lod = lod_fade(s, n);
    if faces_away(s, n) || lod.x <= 0.0 {
        out.clip = vec4<f32>(2.0, 2.0, 2.0, 1.0);
        out.color = vec3<f32>(0.0);
        return out;
    }
    let major = tangent_major(s.major_axis, n);
    let spacing = s.spacing * frame.lod_spacing / sqrt(lod.y);
    let half_length = 0.5 * frame.splat_scale * max(spacing.x, spacing.y) * lod.x;
    let centre = s.position + n * (frame.normal_offset * min(spacing.x, spacing.y));
    let a = frame.view_proj * vec4<f32>(centre - major * half_length, 1.0);
    let b = frame.view_proj * vec4<f32>(centre + major * half_length, 1.0);
    // Screen-space direction of the stroke in pixels; a stroke seen end-on is a dot.
    let pixels = 0.5 * frame.viewport;
    var along = (b.xy / b.w - a.xy / a.w) * pixels;
    if dot(along, along) < 1e-8 {
        along = vec2<f32>(1.0, 0.0);
    }
    along = normalize(along);
    let width = GLYPH_WIDTH_PX * max(frame.viewport.y / 960.0, 1.0);
    // Half the width, from pixels to normalized device coordinates.
    let offset = vec2<f32>(-along.y, along.x) * (0.5 * width) / pixels;
    let end = select(a, b, (corner & 1u) == 1u);
    let side = f32(corner >> 1u) * 2.0 - 1.0;
    out.clip = vec4<f32>(end.xy + offset * side * end.w, end.zw);
    out.color = srgb_to_linear(glyph_color(s)) * shade(n, s.position);
    return out;
}

// Strokes take the splats' colours, darkened so that they read as ink on the lit mesh.
fn glyph_color(s: Sample) -> vec3<f32> {
    return splat_color(s) * 0.3;
}

@fragment
fn fs_glyph(v: GlyphVarying) -> @location(0) vec4<f32> {
    return vec4<f32>(v.color, 1.0);
}

// The fade weight of every sample under the frame's level of detail (0: not drawn),
// as the splat pipelines compute it: the GPU's visible set, read back by
// systems/src/gpu/lod.rs to check it against the CPU's and to count what is shown.
@group(1) @binding(0) var<storage, read> lod_samples: array<Sample>;
@group(1) @binding(1) var<storage, read_write> lod_fades: array<f32>;

@compute @workgroup_size(64)
fn cs_lod_fades(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.y * (64u * 1024u) + id.x;
    if k >= arrayLength(&lod_fades) {
        return;
    }
    let s = lod_samples[k];
    lod_fades[k] = lod_fade(s, normalize(s.normal)).x;
}
