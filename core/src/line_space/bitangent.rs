//! Bitangents between two objects, and whether they are free.

use super::{object_ahead_of, ranked, Bound};
use crate::geom::sos::{self, Angle};
use crate::geom::Sign;
use crate::scene::{ObjectId, SceneRef};

/// An oriented line tangent to two objects, through vertex `first` (of object
/// `first_object`) and then vertex `second` (of `second_object`): direction θ is that of
/// `second − first`. Vertices are global indices.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct Bitangent {
    /// The object whose tangent point comes first along the line.
    pub first_object: ObjectId,
    /// Its tangent vertex (global index).
    pub first: usize,
    /// Which chain of `first_object` the line lies on.
    pub first_bound: Bound,
    /// The object whose tangent point comes second.
    pub second_object: ObjectId,
    /// Its tangent vertex (global index).
    pub second: usize,
    /// Which chain of `second_object` the line lies on.
    pub second_bound: Bound,
}

impl Bitangent {
    /// The direction θ of the line.
    pub fn angle(&self, scene: &SceneRef<'_>) -> Angle {
        Angle::of_pair(ranked(scene, self.first), ranked(scene, self.second))
    }
}

/// The side of the oriented line `a → b` on which the object of vertex `a` lies, if the
/// line is tangent to it at `a`: `Lower` if the object is on the left (perturbed
/// orientations; also the check of a loaded file's vertices).
pub(crate) fn tangency(
    scene: &SceneRef<'_>,
    object: ObjectId,
    a: usize,
    b: usize,
) -> Option<Bound> {
    let obj = scene.object(object)?;
    let (first, n) = (obj.first_vertex(), obj.len());
    let k = a.checked_sub(first)?;
    let prev = first + (k + n - 1) % n;
    let next = first + (k + 1) % n;
    let (ra, rb) = (ranked(scene, a), ranked(scene, b));
    let sp = sos::orient(ra, rb, ranked(scene, prev));
    let sn = sos::orient(ra, rb, ranked(scene, next));
    match (sp, sn) {
        (Sign::Positive, Sign::Positive) => Some(Bound::Lower),
        (Sign::Negative, Sign::Negative) => Some(Bound::Upper),
        _ => None,
    }
}

/// All oriented bitangents of two distinct objects (8 for disjoint convex polygons under
/// the perturbation: 4 lines, 2 orientations each), free or not.
///
/// Cost: `|A|·|B|` vertex pairs, two orientation tests each.
pub fn bitangents<'a>(
    scene: SceneRef<'a>,
    a: ObjectId,
    b: ObjectId,
) -> impl Iterator<Item = Bitangent> + 'a {
    let range = |id: ObjectId| {
        scene
            .object(id)
            .map(|o| o.first_vertex()..o.first_vertex() + o.len())
            .unwrap_or(0..0)
    };
    let (ra, rb) = (range(a), range(b));
    ra.flat_map(move |i| rb.clone().map(move |j| (i, j)))
        .flat_map(move |(i, j)| {
            let ta = tangency(&scene, a, i, j);
            let tb = tangency(&scene, b, j, i).map(flip);
            let forward = ta.zip(tb).map(|(ba, bb)| Bitangent {
                first_object: a,
                first: i,
                first_bound: ba,
                second_object: b,
                second: j,
                second_bound: bb,
            });
            // The reversed orientation swaps left and right.
            let backward = forward.map(|f| Bitangent {
                first_object: b,
                first: j,
                first_bound: flip(f.second_bound),
                second_object: a,
                second: i,
                second_bound: flip(f.first_bound),
            });
            forward.into_iter().chain(backward)
        })
}

/// The one directed bitangent that runs from object `p.object`, tangent on chain `p`, to
/// object `q.object`, tangent on chain `q` (free or not), as its tangent vertices (global
/// indices). `None` for two chains of one object.
///
/// For two disjoint convex objects each of the 8 directed bitangents has a different
/// (first object, first bound, second bound) — the 4 lines give the 4 bound pairs in one
/// orientation — so this is the bitangent [`bitangents`] lists with these chains, decided
/// by the same tests as [`tangency`] (inlined here, with each vertex's neighbours looked
/// up once: this is the inner loop of the kinetic sweep).
///
/// Cost: at most `|P|·|Q|` vertex pairs, one or two orientation tests each, two more for
/// the pairs tangent to P.
#[cfg(feature = "alloc")]
pub(crate) fn chain_bitangent(
    scene: &SceneRef<'_>,
    p: super::Chain,
    q: super::Chain,
) -> Option<(usize, usize)> {
    if p.object == q.object {
        return None;
    }
    let (op, oq) = (scene.object(p.object)?, scene.object(q.object)?);
    use crate::geom::{sos::RankedPoint, Point};
    let (pv, qv) = (scene.polygon(op), scene.polygon(oq));
    let (fp, fq) = (op.first_vertex(), oq.first_vertex());
    // `tangency(a, b)` is `Lower` iff both neighbours of `a` are left of `a → b`.
    let sign = |b: Bound| match b {
        Bound::Lower => Sign::Positive,
        Bound::Upper => Sign::Negative,
    };
    let (want_p, want_q) = (sign(p.bound), sign(flip(q.bound)));
    // Vertex k of a polygon with its rank, and its two neighbours (cyclically, without a
    // division: this runs for every pair of vertices).
    let around = |v: &[Point], first: usize, k: usize| {
        let prev = k.checked_sub(1).unwrap_or(v.len().saturating_sub(1));
        let next = if k + 1 < v.len() { k + 1 } else { 0 };
        let at = |i: usize| v.get(i).map(|&pt| RankedPoint::vertex(pt, first + i));
        Some((at(prev)?, at(k)?, at(next)?))
    };
    for a in 0..pv.len() {
        let (pprev, pa, pnext) = around(pv, fp, a)?;
        for b in 0..qv.len() {
            let qb = RankedPoint::vertex(*qv.get(b)?, fq + b);
            let w = difference(pa, qb);
            if orient_along(w, pa, qb, pprev) != want_p || orient_along(w, pa, qb, pnext) != want_p
            {
                continue;
            }
            let (qprev, _, qnext) = around(qv, fq, b)?;
            let w = (-w.0, -w.1);
            if orient_along(w, qb, pa, qprev) == want_q && orient_along(w, qb, pa, qnext) == want_q
            {
                return Some((fp + a, fq + b));
            }
        }
    }
    None
}

/// `b − a` on the scene grid (`|raw| < 2³⁰`, so each component is below 2³¹).
#[cfg(feature = "alloc")]
#[inline(always)]
fn difference(a: sos::RankedPoint, b: sos::RankedPoint) -> (i64, i64) {
    (
        i64::from(b.point.x()) - i64::from(a.point.x()),
        i64::from(b.point.y()) - i64::from(a.point.y()),
    )
}

/// [`sos::orient`]`(a, b, c)` given `w = b − a` (the inner loop of [`chain_bitangent`]
/// shares it between two tests): the exact sign of `cross(w, c − a)` (products below 2⁶²,
/// exact in `i64`), the perturbed predicate only where it is zero. With `naive-f64`,
/// `sos::orient` itself, as every predicate.
#[cfg(feature = "alloc")]
#[inline(always)]
fn orient_along(
    w: (i64, i64),
    a: sos::RankedPoint,
    b: sos::RankedPoint,
    c: sos::RankedPoint,
) -> Sign {
    #[cfg(not(feature = "naive-f64"))]
    {
        let e = difference(a, c);
        match Sign::of_i64(w.0 * e.1 - w.1 * e.0) {
            Sign::Zero => {}
            s => return s,
        }
    }
    #[cfg(feature = "naive-f64")]
    let _ = w;
    orient_tie(a, b, c)
}

/// [`sos::orient`] out of line: reached only for exactly collinear triples (and with
/// `naive-f64`), and inlined it would crowd the registers of the inner loop.
#[cfg(feature = "alloc")]
#[cold]
#[inline(never)]
fn orient_tie(a: sos::RankedPoint, b: sos::RankedPoint, c: sos::RankedPoint) -> Sign {
    sos::orient(a, b, c)
}

fn flip(b: Bound) -> Bound {
    match b {
        Bound::Lower => Bound::Upper,
        Bound::Upper => Bound::Lower,
    }
}

/// Whether the segment between the two tangent points meets no other object.
///
/// An object C meets the segment iff the line crosses C (vertices strictly on both sides,
/// perturbed) and C's chord lies between the tangent points: ahead of the first and behind
/// the second. Disjointness makes "between" well defined. A bounding-box test skips
/// objects far from the segment.
pub fn is_free(scene: &SceneRef<'_>, t: &Bitangent) -> bool {
    let angle = t.angle(scene);
    let (p, q) = (ranked(scene, t.first), ranked(scene, t.second));
    let lo = (p.point.x().min(q.point.x()), p.point.y().min(q.point.y()));
    let hi = (p.point.x().max(q.point.x()), p.point.y().max(q.point.y()));
    scene.objects().iter().enumerate().all(|(c, obj)| {
        let c = ObjectId(c as u32);
        if c == t.first_object || c == t.second_object {
            return true;
        }
        let (min, max) = obj.bbox();
        if max.x() < lo.0 || min.x() > hi.0 || max.y() < lo.1 || min.y() > hi.1 {
            return true;
        }
        let between = object_ahead_of(scene, c, &angle, p) == Some(true)
            && object_ahead_of(scene, c, &angle, q) == Some(false);
        !between
    })
}

/// Which objects of a vertex (a directed bitangent through P then Q) a corner face — one of
/// the four wedges around the vertex, see [`crate::partition`] — has as floor and ceiling:
/// P is crossed between the line's ends in the wedge or not, Q likewise.
#[cfg(any(feature = "alloc", feature = "format"))]
#[derive(Clone, Copy)]
pub(crate) struct Corner {
    pub(crate) p_crossed: bool,
    pub(crate) q_crossed: bool,
}

#[cfg(any(feature = "alloc", feature = "format"))]
impl Corner {
    /// Whether a cylinder with this floor and ceiling is the corner face: (X, Y) for no
    /// object crossed, (P, Y) for P, (X, Q) for Q and (P, Q) for both.
    pub(crate) fn matches(
        self,
        b: &Bitangent,
        floor: Option<ObjectId>,
        ceiling: Option<ObjectId>,
    ) -> bool {
        let (p, q) = (Some(b.first_object), Some(b.second_object));
        match (self.p_crossed, self.q_crossed) {
            (false, false) => floor != p && floor != q && ceiling != p && ceiling != q,
            (true, false) => floor == p && ceiling != q,
            (false, true) => ceiling == q && floor != p,
            (true, true) => floor == p && ceiling == q,
        }
    }

    /// The corners of the top, bottom, left and right wedges of vertex `b` (the table in
    /// [`crate::partition`]).
    pub(crate) fn wedges(b: &Bitangent) -> [Corner; 4] {
        let (p, q) = (
            b.first_bound == Bound::Lower,
            b.second_bound == Bound::Lower,
        );
        let corner = |p_crossed, q_crossed| Corner {
            p_crossed,
            q_crossed,
        };
        [corner(p, q), corner(!p, !q), corner(p, !q), corner(!p, q)]
    }

    /// The floor and ceiling of this (the right) wedge's face, from the floors and ceilings
    /// of the three corner faces the vertex closes: X, the object before `p`, is the floor
    /// of the one whose floor is neither P nor Q, and Y, the one after `q`, likewise the
    /// ceiling. `None` if a needed one is missing (inconsistent input).
    pub(crate) fn face(
        self,
        b: &Bitangent,
        closed: [(Option<ObjectId>, Option<ObjectId>); 3],
    ) -> Option<(Option<ObjectId>, Option<ObjectId>)> {
        let (p, q) = (Some(b.first_object), Some(b.second_object));
        let x = || closed.iter().find(|c| c.0 != p && c.0 != q).map(|c| c.0);
        let y = || closed.iter().find(|c| c.1 != p && c.1 != q).map(|c| c.1);
        Some(match (self.p_crossed, self.q_crossed) {
            (false, false) => (x()?, y()?),
            (true, false) => (p, y()?),
            (false, true) => (x()?, q),
            (true, true) => (p, q),
        })
    }
}
