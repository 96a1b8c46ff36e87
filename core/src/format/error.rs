//! [`FormatError`]: why bytes are not a complex file, naming what and where.

#[cfg(feature = "alloc")]
use crate::partition::ComplexError;
use crate::scene::SceneError;

/// A part of a file (the header's parts bitset names the optional ones).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Part {
    /// The fixed-size header.
    Header,
    /// The scene: objects and their vertices.
    Scene,
    /// The complex: vertices (free bitangents) and cylinders.
    Complex,
    /// The history DAG of the randomized construction (optional).
    History,
}

impl Part {
    /// The name used in messages.
    pub fn name(self) -> &'static str {
        match self {
            Part::Header => "header",
            Part::Scene => "scene",
            Part::Complex => "complex",
            Part::History => "history",
        }
    }
}

/// An arena of a part: the elements are decoded one by one.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Arena {
    /// Scene objects (material and vertex count).
    Object,
    /// Scene vertices (points).
    Point,
    /// Complex vertices (directed free bitangents).
    Vertex,
    /// Cylinders.
    Cylinder,
    /// Vertices of the history (every free bitangent that ever bounded a cylinder).
    HistoryVertex,
    /// The region of a pruned complex (versions 2 and 4): its four coordinates.
    Region,
    /// History nodes (every cylinder that ever existed) and their child counts.
    Node,
    /// History links (child node ids).
    Link,
    /// Insertions of the randomized construction (object, first node).
    Insertion,
    /// Scratch slots for the open cylinders while a version-3 or 4 file's cylinders are
    /// replayed (`decode_into`'s `Scratch::open`).
    OpenSlot,
    /// The kept map of a version-4 file (one bit per replayed cylinder).
    KeptMap,
}

impl Arena {
    /// The name used in messages.
    pub fn name(self) -> &'static str {
        match self {
            Arena::Object => "object",
            Arena::Point => "scene vertex",
            Arena::Vertex => "complex vertex",
            Arena::Cylinder => "cylinder",
            Arena::HistoryVertex => "history part: vertex",
            Arena::Region => "region",
            Arena::Node => "history part: node",
            Arena::Link => "history part: link",
            Arena::Insertion => "history part: insertion",
            Arena::OpenSlot => "open-cylinder slot",
            Arena::KeptMap => "kept map",
        }
    }
}

/// What is wrong with one field of one element.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Problem {
    /// postcard cannot decode the field (the reason: a varint that does not end or
    /// overflows, or the part ends inside the field).
    Malformed(&'static str),
    /// The value must be below `limit` (ids, counts, discriminants) or in a documented
    /// range (coordinates, refractive indices).
    OutOfRange {
        /// The decoded value (an id, without the `+1` of optional fields).
        value: u64,
        /// The exclusive upper bound it breaks.
        limit: u64,
    },
    /// A coordinate or refractive index outside its range `[min, max]` (raw units).
    NotInRange {
        /// The decoded raw value.
        value: i64,
        /// Smallest allowed.
        min: i64,
        /// Largest allowed.
        max: i64,
    },
    /// A vertex count below 3.
    TooFewVertices(u32),
    /// A complex vertex whose two tangent vertices lie on the same object.
    SameObject,
    /// The line through the two tangent vertices is not tangent at this one.
    NotTangent,
    /// Complex vertices must be sorted by θ, strictly.
    NotSorted,
    /// The neighbour does not link back.
    NotSymmetric,
    /// The neighbour has a different floor, ceiling or shared wall.
    NeighbourMismatch,
    /// The right wall does not come after the left wall in θ.
    WallOrder,
    /// The cylinders of a version-3 file do not replay from its vertices (the reason).
    Replay(&'static str),
    /// The kept map of a version-4 file is wrong (the reason).
    KeptMap(&'static str),
}

impl core::fmt::Display for Problem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Problem::Malformed(why) => write!(f, "malformed ({why})"),
            Problem::OutOfRange { value, limit } => {
                write!(f, "{value} out of range (must be < {limit})")
            }
            Problem::NotInRange { value, min, max } => {
                write!(f, "{value} outside [{min}, {max}]")
            }
            Problem::TooFewVertices(k) => write!(f, "{k} vertices, a polygon needs at least 3"),
            Problem::SameObject => write!(f, "both tangent vertices on one object"),
            Problem::NotTangent => write!(f, "the line is not tangent there"),
            Problem::NotSorted => write!(f, "not after the previous vertex in θ"),
            Problem::NotSymmetric => write!(f, "the neighbour does not link back"),
            Problem::NeighbourMismatch => {
                write!(f, "the neighbour differs in floor, ceiling or wall")
            }
            Problem::WallOrder => write!(f, "the right wall is not after the left wall"),
            Problem::Replay(why) => write!(f, "the cylinders do not replay: {why}"),
            Problem::KeptMap(why) => write!(f, "wrong kept map: {why}"),
        }
    }
}

/// What is wrong with a count of the header.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum CountProblem {
    /// The elements cannot fit in their part: each takes at least `min_bytes` / count.
    ExceedsPart {
        /// Bytes the count needs at least.
        min_bytes: u64,
        /// Bytes the part has.
        part_bytes: u64,
    },
    /// Beyond what a scene or complex may hold.
    ExceedsLimit {
        /// The largest allowed value.
        limit: u64,
    },
    /// Breaks `cylinders = 3·objects + 1 + 3·complex vertices` (`≤` for a complex pruned
    /// to a region) or `scene vertices ≥ 3·objects`.
    Inconsistent,
    /// Non-zero although what it describes is absent (a part, or the seed).
    MustBeZero,
}

/// Why bytes are not a valid complex file. Every variant says where: a byte offset, a
/// part, an element index and field.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[non_exhaustive]
pub enum FormatError {
    /// Fewer bytes than the fixed-size header (or than magic and version).
    TooShort {
        /// Bytes given.
        len: usize,
        /// Bytes needed.
        needed: usize,
    },
    /// The file does not start with the magic bytes `VCX\0`.
    BadMagic {
        /// The first four bytes.
        found: [u8; 4],
    },
    /// A format version this reader does not know (nothing after the version is read).
    UnsupportedVersion {
        /// The version in the file.
        found: u16,
        /// The newest version this reader supports (it reads versions 1 to this).
        supported: u16,
    },
    /// A version-2 file without the region flag (version 2 exists only for complexes
    /// pruned to a region; anything else is written as version 1).
    RegionFlagMissing,
    /// Option flags this version does not define.
    UnknownFlags {
        /// The unknown bits.
        bits: u16,
    },
    /// Parts this version does not define.
    UnknownParts {
        /// The unknown bits.
        bits: u32,
    },
    /// A part every file of this version must have.
    MissingPart {
        /// The part.
        part: Part,
    },
    /// A part this reader knows but cannot load (not produced by version-1 readers, which
    /// load every part they define; kept for tools).
    UnsupportedPart {
        /// The part.
        part: Part,
    },
    /// A count of the header that cannot be right.
    Count {
        /// The header field.
        field: &'static str,
        /// Its byte offset.
        offset: usize,
        /// Its value.
        count: u64,
        /// Why.
        problem: CountProblem,
    },
    /// The file length disagrees with the header (truncated, or bytes appended).
    Length {
        /// Bytes given.
        len: usize,
        /// Bytes the header describes.
        expected: u64,
    },
    /// The CRC-32 at the end does not match the bytes before it.
    Checksum {
        /// Byte offset of the stored checksum.
        offset: usize,
        /// The stored value.
        stored: u32,
        /// The value computed from the bytes.
        computed: u32,
    },
    /// One field of one element is wrong.
    Element {
        /// The arena.
        arena: Arena,
        /// The element's index in its arena.
        index: usize,
        /// The field's name.
        field: &'static str,
        /// Byte offset of the field (of the element for checks across elements).
        offset: usize,
        /// What is wrong.
        problem: Problem,
    },
    /// The elements of a part do not end where the header says the part ends.
    PartSize {
        /// The part.
        part: Part,
        /// Byte offset of the part's end by the header.
        end: usize,
        /// Byte offset where its elements ended.
        used: usize,
    },
    /// The scene part decodes but is not a valid scene.
    Scene {
        /// Byte offset of the scene part.
        offset: usize,
        /// Why (object and vertex ids as stored in the file).
        error: SceneError,
    },
    /// The complex part decodes, every id is in range, but it is not a consistent complex.
    #[cfg(feature = "alloc")]
    Complex {
        /// Byte offset of the complex part.
        offset: usize,
        /// Why.
        error: ComplexError,
    },
    /// The history part decodes, every id is in range, but it is not a valid history of
    /// this scene and complex (`History::from_parts` refused it: a cycle, a node no link
    /// reaches, leaves that are not the live cylinders, …), or its live cylinders differ
    /// from the complex part.
    #[cfg(feature = "alloc")]
    History {
        /// Byte offset of the history part.
        offset: usize,
        /// Why.
        error: ComplexError,
    },
    /// Caller-provided storage is too small for an arena (sizes come from the header).
    Capacity {
        /// The arena.
        arena: Arena,
        /// Elements in the file.
        needed: usize,
        /// Elements the storage holds.
        capacity: usize,
    },
    /// Encoding: the output buffer is too small.
    BufferTooSmall {
        /// Bytes needed so far when it ran out (at least).
        needed: usize,
        /// Bytes given.
        capacity: usize,
    },
    /// Encoding: the input cannot be written (why).
    NotEncodable(&'static str),
}

impl core::error::Error for FormatError {}

impl core::fmt::Display for FormatError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            FormatError::TooShort { len, needed } => {
                write!(f, "file is {len} bytes, a header needs {needed}")
            }
            FormatError::BadMagic { found } => write!(
                f,
                "bad magic {found:02x?} at byte 0 (not a vcx complex file, which starts with \"VCX\\0\")"
            ),
            FormatError::UnsupportedVersion { found, supported } => write!(
                f,
                "format version {found} at byte 4 is not supported (this reader supports versions 1 to {supported})"
            ),
            FormatError::RegionFlagMissing => write!(
                f,
                "format version 2 at byte 4 without the region flag (bit 2 of the flags at byte 6)"
            ),
            FormatError::UnknownFlags { bits } => {
                write!(f, "unknown option flags {bits:#06x} at byte 6")
            }
            FormatError::UnknownParts { bits } => {
                write!(f, "unknown parts {bits:#010x} at byte 8")
            }
            FormatError::MissingPart { part } => {
                write!(f, "the {} part is missing (parts at byte 8)", part.name())
            }
            FormatError::UnsupportedPart { part } => write!(
                f,
                "the {} part is not supported by this reader (parts at byte 8)",
                part.name()
            ),
            FormatError::Count {
                field,
                offset,
                count,
                problem,
            } => {
                // The history part's vertex count is a prefix of that part.
                let place = if offset < super::HEADER_LEN {
                    "header"
                } else {
                    "history part"
                };
                write!(f, "{place}: {field} {count} (byte {offset}) ")?;
                match problem {
                    CountProblem::ExceedsPart {
                        min_bytes,
                        part_bytes,
                    } => write!(
                        f,
                        "needs at least {min_bytes} bytes, its part has {part_bytes}"
                    ),
                    CountProblem::ExceedsLimit { limit } => write!(f, "exceeds the limit {limit}"),
                    CountProblem::Inconsistent => write!(f, "is inconsistent with the other counts"),
                    CountProblem::MustBeZero => write!(f, "must be 0: what it describes is absent"),
                }
            }
            FormatError::Length { len, expected } => {
                write!(f, "file is {len} bytes, the header describes {expected} (truncated or extended)")
            }
            FormatError::Checksum {
                offset,
                stored,
                computed,
            } => write!(
                f,
                "checksum mismatch: stored {stored:#010x} at byte {offset}, computed {computed:#010x} (corrupt file)"
            ),
            FormatError::Element {
                arena,
                index,
                field,
                offset,
                problem,
            } => write!(
                f,
                "{} {index}: {field} {problem} (byte {offset})",
                arena.name()
            ),
            FormatError::PartSize { part, end, used } => write!(
                f,
                "{} part: its elements end at byte {used}, the header says byte {end}",
                part.name()
            ),
            FormatError::Scene { offset, error } => {
                write!(f, "scene part (byte {offset}): {error}")
            }
            #[cfg(feature = "alloc")]
            FormatError::Complex { offset, error } => {
                write!(f, "complex part (byte {offset}): {error}")
            }
            #[cfg(feature = "alloc")]
            FormatError::History { offset, error } => {
                write!(f, "history part (byte {offset}): {error}")
            }
            FormatError::Capacity {
                arena,
                needed,
                capacity,
            } => write!(
                f,
                "storage for {}s holds {capacity}, the file has {needed}",
                arena.name()
            ),
            FormatError::BufferTooSmall { needed, capacity } => write!(
                f,
                "output buffer of {capacity} bytes is too small (needs at least {needed})"
            ),
            FormatError::NotEncodable(why) => write!(f, "cannot encode: {why}"),
        }
    }
}
