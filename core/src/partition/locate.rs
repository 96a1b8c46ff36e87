//! Point location by scanning the cylinders that cross a direction.
//!
//! This is the brute-force locate on a built complex — O(cylinders) per query — used for
//! checking and for the CLI until the history DAG of the randomized construction (§4.2)
//! provides the O(log² n) one. It applies the same predicates the DAG will.

use super::{Complex, CylinderId};
use crate::geom::predicates::{self, Direction};
use crate::geom::sos::Angle;
use crate::geom::{QueryPoint, Sign};
use crate::line_space::{object_ahead_of_query, ranked, tangent_vertex};
use crate::scene::{ObjectId, SceneRef};

/// Where a query point is.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Location {
    /// In free space: the ray from the point in the query direction lies in this cylinder.
    Free {
        /// The cylinder; its ceiling is the forward object and its floor the backward one.
        cylinder: CylinderId,
    },
    /// Strictly inside an object.
    Inside {
        /// The object.
        object: ObjectId,
    },
    /// On the boundary of an object (exactly, before any perturbation).
    OnBoundary {
        /// The object.
        object: ObjectId,
    },
}

/// Whether `q` is inside or on the boundary of an object (exact predicates).
pub fn point_in_scene(scene: &SceneRef<'_>, q: QueryPoint) -> Option<Location> {
    (0..scene.len()).find_map(|i| point_in_object(scene, ObjectId(i as u32), q))
}

/// Whether `q` lies inside or on the boundary of object `object`.
pub(crate) fn point_in_object(
    scene: &SceneRef<'_>,
    object: ObjectId,
    q: QueryPoint,
) -> Option<Location> {
    let obj = scene.object(object)?;
    let (min, max) = obj.bbox();
    let (lo, hi) = (min.to_query(), max.to_query());
    if q.x() < lo.x() || q.x() > hi.x() || q.y() < lo.y() || q.y() > hi.y() {
        return None;
    }
    let poly = scene.polygon(obj);
    let mut on_line = false;
    for (k, a) in poly.iter().enumerate() {
        let b = poly.get((k + 1) % poly.len()).copied().unwrap_or(*a);
        match predicates::orient_query(*a, b, q) {
            Sign::Negative => return None,
            Sign::Zero => on_line = true,
            Sign::Positive => {}
        }
    }
    Some(if on_line {
        Location::OnBoundary { object }
    } else {
        Location::Inside { object }
    })
}

impl<S: super::Storage> Complex<S> {
    /// The cylinder among `candidates` (all crossing θ = `angle`) that contains the line of
    /// direction θ through the free point `q`, in the layer containing `q`.
    pub(crate) fn locate_among<'s>(
        &'s self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        angle: &Angle,
        mut candidates: impl Iterator<Item = (CylinderId, &'s super::Cylinder)>,
    ) -> Option<CylinderId> {
        let below = |chain: crate::line_space::Chain| {
            let v = tangent_vertex(scene, chain.object, angle, chain.bound);
            angle.offset_cmp_query(q, ranked(scene, v))
        };
        candidates
            .find(|(_, c)| {
                c.bottom.is_none_or(|b| below(b) == Sign::Negative)
                    && c.top.is_none_or(|t| below(t) == Sign::Positive)
                    && c.floor
                        .is_none_or(|f| object_ahead_of_query(scene, f, angle, q) == Some(false))
                    && c.ceiling
                        .is_none_or(|g| object_ahead_of_query(scene, g, angle, q) == Some(true))
            })
            .map(|(id, _)| id)
    }

    /// Locates the ray from `q` in direction `d`: the cylinder containing it, or the object
    /// the point is in or on. A point on a bitangent, an edge's extension or a wall is
    /// decided by the perturbation (`q` moves to `q + (ε, ε²)`).
    pub fn locate(&self, scene: &SceneRef<'_>, q: QueryPoint, d: Direction) -> Option<Location> {
        if let Some(l) = point_in_scene(scene, q) {
            return Some(l);
        }
        let angle = Angle::constant(d);
        let cylinder = self.locate_among(scene, q, &angle, self.cylinders_at(scene, &angle))?;
        Some(Location::Free { cylinder })
    }
}
