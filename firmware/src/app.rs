//! The walk the firmware runs, shared verbatim with the host test `tests/tests/no_alloc.rs`
//! (which includes this file), so the host checks the exact code path the device runs: no
//! std, no heap, no recursion.
//!
//! The data comes from `scene_data.rs` (generated, checked for staleness by the host test):
//! the scene's polygons, the complex's vertices and cylinders as statics in flash, and the
//! viewpoints. [`complex`] takes the vertices and cylinders as slices, so when the device
//! format lands they come from `decode_into` of an `include_bytes!` blob into RAM buffers
//! instead, and nothing else changes.

use vcx::geom::sos::Angle;
use vcx::geom::QueryPoint;
use vcx::partition::{
    BorderBuffers, BorderSizes, BufferTooSmall, Complex, Cylinder, CylinderId, Slices, Vertex,
};
use vcx::scene::FixedScene;
use vcx::walk::{view_capacity, view_into, ViewInterval, WalkError};
use vcx::{SceneError, SceneRef};

use crate::scene_data as data;

/// Whether vertex angles are kept in RAM (`size_of::<Angle>()` bytes per complex vertex)
/// or computed when a walk meets a wall (slower walks, less RAM).
pub const WITH_ANGLES: bool = false;

/// Sizes of the derived-state buffers, from the counts alone.
pub const SIZES: BorderSizes =
    BorderSizes::for_counts(data::OBJECTS, data::COMPLEX_VERTICES, data::CYLINDERS);
/// Length of the angle buffer (0: computed on demand).
pub const ANGLES: usize = if WITH_ANGLES { SIZES.angles } else { 0 };
/// Intervals the output buffer holds: enough for any view of the scene.
pub const CAPACITY: usize = view_capacity(data::OBJECTS);

/// The validated scene, in fixed-capacity storage.
pub type Scene = FixedScene<{ data::SCENE_VERTICES }, { data::OBJECTS }>;

/// The derived state of the complex: all zero at start, so a `static` of it lands in
/// `.bss` (no flash image).
#[derive(Debug)]
pub struct Ram {
    /// Vertex angles (empty unless [`WITH_ANGLES`]).
    pub angles: [Angle; ANGLES],
    /// Tiling cylinder ids.
    pub ids: [CylinderId; SIZES.ids],
    /// Tiling offsets.
    pub offsets: [u32; SIZES.offsets],
    /// Start indices across arcs.
    pub start: [[[u32; 2]; 2]; SIZES.start],
}

impl Ram {
    /// Zeroed buffers.
    pub const fn new() -> Ram {
        Ram {
            angles: [Angle::ZERO; ANGLES],
            ids: [CylinderId::ZERO; SIZES.ids],
            offsets: [0; SIZES.offsets],
            start: [[[0; 2]; 2]; SIZES.start],
        }
    }
}

/// The output buffer of a view.
pub type Out = [ViewInterval; CAPACITY];

/// An empty output buffer.
pub const fn out() -> Out {
    [ViewInterval {
        start: Angle::ZERO,
        object: None,
        start_vertex: None,
    }; CAPACITY]
}

/// What can go wrong on the device.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Error {
    /// The embedded scene does not validate.
    Scene(SceneError),
    /// A derived-state buffer is too short.
    Buffers(BufferTooSmall),
    /// The walk failed.
    Walk(WalkError),
    /// An embedded viewpoint is out of the query range.
    Viewpoint(usize),
    /// A static buffer was taken twice.
    Taken,
}

/// Validates the embedded scene into fixed-capacity storage. (`inline(never)` here and
/// below: the firmware measures each phase's stack below `main`.)
#[inline(never)]
pub fn scene() -> Result<Scene, Error> {
    Scene::new(data::POLYGONS.iter().map(|&(m, p)| (m, p))).map_err(Error::Scene)
}

/// The complex over `vertices` and `cylinders` (statics in flash here), with its derived
/// state rebuilt into `ram`.
#[inline(never)]
pub fn complex<'a>(
    scene: &SceneRef<'_>,
    vertices: &'a [Vertex],
    cylinders: &'a [Cylinder],
    ram: &'a mut Ram,
) -> Result<Complex<Slices<'a>>, Error> {
    let buffers = BorderBuffers {
        angles: &mut ram.angles,
        ids: &mut ram.ids,
        offsets: &mut ram.offsets,
        start: &mut ram.start,
    };
    Complex::from_slices(scene, vertices, cylinders, buffers).map_err(Error::Buffers)
}

/// Walks the view from every embedded viewpoint into `out`, calling `each` with the
/// viewpoint's index and its intervals. Returns a checksum of the views.
#[inline(never)]
pub fn views(
    complex: &Complex<Slices<'_>>,
    scene: &SceneRef<'_>,
    out: &mut Out,
    mut each: impl FnMut(usize, &[ViewInterval]),
) -> Result<u32, Error> {
    let mut checksum = 0u32;
    for (k, &(x, y)) in data::VIEWPOINTS.iter().enumerate() {
        let q = QueryPoint::from_raw(x, y).ok_or(Error::Viewpoint(k))?;
        let n = view_into(complex, scene, q, out).map_err(Error::Walk)?;
        let view = out.get(..n).unwrap_or(&[]);
        for i in view {
            let object = i.object.map_or(0xffff, |o| o.0);
            checksum = checksum.rotate_left(5) ^ object;
        }
        each(k, view);
    }
    Ok(checksum)
}
