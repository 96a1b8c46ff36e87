//! Ray trees: the primary view, then recursively what is seen through mirrors, refractive
//! objects and screens (DESIGN.md §6, the paper's §5).
//!
//! See the module documentation of [`crate::walk`] for the model; this file holds the
//! recursion. Every primary interval (a run of the primary walk with one ceiling) is a
//! *piece*: an exact open angular range `(from, to)` of directions from an eye, with the
//! object seen. A piece is resolved by its ceiling's material:
//!
//! * nothing or an opaque object (or any object once the depth is used up): a leaf;
//! * a screen S: the same eye walks the same range anchored to the layer whose floor is S
//!   ([`super::Anchor::Floor`]); its pieces are resolved in turn at the same level;
//! * a mirror M: the range is split where the hit edge changes (the directions to M's
//!   vertices); per edge the eye is reflected across the edge's line, rounded
//!   ([`super::optics`]), and the reflected range — reversed, mirrors flip orientation —
//!   is walked anchored to M;
//! * a refractive M: split by the entry edge, tangent-law eye at the entry edge, split by
//!   the exit edge (M's own vertices seen from that eye), tangent-law eye at the exit edge,
//!   walked anchored to M; orientation is preserved.
//!
//! Leaves come out in primary angular order; neighbours with equal branches are merged.

use alloc::rc::Rc;
use alloc::vec::Vec;
use core::cmp::Ordering;

use super::WalkError;
use crate::geom::predicates::Direction;
use crate::geom::sos::Angle;
use crate::geom::wide::{mod_p, residue_i128, Wide, P};
use crate::geom::{Point, QueryPoint, Sign};
use crate::partition::{Complex, Storage};
use crate::scene::{Material, ObjectId, SceneRef};
// Anchored walks (behind screens, mirrors and refractive objects).
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
use {
    super::{Anchor, Position},
    crate::line_space::{ranked, Bound, Chain},
    crate::partition::{Cylinder, CylinderId, Layer, Side, Wall},
};
// Changes of eye (mirrors and refractive objects).
#[cfg(any(feature = "mirrors", feature = "refraction"))]
use super::optics;

/// One interval of a ray-tree sweep: primary directions from `start` counter-clockwise to
/// the next interval's start, over which the branch is constant.
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

/// A range end: a direction from an eye, with the vertex it points at (and whether that
/// vertex is ahead of the eye) when it is the direction of an eye–vertex pair.
#[derive(Clone, Debug)]
struct Dir {
    angle: Angle,
    vertex: Option<(usize, bool)>,
    /// For an end placed in `f64` through a hop ([`Tree::map_end`]; `angle` is then
    /// rounded): the exact direction, so that events and vertices exactly on it are
    /// classified exactly (a vertex exactly on a mapped range end is a frequent
    /// degeneracy of grid scenes, `spurious_sliver_diagonal.rs`). `None` past `Wide`'s
    /// budget. Shared, not copied: a `Wide` pair is 272 bytes, and range ends are moved
    /// around a lot.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(dead_code)
    )]
    exact: Option<Rc<(Wide, Wide)>>,
}

impl Dir {
    fn vertex(angle: Angle, vertex: usize, ahead: bool) -> Dir {
        Dir {
            angle,
            vertex: Some((vertex, ahead)),
            exact: None,
        }
    }
}

/// Range ends against exact directions, for anchored walks and splits.
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
impl Dir {
    /// The sign of `cross(self, v)`: `Positive` if `v` lies counter-clockwise of this
    /// direction (within a half turn), exactly.
    fn turn(&self, v: (i128, i128)) -> Sign {
        match self.exact.as_deref().and_then(|x| Wide::cross(x, v)) {
            Some(c) => c.sign(),
            None => Sign::of_i128(cross(self.angle.vector(), v)),
        }
    }

    /// Where the event direction `a`, met by a walk of a range, lies against this range
    /// end: `Equal` exactly on it, `Less` before it, `Greater` after it (the walk's range is
    /// less than a half turn, so the side of the line decides). Without an exact
    /// direction only `Equal` is decided (`inside` otherwise: the walk itself orders
    /// events against an exact end).
    fn place(&self, a: &Angle, inside: Ordering) -> Ordering {
        if self.exact.is_none() {
            return if a.cmp_exact(&self.angle) == Ordering::Equal {
                Ordering::Equal
            } else {
                inside
            };
        }
        match self.turn(a.vector()) {
            Sign::Positive => Ordering::Greater,
            Sign::Zero => Ordering::Equal,
            Sign::Negative => Ordering::Less,
        }
    }
}

/// How the vertex of a boundary is found once the branches on both sides are known (the
/// reference's rule): among the stages of the ray at the boundary (the primary stage, then
/// one per hop), the first one whose ray, beyond its origin, holds a vertex of the object
/// that stage hits on either side; the vertex nearest to that stage's eye. Every stage is
/// tested exactly, earlier ones on the boundary direction mapped back through the hops in
/// 1024-bit integers ([`Tree::map_hop_exact`], up to 9 hops); beyond that in `f64` with a
/// relative tolerance of 10⁻¹² (a tolerance took a vertex 6·10⁻¹³ rad off the ray,
/// `boundary_vertex_mirror_corner.rs`).
#[derive(Clone, Debug)]
struct Rule {
    /// The hops up to the stage where the boundary arises (shared with the tree's stack).
    hops: Rc<[Hop]>,
    /// The eye of that stage and the exact direction of the boundary from it.
    eye: QueryPoint,
    dir: (i128, i128),
    /// Branch index of the object hit by that stage.
    level: usize,
    /// The vertex that caused the boundary, if no vertex is found by the rule.
    fallback: Option<usize>,
}

/// A boundary between pieces: its primary angle is computed from the rule
/// ([`Tree::radians`]) only if it starts an interval.
#[derive(Clone, Debug)]
struct Boundary {
    exact: Option<Angle>,
    rule: Rule,
}

/// An exact open range of directions from an eye with the object seen over it.
#[derive(Clone)]
struct Piece {
    from: Dir,
    to: Dir,
    ceiling: Option<ObjectId>,
    boundary: Boundary,
}

struct Leaf {
    branch: Vec<ObjectId>,
    boundary: Boundary,
}

/// One change of eye: a ray from `prev` hits the line of the edge `a → b` (global vertex
/// indices) and continues on a line through `next`.
#[derive(Clone, Copy, Debug)]
struct Hop {
    prev: QueryPoint,
    a: usize,
    b: usize,
    next: QueryPoint,
    /// Branch index of the object hit by the stage starting at this hop.
    level: usize,
}

struct Tree<'a, 's, S: Storage> {
    complex: &'a Complex<S>,
    scene: &'a SceneRef<'s>,
    /// The changes of eye down to the current level: replaced, not mutated, on a hop, so
    /// that every boundary of a level shares it.
    hops: Rc<[Hop]>,
    branch: Vec<ObjectId>,
    /// Scratch for the events of an anchored walk.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(dead_code)
    )]
    events: core::cell::Cell<Vec<(Dir, Option<ObjectId>)>>,
}

/// The ray trees from the free point `q` to depth `depth` over the full circle: intervals
/// sorted by start angle, each with its branch and the vertex causing its start boundary
/// (the last interval continues through θ = 0 into the first). Neighbouring intervals have
/// different branches. Build the complex over the whole scene, screens included.
///
/// Errors: `q` not free; a rounded virtual eye degenerate or out of range; an anchored
/// walk that finds no start cylinder (a rounded range end that misses the object's sheet).
///
/// Any storage: an owned complex, or one over caller slices (`Complex::from_slices`, e.g.
/// decoded by `format::decode_into`); the tree itself allocates (`alloc`).
pub fn ray_tree<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
) -> Result<Vec<TreeInterval>, WalkError> {
    sweep(complex, scene, q, depth, None, true)
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
/// walk is the full one (starting it at `from` needs point location in a history).
pub fn ray_tree_range<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
    from: Direction,
    to: Direction,
) -> Result<Vec<TreeInterval>, WalkError> {
    sweep(complex, scene, q, depth, Some((from, to)), true)
}

/// The ray tree over a field of view as a frame draws it: the intervals of
/// [`ray_tree_range`] without their boundary vertices (`start_vertex` is always `None`),
/// which spares the vertex rule's mapping of every boundary back through its hops.
pub fn frame_tree<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
    from: Direction,
    to: Direction,
) -> Result<Vec<TreeInterval>, WalkError> {
    sweep(complex, scene, q, depth, Some((from, to)), false)
}

fn sweep<S: Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    q: QueryPoint,
    depth: usize,
    range: Option<(Direction, Direction)>,
    vertices: bool,
) -> Result<Vec<TreeInterval>, WalkError> {
    let mut tree = Tree {
        complex,
        scene,
        hops: Rc::from(Vec::new()),
        branch: Vec::new(),
        events: Default::default(),
    };
    let range = range.map(|(f, t)| (Angle::constant(f), Angle::constant(t)));
    let pieces = match tree.primary(q)? {
        Ok(pieces) => pieces,
        Err(object) => {
            return Ok(alloc::vec![TreeInterval {
                start: range.map_or(0.0, |r| r.0.radians()),
                exact_start: range.map(|r| r.0),
                branch: object.into_iter().collect(),
                start_vertex: None,
            }])
        }
    };
    let mut leaves = Vec::new();
    let Some((f, t)) = range else {
        for p in pieces {
            tree.piece(q, depth, p, &mut leaves)?;
        }
        return Ok(tree.assemble(&leaves));
    };
    let (context, inside) = tree.clip(q, pieces, f, t, vertices);
    // A boundary exactly on `from` is resolved against the last leaf before it.
    let mut before = Vec::new();
    if let Some(p) = context {
        tree.piece(q, depth, p, &mut before)?;
    }
    for p in inside {
        tree.piece(q, depth, p, &mut leaves)?;
    }
    let mut out: Vec<TreeInterval> = Vec::new();
    let mut prev = before.last().map(|l| &l.branch);
    for (i, leaf) in leaves.iter().enumerate() {
        let start_vertex = match prev {
            // Inside the range, equal neighbours merge; the first interval starts at `from`
            // even where the full tree has no boundary.
            Some(left) if *left == leaf.branch && i > 0 => continue,
            Some(left) if *left != leaf.branch && vertices => {
                tree.resolve(&leaf.boundary.rule, left, &leaf.branch)
            }
            _ => None,
        };
        out.push(TreeInterval {
            start: if i == 0 {
                f.radians()
            } else {
                tree.radians(&leaf.boundary)
            },
            exact_start: if i == 0 { Some(f) } else { leaf.boundary.exact },
            branch: leaf.branch.clone(),
            start_vertex,
        });
        prev = Some(&leaf.branch);
    }
    Ok(out)
}

impl<S: Storage> Tree<'_, '_, S> {
    /// The primary pieces (cyclic, in angular order) restricted to the range from `f`
    /// counter-clockwise to `t` (the full circle if equal), in order from `f`, the first
    /// starting at `f` and the last ending at `t`; and the left side of `f` when a boundary
    /// of the full tree may lie exactly on `f`: the piece before when a piece starts there,
    /// else the containing piece up to `f` when a vertex that can cause a primary-level
    /// boundary (one of the piece's object, or any behind a screen) lies on the ray — only
    /// if `context` (the vertex of that boundary is wanted).
    fn clip(
        &self,
        q: QueryPoint,
        pieces: Vec<Piece>,
        f: Angle,
        t: Angle,
        context: bool,
    ) -> (Option<Piece>, Vec<Piece>) {
        let n = pieces.len();
        // Position counter-clockwise from `f`: (lap, angle), lap 1 for directions before `f`.
        let lap = |a: &Angle| u8::from(a.cmp_exact(&f) == Ordering::Less);
        let before = |(la, a): (u8, &Angle), (lb, b): (u8, &Angle)| {
            la < lb || (la == lb && a.cmp_exact(b) == Ordering::Less)
        };
        let end = (
            if t.cmp_exact(&f) == Ordering::Greater {
                0
            } else {
                1
            },
            &t,
        );
        // The piece containing `f`: the last one starting at or before it, else the last one
        // (it wraps through θ = 0).
        let k0 = pieces
            .iter()
            .rposition(|p| p.from.angle.cmp_exact(&f) != Ordering::Greater)
            .unwrap_or(n.saturating_sub(1));
        let at = |f: Angle| Dir {
            angle: f,
            vertex: None,
            exact: None,
        };
        let on_f = pieces
            .get(k0)
            .is_some_and(|p| p.from.angle.cmp_exact(&f) == Ordering::Equal);
        let context = if !context {
            None
        } else if on_f {
            pieces.get((k0 + n - 1) % n).cloned()
        } else {
            pieces
                .get(k0)
                .filter(|p| self.vertex_on_ray(q, &f, p.ceiling))
                .map(|p| Piece {
                    to: at(f),
                    ..p.clone()
                })
        };
        // Where the `j`-th piece from `k0` starts (j ≤ n; the n-th is `k0` again, on lap 1
        // unless it starts after `f`), counter-clockwise from `f`.
        let pos = |j: usize| -> (u8, &Angle) {
            match pieces.get((k0 + j) % n).map(|p| &p.from.angle) {
                Some(a) if j == 0 => (0, a),
                Some(a) if j < n => (lap(a), a),
                Some(a) if j == n => (lap(a).max(u8::from(on_f)), a),
                _ => (2, &f),
            }
        };
        let mut out: Vec<Piece> = Vec::new();
        for j in 0..=n {
            let Some(mut p) = pieces.get((k0 + j) % n).cloned() else {
                break;
            };
            if j > 0 && !before(pos(j), end) {
                break;
            }
            if j == 0 && !on_f {
                p.from = at(f);
                p.boundary = Boundary {
                    exact: Some(f),
                    rule: Rule {
                        hops: self.hops.clone(),
                        eye: q,
                        dir: f.vector(),
                        level: 0,
                        fallback: None,
                    },
                };
            }
            let last = !before(pos(j + 1), end);
            if last {
                p.to = at(t);
            }
            out.push(p);
            if last {
                break;
            }
        }
        (context, out)
    }

    /// Whether a vertex that can make a primary-level boundary lies exactly on the ray from
    /// `q` at `f`: one of `ceiling` (mirror and refraction splits), or any vertex if
    /// `ceiling` is a screen (events of the walk behind it).
    fn vertex_on_ray(&self, q: QueryPoint, f: &Angle, ceiling: Option<ObjectId>) -> bool {
        let Some(obj) = ceiling.and_then(|c| self.scene.object(c)) else {
            return false;
        };
        let range = if obj.material == Material::Screen {
            0..self.scene.vertices().len()
        } else {
            obj.first_vertex()..obj.first_vertex() + obj.len()
        };
        let d = f.vector();
        // Bit budget: |d| ≤ 2⁶³, |v − q| ≤ 2⁵⁴: products < 2¹¹⁸, exact in `i128`.
        range.into_iter().any(|v| {
            let w = diff(self.qpoint(v), q);
            cross(d, w) == 0 && d.0 * w.0 + d.1 * w.1 > 0
        })
    }
}

fn side(a: QueryPoint, b: QueryPoint, p: QueryPoint) -> Sign {
    let (ex, ey) = (
        i128::from(b.x()) - i128::from(a.x()),
        i128::from(b.y()) - i128::from(a.y()),
    );
    let (px, py) = (
        i128::from(p.x()) - i128::from(a.x()),
        i128::from(p.y()) - i128::from(a.y()),
    );
    Sign::of_i128(ex * py - ey * px)
}

/// Whether `a` lies exactly at θ = 0 but the perturbation puts it just below 2π.
#[cfg(any(feature = "mirrors", feature = "refraction", feature = "screens"))]
fn wraps(a: &Angle) -> bool {
    a.cmp_exact(&Angle::ZERO) == Ordering::Equal
        && a.cmp_angle(&Angle::constant(Direction { x: 1, y: -1 })) == Ordering::Greater
}

fn cross(u: (i128, i128), v: (i128, i128)) -> i128 {
    u.0 * v.1 - u.1 * v.0
}

fn diff(p: QueryPoint, e: QueryPoint) -> (i128, i128) {
    (
        i128::from(p.x()) - i128::from(e.x()),
        i128::from(p.y()) - i128::from(e.y()),
    )
}

impl<S: Storage> Tree<'_, '_, S> {
    fn point(&self, i: usize) -> Point {
        self.scene.vertices().get(i).copied().unwrap_or_default()
    }

    fn qpoint(&self, i: usize) -> QueryPoint {
        self.point(i).to_query()
    }

    /// The primary pieces from a full walk, or the object seen all around if the view has
    /// no boundary.
    #[allow(clippy::type_complexity)]
    fn primary(&self, q: QueryPoint) -> Result<Result<Vec<Piece>, Option<ObjectId>>, WalkError> {
        let mut first: Option<Option<ObjectId>> = None;
        let mut events: Vec<(Dir, Option<ObjectId>)> = Vec::new();
        self.complex.walk_trace(self.scene, q, |s| {
            let ceiling = self.complex.ceiling(s.cylinder);
            match (first, s.vertex) {
                (None, _) => first = Some(ceiling),
                (Some(_), Some(v)) if s.ahead => {
                    events.push((Dir::vertex(s.angle, v, true), ceiling))
                }
                _ => {}
            }
        })?;
        let start_object = first.flatten();
        // Events exactly at θ = 0 may be perturbed to just below 2π: move them to the front.
        let at_zero = events
            .iter()
            .rev()
            .take_while(|e| e.0.angle.cmp_exact(&Angle::ZERO) == Ordering::Equal)
            .count();
        let mut seen = match events.len().checked_sub(at_zero + 1) {
            Some(k) if at_zero > 0 => events[k].1,
            _ => start_object,
        };
        events.rotate_right(at_zero);
        // Clusters of events on one exact ray where the object changes: (first, last, after).
        let mut clusters: Vec<(Dir, Dir, Option<ObjectId>)> = Vec::new();
        let mut i = 0;
        while i < events.len() {
            let mut j = i + 1;
            while j < events.len()
                && events[j].0.angle.cmp_exact(&events[i].0.angle) == Ordering::Equal
            {
                j += 1;
            }
            let after = events[j - 1].1;
            if after != seen {
                clusters.push((events[i].0.clone(), events[j - 1].0.clone(), after));
                seen = after;
            }
            i = j;
        }
        if clusters.is_empty() {
            return Ok(Err(start_object));
        }
        let n = clusters.len();
        Ok(Ok((0..n)
            .map(|k| {
                let (first, last, after) = clusters[k].clone();
                Piece {
                    from: last,
                    to: clusters[(k + 1) % n].0.clone(),
                    ceiling: after,
                    boundary: self.event_boundary(q, &first),
                }
            })
            .collect()))
    }

    /// The boundary made by a walk event at the current level.
    fn event_boundary(&self, eye: QueryPoint, d: &Dir) -> Boundary {
        let dir = d.angle.vector();
        Boundary {
            exact: self.hops.is_empty().then_some(d.angle),
            rule: Rule {
                hops: Rc::clone(&self.hops),
                eye,
                dir,
                level: self.branch.len(),
                fallback: d.vertex.map(|v| v.0),
            },
        }
    }

    /// The primary angle (radians, `f64`) of a boundary: its direction intersected with
    /// each hop's edge line, continued from the previous eye.
    fn radians(&self, b: &Boundary) -> f64 {
        let d = self.map_dir(&b.rule.hops, b.rule.eye, b.rule.dir);
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
    /// from the first hop's `prev` eye (`f64`). Per hop the hit point `X = cur + t·d` on the
    /// edge's line is taken relative to the previous eye as `(cur − prev) + t·d`, with the
    /// numerator of `t` exact: no term is much larger than the result, so an eye next to
    /// the edge loses no precision (`X − prev` as `(a − prev) + u·(b − a)` cancels there).
    fn map_dir(&self, hops: &[Hop], eye: QueryPoint, dir: (i128, i128)) -> (f64, f64) {
        let mut d = (dir.0 as f64, dir.1 as f64);
        let mut cur = eye;
        for hop in hops.iter().rev() {
            let (a, b) = (self.qpoint(hop.a), self.qpoint(hop.b));
            let e = diff(b, a);
            let ef = (e.0 as f64, e.1 as f64);
            let den = d.0 * ef.1 - d.1 * ef.0;
            d = if den == 0.0 {
                // Along the edge's line: its midpoint.
                let ap = diff(a, hop.prev);
                (ap.0 as f64 + 0.5 * ef.0, ap.1 as f64 + 0.5 * ef.1)
            } else {
                let t = cross(diff(a, cur), e) as f64 / den;
                let cp = diff(cur, hop.prev);
                (cp.0 as f64 + t * d.0, cp.1 as f64 + t * d.1)
            };
            cur = hop.prev;
        }
        d
    }

    /// Resolves the piece `p` seen from `eye` by its ceiling's material into leaves.
    // Without any ray type past the primary view, the eye is not needed.
    #[cfg_attr(
        not(any(feature = "mirrors", feature = "refraction", feature = "screens")),
        allow(unused_variables)
    )]
    fn piece(
        &mut self,
        eye: QueryPoint,
        depth: usize,
        p: Piece,
        out: &mut Vec<Leaf>,
    ) -> Result<(), WalkError> {
        let Some(c) = p.ceiling else {
            out.push(Leaf {
                branch: self.branch.clone(),
                boundary: p.boundary,
            });
            return Ok(());
        };
        let material = self.scene.object(c).ok_or(WalkError::Corrupt)?.material;
        match material {
            #[cfg(feature = "screens")]
            Material::Screen => {
                for sp in self.floor_pieces(eye, c, &p.from, &p.to, p.boundary)? {
                    self.piece(eye, depth, sp, out)?;
                }
                Ok(())
            }
            #[cfg(feature = "mirrors")]
            Material::Mirror if depth > 0 => self.mirror(eye, c, &p, depth, out),
            #[cfg(feature = "refraction")]
            Material::Refractive { eta } if depth > 0 => {
                self.refractive(eye, c, eta, &p, depth, out)
            }
            // The ray type's code is compiled out (cargo features): an error, never a tree
            // that silently stops at the object.
            _ if continues(material, depth) => Err(WalkError::RayTypeDisabled {
                object: c,
                material,
            }),
            _ => {
                let mut branch = self.branch.clone();
                branch.push(c);
                out.push(Leaf {
                    branch,
                    boundary: p.boundary,
                });
                Ok(())
            }
        }
    }

    /// Merges neighbouring leaves with equal branches and resolves the boundary vertices.
    fn assemble(&self, leaves: &[Leaf]) -> Vec<TreeInterval> {
        let m = leaves.len();
        let starts: Vec<usize> = (0..m)
            .filter(|&i| leaves[(i + m - 1) % m].branch != leaves[i].branch)
            .collect();
        if starts.is_empty() {
            return alloc::vec![TreeInterval {
                start: 0.0,
                exact_start: None,
                branch: leaves.first().map(|l| l.branch.clone()).unwrap_or_default(),
                start_vertex: None,
            }];
        }
        let mut out: Vec<TreeInterval> = starts
            .iter()
            .map(|&i| {
                let (left, right) = (&leaves[(i + m - 1) % m], &leaves[i]);
                TreeInterval {
                    start: self.radians(&right.boundary),
                    exact_start: right.boundary.exact,
                    branch: right.branch.clone(),
                    start_vertex: self.resolve(&right.boundary.rule, &left.branch, &right.branch),
                }
            })
            .collect();
        out.sort_by(|a, b| a.start.total_cmp(&b.start));
        out
    }

    fn resolve(&self, rule: &Rule, left: &[ObjectId], right: &[ObjectId]) -> Option<usize> {
        let stages = rule.hops.len();
        // The boundary direction at every earlier stage modulo P, mapped back hop by hop
        // once: most stages hold no candidate vertex on the ray, which different residues
        // prove; the 1024-bit mapping is made only when a candidate passes.
        let mut residues: Vec<Option<(u64, u64)>> = alloc::vec![None; stages];
        let mut r = Some((residue_i128(rule.dir.0), residue_i128(rule.dir.1)));
        for st in (0..stages).rev() {
            let cur = rule.hops.get(st + 1).map_or(rule.eye, |h| h.prev);
            r = r.and_then(|r| self.map_hop_residue(rule.hops.get(st)?, cur, r));
            if let Some(slot) = residues.get_mut(st) {
                *slot = r;
            }
        }
        let mut mapped: Option<Vec<Option<(Wide, Wide)>>> = None;
        for st in 0..=stages {
            let (eye, level, origin) = match st.checked_sub(1).and_then(|i| rule.hops.get(i)) {
                None => (rule.hops.first().map_or(rule.eye, |h| h.prev), 0, None),
                Some(h) => (h.next, h.level, Some((h.a, h.b))),
            };
            let level = if st == stages { rule.level } else { level };
            let owners = [left.get(level), right.get(level)];
            // The vertices of the objects this stage hits on either side, beyond the
            // stage's origin edge (a ray leaving a mirror or refractive edge).
            let origin = origin.map(|(ia, ib)| {
                let (a, b) = (self.qpoint(ia), self.qpoint(ib));
                (a, b, side(a, b, eye))
            });
            let candidates = owners
                .iter()
                .enumerate()
                .filter(|&(k, id)| id.is_some() && !(k == 1 && owners[0] == *id))
                .filter_map(|(_, id)| self.scene.object(*(*id)?))
                .flat_map(|obj| obj.first_vertex()..obj.first_vertex() + obj.len())
                .filter(|&v| {
                    origin.is_none_or(|(a, b, se)| {
                        let sw = side(a, b, self.qpoint(v));
                        sw != Sign::Zero && sw != se
                    })
                });
            let hops = rule.hops.get(st..).unwrap_or(&[]);
            if hops.is_empty() {
                // The stage where the boundary arises: `i128` suffices (products < 2¹⁰⁸).
                let best = nearest_on_ray(candidates, |v| {
                    let w = diff(self.qpoint(v), eye);
                    (cross(rule.dir, w) == 0).then_some(rule.dir.0 * w.0 + rule.dir.1 * w.1)
                });
                return best.or(rule.fallback);
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
            let mapped = mapped.get_or_insert_with(|| self.map_exact(rule));
            let best = match mapped.get(st).and_then(Option::as_ref) {
                Some(d) => nearest_on_ray(candidates, |v| {
                    let w = diff(self.qpoint(v), eye);
                    (Wide::cross(d, w)?.sign() == Sign::Zero)
                        .then(|| Wide::dot(d, w))
                        .flatten()
                }),
                None => {
                    // Past the exact budget (more hops than `Wide` holds): `f64`.
                    let d = self.map_dir(hops, rule.eye, rule.dir);
                    nearest_on_ray(candidates, |v| {
                        let w = diff(self.qpoint(v), eye);
                        let wf = (w.0 as f64, w.1 as f64);
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
        rule.fallback
    }

    /// The boundary direction of `rule` at every stage before the last, mapped back hop by
    /// hop exactly ([`Tree::map_hop_exact`]); `None` past `Wide`'s budget.
    fn map_exact(&self, rule: &Rule) -> Vec<Option<(Wide, Wide)>> {
        let stages = rule.hops.len();
        let mut mapped: Vec<Option<(Wide, Wide)>> = alloc::vec![None; stages];
        let mut d = Some((Wide::from_i128(rule.dir.0), Wide::from_i128(rule.dir.1)));
        for st in (0..stages).rev() {
            let cur = rule.hops.get(st + 1).map_or(rule.eye, |h| h.prev);
            d = d.and_then(|d| self.map_hop_exact(rule.hops.get(st)?, cur, &d));
            if let Some(slot) = mapped.get_mut(st) {
                *slot = d;
            }
        }
        mapped
    }

    /// [`Tree::map_hop_exact`] modulo `P` (`wide::mod_p`), up to sign: `None` when the
    /// hit's denominator may be zero (its residue is), where the exact hop takes the
    /// edge's midpoint instead. Equal exact directions have equal residues up to sign, so
    /// different residues of a cross product's two terms prove it nonzero.
    fn map_hop_residue(&self, hop: &Hop, cur: QueryPoint, d: (u64, u64)) -> Option<(u64, u64)> {
        let mul = |a: u64, b: u64| mod_p(u128::from(a) * u128::from(b));
        let add = |a: u64, b: u64| mod_p(u128::from(a) + u128::from(b));
        let a = self.qpoint(hop.a);
        let e = diff(self.qpoint(hop.b), a);
        let (e0, e1) = (residue_i128(e.0), residue_i128(e.1));
        let den = add(mul(d.0, e1), P - mul(d.1, e0));
        if den == 0 {
            return None;
        }
        let (num, cp) = (residue_i128(cross(diff(a, cur), e)), diff(cur, hop.prev));
        Some((
            add(mul(den, residue_i128(cp.0)), mul(d.0, num)),
            add(mul(den, residue_i128(cp.1)), mul(d.1, num)),
        ))
    }

    /// One hop of [`Tree::map_dir`] exactly: the direction `d` from `cur` (the eye after
    /// `hop`) mapped back to a direction from `hop.prev`, scaled by the hit's denominator;
    /// `None` past `Wide`'s 1024 bits. Bit budget: a direction of `b` bits becomes one of
    /// at most `b + 102` (query differences ≤ 2⁵³, edges ≤ 2⁴⁸), so 9 hops from a 54-bit
    /// direction fit and the final cross with a query difference too.
    fn map_hop_exact(&self, hop: &Hop, cur: QueryPoint, d: &(Wide, Wide)) -> Option<(Wide, Wide)> {
        let a = self.qpoint(hop.a);
        let e = diff(self.qpoint(hop.b), a);
        let den = Wide::cross(d, e)?;
        Some(match den.sign() {
            // Along the edge's line: its midpoint, as `map_dir`.
            Sign::Zero => {
                let ap = diff(a, hop.prev);
                (
                    Wide::from_i128(2 * ap.0 + e.0),
                    Wide::from_i128(2 * ap.1 + e.1),
                )
            }
            // `X − prev = (cur − prev) + (num / den)·d`, times `|den|`.
            s => {
                let (num, cp) = (cross(diff(a, cur), e), diff(cur, hop.prev));
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
    /// Whether a vertex of `object` lies exactly on the line through `eye` with the
    /// direction of `a`. Bit budget: |a| ≤ 2⁶³, |v − eye| ≤ 2⁵⁴: products < 2¹¹⁸.
    fn vertex_on_line(&self, eye: QueryPoint, a: &Angle, object: ObjectId) -> bool {
        let d = a.vector();
        self.scene.object(object).is_some_and(|o| {
            (o.first_vertex()..o.first_vertex() + o.len())
                .any(|v| cross(d, diff(self.qpoint(v), eye)) == 0)
        })
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
        let Some(obj) = self.scene.object(chain.object) else {
            return Sign::Zero;
        };
        let (first, n) = (obj.first_vertex(), obj.len());
        let (some, none) = match chain.bound {
            Bound::Lower => (Sign::Negative, Sign::Positive),
            Bound::Upper => (Sign::Positive, Sign::Negative),
        };
        if (first..first + n).any(|v| self.side_after(eye, from, v, ccw) == some) {
            some
        } else {
            none
        }
    }

    /// The cylinder with floor `m` containing the line through `eye` just after the range
    /// start `from` — turned by an infinitesimal that exceeds the symbolic perturbation, so
    /// that everything exactly on the opening ray is behind (the range is open) — and the
    /// angle to start walking from: the perturbed direction of the last tangent of the
    /// cylinder's chains exactly on the opening ray, or `from` (the walk would otherwise
    /// cross those tangents again).
    fn locate_floor(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        from: &Dir,
    ) -> Result<(CylinderId, Angle), WalkError> {
        let angle = &from.angle;
        let id = match self.stack_floor(eye, m, angle) {
            Some(id) => id,
            None => self.scan_floor(eye, m, angle, true)?,
        };
        let c = self.complex.cylinder(id).ok_or(WalkError::Corrupt)?;
        // The turned line lies past θ = 0: an opening ray exactly at θ = 0 that the
        // perturbation puts just below 2π starts the walk at θ = 0 instead.
        let mut theta = if wraps(angle) { Angle::ZERO } else { *angle };
        for chain in [c.bottom, c.top].into_iter().flatten() {
            // Only a vertex exactly on the opening line can make a tangent exactly on it.
            if chain.object == m || !self.vertex_on_line(eye, angle, chain.object) {
                continue;
            }
            let (tangents, count) = crate::line_space::tangents_from(self.scene, chain.object, eye);
            for &(h, _) in tangents.iter().take(count) {
                let fwd = Angle::from_query(eye, ranked(self.scene, h));
                for a in [fwd, fwd.reversed()] {
                    if a.cmp_exact(angle) == Ordering::Equal
                        && !wraps(&a)
                        && a.cmp_angle(&theta) == Ordering::Greater
                    {
                        theta = a;
                    }
                }
            }
        }
        Ok((id, theta))
    }

    /// Whether the cylinder `c` contains the line through `eye` just after `from` (see
    /// [`Tree::locate_floor`]): walls exactly at `from` lie behind it; a wall exactly at
    /// θ = 0 that the perturbation puts just below 2π counts as 2π.
    fn contains_after(&self, eye: QueryPoint, from: &Angle, c: &Cylinder, ccw: bool) -> bool {
        let cmp_wall = |a: &Angle| {
            if wraps(a) {
                Ordering::Greater
            } else {
                a.cmp_exact(from)
            }
        };
        let wall = |w: Wall, left: bool| match self.complex.wall_angle(self.scene, w) {
            None => true,
            // Turned counter-clockwise, walls exactly at the angle are behind; clockwise,
            // ahead.
            Some(a) if left && ccw => cmp_wall(&a) != Ordering::Greater,
            Some(a) if left => cmp_wall(&a) == Ordering::Less,
            Some(a) if ccw => cmp_wall(&a) == Ordering::Greater,
            Some(a) => cmp_wall(&a) != Ordering::Less,
        };
        wall(c.left, true)
            && wall(c.right, false)
            && c.bottom
                .is_none_or(|b| self.chain_after(eye, from, b, ccw) == Sign::Negative)
            && c.top
                .is_none_or(|t| self.chain_after(eye, from, t, ccw) == Sign::Positive)
    }

    /// The start cylinder found through the per-chain tilings: the cylinders with floor `m`
    /// at `from` (perturbed) stack up from `m`'s lower chain to its upper one; climb from
    /// the nearer end until the next chain lies beyond the eye's line. O(log n) per tiling lookup plus the height of the stack.
    /// `None` where something lies exactly on the opening ray and the perturbed angle and
    /// the turned line disagree (the caller then scans).
    fn stack_floor(&self, eye: QueryPoint, m: ObjectId, from: &Angle) -> Option<CylinderId> {
        // Climb from the end of `m`'s sheet nearer to the eye's line: an `f64` estimate
        // only picks the end, either climb is exact.
        let up = self.nearer_lower(eye, m, from);
        let (start, side, inward) = if up {
            (Bound::Lower, Side::Above, Sign::Negative)
        } else {
            (Bound::Upper, Side::Below, Sign::Positive)
        };
        let first = Chain {
            object: m,
            bound: start,
        };
        if self.chain_after(eye, from, first, true) != inward {
            return None;
        }
        // The tilings are searched at the perturbed angle, on the turned line's lap.
        let probe = if wraps(from) { Angle::ZERO } else { *from };
        let mut id = self
            .complex
            .across(self.scene, first, side, Layer::After, &probe)?;
        for _ in 0..self.complex.cylinders().len() {
            let c = self.complex.cylinder(id)?;
            if c.floor != Some(m) {
                return None;
            }
            let next = match if up { c.top } else { c.bottom } {
                Some(t) if self.chain_after(eye, from, t, true) != inward.flip() => t,
                _ => return self.contains_after(eye, from, c, true).then_some(id),
            };
            // Beyond a chain whose object lies on the far side (above a lower chain, below
            // an upper one) that object is crossed: the layer ending there.
            let layer = if next.bound == start {
                Layer::Before
            } else {
                Layer::Around
            };
            id = self.complex.across(self.scene, next, side, layer, &probe)?;
        }
        None
    }

    /// Whether the eye's line at `from` lies nearer (in `f64`) to `m`'s lower chain than to
    /// its upper one.
    fn nearer_lower(&self, eye: QueryPoint, m: ObjectId, from: &Angle) -> bool {
        let d = from.vector();
        let d = (d.0 as f64, d.1 as f64);
        let Some(obj) = self.scene.object(m) else {
            return true;
        };
        let (lo, hi) = (obj.first_vertex()..obj.first_vertex() + obj.len())
            .map(|v| {
                let w = diff(self.qpoint(v), eye);
                d.0 * w.1 as f64 - d.1 * w.0 as f64
            })
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), u| {
                (lo.min(u), hi.max(u))
            });
        -lo <= hi
    }

    /// [`Tree::stack_floor`] by a scan over the cylinders: O(cylinders), for the
    /// degenerate cases only. With `ccw` false, the line turned clockwise (just before
    /// `from`).
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
            .find(|(_, c)| c.floor == Some(m) && self.contains_after(eye, from, c, ccw))
            .and_then(|(i, _)| CylinderId::from_index(i))
            .ok_or(WalkError::NoStart)
    }

    /// Walks `(from, to)` from `eye` anchored to the floor `m` and cuts it into pieces; the
    /// first piece starts with `first`.
    fn floor_pieces(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        from: &Dir,
        to: &Dir,
        first: Boundary,
    ) -> Result<Vec<Piece>, WalkError> {
        if from.angle.cmp_exact(&to.angle) == Ordering::Equal {
            // Both ends placed on one direction (`map_range`): the range is thinner than
            // `f64` resolves and lies on one side of it, the side where the line meets
            // `m`'s sheet — just before the direction, else just after it. One piece;
            // never a walk around the full circle.
            let id = match self.scan_floor(eye, m, &to.angle, false) {
                Err(WalkError::NoStart) => self.locate_floor(eye, m, from)?.0,
                r => r?,
            };
            return Ok(alloc::vec![Piece {
                from: from.clone(),
                to: to.clone(),
                ceiling: self.complex.ceiling(id),
                boundary: first,
            }]);
        }
        let (start, theta) = self.locate_floor(eye, m, from)?;
        let lap = if to.angle.cmp_angle(&theta) == Ordering::Greater {
            0
        } else {
            1
        };
        // The events buffer of the last anchored walk, reused (walks do not nest).
        let mut events = self.events.take();
        events.clear();
        self.complex.walk_from(
            self.scene,
            eye,
            Anchor::Floor(m),
            start,
            theta,
            Some(Position {
                lap,
                angle: to.angle,
            }),
            &mut |s| {
                if let Some(v) = s.vertex {
                    events.push((
                        Dir::vertex(s.angle, v, s.ahead),
                        self.complex.ceiling(s.cylinder),
                    ));
                }
            },
        )?;
        let mut seen = self.complex.ceiling(start);
        let mut pieces = Vec::new();
        let (mut cur_from, mut cur_boundary, mut end) = (from.clone(), first, to.clone());
        let mut i = 0;
        while i < events.len() {
            let mut j = i + 1;
            while j < events.len()
                && events[j].0.angle.cmp_exact(&events[i].0.angle) == Ordering::Equal
            {
                j += 1;
            }
            let d = &events[i].0;
            match to.place(&d.angle, Ordering::Less) {
                // On the closing ray: not inside the open range.
                Ordering::Equal => {
                    end = d.clone();
                    break;
                }
                // Past the exact end, before the rounded one.
                Ordering::Greater => break,
                Ordering::Less => {}
            }
            let after = events[j - 1].1;
            let opening = from.place(&d.angle, Ordering::Greater);
            if opening != Ordering::Greater {
                // On the opening ray (or before the exact start, after the rounded one):
                // part of the state at the start.
                seen = after;
                if opening == Ordering::Equal {
                    cur_from = events[j - 1].0.clone();
                }
            } else if after != seen {
                pieces.push(Piece {
                    from: cur_from,
                    to: d.clone(),
                    ceiling: seen,
                    boundary: cur_boundary,
                });
                cur_from = events[j - 1].0.clone();
                cur_boundary = self.event_boundary(eye, d);
                seen = after;
            }
            i = j;
        }
        pieces.push(Piece {
            from: cur_from,
            to: end,
            ceiling: seen,
            boundary: cur_boundary,
        });
        self.events.set(events);
        Ok(pieces)
    }
}

/// Changes of eye: splitting a range by the edges of a mirror or refractive object, the
/// virtual eyes and the ranges seen from them.
#[cfg(any(feature = "mirrors", feature = "refraction"))]
impl<S: Storage> Tree<'_, '_, S> {
    fn toward(&self, eye: QueryPoint, v: usize) -> Dir {
        Dir::vertex(Angle::from_query(eye, ranked(self.scene, v)), v, true)
    }

    /// The boundary where the hit (or exit) edge changes at vertex `v` seen from `eye`.
    fn split_boundary(&self, eye: QueryPoint, v: usize) -> Boundary {
        self.event_boundary(eye, &self.toward(eye, v))
    }

    /// The range end `end` (a direction from `hop.prev`) seen from `hop.next`: exact if it
    /// points at an endpoint of the hop's edge (or the hit point falls on or beyond one),
    /// otherwise the direction to the hit point on the edge's line, computed in `f64` (it
    /// only places the range end; the angular error is about 2⁻⁵² rad).
    fn map_end(&self, end: &Dir, hop: &Hop) -> Result<Dir, WalkError> {
        if let Some((v, _)) = end.vertex {
            if v == hop.a || v == hop.b {
                return Ok(self.toward(hop.next, v));
            }
        }
        let d = end.angle.vector();
        let (a, b) = (self.qpoint(hop.a), self.qpoint(hop.b));
        let e = diff(b, a);
        let den = cross(d, e);
        if den == 0 {
            return Err(WalkError::Corrupt);
        }
        let u = cross(d, diff(hop.prev, a)) as f64 / den as f64;
        // At or beyond an end of the edge (by rounding): that endpoint, exactly.
        if u <= 0.0 || u >= 1.0 {
            return Ok(self.toward(hop.next, if u <= 0.0 { hop.a } else { hop.b }));
        }
        // `P − next = (prev − next) + t·d` with `t = cross(a − prev, e) / den` (see
        // `map_dir`) in `f64`, scaled so that its larger component is about 2⁵²: the
        // direction keeps `f64` precision instead of the query grid's, so that a range far
        // thinner than a grid step at the edge keeps its two ends apart.
        let t = cross(diff(a, hop.prev), e) as f64 / den as f64;
        let pn = diff(hop.prev, hop.next);
        let (fx, fy) = (pn.0 as f64 + t * d.0 as f64, pn.1 as f64 + t * d.1 as f64);
        let big = libm::fmax(libm::fabs(fx), libm::fabs(fy));
        if !big.is_finite() || big == 0.0 {
            return Err(WalkError::Corrupt);
        }
        let (_, exp) = libm::frexp(big);
        let lim = crate::geom::point::MAX_ABS_DIRECTION as f64;
        let (vx, vy) = (
            libm::round(libm::scalbn(fx, 52 - exp)),
            libm::round(libm::scalbn(fy, 52 - exp)),
        );
        if libm::fabs(vx) > lim || libm::fabs(vy) > lim {
            return Err(WalkError::Corrupt);
        }
        let dir = Direction::new(vx as i64, vy as i64).ok_or(WalkError::Corrupt)?;
        // The same exactly, scaled by |den|: `(prev − next)·den + num·d`.
        let exact = (|| {
            let d = end
                .exact
                .as_deref()
                .copied()
                .unwrap_or((Wide::from_i128(d.0), Wide::from_i128(d.1)));
            let den = Wide::cross(&d, e)?;
            let num = cross(diff(a, hop.prev), e);
            let x = den.mul_i128(pn.0)?.add(&d.0.mul_i128(num)?)?;
            let y = den.mul_i128(pn.1)?.add(&d.1.mul_i128(num)?)?;
            match den.sign() {
                Sign::Negative => Some(Rc::new((x.neg(), y.neg()))),
                Sign::Zero => None,
                Sign::Positive => Some(Rc::new((x, y))),
            }
        })();
        Ok(Dir {
            angle: Angle::constant(dir),
            vertex: None,
            exact,
        })
    }

    /// The range `(lo, hi)` (exact, less than π wide: it lies on one edge) seen through
    /// `hop`, reversed if `flip` (mirrors). Mapped ends are placed to `f64` precision, so a
    /// range thinner than that can come out with both ends on one direction or crossed:
    /// it is then collapsed onto one direction, the end that points at a vertex if only
    /// one does (`split` and `floor_pieces` take a collapsed range as the ray just before
    /// that direction).
    fn map_range(
        &self,
        lo: &Dir,
        hi: &Dir,
        hop: &Hop,
        flip: bool,
    ) -> Result<(Dir, Dir), WalkError> {
        let (a, b) = (self.map_end(lo, hop)?, self.map_end(hi, hop)?);
        let (a, b) = if flip { (b, a) } else { (a, b) };
        let thin = cross(lo.angle.vector(), hi.angle.vector()) == 0;
        if thin || cross(a.angle.vector(), b.angle.vector()) <= 0 {
            let keep = if a.vertex.is_some() && b.vertex.is_none() {
                a
            } else {
                b
            };
            return Ok((keep.clone(), keep));
        }
        Ok((a, b))
    }

    /// Splits the range `(lo, hi)` seen from `eye` on `m` by the edges of `m` facing the eye
    /// (`front`) or facing away (`!front`, the exit edges of a ray inside `m`): the pieces
    /// in counter-clockwise order with their start and edge (global vertex indices).
    fn split(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        lo: &Dir,
        hi: &Dir,
        first: Boundary,
        front: bool,
    ) -> Vec<(Dir, Dir, Boundary, (usize, usize))> {
        let (lv, hv) = (lo.angle.vector(), hi.angle.vector());
        // Both ends on one direction (see `map_range`): the one edge the ray just before
        // `hi` crosses, else the one just after it, as `floor_pieces` takes such a range.
        if cross(lv, hv) == 0 {
            return self.split_collapsed(eye, m, (lo, hi), first, front);
        }
        let mut out = Vec::new();
        for ((ia, ib), (s0, s1)) in self.facing_edges(eye, m, front) {
            let (v0, v1) = (diff(self.qpoint(s0), eye), diff(self.qpoint(s1), eye));
            // Against the range ends exactly (`Dir::turn`).
            let (start, boundary, sv) = if lo.turn(v0) == Sign::Positive {
                (self.toward(eye, s0), self.split_boundary(eye, s0), Some(v0))
            } else {
                (lo.clone(), first.clone(), None)
            };
            let (end, ev) = if hi.turn(v1) == Sign::Negative {
                (self.toward(eye, s1), Some(v1))
            } else {
                (hi.clone(), None)
            };
            let nonempty = match (sv, ev) {
                (Some(a), Some(b)) => cross(a, b) > 0,
                (None, Some(b)) => lo.turn(b) == Sign::Positive,
                (Some(a), None) => hi.turn(a) == Sign::Negative,
                (None, None) => cross(lv, hv) > 0,
            };
            if nonempty {
                out.push((start, end, boundary, (ia, ib)));
            }
        }
        out.sort_by(|a, b| {
            let c = cross(a.0.angle.vector(), b.0.angle.vector());
            0.cmp(&c)
        });
        out
    }

    /// The edges of `m` facing `eye` (`front`) or facing away from it: each as `(a, b)` in
    /// `m`'s order and as `(s0, s1)`, its endpoints counter-clockwise from the eye (a front
    /// edge spans b → a, a back edge a → b). Global vertex indices.
    fn facing_edges(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        front: bool,
    ) -> impl Iterator<Item = ((usize, usize), (usize, usize))> + Clone + '_ {
        let (f, n) = self
            .scene
            .object(m)
            .map_or((0, 0), |o| (o.first_vertex(), o.len()));
        (0..n).filter_map(move |k| {
            let (ia, ib) = (f + k, f + (k + 1) % n);
            match (front, side(self.qpoint(ia), self.qpoint(ib), eye)) {
                (true, Sign::Negative) => Some(((ia, ib), (ib, ia))),
                (false, Sign::Positive) => Some(((ia, ib), (ia, ib))),
                _ => None,
            }
        })
    }

    /// [`Tree::split`] of a range `(lo, hi)` collapsed onto one direction: the edge crossed
    /// just before it, else just after it (at most one piece).
    fn split_collapsed(
        &self,
        eye: QueryPoint,
        m: ObjectId,
        (lo, hi): (&Dir, &Dir),
        first: Boundary,
        front: bool,
    ) -> Vec<(Dir, Dir, Boundary, (usize, usize))> {
        let h = hi.angle.vector();
        let edges = self.facing_edges(eye, m, front).map(|(e, (s0, s1))| {
            let (v0, v1) = (diff(self.qpoint(s0), eye), diff(self.qpoint(s1), eye));
            (e, cross(v0, h), cross(h, v1))
        });
        let before = edges.clone().find(|&(_, c0, c1)| c0 > 0 && c1 >= 0);
        let edge = before.or_else(|| edges.clone().find(|&(_, c0, c1)| c0 >= 0 && c1 > 0));
        edge.map(|(e, _, _)| (lo.clone(), hi.clone(), first, e))
            .into_iter()
            .collect()
    }

    /// Pushes `hop` on the stack of hops; returns the stack to restore.
    fn enter(&mut self, hop: Hop) -> Rc<[Hop]> {
        let inner = self.hops.iter().copied().chain([hop]).collect();
        core::mem::replace(&mut self.hops, inner)
    }

    /// Walks the pieces of `(from, to)` seen from `eye` anchored to `m`, one level deeper.
    #[allow(clippy::too_many_arguments)]
    fn deeper(
        &mut self,
        eye: QueryPoint,
        m: ObjectId,
        from: &Dir,
        to: &Dir,
        first: Boundary,
        depth: usize,
        out: &mut Vec<Leaf>,
    ) -> Result<(), WalkError> {
        self.branch.push(m);
        let r = self
            .floor_pieces(eye, m, from, to, first)
            .and_then(|pieces| {
                pieces
                    .into_iter()
                    .try_for_each(|sp| self.piece(eye, depth - 1, sp, out))
            });
        self.branch.pop();
        r
    }

    #[cfg(feature = "mirrors")]
    fn mirror(
        &mut self,
        eye: QueryPoint,
        m: ObjectId,
        p: &Piece,
        depth: usize,
        out: &mut Vec<Leaf>,
    ) -> Result<(), WalkError> {
        let level = self.branch.len();
        for (lo, hi, boundary, (ia, ib)) in
            self.split(eye, m, &p.from, &p.to, p.boundary.clone(), true)
        {
            let (a, b) = (self.point(ia), self.point(ib));
            let e = optics::reflect(eye, a, b).ok_or(WalkError::EyeOutOfRange)?;
            let (aq, bq) = (a.to_query(), b.to_query());
            let (s0, s1) = (side(aq, bq, eye), side(aq, bq, e));
            if s1 == Sign::Zero || s1 == s0 {
                return Err(WalkError::DegenerateOptics { level });
            }
            let hop = Hop {
                prev: eye,
                a: ia,
                b: ib,
                next: e,
                level: level + 1,
            };
            // Mirrors flip orientation: counter-clockwise from the image of `hi`.
            let (from, to) = self.map_range(&lo, &hi, &hop, true)?;
            let outer = self.enter(hop);
            let mut tmp = Vec::new();
            let r = self.deeper(e, m, &from, &to, boundary.clone(), depth, &mut tmp);
            self.hops = outer;
            r?;
            // Back to primary order: reversed, each leaf starting at its successor's start.
            let k = tmp.len();
            for i in 0..k {
                out.push(Leaf {
                    branch: core::mem::take(&mut tmp[k - 1 - i].branch),
                    boundary: if i == 0 {
                        boundary.clone()
                    } else {
                        tmp[k - i].boundary.clone()
                    },
                });
            }
        }
        Ok(())
    }

    #[cfg(feature = "refraction")]
    fn refractive(
        &mut self,
        eye: QueryPoint,
        m: ObjectId,
        eta: crate::scene::Eta,
        p: &Piece,
        depth: usize,
        out: &mut Vec<Leaf>,
    ) -> Result<(), WalkError> {
        let level = self.branch.len();
        for (lo, hi, boundary, (ia, ib)) in
            self.split(eye, m, &p.from, &p.to, p.boundary.clone(), true)
        {
            let (a, b) = (self.point(ia), self.point(ib));
            let e1 = optics::refract(eye, a, b, eta, true).ok_or(WalkError::EyeOutOfRange)?;
            let (aq, bq) = (a.to_query(), b.to_query());
            let (s0, s1) = (side(aq, bq, eye), side(aq, bq, e1));
            if s1 == Sign::Zero || s1 != s0 {
                return Err(WalkError::DegenerateOptics { level });
            }
            let hop = Hop {
                prev: eye,
                a: ia,
                b: ib,
                next: e1,
                // The inside stage hits the refractive object itself.
                level,
            };
            let (from1, to1) = self.map_range(&lo, &hi, &hop, false)?;
            let outer = self.enter(hop);
            let r = self.exits(e1, m, eta, &from1, &to1, boundary, depth, level, out);
            self.hops = outer;
            r?;
        }
        Ok(())
    }

    #[cfg(feature = "refraction")]
    #[allow(clippy::too_many_arguments)]
    fn exits(
        &mut self,
        e1: QueryPoint,
        m: ObjectId,
        eta: crate::scene::Eta,
        from1: &Dir,
        to1: &Dir,
        boundary: Boundary,
        depth: usize,
        level: usize,
        out: &mut Vec<Leaf>,
    ) -> Result<(), WalkError> {
        for (lo, hi, b2, (ja, jb)) in self.split(e1, m, from1, to1, boundary, false) {
            let (a, b) = (self.point(ja), self.point(jb));
            let e2 = optics::refract(e1, a, b, eta, false).ok_or(WalkError::EyeOutOfRange)?;
            let (aq, bq) = (a.to_query(), b.to_query());
            let (s0, s1) = (side(aq, bq, e1), side(aq, bq, e2));
            if s1 == Sign::Zero || s1 != s0 {
                return Err(WalkError::DegenerateOptics { level });
            }
            let hop = Hop {
                prev: e1,
                a: ja,
                b: jb,
                next: e2,
                level: level + 1,
            };
            let (from, to) = self.map_range(&lo, &hi, &hop, false)?;
            let outer = self.enter(hop);
            let r = self.deeper(e2, m, &from, &to, b2, depth, out);
            self.hops = outer;
            r?;
        }
        Ok(())
    }
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

#[cfg(test)]
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
            hops: alloc::rc::Rc::from(Vec::new()),
            branch: Vec::new(),
            events: Default::default(),
        };
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |m: i64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % (2 * m as u64 + 1)) as i64 - m
        };
        let same = |r: (u64, u64), w: (Wide, Wide)| {
            let (x, y) = (w.0.residue(), w.1.residue());
            r == (x, y) || r == ((P - x) % P, (P - y) % P)
        };
        let mut compared = 0;
        for round in 0..200 {
            let hops: Vec<Hop> = (0..1 + round % 5)
                .map(|_| {
                    let k = next(5).unsigned_abs() as usize % 4;
                    let q = |x: i64, y: i64| QueryPoint::from_raw(x << 20, y << 20).unwrap();
                    Hop {
                        prev: q(next(1000), next(1000)),
                        a: 4 + k,
                        b: 4 + (k + 1) % 4,
                        next: q(next(1000), next(1000)),
                        level: 0,
                    }
                })
                .collect();
            let eye = QueryPoint::from_raw(next(1 << 40), next(1 << 40)).unwrap();
            // Every fourth round the direction runs along the last hop's edge.
            let dir = if round % 4 == 0 {
                let h = hops.last().unwrap();
                let (a, b) = (tree.qpoint(h.a), tree.qpoint(h.b));
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
                let cur = hops.get(st + 1).map_or(eye, |h| h.prev);
                r = r.and_then(|r| tree.map_hop_residue(&hops[st], cur, r));
                d = d.and_then(|d| tree.map_hop_exact(&hops[st], cur, &d));
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
}
