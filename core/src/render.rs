//! Rendering helpers: a view or a ray tree turned into screen columns, with **exact
//! per-column coverage** (DESIGN.md §6, the paper's Fig. 20).
//!
//! # Camera
//!
//! A perspective camera at `eye` looking along `heading` with a horizontal field of view
//! `fov < π` and `W` columns. Columns are equally spaced on the **image line**, the line at
//! distance 1 ahead of the eye: with `f` the unit heading and `r` the unit vector to its
//! right, the image coordinate of a direction `d` is `x = dot(d, r) / dot(d, f)` (the
//! tangent of the angle from the heading, clockwise positive), and column `c` (0 is the
//! leftmost) spans `x ∈ [x_c, x_{c+1}]`, `x_c = (2c/W − 1)·tan(fov/2)`. In angles, column
//! edge `c` lies at `heading − atan((2c/W − 1)·tan(fov/2))`. Each edge is the direction of
//! an **integer vector** (components ≤ 2⁵⁰, the rounding of `f + x_c·r`), so that comparing
//! it with an exact boundary is an exact predicate; the camera *is* these integer edges,
//! and `x_c` is recomputed from them for the fractions.
//!
//! # Coverage
//!
//! For each column, the fraction of its extent **on the image line (tan-space)** covered
//! by each interval. Which column a boundary falls in — or whether it lies exactly on a
//! column edge or outside the field of view — is decided exactly where the boundary is
//! exact (every boundary of a view, the primary boundaries of a ray tree: the sign of
//! `cross(edge, boundary)` in `i128`, products below 2⁵⁰·2⁵⁴); a deeper ray-tree boundary
//! is known in `f64` only ([`crate::walk::TreeInterval::start`]) and is placed by its
//! `f64` image coordinate. Only the fractions are then computed in `f64`, from the boundary's image
//! coordinate, clamped to the column decided exactly. A boundary exactly on a column edge
//! makes no zero-width piece.
//!
//! Everything here writes into caller buffers or calls back: nothing allocates except the
//! convenience `CoverageTable` (feature `alloc`). Without a heap, a frame's ray tree comes
//! from [`crate::walk::frame_tree_into`] into a caller's buffer of [`FrameInterval`]s.
//!
//! # Hits and the `f64` optics
//!
//! [`hit_along`] follows a branch along one ray in `f64` (output only: distances and
//! shading): a mirror reflects the eye across the hit edge's line, a refractive object
//! moves it by the tangent law at the entry and at the exit edge ([`transform_eye_f64`]),
//! exactly the optics of [`crate::walk`] without the rounding of the eyes. The ray casters
//! of the `vcx-baselines` crate use the same functions. [`Hits`] does the same for many
//! rays of one eye, remembering per level the edge hit and the optics derived from it, and
//! [`centre_hits`] gives a frame's centre intervals and hits in one pass.

#[cfg(feature = "alloc")]
use alloc::vec::Vec;
use core::cmp::Ordering;

use crate::geom::predicates::Direction;
use crate::geom::sos::Angle;
use crate::geom::QueryPoint;
use crate::scene::{Material, ObjectId, SceneRef};
#[cfg(feature = "alloc")]
use crate::walk::TreeInterval;
use crate::walk::{TreeSpan, ViewInterval};

/// Largest field of view, just under π (the image line needs `fov < π`).
pub const MAX_FOV: f64 = 179.0 * core::f64::consts::PI / 180.0;

/// Longest branch a [`Branch`] holds: depth 16 plus the primary object.
pub const MAX_BRANCH: usize = 17;

/// Objects along a ray, primary first, screens left out (fixed capacity, no heap).
pub type Branch = heapless::Vec<ObjectId, MAX_BRANCH>;

/// Components of the integer edge vectors are scaled to this magnitude.
const EDGE_SCALE: f64 = (1u64 << 50) as f64;

/// Why a camera could not be made.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum RenderError {
    /// Zero columns, or more than 2²⁴.
    Width,
    /// The field of view is not in `(0, MAX_FOV]`, or not finite; or the columns are so
    /// narrow that two edges round to the same integer direction.
    Fov,
    /// The heading is not finite.
    Heading,
}

impl core::fmt::Display for RenderError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RenderError::Width => write!(f, "the width must be 1 to 16777216 columns"),
            RenderError::Fov => write!(f, "the field of view must be above 0 and at most 179°"),
            RenderError::Heading => write!(f, "the heading must be a finite number"),
        }
    }
}

impl core::error::Error for RenderError {}

/// A column edge (or centre): the exact integer direction and its image coordinate.
#[derive(Clone, Copy, Debug)]
pub struct Edge {
    /// The integer direction vector (components ≤ 2⁵⁰).
    pub vector: (i64, i64),
    /// Image coordinate of `vector` (`f64`, output only).
    pub x: f64,
}

impl Edge {
    /// The exact angle of the edge.
    pub fn angle(&self) -> Angle {
        let d = Direction::new(self.vector.0, self.vector.1).unwrap_or(Direction { x: 1, y: 0 });
        Angle::constant(d)
    }

    /// The direction as an `f64` vector (not normalized).
    pub fn direction(&self) -> (f64, f64) {
        (self.vector.0 as f64, self.vector.1 as f64)
    }
}

/// 1.5·2⁵²: adding it to `|x| ≤ 2⁵¹` leaves an integer in `[2⁵², 2⁵³)`, where the `f64`
/// step is 1.
const MAGIC: f64 = 6_755_399_441_055_744.0;

/// `x` rounded to an integer (ties to even) for `|x| ≤ 2⁵¹`: adding 1.5·2⁵² leaves no
/// fraction bits, and in `[2⁵², 2⁵³)` the bits of `x + MAGIC` are those of `MAGIC` plus
/// the integer, so one integer subtraction reads it — a hardware addition instead of the
/// software `libm::round`, and no saturating float-to-integer conversion (a frame rounds
/// two per column edge and centre).
fn round_small_i64(x: f64) -> i64 {
    ((x + MAGIC).to_bits() as i64).wrapping_sub(MAGIC.to_bits() as i64)
}

/// A perspective camera with `width` columns (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    eye: QueryPoint,
    width: usize,
    heading: f64,
    tan_half: f64,
    forward: (f64, f64),
    right: (f64, f64),
    /// Whether the columns are wide enough that the edges are strictly in order, as
    /// directions and as image coordinates (see [`Camera::place`]).
    ordered: bool,
}

impl Camera {
    /// A camera at `eye` looking along `heading` (radians, counter-clockwise from +x) with
    /// the field of view `fov` (radians) and `width` columns.
    pub fn new(
        eye: QueryPoint,
        heading: f64,
        fov: f64,
        width: usize,
    ) -> Result<Camera, RenderError> {
        if width == 0 || width > 1 << 24 {
            return Err(RenderError::Width);
        }
        if !heading.is_finite() {
            return Err(RenderError::Heading);
        }
        if !(fov > 0.0 && fov <= MAX_FOV) {
            return Err(RenderError::Fov);
        }
        let (s, c) = (libm::sin(heading), libm::cos(heading));
        let tan_half = libm::tan(fov / 2.0);
        let cam = Camera {
            eye,
            width,
            heading,
            tan_half,
            forward: (c, s),
            right: (s, -c),
            ordered: column_angle(tan_half, width) > ORDER_MARGIN,
        };
        // Edges must be distinct integer directions, in order.
        let (l, r) = (cam.edge(0), cam.edge(width));
        if cross_i(l.vector, r.vector) >= 0 || l.x >= r.x {
            return Err(RenderError::Fov);
        }
        Ok(cam)
    }

    /// The eye.
    pub fn eye(&self) -> QueryPoint {
        self.eye
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// The heading in radians.
    pub fn heading(&self) -> f64 {
        self.heading
    }

    /// `tan(fov / 2)`: the image line spans `[−tan_half, tan_half]`.
    pub fn tan_half(&self) -> f64 {
        self.tan_half
    }

    /// Image coordinate of the direction `d` (tan-space; meaningful for `d` ahead).
    pub fn image_x(&self, d: (f64, f64)) -> f64 {
        let along = d.0 * self.forward.0 + d.1 * self.forward.1;
        let side = d.0 * self.right.0 + d.1 * self.right.1;
        side / along
    }

    /// The direction (not normalized) of the image coordinate `x`.
    pub fn direction_at(&self, x: f64) -> (f64, f64) {
        (
            self.forward.0 + x * self.right.0,
            self.forward.1 + x * self.right.1,
        )
    }

    /// The nominal image coordinate of column edge `c` (`0 ≤ c ≤ width`).
    pub fn nominal_x(&self, c: usize) -> f64 {
        (2.0 * c as f64 / self.width as f64 - 1.0) * self.tan_half
    }

    /// The integer vector of the image coordinate `x` (see the module documentation).
    fn vector_at(&self, x: f64) -> (i64, i64) {
        let d = self.direction_at(x);
        // A comparison, not `f64::max` or `libm::fmax` (NaN handling): the magnitudes are
        // never NaN, and equal ones are the same value.
        let (ax, ay) = (libm::fabs(d.0), libm::fabs(d.1));
        let m = if ax < ay { ay } else { ax };
        let k = EDGE_SCALE / m;
        (round_small_i64(d.0 * k), round_small_i64(d.1 * k))
    }

    fn rounded(&self, x: f64) -> Edge {
        let v = self.vector_at(x);
        Edge {
            vector: v,
            x: self.image_x((v.0 as f64, v.1 as f64)),
        }
    }

    /// The centre vectors of the columns from the left (each [`Camera::centre`]'s
    /// `vector`), computing each nominal edge coordinate once.
    fn centre_vectors(&self) -> impl Iterator<Item = (i64, i64)> + '_ {
        let mut right = self.nominal_x(0);
        (0..self.width).map(move |c| {
            let left = right;
            right = self.nominal_x(c + 1);
            self.vector_at((left + right) / 2.0)
        })
    }

    /// Column edge `c` (`0` is the left edge of the image, `width` the right edge).
    #[inline]
    pub fn edge(&self, c: usize) -> Edge {
        self.rounded(self.nominal_x(c.min(self.width)))
    }

    /// The field of view as exact directions counter-clockwise from the right edge to the
    /// left edge: the range for [`crate::walk::view_range`] and
    /// [`crate::walk::ray_tree_range`], whose intervals [`coverage`] and
    /// [`centre_intervals`] take like full ones.
    pub fn range(&self) -> (Direction, Direction) {
        let d =
            |e: Edge| Direction::new(e.vector.0, e.vector.1).unwrap_or(Direction { x: 1, y: 0 });
        (d(self.edge(self.width)), d(self.edge(0)))
    }

    /// The direction through the centre of column `c`, rounded to an integer vector.
    pub fn centre(&self, c: usize) -> Edge {
        self.rounded((self.nominal_x(c) + self.nominal_x(c + 1)) / 2.0)
    }

    /// Image coordinate of sample `k` of `s` in column `c`: the centre of stratum `k`
    /// (stratified sampling, `s = 1` is the column centre).
    pub fn sample_x(&self, c: usize, k: usize, s: usize) -> f64 {
        let (a, b) = (self.nominal_x(c), self.nominal_x(c + 1));
        a + (b - a) * (k as f64 + 0.5) / s.max(1) as f64
    }

    /// Where [`merge`]'s column-by-column scan stops for a boundary at or right of edge
    /// `first` (`at`, with `first < width`): the first column `c ≥ first` whose right edge
    /// the boundary is strictly left of, or the last column; with its edges. For a camera
    /// whose edges are in order (`ordered`): `c` starts at the column `guess` (from the
    /// boundary's image coordinate), then is confirmed exactly against its two edges,
    /// moving to a neighbour while it is not (the boundary's side of the edges changes
    /// once, so the moves go one way). Inlined: one call per boundary of a frame.
    #[inline]
    fn place(&self, bound: &Bound, guess: usize, first: usize, at: Edge) -> (usize, Edge, Edge) {
        let w = self.width;
        let mut c = guess.max(first).min(w.saturating_sub(1));
        let edge = |c: usize| if c == first { at } else { self.edge(c) };
        let (mut a, mut b) = (edge(c), self.edge(c + 1));
        for _ in 0..w {
            if c > first && bound.side(&a) == Ordering::Greater {
                c -= 1;
                (a, b) = (edge(c), a);
            } else if c + 1 < w && bound.side(&b) != Ordering::Greater {
                c += 1;
                (a, b) = (b, self.edge(c + 1));
            } else {
                break;
            }
        }
        (c, a, b)
    }

    /// The start of `iv` if it lies strictly inside the field of view whose outer edges
    /// are `left` and `right` (the camera's edges 0 and `width`): decided exactly for an
    /// exact start, by its `f64` image coordinate otherwise.
    fn inside<I: Interval>(&self, iv: &I, left: &Edge, right: &Edge) -> Option<Bound> {
        match iv.exact_start() {
            Some(s) => {
                // The vector is kept in `i64` (always `Some`): crosses with the edges are
                // single widening products.
                let v = s.vector64()?;
                // Inside the open arc (R, L) of width < π: R → v and v → L both turn left.
                (cross_i(right.vector, v) > 0 && cross_i(left.vector, v) < 0)
                    .then_some(Bound::Exact(v))
            }
            None => {
                let radians = iv.start_radians();
                // One argument reduction for both (`sincos` gives the bits of `sin` and
                // `cos`: the same kernels on the same reduced argument).
                let (sin, cos) = libm::sincos(radians);
                let d = (cos, sin);
                if d.0 * self.forward.0 + d.1 * self.forward.1 <= 0.0 {
                    return None;
                }
                let x = self.image_x(d);
                (x > left.x && x < right.x).then_some(Bound::Approx(x))
            }
        }
    }
}

/// `sin(fov) / width`, with `fov = 2·atan(tan_half)`: the smallest angle between two
/// nominal column edges, less `O(2⁻²⁰)` relative for the rounding of their coordinates
/// (the edge at `x` makes the angle `atan(x)` with the heading; `atan` has its smallest
/// slope `1 / (1 + tan_half²)` at the outer edges).
fn column_angle(tan_half: f64, width: usize) -> f64 {
    2.0 * tan_half / (1.0 + tan_half * tan_half) / width as f64
}

/// A camera whose [`column_angle`] exceeds this has its edges strictly in order. An edge
/// vector is within `2⁻⁴⁸` radians of its nominal direction (the `f64` direction
/// `f + x·r` is within `2⁻⁵⁰`, since `f ⊥ r` and `|f| = |r|` exactly; scaling and
/// rounding to integers of magnitude 2⁵⁰ add below `2⁻⁵⁰`), and its image coordinate within
/// `(1 + x²)·2⁻⁴⁷` of `x`: both orders hold once the columns are wider than `2⁻⁴⁶`
/// radians. `2⁻⁴⁰` leaves room for the rounding of [`column_angle`] itself; only
/// cameras of absurdly narrow columns (`sin(fov) < width·2⁻⁴⁰`) fall below it.
const ORDER_MARGIN: f64 = 1.0 / (1u64 << 40) as f64;

/// A boundary strictly inside the field of view: its exact direction, or its image
/// coordinate when it is known in `f64` only.
#[derive(Clone, Copy, Debug)]
enum Bound {
    Exact((i64, i64)),
    Approx(f64),
}

impl Bound {
    /// Where the boundary lies against the edge (or centre) `e`: `Greater` strictly left of
    /// it (counter-clockwise), `Equal` on it, `Less` right of it. Exact for an exact
    /// boundary (the sign of `cross(e, v)`).
    #[inline]
    fn side(&self, e: &Edge) -> Ordering {
        self.side_of(e.vector, || e.x)
    }

    /// [`Bound::side`] for the direction `e` of image coordinate `x()` (asked only for a
    /// boundary known in `f64`).
    #[inline]
    fn side_of(&self, e: (i64, i64), x: impl FnOnce() -> f64) -> Ordering {
        match self {
            // The sign of `cross(e, v)`, as a comparison of its two products.
            Bound::Exact(v) => {
                (i128::from(e.0) * i128::from(v.1)).cmp(&(i128::from(e.1) * i128::from(v.0)))
            }
            Bound::Approx(b) => x().partial_cmp(b).unwrap_or(Ordering::Less),
        }
    }

    /// The image coordinate (output).
    fn x(&self, camera: &Camera) -> f64 {
        match self {
            Bound::Exact(v) => camera.image_x((v.0 as f64, v.1 as f64)),
            Bound::Approx(x) => *x,
        }
    }
}

/// `cross(u, v)` for an edge vector (≤ 2⁵⁰) and an edge or boundary vector (`i64`):
/// below 2¹¹⁴, two widening products.
#[inline]
fn cross_i(u: (i64, i64), v: (i64, i64)) -> i128 {
    i128::from(u.0) * i128::from(v.1) - i128::from(u.1) * i128::from(v.0)
}

/// An interval of a sweep (a view or a ray tree): where it starts and what it sees.
pub trait Interval {
    /// The exact start direction, when the boundary is exact.
    fn exact_start(&self) -> Option<Angle>;
    /// The start direction in radians in `[0, 2π)` (output precision).
    fn start_radians(&self) -> f64;
    /// The objects along the ray, primary first (a view: the object seen, or nothing).
    fn branch(&self) -> &[ObjectId];
}

impl Interval for ViewInterval {
    fn exact_start(&self) -> Option<Angle> {
        Some(self.start)
    }
    fn start_radians(&self) -> f64 {
        self.start.radians()
    }
    fn branch(&self) -> &[ObjectId] {
        self.object.as_slice()
    }
}

#[cfg(feature = "alloc")]
impl Interval for TreeInterval {
    fn exact_start(&self) -> Option<Angle> {
        self.exact_start
    }
    fn start_radians(&self) -> f64 {
        self.start
    }
    fn branch(&self) -> &[ObjectId] {
        &self.branch
    }
}

/// A ray-tree interval with its branch in fixed capacity: what a device keeps of the
/// spans of [`crate::walk::frame_tree_into`] to render a frame without a heap.
#[derive(Clone, Debug)]
pub struct FrameInterval {
    /// As [`TreeSpan::start`].
    pub start: f64,
    /// As [`TreeSpan::exact_start`].
    pub exact_start: Option<Angle>,
    /// The branch (at most [`MAX_BRANCH`] objects).
    pub branch: Branch,
}

impl FrameInterval {
    /// The span kept, or `None` if its branch is longer than [`MAX_BRANCH`].
    pub fn new(span: &TreeSpan<'_>) -> Option<FrameInterval> {
        Some(FrameInterval {
            start: span.start,
            exact_start: span.exact_start,
            branch: Branch::from_slice(span.branch).ok()?,
        })
    }
}

impl Interval for FrameInterval {
    fn exact_start(&self) -> Option<Angle> {
        self.exact_start
    }
    fn start_radians(&self) -> f64 {
        self.start
    }
    fn branch(&self) -> &[ObjectId] {
        &self.branch
    }
}

/// A direction to place among interval starts: exact, with its angle in radians for the
/// starts known in `f64` only (computed once, not per comparison).
struct Probe {
    angle: Angle,
    radians: core::cell::OnceCell<f64>,
}

impl Probe {
    fn new(angle: Angle) -> Probe {
        Probe {
            angle,
            radians: core::cell::OnceCell::new(),
        }
    }

    /// Whether interval `i` starts at or before the probe (exactly when the start is
    /// exact, in `f64` otherwise).
    fn after_start<I: Interval>(&self, i: &I) -> bool {
        match i.exact_start() {
            Some(s) => s.cmp_exact(&self.angle) != Ordering::Greater,
            None => i.start_radians() <= *self.radians.get_or_init(|| self.angle.radians()),
        }
    }

    fn find<I: Interval>(&self, intervals: &[I]) -> usize {
        let p = intervals.partition_point(|s| self.after_start(s));
        if p == 0 {
            intervals.len().saturating_sub(1)
        } else {
            p - 1
        }
    }
}

/// Order of interval `i`'s start against the exact direction `a` (exactly when the start
/// is exact, in `f64` otherwise).
fn start_cmp<I: Interval>(i: &I, a: &Angle) -> Ordering {
    match i.exact_start() {
        Some(s) => s.cmp_exact(a),
        None => i.start_radians().total_cmp(&a.radians()),
    }
}

/// Index of the interval containing the direction `a` (exact, see [`Interval`]): the last
/// one whose start is not after `a`, or the last interval (which wraps through θ = 0).
/// A direction exactly on a boundary belongs to the interval starting there.
pub fn interval_at<I: Interval>(intervals: &[I], a: &Angle) -> usize {
    Probe::new(*a).find(intervals)
}

/// One piece of a column: the part from image coordinate `from` to `to` sees `interval`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// The column.
    pub column: usize,
    /// Index of the interval seen.
    pub interval: usize,
    /// Image coordinate where the piece starts (left).
    pub from: f64,
    /// Image coordinate where it ends (right).
    pub to: f64,
    /// Fraction of the column's extent on the image line, in `(0, 1]`.
    pub fraction: f64,
}

/// The exact coverage of the camera's columns by the intervals of a view or a ray tree
/// (sorted by start angle, the last wrapping through θ = 0, as [`crate::walk::view`] and
/// [`crate::walk::ray_tree`] return them). Calls `emit` for every piece of positive width,
/// column by column from the left, each column's pieces from left to right. Allocates
/// nothing; O(W + boundaries in view + log intervals): columns and boundaries are merged
/// left to right, each column edge computed once. An empty `intervals` emits nothing.
pub fn coverage<I: Interval>(camera: &Camera, intervals: &[I], emit: impl FnMut(Piece)) {
    merge(camera, intervals, &mut Pieces(emit));
}

/// What the merge of columns and boundaries ([`merge`]) reports to.
trait Cover {
    /// Whether whole columns are wanted as pieces (with their edges' image coordinates):
    /// then every column edge is computed; otherwise runs of whole columns come to
    /// [`Cover::whole`] and only the edges next to boundaries are computed.
    const PIECES: bool;
    /// A piece of positive width (in column order, each column's from the left).
    fn piece(&mut self, p: Piece);
    /// Columns `cols` lie wholly in `interval` (never when [`Cover::PIECES`]).
    fn whole(&mut self, cols: core::ops::Range<usize>, interval: usize);
}

/// [`coverage`]'s pieces, every column as pieces.
struct Pieces<F>(F);

impl<F: FnMut(Piece)> Cover for Pieces<F> {
    const PIECES: bool = true;
    fn piece(&mut self, p: Piece) {
        (self.0)(p);
    }
    fn whole(&mut self, _: core::ops::Range<usize>, _: usize) {}
}

/// Reports the part of column `col` (edges at image coordinates `a`, `b`) from `from` to
/// `to` seen in `interval`, if it has positive width. Inlined: two calls per boundary.
#[inline]
fn piece(
    out: &mut impl Cover,
    col: usize,
    interval: usize,
    (a, b): (f64, f64),
    from: f64,
    to: f64,
) {
    // The rest of a column from its left edge: the whole column, fraction exactly 1
    // (what the clamps and the division below give, without them).
    if to == f64::INFINITY && from.to_bits() == a.to_bits() {
        if b > a {
            out.piece(Piece {
                column: col,
                interval,
                from,
                to: b,
                fraction: 1.0,
            });
        }
        return;
    }
    let (from, to) = (clamp(from, a, b), clamp(to, a, b));
    if to > from {
        out.piece(Piece {
            column: col,
            interval,
            from,
            to,
            fraction: (to - from) / (b - a),
        });
    }
}

/// [`coverage`] into `out`: columns and boundaries merged left to right. Without
/// [`Cover::PIECES`], in a camera whose edges are in order, a boundary beyond the current
/// column is placed by [`Camera::place`] and the whole columns before it are one run.
fn merge<I: Interval, O: Cover>(camera: &Camera, intervals: &[I], out: &mut O) {
    let n = intervals.len();
    let w = camera.width;
    if n == 0 {
        return;
    }
    let jump = !O::PIECES && camera.ordered;
    // Columns per unit of image coordinate, for the guesses of `Camera::place`.
    let per_x = w as f64 / (2.0 * camera.tan_half);
    let left = camera.edge(0);
    let la = left.angle();
    // The interval just clockwise of the left edge.
    let mut cur = interval_at(intervals, &la);
    if n > 1
        && intervals
            .get(cur)
            .is_some_and(|i| start_cmp(i, &la) == Ordering::Equal)
    {
        cur = before(cur, n);
    }
    let right = camera.edge(w);
    // Column `col` spans the edges `a` to `b`, each computed once per frame; its part left
    // of `x` is done.
    let mut col = 0;
    let (mut a, mut b) = (left, camera.edge(1));
    let mut x = left.x;
    // Boundaries clockwise from the left edge: the start of the current interval, then of
    // the one before, … until one lies outside the field of view. Boundaries and columns
    // are merged left to right: O(W + boundaries in view).
    if n > 1 {
        let inside = |i: usize| {
            intervals
                .get(i)
                .and_then(|iv| camera.inside(iv, &left, &right))
        };
        let mut upcoming = inside(cur);
        for _ in 0..n {
            let Some(bound) = upcoming else { break };
            // The next boundary, found before this one is placed (it does not depend on
            // the placement): its `sincos` overlaps the work below.
            let clockwise = before(cur, n);
            upcoming = inside(clockwise);
            // Columns whose right edge is at or left of the boundary end before it (a
            // boundary exactly on an inner edge makes no piece).
            if jump {
                if col + 1 < w && bound.side(&b) != Ordering::Greater {
                    piece(out, col, cur, (a.x, b.x), x, f64::INFINITY);
                    let next;
                    // The column of `bx`: its floor (rounding `v − 0.5`; an integer `v`
                    // may go one down), clamped. A guess only, confirmed exactly by
                    // `place`: any value is safe (NaN gives some integer), and the
                    // rounding is cheaper than the saturating `as usize`.
                    let v = (bound.x(camera) + camera.tan_half) * per_x;
                    let guess = round_small_i64(v - 0.5).clamp(0, w as i64) as usize;
                    (next, a, b) = camera.place(&bound, guess, col + 1, b);
                    if next > col + 1 {
                        out.whole(col + 1..next, cur);
                    }
                    col = next;
                    x = a.x;
                }
            } else {
                while col + 1 < w && bound.side(&b) != Ordering::Greater {
                    piece(out, col, cur, (a.x, b.x), x, f64::INFINITY);
                    col += 1;
                    a = b;
                    b = camera.edge(col + 1);
                    x = a.x;
                }
            }
            // A boundary at or left of the column's left edge is already passed (an `f64`
            // boundary out of order next to an exact one, or one exactly on the edge).
            if bound.side(&a) == Ordering::Less {
                let bx = bound.x(camera).max(x);
                piece(out, col, cur, (a.x, b.x), x, bx);
                x = bx;
            }
            cur = clockwise;
        }
    }
    if jump {
        piece(out, col, cur, (a.x, b.x), x, f64::INFINITY);
        if col + 1 < w {
            out.whole(col + 1..w, cur);
        }
        return;
    }
    while col < w {
        piece(out, col, cur, (a.x, b.x), x, f64::INFINITY);
        col += 1;
        a = b;
        b = camera.edge(col + 1);
        x = a.x;
    }
}

/// The interval clockwise of interval `i < n` (the one before it, wrapping): a compare
/// rather than `(i + n − 1) % n`, whose division the merge would pay per boundary.
#[inline]
fn before(i: usize, n: usize) -> usize {
    i.checked_sub(1).unwrap_or(n.saturating_sub(1))
}

/// `v.clamp(a, b)` for `a ≤ b` (the column's edges, in order) without `f64::clamp`'s
/// check of the bounds: the same comparisons, in the same order.
#[inline]
fn clamp(v: f64, a: f64, b: f64) -> f64 {
    if v < a {
        a
    } else if v > b {
        b
    } else {
        v
    }
}

/// Rotates intervals listed counter-clockwise from a range's start (what
/// [`crate::walk::view_range`] and [`crate::walk::ray_tree_range`] return) into start-angle
/// order, the order [`coverage`] and [`centre_intervals`] take: the run wraps through θ = 0
/// at most once, where the start angle drops by more than π (deep starts known in `f64`
/// only may drop by rounding next to exact ones).
pub fn angle_order<I: Interval>(intervals: &mut [I]) {
    let wrap = intervals
        .windows(2)
        .position(|w| match w {
            [a, b] => b.start_radians() < a.start_radians() - core::f64::consts::PI,
            _ => false,
        })
        .map_or(0, |k| k + 1);
    intervals.rotate_left(wrap);
}

/// The interval seen through the centre of each column (exactly, see [`interval_at`]),
/// written into `out` (its first `min(out.len(), width)` columns).
///
/// Columns run clockwise: the first centre is placed by bisection, then centres and the
/// boundaries in view are merged, one comparison per column and per boundary passed
/// (exact for an exact start, by image coordinate for a start known in `f64` only, as
/// [`coverage`] places it). O(W + log intervals) for a frame.
pub fn centre_intervals<I: Interval>(camera: &Camera, intervals: &[I], out: &mut [usize]) {
    if intervals.is_empty() {
        out.iter_mut().for_each(|s| *s = 0);
        return;
    }
    let mut sweep = None;
    for (slot, centre) in out.iter_mut().zip(camera.centre_vectors()) {
        *slot = sweep
            .get_or_insert_with(|| Centres::new(camera, intervals, centre))
            .next(centre);
    }
}

/// The merge of column centres (left to right) with the interval starts (clockwise).
struct Centres<'a, I> {
    camera: &'a Camera,
    intervals: &'a [I],
    left: Edge,
    right: Edge,
    /// The interval of the last centre, and its start if it lies inside the field of
    /// view (a start outside is right of every centre still to come).
    cur: usize,
    at: Option<Bound>,
    /// Starts passed: after all `n`, the sweep went round the circle (every start in view).
    passed: usize,
}

impl<'a, I: Interval> Centres<'a, I> {
    /// The sweep at the first centre (its interval found by bisection, exactly).
    fn new(camera: &'a Camera, intervals: &'a [I], first: (i64, i64)) -> Self {
        let (left, right) = (camera.edge(0), camera.edge(camera.width));
        let first = Direction::new(first.0, first.1).unwrap_or(Direction { x: 1, y: 0 });
        let cur = interval_at(intervals, &Angle::constant(first));
        let at = intervals
            .get(cur)
            .and_then(|iv| camera.inside(iv, &left, &right));
        Centres {
            camera,
            intervals,
            left,
            right,
            cur,
            at,
            passed: 0,
        }
    }

    /// The interval through `centre`, right of the previous centre: past every start
    /// strictly left of it (a start exactly on it begins its interval).
    fn next(&mut self, centre: (i64, i64)) -> usize {
        let n = self.intervals.len();
        let camera = self.camera;
        let x = || camera.image_x((centre.0 as f64, centre.1 as f64));
        while self.passed < n {
            match self.at {
                Some(b) if b.side_of(centre, x) == Ordering::Greater => {}
                _ => break,
            }
            self.cur = before(self.cur, n);
            self.passed += 1;
            self.at = self
                .intervals
                .get(self.cur)
                .and_then(|iv| self.camera.inside(iv, &self.left, &self.right));
        }
        self.cur
    }
}

/// Per-column coverage by **branch** (pieces of equal branch merged), the common output
/// of the complex and of the ray casters of `vcx-baselines`.
#[cfg(feature = "alloc")]
#[derive(Clone, Debug, Default)]
pub struct CoverageTable {
    /// Where each ended column's entries begin; they end where the next column's begin
    /// (the open column's after the last), or after one entry for a column marked
    /// [`SHARED`]: a run of whole columns shares one entry, written once. One word per
    /// column, half the memory a frame writes with `(start, end)` pairs.
    starts: Vec<usize>,
    /// Branches and covered fractions, grouped by column.
    entries: Vec<(Branch, f64)>,
    /// Where the current (open) column's entries begin.
    open: usize,
}

/// The mark of a [`CoverageTable`] column whose one entry is shared by a run of columns:
/// the top bit of its start, never set in an index (a `Vec` holds at most `isize::MAX`
/// bytes, so fewer entries than this bit's value).
#[cfg(feature = "alloc")]
const SHARED: usize = 1 << (usize::BITS - 1);

/// Tables are equal when their columns are: where entries are shared does not matter.
#[cfg(feature = "alloc")]
impl PartialEq for CoverageTable {
    fn eq(&self, other: &CoverageTable) -> bool {
        self.columns() == other.columns()
            && (0..self.columns()).all(|c| self.column(c) == other.column(c))
    }
}

#[cfg(feature = "alloc")]
impl CoverageTable {
    /// An empty table; fill it with [`CoverageTable::push`] and [`CoverageTable::end_column`].
    pub fn new() -> CoverageTable {
        CoverageTable::default()
    }

    /// Clears the table, keeping its buffers.
    pub fn clear(&mut self) {
        self.starts.clear();
        self.entries.clear();
        self.open = 0;
    }

    /// Adds `fraction` of the current column to `branch` (inlined: the casters add every
    /// sample, and the exact table every piece, through it).
    #[inline]
    pub fn push(&mut self, branch: &[ObjectId], fraction: f64) {
        if let Some(e) = self
            .entries
            .get_mut(self.open..)
            .and_then(|col| col.iter_mut().find(|e| e.0.as_slice() == branch))
        {
            e.1 += fraction;
            return;
        }
        push_entry(&mut self.entries, branch, fraction);
    }

    /// Ends the current column (inlined: the casters end every column through it).
    #[inline]
    pub fn end_column(&mut self) {
        self.starts.push(self.open);
        self.open = self.entries.len();
    }

    /// The exact coverage of the camera's columns by the intervals.
    pub fn exact<I: Interval>(camera: &Camera, intervals: &[I]) -> CoverageTable {
        let mut t = CoverageTable::new();
        t.exact_into(camera, intervals);
        t
    }

    /// [`CoverageTable::exact`] into `self` (cleared first), reusing its buffers. Runs of
    /// whole columns take no column edges ([`merge`]) and one entry each.
    pub fn exact_into<I: Interval>(&mut self, camera: &Camera, intervals: &[I]) {
        self.clear();
        self.starts.reserve(camera.width);
        let mut fill = Fill {
            table: self,
            intervals,
            col: 0,
        };
        merge(camera, intervals, &mut fill);
        fill.end_columns(camera.width);
    }

    /// Number of columns.
    pub fn columns(&self) -> usize {
        self.starts.len()
    }

    /// Column `c`'s branches and fractions.
    pub fn column(&self, c: usize) -> &[(Branch, f64)] {
        let Some(&start) = self.starts.get(c) else {
            return &[];
        };
        let a = start & !SHARED;
        let b = if start & SHARED != 0 {
            a + 1
        } else {
            self.starts.get(c + 1).map_or(self.open, |&s| s & !SHARED)
        };
        self.entries.get(a..b).unwrap_or(&[])
    }

    /// The branch covering most of column `c` (the first of equal ones).
    pub fn dominant(&self, c: usize) -> Option<&Branch> {
        let mut best: Option<&(Branch, f64)> = None;
        for e in self.column(c) {
            if best.is_none_or(|b| e.1 > b.1) {
                best = Some(e);
            }
        }
        best.map(|e| &e.0)
    }

    /// Whether column `c` contains more than one branch.
    pub fn mixed(&self, c: usize) -> bool {
        self.column(c).len() > 1
    }

    /// Error of `self` (an estimate) against `exact`, over the columns of both:
    /// `(mean absolute coverage error per column, share of columns whose dominant branch
    /// differs)`. A column's error is half the L1 distance of the two coverage vectors:
    /// the fraction of the column attributed to a wrong branch, in `[0, 1]`.
    pub fn error_against(&self, exact: &CoverageTable) -> (f64, f64) {
        let n = self.columns().min(exact.columns());
        if n == 0 {
            return (0.0, 0.0);
        }
        let (mut sum, mut wrong) = (0.0, 0usize);
        for c in 0..n {
            let (a, b) = (self.column(c), exact.column(c));
            let mut l1 = 0.0;
            for (br, f) in a {
                let g = b.iter().find(|e| e.0 == *br).map_or(0.0, |e| e.1);
                l1 += libm::fabs(f - g);
            }
            for (br, g) in b {
                if !a.iter().any(|e| e.0 == *br) {
                    l1 += g;
                }
            }
            sum += l1 / 2.0;
            if self.dominant(c) != exact.dominant(c) {
                wrong += 1;
            }
        }
        (sum / n as f64, wrong as f64 / n as f64)
    }
}

/// Appends the entry of `branch` (as kept in a table: its first [`MAX_BRANCH`] objects)
/// with `fraction`, built in place: the objects are copied once, into the buffer.
#[cfg(feature = "alloc")]
#[inline]
fn push_entry(entries: &mut Vec<(Branch, f64)>, branch: &[ObjectId], fraction: f64) {
    entries.push((Branch::new(), fraction));
    if let Some(e) = entries.last_mut() {
        let kept = branch.get(..MAX_BRANCH).unwrap_or(branch);
        // Never full: at most `MAX_BRANCH` objects.
        let _ = e.0.extend_from_slice(kept);
    }
}

/// [`CoverageTable::exact_into`]'s filling of the table from [`merge`].
#[cfg(feature = "alloc")]
struct Fill<'a, I> {
    table: &'a mut CoverageTable,
    intervals: &'a [I],
    /// The column being filled.
    col: usize,
}

#[cfg(feature = "alloc")]
impl<I: Interval> Fill<'_, I> {
    /// Ends the columns before `col`: the open one, then empty ones (as many
    /// [`CoverageTable::end_column`]s, in one run of starts).
    fn end_columns(&mut self, col: usize) {
        if self.col < col {
            let t = &mut *self.table;
            let end = t.entries.len();
            t.starts.push(t.open);
            t.starts.resize(t.starts.len() + (col - self.col - 1), end);
            t.open = end;
            self.col = col;
        }
    }
}

#[cfg(feature = "alloc")]
impl<I: Interval> Cover for Fill<'_, I> {
    const PIECES: bool = false;

    // Inlined (into `piece`, two calls per boundary): a call's saving and restoring of
    // registers costs about as much as the few objects it copies.
    #[inline(always)]
    fn piece(&mut self, p: Piece) {
        self.end_columns(p.column);
        let branch = self
            .intervals
            .get(p.interval)
            .map_or(&[][..], |i| i.branch());
        self.table.push(branch, p.fraction);
    }

    fn whole(&mut self, cols: core::ops::Range<usize>, interval: usize) {
        self.end_columns(cols.start);
        let branch = self.intervals.get(interval).map_or(&[][..], |i| i.branch());
        let t = &mut *self.table;
        // One entry for the whole run, each column's only one.
        let first = t.entries.len();
        push_entry(&mut t.entries, branch, 1.0);
        t.starts
            .extend(core::iter::repeat_n(first | SHARED, cols.len()));
        t.open = first + 1;
        self.col = cols.end;
    }
}

/// The eye `F + k·(E − F)` for the foot `F` of `e` on the line through `p` with unit
/// normal `n` (`f64`): `k = −1` reflects, `k = η` enters a refractive object, `1/η` leaves
/// it (the tangent law, as [`crate::walk::optics::transform_eye`] without rounding).
pub fn transform_eye_f64(e: (f64, f64), p: (f64, f64), n: (f64, f64), k: f64) -> (f64, f64) {
    let h = (e.0 - p.0) * n.0 + (e.1 - p.1) * n.1;
    let f = (e.0 - h * n.0, e.1 - h * n.1);
    (f.0 + k * h * n.0, f.1 + k * h * n.1)
}

/// What a ray finally hits along a branch, for drawing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance from the eye to the first object of the branch.
    pub first: f64,
    /// Length of the whole polyline to the last object (unfolded distance).
    pub length: f64,
    /// `|cos|` of the angle between the last stage's ray and the normal of the edge it
    /// hits, in `[0, 1]` (for shading).
    pub facing: f64,
}

/// The ray from `origin` along `dir` against the convex polygon `poly` (counter-clockwise):
/// the parameters of entry and exit and the entry and exit edges, or `None` if it misses.
pub fn clip_polygon(
    poly: &[crate::Point],
    origin: (f64, f64),
    dir: (f64, f64),
) -> Option<(f64, usize, f64, usize)> {
    let (mut t_in, mut e_in, mut t_out, mut e_out) = (f64::NEG_INFINITY, 0, f64::INFINITY, 0);
    // Edge `k` runs from vertex `k` to the next (the last back to the first): each vertex
    // is converted once, carried from one edge to the next.
    let n = poly.len();
    let mut b = poly.first().map_or((0.0, 0.0), |p| p.to_f64());
    for k in 0..n {
        let a = b;
        b = poly.get(if k + 1 < n { k + 1 } else { 0 })?.to_f64();
        // Outward normal of a counter-clockwise edge: (dy, −dx).
        let nrm = (b.1 - a.1, a.0 - b.0);
        let num = nrm.0 * (a.0 - origin.0) + nrm.1 * (a.1 - origin.1);
        let den = nrm.0 * dir.0 + nrm.1 * dir.1;
        if den == 0.0 {
            if num < 0.0 {
                return None;
            }
            continue;
        }
        let t = num / den;
        if den < 0.0 {
            if t > t_in {
                t_in = t;
                e_in = k;
            }
        } else if t < t_out {
            t_out = t;
            e_out = k;
        }
    }
    (t_in <= t_out).then_some((t_in, e_in, t_out, e_out))
}

fn unit_normal(poly: &[crate::Point], k: usize) -> Option<((f64, f64), (f64, f64))> {
    let n = poly.len();
    let (a, b) = (poly.get(k)?.to_f64(), poly.get((k + 1) % n)?.to_f64());
    let (nx, ny) = (b.1 - a.1, a.0 - b.0);
    let l = norm(nx, ny);
    (l > 0.0).then_some((a, (nx / l, ny / l)))
}

/// Follows `branch` along the ray from `eye` in direction `dir` (`f64`, output only): the
/// distance to the first object, the unfolded length to the last and how squarely the last
/// stage meets it; `None` for an empty branch or a ray that misses the next object of the
/// branch (rounding at a grazing boundary), or a branch that continues past a mirror or
/// refractive object when the cargo feature `mirrors` or `refraction` is off.
pub fn hit_along(
    scene: &SceneRef<'_>,
    eye: QueryPoint,
    dir: (f64, f64),
    branch: &[ObjectId],
) -> Option<Hit> {
    let l = norm(dir.0, dir.1);
    if branch.is_empty() || l <= 0.0 {
        return None;
    }
    let mut e = eye.to_f64();
    let mut o = e;
    let mut d = (dir.0 / l, dir.1 / l);
    let (mut first, mut length, mut facing) = (0.0, 0.0, 1.0);
    for (level, id) in branch.iter().enumerate() {
        let obj = scene.object(*id)?;
        let poly = scene.polygon(obj);
        let (t, edge, _, _) = clip_polygon(poly, o, d)?;
        let t = t.max(0.0);
        let p = (o.0 + t * d.0, o.1 + t * d.1);
        length += t;
        if level == 0 {
            first = t;
        }
        let (_, nrm) = unit_normal(poly, edge)?;
        facing = libm::fabs(d.0 * nrm.0 + d.1 * nrm.1);
        if level + 1 == branch.len() {
            break;
        }
        // A ray type compiled out (cargo features `mirrors`, `refraction`) takes no branch
        // past its objects (the ray tree is `WalkError::RayTypeDisabled`); `cfg!` keeps the
        // arms type-checked, and the optimizer drops them.
        let (ne, np) = match obj.material {
            Material::Mirror if cfg!(feature = "mirrors") => {
                (transform_eye_f64(e, p, nrm, -1.0), p)
            }
            Material::Refractive { eta } if cfg!(feature = "refraction") => {
                let eta = eta.to_f64();
                let e1 = transform_eye_f64(e, p, nrm, eta);
                let d1 = unit((p.0 - e1.0, p.1 - e1.1))?;
                let (_, _, t2, exit) = clip_polygon(poly, p, d1)?;
                let t2 = t2.max(0.0);
                let p2 = (p.0 + t2 * d1.0, p.1 + t2 * d1.1);
                length += t2;
                let (_, n2) = unit_normal(poly, exit)?;
                (transform_eye_f64(e1, p2, n2, 1.0 / eta), p2)
            }
            // Opaque objects end a branch; screens are never in one.
            _ => return None,
        };
        d = unit((np.0 - ne.0, np.1 - ne.1))?;
        e = ne;
        o = np;
    }
    Some(Hit {
        first,
        length,
        facing,
    })
}

/// Follows the branches along many rays of one eye, as [`hit_along`] does along each, but
/// remembering per level of the last branch the hit edge and the optics derived from it
/// (unit normal, the next virtual eye): neighbouring columns mostly see the same branch
/// through the same edges, and then a level costs a test that the ray still crosses the
/// remembered edge and the parameter where it does, instead of clipping the polygon. A
/// fixed-size value (no heap); reuse one for the columns of a frame.
///
/// Through mirrors only, the remembered levels are linear forms of the primary direction
/// (the unfolded ray is straight), and a ray that still crosses every remembered edge
/// costs a few dot products per level. [`centre_hits`] goes further along the columns of
/// one interval: they turn clockwise, so of these tests only the one that fails first
/// can fail, and a column costs that test and the two distances.
///
/// The optics are taken at the hit edge's first vertex rather than at the hit point, so
/// that they do not depend on which ray computed them: the result is [`hit_along`]'s up to
/// `f64` rounding whichever rays came before (and up to which of two edges a ray exactly
/// through a vertex meets).
#[derive(Clone, Debug)]
pub struct Hits {
    /// The eye of the remembered levels.
    eye: (f64, f64),
    /// Levels `0..len` are remembered for `eye`.
    len: usize,
    levels: [Level; MAX_BRANCH],
    /// Every call is known to take the same scene (a `Hits` local to [`centre_hits`]): the
    /// remembered levels need not be checked against the scene's objects again.
    same_scene: bool,
}

/// Edge `k` of a polygon (counter-clockwise), its endpoints and unit outward normal.
#[derive(Clone, Copy, Debug)]
struct Side {
    k: usize,
    a: (f64, f64),
    b: (f64, f64),
    n: (f64, f64),
}

impl Side {
    const NONE: Side = Side {
        k: usize::MAX,
        a: (f64::NAN, f64::NAN),
        b: (f64::NAN, f64::NAN),
        n: (f64::NAN, f64::NAN),
    };

    fn of(poly: &[crate::Point], k: usize) -> Option<Side> {
        let (a, b) = (
            poly.get(k)?.to_f64(),
            poly.get((k + 1) % poly.len())?.to_f64(),
        );
        let (nx, ny) = (b.1 - a.1, a.0 - b.0);
        let l = norm(nx, ny);
        (l > 0.0).then_some(Side {
            k,
            a,
            b,
            n: (nx / l, ny / l),
        })
    }

    /// The parameter where the ray `o + t·d` crosses this side of `poly`, if the side is
    /// still `poly`'s edge `k` and the ray enters the polygon through it (`leaving`: leaves
    /// it): then it is what [`clip_polygon`] returns for the side, the same arithmetic.
    /// `same_scene`: `poly` is known to be the polygon the side was taken from.
    fn meet(
        &self,
        poly: &[crate::Point],
        o: (f64, f64),
        d: (f64, f64),
        leaving: bool,
        same_scene: bool,
    ) -> Option<f64> {
        let (a, b) = if same_scene {
            (self.a, self.b)
        } else {
            let a = poly.get(self.k)?.to_f64();
            let b = poly.get((self.k + 1) % poly.len())?.to_f64();
            if a != self.a || b != self.b {
                return None;
            }
            (a, b)
        };
        let nrm = (b.1 - a.1, a.0 - b.0);
        let num = nrm.0 * (a.0 - o.0) + nrm.1 * (a.1 - o.1);
        let den = nrm.0 * d.0 + nrm.1 * d.1;
        // Which side of the ray's line each endpoint lies on.
        let sa = d.0 * (a.1 - o.1) - d.1 * (a.0 - o.0);
        let sb = d.0 * (b.1 - o.1) - d.1 * (b.0 - o.0);
        let crosses = if leaving {
            den > 0.0 && sa <= 0.0 && sb >= 0.0
        } else {
            den < 0.0 && sa >= 0.0 && sb <= 0.0
        };
        crosses.then(|| num / den)
    }
}

/// One remembered level of a [`Hits`]: valid for the eye of this level (determined by the
/// levels before).
#[derive(Clone, Copy, Debug)]
struct Level {
    id: ObjectId,
    material: Material,
    /// The edge the ray enters through.
    entry: Side,
    /// Whether `inner`, `exit` and `next` are computed (not for the last level of a branch).
    optics: bool,
    /// A refractive object: the eye inside, and the edge the ray leaves through.
    inner: (f64, f64),
    exit: Side,
    /// The eye of the next level.
    next: (f64, f64),
    /// When every level before is a mirror: the level in terms of the primary direction.
    lin: Option<Unfolded>,
    /// With `optics`, when this level and every level before are mirrors: the product of
    /// their reflections (the next level's `M` in [`Unfolded`]).
    after: Option<[[f64; 2]; 2]>,
}

/// A level reached through mirrors only, as linear forms of the unit primary direction
/// `u`: the level's ray is the line through its eye `e` along `M·u` (`M` the product of
/// the reflections before), so which side of that line the entry edge's endpoints lie on,
/// the edge normal's component along the ray, and the distance from `e` to the edge are
/// dot products with `u` (the unfolded ray is straight: that distance is the length of the
/// whole path).
#[derive(Clone, Copy, Debug)]
struct Unfolded {
    /// The entry edge's vertices as stored (the scene must still have them).
    pa: crate::Point,
    pb: crate::Point,
    /// `cross(M·u, a − e) = qa·u` and `cross(M·u, b − e) = qb·u`.
    qa: (f64, f64),
    qb: (f64, f64),
    /// `nrm·(M·u) = wd·u` for the edge's outward normal `nrm` (not normalized), and
    /// `num = nrm·(a − e)`: the distance from `e` is `num / (wd·u)`.
    wd: (f64, f64),
    num: f64,
    /// `n·(M·u) = wn·u` for the unit normal `n` (the facing).
    wn: (f64, f64),
}

/// The first and the last level of a branch unfolded through mirrors (`last` `None`: the
/// same level), read by [`Hits::unfolded_hit`].
#[derive(Clone, Copy, Debug)]
struct Ends {
    first: Unfolded,
    last: Option<Unfolded>,
}

impl Ends {
    /// The hit along the unit ray `u` (crossing every entry edge): the distances to the
    /// first and the last entry edge, and how squarely the ray meets the last.
    #[inline]
    fn hit(&self, u: (f64, f64)) -> Option<Hit> {
        let distance = |lin: &Unfolded| {
            let den = dot(lin.wd, u);
            (den < 0.0).then(|| (lin.num / den).max(0.0))
        };
        let first = distance(&self.first)?;
        let (length, lin) = match &self.last {
            None => (first, &self.first),
            Some(lin) => (distance(lin)?, lin),
        };
        Some(Hit {
            first,
            length,
            facing: libm::fabs(dot(lin.wn, u)),
        })
    }
}

/// `Mᵀ·r` for the 2×2 matrix `m` (rows).
fn mt(m: &[[f64; 2]; 2], r: (f64, f64)) -> (f64, f64) {
    (m[0][0] * r.0 + m[1][0] * r.1, m[0][1] * r.0 + m[1][1] * r.1)
}

fn dot(a: (f64, f64), b: (f64, f64)) -> f64 {
    a.0 * b.0 + a.1 * b.1
}

impl Unfolded {
    /// Level data for the entry edge `side` of `poly`, the eye `e` and the product `m` of
    /// the reflections before.
    fn new(poly: &[crate::Point], side: &Side, e: (f64, f64), m: &[[f64; 2]; 2]) -> Option<Self> {
        let pa = *poly.get(side.k)?;
        let pb = *poly.get((side.k + 1) % poly.len())?;
        let (a, b) = (side.a, side.b);
        let nrm = (b.1 - a.1, a.0 - b.0);
        let (ra, rb) = ((a.0 - e.0, a.1 - e.1), (b.0 - e.0, b.1 - e.1));
        Some(Unfolded {
            pa,
            pb,
            qa: mt(m, (ra.1, -ra.0)),
            qb: mt(m, (rb.1, -rb.0)),
            wd: mt(m, nrm),
            num: dot(nrm, ra),
            wn: mt(m, side.n),
        })
    }
}

/// `R·m` for the reflection `R = I − 2·n·nᵀ` across a line of unit normal `n`.
fn reflect(m: &[[f64; 2]; 2], n: (f64, f64)) -> [[f64; 2]; 2] {
    let (a, b, c) = (
        1.0 - 2.0 * n.0 * n.0,
        -2.0 * n.0 * n.1,
        1.0 - 2.0 * n.1 * n.1,
    );
    [
        [a * m[0][0] + b * m[1][0], a * m[0][1] + b * m[1][1]],
        [b * m[0][0] + c * m[1][0], b * m[0][1] + c * m[1][1]],
    ]
}

impl Level {
    const EMPTY: Level = Level {
        id: ObjectId(u32::MAX),
        material: Material::Opaque,
        entry: Side::NONE,
        optics: false,
        inner: (f64::NAN, f64::NAN),
        exit: Side::NONE,
        next: (f64::NAN, f64::NAN),
        lin: None,
        after: None,
    };
}

impl Default for Hits {
    fn default() -> Self {
        Hits::new()
    }
}

impl Hits {
    /// Nothing remembered.
    pub const fn new() -> Hits {
        Hits {
            eye: (f64::NAN, f64::NAN),
            len: 0,
            levels: [Level::EMPTY; MAX_BRANCH],
            same_scene: false,
        }
    }

    /// Forgets the remembered levels (never needed for correctness: a level is used only
    /// for the same eye, objects, materials and edge coordinates).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// As [`hit_along`]`(scene, eye, dir, branch)`, reusing what the previous calls found
    /// (see [`Hits`]).
    pub fn along(
        &mut self,
        scene: &SceneRef<'_>,
        eye: QueryPoint,
        dir: (f64, f64),
        branch: &[ObjectId],
    ) -> Option<Hit> {
        self.along_from(scene, eye, eye.to_f64(), dir, branch, true)
            .0
    }

    /// [`Hits::along`] with `e = eye.to_f64()` (converted once per frame by
    /// [`centre_hits`]); `unfolded`: whether to try [`Hits::unfolded`] (not when the
    /// caller knows that it fails). Also whether the remembered levels now hold `branch`
    /// through mirrors ([`Hits::unfolds`] in a scene known to be the same), found on the
    /// way.
    fn along_from(
        &mut self,
        scene: &SceneRef<'_>,
        eye: QueryPoint,
        e: (f64, f64),
        dir: (f64, f64),
        branch: &[ObjectId],
        unfolded: bool,
    ) -> (Option<Hit>, bool) {
        if branch.len() > MAX_BRANCH {
            return (hit_along(scene, eye, dir, branch), false);
        }
        if e != self.eye {
            self.eye = e;
            self.len = 0;
        }
        if unfolded && branch.len() <= self.len {
            if let Some(hit) = self.unfolded(scene, dir, branch) {
                return (Some(hit), true);
            }
        }
        let old = self.len;
        let (mut done, mut same) = (0, true);
        let hit = self.walk(scene, dir, branch, old, &mut done, &mut same);
        // Deeper remembered levels stay valid only if every level was reused.
        self.len = if hit.is_some() && same { old } else { done };
        match hit {
            Some((hit, unfolds)) => (Some(hit), unfolds),
            None => (None, false),
        }
    }

    /// [`Hits::along`] when the remembered levels hold `branch` through mirrors and the
    /// ray still crosses every remembered entry edge (`None` otherwise): a few dot
    /// products per level.
    fn unfolded(&self, scene: &SceneRef<'_>, dir: (f64, f64), branch: &[ObjectId]) -> Option<Hit> {
        if !self.unfolds(scene, branch) {
            return None;
        }
        self.unfolded_at(dir, branch.len().checked_sub(1)?)
    }

    /// Whether the remembered levels hold `branch` through mirrors: the part of
    /// [`Hits::unfolded`] that does not depend on the ray. After a walk, [`Hits::walk`]
    /// knows it without the check, and [`centre_hits`] keeps it while the levels stay
    /// unchanged.
    fn unfolds(&self, scene: &SceneRef<'_>, branch: &[ObjectId]) -> bool {
        let Some(last) = branch.len().checked_sub(1) else {
            return false;
        };
        if branch.len() > self.len {
            return false;
        }
        for (level, (&id, lv)) in branch.iter().zip(&self.levels).enumerate() {
            let Some(lin) = lv.lin.as_ref() else {
                return false;
            };
            let through = lv.optics && matches!(lv.material, Material::Mirror);
            if lv.id != id || (level < last && !through) {
                return false;
            }
            if !self.same_scene {
                let Some(obj) = scene.object(id) else {
                    return false;
                };
                let poly = scene.polygon(obj);
                if obj.material != lv.material
                    || poly.get(lv.entry.k) != Some(&lin.pa)
                    || poly.get((lv.entry.k + 1) % poly.len()) != Some(&lin.pb)
                {
                    return false;
                }
            }
        }
        true
    }

    /// The ray-dependent part of [`Hits::unfolded`] for levels `0..=last` (checked by
    /// [`Hits::unfolds`]): whether the ray still crosses every entry edge, and the hit.
    #[inline]
    fn unfolded_at(&self, dir: (f64, f64), last: usize) -> Option<Hit> {
        let u = unit_ray(dir)?;
        for lv in self.levels.get(..=last)? {
            let lin = lv.lin.as_ref()?;
            if !(dot(lin.wd, u) < 0.0 && dot(lin.qa, u) >= 0.0 && dot(lin.qb, u) <= 0.0) {
                return None;
            }
        }
        self.unfolded_hit(u, last)
    }

    /// The hit along the unit ray `u` through the unfolded levels `0..=last` (the ray
    /// crosses every entry edge): the distances to the first and the last entry edge.
    #[inline]
    fn unfolded_hit(&self, u: (f64, f64), last: usize) -> Option<Hit> {
        self.ends(last)?.hit(u)
    }

    /// The linear forms of the unfolded levels `0` and `last` (`None` unless both are
    /// unfolded): what [`Hits::unfolded_hit`] reads, taken out once for a run of columns.
    #[inline]
    fn ends(&self, last: usize) -> Option<Ends> {
        let first = self.levels.first()?.lin?;
        let last = match last {
            0 => None,
            l => Some(self.levels.get(l)?.lin?),
        };
        Some(Ends { first, last })
    }

    /// For the unit ray `u` through the unfolded levels `0..=last`: the one constraint of
    /// [`Hits::unfolded_at`] that fails first as the ray turns clockwise (`q` with
    /// `q·u ≥ 0` while the ray crosses every entry edge), or `None` if `u` is on or
    /// outside one. Each constraint holds on a half-turn that ends less than π clockwise
    /// of `u`, and the ends come in the order of the `q`s: a column right of `u` then
    /// takes one test, not three per level ([`centre_hits`]). The edge normal's test
    /// (`den < 0`) follows from the endpoints' (`den = cross(M·u, b − a)`) and is left
    /// to [`Hits::unfolded_hit`] where a distance needs it.
    fn first_to_fail(&self, u: (f64, f64), last: usize) -> Option<(f64, f64)> {
        let mut first = (0.0, 0.0);
        for lv in self.levels.get(..=last)? {
            let lin = lv.lin.as_ref()?;
            for q in [lin.qa, (-lin.qb.0, -lin.qb.1)] {
                let p = dot(q, u);
                if p.is_nan() || p <= 0.0 {
                    return None;
                }
                // `q` counter-clockwise of `first`: its half-turn ends first, clockwise
                // (the zero start is clockwise of every `q`).
                if first.0 * q.1 - first.1 * q.0 >= 0.0 {
                    first = q;
                }
            }
        }
        Some(first)
    }

    /// [`Hits::along`]: `done` counts the levels now remembered for this branch, `same`
    /// whether all of them were reused (levels `0..old` were remembered before); with the
    /// hit, whether the levels hold the branch through mirrors (every level before the
    /// last is a mirror, so the last one's `lin` was computed).
    fn walk(
        &mut self,
        scene: &SceneRef<'_>,
        dir: (f64, f64),
        branch: &[ObjectId],
        old: usize,
        done: &mut usize,
        same: &mut bool,
    ) -> Option<(Hit, bool)> {
        let l = norm(dir.0, dir.1);
        if branch.is_empty() || l <= 0.0 {
            return None;
        }
        let same_scene = self.same_scene;
        let mut e = self.eye;
        let mut o = e;
        let mut d = (dir.0 / l, dir.1 / l);
        let (mut first, mut length, mut facing) = (0.0, 0.0, 1.0);
        // The product of the reflections so far, while every level is a mirror.
        let mut m = Some([[1.0, 0.0], [0.0, 1.0]]);
        let mut unfolds = false;
        for (level, &id) in branch.iter().enumerate() {
            let obj = scene.object(id)?;
            let poly = scene.polygon(obj);
            let lv = self.levels.get_mut(level)?;
            let reuse = *same && level < old && lv.id == id && lv.material == obj.material;
            let t = match reuse
                .then(|| lv.entry.meet(poly, o, d, false, same_scene))
                .flatten()
            {
                Some(t) => t,
                None => {
                    *same = false;
                    let (t, k, _, _) = clip_polygon(poly, o, d)?;
                    let entry = Side::of(poly, k)?;
                    // The optics (`inner`, `exit`, `next`, `after`) are recomputed below
                    // before they are read (`optics` false): only these fields are written.
                    lv.id = id;
                    lv.material = obj.material;
                    lv.entry = entry;
                    lv.optics = false;
                    lv.lin = m.as_ref().and_then(|m| Unfolded::new(poly, &entry, e, m));
                    t
                }
            };
            let t = t.max(0.0);
            let p = (o.0 + t * d.0, o.1 + t * d.1);
            length += t;
            if level == 0 {
                first = t;
            }
            let nrm = lv.entry.n;
            facing = libm::fabs(d.0 * nrm.0 + d.1 * nrm.1);
            if level + 1 == branch.len() {
                *done = level + 1;
                unfolds = m.is_some() && lv.lin.is_some();
                break;
            }
            let fresh = !(*same && lv.optics);
            if fresh {
                *same = false;
                lv.optics = false;
            }
            // As in `hit_along`: a ray type compiled out takes no branch past its objects.
            let np = match obj.material {
                Material::Mirror if cfg!(feature = "mirrors") => {
                    if fresh {
                        lv.next = transform_eye_f64(e, lv.entry.a, nrm, -1.0);
                        lv.after = m.map(|m| reflect(&m, nrm));
                    }
                    m = lv.after;
                    p
                }
                Material::Refractive { eta } if cfg!(feature = "refraction") => {
                    m = None;
                    let eta = eta.to_f64();
                    if fresh {
                        lv.inner = transform_eye_f64(e, lv.entry.a, nrm, eta);
                    }
                    let d1 = unit((p.0 - lv.inner.0, p.1 - lv.inner.1))?;
                    let t2 = match (!fresh)
                        .then(|| lv.exit.meet(poly, p, d1, true, same_scene))
                        .flatten()
                    {
                        Some(t2) => t2,
                        None => {
                            *same = false;
                            lv.optics = false;
                            let (_, _, t2, exit) = clip_polygon(poly, p, d1)?;
                            lv.exit = Side::of(poly, exit)?;
                            lv.next = transform_eye_f64(lv.inner, lv.exit.a, lv.exit.n, 1.0 / eta);
                            t2
                        }
                    };
                    let t2 = t2.max(0.0);
                    length += t2;
                    (p.0 + t2 * d1.0, p.1 + t2 * d1.1)
                }
                // Opaque objects end a branch; screens are never in one.
                _ => return None,
            };
            lv.optics = true;
            d = unit((np.0 - lv.next.0, np.1 - lv.next.1))?;
            e = lv.next;
            o = np;
            *done = level + 1;
        }
        let hit = Hit {
            first,
            length,
            facing,
        };
        Some((hit, unfolds))
    }
}

/// The interval through each column's centre (as [`centre_intervals`]) and the hit along
/// its branch (as [`hit_along`] along [`Camera::centre`], through one [`Hits`]): calls
/// `each(column, interval, hit)` for every column from the left. Allocates nothing;
/// O(W + log intervals) besides the hits. A column of an interval whose branch unfolds
/// through mirrors takes the one test of [`Hits`] that can fail first instead of all of
/// them (the same hit), and a column that sees nothing takes no call.
pub fn centre_hits<I: Interval>(
    scene: &SceneRef<'_>,
    camera: &Camera,
    intervals: &[I],
    mut each: impl FnMut(usize, usize, Option<Hit>),
) {
    let mut hits = Hits {
        same_scene: true,
        ..Hits::new()
    };
    let mut sweep = None;
    let e = camera.eye.to_f64();
    // The interval whose branch the remembered levels unfold, until the next call that may
    // change the levels: its later columns take one test and the distances.
    let mut run: Option<Run> = None;
    for (c, centre) in camera.centre_vectors().enumerate() {
        let k = if intervals.is_empty() {
            0
        } else {
            sweep
                .get_or_insert_with(|| Centres::new(camera, intervals, centre))
                .next(centre)
        };
        let branch = intervals.get(k).map_or(&[][..], |i| i.branch());
        // A ray that sees nothing hits nothing (`hit_along` of an empty branch).
        let Some(last) = branch.len().checked_sub(1) else {
            each(c, k, None);
            continue;
        };
        let dir = (centre.0 as f64, centre.1 as f64);
        // Whether `Hits::unfolded` is still worth trying: not after the constraint that
        // fails first failed (or a distance's `den < 0`, which it checks too).
        let mut unfolded = true;
        if let Some(r) = &mut run {
            if r.interval == k {
                let fast = unit_ray(dir).and_then(|u| {
                    let q = match r.limit {
                        Some(q) => q,
                        None => *r.limit.insert(hits.first_to_fail(u, last)?),
                    };
                    unfolded = false;
                    (dot(q, u) >= 0.0).then(|| r.ends.hit(u))?
                });
                if fast.is_some() {
                    each(c, k, fast);
                    continue;
                }
            }
        }
        // As before the shortcut: `Hits::unfolded`, then the walk.
        let (hit, unfolds) = hits.along_from(scene, camera.eye, e, dir, branch, unfolded);
        run = unfolds.then(|| hits.ends(last)).flatten().map(|ends| Run {
            interval: k,
            ends,
            limit: None,
        });
        each(c, k, hit);
    }
}

/// A run of columns of one interval whose branch the remembered levels unfold through
/// mirrors ([`Hits::unfolds`]), in [`centre_hits`].
struct Run {
    interval: usize,
    /// The levels' ends, read once for the run.
    ends: Ends,
    /// From the run's second column, the constraint that fails first clockwise
    /// ([`Hits::first_to_fail`]).
    limit: Option<(f64, f64)>,
}

/// `|(x, y)|` for output: the components stay far below 2⁵¹¹ (scene coordinates and
/// their differences), so the plain formula cannot overflow, and it is a hardware square
/// root where `hypot`'s scaling is a slow software routine (a frame calls it per column
/// and level).
fn norm(x: f64, y: f64) -> f64 {
    libm::sqrt(x * x + y * y)
}

/// The unit direction of a ray `dir` (`None` for a zero or NaN one; an infinite length
/// gives zeros, which no unfolded level accepts).
#[inline]
fn unit_ray(dir: (f64, f64)) -> Option<(f64, f64)> {
    let l = norm(dir.0, dir.1);
    (!l.is_nan() && l > 0.0).then(|| (dir.0 / l, dir.1 / l))
}

fn unit(v: (f64, f64)) -> Option<(f64, f64)> {
    let l = norm(v.0, v.1);
    (l > 0.0 && l.is_finite()).then(|| (v.0 / l, v.1 / l))
}

#[cfg(test)]
mod tests {
    use super::round_small_i64;
    #[cfg(feature = "alloc")]
    use super::{coverage, Angle, Camera, CoverageTable, Direction, ObjectId};
    #[cfg(feature = "alloc")]
    use alloc::vec::Vec;

    /// Intervals with an exact start or one known in `f64` only.
    #[cfg(feature = "alloc")]
    use crate::walk::TreeInterval as Iv;

    /// The table from every piece of [`coverage`], each through `push`: the column by
    /// column merge, every column edge computed.
    #[cfg(feature = "alloc")]
    fn by_pieces(camera: &Camera, intervals: &[Iv]) -> CoverageTable {
        let mut t = CoverageTable::new();
        let mut col = 0;
        coverage(camera, intervals, |p| {
            while col < p.column {
                t.end_column();
                col += 1;
            }
            t.push(&intervals[p.interval].branch, p.fraction);
        });
        while col < camera.width() {
            t.end_column();
            col += 1;
        }
        t
    }

    /// `CoverageTable::exact` (runs of whole columns without their edges, each run one
    /// shared entry, boundaries placed by their image coordinate) equals the table of
    /// `coverage`'s pieces column by column, bit for bit: boundaries anywhere, exactly on
    /// column edges, known in `f64` only, on cameras of every width and field of view, and
    /// on ones whose edges are not known in order (some columns of zero width: empty).
    #[cfg(feature = "alloc")]
    #[test]
    fn exact_table_equals_the_pieces() {
        let mut next = crate::geom::xorshift(0x9e37_79b9_7f4a_7c15);
        let eye = crate::QueryPoint::from_raw(0, 0).unwrap();
        let branches: [&[u32]; 4] = [&[], &[1], &[2, 1], &[3]];
        let mut reused = CoverageTable::new();
        let (mut jumps, mut shared, mut empty) = (0, 0, 0);
        for case in 0..3000 {
            let unit = |r: u64| (r % 1_000_000) as f64 / 1_000_000.0;
            let heading = unit(next()) * core::f64::consts::TAU;
            let (fov, width) = match case % 8 {
                // Edges not known in order; at 1e-12 many coincide: empty columns.
                7 => ([2e-10, 1e-12][case / 8 % 2], 4096),
                k => (
                    [1e-3, 0.3, 1.5, 2.5, 3.12][k % 5],
                    [1, 2, 3, 7, 64, 800, 801][(next() % 7) as usize],
                ),
            };
            let camera = Camera::new(eye, heading, fov, width).unwrap();
            jumps += usize::from(camera.ordered);
            let mut ivs = Vec::new();
            for _ in 0..1 + next() % 12 {
                let t = camera.tan_half();
                let x = (unit(next()) * 2.4 - 1.2) * t;
                let v = match next() % 4 {
                    // Exactly on a column edge.
                    0 => camera.edge((next() as usize) % (width + 1)).vector,
                    // Anywhere on the circle.
                    1 => ((next() % 2001) as i64 - 1000, (next() % 2001) as i64 - 1000),
                    _ => {
                        let d = camera.direction_at(x);
                        ((d.0 * 1e12) as i64, (d.1 * 1e12) as i64)
                    }
                };
                let Some(d) = Direction::new(v.0, v.1) else {
                    continue;
                };
                let a = Angle::constant(d);
                let exact = (!next().is_multiple_of(3)).then_some(a);
                let branch = branches[(next() % 4) as usize];
                ivs.push(Iv {
                    exact_start: exact,
                    start: a.radians(),
                    branch: branch.iter().map(|&o| ObjectId(o)).collect(),
                    start_vertex: None,
                });
            }
            ivs.sort_by(|a, b| a.start.total_cmp(&b.start));
            let want = by_pieces(&camera, &ivs);
            let table = CoverageTable::exact(&camera, &ivs);
            assert_eq!(table.columns(), width, "case {case}");
            for c in 0..width {
                assert_eq!(table.column(c), want.column(c), "case {case}, column {c}");
            }
            assert_eq!(table, want, "case {case}");
            shared += usize::from(table.entries.len() < want.entries.len());
            empty += (0..width).filter(|&c| table.column(c).is_empty()).count();
            reused.exact_into(&camera, &ivs);
            assert_eq!(reused, want, "case {case}, reused");
        }
        assert!(jumps > 2000, "{jumps}");
        assert!(shared > 1000, "{shared}");
        assert!(empty > 1000, "{empty}");
    }

    /// Tables compare by columns: a run sharing one entry equals the same columns written
    /// one by one, a column of another fraction, branch or length differs, and the entries
    /// of the open column belong to no column.
    #[cfg(feature = "alloc")]
    #[test]
    fn tables_compare_by_columns() {
        let (a, b) = (&[ObjectId(1)][..], &[ObjectId(2)][..]);
        let camera = Camera::new(crate::QueryPoint::from_raw(0, 0).unwrap(), 0.0, 1.0, 3);
        let ivs = [Iv {
            exact_start: None,
            start: 0.0,
            branch: a.to_vec(),
            start_vertex: None,
        }];
        let shared = CoverageTable::exact(&camera.unwrap(), &ivs);
        let columns = |cols: &[&[(&[ObjectId], f64)]]| {
            let mut t = CoverageTable::new();
            for col in cols {
                col.iter().for_each(|&(br, f)| t.push(br, f));
                t.end_column();
            }
            t
        };
        let whole: &[_] = &[(a, 1.0)];
        assert!(shared.entries.len() < shared.columns(), "{shared:?}");
        assert_eq!(shared, columns(&[whole, whole, whole]));
        assert_ne!(shared, columns(&[whole, whole]));
        assert_ne!(shared, columns(&[whole, &[(a, 0.5)], whole]));
        assert_ne!(shared, columns(&[whole, whole, &[(b, 1.0)]]));
        assert_ne!(shared, columns(&[whole, &[(a, 1.0), (b, 0.0)], whole]));
        // The open column's entries are no ended column's.
        let mut open = columns(&[whole, whole]);
        open.push(b, 0.5);
        assert_eq!(open, columns(&[whole, whole]));
    }

    /// The magic-number rounding agrees with `libm::round` away from ties, rounds ties to
    /// even, and is exact up to the largest edge component 2⁵⁰ (and beyond, to 2⁵¹).
    #[test]
    fn round_small_rounds_to_nearest_up_to_2_pow_51() {
        let big = (1u64 << 50) as f64;
        for x in [
            0.0,
            0.3,
            -0.3,
            0.7,
            -0.7,
            1.49,
            -1.51,
            12345.678,
            -98765.4321,
            big,
            -big,
            big - 0.75,
            -(big - 0.25),
            2.0 * big - 1.0,
            -(2.0 * big) + 1.0,
        ] {
            assert_eq!(round_small_i64(x) as f64, libm::round(x), "{x}");
        }
        assert_eq!(round_small_i64(0.5), 0);
        assert_eq!(round_small_i64(1.5), 2);
        assert_eq!(round_small_i64(-2.5), -2);
        assert_eq!(round_small_i64(big + 0.5), big as i64);
    }
}
