//! Construction of a [`TriMesh`]: validation, repairs and adjacency.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec3;
use rayon::prelude::*;

use super::{MeshError, MeshWarning, NONE, TriMesh};

/// How many offending items a warning lists.
const LIST_FIRST: usize = 8;

/// Items (vertices or faces) below which a parallel pass stays on the calling thread:
/// a small mesh would pay more for the threads than it gains.
const MIN_PARALLEL: usize = 1 << 14;

pub(super) fn build(
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    mut warnings: Vec<MeshWarning>,
) -> Result<TriMesh, MeshError> {
    let input_vertices = positions.len();
    // Checked on every thread; the lowest offending vertex or face is reported.
    if let Some(vertex) = positions
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .position_first(|p| !p.is_finite())
    {
        let p = positions[vertex];
        return Err(MeshError::NonFiniteVertex {
            vertex,
            x: p.x,
            y: p.y,
            z: p.z,
        });
    }
    let out_of_range = |t: &[u32; 3]| t.iter().any(|&i| i as usize >= input_vertices);
    if let Some(face) = triangles
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .position_first(out_of_range)
    {
        let index = triangles[face]
            .into_iter()
            .find(|&i| i as usize >= input_vertices)
            .unwrap_or_default();
        return Err(MeshError::IndexOutOfRange {
            face,
            index: i64::from(index),
            vertex_count: input_vertices,
        });
    }

    // Merge vertices at bitwise-identical positions (-0.0 and 0.0 count as equal).
    let key = |p: DVec3| [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
    let mut first_at: FastMap<[u64; 3], u32> = fast_map(input_vertices);
    let mut merged_to: Vec<u32> = Vec::with_capacity(input_vertices);
    let mut merged = 0;
    for (i, p) in positions.iter().enumerate() {
        let first = *first_at.entry(key(*p)).or_insert(i as u32);
        if first as usize != i {
            merged += 1;
        }
        merged_to.push(first);
    }
    if merged > 0 {
        warnings.push(MeshWarning::MergedDuplicateVertices { count: merged });
    }

    // Remove degenerate (repeated vertex or zero area) and duplicated faces: a face
    // is a duplicate when an earlier face that is not degenerate has the same vertex
    // set. Sets are compared by bucketing them by their smallest vertex.
    // Per face (on every thread): its merged corners and, unless it is degenerate, its
    // sorted vertex set.
    let (merged_triangles, sets): (Vec<[u32; 3]>, Vec<Option<[u32; 3]>>) = triangles
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .map(|t| {
            let t = t.map(|v| merged_to[v as usize]);
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let repeated = t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
            if repeated || (b - a).cross(c - a).length_squared() == 0.0 {
                (t, None)
            } else {
                let mut sorted = t;
                sorted.sort_unstable();
                (t, Some(sorted))
            }
        })
        .unzip();
    let degenerate_count = sets.iter().filter(|s| s.is_none()).count();
    let degenerate: Vec<usize> = sets
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(face, _)| face)
        .take(LIST_FIRST)
        .collect();
    let (starts, by_smallest) = bucket_sort(input_vertices, || {
        sets.iter()
            .enumerate()
            .filter_map(|(f, s)| s.map(|[a, b, c]| (a, [b, c, f as u32])))
    });
    let mut duplicate = vec![false; triangles.len()];
    for bucket in starts.windows(2) {
        let bucket = &by_smallest[bucket[0] as usize..bucket[1] as usize];
        for pair in bucket.windows(2) {
            if pair[0][..2] == pair[1][..2] {
                duplicate[pair[1][2] as usize] = true; // the later face of the two
            }
        }
    }
    drop(by_smallest);
    let duplicate_count = duplicate.iter().filter(|&&d| d).count();
    let mut kept: Vec<[u32; 3]> = merged_triangles
        .into_iter()
        .zip(sets.iter().zip(&duplicate))
        .filter(|(_, (set, duplicate))| set.is_some() && !**duplicate)
        .map(|(t, _)| t)
        .collect();
    if degenerate_count > 0 {
        warnings.push(MeshWarning::RemovedDegenerateFaces {
            count: degenerate_count,
            first: degenerate,
        });
    }
    if duplicate_count > 0 {
        warnings.push(MeshWarning::RemovedDuplicateFaces {
            count: duplicate_count,
        });
    }

    // Compact: keep only referenced vertices, in input order.
    let mut new_index = vec![NONE; input_vertices];
    let mut compact_positions = Vec::with_capacity(input_vertices);
    for t in &kept {
        for &v in t {
            if new_index[v as usize] == NONE {
                new_index[v as usize] = 0; // mark; numbered below in input order
            }
        }
    }
    for (v, slot) in new_index.iter_mut().enumerate() {
        if *slot != NONE {
            *slot = compact_positions.len() as u32;
            compact_positions.push(positions[v]);
        }
    }
    let unreferenced = (0..input_vertices)
        .filter(|&v| merged_to[v] as usize == v && new_index[v] == NONE)
        .count();
    if unreferenced > 0 {
        warnings.push(MeshWarning::RemovedUnreferencedVertices {
            count: unreferenced,
        });
    }
    let input_vertex_map: Vec<u32> = (0..input_vertices)
        .map(|v| new_index[merged_to[v] as usize])
        .collect();
    for t in &mut kept {
        *t = t.map(|v| new_index[v as usize]);
    }
    if kept.is_empty() || compact_positions.is_empty() {
        return Err(MeshError::Empty {
            vertices: input_vertices,
            faces: kept.len(),
        });
    }

    let mut mesh = TriMesh {
        positions: compact_positions,
        triangles: kept,
        edges: Vec::new(),
        edge_faces: Vec::new(),
        edge_valence: Vec::new(),
        face_edges: Vec::new(),
        face_neighbors: Vec::new(),
        vertex_face_offsets: Vec::new(),
        vertex_faces: Vec::new(),
        vertex_neighbor_offsets: Vec::new(),
        vertex_neighbors: Vec::new(),
        vertex_neighbor_edges: Vec::new(),
        boundary_loops: Vec::new(),
        face_component: Vec::new(),
        component_count: 0,
        face_areas: Vec::new(),
        face_normals: Vec::new(),
        vertex_normals: Vec::new(),
        warnings,
        input_vertex_map,
    };
    build_vertex_faces(&mut mesh);
    build_edges(&mut mesh);
    build_vertex_neighbors(&mut mesh);
    build_boundary_loops(&mut mesh);
    build_components(&mut mesh);
    build_geometry(&mut mesh);
    Ok(mesh)
}

/// Items grouped by a bucket below `buckets` and sorted within each bucket: the CSR
/// starts (`buckets + 1`) and the items. A counting sort then a sort of each (usually
/// small) bucket, O(n) for bounded buckets; `items` is called twice and must give the
/// same items both times.
fn bucket_sort<T, I>(buckets: usize, items: impl Fn() -> I) -> (Vec<u32>, Vec<T>)
where
    T: Ord + Copy + Default,
    I: Iterator<Item = (u32, T)>,
{
    let mut starts = vec![0u32; buckets + 1];
    for (b, _) in items() {
        starts[b as usize + 1] += 1;
    }
    for b in 0..buckets {
        starts[b + 1] += starts[b];
    }
    let mut fill = starts.clone();
    let mut sorted = vec![T::default(); starts[buckets] as usize];
    for (b, item) in items() {
        let slot = &mut fill[b as usize];
        sorted[*slot as usize] = item;
        *slot += 1;
    }
    for bucket in starts.windows(2) {
        sorted[bucket[0] as usize..bucket[1] as usize].sort_unstable();
    }
    (starts, sorted)
}

/// A `HashMap` with [`FastHasher`]: construction hashes every vertex once, and std's
/// SipHash (built against hash flooding, which cannot change what these maps return,
/// only how fast) cost more than the lookups.
type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHasher>>;

fn fast_map<K, V>(capacity: usize) -> FastMap<K, V> {
    FastMap::with_capacity_and_hasher(capacity, BuildHasherDefault::default())
}

/// A multiply-add hash over 8-byte words (rustc-hash 2's scheme): fast on the short
/// fixed-size integer keys used here (position bits, sorted vertex triples).
#[derive(Default)]
struct FastHasher(u64);

impl FastHasher {
    const K: u64 = 0xf135_7aea_2e62_a9c5;

    fn add(&mut self, word: u64) {
        self.0 = self.0.wrapping_add(word).wrapping_mul(Self::K);
    }
}

impl Hasher for FastHasher {
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            let mut word = [0u8; 8];
            word.copy_from_slice(c);
            self.add(u64::from_le_bytes(word));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut word = [0u8; 8];
            word[..rest.len()].copy_from_slice(rest);
            self.add(u64::from_le_bytes(word) ^ ((rest.len() as u64) << 59));
        }
    }

    fn write_u32(&mut self, i: u32) {
        self.add(u64::from(i));
    }

    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }

    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }

    fn finish(&self) -> u64 {
        // The product's high bits are the well-mixed ones; hashbrown indexes buckets
        // with the low bits.
        self.0.rotate_left(26)
    }
}

/// Vertices per chunk of the parallel edge build.
const EDGE_CHUNK: usize = 4096;

/// The edges whose smaller vertex lies in one chunk of vertices, in (min, max) order.
#[derive(Default)]
struct EdgeChunk {
    edges: Vec<[u32; 2]>,
    valence: Vec<u32>,
    /// The faces of each edge's first two half-edges (by corner), `NONE` where absent.
    faces: Vec<[u32; 2]>,
    /// Per vertex of the chunk, how many edges have it as their smaller vertex.
    per_vertex: Vec<u32>,
    /// Edges with more than two faces.
    non_manifold: Vec<[u32; 2]>,
}

/// Edges, edge-to-face, face-to-edge and face neighbours: per vertex `v` (chunks of
/// vertices on every thread), the half-edges of its faces whose smaller vertex is `v`,
/// sorted by (larger vertex, corner), so edges come in (min, max) order and each
/// edge's faces in corner order whatever the threads; then per face (on every
/// thread) its edges, looked up among its smaller vertex's. Needs the vertex-face
/// lists.
fn build_edges(mesh: &mut TriMesh) {
    let v_count = mesh.positions.len();
    let (triangles, offsets, ring) = (
        &mesh.triangles,
        &mesh.vertex_face_offsets,
        &mesh.vertex_faces,
    );
    let chunks: Vec<EdgeChunk> = (0..v_count.div_ceil(EDGE_CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut out = EdgeChunk::default();
            let mut half: Vec<(u32, u32)> = Vec::new();
            for v in (c * EDGE_CHUNK) as u32..((c + 1) * EDGE_CHUNK).min(v_count) as u32 {
                half.clear();
                for &f in &ring[offsets[v as usize] as usize..offsets[v as usize + 1] as usize] {
                    let t = triangles[f as usize];
                    for k in 0..3 {
                        let (a, b) = (t[k], t[(k + 1) % 3]);
                        if a.min(b) == v {
                            half.push((a.max(b), 3 * f + k as u32));
                        }
                    }
                }
                half.sort_unstable();
                let before = out.edges.len();
                let mut i = 0;
                while i < half.len() {
                    let max = half[i].0;
                    let mut j = i + 1;
                    while j < half.len() && half[j].0 == max {
                        j += 1;
                    }
                    out.edges.push([v, max]);
                    let valence = (j - i) as u32;
                    out.valence.push(valence);
                    let second = if valence >= 2 {
                        half[i + 1].1 / 3
                    } else {
                        NONE
                    };
                    out.faces.push([half[i].1 / 3, second]);
                    if valence > 2 {
                        out.non_manifold.push([v, max]);
                    }
                    i = j;
                }
                out.per_vertex.push((out.edges.len() - before) as u32);
            }
            out
        })
        .collect();
    let mut first_edge = Vec::with_capacity(v_count + 1);
    first_edge.push(0u32);
    let mut non_manifold = 0;
    let mut first_non_manifold = Vec::new();
    let edge_count = chunks.iter().map(|c| c.edges.len()).sum();
    mesh.edges.reserve_exact(edge_count);
    mesh.edge_valence.reserve_exact(edge_count);
    mesh.edge_faces.reserve_exact(edge_count);
    for chunk in chunks {
        for n in chunk.per_vertex {
            first_edge.push(first_edge[first_edge.len() - 1] + n);
        }
        non_manifold += chunk.non_manifold.len();
        let room = LIST_FIRST.saturating_sub(first_non_manifold.len());
        first_non_manifold.extend(chunk.non_manifold.into_iter().take(room));
        mesh.edges.extend(chunk.edges);
        mesh.edge_valence.extend(chunk.valence);
        mesh.edge_faces.extend(chunk.faces);
    }
    // Per face, each side's edge among those of its smaller vertex (a handful), and
    // the face across it where the edge has exactly two faces.
    let (edges, valence, edge_faces) = (&mesh.edges, &mesh.edge_valence, &mesh.edge_faces);
    (mesh.face_edges, mesh.face_neighbors) = mesh
        .triangles
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .enumerate()
        .map(|(f, t)| {
            let mut face_edges = [NONE; 3];
            let mut neighbors = [NONE; 3];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let (min, max) = (a.min(b), a.max(b));
                let range = first_edge[min as usize]..first_edge[min as usize + 1];
                // Every side of a face is an edge of its smaller vertex.
                let e = range
                    .clone()
                    .find(|&e| edges[e as usize][1] == max)
                    .unwrap_or(range.start);
                face_edges[k] = e;
                if valence[e as usize] == 2 {
                    let [f0, f1] = edge_faces[e as usize];
                    neighbors[k] = if f0 == f as u32 { f1 } else { f0 };
                }
            }
            (face_edges, neighbors)
        })
        .unzip();
    if non_manifold > 0 {
        mesh.warnings.push(MeshWarning::NonManifoldEdges {
            count: non_manifold,
            first: first_non_manifold,
        });
    }
}

/// CSR list of the faces around each vertex, in face order.
fn build_vertex_faces(mesh: &mut TriMesh) {
    let v_count = mesh.positions.len();
    let mut counts = vec![0u32; v_count + 1];
    for t in &mesh.triangles {
        for &v in t {
            counts[v as usize + 1] += 1;
        }
    }
    for i in 0..v_count {
        counts[i + 1] += counts[i];
    }
    let mut fill = counts.clone();
    let mut faces = vec![0u32; 3 * mesh.triangles.len()];
    for (f, t) in mesh.triangles.iter().enumerate() {
        for &v in t {
            faces[fill[v as usize] as usize] = f as u32;
            fill[v as usize] += 1;
        }
    }
    mesh.vertex_face_offsets = counts;
    mesh.vertex_faces = faces;
}

/// CSR list of the neighbouring vertices (and joining edges) around each vertex.
fn build_vertex_neighbors(mesh: &mut TriMesh) {
    let v_count = mesh.positions.len();
    let mut ncounts = vec![0u32; v_count + 1];
    for [a, b] in &mesh.edges {
        ncounts[*a as usize + 1] += 1;
        ncounts[*b as usize + 1] += 1;
    }
    for i in 0..v_count {
        ncounts[i + 1] += ncounts[i];
    }
    let mut fill = ncounts.clone();
    // (neighbour, edge) pairs, sorted by neighbour within each vertex.
    let mut pairs = vec![(0u32, 0u32); 2 * mesh.edges.len()];
    for (e, [a, b]) in mesh.edges.iter().enumerate() {
        pairs[fill[*a as usize] as usize] = (*b, e as u32);
        fill[*a as usize] += 1;
        pairs[fill[*b as usize] as usize] = (*a, e as u32);
        fill[*b as usize] += 1;
    }
    for v in 0..v_count {
        pairs[ncounts[v] as usize..ncounts[v + 1] as usize].sort_unstable();
    }
    let nbrs: Vec<u32> = pairs.iter().map(|p| p.0).collect();
    mesh.vertex_neighbor_edges = pairs.iter().map(|p| p.1).collect();
    mesh.vertex_neighbor_offsets = ncounts;
    mesh.vertex_neighbors = nbrs;
}

/// Boundary loops: chains of boundary edges (edges with exactly one face). Each edge is
/// used exactly once. A loop starts along an edge in its face's direction and, at each
/// vertex, continues along an unused boundary edge that leaves the vertex in its own
/// face's direction if there is one, so on a consistently oriented mesh every loop
/// follows its faces' orientation. Otherwise (faces wound inconsistently, or a
/// non-orientable surface such as a Möbius strip) it continues along any unused boundary
/// edge at the vertex, so loops stay closed instead of breaking into open chains. Robust
/// to non-manifold vertices (several loops through one vertex). Only next to
/// non-manifold edges, where a vertex can touch an odd number of boundary edges, can a
/// chain end away from its start.
fn build_boundary_loops(mesh: &mut TriMesh) {
    // Each boundary edge as (from, to) in its face's direction, and the boundary edges
    // touching each vertex, in face order (so the walk is deterministic).
    let mut ends: Vec<(u32, u32)> = Vec::new();
    let mut touching: FastMap<u32, Vec<u32>> = fast_map(0);
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let e = mesh.face_edges[f][k];
            if mesh.edge_valence[e as usize] == 1 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                touching.entry(a).or_default().push(ends.len() as u32);
                touching.entry(b).or_default().push(ends.len() as u32);
                ends.push((a, b));
            }
        }
    }
    let mut used = vec![false; ends.len()];
    for start in 0..ends.len() {
        if used[start] {
            continue;
        }
        let mut lp = Vec::new();
        let (mut h, mut from) = (start, ends[start].0);
        loop {
            used[h] = true;
            lp.push(from);
            let (a, b) = ends[h];
            let to = if from == a { b } else { a };
            let unused = || {
                touching
                    .get(&to)
                    .into_iter()
                    .flatten()
                    .map(|&n| n as usize)
                    .filter(|&n| !used[n])
            };
            let next = unused()
                .find(|&n| ends[n].0 == to)
                .or_else(|| unused().next());
            match next {
                Some(n) => {
                    h = n;
                    from = to;
                }
                None => break,
            }
        }
        mesh.boundary_loops.push(lp);
    }
}

/// Connected components over manifold edges (breadth-first, deterministic).
fn build_components(mesh: &mut TriMesh) {
    let f_count = mesh.triangles.len();
    let mut comp = vec![NONE; f_count];
    let mut count = 0u32;
    let mut queue = Vec::new();
    for seed in 0..f_count {
        if comp[seed] != NONE {
            continue;
        }
        comp[seed] = count;
        queue.clear();
        queue.push(seed as u32);
        while let Some(f) = queue.pop() {
            for &n in &mesh.face_neighbors[f as usize] {
                if n != NONE && comp[n as usize] == NONE {
                    comp[n as usize] = count;
                    queue.push(n);
                }
            }
        }
        count += 1;
    }
    mesh.face_component = comp;
    mesh.component_count = count as usize;
    if count > 1 {
        mesh.warnings.push(MeshWarning::SeveralComponents {
            count: count as usize,
        });
    }
}

/// Face areas and normals; area-weighted vertex normals.
fn build_geometry(mesh: &mut TriMesh) {
    // Twice the area times the unit normal, per face (on every thread).
    let positions = &mesh.positions;
    let doubled: Vec<DVec3> = mesh
        .triangles
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            (b - a).cross(c - a)
        })
        .collect();
    mesh.face_areas = doubled
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .map(|n2| 0.5 * n2.length())
        .collect();
    mesh.face_normals = doubled
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .map(|n2| n2.normalize_or_zero())
        .collect();
    // Each vertex sums its faces in face order (the order of its CSR list), so the
    // result does not depend on the threads.
    let (offsets, faces, normals) = (
        &mesh.vertex_face_offsets,
        &mesh.vertex_faces,
        &mesh.face_normals,
    );
    mesh.vertex_normals = (0..mesh.positions.len())
        .into_par_iter()
        .with_min_len(MIN_PARALLEL)
        .map(|v| {
            let ring = &faces[offsets[v] as usize..offsets[v + 1] as usize];
            let sum = ring
                .iter()
                .fold(DVec3::ZERO, |s, &f| s + doubled[f as usize]);
            // A vertex whose faces cancel out (a pinched fold) keeps its first face's
            // normal.
            sum.try_normalize()
                .unwrap_or_else(|| normals[ring[0] as usize])
        })
        .collect();
}
