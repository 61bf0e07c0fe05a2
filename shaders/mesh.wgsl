// The mesh under the splats: flat-shaded triangles, plain grey or by segment.
// Appended to common.wgsl. Vertex buffer 0: MeshVertex (systems/src/gpu/layout.rs).

struct MeshVertex {
    @location(0) position: vec3<f32>,
    @location(1) segment: u32,
    @location(2) normal: vec3<f32>,
}

struct MeshVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) segment: u32,
}

@vertex
fn vs_mesh(v: MeshVertex) -> MeshVarying {
    var out: MeshVarying;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.segment = v.segment;
    return out;
}

@fragment
fn fs_mesh(v: MeshVarying) -> @location(0) vec4<f32> {
    var base = vec3<f32>(0.55, 0.56, 0.58);
    if frame.mesh_mode == 1u && v.segment != 0xffffffffu {
        base = segment_color(v.segment);
    }
    // Two-sided: the viewer may see the inside of an open mesh.
    var n = normalize(v.normal);
    if dot(n, frame.eye.xyz - v.world) < 0.0 {
        n = -n;
    }
    return vec4<f32>(srgb_to_linear(base) * shade(n, v.world), 1.0);
}
