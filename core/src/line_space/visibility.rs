//! All free bitangents of a scene (the vertices of the visibility complex) in θ order,
//! output-sensitively.
//!
//! **The brute force** ([`free_bitangents_brute_force`]) is the definition: every pair of
//! objects, every pair of vertices, and a freeness test against every object — O(n³).
//!
//! **The kinetic sweep** ([`free_bitangents`]) finds the same set in
//! O((n + V) log(n + V)) predicate evaluations for V vertices (objects of bounded size),
//! by running the bookkeeping of the rotational sweep of `partition::sweep` with a priority
//! queue in place of the list of vertices (the topological sweep of Pocchiola & Vegter):
//!
//! * In the sweep every vertex `v` (p on P's chain `cp`, then q on Q's chain `cq`) closes
//!   its *left wedge*: an open cylinder whose bottom arc lies on `cp` and top arc on `cq`;
//!   at `v` the two arcs meet and the cylinder is pinched to nothing (`build_by_sweep`
//!   fails with `SweepLostCylinder` if that cylinder is missing).
//! * Conversely, a cylinder with bottom chain X and top chain Y can only be pinched at a
//!   line tangent to both, oriented from X's object to Y's, with X's object on X's side
//!   and Y's on Y's: of the 8 directed bitangents of two objects exactly one
//!   ([`super::bitangent::chain_bitangent`]). It is the cylinder's *pinch candidate*. The
//!   cylinder is either closed earlier by a vertex on one of its arcs (as the top or bottom
//!   wedge of that vertex) or lives until its candidate, which is then the next vertex.
//!   A candidate not after the cylinder's left wall lies beyond θ = 2π: the cylinder is
//!   still open at the end of the sweep.
//! * So the next vertex after θ is the earliest candidate among the open cylinders: take
//!   it, close and open cylinders exactly as `build_by_sweep` does; the three cylinders
//!   opened take the slots of the three closed, and their candidates replace the closed
//!   ones' in the heap (one sift each instead of a removal and an insertion).
//! * Each vertex is found with the cylinders it closes and opens, so the sweep reports
//!   them ([`Events`]) and `build_by_sweep` writes the partition as it goes, without a
//!   second pass over the vertices.
//!
//! Open cylinders are indexed by chain: at any θ a chain has at most two cylinders above
//! it and two below (one layer on the side where its object is not crossed, the layers
//! before and after the object on the other), so lookups are O(1) instead of a search.
//!
//! Every decision is one of the exact perturbed predicates of the brute force
//! ([`super::bitangent`]'s tangency test, [`Angle::cmp_angle`]); the heap orders by an
//! integer pseudo-angle that never contradicts θ ([`Key::coarse`]), and on equal values by
//! the exact integer cross product, then `cmp_angle`. No floats anywhere. A cylinder's
//! pair of chains often comes back a few vertices later, so the last few pinch
//! candidates of each bottom chain are remembered ([`MEMO`]).
//!
//! Why not a grid of buckets: walking the segment of each candidate bitangent cell by cell
//! makes the freeness test cheap, but the candidates are still all O(n²) object pairs
//! (8·10⁶ for n = 4096) while the grid scene has about 100 vertices per object; the
//! kinetic sweep never looks at a pair that does not share a cylinder.
//!
//! **Safety net.** The argument above relies on the invariants of a valid partition
//! (at most two open cylinders per chain and side, one cylinder per key, the three wedges
//! found and distinct, the cross-section at 2π equal to the one at 0). They are checked
//! as the sweep goes; if one fails, [`free_bitangents`] returns the brute force instead
//! (and `build_by_sweep` replays it), so the result is the definition's in every case.

use alloc::vec::Vec;
use core::cmp::Ordering;

use super::bitangent::{bitangents, chain_bitangent, is_free};
use super::{cross_section, Bitangent, Bound, Chain, Corner, Interval};
use crate::geom::predicates::Direction;
use crate::geom::sos::{self, Angle, RankedPoint};
use crate::geom::Sign;
use crate::scene::{ObjectId, SceneRef};

/// All directed free bitangents of the scene, sorted by θ.
///
/// Cost: O((n + V) log(n + V)) for V free bitangents, times `|P|·|Q|` for the size of the
/// objects. Equal to [`free_bitangents_brute_force`] sorted by θ.
pub fn free_bitangents(scene: &SceneRef<'_>) -> Vec<Bitangent> {
    let mut out = Vec::new();
    match Kinetic::run(scene, &mut out) {
        Some(()) => out,
        None => free_bitangents_by_definition(scene),
    }
}

/// [`free_bitangents_brute_force`] sorted by θ: the kinetic sweep's fallback.
pub(crate) fn free_bitangents_by_definition(scene: &SceneRef<'_>) -> Vec<Bitangent> {
    let mut keyed: Vec<(Angle, Bitangent)> = free_bitangents_brute_force(scene)
        .into_iter()
        .map(|b| (b.angle(scene), b))
        .collect();
    keyed.sort_by(|a, b| a.0.cmp_angle(&b.0));
    keyed.into_iter().map(|(_, b)| b).collect()
}

/// The rotational sweep's events as the kinetic sweep meets them, in θ order, for a caller
/// that builds the partition on the way ([`kinetic_sweep`]). Cylinders are named by their
/// slot; a vertex's three opened cylinders take the slots of the three it closes. `None`
/// from a method stops the sweep.
pub(crate) trait Events {
    /// The cylinder at θ = 0 number `i` (in [`cross_section`] order, the `i`-th call) is
    /// open in `slot`.
    fn initial(&mut self, slot: u32, c: &Interval) -> Option<()>;
    /// The next vertex `b` closes the cylinders in slots `closed` (its top, bottom and
    /// left wedges) and opens the cylinders `opened` with their slots (right of the top
    /// wedge, right of the bottom wedge, the right wedge).
    fn vertex(
        &mut self,
        b: &Bitangent,
        closed: [u32; 3],
        opened: [(u32, Interval); 3],
    ) -> Option<()>;
    /// At θ = 2π: the cylinder open in `slot` continues the cylinder at θ = 0 number
    /// `initial` (called once for each, after the last vertex).
    fn wrap(&mut self, slot: u32, initial: usize) -> Option<()>;
}

/// Only the vertices: the free bitangents in θ order.
impl Events for Vec<Bitangent> {
    fn initial(&mut self, _: u32, _: &Interval) -> Option<()> {
        Some(())
    }
    fn vertex(&mut self, b: &Bitangent, _: [u32; 3], _: [(u32, Interval); 3]) -> Option<()> {
        self.push(*b);
        Some(())
    }
    fn wrap(&mut self, _: u32, _: usize) -> Option<()> {
        Some(())
    }
}

/// The kinetic sweep of [`free_bitangents`], reporting its events to `events`; `None` if an
/// invariant of the partition failed (or `events` stopped it) — the caller then falls back
/// to [`free_bitangents_by_definition`].
pub(crate) fn kinetic_sweep<E: Events>(scene: &SceneRef<'_>, events: &mut E) -> Option<()> {
    Kinetic::run(scene, events)
}

/// All directed free bitangents of the scene by the definition: every pair of objects
/// (in id order), its 8 bitangents ([`bitangents`]), each tested against every object
/// ([`is_free`]). Not sorted.
///
/// Cost: O(n³).
pub(crate) fn free_bitangents_brute_force(scene: &SceneRef<'_>) -> Vec<Bitangent> {
    let n = scene.len();
    let mut out = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            let (a, b) = (ObjectId(a as u32), ObjectId(b as u32));
            out.extend(bitangents(*scene, a, b).filter(|t| is_free(scene, t)));
        }
    }
    out
}

/// No cylinder in a chain slot; no heap position.
const EMPTY: u32 = u32::MAX;

/// A pinch candidate's direction as the heap compares it: the half-plane of θ and the
/// direction vector on the scene grid. Bit budget: scene coordinates have `|raw| < 2³⁰`
/// ([`Point`](crate::geom::Point) enforces it), so differences fit `i32` (`< 2³¹`),
/// products `< 2⁶²` and their difference `< 2⁶³`: exact in `i64`.
#[derive(Clone, Copy, Debug)]
struct Key {
    dx: i32,
    dy: i32,
    /// Whether θ lies in `[0, π)` (perturbed).
    upper: bool,
}

impl Key {
    /// [`Angle::cmp_angle`] of the two directions where the exact test decides it: the
    /// half-plane, then the sign of the cross product. `None` for exactly parallel
    /// directions, which only the perturbed comparison orders.
    #[inline(always)]
    fn cmp_exact(&self, other: &Key) -> Option<Ordering> {
        if self.upper != other.upper {
            return Some(if self.upper {
                Ordering::Less
            } else {
                Ordering::Greater
            });
        }
        let cross =
            i64::from(self.dx) * i64::from(other.dy) - i64::from(self.dy) * i64::from(other.dx);
        match cross.cmp(&0) {
            Ordering::Greater => Some(Ordering::Less),
            Ordering::Less => Some(Ordering::Greater),
            Ordering::Equal => None,
        }
    }

    /// θ coarsely, as the heap compares it first: non-decreasing in θ (in the order of
    /// [`Key::cmp_exact`], then the perturbed one), so that different values order two
    /// directions as exactly as the cross product and equal ones (rare) go to it. The
    /// direction turned into the upper half-plane, `(dx, dy)` with `dy ≥ 0`, has the
    /// "diamond angle" `t = (dy + |dx| − dx) / (dy + |dx|)`, increasing from 0 (θ = 0) to
    /// 2 (θ = π); the lower half-plane adds 2. The value is `⌊t · 2³⁰⌋`, exact integer
    /// division: the numerator is below 2³³·2³⁰ (differences below 2³¹), and `⌊·⌋` keeps
    /// the order. `None` for a zero direction (never for distinct vertices).
    fn coarse(&self) -> Option<u64> {
        let (dx, dy) = (i64::from(self.dx), i64::from(self.dy));
        let (dx, dy) = if self.upper { (dx, dy) } else { (-dx, -dy) };
        let den = u64::try_from(dy).ok()?.checked_add(dx.unsigned_abs())?;
        let num = u64::try_from(i64::try_from(den).ok()?.checked_sub(dx)?).ok()?;
        let t = (num << 30).checked_div(den)?;
        Some(if self.upper { t } else { t + (2 << 30) })
    }
}

/// A pinch candidate: the directed bitangent through `p`, then `q`.
#[derive(Clone, Copy, Debug)]
struct Event {
    p: RankedPoint,
    q: RankedPoint,
    key: Key,
    /// [`Key::coarse`].
    coarse: u64,
}

impl Event {
    /// `None` only for coordinates out of the scene range (never for a valid scene).
    fn new(scene: &SceneRef<'_>, p: usize, q: usize) -> Option<Event> {
        let (p, q) = (super::ranked(scene, p), super::ranked(scene, q));
        let d = |a: i32, b: i32| i32::try_from(i64::from(b) - i64::from(a)).ok();
        let (dx, dy) = (d(p.point.x(), q.point.x())?, d(p.point.y(), q.point.y())?);
        // The half-plane test of `cmp_angle`: the perturbed sign of dot((0, 1), q − p),
        // the sign of `dy` unless it is zero; never zero for distinct vertices.
        let upper = match dy.cmp(&0) {
            Ordering::Greater => true,
            Ordering::Less => false,
            Ordering::Equal => match sos::along(Direction { x: 0, y: 1 }, p, q) {
                Sign::Positive => true,
                Sign::Negative => false,
                Sign::Zero => q.point.x() > p.point.x(),
            },
        };
        let key = Key { dx, dy, upper };
        let coarse = key.coarse()?;
        Some(Event { p, q, key, coarse })
    }

    fn angle(&self) -> Angle {
        Angle::of_pair(self.p, self.q)
    }

    /// [`Angle::cmp_angle`] of the two directions, the exact test first; only exactly
    /// parallel directions go to the perturbed comparison.
    fn cmp_direction(&self, other: &Event) -> Ordering {
        self.key
            .cmp_exact(&other.key)
            .unwrap_or_else(|| self.angle().cmp_angle(&other.angle()))
    }
}

/// A queued candidate: its coarse direction ([`Key::coarse`]) and its cylinder slot (16
/// bytes, so that sifting touches only the heap array).
#[derive(Clone, Copy, Debug)]
struct Entry {
    coarse: u64,
    cylinder: u32,
}

/// The pinch candidates of the open cylinders: a binary min-heap indexed by cylinder slot,
/// so that the cylinder opened in a slot replaces the candidate of the one closed there.
///
/// Only live candidates are stored (at most one per slot, about 3n + 1), so the heap
/// stays small and in cache. (Lazy deletion would keep the ~2V candidates of cylinders
/// closed by a vertex on their arcs; a heap or bucket queue of that size spends its time
/// in cache misses: measured 2–3× slower on the grid scene.)
#[derive(Debug, Default)]
struct Heap {
    entries: Vec<Entry>,
    /// Per cylinder slot: its candidate's index in `entries`, or `EMPTY`.
    position: Vec<u32>,
    /// Per cylinder slot: its candidate, for equal coarse directions.
    events: Vec<Option<Event>>,
}

/// Queue order: θ, then the slot (a total order; equal θ means the same bitangent): the
/// coarse directions where they differ, else the candidates (`events`, by slot).
#[inline(always)]
fn before(events: &[Option<Event>], a: &Entry, b: &Entry) -> bool {
    if a.coarse != b.coarse {
        return a.coarse < b.coarse;
    }
    before_tied(events, a, b)
}

/// [`before`] for equal coarse directions (rare; out of line so that the sifting loops keep
/// their registers).
#[cold]
#[inline(never)]
fn before_tied(events: &[Option<Event>], a: &Entry, b: &Entry) -> bool {
    let event = |e: &Entry| events.get(e.cylinder as usize).copied().flatten();
    let theta = match (event(a), event(b)) {
        (Some(x), Some(y)) => x.cmp_direction(&y),
        _ => Ordering::Equal,
    };
    theta.then(a.cylinder.cmp(&b.cylinder)) == Ordering::Less
}

/// Puts `e` at index `i` of the heap and records its position.
#[inline(always)]
fn place(entries: &mut [Entry], position: &mut [u32], i: usize, e: Entry) {
    if let Some(slot) = entries.get_mut(i) {
        *slot = e;
    }
    if let Some(p) = position.get_mut(e.cylinder as usize) {
        *p = i as u32;
    }
}

impl Heap {
    /// Moves entry `i` up while it comes before its parent (≤ log₂ len steps), moving the
    /// parents down into the hole; returns its new index.
    fn sift_up(&mut self, mut i: usize) -> usize {
        let Heap {
            entries,
            position,
            events,
        } = self;
        let Some(&e) = entries.get(i) else {
            return i;
        };
        while i > 0 {
            let parent = (i - 1) / 2;
            match entries.get(parent) {
                Some(&p) if before(events, &e, &p) => {
                    place(entries, position, i, p);
                    i = parent;
                }
                _ => break,
            }
        }
        place(entries, position, i, e);
        i
    }

    /// Restores the heap order around entry `i`, whose key changed.
    fn sift(&mut self, i: usize) {
        if self.sift_up(i) == i {
            self.sift_down(i);
        }
    }

    /// Moves entry `i` down while a child comes before it (≤ log₂ len steps), moving the
    /// children up into the hole.
    fn sift_down(&mut self, mut i: usize) {
        let Heap {
            entries,
            position,
            events,
        } = self;
        let Some(&e) = entries.get(i) else {
            return;
        };
        loop {
            let l = 2 * i + 1;
            let Some(&left) = entries.get(l) else {
                break;
            };
            let (c, child) = match entries.get(l + 1) {
                Some(&right) if before(events, &right, &left) => (l + 1, right),
                _ => (l, left),
            };
            if !before(events, &child, &e) {
                break;
            }
            place(entries, position, i, child);
            i = c;
        }
        place(entries, position, i, e);
    }

    /// Sets the candidate of cylinder slot `slot` (`None`: none), replacing the one there.
    fn set(&mut self, slot: u32, event: Option<Event>) -> Option<()> {
        let s = slot as usize;
        if self.position.len() <= s {
            self.position.resize(s + 1, EMPTY);
            self.events.resize(s + 1, None);
        }
        *self.events.get_mut(s)? = event;
        let i = *self.position.get(s)?;
        match (i, event) {
            (EMPTY, None) => {}
            (EMPTY, Some(e)) => {
                let i = self.entries.len();
                u32::try_from(i).ok().filter(|&i| i != EMPTY)?;
                self.entries.push(Entry {
                    coarse: e.coarse,
                    cylinder: slot,
                });
                self.sift_up(i);
            }
            (i, Some(e)) => {
                let i = i as usize;
                self.entries.get_mut(i)?.coarse = e.coarse;
                self.sift(i);
            }
            (i, None) => {
                let i = i as usize;
                *self.position.get_mut(s)? = EMPTY;
                let last = self.entries.pop()?;
                if i < self.entries.len() {
                    place(&mut self.entries, &mut self.position, i, last);
                    self.sift(i);
                }
            }
        }
        Some(())
    }

    /// The earliest candidate and its cylinder slot.
    fn first(&self) -> Option<(u32, Event)> {
        let slot = self.entries.first()?.cylinder;
        Some((slot, (*self.events.get(slot as usize)?)?))
    }
}

/// The open cylinders, indexed by bottom and by top chain, and the heap of their pinch
/// candidates.
struct Kinetic<'s, 'a> {
    scene: &'s SceneRef<'a>,
    /// Per cylinder slot: the open cylinder as an interval (floor, ceiling, bottom and top
    /// chain). A vertex's three opened cylinders take the slots of the three it closes, so
    /// the table stays as large as the cross-section (3n + 1) and in cache.
    cylinders: Vec<Interval>,
    /// Per chain (`2·object + bound`): the open cylinders whose bottom arc is on it.
    by_bottom: Vec<[u32; 2]>,
    /// Per chain: the open cylinders whose top arc is on it.
    by_top: Vec<[u32; 2]>,
    heap: Heap,
    /// Per chain (`2·object + bound`): the last [`MEMO`] top chains asked for with it as
    /// bottom chain, and their [`chain_bitangent`].
    memo: Vec<[Memo; MEMO]>,
}

/// Pinch candidates remembered per bottom chain: a cylinder's pair of chains often comes
/// back a few vertices later (on the grid scene, a quarter of the pairs asked for are
/// among the last four on the same bottom chain).
const MEMO: usize = 4;

/// A remembered [`chain_bitangent`]: the top chain's index (`EMPTY`: none) and the tangent
/// vertices (`EMPTY`: no bitangent).
#[derive(Clone, Copy)]
struct Memo {
    top: u32,
    p: u32,
    q: u32,
}

fn chain_index(c: Chain) -> usize {
    2 * c.object.0 as usize + usize::from(c.bound == Bound::Upper)
}

impl<'s, 'a> Kinetic<'s, 'a> {
    /// Sweeps θ from 0 to 2π, reporting to `events`; `None` if an invariant of the
    /// partition failed.
    fn run<E: Events>(scene: &'s SceneRef<'a>, events: &mut E) -> Option<()> {
        let n = scene.len();
        let mut k = Kinetic {
            scene,
            cylinders: Vec::new(),
            by_bottom: alloc::vec![[EMPTY; 2]; 2 * n],
            by_top: alloc::vec![[EMPTY; 2]; 2 * n],
            heap: Heap::default(),
            memo: alloc::vec![
                [Memo {
                    top: EMPTY,
                    p: EMPTY,
                    q: EMPTY
                }; MEMO];
                2 * n
            ],
        };
        let key = |c: &Interval| (c.bottom, c.top, c.floor, c.ceiling);
        // The cylinders at θ = 0 with their slots, for the check at θ = 2π.
        let mut initial: Vec<(Interval, u32)> = Vec::new();
        for (i, iv) in cross_section(scene, &Angle::ZERO).into_iter().enumerate() {
            let slot = k.open_initial(iv)?;
            events.initial(slot, &iv)?;
            initial.push((iv, u32::try_from(i).ok()?));
        }
        // At most 8 directed bitangents per pair of objects, each found once (θ grows).
        let most = n.saturating_mul(n.saturating_sub(1)).saturating_mul(4);
        let mut vertices = 0usize;
        while let Some((cylinder, event)) = k.heap.first() {
            if vertices >= most {
                return None;
            }
            k.vertex(cylinder, &event, events)?;
            vertices += 1;
        }
        // θ = 2π: the cross-section is the one at θ = 0 again; with one cylinder per key,
        // sorting both pairs each open cylinder with the one at θ = 0 it continues.
        let mut last: Vec<(Interval, u32)> = k
            .cylinders
            .iter()
            .enumerate()
            .map(|(slot, c)| Some((*c, u32::try_from(slot).ok()?)))
            .collect::<Option<_>>()?;
        last.sort_unstable_by_key(|c| key(&c.0));
        initial.sort_unstable_by_key(|c| key(&c.0));
        if last.len() != initial.len() || last.iter().zip(&initial).any(|(a, b)| a.0 != b.0) {
            return None;
        }
        for ((_, slot), (_, i)) in last.iter().zip(&initial) {
            events.wrap(*slot, *i as usize)?;
        }
        Some(())
    }

    /// Opens cylinder `c` at θ = 0 in a new slot and queues its pinch candidate; returns
    /// its slot.
    fn open_initial(&mut self, c: Interval) -> Option<u32> {
        let id = u32::try_from(self.cylinders.len())
            .ok()
            .filter(|&i| i != EMPTY)?;
        for (chain, index) in [(c.bottom, &mut self.by_bottom), (c.top, &mut self.by_top)] {
            let Some(chain) = chain else { continue };
            let slot = index
                .get_mut(chain_index(chain))?
                .iter_mut()
                .find(|s| **s == EMPTY)?;
            *slot = id;
        }
        self.cylinders.push(c);
        self.check_keys(id)?;
        self.queue(id, None)?;
        Some(id)
    }

    /// Checks the sweep's keys at the open cylinder in `slot`: no other open cylinder on
    /// its bottom or top chain has its floor and ceiling.
    fn check_keys(&self, slot: u32) -> Option<()> {
        let c = self.cylinders.get(slot as usize)?;
        let same = |o: &Interval| o.floor == c.floor && o.ceiling == c.ceiling;
        for (chain, index) in [(c.bottom, &self.by_bottom), (c.top, &self.by_top)] {
            let Some(chain) = chain else { continue };
            let clash = index.get(chain_index(chain))?.iter().any(|&s| {
                s != EMPTY && s != slot && self.cylinders.get(s as usize).is_none_or(same)
            });
            if clash {
                return None;
            }
        }
        Some(())
    }

    /// Queues the pinch candidate of the cylinder in `slot` if that comes after `after`
    /// (the vertex at its left wall; `None`: θ = 0), in place of the slot's previous one.
    fn queue(&mut self, slot: u32, after: Option<&Event>) -> Option<()> {
        let c = *self.cylinders.get(slot as usize)?;
        let mut candidate = None;
        if let (Some(bottom), Some(top)) = (c.bottom, c.top) {
            if let Some((p, q)) = self.chain_bitangent(bottom, top)? {
                let e = Event::new(self.scene, p, q)?;
                let later = match after {
                    Some(v) => e.cmp_direction(v) == Ordering::Greater,
                    None => e.angle().cmp_angle(&Angle::ZERO) == Ordering::Greater,
                };
                candidate = later.then_some(e);
            }
        }
        self.heap.set(slot, candidate)
    }

    /// [`chain_bitangent`], remembered ([`MEMO`]); `None` for a chain out of range.
    fn chain_bitangent(&mut self, bottom: Chain, top: Chain) -> Option<Option<(usize, usize)>> {
        let memo = self.memo.get_mut(chain_index(bottom))?;
        let t = u32::try_from(chain_index(top)).ok()?;
        if let Some(m) = memo.iter().find(|m| m.top == t) {
            return Some((m.p != EMPTY).then_some((m.p as usize, m.q as usize)));
        }
        let b = chain_bitangent(self.scene, bottom, top);
        let index = |v: usize| u32::try_from(v).ok().filter(|&v| v != EMPTY);
        let [p, q] = match b {
            Some((p, q)) => [index(p)?, index(q)?],
            None => [EMPTY; 2],
        };
        memo.copy_within(..MEMO - 1, 1);
        if let Some(first) = memo.first_mut() {
            *first = Memo { top: t, p, q };
        }
        Some(b)
    }

    /// The open cylinder on `chain` (by bottom or top) whose floor and ceiling match the
    /// corner; among several, the smallest (floor, ceiling), as the sweep's ordered map.
    fn find(&self, by_top: bool, chain: Chain, corner: Corner, b: &Bitangent) -> Option<usize> {
        let index = if by_top {
            &self.by_top
        } else {
            &self.by_bottom
        };
        let [x, y] = *index.get(chain_index(chain))?;
        let face = |s: u32| {
            let c = *self.cylinders.get(s as usize)?;
            corner
                .matches(b, c.floor, c.ceiling)
                .then_some((s as usize, (c.floor, c.ceiling)))
        };
        match (face(x), face(y)) {
            (Some(x), Some(y)) => Some(if y.1 < x.1 { y.0 } else { x.0 }),
            (x, y) => x.or(y).map(|f| f.0),
        }
    }

    /// Processes the vertex of a pinch candidate as `build_by_sweep` does: closes its top,
    /// bottom and left wedges (the last is the candidate's cylinder) and opens the three
    /// cylinders right of it; reports it to `events`.
    fn vertex<E: Events>(&mut self, cylinder: u32, event: &Event, events: &mut E) -> Option<()> {
        let left_id = cylinder as usize;
        let left = *self.cylinders.get(left_id)?;
        let (cp, cq) = (left.bottom?, left.top?);
        let b = Bitangent {
            first_object: cp.object,
            first: (event.p.rank as usize).checked_sub(1)?,
            first_bound: cp.bound,
            second_object: cq.object,
            second: (event.q.rank as usize).checked_sub(1)?,
            second_bound: cq.bound,
        };
        let [top, bottom, left_corner, right] = Corner::wedges(&b);

        // Top wedge: bottom arc switches from Q's chain to P's.
        let t = self.find(false, cq, top, &b)?;
        // Bottom wedge: top arc switches from P's chain to Q's.
        let d = self.find(true, cp, bottom, &b)?;
        // Left wedge: the pinched cylinder itself.
        let l = self.find(false, cp, left_corner, &b)?;
        if l != left_id || t == d || t == l || d == l {
            return None;
        }
        let interval = |s: usize| self.cylinders.get(s).copied();
        let (ct, cd, cl) = (interval(t)?, interval(d)?, interval(l)?);

        // The right wedge's face, from the floors and ceilings just closed.
        let closed = [ct, cd, cl].map(|c| (c.floor, c.ceiling));
        let (floor, ceiling) = right.face(&b, closed)?;
        let opened = [
            Interval {
                bottom: Some(cp),
                ..ct
            },
            Interval {
                top: Some(cq),
                ..cd
            },
            Interval {
                floor,
                ceiling,
                bottom: Some(cq),
                top: Some(cp),
            },
        ];
        // Slot ids are below `EMPTY` (`open_initial`), so they fit `u32`.
        let [t, d, l] = [t, d, l].map(|s| s as u32);
        // The opened cylinders take the closed ones' slots: right of the top wedge l's,
        // right of the bottom wedge d's, the right wedge t's. Their bottom chains are those
        // of the closed cylinders in these slots (P's, d's, Q's), so the bottom-chain index
        // stays; their top chains (t's, Q's, P's) are those of t, l and d, so on those
        // chains the top-chain index moves t to l, l to d and d to t.
        let slots = [l, d, t];
        let chains = [ct.top, Some(cq), Some(cp)];
        for (k, &chain) in chains.iter().enumerate() {
            let Some(chain) = chain else { continue };
            // Each chain once (two of them may coincide).
            if chains.iter().take(k).any(|&c| c == Some(chain)) {
                continue;
            }
            for s in self.by_top.get_mut(chain_index(chain))? {
                *s = match *s {
                    x if x == t => l,
                    x if x == l => d,
                    x if x == d => t,
                    x => x,
                };
            }
        }
        for (slot, c) in slots.into_iter().zip(opened) {
            *self.cylinders.get_mut(slot as usize)? = c;
        }
        for slot in slots {
            self.check_keys(slot)?;
            self.queue(slot, Some(event))?;
        }
        events.vertex(
            &b,
            [t, d, l],
            [
                (slots[0], opened[0]),
                (slots[1], opened[1]),
                (slots[2], opened[2]),
            ],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point;
    use crate::scene::{Material, Scene};

    fn pt(x: i32, y: i32) -> Point {
        Point::from_raw(x << 16, y << 16).unwrap()
    }

    fn boxes(cols: i32, rows: i32, size: i32, gap: i32) -> Scene {
        let polys: Vec<Vec<Point>> = (0..cols)
            .flat_map(|i| (0..rows).map(move |j| (i, j)))
            .map(|(i, j)| {
                let (x, y) = (i * (size + gap), j * (size + gap));
                alloc::vec![
                    pt(x, y),
                    pt(x + size, y),
                    pt(x + size, y + size),
                    pt(x, y + size)
                ]
            })
            .collect();
        Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap()
    }

    fn sorted(scene: &SceneRef<'_>, mut v: Vec<Bitangent>) -> Vec<Bitangent> {
        v.sort_by(|a, b| a.angle(scene).cmp_angle(&b.angle(scene)));
        v
    }

    /// Random triangles, one per cell of a `c × c` grid, with vertices on a coarse lattice
    /// (many collinear triples and shared supporting lines across cells).
    fn coarse_grid(c: i32, seed: u64) -> Scene {
        let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let mut next = |m: i32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as i32
        };
        let mut polys = Vec::new();
        for k in 0..c * c {
            let (x0, y0) = (6 * (k % c), 6 * (k / c));
            loop {
                let t: Vec<Point> = (0..3)
                    .map(|_| pt(x0 + 1 + next(5), y0 + 1 + next(5)))
                    .collect();
                if Scene::new([(Material::Opaque, &t[..])]).is_ok() {
                    polys.push(t);
                    break;
                }
            }
        }
        Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap()
    }

    #[test]
    fn kinetic_sweep_matches_the_brute_force_on_coarse_random_grids() {
        for c in 1..=5 {
            for seed in 0..8 {
                let s = coarse_grid(c, seed);
                let s = s.as_ref();
                let mut fast = Vec::new();
                Kinetic::run(&s, &mut fast).expect("invariants hold");
                let slow = sorted(&s, free_bitangents_brute_force(&s));
                assert_eq!(fast, slow, "{c}x{c} seed {seed}");
            }
        }
    }

    /// The derived state the rotational sweep builds as it goes is the one every complex
    /// gets rebuilt (`Complex::new_owned`).
    #[test]
    fn sweep_borders_match_the_rebuilt_ones() {
        let scenes = (1..=5)
            .flat_map(|c| (0..4).map(move |seed| coarse_grid(c, seed)))
            .chain(
                [(1, 1, 2, 1), (3, 3, 2, 1), (4, 2, 3, 1)].map(|(c, r, s, g)| boxes(c, r, s, g)),
            );
        for scene in scenes {
            let s = scene.as_ref();
            let c = crate::partition::build_by_sweep(&s).expect("a valid scene");
            let rebuilt =
                crate::partition::Complex::new_owned(c.vertices.clone(), c.cylinders.clone(), &s);
            assert!(c.borders.same_as(&rebuilt.borders));
        }
    }

    /// [`Key::coarse`] never contradicts the exact order of [`Key::cmp_exact`], from small
    /// directions to the extremes of the bit budget (differences up to 2³¹ − 1), with both
    /// perturbed half-planes for horizontal directions.
    #[test]
    fn coarse_directions_keep_the_exact_order() {
        let m = (1i32 << 30) - 1;
        let sizes = [0, 1, 2, 3, 7, 1 << 20, m, 2 * m + 1];
        let mut keys = Vec::new();
        for &x in &sizes {
            for &y in &sizes {
                for (dx, dy) in [(x, y), (-x, y), (x, -y), (-x, -y)] {
                    let uppers: &[bool] = match dy.cmp(&0) {
                        Ordering::Greater => &[true],
                        Ordering::Less => &[false],
                        Ordering::Equal => &[true, false],
                    };
                    for &upper in uppers {
                        if (dx, dy) != (0, 0) {
                            keys.push(Key { dx, dy, upper });
                        }
                    }
                }
            }
        }
        for a in &keys {
            for b in &keys {
                let (ca, cb) = (a.coarse().unwrap(), b.coarse().unwrap());
                if let Some(o) = a.cmp_exact(b) {
                    if o == Ordering::Less {
                        assert!(ca <= cb, "{a:?} {b:?}");
                    }
                } else if a.dx.signum() == b.dx.signum() && a.dy.signum() == b.dy.signum() {
                    // The same direction: the same value.
                    assert_eq!(ca, cb, "{a:?} {b:?}");
                }
            }
        }
    }

    #[test]
    fn kinetic_sweep_matches_the_brute_force_on_collinear_lattices() {
        for (cols, rows, size, gap) in [(1, 1, 2, 1), (2, 1, 2, 1), (3, 3, 2, 1), (4, 2, 3, 1)] {
            let s = boxes(cols, rows, size, gap);
            let s = s.as_ref();
            let mut fast = Vec::new();
            Kinetic::run(&s, &mut fast).expect("invariants hold");
            let slow = sorted(&s, free_bitangents_brute_force(&s));
            assert_eq!(fast, slow, "{cols}x{rows}");
        }
    }
}
