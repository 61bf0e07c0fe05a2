//! The smallest eigenpair of the connection Laplacian `A z = lambda M z` for the
//! line-field solvers of [`design`](super::design): the smoothest field (its vector)
//! and the estimate of `lambda_1` behind the smoothness shift (its value). With a
//! direct factor: Rayleigh-Ritz on a Krylov space ([`lanczos`](super::lanczos)); with
//! multigrid: preconditioned inverse iteration. Both start from one fixed
//! pseudo-random vector, so results are deterministic.

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

/// Inverse power iteration for the smallest eigenpair of `A z = lambda M z` with the
/// factor `llt` of `A + shift M`, from `x`, `M`-normalised each step, until the
/// Rayleigh quotient changes by at most `tolerance` times its value (or `shift`) or
/// after `max` steps. Returns the iterate (`z^H M z = 1`) and the steps taken.
fn inverse_iteration(
    system: &Connection,
    factor: &mut Factor,
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
    let mut work = match factor {
        Factor::Multigrid(amg) => Some(amg.workspace()),
        Factor::Direct(_) => None,
    };
    let mut step = vec![c64::new(0.0, 0.0); if work.is_some() { x.len() } else { 0 }];
    for _ in 0..max {
        if let (Factor::Multigrid(amg), Some(work)) = (&*factor, &mut work) {
            // Preconditioned inverse iteration (Knyazev and Neymeyr 2003): a V-cycle
            // on the eigen-residual instead of a full solve, since the iteration only
            // needs the direction.
            let rho = system.energy(&x);
            let mut residual = system.apply(&x);
            for ((r, z), m) in residual.iter_mut().zip(&x).zip(&system.mass) {
                *r -= *z * (rho * m);
            }
            amg.apply(&residual, &mut step, work);
            for (z, s) in x.iter_mut().zip(&step) {
                *z -= *s;
            }
        } else {
            for (z, m) in x.iter_mut().zip(&system.mass) {
                *z *= *m;
            }
            factor.solve(&mut x)?;
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
/// at most `tolerance` times the larger of its magnitude and `floor`, or after `max`
/// solves: Rayleigh-Ritz on a Krylov space ([`lanczos`](super::lanczos)) with a direct
/// factor, preconditioned inverse iteration with multigrid. Returns the vector
/// (`z^H M z = 1`), its value (never below the eigenvalue) and the solves taken, and
/// the factor, for the caller to reuse or to [`recycle`](Connection::recycle).
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
    let found = if matches!(factor, Factor::Direct(_)) {
        let options = lanczos::KrylovOptions {
            max_solves: max,
            tolerance,
            floor,
            basis_limit: KRYLOV_BASIS,
            residual: vector.then(|| tolerance.sqrt()),
        };
        lanczos::smallest_eigenpair(
            &system.mass,
            start_vector(n),
            options,
            |x| {
                x.iter_mut().zip(&system.mass).for_each(|(z, m)| *z *= *m);
                factor.solve(x)
            },
            |x| system.apply(x),
        )
        .map(|(value, x, solves)| (x, value, solves))
    } else {
        inverse_iteration(
            system,
            &mut factor,
            start_vector(n),
            max,
            tolerance,
            floor.max(shift),
        )
        .map(|(x, solves)| {
            let value = system.energy(&x);
            (x, value, solves)
        })
    };
    Ok((found?, factor))
}
