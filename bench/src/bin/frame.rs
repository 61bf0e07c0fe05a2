//! The frame budget: per-frame resampling plus upload into the GPU sample buffer, for
//! 10^5 and 10^6 samples, on the default scene and on the bunny, as a Markdown table:
//! `cargo run --release -p strata-bench --bin frame [-- repeats]`.
//!
//! One frame is `SampleStream::sample` (`Sampler::sample_into` into a reused vector)
//! then `SampleStream::upload` (copy into a mapped staging chunk, record and submit the
//! copy into the device buffer). Both are CPU time: the GPU's own copy runs after the
//! submit and is not waited for. Between frames (outside the timing) the device is
//! drained so each frame starts from the steady state, as behind a presented frame.
//! Medians of `repeats` frames (default 15) after two warm-up frames.
//!
//! Each scene and count runs twice: `full` as above, and `sites`, where the CPU writes
//! only 16-byte `SampleSite`s (`SampleStream::frame_sites`) and a compute pass expands
//! them into the sample buffer. `gpu` is the time of draining the device after the
//! frame (the copy, and for sites the expansion pass): on the software adapter this is
//! CPU time too; on a GPU it runs on the device after the submit (not measured here:
//! this machine has none).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use strata_systems::config::SceneConfig;
use strata_systems::gpu::headless::HeadlessTarget;
use strata_systems::gpu::{GpuContext, GpuOptions, SampleStream, SiteExpander, SplatRenderer};
use strata_systems::scene::Scene;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats = strata_bench::repeats_arg(15)?.max(1);
    let ctx = GpuContext::headless(&GpuOptions::default())?;
    let configs = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../configs");
    let mut scenes = vec![("default (genus 2)", configs.join("default.ron"))];
    match strata_bench::shared_mesh_dir() {
        Ok(_) => scenes.push((
            "stanford-bunny, 3:1",
            configs.join("stanford-bunny-anisotropic.ron"),
        )),
        Err(e) => eprintln!("skipping the bunny: {e}"),
    }
    println!(
        "Adapter: {}. Medians of {repeats} frames, ms.\n",
        ctx.adapter_summary()
    );
    println!(
        "| scene | faces | segments | N | mode | sampling | upload | sampling + upload | fastest frame | M samples/s | gpu |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    // A tiny target: only the pipelines' formats matter here.
    let target = HeadlessTarget::new(&ctx.device, 16, 16, 1)?;
    for (name, path) in scenes {
        let config = SceneConfig::load(&path)?;
        let scene = Scene::build(&config)?;
        let mut expander = SiteExpander::new(&ctx.device, &scene.sampler)?;
        for (n, sites) in [
            (100_000usize, false),
            (100_000, true),
            (1_000_000, false),
            (1_000_000, true),
        ] {
            let mut renderer = SplatRenderer::new(&ctx.device, target.format())?;
            let mut stream = SampleStream::new();
            let (mut sample, mut upload, mut total) = (Vec::new(), Vec::new(), Vec::new());
            let mut gpu = Vec::new();
            for frame in 0..repeats + 2 {
                let (sampler, seed) = (&scene.sampler, frame as u64);
                let t = if sites {
                    stream.frame_sites(
                        sampler,
                        n,
                        seed,
                        &mut expander,
                        &mut renderer,
                        &ctx.device,
                        &ctx.queue,
                    )?
                } else {
                    stream.frame(sampler, n, seed, &mut renderer, &ctx.device, &ctx.queue)?
                };
                let drain = Instant::now();
                ctx.wait_idle("draining the queue between frames")?;
                if frame >= 2 {
                    sample.push(ms(t.sample));
                    upload.push(ms(t.upload));
                    total.push(ms(t.sample + t.upload));
                    gpu.push(ms(drain.elapsed()));
                }
            }
            let fastest = total.iter().copied().fold(f64::INFINITY, f64::min);
            let total_median = median(total);
            println!(
                "| {name} | {} | {} | {n} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} | {:.2} |",
                scene.mesh.face_count(),
                scene.sampler.segments().len(),
                if sites { "sites" } else { "full" },
                median(sample),
                median(upload),
                total_median,
                fastest,
                n as f64 / total_median / 1e3,
                median(gpu),
            );
        }
    }
    Ok(())
}
