//! Simulation of Simplicity (Edelsbrunner & Mücke 1990): a fixed symbolic perturbation
//! that makes every predicate non-zero, so that construction and walking see one
//! consistent scene in general position (DESIGN.md §2).
//!
//! **The perturbation.** Every point carries a *rank*: the query point (viewpoint, virtual
//! viewpoint, ray origin) has rank 0, the scene vertex with global index `i` (its index in
//! [`crate::SceneRef::vertices`]) has rank `i + 1`. A point of rank `r` is moved to
//! `(x + ε^(2^(2r)), y + ε^(2^(2r+1)))` for an infinitesimal `ε > 0`. Direction vectors
//! given by the caller are constants and are not perturbed.
//!
//! Every predicate here is the sign of a polynomial of degree ≤ 2 in the coordinates that is
//! multilinear in the perturbation variables (a cross or dot product of differences), so
//! its perturbed value is `F + Σ ∂F/∂εᵥ·εᵥ + Σ ∂²F/∂εᵤ∂εᵥ·εᵤεᵥ`. Monomials are ordered by
//! their exponent `Σ 2^k`, i.e. by the binary number whose bits are the variables: the sign
//! is that of the first non-zero coefficient in that order. First derivatives are
//! coordinate differences, second derivatives are −1, 0 or 1, so the fallback costs a few
//! subtractions and runs only when the exact value is zero.
//!
//! Because rank 0 dominates, a predicate involving the query point `q` is decided as if
//! `q` were moved to `q + (ε, ε²)`: a viewpoint on a bitangent or on an edge's extension
//! is pushed off it consistently in every predicate.
//!
//! Consistency: the perturbed signs are the signs of a real configuration (the scene at a
//! small enough ε), so they are antisymmetric, transitive and agree with the exact sign
//! whenever that is non-zero. `Zero` is returned only when a polynomial vanishes
//! identically: two arguments that are the same point in a way that makes the expression
//! zero (e.g. `orient(p, p, r)`), or constant-only input such as two equal directions.

use core::cmp::Ordering;

use super::predicates::{self, upper_half, Direction};
use super::{Point, QueryPoint, Sign};

/// A scene vertex with its perturbation rank (global vertex index + 1).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct RankedPoint {
    /// Position on the scene grid.
    pub point: Point,
    /// Perturbation rank: global vertex index + 1 (rank 0 is the query point).
    pub rank: u32,
}

impl RankedPoint {
    /// The vertex with global index `index` at `point`.
    #[inline]
    pub fn vertex(point: Point, index: usize) -> RankedPoint {
        RankedPoint {
            point,
            rank: index as u32 + 1,
        }
    }
}

/// A point of a perturbed predicate, on the query grid, with its rank (`None`: constant).
/// Stored as `i64` (query coordinates and constants are `i64`) to keep an [`Angle`] small;
/// every predicate widens to `i128` before subtracting.
#[derive(Clone, Copy, Debug)]
struct Sym {
    x: i64,
    y: i64,
    rank: Option<u32>,
}

impl Sym {
    const ORIGIN: Sym = Sym {
        x: 0,
        y: 0,
        rank: None,
    };

    fn vertex(v: RankedPoint) -> Sym {
        let q = v.point.to_query();
        Sym {
            x: q.x(),
            y: q.y(),
            rank: Some(v.rank),
        }
    }

    fn query(q: QueryPoint) -> Sym {
        Sym {
            x: q.x(),
            y: q.y(),
            rank: Some(0),
        }
    }

    /// `self − other`, exact in `i128`.
    #[inline]
    fn minus(self, other: Sym) -> (i128, i128) {
        (
            i128::from(self.x) - i128::from(other.x),
            i128::from(self.y) - i128::from(other.y),
        )
    }

    /// The same point: same coordinates and rank.
    #[inline]
    fn same(self, other: Sym) -> bool {
        self.x == other.x && self.y == other.y && self.rank == other.rank
    }

    fn constant(d: Direction) -> Sym {
        Sym {
            x: d.x,
            y: d.y,
            rank: None,
        }
    }
}

/// A perturbed point of a predicate and its coefficients in the two vectors `u`, `v`.
#[derive(Clone, Copy, Default)]
struct Var {
    rank: u32,
    su: i128,
    sv: i128,
}

/// Collects the distinct perturbed points of `u = a − b`, `v = c − d` from the ranks of
/// `a, b, c, d` (`None`: a constant), sorted by rank.
fn vars(ranks: [Option<u32>; 4]) -> ([Var; 4], usize) {
    let mut out = [Var::default(); 4];
    let mut n = 0;
    for (r, su, sv) in [
        (ranks[0], 1, 0),
        (ranks[1], -1, 0),
        (ranks[2], 0, 1),
        (ranks[3], 0, -1),
    ] {
        let Some(rank) = r else { continue };
        if let Some(v) = out[..n].iter_mut().find(|v| v.rank == rank) {
            v.su += su;
            v.sv += sv;
        } else {
            out[n] = Var { rank, su, sv };
            n += 1;
        }
    }
    out[..n].sort_unstable_by_key(|v| v.rank);
    (out, n)
}

/// Exact `cross(a − b, c − d)`. Where the differences fit `i64` (always, for coordinates
/// in range) the products are single widening multiplications; the difference of two
/// products of `i64` values is below 2¹²⁷ in magnitude, so exact.
#[cfg(not(feature = "naive-f64"))]
#[inline]
fn det(a: Sym, b: Sym, c: Sym, d: Sym) -> i128 {
    match (
        a.x.checked_sub(b.x),
        a.y.checked_sub(b.y),
        c.x.checked_sub(d.x),
        c.y.checked_sub(d.y),
    ) {
        (Some(ux), Some(uy), Some(vx), Some(vy)) => {
            i128::from(ux) * i128::from(vy) - i128::from(uy) * i128::from(vx)
        }
        _ => {
            let ((ux, uy), (vx, vy)) = (a.minus(b), c.minus(d));
            ux * vy - uy * vx
        }
    }
}

/// Perturbed sign of `cross(a − b, c − d)`.
///
/// Bit budget: coordinates on the query grid (≤ 2⁵², or constants ≤ 2⁵²), differences
/// ≤ 2⁵³, products ≤ 2¹⁰⁶: exact in `i128`.
#[inline]
fn cross(a: Sym, b: Sym, c: Sym, d: Sym) -> Sign {
    #[cfg(feature = "naive-f64")]
    let exact = {
        let ((ux, uy), (vx, vy)) = (a.minus(b), c.minus(d));
        super::naive::cross(ux, uy, vx, vy)
    };
    #[cfg(not(feature = "naive-f64"))]
    let exact = Sign::of_i128(det(a, b, c, d));
    if exact != Sign::Zero {
        return exact;
    }
    cross_tie(a, b, c, d)
}

/// [`cross`] where the exact value is zero: the first non-zero coefficient of the
/// perturbation (rare: kept out of line so the exact path stays small).
#[cold]
#[inline(never)]
fn cross_tie(a: Sym, b: Sym, c: Sym, d: Sym) -> Sign {
    // The same pair twice (a direction compared with itself, as a walk does with the
    // tangent it just crossed): the polynomial vanishes identically.
    if a.same(c) && b.same(d) {
        return Sign::Zero;
    }
    first_coefficient(a.minus(b), c.minus(d), [a.rank, b.rank, c.rank, d.rank])
}

/// The sign of the first non-zero coefficient of the perturbed `cross(a − b, c − d)`, from
/// the exact differences `u = a − b`, `v = c − d` and the ranks of `a, b, c, d`: the
/// coefficients are differences and signs, so the points' positions are not needed.
fn first_coefficient(u: (i128, i128), v: (i128, i128), ranks: [Option<u32>; 4]) -> Sign {
    let ((ux, uy), (vx, vy)) = (u, v);
    let (vars, n) = vars(ranks);
    // Variable k is (point k / 2, axis k % 2), in significance order. Monomial order: the
    // single variable k, then the pairs (j, k) for j < k (binary counting order).
    let single = |k: usize| -> i128 {
        let p = vars[k / 2];
        if k.is_multiple_of(2) {
            p.su * vy - p.sv * uy // ∂F/∂εx
        } else {
            p.sv * ux - p.su * vx // ∂F/∂εy
        }
    };
    let pair = |j: usize, k: usize| -> i128 {
        // ∂²F/∂εx(P)∂εy(Q) = su_P·sv_Q − sv_P·su_Q; same-axis pairs vanish.
        let (pj, pk) = (vars[j / 2], vars[k / 2]);
        match (j % 2, k % 2) {
            (0, 1) => pj.su * pk.sv - pj.sv * pk.su,
            (1, 0) => pk.su * pj.sv - pk.sv * pj.su,
            _ => 0,
        }
    };
    for k in 0..2 * n {
        let s = Sign::of_i128(single(k));
        if s != Sign::Zero {
            return s;
        }
        for j in 0..k {
            let s = Sign::of_i128(pair(j, k));
            if s != Sign::Zero {
                return s;
            }
        }
    }
    Sign::Zero
}

/// Perturbed sign of `dot(w, a − b)` for a constant vector `w`.
fn dot(w: Direction, a: Sym, b: Sym) -> Sign {
    #[cfg(feature = "naive-f64")]
    let exact = {
        let (ex, ey) = a.minus(b);
        super::naive::dot(w.x as i128, w.y as i128, ex, ey)
    };
    #[cfg(not(feature = "naive-f64"))]
    let exact = {
        let (ex, ey) = a.minus(b);
        Sign::of_i128(w.x as i128 * ex + w.y as i128 * ey)
    };
    if exact != Sign::Zero {
        return exact;
    }
    let (vars, n) = vars([a.rank, b.rank, None, None]);
    for p in &vars[..n] {
        for c in [p.su * w.x as i128, p.su * w.y as i128] {
            let s = Sign::of_i128(c);
            if s != Sign::Zero {
                return s;
            }
        }
    }
    Sign::Zero
}

/// Perturbed [`predicates::orient`]: `Positive` if `r` is left of `p → q`.
/// Never `Zero` unless two arguments have the same rank.
#[inline]
pub fn orient(p: RankedPoint, q: RankedPoint, r: RankedPoint) -> Sign {
    match predicates::orient(p.point, q.point, r.point) {
        Sign::Zero => cross(
            Sym::vertex(q),
            Sym::vertex(p),
            Sym::vertex(r),
            Sym::vertex(p),
        ),
        s => s,
    }
}

/// Perturbed [`predicates::orient_query`]: side of the query point `q` w.r.t. `a → b`.
/// Never `Zero` unless `a` and `b` have the same rank.
pub fn orient_query(a: RankedPoint, b: RankedPoint, q: QueryPoint) -> Sign {
    cross(
        Sym::vertex(b),
        Sym::vertex(a),
        Sym::query(q),
        Sym::vertex(a),
    )
}

/// Side of the vertex `v` w.r.t. the line through `q` with direction `d`: sign of
/// `cross(d, v − q)`, `Positive` if `v` is to the left. Never `Zero`.
pub fn side_of_line(q: QueryPoint, d: Direction, v: RankedPoint) -> Sign {
    cross(Sym::constant(d), Sym::ORIGIN, Sym::vertex(v), Sym::query(q))
}

/// Perturbed [`predicates::parallel_offset`] for two vertices: `Positive` if the line of
/// direction `d` through `s` is left of the one through `r`. Never `Zero` for distinct ranks.
pub fn parallel_offset(d: Direction, r: RankedPoint, s: RankedPoint) -> Sign {
    cross(
        Sym::constant(d),
        Sym::ORIGIN,
        Sym::vertex(s),
        Sym::vertex(r),
    )
}

/// Perturbed order along direction `d` of the query point `q` and the vertex `v`:
/// `Positive` if `v` comes after `q`. Never `Zero`.
pub fn along_query(d: Direction, q: QueryPoint, v: RankedPoint) -> Sign {
    dot(d, Sym::vertex(v), Sym::query(q))
}

/// Perturbed order along direction `d` of two vertices: `Positive` if `r` comes after `p`.
/// Never `Zero` for distinct ranks.
pub fn along(d: Direction, p: RankedPoint, r: RankedPoint) -> Sign {
    dot(d, Sym::vertex(r), Sym::vertex(p))
}

/// Perturbed [`predicates::object_ahead`]: the line through `q` with direction `d` crosses
/// the counter-clockwise edge `a → b`; `Positive` if the object is ahead of `q`.
/// Never `Zero` for distinct `a`, `b`.
pub fn object_ahead(q: QueryPoint, d: Direction, a: RankedPoint, b: RankedPoint) -> Sign {
    let crossing = cross(
        Sym::constant(d),
        Sym::ORIGIN,
        Sym::vertex(b),
        Sym::vertex(a),
    );
    orient_query(a, b, q).times(crossing)
}

/// Whether the perturbed vector `head − tail` lies in the upper half-plane `[0, π)`.
#[cfg(feature = "naive-f64")]
fn upper(head: Sym, tail: Sym) -> bool {
    match dot(Direction { x: 0, y: 1 }, head, tail) {
        Sign::Zero => upper_half(head.minus(tail).0, 0),
        s => s == Sign::Positive,
    }
}

/// Whether the perturbed vector `head − tail` lies in the upper half-plane `[0, π)`: the
/// sign of `dot((0, 1), head − tail)` as [`dot`] decides it, without its general fallback.
/// Where the y difference is zero, the first non-zero coefficient in rank order is that of
/// the y-perturbation of the lower-ranked point (x-perturbations have coefficient 0): +1 for
/// the head, −1 for the tail. Neither perturbed, or the same point: the exact test.
#[cfg(not(feature = "naive-f64"))]
#[inline]
fn upper(head: Sym, tail: Sym) -> bool {
    match head.y.cmp(&tail.y) {
        Ordering::Greater => true,
        Ordering::Less => false,
        Ordering::Equal => match (head.rank, tail.rank) {
            (Some(h), Some(t)) if h != t => h < t,
            (Some(_), None) => true,
            (None, Some(_)) => false,
            _ => upper_half(head.minus(tail).0, 0),
        },
    }
}

#[inline]
fn direction_cmp_sym(p1: Sym, q1: Sym, p2: Sym, q2: Sym) -> Ordering {
    let (h1, h2) = (upper(q1, p1), upper(q2, p2));
    if h1 != h2 {
        return if h1 {
            Ordering::Less
        } else {
            Ordering::Greater
        };
    }
    match cross(q1, p1, q2, p2) {
        Sign::Positive => Ordering::Less,
        Sign::Zero => Ordering::Equal,
        Sign::Negative => Ordering::Greater,
    }
}

/// Perturbed [`predicates::direction_cmp`]: order of the directions of `q1 − p1` and
/// `q2 − p2` by angle in `[0, 2π)` from +x. `Equal` only for the same pair of points.
pub fn direction_cmp(
    p1: RankedPoint,
    q1: RankedPoint,
    p2: RankedPoint,
    q2: RankedPoint,
) -> Ordering {
    direction_cmp_sym(
        Sym::vertex(p1),
        Sym::vertex(q1),
        Sym::vertex(p2),
        Sym::vertex(q2),
    )
}

/// Order of the directions from the query point `q` to the vertices `v1` and `v2`, by
/// angle in `[0, 2π)` from +x: the order in which a ray sweeping counter-clockwise around
/// `q` from +x meets them. `Equal` only if `v1` and `v2` have the same rank.
pub fn direction_cmp_query(q: QueryPoint, v1: RankedPoint, v2: RankedPoint) -> Ordering {
    let q = Sym::query(q);
    direction_cmp_sym(q, Sym::vertex(v1), q, Sym::vertex(v2))
}

/// Order of the direction from `q` to `v` and the constant direction `d`, by angle in
/// `[0, 2π)` from +x. Never `Equal`.
pub fn direction_cmp_query_dir(q: QueryPoint, v: RankedPoint, d: Direction) -> Ordering {
    direction_cmp_sym(Sym::query(q), Sym::vertex(v), Sym::ORIGIN, Sym::constant(d))
}

/// An angle θ on the circle of directions, as the perturbed direction of a vector: the
/// direction of a pair of vertices (bitangents, edges), from the query point to a vertex
/// (sweeps), or a constant direction (walls such as θ = 0). All comparisons are exact
/// degree-2 predicates under the perturbation of this module.
///
/// Stored as the exact vector `head − tail` and the two points' ranks, 24 bytes: every
/// predicate on an angle is a polynomial in that vector and the other points' differences,
/// and its perturbation needs only the ranks (see [`first_coefficient`]), so the points'
/// positions are not kept. The vector fits `i64` for all coordinates in range (query grid
/// ≤ 2⁵², vertices ≤ 2⁴⁶, constant directions ≤ 2⁵²: differences ≤ 2⁵³); a walk compares
/// angles at every event and moves them into its state, and the vector is the comparison
/// key, so nothing is recomputed per comparison.
#[derive(Clone, Copy, Debug)]
pub struct Angle {
    x: i64,
    y: i64,
    /// Rank of the head ([`NO_RANK`]: a constant).
    head: u32,
    /// Rank of the tail.
    tail: u32,
}

/// The rank of an unperturbed point (a constant) in an [`Angle`]: vertex ranks are
/// `index + 1` of `u32` vertex indices, so never this.
const NO_RANK: u32 = u32::MAX;

#[inline(always)]
fn pack_rank(r: Option<u32>) -> u32 {
    r.unwrap_or(NO_RANK)
}

#[inline(always)]
fn unpack_rank(r: u32) -> Option<u32> {
    (r != NO_RANK).then_some(r)
}

impl Angle {
    /// θ = 0, the direction +x (the permanent wall of the line space).
    pub const ZERO: Angle = Angle {
        x: 1,
        y: 0,
        head: NO_RANK,
        tail: NO_RANK,
    };

    /// The direction of `head − tail`, for points on the query grid (which their types
    /// keep within ±2⁵²: the difference fits `i64`, and wrapping never happens).
    #[inline(always)]
    fn of_syms(head: Sym, tail: Sym) -> Angle {
        Angle {
            x: head.x.wrapping_sub(tail.x),
            y: head.y.wrapping_sub(tail.y),
            head: pack_rank(head.rank),
            tail: pack_rank(tail.rank),
        }
    }

    /// The direction of `to − from`.
    #[inline]
    pub fn of_pair(from: RankedPoint, to: RankedPoint) -> Angle {
        Angle::of_syms(Sym::vertex(to), Sym::vertex(from))
    }

    /// The direction from the query point `q` to the vertex `v`.
    #[inline]
    pub fn from_query(q: QueryPoint, v: RankedPoint) -> Angle {
        Angle::of_syms(Sym::vertex(v), Sym::query(q))
    }

    /// The direction from the vertex `v` to the query point `q`: `from_query(q, v)`
    /// reversed, without negating (a walk leaves a cylinder at such reversed tangents).
    #[inline]
    pub(crate) fn to_query(v: RankedPoint, q: QueryPoint) -> Angle {
        Angle::of_syms(Sym::query(q), Sym::vertex(v))
    }

    /// A constant direction (its vector is `d` itself, exact for any components).
    #[inline]
    pub fn constant(d: Direction) -> Angle {
        Angle {
            x: d.x,
            y: d.y,
            head: NO_RANK,
            tail: NO_RANK,
        }
    }

    /// The opposite direction, θ + π (exact: only a constant with a component `i64::MIN`,
    /// beyond [`Direction::new`]'s bound, would saturate).
    #[must_use]
    #[inline]
    pub fn reversed(self) -> Angle {
        Angle {
            x: self.x.saturating_neg(),
            y: self.y.saturating_neg(),
            head: self.tail,
            tail: self.head,
        }
    }

    /// The ranks of head and tail.
    #[inline(always)]
    fn ranks(&self) -> [Option<u32>; 2] {
        [unpack_rank(self.head), unpack_rank(self.tail)]
    }

    /// Whether the perturbed vector lies in the upper half-plane `[0, π)`: the sign of
    /// `dot((0, 1), head − tail)` as [`dot`] decides it (see [`upper`]): the sign of `y`,
    /// else the y-perturbation of the lower-ranked point (+1 for the head, −1 for the
    /// tail), else (neither perturbed, or the same point) the exact test.
    #[inline(always)]
    fn upper(&self) -> bool {
        // The sign test alone where `y ≠ 0` (a walk keys an angle or two per event).
        if self.y != 0 {
            return self.y > 0;
        }
        match (unpack_rank(self.head), unpack_rank(self.tail)) {
            (Some(h), Some(t)) if h != t => h < t,
            (Some(_), None) => true,
            (None, Some(_)) => false,
            _ => self.x > 0,
        }
    }

    /// Exact (unperturbed) order on the circle by angle in `[0, 2π)` from +x: `Equal` for
    /// exactly the same direction. For output decisions such as dropping events of zero
    /// angular width; construction and walking use [`Angle::cmp_angle`].
    #[inline]
    pub fn cmp_exact(&self, other: &Angle) -> Ordering {
        let (hu, hv) = (upper_half64(self.x, self.y), upper_half64(other.x, other.y));
        if hu != hv {
            return if hu {
                Ordering::Less
            } else {
                Ordering::Greater
            };
        }
        #[cfg(feature = "naive-f64")]
        return super::naive::cross(self.x.into(), self.y.into(), other.x.into(), other.y.into())
            .flip()
            .to_i8()
            .cmp(&0);
        // Products of `i64` values: exact in `i128` (see `det`).
        #[cfg(not(feature = "naive-f64"))]
        0.cmp(&det64(self.x, self.y, other.x, other.y))
    }

    /// The direction vector (head − tail) on the query grid, exact.
    #[inline]
    pub fn vector(&self) -> (i128, i128) {
        (i128::from(self.x), i128::from(self.y))
    }

    /// `self.cmp_exact(&Angle::ZERO) == Equal`: the direction is exactly +x.
    #[inline]
    pub(crate) fn is_exactly_zero(&self) -> bool {
        self.y == 0 && self.x > 0
    }

    /// [`Angle::vector`] in `i64` (always: the vector is kept so).
    #[inline]
    pub(crate) fn vector64(&self) -> Option<(i64, i64)> {
        Some((self.x, self.y))
    }

    /// The angle in radians in `[0, 2π)`, for output only.
    pub fn radians(&self) -> f64 {
        let a = libm::atan2(self.y as f64, self.x as f64);
        if a < 0.0 {
            a + 2.0 * core::f64::consts::PI
        } else {
            a
        }
    }

    /// Order on the circle by angle in `[0, 2π)` from +x.
    #[inline]
    pub fn cmp_angle(&self, other: &Angle) -> Ordering {
        let (hu, hv) = (self.upper(), other.upper());
        if hu != hv {
            return if hu {
                Ordering::Less
            } else {
                Ordering::Greater
            };
        }
        match cross_angles(self, other) {
            Sign::Positive => Ordering::Less,
            Sign::Zero => Ordering::Equal,
            Sign::Negative => Ordering::Greater,
        }
    }

    /// This angle with its half-plane, for an angle compared many times (a walk's current
    /// angle and candidate exits).
    #[inline]
    pub(crate) fn keyed(self) -> KeyedAngle {
        KeyedAngle {
            angle: self,
            upper: self.upper(),
        }
    }

    /// Offset order of the lines of direction θ through the vertices `p` and `r`:
    /// `Positive` if the line through `r` lies to the left of the line through `p`
    /// (sign of `cross(d, r − p)`).
    pub fn offset_cmp(&self, p: RankedPoint, r: RankedPoint) -> Sign {
        cross_with(self, Sym::vertex(r), Sym::vertex(p))
    }

    /// [`Angle::offset_cmp`] just after θ (at θ + ε). Differs only for the two vertices
    /// that define θ, whose lines coincide at θ: turning counter-clockwise, the line through
    /// the farther one along the direction falls below (`cross(d + ε·d⊥, w) = −ε·dot(d, w)`).
    pub fn offset_cmp_after(&self, p: RankedPoint, r: RankedPoint) -> Sign {
        match self.offset_cmp(p, r) {
            Sign::Zero => self.along_exact(p, r).flip(),
            s => s,
        }
    }

    /// Offset order of the line of direction θ through the query point `q` and the one
    /// through the vertex `r`: `Positive` if the line through `r` lies to the left.
    pub fn offset_cmp_query(&self, q: QueryPoint, r: RankedPoint) -> Sign {
        cross_with(self, Sym::vertex(r), Sym::query(q))
    }

    /// Point against object along the line of direction θ through the vertex `o`, which
    /// crosses the counter-clockwise edge `e0 → e1` of another object: `Positive` if the
    /// object lies ahead of `o`. This is `orient(e0, e1, o) · cross(d, e1 − e0)` (see
    /// [`predicates::object_ahead`]); both factors are perturbed, so never `Zero` for
    /// distinct ranks.
    pub fn object_ahead_of_vertex(&self, o: RankedPoint, e0: RankedPoint, e1: RankedPoint) -> Sign {
        let crossing = cross_with(self, Sym::vertex(e1), Sym::vertex(e0));
        orient(e0, e1, o).times(crossing)
    }

    /// As [`Angle::object_ahead_of_vertex`], from a query point.
    pub fn object_ahead_of_query(&self, q: QueryPoint, e0: RankedPoint, e1: RankedPoint) -> Sign {
        let crossing = cross_with(self, Sym::vertex(e1), Sym::vertex(e0));
        orient_query(e0, e1, q).times(crossing)
    }

    /// Order of the vertices `p` and `r` along a line of direction θ: `Positive` if `r`
    /// comes after `p` (sign of `dot(d, r − p)`). Exact only: for the perturbed order of
    /// points *on one line* use [`object_ahead`]-style predicates.
    pub fn along_exact(&self, p: RankedPoint, r: RankedPoint) -> Sign {
        let (dx, dy) = self.vector();
        let (wx, wy) = Sym::vertex(r).minus(Sym::vertex(p));
        #[cfg(feature = "naive-f64")]
        return super::naive::dot(dx, dy, wx, wy);
        #[cfg(not(feature = "naive-f64"))]
        Sign::of_i128(dx * wx + dy * wy)
    }
}

/// `ux·vy − uy·vx` of `i64` values, exact in `i128` (the difference of two products below
/// 2¹²⁶ in magnitude).
#[cfg(not(feature = "naive-f64"))]
#[inline(always)]
fn det64(ux: i64, uy: i64, vx: i64, vy: i64) -> i128 {
    i128::from(ux) * i128::from(vy) - i128::from(uy) * i128::from(vx)
}

/// Perturbed sign of `cross(a, b)` for two angles (their vectors as `head − tail`).
#[inline]
fn cross_angles(a: &Angle, b: &Angle) -> Sign {
    #[cfg(feature = "naive-f64")]
    let exact = super::naive::cross(a.x.into(), a.y.into(), b.x.into(), b.y.into());
    #[cfg(not(feature = "naive-f64"))]
    let exact = Sign::of_i128(det64(a.x, a.y, b.x, b.y));
    if exact != Sign::Zero {
        return exact;
    }
    cross_angles_tie(a, b)
}

/// [`cross_angles`] where the exact value is zero (as [`cross_tie`]).
#[cold]
#[inline(never)]
fn cross_angles_tie(a: &Angle, b: &Angle) -> Sign {
    // The same pair twice (same ranks and vector: the same points, or constants only):
    // the polynomial vanishes identically.
    if a.head == b.head && a.tail == b.tail && a.x == b.x && a.y == b.y {
        return Sign::Zero;
    }
    let [ha, ta] = a.ranks();
    let [hb, tb] = b.ranks();
    first_coefficient(a.vector(), b.vector(), [ha, ta, hb, tb])
}

/// Perturbed sign of `cross(a, c − d)` for an angle `a` (as `head − tail`): `c − d` as an
/// angle, for vertices and query points (their difference fits `i64`).
#[inline]
fn cross_with(a: &Angle, c: Sym, d: Sym) -> Sign {
    cross_angles(a, &Angle::of_syms(c, d))
}

/// [`upper_half`] in `i64`.
#[inline]
fn upper_half64(x: i64, y: i64) -> bool {
    y > 0 || (y == 0 && x > 0)
}

/// An [`Angle`] with its half-plane: [`KeyedAngle::cmp`] is [`Angle::cmp_angle`] with
/// that precomputed, the perturbation consulted only where the cross product is exactly
/// zero. 32 bytes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct KeyedAngle {
    /// The angle.
    pub(crate) angle: Angle,
    upper: bool,
}

impl KeyedAngle {
    /// Its half-plane, for a holder that keeps the angle and this flag apart (a walker
    /// packs it beside its other flags: 8 bytes less than a `KeyedAngle`'s padding).
    #[inline(always)]
    pub(crate) fn upper_half(&self) -> bool {
        self.upper
    }

    /// The keyed angle of `angle` with the half-plane [`KeyedAngle::upper_half`] gave.
    #[inline(always)]
    pub(crate) fn from_parts(angle: Angle, upper: bool) -> KeyedAngle {
        KeyedAngle { angle, upper }
    }

    /// [`Angle::cmp_angle`]`(&self.angle, &other.angle)`. Always inlined: a walk calls it
    /// about three times per event, and out of line the call cost a view 4 %.
    #[inline(always)]
    pub(crate) fn cmp(&self, other: &KeyedAngle) -> Ordering {
        if self.upper != other.upper {
            return if self.upper {
                Ordering::Less
            } else {
                Ordering::Greater
            };
        }
        match cross_angles(&self.angle, &other.angle) {
            Sign::Positive => Ordering::Less,
            Sign::Zero => Ordering::Equal,
            Sign::Negative => Ordering::Greater,
        }
    }

    /// [`Angle::cmp_angle`]`(&self.angle, other)` with this side's half-plane precomputed
    /// (a walk compares one event with several walls' angles).
    #[inline]
    pub(crate) fn cmp_angle(&self, other: &Angle) -> Ordering {
        let upper_other = other.upper();
        if self.upper != upper_other {
            return if self.upper {
                Ordering::Less
            } else {
                Ordering::Greater
            };
        }
        match cross_angles(&self.angle, other) {
            Sign::Positive => Ordering::Less,
            Sign::Zero => Ordering::Equal,
            Sign::Negative => Ordering::Greater,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: i32, y: i32, index: usize) -> RankedPoint {
        RankedPoint::vertex(Point::from_raw(x, y).unwrap(), index)
    }

    #[test]
    fn collinear_triples_get_a_consistent_nonzero_sign() {
        let (a, b, c) = (v(0, 0, 0), v(1, 1, 1), v(2, 2, 2));
        let s = orient(a, b, c);
        assert_ne!(s, Sign::Zero);
        // Antisymmetry and cyclic invariance, as for a real triangle.
        assert_eq!(orient(b, a, c), s.flip());
        assert_eq!(orient(b, c, a), s);
        assert_eq!(orient(c, a, b), s);
        assert_eq!(orient(a, c, b), s.flip());
    }

    #[test]
    fn coincident_ranks_are_zero() {
        let a = v(3, 4, 7);
        assert_eq!(orient(a, a, v(1, 1, 1)), Sign::Zero);
    }

    #[test]
    fn query_on_a_line_is_pushed_by_eps() {
        // q on the x-axis through two vertices; q moves to q + (ε, ε²): above the axis.
        let (a, b) = (v(0, 0, 0), v(10, 0, 1));
        let q = Point::from_raw(5, 0).unwrap().to_query();
        assert_eq!(orient_query(a, b, q), Sign::Positive);
        assert_eq!(orient_query(b, a, q), Sign::Negative);
        // A vertical line: the x-perturbation decides.
        let (c, d) = (v(0, 0, 0), v(0, 10, 1));
        let q = Point::from_raw(0, 5).unwrap().to_query();
        assert_eq!(orient_query(c, d, q), Sign::Negative); // q + ε is right of upward c→d
    }

    /// Points with ties everywhere: coordinates in {−1, 0, 1}, as vertices of several
    /// ranks, the query point (rank 0) and constants.
    fn tie_points() -> impl Iterator<Item = Sym> {
        let ranks = [None, Some(0), Some(1), Some(2), Some(5)];
        (-1..=1).flat_map(move |x| {
            (-1..=1).flat_map(move |y| ranks.into_iter().map(move |rank| Sym { x, y, rank }))
        })
    }

    /// The half-plane test through the general perturbed `dot` (the definition).
    fn upper_by_dot(head: Sym, tail: Sym) -> bool {
        match dot(Direction { x: 0, y: 1 }, head, tail) {
            Sign::Zero => upper_half(head.minus(tail).0, 0),
            s => s == Sign::Positive,
        }
    }

    #[test]
    fn fast_paths_agree_with_the_general_perturbation() {
        // Angles as pairs of points (the definition) and as stored (vector and ranks).
        let pairs = || tie_points().flat_map(|h| tie_points().map(move |t| (h, t)));
        for (h, t) in pairs() {
            assert_eq!(upper(h, t), upper_by_dot(h, t), "{h:?} {t:?}");
            assert_eq!(
                Angle::of_syms(h, t).upper(),
                upper_by_dot(h, t),
                "{h:?} {t:?}"
            );
            // The same pair twice vanishes identically (the shortcut of `cross_tie`).
            let ranks = [h.rank, t.rank, h.rank, t.rank];
            assert_eq!(
                first_coefficient(h.minus(t), h.minus(t), ranks),
                Sign::Zero,
                "{h:?} {t:?}"
            );
        }
        for (ha, ta) in pairs().step_by(7) {
            for (hb, tb) in pairs().step_by(3) {
                let (a, b) = (Angle::of_syms(ha, ta), Angle::of_syms(hb, tb));
                let defined = direction_cmp_sym(ta, ha, tb, hb);
                assert_eq!(a.cmp_angle(&b), defined, "{a:?} {b:?}");
                let (ka, kb) = (a.keyed(), b.keyed());
                assert_eq!(ka.cmp(&kb), defined, "{a:?} {b:?}");
                assert_eq!(ka.cmp_angle(&b), defined, "{a:?} {b:?}");
                let ((ux, uy), (vx, vy)) = (ha.minus(ta), hb.minus(tb));
                let general = match Sign::of_i128(ux * vy - uy * vx) {
                    Sign::Zero => {
                        first_coefficient((ux, uy), (vx, vy), [ha.rank, ta.rank, hb.rank, tb.rank])
                    }
                    s => s,
                };
                assert_eq!(cross(ha, ta, hb, tb), general);
                assert_eq!(cross_angles(&a, &b), general, "{a:?} {b:?}");
                assert_eq!(cross_with(&a, hb, tb), general, "{a:?} {hb:?} {tb:?}");
            }
        }
    }

    /// The keyed comparisons at the extremes of the range: query points at ±2⁵² (the
    /// query grid's bound), vertices at ±(2³⁰ − 1) on the scene grid, with many exact ties.
    #[test]
    fn keyed_comparisons_agree_at_the_extremes() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            state >> 11
        };
        const Q: i64 = 1 << 52;
        const V: i32 = (1 << 30) - 1;
        let mut pick_q = || [-Q, -Q + 1, -1, 0, 1, Q - 1, Q][next() as usize % 7];
        let qs: [crate::geom::QueryPoint; 12] = core::array::from_fn(|_| {
            crate::geom::QueryPoint::from_raw(pick_q(), pick_q()).unwrap()
        });
        let mut next2 = move || {
            state = state
                .wrapping_mul(2862933555777941757)
                .wrapping_add(3037000493);
            state >> 13
        };
        let c = |k: u64| [-V, -V + 1, -1, 0, 1, V - 1, V][k as usize % 7];
        let vs: [RankedPoint; 12] = core::array::from_fn(|i| v(c(next2()), c(next2()), i));
        // Each angle with its pair of points (head, tail): the definition.
        let mut angles = heapless::Vec::<(Angle, Sym, Sym), 512>::new();
        for q in &qs {
            for w in &vs {
                let (h, t) = (Sym::vertex(*w), Sym::query(*q));
                angles.push((Angle::from_query(*q, *w), h, t)).unwrap();
                angles
                    .push((Angle::from_query(*q, *w).reversed(), t, h))
                    .unwrap();
            }
        }
        for a in &vs {
            for b in &vs {
                let (h, t) = (Sym::vertex(*b), Sym::vertex(*a));
                angles.push((Angle::of_pair(*a, *b), h, t)).unwrap();
            }
        }
        let x = Sym::constant(Direction { x: 1, y: 0 });
        angles.push((Angle::ZERO, x, Sym::ORIGIN)).unwrap();
        for (a, ha, ta) in &angles {
            let ka = a.keyed();
            for (b, hb, tb) in &angles {
                let expected = direction_cmp_sym(*ta, *ha, *tb, *hb);
                assert_eq!(a.cmp_angle(b), expected, "{a:?} {b:?}");
                assert_eq!(ka.cmp_angle(b), expected, "{a:?} {b:?}");
                assert_eq!(ka.cmp(&b.keyed()), expected, "{a:?} {b:?}");
                assert_eq!(
                    cross_with(a, *hb, *tb),
                    cross(*ha, *ta, *hb, *tb),
                    "{a:?} {b:?}"
                );
            }
        }
    }

    #[test]
    fn directions_from_a_viewpoint_on_an_edge_extension_are_ordered() {
        let q = Point::from_raw(-10, 0).unwrap().to_query();
        let (a, b) = (v(0, 0, 0), v(5, 0, 1));
        let o = direction_cmp_query(q, a, b);
        assert_ne!(o, Ordering::Equal);
        assert_eq!(direction_cmp_query(q, b, a), o.reverse());
        // q + (ε, ε²) is just above the axis: the directions to a and b point slightly
        // below +x, i.e. near 2π; the nearer vertex a is further below, so it comes first.
        assert_eq!(o, Ordering::Less);
        assert_eq!(
            direction_cmp_query_dir(q, a, Direction::new(1, 0).unwrap()),
            Ordering::Greater
        );
    }
}
