//! Walking the complex (DESIGN.md §6, the paper's §5): the lines through a point `q` form
//! its trace in line space; sweeping a ray around `q` walks the trace from cylinder to
//! cylinder. Across a secondary wall the walk moves to the right neighbour; across a
//! primary wall (a chain of object H, crossed where the line through `q` is tangent to H
//! at `h`) it moves to the cylinder on the other side — and where H is crossed on that
//! side, into the layer before H if `h` lies ahead of `q`, after H otherwise (the paper's
//! "stay on the sheet or hop", Fig. 6). No predicate is needed for that choice: the
//! tangent line's orientation says whether `h` is ahead.
//!
//! The walk starts at θ = 0 among the cylinders crossing the permanent wall and visits
//! the events in perturbed order; the view is the sequence of ceilings.
//!
//! # Ray trees (`frame_tree_into` without a heap; `ray_tree` and friends with `alloc`)
//!
//! The walker has two anchorings ([`Anchor`]): `Point` (the layer containing the eye, the
//! view) and `Floor(M)` (the layer whose floor is M: the segments starting where the line
//! leaves M), walked over an exact open angular range from a (virtual) eye, in either
//! direction (`Walker`: resumable, one event per call). An anchored walk starts in the
//! cylinder with floor M that contains the eye's line just after the range start (just
//! before it, walking clockwise), turned by more than the symbolic perturbation
//! (everything exactly on the opening ray is behind: the range is open), found by climbing
//! the stack of M's floor cylinders through the per-chain tilings (`Complex::across`; a
//! scan only where something lies exactly on the opening ray and the two disagree); events
//! on the closing ray are dropped.
//!
//! Each piece of a walk (a run with one ceiling) is resolved by its ceiling —
//! * a **screen** S: the same eye walks the same range anchored to S (S is not in the
//!   branch and uses no depth);
//! * a **mirror** M: the range is split by the directions to M's vertices (the hit edge
//!   changes there); per edge the eye is reflected across the edge's line and rounded
//!   exactly to the query grid ([`optics`]); the range is mapped to the new eye (exactly
//!   `E' → v` at a vertex of the edge, otherwise the direction to the hit point on the
//!   edge — computed in `f64` at 2⁻⁵² rad, it only places the range end); mirrors flip
//!   orientation, so the new eye walks it anchored to M **clockwise** where the mirror's
//!   eye walked counter-clockwise (and back at the next mirror), one level deeper;
//! * a **refractive** M (tangent law, DESIGN.md §6): split by the entry edge, entry eye
//!   `E₁ = F + η(E − F)`, split by the exit edge (M's own vertices seen from `E₁`), exit
//!   eye `E₂ = F' + (E₁ − F')/η`, walked anchored to M; orientation is preserved, and the
//!   pass is one depth level with M once in the branch.
//!
//! **Lock step** (the paper's §5): the generations in use are a stack of frames in a
//! fixed-capacity [`TreeScratch`] — the primary walk, per level the split by a mirror's or
//! refractive object's edges and the walk behind it, a walk behind each screen on the way.
//! The top frame yields its next piece, which is a leaf or pushes the frame resolving it;
//! an exhausted frame is popped and its parent resumes. Since every walk goes in the
//! direction that maps to counter-clockwise primary directions, the leaves come out in
//! primary order and each generation advances exactly as far as the primary direction: no
//! buffering, no allocation, no recursion. Leaves with equal branches merge into intervals
//! as they come; a boundary's vertex is resolved when the first leaf after it arrives,
//! while the hops it was made through are still on the stack. The `alloc` entry points
//! ([`ray_tree`], [`ray_tree_range`], [`frame_tree`]) collect the same stream.
//!
//! Boundaries deeper than the primary are mapped back to primary angles in `f64` for
//! output.
//!
//! A rounded eye on or across its interface line is an error
//! ([`WalkError::DegenerateOptics`], as in the reference); an eye beyond the query range
//! (`|raw| > 2⁵²`, e.g. after refraction by a large η far from the interface) is
//! [`WalkError::EyeOutOfRange`].
//!
//! The cargo features `mirrors`, `refraction` and `screens` compile in the three kinds of
//! interval resolution above; without one, a tree that meets such an object (a mirror or
//! refractive object with depth to spare, or any screen) is
//! [`WalkError::RayTypeDisabled`], never a tree that silently stops there.
//!
//! **The tangent law against Snell's law.** The tangent law `tan θ₂ = tan θ₁ / η` keeps
//! refraction a change of eye (every refracted ray passes through one virtual point), but
//! it bends less than Snell's `sin θ₂ = sin θ₁ / η` near grazing incidence and has no
//! critical angle. Refraction angle θ₂ in degrees for η = 1.5, from
//! `tests/tests/ray_trees.rs` (`tangent_law_error_table`, run with `--nocapture` for
//! η = 1.33 and 1.6 as well):
//!
//! | θ₁ | Snell | tangent law | error |
//! |---:|---:|---:|---:|
//! | 0 | 0.000 | 0.000 | +0.000 |
//! | 10 | 6.648 | 6.704 | +0.057 |
//! | 20 | 13.180 | 13.639 | +0.459 |
//! | 30 | 19.471 | 21.052 | +1.581 |
//! | 40 | 25.374 | 29.223 | +3.849 |
//! | 50 | 30.710 | 38.467 | +7.757 |
//! | 60 | 35.264 | 49.107 | +13.842 |
//! | 70 | 38.790 | 61.367 | +22.578 |
//! | 80 | 41.036 | 75.185 | +34.149 |
//! | 85 | 41.616 | 82.524 | +40.908 |
//! | 89 | 41.803 | 88.500 | +46.698 |

pub mod optics;
mod tree;
mod view;

#[cfg(feature = "alloc")]
pub use tree::{frame_tree, ray_tree, ray_tree_range, TreeInterval};
pub use tree::{frame_tree_into, TreeScratch, TreeSpan, MAX_TREE_DEPTH};
#[cfg(feature = "alloc")]
pub use view::{view, view_range};
pub use view::{view_capacity, view_into, view_range_into, ViewInterval};

use crate::geom::sos::{Angle, KeyedAngle};
use crate::geom::QueryPoint;
use crate::line_space::{ranked, Bound, Chain};
use crate::partition::{
    Complex, Cylinder, CylinderId, Layer, Location, Side, Storage, Wall, NO_ARC_VERTEX,
};
use crate::scene::{ObjectId, SceneRef};

/// Entries of the tangent cache of a ray tree's walkers (one set of two, see [`Walker`]):
/// each frame of a [`TreeScratch`] holds one, 16 bytes an entry, cleared at every walk.
/// A walk behind a mirror or refractive object takes a few steps from an eye of its own
/// (2.4 on average in the hall at depth 5, where a virtual eye almost never walks twice),
/// so few entries pay: two take 0.35 % fewer instructions per hall frame than eight and
/// 0.14 % per mixed frame (four: 0.24 % and 0.20 %), clearing and copying less of the
/// frame; a depth-1 frame on the n = 1024 grid (a primary walk) is not slower either.
const TANGENT_CACHE: usize = 2;

/// Entries of the tangent cache of a view's walk ([`Complex::walk_from`]), one walker on
/// the stack: a grid view from n = 1024 meets about 40 objects' chains, revisited all
/// around the circle (32 entries miss a third more often: +3.3 % instructions per view
/// for 512 B less stack; 128 cost more to clear than they save). Measured without the arc
/// vertices (`BordersRef`), as a complex over caller-provided slices walks; with them the
/// cache serves only the arcs that are not one vertex's (on the n = 1024 grid two misses
/// per view instead of 52).
const VIEW_TANGENT_CACHE: usize = 64;

/// How a walk follows a trace across primary walls.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Anchor {
    /// Stay in the layer containing the eye (the view from a point): across a chain where
    /// the object is crossed, the layer before it if its tangent vertex is ahead of the
    /// eye, after it otherwise.
    Point,
    /// Stay in the layer whose floor is this object (the segments starting where the line
    /// leaves it): across a chain where its object H is crossed, the layer before H (H
    /// appears between the floor and the old ceiling); leaving it, the single layer. Used
    /// behind mirrors, refractive objects and screens; the eye is virtual and may lie
    /// anywhere.
    Floor(ObjectId),
}

/// A position on the unwrapped circle of a range walk: `lap` 1 is past θ = 2π
/// (counter-clockwise) or past θ = 0 (clockwise, see [`Walker`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Position {
    pub(crate) lap: u8,
    pub(crate) angle: Angle,
}

/// One step of a walk: the trace entered `cylinder` at `angle`, crossing the chain of the
/// object of `vertex` (a global vertex index) or, with `vertex: None`, a secondary wall.
#[derive(Clone, Copy, Debug)]
pub struct Step {
    /// Where the step happens.
    pub angle: Angle,
    /// The tangent vertex whose chain was crossed; `None` for a secondary wall.
    pub vertex: Option<usize>,
    /// Whether that vertex lies ahead of `q` (so the step can change the view).
    pub ahead: bool,
    /// The cylinder entered.
    pub cylinder: CylinderId,
}

/// Leaving a cylinder across a primary wall: the chain, the side of it entered, the tangent
/// vertex and whether it lies ahead of the viewpoint.
#[derive(Clone, Copy)]
struct ChainExit {
    chain: Chain,
    side: Side,
    vertex: usize,
    ahead: bool,
}

/// Why a walk could not be done.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum WalkError {
    /// The viewpoint is inside or on an object.
    NotFree(Location),
    /// The complex is inconsistent (no cylinder across a wall, or the walk did not end).
    Corrupt,
    /// A virtual eye rounded to the query grid fell on or across the interface line it was
    /// built from (the reference's `DegenerateOptics`); `level` is the branch index of the
    /// mirror or refractive object.
    DegenerateOptics {
        /// Depth level of the interaction.
        level: usize,
    },
    /// A virtual eye left the query range (`|raw| > 2⁵²`, about ±10⁶ units).
    EyeOutOfRange,
    /// An anchored walk found no cylinder with the anchor as floor at its start (a range
    /// end placed in `f64` missed the object's sheet: a range thinner than `f64` resolves).
    NoStart,
    /// The caller's output buffer is full ([`view_into`]): `needed` is a lower bound of
    /// the length that would do ([`view_capacity`] is always enough).
    BufferFull {
        /// Intervals produced so far, plus the one that did not fit.
        needed: usize,
    },
    /// The complex is pruned to a region of viewpoints (`vcx build --region`,
    /// [`Complex::region`]) and the viewpoint lies outside it: the cylinders its view
    /// needs may be missing.
    OutsideRegion(crate::partition::Region),
    /// A ray tree needs a ray type whose code this build of `vcx` leaves out: `object`
    /// (with its `material`) is a mirror or refractive object met with depth to spare, or
    /// a screen, and the cargo feature `mirrors`, `refraction` or `screens` is off
    /// ([`WalkError::missing_feature`]).
    RayTypeDisabled {
        /// The object the ray tree met.
        object: ObjectId,
        /// Its material.
        material: crate::scene::Material,
    },
    /// A ray tree needs more frames (generations, screens on the way) or a longer branch
    /// than its [`TreeScratch`] holds.
    TreeTooDeep,
}

impl WalkError {
    /// The cargo feature of `vcx` that would avoid this error, for
    /// [`WalkError::RayTypeDisabled`].
    pub fn missing_feature(&self) -> Option<&'static str> {
        match self {
            WalkError::RayTypeDisabled { material, .. } => match material {
                crate::scene::Material::Mirror => Some("mirrors"),
                crate::scene::Material::Refractive { .. } => Some("refraction"),
                crate::scene::Material::Screen => Some("screens"),
                crate::scene::Material::Opaque => None,
            },
            _ => None,
        }
    }
}

impl core::fmt::Display for WalkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            WalkError::NotFree(Location::Inside { object }) => {
                write!(f, "viewpoint is inside object {}", object.0)
            }
            WalkError::NotFree(Location::OnBoundary { object }) => {
                write!(f, "viewpoint is on the boundary of object {}", object.0)
            }
            WalkError::NotFree(Location::Free { .. }) => write!(f, "viewpoint is free"),
            WalkError::Corrupt => write!(f, "the complex is inconsistent"),
            WalkError::DegenerateOptics { level } => {
                write!(f, "rounded virtual eye is degenerate at level {level}")
            }
            WalkError::EyeOutOfRange => write!(f, "a virtual eye left the query range"),
            WalkError::NoStart => write!(f, "an anchored walk found no start cylinder"),
            WalkError::TreeTooDeep => write!(f, "the ray tree is deeper than its scratch holds"),
            WalkError::BufferFull { needed } => {
                write!(f, "output buffer full: at least {needed} intervals needed")
            }
            WalkError::OutsideRegion(r) => {
                let ((x0, y0), (x1, y1)) = (r.min().to_f64(), r.max().to_f64());
                write!(
                    f,
                    "viewpoint outside the region {x0},{y0},{x1},{y1} the complex was pruned to"
                )
            }
            WalkError::RayTypeDisabled { object, material } => write!(
                f,
                "the ray tree meets {} object {}, but vcx was built without the cargo feature \
                 `{}` (enable it to follow rays past it)",
                material.name(),
                object.0,
                self.missing_feature().unwrap_or("?")
            ),
        }
    }
}

impl core::error::Error for WalkError {}

impl<S: Storage> Complex<S> {
    /// Walks the trace of the free point `q` once around, from θ = 0, calling `step` for
    /// every cylinder entered (the first call is the start cylinder, with `vertex: None`).
    /// Allocates nothing; every iteration enters a new cylinder, and the walk is bounded by
    /// four times the number of cylinders. The start cylinder is found among the cylinders
    /// at θ = 0 (left wall [`Wall::Zero`]) in arena order: both constructions number those
    /// first (the sweep creates them first, `History::complex` puts them first), so the
    /// scan stops within them — O(cylinders at θ = 0), about 3n for the grid scenes — and
    /// the exact test runs only on those whose chains' heights bracket `q`.
    ///
    /// A complex pruned to a region ([`Complex::region`]) walks only from points inside it
    /// ([`WalkError::OutsideRegion`] otherwise); a link it lacks stops the walk with
    /// [`WalkError::Corrupt`].
    pub fn walk_trace(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        mut step: impl FnMut(&Step),
    ) -> Result<(), WalkError> {
        let cur = self.trace_start(scene, q)?;
        step(&Step {
            angle: Angle::ZERO,
            vertex: None,
            ahead: false,
            cylinder: cur,
        });
        self.walk_from(scene, q, Anchor::Point, cur, Angle::ZERO, None, &mut step)
    }

    /// The cylinder of the trace of the free point `q` at θ = 0, where
    /// [`Complex::walk_trace`] starts (see there).
    pub(crate) fn trace_start(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
    ) -> Result<CylinderId, WalkError> {
        // A pruned complex holds only what views from its region need (`partition::region`).
        if let Some(r) = self.region().filter(|r| !r.contains(q)) {
            return Err(WalkError::OutsideRegion(r));
        }
        // A pruned complex's cross-section at θ = 0 holds the start cylinder of every free
        // point of its region, but not necessarily the cylinders that show a point is not
        // free: there the objects are tested first.
        let whole = self.region().is_none();
        if !whole {
            if let Some(l) = crate::partition::point_in_scene(scene, q) {
                return Err(WalkError::NotFree(l));
            }
        }
        if let Some(found) = self.trace_start_indexed(scene, q, whole) {
            return found;
        }
        self.trace_start_scan(scene, q)
    }

    /// [`Complex::trace_start`] by scanning all objects and all cylinders at θ = 0 (where
    /// the index cannot answer: a corrupt complex).
    fn trace_start_scan(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
    ) -> Result<CylinderId, WalkError> {
        if let Some(l) = crate::partition::point_in_scene(scene, q) {
            return Err(WalkError::NotFree(l));
        }
        // At θ = 0 a chain's tangent is its object's lowest (lower chain) or highest (upper
        // chain) vertex, so a cylinder whose bottom tangent lies above `q` or whose top
        // tangent lies below it (in y, from the bounding boxes: exact integers) cannot hold
        // `q`'s line; the exact, perturbed test runs on the few that remain.
        let qy = q.y();
        let height = |chain: &Chain| crate::partition::zero_height(scene, *chain);
        let zero = self
            .cylinders()
            .iter()
            .enumerate()
            .filter(|(_, c)| {
                c.left == Wall::Zero
                    && c.bottom.is_none_or(|b| height(&b).is_none_or(|y| y <= qy))
                    && c.top.is_none_or(|t| height(&t).is_none_or(|y| y >= qy))
            })
            .map(|(i, c)| (CylinderId::from_index(i).unwrap_or(CylinderId::ZERO), c));
        self.locate_among(scene, q, &Angle::ZERO, zero)
            .ok_or(WalkError::Corrupt)
    }

    /// [`Complex::trace_start`] through the index of the cross-section at θ = 0
    /// ([`Complex::at_zero`]), in time following the cylinders stabbed at `q`'s height
    /// instead of all objects and all `3n + 1` cylinders there; `None` if the index cannot
    /// answer (the caller scans). With `whole` (the complex is not pruned to a region) it
    /// also decides whether `q` is free; otherwise the caller has.
    ///
    /// `q` is free unless an object contains it; such an object is the floor of a stabbed
    /// cylinder (the layer after it) when `q` lies strictly between its lowest and highest
    /// vertex, else its lower or upper chain bounds a stabbed cylinder at exactly `q`'s
    /// height. Of the stabbed cylinders only those whose floor reaches back to `q` and whose
    /// ceiling reaches ahead of it (bounding boxes, exact integers) get the exact test, and
    /// the start cylinder ends the search (see the comment there).
    fn trace_start_indexed(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        whole: bool,
    ) -> Option<Result<CylinderId, WalkError>> {
        use crate::partition::{point_in_object, zero_height};
        let (qx, qy) = (q.x(), q.y());
        let bbox = |o: ObjectId| {
            let (lo, hi) = scene.object(o)?.bbox();
            Some((lo.to_query(), hi.to_query()))
        };
        let height = |chain: Option<Chain>| chain.and_then(|ch| zero_height(scene, ch));
        let mut found = None;
        let mut not_free = None;
        let answered = self.at_zero(scene, qy, |id, c| {
            let on = |chain: Option<Chain>| {
                chain
                    .filter(|_| height(chain) == Some(qy))
                    .map(|ch| ch.object)
            };
            let (on_bottom, on_top) = (on(c.bottom), on(c.top));
            let objects = [c.floor, on_bottom, on_top].into_iter().flatten();
            for o in objects.filter(|_| whole) {
                if let Some(l) = point_in_object(scene, o, q) {
                    not_free = Some(l);
                    return true;
                }
            }
            let behind = c
                .floor
                .is_none_or(|f| bbox(f).is_none_or(|(lo, _)| lo.x() <= qx));
            let ahead = c
                .ceiling
                .is_none_or(|g| bbox(g).is_none_or(|(_, hi)| hi.x() >= qx));
            if found.is_none()
                && behind
                && ahead
                && self
                    .locate_among(scene, q, &Angle::ZERO, core::iter::once((id, c)))
                    .is_some()
            {
                found = Some(id);
                // The start cylinder ends the search, the freeness test too unless one of
                // its arcs lies at `q`'s height. An object containing `q` (or with `q` on
                // its boundary) is crossed by the perturbed line through `q` — then it is
                // this cylinder's floor (tested above) or ceiling, as every other layer of
                // the line has floor and ceiling both behind `q` or both ahead — or only
                // touches it, at its lowest or highest height, between this cylinder's
                // floor and ceiling: then this cylinder's arc lies at that height.
                if !whole {
                    return true;
                }
                if on_bottom.is_some() || on_top.is_some() {
                    return false;
                }
                not_free = c.ceiling.and_then(|g| point_in_object(scene, g, q));
                return true;
            }
            false
        });
        match (not_free, found) {
            (Some(l), _) => Some(Err(WalkError::NotFree(l))),
            (None, Some(id)) if answered => Some(Ok(id)),
            _ => None,
        }
    }

    /// The walker shared by [`Complex::walk_trace`] and the anchored walks of ray trees:
    /// from cylinder `cur` at angle `from`, counter-clockwise, until `end` (`None`: until
    /// θ = 2π; `Some(end)`: the first event at or after `end`, which may lie past θ = 0 —
    /// the walk then crosses the permanent wall to the right neighbour). Calls `step` for
    /// every cylinder entered after the start. With [`Anchor::Floor`]`(m)` the chains of `m`
    /// are never crossed (the caller keeps the trace inside `m`'s sheet) and the eye may lie
    /// anywhere, even inside an object: only the tangents that exist are used. A loop over
    /// a counter-clockwise [`Walker`].
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn walk_from(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        anchor: Anchor,
        cur: CylinderId,
        from: Angle,
        end: Option<Position>,
        step: &mut impl FnMut(&Step),
    ) -> Result<(), WalkError> {
        let trace = Trace::new(q, anchor, end);
        let mut walker = Walker::<VIEW_TANGENT_CACHE>::new(cur, from, true);
        while let Some(s) = walker.next_step_in::<S, true>(self, scene, &trace)? {
            step(&s);
        }
        Ok(())
    }

    /// The object a cylinder's rays see ahead.
    pub fn ceiling(&self, id: CylinderId) -> Option<ObjectId> {
        self.cylinder(id).and_then(|c| c.ceiling)
    }
}

/// One entry of a walk's tangent cache: the object and its tangent vertices from the eye
/// indexed by the chain on which the line from the eye through them lies (`Lower`,
/// `Upper`), packed (a ray tree keeps a walker per frame): 16 bytes. An eye outside a
/// convex object has exactly two tangents, one on each chain (the edges' sides of the line
/// change sign twice round the polygon, once each way); inside, none.
#[derive(Clone, Copy, Debug)]
struct CachedTangents {
    /// The object's id; `u32::MAX` in an empty entry, whose `two: false` (no tangents) is
    /// also the truth for that id (no scene has that many objects), so a plain integer
    /// comparison finds an entry.
    object: u32,
    /// By [`Bound`]: `Lower`, `Upper`.
    vertices: [u32; 2],
    /// The eye is outside: both tangents exist (otherwise there are none).
    two: bool,
}

/// The index of a bound in [`CachedTangents::vertices`].
#[inline(always)]
fn bound_index(b: Bound) -> usize {
    match b {
        Bound::Lower => 0,
        Bound::Upper => 1,
    }
}

impl CachedTangents {
    const EMPTY: CachedTangents = CachedTangents {
        object: u32::MAX,
        vertices: [0; 2],
        two: false,
    };

    /// `None` if a vertex index does not fit or the tangents are not one per chain or
    /// none (then they are not cached).
    fn pack(object: ObjectId, t: [(usize, Bound); 2], count: usize) -> Option<CachedTangents> {
        let [(v0, b0), (v1, b1)] = t;
        let mut vertices = [0; 2];
        match count {
            0 => {}
            2 if b0 != b1 => {
                *vertices.get_mut(bound_index(b0))? = u32::try_from(v0).ok()?;
                *vertices.get_mut(bound_index(b1))? = u32::try_from(v1).ok()?;
            }
            _ => return None,
        }
        Some(CachedTangents {
            object: object.0,
            vertices,
            two: count == 2,
        })
    }

    /// The tangent vertex on `bound`, if any.
    #[inline(always)]
    fn on(&self, bound: Bound) -> Option<usize> {
        if !self.two {
            return None;
        }
        self.vertices.get(bound_index(bound)).map(|&v| v as usize)
    }
}

/// What a [`Walker`] follows and never changes: the eye `q`, the layer it keeps and where
/// it ends (see [`Walker`]). Apart from the walker's state and passed to every step: a ray
/// tree's frame holds its eye and the end of its range anyway, so its walker does not keep
/// them a second time (64 bytes less per frame, `TreeScratch`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Trace {
    pub(crate) q: QueryPoint,
    pub(crate) anchor: Anchor,
    end: Option<(u8, KeyedAngle)>,
}

impl Trace {
    #[inline]
    pub(crate) fn new(q: QueryPoint, anchor: Anchor, end: Option<Position>) -> Trace {
        Trace {
            q,
            anchor,
            end: end.map(|e| (e.lap, e.angle.keyed())),
        }
    }
}

/// A resumable walk of the trace of `q`: [`Walker::next_step`] advances one event at a
/// time, so several traces (the generations of a ray tree) can be walked in lock step.
/// Allocates nothing.
///
/// Counter-clockwise (`ccw`) it visits the events after θ, smallest first: the exits of a
/// cylinder are its right wall and the crossings of its chains after θ. Clockwise (the
/// traces behind an odd number of mirrors, which flip orientation) it is the mirror image:
/// the events before θ, largest first; the exits are the left wall (to the left
/// neighbour) and the chain crossings before θ, crossed with the same side and layer rule
/// (which depends on the tangent line, not on the direction of the walk). `from` is the
/// angle at which the walk entered `cur` (or any angle inside it): the walk continues
/// strictly after it (ccw) or strictly before it (cw), so a clockwise walk of the cylinder
/// a counter-clockwise one entered at α and left at β starts there at β.
///
/// Laps: a walk with an `end` crosses the permanent wall θ = 0 once per lap.
/// Counter-clockwise that is the right wall [`Wall::Zero`] (θ = 2π), entered on `lap + 1`
/// at θ = 0.
/// Clockwise it is the left wall [`Wall::Zero`] (θ = 0), entered on `lap + 1` at θ = 2π,
/// which no [`Angle`] represents: the walker keeps a flag (`full`) under which every angle
/// lies before it, and the [`Step`] reports [`Angle::ZERO`]. A clockwise [`Position`]
/// `{ lap, angle }` lies past the events of smaller laps and of the same lap with larger
/// angles, so `Position { lap: 1, angle: Angle::ZERO }` ends a clockwise walk started at
/// θ = 0 after one full turn. With `end: None` a walk stops at the permanent wall in
/// either direction (θ = 2π ccw, θ = 0 cw) without crossing it.
///
/// A chain's candidate exit is the crossing at its tangent vertex from `q`; where the
/// cylinder's arc on that chain is one vertex's sinusoid (the arc vertices kept by
/// `Complex::with_arc_vertices`) it is that vertex, without the tangents (see
/// [`Walker::candidate`]).
///
/// `K` is the number of entries of the tangent cache (even): two-way set associative,
/// the set chosen by a multiplicative hash of the object id (neighbouring objects, which a
/// walk meets together, land in different sets); a miss moves the set's first entry to its
/// second.
#[derive(Clone, Debug)]
pub(crate) struct Walker<const K: usize = TANGENT_CACHE> {
    /// The cylinder the walk is in.
    cur: CylinderId,
    /// The angle of the last event (or the start); meaningless while `full`. Its
    /// half-plane is `upper` ([`Walker::theta`]): a `KeyedAngle` here would pad the walker
    /// by 8 bytes, and a ray tree keeps a walker per frame.
    theta: Angle,
    upper: bool,
    /// Clockwise only: θ is 2π (the walk just crossed the permanent wall).
    full: bool,
    lap: u8,
    /// The tangent vertex of the last event, if it crossed a chain: never an exit of the
    /// cylinder entered, so its angle is not computed (see [`Walker::chain_exit_ccw`]).
    /// A `u32` (a scene has at most `MAX_VERTICES`; `None` otherwise, which only costs
    /// that angle): a ray tree keeps a walker per frame.
    last: Option<u32>,
    /// The tangents from `q` to recent chain objects: consecutive cylinders of a trace
    /// mostly share a chain, a walk comes back to the objects near the eye all around the
    /// circle, and the tangents depend only on the object.
    cache: [CachedTangents; K],
    /// Events taken so far; a walk takes at most `8 · cylinders + 8`: a lap enters each
    /// cylinder a bounded number of times, and a range walk of a ray tree goes round at
    /// most twice (more means the complex is inconsistent).
    steps: usize,
    ccw: bool,
}

/// Whether the clockwise position `a` comes strictly before `b` (`None`: θ = 2π, the first
/// angle of its lap going clockwise). Inlined into the clockwise step (up to three per
/// step): a call each cost a hall frame 0.6 % more instructions and a mixed one 0.3 %
/// (since the tree's steps carry no error, `tree::Events`; before, inlining cost the mixed
/// frame more than it saved).
#[inline(always)]
fn cw_before(a: (u8, Option<&KeyedAngle>), b: (u8, Option<&KeyedAngle>)) -> bool {
    use core::cmp::Ordering;
    a.0 < b.0
        || (a.0 == b.0
            && match (a.1, b.1) {
                (Some(x), Some(y)) => x.cmp(y) == Ordering::Greater,
                (None, Some(_)) => true,
                (_, None) => false,
            })
}

/// Whether the counter-clockwise position `a` comes strictly before `b`.
#[inline]
fn ccw_before(a: (u8, &KeyedAngle), b: (u8, &KeyedAngle)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1.cmp(b.1) == core::cmp::Ordering::Less)
}

impl<const K: usize> Walker<K> {
    /// A walk of the trace of `q` from cylinder `cur` at angle `from` (lap 0), until `end`
    /// (see the type's documentation for laps and `None`), with a tangent cache of `K`
    /// entries. Inlined: a call builds the walker apart and moves it (a `memcpy`).
    #[inline]
    pub(crate) fn new(cur: CylinderId, from: Angle, ccw: bool) -> Walker<K> {
        const { assert!(K >= 2 && K.is_multiple_of(2), "sets of two entries") };
        Walker {
            cur,
            theta: from,
            upper: from.keyed().upper_half(),
            full: false,
            lap: 0,
            last: None,
            cache: [CachedTangents::EMPTY; K],
            steps: 0,
            ccw,
        }
    }

    /// A clockwise walk that starts at θ = 2π in `cur` (the cylinder just below it),
    /// where no [`Angle`] can start it: every angle of its lap lies ahead.
    #[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
    pub(crate) fn at_top(mut self) -> Walker<K> {
        self.full = !self.ccw;
        self
    }

    /// The cylinder the walk is in now.
    #[cfg(all(test, feature = "alloc"))]
    pub(crate) fn cylinder(&self) -> CylinderId {
        self.cur
    }

    /// The angle and cylinder of the last step taken, as its [`Step`] has them (θ = 2π
    /// clockwise is [`Angle::ZERO`] there and here): a ray tree's look-ahead keeps the rest
    /// of the step, not these again.
    #[inline(always)]
    pub(crate) fn last_step(&self) -> (Angle, CylinderId) {
        (self.theta, self.cur)
    }

    /// The angle of the last event with its half-plane.
    #[inline(always)]
    fn theta(&self) -> KeyedAngle {
        KeyedAngle::from_parts(self.theta, self.upper)
    }

    /// Whether `h` is the tangent vertex of the chain the last event crossed.
    #[inline(always)]
    fn just_crossed(&self, h: usize) -> bool {
        self.last.is_some_and(|l| l as usize == h)
    }

    /// The lap of the last event (or 0 at the start): how often the walk crossed the
    /// permanent wall θ = 0.
    pub(crate) fn lap(&self) -> u8 {
        self.lap
    }

    /// The next event (one step), or `None` when the walk is over: θ reached `end`, or
    /// the permanent wall without an `end`. After `None` or an error, the same again.
    /// Inlined into the ray tree's one caller: left to itself the compiler keeps it out of
    /// line or not depending on unrelated edits (≈ 2 % of a hall frame's instructions).
    #[inline(always)]
    pub(crate) fn next_step<S: Storage>(
        &mut self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
    ) -> Result<Option<Step>, WalkError> {
        if self.ccw {
            self.next_step_in::<S, true>(complex, scene, t)
        } else {
            self.next_step_in::<S, false>(complex, scene, t)
        }
    }

    /// [`Walker::next_step`] in the direction `CCW` (which must be `self.ccw`), inlined
    /// into `walk_from`'s loop: a call per step costs a view about 10 % more instructions.
    #[inline(always)]
    fn next_step_in<S: Storage, const CCW: bool>(
        &mut self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
    ) -> Result<Option<Step>, WalkError> {
        // Bounded by the events taken: a walk that ended (or failed) stays so, as the
        // state does not change.
        if self.steps >= 8 * complex.cylinders().len() + 8 {
            return Err(WalkError::Corrupt);
        }
        let r = if CCW {
            self.next_ccw(complex, scene, t)
        } else {
            self.next_cw(complex, scene, t)
        };
        if let Ok(Some(_)) = r {
            self.steps += 1;
        }
        r
    }

    /// The tangent vertex from `q` to `object` on chain `bound` (the line from `q` through
    /// it lies on that chain), through the cache; `None` if there is none.
    #[inline]
    fn tangent_on(
        &mut self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        object: ObjectId,
        bound: Bound,
    ) -> Option<usize> {
        // Fibonacci hashing: bits 16 and up of `id · 2³²/φ` pick the set.
        let set = 2 * ((object.0.wrapping_mul(0x9e37_79b9) >> 16) as usize % (K / 2));
        let ways = self.cache.get(set..set + 2).unwrap_or_default();
        if let Some(e) = ways.iter().find(|e| e.object == object.0) {
            return e.on(bound);
        }
        let (t, n) = crate::line_space::tangents_from(scene, object, q);
        match (
            CachedTangents::pack(object, t, n),
            self.cache.get_mut(set..set + 2),
        ) {
            (Some(new), Some([first, second])) => {
                *second = *first;
                *first = new;
                new.on(bound)
            }
            (Some(new), _) => new.on(bound),
            // Not one tangent per chain (not a convex object): the first on `bound`.
            (None, _) => t
                .iter()
                .take(n)
                .find(|&&(_, b)| b == bound)
                .map(|&(h, _)| h),
        }
    }

    /// The tangent vertex of the one crossing of `chain` with the vertex `ahead` of the eye
    /// or behind it that can be an exit of the cylinder (see [`exits_through`]); `arc` is
    /// the cylinder's arc vertex on that chain ([`NO_ARC_VERTEX`]: none).
    ///
    /// Where the arc is one vertex's sinusoid that vertex is the candidate, without the
    /// tangents from the eye: if the line through the eye and it has a direction inside
    /// the cylinder's θ-range, it is the chain's tangent line there (the chain's line in
    /// that direction passes through the vertex), so the vertex is the tangent; and a
    /// tangent line of the chain with a direction inside passes through the arc's vertex,
    /// so no other tangent vertex can give a crossing inside. Outside the range the
    /// candidate is compared away either way.
    #[inline(always)]
    fn candidate(
        &mut self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        chain: Chain,
        arc: u32,
        ahead: bool,
    ) -> Option<usize> {
        if arc != NO_ARC_VERTEX {
            return Some(arc as usize);
        }
        self.tangent_on(scene, q, chain.object, tangent_bound(chain, ahead))
    }

    /// One counter-clockwise step: the first exit after θ.
    #[inline(always)]
    fn next_ccw<S: Storage>(
        &mut self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
    ) -> Result<Option<Step>, WalkError> {
        let c = complex.cylinder(self.cur).ok_or(WalkError::Corrupt)?;
        let lap = self.lap;
        let [bottom, top] = complex.borders_ref().arcs(self.cur);
        let found = match self.exit_by_arcs(complex, scene, t, c, [bottom, top]) {
            Some((angle, exit)) => Some((lap, angle, exit)),
            None => {
                // The right wall, or a crossing of the bottom or top chain.
                let mut best: Option<(u8, KeyedAngle, Option<ChainExit>)> = match c.right {
                    // The permanent wall ends a full-circle walk; a range walk crosses it.
                    Wall::Zero => t
                        .end
                        .map(|_| (lap.saturating_add(1), Angle::ZERO.keyed(), None)),
                    w => complex.wall_angle(scene, w).map(|a| (lap, a.keyed(), None)),
                };
                // Unrolled by hand: the loop over the two chains cost a view 2 % more.
                self.chain_exit_ccw(scene, t, (c.bottom, bottom), Side::Below, &mut best);
                self.chain_exit_ccw(scene, t, (c.top, top), Side::Above, &mut best);
                best
            }
        };
        let Some((l, angle, exit)) = found else {
            return match t.end {
                None => Ok(None), // θ reached 2π
                Some(_) => Err(WalkError::Corrupt),
            };
        };
        if let Some((e_lap, e_angle)) = &t.end {
            if !ccw_before((l, &angle), (*e_lap, e_angle)) {
                return Ok(None);
            }
        }
        let next = match exit {
            None => c.right_neighbour.ok_or(WalkError::Corrupt)?,
            Some(e) => self.cross(complex, scene, t.anchor, c, e, &angle)?,
        };
        (self.theta, self.upper) = (angle.angle, angle.upper_half());
        self.last = exit.and_then(|e| u32::try_from(e.vertex).ok());
        self.lap = l;
        self.cur = next;
        Ok(Some(step_of(angle.angle, exit, next)))
    }

    /// [`Walker::next_ccw`]'s exit for the usual cylinder: its right wall is a vertex's and
    /// each arc the walk can leave through is one vertex's sinusoid (`arcs`, see
    /// [`Walker::candidate`]); `None` for any other, or where the exact order of two exits
    /// is a tie (the perturbation decides there: the caller compares in full).
    ///
    /// Such a cylinder spans less than half a turn (an arc vertex is tangent over less than
    /// half a turn), and each arc's crossing lies within half a turn after θ: the trace is
    /// inside the cylinder just after θ, on the far side of the arc from where it leaves
    /// (its offset minus the arc's is a sinusoid in θ with zeros half a turn apart). Angles
    /// within one half turn are ordered by the sign of their exact cross product: one
    /// product per arc, no half-planes, laps or comparison with θ.
    #[inline(always)]
    fn exit_by_arcs<S: Storage>(
        &self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
        c: &Cylinder,
        [bottom, top]: [u32; 2],
    ) -> Option<(KeyedAngle, Option<ChainExit>)> {
        let Wall::Vertex(v) = c.right else {
            return None;
        };
        let mut best = *complex.borders_ref().angle(v.index())?;
        let mut exit = None;
        // Unrolled by hand, as in `next_ccw`.
        self.arc_exit(
            scene,
            t,
            (c.bottom, bottom),
            Side::Below,
            (&mut best, &mut exit),
        )?;
        self.arc_exit(scene, t, (c.top, top), Side::Above, (&mut best, &mut exit))?;
        Some((best.keyed(), exit))
    }

    /// The crossing of `chain` at its arc vertex `arc` into `(best, exit)` if it comes
    /// before `best` (see [`Walker::exit_by_arcs`]); `None` where the arc has no vertex or
    /// on an exact tie.
    #[inline(always)]
    fn arc_exit(
        &self,
        scene: &SceneRef<'_>,
        t: &Trace,
        (chain, arc): (Option<Chain>, u32),
        side: Side,
        (best, exit): (&mut Angle, &mut Option<ChainExit>),
    ) -> Option<()> {
        let Some(chain) = chain else {
            return Some(());
        };
        if t.anchor == Anchor::Floor(chain.object) {
            return Some(());
        }
        if arc == NO_ARC_VERTEX {
            return None;
        }
        let h = arc as usize;
        // The vertex just crossed is no exit (see `chain_exit_ccw`).
        if self.just_crossed(h) {
            return Some(());
        }
        let ahead = exits_through(side, true);
        let a = tangent_angle(scene, t.q, h, ahead);
        if before_within_half_turn(&a, best)? {
            *best = a;
            *exit = Some(ChainExit {
                chain,
                side,
                vertex: h,
                ahead,
            });
        }
        Some(())
    }

    /// The crossing of `chain` (the cylinder's chain on `side`, with its arc vertex
    /// `arc`) after θ that takes a counter-clockwise walk out of the cylinder, into `best`
    /// if it comes first.
    #[inline(always)]
    fn chain_exit_ccw(
        &mut self,
        scene: &SceneRef<'_>,
        t: &Trace,
        (chain, arc): (Option<Chain>, u32),
        side: Side,
        best: &mut Option<(u8, KeyedAngle, Option<ChainExit>)>,
    ) {
        use core::cmp::Ordering;
        let Some(chain) = chain else { return };
        if t.anchor == Anchor::Floor(chain.object) {
            return;
        }
        let lap = self.lap;
        // Counter-clockwise the trace leaves upward through the top chain (a tangent
        // ahead) and downward through the bottom one (a tangent behind): see
        // `exits_through`. The line q → h lies on the chain of h's tangent, its reverse on
        // the other: the candidate is the tangent on this chain (ahead) or the other one.
        let ahead = exits_through(side, true);
        let Some(h) = self.candidate(scene, t.q, chain, arc, ahead) else {
            return;
        };
        // The vertex just crossed: the line from the eye through it is the one at θ, or (an
        // arc vertex, tangent over less than half a turn) its reverse at θ + π.
        if self.just_crossed(h) {
            return;
        }
        let a = tangent_angle(scene, t.q, h, ahead).keyed();
        // Against the best exit first: most candidates lie past it, and of those before it
        // only the ones after θ count (fewer comparisons than the other way round).
        if best
            .as_ref()
            .is_none_or(|(l, b, _)| ccw_before((lap, &a), (*l, b)))
            && a.cmp(&self.theta()) == Ordering::Greater
        {
            let exit = ChainExit {
                chain,
                side,
                vertex: h,
                ahead,
            };
            *best = Some((lap, a, Some(exit)));
        }
    }

    /// The mirror image of [`Walker::chain_exit_ccw`]: the crossing of `chain` before θ
    /// that takes a clockwise walk out of the cylinder (`None` angle in `best`: θ = 2π).
    #[inline(always)]
    fn chain_exit_cw(
        &mut self,
        scene: &SceneRef<'_>,
        t: &Trace,
        (chain, arc): (Option<Chain>, u32),
        side: Side,
        best: &mut Option<(u8, Option<KeyedAngle>, Option<ChainExit>)>,
    ) {
        use core::cmp::Ordering;
        let Some(chain) = chain else { return };
        if t.anchor == Anchor::Floor(chain.object) {
            return;
        }
        let lap = self.lap;
        let bound = tangent_bound(chain, exits_through(side, false));
        let Some(h) = self.candidate(scene, t.q, chain, arc, bound == chain.bound) else {
            return;
        };
        // The vertex just crossed, as counter-clockwise (θ − π for an arc vertex's reverse).
        if self.just_crossed(h) {
            return;
        }
        let (a, ahead) = tangent_event(scene, t.q, h, bound, chain);
        // Against the best exit first, as counter-clockwise.
        if best
            .as_ref()
            .is_none_or(|(l, b, _)| cw_before((lap, Some(&a)), (*l, b.as_ref())))
            && (self.full || a.cmp(&self.theta()) == Ordering::Less)
        {
            let exit = ChainExit {
                chain,
                side,
                vertex: h,
                ahead,
            };
            *best = Some((lap, Some(a), Some(exit)));
        }
    }

    /// One clockwise step: the last exit before θ (the mirror image of `next_ccw`).
    #[inline]
    fn next_cw<S: Storage>(
        &mut self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        t: &Trace,
    ) -> Result<Option<Step>, WalkError> {
        let c = complex.cylinder(self.cur).ok_or(WalkError::Corrupt)?;
        let lap = self.lap;
        // The left wall, or a crossing of the bottom or top chain; `None` angle: θ = 2π
        // on the next lap, past the permanent wall.
        let mut best: Option<(u8, Option<KeyedAngle>, Option<ChainExit>)> = match c.left {
            Wall::Zero => t.end.map(|_| (lap.saturating_add(1), None, None)),
            w => complex
                .wall_angle(scene, w)
                .map(|a| (lap, Some(a.keyed()), None)),
        };
        // Unrolled by hand, as counter-clockwise.
        let [bottom, top] = complex.borders_ref().arcs(self.cur);
        self.chain_exit_cw(scene, t, (c.bottom, bottom), Side::Below, &mut best);
        self.chain_exit_cw(scene, t, (c.top, top), Side::Above, &mut best);
        let Some((l, angle, exit)) = best else {
            return match t.end {
                None => Ok(None), // θ reached 0
                Some(_) => Err(WalkError::Corrupt),
            };
        };
        if let Some((e_lap, e_angle)) = &t.end {
            if !cw_before((l, angle.as_ref()), (*e_lap, Some(e_angle))) {
                return Ok(None);
            }
        }
        let next = match (exit, &angle) {
            (None, _) => c.left_neighbour.ok_or(WalkError::Corrupt)?,
            (Some(e), Some(a)) => self.cross(complex, scene, t.anchor, c, e, a)?,
            // A chain crossing always has an angle.
            (Some(_), None) => return Err(WalkError::Corrupt),
        };
        self.full = angle.is_none();
        let at = angle.map_or(Angle::ZERO, |a| a.angle);
        let theta = angle.unwrap_or_else(|| Angle::ZERO.keyed());
        (self.theta, self.upper) = (theta.angle, theta.upper_half());
        self.last = exit.and_then(|e| u32::try_from(e.vertex).ok());
        self.lap = l;
        self.cur = next;
        Ok(Some(step_of(at, exit, next)))
    }

    /// The cylinder entered leaving the current one, `c`, across a chain at `angle` (strictly
    /// inside its θ-range, so the same in both directions).
    #[inline(always)]
    fn cross<S: Storage>(
        &self,
        complex: &Complex<S>,
        scene: &SceneRef<'_>,
        anchor: Anchor,
        c: &Cylinder,
        exit: ChainExit,
        angle: &KeyedAngle,
    ) -> Result<CylinderId, WalkError> {
        let ChainExit {
            chain, side, ahead, ..
        } = exit;
        // Lines on the far side of a lower chain cross the object iff that side is above
        // it; of an upper chain iff it is below.
        let crossed = match chain.bound {
            Bound::Lower => Side::Above,
            Bound::Upper => Side::Below,
        };
        let layer = if side != crossed {
            Layer::Around
        } else if ahead || matches!(anchor, Anchor::Floor(_)) {
            // Point: h ahead of q, so the segment through q ends at the object.
            // Floor(m): the object appears between m and the old ceiling.
            Layer::Before
        } else {
            Layer::After
        };
        // The entered cylinder overlaps the one left: scan the far side from there
        // (usually a step or two) instead of bisecting the tiling.
        let next = complex
            .across_from_cylinder(scene, self.cur, c, side, layer, angle)
            .ok_or(WalkError::Corrupt)?;
        if let Anchor::Floor(m) = anchor {
            if complex.cylinder(next).and_then(|n| n.floor) != Some(m) {
                return Err(WalkError::Corrupt);
            }
        }
        Ok(next)
    }
}

/// Which tangent events can take a walk out of a cylinder through its chain on `side`:
/// `true` those whose tangent vertex lies ahead of `q`, `false` those behind. No predicate
/// is needed. Along the arc of vertex h the chain's offset minus the trace's is
/// `cross(d, h − q)`, whose derivative in θ is `−dot(d, h − q)`: where the line q → h is
/// tangent with h ahead (`d` along `h − q`) the trace crosses the chain upward, with h
/// behind downward (the perturbation keeps the crossing transversal). A trace inside a
/// cylinder lies above its bottom chain and below its top one, so counter-clockwise it
/// leaves through the top only at a tangent ahead and through the bottom only at one
/// behind; clockwise the other way round. Each chain gives one candidate, not two.
#[inline(always)]
fn exits_through(side: Side, ccw: bool) -> bool {
    (side == Side::Above) == ccw
}

/// Whether the direction `a` comes before `b` where both lie strictly within half a turn
/// after one angle: then the exact cross product orders them; `None` where it is zero (the
/// perturbation decides: the caller compares in full).
#[inline(always)]
fn before_within_half_turn(a: &Angle, b: &Angle) -> Option<bool> {
    let ((ax, ay), (bx, by)) = (a.vector64()?, b.vector64()?);
    let cross = i128::from(ax) * i128::from(by) - i128::from(ay) * i128::from(bx);
    (cross != 0).then_some(cross > 0)
}

/// The chain on which the line from the eye through a tangent vertex of `chain`'s object
/// lies, for the crossings of `chain` with the vertex ahead (`chain` itself) or behind
/// (the other one: the reversed line lies on `chain`).
#[inline(always)]
fn tangent_bound(chain: Chain, ahead: bool) -> Bound {
    match (chain.bound, ahead) {
        (b, true) => b,
        (Bound::Lower, false) => Bound::Upper,
        (Bound::Upper, false) => Bound::Lower,
    }
}

/// The crossing of `chain` by the trace of `q` where it is tangent to the chain's object
/// at vertex `h` (a tangent from `q` on `bound`): its angle, and whether `h` lies ahead.
#[inline]
fn tangent_event(
    scene: &SceneRef<'_>,
    q: QueryPoint,
    h: usize,
    bound: Bound,
    chain: Chain,
) -> (KeyedAngle, bool) {
    // The line q → h lies on `bound`; its reverse on the other chain.
    let ahead = bound == chain.bound;
    (tangent_angle(scene, q, h, ahead).keyed(), ahead)
}

/// The direction of the tangent line through vertex `h` from `q`: `h − q` with `h` ahead,
/// else `q − h` (built as such, no negation).
#[inline(always)]
fn tangent_angle(scene: &SceneRef<'_>, q: QueryPoint, h: usize, ahead: bool) -> Angle {
    if ahead {
        Angle::from_query(q, ranked(scene, h))
    } else {
        Angle::to_query(ranked(scene, h), q)
    }
}

/// The step entering `cylinder` at `angle` across `exit` (`None`: a secondary wall).
#[inline]
fn step_of(angle: Angle, exit: Option<ChainExit>, cylinder: CylinderId) -> Step {
    let (vertex, ahead) = exit.map_or((None, false), |e| (Some(e.vertex), e.ahead));
    Step {
        angle,
        vertex,
        ahead,
        cylinder,
    }
}

#[cfg(all(test, feature = "alloc"))]
mod tests {
    use alloc::vec::Vec;
    use core::cmp::Ordering;

    use super::*;
    use crate::geom::Point;
    use crate::partition::{build_by_sweep, Complex};
    use crate::scene::{Material, Scene};

    /// A small deterministic generator (Knuth's MMIX LCG).
    struct Lcg(u64);

    impl Lcg {
        /// Uniform in `0..n`.
        fn below(&mut self, n: u32) -> i32 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((self.0 >> 33) % u64::from(n)) as i32
        }
    }

    fn p(x: i32, y: i32) -> Point {
        Point::from_raw(x << 16, y << 16).unwrap()
    }

    /// One convex object per cell of a `k × k` grid of 8-unit cells (a few cells empty),
    /// integer corners strictly inside the cell, so objects are disjoint: boxes and
    /// triangles, many sharing coordinates (collinear vertices, equal heights).
    fn random_scene(seed: u64, k: i32) -> Scene {
        let mut rng = Lcg(seed);
        let mut polys: Vec<Vec<Point>> = Vec::new();
        for i in 0..k {
            for j in 0..k {
                let (x0, y0) = (8 * i, 8 * j);
                match rng.below(4) {
                    0 => {}
                    1 => {
                        let (a, b) = (x0 + 1 + rng.below(3), y0 + 1 + rng.below(3));
                        let (c, d) = (x0 + 4 + rng.below(3), y0 + 4 + rng.below(3));
                        polys.push(alloc::vec![p(a, b), p(c, b), p(c, d), p(a, d)]);
                    }
                    _ => loop {
                        let mut q = || (x0 + 1 + rng.below(7), y0 + 1 + rng.below(7));
                        let (a, b, c) = (q(), q(), q());
                        let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
                        if cross != 0 {
                            polys.push(alloc::vec![p(a.0, a.1), p(b.0, b.1), p(c.0, c.1)]);
                            break;
                        }
                    },
                }
            }
        }
        Scene::new(polys.iter().map(|v| (Material::Opaque, v.as_slice()))).unwrap()
    }

    /// The boxes of `walk::tree`'s tests: few objects, long events.
    fn boxes() -> Scene {
        let r = |x0, y0, x1, y1| alloc::vec![p(x0, y0), p(x1, y0), p(x1, y1), p(x0, y1)];
        let polys = [r(-6, -2, -4, 1), r(4, -1, 6, 2), r(-3, -7, 3, -5)];
        Scene::new(polys.iter().map(|v| (Material::Opaque, v.as_slice()))).unwrap()
    }

    /// Viewpoints: integer points on the heights of vertices (events exactly at θ = 0
    /// and π, and collinear with vertices), half-integer and random fine-grid points.
    fn viewpoints(scene: &Scene, seed: u64, count: usize) -> Vec<QueryPoint> {
        let s = scene.as_ref();
        let (mut lo, mut hi) = ((i32::MAX, i32::MAX), (i32::MIN, i32::MIN));
        for v in s.vertices() {
            let (x, y) = (v.x() >> 16, v.y() >> 16);
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        let (w, h) = ((hi.0 - lo.0 + 3) as u32, (hi.1 - lo.1 + 3) as u32);
        let mut rng = Lcg(seed);
        let mut out = Vec::new();
        let unit = 1i64 << 32;
        for k in 0..count {
            let q = match k % 3 {
                0 => {
                    let vs = s.vertices();
                    let v = vs[rng.below(vs.len() as u32) as usize];
                    let x = i64::from(lo.0 - 1 + rng.below(w));
                    QueryPoint::from_raw(x * unit, i64::from(v.y() >> 16) * unit)
                }
                1 => {
                    let x = i64::from(lo.0 - 1 + rng.below(w));
                    let y = i64::from(lo.1 - 1 + rng.below(h));
                    QueryPoint::from_raw(x * unit + unit / 2, y * unit + unit / 2)
                }
                _ => {
                    let x = i64::from(lo.0 - 1) * unit + i64::from(rng.below(w << 8)) * (unit >> 8);
                    let y = i64::from(lo.1 - 1) * unit
                        + i64::from(rng.below(h << 8)) * (unit >> 8)
                        + i64::from(rng.below(1 << 20));
                    QueryPoint::from_raw(x, y)
                }
            };
            out.extend(q);
        }
        out
    }

    /// A walker with its trace, as the tests drive it.
    #[derive(Clone)]
    struct Traced<const K: usize = TANGENT_CACHE>(Walker<K>, Trace);

    impl<const K: usize> Traced<K> {
        fn new(
            q: QueryPoint,
            anchor: Anchor,
            cur: CylinderId,
            from: Angle,
            end: Option<Position>,
            ccw: bool,
        ) -> Self {
            Traced(Walker::new(cur, from, ccw), Trace::new(q, anchor, end))
        }

        fn next_step<S: Storage>(
            &mut self,
            c: &Complex<S>,
            s: &SceneRef<'_>,
        ) -> Result<Option<Step>, WalkError> {
            self.0.next_step(c, s, &self.1)
        }

        fn cylinder(&self) -> CylinderId {
            self.0.cylinder()
        }
    }

    /// The steps of a walker until it ends.
    fn run(c: &Complex, s: &SceneRef<'_>, w: &mut Traced) -> Vec<Step> {
        let mut out = Vec::new();
        while let Some(st) = w.next_step(c, s).unwrap() {
            out.push(st);
        }
        assert!(
            w.next_step(c, s).unwrap().is_none(),
            "a finished walk stays finished"
        );
        out
    }

    /// `cw` is `ccw` backwards: the same events (angle, vertex, ahead) in reverse order,
    /// each entering the cylinder the ccw walk left there (`left[k]` before `ccw[k]`).
    fn assert_reversed(cw: &[Step], ccw: &[Step], left: &[CylinderId]) {
        assert_eq!(cw.len(), ccw.len(), "event counts");
        for ((a, b), l) in cw.iter().zip(ccw.iter().rev()).zip(left.iter().rev()) {
            assert_eq!(
                a.angle.cmp_angle(&b.angle),
                Ordering::Equal,
                "{a:?} vs {b:?}"
            );
            assert_eq!((a.vertex, a.ahead), (b.vertex, b.ahead), "{a:?} vs {b:?}");
            assert_eq!(a.cylinder, *l, "{a:?} vs {b:?}");
        }
    }

    /// Every clockwise walk checked against the counter-clockwise `walk_trace` of the same
    /// viewpoint: the full circle from the θ = 0 start cylinder, range walks between event
    /// angles (also across θ = 0), the counter-clockwise [`Walker`] itself, and anchored
    /// walks both ways. Returns the number of viewpoints walked (free ones), of those with
    /// events exactly at θ = 0 or π, and of anchored walks checked.
    fn check_scene(scene: &Scene, seed: u64, count: usize) -> (usize, usize, usize) {
        let s = scene.as_ref();
        let c = build_by_sweep(&s).unwrap();
        let mut rng = Lcg(seed ^ 0x9e37_79b9);
        let (mut walked, mut exact, mut anchored) = (0, 0, 0);
        let horizontal = [Angle::ZERO, Angle::ZERO.reversed()];
        for q in viewpoints(scene, seed, count) {
            let mut ccw = Vec::new();
            match c.walk_trace(&s, q, |st| ccw.push(*st)) {
                Ok(()) => {}
                Err(WalkError::NotFree(_)) => continue,
                Err(e) => panic!("walk_trace from {q:?}: {e:?}"),
            }
            walked += 1;
            exact += usize::from(ccw[1..].iter().any(|st| {
                horizontal
                    .iter()
                    .any(|h| st.angle.cmp_exact(h) == Ordering::Equal)
            }));
            // ccw[0] is the start cylinder (θ = 0), ccw[i] the i-th event.
            let n = ccw.len() - 1;
            let cyl: Vec<CylinderId> = ccw.iter().map(|st| st.cylinder).collect();
            let last = cyl[n];

            // Full circle, clockwise: across the permanent wall into the last cylinder of
            // the ccw walk, then every event back to θ = 0.
            let full = Position {
                lap: 1,
                angle: Angle::ZERO,
            };
            let mut w = Traced::new(q, Anchor::Point, cyl[0], Angle::ZERO, Some(full), false);
            let cw = run(&c, &s, &mut w);
            assert!(!cw.is_empty(), "from {q:?}");
            assert_eq!(cw[0].vertex, None, "from {q:?}");
            assert_eq!(cw[0].angle.cmp_angle(&Angle::ZERO), Ordering::Equal);
            assert_eq!(cw[0].cylinder, last, "from {q:?}: across θ = 0");
            assert_reversed(&cw[1..], &ccw[1..], &cyl[..n]);
            assert_eq!(w.cylinder(), cyl[0]);

            // The counter-clockwise walker is `walk_trace`.
            let mut w = Traced::new(q, Anchor::Point, cyl[0], Angle::ZERO, None, true);
            let again = run(&c, &s, &mut w);
            assert_eq!(again.len(), n);
            for (a, b) in again.iter().zip(&ccw[1..]) {
                assert_eq!(a.angle.cmp_angle(&b.angle), Ordering::Equal);
                assert_eq!((a.vertex, a.cylinder), (b.vertex, b.cylinder));
            }

            if n < 2 {
                continue;
            }
            for _ in 0..4 {
                // Clockwise from inside cylinder `cyl[j]` (at its ccw exit angle
                // `ccw[j + 1]`) down to the event `ccw[i]`, i ≤ j < n: the events
                // `ccw[i + 1..=j]` backwards; `i = 0` ends at θ = 0.
                let j = rng.below(n as u32) as usize;
                let i = rng.below(j as u32 + 1) as usize;
                let (hi, lo) = (ccw[j + 1].angle, ccw[i].angle);
                let end = Position { lap: 0, angle: lo };
                let mut w = Traced::new(q, Anchor::Point, cyl[j], hi, Some(end), false);
                let cw = run(&c, &s, &mut w);
                assert_reversed(&cw, &ccw[i + 1..=j], &cyl[i..j]);
                assert_eq!(w.cylinder(), cyl[i]);
                if i == 0 {
                    let mut w = Traced::new(q, Anchor::Point, cyl[j], hi, None, false);
                    assert_eq!(run(&c, &s, &mut w).len(), j);
                }
                // The same range counter-clockwise (`walk_from`, as ray trees use it).
                let mut fwd = Vec::new();
                let end = Position { lap: 0, angle: hi };
                c.walk_from(&s, q, Anchor::Point, cyl[i], lo, Some(end), &mut |st| {
                    fwd.push(*st)
                })
                .unwrap();
                assert_eq!(fwd.len(), j - i);
                for (a, b) in fwd.iter().zip(&ccw[i + 1..=j]) {
                    assert_eq!(a.angle.cmp_angle(&b.angle), Ordering::Equal);
                    assert_eq!((a.vertex, a.cylinder), (b.vertex, b.cylinder));
                }

                // Clockwise across θ = 0: from inside `cyl[j]` down to θ = 0, over the
                // permanent wall into `last`, and on down to the event `ccw[k]`, k > j + 1.
                if j + 2 <= n {
                    let k = j + 2 + rng.below((n - j - 1) as u32) as usize;
                    let end = Position {
                        lap: 1,
                        angle: ccw[k].angle,
                    };
                    let mut w = Traced::new(q, Anchor::Point, cyl[j], hi, Some(end), false);
                    let cw = run(&c, &s, &mut w);
                    assert_eq!(cw.len(), j + 1 + (n - k), "from {q:?}");
                    assert_reversed(&cw[..j], &ccw[1..=j], &cyl[..j]);
                    assert_eq!((cw[j].vertex, cw[j].cylinder), (None, last));
                    assert_reversed(&cw[j + 1..], &ccw[k + 1..], &cyl[k..n]);
                    assert_eq!(w.cylinder(), cyl[k]);
                }
            }

            // Anchored to a floor M: counter-clockwise from a cylinder of the trace with
            // floor M at its entry angle, up to the next tangent from `q` to M (the lines
            // through `q` cross M up to there: the trace stays in M's sheet), then
            // clockwise back from that angle.
            for i in 1..n {
                let Some(m) = c.cylinder(cyl[i]).and_then(|x| x.floor) else {
                    continue;
                };
                // The next direction after `lo` in which the line through `q` is tangent
                // to M (the point walk may not see it: M hidden behind another object).
                let lo = ccw[i].angle;
                let (t, count) = crate::line_space::tangents_from(&s, m, q);
                let hi = t
                    .iter()
                    .take(count)
                    .flat_map(|&(h, _)| {
                        let a = Angle::from_query(q, ranked(&s, h));
                        [a, a.reversed()]
                    })
                    .filter(|a| a.cmp_angle(&lo) == Ordering::Greater)
                    .min_by(|a, b| a.cmp_angle(b));
                let Some(hi) = hi else { continue };
                let anchor = Anchor::Floor(m);
                let end = Position { lap: 0, angle: hi };
                let mut w = Traced::new(q, anchor, cyl[i], lo, Some(end), true);
                let fwd = run(&c, &s, &mut w);
                let mut entered: Vec<CylinderId> = alloc::vec![cyl[i]];
                entered.extend(fwd.iter().map(|st| st.cylinder));
                for st in &fwd {
                    let f = c.cylinder(st.cylinder).and_then(|x| x.floor);
                    assert_eq!(f, Some(m), "from {q:?}: left the sheet of {m:?}");
                }
                let end = Position { lap: 0, angle: lo };
                let mut w = Traced::new(q, anchor, w.cylinder(), hi, Some(end), false);
                let back = run(&c, &s, &mut w);
                assert_reversed(&back, &fwd, &entered[..fwd.len()]);
                assert_eq!(w.cylinder(), cyl[i]);
                anchored += usize::from(!fwd.is_empty());
            }
        }
        (walked, exact, anchored)
    }

    /// A cylinder's arc vertex (`Complex::with_arc_vertices`) gives the same walks as the
    /// tangents from the eye: every step of full counter-clockwise and clockwise walks from
    /// viewpoints on vertex heights, on the vertices' lattice and at random, with the arc
    /// vertices and without them. Also checks that most arcs have one.
    #[test]
    fn arc_vertices_walk_as_the_tangents() {
        let mut scenes: Vec<Scene> = (1..=10u64)
            .map(|seed| random_scene(seed, 2 + (seed as i32 % 4)))
            .collect();
        scenes.push(boxes());
        let (mut steps, mut arcs, mut bounded) = (0, 0, 0);
        for (k, scene) in scenes.iter().enumerate() {
            let s = scene.as_ref();
            let c = build_by_sweep(&s).unwrap().with_arc_vertices(&s);
            let with = c.as_slices();
            assert!(with.borders_ref().has_arcs());
            let without = Complex {
                borders: with.borders_ref().without_arcs(),
                ..with.clone()
            };
            for (i, z) in c.cylinders().iter().enumerate() {
                let id = CylinderId::from_index(i).unwrap();
                let [b, t] = with.borders_ref().arcs(id);
                bounded += usize::from(z.bottom.is_some()) + usize::from(z.top.is_some());
                arcs += usize::from(b != NO_ARC_VERTEX) + usize::from(t != NO_ARC_VERTEX);
            }
            let mut points = viewpoints(scene, k as u64 + 7, 120);
            points.extend(s.vertices().iter().map(|v| {
                let v = v.to_query();
                QueryPoint::from_raw(v.x() + (1 << 30), v.y()).unwrap()
            }));
            for q in points {
                let Ok(start) = c.trace_start(&s, q) else {
                    continue;
                };
                let full = Position {
                    lap: 1,
                    angle: Angle::ZERO,
                };
                for (end, ccw) in [(None, true), (Some(full), false)] {
                    let mut a = Traced::<8>::new(q, Anchor::Point, start, Angle::ZERO, end, ccw);
                    let mut b = a.clone();
                    loop {
                        let (x, y) = (a.next_step(&with, &s), b.next_step(&without, &s));
                        match (x.unwrap(), y.unwrap()) {
                            (Some(x), Some(y)) => {
                                assert_eq!(x.angle.cmp_angle(&y.angle), Ordering::Equal);
                                assert_eq!((x.vertex, x.ahead), (y.vertex, y.ahead));
                                assert_eq!(x.cylinder, y.cylinder, "scene {k}, q = {q:?}");
                                steps += 1;
                            }
                            (None, None) => break,
                            (x, y) => panic!("scene {k}, q = {q:?}: {x:?} vs {y:?}"),
                        }
                    }
                }
            }
        }
        assert!(steps > 50_000, "{steps} steps");
        assert!(
            2 * arcs > bounded,
            "{arcs} of {bounded} arcs have one vertex"
        );
    }

    /// Every arc vertex kept is the tangent vertex of its chain in every direction strictly
    /// inside the cylinder's θ-range, tried at the directions of all pairs of vertices and
    /// the axes (cylinders round more than half a turn included).
    #[test]
    fn arc_vertices_are_the_chains_tangent_vertices() {
        let mut scenes: Vec<Scene> = (1..=8u64).map(|seed| random_scene(seed, 3)).collect();
        scenes.push(boxes());
        let mut checked = 0;
        for scene in &scenes {
            let s = scene.as_ref();
            let c = build_by_sweep(&s).unwrap().with_arc_vertices(&s);
            let n = s.vertices().len();
            let mut directions: Vec<Angle> = (0..n * n)
                .filter(|k| k / n != k % n)
                .map(|k| Angle::of_pair(ranked(&s, k / n), ranked(&s, k % n)))
                .collect();
            directions.extend([Angle::ZERO.reversed()]);
            for (i, z) in c.cylinders().iter().enumerate() {
                let arcs = c.borders_ref().arcs(CylinderId::from_index(i).unwrap());
                let left = c.wall_angle(&s, z.left).unwrap_or(Angle::ZERO);
                let right = c.wall_angle(&s, z.right);
                let inside = directions.iter().filter(|d| {
                    d.cmp_angle(&left) == Ordering::Greater
                        && right.is_none_or(|r| d.cmp_angle(&r) == Ordering::Less)
                });
                for d in inside {
                    for (chain, v) in [z.bottom, z.top].into_iter().zip(arcs) {
                        let (Some(chain), true) = (chain, v != NO_ARC_VERTEX) else {
                            continue;
                        };
                        let t = crate::line_space::tangent_vertex(&s, chain.object, d, chain.bound);
                        assert_eq!(t, v as usize, "cylinder {i} {z:?}, direction {d:?}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 50_000, "{checked}");
    }

    #[test]
    fn clockwise_walks_reverse_the_counter_clockwise_trace() {
        let (walked, exact, anchored) = check_scene(&boxes(), 1, 90);
        assert!(
            walked > 40 && exact > 10 && anchored > 20,
            "{walked} {exact} {anchored}"
        );
        for seed in 1..=12 {
            let k = 2 + (seed as i32 % 3);
            let scene = random_scene(seed, k);
            let (walked, exact, anchored) = check_scene(&scene, seed, 150);
            let counts = (walked, exact, anchored);
            assert!(
                walked > 60 && exact > 20 && anchored > 60,
                "seed {seed}: {counts:?}"
            );
        }
    }

    /// The step bound is kept across calls: a walk whose end it never reaches (laps
    /// round and round, both ways) errs `Corrupt` after `8 · cylinders + 8` steps, and
    /// stays failed.
    #[test]
    fn a_walk_that_does_not_end_is_corrupt() {
        let scene = boxes();
        let s = scene.as_ref();
        let c = build_by_sweep(&s).unwrap();
        let q = QueryPoint::from_f64(0.5, 0.25).unwrap();
        let mut start = None;
        c.walk_trace(&s, q, |st| {
            start.get_or_insert(st.cylinder);
        })
        .unwrap();
        // Going round and round: an end on a lap no walk reaches within the bound.
        let end = Position {
            lap: u8::MAX,
            angle: Angle::ZERO,
        };
        for ccw in [true, false] {
            let mut w: Traced = Traced::new(
                q,
                Anchor::Point,
                start.unwrap(),
                Angle::ZERO,
                Some(end),
                ccw,
            );
            let mut steps = 0;
            let err = loop {
                match w.next_step(&c, &s) {
                    Ok(Some(_)) => steps += 1,
                    Ok(None) => panic!("ended after {steps} steps"),
                    Err(e) => break e,
                }
            };
            assert_eq!(err, WalkError::Corrupt);
            assert_eq!(steps, 8 * c.cylinders().len() + 8);
            assert_eq!(w.next_step(&c, &s).unwrap_err(), WalkError::Corrupt);
        }
    }

    /// The θ = 0 index gives the scan's start cylinder or `NotFree` object for every
    /// viewpoint — free, inside, on edges, on vertices and on vertex heights — and stabs
    /// exactly the cylinders at θ = 0 whose closed height range holds the viewpoint.
    #[test]
    fn indexed_start_agrees_with_the_scan() {
        let scenes = (0..12u64)
            .map(|seed| random_scene(seed, 2 + (seed % 5) as i32))
            .chain([boxes()]);
        let (mut free, mut not_free) = (0, 0);
        for (k, scene) in scenes.enumerate() {
            let s = scene.as_ref();
            let c: Complex = build_by_sweep(&s).unwrap();
            let mut points = viewpoints(&scene, k as u64, 300);
            points.extend(s.vertices().iter().map(|v| v.to_query()));
            for q in points {
                let scan = c.trace_start_scan(&s, q);
                let indexed = c
                    .trace_start_indexed(&s, q, true)
                    .expect("the index answers");
                assert_eq!(indexed, scan, "scene {k}, q = {q:?}");
                if let Ok(id) = scan {
                    assert_eq!(c.trace_start_indexed(&s, q, false), Some(Ok(id)));
                }
                match scan {
                    Ok(_) => free += 1,
                    Err(_) => not_free += 1,
                }
                let mut stabbed = Vec::new();
                assert!(c.at_zero(&s, q.y(), |id, _| {
                    stabbed.push(id);
                    false
                }));
                stabbed.sort();
                let height = |ch: Option<Chain>, none: i64| {
                    ch.map_or(none, |ch| {
                        let (lo, hi) = s.object(ch.object).unwrap().bbox();
                        match ch.bound {
                            Bound::Lower => lo.to_query().y(),
                            Bound::Upper => hi.to_query().y(),
                        }
                    })
                };
                let expected: Vec<CylinderId> = c
                    .cylinders()
                    .iter()
                    .enumerate()
                    .filter(|(_, z)| {
                        z.left == Wall::Zero
                            && height(z.bottom, i64::MIN) <= q.y()
                            && q.y() <= height(z.top, i64::MAX)
                    })
                    .map(|(i, _)| CylinderId::from_index(i).unwrap())
                    .collect();
                assert_eq!(stabbed, expected, "scene {k}, height {}", q.y());
            }
        }
        assert!(free > 1000 && not_free > 100, "{free} free, {not_free} not");
    }
}
