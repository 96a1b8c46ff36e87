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
//! the new cylinders overlapping it. Point location descends from the first cylinder,
//! choosing at each node the child that contains the query.

use alloc::collections::{BTreeMap, BTreeSet};
use alloc::vec::Vec;
use core::cmp::Ordering;

use super::borders::{Layer, Side};
use super::{Complex, ComplexError, Cylinder, CylinderId, Vertex, VertexId, Wall};
use crate::geom::sos::{Angle, RankedPoint};
use crate::geom::{QueryPoint, Sign};
use crate::line_space::{
    bitangents, object_ahead_of, object_ahead_of_query, ranked, tangent_vertex, Bitangent, Bound,
    Chain,
};
use crate::scene::{ObjectId, SceneRef};

/// A wall position as an ordered key: θ = 0 first, then by angle.
#[derive(Clone, Copy, Debug)]
struct WallKey(Option<Angle>);

impl PartialEq for WallKey {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for WallKey {}
impl PartialOrd for WallKey {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for WallKey {
    fn cmp(&self, other: &Self) -> Ordering {
        match (&self.0, &other.0) {
            (None, None) => Ordering::Equal,
            (None, Some(_)) => Ordering::Less,
            (Some(_), None) => Ordering::Greater,
            (Some(a), Some(b)) => a.cmp_angle(b),
        }
    }
}

/// What a query point is: a scene vertex (while inserting) or a user's query point.
#[derive(Clone, Copy, Debug)]
enum Probe {
    Vertex(RankedPoint),
    Query(QueryPoint),
}

/// The floor, ceiling and arcs of a replacement interval.
type Shape = (
    Option<ObjectId>,
    Option<ObjectId>,
    Option<Chain>,
    Option<Chain>,
);

fn shape(c: &Cylinder) -> Shape {
    (c.floor, c.ceiling, c.bottom, c.top)
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

/// The partition under construction and its history.
#[derive(Clone, Debug)]
pub struct History {
    cylinders: Vec<Cylinder>,
    alive: Vec<bool>,
    children: Vec<Vec<CylinderId>>,
    vertices: Vec<Vertex>,
    borders: BTreeMap<(Chain, Side, Layer, WallKey), CylinderId>,
    order: Vec<ObjectId>,
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
#[derive(Clone, Debug, Default)]
pub struct BuildOptions {
    /// Seed of the random insertion order (same seed, same complex).
    pub seed: u64,
    /// Objects inserted first, in this order (the paper's screens first, §7); the rest
    /// follow in random order.
    pub first: Vec<ObjectId>,
}

impl Default for History {
    fn default() -> Self {
        History::new()
    }
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
            children: alloc::vec![Vec::new()],
            vertices: Vec::new(),
            borders: BTreeMap::new(),
            order: Vec::new(),
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
        for id in options.first.iter().copied().chain(rest) {
            h.insert(scene, id)?;
        }
        Ok(h)
    }

    /// The insertion order used.
    pub fn order(&self) -> &[ObjectId] {
        &self.order
    }

    /// Size and depth of the history.
    pub fn stats(&self) -> HistoryStats {
        let links = self.children.iter().map(Vec::len).sum();
        // Depth by dynamic programming over nodes in creation order (children are younger).
        let mut depth = alloc::vec![0usize; self.cylinders.len()];
        let mut max = 0;
        for i in 0..self.cylinders.len() {
            for c in &self.children[i] {
                let d = depth[i] + 1;
                if d > depth[c.index()] {
                    depth[c.index()] = d;
                }
            }
            if self.alive[i] {
                max = max.max(depth[i]);
            }
        }
        HistoryStats {
            nodes: self.cylinders.len(),
            links,
            depth: max,
        }
    }

    /// The live partition as a complex (cylinders and vertices renumbered).
    pub fn complex(&self, scene: &SceneRef<'_>) -> Result<Complex, ComplexError> {
        let mut vmap: BTreeMap<VertexId, VertexId> = BTreeMap::new();
        let mut cmap: BTreeMap<CylinderId, CylinderId> = BTreeMap::new();
        for (i, _) in self
            .cylinders
            .iter()
            .enumerate()
            .filter(|(i, _)| self.alive[*i])
        {
            let id = CylinderId::from_index(cmap.len()).ok_or(ComplexError::TooLarge)?;
            cmap.insert(CylinderId(i as u32), id);
        }
        let mut used: Vec<(Angle, VertexId)> = Vec::new();
        for (i, c) in self.cylinders.iter().enumerate() {
            if !self.alive[i] {
                continue;
            }
            for w in [c.left, c.right] {
                if let Wall::Vertex(v) = w {
                    if !used.iter().any(|(_, u)| *u == v) {
                        let b = self.vertices.get(v.index()).ok_or(ComplexError::TooLarge)?;
                        used.push((b.bitangent.angle(scene), v));
                    }
                }
            }
        }
        used.sort_by(|a, b| a.0.cmp_angle(&b.0));
        let mut vertices = Vec::with_capacity(used.len());
        for (k, (_, v)) in used.iter().enumerate() {
            vmap.insert(*v, VertexId::from_index(k).ok_or(ComplexError::TooLarge)?);
            vertices.push(self.vertices[v.index()]);
        }
        let wall = |w: Wall| match w {
            Wall::Zero => Wall::Zero,
            Wall::Vertex(v) => vmap.get(&v).map_or(Wall::Zero, |&n| Wall::Vertex(n)),
        };
        let mut cylinders = Vec::with_capacity(cmap.len());
        for (old, _) in &cmap {
            let c = self.cylinders[old.index()];
            cylinders.push(Cylinder {
                left: wall(c.left),
                right: wall(c.right),
                left_neighbour: c.left_neighbour.and_then(|n| cmap.get(&n).copied()),
                right_neighbour: c.right_neighbour.and_then(|n| cmap.get(&n).copied()),
                ..c
            });
        }
        let mut complex = Complex {
            vertices,
            cylinders,
            borders: Default::default(),
        };
        complex.borders = super::borders::build(scene, &complex);
        Ok(complex)
    }

    fn wall_angle(&self, scene: &SceneRef<'_>, w: Wall) -> Option<Angle> {
        match w {
            Wall::Zero => None,
            Wall::Vertex(v) => self
                .vertices
                .get(v.index())
                .map(|v| v.bitangent.angle(scene)),
        }
    }

    /// Whether θ⁺ (just after θ) lies in the cylinder's θ-range.
    fn spans(&self, scene: &SceneRef<'_>, c: &Cylinder, theta: &Angle) -> bool {
        let left = self
            .wall_angle(scene, c.left)
            .is_none_or(|l| l.cmp_angle(theta) != Ordering::Greater);
        let right = self
            .wall_angle(scene, c.right)
            .is_none_or(|r| theta.cmp_angle(&r) == Ordering::Less);
        left && right
    }

    /// Whether the cylinder contains the line of direction θ⁺ through the probe, in the
    /// layer of the probe.
    fn contains(&self, scene: &SceneRef<'_>, c: &Cylinder, theta: &Angle, probe: Probe) -> bool {
        if !self.spans(scene, c, theta) {
            return false;
        }
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
        let ahead = |o: ObjectId| match probe {
            Probe::Vertex(p) => object_ahead_of(scene, o, theta, p),
            Probe::Query(q) => object_ahead_of_query(scene, o, theta, q),
        };
        c.bottom.is_none_or(|b| above(b) == Sign::Negative)
            && c.top.is_none_or(|t| above(t) == Sign::Positive)
            && c.floor.is_none_or(|f| ahead(f) == Some(false))
            && c.ceiling.is_none_or(|g| ahead(g) == Some(true))
    }

    /// Descends the history to the live cylinder containing the probe's line at θ⁺.
    fn locate_probe(
        &self,
        scene: &SceneRef<'_>,
        theta: &Angle,
        probe: Probe,
    ) -> Option<CylinderId> {
        let mut cur = CylinderId::ZERO;
        for _ in 0..self.cylinders.len() {
            if *self.alive.get(cur.index())? {
                return Some(cur);
            }
            cur = *self.children.get(cur.index())?.iter().find(|&&k| {
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
        d: crate::geom::predicates::Direction,
    ) -> Option<(CylinderId, &Cylinder)> {
        let id = self.locate_probe(scene, &Angle::constant(d), Probe::Query(q))?;
        Some((id, self.cylinders.get(id.index())?))
    }

    /// The live cylinder across `chain` on `side` in `layer` at θ⁺.
    fn across(
        &self,
        scene: &SceneRef<'_>,
        chain: Chain,
        side: Side,
        layer: Layer,
        theta: &Angle,
    ) -> Option<CylinderId> {
        let hi = (chain, side, layer, WallKey(Some(*theta)));
        let (k, id) = self.borders.range(..=hi).next_back()?;
        (k.0 == chain && k.1 == side && k.2 == layer)
            .then_some(*id)
            .filter(|id| {
                self.cylinders
                    .get(id.index())
                    .is_some_and(|c| self.spans(scene, c, theta))
            })
    }

    fn border_keys(
        &self,
        scene: &SceneRef<'_>,
        c: &Cylinder,
    ) -> [Option<(Chain, Side, Layer, WallKey)>; 2] {
        let key = WallKey(self.wall_angle(scene, c.left));
        let layer = |chain: Chain| {
            if c.ceiling == Some(chain.object) {
                Layer::Before
            } else if c.floor == Some(chain.object) {
                Layer::After
            } else {
                Layer::Around
            }
        };
        [
            c.top.map(|t| (t, Side::Below, layer(t), key)),
            c.bottom.map(|b| (b, Side::Above, layer(b), key)),
        ]
    }

    fn push(&mut self, c: Cylinder) -> Result<CylinderId, ComplexError> {
        let id = CylinderId::from_index(self.cylinders.len()).ok_or(ComplexError::TooLarge)?;
        self.cylinders.push(c);
        self.alive.push(false); // made live when the insertion commits
        self.children.push(Vec::new());
        Ok(id)
    }

    /// Inserts object `n` of `scene` (`Update Cylindrical Partition`). Objects not inserted
    /// are ignored by every predicate, so any subset can be built in any order.
    pub fn insert(&mut self, scene: &SceneRef<'_>, n: ObjectId) -> Result<(), ComplexError> {
        let lost = |step: &'static str| ComplexError::InsertionLost {
            object: n.0 as usize,
            step,
        };
        let zero = Angle::ZERO;
        let start = ranked(scene, tangent_vertex(scene, n, &zero, Bound::Lower));
        let i0 = self
            .locate_probe(scene, &zero, Probe::Vertex(start))
            .ok_or(lost("locate start"))?;
        let mut ins = Insertion {
            n,
            chain: Vec::new(),
            open: BTreeMap::new(),
            created: Vec::new(),
            ..Default::default()
        };
        ins.chain = self
            .chain_up(scene, n, i0, &zero, None)
            .ok_or(lost("chain at 0"))?;
        let shapes = derive(&self.cylinders, &ins.chain, n);
        for &shape in &shapes {
            let id = self.push(Cylinder::new(shape, Wall::Zero))?;
            ins.open.insert(shape, id);
            ins.created.push(id);
        }
        ins.record_children(self, &shapes);
        let mut theta: Option<Angle> = None;

        for _ in 0..4 * self.cylinders.len() + 16 {
            let Some(event) = self.next_event(scene, &ins, theta.as_ref()) else {
                break;
            };
            let (angle, wall, crossing) = match event {
                Event::Wall(w) => (
                    self.wall_angle(scene, Wall::Vertex(w))
                        .ok_or(lost("wall"))?,
                    Wall::Vertex(w),
                    None,
                ),
                Event::Cross {
                    bitangent,
                    lower,
                    exit,
                } => {
                    let v =
                        VertexId::from_index(self.vertices.len()).ok_or(ComplexError::TooLarge)?;
                    self.vertices.push(Vertex { bitangent });
                    (
                        bitangent.angle(scene),
                        Wall::Vertex(v),
                        Some((bitangent, lower, exit)),
                    )
                }
            };
            // The chain just after the event.
            let first = *ins.chain.first().ok_or(lost("empty chain"))?;
            let i0 = match crossing {
                Some((b, true, (chain, side))) => {
                    let layer = layer_across(
                        chain,
                        side,
                        n_after(scene, n, chain.object, &angle, Some(&b)),
                    );
                    self.across(scene, chain, side, layer, &angle)
                        .ok_or(lost("across at crossing"))?
                }
                _ if self.cylinders[first.index()].right == wall => self.cylinders[first.index()]
                    .right_neighbour
                    .ok_or(lost("right neighbour"))?,
                _ => first,
            };
            let bitangent = crossing.map(|c| c.0);
            let chain = self
                .chain_up(scene, n, i0, &angle, bitangent.as_ref())
                .ok_or(lost("chain up"))?;
            self.step(&mut ins, chain, wall)?;
            theta = Some(angle);
        }
        self.finish(scene, ins)
    }

    /// The chain of conflict cylinders at θ⁺ from `i0` (holding N's lower tangent line)
    /// up to the one holding N's upper tangent line.
    fn chain_up(
        &self,
        scene: &SceneRef<'_>,
        n: ObjectId,
        i0: CylinderId,
        theta: &Angle,
        event: Option<&Bitangent>,
    ) -> Option<Vec<CylinderId>> {
        let top_n = ranked(scene, tangent_vertex(scene, n, theta, Bound::Upper));
        let mut out = alloc::vec![i0];
        let mut cur = i0;
        for _ in 0..self.cylinders.len() {
            let c = self.cylinders.get(cur.index())?;
            let Some(top) = c.top else { return Some(out) };
            let h = ranked(scene, tangent_vertex(scene, top.object, theta, top.bound));
            if theta.offset_cmp_after(top_n, h) == Sign::Positive {
                return Some(out);
            }
            let layer = layer_across(
                top,
                Side::Above,
                n_after(scene, n, top.object, theta, event),
            );
            cur = self.across(scene, top, Side::Above, layer, theta)?;
            out.push(cur);
        }
        None
    }

    /// The next event after θ: a wall of a chain cylinder, or N's lower (upper) chain
    /// crossing an arc of the bottom (top) cylinder of the chain.
    fn next_event(
        &self,
        scene: &SceneRef<'_>,
        ins: &Insertion,
        theta: Option<&Angle>,
    ) -> Option<Event> {
        let after = |a: &Angle| theta.is_none_or(|t| a.cmp_angle(t) == Ordering::Greater);
        let mut best: Option<(Angle, Event)> = None;
        let offer = |a: Angle, e: Event, best: &mut Option<(Angle, Event)>| {
            if after(&a)
                && best
                    .as_ref()
                    .is_none_or(|(b, _)| a.cmp_angle(b) == Ordering::Less)
            {
                *best = Some((a, e));
            }
        };
        for &id in &ins.chain {
            if let Wall::Vertex(w) = self.cylinders[id.index()].right {
                if let Some(a) = self.wall_angle(scene, Wall::Vertex(w)) {
                    offer(a, Event::Wall(w), &mut best);
                }
            }
        }
        let ends = [
            (ins.chain.first(), Bound::Lower),
            (ins.chain.last(), Bound::Upper),
        ];
        for (id, bound) in ends {
            let Some(c) = id.and_then(|id| self.cylinders.get(id.index())) else {
                continue;
            };
            let right = self.wall_angle(scene, c.right);
            for (arc, side) in [(c.bottom, Side::Below), (c.top, Side::Above)] {
                let Some(arc) = arc else { continue };
                for b in bitangents(*scene, ins.n, arc.object) {
                    let fits = (b.first_object == ins.n
                        && b.first_bound == bound
                        && b.second_bound == arc.bound)
                        || (b.second_object == ins.n
                            && b.second_bound == bound
                            && b.first_bound == arc.bound);
                    let a = b.angle(scene);
                    if fits
                        && right
                            .as_ref()
                            .is_none_or(|r| a.cmp_angle(r) == Ordering::Less)
                    {
                        let event = Event::Cross {
                            bitangent: b,
                            lower: bound == Bound::Lower,
                            exit: (arc, side),
                        };
                        offer(a, event, &mut best);
                    }
                }
            }
        }
        best.map(|(_, e)| e)
    }

    /// Moves the insertion to the chain after an event at `wall`.
    fn step(
        &mut self,
        ins: &mut Insertion,
        chain: Vec<CylinderId>,
        wall: Wall,
    ) -> Result<(), ComplexError> {
        let derived = derive(&self.cylinders, &chain, ins.n);
        let shapes: BTreeSet<Shape> = derived.iter().copied().collect();
        let mut closers: Vec<CylinderId> = Vec::new();
        let mut openers: Vec<CylinderId> = Vec::new();
        // Replacement intervals that changed.
        let gone: Vec<Shape> = ins
            .open
            .keys()
            .filter(|s| !shapes.contains(s))
            .copied()
            .collect();
        for s in gone {
            if let Some(id) = ins.open.remove(&s) {
                self.cylinders[id.index()].right = wall;
                closers.push(id);
            }
        }
        for s in shapes {
            if let alloc::collections::btree_map::Entry::Vacant(e) = ins.open.entry(s) {
                let id = self.push(Cylinder::new(s, wall))?;
                e.insert(id);
                ins.created.push(id);
                openers.push(id);
            }
        }
        // Old cylinders entering or leaving the conflict region between their walls keep
        // their geometry outside it, as new cylinders with a new wall.
        let before: BTreeSet<CylinderId> = ins.chain.iter().copied().collect();
        let after: BTreeSet<CylinderId> = chain.iter().copied().collect();
        for &d in after.difference(&before) {
            let old = self.cylinders[d.index()];
            if old.left == wall {
                continue; // opens at this very wall: nothing of it lies outside before
            }
            let piece = match ins.remainder.remove(&d) {
                Some(p) => p, // left earlier, comes back now
                None => {
                    let p = self.push(Cylinder {
                        right_neighbour: None,
                        ..old
                    })?;
                    ins.created.push(p);
                    ins.first_piece.insert(d, p);
                    self.children[d.index()].push(p);
                    p
                }
            };
            self.cylinders[piece.index()].right = wall;
            self.cylinders[piece.index()].right_neighbour = None;
            ins.last_piece.remove(&d);
            closers.push(piece);
        }
        for &d in before.difference(&after) {
            let old = self.cylinders[d.index()];
            if old.right == wall {
                continue; // closes at this very wall
            }
            let p = self.push(Cylinder {
                left: wall,
                left_neighbour: None,
                ..old
            })?;
            ins.created.push(p);
            ins.remainder.insert(d, p);
            ins.last_piece.insert(d, p);
            self.children[d.index()].push(p);
            openers.push(p);
        }
        // Faces continuing across the wall keep their floor and ceiling.
        for &c in &closers {
            let (f, g) = (
                self.cylinders[c.index()].floor,
                self.cylinders[c.index()].ceiling,
            );
            if let Some(&o) = openers.iter().find(|&&o| {
                let oc = &self.cylinders[o.index()];
                oc.floor == f && oc.ceiling == g && oc.left_neighbour.is_none()
            }) {
                self.cylinders[c.index()].right_neighbour = Some(o);
                self.cylinders[o.index()].left_neighbour = Some(c);
            }
        }
        ins.chain = chain;
        ins.record_children(self, &derived);
        Ok(())
    }

    /// Closes the insertion at θ = 2π: links across θ = 0 and to unchanged neighbours,
    /// retires the conflict cylinders and makes the new ones live.
    fn finish(&mut self, scene: &SceneRef<'_>, mut ins: Insertion) -> Result<(), ComplexError> {
        let lost = |step: &'static str| ComplexError::InsertionLost {
            object: ins.n.0 as usize,
            step,
        };
        // Replacement intervals still open continue across θ = 0 into those opened there.
        let at_zero: BTreeMap<Shape, CylinderId> = ins
            .created
            .iter()
            .filter(|id| self.cylinders[id.index()].left == Wall::Zero)
            .map(|&id| (shape(&self.cylinders[id.index()]), id))
            .collect();
        for (s, id) in core::mem::take(&mut ins.open) {
            let first = *at_zero.get(&s).ok_or(lost("wrap at zero"))?;
            self.cylinders[id.index()].right_neighbour = Some(first);
            self.cylinders[first.index()].left_neighbour = Some(id);
        }
        let destroyed = core::mem::take(&mut ins.destroyed);
        // The first piece of an old cylinder continues from its old left neighbour (or from
        // that neighbour's last piece); the last piece leads to the old right neighbour.
        for (&d, &p) in &ins.first_piece {
            // A cylinder born at a vertex (right wedge) has no left neighbour.
            let Some(l) = self.cylinders[d.index()].left_neighbour else {
                continue;
            };
            let l = if destroyed.contains(&l) {
                *ins.last_piece.get(&l).ok_or(lost("first piece link"))?
            } else {
                l
            };
            self.cylinders[p.index()].left_neighbour = Some(l);
            self.cylinders[l.index()].right_neighbour = Some(p);
        }
        for (&d, &p) in &ins.last_piece {
            let Some(r) = self.cylinders[d.index()].right_neighbour else {
                continue;
            };
            let r = if destroyed.contains(&r) {
                *ins.first_piece.get(&r).ok_or(lost("last piece link"))?
            } else {
                r
            };
            self.cylinders[p.index()].right_neighbour = Some(r);
            self.cylinders[r.index()].left_neighbour = Some(p);
        }
        for &d in &destroyed {
            self.alive[d.index()] = false;
            let c = self.cylinders[d.index()];
            for k in self.border_keys(scene, &c).into_iter().flatten() {
                self.borders.remove(&k);
            }
        }
        for &id in &ins.created {
            self.alive[id.index()] = true;
            let c = self.cylinders[id.index()];
            for k in self.border_keys(scene, &c).into_iter().flatten() {
                self.borders.insert(k, id);
            }
        }
        self.order.push(ins.n);
        Ok(())
    }
}

impl Cylinder {
    fn new((floor, ceiling, bottom, top): Shape, left: Wall) -> Cylinder {
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

/// The state of one insertion.
#[derive(Default)]
struct Insertion {
    n: ObjectId,
    /// Conflict cylinders at the current θ, upward in u.
    chain: Vec<CylinderId>,
    /// Replacement intervals open at the current θ.
    open: BTreeMap<Shape, CylinderId>,
    /// Every cylinder created by this insertion.
    created: Vec<CylinderId>,
    /// Every conflict cylinder seen.
    destroyed: BTreeSet<CylinderId>,
    /// Pieces of old cylinders outside the conflict region: the one before the cylinder
    /// first entered the chain, the open one after it left, and the last one.
    first_piece: BTreeMap<CylinderId, CylinderId>,
    remainder: BTreeMap<CylinderId, CylinderId>,
    last_piece: BTreeMap<CylinderId, CylinderId>,
}

impl Default for ObjectId {
    fn default() -> Self {
        ObjectId(0)
    }
}

impl Insertion {
    /// Links every chain cylinder to the replacement intervals covering it now.
    fn record_children(&mut self, h: &mut History, shapes: &[Shape]) {
        let k = self.chain.len();
        for (j, &d) in self.chain.iter().enumerate() {
            self.destroyed.insert(d);
            let f = h.cylinders[d.index()].floor;
            let g = h.cylinders[d.index()].ceiling;
            let n = Some(self.n);
            for s in shapes {
                // I₀ below N, I_k above N, and the (F, N) and (N, G) runs through j.
                let covers = (j == 0
                    && s.3
                        == Some(Chain {
                            object: self.n,
                            bound: Bound::Lower,
                        })
                    && s.0 == f
                    && s.1 == g)
                    || (j + 1 == k
                        && s.2
                            == Some(Chain {
                                object: self.n,
                                bound: Bound::Upper,
                            })
                        && s.0 == f
                        && s.1 == g)
                    || (s.0 == f && s.1 == n)
                    || (s.0 == n && s.1 == g);
                if covers {
                    if let Some(&id) = self.open.get(s) {
                        let ch = &mut h.children[d.index()];
                        if !ch.contains(&id) {
                            ch.push(id);
                        }
                    }
                }
            }
        }
    }
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
/// object is crossed on that side, before it if N comes before it along the lines.
fn layer_across(chain: Chain, side: Side, n_after: bool) -> Layer {
    let crossed = match chain.bound {
        Bound::Lower => Side::Above,
        Bound::Upper => Side::Below,
    };
    if side != crossed {
        Layer::Around
    } else if n_after {
        Layer::After
    } else {
        Layer::Before
    }
}

/// Whether N lies after object `h` along the lines of direction θ⁺ through the tangent
/// point of `h`'s chain. At a bitangent of N and `h` the line is tangent to both; the
/// bitangent's order decides.
fn n_after(
    scene: &SceneRef<'_>,
    n: ObjectId,
    h: ObjectId,
    theta: &Angle,
    event: Option<&Bitangent>,
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
    let v = [Bound::Lower, Bound::Upper]
        .into_iter()
        .map(|b| ranked(scene, tangent_vertex(scene, h, theta, b)))
        .find_map(|p| object_ahead_of(scene, n, theta, p));
    v.unwrap_or(false)
}

/// The replacement intervals of a chain (module documentation).
fn derive(cylinders: &[Cylinder], chain: &[CylinderId], n: ObjectId) -> Vec<Shape> {
    let lower = Some(Chain {
        object: n,
        bound: Bound::Lower,
    });
    let upper = Some(Chain {
        object: n,
        bound: Bound::Upper,
    });
    let get = |id: &CylinderId| cylinders.get(id.index()).copied();
    let mut out = Vec::new();
    let (Some(first), Some(last)) = (chain.first().and_then(get), chain.last().and_then(get))
    else {
        return out;
    };
    out.push((first.floor, first.ceiling, first.bottom, lower));
    out.push((last.floor, last.ceiling, upper, last.top));
    // Runs of equal floor give (F, N); runs of equal ceiling give (N, G).
    for before in [true, false] {
        let key = |c: &Cylinder| if before { c.floor } else { c.ceiling };
        let mut start = lower;
        let members: Vec<Cylinder> = chain.iter().filter_map(get).collect();
        for (j, c) in members.iter().enumerate() {
            let next = members.get(j + 1);
            if next.is_none_or(|m| key(m) != key(c)) {
                let end = if next.is_some() { c.top } else { upper };
                let (f, g) = if before {
                    (key(c), Some(n))
                } else {
                    (Some(n), key(c))
                };
                out.push((f, g, start, end));
                start = c.top;
            }
        }
    }
    out
}
