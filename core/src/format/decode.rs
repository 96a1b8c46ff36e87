//! Reading a file without trusting it: header first, then every arena element by element
//! and field by field, each id checked as it is read, then the links between elements.

use core::cmp::Ordering;

use serde::de::DeserializeOwned;

use super::encode::{MIRROR, OPAQUE, REFRACTIVE, SCREEN};
use super::{Arena, CountProblem, FormatError, Header, Part, Problem};
use crate::geom::point::MAX_ABS_RAW;
use crate::geom::sos::Angle;
use crate::geom::Point;
use crate::line_space::{tangency, Bitangent, Bound, Chain};
use crate::partition::{
    open_slots, replay, replay_stream, Cylinder, CylinderId, Region, ReplayError, Slots, Stream,
    Vertex, VertexId, Wall,
};
use crate::scene::{Eta, FixedScene, Material, ObjectId, SceneRef};

/// One object of the scene part as stored: material and vertex count.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct SceneObject {
    /// What the object does to rays.
    pub material: Material,
    /// Number of vertices.
    pub vertices: u32,
}

impl SceneObject {
    /// A placeholder to fill caller storage with before decoding.
    pub const BLANK: SceneObject = SceneObject {
        material: Material::Opaque,
        vertices: 0,
    };
}

/// A placeholder vertex to fill caller storage with before decoding.
pub const BLANK_VERTEX: Vertex = Vertex {
    bitangent: Bitangent {
        first_object: ObjectId(0),
        first: 0,
        first_bound: Bound::Lower,
        second_object: ObjectId(0),
        second: 0,
        second_bound: Bound::Lower,
    },
};

/// A placeholder cylinder to fill caller storage with before decoding.
pub const BLANK_CYLINDER: Cylinder = crate::partition::BLANK_CYLINDER;

/// Scratch storage, sized from the header (`objects`, `scene_vertices`): needed only
/// while decoding, reusable after.
#[derive(Debug)]
pub struct Scratch<'a> {
    /// At least `header.objects` entries.
    pub objects: &'a mut [SceneObject],
    /// At least `header.scene_vertices` entries.
    pub points: &'a mut [Point],
    /// The open cylinders while a version-3 or 4 file's cylinders are replayed: at least
    /// [`Scratch::open_len`]`(header.objects)` entries (may be empty for versions 1 and 2).
    pub open: &'a mut [Slots],
}

impl Scratch<'_> {
    /// Entries of [`Scratch::open`] a version-3 or 4 file of `objects` objects needs.
    pub const fn open_len(objects: usize) -> usize {
        open_slots(objects)
    }
}

/// A file decoded into caller storage without allocation: the validated scene and the
/// complex's arenas, every id and link checked (see [`decode_into`]).
#[derive(Debug)]
pub struct Decoded<'a, const V: usize, const O: usize> {
    /// The header.
    pub header: Header,
    /// The scene, validated by [`FixedScene::new`].
    pub scene: FixedScene<V, O>,
    /// The complex's vertices, sorted by θ.
    pub vertices: &'a [Vertex],
    /// The cylinders.
    pub cylinders: &'a [Cylinder],
    /// The region the complex is pruned to (versions 2 and 4), if any: pass it to
    /// [`Complex::with_region`](crate::partition::Complex::with_region) so walks from
    /// outside it fail instead of reaching missing cylinders.
    pub region: Option<Region>,
}

/// A reader of one part: postcard fields, one at a time, never past the part's end.
struct Reader<'b> {
    bytes: &'b [u8],
    pos: usize,
    end: usize,
}

impl Reader<'_> {
    fn new(bytes: &[u8], range: core::ops::Range<usize>) -> Reader<'_> {
        Reader {
            bytes,
            pos: range.start,
            end: range.end,
        }
    }

    /// The next field and its byte offset.
    fn field<T: DeserializeOwned>(
        &mut self,
        arena: Arena,
        index: usize,
        field: &'static str,
    ) -> Result<(T, usize), FormatError> {
        let at = self.pos;
        let malformed = |why| FormatError::Element {
            arena,
            index,
            field,
            offset: at,
            problem: Problem::Malformed(why),
        };
        let rest = self
            .bytes
            .get(self.pos..self.end)
            .ok_or(malformed("past the end of its part"))?;
        match postcard::take_from_bytes::<T>(rest) {
            Ok((value, tail)) => {
                self.pos = self.end - tail.len();
                Ok((value, at))
            }
            Err(postcard::Error::DeserializeUnexpectedEnd) => {
                Err(malformed("its part ends inside it"))
            }
            Err(postcard::Error::DeserializeBadVarint) => {
                Err(malformed("varint too long or too large"))
            }
            Err(_) => Err(malformed("not a postcard value of its type")),
        }
    }

    /// An id field below `limit`.
    fn id(
        &mut self,
        arena: Arena,
        index: usize,
        field: &'static str,
        limit: usize,
    ) -> Result<usize, FormatError> {
        let (v, at) = self.field::<u32>(arena, index, field)?;
        check_below(arena, index, field, at, u64::from(v), limit)?;
        Ok(v as usize)
    }

    /// An optional id field (`0` none, `id + 1`) with id below `limit`.
    fn opt_id(
        &mut self,
        arena: Arena,
        index: usize,
        field: &'static str,
        limit: usize,
    ) -> Result<Option<usize>, FormatError> {
        let (v, at) = self.field::<u32>(arena, index, field)?;
        match v.checked_sub(1) {
            None => Ok(None),
            Some(id) => {
                check_below(arena, index, field, at, u64::from(id), limit)?;
                Ok(Some(id as usize))
            }
        }
    }

    /// The part's elements must end exactly at its end.
    fn finish(&self, part: Part) -> Result<(), FormatError> {
        if self.pos != self.end {
            return Err(FormatError::PartSize {
                part,
                end: self.end,
                used: self.pos,
            });
        }
        Ok(())
    }
}

fn check_below(
    arena: Arena,
    index: usize,
    field: &'static str,
    offset: usize,
    value: u64,
    limit: usize,
) -> Result<(), FormatError> {
    if value >= limit as u64 {
        return Err(FormatError::Element {
            arena,
            index,
            field,
            offset,
            problem: Problem::OutOfRange {
                value,
                limit: limit as u64,
            },
        });
    }
    Ok(())
}

fn capacity(arena: Arena, needed: u32, capacity: usize) -> Result<usize, FormatError> {
    let needed = needed as usize;
    if needed > capacity {
        return Err(FormatError::Capacity {
            arena,
            needed,
            capacity,
        });
    }
    Ok(needed)
}

/// Decodes the scene part into `objects[..n]` and `points[..nv]` (points as written).
fn decode_scene(
    bytes: &[u8],
    h: &Header,
    objects: &mut [SceneObject],
    points: &mut [Point],
) -> Result<(), FormatError> {
    let n = capacity(Arena::Object, h.objects, objects.len())?;
    let nv = capacity(Arena::Point, h.scene_vertices, points.len())?;
    let mut r = Reader::new(bytes, h.part_range(Part::Scene));
    let mut total = 0usize;
    for (i, slot) in objects.iter_mut().take(n).enumerate() {
        let (tag, at) = r.field::<u32>(Arena::Object, i, "material")?;
        let material = match tag {
            OPAQUE => Material::Opaque,
            MIRROR => Material::Mirror,
            SCREEN => Material::Screen,
            REFRACTIVE => {
                let (raw, at) = r.field::<u32>(Arena::Object, i, "eta")?;
                let eta = Eta::from_raw(raw).ok_or(FormatError::Element {
                    arena: Arena::Object,
                    index: i,
                    field: "eta",
                    offset: at,
                    problem: Problem::NotInRange {
                        value: i64::from(raw),
                        min: i64::from(Eta::MIN_RAW),
                        max: i64::from(Eta::MAX_RAW),
                    },
                })?;
                Material::Refractive { eta }
            }
            _ => {
                check_below(Arena::Object, i, "material", at, u64::from(tag), 4)?;
                Material::Opaque
            }
        };
        let (k, at) = r.field::<u32>(Arena::Object, i, "vertices")?;
        let element = |problem| FormatError::Element {
            arena: Arena::Object,
            index: i,
            field: "vertices",
            offset: at,
            problem,
        };
        if k < 3 {
            return Err(element(Problem::TooFewVertices(k)));
        }
        let left = nv - total;
        if k as usize > left {
            return Err(element(Problem::OutOfRange {
                value: u64::from(k),
                limit: left as u64 + 1,
            }));
        }
        total += k as usize;
        *slot = SceneObject {
            material,
            vertices: k,
        };
    }
    if total != nv {
        return Err(FormatError::Count {
            field: "scene_vertices",
            offset: super::offset::SCENE_VERTICES,
            count: nv as u64,
            problem: CountProblem::Inconsistent,
        });
    }
    for (k, slot) in points.iter_mut().take(nv).enumerate() {
        let mut coordinate = |field| -> Result<i32, FormatError> {
            let (v, at) = r.field::<i32>(Arena::Point, k, field)?;
            if v.unsigned_abs() > MAX_ABS_RAW as u32 {
                return Err(FormatError::Element {
                    arena: Arena::Point,
                    index: k,
                    field,
                    offset: at,
                    problem: Problem::NotInRange {
                        value: i64::from(v),
                        min: -i64::from(MAX_ABS_RAW),
                        max: i64::from(MAX_ABS_RAW),
                    },
                });
            }
            Ok(v)
        };
        let (x, y) = (coordinate("x")?, coordinate("y")?);
        *slot = Point::from_raw(x, y).unwrap_or_default();
    }
    r.finish(Part::Scene)
}

/// The decoded objects as `(material, vertices as written)`, for `Scene::new`.
fn scene_input<'p>(
    objects: &'p [SceneObject],
    points: &'p [Point],
) -> impl Iterator<Item = (Material, &'p [Point])> + 'p {
    objects.iter().scan(0usize, move |start, o| {
        let range = *start..*start + o.vertices as usize;
        *start = range.end;
        Some((o.material, points.get(range).unwrap_or(&[])))
    })
}

/// The object owning global vertex `v`.
fn object_of(scene: &SceneRef<'_>, v: usize) -> Option<ObjectId> {
    let objects = scene.objects();
    let i = objects.partition_point(|o| o.first_vertex() + o.len() <= v);
    let o = objects.get(i)?;
    (o.first_vertex() <= v).then_some(ObjectId(i as u32))
}

fn flip(b: Bound) -> Bound {
    match b {
        Bound::Lower => Bound::Upper,
        Bound::Upper => Bound::Lower,
    }
}

/// Reads `vertices.len()` vertices of `arena` (the complex's or the history's): two
/// global vertex indices each, in range and on two objects; the objects and chains are
/// derived and the tangency at both ends checked. With `sorted`, θ must increase strictly
/// (the complex's vertices; the history's are in creation order).
fn read_vertices(
    r: &mut Reader<'_>,
    a: Arena,
    scene: &SceneRef<'_>,
    vertices: &mut [Vertex],
    sorted: bool,
) -> Result<(), FormatError> {
    let mut previous: Option<Angle> = None;
    for (i, slot) in vertices.iter_mut().enumerate() {
        *slot = read_vertex(r, a, scene, i, sorted.then_some(&mut previous))?;
    }
    Ok(())
}

/// Reads vertex `i` of [`read_vertices`]; with `previous` (the angle of the vertex before,
/// updated), θ must increase strictly.
fn read_vertex(
    r: &mut Reader<'_>,
    a: Arena,
    scene: &SceneRef<'_>,
    i: usize,
    previous: Option<&mut Option<Angle>>,
) -> Result<Vertex, FormatError> {
    let points = scene.vertices().len();
    let first_at = r.pos;
    let first = r.id(a, i, "first", points)?;
    let second_at = r.pos;
    let second = r.id(a, i, "second", points)?;
    let element = |field, offset, problem| FormatError::Element {
        arena: a,
        index: i,
        field,
        offset,
        problem,
    };
    // In range, so both have an object.
    let (Some(p), Some(q)) = (object_of(scene, first), object_of(scene, second)) else {
        return Err(element("first", first_at, Problem::NotTangent));
    };
    if p == q {
        return Err(element("second", second_at, Problem::SameObject));
    }
    let first_bound =
        tangency(scene, p, first, second).ok_or(element("first", first_at, Problem::NotTangent))?;
    let second_bound = tangency(scene, q, second, first).map(flip).ok_or(element(
        "second",
        second_at,
        Problem::NotTangent,
    ))?;
    let bitangent = Bitangent {
        first_object: p,
        first,
        first_bound,
        second_object: q,
        second,
        second_bound,
    };
    if let Some(previous) = previous {
        let angle = bitangent.angle(scene);
        if previous.is_some_and(|prev| prev.cmp_angle(&angle) != Ordering::Less) {
            return Err(element("first", first_at, Problem::NotSorted));
        }
        *previous = Some(angle);
    }
    Ok(Vertex { bitangent })
}

/// An object id as read (in range).
fn object(id: Option<usize>) -> Option<ObjectId> {
    id.map(|o| ObjectId(o as u32))
}

/// A chain id as read (in range): `2·object + (0 lower, 1 upper)`.
fn chain(id: Option<usize>) -> Option<Chain> {
    id.map(|c| Chain {
        object: ObjectId((c / 2) as u32),
        bound: if c % 2 == 0 {
            Bound::Lower
        } else {
            Bound::Upper
        },
    })
}

/// Reads `cylinders.len()` cylinders of `arena` (the complex's, or the history's nodes):
/// eight optional ids each, checked as read against `objects` (floor, ceiling), `2·objects`
/// (chains), `walls` (vertices of the same part) and the arena's own length (neighbours).
fn read_cylinders(
    r: &mut Reader<'_>,
    a: Arena,
    objects: usize,
    walls: usize,
    cylinders: &mut [Cylinder],
) -> Result<(), FormatError> {
    let (n, nv, nc) = (objects, walls, cylinders.len());
    let wall = |id: Option<usize>| match id {
        None => Wall::Zero,
        Some(v) => Wall::Vertex(VertexId::from_index(v).unwrap_or(VertexId::ZERO)),
    };
    let neighbour = |id: Option<usize>| id.and_then(CylinderId::from_index);
    for (i, slot) in cylinders.iter_mut().enumerate() {
        *slot = Cylinder {
            floor: object(r.opt_id(a, i, "floor", n)?),
            ceiling: object(r.opt_id(a, i, "ceiling", n)?),
            bottom: chain(r.opt_id(a, i, "bottom", 2 * n)?),
            top: chain(r.opt_id(a, i, "top", 2 * n)?),
            left: wall(r.opt_id(a, i, "left", nv)?),
            right: wall(r.opt_id(a, i, "right", nv)?),
            left_neighbour: neighbour(r.opt_id(a, i, "left_neighbour", nc)?),
            right_neighbour: neighbour(r.opt_id(a, i, "right_neighbour", nc)?),
        };
    }
    Ok(())
}

/// Reads the region at the start of a version-2 complex part: four coordinates in range,
/// `x0 ≤ x1`, `y0 ≤ y1`.
fn read_region(r: &mut Reader<'_>) -> Result<Region, FormatError> {
    let mut c = [0i32; 4];
    let fields = ["x0", "y0", "x1", "y1"];
    for (k, field) in fields.iter().enumerate() {
        let (v, at) = r.field::<i32>(Arena::Region, 0, field)?;
        // The upper corner must not be below the lower one.
        let min = match k {
            2 | 3 => c.get(k - 2).copied().unwrap_or(0),
            _ => -MAX_ABS_RAW,
        };
        if v < min || v > MAX_ABS_RAW {
            return Err(FormatError::Element {
                arena: Arena::Region,
                index: 0,
                field,
                offset: at,
                problem: Problem::NotInRange {
                    value: i64::from(v),
                    min: i64::from(min),
                    max: i64::from(MAX_ABS_RAW),
                },
            });
        }
        if let Some(slot) = c.get_mut(k) {
            *slot = v;
        }
    }
    let [x0, y0, x1, y1] = c;
    // In range and ordered (checked above), so this is always a box.
    Point::from_raw(x0, y0)
        .zip(Point::from_raw(x1, y1))
        .and_then(|(a, b)| Region::new(a, b))
        .ok_or(FormatError::Element {
            arena: Arena::Region,
            index: 0,
            field: "x0",
            offset: r.pos,
            problem: Problem::Malformed("not a box"),
        })
}

/// Decodes the complex part into `vertices[..V]` and `cylinders[..C]` and checks every id
/// and link: tangent vertices in range, on two objects, tangent there; vertices strictly
/// sorted by θ; cylinder objects, chains, walls and neighbours in range; walls in θ order;
/// neighbours symmetric with the same floor, ceiling and shared wall. A version-3 file
/// stores only the cylinders at θ = 0 (four ids each): the others are replayed from the
/// vertices (`open` holds the open cylinders meanwhile), and a vertex whose cylinders are
/// not open is named. Returns the region of a version-2 file.
fn decode_complex(
    bytes: &[u8],
    h: &Header,
    scene: &SceneRef<'_>,
    vertices: &mut [Vertex],
    cylinders: &mut [Cylinder],
    open: &mut [Slots],
) -> Result<Option<Region>, FormatError> {
    let nv = capacity(Arena::Vertex, h.complex_vertices, vertices.len())?;
    let nc = capacity(Arena::Cylinder, h.cylinders, cylinders.len())?;
    let vertices = vertices.get_mut(..nv).unwrap_or_default();
    let cylinders = cylinders.get_mut(..nc).unwrap_or_default();
    let range = h.part_range(Part::Complex);
    let mut r = Reader::new(bytes, range.clone());
    let region = if h.region {
        Some(read_region(&mut r)?)
    } else {
        None
    };
    if h.has_kept_map() {
        decode_pruned(bytes, h, *scene, r, vertices, cylinders, open)?;
        return Ok(region);
    }
    let start = r.pos;
    read_vertices(&mut r, Arena::Vertex, scene, vertices, true)?;
    if !h.replays_cylinders() {
        read_cylinders(&mut r, Arena::Cylinder, scene.len(), nv, cylinders)?;
        r.finish(Part::Complex)?;
        check_links(bytes, start, nv, cylinders)?;
        return Ok(region);
    }
    let initial = h.stored_cylinders() as usize;
    capacity(Arena::OpenSlot, open_slots(scene.len()) as u32, open.len())?;
    read_initial(
        &mut r,
        scene.len(),
        cylinders.get_mut(..initial).unwrap_or_default(),
    )?;
    r.finish(Part::Complex)?;
    replay(scene.len(), vertices, initial, cylinders, open)
        .map_err(|e| replay_error(bytes, start, nv, initial, e))?;
    Ok(region)
}

/// A replay failure as the stored element at fault: the cylinder at θ = 0, or the vertex
/// that opened (or failed to close) the cylinder. `start`: the first vertex's offset,
/// `nv`: the stored vertices.
fn replay_error(
    bytes: &[u8],
    start: usize,
    nv: usize,
    initial: usize,
    e: ReplayError,
) -> FormatError {
    let stored = |i: usize| i < initial;
    let (arena, index, why) = match e {
        ReplayError::Lost(v) => (
            Arena::Vertex,
            v,
            "a corner face it closes has no open cylinder",
        ),
        ReplayError::Crowded(i) => (
            Arena::Cylinder,
            i,
            "a third cylinder at θ = 0 on its bottom or top chain",
        ),
        ReplayError::Unmatched(i) if stored(i) => (
            Arena::Cylinder,
            i,
            "not continued by exactly one cylinder open at θ = 2π",
        ),
        ReplayError::Unmatched(i) => (
            Arena::Vertex,
            (i - initial) / 3,
            "a cylinder it opens continues into no cylinder at θ = 0",
        ),
        ReplayError::Storage | ReplayError::Input => (Arena::Cylinder, 0, "storage too small"),
    };
    let skip = match arena {
        Arena::Vertex => index.saturating_mul(2),
        _ => nv.saturating_mul(2).saturating_add(index.saturating_mul(4)),
    };
    FormatError::Element {
        arena,
        index,
        field: if arena == Arena::Vertex {
            "first"
        } else {
            "floor"
        },
        offset: varint_offset(bytes, start, skip),
        problem: Problem::Replay(why),
    }
}

/// The rest of a version-4 complex part after the region (`docs/format.md`, "Version
/// 4"): the count of all vertices, the vertices, the cylinders at θ = 0 and the kept map,
/// replayed streaming into the kept arenas `vertices` and `cylinders` (the header's
/// counts): the storage is theirs and `open`'s, never the whole complex's.
fn decode_pruned(
    bytes: &[u8],
    h: &Header,
    scene: SceneRef<'_>,
    mut r: Reader<'_>,
    vertices: &mut [Vertex],
    cylinders: &mut [Cylinder],
    open: &mut [Slots],
) -> Result<(), FormatError> {
    let n = scene.len();
    let initial = h.stored_cylinders() as usize;
    capacity(Arena::OpenSlot, open_slots(n) as u32, open.len())?;
    let (all, at) = r.field::<u32>(Arena::Vertex, 0, "count")?;
    let count = |problem| FormatError::Count {
        field: "all_vertices",
        offset: at,
        count: u64::from(all),
        problem,
    };
    // Against the part before anything is read: what is left must hold all vertices, the
    // cylinders at θ = 0 and the kept map's length.
    let left = r.end.saturating_sub(r.pos) as u64;
    let needed = u64::from(all) * super::MIN_VERTEX_BYTES
        + initial as u64 * super::MIN_INITIAL_CYLINDER_BYTES
        + 1;
    if needed > left {
        return Err(count(CountProblem::ExceedsPart {
            min_bytes: needed,
            part_bytes: left,
        }));
    }
    let all = all as usize;
    if all < vertices.len() {
        return Err(count(CountProblem::Inconsistent));
    }
    let start = r.pos;
    // Find the cylinders at θ = 0 and the kept map past the vertices (read again, and
    // checked, by the replay).
    for i in 0..all {
        r.field::<u32>(Arena::Vertex, i, "first")?;
        r.field::<u32>(Arena::Vertex, i, "second")?;
    }
    let initial_start = r.pos;
    for i in 0..initial {
        read_initial_one(&mut r, n, i)?;
    }
    let (len, len_at) = r.field::<u32>(Arena::KeptMap, 0, "length")?;
    let kept_map = |field, offset, why| FormatError::Element {
        arena: Arena::KeptMap,
        index: 0,
        field,
        offset,
        problem: Problem::KeptMap(why),
    };
    // In `u64`: no overflow on 32-bit targets (`all` < 2³¹ by the check above).
    let replayed = initial as u64 + 3 * all as u64;
    let wrong_length = kept_map("length", len_at, "not one bit per replayed cylinder");
    if u64::from(len) != replayed.div_ceil(8) {
        return Err(wrong_length);
    }
    let replayed = usize::try_from(replayed).map_err(|_| wrong_length)?;
    let map_at = r.pos;
    let map_end = map_at.checked_add(len as usize).filter(|&e| e <= r.end);
    let map = map_end.and_then(|e| bytes.get(map_at..e)).ok_or(kept_map(
        "bits",
        map_at,
        "its part ends inside it",
    ))?;
    r.pos = map_at + map.len();
    r.finish(Part::Complex)?;
    if !replayed.is_multiple_of(8) && map.last().is_some_and(|b| b >> (replayed % 8) != 0) {
        return Err(kept_map(
            "bits",
            r.pos - 1,
            "a bit past the last cylinder is set",
        ));
    }
    let ones: usize = map.iter().map(|b| b.count_ones() as usize).sum();
    if ones != cylinders.len() {
        return Err(FormatError::Count {
            field: "cylinders",
            offset: super::offset::CYLINDERS,
            count: u64::from(h.cylinders),
            problem: CountProblem::Inconsistent,
        });
    }
    let mut stream = Pruned {
        scene,
        vertex_reader: Reader {
            bytes,
            pos: start,
            end: initial_start,
        },
        next_vertex: 0,
        previous: None,
        initial_reader: Reader {
            bytes,
            pos: initial_start,
            end: len_at,
        },
        initial_start,
        map,
        vertices,
        cylinders,
        error: None,
    };
    let kept_vertices_wrong = FormatError::Count {
        field: "complex_vertices",
        offset: super::offset::COMPLEX_VERTICES,
        count: u64::from(h.complex_vertices),
        problem: CountProblem::Inconsistent,
    };
    let (kept_vertices, _) =
        replay_stream(n, initial, all, &mut stream, open).map_err(|e| match e {
            ReplayError::Input => stream.error.unwrap_or(kept_vertices_wrong),
            ReplayError::Storage => kept_vertices_wrong,
            e => replay_error(bytes, start, all, initial, e),
        })?;
    if kept_vertices != stream.vertices.len() {
        return Err(kept_vertices_wrong);
    }
    Ok(())
}

/// The replay's input from a version-4 file, and the kept arenas it fills.
struct Pruned<'b, 's, 'o> {
    scene: SceneRef<'s>,
    vertex_reader: Reader<'b>,
    next_vertex: usize,
    previous: Option<Angle>,
    initial_reader: Reader<'b>,
    initial_start: usize,
    map: &'b [u8],
    vertices: &'o mut [Vertex],
    cylinders: &'o mut [Cylinder],
    /// The first failure to read the input.
    error: Option<FormatError>,
}

impl Pruned<'_, '_, '_> {
    fn input<T>(&mut self, read: Result<T, FormatError>) -> Result<T, ReplayError> {
        read.map_err(|e| {
            self.error = Some(e);
            ReplayError::Input
        })
    }
}

impl Stream for Pruned<'_, '_, '_> {
    fn vertex(&mut self) -> Result<Vertex, ReplayError> {
        let i = self.next_vertex;
        self.next_vertex += 1;
        let read = read_vertex(
            &mut self.vertex_reader,
            Arena::Vertex,
            &self.scene,
            i,
            Some(&mut self.previous),
        );
        self.input(read)
    }

    fn initial(&mut self, i: usize) -> Result<Cylinder, ReplayError> {
        if i == 0 {
            self.initial_reader.pos = self.initial_start;
        }
        let read = read_initial_one(&mut self.initial_reader, self.scene.len(), i);
        self.input(read)
    }

    fn keep(&mut self, id: usize) -> Result<bool, ReplayError> {
        let byte = self.map.get(id / 8).ok_or(ReplayError::Storage)?;
        Ok(byte >> (id % 8) & 1 == 1)
    }

    fn put_vertex(&mut self, new: usize, v: &Vertex) -> Result<(), ReplayError> {
        *self.vertices.get_mut(new).ok_or(ReplayError::Storage)? = *v;
        Ok(())
    }

    fn cylinders(&mut self) -> &mut [Cylinder] {
        self.cylinders
    }
}

/// Reads the cylinders at θ = 0 of a version-3 file: floor, ceiling, bottom and top, each
/// checked as read like a whole cylinder's (the replay sets the rest).
fn read_initial(
    r: &mut Reader<'_>,
    objects: usize,
    cylinders: &mut [Cylinder],
) -> Result<(), FormatError> {
    for (i, slot) in cylinders.iter_mut().enumerate() {
        *slot = read_initial_one(r, objects, i)?;
    }
    Ok(())
}

/// Cylinder `i` of [`read_initial`].
fn read_initial_one(r: &mut Reader<'_>, n: usize, i: usize) -> Result<Cylinder, FormatError> {
    let a = Arena::Cylinder;
    Ok(Cylinder {
        floor: object(r.opt_id(a, i, "floor", n)?),
        ceiling: object(r.opt_id(a, i, "ceiling", n)?),
        bottom: chain(r.opt_id(a, i, "bottom", 2 * n)?),
        top: chain(r.opt_id(a, i, "top", 2 * n)?),
        ..BLANK_CYLINDER
    })
}

/// Decodes the history part (`docs/format.md`, "History part") into the arenas of
/// [`HistoryParts`](crate::partition::HistoryParts): the vertex count prefix against the
/// part's length, then every element and id as read. The DAG itself (acyclic, leaves =
/// live) is checked by `History::from_parts`.
#[cfg(feature = "alloc")]
fn decode_history(
    bytes: &[u8],
    h: &Header,
    scene: &SceneRef<'_>,
) -> Result<crate::partition::HistoryParts, FormatError> {
    use alloc::vec;
    use alloc::vec::Vec;
    let range = h.part_range(Part::History);
    let mut r = Reader::new(bytes, range.clone());
    let n = scene.len();
    let (nn, nl) = (h.history_nodes as usize, h.history_links as usize);
    let (hv, at) = r.field::<u32>(Arena::HistoryVertex, 0, "count")?;
    // The count against what is left of the part after the other arenas' minimum, before
    // anything is reserved.
    let rest = (nn as u64) * super::MIN_NODE_BYTES
        + (nl as u64) * super::MIN_LINK_BYTES
        + (n as u64) * super::MIN_INSERTION_BYTES;
    let left = (range.end.saturating_sub(r.pos)) as u64;
    let needed = rest + u64::from(hv) * super::MIN_VERTEX_BYTES;
    if needed > left {
        return Err(FormatError::Count {
            field: "history_vertices",
            offset: at,
            count: u64::from(hv),
            problem: CountProblem::ExceedsPart {
                min_bytes: needed,
                part_bytes: left,
            },
        });
    }
    let mut vertices = vec![BLANK_VERTEX; hv as usize];
    read_vertices(&mut r, Arena::HistoryVertex, scene, &mut vertices, false)?;
    let mut nodes = vec![BLANK_CYLINDER; nn];
    read_cylinders(&mut r, Arena::Node, n, hv as usize, &mut nodes)?;
    // Child counts; the ranges are their prefix sums (derived, not stored).
    let mut children = Vec::with_capacity(nn);
    let mut total = 0usize;
    for i in 0..nn {
        let (k, at) = r.field::<u32>(Arena::Node, i, "children")?;
        let left = nl - total;
        if k as usize > left {
            return Err(FormatError::Element {
                arena: Arena::Node,
                index: i,
                field: "children",
                offset: at,
                problem: Problem::OutOfRange {
                    value: u64::from(k),
                    limit: left as u64 + 1,
                },
            });
        }
        children.push((total as u32, k));
        total += k as usize;
    }
    if total != nl {
        return Err(FormatError::Count {
            field: "history_links",
            offset: super::offset::HISTORY_LINKS,
            count: nl as u64,
            problem: CountProblem::Inconsistent,
        });
    }
    let mut links = Vec::with_capacity(nl);
    for j in 0..nl {
        let id = r.id(Arena::Link, j, "node", nn)?;
        links.push(CylinderId::from_index(id).unwrap_or(CylinderId::ZERO));
    }
    let (mut order, mut starts) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for k in 0..n {
        order.push(ObjectId(r.id(Arena::Insertion, k, "object", n)? as u32));
        starts.push(r.id(Arena::Insertion, k, "first_node", nn + 1)? as u32);
    }
    r.finish(Part::History)?;
    Ok(crate::partition::HistoryParts {
        nodes,
        children,
        links,
        vertices,
        order,
        starts,
        // Both kinds load; `History::validate` checks a compacted one has no piece nodes.
        compacted: h.compacted,
    })
}

/// Position of a wall in θ order: θ = 0 first, then by vertex (vertices are sorted).
fn wall_rank(w: Wall) -> usize {
    match w {
        Wall::Zero => 0,
        Wall::Vertex(v) => v.index() + 1,
    }
}

/// Links between cylinders (all ids already in range).
fn check_links(
    bytes: &[u8],
    part_start: usize,
    vertices: usize,
    cylinders: &[Cylinder],
) -> Result<(), FormatError> {
    let fail = |i: usize, field, problem| FormatError::Element {
        arena: Arena::Cylinder,
        index: i,
        field,
        // Each vertex is 2 varints and each cylinder 8: skip to this cylinder's first.
        offset: varint_offset(bytes, part_start, 2 * vertices + 8 * i),
        problem,
    };
    for (i, c) in cylinders.iter().enumerate() {
        if c.right != Wall::Zero && wall_rank(c.left) >= wall_rank(c.right) {
            return Err(fail(i, "right", Problem::WallOrder));
        }
        if let Some(r) = c.right_neighbour {
            let n = cylinders.get(r.index()).ok_or_else(|| {
                fail(
                    i,
                    "right_neighbour",
                    Problem::OutOfRange {
                        value: r.index() as u64,
                        limit: cylinders.len() as u64,
                    },
                )
            })?;
            if n.left_neighbour.map(CylinderId::index) != Some(i) {
                return Err(fail(i, "right_neighbour", Problem::NotSymmetric));
            }
            if n.floor != c.floor || n.ceiling != c.ceiling || n.left != c.right {
                return Err(fail(i, "right_neighbour", Problem::NeighbourMismatch));
            }
        }
        if let Some(l) = c.left_neighbour {
            let n = cylinders.get(l.index()).ok_or_else(|| {
                fail(
                    i,
                    "left_neighbour",
                    Problem::OutOfRange {
                        value: l.index() as u64,
                        limit: cylinders.len() as u64,
                    },
                )
            })?;
            if n.right_neighbour.map(CylinderId::index) != Some(i) {
                return Err(fail(i, "left_neighbour", Problem::NotSymmetric));
            }
        }
    }
    Ok(())
}

/// The byte offset after skipping `k` varints from `start` (for error messages only: the
/// bytes were decoded already, so every varint ends).
fn varint_offset(bytes: &[u8], start: usize, k: usize) -> usize {
    let mut pos = start;
    let mut left = k;
    while left > 0 {
        match bytes.get(pos) {
            Some(b) => {
                if b & 0x80 == 0 {
                    left -= 1;
                }
                pos += 1;
            }
            None => break,
        }
    }
    pos
}

/// Decodes and validates a file into caller storage, without allocating: `scratch`
/// (objects and points of the scene part, free again afterwards), `vertices` and
/// `cylinders` (kept: the result borrows them), each at least as large as the header's
/// counts ([`Header::read`] gives them first). The scene is validated into a
/// [`FixedScene`] with capacity `V` vertices and `O` objects.
///
/// Checked: everything [`Header::read`] checks, every element and id (see `decode_complex`
/// in the source for the list). The cross-section and count checks of
/// [`Complex::validate`](crate::partition::Complex::validate) and the rebuild of the
/// derived adjacency need `alloc` ([`decode`]).
pub fn decode_into<'a, const V: usize, const O: usize>(
    bytes: &[u8],
    scratch: Scratch<'_>,
    vertices: &'a mut [Vertex],
    cylinders: &'a mut [Cylinder],
) -> Result<Decoded<'a, V, O>, FormatError> {
    // The history part is skipped (a device walks without it); `Header::read` checked its
    // length and the checksum over it.
    let header = Header::read(bytes)?;
    capacity(Arena::Object, header.objects, O)?;
    capacity(Arena::Point, header.scene_vertices, V)?;
    decode_scene(bytes, &header, scratch.objects, scratch.points)?;
    let n = header.objects as usize;
    let nv = header.scene_vertices as usize;
    let scene = FixedScene::<V, O>::new(scene_input(
        scratch.objects.get(..n).unwrap_or_default(),
        scratch.points.get(..nv).unwrap_or_default(),
    ))
    .map_err(|error| FormatError::Scene {
        offset: super::HEADER_LEN,
        error,
    })?;
    let region = decode_complex(
        bytes,
        &header,
        &scene.as_ref(),
        vertices,
        cylinders,
        scratch.open,
    )?;
    let (kv, kc) = (header.complex_vertices as usize, header.cylinders as usize);
    Ok(Decoded {
        header,
        scene,
        vertices: vertices.get(..kv).unwrap_or_default(),
        cylinders: cylinders.get(..kc).unwrap_or_default(),
        region,
    })
}

/// A file decoded into owned storage and fully validated.
#[cfg(feature = "alloc")]
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The header.
    pub header: Header,
    /// The scene (validated by `Scene::new`).
    pub scene: crate::scene::Scene,
    /// The complex (validated by `Complex::from_parts`: derived state rebuilt).
    pub complex: crate::partition::Complex,
    /// The history, if the file has one (validated by `History::from_parts`; its live
    /// cylinders are the complex's).
    pub history: Option<crate::partition::History>,
}

/// Decodes and fully validates a file: [`decode_into`]'s checks, then
/// [`Complex::from_parts`](crate::partition::Complex::from_parts) — the rebuilt adjacency
/// and [`Complex::validate`](crate::partition::Complex::validate) — and, if the file has
/// a history, its arenas element by element, `History::from_parts` (ids, insertion order,
/// acyclicity, leaves = live, derived state rebuilt) and the equality of its live
/// partition with the complex part. Allocation is bounded
/// by a small multiple of `bytes.len()`: every count was checked against its part's
/// length before anything is reserved.
#[cfg(feature = "alloc")]
pub fn decode(bytes: &[u8]) -> Result<Loaded, FormatError> {
    use alloc::vec;
    let header = Header::read(bytes)?;
    let mut objects = vec![SceneObject::BLANK; header.objects as usize];
    let mut points = vec![Point::default(); header.scene_vertices as usize];
    decode_scene(bytes, &header, &mut objects, &mut points)?;
    let scene = crate::scene::Scene::new(scene_input(&objects, &points)).map_err(|error| {
        FormatError::Scene {
            offset: super::HEADER_LEN,
            error,
        }
    })?;
    drop((objects, points));
    let mut vertices = vec![BLANK_VERTEX; header.complex_vertices as usize];
    let mut cylinders = vec![BLANK_CYLINDER; header.cylinders as usize];
    let scene_ref = scene.as_ref();
    let mut open = if header.replays_cylinders() {
        vec![crate::partition::ZERO_SLOTS; open_slots(scene_ref.len())]
    } else {
        vec![]
    };
    let region = decode_complex(
        bytes,
        &header,
        &scene_ref,
        &mut vertices,
        &mut cylinders,
        &mut open,
    )?;
    drop(open);
    // A region file is checked with what a pruned complex still satisfies
    // (`Complex::validate`).
    let complex =
        crate::partition::Complex::from_region_parts(&scene_ref, region, vertices, cylinders)
            .map_err(|error| FormatError::Complex {
                offset: header.part_range(Part::Complex).start,
                error,
            })?;
    let history = if header.has_history() {
        let offset = header.part_range(Part::History).start;
        let fail = |error| FormatError::History { offset, error };
        let parts = decode_history(bytes, &header, &scene_ref)?;
        let history = crate::partition::History::from_parts(&scene_ref, parts).map_err(fail)?;
        check_history_complex(&scene_ref, &history, &complex).map_err(fail)?;
        Some(history)
    } else {
        None
    };
    Ok(Loaded {
        header,
        scene,
        complex,
        history,
    })
}

/// With a history, the complex part must be its live partition as `History::complex`
/// numbers it: then a cylinder found by point location in the history is the complex's.
#[cfg(feature = "alloc")]
fn check_history_complex(
    scene: &SceneRef<'_>,
    history: &crate::partition::History,
    complex: &crate::partition::Complex,
) -> Result<(), crate::partition::ComplexError> {
    let live = history.complex(scene)?;
    if live.vertices() != complex.vertices() || live.cylinders() != complex.cylinders() {
        return Err(crate::partition::ComplexError::History {
            node: 0,
            what: "its live partition differs from the complex part",
        });
    }
    Ok(())
}
