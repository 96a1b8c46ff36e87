//! Ray trees: the primary view, then what is seen through mirrors, refractive objects and
//! screens (DESIGN.md §6, the paper's §5), walked in lock step without allocating.
//!
//! See the module documentation of [`crate::walk`] for the model. Every run of a walk with
//! one ceiling is a *piece*: an exact open angular range of directions from an eye, with
//! the object seen. A piece is resolved by its ceiling's material:
//!
//! * nothing or an opaque object (or any object once the depth is used up): a leaf;
//! * a screen S: the same eye walks the same range anchored to the layer whose floor is S
//!   ([`super::Anchor::Floor`]); its pieces are resolved in turn at the same level;
//! * a mirror M: the range is split where the hit edge changes (the directions to M's
//!   vertices); per edge the eye is reflected across the edge's line, rounded
//!   ([`super::optics`]), and the reflected range is walked anchored to M — **clockwise**
//!   where the primary walk goes counter-clockwise: mirrors flip orientation;
//! * a refractive M: split by the entry edge, tangent-law eye at the entry edge, split by
//!   the exit edge (M's own vertices seen from that eye), tangent-law eye at the exit edge,
//!   walked anchored to M; orientation is preserved.
//!
//! **Lock step.** Each walk is resumable ([`super::Walker`]): one step per call. The
//! generations in use are a stack of *frames* in a fixed-capacity [`TreeScratch`] (the
//! primary walk, then per level a split of a mirror or refractive object and the walk
//! behind it, and a walk behind every screen on the way). The top frame yields its next
//! piece; the piece either is a leaf or pushes the frame that resolves it; an exhausted
//! frame is popped and its parent resumes. Every frame walks in the direction that maps to
//! counter-clockwise primary directions, so leaves come out in primary angular order, and
//! the whole tree is the sequence of leaves: each generation is advanced exactly as far as
//! the primary direction has moved. Nothing is buffered, nothing allocated, no recursion;
//! the RAM is the scratch (a formula of its capacity, [`TreeScratch`]) plus a bounded stack.
//!
//! Leaves with equal branches are merged into intervals as they come ([`Emitter`]); the
//! vertex of a boundary is resolved when the first leaf after it arrives, while the hops
//! it was made through are still on the stack.

#[cfg(feature = "alloc")]
use alloc::vec::Vec;
use core::cmp::Ordering;

use super::{Anchor, Position, Step, Trace, WalkError, Walker};
use crate::geom::predicates::Direction;
use crate::geom::sos::Angle;
use crate::geom::wide::{i128_to_f64 as to_f64, mod_p, residue_i128, Wide, P};
use crate::geom::{Point, QueryPoint, Sign};
use crate::partition::{Complex, CylinderId, Storage};
use crate::scene::{Material, ObjectId, SceneRef};
// Anchored walks (behind screens, mirrors and refractive objects).
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
use {
    crate::line_space::{object_ahead_of_query, ranked, Bound, Chain},
    crate::partition::{Cylinder, Layer, Side, Wall, NO_ARC_VERTEX},
};
// Changes of eye (mirrors and refractive objects).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
use super::optics;

mod mapped;
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
use mapped::HopChain;
use mapped::Mapped;
#[cfg(any(feature = "mirrors", feature = "refraction"))]
use mapped::Terms;

/// One interval of a ray-tree sweep: primary directions from `start` counter-clockwise to
/// the next interval's start, over which the branch is constant.
#[cfg(feature = "alloc")]
#[derive(Clone, Debug)]
pub struct TreeInterval {
    /// Primary angle of the start boundary in radians in `[0, 2π)`, for output: exact up
    /// to `f64` rounding for a primary boundary, mapped back through the hit edges in `f64`
    /// for a deeper one. `0.0` for a sweep without boundaries.
    pub start: f64,
    /// The exact primary direction of the start boundary, when the boundary is primary
    /// (caused by the view from the real eye or a split of a primary mirror/refractive
    /// object); `None` for deeper boundaries and for a sweep without boundaries.
    pub exact_start: Option<Angle>,
    /// Objects along the ray, primary first, screens left out, at most `depth + 1`.
    pub branch: Vec<ObjectId>,
    /// The vertex causing the start boundary (global index); `None` without boundaries.
    pub start_vertex: Option<usize>,
}

/// One interval of a ray tree as [`frame_tree_into`] streams it: [`TreeInterval`] with the
/// branch borrowed from the walk's scratch and without the boundary vertex.
#[derive(Clone, Copy, Debug)]
pub struct TreeSpan<'b> {
    /// Primary angle of the start boundary in radians in `[0, 2π)` (as
    /// `TreeInterval::start`); the first span starts at the range start.
    pub start: f64,
    /// The exact primary direction of the start boundary when it is primary.
    pub exact_start: Option<Angle>,
    /// Objects along the ray, primary first, screens left out.
    pub branch: &'b [ObjectId],
}

/// A range end: a direction from an eye, with the vertex it points at when it is the
/// direction of an eye–vertex pair. 32 bytes: a ray tree holds three per frame.
#[derive(Clone, Debug)]
struct Dir {
    angle: Angle,
    /// The vertex (global index) if `pointed`; indices fit (at most
    /// [`crate::scene::MAX_VERTICES`]).
    index: u32,
    pointed: bool,
    /// For an end placed in `f64` through a hop ([`Tree::map_end`]; `angle` is then
    /// rounded): the exact direction, so that events and vertices exactly on it are
    /// classified exactly (a vertex exactly on a mapped range end is a frequent
    /// degeneracy of grid scenes, `spurious_sliver_diagonal.rs`), as its index in the
    /// stack of exact directions ([`Stacks::exacts`] flattened: a [`Mapped`] each, 48
    /// bytes, so range ends, which are moved around a lot, do not carry them; two per hop,
    /// at most `4·MAX_TREE_DEPTH + 4`). `None` past `Wide`'s budget.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(dead_code)
    )]
    exact: Option<u8>,
}

impl Dir {
    fn vertex(angle: Angle, vertex: usize) -> Dir {
        match u32::try_from(vertex) {
            Ok(index) => Dir {
                angle,
                index,
                pointed: true,
                exact: None,
            },
            // Never: a scene has at most `MAX_VERTICES`.
            Err(_) => Dir::at(angle),
        }
    }

    fn at(angle: Angle) -> Dir {
        Dir {
            angle,
            index: 0,
            pointed: false,
            exact: None,
        }
    }

    fn of(s: &Step) -> Dir {
        match s.vertex {
            Some(v) => Dir::vertex(s.angle, v),
            None => Dir::at(s.angle),
        }
    }

    /// The vertex this end points at.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction")),
        allow(dead_code)
    )]
    fn points_at(&self) -> Option<u32> {
        self.pointed.then_some(self.index)
    }
}

/// The exact directions of the mapped range ends in use ([`Stacks::exacts`] flattened) and
/// what rebuilds them: the hops, and the scene's vertices.
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
#[derive(Clone, Copy)]
struct Ends<'e> {
    mapped: &'e [Mapped],
    chain: HopChain<'e>,
}

#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
impl<'e> Ends<'e> {
    /// `eye`: the primary eye, before the first of `hops`.
    fn new(
        mapped: &'e [Mapped],
        (eye, hops): (QueryPoint, &'e [Hop]),
        points: &'e [Point],
    ) -> Self {
        Ends {
            mapped,
            chain: HopChain { eye, hops, points },
        }
    }
}

/// Range ends against exact directions, for anchored walks and splits.
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
impl Dir {
    /// The sign of `cross(self, v)`: `Positive` if `v` lies counter-clockwise of this
    /// direction (within a half turn), exactly. Inlined: mostly without an exact direction,
    /// two single widening products (the callers' vectors are `i64`s widened).
    #[inline]
    fn turn(&self, ends: Ends<'_>, v: (i128, i128)) -> Sign {
        let mapped = self.exact.and_then(|i| ends.mapped.get(usize::from(i)));
        match mapped.and_then(|x| x.turn(ends.chain, v)) {
            Some(s) => s,
            None => Sign::of_i128(cross(self.angle.vector(), v)),
        }
    }

    /// Where the event direction `a`, met by a walk of a range in the direction `ccw`, lies
    /// against this range end in walk order: `Equal` exactly on it, `Less` before it,
    /// `Greater` after it (the walk's range is less than a half turn, so the side of the
    /// line decides). Without an exact direction only `Equal` is decided (`inside`
    /// otherwise: the walk itself orders events against an exact end).
    fn place(&self, ends: Ends<'_>, a: &Angle, inside: Ordering, ccw: bool) -> Ordering {
        if self.exact.is_none() {
            return if a.cmp_exact(&self.angle) == Ordering::Equal {
                Ordering::Equal
            } else {
                inside
            };
        }
        let ccw_order = match self.turn(ends, a.vector()) {
            Sign::Positive => Ordering::Greater,
            Sign::Zero => Ordering::Equal,
            Sign::Negative => Ordering::Less,
        };
        if ccw {
            ccw_order
        } else {
            ccw_order.reverse()
        }
    }
}

/// A boundary between pieces: its primary angle is computed from it ([`Tree::radians`])
/// only if it starts an interval. 56 bytes: a tree keeps one per frame.
///
/// Its vertex is found once the branches on both sides are known (the reference's rule):
/// among the stages of the ray at the boundary (the primary stage, then one per hop), the
/// first one whose ray, beyond its origin, holds a vertex of the object that stage hits on
/// either side; the vertex nearest to that stage's eye. Every stage is tested exactly,
/// earlier ones on the boundary direction mapped back through the hops in 1024-bit
/// integers ([`Tree::map_hop_exact`], up to 9 hops), later ones (where the boundary's own
/// stage holds none: a screen's event) mapped forward through the hops of the leaf after
/// the boundary ([`Tree::resolve_beyond`]); beyond that in `f64` with a relative
/// tolerance of 10⁻¹² (a tolerance took a vertex 6·10⁻¹³ rad off the ray,
/// `boundary_vertex_mirror_corner.rs`).
#[derive(Clone, Copy, Debug)]
struct Boundary {
    /// The number of hops up to the stage where the boundary arises: a prefix of the
    /// stack of hops that stays in place until the boundary is resolved (a byte, as in
    /// [`Level`]). The eye of that stage is the last of these hops' ([`Boundary::eye`]),
    /// not kept here (16 bytes; a frame holds a boundary).
    stage: u8,
    /// The direction of the boundary from the stage's eye (exact: the direction of a walk
    /// event or a range end from that eye).
    angle: Angle,
    /// Branch index of the object hit by that stage.
    level: u8,
    /// The vertex that caused the boundary, if no vertex is found by the rule: `fallback`
    /// where `falls_back` (two fields, as in [`Dir`]: an `Option<u32>` would pad the
    /// boundary from 48 to 56 bytes, and a frame holds one).
    fallback: u32,
    falls_back: bool,
}

impl Boundary {
    /// The eye of the boundary's stage, from the primary eye `q` and the stack of hops it
    /// lies on.
    fn eye(&self, q: QueryPoint, hops: &[Hop]) -> QueryPoint {
        eye_before(q, hops, self.stage.into())
    }

    /// The exact primary angle, for a boundary of the primary stage.
    fn exact(&self) -> Option<Angle> {
        (self.stage == 0).then_some(self.angle)
    }

    /// The direction from the stage's eye.
    fn dir(&self) -> (i128, i128) {
        self.angle.vector()
    }

    /// The vertex that caused the boundary, if any.
    fn fallback(&self) -> Option<u32> {
        self.falls_back.then_some(self.fallback)
    }
}

/// An exact open range of directions from an eye with the object seen over it, `from`
/// first in the walk's direction.
#[cfg_attr(
    not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
    allow(dead_code)
)]
#[derive(Clone)]
struct Piece {
    from: Dir,
    to: Dir,
    ceiling: Option<ObjectId>,
    boundary: Boundary,
}

impl Piece {
    /// A piece to overwrite ([`PrimaryWalk::next_piece`], [`RangeWalk::next_piece`]).
    fn empty() -> Piece {
        Piece {
            from: Dir::at(Angle::ZERO),
            to: Dir::at(Angle::ZERO),
            ceiling: None,
            boundary: Boundary {
                stage: 0,
                angle: Angle::ZERO,
                level: 0,
                fallback: 0,
                falls_back: false,
            },
        }
    }
}

/// One change of eye: a ray from the eye before it (`prev`: the last hop's `next` on the
/// stack, or the primary eye, [`eye_before`]; not kept, 16 bytes) hits the line of the
/// edge `a → b` (global vertex indices) and continues on a line through `next`; the stage
/// starting at it hits the object at its branch index (its level).
/// 24 bytes: a vertex index is below [`crate::scene::MAX_VERTICES`] = 2²⁶, so `a` keeps
/// the level (a branch index plus at most one, so at most `MAX_TREE_DEPTH + 2` < 2⁶) in its
/// top 6 bits, checked where a hop is made ([`Hop::new`]; a byte of its own would pad the
/// hop to 32 bytes).
#[derive(Clone, Copy, Debug)]
struct Hop {
    a_level: u32,
    b: u32,
    next: QueryPoint,
}

/// Bits of a vertex index in [`Hop::a_level`].
const HOP_VERTEX_BITS: u32 = 26;
const _: () = assert!(crate::scene::MAX_VERTICES <= 1 << HOP_VERTEX_BITS);
const _: () = assert!(MAX_TREE_DEPTH + 2 < 1 << (32 - HOP_VERTEX_BITS));

impl Hop {
    /// `None` if a vertex index is past [`crate::scene::MAX_VERTICES`] or the level past
    /// what the top bits hold.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction")),
        allow(dead_code)
    )]
    fn new((a, b): (usize, usize), next: QueryPoint, level: usize) -> Option<Hop> {
        let fits = |v: usize| v < 1 << HOP_VERTEX_BITS;
        if !fits(a) || !fits(b) || level >= 1 << (32 - HOP_VERTEX_BITS) {
            return None;
        }
        Some(Hop {
            a_level: (a | level << HOP_VERTEX_BITS) as u32,
            b: b as u32,
            next,
        })
    }

    fn a(&self) -> usize {
        (self.a_level & ((1 << HOP_VERTEX_BITS) - 1)) as usize
    }

    fn b(&self) -> usize {
        self.b as usize
    }

    /// Branch index of the object hit by the stage starting at this hop.
    fn level(&self) -> usize {
        (self.a_level >> HOP_VERTEX_BITS) as usize
    }
}

/// The eye before hop `i` of `hops`, the first of which leaves the eye `q`: the last hop's
/// `next`, or `q`.
#[inline]
fn eye_before(q: QueryPoint, hops: &[Hop], i: usize) -> QueryPoint {
    match i.checked_sub(1) {
        Some(j) => hops.get(j).map_or(q, |h| h.next),
        None => q,
    }
}

/// The scene-side context of a tree: the complex and the scene.
struct Tree<'a, 's, S: Storage> {
    complex: &'a Complex<S>,
    scene: &'a SceneRef<'s>,
}

/// A ray tree's working memory without a heap: the stack of frames (generations of traces
/// in lock step) — at most `W` walks and `S` splits — and the changes of eye (hops) held
/// at once, at most `H`. A tree needs one walk for the primary view, then per level of
/// depth a split and a walk (a mirror: its split and the reflected walk) or two splits and
/// a walk (a refractive object: entry split, exit split and the walk), plus a walk per
/// screen along the way: `W = depth + 1` and `S = depth` through mirrors, `S = 2·depth`
/// with refraction, and a few more walks for screens. Every split changes the eye once
/// and screens change none, so the default `H = S` always suffices. Deeper trees fail
/// with [`WalkError::TreeTooDeep`], never overflow; so do trees deeper than
/// [`MAX_TREE_DEPTH`]. Reused across trees. Size on x86-64:
/// `216·W + 72·S + 120·H + 280` bytes — walks of 216 bytes, splits of 72 (each in its
/// own stack: a split is smaller than a walk), per hop 24 bytes and the exact directions
/// of its two mapped range ends (96 bytes, [`Mapped`]), and the primary eye, the branch,
/// the start hints of anchored walks and the edge hints of splits
/// (`tree_scratch_is_bounded` in `tests/tests/no_alloc.rs` prints it and checks it).
pub struct TreeScratch<const W: usize, const S: usize = W, const H: usize = S> {
    stacks: Stacks<Fixed<W, S, H>>,
}

/// The stacks of a [`TreeScratch`]: `W` walks, `S` splits and `H` hops.
struct Fixed<const W: usize, const S: usize, const H: usize>;

/// Deepest ray tree a walk follows (the branch holds `MAX_TREE_DEPTH + 1` objects, as
/// [`crate::render::Branch`]).
pub const MAX_TREE_DEPTH: usize = 16;

/// Objects along a ray, primary first.
type Branch = heapless::Vec<ObjectId, { MAX_TREE_DEPTH + 1 }>;

/// Changes of eye a growing stack of frames holds at once: two per level (refraction).
#[cfg(feature = "alloc")]
const MAX_HOPS: usize = 2 * MAX_TREE_DEPTH;

/// The stacks of a tree in progress (fixed capacity, or vectors under `alloc`, as `F`
/// has them): the frames — walks and splits in their own stacks, in one order: a split
/// lies above the walks below its [`Split::walks`] — the hops and the branch down to the
/// top frame.
struct Stacks<F: Frames> {
    frames: FrameStacks<F>,
    /// The primary eye. A frame's eye is not kept in it: it is the eye after the last hop
    /// on the stack while the frame is on top ([`Stacks::eye`]).
    eye: QueryPoint,
    hops: F::Hops,
    branch: Branch,
    /// The exact directions of the range ends mapped through the hops, one [`ExactPair`]
    /// per hop ([`Tree::map_range`]), as many as hops at most (see [`Frames::Exacts`]).
    exacts: F::Exacts,
    /// The start cylinders last found by anchored walks ([`Tree::locate_floor`]).
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    floors: Floors,
    /// The edges the last splits started on.
    #[cfg(any(feature = "mirrors", feature = "refraction"))]
    edges: Edges,
    /// The places of frames that left the stack, held by others ([`Level::held`]): a
    /// stack of `W` walks holds `W` with these, as it would hold the walks themselves;
    /// and so for splits.
    held: (usize, usize),
}

/// Per floor object (direct-mapped by its id), the start cylinder of the last walk anchored
/// to it. Behind a refractive object the walks of neighbouring exit pieces (close virtual
/// eyes) mostly start in one cylinder: one exact containment test
/// ([`Tree::contains_after`]) confirms the hint instead of a climb of the object's sheet
/// (`mixed.json`: 59 % of the walks; behind mirrors 9 %, too few to pay for the test, so
/// they do not ask). Only a hint: the cylinder with floor `m` containing the turned line is
/// unique (a line leaves a convex object once), so a confirmed hint is the climb's answer.
/// A slot keeps only the cylinder, as its index plus one (4 bytes, and an empty slot is zero
/// bytes, so a static scratch needs no flash image): a hint for `m` is one whose floor is
/// `m`. Emptied with the other stacks at every tree (the scratch may change scenes).
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
type Floors = [Option<core::num::NonZeroU32>; FLOOR_HINTS];

/// Slots of [`Floors`].
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
const FLOOR_HINTS: usize = 16;

/// Per object split by its front edges (mirror, entry; direct-mapped by its id), the edge
/// (index in the object) the first piece of its last split started on: the next split of
/// the object (a neighbouring piece, a close eye) mostly starts on it too, and trying it
/// first spares the scan of the facing edges (−1.9 % instructions in the hall frame; 16
/// slots save no more). Only a hint ([`Cut::hint`]); emptied with the other stacks at
/// every tree.
#[cfg(any(feature = "mirrors", feature = "refraction"))]
type Edges = [Option<(ObjectId, EdgeIndex)>; EDGE_HINTS];

/// Slots of [`Edges`].
#[cfg(any(feature = "mirrors", feature = "refraction"))]
const EDGE_HINTS: usize = 8;

impl<F: Frames> Stacks<F> {
    const fn new(walks: F::Walks, splits: F::Splits, hops: F::Hops, exacts: F::Exacts) -> Self {
        Stacks {
            frames: FrameStacks { walks, splits },
            eye: QueryPoint::ORIGIN,
            hops,
            branch: heapless::Vec::new(),
            exacts,
            #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
            floors: [None; FLOOR_HINTS],
            #[cfg(any(feature = "mirrors", feature = "refraction"))]
            edges: [None; EDGE_HINTS],
            held: (0, 0),
        }
    }

    /// The eye of the top frame (or of the frame that just left it with its last piece,
    /// which leaves the hops as they are): hops are pushed right before the frame that
    /// owns them and popped with it, so the last one led to that frame's eye.
    #[inline(always)]
    fn eye(&self) -> QueryPoint {
        eye_before(self.eye, &self.hops, self.hops.len())
    }

    /// The lengths of the hop and branch stacks: where a boundary arises (its stage and
    /// level, [`Boundary`]).
    fn lengths(&self) -> Result<(u8, u8), WalkError> {
        let len = |n: usize| u8::try_from(n).map_err(|_| WalkError::TreeTooDeep);
        Ok((len(self.hops.len())?, len(self.branch.len())?))
    }

    /// [`WalkError::TreeTooDeep`] unless a frame of `level` fits beside the held places,
    /// with the places `level` holds: a split if `split`, else a walk.
    fn room(&self, level: Level, split: bool) -> Result<(), WalkError> {
        let (walks, splits) = level.held();
        let (walks, splits) = (walks + usize::from(!split), splits + usize::from(split));
        if self.frames.walks.room() < self.held.0.saturating_add(walks)
            || self.frames.splits.room() < self.held.1.saturating_add(splits)
        {
            return Err(WalkError::TreeTooDeep);
        }
        Ok(())
    }

    /// Takes the places `level` holds.
    fn hold(&mut self, level: Level) {
        let (walks, splits) = level.held();
        self.held = (self.held.0 + walks, self.held.1 + splits);
    }

    /// Pushes the walk `f` of `level`, which takes its held places too. Inlined, so that
    /// the frame is built in its slot: a call moves it there (a `memcpy` per push).
    #[inline(always)]
    fn push(&mut self, level: Level, f: Frame) -> Result<(), WalkError> {
        self.room(level, false)?;
        self.frames.walks.push(f)?;
        self.hold(level);
        Ok(())
    }

    /// Pushes the split `s` of `level` (`s.walks` is set here), as [`Stacks::push`].
    #[cfg(any(feature = "mirrors", feature = "refraction"))]
    #[inline(always)]
    fn push_split(&mut self, level: Level, mut s: Split) -> Result<(), WalkError> {
        self.room(level, true)?;
        s.walks = u16::try_from(self.frames.walks.len()).map_err(|_| WalkError::TreeTooDeep)?;
        self.frames.splits.push(s)?;
        self.hold(level);
        Ok(())
    }

    /// Pops the top frame of `level`, leaving what it pushed with it.
    fn leave(&mut self, level: Level) {
        self.frames.pop();
        let (walks, splits) = level.held();
        self.held = (
            self.held.0.saturating_sub(walks),
            self.held.1.saturating_sub(splits),
        );
    }

    /// Empties the stacks for a new tree from the primary eye `eye`.
    fn clear(&mut self, eye: QueryPoint) {
        self.eye = eye;
        self.frames.walks.clear();
        self.frames.splits.clear();
        self.held = (0, 0);
        self.hops.clear();
        self.branch.clear();
        self.exacts.truncate_to(0);
    }

    /// Pops the exhausted top frame of `level` and what it pushed with it.
    fn pop(&mut self, level: Level) {
        self.leave(level);
        self.restore(level);
    }

    /// Drops what the frame of `level` pushed with it.
    fn restore(&mut self, level: Level) {
        self.hops.truncate(level.hops.into());
        self.branch.truncate(level.branch.into());
        self.exacts.truncate_to(level.exacts.into());
    }
}

/// The storage of a tree's stacks: fixed capacity ([`Fixed`]) or vectors ([`Growing`]).
trait Frames {
    /// The stack of exact directions. Each entry is pushed by [`Tree::change_eye`] right
    /// before the one frame that owns it (its `Level::exacts` is the length below the
    /// entry) and popped with that frame, and the primary frame owns none: the stack never
    /// holds more entries than hops (nor hops than splits), so a capacity of `H` entries
    /// for `H` hops never overflows (two exact directions each).
    type Exacts: ExactStack;
    /// The stack of hops.
    type Hops: HopStack;
    /// The stack of walks.
    type Walks: FrameStack<Frame>;
    /// The stack of splits (empty without mirrors and refraction).
    type Splits: FrameStack<Split>;
}

/// A stack of frames of one kind.
trait FrameStack<T> {
    /// How many more fit.
    fn room(&self) -> usize;
    fn len(&self) -> usize;
    /// [`WalkError::TreeTooDeep`] when full.
    fn push(&mut self, f: T) -> Result<(), WalkError>;
    fn pop(&mut self);
    fn last_mut(&mut self) -> Option<&mut T>;
    fn clear(&mut self);
}

impl<T, const N: usize> FrameStack<T> for heapless::Vec<T, N> {
    fn room(&self) -> usize {
        N - self.as_slice().len()
    }
    fn len(&self) -> usize {
        self.as_slice().len()
    }
    fn push(&mut self, f: T) -> Result<(), WalkError> {
        heapless::Vec::push(self, f).map_err(|_| WalkError::TreeTooDeep)
    }
    fn pop(&mut self) {
        heapless::Vec::pop(self);
    }
    fn last_mut(&mut self) -> Option<&mut T> {
        <[T]>::last_mut(self)
    }
    fn clear(&mut self) {
        heapless::Vec::clear(self)
    }
}

// The `alloc` entry points grow the stacks as needed: fixed ones of the largest size would
// be moved and cleared on every call.
#[cfg(feature = "alloc")]
impl<T> FrameStack<T> for Vec<T> {
    fn room(&self) -> usize {
        usize::MAX
    }
    fn len(&self) -> usize {
        Vec::len(self)
    }
    fn push(&mut self, f: T) -> Result<(), WalkError> {
        Vec::push(self, f);
        Ok(())
    }
    fn pop(&mut self) {
        Vec::pop(self);
    }
    fn last_mut(&mut self) -> Option<&mut T> {
        <[T]>::last_mut(self)
    }
    fn clear(&mut self) {
        Vec::clear(self)
    }
}

/// The walks and splits of a tree, in one stack order: a split lies above the walks below
/// its [`Split::walks`] and below the others.
struct FrameStacks<F: Frames> {
    walks: F::Walks,
    splits: F::Splits,
}

impl<F: Frames> FrameStacks<F> {
    /// Whether the top frame is a split.
    fn split_on_top(&mut self) -> bool {
        #[cfg(any(feature = "mirrors", feature = "refraction"))]
        if let Some(s) = self.splits.last_mut() {
            return usize::from(s.walks) == self.walks.len();
        }
        false
    }

    /// The top frame.
    fn top(&mut self) -> Option<Top<'_>> {
        if self.split_on_top() {
            #[cfg(any(feature = "mirrors", feature = "refraction"))]
            return self.splits.last_mut().map(Top::Split);
        }
        self.walks.last_mut().map(Top::Walk)
    }

    fn pop(&mut self) {
        if self.split_on_top() {
            self.splits.pop();
        } else {
            self.walks.pop();
        }
    }
}

/// The top frame of a tree's stacks.
enum Top<'f> {
    Walk(&'f mut Frame),
    #[cfg(any(feature = "mirrors", feature = "refraction"))]
    Split(&'f mut Split),
}

/// The exact directions of the two ends of a range mapped through a hop, by the end's
/// position in the range: `Dir::exact` indexes the stack flattened, `2·entry + end`. A
/// slot no end points at (an end without one, or dropped by a collapse) is never read.
type ExactPair = [Mapped; 2];

/// A fresh entry of a stack of [`ExactPair`]s, and the directions below it, flattened.
type Reserved<'e> = (&'e mut ExactPair, &'e [Mapped]);

/// A stack of [`ExactPair`]s.
// Only mirrors and refraction push; with screens alone the stack stays empty.
#[cfg_attr(
    not(any(feature = "mirrors", feature = "refraction")),
    allow(dead_code)
)]
trait ExactStack {
    /// Pushes an entry, or [`WalkError::TreeTooDeep`] when full: the entry to fill in
    /// place and the directions below it, flattened.
    fn reserve(&mut self) -> Result<Reserved<'_>, WalkError>;
    fn truncate_to(&mut self, len: usize);
    fn entries(&self) -> &[ExactPair];
    /// All exact directions in order, as `Dir::exact` indexes them.
    fn flat(&self) -> &[Mapped] {
        self.entries().as_flattened()
    }
}

/// A stack of [`ExactPair`]s over `V`, whose popped entries stay as slots for the next
/// pushes (the stale directions of a reused slot are never read: an end points at its slot
/// only once written).
struct ExactSlots<V> {
    slots: V,
    len: usize,
}

impl<V> ExactSlots<V> {
    const fn new(slots: V) -> Self {
        ExactSlots { slots, len: 0 }
    }
}

/// Storage that grows by one zero entry ([`ExactSlots`]).
#[cfg_attr(
    not(any(feature = "mirrors", feature = "refraction")),
    allow(dead_code)
)]
trait Grow: core::ops::DerefMut<Target = [ExactPair]> {
    fn grow(&mut self) -> Result<(), WalkError>;
}

impl<const N: usize> Grow for heapless::Vec<ExactPair, N> {
    fn grow(&mut self) -> Result<(), WalkError> {
        self.push(ExactPair::default())
            .map_err(|_| WalkError::TreeTooDeep)
    }
}

#[cfg(feature = "alloc")]
impl Grow for Vec<ExactPair> {
    fn grow(&mut self) -> Result<(), WalkError> {
        self.push(ExactPair::default());
        Ok(())
    }
}

impl<V: Grow> ExactStack for ExactSlots<V> {
    fn reserve(&mut self) -> Result<Reserved<'_>, WalkError> {
        if self.len == self.slots.len() {
            self.slots.grow()?;
        }
        self.len += 1;
        split_top(self.slots.get_mut(..self.len).ok_or(WalkError::Corrupt)?)
    }
    fn truncate_to(&mut self, len: usize) {
        self.len = self.len.min(len);
    }
    fn entries(&self) -> &[ExactPair] {
        self.slots.get(..self.len).unwrap_or(&[])
    }
}

/// The top entry of `s`, and the directions below it.
#[cfg_attr(
    not(any(feature = "mirrors", feature = "refraction")),
    allow(dead_code)
)]
fn split_top(s: &mut [ExactPair]) -> Result<Reserved<'_>, WalkError> {
    let (top, below) = s.split_last_mut().ok_or(WalkError::Corrupt)?;
    Ok((top, below.as_flattened()))
}

impl<const W: usize, const S: usize, const H: usize> Frames for Fixed<W, S, H> {
    type Exacts = ExactSlots<heapless::Vec<ExactPair, H>>;
    type Hops = heapless::Vec<Hop, H>;
    type Walks = heapless::Vec<Frame, W>;
    type Splits = heapless::Vec<Split, S>;
}

/// The stacks of the `alloc` entry points.
#[cfg(feature = "alloc")]
struct Growing;

#[cfg(feature = "alloc")]
impl Frames for Growing {
    type Exacts = ExactSlots<Vec<ExactPair>>;
    type Hops = heapless::Vec<Hop, MAX_HOPS>;
    type Walks = Vec<Frame>;
    type Splits = Vec<Split>;
}

#[cfg(feature = "alloc")]
impl Stacks<Growing> {
    fn growing() -> Self {
        Stacks::new(
            Vec::new(),
            Vec::new(),
            heapless::Vec::new(),
            ExactSlots::new(Vec::new()),
        )
    }
}

/// A stack of [`Hop`]s, of fixed capacity.
// Only mirrors and refraction push.
#[cfg_attr(
    not(any(feature = "mirrors", feature = "refraction")),
    allow(dead_code)
)]
trait HopStack: core::ops::Deref<Target = [Hop]> {
    /// [`WalkError::TreeTooDeep`] when full.
    fn push(&mut self, hop: Hop) -> Result<(), WalkError>;
    fn truncate(&mut self, len: usize);
    fn clear(&mut self);
}

impl<const H: usize> HopStack for heapless::Vec<Hop, H> {
    fn push(&mut self, hop: Hop) -> Result<(), WalkError> {
        heapless::Vec::push(self, hop).map_err(|_| WalkError::TreeTooDeep)
    }
    fn truncate(&mut self, len: usize) {
        heapless::Vec::truncate(self, len)
    }
    fn clear(&mut self) {
        heapless::Vec::clear(self)
    }
}

impl<const W: usize, const S: usize, const H: usize> TreeScratch<W, S, H> {
    /// Empty scratch.
    pub const fn new() -> Self {
        TreeScratch {
            stacks: Stacks::new(
                heapless::Vec::new(),
                heapless::Vec::new(),
                heapless::Vec::new(),
                ExactSlots::new(heapless::Vec::new()),
            ),
        }
    }
}

impl<const W: usize, const S: usize, const H: usize> core::fmt::Debug for TreeScratch<W, S, H> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "TreeScratch<{W}, {S}, {H}>")
    }
}

impl<const W: usize, const S: usize, const H: usize> Default for TreeScratch<W, S, H> {
    fn default() -> Self {
        Self::new()
    }
}

/// A walk of the tree in progress (the other frames are [`Split`]s).
// Without a heap the variants cannot be boxed: a stack slot holds the largest.
#[allow(clippy::large_enum_variant)]
enum Frame {
    /// The primary walk over the range.
    Primary(PrimaryWalk),
    /// A walk anchored to a floor object behind a screen, mirror or refractive object.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    Walk(RangeWalk),
}

/// What every frame shares (its eye is [`Stacks::eye`] while it is on top): the depth left
/// to its pieces, its walking direction
/// (counter-clockwise primary directions map to `ccw` ones from its eye), the lengths of
/// the hop and branch stacks to restore when it is popped and the places it holds.
#[cfg_attr(
    not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
    allow(dead_code)
)]
#[derive(Clone, Copy)]
struct Level {
    /// At most `MAX_TREE_DEPTH + 1` ([`Tree::primary_walk`]); the stack lengths below are
    /// at most `2·MAX_TREE_DEPTH` hops and entries and `MAX_TREE_DEPTH + 1` objects
    /// ([`Level::marks`]): bytes, as a tree keeps a level per frame.
    depth: u8,
    ccw: bool,
    hops: u8,
    branch: u8,
    exacts: u8,
    /// The places of the walks and splits that left the stack with their last piece,
    /// which this frame continues: it stands for them in the stacks' capacity until it is
    /// popped (they would have been popped right after it) and restores the stacks as they
    /// would have. Walks may be many (screens), splits are at most two per level. Two
    /// fields, not a pair: a pair would pad the level to 32 bytes.
    held_walks: u16,
    held_splits: u8,
}

impl Level {
    /// The walks and splits whose places it holds.
    fn held(&self) -> (usize, usize) {
        (self.held_walks.into(), self.held_splits.into())
    }
}

#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
impl Level {
    /// `self` restoring the stacks as `sc` holds them now.
    fn marks<F: Frames>(self, sc: &Stacks<F>) -> Result<Level, WalkError> {
        let (hops, branch) = sc.lengths()?;
        Ok(Level {
            hops,
            branch,
            exacts: u8::try_from(sc.exacts.entries().len()).map_err(|_| WalkError::TreeTooDeep)?,
            held_walks: 0,
            held_splits: 0,
            ..self
        })
    }

    /// `self` also holding the place of the frame that leaves the stack: a split if
    /// `split`, else a walk.
    fn holding(self, split: bool) -> Result<Level, WalkError> {
        let (mut walks, mut splits) = (self.held_walks, self.held_splits);
        if split {
            splits = splits.checked_add(1).ok_or(WalkError::TreeTooDeep)?;
        } else {
            walks = walks.checked_add(1).ok_or(WalkError::TreeTooDeep)?;
        }
        Ok(Level {
            held_walks: walks,
            held_splits: splits,
            ..self
        })
    }
}

/// The primary walk restricted to the range `(f, t)` (exact positions: the lap of the walk
/// and the exact angle; `t` is on lap 1 when it does not lie after `f`).
struct PrimaryWalk {
    level: Level,
    events: Events,
    t: Angle,
    t_lap: u8,
    seen: Option<ObjectId>,
    /// The start of the current piece. Until an event after `f`, exactly on `f`'s ray (a
    /// vertex there, or `f`): it stands for `f` (a walk keeps no copy, 24 bytes; a tree
    /// keeps a walk per level).
    cur_from: Dir,
    cur_boundary: Boundary,
    /// Closing on an event exactly at `t` that changes the object: end at that event
    /// (the piece before a boundary, as the full tree has it) instead of at `t`.
    close_on_event: bool,
    /// Whether the walk closed on such an event (a primary boundary lies exactly on `t`).
    closed_on_boundary: bool,
    done: bool,
}

impl PrimaryWalk {
    /// What the walker follows: the primary eye `q` (the stacks', [`Stacks::eye`]), round
    /// past θ = 0 once more to reach `t`.
    fn trace(&self, q: QueryPoint) -> Trace {
        Trace::new(
            q,
            Anchor::Point,
            Some(Position {
                lap: 2,
                angle: Angle::ZERO,
            }),
        )
    }
}

/// A walk anchored to the floor `m` over the open range `(from, to)` in the frame's
/// direction.
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
struct RangeWalk {
    level: Level,
    /// `None` for a range collapsed onto one direction (one piece, no walk).
    events: Option<Events>,
    /// The floor the walk keeps, and the lap of its end `to` (the walker's [`Trace`]).
    m: ObjectId,
    end_lap: u8,
    to: Dir,
    seen: Option<ObjectId>,
    /// The start of the current piece; until `past_from`, the range's start `from` (no
    /// copy is kept: 32 bytes, and a tree keeps a walk per level), moved only onto `from`'s
    /// exact ray or, between the rounded and the exact start, only in its rounded angle.
    cur_from: Dir,
    cur_boundary: Boundary,
    /// An event strictly after `from` was met: the exact angles of events only grow along
    /// the walk, so every later one is after `from` too (no more [`Dir::place`] there).
    past_from: bool,
    done: bool,
}

/// How a split frame continues each edge piece.
#[cfg(any(feature = "mirrors", feature = "refraction"))]
#[derive(Clone, Copy, PartialEq, Eq)]
enum SplitKind {
    #[cfg(feature = "mirrors")]
    Mirror,
    #[cfg(feature = "refraction")]
    Entry(crate::scene::Eta),
    #[cfg(feature = "refraction")]
    Exit(crate::scene::Eta),
}

/// The range `(from, to)` from the frame's eye on `m` cut by `m`'s edges facing the eye
/// (mirror, entry) or facing away (exit), yielded in the frame's direction. Its first piece
/// is cut with the range at hand before the frame is pushed ([`Tree::first_edge`]), and
/// every later one starts strictly inside the range, where the last one ended: the frame
/// keeps neither the range's start nor its first boundary (64 bytes).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
struct Split {
    level: Level,
    cut: Cut,
    to: Dir,
    /// The walks below it in the stack order ([`Stacks::push_split`]).
    walks: u16,
}

/// No splits without mirrors and refraction.
#[cfg(not(any(feature = "mirrors", feature = "refraction")))]
enum Split {}

/// How far a split has cut its range: the object, how its pieces continue, the last edge
/// piece yielded. Apart from the range, which a split done with its first piece never
/// copies (it is the piece it was made from).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
#[derive(Clone, Copy)]
struct Cut {
    m: ObjectId,
    kind: SplitKind,
    /// The edge of the last edge piece yielded, as an [`EdgeIndex`] (4 bytes; a tree keeps
    /// a cut per split). The next piece is its neighbour's, which starts where it ended
    /// ([`Cut::next`]), so its start direction is not kept (16 bytes).
    last: Option<EdgeIndex>,
    /// An edge to try first for the first piece: taken if its piece starts at the start
    /// of the range (see [`Edges`]).
    hint: Option<EdgeIndex>,
    done: bool,
}

/// An edge of an object, its index in the object kept plus one in a `NonZeroU32`: 4 bytes
/// as an `Option` (a tree keeps two per split and a table of them), where an `Option<u32>`
/// takes 8. An object's edges are at most [`crate::scene::MAX_VERTICES`].
#[cfg(any(feature = "mirrors", feature = "refraction"))]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct EdgeIndex(core::num::NonZeroU32);

#[cfg(any(feature = "mirrors", feature = "refraction"))]
impl EdgeIndex {
    /// `None` past `u32::MAX − 1` (never for an object's edge).
    fn new(k: usize) -> Option<EdgeIndex> {
        let raw = u32::try_from(k).ok()?.checked_add(1)?;
        core::num::NonZeroU32::new(raw).map(EdgeIndex)
    }

    fn get(self) -> usize {
        (self.0.get() - 1) as usize
    }
}

/// An edge of an object: its vertices (global indices) in the object's order.
#[cfg(any(feature = "mirrors", feature = "refraction"))]
type Edge = (usize, usize);

/// An edge piece of a split's range: the edge (global vertex indices in `m`'s order) and
/// the vertices where its piece starts and ends in walk order (`None`: at the range's
/// start or end).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
struct EdgePiece {
    edge: Edge,
    start: Option<usize>,
    end: Option<usize>,
}

/// A resumable walk read one cluster of events at a time: the steps whose tangent vertex
/// lies on one exact ray (and, for the primary walk, on one lap).
struct Events {
    walker: Walker,
    peek: Option<Peeked>,
    /// Only steps that can change the primary view (tangent vertex ahead of the eye).
    ahead_only: bool,
    over: bool,
    /// The walker failed, with its only error ([`WalkError::Corrupt`]): kept here, so that
    /// a step is an `Option` and the error is checked once per cluster (−0.3 %
    /// instructions in the mixed frame); every later cluster reports it, as the walker would.
    failed: bool,
}

/// The step [`Events`] looked ahead to: the walker's last step, whose angle, cylinder and
/// lap the walker still holds (it takes no other until the step is read), so only the rest
/// is kept — 8 bytes, not a `Step`'s 56 with the lap: a tree keeps one per frame.
#[derive(Clone, Copy)]
struct Peeked {
    /// The step's vertex: a step that counts has one, kept as a `u32`.
    vertex: u32,
    ahead: bool,
    /// The step lies exactly at θ = 0 and the perturbation puts it just below 2π: its lap
    /// is the walker's plus one.
    wraps: bool,
}

impl Peeked {
    /// `None` for a step without a vertex or with one past `u32` (never: a scene has at
    /// most `MAX_VERTICES`).
    fn of(s: &Step, wraps: bool) -> Option<Peeked> {
        Some(Peeked {
            vertex: u32::try_from(s.vertex?).ok()?,
            ahead: s.ahead,
            wraps,
        })
    }

    /// The step and its lap, with what `walker` (which took it last) holds of it.
    fn step(&self, walker: &Walker) -> (Step, u8) {
        let (angle, cylinder) = walker.last_step();
        let step = Step {
            angle,
            vertex: Some(self.vertex as usize),
            ahead: self.ahead,
            cylinder,
        };
        (step, walker.lap() + u8::from(self.wraps))
    }
}

/// A cluster: the first and last step on one exact ray (in walk order) and its lap.
struct Cluster {
    first: Step,
    last: Step,
    lap: u8,
}

impl Cluster {
    /// A cluster to overwrite ([`Events::cluster`]).
    fn empty() -> Cluster {
        let none = Step {
            angle: Angle::ZERO,
            vertex: None,
            ahead: false,
            cylinder: CylinderId::from_raw(0),
        };
        Cluster {
            first: none,
            last: none,
            lap: 0,
        }
    }
}

impl Events {
    fn new(walker: Walker, ahead_only: bool) -> Events {
        Events {
            walker,
            peek: None,
            ahead_only,
            over: false,
            failed: false,
        }
    }

    /// The next step that counts from the walker (not `peek`), and whether it belongs to
    /// the lap after the walker's: a step exactly at θ = 0 that the perturbation puts just
    /// below 2π.
    /// Inlined into [`Events::next_cluster`]'s one call.
    #[inline(always)]
    fn step<S: Storage>(
        &mut self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
    ) -> Option<(Step, bool)> {
        while !self.over {
            let s = match self.walker.next_step(complex, scene, t) {
                Ok(Some(s)) => s,
                r => {
                    self.over = true;
                    self.failed = r.is_err();
                    break;
                }
            };
            if s.vertex.is_some() && (s.ahead || !self.ahead_only) {
                // `wraps` is a call: made only for a step exactly at θ = 0 (−0.1 %
                // instructions in the hall frame).
                let at_zero = s.angle.is_exactly_zero() && wraps(&s.angle);
                return Some((s, at_zero));
            }
        }
        None
    }

    /// The next cluster, written to `out` (two steps with their angles, which every move
    /// copies; kept out of the frames, which it would enlarge); `false` when there is none.
    #[inline(always)]
    fn cluster<S: Storage>(
        &mut self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
        out: &mut Cluster,
    ) -> Result<bool, WalkError> {
        // Over (every walk's last call; no step is peeked then, only while the walker goes
        // on): no call of the walk's body (−0.6 % instructions in the hall frame, −0.2 % in
        // mixed).
        if self.over {
            return if self.failed {
                Err(WalkError::Corrupt)
            } else {
                Ok(false)
            };
        }
        self.next_cluster(complex, scene, t, out)
    }

    /// [`Events::cluster`] while the walk goes on.
    fn next_cluster<S: Storage>(
        &mut self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
        out: &mut Cluster,
    ) -> Result<bool, WalkError> {
        // The step ending the last cluster is this one's first: taken here, not through
        // `step`, whose walker costs more than the step it returns.
        let mut open = match self.peek.take() {
            Some(p) => {
                let (first, lap) = p.step(&self.walker);
                *out = Cluster {
                    first,
                    last: first,
                    lap,
                };
                true
            }
            None => false,
        };
        // One call of `step`, inlined: the walker once, without a call per step (−1.2 %
        // instructions in the hall frame).
        while let Some((s, at_zero)) = self.step(complex, scene, t) {
            let l = self.walker.lap() + u8::from(at_zero);
            if !open {
                *out = Cluster {
                    first: s,
                    last: s,
                    lap: l,
                };
                open = true;
            } else if l == out.lap && s.angle.cmp_exact(&out.first.angle) == Ordering::Equal {
                out.last = s;
            } else {
                self.peek = Peeked::of(&s, at_zero);
                // A step it cannot keep (never) fails the walk rather than drop it.
                self.failed |= self.peek.is_none();
                self.over |= self.peek.is_none();
                break;
            }
        }
        if self.failed {
            return Err(WalkError::Corrupt);
        }
        Ok(open)
    }
}

/// Merges leaves into intervals as they come and hands each finished interval to the
/// sink, resolving its start vertex (if `vertices`) while the hops of its boundary are on
/// the stack.
struct Emitter<'k, K: FnMut(Interval<'_>)> {
    sink: &'k mut K,
    vertices: bool,
    /// The range start, where the first interval starts.
    f: Angle,
    /// The branch on the left of `f` (from the context piece), for the first vertex.
    left_of_f: Option<Branch>,
    current: Option<Pending>,
}

/// The interval being merged.
struct Pending {
    start: f64,
    exact_start: Option<Angle>,
    branch: Branch,
    start_vertex: Option<usize>,
}

/// A finished interval, handed to the sink.
#[cfg_attr(not(feature = "alloc"), allow(dead_code))]
struct Interval<'b> {
    start: f64,
    exact_start: Option<Angle>,
    branch: &'b [ObjectId],
    start_vertex: Option<usize>,
}

/// The ray trees from the free point `q` to depth `depth` over the full circle: intervals
/// sorted by start angle, each with its branch and the vertex causing its start boundary
/// (the last interval continues through θ = 0 into the first). Neighbouring intervals have
/// different branches. Build the complex over the whole scene, screens included.
///
/// Errors: `q` not free; a rounded virtual eye degenerate or out of range; an anchored
/// walk that finds no start cylinder (a rounded range end that misses the object's sheet);
/// a tree deeper than 16 levels with refraction at each ([`WalkError::TreeTooDeep`]).
///
/// Any storage: an owned complex, or one over caller slices (`Complex::from_slices`, e.g.
/// decoded by `format::decode_into`). The walk itself is [`frame_tree_into`]'s; this
/// collects its intervals (`alloc`).
#[cfg(feature = "alloc")]
pub fn ray_tree<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
) -> Result<Vec<TreeInterval>, WalkError> {
    // The full circle round from a primary boundary: a cut anywhere else (θ = 0) could
    // fall exactly on a deeper boundary, whose rule the cut would lose.
    let tree = Tree { complex, scene };
    let start = complex.trace_start(scene, q)?;
    let first = tree.first_boundary(q, start)?;
    let d = match &first {
        Some(b) => {
            let v = b.angle.vector();
            match (i64::try_from(v.0), i64::try_from(v.1)) {
                (Ok(x), Ok(y)) => Direction::new(x, y).ok_or(WalkError::Corrupt)?,
                _ => return Err(WalkError::Corrupt),
            }
        }
        // Nothing seen all around.
        None => Direction { x: 1, y: 0 },
    };
    let mut out = collect(complex, scene, (q, start), depth, (d, d), true, false)?;
    let left = out.last().map(|i| i.branch.clone()).unwrap_or_default();
    let several = out.len() > 1;
    match out.first_mut() {
        // A boundary of the primary walk where the branch stays (a screen appears): the
        // last interval continues through it.
        Some(i) if several && i.branch == left => {
            out.remove(0);
        }
        // The first interval starts on the boundary: its vertex is resolved against the
        // last interval, which ends there (the primary stage: no hops).
        Some(i) => {
            if let Some(b) = first {
                let rule = tree.event_boundary((0, 0), &b);
                i.exact_start = Some(b.angle);
                i.start_vertex = tree.resolve((q, &[]), &rule, &left, &i.branch);
            }
        }
        None => {}
    }
    match out.as_mut_slice() {
        // One branch all around: no boundary.
        [only] => {
            only.start = 0.0;
            only.exact_start = None;
            only.start_vertex = None;
        }
        all => all.sort_by(|a, b| a.start.total_cmp(&b.start)),
    }
    Ok(out)
}

/// The ray trees restricted to the primary directions counter-clockwise from `from` to
/// `to` (a field of view; `from == to` is the full circle starting at `from`), as
/// [`crate::walk::view_range`] restricts a view: the interval containing `from` starts at
/// `from` — its `start_vertex` is `None` unless a boundary of the full tree lies exactly on
/// `from` — and the others are the full tree's intervals whose start lies strictly inside
/// the range; a boundary exactly on `to` is left out. In counter-clockwise order from
/// `from`, like `view_range` (sorting by `f64` start angles could not place an interval
/// that starts within rounding of `from` at the far end of a full circle);
/// [`crate::render::angle_order`] rotates them into the start-angle order the renderer takes.
///
/// Only the primary pieces inside the range are followed through mirrors, refractive
/// objects and screens, so the secondary work is that of the field of view; the primary
/// walk starts at `from`, in the cylinder found through the objects on the line (no history
/// needed), or at θ = 0 where a vertex lies exactly on that line. The
/// vertex of the first interval needs the branch just before `from`: where a vertex lies
/// exactly on the ray at `from`, the piece before it is walked first.
#[cfg(feature = "alloc")]
pub fn ray_tree_range<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
    from: Direction,
    to: Direction,
) -> Result<Vec<TreeInterval>, WalkError> {
    let start = complex.trace_start(scene, q)?;
    collect(complex, scene, (q, start), depth, (from, to), true, true)
}

/// The ray tree over a field of view as a frame draws it: the intervals of
/// [`ray_tree_range`] without their boundary vertices (`start_vertex` is always `None`),
/// collected from [`frame_tree_into`].
#[cfg(feature = "alloc")]
pub fn frame_tree<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
    from: Direction,
    to: Direction,
) -> Result<Vec<TreeInterval>, WalkError> {
    let start = complex.trace_start(scene, q)?;
    collect(complex, scene, (q, start), depth, (from, to), false, false)
}

/// The intervals of the sweep from `q` (its θ = 0 cylinder `start`) over `range`, with
/// their vertices if `vertices` — the first one's (`context`) only when a full-tree
/// boundary may lie exactly on the range start.
#[cfg(feature = "alloc")]
fn collect<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    (q, start): (QueryPoint, CylinderId),
    depth: usize,
    range: (Direction, Direction),
    vertices: bool,
    context: bool,
) -> Result<Vec<TreeInterval>, WalkError> {
    let mut stacks = Stacks::growing();
    let mut out = Vec::new();
    let mut sink = |i: Interval<'_>| {
        out.push(TreeInterval {
            start: i.start,
            exact_start: i.exact_start,
            branch: i.branch.to_vec(),
            start_vertex: i.start_vertex,
        })
    };
    sweep(
        complex,
        scene,
        (q, start),
        depth,
        range,
        (vertices, context),
        &mut stacks,
        &mut sink,
    )?;
    Ok(out)
}

/// The ray tree over the primary directions counter-clockwise from `from` to `to` (the
/// intervals of [`ray_tree_range`] without vertices, as [`frame_tree`] collects them),
/// handed to `emit` one interval at a time in counter-clockwise order from `from`,
/// **without allocating**: the traces of all generations are walked in lock step in
/// `scratch` ([`TreeScratch`]). `from == to` is the full circle from `from`.
///
/// Errors as [`ray_tree`], and [`WalkError::TreeTooDeep`] when the tree needs more frames
/// or hops than `scratch` holds.
#[allow(clippy::too_many_arguments)]
pub fn frame_tree_into<T: Storage, const W: usize, const S: usize, const H: usize>(
    complex: &Complex<T>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
    from: Direction,
    to: Direction,
    scratch: &mut TreeScratch<W, S, H>,
    mut emit: impl FnMut(TreeSpan<'_>),
) -> Result<(), WalkError> {
    let start = complex.trace_start(scene, q)?;
    let mut sink = |i: Interval<'_>| {
        emit(TreeSpan {
            start: i.start,
            exact_start: i.exact_start,
            branch: i.branch,
        })
    };
    sweep(
        complex,
        scene,
        (q, start),
        depth,
        (from, to),
        (false, false),
        &mut scratch.stacks,
        &mut sink,
    )
}

#[allow(clippy::too_many_arguments)]
fn sweep<S: Storage, F: Frames, K: FnMut(Interval<'_>)>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    (q, start): (QueryPoint, CylinderId),
    depth: usize,
    (from, to): (Direction, Direction),
    (vertices, context): (bool, bool),
    scratch: &mut Stacks<F>,
    sink: &mut K,
) -> Result<(), WalkError> {
    let tree = Tree { complex, scene };
    let (f, t) = (Angle::constant(from), Angle::constant(to));
    scratch.clear(q);
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    {
        scratch.floors = [None; FLOOR_HINTS];
    }
    #[cfg(any(feature = "mirrors", feature = "refraction"))]
    {
        scratch.edges = [None; EDGE_HINTS];
    }
    let mut em = Emitter {
        sink,
        vertices,
        f,
        left_of_f: None,
        current: None,
    };
    // The branch just left of `from`, for the first interval's vertex: only where a vertex
    // lies exactly on the ray (else no boundary of the full tree can lie on it).
    if context && tree.any_vertex_on_ray(q, &f) {
        em.left_of_f = tree.left_of(scratch, q, start, depth, f)?;
    }
    let primary = tree.primary_walk(tree.primary_start(q, start, &f), depth, f, t, false);
    scratch.push(primary.level, Frame::Primary(primary))?;
    tree.drive(scratch, &mut em, (&mut Piece::empty(), false))?;
    em.finish();
    Ok(())
}

impl<S: Storage> Tree<'_, '_, S> {
    /// The primary walk over `(f, t)` from the cylinder `start` at the angle `theta` (the
    /// θ = 0 cylinder at θ = 0, or [`Tree::primary_start`]'s at `f`): lap 0 is the same
    /// unwrapped circle either way.
    fn primary_walk(
        &self,
        (start, theta): (CylinderId, Angle),
        depth: usize,
        f: Angle,
        t: Angle,
        close_on_event: bool,
    ) -> PrimaryWalk {
        // The walk may go round past θ = 0 once more to reach `t`.
        let walker = Walker::new(start, theta, true);
        // Deeper than `MAX_TREE_DEPTH` overflows the branch anyway (`TreeTooDeep`).
        let depth = u8::try_from(depth.min(MAX_TREE_DEPTH + 1)).unwrap_or(u8::MAX);
        PrimaryWalk {
            level: Level {
                depth,
                ccw: true,
                hops: 0,
                branch: 0,
                exacts: 0,
                held_walks: 0,
                held_splits: 0,
            },
            events: Events::new(walker, true),
            t,
            t_lap: u8::from(t.cmp_exact(&f) != Ordering::Greater),
            seen: self.complex.ceiling(start),
            cur_from: Dir::at(f),
            cur_boundary: Boundary {
                stage: 0,
                angle: f,
                level: 0,
                fallback: 0,
                falls_back: false,
            },
            close_on_event,
            closed_on_boundary: false,
            done: false,
        }
    }

    /// The first primary boundary from θ = 0 counter-clockwise (the first event of the
    /// first cluster of events on one exact ray where the object seen changes), if any.
    #[cfg(feature = "alloc")]
    fn first_boundary(&self, q: QueryPoint, start: CylinderId) -> Result<Option<Dir>, WalkError> {
        let zero = Angle::ZERO;
        let mut walk = self.primary_walk((start, zero), 0, zero, zero, false);
        let mut seen = self.complex.ceiling(start);
        let c = &mut Cluster::empty();
        let trace = walk.trace(q);
        while walk.events.cluster(self.complex, self.scene, &trace, c)? {
            // Round once (lap 1 holds the events at θ = 0 that end the first lap).
            if c.lap > 1 || (c.lap == 1 && c.first.angle.cmp_exact(&zero) != Ordering::Equal) {
                break;
            }
            let after = self.complex.ceiling(c.last.cylinder);
            if after != seen {
                return Ok(Some(Dir::of(&c.first)));
            }
            seen = after;
        }
        Ok(None)
    }

    /// The branch of the last leaf just before `f`: the piece of the primary walk that ends
    /// at `f` (the whole piece before a boundary exactly on `f`, else the containing one up
    /// to `f`), resolved alone. `None` when no boundary of the full tree can lie on `f`.
    fn left_of<F: Frames>(
        &self,
        scratch: &mut Stacks<F>,
        q: QueryPoint,
        start: CylinderId,
        depth: usize,
        f: Angle,
    ) -> Result<Option<Branch>, WalkError> {
        let mut walk = self.primary_walk((start, Angle::ZERO), depth, f, f, true);
        let mut last = Piece::empty();
        let mut any = false;
        let c = &mut Cluster::empty();
        while walk.next_piece(self, q, &mut last, c)? {
            any = true;
        }
        if !any {
            return Ok(None);
        }
        if !walk.closed_on_boundary && !self.vertex_on_ray(q, &f, last.ceiling) {
            return Ok(None);
        }
        let mut left: Option<Branch> = None;
        let mut keep = |i: Interval<'_>| left = heapless::Vec::from_slice(i.branch).ok();
        let mut em = Emitter {
            sink: &mut keep,
            vertices: false,
            f,
            left_of_f: None,
            current: None,
        };
        let fresh = self.resolve_piece(scratch, walk.level, &mut last, &mut em, false)?;
        self.drive(scratch, &mut em, (&mut last, fresh))?;
        em.finish();
        Ok(left)
    }

    /// Resolves pieces from the top frame until the stack is empty. Terminates: every
    /// walk is bounded by its walker, every split by its object's edges, and the stack by
    /// its capacity.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(unused_variables, unused_assignments)
    )]
    fn drive<F: Frames, K: FnMut(Interval<'_>)>(
        &self,
        sc: &mut Stacks<F>,
        em: &mut Emitter<'_, K>,
        (piece, mut fresh): (&mut Piece, bool),
    ) -> Result<(), WalkError> {
        let mut cluster = Cluster::empty();
        // `fresh`: the top frame was just pushed, its range and first boundary as `piece`
        // holds them: its first piece need not write what it shares with the range (the
        // usual piece behind a mirror is the whole range).
        loop {
            let (stage, level_len) = sc.lengths()?;
            let eye = sc.eye();
            let Some(top) = sc.frames.top() else {
                return Ok(());
            };
            // A piece is written in place and resolved by reference, an edge resolved where
            // it is made: every move of a piece (128 bytes) is a copy.
            match top {
                Top::Walk(Frame::Primary(w)) => {
                    let level = w.level;
                    fresh = if w.next_piece(self, eye, piece, &mut cluster)? {
                        self.resolve_piece(sc, level, piece, em, false)?
                    } else {
                        sc.pop(level);
                        false
                    };
                }
                #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
                Top::Walk(Frame::Walk(w)) => {
                    let level = w.level;
                    let (c, at) = (&mut cluster, (eye, stage, level_len));
                    fresh = if w.next_piece(
                        self,
                        Ends::new(sc.exacts.flat(), (sc.eye, &sc.hops), self.scene.vertices()),
                        at,
                        (piece, fresh),
                        c,
                    )? {
                        // Its last piece: the walk leaves the stack now.
                        let left = w.done;
                        if left {
                            sc.leave(level);
                        }
                        self.resolve_piece(sc, level, piece, em, left)?
                    } else {
                        sc.pop(level);
                        false
                    };
                }
                #[cfg(any(feature = "mirrors", feature = "refraction"))]
                Top::Split(s) => {
                    let (level, m, kind) = (s.level, s.cut.m, s.cut.kind);
                    let at = (eye, stage, level_len);
                    fresh = match s.next_edge(
                        self,
                        Ends::new(sc.exacts.flat(), (sc.eye, &sc.hops), self.scene.vertices()),
                        at,
                        piece,
                    )? {
                        // Done with its last edge piece, the split leaves the stack now.
                        Some(e) if s.cut.done => {
                            sc.leave(level);
                            self.change_eye(sc, level, m, kind, piece, e, true)?
                        }
                        Some(e) => self.change_eye(sc, level, m, kind, piece, e, false)?,
                        None => {
                            sc.pop(level);
                            false
                        }
                    };
                }
            }
        }
    }

    /// Resolves the piece `p` seen from the frame `level` by its ceiling's material: a leaf,
    /// or the frames that walk on behind it (`p` may be overwritten). `left`: the frame has
    /// left the stack with this, its last piece (sparing the driver a step); the stacks are
    /// restored as its pop would have, after a leaf or by the frame pushed in its place,
    /// which holds its place in the capacity. `true` if it pushed a frame (now the top) whose
    /// range and first boundary are `p`'s as left here.
    // Without any ray type past the primary view, every piece is a leaf.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(unused_variables, unreachable_code)
    )]
    fn resolve_piece<F: Frames, K: FnMut(Interval<'_>)>(
        &self,
        sc: &mut Stacks<F>,
        level: Level,
        p: &mut Piece,
        em: &mut Emitter<'_, K>,
        left: bool,
    ) -> Result<bool, WalkError> {
        let Some(c) = p.ceiling else {
            em.leaf(self, (sc.eye, &sc.hops), &sc.branch, &p.boundary)?;
            if left {
                sc.restore(level);
            }
            return Ok(false);
        };
        let material = self.scene.object(c).ok_or(WalkError::Corrupt)?.material;
        // A frame pushed here restores the stacks as they are now, or in place of `level`'s.
        #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
        let here = if left {
            level.holding(false)?
        } else {
            level.marks(sc)?
        };
        match material {
            #[cfg(feature = "screens")]
            Material::Screen => self
                .push_range_walk(sc, here, c, (&p.from, &p.to), &p.boundary, false)
                .map(|()| true),
            #[cfg(feature = "mirrors")]
            Material::Mirror if level.depth > 0 => self.split(sc, here, c, SplitKind::Mirror, p),
            #[cfg(feature = "refraction")]
            Material::Refractive { eta } if level.depth > 0 => {
                self.split(sc, here, c, SplitKind::Entry(eta), p)
            }
            // The ray type's code is compiled out (cargo features): an error, never a tree
            // that silently stops at the object.
            _ if continues(material, level.depth.into()) => Err(WalkError::RayTypeDisabled {
                object: c,
                material,
            }),
            _ => {
                sc.branch.push(c).map_err(|_| WalkError::TreeTooDeep)?;
                em.leaf(self, (sc.eye, &sc.hops), &sc.branch, &p.boundary)?;
                sc.branch.pop();
                if left {
                    sc.restore(level);
                }
                Ok(false)
            }
        }
    }

    /// The boundary made by a walk event at the given stage (hops) and level (branch index).
    fn event_boundary(&self, (stage, level): (u8, u8), d: &Dir) -> Boundary {
        Boundary {
            stage,
            angle: d.angle,
            level,
            fallback: d.index,
            falls_back: d.pointed,
        }
    }
}

impl PrimaryWalk {
    /// The next piece inside the range, in counter-clockwise order from `f`, seen from the
    /// primary eye `q`, written to `out`; `false` (and `out` untouched) when there is none.
    /// `c`: room for a cluster.
    fn next_piece<S: Storage>(
        &mut self,
        tree: &Tree<'_, '_, S>,
        q: QueryPoint,
        out: &mut Piece,
        c: &mut Cluster,
    ) -> Result<bool, WalkError> {
        if self.done {
            return Ok(false);
        }
        let trace = self.trace(q);
        loop {
            // The walk ends past `t` (on lap 2): `t` closes the last piece.
            if !self.events.cluster(tree.complex, tree.scene, &trace, c)? {
                self.done = true;
                out.from = self.cur_from.clone();
                out.to = Dir::at(self.t);
                out.ceiling = self.seen;
                out.boundary = self.cur_boundary;
                return Ok(true);
            }
            let after = tree.complex.ceiling(c.last.cylinder);
            // Against `f`, which `cur_from` stands for until the first event after it; later
            // events lie after `cur_from` too (they come in order, each on its own ray).
            let at_f = match c.lap.cmp(&0) {
                Ordering::Equal => c.first.angle.cmp_exact(&self.cur_from.angle),
                o => o,
            };
            match at_f {
                Ordering::Less => {
                    self.seen = after;
                    continue;
                }
                // On the opening ray: the state at the start; a change there is a boundary
                // of the full tree on `f`, which starts the first piece.
                Ordering::Equal => {
                    if after != self.seen {
                        self.cur_from = Dir::of(&c.last);
                        self.cur_boundary = tree.event_boundary((0, 0), &Dir::of(&c.first));
                    }
                    self.seen = after;
                    continue;
                }
                Ordering::Greater => {}
            }
            let at_t = match c.lap.cmp(&self.t_lap) {
                Ordering::Equal => c.first.angle.cmp_exact(&self.t),
                o => o,
            };
            if at_t != Ordering::Less {
                self.done = true;
                self.closed_on_boundary = at_t == Ordering::Equal && after != self.seen;
                out.from = self.cur_from.clone();
                out.to = if self.close_on_event && self.closed_on_boundary {
                    Dir::of(&c.first)
                } else {
                    Dir::at(self.t)
                };
                out.ceiling = self.seen;
                out.boundary = self.cur_boundary;
                return Ok(true);
            }
            if after != self.seen {
                out.from = core::mem::replace(&mut self.cur_from, Dir::of(&c.last));
                out.to = Dir::of(&c.first);
                out.ceiling = self.seen;
                out.boundary = core::mem::replace(
                    &mut self.cur_boundary,
                    tree.event_boundary((0, 0), &out.to),
                );
                self.seen = after;
                return Ok(true);
            }
        }
    }
}

impl<K: FnMut(Interval<'_>)> Emitter<'_, K> {
    /// A leaf: `branch` over the primary directions from `boundary` to the next leaf's.
    fn leaf<S: Storage>(
        &mut self,
        tree: &Tree<'_, '_, S>,
        hops: (QueryPoint, &[Hop]),
        branch: &[ObjectId],
        boundary: &Boundary,
    ) -> Result<(), WalkError> {
        let first = self.current.is_none();
        let left: Option<&[ObjectId]> = match &self.current {
            Some(c) if c.branch.as_slice() == branch => return Ok(()),
            Some(c) => Some(c.branch.as_slice()),
            None => self.left_of_f.as_deref(),
        };
        let start_vertex = match left {
            Some(left) if self.vertices && left != branch => {
                tree.resolve(hops, boundary, left, branch)
            }
            _ => None,
        };
        let next = Pending {
            start: if first {
                self.f.radians()
            } else {
                tree.radians(hops, boundary)
            },
            exact_start: if first {
                Some(self.f)
            } else {
                boundary.exact()
            },
            branch: heapless::Vec::from_slice(branch).map_err(|_| WalkError::TreeTooDeep)?,
            start_vertex,
        };
        if let Some(done) = self.current.replace(next) {
            (self.sink)(Interval {
                start: done.start,
                exact_start: done.exact_start,
                branch: &done.branch,
                start_vertex: done.start_vertex,
            });
        }
        Ok(())
    }

    /// Hands over the last interval.
    fn finish(&mut self) {
        if let Some(done) = self.current.take() {
            (self.sink)(Interval {
                start: done.start,
                exact_start: done.exact_start,
                branch: &done.branch,
                start_vertex: done.start_vertex,
            });
        }
    }
}

impl<S: Storage> Tree<'_, '_, S> {
    fn point(&self, i: usize) -> Point {
        self.scene.vertices().get(i).copied().unwrap_or_default()
    }

    fn qpoint(&self, i: usize) -> QueryPoint {
        self.point(i).to_query()
    }

    /// Whether a vertex that can make a primary-level boundary lies exactly on the ray from
    /// `q` at `f`: one of `ceiling` (mirror and refraction splits), or any vertex if
    /// `ceiling` is a screen (events of the walk behind it).
    fn vertex_on_ray(&self, q: QueryPoint, f: &Angle, ceiling: Option<ObjectId>) -> bool {
        let Some(obj) = ceiling.and_then(|c| self.scene.object(c)) else {
            return false;
        };
        if obj.material == Material::Screen {
            return self.any_vertex_on_ray(q, f);
        }
        self.on_ray(q, f, obj.first_vertex()..obj.first_vertex() + obj.len())
    }

    /// Whether any vertex of the scene lies exactly on the ray from `q` at `f` (every
    /// primary event at `f` is the direction to such a vertex).
    fn any_vertex_on_ray(&self, q: QueryPoint, f: &Angle) -> bool {
        self.on_ray(q, f, 0..self.scene.vertices().len())
    }

    /// Bit budget: |d| ≤ 2⁶³, |v − q| ≤ 2⁵⁴: products < 2¹¹⁸, exact in `i128`.
    fn on_ray(&self, q: QueryPoint, f: &Angle, vertices: core::ops::Range<usize>) -> bool {
        let d = f.vector();
        vertices.into_iter().any(|v| {
            let w = diff(self.qpoint(v), q);
            cross(d, w) == 0 && d.0 * w.0 + d.1 * w.1 > 0
        })
    }

    /// The primary angle (radians, `f64`) of a boundary: its direction intersected with
    /// each hop's edge line, continued from the previous eye (`q`, the primary eye, and
    /// the stack of hops).
    fn radians(&self, (q, hops): (QueryPoint, &[Hop]), rule: &Boundary) -> f64 {
        let d = self.map_dir(
            (q, hops.get(..rule.stage.into()).unwrap_or(hops)),
            rule.eye(q, hops),
            rule.dir(),
        );
        let a = libm::atan2(d.1, d.0);
        let tau = 2.0 * core::f64::consts::PI;
        if a < 0.0 {
            let a = a + tau;
            if a >= tau {
                0.0
            } else {
                a
            }
        } else {
            a
        }
    }

    /// The direction `dir` from `eye` after the hops `hops`, mapped back to a direction
    /// from the eye `first` before them (`f64`). Per hop the hit point `X = cur + t·d` on the
    /// edge's line is taken relative to the previous eye as `(cur − prev) + t·d`, with the
    /// numerator of `t` exact: no term is much larger than the result, so an eye next to
    /// the edge loses no precision (`X − prev` as `(a − prev) + u·(b − a)` cancels there).
    fn map_dir(
        &self,
        (first, hops): (QueryPoint, &[Hop]),
        eye: QueryPoint,
        dir: (i128, i128),
    ) -> (f64, f64) {
        let mut d = (to_f64(dir.0), to_f64(dir.1));
        let mut cur = eye;
        let mut rest = hops;
        while let Some((hop, before)) = rest.split_last() {
            let prev = before.last().map_or(first, |h| h.next);
            let (a, b) = (self.qpoint(hop.a()), self.qpoint(hop.b()));
            let e = diff(b, a);
            let ef = (to_f64(e.0), to_f64(e.1));
            let den = d.0 * ef.1 - d.1 * ef.0;
            d = if den == 0.0 {
                // Along the edge's line: its midpoint.
                let ap = diff(a, prev);
                (to_f64(ap.0) + 0.5 * ef.0, to_f64(ap.1) + 0.5 * ef.1)
            } else {
                let t = to_f64(cross(diff(a, cur), e)) / den;
                let cp = diff(cur, prev);
                (to_f64(cp.0) + t * d.0, to_f64(cp.1) + t * d.1)
            };
            (cur, rest) = (prev, before);
        }
        d
    }

    /// The vertex of the boundary of `rule` between the branches `left` and `right`; `q` is
    /// the primary eye and `hops` the stack of hops, of which the rule's stage is a prefix.
    /// Out of line: its 1024-bit tables (3.4 KiB) would otherwise take stack in every
    /// caller, even in the walks that resolve no vertex (frames).
    #[inline(never)]
    fn resolve(
        &self,
        (q, hops): (QueryPoint, &[Hop]),
        rule: &Boundary,
        left: &[ObjectId],
        right: &[ObjectId],
    ) -> Option<usize> {
        let all = hops;
        let hops = hops.get(..rule.stage.into())?;
        let rule_eye = rule.eye(q, hops);
        let stages = hops.len();
        // The boundary direction at every earlier stage modulo P, mapped back hop by hop
        // once: most stages hold no candidate vertex on the ray, which different residues
        // prove; the 1024-bit mapping is made only when a candidate passes.
        let mut residues = [None::<(u64, u64)>; MAX_STAGES];
        let dir = rule.dir();
        let mut r = Some((residue_i128(dir.0), residue_i128(dir.1)));
        for st in (0..stages).rev() {
            let prev = eye_before(q, hops, st);
            r = r.and_then(|r| self.map_hop_residue((prev, hops.get(st)?), r));
            if let Some(slot) = residues.get_mut(st) {
                *slot = r;
            }
        }
        let mut mapped: Option<[Option<(Wide, Wide)>; MAX_STAGES]> = None;
        for st in 0..=stages {
            let (eye, level, origin) = match st.checked_sub(1).and_then(|i| hops.get(i)) {
                None => (q, 0, None),
                Some(h) => (h.next, h.level(), Some((h.a(), h.b()))),
            };
            let level = if st == stages {
                rule.level.into()
            } else {
                level
            };
            let owners = [left.get(level).copied(), right.get(level).copied()];
            let candidates = self.stage_candidates(eye, origin, owners);
            let later = hops.get(st..).unwrap_or(&[]);
            if later.is_empty() {
                // The stage where the boundary arises: `i128` suffices (products < 2¹⁰⁸).
                let best = nearest_on_ray(candidates, |v| {
                    let w = diff(self.qpoint(v), eye);
                    (cross(dir, w) == 0).then_some(dir.0 * w.0 + dir.1 * w.1)
                });
                return best
                    .or_else(|| self.resolve_beyond((q, all), rule, left, right))
                    .or(rule.fallback().map(|v| v as usize));
            }
            // Different residues of `cross(d, w)`'s two products prove it nonzero.
            if let Some(&Some((r0, r1))) = residues.get(st) {
                let m = |a: u64, b: i128| mod_p(u128::from(a) * u128::from(residue_i128(b)));
                let mut on_ray = candidates.clone().filter(|&v| {
                    let w = diff(self.qpoint(v), eye);
                    m(r0, w.1) == m(r1, w.0)
                });
                if on_ray.next().is_none() {
                    continue;
                }
            }
            let mapped = mapped.get_or_insert_with(|| self.map_exact((q, hops), rule));
            let best = match mapped.get(st).and_then(Option::as_ref) {
                Some(d) => self.nearest_on_exact_ray(candidates, eye, d),
                None => {
                    // Past the exact budget (more hops than `Wide` holds): `f64`.
                    let d = self.map_dir((eye, later), rule_eye, rule.dir());
                    nearest_on_ray(candidates, |v| {
                        let w = diff(self.qpoint(v), eye);
                        let wf = (to_f64(w.0), to_f64(w.1));
                        let c = d.0 * wf.1 - d.1 * wf.0;
                        let scale = libm::hypot(d.0, d.1) * libm::hypot(wf.0, wf.1);
                        (libm::fabs(c) <= 1e-12 * scale).then_some(d.0 * wf.0 + d.1 * wf.1)
                    })
                }
            };
            if best.is_some() {
                return best;
            }
        }
        rule.fallback().map(|v| v as usize)
    }

    /// The boundary direction of `rule` (from the eye after `hops`, which leave the primary
    /// eye `q`) at every stage before the last, mapped back hop by hop exactly
    /// ([`Tree::map_hop_exact`]); `None` past `Wide`'s budget.
    fn map_exact(
        &self,
        (q, hops): (QueryPoint, &[Hop]),
        rule: &Boundary,
    ) -> [Option<(Wide, Wide)>; MAX_STAGES] {
        let mut mapped = [None; MAX_STAGES];
        let (x, y) = rule.dir();
        let mut d = Some((Wide::from_i128(x), Wide::from_i128(y)));
        for st in (0..hops.len()).rev() {
            let prev = eye_before(q, hops, st);
            d = d.and_then(|d| self.map_hop_exact((prev, hops.get(st)?), &d));
            if let Some(slot) = mapped.get_mut(st) {
                *slot = d;
            }
        }
        mapped
    }
    /// [`Tree::resolve`] past the stage where the boundary arises, when that stage holds no
    /// vertex of the objects its ray hits (the event was a screen's vertex, and screens
    /// are in no branch): the reference's rule reads the ray on, stage by stage, so the
    /// boundary direction is mapped forward exactly through the hops of the leaf after the
    /// boundary (`hops` past the rule's stage: still on the stack, and its chain holds at
    /// the boundary, where that leaf starts). `None` if no stage has a candidate on its ray,
    /// or past `Wide`'s budget.
    fn resolve_beyond(
        &self,
        (q, hops): (QueryPoint, &[Hop]),
        rule: &Boundary,
        left: &[ObjectId],
        right: &[ObjectId],
    ) -> Option<usize> {
        let (x, y) = rule.dir();
        let mut d = (Wide::from_i128(x), Wide::from_i128(y));
        let stage = usize::from(rule.stage);
        for (i, hop) in hops.iter().enumerate().skip(stage) {
            d = self.map_hop_forward((eye_before(q, hops, i), hop), &d)?;
            let owners = [
                left.get(hop.level()).copied(),
                right.get(hop.level()).copied(),
            ];
            let candidates = self.stage_candidates(hop.next, Some((hop.a(), hop.b())), owners);
            let best = self.nearest_on_exact_ray(candidates, hop.next, &d);
            if best.is_some() {
                return best;
            }
        }
        None
    }

    /// The vertices of the objects a stage of a boundary's ray hits on either side
    /// (`owners`, one object looked at once), beyond the stage's origin edge (a ray leaving
    /// a mirror or refractive edge; global vertex indices) seen from the stage's eye.
    fn stage_candidates(
        &self,
        eye: QueryPoint,
        origin: Option<(usize, usize)>,
        owners: [Option<ObjectId>; 2],
    ) -> impl Iterator<Item = usize> + Clone + '_ {
        let origin = origin.map(|(ia, ib)| {
            let (a, b) = (self.qpoint(ia), self.qpoint(ib));
            (a, b, side(a, b, eye))
        });
        let second = owners[1].filter(|&id| owners[0] != Some(id));
        [owners[0], second]
            .into_iter()
            .flatten()
            .filter_map(|id| self.scene.object(id))
            .flat_map(|obj| obj.first_vertex()..obj.first_vertex() + obj.len())
            .filter(move |&v| {
                origin.is_none_or(|(a, b, se)| {
                    let sw = side(a, b, self.qpoint(v));
                    sw != Sign::Zero && sw != se
                })
            })
    }

    /// Of `candidates`, the vertex exactly on the ray from `eye` in the exact direction
    /// `d`, nearest to `eye`.
    fn nearest_on_exact_ray(
        &self,
        candidates: impl Iterator<Item = usize>,
        eye: QueryPoint,
        d: &(Wide, Wide),
    ) -> Option<usize> {
        nearest_on_ray(candidates, |v| {
            let w = diff(self.qpoint(v), eye);
            (Wide::cross(d, w)?.sign() == Sign::Zero)
                .then(|| Wide::dot(d, w))
                .flatten()
        })
    }

    /// The direction `d` from `prev` continued through `hop` (which leaves `prev`): from
    /// `hop.next` to the hit `X = prev + (num/den)·d` on the edge's line,
    /// `(prev − next)·den + num·d` times the sign of `den` (a positive multiple). `None`
    /// along the edge's line or past `Wide`'s budget (bits as [`Tree::map_hop_exact`]).
    fn map_hop_forward(
        &self,
        (prev, hop): (QueryPoint, &Hop),
        d: &(Wide, Wide),
    ) -> Option<(Wide, Wide)> {
        let a = self.qpoint(hop.a());
        let e = diff(self.qpoint(hop.b()), a);
        let den = Wide::cross(d, e)?;
        let negative = match den.sign() {
            Sign::Zero => return None,
            s => s == Sign::Negative,
        };
        let (num, pn) = (cross(diff(a, prev), e), diff(prev, hop.next));
        let x = den.mul_i128(pn.0)?.add(&d.0.mul_i128(num)?)?;
        let y = den.mul_i128(pn.1)?.add(&d.1.mul_i128(num)?)?;
        Some(if negative { (x.neg(), y.neg()) } else { (x, y) })
    }

    /// [`Tree::map_hop_exact`] modulo `P` (`wide::mod_p`), up to sign: `None` when the
    /// hit's denominator may be zero (its residue is), where the exact hop takes the
    /// edge's midpoint instead. Equal exact directions have equal residues up to sign, so
    /// different residues of a cross product's two terms prove it nonzero.
    fn map_hop_residue(
        &self,
        (prev, hop): (QueryPoint, &Hop),
        d: (u64, u64),
    ) -> Option<(u64, u64)> {
        let cur = hop.next;
        let mul = |a: u64, b: u64| mod_p(u128::from(a) * u128::from(b));
        let add = |a: u64, b: u64| mod_p(u128::from(a) + u128::from(b));
        let a = self.qpoint(hop.a());
        let e = diff(self.qpoint(hop.b()), a);
        let (e0, e1) = (residue_i128(e.0), residue_i128(e.1));
        let den = add(mul(d.0, e1), P - mul(d.1, e0));
        if den == 0 {
            return None;
        }
        let (num, cp) = (residue_i128(cross(diff(a, cur), e)), diff(cur, prev));
        Some((
            add(mul(den, residue_i128(cp.0)), mul(d.0, num)),
            add(mul(den, residue_i128(cp.1)), mul(d.1, num)),
        ))
    }

    /// One hop of [`Tree::map_dir`] exactly: the direction `d` from `hop.next` mapped back
    /// to a direction from `prev` (the eye `hop` leaves), scaled by the hit's denominator;
    /// `None` past `Wide`'s 1024 bits. Bit budget: a direction of `b` bits becomes one of
    /// at most `b + 102` (query differences ≤ 2⁵³, edges ≤ 2⁴⁸), so 9 hops from a 54-bit
    /// direction fit and the final cross with a query difference too.
    fn map_hop_exact(
        &self,
        (prev, hop): (QueryPoint, &Hop),
        d: &(Wide, Wide),
    ) -> Option<(Wide, Wide)> {
        let cur = hop.next;
        let a = self.qpoint(hop.a());
        let e = diff(self.qpoint(hop.b()), a);
        let den = Wide::cross(d, e)?;
        Some(match den.sign() {
            // Along the edge's line: its midpoint, as `map_dir`.
            Sign::Zero => {
                let ap = diff(a, prev);
                (
                    Wide::from_i128(2 * ap.0 + e.0),
                    Wide::from_i128(2 * ap.1 + e.1),
                )
            }
            // `X − prev = (cur − prev) + (num / den)·d`, times `|den|`.
            s => {
                let (num, cp) = (cross(diff(a, cur), e), diff(cur, prev));
                let x = den.mul_i128(cp.0)?.add(&d.0.mul_i128(num)?)?;
                let y = den.mul_i128(cp.1)?.add(&d.1.mul_i128(num)?)?;
                if s == Sign::Negative {
                    (x.neg(), y.neg())
                } else {
                    (x, y)
                }
            }
        })
    }
}

/// Anchored walks: the pieces of a range seen from an eye in the layer whose floor is an
/// object (behind a screen, a mirror or a refractive object).
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
impl<S: Storage> Tree<'_, '_, S> {
    /// Where the primary walk over a range from `f` starts: the cylinder holding the ray
    /// from `q` at `f`, at `f`, so that the walk skips every event before the range — or
    /// the θ = 0 cylinder `start` at θ = 0 where that cylinder is not found directly.
    /// Without a history: the line's objects nearest to `q` behind and ahead are picked in
    /// `f64` and confirmed exactly — the cylinder with the one behind as floor
    /// ([`Tree::stack_floor`]) must have its ceiling ahead of `q` (else that ceiling, nearer,
    /// is tried next); with nothing behind, the cylinder with the one ahead as ceiling
    /// ([`Tree::stack_ceiling`]) must have its floor behind `q` or none. Only where no
    /// vertex lies exactly on the line (then no event lies exactly at `f`, and the cylinder
    /// just after `f` is the one at `f`), `f` is not θ = 0, the line meets an object and
    /// the complex is not pruned to a region (whose cylinders off `q`'s trace may be
    /// missing).
    fn primary_start(&self, q: QueryPoint, start: CylinderId, f: &Angle) -> (CylinderId, Angle) {
        let fallback = (start, Angle::ZERO);
        if self.complex.region().is_some() || f.is_exactly_zero() {
            return fallback;
        }
        let (Ok(dx), Ok(dy)) = (i64::try_from(f.vector().0), i64::try_from(f.vector().1)) else {
            return fallback;
        };
        let (qx, qy) = (q.x(), q.y());
        // Per vertex: the exact side of the line (cross product) and the position along
        // it (`f64`). Bit budget: |d| ≤ 2⁶³, |v − q| ≤ 2⁵⁴: products < 2¹¹⁸, exact in
        // `i128` from single widening products.
        let at = |v: usize| {
            let p = self.qpoint(v);
            let (wx, wy) = (p.x() - qx, p.y() - qy);
            let along = dx as f64 * wx as f64 + dy as f64 * wy as f64;
            (cross_q((dx.into(), dy.into()), p, q), along)
        };
        // The crossings nearest to `q` behind and ahead: (position along the line, object).
        let mut behind: Option<(f64, ObjectId)> = None;
        let mut ahead: Option<(f64, ObjectId)> = None;
        // Of the objects the line misses, the nearest below and above it (exact).
        let mut below: Option<(i128, ObjectId)> = None;
        let mut above: Option<(i128, ObjectId)> = None;
        for (i, obj) in self.scene.objects().iter().enumerate() {
            let (first, n) = (obj.first_vertex(), obj.len());
            let Ok(id) = u32::try_from(i) else {
                return fallback;
            };
            if n == 0 {
                continue;
            }
            // The range of the cross product over the bounding box (at the corners that
            // extremise it): a box on one side of the line holds no vertex on it, and is
            // read vertex by vertex only if it may lie nearer than the nearest so far.
            let (lo_box, hi_box) = obj.bbox();
            let (lo_box, hi_box) = (lo_box.to_query(), hi_box.to_query());
            let corner = |max: bool| {
                let x = if (dy > 0) == max {
                    lo_box.x()
                } else {
                    hi_box.x()
                };
                let y = if (dx > 0) == max {
                    hi_box.y()
                } else {
                    lo_box.y()
                };
                i128::from(dx) * i128::from(y - qy) - i128::from(dy) * i128::from(x - qx)
            };
            let (box_lo, box_hi) = (corner(false), corner(true));
            if box_hi < 0 && below.is_some_and(|(c, _)| box_hi <= c) {
                continue;
            }
            if box_lo > 0 && above.is_some_and(|(c, _)| box_lo >= c) {
                continue;
            }
            let v0 = at(first);
            let mut prev = v0;
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            let (mut lowest, mut highest) = (v0.0, v0.0);
            for k in 1..=n {
                let cur = if k == n { v0 } else { at(first + k) };
                if cur.0 == 0 {
                    return fallback;
                }
                (lowest, highest) = (lowest.min(cur.0), highest.max(cur.0));
                if (cur.0 < 0) != (prev.0 < 0) {
                    // Where the edge crosses the line.
                    let (ca, cb) = (prev.0 as f64, cur.0 as f64);
                    let pos = prev.1 + (cur.1 - prev.1) * (ca / (ca - cb));
                    (lo, hi) = (lo.min(pos), hi.max(pos));
                }
                prev = cur;
            }
            if highest < 0 {
                if below.is_none_or(|(c, _)| highest > c) {
                    below = Some((highest, ObjectId(id)));
                }
            } else if lowest > 0 {
                if above.is_none_or(|(c, _)| lowest < c) {
                    above = Some((lowest, ObjectId(id)));
                }
            } else if hi < 0.0 && behind.is_none_or(|(p, _)| hi > p) {
                behind = Some((hi, ObjectId(id)));
            } else if lo >= 0.0 && lo.is_finite() && ahead.is_none_or(|(p, _)| lo < p) {
                ahead = Some((lo, ObjectId(id)));
            }
        }
        let ahead_of = |o: ObjectId| object_ahead_of_query(self.scene, o, f, q);
        // Each try moves to an object nearer to `q` along the line.
        match (behind, ahead) {
            (Some((_, mut m)), _) => {
                for _ in 0..self.scene.len() {
                    if ahead_of(m) != Some(false) {
                        return fallback;
                    }
                    let Some(id) = self.stack_floor(q, m, f, true) else {
                        return fallback;
                    };
                    match self.complex.cylinder(id).map(|c| c.ceiling) {
                        Some(Some(g)) if ahead_of(g) != Some(true) => m = g,
                        Some(_) => return (id, *f),
                        None => return fallback,
                    }
                }
            }
            (None, Some((_, mut g))) => {
                for _ in 0..self.scene.len() {
                    if ahead_of(g) != Some(true) {
                        return fallback;
                    }
                    let Some(id) = self.stack_ceiling(q, g, f) else {
                        return fallback;
                    };
                    match self.complex.cylinder(id).map(|c| c.floor) {
                        Some(Some(m)) if ahead_of(m) != Some(false) => g = m,
                        Some(_) => return (id, *f),
                        None => return fallback,
                    }
                }
            }
            // The line meets nothing: the empty strip between the nearest objects below
            // and above it is one cylinder, next to the nearer one's chain.
            (None, None) => {
                let (chain, side) = match (below, above) {
                    (Some((_, o)), _) => (
                        Chain {
                            object: o,
                            bound: Bound::Upper,
                        },
                        Side::Above,
                    ),
                    (None, Some((_, o))) => (
                        Chain {
                            object: o,
                            bound: Bound::Lower,
                        },
                        Side::Below,
                    ),
                    (None, None) => return fallback,
                };
                let id = self
                    .complex
                    .across(self.scene, chain, side, Layer::Around, f);
                if let Some((id, c)) = id.and_then(|id| Some((id, self.complex.cylinder(id)?))) {
                    if c.floor.is_none()
                        && c.ceiling.is_none()
                        && self.contains_after(q, f, (id, c), true, &[])
                    {
                        return (id, *f);
                    }
                }
            }
        }
        fallback
    }

    /// The cylinder with ceiling `g` containing the line through `q` at `f`, for
    /// [`Tree::primary_start`] (no vertex exactly on the line, `f` not θ = 0, counter-
    /// clockwise): the cylinders with ceiling `g` at `f` stack up from `g`'s lower chain to
    /// its upper one; climb until the next chain lies above the line, as
    /// [`Tree::stack_floor`] climbs a floor's.
    fn stack_ceiling(&self, q: QueryPoint, g: ObjectId, f: &Angle) -> Option<CylinderId> {
        let first = Chain {
            object: g,
            bound: Bound::Lower,
        };
        if self.chain_after(q, f, first, true) != Sign::Negative {
            return None;
        }
        let key = f.keyed();
        let mut id =
            self.complex
                .across_keyed(self.scene, first, Side::Above, Layer::Before, &key)?;
        let mut crossed = (first, Sign::Negative);
        for _ in 0..self.complex.cylinders().len() {
            let c = self.complex.cylinder(id)?;
            if c.ceiling != Some(g) {
                return None;
            }
            let Some(t) = c.top else {
                return self
                    .contains_after(q, f, (id, c), true, &[crossed])
                    .then_some(id);
            };
            let side = self.arc_after(q, f, (id, t, true), true);
            if side == Sign::Positive {
                let known = [crossed, (t, side)];
                return self
                    .contains_after(q, f, (id, c), true, &known)
                    .then_some(id);
            }
            crossed = (t, side);
            // Above a lower chain its object is crossed before `g`: the layer starting
            // there; above an upper chain it is not crossed any more.
            let layer = match t.bound {
                Bound::Lower => Layer::After,
                Bound::Upper => Layer::Around,
            };
            id = self
                .complex
                .across_from_keyed(self.scene, id, Side::Above, layer, &key)?;
        }
        None
    }

    /// Whether a vertex of `object` lies exactly on the line through `eye` with the
    /// direction of `a` (read only where the bounding box meets the line).
    fn vertex_on_line(&self, eye: QueryPoint, a: &Angle, object: ObjectId) -> bool {
        let (Some(o), Some(d)) = (self.scene.object(object), a.vector64()) else {
            return false;
        };
        box_side(d, o, eye) == Sign::Zero
            && self
                .scene
                .polygon(o)
                .iter()
                .any(|&p| line_cross(d, p, eye) == 0)
    }

    /// Side of the line through `v` against the line through `eye`, both of direction `d`
    /// turned counter-clockwise by an infinitesimal δ (larger than the symbolic
    /// perturbation): `Positive` if `v`'s line lies left (above). A vertex exactly on the
    /// eye's line falls below if it lies ahead of the eye (`cross(d + δd⊥, t·d) = −δt|d|²`),
    /// rises above if behind; only a vertex at the eye itself falls back to the perturbation.
    /// Bit budget: `|d| ≤ 2⁵³`, `|v − eye| ≤ 2⁵³`, cross and dot `< 2¹⁰⁷`, exact in `i128`.
    fn side_after(&self, eye: QueryPoint, from: &Angle, v: usize, ccw: bool) -> Sign {
        let d = from.vector();
        let w = diff(self.qpoint(v), eye);
        match Sign::of_i128(cross(d, w)) {
            Sign::Zero => match Sign::of_i128(d.0 * w.0 + d.1 * w.1) {
                Sign::Zero => from.offset_cmp_query(eye, ranked(self.scene, v)),
                s if ccw => s.flip(),
                s => s,
            },
            s => s,
        }
    }

    /// Side of `chain` against the line through `eye` just after `from` (as
    /// [`Tree::side_after`]): the lower chain is the lowest vertex line of its object, so
    /// it lies below iff some vertex line does; the upper chain is the highest.
    fn chain_after(&self, eye: QueryPoint, from: &Angle, chain: Chain, ccw: bool) -> Sign {
        let (Some(obj), Some(d)) = (self.scene.object(chain.object), from.vector64()) else {
            return Sign::Zero;
        };
        let first = obj.first_vertex();
        let (some, none) = match chain.bound {
            Bound::Lower => (Sign::Negative, Sign::Positive),
            Bound::Upper => (Sign::Positive, Sign::Negative),
        };
        // An object whose bounding box lies on one side of the line lies there whole.
        match box_side(d, obj, eye) {
            Sign::Zero => {}
            s => return s,
        }
        // A vertex exactly on the line takes the full rule.
        let side = |k: usize, p: Point| match Sign::of_i128(line_cross(d, p, eye)) {
            Sign::Zero => self.side_after(eye, from, first + k, ccw),
            s => s,
        };
        let vertices = self.scene.polygon(obj).iter();
        if vertices.enumerate().any(|(k, &p)| side(k, p) == some) {
            some
        } else {
            none
        }
    }

    /// [`Tree::chain_after`] for the arc of cylinder `c` (`top` or bottom) at `from` inside
    /// `c`'s θ-range (its closure, exactly). Where the arc is one vertex's sinusoid
    /// ([`crate::partition::NO_ARC_VERTEX`] otherwise) that vertex is an extreme one of the
    /// chain's object along every direction of the closed range, so a line through it off
    /// the eye's line puts the whole chain on that side: one cross product instead of one
    /// per vertex. On the line, the full rule.
    fn arc_after(
        &self,
        eye: QueryPoint,
        from: &Angle,
        (id, chain, top): (CylinderId, Chain, bool),
        ccw: bool,
    ) -> Sign {
        let v = self.complex.borders_ref().arcs(id)[usize::from(top)];
        if v != NO_ARC_VERTEX {
            match Sign::of_i128(cross_q(from.vector(), self.qpoint(v as usize), eye)) {
                Sign::Zero => {}
                s => return s,
            }
        }
        self.chain_after(eye, from, chain, ccw)
    }

    /// The cylinder with floor `m` containing the line through `eye` just after the range
    /// start `from` in the walk's direction (`ccw`, else just before it) — turned by an
    /// infinitesimal that exceeds the symbolic perturbation, so that everything exactly on
    /// the opening ray is behind (the range is open) — and the angle to start walking from:
    /// the perturbed direction of the last tangent (in walk order) of the cylinder's chains
    /// exactly on the opening ray, or `from` (the walk would otherwise cross those tangents
    /// again); `None` for the top of the circle (a clockwise walk from exactly θ = 0).
    /// Always inlined, as [`Tree::stack_floor`] into it: out of line it cost a hall frame
    /// 0.28 % more instructions, a mixed frame 0.53 %.
    #[inline(always)]
    fn locate_floor(
        &self,
        (floors, hint): (&mut Floors, bool),
        eye: QueryPoint,
        m: ObjectId,
        from: &Dir,
        ccw: bool,
    ) -> Result<(CylinderId, Option<Angle>), WalkError> {
        let angle = &from.angle;
        // Only the walks that ask for a hint keep one: the others' floors are never asked.
        let slot = floors.get_mut(m.0 as usize % FLOOR_HINTS).filter(|_| hint);
        let hint = slot.as_ref().and_then(|s| **s).and_then(|h| {
            let id = CylinderId::from_index(h.get() as usize - 1)?;
            let c = self.complex.cylinder(id)?;
            (c.floor == Some(m) && self.contains_after(eye, angle, (id, c), ccw, &[])).then_some(id)
        });
        let id = match hint {
            Some(id) => id,
            None => match self.stack_floor(eye, m, angle, ccw) {
                Some(id) => id,
                None => self.scan_floor(eye, m, angle, ccw)?,
            },
        };
        if let Some(slot) = slot {
            // `None` past `u32::MAX − 1` cylinders (never), which only drops the hint.
            *slot = u32::try_from(id.index() + 1)
                .ok()
                .and_then(core::num::NonZeroU32::new);
        }
        let c = self.complex.cylinder(id).ok_or(WalkError::Corrupt)?;
        let zero = angle.is_exactly_zero();
        // Counter-clockwise, the turned line lies past θ = 0: an opening ray exactly at
        // θ = 0 that the perturbation puts just below 2π starts the walk at θ = 0 instead,
        // and tangents exactly at θ = 0 just below 2π are ahead. Clockwise from exactly
        // θ = 0 the turned line lies just below 2π: the walk starts at the top (`None`),
        // and the tangents exactly at θ = 0 just below 2π are behind it, the others ahead.
        let mut theta = match (ccw, zero) {
            (true, true) if wraps(angle) => Some(Angle::ZERO),
            (false, true) => None,
            _ => Some(*angle),
        };
        let behind = if ccw {
            Ordering::Greater
        } else {
            Ordering::Less
        };
        let near_side = |a: &Angle| wraps(a) == (!ccw && zero);
        // One object on both arcs (the ceiling, mostly) is looked at once.
        let top = c
            .top
            .filter(|t| c.bottom.is_none_or(|b| b.object != t.object));
        for chain in [c.bottom, top].into_iter().flatten() {
            // Only a vertex exactly on the opening line can make a tangent exactly on it.
            if chain.object == m || !self.vertex_on_line(eye, angle, chain.object) {
                continue;
            }
            let (tangents, count) = crate::line_space::tangents_from(self.scene, chain.object, eye);
            for &(h, _) in tangents.iter().take(count) {
                let fwd = Angle::from_query(eye, ranked(self.scene, h));
                for a in [fwd, fwd.reversed()] {
                    if a.cmp_exact(angle) == Ordering::Equal
                        && near_side(&a)
                        && theta.is_none_or(|t| a.cmp_angle(&t) == behind)
                    {
                        theta = Some(a);
                    }
                }
            }
        }
        Ok((id, theta))
    }

    /// Whether the cylinder `c` contains the line through `eye` just after `from` (`ccw`,
    /// else just before it; see [`Tree::locate_floor`]): walls exactly at `from` lie behind
    /// it; a wall exactly at θ = 0 that the perturbation puts just below 2π counts as 2π,
    /// and the line just before exactly θ = 0 lies below 2π, after every other wall.
    /// `known` holds chains whose [`Tree::chain_after`] the caller has already computed.
    /// The walls are tested first: past them `from` lies in `c`'s closed θ-range, where
    /// the arcs' sides are [`Tree::arc_after`]'s (one cross product at an arc vertex).
    fn contains_after(
        &self,
        eye: QueryPoint,
        from: &Angle,
        (id, c): (CylinderId, &Cylinder),
        ccw: bool,
        known: &[(Chain, Sign)],
    ) -> bool {
        let chain_side = |ch: Chain, top: bool| {
            known.iter().find(|(k, _)| *k == ch).map_or_else(
                || self.arc_after(eye, from, (id, ch, top), ccw),
                |&(_, s)| s,
            )
        };
        self.wall_after(from, c.left, true, ccw)
            && self.wall_after(from, c.right, false, ccw)
            && c.bottom
                .is_none_or(|b| chain_side(b, false) == Sign::Negative)
            && c.top.is_none_or(|t| chain_side(t, true) == Sign::Positive)
    }

    /// Whether the line through the eye just after `from` (`ccw`, else just before it)
    /// lies on the inner side of the wall `w` of a cylinder, its `left` wall or its right
    /// one (see [`Tree::contains_after`]). `wraps` only for a wall exactly at θ = 0 (it is
    /// out of line). Always inlined: called out of line (the compiler's choice) it cost a
    /// hall frame 0.3 % more instructions, a mixed frame 0.6 %.
    #[inline(always)]
    fn wall_after(&self, from: &Angle, w: Wall, left: bool, ccw: bool) -> bool {
        let borders = self.complex.borders_ref();
        let computed;
        let a = match w {
            Wall::Zero => return true,
            Wall::Vertex(v) => match borders.angle(v.index()) {
                Some(a) => a,
                None => match self.complex.wall_angle(self.scene, w) {
                    Some(a) => {
                        computed = a;
                        &computed
                    }
                    None => return true,
                },
            },
        };
        // A wall exactly at θ = 0 that the perturbation puts just below 2π counts as 2π,
        // and the line just before exactly θ = 0 lies below 2π, after every other wall.
        let o = if a.is_exactly_zero() && wraps(a) {
            Ordering::Greater
        } else if !ccw && from.is_exactly_zero() {
            Ordering::Less
        } else {
            a.cmp_exact(from)
        };
        // Turned counter-clockwise, walls exactly at the angle are behind; clockwise, ahead.
        match (left, ccw) {
            (true, true) => o != Ordering::Greater,
            (true, false) => o == Ordering::Less,
            (false, true) => o == Ordering::Greater,
            (false, false) => o != Ordering::Less,
        }
    }

    /// The start cylinder found through the per-chain tilings: the cylinders with floor `m`
    /// at `from` (perturbed) stack up from `m`'s lower chain to its upper one; climb from
    /// the nearer end until the next chain lies beyond the eye's line. O(log n) per tiling lookup plus the height of the stack.
    /// The climb proves the chains' sides and the perturbed θ-range: of
    /// [`Tree::contains_after`] only the wall the turned line leaves behind is left to test.
    /// `None` where something lies exactly on the opening ray and the perturbed angle and
    /// the turned line disagree (the caller then scans). Always inlined (into
    /// [`Tree::locate_floor`] and [`Tree::primary_start`]): out of line it cost a hall
    /// frame 0.65 % more instructions, a mixed frame 0.27 %.
    #[inline(always)]
    fn stack_floor(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        from: &Angle,
        ccw: bool,
    ) -> Option<CylinderId> {
        // Climb from the end of `m`'s sheet nearer to the eye's line (either climb is
        // exact); that end's vertex line off the eye's line is the side of its chain, and
        // so is the far end's for `m`'s other chain.
        let (lo, hi) = self.extremes(eye, m, from)?;
        let up = -lo <= hi;
        let (start, far, side, inward, end, far_end) = if up {
            (
                Bound::Lower,
                Bound::Upper,
                Side::Above,
                Sign::Negative,
                lo,
                hi,
            )
        } else {
            (
                Bound::Upper,
                Bound::Lower,
                Side::Below,
                Sign::Positive,
                hi,
                lo,
            )
        };
        let first = Chain {
            object: m,
            bound: start,
        };
        let last = Chain {
            object: m,
            bound: far,
        };
        let first_side = match Sign::of_i128(end) {
            Sign::Zero => self.chain_after(eye, from, first, ccw),
            s => s,
        };
        if first_side != inward {
            return None;
        }
        // The tilings are searched at the perturbed angle, on the turned line's lap (none
        // holds the top of the circle: the caller scans). `wraps` only where exactly at
        // θ = 0 (it is out of line).
        let zero = from.is_exactly_zero();
        let probe = match (ccw, zero) {
            (true, true) if wraps(from) => Angle::ZERO,
            (false, true) => return None,
            _ => *from,
        };
        let key = probe.keyed();
        let mut id = self
            .complex
            .across_keyed(self.scene, first, side, Layer::After, &key)?;
        // The last chain crossed, on the eye's side of the line.
        let mut crossed = (first, inward);
        for _ in 0..self.complex.cylinders().len() {
            let c = self.complex.cylinder(id)?;
            if c.floor != Some(m) {
                return None;
            }
            let (near, next) = if up {
                (c.bottom, c.top)
            } else {
                (c.top, c.bottom)
            };
            let next_side = match next {
                Some(t) if t == last && far_end != 0 => Some((t, Sign::of_i128(far_end))),
                Some(t) => Some((t, self.arc_after(eye, from, (id, t, up), ccw))),
                None => None,
            };
            match next_side {
                Some((t, s)) if s != inward.flip() => crossed = (t, s),
                _ => {
                    // Every cylinder of the climb holds the probe strictly inside its
                    // θ-range (the tilings are searched and scanned at it), so only a wall
                    // exactly at `from` that the turned line leaves behind can exclude it,
                    // and the chains crossed are its arcs.
                    if near == Some(crossed.0) && crossed.1 == inward {
                        let (w, left) = if ccw {
                            (c.right, false)
                        } else {
                            (c.left, true)
                        };
                        return self.wall_after(from, w, left, ccw).then_some(id);
                    }
                    let known = [crossed, next_side.unwrap_or(crossed)];
                    return self
                        .contains_after(eye, from, (id, c), ccw, &known)
                        .then_some(id);
                }
            }
            // Beyond a chain whose object lies on the far side (above a lower chain, below
            // an upper one) that object is crossed: the layer ending there.
            let layer = if crossed.0.bound == start {
                Layer::Before
            } else {
                Layer::Around
            };
            // The cylinder entered overlaps `c` in θ: a short scan from `c`'s place in the
            // tiling, not a search of it.
            id = self
                .complex
                .across_from_cylinder(self.scene, id, c, side, layer, &key)?;
        }
        None
    }

    /// The least and greatest `cross(d, v − eye)` over the vertices `v` of `m`, `d` the
    /// direction of `from`: the lines of `m`'s lower and upper chains against the eye's
    /// line (`None`: no such object). Bit budget as [`line_cross`].
    fn extremes(&self, eye: QueryPoint, m: ObjectId, from: &Angle) -> Option<(i128, i128)> {
        let d = from.vector64()?;
        let (first, rest) = self.scene.polygon(self.scene.object(m)?).split_first()?;
        let c = line_cross(d, *first, eye);
        Some(rest.iter().fold((c, c), |(lo, hi), &p| {
            let c = line_cross(d, p, eye);
            (c.min(lo), c.max(hi))
        }))
    }

    /// [`Tree::stack_floor`] by a scan over the cylinders: O(cylinders), for the
    /// degenerate cases only.
    fn scan_floor(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        from: &Angle,
        ccw: bool,
    ) -> Result<CylinderId, WalkError> {
        self.complex
            .cylinders()
            .iter()
            .enumerate()
            .find_map(|(i, c)| {
                let id = CylinderId::from_index(i)?;
                (c.floor == Some(m) && self.contains_after(eye, from, (id, c), ccw, &[]))
                    .then_some(id)
            })
            .ok_or(WalkError::NoStart)
    }
}

/// `cross(d, p − eye)` for a vertex `p` and the direction `d` of an [`Angle`] (kept in
/// `i64`): single widening products. Bit budget: `|d| ≤ 2⁶³`, `|p − eye| ≤ 2⁵⁴` (query
/// grid), products `< 2¹¹⁷`, exact in `i128`.
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
#[inline(always)]
fn line_cross(d: (i64, i64), p: Point, eye: QueryPoint) -> i128 {
    let p = p.to_query();
    offset_cross(d, p.x() - eye.x(), p.y() - eye.y())
}

/// `cross(d, (wx, wy))`, bit budget as [`line_cross`].
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
#[inline(always)]
fn offset_cross(d: (i64, i64), wx: i64, wy: i64) -> i128 {
    i128::from(d.0) * i128::from(wy) - i128::from(d.1) * i128::from(wx)
}

/// The side of the line through `eye` with direction `d` on which the bounding box of `o`
/// lies whole (`Zero`: the box meets the line), from the two corners where
/// [`line_cross`] (linear in the point) is least and greatest. Bit budget as
/// [`line_cross`].
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
#[inline]
fn box_side(d: (i64, i64), o: &crate::scene::Object, eye: QueryPoint) -> Sign {
    let (lo, hi) = o.bbox();
    let (lo, hi) = (lo.to_query(), hi.to_query());
    let (lo, hi) = (
        (lo.x() - eye.x(), lo.y() - eye.y()),
        (hi.x() - eye.x(), hi.y() - eye.y()),
    );
    // `dx·wy − dy·wx`: least at the lowest `wy` where `dx > 0` and at the greatest `wx`
    // where `dy > 0`.
    let (x_least, x_most) = if d.1 > 0 { (hi.0, lo.0) } else { (lo.0, hi.0) };
    let (y_least, y_most) = if d.0 > 0 { (lo.1, hi.1) } else { (hi.1, lo.1) };
    if offset_cross(d, x_least, y_least) > 0 {
        Sign::Positive
    } else if offset_cross(d, x_most, y_most) < 0 {
        Sign::Negative
    } else {
        Sign::Zero
    }
}

/// Without anchored walks (no ray type past the primary view compiled) the primary walk
/// starts at θ = 0.
#[cfg(not(any(feature = "mirrors", feature = "refraction", feature = "screens")))]
impl<S: Storage> Tree<'_, '_, S> {
    fn primary_start(&self, _: QueryPoint, start: CylinderId, _: &Angle) -> (CylinderId, Angle) {
        (start, Angle::ZERO)
    }
}

/// The walk behind a screen, mirror or refractive object.
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
impl<S: Storage> Tree<'_, '_, S> {
    /// Pushes the frame that walks `(from, to)` (in `level`'s direction) from `level`'s eye
    /// anchored to the floor `m`; its first piece starts with `first`. Built in the push:
    /// a frame (its walker) is large, and every move of it is a copy.
    #[allow(clippy::too_many_arguments)]
    fn push_range_walk<F: Frames>(
        &self,
        sc: &mut Stacks<F>,
        level: Level,
        m: ObjectId,
        (from, to): (&Dir, &Dir),
        first: &Boundary,
        hint: bool,
    ) -> Result<(), WalkError> {
        let eye = sc.eye();
        let (start, walk) = if from.angle.cmp_exact(&to.angle) == Ordering::Equal {
            // Both ends placed on one direction (`map_range`): the range is thinner than
            // `f64` resolves and lies on one side of it, the side where the line meets
            // `m`'s sheet — just before the direction, else just after it. One piece;
            // never a walk around the full circle.
            let id = match self.scan_floor(eye, m, &to.angle, false) {
                Err(WalkError::NoStart) => {
                    self.locate_floor((&mut sc.floors, hint), eye, m, from, true)?
                        .0
                }
                r => r?,
            };
            (id, None)
        } else {
            let (start, theta) =
                self.locate_floor((&mut sc.floors, hint), eye, m, from, level.ccw)?;
            // The end on the first lap if it lies ahead of the start in walk order.
            let ahead = if level.ccw {
                Ordering::Greater
            } else {
                Ordering::Less
            };
            let lap = match theta {
                Some(theta) if to.angle.cmp_angle(&theta) == ahead => 0,
                Some(_) => 1,
                // From the top of the circle everything is ahead.
                None => 0,
            };
            (start, Some((theta, lap)))
        };
        let walker = |(theta, lap): (Option<Angle>, u8)| {
            let walker = Walker::new(start, theta.unwrap_or(Angle::ZERO), level.ccw);
            let walker = if theta.is_none() {
                walker.at_top()
            } else {
                walker
            };
            (Events::new(walker, false), lap)
        };
        let (events, end_lap) = walk.map(walker).unzip();
        sc.push(
            level,
            Frame::Walk(RangeWalk {
                level,
                events,
                m,
                end_lap: end_lap.unwrap_or(0),
                seen: self.complex.ceiling(start),
                cur_from: from.clone(),
                to: to.clone(),
                cur_boundary: *first,
                past_from: false,
                done: false,
            }),
        )
    }
}

#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
impl RangeWalk {
    /// The next piece of the range in walk order; `eye` is the frame's ([`Stacks::eye`]),
    /// `stage` and `level` are the lengths of the hop and branch stacks above this frame
    /// (its boundaries' stage and level). `fresh`:
    /// `out` holds the range and first boundary the walk was pushed with: the first piece
    /// does not write the start, end and boundary it shares with them (an event on the
    /// opening ray, which moves the start, writes it there). `c`: room for a cluster.
    fn next_piece<S: Storage>(
        &mut self,
        tree: &Tree<'_, '_, S>,
        ends: Ends<'_>,
        (eye, stage, level): (QueryPoint, u8, u8),
        (out, fresh): (&mut Piece, bool),
        c: &mut Cluster,
    ) -> Result<bool, WalkError> {
        if self.done {
            return Ok(false);
        }
        let ccw = self.level.ccw;
        let mut end = None;
        let trace = Trace::new(
            eye,
            Anchor::Floor(self.m),
            Some(Position {
                lap: self.end_lap,
                angle: self.to.angle,
            }),
        );
        if let Some(events) = self.events.as_mut() {
            while events.cluster(tree.complex, tree.scene, &trace, c)? {
                match self.to.place(ends, &c.first.angle, Ordering::Less, ccw) {
                    // On the closing ray: not inside the open range.
                    Ordering::Equal => {
                        end = Some(Dir::of(&c.first));
                        break;
                    }
                    // Past the exact end, before the rounded one.
                    Ordering::Greater => break,
                    Ordering::Less => {}
                }
                let after = tree.complex.ceiling(c.last.cylinder);
                // `cur_from` stands for `from` here: on its exact ray it places as `from`
                // does (no later cluster is on that ray), and between the ends only its
                // exact direction, which it keeps, places.
                let opening = if self.past_from {
                    Ordering::Greater
                } else {
                    self.cur_from
                        .place(ends, &c.first.angle, Ordering::Greater, ccw)
                };
                self.past_from = opening == Ordering::Greater;
                if opening != Ordering::Greater {
                    // On the opening ray (or before the exact start, after the rounded
                    // one): part of the state at the start.
                    self.seen = after;
                    if opening == Ordering::Equal {
                        self.cur_from = Dir::of(&c.last);
                        if fresh {
                            out.from = self.cur_from.clone();
                        }
                    } else {
                        // Between the rounded and the exact start: the event is a closer
                        // rounding of it, one where a walk behind this piece finds the
                        // object it sees (`no_start_range_near_glass_vertex.rs`).
                        self.cur_from.angle = c.last.angle;
                        if fresh {
                            out.from.angle = c.last.angle;
                        }
                    }
                } else if after != self.seen {
                    let from = core::mem::replace(&mut self.cur_from, Dir::of(&c.last));
                    out.to = Dir::of(&c.first);
                    out.ceiling = self.seen;
                    let next = tree.event_boundary((stage, level), &out.to);
                    if fresh {
                        self.cur_boundary = next;
                    } else {
                        out.from = from;
                        out.boundary = core::mem::replace(&mut self.cur_boundary, next);
                    }
                    self.seen = after;
                    return Ok(true);
                }
            }
        }
        self.done = true;
        match end {
            Some(e) => out.to = e,
            None if fresh => {}
            None => out.to = self.to.clone(),
        }
        out.ceiling = self.seen;
        if !fresh {
            out.from = self.cur_from.clone();
            out.boundary = self.cur_boundary;
        }
        Ok(true)
    }
}

/// Changes of eye: splitting a range by the edges of a mirror or refractive object, the
/// virtual eyes and the ranges seen from them.
#[cfg(any(feature = "mirrors", feature = "refraction"))]
impl<S: Storage> Tree<'_, '_, S> {
    fn toward(&self, eye: QueryPoint, v: usize) -> Dir {
        Dir::vertex(Angle::from_query(eye, ranked(self.scene, v)), v)
    }

    /// The range end `end` (a direction from the eye `hop` leaves, the top of `chain`) seen
    /// from `hop.next`, written over
    /// it (no move of a returned end): exact if it points at an endpoint of the hop's edge
    /// (or the hit point falls on or beyond one),
    /// otherwise the direction to the hit point on the edge's line, computed in `f64` (it
    /// only places the range end; the angular error is about 2⁻⁵² rad), and in the latter
    /// case its exact direction, written to `out` (at the flattened index `at`) unless past
    /// `Wide`'s budget. `below`: the stack of exact directions below `out`, flattened;
    /// `chain`: the hops below `hop`.
    fn map_end(
        &self,
        (below, out, at, chain): (&[Mapped], &mut Mapped, usize, HopChain<'_>),
        end: &mut Dir,
        hop: &Hop,
        mirror: bool,
    ) -> Result<(), WalkError> {
        if let Some(v) = end.points_at().map(|v| v as usize) {
            if v == hop.a() || v == hop.b() {
                *end = self.toward(hop.next, v);
                return Ok(());
            }
        }
        // Kept in `i64` as well: the exact products below take `i64` factors.
        let d64 = end.angle.vector64().ok_or(WalkError::Corrupt)?;
        let d = (i128::from(d64.0), i128::from(d64.1));
        let (a, b) = (self.qpoint(hop.a()), self.qpoint(hop.b()));
        let e = diff(b, a);
        let den = cross(d, e);
        if den == 0 {
            return Err(WalkError::Corrupt);
        }
        // The hit's parameter on the edge is `u = nu / den`.
        let prev = chain.prev(chain.hops.len());
        let nu = cross(d, diff(prev, a));
        // At or beyond an end of the edge (by rounding): that endpoint, exactly.
        if let Some(at_b) = edge_end(nu, den) {
            *end = self.toward(hop.next, if at_b { hop.b() } else { hop.a() });
            return Ok(());
        }
        // Strictly inside the edge (exactly: the quotient of the correctly rounded terms
        // lies in (0, 1) only if the exact one does). Through an axis-parallel mirror edge
        // an exact end stays exact (`reflected`): no rounding and no wide directions.
        let num = cross(diff(a, prev), e);
        let axis = e.0 == 0 || e.1 == 0;
        if mirror && axis && end.exact.is_none() {
            if let Some(dir) = reflected(d, e, num, den) {
                *end = Dir::at(Angle::constant(dir));
                return Ok(());
            }
        }
        // `P − next = (prev − next) + t·d` with `t = cross(a − prev, e) / den` (see
        // `map_dir`) in `f64`, scaled so that its larger component is about 2⁵²: the
        // direction keeps `f64` precision instead of the query grid's, so that a range far
        // thinner than a grid step at the edge keeps its two ends apart.
        let t = to_f64(num) / to_f64(den);
        let pn64 = diff64(prev, hop.next);
        let pn = (i128::from(pn64.0), i128::from(pn64.1));
        let (fx, fy) = (
            to_f64(pn.0) + t * to_f64(d.0),
            to_f64(pn.1) + t * to_f64(d.1),
        );
        // The larger magnitude: a comparison, not `libm::fmax` (neither is NaN: `den ≠ 0`).
        let (ax, ay) = (libm::fabs(fx), libm::fabs(fy));
        let big = if ax < ay { ay } else { ax };
        if !big.is_finite() || big == 0.0 {
            return Err(WalkError::Corrupt);
        }
        // `libm::frexp`'s exponent and `libm::scalbn`'s scaling, read from and written to
        // the bits (the same values, without the software routines): `big` is normal, at
        // least 2⁻¹⁸⁰ (a sum of `f64`s of magnitude at least 2⁻¹²⁸ — ratios and products of
        // integers below 2¹²⁸ — is zero or at least their smallest ulp) and below 2¹⁹², so
        // the power of two 2^(52 − exp) is normal and the scaled components stay normal:
        // the products are exact.
        let exp = ((big.to_bits() >> 52) & 0x7ff) as i32 - 0x3fe;
        let scale = f64::from_bits(((0x3ff + 52 - exp) as u64) << 52);
        let lim = crate::geom::point::MAX_ABS_DIRECTION as f64;
        let (vx, vy) = (round_away(fx * scale), round_away(fy * scale));
        if libm::fabs(vx) > lim || libm::fabs(vy) > lim {
            return Err(WalkError::Corrupt);
        }
        // The rounded line must still cross the edge strictly (exact: products of 2⁵² · 2⁵³):
        // a hit closer to an endpoint than the rounding is that endpoint, or the walk
        // behind the edge would start on a line that misses the object.
        let v = (i128::from(vx as i64), i128::from(vy as i64));
        if cross_q(v, a, hop.next).signum() * cross_q(v, b, hop.next).signum() >= 0 {
            let u = to_f64(nu) / to_f64(den);
            *end = self.toward(hop.next, if u < 0.5 { hop.a() } else { hop.b() });
            return Ok(());
        }
        let dir = Direction::new(vx as i64, vy as i64).ok_or(WalkError::Corrupt)?;
        // The same exactly, as a recipe and an enclosure (`mapped`), kept on the stack of
        // exact directions until the frame walking it is popped; none past `Wide`'s budget.
        let t = Terms::of((prev, hop), chain.points);
        let here = u8::try_from(chain.hops.len()).map_err(|_| WalkError::TreeTooDeep)?;
        let mapped = match end.exact.and_then(|i| below.get(usize::from(i))) {
            Some(x) => x.through(chain, &t, here, mirror && axis),
            None => Mapped::start(d64, &t, here),
        };
        let exact = match mapped {
            Some(m) => {
                *out = m;
                Some(u8::try_from(at).map_err(|_| WalkError::TreeTooDeep)?)
            }
            None => None,
        };
        *end = Dir {
            exact,
            ..Dir::at(Angle::constant(dir))
        };
        Ok(())
    }

    /// The range `(p.from, p.to)` of a frame walking `ccw` (exact, less than π wide: it lies
    /// on one edge) seen through `hop`, written over it: each end by its image, which is the
    /// same end in the walk order behind the hop (`ccw`, reversed if `flip`: mirrors), so
    /// nothing is swapped or moved but the ends themselves. Mapped ends are placed to `f64`
    /// precision, so a range thinner than that can come out with both ends on one direction
    /// or crossed: it is then collapsed onto one direction, the end that points at a vertex
    /// if only one does (`split_collapsed` and `push_range_walk` take a collapsed range as
    /// the ray just before that direction). The exact directions of the mapped ends go on
    /// `exacts`, one entry for the two, kept until the frame walking the range is popped.
    /// Inlined into its one caller, [`Tree::change_eye`] (out of line: +0.6 % instructions
    /// in the mixed frame).
    #[inline(always)]
    fn map_range<E: ExactStack>(
        &self,
        (exacts, (eye, hops)): (&mut E, (QueryPoint, &[Hop])),
        p: &mut Piece,
        ccw: bool,
        hop: &Hop,
        flip: bool,
    ) -> Result<(), WalkError> {
        // One entry for both ends, reserved first and dropped if neither end uses it.
        let entry = exacts.entries().len();
        let at = entry.checked_mul(2).ok_or(WalkError::TreeTooDeep)?;
        let ([x0, x1], below) = exacts.reserve()?;
        let thin = cross(p.from.angle.vector(), p.to.angle.vector()) == 0;
        // Mapped in counter-clockwise order from the frame's eye.
        let (lo, hi) = if ccw {
            (&mut p.from, &mut p.to)
        } else {
            (&mut p.to, &mut p.from)
        };
        let chain = HopChain {
            eye,
            hops,
            points: self.scene.vertices(),
        };
        self.map_end((below, x0, at, chain), lo, hop, flip)?;
        self.map_end((below, x1, at + 1, chain), hi, hop, flip)?;
        if lo.exact.is_none() && hi.exact.is_none() {
            exacts.truncate_to(entry);
        }
        // Counter-clockwise from the eye behind the hop.
        let (a, b) = if flip { (&*hi, &*lo) } else { (&*lo, &*hi) };
        if thin || cross(a.angle.vector(), b.angle.vector()) <= 0 {
            let keep = if a.pointed && !b.pointed {
                a.clone()
            } else {
                b.clone()
            };
            p.from = keep.clone();
            p.to = keep;
        }
        Ok(())
    }

    /// Splits the piece `p` seen from `level` by the edges of `m` and continues its first
    /// edge piece (written over `p`). `true` if a frame was pushed, as
    /// [`Tree::resolve_piece`].
    fn split<F: Frames>(
        &self,
        sc: &mut Stacks<F>,
        level: Level,
        m: ObjectId,
        kind: SplitKind,
        p: &mut Piece,
    ) -> Result<bool, WalkError> {
        match self.first_edge(sc, level, m, kind, p)? {
            Some((edge, left)) => self.change_eye(sc, level, m, kind, p, edge, left),
            None => Ok(false),
        }
    }

    /// Cuts the first edge piece of the split of `p`'s range (seen from `level`'s eye) by
    /// the edges of `m`, written over `p`: its edge, and whether the split is done with it.
    /// The split frame is pushed only if more may follow: a split done with its first piece
    /// leaves its place to that piece's frame (the usual mirror piece lies on one edge; a
    /// frame is large, and every push a copy). `None` if no edge piece: nothing pushed, the
    /// stacks restored as `level`'s pop would. Out of line: inlined, its locals would sit
    /// in the frame of every change of eye below it (+128 B of the firmware's stack).
    #[inline(never)]
    fn first_edge<F: Frames>(
        &self,
        sc: &mut Stacks<F>,
        level: Level,
        m: ObjectId,
        kind: SplitKind,
        p: &mut Piece,
    ) -> Result<Option<(Edge, bool)>, WalkError> {
        // The split's place, as if pushed.
        sc.room(level, true)?;
        // Direct-mapped: the slot holds `m`'s edge, or another object's. Only splits by
        // front edges keep hints (see [`Edges`]).
        let front = kind.front();
        let slot = m.0 as usize % EDGE_HINTS;
        let hint = sc.edges.get(slot).copied().flatten();
        let hint = hint.filter(|&(o, _)| front && o == m).map(|(_, k)| k);
        let mut cut = Cut {
            m,
            kind,
            last: None,
            hint,
            done: false,
        };
        let (stage, index) = sc.lengths()?;
        let eye = sc.eye();
        let Some(e) = cut.next(
            self,
            Ends::new(sc.exacts.flat(), (sc.eye, &sc.hops), self.scene.vertices()),
            (eye, level.ccw),
            (Some(&p.from), &p.to),
        ) else {
            sc.restore(level);
            return Ok(None);
        };
        if let (true, Some(h), Some(k)) = (front, sc.edges.get_mut(slot), cut.last) {
            *h = Some((m, k));
        }
        let left = cut.done;
        if !left {
            // More pieces may follow: the frame keeps the range's end, before `p` becomes
            // the first.
            sc.push_split(
                level,
                Split {
                    level,
                    cut,
                    to: p.to.clone(),
                    walks: 0,
                },
            )?;
        }
        // `p` is the range: the ends and boundary the piece shares with it are there.
        self.write_edge_piece((eye, stage, index), &e, p, None)?;
        Ok(Some((e.edge, left)))
    }

    /// Continues the edge piece `p` (its range in the split frame's direction, overwritten
    /// by the range seen behind the edge as [`Tree::map_range`] has it, and its first
    /// boundary) of the split of `m` seen from `level`'s eye across the edge: the virtual
    /// eye beyond it, the hop on the stack and the frame that walks on (for an entry edge,
    /// first the split by the exit edges, [`Tree::first_edge`]). `left`: the split (of
    /// `level`) is not on the stack, done with this piece; the frame holds its place and
    /// restores its stacks. `true` if a frame was pushed, as [`Tree::resolve_piece`].
    #[allow(clippy::too_many_arguments)]
    fn change_eye<F: Frames>(
        &self,
        sc: &mut Stacks<F>,
        level: Level,
        m: ObjectId,
        kind: SplitKind,
        p: &mut Piece,
        edge: Edge,
        left: bool,
    ) -> Result<bool, WalkError> {
        let here = self.hop(sc, level, kind, p, edge, left)?;
        // Behind a refractive object's exit edge, neighbouring pieces' walks mostly start
        // in one cylinder: a hint pays there (not behind mirrors).
        let (here, hint) = match kind {
            #[cfg(feature = "refraction")]
            SplitKind::Entry(eta) => {
                let exit = SplitKind::Exit(eta);
                let Some((edge, left)) = self.first_edge(sc, here, m, exit, p)? else {
                    return Ok(false);
                };
                (self.hop(sc, here, exit, p, edge, left)?, true)
            }
            // An exit split's later pieces (its first is continued above).
            _ => (here, !kind.front()),
        };
        sc.branch.push(m).map_err(|_| WalkError::TreeTooDeep)?;
        let deeper = Level {
            depth: level.depth - 1,
            ..here
        };
        self.push_range_walk(sc, deeper, m, (&p.from, &p.to), &p.boundary, hint)?;
        Ok(true)
    }

    /// The change of eye across the edge `(ia, ib)` of the edge piece `p` of a split by
    /// `kind` seen from `level`'s eye: the hop pushed, `p`'s range mapped behind it; the
    /// level of the frame that continues it (turned where the hop flips orientation,
    /// holding the split's place if `left`, as [`Tree::change_eye`]). Inlined: a call
    /// cost the hall and mixed frames about 1 % more instructions.
    #[inline(always)]
    fn hop<F: Frames>(
        &self,
        sc: &mut Stacks<F>,
        level: Level,
        kind: SplitKind,
        p: &mut Piece,
        (ia, ib): Edge,
        left: bool,
    ) -> Result<Level, WalkError> {
        let eye = sc.eye();
        let index = sc.branch.len();
        let (a, b) = (self.point(ia), self.point(ib));
        let (eye2, flip, hop_level) = match kind {
            #[cfg(feature = "mirrors")]
            SplitKind::Mirror => (optics::reflect(eye, a, b), true, index + 1),
            // The inside stage hits the refractive object itself.
            #[cfg(feature = "refraction")]
            SplitKind::Entry(eta) => (optics::refract(eye, a, b, eta, true), false, index),
            #[cfg(feature = "refraction")]
            SplitKind::Exit(eta) => (optics::refract(eye, a, b, eta, false), false, index + 1),
        };
        let eye2 = eye2.ok_or(WalkError::EyeOutOfRange)?;
        // A mirror's image lies across the edge's line, a refracted eye on the same side.
        let (aq, bq) = (a.to_query(), b.to_query());
        let (s0, s1) = (side(aq, bq, eye), side(aq, bq, eye2));
        if s1 == Sign::Zero || (s1 == s0) == flip {
            return Err(WalkError::DegenerateOptics { level: index });
        }
        // Vertex indices are below `MAX_VERTICES`, and levels bounded by the branch.
        let hop = Hop::new((ia, ib), eye2, hop_level).ok_or(WalkError::TreeTooDeep)?;
        let turned = Level {
            ccw: level.ccw != flip,
            ..level
        };
        let here = if left {
            turned.holding(true)?
        } else {
            turned.marks(sc)?
        };
        self.map_range(
            (&mut sc.exacts, (sc.eye, &sc.hops)),
            p,
            level.ccw,
            &hop,
            flip,
        )?;
        sc.hops.push(hop)?;
        Ok(here)
    }

    /// The edges of `m` facing `eye` (`front`) or facing away from it: each as `(a, b)` in
    /// `m`'s order and as `(s0, s1)`, its endpoints counter-clockwise from the eye (a front
    /// edge spans b → a, a back edge a → b), global vertex indices; and its index in `m`.
    fn facing_edges(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        front: bool,
    ) -> impl Iterator<Item = FacingEdge> + Clone + '_ {
        let (f, n) = self
            .scene
            .object(m)
            .map_or((0, 0), |o| (o.first_vertex(), o.len()));
        (0..n).filter_map(move |k| facing(self, eye, (f, n), front, k))
    }

    /// Edge `k` of `m` as [`Tree::facing_edges`] yields it, if it faces that way.
    fn facing_edge(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        front: bool,
        k: usize,
    ) -> Option<FacingEdge> {
        let o = self.scene.object(m)?;
        if k >= o.len() {
            return None;
        }
        facing(self, eye, (o.first_vertex(), o.len()), front, k)
    }

    /// The edge of `m` facing `eye` (`front`) or facing away where the ray from `eye` at
    /// `a` crosses its outline, if it is such an edge: a guess (by `a`'s rounded vector),
    /// see [`Cut::next`]. One cross product a vertex: the outline crosses the ray's line
    /// where the vertices' side of it changes, into the object at a front edge, out at a
    /// back edge. Out of line: inlined, the compiler built `push_range_walk`'s frame by a
    /// copy (+1.2 % instructions in the hall frame).
    #[inline(never)]
    fn edge_toward(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        front: bool,
        a: &Angle,
    ) -> Option<FacingEdge> {
        let o = self.scene.object(m)?;
        let (f, n) = (o.first_vertex(), o.len());
        // `cross(p − eye, d)`, negated: products of `i64`s, a difference below 2⁵³ times a
        // component below 2⁶³.
        let d = a.vector64()?;
        let side = |p: &Point| {
            let p = p.to_query();
            -offset_cross(d, p.x() - eye.x(), p.y() - eye.y())
        };
        let outline = self.scene.vertices().get(f..f + n)?;
        let (head, rest) = outline.split_first()?;
        let first = side(head);
        let mut s = first;
        // Edge `k` runs from vertex `k` to `k + 1`, the last one back to the first (this
        // loop, not `skip` and a chained side: −0.15 % instructions in the mixed frame).
        for (k, p) in rest.iter().map(Some).chain([None]).enumerate() {
            let t = p.map_or(first, side);
            // Its ends counter-clockwise from the eye (as `facing` orders them) right of
            // the ray or on it, then left of it or on it.
            let (s0, s1) = if front { (t, s) } else { (s, t) };
            if s0 >= 0 && s1 <= 0 {
                return facing(self, eye, (f, n), front, k);
            }
            s = t;
        }
        None
    }

    /// The edge of a split of a range collapsed onto the direction of `hi`: the edge
    /// crossed just before it, else just after it.
    fn split_collapsed(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        hi: &Dir,
        front: bool,
    ) -> Option<(usize, usize)> {
        let h = hi.angle.vector();
        let edges = self.facing_edges(eye, m, front).map(|(e, (s0, s1), _)| {
            let (v0, v1) = (diff(self.qpoint(s0), eye), diff(self.qpoint(s1), eye));
            (e, cross(v0, h), cross(h, v1))
        });
        let before = edges.clone().find(|&(_, c0, c1)| c0 > 0 && c1 >= 0);
        let edge = before.or_else(|| edges.clone().find(|&(_, c0, c1)| c0 >= 0 && c1 > 0));
        edge.map(|(e, _, _)| e)
    }
}

/// A facing edge: `(a, b)` in the object's order, its endpoints counter-clockwise from the
/// eye, and its index in the object (see [`Tree::facing_edges`]).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
type FacingEdge = ((usize, usize), (usize, usize), usize);

/// Edge `k` of the polygon of `n` vertices from global index `f`, as
/// [`Tree::facing_edges`] yields it, if it faces `eye` (`front`) or faces away.
#[cfg(any(feature = "mirrors", feature = "refraction"))]
fn facing<S: Storage>(
    tree: &Tree<'_, '_, S>,
    eye: QueryPoint,
    (f, n): (usize, usize),
    front: bool,
    k: usize,
) -> Option<FacingEdge> {
    let (ia, ib) = (f + k, f + (k + 1) % n);
    match (front, side(tree.qpoint(ia), tree.qpoint(ib), eye)) {
        (true, Sign::Negative) => Some(((ia, ib), (ib, ia), k)),
        (false, Sign::Positive) => Some(((ia, ib), (ia, ib), k)),
        _ => None,
    }
}

#[cfg(any(feature = "mirrors", feature = "refraction"))]
impl SplitKind {
    /// Whether the split is by the edges facing the eye (not the exit edges).
    fn front(self) -> bool {
        match self {
            #[cfg(feature = "refraction")]
            SplitKind::Exit(_) => false,
            #[allow(unreachable_patterns)]
            _ => true,
        }
    }
}

#[cfg(any(feature = "mirrors", feature = "refraction"))]
impl Split {
    /// The next edge piece in the frame's direction (never the first, [`Split`]): its
    /// edge, with its range in walk order and its first boundary written to `out` (its
    /// ceiling is left as it is); `eye`, `stage` and `level` as for
    /// [`RangeWalk::next_piece`].
    #[inline]
    fn next_edge<S: Storage>(
        &mut self,
        tree: &Tree<'_, '_, S>,
        ends: Ends<'_>,
        (eye, stage, level): (QueryPoint, u8, u8),
        out: &mut Piece,
    ) -> Result<Option<Edge>, WalkError> {
        let ccw = self.level.ccw;
        // Never: a split on the stack has cut its first piece.
        if self.cut.last.is_none() && !self.cut.done {
            return Err(WalkError::Corrupt);
        }
        let Some(e) = self.cut.next(tree, ends, (eye, ccw), (None, &self.to)) else {
            return Ok(None);
        };
        tree.write_edge_piece((eye, stage, level), &e, out, Some(&self.to))?;
        Ok(Some(e.edge))
    }
}

#[cfg(any(feature = "mirrors", feature = "refraction"))]
impl Cut {
    /// The next edge piece of the range `(from, to)` seen from `eye` in the direction
    /// `ccw`. The nonempty pieces are disjoint, so each is the one whose start comes first
    /// after the last one's. `from` is needed for the first piece only, and later ones are
    /// cut without it (a first piece without it is `None`, never): each starts where the
    /// last one ended, strictly inside the range, so every test against `from` holds for it.
    fn next<S: Storage>(
        &mut self,
        tree: &Tree<'_, '_, S>,
        ends: Ends<'_>,
        (eye, ccw): (QueryPoint, bool),
        (from, to): (Option<&Dir>, &Dir),
    ) -> Option<EdgePiece> {
        if self.done {
            return None;
        }
        let front = self.kind.front();
        // The counter-clockwise ends; `None`: `from`, not at hand.
        let (lo, hi) = if ccw {
            (from, Some(to))
        } else {
            (Some(to), from)
        };
        let (lv, hv) = (lo.map(|d| d.angle.vector()), hi.map(|d| d.angle.vector()));
        // Both ends on one direction (see `map_range`): the one edge the ray just before
        // `hi` crosses, else the one just after it, as `push_range_walk` takes such a range.
        // Only a first piece: such a split is done with it.
        if let (Some(l), Some(h), Some(hi)) = (lv, hv, hi) {
            if cross(l, h) == 0 {
                self.done = true;
                let edge = tree.split_collapsed(eye, self.m, hi, front)?;
                return Some(EdgePiece {
                    edge,
                    start: None,
                    end: None,
                });
            }
        }
        // Whether `v` turns `s` from the end `d` (`None`: `from` for a later piece, which
        // lies after it).
        let turns =
            |d: Option<&Dir>, v: (i128, i128), s: Sign| d.is_none_or(|d| d.turn(ends, v) == s);
        // In walk order: `a` before `b`.
        let before = |a: (i128, i128), b: (i128, i128)| {
            let c = cross(a, b);
            if ccw {
                c > 0
            } else {
                c < 0
            }
        };
        // An edge's piece of the range: (walk start key, start vertex, end vertex), or
        // `None` where the edge does not face the eye or the piece is empty.
        let piece = |((_, _), (s0, s1)): ((usize, usize), (usize, usize))| {
            let (v0, v1) = (diff(tree.qpoint(s0), eye), diff(tree.qpoint(s1), eye));
            // Against the range ends exactly (`Dir::turn`), counter-clockwise.
            let sv = turns(lo, v0, Sign::Positive).then_some(v0);
            let ev = turns(hi, v1, Sign::Negative).then_some(v1);
            let nonempty = match (sv, ev) {
                (Some(a), Some(b)) => cross(a, b) > 0,
                (None, Some(b)) => turns(lo, b, Sign::Positive),
                (Some(a), None) => turns(hi, a, Sign::Negative),
                (None, None) => lv.zip(hv).is_some_and(|(l, h)| cross(l, h) > 0),
            };
            if !nonempty {
                return None;
            }
            // An end without its vertex is at hand (`turns` holds for an end not at hand).
            Some(if ccw {
                (sv.or(lv)?, sv.map(|_| s0), ev.map(|_| s1))
            } else {
                (ev.or(hv)?, ev.map(|_| s1), sv.map(|_| s0))
            })
        };
        // The facing edges of a convex polygon are seen in polygon order (front edges
        // counter-clockwise in decreasing order, back edges in increasing order), and the
        // pieces of the range are contiguous: after the first piece, the next is the
        // neighbouring edge's, or there is none. It starts at the vertex the two edges
        // share, where the last piece ended (it was not done, so it ended strictly inside
        // the range, after its own start): after the last piece.
        let next = self.last.and_then(|k| {
            let k = k.get();
            let n = tree.scene.object(self.m).map_or(0, |o| o.len());
            let up = front != ccw;
            let k = if up {
                (k + 1) % n.max(1)
            } else {
                (k + n - 1) % n.max(1)
            };
            let e = tree.facing_edge(eye, self.m, front, k)?;
            let (key, start, end) = piece((e.0, e.1))?;
            Some((key, e.0, start, end, k))
        });
        // The first piece: the hinted edge's if it starts at the start of the range (no
        // start vertex: every other piece starts strictly inside it), else the one
        // starting first. Without a hint (exit splits keep none), the edge the ray at the
        // start crosses is the likely one: tried the same way, it spares the scan's exact
        // turns (a wrong guess costs time, not a wrong piece).
        let first = |from: &Dir| {
            let tried = match self.hint {
                Some(k) => tree.facing_edge(eye, self.m, front, k.get()),
                None => tree.edge_toward(eye, self.m, front, &from.angle),
            };
            let hinted = tried.and_then(|(edge, ends, k)| {
                let (key, start, end) = piece((edge, ends))?;
                start.is_none().then_some((key, edge, start, end, k))
            });
            if hinted.is_some() {
                return hinted;
            }
            let mut best = None;
            for (edge, ends, k) in tree.facing_edges(eye, self.m, front) {
                let Some((key, start, end)) = piece((edge, ends)) else {
                    continue;
                };
                if best
                    .as_ref()
                    .is_none_or(|(b, ..): &((i128, i128), _, _, _, _)| before(key, *b))
                {
                    best = Some((key, edge, start, end, k));
                }
                // A piece from the start of the range (no start vertex) comes first: every
                // other piece starts strictly inside the range.
                if start.is_none() {
                    break;
                }
            }
            best
        };
        let found = match (self.last, from) {
            (Some(_), _) => next,
            (None, Some(from)) => first(from),
            // Never (see above).
            (None, None) => None,
        };
        let Some((_, edge, start, end, k)) = found else {
            self.done = true;
            return None;
        };
        // `None` never (an object's edge), which would only end the split early. The piece
        // reaches the end of the range: the facing edges' pieces are disjoint, so no later
        // one is nonempty.
        self.last = EdgeIndex::new(k);
        self.done = self.last.is_none() || end.is_none();
        Some(EdgePiece { edge, start, end })
    }
}

#[cfg(any(feature = "mirrors", feature = "refraction"))]
impl<S: Storage> Tree<'_, '_, S> {
    /// Writes the edge piece `e` seen from `eye` (its boundaries at the given stage and
    /// level) to `out`: its range in walk order and its first boundary, the end it shares
    /// with the split's range from `to` (the range's end) — or already in `out` if `None`
    /// (the piece the split was made from: the usual mirror piece is the whole range,
    /// nothing to copy back). Field by field: a piece's fields are large, and every move is
    /// a copy.
    fn write_edge_piece(
        &self,
        (eye, stage, level): (QueryPoint, u8, u8),
        e: &EdgePiece,
        out: &mut Piece,
        to: Option<&Dir>,
    ) -> Result<(), WalkError> {
        match (e.start, to) {
            // The hit (or exit) edge changes at vertex `v`.
            (Some(v), _) => {
                out.from = self.toward(eye, v);
                out.boundary = self.event_boundary((stage, level), &out.from);
            }
            (None, None) => {}
            // Never: only a first piece starts at the range's start, and it is cut with the
            // range at hand ([`Tree::first_edge`]).
            (None, Some(_)) => return Err(WalkError::Corrupt),
        }
        match (e.end, to) {
            (Some(v), _) => out.to = self.toward(eye, v),
            (None, Some(to)) => out.to = to.clone(),
            (None, None) => {}
        }
        Ok(())
    }
}

/// Whether the hit at `u = nu / den` (`den ≠ 0`) on an edge lies at or beyond its end `b`
/// (`Some(true)`: `u ≥ 1`) or its start `a` (`Some(false)`: `u ≤ 0`), or strictly inside
/// (`None`), as `u` in `f64` places it — the quotient of the correctly rounded terms, which
/// lies in (0, 1) only if the exact one does — but computed only near 1. It is `≤ 0` exactly
/// where `nu / den` is (nonzero terms keep their signs, and `|u| > 2⁻¹²⁸` does not
/// underflow) and `≥ 1` where `|nu| ≥ |den|` (rounding is monotonic), and nowhere else
/// unless `|den| − |nu| ≤ |den|·2⁻⁴⁸`: below that the rounded terms' quotient is
/// `< (1 − 2⁻⁴⁸)(1 + 2⁻⁵³)/(1 − 2⁻⁵³) < 1 − 2⁻⁴⁹`, which rounds below 1. Two software
/// `i128` conversions spared per range end mapped (−1.1 % instructions in the hall frame).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
#[inline]
fn edge_end(nu: i128, den: i128) -> Option<bool> {
    let (n, d) = (nu.unsigned_abs(), den.unsigned_abs());
    if nu == 0 || (nu < 0) != (den < 0) {
        Some(false)
    } else if n >= d || (d - n <= d >> 48 && to_f64(nu) / to_f64(den) >= 1.0) {
        Some(true)
    } else {
        None
    }
}

/// `libm::round(x)` (nearest, ties away from zero) for `|x| < 2⁶²`, or NaN: the
/// truncation `x as i64` and the fraction `x − trunc` are exact there, so this is the same
/// value without the software routine (a mapped range end rounds two).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
fn round_away(x: f64) -> f64 {
    let t = x as i64;
    let f = x - t as f64;
    let r = if f >= 0.5 {
        t + 1
    } else if f <= -0.5 {
        t - 1
    } else {
        t
    };
    if x.is_nan() {
        x
    } else {
        r as f64
    }
}

/// The direction `d` from the previous eye, hitting the line of the mirror edge `e` at
/// `t = num / den` (`den = cross(d, e)`), seen from the virtual eye, exactly, if `e` is
/// axis-parallel: there the virtual eye is the exact reflection of the previous one
/// ([`optics::reflect`] rounds nothing), so the hit `X` seen from it is the hit seen from
/// the previous eye reflected — `X − next = t·R(d)`, `R` negating the coordinate across the
/// edge. `None` for another edge, `t = 0` or a direction out of range.
#[cfg(any(feature = "mirrors", feature = "refraction"))]
fn reflected(d: (i128, i128), e: (i128, i128), num: i128, den: i128) -> Option<Direction> {
    let r = match e {
        (0, _) => (-d.0, d.1),
        (_, 0) => (d.0, -d.1),
        _ => return None,
    };
    let r = match num.signum() * den.signum() {
        1 => r,
        -1 => (-r.0, -r.1),
        _ => return None,
    };
    Direction::new(i64::try_from(r.0).ok()?, i64::try_from(r.1).ok()?)
}

fn side(a: QueryPoint, b: QueryPoint, p: QueryPoint) -> Sign {
    Sign::of_i128(cross(diff(b, a), diff(p, a)))
}

/// Whether `a` lies exactly at θ = 0 but the perturbation puts it just below 2π.
pub(super) fn wraps(a: &Angle) -> bool {
    a.is_exactly_zero()
        && a.cmp_angle(&Angle::constant(Direction { x: 1, y: -1 })) == Ordering::Greater
}

/// `cross(d, p − e)`, with single widening products where `d` fits in 64 bits (every
/// direction of a walk does: a `Direction`, or a difference of query points); `p − e` does
/// (`< 2⁵⁴`). Bit budget as [`cross`].
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
#[inline]
fn cross_q(d: (i128, i128), p: QueryPoint, e: QueryPoint) -> i128 {
    let (wx, wy) = (p.x() - e.x(), p.y() - e.y());
    match (i64::try_from(d.0), i64::try_from(d.1)) {
        (Ok(x), Ok(y)) => i128::from(x) * i128::from(wy) - i128::from(y) * i128::from(wx),
        _ => d.0 * i128::from(wy) - d.1 * i128::from(wx),
    }
}

fn cross(u: (i128, i128), v: (i128, i128)) -> i128 {
    u.0 * v.1 - u.1 * v.0
}

/// `p − e`, subtracted in 64 bits (query coordinates are at most 2⁵² in magnitude): the
/// compiler then knows the values fit in 64 bits and multiplies them as such.
fn diff(p: QueryPoint, e: QueryPoint) -> (i128, i128) {
    let (x, y) = diff64(p, e);
    (i128::from(x), i128::from(y))
}

/// [`diff`] kept in `i64` (below 2⁵³ in magnitude), for `i64` factors.
fn diff64(p: QueryPoint, e: QueryPoint) -> (i64, i64) {
    (p.x() - e.x(), p.y() - e.y())
}

/// Whether a ray tree looks past an object of `material` with `depth` levels left: always
/// through a screen, into a mirror or refractive object while depth remains.
fn continues(material: Material, depth: usize) -> bool {
    match material {
        Material::Screen => true,
        Material::Mirror | Material::Refractive { .. } => depth > 0,
        Material::Opaque => false,
    }
}

/// The candidate vertex on the ray nearest to its origin: `along(v)` is `None` off the
/// ray, else the (scaled) distance along it, which must be positive.
fn nearest_on_ray<K: PartialOrd + Default>(
    candidates: impl Iterator<Item = usize>,
    along: impl Fn(usize) -> Option<K>,
) -> Option<usize> {
    let mut best: Option<(K, usize)> = None;
    for v in candidates {
        let Some(k) = along(v) else { continue };
        if k > K::default() && best.as_ref().is_none_or(|(b, _)| k < *b) {
            best = Some((k, v));
        }
    }
    best.map(|(_, v)| v)
}

/// Stages (hops) whose boundary directions [`Tree::resolve`] maps exactly: `Wide` holds
/// 9 hops; later stages are tested in `f64`.
const MAX_STAGES: usize = 12;

#[cfg(all(test, feature = "alloc"))]
mod tests {
    use alloc::format;
    use alloc::vec::Vec;

    use super::ray_tree;
    use crate::geom::{Point, QueryPoint};
    use crate::partition::build_by_sweep;
    use crate::scene::{Eta, Material, ObjectId, Scene};
    use crate::walk::{view, WalkError};

    fn rect(x0: i32, y0: i32, x1: i32, y1: i32) -> Vec<Point> {
        let p = |x: i32, y: i32| Point::from_raw(x << 16, y << 16).unwrap();
        alloc::vec![p(x0, y0), p(x1, y0), p(x1, y1), p(x0, y1)]
    }

    /// Opaque boxes left of and below the eye `(0.5, 0.25)`, and object 1 of `material`
    /// right of it, facing the left box.
    fn scene(material: Material) -> Scene {
        let objects = [
            (Material::Opaque, rect(-6, -2, -4, 1)),
            (material, rect(4, -1, 6, 2)),
            (Material::Opaque, rect(-3, -7, 3, -5)),
        ];
        Scene::new(objects.iter().map(|(m, p)| (*m, p.as_slice()))).unwrap()
    }

    fn eye() -> QueryPoint {
        QueryPoint::from_f64(0.5, 0.25).unwrap()
    }

    /// Whether this build follows rays past objects of `material` (its cargo feature).
    fn compiled(material: Material) -> bool {
        match material {
            Material::Mirror => cfg!(feature = "mirrors"),
            Material::Refractive { .. } => cfg!(feature = "refraction"),
            Material::Screen => cfg!(feature = "screens"),
            Material::Opaque => true,
        }
    }

    /// A ray tree that meets a ray type compiled out is `RayTypeDisabled` naming the object
    /// and the feature; with the feature on it is a tree (through the mirror: the left box
    /// reflected). Runs in every feature combination (`.ci/run` runs it with none).
    #[test]
    fn ray_types_follow_the_cargo_features() {
        let eta = Eta::from_f64(1.5).unwrap();
        for material in [
            Material::Mirror,
            Material::Refractive { eta },
            Material::Screen,
        ] {
            let s = scene(material);
            let (s, name) = (s.as_ref(), material.name());
            let c = build_by_sweep(&s).unwrap();
            match (compiled(material), ray_tree(&c, &s, eye(), 1)) {
                (false, Err(e)) => {
                    assert_eq!(
                        e,
                        WalkError::RayTypeDisabled {
                            object: ObjectId(1),
                            material
                        }
                    );
                    let feature = e.missing_feature().unwrap();
                    let shown = format!("{e}");
                    assert!(shown.contains(feature) && shown.contains(name), "{shown}");
                }
                (true, Ok(tree)) if material == Material::Mirror => {
                    let through = [ObjectId(1), ObjectId(0)];
                    assert!(tree.iter().any(|t| t.branch == through), "{tree:?}");
                }
                (true, Ok(_)) => {}
                (on, r) => panic!("{name}: feature on: {on}, tree {r:?}"),
            }
        }
    }

    /// A xorshift generator of integers uniform in `-m..=m`.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    fn uniform(seed: u64) -> impl FnMut(i64) -> i64 {
        let mut next = crate::geom::xorshift(seed);
        move |m| (next() % (2 * m as u64 + 1)) as i64 - m
    }

    /// `edge_end` places the hit on the edge as the `f64` quotient does, also where the
    /// quotient rounds to 1 (`nu` just below `den`, at every magnitude) and at the margin
    /// of its exact shortcut.
    #[cfg(any(feature = "mirrors", feature = "refraction"))]
    #[test]
    fn edge_end_is_the_f64_quotient() {
        use super::{edge_end, to_f64};
        let mut next = uniform(0x9e37_79b9_7f4a_7c15u64);
        let (mut near, mut checked) = (0, 0);
        for round in 0..200_000u32 {
            // `den` of 4 to 124 bits, `nu` off `±den` by a gap of up to 70 bits, or anywhere.
            let wide = (i128::from(next(1 << 62)) << 62) + i128::from(next(1 << 62));
            let den = wide >> next(120).unsigned_abs();
            if den == 0 {
                continue;
            }
            let gap =
                i128::from(next(1 << 62) >> next(62).unsigned_abs()) << next(8).unsigned_abs();
            let nu = match round % 4 {
                0 => den - gap,
                1 => -den + gap,
                _ => i128::from(next(1 << 62)) << next(40).unsigned_abs(),
            };
            let u = to_f64(nu) / to_f64(den);
            let expected = if u <= 0.0 {
                Some(false)
            } else if u >= 1.0 {
                Some(true)
            } else {
                None
            };
            assert_eq!(edge_end(nu, den), expected, "nu {nu} den {den}");
            near += usize::from(nu.unsigned_abs() < den.unsigned_abs() && expected == Some(true));
            checked += 1;
        }
        assert!(checked > 150_000 && near > 100, "{checked} {near}");
    }

    /// Through an axis-parallel mirror edge, the reflected exact direction of a range end
    /// (`reflected`, `reflect_axis`) is the direction to the hit point from the virtual
    /// eye, as `map_end`'s general formula `sign(den)·((prev − next)·den + num·d)` has it.
    #[cfg(feature = "mirrors")]
    #[test]
    fn axis_mirror_hop_reflects_the_exact_direction() {
        use super::mapped::reflect_axis;
        use super::{cross, diff, reflected};
        use crate::geom::wide::Wide;
        use crate::geom::Sign;
        use crate::walk::optics;
        let mut next = uniform(0x2545_f491_4f6c_dd1du64);
        let mut compared = 0;
        for round in 0..2000 {
            let (x, y, len) = (
                next(1 << 20) as i32,
                next(1 << 20) as i32,
                next(1 << 10) as i32,
            );
            let (a, b) = if round % 2 == 0 {
                (Point::from_raw(x, y), Point::from_raw(x, y + len))
            } else {
                (Point::from_raw(x, y), Point::from_raw(x + len, y))
            };
            let (Some(a), Some(b)) = (a, b) else { continue };
            let Some(prev) = QueryPoint::from_raw(next(1 << 40), next(1 << 40)) else {
                continue;
            };
            let Some(eye2) = optics::reflect(prev, a, b) else {
                continue;
            };
            let e = diff(b.to_query(), a.to_query());
            let e1 = (e.0.signum(), e.1.signum());
            let d = (i128::from(next(1 << 40)), i128::from(next(1 << 40)));
            let (den, num) = (cross(d, e1), cross(diff(a.to_query(), prev), e1));
            if den == 0 || num == 0 {
                continue;
            }
            let pn = diff(prev, eye2);
            let general = (
                den.signum() * (den * pn.0 + num * d.0),
                den.signum() * (den * pn.1 + num * d.1),
            );
            // An exact angle, and a wide exact direction.
            let r = reflected(d, e1, num, den).unwrap();
            let r = (i128::from(r.x), i128::from(r.y));
            assert_eq!(cross(r, general), 0, "round {round}");
            assert!(r.0 * general.0 + r.1 * general.1 > 0, "round {round}");
            let wide = (Wide::from_i128(d.0), Wide::from_i128(d.1));
            let mut out = (Wide::default(), Wide::default());
            assert!(reflect_axis(&wide, e1, num, &mut out), "round {round}");
            assert_eq!(
                Wide::cross_sign(&out, general),
                Some(Sign::Zero),
                "round {round}"
            );
            let dot = Wide::dot(&out, general).map(|w| w.sign());
            assert_eq!(dot, Some(Sign::Positive), "round {round}");
            compared += 1;
        }
        assert!(compared > 1000, "{compared}");
    }

    /// The boundary-direction filter of `resolve`: mapped back through hops modulo P it
    /// agrees (up to sign) with the exact 1024-bit mapping's residue at every stage, and
    /// gives up exactly where a denominator may vanish (a direction along an edge).
    #[cfg(any(feature = "mirrors", feature = "refraction"))]
    #[test]
    fn residue_mapping_agrees_with_the_exact_mapping() {
        use super::{Hop, Tree, P};
        use crate::geom::wide::Wide;
        let s = scene(Material::Mirror);
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        let tree = Tree {
            complex: &c,
            scene: &s,
        };
        let mut next = uniform(0x9e37_79b9_7f4a_7c15u64);
        let same = |r: (u64, u64), w: (Wide, Wide)| {
            let (x, y) = (w.0.residue(), w.1.residue());
            r == (x, y) || r == ((P - x) % P, (P - y) % P)
        };
        let mut compared = 0;
        for round in 0..200 {
            let q = |x: i64, y: i64| QueryPoint::from_raw(x << 20, y << 20).unwrap();
            let first = q(next(1000), next(1000));
            let hops: Vec<Hop> = (0..1 + round % 5)
                .map(|_| {
                    let k = next(5).unsigned_abs() as usize % 4;
                    let eye = q(next(1000), next(1000));
                    Hop::new((4 + k, 4 + (k + 1) % 4), eye, 0).unwrap()
                })
                .collect();
            // Every fourth round the direction runs along the last hop's edge.
            let dir = if round % 4 == 0 {
                let h = hops.last().unwrap();
                let (a, b) = (tree.qpoint(h.a()), tree.qpoint(h.b()));
                (
                    i128::from(b.x()) - i128::from(a.x()),
                    i128::from(b.y()) - i128::from(a.y()),
                )
            } else {
                (i128::from(next(1 << 50)), i128::from(next(1 << 50)))
            };
            let mut r = Some((
                crate::geom::wide::residue_i128(dir.0),
                crate::geom::wide::residue_i128(dir.1),
            ));
            let mut d = Some((Wide::from_i128(dir.0), Wide::from_i128(dir.1)));
            for st in (0..hops.len()).rev() {
                let hop = (super::eye_before(first, &hops, st), &hops[st]);
                r = r.and_then(|r| tree.map_hop_residue(hop, r));
                d = d.and_then(|d| tree.map_hop_exact(hop, &d));
                if round % 4 == 0 && st + 1 == hops.len() {
                    assert!(r.is_none(), "round {round}: along the edge");
                }
                if let (Some(r), Some(d)) = (r, d) {
                    assert!(same(r, d), "round {round}, stage {st}");
                    compared += 1;
                }
            }
        }
        assert!(compared > 300, "{compared}");
    }

    /// Depth 0 needs no ray type but screens: the tree is the view in every build.
    #[test]
    fn depth_zero_tree_is_the_view_without_ray_features() {
        let eta = Eta::from_f64(1.5).unwrap();
        for material in [Material::Mirror, Material::Refractive { eta }] {
            let s = scene(material);
            let s = s.as_ref();
            let c = build_by_sweep(&s).unwrap();
            let (tree, v) = (ray_tree(&c, &s, eye(), 0), view(&c, &s, eye()));
            let (tree, v) = (tree.unwrap(), v.unwrap());
            assert_eq!(tree.len(), v.len());
            for (t, v) in tree.iter().zip(&v) {
                assert_eq!(t.branch.first().copied(), v.object);
                assert_eq!(t.branch.len(), usize::from(v.object.is_some()));
                assert_eq!(t.start_vertex, v.start_vertex);
            }
        }
    }

    /// `render::hit_along` follows a branch through a mirror only with `mirrors`: the ray
    /// right from the eye meets the mirror at x = 4 (3.5 away) and the left box at x = −4
    /// (8 more).
    #[test]
    fn hit_along_follows_the_cargo_features() {
        let s = scene(Material::Mirror);
        let branch = [ObjectId(1), ObjectId(0)];
        let hit = crate::render::hit_along(&s.as_ref(), eye(), (1.0, 0.0), &branch);
        assert_eq!(hit.is_some(), cfg!(feature = "mirrors"), "{hit:?}");
        if let Some(h) = hit {
            assert!(libm::fabs(h.first - 3.5) < 1e-9 && libm::fabs(h.length - 11.5) < 1e-9);
        }
    }

    /// The primary walk of a range starts at `f` in the cylinder the walk from θ = 0 is in
    /// just after `f`, found through the objects behind, ahead or (a line that meets
    /// nothing) beside the eye; it falls back to θ = 0 only where a vertex lies on the line.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    #[test]
    fn primary_start_is_where_the_walk_from_zero_is() {
        use super::{Anchor, Trace, Tree, Walker};
        use crate::geom::predicates::Direction;
        use crate::geom::sos::Angle;
        use core::cmp::Ordering;
        let tri = |x: i32, y: i32| {
            let p = |x: i32, y: i32| Point::from_raw(x << 16, y << 16).unwrap();
            alloc::vec![p(x, y), p(x + 3, y + 1), p(x + 1, y + 4)]
        };
        let objects = [
            (Material::Mirror, rect(-9, -2, -7, 3)),
            (Material::Opaque, tri(2, 5)),
            (Material::Opaque, rect(4, -6, 9, -5)),
            (Material::Opaque, tri(-5, -9)),
            (Material::Mirror, rect(6, 1, 7, 8)),
            (Material::Opaque, tri(-4, 6)),
        ];
        let s = Scene::new(objects.iter().map(|(m, p)| (*m, p.as_slice()))).unwrap();
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        let tree = Tree {
            complex: &c,
            scene: &s,
        };
        let (mut routes, mut fallbacks) = ([0usize; 3], 0);
        let mut seed = 7u64;
        let mut next = |m: u64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) % m
        };
        for _ in 0..3000 {
            let (x, y) = (
                next(2400) as f64 / 100.0 - 12.0,
                next(2400) as f64 / 100.0 - 12.0,
            );
            let q = QueryPoint::from_f64(x, y).unwrap();
            let Ok(start) = c.trace_start(&s, q) else {
                continue;
            };
            // Random directions, and now and then one through a vertex.
            let d = if next(8) == 0 {
                let v = s.vertices()[next(s.vertices().len() as u64) as usize].to_query();
                Direction::new(v.x() - q.x(), v.y() - q.y()).unwrap()
            } else {
                let (dx, dy) = (next(2001) as i64 - 1000, next(2001) as i64 - 1000);
                Direction::new(dx << next(30), dy << next(30)).unwrap_or(Direction { x: 1, y: 0 })
            };
            let f = Angle::constant(d);
            let (id, theta) = tree.primary_start(q, start, &f);
            if theta.cmp_exact(&Angle::ZERO) == Ordering::Equal {
                assert_eq!(id, start);
                fallbacks += 1;
                continue;
            }
            let trace = Trace::new(q, Anchor::Point, None);
            let mut walker: Walker = Walker::new(start, Angle::ZERO, true);
            let mut at = start;
            while let Some(step) = walker.next_step(&c, &s, &trace).unwrap() {
                if step.angle.cmp_exact(&f) == Ordering::Greater {
                    break;
                }
                at = step.cylinder;
            }
            assert_eq!(id, at, "q {q:?} d {d:?}");
            let cyl = c.cylinder(id).unwrap();
            routes[match (cyl.floor, cyl.ceiling) {
                (Some(_), _) => 0,
                (None, Some(_)) => 1,
                (None, None) => 2,
            }] += 1;
        }
        // Every route is taken, and the fallback is rare.
        assert!(routes.iter().all(|&r| r > 20), "{routes:?}");
        assert!(
            fallbacks * 4 < routes.iter().sum::<usize>(),
            "{fallbacks} {routes:?}"
        );
    }

    /// Three boxes and two triangles around the origin, and their complex with its arc
    /// vertices: the scene of the anchored-start tests.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    fn anchored() -> (Scene, crate::partition::Complex) {
        let tri = |x: i32, y: i32| {
            let p = |x: i32, y: i32| Point::from_raw(x << 16, y << 16).unwrap();
            alloc::vec![p(x, y), p(x + 3, y + 1), p(x + 1, y + 4)]
        };
        let objects = [
            rect(-9, -2, -7, 3),
            tri(2, 5),
            rect(4, -6, 9, -5),
            tri(-5, -9),
            rect(6, 1, 7, 8),
        ];
        let s = Scene::new(objects.iter().map(|p| (Material::Opaque, p.as_slice()))).unwrap();
        let c = build_by_sweep(&s.as_ref())
            .unwrap()
            .with_arc_vertices(&s.as_ref());
        (s, c)
    }

    /// The eyes of the anchored-walk tests, with the two tangent vertices of a wall of `c`:
    /// for each wall, on its line beyond either tangent point (openings exactly at the
    /// wall's angle, through one of its vertices), then `anywhere` eyes in the scene's box
    /// drawn from `seed`.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    fn wall_eyes(
        c: &crate::partition::Complex,
        s: &crate::scene::SceneRef<'_>,
        anywhere: usize,
        seed: u64,
    ) -> Vec<(QueryPoint, [usize; 2])> {
        let mut next = uniform(seed);
        let mut eyes = Vec::new();
        for v in c.vertices() {
            let b = v.bitangent;
            let (p, r) = (s.vertices()[b.first], s.vertices()[b.second]);
            let (p, r) = (p.to_query(), r.to_query());
            for k in 0..4 + anywhere {
                let q = if k < 4 {
                    let t = [-2, -1, 2, 3][k];
                    QueryPoint::from_raw(p.x() + t * (r.x() - p.x()), p.y() + t * (r.y() - p.y()))
                } else {
                    QueryPoint::from_f64(
                        next(2400) as f64 / 100.0 - 12.0,
                        next(2400) as f64 / 100.0 - 12.0,
                    )
                    .ok()
                };
                eyes.extend(q.map(|q| (q, [b.first, b.second])));
            }
        }
        eyes
    }

    /// The start cylinder the climb of a floor's sheet finds (`Tree::stack_floor`: chain
    /// sides by bounding box, arc vertex or the floor's extremes, one wall tested) is the
    /// one the scan with the full containment test finds, for eyes on the lines of walls
    /// (openings exactly at a wall's angle, through one of its vertices) and elsewhere; and
    /// a chain's side (`Tree::chain_after`) is the side of its extreme vertex line; the
    /// containment test (`Tree::contains_after`) reads the same with arc vertices as without.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    #[test]
    fn stack_floor_is_the_scans() {
        use super::{ranked, Bound, Chain, Tree};
        use crate::geom::sos::Angle;
        use crate::geom::Sign;
        use crate::partition::Wall;
        use crate::scene::ObjectId;
        use core::cmp::Ordering;
        let (s, c) = anchored();
        let s = s.as_ref();
        let tree = Tree {
            complex: &c,
            scene: &s,
        };
        // The containment test without arc vertices reads every chain's vertices.
        let with = c.as_slices();
        let without = crate::partition::Complex {
            borders: with.borders_ref().without_arcs(),
            ..with.clone()
        };
        let plain = Tree {
            complex: &without,
            scene: &s,
        };
        let (mut climbed, mut at_wall, mut inside) = (0, 0, 0);
        for (q, hs) in wall_eyes(&c, &s, 2, 5) {
            for h in hs {
                let a = Angle::from_query(q, ranked(&s, h));
                for (m, ccw) in (0..s.len() as u32).flat_map(|m| [(m, true), (m, false)]) {
                    let m = ObjectId(m);
                    for bound in [Bound::Lower, Bound::Upper] {
                        // The reference: some vertex on the chain's side by the full rule.
                        let o = s.object(m).unwrap();
                        let some = if bound == Bound::Lower {
                            Sign::Negative
                        } else {
                            Sign::Positive
                        };
                        let any = (o.first_vertex()..o.first_vertex() + o.len()).any(|v| {
                            match super::cross_q(a.vector(), tree.qpoint(v), q) {
                                0 => tree.side_after(q, &a, v, ccw) == some,
                                x => Sign::of_i128(x) == some,
                            }
                        });
                        let chain = Chain { object: m, bound };
                        let side = tree.chain_after(q, &a, chain, ccw);
                        assert_eq!(side == some, any, "{q:?} {a:?} {chain:?}");
                    }
                    for (i, cyl) in c.cylinders().iter().enumerate() {
                        let id = crate::partition::CylinderId::from_index(i).unwrap();
                        let fast = tree.contains_after(q, &a, (id, cyl), ccw, &[]);
                        let full = plain.contains_after(q, &a, (id, cyl), ccw, &[]);
                        assert_eq!(fast, full, "{q:?} {a:?} {id:?}");
                        inside += usize::from(fast);
                    }
                    let Some(id) = tree.stack_floor(q, m, &a, ccw) else {
                        continue;
                    };
                    assert_eq!(tree.scan_floor(q, m, &a, ccw).ok(), Some(id), "{q:?} {a:?}");
                    climbed += 1;
                    let cyl = c.cylinder(id).unwrap();
                    let on = |w: Wall| {
                        c.wall_angle(&s, w)
                            .is_some_and(|w| w.cmp_exact(&a) == Ordering::Equal)
                    };
                    at_wall += usize::from(on(cyl.left) || on(cyl.right));
                }
            }
        }
        assert!(climbed > 1000 && at_wall > 100, "{climbed} {at_wall}");
        assert!(inside > 1000, "{inside}");
    }

    /// The angle an anchored walk starts from (`Tree::locate_floor`) is the last tangent in
    /// walk order, from either chain's object of the start cylinder, exactly on the opening
    /// ray and on its near side — found here from all tangents of both objects, without
    /// the filter by vertices on the line or the one look at an object on both chains —
    /// for eyes on the lines of walls, whose tangents lie on the ray.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    #[test]
    fn locate_floor_starts_past_the_tangents_on_the_ray() {
        use super::{ranked, wraps, Dir, Tree, FLOOR_HINTS};
        use crate::geom::sos::Angle;
        use crate::scene::ObjectId;
        use core::cmp::Ordering;
        let (s, c) = anchored();
        let s = s.as_ref();
        let tree = Tree {
            complex: &c,
            scene: &s,
        };
        let (mut located, mut moved, mut by_top) = (0, 0, 0);
        for (q, hs) in wall_eyes(&c, &s, 0, 0) {
            for h in hs {
                let fwd = Angle::from_query(q, ranked(&s, h));
                for (a, m, ccw) in [fwd, fwd.reversed()].into_iter().flat_map(|a| {
                    (0..s.len() as u32).flat_map(move |m| [(a, m, true), (a, m, false)])
                }) {
                    let m = ObjectId(m);
                    let mut floors = [None; FLOOR_HINTS];
                    let found = tree.locate_floor((&mut floors, false), q, m, &Dir::at(a), ccw);
                    let Ok((id, theta)) = found else { continue };
                    let cyl = c.cylinder(id).unwrap();
                    let zero = a.is_exactly_zero();
                    let mut want = match (ccw, zero) {
                        (true, true) if wraps(&a) => Some(Angle::ZERO),
                        (false, true) => None,
                        _ => Some(a),
                    };
                    let behind = if ccw {
                        Ordering::Greater
                    } else {
                        Ordering::Less
                    };
                    let mut touched = [false; 2];
                    for (i, chain) in [cyl.bottom, cyl.top].into_iter().enumerate() {
                        let Some(o) = chain.map(|ch| ch.object).filter(|&o| o != m) else {
                            continue;
                        };
                        let (tangents, count) = crate::line_space::tangents_from(&s, o, q);
                        let mut on = false;
                        for &(k, _) in tangents.iter().take(count) {
                            let f = Angle::from_query(q, ranked(&s, k));
                            for x in [f, f.reversed()] {
                                if x.cmp_exact(&a) == Ordering::Equal
                                    && wraps(&x) == (!ccw && zero)
                                    && want.is_none_or(|w| x.cmp_angle(&w) == behind)
                                {
                                    want = Some(x);
                                    on = true;
                                }
                            }
                        }
                        touched[i] |= on;
                    }
                    let same = match (theta, want) {
                        (Some(x), Some(y)) => x.cmp_angle(&y) == Ordering::Equal,
                        (x, y) => x.is_none() && y.is_none(),
                    };
                    assert!(same, "{q:?} {a:?} {m:?} {ccw}: {theta:?}, want {want:?}");
                    located += 1;
                    moved += usize::from(touched != [false; 2]);
                    // The top chain's object gave the start angle, not the bottom's.
                    by_top += usize::from(touched == [false, true]);
                }
            }
        }
        assert!(
            located > 2000 && moved > 100 && by_top > 50,
            "{located} {moved} {by_top}"
        );
    }

    /// An anchored walk's first piece written over the range it was pushed with (`fresh`:
    /// the start, end and boundary it shares with the range not written) is the piece
    /// written whole, and so are the pieces after it, for ranges between vertices'
    /// directions from eyes on the lines of walls and elsewhere, with starts exact or not.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    #[test]
    fn fresh_range_walk_pieces_are_the_written_ones() {
        use super::{
            cross, ranked, Boundary, Cluster, Dir, Ends, Frame, Level, Mapped, Piece, Stacks, Top,
            Tree,
        };
        use crate::geom::predicates::Direction;
        use crate::geom::sos::Angle;
        let (s, c) = anchored();
        let s = s.as_ref();
        let tree = Tree {
            complex: &c,
            scene: &s,
        };
        let (mut walks, mut pieces, mut moved) = (0, 0, 0);
        let n = s.vertices().len();
        for (q, hs) in wall_eyes(&c, &s, 1, 7) {
            let toward = |h: usize| Dir::vertex(Angle::from_query(q, ranked(&s, h)), h);
            for (h, ccw) in hs.into_iter().flat_map(|h| [(h, true), (h, false)]) {
                let from = toward(h);
                // The same start as an exact end whose angle is rounded before it in walk
                // order (by about 10⁻⁶ rad, as mapped through a hop): the walk then meets
                // the event of `h` on the opening ray, which moves the start onto `h`.
                let v = from.angle.vector();
                let exacts = [Mapped::exactly((v.0 as i64, v.1 as i64), 0)];
                let mapped = Ends::new(&exacts, (QueryPoint::ORIGIN, &[]), &[]);
                let (mut x, mut y) = v;
                while x.abs().max(y.abs()) >= 1 << 30 {
                    (x, y) = (x >> 1, y >> 1);
                }
                let t = if ccw { 1 } else { -1 };
                let (x, y) = ((x << 20) + t * y, (y << 20) - t * x);
                let d = Direction::new(x as i64, y as i64).unwrap();
                let exact = Dir {
                    exact: Some(0),
                    ..Dir::at(Angle::constant(d))
                };
                // Ends a few vertices' directions on, less than a half turn.
                let sign = |t: &Dir| cross(from.angle.vector(), t.angle.vector()).signum();
                let ends = (0..n)
                    .map(toward)
                    .filter(|t| sign(t) == if ccw { 1 } else { -1 });
                for (to, from) in ends
                    .take(3)
                    .flat_map(|t| [(t.clone(), from.clone()), (t, exact.clone())])
                {
                    let first = Boundary {
                        stage: 0,
                        angle: from.angle,
                        level: 0,
                        fallback: h as u32,
                        falls_back: true,
                    };
                    let level = Level {
                        depth: 1,
                        ccw,
                        hops: 0,
                        branch: 0,
                        exacts: 0,
                        held_walks: 0,
                        held_splits: 0,
                    };
                    for m in (0..s.len() as u32).map(ObjectId) {
                        let run = |fresh: bool| {
                            let mut sc = Stacks::growing();
                            sc.eye = q;
                            tree.push_range_walk(&mut sc, level, m, (&from, &to), &first, false)
                                .ok()?;
                            let mut out = Piece::empty();
                            if fresh {
                                (out.from, out.to, out.boundary) =
                                    (from.clone(), to.clone(), first);
                            }
                            let (mut fresh, mut c) = (fresh, Cluster::empty());
                            let mut written = Vec::new();
                            let Some(Top::Walk(Frame::Walk(w))) = sc.frames.top() else {
                                return None;
                            };
                            while w
                                .next_piece(&tree, mapped, (q, 0, 0), (&mut out, fresh), &mut c)
                                .ok()?
                            {
                                fresh = false;
                                let Piece {
                                    from,
                                    to,
                                    ceiling,
                                    boundary,
                                } = &out;
                                written.push(format!("{from:?} {to:?} {ceiling:?} {boundary:?}"));
                            }
                            Some(written)
                        };
                        let whole = run(false);
                        assert_eq!(run(true), whole, "{q:?} {from:?} {to:?} {m:?} {ccw}");
                        walks += usize::from(whole.is_some());
                        let start = format!("{from:?} ");
                        moved +=
                            usize::from(whole.as_ref().is_some_and(|w| {
                                w.first().is_some_and(|p| !p.starts_with(&start))
                            }));
                        pieces += whole.map_or(0, |w| w.len());
                    }
                }
            }
        }
        assert!(
            walks > 1000 && pieces > walks && moved > 100,
            "{walks} {pieces} {moved}"
        );
    }

    /// A split's pieces (`Cut::next`) are the same whatever edge hint it starts with: none
    /// (the guess of `Tree::edge_toward`), each edge of the object, or out of range (the
    /// scan alone), for front and back edges, ranges on the object (as split: they hit it)
    /// between its vertices' directions and directions just off them, from eyes on the
    /// lines of walls and elsewhere.
    #[cfg(feature = "refraction")]
    #[test]
    fn split_pieces_do_not_depend_on_the_hint() {
        use super::{cross, diff, ranked, Cut, Dir, EdgeIndex, Ends, SplitKind, Tree};
        use crate::geom::predicates::Direction;
        use crate::geom::sos::Angle;
        let (s, c) = anchored();
        let s = s.as_ref();
        let tree = Tree {
            complex: &c,
            scene: &s,
        };
        let eta = Eta::from_f64(1.5).unwrap();
        let (mut splits, mut pieces, mut guessed) = (0, 0, 0);
        for (q, _) in wall_eyes(&c, &s, 1, 11).into_iter().step_by(3) {
            for m in (0..s.len() as u32).map(ObjectId) {
                let o = s.object(m).unwrap();
                let ids = o.first_vertex()..o.first_vertex() + o.len();
                // Only eyes outside `m`, and directions whose ray hits it.
                if tree.facing_edges(q, m, true).next().is_none() {
                    continue;
                }
                let hits = |d: &Dir| {
                    let d = d.angle.vector();
                    let v = ids.clone().map(|k| diff(tree.qpoint(k), q));
                    let c = v.clone().map(|v| cross(v, d));
                    c.clone().any(|c| c >= 0)
                        && c.clone().any(|c| c <= 0)
                        && v.clone().any(|v| v.0 * d.0 + v.1 * d.1 > 0)
                };
                // Each vertex's direction, and ones just either side of it.
                let dirs: Vec<Dir> = ids
                    .clone()
                    .flat_map(|h| {
                        let at = Dir::vertex(Angle::from_query(q, ranked(&s, h)), h);
                        let (mut x, mut y) = at.angle.vector();
                        while x.abs().max(y.abs()) >= 1 << 30 {
                            (x, y) = (x >> 1, y >> 1);
                        }
                        let off = |t: i128| {
                            let d = Direction::new(
                                ((x << 20) - t * y) as i64,
                                ((y << 20) + t * x) as i64,
                            );
                            d.map(|d| Dir::at(Angle::constant(d)))
                        };
                        [Some(at), off(1), off(-1)]
                    })
                    .flatten()
                    .filter(hits)
                    .collect();
                for (from, to) in dirs.iter().flat_map(|a| dirs.iter().map(move |b| (a, b))) {
                    let turn = cross(from.angle.vector(), to.angle.vector());
                    let ccw = turn > 0;
                    for kind in [SplitKind::Entry(eta), SplitKind::Exit(eta)] {
                        // `from` at every piece, or (as a split frame has it) at the
                        // first only.
                        let run_from = |hint: Option<EdgeIndex>, every: bool| {
                            let mut cut = Cut {
                                m,
                                kind,
                                last: None,
                                hint,
                                done: false,
                            };
                            let mut out = Vec::new();
                            for i in 0..o.len() + 2 {
                                let from = (every || i == 0).then_some(from);
                                let ends = Ends::new(&[], (q, &[]), &[]);
                                let Some(e) = cut.next(&tree, ends, (q, ccw), (from, to)) else {
                                    break;
                                };
                                out.push((e.edge, e.start, e.end));
                            }
                            out
                        };
                        let run = |hint: Option<EdgeIndex>| {
                            let out = run_from(hint, false);
                            assert_eq!(out, run_from(hint, true), "{q:?} {from:?} {to:?} {m:?}");
                            out
                        };
                        let scan = run(EdgeIndex::new(o.len()));
                        let far = EdgeIndex::new(u32::MAX as usize - 1);
                        for hint in (0..o.len()).map(EdgeIndex::new).chain([None, far]) {
                            assert_eq!(run(hint), scan, "{q:?} {from:?} {to:?} {m:?} {hint:?}");
                        }
                        let start = if ccw { &from.angle } else { &to.angle };
                        let guess = tree.edge_toward(q, m, kind.front(), start);
                        splits += usize::from(turn != 0);
                        pieces += scan.len();
                        guessed += usize::from(
                            scan.first()
                                .is_some_and(|p| p.1.is_none() && guess.map(|e| e.0) == Some(p.0)),
                        );
                    }
                }
            }
        }
        assert!(
            splits > 50_000 && pieces > splits && guessed > splits / 2,
            "{splits} {pieces} {guessed}"
        );
    }

    /// The side of a cylinder's arc taken at its arc vertex (`Tree::arc_after`) is the
    /// chain's side by all its vertices (`Tree::chain_after`), at the walls' angles and
    /// between them, from eyes all around.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    #[test]
    fn arc_vertex_side_is_the_chains() {
        use super::Tree;
        use crate::geom::predicates::Direction;
        use crate::geom::sos::Angle;
        use crate::partition::{CylinderId, Wall, NO_ARC_VERTEX};
        let (s, c) = anchored();
        let s = s.as_ref();
        let tree = Tree {
            complex: &c,
            scene: &s,
        };
        let mut next = uniform(11);
        let (mut by_arc, mut on_line) = (0, 0);
        for (i, cyl) in c.cylinders().iter().enumerate() {
            let id = CylinderId::from_index(i).unwrap();
            let (Wall::Vertex(_), Wall::Vertex(_)) = (cyl.left, cyl.right) else {
                continue;
            };
            let (l, r) = (
                c.wall_angle(&s, cyl.left).unwrap(),
                c.wall_angle(&s, cyl.right).unwrap(),
            );
            let mut angles = alloc::vec![l, r];
            // Between the walls: the sum of their directions, for a range under a half turn.
            let (lv, rv) = (l.vector(), r.vector());
            if lv.0 * rv.1 - lv.1 * rv.0 > 0 {
                let d = Direction::new((lv.0 + rv.0) as i64, (lv.1 + rv.1) as i64).unwrap();
                angles.push(Angle::constant(d));
            }
            let arcs = c.borders_ref().arcs(id);
            for (top, chain) in [(false, cyl.bottom), (true, cyl.top)] {
                let Some(chain) = chain else { continue };
                let v = arcs[usize::from(top)];
                if v == NO_ARC_VERTEX {
                    continue;
                }
                for a in &angles {
                    // Random eyes, and eyes on the line through the arc vertex.
                    for k in 0..8 {
                        let q = if k < 2 {
                            let p = tree.qpoint(v as usize);
                            let (dx, dy) = a.vector();
                            let t = next(3) as i128;
                            QueryPoint::from_raw(
                                (p.x() as i128 + t * dx) as i64,
                                (p.y() as i128 + t * dy) as i64,
                            )
                        } else {
                            QueryPoint::from_f64(
                                next(1200) as f64 / 100.0,
                                next(1200) as f64 / 100.0,
                            )
                            .ok()
                        };
                        let Some(q) = q else { continue };
                        for ccw in [true, false] {
                            let s_arc = tree.arc_after(q, a, (id, chain, top), ccw);
                            assert_eq!(
                                s_arc,
                                tree.chain_after(q, a, chain, ccw),
                                "{i} {a:?} {q:?}"
                            );
                            match super::cross_q(a.vector(), tree.qpoint(v as usize), q) {
                                0 => on_line += 1,
                                _ => by_arc += 1,
                            }
                        }
                    }
                }
            }
        }
        assert!(by_arc > 1000 && on_line > 100, "{by_arc} {on_line}");
    }

    /// A walk's clusters end for good: after the last one every call is `false`, and after
    /// the walker fails (a walk round and round, past its step bound, as in `walk`'s
    /// `a_walk_that_does_not_end_is_corrupt`) every call is `Corrupt` — answered without
    /// the walker once it is over.
    #[test]
    fn clusters_stay_ended_and_failed() {
        use super::{Anchor, Angle, Cluster, Events, Position, Trace, Walker};
        let s = scene(Material::Opaque);
        let s = s.as_ref();
        let c = build_by_sweep(&s).unwrap();
        let start = c.trace_start(&s, eye()).unwrap();
        let out = &mut Cluster::empty();
        for (lap, last) in [(1, Ok(false)), (u8::MAX, Err(WalkError::Corrupt))] {
            let end = Position {
                lap,
                angle: Angle::ZERO,
            };
            let trace = Trace::new(eye(), Anchor::Point, Some(end));
            let mut events = Events::new(Walker::new(start, Angle::ZERO, true), false);
            let mut clusters = 0;
            let ended = loop {
                match events.cluster(&c, &s, &trace, out) {
                    Ok(true) => clusters += 1,
                    r => break r,
                }
            };
            assert!(clusters > 4, "{clusters}");
            for _ in 0..3 {
                assert_eq!(ended, last);
                assert_eq!(events.cluster(&c, &s, &trace, out), last);
            }
        }
    }
}
