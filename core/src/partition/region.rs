//! Pruning the complex to a region of viewpoints (`vcx build --region X0,Y0,X1,Y1`; the
//! paper's bounding box of §4.1, done with exact integer predicates).
//!
//! **What is needed.** The view from a free point `q` walks exactly the cylinders that
//! contain a line through `q` (its trace, DESIGN.md §6). With the symbolic perturbation the
//! walk is that of `q + (ε, ε²)`; letting ε → 0, every cylinder `c` it enters has `q` in the
//! closure of its *swept region* R(c), the union of the free segments of its lines — exact,
//! unperturbed geometry with closed inequalities. So for viewpoints in the closed box B a
//! cylinder is needed only if `closure(R(c))` meets B, and a cylinder may be dropped once
//! that is *proved* empty. The walk's start (the cylinder at θ = 0 holding `q`) and every
//! cylinder across a wall it takes are such cylinders, so a walk from B never needs a
//! dropped one.
//!
//! **What this module keeps: a conservative superset**, never dropping a needed cylinder.
//! The exact union R(c) is not computed; instead four necessary conditions, each decided
//! exactly (integer cross and dot products, degree 2 in coordinates, `i128`), and a
//! cylinder is dropped as soon as one of them fails. Let `[d_L, d_R]` be the cylinder's
//! closed arc of directions (its walls: `d` = the exact direction of the wall's bitangent,
//! `(1, 0)` for θ = 0), F its floor, G its ceiling, and `K` the closed cone of the
//! directions of the arc (convex when the arc is shorter than π; exactly π or more: the
//! cone conditions are skipped).
//!
//! 1. **Lines** (line space): some line of the closed cylinder meets B. At each θ the lines
//!    of `c` are the offsets `[b(θ), t(θ)]` between its bottom and top arc, those meeting B
//!    `[min_k u_k(θ), max_k u_k(θ)]` over B's corners `k` (`u = cross(d, p)`). Both are
//!    intervals that move continuously with θ and `b ≤ t`, so if they are disjoint over the
//!    whole arc, then the cylinder lies entirely above B's band or entirely below it (it
//!    cannot switch sides without overlapping). "Entirely above" means every corner lies
//!    strictly right of the bottom tangent line for every θ of the arc: for a lower chain
//!    of object O (`b = min_v cross(d, v)`) that is `cross(d, k − v) < 0` for every corner
//!    `k`, vertex `v` of O and direction `d` of the arc; for an upper chain (`b = max_v`)
//!    it is proved with one vertex `v` of O that works for the whole arc (sufficient). A
//!    condition `cross(d, w) < 0` holds on the whole arc iff it holds at both ends (the
//!    arc is shorter than π; checked with the perturbed angles). "Entirely below"
//!    symmetrically with the top arc. No bottom (top) arc: never above (below).
//! 2. **Hull**: with both F and G, every segment of `c` runs from a point of F to a point
//!    of G, so R(c) ⊆ conv(F ∪ G); dropped if a separating axis shows conv(F ∪ G) ∩ B = ∅
//!    (candidate axes: the box's, F's and G's edge normals and the normals of every
//!    vertex pair of F × G, which include the hull's bridges — complete for two convex
//!    polygons).
//! 3. **Forward cone** (F exists, cone convex): a segment leaves F in a direction of the
//!    arc, so R(c) ⊆ F ⊕ K; dropped if (B − F) ∩ K = ∅, by separating axes (normals of the
//!    box's and F's edges and of the cone's two rays).
//! 4. **Backward cone** (G exists): R(c) ⊆ G ⊕ (−K); dropped if (G − B) ∩ K = ∅.
//!
//! Each condition only ever drops when a strict separation is found, so ties (a box
//! touching a segment, a corner on a tangent) keep the cylinder: the result is the
//! closure-superset above, whatever the perturbation does.
//!
//! **Pruned complex.** The kept cylinders are renumbered with those whose left wall is
//! θ = 0 first (primary walks find their start in that prefix, ARCHITECTURE.md "Where a
//! primary walk starts"), each group in the old order; links to dropped cylinders become
//! `None`; the vertices no kept wall names are dropped (the rest keep their θ order). The
//! result records the region ([`Complex::region`]): a walk from a point outside it is
//! [`WalkError::OutsideRegion`](crate::walk::WalkError::OutsideRegion), and a walk that
//! meets a missing link (a wrong pruning or a crafted file) stops with
//! [`WalkError::Corrupt`](crate::walk::WalkError::Corrupt).
//!
//! **Ray trees.** Behind a mirror, refractive object or screen M, a ray tree walks anchored
//! to M: the cylinders with floor M, from eyes anywhere (virtual eyes behind mirrors and
//! refractive objects leave the box; past a screen the eye is the same). So every
//! cylinder whose floor is such an object is kept (M's sheet entire); the others are
//! entered only by primary walks from the box, and pruned by the conditions above. An
//! anchored walk's start climbs M's sheet from M's chain through the tilings of the border
//! index, which hold the kept cylinders only: a step across a chain whose true answer was
//! dropped would find the next kept cylinder instead, so a pruned complex checks that the
//! cylinder found contains the angle ([`Complex::across_from`]) and the climb, never
//! wrong, falls back to a scan. A scene of mirrors only keeps most of its complex; the
//! tighter set (lines through the images of the box, to the depth) is not computed.

use crate::geom::{Point, QueryPoint};

#[cfg(feature = "alloc")]
use super::{Complex, Cylinder, CylinderId, VertexId, Wall};
#[cfg(feature = "alloc")]
use crate::geom::sos::Angle;
#[cfg(feature = "alloc")]
use crate::line_space::{Bound, Chain};
#[cfg(feature = "alloc")]
use crate::scene::{ObjectId, SceneRef};

/// A closed axis-aligned box of viewpoints on the scene grid: `min.x ≤ x ≤ max.x`,
/// `min.y ≤ y ≤ max.y`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Region {
    min: Point,
    max: Point,
}

impl Region {
    /// The box with these corners; `None` unless `min ≤ max` in both coordinates (a
    /// degenerate box — a segment or a point — is allowed).
    pub fn new(min: Point, max: Point) -> Option<Region> {
        (min.x() <= max.x() && min.y() <= max.y()).then_some(Region { min, max })
    }

    /// Lower-left corner.
    pub fn min(&self) -> Point {
        self.min
    }

    /// Upper-right corner.
    pub fn max(&self) -> Point {
        self.max
    }

    /// Whether `q` lies in the closed box (exact: scene points lift to the query grid by a
    /// shift).
    pub fn contains(&self, q: QueryPoint) -> bool {
        let (lo, hi) = (self.min.to_query(), self.max.to_query());
        lo.x() <= q.x() && q.x() <= hi.x() && lo.y() <= q.y() && q.y() <= hi.y()
    }

    /// The four corners, counter-clockwise from the lower left, as raw `i128`.
    #[cfg(feature = "alloc")]
    fn corners(&self) -> [V; 4] {
        let (a, b) = (v(self.min), v(self.max));
        [a, (b.0, a.1), b, (a.0, b.1)]
    }
}

/// Why a complex cannot be pruned to a region.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum RegionError {
    /// The complex is itself already pruned.
    AlreadyPruned,
}

impl core::fmt::Display for RegionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RegionError::AlreadyPruned => write!(f, "the complex is already pruned to a region"),
        }
    }
}

impl core::error::Error for RegionError {}

/// An exact vector or point on the scene grid (raw units), widened.
#[cfg(feature = "alloc")]
type V = (i128, i128);

#[cfg(feature = "alloc")]
fn v(p: Point) -> V {
    (i128::from(p.x()), i128::from(p.y()))
}

#[cfg(feature = "alloc")]
fn sub(a: V, b: V) -> V {
    (a.0 - b.0, a.1 - b.1)
}

/// `cross(a, b)`; with components below 2³² in magnitude, below 2⁶⁵: exact in `i128`.
#[cfg(feature = "alloc")]
fn cross(a: V, b: V) -> i128 {
    a.0 * b.1 - a.1 * b.0
}

#[cfg(feature = "alloc")]
fn dot(a: V, b: V) -> i128 {
    a.0 * b.0 + a.1 * b.1
}

/// The left normal: `dot(perp(e), x) = cross(e, x)`.
#[cfg(feature = "alloc")]
fn perp(e: V) -> V {
    (-e.1, e.0)
}

#[cfg(feature = "alloc")]
fn neg(e: V) -> V {
    (-e.0, -e.1)
}

/// A cylinder's closed arc of directions, exact ends, and whether it is shorter than π
/// (decided on the perturbed angles; the exact arc is then at most π).
#[cfg(feature = "alloc")]
struct Arc {
    left: V,
    right: V,
    short: bool,
}

#[cfg(feature = "alloc")]
impl Arc {
    /// `sign · cross(d, w) > 0` for every direction `d` of the arc (false if the arc is
    /// not short). Both ends inside an open half-circle and an arc shorter than π: the
    /// whole arc is inside (leaving it needs a detour of length π).
    fn strictly(&self, w: V, sign: i128) -> bool {
        self.short && sign * cross(self.left, w) > 0 && sign * cross(self.right, w) > 0
    }

    /// Whether the closed cone of the arc's directions is convex with rays `left`,
    /// `right` as its boundary: short, and the exact ends not opposite.
    fn convex_cone(&self) -> bool {
        let c = cross(self.left, self.right);
        self.short && (c > 0 || (c == 0 && dot(self.left, self.right) > 0))
    }

    /// Whether `sup_{x ∈ K} dot(n, x)` is 0 (the apex) rather than +∞.
    fn cone_bounded(&self, n: V) -> bool {
        dot(n, self.left) <= 0 && dot(n, self.right) <= 0
    }
}

#[cfg(feature = "alloc")]
fn min_max(points: impl Iterator<Item = V>, n: V) -> (i128, i128) {
    points.fold((i128::MAX, i128::MIN), |(lo, hi), p| {
        let d = dot(n, p);
        (lo.min(d), hi.max(d))
    })
}

/// The edge vectors of a counter-clockwise polygon.
#[cfg(feature = "alloc")]
fn edges(poly: &[Point]) -> impl Iterator<Item = V> + '_ {
    poly.iter()
        .zip(poly.iter().cycle().skip(1))
        .map(|(a, b)| sub(v(*b), v(*a)))
}

/// The tests of the module doc for one region and scene.
#[cfg(feature = "alloc")]
struct Pruner<'s> {
    scene: SceneRef<'s>,
    corners: [V; 4],
}

#[cfg(feature = "alloc")]
impl Pruner<'_> {
    fn polygon(&self, o: ObjectId) -> &[Point] {
        self.scene
            .object(o)
            .map_or(&[], |obj| self.scene.polygon(obj))
    }

    /// Whether the cylinder's floor is a mirror, refractive object or screen: the walks
    /// of ray trees behind it are anchored to it, from eyes anywhere (module doc).
    fn behind(&self, c: &Cylinder) -> bool {
        c.floor
            .and_then(|f| self.scene.object(f))
            .is_some_and(|o| o.material != crate::scene::Material::Opaque)
    }

    /// Whether the cylinder may be needed by a view from the box (false: proved not).
    fn needed<S: super::Storage>(&self, complex: &Complex<S>, c: &Cylinder) -> bool {
        let Some(arc) = self.arc(complex, c) else {
            return true;
        };
        if self.lines_miss(&arc, c) {
            return false;
        }
        if let (Some(f), Some(g)) = (c.floor, c.ceiling) {
            if self.hull_misses(f, g) {
                return false;
            }
        }
        if arc.convex_cone() {
            if let Some(f) = c.floor {
                // (B − F) ∩ K = ∅: points b − f.
                if self.cone_misses(&arc, f, 1) {
                    return false;
                }
            }
            if let Some(g) = c.ceiling {
                // (G − B) ∩ K = ∅: points g − b.
                if self.cone_misses(&arc, g, -1) {
                    return false;
                }
            }
        }
        true
    }

    /// The exact arc of a cylinder; `None` if a wall's vertex is out of range.
    fn arc<S: super::Storage>(&self, complex: &Complex<S>, c: &Cylinder) -> Option<Arc> {
        let dir = |w: Wall| -> Option<V> {
            match w {
                Wall::Zero => Some((1, 0)),
                Wall::Vertex(id) => {
                    let b = complex.vertex(id)?.bitangent;
                    let p = *self.scene.vertices().get(b.first)?;
                    let q = *self.scene.vertices().get(b.second)?;
                    Some(sub(v(q), v(p)))
                }
            }
        };
        let angle = |w: Wall| complex.wall_angle(&self.scene, w);
        let pi = Angle::ZERO.reversed();
        let less = |a: &Angle, b: &Angle| a.cmp_angle(b) == core::cmp::Ordering::Less;
        // Shorter than π: θ_R < θ_L + π, on the perturbed angles (θ_R = 2π for θ = 0).
        let short = match (c.left, c.right) {
            (Wall::Zero, Wall::Zero) => false,
            (Wall::Zero, r) => less(&angle(r)?, &pi),
            (l, r) => {
                let l = angle(l)?;
                if !less(&l, &pi) {
                    true // θ_L ≥ π: θ_L + π ≥ 2π ≥ θ_R
                } else {
                    match r {
                        Wall::Zero => false,
                        r => less(&angle(r)?, &l.reversed()),
                    }
                }
            }
        };
        Some(Arc {
            left: dir(c.left)?,
            right: dir(c.right)?,
            short,
        })
    }

    /// Test 1: the closed cylinder lies entirely above or entirely below the band of lines
    /// meeting the box.
    fn lines_miss(&self, arc: &Arc, c: &Cylinder) -> bool {
        // Above: every corner strictly right of the bottom tangent (sign −1); below: every
        // corner strictly left of the top tangent (sign +1).
        let side = |chain: Option<Chain>, sign: i128, extreme: Bound| -> bool {
            let Some(chain) = chain else { return false };
            let poly = self.polygon(chain.object);
            if poly.is_empty() {
                return false;
            }
            let works = |p: &Point| {
                self.corners
                    .iter()
                    .all(|&k| arc.strictly(sub(k, v(*p)), sign))
            };
            if chain.bound == extreme {
                // The tangent is the extreme over all vertices: every vertex must work.
                poly.iter().all(works)
            } else {
                // The tangent is the other extreme: one vertex working throughout suffices.
                poly.iter().any(works)
            }
        };
        side(c.bottom, -1, Bound::Lower) || side(c.top, 1, Bound::Upper)
    }

    /// Test 2: a separating axis between conv(F ∪ G) and the box.
    fn hull_misses(&self, f: ObjectId, g: ObjectId) -> bool {
        let (pf, pg) = (self.polygon(f), self.polygon(g));
        if pf.is_empty() || pg.is_empty() {
            return false;
        }
        let hull = || pf.iter().chain(pg).map(|p| v(*p));
        let separates = |n: V| {
            let (_, h) = min_max(hull(), n);
            let (b, _) = min_max(self.corners.iter().copied(), n);
            h < b
        };
        let axes = [(1, 0), (0, 1)]
            .into_iter()
            .chain(edges(pf).map(perp))
            .chain(edges(pg).map(perp));
        let bridges = pf
            .iter()
            .flat_map(|a| pg.iter().map(move |b| perp(sub(v(*b), v(*a)))));
        axes.chain(bridges)
            .any(|n| separates(n) || separates(neg(n)))
    }

    /// Tests 3 and 4: a separating axis between the cone K and `sign · (B − O)`.
    fn cone_misses(&self, arc: &Arc, o: ObjectId, sign: i128) -> bool {
        let poly = self.polygon(o);
        if poly.is_empty() {
            return false;
        }
        // min over m = sign·(b − p) of dot(n, m).
        let min_m = |n: V| {
            let (b_lo, b_hi) = min_max(self.corners.iter().copied(), n);
            let (p_lo, p_hi) = min_max(poly.iter().map(|p| v(*p)), n);
            if sign > 0 {
                b_lo - p_hi
            } else {
                p_lo - b_hi
            }
        };
        let separates = |n: V| arc.cone_bounded(n) && min_m(n) > 0;
        let axes = [(1, 0), (0, 1), perp(arc.left), perp(arc.right)]
            .into_iter()
            .chain(edges(poly).map(perp));
        axes.into_iter().any(|n| separates(n) || separates(neg(n)))
    }
}

/// Which cylinders of `complex` a view or ray tree from a viewpoint in `region` may enter
/// (module doc: a superset of the exact set, never missing one).
#[cfg(feature = "alloc")]
pub fn needed_cylinders<S: super::Storage>(
    complex: &Complex<S>,
    scene: &SceneRef<'_>,
    region: &Region,
) -> alloc::vec::Vec<bool> {
    let pruner = Pruner {
        scene: *scene,
        corners: region.corners(),
    };
    complex
        .cylinders()
        .iter()
        .map(|c| pruner.behind(c) || pruner.needed(complex, c))
        .collect()
}

#[cfg(feature = "alloc")]
impl Complex {
    /// The complex pruned to the cylinders a view or ray tree from a viewpoint in `region`
    /// may enter (module doc of `partition::region`): kept cylinders renumbered with those
    /// at θ = 0 first, links to dropped ones removed, unused vertices dropped. Views and
    /// ray trees from inside the region equal those of the full complex; from outside they
    /// are [`WalkError::OutsideRegion`](crate::walk::WalkError::OutsideRegion).
    pub fn prune_to_region(
        &self,
        scene: &SceneRef<'_>,
        region: Region,
    ) -> Result<Complex, RegionError> {
        let keep = self.needed_in(scene, &region)?;
        Ok(self.keep_only(scene, region, &keep))
    }

    /// [`needed_cylinders`] for [`Complex::prune_to_region`], after its check: the
    /// complex is whole.
    pub(crate) fn needed_in(
        &self,
        scene: &SceneRef<'_>,
        region: &Region,
    ) -> Result<alloc::vec::Vec<bool>, RegionError> {
        if self.region.is_some() {
            return Err(RegionError::AlreadyPruned);
        }
        Ok(needed_cylinders(self, scene, region))
    }

    /// The complex of the cylinders `keep` marks, renumbered as
    /// [`Complex::prune_to_region`] describes, for `region`.
    pub(crate) fn keep_only(&self, scene: &SceneRef<'_>, region: Region, keep: &[bool]) -> Complex {
        let kept = |i: usize| keep.get(i).copied().unwrap_or(false);
        // New ids: the kept cylinders at θ = 0, then the others, each in the old order.
        let order: alloc::vec::Vec<usize> = (0..self.cylinders.len())
            .filter(|&i| kept(i) && self.cylinders.get(i).is_some_and(|c| c.left == Wall::Zero))
            .chain((0..self.cylinders.len()).filter(|&i| {
                kept(i) && self.cylinders.get(i).is_some_and(|c| c.left != Wall::Zero)
            }))
            .collect();
        let mut new_id = alloc::vec![None; self.cylinders.len()];
        for (k, &i) in order.iter().enumerate() {
            if let Some(slot) = new_id.get_mut(i) {
                *slot = CylinderId::from_index(k);
            }
        }
        // Vertices some kept wall names, in their (θ) order.
        let mut used = alloc::vec![false; self.vertices.len()];
        for &i in &order {
            if let Some(c) = self.cylinders.get(i) {
                for w in [c.left, c.right] {
                    if let Wall::Vertex(v) = w {
                        if let Some(u) = used.get_mut(v.index()) {
                            *u = true;
                        }
                    }
                }
            }
        }
        let mut new_vertex = alloc::vec![None; self.vertices.len()];
        let mut vertices = alloc::vec::Vec::new();
        for (i, vtx) in self.vertices.iter().enumerate() {
            if used.get(i).copied().unwrap_or(false) {
                if let Some(slot) = new_vertex.get_mut(i) {
                    *slot = VertexId::from_index(vertices.len());
                }
                vertices.push(*vtx);
            }
        }
        let wall = |w: Wall| match w {
            Wall::Zero => Wall::Zero,
            Wall::Vertex(v) => new_vertex
                .get(v.index())
                .copied()
                .flatten()
                .map_or(Wall::Zero, Wall::Vertex),
        };
        let link = |l: Option<CylinderId>| l.and_then(|l| new_id.get(l.index()).copied().flatten());
        let cylinders = order
            .iter()
            .filter_map(|&i| self.cylinders.get(i))
            .map(|c| Cylinder {
                left: wall(c.left),
                right: wall(c.right),
                left_neighbour: link(c.left_neighbour),
                right_neighbour: link(c.right_neighbour),
                ..*c
            })
            .collect();
        let mut pruned = Complex::new_owned(vertices, cylinders, scene);
        pruned.region = Some(region);
        pruned
    }
}
