//! The view from a point: the exact angular intervals of the object seen, from a walk.

use alloc::vec::Vec;
use core::cmp::Ordering;

use super::WalkError;
use crate::geom::sos::Angle;
use crate::geom::QueryPoint;
use crate::partition::Complex;
use crate::scene::{ObjectId, SceneRef};

/// One interval of a view: directions from `start` (inclusive of nothing: boundaries are
/// reported, not what is seen exactly on them) to the next interval's start, counter-
/// clockwise, seeing `object` (`None`: nothing).
#[derive(Clone, Copy, Debug)]
pub struct ViewInterval {
    /// Direction of the start boundary (θ = 0 for a view with no boundary).
    pub start: Angle,
    /// The object seen.
    pub object: Option<ObjectId>,
    /// The vertex causing the start boundary (global index): the vertex nearest to the
    /// viewpoint on the boundary ray among those of the objects seen on either side.
    pub start_vertex: Option<usize>,
}

/// The view from the free point `q` over the full circle, as intervals sorted by start
/// angle in `[0, 2π)`; the last one continues through θ = 0 into the first unless a
/// boundary lies exactly at θ = 0. Neighbouring intervals see different objects. Events of
/// zero angular width created by the perturbation (several events on one exact ray) are
/// merged into one boundary.
///
/// The complex must be built from a scene without screens (views treat screens as
/// transparent; walking through them needs secondary traces).
pub fn view(
    complex: &Complex,
    scene: &SceneRef<'_>,
    q: QueryPoint,
) -> Result<Vec<ViewInterval>, WalkError> {
    // Raw events in perturbed order: (angle, tangent vertex, ceiling after).
    let mut first: Option<Option<ObjectId>> = None;
    let mut events: Vec<(Angle, usize, Option<ObjectId>)> = Vec::new();
    complex.walk_trace(scene, q, |s| {
        let ceiling = complex.ceiling(s.cylinder);
        match (first, s.vertex) {
            (None, _) => first = Some(ceiling),
            (Some(_), Some(v)) if s.ahead => events.push((s.angle, v, ceiling)),
            _ => {}
        }
    })?;
    let start_object = first.flatten();

    // Events exactly at θ = 0 may be perturbed to just below 2π: move them to the front so
    // that every exact ray's events are contiguous.
    let at_zero = events
        .iter()
        .rev()
        .take_while(|e| e.0.cmp_exact(&Angle::ZERO) == Ordering::Equal)
        .count();
    let mut seen = match events.len().checked_sub(at_zero + 1) {
        Some(k) if at_zero > 0 => events[k].2,
        _ => start_object,
    };
    events.rotate_right(at_zero);

    // Cluster events on exactly the same ray; keep a boundary where the object changes.
    let mut out: Vec<ViewInterval> = Vec::new();
    let mut i = 0;
    while i < events.len() {
        let mut j = i + 1;
        while j < events.len() && events[j].0.cmp_exact(&events[i].0) == Ordering::Equal {
            j += 1;
        }
        let after = events[j - 1].2;
        if after != seen {
            let vertex =
                nearest_on_ray(scene, q, &events[i].0, [seen, after]).or(Some(events[i].1));
            out.push(ViewInterval {
                start: events[i].0,
                object: after,
                start_vertex: vertex,
            });
            seen = after;
        }
        i = j;
    }
    // The interval through θ = 0: merge with the first if the object at 0 is the one seen
    // at the end; otherwise θ = 0 itself cannot be a boundary (no event lies exactly there
    // in the perturbed order, and the walk starts with the object at 0⁺).
    if out.is_empty() {
        out.push(ViewInterval {
            start: Angle::ZERO,
            object: start_object,
            start_vertex: None,
        });
    }
    Ok(out)
}

/// The vertex nearest to `q` lying exactly on the ray from `q` in direction `angle`, among
/// the vertices of the given objects.
fn nearest_on_ray(
    scene: &SceneRef<'_>,
    q: QueryPoint,
    angle: &Angle,
    objects: [Option<ObjectId>; 2],
) -> Option<usize> {
    let (dx, dy) = angle.vector();
    let mut best: Option<(i128, usize)> = None;
    for id in objects.iter().flatten() {
        let Some(obj) = scene.object(*id) else {
            continue;
        };
        for k in obj.first_vertex()..obj.first_vertex() + obj.len() {
            let Some(v) = scene.vertices().get(k) else {
                continue;
            };
            let v = v.to_query();
            let (wx, wy) = (v.x() as i128 - q.x() as i128, v.y() as i128 - q.y() as i128);
            let along = dx * wx + dy * wy;
            if dx * wy - dy * wx == 0 && along > 0 && best.is_none_or(|(b, _)| along < b) {
                best = Some((along, k));
            }
        }
    }
    best.map(|(_, k)| k)
}
