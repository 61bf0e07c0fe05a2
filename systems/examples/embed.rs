//! Embedding the streaming engine in a caller's bevy_ecs `World` and `Schedule`, driven
//! by hand (no files, no watcher): spawn a mesh entity, run the schedule, change one
//! component at a time and see which stages rerun.
//!
//! `cargo run --release -p strata-systems --example embed`

use std::sync::Arc;

use bevy_ecs::prelude::*;
use strata_engine::field::FieldSpec;
use strata_engine::mesh::shapes;
use strata_engine::surface::SurfaceOptions;
use strata_systems::ecs::{
    self, CurveSettings, FieldData, MeshBundle, SampleBuffer, SamplingSettings, StageStats,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mesh = Arc::new(shapes::torus(1.0, 0.4, 48)?);
    let field = |direction| {
        FieldSpec::Constant {
            direction,
            anisotropy: 3.0,
            density: 1.0,
        }
        .build(&mesh)
        .map(Arc::new)
    };

    // The caller's world and schedule (a Bevy app's would do).
    let mut world = World::new();
    let mut schedule = Schedule::default();
    ecs::register(&mut world, &mut schedule);
    let options = SurfaceOptions::default();
    let entity = world
        .spawn(MeshBundle::new(
            mesh.clone(),
            field([1.0, 0.3, 0.2])?,
            options,
            20_000,
            1,
        ))
        .id();

    let mut update = |world: &mut World, what: &str| {
        world.resource_mut::<StageStats>().clear();
        // Builds run off the frame; an application calls `schedule.run` every frame,
        // this example waits until each change's build is applied.
        ecs::settle(world, &mut schedule, std::time::Duration::from_secs(600));
        world.clear_trackers();
        let stats = world.resource::<StageStats>();
        println!("{what}:");
        for r in &stats.runs {
            println!(
                "  {:<17} {:>6} items {:>8.2} ms  {}",
                r.stage.name(),
                r.items,
                r.took.as_secs_f64() * 1e3,
                r.note
            );
        }
        let samples = world
            .get::<SampleBuffer>(entity)
            .map_or(0, |b| b.samples.len());
        println!("  -> {samples} samples");
    };

    update(&mut world, "first update");
    update(&mut world, "nothing changed");
    if let Some(mut s) = world.get_mut::<SamplingSettings>(entity) {
        s.count = 50_000;
    }
    update(&mut world, "sample count 50 000");
    if let Some(mut c) = world.get_mut::<CurveSettings>(entity) {
        c.0.max_cell_share = 1.0 / 16384.0;
    }
    update(&mut world, "coarser cells (omega)");
    if let Some(mut f) = world.get_mut::<FieldData>(entity) {
        f.0 = field([0.2, 0.3, 1.0])?;
    }
    update(&mut world, "new field everywhere");
    for e in world.resource::<ecs::EngineErrors>().0.iter() {
        eprintln!("error: {e}");
    }
    Ok(())
}
