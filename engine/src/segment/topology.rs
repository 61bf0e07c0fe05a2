//! Topology of a patch of faces cut open along edges, and the cuts that make it a disc
//! (paper section 4.2).
//!
//! Input: a [`TriMesh`], a patch (a list of its faces) and a cut mask over mesh edges;
//! for [`disc_cuts`] also per-edge costs (see [`field_edge_costs`]). Output: the cut-open
//! patch's vertex, edge and face counts, Euler characteristic and boundary loops
//! ([`PatchTopology`]); or the extra edges to cut so that it becomes a topological disc.
//! Cost: O(F_p log F_p) for a patch of `F_p` faces, plus one O(F) mask of the mesh's
//! faces per call.
//!
//! # Cutting open
//! Two faces of the patch are *joined* across an edge when the edge is manifold (two
//! faces), both are in the patch and the edge is not cut. Everything else is a
//! boundary side: mesh boundary, the edge of a face whose neighbour is outside the
//! patch, either side of a seam (a cut edge inside the patch), every side of a
//! non-manifold edge (which is thus split into manifold sheets). A mesh vertex splits
//! into as many vertices as there are fans of its patch corners linked through joined
//! edges (union-find over corners).
//!
//! # Disc cuts
//! The paper cuts a segment along field-following shortest paths between its boundary
//! loops, joined by a minimum spanning tree, and needs more for closed patches and
//! handles. Both are the tree-cotree construction (Eppstein 2003, "Dynamic generators
//! of topologically embedded graphs"), as a greedy system of loops (Erickson and
//! Whittlesey 2005):
//! 1. a shortest-path tree `T` over the cut-open patch's vertices with the field costs,
//!    grown from all boundary vertices at once (the boundary is pinched into one root:
//!    the paper's "edge distances along boundaries set to 0"), or from one root vertex
//!    on a closed patch;
//! 2. a *maximum* spanning tree `C` of the faces across the joined edges not in `T`,
//!    weighted by the length of each edge's loop `d(u) + c(u, v) + d(v)`;
//! 3. the leftover edges `L` (neither in `T` nor crossed by `C`; there are
//!    `1 - chi = 2 g + b - 1` of them) each close the shortest loop through the root:
//!    for a patch of genus 0 they are exactly the minimum spanning tree of shortest
//!    paths between boundary loops, for handles the greedy shortest non-separating
//!    loops;
//! 4. the patch cut along `T` and `L` is a disc (its faces stay glued along the tree
//!    `C` only); pruning dangling branches of `T` (never the boundary) keeps it one.
//!    A closed sphere-like patch prunes to nothing and is slit along its cheapest
//!    edge at the root instead (a sphere cut along one edge is a disc).
//!
//! [`field_edge_costs`]: super::paths::field_edge_costs

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use rayon::slice::ParallelSliceMut;

use super::paths::UnionFind;
use crate::mesh::face_set::MaskFaces;
use crate::mesh::{NONE, TriMesh};

/// `component_root` of vertices reached from the (pinched) boundary.
const BOUNDARY_ROOT: u32 = NONE - 1;

/// Topology of a patch of faces after cutting it open along edges.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PatchTopology {
    /// Vertices of the cut-open patch (a mesh vertex split by cuts counts once per
    /// piece).
    pub vertex_count: usize,
    /// Edges of the cut-open patch (a seam counts twice).
    pub edge_count: usize,
    /// Faces of the patch.
    pub face_count: usize,
    /// `vertex_count - edge_count + face_count`: 1 for a disc, 0 for an annulus, 2 for
    /// a sphere, `2 - 2 genus - loops` in general (per connected component, summed).
    pub euler_characteristic: i64,
    /// Boundary loops as mesh vertex sequences, each following its faces' orientation
    /// where the patch is consistently oriented (a vertex on a seam appears once per
    /// side). Deterministic order: by the first boundary side, in patch face order.
    pub boundary_loops: Vec<Vec<u32>>,
}

/// A patch cut open: local faces, joins between them, corner classes.
struct CutPatch {
    /// Patch faces (mesh ids), ascending, distinct.
    faces: Vec<u32>,
    /// Per local face and side, the local face joined across it, or `NONE`.
    across: Vec<[u32; 3]>,
    /// Per local corner `3 f + k`, its vertex of the cut-open patch.
    class: Vec<u32>,
    /// Number of vertices of the cut-open patch.
    class_count: usize,
}

impl CutPatch {
    fn new(mesh: &TriMesh, faces: &[u32], cut: &[bool]) -> Self {
        assert_eq!(cut.len(), mesh.edge_count(), "one cut flag per mesh edge");
        let mut faces = faces.to_vec();
        faces.sort_unstable();
        faces.dedup();
        // Places by search or table, not a per-mesh-face array: a small patch of a
        // large mesh costs in proportion to the patch (splitting tests every piece).
        let places = MaskFaces::from_sorted(faces, mesh.face_count());
        let local = |g: u32| places.index(g).map_or(NONE, |i| i as u32);
        let across: Vec<[u32; 3]> = places
            .faces()
            .iter()
            .map(|&f| {
                mesh.face_edges()[f as usize].map(|e| {
                    let e = e as usize;
                    if mesh.edge_valence()[e] != 2 || cut[e] {
                        return NONE;
                    }
                    let [f0, f1] = mesh.edge_faces()[e];
                    let g = if f0 == f { f1 } else { f0 };
                    if g == f { NONE } else { local(g) }
                })
            })
            .collect();
        let faces = places.into_faces();
        let mut corners = UnionFind::new(3 * faces.len());
        for (lf, sides) in across.iter().enumerate() {
            let t = mesh.triangles()[faces[lf] as usize];
            for (k, &lg) in sides.iter().enumerate() {
                if lg == NONE || (lg as usize) < lf {
                    continue;
                }
                let tg = mesh.triangles()[faces[lg as usize] as usize];
                for kk in [k, (k + 1) % 3] {
                    if let Some(m) = tg.iter().position(|&v| v == t[kk]) {
                        corners.union((3 * lf + kk) as u32, 3 * lg + m as u32);
                    }
                }
            }
        }
        let mut class = vec![NONE; 3 * faces.len()];
        let mut class_count = 0;
        for c in 0..class.len() {
            let root = corners.find(c as u32) as usize;
            if class[root] == NONE {
                class[root] = class_count;
                class_count += 1;
            }
            class[c] = class[root];
        }
        Self {
            faces,
            across,
            class,
            class_count: class_count as usize,
        }
    }

    /// Boundary sides `(local face, side)`, in order.
    fn boundary_sides(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.across
            .iter()
            .enumerate()
            .flat_map(|(lf, s)| (0..3).filter(move |&k| s[k] == NONE).map(move |k| (lf, k)))
    }

    /// The two vertex classes of side `k` of local face `lf` (tail, head).
    fn side_classes(&self, lf: usize, k: usize) -> (u32, u32) {
        (self.class[3 * lf + k], self.class[3 * lf + (k + 1) % 3])
    }
}

/// Topology of the patch made of `faces` (mesh face ids; duplicates ignored), cut open
/// along the edges flagged in `cut` (one flag per mesh edge). See the [module
/// docs](self) for what "cut open" means. O(F_p log F_p + F).
///
/// ```
/// use strata_engine::{mesh::shapes, segment::patch_topology};
/// let mesh = shapes::torus(1.0, 0.4, 12)?;
/// let all: Vec<u32> = (0..mesh.face_count() as u32).collect();
/// let top = patch_topology(&mesh, &all, &vec![false; mesh.edge_count()]);
/// assert_eq!((top.euler_characteristic, top.boundary_loops.len()), (0, 0));
/// # Ok::<(), strata_engine::mesh::MeshError>(())
/// ```
pub fn patch_topology(mesh: &TriMesh, faces: &[u32], cut: &[bool]) -> PatchTopology {
    let patch = CutPatch::new(mesh, faces, cut);
    let face_count = patch.faces.len();
    let sides = 3 * face_count;
    let joined = patch
        .across
        .iter()
        .flatten()
        .filter(|&&g| g != NONE)
        .count()
        / 2;
    let edge_count = sides - joined;

    // Boundary loops: walk boundary sides head to tail through the vertex classes.
    let boundary: Vec<(usize, usize)> = patch.boundary_sides().collect();
    let mut touching: Vec<Vec<u32>> = vec![Vec::new(); patch.class_count];
    for (i, &(lf, k)) in boundary.iter().enumerate() {
        let (a, b) = patch.side_classes(lf, k);
        touching[a as usize].push(i as u32);
        if b != a {
            touching[b as usize].push(i as u32);
        }
    }
    let mut used = vec![false; boundary.len()];
    let mut boundary_loops = Vec::new();
    for start in 0..boundary.len() {
        if used[start] {
            continue;
        }
        let mut lp = Vec::new();
        let (lf, k) = boundary[start];
        let (mut side, mut from) = (start, patch.side_classes(lf, k).0);
        loop {
            used[side] = true;
            let (lf, k) = boundary[side];
            let (a, b) = patch.side_classes(lf, k);
            let t = mesh.triangles()[patch.faces[lf] as usize];
            let (from_vertex, to) = if from == a {
                (t[k], b)
            } else {
                (t[(k + 1) % 3], a)
            };
            lp.push(from_vertex);
            let unused = || {
                touching[to as usize]
                    .iter()
                    .map(|&s| s as usize)
                    .filter(|&s| !used[s])
            };
            // Prefer the side leaving `to` in its face's direction; on inconsistently
            // oriented patches take any unused side so that loops stay closed.
            let next = unused()
                .find(|&s| patch.side_classes(boundary[s].0, boundary[s].1).0 == to)
                .or_else(|| unused().next());
            match next {
                Some(s) => {
                    side = s;
                    from = to;
                }
                None => break,
            }
        }
        boundary_loops.push(lp);
    }

    PatchTopology {
        vertex_count: patch.class_count,
        edge_count,
        face_count,
        euler_characteristic: patch.class_count as i64 - edge_count as i64 + face_count as i64,
        boundary_loops,
    }
}

impl PatchTopology {
    /// Whether the cut-open patch is a topological disc: Euler characteristic 1 and
    /// one boundary loop (what a parameterization needs).
    pub fn is_disc(&self) -> bool {
        self.euler_characteristic == 1 && self.boundary_loops.len() == 1
    }
}

/// Whether `faces`, cut open along `cut`, form a topological disc (see
/// [`PatchTopology::is_disc`]). O(F_p log F_p + F).
pub fn is_disc(mesh: &TriMesh, faces: &[u32], cut: &[bool]) -> bool {
    patch_topology(mesh, faces, cut).is_disc()
}

/// An edge of the cut-open patch joining two local faces.
struct Joined {
    /// Mesh edge.
    edge: u32,
    /// Its two vertex classes.
    ends: [u32; 2],
    /// Its two local faces.
    faces: [u32; 2],
}

/// The cut-open patch's vertices (classes) and the joined edges between them.
struct JoinedGraph {
    /// Joined edges, in local face and side order.
    joined: Vec<Joined>,
    /// Per class, the start of its list in `adjacent` (CSR offsets, `n + 1` long).
    offsets: Vec<usize>,
    /// Per class, `(neighbour class, joined edge)`, sorted by both.
    adjacent: Vec<(u32, u32)>,
}

impl JoinedGraph {
    fn new(mesh: &TriMesh, patch: &CutPatch) -> Self {
        let n = patch.class_count;
        let mut joined: Vec<Joined> = Vec::new();
        for (lf, sides) in patch.across.iter().enumerate() {
            for (k, &lg) in sides.iter().enumerate() {
                if lg != NONE && (lg as usize) > lf {
                    let (a, b) = patch.side_classes(lf, k);
                    joined.push(Joined {
                        edge: mesh.face_edges()[patch.faces[lf] as usize][k],
                        ends: [a, b],
                        faces: [lf as u32, lg],
                    });
                }
            }
        }
        // Class adjacency (CSR) over joined edges, each list sorted by (neighbour, edge).
        let mut offsets = vec![0usize; n + 1];
        for j in &joined {
            offsets[j.ends[0] as usize + 1] += 1;
            offsets[j.ends[1] as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut adjacent = vec![(0u32, 0u32); 2 * joined.len()];
        for (ji, j) in joined.iter().enumerate() {
            for s in 0..2 {
                let v = j.ends[s] as usize;
                adjacent[fill[v]] = (j.ends[1 - s], ji as u32);
                fill[v] += 1;
            }
        }
        for v in 0..n {
            adjacent[offsets[v]..offsets[v + 1]].sort_unstable();
        }
        Self {
            joined,
            offsets,
            adjacent,
        }
    }

    /// Number of classes (vertices of the cut-open patch).
    fn class_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// `(neighbour class, joined edge)` of class `v`, sorted.
    fn neighbours(&self, v: usize) -> &[(u32, u32)] {
        &self.adjacent[self.offsets[v]..self.offsets[v + 1]]
    }

    /// The cost of joined edge `ji`'s mesh edge.
    fn cost(&self, costs: &[f64], ji: usize) -> f64 {
        costs[self.joined[ji].edge as usize]
    }
}

/// Step 1's shortest-path forest `T` over the classes.
struct PathForest {
    /// Distance from the boundary (or the component's root on a closed component).
    dist: Vec<f64>,
    /// Per class, the joined edge to its parent, or `NONE` at a root.
    pred: Vec<u32>,
    /// Per class, its closed component's root class, or [`BOUNDARY_ROOT`].
    component_root: Vec<u32>,
    /// The root class of each closed component, in order.
    closed_roots: Vec<u32>,
}

impl PathForest {
    /// Dijkstra from all `protected` (boundary) classes at once, then from the first
    /// unreached class of each closed component; ties go to the lower joined edge.
    fn grow(graph: &JoinedGraph, costs: &[f64], protected: &[bool]) -> Self {
        let n = graph.class_count();
        let mut dist = vec![f64::INFINITY; n];
        let mut pred = vec![NONE; n];
        let mut settled = vec![false; n];
        let mut component_root = vec![NONE; n];
        let mut closed_roots = Vec::new();
        let mut heap = BinaryHeap::new();
        for v in 0..n {
            if protected[v] {
                dist[v] = 0.0;
                component_root[v] = BOUNDARY_ROOT;
                heap.push(Reverse((0u64, v as u32)));
            }
        }
        let mut next_unreached = 0;
        loop {
            while let Some(Reverse((bits, v))) = heap.pop() {
                let v = v as usize;
                if settled[v] || bits != dist[v].to_bits() {
                    continue;
                }
                settled[v] = true;
                for &(w, ji) in graph.neighbours(v) {
                    let w = w as usize;
                    if settled[w] {
                        continue;
                    }
                    let nd = dist[v] + graph.cost(costs, ji as usize);
                    let old = dist[w];
                    if nd < old || (nd == old && pred[w] != NONE && ji < pred[w]) {
                        dist[w] = nd;
                        pred[w] = ji;
                        component_root[w] = component_root[v];
                        if nd < old {
                            heap.push(Reverse((nd.to_bits(), w as u32)));
                        }
                    }
                }
            }
            while next_unreached < n && dist[next_unreached].is_finite() {
                next_unreached += 1;
            }
            if next_unreached == n {
                break;
            }
            let r = next_unreached;
            dist[r] = 0.0;
            component_root[r] = r as u32;
            closed_roots.push(r as u32);
            heap.push(Reverse((0u64, r as u32)));
        }
        Self {
            dist,
            pred,
            component_root,
            closed_roots,
        }
    }

    /// Per joined edge, whether it is in the forest.
    fn tree_edges(&self, joined_count: usize) -> Vec<bool> {
        let mut in_tree = vec![false; joined_count];
        for &p in &self.pred {
            if p != NONE {
                in_tree[p as usize] = true;
            }
        }
        in_tree
    }

    /// Length of the loop that joined edge `ji` closes through the root:
    /// `d(u) + c(u, v) + d(v)`.
    fn loop_length(&self, graph: &JoinedGraph, costs: &[f64], ji: usize) -> f64 {
        let j = &graph.joined[ji];
        self.dist[j.ends[0] as usize] + costs[j.edge as usize] + self.dist[j.ends[1] as usize]
    }
}

/// `x`'s bits mapped so that unsigned order is [`f64::total_cmp`]'s order.
fn total_order_bits(x: f64) -> u64 {
    let bits = x.to_bits();
    if bits >> 63 == 1 {
        !bits
    } else {
        bits | 1 << 63
    }
}

/// Steps 2 and 3: the maximum spanning forest `C` of the `face_count` local faces
/// across the joined edges outside `in_tree`, by loop length; returns `in_tree` with
/// the leftover edges `L` (which close the loops) added.
fn add_leftover_loops(
    graph: &JoinedGraph,
    costs: &[f64],
    forest: &PathForest,
    face_count: usize,
    in_tree: Vec<bool>,
) -> Vec<bool> {
    let joined = &graph.joined;
    // Longest loops first, ties by mesh edge (unique per joined edge, so the order is
    // total and a parallel sort gives the sequential one). Keys computed once: sorting
    // with the lengths computed in the comparison took 0.19 s of 0.48 on a segment of
    // 693k faces.
    let mut cotree: Vec<(u64, u32, u32)> = (0..joined.len())
        .filter(|&ji| !in_tree[ji])
        .map(|ji| {
            (
                !total_order_bits(forest.loop_length(graph, costs, ji)),
                joined[ji].edge,
                ji as u32,
            )
        })
        .collect();
    cotree.par_sort_unstable();
    let mut dual = UnionFind::new(face_count);
    let mut in_cut = in_tree;
    for (_, _, ji) in cotree {
        let ji = ji as usize;
        let [f, g] = joined[ji].faces;
        if !dual.union(f, g) {
            in_cut[ji] = true;
        }
    }
    in_cut
}

/// Step 4: unflags the dangling branches of the cut graph `in_cut`, leaf by leaf,
/// never at a `protected` (boundary) class.
fn prune_dangling(graph: &JoinedGraph, protected: &[bool], in_cut: &mut [bool]) {
    let n = graph.class_count();
    let mut degree = vec![0u32; n];
    for (ji, j) in graph.joined.iter().enumerate() {
        if in_cut[ji] {
            degree[j.ends[0] as usize] += 1;
            degree[j.ends[1] as usize] += 1;
        }
    }
    let mut leaves: Vec<u32> = (0..n as u32)
        .filter(|&v| degree[v as usize] == 1 && !protected[v as usize])
        .collect();
    while let Some(v) = leaves.pop() {
        let v = v as usize;
        if degree[v] != 1 {
            continue;
        }
        let Some(&(w, ji)) = graph
            .neighbours(v)
            .iter()
            .find(|&&(_, ji)| in_cut[ji as usize])
        else {
            continue;
        };
        in_cut[ji as usize] = false;
        degree[v] -= 1;
        degree[w as usize] -= 1;
        if degree[w as usize] == 1 && !protected[w as usize] {
            leaves.push(w);
        }
    }
}

/// Flags the cheapest edge at the root of each closed component that pruned to
/// nothing (genus 0): a sphere slit along one edge is a disc.
fn slit_closed_spheres(
    graph: &JoinedGraph,
    costs: &[f64],
    forest: &PathForest,
    in_cut: &mut [bool],
) {
    let joined = &graph.joined;
    let mut has_cut = vec![false; graph.class_count()];
    for (ji, j) in joined.iter().enumerate() {
        if in_cut[ji] {
            let r = forest.component_root[j.ends[0] as usize];
            if r != BOUNDARY_ROOT {
                has_cut[r as usize] = true;
            }
        }
    }
    for &r in &forest.closed_roots {
        let r = r as usize;
        if has_cut[r] {
            continue;
        }
        let cheapest = graph
            .neighbours(r)
            .iter()
            .map(|&(_, ji)| ji as usize)
            .min_by(|&x, &y| {
                graph
                    .cost(costs, x)
                    .total_cmp(&graph.cost(costs, y))
                    .then(joined[x].edge.cmp(&joined[y].edge))
            });
        if let Some(ji) = cheapest {
            in_cut[ji] = true;
        }
    }
}

/// The mesh edges (ascending, none already in `cut`) to cut in addition to `cut` so
/// that every connected component of the patch made of `faces` becomes a topological
/// disc (Euler characteristic 1, one boundary loop; check with [`patch_topology`]).
///
/// The cuts are field-following shortest paths (with `costs`, one finite non-negative
/// value per mesh edge, e.g.
/// from [`field_edge_costs`](super::paths::field_edge_costs)) between the patch's
/// boundary loops, joined as a minimum spanning tree, plus for handles the shortest
/// non-separating loops (tree-cotree, see the [module docs](self)). Every returned
/// edge has both faces in the patch; the returned edges together with the patch's
/// boundary form a connected graph per component, without dangling branches. Empty for
/// a disc. O(F_p log F_p + F).
///
/// ```
/// use strata_engine::{field::FieldSpec, mesh::shapes, segment::{disc_cuts, field_edge_costs, patch_topology}};
/// let mesh = shapes::torus(1.0, 0.4, 12)?;
/// let spec = FieldSpec::Constant { direction: [0.0, 0.0, 1.0], anisotropy: 2.0, density: 1.0 };
/// let costs = field_edge_costs(&mesh, &spec.build(&mesh)?);
/// let all: Vec<u32> = (0..mesh.face_count() as u32).collect();
/// let mut cut = vec![false; mesh.edge_count()];
/// for e in disc_cuts(&mesh, &costs, &all, &cut) {
///     cut[e as usize] = true;
/// }
/// let top = patch_topology(&mesh, &all, &cut);
/// assert_eq!((top.euler_characteristic, top.boundary_loops.len()), (1, 1));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn disc_cuts(mesh: &TriMesh, costs: &[f64], faces: &[u32], cut: &[bool]) -> Vec<u32> {
    assert_eq!(costs.len(), mesh.edge_count(), "one cost per mesh edge");
    let patch = CutPatch::new(mesh, faces, cut);
    let graph = JoinedGraph::new(mesh, &patch);

    // 1. Shortest-path forest from the boundary, then from one root per closed
    // component.
    let mut protected = vec![false; patch.class_count];
    for (lf, k) in patch.boundary_sides() {
        let (a, b) = patch.side_classes(lf, k);
        protected[a as usize] = true;
        protected[b as usize] = true;
    }
    let forest = PathForest::grow(&graph, costs, &protected);
    let in_tree = forest.tree_edges(graph.joined.len());

    // 2. Maximum spanning forest of the faces across the other joined edges, by loop
    // length; 3. what it leaves over closes the loops.
    let mut in_cut = add_leftover_loops(&graph, costs, &forest, patch.faces.len(), in_tree);
    // 4. Prune dangling branches (never at the boundary); a closed component that
    // pruned to nothing (genus 0) is slit along one edge.
    prune_dangling(&graph, &protected, &mut in_cut);
    slit_closed_spheres(&graph, costs, &forest, &mut in_cut);

    let mut out: Vec<u32> = graph
        .joined
        .iter()
        .zip(&in_cut)
        .filter(|&(_, &c)| c)
        .map(|(j, _)| j.edge)
        .collect();
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use crate::fixtures::{field_on, oblique};
    use std::collections::BTreeSet;
    use std::time::Instant;

    use super::*;
    use crate::io::shared_mesh;
    use crate::mesh::shapes;
    use crate::segment::paths::field_edge_costs;

    fn all_faces(mesh: &TriMesh) -> Vec<u32> {
        (0..mesh.face_count() as u32).collect()
    }

    fn no_cut(mesh: &TriMesh) -> Vec<bool> {
        vec![false; mesh.edge_count()]
    }

    #[test]
    fn the_disc_test_tells_a_disc_from_an_annulus_and_a_closed_surface() {
        let plane = shapes::plane(1.0, 6).expect("plane");
        assert!(is_disc(&plane, &all_faces(&plane), &no_cut(&plane)));
        // The plane without its middle faces: an annulus (Euler characteristic 0).
        let ring: Vec<u32> = all_faces(&plane)
            .into_iter()
            .filter(|&f| {
                let c = plane.face_positions(f).iter().sum::<glam::DVec3>() / 3.0;
                (c.x - 0.5).abs() > 0.2 || (c.y - 0.5).abs() > 0.2
            })
            .collect();
        assert!(ring.len() < plane.face_count());
        let top = patch_topology(&plane, &ring, &no_cut(&plane));
        assert_eq!((top.euler_characteristic, top.boundary_loops.len()), (0, 2));
        assert!(!top.is_disc());
        assert!(!is_disc(&plane, &ring, &no_cut(&plane)));
        // Closed surfaces are not discs; a sphere slit along one edge is.
        let sphere = shapes::sphere(1.0, 4).expect("sphere");
        assert!(!is_disc(&sphere, &all_faces(&sphere), &no_cut(&sphere)));
        let mut slit = no_cut(&sphere);
        slit[0] = true;
        assert!(is_disc(&sphere, &all_faces(&sphere), &slit));
        let torus = shapes::torus(1.0, 0.4, 8).expect("torus");
        assert!(!is_disc(&torus, &all_faces(&torus), &no_cut(&torus)));
    }

    fn costs(mesh: &TriMesh) -> Vec<f64> {
        let field = field_on(mesh, &oblique(2.0));
        field_edge_costs(mesh, &field)
    }

    /// The edge joining vertices `a` and `b`.
    fn edge_between(mesh: &TriMesh, a: u32, b: u32) -> usize {
        let key = [a.min(b), a.max(b)];
        mesh.edges()
            .iter()
            .position(|e| *e == key)
            .expect("edge exists")
    }

    fn plane_slit(n: u32, row: u32, from: u32, to: u32) -> (TriMesh, Vec<bool>) {
        let mesh = shapes::plane(1.0, n).expect("plane");
        let idx = |i: u32, j: u32| j * (n + 1) + i;
        let mut cut = no_cut(&mesh);
        for i in from..to {
            cut[edge_between(&mesh, idx(i, row), idx(i + 1, row))] = true;
        }
        (mesh, cut)
    }

    fn summary(t: &PatchTopology) -> (i64, usize) {
        (t.euler_characteristic, t.boundary_loops.len())
    }

    #[test]
    fn topology_of_shapes() {
        let cases = [
            ("plane", shapes::plane(1.0, 6).expect("plane"), (1, 1)),
            (
                "cylinder",
                shapes::cylinder(1.0, 2.0, 12).expect("cylinder"),
                (0, 2),
            ),
            ("sphere", shapes::sphere(1.0, 3).expect("sphere"), (2, 0)),
            ("torus", shapes::torus(1.0, 0.4, 10).expect("torus"), (0, 0)),
            ("genus2", shapes::genus2(1.0, 1).expect("genus2"), (-2, 0)),
        ];
        for (name, mesh, expected) in &cases {
            let t = patch_topology(mesh, &all_faces(mesh), &no_cut(mesh));
            assert_eq!(summary(&t), *expected, "{name}");
            assert_eq!(
                (t.vertex_count, t.edge_count, t.face_count),
                (mesh.vertex_count(), mesh.edge_count(), mesh.face_count()),
                "{name}"
            );
            // The same loops as the mesh's own, up to rotation.
            let canonical = |loops: &[Vec<u32>]| -> BTreeSet<Vec<u32>> {
                loops
                    .iter()
                    .map(|l| {
                        let m = (0..l.len()).min_by_key(|&i| l[i]).unwrap_or(0);
                        l[m..].iter().chain(&l[..m]).copied().collect()
                    })
                    .collect()
            };
            assert_eq!(
                canonical(&t.boundary_loops),
                canonical(mesh.boundary_loops())
            );
        }
    }

    #[test]
    fn slits_split_vertices() {
        let n = 8;
        // From the boundary inwards: still a disc, the loop runs in and out of the slit.
        let (mesh, cut) = plane_slit(n, 4, 0, 4);
        let t = patch_topology(&mesh, &all_faces(&mesh), &cut);
        assert_eq!(summary(&t), (1, 1));
        assert_eq!(t.vertex_count, mesh.vertex_count() + 4);
        assert_eq!(t.edge_count, mesh.edge_count() + 4);
        assert_eq!(t.boundary_loops[0].len(), 4 * n as usize + 8);
        // Inside: an annulus.
        let (mesh, cut) = plane_slit(n, 4, 2, 6);
        let t = patch_topology(&mesh, &all_faces(&mesh), &cut);
        assert_eq!(summary(&t), (0, 2));
        // Right across: two discs.
        let (mesh, cut) = plane_slit(n, 4, 0, n);
        let t = patch_topology(&mesh, &all_faces(&mesh), &cut);
        assert_eq!(summary(&t), (2, 2));
    }

    #[test]
    fn sub_patches_and_outer_cuts() {
        let mesh = shapes::plane(1.0, 8).expect("plane");
        let left: Vec<u32> = (0..mesh.face_count() as u32)
            .filter(|&f| mesh.face_positions(f).iter().all(|p| p.x <= 0.5))
            .collect();
        let mut cut = no_cut(&mesh);
        let t = patch_topology(&mesh, &left, &cut);
        assert_eq!(summary(&t), (1, 1));
        // Cutting edges on the patch's rim changes nothing.
        for (e, [f0, f1]) in mesh.edge_faces().iter().enumerate() {
            let inside = |f: u32| left.contains(&f);
            if inside(*f0) != (*f1 != NONE && inside(*f1)) {
                cut[e] = true;
            }
        }
        assert_eq!(patch_topology(&mesh, &left, &cut), t);
        // Duplicates are ignored; the empty patch is empty.
        let twice: Vec<u32> = left.iter().chain(&left).copied().collect();
        assert_eq!(patch_topology(&mesh, &twice, &no_cut(&mesh)), t);
        let empty = patch_topology(&mesh, &[], &no_cut(&mesh));
        assert_eq!((empty.vertex_count, empty.euler_characteristic), (0, 0));
    }

    /// Applies `disc_cuts` and checks the result is a disc with well-formed cuts.
    fn check_disc_cuts(name: &str, mesh: &TriMesh, faces: &[u32], cut: &[bool]) -> usize {
        let c = costs(mesh);
        let start = Instant::now();
        let extra = disc_cuts(mesh, &c, faces, cut);
        let elapsed = start.elapsed().as_secs_f64() * 1e3;
        assert!(
            extra.windows(2).all(|w| w[0] < w[1]),
            "{name}: not ascending"
        );
        let in_patch: BTreeSet<u32> = faces.iter().copied().collect();
        for &e in &extra {
            assert!(!cut[e as usize], "{name}: edge {e} already cut");
            let [f0, f1] = mesh.edge_faces()[e as usize];
            assert!(
                in_patch.contains(&f0) && f1 != NONE && in_patch.contains(&f1),
                "{name}: edge {e} is not inside the patch"
            );
        }
        let mut all_cut = cut.to_vec();
        for &e in &extra {
            all_cut[e as usize] = true;
        }
        let before = patch_topology(mesh, faces, cut);
        let after = patch_topology(mesh, faces, &all_cut);
        println!(
            "{name}: chi {} with {} loops -> {} extra cut edges in {elapsed:.1} ms -> chi {}, {} loop(s)",
            before.euler_characteristic,
            before.boundary_loops.len(),
            extra.len(),
            after.euler_characteristic,
            after.boundary_loops.len()
        );
        assert_eq!(summary(&after), (1, 1), "{name}");
        if summary(&before) == (1, 1) {
            assert!(extra.is_empty(), "{name}: a disc needs no cut");
        }

        // The new cuts and the old boundary form one connected graph with no dangling
        // branch (a vertex of degree 1 in the new cuts lies on the old boundary), apart
        // from the single slit of a closed genus-0 patch.
        let boundary: BTreeSet<u32> = before.boundary_loops.iter().flatten().copied().collect();
        let mut degree = std::collections::BTreeMap::<u32, u32>::new();
        let mut sets = UnionFind::new(mesh.vertex_count());
        for &e in &extra {
            let [a, b] = mesh.edges()[e as usize];
            sets.union(a, b);
            *degree.entry(a).or_default() += 1;
            *degree.entry(b).or_default() += 1;
        }
        for l in &before.boundary_loops {
            for w in l.windows(2) {
                sets.union(w[0], w[1]);
            }
        }
        let touched: BTreeSet<u32> = degree
            .keys()
            .chain(&boundary)
            .map(|&v| sets.find(v))
            .collect();
        assert!(
            touched.len() <= 1,
            "{name}: cuts and boundary are not connected"
        );
        if !(before.boundary_loops.is_empty() && extra.len() == 1) {
            for (v, d) in &degree {
                assert!(
                    *d > 1 || boundary.contains(v),
                    "{name}: dangling cut at {v}"
                );
            }
        }
        extra.len()
    }

    #[test]
    fn disc_cuts_make_shapes_discs() {
        let cases = [
            ("plane", shapes::plane(1.0, 6).expect("plane")),
            (
                "cylinder",
                shapes::cylinder(1.0, 2.0, 12).expect("cylinder"),
            ),
            ("sphere", shapes::sphere(1.0, 3).expect("sphere")),
            ("torus", shapes::torus(1.0, 0.4, 10).expect("torus")),
            ("genus2", shapes::genus2(1.0, 2).expect("genus2")),
        ];
        for (name, mesh) in &cases {
            check_disc_cuts(name, mesh, &all_faces(mesh), &no_cut(mesh));
        }
        let (mesh, cut) = plane_slit(8, 4, 0, 4);
        assert_eq!(
            check_disc_cuts("slit from rim", &mesh, &all_faces(&mesh), &cut),
            0
        );
        let (mesh, cut) = plane_slit(8, 4, 2, 6);
        check_disc_cuts("inner slit", &mesh, &all_faces(&mesh), &cut);
        // A sphere already cut along a tree is a disc.
        let mesh = shapes::sphere(1.0, 3).expect("sphere");
        let mut cut = no_cut(&mesh);
        for v in 1..5 {
            cut[edge_between(&mesh, 0, mesh.vertex_neighbors(0)[v - 1])] = true;
        }
        assert_eq!(
            check_disc_cuts("sphere with star", &mesh, &all_faces(&mesh), &cut),
            0
        );
        // A band of the torus (an annulus) and a torus with a hole.
        let mesh = shapes::torus(1.0, 0.4, 10).expect("torus");
        let band: Vec<u32> = (0..mesh.face_count() as u32)
            .filter(|&f| mesh.face_positions(f).iter().all(|p| p.z >= -0.1))
            .collect();
        check_disc_cuts("torus band", &mesh, &band, &no_cut(&mesh));
        let holed: Vec<u32> = (1..mesh.face_count() as u32).collect();
        check_disc_cuts("holed torus", &mesh, &holed, &no_cut(&mesh));
    }

    #[test]
    fn cylinder_is_cut_once_from_rim_to_rim() {
        let mesh = shapes::cylinder(1.0, 2.0, 12).expect("cylinder");
        let mut heights: Vec<i64> = mesh
            .positions()
            .iter()
            .map(|p| (p.z * 1e6).round() as i64)
            .collect();
        heights.sort_unstable();
        heights.dedup();
        let rows = heights.len() - 1;
        let extra = disc_cuts(&mesh, &costs(&mesh), &all_faces(&mesh), &no_cut(&mesh));
        assert_eq!(
            extra.len(),
            rows,
            "one edge per row of the shortest rim-to-rim path"
        );
    }

    #[test]
    fn disc_cuts_on_shared_meshes() {
        for name in [
            "two-torus.obj",
            "rocker-arm.obj",
            "stanford-bunny.obj",
            "spot.obj",
            "cow.obj",
        ] {
            let Some(mesh) = shared_mesh(name) else {
                continue;
            };
            check_disc_cuts(name, &mesh, &all_faces(&mesh), &no_cut(&mesh));
        }
    }

    /// Faces of each connected component of the patch cut open along `cut`.
    fn components(mesh: &TriMesh, faces: &[u32], cut: &[bool]) -> Vec<Vec<u32>> {
        let patch = CutPatch::new(mesh, faces, cut);
        let mut sets = UnionFind::new(patch.faces.len());
        for (lf, sides) in patch.across.iter().enumerate() {
            for &lg in sides {
                if lg != NONE {
                    sets.union(lf as u32, lg);
                }
            }
        }
        let mut by_root = std::collections::BTreeMap::<u32, Vec<u32>>::new();
        for lf in 0..patch.faces.len() as u32 {
            by_root
                .entry(sets.find(lf))
                .or_default()
                .push(patch.faces[lf as usize]);
        }
        by_root.into_values().collect()
    }

    #[test]
    fn random_patches_with_random_seams_become_discs() {
        use crate::rng::Rng;
        let meshes = [
            shapes::torus(1.0, 0.4, 10).expect("torus"),
            shapes::genus2(1.0, 1).expect("genus2"),
            shapes::sphere(1.0, 4).expect("sphere"),
        ];
        for (m, mesh) in meshes.iter().enumerate() {
            let c = costs(mesh);
            for seed in 0..40 {
                let mut rng = Rng::new(seed, m as u64);
                // Grow a patch from a random face, breadth first, to a random size.
                let target = 1 + rng.below(mesh.face_count() as u64) as usize;
                let mut taken = vec![false; mesh.face_count()];
                let first = rng.below(mesh.face_count() as u64) as u32;
                let mut queue = std::collections::VecDeque::from([first]);
                taken[first as usize] = true;
                let mut faces = Vec::new();
                while let Some(f) = queue.pop_front() {
                    faces.push(f);
                    if faces.len() == target {
                        break;
                    }
                    for g in mesh.face_neighbors()[f as usize] {
                        if g != NONE && !taken[g as usize] && rng.next_f64() < 0.8 {
                            taken[g as usize] = true;
                            queue.push_back(g);
                        }
                    }
                }
                // Random seams: a few percent of the edges.
                let cut: Vec<bool> = (0..mesh.edge_count())
                    .map(|_| rng.next_f64() < 0.03)
                    .collect();
                let extra = disc_cuts(mesh, &c, &faces, &cut);
                let mut all_cut = cut.clone();
                for &e in &extra {
                    assert!(!cut[e as usize]);
                    all_cut[e as usize] = true;
                }
                // Every piece is a disc; and the cuts did not split a piece in two.
                let before = components(mesh, &faces, &cut).len();
                let pieces = components(mesh, &faces, &all_cut);
                assert_eq!(
                    pieces.len(),
                    before,
                    "mesh {m} seed {seed}: a piece fell apart"
                );
                for piece in &pieces {
                    let t = patch_topology(mesh, piece, &all_cut);
                    assert_eq!(summary(&t), (1, 1), "mesh {m} seed {seed}");
                }
            }
        }
    }

    #[test]
    fn disc_cuts_are_deterministic() {
        let mesh = shapes::genus2(1.0, 1).expect("genus2");
        let c = costs(&mesh);
        let faces = all_faces(&mesh);
        let reversed: Vec<u32> = faces.iter().rev().copied().collect();
        assert_eq!(
            disc_cuts(&mesh, &c, &faces, &no_cut(&mesh)),
            disc_cuts(&mesh, &c, &reversed, &no_cut(&mesh))
        );
    }
}
