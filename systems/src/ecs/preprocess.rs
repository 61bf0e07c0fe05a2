//! Preprocessing systems: segmentation, parameterization, curves (cells) and chains
//! (sampler assembly), each redoing only what a change invalidated.
//!
//! - [`segment_meshes`] runs when a mesh entity's mesh, field or settings changed. A
//!   field-only change re-segments only the union of the segments that hold a vertex
//!   whose tensor changed (a sub-mesh, [`segment_region`]); every other segment entity
//!   is left untouched. Any other change segments the whole mesh, and new segments
//!   whose content hash equals an existing segment's keep that entity. A mesh replaced
//!   by one with the same positions and triangles counts as unchanged.
//! - [`parameterize_segments`] runs for segment entities that are new or whose faces
//!   changed (`Changed<SegmentFaces>`), in parallel over segments.
//! - [`build_curves`] runs for segments whose parameterization changed, or for all of
//!   a mesh's segments when its [`CurveSettings`] changed. A segment's cell budget is
//!   its share of the mesh's total measure ([`segment_cells`]); segments kept across a
//!   field change keep cells budgeted with the total of when they were built (the
//!   budget only sets refinement: sampling uses the cells' exact measures, so the
//!   density is unaffected).
//! - [`assemble_samplers`] rebuilds a mesh's sampler (segment order and chains) when
//!   any of its segments' cells changed or a segment was removed.
//!
//! Each system reads components, calls engine functions, and writes results.

use std::collections::{HashMap, HashSet};
use std::hash::{Hash, Hasher};
use std::sync::Arc;
use std::time::Instant;

use bevy_ecs::prelude::*;
use rayon::prelude::*;
use strata_engine::field::TensorField;
use strata_engine::mesh::{NONE, TriMesh};
use strata_engine::sample::Sampler;
use strata_engine::segment::{Segmentation, segment, segment_region, touched_segments};
use strata_engine::surface::{
    CellInput, SplitContext, SurfaceOptions, lowest_face, order_segments,
    parameterize_segment_with_splitting, segment_cells, total_measure,
};

use super::EngineError;
use super::components::*;
use super::stats::{EngineErrors, Stage, StageStats};

/// The content hash of a segment (see [`SegmentFaces`]).
pub fn segment_hash(
    mesh: &TriMesh,
    field: &TensorField,
    faces: &[u32],
    cut_edges: &[u32],
    options: &SurfaceOptions,
) -> u64 {
    // SipHash with fixed keys: the same content hashes the same in every run.
    let mut h = std::collections::hash_map::DefaultHasher::new();
    faces.hash(&mut h);
    cut_edges.hash(&mut h);
    for &f in faces {
        for v in mesh.triangles()[f as usize] {
            let p = mesh.positions()[v as usize];
            [p.x, p.y, p.z].map(f64::to_bits).hash(&mut h);
            field.tensors()[v as usize]
                .to_cols_array()
                .map(f64::to_bits)
                .hash(&mut h);
        }
    }
    // Everything else a segment's parameterization depends on.
    options.parameterization_key().hash(&mut h);
    h.finish()
}

/// The cut edges among `cut` that touch `faces` (sorted).
fn cuts_touching(mesh: &TriMesh, faces: &[u32], cut: &HashSet<u32>) -> Vec<u32> {
    if cut.is_empty() {
        return Vec::new();
    }
    let mut out: Vec<u32> = faces
        .iter()
        .flat_map(|&f| mesh.face_edges()[f as usize])
        .filter(|e| cut.contains(e))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Segment entities (faces, cut edges, hash) for the segments of `seg`.
fn segment_components(
    entity: Entity,
    mesh: &TriMesh,
    field: &TensorField,
    seg: &Segmentation,
    options: &SurfaceOptions,
) -> Vec<SegmentFaces> {
    let cut: HashSet<u32> = seg.cut_edges.iter().copied().collect();
    seg.segments
        .par_iter()
        .map(|s| {
            let cut_edges = cuts_touching(mesh, &s.faces, &cut);
            let hash = segment_hash(mesh, field, &s.faces, &cut_edges, options);
            SegmentFaces {
                mesh: entity,
                faces: s.faces.clone(),
                cut_edges,
                hash,
            }
        })
        .collect()
}

/// Segments meshes whose mesh, field or settings changed (see the module docs).
#[allow(clippy::type_complexity)]
pub fn segment_meshes(
    mut commands: Commands,
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    mut meshes: Query<
        (
            Entity,
            &MeshData,
            &FieldData,
            &PreprocessSettings,
            &mut SegmentationState,
        ),
        Or<(
            Changed<MeshData>,
            Changed<FieldData>,
            Changed<PreprocessSettings>,
        )>,
    >,
    segments: Query<(Entity, &SegmentFaces)>,
) {
    for (entity, mesh, field, settings, mut state) in &mut meshes {
        let t = Instant::now();
        let (mesh, field, options) = (&mesh.0, &field.0, settings.0);
        let existing: Vec<(Entity, &SegmentFaces)> =
            segments.iter().filter(|(_, s)| s.mesh == entity).collect();
        // A mesh reloaded with the same content (a file saved unchanged) counts as the same.
        let same_mesh = state.mesh.as_ref().is_some_and(|m| {
            Arc::ptr_eq(m, mesh)
                || (m.positions() == mesh.positions() && m.triangles() == mesh.triangles())
        });
        let same_settings = state.settings == Some(*settings);
        let previous_field = state.field.clone();
        let mut note = String::new();
        let produced = match (
            same_mesh && same_settings && !existing.is_empty(),
            previous_field,
        ) {
            (true, Some(old)) => {
                // Field-only change: re-segment the segments it touched.
                let faces: Vec<&[u32]> = existing.iter().map(|(_, s)| &s.faces[..]).collect();
                let touched: Vec<&(Entity, &SegmentFaces)> =
                    touched_segments(mesh, &old, field, &faces)
                        .into_iter()
                        .map(|i| &existing[i])
                        .collect();
                let mut region: Vec<u32> =
                    touched.iter().flat_map(|(_, s)| s.faces.clone()).collect();
                region.sort_unstable();
                if region.is_empty() {
                    note = "field unchanged on every segment".to_owned();
                    Some(Vec::new())
                } else {
                    let result = if region.len() == mesh.face_count() {
                        segment(mesh, field, &options.segment).map_err(EngineError::from)
                    } else {
                        segment_region(mesh, field, &region, &options.segment).or_else(|e| {
                            // A region that cannot be cut out on its own: do it all.
                            note = format!("whole mesh ({e}); ");
                            segment(mesh, field, &options.segment).map_err(EngineError::from)
                        })
                    };
                    match result {
                        Ok(seg) if note.is_empty() && region.len() < mesh.face_count() => {
                            note = format!(
                                "region of {} faces ({} of {} segments)",
                                region.len(),
                                touched.len(),
                                existing.len()
                            );
                            for (e, _) in &touched {
                                commands.entity(*e).despawn();
                            }
                            Some(segment_components(entity, mesh, field, &seg, &options))
                        }
                        Ok(seg) => {
                            note.push_str("whole mesh");
                            Some(replace_all(
                                &mut commands,
                                entity,
                                mesh,
                                field,
                                &seg,
                                &options,
                                &existing,
                            ))
                        }
                        Err(e) => {
                            errors.0.push(e);
                            None
                        }
                    }
                }
            }
            _ => match segment(mesh, field, &options.segment) {
                Ok(seg) => {
                    note = "whole mesh".to_owned();
                    Some(replace_all(
                        &mut commands,
                        entity,
                        mesh,
                        field,
                        &seg,
                        &options,
                        &existing,
                    ))
                }
                Err(e) => {
                    errors.0.push(e.into());
                    None
                }
            },
        };
        let Some(new_segments) = produced else {
            continue; // the last good segments stay
        };
        let count = new_segments.len();
        for faces in new_segments {
            commands.spawn(SegmentBundle {
                faces,
                params: SegmentParams::default(),
                cells: SegmentCells::default(),
            });
        }
        state.mesh = Some(mesh.clone());
        state.field = Some(field.clone());
        state.settings = Some(*settings);
        stats.record(Stage::Segmentation, entity, count, t.elapsed(), note);
    }
}

/// Despawns segment entities whose mesh entity no longer exists (or lost its mesh).
pub fn despawn_orphan_segments(
    mut commands: Commands,
    meshes: Query<(), With<MeshData>>,
    segments: Query<(Entity, &SegmentFaces)>,
) {
    for (e, s) in &segments {
        if meshes.get(s.mesh).is_err() {
            commands.entity(e).despawn();
        }
    }
}

/// A whole-mesh segmentation replacing `existing`: segments whose hash matches an
/// existing one keep that entity; the others are returned for spawning, and unmatched
/// existing entities are despawned.
fn replace_all(
    commands: &mut Commands,
    entity: Entity,
    mesh: &TriMesh,
    field: &TensorField,
    seg: &Segmentation,
    options: &SurfaceOptions,
    existing: &[(Entity, &SegmentFaces)],
) -> Vec<SegmentFaces> {
    let mut by_hash: HashMap<u64, Entity> = existing.iter().map(|(e, s)| (s.hash, *e)).collect();
    let mut spawn = Vec::new();
    for s in segment_components(entity, mesh, field, seg, options) {
        if by_hash.remove(&s.hash).is_none() {
            spawn.push(s);
        }
    }
    for e in by_hash.into_values() {
        commands.entity(e).despawn();
    }
    spawn
}

/// Parameterizes new or changed segments, in parallel (see the module docs).
pub fn parameterize_segments(
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    meshes: Query<(
        &MeshData,
        &FieldData,
        &PreprocessSettings,
        &SegmentationState,
    )>,
    all: Query<&SegmentFaces>,
    mut dirty: Query<(&SegmentFaces, &mut SegmentParams), Changed<SegmentFaces>>,
) {
    let mut by_mesh: HashMap<Entity, Vec<(Mut<SegmentParams>, &SegmentFaces)>> = HashMap::new();
    for (faces, params) in &mut dirty {
        by_mesh.entry(faces.mesh).or_default().push((params, faces));
    }
    let mut keys: Vec<Entity> = by_mesh.keys().copied().collect();
    keys.sort();
    for mesh_entity in keys {
        let Some(mut work) = by_mesh.remove(&mesh_entity) else {
            continue;
        };
        let Ok((mesh, field, settings, state)) = meshes.get(mesh_entity) else {
            continue;
        };
        if !state.segments_current(mesh) {
            continue; // the mesh's segmentation failed: its segments are stale
        }
        let t = Instant::now();
        let (mesh, field, options) = (&*mesh.0, &*field.0, &settings.0);
        let cut: Vec<u32> = all
            .iter()
            .filter(|s| s.mesh == mesh_entity)
            .flat_map(|s| s.cut_edges.iter().copied())
            .collect();
        let context = SplitContext::new(mesh, field, &cut, options);
        let results: Vec<_> = work
            .par_iter()
            .map(|(_, s)| {
                parameterize_segment_with_splitting(mesh, field, &context, &s.faces, options)
            })
            .collect();
        let count = work.len();
        for ((params, _), result) in work.iter_mut().zip(results) {
            match result {
                Ok((pieces, report)) => {
                    params.pieces = pieces;
                    params.report = report;
                }
                Err(e) => errors.0.push(EngineError::Surface(e)),
            }
        }
        stats.record(
            Stage::Parameterization,
            mesh_entity,
            count,
            t.elapsed(),
            String::new(),
        );
    }
}

/// Rebuilds the cells of segments whose parameterization changed, or of all of a
/// mesh's segments when its omega ([`CurveSettings`]) changed.
pub fn build_curves(
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    meshes: Query<(
        Entity,
        &MeshData,
        &FieldData,
        Ref<CurveSettings>,
        &SegmentationState,
    )>,
    mut segments: Query<(&SegmentFaces, Ref<SegmentParams>, &mut SegmentCells)>,
) {
    for (mesh_entity, mesh, field, curve, state) in &meshes {
        if !state.segments_current(mesh) {
            continue;
        }
        let omega_changed = curve.is_changed();
        let note = if omega_changed && !curve.is_added() {
            "omega changed"
        } else {
            ""
        };
        let mut mine: Vec<(bool, &SegmentFaces, Ref<SegmentParams>, Mut<SegmentCells>)> = segments
            .iter_mut()
            .filter(|(s, _, _)| s.mesh == mesh_entity)
            .map(|(s, p, c)| (p.is_changed(), s, p, c))
            .collect();
        let any_params = mine.iter().any(|m| m.0);
        if !(omega_changed || any_params) || mine.is_empty() {
            continue;
        }
        let t = Instant::now();
        let (mesh, field) = (&*mesh.0, &*field.0);
        // New layouts and measures for the segments whose parameterization changed.
        mine.par_iter_mut()
            .filter(|m| m.0)
            .for_each(|(_, _, params, cells)| {
                cells.inputs = params
                    .pieces
                    .iter()
                    .map(|p| CellInput::new(mesh, field, p))
                    .collect();
            });
        // Summed in the engine's segment order: bit-identical to a whole build.
        let total = total_measure(mine.iter().flat_map(|(_, _, params, cells)| {
            params
                .pieces
                .iter()
                .zip(&cells.inputs)
                .map(|(p, c)| (lowest_face(p), c.measure))
        }));
        let options = curve.0;
        let results: Vec<Result<(), EngineError>> = mine
            .par_iter_mut()
            .filter(|m| omega_changed || m.0)
            .map(|(_, _, params, cells)| {
                let curves = params
                    .pieces
                    .iter()
                    .zip(&cells.inputs)
                    .map(|(p, c)| segment_cells(p, c, total, &options).map(Arc::new))
                    .collect::<Result<Vec<_>, _>>()?;
                cells.curves = curves;
                Ok(())
            })
            .collect();
        let count = results.len();
        errors.0.extend(results.into_iter().filter_map(Result::err));
        stats.record(
            Stage::Curves,
            mesh_entity,
            count,
            t.elapsed(),
            note.to_owned(),
        );
    }
}

/// Rebuilds a mesh's sampler (segments in the engine's order, linked into chains)
/// when any of its segments' cells changed or a segment was removed. When the segments
/// are the ones the current sampler holds (only their cells changed: a new omega), its
/// chains are kept and no [`Stage::Chains`] run is recorded.
pub fn assemble_samplers(
    mut stats: ResMut<StageStats>,
    mut errors: ResMut<EngineErrors>,
    mut removed: RemovedComponents<SegmentFaces>,
    mut meshes: Query<(
        Entity,
        &MeshData,
        &FieldData,
        &SegmentationState,
        &mut MeshSampler,
    )>,
    segments: Query<(&SegmentFaces, &SegmentParams, Ref<SegmentCells>)>,
) {
    let any_removed = removed.read().count() > 0;
    for (mesh_entity, mesh, field, state, mut sampler) in &mut meshes {
        if !state.segments_current(mesh) {
            continue;
        }
        let mine: Vec<_> = segments
            .iter()
            .filter(|(s, _, _)| s.mesh == mesh_entity)
            .collect();
        let changed = mine.iter().any(|(_, _, c)| c.is_changed());
        if !(changed || any_removed) || mine.is_empty() {
            continue;
        }
        let t = Instant::now();
        let mut pieces = Vec::new();
        let mut complete = true;
        for (_, params, cells) in &mine {
            complete &= cells.curves.len() == params.pieces.len() && !params.pieces.is_empty();
            for (p, c) in params.pieces.iter().zip(&cells.curves) {
                pieces.push((lowest_face(p), p.faces.clone(), Arc::clone(c)));
            }
        }
        if !complete {
            // A segment failed upstream (its error is reported): keep the last sampler.
            continue;
        }
        let segs = order_segments(pieces);
        let count = segs.len();
        // Same segments as the current sampler (only their cells changed, e.g. a new
        // omega): keep its chains instead of linking them again.
        let kept_chains: Option<Vec<Vec<u32>>> = sampler.0.as_ref().and_then(|old| {
            let same = old.segments().len() == segs.len()
                && old
                    .segments()
                    .iter()
                    .zip(&segs)
                    .all(|(a, b)| a.faces == b.faces);
            same.then(|| old.chains().iter().map(|c| c.to_vec()).collect())
        });
        let relinked = kept_chains.is_none();
        let built = match &kept_chains {
            Some(chains) => Sampler::with_chains(mesh.0.clone(), field.0.clone(), segs, chains),
            None => Sampler::new(mesh.0.clone(), field.0.clone(), segs),
        };
        match built {
            Ok(s) => {
                sampler.0 = Some(s);
                if relinked {
                    stats.record(
                        Stage::Chains,
                        mesh_entity,
                        count,
                        t.elapsed(),
                        String::new(),
                    );
                }
            }
            Err(e) => errors.0.push(EngineError::Sample(e)),
        }
    }
}

/// Faces per segment id of a mesh's current segments (`NONE` where a face has no
/// segment): the covering the segment entities form, for checks.
pub fn face_segments(world: &mut World, mesh_entity: Entity, face_count: usize) -> Vec<u32> {
    let mut out = vec![NONE; face_count];
    let mut q = world.query::<&SegmentFaces>();
    let mut segs: Vec<&SegmentFaces> = q.iter(world).filter(|s| s.mesh == mesh_entity).collect();
    segs.sort_by_key(|s| s.faces.first().copied());
    for (i, s) in segs.iter().enumerate() {
        for &f in &s.faces {
            out[f as usize] = i as u32;
        }
    }
    out
}
