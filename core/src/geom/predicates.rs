//! Exact predicates. Every one is the sign of a degree-2 polynomial in coordinate
//! differences (DESIGN.md §2); they may return [`Sign::Zero`] on degenerate input.
//! The perturbed, never-zero versions live in [`crate::geom::sos`].

use super::{Point, QueryPoint, Sign};

/// Orientation of `r` with respect to the directed line `p → q`:
/// `Positive` if `r` is to the left (counter-clockwise turn `p, q, r`), `Negative` if to
/// the right, `Zero` if the three points are collinear.
///
/// Bit budget: differences ≤ 2³¹ − 2 in magnitude, products < 2⁶², determinant < 2⁶³:
/// exact in `i64`.
#[inline]
pub fn orient(p: Point, q: Point, r: Point) -> Sign {
    Sign::of_i64(orient_det(p, q, r))
}

/// The determinant behind [`orient`]: twice the signed area of the triangle `p, q, r`.
#[inline]
pub fn orient_det(p: Point, q: Point, r: Point) -> i64 {
    let (px, py) = (p.x() as i64, p.y() as i64);
    let ux = q.x() as i64 - px;
    let uy = q.y() as i64 - py;
    let vx = r.x() as i64 - px;
    let vy = r.y() as i64 - py;
    ux * vy - uy * vx
}
