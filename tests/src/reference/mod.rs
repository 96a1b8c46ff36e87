//! Exact brute-force reference: shared number type, scene conversion and result types.
//!
//! Units: scene coordinates are `raw / 2^16` ([`vcx::Point`]), query points `raw / 2^32`
//! ([`vcx::QueryPoint`]); both convert exactly to [`Vec2`]. A *direction* is any non-zero
//! vector; results report directions as primitive integer vectors (see
//! [`Vec2::primitive`]) so that equal directions compare equal with `==`.

mod bitangents;
mod ray_tree;
mod shoot;
mod sos;
mod view;

pub use bitangents::{free_bitangents, Bitangent, Bitangents};
pub use ray_tree::{trace_ray, Hit, RayTreeOptions, Stage, Trace};
pub use shoot::{shoot, shoot_perturbed, RayObjects};
pub use sos::{scene_orient, sos_orient};
pub use view::{ray_tree, view, TreeInterval, ViewInterval};

use core::cmp::Ordering;
use core::fmt;

use num_bigint::BigInt;
use num_integer::Integer;
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};
use vcx::{Material, ObjectId, Point, QueryPoint, SceneRef};

/// An exact rational point or vector.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub struct Vec2 {
    /// x in scene units.
    pub x: BigRational,
    /// y in scene units.
    pub y: BigRational,
}

fn q(v: i64) -> BigRational {
    BigRational::from_integer(BigInt::from(v))
}

fn pow2(bits: u32) -> BigRational {
    BigRational::from_integer(BigInt::one() << bits)
}

impl Vec2 {
    /// A vector from rational coordinates.
    pub fn new(x: BigRational, y: BigRational) -> Vec2 {
        Vec2 { x, y }
    }

    /// A vector with integer coordinates in scene units.
    pub fn from_i64(x: i64, y: i64) -> Vec2 {
        Vec2::new(q(x), q(y))
    }

    /// `(xn/xd, yn/yd)` in scene units. Panics if a denominator is zero.
    pub fn from_ratios(xn: i64, xd: i64, yn: i64, yd: i64) -> Vec2 {
        Vec2::new(
            BigRational::new(xn.into(), xd.into()),
            BigRational::new(yn.into(), yd.into()),
        )
    }

    /// A scene point, exactly (`raw / 2^16`).
    pub fn from_point(p: Point) -> Vec2 {
        let s = pow2(vcx::geom::point::FRAC_BITS);
        Vec2::new(q(p.x().into()) / &s, q(p.y().into()) / &s)
    }

    /// A query point, exactly (`raw / 2^32`).
    pub fn from_query(p: QueryPoint) -> Vec2 {
        let s = pow2(vcx::geom::point::QUERY_FRAC_BITS);
        Vec2::new(q(p.x()) / &s, q(p.y()) / &s)
    }

    /// The nearest point of the query grid (multiples of 2^-32 per coordinate, ties away
    /// from zero) — how the core stores virtual viewpoints.
    pub fn round_to_query_grid(&self) -> Vec2 {
        let s = pow2(vcx::geom::point::QUERY_FRAC_BITS);
        // `Ratio::round` rounds half-way cases away from zero.
        Vec2::new((&self.x * &s).round() / &s, (&self.y * &s).round() / &s)
    }

    /// Whether both coordinates are zero.
    pub fn is_zero(&self) -> bool {
        self.x.is_zero() && self.y.is_zero()
    }

    /// `self + o`.
    pub fn add(&self, o: &Vec2) -> Vec2 {
        Vec2::new(&self.x + &o.x, &self.y + &o.y)
    }

    /// `self - o`.
    pub fn sub(&self, o: &Vec2) -> Vec2 {
        Vec2::new(&self.x - &o.x, &self.y - &o.y)
    }

    /// `k · self`.
    pub fn scale(&self, k: &BigRational) -> Vec2 {
        Vec2::new(&self.x * k, &self.y * k)
    }

    /// `-self`.
    pub fn neg(&self) -> Vec2 {
        Vec2::new(-&self.x, -&self.y)
    }

    /// Rotated by +90°: `(-y, x)`.
    pub fn rot90(&self) -> Vec2 {
        Vec2::new(-&self.y, self.x.clone())
    }

    /// `self.x · o.y − self.y · o.x` (positive if `o` is counter-clockwise of `self`).
    pub fn cross(&self, o: &Vec2) -> BigRational {
        &self.x * &o.y - &self.y * &o.x
    }

    /// Dot product.
    pub fn dot(&self, o: &Vec2) -> BigRational {
        &self.x * &o.x + &self.y * &o.y
    }

    /// The same direction as a primitive integer vector (gcd of the coordinates 1);
    /// zero stays zero. Two non-zero vectors point the same way iff their primitive
    /// vectors are equal.
    pub fn primitive(&self) -> Vec2 {
        if self.is_zero() {
            return self.clone();
        }
        let l = self.x.denom().lcm(self.y.denom());
        let xi = self.x.numer() * (&l / self.x.denom());
        let yi = self.y.numer() * (&l / self.y.denom());
        let g = xi.gcd(&yi);
        Vec2::new(
            BigRational::from_integer(xi / &g),
            BigRational::from_integer(yi / &g),
        )
    }

    /// Coordinates as floats, for output.
    pub fn to_f64(&self) -> (f64, f64) {
        let f = |v: &BigRational| v.to_f64().unwrap_or(f64::NAN);
        (f(&self.x), f(&self.y))
    }

    /// The direction's angle in `[0, 2π)` counter-clockwise from +x, for output only.
    pub fn angle(&self) -> f64 {
        let p = self.primitive();
        let (mut x, mut y) = (p.x.to_integer(), p.y.to_integer());
        let bits = x.bits().max(y.bits());
        if bits > 60 {
            x >>= bits - 60;
            y >>= bits - 60;
        }
        let a = y.to_f64().unwrap_or(0.0).atan2(x.to_f64().unwrap_or(0.0));
        let tau = core::f64::consts::TAU;
        let a = if a < 0.0 { a + tau } else { a };
        if a >= tau {
            f64::from_bits(tau.to_bits() - 1)
        } else {
            a
        }
    }
}

impl fmt::Display for Vec2 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", self.x, self.y)
    }
}

/// Why the reference refused a query.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum RefError {
    /// The viewpoint lies inside or on the boundary of this object (the lowest such id).
    ViewpointNotFree {
        /// The object containing the viewpoint.
        object: ObjectId,
    },
    /// The ray direction is the zero vector.
    ZeroDirection,
    /// With eyes rounded to the query grid, a rounded virtual eye fell on or across the
    /// interface line it was built from, so the optics is undefined (exact optics never
    /// does this). `level` is the depth level of the interaction.
    DegenerateOptics {
        /// Depth level of the mirror or refractive object.
        level: usize,
    },
}

impl fmt::Display for RefError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RefError::ViewpointNotFree { object } => {
                write!(f, "viewpoint is not free: it lies in object {}", object.0)
            }
            RefError::ZeroDirection => write!(f, "ray direction is zero"),
            RefError::DegenerateOptics { level } => {
                write!(f, "rounded virtual eye is degenerate at level {level}")
            }
        }
    }
}

/// A vertex as the user sees it: object id and the vertex's index as written in the input.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct VertexRef {
    /// The object.
    pub object: ObjectId,
    /// Index of the vertex in the object's input list (`Object::written_vertex_id`).
    pub vertex: usize,
}

/// One angular interval of a sweep around a viewpoint, counter-clockwise from `start` to
/// `end`. Over the open interval the result `value` is constant.
#[derive(Clone, PartialEq, Debug)]
pub struct Interval<T> {
    /// Start direction (primitive integer vector). Equal to `end` only for the single
    /// full-circle interval of a sweep without boundaries; then it is `(1, 0)`.
    pub start: Vec2,
    /// End direction = start of the next interval.
    pub end: Vec2,
    /// Angle of `start` in `[0, 2π)`, for printing.
    pub start_angle: f64,
    /// Angle of `end` in `[0, 2π)`, for printing.
    pub end_angle: f64,
    /// What is seen over the interval.
    pub value: T,
    /// The vertex that causes the start boundary (`None` only for the full circle).
    pub start_vertex: Option<VertexRef>,
}

/// A scene object converted to exact rationals.
#[derive(Clone, Debug)]
pub(crate) struct RObject {
    pub id: ObjectId,
    pub material: Material,
    /// Counter-clockwise vertices.
    pub poly: Vec<Vec2>,
    /// Global index of the first vertex in `SceneRef::vertices()` (rank − 1 in the SoS).
    pub first: usize,
    /// Written vertex id of each counter-clockwise vertex.
    pub written: Vec<usize>,
}

impl RObject {
    /// The directed edge `k`: from ccw vertex `k` to vertex `k + 1`.
    pub fn edge(&self, k: usize) -> (&Vec2, &Vec2) {
        (&self.poly[k], &self.poly[(k + 1) % self.poly.len()])
    }

    pub fn vertex_ref(&self, k: usize) -> VertexRef {
        VertexRef {
            object: self.id,
            vertex: self.written[k],
        }
    }

    pub fn is_screen(&self) -> bool {
        self.material == Material::Screen
    }

    /// Whether `p` lies in the closed polygon (left of or on every ccw edge).
    pub fn contains(&self, p: &Vec2) -> bool {
        (0..self.poly.len()).all(|k| {
            let (a, b) = self.edge(k);
            !b.sub(a).cross(&p.sub(a)).is_negative()
        })
    }
}

/// The scene's objects in exact rationals.
pub(crate) fn objects(scene: SceneRef<'_>) -> Vec<RObject> {
    scene
        .objects()
        .iter()
        .enumerate()
        .map(|(i, o)| RObject {
            id: ObjectId(i as u32),
            material: o.material,
            poly: scene
                .polygon(o)
                .iter()
                .map(|p| Vec2::from_point(*p))
                .collect(),
            first: o.first_vertex(),
            written: (0..o.len()).map(|k| o.written_vertex_id(k)).collect(),
        })
        .collect()
}

/// `Ok` if `p` is outside every closed object (screens included).
pub(crate) fn check_free(objs: &[RObject], p: &Vec2) -> Result<(), RefError> {
    match objs.iter().find(|o| o.contains(p)) {
        Some(o) => Err(RefError::ViewpointNotFree { object: o.id }),
        None => Ok(()),
    }
}

/// The parameter range of the line `o + t·d` inside a closed convex polygon.
#[derive(Clone, Debug)]
pub(crate) struct Chord {
    pub t_in: BigRational,
    pub t_out: BigRational,
    /// The edge whose half-plane bounds `t_in` (the entry edge).
    pub edge_in: usize,
    /// The edge whose half-plane bounds `t_out` (the exit edge).
    pub edge_out: usize,
}

/// Clips the line `o + t·d` (`d ≠ 0`) by the half-planes of the ccw polygon: edge `ab`
/// keeps the points `p` with `cross(b − a, p − a) ≥ 0`. `None` if the line misses the
/// closed polygon. When a vertex binds (two edges give the same bound) the first edge in
/// ccw order is reported.
pub(crate) fn chord(poly: &[Vec2], o: &Vec2, d: &Vec2) -> Option<Chord> {
    let (mut lower, mut upper) = (Vec::new(), Vec::new());
    for k in 0..poly.len() {
        let (a, b) = (&poly[k], &poly[(k + 1) % poly.len()]);
        let e = b.sub(a);
        let c0 = e.cross(&o.sub(a));
        let c1 = e.cross(d);
        if c1.is_zero() {
            if c0.is_negative() {
                return None;
            }
            continue;
        }
        // c0 + t·c1 ≥ 0  ⇔  t ≥ t0 (c1 > 0) or t ≤ t0 (c1 < 0).
        let t0 = -c0 / &c1;
        if c1.is_positive() {
            lower.push((t0, k));
        } else {
            upper.push((t0, k));
        }
    }
    // A bounded polygon bounds every non-zero direction on both sides. (`max_by` keeps the
    // last maximum, hence `rev`: ties go to the first edge.)
    let (t_in, edge_in) = lower.into_iter().rev().max_by(|a, b| a.0.cmp(&b.0))?;
    let (t_out, edge_out) = upper.into_iter().min_by(|a, b| a.0.cmp(&b.0))?;
    (t_in <= t_out).then_some(Chord {
        t_in,
        t_out,
        edge_in,
        edge_out,
    })
}

/// The intersection of the line through `p` with direction `d` and the line `ab`;
/// `None` if they are parallel.
pub(crate) fn line_intersection(p: &Vec2, d: &Vec2, a: &Vec2, b: &Vec2) -> Option<Vec2> {
    let e = b.sub(a);
    let den = e.cross(d);
    if den.is_zero() {
        return None;
    }
    // cross(e, p + t·d − a) = 0.
    let t = e.cross(&a.sub(p)) / den;
    Some(p.add(&d.scale(&t)))
}

/// Which half of the circle a direction is in: 0 for angles in `[0, π)`, 1 for `[π, 2π)`.
fn half(v: &Vec2) -> u8 {
    if v.y.is_positive() || (v.y.is_zero() && v.x.is_positive()) {
        0
    } else {
        1
    }
}

/// Order of two non-zero directions by angle in `[0, 2π)` counter-clockwise from +x:
/// half-plane first, then the cross product. `Equal` iff they point the same way.
pub fn cmp_angle(a: &Vec2, b: &Vec2) -> Ordering {
    half(a).cmp(&half(b)).then_with(|| {
        let c = a.cross(b);
        if c.is_positive() {
            Ordering::Less
        } else if c.is_negative() {
            Ordering::Greater
        } else {
            Ordering::Equal
        }
    })
}

/// Order of two directions by angle counter-clockwise from `base`, in `[0, 2π)`.
pub(crate) fn cmp_from(base: &Vec2, a: &Vec2, b: &Vec2) -> Ordering {
    // (dot, cross) is the vector rotated by −angle(base) (and scaled by |base|).
    let rel = |v: &Vec2| Vec2::new(base.dot(v), base.cross(v));
    cmp_angle(&rel(a), &rel(b))
}

/// Whether direction `d` lies strictly inside the open counter-clockwise arc from `lo` to
/// `hi` (all primitive). `lo == hi` means the full circle minus `lo`.
pub(crate) fn strictly_inside(lo: &Vec2, hi: &Vec2, d: &Vec2) -> bool {
    if d == lo || d == hi {
        return false;
    }
    lo == hi || cmp_from(lo, d, hi) == Ordering::Less
}

/// One direction strictly inside the open arc from `lo` to `hi` (primitive): `lo + hi` if
/// the arc is shorter than π, otherwise `lo` rotated by +90°.
pub(crate) fn arc_sample(lo: &Vec2, hi: &Vec2) -> Vec2 {
    if lo != hi && lo.cross(hi).is_positive() {
        lo.add(hi).primitive()
    } else {
        lo.rot90()
    }
}
