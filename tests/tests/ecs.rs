//! The ECS streaming engine without files: the engine's result through the world
//! equals the engine stages called directly, and each kind of change reruns only the
//! stages and segments it invalidates (asserted on the per-stage counters).

use std::collections::HashSet;
use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::DVec3;
use strata_engine::field::TensorField;
use strata_engine::fixtures::{field_on, oblique};
use strata_engine::mesh::{NONE, TriMesh};
use strata_engine::surface::{Preprocessed, SurfaceOptions};
use strata_systems::ecs::{
    self, CurveSettings, FieldData, MeshBundle, MeshTransform, SampleBuffer, SamplingSettings,
    SegmentFaces, SegmentParams, Stage, StageStats,
};
use strata_tests::shared_mesh_dir;

fn bunny() -> Option<Arc<TriMesh>> {
    let dir = shared_mesh_dir()?;
    Some(Arc::new(
        strata_engine::io::load(&dir.join("stanford-bunny.obj")).expect("bunny loads"),
    ))
}

fn projected(mesh: &TriMesh) -> Arc<TensorField> {
    Arc::new(field_on(mesh, &oblique(3.0)))
}

/// Longest wait for a build (the bunny on a busy machine).
const LIMIT: std::time::Duration = std::time::Duration::from_secs(120);

struct Engine {
    world: World,
    schedule: Schedule,
    mesh: Entity,
}

impl Engine {
    fn new(mesh: Arc<TriMesh>, field: Arc<TensorField>, count: usize, seed: u64) -> Self {
        let mut world = World::new();
        let mut schedule = Schedule::default();
        ecs::register(&mut world, &mut schedule);
        let bundle = MeshBundle::new(mesh, field, SurfaceOptions::default(), count, seed);
        let mesh = world.spawn(bundle).id();
        let mut e = Self {
            world,
            schedule,
            mesh,
        };
        e.update();
        e
    }

    /// Runs updates until the builds a change started are applied.
    fn update(&mut self) {
        self.world.resource_mut::<StageStats>().clear();
        assert!(
            ecs::settle(&mut self.world, &mut self.schedule, LIMIT),
            "builds did not finish"
        );
        self.world.clear_trackers();
        let errors = &self.world.resource::<ecs::EngineErrors>().0;
        assert!(errors.is_empty(), "{errors:?}");
    }

    fn stats(&self) -> &StageStats {
        self.world.resource::<StageStats>()
    }

    fn samples(&self) -> Vec<strata_engine::sample::Sample> {
        self.world
            .get::<SampleBuffer>(self.mesh)
            .expect("buffer")
            .samples
            .clone()
    }

    fn segments(&mut self) -> Vec<(Entity, Vec<u32>, usize)> {
        let mut q = self
            .world
            .query::<(Entity, &SegmentFaces, &SegmentParams)>();
        let mut out: Vec<_> = q
            .iter(&self.world)
            .map(|(e, s, p)| (e, s.faces.clone(), p.pieces.len()))
            .collect();
        out.sort_by_key(|s| s.1[0]);
        out
    }
}

/// Every face in exactly one segment entity, every segment parameterized.
fn assert_covering(engine: &mut Engine, face_count: usize) {
    let mut owner = vec![NONE; face_count];
    for (i, (_, faces, pieces)) in engine.segments().into_iter().enumerate() {
        assert!(pieces > 0, "segment {i} has no parameterization");
        for f in faces {
            assert_eq!(owner[f as usize], NONE, "face {f} in two segments");
            owner[f as usize] = i as u32;
        }
    }
    assert!(owner.iter().all(|&o| o != NONE), "a face has no segment");
}

#[test]
fn ecs_result_equals_the_engine_stages_called_directly() {
    let Some(mesh) = bunny() else {
        eprintln!("skipped: shared meshes missing");
        return;
    };
    let field = projected(&mesh);
    let (count, seed) = (30_000, 11);
    let mut engine = Engine::new(mesh.clone(), field.clone(), count, seed);
    let direct = Preprocessed::build(mesh.clone(), field.clone(), &SurfaceOptions::default())
        .expect("direct");
    let expected = direct.sampler.sample(count, seed);
    let got = engine.samples();
    assert_eq!(got.len(), count);
    assert!(got == expected, "ECS samples differ from the engine's");
    // The sampler shares the segment entities' cells instead of holding copies.
    let mut cells = engine.world.query::<&ecs::SegmentCells>();
    let owned: Vec<*const strata_engine::curve::SegmentCurve> = cells
        .iter(&engine.world)
        .flat_map(|c| c.curves.iter().map(Arc::as_ptr))
        .collect();
    let sampler = engine
        .world
        .get::<ecs::MeshSampler>(engine.mesh)
        .expect("sampler");
    let segments = sampler.0.as_ref().expect("assembled").segments();
    assert_eq!(segments.len(), owned.len());
    for s in segments {
        assert!(
            owned.contains(&Arc::as_ptr(&s.curve)),
            "segment {} copied",
            s.segment
        );
    }
    // And the same number of final segments.
    let stats = engine.stats();
    assert_eq!(
        stats.items_of(Stage::Chains),
        direct.params.len(),
        "segments assembled"
    );
    assert_eq!(
        stats.items_of(Stage::Segmentation),
        direct.segmentation.segments.len()
    );

    // A new segmentation seed re-segments the whole mesh; segments that come out the
    // same keep their entities and results, and the samples still equal the engine's.
    let mut options = SurfaceOptions::default();
    options.segment.seed = 5;
    engine
        .world
        .get_mut::<ecs::PreprocessSettings>(engine.mesh)
        .expect("settings")
        .0
        .segment
        .seed = 5;
    engine.update();
    let direct = Preprocessed::build(mesh, field, &options).expect("direct, seed 5");
    assert!(
        engine.samples() == direct.sampler.sample(count, seed),
        "after re-segmentation"
    );
    let stats = engine.stats();
    assert!(
        stats.items_of(Stage::Parameterization) <= direct.segmentation.segments.len(),
        "only new segments are parameterized"
    );
}

#[test]
fn each_change_reruns_only_what_it_invalidates() {
    let Some(mesh) = bunny() else {
        eprintln!("skipped: shared meshes missing");
        return;
    };
    let field = projected(&mesh);
    let mut engine = Engine::new(mesh.clone(), field, 20_000, 3);
    let first = engine.samples();
    let all_segments = engine.segments();
    assert_eq!(
        engine.stats().stages_run(),
        vec![
            Stage::Segmentation,
            Stage::Parameterization,
            Stage::Curves,
            Stage::Chains,
            Stage::Sampling
        ]
    );

    // Nothing changed: nothing runs.
    engine.update();
    assert!(engine.stats().runs.is_empty(), "{:?}", engine.stats().runs);

    // Sample count: sampling only.
    let e = engine.mesh;
    engine
        .world
        .get_mut::<SamplingSettings>(e)
        .expect("settings")
        .count = 25_000;
    engine.update();
    assert_eq!(engine.stats().stages_run(), vec![Stage::Sampling]);
    assert_eq!(engine.samples().len(), 25_000);

    // Transform: sampling only; positions move by the translation.
    engine
        .world
        .get_mut::<SamplingSettings>(e)
        .expect("s")
        .count = 20_000;
    engine.world.get_mut::<MeshTransform>(e).expect("t").0 =
        glam::DAffine3::from_translation(DVec3::new(0.0, 0.0, 2.0));
    engine.update();
    assert_eq!(engine.stats().stages_run(), vec![Stage::Sampling]);
    let moved = engine.samples();
    assert!((moved[0].position[2] - first[0].position[2] - 2.0).abs() < 1e-5);
    assert_eq!(moved[0].face, first[0].face);

    // Omega (cell refinement): curves of every segment and sampling; the chains are
    // kept (same segments).
    engine
        .world
        .get_mut::<CurveSettings>(e)
        .expect("curve")
        .0
        .max_cell_share = 1.0 / 16384.0;
    engine.update();
    assert_eq!(
        engine.stats().stages_run(),
        vec![Stage::Curves, Stage::Sampling]
    );
    assert_eq!(engine.stats().items_of(Stage::Curves), all_segments.len());
    assert_eq!(engine.segments(), all_segments, "segments kept");

    // The field in a cap of about 10% of the faces: only the segments it touched are
    // re-segmented and re-parameterized; the others keep their entities.
    let cap = strata_bench::cap_height(&mesh, 0.1);
    engine.world.get_mut::<FieldData>(e).expect("field").0 =
        Arc::new(strata_bench::cap_field(&mesh, cap, DVec3::Z).expect("field"));
    engine.update();
    let stats = engine.stats().clone();
    assert_eq!(
        stats.stages_run(),
        vec![
            Stage::Segmentation,
            Stage::Parameterization,
            Stage::Curves,
            Stage::Chains,
            Stage::Sampling
        ]
    );
    let seg_run = &stats.runs[0];
    assert!(seg_run.note.starts_with("region of"), "{}", seg_run.note);
    let after = engine.segments();
    let before: HashSet<Entity> = all_segments.iter().map(|s| s.0).collect();
    let kept = after.iter().filter(|s| before.contains(&s.0)).count();
    let new = after.len() - kept;
    assert!(kept > 0 && new > 0, "kept {kept}, new {new}");
    assert!(
        kept > all_segments.len() / 2,
        "a 10% cap kept only {kept} of {} segments",
        all_segments.len()
    );
    assert_eq!(stats.items_of(Stage::Segmentation), new);
    assert_eq!(stats.items_of(Stage::Parameterization), new);
    assert_eq!(stats.items_of(Stage::Curves), new);
    // Every kept segment is one that no changed vertex touches.
    let touched = |faces: &[u32]| {
        faces
            .iter()
            .any(|&f| mesh.face_positions(f).iter().any(|p| p.y > cap))
    };
    for s in after.iter().filter(|s| before.contains(&s.0)) {
        assert!(!touched(&s.1), "a kept segment holds a changed vertex");
    }
    for s in all_segments
        .iter()
        .filter(|s| !after.iter().any(|a| a.0 == s.0))
    {
        assert!(touched(&s.1), "an untouched segment was re-segmented");
    }
    assert_covering(&mut engine, mesh.face_count());
    assert_eq!(engine.samples().len(), 20_000);

    // Despawning the mesh entity despawns its segments.
    engine.world.despawn(e);
    engine.schedule.run(&mut engine.world);
    assert!(engine.segments().is_empty());
}

/// A Bevy app keeps its schedules in the world (`Schedules`); the engine registers
/// into one of them with `World::schedule_scope`, and runs with `run_schedule`.
#[test]
fn registers_into_a_labelled_schedule_stored_in_the_world() {
    use bevy_ecs::schedule::ScheduleLabel;
    #[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
    struct Update;

    let mesh = Arc::new(strata_engine::mesh::shapes::sphere(1.0, 4).expect("sphere"));
    let field = projected(&mesh);
    let mut world = World::new();
    world.add_schedule(Schedule::new(Update));
    world.schedule_scope(Update, ecs::register);
    let e = world
        .spawn(MeshBundle::new(
            mesh,
            field,
            SurfaceOptions::default(),
            321,
            1,
        ))
        .id();
    // The first update starts the build off the frame; updates apply it when done.
    let start = std::time::Instant::now();
    loop {
        world.run_schedule(Update);
        if world.resource::<ecs::PreprocessJobs>().is_idle() || start.elapsed() > LIMIT {
            break;
        }
        world.resource_mut::<ecs::PreprocessJobs>().wait(LIMIT);
    }
    assert_eq!(
        world.get::<SampleBuffer>(e).map(|b| b.samples.len()),
        Some(321)
    );
    assert_eq!(world.resource::<StageStats>().runs_of(Stage::Sampling), 1);

    // Nothing changed: no sampling, unless requested once or asked for every update.
    world.run_schedule(Update);
    assert_eq!(world.resource::<StageStats>().runs_of(Stage::Sampling), 1);
    world.resource_mut::<ecs::SampleRequest>().0 = true;
    world.run_schedule(Update);
    world.run_schedule(Update);
    assert_eq!(world.resource::<StageStats>().runs_of(Stage::Sampling), 2);
    world
        .resource_mut::<ecs::EngineSettings>()
        .sample_every_update = true;
    world.run_schedule(Update);
    world.run_schedule(Update);
    assert_eq!(world.resource::<StageStats>().runs_of(Stage::Sampling), 4);
    assert_eq!(
        world.resource::<StageStats>().runs_of(Stage::Segmentation),
        1
    );
}

/// Issue 22: a count set by host code beyond what one request can index is an engine
/// error that keeps the last samples (it was an abort in the buffer's resize), and a
/// count that fits again samples as before.
#[test]
fn counts_beyond_a_request_are_errors_that_keep_the_samples() {
    let mesh = Arc::new(strata_engine::mesh::shapes::sphere(1.0, 4).expect("sphere"));
    let field = projected(&mesh);
    let mut engine = Engine::new(mesh, field, 500, 3);
    let good = engine.samples();
    assert_eq!(good.len(), 500);
    let set_count = |engine: &mut Engine, count: usize| {
        engine
            .world
            .get_mut::<SamplingSettings>(engine.mesh)
            .expect("settings")
            .count = count;
        engine.schedule.run(&mut engine.world);
        std::mem::take(&mut engine.world.resource_mut::<ecs::EngineErrors>().0)
    };
    let errors = set_count(&mut engine, (1 << 32) + 1);
    assert_eq!(errors.len(), 1, "{errors:?}");
    let message = errors[0].to_string();
    assert!(
        message.starts_with("sampling: at most 2^32") && message.contains("32-bit"),
        "{message}"
    );
    assert_eq!(engine.samples(), good, "last samples kept");
    assert!(set_count(&mut engine, 600).is_empty());
    assert_eq!(engine.samples().len(), 600);
}
