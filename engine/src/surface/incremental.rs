//! Incremental preprocessing: a surface rebuilt from its last build, redoing only what a
//! change invalidated, cancellable between stages and between segments, with progress.
//! This is what an engine runs as a background task when a mesh, a field or a setting
//! changes; the ECS layer (`strata-systems`) only snapshots its components into a
//! [`SurfaceState`], runs [`rebuild`] off the frame and writes the [`BuildOutcome`] back.
//!
//! What a change redoes ([`rebuild`]):
//! - nothing built before, another mesh (by content: a mesh reloaded unchanged is the
//!   same), or other segmentation settings: the whole surface path of
//!   [`Preprocessed::build_surface`](super::Preprocessed::build_surface). On the same
//!   mesh, segments whose [`segment_key`] is unchanged keep their parameterization and
//!   cells;
//! - a field change only: the segments holding a vertex whose (prepared) tensor
//!   changed are segmented again as one region
//!   ([`segment_region`]); the others are kept whole;
//! - the cell settings only: every segment's cells, nothing before; the chains are
//!   kept.
//!
//! A first build is bit for bit [`Preprocessed::build_surface`](super::Preprocessed::build_surface):
//! same prepared field, segmentation, pieces, cell budget, segment order and chains.
//! Kept segments keep the cells they were budgeted with (the budget only sets
//! refinement; sampling uses the cells' exact measures, so density is unaffected).
//!
//! Cost: that of the stages it runs; the snapshot and the outcome are `Arc`s, O(segments)
//! to move. Deterministic for any thread count and any order of the previous segments.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::{
    KeyBuilder, SegmentationKind, SplitContext, SurfaceError, SurfaceOptions, SurfaceReport,
    lowest_face, order_segments, parameterize_segment_with_splitting, prepare_field, segment_cells,
    segment_prepared, total_measure,
};
use crate::curve::{CellInput, SegmentCurve};
use crate::field::TensorField;
use crate::mesh::TriMesh;
use crate::param::SegmentParam;
use crate::sample::Sampler;
use crate::segment::{Segmentation, segment_region, touched_segments};

pub use super::build_control::{BuildControl, BuildProgress, BuildStage};

/// A segment's faces as segmentation left it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SegmentCut {
    /// Its faces (mesh face ids, ascending).
    pub faces: Vec<u32>,
    /// The segmentation's cut edges that touch its faces (ascending); the walk and the
    /// parameterization treat them as boundary.
    pub cut_edges: Vec<u32>,
    /// Its [`segment_key`]: everything its parameterization depends on.
    pub key: u64,
}

/// A segment's parameterized pieces (usually one; more when it was split) and what
/// its cells are built from.
#[derive(Clone, Debug)]
pub struct SegmentPieces {
    /// The pieces, ordered by their lowest face.
    pub pieces: Vec<SegmentParam>,
    /// Per piece: unit-square layout, corner densities and measure.
    pub inputs: Vec<CellInput>,
    /// Splits and fallbacks that happened.
    pub report: SurfaceReport,
}

/// The adaptive Hilbert cells of a segment's pieces (shared with the sampler).
#[derive(Clone, Debug)]
pub struct SegmentCurves {
    /// One per piece.
    pub curves: Vec<Arc<SegmentCurve>>,
}

/// One segment of a build: cut, pieces and cells, each shared, so that a change that
/// keeps one part replaces only the others.
#[derive(Clone, Debug)]
pub struct BuiltSegment {
    /// Its faces and cut edges.
    pub cut: Arc<SegmentCut>,
    /// Its parameterized pieces.
    pub pieces: Arc<SegmentPieces>,
    /// Its cells.
    pub curves: Arc<SegmentCurves>,
}

/// What a build is computed from.
#[derive(Clone, Debug)]
pub struct BuildInputs {
    /// The mesh.
    pub mesh: Arc<TriMesh>,
    /// The field, as the user gave it.
    pub field: Arc<TensorField>,
    /// Every setting, cells included.
    pub options: SurfaceOptions,
}

/// A completed build: the base of the next [`rebuild`].
#[derive(Clone, Debug)]
pub struct SurfaceState {
    /// What it was built from.
    pub inputs: BuildInputs,
    /// The field the surface path worked with ([`prepare_field`]).
    pub working_field: Arc<TensorField>,
    /// Charts or field-aligned segments.
    pub kind: SegmentationKind,
    /// The segments, in any order.
    pub segments: Vec<BuiltSegment>,
    /// The sampler's chains (segment ids in sampler order), kept when only cells change.
    pub chains: Vec<Vec<u32>>,
}

/// One stage a build ran.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildRun {
    /// The stage.
    pub stage: BuildStage,
    /// Items: segments produced (segmentation), parameterized, given cells; pieces
    /// linked (chains).
    pub items: usize,
    /// Wall time.
    pub took: Duration,
    /// A short note ("region of 812 faces (3 of 65 segments)", "omega changed").
    pub note: String,
}

/// The result of a [`rebuild`].
#[derive(Debug)]
pub struct BuildOutcome {
    /// The new state (the base of the next build).
    pub state: SurfaceState,
    /// Per segment of `state`: the index of the previous segment whose cut and pieces
    /// it kept (its curves are new when the cell settings changed), `None` if new.
    pub origins: Vec<Option<usize>>,
    /// The new sampler; `None` when the previous one is still exact (nothing that
    /// sampling reads changed).
    pub sampler: Option<Sampler>,
    /// The stages that ran, in order.
    pub runs: Vec<BuildRun>,
}

/// Domain of [`segment_key`].
const SEGMENT: u64 = 2;

/// A stable key of everything a segment's parameterization with splitting reads: its
/// faces with their vertex ids, positions and tensors, its cut edges, and
/// [`SurfaceOptions::parameterization_key`]. Equal keys on the same mesh mean the
/// segment's pieces can be reused. Cost O(segment).
pub fn segment_key(
    mesh: &TriMesh,
    field: &TensorField,
    faces: &[u32],
    cut_edges: &[u32],
    options: &SurfaceOptions,
) -> u64 {
    let mut key = KeyBuilder::new(SEGMENT)
        .word(options.parameterization_key())
        .word(faces.len() as u64)
        .word(cut_edges.len() as u64);
    for &f in faces {
        key = key.word(u64::from(f));
        for v in mesh.triangles()[f as usize] {
            let p = mesh.positions()[v as usize];
            key = key.word(u64::from(v)).float(p.x).float(p.y).float(p.z);
            for x in field.tensors()[v as usize].to_cols_array() {
                key = key.float(x);
            }
        }
    }
    for &e in cut_edges {
        key = key.word(u64::from(e));
    }
    key.finish()
}

/// What segmentation decided: previous segments kept, new cuts to parameterize.
struct Plan {
    kept: Vec<usize>,
    new: Vec<SegmentCut>,
    note: String,
}

/// Rebuilds the surface for `inputs` from `previous` (see the module docs), checking
/// `control` for cancellation and reporting progress to it. Errors: invalid options,
/// a stage's failure, or [`SurfaceError::Cancelled`]; `previous` stays valid either way.
pub fn rebuild(
    inputs: BuildInputs,
    previous: Option<&SurfaceState>,
    control: &BuildControl,
) -> Result<BuildOutcome, SurfaceError> {
    let result = run(inputs, previous, control);
    control.finish();
    result
}

fn run(
    inputs: BuildInputs,
    previous: Option<&SurfaceState>,
    control: &BuildControl,
) -> Result<BuildOutcome, SurfaceError> {
    inputs.options.validate()?;
    let (mesh, options) = (&*inputs.mesh, &inputs.options);
    let Lenders {
        same_mesh,
        same_settings,
        same_field,
    } = Lenders::of(previous, &inputs);
    let mut runs = Vec::new();
    let (working_field, kind, plan) = match same_field {
        Some(p) => (
            p.working_field.clone(),
            p.kind,
            Plan {
                kept: (0..p.segments.len()).collect(),
                new: Vec::new(),
                note: String::new(),
            },
        ),
        None => segment(&inputs, same_mesh, same_settings, control, &mut runs)?,
    };
    let previous_segments: &[BuiltSegment] = same_mesh.map_or(&[], |p| &p.segments);
    let fresh = parameterize(
        mesh,
        &working_field,
        options,
        previous_segments,
        &plan,
        control,
        &mut runs,
    )?;
    let cells_changed = previous.is_none_or(|p| p.inputs.options.curve != options.curve);
    let mut segments: Vec<BuiltSegment> = plan
        .kept
        .iter()
        .map(|&i| previous_segments[i].clone())
        .collect();
    let mut origins: Vec<Option<usize>> = plan.kept.iter().map(|&i| Some(i)).collect();
    let first_new = segments.len();
    let rebuild_from = if cells_changed { 0 } else { first_new };
    segments.extend(fresh.into_iter().map(|(cut, pieces)| BuiltSegment {
        cut: Arc::new(cut),
        pieces: Arc::new(pieces),
        curves: Arc::new(SegmentCurves { curves: Vec::new() }),
    }));
    origins.resize(segments.len(), None);
    let note = if cells_changed && previous.is_some() {
        "omega changed"
    } else {
        ""
    };
    build_curves(
        &mut segments[..],
        rebuild_from,
        options,
        control,
        note,
        &mut runs,
    )?;
    let sampler = if rebuild_from == segments.len() {
        None // no segment and no cell changed: the sampler is still exact
    } else {
        let kept_chains = (first_new == segments.len())
            .then(|| same_mesh.map(|p| p.chains.as_slice()))
            .flatten()
            .filter(|c| !c.is_empty());
        Some(assemble(
            &inputs.mesh,
            &working_field,
            &segments,
            kept_chains,
            control,
            &mut runs,
        )?)
    };
    let chains = match (&sampler, previous) {
        (Some(s), _) => s.chains().iter().map(|c| c.to_vec()).collect(),
        (None, Some(p)) => p.chains.clone(),
        (None, None) => Vec::new(),
    };
    Ok(BuildOutcome {
        state: SurfaceState {
            inputs,
            working_field,
            kind,
            segments,
            chains,
        },
        origins,
        sampler,
        runs,
    })
}

/// The previous build, where it can lend to this one: each a narrower match than the
/// one before.
struct Lenders<'a> {
    /// Built on a mesh of the same positions and triangles: its segments may be kept.
    same_mesh: Option<&'a SurfaceState>,
    /// ... and with the same settings apart from the cells': its segmentation may be
    /// updated in a region.
    same_settings: Option<&'a SurfaceState>,
    /// ... and with the same field: its segmentation stands as it is.
    same_field: Option<&'a SurfaceState>,
}

impl<'a> Lenders<'a> {
    /// What `previous` can lend to a build of `inputs`.
    fn of(previous: Option<&'a SurfaceState>, inputs: &BuildInputs) -> Self {
        let mesh = &*inputs.mesh;
        let same_mesh = previous.filter(|p| {
            Arc::ptr_eq(&p.inputs.mesh, &inputs.mesh)
                || (p.inputs.mesh.positions() == mesh.positions()
                    && p.inputs.mesh.triangles() == mesh.triangles())
        });
        let same_settings = same_mesh
            .filter(|p| without_cells(&p.inputs.options) == without_cells(&inputs.options));
        let same_field = same_settings.filter(|p| {
            Arc::ptr_eq(&p.inputs.field, &inputs.field)
                || p.inputs.field.tensors() == inputs.field.tensors()
        });
        Lenders {
            same_mesh,
            same_settings,
            same_field,
        }
    }
}

/// The segmentation stage of a build whose field changed: the working field, its kind
/// of segmentation and the plan of segments kept and new, recorded in `runs`.
fn segment(
    inputs: &BuildInputs,
    same_mesh: Option<&SurfaceState>,
    same_settings: Option<&SurfaceState>,
    control: &BuildControl,
    runs: &mut Vec<BuildRun>,
) -> Result<(Arc<TensorField>, SegmentationKind, Plan), SurfaceError> {
    let (mesh, options) = (&*inputs.mesh, &inputs.options);
    control.enter(BuildStage::Segmentation, 1)?;
    let t = Instant::now();
    let (working, kind) = prepare_field(mesh, inputs.field.clone(), options)?;
    control.check()?;
    let plan = segment_changes(mesh, &working, kind, options, same_mesh, same_settings)?;
    control.advance();
    runs.push(BuildRun {
        stage: BuildStage::Segmentation,
        items: plan.new.len(),
        took: t.elapsed(),
        note: plan.note.clone(),
    });
    Ok((working, kind, plan))
}

/// The options with the cell settings at their default: what segmentation and
/// parameterization read.
fn without_cells(options: &SurfaceOptions) -> SurfaceOptions {
    SurfaceOptions {
        curve: Default::default(),
        ..*options
    }
}

/// Segments what changed (see the module docs): a region when only the field changed
/// on a field-aligned build, the whole mesh otherwise, keeping previous segments whose
/// key is unchanged.
fn segment_changes(
    mesh: &TriMesh,
    working: &TensorField,
    kind: SegmentationKind,
    options: &SurfaceOptions,
    same_mesh: Option<&SurfaceState>,
    same_settings: Option<&SurfaceState>,
) -> Result<Plan, SurfaceError> {
    let aligned = |k: SegmentationKind| matches!(k, SegmentationKind::FieldAligned { .. });
    if let Some(prev) =
        same_settings.filter(|p| aligned(p.kind) && aligned(kind) && !p.segments.is_empty())
    {
        let faces: Vec<&[u32]> = prev.segments.iter().map(|s| &s.cut.faces[..]).collect();
        let touched = touched_segments(mesh, &prev.working_field, working, &faces);
        if touched.is_empty() {
            return Ok(Plan {
                kept: (0..prev.segments.len()).collect(),
                new: Vec::new(),
                note: "field unchanged on every segment".to_owned(),
            });
        }
        let mut region: Vec<u32> = touched
            .iter()
            .flat_map(|&i| faces[i].iter().copied())
            .collect();
        region.sort_unstable();
        let failed = if region.len() < mesh.face_count() {
            match segment_region(mesh, working, &region, &options.segment) {
                Ok(seg) => {
                    let mut is_touched = vec![false; prev.segments.len()];
                    for &i in &touched {
                        is_touched[i] = true;
                    }
                    return Ok(Plan {
                        kept: (0..prev.segments.len())
                            .filter(|&i| !is_touched[i])
                            .collect(),
                        new: cuts(mesh, working, &seg, options),
                        note: format!(
                            "region of {} faces ({} of {} segments)",
                            region.len(),
                            touched.len(),
                            prev.segments.len()
                        ),
                    });
                }
                // A region that cannot be cut out on its own: do it all.
                Err(e) => format!(" (region: {e})"),
            }
        } else {
            String::new()
        };
        let mut plan = whole(mesh, working, kind, options, same_mesh)?;
        plan.note.push_str(&failed);
        return Ok(plan);
    }
    whole(mesh, working, kind, options, same_mesh)
}

/// The whole mesh segmented; previous segments (on the same mesh) with an equal key
/// are kept instead of their new twins.
fn whole(
    mesh: &TriMesh,
    working: &TensorField,
    kind: SegmentationKind,
    options: &SurfaceOptions,
    same_mesh: Option<&SurfaceState>,
) -> Result<Plan, SurfaceError> {
    let seg = segment_prepared(mesh, working, kind, options)?;
    let mut by_key: HashMap<u64, usize> = same_mesh
        .map(|p| {
            p.segments
                .iter()
                .enumerate()
                .map(|(i, s)| (s.cut.key, i))
                .collect()
        })
        .unwrap_or_default();
    let mut kept = Vec::new();
    let mut new = Vec::new();
    for cut in cuts(mesh, working, &seg, options) {
        match by_key.remove(&cut.key) {
            Some(i) => kept.push(i),
            None => new.push(cut),
        }
    }
    kept.sort_unstable();
    Ok(Plan {
        kept,
        new,
        note: "whole mesh".to_owned(),
    })
}

/// The cuts of `seg`'s segments (faces, touching cut edges, key), in parallel.
fn cuts(
    mesh: &TriMesh,
    field: &TensorField,
    seg: &Segmentation,
    options: &SurfaceOptions,
) -> Vec<SegmentCut> {
    let mut is_cut = vec![false; mesh.edge_count()];
    for &e in &seg.cut_edges {
        if let Some(c) = is_cut.get_mut(e as usize) {
            *c = true;
        }
    }
    seg.segments
        .par_iter()
        .map(|s| {
            let mut cut_edges: Vec<u32> = s
                .faces
                .iter()
                .flat_map(|&f| mesh.face_edges()[f as usize])
                .filter(|&e| is_cut[e as usize])
                .collect();
            cut_edges.sort_unstable();
            cut_edges.dedup();
            let key = segment_key(mesh, field, &s.faces, &cut_edges, options);
            SegmentCut {
                faces: s.faces.clone(),
                cut_edges,
                key,
            }
        })
        .collect()
}

/// Parameterizes the plan's new cuts (splitting invalid ones) and prepares their
/// cells' inputs, segments in parallel.
fn parameterize(
    mesh: &TriMesh,
    field: &TensorField,
    options: &SurfaceOptions,
    previous: &[BuiltSegment],
    plan: &Plan,
    control: &BuildControl,
    runs: &mut Vec<BuildRun>,
) -> Result<Vec<(SegmentCut, SegmentPieces)>, SurfaceError> {
    if plan.new.is_empty() {
        return Ok(Vec::new());
    }
    control.enter(BuildStage::Parameterization, plan.new.len())?;
    let t = Instant::now();
    let cut_edges: Vec<u32> = plan
        .kept
        .iter()
        .flat_map(|&i| previous[i].cut.cut_edges.iter().copied())
        .chain(plan.new.iter().flat_map(|c| c.cut_edges.iter().copied()))
        .collect();
    let context = SplitContext::new(mesh, field, &cut_edges, options);
    let pieces: Vec<SegmentPieces> = plan
        .new
        .par_iter()
        .map(|cut| {
            control.check()?;
            let (pieces, report) =
                parameterize_segment_with_splitting(mesh, field, &context, &cut.faces, options)?;
            let inputs = pieces
                .iter()
                .map(|p| CellInput::new(mesh, field, p))
                .collect();
            control.advance();
            Ok(SegmentPieces {
                pieces,
                inputs,
                report,
            })
        })
        .collect::<Result<_, SurfaceError>>()?;
    runs.push(BuildRun {
        stage: BuildStage::Parameterization,
        items: pieces.len(),
        took: t.elapsed(),
        note: String::new(),
    });
    Ok(plan.new.iter().cloned().zip(pieces).collect())
}

/// Builds the cells of `segments[from..]` under the budget of all segments' total
/// measure (summed in the engine's order, so bit for bit a whole build's).
fn build_curves(
    segments: &mut [BuiltSegment],
    from: usize,
    options: &SurfaceOptions,
    control: &BuildControl,
    note: &str,
    runs: &mut Vec<BuildRun>,
) -> Result<(), SurfaceError> {
    if from == segments.len() {
        return Ok(());
    }
    control.enter(BuildStage::Cells, segments.len() - from)?;
    let t = Instant::now();
    let total = total_measure(segments.iter().flat_map(|s| {
        s.pieces
            .pieces
            .iter()
            .zip(&s.pieces.inputs)
            .map(|(p, c)| (lowest_face(p), c.measure))
    }));
    segments[from..]
        .par_iter_mut()
        .enumerate()
        .try_for_each(|(i, s)| {
            control.check()?;
            let curves = s
                .pieces
                .pieces
                .iter()
                .zip(&s.pieces.inputs)
                .map(|(p, c)| segment_cells(p, c, total, &options.curve).map(Arc::new))
                .collect::<Result<Vec<_>, _>>()
                .map_err(|source| SurfaceError::Curve {
                    segment: from + i,
                    source,
                })?;
            s.curves = Arc::new(SegmentCurves { curves });
            control.advance();
            Ok::<(), SurfaceError>(())
        })?;
    runs.push(BuildRun {
        stage: BuildStage::Cells,
        items: segments.len() - from,
        took: t.elapsed(),
        note: note.to_owned(),
    });
    Ok(())
}

/// The sampler of `segments`: ordered as a whole build orders them, linked into chains
/// (or given `chains` when the pieces are the previous build's).
fn assemble(
    mesh: &Arc<TriMesh>,
    field: &Arc<TensorField>,
    segments: &[BuiltSegment],
    chains: Option<&[Vec<u32>]>,
    control: &BuildControl,
    runs: &mut Vec<BuildRun>,
) -> Result<Sampler, SurfaceError> {
    control.enter(BuildStage::Chains, 1)?;
    let t = Instant::now();
    let ordered = order_segments(segments.iter().flat_map(|s| {
        s.pieces
            .pieces
            .iter()
            .zip(&s.curves.curves)
            .map(|(p, c)| (lowest_face(p), p.faces.clone(), Arc::clone(c)))
    }));
    let count = ordered.len();
    let sampler = match chains {
        Some(chains) => Sampler::with_chains(mesh.clone(), field.clone(), ordered, chains)?,
        None => {
            let s = Sampler::new(mesh.clone(), field.clone(), ordered)?;
            runs.push(BuildRun {
                stage: BuildStage::Chains,
                items: count,
                took: t.elapsed(),
                note: String::new(),
            });
            s
        }
    };
    control.advance();
    Ok(sampler)
}

#[cfg(test)]
#[path = "incremental_tests.rs"]
mod tests;
