//! A frame of the ECS engine with GPU sampling ([`strata_systems::gpu::backend`]) costs
//! the CPU nothing per sample: a counting global allocator around the system's, and
//! the engine's schedule run with `sampler: Gpu` on whatever adapter wgpu opens (the
//! software adapter in CI; skipped without one unless `STRATA_REQUIRE_GPU=1`).
//!
//! Checked: the resample runs on the GPU into the renderer's buffer (the CPU's sample
//! buffer stays empty, the GPU's records are the CPU's samples); a frame that resamples
//! allocates the same blocks and bytes at 10^3 and 10^5 samples (a fixed cost, none
//! per sample), at most [`FRAME_ALLOCATIONS`] blocks and [`FRAME_BYTES`], itemized and
//! printed: bevy_ecs's schedule (what an idle frame allocates), the engine's request
//! table (nothing: `FlatSampler::request_into` reuses the GPU sampler's table), and
//! wgpu, which is held against a floor measured in the same process (one
//! `write_buffer`, an encoder with one compute pass and one dispatch, one submission:
//! at most [`WGPU_MARGIN`] more) and against the same shape of frame bare (one pass,
//! two dispatches: at most [`SHAPE_MARGIN`] more); on bevy_ecs's single-threaded
//! executor the frame allocates wgpu's part alone. It uploads only the
//! per-segment request table (the uniforms only when the count changes), against 16
//! bytes per sample for sites and 64 for records; a frame that repeats count and seed
//! neither recomputes nor uploads anything and allocates less; a frame with nothing
//! to redraw allocates nothing beyond what bevy_ecs's schedule allocates by itself
//! (the same as with the CPU's sampler). The binary holds this one test, so no other
//! test allocates while it counts.

use std::alloc::System;
use std::io::Write;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};
use strata_engine::field::FieldSpec;
use strata_engine::mesh::shapes;
use strata_engine::sample::flat::FlatRequest;
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

/// Allocations per resampling frame at most (measured on the software adapter: 71,
/// 12 of them bevy_ecs's schedule; see the assertions).
const FRAME_ALLOCATIONS: usize = 76;
/// Bytes allocated per resampling frame at most (measured: 12-16 KB, as wgpu's
/// internal vectors happen to grow).
const FRAME_BYTES: usize = 20 * 1024;
/// What strata's frame may allocate in wgpu beyond the floor (one `write_buffer`, an
/// encoder with one compute pass and one dispatch, one submission): the expansion's
/// dispatch in the same pass, with its own pipeline and bind group (7 measured on the
/// software adapter).
const WGPU_MARGIN: usize = 10;
/// What strata's frame may allocate in wgpu beyond the same shape of frame bare (one
/// pass, two dispatches of two pipelines, one `write_buffer`): the barrier wgpu
/// records between strata's two dependent dispatches and the sites pass's four
/// bindings where the bare dispatches bind one buffer (2-4 measured).
const SHAPE_MARGIN: usize = 6;

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

/// Allocations and bytes of the engine's request table for `(count, seed)` alone,
/// written into a table that a first request grew (`FlatSampler::request_into`, what
/// a resampling frame computes on the CPU); and the table's bytes as uploaded.
fn request_cost(engine: &Engine, count: usize, seed: u64) -> ((usize, usize), usize) {
    let (gpu, sampler) = samplers(engine);
    let flat = gpu.flat();
    let mut table = FlatRequest::default();
    flat.request_into(sampler, count as u64, seed + 1, &mut table)
        .expect("request");
    let cost = counted(|| {
        flat.request_into(sampler, count as u64, seed, &mut table)
            .expect("request");
        std::hint::black_box(&table);
    });
    let words = std::mem::size_of_val(table.groups.as_slice()) / 4
        + table.levels.len()
        + 2 * table.thresholds.len();
    (cost, 4 * words)
}

/// The shape of a bare wgpu frame ([`bare_frame`]).
#[derive(Clone, Copy, Debug)]
struct Shape {
    /// Compute passes.
    passes: usize,
    /// Dispatches in each pass (set pipeline, set bind group, dispatch).
    dispatches: usize,
    /// Timestamps at each pass's begin and end, resolved into a buffer.
    timestamps: bool,
}

/// A compute pass that writes its invocation ids: the least a dispatch can be.
const BARE_SHADER: &str = "
@group(0) @binding(0) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&out) { out[id.x] = id.x; }
}";

/// Allocations and bytes of a frame of wgpu alone, at most over a few frames after a
/// warm-up: one `queue.write_buffer` of `upload` bytes, a command encoder with
/// `shape`'s compute passes and dispatches on an
/// unlabelled encoder and passes, finished and submitted (waiting for the device
/// outside the count, as in an engine frame). One pass without timestamps is the
/// floor of any frame that uploads parameters and runs a compute pass.
fn bare_frame(engine: &Engine, shape: Shape, upload: usize) -> (usize, usize) {
    let ctx = &engine.world.resource::<GpuSplats>().ctx;
    let (device, queue) = (&ctx.device, &ctx.queue);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("bare frame"),
        source: wgpu::ShaderSource::Wgsl(BARE_SHADER.into()),
    });
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("bare frame"),
        size: upload.next_multiple_of(4).max(4096) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    // A pipeline and a bind group per dispatch, as strata's dispatches have theirs.
    let dispatches: Vec<(wgpu::ComputePipeline, wgpu::BindGroup)> = (0..shape.dispatches)
        .map(|_| {
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("bare frame"),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            });
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("bare frame"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                }],
            });
            (pipeline, bind_group)
        })
        .collect();
    let timer = (shape.timestamps && device.features().contains(wgpu::Features::TIMESTAMP_QUERY))
        .then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("bare frame"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * shape.passes as u32,
            });
            let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bare frame"),
                size: 16 * shape.passes as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE,
                mapped_at_creation: false,
            });
            (set, resolve)
        });
    let data = vec![0u8; upload.next_multiple_of(4)];
    let frame = || {
        queue.write_buffer(&buffer, 0, &data);
        let mut encoder = device.create_command_encoder(&Default::default());
        for p in 0..shape.passes as u32 {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: timer
                    .as_ref()
                    .map(|(set, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(2 * p),
                        end_of_pass_write_index: Some(2 * p + 1),
                    }),
            });
            for (pipeline, bind_group) in &dispatches {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind_group, &[]);
                pass.dispatch_workgroups(16, 1, 1);
            }
        }
        if let Some((set, resolve)) = &timer {
            encoder.resolve_query_set(set, 0..2 * shape.passes as u32, resolve, 0);
        }
        queue.submit([encoder.finish()]);
    };
    let mut worst = (0, 0);
    for i in 0..8 {
        let cost = counted(frame);
        ctx.wait_idle("a bare frame").expect("device");
        if i >= 3 {
            worst = (worst.0.max(cost.0), worst.1.max(cost.1));
        }
    }
    worst
}

/// Allocations and bytes of the engine's frame with nothing to redraw (bevy_ecs's
/// `Schedule::run` allocates a few blocks even then), the least over a few.
fn idle_frame(engine: &mut Engine) -> ((usize, usize), u64) {
    let every = engine
        .world
        .resource::<EngineSettings>()
        .sample_every_update;
    engine
        .world
        .resource_mut::<EngineSettings>()
        .sample_every_update = false;
    engine.frame();
    let before = engine.gpu_frames();
    let least = (0..5).map(|_| engine.frame()).min().expect("frames");
    let drawn = engine.gpu_frames() - before;
    engine
        .world
        .resource_mut::<EngineSettings>()
        .sample_every_update = every;
    (least, drawn)
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
        let record = engine.world.resource::<GpuSampling>().last.record;
        // The parts: bevy_ecs's schedule (an idle frame), the engine's request, and
        // wgpu's floor and strata's shape of frame measured bare in this process.
        let (schedule, drawn) = idle_frame(&mut engine);
        assert_eq!(drawn, 0, "an idle frame resampled");
        let (request, upload) = request_cost(&engine, count, 19);
        let floor = bare_frame(
            &engine,
            Shape {
                passes: 1,
                dispatches: 1,
                timestamps: false,
            },
            upload,
        );
        // Strata's shape: the sites and their expansion as two dispatches of one
        // pass (two passes with their timestamps where the sampler times them).
        let timed = samplers(&engine).0.times_passes();
        let shape = Shape {
            passes: if timed { 2 } else { 1 },
            dispatches: if timed { 1 } else { 2 },
            timestamps: timed,
        };
        let bare = bare_frame(&engine, shape, upload);
        let wgpu = worst.0.saturating_sub(schedule.0 + request.0);
        // A frame that repeats count and seed: no request computed, nothing uploaded.
        let before = engine.gpu_frames();
        let repeat = (0..3).map(|_| engine.frame()).max().expect("frames");
        assert_eq!(engine.gpu_frames() - before, 3, "repeated frames resampled");
        let _ = writeln!(
            std::io::stderr(),
            "{count} samples: per frame at most {} allocations ({} bytes), {upload} bytes uploaded; of these bevy_ecs's schedule {} ({} bytes, as in an idle frame), the engine's request {} ({} bytes), wgpu {wgpu}; wgpu's floor (one write_buffer, an encoder with one compute pass and one dispatch, submitted) {} allocations ({} bytes), the same shape bare ({shape:?}) {} ({} bytes); a frame repeating count and seed {} allocations ({} bytes), nothing uploaded; the last took the CPU {:.3} ms to record and submit",
            worst.0,
            worst.1,
            schedule.0,
            schedule.1,
            request.0,
            request.1,
            floor.0,
            floor.1,
            bare.0,
            bare.1,
            repeat.0,
            repeat.1,
            record.as_secs_f64() * 1e3
        );
        cost.push((worst, upload, request, wgpu, floor, bare, repeat));
    }
    let [(small, small_up, ..), (large, large_up, ..)] = cost[..] else {
        unreachable!()
    };
    // A fixed cost: no allocation or byte that grows with the count (10^5 sites alone
    // would be 1.6 MB; wgpu's internal vectors grow by a few KB in some frames).
    assert!(
        large.0 <= small.0 + 4 && large.1 <= small.1 + 8192,
        "per frame: {small:?} at 10^3, {large:?} at 10^5"
    );
    for &(frame, _, request, wgpu, floor, bare, repeat) in &cost {
        assert!(
            frame.0 <= FRAME_ALLOCATIONS && frame.1 <= FRAME_BYTES,
            "{frame:?}"
        );
        // The request table is reused: nothing allocated once it has grown.
        assert_eq!(request.0, 0, "the engine's request allocated");
        // wgpu: the floor plus what a second pass and timestamps add, and nothing
        // beyond what the same shape of frame allocates bare.
        assert!(
            wgpu <= floor.0 + WGPU_MARGIN,
            "wgpu allocated {wgpu} in a frame, its floor is {floor:?}"
        );
        assert!(
            wgpu <= bare.0 + SHAPE_MARGIN,
            "strata allocated {wgpu} in wgpu, the same passes bare {bare:?}"
        );
        // A repeated request is neither recomputed nor uploaded again.
        assert!(
            repeat.0 < frame.0,
            "a frame repeating count and seed allocated as much: {repeat:?}, {frame:?}"
        );
    }
    // bevy_ecs's part is its multi-threaded executor's (a task per system): a host
    // that runs the schedule on the single-threaded executor allocates none of it.
    engine
        .schedule
        .set_executor(bevy_ecs::schedule::SingleThreadedExecutor::new());
    let single = (20..28)
        .map(|seed| {
            engine.set(100_000, seed);
            engine.frame()
        })
        .skip(3)
        .max()
        .expect("frames");
    let (single_idle, _) = idle_frame(&mut engine);
    let _ = writeln!(
        std::io::stderr(),
        "with bevy_ecs's single-threaded executor: per frame at most {} allocations ({} bytes), an idle frame {} ({} bytes)",
        single.0,
        single.1,
        single_idle.0,
        single_idle.1
    );
    let (_, _, _, wgpu, ..) = cost[1];
    assert!(
        single.0 <= wgpu + 1,
        "single-threaded, a frame allocated beyond wgpu's part: {single:?}"
    );
    engine
        .schedule
        .set_executor(bevy_ecs::schedule::MultiThreadedExecutor::new());
    engine.set(100_000, 19);
    engine.frame();
    // Only parameters: the per-segment table, nothing per sample.
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
    // Nothing to redraw: nothing drawn, and no allocation beyond the schedule's own:
    // the same as the same engine's idle frame with the CPU's sampler.
    let (on_gpu, drawn) = idle_frame(&mut engine);
    assert_eq!(drawn, 0, "an idle frame resampled");
    engine.world.resource_mut::<EngineSettings>().sampler = SamplerBackend::Cpu;
    let (on_cpu, _) = idle_frame(&mut engine);
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
