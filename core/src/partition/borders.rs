//! Adjacency across primary walls: for every chain, the cylinders bordering it from above
//! and from below, in θ order. Each list tiles the whole circle of directions once: below
//! a lower chain (and above an upper chain) lies one layer, the one in which the chain's
//! object is not crossed; on the other side lie two, before and after the object in t.

use alloc::collections::BTreeMap;
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

/// The bordering cylinders of every chain, side and layer, sorted by θ.
pub(crate) type Borders = BTreeMap<(Chain, Side, Layer), Vec<CylinderId>>;

pub(crate) fn build(scene: &SceneRef<'_>, complex: &Complex) -> Borders {
    let mut out: Borders = BTreeMap::new();
    for (i, c) in complex.cylinders.iter().enumerate() {
        let id = CylinderId(i as u32);
        if let Some(t) = c.top {
            out.entry((t, Side::Below, Layer::of(c, t)))
                .or_default()
                .push(id);
        }
        if let Some(b) = c.bottom {
            out.entry((b, Side::Above, Layer::of(c, b)))
                .or_default()
                .push(id);
        }
    }
    for list in out.values_mut() {
        let mut keyed: Vec<(Option<Angle>, CylinderId)> = list
            .iter()
            .map(|&id| (complex.left_angle(scene, id), id))
            .collect();
        keyed.sort_by(|a, b| match (&a.0, &b.0) {
            (None, None) => Ordering::Equal,
            (None, Some(_)) => Ordering::Less,
            (Some(_), None) => Ordering::Greater,
            (Some(x), Some(y)) => x.cmp_angle(y),
        });
        *list = keyed.into_iter().map(|(_, id)| id).collect();
    }
    out
}

impl Complex {
    /// The angle of the cylinder's left wall; `None` for θ = 0.
    pub(crate) fn left_angle(&self, scene: &SceneRef<'_>, id: CylinderId) -> Option<Angle> {
        self.cylinders
            .get(id.index())
            .and_then(|c| self.wall_angle(scene, c.left))
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
        let list = self.borders.get(&(chain, side, layer))?;
        // The last cylinder whose left wall lies before `angle` (θ = 0 lies before all).
        let k = list.partition_point(|&id| {
            self.left_angle(scene, id)
                .is_none_or(|l| l.cmp_angle(angle) == Ordering::Less)
        });
        let id = *list.get(k.checked_sub(1)?)?;
        let c = self.cylinders.get(id.index())?;
        matches!(c.right, Wall::Zero).then_some(id).or_else(|| {
            self.wall_angle(scene, c.right)
                .filter(|r| angle.cmp_angle(r) == Ordering::Less)
                .map(|_| id)
        })
    }
}
