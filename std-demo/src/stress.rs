//! Near-degenerate scenes for the numerical-stability stress test (`vcx bench stability`,
//! `tests/tests/stability.rs`).
//!
//! Every family is drawn on a design lattice of `±255` units; a design unit is `2^(e+8)`
//! raw grid units for the scale `e` in [`SCALES`], so the scene reaches about `±2^e` scene
//! units: from `e = −8`, where a design unit is the finest grid unit (2⁻¹⁶), to `e = 14`,
//! the top of the coordinate range (`|raw| ≤ 2³⁰ − 1`). Vertices get random raw offsets
//! below one design unit, so long edges have generic directions.
//!
//! **One grid step.** The near-degeneracies are as near as the grid allows, at every scale:
//! a point "one grid step off" the line through `a` and `b` is a grid point on the
//! neighbouring lattice line parallel to `ab` (Bézout), so `orient(a, b, c) = ±gcd(b − a)`,
//! the smallest non-zero value — for a generic direction far less than one grid unit of
//! distance. For axis-parallel lines it is one grid unit. The determinant stays this
//! small while the products of differences grow with the scale: that is what breaks `f64`
//! (products beyond 2⁵³).
//!
//! Families ([`Family`]):
//! * `collinear`: collinear lattices — rows of triangles whose bases lie on one lattice
//!   line (exactly collinear vertices across objects), half of them moved one grid step
//!   off it (nearly collinear);
//! * `unit-gap`: pairs of triangles one grid step apart across a shared line (a third of
//!   them axis-parallel: one grid unit);
//! * `sliver`: long thin triangles across the scene, the apex one grid step off the base;
//! * `parallel`: rows of long thin trapezoids whose top edge turns from the bottom one by
//!   the smallest lattice angle (`cross(u, v) = 1`), the next row's bottom edge parallel to
//!   the top one;
//! * `bitangent`: random triangles; viewpoints on bitangent lines of two objects;
//! * `edge-ext`: random triangles; viewpoints on extensions of edges.
//!
//! Viewpoints (query grid, 2⁻³²) are a third each: exactly on a line through two vertices
//! (a bitangent's line, an edge's extension, or any two vertices for the first four
//! families), one query-grid step off such a line, and random free points.
//!
//! Generation uses only its own exact integer arithmetic (never the crate's predicates), so
//! the exact and the naive builds of `vcx` generate the same scenes; every object is
//! checked strictly convex and disjoint from the others before it is kept. The output
//! depends only on the arguments (`ChaCha8Rng`).

use core::fmt;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use vcx::geom::point::MAX_ABS_RAW;
use vcx::{Material, Point, QueryPoint, Scene, SceneError};

/// The scales: a scene reaches about `±2^e` scene units (`e = −8`: the lattice is the
/// finest grid; `e = 14`: the top of the range).
pub const SCALES: [i32; 9] = [-8, -4, 0, 4, 8, 10, 12, 13, 14];

/// Half-width of the design lattice, in design units.
const HALF: i64 = 255;
/// How many times an object or a viewpoint is redrawn before it is skipped.
const TRIES: usize = 64;

/// A family of near-degenerate scenes (module documentation).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Family {
    /// Rows of triangles on shared lattice lines, half moved one grid step off.
    Collinear,
    /// Pairs of objects one grid step apart.
    UnitGap,
    /// Long thin triangles, apex one grid step off the base.
    Sliver,
    /// Thin trapezoids with nearly parallel edges.
    Parallel,
    /// Viewpoints on bitangent lines.
    Bitangent,
    /// Viewpoints on extensions of edges.
    EdgeExtension,
}

impl Family {
    /// Every family, in report order.
    pub const ALL: [Family; 6] = [
        Family::Collinear,
        Family::UnitGap,
        Family::Sliver,
        Family::Parallel,
        Family::Bitangent,
        Family::EdgeExtension,
    ];

    /// Name in reports and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Family::Collinear => "collinear",
            Family::UnitGap => "unit-gap",
            Family::Sliver => "sliver",
            Family::Parallel => "parallel",
            Family::Bitangent => "bitangent",
            Family::EdgeExtension => "edge-ext",
        }
    }

    /// The family of a name.
    pub fn from_name(name: &str) -> Option<Family> {
        Family::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// Why a stress scene could not be made.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum StressError {
    /// The scale is outside `−8..=14`.
    Scale(i32),
}

impl fmt::Display for StressError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StressError::Scale(e) => write!(f, "scale {e} outside -8..=14"),
        }
    }
}

impl core::error::Error for StressError {}

/// One generated instance: opaque convex polygons (counter-clockwise, raw grid) and free
/// viewpoints.
#[derive(Clone, Debug)]
pub struct StressScene {
    /// Its family.
    pub family: Family,
    /// Its scale `e` (coordinates up to about `±2^e` scene units).
    pub scale: i32,
    /// The polygons, counter-clockwise.
    pub polygons: Vec<Vec<Point>>,
    /// Free viewpoints (checked exactly against every polygon).
    pub viewpoints: Vec<QueryPoint>,
}

impl StressScene {
    /// The validated scene (all objects opaque). With the naive predicates the validation
    /// itself may reject it.
    pub fn scene(&self) -> Result<Scene, SceneError> {
        Scene::new(
            self.polygons
                .iter()
                .map(|p| (Material::Opaque, p.as_slice())),
        )
    }

    /// A 64-bit FNV-1a fingerprint of the coordinates and viewpoints: two runs joined by
    /// `vcx bench stability --compare` must agree on it.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv::new();
        for p in &self.polygons {
            h.write(&(p.len() as u64).to_le_bytes());
            for v in p {
                h.write(&v.x().to_le_bytes());
                h.write(&v.y().to_le_bytes());
            }
        }
        for q in &self.viewpoints {
            h.write(&q.x().to_le_bytes());
            h.write(&q.y().to_le_bytes());
        }
        h.finish()
    }
}

/// 64-bit FNV-1a: small, portable, stable across runs (for fingerprints of scenes and
/// views).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Fnv {
    /// The empty hash.
    pub fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    /// Adds bytes.
    pub fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.0 ^= u64::from(*b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// The hash.
    pub fn finish(self) -> u64 {
        self.0
    }
}

impl Default for Fnv {
    fn default() -> Fnv {
        Fnv::new()
    }
}

/// Generates the instance of `family` at scale `e` with about `objects` objects and up to
/// `viewpoints` viewpoints; `seed` and `instance` select the random draw.
pub fn generate(
    family: Family,
    e: i32,
    objects: usize,
    viewpoints: usize,
    seed: u64,
    instance: u64,
) -> Result<StressScene, StressError> {
    if !(-8..=14).contains(&e) {
        return Err(StressError::Scale(e));
    }
    let mix = ((family as u64) << 56) ^ (((e + 8) as u64) << 48) ^ (instance << 24) ^ seed;
    let mut b = Builder {
        step: 1i64 << (e + 8),
        rng: ChaCha8Rng::seed_from_u64(mix),
        polys: Vec::new(),
    };
    let n = objects.max(1);
    match family {
        Family::Collinear => collinear(&mut b, n),
        Family::UnitGap => unit_gap(&mut b, n),
        Family::Sliver => slivers(&mut b, n),
        Family::Parallel => parallel(&mut b, n),
        Family::Bitangent | Family::EdgeExtension => triangles(&mut b, n),
    }
    let views = b.viewpoints(family, viewpoints);
    let polygons = b
        .polys
        .iter()
        .map(|p| {
            p.iter()
                .filter_map(|&(x, y)| Point::from_raw(x as i32, y as i32))
                .collect()
        })
        .collect();
    Ok(StressScene {
        family,
        scale: e,
        polygons,
        viewpoints: views,
    })
}

type P = (i64, i64);

/// `cross(a − o, b − o)`, exact.
fn cross(o: P, a: P, b: P) -> i128 {
    let (ax, ay) = (i128::from(a.0 - o.0), i128::from(a.1 - o.1));
    let (bx, by) = (i128::from(b.0 - o.0), i128::from(b.1 - o.1));
    ax * by - ay * bx
}

/// The cyclic successor of index `i` in a list of `n`.
fn next(i: usize, n: usize) -> usize {
    if i + 1 == n {
        0
    } else {
        i + 1
    }
}

/// Strictly convex and counter-clockwise, at least three vertices, inside the range.
fn strictly_convex(p: &[P]) -> bool {
    let n = p.len();
    if n < 3 {
        return false;
    }
    let in_range =
        |v: &P| v.0.abs() <= i64::from(MAX_ABS_RAW) && v.1.abs() <= i64::from(MAX_ABS_RAW);
    if !p.iter().all(in_range) {
        return false;
    }
    // All left turns, and the edge directions wind once: the y-direction changes sign
    // exactly twice (or the polygon is a triangle, which cannot wind twice).
    let turns = (0..n).all(
        |i| match (p.get(i), p.get(next(i, n)), p.get(next(next(i, n), n))) {
            (Some(&a), Some(&b), Some(&c)) => cross(a, b, c) > 0,
            _ => false,
        },
    );
    let mut area: i128 = 0;
    for i in 0..n {
        if let (Some(&a), Some(&b)) = (p.get(i), p.get(next(i, n))) {
            area += i128::from(a.0) * i128::from(b.1) - i128::from(b.0) * i128::from(a.1);
        }
    }
    // With all left turns the total turning is 2πk; a positive area and a convex hull
    // built by Andrew's chain (or three or four vertices) give k = 1.
    turns && area > 0 && (n <= 4 || hull(p.to_vec()).len() == n)
}

/// Whether some edge of `a` (counter-clockwise) has every vertex of `b` strictly outside.
fn separated_by_edge_of(a: &[P], b: &[P]) -> bool {
    let n = a.len();
    (0..n).any(|i| match (a.get(i), a.get(next(i, n))) {
        (Some(&p), Some(&q)) => b.iter().all(|&v| cross(p, q, v) < 0),
        _ => false,
    })
}

/// Disjoint (not even touching) convex polygons: an edge of one separates them strictly.
fn disjoint(a: &[P], b: &[P]) -> bool {
    separated_by_edge_of(a, b) || separated_by_edge_of(b, a)
}

/// Strictly convex hull, counter-clockwise (Andrew's monotone chain).
fn hull(mut pts: Vec<P>) -> Vec<P> {
    pts.sort_unstable();
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let mut out: Vec<P> = Vec::with_capacity(pts.len() + 1);
    let push = |out: &mut Vec<P>, p: P, start: usize| {
        while out.len() >= start + 2 {
            let (Some(&a), Some(&b)) = (out.get(out.len() - 2), out.last()) else {
                break;
            };
            if cross(a, b, p) > 0 {
                break;
            }
            out.pop();
        }
        out.push(p);
    };
    for &p in &pts {
        push(&mut out, p, 0);
    }
    out.pop();
    let start = out.len();
    for &p in pts.iter().rev() {
        push(&mut out, p, start);
    }
    out.pop();
    out
}

/// Whether the query point `q` (query grid) lies strictly outside the polygon `p` (raw).
fn outside(p: &[P], q: (i128, i128)) -> bool {
    let n = p.len();
    (0..n).any(|i| match (p.get(i), p.get(next(i, n))) {
        (Some(&a), Some(&b)) => {
            let (a, b) = (lift(a), lift(b));
            (b.0 - a.0) * (q.1 - a.1) - (b.1 - a.1) * (q.0 - a.0) < 0
        }
        _ => false,
    })
}

type Q = (i128, i128);

/// `(g, s, r)` with `a·s + b·r = g = gcd(a, b) ≥ 0` (extended Euclid; ≤ 200 steps for
/// 128-bit inputs, the bound is a safety net).
fn ext_gcd(a: i128, b: i128) -> (i128, i128, i128) {
    let (mut r0, mut r1) = (a, b);
    let (mut s0, mut s1) = (1i128, 0i128);
    let (mut t0, mut t1) = (0i128, 1i128);
    for _ in 0..400 {
        if r1 == 0 {
            break;
        }
        let q = r0.div_euclid(r1);
        (r0, r1) = (r1, r0 - q * r1);
        (s0, s1) = (s1, s0 - q * s1);
        (t0, t1) = (t1, t0 - q * t1);
    }
    if r0 < 0 {
        (-r0, -s0, -t0)
    } else {
        (r0, s0, t0)
    }
}

/// `num / den` rounded to the nearest integer (`den > 0`).
fn round_div(num: i128, den: i128) -> i128 {
    (2 * num + den).div_euclid(2 * den)
}

/// The lattice point one grid step off the line through `a` with direction `d` (on the
/// neighbouring parallel lattice line, to the left for `side = 1`, right for `−1`), near
/// `a + (t_num / t_den)·d`: `cross(d, c − a) = side · gcd(d)`, the smallest non-zero value.
/// `None` for `d = 0`.
fn step_off(a: Q, d: Q, t_num: i128, t_den: i128, side: i128) -> Option<Q> {
    let (g, _, _) = ext_gcd(d.0, d.1);
    if g == 0 {
        return None;
    }
    let (l, m) = (d.0 / g, d.1 / g);
    // l·s + m·r = 1, so w = (−r, s) has cross((l, m), w) = l·s + m·r = 1.
    let (_, s, r) = ext_gcd(l, m);
    let w = (-r * side, s * side);
    // Slide w along (l, m) to the position t·d.
    let norm = l * l + m * m;
    let k = round_div(t_num * g * norm - t_den * (w.0 * l + w.1 * m), t_den * norm);
    Some((a.0 + w.0 + k * l, a.1 + w.1 + k * m))
}

fn lift(v: P) -> Q {
    (i128::from(v.0) << 16, i128::from(v.1) << 16)
}

fn to_p(q: Q) -> Option<P> {
    Some((i64::try_from(q.0).ok()?, i64::try_from(q.1).ok()?))
}

struct Builder {
    /// Raw grid units per design unit.
    step: i64,
    rng: ChaCha8Rng,
    /// Kept polygons, raw coordinates, counter-clockwise.
    polys: Vec<Vec<P>>,
}

impl Builder {
    /// The raw point of design coordinates `(x, y)`.
    fn at(&self, x: i64, y: i64) -> P {
        (x * self.step, y * self.step)
    }

    /// A random raw offset below one design unit.
    fn jitter(&mut self) -> i64 {
        self.rng.gen_range(0..self.step)
    }

    /// The design point `(x, y)` moved by a random raw offset below one design unit.
    fn generic(&mut self, x: i64, y: i64) -> P {
        let p = self.at(x, y);
        (p.0 + self.jitter(), p.1 + self.jitter())
    }

    /// Keeps `p` if strictly convex (after turning it counter-clockwise) and disjoint from
    /// every kept polygon.
    fn add(&mut self, mut p: Vec<P>) -> bool {
        let n = p.len();
        let mut area: i128 = 0;
        for i in 0..n {
            if let (Some(&a), Some(&b)) = (p.get(i), p.get(next(i, n))) {
                area += i128::from(a.0) * i128::from(b.1) - i128::from(b.0) * i128::from(a.1);
            }
        }
        if area < 0 {
            p.reverse();
        }
        if !strictly_convex(&p) || !self.polys.iter().all(|o| disjoint(o, &p)) {
            return false;
        }
        self.polys.push(p);
        true
    }

    /// Keeps all of `ps` or none.
    fn add_all(&mut self, ps: Vec<Vec<P>>) -> bool {
        let before = self.polys.len();
        for p in ps {
            if !self.add(p) {
                self.polys.truncate(before);
                return false;
            }
        }
        true
    }

    /// Cells per side for `n` objects, and the cell size in design units.
    fn cells(n: usize) -> (i64, i64) {
        let mut g: i64 = 1;
        while g * g < n as i64 && g < 64 {
            g += 1;
        }
        (g, ((2 * HALF) / g).max(4))
    }

    /// A random primitive direction `(l, m)` with `l` in `lo..=hi` raw units and
    /// `|m| ≤ slope · l` (at least 1); `None` if none was found.
    fn primitive(&mut self, lo: i64, hi: i64, slope: f64) -> Option<Q> {
        for _ in 0..TRIES {
            let l = self.rng.gen_range(lo.max(1)..=hi.max(lo.max(1)));
            let mmax = ((l as f64 * slope) as i64).max(1);
            let m = self.rng.gen_range(-mmax..=mmax);
            if ext_gcd(i128::from(l), i128::from(m)).0 == 1 {
                return Some((i128::from(l), i128::from(m)));
            }
        }
        None
    }

    /// Viewpoints for `family` (module documentation), at most `count`.
    fn viewpoints(&mut self, family: Family, count: usize) -> Vec<QueryPoint> {
        let mut out: Vec<QueryPoint> = Vec::new();
        let verts: Vec<P> = self.polys.iter().flatten().copied().collect();
        if verts.is_empty() {
            return out;
        }
        for k in 0..count * TRIES {
            if out.len() >= count {
                break;
            }
            let kind = k % 3;
            let exact = kind == 0;
            let candidate = match (family, kind) {
                (_, 2) => Some(self.random_point()),
                (Family::Bitangent, _) => self.on_bitangent(exact),
                (Family::EdgeExtension, _) => self.on_edge_extension(exact),
                _ => {
                    let i = self.rng.gen_range(0..verts.len());
                    let j = self.rng.gen_range(0..verts.len());
                    match (verts.get(i), verts.get(j)) {
                        (Some(&a), Some(&b)) if a != b => {
                            let m = self.rng.gen_range(-6..=10);
                            self.on_line(a, b, m, exact)
                        }
                        _ => None,
                    }
                }
            };
            let Some(q) = candidate else { continue };
            if self.polys.iter().all(|p| outside(p, q)) {
                let point = i64::try_from(q.0)
                    .ok()
                    .zip(i64::try_from(q.1).ok())
                    .and_then(|(x, y)| QueryPoint::from_raw(x, y));
                if let Some(point) = point {
                    if !out.contains(&point) {
                        out.push(point);
                    }
                }
            }
        }
        out
    }

    /// A random query point in the scene's box, with random fractional bits.
    fn random_point(&mut self) -> Q {
        let lim = HALF * self.step;
        let mut c = || {
            (i128::from(self.rng.gen_range(-lim..=lim)) << 16)
                + i128::from(self.rng.gen_range(0..1i64 << 16))
        };
        (c(), c())
    }

    /// A query point near `a + (m/4)(b − a)`: exactly on the line through `a` and `b`, or
    /// one query-grid step off it (to a random side).
    fn on_line(&mut self, a: P, b: P, m: i128, exact: bool) -> Option<Q> {
        let (a, b) = (lift(a), lift(b));
        let d = (b.0 - a.0, b.1 - a.1);
        if exact {
            // Exact: d is a multiple of 2¹⁶.
            Some((a.0 + d.0 * m / 4, a.1 + d.1 * m / 4))
        } else {
            let side = if self.rng.gen_bool(0.5) { 1 } else { -1 };
            step_off(a, d, m, 4, side)
        }
    }

    /// A point on (or one query step off) the line through vertices of two objects that is
    /// tangent to both.
    fn on_bitangent(&mut self, exact: bool) -> Option<Q> {
        let n = self.polys.len();
        if n < 2 {
            return None;
        }
        for _ in 0..TRIES {
            let (i, j) = (self.rng.gen_range(0..n), self.rng.gen_range(0..n));
            let (Some(pa), Some(pb)) = (self.polys.get(i), self.polys.get(j)) else {
                continue;
            };
            if i == j {
                continue;
            }
            let (Some(&a), Some(&b)) = (
                pa.get(self.rng.gen_range(0..pa.len())),
                pb.get(self.rng.gen_range(0..pb.len())),
            ) else {
                continue;
            };
            let tangent = |p: &[P]| {
                let s: Vec<i128> = p.iter().map(|&v| cross(a, b, v).signum()).collect();
                s.iter().all(|&x| x >= 0) || s.iter().all(|&x| x <= 0)
            };
            if tangent(pa) && tangent(pb) {
                let m = self.rng.gen_range(-6..=10);
                if m != 0 && m != 4 {
                    return self.on_line(a, b, m, exact);
                }
            }
        }
        None
    }

    /// A point on (or one query step off) the extension of an edge beyond one of its ends.
    fn on_edge_extension(&mut self, exact: bool) -> Option<Q> {
        let n = self.polys.len();
        let p = self.polys.get(self.rng.gen_range(0..n.max(1)))?;
        let k = self.rng.gen_range(0..p.len().max(1));
        let (&a, &b) = (p.get(k)?, p.get(next(k, p.len()))?);
        let (a, b) = if self.rng.gen_bool(0.5) {
            (a, b)
        } else {
            (b, a)
        };
        // Beyond b: t = m/4 in (1, 3].
        let m = self.rng.gen_range(5..=12);
        self.on_line(a, b, m, exact)
    }
}

/// `collinear` (module documentation): rows of triangles with bases on one lattice line.
fn collinear(b: &mut Builder, n: usize) {
    let (rows, _) = Builder::cells(n);
    let per_row = ((n as i64 + rows - 1) / rows).max(1);
    let gap = (2 * HALF) / rows;
    // Bases of length about 2·HALF / (2·per_row) design units, one per segment of the line.
    let seg = ((2 * HALF) / (2 * per_row)).max(1);
    let mut left = n as i64;
    for row in 0..rows {
        let y = -HALF + row * gap + gap / 2;
        let slope = (gap as f64 / 4.0) / (2.0 * HALF as f64);
        let Some(u) = b.primitive(seg * b.step / 2, seg * b.step, slope) else {
            continue;
        };
        let o = b.generic(-HALF + 1, y);
        let origin = (i128::from(o.0), i128::from(o.1));
        // The number of lattice steps u per base (u may be short at small scales).
        let len = (seg * b.step) as i128;
        let steps = (len / u.0.max(1)).max(1);
        for k in 0..per_row.min(left) {
            let start = 2 * i128::from(k) * steps;
            let a = (origin.0 + start * u.0, origin.1 + start * u.1);
            let c = (a.0 + steps * u.0, a.1 + steps * u.1);
            let h = i128::from((gap / 4).max(1) * b.step);
            let apex_side = if b.rng.gen_bool(0.5) { 1 } else { -1 };
            let apex = ((a.0 + c.0) / 2, (a.1 + c.1) / 2 + apex_side * h);
            // Half the objects one grid step off the line (all three vertices moved).
            let off = if b.rng.gen_bool(0.5) {
                let side = if b.rng.gen_bool(0.5) { 1 } else { -1 };
                step_off((0, 0), u, 0, 1, side)
            } else {
                Some((0, 0))
            };
            let Some(w) = off else { continue };
            let pts: Option<Vec<P>> = [a, c, apex]
                .iter()
                .map(|&(x, y)| to_p((x + w.0, y + w.1)))
                .collect();
            if let Some(pts) = pts {
                if b.add(pts.clone()) {
                    left -= 1;
                } else if w != (0, 0) {
                    // Moving it made it touch a neighbour: keep it on the line.
                    let back: Option<Vec<P>> = [a, c, apex].iter().map(|&v| to_p(v)).collect();
                    if back.is_some_and(|p| b.add(p)) {
                        left -= 1;
                    }
                }
            }
        }
    }
}

/// `unit-gap` (module documentation): each cell holds two triangles one grid step apart.
fn unit_gap(b: &mut Builder, n: usize) {
    let pairs = n.div_ceil(2);
    let (g, c) = Builder::cells(pairs);
    let h = c / 2;
    for cell in 0..pairs as i64 {
        let (cx, cy) = (-HALF + (cell % g) * c + h, -HALF + (cell / g) * c + h);
        for _ in 0..TRIES {
            // The shared line: direction u (axis-parallel a third of the time), `steps`
            // lattice steps of u per base, about half a cell long.
            let len = (h * b.step) as i128;
            let u: Q = match b.rng.gen_range(0..3) {
                0 if b.rng.gen_bool(0.5) => (1, 0),
                0 => (0, 1),
                _ => {
                    let Some((l, m)) = b.primitive(h * b.step / 4, h * b.step / 2, 1.0) else {
                        continue;
                    };
                    if b.rng.gen_bool(0.5) {
                        (l, m)
                    } else {
                        (-m, l)
                    }
                }
            };
            let ulen = u.0.abs().max(u.1.abs()).max(1);
            let steps = (len / ulen).max(1);
            let p = b.generic(cx - h / 2, cy - h / 2);
            let p = (i128::from(p.0), i128::from(p.1));
            let along = |k: i128| (p.0 + k * u.0, p.1 + k * u.1);
            let (a0, a1) = (along(0), along(steps));
            // The apexes: a design-sized step to the right of u, and to the left.
            let dep = i128::from((h / 3).max(1) * b.step);
            let norm = |v: Q| -> Q {
                let m = v.0.abs().max(v.1.abs()).max(1);
                (v.0 * dep / m, v.1 * dep / m)
            };
            let right = norm((u.1, -u.0));
            let mid = ((a0.0 + a1.0) / 2, (a0.1 + a1.1) / 2);
            let apex_r = (mid.0 + right.0, mid.1 + right.1);
            // The second triangle's base on the neighbouring lattice line to the left.
            let Some(w) = step_off((0, 0), u, steps / 2, 1, 1) else {
                continue;
            };
            let (b0, b1) = (
                (a0.0 + w.0 - steps / 4 * u.0, a0.1 + w.1 - steps / 4 * u.1),
                (a1.0 + w.0 - steps / 4 * u.0, a1.1 + w.1 - steps / 4 * u.1),
            );
            let apex_l = ((b0.0 + b1.0) / 2 - right.0, (b0.1 + b1.1) / 2 - right.1);
            let first: Option<Vec<P>> = [a0, a1, apex_r].iter().map(|&v| to_p(v)).collect();
            let second: Option<Vec<P>> = [b0, b1, apex_l].iter().map(|&v| to_p(v)).collect();
            if let (Some(f), Some(s)) = (first, second) {
                if b.add_all(vec![f, s]) {
                    break;
                }
            }
        }
    }
}

/// `sliver` (module documentation): one long thin triangle per row.
fn slivers(b: &mut Builder, n: usize) {
    let rows = n as i64;
    let gap = ((2 * HALF) / rows).max(4);
    for row in 0..rows {
        let yc = -HALF + row * gap + gap / 2;
        let slack = (gap / 2 - 2).max(0);
        for _ in 0..TRIES {
            let xa = b.rng.gen_range(-HALF..=-HALF / 2);
            let xb = b.rng.gen_range(HALF / 2..HALF);
            let (ya, yb) = (
                yc + b.rng.gen_range(-slack..=slack),
                yc + b.rng.gen_range(-slack..=slack),
            );
            let (pa, pb) = (b.generic(xa, ya), b.generic(xb, yb));
            let a = (i128::from(pa.0), i128::from(pa.1));
            let d = (i128::from(pb.0 - pa.0), i128::from(pb.1 - pa.1));
            let side = if b.rng.gen_bool(0.5) { 1 } else { -1 };
            let Some(apex) = step_off(a, d, 1, 2, side).and_then(to_p) else {
                continue;
            };
            if b.add(vec![pa, pb, apex]) {
                break;
            }
        }
    }
}

/// `parallel` (module documentation): rows of thin trapezoids; the top edge `v` of a row
/// has `cross(u, v) = 1` with its bottom edge `u`, and is the next row's bottom edge.
fn parallel(b: &mut Builder, n: usize) {
    let rows = n as i64;
    let gap = ((2 * HALF) / rows).max(4);
    let thick = (gap / 6).clamp(1, 2);
    let (lo, hi) = (200 * b.step, 240 * b.step);
    let mut u: Option<Q> = None;
    for row in 0..rows {
        let y0 = -HALF + row * gap + 1;
        for _ in 0..TRIES {
            let bottom = match u {
                Some(v) if v.0 >= i128::from(lo) / 2 && v.0 <= i128::from(hi) => v,
                // Slopes up to 1/32: both components of u beyond 2²⁶·⁵ at the top of the
                // range, so that the products of cross(u, v) exceed 2⁵³.
                _ => match b.primitive(lo, hi, 1.0 / 32.0) {
                    Some(v) => v,
                    None => continue,
                },
            };
            // v = u + w with cross(u, w) = 1 (w reduced along u): the nearest direction.
            let Some(w) = step_off((0, 0), bottom, 0, 1, 1) else {
                continue;
            };
            let top = (bottom.0 + w.0, bottom.1 + w.1);
            let p = b.generic(-HALF + 2, y0);
            // A falling row starts higher, so that it stays in its band.
            let p = (i128::from(p.0), i128::from(p.1) - bottom.1.min(0));
            let lift_h = i128::from(thick * b.step);
            let bl = p;
            let br = (p.0 + bottom.0, p.1 + bottom.1);
            let tl = (p.0, p.1 + lift_h);
            let tr = (tl.0 + top.0, tl.1 + top.1);
            let quad: Option<Vec<P>> = [bl, br, tr, tl].iter().map(|&v| to_p(v)).collect();
            if quad.is_some_and(|q| b.add(q)) {
                u = Some(top);
                break;
            }
            u = None;
        }
    }
}

/// `bitangent`, `edge-ext`: a random triangle with generic coordinates per cell.
fn triangles(b: &mut Builder, n: usize) {
    let (g, c) = Builder::cells(n);
    for cell in 0..n as i64 {
        let (x0, y0) = (-HALF + (cell % g) * c, -HALF + (cell / g) * c);
        for _ in 0..TRIES {
            let mut r = || {
                let (x, y) = (
                    x0 + 1 + b.rng.gen_range(0..(c - 3).max(1)),
                    y0 + 1 + b.rng.gen_range(0..(c - 3).max(1)),
                );
                b.generic(x, y)
            };
            let poly = vec![r(), r(), r()];
            if b.add(poly) {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_family_and_scale_makes_objects_and_free_viewpoints() {
        for f in Family::ALL {
            for e in SCALES {
                let s = generate(f, e, 12, 8, 1, 0).unwrap();
                assert!(
                    s.polygons.len() >= 6,
                    "{} {e}: {}",
                    f.name(),
                    s.polygons.len()
                );
                assert!(s.viewpoints.len() >= 4, "{} {e}", f.name());
                assert_eq!(
                    s.fingerprint(),
                    generate(f, e, 12, 8, 1, 0).unwrap().fingerprint()
                );
            }
        }
        assert!(generate(Family::Sliver, 15, 4, 4, 1, 0).is_err());
    }

    #[test]
    fn one_grid_step_off_is_the_smallest_determinant() {
        for (d, t) in [
            ((7, 3), (1, 2)),
            ((1 << 30, 3), (5, 4)),
            ((0, 5), (0, 1)),
            ((-12, 18), (3, 1)),
        ] {
            for side in [1, -1] {
                let c = step_off((10, -4), d, t.0, t.1, side).unwrap();
                let w = (c.0 - 10, c.1 + 4);
                let g = ext_gcd(d.0, d.1).0;
                assert_eq!(d.0 * w.1 - d.1 * w.0, side * g, "{d:?} {t:?}");
                // Near t·d: within one step of the line direction.
                let along = (w.0 * d.0 + w.1 * d.1) as f64 / (d.0 * d.0 + d.1 * d.1) as f64;
                assert!(
                    (along - t.0 as f64 / t.1 as f64).abs() <= 1.0,
                    "{d:?} {t:?} {along}"
                );
            }
        }
        assert_eq!(step_off((0, 0), (0, 0), 1, 1, 1), None);
    }

    #[test]
    fn convexity_and_disjointness_are_strict() {
        assert!(strictly_convex(&[(0, 0), (2, 0), (0, 2)]));
        assert!(!strictly_convex(&[(0, 0), (1, 0), (2, 0), (0, 2)]));
        let a = [(0, 0), (2, 0), (0, 2)];
        assert!(!disjoint(&a, &[(2, 0), (4, 0), (4, 2)])); // touching
        assert!(disjoint(&a, &[(3, 0), (4, 0), (4, 2)]));
    }
}
