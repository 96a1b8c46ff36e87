//! Scenes: pairwise-disjoint convex polygons with a material each.
//!
//! A scene is only ever seen through a validated view, [`SceneRef`]: every object has at
//! least three vertices in strictly convex counter-clockwise order, every coordinate is in
//! range, and no two objects touch or overlap. Storage is either caller-provided with
//! fixed capacity ([`FixedScene`], `no_std`) or growable (`Scene`, feature `alloc`).
//!
//! Ids: object id = index of the object in the input; vertex id = index of the vertex in
//! that object's input list, *as written*. Internally vertices are stored counter-clockwise;
//! [`Object::written_vertex_id`] maps back.

mod validate;

pub use validate::SceneError;

use crate::geom::Point;

/// Index of an object in its scene (the order of the input file).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(transparent)]
pub struct ObjectId(pub u32);

/// Largest number of objects in a scene.
pub const MAX_OBJECTS: usize = 1 << 24;
/// Largest total number of vertices in a scene (vertex ranks for the perturbation fit in
/// `u32` with room for query points).
pub const MAX_VERTICES: usize = 1 << 26;

/// Refractive index on a 2⁻¹⁶ grid: raw `u32`, `MIN_RAW ≤ raw ≤ MAX_RAW`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Eta(u32);

impl Eta {
    /// Fractional bits of the refractive index.
    pub const FRAC_BITS: u32 = 16;
    /// Smallest raw index: 1/64.
    pub const MIN_RAW: u32 = 1 << 10;
    /// Largest raw index: 64.
    pub const MAX_RAW: u32 = 64 << 16;

    /// An index from its raw value; `None` if outside `[1/64, 64]`.
    pub const fn from_raw(raw: u32) -> Option<Eta> {
        if raw < Eta::MIN_RAW || raw > Eta::MAX_RAW {
            None
        } else {
            Some(Eta(raw))
        }
    }

    /// The index nearest to `v`; `None` if `v` is not finite or the rounded value is
    /// outside `[1/64, 64]`.
    pub fn from_f64(v: f64) -> Option<Eta> {
        if !v.is_finite() {
            return None;
        }
        let r = libm::round(v * (1u32 << Eta::FRAC_BITS) as f64);
        if r < Eta::MIN_RAW as f64 || r > Eta::MAX_RAW as f64 {
            return None;
        }
        Some(Eta(r as u32))
    }

    /// Raw value in units of 2⁻¹⁶.
    pub const fn raw(self) -> u32 {
        self.0
    }

    /// The index as a float, for output.
    pub fn to_f64(self) -> f64 {
        self.0 as f64 / (1u32 << Eta::FRAC_BITS) as f64
    }
}

/// What light does at an object.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Material {
    /// Stops rays.
    Opaque,
    /// Reflects rays across the hit edge.
    Mirror,
    /// Refracts rays by the tangent law (DESIGN.md §6) with this index.
    Refractive {
        /// Refractive index of the object's interior (outside is 1).
        eta: Eta,
    },
    /// Transparent: rays pass unchanged. Screens cut the complex into smaller parts.
    Screen,
}

impl Material {
    /// Name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Material::Opaque => "opaque",
            Material::Mirror => "mirror",
            Material::Refractive { .. } => "refractive",
            Material::Screen => "screen",
        }
    }
}

/// One validated object: a strictly convex polygon stored counter-clockwise.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Object {
    /// What the object does to rays.
    pub material: Material,
    /// First vertex in the scene's vertex array.
    start: u32,
    /// Number of vertices (≥ 3).
    len: u32,
    /// Whether the input listed the vertices clockwise (so storage reversed them).
    reversed: bool,
    /// Lower-left corner of the bounding box.
    min: Point,
    /// Upper-right corner of the bounding box.
    max: Point,
}

impl Object {
    /// Number of vertices.
    #[inline]
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Always false: a validated object has at least three vertices.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Index of this object's first vertex in [`SceneRef::vertices`]; its vertices are
    /// `first_vertex() .. first_vertex() + len()`, counter-clockwise. The global index is
    /// also the vertex's rank in the symbolic perturbation.
    #[inline]
    pub fn first_vertex(&self) -> usize {
        self.start as usize
    }

    /// The id (index in the input list) of the `k`-th counter-clockwise vertex.
    #[inline]
    pub fn written_vertex_id(&self, k: usize) -> usize {
        if self.reversed {
            (self.len() - k) % self.len()
        } else {
            k
        }
    }

    /// Whether the input listed this object's vertices clockwise.
    #[inline]
    pub fn was_clockwise(&self) -> bool {
        self.reversed
    }

    /// Lower-left and upper-right corners of the bounding box.
    #[inline]
    pub fn bbox(&self) -> (Point, Point) {
        (self.min, self.max)
    }
}

/// A validated scene, borrowed: the view every algorithm takes.
#[derive(Clone, Copy, Debug)]
pub struct SceneRef<'a> {
    vertices: &'a [Point],
    objects: &'a [Object],
}

impl<'a> SceneRef<'a> {
    /// All vertices, object after object, each object counter-clockwise.
    #[inline]
    pub fn vertices(&self) -> &'a [Point] {
        self.vertices
    }

    /// All objects, in input order.
    #[inline]
    pub fn objects(&self) -> &'a [Object] {
        self.objects
    }

    /// Number of objects.
    #[inline]
    pub fn len(&self) -> usize {
        self.objects.len()
    }

    /// Whether the scene has no objects.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    /// The object with this id.
    #[inline]
    pub fn object(&self, id: ObjectId) -> Option<&'a Object> {
        self.objects.get(id.0 as usize)
    }

    /// The counter-clockwise vertices of an object.
    #[inline]
    pub fn polygon(&self, object: &Object) -> &'a [Point] {
        // A validated scene stores every object's range inside `vertices`.
        self.vertices
            .get(object.first_vertex()..object.first_vertex() + object.len())
            .unwrap_or(&[])
    }
}

/// A scene in fixed-capacity storage: at most `V` vertices and `O` objects, no heap.
#[derive(Clone, Debug, Default)]
pub struct FixedScene<const V: usize, const O: usize> {
    vertices: heapless::Vec<Point, V>,
    objects: heapless::Vec<Object, O>,
    /// Scratch for the broad phase of the disjointness check.
    order: heapless::Vec<u32, O>,
}

impl<const V: usize, const O: usize> FixedScene<V, O> {
    /// Validates the objects and stores them. Errors name the object (and vertex) at fault.
    pub fn new<'p, I>(objects: I) -> Result<Self, SceneError>
    where
        I: IntoIterator<Item = (Material, &'p [Point])>,
    {
        let mut s = FixedScene {
            vertices: heapless::Vec::new(),
            objects: heapless::Vec::new(),
            order: heapless::Vec::new(),
        };
        for (i, (material, pts)) in objects.into_iter().enumerate() {
            let obj = validate::polygon(i, material, pts, s.vertices.len())?;
            if s.vertices.len() + pts.len() > V {
                return Err(SceneError::CapacityExceeded { object: i });
            }
            s.objects
                .push(obj)
                .map_err(|_| SceneError::CapacityExceeded { object: i })?;
            s.order
                .push(i as u32)
                .map_err(|_| SceneError::CapacityExceeded { object: i })?;
            validate::store_ccw(pts, obj.was_clockwise(), |p| {
                // Capacity was checked above.
                let _ = s.vertices.push(p);
            });
        }
        validate::disjoint(&s.vertices, &s.objects, &mut s.order)?;
        Ok(s)
    }

    /// The validated view.
    pub fn as_ref(&self) -> SceneRef<'_> {
        SceneRef {
            vertices: &self.vertices,
            objects: &self.objects,
        }
    }
}

/// A scene in growable storage.
#[cfg(feature = "alloc")]
#[derive(Clone, Debug, Default)]
pub struct Scene {
    vertices: alloc::vec::Vec<Point>,
    objects: alloc::vec::Vec<Object>,
}

#[cfg(feature = "alloc")]
impl Scene {
    /// Validates the objects and stores them. Errors name the object (and vertex) at fault.
    pub fn new<'p, I>(objects: I) -> Result<Scene, SceneError>
    where
        I: IntoIterator<Item = (Material, &'p [Point])>,
    {
        let mut s = Scene::default();
        for (i, (material, pts)) in objects.into_iter().enumerate() {
            if i >= MAX_OBJECTS || s.vertices.len() + pts.len() > MAX_VERTICES {
                return Err(SceneError::CapacityExceeded { object: i });
            }
            let obj = validate::polygon(i, material, pts, s.vertices.len())?;
            s.objects.push(obj);
            validate::store_ccw(pts, obj.was_clockwise(), |p| s.vertices.push(p));
        }
        let mut order: alloc::vec::Vec<u32> = (0..s.objects.len() as u32).collect();
        validate::disjoint(&s.vertices, &s.objects, &mut order)?;
        Ok(s)
    }

    /// The validated view.
    pub fn as_ref(&self) -> SceneRef<'_> {
        SceneRef {
            vertices: &self.vertices,
            objects: &self.objects,
        }
    }
}

/// A subset of a validated scene's objects, sharing its vertex array — so vertex ranks,
/// and with them the perturbation, are those of the whole scene. Object ids in the
/// subset's [`SceneRef`] are positions in the subset; [`SubScene::original`] maps back.
/// Used for views (screens left out) and to compare the incremental construction with
/// the partition of each prefix of the insertion order.
#[cfg(feature = "alloc")]
#[derive(Clone, Debug)]
pub struct SubScene<'a> {
    vertices: &'a [Point],
    objects: alloc::vec::Vec<Object>,
    ids: alloc::vec::Vec<ObjectId>,
}

#[cfg(feature = "alloc")]
impl<'a> SubScene<'a> {
    /// The objects of `scene` with the given ids, in that order (unknown ids are skipped).
    /// Any subset of a valid scene is valid.
    pub fn new(scene: SceneRef<'a>, ids: impl IntoIterator<Item = ObjectId>) -> SubScene<'a> {
        let mut objects = alloc::vec::Vec::new();
        let mut kept = alloc::vec::Vec::new();
        for id in ids {
            if let Some(o) = scene.object(id) {
                objects.push(*o);
                kept.push(id);
            }
        }
        SubScene {
            vertices: scene.vertices,
            objects,
            ids: kept,
        }
    }

    /// The validated view of the subset.
    pub fn as_ref(&self) -> SceneRef<'_> {
        SceneRef {
            vertices: self.vertices,
            objects: &self.objects,
        }
    }

    /// The id in the whole scene of the subset's object `id`.
    pub fn original(&self, id: ObjectId) -> Option<ObjectId> {
        self.ids.get(id.0 as usize).copied()
    }
}
