//! Virtual eyes of the ray-tree optics, rounded exactly to the query grid (DESIGN.md §6).
//!
//! Every interaction moves the eye `E` along the normal of an interface line `ab`: with `F`
//! the foot of `E` on the line, the new eye is `E' = F + k·(E − F)` — `k = −1` reflects
//! (mirror), `k = η` enters a refractive object and `k = 1/η` leaves it (the tangent law
//! η₁·tanθ₁ = η₂·tanθ₂, see [`crate::walk`] for its error against Snell's law). The result
//! is rounded to the query grid (2⁻³², nearest, ties away from zero) at once, as the
//! reference does with `round_eyes`; all later predicates are exact for the rounded eye.
//!
//! **Exact rounding in `i128`.** In query units (raw 2⁻³²) let `w = E − a` and `d = b − a`
//! (`d` in scene units, raw 2⁻¹⁶, so `|d|` components `< 2³¹`), `N = |d|² < 2⁶³`,
//! `t = dot(w, d)`. The scale of `d` cancels in `t·d/N`, which is `F − a` in query units:
//!
//! ```text
//! E' = a + (t·d)/N + k·g/N,   g = N·w − t·d   (= N·(E − F), so |g/N| ≤ |w|)
//! ```
//!
//! Bit budget, with `|E| ≤ 2⁵²` and `|a| ≤ 2⁴⁶`: `|w| < 2⁵³`, `|t| < 2⁸⁵`, `|t·d| < 2¹¹⁶`,
//! `|N·w| < 2¹¹⁶`, `|g| < 2¹¹⁷` — all in `i128`. The quotient `k·g/N` with `k = kn/kd`
//! (`|kn|, kd ≤ 2²²`) would not fit as one fraction (`2²² · 2¹¹⁷`), so it is split by
//! quotient and remainder: `t·d = q₁N + r₁`, `g = q₂N + r₂`, `kn·q₂ = q₄·kd + r₄` (Euclidean,
//! `0 ≤ r < divisor`; `|q₁|, |q₂| ≤ |w| + 1 < 2⁵⁴` because they are coordinates of `F − a`
//! and `E − F`, floored), leaving
//!
//! ```text
//! E' = (a + q₁ + q₄) + (r₄·N + r₁·kd + kn·r₂) / (kd·N)
//! ```
//!
//! with a numerator `< 3·2⁸⁵` and a denominator `< 2⁸⁵`; one more Euclidean division and a
//! comparison of twice the remainder with the denominator round it. The second division is
//! none: `g = N·(w − q₁) − r₁`, so `(q₂, r₂)` is `(w − q₁, 0)` if `r₁ = 0`, else
//! `(w − q₁ − 1, N − r₁)`; and `kn·q₂` (`< 2⁷⁶`) mostly fits a 64-bit division (−4 %
//! instructions in the mixed frame). The last quotient is below `2 + kn/kd` (`r₄·N` and
//! `r₁·kd` are each below the denominator), so below 4 for indices below 2: a few
//! comparisons find it; and the numerator's products are of `i64` factors, single widening
//! multiplications (−3.7 % instructions in the mixed frame). The first division (and a
//! mirror's one fraction over `N`) is an `f64` estimate corrected by the exact remainder,
//! not the software `i128` division (−1.8 %). `tests/tests/ray_trees.rs` checks this
//! against big rationals at the extremes of the range.

use crate::geom::point::QUERY_MAX_ABS_RAW;
use crate::geom::{Point, QueryPoint};
#[cfg(feature = "refraction")]
use crate::scene::Eta;

/// Euclidean quotient and remainder by a positive `d`: one division (`div_euclid` and
/// `rem_euclid` are a software `i128` division each).
fn div_rem(x: i128, d: i128) -> (i128, i128) {
    let (q, r) = (x / d, x % d);
    if r < 0 {
        (q - 1, r + d)
    } else {
        (q, r)
    }
}

/// Euclidean [`div_rem`] by a positive `d < 2⁶³` without the software `i128` division: the
/// quotient estimated in `f64` and corrected by the exact remainder (`|q·d| < 2¹²⁵`, and
/// `x − q·d` is within a few `d`: no overflow). The estimate is off by about
/// `|q|·2⁻⁵¹ + 2¹¹/d` units (the low half's rounding is absolute): a step or two for the
/// divisors `N` used here (2³² for an edge one scene unit long) and the coordinates of real
/// scenes, and [`div_rem`] where eight steps do not reach it or past `|q| = 2⁶²`.
#[inline(always)]
fn div_rem_estimated(x: i128, d: i64) -> (i128, i128) {
    // `x` as `f64` from its two 64-bit halves: an estimate, not the rounded value.
    let xf = ((x >> 64) as i64 as f64) * 18_446_744_073_709_551_616.0 + (x as u64 as f64);
    let qf = xf / d as f64;
    // Past 2⁶²: beyond the estimate's range (a NaN, impossible here, would be corrected
    // from 0 and fall back as well).
    if libm::fabs(qf) >= 4_611_686_018_427_387_904.0 {
        return div_rem(x, i128::from(d));
    }
    let d = i128::from(d);
    // Truncated toward zero; the steps below floor it.
    let mut q = i128::from(qf as i64);
    let mut r = x - q * d;
    for _ in 0..8 {
        if r < 0 {
            (q, r) = (q - 1, r + d);
        } else if r >= d {
            (q, r) = (q + 1, r - d);
        } else {
            return (q, r);
        }
    }
    div_rem(x, d)
}

/// Euclidean [`div_rem`] in 64 bits where `x` and `d` fit (a hardware division, the same
/// quotient and remainder), else in 128.
fn div_rem_narrow(x: i128, d: i128) -> (i128, i128) {
    match (i64::try_from(x), i64::try_from(d)) {
        (Ok(x), Ok(d)) => {
            let (q, r) = (x / d, x % d);
            let (q, r) = if r < 0 { (q - 1, r + d) } else { (q, r) };
            (i128::from(q), i128::from(r))
        }
        _ => div_rem(x, d),
    }
}

/// Euclidean [`div_rem`] of `x` by a positive `d` where the quotient is mostly small: in
/// `[0, 4)` by at most three comparisons and subtractions (no software division), else by
/// [`div_rem`].
fn div_rem_small(x: i128, d: i128) -> (i128, i128) {
    // `4·d < 2⁸⁷` for the denominators `kd·N < 2⁸⁵` used here.
    if x < 0 || x >= 4 * d {
        return div_rem(x, d);
    }
    let (mut q, mut r) = (0, x);
    while r >= d {
        (q, r) = (q + 1, r - d);
    }
    (q, r)
}

/// `round(a + td/N + kn·g/(kd·N))` with `g = N·w − td` for one coordinate (see the module
/// documentation). `N < 2⁶³` and `|kn|, kd ≤ 2²²` are `i64`, and so are the remainders
/// below them: their products are single widening multiplications.
fn round_coordinate(a: i128, td: i128, w: i128, n: i64, kn: i64, kd: i64) -> i128 {
    let wide = i128::from;
    // With `kd = 1` and `td + kn·g` in `i128` (a mirror: `kn = −1`, `< 2¹¹⁸`) the value is
    // one fraction over `N`: the same floor and remainder with one division.
    let one = match (kn, kd) {
        // A mirror: `td − g` without the multiplication's overflow check.
        (-1, 1) => td.checked_sub(wide(n) * w - td),
        (_, 1) => wide(kn)
            .checked_mul(wide(n) * w - td)
            .and_then(|x| x.checked_add(td)),
        _ => None,
    };
    let (base, s, den) = match one {
        Some(num) => {
            let (q, s) = div_rem_estimated(num, n);
            (a + q, s, wide(n))
        }
        None => {
            let (q1, r1) = div_rem_estimated(td, n);
            // `0 ≤ r₁ < N < 2⁶³`.
            let r1 = r1 as i64;
            // `g = N·(w − q₁) − r₁`: its quotient and remainder by `N` without a division.
            let (q2, r2) = if r1 == 0 {
                (w - q1, 0)
            } else {
                (w - q1 - 1, n - r1)
            };
            let (q4, r4) = div_rem_narrow(wide(kn) * q2, wide(kd));
            // `0 ≤ r₄ < kd ≤ 2²²`; each product below is `< 2⁸⁵`.
            let r4 = r4 as i64;
            let num = wide(r4) * wide(n) + wide(r1) * wide(kd) + wide(kn) * wide(r2);
            let den = wide(kd) * wide(n);
            // `num / den < 2 + kn/kd`: below 4 for the indices of real materials.
            let (j, s) = div_rem_small(num, den);
            (a + q1 + q4 + j, s, den)
        }
    };
    match (2 * s).cmp(&den) {
        core::cmp::Ordering::Greater => base + 1,
        // Exactly half-way: away from zero.
        core::cmp::Ordering::Equal if base >= 0 => base + 1,
        _ => base,
    }
}

/// The eye `F + (kn/kd)·(E − F)` for the foot `F` of `e` on the line `ab`, rounded to the
/// query grid (nearest, ties away from zero). `None` if `a == b`, `kd ≤ 0`, a factor is
/// beyond `2²²` in magnitude, or the result leaves the query range. Inlined: a mirror's
/// constant factor folds its checks and products away.
#[inline]
pub fn transform_eye(e: QueryPoint, a: Point, b: Point, kn: i64, kd: i64) -> Option<QueryPoint> {
    if kd <= 0 || kd > 1 << 22 || kn.unsigned_abs() > 1 << 22 {
        return None;
    }
    let aq = a.to_query();
    // Differences subtracted in 64 bits (scene coordinates below 2³⁰, query ones at most
    // 2⁵²): the compiler then knows they fit and multiplies them as such.
    let (dx, dy) = (
        i128::from(i64::from(b.x()) - i64::from(a.x())),
        i128::from(i64::from(b.y()) - i64::from(a.y())),
    );
    // `N < 2⁶³`: an `i64`.
    let n = (dx * dx + dy * dy) as i64;
    if n == 0 {
        return None;
    }
    // w in query units; d in scene units. t·d/N is then in query units as well.
    let (wx, wy) = (i128::from(e.x() - aq.x()), i128::from(e.y() - aq.y()));
    let (x, y) = if kd == 1 && (dx == 0 || dy == 0) {
        // An axis-parallel line with an integer factor (a mirror wall): the foot is `e`
        // with one coordinate of `a`, and the new eye lies on the grid — the value the
        // general rounding below gives, without its divisions (`|kn·w| < 2⁷⁵`).
        if dy == 0 {
            (i128::from(e.x()), i128::from(aq.y()) + i128::from(kn) * wy)
        } else {
            (i128::from(aq.x()) + i128::from(kn) * wx, i128::from(e.y()))
        }
    } else {
        let t = wx * dx + wy * dy;
        let (tdx, tdy) = (t * dx, t * dy);
        (
            round_coordinate(i128::from(aq.x()), tdx, wx, n, kn, kd),
            round_coordinate(i128::from(aq.y()), tdy, wy, n, kn, kd),
        )
    };
    let lim = i128::from(QUERY_MAX_ABS_RAW);
    if x.abs() > lim || y.abs() > lim {
        return None;
    }
    QueryPoint::from_raw(x as i64, y as i64)
}

/// The reflection of `e` across the line `ab`, rounded to the query grid.
#[cfg(feature = "mirrors")]
pub fn reflect(e: QueryPoint, a: Point, b: Point) -> Option<QueryPoint> {
    transform_eye(e, a, b, -1, 1)
}

/// The tangent-law eye at the interface `ab`: entering (`F + η(E − F)`) or leaving
/// (`F + (E − F)/η`) an object of index `eta`, rounded to the query grid.
#[cfg(feature = "refraction")]
pub fn refract(e: QueryPoint, a: Point, b: Point, eta: Eta, entering: bool) -> Option<QueryPoint> {
    let (raw, one) = (i64::from(eta.raw()), 1i64 << Eta::FRAC_BITS);
    if entering {
        transform_eye(e, a, b, raw, one)
    } else {
        transform_eye(e, a, b, one, raw)
    }
}

#[cfg(test)]
mod tests {
    use super::{div_rem, div_rem_estimated};

    /// The estimated division is the Euclidean one: at every magnitude of the dividend up
    /// to 2¹¹⁹ and of the divisor up to 2⁶³ (quotients from 0 to past the estimate's range,
    /// where it falls back), near multiples of the divisor (remainders 0 and `d − 1`), and
    /// at the extremes.
    #[test]
    fn estimated_division_is_euclidean() {
        let mut next = crate::geom::xorshift(0x2545_f491_4f6c_dd1d);
        let check = |x: i128, d: i64| {
            assert_eq!(
                div_rem_estimated(x, d),
                div_rem(x, i128::from(d)),
                "{x} / {d}"
            );
        };
        for _ in 0..200_000 {
            let d = (next() >> 1 >> (next() % 63)).max(1) as i64;
            let x = ((i128::from(next()) << 64 | i128::from(next())) >> 9) >> (next() % 119);
            check(x, d);
            // Near a multiple of `d` (a remainder of 0 or `d − 1`), where a quotient off by
            // one shows.
            let q = x / i128::from(d);
            if let Some(m) = q.checked_mul(i128::from(d)) {
                for k in [m - 1, m, m + 1] {
                    if k.unsigned_abs() < 1 << 119 {
                        check(k, d);
                    }
                }
            }
        }
        let max = (1i128 << 119) - 1;
        for x in [0, 1, -1, max, -max, max / 3, -max / 3] {
            for d in [1, 2, 3, (1 << 31) + 1, i64::MAX - 1, i64::MAX] {
                check(x, d);
            }
        }
    }
}
