//! `EngineSettings::sampler` in the ECS engine: who draws a mesh's samples for each
//! choice, with and without a GPU layer. Without a GPU: `auto` and `cpu` draw on the
//! CPU, a forced `gpu` is one `EngineError` and the CPU keeps drawing. With a GPU layer
//! on the software adapter (skipped without one unless `STRATA_REQUIRE_GPU=1`): `auto`
//! keeps the CPU, `gpu` draws into the renderer's buffer and leaves the CPU's buffer
//! alone, a mesh transform other than the identity keeps the CPU, and switching back to
//! `cpu` redraws on the CPU.

use std::sync::Arc;
use std::time::Duration;

use bevy_ecs::prelude::*;
use strata_engine::field::FieldSpec;
use strata_engine::mesh::shapes;
use strata_engine::surface::SurfaceOptions;
use strata_systems::ecs::{
    self, EngineErrors, EngineSettings, GpuSampled, MeshBundle, MeshTransform, SampleBuffer,
    SamplerBackend,
};
use strata_systems::gpu::backend::{self, GpuSampling, UsedSampler};
use strata_systems::gpu::{GpuContext, GpuSplats, HeadlessTarget, SplatRenderer};

/// An engine world with one settled sphere of 500 samples, the GPU layer registered.
fn engine() -> (World, Schedule, Entity) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    ecs::register(&mut world, &mut schedule);
    strata_systems::gpu::upload::register(&mut schedule);
    backend::register(&mut world, &mut schedule);
    let mesh = Arc::new(shapes::sphere(1.0, 3).expect("sphere"));
    let field = FieldSpec::Constant {
        direction: [1.0, 0.3, 0.2],
        anisotropy: 2.0,
        density: 1.0,
    };
    let field = Arc::new(field.build(&mesh).expect("field"));
    let e = world
        .spawn(MeshBundle::new(
            mesh,
            field,
            SurfaceOptions::default(),
            500,
            3,
        ))
        .id();
    schedule.run(&mut world);
    assert!(ecs::settle(
        &mut world,
        &mut schedule,
        Duration::from_secs(120)
    ));
    (world, schedule, e)
}

fn set(world: &mut World, choice: SamplerBackend) {
    world.resource_mut::<EngineSettings>().sampler = choice;
}

fn generation(world: &World, e: Entity) -> u64 {
    world.get::<SampleBuffer>(e).expect("buffer").generation
}

fn used(world: &World) -> Option<UsedSampler> {
    world.resource::<GpuSampling>().used.map(|u| u.used)
}

#[test]
fn without_a_gpu_the_cpu_draws_and_a_forced_gpu_is_an_error() {
    let (mut world, mut schedule, e) = engine();
    assert_eq!(used(&world), Some(UsedSampler::Cpu), "auto without a GPU");
    let drawn = generation(&world, e);
    assert!(drawn > 0);
    set(&mut world, SamplerBackend::Gpu);
    world.resource_mut::<ecs::SampleRequest>().0 = true;
    schedule.run(&mut world);
    schedule.run(&mut world);
    let errors = std::mem::take(&mut world.resource_mut::<EngineErrors>().0);
    assert_eq!(errors.len(), 1, "{errors:?}");
    let message = errors[0].to_string();
    assert!(
        message.contains("sampler gpu needs a GPU adapter") && !message.contains('\n'),
        "{message}"
    );
    assert_eq!(world.resource::<GpuSampled>().0, None);
    assert!(generation(&world, e) > drawn, "the CPU kept drawing");
}

#[test]
fn with_a_gpu_the_switch_picks_who_draws() {
    let Some(ctx) = GpuContext::headless_or_skip("with_a_gpu_the_switch_picks_who_draws") else {
        return;
    };
    let hardware = backend::is_hardware(&ctx.adapter.get_info());
    let target = HeadlessTarget::new(&ctx.device, 32, 32, 1).expect("target");
    let renderer = SplatRenderer::new(&ctx.device, target.format()).expect("renderer");
    let (mut world, mut schedule, e) = engine();
    world.insert_resource(GpuSplats::new(ctx, renderer));
    let gpu_len = |world: &World| world.resource::<GpuSplats>().renderer.samples().len();
    // Auto: the GPU only on a hardware adapter.
    schedule.run(&mut world);
    let auto = if hardware {
        UsedSampler::Gpu
    } else {
        UsedSampler::Cpu
    };
    assert_eq!(used(&world), Some(auto));
    // Gpu: the renderer's buffer gets the new count, the CPU's buffer stays as it was.
    set(&mut world, SamplerBackend::Gpu);
    let before = generation(&world, e);
    world
        .get_mut::<ecs::SamplingSettings>(e)
        .expect("settings")
        .count = 700;
    schedule.run(&mut world);
    assert_eq!(world.resource::<GpuSampled>().0, Some(e));
    assert_eq!(generation(&world, e), before, "the CPU drew");
    assert_eq!(gpu_len(&world), 700);
    assert_eq!(world.resource::<GpuSampling>().last.count, 700);
    // A transform other than the identity: the CPU draws (the GPU's spacings would not
    // follow the scale).
    world.get_mut::<MeshTransform>(e).expect("transform").0 =
        glam::DAffine3::from_scale(glam::DVec3::splat(2.0));
    schedule.run(&mut world);
    assert_eq!(world.resource::<GpuSampled>().0, None);
    assert!(generation(&world, e) > before);
    world.get_mut::<MeshTransform>(e).expect("transform").0 = glam::DAffine3::IDENTITY;
    schedule.run(&mut world);
    assert_eq!(world.resource::<GpuSampled>().0, Some(e));
    // Back to the CPU: it draws the entity again, and the upload replaces the GPU's.
    set(&mut world, SamplerBackend::Cpu);
    let before = generation(&world, e);
    schedule.run(&mut world);
    assert_eq!(world.resource::<GpuSampled>().0, None);
    assert!(generation(&world, e) > before);
    assert_eq!(gpu_len(&world), 700);
    assert!(world.resource::<EngineErrors>().0.is_empty());
}
