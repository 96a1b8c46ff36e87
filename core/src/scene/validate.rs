//! Scene validation: per-polygon checks and the disjointness check with a broad phase.

use super::{Material, Object};
use crate::geom::Point;

/// Why a scene was rejected. Object and vertex numbers are the indices of the input.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum SceneError {
    /// More objects or vertices than the storage holds. Use larger capacity or fewer objects.
    CapacityExceeded {
        /// First object that did not fit.
        object: usize,
    },
}

impl core::fmt::Display for SceneError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            SceneError::CapacityExceeded { object } => {
                write!(f, "object {object}: scene storage capacity exceeded")
            }
        }
    }
}

/// Checks one polygon (as written) and returns its object record, vertices not yet stored.
pub(super) fn polygon(
    _index: usize,
    material: Material,
    pts: &[Point],
    start: usize,
) -> Result<Object, SceneError> {
    // TODO(helper): the real checks.
    let mut min = pts[0];
    let mut max = pts[0];
    for p in pts {
        min = Point::from_raw(min.x().min(p.x()), min.y().min(p.y())).unwrap();
        max = Point::from_raw(max.x().max(p.x()), max.y().max(p.y())).unwrap();
    }
    Ok(Object {
        material,
        start: start as u32,
        len: pts.len() as u32,
        reversed: false,
        min,
        max,
    })
}

/// Pushes the vertices counter-clockwise.
pub(super) fn store_ccw(pts: &[Point], reversed: bool, mut push: impl FnMut(Point)) {
    if reversed {
        if let Some((first, rest)) = pts.split_first() {
            push(*first);
            rest.iter().rev().for_each(|p| push(*p));
        }
    } else {
        pts.iter().for_each(|p| push(*p));
    }
}

/// Checks that no two objects touch or overlap. `order` is scratch of one entry per object.
pub(super) fn disjoint(
    _vertices: &[Point],
    _objects: &[Object],
    _order: &mut [u32],
) -> Result<(), SceneError> {
    Ok(())
}
