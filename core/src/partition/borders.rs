//! Adjacency across primary walls: for every chain, the cylinders bordering it from above
//! and from below, in θ order. Each list tiles the whole circle of directions once: below
//! a lower chain (and above an upper chain) lies one layer, the one in which the chain's
//! object is not crossed; on the other side lie two, before and after the object in t.

use alloc::vec::Vec;
use core::cmp::Ordering;

use super::{Complex, Cylinder, CylinderId, Wall};
use crate::geom::sos::Angle;
use crate::line_space::Chain;
use crate::scene::SceneRef;

/// Which side of a chain a cylinder lies on.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Side {
    /// The chain is the cylinder's top arc.
    Below,
    /// The chain is the cylinder's bottom arc.
    Above,
}

/// Where a bordering cylinder's free segments lie relative to the chain's object.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Layer {
    /// The object is not crossed on this side of the chain.
    Around,
    /// Segments ending at the object (its ceiling is the object).
    Before,
    /// Segments starting at the object (its floor is the object).
    After,
}

impl Layer {
    fn of(c: &Cylinder, chain: Chain) -> Layer {
        if c.ceiling == Some(chain.object) {
            Layer::Before
        } else if c.floor == Some(chain.object) {
            Layer::After
        } else {
            Layer::Around
        }
    }
}

/// Derived lookup state of a complex, rebuilt from its cylinders and vertices (never
/// trusted from a file): the angle of every vertex, and for every chain, side and layer the
/// bordering cylinders sorted by θ, addressed by an index (no map on the walk's hot path).
#[derive(Clone, Debug, Default)]
pub(crate) struct Borders {
    /// θ of every vertex, in vertex order.
    pub(crate) angles: Vec<Angle>,
    /// `tilings[slot(chain, side, layer)]`: cylinders sorted by θ.
    tilings: Vec<Vec<CylinderId>>,
    /// For every cylinder, its bottom (`[0]`) and top (`[1]`) arc, and each of the (at most
    /// two) layers on the far side of that arc: the index, in the far side's tiling, of the
    /// cylinder containing this cylinder's left wall. A walk leaving the cylinder across
    /// the arc scans forward from there.
    start: Vec<[[u32; 2]; 2]>,
}

/// Index of a (chain, side, layer) tiling: 12 slots per object.
fn slot(chain: Chain, side: Side, layer: Layer) -> usize {
    let bound = match chain.bound {
        crate::line_space::Bound::Lower => 0,
        crate::line_space::Bound::Upper => 1,
    };
    let side = match side {
        Side::Below => 0,
        Side::Above => 1,
    };
    let layer = match layer {
        Layer::Around => 0,
        Layer::Before => 1,
        Layer::After => 2,
    };
    ((chain.object.0 as usize * 2 + bound) * 2 + side) * 3 + layer
}

pub(crate) fn build(scene: &SceneRef<'_>, complex: &Complex) -> Borders {
    let angles: Vec<Angle> = complex
        .vertices
        .iter()
        .map(|v| v.bitangent.angle(scene))
        .collect();
    let mut tilings: Vec<Vec<CylinderId>> = alloc::vec![Vec::new(); 12 * scene.len()];
    for (i, c) in complex.cylinders.iter().enumerate() {
        let id = CylinderId(i as u32);
        for (chain, side) in [(c.top, Side::Below), (c.bottom, Side::Above)] {
            if let Some(t) = chain.and_then(|ch| tilings.get_mut(slot(ch, side, Layer::of(c, ch))))
            {
                t.push(id);
            }
        }
    }
    // Vertices are sorted by θ (an invariant `validate` checks), so a wall's position in θ
    // is its vertex index, θ = 0 first: sorting and merging compare integers.
    let left = |id: &CylinderId| {
        complex
            .cylinders
            .get(id.index())
            .map_or(0, |c| wall_rank(c.left))
    };
    for list in &mut tilings {
        list.sort_by_key(left);
    }
    let mut start = alloc::vec![[[0u32; 2]; 2]; complex.cylinders.len()];
    // For every chain, merge each tiling with the tilings across the chain: both are sorted
    // by left wall, so one pass finds, for every cylinder, the far cylinder containing its
    // left wall.
    for object in 0..scene.len() {
        for bound in [
            crate::line_space::Bound::Lower,
            crate::line_space::Bound::Upper,
        ] {
            let chain = Chain {
                object: crate::scene::ObjectId(object as u32),
                bound,
            };
            // Cylinders above the chain leave it through their bottom (arc 0) to the side
            // below, and conversely.
            for (own_side, arc, far_side) in
                [(Side::Above, 0, Side::Below), (Side::Below, 1, Side::Above)]
            {
                for own_layer in far_layers(chain, own_side) {
                    let Some(own) = tilings.get(slot(chain, own_side, own_layer)) else {
                        continue;
                    };
                    for (l, far_layer) in far_layers(chain, far_side).into_iter().enumerate() {
                        let Some(far) = tilings.get(slot(chain, far_side, far_layer)) else {
                            continue;
                        };
                        let mut j = 0;
                        for id in own {
                            let l_own = left(id);
                            while far.get(j + 1).is_some_and(|f| left(f) <= l_own) {
                                j += 1;
                            }
                            if let Some(e) = start.get_mut(id.index()) {
                                e[arc][l] = j as u32;
                            }
                        }
                    }
                }
            }
        }
    }
    Borders {
        angles,
        tilings,
        start,
    }
}

/// The position of a wall in θ order: θ = 0 first, then by vertex (vertices are sorted).
fn wall_rank(w: Wall) -> usize {
    match w {
        Wall::Zero => 0,
        Wall::Vertex(v) => v.index() + 1,
    }
}

/// The layers on side `side` of `chain`: two (before and after the object) where the
/// object is crossed, one otherwise.
fn far_layers(chain: Chain, side: Side) -> heapless::Vec<Layer, 2> {
    let crossed = match chain.bound {
        crate::line_space::Bound::Lower => Side::Above,
        crate::line_space::Bound::Upper => Side::Below,
    };
    let mut out = heapless::Vec::new();
    if side == crossed {
        let _ = out.push(Layer::Before);
        let _ = out.push(Layer::After);
    } else {
        let _ = out.push(Layer::Around);
    }
    out
}

impl Complex {
    /// Leaving cylinder `from` across its bottom (`side` = `Below`) or top (`Above`) arc at
    /// `angle` (within `from`'s θ-range), the cylinder entered in `layer`. Looks near the
    /// position of `from` along the chain instead of searching the whole chain: the
    /// cylinders on both sides of a chain are sorted by θ, and the one entered overlaps
    /// `from`, so the scan is short.
    pub fn across_from(
        &self,
        scene: &SceneRef<'_>,
        from: CylinderId,
        side: Side,
        layer: Layer,
        angle: &Angle,
    ) -> Option<CylinderId> {
        let c = self.cylinders.get(from.index())?;
        let (chain, arc) = match side {
            Side::Below => (c.bottom?, 0),
            Side::Above => (c.top?, 1),
        };
        let l = far_layers(chain, side).iter().position(|&x| x == layer)?;
        let list = self.borders.tilings.get(slot(chain, side, layer))?;
        let first = *self.borders.start.get(from.index())?.get(arc)?.get(l)? as usize;
        // The far cylinders overlapping `from` follow each other from `first`.
        for id in list.iter().skip(first) {
            let f = self.cylinders.get(id.index())?;
            let before_right = match f.right {
                Wall::Zero => true,
                w => angle.cmp_angle(&self.wall_angle(scene, w)?) == Ordering::Less,
            };
            if before_right {
                return Some(*id);
            }
        }
        None
    }

    /// The cylinder bordering `chain` on `side` in `layer` whose θ-range contains `angle`.
    pub fn across(
        &self,
        scene: &SceneRef<'_>,
        chain: Chain,
        side: Side,
        layer: Layer,
        angle: &Angle,
    ) -> Option<CylinderId> {
        let list = self.borders.tilings.get(slot(chain, side, layer))?;
        let before = |w: Wall| match w {
            Wall::Zero => true,
            Wall::Vertex(_) => self
                .wall_angle(scene, w)
                .is_some_and(|l| l.cmp_angle(angle) == Ordering::Less),
        };
        // The last cylinder whose left wall lies before `angle` (θ = 0 lies before all).
        let k = list.partition_point(|&id| {
            self.cylinders
                .get(id.index())
                .is_some_and(|c| before(c.left))
        });
        let id = *list.get(k.checked_sub(1)?)?;
        let c = self.cylinders.get(id.index())?;
        let inside = match c.right {
            Wall::Zero => true,
            w => self
                .wall_angle(scene, w)
                .is_some_and(|r| angle.cmp_angle(&r) == Ordering::Less),
        };
        inside.then_some(id)
    }
}
