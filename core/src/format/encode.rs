//! Writing a file: header, scene part, complex part, history part (optional), checksum
//! (`docs/format.md`).

use serde::Serialize;

use super::{
    crc32, FormatError, Header, CHECKSUM_LEN, HEADER_LEN, PART_COMPLEX, PART_HISTORY, PART_SCENE,
    VERSION, VERSION_PRUNED, VERSION_REGION, VERSION_REPLAY,
};
use crate::line_space::Bound;
use crate::partition::Region;
use crate::partition::{Cylinder, CylinderId, Vertex, Wall};
use crate::scene::{Material, ObjectId, SceneRef};

/// What the header records about how the complex was built.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct EncodeOptions {
    /// Seed of the randomized incremental construction (`None`: not recorded, e.g. built
    /// by the rotational sweep).
    pub seed: Option<u64>,
    /// Whether the history is search-path compacted (§4.4 of the paper). When a history is
    /// written the flag is the history's own
    /// ([`HistoryParts::compacted`](crate::partition::HistoryParts::compacted)), whatever
    /// this says.
    pub compacted: bool,
    /// Store every cylinder (version 1; version 2 for a complex pruned to a region) even
    /// where version 3 (4) would store only those at θ = 0 and let the reader replay the
    /// rest: for older readers. (Files with a history store every cylinder anyway.)
    pub explicit_cylinders: bool,
}

/// The arenas of a history to write, borrowed (the fields of
/// [`HistoryParts`](crate::partition::HistoryParts)).
#[derive(Clone, Copy, Debug)]
struct HistoryView<'h> {
    nodes: &'h [Cylinder],
    children: &'h [(u32, u32)],
    links: &'h [CylinderId],
    vertices: &'h [Vertex],
    order: &'h [ObjectId],
    starts: &'h [u32],
    compacted: bool,
}

/// The kept map of a version-4 file and what it keeps.
#[derive(Clone, Copy, Debug)]
struct Kept<'k> {
    /// One bit per replayed cylinder, least significant bit first.
    map: &'k [u8],
    vertices: usize,
    cylinders: usize,
}

/// Material discriminants (postcard enum encoding: `varint(u32)`, then the fields).
pub(super) const OPAQUE: u32 = 0;
pub(super) const MIRROR: u32 = 1;
pub(super) const REFRACTIVE: u32 = 2;
pub(super) const SCREEN: u32 = 3;

/// Appends postcard encodings to a buffer, or only counts bytes (`out: None`).
struct Writer<'o> {
    out: Option<&'o mut [u8]>,
    pos: usize,
}

impl Writer<'_> {
    fn put<T: Serialize>(&mut self, value: &T) -> Result<(), FormatError> {
        // Every field is a varint of at most 32 bits: 5 bytes.
        let mut tmp = [0u8; 8];
        let used = postcard::to_slice(value, &mut tmp)
            .map_err(|_| FormatError::NotEncodable("a field does not fit 8 bytes"))?
            .len();
        let end = self.pos + used;
        if let Some(out) = self.out.as_deref_mut() {
            let capacity = out.len();
            let (dst, src) = (
                out.get_mut(self.pos..end)
                    .ok_or(FormatError::BufferTooSmall {
                        needed: end,
                        capacity,
                    })?,
                tmp.get(..used).unwrap_or(&[]),
            );
            dst.copy_from_slice(src);
        }
        self.pos = end;
        Ok(())
    }
}

/// `0` for none, `id + 1` otherwise: optional ids in one varint.
fn opt(id: Option<usize>) -> Result<u32, FormatError> {
    match id {
        None => Ok(0),
        Some(i) => u32::try_from(i)
            .ok()
            .and_then(|i| i.checked_add(1))
            .ok_or(FormatError::NotEncodable("an id does not fit u32")),
    }
}

fn id(i: usize) -> Result<u32, FormatError> {
    u32::try_from(i).map_err(|_| FormatError::NotEncodable("an id does not fit u32"))
}

/// A chain as one optional id: `2·object + (0 lower, 1 upper)`.
fn chain(c: Option<crate::line_space::Chain>) -> Result<u32, FormatError> {
    opt(c.map(|c| {
        2 * c.object.0 as usize
            + match c.bound {
                Bound::Lower => 0,
                Bound::Upper => 1,
            }
    }))
}

fn wall(w: Wall) -> Result<u32, FormatError> {
    opt(match w {
        Wall::Zero => None,
        Wall::Vertex(v) => Some(v.index()),
    })
}

/// The scene part: objects, then every object's vertices in the order written.
fn scene_part(w: &mut Writer<'_>, scene: &SceneRef<'_>) -> Result<(), FormatError> {
    for object in scene.objects() {
        match object.material {
            Material::Opaque => w.put(&OPAQUE)?,
            Material::Mirror => w.put(&MIRROR)?,
            Material::Refractive { eta } => {
                w.put(&REFRACTIVE)?;
                w.put(&eta.raw())?;
            }
            Material::Screen => w.put(&SCREEN)?,
        }
        w.put(&id(object.len())?)?;
    }
    for object in scene.objects() {
        let polygon = scene.polygon(object);
        // `written_vertex_id` is an involution: written vertex j is stored at index
        // `written_vertex_id(j)`; writing in input order makes `Scene::new` rebuild the
        // same storage (and so the same vertex ranks).
        for j in 0..polygon.len() {
            let p = polygon
                .get(object.written_vertex_id(j))
                .ok_or(FormatError::NotEncodable(
                    "an object's vertices are missing",
                ))?;
            w.put(&p.x())?;
            w.put(&p.y())?;
        }
    }
    Ok(())
}

/// The complex part: the region (versions 2 and 4, if pruned), the count of vertices
/// (version 4), vertices (their two tangent vertices), then every cylinder or (versions 3
/// and 4, `replay`) the cylinders at θ = 0 only, four ids each, in the order they have in
/// `cylinders`, and (version 4) the kept map: its byte length, then its bytes.
fn complex_part(
    w: &mut Writer<'_>,
    region: Option<&Region>,
    replay: bool,
    kept: Option<&Kept<'_>>,
    vertices: &[Vertex],
    cylinders: &[Cylinder],
) -> Result<(), FormatError> {
    if let Some(r) = region {
        for c in [r.min().x(), r.min().y(), r.max().x(), r.max().y()] {
            w.put(&c)?;
        }
    }
    if kept.is_some() {
        w.put(&id(vertices.len())?)?;
    }
    put_vertices(w, vertices)?;
    if !replay {
        return put_cylinders(w, cylinders);
    }
    for c in cylinders.iter().filter(|c| c.left == Wall::Zero) {
        w.put(&opt(c.floor.map(|o| o.0 as usize))?)?;
        w.put(&opt(c.ceiling.map(|o| o.0 as usize))?)?;
        w.put(&chain(c.bottom)?)?;
        w.put(&chain(c.top)?)?;
    }
    if let Some(k) = kept {
        w.put(&id(k.map.len())?)?;
        for b in k.map {
            w.put(b)?;
        }
    }
    Ok(())
}

/// Vertices: their two tangent vertices (the complex's and the history's alike).
fn put_vertices(w: &mut Writer<'_>, vertices: &[Vertex]) -> Result<(), FormatError> {
    for v in vertices {
        w.put(&id(v.bitangent.first)?)?;
        w.put(&id(v.bitangent.second)?)?;
    }
    Ok(())
}

/// Cylinders: eight optional ids (the complex's cylinders and the history's nodes alike).
fn put_cylinders(w: &mut Writer<'_>, cylinders: &[Cylinder]) -> Result<(), FormatError> {
    for c in cylinders {
        w.put(&opt(c.floor.map(|o| o.0 as usize))?)?;
        w.put(&opt(c.ceiling.map(|o| o.0 as usize))?)?;
        w.put(&chain(c.bottom)?)?;
        w.put(&chain(c.top)?)?;
        w.put(&wall(c.left)?)?;
        w.put(&wall(c.right)?)?;
        w.put(&opt(c.left_neighbour.map(|n| n.index()))?)?;
        w.put(&opt(c.right_neighbour.map(|n| n.index()))?)?;
    }
    Ok(())
}

/// The history part: vertex count, vertices, nodes, child counts, links in node order,
/// insertions (object, first node). Returns the number of links written.
fn history_part(w: &mut Writer<'_>, h: &HistoryView<'_>) -> Result<usize, FormatError> {
    let broken = FormatError::NotEncodable("the history's arenas do not fit each other");
    if h.children.len() != h.nodes.len() || h.order.len() != h.starts.len() {
        return Err(broken);
    }
    w.put(&id(h.vertices.len())?)?;
    put_vertices(w, h.vertices)?;
    put_cylinders(w, h.nodes)?;
    for &(_, len) in h.children {
        w.put(&len)?;
    }
    let mut written = 0usize;
    for &(start, len) in h.children {
        let end = (start as usize).checked_add(len as usize).ok_or(broken)?;
        let kids = h.links.get(start as usize..end).ok_or(broken)?;
        for k in kids {
            w.put(&id(k.index())?)?;
        }
        written += kids.len();
    }
    for (o, &start) in h.order.iter().zip(h.starts) {
        w.put(&o.0)?;
        w.put(&start)?;
    }
    Ok(written)
}

/// The header for this scene and complex (part sizes by a counting pass).
fn header(
    scene: &SceneRef<'_>,
    region: Option<&Region>,
    kept: Option<&Kept<'_>>,
    vertices: &[Vertex],
    cylinders: &[Cylinder],
    history: Option<&HistoryView<'_>>,
    options: &EncodeOptions,
) -> Result<Header, FormatError> {
    // The file stores whole objects in order: every vertex must belong to exactly one
    // object, in order (a `SubScene` that left objects out shares its parent's vertex
    // array and cannot be written; build its own `Scene`).
    let mut next = 0;
    for o in scene.objects() {
        if o.first_vertex() != next {
            return Err(FormatError::NotEncodable(
                "the scene's objects do not cover its vertex array in order (a SubScene?)",
            ));
        }
        next += o.len();
    }
    if next != scene.vertices().len() {
        return Err(FormatError::NotEncodable(
            "the scene's objects do not cover its vertex array in order (a SubScene?)",
        ));
    }
    let mut w = Writer { out: None, pos: 0 };
    scene_part(&mut w, scene)?;
    let scene_bytes = id(w.pos)?;
    // Files with a region or a history store every cylinder (a region keeps only some,
    // and the history names the cylinders as its construction numbered them).
    let version = if kept.is_some() {
        VERSION_PRUNED
    } else if region.is_some() {
        VERSION_REGION
    } else if history.is_some() || options.explicit_cylinders {
        VERSION
    } else {
        VERSION_REPLAY
    };
    if version == VERSION_REPLAY || version == VERSION_PRUNED {
        let at_zero = cylinders.iter().filter(|c| c.left == Wall::Zero).count();
        if at_zero != 3 * scene.len() + 1 {
            return Err(FormatError::NotEncodable(
                "the complex does not have 3n + 1 cylinders at θ = 0",
            ));
        }
    }
    let mut w = Writer { out: None, pos: 0 };
    complex_part(
        &mut w,
        region,
        version == VERSION_REPLAY || version == VERSION_PRUNED,
        kept,
        vertices,
        cylinders,
    )?;
    let complex_bytes = id(w.pos)?;
    let (mut parts, mut history_bytes, mut history_links) = (PART_SCENE | PART_COMPLEX, 0, 0);
    if let Some(h) = history {
        if region.is_some() {
            return Err(FormatError::NotEncodable(
                "a complex pruned to a region is written without history",
            ));
        }
        if h.order.len() != scene.len() {
            return Err(FormatError::NotEncodable(
                "the history has not inserted every object of the scene",
            ));
        }
        let mut w = Writer { out: None, pos: 0 };
        history_links = id(history_part(&mut w, h)?)?;
        history_bytes = id(w.pos)?;
        parts |= PART_HISTORY;
    }
    Ok(Header {
        version,
        region: region.is_some(),
        parts,
        seed: options.seed,
        compacted: history.map_or(options.compacted, |h| h.compacted),
        objects: id(scene.len())?,
        scene_vertices: id(scene.vertices().len())?,
        complex_vertices: id(kept.map_or(vertices.len(), |k| k.vertices))?,
        cylinders: id(kept.map_or(cylinders.len(), |k| k.cylinders))?,
        history_nodes: id(history.map_or(0, |h| h.nodes.len()))?,
        history_links,
        scene_bytes,
        complex_bytes,
        history_bytes,
    })
}

/// Bytes [`encode_into`] writes for this scene and complex.
pub fn encoded_len(
    scene: &SceneRef<'_>,
    vertices: &[Vertex],
    cylinders: &[Cylinder],
    options: &EncodeOptions,
) -> Result<usize, FormatError> {
    let h = header(scene, None, None, vertices, cylinders, None, options)?;
    usize::try_from(h.file_len()).map_err(|_| FormatError::NotEncodable("file too large"))
}

/// Writes the file for a scene and its complex (`complex.vertices()`,
/// `complex.cylinders()`) into `out`, without history; returns the number of bytes
/// written: version 3 (only the cylinders at θ = 0, in their order in `cylinders`; a
/// reader numbers the others as the sweep does), or version 1 with
/// [`EncodeOptions::explicit_cylinders`]. No allocation: usable on a device. The complex
/// is trusted (it comes from a construction or a validated load); readers check
/// everything anyway.
pub fn encode_into(
    scene: &SceneRef<'_>,
    vertices: &[Vertex],
    cylinders: &[Cylinder],
    options: &EncodeOptions,
    out: &mut [u8],
) -> Result<usize, FormatError> {
    write_file(scene, None, None, vertices, cylinders, None, options, out)
}

#[allow(clippy::too_many_arguments)] // the parts of a file, each optional
fn write_file(
    scene: &SceneRef<'_>,
    region: Option<&Region>,
    kept: Option<&Kept<'_>>,
    vertices: &[Vertex],
    cylinders: &[Cylinder],
    history: Option<&HistoryView<'_>>,
    options: &EncodeOptions,
    out: &mut [u8],
) -> Result<usize, FormatError> {
    let h = header(scene, region, kept, vertices, cylinders, history, options)?;
    let len =
        usize::try_from(h.file_len()).map_err(|_| FormatError::NotEncodable("file too large"))?;
    let capacity = out.len();
    let out = out.get_mut(..len).ok_or(FormatError::BufferTooSmall {
        needed: len,
        capacity,
    })?;
    let (head, rest) = out.split_at_mut(HEADER_LEN);
    head.copy_from_slice(&h.to_bytes());
    let mut w = Writer {
        out: Some(rest),
        pos: 0,
    };
    scene_part(&mut w, scene)?;
    complex_part(
        &mut w,
        region,
        h.replays_cylinders(),
        kept,
        vertices,
        cylinders,
    )?;
    if let Some(hv) = history {
        history_part(&mut w, hv)?;
    }
    let body_end = len - CHECKSUM_LEN;
    let crc = crc32(out.get(..body_end).unwrap_or(&[]));
    if let Some(tail) = out.get_mut(body_end..) {
        tail.copy_from_slice(&crc.to_le_bytes());
    }
    Ok(len)
}

/// The file for a scene, its complex and optionally the history of the randomized
/// construction that built it, in a new vector. With a history, the complex must be its
/// live partition as [`History::complex`](crate::partition::History::complex) numbers it
/// (build both by the randomized construction), and the history must have inserted every
/// object; the header's compacted flag is the history's
/// ([`History::is_compacted`](crate::partition::History::is_compacted)), and the file is
/// version 1 (every cylinder stored). A complex pruned to a region
/// ([`Complex::region`](crate::partition::Complex::region)) is written without history, as
/// version 4 ([`encode_region`] of the whole complex, which this rebuilds by the rotational
/// sweep: pass the whole complex to [`encode_region`] to skip that), or as version 2 (every
/// kept cylinder stored) with [`EncodeOptions::explicit_cylinders`]. Any other complex is
/// written as version 3 (only the cylinders at θ = 0 stored) unless
/// [`EncodeOptions::explicit_cylinders`].
#[cfg(feature = "alloc")]
pub fn encode(
    scene: &SceneRef<'_>,
    complex: &crate::partition::Complex,
    history: Option<&crate::partition::History>,
    options: &EncodeOptions,
) -> Result<alloc::vec::Vec<u8>, FormatError> {
    let Some(history) = history else {
        if let (Some(region), false) = (complex.region(), options.explicit_cylinders) {
            let whole = crate::partition::build_by_sweep(scene)
                .map_err(|_| FormatError::NotEncodable("the scene's complex cannot be rebuilt"))?;
            return encode_region(scene, &whole, region, options);
        }
        return encode_parts(scene, complex, None, options);
    };
    let live = history
        .complex(scene)
        .map_err(|_| FormatError::NotEncodable("the history's live partition is invalid"))?;
    if live.vertices() != complex.vertices() || live.cylinders() != complex.cylinders() {
        return Err(FormatError::NotEncodable(
            "the complex is not the history's live partition (build both by the randomized \
             construction)",
        ));
    }
    encode_parts(scene, complex, Some(&history.to_parts()), options)
}

/// [`encode`] with the history's arenas as given, trusted as [`encode_into`] trusts the
/// complex (for tools and tests: readers check everything).
#[cfg(feature = "alloc")]
pub fn encode_history_parts(
    scene: &SceneRef<'_>,
    complex: &crate::partition::Complex,
    history: &crate::partition::HistoryParts,
    options: &EncodeOptions,
) -> Result<alloc::vec::Vec<u8>, FormatError> {
    encode_parts(scene, complex, Some(history), options)
}

#[cfg(feature = "alloc")]
fn encode_parts(
    scene: &SceneRef<'_>,
    complex: &crate::partition::Complex,
    history: Option<&crate::partition::HistoryParts>,
    options: &EncodeOptions,
) -> Result<alloc::vec::Vec<u8>, FormatError> {
    let (v, c) = (complex.vertices(), complex.cylinders());
    let view = history.map(|p| HistoryView {
        nodes: &p.nodes,
        children: &p.children,
        links: &p.links,
        vertices: &p.vertices,
        order: &p.order,
        starts: &p.starts,
        compacted: p.compacted,
    });
    let region = complex.region();
    to_vec(scene, region.as_ref(), None, v, c, view.as_ref(), options)
}

/// The version-4 file of the whole complex `whole` (not pruned, any numbering) for
/// viewpoints in `region` (`docs/format.md`, "Version 4"): version 3 of `whole` plus the
/// region and the kept map, which marks in replay order the cylinders
/// [`Complex::prune_to_region`](crate::partition::Complex::prune_to_region) keeps. A reader
/// decodes it to `prune_to_region` of the complex it replays (numbered as the sweep
/// numbers it), storing only the kept cylinders and vertices. No history; the scene must
/// be all opaque.
#[cfg(feature = "alloc")]
pub fn encode_region(
    scene: &SceneRef<'_>,
    whole: &crate::partition::Complex,
    region: Region,
    options: &EncodeOptions,
) -> Result<alloc::vec::Vec<u8>, FormatError> {
    use crate::partition::{open_slots, replay, Complex, BLANK_CYLINDER, ZERO_SLOTS};
    if whole.region().is_some() {
        return Err(FormatError::NotEncodable(
            "encode_region needs the whole complex, not a pruned one",
        ));
    }
    // The complex as a reader replays it: the cylinders at θ = 0 in their order, then
    // three per vertex.
    let vertices = whole.vertices();
    let mut cylinders: alloc::vec::Vec<Cylinder> = whole
        .cylinders()
        .iter()
        .filter(|c| c.left == Wall::Zero)
        .copied()
        .collect();
    let initial = cylinders.len();
    cylinders.resize(initial + 3 * vertices.len(), BLANK_CYLINDER);
    let mut open = alloc::vec![ZERO_SLOTS; open_slots(scene.len())];
    replay(scene.len(), vertices, initial, &mut cylinders, &mut open)
        .map_err(|_| FormatError::NotEncodable("the complex does not replay"))?;
    let replayed = Complex::new_owned(vertices.to_vec(), cylinders, scene);
    let keep = replayed
        .needed_in(scene, &region)
        .map_err(|_| FormatError::NotEncodable("the scene has an object that is not opaque"))?;
    let pruned = replayed.keep_only(scene, region, &keep);
    let mut map = alloc::vec![0u8; keep.len().div_ceil(8)];
    for (i, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
        if let Some(b) = map.get_mut(i / 8) {
            *b |= 1 << (i % 8);
        }
    }
    let kept = Kept {
        map: &map,
        vertices: pruned.vertices().len(),
        cylinders: pruned.cylinders().len(),
    };
    let (v, c) = (replayed.vertices(), replayed.cylinders());
    to_vec(scene, Some(&region), Some(&kept), v, c, None, options)
}

/// [`write_file`] into a vector of the file's length.
#[cfg(feature = "alloc")]
fn to_vec(
    scene: &SceneRef<'_>,
    region: Option<&Region>,
    kept: Option<&Kept<'_>>,
    vertices: &[Vertex],
    cylinders: &[Cylinder],
    history: Option<&HistoryView<'_>>,
    options: &EncodeOptions,
) -> Result<alloc::vec::Vec<u8>, FormatError> {
    let h = header(scene, region, kept, vertices, cylinders, history, options)?;
    let len =
        usize::try_from(h.file_len()).map_err(|_| FormatError::NotEncodable("file too large"))?;
    let mut out = alloc::vec![0u8; len];
    let len = write_file(
        scene, region, kept, vertices, cylinders, history, options, &mut out,
    )?;
    out.truncate(len);
    Ok(out)
}
