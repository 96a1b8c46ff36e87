//! Building the canonical partition by a rotational sweep over θ.
//!
//! The cross-section at θ = 0 opens one cylinder per interval; then the vertices (directed
//! free bitangents) are processed in θ order, each closing three cylinders and opening
//! three (see the table in [`super`]); at θ = 2π the cylinders still open are linked to
//! those opened at θ = 0.
//!
//! The sweep is the output-sensitive kinetic sweep of [`crate::line_space::free_bitangents`]
//! (O((n + V) log n)), which finds each vertex together with the cylinders it closes and
//! opens: the partition is written as it goes ([`Partition`]), each event in O(1), and so is
//! the complex's derived state (the tilings and start indices of `borders`, which the
//! replay's numbering by left wall lets it count on the way instead of sorting). If one
//! of the kinetic sweep's invariants fails, the vertices come from the O(n³) brute force
//! instead and [`super::replay`] (the loop shared with the reader of version-3 files) finds
//! the cylinders. The randomized incremental construction with history (§4 of the paper)
//! produces the same partition.

use alloc::vec::Vec;

use super::borders::SweepBorders;
use super::replay::{open_slots, replay, ReplayError, BLANK, ZERO_SLOTS};
use super::{Complex, Cylinder, CylinderId, Vertex, VertexId, Wall};
use crate::geom::sos::Angle;
use crate::line_space::{
    cross_section, free_bitangents_by_definition, kinetic_sweep, Bitangent, Events, Interval,
};
use crate::partition::ComplexError;
use crate::scene::SceneRef;

/// The partition as the kinetic sweep reports it: the replay's numbering (the cylinders at
/// θ = 0 first, then the three opened by each vertex in θ order), its walls and links, and
/// the complex's derived state, which that numbering lets it build on the way.
struct Partition {
    vertices: Vec<Vertex>,
    cylinders: Vec<Cylinder>,
    /// Per slot of the kinetic sweep: the cylinder open in it.
    open: Vec<CylinderId>,
    borders: SweepBorders,
}

/// A cylinder with this interval, its walls θ = 0 and no neighbours yet.
fn cylinder(c: &Interval) -> Cylinder {
    Cylinder {
        floor: c.floor,
        ceiling: c.ceiling,
        bottom: c.bottom,
        top: c.top,
        ..BLANK
    }
}

impl Partition {
    /// The cylinder open in `slot`.
    fn open_in(&self, slot: u32) -> Option<CylinderId> {
        self.open.get(slot as usize).copied()
    }

    /// Records that `id` is open in `slot`.
    fn set_open(&mut self, slot: u32, id: CylinderId) -> Option<()> {
        let s = slot as usize;
        if self.open.len() <= s {
            self.open.resize(s + 1, CylinderId::ZERO);
        }
        *self.open.get_mut(s)? = id;
        Some(())
    }
}

impl Events for Partition {
    fn initial(&mut self, slot: u32, c: &Interval) -> Option<()> {
        let id = CylinderId::from_index(self.cylinders.len())?;
        self.cylinders.push(cylinder(c));
        self.set_open(slot, id)
    }

    fn vertex(
        &mut self,
        b: &Bitangent,
        closed: [u32; 3],
        opened: [(u32, Interval); 3],
    ) -> Option<()> {
        // The cylinders at θ = 0, all there by the first vertex.
        if self.vertices.is_empty() {
            self.borders.add(&self.cylinders);
        }
        let wall = Wall::Vertex(VertexId::from_index(self.vertices.len())?);
        self.vertices.push(Vertex { bitangent: *b });
        // Read before the opened cylinders take the closed ones' slots.
        let [t, d, l] = closed.map(|s| self.open_in(s));
        let first = self.cylinders.len();
        let ids = [first, first + 1, first + 2].map(CylinderId::from_index);
        // The top and bottom wedges' faces continue right of the vertex; the left wedge's
        // ends and the right wedge's starts.
        for (closed, next) in [(t, ids[0]), (d, ids[1]), (l, None)] {
            let c = self.cylinders.get_mut(closed?.index())?;
            c.right = wall;
            c.right_neighbour = next;
        }
        for (((slot, c), id), previous) in opened.iter().zip(ids).zip([t, d, None]) {
            self.cylinders.push(Cylinder {
                left: wall,
                left_neighbour: previous,
                ..cylinder(c)
            });
            self.set_open(*slot, id?)?;
        }
        self.borders.add(self.cylinders.get(first..)?);
        Some(())
    }

    fn wrap(&mut self, slot: u32, initial: usize) -> Option<()> {
        let last = self.open_in(slot)?;
        let first = CylinderId::from_index(initial)?;
        self.cylinders.get_mut(last.index())?.right_neighbour = Some(first);
        self.cylinders.get_mut(initial)?.left_neighbour = Some(last);
        Some(())
    }
}

/// Builds the canonical cylindrical partition of a validated scene.
pub fn build_by_sweep(scene: &SceneRef<'_>) -> Result<Complex, ComplexError> {
    let mut partition = Partition {
        vertices: Vec::new(),
        cylinders: Vec::new(),
        open: Vec::new(),
        borders: SweepBorders::new(scene.len()),
    };
    if kinetic_sweep(scene, &mut partition).is_some() {
        let Partition {
            vertices,
            cylinders,
            mut borders,
            ..
        } = partition;
        // Without vertices, the cylinders at θ = 0 are still to count.
        if vertices.is_empty() {
            borders.add(&cylinders);
        }
        let borders = borders.finish(scene, &vertices, &cylinders);
        return Ok(Complex::with_borders(vertices, cylinders, borders));
    }
    let vertices: Vec<Vertex> = free_bitangents_by_definition(scene)
        .into_iter()
        .map(|bitangent| Vertex { bitangent })
        .collect();
    let mut cylinders: Vec<Cylinder> = cross_section(scene, &Angle::ZERO)
        .iter()
        .map(cylinder)
        .collect();
    let initial = cylinders.len();
    cylinders.resize(initial + 3 * vertices.len(), BLANK);
    let mut open = alloc::vec![ZERO_SLOTS; open_slots(scene.len())];
    replay(scene.len(), &vertices, initial, &mut cylinders, &mut open).map_err(|e| match e {
        ReplayError::Lost(vertex) => ComplexError::SweepLostCylinder { vertex },
        ReplayError::Crowded(_) | ReplayError::Unmatched(_) => ComplexError::SweepUnmatchedAtZero,
        ReplayError::Storage | ReplayError::Input => ComplexError::TooLarge,
    })?;
    Ok(Complex::new_owned(vertices, cylinders, scene))
}
