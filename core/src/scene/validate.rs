//! Scene validation: per-polygon checks and the disjointness check with a broad phase.
//!
//! Every decision is an exact integer predicate ([`orient`] in `i64`, the signed area in
//! `i128`, signs of coordinate differences); nothing here allocates or panics on input.

use super::{Material, Object};
use crate::geom::predicates::{orient, orient_det};
use crate::geom::{Point, Sign};

/// Why a scene was rejected. Object and vertex numbers are the indices of the input.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum SceneError {
    /// More objects or vertices than the storage holds. Use larger capacity or fewer objects.
    CapacityExceeded {
        /// First object that did not fit.
        object: usize,
    },
    /// A polygon has fewer than three vertices. Give at least three, or drop the object.
    TooFewVertices {
        /// The object.
        object: usize,
        /// How many vertices it has.
        len: usize,
    },
    /// Two consecutive vertices are the same point, or the last repeats the first (the
    /// polygon closes by itself). Remove the repeated vertex.
    RepeatedVertex {
        /// The object.
        object: usize,
        /// The later of the two equal vertices in the input list.
        vertex: usize,
        /// The earlier one: `vertex - 1`, or `0` when the last vertex repeats the first.
        same_as: usize,
    },
    /// A vertex lies on the line through its two neighbours (a straight angle or a spike).
    /// Remove the vertex, or move it outward.
    CollinearVertices {
        /// The object.
        object: usize,
        /// The vertex in the middle.
        vertex: usize,
    },
    /// The boundary turns the other way at this vertex (a reflex corner): the polygon is
    /// not convex. Split the object into convex parts.
    NotConvex {
        /// The object.
        object: usize,
        /// The reflex vertex.
        vertex: usize,
    },
    /// The boundary turns the same way at every vertex but goes around more than once, so it
    /// crosses itself (a pentagram, say). List the vertices in order around the polygon.
    SelfIntersecting {
        /// The object.
        object: usize,
        /// How many times the boundary goes around (at least 2).
        windings: usize,
    },
    /// Two objects touch: they share boundary points but no interior point. Objects must
    /// be pairwise disjoint; leave a gap of at least one grid unit, or merge them into one
    /// convex object.
    ObjectsTouch {
        /// The smaller object index.
        first: usize,
        /// The larger object index.
        second: usize,
    },
    /// Two objects overlap: they share interior points. Move them apart.
    ObjectsOverlap {
        /// The smaller object index.
        first: usize,
        /// The larger object index.
        second: usize,
    },
}

impl core::error::Error for SceneError {}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            SceneError::CapacityExceeded { object } => {
                write!(f, "object {object}: scene storage capacity exceeded")
            }
            SceneError::TooFewVertices { object, len } => write!(
                f,
                "object {object}: {len} vertices, a polygon needs at least 3"
            ),
            SceneError::RepeatedVertex {
                object,
                vertex,
                same_as,
            } => write!(
                f,
                "object {object}, vertex {vertex}: same point as vertex {same_as}"
            ),
            SceneError::CollinearVertices { object, vertex } => write!(
                f,
                "object {object}, vertex {vertex}: on the line through its neighbours"
            ),
            SceneError::NotConvex { object, vertex } => write!(
                f,
                "object {object}, vertex {vertex}: reflex corner, the polygon is not convex"
            ),
            SceneError::SelfIntersecting { object, windings } => write!(
                f,
                "object {object}: boundary goes around {windings} times, it crosses itself"
            ),
            SceneError::ObjectsTouch { first, second } => {
                write!(f, "objects {first} and {second} touch")
            }
            SceneError::ObjectsOverlap { first, second } => {
                write!(f, "objects {first} and {second} overlap")
            }
        }
    }
}

/// `(previous, vertex, next)` for every vertex, cyclically, in input order.
fn corners(pts: &[Point]) -> impl Iterator<Item = (Point, Point, Point)> + '_ {
    let prev = pts.last().into_iter().chain(pts);
    let next = pts.iter().skip(1).chain(pts.first());
    prev.zip(pts).zip(next).map(|((&p, &v), &n)| (p, v, n))
}

/// `(from, to)` for every edge, cyclically, in input order.
fn edges(pts: &[Point]) -> impl Iterator<Item = (Point, Point)> + '_ {
    pts.iter()
        .zip(pts.iter().skip(1).chain(pts.first()))
        .map(|(&a, &b)| (a, b))
}

/// Whether the direction `a → b` (non-zero) has angle in `[0, π)`: pointing up, or
/// exactly along +x. The complement is `[π, 2π)`.
fn upper_half(a: Point, b: Point) -> bool {
    let dx = i64::from(b.x()) - i64::from(a.x());
    let dy = i64::from(b.y()) - i64::from(a.y());
    dy > 0 || (dy == 0 && dx > 0)
}

/// Checks one polygon (as written) and returns its object record, vertices not yet stored.
///
/// Either winding is accepted; `reversed` records a clockwise input. Checks, in order
/// (the first failure is reported, at the smallest vertex index within a check): vertex
/// count, storage indices fit `u32`, repeated consecutive vertices, then collinear or
/// reflex corners, then winding number one.
pub(super) fn polygon(
    index: usize,
    material: Material,
    pts: &[Point],
    start: usize,
) -> Result<Object, SceneError> {
    let n = pts.len();
    let Some(&first) = pts.first() else {
        return Err(SceneError::TooFewVertices {
            object: index,
            len: n,
        });
    };
    if n < 3 {
        return Err(SceneError::TooFewVertices {
            object: index,
            len: n,
        });
    }
    let capacity = SceneError::CapacityExceeded { object: index };
    let (Ok(start32), Ok(len32)) = (u32::try_from(start), u32::try_from(n)) else {
        return Err(capacity);
    };
    if start32.checked_add(len32).is_none() {
        return Err(capacity);
    }

    // Repeated consecutive vertices; the closing pair (last, first) is checked last.
    for (i, (a, b)) in edges(pts).enumerate() {
        if a == b {
            let (vertex, same_as) = if i + 1 == n { (i, 0) } else { (i + 1, i) };
            return Err(SceneError::RepeatedVertex {
                object: index,
                vertex,
                same_as,
            });
        }
    }

    // Orientation = sign of the signed area (a fan from the first vertex): for a simple
    // polygon the corners turning the other way are exactly the reflex ones. Each term is
    // below 2⁶³ and there are fewer than 2³² of them: exact in `i128`.
    let twice_area: i128 = edges(pts)
        .map(|(a, b)| i128::from(orient_det(first, a, b)))
        .sum();
    // A curve whose corners all turn one way is not "not convex" even if its loops give
    // the other area sign (a self-intersecting star): the winding count below names it.
    // Collinear corners do not count here: they are reported as such.
    let mut turns = corners(pts)
        .map(|(p, v, q)| orient(p, v, q))
        .filter(|&s| s != Sign::Zero);
    let first_turn = turns.next();
    let uniform = turns.all(|s| Some(s) == first_turn);
    let turn = match first_turn {
        Some(t) if uniform => t,
        _ if twice_area < 0 => Sign::Negative,
        _ => Sign::Positive,
    };
    for (vertex, (p, v, q)) in corners(pts).enumerate() {
        let s = orient(p, v, q);
        if s == Sign::Zero {
            return Err(SceneError::CollinearVertices {
                object: index,
                vertex,
            });
        }
        if s != turn {
            return Err(SceneError::NotConvex {
                object: index,
                vertex,
            });
        }
    }

    // All corners turn the same way, each by less than π, so the edge direction rotates
    // monotonically and returns to itself after 2π·k, k ≥ 1; the polygon is convex (and
    // simple) iff k = 1. k is the number of times the direction passes the angle 0, i.e.
    // goes from the half [π, 2π) to the half [0, π): a turn of less than π passes 0 or π
    // at most once, and in a cyclic sequence of halves there are as many passes one way as
    // the other, so the count is the same for either orientation.
    let windings = corners(pts)
        .filter(|&(p, v, q)| !upper_half(p, v) && upper_half(v, q))
        .count();
    if windings != 1 {
        return Err(SceneError::SelfIntersecting {
            object: index,
            windings,
        });
    }

    let (mut lo_x, mut lo_y, mut hi_x, mut hi_y) = (first.x(), first.y(), first.x(), first.y());
    for p in pts {
        lo_x = lo_x.min(p.x());
        lo_y = lo_y.min(p.y());
        hi_x = hi_x.max(p.x());
        hi_y = hi_y.max(p.y());
    }
    // Each coordinate is one of an input point's, so it is in range and `from_raw` succeeds;
    // the fallback is never taken.
    let min = Point::from_raw(lo_x, lo_y).unwrap_or(first);
    let max = Point::from_raw(hi_x, hi_y).unwrap_or(first);
    Ok(Object {
        material,
        start: start32,
        len: len32,
        reversed: turn == Sign::Negative,
        min,
        max,
    })
}

/// Pushes the vertices counter-clockwise.
pub(super) fn store_ccw(pts: &[Point], reversed: bool, mut push: impl FnMut(Point)) {
    if reversed {
        if let Some((first, rest)) = pts.split_first() {
            push(*first);
            rest.iter().rev().for_each(|p| push(*p));
        }
    } else {
        pts.iter().for_each(|p| push(*p));
    }
}

/// How two closed convex polygons meet.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Contact {
    /// No common point.
    Disjoint,
    /// Common boundary points, no common interior point.
    Touch,
    /// A common interior point.
    Overlap,
}

/// Where the vertices of `other` lie with respect to the line of the edge `a → b` of a
/// counter-clockwise polygon.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Side {
    /// All strictly on the outer (right) side.
    Outside,
    /// All on the outer side or on the line, at least one on the line.
    OutsideOrOn,
    /// At least one strictly on the inner side.
    Inside,
}

fn side(a: Point, b: Point, other: &[Point]) -> Side {
    let mut on_line = false;
    for &v in other {
        match orient(a, b, v) {
            Sign::Positive => return Side::Inside,
            Sign::Zero => on_line = true,
            Sign::Negative => {}
        }
    }
    if on_line {
        Side::OutsideOrOn
    } else {
        Side::Outside
    }
}

/// Exact contact of two strictly convex counter-clockwise polygons.
///
/// Why it is exact: look at the Minkowski difference D = P − Q, a convex polygon whose
/// edges are translates of P's edges and of Q's edges reversed; for an edge of P with
/// outward normal n, the offset of D's edge is h_P(n) − min over Q of n·q.
/// * P, Q disjoint ⇔ 0 ∉ D ⇔ 0 strictly outside some edge of D ⇔ some edge line of P (or
///   of Q) has all vertices of the other strictly on its outer side (the separating axis
///   theorem, with the axis among edge normals).
/// * Given they meet: interiors disjoint ⇔ 0 ∉ int D (int D = int P − int Q) ⇔ 0 on an
///   edge line of D ⇔ some edge line of P (or Q) has all vertices of the other on its
///   closed outer side. Conversely such a line puts the two interiors in opposite open
///   half-planes, so the test is also sufficient: touching, not overlapping.
fn contact(p: &[Point], q: &[Point]) -> Contact {
    let mut touch = false;
    for (poly, other) in [(p, q), (q, p)] {
        for (a, b) in edges(poly) {
            match side(a, b, other) {
                Side::Outside => return Contact::Disjoint,
                Side::OutsideOrOn => touch = true,
                Side::Inside => {}
            }
        }
    }
    if touch {
        Contact::Touch
    } else {
        Contact::Overlap
    }
}

/// Checks that no two objects touch or overlap. `order` is scratch of one entry per object.
///
/// Broad phase: sweep and prune. Objects are sorted by the low end of their bounding box
/// on the axis where those low ends spread more, and each object is only compared with
/// the following ones whose box starts before its own ends; the exact narrow phase
/// ([`contact`]) runs only for closed boxes that overlap (touching boxes included).
/// Of all offending pairs the one with the smallest `(first, second)` is reported, so
/// the error does not depend on the sort.
pub(super) fn disjoint(
    vertices: &[Point],
    objects: &[Object],
    order: &mut [u32],
) -> Result<(), SceneError> {
    let n = objects.len();
    let Some(order) = order.get_mut(..n) else {
        return Err(SceneError::CapacityExceeded {
            object: order.len(),
        });
    };
    for (i, slot) in order.iter_mut().enumerate() {
        *slot = u32::try_from(i).map_err(|_| SceneError::CapacityExceeded { object: i })?;
    }

    // Sweep along the axis where the boxes' low corners spread more (a column of objects
    // is swept along y).
    let spread = |coord: fn(Point) -> i32| {
        let lows = objects.iter().map(|o| i64::from(coord(o.min)));
        let lo = lows.clone().min().unwrap_or(0);
        let hi = lows.max().unwrap_or(0);
        hi - lo
    };
    let along_x = spread(Point::x) >= spread(Point::y);
    let lo = |o: &Object| if along_x { o.min.x() } else { o.min.y() };
    let hi = |o: &Object| if along_x { o.max.x() } else { o.max.y() };
    let across_overlap = |a: &Object, b: &Object| {
        if along_x {
            a.min.y() <= b.max.y() && b.min.y() <= a.max.y()
        } else {
            a.min.x() <= b.max.x() && b.min.x() <= a.max.x()
        }
    };
    order.sort_unstable_by_key(|&i| (objects.get(i as usize).map_or(i32::MAX, lo), i));

    let polygon = |o: &Object| {
        o.first_vertex()
            .checked_add(o.len())
            .and_then(|end| vertices.get(o.first_vertex()..end))
            .unwrap_or(&[])
    };
    let mut worst: Option<((u32, u32), Contact)> = None;
    let mut rest: &[u32] = order;
    while let Some((&ia, tail)) = rest.split_first() {
        rest = tail;
        let Some(a) = objects.get(ia as usize) else {
            continue;
        };
        for &ib in tail {
            let Some(b) = objects.get(ib as usize) else {
                continue;
            };
            if lo(b) > hi(a) {
                break;
            }
            if !across_overlap(a, b) {
                continue;
            }
            let pair = (ia.min(ib), ia.max(ib));
            if worst.is_some_and(|(w, _)| w <= pair) {
                continue;
            }
            match contact(polygon(a), polygon(b)) {
                Contact::Disjoint => {}
                c => worst = Some((pair, c)),
            }
        }
    }
    match worst {
        None => Ok(()),
        Some(((first, second), c)) => {
            let (first, second) = (first as usize, second as usize);
            Err(if c == Contact::Touch {
                SceneError::ObjectsTouch { first, second }
            } else {
                SceneError::ObjectsOverlap { first, second }
            })
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::geom::point::MAX_ABS_RAW;
    use crate::scene::FixedScene;
    use std::format;
    use std::vec::Vec;

    const M: i32 = MAX_ABS_RAW;

    fn pts(c: &[(i32, i32)]) -> Vec<Point> {
        c.iter()
            .map(|&(x, y)| Point::from_raw(x, y).unwrap())
            .collect()
    }

    /// Validates a scene in fixed storage large enough for every test here.
    fn check(objects: &[Vec<Point>]) -> Result<(), SceneError> {
        FixedScene::<4096, 1024>::new(objects.iter().map(|p| (Material::Opaque, p.as_slice())))
            .map(|_| ())
    }

    fn square(x: i32, y: i32, side: i32) -> Vec<Point> {
        pts(&[(x, y), (x + side, y), (x + side, y + side), (x, y + side)])
    }

    fn one(c: &[(i32, i32)]) -> Result<Object, SceneError> {
        polygon(3, Material::Opaque, &pts(c), 0)
    }

    /// A regular star polygon {n/k} with radius `r`, rounded to the grid.
    fn star(n: usize, k: usize, r: f64) -> Vec<Point> {
        (0..n)
            .map(|i| {
                let a = 2.0 * core::f64::consts::PI * ((i * k) % n) as f64 / n as f64;
                Point::from_raw((r * a.cos()).round() as i32, (r * a.sin()).round() as i32).unwrap()
            })
            .collect()
    }

    #[test]
    fn too_few_vertices() {
        assert_eq!(
            one(&[(0, 0), (1, 0)]),
            Err(SceneError::TooFewVertices { object: 3, len: 2 })
        );
        assert_eq!(
            one(&[]),
            Err(SceneError::TooFewVertices { object: 3, len: 0 })
        );
        let objects = [square(0, 0, 5), pts(&[(10, 10)])];
        assert_eq!(
            check(&objects),
            Err(SceneError::TooFewVertices { object: 1, len: 1 })
        );
    }

    #[test]
    fn repeated_vertex() {
        assert_eq!(
            one(&[(0, 0), (10, 0), (10, 0), (0, 10)]),
            Err(SceneError::RepeatedVertex {
                object: 3,
                vertex: 2,
                same_as: 1
            })
        );
        // The closing vertex written out again.
        assert_eq!(
            one(&[(0, 0), (10, 0), (0, 10), (0, 0)]),
            Err(SceneError::RepeatedVertex {
                object: 3,
                vertex: 3,
                same_as: 0
            })
        );
        // A repeat that is not consecutive is a different problem (a spike).
        assert_eq!(
            one(&[(0, 0), (10, 0), (0, 0), (0, 10)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 1
            })
        );
    }

    #[test]
    fn collinear_vertices() {
        assert_eq!(
            one(&[(0, 0), (5, 0), (10, 0), (10, 10)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 1
            })
        );
        // At vertex 0, whose predecessor is the last vertex.
        assert_eq!(
            one(&[(5, 0), (10, 0), (10, 10), (0, 10), (0, 0)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 0
            })
        );
        // At the last vertex.
        assert_eq!(
            one(&[(0, 0), (10, 0), (10, 10), (0, 10), (0, 5)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 4
            })
        );
        // A spike back along the previous edge, clockwise input.
        assert_eq!(
            one(&[(0, 0), (0, 10), (10, 10), (10, 0), (10, 5)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 3
            })
        );
        // Three points on a line: not a polygon.
        assert_eq!(
            one(&[(0, 0), (1, 1), (2, 2)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 0
            })
        );
        // Every other corner turns clockwise, with a positive area (the loop winds
        // twice): no corner is reflex, the spike at vertex 5 is what is wrong (fuzz
        // regression `build_complex/clockwise_spike`).
        assert_eq!(
            one(&[(110, 0), (42, -1), (-1, 38), (0, 42), (1, 0), (0, 0)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 5
            })
        );
    }

    #[test]
    fn not_convex_names_the_reflex_vertex() {
        let dent_ccw = [(0, 0), (10, 0), (10, 10), (5, 5), (0, 10)];
        assert_eq!(
            one(&dent_ccw),
            Err(SceneError::NotConvex {
                object: 3,
                vertex: 3
            })
        );
        let mut dent_cw = dent_ccw;
        dent_cw.reverse();
        assert_eq!(
            one(&dent_cw),
            Err(SceneError::NotConvex {
                object: 3,
                vertex: 1
            })
        );
        // Two reflex corners: the first one is named.
        assert_eq!(
            one(&[(0, 0), (10, 0), (9, 5), (10, 10), (0, 10), (1, 5)]),
            Err(SceneError::NotConvex {
                object: 3,
                vertex: 2
            })
        );
        // A bow tie: zero area, mixed turns.
        assert!(matches!(
            one(&[(0, 0), (10, 10), (10, 0), (0, 10)]),
            Err(SceneError::NotConvex { object: 3, .. })
        ));
    }

    #[test]
    fn self_intersecting_stars_are_rejected() {
        let pentagram = pts(&[(0, 100), (59, -81), (-95, 31), (95, 31), (-59, -81)]);
        assert_eq!(
            polygon(2, Material::Opaque, &pentagram, 0),
            Err(SceneError::SelfIntersecting {
                object: 2,
                windings: 2
            })
        );
        let mut clockwise = pentagram.clone();
        clockwise.reverse();
        assert_eq!(
            polygon(2, Material::Opaque, &clockwise, 0),
            Err(SceneError::SelfIntersecting {
                object: 2,
                windings: 2
            })
        );
        assert_eq!(
            polygon(0, Material::Opaque, &star(7, 3, 1e6), 0),
            Err(SceneError::SelfIntersecting {
                object: 0,
                windings: 3
            })
        );
        // A square traced twice.
        assert_eq!(
            one(&[
                (0, 0),
                (10, 0),
                (10, 10),
                (0, 10),
                (0, 0),
                (10, 0),
                (10, 10),
                (0, 10)
            ]),
            Err(SceneError::SelfIntersecting {
                object: 3,
                windings: 2
            })
        );
        // Regular polygons {n/1} wind once, from any starting direction.
        for n in 3..40 {
            assert!(polygon(0, Material::Opaque, &star(n, 1, 1e6), 0).is_ok());
            let mut p = star(n, 1, 1e6);
            p.reverse();
            assert!(polygon(0, Material::Opaque, &p, 0).is_ok());
        }
    }

    #[test]
    fn polygon_record() {
        let obj = polygon(5, Material::Mirror, &pts(&[(3, -1), (7, 4), (-2, 9)]), 17).unwrap();
        assert_eq!(obj.material, Material::Mirror);
        assert_eq!(obj.first_vertex(), 17);
        assert_eq!(obj.len(), 3);
        assert!(!obj.was_clockwise());
        assert_eq!(obj.bbox(), (pts(&[(-2, -1)])[0], pts(&[(7, 9)])[0]));
        // Indices that do not fit `u32`.
        assert_eq!(
            polygon(5, Material::Opaque, &square(0, 0, 1), u32::MAX as usize - 2),
            Err(SceneError::CapacityExceeded { object: 5 })
        );
    }

    #[test]
    fn clockwise_input_is_stored_counter_clockwise() {
        let cw = pts(&[(0, 0), (0, 10), (5, 14), (10, 10), (10, 0)]);
        let objects = [square(-20, 0, 5), cw.clone()];
        let scene =
            FixedScene::<16, 2>::new(objects.iter().map(|p| (Material::Opaque, p.as_slice())))
                .unwrap();
        let view = scene.as_ref();
        assert!(!view.objects()[0].was_clockwise());
        let obj = &view.objects()[1];
        assert!(obj.was_clockwise());
        assert_eq!(obj.first_vertex(), 4);
        let stored = view.polygon(obj);
        assert_eq!(stored.len(), 5);
        for k in 0..5 {
            assert_eq!(stored[k], cw[obj.written_vertex_id(k)]);
            let next = stored[(k + 1) % 5];
            let after = stored[(k + 2) % 5];
            assert_eq!(orient(stored[k], next, after), Sign::Positive);
        }
    }

    #[test]
    fn contact_kinds() {
        let a = square(0, 0, 10);
        let cases: [(Vec<Point>, Contact); 13] = [
            // One grid unit apart, along an axis and diagonally.
            (square(11, 0, 10), Contact::Disjoint),
            (square(11, 11, 10), Contact::Disjoint),
            (pts(&[(11, 10), (20, 1), (20, 10)]), Contact::Disjoint),
            // Corner to corner.
            (square(10, 10, 10), Contact::Touch),
            // A whole shared edge, and part of an edge.
            (square(10, 0, 10), Contact::Touch),
            (pts(&[(10, 2), (20, 2), (20, 8), (10, 8)]), Contact::Touch),
            (pts(&[(10, 5), (20, 5), (20, 15), (10, 15)]), Contact::Touch),
            // A vertex on the interior of an edge.
            (pts(&[(10, 5), (20, 0), (20, 10)]), Contact::Touch),
            // Inside, inside touching the boundary, identical.
            (square(2, 2, 5), Contact::Overlap),
            (square(0, 0, 5), Contact::Overlap),
            (square(0, 0, 10), Contact::Overlap),
            // Crossing: a plus sign, and a corner cut.
            (pts(&[(-5, 3), (15, 3), (15, 7), (-5, 7)]), Contact::Overlap),
            (pts(&[(9, 9), (20, 9), (20, 20), (9, 20)]), Contact::Overlap),
        ];
        for (i, (b, want)) in cases.iter().enumerate() {
            assert_eq!(contact(&a, b), *want, "case {i}");
            assert_eq!(contact(b, &a), *want, "case {i} swapped");
        }
        // Tip to tip of two diamonds with no parallel edges.
        let d1 = pts(&[(0, 0), (10, -5), (20, 0), (10, 5)]);
        let d2 = pts(&[(20, 0), (30, -7), (40, 0), (30, 3)]);
        assert_eq!(contact(&d1, &d2), Contact::Touch);
        let d3 = pts(&[(21, 0), (30, -7), (40, 0), (30, 3)]);
        assert_eq!(contact(&d1, &d3), Contact::Disjoint);
        let d4 = pts(&[(19, 0), (30, -7), (40, 0), (30, 3)]);
        assert_eq!(contact(&d1, &d4), Contact::Overlap);
    }

    /// Strict convex hull, counter-clockwise (monotone chain, collinear points dropped).
    fn hull(mut p: Vec<Point>) -> Vec<Point> {
        p.sort();
        p.dedup();
        let mut h: Vec<Point> = Vec::new();
        for pass in 0..2 {
            let start = h.len();
            for &q in p.iter() {
                while h.len() >= start + 2
                    && orient(h[h.len() - 2], h[h.len() - 1], q) != Sign::Positive
                {
                    h.pop();
                }
                h.push(q);
            }
            h.pop();
            if pass == 0 {
                p.reverse();
            }
        }
        h
    }

    /// Brute-force contact: collect the points of P ∩ Q that include all its corners
    /// (vertices of one inside the other, crossings of edges), as rationals `(x, y, d)`;
    /// none → disjoint, all collinear → touch, else overlap.
    fn contact_reference(p: &[Point], q: &[Point]) -> Contact {
        let inside =
            |poly: &[Point], v: Point| edges(poly).all(|(a, b)| orient(a, b, v) != Sign::Negative);
        let mut cand: Vec<(i128, i128, i128)> = Vec::new();
        let r = |v: Point| (v.x() as i128, v.y() as i128, 1i128);
        for (poly, other) in [(p, q), (q, p)] {
            for &v in poly {
                if inside(other, v) {
                    cand.push(r(v));
                }
            }
        }
        for (a, b) in edges(p) {
            for (c, d) in edges(q) {
                let (o1, o2) = (orient(a, b, c), orient(a, b, d));
                let (o3, o4) = (orient(c, d, a), orient(c, d, b));
                if o1 == o2 || o3 == o4 {
                    continue; // parallel, or no crossing; endpoints are covered above
                }
                let (ux, uy) = ((b.x() - a.x()) as i128, (b.y() - a.y()) as i128);
                let (vx, vy) = ((d.x() - c.x()) as i128, (d.y() - c.y()) as i128);
                let (wx, wy) = ((c.x() - a.x()) as i128, (c.y() - a.y()) as i128);
                let den = ux * vy - uy * vx;
                let t = wx * vy - wy * vx;
                cand.push((
                    a.x() as i128 * den + t * ux,
                    a.y() as i128 * den + t * uy,
                    den,
                ));
            }
        }
        if cand.is_empty() {
            return Contact::Disjoint;
        }
        let det = |a: (i128, i128, i128), b: (i128, i128, i128), c: (i128, i128, i128)| {
            a.0 * (b.1 * c.2 - b.2 * c.1) - a.1 * (b.0 * c.2 - b.2 * c.0)
                + a.2 * (b.0 * c.1 - b.1 * c.0)
        };
        for &a in &cand {
            for &b in &cand {
                for &c in &cand {
                    if det(a, b, c) != 0 {
                        return Contact::Overlap;
                    }
                }
            }
        }
        Contact::Touch
    }

    #[test]
    fn contact_matches_brute_force() {
        let mut xorshift = crate::geom::xorshift(0x9E37_79B9_7F4A_7C15);
        let mut next = |m: u64| (xorshift() % m) as i32;
        let mut counts = [0usize; 3];
        for _ in 0..20_000 {
            let mut poly = || loop {
                let k = 3 + next(4) as usize;
                let h = hull((0..k).map(|_| pts(&[(next(7), next(7))])[0]).collect());
                if h.len() >= 3 {
                    return h;
                }
            };
            let (p, q) = (poly(), poly());
            let want = contact_reference(&p, &q);
            assert_eq!(contact(&p, &q), want, "{p:?} {q:?}");
            assert_eq!(contact(&q, &p), want, "{q:?} {p:?}");
            counts[want as usize] += 1;
        }
        assert!(counts.iter().all(|&c| c > 500), "{counts:?}");
    }

    #[test]
    fn scene_reports_touch_and_overlap_with_both_indices() {
        let far = square(1000, 1000, 5);
        let a = square(0, 0, 10);
        let b_touch = pts(&[(10, 5), (20, 0), (20, 10)]);
        let b_in = square(2, 2, 5);
        assert_eq!(
            check(&[far.clone(), b_touch, square(-100, 0, 5), a.clone()]),
            Err(SceneError::ObjectsTouch {
                first: 1,
                second: 3
            })
        );
        // `far` twice overlaps itself; that pair (0, 2) is smaller than (1, 3).
        assert_eq!(
            check(&[far.clone(), b_in.clone(), far.clone(), a.clone()]),
            Err(SceneError::ObjectsOverlap {
                first: 0,
                second: 2
            })
        );
        assert_eq!(
            check(&[square(500, 0, 5), b_in, far, a]),
            Err(SceneError::ObjectsOverlap {
                first: 1,
                second: 3
            })
        );
    }

    #[test]
    fn smallest_pair_is_reported() {
        // 0–1 touch, 2–3 overlap, 1–4 overlap: (0, 1) wins whatever the sweep order.
        let objects = [
            square(100, 0, 10),
            square(110, 0, 10),
            square(0, 0, 10),
            square(5, 5, 10),
            square(112, 2, 3),
        ];
        assert_eq!(
            check(&objects),
            Err(SceneError::ObjectsTouch {
                first: 0,
                second: 1
            })
        );
    }

    fn grid(side: i32, pitch: i32, n: i32) -> Vec<Vec<Point>> {
        let mut v = Vec::new();
        for row in 0..n {
            for col in 0..n {
                v.push(square(col * pitch, row * pitch, side));
            }
        }
        v
    }

    #[test]
    fn dense_grid_of_squares() {
        let g = grid(10, 11, 20);
        assert_eq!(g.len(), 400);
        assert_eq!(check(&g), Ok(()));
        // Zero gap: every neighbour touches; the first pair is (0, 1).
        assert_eq!(
            check(&grid(10, 10, 20)),
            Err(SceneError::ObjectsTouch {
                first: 0,
                second: 1
            })
        );
        // One bad pair at the end.
        let mut g = grid(10, 11, 20);
        g[399] = square(19 * 11 - 1, 19 * 11, 10);
        assert_eq!(
            check(&g),
            Err(SceneError::ObjectsTouch {
                first: 398,
                second: 399
            })
        );
        g[399] = square(19 * 11 - 2, 19 * 11, 10);
        assert_eq!(
            check(&g),
            Err(SceneError::ObjectsOverlap {
                first: 398,
                second: 399
            })
        );
    }

    #[test]
    fn column_sweeps_along_y() {
        let column: Vec<_> = (0..300).map(|i| square(0, i * 11, 10)).collect();
        assert_eq!(check(&column), Ok(()));
        let mut column = column;
        column[150] = square(0, 150 * 11 - 1, 10);
        assert_eq!(
            check(&column),
            Err(SceneError::ObjectsTouch {
                first: 149,
                second: 150
            })
        );
    }

    #[test]
    fn extreme_coordinates() {
        // The four corners of the range.
        let corners = [
            pts(&[(-M, -M), (-M + 1, -M), (-M, -M + 1)]),
            pts(&[(M, -M), (M, -M + 1), (M - 1, -M)]),
            pts(&[(M, M), (M, M - 1), (M - 1, M)]),
            pts(&[(-M, M), (-M, M - 1), (-M + 1, M)]),
        ];
        assert_eq!(check(&corners), Ok(()));
        let o = polygon(0, Material::Opaque, &corners[2], 0).unwrap();
        assert!(o.was_clockwise());
        assert_eq!(o.bbox(), (pts(&[(M - 1, M - 1)])[0], pts(&[(M, M)])[0]));

        // A triangle across the whole range with the long edge A → B (gcd of its direction
        // is 1), and triangles one unit of area away from it: floats cannot tell these apart.
        let (a, b, c) = ((-M, -M), (M - 1, M), (-M, M));
        let p = pts(&[a, b, c]);
        assert_eq!(orient_det(p[0], p[1], pts(&[(-M + 1, -M + 1)])[0]), -1);
        let beside = pts(&[(-M + 1, -M + 1), (M, -M), (M, M - 2)]);
        assert_eq!(check(&[p.clone(), beside]), Ok(()));
        let inside = pts(&[(-M + 1, -M + 2), (M, -M), (M, M - 2)]);
        assert_eq!(
            check(&[p.clone(), inside]),
            Err(SceneError::ObjectsOverlap {
                first: 0,
                second: 1
            })
        );
        let at_vertex = pts(&[a, (M, -M), (M, M - 2)]);
        assert_eq!(
            check(&[at_vertex, p.clone()]),
            Err(SceneError::ObjectsTouch {
                first: 0,
                second: 1
            })
        );
        // Collinear and reflex tests at the extremes.
        assert_eq!(
            one(&[(-M, -M), (0, 0), (M, M), (-M, M)]),
            Err(SceneError::CollinearVertices {
                object: 3,
                vertex: 1
            })
        );
        assert_eq!(
            one(&[(-M, -M), (-1, 0), (M, M), (-M, M)]),
            Err(SceneError::NotConvex {
                object: 3,
                vertex: 1
            })
        );
        assert!(one(&[(-M, -M), (0, -1), (M, M), (-M, M)]).is_ok());
        // A full-range square winds once.
        assert!(one(&[(-M, -M), (M, -M), (M, M), (-M, M)]).is_ok());
    }

    #[test]
    fn capacity() {
        let three = [square(0, 0, 1), square(5, 0, 1), square(10, 0, 1)];
        let err =
            FixedScene::<8, 4>::new(three.iter().map(|p| (Material::Opaque, p.as_slice()))).err();
        assert_eq!(err, Some(SceneError::CapacityExceeded { object: 2 }));
        let err =
            FixedScene::<64, 2>::new(three.iter().map(|p| (Material::Opaque, p.as_slice()))).err();
        assert_eq!(err, Some(SceneError::CapacityExceeded { object: 2 }));
        // Scratch shorter than the object list.
        let objs: Vec<Object> = three
            .iter()
            .enumerate()
            .map(|(i, p)| polygon(i, Material::Opaque, p, 4 * i).unwrap())
            .collect();
        let verts: Vec<Point> = three.concat();
        assert_eq!(
            disjoint(&verts, &objs, &mut [0, 0]),
            Err(SceneError::CapacityExceeded { object: 2 })
        );
        // Scratch with stale contents is refilled.
        assert_eq!(disjoint(&verts, &objs, &mut [7, 7, 7, 7]), Ok(()));
    }

    #[test]
    fn empty_scene() {
        assert_eq!(check(&[]), Ok(()));
    }

    #[test]
    fn display_is_one_line() {
        let cases = [
            (
                SceneError::CapacityExceeded { object: 4 },
                "object 4: scene storage capacity exceeded",
            ),
            (
                SceneError::TooFewVertices { object: 1, len: 2 },
                "object 1: 2 vertices, a polygon needs at least 3",
            ),
            (
                SceneError::RepeatedVertex {
                    object: 0,
                    vertex: 3,
                    same_as: 0,
                },
                "object 0, vertex 3: same point as vertex 0",
            ),
            (
                SceneError::CollinearVertices {
                    object: 2,
                    vertex: 5,
                },
                "object 2, vertex 5: on the line through its neighbours",
            ),
            (
                SceneError::NotConvex {
                    object: 3,
                    vertex: 2,
                },
                "object 3, vertex 2: reflex corner, the polygon is not convex",
            ),
            (
                SceneError::SelfIntersecting {
                    object: 7,
                    windings: 2,
                },
                "object 7: boundary goes around 2 times, it crosses itself",
            ),
            (
                SceneError::ObjectsTouch {
                    first: 1,
                    second: 9,
                },
                "objects 1 and 9 touch",
            ),
            (
                SceneError::ObjectsOverlap {
                    first: 0,
                    second: 3,
                },
                "objects 0 and 3 overlap",
            ),
        ];
        for (e, s) in cases {
            assert_eq!(format!("{e}"), s);
        }
    }

    #[cfg(feature = "alloc")]
    #[test]
    fn growable_scene() {
        use crate::scene::Scene;
        let cw = pts(&[(0, 0), (0, 10), (10, 10), (10, 0)]);
        let objects = [square(20, 0, 10), cw.clone()];
        let scene = Scene::new(objects.iter().map(|p| (Material::Screen, p.as_slice()))).unwrap();
        let view = scene.as_ref();
        let obj = &view.objects()[1];
        assert!(obj.was_clockwise());
        for k in 0..4 {
            assert_eq!(view.polygon(obj)[k], cw[obj.written_vertex_id(k)]);
        }
        let objects = [square(20, 0, 10), cw, square(-10, 10, 10)];
        assert_eq!(
            Scene::new(objects.iter().map(|p| (Material::Opaque, p.as_slice()))).err(),
            Some(SceneError::ObjectsTouch {
                first: 1,
                second: 2
            })
        );
    }
}
