//! Points on the fixed-point grid of scene coordinates, and query points on a finer grid.

use fixed::types::I16F16;

/// Fractional bits of scene coordinates: the grid unit is 2⁻¹⁶ scene units.
pub const FRAC_BITS: u32 = 16;

/// Largest absolute raw scene coordinate, 2³⁰ − 1 grid units (just under 16384.0).
///
/// Why: a coordinate difference then fits in 31 bits plus sign, a product of two
/// differences in 62 bits, and a 2×2 determinant of differences in 63 bits — so every
/// scene predicate is exact in `i64` (see the bit budgets in [`crate::geom::predicates`]).
pub const MAX_ABS_RAW: i32 = (1 << 30) - 1;

/// Fractional bits of query points (viewpoints, virtual viewpoints): 16 more than scene
/// coordinates, so a scene point converts exactly and reflected viewpoints keep precision.
pub const QUERY_FRAC_BITS: u32 = 32;

/// Largest absolute raw query coordinate, 2⁵² (2²⁰ = 1 048 576 scene units).
///
/// Why: virtual viewpoints (reflections, refraction) may leave the scene's box; with this
/// bound a difference fits in 54 bits and a 2×2 determinant in 109 bits, exact in `i128`.
pub const QUERY_MAX_ABS_RAW: i64 = 1 << 52;

/// Largest absolute component of a direction vector given to the query predicates (2⁵²).
pub const MAX_ABS_DIRECTION: i64 = 1 << 52;

/// A vertex position on the scene grid: raw `i32` in units of 2⁻¹⁶ ([`I16F16`]),
/// with `|raw| ≤` [`MAX_ABS_RAW`] on both axes.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Point {
    x: i32,
    y: i32,
}

/// Why a coordinate could not be put on the grid.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum CoordinateError {
    /// NaN or infinite.
    NotFinite,
    /// Outside `±MAX_ABS_RAW` grid units (about ±16384 scene units).
    OutOfRange,
}

impl Point {
    /// A point from raw grid coordinates; `None` if outside the range.
    pub const fn from_raw(x: i32, y: i32) -> Option<Point> {
        if x.unsigned_abs() > MAX_ABS_RAW as u32 || y.unsigned_abs() > MAX_ABS_RAW as u32 {
            None
        } else {
            Some(Point { x, y })
        }
    }

    /// A point from fixed-point coordinates; `None` if outside the range.
    pub fn from_fixed(x: I16F16, y: I16F16) -> Option<Point> {
        Point::from_raw(x.to_bits(), y.to_bits())
    }

    /// The grid point nearest to `(x, y)` (ties away from zero), and whether rounding
    /// moved it.
    pub fn from_f64(x: f64, y: f64) -> Result<(Point, bool), CoordinateError> {
        let (rx, mx) = coord_from_f64(x)?;
        let (ry, my) = coord_from_f64(y)?;
        Ok((Point { x: rx, y: ry }, mx || my))
    }

    /// Raw x in grid units.
    #[inline]
    pub const fn x(self) -> i32 {
        self.x
    }

    /// Raw y in grid units.
    #[inline]
    pub const fn y(self) -> i32 {
        self.y
    }

    /// x as a fixed-point number.
    pub fn x_fixed(self) -> I16F16 {
        I16F16::from_bits(self.x)
    }

    /// y as a fixed-point number.
    pub fn y_fixed(self) -> I16F16 {
        I16F16::from_bits(self.y)
    }

    /// Coordinates in scene units, for output only.
    pub fn to_f64(self) -> (f64, f64) {
        (
            raw_to_f64(self.x as i64, FRAC_BITS),
            raw_to_f64(self.y as i64, FRAC_BITS),
        )
    }

    /// The same point on the query grid (exact).
    pub const fn to_query(self) -> QueryPoint {
        QueryPoint {
            x: (self.x as i64) << (QUERY_FRAC_BITS - FRAC_BITS),
            y: (self.y as i64) << (QUERY_FRAC_BITS - FRAC_BITS),
        }
    }
}

fn coord_from_f64(v: f64) -> Result<(i32, bool), CoordinateError> {
    if !v.is_finite() {
        return Err(CoordinateError::NotFinite);
    }
    let scaled = v * (1u64 << FRAC_BITS) as f64; // exact: a power-of-two scale
    let r = libm::round(scaled);
    if r.is_nan() || r.abs() > MAX_ABS_RAW as f64 {
        return Err(CoordinateError::OutOfRange);
    }
    Ok((r as i32, r != scaled))
}

pub(crate) fn raw_to_f64(raw: i64, frac_bits: u32) -> f64 {
    raw as f64 / (1u64 << frac_bits) as f64
}

/// A query point (viewpoint, virtual viewpoint, ray origin) on the finer query grid:
/// raw `i64` in units of 2⁻³², `|raw| ≤` [`QUERY_MAX_ABS_RAW`].
///
/// Query predicates run in `i128`. Under the symbolic perturbation a query point is
/// perturbed more than any scene vertex (rank 0, see [`crate::geom::sos`]).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct QueryPoint {
    x: i64,
    y: i64,
}

impl QueryPoint {
    /// The origin (a `const` [`Default`]).
    pub(crate) const ORIGIN: QueryPoint = QueryPoint { x: 0, y: 0 };

    /// A query point from raw coordinates (units of 2⁻³²); `None` if outside the range.
    pub const fn from_raw(x: i64, y: i64) -> Option<QueryPoint> {
        if x.unsigned_abs() > QUERY_MAX_ABS_RAW as u64
            || y.unsigned_abs() > QUERY_MAX_ABS_RAW as u64
        {
            None
        } else {
            Some(QueryPoint { x, y })
        }
    }

    /// The query-grid point nearest to `(x, y)` in scene units.
    pub fn from_f64(x: f64, y: f64) -> Result<QueryPoint, CoordinateError> {
        let conv = |v: f64| -> Result<i64, CoordinateError> {
            if !v.is_finite() {
                return Err(CoordinateError::NotFinite);
            }
            let r = libm::round(v * (1u64 << QUERY_FRAC_BITS) as f64);
            if r.is_nan() || r.abs() > QUERY_MAX_ABS_RAW as f64 {
                return Err(CoordinateError::OutOfRange);
            }
            Ok(r as i64)
        };
        Ok(QueryPoint {
            x: conv(x)?,
            y: conv(y)?,
        })
    }

    /// Raw x in units of 2⁻³².
    #[inline]
    pub const fn x(self) -> i64 {
        self.x
    }

    /// Raw y in units of 2⁻³².
    #[inline]
    pub const fn y(self) -> i64 {
        self.y
    }

    /// Coordinates in scene units, for output only.
    pub fn to_f64(self) -> (f64, f64) {
        (
            raw_to_f64(self.x, QUERY_FRAC_BITS),
            raw_to_f64(self.y, QUERY_FRAC_BITS),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_is_enforced() {
        assert!(Point::from_raw(MAX_ABS_RAW, -MAX_ABS_RAW).is_some());
        assert!(Point::from_raw(MAX_ABS_RAW + 1, 0).is_none());
        assert!(Point::from_raw(0, i32::MIN).is_none());
        assert!(QueryPoint::from_raw(QUERY_MAX_ABS_RAW, -QUERY_MAX_ABS_RAW).is_some());
        assert!(QueryPoint::from_raw(i64::MIN, 0).is_none());
    }

    #[test]
    fn f64_conversion_rounds_and_reports() {
        assert_eq!(
            Point::from_f64(1.5, -2.0),
            Ok((Point::from_raw(3 << 15, -2 << 16).unwrap(), false))
        );
        let (p, moved) = Point::from_f64(0.1, 0.0).unwrap();
        assert!(moved);
        assert_eq!(p.x(), 6554);
        assert_eq!(
            Point::from_f64(f64::NAN, 0.0),
            Err(CoordinateError::NotFinite)
        );
        assert_eq!(
            Point::from_f64(0.0, f64::INFINITY),
            Err(CoordinateError::NotFinite)
        );
        assert_eq!(
            Point::from_f64(16384.0, 0.0),
            Err(CoordinateError::OutOfRange)
        );
        assert!(Point::from_f64(16383.99, 0.0).is_ok());
        assert_eq!(Point::from_raw(5, 7).unwrap().to_query().x(), 5 << 16);
    }
}
