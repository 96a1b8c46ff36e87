//! Degenerate scenes on purpose, and the checks run on them: shared by the cargo-fuzz
//! targets (`fuzz/`), the property harness (`tests/tests/degenerate.rs`) and the replay of
//! the committed regressions (`tests/tests/fuzz_regressions.rs`).
//!
//! **Inputs.** [`BuildInput`], [`LocateInput`], [`WalkInput`], [`RayTreeInput`],
//! [`IncrementalInput`] and [`CoverageInput`] (one per fuzz target) are small structures
//! that implement [`Arbitrary`] (so libFuzzer and proptest drive them from bytes, see
//! [`decode`]) and print with `{:?}` as Rust code: with `use vcx_tests::generators::{*,
//! Dir8::*, DirSpec::*, Gap::*, Mat::*, Place::*, PointSpec::*, Shape::*, StartSpec::*};`
//! a printed input pastes into a test as an expression.
//!
//! **Scenes.** A [`SceneSpec`] lays shapes on a coarse grid of `2^step` raw units (raw unit =
//! 2⁻¹⁶, the finest grid), so that collinear vertices, shared supporting lines and parallel
//! edges are the rule: axis-aligned boxes, convex hulls of lattice points, slivers (a
//! triangle one raw unit thick), tiny triangles of one raw unit, translated and mirrored
//! copies of earlier objects at gaps of zero (touching), one or two raw units, or one
//! cell, and vertex lists taken as written (often invalid). Steps near 23 reach the edge
//! of the coordinate range, and [`Place::Corner`] moves the whole scene against a corner
//! of the range, `±(2³⁰ − 1)` raw, where every coordinate is extreme and differences are
//! small. Everything is clamped to the range.
//!
//! **Checks.** Each `check_*` function returns `Err(message)` on any disagreement:
//! * [`check_validation`]: [`Scene::new`] against an independent exact oracle (every
//!   polygon error names an invalid polygon and a vertex that shows it; touch versus
//!   overlap by separating edges; valid scenes are stored counter-clockwise with the
//!   written vertex ids);
//! * [`check_complex`]: `build_by_sweep`, `validate`, `validate_at` along the axes, the
//!   diagonals, the scene's own edge directions and extra directions, and the number of
//!   free bitangents against [`reference::free_bitangents`];
//! * [`compare_locate`]: point location against [`reference::shoot_perturbed`];
//! * [`compare_view`]: the walked view against [`reference::view`] (same intervals, objects,
//!   boundary directions and boundary vertices);
//! * [`compare_ray_tree`]: walked ray trees against [`reference::ray_tree`] with rounded
//!   eyes;
//! * [`check_incremental`]: the randomized incremental construction against the sweep
//!   after every insertion, with memory budgets and rollback;
//! * [`check_scene_json`]: the JSON scene loader.
//! * [`check_coverage`]: the coverage table against the column-by-column pieces.

use core::fmt::{Debug, Formatter, Result as FmtResult};

use arbitrary::{Arbitrary, Unstructured};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{Signed, Zero};
use vcx::geom::point::MAX_ABS_RAW;
use vcx::geom::predicates::Direction;
use vcx::geom::sos::Angle;
use vcx::partition::{build_by_sweep, Complex, Location};
use vcx::walk::{view, TreeInterval, WalkError};
use vcx::{Eta, Material, ObjectId, Point, QueryPoint, Scene, SceneError, SceneRef, SubScene};

use crate::reference::{self, RefError, Vec2};

/// At most this many objects per scene.
pub const MAX_OBJECTS: usize = 12;
/// At most this many points per hull or written polygon.
pub const MAX_POINTS: usize = 8;

/// Decodes fuzzer bytes exactly as `libfuzzer_sys::fuzz_target!` (0.4) does: too short for
/// the size hint, or `arbitrary_take_rest` fails, is `None` (the target rejects the input).
pub fn decode<'a, T: Arbitrary<'a>>(bytes: &'a [u8]) -> Option<T> {
    if bytes.len() < T::size_hint(0).0 {
        return None;
    }
    T::arbitrary_take_rest(Unstructured::new(bytes)).ok()
}

fn bounded_vec<'a, T: Arbitrary<'a>>(
    u: &mut Unstructured<'a>,
    max: usize,
) -> arbitrary::Result<Vec<T>> {
    let n = u.int_in_range(0..=max)?;
    (0..n).map(|_| T::arbitrary(u)).collect()
}

fn objects<'a>(u: &mut Unstructured<'a>) -> arbitrary::Result<Vec<Obj>> {
    bounded_vec(u, MAX_OBJECTS)
}

fn points<'a>(u: &mut Unstructured<'a>) -> arbitrary::Result<Vec<(i8, i8)>> {
    bounded_vec(u, MAX_POINTS)
}

/// Prints a slice as `vec![…]`, so that printed inputs are Rust code.
struct VecLit<'a, T>(&'a [T]);

impl<T: Debug> Debug for VecLit<'_, T> {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        f.write_str("vec!")?;
        f.debug_list().entries(self.0).finish()
    }
}

// ---------------------------------------------------------------------------------------
// Scene specifications.

/// A degenerate scene (module documentation).
#[derive(Clone, PartialEq, Eq, Arbitrary)]
pub struct SceneSpec {
    /// The coarse grid cell is `2^step` raw units (`0..=23`; 16 is one unit).
    #[arbitrary(with = |u: &mut Unstructured| u.int_in_range(0..=23u8))]
    pub step: u8,
    /// Where the scene lies in the coordinate range.
    pub place: Place,
    /// The objects in input order (at most [`MAX_OBJECTS`]).
    #[arbitrary(with = objects)]
    pub objects: Vec<Obj>,
}

impl Debug for SceneSpec {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        f.debug_struct("SceneSpec")
            .field("step", &self.step)
            .field("place", &self.place)
            .field("objects", &VecLit(&self.objects))
            .finish()
    }
}

/// Where a scene lies.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub enum Place {
    /// As generated, around the origin.
    Origin,
    /// Translated so that its extreme coordinates are `±(2³⁰ − 1)` raw: the right (`east`)
    /// or left edge, the top (`north`) or bottom edge.
    Corner {
        /// Against `x = +(2³⁰ − 1)` rather than `−(2³⁰ − 1)`.
        east: bool,
        /// Against `y = +(2³⁰ − 1)` rather than `−(2³⁰ − 1)`.
        north: bool,
    },
}

/// One object of a [`SceneSpec`].
#[derive(Clone, PartialEq, Eq, Debug, Arbitrary)]
pub struct Obj {
    /// Its material.
    pub material: Mat,
    /// Written clockwise (reverses the generated counter-clockwise list).
    pub reversed: bool,
    /// The written list starts at this generated vertex (modulo the count).
    pub rotate: u8,
    /// Its shape.
    pub shape: Shape,
}

/// A material ([`Mat::Glass`] is refractive with η = 1.5).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub enum Mat {
    /// [`Material::Opaque`].
    Opaque,
    /// [`Material::Mirror`].
    Mirror,
    /// [`Material::Refractive`] with η = 1.5.
    Glass,
    /// [`Material::Screen`].
    Screen,
}

impl Mat {
    /// The core's material.
    pub fn material(self) -> Material {
        match self {
            Mat::Opaque => Material::Opaque,
            Mat::Mirror => Material::Mirror,
            Mat::Glass => Material::Refractive {
                eta: Eta::from_raw(3 << 15).expect("1.5 is a valid index"),
            },
            Mat::Screen => Material::Screen,
        }
    }
}

/// The eight compass directions.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub enum Dir8 {
    /// +x.
    E,
    /// +x +y.
    NE,
    /// +y.
    N,
    /// −x +y.
    NW,
    /// −x.
    W,
    /// −x −y.
    SW,
    /// −y.
    S,
    /// +x −y.
    SE,
}

impl Dir8 {
    fn signs(self) -> (i64, i64) {
        match self {
            Dir8::E => (1, 0),
            Dir8::NE => (1, 1),
            Dir8::N => (0, 1),
            Dir8::NW => (-1, 1),
            Dir8::W => (-1, 0),
            Dir8::SW => (-1, -1),
            Dir8::S => (0, -1),
            Dir8::SE => (1, -1),
        }
    }
}

/// The gap between an object and its copy.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub enum Gap {
    /// None: the copy touches (an invalid scene unless repaired).
    Touch,
    /// One raw unit (2⁻¹⁶): near-touching.
    Unit,
    /// Two raw units.
    TwoUnits,
    /// One coarse cell.
    Cell,
}

/// The shape of an object; coordinates are in coarse cells.
#[derive(Clone, PartialEq, Eq, Arbitrary)]
pub enum Shape {
    /// The axis-aligned box from cell `(x, y)` to `(x + w, y + h)`.
    Rect {
        /// Left edge.
        x: i8,
        /// Bottom edge.
        y: i8,
        /// Width in cells (`1..=16`).
        #[arbitrary(with = |u: &mut Unstructured| u.int_in_range(1..=16u8))]
        w: u8,
        /// Height in cells (`1..=16`).
        #[arbitrary(with = |u: &mut Unstructured| u.int_in_range(1..=16u8))]
        h: u8,
    },
    /// The strictly convex hull of lattice points (fewer than three vertices if they are
    /// collinear: then invalid).
    Hull {
        /// The points.
        #[arbitrary(with = points)]
        points: Vec<(i8, i8)>,
    },
    /// A vertex list as written: usually invalid (not convex, collinear, repeated…).
    Written {
        /// The vertices.
        #[arbitrary(with = points)]
        points: Vec<(i8, i8)>,
    },
    /// The triangle `a`, `b`, and the midpoint of `ab` (rounded down to the raw grid)
    /// moved one raw unit to one side.
    Sliver {
        /// One end.
        a: (i8, i8),
        /// The other end.
        b: (i8, i8),
        /// Which side the apex is moved to.
        left: bool,
    },
    /// A right triangle with legs of one raw unit at a lattice point.
    Tiny {
        /// The right-angle corner.
        at: (i8, i8),
    },
    /// A translated copy of an earlier object (`of` modulo their count), beside its
    /// bounding box in direction `dir` at gap `gap`.
    Translated {
        /// Index of the earlier object.
        of: u8,
        /// Where the copy goes.
        dir: Dir8,
        /// How far.
        gap: Gap,
    },
    /// A mirror image of an earlier object across the line at `gap / 2` beyond its
    /// bounding box in direction `dir` (a point reflection for the diagonals).
    Reflected {
        /// Index of the earlier object.
        of: u8,
        /// Where the image goes.
        dir: Dir8,
        /// How far.
        gap: Gap,
    },
}

impl Debug for Shape {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        match self {
            Shape::Rect { x, y, w, h } => f
                .debug_struct("Rect")
                .field("x", x)
                .field("y", y)
                .field("w", w)
                .field("h", h)
                .finish(),
            Shape::Hull { points } => f
                .debug_struct("Hull")
                .field("points", &VecLit(points))
                .finish(),
            Shape::Written { points } => f
                .debug_struct("Written")
                .field("points", &VecLit(points))
                .finish(),
            Shape::Sliver { a, b, left } => f
                .debug_struct("Sliver")
                .field("a", a)
                .field("b", b)
                .field("left", left)
                .finish(),
            Shape::Tiny { at } => f.debug_struct("Tiny").field("at", at).finish(),
            Shape::Translated { of, dir, gap } => f
                .debug_struct("Translated")
                .field("of", of)
                .field("dir", dir)
                .field("gap", gap)
                .finish(),
            Shape::Reflected { of, dir, gap } => f
                .debug_struct("Reflected")
                .field("of", of)
                .field("dir", dir)
                .field("gap", gap)
                .finish(),
        }
    }
}

type P = (i64, i64);

fn cross(o: P, a: P, b: P) -> i128 {
    let (ax, ay) = (i128::from(a.0 - o.0), i128::from(a.1 - o.1));
    let (bx, by) = (i128::from(b.0 - o.0), i128::from(b.1 - o.1));
    ax * by - ay * bx
}

/// Strictly convex hull, counter-clockwise (Andrew's monotone chain); fewer than three
/// points if all are collinear.
fn hull(mut pts: Vec<P>) -> Vec<P> {
    pts.sort_unstable();
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    // Lower chain left to right, then upper chain right to left.
    let mut out: Vec<P> = Vec::with_capacity(pts.len() + 1);
    let chain = |out: &mut Vec<P>, p: P, start: usize| {
        while out.len() >= start + 2 && cross(out[out.len() - 2], out[out.len() - 1], p) <= 0 {
            out.pop();
        }
        out.push(p);
    };
    for &p in &pts {
        chain(&mut out, p, 0);
    }
    out.pop();
    let start = out.len();
    for &p in pts.iter().rev() {
        chain(&mut out, p, start);
    }
    out.pop();
    out
}

fn bbox(pts: &[P]) -> Option<(P, P)> {
    let first = *pts.first()?;
    Some(pts.iter().fold((first, first), |(lo, hi), p| {
        (
            (lo.0.min(p.0), lo.1.min(p.1)),
            (hi.0.max(p.0), hi.1.max(p.1)),
        )
    }))
}

/// A scene spec turned into coordinates.
#[derive(Clone, Debug)]
pub struct Realized {
    /// Every object as written (possibly invalid), in input order.
    pub written: Vec<(Material, Vec<Point>)>,
    /// The coarse cell in raw units.
    pub cell: i64,
    /// The translation applied by [`SceneSpec::place`], in raw units.
    pub offset: P,
}

impl SceneSpec {
    /// The objects' coordinates.
    pub fn realize(&self) -> Realized {
        let step = u32::from(self.step.min(23));
        let cell = 1i64 << step;
        let at = |(x, y): (i8, i8)| (i64::from(x) * cell, i64::from(y) * cell);
        let gap_raw = |g: Gap| match g {
            Gap::Touch => 0,
            Gap::Unit => 1,
            Gap::TwoUnits => 2,
            Gap::Cell => cell,
        };
        // Model coordinates (raw units, unbounded) and whether to take the hull.
        let mut model: Vec<(Vec<P>, bool)> = Vec::new();
        for (i, o) in self.objects.iter().take(MAX_OBJECTS).enumerate() {
            let earlier = |of: u8| -> Vec<P> {
                if i == 0 {
                    Vec::new()
                } else {
                    model[usize::from(of) % i].0.clone()
                }
            };
            let shape = match &o.shape {
                Shape::Rect { x, y, w, h } => {
                    let (x0, y0) = at((*x, *y));
                    let (w, h) = (
                        i64::from((*w).clamp(1, 16)) * cell,
                        i64::from((*h).clamp(1, 16)) * cell,
                    );
                    (
                        vec![(x0, y0), (x0 + w, y0), (x0 + w, y0 + h), (x0, y0 + h)],
                        true,
                    )
                }
                Shape::Hull { points } => (
                    points.iter().take(MAX_POINTS).map(|&p| at(p)).collect(),
                    true,
                ),
                Shape::Written { points } => (
                    points.iter().take(MAX_POINTS).map(|&p| at(p)).collect(),
                    false,
                ),
                Shape::Sliver { a, b, left } => {
                    let (a, b) = (at(*a), at(*b));
                    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
                    let m = (a.0 + dx.div_euclid(2), a.1 + dy.div_euclid(2));
                    let s = if *left { 1 } else { -1 };
                    let apex = if dx.abs() >= dy.abs() {
                        (m.0, m.1 + s * dx.signum())
                    } else {
                        (m.0 - s * dy.signum(), m.1)
                    };
                    (vec![a, b, apex], true)
                }
                Shape::Tiny { at: p } => {
                    let p = at(*p);
                    (vec![p, (p.0 + 1, p.1), (p.0, p.1 + 1)], true)
                }
                Shape::Translated { of, dir, gap } => {
                    let src = earlier(*of);
                    let (sx, sy) = dir.signs();
                    let g = gap_raw(*gap);
                    let t = bbox(&src).map_or((0, 0), |(lo, hi)| {
                        (sx * (hi.0 - lo.0 + g), sy * (hi.1 - lo.1 + g))
                    });
                    (src.iter().map(|p| (p.0 + t.0, p.1 + t.1)).collect(), true)
                }
                Shape::Reflected { of, dir, gap } => {
                    let src = earlier(*of);
                    let (sx, sy) = dir.signs();
                    let g = gap_raw(*gap);
                    let pts = match bbox(&src) {
                        None => Vec::new(),
                        Some((lo, hi)) => {
                            // Reflect across x = c (2c = 2·edge ± g), likewise y.
                            let two_cx = match sx {
                                1 => 2 * hi.0 + g,
                                -1 => 2 * lo.0 - g,
                                _ => 0,
                            };
                            let two_cy = match sy {
                                1 => 2 * hi.1 + g,
                                -1 => 2 * lo.1 - g,
                                _ => 0,
                            };
                            src.iter()
                                .map(|p| {
                                    (
                                        if sx == 0 { p.0 } else { two_cx - p.0 },
                                        if sy == 0 { p.1 } else { two_cy - p.1 },
                                    )
                                })
                                .collect()
                        }
                    };
                    (pts, true)
                }
            };
            let shape = if shape.1 {
                (hull(shape.0), true)
            } else {
                shape
            };
            model.push(shape);
        }
        let max = i64::from(MAX_ABS_RAW);
        let all: Vec<P> = model.iter().flat_map(|m| m.0.iter().copied()).collect();
        let offset = match (self.place, bbox(&all)) {
            (Place::Corner { east, north }, Some((lo, hi))) => (
                if east { max - hi.0 } else { -max - lo.0 },
                if north { max - hi.1 } else { -max - lo.1 },
            ),
            _ => (0, 0),
        };
        let clamp = |p: &P| {
            (
                (p.0 + offset.0).clamp(-max, max),
                (p.1 + offset.1).clamp(-max, max),
            )
        };
        let written = self
            .objects
            .iter()
            .zip(&model)
            .map(|(o, (pts, take_hull))| {
                let pts: Vec<P> = pts.iter().map(clamp).collect();
                let mut pts = if *take_hull { hull(pts) } else { pts };
                if o.reversed {
                    pts.reverse();
                }
                if !pts.is_empty() {
                    let k = usize::from(o.rotate) % pts.len();
                    pts.rotate_left(k);
                }
                let pts = pts
                    .iter()
                    .map(|&(x, y)| {
                        Point::from_raw(x as i32, y as i32).expect("clamped to the range")
                    })
                    .collect();
                (o.material.material(), pts)
            })
            .collect();
        Realized {
            written,
            cell,
            offset,
        }
    }
}

impl Realized {
    /// The objects kept by a greedy repair: in input order, every object that is a valid
    /// polygon and disjoint from those kept before it (decided by the oracle of
    /// [`check_validation`]).
    pub fn repaired(&self) -> Vec<(Material, Vec<Point>)> {
        let mut kept: Vec<(Material, Vec<Point>)> = Vec::new();
        let mut kept_ccw: Vec<Vec<P>> = Vec::new();
        for (m, pts) in &self.written {
            let facts = PolygonFacts::of(pts);
            if !facts.valid() {
                continue;
            }
            let ccw = facts.ccw(pts);
            if kept_ccw
                .iter()
                .all(|k| relation(k, &ccw) == Relation::Disjoint)
            {
                kept.push((*m, pts.clone()));
                kept_ccw.push(ccw);
            }
        }
        kept
    }

    /// The repaired scene ([`Realized::repaired`]); an error if the core rejects it (then
    /// the core and the oracle disagree).
    pub fn scene(&self) -> Result<Scene, String> {
        let polys = self.repaired();
        Scene::new(polys.iter().map(|(m, p)| (*m, &p[..]))).map_err(|e| {
            format!("the core rejects a scene the oracle accepts: {e} ({e:?})\n{polys:?}")
        })
    }

    /// A coarse grid point as a query point.
    pub fn cell_point(&self, x: i8, y: i8) -> Option<QueryPoint> {
        let x = (i64::from(x) * self.cell + self.offset.0).checked_mul(1 << 16)?;
        let y = (i64::from(y) * self.cell + self.offset.1).checked_mul(1 << 16)?;
        QueryPoint::from_raw(x, y)
    }
}

// ---------------------------------------------------------------------------------------
// The validation oracle.

/// Exact facts about one written polygon, computed independently of the core.
#[derive(Clone, Debug)]
struct PolygonFacts {
    n: usize,
    /// `repeated[i]`: vertex `i` equals vertex `i − 1` (cyclically).
    repeated: Vec<bool>,
    /// Sign of `orient(prev, v, next)` at each vertex.
    turn: Vec<i8>,
    /// For a polygon turning strictly the same way at every vertex: how many times the
    /// boundary goes around.
    windings: Option<usize>,
}

fn lift(p: Point) -> P {
    (i64::from(p.x()), i64::from(p.y()))
}

/// `[0, π)` versus `[π, 2π)` for a non-zero vector.
fn upper(v: P) -> bool {
    v.1 > 0 || (v.1 == 0 && v.0 > 0)
}

impl PolygonFacts {
    fn of(pts: &[Point]) -> PolygonFacts {
        let p: Vec<P> = pts.iter().map(|&q| lift(q)).collect();
        let n = p.len();
        let at = |i: usize| p[i % n];
        let repeated = (0..n).map(|i| at(i) == at(i + n - 1)).collect();
        let turn: Vec<i8> = (0..n)
            .map(|i| cross(at(i + n - 1), at(i), at(i + 1)).signum() as i8)
            .collect();
        let windings = if n >= 3 && (turn.iter().all(|&t| t > 0) || turn.iter().all(|&t| t < 0)) {
            // Count the edges whose direction passes angle 0 from the previous edge's,
            // walking counter-clockwise (reverse a clockwise list).
            let mut q = p.clone();
            if turn[0] < 0 {
                q.reverse();
            }
            let edge = |i: usize| {
                let (a, b) = (q[i % n], q[(i + 1) % n]);
                (b.0 - a.0, b.1 - a.1)
            };
            let before = |u: P, v: P| -> bool {
                // Angle of u < angle of v in [0, 2π).
                match (upper(u), upper(v)) {
                    (true, false) => true,
                    (false, true) => false,
                    _ => cross((0, 0), u, v) > 0,
                }
            };
            Some((0..n).filter(|&i| before(edge(i + 1), edge(i))).count())
        } else {
            None
        };
        PolygonFacts {
            n,
            repeated,
            turn,
            windings,
        }
    }

    fn valid(&self) -> bool {
        self.n >= 3 && !self.repeated.contains(&true) && self.windings == Some(1)
    }

    /// The points counter-clockwise (for a valid polygon).
    fn ccw(&self, pts: &[Point]) -> Vec<P> {
        let mut p: Vec<P> = pts.iter().map(|&q| lift(q)).collect();
        if self.turn.first().is_some_and(|&t| t < 0) {
            p.reverse();
        }
        p
    }

    /// Whether the core's polygon error for this object is justified by these facts.
    fn justifies(&self, pts: &[Point], e: &SceneError) -> bool {
        match *e {
            SceneError::TooFewVertices { len, .. } => self.n < 3 && len == self.n,
            SceneError::RepeatedVertex {
                vertex, same_as, ..
            } => {
                vertex < self.n
                    && same_as < self.n
                    && pts[vertex] == pts[same_as]
                    && (same_as + 1 == vertex || (vertex + 1 == self.n && same_as == 0))
            }
            SceneError::CollinearVertices { vertex, .. } => {
                vertex < self.n && self.turn[vertex] == 0
            }
            SceneError::NotConvex { vertex, .. } => {
                vertex < self.n && self.turn[vertex] != 0 && self.turn.contains(&-self.turn[vertex])
            }
            SceneError::SelfIntersecting { windings, .. } => {
                windings >= 2 && self.windings == Some(windings)
            }
            _ => false,
        }
    }
}

/// How two closed convex polygons meet.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Relation {
    Disjoint,
    Touch,
    Overlap,
}

/// Separating-edge test on counter-clockwise polygons: disjoint iff some edge has the other
/// polygon strictly outside; interiors disjoint iff some edge has it outside or on.
fn relation(a: &[P], b: &[P]) -> Relation {
    let outside = |a: &[P], b: &[P], strict: bool| {
        (0..a.len()).any(|i| {
            let (p, q) = (a[i], a[(i + 1) % a.len()]);
            b.iter().all(|&r| {
                let c = cross(p, q, r);
                c < 0 || (!strict && c == 0)
            })
        })
    };
    if outside(a, b, true) || outside(b, a, true) {
        Relation::Disjoint
    } else if outside(a, b, false) || outside(b, a, false) {
        Relation::Touch
    } else {
        Relation::Overlap
    }
}

fn object_of(e: &SceneError) -> Option<usize> {
    match *e {
        SceneError::TooFewVertices { object, .. }
        | SceneError::RepeatedVertex { object, .. }
        | SceneError::CollinearVertices { object, .. }
        | SceneError::NotConvex { object, .. }
        | SceneError::SelfIntersecting { object, .. } => Some(object),
        _ => None,
    }
}

/// [`Scene::new`]'s answer for `written` against the oracle (module documentation).
pub fn check_validation(
    written: &[(Material, Vec<Point>)],
    result: &Result<Scene, SceneError>,
) -> Result<(), String> {
    let facts: Vec<PolygonFacts> = written.iter().map(|(_, p)| PolygonFacts::of(p)).collect();
    let first_invalid = facts.iter().position(|f| !f.valid());
    let show = || format!("{written:?}: core {:?}", result.as_ref().map(|_| ()));
    match (result, first_invalid) {
        (Err(e), Some(i)) => {
            let Some(object) = object_of(e) else {
                return Err(format!(
                    "object {i} is invalid, the core reports {e:?}\n{}",
                    show()
                ));
            };
            if object != i || !facts[i].justifies(&written[i].1, e) {
                return Err(format!(
                    "object {i} is the first invalid one ({:?}), the core reports {e:?}\n{}",
                    facts[i],
                    show()
                ));
            }
            Ok(())
        }
        (Ok(_), Some(i)) => Err(format!(
            "the core accepts invalid object {i} ({:?})\n{}",
            facts[i],
            show()
        )),
        (result, None) => {
            let ccw: Vec<Vec<P>> = facts
                .iter()
                .zip(written)
                .map(|(f, (_, p))| f.ccw(p))
                .collect();
            let mut first_bad = None;
            for i in 0..ccw.len() {
                for j in i + 1..ccw.len() {
                    let r = relation(&ccw[i], &ccw[j]);
                    if r != Relation::Disjoint && first_bad.is_none() {
                        first_bad = Some((i, j, r));
                    }
                }
            }
            match (result, first_bad) {
                (Ok(scene), None) => check_stored(written, &facts, scene),
                (Ok(_), Some((i, j, r))) => Err(format!(
                    "the core accepts objects {i} and {j}, which are {r:?}\n{}",
                    show()
                )),
                (Err(e), _) => {
                    let (first, second, want) = match *e {
                        SceneError::ObjectsTouch { first, second } => {
                            (first, second, Relation::Touch)
                        }
                        SceneError::ObjectsOverlap { first, second } => {
                            (first, second, Relation::Overlap)
                        }
                        _ => {
                            return Err(format!(
                                "all polygons are valid, the core reports {e:?}\n{}",
                                show()
                            ))
                        }
                    };
                    if first >= second
                        || second >= ccw.len()
                        || relation(&ccw[first], &ccw[second]) != want
                    {
                        return Err(format!(
                            "the core reports {e:?}; the oracle finds {:?} (first pair {first_bad:?})\n{}",
                            ccw.get(second)
                                .filter(|_| first < second)
                                .map(|b| relation(&ccw[first], b)),
                            show()
                        ));
                    }
                    Ok(())
                }
            }
        }
    }
}

/// A valid scene stores each object counter-clockwise, with the written ids and material.
fn check_stored(
    written: &[(Material, Vec<Point>)],
    facts: &[PolygonFacts],
    scene: &Scene,
) -> Result<(), String> {
    let s = scene.as_ref();
    if s.len() != written.len() {
        return Err(format!(
            "{} objects stored, {} written",
            s.len(),
            written.len()
        ));
    }
    for (i, (o, (m, pts))) in s.objects().iter().zip(written).enumerate() {
        let poly = s.polygon(o);
        let ok = o.material == *m
            && poly.len() == pts.len()
            && o.was_clockwise() == (facts[i].turn[0] < 0)
            && (0..poly.len()).all(|k| {
                let (a, b, c) = (
                    lift(poly[k]),
                    lift(poly[(k + 1) % poly.len()]),
                    lift(poly[(k + 2) % poly.len()]),
                );
                cross(a, b, c) > 0 && pts.get(o.written_vertex_id(k)) == Some(&poly[k])
            });
        if !ok {
            return Err(format!(
                "object {i} stored as {poly:?} (clockwise {}), written {pts:?}",
                o.was_clockwise()
            ));
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// The complex.

/// Directions where the complex is checked against the brute-force cross-section: the
/// axes, the diagonals, `extra`, and the directions of the scene's first 24 edges (both
/// ways) — constant directions parallel to edges are the most degenerate ones.
pub fn check_directions(s: &SceneRef<'_>, extra: &[(i8, i8)]) -> Vec<Direction> {
    let mut out: Vec<Direction> = [
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
        (-1, -1),
        (0, -1),
        (1, -1),
    ]
    .iter()
    .chain(extra)
    .filter_map(|&(x, y)| Direction::new(i64::from(x), i64::from(y)))
    .collect();
    let mut edges = 0;
    for o in s.objects() {
        let poly = s.polygon(o);
        for k in 0..poly.len() {
            if edges == 24 {
                break;
            }
            let (a, b) = (lift(poly[k]), lift(poly[(k + 1) % poly.len()]));
            out.extend(Direction::new(b.0 - a.0, b.1 - a.1));
            out.extend(Direction::new(a.0 - b.0, a.1 - b.1));
            edges += 1;
        }
    }
    out
}

/// Builds the complex of a valid scene and checks it (module documentation).
pub fn check_complex(s: &SceneRef<'_>, extra: &[(i8, i8)]) -> Result<Complex, String> {
    let c = build_by_sweep(s).map_err(|e| format!("build_by_sweep: {e} ({e:?})"))?;
    c.validate(s)
        .map_err(|e| format!("validate: {e} ({e:?})"))?;
    for d in check_directions(s, extra) {
        c.validate_at(s, &Angle::constant(d))
            .map_err(|e| format!("validate_at {d:?}: {e} ({e:?})"))?;
    }
    let want = reference::free_bitangents(*s);
    if c.free_bitangents() != want.undirected || c.vertices().len() != want.directed {
        return Err(format!(
            "free bitangents: core {} ({} directed), reference {} ({} directed)",
            c.free_bitangents(),
            c.vertices().len(),
            want.undirected,
            want.directed
        ));
    }
    Ok(c)
}

/// Point location from `q` in direction `d` against exact ray shooting under the
/// perturbation. `Ok(true)` if `q` is free (a cylinder was compared), `Ok(false)` if both
/// agree that `q` is in or on an object.
pub fn compare_locate(
    s: &SceneRef<'_>,
    c: &Complex,
    q: QueryPoint,
    d: Direction,
) -> Result<bool, String> {
    let rq = Vec2::from_query(q);
    let rd = Vec2::from_i64(d.x, d.y);
    match (c.locate(s, q, d), reference::shoot_perturbed(*s, &rq, &rd)) {
        (Some(Location::Free { cylinder }), Ok(want)) => {
            let cyl = c
                .cylinder(cylinder)
                .ok_or_else(|| format!("q {q:?} d {d:?}: cylinder {cylinder:?} out of range"))?;
            if (cyl.ceiling, cyl.floor) != (want.forward, want.backward) {
                return Err(format!(
                    "q {q:?} d {d:?}: core (ceiling, floor) {:?}, reference (forward, backward) {:?}",
                    (cyl.ceiling, cyl.floor),
                    (want.forward, want.backward)
                ));
            }
            Ok(true)
        }
        (
            Some(Location::Inside { object } | Location::OnBoundary { object }),
            Err(RefError::ViewpointNotFree { object: want }),
        ) if object == want => Ok(false),
        (got, want) => Err(format!("q {q:?} d {d:?}: core {got:?}, reference {want:?}")),
    }
}

/// (object, vertex id as written) of a global vertex index.
pub fn written_vertex(s: &SceneRef<'_>, k: usize) -> Option<(u32, usize)> {
    s.objects().iter().enumerate().find_map(|(i, o)| {
        (o.first_vertex()..o.first_vertex() + o.len())
            .contains(&k)
            .then(|| (i as u32, o.written_vertex_id(k - o.first_vertex())))
    })
}

/// Whether the integer vector `v` points exactly along the reference direction `r`.
pub fn same_direction(v: (i128, i128), r: &Vec2) -> bool {
    let big = |x: i128| BigRational::from_integer(BigInt::from(x));
    let d = Vec2::new(big(v.0), big(v.1));
    d.cross(r).is_zero() && d.dot(r).is_positive()
}

/// The view from `q` walked in the complex of the scene's non-screen objects (`sub`, a
/// [`SubScene`] of `s`, and its complex `c`) against the reference view of `s` (screens
/// transparent). `Ok(true)` if `q` is free and the views were compared.
pub fn compare_view(
    s: &SceneRef<'_>,
    sub: &SubScene<'_>,
    c: &Complex,
    q: QueryPoint,
) -> Result<bool, String> {
    let sr = sub.as_ref();
    let want = reference::view(*s, &Vec2::from_query(q));
    let got = view(c, &sr, q);
    let (want, got) = match (want, got) {
        (Err(_), Err(WalkError::NotFree(_))) => return Ok(false),
        // In a screen: the reference refuses, the screen-less complex does not.
        (Err(RefError::ViewpointNotFree { object }), Ok(_))
            if s.object(object)
                .is_some_and(|o| o.material == Material::Screen) =>
        {
            return Ok(false)
        }
        (Ok(w), Ok(g)) => (w, g),
        (w, g) => return Err(format!("q {q:?}: reference {w:?}, core {g:?}")),
    };
    let show = |why: &str| format!("q {q:?}: {why}\n core {got:#?}\n reference {want:#?}");
    if got.len() != want.len() {
        return Err(show("different number of intervals"));
    }
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        let object = g.object.and_then(|o| sub.original(o));
        if object != w.value {
            return Err(show(&format!("interval {i}: object")));
        }
        if w.start_vertex.is_some() && !same_direction(g.start.vector(), &w.start) {
            return Err(show(&format!("interval {i}: start direction")));
        }
        let gv = g.start_vertex.and_then(|k| written_vertex(s, k));
        let wv = w.start_vertex.map(|v| (v.object.0, v.vertex));
        if gv != wv {
            return Err(show(&format!(
                "interval {i}: boundary vertex core {gv:?}, reference {wv:?}"
            )));
        }
    }
    Ok(true)
}

// ---------------------------------------------------------------------------------------
// Queries.

/// A query point, placed to hit degeneracies. Vertex indices are global
/// (`SceneRef::vertices()`, counter-clockwise storage), modulo the vertex count.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub enum PointSpec {
    /// The coarse grid point `(x, y)`.
    GridPoint {
        /// x in cells.
        x: i8,
        /// y in cells.
        y: i8,
    },
    /// On the line through vertices `a` and `b`: `a + (t/4)(b − a)` (an edge's extension
    /// when they are neighbours, a bitangent's line when they are on different objects).
    OnLine {
        /// First vertex.
        a: u8,
        /// Second vertex.
        b: u8,
        /// Position in quarters of `b − a`.
        t: i8,
    },
    /// Vertex `v` moved by `(dx, dy) · 2^shift` query units (2⁻³²; `shift` in `0..=40`).
    NearVertex {
        /// The vertex.
        v: u8,
        /// x offset.
        dx: i8,
        /// y offset.
        dy: i8,
        /// Scale of the offset: 0 is the query grid, 16 the scene grid, 32 one unit.
        #[arbitrary(with = |u: &mut Unstructured| u.int_in_range(0..=40u8))]
        shift: u8,
    },
    /// Any query point, in raw query units (2⁻³²); for hand-minimized regressions.
    Raw {
        /// x.
        x: i64,
        /// y.
        y: i64,
    },
}

impl PointSpec {
    /// The query point (`None` when out of range or the scene has no vertex).
    pub fn point(self, r: &Realized, s: &SceneRef<'_>) -> Option<QueryPoint> {
        let v = s.vertices();
        let vertex = |k: u8| -> Option<(i64, i64)> {
            let p = v.get(usize::from(k) % v.len().max(1))?;
            Some((i64::from(p.x()) << 16, i64::from(p.y()) << 16))
        };
        match self {
            PointSpec::GridPoint { x, y } => r.cell_point(x, y),
            PointSpec::OnLine { a, b, t } => {
                let (a, b) = (vertex(a)?, vertex(b)?);
                let t = i64::from(t);
                QueryPoint::from_raw(
                    a.0.checked_add(((b.0 - a.0) >> 2).checked_mul(t)?)?,
                    a.1.checked_add(((b.1 - a.1) >> 2).checked_mul(t)?)?,
                )
            }
            PointSpec::NearVertex { v, dx, dy, shift } => {
                let p = vertex(v)?;
                let s = u32::from(shift.min(40));
                QueryPoint::from_raw(p.0 + (i64::from(dx) << s), p.1 + (i64::from(dy) << s))
            }
            PointSpec::Raw { x, y } => QueryPoint::from_raw(x, y),
        }
    }
}

/// The direction of a ray.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub enum DirSpec {
    /// A compass direction.
    Axis(Dir8),
    /// From the ray's origin towards vertex `v` (through it).
    Towards {
        /// The vertex.
        v: u8,
    },
    /// Along the line from vertex `a` to vertex `b` (an edge's direction for neighbours).
    Along {
        /// From.
        a: u8,
        /// To.
        b: u8,
    },
    /// Any small integer vector.
    Free {
        /// x.
        x: i16,
        /// y.
        y: i16,
    },
}

impl DirSpec {
    /// The direction from `q` (`None` for a zero or too long vector).
    pub fn direction(self, q: QueryPoint, s: &SceneRef<'_>) -> Option<Direction> {
        let v = s.vertices();
        let vertex = |k: u8| v.get(usize::from(k) % v.len().max(1)).copied();
        match self {
            DirSpec::Axis(d) => {
                let (x, y) = d.signs();
                Direction::new(x, y)
            }
            DirSpec::Towards { v } => {
                let p = vertex(v)?.to_query();
                Direction::new(p.x() - q.x(), p.y() - q.y())
            }
            DirSpec::Along { a, b } => {
                let (a, b) = (vertex(a)?, vertex(b)?);
                Direction::new(
                    i64::from(b.x()) - i64::from(a.x()),
                    i64::from(b.y()) - i64::from(a.y()),
                )
            }
            DirSpec::Free { x, y } => Direction::new(i64::from(x), i64::from(y)),
        }
    }
}

/// A ray from a query point.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub struct RaySpec {
    /// Its origin.
    pub from: PointSpec,
    /// Its direction.
    pub dir: DirSpec,
}

// ---------------------------------------------------------------------------------------
// Inputs of the fuzz targets, and their checks.

/// Input of the `build` target.
#[derive(Clone, PartialEq, Eq, Arbitrary)]
pub struct BuildInput {
    /// The scene.
    pub scene: SceneSpec,
    /// Extra directions for `validate_at` (at most 4).
    #[arbitrary(with = |u: &mut Unstructured| bounded_vec(u, 4))]
    pub directions: Vec<(i8, i8)>,
}

impl Debug for BuildInput {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        f.debug_struct("BuildInput")
            .field("scene", &self.scene)
            .field("directions", &VecLit(&self.directions))
            .finish()
    }
}

/// Validation of the written scene against the oracle, then the repaired scene's complex.
pub fn check_build(input: &BuildInput) -> Result<(), String> {
    let r = input.scene.realize();
    let result = Scene::new(r.written.iter().map(|(m, p)| (*m, &p[..])));
    check_validation(&r.written, &result)?;
    let scene = r.scene()?;
    check_complex(&scene.as_ref(), &input.directions)?;
    Ok(())
}

/// Input of the `locate` target.
#[derive(Clone, PartialEq, Eq, Arbitrary)]
pub struct LocateInput {
    /// The scene (repaired).
    pub scene: SceneSpec,
    /// The rays (at most 8).
    #[arbitrary(with = |u: &mut Unstructured| bounded_vec(u, 8))]
    pub rays: Vec<RaySpec>,
}

impl Debug for LocateInput {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        f.debug_struct("LocateInput")
            .field("scene", &self.scene)
            .field("rays", &VecLit(&self.rays))
            .finish()
    }
}

/// Point location of every ray against exact ray shooting. Returns how many rays were
/// compared from free points.
pub fn check_locate(input: &LocateInput) -> Result<usize, String> {
    let r = input.scene.realize();
    let scene = r.scene()?;
    let s = scene.as_ref();
    let c = build_by_sweep(&s).map_err(|e| format!("build_by_sweep: {e}"))?;
    let mut free = 0;
    for ray in &input.rays {
        let Some(q) = ray.from.point(&r, &s) else {
            continue;
        };
        let Some(d) = ray.dir.direction(q, &s) else {
            continue;
        };
        free += usize::from(compare_locate(&s, &c, q, d).map_err(|e| format!("{ray:?}: {e}"))?);
    }
    Ok(free)
}

/// Input of the `walk` target.
#[derive(Clone, PartialEq, Eq, Arbitrary)]
pub struct WalkInput {
    /// The scene (repaired; screens are left out of the complex and transparent).
    pub scene: SceneSpec,
    /// The viewpoints (at most 4).
    #[arbitrary(with = |u: &mut Unstructured| bounded_vec(u, 4))]
    pub viewpoints: Vec<PointSpec>,
}

impl Debug for WalkInput {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        f.debug_struct("WalkInput")
            .field("scene", &self.scene)
            .field("viewpoints", &VecLit(&self.viewpoints))
            .finish()
    }
}

/// From every viewpoint: the view walked in the complex of the non-screen objects against
/// the reference view, and the depth-0 ray tree walked in the complex of the whole scene
/// against the reference's. Returns how many viewpoints were free.
pub fn check_walk(input: &WalkInput) -> Result<usize, String> {
    let r = input.scene.realize();
    let scene = r.scene()?;
    let s = scene.as_ref();
    let ids = s
        .objects()
        .iter()
        .enumerate()
        .filter(|(_, o)| o.material != Material::Screen)
        .map(|(i, _)| ObjectId(i as u32));
    let sub = SubScene::new(s, ids);
    let c = build_by_sweep(&sub.as_ref()).map_err(|e| format!("build_by_sweep: {e}"))?;
    let whole = build_by_sweep(&s).map_err(|e| format!("build_by_sweep: {e}"))?;
    let (sr, c_arcs) = (sub.as_ref(), c.clone().with_arc_vertices(&sub.as_ref()));
    let whole_arcs = whole.clone().with_arc_vertices(&s);
    let mut free = 0;
    for v in &input.viewpoints {
        let Some(q) = v.point(&r, &s) else { continue };
        free += usize::from(compare_view(&s, &sub, &c, q).map_err(|e| format!("{v:?}: {e}"))?);
        same_with_arc_vertices(view(&c, &sr, q), view(&c_arcs, &sr, q))
            .map_err(|e| format!("{v:?} view: {e}"))?;
        compare_ray_tree(&s, &whole, q, 0).map_err(|e| format!("{v:?} depth 0: {e}"))?;
        same_with_arc_vertices(
            vcx::walk::ray_tree(&whole, &s, q, 0),
            vcx::walk::ray_tree(&whole_arcs, &s, q, 0),
        )
        .map_err(|e| format!("{v:?} depth 0: {e}"))?;
    }
    Ok(free)
}

/// A walk in a complex with the opt-in arc-vertex index (`Complex::with_arc_vertices`)
/// against the same walk without it: its shortcuts must not change a bit of the output
/// (compared in full, exact angles included, through `Debug`).
fn same_with_arc_vertices<T: Debug>(plain: T, indexed: T) -> Result<(), String> {
    let (plain, indexed) = (format!("{plain:?}"), format!("{indexed:?}"));
    if plain == indexed {
        Ok(())
    } else {
        Err(format!(
            "with arc vertices\n plain {plain}\n indexed {indexed}"
        ))
    }
}

/// Input of the `ray_tree` target.
#[derive(Clone, PartialEq, Eq, Arbitrary)]
pub struct RayTreeInput {
    /// The scene (repaired).
    pub scene: SceneSpec,
    /// Depth of the ray trees (`1..=2`).
    #[arbitrary(with = |u: &mut Unstructured| u.int_in_range(1..=2u8))]
    pub depth: u8,
    /// The viewpoints (at most 2).
    #[arbitrary(with = |u: &mut Unstructured| bounded_vec(u, 2))]
    pub viewpoints: Vec<PointSpec>,
}

impl Debug for RayTreeInput {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        f.debug_struct("RayTreeInput")
            .field("scene", &self.scene)
            .field("depth", &self.depth)
            .field("viewpoints", &VecLit(&self.viewpoints))
            .finish()
    }
}

/// The ray tree of the input's depth from every viewpoint against the reference
/// ([`compare_ray_tree`]), and the same tree walked with the arc-vertex index and in the
/// complex pruned to the viewpoints' bounding box (`vcx build --region`). Returns how many
/// were compared.
pub fn check_ray_tree(input: &RayTreeInput) -> Result<usize, String> {
    let r = input.scene.realize();
    let scene = r.scene()?;
    let s = scene.as_ref();
    let c = build_by_sweep(&s).map_err(|e| format!("build_by_sweep: {e}"))?;
    let depth = usize::from(input.depth.clamp(1, 2));
    let c_arcs = c.clone().with_arc_vertices(&s);
    let points: Vec<_> = input
        .viewpoints
        .iter()
        .filter_map(|v| Some((v, v.point(&r, &s)?)))
        .collect();
    let pruned = match region_around(points.iter().map(|&(_, q)| q)) {
        Some(b) => Some(
            c.prune_to_region(&s, b)
                .map_err(|e| format!("prune_to_region {b:?}: {e}"))?,
        ),
        None => None,
    };
    let mut compared = 0;
    for &(v, q) in &points {
        compared += usize::from(
            compare_ray_tree(&s, &c, q, depth).map_err(|e| format!("{v:?} depth {depth}: {e}"))?,
        );
        let tree = vcx::walk::ray_tree(&c, &s, q, depth);
        same_with_arc_vertices(&tree, &vcx::walk::ray_tree(&c_arcs, &s, q, depth))
            .map_err(|e| format!("{v:?} depth {depth}: {e}"))?;
        if let Some(p) = &pruned {
            let got = vcx::walk::ray_tree(p, &s, q, depth);
            if format!("{got:?}") != format!("{tree:?}") {
                return Err(format!(
                    "{v:?} depth {depth}, pruned to {:?}:\n whole {tree:?}\n pruned {got:?}",
                    p.region()
                ));
            }
        }
    }
    Ok(compared)
}

/// The smallest box on the scene grid holding the points, if any.
fn region_around(points: impl Iterator<Item = QueryPoint>) -> Option<vcx::partition::Region> {
    let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
    for q in points {
        lo = (lo.0.min(q.x()), lo.1.min(q.y()));
        hi = (hi.0.max(q.x()), hi.1.max(q.y()));
    }
    // Query coordinates are scene coordinates times 2¹⁶: floor and ceiling.
    let corner = |x: i64, y: i64| Point::from_raw(i32::try_from(x).ok()?, i32::try_from(y).ok()?);
    let min = corner(lo.0 >> 16, lo.1 >> 16)?;
    let max = corner(-((-hi.0) >> 16), -((-hi.1) >> 16))?;
    vcx::partition::Region::new(min, max)
}

/// The ray tree from `q` to `depth` walked in the complex `c` of the whole scene `s`
/// against the reference with eyes rounded as the core rounds them: same intervals,
/// branches and boundary vertices, boundary angles within 10⁻⁹ rad, exact primary
/// boundaries in the reference's direction. `Ok(true)` if compared; `Ok(false)` if `q` is
/// not free, or the optics is degenerate for the reference, or a virtual eye leaves the
/// query range (documented errors).
pub fn compare_ray_tree(
    s: &SceneRef<'_>,
    c: &Complex,
    q: QueryPoint,
    depth: usize,
) -> Result<bool, String> {
    use crate::reference::RayTreeOptions;
    let want = reference::ray_tree(
        *s,
        &Vec2::from_query(q),
        RayTreeOptions {
            depth,
            round_eyes: true,
        },
    );
    let got = vcx::walk::ray_tree(c, s, q, depth);
    let (want, got) = match (want, got) {
        (Err(RefError::ViewpointNotFree { .. }), Err(WalkError::NotFree(_)))
        | (Err(RefError::DegenerateOptics { .. }), _)
        | (_, Err(WalkError::EyeOutOfRange)) => return Ok(false),
        (Ok(w), Ok(g)) => (w, g),
        (w, g) => return Err(format!("q {q:?}: reference {w:?}, core {g:?}")),
    };
    let show = |why: &str| {
        let g: Vec<_> = got
            .iter()
            .map(|i| {
                (
                    i.start,
                    &i.branch,
                    i.start_vertex.and_then(|k| written_vertex(s, k)),
                )
            })
            .collect();
        let w: Vec<_> = want
            .iter()
            .map(|i| {
                (
                    i.start_angle,
                    &i.value,
                    i.start_vertex.map(|v| (v.object.0, v.vertex)),
                )
            })
            .collect();
        format!("q {q:?}: {why}\n core {g:?}\n reference {w:?}")
    };
    if got.len() != want.len() {
        return Err(show("different number of intervals"));
    }
    let tau = core::f64::consts::TAU;
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        if g.branch != w.value {
            return Err(show(&format!("interval {i}: branch")));
        }
        let gv = g.start_vertex.and_then(|k| written_vertex(s, k));
        let wv = w.start_vertex.map(|v| (v.object.0, v.vertex));
        if gv != wv {
            return Err(show(&format!("interval {i}: boundary vertex")));
        }
        if w.start_vertex.is_some() {
            let d = (g.start - w.start_angle).rem_euclid(tau);
            if d.min(tau - d) >= 1e-9 {
                return Err(show(&format!("interval {i}: start angle")));
            }
            if let Some(a) = g.exact_start {
                if !same_direction(a.vector(), &w.start) {
                    return Err(show(&format!("interval {i}: exact start direction")));
                }
            }
        }
    }
    check_tree_ranges(s, c, q, depth, &got)?;
    Ok(true)
}

/// One interval of a restricted ray tree, in order from the range's start: branch and
/// boundary vertex.
pub type RangeRow = (Vec<ObjectId>, Option<usize>);

/// The full ray tree `full` (sorted, cyclic) restricted to the primary directions
/// counter-clockwise from `from` to `to` (the full circle if equal), as
/// `walk::ray_tree_range` defines it: the interval containing `from` first (its vertex only
/// if its start is exactly `from`), then every interval starting strictly inside the range,
/// round to the containing interval's own start if the range reaches it again. Exact for
/// exact (primary) starts; `None` when an `f64`-only start lies within 10⁻⁹ rad of an end
/// (undecidable here).
pub fn restricted(full: &[TreeInterval], from: Direction, to: Direction) -> Option<Vec<RangeRow>> {
    use core::cmp::Ordering::{Equal, Less};
    let tau = core::f64::consts::TAU;
    let (fa, ta) = (Angle::constant(from), Angle::constant(to));
    let (fr, tr) = (fa.radians(), ta.radians());
    let near = |a: f64, b: f64| {
        let d = (a - b).rem_euclid(tau);
        d.min(tau - d) < 1e-9
    };
    if full.len() == 1 {
        return Some(vec![(full[0].branch.clone(), None)]);
    }
    // Position counter-clockwise from `from` as (lap, angle): exact for exact starts, in
    // radians for the others (undecidable next to an end).
    #[derive(Clone, Copy)]
    enum Pos {
        Exact(u8, Angle),
        Rel(f64),
    }
    let lap = |a: &Angle| u8::from(a.cmp_exact(&fa) == Less);
    let pos: Vec<Pos> = full
        .iter()
        .map(|i| match i.exact_start {
            Some(a) => Some(Pos::Exact(lap(&a), a)),
            None if near(i.start, fr) || near(i.start, tr) => None,
            None => Some(Pos::Rel((i.start - fr).rem_euclid(tau))),
        })
        .collect::<Option<_>>()?;
    let full_circle = fa.cmp_exact(&ta) == Equal;
    let lap_t = if full_circle { 1 } else { lap(&ta) };
    // The exact lap says on which side of `from` the end lies; the `f64` difference only
    // how far (a range a few 10⁻¹⁷ rad short of the full circle has `tr == fr`).
    let rel_t = match (full_circle, lap_t) {
        (true, _) => tau,
        (false, 1) => (tr - fr + tau).clamp(0.0, tau),
        (false, _) => (tr - fr).clamp(0.0, tau),
    };
    let at_from = |p: &Pos| matches!(p, Pos::Exact(0, a) if a.cmp_exact(&fa) == Equal);
    let inside = |p: &Pos| match p {
        Pos::Exact(l, a) => *l < lap_t || (*l == lap_t && a.cmp_exact(&ta) == Less),
        Pos::Rel(r) => *r < rel_t,
    };
    // The interval containing `from`: one starting on it, else the one starting last
    // before it (counter-clockwise from `from`, the largest position).
    let key = |p: &Pos| match p {
        Pos::Exact(l, a) => {
            let ar = a.radians();
            // Within rounding of `from` itself the exact lap decides the side. (A start
            // across θ = 0 from `from`, a few 10⁻¹⁰ rad ahead, is no tie: its radians
            // differ from `from`'s by about 2π.)
            match (ar - fr).abs() < 1e-9 {
                true if *l == 0 => 0.0,
                true => tau,
                false => (ar - fr).rem_euclid(tau),
            }
        }
        Pos::Rel(r) => *r,
    };
    // Exact positions compare exactly, by lap and angle.
    let order = |a: &Pos, b: &Pos| match (a, b) {
        (Pos::Exact(la, a), Pos::Exact(lb, b)) => la.cmp(lb).then_with(|| a.cmp_exact(b)),
        _ => key(a).total_cmp(&key(b)),
    };
    let k0 = match pos.iter().position(at_from) {
        Some(k) => k,
        None => (0..full.len()).max_by(|&a, &b| order(&pos[a], &pos[b]))?,
    };
    let on_from = at_from(&pos[k0]);
    let mut rows = vec![(
        full[k0].branch.clone(),
        full[k0].start_vertex.filter(|_| on_from),
    )];
    for j in 1..=full.len() {
        let k = (k0 + j) % full.len();
        // Round to the containing interval again: its own start, unless that is `from`.
        let p = if j == full.len() && on_from {
            Pos::Rel(tau)
        } else {
            pos[k]
        };
        if !inside(&p) {
            break;
        }
        rows.push((full[k].branch.clone(), full[k].start_vertex));
    }
    Some(rows)
}

/// `walk::ray_tree_range` against [`restricted`] of the full tree `full` from `q`, over
/// ranges chosen from the tree and the scene: between exact boundaries, from a boundary
/// round to itself (the full circle), and between directions towards scene vertices.
/// Returns how many ranges were compared.
pub fn check_tree_ranges(
    s: &SceneRef<'_>,
    c: &Complex,
    q: QueryPoint,
    depth: usize,
    full: &[TreeInterval],
) -> Result<usize, String> {
    let exact: Vec<Direction> = full
        .iter()
        .filter_map(|i| i.exact_start)
        .filter_map(|a| {
            let (x, y) = a.vector();
            Direction::new(i64::try_from(x).ok()?, i64::try_from(y).ok()?)
        })
        .collect();
    let toward = |k: usize| {
        let v = s.vertices().get(k % s.vertices().len().max(1))?.to_query();
        Direction::new(v.x() - q.x(), v.y() - q.y())
    };
    let mut ranges = Vec::new();
    for k in 0..exact.len().min(3) {
        ranges.push((Some(exact[k]), exact.get(k + 2).copied()));
        ranges.push((Some(exact[k]), Some(exact[k])));
    }
    for k in [0, 1, 5] {
        ranges.push((toward(k), toward(k + 3)));
        ranges.push((toward(k), toward(k)));
    }
    let ranges = ranges.into_iter().filter_map(|(f, t)| Some((f?, t?)));
    compare_tree_ranges(s, c, q, depth, full, ranges)
}

/// `walk::frame_tree_into` with 64 walks, 64 splits and `H` hops: each interval's start bits and branch.
fn stream<const H: usize>(
    c: &Complex,
    s: &SceneRef<'_>,
    (q, depth, from, to): (QueryPoint, usize, Direction, Direction),
) -> Result<Vec<(u64, Vec<ObjectId>)>, vcx::walk::WalkError> {
    let mut streamed = Vec::new();
    let mut scratch = Box::new(vcx::walk::TreeScratch::<64, 64, H>::new());
    vcx::walk::frame_tree_into(c, s, q, depth, from, to, &mut scratch, |i| {
        streamed.push((i.start.to_bits(), i.branch.to_vec()))
    })?;
    Ok(streamed)
}

/// `walk::ray_tree_range` from `q` against [`restricted`] of the full tree `full` over the
/// given ranges; the ranges [`restricted`] cannot decide are skipped. Returns how many were
/// compared.
pub fn compare_tree_ranges(
    s: &SceneRef<'_>,
    c: &Complex,
    q: QueryPoint,
    depth: usize,
    full: &[TreeInterval],
    ranges: impl IntoIterator<Item = (Direction, Direction)>,
) -> Result<usize, String> {
    // The hops `TreeScratch` documents as enough: one per level through mirrors, two with
    // refraction (the usual depths below; deeper trees take 64).
    let refraction = s
        .objects()
        .iter()
        .any(|o| matches!(o.material, vcx::Material::Refractive { .. }));
    let hops = if refraction { 2 * depth } else { depth };
    let mut compared = 0;
    for (from, to) in ranges {
        let Some(want) = restricted(full, from, to) else {
            continue;
        };
        let at = |e: String| format!("q {q:?} depth {depth} range {from:?}..{to:?}: {e}");
        let got =
            vcx::walk::ray_tree_range(c, s, q, depth, from, to).map_err(|e| at(e.to_string()))?;
        // What a frame draws: the same intervals, without vertices.
        let frame =
            vcx::walk::frame_tree(c, s, q, depth, from, to).map_err(|e| at(e.to_string()))?;
        // The same streamed without a heap (fixed-capacity frames), with `hops`.
        let range = (q, depth, from, to);
        let streamed = match hops {
            0 => stream::<0>(c, s, range),
            1 => stream::<1>(c, s, range),
            2 => stream::<2>(c, s, range),
            3 => stream::<3>(c, s, range),
            4 => stream::<4>(c, s, range),
            5 => stream::<5>(c, s, range),
            6 => stream::<6>(c, s, range),
            8 => stream::<8>(c, s, range),
            10 => stream::<10>(c, s, range),
            _ => stream::<64>(c, s, range),
        }
        .map_err(|e| at(e.to_string()))?;
        let collected: Vec<_> = frame
            .iter()
            .map(|i| (i.start.to_bits(), i.branch.clone()))
            .collect();
        if streamed != collected {
            return Err(at(format!(
                "\n frame_tree_into {streamed:?}\n frame_tree {collected:?}"
            )));
        }
        let same_start = |a: &TreeInterval, b: &TreeInterval| match (a.exact_start, b.exact_start) {
            (Some(x), Some(y)) => x.cmp_exact(&y).is_eq(),
            (x, y) => x.is_none() && y.is_none(),
        };
        if frame.len() != got.len()
            || frame.iter().zip(&got).any(|(a, b)| {
                a.branch != b.branch
                    || a.start_vertex.is_some()
                    || a.start.to_bits() != b.start.to_bits()
                    || !same_start(a, b)
            })
        {
            return Err(at(format!(
                "\n frame_tree {frame:?}\n ray_tree_range {got:?}"
            )));
        }
        let fa = Angle::constant(from);
        if !got
            .first()
            .and_then(|i| i.exact_start)
            .is_some_and(|a| a.cmp_exact(&fa).is_eq())
        {
            return Err(at("the first interval does not start at `from`".into()));
        }
        let got: Vec<RangeRow> = got
            .into_iter()
            .map(|i| (i.branch, i.start_vertex))
            .collect();
        if got != want {
            return Err(at(format!(
                "\n core {got:?}\n restricted full tree {want:?}"
            )));
        }
        compared += 1;
    }
    Ok(compared)
}

/// The JSON scene loader on arbitrary text: an error, or a scene that the oracle accepts,
/// that survives writing and reading back unchanged, and (up to [`MAX_OBJECTS`] objects)
/// whose complex checks out.
pub fn check_scene_json(text: &str) -> Result<(), String> {
    let Ok(file) = vcx_demo::scene_file::parse(text) else {
        return Ok(());
    };
    let s = file.scene.as_ref();
    let written: Vec<(Material, Vec<Point>)> = s
        .objects()
        .iter()
        .map(|o| {
            let poly = s.polygon(o);
            let mut pts = vec![poly[0]; poly.len()];
            for (k, p) in poly.iter().enumerate() {
                if let Some(slot) = pts.get_mut(o.written_vertex_id(k)) {
                    *slot = *p;
                }
            }
            (o.material, pts)
        })
        .collect();
    let again = Scene::new(written.iter().map(|(m, p)| (*m, &p[..])));
    check_validation(&written, &again)?;
    let json = file.to_json();
    let back = vcx_demo::scene_file::parse(&json)
        .map_err(|e| format!("the written file does not load: {e}\n{json}"))?;
    let b = back.scene.as_ref();
    if b.vertices() != s.vertices() || b.objects() != s.objects() {
        return Err(format!(
            "the scene changes when written and read back\n{json}"
        ));
    }
    if s.len() <= MAX_OBJECTS {
        check_complex(&s, &[])?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// The randomized incremental construction.

/// One cylinder in a form independent of ids: floor, ceiling, bottom and top chains
/// (object, bound), left and right walls (the tangent vertices of the bitangent).
type CylinderShape = (
    Option<u32>,
    Option<u32>,
    Option<(u32, u8)>,
    Option<(u32, u8)>,
    Option<(usize, usize)>,
    Option<(usize, usize)>,
);

/// A cylinder with its left and right neighbours.
type CylinderDesc = (CylinderShape, Option<CylinderShape>, Option<CylinderShape>);

/// The canonical description of a complex (sorted cylinder descriptions), with object ids
/// mapped through `id`; vertex indices are global, so subsets of one scene compare.
pub fn describe(c: &Complex, id: impl Fn(ObjectId) -> u32) -> Vec<CylinderDesc> {
    use vcx::partition::{Cylinder, Wall};
    let wall = |w: Wall| match w {
        Wall::Zero => None,
        Wall::Vertex(v) => c.vertex(v).map(|v| (v.bitangent.first, v.bitangent.second)),
    };
    let chain = |ch: Option<vcx::line_space::Chain>| ch.map(|ch| (id(ch.object), ch.bound as u8));
    let one = |cy: &Cylinder| -> CylinderShape {
        (
            cy.floor.map(&id),
            cy.ceiling.map(&id),
            chain(cy.bottom),
            chain(cy.top),
            wall(cy.left),
            wall(cy.right),
        )
    };
    let nb = |n: Option<vcx::partition::CylinderId>| n.and_then(|n| c.cylinder(n)).map(one);
    let mut out: Vec<CylinderDesc> = c
        .cylinders()
        .iter()
        .map(|cy| (one(cy), nb(cy.left_neighbour), nb(cy.right_neighbour)))
        .collect();
    out.sort_unstable();
    out
}

/// Input of the `incremental` target.
#[derive(Clone, PartialEq, Eq, Arbitrary)]
pub struct IncrementalInput {
    /// The scene (repaired).
    pub scene: SceneSpec,
    /// The insertion order: a permutation drawn from this seed.
    pub order_seed: u64,
    /// Screens first (the paper's §7 option), the rest in the drawn order.
    pub screens_first: bool,
    /// A memory budget `(live cylinders, history nodes)` for the step-by-step insertions:
    /// an insertion that exceeds it must fail with `CapacityExceeded` and roll back, and
    /// succeed when retried without a budget.
    #[arbitrary(with = small_budget)]
    pub budget: Option<(u16, u16)>,
    /// Rays for point location through the history (at most 8).
    #[arbitrary(with = |u: &mut Unstructured| bounded_vec(u, 8))]
    pub rays: Vec<RaySpec>,
}

impl Debug for IncrementalInput {
    fn fmt(&self, f: &mut Formatter<'_>) -> FmtResult {
        f.debug_struct("IncrementalInput")
            .field("scene", &self.scene)
            .field("order_seed", &self.order_seed)
            .field("screens_first", &self.screens_first)
            .field("budget", &self.budget)
            .field("rays", &VecLit(&self.rays))
            .finish()
    }
}

/// No budget, or one small enough to be exceeded now and then.
fn small_budget(u: &mut Unstructured<'_>) -> arbitrary::Result<Option<(u16, u16)>> {
    Ok(if u.arbitrary()? {
        Some((u.int_in_range(0..=400)?, u.int_in_range(0..=2000)?))
    } else {
        None
    })
}

/// A permutation of `0..n` from a seed (Fisher–Yates with a 64-bit LCG).
fn permutation(n: usize, seed: u64) -> Vec<usize> {
    let mut out: Vec<usize> = (0..n).collect();
    let mut state = seed;
    for i in (1..n).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        out.swap(i, (state >> 33) as usize % (i + 1));
    }
    out
}

/// The randomized incremental construction: after every insertion (in the input's order)
/// the live partition equals the rotational sweep's partition of the objects inserted so
/// far (and its live cylinder count is the complex's); an insertion over the input's memory
/// budget fails with `CapacityExceeded`, leaves the partition as it was and succeeds when
/// retried without the budget; `History::build` with the seed gives the same partition;
/// point location through the history agrees with the complex's and with exact ray
/// shooting. Returns how many insertions were rolled back.
pub fn check_incremental(input: &IncrementalInput) -> Result<usize, String> {
    use vcx::partition::{Budget, BuildOptions, ComplexError, History};
    let r = input.scene.realize();
    let scene = r.scene()?;
    let s = scene.as_ref();
    let screens: Vec<ObjectId> = (0..s.len() as u32)
        .map(ObjectId)
        .filter(|&id| {
            input.screens_first && s.object(id).map(|o| o.material) == Some(Material::Screen)
        })
        .collect();
    let mut order = screens.clone();
    order.extend(
        permutation(s.len(), input.order_seed)
            .into_iter()
            .map(|i| ObjectId(i as u32))
            .filter(|id| !screens.contains(id)),
    );
    let budget = input.budget.map(|(cylinders, nodes)| Budget {
        cylinders: usize::from(cylinders),
        history_nodes: usize::from(nodes),
        bytes: usize::MAX,
    });
    let mut rollbacks = 0;
    let mut h = History::new();
    let mut before = describe(
        &h.complex(&s).map_err(|e| format!("empty complex: {e}"))?,
        |o| o.0,
    );
    for (i, &n) in order.iter().enumerate() {
        h.set_budget(budget);
        match h.insert(&s, n) {
            Ok(()) => {}
            Err(ComplexError::CapacityExceeded { .. }) if budget.is_some() => {
                // Rolled back: the partition before the insertion, and it goes through
                // without the budget.
                let back = h
                    .complex(&s)
                    .map_err(|e| format!("complex after a rolled back {n:?} (#{i}): {e}"))?;
                if describe(&back, |o| o.0) != before {
                    return Err(format!(
                        "inserting {n:?} (#{i} of {order:?}) over budget {budget:?} did not roll back"
                    ));
                }
                rollbacks += 1;
                h.set_budget(None);
                h.insert(&s, n).map_err(|e| {
                    format!(
                        "inserting {n:?} (#{i} of {order:?}) again after a rollback: {e} ({e:?})"
                    )
                })?;
            }
            Err(e) => return Err(format!("inserting {n:?} (#{i} of {order:?}): {e} ({e:?})")),
        }
        let got = h
            .complex(&s)
            .map_err(|e| format!("complex after {n:?} (#{i} of {order:?}): {e}"))?;
        if h.live_cylinders() != got.cylinders().len() {
            return Err(format!(
                "after {n:?} (#{i}): live_cylinders {} but the complex has {}",
                h.live_cylinders(),
                got.cylinders().len()
            ));
        }
        h.validate(&s)
            .map_err(|e| format!("history after {n:?} (#{i} of {order:?}): {e}"))?;
        let sub = SubScene::new(s, order[..=i].iter().copied());
        let sref = sub.as_ref();
        let want = build_by_sweep(&sref).map_err(|e| format!("build_by_sweep: {e}"))?;
        let g = describe(&got, |o| o.0);
        let w = describe(&want, |o| sub.original(o).map_or(u32::MAX, |o| o.0));
        before = g.clone();
        if g != w {
            let missing: Vec<_> = w.iter().filter(|d| !g.contains(d)).collect();
            let extra: Vec<_> = g.iter().filter(|d| !w.contains(d)).collect();
            return Err(format!(
                "after inserting {n:?} (#{i} of {order:?}) the partition is not the sweep's:\n missing {missing:?}\n extra {extra:?}"
            ));
        }
    }
    let c = build_by_sweep(&s).map_err(|e| format!("build_by_sweep: {e}"))?;
    let built = History::build(
        &s,
        &BuildOptions {
            seed: input.order_seed,
            first: screens,
            ..BuildOptions::default()
        },
    )
    .map_err(|e| format!("History::build: {e} ({e:?})"))?;
    let built = built
        .complex(&s)
        .map_err(|e| format!("History::build complex: {e}"))?;
    if describe(&built, |o| o.0) != describe(&c, |o| o.0) {
        return Err(format!(
            "History::build (seed {}) is not the sweep's partition",
            input.order_seed
        ));
    }
    for ray in &input.rays {
        let Some(q) = ray.from.point(&r, &s) else {
            continue;
        };
        let Some(d) = ray.dir.direction(q, &s) else {
            continue;
        };
        if !compare_locate(&s, &c, q, d).map_err(|e| format!("{ray:?}: {e}"))? {
            continue;
        }
        let Some(Location::Free { cylinder }) = c.locate(&s, q, d) else {
            unreachable!("compared as free")
        };
        let want = c.cylinder(cylinder).map(|c| (c.floor, c.ceiling));
        let got = h.locate(&s, q, d).map(|(_, c)| (c.floor, c.ceiling));
        if got != want {
            return Err(format!(
                "{ray:?}: q {q:?} d {d:?}: history locate (floor, ceiling) {got:?}, complex {want:?}"
            ));
        }
    }
    Ok(rollbacks)
}

// ---------------------------------------------------------------------------------------
// Coverage tables.

/// Where an interval of [`CoverageInput`] starts.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Arbitrary)]
pub enum StartSpec {
    /// Exactly on column edge `c` (modulo `width + 1`).
    Edge(u16),
    /// Next to column edge `c`: its integer vector plus a small offset.
    Near(u16, i8, i8),
    /// Any direction.
    Any(i16, i16),
}

/// A camera and interval starts for [`check_coverage`]: starts on, next to or away from
/// column edges, each exact or known in `f64` only (`true`: exact), with one of four
/// branches; fields of view `(m + 1)/2¹⁶ · 2⁻ᵉ · 179°` (`e < 48`), down to columns
/// narrower than the rounding of their edges.
#[derive(Clone, PartialEq, Eq, Debug, Arbitrary)]
pub struct CoverageInput {
    /// Heading, `h/2¹⁶` of a turn.
    pub heading: u16,
    /// `(m, e)` of the field of view.
    pub fov: (u16, u8),
    /// Width, `w mod 1024 + 1` columns.
    pub width: u16,
    /// The starts used: the first `count mod 9`.
    pub count: u8,
    /// Starts, whether exact, and branch ids.
    pub starts: [(StartSpec, bool, u8); 8],
}

/// [`CoverageTable::exact`] (runs of whole columns placed by image coordinate, one entry
/// per run) against the table of [`coverage`]'s pieces (every column edge computed), column
/// by column, for the camera and intervals of `input`. `Ok` for a camera `Camera::new`
/// rejects.
pub fn check_coverage(input: &CoverageInput) -> Result<(), String> {
    use vcx::render::{coverage, Branch, Camera, CoverageTable, FrameInterval, Interval};
    let eye = QueryPoint::from_raw(0, 0).ok_or("eye")?;
    let heading = f64::from(input.heading) / 65536.0 * core::f64::consts::TAU;
    let (m, e) = input.fov;
    let fov = (f64::from(m) + 1.0) / 65536.0 * 2f64.powi(-i32::from(e % 48)) * 179f64.to_radians();
    let width = usize::from(input.width % 1024) + 1;
    let Ok(camera) = Camera::new(eye, heading, fov, width) else {
        return Ok(());
    };
    let edge = |c: u16| camera.edge(usize::from(c) % (width + 1)).vector;
    let mut ivs = Vec::new();
    for &(spec, exact, branch) in input.starts.iter().take(usize::from(input.count % 9)) {
        let v = match spec {
            StartSpec::Edge(c) => edge(c),
            StartSpec::Near(c, dx, dy) => {
                let v = edge(c);
                (v.0 + i64::from(dx), v.1 + i64::from(dy))
            }
            StartSpec::Any(x, y) => (i64::from(x), i64::from(y)),
        };
        let Some(d) = Direction::new(v.0, v.1) else {
            continue;
        };
        let a = Angle::constant(d);
        let branch =
            Branch::from_slice(&[ObjectId(u32::from(branch % 4))]).map_err(|_| "branch")?;
        ivs.push(FrameInterval {
            start: a.radians(),
            exact_start: exact.then_some(a),
            branch,
        });
    }
    ivs.sort_by(|a, b| a.start.total_cmp(&b.start));
    let mut want = CoverageTable::new();
    let mut col = 0;
    coverage(&camera, &ivs, |p| {
        while col < p.column {
            want.end_column();
            col += 1;
        }
        let branch = ivs.get(p.interval).map_or(&[][..], |i| i.branch());
        want.push(branch, p.fraction);
    });
    while col < width {
        want.end_column();
        col += 1;
    }
    let table = CoverageTable::exact(&camera, &ivs);
    match (0..width).find(|&c| table.column(c) != want.column(c)) {
        None if table.columns() == width => Ok(()),
        None => Err(format!("{} columns, not {width}", table.columns())),
        Some(c) => Err(format!(
            "column {c}: table {:?}, pieces {:?}",
            table.column(c),
            want.column(c)
        )),
    }
}
