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
//! convenience [`CoverageTable`].
//!
//! # Hits and the `f64` optics
//!
//! [`hit_along`] follows a branch along one ray in `f64` (output only: distances and
//! shading): a mirror reflects the eye across the hit edge's line, a refractive object
//! moves it by the tangent law at the entry and at the exit edge ([`transform_eye_f64`]),
//! exactly the optics of [`crate::walk`] without the rounding of the eyes. The ray casters
//! of the `vcx-baselines` crate use the same functions.

use alloc::vec::Vec;
use core::cmp::Ordering;

use crate::geom::predicates::Direction;
use crate::geom::sos::Angle;
use crate::geom::QueryPoint;
use crate::scene::{Material, ObjectId, SceneRef};
use crate::walk::{TreeInterval, ViewInterval};

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

/// `x` rounded to an integer (ties to even) for `|x| ≤ 2⁵¹`: adding and subtracting
/// 1.5·2⁵² leaves no fraction bits, in two hardware additions (`libm::round` is software).
fn round_small(x: f64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    (x + MAGIC) - MAGIC
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
        let cam = Camera {
            eye,
            width,
            heading,
            tan_half: libm::tan(fov / 2.0),
            forward: (c, s),
            right: (s, -c),
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

    fn rounded(&self, x: f64) -> Edge {
        let d = self.direction_at(x);
        let m = libm::fmax(libm::fabs(d.0), libm::fabs(d.1));
        let k = EDGE_SCALE / m;
        let v = (round_small(d.0 * k) as i64, round_small(d.1 * k) as i64);
        Edge {
            vector: v,
            x: self.image_x((v.0 as f64, v.1 as f64)),
        }
    }

    /// Column edge `c` (`0` is the left edge of the image, `width` the right edge).
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

    /// Where the direction `v` (exact) falls: outside the open field of view, exactly on
    /// an inner column edge, or inside a column.
    fn place_exact(&self, v: (i128, i128)) -> Place {
        let (l, r) = (self.edge(0).vector, self.edge(self.width).vector);
        // Inside the open arc (R, L) of width < π: R → v and v → L both turn left.
        if cross_w(r, v) <= 0 || cross_w(l, v) >= 0 {
            return Place::Outside;
        }
        // First inner edge c (1 ≤ c ≤ W) with v on its left (cross(e_c, v) ≥ 0).
        let (mut lo, mut hi) = (1, self.width);
        for _ in 0..64 {
            if lo >= hi {
                break;
            }
            let mid = lo + (hi - lo) / 2;
            if cross_w(self.edge(mid).vector, v) >= 0 {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        if lo < self.width && cross_w(self.edge(lo).vector, v) == 0 {
            return Place::OnEdge(lo);
        }
        let column = lo - 1;
        let (vx, vy) = (v.0 as f64, v.1 as f64);
        Place::Inside {
            column,
            x: self.image_x((vx, vy)),
        }
    }

    /// As [`Camera::place_exact`] for a direction known in `f64` only (radians).
    fn place_f64(&self, radians: f64) -> Place {
        let d = (libm::cos(radians), libm::sin(radians));
        if d.0 * self.forward.0 + d.1 * self.forward.1 <= 0.0 {
            return Place::Outside;
        }
        let x = self.image_x(d);
        if !(x > self.edge(0).x && x < self.edge(self.width).x) {
            return Place::Outside;
        }
        let (mut lo, mut hi) = (1, self.width);
        for _ in 0..64 {
            if lo >= hi {
                break;
            }
            let mid = lo + (hi - lo) / 2;
            if self.edge(mid).x >= x {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        if lo < self.width && self.edge(lo).x == x {
            return Place::OnEdge(lo);
        }
        Place::Inside { column: lo - 1, x }
    }
}

/// Where a boundary falls on the image.
#[derive(Clone, Copy, Debug)]
enum Place {
    Outside,
    OnEdge(usize),
    Inside { column: usize, x: f64 },
}

fn cross_i(u: (i64, i64), v: (i64, i64)) -> i128 {
    i128::from(u.0) * i128::from(v.1) - i128::from(u.1) * i128::from(v.0)
}

/// `cross(e, v)` for an edge vector (≤ 2⁵⁰) and a boundary vector (≤ 2⁵⁴): < 2¹⁰⁵.
fn cross_w(e: (i64, i64), v: (i128, i128)) -> i128 {
    i128::from(e.0) * v.1 - i128::from(e.1) * v.0
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

    /// Whether interval `k` contains the probe: it starts at or before it and the next one
    /// after it; the last interval wraps through θ = 0.
    fn within<I: Interval>(&self, intervals: &[I], k: usize) -> bool {
        let starts = |i: usize| intervals.get(i).is_some_and(|x| self.after_start(x));
        if k + 1 < intervals.len() {
            starts(k) && !starts(k + 1)
        } else {
            starts(k) || !starts(0)
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
/// nothing; O(W + boundaries in view · log W). An empty `intervals` emits nothing.
pub fn coverage<I: Interval>(camera: &Camera, intervals: &[I], mut emit: impl FnMut(Piece)) {
    let n = intervals.len();
    let w = camera.width;
    if n == 0 {
        return;
    }
    let left = camera.edge(0);
    let la = left.angle();
    // The interval just clockwise of the left edge.
    let mut cur = interval_at(intervals, &la);
    if n > 1
        && intervals
            .get(cur)
            .is_some_and(|i| start_cmp(i, &la) == Ordering::Equal)
    {
        cur = (cur + n - 1) % n;
    }
    let mut col = 0;
    let mut x = left.x;
    let mut piece = |col: usize, interval: usize, from: f64, to: f64| {
        let (a, b) = (camera.edge(col).x, camera.edge(col + 1).x);
        let (from, to) = (from.clamp(a, b), to.clamp(a, b));
        if to > from {
            emit(Piece {
                column: col,
                interval,
                from,
                to,
                fraction: (to - from) / (b - a),
            });
        }
    };
    // Boundaries clockwise from the left edge: the start of the current interval, then of
    // the one before, … until one lies outside the field of view.
    if n > 1 {
        for _ in 0..n {
            let Some(iv) = intervals.get(cur) else { break };
            let place = match iv.exact_start() {
                Some(s) => camera.place_exact(s.vector()),
                None => camera.place_f64(iv.start_radians()),
            };
            let (bcol, bx) = match place {
                Place::Outside => break,
                Place::OnEdge(c) => (c, camera.edge(c).x),
                Place::Inside { column, x } => (column, x),
            };
            if bcol < col {
                // Out of order (an `f64` boundary next to an exact one): already passed.
                cur = (cur + n - 1) % n;
                continue;
            }
            while col < bcol {
                piece(col, cur, x, f64::INFINITY);
                col += 1;
                x = camera.edge(col).x;
            }
            let bx = bx.max(x);
            piece(col, cur, x, bx);
            x = bx;
            cur = (cur + n - 1) % n;
        }
    }
    while col < w {
        piece(col, cur, x, f64::INFINITY);
        col += 1;
        x = camera.edge(col).x;
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
/// Columns run clockwise, so the interval of the next column is the same one or an
/// earlier one: each column first tries those two (two comparisons each), and searches
/// by bisection only when neither holds it. O(W + intervals) for a frame.
pub fn centre_intervals<I: Interval>(camera: &Camera, intervals: &[I], out: &mut [usize]) {
    let n = intervals.len();
    if n == 0 {
        out.iter_mut().for_each(|s| *s = 0);
        return;
    }
    let mut k = None;
    for (c, slot) in out.iter_mut().enumerate().take(camera.width) {
        let p = Probe::new(camera.centre(c).angle());
        let found = match k {
            Some(k) if p.within(intervals, k) => k,
            Some(k) if p.within(intervals, (k + n - 1) % n) => (k + n - 1) % n,
            _ => p.find(intervals),
        };
        *slot = found;
        k = Some(found);
    }
}

/// Per-column coverage by **branch** (pieces of equal branch merged), the common output
/// of the complex and of the ray casters of `vcx-baselines`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CoverageTable {
    /// `entries[start[c]..start[c + 1]]` are column `c`'s branches with their fractions.
    pub start: Vec<usize>,
    /// Branches and covered fractions, grouped by column.
    pub entries: Vec<(Branch, f64)>,
}

impl CoverageTable {
    /// An empty table; fill it with [`CoverageTable::push`] and [`CoverageTable::end_column`].
    pub fn new() -> CoverageTable {
        CoverageTable {
            start: alloc::vec![0],
            entries: Vec::new(),
        }
    }

    /// Clears the table, keeping its buffers.
    pub fn clear(&mut self) {
        self.start.clear();
        self.start.push(0);
        self.entries.clear();
    }

    /// Adds `fraction` of the current column to `branch`.
    pub fn push(&mut self, branch: &[ObjectId], fraction: f64) {
        let s = self.start.last().copied().unwrap_or(0);
        if let Some(e) = self
            .entries
            .get_mut(s..)
            .and_then(|col| col.iter_mut().find(|e| e.0.as_slice() == branch))
        {
            e.1 += fraction;
            return;
        }
        let mut b = Branch::new();
        for &o in branch.iter().take(MAX_BRANCH) {
            let _ = b.push(o);
        }
        self.entries.push((b, fraction));
    }

    /// Ends the current column.
    pub fn end_column(&mut self) {
        self.start.push(self.entries.len());
    }

    /// The exact coverage of the camera's columns by the intervals.
    pub fn exact<I: Interval>(camera: &Camera, intervals: &[I]) -> CoverageTable {
        let mut t = CoverageTable::new();
        let mut col = 0;
        coverage(camera, intervals, |p| {
            while col < p.column {
                t.end_column();
                col += 1;
            }
            let branch = intervals.get(p.interval).map_or(&[][..], |i| i.branch());
            t.push(branch, p.fraction);
        });
        while col < camera.width {
            t.end_column();
            col += 1;
        }
        t
    }

    /// Number of columns.
    pub fn columns(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// Column `c`'s branches and fractions.
    pub fn column(&self, c: usize) -> &[(Branch, f64)] {
        match (self.start.get(c), self.start.get(c + 1)) {
            (Some(&a), Some(&b)) => self.entries.get(a..b).unwrap_or(&[]),
            _ => &[],
        }
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
    let n = poly.len();
    let (mut t_in, mut e_in, mut t_out, mut e_out) = (f64::NEG_INFINITY, 0, f64::INFINITY, 0);
    for k in 0..n {
        let (a, b) = (poly.get(k)?.to_f64(), poly.get((k + 1) % n)?.to_f64());
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

/// `|(x, y)|` for output: the components stay far below 2⁵¹¹ (scene coordinates and
/// their differences), so the plain formula cannot overflow, and it is a hardware square
/// root where `hypot`'s scaling is a slow software routine (a frame calls it per column
/// and level).
fn norm(x: f64, y: f64) -> f64 {
    libm::sqrt(x * x + y * y)
}

fn unit(v: (f64, f64)) -> Option<(f64, f64)> {
    let l = norm(v.0, v.1);
    (l > 0.0 && l.is_finite()).then(|| (v.0 / l, v.1 / l))
}

#[cfg(test)]
mod tests {
    use super::round_small;

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
            assert_eq!(round_small(x), libm::round(x), "{x}");
        }
        assert_eq!(round_small(0.5), 0.0);
        assert_eq!(round_small(1.5), 2.0);
        assert_eq!(round_small(-2.5), -2.0);
        assert_eq!(round_small(big + 0.5), big);
    }
}
