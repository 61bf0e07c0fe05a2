// Non-photorealistic styles (issue 21; the paper's Figs. 1, 3, 13 and 14): every sample
// drawn as a painted stroke or an ink dot on paper. Appended to common.wgsl. Vertex
// buffer 0 holds the samples at instance rate, as for the splats; the four vertices of
// a triangle strip are a quad's corners.
//
// Order independence: every colour write uses min blending (a "darken" blend, operation
// Min with factors One), and a fragment writes white where it leaves the paper alone.
// Min is commutative and associative and the target's quantization is monotone, so
// min(quantize(a), quantize(b)) = quantize(min(a, b)) and the image is the per-channel
// minimum over the paper and every fragment whatever the order the strokes are drawn
// in: bit for bit, not just up to rounding. The mesh is drawn first into depth only
// (systems/src/gpu/npr.rs), so strokes behind the surface are depth-tested away; strokes
// never write depth, so no stroke can hide another. What min blending cannot do is glaze:
// overlapping washes do not darken each other (the darker one shows).

// Twin of strata_systems::gpu::layout::NprUniforms (112 bytes).
struct NprParams {
    // Palette stops by tone (sRGB): shadow, mid-tone, light.
    shadow: vec4<f32>,
    mid: vec4<f32>,
    light: vec4<f32>,
    // Ink of stipple dots, pencil and ink strokes (sRGB).
    ink: vec4<f32>,
    // Paper colour (sRGB).
    paper: vec4<f32>,
    // 0: stipple, 1: strokes.
    style: u32,
    // 0 acrylic, 1 crayon, 2 watercolor, 3 pencil, 4 ink.
    brush: u32,
    seed: u32,
    // Focal length in pixels (stipple dots are round on screen).
    focal_px: f32,
    // Relative spread of stroke size and of stroke colour.
    size_jitter: f32,
    hue_jitter: f32,
    // A stroke's length as a multiple of the larger spacing, its width of the smaller.
    stroke_length: f32,
    stroke_width: f32,
}

@group(0) @binding(1) var<uniform> npr: NprParams;

// PCG hash (Jarzynski and Olano 2020, "Hash functions for GPU rendering").
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A stroke's key: its sample's rank hashed with the seed, so that a stroke keeps its
// size, angle and hue from frame to frame and from one draw order to another.
fn stroke_key(index: u32) -> u32 {
    return pcg(index ^ pcg(npr.seed));
}

// Uniform in [0, 1) from a key and a stream number.
fn rand01(key: u32, stream: u32) -> f32 {
    return f32(pcg(key ^ pcg(stream + 0x9e3779b9u)) >> 8u) / 16777216.0;
}

fn lattice(c: vec2<i32>, salt: u32) -> f32 {
    let h = pcg(bitcast<u32>(c.x) ^ pcg(bitcast<u32>(c.y) ^ salt));
    return f32(h >> 8u) / 16777216.0;
}

// Value noise in [0, 1) with smoothstep interpolation between lattice points.
fn value_noise(p: vec2<f32>, salt: u32) -> f32 {
    let i = floor(p);
    let f = p - i;
    let u = f * f * (3.0 - 2.0 * f);
    let c = vec2<i32>(i);
    let a = lattice(c, salt);
    let b = lattice(c + vec2<i32>(1, 0), salt);
    let d = lattice(c + vec2<i32>(0, 1), salt);
    let e = lattice(c + vec2<i32>(1, 1), salt);
    return mix(mix(a, b, u.x), mix(d, e, u.x), u.y);
}

// Tone in [0, 1] (0 darkest): Lambert lighting from the frame's light with a little
// ambient, so that the side away from the light is not one flat colour.
fn tone(n: vec3<f32>) -> f32 {
    return 0.12 + 0.88 * max(dot(n, frame.light_dir.xyz), 0.0);
}

// The palette at tone t (sRGB): shadow to mid-tone to light.
fn palette(t: f32) -> vec3<f32> {
    if t < 0.5 {
        return mix(npr.shadow.rgb, npr.mid.rgb, 2.0 * t);
    }
    return mix(npr.mid.rgb, npr.light.rgb, 2.0 * t - 1.0);
}

// A primitive that draws nothing (clipped away).
const HIDDEN: vec4<f32> = vec4<f32>(2.0, 2.0, 2.0, 1.0);

// What a fragment writes: the stroke's colour where it covers the paper, white (no
// change under min blending) where it does not.
fn darken(color: vec3<f32>, cover: f32) -> vec4<f32> {
    return vec4<f32>(mix(vec3<f32>(1.0), color, clamp(cover, 0.0, 1.0)), 1.0);
}

// ---- Paper: a full-screen triangle.

struct PaperVarying {
    @builtin(position) clip: vec4<f32>,
}

@vertex
fn vs_paper(@builtin(vertex_index) corner: u32) -> PaperVarying {
    let uv = vec2<f32>(f32((corner << 1u) & 2u), f32(corner & 2u));
    return PaperVarying(vec4<f32>(uv * 2.0 - 1.0, 1.0, 1.0));
}

@fragment
fn fs_paper(v: PaperVarying) -> @location(0) vec4<f32> {
    let p = v.clip.xy;
    // Tooth (fine grain) and fibres (long along x), in pixels: the paper stays put.
    let tooth = value_noise(p * 0.7, 11u) * 0.6 + value_noise(p * 0.23, 12u) * 0.4;
    let fibre = value_noise(vec2<f32>(p.x * 0.04, p.y * 0.5), 13u);
    let shade = 0.94 + 0.05 * tooth + 0.03 * smoothstep(0.7, 0.95, fibre);
    return vec4<f32>(srgb_to_linear(npr.paper.rgb * min(shade, 1.0)), 1.0);
}

// ---- The mesh, depth only (its colour writes are masked off): strokes behind it fail
// the depth test.

struct MeshInput {
    @location(0) position: vec3<f32>,
    @location(1) segment: u32,
    @location(2) normal: vec3<f32>,
}

@vertex
fn vs_depth(v: MeshInput) -> @builtin(position) vec4<f32> {
    return frame.view_proj * vec4<f32>(v.position, 1.0);
}

@fragment
fn fs_depth() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}

// ---- Strokes.

struct StrokeVarying {
    @builtin(position) clip: vec4<f32>,
    // Along and across the stroke, -1 to 1.
    @location(0) q: vec2<f32>,
    @location(1) @interpolate(flat) color: vec3<f32>,
    // The stroke's own random number in [0, 1) and its tone.
    @location(2) @interpolate(flat) params: vec2<f32>,
}

// The colour of a stroke of tone t and key `key`, sRGB: the palette with a per-stroke
// hue shift for the paints, graphite grey for pencil, ink for ink.
fn stroke_color(t: f32, key: u32) -> vec3<f32> {
    let jitter = vec3<f32>(rand01(key, 4u), rand01(key, 5u), rand01(key, 6u)) * 2.0 - 1.0;
    switch npr.brush {
        case 3u: {
            return mix(npr.ink.rgb, vec3<f32>(0.45), t) * (1.0 + 0.3 * npr.hue_jitter * jitter.x);
        }
        case 4u: { return npr.ink.rgb; }
        default: {
            return clamp(palette(t) * (1.0 + npr.hue_jitter * jitter), vec3<f32>(0.0), vec3<f32>(1.0));
        }
    }
}

@vertex
fn vs_stroke(@builtin(vertex_index) corner: u32, input: SampleInput) -> StrokeVarying {
    let s = to_sample(input);
    var out: StrokeVarying;
    out.q = vec2<f32>(f32(corner & 1u), f32(corner >> 1u)) * 2.0 - 1.0;
    let n = normalize(s.normal);
    if faces_away(s, n) {
        out.clip = HIDDEN;
        return out;
    }
    // splat.wgsl's convention: semi-axis k of the ellipse lies along axis k (0 the
    // field's major axis, 1 the minor axis n x major) and spans spacing[k]. The stroke
    // runs along the axis of larger spacing (in strata the minor axis on anisotropic
    // fields: the major one is where samples are densest), so that it bridges the gap
    // to the next sample that way; its width follows the smaller spacing.
    let major = tangent_major(s.major_axis, n);
    let minor = cross(n, major);
    var along = major;
    var across = minor;
    var long_spacing = s.spacing.x;
    var short_spacing = s.spacing.y;
    if s.spacing.y > s.spacing.x {
        along = minor;
        across = -major;
        long_spacing = s.spacing.y;
        short_spacing = s.spacing.x;
    }
    let key = stroke_key(s.index);
    // A hand's variation: up to +-8 degrees of turn and the size jitter.
    let angle = (rand01(key, 1u) - 0.5) * 0.28;
    let dir = along * cos(angle) + across * sin(angle);
    let side = across * cos(angle) - along * sin(angle);
    let size = 1.0 + npr.size_jitter * (2.0 * rand01(key, 2u) - 1.0);
    let half_length = 0.5 * frame.splat_scale * npr.stroke_length * long_spacing * size;
    let half_width = min(
        0.5 * frame.splat_scale * npr.stroke_width * short_spacing * size,
        0.45 * half_length
    );
    let lift = frame.normal_offset * short_spacing;
    let world = s.position + n * lift + dir * (out.q.x * half_length) + side * (out.q.y * half_width);
    out.clip = frame.view_proj * vec4<f32>(world, 1.0);
    let t = tone(n);
    out.color = srgb_to_linear(stroke_color(t, key));
    out.params = vec2<f32>(rand01(key, 3u), t);
    return out;
}

// Distance-like measure of a stroke with rounded ends: below 1 inside (1 on the rim).
fn capsule(q: vec2<f32>, straight: f32) -> f32 {
    return length(vec2<f32>(max(abs(q.x) - straight, 0.0) / (1.0 - straight), q.y));
}

@fragment
fn fs_stroke(v: StrokeVarying) -> @location(0) vec4<f32> {
    let q = v.q;
    let r = v.params.x;
    let t = v.params.y;
    let pixel = v.clip.xy;
    let salt = npr.seed;
    // The stroke's own noise offset, so that no two strokes share a texture.
    let o = vec2<f32>(r * 61.0, r * 17.0);
    var color = v.color;
    var cover = 0.0;
    switch npr.brush {
        // Acrylic: opaque body with bristle streaks along the stroke, drier at the tail.
        case 0u: {
            let shape = 1.0 - smoothstep(0.85, 1.0, capsule(q, 0.55));
            let streak = value_noise(vec2<f32>(q.y * 7.0, q.x * 0.6) + o, salt);
            let dry = smoothstep(0.35, 1.0, q.x) * step(streak, 0.4);
            cover = shape * mix(0.75, 1.0, streak) * (1.0 - 0.8 * dry);
            color = color * (0.8 + 0.2 * streak);
        }
        // Crayon: wax catches only the paper's tooth (grain fixed to the paper), more
        // of it where the hand presses harder (darker tone).
        case 1u: {
            let ragged = capsule(q, 0.6) + 0.25 * (value_noise(q * 4.0 + o, salt) - 0.5);
            let shape = 1.0 - smoothstep(0.8, 0.95, ragged);
            let grain = 0.65 * value_noise(pixel * 0.55, salt ^ 21u) + 0.35 * value_noise(pixel * 1.7, salt ^ 22u);
            cover = shape * smoothstep(0.42, 0.52, grain + 0.18 * (1.0 - t));
        }
        // Watercolour: a light, blotchy wash with an irregular rim and wet darkened edges.
        case 2u: {
            let d = capsule(q, 0.35) + 0.3 * (value_noise(q * 2.5 + o, salt) - 0.5);
            let inside = 1.0 - smoothstep(0.92, 1.0, d);
            let edge = smoothstep(0.62, 0.97, d);
            let wash = 0.32 + 0.18 * value_noise(q * 1.5 + o.yx, salt ^ 31u);
            cover = inside * (wash + 0.5 * edge);
            color = color * (1.0 - 0.35 * edge);
        }
        // Pencil: graphite grain streaked along the stroke, lighter at both ends, pressed
        // harder (wider and fuller) where the tone is darker.
        case 3u: {
            let press = mix(1.0, 0.35, t);
            let shape = 1.0 - smoothstep(0.7 * press, press, capsule(vec2<f32>(q.x, q.y / press), 0.8));
            let grain = value_noise(pixel * 0.9, salt ^ 41u);
            let streak = value_noise(vec2<f32>(q.y * 5.0, q.x * 0.8) + o, salt ^ 42u);
            let pressure = (1.0 - 0.6 * q.x * q.x) * mix(1.0, 0.75, t);
            cover = shape * pressure * (0.35 + 0.65 * smoothstep(0.25, 0.75, 0.6 * grain + 0.4 * streak));
        }
        // Ink: a solid line tapered to points at both ends, thicker where the tone is
        // darker (hatching carries the tone).
        default: {
            let taper = pow(max(1.0 - q.x * q.x, 0.0), 0.6) * mix(1.0, 0.3, t);
            cover = 1.0 - smoothstep(taper - 0.2, taper, abs(q.y));
        }
    }
    if cover <= 0.004 {
        discard;
    }
    return darken(color, cover);
}

// ---- Stipple: a round ink dot per sample, bigger where the tone is darker (its area
// follows the darkness, so the mean ink of a region follows its tone).

struct StippleVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) q: vec2<f32>,
    @location(1) @interpolate(flat) r: f32,
}

@vertex
fn vs_stipple(@builtin(vertex_index) corner: u32, input: SampleInput) -> StippleVarying {
    let s = to_sample(input);
    var out: StippleVarying;
    out.q = vec2<f32>(f32(corner & 1u), f32(corner >> 1u)) * 2.0 - 1.0;
    let n = normalize(s.normal);
    let darkness = 1.0 - tone(n);
    if faces_away(s, n) || darkness < 0.02 {
        out.clip = HIDDEN;
        return out;
    }
    let key = stroke_key(s.index);
    let size = 1.0 + npr.size_jitter * (2.0 * rand01(key, 2u) - 1.0);
    let spacing = sqrt(max(s.spacing.x * s.spacing.y, 0.0));
    let radius_world = 0.5 * frame.splat_scale * spacing * sqrt(darkness) * size;
    let centre = s.position + n * (frame.normal_offset * min(s.spacing.x, s.spacing.y));
    let c = frame.view_proj * vec4<f32>(centre, 1.0);
    let radius_px = radius_world * npr.focal_px / max(c.w, 1e-6);
    // Below a third of a pixel a dot would only flicker in and out.
    if radius_px < 0.35 {
        out.clip = HIDDEN;
        return out;
    }
    let ndc = out.q * radius_px / (0.5 * frame.viewport);
    out.clip = vec4<f32>(c.xy + ndc * c.w, c.zw);
    out.r = rand01(key, 3u);
    return out;
}

@fragment
fn fs_stipple(v: StippleVarying) -> @location(0) vec4<f32> {
    let d = length(v.q) + 0.15 * (value_noise(v.q * 2.0 + vec2<f32>(v.r * 40.0), npr.seed) - 0.5);
    let cover = 1.0 - smoothstep(0.8, 1.0, d);
    if cover <= 0.004 {
        discard;
    }
    return darken(srgb_to_linear(npr.ink.rgb), cover);
}
