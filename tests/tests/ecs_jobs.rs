//! Builds off the frame (issue 20): an update that sees a change starts a build and
//! returns while the last good sampler keeps drawing; edits during a build cancel it and
//! end in exactly one build of the newest state; meshes in one world build
//! independently; the background result equals the blocking one bit for bit. Meshes
//! are built here, so nothing skips.

use std::sync::Arc;
use std::time::Duration;

use bevy_ecs::prelude::*;
use glam::DVec3;
use strata_engine::field::TensorField;
use strata_engine::fixtures::constant;
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::sample::Sample;
use strata_engine::surface::SurfaceOptions;
use strata_systems::ecs::{
    self, EngineSettings, FieldData, MeshBundle, MeshSampler, PreprocessJobs, PreprocessMode,
    PreprocessProgress, SampleBuffer, SamplingSettings, Segments, Stage, StageStats,
};

const LIMIT: Duration = Duration::from_secs(120);

/// A 3:1 field along `direction` (projected into the tangent planes).
fn field(mesh: &TriMesh, direction: [f64; 3]) -> Arc<TensorField> {
    let spec = constant(direction, 3.0);
    Arc::new(spec.build(mesh).expect("field"))
}

/// `strata_bench::cap_field` (caps along y), shared.
fn cap(mesh: &TriMesh, y_min: f64, turned: DVec3) -> Arc<TensorField> {
    Arc::new(strata_bench::cap_field(mesh, y_min, turned).expect("field"))
}

fn world(mode: PreprocessMode) -> (World, Schedule) {
    let mut world = World::new();
    let mut schedule = Schedule::default();
    ecs::register(&mut world, &mut schedule);
    world.resource_mut::<EngineSettings>().preprocess = mode;
    (world, schedule)
}

fn settle(world: &mut World, schedule: &mut Schedule) {
    assert!(ecs::settle(world, schedule, LIMIT), "builds did not finish");
    let errors = &world.resource::<ecs::EngineErrors>().0;
    assert!(errors.is_empty(), "{errors:?}");
}

fn samples(world: &World, e: Entity) -> Vec<Sample> {
    world
        .get::<SampleBuffer>(e)
        .expect("buffer")
        .samples
        .clone()
}

#[test]
fn an_update_starts_the_build_and_the_last_sampler_keeps_drawing_until_it_is_done() {
    let mesh = Arc::new(shapes::sphere(1.0, 50).expect("sphere")); // 50,000 faces
    let (mut world, mut schedule) = world(PreprocessMode::Background);
    let bundle = MeshBundle::new(
        mesh.clone(),
        cap(&mesh, 2.0, DVec3::Z),
        SurfaceOptions::default(),
        5000,
        3,
    );
    let e = world.spawn(bundle).id();
    settle(&mut world, &mut schedule);
    let before = samples(&world, e);
    assert_eq!(before.len(), 5000);
    let generation = world.get::<SampleBuffer>(e).expect("buffer").generation;

    let old = world
        .get::<MeshSampler>(e)
        .and_then(|s| s.0.clone())
        .expect("sampler");
    // A field edit on a cap: the update that sees it only starts the build.
    world.get_mut::<FieldData>(e).expect("field").0 = cap(&mesh, 0.6, DVec3::Z);
    world.resource_mut::<StageStats>().clear();
    schedule.run(&mut world);
    assert_eq!(world.resource::<PreprocessJobs>().in_flight(), 1);
    let progress = world.resource::<PreprocessProgress>();
    assert_eq!(progress.jobs.len(), 1);
    assert_eq!(progress.jobs[0].entity, e);
    assert!(
        progress
            .summary()
            .expect("summary")
            .starts_with("building: ")
    );
    assert!(world.resource::<StageStats>().runs.is_empty());
    // Resampling with the old sampler meanwhile works (a count change).
    world
        .get_mut::<SamplingSettings>(e)
        .expect("sampling")
        .count = 4000;
    schedule.run(&mut world);
    let during = samples(&world, e);
    assert_eq!(during.len(), 4000);
    assert!(
        during == old.sample(4000, 3),
        "not the old sampler's samples"
    );

    settle(&mut world, &mut schedule);
    let stats = world.resource::<StageStats>();
    let segmentation: Vec<&str> = stats
        .runs
        .iter()
        .filter(|r| r.stage == Stage::Segmentation)
        .map(|r| r.note.as_str())
        .collect();
    assert!(
        segmentation.len() == 1 && segmentation[0].starts_with("region of"),
        "{:?}",
        stats.runs
    );
    assert!(world.get::<SampleBuffer>(e).expect("buffer").generation > generation + 1);
    assert!(
        samples(&world, e) != during,
        "the new sampler replaced the old"
    );
    assert!(world.resource::<PreprocessProgress>().jobs.is_empty());
}

#[test]
fn edits_during_a_build_cancel_it_and_end_in_one_build_of_the_last_state() {
    let mesh = Arc::new(shapes::sphere(1.0, 40).expect("sphere"));
    let first = cap(&mesh, 2.0, DVec3::Z);
    let edits: Vec<Arc<TensorField>> = (0..10)
        .map(|i| {
            cap(
                &mesh,
                0.3 + 0.04 * f64::from(i),
                DVec3::new(0.1 * f64::from(i), 0.0, 1.0),
            )
        })
        .collect();
    let (mut world, mut schedule) = world(PreprocessMode::Background);
    let e = world
        .spawn(MeshBundle::new(
            mesh.clone(),
            first.clone(),
            SurfaceOptions::default(),
            3000,
            9,
        ))
        .id();
    settle(&mut world, &mut schedule);
    let base = world.resource::<PreprocessJobs>().counts();
    for edit in &edits {
        world.get_mut::<FieldData>(e).expect("field").0 = edit.clone();
        schedule.run(&mut world);
    }
    settle(&mut world, &mut schedule);
    let counts = world.resource::<PreprocessJobs>().counts();
    let launched = counts.launched - base.launched;
    assert_eq!(counts.completed - base.completed, 1, "{counts:?}");
    assert_eq!(
        counts.cancelled - base.cancelled,
        launched - 1,
        "{counts:?}"
    );
    assert!(launched <= 10);

    // The result is that of one build from the first state to the last edit.
    let (mut direct, mut direct_schedule) = world_blocking_from(&mesh, first, 3000, 9);
    let d = direct
        .query_filtered::<Entity, With<MeshSampler>>()
        .single(&direct)
        .expect("one mesh");
    direct.get_mut::<FieldData>(d).expect("field").0 = edits[9].clone();
    settle(&mut direct, &mut direct_schedule);
    assert!(
        samples(&world, e) == samples(&direct, d),
        "differs from one build of the last edit"
    );
}

fn world_blocking_from(
    mesh: &Arc<TriMesh>,
    field: Arc<TensorField>,
    count: usize,
    seed: u64,
) -> (World, Schedule) {
    let (mut world, mut schedule) = world(PreprocessMode::Blocking);
    world.spawn(MeshBundle::new(
        mesh.clone(),
        field,
        SurfaceOptions::default(),
        count,
        seed,
    ));
    schedule.run(&mut world);
    (world, schedule)
}

#[test]
fn blocking_and_background_builds_give_the_same_samples() {
    let mesh = Arc::new(shapes::torus(1.0, 0.4, 24).expect("torus"));
    let f = field(&mesh, [1.0, 0.3, 0.2]);
    let (mut blocking, mut s1) = world_blocking_from(&mesh, f.clone(), 2000, 4);
    // One update did everything.
    assert_eq!(blocking.resource::<PreprocessJobs>().counts().completed, 1);
    let (mut background, mut s2) = world(PreprocessMode::Background);
    background.spawn(MeshBundle::new(mesh, f, SurfaceOptions::default(), 2000, 4));
    settle(&mut background, &mut s2);
    s1.run(&mut blocking); // nothing left to do
    let a = blocking
        .query::<&SampleBuffer>()
        .single(&blocking)
        .expect("one")
        .samples
        .clone();
    let b = background
        .query::<&SampleBuffer>()
        .single(&background)
        .expect("one")
        .samples
        .clone();
    assert_eq!(a.len(), 2000);
    assert!(a == b);
}

#[test]
fn eight_meshes_build_independently_and_an_edit_rebuilds_only_its_mesh() {
    let (mut world, mut schedule) = world(PreprocessMode::Background);
    let mut entities = Vec::new();
    for i in 0..8u32 {
        let mesh = Arc::new(match i % 4 {
            0 => shapes::sphere(1.0, 6 + i).expect("sphere"),
            1 => shapes::torus(1.0, 0.35, 16 + i).expect("torus"),
            2 => shapes::cylinder(0.5, 1.5, 12 + i).expect("cylinder"),
            _ => shapes::genus2(1.0, 1 + i / 4).expect("genus 2"),
        });
        let f = field(&mesh, [1.0, 0.2 * f64::from(i), 0.3]);
        let mut options = SurfaceOptions::default();
        options.segment.seed = u64::from(i);
        entities.push(
            world
                .spawn(MeshBundle::new(
                    mesh,
                    f,
                    options,
                    500 + 100 * i as usize,
                    u64::from(i),
                ))
                .id(),
        );
    }
    settle(&mut world, &mut schedule);
    for (i, &e) in entities.iter().enumerate() {
        assert_eq!(samples(&world, e).len(), 500 + 100 * i);
        assert!(world.get::<Segments>(e).is_some_and(|s| !s.is_empty()));
    }
    let generations: Vec<u64> = entities
        .iter()
        .map(|&e| world.get::<SampleBuffer>(e).expect("buffer").generation)
        .collect();
    world.resource_mut::<StageStats>().clear();
    let edited = entities[5];
    let mesh = world.get::<ecs::MeshData>(edited).expect("mesh").0.clone();
    world.get_mut::<FieldData>(edited).expect("field").0 = field(&mesh, [0.0, 1.0, 0.2]);
    settle(&mut world, &mut schedule);
    let stats = world.resource::<StageStats>();
    assert!(stats.runs_of(Stage::Segmentation) == 1, "{:?}", stats.runs);
    assert!(
        stats.runs.iter().all(|r| r.entity == edited),
        "{:?}",
        stats.runs
    );
    for (i, &e) in entities.iter().enumerate() {
        let g = world.get::<SampleBuffer>(e).expect("buffer").generation;
        assert_eq!(g != generations[i], e == edited, "mesh {i}");
    }
    // Despawning a mesh despawns its segments (a relationship).
    let segments: Vec<Entity> = world
        .get::<Segments>(edited)
        .expect("segments")
        .iter()
        .collect();
    world.despawn(edited);
    assert!(segments.iter().all(|&s| world.get_entity(s).is_err()));
}

#[test]
fn a_failed_build_keeps_the_last_good_state() {
    let mesh = Arc::new(shapes::torus(1.0, 0.4, 20).expect("torus"));
    let (mut world, mut schedule) = world(PreprocessMode::Background);
    let e = world
        .spawn(MeshBundle::new(
            mesh.clone(),
            field(&mesh, [1.0, 0.0, 0.0]),
            SurfaceOptions::default(),
            800,
            1,
        ))
        .id();
    settle(&mut world, &mut schedule);
    let good = samples(&world, e);
    // Settings a build refuses (min_segment_faces 0): an error, the samples stay.
    world
        .get_mut::<ecs::PreprocessSettings>(e)
        .expect("settings")
        .0
        .min_segment_faces = 0;
    assert!(ecs::settle(&mut world, &mut schedule, LIMIT));
    let errors = std::mem::take(&mut world.resource_mut::<ecs::EngineErrors>().0);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].to_string().contains("min_segment_faces"),
        "{}",
        errors[0]
    );
    assert!(samples(&world, e) == good);
    assert_eq!(world.resource::<PreprocessJobs>().counts().failed, 1);
}

/// A level-of-detail pool (ranks `0..base` drawn again when the sampler changes) is
/// built off the frame too: while it builds, the old pool keeps following the camera
/// with the sampler it was drawn from; then the new pool and its sampler replace both.
#[test]
fn a_level_of_detail_pool_is_rebuilt_off_the_frame() {
    use strata_systems::ecs::{Lod, LodState};
    use strata_systems::gpu::{OrbitCamera, SplatLod};
    let mesh = Arc::new(shapes::sphere(1.0, 30).expect("sphere"));
    let camera = OrbitCamera {
        target: glam::Vec3::ZERO,
        distance: 4.0,
        yaw: 0.3,
        pitch: 0.5,
        fov_y: 40f32.to_radians(),
        radius: 1.0,
    };
    let splat = SplatLod {
        base: 200_000.0,
        expanded: 200_000.0,
        reference: 4000.0,
        max: 4.0,
        cull_back_faces: true,
    };
    let view = splat.view(&camera, (320, 240));
    let (mut world, mut schedule) = world(PreprocessMode::Background);
    let bundle = MeshBundle::new(
        mesh.clone(),
        cap(&mesh, 2.0, DVec3::Z),
        SurfaceOptions::default(),
        100,
        2,
    );
    let lod = Lod {
        view,
        base: 200_000,
        budget: 100_000,
        shown: None,
    };
    let e = world.spawn((bundle, lod, LodState::default())).id();
    settle(&mut world, &mut schedule);
    let state = world.get::<LodState>(e).expect("state");
    assert_eq!(state.builds, 1);
    assert!(state.pool.as_ref().is_some_and(|p| p.len() >= 200_000));
    let old_segments = state.drawn_from().expect("sampler").segments().len();

    // A field edit: the build, then the pool, run off the frame; updates meanwhile
    // keep the old pool and its sampler.
    world.get_mut::<FieldData>(e).expect("field").0 = cap(&mesh, 0.3, DVec3::Z);
    let mut saw_old_pool_with_new_sampler = false;
    let start = std::time::Instant::now();
    while world.get::<LodState>(e).expect("state").builds < 2 {
        schedule.run(&mut world);
        let state = world.get::<LodState>(e).expect("state");
        let current = world
            .get::<MeshSampler>(e)
            .and_then(|s| s.0.as_ref())
            .expect("sampler");
        let drawn = state.drawn_from().expect("the old pool's sampler");
        assert!(state.pool.is_some(), "no pool while the new one builds");
        if state.builds == 1 && drawn.sample(50, 1) != current.sample(50, 1) {
            saw_old_pool_with_new_sampler = true;
        }
        assert!(start.elapsed() < LIMIT, "the pool was not rebuilt");
        std::thread::sleep(Duration::from_millis(1));
    }
    settle(&mut world, &mut schedule);
    let state = world.get::<LodState>(e).expect("state");
    let current = world
        .get::<MeshSampler>(e)
        .and_then(|s| s.0.as_ref())
        .expect("sampler");
    let drawn = state.drawn_from().expect("sampler");
    assert_eq!(drawn.segments().len(), current.segments().len());
    assert!(
        drawn.sample(500, 1) == current.sample(500, 1),
        "the pool is the new sampler's"
    );
    assert_ne!(old_segments, 0);
    // The pool of 200,000 ranks starts building in the update that applies the new
    // sampler, so that update (at least) draws with the old pool and its sampler.
    assert!(
        saw_old_pool_with_new_sampler,
        "the pool was rebuilt inside an update"
    );
}
