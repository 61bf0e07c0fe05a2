//! Construction of a [`TriMesh`]: validation, repairs and adjacency.

use glam::DVec3;

use super::{MeshError, MeshWarning, NONE, TriMesh};
use crate::fast_map::{FastMap, fast_map};

/// How many offending items a warning lists.
const LIST_FIRST: usize = 8;

/// Faces from which [`build`] computes the geometry on a second thread beside the
/// topology: below it, handing work to the thread pool costs more than it saves.
const SIDE_BY_SIDE_FACES: usize = 1 << 17;

/// Largest coordinate magnitude a mesh may have: 1e50. Preprocessing squares lengths
/// (areas, normals, field solves) and multiplies them by densities, and beyond about
/// 1e100 that overflows `f64` (1e100 failed as a zero fallback field, 1e200 inside a
/// Cholesky factorization); 1e50 leaves room for densities up to 1e100.
pub const MAX_COORDINATE: f64 = 1e50;

/// Smallest bounding-box diagonal a mesh with any extent may have: 1e-50, for the same
/// reason at the other end (at 1e-100 every face's area underflows to zero).
pub const MIN_EXTENT: f64 = 1e-50;

/// Checks [`MAX_COORDINATE`] and [`MIN_EXTENT`]. A mesh of one point (extent zero) is
/// left to the emptiness check, which says so.
fn check_scale(positions: &[DVec3]) -> Result<(), MeshError> {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for (vertex, &p) in positions.iter().enumerate() {
        if p.abs().max_element() > MAX_COORDINATE {
            return Err(MeshError::CoordinateOutOfRange {
                vertex,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let extent = if positions.is_empty() {
        0.0
    } else {
        (hi - lo).length()
    };
    if extent > 0.0 && extent < MIN_EXTENT {
        return Err(MeshError::TooSmall { extent });
    }
    Ok(())
}

/// Validates, repairs and indexes a mesh: checks the input ([`check_input`]), merges
/// vertices at equal positions, removes degenerate and duplicated faces and
/// unreferenced vertices (each repair noted in `warnings`), then builds the adjacency
/// and geometry ([`assemble`]).
pub(super) fn build(
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    mut warnings: Vec<MeshWarning>,
) -> Result<TriMesh, MeshError> {
    check_input(&positions, &triangles)?;
    let merged_to = merge_vertices(&positions, &mut warnings);
    let kept = remove_faces(&positions, &triangles, &merged_to, &mut warnings);
    let compact = compact_vertices(&positions, kept, &merged_to, &mut warnings)?;
    Ok(assemble(compact, warnings))
}

/// Checks that positions are finite and within scale ([`check_scale`]) and that every
/// index names a vertex.
fn check_input(positions: &[DVec3], triangles: &[[u32; 3]]) -> Result<(), MeshError> {
    let input_vertices = positions.len();
    for (vertex, p) in positions.iter().enumerate() {
        if !p.is_finite() {
            return Err(MeshError::NonFiniteVertex {
                vertex,
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
    }
    check_scale(positions)?;
    for (face, t) in triangles.iter().enumerate() {
        for &index in t {
            if index as usize >= input_vertices {
                return Err(MeshError::IndexOutOfRange {
                    face,
                    index: index as i64,
                    vertex_count: input_vertices,
                });
            }
        }
    }
    Ok(())
}

/// Per input vertex, the first input vertex at its bitwise-identical position (-0.0
/// and 0.0 count as equal); itself when it is the first.
fn merge_vertices(positions: &[DVec3], warnings: &mut Vec<MeshWarning>) -> Vec<u32> {
    let input_vertices = positions.len();
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
    merged_to
}

/// The faces, on merged vertices, that are neither degenerate (repeated vertex or zero
/// area) nor duplicated (see [`later_duplicates`]), in input order.
fn remove_faces(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    merged_to: &[u32],
    warnings: &mut Vec<MeshWarning>,
) -> Vec<[u32; 3]> {
    let mut degenerate = Vec::new();
    let mut degenerate_count = 0;
    let mut merged_triangles: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    let mut sets: Vec<Option<[u32; 3]>> = Vec::with_capacity(triangles.len());
    for (face, t) in triangles.iter().enumerate() {
        let t = t.map(|v| merged_to[v as usize]);
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let repeated = t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
        merged_triangles.push(t);
        if repeated || (b - a).cross(c - a).length_squared() == 0.0 {
            degenerate_count += 1;
            if degenerate.len() < LIST_FIRST {
                degenerate.push(face);
            }
            sets.push(None);
        } else {
            let mut sorted = t;
            sorted.sort_unstable();
            sets.push(Some(sorted));
        }
    }
    let duplicate = later_duplicates(&sets, positions.len());
    let duplicate_count = duplicate.iter().filter(|&&d| d).count();
    let kept: Vec<[u32; 3]> = merged_triangles
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
    kept
}

/// Per face, whether it duplicates an earlier face: whether an earlier face that is not
/// degenerate has the same sorted vertex set (`None` for a degenerate face). Sets are
/// compared by bucketing them by their smallest vertex, below `vertex_count`.
fn later_duplicates(sets: &[Option<[u32; 3]>], vertex_count: usize) -> Vec<bool> {
    let (starts, by_smallest) = bucket_sort(vertex_count, || {
        sets.iter()
            .enumerate()
            .filter_map(|(f, s)| s.map(|[a, b, c]| (a, [b, c, f as u32])))
    });
    let mut duplicate = vec![false; sets.len()];
    for bucket in starts.windows(2) {
        let bucket = &by_smallest[bucket[0] as usize..bucket[1] as usize];
        for pair in bucket.windows(2) {
            if pair[0][..2] == pair[1][..2] {
                duplicate[pair[1][2] as usize] = true; // the later face of the two
            }
        }
    }
    duplicate
}

/// A mesh's kept faces on its referenced vertices only.
struct Compact {
    /// Referenced vertices' positions, in input order.
    positions: Vec<DVec3>,
    /// Kept faces on the compact vertex numbering.
    triangles: Vec<[u32; 3]>,
    /// Per input vertex, its compact vertex, or `NONE` (see [`TriMesh`]).
    input_vertex_map: Vec<u32>,
}

/// Keeps only the vertices `kept` references, in input order, and renumbers `kept` on
/// them; [`MeshError::Empty`] when nothing is left.
fn compact_vertices(
    positions: &[DVec3],
    mut kept: Vec<[u32; 3]>,
    merged_to: &[u32],
    warnings: &mut Vec<MeshWarning>,
) -> Result<Compact, MeshError> {
    let input_vertices = positions.len();
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
    Ok(Compact {
        positions: compact_positions,
        triangles: kept,
        input_vertex_map,
    })
}

/// The [`TriMesh`] of a valid compact mesh: its topology (edges, vertex rings,
/// boundary loops, components) and its [`Geometry`].
fn assemble(compact: Compact, warnings: Vec<MeshWarning>) -> TriMesh {
    let Compact {
        positions: compact_positions,
        triangles: kept,
        input_vertex_map,
    } = compact;
    // Topology and geometry are independent: on a large mesh they are built side by
    // side (each is sequential, so the result does not depend on the threads).
    let v_count = compact_positions.len();
    let mut mesh = TriMesh {
        positions: Vec::new(),
        triangles: Vec::new(),
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
    let topology = |mesh: &mut TriMesh| {
        build_edges(mesh, &kept, v_count);
        build_vertex_rings(mesh, &kept, v_count);
        build_boundary_loops(mesh, &kept);
        build_components(mesh);
    };
    let geometry = if kept.len() >= SIDE_BY_SIDE_FACES {
        rayon::join(
            || topology(&mut mesh),
            || geometry(&compact_positions, &kept),
        )
        .1
    } else {
        topology(&mut mesh);
        geometry(&compact_positions, &kept)
    };
    mesh.positions = compact_positions;
    mesh.triangles = kept;
    mesh.face_areas = geometry.face_areas;
    mesh.face_normals = geometry.face_normals;
    mesh.vertex_normals = geometry.vertex_normals;
    mesh
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

/// Edges, edge-to-face, face-to-edge and face neighbours, from the half-edges in
/// (min vertex, max vertex, face, corner) order.
fn build_edges(mesh: &mut TriMesh, triangles: &[[u32; 3]], v_count: usize) {
    let f_count = triangles.len();
    // Half-edges by smallest vertex, each bucket sorted by (largest vertex, face,
    // corner): the lexicographic order of (min, max, face, corner), in O(F). The
    // corner is numbered 3 f + k, which fits a u32 as the vertex-face offsets do.
    let (starts, half) = bucket_sort(v_count, || {
        triangles.iter().enumerate().flat_map(|(f, t)| {
            (0..3).map(move |k| {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let corner = 3 * f as u32 + k as u32;
                (a.min(b), (u64::from(a.max(b)) << 32) | u64::from(corner))
            })
        })
    });
    mesh.face_edges = vec![[NONE; 3]; f_count];
    mesh.face_neighbors = vec![[NONE; 3]; f_count];
    let mut non_manifold = 0;
    let mut first_non_manifold = Vec::new();
    let face_corner = |h: u64| (h as u32 / 3, h as u32 % 3);
    for (min, bucket) in starts.windows(2).enumerate() {
        let half = &half[bucket[0] as usize..bucket[1] as usize];
        let mut i = 0;
        while i < half.len() {
            let max = (half[i] >> 32) as u32;
            let mut j = i + 1;
            while j < half.len() && (half[j] >> 32) as u32 == max {
                j += 1;
            }
            let edge = [min as u32, max];
            let e = mesh.edges.len() as u32;
            mesh.edges.push(edge);
            let valence = (j - i) as u32;
            mesh.edge_valence.push(valence);
            let (f0, k0) = face_corner(half[i]);
            let second = if valence >= 2 {
                face_corner(half[i + 1]).0
            } else {
                NONE
            };
            mesh.edge_faces.push([f0, second]);
            for &h in &half[i..j] {
                let (f, k) = face_corner(h);
                mesh.face_edges[f as usize][k as usize] = e;
            }
            if valence == 2 {
                let (f1, k1) = face_corner(half[i + 1]);
                mesh.face_neighbors[f0 as usize][k0 as usize] = f1;
                mesh.face_neighbors[f1 as usize][k1 as usize] = f0;
            } else if valence > 2 {
                non_manifold += 1;
                if first_non_manifold.len() < LIST_FIRST {
                    first_non_manifold.push(edge);
                }
            }
            i = j;
        }
    }
    if non_manifold > 0 {
        mesh.warnings.push(MeshWarning::NonManifoldEdges {
            count: non_manifold,
            first: first_non_manifold,
        });
    }
}

/// The triangles around each of `v_count` vertices as CSR: offsets per vertex and
/// triangle indices, ascending within each vertex (a counting sort, O(V + F)).
pub(crate) fn vertex_triangles(triangles: &[[u32; 3]], v_count: usize) -> (Vec<u32>, Vec<u32>) {
    let mut counts = vec![0u32; v_count + 1];
    for t in triangles {
        for &v in t {
            counts[v as usize + 1] += 1;
        }
    }
    for i in 0..v_count {
        counts[i + 1] += counts[i];
    }
    let mut fill = counts.clone();
    let mut faces = vec![0u32; 3 * triangles.len()];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            faces[fill[v as usize] as usize] = f as u32;
            fill[v as usize] += 1;
        }
    }
    (counts, faces)
}

/// CSR lists of faces and of neighbouring vertices around each vertex.
fn build_vertex_rings(mesh: &mut TriMesh, triangles: &[[u32; 3]], v_count: usize) {
    let (counts, faces) = vertex_triangles(triangles, v_count);
    mesh.vertex_face_offsets = counts;
    mesh.vertex_faces = faces;

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
fn build_boundary_loops(mesh: &mut TriMesh, triangles: &[[u32; 3]]) {
    // Each boundary edge as (from, to) in its face's direction, and the boundary edges
    // touching each vertex, in face order (so the walk is deterministic).
    let mut ends: Vec<(u32, u32)> = Vec::new();
    let mut touching: FastMap<u32, Vec<u32>> = fast_map(0);
    for (f, t) in triangles.iter().enumerate() {
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
    let f_count = mesh.face_neighbors.len();
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

/// Face areas and unit normals, and area-weighted vertex normals.
struct Geometry {
    face_areas: Vec<f64>,
    face_normals: Vec<DVec3>,
    vertex_normals: Vec<DVec3>,
}

/// The [`Geometry`] of a mesh (every vertex used by a face).
fn geometry(positions: &[DVec3], triangles: &[[u32; 3]]) -> Geometry {
    let mut face_areas = Vec::with_capacity(triangles.len());
    let mut face_normals = Vec::with_capacity(triangles.len());
    let mut vertex_normals = vec![DVec3::ZERO; positions.len()];
    // The lowest face of each vertex (its normal is the fallback below).
    let mut first_face = vec![NONE; positions.len()];
    for (f, t) in triangles.iter().enumerate() {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let n2 = (b - a).cross(c - a); // twice the area times the unit normal
        face_areas.push(0.5 * n2.length());
        face_normals.push(n2.normalize_or_zero());
        for &v in t {
            vertex_normals[v as usize] += n2;
            if first_face[v as usize] == NONE {
                first_face[v as usize] = f as u32;
            }
        }
    }
    for (v, n) in vertex_normals.iter_mut().enumerate() {
        // A vertex whose faces cancel out (a pinched fold) keeps its first face's normal.
        *n = n
            .try_normalize()
            .unwrap_or_else(|| face_normals[first_face[v] as usize]);
    }
    Geometry {
        face_areas,
        face_normals,
        vertex_normals,
    }
}
