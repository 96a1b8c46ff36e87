//! Adjacency across primary walls: for every chain, the cylinders bordering it from above
//! and from below, in θ order. Each list tiles the whole circle of directions once: below
//! a lower chain (and above an upper chain) lies one layer, the one in which the chain's
//! object is not crossed; on the other side lie two, before and after the object in t.

#[cfg(feature = "alloc")]
use alloc::vec::Vec;
use core::cmp::Ordering;

#[cfg(feature = "alloc")]
use super::Complex;
use super::{Cylinder, CylinderId, Storage, Vertex, Wall};
use crate::geom::sos::{Angle, KeyedAngle};
use crate::line_space::Chain;
use crate::scene::SceneRef;

/// Which side of a chain a cylinder lies on.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Side {
    /// The chain is the cylinder's top arc.
    Below,
    /// The chain is the cylinder's bottom arc.
    Above,
}

/// Where a bordering cylinder's free segments lie relative to the chain's object.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Layer {
    /// The object is not crossed on this side of the chain.
    Around,
    /// Segments ending at the object (its ceiling is the object).
    Before,
    /// Segments starting at the object (its floor is the object).
    After,
}

impl Layer {
    pub(super) fn of(c: &Cylinder, chain: Chain) -> Layer {
        if c.ceiling == Some(chain.object) {
            Layer::Before
        } else if c.floor == Some(chain.object) {
            Layer::After
        } else {
            Layer::Around
        }
    }
}

/// Derived lookup state of a complex, borrowed: the angle of every vertex, for every
/// chain, side and layer the bordering cylinders sorted by θ (one flat id array cut by
/// offsets), addressed by an index (no map on the walk's hot path), and the index of the
/// cross-section at θ = 0 that starts a view ([`Complex::at_zero`]). Rebuilt from the
/// cylinders and vertices, never trusted from a file: [`BordersRef::rebuild_into`].
#[derive(Clone, Copy, Debug, Default)]
pub struct BordersRef<'a> {
    /// θ of every vertex, in vertex order; empty to compute angles on demand (saves
    /// `size_of::<Angle>()` bytes of RAM per vertex, costs one angle construction per wall).
    angles: &'a [Angle],
    /// The tilings, one after the other: `ids[offsets[k]..offsets[k + 1]]` is tiling `k`;
    /// after the `12 · objects` tilings, the cylinders at θ = 0 sorted by the height of
    /// their bottom arc, then their interval tree's maxima (see `ZeroIndex`).
    ids: &'a [CylinderId],
    /// `12 · objects + 3` offsets into `ids`.
    offsets: &'a [u32],
    /// For every cylinder, its bottom (`[0]`) and top (`[1]`) arc, and each of the (at most
    /// two) layers on the far side of that arc: the index, in the far side's tiling, of the
    /// cylinder containing this cylinder's left wall. A walk leaving the cylinder across
    /// the arc scans forward from there.
    start: &'a [[[u32; 2]; 2]],
    /// For every cylinder, the vertex of its bottom (`[0]`) and top (`[1]`) arc where that
    /// arc is one vertex's sinusoid ([`crate::line_space::arc_vertex`]; global index,
    /// [`NO_ARC_VERTEX`] otherwise): a walk takes its candidate exit there without the
    /// tangents from the eye. Empty unless kept by `Complex::with_arc_vertices` (walks then
    /// use the tangents for every arc).
    arcs: &'a [[u32; 2]],
}

/// An arc without a single vertex in [`BordersRef`]'s arc vertices (or unbounded).
pub(crate) const NO_ARC_VERTEX: u32 = u32::MAX;

/// Derived lookup state of a complex in growable storage (feature `alloc`).
#[cfg(feature = "alloc")]
#[derive(Clone, Debug, Default)]
pub struct Borders {
    angles: Vec<Angle>,
    ids: Vec<CylinderId>,
    offsets: Vec<u32>,
    start: Vec<[[u32; 2]; 2]>,
    arcs: Vec<[u32; 2]>,
}

#[cfg(feature = "alloc")]
impl Borders {
    /// The borrowed view.
    #[inline]
    pub fn borrowed(&self) -> BordersRef<'_> {
        BordersRef {
            angles: &self.angles,
            ids: &self.ids,
            offsets: &self.offsets,
            start: &self.start,
            arcs: &self.arcs,
        }
    }
}

/// How many elements each buffer of [`BorderBuffers`] needs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct BorderSizes {
    /// Vertex angles: one per vertex (or 0, to compute them on demand).
    pub angles: usize,
    /// Cylinder ids of the tilings (one per bounded arc of a cylinder, at most two each)
    /// and of the θ = 0 index (two per cylinder at θ = 0: `3 · objects + 1` of them).
    pub ids: usize,
    /// Tiling offsets: `12 · objects + 3`.
    pub offsets: usize,
    /// Start indices: one per cylinder.
    pub start: usize,
}

impl BorderSizes {
    /// Sizes that suffice for any complex with these counts (`ids` is the upper bound
    /// `2 · cylinders + 2 · (3 · objects + 1)`); usable in `const` array lengths.
    pub const fn for_counts(objects: usize, vertices: usize, cylinders: usize) -> BorderSizes {
        BorderSizes {
            angles: vertices,
            ids: 2 * cylinders + 2 * (3 * objects + 1),
            offsets: 12 * objects + 3,
            start: cylinders,
        }
    }

    /// The exact sizes for these cylinders (`ids` counts their bounded arcs and twice the
    /// cylinders at θ = 0).
    pub fn exact(objects: usize, vertices: usize, cylinders: &[Cylinder]) -> BorderSizes {
        let arcs: usize = cylinders
            .iter()
            .map(|c| usize::from(c.bottom.is_some()) + usize::from(c.top.is_some()))
            .sum();
        let zero = cylinders.iter().filter(|c| c.left == Wall::Zero).count();
        BorderSizes {
            ids: arcs + 2 * zero,
            ..BorderSizes::for_counts(objects, vertices, cylinders.len())
        }
    }

    /// Bytes of RAM the four buffers take (with vertex angles).
    pub const fn bytes(&self) -> usize {
        self.angles * core::mem::size_of::<Angle>()
            + self.ids * core::mem::size_of::<CylinderId>()
            + self.offsets * core::mem::size_of::<u32>()
            + self.start * core::mem::size_of::<[[u32; 2]; 2]>()
    }
}

/// Caller-provided buffers that [`BordersRef::rebuild_into`] fills; sizes from
/// [`BorderSizes`]. Longer buffers are fine (only a prefix is used); `angles` may also be
/// empty.
#[derive(Debug)]
pub struct BorderBuffers<'a> {
    /// Vertex angles.
    pub angles: &'a mut [Angle],
    /// Tiling cylinder ids.
    pub ids: &'a mut [CylinderId],
    /// Tiling offsets.
    pub offsets: &'a mut [u32],
    /// Start indices.
    pub start: &'a mut [[[u32; 2]; 2]],
}

/// A buffer given to [`BordersRef::rebuild_into`] is too short.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct BufferTooSmall {
    /// Which buffer: `"angles"`, `"ids"`, `"offsets"` or `"start"`.
    pub buffer: &'static str,
    /// How many elements it needs.
    pub needed: usize,
    /// How many it has.
    pub len: usize,
}

impl core::fmt::Display for BufferTooSmall {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "buffer `{}` holds {} elements, {} needed",
            self.buffer, self.len, self.needed
        )
    }
}

impl core::error::Error for BufferTooSmall {}

/// Index of a (chain, side, layer) tiling (and of the randomized construction's border
/// index): 12 slots per object.
pub(super) fn slot(chain: Chain, side: Side, layer: Layer) -> usize {
    let bound = match chain.bound {
        crate::line_space::Bound::Lower => 0,
        crate::line_space::Bound::Upper => 1,
    };
    let side = match side {
        Side::Below => 0,
        Side::Above => 1,
    };
    let layer = match layer {
        Layer::Around => 0,
        Layer::Before => 1,
        Layer::After => 2,
    };
    ((chain.object.0 as usize * 2 + bound) * 2 + side) * 3 + layer
}

/// The tiling slots a cylinder appears in: below its top arc, above its bottom arc.
fn tiling_slots(c: &Cylinder) -> [Option<usize>; 2] {
    [(c.top, Side::Below), (c.bottom, Side::Above)]
        .map(|(chain, side)| chain.map(|ch| slot(ch, side, Layer::of(c, ch))))
}

/// Builds the derived state in growable storage (construction and `alloc` loading).
#[cfg(feature = "alloc")]
pub(crate) fn build(scene: &SceneRef<'_>, complex: &Complex) -> Borders {
    let sizes = BorderSizes::exact(scene.len(), complex.vertices.len(), &complex.cylinders);
    let mut b = Borders {
        angles: alloc::vec![Angle::ZERO; sizes.angles],
        ids: alloc::vec![CylinderId::ZERO; sizes.ids],
        offsets: alloc::vec![0; sizes.offsets],
        start: alloc::vec![[[0; 2]; 2]; sizes.start],
        arcs: Vec::new(),
    };
    let buffers = BorderBuffers {
        angles: &mut b.angles,
        ids: &mut b.ids,
        offsets: &mut b.offsets,
        start: &mut b.start,
    };
    // The buffers have the exact sizes, so this cannot fail; an empty state only makes
    // walks report `Corrupt`.
    let used = BordersRef::rebuild_into(scene, &complex.vertices, &complex.cylinders, buffers)
        .map(|r| r.ids.len())
        .unwrap_or(0);
    b.ids.truncate(used);
    b
}

/// The derived state written as the rotational sweep numbers the cylinders (the replay's
/// order: by left wall), instead of [`build`]'s sort and merge afterwards: a cylinder's
/// place in each of its tilings is the count of that tiling so far, and once every
/// cylinder up to its left wall is counted, its start index on each far side is the last
/// cylinder counted there (the cylinder containing its left wall). Equal to [`build`] on
/// the same complex (tested); [`build`] stays the state of every loaded complex.
#[cfg(feature = "alloc")]
pub(crate) struct SweepBorders {
    objects: usize,
    /// `counts[s + 1]`: cylinders in slot `s` so far (12 tiling slots per object, then the
    /// two of the θ = 0 index); the prefix sums become the offsets.
    counts: Vec<u32>,
    /// Per cylinder: its two tiling slots (`u32::MAX`: none) and its place in each.
    places: Vec<[(u32, u32); 2]>,
    start: Vec<[[u32; 2]; 2]>,
}

#[cfg(feature = "alloc")]
impl SweepBorders {
    pub(crate) fn new(objects: usize) -> SweepBorders {
        SweepBorders {
            objects,
            counts: alloc::vec![0; 12 * objects + 3],
            places: Vec::new(),
            start: Vec::new(),
        }
    }

    /// Counts the next cylinders, all with one left wall, later than every one counted
    /// before (ids in order), and sets their start indices.
    pub(crate) fn add(&mut self, group: &[Cylinder]) {
        let tilings = 12 * self.objects;
        for c in group {
            let mut places = [(u32::MAX, 0); 2];
            // Below its top arc, above its bottom arc (`tiling_slots`).
            for (place, (chain, side)) in places
                .iter_mut()
                .zip([(c.top, Side::Below), (c.bottom, Side::Above)])
            {
                let Some(chain) = chain else { continue };
                let s = slot(chain, side, Layer::of(c, chain));
                if s >= tilings {
                    continue;
                }
                if let Some(n) = self.counts.get_mut(s + 1) {
                    *place = (s as u32, *n);
                    *n += 1;
                }
            }
            if c.left == Wall::Zero {
                for s in [tilings, tilings + 1] {
                    if let Some(n) = self.counts.get_mut(s + 1) {
                        *n += 1;
                    }
                }
            }
            self.places.push(places);
        }
        for c in group {
            let start = far_starts(c, self.objects, &self.counts);
            self.start.push(start);
        }
    }

    /// The derived state of the complex with these vertices (sorted by θ) and cylinders
    /// (every one added).
    pub(crate) fn finish(
        self,
        scene: &SceneRef<'_>,
        vertices: &[Vertex],
        cylinders: &[Cylinder],
    ) -> Borders {
        let SweepBorders {
            objects,
            counts: mut offsets,
            places,
            start,
        } = self;
        let mut sum = 0u32;
        for o in offsets.iter_mut() {
            sum = sum.saturating_add(*o);
            *o = sum;
        }
        let mut ids = alloc::vec![CylinderId::ZERO; sum as usize];
        let zero = 12 * objects;
        // Places in the θ = 0 index: the cylinders at θ = 0 in id order.
        let mut at_zero = 0u32;
        for (i, (places, c)) in places.iter().zip(cylinders).enumerate() {
            let Some(id) = CylinderId::from_index(i) else {
                break;
            };
            let mut index = [(u32::MAX, 0); 2];
            if c.left == Wall::Zero {
                index = [(zero as u32, at_zero), (zero as u32 + 1, at_zero)];
                at_zero += 1;
            }
            for (s, k) in places.iter().chain(&index) {
                let at = offsets.get(*s as usize).map(|&o| o as usize + *k as usize);
                if let Some(slot) = at.and_then(|a| ids.get_mut(a)) {
                    *slot = id;
                }
            }
        }
        let (head, tail) = ids.split_at_mut(range(&offsets, zero + 1).map_or(0, |r| r.start));
        if let (Some(sorted), Some(maxima)) = (
            range(&offsets, zero).and_then(|r| head.get_mut(r)),
            range(&offsets, zero + 1).and_then(|r| tail.get_mut(..r.len())),
        ) {
            ZeroIndex::build(scene, cylinders, sorted, maxima);
        }
        Borders {
            angles: vertices.iter().map(|v| v.bitangent.angle(scene)).collect(),
            ids,
            offsets,
            start,
            arcs: Vec::new(),
        }
    }
}

#[cfg(all(test, feature = "alloc"))]
impl Borders {
    /// Whether both states are the same (angles by their exact comparison).
    pub(crate) fn same_as(&self, other: &Borders) -> bool {
        self.ids == other.ids
            && self.offsets == other.offsets
            && self.start == other.start
            && self.arcs == other.arcs
            && self.angles.len() == other.angles.len()
            && (self.angles.iter().zip(&other.angles))
                .all(|(a, b)| a.cmp_angle(b) == Ordering::Equal)
    }
}

#[cfg(feature = "alloc")]
impl Borders {
    /// Keeps the arc vertices of `complex` (this state's complex): see
    /// [`Complex::with_arc_vertices`].
    pub(crate) fn keep_arc_vertices(&mut self, scene: &SceneRef<'_>, complex: &Complex) {
        self.arcs = arc_vertices(scene, complex, &self.angles);
    }
}

/// The arc vertices of every cylinder (see [`BordersRef`]), from the walls' angles
/// (`angles`, or computed where empty). Vertices whose bitangent touches the arc's chain
/// give its tangent vertex at that wall directly.
#[cfg(feature = "alloc")]
fn arc_vertices(scene: &SceneRef<'_>, complex: &Complex, angles: &[Angle]) -> Vec<[u32; 2]> {
    let wall = |w: Wall| match w {
        Wall::Zero => Some((Angle::ZERO, None)),
        Wall::Vertex(v) => {
            let b = complex.vertices.get(v.index())?.bitangent;
            let angle = angles
                .get(v.index())
                .copied()
                .unwrap_or_else(|| b.angle(scene));
            Some((angle, Some(b)))
        }
    };
    let on = |b: Option<crate::line_space::Bitangent>, chain: Chain| {
        let b = b?;
        if (b.first_object, b.first_bound) == (chain.object, chain.bound) {
            Some(b.first)
        } else if (b.second_object, b.second_bound) == (chain.object, chain.bound) {
            Some(b.second)
        } else {
            None
        }
    };
    complex
        .cylinders
        .iter()
        .map(|c| {
            let ends = (wall(c.left), wall(c.right));
            let mut out = [NO_ARC_VERTEX; 2];
            let (Some((l, lb)), Some((r, rb))) = ends else {
                return out;
            };
            // A cylinder round the whole circle has no single vertex on any arc.
            if c.left == Wall::Zero && c.right == Wall::Zero {
                return out;
            }
            for (slot, chain) in out.iter_mut().zip([c.bottom, c.top]) {
                let Some(chain) = chain.filter(|ch| scene.object(ch.object).is_some()) else {
                    continue;
                };
                let v = crate::line_space::arc_vertex(
                    scene,
                    chain,
                    (&l, on(lb, chain)),
                    (&r, on(rb, chain)),
                    c.right == Wall::Zero,
                );
                if let Some(v) = v.and_then(|v| u32::try_from(v).ok()) {
                    *slot = v;
                }
            }
            out
        })
        .collect()
}

impl<'a> BordersRef<'a> {
    /// Rebuilds the derived state of the complex with these vertices and cylinders into
    /// the caller's buffers, without allocating: a counting sort of the cylinders into
    /// their tilings, a `sort_unstable` of each tiling by left wall, and one merge per
    /// chain for the start indices. Time O(C log C), no heap.
    ///
    /// The vertices must be sorted by θ (as every constructed or validated complex is); ids
    /// out of range are skipped, so a corrupt complex makes walks fail, never panic.
    pub fn rebuild_into(
        scene: &SceneRef<'_>,
        vertices: &[Vertex],
        cylinders: &[Cylinder],
        buffers: BorderBuffers<'a>,
    ) -> Result<BordersRef<'a>, BufferTooSmall> {
        let need = BorderSizes::exact(scene.len(), vertices.len(), cylinders);
        let check = |buffer, len: usize, needed: usize| {
            if len < needed {
                Err(BufferTooSmall {
                    buffer,
                    needed,
                    len,
                })
            } else {
                Ok(())
            }
        };
        if !buffers.angles.is_empty() {
            check("angles", buffers.angles.len(), need.angles)?;
        }
        check("ids", buffers.ids.len(), need.ids)?;
        check("offsets", buffers.offsets.len(), need.offsets)?;
        check("start", buffers.start.len(), need.start)?;
        let BorderBuffers {
            angles,
            ids,
            offsets,
            start,
        } = buffers;
        let angles = match angles.get_mut(..need.angles) {
            Some(a) if !a.is_empty() => a,
            _ => &mut [],
        };
        for (a, v) in angles.iter_mut().zip(vertices) {
            *a = v.bitangent.angle(scene);
        }
        let (ids, offsets, start) = match (
            ids.get_mut(..need.ids),
            offsets.get_mut(..need.offsets),
            start.get_mut(..need.start),
        ) {
            (Some(i), Some(o), Some(s)) => (i, o, s),
            _ => {
                return Err(BufferTooSmall {
                    buffer: "ids",
                    needed: need.ids,
                    len: 0,
                })
            }
        };

        // Counting sort into the tilings: count per slot, prefix sums, place (the offsets
        // serve as cursors and end up shifted by one slot), shift back. The two slots of
        // the θ = 0 index follow the tilings. Slots past the last object's (corrupt ids)
        // are skipped.
        // Each cylinder's (at most four) slots are computed once, kept in its `start` entry
        // (free until the merge below) between the two passes.
        let tilings = 12 * scene.len();
        let zero_slot = tilings;
        offsets.fill(0);
        for (c, kept) in cylinders.iter().zip(start.iter_mut()) {
            // A cylinder at θ = 0 goes in both slots of the index (the second one's
            // contents are replaced by the tree maxima).
            let zero = c.left == Wall::Zero;
            let [top, bottom] = tiling_slots(c).map(|s| s.filter(|&s| s < tilings));
            let slots = [
                top,
                bottom,
                zero.then_some(zero_slot),
                zero.then_some(zero_slot + 1),
            ];
            // At most four slots, into the four entries (unused ones `u32::MAX`).
            let mut entries = [u32::MAX; 4];
            for (s, k) in slots.into_iter().flatten().zip(entries.iter_mut()) {
                if let Some(n) = offsets.get_mut(s + 1) {
                    *n += 1;
                }
                *k = s as u32;
            }
            kept.as_flattened_mut().copy_from_slice(&entries);
        }
        let mut sum = 0u32;
        for o in offsets.iter_mut() {
            sum = sum.saturating_add(*o);
            *o = sum;
        }
        for (i, kept) in start.iter().enumerate() {
            let Some(id) = CylinderId::from_index(i) else {
                break;
            };
            for s in kept.as_flattened().iter().take_while(|&&s| s != u32::MAX) {
                if let Some(cursor) = offsets.get_mut(*s as usize) {
                    if let Some(slot) = ids.get_mut(*cursor as usize) {
                        *slot = id;
                    }
                    *cursor += 1;
                }
            }
        }
        offsets.copy_within(..offsets.len().saturating_sub(1), 1);
        if let Some(o) = offsets.first_mut() {
            *o = 0;
        }

        // Vertices are sorted by θ (an invariant `validate` checks), so a wall's position in
        // θ is its vertex index, θ = 0 first: sorting and merging compare integers.
        let left = |id: &CylinderId| cylinders.get(id.index()).map_or(0, |c| wall_rank(c.left));
        // Cylinders numbered in left-wall order (the replay's numbering: θ = 0 first, then
        // three per vertex in θ order) were placed into every tiling already sorted.
        if !cylinders.is_sorted_by_key(|c| wall_rank(c.left)) {
            for k in 0..tilings {
                if let Some(list) = range(offsets, k).and_then(|r| ids.get_mut(r)) {
                    list.sort_unstable_by_key(left);
                }
            }
        }
        let (zero, maxima) = match (range(offsets, zero_slot), range(offsets, zero_slot + 1)) {
            (Some(z), Some(m)) => {
                let (head, tail) = ids.split_at_mut(m.start);
                (head.get_mut(z), tail.get_mut(..m.len()))
            }
            _ => (None, None),
        };
        if let (Some(zero), Some(maxima)) = (zero, maxima) {
            ZeroIndex::build(scene, cylinders, zero, maxima);
        }
        let ids: &'a [CylinderId] = ids;
        let offsets: &'a [u32] = offsets;
        let tiling = |k: usize| range(offsets, k).and_then(|r| ids.get(r)).unwrap_or(&[]);

        start.fill([[0; 2]; 2]);
        // For every chain, merge each tiling with the tilings across the chain: both are
        // sorted by left wall, so one pass finds, for every cylinder, the far cylinder
        // containing its left wall.
        for object in 0..scene.len() {
            for bound in [
                crate::line_space::Bound::Lower,
                crate::line_space::Bound::Upper,
            ] {
                let chain = Chain {
                    object: crate::scene::ObjectId(object as u32),
                    bound,
                };
                // Cylinders above the chain leave it through their bottom (arc 0) to the
                // side below, and conversely.
                for (own_side, arc, far_side) in
                    [(Side::Above, 0, Side::Below), (Side::Below, 1, Side::Above)]
                {
                    for own_layer in far_layers(chain, own_side) {
                        let own = tiling(slot(chain, own_side, own_layer));
                        for (l, far_layer) in far_layers(chain, far_side).into_iter().enumerate() {
                            let far = tiling(slot(chain, far_side, far_layer));
                            let mut j = 0;
                            for id in own {
                                let l_own = left(id);
                                while far.get(j + 1).is_some_and(|f| left(f) <= l_own) {
                                    j += 1;
                                }
                                if let Some(e) = start
                                    .get_mut(id.index())
                                    .and_then(|e| e.get_mut(arc))
                                    .and_then(|e| e.get_mut(l))
                                {
                                    *e = j as u32;
                                }
                            }
                        }
                    }
                }
            }
        }
        Ok(BordersRef {
            angles,
            ids,
            offsets,
            start,
            arcs: &[],
        })
    }

    /// The same state without the arc vertices (walks then take every candidate exit from
    /// the tangents), to check that both walk alike.
    #[cfg(all(test, feature = "alloc"))]
    pub(crate) fn without_arcs(self) -> BordersRef<'a> {
        BordersRef { arcs: &[], ..self }
    }

    /// Whether the arc vertices are kept.
    #[cfg(all(test, feature = "alloc"))]
    pub(crate) fn has_arcs(&self) -> bool {
        !self.arcs.is_empty()
    }

    /// The vertices of the bottom and top arcs of cylinder `c` (see the type), if kept.
    #[inline(always)]
    pub(crate) fn arcs(&self, c: CylinderId) -> [u32; 2] {
        self.arcs
            .get(c.index())
            .copied()
            .unwrap_or([NO_ARC_VERTEX; 2])
    }

    /// The angle of vertex `v`, if stored.
    pub(crate) fn angle(&self, v: usize) -> Option<&'a Angle> {
        self.angles.get(v)
    }

    /// The cylinders bordering `chain` on `side` in `layer`, sorted by θ. Inlined: a view
    /// looks up a tiling at every chain crossing.
    #[inline]
    fn tiling(&self, chain: Chain, side: Side, layer: Layer) -> Option<&'a [CylinderId]> {
        range(self.offsets, slot(chain, side, layer)).and_then(|r| self.ids.get(r))
    }

    /// Bytes of the borrowed buffers.
    pub fn bytes(&self) -> usize {
        core::mem::size_of_val(self.angles)
            + core::mem::size_of_val(self.ids)
            + core::mem::size_of_val(self.offsets)
            + core::mem::size_of_val(self.start)
            + core::mem::size_of_val(self.arcs)
    }
}

/// Heapsort of `ids` by `key`, for the θ = 0 index: in place, no heap, O(k log k), and a
/// few hundred bytes of a device's flash where another instantiation of the standard
/// library's sort costs kilobytes.
fn sort_by_key(ids: &mut [CylinderId], key: &dyn Fn(&CylinderId) -> i64) {
    // Moves the element at `root` down the max-heap `ids[..end]` (`root` at least doubles
    // per round).
    let sift = |ids: &mut [CylinderId], mut root: usize, end: usize| {
        let k = |ids: &[CylinderId], i: usize| ids.get(i).map(key);
        while 2 * root + 1 < end {
            let mut child = 2 * root + 1;
            if child + 1 < end && k(ids, child + 1) > k(ids, child) {
                child += 1;
            }
            if k(ids, child) <= k(ids, root) {
                return;
            }
            ids.swap(root, child);
            root = child;
        }
    };
    for root in (0..ids.len() / 2).rev() {
        sift(ids, root, ids.len());
    }
    for end in (1..ids.len()).rev() {
        ids.swap(0, end);
        sift(ids, 0, end);
    }
}

/// The id range of tiling `k`.
#[inline]
fn range(offsets: &[u32], k: usize) -> Option<core::ops::Range<usize>> {
    let a = *offsets.get(k)? as usize;
    let b = *offsets.get(k + 1)? as usize;
    (a <= b).then_some(a..b)
}

/// The position of a wall in θ order: θ = 0 first, then by vertex (vertices are sorted).
fn wall_rank(w: Wall) -> usize {
    match w {
        Wall::Zero => 0,
        Wall::Vertex(v) => v.index() + 1,
    }
}

/// The position of a right wall in θ order: by vertex, θ = 0 (here 2π) last.
fn right_rank(w: Wall) -> usize {
    match w {
        Wall::Zero => usize::MAX,
        Wall::Vertex(v) => v.index(),
    }
}

/// The start indices of cylinder `c` (see [`BordersRef`]) from the counts of the tilings
/// of a scene of `objects` objects (`counts[s + 1]`: tiling `s`) once every cylinder with a
/// left wall up to `c`'s is counted, in left-wall order: on each far side, the last one
/// counted (0 where none, or where `c` is in no tiling of that arc, as the merge of
/// [`BordersRef::rebuild_into`] leaves them).
#[cfg(feature = "alloc")]
fn far_starts(c: &Cylinder, objects: usize, counts: &[u32]) -> [[u32; 2]; 2] {
    let mut out = [[0; 2]; 2];
    let count = |s: usize| counts.get(s + 1).map_or(0, |n| n.saturating_sub(1));
    for (entry, (chain, own_side, far_side)) in out.iter_mut().zip([
        (c.bottom, Side::Above, Side::Below),
        (c.top, Side::Below, Side::Above),
    ]) {
        let Some(chain) = chain else { continue };
        if chain.object.0 as usize >= objects {
            continue;
        }
        // `c` is in its own side's tiling (else the merge leaves it at 0); the far side has
        // the layers before and after the object where it is crossed, else the one around.
        *entry = match far_layer_index(chain, own_side, Layer::of(c, chain)) {
            None => continue,
            Some(_) if far_layer_index(chain, far_side, Layer::Around).is_some() => {
                [count(slot(chain, far_side, Layer::Around)), 0]
            }
            Some(_) => [
                count(slot(chain, far_side, Layer::Before)),
                count(slot(chain, far_side, Layer::After)),
            ],
        };
    }
    out
}

/// The position of `layer` in [`far_layers`]`(chain, side)` (`None`: not one of them),
/// without building the list.
#[inline]
fn far_layer_index(chain: Chain, side: Side, layer: Layer) -> Option<usize> {
    let crossed = match chain.bound {
        crate::line_space::Bound::Lower => Side::Above,
        crate::line_space::Bound::Upper => Side::Below,
    };
    match (side == crossed, layer) {
        (true, Layer::Before) | (false, Layer::Around) => Some(0),
        (true, Layer::After) => Some(1),
        _ => None,
    }
}

/// The layers on side `side` of `chain`: two (before and after the object) where the
/// object is crossed, one otherwise.
fn far_layers(chain: Chain, side: Side) -> heapless::Vec<Layer, 2> {
    let crossed = match chain.bound {
        crate::line_space::Bound::Lower => Side::Above,
        crate::line_space::Bound::Upper => Side::Below,
    };
    let mut out = heapless::Vec::new();
    if side == crossed {
        let _ = out.push(Layer::Before);
        let _ = out.push(Layer::After);
    } else {
        let _ = out.push(Layer::Around);
    }
    out
}

impl<S: Storage> super::Complex<S> {
    /// Leaving cylinder `from` across its bottom (`side` = `Below`) or top (`Above`) arc at
    /// `angle` (strictly within `from`'s θ-range), the cylinder entered in `layer`. Looks
    /// near the position of `from` along the chain instead of searching the whole chain:
    /// the cylinders on both sides of a chain are sorted by θ, and the one entered overlaps
    /// `from`, so the scan is short.
    pub fn across_from(
        &self,
        scene: &SceneRef<'_>,
        from: CylinderId,
        side: Side,
        layer: Layer,
        angle: &Angle,
    ) -> Option<CylinderId> {
        self.across_from_keyed(scene, from, side, layer, &angle.keyed())
    }

    /// [`Complex::across_from`] with the angle's comparison key computed once (the walk
    /// has it already).
    #[inline(always)]
    pub(crate) fn across_from_keyed(
        &self,
        scene: &SceneRef<'_>,
        from: CylinderId,
        side: Side,
        layer: Layer,
        angle: &KeyedAngle,
    ) -> Option<CylinderId> {
        self.across_from_cylinder(scene, from, self.cylinder(from)?, side, layer, angle)
    }

    /// [`Complex::across_from_keyed`] with the cylinder `from` at hand as `c` (a walk has
    /// read it already).
    #[inline(always)]
    pub(crate) fn across_from_cylinder(
        &self,
        scene: &SceneRef<'_>,
        from: CylinderId,
        c: &Cylinder,
        side: Side,
        layer: Layer,
        angle: &KeyedAngle,
    ) -> Option<CylinderId> {
        let (chain, arc) = match side {
            Side::Below => (c.bottom?, 0),
            Side::Above => (c.top?, 1),
        };
        let l = far_layer_index(chain, side, layer)?;
        let borders = self.borders_ref();
        let list = borders.tiling(chain, side, layer)?;
        let first = *borders.start.get(from.index())?.get(arc)?.get(l)? as usize;
        // `angle` lies strictly inside `c`'s θ-range, so before every wall at or after its
        // right wall and after every wall at or before its left wall: walls are ordered by
        // vertex index (vertices are sorted by θ), so a far cylinder is accepted or passed
        // over by index, without reading its wall's angle, unless its right wall lies
        // strictly between `c`'s walls.
        let c_right = right_rank(c.right);
        let c_left = wall_rank(c.left);
        // The far cylinders overlapping `from` follow each other from `first`.
        for id in list.iter().skip(first) {
            let f = self.cylinder(*id)?;
            let before_right = match f.right {
                Wall::Zero => true,
                w if right_rank(w) >= c_right => true,
                w if wall_rank(w) <= c_left => false,
                // The stored angle by reference, from the `BordersRef` at hand.
                Wall::Vertex(v) => match borders.angle(v.index()) {
                    Some(a) => angle.cmp_angle(a) == Ordering::Less,
                    None => angle.cmp_angle(&self.wall_angle(scene, f.right)?) == Ordering::Less,
                },
            };
            if before_right {
                // A pruned complex's tiling may lack the cylinder entered: the next one
                // kept would start after `angle` (a climb of an anchored walk's start
                // leaving the kept sheet, `partition::region`), so its left wall is checked.
                let inside = self.region.is_none()
                    || self.cmp_wall(&borders, scene, f.left, angle) == Some(Ordering::Greater);
                return inside.then_some(*id);
            }
        }
        None
    }

    /// The cylinder bordering `chain` on `side` in `layer` whose θ-range contains `angle`.
    pub fn across(
        &self,
        scene: &SceneRef<'_>,
        chain: Chain,
        side: Side,
        layer: Layer,
        angle: &Angle,
    ) -> Option<CylinderId> {
        self.across_keyed(scene, chain, side, layer, &angle.keyed())
    }

    /// `angle` against the wall `w`: `Greater` past it (θ = 0 lies before all), the wall's
    /// angle read by reference from `borders` where stored. Always inlined: a tiling search
    /// compares at every step.
    #[inline(always)]
    fn cmp_wall(
        &self,
        borders: &BordersRef<'_>,
        scene: &SceneRef<'_>,
        w: Wall,
        angle: &KeyedAngle,
    ) -> Option<Ordering> {
        match w {
            Wall::Zero => Some(Ordering::Greater),
            Wall::Vertex(v) => match borders.angle(v.index()) {
                Some(a) => Some(angle.cmp_angle(a)),
                None => Some(angle.cmp_angle(&self.wall_angle(scene, w)?)),
            },
        }
    }

    /// [`Complex::across`] with the angle's comparison key computed once and the walls'
    /// stored angles read by reference (an anchored walk's start climbs from here).
    pub(crate) fn across_keyed(
        &self,
        scene: &SceneRef<'_>,
        chain: Chain,
        side: Side,
        layer: Layer,
        angle: &KeyedAngle,
    ) -> Option<CylinderId> {
        let borders = self.borders_ref();
        let list = borders.tiling(chain, side, layer)?;
        let cylinders = self.cylinders();
        // The number of cylinders whose left wall `angle` is past (a prefix: the tiling is
        // sorted by θ), by bisection; `len` at least halves per round.
        let (mut k, mut len) = (0, list.len());
        while len > 0 {
            let half = len / 2;
            let past = match list.get(k + half).and_then(|id| cylinders.get(id.index())) {
                Some(c) => self.cmp_wall(&borders, scene, c.left, angle) == Some(Ordering::Greater),
                None => false,
            };
            if past {
                k += half + 1;
                len -= half + 1;
            } else {
                len = half;
            }
        }
        let id = *list.get(k.checked_sub(1)?)?;
        let c = cylinders.get(id.index())?;
        let inside = match c.right {
            Wall::Zero => true,
            w => self.cmp_wall(&borders, scene, w, angle) == Some(Ordering::Less),
        };
        inside.then_some(id)
    }
}

/// The index of the cross-section at θ = 0, where every view starts (the walk's start
/// cylinder is the one containing the horizontal line through the viewpoint, in its
/// layer). At θ = 0 a cylinder spans the offsets (here: heights `y`) from its bottom
/// arc's chain to its top arc's — a chain's point at θ = 0 is its object's lowest (lower
/// chain) or highest (upper chain) vertex, so its height is an exact integer from the
/// bounding box. The cylinders at θ = 0 are kept sorted by bottom height, with an
/// implicit interval tree over that order (Li's cgranges layout: the in-order array is
/// the tree; node `i` of level `k`, `k` the trailing ones of `i`, spans `i ± (2ᵏ − 1)`)
/// holding per node the cylinder of greatest top height in its subtree. A stabbing query
/// visits the cylinders whose closed height range contains a height in
/// O(log Z + stabbed · log Z) instead of scanning all `Z = 3 · objects + 1`.
struct ZeroIndex<'a, 's> {
    scene: SceneRef<'s>,
    cylinders: &'a [Cylinder],
    /// The cylinders at θ = 0 sorted by bottom height.
    sorted: &'a [CylinderId],
    /// Per node of the tree, the cylinder of greatest top height in its subtree.
    maxima: &'a [CylinderId],
}

/// The height of a chain's point at θ = 0 (`None`: an object id out of range).
pub(crate) fn zero_height(scene: &SceneRef<'_>, chain: Chain) -> Option<i64> {
    let (lo, hi) = scene.object(chain.object)?.bbox();
    let p = match chain.bound {
        crate::line_space::Bound::Lower => lo,
        crate::line_space::Bound::Upper => hi,
    };
    Some(p.to_query().y())
}

/// A cylinder's closed height range at θ = 0; unbounded (or corrupt) arcs give the
/// extremes, so it is never too short.
#[inline]
fn zero_span(scene: &SceneRef<'_>, c: &Cylinder) -> (i64, i64) {
    (
        c.bottom
            .and_then(|b| zero_height(scene, b))
            .unwrap_or(i64::MIN),
        zero_top(scene, c),
    )
}

/// The top of [`zero_span`] alone.
#[inline]
fn zero_top(scene: &SceneRef<'_>, c: &Cylinder) -> i64 {
    c.top
        .and_then(|t| zero_height(scene, t))
        .unwrap_or(i64::MAX)
}

/// Levels of the implicit tree over `len` nodes: the root is node `2^levels - 1`.
fn zero_levels(len: usize) -> u32 {
    let mut k = 0;
    while k < 40 && (1usize << (k + 1)) - 1 < len {
        k += 1;
    }
    k
}

impl<'a, 's> ZeroIndex<'a, 's> {
    /// The closed height range of cylinder `id` at θ = 0.
    #[inline]
    fn span(&self, id: CylinderId) -> (i64, i64) {
        self.cylinders
            .get(id.index())
            .map_or((i64::MIN, i64::MAX), |c| zero_span(&self.scene, c))
    }

    /// The top of [`ZeroIndex::span`] alone (a stab reads the subtrees' maxima's tops).
    #[inline]
    fn top(&self, id: CylinderId) -> i64 {
        self.cylinders
            .get(id.index())
            .map_or(i64::MAX, |c| zero_top(&self.scene, c))
    }

    /// Sorts `sorted` by bottom height and fills `maxima`, bottom-up.
    fn build(
        scene: &SceneRef<'_>,
        cylinders: &[Cylinder],
        sorted: &mut [CylinderId],
        maxima: &mut [CylinderId],
    ) {
        sort_by_key(sorted, &|id| {
            cylinders
                .get(id.index())
                .map_or(i64::MIN, |c| zero_span(scene, c).0)
        });
        maxima.copy_from_slice(sorted);
        let levels = zero_levels(sorted.len());
        for level in 1..=levels {
            let half = 1usize << (level - 1);
            // Nodes of this level: i ≡ 2^level − 1 (mod 2^(level + 1)).
            let mut i = (1usize << level) - 1;
            while i < maxima.len() {
                let index = ZeroIndex {
                    scene: *scene,
                    cylinders,
                    sorted,
                    maxima,
                };
                let mut best = maxima.get(i).copied();
                for child in [i - half, i + half] {
                    let Some(m) = index.subtree_argmax(child, level - 1) else {
                        continue;
                    };
                    if best.is_none_or(|b| index.span(m).1 > index.span(b).1) {
                        best = Some(m);
                    }
                }
                if let (Some(slot), Some(b)) = (maxima.get_mut(i), best) {
                    *slot = b;
                }
                i += 1 << (level + 1);
            }
        }
    }

    /// The cylinder of greatest top height in the subtree of node `i` at `level` (a node
    /// past the end holds its left subtree's real nodes), or `None` for an empty subtree.
    fn subtree_argmax(&self, mut i: usize, mut level: u32) -> Option<CylinderId> {
        loop {
            if let Some(id) = self.maxima.get(i) {
                return Some(*id);
            }
            if level == 0 {
                return None;
            }
            level -= 1;
            i = i.checked_sub(1 << level)?;
        }
    }

    /// Calls `visit` for every cylinder whose closed height range contains `y`; stops
    /// early when `visit` returns `true`. Returns `false` if the traversal was cut short
    /// by its fixed stack (never for a well-formed tree: the stack holds one pending
    /// sibling per level).
    fn stab(&self, y: i64, visit: &mut impl FnMut(CylinderId, &'a Cylinder) -> bool) -> bool {
        let levels = zero_levels(self.sorted.len());
        let mut stack: heapless::Vec<(usize, u32), 48> = heapless::Vec::new();
        if stack.push(((1usize << levels) - 1, levels)).is_err() {
            return false;
        }
        while let Some((i, level)) = stack.pop() {
            if self
                .subtree_argmax(i, level)
                .is_none_or(|m| self.top(m) < y)
            {
                continue;
            }
            let node = self.sorted.get(i).copied();
            let span = node.map(|id| self.span(id));
            if let (Some(id), Some((lo, hi))) = (node, span) {
                if lo <= y && y <= hi {
                    if let Some(c) = self.cylinders.get(id.index()) {
                        if visit(id, c) {
                            return true;
                        }
                    }
                }
            }
            if level == 0 {
                continue;
            }
            let half = 1usize << (level - 1);
            // The right subtree starts at or above this node (none past the end).
            if span.is_some_and(|(lo, _)| lo <= y) && stack.push((i + half, level - 1)).is_err() {
                return false;
            }
            if stack.push((i - half, level - 1)).is_err() {
                return false;
            }
        }
        true
    }
}

impl<S: Storage> super::Complex<S> {
    /// Calls `visit` for the cylinders at θ = 0 whose closed height range (from their arcs'
    /// chains, see `ZeroIndex`) contains `y` — a superset of those containing a
    /// horizontal line at height `y` — until it returns `true`. Returns `false` if the
    /// index could not answer (a corrupt complex): the caller then scans.
    pub(crate) fn at_zero<'s>(
        &'s self,
        scene: &SceneRef<'_>,
        y: i64,
        mut visit: impl FnMut(CylinderId, &'s Cylinder) -> bool,
    ) -> bool {
        let b = self.borders_ref();
        let k = b.offsets.len().saturating_sub(3);
        let (Some(sorted), Some(maxima)) = (
            range(b.offsets, k).and_then(|r| b.ids.get(r)),
            range(b.offsets, k + 1).and_then(|r| b.ids.get(r)),
        ) else {
            return false;
        };
        let index = ZeroIndex {
            scene: *scene,
            cylinders: self.cylinders(),
            sorted,
            maxima,
        };
        index.stab(y, &mut visit)
    }
}
