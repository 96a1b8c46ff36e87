//! Exact predicates. Every one is the sign of a degree-2 polynomial in coordinate
//! differences (DESIGN.md §2); they may return [`Sign::Zero`] on degenerate input.
//! The perturbed, never-zero versions used by construction and walking live in
//! [`crate::geom::sos`].
//!
//! Scene-only predicates run in `i64` on raw grid coordinates; predicates with a query
//! point lift scene points to the query grid (exact shift by 16 bits) and run in `i128`.

use core::cmp::Ordering;

use super::{Point, QueryPoint, Sign};

/// A direction vector with integer components, `|x|, |y| ≤` [`super::point::MAX_ABS_DIRECTION`].
/// Only its direction matters; it is never perturbed.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Direction {
    /// x component.
    pub x: i64,
    /// y component.
    pub y: i64,
}

impl Direction {
    /// A direction; `None` for the zero vector or components beyond the bound.
    pub const fn new(x: i64, y: i64) -> Option<Direction> {
        let m = super::point::MAX_ABS_DIRECTION as u64;
        if (x == 0 && y == 0) || x.unsigned_abs() > m || y.unsigned_abs() > m {
            None
        } else {
            Some(Direction { x, y })
        }
    }
}

/// Orientation of `r` with respect to the directed line `p → q`:
/// `Positive` if `r` is to the left (counter-clockwise turn `p, q, r`), `Negative` if to
/// the right, `Zero` if the three points are collinear.
///
/// Bit budget: differences ≤ 2³¹ − 2 in magnitude, products < 2⁶², determinant < 2⁶³:
/// exact in `i64`.
#[inline]
pub fn orient(p: Point, q: Point, r: Point) -> Sign {
    #[cfg(feature = "naive-f64")]
    {
        let d = |a: i32, b: i32| i128::from(a) - i128::from(b);
        super::naive::cross(
            d(q.x(), p.x()),
            d(q.y(), p.y()),
            d(r.x(), p.x()),
            d(r.y(), p.y()),
        )
    }
    #[cfg(not(feature = "naive-f64"))]
    Sign::of_i64(orient_det(p, q, r))
}

/// The determinant behind [`orient`]: twice the signed area of the triangle `p, q, r`,
/// in square grid units. Same bit budget as [`orient`].
#[inline]
pub fn orient_det(p: Point, q: Point, r: Point) -> i64 {
    cross_i64(
        q.x() as i64 - p.x() as i64,
        q.y() as i64 - p.y() as i64,
        r.x() as i64 - p.x() as i64,
        r.y() as i64 - p.y() as i64,
    )
}

#[inline]
fn cross_i64(ux: i64, uy: i64, vx: i64, vy: i64) -> i64 {
    ux * vy - uy * vx
}

/// Whether the vector `(x, y)` points into the half-open upper half-plane `[0, π)`.
#[inline]
pub(crate) fn upper_half(x: i128, y: i128) -> bool {
    y > 0 || (y == 0 && x > 0)
}

/// Order of the directions of `q1 − p1` and `q2 − p2` on the circle, by angle in
/// `[0, 2π)` counter-clockwise from +x (half-plane first, then the cross product).
/// `Equal` for parallel, same-sense vectors.
///
/// Bit budget: as [`orient`] (cross of two differences, `i64`). Zero vectors compare as
/// angle 0's half-plane predecessor and must not be passed.
pub fn direction_cmp(p1: Point, q1: Point, p2: Point, q2: Point) -> Ordering {
    let (ux, uy) = (q1.x() as i64 - p1.x() as i64, q1.y() as i64 - p1.y() as i64);
    let (vx, vy) = (q2.x() as i64 - p2.x() as i64, q2.y() as i64 - p2.y() as i64);
    let hu = upper_half(ux as i128, uy as i128);
    let hv = upper_half(vx as i128, vy as i128);
    if hu != hv {
        return if hu {
            Ordering::Less
        } else {
            Ordering::Greater
        };
    }
    #[cfg(feature = "naive-f64")]
    {
        super::naive::cross(ux as i128, uy as i128, vx as i128, vy as i128)
            .flip()
            .to_i8()
            .cmp(&0)
    }
    #[cfg(not(feature = "naive-f64"))]
    0.cmp(&cross_i64(ux, uy, vx, vy))
}

/// Order of `p` and `r` along a line of direction `d`: sign of `dot(d, r − p)`;
/// `Positive` if `r` comes after `p`.
///
/// Bit budget: query scale; `|d| ≤ 2⁵²`, differences ≤ 2⁵³: products ≤ 2¹⁰⁵, exact in `i128`.
pub fn along(d: Direction, p: QueryPoint, r: QueryPoint) -> Sign {
    let dx = r.x() as i128 - p.x() as i128;
    let dy = r.y() as i128 - p.y() as i128;
    #[cfg(feature = "naive-f64")]
    return super::naive::dot(d.x as i128, d.y as i128, dx, dy);
    #[cfg(not(feature = "naive-f64"))]
    Sign::of_i128(d.x as i128 * dx + d.y as i128 * dy)
}

/// Offset order of the two parallel lines of direction `d` through `r` and `s`:
/// sign of `cross(d, s − r)`; `Positive` if the line through `s` lies to the left of the
/// line through `r`.
///
/// Bit budget: as [`along`].
pub fn parallel_offset(d: Direction, r: QueryPoint, s: QueryPoint) -> Sign {
    let dx = s.x() as i128 - r.x() as i128;
    let dy = s.y() as i128 - r.y() as i128;
    #[cfg(feature = "naive-f64")]
    return super::naive::cross(d.x as i128, d.y as i128, dx, dy);
    #[cfg(not(feature = "naive-f64"))]
    Sign::of_i128(d.x as i128 * dy - d.y as i128 * dx)
}

/// Orientation of the query point `q` with respect to the directed line `a → b` through
/// two scene points; conventions as [`orient`].
///
/// Bit budget: scene points lifted to the query grid (≤ 2⁴⁶), query ≤ 2⁵²: differences
/// ≤ 2⁵³, determinant ≤ 2¹⁰⁷, exact in `i128`.
pub fn orient_query(a: Point, b: Point, q: QueryPoint) -> Sign {
    let (a, b) = (a.to_query(), b.to_query());
    let ux = b.x() as i128 - a.x() as i128;
    let uy = b.y() as i128 - a.y() as i128;
    let vx = q.x() as i128 - a.x() as i128;
    let vy = q.y() as i128 - a.y() as i128;
    #[cfg(feature = "naive-f64")]
    return super::naive::cross(ux, uy, vx, vy);
    #[cfg(not(feature = "naive-f64"))]
    Sign::of_i128(ux * vy - uy * vx)
}

/// Point against object along a line: the line through the query point `q` with direction
/// `d` crosses the edge `a → b` of a counter-clockwise convex object. Returns `Positive` if
/// the object lies ahead of `q` (along `d`), `Negative` if behind, `Zero` if undecided
/// (`q` on the edge's line or `d` parallel to the edge).
///
/// This is `orient(a, b, q) · cross(d, b − a)`: entering through `ab` (`cross(d, b−a) < 0`)
/// the object is ahead iff `q` is outside `ab`; leaving through it, iff `q` is inside.
/// Bit budget: the product of two signs of [`orient_query`]-sized determinants.
pub fn object_ahead(q: QueryPoint, d: Direction, a: Point, b: Point) -> Sign {
    let ex = b.x() as i128 - a.x() as i128;
    let ey = b.y() as i128 - a.y() as i128;
    #[cfg(feature = "naive-f64")]
    let crossing = super::naive::cross(d.x as i128, d.y as i128, ex, ey);
    #[cfg(not(feature = "naive-f64"))]
    let crossing = Sign::of_i128(d.x as i128 * ey - d.y as i128 * ex);
    orient_query(a, b, q).times(crossing)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: i32, y: i32) -> Point {
        Point::from_raw(x, y).unwrap()
    }

    #[test]
    fn orient_basics_and_extremes() {
        assert_eq!(orient(p(0, 0), p(1, 0), p(0, 1)), Sign::Positive);
        assert_eq!(orient(p(0, 0), p(0, 1), p(1, 0)), Sign::Negative);
        assert_eq!(orient(p(0, 0), p(1, 1), p(2, 2)), Sign::Zero);
        let m = super::super::point::MAX_ABS_RAW;
        // The largest determinant: a triangle spanning the whole range.
        let d = orient_det(p(-m, -m), p(m, -m), p(m, m));
        assert_eq!(d as i128, (2 * m as i128) * (2 * m as i128));
        assert_eq!(orient(p(-m, -m), p(m, m), p(m, -m)), Sign::Negative);
        assert_eq!(orient(p(-m, -m), p(m, m), p(m - 1, m - 1)), Sign::Zero);
    }

    #[test]
    fn direction_order_on_the_circle() {
        let o = p(0, 0);
        let dirs = [
            p(1, 0),
            p(1, 1),
            p(0, 1),
            p(-1, 1),
            p(-1, 0),
            p(-1, -1),
            p(0, -1),
            p(1, -1),
        ];
        for (i, a) in dirs.iter().enumerate() {
            for (j, b) in dirs.iter().enumerate() {
                assert_eq!(direction_cmp(o, *a, o, *b), i.cmp(&j), "{i} {j}");
            }
        }
        assert_eq!(direction_cmp(o, p(2, 2), p(5, 5), p(6, 6)), Ordering::Equal);
    }

    #[test]
    fn object_ahead_of_query() {
        // Unit square (one grid unit), counter-clockwise; q to its left, looking +x.
        let left = (p(0, 1), p(0, 0)); // left edge, downward in ccw order
        let right = (p(1, 0), p(1, 1));
        let dx = Direction::new(1, 0).unwrap();
        let q = QueryPoint::from_raw(-5 << 16, 1 << 15).unwrap();
        // Entering through the left edge: ahead; looking back: behind.
        assert_eq!(object_ahead(q, dx, left.0, left.1), Sign::Positive);
        assert_eq!(
            object_ahead(q, Direction::new(-1, 0).unwrap(), left.0, left.1),
            Sign::Negative
        );
        // Leaving through the right edge gives the same answer.
        assert_eq!(object_ahead(q, dx, right.0, right.1), Sign::Positive);
        // q beyond the square: behind, from either edge.
        let q2 = QueryPoint::from_raw(7 << 16, 1 << 15).unwrap();
        assert_eq!(object_ahead(q2, dx, left.0, left.1), Sign::Negative);
        assert_eq!(object_ahead(q2, dx, right.0, right.1), Sign::Negative);
        // A line along the bottom edge is undecided exactly.
        let q3 = p(-5, 0).to_query();
        assert_eq!(object_ahead(q3, dx, p(0, 0), p(1, 0)), Sign::Zero);
    }
}
