//! The walk the firmware runs, shared verbatim with the host test `tests/tests/no_alloc.rs`
//! (which includes this file), so the host checks the exact code path the device runs: no
//! std, no heap, no recursion.
//!
//! The complex is the file `firmware/hall.vcx` (`docs/format.md`), embedded with
//! `include_bytes!` and trusted in nothing: [`decode`] checks it with
//! `format::decode_into` into static buffers ([`Arenas`]: the scene part's scratch, the
//! complex's vertices and cylinders), [`complex`] rebuilds the derived state into [`Ram`]
//! with `Complex::from_slices`, and [`views`] walks the view from each viewpoint of
//! `viewpoints.rs` (generated, as the `.vcx` is, and checked for staleness by the host
//! test). The buffer sizes are the file's header counts, read at compile time.
//!
//! [`trees`] then walks a ray-tree frame from each viewpoint: a camera of [`COLUMNS`]
//! columns and a 90° field of view along [`heading`], the tree of depth [`TREE_DEPTH`]
//! streamed by `walk::frame_tree_into` through a [`TreeRam`] (the generations in lock step)
//! into a [`Frame`] of `render::FrameInterval`s, put in start-angle order and covered
//! column by column (`render::coverage`).

use vcx::format::{self, Decoded, FormatError, SceneObject, Scratch};
use vcx::geom::sos::Angle;
use vcx::geom::{Point, QueryPoint};
use vcx::line_space::{Bound, Chain};
use vcx::partition::{
    BorderBuffers, BorderSizes, BufferTooSmall, Complex, Cylinder, CylinderId, Slices, Slots,
    Vertex, ZERO_SLOTS,
};
use vcx::render::{angle_order, coverage, Camera, FrameInterval, RenderError};
use vcx::walk::{frame_tree_into, view_capacity, view_into, TreeScratch, ViewInterval, WalkError};
use vcx::{ObjectId, SceneRef};

use crate::viewpoints::VIEWPOINTS;

/// The embedded file, as `vcx build std-demo/scenes/hall.json -o firmware/hall.vcx
/// --history never` writes it (the host test checks that it is). Postcard needs no
/// alignment.
const FILE: &[u8] = include_bytes!("../hall.vcx");

/// The embedded file: one copy in flash (a `static`, where each use of the `const` could
/// be its own).
pub static VCX: &[u8] = FILE;

/// A `u32` header field of the embedded file, at compile time (0 if the file is too short:
/// then `decode_into` reports it, at run time, as the error it is).
const fn header(offset: usize) -> usize {
    match FILE.split_at_checked(offset) {
        Some((_, rest)) => match rest.first_chunk::<4>() {
            Some(b) => u32::from_le_bytes(*b) as usize,
            None => 0,
        },
        None => 0,
    }
}

/// Objects of the scene (the header's count).
pub const OBJECTS: usize = header(format::offset::OBJECTS);
/// Vertices of the scene.
pub const SCENE_VERTICES: usize = header(format::offset::SCENE_VERTICES);
/// Vertices of the complex.
pub const COMPLEX_VERTICES: usize = header(format::offset::COMPLEX_VERTICES);
/// Cylinders of the complex.
pub const CYLINDERS: usize = header(format::offset::CYLINDERS);

/// Whether vertex angles are kept in RAM (`size_of::<Angle>()` bytes per complex vertex)
/// or computed when a walk meets a wall (slower walks, less RAM).
pub const WITH_ANGLES: bool = false;

/// Sizes of the derived-state buffers, from the counts alone.
pub const SIZES: BorderSizes = BorderSizes::for_counts(OBJECTS, COMPLEX_VERTICES, CYLINDERS);
/// Length of the angle buffer (0: computed on demand).
pub const ANGLES: usize = if WITH_ANGLES { SIZES.angles } else { 0 };
/// Intervals the output buffer holds: enough for any view of the scene.
pub const CAPACITY: usize = view_capacity(OBJECTS);

/// The decoded file: the scene (validated into fixed-capacity storage) and the complex's
/// arenas, borrowed from [`Arenas`].
pub type File<'a> = Decoded<'a, SCENE_VERTICES, OBJECTS>;

/// A blank point (checked when compiled: (0, 0) is in range).
const ORIGIN: Point = match Point::from_raw(0, 0) {
    Some(p) => p,
    None => panic!("(0, 0) is a point"),
};

/// A blank cylinder of all-zero bytes, so that a `static` of [`Arenas`] lands in `.bss`
/// rather than in `.data` with a flash image of blanks: `format::BLANK_CYLINDER` has no
/// chains, and `None` of a chain is a niche value of its bound (2), not 0.
const ZERO_CYLINDER: Cylinder = Cylinder {
    bottom: Some(CHAIN_ZERO),
    top: Some(CHAIN_ZERO),
    ..format::BLANK_CYLINDER
};
const CHAIN_ZERO: Chain = Chain {
    object: ObjectId(0),
    bound: Bound::Lower,
};

/// What `decode_into` fills: the scratch of the scene part and of the replay of the
/// cylinders (free again after decoding) and the complex's vertices and cylinders, which
/// the walk reads. Blank at start.
#[derive(Debug)]
pub struct Arenas {
    /// Objects of the scene part (scratch).
    pub objects: [SceneObject; OBJECTS],
    /// Points of the scene part (scratch).
    pub points: [Point; SCENE_VERTICES],
    /// The open cylinders while the cylinders are replayed (scratch).
    pub open: [Slots; Scratch::open_len(OBJECTS)],
    /// Vertices of the complex.
    pub vertices: [Vertex; COMPLEX_VERTICES],
    /// Cylinders of the complex.
    pub cylinders: [Cylinder; CYLINDERS],
}

impl Arenas {
    /// Blank buffers.
    pub const fn new() -> Arenas {
        Arenas {
            objects: [SceneObject::BLANK; OBJECTS],
            points: [ORIGIN; SCENE_VERTICES],
            open: [ZERO_SLOTS; Scratch::open_len(OBJECTS)],
            vertices: [format::BLANK_VERTEX; COMPLEX_VERTICES],
            cylinders: [ZERO_CYLINDER; CYLINDERS],
        }
    }
}

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
    /// The embedded file does not decode (or its scene does not validate).
    Format(FormatError),
    /// A derived-state buffer is too short.
    Buffers(BufferTooSmall),
    /// The walk failed.
    Walk(WalkError),
    /// An embedded viewpoint is out of the query range.
    Viewpoint(usize),
    /// A static buffer was taken twice.
    Taken,
    /// The camera of a ray-tree frame could not be made.
    Camera(RenderError),
    /// A ray-tree frame has more intervals than [`FRAME_CAPACITY`].
    FrameFull,
    /// A ray-tree interval's branch is longer than `render::MAX_BRANCH`.
    BranchTooLong,
}

/// Decodes and checks `bytes` (the embedded [`VCX`] on the device) into `arenas`: the
/// scene validated into fixed-capacity storage, the complex's vertices and cylinders with
/// every id and link checked. (`inline(never)` here and below: the firmware measures each
/// phase's stack below `main`.)
#[inline(never)]
pub fn decode<'a>(bytes: &[u8], arenas: &'a mut Arenas) -> Result<File<'a>, Error> {
    let scratch = Scratch {
        objects: &mut arenas.objects,
        points: &mut arenas.points,
        open: &mut arenas.open,
    };
    format::decode_into(bytes, scratch, &mut arenas.vertices, &mut arenas.cylinders)
        .map_err(Error::Format)
}

/// The complex over the decoded `vertices` and `cylinders`, with its derived state rebuilt
/// into `ram`.
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
    for (k, &(x, y)) in VIEWPOINTS.iter().enumerate() {
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

/// Depth of the ray trees: four bounces. The hall's four walls are mirrors, so nearly every
/// ray is reflected to the full depth, and the intervals of a frame multiply with it (see
/// [`FRAME_CAPACITY`]).
pub const TREE_DEPTH: usize = 4;

/// Walks of the tree walk's stack: the primary walk, then one per level (the reflected
/// walk behind a mirror). The hall has mirrors and opaque objects only — no screens (a
/// walk each) — so `depth + 1` suffices; a file that needs more is a
/// `WalkError::TreeTooDeep`, and the host test checks that one fewer is too few.
pub const TREE_WALKS: usize = TREE_DEPTH + 1;

/// Splits of the tree walk's stack: one per level for a mirror (refraction would need two,
/// an entry and an exit split); the host test checks that one fewer is too few.
pub const TREE_SPLITS: usize = TREE_DEPTH;

/// Changes of eye the tree walk holds at once: one per split (`TreeScratch`'s default).
pub const TREE_HOPS: usize = TREE_SPLITS;

/// The ray tree's working memory.
pub type TreeRam = TreeScratch<TREE_WALKS, TREE_SPLITS, TREE_HOPS>;

/// Columns of a frame.
pub const COLUMNS: usize = 64;

/// Field of view of a frame: 90°.
pub const FOV: f64 = core::f64::consts::FRAC_PI_2;

/// Intervals a frame holds: the six frames have at most 83, a frame of any heading (every
/// 5°) from the six viewpoints at most 104 (`firmware_trees_match_owned_frame_tree` prints
/// both and checks the second against this). Their number grows by about 15 per level of
/// depth here; a frame with more is [`Error::FrameFull`].
pub const FRAME_CAPACITY: usize = 128;

/// The intervals of a ray-tree frame.
pub type Frame = heapless::Vec<FrameInterval, FRAME_CAPACITY>;

/// The heading of the camera at viewpoint `k`, in radians: a sixth of a turn apart, so the
/// six frames look every way.
pub fn heading(k: usize) -> f64 {
    0.25 + k as f64 * (core::f64::consts::TAU / 6.0)
}

/// Walks the ray-tree frame from every embedded viewpoint ([`heading`], [`FOV`],
/// [`COLUMNS`], [`TREE_DEPTH`]) into `frame`, in start-angle order, and covers its columns;
/// calls `each` with the viewpoint's index, its camera, its intervals and the sum of the
/// coverage fractions (one per column). Returns a checksum of the branches and the pieces.
#[inline(never)]
pub fn trees(
    complex: &Complex<Slices<'_>>,
    scene: &SceneRef<'_>,
    scratch: &mut TreeRam,
    frame: &mut Frame,
    mut each: impl FnMut(usize, &Camera, &[FrameInterval], f64),
) -> Result<u32, Error> {
    let mut checksum = 0u32;
    for (k, &(x, y)) in VIEWPOINTS.iter().enumerate() {
        let q = QueryPoint::from_raw(x, y).ok_or(Error::Viewpoint(k))?;
        let camera = Camera::new(q, heading(k), FOV, COLUMNS).map_err(Error::Camera)?;
        let (from, to) = camera.range();
        frame.clear();
        // The first failure to keep a span; the walk runs on (it cannot be stopped from
        // here), keeping nothing more.
        let mut kept = Ok(());
        frame_tree_into(complex, scene, q, TREE_DEPTH, from, to, scratch, |span| {
            if kept.is_ok() {
                kept = match FrameInterval::new(&span) {
                    Some(i) => frame.push(i).map_err(|_| Error::FrameFull),
                    None => Err(Error::BranchTooLong),
                };
            }
        })
        .map_err(Error::Walk)?;
        kept?;
        angle_order(frame.as_mut_slice());
        for i in frame.iter() {
            for o in &i.branch {
                checksum = checksum.rotate_left(5) ^ o.0;
            }
            checksum = checksum.rotate_left(5) ^ 0xffff;
        }
        let mut covered = 0.0;
        coverage(&camera, frame, |p| {
            covered += p.fraction;
            checksum = checksum.rotate_left(5) ^ ((p.column as u32) << 16 | p.interval as u32);
        });
        each(k, &camera, frame, covered);
    }
    Ok(checksum)
}
