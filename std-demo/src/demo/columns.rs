//! The view turned into screen columns.
//!
//! Column `k` of `n` spans the directions from `heading + fov/2 − k·fov/n` (its left edge)
//! down to `heading + fov/2 − (k+1)·fov/n` (its right edge); column 0 is the leftmost. The
//! column edges are rounded to integer direction vectors (a drawing choice); which view
//! intervals cover a column — the interval at each edge and every interval boundary
//! strictly inside — is then decided **exactly** by comparing those directions with the
//! exact interval boundaries ([`Angle::cmp_exact`]). Only the covered fractions, the hit
//! distances and the shading are computed in `f64`, for drawing.
//!
//! At depth > 0 the intervals are those of the ray tree: the primary boundaries are exact
//! as above; a deeper boundary is known in `f64` only and is compared as the integer
//! direction closest to it. A piece then shows the last object of its branch (what the ray
//! finally hits, at the unfolded length of the ray's polyline, [`super::trace_branch`]),
//! with the primary object and the number of bounces for the tint and the band.

use core::cmp::Ordering;
use core::f64::consts::TAU;

use vcx::geom::predicates::Direction;
use vcx::geom::sos::Angle;
use vcx::ObjectId;

use super::{escapes, ray_polygon, trace_branch, FrameData, Seen, World};

/// Part of a column that sees one object (or nothing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// The object finally hit (id in the whole scene, the last of the branch); `None`:
    /// nothing (or the ray escapes after a mirror or a refractive object).
    pub object: Option<ObjectId>,
    /// The object hit first (the primary one), when the ray goes on from it (a mirror or a
    /// refractive object at depth > 0); `None` otherwise.
    pub first: Option<ObjectId>,
    /// Objects the ray went through or bounced off before the last one (0 at depth 0).
    pub bounces: usize,
    /// Distance to the first hit (the primary object), for the band; infinite without one.
    pub first_distance: f64,
    /// Fraction of the column's angular span covered, in `[0, 1]`.
    pub fraction: f64,
    /// Distance from the viewpoint to the hit along the column's central ray (or, for a
    /// piece that does not cover the centre, along the piece's middle ray); infinite for
    /// nothing.
    pub distance: f64,
    /// How squarely the hit edge faces the ray, `|cos|` of the angle between the ray and
    /// the edge normal, in `[0, 1]` (for shading).
    pub facing: f64,
}

/// The pieces of one column, left to right.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Column {
    /// Pieces ordered from the left edge of the column (larger angle) to the right.
    pub pieces: Vec<Piece>,
}

/// The exact angle of an integer direction vector close to the direction `radians`.
pub fn direction_angle(radians: f64) -> Angle {
    let scale = (1u64 << 48) as f64;
    let (x, y) = (
        (radians.cos() * scale).round() as i64,
        (radians.sin() * scale).round() as i64,
    );
    Angle::constant(Direction::new(x, y).unwrap_or(Direction { x: 1, y: 0 }))
}

/// Index of the interval of `view` that contains the direction `a`: the last one whose
/// start is not after `a`, or the last interval (which wraps through θ = 0).
pub fn interval_at(view: &[Seen], a: &Angle) -> usize {
    let p = view.partition_point(|s| s.start.cmp_exact(a) != Ordering::Greater);
    if p == 0 {
        view.len().saturating_sub(1)
    } else {
        p - 1
    }
}

/// Whether `x` lies strictly inside the counter-clockwise arc from `lo` to `hi` (exact).
pub fn strictly_between(lo: &Angle, x: &Angle, hi: &Angle) -> bool {
    match lo.cmp_exact(hi) {
        Ordering::Less => lo.cmp_exact(x) == Ordering::Less && x.cmp_exact(hi) == Ordering::Less,
        Ordering::Greater => lo.cmp_exact(x) == Ordering::Less || x.cmp_exact(hi) == Ordering::Less,
        Ordering::Equal => false,
    }
}

/// The `n` columns of the field of view `fov` (radians, below 2π) around `heading`.
pub fn columns(world: &World, frame: &FrameData, heading: f64, fov: f64, n: usize) -> Vec<Column> {
    let view = &frame.view;
    if n == 0 || view.is_empty() {
        return Vec::new();
    }
    let q = frame.q.to_f64();
    let step = fov / n as f64;
    let left = heading + fov / 2.0;
    let edges: Vec<(f64, Angle)> = (0..=n)
        .map(|k| {
            let a = left - step * k as f64;
            (a, direction_angle(a))
        })
        .collect();
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (_, hi) = &edges[k];
        let (lo_rad, lo) = &edges[k + 1];
        // Walk counter-clockwise from the right edge: the interval there, then each
        // boundary strictly inside the column.
        let mut i = interval_at(view, lo);
        let mut cuts: Vec<(usize, f64)> = Vec::new(); // (interval, offset of its start)
        cuts.push((i, 0.0));
        for _ in 1..view.len() {
            let next = (i + 1) % view.len();
            if !strictly_between(lo, &view[next].start, hi) {
                break;
            }
            let off = (view[next].start_radians - lo_rad).rem_euclid(TAU);
            cuts.push((next, off.clamp(0.0, step)));
            i = next;
        }
        let centre = step / 2.0;
        let mut pieces: Vec<Piece> = Vec::with_capacity(cuts.len());
        for (j, &(iv, from)) in cuts.iter().enumerate() {
            let to = cuts.get(j + 1).map_or(step, |c| c.1);
            let seen = &view[iv];
            let ray = if (from..=to).contains(&centre) {
                centre
            } else {
                (from + to) / 2.0
            };
            let (object, first, bounces, distance, facing, first_distance) = if frame.depth == 0 {
                let (d, f) = hit(world, seen.object, q, lo_rad + ray);
                (seen.object, None, 0, d, f, d)
            } else {
                deep_hit(world, seen, frame.depth, q, lo_rad + ray)
            };
            pieces.push(Piece {
                object,
                first,
                bounces,
                first_distance,
                fraction: if step > 0.0 { (to - from) / step } else { 1.0 },
                distance,
                facing,
            });
        }
        // Left to right is decreasing angle.
        pieces.reverse();
        out.push(Column { pieces });
    }
    out
}

/// The final object, the first object (if the ray goes on), the bounces, the unfolded
/// distance and facing of the final hit, and the distance of the first hit, along the
/// ray from `q` at angle `a` following the branch of `seen`.
fn deep_hit(
    world: &World,
    seen: &Seen,
    depth: usize,
    q: (f64, f64),
    a: f64,
) -> (Option<ObjectId>, Option<ObjectId>, usize, f64, f64, f64) {
    let branch = &seen.branch;
    let escaped = escapes(world, branch, depth);
    let stages = trace_branch(world, q, a, branch, false, 0.0);
    let length = |s: &super::Stage| (s.to.0 - s.from.0).hypot(s.to.1 - s.from.1);
    let first_distance = stages.first().map_or(f64::INFINITY, length);
    let bounces = if escaped {
        branch.len()
    } else {
        branch.len().saturating_sub(1)
    };
    let first = (bounces > 0).then(|| branch.first().copied()).flatten();
    if escaped || stages.is_empty() {
        return (None, first, bounces, f64::INFINITY, 0.0, first_distance);
    }
    let total: f64 = stages.iter().map(length).sum::<f64>().max(1e-9);
    let last = stages[stages.len() - 1];
    let facing = match last.hit {
        Some((o, e)) => {
            let poly = &world.polygons[o.0 as usize];
            let a0 = poly[e];
            let a1 = poly[(e + 1) % poly.len()];
            let (ex, ey) = (a1.0 - a0.0, a1.1 - a0.1);
            let (dx, dy) = (last.to.0 - last.from.0, last.to.1 - last.from.1);
            let n = ex.hypot(ey) * dx.hypot(dy);
            if n > 0.0 {
                ((ey * dx - ex * dy) / n).abs()
            } else {
                1.0
            }
        }
        None => 0.5,
    };
    (
        branch.last().copied(),
        first,
        bounces,
        total,
        facing,
        first_distance,
    )
}

/// Distance and facing of the hit of the ray from `q` at angle `a` with `object`.
fn hit(world: &World, object: Option<ObjectId>, q: (f64, f64), a: f64) -> (f64, f64) {
    let Some(poly) = object.and_then(|o| world.polygons.get(o.0 as usize)) else {
        return (f64::INFINITY, 0.0);
    };
    let d = (a.cos(), a.sin());
    if let Some((t, k)) = ray_polygon(poly, q, d) {
        let a0 = poly[k];
        let a1 = poly[(k + 1) % poly.len()];
        let e = (a1.0 - a0.0, a1.1 - a0.1);
        let len = e.0.hypot(e.1);
        let facing = if len > 0.0 {
            ((e.1 * d.0 - e.0 * d.1) / len).abs()
        } else {
            1.0
        };
        (t, facing)
    } else {
        // A grazing ray that rounding made miss: the distance to the object.
        (super::polygon_distance(poly, q.0, q.1), 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{compute_frame, World};

    #[test]
    fn columns_cover_exactly_the_boundaries_in_view() {
        let world = World::builtin().unwrap();
        for (x, y) in [(40.1, 43.15), (9.0, 10.0), (70.3, 20.7), (-5.0, 40.0)] {
            let q = vcx::QueryPoint::from_f64(x, y).unwrap();
            let frame = compute_frame(&world, q, 0).unwrap();
            for (heading, fov, n) in [(1.0, 1.5, 97), (5.9, 3.0, 40), (0.0, 0.3, 7)] {
                let cols = columns(&world, &frame, heading, fov, n);
                assert_eq!(cols.len(), n);
                // Boundaries inside columns = interval starts strictly inside the field of
                // view, minus those exactly on a column edge (none here).
                let lo = direction_angle(heading - fov / 2.0);
                let hi = direction_angle(heading + fov / 2.0);
                let inside = frame
                    .view
                    .iter()
                    .filter(|s| strictly_between(&lo, &s.start, &hi))
                    .count();
                let cuts: usize = cols.iter().map(|c| c.pieces.len() - 1).sum();
                assert_eq!(cuts, inside, "({x}, {y}) heading {heading}");
                for c in &cols {
                    let total: f64 = c.pieces.iter().map(|p| p.fraction).sum();
                    assert!((total - 1.0).abs() < 1e-9, "{c:?}");
                    for p in &c.pieces {
                        assert!((0.0..=1.0).contains(&p.fraction));
                        assert_eq!(p.object.is_some(), p.distance.is_finite(), "{p:?}");
                        assert!(p.distance > 0.0);
                    }
                    // Neighbouring pieces see different things.
                    assert!(c.pieces.windows(2).all(|w| w[0].object != w[1].object));
                }
                // The object at each column's centre, by the float angle, is the one of an
                // interval at that angle.
                for (k, c) in cols.iter().enumerate() {
                    let a = heading + fov / 2.0 - fov * (k as f64 + 0.5) / n as f64;
                    let i = interval_at(&frame.view, &direction_angle(a));
                    assert!(c.pieces.iter().any(|p| p.object == frame.view[i].object));
                }
            }
        }
    }
}
