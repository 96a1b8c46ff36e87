//! The naive `f64` variant of the predicates (cargo feature `naive-f64`; never a default,
//! used only by `vcx bench stability` to measure what exactness buys and costs).
//!
//! With the feature on, the leading determinant of every predicate in [`super::predicates`]
//! and [`super::sos`] is evaluated as a user would write it: coordinates converted to
//! `f64`, differences, products and the sum in `f64` (no fused multiply-add: Rust never
//! contracts), and its sign taken. Only when that value is exactly `0.0` does the
//! predicate fall through to the same Simulation of Simplicity as the exact code, so the
//! two variants differ by rounding only.
//!
//! The callers pass integer coordinate differences: every coordinate is an integer of at
//! most 2⁵² in magnitude (query grid, or a direction), so it and its difference with another
//! (≤ 2⁵³) are exact in `f64` and converting the integer difference is the same as
//! subtracting the converted coordinates. Rounding starts at the products (> 2⁵³).

use super::Sign;

/// An integer of magnitude ≤ 2⁵³ (a coordinate difference) as `f64`: exact. Goes through
/// `i64` because that conversion is one instruction where `i128 → f64` is a library call.
#[inline]
fn f(v: i128) -> f64 {
    v as i64 as f64
}

/// The sign of a finite `f64`; `0.0` and `-0.0` are `Zero`.
#[inline]
fn sign(v: f64) -> Sign {
    if v > 0.0 {
        Sign::Positive
    } else if v < 0.0 {
        Sign::Negative
    } else {
        Sign::Zero
    }
}

/// Sign of `ux·vy − uy·vx`, in `f64`.
#[inline]
pub(crate) fn cross(ux: i128, uy: i128, vx: i128, vy: i128) -> Sign {
    sign(f(ux) * f(vy) - f(uy) * f(vx))
}

/// Sign of `wx·ux + wy·uy`, in `f64`.
#[inline]
pub(crate) fn dot(wx: i128, wy: i128, ux: i128, uy: i128) -> Sign {
    sign(f(wx) * f(ux) + f(wy) * f(uy))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_on_small_values_and_rounds_on_large_ones() {
        assert_eq!(cross(2, 3, 4, 6), Sign::Zero);
        assert_eq!(cross(1, 0, 0, 1), Sign::Positive);
        assert_eq!(dot(1, 1, -1, 2), Sign::Positive);
        // (2²⁷ + 1)(2²⁷ − 1) − 2²⁷·2²⁷ = −1, lost in the rounding of the first product.
        let a = 1i128 << 27;
        assert_eq!(cross(a + 1, a, a, a - 1), Sign::Zero);
    }
}
