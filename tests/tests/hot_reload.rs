//! Hot reload through real files in a temporary folder and the real watcher: each
//! change reruns only what it invalidates, bad saves keep the last good state and say
//! where they failed, deleted and re-created files recover, bursts of saves end in the
//! state of the last one. Every wait is bounded.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::DVec3;
use strata_engine::field::format_field_file;
use strata_engine::mesh::TriMesh;
use strata_systems::ecs::{SegmentFaces, Stage};
use strata_systems::hot_reload::{SceneState, StreamingEngine};
use strata_tests::shared_mesh_dir;

/// Longest wait for one change to show (preprocessing the bunny on a busy machine
/// included).
const LIMIT: Duration = Duration::from_secs(60);

/// Runs updates until `done` holds or `LIMIT` passes; true if it held.
fn wait_until(
    engine: &mut StreamingEngine,
    mut done: impl FnMut(&mut StreamingEngine) -> bool,
) -> bool {
    let start = Instant::now();
    loop {
        engine.update();
        if done(engine) {
            return true;
        }
        if start.elapsed() > LIMIT {
            return false;
        }
        engine.wait(Duration::from_millis(50));
    }
}

/// Saves like an editor that writes a temporary file and renames it over the target.
fn save_by_rename(path: &Path, text: &str) {
    let tmp = path.with_extension("ron.tmp~");
    std::fs::write(&tmp, text).expect("write temp");
    std::fs::rename(&tmp, path).expect("rename");
}

/// Saves in place (truncate and write).
fn save_in_place(path: &Path, text: &str) {
    std::fs::write(path, text).expect("write");
}

fn sphere_scene(count: u64) -> String {
    format!(
        "(\n    mesh: Shape(Sphere(radius: 1.0, resolution: 6)),\n    field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0),\n    sampling: (count: {count}, seed: 5),\n)\n"
    )
}

fn count_is(n: usize) -> impl FnMut(&mut StreamingEngine) -> bool {
    move |e: &mut StreamingEngine| e.samples().len() == n
}

#[test]
fn malformed_save_keeps_the_samples_and_reports_line_and_column() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("scene.ron");
    save_in_place(&scene, &sphere_scene(1000));
    let mut engine = StreamingEngine::watch(&scene).expect("watch");
    assert!(
        wait_until(&mut engine, count_is(1000)),
        "first scene applied"
    );
    let good = engine.samples().to_vec();
    let generation = engine.sample_generation();

    // Line 4 holds a negative count: a parse error at line 4.
    save_in_place(
        &scene,
        "(\n    mesh: Shape(Sphere(radius: 1.0, resolution: 6)),\n    field: Constant(direction: (1.0, 0.0, 0.0), anisotropy: 2.0, density: 1.0),\n    sampling: (count: -3, seed: 5),\n)\n",
    );
    let mut errors = Vec::new();
    assert!(
        wait_until(&mut engine, |e| {
            errors.extend(e.take_errors());
            !errors.is_empty()
        }),
        "the bad save was reported"
    );
    let message = errors[0].to_string();
    assert!(
        message.contains("scene.ron:4:") && message.split(':').count() >= 4,
        "file:line:column: {message}"
    );
    assert_eq!(engine.samples(), good.as_slice(), "last good samples kept");
    assert_eq!(engine.sample_generation(), generation);

    // A save that parses but does not validate: the option's line and column.
    save_by_rename(
        &scene,
        "(\n    mesh: Shape(Sphere(radius: 1.0, resolution: 6)),\n    sampling: (count: 900, seed: 5),\n    curve: (max_cell_share: 2.0),\n)\n",
    );
    errors.clear();
    assert!(
        wait_until(&mut engine, |e| {
            errors.extend(e.take_errors());
            !errors.is_empty()
        }),
        "the invalid save was reported"
    );
    let message = errors[0].to_string();
    assert!(
        message.contains("scene.ron:4:13: ") && message.contains("max_cell_share"),
        "{message}"
    );
    assert_eq!(engine.samples(), good.as_slice(), "last good samples kept");

    // The next good save applies.
    save_by_rename(&scene, &sphere_scene(1500));
    assert!(wait_until(&mut engine, count_is(1500)), "good save applied");
    assert!(engine.take_errors().is_empty());
}

/// Issue 22: a save asking for more samples than memory holds, or than a request can
/// index, is reported and changes nothing (it aborted the process).
#[test]
fn counts_beyond_memory_are_refused_keeping_the_samples() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("scene.ron");
    save_in_place(&scene, &sphere_scene(1000));
    let mut engine = StreamingEngine::watch(&scene).expect("watch");
    assert!(wait_until(&mut engine, count_is(1000)), "first scene");
    let good = engine.samples().to_vec();
    let mut cases = vec![(1u64 << 32) + 1];
    // 2^32 samples need 275 GB: refused by memory wherever there is less.
    let memory = strata_systems::budget::available_memory();
    if memory.is_some_and(|m| m < 64 << 32) {
        cases.push(1 << 32);
    }
    for count in cases {
        save_by_rename(&scene, &sphere_scene(count));
        let mut errors = Vec::new();
        assert!(
            wait_until(&mut engine, |e| {
                errors.extend(e.take_errors());
                !errors.is_empty()
            }),
            "{count}: reported"
        );
        let message = errors[0].to_string();
        let why = if count > 1 << 32 {
            "sample indices are 32-bit"
        } else {
            "of memory available"
        };
        assert!(message.contains(why), "{count}: {message}");
        assert_eq!(engine.samples(), good.as_slice(), "last good samples kept");
    }
    save_by_rename(&scene, &sphere_scene(1200));
    assert!(wait_until(&mut engine, count_is(1200)), "good save applied");
}

#[test]
fn a_scene_bad_at_startup_is_picked_up_when_fixed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("scene.ron");
    save_in_place(
        &scene,
        "(mesh: Shape(Sphere(radius: 1.0, resolution: 6)), colour: 3)",
    );
    let mut engine = StreamingEngine::watch(&scene).expect("watch");
    // The watcher sends the first scene (here: its error) once it has read it.
    assert!(
        engine.wait_for_change(LIMIT),
        "the first scene was not read"
    );
    engine.update();
    let errors = engine.take_errors();
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].to_string().contains("scene.ron:1:"),
        "{}",
        errors[0]
    );
    assert!(engine.samples().is_empty());
    save_by_rename(&scene, &sphere_scene(700));
    assert!(
        wait_until(&mut engine, count_is(700)),
        "fixed scene applied"
    );
}

#[test]
fn deleted_and_recreated_scene_recovers_and_bursts_end_in_the_last_state() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("scene.ron");
    save_in_place(&scene, &sphere_scene(400));
    let mut engine = StreamingEngine::watch(&scene).expect("watch");
    assert!(wait_until(&mut engine, count_is(400)));

    std::fs::remove_file(&scene).expect("delete");
    std::thread::sleep(Duration::from_millis(150)); // let the watcher see the deletion
    engine.update();
    assert_eq!(
        engine.samples().len(),
        400,
        "a deleted scene changes nothing"
    );
    save_in_place(&scene, &sphere_scene(450));
    assert!(
        wait_until(&mut engine, count_is(450)),
        "re-created scene applied"
    );

    // 100 saves in quick succession, alternating the two ways editors save.
    for i in 0..100u64 {
        let text = sphere_scene(500 + i);
        if i % 2 == 0 {
            save_in_place(&scene, &text);
        } else {
            save_by_rename(&scene, &text);
        }
    }
    assert!(wait_until(&mut engine, count_is(599)), "last save applied");
    // Nothing later arrives that would move it away from the last save.
    std::thread::sleep(Duration::from_millis(300));
    engine.update();
    assert_eq!(engine.samples().len(), 599);
    let state = engine.world.resource::<SceneState>();
    assert_eq!(state.config.as_ref().map(|c| c.sampling.count), Some(599));
    // Only parse errors of half-written files may have been reported, never a lost state.
    for e in engine.take_errors() {
        assert!(e.to_string().contains("scene.ron"), "{e}");
    }
}

/// The bunny written as PLY (so that its vertex order is the file's, for the field
/// file), a field file with a cap of about `share` of the faces turned, and a scene.
struct BunnyFiles {
    mesh: TriMesh,
    scene: PathBuf,
    field: PathBuf,
}

fn bunny_files(dir: &Path) -> Option<BunnyFiles> {
    let src = shared_mesh_dir()?.join("stanford-bunny.obj");
    let mesh = strata_engine::io::load(&src).expect("bunny");
    let ply = dir.join("bunny.ply");
    strata_engine::io::write_mesh_ply(&ply, &mesh, None).expect("write ply");
    let mesh = strata_engine::io::load(&ply).expect("reload");
    let field = dir.join("bunny.field");
    std::fs::write(
        &field,
        format_field_file(&strata_bench::cap_field(&mesh, f64::INFINITY, DVec3::Z).expect("field")),
    )
    .expect("field");
    let scene = dir.join("bunny.ron");
    Some(BunnyFiles { mesh, scene, field })
}

fn bunny_scene(count: u64, max_cell_share: f64) -> String {
    format!(
        "(\n    mesh: File(\"bunny.ply\"),\n    field: File(path: \"bunny.field\"),\n    sampling: (count: {count}, seed: 2),\n    curve: (max_cell_share: {max_cell_share:?}),\n)\n"
    )
}

fn segment_count(engine: &mut StreamingEngine) -> usize {
    engine
        .world
        .query::<&SegmentFaces>()
        .iter(&engine.world)
        .count()
}

#[test]
fn bunny_scene_changes_rerun_only_what_they_invalidate() {
    let dir = tempfile::tempdir().expect("tempdir");
    let Some(files) = bunny_files(dir.path()) else {
        eprintln!("skipped: shared meshes missing");
        return;
    };
    let share = 1.0 / 65536.0;
    save_in_place(&files.scene, &bunny_scene(20_000, share));
    let mut engine = StreamingEngine::watch(&files.scene).expect("watch");
    assert!(
        wait_until(&mut engine, count_is(20_000)),
        "bunny scene applied"
    );
    assert!(engine.take_errors().is_empty());
    let segments = segment_count(&mut engine);

    // Sample count only: sampling only.
    engine.clear_stats();
    save_by_rename(&files.scene, &bunny_scene(30_000, share));
    assert!(wait_until(&mut engine, count_is(30_000)));
    assert_eq!(
        engine.stats().stages_run(),
        vec![Stage::Scene, Stage::Sampling]
    );

    // Omega only: curves (every segment) and sampling; the chains are kept.
    engine.clear_stats();
    let generation = engine.sample_generation();
    save_in_place(&files.scene, &bunny_scene(30_000, share * 4.0));
    assert!(wait_until(&mut engine, |e| e.sample_generation() > generation));
    assert_eq!(
        engine.stats().stages_run(),
        vec![Stage::Scene, Stage::Curves, Stage::Sampling]
    );
    assert_eq!(engine.stats().items_of(Stage::Curves), segments);

    // The field file changes on a cap of about 10% of the faces (the scene file is
    // untouched): only the segments holding a changed vertex are redone.
    engine.clear_stats();
    let generation = engine.sample_generation();
    let cap = strata_bench::cap_height(&files.mesh, 0.1);
    let text =
        format_field_file(&strata_bench::cap_field(&files.mesh, cap, DVec3::Z).expect("field"));
    let tmp = dir.path().join("bunny.field.tmp");
    std::fs::write(&tmp, text).expect("write");
    std::fs::rename(&tmp, &files.field).expect("rename");
    assert!(wait_until(&mut engine, |e| e.sample_generation() > generation));
    assert!(engine.take_errors().is_empty());
    let stats = engine.stats().clone();
    assert_eq!(
        stats.stages_run(),
        vec![
            Stage::Scene,
            Stage::Segmentation,
            Stage::Parameterization,
            Stage::Curves,
            Stage::Chains,
            Stage::Sampling
        ]
    );
    let redone = stats.items_of(Stage::Parameterization);
    assert_eq!(redone, stats.items_of(Stage::Segmentation));
    assert_eq!(redone, stats.items_of(Stage::Curves));
    let now = segment_count(&mut engine);
    assert!(
        redone > 0 && redone < now / 2,
        "{redone} of {now} segments redone"
    );
    assert_eq!(engine.samples().len(), 30_000);

    // The mesh file rewritten on disk is reloaded; identical content keeps every
    // segment (the same content: nothing is segmented again).
    engine.clear_stats();
    let generation = engine.sample_generation();
    let segments_before = segment_count(&mut engine);
    strata_engine::io::write_mesh_ply(&dir.path().join("bunny.ply"), &files.mesh, None)
        .expect("rewrite mesh");
    let builds = engine.builds().completed;
    assert!(wait_until(&mut engine, |e| e.builds().completed > builds
        && e.is_idle()));
    assert_eq!(
        engine.sample_generation(),
        generation,
        "nothing to resample: {:?}",
        engine.stats().runs
    );
    let stats = engine.stats();
    let scene_note = &stats.runs[0].note;
    assert!(scene_note.contains("mesh"), "{scene_note}");
    // The same positions, triangles and tensors: nothing to segment again.
    assert_eq!(stats.stages_run(), vec![Stage::Scene], "{:?}", stats.runs);
    assert_eq!(segment_count(&mut engine), segments_before);
}

#[test]
fn strata_watch_writes_the_samples_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("scene.ron");
    save_in_place(&scene, &sphere_scene(1234));
    let out = dir.path().join("samples.ply");
    let argv = [
        "strata",
        "watch",
        scene.to_str().expect("utf-8 path"),
        "--out",
        out.to_str().expect("utf-8 path"),
        "--updates",
        "1",
    ];
    let cli = <strata_systems::cli::Cli as clap::Parser>::try_parse_from(argv).expect("args");
    strata_systems::cli::run(cli).expect("strata watch");
    let samples = strata_engine::io::read_samples_ply(&out).expect("samples file");
    assert_eq!(samples.len(), 1234);
    // No temporary file left beside it.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .expect("dir")
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

/// `strata watch` refuses an output folder that is missing at the start (before any
/// work), but one that goes missing while it runs costs only that write: it reports
/// the failed write, keeps running, and writes after the next change.
#[test]
fn strata_watch_survives_a_missing_output_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = dir.path().join("scene.ron");
    save_in_place(&scene, &sphere_scene(1000));
    let folder = dir.path().join("out");
    let out = folder.join("samples.ply");
    let argv = |updates: &str| -> Vec<String> {
        let words = [
            "strata",
            "watch",
            scene.to_str().expect("utf-8 path"),
            "--out",
        ];
        let mut argv: Vec<String> = words.map(str::to_owned).into();
        argv.extend([
            out.to_string_lossy().into_owned(),
            "--updates".into(),
            updates.into(),
        ]);
        argv
    };
    // Missing at the start: refused before any work, naming the folder.
    let cli = <strata_systems::cli::Cli as clap::Parser>::try_parse_from(argv("1")).expect("args");
    let error = strata_systems::cli::run(cli).expect_err("a missing folder is refused");
    assert!(error.to_string().contains("does not exist"), "{error}");

    std::fs::create_dir(&folder).expect("create the output folder");
    let argv = argv("3");
    let watch = std::thread::spawn(move || {
        let cli = <strata_systems::cli::Cli as clap::Parser>::try_parse_from(argv)?;
        strata_systems::cli::run(cli)
    });
    let wait_for = |len: usize| {
        let start = Instant::now();
        while start.elapsed() < LIMIT {
            if strata_engine::io::read_samples_ply(&out).is_ok_and(|s| s.len() == len) {
                return true;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        false
    };
    assert!(wait_for(1000), "the first update was not written");
    // The folder goes away: the next update's write fails, and watch keeps running.
    std::fs::remove_dir_all(&folder).expect("remove the output folder");
    save_in_place(&scene, &sphere_scene(1100));
    std::thread::sleep(Duration::from_secs(2));
    assert!(!watch.is_finished(), "watch stopped after a failed write");
    std::fs::create_dir(&folder).expect("create the output folder again");
    save_in_place(&scene, &sphere_scene(1300));
    let start = Instant::now();
    while !watch.is_finished() && start.elapsed() < LIMIT {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(watch.is_finished(), "watch did not apply the edit");
    watch.join().expect("no panic").expect("strata watch");
    let samples = strata_engine::io::read_samples_ply(&out).expect("samples file");
    assert_eq!(samples.len(), 1300);
}
