//! Exact fixed-point geometry: grid points, degree-2 integer predicates and the
//! symbolic perturbation that breaks their ties (DESIGN.md §2).
//!
//! * [`point`]: scene points on the 2⁻¹⁶ grid, query points on the 2⁻³² grid.
//! * [`predicates`]: exact signs (may be zero), each with its bit budget.
//! * [`sos`]: Simulation of Simplicity — the same predicates, never zero.
//! * `naive` (feature `naive-f64` only): the same predicates with the leading determinant
//!   rounded in `f64`, for the stability benchmark; never for real use.

pub mod point;
pub mod predicates;
pub mod sos;
pub(crate) mod wide;

#[cfg(feature = "naive-f64")]
mod naive;

/// Whether this build decides with the naive `f64` predicates (feature `naive-f64`, for the
/// stability benchmark only) instead of the exact ones.
pub const NAIVE_F64: bool = cfg!(feature = "naive-f64");

pub use point::{CoordinateError, Point, QueryPoint};

/// The sign of a predicate.
///
/// Exact predicates may return [`Sign::Zero`]; the perturbed ones in [`sos`] return
/// `Zero` only for inputs that are degenerate even symbolically (documented per function).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Sign {
    /// Strictly negative.
    Negative,
    /// Exactly zero.
    Zero,
    /// Strictly positive.
    Positive,
}

impl Sign {
    /// The sign of an integer.
    #[inline]
    pub fn of_i64(v: i64) -> Sign {
        match v {
            0 => Sign::Zero,
            v if v > 0 => Sign::Positive,
            _ => Sign::Negative,
        }
    }

    /// The sign of a wide integer.
    #[inline]
    pub fn of_i128(v: i128) -> Sign {
        match v {
            0 => Sign::Zero,
            v if v > 0 => Sign::Positive,
            _ => Sign::Negative,
        }
    }

    /// The opposite sign.
    #[inline]
    #[must_use]
    pub fn flip(self) -> Sign {
        match self {
            Sign::Negative => Sign::Positive,
            Sign::Zero => Sign::Zero,
            Sign::Positive => Sign::Negative,
        }
    }

    /// The sign of a product.
    #[inline]
    #[must_use]
    pub fn times(self, other: Sign) -> Sign {
        match (self, other) {
            (Sign::Zero, _) | (_, Sign::Zero) => Sign::Zero,
            (a, b) if a == b => Sign::Positive,
            _ => Sign::Negative,
        }
    }

    /// `-1`, `0` or `1`.
    #[inline]
    pub fn to_i8(self) -> i8 {
        match self {
            Sign::Negative => -1,
            Sign::Zero => 0,
            Sign::Positive => 1,
        }
    }
}

/// Marsaglia's xorshift64 from `seed`: the unit tests' reproducible random numbers.
#[cfg(test)]
pub(crate) fn xorshift(mut seed: u64) -> impl FnMut() -> u64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    }
}
