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
//! # Ray trees (`ray_tree`, feature `alloc`)
//!
//! The walker has two anchorings ([`Anchor`]): `Point` (the layer containing the eye, the
//! view) and `Floor(M)` (the layer whose floor is M: the segments starting where the line
//! leaves M), walked over an exact open angular range from a (virtual) eye. An anchored
//! walk starts in the cylinder with floor M that contains the eye's line just after the
//! range start, turned by more than the symbolic perturbation (everything exactly on the
//! opening ray is behind: the range is open), found by climbing the stack of M's floor
//! cylinders through the per-chain tilings (`Complex::across`; a scan only where
//! something lies exactly on the opening ray and the two disagree); events on the closing
//! ray are dropped.
//!
//! The tree is built by **recursion per interval**, not by the paper's lock-step walk of
//! all generations: each primary interval is resolved by its ceiling —
//! * a **screen** S: the same eye walks the same range anchored to S (S is not in the
//!   branch and uses no depth);
//! * a **mirror** M: the range is split by the directions to M's vertices (the hit edge
//!   changes there); per edge the eye is reflected across the edge's line and rounded
//!   exactly to the query grid ([`optics`]); the range is mapped to the new eye (exactly
//!   `E' → v` at a vertex of the edge, otherwise the direction to the hit point on the
//!   edge — computed in `f64` at 2⁻⁵² rad, it only places the range end) and reversed
//!   (mirrors flip orientation); the new eye walks it anchored to M, one level deeper;
//! * a **refractive** M (tangent law, DESIGN.md §6): split by the entry edge, entry eye
//!   `E₁ = F + η(E − F)`, split by the exit edge (M's own vertices seen from `E₁`), exit
//!   eye `E₂ = F' + (E₁ − F')/η`, walked anchored to M; orientation is preserved, and the
//!   pass is one depth level with M once in the branch.
//!
//! Boundaries deeper than the primary are mapped back to primary angles in `f64` for
//! output. A later optimization keeps the secondary traces of one primary interval in a
//! fixed-capacity `heapless` array and walks them in lock step (no allocation; the
//! current version allocates the leaves and branches).
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
#[cfg(feature = "alloc")]
mod tree;
mod view;

#[cfg(feature = "alloc")]
pub use tree::{frame_tree, ray_tree, ray_tree_range, TreeInterval};
#[cfg(feature = "alloc")]
pub use view::{view, view_range};
pub use view::{view_capacity, view_into, view_range_into, ViewInterval};

use crate::geom::sos::{Angle, KeyedAngle};
use crate::geom::QueryPoint;
use crate::line_space::{ranked, Bound, Chain};
use crate::partition::{Complex, CylinderId, Layer, Location, Side, Storage, Wall};
use crate::scene::{ObjectId, SceneRef};

/// Entries of a walk's cache of tangents from the eye (round robin): eight hold the
/// objects a grid view's consecutive cylinders share (four missed often enough to cost
/// about 7 % of a view; sixteen cost more to search than they save).
const TANGENT_CACHE: usize = 8;

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

/// A position on the unwrapped circle of a range walk: `lap` 1 is past θ = 2π.
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
        // A pruned complex holds only what views from its region need (`partition::region`).
        if let Some(r) = self.region().filter(|r| !r.contains(q)) {
            return Err(WalkError::OutsideRegion(r));
        }
        if let Some(l) = crate::partition::point_in_scene(scene, q) {
            return Err(WalkError::NotFree(l));
        }
        // At θ = 0 a chain's tangent is its object's lowest (lower chain) or highest (upper
        // chain) vertex, so a cylinder whose bottom tangent lies above `q` or whose top
        // tangent lies below it (in y, from the bounding boxes: exact integers) cannot hold
        // `q`'s line; the exact, perturbed test runs on the few that remain.
        let qy = q.y();
        let height = |chain: &Chain| {
            let (lo, hi) = scene.object(chain.object)?.bbox();
            let p = match chain.bound {
                Bound::Lower => lo,
                Bound::Upper => hi,
            };
            Some(p.to_query().y())
        };
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
        let cur = self
            .locate_among(scene, q, &Angle::ZERO, zero)
            .ok_or(WalkError::Corrupt)?;
        step(&Step {
            angle: Angle::ZERO,
            vertex: None,
            ahead: false,
            cylinder: cur,
        });
        self.walk_from(scene, q, Anchor::Point, cur, Angle::ZERO, None, &mut step)
    }

    /// The walker shared by [`Complex::walk_trace`] and the anchored walks of ray trees:
    /// from cylinder `cur` at angle `from`, counter-clockwise, until `end` (`None`: until
    /// θ = 2π; `Some(end)`: the first event at or after `end`, which may lie past θ = 0 —
    /// the walk then crosses the permanent wall to the right neighbour). Calls `step` for
    /// every cylinder entered after the start. With [`Anchor::Floor`]`(m)` the chains of `m`
    /// are never crossed (the caller keeps the trace inside `m`'s sheet) and the eye may lie
    /// anywhere, even inside an object: only the tangents that exist are used.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn walk_from(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        anchor: Anchor,
        mut cur: CylinderId,
        from: Angle,
        end: Option<Position>,
        step: &mut impl FnMut(&Step),
    ) -> Result<(), WalkError> {
        use core::cmp::Ordering;
        // Angles compared more than once carry their half-plane and vector (`KeyedAngle`).
        let mut theta = from.keyed();
        let mut lap = 0u8;
        let before = |a: (u8, &KeyedAngle), b: (u8, &KeyedAngle)| {
            a.0 < b.0 || (a.0 == b.0 && a.1.cmp(b.1) == Ordering::Less)
        };
        let end = end.map(|e| (e.lap, e.angle.keyed()));
        // The tangents from `q` to the last few chain objects: consecutive cylinders of a
        // trace mostly share a chain, and the tangents depend only on the object.
        let mut cache = [(None::<ObjectId>, [(0usize, Bound::Lower); 2], 0usize); TANGENT_CACHE];
        let mut next_slot = 0;
        let mut tangents = |object: ObjectId| {
            if let Some(&(_, t, n)) = cache.iter().find(|e| e.0 == Some(object)) {
                return (t, n);
            }
            let (t, n) = crate::line_space::tangents_from(scene, object, q);
            if let Some(slot) = cache.get_mut(next_slot % TANGENT_CACHE) {
                *slot = (Some(object), t, n);
            }
            next_slot += 1;
            (t, n)
        };
        for _ in 0..4 * self.cylinders().len() + 4 {
            let c = self.cylinder(cur).ok_or(WalkError::Corrupt)?;
            // The first exit after θ: the right wall, or a crossing of the bottom or top chain.
            let mut best: Option<(u8, KeyedAngle, Option<ChainExit>)> = match c.right {
                // The permanent wall ends a full-circle walk; a range walk crosses it.
                Wall::Zero => end.map(|_| (lap + 1, Angle::ZERO.keyed(), None)),
                w => self.wall_angle(scene, w).map(|a| (lap, a.keyed(), None)),
            };
            for (chain, side) in [(c.bottom, Side::Below), (c.top, Side::Above)] {
                let Some(chain) = chain else { continue };
                if anchor == Anchor::Floor(chain.object) {
                    continue;
                }
                let (found, count) = tangents(chain.object);
                for &(h, bound) in found.iter().take(count) {
                    let forward = Angle::from_query(q, ranked(scene, h));
                    // The line q → h lies on `bound`; its reverse on the other chain.
                    let (a, ahead) = if bound == chain.bound {
                        (forward.keyed(), true)
                    } else {
                        (forward.reversed().keyed(), false)
                    };
                    let later = a.cmp(&theta) == Ordering::Greater;
                    if later
                        && best
                            .as_ref()
                            .is_none_or(|(l, b, _)| before((lap, &a), (*l, b)))
                    {
                        best = Some((
                            lap,
                            a,
                            Some(ChainExit {
                                chain,
                                side,
                                vertex: h,
                                ahead,
                            }),
                        ));
                    }
                }
            }
            let Some((l, angle, exit)) = best else {
                return match end {
                    None => Ok(()), // θ reached 2π
                    Some(_) => Err(WalkError::Corrupt),
                };
            };
            if let Some((e_lap, e_angle)) = &end {
                if !before((l, &angle), (*e_lap, e_angle)) {
                    return Ok(());
                }
            }
            theta = angle;
            lap = l;
            cur = match exit {
                None => c.right_neighbour.ok_or(WalkError::Corrupt)?,
                Some(ChainExit {
                    chain, side, ahead, ..
                }) => {
                    // Lines on the far side of a lower chain cross the object iff that side
                    // is above it; of an upper chain iff it is below.
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
                    // The entered cylinder overlaps the one left: scan the far side from
                    // there (usually a step or two) instead of bisecting the tiling.
                    let next = self
                        .across_from(scene, cur, side, layer, &theta.angle)
                        .ok_or(WalkError::Corrupt)?;
                    if let Anchor::Floor(m) = anchor {
                        if self.cylinder(next).and_then(|n| n.floor) != Some(m) {
                            return Err(WalkError::Corrupt);
                        }
                    }
                    next
                }
            };
            let (vertex, ahead) = exit.map_or((None, false), |e| (Some(e.vertex), e.ahead));
            step(&Step {
                angle: theta.angle,
                vertex,
                ahead,
                cylinder: cur,
            });
        }
        Err(WalkError::Corrupt)
    }

    /// The object a cylinder's rays see ahead.
    pub fn ceiling(&self, id: CylinderId) -> Option<ObjectId> {
        self.cylinder(id).and_then(|c| c.ceiling)
    }
}
