//! The engine as a Bevy plugin: a headless `App` with `StrataPlugin` preprocesses and
//! samples several mesh entities (on the mesh, with the counts asked for, the same bits
//! in a second app), and a change of one entity's sample count resamples that one only.
//!
//! Preprocessing may take several updates (it is meant to run off the frame), so the
//! tests update until the buffers are full, within a bounded time, never a fixed count.

use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy_app::{App, Update};
use bevy_ecs::prelude::*;
use strata_engine::fixtures::{constant, field_on};
use strata_engine::mesh::{TriMesh, shapes};
use strata_engine::sample::Sample;
use strata_engine::surface::SurfaceOptions;
use strata_systems::StrataPlugin;
use strata_systems::ecs::{
    EngineErrors, EngineSystems, MeshBundle, SampleBuffer, SamplingSettings, Stage, StageStats,
};

/// How long a test waits for the engine before it fails.
const TIMEOUT: Duration = Duration::from_secs(60);

/// A mesh entity of a test app and what it was spawned with.
struct Probe {
    entity: Entity,
    mesh: Arc<TriMesh>,
    count: usize,
}

fn constant_field(
    mesh: &TriMesh,
    direction: [f64; 3],
    anisotropy: f64,
) -> Arc<strata_engine::field::TensorField> {
    Arc::new(field_on(mesh, &constant(direction, anisotropy)))
}

/// An app with the plugin and two mesh entities: a sphere and a torus, with different
/// fields, counts and seeds.
fn two_mesh_app() -> (App, [Probe; 2]) {
    let mut app = App::new();
    app.add_plugins(StrataPlugin);
    let sphere = Arc::new(shapes::sphere(1.0, 4).expect("sphere"));
    let torus = Arc::new(shapes::torus(1.0, 0.4, 12).expect("torus"));
    let specs = [
        (sphere, [1.0, 0.3, 0.2], 3.0, 2_000, 11),
        (torus, [0.0, 0.0, 1.0], 1.5, 3_500, 5),
    ];
    let probes = specs.map(|(mesh, direction, anisotropy, count, seed)| {
        let field = constant_field(&mesh, direction, anisotropy);
        let bundle = MeshBundle::new(mesh.clone(), field, SurfaceOptions::default(), count, seed);
        let entity = app.world_mut().spawn(bundle).id();
        Probe {
            entity,
            mesh,
            count,
        }
    });
    (app, probes)
}

/// Updates `app` until `done` holds (checked after every update), failing on an engine
/// error or after [`TIMEOUT`].
fn update_until(app: &mut App, what: &str, done: impl Fn(&World) -> bool) {
    let start = Instant::now();
    loop {
        app.update();
        let errors = &app.world().resource::<EngineErrors>().0;
        assert!(errors.is_empty(), "{what}: engine errors {errors:?}");
        if done(app.world()) {
            return;
        }
        assert!(
            start.elapsed() < TIMEOUT,
            "{what}: not done within {TIMEOUT:?}"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn buffer(world: &World, e: Entity) -> &SampleBuffer {
    world.get::<SampleBuffer>(e).expect("sample buffer")
}

fn filled(world: &World, probes: &[Probe]) -> bool {
    probes
        .iter()
        .all(|p| buffer(world, p.entity).samples.len() == p.count)
}

/// Every field of every sample as bits, so that equal vectors mean bit-identical
/// samples (`==` on floats would also call 0.0 and -0.0 equal).
fn sample_bits(samples: &[Sample]) -> Vec<u32> {
    samples
        .iter()
        .flat_map(|s| {
            let floats = s
                .position
                .iter()
                .chain(&s.normal)
                .chain(&s.major_axis)
                .chain(&s.bary)
                .chain(&s.spacing)
                .map(|x| x.to_bits());
            [s.face, s.segment, s.index].into_iter().chain(floats)
        })
        .collect()
}

/// Each sample is on its face: a valid face index, barycentrics in the triangle, and
/// the position they give (the transform is the identity).
fn assert_on_mesh(samples: &[Sample], mesh: &TriMesh, what: &str) {
    let scale = mesh
        .positions()
        .iter()
        .map(|p| p.length())
        .fold(0.0, f64::max);
    for (i, s) in samples.iter().enumerate() {
        assert!(
            (s.face as usize) < mesh.face_count(),
            "{what}: sample {i} on face {} of {}",
            s.face,
            mesh.face_count()
        );
        let [b1, b2] = s.bary.map(f64::from);
        let b0 = 1.0 - b1 - b2;
        for b in [b0, b1, b2] {
            assert!(
                (-1e-5..=1.0 + 1e-5).contains(&b),
                "{what}: sample {i} barycentrics {:?}",
                s.bary
            );
        }
        let [p0, p1, p2] = mesh.face_positions(s.face);
        let expected = p0 * b0 + p1 * b1 + p2 * b2;
        let got = glam::DVec3::from(s.position.map(f64::from));
        assert!(
            (got - expected).length() <= 1e-5 * scale,
            "{what}: sample {i} at {got} is off its face ({expected})"
        );
    }
}

#[test]
fn plugin_app_samples_two_meshes_deterministically() {
    let (mut app, probes) = two_mesh_app();
    update_until(&mut app, "first app", |w| filled(w, &probes));

    let world = app.world();
    let stats = world.resource::<StageStats>();
    for (k, p) in probes.iter().enumerate() {
        let samples = &buffer(world, p.entity).samples;
        assert_eq!(samples.len(), p.count, "mesh {k}");
        assert_on_mesh(samples, &p.mesh, &format!("mesh {k}"));
        let segmented = stats
            .runs
            .iter()
            .filter(|r| r.stage == Stage::Segmentation && r.entity == p.entity)
            .map(|r| r.items)
            .sum::<usize>();
        assert!(segmented > 0, "mesh {k}: no segmentation recorded");
    }

    // A second app built the same way gives the same bits.
    let (mut again, again_probes) = two_mesh_app();
    update_until(&mut again, "second app", |w| filled(w, &again_probes));
    for (k, (p, q)) in probes.iter().zip(&again_probes).enumerate() {
        let first = &buffer(app.world(), p.entity).samples;
        let second = &buffer(again.world(), q.entity).samples;
        assert!(
            sample_bits(first) == sample_bits(second),
            "mesh {k}: the second app's samples differ"
        );
    }
}

#[test]
fn a_count_change_resamples_only_its_entity() {
    let (mut app, probes) = two_mesh_app();
    update_until(&mut app, "start", |w| filled(w, &probes));
    let [changed, other] = &probes;
    let before = app.world().resource::<StageStats>().update;
    let other_generation = buffer(app.world(), other.entity).generation;
    let other_bits = sample_bits(&buffer(app.world(), other.entity).samples);
    let changed_generation = buffer(app.world(), changed.entity).generation;

    let count = changed.count + 600;
    app.world_mut()
        .get_mut::<SamplingSettings>(changed.entity)
        .expect("sampling settings")
        .count = count;
    update_until(&mut app, "resampling", |w| {
        buffer(w, changed.entity).samples.len() == count
    });
    // A few more updates: nothing is left pending for the other entity either.
    for _ in 0..3 {
        app.update();
    }

    let world = app.world();
    let buf = buffer(world, changed.entity);
    assert!(
        buf.generation > changed_generation,
        "changed entity resampled"
    );
    assert_on_mesh(&buf.samples, &changed.mesh, "changed mesh");
    let untouched = buffer(world, other.entity);
    assert_eq!(
        untouched.generation, other_generation,
        "other entity resampled"
    );
    assert!(sample_bits(&untouched.samples) == other_bits);

    // A count change reruns sampling only, and only for its entity.
    let since: Vec<_> = world
        .resource::<StageStats>()
        .runs
        .iter()
        .filter(|r| r.update > before)
        .collect();
    assert!(
        since
            .iter()
            .all(|r| r.stage == Stage::Sampling && r.entity == changed.entity),
        "runs after the count change: {since:?}"
    );
    assert!(!since.is_empty(), "no sampling recorded for the change");
    assert!(world.resource::<EngineErrors>().0.is_empty());
}

/// Host systems in `Update` order themselves against the engine's sets: one after
/// `EngineSystems::Sample` sees a buffer in the update that filled it.
#[test]
fn host_systems_after_the_engine_see_fresh_samples() {
    #[derive(Resource, Default)]
    struct Seen(Vec<(usize, u64)>);

    fn watch_buffers(buffers: Query<&SampleBuffer, Changed<SampleBuffer>>, mut seen: ResMut<Seen>) {
        seen.0
            .extend(buffers.iter().map(|b| (b.samples.len(), b.generation)));
    }

    let mut app = App::new();
    app.add_plugins(StrataPlugin)
        .init_resource::<Seen>()
        .add_systems(Update, watch_buffers.after(EngineSystems::Sample));
    let mesh = Arc::new(shapes::sphere(1.0, 3).expect("sphere"));
    let field = constant_field(&mesh, [0.0, 1.0, 0.0], 2.0);
    let e = app
        .world_mut()
        .spawn(MeshBundle::new(
            mesh,
            field,
            SurfaceOptions::default(),
            700,
            3,
        ))
        .id();
    update_until(&mut app, "sampling", |w| buffer(w, e).samples.len() == 700);
    let generation = buffer(app.world(), e).generation;
    assert!(
        app.world()
            .resource::<Seen>()
            .0
            .contains(&(700, generation)),
        "the host system did not see the samples in the update that drew them"
    );
}
