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

#[cfg(feature = "alloc")]
mod view;

#[cfg(feature = "alloc")]
pub use view::{view, ViewInterval};

use crate::geom::sos::Angle;
use crate::geom::QueryPoint;
use crate::line_space::{ranked, tangents_from, Bound, Chain};
use crate::partition::{Complex, CylinderId, Layer, Location, Side, Wall};
use crate::scene::{ObjectId, SceneRef};

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
        }
    }
}

impl core::error::Error for WalkError {}

impl Complex {
    /// Walks the trace of the free point `q` once around, from θ = 0, calling `step` for
    /// every cylinder entered (the first call is the start cylinder, with `vertex: None`).
    /// Allocates nothing; every iteration enters a new cylinder, and the walk is bounded by
    /// four times the number of cylinders.
    pub fn walk_trace(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        mut step: impl FnMut(&Step),
    ) -> Result<(), WalkError> {
        if let Some(l) = crate::partition::point_in_scene(scene, q) {
            return Err(WalkError::NotFree(l));
        }
        let zero = self
            .cylinders
            .iter()
            .enumerate()
            .filter(|(_, c)| c.left == Wall::Zero)
            .map(|(i, c)| (CylinderId::from_index(i).unwrap_or(CylinderId::ZERO), c));
        let mut cur = self
            .locate_among(scene, q, &Angle::ZERO, zero)
            .ok_or(WalkError::Corrupt)?;
        let mut theta = Angle::ZERO;
        step(&Step {
            angle: theta,
            vertex: None,
            ahead: false,
            cylinder: cur,
        });
        for _ in 0..4 * self.cylinders.len() + 4 {
            let c = self.cylinder(cur).ok_or(WalkError::Corrupt)?;
            // The first exit after θ: the right wall, or a crossing of the bottom or top chain.
            let mut best: Option<(Angle, Option<ChainExit>)> =
                self.wall_angle(scene, c.right).map(|a| (a, None));
            for (chain, side) in [(c.bottom, Side::Below), (c.top, Side::Above)] {
                let Some(chain) = chain else { continue };
                for (h, bound) in tangents_from(scene, chain.object, q) {
                    let forward = Angle::from_query(q, ranked(scene, h));
                    // The line q → h lies on `bound`; its reverse on the other chain.
                    let (a, ahead) = if bound == chain.bound {
                        (forward, true)
                    } else {
                        (forward.reversed(), false)
                    };
                    let later = a.cmp_angle(&theta) == core::cmp::Ordering::Greater;
                    if later
                        && best
                            .as_ref()
                            .is_none_or(|(b, _)| a.cmp_angle(b) == core::cmp::Ordering::Less)
                    {
                        best = Some((
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
            let Some((angle, exit)) = best else {
                return Ok(());
            }; // θ reached 2π
            theta = angle;
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
                    } else if ahead {
                        Layer::Before
                    } else {
                        Layer::After
                    };
                    self.across_from(scene, cur, side, layer, &theta)
                        .ok_or(WalkError::Corrupt)?
                }
            };
            let (vertex, ahead) = exit.map_or((None, false), |e| (Some(e.vertex), e.ahead));
            step(&Step {
                angle: theta,
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
