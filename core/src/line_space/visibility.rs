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
//! * So the next vertex after θ is the earliest candidate among the open cylinders: pop
//!   it, close and open cylinders exactly as `build_by_sweep` does (closing takes a
//!   cylinder's candidate out of the heap), push the candidates of the new cylinders.
//!
//! Open cylinders are indexed by chain: at any θ a chain has at most two cylinders above
//! it and two below (one layer on the side where its object is not crossed, the layers
//! before and after the object on the other), so lookups are O(1) instead of a search.
//!
//! Every decision is one of the exact perturbed predicates of the brute force
//! ([`super::bitangent`]'s tangency test, [`Angle::cmp_angle`]); the heap orders by an
//! exact integer cross product and defers to `cmp_angle` on ties. No floats anywhere.
//!
//! Why not a grid of buckets: walking the segment of each candidate bitangent cell by cell
//! makes the freeness test cheap, but the candidates are still all O(n²) object pairs
//! (8·10⁶ for n = 4096) while the grid scene has about 100 vertices per object; the
//! kinetic sweep never looks at a pair that does not share a cylinder.
//!
//! **Safety net.** The argument above relies on the invariants of a valid partition
//! (at most two open cylinders per chain and side, one cylinder per key, the three wedges
//! found and distinct, the cross-section at 2π equal to the one at 0). They are checked
//! as the sweep goes; if one fails, [`free_bitangents`] returns the brute force instead,
//! so the result is the definition's in every case.

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
    Kinetic::run(scene).unwrap_or_else(|| {
        let mut keyed: Vec<(Angle, Bitangent)> = free_bitangents_brute_force(scene)
            .into_iter()
            .map(|b| (b.angle(scene), b))
            .collect();
        keyed.sort_by(|a, b| a.0.cmp_angle(&b.0));
        keyed.into_iter().map(|(_, b)| b).collect()
    })
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

/// The pinch candidate of the cylinder in slot `cylinder`: the directed bitangent through
/// `p`, then `q`.
#[derive(Clone, Copy, Debug)]
struct Event {
    p: RankedPoint,
    q: RankedPoint,
    cylinder: u32,
    /// Whether θ lies in `[0, π)` (perturbed).
    upper: bool,
}

impl Event {
    fn new(scene: &SceneRef<'_>, p: usize, q: usize, cylinder: u32) -> Event {
        let (p, q) = (super::ranked(scene, p), super::ranked(scene, q));
        // The half-plane test of `cmp_angle`: the perturbed sign of dot((0, 1), q − p),
        // never zero for distinct vertices.
        let upper = match sos::along(Direction { x: 0, y: 1 }, p, q) {
            Sign::Positive => true,
            Sign::Negative => false,
            Sign::Zero => q.point.x() > p.point.x(),
        };
        Event {
            p,
            q,
            cylinder,
            upper,
        }
    }

    fn angle(&self) -> Angle {
        Angle::of_pair(self.p, self.q)
    }

    /// [`Angle::cmp_angle`] of the two directions, fast path first: the same half-plane
    /// test, then the exact cross product of the scene-grid differences; only exactly
    /// parallel directions go to the perturbed comparison. Bit budget: scene coordinates
    /// have `|raw| < 2³⁰` ([`Point`](crate::geom::Point) enforces it), so differences are
    /// `< 2³¹`, products `< 2⁶²` and their difference `< 2⁶³`: exact in `i64`.
    fn cmp_direction(&self, other: &Event) -> Ordering {
        if self.upper != other.upper {
            return if self.upper {
                Ordering::Less
            } else {
                Ordering::Greater
            };
        }
        let d = |e: &Event| {
            (
                i64::from(e.q.point.x()) - i64::from(e.p.point.x()),
                i64::from(e.q.point.y()) - i64::from(e.p.point.y()),
            )
        };
        let ((ux, uy), (vx, vy)) = (d(self), d(other));
        match (ux * vy - uy * vx).cmp(&0) {
            Ordering::Greater => Ordering::Less,
            Ordering::Less => Ordering::Greater,
            Ordering::Equal => self.angle().cmp_angle(&other.angle()),
        }
    }

    /// Queue order: θ, then the slot (a total order; equal θ means the same bitangent).
    fn before(&self, other: &Event) -> bool {
        self.cmp_direction(other)
            .then(self.cylinder.cmp(&other.cylinder))
            == Ordering::Less
    }
}

/// The pinch candidates of the open cylinders: a binary min-heap indexed by cylinder slot,
/// so that a cylinder closed before its pinch takes its candidate out.
///
/// Only live candidates are stored (at most one per open cylinder, about 3n + 1), so the
/// heap stays small and in cache. (Lazy deletion would keep the ~2V candidates of
/// cylinders closed by a vertex on their arcs; a heap or bucket queue of that size spends
/// its time in cache misses: measured 2–3× slower on the grid scene.)
#[derive(Debug, Default)]
struct Heap {
    events: Vec<Event>,
    /// Per cylinder slot: its candidate's index in `events`, or `EMPTY`.
    position: Vec<u32>,
}

impl Heap {
    fn set_position(&mut self, i: usize) {
        if let Some(e) = self.events.get(i) {
            if let Some(p) = self.position.get_mut(e.cylinder as usize) {
                *p = i as u32;
            }
        }
    }

    fn before(&self, i: usize, j: usize) -> bool {
        match (self.events.get(i), self.events.get(j)) {
            (Some(a), Some(b)) => a.before(b),
            _ => false,
        }
    }

    fn swap(&mut self, i: usize, j: usize) {
        if i < self.events.len() && j < self.events.len() {
            self.events.swap(i, j);
            self.set_position(i);
            self.set_position(j);
        }
    }

    /// Moves entry `i` up while it comes before its parent (≤ log₂ len steps).
    fn sift_up(&mut self, mut i: usize) {
        while i > 0 {
            let parent = (i - 1) / 2;
            if !self.before(i, parent) {
                break;
            }
            self.swap(i, parent);
            i = parent;
        }
    }

    /// Moves entry `i` down while a child comes before it (≤ log₂ len steps).
    fn sift_down(&mut self, mut i: usize) {
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut first = i;
            if l < self.events.len() && self.before(l, first) {
                first = l;
            }
            if r < self.events.len() && self.before(r, first) {
                first = r;
            }
            if first == i {
                break;
            }
            self.swap(i, first);
            i = first;
        }
    }

    /// Inserts the candidate of a cylinder that has none.
    fn push(&mut self, e: Event) -> Option<()> {
        let slot = e.cylinder as usize;
        if self.position.len() <= slot {
            self.position.resize(slot + 1, EMPTY);
        }
        if self.position.get(slot).copied() != Some(EMPTY) {
            return None;
        }
        let i = self.events.len();
        u32::try_from(i).ok().filter(|&i| i != EMPTY)?;
        self.events.push(e);
        self.set_position(i);
        self.sift_up(i);
        Some(())
    }

    /// Takes out the candidate of cylinder slot `slot`, if any.
    fn remove(&mut self, slot: usize) -> Option<Event> {
        let i = *self.position.get(slot)?;
        if i == EMPTY {
            return None;
        }
        let i = i as usize;
        let last = self.events.len().checked_sub(1)?;
        self.swap(i, last);
        let e = self.events.pop()?;
        if let Some(p) = self.position.get_mut(slot) {
            *p = EMPTY;
        }
        if i < self.events.len() {
            self.sift_down(i);
            self.sift_up(i);
        }
        Some(e)
    }

    /// Takes out the earliest candidate.
    fn pop(&mut self) -> Option<Event> {
        let slot = self.events.first()?.cylinder as usize;
        self.remove(slot)
    }
}

/// A cylinder slot: the cylinder as an interval (floor, ceiling, bottom and top chain).
/// Slots of closed cylinders are reused, so the table stays as small as the cross-section
/// (about 3n + 1) and in cache.
#[derive(Clone, Copy, Debug)]
struct Slot {
    interval: Interval,
    open: bool,
}

/// The open cylinders, indexed by bottom and by top chain, and the heap of their pinch
/// candidates.
struct Kinetic<'s, 'a> {
    scene: &'s SceneRef<'a>,
    cylinders: Vec<Slot>,
    /// Slots of closed cylinders.
    free: Vec<u32>,
    /// Per chain (`2·object + bound`): the open cylinders whose bottom arc is on it.
    by_bottom: Vec<[u32; 2]>,
    /// Per chain: the open cylinders whose top arc is on it.
    by_top: Vec<[u32; 2]>,
    heap: Heap,
}

fn chain_index(c: Chain) -> usize {
    2 * c.object.0 as usize + usize::from(c.bound == Bound::Upper)
}

impl<'s, 'a> Kinetic<'s, 'a> {
    /// The vertices in θ order, or `None` if an invariant of the partition failed.
    fn run(scene: &'s SceneRef<'a>) -> Option<Vec<Bitangent>> {
        let n = scene.len();
        let mut k = Kinetic {
            scene,
            cylinders: Vec::new(),
            free: Vec::new(),
            by_bottom: alloc::vec![[EMPTY; 2]; 2 * n],
            by_top: alloc::vec![[EMPTY; 2]; 2 * n],
            heap: Heap::default(),
        };
        let mut initial: Vec<Interval> = cross_section(scene, &Angle::ZERO);
        for &iv in &initial {
            k.open_cylinder(iv, None)?;
        }
        // At most 8 directed bitangents per pair of objects, each found once (θ grows).
        let most = n.saturating_mul(n.saturating_sub(1)).saturating_mul(4);
        let mut out: Vec<Bitangent> = Vec::new();
        while let Some(event) = k.heap.pop() {
            if out.len() >= most {
                return None;
            }
            let vertex = k.vertex(&event)?;
            out.push(vertex);
        }
        // θ = 2π: the cross-section is the one at θ = 0 again.
        let key = |c: &Interval| (c.bottom, c.top, c.floor, c.ceiling);
        let mut last: Vec<Interval> = k
            .cylinders
            .iter()
            .filter(|c| c.open)
            .map(|c| c.interval)
            .collect();
        last.sort_unstable_by_key(key);
        initial.sort_unstable_by_key(key);
        (last == initial).then_some(out)
    }

    /// Opens a cylinder and queues its pinch candidate if that comes after `after` (the
    /// vertex at its left wall; `None`: θ = 0).
    fn open_cylinder(&mut self, c: Interval, after: Option<&Event>) -> Option<()> {
        let id = match self.free.last() {
            Some(&id) => id,
            None => u32::try_from(self.cylinders.len())
                .ok()
                .filter(|&i| i != EMPTY)?,
        };
        let same = |o: &Slot| o.interval.floor == c.floor && o.interval.ceiling == c.ceiling;
        for (chain, index) in [(c.bottom, &mut self.by_bottom), (c.top, &mut self.by_top)] {
            let Some(chain) = chain else { continue };
            let slots = index.get_mut(chain_index(chain))?;
            // One cylinder per (chain, floor, ceiling): the sweep's keys.
            let clash = slots
                .iter()
                .any(|&s| s != EMPTY && self.cylinders.get(s as usize).is_none_or(&same));
            let slot = slots.iter_mut().find(|s| **s == EMPTY);
            match (clash, slot) {
                (false, Some(slot)) => *slot = id,
                _ => return None,
            }
        }
        let slot = Slot {
            interval: c,
            open: true,
        };
        match self.free.pop() {
            Some(_) => *self.cylinders.get_mut(id as usize)? = slot,
            None => self.cylinders.push(slot),
        }
        if let (Some(bottom), Some(top)) = (c.bottom, c.top) {
            if let Some((p, q)) = chain_bitangent(self.scene, bottom, top) {
                let e = Event::new(self.scene, p, q, id);
                let later = match after {
                    Some(v) => e.cmp_direction(v) == Ordering::Greater,
                    None => e.angle().cmp_angle(&Angle::ZERO) == Ordering::Greater,
                };
                if later {
                    self.heap.push(e)?;
                }
            }
        }
        Some(())
    }

    fn close(&mut self, id: usize) -> Option<Interval> {
        let slot = self.cylinders.get_mut(id)?;
        if !slot.open {
            return None;
        }
        slot.open = false;
        let c = slot.interval;
        self.free.push(u32::try_from(id).ok()?);
        self.heap.remove(id);
        for (chain, index) in [(c.bottom, &mut self.by_bottom), (c.top, &mut self.by_top)] {
            let Some(chain) = chain else { continue };
            let slots = index.get_mut(chain_index(chain))?;
            let slot = slots.iter_mut().find(|s| **s as usize == id)?;
            *slot = EMPTY;
        }
        Some(c)
    }

    /// The open cylinder on `chain` (by bottom or top) whose floor and ceiling match the
    /// corner; among several, the smallest (floor, ceiling), as the sweep's ordered map.
    fn find(&self, by_top: bool, chain: Chain, corner: Corner, b: &Bitangent) -> Option<usize> {
        let index = if by_top {
            &self.by_top
        } else {
            &self.by_bottom
        };
        index
            .get(chain_index(chain))?
            .iter()
            .filter(|&&s| s != EMPTY)
            .filter_map(|&s| Some((s as usize, self.cylinders.get(s as usize)?.interval)))
            .filter(|(_, c)| corner.matches(b, c.floor, c.ceiling))
            .min_by_key(|(_, c)| (c.floor, c.ceiling))
            .map(|(s, _)| s)
    }

    /// Processes the vertex of a pinch candidate as `build_by_sweep` does: closes its top,
    /// bottom and left wedges (the last is the candidate's cylinder) and opens the three
    /// cylinders right of it.
    fn vertex(&mut self, event: &Event) -> Option<Bitangent> {
        let left_id = event.cylinder as usize;
        let left = self.cylinders.get(left_id).filter(|c| c.open)?.interval;
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
        let (ct, cd, cl) = (self.close(t)?, self.close(d)?, self.close(l)?);

        // The right wedge's face, from the floors and ceilings just closed.
        let closed = [ct, cd, cl].map(|c| (c.floor, c.ceiling));
        let (floor, ceiling) = right.face(&b, closed)?;
        self.open_cylinder(
            Interval {
                bottom: Some(cp),
                ..ct
            },
            Some(event),
        )?;
        self.open_cylinder(
            Interval {
                top: Some(cq),
                ..cd
            },
            Some(event),
        )?;
        self.open_cylinder(
            Interval {
                floor,
                ceiling,
                bottom: Some(cq),
                top: Some(cp),
            },
            Some(event),
        )?;
        Some(b)
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
                let fast = Kinetic::run(&s).expect("invariants hold");
                let slow = sorted(&s, free_bitangents_brute_force(&s));
                assert_eq!(fast, slow, "{c}x{c} seed {seed}");
            }
        }
    }

    #[test]
    fn kinetic_sweep_matches_the_brute_force_on_collinear_lattices() {
        for (cols, rows, size, gap) in [(1, 1, 2, 1), (2, 1, 2, 1), (3, 3, 2, 1), (4, 2, 3, 1)] {
            let s = boxes(cols, rows, size, gap);
            let s = s.as_ref();
            let fast = Kinetic::run(&s).expect("invariants hold");
            let slow = sorted(&s, free_bitangents_brute_force(&s));
            assert_eq!(fast, slow, "{cols}x{rows}");
        }
    }
}
