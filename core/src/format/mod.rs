//! The versioned binary complex format: build offline, walk on the device (DESIGN.md §7).
//!
//! The layout is specified in `docs/format.md`; in short:
//!
//! ```text
//! 0    header   56 bytes, fixed layout, little endian: magic "VCX\0", version, flags,
//!               parts bitset, counts, seed, byte length of each part
//! 56   scene    objects (material, vertex count), then vertices as written   (postcard)
//! ..   complex  vertices (two tangent vertices), then cylinders (8 ids each)  (postcard)
//!               or, version 3, only the 3n + 1 cylinders at θ = 0 (4 ids each): the
//!               reader replays the rest from the vertices (`partition::replay`);
//!               version 4: region, vertex count, version 3's data, kept map (bits)
//! ..   history  optional: vertex count, then history vertices, nodes (cylinders), child
//!               counts, links, insertions (object, first node)          (postcard)
//! end-4         CRC-32/IEEE of every byte before it, little endian
//! ```
//!
//! **No trust in the bytes.** [`Header::read`] checks magic, version, known flags and
//! parts, every count against its part's byte length (before anything is reserved: an
//! inflated count is an error, not an allocation), the file length and the checksum.
//! The arenas are then decoded element by element, field by field, with
//! `postcard::take_from_bytes`, each id checked against its arena as it is read; links
//! between elements (neighbours, θ order of the vertices, tangency of every bitangent) are
//! checked after; derived state (the adjacency across chains, vertex angles, and in
//! version 3 all cylinders but those at θ = 0) is rebuilt, never read. Every failure is a [`FormatError`] naming the part, element, field and byte
//! offset.
//!
//! Storage: [`decode_into`] fills caller-provided slices sized from the header (no heap;
//! the scene goes into a [`FixedScene`]); under `alloc`, [`decode`] allocates and returns
//! a validated [`Complex`](crate::partition::Complex), built by
//! [`Complex::from_parts`](crate::partition::Complex::from_parts) — after which a walk
//! cannot index out of bounds or loop forever — and the history, if stored, through
//! `History::from_parts`. [`decode_into`] skips the history part (devices walk without
//! it; the checksum still covers it). [`encode_into`] writes into a caller's buffer
//! (no history); [`encode`] allocates and writes the history if given one.

mod crc;
mod decode;
mod encode;
mod error;

pub use crc::crc32;
#[cfg(feature = "alloc")]
pub use decode::{decode, Loaded};
pub use decode::{decode_into, Decoded, SceneObject, Scratch, BLANK_CYLINDER, BLANK_VERTEX};
#[cfg(feature = "alloc")]
pub use encode::{encode, encode_history_parts, encode_region};
pub use encode::{encode_into, encoded_len, EncodeOptions};
pub use error::{Arena, CountProblem, FormatError, Part, Problem};

#[allow(unused_imports)] // for the docs
use crate::scene::FixedScene;

/// The first four bytes of every file.
pub const MAGIC: [u8; 4] = *b"VCX\0";
/// The format version this code writes for a complex of the whole scene (and reads).
pub const VERSION: u16 = 1;
/// The format version of a complex pruned to a region (`vcx build --region`): version 1
/// plus flag bit 2 and the region at the start of the complex part, every kept cylinder
/// stored. Written only for such complexes and only with
/// [`EncodeOptions::explicit_cylinders`] (by default they are [`VERSION_PRUNED`]).
pub const VERSION_REGION: u16 = 2;
/// The format version of a whole complex written without history (the default of
/// [`encode`] and [`encode_into`]): version 1 with only the cylinders at θ = 0 stored
/// (floor, ceiling, bottom, top); the reader replays the others from the vertices
/// (`partition::replay`, the rotational sweep's event loop). Never has a history part.
pub const VERSION_REPLAY: u16 = 3;
/// The format version of a complex pruned to a region written without history (the
/// default of [`encode`] for such a complex): version 3 of the whole complex (plus the
/// count of its vertices) with the region first and, last, the kept map: one bit per
/// replayed cylinder. The reader replays the whole complex but stores only the kept
/// cylinders and the vertices their walls name (`partition::replay`, streaming).
pub const VERSION_PRUNED: u16 = 4;
/// Bytes of the fixed-size header.
pub const HEADER_LEN: usize = 56;
/// Bytes of the checksum at the end.
pub const CHECKSUM_LEN: usize = 4;

/// Flag bit: the header's `seed` field holds the seed of the randomized construction.
pub const FLAG_SEED: u16 = 1 << 0;
/// Flag bit: the history is search-path compacted (§4.4 of the paper).
pub const FLAG_COMPACTED: u16 = 1 << 1;
/// Flag bit (versions 2 and 4): the complex is pruned to a region of viewpoints, stored at the
/// start of the complex part.
pub const FLAG_REGION: u16 = 1 << 2;
/// Every flag bit version 1 defines.
pub const KNOWN_FLAGS: u16 = FLAG_SEED | FLAG_COMPACTED;
/// Every flag bit versions 2 and 4 define.
pub const KNOWN_FLAGS_V2: u16 = KNOWN_FLAGS | FLAG_REGION;

/// Part bit: the scene.
pub const PART_SCENE: u32 = 1 << 0;
/// Part bit: the complex.
pub const PART_COMPLEX: u32 = 1 << 1;
/// Part bit: the history DAG of the randomized construction (optional).
pub const PART_HISTORY: u32 = 1 << 2;
/// Every part bit version 1 defines.
pub const KNOWN_PARTS: u32 = PART_SCENE | PART_COMPLEX | PART_HISTORY;
/// Every part bit version 3 defines (no history).
pub const KNOWN_PARTS_V3: u32 = PART_SCENE | PART_COMPLEX;

/// Smallest encoding of one element of each arena, in bytes: a count larger than its
/// part's length divided by this is rejected before anything is reserved.
pub const MIN_OBJECT_BYTES: u64 = 2;
/// See [`MIN_OBJECT_BYTES`]: two coordinates of at least one byte.
pub const MIN_POINT_BYTES: u64 = 2;
/// See [`MIN_OBJECT_BYTES`]: two vertex indices.
pub const MIN_VERTEX_BYTES: u64 = 2;
/// See [`MIN_OBJECT_BYTES`]: eight ids.
pub const MIN_CYLINDER_BYTES: u64 = 8;
/// See [`MIN_OBJECT_BYTES`]: a cylinder at θ = 0 of version 3 is four ids.
pub const MIN_INITIAL_CYLINDER_BYTES: u64 = 4;
/// See [`MIN_OBJECT_BYTES`]: a history node is a cylinder and its child count.
pub const MIN_NODE_BYTES: u64 = MIN_CYLINDER_BYTES + 1;
/// See [`MIN_OBJECT_BYTES`]: a link is one node id.
pub const MIN_LINK_BYTES: u64 = 1;
/// See [`MIN_OBJECT_BYTES`]: an insertion is an object and its first node.
pub const MIN_INSERTION_BYTES: u64 = 2;
/// See [`MIN_OBJECT_BYTES`]: the history part's vertex count prefix.
pub const MIN_HISTORY_PREFIX_BYTES: u64 = 1;
/// See [`MIN_OBJECT_BYTES`]: the region's four coordinates (versions 2 and 4, flag bit 2).
pub const MIN_REGION_BYTES: u64 = 4;
/// See [`MIN_OBJECT_BYTES`]: what version 4 adds to version 3 besides the region and the
/// vertices the region drops: the vertex count and the kept map's length prefix.
pub const MIN_PRUNED_EXTRA_BYTES: u64 = 2;

/// Byte offsets of the header fields (`docs/format.md`, table "Header").
pub mod offset {
    /// `[u8; 4]` magic.
    pub const MAGIC: usize = 0;
    /// `u16` format version.
    pub const VERSION: usize = 4;
    /// `u16` option flags.
    pub const FLAGS: usize = 6;
    /// `u32` parts bitset.
    pub const PARTS: usize = 8;
    /// `u32` scene objects.
    pub const OBJECTS: usize = 12;
    /// `u32` scene vertices.
    pub const SCENE_VERTICES: usize = 16;
    /// `u32` complex vertices.
    pub const COMPLEX_VERTICES: usize = 20;
    /// `u32` cylinders.
    pub const CYLINDERS: usize = 24;
    /// `u32` history nodes.
    pub const HISTORY_NODES: usize = 28;
    /// `u32` history links.
    pub const HISTORY_LINKS: usize = 32;
    /// `u64` construction seed.
    pub const SEED: usize = 36;
    /// `u32` bytes of the scene part.
    pub const SCENE_BYTES: usize = 44;
    /// `u32` bytes of the complex part.
    pub const COMPLEX_BYTES: usize = 48;
    /// `u32` bytes of the history part.
    pub const HISTORY_BYTES: usize = 52;
}

/// The header of a file: counts and options, read and checked before any arena.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Header {
    /// Format version ([`VERSION`], [`VERSION_REGION`] for a pruned complex,
    /// [`VERSION_REPLAY`] for replayed cylinders, [`VERSION_PRUNED`] for both).
    pub version: u16,
    /// Parts bitset ([`PART_SCENE`], [`PART_COMPLEX`], [`PART_HISTORY`]).
    pub parts: u32,
    /// Seed of the randomized construction that built the complex, if recorded.
    pub seed: Option<u64>,
    /// Whether the history is search-path compacted (meaningful with a history).
    pub compacted: bool,
    /// Whether the complex is pruned to a region (versions 2 and 4, flag bit 2); the
    /// region is the start of the complex part.
    pub region: bool,
    /// Scene objects.
    pub objects: u32,
    /// Scene vertices (all objects).
    pub scene_vertices: u32,
    /// Complex vertices (directed free bitangents); version 4: those kept (the file
    /// stores all, counted in the complex part).
    pub complex_vertices: u32,
    /// Cylinders; version 4: those kept.
    pub cylinders: u32,
    /// History nodes (0 without history).
    pub history_nodes: u32,
    /// History links (0 without history).
    pub history_links: u32,
    /// Bytes of the scene part.
    pub scene_bytes: u32,
    /// Bytes of the complex part.
    pub complex_bytes: u32,
    /// Bytes of the history part (0 without history).
    pub history_bytes: u32,
}

/// Little-endian field readers over a slice known to hold the whole header.
fn le_u16(b: &[u8], at: usize) -> u16 {
    let mut a = [0u8; 2];
    if let Some(s) = b.get(at..at + 2) {
        a.copy_from_slice(s);
    }
    u16::from_le_bytes(a)
}

fn le_u32(b: &[u8], at: usize) -> u32 {
    let mut a = [0u8; 4];
    if let Some(s) = b.get(at..at + 4) {
        a.copy_from_slice(s);
    }
    u32::from_le_bytes(a)
}

fn le_u64(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    if let Some(s) = b.get(at..at + 8) {
        a.copy_from_slice(s);
    }
    u64::from_le_bytes(a)
}

impl Header {
    /// Reads and checks the header of a whole file: magic, version (an unknown one is
    /// [`FormatError::UnsupportedVersion`], and nothing after it is read), flags and parts
    /// this version defines, every count against its limit and its part's length, the
    /// file length, and the checksum. Touches no arena; allocates nothing.
    pub fn read(bytes: &[u8]) -> Result<Header, FormatError> {
        let h = Header::read_unchecked(bytes)?;
        h.check_length(bytes.len())?;
        check_checksum(bytes)?;
        Ok(h)
    }

    /// [`Header::read`] without the file length and checksum (for tools that show a
    /// damaged file's header). Still checks magic, version, flags, parts and counts.
    pub fn read_unchecked(bytes: &[u8]) -> Result<Header, FormatError> {
        let too_short = |needed| FormatError::TooShort {
            len: bytes.len(),
            needed,
        };
        let magic = bytes.get(..4).ok_or(too_short(4))?;
        if magic != MAGIC {
            let mut found = [0u8; 4];
            found.copy_from_slice(magic);
            return Err(FormatError::BadMagic { found });
        }
        if bytes.len() < offset::FLAGS {
            return Err(too_short(offset::FLAGS));
        }
        let version = le_u16(bytes, offset::VERSION);
        if !(VERSION..=VERSION_PRUNED).contains(&version) {
            return Err(FormatError::UnsupportedVersion {
                found: version,
                supported: VERSION_PRUNED,
            });
        }
        if bytes.len() < HEADER_LEN + CHECKSUM_LEN {
            return Err(too_short(HEADER_LEN + CHECKSUM_LEN));
        }
        let flags = le_u16(bytes, offset::FLAGS);
        let with_region = version == VERSION_REGION || version == VERSION_PRUNED;
        let known = if with_region {
            KNOWN_FLAGS_V2
        } else {
            KNOWN_FLAGS
        };
        if flags & !known != 0 {
            return Err(FormatError::UnknownFlags {
                bits: flags & !known,
            });
        }
        if with_region && flags & FLAG_REGION == 0 {
            return Err(FormatError::RegionFlagMissing);
        }
        let parts = le_u32(bytes, offset::PARTS);
        let known = if version == VERSION_REPLAY || version == VERSION_PRUNED {
            KNOWN_PARTS_V3
        } else {
            KNOWN_PARTS
        };
        if parts & !known != 0 {
            return Err(FormatError::UnknownParts {
                bits: parts & !known,
            });
        }
        for (bit, part) in [(PART_SCENE, Part::Scene), (PART_COMPLEX, Part::Complex)] {
            if parts & bit == 0 {
                return Err(FormatError::MissingPart { part });
            }
        }
        let seed_raw = le_u64(bytes, offset::SEED);
        let h = Header {
            version,
            parts,
            seed: (flags & FLAG_SEED != 0).then_some(seed_raw),
            compacted: flags & FLAG_COMPACTED != 0,
            region: flags & FLAG_REGION != 0,
            objects: le_u32(bytes, offset::OBJECTS),
            scene_vertices: le_u32(bytes, offset::SCENE_VERTICES),
            complex_vertices: le_u32(bytes, offset::COMPLEX_VERTICES),
            cylinders: le_u32(bytes, offset::CYLINDERS),
            history_nodes: le_u32(bytes, offset::HISTORY_NODES),
            history_links: le_u32(bytes, offset::HISTORY_LINKS),
            scene_bytes: le_u32(bytes, offset::SCENE_BYTES),
            complex_bytes: le_u32(bytes, offset::COMPLEX_BYTES),
            history_bytes: le_u32(bytes, offset::HISTORY_BYTES),
        };
        if h.seed.is_none() && seed_raw != 0 {
            return Err(count(
                "seed",
                offset::SEED,
                seed_raw,
                CountProblem::MustBeZero,
            ));
        }
        h.check_counts()?;
        Ok(h)
    }

    /// Whether only the cylinders at θ = 0 are stored and the others are replayed from
    /// the vertices (versions 3 and 4).
    pub fn replays_cylinders(&self) -> bool {
        self.version == VERSION_REPLAY || self.version == VERSION_PRUNED
    }

    /// Whether the file stores the whole complex and a kept map (version 4).
    pub fn has_kept_map(&self) -> bool {
        self.version == VERSION_PRUNED
    }

    /// Cylinders stored in the complex part: all, or (versions 3 and 4) the
    /// `3·objects + 1` at θ = 0.
    pub fn stored_cylinders(&self) -> u32 {
        if self.replays_cylinders() {
            self.objects.saturating_mul(3).saturating_add(1)
        } else {
            self.cylinders
        }
    }

    /// Whether the file has a history part.
    pub fn has_history(&self) -> bool {
        self.parts & PART_HISTORY != 0
    }

    /// Total file length the header describes: header, parts, checksum.
    pub fn file_len(&self) -> u64 {
        HEADER_LEN as u64
            + u64::from(self.scene_bytes)
            + u64::from(self.complex_bytes)
            + u64::from(self.history_bytes)
            + CHECKSUM_LEN as u64
    }

    /// Byte range of a part in the file (the header for [`Part::Header`]). Only
    /// meaningful after the length check of [`Header::read`].
    pub fn part_range(&self, part: Part) -> core::ops::Range<usize> {
        let scene = HEADER_LEN..HEADER_LEN + self.scene_bytes as usize;
        let complex = scene.end..scene.end + self.complex_bytes as usize;
        let history = complex.end..complex.end + self.history_bytes as usize;
        match part {
            Part::Header => 0..HEADER_LEN,
            Part::Scene => scene,
            Part::Complex => complex,
            Part::History => history,
        }
    }

    /// Counts against their limits, each other, and their parts' lengths.
    fn check_counts(&self) -> Result<(), FormatError> {
        let (n, nv) = (u64::from(self.objects), u64::from(self.scene_vertices));
        let (v, c) = (u64::from(self.complex_vertices), u64::from(self.cylinders));
        if n > crate::scene::MAX_OBJECTS as u64 {
            return Err(count(
                "objects",
                offset::OBJECTS,
                n,
                CountProblem::ExceedsLimit {
                    limit: crate::scene::MAX_OBJECTS as u64,
                },
            ));
        }
        if nv > crate::scene::MAX_VERTICES as u64 {
            return Err(count(
                "scene_vertices",
                offset::SCENE_VERTICES,
                nv,
                CountProblem::ExceedsLimit {
                    limit: crate::scene::MAX_VERTICES as u64,
                },
            ));
        }
        if nv < 3 * n {
            return Err(count(
                "scene_vertices",
                offset::SCENE_VERTICES,
                nv,
                CountProblem::Inconsistent,
            ));
        }
        // A pruned complex keeps at most the 3n + 1 cylinders at θ = 0 and three opened by
        // each vertex it keeps; a whole one has exactly that many.
        let full = 3 * n + 1 + 3 * v;
        if (self.region && c > full) || (!self.region && c != full) {
            return Err(count(
                "cylinders",
                offset::CYLINDERS,
                c,
                CountProblem::Inconsistent,
            ));
        }
        let fits = |field, at, k: u64, min: u64, part: u32| {
            if min > u64::from(part) {
                Err(count(
                    field,
                    at,
                    k,
                    CountProblem::ExceedsPart {
                        min_bytes: min,
                        part_bytes: u64::from(part),
                    },
                ))
            } else {
                Ok(())
            }
        };
        let objects_min = n * MIN_OBJECT_BYTES;
        fits("objects", offset::OBJECTS, n, objects_min, self.scene_bytes)?;
        let points_min = objects_min + nv * MIN_POINT_BYTES;
        fits(
            "scene_vertices",
            offset::SCENE_VERTICES,
            nv,
            points_min,
            self.scene_bytes,
        )?;
        let region_min = if self.region { MIN_REGION_BYTES } else { 0 };
        let vertices_min = region_min + v * MIN_VERTEX_BYTES;
        fits(
            "complex_vertices",
            offset::COMPLEX_VERTICES,
            v,
            vertices_min,
            self.complex_bytes,
        )?;
        let cylinders_min = if self.has_kept_map() {
            (3 * n + 1) * MIN_INITIAL_CYLINDER_BYTES + MIN_PRUNED_EXTRA_BYTES
        } else if self.replays_cylinders() {
            (3 * n + 1) * MIN_INITIAL_CYLINDER_BYTES
        } else {
            c * MIN_CYLINDER_BYTES
        };
        fits(
            "cylinders",
            offset::CYLINDERS,
            c,
            vertices_min + cylinders_min,
            self.complex_bytes,
        )?;
        if self.has_history() {
            // Without the vertices (their count is the part's prefix, checked when read).
            let (hn, hl) = (u64::from(self.history_nodes), u64::from(self.history_links));
            if hn == 0 {
                return Err(count(
                    "history_nodes",
                    offset::HISTORY_NODES,
                    hn,
                    CountProblem::Inconsistent,
                ));
            }
            let nodes_min =
                MIN_HISTORY_PREFIX_BYTES + n * MIN_INSERTION_BYTES + hn * MIN_NODE_BYTES;
            fits(
                "history_nodes",
                offset::HISTORY_NODES,
                hn,
                nodes_min,
                self.history_bytes,
            )?;
            fits(
                "history_links",
                offset::HISTORY_LINKS,
                hl,
                nodes_min + hl * MIN_LINK_BYTES,
                self.history_bytes,
            )?;
        } else {
            for (field, at, k) in [
                ("history_nodes", offset::HISTORY_NODES, self.history_nodes),
                ("history_links", offset::HISTORY_LINKS, self.history_links),
                ("history_bytes", offset::HISTORY_BYTES, self.history_bytes),
            ] {
                if k != 0 {
                    return Err(count(field, at, u64::from(k), CountProblem::MustBeZero));
                }
            }
        }
        Ok(())
    }

    /// The file length against the header.
    fn check_length(&self, len: usize) -> Result<(), FormatError> {
        if len as u64 != self.file_len() {
            return Err(FormatError::Length {
                len,
                expected: self.file_len(),
            });
        }
        Ok(())
    }

    /// The 56 header bytes.
    pub fn to_bytes(&self) -> [u8; HEADER_LEN] {
        let mut b = [0u8; HEADER_LEN];
        let mut put = |at: usize, v: &[u8]| {
            if let Some(d) = b.get_mut(at..at + v.len()) {
                d.copy_from_slice(v);
            }
        };
        let flags = if self.seed.is_some() { FLAG_SEED } else { 0 }
            | if self.compacted { FLAG_COMPACTED } else { 0 }
            | if self.region { FLAG_REGION } else { 0 };
        put(offset::MAGIC, &MAGIC);
        put(offset::VERSION, &self.version.to_le_bytes());
        put(offset::FLAGS, &flags.to_le_bytes());
        put(offset::PARTS, &self.parts.to_le_bytes());
        put(offset::OBJECTS, &self.objects.to_le_bytes());
        put(offset::SCENE_VERTICES, &self.scene_vertices.to_le_bytes());
        put(
            offset::COMPLEX_VERTICES,
            &self.complex_vertices.to_le_bytes(),
        );
        put(offset::CYLINDERS, &self.cylinders.to_le_bytes());
        put(offset::HISTORY_NODES, &self.history_nodes.to_le_bytes());
        put(offset::HISTORY_LINKS, &self.history_links.to_le_bytes());
        put(offset::SEED, &self.seed.unwrap_or(0).to_le_bytes());
        put(offset::SCENE_BYTES, &self.scene_bytes.to_le_bytes());
        put(offset::COMPLEX_BYTES, &self.complex_bytes.to_le_bytes());
        put(offset::HISTORY_BYTES, &self.history_bytes.to_le_bytes());
        b
    }
}

fn count(field: &'static str, offset: usize, count: u64, problem: CountProblem) -> FormatError {
    FormatError::Count {
        field,
        offset,
        count,
        problem,
    }
}

/// The stored checksum (last four bytes) against the CRC-32 of everything before it.
fn check_checksum(bytes: &[u8]) -> Result<(), FormatError> {
    let at = bytes
        .len()
        .checked_sub(CHECKSUM_LEN)
        .ok_or(FormatError::TooShort {
            len: bytes.len(),
            needed: HEADER_LEN + CHECKSUM_LEN,
        })?;
    let (body, tail) = bytes.split_at(at);
    let stored = le_u32(tail, 0);
    let computed = crc32(body);
    if stored != computed {
        return Err(FormatError::Checksum {
            offset: at,
            stored,
            computed,
        });
    }
    Ok(())
}
