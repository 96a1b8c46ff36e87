//! The cylinders of the canonical partition from its vertices: the event loop of the
//! rotational sweep, without the sweep's geometry.
//!
//! Given the cylinders at θ = 0 and the vertices sorted by θ, every vertex closes the three
//! open cylinders of its corner faces and opens three (the table in [`super`]): which ones
//! follows from the vertex's chains and objects alone, with no predicate. So the reader
//! of a version-3 file (which stores only the vertices and the cylinders at θ = 0,
//! `docs/format.md`) and the rotational sweep ([`super::build_by_sweep`]) when its kinetic
//! sweep falls back to the brute-force vertices share this loop (otherwise the kinetic
//! sweep finds each vertex's cylinders itself and builds the same partition).
//! It allocates nothing: the open cylinders are kept in a caller's slice of
//! [`open_slots`] entries, one per chain (at a fixed θ at most two open cylinders share a
//! chain on one side: the layers before and after its object).
//!
//! **Streaming.** The loop reads its input through a [`Stream`] (vertices in θ order, the
//! cylinders at θ = 0) and writes only the cylinders the stream keeps, renumbered in
//! replay order, and the vertices a kept cylinder's wall names, renumbered in θ order:
//! the numbering of [`Complex::prune_to_region`](super::Complex::prune_to_region), whose
//! kept cylinders at θ = 0 come first because the replay numbers them first. An open
//! cylinder lives in the open slots with the fields the loop reads (once, in its bottom
//! chain's slot; its top chain's slot says where), so the storage is the kept arenas and
//! the slots, never the whole complex (the reader of a version-4 region file). Keeping
//! everything is the sweep's partition ([`replay`]).

use super::{Cylinder, CylinderId, Vertex, VertexId, Wall};
use crate::line_space::{Bitangent, Bound, Chain, Corner};
use crate::scene::ObjectId;
use core::num::NonZeroU32;

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

/// An open cylinder: its id in replay order, its id among the kept ones, and the fields
/// the replay reads (the others are written to the kept cylinder, if any).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Open {
    id: CylinderId,
    kept: Option<CylinderId>,
    floor: Option<ObjectId>,
    ceiling: Option<ObjectId>,
    bottom: Option<Chain>,
    top: Option<Chain>,
}

impl Open {
    /// The cylinder with these fields, its walls θ = 0 and no neighbours yet.
    fn cylinder(&self) -> Cylinder {
        Cylinder {
            floor: self.floor,
            ceiling: self.ceiling,
            bottom: self.bottom,
            top: self.top,
            ..BLANK
        }
    }
}

/// One chain's open cylinders (at a fixed θ at most two share a chain on one side): the
/// records of those whose bottom arc it is, and where the records of those whose top arc
/// it is are, so that each record is stored once.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Slots {
    by_bottom: [Option<Open>; 2],
    by_top: [Option<Place>; 2],
}

/// Where an open cylinder's record is: record `k` of chain slot `s` is at position
/// `2·s + k`, stored plus one so that `None` is all zero bytes.
type Place = NonZeroU32;

/// Slots whose bytes are all zero, for a `static` scratch of them to land in `.bss`
/// rather than in `.data` with a flash image (`None` of an `Open` is a niche value of a
/// chain's bound, not 0). The replay clears its slots before use, so any value will do:
/// these are the blank slots for any caller.
pub const ZERO_SLOTS: Slots = {
    let chain = Some(Chain {
        object: ObjectId(0),
        bound: Bound::Lower,
    });
    let zero = Open {
        id: CylinderId::ZERO,
        kept: None,
        floor: None,
        ceiling: None,
        bottom: chain,
        top: chain,
    };
    Slots {
        by_bottom: [Some(zero); 2],
        by_top: [None; 2],
    }
};

/// Entries of the scratch slice [`replay`] needs for a scene of `objects` objects: one
/// per chain and one for "no chain" (the unbounded cylinders).
pub const fn open_slots(objects: usize) -> usize {
    2 * objects + 1
}

/// Why the vertices do not replay into a partition (a corrupt file, or a bug).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum ReplayError {
    /// Vertex `.0` closes a corner face that has no open cylinder.
    Lost(usize),
    /// Cylinder `.0` at θ = 0 would be a third open cylinder on one chain (a vertex's
    /// opened cylinders take the places of those it closes, so only these can crowd).
    Crowded(usize),
    /// Cylinder `.0` (replay order), at θ = 0 or open at θ = 2π, has no partner across
    /// the wall θ = 0.
    Unmatched(usize),
    /// The slices are too short or ids overflow `u32`.
    Storage,
    /// The stream could not read its input (it keeps its own error; only the file
    /// reader's can fail).
    #[cfg_attr(not(feature = "format"), allow(dead_code))]
    Input,
}

/// The input and output of [`replay_stream`].
pub(crate) trait Stream {
    /// The next vertex in θ order (asked for once each, in order).
    fn vertex(&mut self) -> Result<Vertex, ReplayError>;
    /// The cylinder at θ = 0 number `i` (floor, ceiling, bottom, top; the rest is
    /// ignored). Asked for in order, twice: when opened, and when matched at θ = 2π.
    fn initial(&mut self, i: usize) -> Result<Cylinder, ReplayError>;
    /// Whether the cylinder `id` (replay order) is kept: asked in order, the cylinders at
    /// θ = 0 twice like [`Stream::initial`].
    fn keep(&mut self, id: usize) -> Result<bool, ReplayError>;
    /// Stores kept vertex number `new`.
    fn put_vertex(&mut self, new: usize, v: &Vertex) -> Result<(), ReplayError>;
    /// The kept cylinders, by new id.
    fn cylinders(&mut self) -> &mut [Cylinder];
}

/// Slot of a chain; the last slot is for "no chain".
fn chain_slot(chain: Option<Chain>, objects: usize) -> usize {
    match chain {
        None => 2 * objects,
        Some(c) => 2 * c.object.0 as usize + usize::from(c.bound == Bound::Upper),
    }
}

/// The open cylinders, indexed by bottom chain and by top chain.
struct OpenSet<'s> {
    objects: usize,
    slots: &'s mut [Slots],
}

impl OpenSet<'_> {
    /// The record at `position` (`2·slot + k`).
    fn record(&self, position: usize) -> Option<&Open> {
        self.slots
            .get(position / 2)?
            .by_bottom
            .get(position % 2)?
            .as_ref()
    }

    /// The open cylinder whose top arc (`by_top`) or bottom arc is `chain` and whose
    /// floor and ceiling are `corner`'s at `b`, and its record's position. Inlined: three
    /// calls per vertex, each with a constant `by_top`.
    #[inline(always)]
    fn find(
        &self,
        by_top: bool,
        chain: Chain,
        corner: Corner,
        b: &Bitangent,
    ) -> Option<(usize, Open)> {
        let slot = chain_slot(Some(chain), self.objects);
        let positions = match by_top {
            true => self
                .slots
                .get(slot)?
                .by_top
                .map(|p| p.map(|p| p.get() as usize - 1)),
            false => [Some(2 * slot), Some(2 * slot + 1)],
        };
        positions.into_iter().flatten().find_map(|p| {
            let c = self.record(p)?;
            corner.matches(b, c.floor, c.ceiling).then_some((p, *c))
        })
    }

    /// Opens cylinder `c` at θ = 0.
    fn insert(&mut self, c: Open) -> Result<(), ReplayError> {
        let crowded = ReplayError::Crowded(c.id.index());
        let slot = chain_slot(c.bottom, self.objects);
        let (k, record) = self
            .slots
            .get_mut(slot)
            .ok_or(ReplayError::Storage)?
            .by_bottom
            .iter_mut()
            .enumerate()
            .find(|(_, r)| r.is_none())
            .ok_or(crowded)?;
        *record = Some(c);
        let place = place(2 * slot + k).ok_or(ReplayError::Storage)?;
        let free = self
            .slots
            .get_mut(chain_slot(c.top, self.objects))
            .ok_or(ReplayError::Storage)?
            .by_top
            .iter_mut()
            .find(|p| p.is_none())
            .ok_or(crowded)?;
        *free = Some(place);
        Ok(())
    }

    /// Puts `c` at `position`, in place of the closed cylinder whose record was there
    /// (same bottom chain).
    fn put(&mut self, position: usize, c: Open) {
        if let Some(record) = self
            .slots
            .get_mut(position / 2)
            .and_then(|s| s.by_bottom.get_mut(position % 2))
        {
            *record = Some(c);
        }
    }

    /// Points `chain`'s reference to the record at `from` to the one at `to`.
    fn repoint(&mut self, chain: Option<Chain>, from: usize, to: usize) {
        let (Some(slots), Some(from), Some(to)) = (
            self.slots.get_mut(chain_slot(chain, self.objects)),
            place(from),
            place(to),
        ) else {
            return;
        };
        if let Some(p) = slots.by_top.iter_mut().find(|p| **p == Some(from)) {
            *p = Some(to);
        }
    }
}

/// The place of the record at `position`.
fn place(position: usize) -> Option<Place> {
    u32::try_from(position + 1).ok().and_then(Place::new)
}

/// A kept cylinder of the output.
fn output<S: Stream>(stream: &mut S, id: CylinderId) -> Result<&mut Cylinder, ReplayError> {
    stream
        .cylinders()
        .get_mut(id.index())
        .ok_or(ReplayError::Storage)
}

/// Hands out the kept cylinders' new ids, in replay order.
struct Numbering {
    next: usize,
}

impl Numbering {
    fn number<S: Stream>(
        &mut self,
        stream: &mut S,
        id: usize,
    ) -> Result<Option<CylinderId>, ReplayError> {
        if !stream.keep(id)? {
            return Ok(None);
        }
        let new = CylinderId::from_index(self.next).ok_or(ReplayError::Storage)?;
        self.next += 1;
        Ok(Some(new))
    }
}

/// The replay over a [`Stream`] of `initial` cylinders at θ = 0 and `vertices` vertices
/// (module doc): writes the kept cylinders with their walls and links (a link to a
/// dropped cylinder is `None`) and the kept vertices; returns how many vertices and
/// cylinders it kept. `open` needs [`open_slots`]`(objects)` entries.
///
/// Replay ids: the cylinders at θ = 0 first, then the three opened by each vertex in θ
/// order (top wedge, bottom wedge, right wedge), which is how the sweep numbers them.
pub(crate) fn replay_stream<S: Stream>(
    objects: usize,
    initial: usize,
    vertices: usize,
    stream: &mut S,
    open: &mut [Slots],
) -> Result<(usize, usize), ReplayError> {
    let slots = open
        .get_mut(..open_slots(objects))
        .ok_or(ReplayError::Storage)?;
    slots.fill(Slots {
        by_bottom: [None; 2],
        by_top: [None; 2],
    });
    let mut open = OpenSet { objects, slots };
    let id_of = |i: usize| CylinderId::from_index(i).ok_or(ReplayError::Storage);
    // Every replay id fits (so `initial + 3·vi` below cannot overflow).
    vertices
        .checked_mul(3)
        .and_then(|k| k.checked_add(initial))
        .ok_or(ReplayError::Storage)?;
    let mut numbering = Numbering { next: 0 };
    for i in 0..initial {
        let z = stream.initial(i)?;
        let c = Open {
            id: id_of(i)?,
            kept: numbering.number(stream, i)?,
            floor: z.floor,
            ceiling: z.ceiling,
            bottom: z.bottom,
            top: z.top,
        };
        if let Some(new) = c.kept {
            *output(stream, new)? = c.cylinder();
        }
        open.insert(c)?;
    }

    let mut kept_vertices = 0usize;
    for vi in 0..vertices {
        let v = stream.vertex()?;
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
        // Top wedge: bottom arc switches from Q's chain to P's.
        let (at_t, t) = open.find(false, cq, top, &b).ok_or(lost)?;
        // Bottom wedge: top arc switches from P's chain to Q's.
        let (at_d, d) = open.find(true, cp, bottom, &b).ok_or(lost)?;
        // Left wedge: between P's chain (below) and Q's (above); closes.
        let (at_l, l) = open
            .find(false, cp, left, &b)
            .filter(|(_, c)| c.top == Some(cq))
            .ok_or(lost)?;
        if at_t == at_d || at_t == at_l || at_d == at_l {
            return Err(lost);
        }

        // The right wedge's face, from the floors and ceilings just closed.
        let closed = [t, d, l].map(|c| (c.floor, c.ceiling));
        let (floor, ceiling) = right.face(&b, closed).ok_or(lost)?;

        let first = initial + 3 * vi;
        let mut opened = [
            Open {
                bottom: Some(cp),
                ..t
            },
            Open { top: Some(cq), ..d },
            Open {
                floor,
                ceiling,
                bottom: Some(cq),
                top: Some(cp),
                ..t
            },
        ];
        for (k, c) in opened.iter_mut().enumerate() {
            c.id = id_of(first + k)?;
            c.kept = numbering.number(stream, first + k)?;
        }
        // The vertex is kept iff it is a wall of a kept cylinder: of one it closes or opens.
        let wall = if [t.kept, d.kept, l.kept]
            .iter()
            .chain(opened.iter().map(|c| &c.kept))
            .any(Option::is_some)
        {
            stream.put_vertex(kept_vertices, &v)?;
            let id = VertexId::from_index(kept_vertices).ok_or(ReplayError::Storage)?;
            kept_vertices += 1;
            Wall::Vertex(id)
        } else {
            Wall::Zero
        };
        let [o_t, o_d, _] = &opened;
        for (closed, next) in [(t.kept, o_t.kept), (d.kept, o_d.kept), (l.kept, None)] {
            if let Some(new) = closed {
                let c = output(stream, new)?;
                c.right = wall;
                c.right_neighbour = next;
            }
        }
        // The opened cylinders take the closed ones' places: o_t has l's bottom chain (P's),
        // o_d d's, o_r t's (Q's); and o_t has t's top chain, o_d l's (Q's), o_r d's (P's).
        let places = [at_l, at_d, at_t];
        for ((c, previous), position) in opened.into_iter().zip([t.kept, d.kept, None]).zip(places)
        {
            if let Some(new) = c.kept {
                *output(stream, new)? = Cylinder {
                    left: wall,
                    left_neighbour: previous,
                    ..c.cylinder()
                };
            }
            open.put(position, c);
        }
        for ((chain, from), to) in [(t.top, at_t), (l.top, at_l), (d.top, at_d)]
            .into_iter()
            .zip(places)
        {
            open.repoint(chain, from, to);
        }
    }

    // θ = 2π: each cylinder at θ = 0 continues the open cylinder with the same bottom
    // chain, floor and ceiling, and no open cylinder is left over.
    let mut at_zero = Numbering { next: 0 };
    for i in 0..initial {
        let z = stream.initial(i)?;
        let z_kept = at_zero.number(stream, i)?;
        let c = open
            .slots
            .get_mut(chain_slot(z.bottom, objects))
            .and_then(|slots| {
                slots
                    .by_bottom
                    .iter_mut()
                    .find(|c| c.is_some_and(|c| c.floor == z.floor && c.ceiling == z.ceiling))
            })
            .and_then(Option::take)
            .ok_or(ReplayError::Unmatched(i))?;
        if let Some(new) = c.kept {
            output(stream, new)?.right_neighbour = z_kept;
        }
        if let Some(new) = z_kept {
            output(stream, new)?.left_neighbour = c.kept;
        }
    }
    if let Some(c) = open
        .slots
        .iter()
        .flat_map(|s| s.by_bottom.iter().flatten())
        .next()
    {
        return Err(ReplayError::Unmatched(c.id.index()));
    }
    Ok((kept_vertices, numbering.next))
}

/// Everything kept: the partition in caller storage.
struct Whole<'a> {
    vertices: core::slice::Iter<'a, Vertex>,
    cylinders: &'a mut [Cylinder],
}

impl Stream for Whole<'_> {
    fn vertex(&mut self) -> Result<Vertex, ReplayError> {
        self.vertices.next().copied().ok_or(ReplayError::Storage)
    }
    fn initial(&mut self, i: usize) -> Result<Cylinder, ReplayError> {
        self.cylinders.get(i).copied().ok_or(ReplayError::Storage)
    }
    fn keep(&mut self, _: usize) -> Result<bool, ReplayError> {
        Ok(true)
    }
    fn put_vertex(&mut self, _: usize, _: &Vertex) -> Result<(), ReplayError> {
        Ok(())
    }
    fn cylinders(&mut self) -> &mut [Cylinder] {
        self.cylinders
    }
}

/// Fills `cylinders[initial..]` (exactly three per vertex) from the cylinders at θ = 0 in
/// `cylinders[..initial]` (floor, ceiling, bottom and top set; walls and neighbours are
/// overwritten) and the vertices sorted by θ, and links the cylinders open at θ = 2π to
/// those at θ = 0: [`replay_stream`] keeping everything. `open` needs
/// [`open_slots`]`(objects)` entries.
pub(crate) fn replay(
    objects: usize,
    vertices: &[Vertex],
    initial: usize,
    cylinders: &mut [Cylinder],
    open: &mut [Slots],
) -> Result<(), ReplayError> {
    if cylinders.len() != initial + 3 * vertices.len() {
        return Err(ReplayError::Storage);
    }
    let mut whole = Whole {
        vertices: vertices.iter(),
        cylinders,
    };
    replay_stream(objects, initial, vertices.len(), &mut whole, open).map(|_| ())
}
