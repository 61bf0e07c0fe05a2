//! The whole segmentation: seeds, random walk, singularity trees, disc cuts.

use rayon::prelude::*;

use super::comb_flips::comb_flip_vertices;
use super::paths::{field_edge_costs_with, singularity_tree_to};
use super::seeds::{MAX_REGION_SHARE, RegionLimits, SeedGraph, face_frames, place_seeds_sized};
use super::singularity::{line_field_transport, singularities_from};
use super::topology::{disc_cuts, is_disc, patch_topology};
use super::walk::{random_walk, walk_weights};
use super::{
    Segment, SegmentError, SegmentOptions, Segmentation, Singularity, singularity_clusters,
};
use crate::field::TensorField;
use crate::mesh::{FaceSet, NONE, TriMesh, connected_parts, group_by_label};

/// How many times a segment that is still not a disc after cutting is split in two
/// before giving up (each split halves it, so this is never reached on real meshes).
const MAX_SPLIT_ROUNDS: usize = 24;

/// Segments `mesh` along `field` (paper section 4).
///
/// 1. For each connected part of the mesh holding singular faces, the minimum spanning
///    tree of field-following paths between its singularities (or from a lone one to
///    the part's boundary) becomes a cut the walk may not cross. Only faces of clusters
///    the field winds around count
///    ([`singularity_clusters`](super::singularity_clusters) with a non-zero index): a
///    dipole (a `+1/2` face touching a `-1/2` face) has no winding around it, and
///    cutting to it fragmented segments more than it saved splits (bench/README.md,
///    "Trees to net singularities only"). Each singular face is reached at the corner
///    the per-face frames cannot be combed around
///    ([`comb_flip_vertices`](super::comb_flip_vertices)), where there is one: the
///    vertex the parameterization needs on a cut.
/// 2. Seeds and random walk over the whole mesh, with the trees cut.
/// 3. The borders between segments are smoothed: a face sharing two edges with
///    another segment joins it ([`FaceSet::smooth_labels`]), since a field-aligned
///    map folds such one-face ears and notches over and the segment fails the
///    overlap test (bench/README.md, "Borders that fold").
/// 4. Every segment that is not a disc is cut along field-following paths (4.2); a
///    segment that still is not a disc is split in two by the walk, until all are.
///
/// **Deviation: trees first.** The paper walks first, then cuts a tree inside each
/// segment holding singularities and walks that segment again (on a smooth field
/// nearly the whole mesh, twice). Cutting first and walking once gives fewer segments
/// at every size for the same time: medians over seeds 1 to 5 on the bunny and its
/// two Loop subdivisions 25 / 28 / 26 -> 16 / 18 / 17 (designed field) and 119 / 171
/// / 230 -> 64 / 92 / 104 (projected constant field; bench/README.md, "Trees before
/// the walk"). Fields without singularities are walked exactly as before.
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
    segment_sized(mesh, field, options, mesh.area())
}

/// [`segment`] of a mesh cut out of a surface of area `surface_area`, whose seeding
/// rule ([`MIN_REGION_SHARE`](super::seeds::MIN_REGION_SHARE)) it keeps.
pub(crate) fn segment_sized(
    mesh: &TriMesh,
    field: &TensorField,
    options: &SegmentOptions,
    surface_area: f64,
) -> Result<Segmentation, SegmentError> {
    options.validate()?;
    let frames = face_frames(mesh, field);
    let mut cut = vec![false; mesh.edge_count()];

    // The field's edge costs, its singularities and the comb flips, for the trees.
    let transport = line_field_transport(mesh, field);
    let (costs, (singularities, flips)) = rayon::join(
        || field_edge_costs_with(mesh, field, &transport),
        || {
            rayon::join(
                || singularities_from(mesh, &transport),
                || comb_flip_vertices(mesh, &frames.major),
            )
        },
    );

    // 1. Trees between the net singularities of each connected part: cuts the walk
    // may not cross.
    cut_singularity_trees(mesh, &costs, &singularities, &flips, &mut cut);

    // 2. Seeds and random walk over the whole mesh, the trees cut.
    let all = FaceSet::all(mesh);
    let weights = walk_weights(mesh, &frames, options.sigma, &cut);
    let seeds = place_seeds_sized(
        SeedGraph::new(mesh, &frames, &weights, all.mask()),
        options.beta,
        options.seed,
        RegionLimits {
            surface_area,
            max_share: MAX_REGION_SHARE,
        },
    );
    let walked = random_walk(mesh, &weights, all.mask(), &seeds)?;
    let mut labels = connected_parts(mesh, &walked, &cut);

    // 3. Borders without one-face zigzags. Before the disc step, which repairs what a
    // move could not foresee.
    all.smooth_labels(mesh, &cut, &mut labels);
    labels = connected_parts(mesh, &labels, &cut);

    // 4. Discs.
    for _ in 0..MAX_SPLIT_ROUNDS {
        let groups = group_by_label(&labels, 0..mesh.face_count() as u32);
        let to_split = cut_to_discs(mesh, &costs, &groups, &mut cut);
        if to_split.is_empty() {
            break;
        }
        let weights = walk_weights(mesh, &frames, options.sigma, &cut);
        split_in_two(mesh, &weights, &cut, &groups, &to_split, &mut labels)?;
        labels = connected_parts(mesh, &labels, &cut);
    }

    Ok(assemble(mesh, &labels, &cut, singularities))
}

/// Step 1: flags in `cut` the trees of field-following paths (over `costs`) between
/// the net singularities of each connected part of the mesh (those of clusters with a
/// non-zero index), reaching each singular face at its comb flip in `flips`.
fn cut_singularity_trees(
    mesh: &TriMesh,
    costs: &[f64],
    singularities: &[Singularity],
    flips: &[bool],
    cut: &mut [bool],
) {
    let f_count = mesh.face_count();
    let net_faces: Vec<u32> = singularity_clusters(mesh, singularities)
        .into_iter()
        .filter(|c| c.is_singular())
        .flat_map(|c| c.faces)
        .collect();
    if net_faces.is_empty() {
        return;
    }
    let net = FaceSet::new(mesh, &net_faces);
    let parts = connected_parts(mesh, &vec![0; f_count], cut);
    let groups = group_by_label(&parts, 0..f_count as u32);
    let trees: Vec<Vec<u32>> = groups
        .par_iter()
        .map(|faces| {
            let sing: Vec<u32> = faces.iter().copied().filter(|&f| net.contains(f)).collect();
            if sing.is_empty() {
                return Vec::new();
            }
            let region = FaceSet::new(mesh, faces);
            singularity_tree_to(mesh, costs, &sing, region.mask(), flips)
        })
        .collect();
    for tree in &trees {
        for &e in tree {
            cut[e as usize] = true;
        }
    }
}

/// One round of step 4: flags in `cut` the disc cuts of every segment (`groups`, one
/// face list per label) that is not a disc; returns the indices of the segments that
/// are still not discs after them.
fn cut_to_discs(
    mesh: &TriMesh,
    costs: &[f64],
    groups: &[Vec<u32>],
    cut: &mut [bool],
) -> Vec<usize> {
    let before: &[bool] = cut;
    let extra: Vec<(usize, Vec<u32>, bool)> = groups
        .par_iter()
        .enumerate()
        .map(|(i, faces)| {
            if is_disc(mesh, faces, before) {
                return (i, Vec::new(), true);
            }
            let new_cuts = disc_cuts(mesh, costs, faces, before);
            let mut with = before.to_vec();
            for &e in &new_cuts {
                with[e as usize] = true;
            }
            (i, new_cuts, is_disc(mesh, faces, &with))
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
    to_split
}

/// Step 4's fallback: splits each segment `groups[i]` for `i` in `to_split` in two
/// with the walk (over `weights`), seeded at its two faces farthest apart in the face
/// graph; the second half gets a new label in `labels`.
fn split_in_two(
    mesh: &TriMesh,
    weights: &[f64],
    cut: &[bool],
    groups: &[Vec<u32>],
    to_split: &[usize],
    labels: &mut [u32],
) -> Result<(), SegmentError> {
    let mut next = labels
        .iter()
        .copied()
        .filter(|&l| l != NONE)
        .max()
        .unwrap_or(0)
        + 1;
    for &i in to_split {
        let faces = &groups[i];
        let mask = FaceSet::new(mesh, faces);
        let Some([a, b]) = mask.far_pair(mesh, cut) else {
            continue;
        };
        if a == b {
            continue;
        }
        let local = random_walk(mesh, weights, mask.mask(), &[a, b])?;
        for &f in faces {
            if local[f as usize] == 1 {
                labels[f as usize] = next;
            }
        }
        next += 1;
    }
    Ok(())
}

/// The [`Segmentation`] of final `labels`: segments numbered by their lowest face,
/// with their topology cut open along `cut`, and the cuts that run inside a segment.
fn assemble(
    mesh: &TriMesh,
    labels: &[u32],
    cut: &[bool],
    singularities: Vec<Singularity>,
) -> Segmentation {
    let f_count = mesh.face_count();
    let all_singular: Vec<u32> = singularities.iter().map(|s| s.face).collect();
    let singular = FaceSet::new(mesh, &all_singular);
    let groups = group_by_label(labels, 0..f_count as u32);
    let mut face_segment = vec![0u32; f_count];
    let segments: Vec<Segment> = groups
        .par_iter()
        .map(|faces| {
            let topo = patch_topology(mesh, faces, cut);
            Segment {
                faces: faces.clone(),
                boundary_loops: topo.boundary_loops,
                euler_characteristic: topo.euler_characteristic,
                has_singular_face: faces.iter().any(|&f| singular.contains(f)),
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
    Segmentation {
        face_segment,
        segments,
        singularities,
        cut_edges,
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec2, DVec3};

    use super::*;
    use crate::mesh::shapes;
    use crate::segment::{detect_singularities, singularity_clusters};

    /// A plane's 3:1 field turning by `+1/2` around each `a` and `-1/2` around each `b`
    /// of `pairs` (`theta = sum (arg(p - a) - arg(p - b)) / 2`).
    fn pairs_field(mesh: &TriMesh, pairs: &[(DVec2, DVec2)]) -> TensorField {
        let arg = |p: DVec2, c: DVec2| (p.y - c.y).atan2(p.x - c.x);
        let dirs: Vec<DVec3> = mesh
            .positions()
            .iter()
            .map(|p| {
                let p = p.truncate();
                let t: f64 = pairs
                    .iter()
                    .map(|&(a, b)| 0.5 * (arg(p, a) - arg(p, b)))
                    .sum();
                DVec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        TensorField::from_frames(mesh, &dirs, &vec![[3.0, 1.0 / 3.0]; dirs.len()])
            .expect("valid field")
    }

    fn barycentre(mesh: &TriMesh, f: u32) -> DVec2 {
        (mesh.face_positions(f).iter().sum::<DVec3>() / 3.0).truncate()
    }

    /// The barycentres of the face nearest `at` and of a face sharing one vertex with
    /// it, chosen so that the pair is detected as one dipole (two touching singular
    /// faces of opposite index).
    fn dipole_near(mesh: &TriMesh, at: DVec2) -> (DVec2, DVec2) {
        let d = |g: u32| barycentre(mesh, g).distance(at);
        let f = (0..mesh.face_count() as u32)
            .min_by(|&x, &y| d(x).total_cmp(&d(y)))
            .expect("faces");
        let tf = mesh.triangles()[f as usize];
        let shares_vertex = |g: u32| {
            let tg = mesh.triangles()[g as usize];
            tg.iter().filter(|v| tf.contains(v)).count() == 1
        };
        (0..mesh.face_count() as u32)
            .filter(|&g| shares_vertex(g))
            .map(|g| (barycentre(mesh, f), barycentre(mesh, g)))
            .find(|&pair| {
                let found = detect_singularities(mesh, &pairs_field(mesh, &[pair]));
                let clusters = singularity_clusters(mesh, &found);
                found.len() == 2 && clusters.len() == 1 && !clusters[0].is_singular()
            })
            .expect("a face whose pair with the nearest is a dipole")
    }

    #[test]
    fn dipoles_stay_inside_segments_and_net_singularities_reach_a_border() {
        let mesh = shapes::plane(1.0, 24).expect("plane");
        let options = SegmentOptions::default();
        // Two dipoles apart: a tree between them would cut the plane for nothing.
        let dipoles = [
            dipole_near(&mesh, DVec2::new(0.3, 0.5)),
            dipole_near(&mesh, DVec2::new(0.7, 0.5)),
        ];
        let seg = segment(&mesh, &pairs_field(&mesh, &dipoles), &options).expect("segment");
        let clusters = singularity_clusters(&mesh, &seg.singularities);
        assert_eq!(seg.singularities.len(), 4, "{:?}", seg.singularities);
        assert!(clusters.iter().all(|c| !c.is_singular()), "{clusters:?}");
        assert!(
            seg.cut_edges.is_empty(),
            "no tree to a dipole: {:?}",
            seg.cut_edges
        );
        for s in &seg.singularities {
            assert!(seg.segments[seg.face_segment[s.face as usize] as usize].has_singular_face);
        }

        // Two net singularities apart: each lies on a segment's border or a cut.
        let pair = [(DVec2::new(0.3, 0.5), DVec2::new(0.7, 0.5))];
        let seg = segment(&mesh, &pairs_field(&mesh, &pair), &options).expect("segment");
        let clusters = singularity_clusters(&mesh, &seg.singularities);
        assert_eq!(clusters.iter().filter(|c| c.is_singular()).count(), 2);
        for c in clusters.iter().filter(|c| c.is_singular()) {
            for &face in &c.faces {
                let id = seg.face_segment[face as usize];
                let on_border = mesh.face_edges()[face as usize].iter().any(|&e| {
                    seg.cut_edges.contains(&e)
                        || mesh.edge_faces()[e as usize]
                            .iter()
                            .any(|&h| h != NONE && seg.face_segment[h as usize] != id)
                });
                assert!(
                    on_border,
                    "net singular face {face} lies inside its segment"
                );
            }
        }
    }
}
