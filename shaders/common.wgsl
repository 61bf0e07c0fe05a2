// Shared by every strata pipeline: the GPU twins of the Rust structs in
// systems/src/gpu/layout.rs, the per-frame uniforms, and colour helpers.
// A pipeline's module is this file followed by the pipeline's own file.

// Twin of strata_engine::sample::Sample (64 bytes). Storage layout: a vec3<f32> takes
// 12 bytes at 16-byte alignment, so each scalar after it fills the fourth lane.
struct Sample {
    position: vec3<f32>,
    face: u32,
    normal: vec3<f32>,
    segment: u32,
    major_axis: vec3<f32>,
    index: u32,
    bary: vec2<f32>,
    spacing: vec2<f32>,
}

// Twin of strata_systems::gpu::layout::FrameUniforms (176 bytes).
struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    light_dir: vec4<f32>,
    base_color: vec4<f32>,
    log_density_range: vec2<f32>,
    viewport: vec2<f32>,
    splat_scale: f32,
    color_mode: u32,
    footprint: u32,
    mesh_mode: u32,
    normal_offset: f32,
    // Bit 0: level of detail on; bit 1: back faces get multiplier 0.
    lod_flags: u32,
    // The factor of the samples' spacings: sqrt(expanded base / base).
    lod_spacing: f32,
    _pad0: u32,
    // Base count, reference area (pixels^2 per unit area), clamp, focal length (pixels).
    lod: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

// sRGB-encoded colour to linear (render targets are *Srgb formats, which encode back).
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return pow(c, vec3<f32>(2.2));
}

// The segment hues of systems/src/atlas.rs (golden-ratio hue steps), lifted to
// 60 + 195 c as in `strata segment`'s coloured mesh; sRGB.
fn segment_color(id: u32) -> vec3<f32> {
    let hue = fract(f32(id) * 0.618034) * 6.0;
    let x = 1.0 - abs(hue % 2.0 - 1.0);
    var c: vec3<f32>;
    switch u32(hue) {
        case 0u: { c = vec3<f32>(1.0, x, 0.0); }
        case 1u: { c = vec3<f32>(x, 1.0, 0.0); }
        case 2u: { c = vec3<f32>(0.0, 1.0, x); }
        case 3u: { c = vec3<f32>(0.0, x, 1.0); }
        case 4u: { c = vec3<f32>(x, 0.0, 1.0); }
        default: { c = vec3<f32>(1.0, 0.0, x); }
    }
    return (vec3<f32>(60.0) + 195.0 * c) / 255.0;
}

// Viridis through five of its published stops, t in [0, 1]; sRGB.
fn viridis(t: f32) -> vec3<f32> {
    let stops = array<vec3<f32>, 5>(
        vec3<f32>(0.267, 0.005, 0.329),
        vec3<f32>(0.229, 0.322, 0.546),
        vec3<f32>(0.128, 0.567, 0.551),
        vec3<f32>(0.369, 0.789, 0.383),
        vec3<f32>(0.993, 0.906, 0.144),
    );
    let x = clamp(t, 0.0, 1.0) * 4.0;
    let i = min(u32(x), 3u);
    return mix(stops[i], stops[i + 1u], x - f32(i));
}

// Ambient plus two-sided diffuse from the frame's light plus a weaker headlight.
fn shade(normal: vec3<f32>, position: vec3<f32>) -> f32 {
    let n = normalize(normal);
    let to_eye = normalize(frame.eye.xyz - position);
    let key = max(dot(n, frame.light_dir.xyz), 0.0);
    let head = max(dot(n, to_eye), 0.0);
    return 0.22 + 0.58 * key + 0.3 * head;
}

// A Sample read at instance rate from vertex buffer 0 (layout: SAMPLE_ATTRIBUTES in
// systems/src/gpu/layout.rs), by the splat and the stroke pipelines.
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

fn to_sample(i: SampleInput) -> Sample {
    return Sample(i.position, i.face, i.normal, i.segment, i.major_axis, i.index, i.bary, i.spacing);
}

// The field's major axis made a unit tangent of the plane with unit normal n (any
// tangent where the axis is missing or normal to the plane).
fn tangent_major(axis: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var major = axis - dot(axis, n) * n;
    if dot(major, major) < 1e-12 {
        major = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(n.x) > 0.9);
        major = major - dot(major, n) * n;
    }
    return normalize(major);
}

// Whether a sample faces away from the camera (dropped: a closed surface hides it).
fn faces_away(s: Sample, n: vec3<f32>) -> bool {
    return dot(n, frame.eye.xyz - s.position) <= 0.0;
}
