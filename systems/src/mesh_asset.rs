//! The samples of each mesh entity as a bevy_mesh [`Mesh`] in [`Assets<Mesh>`] (feature
//! `bevy-mesh`), so that a Bevy app draws them with its own material: a point list
//! whose vertex `k` is sample `k`, with positions, normals and two custom attributes,
//! [`ATTRIBUTE_SPACING`] and [`ATTRIBUTE_MAJOR_AXIS`], for a splat material that
//! orients and sizes each point along the field.
//!
//! [`write_sample_meshes`] runs after [`EngineSystems::Sample`]: a mesh entity whose
//! [`SampleBuffer`] moved to a new generation gets its asset rewritten in place (its
//! attribute vectors reused, so a steady count allocates nothing), or, the first time,
//! a new asset, a [`SampleMesh`] with its handle and a [`Mesh3d`] for Bevy's renderer.
//!
//! Cost: O(samples) copies per rewritten buffer; nothing for unchanged ones.

use bevy_asset::{Assets, Handle, RenderAssetUsages};
use bevy_ecs::prelude::*;
use bevy_mesh::{
    Mesh, Mesh3d, MeshVertexAttribute, PrimitiveTopology, VertexAttributeValues, VertexFormat,
};
use strata_engine::sample::Sample;

use crate::ecs::{EngineSystems, SampleBuffer};

/// Per-sample spacing along the major and the minor axis (world units), two floats:
/// [`Sample::spacing`].
pub const ATTRIBUTE_SPACING: MeshVertexAttribute =
    MeshVertexAttribute::new("Strata_Spacing", 0x5354_5241_0001, VertexFormat::Float32x2);

/// Per-sample unit tangent of densest spacing, three floats: [`Sample::major_axis`]
/// (the minor axis is `normal x major_axis`).
pub const ATTRIBUTE_MAJOR_AXIS: MeshVertexAttribute = MeshVertexAttribute::new(
    "Strata_MajorAxis",
    0x5354_5241_0002,
    VertexFormat::Float32x3,
);

/// The sample mesh of a mesh entity: the handle of its asset and the
/// [`SampleBuffer::generation`] the asset holds.
#[derive(Component, Clone, Debug)]
pub struct SampleMesh {
    /// The asset in [`Assets<Mesh>`].
    pub handle: Handle<Mesh>,
    /// The sample buffer's generation written into it.
    pub generation: u64,
}

/// Registers [`write_sample_meshes`] after sampling, and an [`Assets<Mesh>`] resource
/// when the app has none (a headless app without Bevy's asset plugin).
pub fn register(world: &mut World, schedule: &mut Schedule) {
    if !world.contains_resource::<Assets<Mesh>>() {
        world.init_resource::<Assets<Mesh>>();
    }
    schedule.add_systems(write_sample_meshes.after(EngineSystems::Sample));
}

/// Writes each changed sample buffer into its entity's mesh asset (module docs).
pub fn write_sample_meshes(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut buffers: Query<(Entity, &SampleBuffer, Option<&mut SampleMesh>)>,
) {
    for (entity, buffer, existing) in &mut buffers {
        match existing {
            Some(state) if state.generation == buffer.generation => {}
            Some(mut state) => {
                let rewritten = match meshes.get_mut(&state.handle) {
                    Some(mut mesh) => {
                        fill(&mut mesh, &buffer.samples);
                        true
                    }
                    None => false,
                };
                if !rewritten {
                    // The app removed the asset: make it again.
                    let handle = meshes.add(new_mesh(&buffer.samples));
                    commands.entity(entity).insert(Mesh3d(handle.clone()));
                    state.handle = handle;
                }
                state.generation = buffer.generation;
            }
            None => {
                let handle = meshes.add(new_mesh(&buffer.samples));
                commands.entity(entity).insert((
                    Mesh3d(handle.clone()),
                    SampleMesh {
                        handle,
                        generation: buffer.generation,
                    },
                ));
            }
        }
    }
}

/// A point list of `samples`.
fn new_mesh(samples: &[Sample]) -> Mesh {
    let mut mesh = Mesh::new(PrimitiveTopology::PointList, RenderAssetUsages::default());
    fill(&mut mesh, samples);
    mesh
}

/// Writes `samples` into `mesh`'s attributes, reusing their vectors.
fn fill(mesh: &mut Mesh, samples: &[Sample]) {
    let vec3 = |get: fn(&Sample) -> [f32; 3]| move |s: &Sample| get(s);
    put3(
        mesh,
        Mesh::ATTRIBUTE_POSITION,
        samples,
        vec3(|s| s.position),
    );
    put3(mesh, Mesh::ATTRIBUTE_NORMAL, samples, vec3(|s| s.normal));
    put3(mesh, ATTRIBUTE_MAJOR_AXIS, samples, vec3(|s| s.major_axis));
    match mesh.attribute_mut(ATTRIBUTE_SPACING) {
        Some(VertexAttributeValues::Float32x2(values)) => {
            values.clear();
            values.extend(samples.iter().map(|s| s.spacing));
        }
        _ => {
            let values: Vec<[f32; 2]> = samples.iter().map(|s| s.spacing).collect();
            mesh.insert_attribute(ATTRIBUTE_SPACING, values);
        }
    }
}

/// Writes a three-float attribute of every sample, reusing its vector.
fn put3(
    mesh: &mut Mesh,
    attribute: MeshVertexAttribute,
    samples: &[Sample],
    get: impl Fn(&Sample) -> [f32; 3],
) {
    match mesh.attribute_mut(attribute.id) {
        Some(VertexAttributeValues::Float32x3(values)) => {
            values.clear();
            values.extend(samples.iter().map(&get));
        }
        _ => {
            let values: Vec<[f32; 3]> = samples.iter().map(get).collect();
            mesh.insert_attribute(attribute, values);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::time::{Duration, Instant};

    use bevy_app::App;
    use bevy_asset::Assets;
    use bevy_mesh::{Mesh, VertexAttributeValues};
    use strata_engine::fixtures;
    use strata_engine::mesh::shapes;
    use strata_engine::surface::SurfaceOptions;

    use super::{ATTRIBUTE_MAJOR_AXIS, ATTRIBUTE_SPACING, SampleMesh};
    use crate::StrataPlugin;
    use crate::ecs::{MeshBundle, SampleBuffer, SamplingSettings};

    fn attribute3(mesh: &Mesh, id: impl Into<bevy_mesh::MeshVertexAttributeId>) -> Vec<[f32; 3]> {
        match mesh.attribute(id) {
            Some(VertexAttributeValues::Float32x3(v)) => v.clone(),
            other => panic!("a three-float attribute, got {other:?}"),
        }
    }

    /// Updates until the entity's asset holds `count` samples of the buffer's
    /// generation; returns that generation.
    fn settle(app: &mut App, e: bevy_ecs::entity::Entity, count: usize, after: u64) -> u64 {
        let start = Instant::now();
        loop {
            app.update();
            let world = app.world();
            let buffer = world.get::<SampleBuffer>(e).expect("buffer");
            if let Some(state) = world.get::<SampleMesh>(e)
                && buffer.samples.len() == count
                && buffer.generation > after
                && state.generation == buffer.generation
            {
                return buffer.generation;
            }
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "no samples in 60 s"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Asserts the entity's asset holds exactly its buffer's samples.
    fn check_asset(app: &App, e: bevy_ecs::entity::Entity) {
        let world = app.world();
        let samples = &world.get::<SampleBuffer>(e).expect("buffer").samples;
        let handle = &world.get::<SampleMesh>(e).expect("sample mesh").handle;
        let mesh = world
            .resource::<Assets<Mesh>>()
            .get(handle)
            .expect("the asset");
        assert_eq!(
            mesh.primitive_topology(),
            bevy_mesh::PrimitiveTopology::PointList
        );
        let positions: Vec<[f32; 3]> = samples.iter().map(|s| s.position).collect();
        let normals: Vec<[f32; 3]> = samples.iter().map(|s| s.normal).collect();
        let axes: Vec<[f32; 3]> = samples.iter().map(|s| s.major_axis).collect();
        assert_eq!(attribute3(mesh, Mesh::ATTRIBUTE_POSITION), positions);
        assert_eq!(attribute3(mesh, Mesh::ATTRIBUTE_NORMAL), normals);
        assert_eq!(attribute3(mesh, ATTRIBUTE_MAJOR_AXIS.id), axes);
        let spacings: Vec<[f32; 2]> = samples.iter().map(|s| s.spacing).collect();
        match mesh.attribute(ATTRIBUTE_SPACING.id) {
            Some(VertexAttributeValues::Float32x2(v)) => assert_eq!(*v, spacings),
            other => panic!("two floats per spacing, got {other:?}"),
        }
    }

    #[test]
    fn the_mesh_asset_holds_the_samples_and_follows_them_in_place() {
        let mesh = Arc::new(shapes::sphere(1.0, 4).expect("sphere"));
        let field = Arc::new(fixtures::along_x_2to1_on(&mesh));
        let mut app = App::new();
        app.add_plugins(StrataPlugin);
        let bundle = MeshBundle::new(mesh, field, SurfaceOptions::default(), 400, 7);
        let e = app.world_mut().spawn(bundle).id();
        let first = settle(&mut app, e, 400, 0);
        check_asset(&app, e);
        let handle = app
            .world()
            .get::<SampleMesh>(e)
            .expect("state")
            .handle
            .clone();
        let before = app
            .world()
            .get::<SampleBuffer>(e)
            .expect("b")
            .samples
            .clone();

        // Another seed and count: the same asset, rewritten.
        app.world_mut()
            .get_mut::<SamplingSettings>(e)
            .expect("settings")
            .count = 250;
        app.world_mut()
            .get_mut::<SamplingSettings>(e)
            .expect("settings")
            .seed = 8;
        settle(&mut app, e, 250, first);
        check_asset(&app, e);
        let state = app.world().get::<SampleMesh>(e).expect("state");
        assert_eq!(state.handle, handle, "updated in place");
        assert_eq!(app.world().resource::<Assets<Mesh>>().len(), 1);
        let after = &app.world().get::<SampleBuffer>(e).expect("b").samples;
        assert_ne!(before[..250], after[..], "the samples changed");
    }
}
