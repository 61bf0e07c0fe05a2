//! Field-following shortest paths over mesh edges (paper section 4.1.2): Dijkstra with
//! an edge cost that is low along field lines, and the minimum spanning tree of the
//! shortest paths joining a region's singularities.
//!
//! Input: a [`TriMesh`], a [`TensorField`] (for the costs), singular faces and a region
//! (a face mask). Output: edge costs, shortest-path trees, and the mesh edges of a
//! singularity tree. Cost: O(E) for the costs; O((V + E) log V) per Dijkstra (only the
//! allowed part of the mesh is explored, but `dist`/`pred_edge` are O(V) arrays); a
//! singularity tree is one multi-source Dijkstra plus an O(E log E) Kruskal whatever
//! the number of singularities (Mehlhorn 1988, "A faster approximation algorithm for
//! the Steiner problem in graphs"), plus one early-stopped Dijkstra per lone
//! singularity.
//!
//! The paper's distance `D_ij` is the angle between the major eigenvectors at the two
//! ends of an edge, times its length: it keeps paths where the field turns little, but
//! says nothing about whether the edge runs *along* the field. [`field_edge_costs`] adds
//! that term (see there), which is what makes the paths follow field lines, as the
//! paper asks ("paths lying along the tensor field lines"). Everything here is
//! sequential and deterministic: the heap breaks distance ties by the lower vertex
//! index, relaxation ties by the lower edge index, Kruskal ties by the lower node
//! indices, then edge index.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use rayon::prelude::*;

use super::singularity::{LineFieldTransport, line_field_transport};
use crate::field::{TensorField, eigen_in_plane};
use crate::mesh::face_set::{DENSE_SHARE, MaskFaces};
use crate::mesh::{NONE, TriMesh};

/// Cost per unit length of an edge that runs exactly along a field line through a field
/// that does not turn: the floor that keeps every cost positive, so that among
/// equally aligned routes the shorter one wins.
pub const COST_FLOOR: f64 = 0.05;

/// Coherence `(l1 - l2) / (l1 + l2)` at which the angle terms of [`field_edge_costs`]
/// count half: below it the field's directions fade out of the cost (they are noise
/// where the field is nearly isotropic).
pub const HALF_WEIGHT_COHERENCE: f64 = 0.05;

/// Field-following cost of every mesh edge, always finite and `> 0`:
///
/// `cost_e = |e| (COST_FLOOR + w (alpha_e + tau_e))`, with
/// - `alpha_e` in `[0, pi/4]`: the angle between the edge and the nearest of the major
///   and minor field lines of the mean of its two end tensors, in the plane normal to
///   the mean of the two vertex normals (paths may follow either family of lines);
/// - `tau_e` in `[0, pi/2]`: the paper's `D_ij`, the angle between the major directions
///   at the two ends, compared through the connection of
///   [`line_field_transport`] (`|edge_turn| / 2`);
/// - `w = c / (c + HALF_WEIGHT_COHERENCE)` with `c` the coherence of the mean tensor,
///   so that both angles fade out where the field is isotropic and the cost becomes
///   plain length there.
///
/// O(V + E + F) (one [`line_field_transport`]).
pub fn field_edge_costs(mesh: &TriMesh, field: &TensorField) -> Vec<f64> {
    field_edge_costs_with(mesh, field, &line_field_transport(mesh, field))
}

/// [`field_edge_costs`] with the field's transport already computed (the segmentation
/// also needs it to find singularities, so it computes it once for both).
pub fn field_edge_costs_with(
    mesh: &TriMesh,
    field: &TensorField,
    transport: &LineFieldTransport,
) -> Vec<f64> {
    let pos = mesh.positions();
    let normals = mesh.vertex_normals();
    let tensors = field.tensors();
    // Each edge's cost alone, in parallel (an eigen-decomposition each: 0.3 s of one
    // core at 1.1M faces); the same values for any thread count.
    mesh.edges()
        .par_iter()
        .enumerate()
        .map(|(e, &[a, b])| {
            let (a, b) = (a as usize, b as usize);
            let d = pos[b] - pos[a];
            let length = d.length();
            let mut n = normals[a] + normals[b];
            if n.length_squared() < 1e-24 {
                n = mesh.face_normals()[mesh.edge_faces()[e][0] as usize];
            }
            let n = n.normalize();
            let eig = eigen_in_plane(&((tensors[a] + tensors[b]) * 0.5), n);
            let along = d - n * n.dot(d);
            let alpha = if along.length_squared() > 1e-24 * length * length {
                let angle = super::line_angle(along.normalize(), eig.major);
                angle.min(std::f64::consts::FRAC_PI_2 - angle)
            } else {
                0.0
            };
            let trace = eig.l1 + eig.l2;
            let coherence = if trace > 0.0 {
                ((eig.l1 - eig.l2) / trace).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let weight = coherence / (coherence + HALF_WEIGHT_COHERENCE);
            let tau = 0.5 * transport.edge_turn[e].abs();
            (length * (COST_FLOOR + weight * (alpha + tau))).max(f64::MIN_POSITIVE)
        })
        .collect()
}

/// A shortest-path forest from a set of sources.
#[derive(Clone, Debug, PartialEq)]
pub struct ShortestPaths {
    /// Per vertex, the cost of the cheapest path from any source (`f64::INFINITY` where
    /// unreachable; 0 at the sources).
    pub dist: Vec<f64>,
    /// Per vertex, the last edge of that path ([`NONE`] at sources and unreachable
    /// vertices).
    pub pred_edge: Vec<u32>,
}

impl ShortestPaths {
    /// The edges of the cheapest path to `target`, in order from its source to
    /// `target`; empty if `target` is a source or unreachable. O(path length).
    pub fn path_edges(&self, mesh: &TriMesh, target: u32) -> Vec<u32> {
        self.path_edges_in(mesh, target, &|v| v as usize)
    }

    /// [`path_edges`](Self::path_edges) for paths whose vertex `v` is entry `index(v)`.
    fn path_edges_in(&self, mesh: &TriMesh, target: u32, index: &dyn Fn(u32) -> usize) -> Vec<u32> {
        let mut path = Vec::new();
        let mut v = target;
        while self.pred_edge[index(v)] != NONE {
            let e = self.pred_edge[index(v)];
            path.push(e);
            let [a, b] = mesh.edges()[e as usize];
            v = if a == v { b } else { a };
        }
        path.reverse();
        path
    }
}

/// Vertex-to-edge incidence: each vertex's `(neighbour, edge)` pairs sorted by
/// neighbour, read from the mesh's own one-ring tables (built once with the mesh).
pub(crate) struct VertexEdges<'a> {
    mesh: &'a TriMesh,
}

impl<'a> VertexEdges<'a> {
    pub(crate) fn new(mesh: &'a TriMesh) -> Self {
        Self { mesh }
    }

    fn of(&self, v: u32) -> impl Iterator<Item = (u32, u32)> + 'a {
        let mesh = self.mesh;
        mesh.vertex_neighbors(v)
            .iter()
            .copied()
            .zip(mesh.vertex_edges(v).iter().copied())
    }
}

/// The vertices a Dijkstra run may reach, and where each is stored: vertex `v` is
/// entry `index(v)` of `count` (the identity over the whole mesh, or a region's
/// vertices, so that a run over a small region of a large mesh costs in proportion
/// to the region). Every vertex reachable through allowed edges must have an entry.
struct Vertices<'a> {
    count: usize,
    index: &'a dyn Fn(u32) -> usize,
}

/// Dijkstra over `adjacency`; stops early at the first settled vertex for which `stop`
/// holds and returns it. The paths are stored by `vertices.index`.
fn run_dijkstra(
    adjacency: &VertexEdges<'_>,
    vertices: &Vertices<'_>,
    costs: &[f64],
    sources: &[u32],
    allowed: &dyn Fn(u32) -> bool,
    stop: &dyn Fn(u32) -> bool,
) -> (ShortestPaths, Option<u32>) {
    let (count, at) = (vertices.count, vertices.index);
    let mut dist = vec![f64::INFINITY; count];
    let mut pred_edge = vec![NONE; count];
    let mut settled = vec![false; count];
    // Non-negative floats order like their bit patterns.
    let mut heap = BinaryHeap::new();
    for &s in sources {
        dist[at(s)] = 0.0;
        heap.push(Reverse((0u64, s)));
    }
    let mut reached = None;
    while let Some(Reverse((bits, v))) = heap.pop() {
        let iv = at(v);
        if settled[iv] || bits != dist[iv].to_bits() {
            continue;
        }
        settled[iv] = true;
        if stop(v) {
            reached = Some(v);
            break;
        }
        for (w, e) in adjacency.of(v) {
            if !allowed(e) {
                continue;
            }
            let iw = at(w);
            if settled[iw] {
                continue;
            }
            let nd = dist[iv] + costs[e as usize];
            let old = dist[iw];
            if nd < old || (nd == old && e < pred_edge[iw]) {
                dist[iw] = nd;
                pred_edge[iw] = e;
                if nd < old {
                    heap.push(Reverse((nd.to_bits(), w)));
                }
            }
        }
    }
    (ShortestPaths { dist, pred_edge }, reached)
}

/// Cheapest paths from `sources` (vertices, at distance 0) over the mesh's edges for
/// which `allowed` holds, with non-negative edge `costs` (one per mesh edge, e.g. from
/// [`field_edge_costs`]). Deterministic: distance ties are settled lower vertex first,
/// and a vertex reached at equal cost by two edges keeps the lower edge.
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, segment::paths};
/// let mesh = shapes::plane(1.0, 8)?;
/// let spec = FieldSpec::Constant { direction: [1.0, 0.0, 0.0], anisotropy: 2.0, density: 1.0 };
/// let costs = paths::field_edge_costs(&mesh, &spec.build(&mesh)?);
/// let tree = paths::dijkstra(&mesh, &costs, &[0], &|_| true);
/// // Along the field (the x axis, vertices 0..=8) the path is straight.
/// assert_eq!(tree.path_edges(&mesh, 8).len(), 8);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn dijkstra(
    mesh: &TriMesh,
    costs: &[f64],
    sources: &[u32],
    allowed: &dyn Fn(u32) -> bool,
) -> ShortestPaths {
    assert_eq!(costs.len(), mesh.edge_count(), "one cost per mesh edge");
    let adjacency = VertexEdges::new(mesh);
    let whole = Vertices {
        count: mesh.vertex_count(),
        index: &|v| v as usize,
    };
    run_dijkstra(&adjacency, &whole, costs, sources, allowed, &|_| false).0
}

/// Smallest-root union-find with path halving.
pub(crate) struct UnionFind(Vec<u32>);

impl UnionFind {
    pub(crate) fn new(n: usize) -> Self {
        Self((0..n as u32).collect())
    }

    pub(crate) fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            self.0[i as usize] = self.0[self.0[i as usize] as usize];
            i = self.0[i as usize];
        }
        i
    }

    /// Joins the sets of `a` and `b`; false if they were already one.
    pub(crate) fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.0[ra.max(rb) as usize] = ra.min(rb);
        true
    }
}

/// The mesh edges (ascending) that join the singularities of a region along the field
/// (paper section 4.1.2, Fig. 6).
///
/// - Nodes: the singular faces of `singular_faces` that lie in `region` (a mask over
///   faces; others are ignored), each represented by its lowest-index vertex so that
///   the paths meet and the result is connected as an edge set.
/// - Paths use only edges with at least one adjacent face in the region.
/// - Two or more nodes: the minimum spanning tree of the complete graph whose edges are
///   the pairwise shortest paths (paper), computed without the `k^2` paths: one
///   multi-source Dijkstra splits the region into the nodes' Voronoi cells, and Kruskal
///   over the cheapest links `d(u) + c(u, v) + d(v)` between cells yields a minimum
///   spanning tree of that complete graph (Mehlhorn 1988); its paths are returned. They
///   run inside the cells and cannot cross, so the result is a tree (a forest if the
///   region is disconnected); a final Kruskal pass enforces this anyway.
/// - A node with no other node reachable (a lone singularity): the shortest path from
///   any corner of its face to the region's boundary (edges whose two faces are not
///   both in the region, including mesh boundary edges); empty if the face already
///   touches it.
/// - A lone singularity in a region without a boundary (a closed component): nothing.
///   The singular face is removed from its segment and sampled isotropically (paper
///   section 4.1.2), so the hole it leaves is already the boundary the path would
///   lead to; disc cutting ([`disc_cuts`](super::topology::disc_cuts)) handles the
///   rest of the topology.
///
/// Cost: one Dijkstra over the mesh, O(E log E) for the links, one early-stopped
/// Dijkstra per lone node. A region with at least 1/16 of the mesh's vertices finds
/// their places in a per-mesh-vertex table (`MaskFaces`), not by binary search, and a
/// region of more than about 1/100 of the mesh lists its corners and edges by marking,
/// not sorting (bunny subdivided twice, smooth field, one region of nearly the whole
/// mesh: 1.1 s -> 0.35 s, the same edges).
pub fn singularity_tree(
    mesh: &TriMesh,
    costs: &[f64],
    singular_faces: &[u32],
    region: &[bool],
) -> Vec<u32> {
    singularity_tree_to(mesh, costs, singular_faces, region, &[])
}

/// [`singularity_tree`] with each singular face represented by its lowest-index
/// corner among those flagged in `ends` (one flag per mesh vertex; empty: none
/// flagged), and by its lowest-index corner where none is. The surface pipeline flags
/// the vertices the parameterization cannot comb around
/// ([`comb_flip_vertices`](super::comb_flip_vertices)), so that the tree's cuts end
/// where the per-face frames wind.
pub fn singularity_tree_to(
    mesh: &TriMesh,
    costs: &[f64],
    singular_faces: &[u32],
    region: &[bool],
    ends: &[bool],
) -> Vec<u32> {
    assert_eq!(costs.len(), mesh.edge_count(), "one cost per mesh edge");
    assert!(
        ends.is_empty() || ends.len() == mesh.vertex_count(),
        "one end flag per mesh vertex"
    );
    assert_eq!(region.len(), mesh.face_count(), "one region flag per face");
    let mut nodes: Vec<u32> = singular_faces
        .iter()
        .copied()
        .filter(|&f| in_region(region, f))
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let k = nodes.len();
    if k == 0 {
        return Vec::new();
    }
    let part = RegionPart::new(mesh, region);
    let corners = |i: usize| mesh.triangles()[nodes[i] as usize];
    let reps = node_representatives(mesh, &nodes, ends);
    let (mut union, degree) = part.voronoi_tree(costs, &reps);
    // Path ends that must stay: the singular faces' corners and the boundary ends of
    // lone paths.
    let mut terminal: Vec<u32> = (0..k).flat_map(corners).collect();
    for i in (0..k).filter(|&i| degree[i] == 0) {
        if let Some((path, v)) = part.path_to_boundary(costs, &corners(i)) {
            union.extend(path);
            terminal.push(v);
        }
    }
    union.sort_unstable();
    union.dedup();
    terminal.sort_unstable();
    terminal.dedup();
    forest_of(mesh, costs, &union, &terminal)
}

/// Whether face `f` (possibly `NONE`) is flagged in `region`.
fn in_region(region: &[bool], f: u32) -> bool {
    f != NONE && region[f as usize]
}

/// Per node (a singular face of `nodes`), the corner that represents it: its lowest
/// corner flagged in `ends` (one flag per mesh vertex, or empty), else its lowest, so
/// that the tree's paths meet at vertices and the tree is connected as an edge set.
fn node_representatives(mesh: &TriMesh, nodes: &[u32], ends: &[bool]) -> Vec<u32> {
    let flagged = |v: &u32| ends.get(*v as usize).copied().unwrap_or(false);
    nodes
        .iter()
        .map(|&f| {
            let c = mesh.triangles()[f as usize];
            let flagged = c.into_iter().filter(flagged).min();
            flagged.or(c.into_iter().min()).unwrap_or(0)
        })
        .collect()
}

/// The part of the mesh a region's singularity tree runs in, sized by the region: its
/// allowed edges are those of its faces, and their ends are its faces' corners
/// (`places`, ascending; vertex `v` is entry `at(v)`).
struct RegionPart<'a> {
    mesh: &'a TriMesh,
    /// The region's face flags.
    region: &'a [bool],
    /// The region's faces' corners and their places.
    places: MaskFaces,
    /// The region's faces' edges, ascending.
    edges: Vec<u32>,
    /// Per corner, whether it lies on the region's boundary (an edge whose two faces
    /// are not both in the region, including mesh boundary edges).
    on_boundary: Vec<bool>,
}

impl<'a> RegionPart<'a> {
    fn new(mesh: &'a TriMesh, region: &'a [bool]) -> Self {
        let faces: Vec<u32> = (0..mesh.face_count() as u32)
            .filter(|&f| region[f as usize])
            .collect();
        let corners = faces.iter().flat_map(|&f| mesh.triangles()[f as usize]);
        let places = MaskFaces::from_sorted(
            distinct_ascending(corners, 3 * faces.len(), mesh.vertex_count()),
            mesh.vertex_count(),
        );
        let edges = distinct_ascending(
            faces.iter().flat_map(|&f| mesh.face_edges()[f as usize]),
            3 * faces.len(),
            mesh.edge_count(),
        );
        let mut part = Self {
            mesh,
            region,
            places,
            edges,
            on_boundary: Vec::new(),
        };
        let mut on_boundary = vec![false; part.places.faces().len()];
        for &e in &part.edges {
            let [f0, f1] = mesh.edge_faces()[e as usize];
            let interior = mesh.edge_valence()[e as usize] == 2
                && in_region(region, f0)
                && in_region(region, f1);
            if !interior {
                for v in mesh.edges()[e as usize] {
                    on_boundary[part.at(v)] = true;
                }
            }
        }
        part.on_boundary = on_boundary;
        part
    }

    /// Corner `v`'s entry.
    fn at(&self, v: u32) -> usize {
        self.places.index(v).expect("a corner of a region face")
    }

    /// Whether paths may use mesh edge `e`: at least one of its faces is in the region.
    fn allowed(&self, e: u32) -> bool {
        let [f0, f1] = self.mesh.edge_faces()[e as usize];
        in_region(self.region, f0) || in_region(self.region, f1)
    }

    /// [`run_dijkstra`] over the region's allowed edges, stored by corner entry.
    fn dijkstra(
        &self,
        costs: &[f64],
        sources: &[u32],
        stop: &dyn Fn(u32) -> bool,
    ) -> (ShortestPaths, Option<u32>) {
        let at = |v: u32| self.at(v);
        let vertices = Vertices {
            count: self.places.faces().len(),
            index: &at,
        };
        let allowed = |e: u32| self.allowed(e);
        run_dijkstra(
            &VertexEdges::new(self.mesh),
            &vertices,
            costs,
            sources,
            &allowed,
            stop,
        )
    }

    /// Mehlhorn (1988): one multi-source Dijkstra from the nodes' representatives
    /// `reps` partitions the region into their Voronoi cells; the cheapest edge between
    /// two cells, d(u) + c(u, v) + d(v), links them. A minimum spanning tree of these
    /// links is a minimum spanning tree of the complete graph of pairwise shortest
    /// paths, and its expanded paths never cross. Returns the tree's path edges (with
    /// repeats) and each node's degree in it.
    fn voronoi_tree(&self, costs: &[f64], reps: &[u32]) -> (Vec<u32>, Vec<usize>) {
        let mesh = self.mesh;
        let k = reps.len();
        let at = |v: u32| self.at(v);
        let mut sources = reps.to_vec();
        sources.sort_unstable();
        sources.dedup();
        let (cells, _) = self.dijkstra(costs, &sources, &|_| false);
        let mut node_of_source = vec![NONE; self.places.faces().len()];
        for (i, &r) in reps.iter().enumerate().rev() {
            node_of_source[at(r)] = i as u32;
        }
        let cell = nearest_source_node(mesh, self.places.faces(), &at, &cells, &node_of_source);
        let mut sets = UnionFind::new(k);
        let mut degree = vec![0usize; k];
        for (i, &r) in reps.iter().enumerate() {
            let first = node_of_source[at(r)];
            if first != i as u32 && sets.union(first, i as u32) {
                degree[i] += 1;
                degree[first as usize] += 1;
            }
        }
        let mut links: Vec<(f64, u32, u32, u32)> = Vec::new();
        for &e in &self.edges {
            let [a, b] = mesh.edges()[e as usize];
            let (ia, ib) = (at(a), at(b));
            let (ca, cb) = (cell[ia], cell[ib]);
            if ca != NONE && cb != NONE && ca != cb {
                let w = cells.dist[ia] + costs[e as usize] + cells.dist[ib];
                links.push((w, ca.min(cb), ca.max(cb), e));
            }
        }
        links.sort_by(|x, y| {
            x.0.total_cmp(&y.0)
                .then((x.1, x.2, x.3).cmp(&(y.1, y.2, y.3)))
        });
        let mut union = Vec::new();
        for &(_, i, j, e) in &links {
            if sets.union(i, j) {
                degree[i as usize] += 1;
                degree[j as usize] += 1;
                let [a, b] = mesh.edges()[e as usize];
                union.push(e);
                union.extend(cells.path_edges_in(mesh, a, &at));
                union.extend(cells.path_edges_in(mesh, b, &at));
            }
        }
        (union, degree)
    }

    /// A lone node's shortest path from any of its face's `corners` to the region's
    /// boundary and the boundary vertex it ends at; `None` where no boundary is
    /// reachable.
    fn path_to_boundary(&self, costs: &[f64], corners: &[u32]) -> Option<(Vec<u32>, u32)> {
        let at = |v: u32| self.at(v);
        let stop = |v: u32| self.on_boundary[at(v)];
        let (tree, reached) = self.dijkstra(costs, corners, &stop);
        reached.map(|v| (tree.path_edges_in(self.mesh, v, &at), v))
    }
}

/// The distinct values of `ids` (about `expected` of them with repeats, each below
/// `count`), ascending. At least `count / DENSE_SHARE` ids are marked in a table of
/// `count` flags read in order; fewer are sorted, so a small region's cost stays in
/// proportion to it.
fn distinct_ascending(ids: impl Iterator<Item = u32>, expected: usize, count: usize) -> Vec<u32> {
    if expected * DENSE_SHARE >= count {
        let mut seen = vec![false; count];
        for id in ids {
            seen[id as usize] = true;
        }
        (0..count as u32).filter(|&i| seen[i as usize]).collect()
    } else {
        let mut v: Vec<u32> = ids.collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// Per vertex of `verts` (entry `at(v)`), the node whose source its shortest path
/// starts from (`NONE` where unreached), found by following `pred_edge` (memoised, so
/// O(|verts|) in all).
fn nearest_source_node(
    mesh: &TriMesh,
    verts: &[u32],
    at: &dyn Fn(u32) -> usize,
    tree: &ShortestPaths,
    node_of_source: &[u32],
) -> Vec<u32> {
    let mut cell = vec![NONE; verts.len()];
    let mut chain = Vec::new();
    for i in 0..verts.len() {
        if !tree.dist[i].is_finite() || cell[i] != NONE {
            continue;
        }
        let mut u = i;
        while cell[u] == NONE && tree.pred_edge[u] != NONE {
            chain.push(u);
            let [a, b] = mesh.edges()[tree.pred_edge[u] as usize];
            u = if at(a) == u { at(b) } else { at(a) };
        }
        let label = if cell[u] != NONE {
            cell[u]
        } else {
            node_of_source[u]
        };
        cell[u] = label;
        for w in chain.drain(..) {
            cell[w] = label;
        }
    }
    cell
}

/// Makes a union of paths a forest: a minimum spanning forest of it (Kruskal by cost,
/// then edge index; shortest paths from different sources can cross and close a
/// cycle, which would cut a piece off the region), then leaves that are not
/// `terminal` (sorted) pruned away. Ascending edge order.
fn forest_of(mesh: &TriMesh, costs: &[f64], edges: &[u32], terminal: &[u32]) -> Vec<u32> {
    let mut order = edges.to_vec();
    order.sort_by(|&x, &y| {
        costs[x as usize]
            .total_cmp(&costs[y as usize])
            .then(x.cmp(&y))
    });
    let mut verts: Vec<u32> = edges
        .iter()
        .flat_map(|&e| mesh.edges()[e as usize])
        .collect();
    verts.sort_unstable();
    verts.dedup();
    let local = |v: u32| verts.binary_search(&v).unwrap_or(0) as u32;
    let mut sets = UnionFind::new(verts.len());
    let mut kept: Vec<u32> = order
        .into_iter()
        .filter(|&e| {
            let [a, b] = mesh.edges()[e as usize];
            sets.union(local(a), local(b))
        })
        .collect();
    kept.sort_unstable();
    // Prune non-terminal leaves until none is left.
    let mut degree = vec![0u32; verts.len()];
    for &e in &kept {
        for v in mesh.edges()[e as usize] {
            degree[local(v) as usize] += 1;
        }
    }
    let mut alive = vec![true; kept.len()];
    loop {
        let mut changed = false;
        for (i, &e) in kept.iter().enumerate() {
            if !alive[i] {
                continue;
            }
            let [a, b] = mesh.edges()[e as usize];
            let leaf =
                |v: u32| degree[local(v) as usize] == 1 && terminal.binary_search(&v).is_err();
            if leaf(a) || leaf(b) {
                alive[i] = false;
                degree[local(a) as usize] -= 1;
                degree[local(b) as usize] -= 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    kept.into_iter()
        .zip(alive)
        .filter(|&(_, keep)| keep)
        .map(|(e, _)| e)
        .collect()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::field::FieldSpec;
    use crate::fixtures;
    use crate::io::shared_mesh;
    use crate::mesh::shapes;
    use crate::segment::singularity::detect_singularities;

    #[test]
    fn distinct_ascending_is_the_same_by_table_and_by_sort() {
        // Pseudo-random ids with repeats; `count` decides the strategy.
        let ids: Vec<u32> = (0..3000u32).map(|i| (i * 7919) % 1000).collect();
        let mut expected = ids.clone();
        expected.sort_unstable();
        expected.dedup();
        assert_eq!(expected.len(), 1000);
        // Dense: 3000 ids of 1000 possible values (a table).
        assert_eq!(
            distinct_ascending(ids.iter().copied(), 3000, 1000),
            expected
        );
        // Sparse: the same ids among 10^6 possible values (a sort).
        const { assert!(3000 * DENSE_SHARE < 1_000_000) };
        assert_eq!(
            distinct_ascending(ids.into_iter(), 3000, 1_000_000),
            expected
        );
    }

    /// Unit direction of edge `e` from its first to its second vertex.
    fn edge_direction(mesh: &TriMesh, e: u32) -> DVec3 {
        let [a, b] = mesh.edges()[e as usize];
        (mesh.positions()[b as usize] - mesh.positions()[a as usize]).normalize()
    }

    /// The constant 2:1 field along `direction` on `mesh`.
    fn constant(mesh: &TriMesh, direction: [f64; 3]) -> TensorField {
        fixtures::field_on(mesh, &fixtures::constant(direction, 2.0))
    }

    /// Checks that `edges` (in order) form a chain from `start`; returns its end.
    fn chain_end(mesh: &TriMesh, edges: &[u32], start: u32) -> u32 {
        let mut v = start;
        for &e in edges {
            let [a, b] = mesh.edges()[e as usize];
            assert!(
                a == v || b == v,
                "edge {e} does not continue the chain at {v}"
            );
            v = if a == v { b } else { a };
        }
        v
    }

    /// Whether an edge set is a tree (connected, acyclic); returns its vertices.
    fn tree_vertices(mesh: &TriMesh, edges: &[u32]) -> Vec<u32> {
        let mut verts: Vec<u32> = edges
            .iter()
            .flat_map(|&e| mesh.edges()[e as usize])
            .collect();
        verts.sort_unstable();
        verts.dedup();
        let mut sets = UnionFind::new(mesh.vertex_count());
        for &e in edges {
            let [a, b] = mesh.edges()[e as usize];
            assert!(sets.union(a, b), "cycle through edge {e}");
        }
        let roots: std::collections::BTreeSet<u32> = verts.iter().map(|&v| sets.find(v)).collect();
        assert!(roots.len() <= 1, "tree is disconnected");
        verts
    }

    #[test]
    fn costs_are_positive_and_lowest_along_the_field() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let costs = field_edge_costs(&mesh, &constant(&mesh, [1.0, 0.0, 0.0]));
        let h = 1.0 / 8.0;
        for (e, &c) in costs.iter().enumerate() {
            assert!(c > 0.0 && c.is_finite());
            let d = edge_direction(&mesh, e as u32);
            if d.x.abs() > 0.99 || d.y.abs() > 0.99 {
                assert!((c - h * COST_FLOOR).abs() < 1e-12, "axis edge {e}: {c}");
            } else {
                assert!(c > 10.0 * h * COST_FLOOR, "diagonal edge {e}: {c}");
            }
        }
        for (name, mesh) in [
            ("sphere", shapes::sphere(1.0, 5).expect("sphere")),
            ("genus2", shapes::genus2(1.0, 1).expect("genus2")),
        ] {
            let costs = field_edge_costs(&mesh, &constant(&mesh, [1.0, 0.3, 0.2]));
            assert!(costs.iter().all(|c| *c > 0.0 && c.is_finite()), "{name}");
        }
    }

    #[test]
    fn costs_and_walk_weights_do_not_depend_on_the_thread_count() {
        let (mesh, field) = crate::fixtures::torus_case();
        let frames = crate::segment::face_frames(&mesh, &field);
        let blocked: Vec<bool> = (0..mesh.edge_count()).map(|e| e % 11 == 0).collect();
        let run = || {
            let costs = field_edge_costs(&mesh, &field);
            let weights = crate::segment::walk_weights(&mesh, &frames, 1.0, &blocked);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
            (bits(&costs), bits(&weights))
        };
        assert_eq!(crate::on_threads(1, run), crate::on_threads(3, run));
    }

    #[test]
    fn paths_follow_the_field_lines() {
        let n = 8;
        let mesh = shapes::plane(1.0, n).expect("plane");
        let idx = |i: u32, j: u32| j * (n + 1) + i;
        // Along the grid's diagonals: the path is the diagonal chain.
        let costs = field_edge_costs(&mesh, &constant(&mesh, [1.0, 1.0, 0.0]));
        let tree = dijkstra(&mesh, &costs, &[idx(0, 0)], &|_| true);
        let path = tree.path_edges(&mesh, idx(n, n));
        assert_eq!(path.len(), n as usize);
        assert_eq!(chain_end(&mesh, &path, idx(0, 0)), idx(n, n));
        // Along x: from (0, 2) to (8, 6) only axis-aligned (major and minor) edges.
        let costs = field_edge_costs(&mesh, &constant(&mesh, [1.0, 0.0, 0.0]));
        let tree = dijkstra(&mesh, &costs, &[idx(0, 2)], &|_| true);
        let path = tree.path_edges(&mesh, idx(8, 6));
        assert_eq!(path.len(), 12);
        for &e in &path {
            let d = edge_direction(&mesh, e);
            assert!(d.x.abs() > 0.99 || d.y.abs() > 0.99);
        }
    }

    #[test]
    fn dijkstra_matches_bellman_ford_and_respects_allowed() {
        let mesh = shapes::torus(1.0, 0.4, 8).expect("torus");
        let costs = field_edge_costs(&mesh, &constant(&mesh, [1.0, 0.3, 0.2]));
        let allowed = |e: u32| e % 7 != 3;
        let sources = [5, 17];
        let tree = dijkstra(&mesh, &costs, &sources, &allowed);
        let mut reference = vec![f64::INFINITY; mesh.vertex_count()];
        for &s in &sources {
            reference[s as usize] = 0.0;
        }
        for _ in 0..mesh.vertex_count() {
            for (e, &[a, b]) in mesh.edges().iter().enumerate() {
                if !allowed(e as u32) {
                    continue;
                }
                let (a, b) = (a as usize, b as usize);
                let c = costs[e];
                reference[b] = reference[b].min(reference[a] + c);
                reference[a] = reference[a].min(reference[b] + c);
            }
        }
        for v in 0..mesh.vertex_count() as u32 {
            assert!((tree.dist[v as usize] - reference[v as usize]).abs() < 1e-9);
            let path = tree.path_edges(&mesh, v);
            assert!(path.iter().all(|&e| allowed(e)));
            let sum: f64 = path.iter().map(|&e| costs[e as usize]).sum();
            assert!((sum - tree.dist[v as usize]).abs() < 1e-9);
            let start = if path.is_empty() {
                v
            } else {
                let [a, b] = mesh.edges()[path[0] as usize];
                if sources.contains(&a) { a } else { b }
            };
            assert!(sources.contains(&start));
            assert_eq!(chain_end(&mesh, &path, start), v);
        }
        // Nothing allowed: only the sources are reached.
        let tree = dijkstra(&mesh, &costs, &[0], &|_| false);
        assert_eq!(tree.dist.iter().filter(|d| d.is_finite()).count(), 1);
        assert!(tree.path_edges(&mesh, 1).is_empty());
        assert_eq!(tree, dijkstra(&mesh, &costs, &[0], &|_| false));
    }

    /// A planar field with `+-1/2` singularities at the given points.
    fn planar_singular_field(mesh: &TriMesh, points: &[(f64, f64, f64)]) -> TensorField {
        let dirs: Vec<DVec3> = mesh
            .positions()
            .iter()
            .map(|p| {
                let t: f64 = points
                    .iter()
                    .map(|&(x, y, s)| 0.5 * s * (p.y - y).atan2(p.x - x))
                    .sum();
                DVec3::new(t.cos(), t.sin(), 0.0)
            })
            .collect();
        TensorField::from_frames(mesh, &dirs, &vec![[4.0, 1.0]; mesh.vertex_count()])
            .expect("valid field")
    }

    /// The `n` x `n` unit plane with [`planar_singular_field`] at `points`: the mesh,
    /// its singular faces (one per point) and the field's edge costs.
    fn plane_case(n: u32, points: &[(f64, f64, f64)]) -> (TriMesh, Vec<u32>, Vec<f64>) {
        let mesh = shapes::plane(1.0, n).expect("plane");
        let field = planar_singular_field(&mesh, points);
        let singular: Vec<u32> = detect_singularities(&mesh, &field)
            .iter()
            .map(|s| s.face)
            .collect();
        assert_eq!(singular.len(), points.len());
        let costs = field_edge_costs(&mesh, &field);
        (mesh, singular, costs)
    }

    #[test]
    fn tree_ends_at_the_flagged_corner_of_each_singular_face() {
        let (mesh, singular, costs) = plane_case(20, &[(0.23, 0.31, 1.0), (0.71, 0.62, -1.0)]);
        let region = vec![true; mesh.face_count()];
        let plain = singularity_tree(&mesh, &costs, &singular, &region);
        let reached = tree_vertices(&mesh, &plain);
        // Flag, on each singular face, a corner the plain tree does not reach (it ends
        // at the lowest corner), and vertices on no singular face (ignored).
        let mut ends = vec![false; mesh.vertex_count()];
        let mut wanted = Vec::new();
        for &f in &singular {
            let t = mesh.triangles()[f as usize];
            let v = *t
                .iter()
                .filter(|v| reached.binary_search(v).is_err())
                .max()
                .expect("a corner off the plain tree");
            ends[v as usize] = true;
            wanted.push(v);
        }
        ends[0] = true;
        ends[mesh.vertex_count() - 1] = true;
        let tree = singularity_tree_to(&mesh, &costs, &singular, &region, &ends);
        let verts = tree_vertices(&mesh, &tree);
        for v in wanted {
            assert!(verts.binary_search(&v).is_ok(), "flagged corner {v}");
        }
        // No flags: the plain tree.
        assert_eq!(
            singularity_tree_to(&mesh, &costs, &singular, &region, &[]),
            plain
        );
    }

    #[test]
    fn tree_joins_all_singularities_of_a_region() {
        let (mesh, singular, costs) = plane_case(
            20,
            &[(0.23, 0.31, 1.0), (0.71, 0.37, 1.0), (0.52, 0.74, -1.0)],
        );
        let region = vec![true; mesh.face_count()];
        let tree = singularity_tree(&mesh, &costs, &singular, &region);
        let verts = tree_vertices(&mesh, &tree);
        for &f in &singular {
            let t = mesh.triangles()[f as usize];
            assert!(t.iter().any(|v| verts.binary_search(v).is_ok()), "face {f}");
        }
        // Deterministic, and independent of the order the faces are given in.
        let reversed: Vec<u32> = singular.iter().rev().copied().collect();
        assert_eq!(tree, singularity_tree(&mesh, &costs, &reversed, &region));
    }

    #[test]
    fn lone_singularity_goes_to_the_region_boundary() {
        let n = 20;
        let mesh = shapes::plane(1.0, n).expect("plane");
        let field = planar_singular_field(&mesh, &[(0.23, 0.46, 1.0)]);
        let singular: Vec<u32> = detect_singularities(&mesh, &field)
            .iter()
            .map(|s| s.face)
            .collect();
        let costs = field_edge_costs(&mesh, &field);
        // Region: the left half (x < 0.5) of the plane.
        let region: Vec<bool> = (0..mesh.face_count() as u32)
            .map(|f| mesh.face_positions(f).iter().all(|p| p.x <= 0.5 + 1e-12))
            .collect();
        let path = singularity_tree(&mesh, &costs, &singular, &region);
        assert!(!path.is_empty());
        tree_vertices(&mesh, &path);
        let mut degree = std::collections::BTreeMap::<u32, u32>::new();
        for &e in &path {
            for v in mesh.edges()[e as usize] {
                *degree.entry(v).or_default() += 1;
            }
            let [f0, f1] = mesh.edge_faces()[e as usize];
            assert!(region[f0 as usize] || (f1 != NONE && region[f1 as usize]));
        }
        let ends: Vec<u32> = degree
            .iter()
            .filter(|&(_, d)| *d == 1)
            .map(|(v, _)| *v)
            .collect();
        assert_eq!(ends.len(), 2);
        let t = mesh.triangles()[singular[0] as usize];
        let on_face = |v: &u32| t.contains(v);
        let far = ends.iter().find(|v| !on_face(v)).expect("a far end");
        let p = mesh.positions()[*far as usize];
        assert!(
            (p.x - 0.5).abs() < 1e-12
                || p.x.abs() < 1e-12
                || p.y.abs() < 1e-12
                || p.y > 1.0 - 1e-12,
            "path ends inside the region at {p}"
        );
        assert!(ends.iter().any(on_face));
        // Outside the region the singularity is ignored.
        let other: Vec<bool> = region.iter().map(|r| !r).collect();
        assert!(singularity_tree(&mesh, &costs, &singular, &other).is_empty());
    }

    /// Cost of the brute-force minimum spanning tree over pairwise shortest paths
    /// between the nodes' representative vertices (the paper's construction).
    fn brute_force_mst_cost(mesh: &TriMesh, costs: &[f64], faces: &[u32], region: &[bool]) -> f64 {
        let allowed = |e: u32| {
            let [f0, f1] = mesh.edge_faces()[e as usize];
            region[f0 as usize] || (f1 != NONE && region[f1 as usize])
        };
        let reps: Vec<u32> = faces
            .iter()
            .map(|&f| {
                *mesh.triangles()[f as usize]
                    .iter()
                    .min()
                    .expect("3 corners")
            })
            .collect();
        let mut pairs = Vec::new();
        for i in 0..reps.len() {
            let tree = dijkstra(mesh, costs, &[reps[i]], &allowed);
            for (j, r) in reps.iter().enumerate().skip(i + 1) {
                pairs.push((tree.dist[*r as usize], i as u32, j as u32));
            }
        }
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut sets = UnionFind::new(reps.len());
        pairs
            .iter()
            .filter(|p| p.0.is_finite() && sets.union(p.1, p.2))
            .map(|p| p.0)
            .sum()
    }

    #[test]
    fn tree_is_as_cheap_as_the_paper_s_pairwise_mst() {
        let (mesh, singular, costs) = plane_case(
            24,
            &[
                (0.13, 0.21, 1.0),
                (0.81, 0.27, 1.0),
                (0.52, 0.84, -1.0),
                (0.33, 0.62, -1.0),
                (0.68, 0.53, 1.0),
            ],
        );
        let region = vec![true; mesh.face_count()];
        let tree = singularity_tree(&mesh, &costs, &singular, &region);
        let cost: f64 = tree.iter().map(|&e| costs[e as usize]).sum();
        let mst = brute_force_mst_cost(&mesh, &costs, &singular, &region);
        println!("tree cost {cost}, pairwise MST {mst}");
        // Shared stretches can only make the union cheaper than the MST's sum.
        assert!(cost <= mst + 1e-9 && cost >= 0.5 * mst, "{cost} vs {mst}");
    }

    #[test]
    fn lone_singularity_on_a_closed_region_gives_nothing() {
        let mesh = shapes::sphere(1.0, 4).expect("sphere");
        let field = constant(&mesh, [1.0, 0.3, 0.2]);
        let costs = field_edge_costs(&mesh, &field);
        let region = vec![true; mesh.face_count()];
        assert!(singularity_tree(&mesh, &costs, &[7], &region).is_empty());
        let two = singularity_tree(&mesh, &costs, &[7, 300], &region);
        assert!(!two.is_empty());
        tree_vertices(&mesh, &two);
    }

    #[test]
    fn trees_on_shared_meshes() {
        let Some(mesh) = shared_mesh("spot.obj") else {
            return;
        };
        let field = FieldSpec::default_curvature()
            .build(&mesh)
            .expect("curvature field");
        let singular: Vec<u32> = detect_singularities(&mesh, &field)
            .iter()
            .map(|s| s.face)
            .collect();
        let costs = field_edge_costs(&mesh, &field);
        let region = vec![true; mesh.face_count()];
        let start = std::time::Instant::now();
        let tree = singularity_tree(&mesh, &costs, &singular, &region);
        println!(
            "spot curvature field: {} singularities, tree of {} edges in {:.1} ms",
            singular.len(),
            tree.len(),
            start.elapsed().as_secs_f64() * 1e3
        );
        let verts = tree_vertices(&mesh, &tree);
        for &f in &singular {
            let t = mesh.triangles()[f as usize];
            assert!(t.iter().any(|v| verts.binary_search(v).is_ok()), "face {f}");
        }
        let cost: f64 = tree.iter().map(|&e| costs[e as usize]).sum();
        let mst = brute_force_mst_cost(&mesh, &costs, &singular, &region);
        println!("spot: tree cost {cost}, pairwise MST {mst}");
        assert!(cost <= mst + 1e-9 && cost >= 0.5 * mst, "{cost} vs {mst}");
    }
}
