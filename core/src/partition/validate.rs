//! Invariants of a complex (spade's `sanity_check` idea): called by tests and fuzz targets
//! after every build.

use super::{Complex, Wall};
use crate::geom::sos::Angle;
use crate::line_space::{cross_section, Interval};
use crate::scene::SceneRef;

/// Why a complex is inconsistent (a bug, or corrupt input in a loaded file).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum ComplexError {
    /// More cylinders or vertices than `u32` ids can address.
    TooLarge,
    /// The sweep found no open cylinder for a corner face at this vertex (a bug).
    SweepLostCylinder {
        /// Index of the vertex.
        vertex: usize,
    },
    /// A cylinder open at θ = 2π has no counterpart at θ = 0 (a bug).
    SweepUnmatchedAtZero,
    /// Left/right adjacency is not symmetric, or neighbours disagree on floor, ceiling or wall.
    Adjacency {
        /// The cylinder at fault.
        cylinder: usize,
    },
    /// A cylinder or neighbour id is out of range.
    IdOutOfRange {
        /// The cylinder at fault.
        cylinder: usize,
    },
    /// The cylinders crossing a direction disagree with the cross-section there.
    CrossSection,
    /// An insertion of the randomized construction lost track of its conflict cylinders
    /// (a bug).
    InsertionLost {
        /// The object being inserted.
        object: usize,
        /// Where it got lost.
        step: &'static str,
    },
    /// Counts break `cylinders = 3·objects + 1 + 3·vertices` (for a complex pruned to a
    /// region: a vertex closes or opens more than three cylinders or none at all, or
    /// `cylinders > 3·objects + 1 + 3·vertices`).
    Count,
    /// A complex pruned to a region has a cylinder at θ = 0 after one that is not.
    ZeroPrefix {
        /// The cylinder at fault.
        cylinder: usize,
    },
    /// A vertex's tangent vertices or objects are out of range for the scene.
    VertexOutOfRange {
        /// The vertex at fault.
        vertex: usize,
    },
    /// Vertices are not strictly sorted by θ (the adjacency across chains relies on it).
    VerticesNotSorted {
        /// The first vertex not after its predecessor.
        vertex: usize,
    },
    /// A cylinder's right wall is not after its left wall in θ.
    WallOrder {
        /// The cylinder at fault.
        cylinder: usize,
    },
    /// The history DAG is malformed: a link out of range or not to a younger node (a
    /// cycle), a node no link reaches, a live node with children or a dead one without, a
    /// piece node in a history flagged compacted.
    History {
        /// The node at fault.
        node: usize,
        /// Which rule it breaks.
        what: &'static str,
    },
    /// The construction needs more than its memory budget allows (or than the allocator
    /// gives): what was needed so far when it stopped.
    CapacityExceeded {
        /// Live cylinders.
        cylinders: usize,
        /// History nodes (every cylinder that ever existed).
        history_nodes: usize,
        /// Estimated bytes of the arenas.
        bytes: usize,
    },
}

impl core::error::Error for ComplexError {}

/// A cylinder's interval of the cross-section: its floor, ceiling and arcs.
fn interval(c: &super::Cylinder) -> Interval {
    Interval {
        floor: c.floor,
        ceiling: c.ceiling,
        bottom: c.bottom,
        top: c.top,
    }
}

impl core::fmt::Display for ComplexError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            ComplexError::TooLarge => write!(f, "complex too large for 32-bit ids"),
            ComplexError::SweepLostCylinder { vertex } => {
                write!(f, "vertex {vertex}: no open cylinder for a corner face")
            }
            ComplexError::SweepUnmatchedAtZero => {
                write!(f, "cylinder open at 2π has no match at 0")
            }
            ComplexError::Adjacency { cylinder } => {
                write!(f, "cylinder {cylinder}: adjacency is inconsistent")
            }
            ComplexError::IdOutOfRange { cylinder } => {
                write!(f, "cylinder {cylinder}: id out of range")
            }
            ComplexError::CrossSection => write!(f, "cylinders disagree with the cross-section"),
            ComplexError::InsertionLost { object, step } => {
                write!(f, "inserting object {object}: conflict chain lost ({step})")
            }
            ComplexError::Count => write!(f, "cylinder count breaks 3n + 1 + 3V"),
            ComplexError::ZeroPrefix { cylinder } => write!(
                f,
                "cylinder {cylinder}: starts at θ = 0 but follows cylinders that do not"
            ),
            ComplexError::VertexOutOfRange { vertex } => {
                write!(f, "vertex {vertex}: tangent vertex or object out of range")
            }
            ComplexError::VerticesNotSorted { vertex } => {
                write!(f, "vertex {vertex}: not after the previous vertex in θ")
            }
            ComplexError::WallOrder { cylinder } => {
                write!(f, "cylinder {cylinder}: right wall not after left wall")
            }
            ComplexError::History { node, what } => write!(f, "history node {node}: {what}"),
            ComplexError::CapacityExceeded {
                cylinders,
                history_nodes,
                bytes,
            } => write!(
                f,
                "construction exceeds its budget: {cylinders} cylinders, {history_nodes} history nodes, about {bytes} bytes"
            ),
        }
    }
}

impl Complex {
    /// A complex from its arenas (e.g. decoded from a file): the derived state is rebuilt
    /// with `borders::build`, never taken from the caller, after [`Complex::validate`]
    /// passed — so a walk of the result cannot index out of bounds or loop forever.
    pub fn from_parts(
        scene: &SceneRef<'_>,
        vertices: alloc::vec::Vec<super::Vertex>,
        cylinders: alloc::vec::Vec<super::Cylinder>,
    ) -> Result<Complex, ComplexError> {
        Complex::from_region_parts(scene, None, vertices, cylinders)
    }

    /// [`Complex::from_parts`] for a complex pruned to `region` (`Some`; e.g. decoded from
    /// a version-2 file): validated with the checks a pruned complex still satisfies (see
    /// [`Complex::validate`]).
    pub fn from_region_parts(
        scene: &SceneRef<'_>,
        region: Option<super::Region>,
        vertices: alloc::vec::Vec<super::Vertex>,
        cylinders: alloc::vec::Vec<super::Cylinder>,
    ) -> Result<Complex, ComplexError> {
        if u32::try_from(cylinders.len()).is_err() || u32::try_from(vertices.len()).is_err() {
            return Err(ComplexError::TooLarge);
        }
        let mut complex = Complex {
            vertices,
            cylinders,
            borders: Default::default(),
            region,
        };
        complex.validate(scene)?;
        complex.borders = super::borders::build(scene, &complex);
        Ok(complex)
    }

    /// Checks the structural invariants: ids in range, vertices strictly sorted by θ,
    /// walls in θ order, left/right adjacency symmetric with the same floor, ceiling and
    /// shared wall, every vertex closing and opening three cylinders, the count
    /// `3n + 1 + 3V`, and that the cylinders crossing θ = 0 are exactly the cross-section
    /// there.
    ///
    /// A complex pruned to a region ([`Complex::region`]) lacks cylinders by design, so
    /// exactly the checks that count cylinders are relaxed for it, and only for it: every
    /// vertex closes and opens at most three cylinders and is a wall of at least one,
    /// `cylinders ≤ 3n + 1 + 3V`, and the cylinders crossing θ = 0 are a part of the
    /// cross-section there (each interval at most once) and come first in the arena (the
    /// walk's start scans that prefix). The other checks are the same.
    pub fn validate(&self, scene: &SceneRef<'_>) -> Result<(), ComplexError> {
        let nc = self.cylinders.len();
        let (objects, points) = (scene.len(), scene.vertices().len());
        let mut previous: Option<Angle> = None;
        for (i, v) in self.vertices.iter().enumerate() {
            let b = &v.bitangent;
            if b.first >= points
                || b.second >= points
                || b.first_object.0 as usize >= objects
                || b.second_object.0 as usize >= objects
            {
                return Err(ComplexError::VertexOutOfRange { vertex: i });
            }
            // `borders` sorts walls by vertex index: that must be θ order.
            let angle = b.angle(scene);
            if previous.is_some_and(|p| p.cmp_angle(&angle) != core::cmp::Ordering::Less) {
                return Err(ComplexError::VerticesNotSorted { vertex: i });
            }
            previous = Some(angle);
        }
        let rank = |w: Wall| match w {
            Wall::Zero => 0,
            Wall::Vertex(v) => v.index() + 1,
        };
        for (i, c) in self.cylinders.iter().enumerate() {
            let wall_ok = |w: Wall| match w {
                Wall::Zero => true,
                Wall::Vertex(v) => v.index() < self.vertices.len(),
            };
            let object_ok =
                |o: Option<crate::scene::ObjectId>| o.is_none_or(|o| (o.0 as usize) < objects);
            if !wall_ok(c.left)
                || !wall_ok(c.right)
                || !object_ok(c.floor)
                || !object_ok(c.ceiling)
                || !object_ok(c.bottom.map(|ch| ch.object))
                || !object_ok(c.top.map(|ch| ch.object))
            {
                return Err(ComplexError::IdOutOfRange { cylinder: i });
            }
            if c.right != Wall::Zero && rank(c.left) >= rank(c.right) {
                return Err(ComplexError::WallOrder { cylinder: i });
            }
            if let Some(r) = c.right_neighbour {
                let n = self
                    .cylinders
                    .get(r.index())
                    .ok_or(ComplexError::IdOutOfRange { cylinder: i })?;
                if n.left_neighbour.map(|l| l.index()) != Some(i)
                    || n.floor != c.floor
                    || n.ceiling != c.ceiling
                    || n.left != c.right
                {
                    return Err(ComplexError::Adjacency { cylinder: i });
                }
            }
            if let Some(l) = c.left_neighbour {
                let n = self
                    .cylinders
                    .get(l.index())
                    .ok_or(ComplexError::IdOutOfRange { cylinder: i })?;
                if n.right_neighbour.map(|r| r.index()) != Some(i) {
                    return Err(ComplexError::Adjacency { cylinder: i });
                }
            }
        }
        let mut closes = alloc::vec![0u8; self.vertices.len()];
        let mut opens = alloc::vec![0u8; self.vertices.len()];
        for c in &self.cylinders {
            if let Wall::Vertex(v) = c.right {
                closes[v.index()] = closes[v.index()].saturating_add(1);
            }
            if let Wall::Vertex(v) = c.left {
                opens[v.index()] = opens[v.index()].saturating_add(1);
            }
        }
        if self.region.is_some() {
            return self.validate_pruned(scene, &closes, &opens);
        }
        if closes.iter().chain(&opens).any(|&k| k != 3)
            || nc != 3 * scene.len() + 1 + 3 * self.vertices.len()
        {
            return Err(ComplexError::Count);
        }
        let mut at_zero: alloc::vec::Vec<Interval> = self
            .cylinders
            .iter()
            .filter(|c| c.left == Wall::Zero)
            .map(interval)
            .collect();
        let mut want = cross_section(scene, &Angle::ZERO);
        at_zero.sort();
        want.sort();
        if at_zero != want {
            return Err(ComplexError::CrossSection);
        }
        Ok(())
    }

    /// The counting checks of a pruned complex ([`Complex::validate`]).
    fn validate_pruned(
        &self,
        scene: &SceneRef<'_>,
        closes: &[u8],
        opens: &[u8],
    ) -> Result<(), ComplexError> {
        let nc = self.cylinders.len();
        if closes.iter().chain(opens).any(|&k| k > 3)
            || closes.iter().zip(opens).any(|(&c, &o)| c == 0 && o == 0)
            || nc > 3 * scene.len() + 1 + 3 * self.vertices.len()
        {
            return Err(ComplexError::Count);
        }
        // The cylinders at θ = 0 first, then none.
        let prefix = self
            .cylinders
            .iter()
            .take_while(|c| c.left == Wall::Zero)
            .count();
        if let Some(i) = self
            .cylinders
            .iter()
            .skip(prefix)
            .position(|c| c.left == Wall::Zero)
        {
            return Err(ComplexError::ZeroPrefix {
                cylinder: prefix + i,
            });
        }
        let mut at_zero: alloc::vec::Vec<Interval> =
            self.cylinders.iter().take(prefix).map(interval).collect();
        let mut want = cross_section(scene, &Angle::ZERO);
        at_zero.sort();
        want.sort();
        // A sub-multiset of the cross-section: a merge of the two sorted lists.
        let mut rest = want.iter();
        for got in &at_zero {
            if !rest.by_ref().any(|w| w == got) {
                return Err(ComplexError::CrossSection);
            }
        }
        Ok(())
    }

    /// Checks that the cylinders whose θ-range contains `angle` are exactly the intervals
    /// of the brute-force cross-section at `angle` (which must not be a vertex's angle).
    pub fn validate_at(&self, scene: &SceneRef<'_>, angle: &Angle) -> Result<(), ComplexError> {
        let mut got: alloc::vec::Vec<Interval> = self
            .cylinders_at(scene, angle)
            .map(|(_, c)| Interval {
                floor: c.floor,
                ceiling: c.ceiling,
                bottom: c.bottom,
                top: c.top,
            })
            .collect();
        let mut want = cross_section(scene, angle);
        got.sort();
        want.sort();
        if got != want {
            return Err(ComplexError::CrossSection);
        }
        Ok(())
    }
}
