//! The cylindrical partition of line space: the visibility complex as it is stored and
//! walked (DESIGN.md §3).
//!
//! A **face** of the complex is a connected set of maximal free segments with the same
//! floor and ceiling; in the `(θ, u)` cylinder it is a region bounded by chains. Each face
//! is cut by vertical (**secondary**) walls θ = const into **cylinders**: trapezoids with
//! one bottom and one top arc (pieces of chains; the **primary** walls) times the free
//! t-range between floor and ceiling.
//!
//! Walls: the permanent wall θ = 0, and at every vertex of the complex (a directed free
//! bitangent through tangent points `p` then `q`, objects P then Q) the walls that the
//! local picture dictates. Near the vertex the chains of P and Q cross and cut the plane
//! into four wedges; in each wedge a different subset of {P, Q} is crossed between the
//! objects X before `p` and Y after `q`, and six faces meet: (X,P) and (Q,Y) pass by, and
//! four faces have a corner at the vertex —
//!
//! | wedge | crossed | corner face | at the vertex |
//! |---|---|---|---|
//! | top (above both chains) | P iff P-lower, Q iff Q-lower | see below | wall up: its bottom arc switches from Q's chain to P's |
//! | bottom | P iff P-upper, Q iff Q-upper | | wall down: its top arc switches from P's chain to Q's |
//! | left (θ < θ_v, between) | P iff P-lower, Q iff Q-upper | | its cylinder closes |
//! | right (θ > θ_v, between) | P iff P-upper, Q iff Q-lower | | a cylinder opens |
//!
//! The corner face for the crossed subset S is (X,Y) for {}, (P,Y) for {P}, (X,Q) for {Q}
//! and (P,Q) for {P,Q}. Before θ_v the chain of Q lies above that of P (the line through
//! the farther point `q` turns left of the one through `p` when θ decreases).
//!
//! Walls run from a vertex up or down to the nearest arc of their face, so the partition
//! is canonical: it depends on the scene only. Consequently every vertex closes three
//! cylinders and opens three, and the number of cylinders is `3n + 1 + 3V` for `n`
//! objects and `V` vertices (the cross-section at θ = 0 has `3n + 1` intervals).

mod borders;
mod locate;
pub mod region;
#[cfg(any(feature = "alloc", feature = "format"))]
mod replay;
#[cfg(feature = "alloc")]
mod ric;
#[cfg(feature = "alloc")]
mod sweep;
#[cfg(feature = "alloc")]
mod validate;

pub(crate) use borders::zero_height;
#[cfg(feature = "alloc")]
pub use borders::Borders;
pub(crate) use borders::NO_ARC_VERTEX;
pub use borders::{BorderBuffers, BorderSizes, BordersRef, BufferTooSmall, Layer, Side};
pub(crate) use locate::point_in_object;
pub use locate::{point_in_scene, Location};
pub use region::{Region, RegionError};
#[cfg(any(feature = "alloc", feature = "format"))]
pub use replay::{open_slots, Open, Slots, ZERO_SLOTS};
#[cfg(feature = "format")]
pub(crate) use replay::{replay, replay_stream, ReplayError, Stream, BLANK as BLANK_CYLINDER};
#[cfg(feature = "alloc")]
pub use ric::{Budget, BuildOptions, History, HistoryParts, HistoryStats};
#[cfg(feature = "alloc")]
pub use sweep::build_by_sweep;
#[cfg(feature = "alloc")]
pub use validate::ComplexError;

use crate::ids::id_type;
use crate::line_space::{Bitangent, Chain};
use crate::scene::ObjectId;

id_type!(
    /// A cylinder of the partition.
    CylinderId
);
id_type!(
    /// A vertex of the complex: a directed free bitangent.
    VertexId
);

/// A vertex of the complex: a directed free bitangent.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Vertex {
    /// The line, its tangent points and chains.
    pub bitangent: Bitangent,
}

/// A secondary wall: a vertical line θ = const in line space.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Wall {
    /// θ = 0 (as a left wall) or θ = 2π (as a right wall).
    Zero,
    /// θ of a vertex of the complex.
    Vertex(VertexId),
}

/// One cylinder: a trapezoid in `(θ, u)` times the free segments between floor and ceiling.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Cylinder {
    /// Object behind the free segments (`None`: infinity).
    pub floor: Option<ObjectId>,
    /// Object ahead of the free segments (`None`: infinity) — what a ray in this cylinder sees.
    pub ceiling: Option<ObjectId>,
    /// Bottom arc (`None`: unbounded below).
    pub bottom: Option<Chain>,
    /// Top arc (`None`: unbounded above).
    pub top: Option<Chain>,
    /// Left wall.
    pub left: Wall,
    /// Right wall.
    pub right: Wall,
    /// The cylinder of the same face across the left wall (`None` if the face starts here).
    pub left_neighbour: Option<CylinderId>,
    /// The cylinder of the same face across the right wall (`None` if the face ends here).
    pub right_neighbour: Option<CylinderId>,
}

impl CylinderId {
    /// The id with this raw value, in `const` context (for complexes embedded as Rust
    /// statics, e.g. in firmware).
    pub const fn from_raw(raw: u32) -> Self {
        CylinderId(raw)
    }
}

impl VertexId {
    /// The id with this raw value, in `const` context.
    pub const fn from_raw(raw: u32) -> Self {
        VertexId(raw)
    }
}

/// Where a [`Complex`] keeps its arrays: the vertices, the cylinders and the derived
/// lookup state ([`BordersRef`]). [`Owned`] keeps them in vectors (feature `alloc`;
/// construction and `alloc` loading); [`Slices`] borrows them from the caller (no heap:
/// statics in flash, or buffers a loader filled), so a device can walk a complex without
/// an allocator.
pub trait Storage {
    /// The vertices (directed free bitangents), sorted by θ.
    type Vertices: AsRef<[Vertex]>;
    /// The cylinders.
    type Cylinders: AsRef<[Cylinder]>;
    /// The derived lookup state.
    type Borders;
    /// The derived state as borrowed slices.
    fn borders(b: &Self::Borders) -> BordersRef<'_>;
}

/// Growable storage: vectors (feature `alloc`). The default storage of [`Complex`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Owned;

#[cfg(feature = "alloc")]
impl Storage for Owned {
    type Vertices = alloc::vec::Vec<Vertex>;
    type Cylinders = alloc::vec::Vec<Cylinder>;
    type Borders = Borders;
    #[inline]
    fn borders(b: &Borders) -> BordersRef<'_> {
        b.borrowed()
    }
}

/// Borrowed storage: slices the caller provides (no heap). Build one with
/// [`Complex::from_slices`] or borrow an owned complex with [`Complex::as_slices`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Slices<'a>(core::marker::PhantomData<&'a ()>);

impl<'a> Storage for Slices<'a> {
    type Vertices = &'a [Vertex];
    type Cylinders = &'a [Cylinder];
    type Borders = BordersRef<'a>;
    fn borders<'s>(b: &'s BordersRef<'a>) -> BordersRef<'s> {
        *b
    }
}

/// The visibility complex of a scene as a cylindrical partition, in storage `S`
/// ([`Owned`] vectors by default, or caller-provided [`Slices`]).
#[cfg(feature = "alloc")]
#[derive(Clone, Debug, Default)]
pub struct Complex<S: Storage = Owned> {
    pub(crate) vertices: S::Vertices,
    pub(crate) cylinders: S::Cylinders,
    pub(crate) borders: S::Borders,
    /// The box of viewpoints the complex was pruned to (`region`); `None`: the whole
    /// complex.
    pub(crate) region: Option<Region>,
}

/// The visibility complex of a scene as a cylindrical partition, in storage `S` (without
/// the feature `alloc` only [`Slices`] exist).
#[cfg(not(feature = "alloc"))]
#[derive(Clone, Debug, Default)]
pub struct Complex<S: Storage> {
    pub(crate) vertices: S::Vertices,
    pub(crate) cylinders: S::Cylinders,
    pub(crate) borders: S::Borders,
    /// The box of viewpoints the complex was pruned to (`region`); `None`: the whole
    /// complex.
    pub(crate) region: Option<Region>,
}

#[cfg(feature = "alloc")]
impl Complex {
    /// An owned complex from its vertices (sorted by θ) and cylinders, with its derived
    /// state rebuilt.
    pub(crate) fn new_owned(
        vertices: alloc::vec::Vec<Vertex>,
        cylinders: alloc::vec::Vec<Cylinder>,
        scene: &crate::scene::SceneRef<'_>,
    ) -> Complex {
        let mut complex = Complex {
            vertices,
            cylinders,
            borders: Borders::default(),
            region: None,
        };
        complex.borders = borders::build(scene, &complex);
        complex
    }

    /// An owned complex from its vertices (sorted by θ), cylinders and their derived state,
    /// built by the construction as it went (the rotational sweep); equal to what
    /// [`Complex::new_owned`] rebuilds.
    pub(crate) fn with_borders(
        vertices: alloc::vec::Vec<Vertex>,
        cylinders: alloc::vec::Vec<Cylinder>,
        borders: Borders,
    ) -> Complex {
        Complex {
            vertices,
            cylinders,
            borders,
            region: None,
        }
    }

    /// The same complex with its walk index of arc vertices: for every cylinder, the
    /// vertex of its bottom and top arc where that arc is one vertex's sinusoid over the
    /// cylinder's θ-range (8 bytes per cylinder). Walks (views, ray trees) then take the
    /// candidate exit across such an arc without the tangents from the eye: the same
    /// results, about 15 % fewer instructions per view of the n = 1024 grid. Neither
    /// construction nor decoding computes it (it costs about half a decode, ~565
    /// instructions per cylinder); slice complexes (devices) walk without it.
    pub fn with_arc_vertices(mut self, scene: &crate::scene::SceneRef<'_>) -> Complex {
        let mut borders = core::mem::take(&mut self.borders);
        borders.keep_arc_vertices(scene, &self);
        self.borders = borders;
        self
    }
}

impl<'a> Complex<Slices<'a>> {
    /// A complex over caller-provided slices: the vertices (sorted by θ) and cylinders,
    /// e.g. statics in flash or arrays a loader validated, and buffers for the derived
    /// state (sizes from [`BorderSizes`]), which is rebuilt into them without allocating.
    ///
    /// The arrays are not validated here (the loader does that); ids out of range make
    /// walks fail with an error, never panic or loop.
    pub fn from_slices(
        scene: &crate::scene::SceneRef<'_>,
        vertices: &'a [Vertex],
        cylinders: &'a [Cylinder],
        buffers: BorderBuffers<'a>,
    ) -> Result<Self, BufferTooSmall> {
        let borders = BordersRef::rebuild_into(scene, vertices, cylinders, buffers)?;
        Ok(Complex {
            vertices,
            cylinders,
            borders,
            region: None,
        })
    }

    /// The same complex marked as pruned to `region` (a device that decoded a region
    /// file passes `Decoded::region` here): walks from outside it are
    /// [`WalkError::OutsideRegion`](crate::walk::WalkError::OutsideRegion).
    #[must_use]
    pub fn with_region(mut self, region: Option<Region>) -> Self {
        self.region = region;
        self
    }
}

impl<S: Storage> Complex<S> {
    /// The vertices (directed free bitangents), sorted by θ.
    pub fn vertices(&self) -> &[Vertex] {
        self.vertices.as_ref()
    }

    /// The cylinders.
    pub fn cylinders(&self) -> &[Cylinder] {
        self.cylinders.as_ref()
    }

    /// The derived lookup state.
    pub fn borders_ref(&self) -> BordersRef<'_> {
        S::borders(&self.borders)
    }

    /// The same complex over borrowed slices (no copy, no allocation).
    pub fn as_slices(&self) -> Complex<Slices<'_>> {
        Complex {
            vertices: self.vertices(),
            cylinders: self.cylinders(),
            borders: self.borders_ref(),
            region: self.region,
        }
    }

    /// The box of viewpoints this complex was pruned to ([`Complex::prune_to_region`]),
    /// if any: it holds only the cylinders views from there need.
    pub fn region(&self) -> Option<Region> {
        self.region
    }

    /// The cylinder with this id.
    pub fn cylinder(&self, id: CylinderId) -> Option<&Cylinder> {
        self.cylinders().get(id.index())
    }

    /// The vertex with this id.
    pub fn vertex(&self, id: VertexId) -> Option<&Vertex> {
        self.vertices().get(id.index())
    }

    /// Number of undirected free bitangents between two different objects, counted from the
    /// vertices (each segment is a vertex in both directions).
    pub fn free_bitangents(&self) -> usize {
        self.vertices().len() / 2
    }

    /// The angle of a wall; `None` for θ = 0 (which is 0 on the left and 2π on the right).
    pub fn wall_angle(
        &self,
        scene: &crate::scene::SceneRef<'_>,
        wall: Wall,
    ) -> Option<crate::geom::sos::Angle> {
        match wall {
            Wall::Zero => None,
            Wall::Vertex(v) => match self.borders_ref().angle(v.index()) {
                Some(a) => Some(*a),
                None => self.vertex(v).map(|v| v.bitangent.angle(scene)),
            },
        }
    }

    /// The cylinders whose open θ-range contains `angle` (by a scan: O(cylinders)).
    pub fn cylinders_at<'s>(
        &'s self,
        scene: &'s crate::scene::SceneRef<'_>,
        angle: &'s crate::geom::sos::Angle,
    ) -> impl Iterator<Item = (CylinderId, &'s Cylinder)> + 's {
        use core::cmp::Ordering;
        self.cylinders()
            .iter()
            .enumerate()
            .filter_map(move |(i, c)| {
                let after_left = self
                    .wall_angle(scene, c.left)
                    .is_none_or(|l| l.cmp_angle(angle) == Ordering::Less);
                let before_right = self
                    .wall_angle(scene, c.right)
                    .is_none_or(|r| angle.cmp_angle(&r) == Ordering::Less);
                (after_left && before_right).then_some((CylinderId(i as u32), c))
            })
    }
}

#[cfg(feature = "alloc")]
impl Complex {
    /// Number of faces: connected chains of cylinders across secondary walls.
    pub fn faces(&self) -> usize {
        // A face is a path (born at a vertex, dies at a vertex) or a cycle through θ = 0.
        let born = self
            .cylinders
            .iter()
            .filter(|c| c.left_neighbour.is_none())
            .count();
        let mut on_cycle = 0;
        let mut seen = alloc::vec![false; self.cylinders.len()];
        for start in 0..self.cylinders.len() {
            if seen[start] {
                continue;
            }
            // Walk right until the chain ends or returns; bounded by the number of cylinders.
            let mut cur = start;
            let mut cycle = false;
            for _ in 0..self.cylinders.len() {
                seen[cur] = true;
                match self.cylinders[cur].right_neighbour {
                    Some(n) if n.index() == start => {
                        cycle = true;
                        break;
                    }
                    Some(n) if !seen[n.index()] => cur = n.index(),
                    _ => break,
                }
            }
            if cycle {
                on_cycle += 1;
            }
        }
        born + on_cycle
    }
}
