//! Forward and backward object of a ray from a free point, exact and perturbed.
//!
//! **Perturbed variant.** The core breaks ties with Simulation of Simplicity; a query point
//! has rank 0, perturbed by `(ε, ε²)`, which dominates the perturbation of every scene
//! vertex (ranks ≥ 1 move by `ε⁴` or less). So the perturbed answer is the exact answer for
//! `q' = q + (ε, ε²)`, ε > 0 infinitesimal. For a vertex `v`,
//!
//! ```text
//! cross(d, v − q') = cross(d, v − q) + d.y·ε − d.x·ε²    (c0, c1, c2; c3 = 0)
//! ```
//!
//! whose sign is that of the first non-zero coefficient — never zero since `d ≠ 0`, which
//! is also why the vertices' own (smaller) perturbations never matter. An object is crossed
//! by the perturbed line iff it has vertices strictly on both sides. A crossed object's
//! exact chord is non-empty (the limit line meets the closed polygon) and does not contain
//! `q` (q is free, at positive distance), so "ahead" is `t_in > 0` exactly. Chords of
//! disjoint closed objects on one line are disjoint closed intervals, so their exact order
//! is also the perturbed order: the nearest crossed object ahead is the answer.

use num_traits::{Signed, Zero};
use vcx::{ObjectId, SceneRef};

use super::{check_free, chord, objects, RObject, RefError, Vec2};

/// The objects a line through a point meets first on either side of it.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct RayObjects {
    /// Nearest object along `d` (screens count).
    pub forward: Option<ObjectId>,
    /// Nearest object along `−d`.
    pub backward: Option<ObjectId>,
}

/// Exact forward and backward objects of the ray from the free point `q` with direction
/// `d`: the nearest objects (screens included) whose closed polygon meets the ray at
/// `t > 0` along `d`, respectively `−d`.
pub fn shoot(scene: SceneRef<'_>, q: &Vec2, d: &Vec2) -> Result<RayObjects, RefError> {
    shoot_with(scene, q, d, |_, _| true)
}

/// The same under the core's symbolic perturbation, i.e. for `q + (ε, ε²)` (module
/// documentation): a line that only touches an object (at a vertex or along an edge) either
/// crosses it or misses it.
pub fn shoot_perturbed(scene: SceneRef<'_>, q: &Vec2, d: &Vec2) -> Result<RayObjects, RefError> {
    shoot_with(scene, q, d, |o, d| crossed(o, q, d))
}

fn shoot_with(
    scene: SceneRef<'_>,
    q: &Vec2,
    d: &Vec2,
    counts: impl Fn(&RObject, &Vec2) -> bool,
) -> Result<RayObjects, RefError> {
    if d.is_zero() {
        return Err(RefError::ZeroDirection);
    }
    let objs = objects(scene);
    check_free(&objs, q)?;
    let first = |d: &Vec2| {
        objs.iter()
            .filter(|o| counts(o, d))
            .filter_map(|o| Some((o.id, chord(&o.poly, q, d)?.t_in)))
            .filter(|(_, t)| t.is_positive())
            .min_by(|a, b| a.1.cmp(&b.1))
            .map(|(id, _)| id)
    };
    Ok(RayObjects {
        forward: first(d),
        backward: first(&d.neg()),
    })
}

/// Whether the line through `q + (ε, ε²)` with direction `d` has vertices of `o` strictly on
/// both sides.
fn crossed(o: &RObject, q: &Vec2, d: &Vec2) -> bool {
    let sign = |v: &Vec2| {
        let coeffs = [d.cross(&v.sub(q)), d.y.clone(), -&d.x];
        coeffs
            .into_iter()
            .find(|c| !c.is_zero())
            .map_or(0, |c| if c.is_positive() { 1 } else { -1 })
    };
    let signs: Vec<i8> = o.poly.iter().map(sign).collect();
    signs.contains(&1) && signs.contains(&-1)
}
