//! Sweeps around a viewpoint: the view (depth 0) and ray trees (depth D).
//!
//! **Critical directions.** Stage 0: the directions from the viewpoint to every vertex of
//! every non-screen object. Stage `s ≥ 1`: the directions from stage `s`'s eye to every
//! non-screen vertex, mapped back exactly to a primary direction through the chain of hit
//! edges of stages `0..s` (the stage-`s` line through the eye meets the line of the edge
//! hit at stage `s − 1` at `X`; stage `s − 1` runs from its eye through `X`; and so on down
//! to stage 0). The map is only meaningful where that chain is constant, so the sweep
//! refines recursively: [`refine`] is called on an open arc on which the hit edges of
//! stages `0..s` are known to be constant, samples one ray inside it, and splits the arc at
//! the stage-`s` critical directions, after which stage `s` is constant on every piece.
//! Between critical directions a ray's hits can only change when one of its stages sweeps
//! over a vertex (objects are disjoint, so nothing can cross a stage's origin), so one
//! sample per final piece is exact. Extra critical directions (from vertices behind a
//! stage's origin) only split more finely; equal neighbours are merged at the end.
//!
//! **Boundary vertex** of a boundary between arcs `L` and `R` with different branches:
//! evaluate each side's chain exactly at the boundary direction; among the vertices lying
//! on some stage's ray (beyond the stage's origin) that belong to `L.branch[level]` or
//! `R.branch[level]` for that stage's level, take the lowest stage — stages in the order
//! light travels, the inside stage of a refractive object right after the stage that enters
//! it — then the vertex nearest to that stage's eye. For the view this is: the vertex on the
//! boundary ray of the object seen just before or after, nearest to the viewpoint.

use num_rational::BigRational;
use num_traits::{Signed, Zero};
use vcx::{ObjectId, SceneRef};

use super::ray_tree::{trace, RayTreeOptions, Trace};
use super::{
    arc_sample, check_free, cmp_angle, cmp_from, line_intersection, objects, strictly_inside,
    Interval, RObject, RefError, Vec2, VertexRef,
};

/// An interval of a view: the object seen (screens are transparent).
pub type ViewInterval = Interval<Option<ObjectId>>;

/// An interval of a ray-tree sweep: the branch, primary object first.
pub type TreeInterval = Interval<Vec<ObjectId>>;

/// The view from the free point `q` over the full circle: a cyclic list of intervals
/// sorted by start angle in `[0, 2π)` (the last one may wrap through angle 0), each with the
/// non-screen object seen (`None`: nothing) and the vertex causing its start boundary.
/// A scene with nothing (non-screen) around gives one full-circle interval.
///
/// Errors if `q` lies in or on an object (screens included).
pub fn view(scene: SceneRef<'_>, q: &Vec2) -> Result<Vec<ViewInterval>, RefError> {
    let opts = RayTreeOptions {
        depth: 0,
        round_eyes: false,
    };
    Ok(ray_tree(scene, q, opts)?
        .into_iter()
        .map(|i| Interval {
            start: i.start,
            end: i.end,
            start_angle: i.start_angle,
            end_angle: i.end_angle,
            value: i.value.first().copied(),
            start_vertex: i.start_vertex,
        })
        .collect())
}

/// The ray trees from the free point `q` to depth `opts.depth` over the full circle, with
/// the same interval structure as [`view`]; each interval carries its branch.
///
/// Errors if `q` is not free, or (only with `opts.round_eyes`) if a rounded eye is
/// degenerate on a whole interval.
pub fn ray_tree(
    scene: SceneRef<'_>,
    q: &Vec2,
    opts: RayTreeOptions,
) -> Result<Vec<TreeInterval>, RefError> {
    let objs = objects(scene);
    check_free(&objs, q)?;
    let sweep = Sweep {
        objs: &objs,
        q,
        opts,
    };
    let mut crit: Vec<Vec2> = sweep.vertices().map(|w| w.sub(q).primitive()).collect();
    crit.sort_by(cmp_angle);
    crit.dedup();
    let mut leaves = Vec::new();
    if crit.is_empty() {
        let x = Vec2::from_i64(1, 0);
        let tr = trace(&objs, q, &x, opts);
        leaves.push(Leaf {
            start: x,
            trace: tr,
        });
    } else {
        for i in 0..crit.len() {
            sweep.refine(&crit[i], &crit[(i + 1) % crit.len()], 1, &mut leaves)?;
        }
    }
    Ok(sweep.assemble(leaves))
}

/// An open arc on which the whole trace (every stage's hit edge) is constant; it ends
/// where the next leaf starts.
struct Leaf {
    start: Vec2,
    trace: Trace,
}

struct Sweep<'a> {
    objs: &'a [RObject],
    q: &'a Vec2,
    opts: RayTreeOptions,
}

impl Sweep<'_> {
    /// Every vertex of every non-screen object.
    fn vertices(&self) -> impl Iterator<Item = &Vec2> {
        self.objs
            .iter()
            .filter(|o| !o.is_screen())
            .flat_map(|o| o.poly.iter())
    }

    /// The hit edge's line of stage `j` of `tr` (which must have a hit).
    fn edge_line<'t>(&'t self, tr: &Trace, j: usize) -> Option<(&'t Vec2, &'t Vec2)> {
        let h = tr.stages[j].hit.as_ref()?;
        Some(self.objs[h.object.0 as usize].edge(h.edge))
    }

    /// Refines the open arc `(lo, hi)` on which stages `0..s` hit constant edges.
    fn refine(&self, lo: &Vec2, hi: &Vec2, s: usize, out: &mut Vec<Leaf>) -> Result<(), RefError> {
        let tr = trace(self.objs, self.q, &arc_sample(lo, hi), self.opts);
        if tr.stages.len() <= s {
            if tr.degenerate {
                let level = tr.stages.last().map_or(0, |st| st.level);
                return Err(RefError::DegenerateOptics { level });
            }
            out.push(Leaf {
                start: lo.clone(),
                trace: tr,
            });
            return Ok(());
        }
        let mut cuts: Vec<Vec2> = self
            .vertices()
            .filter_map(|w| self.map_back(&tr, s, w))
            .filter(|d| strictly_inside(lo, hi, d))
            .collect();
        cuts.sort_by(|a, b| cmp_from(lo, a, b));
        cuts.dedup();
        let mut bounds = Vec::with_capacity(cuts.len() + 2);
        bounds.push(lo.clone());
        bounds.extend(cuts);
        bounds.push(hi.clone());
        for w in bounds.windows(2) {
            self.refine(&w[0], &w[1], s + 1, out)?;
        }
        Ok(())
    }

    /// The primary direction whose stage-`s` line (through stage `s`'s eye) passes through
    /// `w`, via the chain of hit edges of `tr`'s stages `0..s`; `None` if a line of the
    /// chain is parallel to the mapped line.
    fn map_back(&self, tr: &Trace, s: usize, w: &Vec2) -> Option<Vec2> {
        let mut d = w.sub(&tr.stages[s].eye);
        for j in (0..s).rev() {
            let (a, b) = self.edge_line(tr, j)?;
            let x = line_intersection(&tr.stages[j + 1].eye, &d, a, b)?;
            d = x.sub(&tr.stages[j].eye);
        }
        (!d.is_zero()).then(|| d.primitive())
    }

    /// Merges neighbouring leaves with equal branches and finds the boundary vertices.
    fn assemble(&self, leaves: Vec<Leaf>) -> Vec<TreeInterval> {
        let m = leaves.len();
        let changes: Vec<usize> = (0..m)
            .filter(|&i| leaves[(i + m - 1) % m].trace.branch != leaves[i].trace.branch)
            .collect();
        if changes.is_empty() {
            let x = Vec2::from_i64(1, 0);
            return vec![Interval {
                start: x.clone(),
                end: x,
                start_angle: 0.0,
                end_angle: 0.0,
                value: leaves[0].trace.branch.clone(),
                start_vertex: None,
            }];
        }
        let mut out: Vec<TreeInterval> = (0..changes.len())
            .map(|c| {
                let (i, j) = (changes[c], changes[(c + 1) % changes.len()]);
                let (left, right) = (&leaves[(i + m - 1) % m], &leaves[i]);
                Interval {
                    start: right.start.clone(),
                    end: leaves[j].start.clone(),
                    start_angle: right.start.angle(),
                    end_angle: leaves[j].start.angle(),
                    value: right.trace.branch.clone(),
                    start_vertex: self.boundary_vertex(left, right),
                }
            })
            .collect();
        // Leaves run counter-clockwise from the smallest stage-0 critical angle, but the
        // last stage-0 gap may be split past angle 0.
        out.sort_by(|a, b| cmp_angle(&a.start, &b.start));
        out
    }

    /// The vertex causing the boundary between `left` and `right` (module documentation).
    fn boundary_vertex(&self, left: &Leaf, right: &Leaf) -> Option<VertexRef> {
        let b = &right.start;
        // Candidates: (stage, squared distance to the stage's eye, vertex).
        let mut found: Vec<(usize, BigRational, VertexRef)> = Vec::new();
        for side in [left, right] {
            for (s, (level, eye, origin, dir)) in self.rays_at(&side.trace, b).iter().enumerate() {
                let owners = [left, right]
                    .map(|l| l.trace.branch.get(*level).copied())
                    .into_iter()
                    .flatten();
                for id in owners {
                    let o = &self.objs[id.0 as usize];
                    for (k, w) in o.poly.iter().enumerate() {
                        let r = w.sub(origin);
                        if !dir.cross(&r).is_zero() || !dir.dot(&r).is_positive() {
                            continue;
                        }
                        found.push((s, w.sub(eye).dot(&w.sub(eye)), o.vertex_ref(k)));
                    }
                }
            }
        }
        found
            .into_iter()
            .min_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)))
            .map(|(_, _, v)| v)
    }

    /// The stages of `tr`'s chain evaluated exactly at primary direction `b` (the limit of
    /// the chain at the end of its arc): `(level, eye, origin, direction)` per stage.
    fn rays_at(&self, tr: &Trace, b: &Vec2) -> Vec<(usize, Vec2, Vec2, Vec2)> {
        let mut out = Vec::new();
        let (mut origin, mut dir) = (self.q.clone(), b.clone());
        for (s, st) in tr.stages.iter().enumerate() {
            out.push((st.level, st.eye.clone(), origin.clone(), dir.clone()));
            let (Some(next), Some((a, e))) = (tr.stages.get(s + 1), self.edge_line(tr, s)) else {
                break;
            };
            // Parallel only if the ray runs along the edge; its endpoints are then on this
            // stage's ray and win over anything deeper.
            let Some(x) = line_intersection(&origin, &dir, a, e) else {
                break;
            };
            dir = x.sub(&next.eye);
            origin = x;
        }
        out
    }
}
