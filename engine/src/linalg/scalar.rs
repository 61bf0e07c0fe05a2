//! The two scalar types of the solvers, real and complex, behind one small trait, and
//! what their matrices multiply ([`Vector`]): the scalar itself, or for real matrices
//! three columns side by side.

use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use faer::c64;
use glam::DVec3;

/// A real (`f64`) or complex (`c64`) number, as the solvers need it.
pub trait Scalar:
    Copy
    + Send
    + Sync
    + PartialEq
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + 'static
{
    /// Zero.
    const ZERO: Self;
    /// The real number `r`.
    fn real(r: f64) -> Self;
    /// The real part.
    fn re(self) -> f64;
    /// The complex conjugate (the number itself when real).
    fn conj(self) -> Self;
    /// `|x|^2`.
    fn abs2(self) -> f64;
    /// `x / |x|`, or 1 for zero.
    fn phase(self) -> Self {
        let a = self.abs2().sqrt();
        if a > 0.0 {
            self.scale(1.0 / a)
        } else {
            Self::real(1.0)
        }
    }
    /// The factor by which the near-null vector passes along a coupling `a_ij` of the
    /// matrix, from `j` to `i`, in the multigrid's aggregates: for complex connection
    /// Laplacians `phase(-a_ij)` (the connection's rotation); for real matrices 1, the
    /// constant, whatever the coupling's sign (a cotangent Laplacian's obtuse corners
    /// make some couplings positive without making the constant less smooth).
    fn transport(coupling: Self) -> Self;
    /// `x * r` for a real `r`.
    fn scale(self, r: f64) -> Self;
    /// Whether both parts are finite.
    fn is_finite(self) -> bool;
}

impl Scalar for f64 {
    const ZERO: Self = 0.0;
    fn real(r: f64) -> Self {
        r
    }
    fn re(self) -> f64 {
        self
    }
    fn conj(self) -> Self {
        self
    }
    fn abs2(self) -> f64 {
        self * self
    }
    fn transport(_coupling: Self) -> Self {
        1.0
    }
    fn scale(self, r: f64) -> Self {
        self * r
    }
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

impl Scalar for c64 {
    const ZERO: Self = c64::new(0.0, 0.0);
    fn real(r: f64) -> Self {
        c64::new(r, 0.0)
    }
    fn re(self) -> f64 {
        self.re
    }
    fn conj(self) -> Self {
        c64::new(self.re, -self.im)
    }
    fn abs2(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    fn transport(coupling: Self) -> Self {
        (-coupling).phase()
    }
    fn scale(self, r: f64) -> Self {
        c64::new(self.re * r, self.im * r)
    }
    fn is_finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
}

/// One entry of the vectors a matrix over `S` multiplies: `S` itself, or for a real
/// matrix a [`DVec3`], three right-hand sides at once, so that a product or a smoothing
/// sweep reads the matrix once for all three. Each column gets exactly the operations,
/// in the same order, that it would get alone.
pub trait Vector<S>:
    Copy + Send + Sync + Add<Output = Self> + Sub<Output = Self> + AddAssign + SubAssign + 'static
{
    /// Zero.
    fn zero() -> Self;
    /// The entry multiplied by the matrix value `s`: `s x`.
    fn times(s: S, x: Self) -> Self;
    /// `x r` for a real `r`.
    fn scaled(self, r: f64) -> Self;
}

impl<S: Scalar> Vector<S> for S {
    fn zero() -> Self {
        S::ZERO
    }
    fn times(s: S, x: Self) -> Self {
        s * x
    }
    fn scaled(self, r: f64) -> Self {
        self.scale(r)
    }
}

impl Vector<f64> for DVec3 {
    fn zero() -> Self {
        DVec3::ZERO
    }
    fn times(s: f64, x: Self) -> Self {
        DVec3::new(s * x.x, s * x.y, s * x.z)
    }
    fn scaled(self, r: f64) -> Self {
        DVec3::new(self.x * r, self.y * r, self.z * r)
    }
}

/// `sum conj(x_i) y_i`.
pub fn dot<S: Scalar>(x: &[S], y: &[S]) -> S {
    x.iter()
        .zip(y)
        .fold(S::ZERO, |acc, (a, b)| acc + a.conj() * *b)
}

/// `sum |x_i|^2`.
pub fn norm2<S: Scalar>(x: &[S]) -> f64 {
    x.iter().map(|v| v.abs2()).sum()
}
