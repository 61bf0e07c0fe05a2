//! Issue 21's drawing targets: the bunny as 15,000 strokes at 1280 x 960 (4x MSAA, as
//! `strata render`), per brush, plus stipple and splats for reference, as a Markdown
//! table: `cargo run --release -p strata-bench --bin strokes [-- repeats]`.
//!
//! Each time is one picture, drawn and read back into CPU memory (what `strata render`
//! does after preprocessing): `HeadlessTarget::render_npr` (or `render` for splats),
//! with the samples already uploaded and the pipelines built. Medians of `repeats`
//! pictures (default 5) after one warm-up. On the software adapter this is all CPU time.

use std::path::PathBuf;
use std::time::Instant;

use strata_systems::config::SceneConfig;
use strata_systems::gpu::headless::HeadlessTarget;
use strata_systems::gpu::{
    Brush, GpuContext, GpuOptions, NprKind, NprRenderer, NprStyle, OrbitCamera, SplatRenderer,
    SplatStyle,
};
use strata_systems::scene::Scene;

const COUNT: usize = 15_000;
const SIZE: (u32, u32) = (1280, 960);

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(5)?.max(1);
    strata_bench::shared_mesh_dir()?;
    let ctx = GpuContext::headless(&GpuOptions::default())?;
    let config =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs/stanford-bunny-smooth.ron");
    let scene = Scene::build(&SceneConfig::load(&config)?)?;
    let samples = scene.sampler.sample(COUNT, 1);
    let target = HeadlessTarget::new(&ctx.device, SIZE.0, SIZE.1, 4)?;
    let mut splats = SplatRenderer::new(&ctx.device, target.format())?;
    splats.upload(&ctx.device, &ctx.queue, &samples)?;
    splats.set_mesh(&ctx.device, &ctx.queue, &scene.mesh, None)?;
    let npr = NprRenderer::new(&ctx.device, target.format())?;
    let camera =
        OrbitCamera::default().fitted_to_mesh(&scene.mesh, SIZE.0 as f32 / SIZE.1 as f32, 1.0);
    let look = SplatStyle::default();
    println!(
        "Adapter: {}. The bunny (`stanford-bunny-smooth.ron`), {COUNT} samples, {}x{}, 4x MSAA; \
         median of {repeats} pictures drawn and read back, ms.\n",
        ctx.adapter_summary(),
        SIZE.0,
        SIZE.1
    );
    println!("| style | draw and read back (ms) | fastest (ms) |");
    println!("| --- | --- | --- |");
    let mut kinds: Vec<Option<NprKind>> = vec![None, Some(NprKind::Stipple)];
    kinds.extend(Brush::ALL.iter().map(|&b| Some(NprKind::Strokes(b))));
    for kind in kinds {
        let mut times = Vec::new();
        for i in 0..=repeats {
            let t = Instant::now();
            match kind {
                None => target.render(&ctx, &splats, &camera, &look)?,
                Some(kind) => {
                    let style = NprStyle::for_samples(kind, 1);
                    target.render_npr(&ctx, &splats, &npr, &camera, &look, &style)?
                }
            };
            if i > 0 {
                times.push(t.elapsed().as_secs_f64() * 1e3);
            }
        }
        times.sort_by(f64::total_cmp);
        let name = match kind {
            None => "splats".to_string(),
            Some(NprKind::Stipple) => "stipple".to_string(),
            Some(NprKind::Strokes(b)) => format!("strokes, {}", b.name()),
        };
        println!(
            "| {name} | {:.0} | {:.0} |",
            times[times.len() / 2],
            times[0]
        );
    }
    Ok(())
}
