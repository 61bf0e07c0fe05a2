//! GPU streaming and splat rendering (issue 8), on whatever adapter wgpu finds (the
//! lavapipe software adapter in CI). Without an adapter these tests print a skip line,
//! unless `STRATA_REQUIRE_GPU=1`, where they fail. The no-adapter error paths need no
//! GPU and always run.

use std::path::Path;

use glam::Vec3;
use strata_engine::fixtures::along_x_2to1_on;
use strata_engine::sample::{Sample, SampleSite};
use strata_systems::config::SceneConfig;
use strata_systems::gpu::buffers::{MIN_CAPACITY, next_capacity};
use strata_systems::gpu::context::scoped;
use strata_systems::gpu::wgpu;
use strata_systems::gpu::{
    Brush, ColorMode, Footprint, GpuContext, GpuError, GpuOptions, HeadlessTarget, MeshMode,
    NprKind, NprRenderer, NprStyle, OrbitCamera, RgbaImage, SiteExpander, SplatRenderer,
    SplatStyle, StyleChoice, StyledFrame,
};
use strata_systems::scene::Scene;

/// An open device, or `None` (after a skip line) when there is no adapter; panics
/// instead when `STRATA_REQUIRE_GPU=1`.
pub(crate) fn gpu(test: &str) -> Option<GpuContext> {
    GpuContext::headless_or_skip(test)
}

fn scene(ron: &str) -> Scene {
    let config = SceneConfig::from_ron(ron, Path::new("test.ron")).expect("test scene parses");
    Scene::build(&config).expect("test scene builds")
}

/// A unit square in the z = 0 plane with a 2:1 field along x.
const PLANE: &str = "(mesh: Shape(Plane(size: 1.0, resolution: 8)), \
     field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0))";

const BACKGROUND: [f32; 3] = [0.0, 0.0, 0.0];

fn is_background(p: [u8; 4]) -> bool {
    p[0] == 0 && p[1] == 0 && p[2] == 0
}

/// Pixel of a world point for a camera and image size (pixel centres at +0.5).
fn project(camera: &OrbitCamera, w: u32, h: u32, p: Vec3) -> (f32, f32) {
    let clip = camera.view_proj(w as f32 / h as f32) * p.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    (
        (ndc.x + 1.0) * 0.5 * w as f32,
        (1.0 - ndc.y) * 0.5 * h as f32,
    )
}

fn render(
    ctx: &GpuContext,
    scene: &Scene,
    samples: &[Sample],
    camera: &OrbitCamera,
    style: &SplatStyle,
    size: (u32, u32),
) -> RgbaImage {
    let target = HeadlessTarget::new(&ctx.device, size.0, size.1, 1).expect("target");
    let mut renderer = SplatRenderer::new(&ctx.device, target.format()).expect("pipelines");
    renderer
        .upload(&ctx.device, &ctx.queue, samples)
        .expect("upload");
    let segments = strata_systems::gpu::splat::face_segments(&scene.sampler);
    renderer
        .set_mesh(&ctx.device, &ctx.queue, &scene.mesh, Some(&segments))
        .expect("mesh");
    target
        .render(ctx, &renderer, camera, style)
        .expect("render")
}

/// A plane seen head-on: the GPU's splat pixels match a CPU rasterization of the same
/// ellipses at pixel centres, every sample's own pixel is covered, and the covered
/// fraction lies within bounds derived from the splat areas.
///
/// With a constant density the spacings satisfy `s0 s1 = A / N`, so N ellipses of
/// semi-axes `k s / 2` cover at most `pi k^2 / 4` of the area (no overlap) and, if the
/// samples were no more even than a Poisson process, `1 - exp(-pi k^2 / 4)`; stratified
/// samples overlap less than Poisson ones.
#[test]
fn splat_pixels_match_the_projected_samples() {
    let Some(ctx) = gpu("splat_pixels_match_the_projected_samples") else {
        return;
    };
    let scene = scene(PLANE);
    let samples = scene.sampler.sample(3000, 3);
    assert!(samples.iter().all(|s| s.normal[2] > 0.99));
    let (w, h) = (512, 512);
    let camera = OrbitCamera {
        yaw: 0.0,
        pitch: 0.0,
        ..OrbitCamera::framing(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 1.0, 0.0, 0.0)
    };
    let scale = 1.0f32;
    let style = SplatStyle {
        color_mode: ColorMode::Constant,
        mesh_mode: MeshMode::None,
        splat_scale: scale,
        background: BACKGROUND,
        base_color: [1.0, 1.0, 1.0],
        ..SplatStyle::default()
    };
    let image = render(&ctx, &scene, &samples, &camera, &style, (w, h));
    assert!(
        image
            .pixels
            .chunks_exact(4)
            .any(|p| !is_background([p[0], p[1], p[2], p[3]])),
        "blank image"
    );

    // The plane maps to the image by a similarity (it faces the camera).
    let (x0, y1) = project(&camera, w, h, Vec3::ZERO);
    let (x1, y0) = project(&camera, w, h, Vec3::new(1.0, 1.0, 0.0));
    let px_per_unit = (x1 - x0) / 1.0;
    assert!(((y1 - y0) - px_per_unit).abs() < 1e-3 * px_per_unit);
    let to_world =
        |px: f32, py: f32| Vec3::new((px - x0) / px_per_unit, (y1 - py) / px_per_unit, 0.0);

    // CPU reference: pixel centres inside any ellipse.
    let mut reference = vec![false; (w * h) as usize];
    for s in &samples {
        let c = Vec3::from(s.position);
        let n = Vec3::from(s.normal).normalize();
        let major = (Vec3::from(s.major_axis) - Vec3::from(s.major_axis).dot(n) * n).normalize();
        let minor = n.cross(major);
        let r = [0.5 * scale * s.spacing[0], 0.5 * scale * s.spacing[1]];
        let reach = r[0].max(r[1]) * px_per_unit + 1.0;
        let (cx, cy) = project(&camera, w, h, c);
        let (lo_x, hi_x) = (
            (cx - reach).max(0.0) as u32,
            ((cx + reach) as u32).min(w - 1),
        );
        let (lo_y, hi_y) = (
            (cy - reach).max(0.0) as u32,
            ((cy + reach) as u32).min(h - 1),
        );
        for py in lo_y..=hi_y {
            for px in lo_x..=hi_x {
                let d = to_world(px as f32 + 0.5, py as f32 + 0.5) - c;
                let (a, b) = (d.dot(major) / r[0], d.dot(minor) / r[1]);
                if a * a + b * b <= 1.0 {
                    reference[(py * w + px) as usize] = true;
                }
            }
        }
        // The sample's own pixel is a splat pixel.
        let p = image.pixel(cx as u32, cy as u32);
        assert!(
            !is_background(p),
            "no splat at sample {} ({cx}, {cy})",
            s.index
        );
    }

    // Interior of the plane (one largest spacing away from its edges).
    let margin = samples
        .iter()
        .map(|s| s.spacing[0].max(s.spacing[1]))
        .fold(0.0f32, f32::max)
        * px_per_unit;
    let (mut total, mut covered, mut agree) = (0usize, 0usize, 0usize);
    for py in (y0 + margin) as u32..(y1 - margin) as u32 {
        for px in (x0 + margin) as u32..(x1 - margin) as u32 {
            let gpu_hit = !is_background(image.pixel(px, py));
            total += 1;
            covered += usize::from(gpu_hit);
            agree += usize::from(gpu_hit == reference[(py * w + px) as usize]);
        }
    }
    let coverage = covered as f64 / total as f64;
    let agreement = agree as f64 / total as f64;
    let area = std::f64::consts::PI * f64::from(scale * scale) / 4.0;
    let (lo, hi) = (1.0 - (-area).exp(), area);
    println!(
        "coverage {coverage:.4} in [{lo:.4}, {hi:.4}] (+-0.02), agreement with the CPU rasterization {agreement:.4}"
    );
    assert!(total > 100_000, "{total} interior pixels");
    assert!(
        coverage >= lo - 0.02 && coverage <= hi + 0.02,
        "coverage {coverage}"
    );
    assert!(agreement > 0.98, "agreement {agreement}");
}

/// Changing the colour mode changes the colours of the splat pixels but not which
/// pixels they are.
#[test]
fn colour_mode_changes_the_image_not_the_coverage() {
    let Some(ctx) = gpu("colour_mode_changes_the_image_not_the_coverage") else {
        return;
    };
    let scene = scene(
        "(mesh: Shape(Plane(size: 1.0, resolution: 32)), field: Planar(density: \
         Gaussian(center: (0.5, 0.5), sigma: 0.15, peak: 8.0, base: 0.5)))",
    );
    let samples = scene.sampler.sample(4000, 1);
    let camera = OrbitCamera::framing(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 1.0, 0.2, 0.3);
    let images: Vec<RgbaImage> = [ColorMode::Density, ColorMode::Segment, ColorMode::Constant]
        .into_iter()
        .map(|color_mode| {
            let style = SplatStyle {
                color_mode,
                mesh_mode: MeshMode::None,
                background: BACKGROUND,
                log_density_range: strata_systems::gpu::layout::log_density_range(&samples),
                ..SplatStyle::default()
            };
            render(&ctx, &scene, &samples, &camera, &style, (256, 256))
        })
        .collect();
    let mask = |im: &RgbaImage| -> Vec<bool> {
        im.pixels
            .chunks_exact(4)
            .map(|p| !is_background([p[0], p[1], p[2], p[3]]))
            .collect()
    };
    let m0 = mask(&images[0]);
    let splat_pixels = m0.iter().filter(|&&m| m).count();
    assert!(splat_pixels > 256 * 256 / 10, "{splat_pixels} splat pixels");
    for (i, a) in images.iter().enumerate() {
        assert_eq!(mask(a), m0, "mode {i} covers other pixels");
        for b in &images[i + 1..] {
            let differing = a
                .pixels
                .chunks_exact(4)
                .zip(b.pixels.chunks_exact(4))
                .zip(&m0)
                .filter(|((p, q), m)| **m && p != q)
                .count();
            assert!(
                differing * 2 > splat_pixels,
                "only {differing} of {splat_pixels} splat pixels changed colour"
            );
        }
    }
}

/// Gaussian splats reach further than discs (1.5 semi-axes) and are softer; the plain
/// mesh fills the plane's whole image.
#[test]
fn footprints_and_mesh_modes_draw_what_they_say() {
    let Some(ctx) = gpu("footprints_and_mesh_modes_draw_what_they_say") else {
        return;
    };
    let scene = scene(PLANE);
    let samples = scene.sampler.sample(1500, 5);
    let (w, h) = (256, 256);
    let camera = OrbitCamera {
        yaw: 0.0,
        pitch: 0.0,
        ..OrbitCamera::framing(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 1.0, 0.0, 0.0)
    };
    let base = SplatStyle {
        color_mode: ColorMode::Constant,
        mesh_mode: MeshMode::None,
        splat_scale: 0.6,
        background: BACKGROUND,
        base_color: [1.0, 1.0, 1.0],
        ..SplatStyle::default()
    };
    let (x0, y1) = project(&camera, w, h, Vec3::ZERO);
    let (x1, y0) = project(&camera, w, h, Vec3::new(1.0, 1.0, 0.0));
    let inside = |x: u32, y: u32| {
        (x as f32) > x0 + 2.0
            && (x as f32) < x1 - 2.0
            && (y as f32) > y0 + 2.0
            && (y as f32) < y1 - 2.0
    };
    let stats = |im: &RgbaImage| {
        let (mut covered, mut total, mut brightness) = (0usize, 0usize, 0f64);
        for y in 0..h {
            for x in 0..w {
                if inside(x, y) {
                    let p = im.pixel(x, y);
                    total += 1;
                    if !is_background(p) {
                        covered += 1;
                        brightness += f64::from(p[0]);
                    }
                }
            }
        }
        (
            covered as f64 / total as f64,
            brightness / covered.max(1) as f64,
        )
    };
    let disc = render(&ctx, &scene, &samples, &camera, &base, (w, h));
    let gaussian = render(
        &ctx,
        &scene,
        &samples,
        &camera,
        &SplatStyle {
            footprint: strata_systems::gpu::Footprint::Gaussian,
            ..base
        },
        (w, h),
    );
    let with_mesh = render(
        &ctx,
        &scene,
        &samples,
        &camera,
        &SplatStyle {
            mesh_mode: MeshMode::Plain,
            ..base
        },
        (w, h),
    );
    let (disc_cover, disc_bright) = stats(&disc);
    let (gauss_cover, gauss_bright) = stats(&gaussian);
    let (mesh_cover, _) = stats(&with_mesh);
    println!(
        "disc: coverage {disc_cover:.3}, mean red {disc_bright:.1}; gaussian: {gauss_cover:.3}, {gauss_bright:.1}; with mesh: {mesh_cover:.3}"
    );
    assert!(gauss_cover > disc_cover, "{gauss_cover} <= {disc_cover}");
    assert!(
        gauss_bright < disc_bright,
        "{gauss_bright} >= {disc_bright}"
    );
    assert_eq!(mesh_cover, 1.0);
}

/// Glyphs draw the field's direction: on the plane with its field along x, seen
/// head-on, the glyph image is not blank, differs from the disc image of the same
/// samples, covers less (thin strokes, not ellipses), and its covered pixels run along
/// x: covered pairs 4 pixels apart (more than a stroke's width, less than its length)
/// are far more often side by side than one above the other.
#[test]
fn glyphs_draw_thin_strokes_along_the_field() {
    let Some(ctx) = gpu("glyphs_draw_thin_strokes_along_the_field") else {
        return;
    };
    let scene = scene(PLANE);
    let samples = scene.sampler.sample(400, 9);
    let (w, h) = (256, 256);
    let camera = OrbitCamera {
        yaw: 0.0,
        pitch: 0.0,
        ..OrbitCamera::framing(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 1.0, 0.0, 0.0)
    };
    let discs = SplatStyle {
        color_mode: ColorMode::Constant,
        mesh_mode: MeshMode::None,
        background: BACKGROUND,
        base_color: [1.0, 1.0, 1.0],
        ..SplatStyle::default()
    };
    let glyphs = SplatStyle {
        footprint: Footprint::Glyph,
        ..discs
    };
    let disc_image = render(&ctx, &scene, &samples, &camera, &discs, (w, h));
    let glyph_image = render(&ctx, &scene, &samples, &camera, &glyphs, (w, h));
    let covered = |im: &RgbaImage, x: u32, y: u32| !is_background(im.pixel(x, y));
    let coverage = |im: &RgbaImage| {
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| covered(im, x, y))
            .count()
    };
    let (disc_cover, glyph_cover) = (coverage(&disc_image), coverage(&glyph_image));
    const GAP: u32 = 4;
    let (mut along, mut across) = (0usize, 0usize);
    for y in 0..h - GAP {
        for x in 0..w - GAP {
            if covered(&glyph_image, x, y) {
                along += usize::from(covered(&glyph_image, x + GAP, y));
                across += usize::from(covered(&glyph_image, x, y + GAP));
            }
        }
    }
    println!(
        "discs cover {disc_cover} pixels, glyphs {glyph_cover}; covered pairs {GAP} pixels apart: {along} along x, {across} along y"
    );
    assert!(glyph_cover > 0, "the glyph image is blank");
    assert_ne!(glyph_image.pixels, disc_image.pixels);
    assert!(glyph_cover < disc_cover, "{glyph_cover} >= {disc_cover}");
    assert!(along > 4 * across, "{along} along x, {across} across");
}

/// Uploads of changing sizes: the buffer follows the capacity policy and reads back
/// exactly the CPU samples every time.
#[test]
fn sample_buffer_reads_back_and_resizes() {
    let Some(ctx) = gpu("sample_buffer_reads_back_and_resizes") else {
        return;
    };
    let scene = scene(PLANE);
    let mut buffer = strata_systems::gpu::GpuSampleBuffer::new(&ctx.device).expect("buffer");
    assert_eq!(buffer.capacity(), MIN_CAPACITY);
    let mut capacity = MIN_CAPACITY;
    let mut reallocations = 0;
    for (frame, n) in [10usize, 5000, 100, 70_000, 70_000, 40_000, 0, 3]
        .into_iter()
        .enumerate()
    {
        let samples = scene.sampler.sample(n, frame as u64);
        buffer
            .upload(&ctx.device, &ctx.queue, &samples)
            .expect("upload");
        let next = next_capacity(capacity, n);
        reallocations += usize::from(next != capacity);
        capacity = next;
        assert_eq!(buffer.capacity(), capacity, "frame {frame}, n {n}");
        assert!(buffer.capacity() >= n.max(MIN_CAPACITY));
        assert_eq!(buffer.reallocations(), reallocations);
        assert_eq!(buffer.len(), n);
        let back = buffer
            .read_back(&ctx.device, &ctx.queue)
            .expect("read back");
        assert!(
            back == samples,
            "frame {frame}: GPU buffer differs from the CPU samples"
        );
    }
    // 10 -> 1024, 5000 -> 8192, 100 -> 1024, 70000 -> 131072, kept, kept, 0 -> 1024.
    assert_eq!(reallocations, 4);
}

/// Sites expanded on the GPU are the CPU's samples up to `f32` round-off: the same
/// face, segment, barycentric coordinates and index, positions within 1e-5 of the
/// bounding-box diagonal, normals and spacings within 1e-4, the same major axis up to
/// sign (where the field is anisotropic; an isotropic tensor has none), on a surface
/// with singularities, with chains (3 samples) and without, across buffer growth.
#[test]
fn expanded_sites_match_the_cpu_samples() {
    let Some(ctx) = gpu("expanded_sites_match_the_cpu_samples") else {
        return;
    };
    let scene = scene(
        "(mesh: Shape(Genus2(size: 2.0, resolution: 3)), \
         field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0))",
    );
    let sampler = &scene.sampler;
    let (lo, hi) = sampler.mesh().bounds();
    let diagonal = (hi - lo).length() as f32;
    let mut expander = SiteExpander::new(&ctx.device, sampler).expect("expander");
    let mut buffer = strata_systems::gpu::GpuSampleBuffer::new(&ctx.device).expect("buffer");
    for n in [3usize, 20_000, 100] {
        let cpu = sampler.sample(n, 5);
        let mut sites = vec![SampleSite::default(); n];
        sampler.sample_sites_into(5, &mut sites);
        expander
            .expand(&ctx.device, &ctx.queue, &sites, &mut buffer)
            .expect("expand");
        let gpu = buffer
            .read_back(&ctx.device, &ctx.queue)
            .expect("read back");
        assert_eq!(gpu.len(), n);
        let mut anisotropic = 0;
        for (k, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
            let at = format!("n {n}, sample {k}");
            assert_eq!(
                (g.face, g.segment, g.bary, g.index),
                (c.face, c.segment, c.bary, c.index),
                "{at}"
            );
            let d = Vec3::from(g.position).distance(Vec3::from(c.position));
            assert!(d <= 1e-5 * diagonal, "{at}: position {d} away");
            let dn = Vec3::from(g.normal).distance(Vec3::from(c.normal));
            assert!(dn <= 1e-4, "{at}: normal {dn} away");
            for (a, b) in g.spacing.iter().zip(&c.spacing) {
                assert!((a - b).abs() <= 1e-4 * b, "{at}: spacing {a} vs {b}");
            }
            if c.spacing[1] > 1.01 * c.spacing[0] {
                anisotropic += 1;
                let dot = Vec3::from(g.major_axis).dot(Vec3::from(c.major_axis));
                assert!(dot.abs() >= 1.0 - 1e-4, "{at}: major axes at dot {dot}");
            }
        }
        assert!(
            anisotropic * 2 > n,
            "n {n}: only {anisotropic} anisotropic samples"
        );
    }
}

/// Uploads without waiting: several frames in a row need no poll in between, and the
/// last one is what the buffer holds.
#[test]
fn uploads_do_not_wait_for_earlier_frames() {
    let Some(ctx) = gpu("uploads_do_not_wait_for_earlier_frames") else {
        return;
    };
    let scene = scene(PLANE);
    let mut stream = strata_systems::gpu::SampleStream::new();
    let target = HeadlessTarget::new(&ctx.device, 64, 64, 1).expect("target");
    let mut renderer = SplatRenderer::new(&ctx.device, target.format()).expect("pipelines");
    for seed in 0..8 {
        let t = stream
            .frame(
                &scene.sampler,
                20_000,
                seed,
                &mut renderer,
                &ctx.device,
                &ctx.queue,
            )
            .expect("frame");
        assert_eq!(t.count, 20_000);
    }
    let back = renderer
        .samples()
        .read_back(&ctx.device, &ctx.queue)
        .expect("read back");
    assert!(back == stream.samples());
    assert!(back == scene.sampler.sample(20_000, 7));
}

/// A validation error inside an error scope comes back as a typed error, not a panic.
#[test]
fn validation_errors_are_typed() {
    let Some(ctx) = gpu("validation_errors_are_typed") else {
        return;
    };
    // MAP_READ may only be combined with COPY_DST without a special feature.
    let result = scoped(&ctx.device, "making an invalid buffer", || {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::VERTEX,
            mapped_at_creation: false,
        })
    });
    match result {
        Err(GpuError::Device { operation, message }) => {
            assert_eq!(operation, "making an invalid buffer");
            assert!(!message.is_empty());
        }
        other => panic!("expected a device error, got {other:?}"),
    }
    // Out-of-range targets are refused before wgpu sees them.
    assert!(matches!(
        HeadlessTarget::new(&ctx.device, 0, 16, 1),
        Err(GpuError::Limit { .. })
    ));
}

/// No backend at all: a typed error, no panic.
#[test]
fn no_backend_is_a_typed_error() {
    let result = GpuContext::headless(&GpuOptions {
        backends: Some(wgpu::Backends::empty()),
        adapter_name: None,
    });
    match result {
        Err(e @ GpuError::NoAdapter { .. }) => {
            let text = e.to_string();
            assert!(text.contains("no GPU adapter"), "{text}");
            assert!(!text.contains('\n'));
        }
        other => panic!("expected NoAdapter, got {other:?}"),
    }
}

/// An adapter name that matches nothing: a typed error listing what there is.
#[test]
fn unknown_adapter_name_is_a_typed_error() {
    let result = GpuContext::headless(&GpuOptions {
        backends: None,
        adapter_name: Some("no-such-adapter-4f1c".into()),
    });
    assert!(
        matches!(&result, Err(GpuError::AdapterNotFound { name, .. }) if name == "no-such-adapter-4f1c"),
        "{result:?}"
    );
}

/// `strata render` end to end: a PNG of the requested size.
#[test]
fn render_command_writes_a_png() {
    use clap::Parser;
    let Some(ctx) = gpu("render_command_writes_a_png") else {
        return;
    };
    println!("adapter: {}", ctx.adapter_summary());
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("plane.ron");
    std::fs::write(&scene, PLANE).expect("scene written");
    let out = dir.path().join("plane.png");
    let cli = strata_systems::cli::Cli::try_parse_from([
        "strata".as_ref(),
        "render".as_ref(),
        scene.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--width".as_ref(),
        "200".as_ref(),
        "--height".as_ref(),
        "120".as_ref(),
        "-n".as_ref(),
        "500".as_ref(),
        "--color".as_ref(),
        "segment".as_ref(),
    ])
    .expect("arguments parse");
    strata_systems::cli::run(cli).expect("render succeeds");
    let bytes = std::fs::read(&out).expect("PNG written");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    assert_eq!((be(&bytes[16..20]), be(&bytes[20..24])), (200, 120));
}

/// `strata render` without a usable adapter fails with one line and writes nothing.
#[test]
fn render_without_an_adapter_fails_in_one_line() {
    use clap::Parser;
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("image.png");
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/default.ron");
    let cli = strata_systems::cli::Cli::try_parse_from([
        "strata".as_ref(),
        "render".as_ref(),
        config.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--adapter".as_ref(),
        "no-such-adapter-4f1c".as_ref(),
    ])
    .expect("arguments parse");
    let error = strata_systems::cli::run(cli).expect_err("no adapter matches");
    let line = strata_systems::cli::one_line(&error);
    assert!(
        line.starts_with("opening a GPU: no GPU adapter named like"),
        "{line}"
    );
    assert!(!line.contains('\n'), "{line}");
    assert!(!out.exists());
}

/// The per-frame ECS system: the engine samples into the mesh entity's buffer and
/// `upload_samples` streams it to the GPU whenever it was rewritten (and only then).
#[test]
fn ecs_upload_system_streams_the_engine_samples() {
    use bevy_ecs::prelude::{Schedule, World};
    use std::sync::Arc;
    use strata_engine::mesh::shapes;
    use strata_engine::surface::SurfaceOptions;
    use strata_systems::ecs::{self, MeshBundle, SampleBuffer, SamplingSettings};
    use strata_systems::gpu::GpuSplats;

    let Some(ctx) = gpu("ecs_upload_system_streams_the_engine_samples") else {
        return;
    };
    let format = HeadlessTarget::new(&ctx.device, 8, 8, 1)
        .expect("target")
        .format();
    let renderer = SplatRenderer::new(&ctx.device, format).expect("pipelines");
    let mut world = World::new();
    let mut schedule = Schedule::default();
    ecs::register(&mut world, &mut schedule);
    strata_systems::gpu::upload::register(&mut schedule);
    world.insert_resource(GpuSplats::new(ctx, renderer));

    let mesh = Arc::new(shapes::sphere(1.0, 3).expect("sphere"));
    let field = Arc::new(along_x_2to1_on(&mesh));
    let e = world
        .spawn(MeshBundle::new(
            mesh,
            field,
            SurfaceOptions::default(),
            3000,
            5,
        ))
        .id();
    let check = |world: &mut World, n: usize, uploads: u64| {
        let cpu = world
            .get::<SampleBuffer>(e)
            .expect("buffer")
            .samples
            .clone();
        assert_eq!(cpu.len(), n);
        let gpu = world.resource::<GpuSplats>();
        assert!(gpu.error.is_none(), "{:?}", gpu.error);
        assert_eq!(gpu.last.uploads, uploads);
        let back = gpu
            .renderer
            .samples()
            .read_back(&gpu.ctx.device, &gpu.ctx.queue)
            .expect("read back");
        assert!(back == cpu, "GPU buffer differs from the engine's samples");
    };
    // The first build runs off the frame; settle waits for it.
    assert!(ecs::settle(
        &mut world,
        &mut schedule,
        std::time::Duration::from_secs(120)
    ));
    world.clear_trackers();
    check(&mut world, 3000, 1);
    // Nothing changed: no resampling, no upload.
    schedule.run(&mut world);
    world.clear_trackers();
    check(&mut world, 3000, 1);
    // A new count: resampled and uploaded (the buffer grows).
    world
        .get_mut::<SamplingSettings>(e)
        .expect("settings")
        .count = 70_000;
    schedule.run(&mut world);
    world.clear_trackers();
    check(&mut world, 70_000, 2);
    // And shrinks again.
    world
        .get_mut::<SamplingSettings>(e)
        .expect("settings")
        .count = 10;
    schedule.run(&mut world);
    world.clear_trackers();
    check(&mut world, 10, 3);
}

/// A sphere lit from the side under a 2.5:1 field: tone varies across it, strokes have a
/// clear direction.
const SPHERE: &str = "(mesh: Shape(Sphere(radius: 1.0, resolution: 8)), \
     field: Constant(direction: (0.0, 1.0, 0.2), anisotropy: 2.5, density: 1.0))";

/// Every stroke and stipple look: stipple, then strokes with each brush.
fn npr_kinds() -> Vec<NprKind> {
    std::iter::once(NprKind::Stipple)
        .chain(Brush::ALL.into_iter().map(NprKind::Strokes))
        .collect()
}

fn npr_name(kind: NprKind) -> String {
    match kind {
        NprKind::Stipple => "stipple".into(),
        NprKind::Strokes(b) => format!("strokes/{}", b.name()),
    }
}

/// `samples` of `scene` drawn as `kind` at 256 x 256 (one sample per pixel).
fn render_npr(ctx: &GpuContext, scene: &Scene, samples: &[Sample], kind: NprKind) -> RgbaImage {
    let target = HeadlessTarget::new(&ctx.device, 256, 256, 1).expect("target");
    let mut splats = SplatRenderer::new(&ctx.device, target.format()).expect("pipelines");
    splats
        .upload(&ctx.device, &ctx.queue, samples)
        .expect("upload");
    splats
        .set_mesh(&ctx.device, &ctx.queue, &scene.mesh, None)
        .expect("mesh");
    let npr = NprRenderer::new(&ctx.device, target.format()).expect("stroke pipelines");
    let camera = OrbitCamera::default().fitted_to_mesh(&scene.mesh, 1.0, 1.0);
    target
        .render_npr(
            ctx,
            &splats,
            &npr,
            &camera,
            &SplatStyle::default(),
            &NprStyle::new(kind, 7),
        )
        .expect("render")
}

/// The luminance (0 to 1) of an sRGB pixel's bytes, weighted on the encoded values.
fn luminance(p: &[u8]) -> f64 {
    (0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])) / 255.0
}

/// Mean and standard deviation of the luminance of the middle half (each way) of
/// `image`, where the test sphere is, and the mean absolute difference of luminance
/// between horizontal neighbours there (how fine the texture is).
fn luminance_stats(image: &RgbaImage) -> [f64; 3] {
    let (w, h) = (image.width, image.height);
    let (xs, ys) = (w / 4..3 * w / 4, h / 4..3 * h / 4);
    let lum = |x, y| luminance(&image.pixel(x, y));
    let all: Vec<f64> = ys
        .clone()
        .flat_map(|y| xs.clone().map(move |x| (x, y)))
        .map(|(x, y)| lum(x, y))
        .collect();
    let n = all.len() as f64;
    let mean = all.iter().sum::<f64>() / n;
    let var = all.iter().map(|l| (l - mean) * (l - mean)).sum::<f64>() / n;
    let steps: Vec<f64> = ys
        .flat_map(|y| xs.clone().skip(1).map(move |x| (x, y)))
        .map(|(x, y)| (lum(x, y) - lum(x - 1, y)).abs())
        .collect();
    let gradient = steps.iter().sum::<f64>() / steps.len() as f64;
    [mean, var.sqrt(), gradient]
}

/// Stipple and every brush draw a picture (paper plus marks that are clearly darker
/// than the paper), and splats, stipple and the five brushes all differ from each
/// other in mean or spread of luminance.
#[test]
fn every_style_and_brush_renders_a_distinct_picture() {
    let Some(ctx) = gpu("every_style_and_brush_renders_a_distinct_picture") else {
        return;
    };
    let scene = scene(SPHERE);
    let samples = scene.sampler.sample(4000, 3);
    let camera = OrbitCamera::default().fitted_to_mesh(&scene.mesh, 1.0, 1.0);
    let splat_style = SplatStyle {
        mesh_mode: MeshMode::None,
        ..SplatStyle::default()
    };
    let mut stats = vec![(
        "splats".to_string(),
        luminance_stats(&render(
            &ctx,
            &scene,
            &samples,
            &camera,
            &splat_style,
            (256, 256),
        )),
    )];
    for kind in npr_kinds() {
        let image = render_npr(&ctx, &scene, &samples, kind);
        let name = npr_name(kind);
        // The paper is the lightest thing there; marks are at least 0.15 darker.
        let stats_here = luminance_stats(&image);
        let [mean, spread, gradient] = stats_here;
        let corner = luminance(&image.pixel(0, 0));
        let marked = image
            .pixels
            .chunks_exact(4)
            .filter(|p| luminance(p) < corner - 0.15)
            .count();
        let share = marked as f64 / f64::from(image.width * image.height);
        println!(
            "{name}: luminance mean {mean:.3}, sd {spread:.3}, gradient {gradient:.3}, paper {corner:.3}, {:.1}% marked",
            100.0 * share
        );
        assert!(corner > 0.8, "{name}: paper luminance {corner}");
        assert!(
            share > 0.01,
            "{name}: only {share} of the pixels are marked"
        );
        stats.push((name, stats_here));
    }
    // Any two differ by more than 0.01 in the mean, the spread or the texture.
    for (i, (a, sa)) in stats.iter().enumerate() {
        for (b, sb) in &stats[i + 1..] {
            let d = (0..3).map(|k| (sa[k] - sb[k]).abs()).fold(0.0, f64::max);
            assert!(d > 0.01, "{a} and {b} look alike: {sa:.4?} and {sb:.4?}");
        }
    }
}

/// A stroke or stipple picture is a function of the samples and the seed: the same
/// image twice, and the same image, bit for bit, with the samples drawn in reverse
/// order (min blending and depth-tested-not-written strokes make the order irrelevant).
#[test]
fn npr_pictures_are_deterministic_and_independent_of_draw_order() {
    let Some(ctx) = gpu("npr_pictures_are_deterministic_and_independent_of_draw_order") else {
        return;
    };
    let scene = scene(SPHERE);
    let samples = scene.sampler.sample(3000, 5);
    let reversed: Vec<Sample> = samples.iter().rev().copied().collect();
    let hash = |image: &RgbaImage| {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        image.pixels.hash(&mut h);
        h.finish()
    };
    for kind in npr_kinds() {
        let name = npr_name(kind);
        let first = render_npr(&ctx, &scene, &samples, kind);
        let again = render_npr(&ctx, &scene, &samples, kind);
        assert_eq!(hash(&first), hash(&again), "{name}: two renders differ");
        let backwards = render_npr(&ctx, &scene, &reversed, kind);
        let differing = first
            .pixels
            .chunks_exact(4)
            .zip(backwards.pixels.chunks_exact(4))
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differing, 0,
            "{name}: {differing} pixels change with the draw order"
        );
    }
}

/// `strata render --style strokes --brush crayon` writes a PNG whose pixels are mostly
/// paper-light, unlike the dark splat background.
#[test]
fn render_command_draws_strokes() {
    use clap::Parser;
    let Some(_ctx) = gpu("render_command_draws_strokes") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("sphere.ron");
    std::fs::write(&scene, SPHERE).expect("scene written");
    for (style, brush) in [("strokes", Some("crayon")), ("stipple", None)] {
        let out = dir.path().join(format!("{style}.png"));
        let mut args: Vec<std::ffi::OsString> = vec!["strata".into(), "render".into()];
        args.extend([scene.clone().into(), "--out".into(), out.clone().into()]);
        let size = [
            "--width", "160", "--height", "120", "-n", "800", "--style", style,
        ];
        args.extend(size.iter().map(Into::into));
        if let Some(b) = brush {
            args.extend(["--brush".into(), b.into()]);
        }
        let cli = strata_systems::cli::Cli::try_parse_from(args).expect("arguments parse");
        strata_systems::cli::run(cli).expect("render succeeds");
        let bytes = std::fs::read(&out).expect("PNG written");
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{style}");
    }
}

/// Unknown styles and brushes, and a brush without `--style strokes`, fail before any
/// GPU work with one line naming the valid choices (no GPU needed).
#[test]
fn bad_style_or_brush_fails_in_one_line() {
    use clap::Parser;
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/default.ron");
    for (extra, expected) in [
        (
            &["--style", "oil"][..],
            "--style must be one of splats, stipple, strokes, not 'oil'",
        ),
        (
            &["--style", "strokes", "--brush", "sponge"][..],
            "--brush must be one of acrylic, crayon, watercolor, pencil, ink, not 'sponge'",
        ),
        (
            &["--brush", "ink"][..],
            "--brush needs --style strokes (not --style splats)",
        ),
        (
            &["--style", "stipple", "--brush", "ink"][..],
            "--brush needs --style strokes (not --style stipple)",
        ),
    ] {
        let mut args: Vec<std::ffi::OsString> = vec!["strata".into(), "render".into()];
        args.push(config.clone().into());
        args.push("--out".into());
        args.push("never-written.png".into());
        args.extend(extra.iter().map(Into::into));
        let cli = strata_systems::cli::Cli::try_parse_from(args).expect("arguments parse");
        let error = strata_systems::cli::run(cli).expect_err("bad choice");
        let line = strata_systems::cli::one_line(&error);
        assert_eq!(line, expected);
    }
    assert!(!Path::new("never-written.png").exists());
}

/// What `strata view` draws into a window whose surface is `Bgra8UnormSrgb` (the usual
/// swapchain format): [`StyledFrame`] with pipelines built for that format, into an
/// offscreen target of that format. Min blending works there too, and every style
/// gives the same picture, byte for byte once read back with red and blue swapped to
/// RGBA, as `strata render`'s `Rgba8UnormSrgb` target.
#[test]
fn window_format_draws_the_same_picture_as_render() {
    let Some(ctx) = gpu("window_format_draws_the_same_picture_as_render") else {
        return;
    };
    let scene = scene(SPHERE);
    let samples = scene.sampler.sample(2000, 7);
    let camera = OrbitCamera::default().fitted_to_mesh(&scene.mesh, 1.0, 1.0);
    let look = SplatStyle::default();
    let bgra = wgpu::TextureFormat::Bgra8UnormSrgb;
    let target = HeadlessTarget::with_format(&ctx.device, 256, 256, 1, bgra).expect("target");
    assert_eq!(target.format().color, bgra);
    let mut splats = SplatRenderer::new(&ctx.device, target.format()).expect("pipelines");
    splats
        .upload(&ctx.device, &ctx.queue, &samples)
        .expect("upload");
    splats
        .set_mesh(&ctx.device, &ctx.queue, &scene.mesh, None)
        .expect("mesh");
    // Built for splats: the stroke pipelines come with the first stroke frame.
    let mut frame = StyledFrame::new(&ctx.device, target.format(), StyleChoice::default())
        .expect("splat frame");
    let kinds = std::iter::once(None).chain(npr_kinds().into_iter().map(Some));
    for kind in kinds {
        frame.choice = StyleChoice::new(kind);
        let name = frame.choice.to_string();
        let window = target
            .draw_and_read(&ctx, |encoder, t| {
                frame.encode(
                    &ctx.device,
                    &ctx.queue,
                    encoder,
                    t,
                    &camera,
                    &splats,
                    &look,
                    7,
                )
            })
            .expect("window-format frame");
        let rendered = match kind {
            Some(kind) => render_npr(&ctx, &scene, &samples, kind),
            None => render(&ctx, &scene, &samples, &camera, &look, (256, 256)),
        };
        let differing = window
            .pixels
            .chunks_exact(4)
            .zip(rendered.pixels.chunks_exact(4))
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(differing, 0, "{name}: {differing} pixels differ");
        let paper = window.pixel(0, 0);
        if kind.is_some() {
            // Paper, not a blue-for-red swap of it: the read-back is RGBA.
            assert!(paper[0] >= paper[2], "{name}: corner {paper:?}");
        }
    }
}

/// `strata view` takes `--style` and `--brush` as `strata render` does and refuses the
/// same mistakes with the same line, before opening any window or GPU (no display
/// needed); `--lod` with stipple or strokes is refused by both.
#[test]
fn view_refuses_bad_style_or_brush_as_render_does() {
    use clap::Parser;
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/default.ron");
    for (extra, expected) in [
        (
            &["--style", "oil"][..],
            "--style must be one of splats, stipple, strokes, not 'oil'",
        ),
        (
            &["--brush", "ink"][..],
            "--brush needs --style strokes (not --style splats)",
        ),
        (
            &["--style", "strokes", "--brush", "sponge"][..],
            "--brush must be one of acrylic, crayon, watercolor, pencil, ink, not 'sponge'",
        ),
        (
            &["--style", "stipple", "--lod"][..],
            "--style stipple does not support --lod yet",
        ),
    ] {
        for command in ["view", "render"] {
            let mut args: Vec<std::ffi::OsString> = vec!["strata".into(), command.into()];
            args.push(config.clone().into());
            if command == "render" {
                args.extend(["--out".into(), "never-written.png".into()]);
            }
            args.extend(extra.iter().map(Into::into));
            let cli = strata_systems::cli::Cli::try_parse_from(args).expect("arguments parse");
            let error = strata_systems::cli::run(cli).expect_err("bad choice");
            let line = strata_systems::cli::one_line(&error);
            assert_eq!(line, expected, "strata {command} {extra:?}");
        }
    }
    assert!(!Path::new("never-written.png").exists());
}
