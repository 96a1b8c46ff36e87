//! Building the canonical partition by a rotational sweep over θ.
//!
//! The cross-section at θ = 0 opens one cylinder per interval; then the vertices (directed
//! free bitangents) are processed in θ order, each closing three cylinders and opening
//! three (see the table in [`super`]; the loop is [`super::replay`], shared with the
//! reader of version-3 files); at θ = 2π the cylinders still open are linked to those
//! opened at θ = 0.
//!
//! The free bitangents come from the output-sensitive kinetic sweep of
//! [`crate::line_space::free_bitangents`] (O((n + V) log n); it falls back to the O(n³)
//! brute force if one of its invariants fails), already in θ order; each event then costs
//! O(1) here. The randomized incremental construction with history (§4 of the paper)
//! produces the same partition.

use alloc::vec::Vec;

use super::replay::{open_slots, replay, ReplayError, BLANK, ZERO_SLOTS};
use super::{Complex, Cylinder, Vertex, Wall};
use crate::geom::sos::Angle;
use crate::line_space::{cross_section, free_bitangents};
use crate::partition::ComplexError;
use crate::scene::SceneRef;

/// All directed free bitangents of the scene, sorted by θ.
///
/// Found by the kinetic sweep of [`crate::line_space::free_bitangents`] (output-sensitive;
/// it falls back to the O(n³) brute force if an invariant of the partition fails), already
/// in θ order: the stable sort below then costs one comparison per vertex and keeps the
/// order defined here whatever the enumeration. (The angles are recomputed in the
/// comparison rather than stored next to the vertices: an `Angle` is 24 bytes, and on
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
    let mut cylinders: Vec<Cylinder> = cross_section(scene, &Angle::ZERO)
        .into_iter()
        .map(|iv| Cylinder {
            floor: iv.floor,
            ceiling: iv.ceiling,
            bottom: iv.bottom,
            top: iv.top,
            left: Wall::Zero,
            right: Wall::Zero,
            left_neighbour: None,
            right_neighbour: None,
        })
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
