//! The whole segmentation: seeds, random walk, singularity trees, disc cuts.

use rayon::prelude::*;

use super::paths::{field_edge_costs_with, singularity_tree};
use super::seeds::{face_frames, place_seeds};
use super::singularity::{line_field_transport, singularities_from};
use super::topology::{disc_cuts, patch_topology};
use super::walk::{connected_parts, random_walk, walk_weights};
use super::{Segment, SegmentError, SegmentOptions, Segmentation};
use crate::field::TensorField;
use crate::mesh::{NONE, TriMesh};

/// How many times a segment that is still not a disc after cutting is split in two
/// before giving up (each split halves it, so this is never reached on real meshes).
const MAX_SPLIT_ROUNDS: usize = 24;

/// Segments `mesh` along `field` (paper section 4).
///
/// 1. Seeds and random walk over the whole mesh.
/// 2. For each segment holding singular faces, the minimum spanning tree of
///    field-following paths between its singularities (or from a lone one to the
///    segment boundary) becomes a cut the walk may not cross, and the segment is
///    re-segmented.
/// 3. Every segment that is not a disc is cut along field-following paths (4.2); a
///    segment that still is not a disc is split in two by the walk, until all are.
///
/// Deterministic for `options.seed`, whatever the thread count.
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, segment::{segment, SegmentOptions}};
/// let mesh = shapes::plane(1.0, 16)?;
/// let field = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 }
///     .build(&mesh)?;
/// let seg = segment(&mesh, &field, &SegmentOptions::default())?;
/// assert_eq!(seg.segments.len(), 1);
/// assert!(seg.singularities.is_empty());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn segment(
    mesh: &TriMesh,
    field: &TensorField,
    options: &SegmentOptions,
) -> Result<Segmentation, SegmentError> {
    options.validate()?;
    let f_count = mesh.face_count();
    let frames = face_frames(mesh, field);
    let transport = line_field_transport(mesh, field);
    let costs = field_edge_costs_with(mesh, field, &transport);
    let singularities = singularities_from(mesh, &transport);
    let mut cut = vec![false; mesh.edge_count()];

    // 1. The whole mesh.
    let all = vec![true; f_count];
    let weights = walk_weights(mesh, &frames, options.sigma, &cut);
    let seeds = place_seeds(mesh, &frames, &weights, &all, options.beta, options.seed);
    let mut labels = connected_parts(mesh, &random_walk(mesh, &weights, &all, &seeds)?, &cut);

    // 2. Singularities on segment boundaries.
    let mut singular = vec![false; f_count];
    for s in &singularities {
        singular[s.face as usize] = true;
    }
    if !singularities.is_empty() {
        let groups = group_faces(&labels);
        let trees: Vec<Vec<u32>> = groups
            .par_iter()
            .map(|faces| {
                let sing: Vec<u32> = faces
                    .iter()
                    .copied()
                    .filter(|&f| singular[f as usize])
                    .collect();
                if sing.is_empty() {
                    return Vec::new();
                }
                let mut region = vec![false; f_count];
                for &f in faces {
                    region[f as usize] = true;
                }
                singularity_tree(mesh, &costs, &sing, &region)
            })
            .collect();
        let touched: Vec<usize> = (0..groups.len())
            .filter(|&i| !trees[i].is_empty())
            .collect();
        for tree in &trees {
            for &e in tree {
                cut[e as usize] = true;
            }
        }
        if !touched.is_empty() {
            let weights = walk_weights(mesh, &frames, options.sigma, &cut);
            let mut next = labels.iter().copied().max().unwrap_or(0) + 1;
            for (round, &i) in touched.iter().enumerate() {
                let mut mask = vec![false; f_count];
                for &f in &groups[i] {
                    mask[f as usize] = true;
                }
                let seed = options.seed.wrapping_add(1 + round as u64);
                let seeds = place_seeds(mesh, &frames, &weights, &mask, options.beta, seed);
                let local = random_walk(mesh, &weights, &mask, &seeds)?;
                // Give the re-segmented faces fresh labels above all existing ones.
                for &f in &groups[i] {
                    labels[f as usize] = next + local[f as usize];
                }
                next += seeds.len() as u32;
            }
            labels = connected_parts(mesh, &labels, &cut);
        }
    }

    // 3. Discs.
    for _ in 0..MAX_SPLIT_ROUNDS {
        let groups = group_faces(&labels);
        let extra: Vec<(usize, Vec<u32>, bool)> = groups
            .par_iter()
            .enumerate()
            .map(|(i, faces)| {
                let topo = patch_topology(mesh, faces, &cut);
                if is_disc(topo.euler_characteristic, topo.boundary_loops.len()) {
                    return (i, Vec::new(), true);
                }
                let new_cuts = disc_cuts(mesh, &costs, faces, &cut);
                let mut with = cut.clone();
                for &e in &new_cuts {
                    with[e as usize] = true;
                }
                let topo = patch_topology(mesh, faces, &with);
                (
                    i,
                    new_cuts,
                    is_disc(topo.euler_characteristic, topo.boundary_loops.len()),
                )
            })
            .collect();
        let mut to_split = Vec::new();
        for (i, new_cuts, ok) in extra {
            for e in new_cuts {
                cut[e as usize] = true;
            }
            if !ok {
                to_split.push(i);
            }
        }
        if to_split.is_empty() {
            break;
        }
        // Fallback: split each remaining non-disc segment in two with the walk,
        // seeded at its two faces farthest apart in the face graph.
        let weights = walk_weights(mesh, &frames, options.sigma, &cut);
        let mut next = labels
            .iter()
            .copied()
            .filter(|&l| l != NONE)
            .max()
            .unwrap_or(0)
            + 1;
        for i in to_split {
            let faces = &groups[i];
            let mut mask = vec![false; f_count];
            for &f in faces {
                mask[f as usize] = true;
            }
            let (a, b) = farthest_pair(mesh, faces, &mask, &cut);
            if a == b {
                continue;
            }
            let local = random_walk(mesh, &weights, &mask, &[a, b])?;
            for &f in faces {
                if local[f as usize] == 1 {
                    labels[f as usize] = next;
                }
            }
            next += 1;
        }
        labels = connected_parts(mesh, &labels, &cut);
    }

    // Output, segments numbered by their lowest face.
    let groups = group_faces(&labels);
    let mut face_segment = vec![0u32; f_count];
    let segments: Vec<Segment> = groups
        .par_iter()
        .map(|faces| {
            let topo = patch_topology(mesh, faces, &cut);
            Segment {
                faces: faces.clone(),
                boundary_loops: topo.boundary_loops,
                euler_characteristic: topo.euler_characteristic,
                has_singular_face: faces.iter().any(|&f| singular[f as usize]),
            }
        })
        .collect();
    for (id, s) in segments.iter().enumerate() {
        for &f in &s.faces {
            face_segment[f as usize] = id as u32;
        }
    }
    // Only cuts that run inside a segment matter; those between segments are
    // segment boundaries anyway.
    let cut_edges = (0..mesh.edge_count() as u32)
        .filter(|&e| cut[e as usize])
        .filter(|&e| {
            let [a, b] = mesh.edge_faces()[e as usize];
            a != NONE && b != NONE && face_segment[a as usize] == face_segment[b as usize]
        })
        .collect();
    Ok(Segmentation {
        face_segment,
        segments,
        singularities,
        cut_edges,
    })
}

fn is_disc(euler: i64, loops: usize) -> bool {
    euler == 1 && loops == 1
}

/// Faces of each label, labels in order of their lowest face (faces ascending).
fn group_faces(labels: &[u32]) -> Vec<Vec<u32>> {
    let mut index = std::collections::HashMap::new();
    let mut groups: Vec<Vec<u32>> = Vec::new();
    for (f, &l) in labels.iter().enumerate() {
        if l == NONE {
            continue;
        }
        let g = *index.entry(l).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(f as u32);
    }
    groups
}

/// Two faces of `faces` far apart in the face graph (a double breadth-first sweep),
/// not crossing cut edges.
fn farthest_pair(mesh: &TriMesh, faces: &[u32], mask: &[bool], cut: &[bool]) -> (u32, u32) {
    let sweep = |start: u32| -> u32 {
        let mut seen = std::collections::HashSet::from([start]);
        let mut queue = std::collections::VecDeque::from([start]);
        let mut last = start;
        while let Some(f) = queue.pop_front() {
            last = f;
            for (k, &n) in mesh.face_neighbors()[f as usize].iter().enumerate() {
                let e = mesh.face_edges()[f as usize][k];
                if n != NONE && mask[n as usize] && !cut[e as usize] && seen.insert(n) {
                    queue.push_back(n);
                }
            }
        }
        last
    };
    let a = sweep(faces[0]);
    (a, sweep(a))
}
