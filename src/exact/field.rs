//! The prime field GF(p), p = 2^61 − 1 (a Mersenne prime): [`Fp`].
//!
//! Elements are `u64` values kept reduced in `[0, p)`. A product of two elements is below
//! 2^122 and folds back with the Mersenne identity 2^61 ≡ 1 (mod p): `x mod p` is
//! `(x & p) + (x >> 61)` up to one final subtraction, so multiplication is one `u128`
//! product, two shifts and an add.

use crate::rng::SplitMix64;
use std::fmt;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// The modulus p = 2^61 − 1.
pub const P: u64 = (1 << 61) - 1;

/// An element of GF(2^61 − 1), stored reduced (`0 ≤ value < p`).
///
/// Implements the field operations (`+ - * /`, negation, the assigning forms), [`Fp::inv`],
/// and the traits nalgebra needs for `DMatrix<Fp>` products, sums, transposes and views
/// (`Scalar`, `num_traits::Zero`, `num_traits::One`).
#[derive(Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Fp(u64);

/// Reduce `x < 2^122` (a product of two reduced elements, or a sum of such) modulo p.
#[inline(always)]
fn reduce128(x: u128) -> u64 {
    // x = hi·2^61 + lo ≡ hi + lo; hi < 2^61 for x < 2^122.
    let lo = (x as u64) & P;
    let hi = (x >> 61) as u64;
    let s = lo + hi;
    if s >= P { s - P } else { s }
}

impl Fp {
    /// Zero.
    pub const ZERO: Fp = Fp(0);
    /// One.
    pub const ONE: Fp = Fp(1);

    /// The residue of `x` modulo p.
    #[inline]
    pub const fn from_u64(x: u64) -> Fp {
        // x = hi·2^61 + lo with hi < 8: one fold, then at most one subtraction.
        let s = (x & P) + (x >> 61);
        Fp(if s >= P { s - P } else { s })
    }

    /// The residue of `x` modulo p (negative values map to p − |x| mod p).
    #[inline]
    pub const fn from_i64(x: i64) -> Fp {
        let m = Fp::from_u64(x.unsigned_abs());
        if x < 0 { m.neg_const() } else { m }
    }

    /// The reduced representative in `[0, p)`.
    #[inline]
    pub const fn value(self) -> u64 {
        self.0
    }

    /// Whether this is the zero element.
    #[inline]
    pub const fn is_zero(self) -> bool {
        self.0 == 0
    }

    #[inline]
    const fn neg_const(self) -> Fp {
        if self.0 == 0 { self } else { Fp(P - self.0) }
    }

    /// The representative of least absolute value as a signed integer, in `(−p/2, p/2]`
    /// (useful to print small integers and to test).
    pub fn to_i64(self) -> i64 {
        if self.0 > P / 2 {
            -((P - self.0) as i64)
        } else {
            self.0 as i64
        }
    }

    /// `self^e` by square and multiply.
    pub fn pow(self, mut e: u64) -> Fp {
        let mut base = self;
        let mut acc = Fp::ONE;
        while e > 0 {
            if e & 1 == 1 {
                acc *= base;
            }
            base *= base;
            e >>= 1;
        }
        acc
    }

    /// The multiplicative inverse, `self^(p−2)` (Fermat). The inverse of zero does not
    /// exist; this returns zero for it (never panics), so callers invert only pivots they
    /// know to be nonzero.
    pub fn inv(self) -> Fp {
        self.pow(P - 2)
    }

    /// A uniformly random element (zero included): 61 bits of the generator, rejecting the
    /// single value p.
    pub fn random(rng: &mut SplitMix64) -> Fp {
        loop {
            let v = rng.next_u64() >> 3;
            if v < P {
                return Fp(v);
            }
        }
    }

    /// A uniformly random nonzero element.
    pub fn random_nonzero(rng: &mut SplitMix64) -> Fp {
        loop {
            let v = Fp::random(rng);
            if !v.is_zero() {
                return v;
            }
        }
    }
}

impl fmt::Debug for Fp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.to_i64())
    }
}

impl fmt::Display for Fp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.to_i64())
    }
}

impl From<u64> for Fp {
    fn from(x: u64) -> Fp {
        Fp::from_u64(x)
    }
}

impl From<i64> for Fp {
    fn from(x: i64) -> Fp {
        Fp::from_i64(x)
    }
}

impl Add for Fp {
    type Output = Fp;
    #[inline(always)]
    fn add(self, rhs: Fp) -> Fp {
        let s = self.0 + rhs.0;
        Fp(if s >= P { s - P } else { s })
    }
}

impl Sub for Fp {
    type Output = Fp;
    #[inline(always)]
    fn sub(self, rhs: Fp) -> Fp {
        Fp(if self.0 >= rhs.0 {
            self.0 - rhs.0
        } else {
            self.0 + P - rhs.0
        })
    }
}

impl Mul for Fp {
    type Output = Fp;
    #[inline(always)]
    fn mul(self, rhs: Fp) -> Fp {
        Fp(reduce128(self.0 as u128 * rhs.0 as u128))
    }
}

impl Div for Fp {
    type Output = Fp;
    /// Multiplication by the inverse (division by zero gives zero, see [`Fp::inv`]).
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn div(self, rhs: Fp) -> Fp {
        self * rhs.inv()
    }
}

impl Neg for Fp {
    type Output = Fp;
    #[inline(always)]
    fn neg(self) -> Fp {
        self.neg_const()
    }
}

impl AddAssign for Fp {
    #[inline(always)]
    fn add_assign(&mut self, rhs: Fp) {
        *self = *self + rhs;
    }
}

impl SubAssign for Fp {
    #[inline(always)]
    fn sub_assign(&mut self, rhs: Fp) {
        *self = *self - rhs;
    }
}

impl MulAssign for Fp {
    #[inline(always)]
    fn mul_assign(&mut self, rhs: Fp) {
        *self = *self * rhs;
    }
}

impl DivAssign for Fp {
    fn div_assign(&mut self, rhs: Fp) {
        *self = *self / rhs;
    }
}

impl std::iter::Sum for Fp {
    fn sum<I: Iterator<Item = Fp>>(iter: I) -> Fp {
        iter.fold(Fp::ZERO, |a, b| a + b)
    }
}

impl num_traits::Zero for Fp {
    fn zero() -> Fp {
        Fp::ZERO
    }
    fn is_zero(&self) -> bool {
        self.0 == 0
    }
}

impl num_traits::One for Fp {
    fn one() -> Fp {
        Fp::ONE
    }
}

/// `dst[i] -= f · src[i]` over two equally long slices (the elimination kernel).
#[inline]
pub(crate) fn axpy_sub(dst: &mut [Fp], f: Fp, src: &[Fp]) {
    let f = f.0 as u128;
    for (d, s) in dst.iter_mut().zip(src) {
        let prod = reduce128(f * s.0 as u128);
        let v = d.0;
        d.0 = if v >= prod { v - prod } else { v + P - prod };
    }
}

/// `v[i] *= f` over a slice.
#[inline]
pub(crate) fn scale(v: &mut [Fp], f: Fp) {
    for x in v {
        *x *= f;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    #[test]
    fn reduction_and_signs() {
        assert_eq!(Fp::from_u64(P), Fp::ZERO);
        assert_eq!(Fp::from_u64(P + 5), Fp::from_u64(5));
        assert_eq!(Fp::from_u64(u64::MAX), Fp::from_u64(u64::MAX % P));
        assert_eq!(Fp::from_i64(-1).value(), P - 1);
        assert_eq!(Fp::from_i64(i64::MIN), Fp::from_u64(P - (1u64 << 63) % P));
        assert_eq!(Fp::from_i64(-7).to_i64(), -7);
        assert_eq!(Fp::from_i64(3) - Fp::from_i64(5), Fp::from_i64(-2));
        assert_eq!(-Fp::ZERO, Fp::ZERO);
        assert_eq!(Fp::from_i64(-3) * Fp::from_i64(4), Fp::from_i64(-12));
    }

    #[test]
    fn products_match_u128_remainder() {
        let mut rng = SplitMix64::new(1);
        for _ in 0..10_000 {
            let (a, b) = (Fp::random(&mut rng), Fp::random(&mut rng));
            let want = ((a.value() as u128 * b.value() as u128) % P as u128) as u64;
            assert_eq!((a * b).value(), want);
            assert_eq!(((a + b) - b), a);
        }
        let m = Fp::from_u64(P - 1);
        assert_eq!(m * m, Fp::ONE);
    }

    #[test]
    fn inverses() {
        let mut rng = SplitMix64::new(2);
        for _ in 0..1000 {
            let a = Fp::random_nonzero(&mut rng);
            assert!(!a.is_zero());
            assert_eq!(a * a.inv(), Fp::ONE);
            assert_eq!(Fp::ONE / a, a.inv());
        }
        assert_eq!(Fp::ZERO.inv(), Fp::ZERO);
    }

    #[test]
    fn random_is_reduced_and_deterministic() {
        let mut r1 = SplitMix64::new(9);
        let mut r2 = SplitMix64::new(9);
        for _ in 0..1000 {
            let a = Fp::random(&mut r1);
            assert!(a.value() < P);
            assert_eq!(a, Fp::random(&mut r2));
        }
    }

    #[test]
    fn kernels() {
        let mut rng = SplitMix64::new(3);
        let a: Vec<Fp> = (0..7).map(|_| Fp::random(&mut rng)).collect();
        let mut b: Vec<Fp> = (0..7).map(|_| Fp::random(&mut rng)).collect();
        let f = Fp::random(&mut rng);
        let want: Vec<Fp> = b.iter().zip(&a).map(|(x, y)| *x - f * *y).collect();
        axpy_sub(&mut b, f, &a);
        assert_eq!(b, want);
        scale(&mut b, f);
        assert_eq!(b[0], want[0] * f);
    }

    #[test]
    fn nalgebra_matrices() {
        let a = DMatrix::from_fn(2, 3, |i, j| Fp::from_i64(i as i64 - j as i64));
        let b = DMatrix::from_fn(3, 2, |i, j| Fp::from_i64((i * j) as i64 + 1));
        let c = &a * &b;
        // Row 0 of a: [0, -1, -2]; column 1 of b: [1, 2, 3].
        assert_eq!(c[(0, 1)], Fp::from_i64(-8));
        let s = &a + &a - &a;
        assert_eq!(s, a);
        assert_eq!(a.transpose()[(2, 0)], Fp::from_i64(-2));
        assert_eq!(a.view((0, 1), (2, 2))[(1, 1)], Fp::from_i64(-1));
        assert_eq!(DMatrix::<Fp>::identity(2, 2) * &a, a);
    }
}
