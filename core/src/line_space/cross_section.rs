//! The cross-section of the complex at a fixed direction θ (the paper's Fig. 5): the
//! maximal free segments of direction θ, grouped into intervals of u with one floor and
//! one ceiling object.

use alloc::vec::Vec;
use core::cmp::Ordering;

use super::{object_ahead_of, ranked, tangent_vertex, Bound, Chain};
use crate::geom::sos::Angle;
use crate::geom::Sign;
use crate::scene::{ObjectId, SceneRef};

/// A maximal interval of u at a fixed θ over which the free segments between `floor` and
/// `ceiling` (backward and forward object; `None` is infinity) persist. It is bounded
/// below and above by the chains whose tangent points lie in this layer (`None`: u is
/// unbounded on that side).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct Interval {
    /// Object behind the free segments (first hit looking backward), if any.
    pub floor: Option<ObjectId>,
    /// Object ahead of the free segments (first hit looking forward), if any.
    pub ceiling: Option<ObjectId>,
    /// Chain at the bottom of the interval.
    pub bottom: Option<Chain>,
    /// Chain at the top of the interval.
    pub top: Option<Chain>,
}

/// All intervals of the cross-section at θ, in the order in which a sweep upward in u
/// closes them. Every object contributes its two tangent events; the objects crossed by
/// the current line are kept in order along it.
///
/// Cost: O(n log n) comparisons for sorting plus O(n²) worst case for the ordered list;
/// this is the brute-force definition the complex is checked against.
pub fn cross_section(scene: &SceneRef<'_>, angle: &Angle) -> Vec<Interval> {
    // (tangent vertex, chain) for every object and bound, sorted by offset u.
    let mut events: Vec<(usize, Chain)> = Vec::with_capacity(2 * scene.len());
    for id in (0..scene.len()).map(|i| ObjectId(i as u32)) {
        for bound in [Bound::Lower, Bound::Upper] {
            events.push((
                tangent_vertex(scene, id, angle, bound),
                Chain { object: id, bound },
            ));
        }
    }
    events.sort_by(
        |a, b| match angle.offset_cmp(ranked(scene, a.0), ranked(scene, b.0)) {
            Sign::Positive => Ordering::Less,
            Sign::Negative => Ordering::Greater,
            Sign::Zero => Ordering::Equal,
        },
    );

    let mut out = Vec::with_capacity(3 * scene.len() + 1);
    // Objects crossed by the current line, in order along it; gap k lies before crossed[k].
    let mut crossed: Vec<ObjectId> = Vec::new();
    let mut gap_bottom: Vec<Option<Chain>> = alloc::vec![None];
    let gap = |crossed: &[ObjectId], k: usize| {
        (
            k.checked_sub(1).and_then(|j| crossed.get(j).copied()),
            crossed.get(k).copied(),
        )
    };
    for (v, chain) in events {
        match chain.bound {
            Bound::Lower => {
                let o = ranked(scene, v);
                let k = crossed
                    .partition_point(|&x| object_ahead_of(scene, x, angle, o) == Some(false));
                let (floor, ceiling) = gap(&crossed, k);
                let bottom = gap_bottom.get(k).copied().flatten();
                out.push(Interval {
                    floor,
                    ceiling,
                    bottom,
                    top: Some(chain),
                });
                crossed.insert(k, chain.object);
                if let Some(g) = gap_bottom.get_mut(k) {
                    *g = Some(chain);
                }
                gap_bottom.insert(k, Some(chain));
            }
            Bound::Upper => {
                let Some(k) = crossed.iter().position(|&x| x == chain.object) else {
                    continue;
                };
                for g in [k, k + 1] {
                    let (floor, ceiling) = gap(&crossed, g);
                    let bottom = gap_bottom.get(g).copied().flatten();
                    out.push(Interval {
                        floor,
                        ceiling,
                        bottom,
                        top: Some(chain),
                    });
                }
                crossed.remove(k);
                gap_bottom.remove(k);
                if let Some(g) = gap_bottom.get_mut(k) {
                    *g = Some(chain);
                }
            }
        }
    }
    out.push(Interval {
        floor: None,
        ceiling: None,
        bottom: gap_bottom.first().copied().flatten(),
        top: None,
    });
    out
}
