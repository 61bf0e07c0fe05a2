//! Chains of neighbouring segments (paper section 6.2), sampled with one stratified
//! sequence each when segments are many relative to the samples.

use super::types::SegmentSampling;
use crate::mesh::TriMesh;

/// Links neighbouring segments into chains (section 6.2): a chain starts at the
/// unchained segment with the fewest unchained neighbours (the edge of what is left,
/// the paper's "weighted toward the boundary"; ties by lowest index) and repeatedly
/// appends the smallest-measure unchained neighbour of its last segment, until there
/// is none. Deterministic.
pub(super) fn link_chains(mesh: &TriMesh, segments: &[SegmentSampling]) -> Vec<Vec<u32>> {
    let mut owner = vec![u32::MAX; mesh.face_count()];
    for (i, s) in segments.iter().enumerate() {
        for &f in &s.faces {
            owner[f as usize] = i as u32;
        }
    }
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); segments.len()];
    for [a, b] in mesh.edge_faces() {
        if *a == crate::mesh::NONE || *b == crate::mesh::NONE {
            continue;
        }
        let (x, y) = (owner[*a as usize], owner[*b as usize]);
        if x != y && x != u32::MAX && y != u32::MAX {
            neighbours[x as usize].push(y);
            neighbours[y as usize].push(x);
        }
    }
    for n in &mut neighbours {
        n.sort_unstable();
        n.dedup();
    }
    let measure = |i: u32| segments[i as usize].curve.measure();
    let mut chained = vec![false; segments.len()];
    let mut chains = Vec::new();
    loop {
        let free_neighbours = |i: usize, chained: &[bool]| {
            neighbours[i]
                .iter()
                .filter(|&&n| !chained[n as usize])
                .count()
        };
        let Some(start) = (0..segments.len())
            .filter(|&i| !chained[i])
            .min_by_key(|&i| (free_neighbours(i, &chained), i))
        else {
            break;
        };
        let mut chain = vec![start as u32];
        chained[start] = true;
        let mut current = start;
        while let Some(next) = neighbours[current]
            .iter()
            .copied()
            .filter(|&n| !chained[n as usize])
            .min_by(|&a, &b| measure(a).total_cmp(&measure(b)).then(a.cmp(&b)))
        {
            chained[next as usize] = true;
            chain.push(next);
            current = next as usize;
        }
        chains.push(chain);
    }
    chains
}
