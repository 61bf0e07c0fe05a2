//! The flag table of `strata render` and `strata view` (the other commands' is in
//! `flags`). Every `render` flag is run once on a small scene into a 64x48 PNG on
//! whatever GPU adapter wgpu finds (lavapipe in CI) and changes the image, its size or
//! the files written; without an adapter the render rows print a skip line, unless
//! `STRATA_REQUIRE_GPU=1`. `view` opens a window, which a headless machine cannot:
//! each of its flags is checked where it lands, in the options the window is opened
//! with (`view_options`, which needs no display); what the window then does with
//! them (size, frame count, drawing) needs a display and is not run here.

use std::path::Path;

use clap::Parser;
use strata_systems::cli::{Cli, Command, one_line, run, view_options};
use strata_systems::ecs::SamplerBackend;
use strata_systems::viewer::ViewerOptions;

/// The flags the rows below cover.
pub(crate) const COVERED: &[&str] = &[
    "render --out",
    "render -o",
    "render --width",
    "render --height",
    "render --msaa",
    "render --count",
    "render -n",
    "render --seed",
    "render --yaw",
    "render --pitch",
    "render --zoom",
    "render --fov",
    "render --color",
    "render --footprint",
    "render --glyphs",
    "render --mesh",
    "render --scale",
    "render --adapter",
    "render --lod",
    "render --lod-max",
    "render --lod-shown",
    "render --frames",
    "render --orbit",
    "render --dolly",
    "render --twist",
    "render --style",
    "render --brush",
    "render --field",
    "render --anisotropy",
    "render --density-from",
    "render --sampler",
    "view --width",
    "view --height",
    "view --frames",
    "view --count",
    "view -n",
    "view --seed",
    "view --yaw",
    "view --pitch",
    "view --zoom",
    "view --fov",
    "view --color",
    "view --footprint",
    "view --glyphs",
    "view --mesh",
    "view --scale",
    "view --adapter",
    "view --lod",
    "view --lod-max",
    "view --lod-shown",
    "view --style",
    "view --brush",
    "view --field",
    "view --anisotropy",
    "view --density-from",
    "view --sampler",
];

/// A small sphere scene with 300 samples, a unit quad and a density file over it.
fn inputs(d: &Path) {
    let scene = "(mesh: Shape(Sphere(radius: 1.0, resolution: 8)), field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 2.0, density: 1.0), sampling: (count: 300, seed: 1))";
    std::fs::write(d.join("scene.ron"), scene).expect("write");
    let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(d.join("quad.obj"), quad).expect("write");
    let field = "strata-field 1\n1 1 1 0 0\n1 1 1 0 0\n9 9 1 0 0\n9 9 1 0 0\n";
    std::fs::write(d.join("q.field"), field).expect("write");
}

/// The command line `strata args...` (`{dir}` stands for `d`).
fn argv(d: &Path, args: &[&str]) -> Vec<String> {
    let folder = d.to_str().expect("utf-8 temp path");
    std::iter::once("strata".to_owned())
        .chain(args.iter().map(|a| a.replace("{dir}", folder)))
        .collect()
}

/// Renders `input` (in `d`) into `name` with `flags` (at 64x48 unless they give a
/// width) and returns the PNG.
fn render(d: &Path, input: &str, name: &str, flags: &[&str]) -> Vec<u8> {
    render_into(d, input, name, flags);
    std::fs::read(d.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Runs `strata render` as [`render`] does, reading nothing back (with `--frames`,
/// the files are numbered).
fn render_into(d: &Path, input: &str, name: &str, flags: &[&str]) {
    let out = format!("{{dir}}/{name}");
    let input = format!("{{dir}}/{input}");
    let mut args = vec!["render", &input, "-o", &out];
    if !flags.contains(&"--width") {
        args.extend_from_slice(&["--width", "64", "--height", "48"]);
    }
    args.extend_from_slice(flags);
    let cli = Cli::try_parse_from(argv(d, &args)).unwrap_or_else(|e| panic!("{flags:?}: {e}"));
    if let Err(e) = run(cli) {
        panic!("render {flags:?}: {}", one_line(&e));
    }
}

/// A PNG's width and height, from its header.
fn png_size(png: &[u8]) -> (u32, u32) {
    assert!(png.starts_with(b"\x89PNG"), "not a PNG");
    let be = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().expect("4 bytes"));
    (be(16), be(20))
}

#[test]
fn every_render_flag_has_an_effect() {
    if crate::gpu::gpu("every_render_flag_has_an_effect").is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    inputs(d);
    // --out, -o, --width, --height: the file and its size.
    let base = render(d, "scene.ron", "base.png", &[]);
    assert_eq!(png_size(&base), (64, 48));
    let small = render(
        d,
        "scene.ron",
        "small.png",
        &["--width", "40", "--height", "30"],
    );
    assert_eq!(png_size(&small), (40, 30));
    // Each of these changes the picture.
    let changes: &[&[&str]] = &[
        &["--msaa", "1"],
        &["--count", "40"],
        &["-n", "40"],
        &["--seed", "7"],
        &["--yaw", "120"],
        &["--pitch", "-40"],
        &["--zoom", "0.6"],
        &["--fov", "60"],
        &["--color", "segment"],
        &["--footprint", "gaussian"],
        &["--glyphs"],
        &["--mesh", "none"],
        &["--scale", "0.3"],
        &["--lod"],
        &["--style", "stipple"],
        &["--style", "strokes"],
    ];
    for (k, flags) in changes.iter().enumerate() {
        let image = render(d, "scene.ron", &format!("c{k}.png"), flags);
        assert!(image != base, "{flags:?} left the image as it was");
    }
    // --count and -n are one flag.
    assert_eq!(bytes(d, "c1.png"), bytes(d, "c2.png"));
    // --brush: another brush, other strokes.
    let acrylic = render(d, "scene.ron", "acrylic.png", &["--style", "strokes"]);
    let ink = render(
        d,
        "scene.ron",
        "ink.png",
        &["--style", "strokes", "--brush", "ink"],
    );
    assert!(acrylic != ink);
    // --adapter: a name that matches the adapter in use draws (on that adapter or
    // another of the same name: Mesa's GL and Vulkan ones share it); one that matches
    // none is refused in one line that names it.
    let name = adapter_name();
    let word = name.split_whitespace().next().expect("an adapter name");
    let named = render(d, "scene.ron", "named.png", &["--adapter", word]);
    assert_eq!(png_size(&named), (64, 48));
    let cli = Cli::try_parse_from(argv(
        d,
        &[
            "render",
            "{dir}/scene.ron",
            "-o",
            "{dir}/none.png",
            "--adapter",
            "no-such-adapter-xyz",
        ],
    ))
    .expect("parses");
    let e = run(cli).expect_err("no such adapter");
    assert!(
        one_line(&e).contains("no-such-adapter-xyz"),
        "{}",
        one_line(&e)
    );
    lod_flags(d);
    mesh_flags(d);
    sampler_flags(d, &base);
}

/// `--sampler`: the GPU's compute passes draw the CPU's samples into the renderer's
/// buffer, so the picture is the CPU's (here its size and bytes; the pixels and the
/// status line that names the sampler are compared in `systems/tests/sampler.rs`,
/// which runs the binary); `auto`, the default, is the CPU on a software adapter;
/// `gpu` with `--lod` is refused in one line.
fn sampler_flags(d: &Path, base: &[u8]) {
    let cpu = render(d, "scene.ron", "cpu.png", &["--sampler", "cpu"]);
    let gpu = render(d, "scene.ron", "gpu.png", &["--sampler", "gpu"]);
    let seeded = render(
        d,
        "scene.ron",
        "gpu7.png",
        &["--sampler", "gpu", "--seed", "7"],
    );
    assert_eq!(png_size(&gpu), (64, 48));
    assert!(seeded != gpu, "--seed left the GPU's picture as it was");
    let ctx = crate::gpu::gpu("sampler flags").expect("an adapter");
    if !strata_systems::gpu::backend::is_hardware(&ctx.adapter.get_info()) {
        assert!(cpu == base, "auto is not the CPU on a software adapter");
        assert!(gpu == cpu, "the GPU's samples drew another picture");
    }
    let args = [
        "render",
        "{dir}/scene.ron",
        "-o",
        "{dir}/no.png",
        "--sampler",
        "gpu",
        "--lod",
    ];
    let cli = Cli::try_parse_from(argv(d, &args)).expect("parses");
    let e = one_line(&run(cli).expect_err("gpu with --lod"));
    assert!(e.contains("--sampler gpu does not apply with --lod"), "{e}");
}

fn bytes(d: &Path, name: &str) -> Vec<u8> {
    std::fs::read(d.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The name of the adapter wgpu picks by default.
fn adapter_name() -> String {
    let ctx = crate::gpu::gpu("adapter name").expect("an adapter");
    ctx.adapter.get_info().name
}

/// `--lod-max`, `--lod-shown`, `--frames`, `--orbit`, `--dolly`, `--twist`.
fn lod_flags(d: &Path) {
    let lod = render(d, "scene.ron", "lod.png", &["--lod", "--zoom", "0.5"]);
    for (k, flags) in [&["--lod-max", "1.5"] as &[&str], &["--lod-shown", "60"]]
        .iter()
        .enumerate()
    {
        let mut all = vec!["--lod", "--zoom", "0.5"];
        all.extend_from_slice(flags);
        let image = render(d, "scene.ron", &format!("l{k}.png"), &all);
        assert!(image != lod, "{flags:?} left the image as it was");
    }
    // Four frames: numbered files; the second frame moves with each camera path flag
    // (the twist swings with the sine of the frame's phase, zero at the ends).
    render_into(d, "scene.ron", "still.png", &["--lod", "--frames", "4"]);
    let still = bytes(d, "still_0001.png");
    assert!(d.join("still_0003.png").exists() && !d.join("still.png").exists());
    for (k, flag) in ["--orbit", "--dolly", "--twist"].iter().enumerate() {
        let value = if *flag == "--dolly" { "0.7" } else { "40" };
        render_into(
            d,
            "scene.ron",
            &format!("p{k}.png"),
            &["--lod", "--frames", "4", flag, value],
        );
        assert!(
            bytes(d, &format!("p{k}_0001.png")) != still,
            "{flag} left the second frame as it was"
        );
    }
}

/// `--field`, `--anisotropy`, `--density-from` on a mesh input.
fn mesh_flags(d: &Path) {
    let plain = render(d, "quad.obj", "quad.png", &["--yaw", "0", "--pitch", "0"]);
    let aligned = render(
        d,
        "quad.obj",
        "quad2.png",
        &[
            "--yaw",
            "0",
            "--pitch",
            "0",
            "--field",
            "direction:1,1,0",
            "--anisotropy",
            "3",
        ],
    );
    let dense = render(
        d,
        "quad.obj",
        "quad3.png",
        &[
            "--yaw",
            "0",
            "--pitch",
            "0",
            "--density-from",
            "{dir}/q.field",
        ],
    );
    assert!(plain != aligned && plain != dense);
}

/// The options `strata view args...` opens its window with.
fn view(d: &Path, args: &[&str]) -> ViewerOptions {
    let mut all = vec!["view"];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(argv(d, &all)).unwrap_or_else(|e| panic!("{args:?}: {e}"));
    let Command::View(view) = cli.command else {
        panic!("not view")
    };
    view_options(&view).unwrap_or_else(|e| panic!("view {args:?}: {}", one_line(&e)))
}

#[test]
fn every_view_flag_reaches_the_window_options() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    inputs(d);
    let scene = "{dir}/scene.ron";
    let base = view(d, &[scene]);
    assert_eq!(
        (base.size, base.max_frames, base.count, base.seed),
        ((1280, 960), None, None, None)
    );
    let o = view(
        d,
        &[
            scene, "--width", "300", "--height", "200", "--frames", "5", "--count", "77", "--seed",
            "9",
        ],
    );
    assert_eq!(
        (o.size, o.max_frames, o.count, o.seed),
        ((300, 200), Some(5), Some(77), Some(9))
    );
    assert_eq!(view(d, &[scene, "-n", "78"]).count, Some(78));
    let o = view(
        d,
        &[
            scene, "--yaw", "90", "--pitch", "-30", "--fov", "50", "--zoom", "0.5",
        ],
    );
    let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
    assert!(close(o.camera.yaw, 90f32.to_radians()));
    assert!(close(o.camera.pitch, (-30f32).to_radians()));
    assert!(close(o.camera.fov_y, 50f32.to_radians()));
    assert!(close(o.zoom, 0.5) && close(base.zoom, 1.0));
    let o = view(
        d,
        &[
            scene,
            "--color",
            "constant",
            "--footprint",
            "gaussian",
            "--mesh",
            "segments",
            "--scale",
            "0.25",
            "--adapter",
            "llvm",
        ],
    );
    let look = |o: &ViewerOptions| {
        format!(
            "{:?} {:?} {:?} {}",
            o.style.color_mode, o.style.footprint, o.style.mesh_mode, o.style.splat_scale
        )
    };
    assert_eq!(look(&base), "Density Disc Plain 0.8");
    assert_eq!(look(&o), "Constant Gaussian Segments 0.25");
    assert_eq!(o.gpu.adapter_name.as_deref(), Some("llvm"));
    // --sampler: auto by default; the choice reaches the engine's settings; gpu with
    // --lod is refused below.
    assert_eq!(base.sampler, SamplerBackend::Auto);
    for (name, want) in [
        ("cpu", SamplerBackend::Cpu),
        ("gpu", SamplerBackend::Gpu),
        ("auto", SamplerBackend::Auto),
    ] {
        assert_eq!(view(d, &[scene, "--sampler", name]).sampler, want);
    }
    assert_eq!(
        format!("{:?}", view(d, &[scene, "--glyphs"]).style.footprint),
        "Glyph"
    );
    // Level of detail.
    assert_eq!((base.lod_max, base.lod_shown), (None, None));
    let o = view(d, &[scene, "--lod"]);
    assert_eq!((o.lod_max, o.lod_shown), (Some(4.0), None));
    let o = view(
        d,
        &[scene, "--lod", "--lod-max", "2.5", "--lod-shown", "900"],
    );
    assert_eq!((o.lod_max, o.lod_shown), (Some(2.5), Some(900)));
    // Paint style and brush.
    let paint = |o: &ViewerOptions| format!("{:?} {:?}", o.paint.style, o.paint.brush);
    let stipple = view(d, &[scene, "--style", "stipple"]);
    let strokes = view(d, &[scene, "--style", "strokes", "--brush", "ink"]);
    assert!(paint(&stipple) != paint(&base) && paint(&strokes) != paint(&stipple));
    assert!(paint(&strokes).contains("Ink"), "{}", paint(&strokes));
    // A mesh input: the flags shape the scene the viewer watches.
    let watched = |args: &[&str]| {
        let o = view(d, args);
        std::fs::read_to_string(&o.scene).expect("the watched scene")
    };
    let plain = watched(&["{dir}/quad.obj"]);
    let aligned = watched(&[
        "{dir}/quad.obj",
        "--field",
        "direction:1,1,0",
        "--anisotropy",
        "3",
    ]);
    let dense = watched(&["{dir}/quad.obj", "--density-from", "{dir}/q.field"]);
    assert!(
        aligned != plain && aligned.contains("anisotropy: 3.0"),
        "{aligned}"
    );
    assert!(dense.contains("q.field") && !plain.contains("q.field"));
    // Bad values are refused before any window would open.
    for (bad, says) in [
        (&["--lod", "--lod-max", "0"] as &[&str], "--lod-max"),
        (&["--zoom", "0"], "--zoom must be a positive number"),
        (
            &["--lod", "--sampler", "gpu"],
            "--sampler gpu does not apply with --lod",
        ),
    ] {
        let mut all = vec!["view", scene];
        all.extend_from_slice(bad);
        let cli = Cli::try_parse_from(argv(d, &all)).expect("parses");
        let Command::View(v) = cli.command else {
            panic!("not view")
        };
        let e = one_line(&view_options(&v).expect_err("refused"));
        assert!(e.contains(says) && !e.contains('\n'), "{bad:?}: {e}");
    }
}
