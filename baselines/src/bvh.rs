//! A BVH ray caster on `parry2d`: a bounding-volume hierarchy over the objects' boxes built
//! by parry's binned SAH builder and searched best-first by parry's `find_best` (the
//! traversal behind `Bvh::cast_ray`), with the shared Cyrus–Beck narrow phase at the
//! leaves, which also gives the hit edge the optics need.

use parry2d_f64::bounding_volume::Aabb;
use parry2d_f64::math::Vector;
use parry2d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry2d_f64::query::Ray;

use crate::prepared::{Kind, Prepared, RayHit};
use crate::trace::Caster;

/// The BVH caster.
#[derive(Clone, Debug)]
pub struct BvhCaster {
    bvh: Bvh,
    /// Object of each leaf.
    objects: Vec<u32>,
}

impl BvhCaster {
    /// Builds the hierarchy over the non-screen objects.
    pub fn new(scene: &Prepared) -> BvhCaster {
        let objects: Vec<u32> = (0..scene.objects.len() as u32)
            .filter(|&i| scene.kind(i) != Kind::Screen)
            .collect();
        let boxes: Vec<Aabb> = objects
            .iter()
            .filter_map(|&i| scene.objects.get(i as usize))
            .map(|o| {
                let b = o.bbox;
                Aabb::new(Vector::new(b[0], b[1]), Vector::new(b[2], b[3]))
            })
            .collect();
        BvhCaster {
            bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes),
            objects,
        }
    }
}

impl Caster for BvhCaster {
    fn nearest(
        &self,
        scene: &Prepared,
        o: (f64, f64),
        d: (f64, f64),
        exclude: Option<u32>,
    ) -> Option<RayHit> {
        let ray = Ray::new(Vector::new(o.0, o.1), Vector::new(d.0, d.1));
        self.bvh
            .find_best(
                f64::MAX,
                |node, best| node.cast_ray(&ray, best),
                |leaf, best| {
                    let obj = *self.objects.get(leaf as usize)?;
                    if Some(obj) == exclude {
                        return None;
                    }
                    let h = scene.enter(obj, o, d)?;
                    (h.t < best).then_some((h.t, h))
                },
            )
            .map(|(_, (_, h))| h)
    }
}
