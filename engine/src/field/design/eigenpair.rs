//! The smallest eigenpair of the connection Laplacian `A z = lambda M z` for the
//! line-field solvers of [`design`](super): the smoothest field (its vector)
//! and the estimate of `lambda_1` behind the smoothness shift (its value). With a
//! direct factor: Rayleigh-Ritz on a Krylov space (`linalg::lanczos`); with
//! multigrid: Rayleigh-Ritz on a space grown by preconditioned residuals (Davidson).
//! Both start from one fixed pseudo-random vector and sum in a fixed order, so results
//! are deterministic.

use faer::c64;

use super::connection::{Connection, Factor};
use crate::field::LineFieldError;
use crate::linalg::{Amg, lanczos};
use crate::mesh::TriMesh;

/// Most solves behind the estimate of `lambda_1` for
/// [`LineFieldOptions::smoothness`](crate::field::LineFieldOptions::smoothness).
pub const LAMBDA_ITERATIONS: usize = 12;

/// The estimate of `lambda_1` stops once a solve changes it by at most this fraction.
/// It converges from above and faster than geometrically (Rayleigh-Ritz on a Krylov
/// space, see `linalg/lanczos.rs`), so the last estimate is much closer than its last change:
/// on the bunny the estimates after 1 to 4 solves are 1441, 516, 489 and 483 against a
/// converged 482.0, so it stops after 4 solves 0.3% high (5 inverse iterations, the
/// method before, stopped 0.8% high), as if `smoothness` were 0.5015 instead of 0.5.
pub const LAMBDA_TOLERANCE: f64 = 2e-2;

/// A fixed pseudo-random value in `[-1, 1)` for index `i` (SplitMix64 finaliser).
pub(crate) fn start_value(i: u64) -> f64 {
    let mut z = i.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// An estimate from above of the smallest eigenvalue `lambda_1` of `A z = lambda M z`,
/// to [`LAMBDA_TOLERANCE`] in at most [`LAMBDA_ITERATIONS`] solves (see
/// [`smallest_eigenpair`]), and with multigrid solves the hierarchy of `A + shift M`
/// it built, for a caller whose next system differs from it by the diagonal only.
pub(crate) fn smallest_eigenvalue(
    mesh: &TriMesh,
    system: &Connection,
    shift: f64,
) -> Result<(f64, Option<Amg<c64>>), LineFieldError> {
    let ((_, value, _), factor) = smallest_eigenpair(
        mesh,
        system,
        shift,
        LAMBDA_ITERATIONS,
        LAMBDA_TOLERANCE,
        0.0,
        false,
    )?;
    Ok(match factor {
        Some(Factor::Multigrid(amg)) => (value, Some(amg)),
        Some(direct) => {
            system.recycle(direct);
            (value, None)
        }
        None => (value, None),
    })
}

/// Most basis vectors of the Krylov space behind [`smallest_eigenpair`] before it
/// restarts from its Ritz vector (memory: this many complex vectors of the mesh).
const KRYLOV_BASIS: usize = 24;

/// Most basis vectors of the multigrid-preconditioned (Davidson) space behind the
/// smoothest field, before it restarts from its two newest Ritz vectors. Each step
/// orthogonalises against the whole basis, which costs more than the V-cycle at a
/// few dozen vectors: on the bunny Loop-subdivided once 8 vectors took 30 steps
/// (0.48 s), 24 took 24 steps (0.60 s) and 3 took 34 (bench/README.md, "The
/// smoothest field by multigrid").
const DAVIDSON_BASIS: usize = 8;

/// The preconditioned Davidson method with the hierarchy `amg` of `A + shift M`
/// ([`lanczos::smallest_eigenpair_preconditioned`]), from the fixed start, with the
/// stopping rule of [`smallest_eigenpair`]. Returns the value, the vector and the
/// V-cycles taken.
fn davidson(
    system: &Connection,
    amg: &Amg<c64>,
    max: usize,
    tolerance: f64,
    floor: f64,
    vector: bool,
) -> Result<(f64, Vec<c64>, usize), LineFieldError> {
    let mut work = amg.workspace();
    let options = stopping_rule(max, tolerance, floor, vector, DAVIDSON_BASIS);
    lanczos::smallest_eigenpair_preconditioned(
        &system.mass,
        start_vector(system.len()),
        options,
        |r, z| amg.apply(r, z, &mut work),
        |x| system.apply(x),
    )
    .map_err(LineFieldError::from)
}

/// The stopping rule of [`smallest_eigenpair`] (shared by both of its solvers) with
/// at most `basis_limit` basis vectors.
fn stopping_rule(
    max: usize,
    tolerance: f64,
    floor: f64,
    vector: bool,
    basis_limit: usize,
) -> lanczos::KrylovOptions {
    lanczos::KrylovOptions {
        max_solves: max,
        tolerance,
        floor,
        basis_limit,
        residual: vector.then(|| tolerance.sqrt()),
    }
}

/// The fixed pseudo-random start of the eigen-iterations.
fn start_vector(n: usize) -> Vec<c64> {
    (0..n as u64)
        .map(|v| c64::new(start_value(2 * v), start_value(2 * v + 1)))
        .collect()
}

/// The vector (`z^H M z = 1`), its value and the solves taken.
type Eigenpair = (Vec<c64>, f64, usize);

/// The smallest eigenpair of `A z = lambda M z` on the whole mesh with the factor of
/// `A + shift M`, from the fixed pseudo-random start, until a step changes the value by
/// at most `tolerance` times the larger of its magnitude and `floor` (and, for the
/// `vector`, its residual is at most `sqrt(tolerance)` times the value), or after
/// `max` solves: Rayleigh-Ritz on a Krylov space (`linalg::lanczos`) with a
/// direct factor, the preconditioned Davidson method
/// ([`lanczos::smallest_eigenpair_preconditioned`]) with multigrid. Preconditioned
/// inverse iteration, which it replaces, keeps one vector: it stalled on the vector
/// (over 200 V-cycles on the bunny subdivided once against Davidson's 30), and its
/// estimates of `lambda_1` stopped 2.8% high on the bunny against Davidson's 0.6% in
/// as many V-cycles (5). Returns the vector (`z^H M z = 1`), its value (never below
/// the eigenvalue) and the solves taken, and the factor, for the caller to reuse or
/// to [`recycle`](Connection::recycle) (`None` where the multigrid hierarchy was
/// built from the floored weights, see [`Connection::preconditioner`]).
pub(crate) fn smallest_eigenpair(
    mesh: &TriMesh,
    system: &Connection,
    shift: f64,
    max: usize,
    tolerance: f64,
    floor: f64,
    vector: bool,
) -> Result<(Eigenpair, Option<Factor>), LineFieldError> {
    let n = system.len();
    let extra: Vec<f64> = system.mass.iter().map(|m| shift * m).collect();
    let identity: Vec<usize> = (0..n).collect();
    let (mut factor, exact) = if system.multigrid {
        let (amg, exact) = system.preconditioner(mesh, &extra)?;
        (Factor::Multigrid(amg), exact)
    } else {
        (system.factor(mesh, &extra, &identity, n)?, true)
    };
    let options = stopping_rule(max, tolerance, floor, vector, KRYLOV_BASIS);
    let found = match &mut factor {
        Factor::Direct(_) => lanczos::smallest_eigenpair(
            &system.mass,
            start_vector(n),
            options,
            |x| {
                x.iter_mut().zip(&system.mass).for_each(|(z, m)| *z *= *m);
                factor.solve(x)
            },
            |x| system.apply(x),
        ),
        Factor::Multigrid(amg) => davidson(system, amg, max, tolerance, floor.max(shift), vector),
    }
    .map(|(value, x, solves)| (x, value, solves));
    // A hierarchy of the floored system is no factor of this one: no caller reuses it.
    Ok((found?, exact.then_some(factor)))
}
