//! The view from a point: the exact angular intervals of the object seen, from a walk.

#[cfg(feature = "alloc")]
use alloc::vec::Vec;
use core::cmp::Ordering;

use super::tree::wraps;
use super::{Anchor, Position, Trace, WalkError, Walker, VIEW_TANGENT_CACHE};
use crate::geom::predicates::Direction;
use crate::geom::sos::Angle;
use crate::geom::QueryPoint;
use crate::partition::{Complex, CylinderId, Storage};
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
#[cfg(feature = "alloc")]
pub fn view<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
) -> Result<Vec<ViewInterval>, WalkError> {
    // Room for a typical view up front (a grid view from n = 1024 has about 50 intervals):
    // growing from empty reallocates five times.
    let mut out = Vec::with_capacity(view_capacity(scene.len()).min(64));
    sweep(complex, scene, q, &mut out)?;
    Ok(out)
}

/// An upper bound of the number of intervals of any view in a scene of `objects` objects:
/// the lines from a point are tangent to each object twice with the tangent vertex ahead,
/// and every boundary is such a tangent.
pub const fn view_capacity(objects: usize) -> usize {
    2 * objects + 1
}

/// `view` into the caller's buffer, without allocating: returns how many intervals it
/// wrote (the prefix of `out`), or [`WalkError::BufferFull`]. A buffer of
/// [`view_capacity`]`(objects)` intervals always suffices.
///
/// RAM: `out.len() · size_of::<ViewInterval>()` for the output, plus the stack of the walk
/// (no recursion; see `ARCHITECTURE.md`, "Storage and walk RAM").
pub fn view_into<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    out: &mut [ViewInterval],
) -> Result<usize, WalkError> {
    let mut sink = SliceSink { out, len: 0 };
    sweep(complex, scene, q, &mut sink)?;
    Ok(sink.len)
}

/// The view from `q` restricted to the directions counter-clockwise from `from` to `to`
/// (a field of view; `from == to` is the full circle starting at `from`), written into
/// `out` like [`view_into`] (a buffer of [`view_capacity`] intervals always suffices):
/// the first interval starts at `from` — its `start_vertex` is `None` unless a boundary
/// of the full view lies exactly on `from` — and the others are the full view's boundaries
/// strictly inside the range, in order from `from`; a boundary exactly on `to` is left
/// out. Decided exactly (`Angle::cmp_exact`), so this is exactly the restriction of the
/// full view. A range round to the interval containing `from` again (the full circle)
/// ends with that interval from its own start (when that is not `from`): one more
/// interval than the full view, which [`view_capacity`] leaves room for.
///
/// Cost: the walk over the range plus the walk to its start, from θ = 0 either way round
/// (the start cylinder is found at θ = 0 without point location), or the full walk where
/// that adds up to three quarters of a turn or more: at most about one full walk. A range
/// from exactly θ = 0, whose boundary merges the events the perturbation puts just below
/// 2π (the last of a walk from θ = 0), is restricted from the full view.
pub fn view_range_into<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    from: Direction,
    to: Direction,
    out: &mut [ViewInterval],
) -> Result<usize, WalkError> {
    use core::f64::consts::TAU;
    let (f, t) = (Angle::constant(from), Angle::constant(to));
    // The walk to choose, by its length in `f64` (the output is exact either way): past
    // three quarters of a turn, two walks (the second from a cold tangent cache) cost
    // more than the full one (measured on the n = 1024 grid).
    let (a, b) = (f.radians(), t.radians());
    let range = if t.cmp_exact(&f) == Ordering::Greater {
        b - a
    } else {
        TAU - a + b
    };
    if f.is_exactly_zero() || 0.75 * TAU <= range + a.min(TAU - a) {
        return restrict(complex, scene, q, (f, t), out);
    }
    let start = complex.trace_start(scene, q)?;
    let begin = if a <= TAU - a {
        (start, Angle::ZERO)
    } else {
        back_to(complex, scene, q, start, &f)?
    };
    let mut sink = SliceSink { out, len: 0 };
    sweep_range(complex, scene, q, begin, (f, t), &mut sink)?;
    Ok(sink.len)
}

/// Where a counter-clockwise walk to `f` (not exactly θ = 0) starts when it comes from
/// 2π: a clockwise walk from the θ = 0 cylinder `start` down to the first step exactly
/// before `f`, which it leaves undone: the cylinder it would leave, and the angle where
/// it was entered counter-clockwise (the walk continues strictly after it). Every step
/// exactly on `f` lies ahead, so [`sweep_range`] sees the boundary on `f` whole. Steps
/// exactly at θ = 0 that the perturbation puts just below 2π lie above `f`.
fn back_to<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    start: CylinderId,
    f: &Angle,
) -> Result<(CylinderId, Angle), WalkError> {
    let end = Position {
        lap: 1,
        angle: Angle::ZERO,
    };
    let trace = Trace::new(q, Anchor::Point, Some(end));
    let mut walker = Walker::<VIEW_TANGENT_CACHE>::new(start, Angle::ZERO, false);
    let mut cur = start;
    loop {
        let lap = walker.lap();
        let Some(s) = walker.next_step_in::<S, false>(complex, scene, &trace)? else {
            break;
        };
        // The step onto the next lap crosses the permanent wall into θ = 2π.
        if walker.lap() == lap && !wraps(&s.angle) && s.angle.cmp_exact(f) == Ordering::Less {
            return Ok((cur, s.angle));
        }
        cur = s.cylinder;
    }
    // Nothing lies between θ = 0 and `f`.
    Ok((start, Angle::ZERO))
}

/// [`view_range_into`] restricting the full view: the containing interval and the
/// boundaries inside the range, found exactly in the full view written into `out`.
fn restrict<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    (f, t): (Angle, Angle),
    out: &mut [ViewInterval],
) -> Result<usize, WalkError> {
    let n = view_into(complex, scene, q, out)?;
    let view = out.get_mut(..n).unwrap_or_default();
    // Counter-clockwise order from `f`: (lap, angle), lap 1 for directions before `f`.
    let lap = |a: &Angle| u8::from(a.cmp_exact(&f) == Ordering::Less);
    let key_t = if t.cmp_exact(&f) == Ordering::Greater {
        0
    } else {
        1
    };
    // The interval containing `f`: the last starting at or before it, else the last one
    // (it wraps through θ = 0).
    let k = view
        .iter()
        .rposition(|i| i.start.cmp_exact(&f) != Ordering::Greater)
        .unwrap_or(n.saturating_sub(1));
    view.rotate_left(k);
    // The containing interval's own start, when it is not `from`: its boundary lies in
    // the range again if the range goes round far enough (the full circle).
    let mut own = None;
    if let Some(first) = view.first_mut() {
        if n == 1 || first.start.cmp_exact(&f) != Ordering::Equal {
            own = (n > 1).then_some(*first);
            first.start = f;
            first.start_vertex = None;
        }
    }
    let inside = |i: &ViewInterval| {
        let l = lap(&i.start);
        l < key_t || (l == key_t && i.start.cmp_exact(&t) == Ordering::Less)
    };
    let m = 1 + view.iter().skip(1).take_while(|i| inside(i)).count();
    match own {
        Some(i) if m == n && inside(&i) => {
            *out.get_mut(n)
                .ok_or(WalkError::BufferFull { needed: n + 1 })? = i;
            Ok(n + 1)
        }
        _ => Ok(m.min(n)),
    }
}

/// [`view_range_into`] into a new vector.
#[cfg(feature = "alloc")]
pub fn view_range<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    from: Direction,
    to: Direction,
) -> Result<Vec<ViewInterval>, WalkError> {
    let mut out = alloc::vec![
        ViewInterval {
            start: Angle::ZERO,
            object: None,
            start_vertex: None,
        };
        view_capacity(scene.len())
    ];
    let n = view_range_into(complex, scene, q, from, to, &mut out)?;
    out.truncate(n);
    Ok(out)
}

/// Where [`sweep`] puts the intervals.
trait Sink {
    fn push(&mut self, i: ViewInterval) -> Result<(), WalkError>;
    /// Moves the last interval to the front.
    fn last_to_front(&mut self);
    fn is_empty(&self) -> bool;
}

#[cfg(feature = "alloc")]
impl Sink for Vec<ViewInterval> {
    #[inline]
    fn push(&mut self, i: ViewInterval) -> Result<(), WalkError> {
        Vec::push(self, i);
        Ok(())
    }
    fn last_to_front(&mut self) {
        self.rotate_right(1);
    }
    fn is_empty(&self) -> bool {
        Vec::is_empty(self)
    }
}

struct SliceSink<'o> {
    out: &'o mut [ViewInterval],
    len: usize,
}

impl Sink for SliceSink<'_> {
    fn push(&mut self, i: ViewInterval) -> Result<(), WalkError> {
        let slot = self.out.get_mut(self.len).ok_or(WalkError::BufferFull {
            needed: self.len + 1,
        })?;
        *slot = i;
        self.len += 1;
        Ok(())
    }
    fn last_to_front(&mut self) {
        if let Some(used) = self.out.get_mut(..self.len) {
            used.rotate_right(1);
        }
    }
    fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// The first event of a cluster of events on one exact ray, and the ceiling after its
/// last event.
#[derive(Clone, Copy)]
struct Cluster {
    angle: Angle,
    vertex: usize,
    after: Option<ObjectId>,
    /// The cluster is that one event (see [`nearest_of_event`]).
    single: bool,
}

/// The view as a stream over one walk, in constant space besides the output.
///
/// The events come in perturbed order. Events exactly at θ = 0 are perturbed either just
/// above 0 (the leading run `P`, first in the walk) or just below 2π (the trailing run `Z`,
/// last): together they are the first cluster of the view (`Z` then `P`), which is only
/// known at the end of the walk, so it is written last and moved to the front. Every other
/// cluster (events on one exact ray) is written as soon as the next one starts.
fn sweep<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    out: &mut impl Sink,
) -> Result<(), WalkError> {
    let on_zero = |a: &Angle| a.is_exactly_zero();
    // The walker's loop here rather than `walk_trace` with a closure: the closure was not
    // inlined, and most steps (secondary walls, tangents behind `q`) need only the filter.
    let start = complex.trace_start(scene, q)?;
    let start_object = complex.ceiling(start);
    let trace = Trace::new(q, Anchor::Point, None);
    let mut walker = Walker::<VIEW_TANGENT_CACHE>::new(start, Angle::ZERO, true);
    // The leading run at θ = 0 (P), the current cluster of the middle, the trailing run (Z).
    let mut lead: Option<Cluster> = None;
    let mut middle: Option<Cluster> = None;
    let mut tail: Option<Cluster> = None;
    let mut in_lead = true;
    // The object seen before the current middle cluster.
    let mut seen: Option<ObjectId> = start_object;
    while let Some(s) = walker.next_step_in::<S, true>(complex, scene, &trace)? {
        // Only a tangent vertex ahead of `q` can change the view.
        let (Some(v), true) = (s.vertex, s.ahead) else {
            continue;
        };
        let ceiling = complex.ceiling(s.cylinder);
        let event = Cluster {
            angle: s.angle,
            vertex: v,
            after: ceiling,
            single: true,
        };
        // A later event of a cluster: its ceiling, and the cluster has several.
        let join = |c: &mut Cluster| {
            c.after = ceiling;
            c.single = false;
        };
        if in_lead && on_zero(&s.angle) {
            match &mut lead {
                Some(c) => join(c),
                None => lead = Some(event),
            }
            seen = ceiling;
            continue;
        }
        in_lead = false;
        if let Some(t) = &mut tail {
            join(t);
            continue;
        }
        match &mut middle {
            Some(m) if m.angle.cmp_exact(&s.angle) == Ordering::Equal => join(m),
            _ => {
                if let Some(m) = middle.take() {
                    emit(scene, q, &m, &mut seen, out)?;
                }
                if on_zero(&s.angle) {
                    tail = Some(event);
                } else {
                    middle = Some(event);
                }
            }
        }
    }
    if let Some(m) = middle.take() {
        emit(scene, q, &m, &mut seen, out)?;
    }
    // The first cluster: Z then P, seen after the last middle cluster (or P, seen at the
    // start of the walk).
    let first = match (tail, lead) {
        (Some(t), Some(p)) => Some((
            Cluster {
                after: p.after,
                single: false,
                ..t
            },
            seen,
        )),
        (Some(t), None) => {
            // The walk returns to its start cylinder, so after Z the start object is seen
            // again; the middle clusters were written on that assumption.
            if t.after != start_object {
                return Err(WalkError::Corrupt);
            }
            Some((t, seen))
        }
        (None, Some(p)) => Some((p, start_object)),
        (None, None) => None,
    };
    if let Some((c, mut before)) = first {
        let wrote = before != c.after;
        emit(scene, q, &c, &mut before, out)?;
        if wrote {
            out.last_to_front();
        }
    }
    if out.is_empty() {
        out.push(ViewInterval {
            start: Angle::ZERO,
            object: start_object,
            start_vertex: None,
        })?;
    }
    Ok(())
}

/// The view over the range `(f, t)` (`f` not exactly θ = 0) from one walk that starts in
/// `cylinder` at `theta` on lap 0 before `f`: at θ = 0, or where [`back_to`] leaves it.
/// Positions are exact on the circle unwrapped from θ = 0, `(lap, angle)`: lap 1 is past
/// θ = 2π, and holds
/// the events exactly at θ = 0 that the perturbation puts just below 2π, so that they form
/// one cluster with those just above (as the full view's first cluster, `Z` then `P`).
/// Events before `f` only change the object seen; clusters from `f` up to `t` (excluded)
/// are written as [`sweep`] writes them, the interval at `f` first.
fn sweep_range<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    (cylinder, theta): (CylinderId, Angle),
    (f, t): (Angle, Angle),
    out: &mut impl Sink,
) -> Result<(), WalkError> {
    let t_lap = u8::from(t.cmp_exact(&f) != Ordering::Greater);
    let cmp = |(l, a): (u8, &Angle), (m, b): (u8, &Angle)| l.cmp(&m).then_with(|| a.cmp_exact(b));
    // The range ends within a lap past `f`: two laps from θ = 0 bound the walk.
    let end = Position {
        lap: 2,
        angle: Angle::ZERO,
    };
    let trace = Trace::new(q, Anchor::Point, Some(end));
    let mut walker = Walker::<VIEW_TANGENT_CACHE>::new(cylinder, theta, true);
    let mut seen = complex.ceiling(cylinder);
    // The interval at `f` is still to be written.
    let mut first = true;
    let mut current: Option<(u8, Cluster)> = None;
    while let Some(s) = walker.next_step_in::<S, true>(complex, scene, &trace)? {
        let (Some(v), true) = (s.vertex, s.ahead) else {
            continue;
        };
        let lap = walker.lap() + u8::from(wraps(&s.angle));
        let ceiling = complex.ceiling(s.cylinder);
        if cmp((lap, &s.angle), (0, &f)) == Ordering::Less {
            seen = ceiling;
            continue;
        }
        if cmp((lap, &s.angle), (t_lap, &t)) != Ordering::Less {
            break;
        }
        match &mut current {
            Some((l, c)) if *l == lap && c.angle.cmp_exact(&s.angle) == Ordering::Equal => {
                c.after = ceiling;
                c.single = false;
            }
            _ => {
                if let Some((_, c)) = current.take() {
                    emit_from(scene, q, &c, &f, (&mut seen, &mut first), out)?;
                }
                let event = Cluster {
                    angle: s.angle,
                    vertex: v,
                    after: ceiling,
                    single: true,
                };
                current = Some((lap, event));
            }
        }
    }
    if let Some((_, c)) = current {
        emit_from(scene, q, &c, &f, (&mut seen, &mut first), out)?;
    }
    if first {
        out.push(ViewInterval {
            start: f,
            object: seen,
            start_vertex: None,
        })?;
    }
    Ok(())
}

/// [`emit`] for a cluster of a range walk at or after `f`, writing the interval at `f`
/// first (while `first`): a boundary exactly on `f` starts it, else `f` itself does.
fn emit_from(
    scene: &SceneRef<'_>,
    q: QueryPoint,
    c: &Cluster,
    f: &Angle,
    (seen, first): (&mut Option<ObjectId>, &mut bool),
    out: &mut impl Sink,
) -> Result<(), WalkError> {
    if core::mem::take(first) && (c.angle.cmp_exact(f) != Ordering::Equal || c.after == *seen) {
        out.push(ViewInterval {
            start: *f,
            object: *seen,
            start_vertex: None,
        })?;
    }
    emit(scene, q, c, seen, out)
}

/// Writes the boundary of a cluster if the object seen changes there.
fn emit(
    scene: &SceneRef<'_>,
    q: QueryPoint,
    c: &Cluster,
    seen: &mut Option<ObjectId>,
    out: &mut impl Sink,
) -> Result<(), WalkError> {
    if c.after != *seen {
        let objects = [*seen, c.after];
        let vertex = if c.single {
            nearest_of_event(scene, q, &c.angle, c.vertex, objects)
        } else {
            nearest_on_ray(scene, q, &c.angle, objects)
        };
        let vertex = vertex.or(Some(c.vertex));
        out.push(ViewInterval {
            start: c.angle,
            object: c.after,
            start_vertex: vertex,
        })?;
        *seen = c.after;
    }
    Ok(())
}

/// [`nearest_on_ray`] for a boundary made by one event, of the tangent vertex `h` (the
/// cluster holds no other event), without scanning both objects: the nearest vertex on the
/// ray is `h` or one on the line's run of collinear vertices through `h` in h's object H
/// (H is convex and on one side of the line: it meets it in `h` or in an edge).
///
/// No vertex of the other object O can lie on the ray nearer than `h`. If O crossed the
/// ray there (entering its interior before `h`), the rays just before and just after would
/// both meet O first, and the view could not change at `h`; if O touched the ray there (a
/// vertex, or an edge on the line), that tangent would be another event on this exact ray.
/// H is one of the two objects seen on either side, as only its chain is crossed here; if
/// `h` belongs to neither (which should not happen), both are scanned.
fn nearest_of_event(
    scene: &SceneRef<'_>,
    q: QueryPoint,
    angle: &Angle,
    h: usize,
    objects: [Option<ObjectId>; 2],
) -> Option<usize> {
    let own = objects.iter().flatten().find_map(|id| {
        let obj = scene.object(*id)?;
        let i = h.checked_sub(obj.first_vertex())?;
        (i < obj.len()).then_some((obj.first_vertex(), obj.len(), i))
    });
    let Some((first, n, i)) = own else {
        return nearest_on_ray(scene, q, angle, objects);
    };
    let (dx, dy) = angle.vector();
    let d64 = angle.vector64();
    // Mostly `h` alone is on the line: the event's direction is `h − q` itself (so `h` lies
    // ahead) and neither neighbour of `h` lies on the line, so the runs below stop at once.
    if let Some((dx, dy)) = d64 {
        let rel = |k: usize| {
            let v = scene.vertices().get(k)?.to_query();
            Some((v.x() - q.x(), v.y() - q.y()))
        };
        let off_line = |k: usize| {
            rel(k).is_some_and(|(wx, wy)| {
                i128::from(dx) * i128::from(wy) != i128::from(dy) * i128::from(wx)
            })
        };
        let next = if i + 1 >= n { 0 } else { i + 1 };
        let prev = if i == 0 { n.saturating_sub(1) } else { i - 1 };
        if (dx, dy) != (0, 0)
            && rel(h) == Some((dx, dy))
            && off_line(first + next)
            && off_line(first + prev)
        {
            return Some(h);
        }
    }
    // `Some(along)` for a vertex on the line, in multiples of |d|.
    let along = |k: usize| {
        let v = scene.vertices().get(k)?.to_query();
        let (wx, wy) = (v.x() - q.x(), v.y() - q.y());
        // `i64` factors where they fit (always, in range): one multiplication per product.
        if let Some((dx, dy)) = d64 {
            let (dx, dy, wx, wy) = (
                i128::from(dx),
                i128::from(dy),
                i128::from(wx),
                i128::from(wy),
            );
            return (dx * wy == dy * wx).then_some(dx * wx + dy * wy);
        }
        let (wx, wy) = (i128::from(wx), i128::from(wy));
        (dx * wy == dy * wx).then_some(dx * wx + dy * wy)
    };
    // As the scan picks: the smallest `along`, then the smallest index.
    let mut best: Option<(i128, usize)> = None;
    let mut consider = |k: usize, a: i128| {
        if a > 0 && best.is_none_or(|b| (a, k) < b) {
            best = Some((a, k));
        }
    };
    if let Some(a) = along(h) {
        consider(h, a);
    }
    // The run on the line through `h`, both ways round the polygon (at most n vertices).
    for forward in [true, false] {
        for step in 1..n {
            // `i ± step` round the polygon (`i < n`, `step < n`), without a division.
            let j = match (forward, i + step) {
                (true, j) if j >= n => j - n,
                (true, j) => j,
                (false, _) if step <= i => i - step,
                (false, _) => i + n - step,
            };
            match along(first + j) {
                Some(a) => consider(first + j, a),
                None => break,
            }
        }
    }
    best.map(|(_, k)| k)
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
        let first = obj.first_vertex();
        let from_first = scene.vertices().get(first..).unwrap_or_default();
        let vertices = from_first.get(..obj.len()).unwrap_or(from_first);
        for (i, v) in vertices.iter().enumerate() {
            let v = v.to_query();
            // Differences of query coordinates: below 2⁵³, no overflow.
            let (wx, wy) = (i128::from(v.x() - q.x()), i128::from(v.y() - q.y()));
            // On the line first (rarely): `along` only for those.
            if dx * wy != dy * wx {
                continue;
            }
            let along = dx * wx + dy * wy;
            if along > 0 && best.is_none_or(|(b, _)| along < b) {
                best = Some((along, first + i));
            }
        }
    }
    best.map(|(_, k)| k)
}
