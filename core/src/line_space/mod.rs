//! The line space: oriented lines `(θ, u)` (DESIGN.md §3).
//!
//! θ is the direction, an [`Angle`]; `u = cross(d(θ), p)` is the signed offset of the line
//! through `p`, growing to the *left* of the direction. For a fixed θ, turn the plane so
//! that θ points along +t: lines are horizontal, u is height, t is the position along the
//! line.
//!
//! * The lines meeting object O form its **sheet**: for each θ the band
//!   `u_lower(θ) ≤ u ≤ u_upper(θ)`, bounded by two **chains** of tangent lines
//!   ([`Chain`]): the lower one (O on the left of the line) and the upper one (O on the
//!   right). A chain is one sinusoid arc per vertex of O, breaking at edge directions.
//! * A **bitangent** is a line on two chains; a free one (nothing between the tangent
//!   points) is a vertex of the visibility complex.
//! * The **cross-section** at θ lists the maximal free segments of direction θ as
//!   intervals in u with a floor and a ceiling object (Fig. 5 of the paper).

mod bitangent;
#[cfg(feature = "alloc")]
mod cross_section;
#[cfg(feature = "alloc")]
mod visibility;

#[cfg(feature = "format")]
pub(crate) use bitangent::tangency;
#[cfg(any(feature = "alloc", feature = "format"))]
pub(crate) use bitangent::Corner;
pub use bitangent::{bitangents, is_free, Bitangent};
#[cfg(feature = "alloc")]
pub use cross_section::{cross_section, Interval};
#[cfg(feature = "alloc")]
pub use visibility::free_bitangents;
#[cfg(feature = "alloc")]
pub(crate) use visibility::{free_bitangents_by_definition, kinetic_sweep, Events};

use crate::geom::sos::{Angle, RankedPoint};
use crate::geom::Sign;
use crate::scene::{ObjectId, SceneRef};

/// Which boundary of a sheet.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Bound {
    /// Tangent lines with the object on their left: the smallest u meeting the object.
    /// Lines above (larger u) cross the object.
    Lower,
    /// Tangent lines with the object on their right: the largest u meeting the object.
    /// Lines below cross the object.
    Upper,
}

/// One boundary curve of a sheet: the tangent lines of `object` on side `bound`. Arcs of
/// the partition (primary walls) are pieces of chains.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Chain {
    /// The tangent object.
    pub object: ObjectId,
    /// Which of its two chains.
    pub bound: Bound,
}

/// The vertex of `object` through which its `bound` tangent line of direction θ passes,
/// as a global vertex index (unique under the perturbation).
///
/// Cost: one offset comparison per vertex of the object.
pub fn tangent_vertex(
    scene: &SceneRef<'_>,
    object: ObjectId,
    angle: &Angle,
    bound: Bound,
) -> usize {
    let Some(obj) = scene.object(object) else {
        return 0;
    };
    let first = obj.first_vertex();
    let mut best = first;
    for i in first + 1..first + obj.len() {
        // Lower: keep the vertex whose line is lowest (others are left of it).
        let other_left = angle.offset_cmp(ranked(scene, best), ranked(scene, i)) == Sign::Positive;
        let better = match bound {
            Bound::Lower => !other_left,
            Bound::Upper => other_left,
        };
        if better {
            best = i;
        }
    }
    best
}

/// The vertex through which every line of `chain` with a direction strictly between the
/// two ends passes, if it is one vertex: the arc of a cylinder with walls at those
/// directions is then one sinusoid, and a trace crosses it only where the line through
/// the eye and that vertex has a direction inside. The range runs counter-clockwise from
/// `from` to `to` (`to_full_turn`: to θ = 2π, `to` being θ = 0), less than a turn; each end
/// comes with the chain's tangent vertex there if the caller knows it (a wall's bitangent
/// touches the chain).
///
/// A chain's tangent vertex advances round the polygon as θ grows, once round per turn,
/// changing only at the object's own edge directions — never exactly at a wall or its
/// reverse (the direction of two vertices of different objects, or a constant, which the
/// perturbation tells apart from an edge's). Each vertex holds it over less than half a
/// turn (its exterior angle), so the others together over more: over at most half a turn
/// the same vertex at both ends means the same vertex throughout, and a longer range is
/// checked at `from` + π as well. Cost: a [`tangent_vertex`] at most, and two or four offset
/// comparisons (the object is convex: a vertex whose neighbours' lines lie on the object's
/// side of its own is the tangent vertex).
#[cfg(feature = "alloc")]
pub(crate) fn arc_vertex(
    scene: &SceneRef<'_>,
    chain: Chain,
    (from, at_from): (&Angle, Option<usize>),
    (to, at_to): (&Angle, Option<usize>),
    to_full_turn: bool,
) -> Option<usize> {
    use core::cmp::Ordering;
    // The vertex at one end, and whether it is known to be the one at `from`.
    let (v, known_at_from) = match (at_from, at_to) {
        (Some(v), _) => (v, true),
        (None, Some(w)) => (w, false),
        (None, None) => (tangent_vertex(scene, chain.object, from, chain.bound), true),
    };
    let obj = scene.object(chain.object)?;
    let (first, n) = (obj.first_vertex(), obj.len());
    let i = v.checked_sub(first).filter(|&i| i < n)?;
    let prev = first + if i == 0 { n - 1 } else { i - 1 };
    let next = first + if i + 1 == n { 0 } else { i + 1 };
    // As `tangent_vertex` keeps the lowest (`Lower`) or highest line.
    let inside = match chain.bound {
        Bound::Lower => Sign::Positive,
        Bound::Upper => Sign::Negative,
    };
    let tangent_at = |angle: &Angle| {
        [prev, next]
            .iter()
            .all(|&k| angle.offset_cmp(ranked(scene, v), ranked(scene, k)) == inside)
    };
    let same_at_to = at_to.map_or_else(|| tangent_at(to), |w| w == v);
    // More than half a turn: `from` in the upper half-plane and `to` past `from` + π.
    let half = from.reversed();
    let longer = from.cmp_angle(&Angle::ZERO.reversed()) == Ordering::Less
        && (to_full_turn || to.cmp_angle(&half) == Ordering::Greater);
    let same = same_at_to && (known_at_from || tangent_at(from));
    (same && (!longer || tangent_at(&half))).then_some(v)
}

/// Whether the object is ahead of the query point `q` along the line of direction θ
/// through it. `None` if the line does not cross the object (perturbed).
pub fn object_ahead_of_query(
    scene: &SceneRef<'_>,
    object: ObjectId,
    angle: &Angle,
    q: crate::geom::QueryPoint,
) -> Option<bool> {
    let obj = scene.object(object)?;
    let first = obj.first_vertex();
    let n = obj.len();
    (0..n).find_map(|k| {
        let (a, b) = (ranked(scene, first + k), ranked(scene, first + (k + 1) % n));
        let (sa, sb) = (angle.offset_cmp_query(q, a), angle.offset_cmp_query(q, b));
        (sa != sb).then(|| angle.object_ahead_of_query(q, a, b) == Sign::Positive)
    })
}

/// The tangent lines from the query point `q` to `object`: for each, the tangent vertex
/// (global index) and the chain on which the oriented line from `q` through that vertex
/// lies (the reversed line lies on the other chain), and how many there are — two if `q`
/// is outside the object, none if it is inside (possible for virtual eyes).
pub fn tangents_from(
    scene: &SceneRef<'_>,
    object: ObjectId,
    q: crate::geom::QueryPoint,
) -> ([(usize, Bound); 2], usize) {
    let mut out = [(0, Bound::Lower); 2];
    let mut found = 0;
    // A validated scene holds every object's vertices (an object without them has none).
    let Some((first, vertices)) = scene.object(object).and_then(|obj| {
        let first = obj.first_vertex();
        Some((
            first,
            scene.vertices().get(first..first.checked_add(obj.len())?)?,
        ))
    }) else {
        return (out, 0);
    };
    let (Some(v0), Some(vl)) = (vertices.first(), vertices.last()) else {
        return (out, 0);
    };
    // Side of the neighbours w.r.t. the line q → h: orient(q, h, x) = orient(h, x, q). Each
    // edge's sign is computed once: orient(h, prev, q) = −orient(prev, h, q), the previous
    // edge's sign (the perturbed determinant changes sign with a swap like the exact one).
    //
    // orient(a, b, q) = cross(a − q, b − q): each vertex's offset from `q` is computed once
    // (query grid, `i64`), the exact sign read from it, the perturbation only where it is
    // exactly zero.
    let rel = |v: &crate::geom::Point| {
        let v = v.to_query();
        // Within ±2⁴⁶ and ±2⁵²: the difference fits, the subtraction never wraps.
        (v.x().wrapping_sub(q.x()), v.y().wrapping_sub(q.y()))
    };
    // The sign of edge `k → next` (local indices) from the offsets of its ends.
    let edge = |k: usize, (ax, ay): (i64, i64), next: usize, (bx, by): (i64, i64)| {
        #[cfg(not(feature = "naive-f64"))]
        match Sign::of_i128(i128::from(ax) * i128::from(by) - i128::from(ay) * i128::from(bx)) {
            Sign::Zero => {}
            s => return s,
        }
        #[cfg(feature = "naive-f64")]
        let _ = (ax, ay, bx, by);
        edge_side_tie(scene, first + k, first + next, q)
    };
    // Vertex k is a tangent where the signs of edges k − 1 and k differ; the line lies on
    // the lower chain if the object is on its left. Found in index order, vertex 0 first.
    let tangent = |k: usize, prev: Sign, sn: Sign| {
        let bound = if sn == Sign::Positive {
            Bound::Lower
        } else {
            Bound::Upper
        };
        (prev.flip() == sn).then_some((first + k, bound))
    };
    // The closing edge (n − 1) → 0 first, then 0 → 1, …, (n − 2) → (n − 1): every edge
    // computed once, and none after the second tangent (a convex object has no more, and
    // only the first two are kept).
    let last = vertices.len() - 1;
    let w0 = rel(v0);
    let closing = edge(last, rel(vl), 0, w0);
    let (mut prev, mut wk) = (closing, w0);
    for (k, v) in vertices.iter().enumerate().skip(1) {
        let wn = rel(v);
        let sn = edge(k - 1, wk, k, wn);
        if let Some(t) = tangent(k - 1, prev, sn) {
            if let Some(slot) = out.get_mut(found) {
                *slot = t;
                found += 1;
            }
            if found == out.len() {
                return (out, found);
            }
        }
        prev = sn;
        wk = wn;
    }
    if let (Some(t), Some(slot)) = (tangent(last, prev, closing), out.get_mut(found)) {
        *slot = t;
        found += 1;
    }
    (out, found)
}

/// `orient_query` of the vertices of global indices `a` and `b` and `q`, through the
/// perturbed predicate (for an edge exactly collinear with `q`: rare, kept out of line).
#[cold]
#[inline(never)]
fn edge_side_tie(scene: &SceneRef<'_>, a: usize, b: usize, q: crate::geom::QueryPoint) -> Sign {
    crate::geom::sos::orient_query(ranked(scene, a), ranked(scene, b), q)
}

/// The vertex with global index `i` and its perturbation rank.
#[inline]
pub fn ranked(scene: &SceneRef<'_>, i: usize) -> RankedPoint {
    RankedPoint::vertex(scene.vertices().get(i).copied().unwrap_or_default(), i)
}

/// Whether the object is ahead of vertex `o` along the line of direction θ through `o`.
/// `None` if the line does not cross the object (perturbed).
pub fn object_ahead_of(
    scene: &SceneRef<'_>,
    object: ObjectId,
    angle: &Angle,
    o: RankedPoint,
) -> Option<bool> {
    let obj = scene.object(object)?;
    let first = obj.first_vertex();
    let n = obj.len();
    // A counter-clockwise edge whose endpoints lie on opposite sides of the line.
    (0..n).find_map(|k| {
        let (a, b) = (ranked(scene, first + k), ranked(scene, first + (k + 1) % n));
        let (sa, sb) = (angle.offset_cmp(o, a), angle.offset_cmp(o, b));
        (sa != sb).then(|| angle.object_ahead_of_vertex(o, a, b) == Sign::Positive)
    })
}

#[cfg(all(test, feature = "alloc"))]
mod tests {
    use alloc::vec::Vec;

    use super::*;
    use crate::geom::{Point, QueryPoint};
    use crate::scene::{Material, Scene};

    /// [`tangents_from`] against its definition through the perturbed `orient_query` of
    /// every edge: vertex k is a tangent where the signs of edges k − 1 and k differ, in
    /// index order. Query points on the lattice of the vertices (on edges' lines, so the
    /// perturbation decides) and at the extremes of the query range (±2⁵²).
    #[test]
    fn tangents_agree_with_the_edge_signs() {
        let p = |x: i32, y: i32| Point::from_raw(x << 16, y << 16).unwrap();
        // A triangle in the corner of the scene grid (raw ±(2³⁰ − 1)).
        const M: i32 = (1 << 30) - 1;
        let raw = |x: i32, y: i32| Point::from_raw(x, y).unwrap();
        let polys: [Vec<Point>; 4] = [
            alloc::vec![p(0, 0), p(4, 0), p(4, 2), p(0, 2)],
            alloc::vec![p(6, 1), p(9, 0), p(8, 3)],
            alloc::vec![p(-5, -5), p(-1, -4), p(0, -1), p(-3, 0), p(-6, -2)],
            alloc::vec![raw(-M, -M), raw(-M + (1 << 20), -M), raw(-M, -M + 3)],
        ];
        let scene = Scene::new(polys.iter().map(|v| (Material::Opaque, v.as_slice()))).unwrap();
        let s = scene.as_ref();
        let unit = 1i64 << 32;
        const Q: i64 = 1 << 52;
        let mut points: Vec<QueryPoint> = Vec::new();
        for x in -8..=11 {
            for y in -7..=5 {
                points.push(QueryPoint::from_raw(x * unit, y * unit).unwrap());
                points.push(QueryPoint::from_raw(x * unit + unit / 3, y * unit - 7).unwrap());
            }
        }
        for (x, y) in [(Q, Q), (-Q, Q), (Q, -Q), (-Q, -Q), (Q, 0), (0, -Q), (-Q, 1)] {
            points.push(QueryPoint::from_raw(x, y).unwrap());
        }
        let mut checked = 0;
        for q in points {
            for (i, obj) in s.objects().iter().enumerate() {
                let (first, n) = (obj.first_vertex(), obj.len());
                let sign = |k: usize| {
                    let (a, b) = (first + k % n, first + (k + 1) % n);
                    crate::geom::sos::orient_query(ranked(&s, a), ranked(&s, b), q)
                };
                let expected: Vec<(usize, Bound)> = (0..n)
                    .filter(|&k| sign(k + n - 1).flip() == sign(k))
                    .map(|k| {
                        let b = if sign(k) == Sign::Positive {
                            Bound::Lower
                        } else {
                            Bound::Upper
                        };
                        (first + k, b)
                    })
                    .take(2)
                    .collect();
                let (t, count) = tangents_from(&s, ObjectId(i as u32), q);
                assert_eq!(&t[..count], &expected[..], "object {i}, q = {q:?}");
                checked += usize::from(count == 2);
            }
        }
        assert!(checked > 1000, "{checked}");
    }
}
