//! Building the canonical partition by a rotational sweep over θ.
//!
//! The cross-section at θ = 0 opens one cylinder per interval; then the vertices (directed
//! free bitangents) are processed in θ order, each closing three cylinders and opening
//! three (see the table in [`super`]); at θ = 2π the cylinders still open are linked to
//! those opened at θ = 0.
//!
//! The free bitangents come from the output-sensitive kinetic sweep of
//! [`crate::line_space::free_bitangents`] (O((n + V) log n); it falls back to the O(n³)
//! brute force if one of its invariants fails), already in θ order; each event then costs
//! O(log n) here. The randomized incremental construction with history (§4 of the paper)
//! produces the same partition.

use alloc::collections::BTreeMap;
use alloc::vec::Vec;

use super::{Complex, Cylinder, CylinderId, Vertex, VertexId, Wall};
use crate::geom::sos::Angle;
use crate::line_space::{cross_section, free_bitangents, Bitangent, Bound, Chain};
use crate::partition::ComplexError;
use crate::scene::{ObjectId, SceneRef};

type Key = (Option<Chain>, Option<ObjectId>, Option<ObjectId>);

/// The open cylinders by bottom chain and by top chain. At a fixed θ at most two open
/// cylinders share a chain on one side (the layers before and after its object), and a key
/// (chain, floor, ceiling) names at most one: two slots per chain, no map on the hot path.
struct Open {
    by_bottom: Vec<[Option<CylinderId>; 2]>,
    by_top: Vec<[Option<CylinderId>; 2]>,
}

/// Slot of a chain; the last slot is for "no chain" (the unbounded cylinders).
fn chain_slot(chain: Option<Chain>, objects: usize) -> usize {
    match chain {
        None => 2 * objects,
        Some(c) => 2 * c.object.0 as usize + usize::from(c.bound == Bound::Upper),
    }
}

impl Open {
    fn new(objects: usize) -> Open {
        Open {
            by_bottom: alloc::vec![[None; 2]; 2 * objects + 1],
            by_top: alloc::vec![[None; 2]; 2 * objects + 1],
        }
    }

    fn slots(
        index: &mut [[Option<CylinderId>; 2]],
        chain: Option<Chain>,
    ) -> Option<&mut [Option<CylinderId>; 2]> {
        let n = (index.len() - 1) / 2;
        index.get_mut(chain_slot(chain, n))
    }

    fn insert(&mut self, id: CylinderId, c: &Cylinder) -> Result<(), ComplexError> {
        for (index, chain) in [(&mut self.by_bottom, c.bottom), (&mut self.by_top, c.top)] {
            let slots = Open::slots(index, chain).ok_or(ComplexError::TooLarge)?;
            let free = slots
                .iter_mut()
                .find(|s| s.is_none())
                .ok_or(ComplexError::SweepUnmatchedAtZero)?;
            *free = Some(id);
        }
        Ok(())
    }

    fn remove(&mut self, id: CylinderId, c: &Cylinder) {
        for (index, chain) in [(&mut self.by_bottom, c.bottom), (&mut self.by_top, c.top)] {
            if let Some(slots) = Open::slots(index, chain) {
                slots
                    .iter_mut()
                    .filter(|s| **s == Some(id))
                    .for_each(|s| *s = None);
            }
        }
    }
}

/// Which objects of a vertex a corner face has as floor and ceiling.
#[derive(Clone, Copy)]
struct Corner {
    p_crossed: bool,
    q_crossed: bool,
}

impl Corner {
    /// Whether an open cylinder with this floor and ceiling is the corner face.
    fn matches(self, b: &Bitangent, floor: Option<ObjectId>, ceiling: Option<ObjectId>) -> bool {
        let (p, q) = (Some(b.first_object), Some(b.second_object));
        match (self.p_crossed, self.q_crossed) {
            (false, false) => floor != p && floor != q && ceiling != p && ceiling != q,
            (true, false) => floor == p && ceiling != q,
            (false, true) => ceiling == q && floor != p,
            (true, true) => floor == p && ceiling == q,
        }
    }
}

/// All directed free bitangents of the scene, sorted by θ.
///
/// Found by the kinetic sweep of [`crate::line_space::free_bitangents`] (output-sensitive;
/// it falls back to the O(n³) brute force if an invariant of the partition fails), already
/// in θ order: the stable sort below then costs one comparison per vertex and keeps the
/// order defined here whatever the enumeration. (The angles are recomputed in the
/// comparison rather than stored next to the vertices: an `Angle` is 80 bytes, and on
/// sorted input there are only V − 1 comparisons.)
fn free_vertices(scene: &SceneRef<'_>) -> Vec<Vertex> {
    let mut out: Vec<Vertex> = free_bitangents(scene)
        .into_iter()
        .map(|bitangent| Vertex { bitangent })
        .collect();
    out.sort_by(|a, b| {
        a.bitangent
            .angle(scene)
            .cmp_angle(&b.bitangent.angle(scene))
    });
    out
}

/// Builds the canonical cylindrical partition of a validated scene.
pub fn build_by_sweep(scene: &SceneRef<'_>) -> Result<Complex, ComplexError> {
    let vertices = free_vertices(scene);
    let mut cylinders: Vec<Cylinder> = Vec::new();
    let mut open = Open::new(scene.len());

    let push = |cylinders: &mut Vec<Cylinder>,
                open: &mut Open,
                c: Cylinder|
     -> Result<CylinderId, ComplexError> {
        let id = CylinderId::from_index(cylinders.len()).ok_or(ComplexError::TooLarge)?;
        open.insert(id, &c)?;
        cylinders.push(c);
        Ok(id)
    };

    for iv in cross_section(scene, &Angle::ZERO) {
        let c = Cylinder {
            floor: iv.floor,
            ceiling: iv.ceiling,
            bottom: iv.bottom,
            top: iv.top,
            left: Wall::Zero,
            right: Wall::Zero,
            left_neighbour: None,
            right_neighbour: None,
        };
        push(&mut cylinders, &mut open, c)?;
    }
    let initial: BTreeMap<Key, CylinderId> = cylinders
        .iter()
        .enumerate()
        .map(|(i, c)| ((c.bottom, c.floor, c.ceiling), CylinderId(i as u32)))
        .collect();

    for (vi, v) in vertices.iter().enumerate() {
        let wall = Wall::Vertex(VertexId::from_index(vi).ok_or(ComplexError::TooLarge)?);
        let b = v.bitangent;
        let cp = Chain {
            object: b.first_object,
            bound: b.first_bound,
        };
        let cq = Chain {
            object: b.second_object,
            bound: b.second_bound,
        };
        let (p_lower, q_lower) = (
            b.first_bound == Bound::Lower,
            b.second_bound == Bound::Lower,
        );
        let top = Corner {
            p_crossed: p_lower,
            q_crossed: q_lower,
        };
        let bottom = Corner {
            p_crossed: !p_lower,
            q_crossed: !q_lower,
        };
        let left = Corner {
            p_crossed: p_lower,
            q_crossed: !q_lower,
        };
        let right = Corner {
            p_crossed: !p_lower,
            q_crossed: q_lower,
        };

        let find = |index: &[[Option<CylinderId>; 2]], chain: Chain, corner: Corner| {
            let slots = index.get(chain_slot(Some(chain), scene.len()))?;
            slots.iter().flatten().copied().find(|id| {
                cylinders
                    .get(id.index())
                    .is_some_and(|c| corner.matches(&b, c.floor, c.ceiling))
            })
        };
        let missing = ComplexError::SweepLostCylinder { vertex: vi };

        // Top wedge: bottom arc switches from Q's chain to P's.
        let t = find(&open.by_bottom, cq, top).ok_or(missing)?;
        // Bottom wedge: top arc switches from P's chain to Q's.
        let d = find(&open.by_top, cp, bottom).ok_or(missing)?;
        // Left wedge: between P's chain (below) and Q's (above); closes.
        let l = find(&open.by_bottom, cp, left)
            .filter(|id| cylinders.get(id.index()).is_some_and(|c| c.top == Some(cq)))
            .ok_or(missing)?;

        let close = |cylinders: &mut Vec<Cylinder>, open: &mut Open, id: CylinderId| -> Cylinder {
            let c = &mut cylinders[id.index()];
            c.right = wall;
            open.remove(id, c);
            *c
        };
        let ct = close(&mut cylinders, &mut open, t);
        let cd = close(&mut cylinders, &mut open, d);
        let cl = close(&mut cylinders, &mut open, l);

        // The right wedge's face, from the floors and ceilings just closed: X is the object
        // before p and Y the one after q.
        let (p, q) = (Some(b.first_object), Some(b.second_object));
        let known = [ct, cd, cl];
        let x = known
            .iter()
            .find(|c| c.floor != p && c.floor != q)
            .map(|c| c.floor);
        let y = known
            .iter()
            .find(|c| c.ceiling != p && c.ceiling != q)
            .map(|c| c.ceiling);
        let (floor, ceiling) = match (right.p_crossed, right.q_crossed) {
            (false, false) => (x.ok_or(missing)?, y.ok_or(missing)?),
            (true, false) => (p, y.ok_or(missing)?),
            (false, true) => (x.ok_or(missing)?, q),
            (true, true) => (p, q),
        };

        let opened = [
            Cylinder {
                bottom: Some(cp),
                left: wall,
                right: Wall::Zero,
                left_neighbour: Some(t),
                right_neighbour: None,
                ..ct
            },
            Cylinder {
                top: Some(cq),
                left: wall,
                right: Wall::Zero,
                left_neighbour: Some(d),
                right_neighbour: None,
                ..cd
            },
            Cylinder {
                floor,
                ceiling,
                bottom: Some(cq),
                top: Some(cp),
                left: wall,
                right: Wall::Zero,
                left_neighbour: None,
                right_neighbour: None,
            },
        ];
        let [nt, nd, _] = opened;
        let id_t = push(&mut cylinders, &mut open, nt)?;
        let id_d = push(&mut cylinders, &mut open, nd)?;
        push(&mut cylinders, &mut open, opened[2])?;
        cylinders[t.index()].right_neighbour = Some(id_t);
        cylinders[d.index()].right_neighbour = Some(id_d);
    }

    // θ = 2π: the open cylinders continue into those opened at θ = 0.
    for id in open.by_bottom.iter().flatten().flatten().copied() {
        let c = &cylinders[id.index()];
        let first = *initial
            .get(&(c.bottom, c.floor, c.ceiling))
            .ok_or(ComplexError::SweepUnmatchedAtZero)?;
        cylinders[id.index()].right_neighbour = Some(first);
        cylinders[first.index()].left_neighbour = Some(id);
    }
    Ok(Complex::new_owned(vertices, cylinders, scene))
}
