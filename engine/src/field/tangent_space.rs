//! The intrinsic tangent spaces of a mesh's vertices and the discrete Levi-Civita
//! connection between them: the one connection that field design and the singularity
//! index both use.
//!
//! # Discretization
//! Knöppel, Crane, Pinkall and Schröder, "Globally optimal direction fields"
//! (SIGGRAPH 2013, section 6.1), with the conventions of geometry-central's
//! `IntrinsicGeometryInterface` (`cornerScaledAngles`, `halfedgeVectorsInVertex`,
//! `transportVectorsAlongHalfedge`, `faceGaussianCurvatures`):
//! - **Angle-rescaled frames.** Around vertex `v` the corner angles `alpha` of its
//!   faces, walked counter-clockwise (the faces' orientation), are scaled by
//!   `s_v = 2 pi / Theta_v` at an interior vertex (`Theta_v` their sum). The angle of
//!   each edge leaving `v` is the scaled sum of the corners before it; the first edge
//!   (of the first fan; a boundary fan's first edge) has angle 0.
//! - **Boundary vertices** keep their corner angles (`s_v = 1`, up to a cap of
//!   `3 pi / 2` for the whole fan): the boundary's turning is not curvature, so a
//!   constant field on a flat piece has no singularity at a boundary corner.
//!   geometry-central instead scales a boundary fan to a half plane (`s_v = pi /
//!   Theta_v`), which pairs with its fields that align to the boundary (Dirichlet
//!   conditions) but puts a half-index at every boundary corner of a free field like
//!   strata's. A vertex whose faces form several fans lays them end to end. Where
//!   every fan is closed (a pinched vertex: the tips of `n` cones meeting in one
//!   point) the connection scales them to `n` turns, so that each cone's defect counts
//!   and the indices sum to the Euler characteristic of the surface with the pinch
//!   split (the world-direction map below treats it as an open fan); where one is
//!   open the vertex is treated as a boundary vertex. An edge shared by more than two
//!   faces keeps the angle of the first fan that reaches it.
//! - **Transport.** Along edge `a -> b` a tangent vector at angle `theta` at `a`
//!   arrives at `b` at `theta + rho_ab`, `rho_ab = phi_b(b -> a) + pi - phi_a(a -> b)`
//!   (it keeps its angle to the edge); a line field's doubled angle turns by
//!   `2 rho_ab`.
//! - **Holonomy.** Around face `f` the transports sum to `Omega_f = sum_corners
//!   s_v alpha - pi` (mod `2 pi`), the vertices' intrinsic angle defects
//!   `2 pi - Theta_v` spread over their corners in proportion to the corner angles.
//!   `Omega_f` is kept as a real number (each corner's term the representative nearest
//!   `s_v alpha`), so that a field's winding plus `2 Omega_f` is exactly a multiple of
//!   `2 pi` ([`face_double_index`](TangentSpaces::face_double_index)), and the indices
//!   sum to the Euler characteristic on a closed manifold mesh (Poincare-Hopf).
//!
//! Nothing here depends on the embedding beyond edge lengths and corner angles, so a
//! crease does not turn the connection and subdividing flat faces does not change it.
//!
//! # World directions
//! Fields come in and go out as world-space directions. Per vertex a monotone,
//! piecewise-linear map of the circle of doubled angles takes a line's doubled angle
//! in the vertex-normal [`tangent_frame`] to its doubled intrinsic angle, and back
//! exactly: the projected edges are the breakpoints (their projected corner angles
//! scaled to the same total as the intrinsic ones; an open fan's gap closes the
//! circle), and a line's two ends `theta`,
//! `theta + pi` are averaged (`M(2 theta) = m(theta) + m(theta + pi) - pi`) so that lines,
//! not vectors, map to lines. On a flat vertex the map is a rotation.
//!
//! Input: a [`TriMesh`]. Output: [`TangentSpaces`]. Cost: O(V + E + F), a handful of
//! small allocations per vertex, in parallel over vertices and faces.

use std::f64::consts::{PI, TAU};

use glam::DVec3;
use rayon::prelude::*;

use super::eigen::{frame_angle, tangent_frame};
use crate::mesh::{NONE, TriMesh};

/// The intrinsic tangent spaces and connection of a mesh (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct TangentSpaces {
    /// Per edge `[a, b]`: the angle of the direction `a -> b` in `a`'s space and in
    /// `b`'s.
    edge_angles: Vec<[f64; 2]>,
    /// Per face, the holonomy `Omega_f` as a real number.
    holonomy: Vec<f64>,
    /// Per face, `sum s_v alpha - pi`.
    defect: Vec<f64>,
    /// Per vertex, the vertex-normal tangent frame world directions are measured in.
    frames: Vec<(DVec3, DVec3)>,
    /// Per vertex, the start of its breakpoints in `map`.
    offsets: Vec<u32>,
    /// Breakpoints `[extrinsic, intrinsic]` doubled angles, both increasing per vertex
    /// over one turn.
    map: Vec<[f64; 2]>,
}

/// One corner of the fan walk around a vertex.
#[derive(Clone, Copy)]
struct Corner {
    /// Edge to the next vertex of the face (the corner's first side, counter-clockwise).
    to_next: u32,
    /// Edge to the previous vertex (its second side).
    to_prev: u32,
    /// The corner angle.
    alpha: f64,
}

/// What one vertex contributes: per incident edge its (unscaled) angle, the scale,
/// and the line map's breakpoints.
struct VertexSpace {
    edges: Vec<(u32, f64)>,
    scale: f64,
    map: Vec<[f64; 2]>,
}

impl TangentSpaces {
    /// Builds the tangent spaces of `mesh`. O(V + E + F).
    pub fn new(mesh: &TriMesh) -> Self {
        let frames: Vec<(DVec3, DVec3)> = mesh
            .vertex_normals()
            .par_iter()
            .map(|n| tangent_frame(*n))
            .collect();
        let spaces: Vec<VertexSpace> = (0..mesh.vertex_count() as u32)
            .into_par_iter()
            .with_min_len(MIN_PARALLEL)
            .map(|v| vertex_space(mesh, v, frames[v as usize]))
            .collect();
        let mut edge_angles = vec![[f64::NAN; 2]; mesh.edge_count()];
        let mut offsets = Vec::with_capacity(spaces.len() + 1);
        let mut map = Vec::new();
        offsets.push(0);
        for (v, space) in spaces.iter().enumerate() {
            for &(e, angle) in &space.edges {
                let side = usize::from(mesh.edges()[e as usize][0] != v as u32);
                // Seen from b, the direction a -> b points back along the edge.
                edge_angles[e as usize][side] = space.scale * angle + side as f64 * PI;
            }
            map.extend_from_slice(&space.map);
            offsets.push(map.len() as u32);
        }
        let scales: Vec<f64> = spaces.iter().map(|s| s.scale).collect();
        let (holonomy, defect) = face_holonomies(mesh, &edge_angles, &scales);
        Self {
            edge_angles,
            holonomy,
            defect,
            frames,
            offsets,
            map,
        }
    }

    /// Per edge `[a, b]` (as [`TriMesh::edges`] stores it), the angle of the direction
    /// `a -> b` in `a`'s tangent space and in `b`'s.
    pub fn edge_angles(&self) -> &[[f64; 2]] {
        &self.edge_angles
    }

    /// The rotation `rho` of edge `e` from its first vertex to its second: a vector at
    /// angle `theta` at `a` is transported to angle `theta + rho` at `b`.
    pub fn transport(&self, e: usize) -> f64 {
        let [a, b] = self.edge_angles[e];
        b - a
    }

    /// Per face, the connection's holonomy `Omega_f` (radians, a real number; sums to
    /// `2 pi chi` on a closed manifold mesh).
    pub fn face_holonomy(&self) -> &[f64] {
        &self.holonomy
    }

    /// Per face, the intrinsic angle defect spread to it, `sum_corners s_v alpha - pi`;
    /// equal to [`face_holonomy`](Self::face_holonomy) wherever the fans are manifold.
    pub fn face_defect(&self) -> &[f64] {
        &self.defect
    }

    /// The doubled intrinsic angle at `v` of the line along the tangent direction `d`
    /// (world space; its part normal to the vertex normal is ignored), with the length
    /// of that tangent part; `None` where `d` has no tangent part.
    pub fn doubled_angle(&self, v: usize, d: DVec3) -> Option<(f64, f64)> {
        let (e1, e2) = self.frames[v];
        let (c, s) = (d.dot(e1), d.dot(e2));
        let len2 = c * c + s * s;
        (len2 > 0.0).then(|| (self.intrinsic(v, 2.0 * s.atan2(c)), len2.sqrt()))
    }

    /// The doubled intrinsic angle at `v` of the line at doubled angle `two_theta` in
    /// the vertex-normal [`tangent_frame`].
    pub fn intrinsic(&self, v: usize, two_theta: f64) -> f64 {
        circle_map(self.breakpoints(v), two_theta, 0)
    }

    /// The unit world direction (in the vertex-normal tangent plane, sign arbitrary) of
    /// the line at doubled intrinsic angle `doubled` at `v`: the inverse of
    /// [`doubled_angle`](Self::doubled_angle).
    pub fn direction(&self, v: usize, doubled: f64) -> DVec3 {
        let two_theta = circle_map(self.breakpoints(v), doubled, 1);
        let (s, c) = (0.5 * two_theta).sin_cos();
        let (e1, e2) = self.frames[v];
        e1 * c + e2 * s
    }

    /// Twice the index of face `f` of a line field given by its doubled intrinsic
    /// angle per vertex: the field's turn against the transport around the face plus
    /// `2 Omega_f`, over `2 pi` (an integer up to round-off by construction).
    pub fn face_double_index(&self, mesh: &TriMesh, doubled: &[f64], f: usize) -> i64 {
        let t = mesh.triangles()[f];
        let fe = mesh.face_edges()[f];
        let mut sum = 2.0 * self.holonomy[f];
        for k in 0..3 {
            let e = fe[k] as usize;
            let [a, b] = mesh.edges()[e];
            let [pa, pb] = self.edge_angles[e];
            let turn = wrap_pi((doubled[b as usize] - 2.0 * pb) - (doubled[a as usize] - 2.0 * pa));
            sum += if a == t[k] { turn } else { -turn };
        }
        (sum / TAU).round() as i64
    }

    fn breakpoints(&self, v: usize) -> &[[f64; 2]] {
        &self.map[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}

/// Vertices (or faces) below which the passes stay on the calling thread.
const MIN_PARALLEL: usize = 1 << 12;

/// `x` wrapped into `(-pi, pi]`.
fn wrap_pi(x: f64) -> f64 {
    let y = x - TAU * (x / TAU).round();
    if y <= -PI { y + TAU } else { y }
}

/// The Euler characteristic of the surface with every pinched vertex split into its
/// cones: `V - E + F` plus `n - 1` for each vertex where `n > 1` closed fans meet. On a
/// closed mesh the line field's indices sum to this (Poincare-Hopf), since the
/// connection counts the defect of each cone. `O(F)`.
pub fn split_euler_characteristic(mesh: &TriMesh) -> i64 {
    let extra: usize = (0..mesh.vertex_count() as u32)
        .map(|v| match fans(mesh, v).1 {
            FanKind::Pinched(n) => n - 1,
            FanKind::Interior | FanKind::Open => 0,
        })
        .sum();
    mesh.euler_characteristic() + extra as i64
}

/// How the faces around a vertex close up.
#[derive(Clone, Copy, PartialEq, Eq)]
enum FanKind {
    /// One closed fan: an interior manifold vertex.
    Interior,
    /// `n > 1` fans, every one closed: a pinched vertex, the tips of `n` cones.
    Pinched(usize),
    /// At least one open fan: a boundary (or non-manifold open) vertex.
    Open,
}

/// The corners at `v` in fan order (counter-clockwise), and how its fans close.
fn fans(mesh: &TriMesh, v: u32) -> (Vec<Corner>, FanKind) {
    let pos = mesh.positions();
    let faces = mesh.vertex_faces(v);
    let corner_of = |f: u32| -> (usize, [u32; 3]) {
        let t = mesh.triangles()[f as usize];
        (t.iter().position(|&u| u == v).unwrap_or(0), t)
    };
    // Counter-clockwise successor of each corner: the face across its second side,
    // if that face continues the fan with the same orientation.
    let next: Vec<Option<usize>> = faces
        .iter()
        .map(|&f| {
            let (k, t) = corner_of(f);
            let g = mesh.face_neighbors()[f as usize][(k + 2) % 3];
            if g == NONE {
                return None;
            }
            let (kg, tg) = corner_of(g);
            (tg[(kg + 1) % 3] == t[(k + 2) % 3])
                .then(|| faces.iter().position(|&h| h == g))
                .flatten()
        })
        .collect();
    let mut has_prev = vec![false; faces.len()];
    for j in next.iter().flatten() {
        has_prev[*j] = true;
    }
    let starts = (0..faces.len()).filter(|&i| !has_prev[i]);
    let mut visited = vec![false; faces.len()];
    let mut order = Vec::with_capacity(faces.len());
    let mut fan_count = 0;
    let walk = |start: usize, order: &mut Vec<usize>, visited: &mut Vec<bool>| {
        let mut i = start;
        while !visited[i] {
            visited[i] = true;
            order.push(i);
            match next[i] {
                Some(j) => i = j,
                None => break,
            }
        }
    };
    let mut open = false;
    for s in starts.collect::<Vec<_>>() {
        walk(s, &mut order, &mut visited);
        fan_count += 1;
        open = true;
    }
    for s in 0..faces.len() {
        if !visited[s] {
            walk(s, &mut order, &mut visited);
            fan_count += 1;
        }
    }
    let corners = order
        .into_iter()
        .map(|i| {
            let f = faces[i];
            let (k, t) = corner_of(f);
            let fe = mesh.face_edges()[f as usize];
            let p = pos[v as usize];
            let u = pos[t[(k + 1) % 3] as usize] - p;
            let w = pos[t[(k + 2) % 3] as usize] - p;
            Corner {
                to_next: fe[k],
                to_prev: fe[(k + 2) % 3],
                alpha: u.cross(w).length().atan2(u.dot(w)),
            }
        })
        .collect();
    let kind = match (open, fan_count) {
        (false, 1) => FanKind::Interior,
        (false, n) if n > 1 => FanKind::Pinched(n),
        _ => FanKind::Open,
    };
    (corners, kind)
}

/// The tangent space of vertex `v` (see [`VertexSpace`]).
fn vertex_space(mesh: &TriMesh, v: u32, frame: (DVec3, DVec3)) -> VertexSpace {
    let (corners, kind) = fans(mesh, v);
    let interior = kind == FanKind::Interior;
    let pos = mesh.positions();
    let total: f64 = corners.iter().map(|c| c.alpha).sum();
    // The scale of the world-direction map: one turn, or an open fan's.
    let map_scale = if !(total > 0.0) {
        1.0
    } else if interior {
        TAU / total
    } else {
        (OPEN_TURN / total).min(1.0)
    };
    // The scale of the connection: a pinched vertex is the tip of `n` cones, each a
    // whole turn, so its fans (laid end to end) are scaled to `n` turns: each cone's
    // angle defect counts and Poincare-Hopf holds on the surface with the pinch split.
    let scale = match kind {
        FanKind::Pinched(n) if total > 0.0 => TAU * n as f64 / total,
        _ => map_scale,
    };
    // The projected angle of the edge `e` leaving v.
    let projected = |e: u32| {
        let [a, b] = mesh.edges()[e as usize];
        let other = if a == v { b } else { a };
        frame_angle(pos[other as usize] - pos[v as usize], frame)
    };
    let mut edges: Vec<(u32, f64)> = Vec::with_capacity(corners.len() + 1);
    // Knots `(projected span so far, intrinsic angle)`, unscaled.
    let mut knots: Vec<(f64, f64)> = Vec::with_capacity(corners.len() + 1);
    let (mut angle, mut span) = (0.0, 0.0);
    let start = corners.first().map_or(0.0, |c| projected(c.to_next));
    for (i, c) in corners.iter().enumerate() {
        if !edges.iter().any(|&(e, _)| e == c.to_next) {
            edges.push((c.to_next, angle));
        }
        knots.push((span, angle));
        angle += c.alpha;
        span += (projected(c.to_prev) - projected(c.to_next)).rem_euclid(TAU);
        let closes = corners.get(i + 1).is_none_or(|n| n.to_next != c.to_prev);
        if closes && !edges.iter().any(|&(e, _)| e == c.to_prev) {
            edges.push((c.to_prev, angle));
        }
    }
    // Scale both sides to one turn (interior) or to at most OPEN_TURN, the rest of the
    // circle a gap from the fan's last edge back to its first (open fans).
    let x_scale = match (interior, span > 0.0) {
        (true, true) => TAU / span,
        (false, true) => (OPEN_TURN / span).min(1.0),
        // The projection collapsed: the intrinsic angles stand in for it.
        (_, false) => map_scale,
    };
    let mut scaled: Vec<(f64, f64)> = knots
        .iter()
        .map(|&(x, y)| {
            let x = if span > 0.0 { x } else { y };
            (x * x_scale, y * map_scale)
        })
        .collect();
    if !interior && total > 0.0 {
        let x = if span > 0.0 { span } else { total };
        scaled.push((x * x_scale, total * map_scale));
    }
    let map = line_map(&scaled, start);
    VertexSpace { edges, scale, map }
}

/// The largest angle an open (boundary or non-manifold) fan keeps unscaled: beyond
/// it the fan is scaled down to it, so that the rest of the circle stays a gap of at
/// least a quarter turn. Boundary fans are otherwise not rescaled (see the module
/// docs).
const OPEN_TURN: f64 = 1.5 * PI;

/// The breakpoints of the doubled-angle line map of a vertex (see the module docs)
/// from the knots `(extrinsic offset, intrinsic angle)` of its vector map `m`
/// (increasing from `(0, 0)`, inside one turn, closed by `(2 pi, 2 pi)`) and the
/// projected angle `start` of its first edge: `M(2 theta) = m(theta) + m(theta + pi)
/// - pi` (`2 m(theta)` where `m` is a rotation), breakpoints at every knot modulo pi.
fn line_map(scaled: &[(f64, f64)], start: f64) -> Vec<[f64; 2]> {
    if scaled.is_empty() {
        return vec![[0.0, 0.0]];
    }
    // `m(u)`: the intrinsic angle of the extrinsic offset `u` in [0, 2 pi].
    let m = |u: f64| -> f64 {
        let i = scaled.partition_point(|&(x, _)| x <= u).saturating_sub(1);
        let (x0, y0) = scaled[i];
        let (x1, y1) = scaled.get(i + 1).copied().unwrap_or((TAU, TAU));
        if x1 > x0 {
            y0 + (u - x0) / (x1 - x0) * (y1 - y0)
        } else {
            y0
        }
    };
    let mut ts: Vec<f64> = scaled.iter().map(|&(x, _)| x.rem_euclid(PI)).collect();
    ts.sort_by(f64::total_cmp);
    ts.dedup();
    ts.into_iter()
        .map(|t| [2.0 * (start + t), m(t) + m(t + PI) - PI])
        .collect()
}

/// Evaluates the doubled-angle line map `knots` (column `from` to the other) at `x`:
/// piecewise linear between knots over one turn, continued periodically.
fn circle_map(knots: &[[f64; 2]], x: f64, from: usize) -> f64 {
    let to = 1 - from;
    let x0 = knots[0][from];
    let u = x0 + (x - x0).rem_euclid(TAU);
    let i = knots.partition_point(|k| k[from] <= u).saturating_sub(1);
    let a = knots[i];
    let b = knots
        .get(i + 1)
        .copied()
        .unwrap_or([knots[0][0] + TAU, knots[0][1] + TAU]);
    if b[from] > a[from] {
        a[to] + (u - a[from]) / (b[from] - a[from]) * (b[to] - a[to])
    } else {
        a[to]
    }
}

/// Per face, the holonomy (each corner's turn lifted to the representative nearest
/// its scaled angle) and the spread defect `sum s alpha - pi`.
fn face_holonomies(
    mesh: &TriMesh,
    edge_angles: &[[f64; 2]],
    scales: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let pos = mesh.positions();
    // The angle at v of the edge e leaving v.
    let out = |e: u32, v: u32| -> f64 {
        let [a, _] = mesh.edges()[e as usize];
        let [pa, pb] = edge_angles[e as usize];
        if v == a { pa } else { pb - PI }
    };
    mesh.triangles()
        .par_iter()
        .with_min_len(MIN_PARALLEL)
        .zip(mesh.face_edges())
        .map(|(t, fe)| {
            let (mut omega, mut defect) = (-PI, -PI);
            for k in 0..3 {
                let v = t[k];
                let p = pos[v as usize];
                let u = pos[t[(k + 1) % 3] as usize] - p;
                let w = pos[t[(k + 2) % 3] as usize] - p;
                let scaled = scales[v as usize] * u.cross(w).length().atan2(u.dot(w));
                let turn = out(fe[(k + 2) % 3], v) - out(fe[k], v);
                omega += scaled + wrap_pi(turn - scaled);
                defect += scaled;
            }
            (omega, defect)
        })
        .unzip()
}

#[cfg(test)]
#[path = "tangent_space_tests.rs"]
mod tests;
