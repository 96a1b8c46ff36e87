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
/// line is tangent to it at `a`: `Lower` if the object is on the left.
fn tangency(scene: &SceneRef<'_>, object: ObjectId, a: usize, b: usize) -> Option<Bound> {
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
