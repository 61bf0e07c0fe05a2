//! A frame of the ECS engine with GPU sampling ([`strata_systems::gpu::backend`]) costs
//! the CPU nothing per sample: a counting global allocator around the system's, and
//! the engine's schedule run with `sampler: Gpu` on whatever adapter wgpu opens (the
//! software adapter in CI; skipped without one unless `STRATA_REQUIRE_GPU=1`).
//!
//! Checked: the resample runs on the GPU into the renderer's buffer (the CPU's sample
//! buffer stays empty, the GPU's records are the CPU's samples); a frame that resamples
//! allocates the same blocks and bytes at 10^3 and 10^5 samples (a fixed cost, none
//! per sample), at most the measured 120 blocks and 24 KiB, of which the GPU sampler
//! adds nothing beyond the engine's request table and wgpu's staging of its two
//! buffer writes (the rest is wgpu's command encoder, passes and submission, the
//! error scopes and bevy_ecs's schedule; both passes keep their bind groups while
//! their buffers and the count stay; each part is counted on its own and printed); it uploads only its parameters (the two uniforms and the per-segment
//! request table, written with `queue.write_buffer` into persistent buffers, against
//! 16 bytes per sample for sites and 64 for records), and a frame that repeats count
//! and seed neither recomputes nor uploads the request; a frame with nothing to redraw allocates
//! nothing beyond what bevy_ecs's schedule allocates by itself (the same as with the
//! CPU's sampler). The binary holds this one test, so no other test allocates while
//! it counts.

use std::alloc::System;
use std::io::Write;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};
use strata_engine::field::FieldSpec;
use strata_engine::mesh::shapes;
use strata_engine::sample::{Sample, Sampler};
use strata_engine::surface::SurfaceOptions;
use strata_systems::ecs::{
    self, EngineSettings, MeshBundle, MeshSampler, SampleBuffer, SamplerBackend, SamplingSettings,
};
use strata_systems::gpu::backend::{self, GpuSampling};
use strata_systems::gpu::{GpuContext, GpuSampler, GpuSplats, HeadlessTarget, SplatRenderer};

/// The system allocator, counting allocations, reallocations and bytes.
#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Allocations (reallocations included) and bytes allocated (a reallocation's growth)
/// while `f` runs.
fn counted(f: impl FnOnce()) -> (usize, usize) {
    let region = Region::new(GLOBAL);
    f();
    let change = region.change();
    (
        change.allocations + change.reallocations,
        change.bytes_allocated,
    )
}

/// An engine world streaming into a headless renderer, sampling on the GPU.
struct Engine {
    world: World,
    schedule: Schedule,
    mesh: Entity,
}

impl Engine {
    fn new(ctx: GpuContext) -> Self {
        let target = HeadlessTarget::new(&ctx.device, 64, 48, 1).expect("target");
        let renderer = SplatRenderer::new(&ctx.device, target.format()).expect("renderer");
        let mut world = World::new();
        let mut schedule = Schedule::default();
        ecs::register(&mut world, &mut schedule);
        strata_systems::gpu::upload::register(&mut schedule);
        backend::register(&mut world, &mut schedule);
        world.insert_resource(GpuSplats::new(ctx, renderer));
        *world.resource_mut::<EngineSettings>() = EngineSettings {
            sampler: SamplerBackend::Gpu,
            sample_every_update: true,
            ..EngineSettings::default()
        };
        let mesh = Arc::new(shapes::sphere(1.0, 4).expect("sphere"));
        let field = FieldSpec::Constant {
            direction: [1.0, 0.3, 0.2],
            anisotropy: 2.0,
            density: 1.0,
        };
        let field = Arc::new(field.build(&mesh).expect("field"));
        let options = SurfaceOptions::default();
        let mesh = world
            .spawn(MeshBundle::new(mesh, field, options, 1000, 1))
            .id();
        schedule.run(&mut world);
        let settled = ecs::settle(
            &mut world,
            &mut schedule,
            std::time::Duration::from_secs(120),
        );
        assert!(settled, "the build did not finish");
        Self {
            world,
            schedule,
            mesh,
        }
    }

    fn set(&mut self, count: usize, seed: u64) {
        let mut s = self
            .world
            .get_mut::<SamplingSettings>(self.mesh)
            .expect("sampling settings");
        s.count = count;
        s.seed = seed;
    }

    /// One update, counted; the device is polled afterwards (outside the count), as a
    /// host's present or poll does.
    fn frame(&mut self) -> (usize, usize) {
        self.world.resource_mut::<ecs::StageStats>().clear();
        let cost = counted(|| self.schedule.run(&mut self.world));
        let gpu = self.world.resource::<GpuSplats>();
        gpu.ctx.wait_idle("a frame").expect("device");
        cost
    }

    fn gpu_frames(&self) -> u64 {
        self.world.resource::<GpuSampling>().last.frames
    }
}

/// Allocations per resampling frame at most (measured: see the assertion).
const FRAME_ALLOCATIONS: usize = 120;
/// Bytes allocated per resampling frame at most.
const FRAME_BYTES: usize = 24 * 1024;

/// The engine's GPU sampler and the mesh's CPU sampler it was built from.
fn samplers(engine: &Engine) -> (&GpuSampler, &Sampler) {
    let state = engine.world.resource::<GpuSampling>();
    let gpu = state.sampler().expect("a GPU sampler");
    let sampler = engine
        .world
        .get::<MeshSampler>(engine.mesh)
        .and_then(|s| s.0.as_ref())
        .expect("sampler");
    (gpu, sampler)
}

/// Allocations and bytes of the engine's request table for `(count, seed)` alone
/// (`FlatSampler::request`, what a resampling frame computes on the CPU).
fn request_cost(engine: &Engine, count: usize, seed: u64) -> (usize, usize) {
    let (gpu, sampler) = samplers(engine);
    let flat = gpu.flat();
    counted(|| {
        let request = flat.request(sampler, count as u64, seed).expect("request");
        std::hint::black_box(&request);
    })
}

/// Allocations and bytes of wgpu's part of a frame without strata: a command encoder
/// with two compute passes (the sites pass and the expansion) recorded empty, and
/// its submission (the most of a resampling frame's allocations; `wait_idle`
/// outside the count, as in a frame).
fn bare_submit(engine: &Engine) -> (usize, usize) {
    let ctx = &engine.world.resource::<GpuSplats>().ctx;
    let (device, queue) = (&ctx.device, &ctx.queue);
    let cost = counted(|| {
        let mut encoder = device.create_command_encoder(&Default::default());
        for _ in 0..2 {
            drop(encoder.begin_compute_pass(&Default::default()));
        }
        queue.submit([encoder.finish()]);
    });
    ctx.wait_idle("an empty submission").expect("device");
    cost
}

/// Allocations and bytes of wgpu's `queue.write_buffer` for what a resample uploads
/// besides the expansion's uniforms (the request table and the sites pass's
/// uniforms: two writes of `bytes` in all; wgpu stages each write).
fn bare_writes(engine: &Engine, bytes: usize) -> (usize, usize) {
    let ctx = &engine.world.resource::<GpuSplats>().ctx;
    let (device, queue) = (&ctx.device, &ctx.queue);
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 4096,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let data = vec![0u8; bytes.next_multiple_of(4).clamp(128, 4096)];
    let cost = counted(|| {
        queue.write_buffer(&buffer, 0, &data[..64]);
        queue.write_buffer(&buffer, 64, &data[64..]);
    });
    queue.submit([]);
    ctx.wait_idle("writes").expect("device");
    cost
}

/// Bytes one GPU resample of `count` samples writes with `queue.write_buffer`: the
/// request table of per-segment counts and levels (its words, as the GPU sampler
/// writes them), the sites pass's uniforms (64 bytes) and the expansion's (32 bytes).
fn upload_bytes(engine: &Engine, count: usize, seed: u64) -> usize {
    let (gpu, sampler) = samplers(engine);
    let request = gpu
        .flat()
        .request(sampler, count as u64, seed)
        .expect("request");
    let words = std::mem::size_of_val(request.groups.as_slice()) / 4
        + request.levels.len()
        + 2 * request.thresholds.len();
    4 * words
        + std::mem::size_of::<strata_systems::gpu::sample::SampleParams>()
        + std::mem::size_of::<strata_systems::gpu::expand::ExpandParams>()
}

#[test]
fn gpu_frames_cost_the_cpu_nothing_per_sample() {
    let Some(ctx) = GpuContext::headless_or_skip("gpu_frames_cost_the_cpu_nothing_per_sample")
    else {
        return;
    };
    let mut engine = Engine::new(ctx);
    let mut cost = Vec::new();
    for count in [1000, 100_000] {
        // Warm up: the buffers grow to the count, the pipelines' caches fill.
        for seed in 0..3 {
            engine.set(count, seed);
            engine.frame();
        }
        let before = engine.gpu_frames();
        let mut worst = (0, 0);
        for seed in 10..20 {
            engine.set(count, seed);
            let (a, b) = engine.frame();
            worst = (worst.0.max(a), worst.1.max(b));
        }
        assert_eq!(
            engine.gpu_frames() - before,
            10,
            "every frame resampled on the GPU"
        );
        let upload = upload_bytes(&engine, count, 19);
        let record = engine.world.resource::<GpuSampling>().last.record;
        // The engine's request (per-segment counts, `FlatSampler::request`) alone, and
        // a frame that repeats the last count and seed: the GPU sampler neither
        // recomputes nor uploads the request then, so what it allocates is the
        // schedule's, wgpu's (command encoder, pass, error scopes, submission) and the
        // expansion's bind group.
        let request = request_cost(&engine, count, 19);
        let bare = bare_submit(&engine);
        let writes = bare_writes(&engine, upload);
        let before = engine.gpu_frames();
        let repeat = (0..3).map(|_| engine.frame()).max().expect("frames");
        assert_eq!(engine.gpu_frames() - before, 3, "repeated frames resampled");
        let _ = writeln!(
            std::io::stderr(),
            "{count} samples: per frame at most {} allocations, {} bytes allocated, {upload} bytes uploaded; of these the engine's request {} allocations ({} bytes); a frame repeating count and seed {} allocations ({} bytes), {} bytes uploaded; wgpu alone, an encoder with two empty compute passes submitted, {} allocations ({} bytes), two buffer writes of the request's bytes {} allocations; the last took the CPU {:.3} ms to record and submit",
            worst.0,
            worst.1,
            request.0,
            request.1,
            repeat.0,
            repeat.1,
            std::mem::size_of::<strata_systems::gpu::expand::ExpandParams>(),
            bare.0,
            bare.1,
            writes.0,
            record.as_secs_f64() * 1e3
        );
        cost.push((worst, upload, request, repeat, writes));
    }
    let [
        (small, small_up, small_request, small_repeat, small_writes),
        (large, large_up, large_request, large_repeat, large_writes),
    ] = cost[..]
    else {
        unreachable!()
    };
    // A fixed cost: no allocation or byte that grows with the count (10^5 sites alone
    // would be 1.6 MB).
    assert!(
        large.0 <= small.0 + 8 && large.1 <= small.1 + 8192,
        "per frame: {small:?} at 10^3, {large:?} at 10^5"
    );
    assert!(large.1 < 64 * 1024, "{large:?}");
    // Tight bounds at the numbers measured on the software adapter (lavapipe, wgpu
    // 30): a frame that resamples allocates at most 80 blocks and 16 KiB (the
    // engine's request a handful of them, bevy_ecs's schedule 12, the rest wgpu's
    // encoder, pass, error scopes and submission and the expansion's bind group), and
    // the GPU sampler itself adds nothing beyond the request: a frame repeating count
    // and seed allocates what a resampling frame does less the request.
    for (frame, request, repeat, writes) in [
        (small, small_request, small_repeat, small_writes),
        (large, large_request, large_repeat, large_writes),
    ] {
        assert!(
            frame.0 <= FRAME_ALLOCATIONS && frame.1 <= FRAME_BYTES,
            "{frame:?}"
        );
        assert!(
            frame.0 <= repeat.0 + request.0 + writes.0 + 1,
            "the GPU sampler allocated beyond the engine's request: {frame:?} per frame, {repeat:?} repeating, {request:?} in the request"
        );
        // A repeated request is neither recomputed nor uploaded again.
        assert!(
            repeat.0 + request.0 <= frame.0,
            "a frame repeating count and seed recomputed the request: {repeat:?}, {frame:?}"
        );
    }
    // Only parameters: the uniforms and the per-segment table, nothing per sample.
    assert!(large_up <= small_up + 1024 && large_up < 16 * 100_000 / 100);
    // The CPU drew nothing; the renderer's buffer holds the CPU's samples.
    let buffer = engine
        .world
        .get::<SampleBuffer>(engine.mesh)
        .expect("buffer");
    assert!(buffer.samples.is_empty() && buffer.generation == 0);
    let gpu = engine.world.resource::<GpuSplats>();
    let records = gpu
        .renderer
        .samples()
        .read_back(&gpu.ctx.device, &gpu.ctx.queue)
        .expect("read back");
    let sampler = engine
        .world
        .get::<MeshSampler>(engine.mesh)
        .and_then(|s| s.0.as_ref())
        .expect("sampler");
    let want: Vec<Sample> = sampler.sample(100_000, 19);
    assert_eq!(records.len(), want.len());
    let far = records
        .iter()
        .zip(&want)
        .filter(|(r, w)| {
            glam::Vec3::from(r.position).distance(w.position.into()) > 1e-4
                || (r.face, r.segment) != (w.face, w.segment)
        })
        .count();
    assert!(far * 10_000 <= want.len(), "{far} samples differ");
    // Nothing to redraw: nothing drawn, and no allocation beyond the schedule's own
    // (bevy_ecs's `Schedule::run` allocates a few blocks even for an empty schedule):
    // the same as the same engine's idle frame with the CPU's sampler.
    let idle = |engine: &mut Engine| {
        engine.frame();
        let before = engine.gpu_frames();
        let least = (0..5).map(|_| engine.frame()).min().expect("frames");
        (least, engine.gpu_frames() - before)
    };
    engine
        .world
        .resource_mut::<EngineSettings>()
        .sample_every_update = false;
    let (on_gpu, drawn) = idle(&mut engine);
    assert_eq!(drawn, 0, "an idle frame resampled");
    engine.world.resource_mut::<EngineSettings>().sampler = SamplerBackend::Cpu;
    let (on_cpu, _) = idle(&mut engine);
    // For the record: the CPU's resample of the same count in the same engine.
    engine
        .world
        .resource_mut::<EngineSettings>()
        .sample_every_update = true;
    engine.frame();
    let stats = engine.world.resource::<ecs::StageStats>();
    let took = stats
        .runs
        .iter()
        .find(|r| r.stage == ecs::Stage::Sampling)
        .expect("a CPU resample")
        .took;
    let _ = writeln!(
        std::io::stderr(),
        "the CPU's resample of 10^5 samples: {:.3} ms",
        took.as_secs_f64() * 1e3
    );
    let buffer = engine
        .world
        .get::<SampleBuffer>(engine.mesh)
        .expect("buffer");
    assert_eq!(buffer.samples.len(), 100_000, "the CPU took over");
    let _ = writeln!(
        std::io::stderr(),
        "idle frame: {on_gpu:?} with the GPU's sampler, {on_cpu:?} with the CPU's"
    );
    assert_eq!(
        on_gpu, on_cpu,
        "the GPU's systems allocated in an idle frame"
    );
}
