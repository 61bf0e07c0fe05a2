//! The smallest eigenpair of the connection Laplacian `A z = lambda M z` for the
//! line-field solvers of [`design`](super::design): the smoothest field (its vector)
//! and the estimate of `lambda_1` behind the smoothness shift (its value). With a
//! direct factor: Rayleigh-Ritz on a Krylov space ([`lanczos`](super::lanczos)); with
//! multigrid: Rayleigh-Ritz on a space grown by preconditioned residuals (Davidson)
//! for the vector, preconditioned inverse iteration for the value. All start from one
//! fixed pseudo-random vector and sum in a fixed order, so results are deterministic.

use faer::c64;

use super::connection::{Connection, Factor};
use super::design::{LAMBDA_ITERATIONS, LAMBDA_TOLERANCE};
use super::lanczos;
use super::line_field::LineFieldError;
use crate::linalg::Amg;
use crate::mesh::TriMesh;

/// A fixed pseudo-random value in `[-1, 1)` for index `i` (SplitMix64 finaliser).
pub(crate) fn start_value(i: u64) -> f64 {
    let mut z = i.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Preconditioned inverse iteration (Knyazev and Neymeyr 2003) for the smallest
/// eigenpair of `A z = lambda M z` with the hierarchy `amg` of `A + shift M`: from
/// `x`, each step subtracts a V-cycle of the eigen-residual `A x - rho M x` and
/// `M`-normalises, until the Rayleigh quotient changes by at most `tolerance` times
/// its value (or `shift`) or after `max` steps. Returns the iterate (`z^H M z = 1`)
/// and the steps taken.
fn inverse_iteration(
    system: &Connection,
    amg: &Amg<c64>,
    mut x: Vec<c64>,
    max: usize,
    tolerance: f64,
    shift: f64,
) -> Result<(Vec<c64>, usize), LineFieldError> {
    let normalise = |x: &mut Vec<c64>| -> Result<(), LineFieldError> {
        let norm2 = system.mass_norm2(x);
        if !(norm2 > 0.0 && norm2.is_finite()) {
            return Err(LineFieldError::Factorization {
                stage: "solve (zero iterate)",
            });
        }
        let scale = 1.0 / norm2.sqrt();
        x.iter_mut().for_each(|z| *z *= scale);
        Ok(())
    };
    normalise(&mut x)?;
    let mut previous = f64::INFINITY;
    let mut iterations = 0;
    let mut work = amg.workspace();
    let mut step = vec![c64::new(0.0, 0.0); x.len()];
    for _ in 0..max {
        let rho = system.energy(&x);
        let mut residual = system.apply(&x);
        for ((r, z), m) in residual.iter_mut().zip(&x).zip(&system.mass) {
            *r -= *z * (rho * m);
        }
        amg.apply(&residual, &mut step, &mut work);
        for (z, s) in x.iter_mut().zip(&step) {
            *z -= *s;
        }
        normalise(&mut x)?;
        iterations += 1;
        let rayleigh = system.energy(&x);
        let settled = (rayleigh - previous).abs() <= tolerance * rayleigh.abs().max(shift);
        previous = rayleigh;
        if settled {
            break;
        }
    }
    Ok((x, iterations))
}

/// An estimate from above of the smallest eigenvalue `lambda_1` of `A z = lambda M z`,
/// to [`LAMBDA_TOLERANCE`] in at most [`LAMBDA_ITERATIONS`] solves (see
/// [`smallest_eigenpair`]), and with multigrid the hierarchy of `A + shift M` it
/// built, for a caller whose next system differs from it by the diagonal only.
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
        Factor::Multigrid(amg) => (value, Some(amg)),
        direct => {
            system.recycle(direct);
            (value, None)
        }
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
/// `max` solves: Rayleigh-Ritz on a Krylov space ([`lanczos`](super::lanczos)) with a
/// direct factor. With multigrid, the vector comes from the preconditioned Davidson
/// method ([`lanczos::smallest_eigenpair_preconditioned`]), and the value alone from
/// preconditioned inverse iteration: it settles to [`LAMBDA_TOLERANCE`] in as few
/// V-cycles (8 against Davidson's 7 at 1.1M faces) with two vectors of memory, where
/// for the vector's 1e-8 it stalled (over 200 V-cycles on the bunny subdivided once,
/// against Davidson's 30). Returns the vector (`z^H M z = 1`), its value (never below
/// the eigenvalue) and the solves taken, and the factor, for the caller to reuse or
/// to [`recycle`](Connection::recycle).
pub(crate) fn smallest_eigenpair(
    mesh: &TriMesh,
    system: &Connection,
    shift: f64,
    max: usize,
    tolerance: f64,
    floor: f64,
    vector: bool,
) -> Result<(Eigenpair, Factor), LineFieldError> {
    let n = system.len();
    let extra: Vec<f64> = system.mass.iter().map(|m| shift * m).collect();
    let identity: Vec<usize> = (0..n).collect();
    let mut factor = system.factor(mesh, &extra, &identity, n)?;
    let mut options = lanczos::KrylovOptions {
        max_solves: max,
        tolerance,
        floor,
        basis_limit: KRYLOV_BASIS,
        residual: vector.then(|| tolerance.sqrt()),
    };
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
        Factor::Multigrid(amg) if vector => {
            let mut work = amg.workspace();
            options.floor = floor.max(shift);
            options.basis_limit = DAVIDSON_BASIS;
            lanczos::smallest_eigenpair_preconditioned(
                &system.mass,
                start_vector(n),
                options,
                |r, z| amg.apply(r, z, &mut work),
                |x| system.apply(x),
            )
        }
        Factor::Multigrid(amg) => inverse_iteration(
            system,
            amg,
            start_vector(n),
            max,
            tolerance,
            floor.max(shift),
        )
        .map(|(x, solves)| (system.energy(&x), x, solves)),
    }
    .map(|(value, x, solves)| (x, value, solves));
    Ok((found?, factor))
}
