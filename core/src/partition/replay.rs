//! The cylinders of the canonical partition from its vertices: the event loop of the
//! rotational sweep, without the sweep's geometry.
//!
//! Given the cylinders at θ = 0 and the vertices sorted by θ, every vertex closes the three
//! open cylinders of its corner faces and opens three (the table in [`super`]): which ones
//! follows from the vertex's chains and objects alone, with no predicate. So the
//! rotational sweep ([`super::build_by_sweep`]) and the reader of a version-3 file (which
//! stores only the vertices and the cylinders at θ = 0, `docs/format.md`) share this loop.
//! It allocates nothing: the open cylinders are indexed in a caller's slice of
//! [`open_slots`] entries, two per chain (at a fixed θ at most two open cylinders share a
//! chain on one side: the layers before and after its object).

use super::{Cylinder, CylinderId, Vertex, VertexId, Wall};
use crate::line_space::{Bound, Chain, Corner};

/// A placeholder cylinder for storage the replay fills.
pub const BLANK: Cylinder = Cylinder {
    floor: None,
    ceiling: None,
    bottom: None,
    top: None,
    left: Wall::Zero,
    right: Wall::Zero,
    left_neighbour: None,
    right_neighbour: None,
};

/// Two open cylinders per chain slot.
pub type Slots = [Option<CylinderId>; 2];

/// Entries of the scratch slice [`replay`] needs for a scene of `objects` objects: one
/// index by bottom chain and one by top chain, each with a slot per chain and one for "no
/// chain" (the unbounded cylinders).
pub const fn open_slots(objects: usize) -> usize {
    2 * (2 * objects + 1)
}

/// Why the vertices do not replay into a partition (a corrupt file, or a bug).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum ReplayError {
    /// Vertex `.0` closes a corner face that has no open cylinder.
    Lost(usize),
    /// Cylinder `.0` would be a third open cylinder on one chain.
    Crowded(usize),
    /// Cylinder `.0`, open at θ = 2π, has no cylinder at θ = 0 to continue into.
    Unmatched(usize),
    /// The slices are too short or ids overflow `u32`.
    Storage,
}

/// Slot of a chain; the last slot is for "no chain".
fn chain_slot(chain: Option<Chain>, objects: usize) -> usize {
    match chain {
        None => 2 * objects,
        Some(c) => 2 * c.object.0 as usize + usize::from(c.bound == Bound::Upper),
    }
}

/// The open cylinders by bottom chain and by top chain.
struct Open<'s> {
    objects: usize,
    by_bottom: &'s mut [Slots],
    by_top: &'s mut [Slots],
}

impl Open<'_> {
    fn insert(&mut self, id: CylinderId, c: &Cylinder) -> Result<(), ReplayError> {
        let n = self.objects;
        for (index, chain) in [(&mut *self.by_bottom, c.bottom), (&mut *self.by_top, c.top)] {
            let slots = index
                .get_mut(chain_slot(chain, n))
                .ok_or(ReplayError::Storage)?;
            let free = slots
                .iter_mut()
                .find(|s| s.is_none())
                .ok_or(ReplayError::Crowded(id.index()))?;
            *free = Some(id);
        }
        Ok(())
    }

    fn remove(&mut self, id: CylinderId, c: &Cylinder) {
        let n = self.objects;
        for (index, chain) in [(&mut *self.by_bottom, c.bottom), (&mut *self.by_top, c.top)] {
            if let Some(slots) = index.get_mut(chain_slot(chain, n)) {
                slots
                    .iter_mut()
                    .filter(|s| **s == Some(id))
                    .for_each(|s| *s = None);
            }
        }
    }
}

/// Fills `cylinders[initial..]` (exactly three per vertex) from the cylinders at θ = 0 in
/// `cylinders[..initial]` (floor, ceiling, bottom and top set; walls and neighbours are
/// overwritten) and the vertices sorted by θ, and links the cylinders open at θ = 2π to
/// those at θ = 0. `open` needs [`open_slots`]`(objects)` entries.
///
/// Cylinder ids are positions in `cylinders`: those at θ = 0 first, then the three opened
/// by each vertex in θ order (top wedge, bottom wedge, right wedge), which is how the
/// sweep numbers them.
pub(crate) fn replay(
    objects: usize,
    vertices: &[Vertex],
    initial: usize,
    cylinders: &mut [Cylinder],
    open: &mut [Slots],
) -> Result<(), ReplayError> {
    let (by_bottom, rest) = open
        .get_mut(..open_slots(objects))
        .ok_or(ReplayError::Storage)?
        .split_at_mut(2 * objects + 1);
    by_bottom.fill([None; 2]);
    rest.fill([None; 2]);
    let mut open = Open {
        objects,
        by_bottom,
        by_top: rest,
    };
    if cylinders.len() != initial + 3 * vertices.len() {
        return Err(ReplayError::Storage);
    }
    let id_of = |i: usize| CylinderId::from_index(i).ok_or(ReplayError::Storage);
    for i in 0..initial {
        let c = cylinders.get_mut(i).ok_or(ReplayError::Storage)?;
        c.left = Wall::Zero;
        c.right = Wall::Zero;
        c.left_neighbour = None;
        c.right_neighbour = None;
        let c = *c;
        open.insert(id_of(i)?, &c)?;
    }

    for (vi, v) in vertices.iter().enumerate() {
        let wall = Wall::Vertex(VertexId::from_index(vi).ok_or(ReplayError::Storage)?);
        let b = v.bitangent;
        let cp = Chain {
            object: b.first_object,
            bound: b.first_bound,
        };
        let cq = Chain {
            object: b.second_object,
            bound: b.second_bound,
        };
        let [top, bottom, left, right] = Corner::wedges(&b);

        let lost = ReplayError::Lost(vi);
        let cylinders_now: &[Cylinder] = cylinders;
        let find = |index: &[Slots], chain: Chain, corner: Corner| {
            let slots = index.get(chain_slot(Some(chain), objects))?;
            slots.iter().flatten().copied().find(|id| {
                cylinders_now
                    .get(id.index())
                    .is_some_and(|c| corner.matches(&b, c.floor, c.ceiling))
            })
        };
        // Top wedge: bottom arc switches from Q's chain to P's.
        let t = find(open.by_bottom, cq, top).ok_or(lost)?;
        // Bottom wedge: top arc switches from P's chain to Q's.
        let d = find(open.by_top, cp, bottom).ok_or(lost)?;
        // Left wedge: between P's chain (below) and Q's (above); closes.
        let l = find(open.by_bottom, cp, left)
            .filter(|id| {
                cylinders_now
                    .get(id.index())
                    .is_some_and(|c| c.top == Some(cq))
            })
            .ok_or(lost)?;
        if t == d || t == l || d == l {
            return Err(lost);
        }

        let mut close = |id: CylinderId| -> Result<Cylinder, ReplayError> {
            let c = cylinders.get_mut(id.index()).ok_or(ReplayError::Storage)?;
            c.right = wall;
            let c = *c;
            open.remove(id, &c);
            Ok(c)
        };
        let (ct, cd, cl) = (close(t)?, close(d)?, close(l)?);

        // The right wedge's face, from the floors and ceilings just closed.
        let closed = [ct, cd, cl].map(|c| (c.floor, c.ceiling));
        let (floor, ceiling) = right.face(&b, closed).ok_or(lost)?;

        let first = initial + 3 * vi;
        let (id_t, id_d) = (id_of(first)?, id_of(first + 1)?);
        let opened = [
            Cylinder {
                bottom: Some(cp),
                left: wall,
                right: Wall::Zero,
                left_neighbour: Some(t),
                right_neighbour: None,
                ..ct
            },
            Cylinder {
                top: Some(cq),
                left: wall,
                right: Wall::Zero,
                left_neighbour: Some(d),
                right_neighbour: None,
                ..cd
            },
            Cylinder {
                floor,
                ceiling,
                bottom: Some(cq),
                top: Some(cp),
                left: wall,
                right: Wall::Zero,
                left_neighbour: None,
                right_neighbour: None,
            },
        ];
        for (k, c) in opened.iter().enumerate() {
            let id = id_of(first + k)?;
            open.insert(id, c)?;
            *cylinders.get_mut(first + k).ok_or(ReplayError::Storage)? = *c;
        }
        for (from, to) in [(t, id_t), (d, id_d)] {
            cylinders
                .get_mut(from.index())
                .ok_or(ReplayError::Storage)?
                .right_neighbour = Some(to);
        }
    }

    // θ = 2π: each open cylinder continues into the cylinder at θ = 0 with the same bottom
    // chain, floor and ceiling. The index by top chain is done with: it now indexes the
    // cylinders at θ = 0 by bottom chain.
    open.by_top.fill([None; 2]);
    for i in 0..initial {
        let c = *cylinders.get(i).ok_or(ReplayError::Storage)?;
        let slots = open
            .by_top
            .get_mut(chain_slot(c.bottom, objects))
            .ok_or(ReplayError::Storage)?;
        let free = slots
            .iter_mut()
            .find(|s| s.is_none())
            .ok_or(ReplayError::Crowded(i))?;
        *free = Some(id_of(i)?);
    }
    for (slot, ids) in open.by_bottom.iter().enumerate() {
        for id in ids.iter().flatten().copied() {
            let c = *cylinders.get(id.index()).ok_or(ReplayError::Storage)?;
            let first = open
                .by_top
                .get(slot)
                .into_iter()
                .flatten()
                .flatten()
                .copied()
                .find(|f| {
                    cylinders
                        .get(f.index())
                        .is_some_and(|z| z.floor == c.floor && z.ceiling == c.ceiling)
                })
                .ok_or(ReplayError::Unmatched(id.index()))?;
            cylinders
                .get_mut(id.index())
                .ok_or(ReplayError::Storage)?
                .right_neighbour = Some(first);
            // Each cylinder at θ = 0 continues exactly one.
            let z = cylinders
                .get_mut(first.index())
                .ok_or(ReplayError::Storage)?;
            if z.left_neighbour.is_some() {
                return Err(ReplayError::Unmatched(id.index()));
            }
            z.left_neighbour = Some(id);
        }
    }
    // And each is continued by exactly one.
    match cylinders
        .get(..initial)
        .ok_or(ReplayError::Storage)?
        .iter()
        .position(|z| z.left_neighbour.is_none())
    {
        Some(i) => Err(ReplayError::Unmatched(i)),
        None => Ok(()),
    }
}
