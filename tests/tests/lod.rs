//! View-dependent level of detail on the GPU (issue 19): a resident progressive pool,
//! the rank cull of the splat pipelines checked against the CPU's visible set, and
//! samples carried by a deforming mesh. On whatever adapter wgpu finds; without one
//! these tests print a skip line (`gpu::gpu`).

use std::path::Path;
use std::sync::Arc;

use glam::{DVec3, Vec3};
use strata_engine::mesh::TriMesh;
use strata_engine::sample::{Budget, LodPool, PoolChange};
use strata_systems::config::SceneConfig;
use strata_systems::gpu::{
    GpuLodPool, GpuSampleBuffer, LodFades, OrbitCamera, SiteExpander, SplatLod, SplatStyle,
};
use strata_systems::scene::Scene;

use crate::gpu::gpu;

/// A torus (radii 1 and 0.4) with a 3:1 field.
fn torus() -> Scene {
    let ron = "(mesh: Shape(Torus(major_radius: 1.0, minor_radius: 0.4, resolution: 24)), \
         field: Constant(direction: (1.0, 0.3, 0.2), anisotropy: 3.0, density: 1.0))";
    let config = SceneConfig::from_ron(ron, Path::new("test.ron")).expect("parses");
    Scene::build(&config).expect("builds")
}

const SIZE: (u32, u32) = (320, 240);
const BASE: f64 = 20_000.0;

fn lod() -> SplatLod {
    SplatLod {
        base: BASE as f32,
        expanded: BASE as f32,
        reference: 4000.0,
        max: 8.0,
        cull_back_faces: true,
    }
}

fn camera(distance: f32, yaw: f32) -> OrbitCamera {
    OrbitCamera {
        target: Vec3::ZERO,
        distance,
        yaw,
        pitch: 0.5,
        fov_y: 40f32.to_radians(),
        radius: 1.4,
    }
}

/// The GPU's fade weights agree with the CPU's entry by entry, except where the
/// threshold `N lod` falls within f32 round-off of the rank; the pool is synced by
/// appending only what each view adds.
#[test]
fn the_gpu_cull_gives_the_cpu_visible_set() {
    let Some(ctx) = gpu("the_gpu_cull_gives_the_cpu_visible_set") else {
        return;
    };
    let scene = torus();
    let s = &scene.sampler;
    let expander = SiteExpander::new(&ctx.device, s).expect("expander");
    let fades = LodFades::new(&ctx.device).expect("fade pass");
    let mut pool = LodPool::new(s, 5, BASE as u32, 2_000_000);
    let mut gpu_pool = GpuLodPool::new(&ctx.device, BASE).expect("pool");
    let mut samples = GpuSampleBuffer::new(&ctx.device).expect("buffer");
    let style = SplatStyle {
        lod: Some(lod()),
        ..SplatStyle::default()
    };
    let mut first = true;
    for (distance, yaw) in [(5.0, 0.3), (3.5, 0.35), (2.6, 0.4)] {
        let cam = camera(distance, yaw);
        let view = lod().view(&cam, SIZE);
        let change = pool
            .update(s, &view, Budget::Base(BASE))
            .expect("the pool's sampler")
            .change;
        let held = gpu_pool.len();
        let bytes = gpu_pool
            .sync(
                &ctx.device,
                &ctx.queue,
                &pool,
                &change,
                &expander,
                &mut samples,
            )
            .expect("sync");
        let sent = if first { pool.len() } else { pool.len() - held };
        assert_eq!(bytes, sent as u64 * 20, "only new entries are sent");
        if !first {
            assert!(matches!(change, PoolChange::Appended(_)), "{change:?}");
        }
        first = false;
        let gpu = fades
            .fades(&ctx.device, &ctx.queue, &samples, &cam, &style, SIZE)
            .expect("fades");
        let mut cpu = vec![0.0f32; pool.len()];
        pool.fades_into(s, &view, BASE, &mut cpu);
        assert_eq!(gpu.len(), cpu.len());
        let (mut shown, mut differ) = (0, 0);
        for (i, (&g, &c)) in gpu.iter().zip(&cpu).enumerate() {
            shown += usize::from(c > 0.0);
            if (g > 0.0) != (c > 0.0) {
                differ += 1;
                let rank = f64::from(pool.ranks()[i]);
                // Only a threshold within round-off of the rank may disagree.
                let site = pool.sites()[i];
                let r = s
                    .record(site.face, site.barycentric().map(f64::from), 0, 0, 1)
                    .expect("record");
                let m = view.multiplier(
                    DVec3::from(r.position.map(f64::from)),
                    DVec3::from(r.normal.map(f64::from)),
                );
                assert!(
                    (BASE * m - rank).abs() <= 1e-3 * BASE * m + 1.0,
                    "entry {i}: rank {rank}, threshold {}",
                    BASE * m
                );
            }
        }
        assert!(shown > 5000, "{shown} shown at distance {distance}");
        assert!(differ * 1000 <= shown, "{differ} of {shown} differ");
    }
    // A view that needs nothing new: nothing is sent.
    let view = lod().view(&camera(2.6, 0.4), SIZE);
    let change = pool
        .update(s, &view, Budget::Base(BASE))
        .expect("the pool's sampler")
        .change;
    assert_eq!(change, PoolChange::Unchanged);
    let bytes = gpu_pool
        .sync(
            &ctx.device,
            &ctx.queue,
            &pool,
            &change,
            &expander,
            &mut samples,
        )
        .expect("sync");
    assert_eq!(bytes, 0);
}

/// After a deformation of the mesh, re-expanded pool samples lie on the deformed
/// surface at their barycentric coordinates; nothing is resampled or uploaded.
#[test]
fn a_deformed_mesh_carries_its_samples() {
    let Some(ctx) = gpu("a_deformed_mesh_carries_its_samples") else {
        return;
    };
    let scene = torus();
    let s = &scene.sampler;
    let expander = SiteExpander::new(&ctx.device, s).expect("expander");
    let mut pool = LodPool::new(s, 2, 5000, 0);
    let mut gpu_pool = GpuLodPool::new(&ctx.device, 5000.0).expect("pool");
    let mut samples = GpuSampleBuffer::new(&ctx.device).expect("buffer");
    let view = lod().view(&camera(4.0, 0.0), SIZE);
    let change = pool
        .update(s, &view, Budget::Base(5000.0))
        .expect("the pool's sampler")
        .change;
    gpu_pool
        .sync(
            &ctx.device,
            &ctx.queue,
            &pool,
            &change,
            &expander,
            &mut samples,
        )
        .expect("sync");
    // A twist about z and a stretch along it.
    let mesh = s.mesh();
    let moved: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|p| {
            let (sin, cos) = (0.8 * p.z).sin_cos();
            DVec3::new(
                cos * p.x - sin * p.y,
                sin * p.x + cos * p.y,
                1.7 * p.z + 0.2,
            )
        })
        .collect();
    let deformed = Arc::new(TriMesh::new(moved, mesh.triangles().to_vec()).expect("mesh"));
    expander
        .set_geometry(&ctx.queue, &deformed)
        .expect("same topology");
    gpu_pool
        .reexpand(&ctx.device, &ctx.queue, &expander, &samples)
        .expect("reexpand");
    let back = samples
        .read_back(&ctx.device, &ctx.queue)
        .expect("read back");
    assert_eq!(back.len(), pool.len());
    for (i, (got, site)) in back.iter().zip(pool.sites()).enumerate() {
        assert_eq!(got.index, pool.ranks()[i], "entry {i} carries its rank");
        let expected = site.position_on(&deformed).expect("a face of the mesh");
        let p = DVec3::from(got.position.map(f64::from));
        assert!(
            p.distance(expected) < 1e-5,
            "entry {i}: {p} against {expected}"
        );
    }
    // The wrong topology is a typed error.
    let small =
        TriMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).expect("triangle");
    let err = expander
        .set_geometry(&ctx.queue, &small)
        .expect_err("mismatch");
    assert!(
        err.to_string().contains("deformed mesh does not match"),
        "{err}"
    );
}

/// `strata render --lod --frames 3 --dolly 0.8 --twist 30`: a numbered PNG per frame
/// of a twisting mesh seen from a camera moving in.
#[test]
fn render_command_writes_a_lod_sequence() {
    let Some(_ctx) = gpu("render_command_writes_a_lod_sequence") else {
        return;
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/sphere-anisotropic.ron");
    let out = dir.path().join("seq.png");
    // `strata render config --out out ...`, 160 x 120.
    let render = |out: &Path, options: &[&str]| {
        use clap::Parser;
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "strata".as_ref(),
            "render".as_ref(),
            config.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ];
        args.extend(
            ["--width", "160", "--height", "120"]
                .iter()
                .chain(options)
                .map(|o: &&str| std::ffi::OsStr::new(*o)),
        );
        strata_systems::cli::Cli::try_parse_from(args)
    };
    let lod_options = ["-n", "3000", "--lod", "--frames", "3", "--dolly", "0.8"];
    let sequence = [&lod_options[..], &["--orbit", "2", "--twist", "30"]].concat();
    let cli = render(&out, &sequence).expect("arguments parse");
    strata_systems::cli::run(cli).expect("render succeeds");
    for frame in 0..3 {
        let png = dir.path().join(format!("seq_{frame:04}.png"));
        let bytes = std::fs::read(&png).expect("frame written");
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", png.display());
    }
    assert!(!out.exists(), "a sequence writes numbered frames only");
    // With a point budget.
    let budget = dir.path().join("budget.png");
    let cli = render(&budget, &["-n", "3000", "--lod", "--lod-shown", "2000"]).expect("parse");
    strata_systems::cli::run(cli).expect("render succeeds");
    assert!(budget.exists());
    let zero = render(&budget, &["--lod", "--lod-shown", "0"]).expect("arguments parse");
    let error = strata_systems::cli::run(zero).expect_err("a budget of nothing");
    assert!(error.to_string().contains("--lod-shown"), "{error}");
    // The level-of-detail options need --lod.
    for option in [["--frames", "3"], ["--lod-shown", "2000"]] {
        assert!(render(&out, &option).is_err(), "{option:?} without --lod");
    }
}

/// Runs the ECS engine until its jobs are done and returns entity `e`'s sampler.
fn settled_sampler(
    world: &mut bevy_ecs::prelude::World,
    schedule: &mut bevy_ecs::prelude::Schedule,
    e: bevy_ecs::entity::Entity,
) -> strata_engine::sample::Sampler {
    use strata_systems::ecs::{self, MeshSampler};
    assert!(ecs::settle(
        world,
        schedule,
        std::time::Duration::from_secs(120)
    ));
    world
        .get::<MeshSampler>(e)
        .and_then(|s| s.0.clone())
        .expect("sampler")
}

/// The ECS engine: a mesh entity with a `Lod` keeps a pool that follows its camera,
/// and the upload system sends only the entries each update appends.
#[test]
fn ecs_lod_pools_follow_the_camera() {
    use bevy_ecs::prelude::{Schedule, World};
    use strata_engine::surface::SurfaceOptions;
    use strata_systems::ecs::{self, Lod, LodState, MeshBundle};
    use strata_systems::gpu::{GpuSplats, SplatRenderer, upload};
    let Some(ctx) = gpu("ecs_lod_pools_follow_the_camera") else {
        return;
    };
    let scene = torus();
    let target = strata_systems::gpu::HeadlessTarget::new(&ctx.device, 16, 16, 1).expect("target");
    let renderer = SplatRenderer::new(&ctx.device, target.format()).expect("renderer");
    let mut world = World::new();
    let mut schedule = Schedule::default();
    ecs::register(&mut world, &mut schedule);
    upload::register(&mut schedule);
    world.insert_resource(GpuSplats::new(ctx, renderer));
    let settings = SurfaceOptions::default();
    let lod_at = |distance: f32| Lod {
        view: lod().view(&camera(distance, 0.3), SIZE),
        base: 20_000,
        budget: 1_000_000,
        shown: None,
    };
    let e = world
        .spawn((
            MeshBundle::new(scene.mesh.clone(), scene.field.clone(), settings, 100, 5),
            lod_at(5.0),
            LodState::default(),
        ))
        .id();
    assert!(ecs::settle(
        &mut world,
        &mut schedule,
        std::time::Duration::from_secs(120)
    ));
    let entries = |world: &World| {
        let state = world.get::<LodState>(e).expect("state");
        (state.pool.as_ref().map_or(0, |p| p.len()), state.builds)
    };
    let (first, builds) = entries(&world);
    assert!(
        first >= 20_000 && builds == 1,
        "{first} entries, {builds} builds"
    );
    let gpu = world.resource::<GpuSplats>();
    assert_eq!(gpu.lod_entries(), first);
    assert_eq!(gpu.renderer.samples().len(), first);
    let uploads = gpu.last.uploads;
    // Closer: the pool grows and only the new entries are sent.
    *world.get_mut::<Lod>(e).expect("lod") = lod_at(2.5);
    schedule.run(&mut world);
    let (second, builds) = entries(&world);
    assert!(second > first && builds == 1, "{second} after {first}");
    let gpu = world.resource::<GpuSplats>();
    assert_eq!(gpu.last.count, second - first);
    assert_eq!(gpu.lod_entries(), second);
    assert_eq!(
        world.get::<LodState>(e).and_then(|s| s.last.clone()),
        Some(PoolChange::Appended(first..second))
    );
    // The same view: nothing drawn, nothing sent.
    schedule.run(&mut world);
    assert_eq!(entries(&world).0, second);
    assert_eq!(world.resource::<GpuSplats>().last.uploads, uploads + 1);
    // A new base count rebuilds the pool, off the frame: the update that sees it keeps
    // the old pool; the new one is in use once it is built.
    world.get_mut::<Lod>(e).expect("lod").base = 10_000;
    schedule.run(&mut world);
    assert_eq!(entries(&world).1, 1);
    assert!(ecs::settle(
        &mut world,
        &mut schedule,
        std::time::Duration::from_secs(120)
    ));
    assert_eq!(entries(&world).1, 2);
    assert_eq!(
        world.resource::<GpuSplats>().lod_entries(),
        entries(&world).0
    );
}

/// The ECS engine on a mesh placed by a similarity: the pool follows the world camera
/// taken into the mesh's frame (so it holds what a renderer of the placed mesh shows),
/// and a transform that is not a similarity is an engine error that keeps the pool.
/// CPU only.
#[test]
fn ecs_lod_pools_follow_a_placed_mesh() {
    use bevy_ecs::prelude::{Schedule, World};
    use glam::{DAffine3, DMat3, DQuat};
    use strata_engine::surface::SurfaceOptions;
    use strata_systems::ecs::{
        self, EngineError, EngineErrors, Lod, LodState, MeshBundle, MeshTransform,
    };
    let scene = torus();
    let mut world = World::new();
    let mut schedule = Schedule::default();
    ecs::register(&mut world, &mut schedule);
    let placed = DAffine3::from_scale_rotation_translation(
        DVec3::splat(2.0),
        DQuat::from_euler(glam::EulerRot::XYZ, 0.4, 0.0, -0.7),
        DVec3::new(3.0, 0.0, 0.0),
    );
    let view = lod().view(
        &OrbitCamera {
            target: Vec3::new(3.0, 0.0, 0.0),
            ..camera(5.0, 0.3)
        },
        SIZE,
    );
    let mut bundle = MeshBundle::new(
        scene.mesh.clone(),
        scene.field.clone(),
        SurfaceOptions::default(),
        100,
        5,
    );
    bundle.transform = MeshTransform(placed);
    let e = world
        .spawn((
            bundle,
            Lod {
                view,
                base: BASE as u32,
                budget: 1_000_000,
                shown: None,
            },
            LodState::default(),
        ))
        .id();
    let sampler = settled_sampler(&mut world, &mut schedule, e);
    let held = |world: &World| {
        let state = world.get::<LodState>(e).expect("state");
        state.pool.as_ref().expect("pool").ranks().to_vec()
    };
    let ranks = held(&world);
    // The same pool as one updated directly with the camera in the mesh's frame...
    let local = view.in_local_frame(&placed).expect("similarity");
    let mut direct = LodPool::new(&sampler, 5, BASE as u32, 1_000_000);
    direct
        .update(&sampler, &local, Budget::Base(BASE))
        .expect("the pool's sampler");
    assert!(direct.complete(&local, BASE));
    assert_eq!(ranks, direct.ranks());
    // ... and not the one the untransformed camera asks for (the bug this fixes).
    let mut ignored = LodPool::new(&sampler, 5, BASE as u32, 1_000_000);
    ignored
        .update(&sampler, &view, Budget::Base(BASE))
        .expect("the pool's sampler");
    assert_ne!(ranks, ignored.ranks());
    // A shear: an engine error, and the pool is kept.
    world.get_mut::<MeshTransform>(e).expect("transform").0 = DAffine3::from_mat3(
        DMat3::from_cols(DVec3::X, DVec3::new(0.5, 1.0, 0.0), DVec3::Z),
    );
    world.resource_mut::<EngineErrors>().0.clear();
    schedule.run(&mut world);
    let errors = &world.resource::<EngineErrors>().0;
    assert!(
        errors.iter().any(|e| matches!(e, EngineError::Lod(_))),
        "{errors:?}"
    );
    let message = errors
        .iter()
        .find(|e| matches!(e, EngineError::Lod(_)))
        .map(ToString::to_string)
        .unwrap_or_default();
    assert!(message.contains("similarity"), "{message}");
    assert_eq!(held(&world), ranks);
}

/// A point budget in the ECS engine: each update thresholds with the base count that
/// shows about the budget under its camera, far or near, and the pool holds every
/// sample that base count shows. CPU only.
#[test]
fn ecs_lod_point_budget_holds_the_shown_count() {
    use bevy_ecs::prelude::{Schedule, World};
    use strata_engine::surface::SurfaceOptions;
    use strata_systems::ecs::{self, Lod, LodState, MeshBundle};
    const SHOWN: u32 = 8000;
    let scene = torus();
    let mut world = World::new();
    let mut schedule = Schedule::default();
    ecs::register(&mut world, &mut schedule);
    let lod_at = |distance: f32| Lod {
        view: lod().view(&camera(distance, 0.3), SIZE),
        base: BASE as u32,
        budget: 1_000_000,
        shown: Some(SHOWN),
    };
    let e = world
        .spawn((
            MeshBundle::new(
                scene.mesh.clone(),
                scene.field.clone(),
                SurfaceOptions::default(),
                100,
                5,
            ),
            lod_at(5.0),
            LodState::default(),
        ))
        .id();
    let sampler = settled_sampler(&mut world, &mut schedule, e);
    let mut bases = vec![];
    for distance in [5.0, 3.5, 2.5] {
        *world.get_mut::<Lod>(e).expect("lod") = lod_at(distance);
        schedule.run(&mut world);
        let state = world.get::<LodState>(e).expect("state");
        let pool = state.pool.as_ref().expect("pool");
        let view = lod_at(distance).view;
        assert!(pool.complete(&view, state.base), "distance {distance}");
        let mut fades = vec![0.0f32; pool.len()];
        pool.fades_into(&sampler, &view, state.base, &mut fades);
        let shown = fades.iter().filter(|&&f| f > 0.0).count() as f64;
        assert!(
            (shown / f64::from(SHOWN) - 1.0).abs() < 0.04,
            "distance {distance}: {shown} shown, base {}",
            state.base
        );
        assert_eq!(state.base, f64::from(state.base as f32), "an f32 base");
        bases.push(state.base);
    }
    // Nearer, each unit of surface covers more pixels: a smaller base count.
    assert!(bases[0] > bases[1] && bases[1] > bases[2], "{bases:?}");
    // Without a budget, the base count is the component's.
    world.get_mut::<Lod>(e).expect("lod").shown = None;
    schedule.run(&mut world);
    assert_eq!(world.get::<LodState>(e).expect("state").base, BASE);
}

/// A point budget on the GPU: every frame of a dolly shows about the budget, the
/// GPU's visible set is the CPU's for the frame's base count, and splats keep the size
/// of the density they show (their spacings scaled by `sqrt(expanded / base)`).
#[test]
fn a_gpu_point_budget_holds_the_shown_count() {
    use strata_systems::gpu::{LodScene, SplatRenderer};
    let Some(ctx) = gpu("a_gpu_point_budget_holds_the_shown_count") else {
        return;
    };
    const SHOWN: u32 = 8000;
    let scene = torus();
    let s = &scene.sampler;
    let target = strata_systems::gpu::HeadlessTarget::new(&ctx.device, 16, 16, 1).expect("target");
    let mut renderer = SplatRenderer::new(&ctx.device, target.format()).expect("renderer");
    let mut lod_scene = LodScene::new(&ctx.device, s, 5, lod(), 1_000_000)
        .expect("scene")
        .with_shown(SHOWN);
    let fades = LodFades::new(&ctx.device).expect("fade pass");
    let mut bases = vec![];
    for distance in [5.0, 3.5, 2.5] {
        let cam = camera(distance, 0.3);
        lod_scene
            .frame(
                &ctx.device,
                &ctx.queue,
                s,
                renderer.samples_mut(),
                &cam,
                SIZE,
            )
            .expect("frame");
        let style = lod_scene.style(&SplatStyle::default());
        let l = style.lod.expect("level of detail");
        assert_eq!(l.expanded, BASE as f32, "expanded for the prefix");
        let gpu = fades
            .fades(
                &ctx.device,
                &ctx.queue,
                renderer.samples(),
                &cam,
                &style,
                SIZE,
            )
            .expect("fades");
        let mut cpu = vec![0.0f32; gpu.len()];
        let view = lod_scene.lod().view(&cam, SIZE);
        lod_scene
            .pool()
            .fades_into(s, &view, f64::from(l.base), &mut cpu);
        let shown = gpu.iter().filter(|&&f| f > 0.0).count();
        let differ = gpu
            .iter()
            .zip(&cpu)
            .filter(|&(&g, &c)| (g > 0.0) != (c > 0.0))
            .count();
        assert!(
            (shown as f64 / f64::from(SHOWN) - 1.0).abs() < 0.04,
            "distance {distance}: {shown} shown"
        );
        assert!(differ * 1000 <= shown, "{differ} of {shown} differ");
        bases.push(l.base);
    }
    assert!(bases[0] > bases[1] && bases[1] > bases[2], "{bases:?}");
}
