//! The line-field solvers on one connected piece (the smoothest field, the guided and
//! constrained field; `pieces.rs` calls them once per piece), [`line_field_energy`]
//! and the solvers' options; the method is in the [folder's docs](super).
//!
//! Input: a mesh, options, guidance and constraints. Output: a [`LineField`]. Cost:
//! see the [folder's docs](super).

use std::borrow::Cow;

use faer::c64;
use glam::DVec3;

use super::cancel::cancel_pairs;
use super::connection::Connection;
use super::eigenpair::{smallest_eigenpair, smallest_eigenvalue};
use super::line_field::{EdgeWeights, LineField, LinearSolver};
use crate::field::LineFieldError;
use crate::field::curvature::area_radius;
use crate::linalg::Amg;
use crate::mesh::TriMesh;

/// Settings of the line-field solvers.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct LineFieldOptions {
    /// Weight of the guidance against smoothness ([`guided_line_field`](crate::field::design::guided_line_field) only). It is
    /// divided by the piece's area, `w = weight / area`, so that it is dimensionless (the
    /// Dirichlet energy of a field is scale-invariant on a surface, the guidance term
    /// `w |z - q|_M^2` scales with area). Range `[0, inf)`, 0 meaning the smoothest field;
    /// default 10.
    pub weight: f64,
    /// Shift `s` toward the smoothest field in guided solves: the system becomes
    /// `A - s lambda_1 M + w M C` (Knöppel et al. 2013's `lambda_t`), where `lambda_1` is
    /// the smallest eigenvalue of the connection Laplacian (estimated from above in at
    /// most [`LAMBDA_ITERATIONS`](crate::field::design::LAMBDA_ITERATIONS) solves). 0 is the plain guided solve; near 1
    /// the field keeps the smoothest field's few singularities and takes only its
    /// rotation and local detail from the guidance. Range `[0, 0.95]`; default 0.
    pub smoothness: f64,
    /// Length over which the surface's normals are smoothed before they define the
    /// connection, as a fraction of the area radius `R = sqrt(area / 4 pi)` of the connected
    /// piece (each piece is solved on its own):
    /// bumps smaller than about `smoothing R` then create no singularities (one
    /// implicit heat step of the normals, see the [module docs](crate::field::design)). Range
    /// `[0, inf)`, 0 using the mesh's own normals; default 0.
    pub smoothing: f64,
    /// Most solves of the smoothest field. Range `[1, inf)`; default 200.
    pub iterations: usize,
    /// The iteration stops when the Rayleigh quotient changes by at most `tolerance`
    /// times its value (or the shift, whichever is larger), and (with a direct solver)
    /// once the smoothest field's relative residual is at most `sqrt(tolerance)`.
    /// Range `(0, inf)`; default 1e-8.
    pub tolerance: f64,
    /// How the sparse systems are solved; default [`LinearSolver::Auto`].
    pub solver: LinearSolver,
    /// Opposite singularities (`+1/2` and `-1/2`) whose centres lie at most this far
    /// apart, as a fraction of the area radius `R`, are cancelled after the solve: the
    /// field's angle on a disc around both is interpolated afresh from the disc's
    /// boundary, around which it winds zero times (see the [module docs](crate::field::design)). With
    /// it the result's directions lie in the mesh's own tangent planes. Range
    /// `[0, inf)`, 0 cancelling none; default 0.
    pub cancel_distance: f64,
    /// The edge weights of the energy: [`EdgeWeights::Cotan`], the paper's (default), or
    /// [`EdgeWeights::Floored`], every weight floored at
    /// [`MIN_EDGE_WEIGHT`](crate::field::design::MIN_EDGE_WEIGHT) (the rule with
    /// smoothing, and the way out where the paper's leave a piece's energy indefinite;
    /// see the [module docs](crate::field::design)).
    pub weights: EdgeWeights,
}

impl Default for LineFieldOptions {
    fn default() -> Self {
        Self {
            weight: 10.0,
            smoothness: 0.0,
            smoothing: 0.0,
            iterations: 200,
            tolerance: 1e-8,
            solver: LinearSolver::Auto,
            cancel_distance: 0.0,
            weights: EdgeWeights::Cotan,
        }
    }
}

impl LineFieldOptions {
    /// Checks every setting against its documented range.
    pub fn validate(&self) -> Result<(), LineFieldError> {
        if !(self.weight.is_finite() && self.weight >= 0.0) {
            return Err(LineFieldError::InvalidOption {
                option: "weight",
                value: self.weight,
                expected: "finite and >= 0",
            });
        }
        if !(self.smoothness >= 0.0 && self.smoothness <= 0.95) {
            return Err(LineFieldError::InvalidOption {
                option: "smoothness",
                value: self.smoothness,
                expected: "in [0, 0.95]",
            });
        }
        if !(self.smoothing.is_finite() && self.smoothing >= 0.0) {
            return Err(LineFieldError::InvalidOption {
                option: "smoothing",
                value: self.smoothing,
                expected: "finite and >= 0",
            });
        }
        if !(self.cancel_distance.is_finite() && self.cancel_distance >= 0.0) {
            return Err(LineFieldError::InvalidOption {
                option: "cancel_distance",
                value: self.cancel_distance,
                expected: "finite and >= 0",
            });
        }
        if self.iterations == 0 {
            return Err(LineFieldError::InvalidOption {
                option: "iterations",
                value: 0.0,
                expected: ">= 1",
            });
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(LineFieldError::InvalidOption {
                option: "tolerance",
                value: self.tolerance,
                expected: "finite and > 0",
            });
        }
        Ok(())
    }
}

/// A hard constraint of
/// [`constrained_line_field`](crate::field::design::constrained_line_field): the field's line at `vertex` is
/// exactly `direction`'s (projected into the vertex's tangent plane; its sign does not
/// matter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineConstraint {
    /// Mesh vertex index.
    pub vertex: u32,
    /// World-space direction, not parallel to the vertex normal.
    pub direction: DVec3,
}

/// The smoothest line field of `mesh`, one connected piece (see
/// [`smoothest_line_field`](crate::field::design::smoothest_line_field), which calls
/// this once per piece).
pub(crate) fn smoothest_piece(
    mesh: &TriMesh,
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    options.validate()?;
    let smoothing = options.smoothing * area_radius(mesh);
    definite(options.weights.first(smoothing), |weights| {
        let system = Connection::build_with(mesh, smoothing, options.solver, true, weights)?;
        smoothest_on(mesh, &system, options)
    })
}

/// `solve` with the edge weights `first`; where that is [`EdgeWeights::Cotan`] and the
/// piece's energy turns out not positive definite (see
/// [`LineFieldError::not_definite`]), `solve` once more with [`EdgeWeights::Floored`]
/// (see the [module docs](super)).
fn definite<T>(
    first: EdgeWeights,
    mut solve: impl FnMut(EdgeWeights) -> Result<T, LineFieldError>,
) -> Result<T, LineFieldError> {
    match solve(first) {
        Err(e) if first == EdgeWeights::Cotan && e.not_definite() => solve(EdgeWeights::Floored),
        found => found,
    }
}

/// [`smoothest_piece`] with the connection already built.
fn smoothest_on(
    mesh: &TriMesh,
    system: &Connection,
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    let shift = system.shift();
    let ((x, value, solves), factor) = smallest_eigenpair(
        mesh,
        system,
        shift,
        options.iterations,
        options.tolerance,
        shift,
        true,
    )?;
    if let Some(factor) = factor {
        system.recycle(factor);
    }
    // A positive definite `A + shift M` has every eigenvalue above `-shift`; a lower
    // Ritz value (a multigrid hierarchy need not notice) shows the energy indefinite.
    if value < -shift {
        return Err(LineFieldError::Indefinite { eigenvalue: value });
    }
    let held = vec![false; x.len()];
    output(mesh, system, x, &held, options, solves)
}

/// The line field of the solution `x` (doubled angles in `system`'s frames) with
/// [`LineFieldOptions::cancel_distance`] applied: pairs are cancelled in the mesh's
/// own frames, where the segmentation measures singularities (with a smoothed
/// connection the two can differ by a pair in a bumpy region), and the field is
/// returned in those frames. Vertices with `held[v]` keep their values.
fn output(
    mesh: &TriMesh,
    system: &Connection,
    x: Vec<c64>,
    held: &[bool],
    options: &LineFieldOptions,
    iterations: usize,
) -> Result<LineField, LineFieldError> {
    if options.cancel_distance == 0.0 {
        return Ok(system.output(&x, iterations));
    }
    let distance = options.cancel_distance * area_radius(mesh);
    if options.smoothing == 0.0 {
        let mut x = x;
        cancel_pairs(mesh, system, &mut x, held, distance)?;
        return Ok(system.output(&x, iterations));
    }
    let own = system.unsmoothed(mesh);
    let mut z = system.transfer(&x, &own);
    cancel_pairs(mesh, &own, &mut z, held, distance)?;
    Ok(own.output(&z, iterations))
}

/// The smoothness energy `E(z) = sum_edges w_ab |z_b - r_ab z_a|^2` of the unit line
/// field along `directions` (one tangent direction per vertex, sign ignored), under the
/// mesh's own connection (no smoothing): the measure
/// [`smoothest_line_field`](crate::field::design::smoothest_line_field)
/// minimises, so fields from different sources can be compared. A direction with no
/// tangent part counts as zero there.
///
/// Errors: an empty mesh, a direction list of the wrong length or with a non-finite
/// vector.
pub fn line_field_energy(mesh: &TriMesh, directions: &[DVec3]) -> Result<f64, LineFieldError> {
    if directions.len() != mesh.vertex_count() {
        return Err(LineFieldError::GuidanceLength {
            expected: mesh.vertex_count(),
            found: directions.len(),
        });
    }
    if let Some(vertex) = directions.iter().position(|d| !d.is_finite()) {
        return Err(LineFieldError::NonFiniteGuidance { vertex });
    }
    let system = Connection::build(mesh, 0.0, LinearSolver::Auto, false)?;
    let z: Vec<c64> = guidance_lines(mesh, &system, directions)
        .into_iter()
        .map(|q| q.map_or(c64::new(0.0, 0.0), |(_, u)| u))
        .collect();
    Ok(system.energy(&z))
}

/// The guided and constrained line field of `mesh`, one connected piece (see
/// [`constrained_line_field`](crate::field::design::constrained_line_field), which
/// calls this once per piece), with the guidance made by `guidance.1` on one thread
/// while the connection is built (and `lambda_1` estimated) on another; `guidance.0`
/// says whether it may be non-empty (without it and without constraints the field is
/// the smoothest, and no `lambda_1` is estimated for a shift). The result does not
/// depend on the thread count.
pub(crate) fn constrained_piece<'g>(
    mesh: &TriMesh,
    (guided, guidance): (bool, impl FnOnce() -> Cow<'g, [DVec3]> + Send),
    constraints: &[LineConstraint],
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    options.validate()?;
    let smoothing = options.smoothing * area_radius(mesh);
    let first = options.weights.first(smoothing);
    let (built, guidance) = connection_beside(mesh, options, guided, constraints, guidance, first);
    let guidance = &*guidance;
    check_guidance(guidance, mesh.vertex_count())?;
    let found = built.and_then(|(system, lambda_1)| {
        constrained_on(mesh, system, lambda_1, guidance, constraints, options)
    });
    match found {
        Err(e) if first == EdgeWeights::Cotan && e.not_definite() => {
            // The paper's weights left the piece's energy indefinite: solved again
            // with the floored ones (see the module docs).
            let floored = EdgeWeights::Floored;
            let system = Connection::build_with(mesh, smoothing, options.solver, true, floored)?;
            let lambda_1 = if may_shift(options, guided, constraints) {
                Some(smallest_eigenvalue(mesh, &system, system.shift())?)
            } else {
                None
            };
            constrained_on(mesh, system, lambda_1, guidance, constraints, options)
        }
        found => found,
    }
}

/// [`constrained_piece`] with the connection built and (when the smoothness shift may
/// apply) `lambda_1` estimated, with its multigrid hierarchy.
fn constrained_on(
    mesh: &TriMesh,
    system: Connection,
    lambda_1: Option<(f64, Option<Amg<c64>>)>,
    guidance: &[DVec3],
    constraints: &[LineConstraint],
    options: &LineFieldOptions,
) -> Result<LineField, LineFieldError> {
    let n = mesh.vertex_count();
    let (lambda_1, hierarchy) = match lambda_1 {
        Some((lambda, hierarchy)) => (Some(lambda), hierarchy),
        None => (None, None),
    };
    let fixed = fixed_values(mesh, &system, constraints)?;
    let q = if options.weight > 0.0 && !guidance.is_empty() {
        guidance_lines(mesh, &system, guidance)
    } else {
        vec![None; n]
    };
    if constraints.is_empty() && q.iter().all(Option::is_none) {
        return smoothest_on(mesh, &system, options);
    }

    let (slots, free) = unknown_slots(&fixed);
    let area: f64 = system.mass.iter().sum();
    let w = options.weight / area;
    // Only a connected component with no guidance and no constraint leaves the system
    // singular (its field is free up to a rotation); the shift pins it to zero there and
    // leaves every other component exact.
    let shift = system.shift();
    let component = |v: usize| mesh.face_components()[mesh.vertex_faces(v as u32)[0] as usize];
    let mut pinned = vec![false; mesh.component_count()];
    for v in 0..n {
        if fixed[v].is_some() || q[v].is_some() {
            pinned[component(v) as usize] = true;
        }
    }
    // Knöppel et al.'s shift toward the smoothest field: `A - s lambda_1 M` weighs each
    // eigenvector of the connection Laplacian by `1 / (lambda_k - s lambda_1)`, so with
    // `s` near 1 the smoothest one dominates wherever the guidance leaves room.
    let pull = match lambda_1 {
        Some(lambda) if pinned.iter().all(|&p| p) => options.smoothness * lambda,
        _ => 0.0,
    };
    let mut extra = vec![0.0; n];
    let mut rhs = vec![c64::new(0.0, 0.0); free];
    for v in 0..n {
        let mut d = if pinned[component(v) as usize] {
            -pull * system.mass[v]
        } else {
            shift * system.mass[v]
        };
        if let Some((c, u)) = q[v] {
            let k = w * system.mass[v] * c;
            d += k;
            if fixed[v].is_none() {
                rhs[slots[v]] += u * k;
            }
        }
        extra[v] = d;
    }
    // Edges with one fixed end: their coupling moves to the right-hand side
    // (row b gains w r z_a, row a gains w conj(r) z_b).
    for e in &system.edges {
        match (fixed[e.a], fixed[e.b]) {
            (Some(za), None) => rhs[slots[e.b]] += e.rotation * za * e.weight,
            (None, Some(zb)) => rhs[slots[e.a]] += e.rotation.conj() * zb * e.weight,
            _ => {}
        }
    }
    if free > 0 {
        // With multigrid, the hierarchy built for lambda_1 (of `A + shift M`)
        // preconditions the shifted system when their ratio is bounded (see
        // `REUSE_CONDITION`), saving a second hierarchy's setup.
        let reuse = hierarchy.filter(|_| {
            free == n
                && lambda_1.is_some_and(|lambda| {
                    reuse_condition(&extra, &system.mass, shift, lambda) <= REUSE_CONDITION
                })
        });
        let unknowns = Unknowns {
            slots: &slots,
            free,
        };
        rhs = solve_shifted(mesh, &system, &extra, pull, unknowns, reuse, rhs)?;
    }
    let x: Vec<c64> = (0..n)
        .map(|v| fixed[v].unwrap_or_else(|| rhs[slots[v]]))
        .collect();
    let held: Vec<bool> = fixed.iter().map(Option::is_some).collect();
    output(mesh, &system, x, &held, options, 0)
}

/// The connection (and, when the smoothness shift may apply, the estimate of
/// `lambda_1` with its multigrid hierarchy) built on one thread, the guidance made on
/// another. `lambda_1` depends on the connection alone, so it is estimated beside the
/// guidance whenever the shift may apply (it is dropped when a component turns out
/// unpinned); the connection's build keeps both threads busy on its own. Without the
/// shift the guidance is made beside the build.
fn connection_beside<'g>(
    mesh: &TriMesh,
    options: &LineFieldOptions,
    guided: bool,
    constraints: &[LineConstraint],
    guidance: impl FnOnce() -> Cow<'g, [DVec3]> + Send,
    weights: EdgeWeights,
) -> (Result<Built, LineFieldError>, Cow<'g, [DVec3]>) {
    let smoothing = options.smoothing * area_radius(mesh);
    let build = || Connection::build_with(mesh, smoothing, options.solver, true, weights);
    if may_shift(options, guided, constraints) {
        rayon::join(
            || -> Result<Built, LineFieldError> {
                let system = build()?;
                let lambda = smallest_eigenvalue(mesh, &system, system.shift())?;
                Ok((system, Some(lambda)))
            },
            guidance,
        )
    } else {
        rayon::join(|| Ok((build()?, None)), guidance)
    }
}

/// Whether the smoothness shift may apply, so that `lambda_1` is estimated.
fn may_shift(options: &LineFieldOptions, guided: bool, constraints: &[LineConstraint]) -> bool {
    options.smoothness > 0.0 && ((options.weight > 0.0 && guided) || !constraints.is_empty())
}

/// What [`connection_beside`] builds: the connection and, when the smoothness shift
/// may apply, the estimate of `lambda_1` with the multigrid hierarchy it built.
type Built = (Connection, Option<(f64, Option<Amg<c64>>)>);

/// Checks a guidance: empty or one finite vector per vertex.
pub(super) fn check_guidance(guidance: &[DVec3], n: usize) -> Result<(), LineFieldError> {
    if !guidance.is_empty() && guidance.len() != n {
        return Err(LineFieldError::GuidanceLength {
            expected: n,
            found: guidance.len(),
        });
    }
    if let Some(vertex) = guidance.iter().position(|d| !d.is_finite()) {
        return Err(LineFieldError::NonFiniteGuidance { vertex });
    }
    Ok(())
}

/// Per vertex its unknown's slot: the free vertices in index order, then the fixed
/// ones (slots >= free); and the count of free ones.
fn unknown_slots(fixed: &[Option<c64>]) -> (Vec<usize>, usize) {
    let n = fixed.len();
    let mut slots = vec![0; n];
    let mut free = 0;
    for v in 0..n {
        if fixed[v].is_none() {
            slots[v] = free;
            free += 1;
        }
    }
    let mut next = free;
    for v in 0..n {
        if fixed[v].is_some() {
            slots[v] = next;
            next += 1;
        }
    }
    (slots, free)
}

/// The unknowns of a constrained solve: each vertex's slot and the free count.
#[derive(Clone, Copy)]
struct Unknowns<'a> {
    slots: &'a [usize],
    free: usize,
}

/// Solves `(A + diag(extra) + pull M) z = rhs` on the free unknowns, first with the
/// hierarchy `reuse` when given and it converges. An estimate of `lambda_1` slightly
/// too high could leave the shifted system indefinite (a failed factorization, or
/// conjugate gradients meeting negative curvature): then the shift is halved (three
/// times at most, then none). Last, where even that fails, the tiny shift
/// `sigma M` that keeps an unguided piece definite is added everywhere: a piece whose
/// guidance is almost zero (a nearly flat crumb of a scan, whose curvature guidance is
/// round-off) is nearly singular without it, which a multigrid hierarchy's dense
/// coarsest factor can find not positive definite.
fn solve_shifted(
    mesh: &TriMesh,
    system: &Connection,
    extra: &[f64],
    pull: f64,
    unknowns: Unknowns<'_>,
    mut reuse: Option<Amg<c64>>,
    rhs: Vec<c64>,
) -> Result<Vec<c64>, LineFieldError> {
    let shift = system.shift();
    let mut attempt = 0;
    loop {
        // The mass multiple added to `extra` at this attempt.
        let back = match attempt {
            0..=3 => pull * (1.0 - 0.5f64.powi(attempt)),
            4 => pull,
            _ => pull + shift,
        };
        let shifted: Vec<f64> = extra
            .iter()
            .zip(&system.mass)
            .map(|(d, m)| d + back * m)
            .collect();
        if let Some(amg) = reuse.take()
            && let Some(z) = system.solve_with_hierarchy(&amg, shift, &shifted, &rhs)
        {
            return Ok(z);
        }
        let mut z = rhs.clone();
        let solved = system
            .factor(mesh, &shifted, unknowns.slots, unknowns.free)
            .and_then(|mut factor| factor.solve(&mut z));
        match solved {
            Ok(()) => return Ok(z),
            Err(e) if attempt >= 5 => return Err(e),
            Err(_) if pull == 0.0 => attempt = 5,
            Err(_) => attempt += 1,
        }
    }
}

/// The largest bound on the condition number of `B^-1 K` under which the shifted
/// system `K = A + diag(extra)` is solved with the hierarchy of `B = A + shift M` built
/// for `lambda_1` (bound from [`reuse_condition`]); above it a hierarchy of `K` is
/// built. The bound is a worst case over single vertices: the bunny's designed field
/// (`configs/stanford-bunny-smooth.ron`) gives 3.3 / 5.2 / 8.6 at 69k / 278k / 1.1M
/// faces and the reused hierarchy takes 21 iterations at 278k and 1.1M, as a fresh one
/// does. Stiffer systems fall above it: the bunny at guidance weights 100 and 1000
/// gives 223 and 1,545, the built-in cylinder with the default design (strong
/// curvature guidance against a small `lambda_1`) 25,935.
pub(crate) const REUSE_CONDITION: f64 = 16.0;

/// A bound on the condition number of `B^-1 K` for `K = A + diag(extra)` and
/// `B = A + shift M` (`M = diag(mass)`), from `z^H B z >= (lambda_1 + shift) z^H M z`:
/// with `r_v = extra_v / mass_v - shift`, the ratio `z^H K z / z^H B z` lies in
/// `[1 + min(r, 0) / (lambda_1 + shift), 1 + max(r, 0) / (lambda_1 + shift)]`.
/// Infinite where the lower end is not positive.
pub(crate) fn reuse_condition(extra: &[f64], mass: &[f64], shift: f64, lambda: f64) -> f64 {
    let (lo, hi) = extra
        .iter()
        .zip(mass)
        .map(|(d, m)| d / m - shift)
        .fold((0.0f64, 0.0f64), |(lo, hi), r| (lo.min(r), hi.max(r)));
    let scale = lambda + shift;
    let (lo, hi) = (1.0 + lo / scale, 1.0 + hi / scale);
    if lo > 0.0 { hi / lo } else { f64::INFINITY }
}

/// Per vertex, the guidance's confidence and unit doubled-angle line in the vertex
/// frame; `None` where there is no guidance.
fn guidance_lines(
    mesh: &TriMesh,
    system: &Connection,
    guidance: &[DVec3],
) -> Vec<Option<(f64, c64)>> {
    guidance
        .iter()
        .zip(mesh.vertex_normals())
        .enumerate()
        .map(|(v, (d, nv))| system.frames.doubled(v, *d - *nv * d.dot(*nv)))
        .collect()
}

/// Per vertex, the fixed unit doubled-angle value of its constraint, if any.
fn fixed_values(
    mesh: &TriMesh,
    system: &Connection,
    constraints: &[LineConstraint],
) -> Result<Vec<Option<c64>>, LineFieldError> {
    check_constraint_vertices(mesh.vertex_count(), constraints)?;
    let mut fixed = vec![None; mesh.vertex_count()];
    for (index, c) in constraints.iter().enumerate() {
        let v = c.vertex as usize;
        let nv = mesh.vertex_normals()[v];
        let d = c.direction;
        let tangent = d - nv * d.dot(nv);
        let usable = d.is_finite() && tangent.length_squared() > 1e-12 * d.length_squared();
        let Some((_, z)) = system.frames.doubled(v, tangent).filter(|_| usable) else {
            return Err(LineFieldError::ConstraintDirection {
                index,
                vertex: c.vertex,
            });
        };
        fixed[v] = Some(z);
    }
    Ok(fixed)
}

/// Every constraint names one of the `n` vertices, and no vertex twice.
pub(super) fn check_constraint_vertices(
    n: usize,
    constraints: &[LineConstraint],
) -> Result<(), LineFieldError> {
    let mut owner = vec![usize::MAX; n];
    for (index, c) in constraints.iter().enumerate() {
        let v = c.vertex as usize;
        if v >= n {
            return Err(LineFieldError::ConstraintVertex {
                index,
                vertex: c.vertex,
                vertices: n,
            });
        }
        if owner[v] != usize::MAX {
            return Err(LineFieldError::DuplicateConstraint {
                first: owner[v],
                second: index,
                vertex: c.vertex,
            });
        }
        owner[v] = index;
    }
    Ok(())
}

#[cfg(test)]
#[path = "solve_tests.rs"]
mod tests;
