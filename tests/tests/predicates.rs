//! The predicates of `vcx::geom` against exact big-integer arithmetic, at the extremes of the
//! coordinate range, and the consistency of the symbolic perturbation.

use core::cmp::Ordering;

use num_bigint::BigInt;
use proptest::prelude::*;
use vcx::geom::point::{MAX_ABS_RAW, QUERY_MAX_ABS_RAW};
use vcx::geom::predicates::{self as exact, Direction};
use vcx::geom::sos::{self, RankedPoint};
use vcx::{Point, QueryPoint, Sign};

fn big(v: i64) -> BigInt {
    BigInt::from(v)
}

fn sign_of(v: &BigInt) -> Sign {
    match v.sign() {
        num_bigint::Sign::Minus => Sign::Negative,
        num_bigint::Sign::NoSign => Sign::Zero,
        num_bigint::Sign::Plus => Sign::Positive,
    }
}

/// cross(b − a, c − a) in big integers, on the query grid (scene points lifted by 2¹⁶).
fn big_cross(a: (i64, i64), b: (i64, i64), c: (i64, i64)) -> BigInt {
    (big(b.0) - big(a.0)) * (big(c.1) - big(a.1)) - (big(b.1) - big(a.1)) * (big(c.0) - big(a.0))
}

fn lift(p: Point) -> (i64, i64) {
    (p.to_query().x(), p.to_query().y())
}

fn coord() -> impl Strategy<Value = i32> {
    // Mostly the extremes and small values, where overflow and ties live.
    prop_oneof![
        3 => -MAX_ABS_RAW..=MAX_ABS_RAW,
        2 => prop_oneof![Just(MAX_ABS_RAW), Just(-MAX_ABS_RAW), Just(MAX_ABS_RAW - 1), Just(-MAX_ABS_RAW + 1)],
        2 => -4i32..=4,
    ]
}

fn point() -> impl Strategy<Value = Point> {
    (coord(), coord()).prop_map(|(x, y)| Point::from_raw(x, y).unwrap())
}

fn query() -> impl Strategy<Value = QueryPoint> {
    let c = prop_oneof![
        3 => -QUERY_MAX_ABS_RAW..=QUERY_MAX_ABS_RAW,
        2 => prop_oneof![Just(QUERY_MAX_ABS_RAW), Just(-QUERY_MAX_ABS_RAW)],
        2 => (-4i64..=4).prop_map(|v| v << 16),
    ];
    (c.clone(), c).prop_map(|(x, y)| QueryPoint::from_raw(x, y).unwrap())
}

fn direction() -> impl Strategy<Value = Direction> {
    let m = vcx::geom::point::MAX_ABS_DIRECTION;
    let c = prop_oneof![-m..=m, Just(m), Just(-m), -2i64..=2];
    (c.clone(), c).prop_filter_map("zero", |(x, y)| Direction::new(x, y))
}

fn ranked(p: Point, i: usize) -> RankedPoint {
    RankedPoint::vertex(p, i)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4096))]

    #[test]
    fn orient_is_exact(a in point(), b in point(), c in point()) {
        prop_assert_eq!(exact::orient(a, b, c), sign_of(&big_cross(lift(a), lift(b), lift(c))));
        let det = big(exact::orient_det(a, b, c));
        let want = big_cross(((a.x()) as i64, a.y() as i64), (b.x() as i64, b.y() as i64), (c.x() as i64, c.y() as i64));
        prop_assert_eq!(det, want);
    }

    #[test]
    fn query_predicates_are_exact(a in point(), b in point(), q in query(), d in direction()) {
        let (qa, qb, qq) = (lift(a), lift(b), (q.x(), q.y()));
        prop_assert_eq!(exact::orient_query(a, b, q), sign_of(&big_cross(qa, qb, qq)));
        let dot = big(d.x) * (big(qb.0) - big(qq.0)) + big(d.y) * (big(qb.1) - big(qq.1));
        prop_assert_eq!(exact::along(d, q, b.to_query()), sign_of(&dot));
        let cr = big(d.x) * (big(qb.1) - big(qq.1)) - big(d.y) * (big(qb.0) - big(qq.0));
        prop_assert_eq!(exact::parallel_offset(d, q, b.to_query()), sign_of(&cr));
        let crossing = big(d.x) * (big(qb.1) - big(qa.1)) - big(d.y) * (big(qb.0) - big(qa.0));
        let ahead = sign_of(&big_cross(qa, qb, qq)).times(sign_of(&crossing));
        prop_assert_eq!(exact::object_ahead(q, d, a, b), ahead);
    }

    #[test]
    fn direction_order_is_exact(p1 in point(), q1 in point(), p2 in point(), q2 in point()) {
        prop_assume!(p1 != q1 && p2 != q2);
        let angle = |p: Point, q: Point| -> (bool, (i64, i64)) {
            let (dx, dy) = (q.x() as i64 - p.x() as i64, q.y() as i64 - p.y() as i64);
            (!(dy > 0 || (dy == 0 && dx > 0)), (dx, dy))
        };
        let (h1, u) = angle(p1, q1);
        let (h2, v) = angle(p2, q2);
        let want = h1.cmp(&h2).then_with(|| {
            let c = big(u.0) * big(v.1) - big(u.1) * big(v.0);
            BigInt::from(0).cmp(&c)
        });
        prop_assert_eq!(exact::direction_cmp(p1, q1, p2, q2), want);
    }

    /// Perturbed signs agree with exact ones when those are non-zero, are never zero for
    /// distinct points, and are antisymmetric.
    #[test]
    fn sos_orient_is_consistent(a in point(), b in point(), c in point(), ranks in Just([0usize, 1, 2]).prop_shuffle()) {
        let (ra, rb, rc) = (ranked(a, ranks[0]), ranked(b, ranks[1]), ranked(c, ranks[2]));
        let s = sos::orient(ra, rb, rc);
        prop_assert_ne!(s, Sign::Zero);
        let e = exact::orient(a, b, c);
        if e != Sign::Zero { prop_assert_eq!(s, e); }
        prop_assert_eq!(sos::orient(rb, ra, rc), s.flip());
        prop_assert_eq!(sos::orient(rb, rc, ra), s);
        prop_assert_eq!(sos::orient(ra, rc, rb), s.flip());
    }

    #[test]
    fn sos_query_predicates_are_consistent(a in point(), b in point(), q in query(), d in direction()) {
        prop_assume!(a != b);
        let (ra, rb) = (ranked(a, 0), ranked(b, 1));
        let s = sos::orient_query(ra, rb, q);
        prop_assert_ne!(s, Sign::Zero);
        prop_assert_eq!(sos::orient_query(rb, ra, q), s.flip());
        let e = exact::orient_query(a, b, q);
        if e != Sign::Zero { prop_assert_eq!(s, e); }
        let side = sos::side_of_line(q, d, ra);
        prop_assert_ne!(side, Sign::Zero);
        let e = exact::parallel_offset(d, q, a.to_query());
        if e != Sign::Zero { prop_assert_eq!(side, e); }
        let ahead = sos::object_ahead(q, d, ra, rb);
        prop_assert_ne!(ahead, Sign::Zero);
        let e = exact::object_ahead(q, d, a, b);
        if e != Sign::Zero { prop_assert_eq!(ahead, e); }
        let al = sos::along_query(d, q, ra);
        prop_assert_ne!(al, Sign::Zero);
        let e = exact::along(d, q, a.to_query());
        if e != Sign::Zero { prop_assert_eq!(al, e); }
    }
}

/// Every triple on a 4×4 grid, every assignment of ranks: the perturbed orientation is a
/// chirotope of points in general position — non-zero, alternating, and consistent with
/// the exact sign.
#[test]
fn exhaustive_small_grid_orientation() {
    let pts: Vec<Point> = (0..16i32)
        .map(|i| Point::from_raw(i % 4, i / 4).unwrap())
        .collect();
    let r: Vec<RankedPoint> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| ranked(*p, (i * 7) % 16))
        .collect();
    for i in 0..16 {
        for j in 0..16 {
            for k in 0..16 {
                let s = sos::orient(r[i], r[j], r[k]);
                if i == j || j == k || i == k {
                    assert_eq!(s, Sign::Zero);
                    continue;
                }
                assert_ne!(s, Sign::Zero, "{i} {j} {k}");
                let e = exact::orient(pts[i], pts[j], pts[k]);
                assert!(e == Sign::Zero || e == s);
                assert_eq!(sos::orient(r[j], r[i], r[k]), s.flip());
                assert_eq!(sos::orient(r[j], r[k], r[i]), s);
            }
        }
    }
}

/// Four points in the perturbed plane satisfy the Grassmann–Plücker relation for rank-3
/// chirotopes: the perturbed signs are realizable, not just antisymmetric. Checked on every
/// 4-subset of a 3×3 grid (many collinear triples).
#[test]
fn exhaustive_small_grid_chirotope_axioms() {
    let pts: Vec<RankedPoint> = (0..9i32)
        .map(|i| {
            ranked(
                Point::from_raw(i % 3, i / 3).unwrap(),
                ((i * 5) % 9) as usize,
            )
        })
        .collect();
    let chi = |a: usize, b: usize, c: usize| sos::orient(pts[a], pts[b], pts[c]).to_i8();
    for a in 0..9 {
        for b in 0..9 {
            for c in 0..9 {
                for d in 0..9 {
                    for e in 0..9 {
                        let idx = [a, b, c, d, e];
                        if (0..5).any(|i| (i + 1..5).any(|j| idx[i] == idx[j])) {
                            continue;
                        }
                        // Three-term GP relation with base (a, b): the set
                        // {χ(a,b,c)χ(a,d,e), −χ(a,b,d)χ(a,c,e), χ(a,b,e)χ(a,c,d)}
                        // is either {0} or contains both +1 and −1.
                        let t = [
                            chi(a, b, c) * chi(a, d, e),
                            -chi(a, b, d) * chi(a, c, e),
                            chi(a, b, e) * chi(a, c, d),
                        ];
                        let pos = t.iter().any(|&x| x > 0);
                        let neg = t.iter().any(|&x| x < 0);
                        assert!(pos == neg, "GP violated at {idx:?}: {t:?}");
                    }
                }
            }
        }
    }
}

/// Sorting the directions from a viewpoint on many collinearities gives a strict total
/// order (no ties, transitive), as a real perturbed viewpoint would see.
#[test]
fn perturbed_direction_order_is_a_total_order() {
    let q = Point::from_raw(0, 0).unwrap().to_query();
    let mut vs: Vec<RankedPoint> = Vec::new();
    for x in -3..=3 {
        for y in -3..=3 {
            if (x, y) != (0, 0) {
                vs.push(ranked(Point::from_raw(x, y).unwrap(), vs.len()));
            }
        }
    }
    let mut sorted = vs.clone();
    sorted.sort_by(|a, b| sos::direction_cmp_query(q, *a, *b));
    for (i, a) in sorted.iter().enumerate() {
        for (j, b) in sorted.iter().enumerate() {
            assert_eq!(sos::direction_cmp_query(q, *a, *b), i.cmp(&j));
        }
    }
    // The exact cyclic order is respected wherever it is strict: read around the circle,
    // the exact angles descend once (at the cut at angle 0, which the perturbation of the
    // viewpoint may move directions across), never more.
    let o = Point::from_raw(0, 0).unwrap();
    let descents = (0..sorted.len())
        .filter(|&i| {
            let (a, b) = (sorted[i].point, sorted[(i + 1) % sorted.len()].point);
            exact::direction_cmp(o, a, o, b) == Ordering::Greater
        })
        .count();
    assert_eq!(descents, 1);
}
