//! Randomized incremental construction of the cylindrical partition, with its history
//! (the paper's §4, `Update Cylindrical Partition`).
//!
//! Objects are inserted in a random order (seeded). Inserting N changes exactly the
//! cylinders that contain lines meeting N inside their free range — the *conflict*
//! cylinders. At a fixed θ they form a chain `I₀ … I_k` upward in u: `I₀` holds N's lower
//! tangent line, `I_k` its upper one, and N's chord lies in the gap of every `I_j` in
//! between. After the insertion that chain is replaced by
//!
//! * `I₀` below N's lower chain and `I_k` above N's upper chain (same floor and ceiling),
//! * the runs of `I_j` with the same floor `F`: cylinders `(F, N)` — the boundaries where the
//!   ceiling changed bound nothing any more and are deleted (merged), and
//! * the runs with the same ceiling `G`: cylinders `(N, G)`.
//!
//! The insertion travels along θ from 0 to 2π, moving the chain at the events: a wall of a
//! chain cylinder, or N's lower (upper) chain crossing the bottom or top arc of `I₀`
//! (`I_k`) — a new vertex of the complex, a bitangent of N. At each event the replacement
//! intervals that changed are closed and opened, so vertices blocked by N vanish by
//! themselves. Parts of an old cylinder outside the conflict region keep its geometry with
//! new walls. The result is the canonical partition (the same as [`super::build_by_sweep`]
//! for every insertion order), which the tests check after every insertion.
//!
//! **History**: every cylinder that ever existed is a node; a destroyed cylinder links to
//! the new cylinders overlapping it (search path compaction, §4.4). Point location
//! descends from the first cylinder, choosing at each node the child that contains the
//! query. Without compaction ([`BuildOptions::compaction`]) a pass over the finished
//! history puts piece nodes between the two (`History::uncompact`).
//!
//! **Storage.** Cylinders (= history nodes), vertices and links live in flat arenas
//! addressed by `u32` ids. A node is destroyed by exactly one insertion, so its children
//! are all known when that insertion ends and are stored as one contiguous range of the
//! link arena (sorted by id, which is creation order).
//!
//! **Border index.** The walk up the conflict chain asks for the live cylinder across an
//! arc at θ. Each (chain, side, layer) has one `Vec` of entries sorted by left wall
//! (addressed by a slot number, not a search tree), searched by bisection. Destroyed
//! cylinders are not removed at once: they are skipped by their alive flag and a list is
//! compacted when a quarter of it is dead. An insertion's new entries are grouped by list
//! at commit and each list is updated once (one pass of moves, not one per entry). Before
//! searching a list, the walk tries the likely answers (the old chain cylinder at that
//! index, its right neighbour, the first cylinder of the spliced tail) with a direct test
//! ([`History::is_above`]): about two thirds of its searches end there.
//!
//! **Angles.** Every vertex keeps a direction key ([`Dir`]): a monotone integer
//! pseudo-angle, then the exact angle (direction vector and perturbation). Comparing walls is one `u64` comparison,
//! an exact `i128` cross product on a tie, and the perturbed [`Angle::cmp_angle`] only for
//! exactly parallel directions. No floats anywhere.
//!
//! **Events.** Between events the chain changes only locally, so after an event it is
//! rebuilt from the first cylinder that changed and spliced back onto the unchanged rest
//! ([`History::chain_up`]); only the rebuilt middle is checked for cylinders entering or
//! leaving the conflict region. An end cylinder's first crossing with N's chain is kept
//! until the end changes or θ reaches it (θ only grows). The bitangents of N with each
//! object met are computed once per insertion, grouped by the pair of chains they join (an
//! event search reads only the group that can fit). The replacement intervals derived from the chain carry the chain
//! indices they cover, so each chain cylinder is linked to exactly the intervals over it;
//! an interval whose shape an event leaves as it was (at the same index when their
//! number stays, else at the same place from either end of its section: the ends, the
//! `(F, N)` runs, the `(N, G)` runs) keeps its cylinder, and only the others are sorted
//! and matched by shape.
//! The order of N and an arc's object along the lines (one offset comparison per vertex
//! of N) is asked only where the layer depends on it.
//!
//! **Scratch.** The per-insertion state (the chain, the open replacement intervals, the
//! per-conflict-cylinder pieces, recorded links, the bitangents of N with its neighbours)
//! lives in [`Scratch`], a set of `Vec`s owned by the [`History`] and cleared — not freed —
//! between insertions (no `bumpalo` arena: reused `Vec`s need no `unsafe`, no reset
//! protocol and no feature), so after the first insertions the construction allocates
//! only when an arena grows. Per-conflict-cylinder state is a sparse set (one `u32` per
//! node, never cleared) instead of maps.
//!
//! **Budget.** [`BuildOptions::budget`] bounds live cylinders, history nodes and the
//! estimated arena bytes ([`History::estimated_bytes`]); exceeding any of them returns
//! [`ComplexError::CapacityExceeded`] — never an abort: the arenas also grow with
//! `try_reserve` — and rolls the failed insertion back.

use alloc::vec::Vec;
use core::cmp::Ordering;
use core::mem::size_of;

use super::borders::{slot, Layer, Side};
use super::{Complex, ComplexError, Cylinder, CylinderId, Vertex, VertexId, Wall};
use crate::geom::predicates::Direction;
use crate::geom::sos::{Angle, RankedPoint};
use crate::geom::{QueryPoint, Sign};
use crate::line_space::{
    bitangents, object_ahead_of, object_ahead_of_query, ranked, tangent_vertex, Bitangent, Bound,
    Chain,
};
use crate::scene::{ObjectId, SceneRef};

/// An angle with a monotone integer key, for fast exact comparisons.
///
/// `key` orders directions: bit 62 is the half-plane (0 for θ ∈ [0, π) under the
/// perturbation, 1 for [π, 2π)), the low 61 bits are `⌊2⁶⁰·p⌋` for the "diamond"
/// pseudo-angle `p = (s − x)/s` in the upper half and `(s + x)/s` in the lower one
/// (`s = |x| + |y|`), which grows strictly with θ inside a half from 0 to 2. Floors of a
/// strictly monotone function are monotone, so different keys decide the order exactly;
/// equal keys fall back to the exact cross product of the vectors, and exactly parallel
/// vectors to the perturbed [`Angle::cmp_angle`]. The key is never 0, which stands for the
/// wall θ = 0 in the border index. Bit 63 ([`SLOW`]) marks a key that is not valid (a
/// vector component beyond 2⁶²): then only the half-plane bit is.
///
/// The angle itself is kept next to its key (32 bytes in all): a vertex's angle is read
/// where its key was, not rebuilt from the vertex and its scene points (a cache miss at
/// large n).
#[derive(Clone, Copy, Debug)]
struct Dir {
    key: u64,
    angle: Angle,
}

/// [`Dir::key`]'s flag of an invalid key.
const SLOW: u64 = 1 << 63;

impl Dir {
    fn of(angle: &Angle) -> Dir {
        let pi = Angle::constant(Direction { x: -1, y: 0 });
        // `cmp_angle` first orders by half-plane: θ < π exactly when θ is in the upper half.
        let upper = angle.cmp_angle(&pi) == Ordering::Less;
        let half: u64 = if upper { 0 } else { 1 << 62 };
        let (x, y) = angle.vector();
        const LIMIT: u64 = 1 << 62;
        match (i64::try_from(x), i64::try_from(y)) {
            (Ok(x), Ok(y))
                if (x, y) != (0, 0) && x.unsigned_abs() <= LIMIT && y.unsigned_abs() <= LIMIT =>
            {
                // Bit budget: s ≤ 2⁶³, numerator ≤ 2s ≤ 2⁶⁴, shifted ≤ 2¹²⁴ < 2¹²⁷. The
                // numerator is ≥ 0 (|x| ≤ s): divided unsigned, which is cheaper.
                let s = x.unsigned_abs() as i128 + y.unsigned_abs() as i128;
                let num = if upper { s - x as i128 } else { s + x as i128 };
                let p = (((num as u128) << 60) / s as u128) as u64; // ≤ 2⁶¹
                Dir {
                    key: (half | p) + 1,
                    angle: *angle,
                }
            }
            _ => Dir {
                // Beyond the documented range: only the half-plane bit is used.
                key: SLOW | (half + 1),
                angle: *angle,
            },
        }
    }

    /// Whether the key is valid.
    #[inline(always)]
    fn fast(&self) -> bool {
        self.key & SLOW == 0
    }

    /// The order of [`Angle::cmp_angle`] when the integers decide it; `None` for exactly
    /// parallel vectors in the same half-plane (the perturbation decides).
    ///
    /// Bit budget of the cross product: components ≤ 2⁶² (`fast`), products ≤ 2¹²⁴:
    /// exact in `i128`.
    #[inline]
    fn cmp(&self, other: &Dir) -> Option<Ordering> {
        if !(self.fast() && other.fast()) {
            let (a, b) = ((self.key >> 62) & 1, (other.key >> 62) & 1);
            return (a != b).then(|| a.cmp(&b));
        }
        if self.key != other.key {
            return Some(self.key.cmp(&other.key));
        }
        let ((ax, ay), (bx, by)) = (self.angle.vector(), other.angle.vector());
        let c = ax * by - ay * bx;
        match c.cmp(&0) {
            Ordering::Greater => Some(Ordering::Less),
            Ordering::Less => Some(Ordering::Greater),
            Ordering::Equal => None,
        }
    }
}

/// [`Dir::cmp`] when the keys alone decide it (both valid and different), else `None`.
#[inline(always)]
fn fast_order(a: &Dir, b: &Dir) -> Option<Ordering> {
    ((a.key | b.key) & SLOW == 0 && a.key != b.key).then(|| a.key.cmp(&b.key))
}

/// Whether a candidate event direction `c` is before `best` (if any) and after θ (if
/// any), when the keys alone decide it (the inlined common case of `next_event`).
#[inline(always)]
fn fast_better(c: &Dir, best: Option<&Dir>, theta: Option<&Dir>) -> Option<bool> {
    if let Some(b) = best {
        if fast_order(c, b)? != Ordering::Less {
            return Some(false);
        }
    }
    match theta {
        Some(t) => Some(fast_order(c, t)? == Ordering::Greater),
        None => Some(true),
    }
}

/// An angle θ with its fast comparison key.
#[derive(Clone, Copy, Debug)]
struct Key {
    dir: Dir,
    /// The vertex whose angle this is, if any (equal vertices: equal angles, at once).
    vertex: Option<VertexId>,
}

impl Key {
    fn new(angle: Angle) -> Key {
        Key {
            dir: Dir::of(&angle),
            vertex: None,
        }
    }

    #[inline(always)]
    fn angle(&self) -> &Angle {
        &self.dir.angle
    }
}

/// What a query point is: a scene vertex (while inserting) or a user's query point.
#[derive(Clone, Copy, Debug)]
enum Probe {
    Vertex(RankedPoint),
    Query(QueryPoint),
}

/// The floor, ceiling and arcs of a replacement interval, packed into one integer whose
/// order is that of the tuple `(floor, ceiling, bottom, top)` (`None` first): 32 bits per
/// field, an object `o` as `o + 1`, a chain as `1 + 2·object + bound`. Object ids stay
/// below 2³⁰ ([`History::insert`] checks), so every field fits.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug, Default)]
struct Shape(u128);

/// Objects a history can hold: [`Shape`] packs ids into 32-bit fields.
const MAX_OBJECTS: usize = 1 << 30;

impl Shape {
    fn new(
        floor: Option<ObjectId>,
        ceiling: Option<ObjectId>,
        bottom: Option<Chain>,
        top: Option<Chain>,
    ) -> Shape {
        Shape::of_fields(
            Shape::object(floor),
            Shape::object(ceiling),
            Shape::chain(bottom),
            Shape::chain(top),
        )
    }

    /// The field of a floor or ceiling (injective: equal fields, equal objects).
    #[inline]
    fn object(o: Option<ObjectId>) -> u128 {
        o.map_or(0, |o| (o.0 as u128 & 0xffff_ffff) + 1)
    }

    /// The field of a bottom or top arc (injective for object ids below 2³¹).
    #[inline]
    fn chain(c: Option<Chain>) -> u128 {
        c.map_or(0, |c| {
            let bound = match c.bound {
                Bound::Lower => 0,
                Bound::Upper => 1,
            };
            1 + 2 * (c.object.0 as u128 & 0x7fff_ffff) + bound
        })
    }

    /// The shape of packed fields (as [`Shape::object`] and [`Shape::chain`] make them).
    #[inline]
    fn of_fields(floor: u128, ceiling: u128, bottom: u128, top: u128) -> Shape {
        Shape(floor << 96 | ceiling << 64 | bottom << 32 | top)
    }

    fn of(c: &Cylinder) -> Shape {
        Shape::new(c.floor, c.ceiling, c.bottom, c.top)
    }

    fn unpack(
        self,
    ) -> (
        Option<ObjectId>,
        Option<ObjectId>,
        Option<Chain>,
        Option<Chain>,
    ) {
        let field = |k: u32| ((self.0 >> (32 * k)) & 0xffff_ffff) as u32;
        let object = |v: u32| v.checked_sub(1).map(ObjectId);
        let chain = |v: u32| {
            v.checked_sub(1).map(|v| Chain {
                object: ObjectId(v / 2),
                bound: if v % 2 == 0 {
                    Bound::Lower
                } else {
                    Bound::Upper
                },
            })
        };
        (
            object(field(3)),
            object(field(2)),
            chain(field(1)),
            chain(field(0)),
        )
    }
}

/// Statistics of a construction.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct HistoryStats {
    /// History nodes: every cylinder that ever existed.
    pub nodes: usize,
    /// Links from destroyed cylinders to their replacements.
    pub links: usize,
    /// Longest path from the root to a live cylinder.
    pub depth: usize,
}

/// Limits on what a construction may allocate (DESIGN.md §4: exceeding them is an error,
/// never an abort).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Budget {
    /// Live cylinders of the partition.
    pub cylinders: usize,
    /// History nodes: every cylinder that ever existed (the cylinder arena).
    pub history_nodes: usize,
    /// Estimated bytes of the arenas, as [`History::estimated_bytes`] counts them.
    pub bytes: usize,
}

impl Budget {
    /// No limit.
    pub const UNLIMITED: Budget = Budget {
        cylinders: usize::MAX,
        history_nodes: usize::MAX,
        bytes: usize::MAX,
    };
}

/// Per-history-node bytes counted by [`History::estimated_bytes`]: the cylinder, its
/// alive flag, its child range and its sparse-set slot.
const NODE_BYTES: usize =
    size_of::<Cylinder>() + size_of::<bool>() + size_of::<(u32, u32)>() + size_of::<u32>();
/// Per-vertex bytes: the vertex and its direction key.
const VERTEX_BYTES: usize = size_of::<Vertex>() + size_of::<Dir>();
/// Per-link bytes.
const LINK_BYTES: usize = size_of::<CylinderId>();
/// Per border-index entry bytes.
const ENTRY_BYTES: usize = size_of::<Entry>();
/// An entry of the border index: a live cylinder and its left wall.
#[derive(Clone, Copy, Debug)]
struct Entry {
    /// The left wall's [`Dir::key`]; 0 for θ = 0 or when the key is not valid.
    key: u64,
    /// The left wall's vertex index; [`ZERO_WALL`] for θ = 0.
    vertex: u32,
    id: CylinderId,
}

/// [`Entry::vertex`] of the wall θ = 0 (vertex ids stay below it).
const ZERO_WALL: u32 = u32::MAX;

/// Border-index slots per object.
const SLOTS: usize = 12;

/// The partition under construction and its history.
#[derive(Clone, Debug)]
pub struct History {
    /// The node arena: every cylinder that ever existed.
    cylinders: Vec<Cylinder>,
    alive: Vec<bool>,
    /// Children of node `i`: `links[start .. start + len]` for `kids[i] = (start, len)`.
    kids: Vec<(u32, u32)>,
    links: Vec<CylinderId>,
    vertices: Vec<Vertex>,
    /// The direction of every vertex.
    dirs: Vec<Dir>,
    /// Live cylinders bordering each (chain, side, layer), sorted by left wall.
    borders: Vec<Vec<Entry>>,
    /// Entries of destroyed cylinders in each border list.
    dead: Vec<u32>,
    /// Entries in all border lists, live and dead.
    entries: usize,
    live: usize,
    order: Vec<ObjectId>,
    /// `starts[k]`: the first node created by the insertion of `order[k]` (the nodes of one
    /// insertion are consecutive).
    starts: Vec<u32>,
    budget: Option<Budget>,
    /// Whether search path compaction was applied (§4.4; [`History::is_compacted`]).
    compacted: bool,
    scratch: Scratch,
}

/// The arenas of a [`History`], what a file stores: everything else (alive flags, vertex
/// direction keys, the border index) is derived by [`History::from_parts`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HistoryParts {
    /// Every cylinder that ever existed, in creation order (node id = index).
    pub nodes: Vec<Cylinder>,
    /// Children of node `i`: `links[start .. start + len]` for `children[i] = (start, len)`.
    pub children: Vec<(u32, u32)>,
    /// The link arena.
    pub links: Vec<CylinderId>,
    /// Every vertex that ever existed (walls refer to them), in creation order.
    pub vertices: Vec<Vertex>,
    /// The insertion order.
    pub order: Vec<ObjectId>,
    /// `starts[k]`: the first node created by inserting `order[k]`.
    pub starts: Vec<u32>,
    /// Whether the history is search-path compacted (§4.4; the file header's flag).
    pub compacted: bool,
}

/// A 64-bit PCG-style generator: enough for a reproducible shuffle, no dependency.
fn shuffle(ids: &mut [ObjectId], seed: u64) {
    let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
    for i in (1..ids.len()).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let r = (state >> 33) as usize % (i + 1);
        ids.swap(i, r);
    }
}

/// Options of the randomized construction.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Seed of the random insertion order (same seed, same complex).
    pub seed: u64,
    /// Objects inserted first, in this order (the paper's screens first, §7); the rest
    /// follow in random order.
    pub first: Vec<ObjectId>,
    /// Memory budget (`None`: unlimited).
    pub budget: Option<Budget>,
    /// Search path compaction (§4.4; default `true`): link each destroyed cylinder
    /// straight to the new cylinders overlapping it. `false` records an insertion's split
    /// and merge as two steps ([`History::is_compacted`]), to measure what compaction
    /// saves; the live partition is the same.
    pub compaction: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            seed: 0,
            first: Vec::new(),
            budget: None,
            compaction: true,
        }
    }
}

impl Default for History {
    fn default() -> Self {
        History::new()
    }
}

/// The border-index entries of a cylinder: its top arc seen from below, its bottom arc
/// seen from above.
fn border_slots(c: &Cylinder) -> [Option<usize>; 2] {
    [
        c.top.map(|t| slot(t, Side::Below, Layer::of(c, t))),
        c.bottom.map(|b| slot(b, Side::Above, Layer::of(c, b))),
    ]
}

impl History {
    /// The partition of the empty scene: one cylinder, all of line space.
    pub fn new() -> History {
        let root = Cylinder {
            floor: None,
            ceiling: None,
            bottom: None,
            top: None,
            left: Wall::Zero,
            right: Wall::Zero,
            left_neighbour: Some(CylinderId::ZERO),
            right_neighbour: Some(CylinderId::ZERO),
        };
        History {
            cylinders: alloc::vec![root],
            alive: alloc::vec![true],
            kids: alloc::vec![(0, 0)],
            links: Vec::new(),
            vertices: Vec::new(),
            dirs: Vec::new(),
            borders: Vec::new(),
            dead: Vec::new(),
            entries: 0,
            live: 1,
            order: Vec::new(),
            starts: Vec::new(),
            budget: None,
            compacted: true,
            scratch: Scratch::default(),
        }
    }

    /// Builds the partition of a scene by randomized incremental construction.
    pub fn build(scene: &SceneRef<'_>, options: &BuildOptions) -> Result<History, ComplexError> {
        let mut rest: Vec<ObjectId> = (0..scene.len() as u32)
            .map(ObjectId)
            .filter(|id| !options.first.contains(id))
            .collect();
        shuffle(&mut rest, options.seed);
        let mut h = History::new();
        h.set_budget(options.budget);
        for id in options.first.iter().copied().chain(rest) {
            h.insert(scene, id)?;
        }
        if !options.compaction {
            h.uncompact()?;
        }
        Ok(h)
    }

    /// Whether the history is search-path compacted (§4.4): every destroyed cylinder
    /// links straight to the new cylinders overlapping it. Built with
    /// [`BuildOptions::compaction`] `false`, it is not: an insertion's split and merge are
    /// two steps (`History::uncompact`).
    pub fn is_compacted(&self) -> bool {
        self.compacted
    }

    /// Sets (or removes) the memory budget checked by later insertions.
    pub fn set_budget(&mut self, budget: Option<Budget>) {
        self.budget = budget;
    }

    /// The insertion order used.
    pub fn order(&self) -> &[ObjectId] {
        &self.order
    }

    /// Number of live cylinders.
    pub fn live_cylinders(&self) -> usize {
        self.live
    }

    /// The estimate of the arena bytes that [`Budget::bytes`] limits: per history node
    /// the [`Cylinder`], its alive flag, child range and sparse-set slot; 4 bytes per
    /// link; per vertex the [`Vertex`] and its direction key; per border-index entry a
    /// 16-byte entry, plus the index's per-object list headers. Not counted: the
    /// spare capacity of the `Vec`s and the per-insertion scratch (linear in the size of
    /// one insertion's conflict region).
    pub fn estimated_bytes(&self) -> usize {
        self.bytes_for(
            self.cylinders.len(),
            self.links.len(),
            self.vertices.len(),
            self.entries,
        )
    }

    fn bytes_for(&self, nodes: usize, links: usize, vertices: usize, entries: usize) -> usize {
        nodes
            .saturating_mul(NODE_BYTES)
            .saturating_add(links.saturating_mul(LINK_BYTES))
            .saturating_add(vertices.saturating_mul(VERTEX_BYTES))
            .saturating_add(entries.saturating_mul(ENTRY_BYTES))
            .saturating_add(
                self.borders
                    .len()
                    .saturating_mul(size_of::<Vec<Entry>>() + size_of::<u32>()),
            )
    }

    /// Checks the budget for the given counts.
    fn check(
        &self,
        live: usize,
        nodes: usize,
        links: usize,
        vertices: usize,
        entries: usize,
    ) -> Result<(), ComplexError> {
        let Some(b) = self.budget else { return Ok(()) };
        let bytes = self.bytes_for(nodes, links, vertices, entries);
        if live > b.cylinders || nodes > b.history_nodes || bytes > b.bytes {
            return Err(ComplexError::CapacityExceeded {
                cylinders: live,
                history_nodes: nodes,
                bytes,
            });
        }
        Ok(())
    }

    /// The children of a node.
    fn children(&self, id: CylinderId) -> &[CylinderId] {
        self.kids
            .get(id.index())
            .and_then(|&(s, l)| self.links.get(s as usize..s as usize + l as usize))
            .unwrap_or(&[])
    }

    /// Size and depth of the history.
    pub fn stats(&self) -> HistoryStats {
        // Depth by dynamic programming over nodes in creation order (children are younger).
        let mut depth = alloc::vec![0usize; self.cylinders.len()];
        let mut max = 0;
        for i in 0..self.cylinders.len() {
            let d = depth[i] + 1;
            for c in self.children(CylinderId(i as u32)) {
                if let Some(x) = depth.get_mut(c.index()) {
                    *x = (*x).max(d);
                }
            }
            if self.alive[i] {
                max = max.max(depth[i]);
            }
        }
        HistoryStats {
            nodes: self.cylinders.len(),
            links: self.links.len(),
            depth: max,
        }
    }

    /// The live partition as a complex (cylinders and vertices renumbered).
    pub fn complex(&self, scene: &SceneRef<'_>) -> Result<Complex, ComplexError> {
        const NONE: u32 = u32::MAX;
        // Live cylinders in node order, those at θ = 0 first (as the sweep creates them):
        // a walk's start scan (`Complex::walk_trace`) then stops within them.
        let mut cmap = alloc::vec![NONE; self.cylinders.len()];
        let mut count = 0usize;
        for zero in [true, false] {
            for (i, m) in cmap.iter_mut().enumerate() {
                let live = self.alive.get(i) == Some(&true);
                let at_zero = self.cylinders.get(i).is_some_and(|c| c.left == Wall::Zero);
                if live && at_zero == zero {
                    *m = u32::try_from(count)
                        .ok()
                        .filter(|&k| k != NONE)
                        .ok_or(ComplexError::TooLarge)?;
                    count += 1;
                }
            }
        }
        let mut vmap = alloc::vec![NONE; self.vertices.len()];
        let mut used: Vec<VertexId> = Vec::new();
        for (i, c) in self.cylinders.iter().enumerate() {
            if !self.alive[i] {
                continue;
            }
            for w in [c.left, c.right] {
                if let Wall::Vertex(v) = w {
                    let m = vmap.get_mut(v.index()).ok_or(ComplexError::TooLarge)?;
                    if *m == NONE {
                        *m = 0;
                        used.push(v);
                    }
                }
            }
        }
        used.sort_by(|&a, &b| self.cmp_vertices(a, b));
        let mut vertices = Vec::with_capacity(used.len());
        for (k, &v) in used.iter().enumerate() {
            vmap[v.index()] = u32::try_from(k).map_err(|_| ComplexError::TooLarge)?;
            vertices.push(self.vertices[v.index()]);
        }
        let wall = |w: Wall| match w {
            Wall::Zero => Wall::Zero,
            Wall::Vertex(v) => match vmap.get(v.index()) {
                Some(&n) if n != NONE => Wall::Vertex(VertexId(n)),
                _ => Wall::Zero,
            },
        };
        let cyl = |n: Option<CylinderId>| match n.and_then(|n| cmap.get(n.index())) {
            Some(&k) if k != NONE => Some(CylinderId(k)),
            _ => None,
        };
        let mut cylinders = alloc::vec![Cylinder::new(Shape::default(), Wall::Zero); count];
        for (i, c) in self.cylinders.iter().enumerate() {
            let Some(slot) = cmap.get(i).and_then(|&k| cylinders.get_mut(k as usize)) else {
                continue;
            };
            *slot = Cylinder {
                left: wall(c.left),
                right: wall(c.right),
                left_neighbour: cyl(c.left_neighbour),
                right_neighbour: cyl(c.right_neighbour),
                ..*c
            };
        }
        let mut complex = Complex {
            vertices,
            cylinders,
            borders: Default::default(),
            region: None,
        };
        complex.borders = super::borders::build(scene, &complex);
        Ok(complex)
    }

    /// The key of a vertex's angle.
    fn vertex_key(&self, v: VertexId) -> Option<Key> {
        Some(Key {
            dir: *self.dirs.get(v.index())?,
            vertex: Some(v),
        })
    }

    /// The order of vertex `v`'s angle against θ (`None`: no such vertex).
    #[inline(always)]
    fn cmp_vertex(&self, v: VertexId, theta: &Key) -> Option<Ordering> {
        // Different valid keys decide alone (the common case, inlined).
        if let Some(o) = self
            .dirs
            .get(v.index())
            .and_then(|d| fast_order(d, &theta.dir))
        {
            return Some(o);
        }
        self.cmp_vertex_exact(v, theta)
    }

    /// [`History::cmp_vertex`] in full.
    fn cmp_vertex_exact(&self, v: VertexId, theta: &Key) -> Option<Ordering> {
        let d = self.dirs.get(v.index())?;
        if theta.vertex == Some(v) {
            return Some(Ordering::Equal);
        }
        Some(
            d.cmp(&theta.dir)
                .unwrap_or_else(|| d.angle.cmp_angle(theta.angle())),
        )
    }

    fn cmp_vertices(&self, a: VertexId, b: VertexId) -> Ordering {
        if a == b {
            return Ordering::Equal;
        }
        match (self.dirs.get(a.index()), self.dirs.get(b.index())) {
            (Some(da), Some(db)) => da.cmp(db).unwrap_or_else(|| da.angle.cmp_angle(&db.angle)),
            _ => a.cmp(&b),
        }
    }

    /// The border-index entry of a cylinder with left wall `w`.
    #[inline]
    fn entry(&self, w: Wall, id: CylinderId) -> Entry {
        match w {
            Wall::Zero => Entry {
                key: 0,
                vertex: ZERO_WALL,
                id,
            },
            Wall::Vertex(v) => Entry {
                key: self
                    .dirs
                    .get(v.index())
                    .filter(|d| d.fast())
                    .map_or(0, |d| d.key),
                vertex: v.0,
                id,
            },
        }
    }

    /// Whether an entry's left wall lies at or before θ.
    #[inline]
    fn entry_at_or_before(&self, e: &Entry, theta: &Key) -> bool {
        // A valid key is never 0 (the key of θ = 0), so it decides alone.
        if e.key != 0 && theta.dir.fast() && e.key != theta.dir.key {
            return e.key < theta.dir.key;
        }
        if e.vertex == ZERO_WALL {
            return true;
        }
        if theta.vertex.is_some_and(|v| v.0 == e.vertex) {
            return true;
        }
        self.cmp_vertex(VertexId(e.vertex), theta)
            .is_none_or(|o| o != Ordering::Greater)
    }

    /// Order of two entries by left wall: θ = 0 first.
    #[inline]
    fn cmp_entries(&self, a: &Entry, b: &Entry) -> Ordering {
        // Valid keys decide alone (never 0, the key of θ = 0).
        if a.key != 0 && b.key != 0 && a.key != b.key {
            return a.key.cmp(&b.key);
        }
        if a.vertex == b.vertex {
            return Ordering::Equal; // the same wall
        }
        match (a.vertex == ZERO_WALL, b.vertex == ZERO_WALL) {
            (true, true) => Ordering::Equal,
            (true, false) => Ordering::Less,
            (false, true) => Ordering::Greater,
            (false, false) => self.cmp_vertices(VertexId(a.vertex), VertexId(b.vertex)),
        }
    }

    /// Whether a left wall lies at or before θ.
    #[inline]
    fn left_at_or_before(&self, w: Wall, theta: &Key) -> bool {
        match w {
            Wall::Zero => true,
            Wall::Vertex(v) => self
                .cmp_vertex(v, theta)
                .is_none_or(|o| o != Ordering::Greater),
        }
    }

    /// Whether θ⁺ (just after θ) lies in the cylinder's θ-range.
    #[inline]
    fn spans(&self, c: &Cylinder, theta: &Key) -> bool {
        self.right_after(c, theta) && self.left_at_or_before(c.left, theta)
    }

    /// Whether the cylinder's right wall lies after θ.
    #[inline]
    fn right_after(&self, c: &Cylinder, theta: &Key) -> bool {
        match c.right {
            Wall::Zero => true,
            Wall::Vertex(v) => self
                .cmp_vertex(v, theta)
                .is_none_or(|o| o == Ordering::Greater),
        }
    }

    /// Whether the cylinder's trapezoid contains the line of direction θ⁺ through the
    /// probe (whatever the layer).
    fn spans_line(&self, scene: &SceneRef<'_>, c: &Cylinder, theta: &Key, probe: Probe) -> bool {
        if !self.spans(c, theta) {
            return false;
        }
        let theta = theta.angle();
        let above = |chain: Chain| {
            let r = ranked(
                scene,
                tangent_vertex(scene, chain.object, theta, chain.bound),
            );
            match probe {
                Probe::Vertex(p) => theta.offset_cmp_after(p, r),
                Probe::Query(q) => theta.offset_cmp_query(q, r),
            }
        };
        c.bottom.is_none_or(|b| above(b) == Sign::Negative)
            && c.top.is_none_or(|t| above(t) == Sign::Positive)
    }

    /// Whether the cylinder contains the line of direction θ⁺ through the probe, in the
    /// layer of the probe.
    fn contains(&self, scene: &SceneRef<'_>, c: &Cylinder, theta: &Key, probe: Probe) -> bool {
        if !self.spans_line(scene, c, theta, probe) {
            return false;
        }
        let theta = theta.angle();
        let ahead = |o: ObjectId| match probe {
            Probe::Vertex(p) => object_ahead_of(scene, o, theta, p),
            Probe::Query(q) => object_ahead_of_query(scene, o, theta, q),
        };
        c.floor.is_none_or(|f| ahead(f) == Some(false))
            && c.ceiling.is_none_or(|g| ahead(g) == Some(true))
    }

    /// Descends the history to the live cylinder containing the probe's line at θ⁺.
    fn locate_probe(&self, scene: &SceneRef<'_>, theta: &Key, probe: Probe) -> Option<CylinderId> {
        let mut cur = CylinderId::ZERO;
        for _ in 0..self.cylinders.len() {
            if *self.alive.get(cur.index())? {
                return Some(cur);
            }
            cur = *self.children(cur).iter().find(|&&k| {
                self.cylinders
                    .get(k.index())
                    .is_some_and(|c| self.contains(scene, c, theta, probe))
            })?;
        }
        None
    }

    /// Point location through the history: the live cylinder containing the ray from the
    /// free point `q` in direction `d` (`q` must not be inside an object), as its history
    /// node id and the cylinder.
    pub fn locate(
        &self,
        scene: &SceneRef<'_>,
        q: QueryPoint,
        d: Direction,
    ) -> Option<(CylinderId, &Cylinder)> {
        let id = self.locate_probe(scene, &Key::new(Angle::constant(d)), Probe::Query(q))?;
        Some((id, self.cylinders.get(id.index())?))
    }

    /// Sheet-anchored point location (the paper's §4.2 for secondary rays): the live
    /// cylinder of the segments of the line through `q` with direction `d` that start where
    /// the line leaves object `m` — the floor is `m`. `q` may lie anywhere on the line (a
    /// virtual eye behind a mirror or inside a refractive object); the line (perturbed as
    /// for a query point) must cross `m`, otherwise `None`.
    ///
    /// The search starts at the nodes created by `m`'s insertion with floor `m` — they
    /// cover every line crossing `m` at that time — and descends keeping floor = `m`:
    /// later insertions only cut that layer, so exactly one child with floor `m` contains
    /// the line. No query depends on objects inserted before `m`. Without compaction the
    /// start may be a piece node of that insertion: it carries its one child's record, so
    /// it contains the line exactly when that child does, and the descent goes on to it.
    pub fn locate_on_sheet(
        &self,
        scene: &SceneRef<'_>,
        m: ObjectId,
        q: QueryPoint,
        d: Direction,
    ) -> Option<(CylinderId, &Cylinder)> {
        let theta = Key::new(Angle::constant(d));
        let probe = Probe::Query(q);
        // The line crosses m iff it passes strictly between m's two tangents.
        let side = |bound| {
            let r = ranked(scene, tangent_vertex(scene, m, theta.angle(), bound));
            theta.angle().offset_cmp_query(q, r)
        };
        if side(Bound::Lower) != Sign::Negative || side(Bound::Upper) != Sign::Positive {
            return None;
        }
        let k = self.order.iter().position(|&o| o == m)?;
        let first = *self.starts.get(k)? as usize;
        let end = self
            .starts
            .get(k + 1)
            .map_or(self.cylinders.len(), |&e| e as usize);
        let on_sheet = |id: CylinderId| {
            self.cylinders
                .get(id.index())
                .is_some_and(|c| c.floor == Some(m) && self.spans_line(scene, c, &theta, probe))
        };
        let mut cur = (first..end)
            .filter_map(CylinderId::from_index)
            .find(|&id| on_sheet(id))?;
        // Each step goes to a younger node: bounded by the number of nodes.
        for _ in 0..self.cylinders.len() {
            if *self.alive.get(cur.index())? {
                return Some((cur, self.cylinders.get(cur.index())?));
            }
            cur = *self.children(cur).iter().find(|&&c| on_sheet(c))?;
        }
        None
    }

    /// The arenas, to store the history (a copy).
    pub fn to_parts(&self) -> HistoryParts {
        HistoryParts {
            nodes: self.cylinders.clone(),
            children: self.kids.clone(),
            links: self.links.clone(),
            vertices: self.vertices.clone(),
            order: self.order.clone(),
            starts: self.starts.clone(),
            compacted: self.compacted,
        }
    }

    /// A history from stored arenas (e.g. decoded from a file), trusting nothing: every id
    /// is checked against the scene and the arenas, the insertion order must name distinct
    /// objects with increasing node ranges, then the derived state (alive flags = leaves,
    /// direction keys, border index) is rebuilt and [`History::validate`] runs — so
    /// `locate` and `locate_on_sheet` on the result index only in range and terminate.
    pub fn from_parts(scene: &SceneRef<'_>, parts: HistoryParts) -> Result<History, ComplexError> {
        let HistoryParts {
            nodes,
            children,
            links,
            vertices,
            order,
            starts,
            compacted,
        } = parts;
        let bad = |node: usize, what| ComplexError::History { node, what };
        if u32::try_from(nodes.len()).is_err()
            || u32::try_from(links.len()).is_err()
            || vertices.len() >= ZERO_WALL as usize
        {
            return Err(ComplexError::TooLarge);
        }
        let (objects, points) = (scene.len(), scene.vertices().len());
        let object_ok = |o: ObjectId| (o.0 as usize) < objects && o.0 as usize <= MAX_OBJECTS;
        for (i, v) in vertices.iter().enumerate() {
            let b = &v.bitangent;
            let owns = |o: ObjectId, k: usize| {
                scene.object(o).is_some_and(|ob| {
                    (ob.first_vertex()..ob.first_vertex() + ob.len()).contains(&k)
                })
            };
            if !owns(b.first_object, b.first)
                || !owns(b.second_object, b.second)
                || b.first_object == b.second_object
            {
                return Err(ComplexError::VertexOutOfRange { vertex: i });
            }
            if b.first >= points || b.second >= points {
                return Err(ComplexError::VertexOutOfRange { vertex: i });
            }
        }
        for (i, c) in nodes.iter().enumerate() {
            let wall_ok = |w: Wall| match w {
                Wall::Zero => true,
                Wall::Vertex(v) => v.index() < vertices.len(),
            };
            let link_ok = |n: Option<CylinderId>| n.is_none_or(|n| n.index() < nodes.len());
            if !wall_ok(c.left)
                || !wall_ok(c.right)
                || ![
                    c.floor,
                    c.ceiling,
                    c.bottom.map(|b| b.object),
                    c.top.map(|t| t.object),
                ]
                .into_iter()
                .flatten()
                .all(object_ok)
                || !link_ok(c.left_neighbour)
                || !link_ok(c.right_neighbour)
            {
                return Err(ComplexError::IdOutOfRange { cylinder: i });
            }
        }
        if nodes.is_empty() || children.len() != nodes.len() {
            return Err(bad(
                nodes.len(),
                "no root, or a child range per node missing",
            ));
        }
        // The order: distinct objects of the scene; node ranges increasing from 1.
        let mut seen = alloc::vec![false; objects];
        if order.len() != starts.len() {
            return Err(bad(0, "insertion order and node ranges differ in length"));
        }
        let mut previous = 0u32;
        for (&o, &start) in order.iter().zip(&starts) {
            match seen.get_mut(o.0 as usize) {
                Some(s) if !*s => *s = true,
                _ => {
                    return Err(bad(
                        start as usize,
                        "insertion order repeats or names no object",
                    ))
                }
            }
            if start <= previous || start as usize > nodes.len() {
                return Err(bad(start as usize, "insertion node ranges not increasing"));
            }
            previous = start;
        }
        let alive: Vec<bool> = children.iter().map(|&(_, len)| len == 0).collect();
        let dirs = vertices
            .iter()
            .map(|v| Dir::of(&v.bitangent.angle(scene)))
            .collect();
        let mut h = History {
            live: alive.iter().filter(|&&a| a).count(),
            cylinders: nodes,
            alive,
            kids: children,
            links,
            vertices,
            dirs,
            borders: alloc::vec![Vec::new(); objects.saturating_mul(SLOTS)],
            dead: alloc::vec![0; objects.saturating_mul(SLOTS)],
            entries: 0,
            order,
            starts,
            budget: None,
            compacted,
            scratch: Scratch::default(),
        };
        h.validate(scene)?;
        // The border index of the live cylinders (for later insertions).
        let live: Vec<(CylinderId, Cylinder)> = (h.cylinders.iter().zip(&h.alive))
            .enumerate()
            .filter(|(_, (_, &alive))| alive)
            .map(|(i, (c, _))| (CylinderId(i as u32), *c))
            .collect();
        for (id, c) in live {
            for sl in border_slots(&c).into_iter().flatten() {
                h.insert_border(sl, h.entry(c.left, id));
            }
        }
        Ok(h)
    }

    /// Checks the history DAG (the paper's §4.2): every link goes to a younger node (so the
    /// DAG is acyclic and a descent is bounded), every node but the root is reached by a
    /// link, the leaves are exactly the live cylinders, a compacted history
    /// ([`History::is_compacted`]) has no piece node (a dead node whose one child has its
    /// trapezoid and layer), and — once every object of `scene`
    /// is inserted — the live cylinders form a valid complex ([`Complex::validate`]).
    pub fn validate(&self, scene: &SceneRef<'_>) -> Result<(), ComplexError> {
        let bad = |node: usize, what| ComplexError::History { node, what };
        let n = self.cylinders.len();
        if self.alive.len() != n || self.kids.len() != n {
            return Err(bad(n, "arena lengths differ"));
        }
        let mut reached = alloc::vec![false; n];
        let mut live = 0;
        for (i, (&(start, len), &alive)) in self.kids.iter().zip(&self.alive).enumerate() {
            let kids = self
                .links
                .get(start as usize..start as usize + len as usize)
                .ok_or(bad(i, "child range out of the link arena"))?;
            if alive != kids.is_empty() {
                return Err(bad(i, "a live node has children or a dead one has none"));
            }
            live += usize::from(alive);
            for c in kids {
                if c.index() <= i || c.index() >= n {
                    return Err(bad(i, "link not to a younger node"));
                }
                reached[c.index()] = true;
            }
            // A piece (a split cylinder's part, merged into its one child) carries its
            // child's record: a compacted history has none.
            if let ([only], Some(c)) = (kids, self.cylinders.get(i)) {
                if self.compacted
                    && self
                        .cylinders
                        .get(only.index())
                        .is_some_and(|k| same_trapezoid(c, k))
                {
                    return Err(bad(i, "a piece node in a compacted history"));
                }
            }
        }
        if let Some(i) = (1..n).find(|&i| !reached[i]) {
            return Err(bad(i, "no link reaches it"));
        }
        if live != self.live {
            return Err(bad(n, "live count differs from the alive flags"));
        }
        if self.order.len() < scene.len() {
            // Part of the scene inserted: `Complex::validate` counts every object.
            return Ok(());
        }
        self.complex(scene)?.validate(scene)
    }

    /// Undoes search path compaction (§4.4) on the finished history: each link `C → C′`
    /// where `C` has several children and `C′` several parents becomes `C → P → C′` with
    /// a dead **piece** node `P = C ∩ C′` — the split of `C` by the new walls, then the
    /// merge of its pieces into `C′`, as two steps. Where `C` has one child (`C ⊂ C′`, a
    /// pure merge) or `C′` one parent (`C′ ⊂ C`, a pure split) the piece would be `C′` or
    /// `C` itself and the link stays. Coarser than the paper's process, which splits edge
    /// by edge and deletes boundaries one at a time, adding more intermediate nodes.
    ///
    /// A piece stores `C′`'s record: reached from `C`, a line lies in `C ∩ C′` iff it lies
    /// in `C′`, so a descent (`locate`, `locate_on_sheet`) tests it exactly as it tests
    /// `C′`. Pieces get the ids just before their `C′` (links still go to younger nodes,
    /// and each insertion's nodes stay one range); the live partition is unchanged. Later
    /// insertions ([`History::insert`]) link as always: the history stays flagged
    /// uncompacted.
    fn uncompact(&mut self) -> Result<(), ComplexError> {
        const NONE: u32 = u32::MAX;
        let n = self.cylinders.len();
        let broken = |node: usize| ComplexError::History {
            node,
            what: "a link out of range while undoing compaction",
        };
        // Parents per node; then, per node, the links that get a piece before it (CSR,
        // by parent id: parents are visited in id order).
        let mut parents = alloc::vec![0u32; n];
        for &c in &self.links {
            let p = parents.get_mut(c.index()).ok_or(broken(c.index()))?;
            *p = p.saturating_add(1);
        }
        let pieced = |c: CylinderId, kids: usize| {
            kids >= 2 && parents.get(c.index()).is_some_and(|&k| k >= 2)
        };
        let mut first = alloc::vec![0u32; n + 1];
        for i in 0..n {
            let kids = self.children(CylinderId(i as u32));
            for &c in kids {
                if pieced(c, kids.len()) {
                    if let Some(f) = first.get_mut(c.index() + 1) {
                        *f += 1;
                    }
                }
            }
        }
        // Prefix sums: `first[j]` pieces go before node j, `first[j + 1] - first[j]` into it.
        let mut sum = 0u32;
        for f in &mut first {
            sum = sum.saturating_add(*f);
            *f = sum;
        }
        let pieces = sum as usize;
        let total = n + pieces;
        let links = self.links.len() + pieces;
        self.check(self.live, total, links, self.vertices.len(), self.entries)?;
        if u32::try_from(total).map_or(true, |t| t == NONE) {
            return Err(ComplexError::TooLarge);
        }
        // New ids: the pieces into node j (by parent), then j.
        let new_id = |j: usize| j as u32 + first.get(j + 1).copied().unwrap_or(0);
        // `piece_of[l]`: the new id of link l's piece (NONE: none). The pieces into c are
        // numbered from `first[c]` in parent order, just before c.
        let mut fill = first.clone();
        let mut piece_of = alloc::vec![NONE; self.links.len()];
        for i in 0..n {
            let (start, len) = self.kids.get(i).copied().unwrap_or((0, 0));
            for l in start as usize..start as usize + len as usize {
                let c = *self.links.get(l).ok_or(broken(i))?;
                if !pieced(c, len as usize) {
                    continue;
                }
                let k = fill.get_mut(c.index()).ok_or(broken(i))?;
                *piece_of.get_mut(l).ok_or(broken(i))? = *k + c.0;
                *k += 1;
            }
        }
        let remap = |c: &Cylinder| Cylinder {
            left_neighbour: c.left_neighbour.map(|k| CylinderId(new_id(k.index()))),
            right_neighbour: c.right_neighbour.map(|k| CylinderId(new_id(k.index()))),
            ..*c
        };
        let mut cylinders = Vec::new();
        let mut alive = Vec::new();
        let mut kids = Vec::new();
        let mut arena = Vec::new();
        if cylinders.try_reserve_exact(total).is_err()
            || alive.try_reserve_exact(total).is_err()
            || kids.try_reserve_exact(total).is_err()
            || arena.try_reserve_exact(links).is_err()
        {
            return Err(ComplexError::CapacityExceeded {
                cylinders: self.live,
                history_nodes: total,
                bytes: self.bytes_for(total, links, self.vertices.len(), self.entries),
            });
        }
        for (j, into) in first.windows(2).enumerate() {
            let c = remap(self.cylinders.get(j).ok_or(broken(j))?);
            for _ in into.first().copied().unwrap_or(0)..into.last().copied().unwrap_or(0) {
                cylinders.push(c);
                alive.push(false);
                kids.push((arena.len() as u32, 1));
                arena.push(CylinderId(new_id(j)));
            }
            cylinders.push(c);
            alive.push(self.alive.get(j).copied().unwrap_or(false));
            let (start, len) = self.kids.get(j).copied().unwrap_or((0, 0));
            kids.push((arena.len() as u32, len));
            for l in start as usize..start as usize + len as usize {
                let c = *self.links.get(l).ok_or(broken(j))?;
                arena.push(match piece_of.get(l) {
                    Some(&p) if p != NONE => CylinderId(p),
                    _ => CylinderId(new_id(c.index())),
                });
            }
        }
        // Each insertion's range now starts with the pieces into its first node.
        for s in &mut self.starts {
            let j = *s as usize;
            *s = match first.get(j) {
                Some(&f) if j < n => *s + f,
                _ => total as u32,
            };
        }
        for list in &mut self.borders {
            for e in list {
                e.id = CylinderId(new_id(e.id.index()));
            }
        }
        self.cylinders = cylinders;
        self.alive = alive;
        self.kids = kids;
        self.links = arena;
        self.scratch.sparse.clear();
        self.compacted = false;
        Ok(())
    }

    /// The live cylinder across `chain` on `side` in `layer` at θ⁺.
    fn across(&self, chain: Chain, side: Side, layer: Layer, theta: &Key) -> Option<CylinderId> {
        let list = self.borders.get(slot(chain, side, layer))?;
        // The last cylinder whose left wall lies at or before θ.
        let k = list.partition_point(|e| self.entry_at_or_before(e, theta));
        // The last live one (destroyed cylinders stay in the lists until compaction).
        let id = list
            .get(..k)?
            .iter()
            .rev()
            .map(|e| e.id)
            .find(|id| self.alive.get(id.index()).is_some_and(|&a| a))?;
        // Its left wall is at or before θ (the entry is before `k`, and the entry's test is
        // `left_at_or_before` on the same wall): only the right wall is left to check.
        self.cylinders
            .get(id.index())
            .is_some_and(|c| self.right_after(c, theta))
            .then_some(id)
    }

    /// Whether `id` is the cylinder [`History::across`] finds above `chain` in `layer` at
    /// θ⁺: a live cylinder with that bottom arc and layer spanning θ⁺ is in that list, and
    /// the live cylinders of a list have disjoint θ-ranges.
    fn is_above(&self, id: CylinderId, chain: Chain, layer: Layer, theta: &Key) -> bool {
        self.alive.get(id.index()) == Some(&true)
            && self.cylinders.get(id.index()).is_some_and(|c| {
                c.bottom == Some(chain) && Layer::of(c, chain) == layer && self.spans(c, theta)
            })
    }

    fn push(&mut self, c: Cylinder) -> Result<CylinderId, ComplexError> {
        let id = CylinderId::from_index(self.cylinders.len()).ok_or(ComplexError::TooLarge)?;
        self.check(
            self.live,
            self.cylinders.len() + 1,
            self.links.len(),
            self.vertices.len(),
            self.entries,
        )?;
        if self.cylinders.try_reserve(1).is_err()
            || self.alive.try_reserve(1).is_err()
            || self.kids.try_reserve(1).is_err()
        {
            return Err(ComplexError::CapacityExceeded {
                cylinders: self.live,
                history_nodes: self.cylinders.len() + 1,
                bytes: self.estimated_bytes().saturating_add(NODE_BYTES),
            });
        }
        self.cylinders.push(c);
        self.alive.push(false); // made live when the insertion commits
        self.kids.push((0, 0));
        Ok(id)
    }

    fn push_vertex(&mut self, bitangent: Bitangent, dir: Dir) -> Result<VertexId, ComplexError> {
        let v = VertexId::from_index(self.vertices.len())
            .filter(|v| v.0 != ZERO_WALL)
            .ok_or(ComplexError::TooLarge)?;
        self.check(
            self.live,
            self.cylinders.len(),
            self.links.len(),
            self.vertices.len() + 1,
            self.entries,
        )?;
        if self.vertices.try_reserve(1).is_err() || self.dirs.try_reserve(1).is_err() {
            return Err(ComplexError::CapacityExceeded {
                cylinders: self.live,
                history_nodes: self.cylinders.len(),
                bytes: self.estimated_bytes().saturating_add(VERTEX_BYTES),
            });
        }
        self.vertices.push(Vertex { bitangent });
        self.dirs.push(dir);
        Ok(v)
    }

    /// Inserts object `n` of `scene` (`Update Cylindrical Partition`). Objects not inserted
    /// are ignored by every predicate, so any subset can be built in any order.
    ///
    /// On an error (a budget exceeded, or a bug) the insertion is rolled back: the history
    /// is the one before the call.
    pub fn insert(&mut self, scene: &SceneRef<'_>, n: ObjectId) -> Result<(), ComplexError> {
        let mut s = core::mem::take(&mut self.scratch);
        let (nodes, vertices) = (self.cylinders.len(), self.vertices.len());
        s.begin(n, nodes, scene.len());
        let result = self.insert_with(scene, &mut s);
        if result.is_ok() {
            // Fits: node ids are u32 (checked by `push`).
            self.starts.push(nodes as u32);
        }
        if result.is_err() {
            self.cylinders.truncate(nodes);
            self.alive.truncate(nodes);
            self.kids.truncate(nodes);
            self.vertices.truncate(vertices);
            self.dirs.truncate(vertices);
        }
        self.scratch = s;
        result
    }

    fn insert_with(&mut self, scene: &SceneRef<'_>, s: &mut Scratch) -> Result<(), ComplexError> {
        let n = s.n;
        let lost = |step: &'static str| ComplexError::InsertionLost {
            object: n.0 as usize,
            step,
        };
        if scene.len() > MAX_OBJECTS {
            return Err(ComplexError::TooLarge);
        }
        let need = scene.len().saturating_mul(SLOTS);
        if self.borders.len() < need {
            self.borders.resize_with(need, Vec::new);
            self.dead.resize(need, 0);
        }
        let zero = Key::new(Angle::ZERO);
        let start = ranked(scene, tangent_vertex(scene, n, zero.angle(), Bound::Lower));
        let i0 = self
            .locate_probe(scene, &zero, Probe::Vertex(start))
            .ok_or(lost("locate start"))?;
        let restart = Restart {
            keep: 0,
            fresh: i0,
            tail_from: usize::MAX,
        };
        self.chain_up(scene, s, restart, &zero, None)
            .ok_or(lost("chain at 0"))?;
        core::mem::swap(&mut s.chain, &mut s.next);
        derive(&self.cylinders, &s.chain, n, &mut s.rows, &mut s.derived);
        s.run_id.clear();
        for k in 0..s.derived.len() {
            let id = self.push(Cylinder::new(s.derived[k].0, Wall::Zero))?;
            s.created.push(id);
            s.run_id.push(id);
        }
        s.chain_dense.clear();
        for k in 0..s.chain.len() {
            let i = s.state_index(s.chain[k]);
            s.chain_dense.push(i);
        }
        s.record_children(0);
        let mut theta: Option<Key> = None;

        for _ in 0..4 * self.cylinders.len() + 16 {
            let Some((mut angle, event)) = self.next_event(scene, s, theta.as_ref()) else {
                break;
            };
            let (wall, crossing) = match event {
                Event::Wall(w) => (Wall::Vertex(w), None),
                Event::Cross {
                    bitangent,
                    lower,
                    exit,
                } => {
                    let v = self.push_vertex(bitangent, angle.dir)?;
                    angle.vertex = Some(v);
                    (Wall::Vertex(v), Some((bitangent, lower, exit)))
                }
            };
            // The chain just after the event, rebuilt only where it changed: below the
            // first cylinder closing at the wall (or from the new bottom, or below the
            // top) and up to an old chain cylinder that the event leaves alone.
            let first = *s.chain.first().ok_or(lost("empty chain"))?;
            let k = s.chain.len();
            let restart = match crossing {
                Some((b, true, (chain, side))) => {
                    let layer = layer_across(chain, side, || {
                        n_after(scene, n, chain.object, angle.angle(), Some(&b), None)
                    });
                    let i0 = self
                        .across(chain, side, layer, &angle)
                        .ok_or(lost("across at crossing"))?;
                    Restart {
                        keep: 0,
                        fresh: i0,
                        tail_from: 0,
                    }
                }
                Some((_, false, _)) => Restart {
                    keep: k.saturating_sub(1),
                    fresh: first,
                    tail_from: usize::MAX,
                },
                None => {
                    let closing = |j: &usize| {
                        s.chain
                            .get(*j)
                            .is_some_and(|c| self.cylinders[c.index()].right == wall)
                    };
                    let a = (0..k).find(closing);
                    let b = (0..k).rev().find(closing);
                    match (a, b) {
                        (Some(0), Some(b)) => Restart {
                            keep: 0,
                            fresh: self.cylinders[first.index()]
                                .right_neighbour
                                .ok_or(lost("right neighbour"))?,
                            tail_from: b + 1,
                        },
                        (Some(a), Some(b)) => Restart {
                            keep: a,
                            fresh: first,
                            tail_from: b + 1,
                        },
                        _ => Restart {
                            keep: 0,
                            fresh: first,
                            tail_from: usize::MAX,
                        },
                    }
                }
            };
            let bitangent = crossing.map(|c| c.0);
            self.chain_up(scene, s, restart, &angle, bitangent.as_ref())
                .ok_or(lost("chain up"))?;
            self.step(s, wall)?;
            theta = Some(angle);
        }
        self.finish(s)
    }

    /// The chain of conflict cylinders at θ⁺ into `s.next`: `restart.keep` cylinders of the
    /// current chain (or, if none, `restart.fresh`, holding N's lower tangent line), then
    /// upward across top arcs to the one holding N's upper tangent line — or, on meeting a
    /// cylinder of the current chain at index ≥ `restart.tail_from`, the rest of the
    /// current chain from there.
    ///
    /// The splice is exact: a chain cylinder that the event does not close still spans θ⁺,
    /// and the cylinder above it in the chain is decided by its top arc, the layer (the
    /// order of N and the arc's object along the lines, which only changes where they have
    /// no common transversal) and whether N's upper tangent line is above the arc (which
    /// only changes at a bitangent of N and the arc's object, an upper crossing event).
    fn chain_up(
        &self,
        scene: &SceneRef<'_>,
        s: &mut Scratch,
        restart: Restart,
        theta: &Key,
        event: Option<&Bitangent>,
    ) -> Option<()> {
        let mut out = core::mem::take(&mut s.next);
        out.clear();
        let r = self.chain_into(scene, s, restart, theta, event, &mut out);
        s.next = out;
        s.splice = r?;
        Some(())
    }

    fn chain_into(
        &self,
        scene: &SceneRef<'_>,
        s: &Scratch,
        restart: Restart,
        theta: &Key,
        event: Option<&Bitangent>,
        out: &mut Vec<CylinderId>,
    ) -> Option<Splice> {
        let n = s.n;
        // The index of a cylinder in the current chain, if it may start the spliced tail
        // (checked against the chain: the position of a cylinder that left it is stale).
        let tail = |c: CylinderId| {
            s.position(c)
                .filter(|&p| p >= restart.tail_from && s.chain.get(p) == Some(&c))
        };
        let keep = restart.keep;
        let untailed = |out: &Vec<CylinderId>| Splice {
            keep,
            old_tail: s.chain.len(),
            new_tail: out.len(),
        };
        let mut cur = if keep == 0 {
            if let Some(p) = tail(restart.fresh) {
                out.extend_from_slice(s.chain.get(p..)?);
                return Some(Splice {
                    keep,
                    old_tail: p,
                    new_tail: 0,
                });
            }
            out.push(restart.fresh);
            restart.fresh
        } else {
            out.extend_from_slice(s.chain.get(..restart.keep)?);
            *out.last()?
        };
        let angle = theta.angle();
        let top_n = ranked(scene, tangent_vertex(scene, n, angle, Bound::Upper));
        for _ in 0..self.cylinders.len() {
            let c = self.cylinders.get(cur.index())?;
            let Some(top) = c.top else {
                return Some(untailed(out));
            };
            let h = ranked(scene, tangent_vertex(scene, top.object, angle, top.bound));
            if angle.offset_cmp_after(top_n, h) == Sign::Positive {
                return Some(untailed(out));
            }
            // The order of N and the arc's object matters only for a lower arc, whose
            // tangent vertex `h` is then the first one `n_after` tries.
            let lower = (top.bound == Bound::Lower).then_some(h);
            let layer = layer_across(top, Side::Above, || {
                n_after(scene, n, top.object, angle, event, lower)
            });
            // Likely answers, tried before the border index: the right neighbour of the
            // cylinder at this index before the event (it continues it if it closed), the
            // first cylinder that may start the tail, the cylinder at this index.
            let at = s.chain.get(out.len()).copied();
            let guess = [
                at.and_then(|o| self.cylinders.get(o.index())?.right_neighbour),
                s.chain.get(restart.tail_from).copied(),
                at,
            ]
            .into_iter()
            .flatten()
            .find(|&g| self.is_above(g, top, layer, theta));
            cur = match guess {
                Some(g) => g,
                None => self.across(top, Side::Above, layer, theta)?,
            };
            if let Some(p) = tail(cur) {
                let new_tail = out.len();
                out.extend_from_slice(s.chain.get(p..)?);
                return Some(Splice {
                    keep,
                    old_tail: p,
                    new_tail,
                });
            }
            out.push(cur);
        }
        None
    }

    /// The next event after θ: a wall of a chain cylinder, or N's lower (upper) chain
    /// crossing an arc of the bottom (top) cylinder of the chain.
    fn next_event(
        &self,
        scene: &SceneRef<'_>,
        s: &mut Scratch,
        theta: Option<&Key>,
    ) -> Option<(Key, Event)> {
        let ends = [
            (s.chain.first().copied(), Bound::Lower),
            (s.chain.last().copied(), Bound::Upper),
        ];
        // An end's first crossing after θ is kept while the end stays and θ has not
        // reached it: θ only grows, and no candidate of the end lies between the θ it was
        // found at and itself.
        let mut stale = [false; 2];
        for (e, &(id, _)) in ends.iter().enumerate() {
            let Some(id) = id else { continue };
            // Whether θ may have reached a kept crossing (keys that do not decide: yes).
            let reached = |(x, _): &Candidate| {
                theta.is_some_and(|t| fast_order(&x.0, &t.dir) != Some(Ordering::Greater))
            };
            let kept = s.crossings.get(e).copied().flatten();
            let kept =
                kept.is_some_and(|(c, first)| c == id && !first.as_ref().is_some_and(reached));
            if kept {
                continue;
            }
            stale[e] = true;
            // The bitangents of N with the arcs' objects, computed once per insertion.
            let Some(c) = self.cylinders.get(id.index()) else {
                continue;
            };
            for arc in [c.bottom, c.top].into_iter().flatten() {
                s.bitangents_with(scene, arc.object);
            }
        }
        // Candidates are compared by their integer keys; the perturbed angle is built
        // only for exact ties.
        let sr = &*s;
        let angle = |src: Src| match src {
            Src::Vertex(v) => self.dirs.get(v.index()).map(|d| d.angle),
            Src::Pool(i) => sr.pool.get(i).map(|x| *x.1.angle()),
        };
        let cmp = |(da, a): (Dir, Src), (db, b): (Dir, Src)| -> Ordering {
            if let (Src::Vertex(x), Src::Vertex(y)) = (a, b) {
                if x == y {
                    return Ordering::Equal;
                }
            }
            da.cmp(&db).unwrap_or_else(|| match (angle(a), angle(b)) {
                (Some(x), Some(y)) => x.cmp_angle(&y),
                _ => Ordering::Equal,
            })
        };
        let after = |(d, a): (Dir, Src)| {
            theta.is_none_or(|t| {
                if let Src::Vertex(v) = a {
                    if t.vertex == Some(v) {
                        return false;
                    }
                }
                d.cmp(&t.dir)
                    .unwrap_or_else(|| angle(a).map_or(Ordering::Equal, |x| x.cmp_angle(t.angle())))
                    == Ordering::Greater
            })
        };
        // Most comparisons are decided by the keys alone: that test is inlined, the rest
        // (ties, parallel vectors) goes through `cmp` and `after`.
        let less = |c: &(Dir, Src), b: &(Dir, Src)| match fast_order(&c.0, &b.0) {
            Some(o) => o == Ordering::Less,
            None => cmp(*c, *b) == Ordering::Less,
        };
        let better = |c: (Dir, Src), best: &Option<Candidate>| {
            best.as_ref().is_none_or(|(b, _)| less(&c, b))
                && theta.is_none_or(|t| match fast_order(&c.0, &t.dir) {
                    Some(o) => o == Ordering::Greater,
                    None => after(c),
                })
        };
        let vertex = |v: VertexId| self.dirs.get(v.index()).map(|&d| (d, Src::Vertex(v)));
        let theta_dir = theta.map(|t| &t.dir);
        // The first crossing after θ of N's `bound` chain with an arc of end cylinder `id`,
        // before its right wall.
        let first_crossing = |id: CylinderId, bound: Bound| {
            let c = self.cylinders.get(id.index())?;
            let right = match c.right {
                Wall::Vertex(v) => vertex(v),
                Wall::Zero => None,
            };
            let mut first: Option<Candidate> = None;
            for (arc, side) in [(c.bottom, Side::Below), (c.top, Side::Above)] {
                let Some(arc) = arc else { continue };
                // Only bitangents from N's `bound` chain to the arc's chain fit.
                let range = sr.cached(arc.object, fit_index(bound, arc.bound));
                for i in range {
                    let Some((b, a)) = sr.pool.get(i) else { break };
                    let cand = (a.dir, Src::Pool(i));
                    let before_right = right.as_ref().is_none_or(|r| {
                        fast_order(&cand.0, &r.0).map_or_else(|| less(&cand, r), Ordering::is_lt)
                    });
                    let first_dir = first.as_ref().map(|b| &b.0 .0);
                    if before_right
                        && fast_better(&cand.0, first_dir, theta_dir)
                            .unwrap_or_else(|| better(cand, &first))
                    {
                        let event = Event::Cross {
                            bitangent: *b,
                            lower: bound == Bound::Lower,
                            exit: (arc, side),
                        };
                        first = Some((cand, event));
                    }
                }
            }
            first
        };
        let mut best: Option<Candidate> = None;
        for &id in &sr.chain {
            if let Wall::Vertex(w) = self.cylinders[id.index()].right {
                // Chain cylinders often share a right wall: the best already.
                if matches!(best, Some((_, Event::Wall(b))) if b == w) {
                    continue;
                }
                if let Some(c) = vertex(w) {
                    let best_dir = best.as_ref().map(|b| &b.0 .0);
                    if fast_better(&c.0, best_dir, theta_dir).unwrap_or_else(|| better(c, &best)) {
                        best = Some((c, Event::Wall(w)));
                    }
                }
            }
        }
        // The first crossings found again (stale ends), stored once the search is done.
        let mut found: [Option<(CylinderId, Option<Candidate>)>; 2] = [None; 2];
        for (e, &(id, bound)) in ends.iter().enumerate() {
            let Some(id) = id else { continue };
            let first = if stale.get(e) == Some(&true) {
                let first = first_crossing(id, bound);
                if let Some(x) = found.get_mut(e) {
                    *x = Some((id, first));
                }
                first
            } else {
                sr.crossings.get(e).copied().flatten().and_then(|(_, f)| f)
            };
            if let Some(first) = first {
                if best.as_ref().is_none_or(|(b, _)| less(&first.0, b)) {
                    best = Some(first);
                }
            }
        }
        let key = match best {
            Some(((_, Src::Vertex(v)), _)) => self.vertex_key(v),
            Some(((_, Src::Pool(i)), _)) => sr.pool.get(i).map(|x| x.1),
            None => None,
        };
        for (slot, f) in s.crossings.iter_mut().zip(found) {
            if f.is_some() {
                *slot = f;
            }
        }
        Some((key?, best?.1))
    }

    /// Closes the replacement intervals of the chain before the event that the derived
    /// intervals no longer have and opens the new ones at `wall`, setting each derived
    /// interval's cylinder (`run_id`).
    ///
    /// The derived intervals have distinct shapes (the chain crosses each arc once, so no
    /// two runs share their end arc), so an interval with a shape it had before keeps its
    /// cylinder, wherever it is matched. When an event keeps their number, intervals are
    /// first matched at the same index; otherwise, since an event changes the chain only
    /// in its middle ([`Splice`]), at the same place from either end of each [`sections`]
    /// part (the two ends, the `(F, N)` runs, the `(N, G)` runs). Only the rest are sorted
    /// and compared by shape. Gone and changed intervals are walked in shape order, so
    /// cylinders close and open in shape order.
    fn reopen(&mut self, s: &mut Scratch, wall: Wall) -> Result<(), ComplexError> {
        s.gone.clear();
        s.shapes.clear();
        if s.derived.len() == s.last_derived.len() {
            for (k, (d, l)) in s.derived.iter().zip(&s.last_derived).enumerate() {
                if d.0 != l.0 {
                    let id = s.run_id.get(k).copied().unwrap_or(CylinderId::ZERO);
                    s.gone.push((l.0, id));
                    s.shapes.push((d.0, k as u32));
                }
            }
        } else {
            core::mem::swap(&mut s.run_id, &mut s.last_run_id);
            s.run_id.clear();
            s.run_id.resize(s.derived.len(), CylinderId::ZERO);
            let n = Shape::object(Some(s.n));
            let old = sections(&s.last_derived, n);
            let new = sections(&s.derived, n);
            for (o, d) in old.into_iter().zip(new) {
                let (Some(old), Some(old_ids), Some(new), Some(ids)) = (
                    s.last_derived.get(o.clone()),
                    s.last_run_id.get(o),
                    s.derived.get(d.clone()),
                    s.run_id.get_mut(d.clone()),
                ) else {
                    continue;
                };
                let (mut ol, mut nl) = (old.len(), new.len());
                let mut head = 0;
                while head < ol.min(nl) && old[head].0 == new[head].0 {
                    ids[head] = old_ids[head];
                    head += 1;
                }
                while ol > head && nl > head && old[ol - 1].0 == new[nl - 1].0 {
                    (ol, nl) = (ol - 1, nl - 1);
                    ids[nl] = old_ids[ol];
                }
                // (Indices in range: `head ≤ ol ≤ old.len()`, `head ≤ nl ≤ new.len()`, and
                // `ids`, `old_ids` are as long as `new`, `old`.)
                for (l, &id) in old[head..ol].iter().zip(&old_ids[head..ol]) {
                    s.gone.push((l.0, id));
                }
                for (k, x) in new[head..nl].iter().enumerate() {
                    s.shapes.push((x.0, (d.start + head + k) as u32));
                }
            }
        }
        s.gone.sort_unstable_by_key(|e| e.0);
        s.shapes.sort_unstable_by_key(|e| e.0);
        let (gone, shapes) = (core::mem::take(&mut s.gone), core::mem::take(&mut s.shapes));
        let mut gone_rest = gone.iter().peekable();
        for &(sn, k) in &shapes {
            // Gone intervals before this shape close.
            while let Some(&(_, id)) = gone_rest.next_if(|o| o.0 < sn) {
                self.close(s, id, wall);
            }
            let id = match gone_rest.next_if(|o| o.0 == sn) {
                Some(&(_, id)) => id,
                None => {
                    let id = self.push(Cylinder::new(sn, wall))?;
                    s.created.push(id);
                    s.openers.push(id);
                    id
                }
            };
            if let Some(r) = s.run_id.get_mut(k as usize) {
                *r = id;
            }
        }
        for &(_, id) in gone_rest {
            self.close(s, id, wall);
        }
        (s.gone, s.shapes) = (gone, shapes);
        Ok(())
    }

    /// Closes replacement interval `id` at `wall`.
    #[inline]
    fn close(&mut self, s: &mut Scratch, id: CylinderId, wall: Wall) {
        if let Some(c) = self.cylinders.get_mut(id.index()) {
            c.right = wall;
        }
        s.closers.push(id);
    }

    /// Moves the insertion to the chain `s.next` after an event at `wall`.
    fn step(&mut self, s: &mut Scratch, wall: Wall) -> Result<(), ComplexError> {
        core::mem::swap(&mut s.derived, &mut s.last_derived);
        derive(&self.cylinders, &s.next, s.n, &mut s.rows, &mut s.derived);
        s.closers.clear();
        s.openers.clear();
        self.reopen(s, wall)?;
        // Old cylinders entering or leaving the conflict region between their walls keep
        // their geometry outside it, as new cylinders with a new wall.
        // Only the middles of the chains differ (`Splice`): their cylinders are stamped.
        let Splice {
            keep,
            old_tail,
            new_tail,
        } = s.splice;
        let stamp = s.next_stamp();
        for &i in s.chain_dense.get(keep..old_tail).unwrap_or(&[]) {
            if let Some(st) = s.dense.get_mut(i) {
                st.before = stamp;
            }
        }
        // The dense indices of the next chain, kept for `record_children`.
        s.next_dense.clear();
        s.next_dense
            .extend_from_slice(s.chain_dense.get(..keep).unwrap_or(&[]));
        for k in keep..new_tail {
            let i = s.state_index(s.next[k]);
            s.dense[i].after = stamp;
            s.next_dense.push(i);
        }
        s.next_dense
            .extend_from_slice(s.chain_dense.get(old_tail..).unwrap_or(&[]));
        s.diff.clear();
        for k in keep..new_tail {
            if s.dense[s.next_dense[k]].before != stamp {
                s.diff.push(s.next[k]);
            }
        }
        s.diff.sort_unstable();
        s.diff.dedup();
        for k in 0..s.diff.len() {
            let d = s.diff[k];
            let old = self.cylinders[d.index()];
            if old.left == wall {
                continue; // opens at this very wall: nothing of it lies outside before
            }
            let di = s.state_index(d);
            let piece = match s.dense[di].remainder.take() {
                Some(p) => p, // left earlier, comes back now
                None => {
                    let p = self.push(Cylinder {
                        right_neighbour: None,
                        ..old
                    })?;
                    s.created.push(p);
                    s.dense[di].first_piece = Some(p);
                    s.firsts.push(d);
                    s.links.push((di as u32, p));
                    p
                }
            };
            self.cylinders[piece.index()].right = wall;
            self.cylinders[piece.index()].right_neighbour = None;
            s.dense[di].last_piece = None;
            s.closers.push(piece);
        }
        s.diff.clear();
        for k in keep..old_tail.min(s.chain.len()) {
            if s.dense[s.chain_dense[k]].after != stamp {
                s.diff.push(s.chain[k]);
            }
        }
        s.diff.sort_unstable();
        s.diff.dedup();
        for k in 0..s.diff.len() {
            let d = s.diff[k];
            let old = self.cylinders[d.index()];
            if old.right == wall {
                continue; // closes at this very wall
            }
            let p = self.push(Cylinder {
                left: wall,
                left_neighbour: None,
                ..old
            })?;
            s.created.push(p);
            let di = s.state_index(d);
            let st = &mut s.dense[di];
            st.remainder = Some(p);
            st.last_piece = Some(p);
            s.lasts.push(d);
            s.links.push((di as u32, p));
            s.openers.push(p);
        }
        // Faces continuing across the wall keep their floor and ceiling.
        for &c in &s.closers {
            let (f, g) = (
                self.cylinders[c.index()].floor,
                self.cylinders[c.index()].ceiling,
            );
            if let Some(&o) = s.openers.iter().find(|&&o| {
                let oc = &self.cylinders[o.index()];
                oc.floor == f && oc.ceiling == g && oc.left_neighbour.is_none()
            }) {
                self.cylinders[c.index()].right_neighbour = Some(o);
                self.cylinders[o.index()].left_neighbour = Some(c);
            }
        }
        core::mem::swap(&mut s.chain, &mut s.next);
        core::mem::swap(&mut s.chain_dense, &mut s.next_dense);
        s.record_children(keep);
        Ok(())
    }

    /// Closes the insertion at θ = 2π: links across θ = 0 and to unchanged neighbours,
    /// retires the conflict cylinders and makes the new ones live. Everything that can
    /// fail is decided before the first change to a cylinder that existed before.
    fn finish(&mut self, s: &mut Scratch) -> Result<(), ComplexError> {
        let lost = |step: &'static str| ComplexError::InsertionLost {
            object: s.n.0 as usize,
            step,
        };
        // Replacement intervals still open continue across θ = 0 into those opened there
        // (the last created with that shape, as a map keyed by shape would keep).
        s.diff.clear();
        s.diff.extend(
            s.created
                .iter()
                .copied()
                .filter(|id| self.cylinders[id.index()].left == Wall::Zero),
        );
        for (&(sh, ..), &id) in s.derived.iter().zip(&s.run_id) {
            let first = *s
                .diff
                .iter()
                .rev()
                .find(|c| Shape::of(&self.cylinders[c.index()]) == sh)
                .ok_or(lost("wrap at zero"))?;
            self.cylinders[id.index()].right_neighbour = Some(first);
            self.cylinders[first.index()].left_neighbour = Some(id);
        }
        // The first piece of an old cylinder continues from its old left neighbour (or from
        // that neighbour's last piece); the last piece leads to the old right neighbour.
        s.firsts.sort_unstable();
        s.firsts.dedup();
        s.lasts.sort_unstable();
        s.lasts.dedup();
        s.plan.clear();
        for &d in &s.firsts {
            let Some(p) = s.get(d).and_then(|st| st.first_piece) else {
                continue;
            };
            // A cylinder born at a vertex (right wedge) has no left neighbour.
            let Some(l) = self.cylinders[d.index()].left_neighbour else {
                continue;
            };
            let l = match s.get(l) {
                Some(st) => st.last_piece.ok_or(lost("first piece link"))?,
                None => l,
            };
            s.plan.push((l, p)); // l then p
        }
        for &d in &s.lasts {
            let Some(p) = s.get(d).and_then(|st| st.last_piece) else {
                continue;
            };
            let Some(r) = self.cylinders[d.index()].right_neighbour else {
                continue;
            };
            let r = match s.get(r) {
                Some(st) => st.first_piece.ok_or(lost("last piece link"))?,
                None => r,
            };
            s.plan.push((p, r)); // p then r
        }
        // The counts after this insertion, against the budget.
        // (Destroyed cylinders' entries stay until their list is compacted: count them.)
        // The new border-index entries, (list, entry) in creation order, for
        // `update_borders` (the created cylinders' arcs and left walls are final).
        s.pending.clear();
        for &id in &s.created {
            let Some(c) = self.cylinders.get(id.index()) else {
                continue;
            };
            for sl in border_slots(c).into_iter().flatten() {
                s.pending.push((sl, self.entry(c.left, id)));
            }
        }
        let entries = self.entries + s.pending.len();
        let live = (self.live + s.created.len()).saturating_sub(s.dense.len());
        // Children: group the recorded links by parent (counting sort over the dense
        // order), sorted by id and without repeats.
        s.count.clear();
        s.count.resize(s.dense.len() + 1, 0);
        for &(k, _) in &s.links {
            if let Some(x) = s.count.get_mut(k as usize + 1) {
                *x += 1;
            }
        }
        for k in 1..s.count.len() {
            s.count[k] += s.count[k - 1];
        }
        s.grouped.clear();
        s.grouped.resize(s.links.len(), CylinderId::ZERO);
        s.fill.clear();
        s.fill.extend_from_slice(&s.count);
        for &(k, c) in &s.links {
            if let Some(at) = s.fill.get_mut(k as usize) {
                s.grouped[*at as usize] = c;
                *at += 1;
            }
        }
        // Each group sorted and without repeats, moved down so that `grouped[..total]` is
        // their concatenation; `count[k]` becomes the start of group `k` there.
        let mut total = 0usize;
        for k in 0..s.dense.len() {
            let (a, b) = (s.count[k] as usize, s.count[k + 1] as usize);
            s.grouped[a..b].sort_unstable();
            s.count[k] = total as u32; // ≤ a: fits
            let mut last = None;
            for i in a..b {
                let c = s.grouped[i];
                if last != Some(c) {
                    s.grouped[total] = c; // total ≤ i
                    total += 1;
                }
                last = Some(c);
            }
        }
        if let Some(end) = s.count.last_mut() {
            *end = total as u32;
        }
        let links = self.links.len() + total;
        if u32::try_from(links).is_err() {
            return Err(ComplexError::TooLarge);
        }
        self.check(
            live,
            self.cylinders.len(),
            links,
            self.vertices.len(),
            entries,
        )?;
        if self.links.try_reserve(total).is_err() {
            return Err(ComplexError::CapacityExceeded {
                cylinders: live,
                history_nodes: self.cylinders.len(),
                bytes: self.bytes_for(self.cylinders.len(), links, self.vertices.len(), entries),
            });
        }
        // Commit.
        for &(a, b) in &s.plan {
            self.cylinders[a.index()].right_neighbour = Some(b);
            self.cylinders[b.index()].left_neighbour = Some(a);
        }
        let base = self.links.len();
        self.links.extend_from_slice(&s.grouped[..total]);
        for k in 0..s.dense.len() {
            let d = s.dense[k].id;
            let (a, b) = (s.count[k], s.count[k + 1]);
            // Fits: checked against u32 above.
            self.kids[d.index()] = (base as u32 + a, b - a);
        }
        for k in 0..s.dense.len() {
            let d = s.dense[k].id;
            self.alive[d.index()] = false;
        }
        for k in 0..s.created.len() {
            self.alive[s.created[k].index()] = true;
        }
        self.update_borders(s);
        self.live = live;
        self.order.push(s.n);
        Ok(())
    }

    /// Updates the border index at commit. Destroyed cylinders are only counted as dead
    /// in their lists ([`History::across`] skips them by their alive flag); a list is
    /// compacted when a quarter of it is dead, so it stays below 4/3 of its live size.
    /// Created cylinders are inserted by bisection, after old entries with an equal left
    /// wall, each list once ([`History::insert_group`]).
    fn update_borders(&mut self, s: &mut Scratch) {
        for st in &s.dense {
            if let Some(c) = self.cylinders.get(st.id.index()) {
                for sl in border_slots(c).into_iter().flatten() {
                    if let Some(d) = self.dead.get_mut(sl) {
                        *d += 1;
                    }
                }
            }
        }
        // The new entries grouped by list (counting sort, creation order kept within a
        // list), then each list updated once: one pass of moves instead of one per entry.
        // (`s.pending` holds them, from `finish`.)
        s.groups.clear();
        if s.per_slot.len() < self.borders.len() {
            s.per_slot.resize(self.borders.len(), 0);
        }
        for &(sl, _) in &s.pending {
            let Some(count) = s.per_slot.get_mut(sl) else {
                continue;
            };
            if *count == 0 {
                s.groups.push((sl, 0, 0));
            }
            *count += 1;
        }
        let mut at = 0;
        for g in &mut s.groups {
            if let Some(count) = s.per_slot.get_mut(g.0) {
                *g = (g.0, at, *count);
                // From here on the next write position in `sorted`.
                (at, *count) = (at + *count, at);
            }
        }
        s.sorted.clear();
        s.sorted
            .resize(s.pending.len(), self.entry(Wall::Zero, CylinderId::ZERO));
        for &(sl, e) in &s.pending {
            if let Some(w) = s.per_slot.get_mut(sl) {
                if let Some(x) = s.sorted.get_mut(*w) {
                    *x = e;
                }
                *w += 1;
            }
        }
        for k in 0..s.groups.len() {
            let (sl, start, len) = s.groups[k];
            if let Some(w) = s.per_slot.get_mut(sl) {
                *w = 0;
            }
            if let Some(group) = s.sorted.get_mut(start..start + len) {
                self.insert_group(sl, group);
            }
        }
    }

    /// Inserts the entries `group` (in creation order) into border list `sl` as
    /// [`History::insert_border`] would one after the other: the same compaction (only
    /// the first insertion can compact: `dead` is 0 after it, and without it the list
    /// only grows), then each entry after every entry with a left wall at or before its
    /// own — on equal walls old entries first, then creation order.
    fn insert_group(&mut self, sl: usize, group: &mut [Entry]) {
        let Some(&first) = group.first() else {
            return;
        };
        self.compact(sl);
        let Some(list) = self.borders.get_mut(sl) else {
            return;
        };
        let mut list = core::mem::take(list);
        // Stable insertion sort: groups are short and nearly sorted (creation follows θ).
        let greater = |a: &Entry, b: &Entry| self.cmp_entries(a, b) == Ordering::Greater;
        for i in 1..group.len() {
            for j in (1..=i).rev() {
                if !greater(&group[j - 1], &group[j]) {
                    break;
                }
                group.swap(j - 1, j);
            }
        }
        // From the last new entry down: its place among the old entries not yet moved,
        // then those after it move up once, past the new entries still to come.
        let old = list.len();
        let k = group.len();
        list.resize(old + k, first);
        let mut end = old;
        for j in (0..k).rev() {
            let e = group[j];
            let before = |x: &Entry| !greater(x, &e);
            // The first entry placed lands anywhere in the list (its distance from the
            // end is mostly over 64 at n = 1024): bisected. The others mostly land at or
            // just below the one placed before them: galloped back from there.
            let p = match list.get(..end) {
                Some(l) if l.last().is_some_and(|x| !before(x)) => {
                    if j + 1 == k {
                        l.partition_point(before)
                    } else {
                        gallop_back(l, before)
                    }
                }
                _ => end,
            };
            if p < end {
                list.copy_within(p..end, p + j + 1);
            }
            list[p + j] = e;
            end = p;
        }
        self.entries += k;
        if let Some(slot) = self.borders.get_mut(sl) {
            *slot = list;
        }
    }

    /// Drops the destroyed cylinders' entries from border list `sl` once they are more
    /// than a quarter of it (amortized: each entry is dropped once).
    fn compact(&mut self, sl: usize) {
        let (Some(list), Some(dead)) = (self.borders.get_mut(sl), self.dead.get_mut(sl)) else {
            return;
        };
        if *dead as usize * 4 > list.len() {
            let before = list.len();
            let alive = &self.alive;
            list.retain(|x| alive.get(x.id.index()).is_some_and(|&a| a));
            self.entries = self.entries.saturating_sub(before - list.len());
            *dead = 0;
        }
    }

    fn insert_border(&mut self, sl: usize, e: Entry) {
        self.compact(sl);
        let Some(list) = self.borders.get(sl) else {
            return;
        };
        // Entries mostly come in wall order (N's own arcs): try the end before bisecting.
        let k = match list.last() {
            Some(x) if self.cmp_entries(x, &e) == Ordering::Greater => {
                list.partition_point(|x| self.cmp_entries(x, &e) != Ordering::Greater)
            }
            _ => list.len(),
        };
        if let Some(list) = self.borders.get_mut(sl) {
            list.insert(k, e);
            self.entries += 1;
        }
    }
}

/// [`slice::partition_point`] searched from the end (galloping, then bisection): it costs
/// the logarithm of the distance from the end.
fn gallop_back<T>(list: &[T], pred: impl Fn(&T) -> bool) -> usize {
    // Invariant: every entry from `hi` on fails `pred`.
    let mut hi = list.len();
    let mut step = 1;
    while hi > 0 {
        let lo = hi.saturating_sub(step);
        match list.get(lo) {
            Some(x) if !pred(x) => hi = lo,
            _ => {
                let rest = list.get(lo..hi).unwrap_or(&[]);
                return lo + rest.partition_point(&pred);
            }
        }
        step = step.saturating_mul(2);
    }
    0
}

/// Whether two cylinders have the same trapezoid and layer (walls, arcs, floor, ceiling).
fn same_trapezoid(a: &Cylinder, b: &Cylinder) -> bool {
    (a.floor, a.ceiling, a.bottom, a.top, a.left, a.right)
        == (b.floor, b.ceiling, b.bottom, b.top, b.left, b.right)
}

impl Cylinder {
    fn new(shape: Shape, left: Wall) -> Cylinder {
        let (floor, ceiling, bottom, top) = shape.unpack();
        Cylinder {
            floor,
            ceiling,
            bottom,
            top,
            left,
            right: Wall::Zero,
            left_neighbour: None,
            right_neighbour: None,
        }
    }
}

/// How [`History::chain_up`] rebuilds the chain after an event.
#[derive(Clone, Copy, Debug)]
struct Restart {
    /// Cylinders of the current chain kept at the bottom.
    keep: usize,
    /// The bottom cylinder when none is kept.
    fresh: CylinderId,
    /// Cylinders of the current chain from this index up may be spliced in unchanged.
    tail_from: usize,
}

/// How the chain after an event is made of the current one: `next[..keep]` is
/// `chain[..keep]`, `next[new_tail..]` is `chain[old_tail..]`, and only the middles
/// `chain[keep..old_tail]` and `next[keep..new_tail]` differ.
#[derive(Clone, Copy, Debug, Default)]
struct Splice {
    keep: usize,
    old_tail: usize,
    new_tail: usize,
}

/// What one insertion knows about a conflict cylinder.
#[derive(Clone, Copy, Debug)]
struct Old {
    id: CylinderId,
    /// Event stamps of membership in the chain before / after the current event.
    before: u32,
    after: u32,
    /// Pieces outside the conflict region: the one before the cylinder first entered the
    /// chain, the open one after it left, and the last one.
    first_piece: Option<CylinderId>,
    remainder: Option<CylinderId>,
    last_piece: Option<CylinderId>,
    /// The last children recorded (to skip repeats cheaply): as many as the intervals
    /// that can cover one chain cylinder (below or above N, and an `(F, N)` and an
    /// `(N, G)` run). [`CylinderId::ZERO`], the root, is never a child: it stands for none.
    recent: [CylinderId; 4],
    /// Index in the current chain while a member (stale after it leaves: checked against
    /// the chain).
    pos: u32,
}

/// The state of one insertion, kept between insertions to reuse its allocations.
#[derive(Clone, Debug, Default)]
struct Scratch {
    n: ObjectId,
    /// Conflict cylinders at the current θ, upward in u.
    chain: Vec<CylinderId>,
    /// Their indices in `dense`.
    chain_dense: Vec<usize>,
    /// The chain after the current event.
    next: Vec<CylinderId>,
    /// How `next` is spliced from `chain`.
    splice: Splice,
    /// The replacement intervals of the chain (open at the current θ) and the chain
    /// indices each covers.
    derived: Vec<(Shape, usize, usize)>,
    /// Those of the chain before the current event.
    last_derived: Vec<(Shape, usize, usize)>,
    /// [`derive`]'s copy of the chain cylinders' fields.
    rows: Vec<Row>,
    /// [`History::reopen`]'s changed intervals `(shape, index in derived)` and gone ones
    /// `(shape, cylinder)`.
    shapes: Vec<(Shape, u32)>,
    gone: Vec<(Shape, CylinderId)>,
    /// The cylinder of each derived interval, and of each in `last_derived`.
    run_id: Vec<CylinderId>,
    last_run_id: Vec<CylinderId>,
    /// `chain_dense` of the chain after the current event.
    next_dense: Vec<usize>,
    /// New border-index entries at commit, (list, entry) in creation order, and grouped
    /// by list: `groups` holds (list, start in `sorted`, count); `per_slot` is all zero
    /// between commits.
    pending: Vec<(usize, Entry)>,
    sorted: Vec<Entry>,
    groups: Vec<(usize, usize, usize)>,
    per_slot: Vec<usize>,
    /// Every cylinder created by this insertion.
    created: Vec<CylinderId>,
    closers: Vec<CylinderId>,
    openers: Vec<CylinderId>,
    diff: Vec<CylinderId>,
    /// (destroyed cylinder's index in `dense`, child) in the order recorded.
    links: Vec<(u32, CylinderId)>,
    firsts: Vec<CylinderId>,
    lasts: Vec<CylinderId>,
    /// Neighbour links to make at commit: (left, right).
    plan: Vec<(CylinderId, CylinderId)>,
    count: Vec<u32>,
    fill: Vec<u32>,

    grouped: Vec<CylinderId>,
    /// Every conflict cylinder seen (the destroyed ones), as a sparse set: `sparse[id]`
    /// indexes `dense` when `dense[sparse[id]].id == id`. `sparse` is never cleared.
    dense: Vec<Old>,
    sparse: Vec<u32>,
    stamp: u32,
    /// Per object: the insertion number and the bounds in `pool` of its bitangents with N,
    /// grouped by the pair of chains they join ([`fit_index`]): group `g` is
    /// `pool[bounds[g] .. bounds[g + 1]]`, in the order [`bitangents`] gives them.
    bt_of: Vec<(u32, [u32; 5])>,
    pool: Vec<(Bitangent, Key)>,
    /// The bitangents of N and one object, before grouping into `pool`.
    found: Vec<(Bitangent, Key)>,
    /// Per end of the chain (bottom, top): the end cylinder and its first crossing after
    /// the θ it was found at ([`History::next_event`]).
    crossings: [Option<(CylinderId, Option<Candidate>)>; 2],
    insertion: u32,
}

// (A derive belongs with the type in `scene`; kept here where the construction needs it.)
#[allow(clippy::derivable_impls)]
impl Default for ObjectId {
    fn default() -> Self {
        ObjectId(0)
    }
}

impl Scratch {
    /// Clears the state for inserting `n` into a history of `nodes` nodes.
    fn begin(&mut self, n: ObjectId, nodes: usize, objects: usize) {
        self.n = n;
        self.chain.clear();
        self.next.clear();
        self.derived.clear();
        self.created.clear();
        self.links.clear();
        self.firsts.clear();
        self.lasts.clear();
        self.dense.clear();
        if self.sparse.len() < nodes {
            self.sparse.resize(nodes, 0);
        }
        self.pool.clear();
        self.crossings = [None; 2];
        if self.bt_of.len() < objects {
            self.bt_of.resize(objects, (0, [0; 5]));
        }
        self.insertion = self.insertion.wrapping_add(1);
        if self.insertion == 0 {
            // Wrapped: forget every stamp.
            self.bt_of.iter_mut().for_each(|e| e.0 = 0);
            self.insertion = 1;
        }
    }

    fn next_stamp(&mut self) -> u32 {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            for d in &mut self.dense {
                d.before = 0;
                d.after = 0;
            }
            self.stamp = 1;
        }
        self.stamp
    }

    fn sparse_index(&self, id: CylinderId) -> Option<&u32> {
        self.sparse
            .get(id.index())
            .filter(|&&k| self.dense.get(k as usize).is_some_and(|o| o.id == id))
    }

    /// The index of `id` in the current chain if a member; else any index (check it
    /// against the chain: [`Old::pos`]).
    fn position(&self, id: CylinderId) -> Option<usize> {
        self.get(id).map(|o| o.pos as usize)
    }

    fn get(&self, id: CylinderId) -> Option<&Old> {
        self.sparse_index(id)
            .and_then(|&k| self.dense.get(k as usize))
    }

    /// The index in `dense` of conflict cylinder `id`, created on first sight.
    #[inline]
    fn state_index(&mut self, id: CylinderId) -> usize {
        match self.sparse_index(id) {
            Some(&k) => k as usize,
            None => {
                let k = self.dense.len();
                if self.sparse.len() <= id.index() {
                    self.sparse.resize(id.index() + 1, 0);
                }
                self.sparse[id.index()] = k as u32;
                self.dense.push(Old {
                    id,
                    before: 0,
                    after: 0,
                    first_piece: None,
                    remainder: None,
                    last_piece: None,
                    recent: [CylinderId::ZERO; 4],
                    pos: 0,
                });
                k
            }
        }
    }

    /// Computes and caches the bitangents of N and `other` (once per insertion).
    fn bitangents_with(&mut self, scene: &SceneRef<'_>, other: ObjectId) {
        let Some(e) = self.bt_of.get(other.0 as usize) else {
            return;
        };
        if e.0 == self.insertion {
            return;
        }
        self.found.clear();
        for b in bitangents(*scene, self.n, other) {
            self.found.push((b, Key::new(b.angle(scene))));
        }
        // The chains a bitangent of N joins: N's one first.
        let fits = |b: &Bitangent, g: usize| {
            (b.first_object == self.n && fit_index(b.first_bound, b.second_bound) == g)
                || (b.second_object == self.n && fit_index(b.second_bound, b.first_bound) == g)
        };
        let mut bounds = [0u32; 5];
        bounds[0] = self.pool.len() as u32;
        for g in 0..4 {
            for e in &self.found {
                if fits(&e.0, g) {
                    self.pool.push(*e);
                }
            }
            bounds[g + 1] = self.pool.len() as u32;
        }
        if let Some(e) = self.bt_of.get_mut(other.0 as usize) {
            *e = (self.insertion, bounds);
        }
    }

    /// The range in `pool` of the cached bitangents of N and `other` joining the chains of
    /// group `group` ([`fit_index`]).
    fn cached(&self, other: ObjectId, group: usize) -> core::ops::Range<usize> {
        match self.bt_of.get(other.0 as usize) {
            Some((i, b)) if *i == self.insertion => match (b.get(group), b.get(group + 1)) {
                (Some(&s), Some(&e)) => s as usize..e as usize,
                _ => 0..0,
            },
            _ => 0..0,
        }
    }

    /// Links every chain cylinder to the replacement intervals covering it now: `I₀` to
    /// the interval below N, `I_k` to the one above, and every `I_j` to the `(F, N)` and
    /// `(N, G)` runs through `j` (as [`derive`] reports them, their cylinders in
    /// `run_id`). `chain_dense` must hold the chain's indices in `dense`.
    ///
    /// Positions ([`Old::pos`]) are set from chain index `from` on: below it the chain is
    /// the one before the event ([`Splice::keep`]).
    fn record_children(&mut self, from: usize) {
        for (k, &i) in self.chain_dense.iter().enumerate().skip(from) {
            if let Some(st) = self.dense.get_mut(i) {
                st.pos = k as u32;
            }
        }
        for (&(_, lo, hi), &id) in self.derived.iter().zip(&self.run_id) {
            // The chain indices `lo..=hi` (an exclusive range: cheaper to walk).
            let end = hi.saturating_add(1).min(self.chain_dense.len());
            for &i in self.chain_dense.get(lo..end).unwrap_or(&[]) {
                let Some(st) = self.dense.get_mut(i) else {
                    break;
                };
                if st.recent.contains(&id) {
                    continue;
                }
                st.recent = [id, st.recent[0], st.recent[1], st.recent[2]];
                self.links.push((i as u32, id));
            }
        }
    }
}

/// The group in [`Scratch::pool`] of the bitangents from N's chain `n` to another
/// object's chain `other`.
fn fit_index(n: Bound, other: Bound) -> usize {
    let k = |b: Bound| match b {
        Bound::Lower => 0,
        Bound::Upper => 1,
    };
    2 * k(n) + k(other)
}

/// A candidate event: its direction, where its angle comes from, and the event.
type Candidate = ((Dir, Src), Event);

/// Where a candidate event's angle comes from.
#[derive(Clone, Copy, Debug)]
enum Src {
    /// An existing vertex.
    Vertex(VertexId),
    /// A cached bitangent of N (`Scratch::pool`).
    Pool(usize),
}

/// An event of an insertion.
#[derive(Clone, Copy, Debug)]
enum Event {
    /// A wall (old vertex) of a chain cylinder.
    Wall(VertexId),
    /// N's lower (`lower`) or upper chain crosses the arc `exit.0` of the bottom or top
    /// chain cylinder, leaving it towards `exit.1`.
    Cross {
        bitangent: Bitangent,
        lower: bool,
        exit: (Chain, Side),
    },
}

/// Which layer across `chain` (entering on `side`) holds N's chord: where the chain's
/// object is crossed on that side, before it if N comes before it along the lines
/// (`n_after`, asked only then: it costs offset comparisons).
fn layer_across(chain: Chain, side: Side, n_after: impl FnOnce() -> bool) -> Layer {
    let crossed = match chain.bound {
        Bound::Lower => Side::Above,
        Bound::Upper => Side::Below,
    };
    if side != crossed {
        Layer::Around
    } else if n_after() {
        Layer::After
    } else {
        Layer::Before
    }
}

/// Whether N lies after object `h` along the lines of direction θ⁺ through the tangent
/// point of `h`'s chain. At a bitangent of N and `h` the line is tangent to both; the
/// bitangent's order decides. `lower`: `h`'s lower tangent vertex at θ, if known.
fn n_after(
    scene: &SceneRef<'_>,
    n: ObjectId,
    h: ObjectId,
    theta: &Angle,
    event: Option<&Bitangent>,
    lower: Option<RankedPoint>,
) -> bool {
    if let Some(b) = event {
        if b.first_object == h && b.second_object == n {
            return true;
        }
        if b.first_object == n && b.second_object == h {
            return false;
        }
    }
    // Any vertex of h on the crossing line works; the chain's tangent vertex lies on it.
    let lower =
        lower.unwrap_or_else(|| ranked(scene, tangent_vertex(scene, h, theta, Bound::Lower)));
    if let Some(a) = object_ahead(scene, n, theta, lower) {
        return a;
    }
    let upper = ranked(scene, tangent_vertex(scene, h, theta, Bound::Upper));
    object_ahead(scene, n, theta, upper).unwrap_or(false)
}

/// [`object_ahead_of`] with each vertex's offset compared once (it compares both ends of
/// every edge): the same first crossing edge, the same answer.
fn object_ahead(
    scene: &SceneRef<'_>,
    object: ObjectId,
    theta: &Angle,
    o: RankedPoint,
) -> Option<bool> {
    let obj = scene.object(object)?;
    let (first, len) = (obj.first_vertex(), obj.len());
    let v0 = ranked(scene, first);
    let s0 = theta.offset_cmp(o, v0);
    let (mut a, mut sa) = (v0, s0);
    for k in 0..len {
        let (b, sb) = if k + 1 < len {
            let b = ranked(scene, first + k + 1);
            (b, theta.offset_cmp(o, b))
        } else {
            (v0, s0)
        };
        if sa != sb {
            return Some(theta.object_ahead_of_vertex(o, a, b) == Sign::Positive);
        }
        (a, sa) = (b, sb);
    }
    None
}

/// The replacement intervals of a chain (module documentation), each with the range of
/// chain indices it covers, into `out`: the interval below N (index 0), the one above N
/// (index k − 1), then the `(F, N)` runs and the `(N, G)` runs upward.
fn derive(
    cylinders: &[Cylinder],
    chain: &[CylinderId],
    n: ObjectId,
    rows: &mut Vec<Row>,
    out: &mut Vec<(Shape, usize, usize)>,
) {
    out.clear();
    let lower = Some(Chain {
        object: n,
        bound: Bound::Lower,
    });
    let upper = Some(Chain {
        object: n,
        bound: Bound::Upper,
    });
    let get = |id: &CylinderId| cylinders.get(id.index());
    let (Some(first), Some(last)) = (chain.first().and_then(get), chain.last().and_then(get))
    else {
        return;
    };
    let k = chain.len();
    out.push((
        Shape::new(first.floor, first.ceiling, first.bottom, lower),
        0,
        0,
    ));
    out.push((
        Shape::new(last.floor, last.ceiling, upper, last.top),
        k - 1,
        k - 1,
    ));
    // The floor, ceiling and top of each chain cylinder, read once and packed as shape
    // fields (up to the first id not in the arena, which ends the runs as if the chain
    // ended there). Packing is injective, so runs compare packed fields.
    rows.clear();
    // (Fields fit 32 bits: object ids stay below 2³⁰.)
    rows.extend(chain.iter().map_while(get).map(|c| {
        (
            Shape::object(c.floor) as u32,
            Shape::object(c.ceiling) as u32,
            Shape::chain(c.top) as u32,
        )
    }));
    let complete = rows.len() == k;
    let (nf, lower, upper) = (
        Shape::object(Some(n)) as u32,
        Shape::chain(lower) as u32,
        Shape::chain(upper) as u32,
    );
    // Runs of equal floor give (F, N); runs of equal ceiling give (N, G).
    for before in [true, false] {
        let key = |c: &Row| if before { c.0 } else { c.1 };
        let mut start = lower;
        let mut from = 0;
        for (j, c) in rows.iter().enumerate() {
            let next = rows.get(j + 1);
            if next.is_none_or(|m| key(m) != key(c)) {
                let end = if next.is_some() { c.2 } else { upper };
                let (f, g) = if before { (key(c), nf) } else { (nf, key(c)) };
                let shape = Shape::of_fields(f.into(), g.into(), start.into(), end.into());
                out.push((shape, from, j));
                start = c.2;
                from = j + 1;
            }
        }
        if !complete {
            return;
        }
    }
}

/// The sections of the derived intervals ([`derive()`]): the two ends, the `(F, N)` runs
/// (their ceiling is N: `n` as [`Shape::object`] packs it), the `(N, G)` runs.
fn sections(derived: &[(Shape, usize, usize)], n: u128) -> [core::ops::Range<usize>; 3] {
    let ends = derived.len().min(2);
    let runs = derived
        .get(ends..)
        .unwrap_or(&[])
        .iter()
        .take_while(|d| (d.0 .0 >> 64) & 0xffff_ffff == n)
        .count();
    [0..ends, ends..ends + runs, ends + runs..derived.len()]
}

/// A chain cylinder's floor, ceiling and top arc as packed [`Shape`] fields, as
/// [`derive`] reads them.
type Row = (u32, u32, u32);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Point;
    use crate::scene::{Material, Scene};

    fn pt(x: i32, y: i32) -> Point {
        Point::from_raw(x << 16, y << 16).unwrap()
    }

    fn scene() -> Scene {
        let polys = [
            alloc::vec![pt(0, 0), pt(4, 0), pt(0, 3)],
            alloc::vec![pt(10, 1), pt(14, 2), pt(11, 5)],
            alloc::vec![pt(3, 8), pt(7, 8), pt(7, 11), pt(3, 11)],
        ];
        Scene::new(polys.iter().map(|p| (Material::Opaque, &p[..]))).unwrap()
    }

    /// The integer keys agree with the perturbed order: vertex pairs of a small grid
    /// (many exactly parallel and axis-parallel directions), constants, and θ = 0.
    #[test]
    fn direction_keys_agree_with_cmp_angle() {
        let mut angles = alloc::vec![Angle::ZERO];
        for (x, y) in [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (3, -2),
            (-7, -7),
            (1 << 52, 1),
        ] {
            angles.push(Angle::constant(Direction { x, y }));
        }
        let pts: Vec<RankedPoint> = (0..16)
            .map(|i| RankedPoint::vertex(pt(i % 4 - 1, i / 4 - 2), i as usize))
            .collect();
        for a in &pts {
            for b in &pts {
                if a.rank != b.rank {
                    angles.push(Angle::of_pair(*a, *b));
                }
            }
        }
        let keys: Vec<Key> = angles.iter().map(|a| Key::new(*a)).collect();
        let mut decided = 0;
        for x in &keys {
            for y in &keys {
                let want = x.angle().cmp_angle(y.angle());
                if let Some(got) = x.dir.cmp(&y.dir) {
                    assert_eq!(got, want, "{:?} {:?}", x.angle(), y.angle());
                    decided += 1;
                }
                if let Some(got) = fast_order(&x.dir, &y.dir) {
                    assert_eq!(got, want);
                }
            }
        }
        assert!(decided > keys.len() * keys.len() / 2);
    }

    /// Every vertex's direction holds its bitangent's angle (the walk reads it there, not
    /// from the vertex), after a construction and after loading its parts.
    #[test]
    fn vertex_directions_hold_their_angles() {
        let s = scene();
        let s = s.as_ref();
        let built = History::build(&s, &BuildOptions::default()).unwrap();
        let loaded = History::from_parts(&s, built.to_parts()).unwrap();
        for h in [&built, &loaded] {
            assert!(!h.vertices.is_empty());
            assert_eq!(h.vertices.len(), h.dirs.len());
            for (v, d) in h.vertices.iter().zip(&h.dirs) {
                let want = Dir::of(&v.bitangent.angle(&s));
                assert_eq!(d.key, want.key);
                assert_eq!(
                    alloc::format!("{:?}", d.angle),
                    alloc::format!("{:?}", want.angle)
                );
            }
        }
    }

    /// Packed shapes sort as the tuples they pack and unpack to them.
    #[test]
    fn shapes_pack_in_tuple_order() {
        let objects = [
            None,
            Some(ObjectId(0)),
            Some(ObjectId(1)),
            Some(ObjectId(77)),
        ];
        let chains = [
            None,
            Some(Chain {
                object: ObjectId(0),
                bound: Bound::Upper,
            }),
            Some(Chain {
                object: ObjectId(1),
                bound: Bound::Lower,
            }),
            Some(Chain {
                object: ObjectId(1),
                bound: Bound::Upper,
            }),
        ];
        let mut all = Vec::new();
        for f in objects {
            for g in objects {
                for b in chains {
                    for t in chains {
                        all.push((f, g, b, t));
                    }
                }
            }
        }
        for x in &all {
            let p = Shape::new(x.0, x.1, x.2, x.3);
            assert_eq!(p.unpack(), *x);
            for y in &all {
                assert_eq!(p.cmp(&Shape::new(y.0, y.1, y.2, y.3)), x.cmp(y));
            }
        }
    }

    #[test]
    fn a_tiny_budget_is_an_error_and_a_large_one_is_not() {
        let s = scene();
        let s = s.as_ref();
        let free = History::build(&s, &BuildOptions::default()).unwrap();
        for budget in [
            Budget {
                cylinders: 5,
                ..Budget::UNLIMITED
            },
            Budget {
                history_nodes: 10,
                ..Budget::UNLIMITED
            },
            Budget {
                bytes: 1000,
                ..Budget::UNLIMITED
            },
        ] {
            let options = BuildOptions {
                budget: Some(budget),
                ..BuildOptions::default()
            };
            match History::build(&s, &options) {
                Err(ComplexError::CapacityExceeded {
                    cylinders,
                    history_nodes,
                    bytes,
                }) => assert!(
                    cylinders > budget.cylinders
                        || history_nodes > budget.history_nodes
                        || bytes > budget.bytes
                ),
                other => panic!("{budget:?}: {other:?}"),
            }
        }
        let large = Budget {
            cylinders: 10_000,
            history_nodes: 10_000,
            bytes: 10_000_000,
        };
        let h = History::build(
            &s,
            &BuildOptions {
                budget: Some(large),
                ..BuildOptions::default()
            },
        )
        .unwrap();
        assert_eq!(h.stats(), free.stats());
        assert!(h.estimated_bytes() <= large.bytes);
        assert_eq!(h.live_cylinders(), h.complex(&s).unwrap().cylinders().len());
    }

    /// After an event only the chain from [`Splice::keep`] up has moved: positions set
    /// from there keep every member's position its index. (A stale one would only lose a
    /// splice — a longer climb to the same chain — which no output shows.)
    #[test]
    fn chain_positions_follow_the_splice() {
        let mut s = Scratch::default();
        s.begin(ObjectId(0), 16, 1);
        let mut set = |chain: &[u32], keep: usize| {
            s.chain = chain.iter().map(|&k| CylinderId(k)).collect();
            s.chain_dense.clear();
            for k in 0..s.chain.len() {
                let i = s.state_index(s.chain[k]);
                s.chain_dense.push(i);
            }
            s.record_children(keep);
            for (k, &c) in s.chain.iter().enumerate() {
                assert_eq!(s.position(c), Some(k), "{chain:?} from {keep}");
            }
        };
        set(&[1, 2, 3, 4], 0);
        set(&[1, 2, 5, 6, 3, 4], 2); // the tail moves up
        set(&[1, 2, 7, 4], 2); // down
        set(&[1, 2, 8, 4], 2); // stays
        set(&[9, 2, 8, 4], 0);
    }

    /// The guesses of the chain walk ([`History::is_above`]) accept exactly the cylinder
    /// the border index finds: every live cylinder with a bottom arc, in every layer, at
    /// θ = 0 and at every vertex.
    #[test]
    fn guesses_agree_with_the_border_index() {
        let s = scene();
        let s = s.as_ref();
        let h = History::build(&s, &BuildOptions::default()).unwrap();
        let thetas: Vec<Key> = core::iter::once(Key::new(Angle::ZERO))
            .chain((0..h.vertices.len()).map(|v| h.vertex_key(VertexId(v as u32)).unwrap()))
            .collect();
        let mut accepted = 0;
        for theta in &thetas {
            for (i, c) in h.cylinders.iter().enumerate() {
                let (id, Some(b)) = (CylinderId(i as u32), c.bottom) else {
                    continue;
                };
                for layer in [Layer::Around, Layer::Before, Layer::After] {
                    let guess = h.is_above(id, b, layer, theta);
                    let found = h.across(b, Side::Above, layer, theta) == Some(id);
                    assert_eq!(guess, found, "{c:?} in {layer:?}");
                    accepted += usize::from(guess);
                }
            }
        }
        assert!(accepted > 0);
    }

    #[test]
    fn a_failed_insertion_is_rolled_back() {
        let s = scene();
        let s = s.as_ref();
        let mut h = History::new();
        h.insert(&s, ObjectId(0)).unwrap();
        let before = h.stats();
        let live = h.live_cylinders();
        h.set_budget(Some(Budget {
            history_nodes: h.stats().nodes + 1,
            ..Budget::UNLIMITED
        }));
        assert!(matches!(
            h.insert(&s, ObjectId(1)),
            Err(ComplexError::CapacityExceeded { .. })
        ));
        assert_eq!((h.stats(), h.live_cylinders()), (before, live));
        h.set_budget(None);
        h.insert(&s, ObjectId(1)).unwrap();
        h.insert(&s, ObjectId(2)).unwrap();
        let want = History::build(&s, &BuildOptions::default()).unwrap();
        assert_eq!(
            h.complex(&s).unwrap().cylinders().len(),
            want.complex(&s).unwrap().cylinders().len()
        );
    }
}
