//! The paper's classical 2D ray tracer (§6): a quadtree over the scene whose leaves hold at
//! most one object, with neighbour links, walked from leaf to leaf along the ray.
//!
//! A node is split while more than one object meets its (closed) box, down to a depth of
//! [`MAX_LEVEL`] (objects one grid unit apart are separated after about 31 halvings of the
//! largest scene; a leaf at the limit keeps every object it meets). Children are stored
//! consecutively (south-west, south-east, north-west, north-east). Each node links, on each
//! side, to the neighbour node of equal or larger size (Samet's ropes); a ray leaving a
//! leaf follows the link of the exit side and descends from there to the leaf containing
//! the exit point, always choosing the half adjacent to the side it came through, so that
//! rounding never sends it back. A hit found in a leaf is final once it lies within that
//! leaf; otherwise it is kept as a candidate until the ray passes it.

use vcx::render::Branch;

use crate::prepared::{Kind, Prepared, RayHit};
use crate::trace::Caster;

/// Deepest level of the tree.
pub const MAX_LEVEL: u32 = 34;

const NONE: u32 = u32::MAX;
/// Sides: west, east, south, north.
const W: usize = 0;
const E: usize = 1;
const S: usize = 2;
const N: usize = 3;

#[derive(Clone, Copy, Debug)]
struct Node {
    min: (f64, f64),
    max: (f64, f64),
    /// Index of the first of four children, or `NONE` for a leaf.
    children: u32,
    /// A leaf's objects are `items[first..first + count]`.
    first: u32,
    count: u32,
    /// Neighbour of equal or larger size across each side (`NONE`: outside the root).
    links: [u32; 4],
}

/// The quadtree tracer.
#[derive(Clone, Debug)]
pub struct Quadtree {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

/// Whether the convex object meets the closed box (separating axes: the box's and the
/// object's edge normals).
fn meets(scene: &Prepared, object: u32, min: (f64, f64), max: (f64, f64)) -> bool {
    let Some(o) = scene.objects.get(object as usize) else {
        return false;
    };
    let b = o.bbox;
    if b[0] > max.0 || b[2] < min.0 || b[1] > max.1 || b[3] < min.1 {
        return false;
    }
    let corners = [
        (min.0, min.1),
        (max.0, min.1),
        (min.0, max.1),
        (max.0, max.1),
    ];
    let (a, n) = (o.first as usize, o.len as usize);
    scene
        .edges
        .get(a..a + n)
        .unwrap_or(&[])
        .iter()
        .all(|e| corners.iter().any(|p| e.n.0 * p.0 + e.n.1 * p.1 <= e.c))
}

impl Quadtree {
    /// Builds the tree over the non-screen objects.
    pub fn new(scene: &Prepared) -> Quadtree {
        let bb = scene.bbox;
        // A square root box with a margin, so that the scene's objects lie strictly inside.
        let size = ((bb[2] - bb[0]).max(bb[3] - bb[1])).max(1.0) * 1.0625;
        let cx = (bb[0] + bb[2]) / 2.0;
        let cy = (bb[1] + bb[3]) / 2.0;
        let root = Node {
            min: (cx - size / 2.0, cy - size / 2.0),
            max: (cx + size / 2.0, cy + size / 2.0),
            children: NONE,
            first: 0,
            count: 0,
            links: [NONE; 4],
        };
        let mut nodes = vec![root];
        let mut items = Vec::new();
        let all: Vec<u32> = (0..scene.objects.len() as u32)
            .filter(|&i| scene.kind(i) != Kind::Screen)
            .collect();
        // Depth-first with an explicit stack of (node, level, objects meeting it).
        let mut stack: Vec<(usize, u32, Vec<u32>)> = vec![(0, 0, all)];
        while let Some((id, level, objs)) = stack.pop() {
            let node = nodes[id];
            if objs.len() <= 1 || level >= MAX_LEVEL {
                nodes[id].first = items.len() as u32;
                nodes[id].count = objs.len() as u32;
                items.extend_from_slice(&objs);
                continue;
            }
            let mid = (
                (node.min.0 + node.max.0) / 2.0,
                (node.min.1 + node.max.1) / 2.0,
            );
            let first = nodes.len() as u32;
            nodes[id].children = first;
            for q in 0..4 {
                let (x0, x1) = if q & 1 == 0 {
                    (node.min.0, mid.0)
                } else {
                    (mid.0, node.max.0)
                };
                let (y0, y1) = if q & 2 == 0 {
                    (node.min.1, mid.1)
                } else {
                    (mid.1, node.max.1)
                };
                let (min, max) = ((x0, y0), (x1, y1));
                let sub: Vec<u32> = objs
                    .iter()
                    .copied()
                    .filter(|&o| meets(scene, o, min, max))
                    .collect();
                nodes.push(Node {
                    min,
                    max,
                    children: NONE,
                    first: 0,
                    count: 0,
                    links: [NONE; 4],
                });
                stack.push((first as usize + q, level + 1, sub));
            }
        }
        // Links, top-down: parents come before their children.
        for id in 0..nodes.len() {
            let p = nodes[id];
            if p.children == NONE {
                continue;
            }
            for q in 0..4u32 {
                let mut links = [NONE; 4];
                let (xb, yb) = (q & 1, q >> 1);
                // (side, child is on that side of its parent, sibling, mirrored child)
                let cases = [
                    (W, xb == 0, q & !1, q | 1),
                    (E, xb == 1, q | 1, q & !1),
                    (S, yb == 0, q & !2, q | 2),
                    (N, yb == 1, q | 2, q & !2),
                ];
                for (side, outer, sibling, mirrored) in cases {
                    links[side] = if !outer {
                        p.children + sibling
                    } else {
                        match p.links[side] {
                            NONE => NONE,
                            nb if nodes[nb as usize].children == NONE => nb,
                            nb => nodes[nb as usize].children + mirrored,
                        }
                    };
                }
                nodes[(p.children + q) as usize].links = links;
            }
        }
        Quadtree { nodes, items }
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }

    /// The most objects any leaf holds (1 unless objects are closer than the finest cell).
    pub fn max_leaf_objects(&self) -> usize {
        self.nodes
            .iter()
            .filter(|n| n.children == NONE)
            .map(|n| n.count as usize)
            .max()
            .unwrap_or(0)
    }

    /// The leaf under `from` containing `p`; across the axis of `entered` (the side of the
    /// node the ray came in through) the half on that side is taken, on the other axis the
    /// half containing `p` (ties: the one the ray heads into).
    fn descend(&self, mut id: u32, p: (f64, f64), d: (f64, f64), entered: Option<usize>) -> u32 {
        for _ in 0..=MAX_LEVEL + 1 {
            let Some(n) = self.nodes.get(id as usize) else {
                return NONE;
            };
            if n.children == NONE {
                return id;
            }
            let mid = ((n.min.0 + n.max.0) / 2.0, (n.min.1 + n.max.1) / 2.0);
            let east = match entered {
                Some(W) => false,
                Some(E) => true,
                _ => p.0 > mid.0 || (p.0 == mid.0 && d.0 > 0.0),
            };
            let north = match entered {
                Some(S) => false,
                Some(N) => true,
                _ => p.1 > mid.1 || (p.1 == mid.1 && d.1 > 0.0),
            };
            id = n.children + u32::from(east) + 2 * u32::from(north);
        }
        NONE
    }

    /// Parameters where the ray enters and leaves the root box, if it meets it.
    fn root_span(&self, o: (f64, f64), d: (f64, f64)) -> Option<(f64, f64)> {
        let r = self.nodes.first()?;
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for (oo, dd, lo, hi) in [(o.0, d.0, r.min.0, r.max.0), (o.1, d.1, r.min.1, r.max.1)] {
            if dd == 0.0 {
                if oo < lo || oo > hi {
                    return None;
                }
            } else {
                let (a, b) = ((lo - oo) / dd, (hi - oo) / dd);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }
}

impl Caster for Quadtree {
    fn nearest(
        &self,
        scene: &Prepared,
        o: (f64, f64),
        d: (f64, f64),
        exclude: Option<u32>,
    ) -> Option<RayHit> {
        let (t0, _) = self.root_span(o, d)?;
        let start = (o.0 + t0 * d.0, o.1 + t0 * d.1);
        let mut leaf = self.descend(0, start, d, None);
        let mut best: Option<RayHit> = None;
        // Objects already tested by this ray (a leaf holds at most one, so the last few
        // suffice to skip the common repeats).
        let mut recent: Branch = Branch::new();
        for _ in 0..self.nodes.len() + 4 {
            let n = self.nodes.get(leaf as usize)?;
            let range = n.first as usize..(n.first + n.count) as usize;
            for &obj in self.items.get(range).unwrap_or(&[]) {
                if Some(obj) == exclude || recent.iter().any(|r| r.0 == obj) {
                    continue;
                }
                if recent.is_full() {
                    recent.clear();
                }
                let _ = recent.push(vcx::ObjectId(obj));
                if let Some(h) = scene.enter(obj, o, d) {
                    if best.is_none_or(|b| h.t < b.t) {
                        best = Some(h);
                    }
                }
            }
            // Leave the leaf: the side whose line the ray reaches first.
            let tx = if d.0 > 0.0 {
                (n.max.0 - o.0) / d.0
            } else if d.0 < 0.0 {
                (n.min.0 - o.0) / d.0
            } else {
                f64::INFINITY
            };
            let ty = if d.1 > 0.0 {
                (n.max.1 - o.1) / d.1
            } else if d.1 < 0.0 {
                (n.min.1 - o.1) / d.1
            } else {
                f64::INFINITY
            };
            let (t_exit, side) = if tx <= ty {
                (tx, if d.0 > 0.0 { E } else { W })
            } else {
                (ty, if d.1 > 0.0 { N } else { S })
            };
            if best.is_some_and(|b| b.t <= t_exit) {
                return best;
            }
            let next = n.links[side];
            if next == NONE {
                return best;
            }
            let p = (o.0 + t_exit * d.0, o.1 + t_exit * d.1);
            // The neighbour's side we enter through is the opposite one.
            let entered = [E, W, N, S][side];
            leaf = self.descend(next, p, d, Some(entered));
        }
        best
    }
}
