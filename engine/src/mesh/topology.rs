//! Construction of a [`TriMesh`]: validation, repairs and adjacency.

use std::collections::HashMap;

use glam::DVec3;

use super::{MeshError, MeshWarning, NONE, TriMesh};

/// How many offending items a warning lists.
const LIST_FIRST: usize = 8;

pub(super) fn build(
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    mut warnings: Vec<MeshWarning>,
) -> Result<TriMesh, MeshError> {
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

    // Merge vertices at bitwise-identical positions (-0.0 and 0.0 count as equal).
    let key = |p: DVec3| [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
    let mut first_at: HashMap<[u64; 3], u32> = HashMap::with_capacity(input_vertices);
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

    // Remove degenerate (repeated vertex or zero area) and duplicated faces.
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    let mut degenerate = Vec::new();
    let mut degenerate_count = 0;
    let mut duplicate_count = 0;
    let mut seen_faces: HashMap<[u32; 3], ()> = HashMap::with_capacity(triangles.len());
    for (face, t) in triangles.iter().enumerate() {
        let t = t.map(|v| merged_to[v as usize]);
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let repeated = t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
        if repeated || (b - a).cross(c - a).length_squared() == 0.0 {
            degenerate_count += 1;
            if degenerate.len() < LIST_FIRST {
                degenerate.push(face);
            }
            continue;
        }
        let mut sorted = t;
        sorted.sort_unstable();
        if seen_faces.insert(sorted, ()).is_some() {
            duplicate_count += 1;
            continue;
        }
        kept.push(t);
    }
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
    build_edges(&mut mesh);
    build_vertex_rings(&mut mesh);
    build_boundary_loops(&mut mesh);
    build_components(&mut mesh);
    build_geometry(&mut mesh);
    Ok(mesh)
}

/// Edges, edge-to-face, face-to-edge and face neighbours, by sorting half-edge keys.
fn build_edges(mesh: &mut TriMesh) {
    let f_count = mesh.triangles.len();
    // (min vertex, max vertex, face, corner) for every half-edge.
    let mut half: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(3 * f_count);
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            half.push((a.min(b), a.max(b), f as u32, k as u8));
        }
    }
    half.sort_unstable();
    mesh.face_edges = vec![[NONE; 3]; f_count];
    mesh.face_neighbors = vec![[NONE; 3]; f_count];
    let mut non_manifold = 0;
    let mut first_non_manifold = Vec::new();
    let mut i = 0;
    while i < half.len() {
        let mut j = i + 1;
        while j < half.len() && half[j].0 == half[i].0 && half[j].1 == half[i].1 {
            j += 1;
        }
        let e = mesh.edges.len() as u32;
        mesh.edges.push([half[i].0, half[i].1]);
        let valence = (j - i) as u32;
        mesh.edge_valence.push(valence);
        let second = if valence >= 2 { half[i + 1].2 } else { NONE };
        mesh.edge_faces.push([half[i].2, second]);
        for h in &half[i..j] {
            mesh.face_edges[h.2 as usize][h.3 as usize] = e;
        }
        if valence == 2 {
            let (f0, k0, f1, k1) = (half[i].2, half[i].3, half[i + 1].2, half[i + 1].3);
            mesh.face_neighbors[f0 as usize][k0 as usize] = f1;
            mesh.face_neighbors[f1 as usize][k1 as usize] = f0;
        } else if valence > 2 {
            non_manifold += 1;
            if first_non_manifold.len() < LIST_FIRST {
                first_non_manifold.push([half[i].0, half[i].1]);
            }
        }
        i = j;
    }
    if non_manifold > 0 {
        mesh.warnings.push(MeshWarning::NonManifoldEdges {
            count: non_manifold,
            first: first_non_manifold,
        });
    }
}

/// CSR lists of faces and of neighbouring vertices around each vertex.
fn build_vertex_rings(mesh: &mut TriMesh) {
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
    let mut touching: HashMap<u32, Vec<u32>> = HashMap::new();
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
    let mut vertex_normals = vec![DVec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let n2 = (b - a).cross(c - a); // twice the area times the unit normal
        mesh.face_areas.push(0.5 * n2.length());
        mesh.face_normals.push(n2.normalize_or_zero());
        for &v in t {
            vertex_normals[v as usize] += n2;
        }
    }
    for (v, n) in vertex_normals.iter_mut().enumerate() {
        // A vertex whose faces cancel out (a pinched fold) keeps its first face's normal.
        *n = n.try_normalize().unwrap_or_else(|| {
            let f = mesh.vertex_faces[mesh.vertex_face_offsets[v] as usize];
            mesh.face_normals[f as usize]
        });
    }
    mesh.vertex_normals = vertex_normals;
}
