//! [`StrataPlugin`]: the streaming engine ([`crate::ecs`]) as a `bevy_app` plugin, the
//! entry point for Bevy hosts. Adding it registers the engine's resources and systems
//! into the app's `Update` schedule with [`ecs::register`]; the host then spawns mesh
//! entities ([`MeshBundle`](crate::ecs::MeshBundle)) and reads their
//! [`SampleBuffer`](crate::ecs::SampleBuffer)s. Nothing else is added: no task pools,
//! no runner, no other schedules (with the `bevy-mesh` feature, the samples' `Mesh`
//! assets of `mesh_asset` too). Non-Bevy hosts call [`ecs::register`] on their own
//! `World` and `Schedule` instead; both paths run the same systems.
//!
//! Cost: one schedule registration at build time; per update, exactly what the
//! engine's systems cost (see [`crate::ecs`]).

use bevy_app::{App, Plugin, Update};

use crate::ecs;

/// Adds the streaming engine to a Bevy [`App`]: its resources (those of
/// [`ecs::register`], among them [`StageStats`](crate::ecs::StageStats),
/// [`EngineErrors`](crate::ecs::EngineErrors) and
/// [`EngineSettings`](crate::ecs::EngineSettings)) and its systems in the `Update`
/// schedule, ordered by [`EngineSystems`](crate::ecs::EngineSystems). Order a host's
/// systems against those sets, for example after `EngineSystems::Sample` to read the
/// samples in the update that drew them.
///
/// Spawn one entity per mesh with [`MeshBundle::new`](crate::ecs::MeshBundle::new); its
/// [`SampleBuffer`](crate::ecs::SampleBuffer) holds the samples once the mesh is
/// preprocessed and sampled. Preprocessing may take several updates (it runs off the
/// frame), so read the buffer when it holds the count asked for, or when its
/// `generation` moves, rather than after a fixed number of updates. Global settings
/// are the [`EngineSettings`](crate::ecs::EngineSettings) resource: change them after
/// adding the plugin (`app.insert_resource(EngineSettings { .. })`).
///
/// The plugin is unique (adding it twice panics, as for any unique Bevy plugin): the
/// engine's systems must run once per update.
///
/// ```
/// use std::sync::Arc;
/// use std::time::{Duration, Instant};
/// use bevy_app::App;
/// use strata_engine::{field::FieldSpec, mesh::shapes, surface::SurfaceOptions};
/// use strata_systems::StrataPlugin;
/// use strata_systems::ecs::{MeshBundle, SampleBuffer};
///
/// let mesh = Arc::new(shapes::sphere(1.0, 4)?);
/// let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 };
/// let field = Arc::new(field.build(&mesh)?);
/// let mut app = App::new();
/// app.add_plugins(StrataPlugin);
/// let options = SurfaceOptions::default();
/// let e = app.world_mut().spawn(MeshBundle::new(mesh, field, options, 500, 7)).id();
///
/// // Preprocessing may finish only after a few updates: update until the buffer is full.
/// let start = Instant::now();
/// let count = |app: &App| app.world().get::<SampleBuffer>(e).map(|b| b.samples.len());
/// while count(&app) != Some(500) && start.elapsed() < Duration::from_secs(60) {
///     app.update();
///     std::thread::sleep(Duration::from_millis(5));
/// }
/// assert_eq!(count(&app), Some(500), "no samples within 60 s");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct StrataPlugin;

impl Plugin for StrataPlugin {
    fn build(&self, app: &mut App) {
        // `App::new` creates `Update` only when a first system is added to it; the
        // engine registers through the world, which needs it to exist.
        app.init_schedule(Update);
        app.world_mut().schedule_scope(Update, ecs::register);
        // With `bevy-mesh`, each mesh entity's samples also become a `Mesh` asset.
        #[cfg(feature = "bevy-mesh")]
        app.world_mut()
            .schedule_scope(Update, crate::mesh_asset::register);
    }
}
