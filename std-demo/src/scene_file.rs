//! The JSON scene interchange format.
//!
//! ```json
//! {
//!   "generated_by": "anything: extra top-level fields are kept",
//!   "objects": [
//!     {"name": "box", "material": "opaque", "vertices": [[0, 0], [4, 0], [4, 3], [0, 3]]},
//!     {"material": "refractive", "eta": 1.5, "vertices": [[6, 0], [9, 0], [7.5, 2]]},
//!     {"material": "mirror", "vertices": [[0, 5], [0, 6], [3, 5.5]]},
//!     {"material": "screen", "vertices": [[5, 4], [5.25, 4], [5.25, 8], [5, 8]]}
//!   ]
//! }
//! ```
//!
//! * **Ids**: object id = index in `objects`; vertex id = index in `vertices`, as written.
//!   Every error and every later output (views, ray trees) uses these ids.
//! * **Winding**: either; the scene stores counter-clockwise and remembers the input's.
//! * **Materials**: `"opaque"`, `"mirror"`, `"screen"`, and `"refractive"` with a required
//!   `"eta"` (a number in `[1/64, 64]`, rounded to the 2⁻¹⁶ grid).
//!   `"eta"` on any other material is rejected ([`SceneFileError::EtaOnNonRefractive`]):
//!   it is almost always a typo in the material, and ignoring it would hide that.
//! * **Coordinates**: numbers, rounded to the nearest point of the 2⁻¹⁶ grid; the absolute
//!   value must stay below 16384 (see [`vcx::geom::point::MAX_ABS_RAW`]). Validation runs
//!   on the rounded points. When it fails on objects that rounding moved, and the same
//!   objects as written pass on a grid up to 2¹⁶ times finer (or are too large to try),
//!   the error says the problem appeared after rounding ([`SceneFileError::Scene`]).
//! * **Extra fields** (`name`, `color`, anything) on objects and at the top level are kept
//!   in [`ObjectMeta::extra`] and [`SceneFile::top`], and written back by [`to_json`].
//!
//! [`to_json`] writes coordinates exactly (`raw / 65536` as an `f64`, which is exact), in
//! the input's vertex order and winding, so `parse(to_json(f))` gives back the same scene;
//! `eta` is written as the shortest decimal that rounds to the same index (1.33 stays 1.33).
//! Top-level extra fields come first and `"objects"` last; within an object, extra fields
//! come first (in their written order), then `material`, `eta`, `vertices`.

use core::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;
use serde_json::{Map, Value};
use vcx::geom::point::{FRAC_BITS, MAX_ABS_RAW};
use vcx::geom::{CoordinateError, Point};
use vcx::{Eta, Material, Scene, SceneError};

// Messages say the range is |v| <= 16384 - 2^-16.
const _: () = assert!(MAX_ABS_RAW == (1 << 30) - 1);

/// The scene grid, for messages and summaries.
pub const GRID: &str = "2^-16";

/// What a scene file holds besides the scene itself, for one object.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectMeta {
    /// Every field other than `material`, `eta` and `vertices`, in written order.
    pub extra: Map<String, Value>,
    /// How many of the object's vertices rounding to the grid moved.
    pub rounded_vertices: usize,
}

impl ObjectMeta {
    /// The object's `name` field, if it has a string one.
    pub fn name(&self) -> Option<&str> {
        self.extra.get("name").and_then(Value::as_str)
    }
}

/// A parsed and validated scene file.
#[derive(Clone, Debug)]
pub struct SceneFile {
    /// The validated scene; object `i` is the file's object `i`.
    pub scene: Scene,
    /// One entry per object, in the same order.
    pub meta: Vec<ObjectMeta>,
    /// Top-level fields other than `objects`, in written order.
    pub top: Map<String, Value>,
}

/// One object to build a [`SceneFile`] from (used by the generators).
#[derive(Clone, Debug)]
pub struct ObjectSpec {
    /// What the object does to rays.
    pub material: Material,
    /// Vertices in written order (either winding).
    pub vertices: Vec<Point>,
    /// Extra fields to keep, such as `name`.
    pub extra: Map<String, Value>,
}

impl SceneFile {
    /// Validates the objects and keeps their extra fields. The points are already on the
    /// grid, so no object counts as rounded.
    pub fn new(objects: Vec<ObjectSpec>, top: Map<String, Value>) -> Result<Self, SceneError> {
        let scene = Scene::new(objects.iter().map(|o| (o.material, o.vertices.as_slice())))?;
        let meta = objects
            .into_iter()
            .map(|o| ObjectMeta {
                extra: o.extra,
                rounded_vertices: 0,
            })
            .collect();
        Ok(SceneFile { scene, meta, top })
    }

    /// Number of vertices, over all objects, that rounding to the grid moved.
    pub fn rounded_vertices(&self) -> usize {
        self.meta.iter().map(|m| m.rounded_vertices).sum()
    }

    /// The file as JSON text; see [`to_json`].
    pub fn to_json(&self) -> String {
        to_json(self)
    }
}

/// Which coordinate of a vertex.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Axis {
    /// The first number of the pair.
    X,
    /// The second number of the pair.
    Y,
}

impl fmt::Display for Axis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Axis::X => "x",
            Axis::Y => "y",
        })
    }
}

/// Why a scene file was rejected. `Display` is one line that names the object and vertex
/// (or the JSON line and column) at fault; object and vertex numbers are indices as
/// written, counting from 0.
#[derive(Debug)]
#[non_exhaustive]
pub enum SceneFileError {
    /// The file could not be read. Check the path and permissions.
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The text is not JSON. Fix the syntax at that place.
    InvalidJson {
        /// Line, from 1.
        line: usize,
        /// Column (byte in the line), from 1.
        column: usize,
        /// Where in the scene that is (`object 2, vertex 1`), if it could be told.
        place: Option<String>,
        /// What the JSON parser expected.
        message: String,
    },
    /// The top level is not a JSON object. Wrap the scene in `{"objects": [...]}`.
    TopNotObject,
    /// The top-level object has no `objects` field. Add the list of objects.
    MissingObjects,
    /// `objects` is not an array. Make it a list of objects.
    ObjectsNotArray,
    /// An entry of `objects` is not a JSON object.
    ObjectNotMap {
        /// The object.
        object: usize,
    },
    /// An object has no `material`. Add one of opaque, mirror, refractive, screen.
    MissingMaterial {
        /// The object.
        object: usize,
    },
    /// `material` is not a string.
    MaterialNotString {
        /// The object.
        object: usize,
    },
    /// `material` is not one of opaque, mirror, refractive, screen.
    UnknownMaterial {
        /// The object.
        object: usize,
        /// What was written (shortened if long).
        name: String,
    },
    /// An object has no `vertices`. Add the list of `[x, y]` pairs.
    MissingVertices {
        /// The object.
        object: usize,
    },
    /// `vertices` is not an array.
    VerticesNotArray {
        /// The object.
        object: usize,
    },
    /// A vertex is not an array of exactly two numbers.
    VertexNotPair {
        /// The object.
        object: usize,
        /// The vertex.
        vertex: usize,
    },
    /// A coordinate is not finite (a number too large for a float, such as `1e999`).
    CoordinateNotFinite {
        /// The object.
        object: usize,
        /// The vertex.
        vertex: usize,
        /// Which coordinate.
        axis: Axis,
    },
    /// A coordinate is outside the grid's range (absolute value below 16384).
    /// Scale the scene down.
    CoordinateOutOfRange {
        /// The object.
        object: usize,
        /// The vertex.
        vertex: usize,
        /// Which coordinate.
        axis: Axis,
        /// The value written.
        value: f64,
    },
    /// A refractive object has no `eta`. Add its refractive index.
    EtaMissing {
        /// The object.
        object: usize,
    },
    /// `eta` is not a number.
    EtaNotNumber {
        /// The object.
        object: usize,
    },
    /// `eta` is not finite (a number too large for a float).
    EtaNotFinite {
        /// The object.
        object: usize,
    },
    /// `eta` is zero or negative.
    EtaNotPositive {
        /// The object.
        object: usize,
        /// The value written.
        value: f64,
    },
    /// `eta` is outside `[1/64, 64]` (after rounding to the 2⁻¹⁶ grid).
    EtaOutOfRange {
        /// The object.
        object: usize,
        /// The value written.
        value: f64,
    },
    /// `eta` is given on an object that is not refractive. Fix the material or drop `eta`.
    EtaOnNonRefractive {
        /// The object.
        object: usize,
        /// Its material.
        material: &'static str,
    },
    /// The scene itself is invalid (see [`SceneError`]).
    Scene {
        /// What the scene validation found.
        error: SceneError,
        /// Whether the problem appeared with rounding to the grid: rounding moved a
        /// coordinate of an object the error names, and those objects as written pass
        /// validation on a finer grid (or are too large to check that way).
        after_rounding: bool,
    },
}

impl SceneFileError {
    /// The first object the error names, if any.
    pub fn object(&self) -> Option<usize> {
        use SceneFileError as E;
        match *self {
            E::Io { .. }
            | E::TopNotObject
            | E::MissingObjects
            | E::ObjectsNotArray
            | E::InvalidJson { .. } => None,
            E::ObjectNotMap { object }
            | E::MissingMaterial { object }
            | E::MaterialNotString { object }
            | E::UnknownMaterial { object, .. }
            | E::MissingVertices { object }
            | E::VerticesNotArray { object }
            | E::VertexNotPair { object, .. }
            | E::CoordinateNotFinite { object, .. }
            | E::CoordinateOutOfRange { object, .. }
            | E::EtaMissing { object }
            | E::EtaNotNumber { object }
            | E::EtaNotFinite { object }
            | E::EtaNotPositive { object, .. }
            | E::EtaOutOfRange { object, .. }
            | E::EtaOnNonRefractive { object, .. } => Some(object),
            E::Scene { error, .. } => scene_error_objects(&error).first().copied(),
        }
    }
}

impl fmt::Display for SceneFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use SceneFileError as E;
        match self {
            E::Io { path, source } => write!(f, "cannot read {}: {source}", path.display()),
            E::InvalidJson {
                line,
                column,
                place,
                message,
            } => {
                write!(f, "invalid JSON at line {line}, column {column}")?;
                if let Some(place) = place {
                    write!(f, " ({place})")?;
                }
                write!(f, ": {message}")
            }
            E::TopNotObject => {
                f.write_str("the top level must be a JSON object with an \"objects\" array")
            }
            E::MissingObjects => f.write_str("no \"objects\" field at the top level"),
            E::ObjectsNotArray => f.write_str("\"objects\" must be an array"),
            E::ObjectNotMap { object } => {
                write!(f, "object {object}: must be a JSON object")
            }
            E::MissingMaterial { object } => write!(
                f,
                "object {object}: no \"material\" (one of opaque, mirror, refractive, screen)"
            ),
            E::MaterialNotString { object } => {
                write!(f, "object {object}: \"material\" must be a string")
            }
            E::UnknownMaterial { object, name } => write!(
                f,
                "object {object}: unknown material {name:?} \
                 (expected opaque, mirror, refractive or screen)"
            ),
            E::MissingVertices { object } => write!(f, "object {object}: no \"vertices\""),
            E::VerticesNotArray { object } => write!(
                f,
                "object {object}: \"vertices\" must be an array of [x, y] pairs"
            ),
            E::VertexNotPair { object, vertex } => write!(
                f,
                "object {object}, vertex {vertex}: must be a pair of numbers [x, y]"
            ),
            E::CoordinateNotFinite {
                object,
                vertex,
                axis,
            } => write!(
                f,
                "object {object}, vertex {vertex}: coordinate {axis} is not finite"
            ),
            E::CoordinateOutOfRange {
                object,
                vertex,
                axis,
                value,
            } => write!(
                f,
                "object {object}, vertex {vertex}: coordinate {axis} = {} is out of range \
                 (the grid holds |v| <= 16384 - 2^-16)",
                Num(*value),
            ),
            E::EtaMissing { object } => write!(
                f,
                "object {object}: refractive object needs \"eta\" (its refractive index)"
            ),
            E::EtaNotNumber { object } => {
                write!(f, "object {object}: \"eta\" must be a number")
            }
            E::EtaNotFinite { object } => write!(f, "object {object}: \"eta\" is not finite"),
            E::EtaNotPositive { object, value } => write!(
                f,
                "object {object}: \"eta\" = {} must be positive",
                Num(*value)
            ),
            E::EtaOutOfRange { object, value } => write!(
                f,
                "object {object}: \"eta\" = {} is out of range [{}, {}]",
                Num(*value),
                Num(f64::from(Eta::MIN_RAW) / f64::from(1u32 << Eta::FRAC_BITS)),
                Num(f64::from(Eta::MAX_RAW) / f64::from(1u32 << Eta::FRAC_BITS)),
            ),
            E::EtaOnNonRefractive { object, material } => write!(
                f,
                "object {object}: \"eta\" given but the material is {material}, not refractive"
            ),
            E::Scene {
                error,
                after_rounding,
            } => {
                write!(f, "{error}")?;
                if *after_rounding {
                    write!(f, " (after rounding coordinates to the {GRID} grid)")?;
                }
                Ok(())
            }
        }
    }
}

impl core::error::Error for SceneFileError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            SceneFileError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Reads and parses a scene file.
pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneFileError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| SceneFileError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_bytes(&bytes)
}

/// Parses a scene file's text.
pub fn parse(text: &str) -> Result<SceneFile, SceneFileError> {
    parse_bytes(text.as_bytes())
}

/// Parses a scene file's bytes (UTF-8 JSON; invalid UTF-8 is an [`InvalidJson`] error).
///
/// [`InvalidJson`]: SceneFileError::InvalidJson
pub fn parse_bytes(bytes: &[u8]) -> Result<SceneFile, SceneFileError> {
    let value: Value = serde_json::from_slice(bytes).map_err(|e| json_error(bytes, &e))?;
    from_value(value)
}

/// Builds a scene file from parsed JSON.
pub fn from_value(value: Value) -> Result<SceneFile, SceneFileError> {
    let Value::Object(mut top) = value else {
        return Err(SceneFileError::TopNotObject);
    };
    let objects = match top.shift_remove("objects") {
        None => return Err(SceneFileError::MissingObjects),
        Some(Value::Array(objects)) => objects,
        Some(_) => return Err(SceneFileError::ObjectsNotArray),
    };
    let mut materials = Vec::with_capacity(objects.len());
    let mut polygons = Vec::with_capacity(objects.len());
    let mut written = Vec::with_capacity(objects.len());
    let mut meta = Vec::with_capacity(objects.len());
    for (object, entry) in objects.into_iter().enumerate() {
        let Value::Object(mut fields) = entry else {
            return Err(SceneFileError::ObjectNotMap { object });
        };
        let material = material(object, &mut fields)?;
        let (polygon, numbers, rounded_vertices) = vertices(object, &mut fields)?;
        materials.push(material);
        polygons.push(polygon);
        written.push(numbers);
        meta.push(ObjectMeta {
            extra: fields,
            rounded_vertices,
        });
    }
    let scene = Scene::new(
        materials
            .iter()
            .copied()
            .zip(polygons.iter().map(Vec::as_slice)),
    )
    .map_err(|error| {
        let named = scene_error_objects(&error);
        let moved = named
            .iter()
            .any(|&i| meta.get(i).is_some_and(|m| m.rounded_vertices > 0));
        let as_written: Vec<&[[f64; 2]]> = named
            .iter()
            .filter_map(|&i| written.get(i).map(Vec::as_slice))
            .collect();
        SceneFileError::Scene {
            error,
            after_rounding: moved && valid_on_finer_grid(&as_written) != Some(false),
        }
    })?;
    Ok(SceneFile { scene, meta, top })
}

/// Takes `material` and `eta` out of an object's fields.
fn material(object: usize, fields: &mut Map<String, Value>) -> Result<Material, SceneFileError> {
    let name = match fields.shift_remove("material") {
        None => return Err(SceneFileError::MissingMaterial { object }),
        Some(Value::String(name)) => name,
        Some(_) => return Err(SceneFileError::MaterialNotString { object }),
    };
    let eta = fields.shift_remove("eta");
    let material = match name.as_str() {
        "opaque" => Material::Opaque,
        "mirror" => Material::Mirror,
        "screen" => Material::Screen,
        "refractive" => {
            let Some(eta) = eta else {
                return Err(SceneFileError::EtaMissing { object });
            };
            return Ok(Material::Refractive {
                eta: parse_eta(object, &eta)?,
            });
        }
        _ => {
            return Err(SceneFileError::UnknownMaterial {
                object,
                name: shorten(&name),
            })
        }
    };
    if eta.is_some() {
        return Err(SceneFileError::EtaOnNonRefractive {
            object,
            material: material.name(),
        });
    }
    Ok(material)
}

fn parse_eta(object: usize, eta: &Value) -> Result<Eta, SceneFileError> {
    let Value::Number(n) = eta else {
        return Err(SceneFileError::EtaNotNumber { object });
    };
    let value = n.as_f64().unwrap_or(f64::INFINITY);
    if !value.is_finite() {
        return Err(SceneFileError::EtaNotFinite { object });
    }
    if value <= 0.0 {
        return Err(SceneFileError::EtaNotPositive { object, value });
    }
    Eta::from_f64(value).ok_or(SceneFileError::EtaOutOfRange { object, value })
}

/// Takes `vertices` out of an object's fields: the grid points, the numbers as written,
/// and how many points rounding moved.
#[allow(clippy::type_complexity)]
fn vertices(
    object: usize,
    fields: &mut Map<String, Value>,
) -> Result<(Vec<Point>, Vec<[f64; 2]>, usize), SceneFileError> {
    let list = match fields.shift_remove("vertices") {
        None => return Err(SceneFileError::MissingVertices { object }),
        Some(Value::Array(list)) => list,
        Some(_) => return Err(SceneFileError::VerticesNotArray { object }),
    };
    let mut points = Vec::with_capacity(list.len());
    let mut numbers = Vec::with_capacity(list.len());
    let mut rounded = 0;
    for (vertex, v) in list.iter().enumerate() {
        let not_pair = SceneFileError::VertexNotPair { object, vertex };
        let Some([x, y]) = v
            .as_array()
            .map(Vec::as_slice)
            .and_then(|s| <&[Value; 2]>::try_from(s).ok())
        else {
            return Err(not_pair);
        };
        let (Some(x), Some(y)) = (number(x), number(y)) else {
            return Err(not_pair);
        };
        for (axis, value) in [(Axis::X, x), (Axis::Y, y)] {
            // Check each axis alone so the error names it.
            match Point::from_f64(value, 0.0) {
                Ok(_) => {}
                Err(CoordinateError::NotFinite) => {
                    return Err(SceneFileError::CoordinateNotFinite {
                        object,
                        vertex,
                        axis,
                    })
                }
                Err(CoordinateError::OutOfRange) => {
                    return Err(SceneFileError::CoordinateOutOfRange {
                        object,
                        vertex,
                        axis,
                        value,
                    })
                }
            }
        }
        match Point::from_f64(x, y) {
            Ok((p, moved)) => {
                points.push(p);
                numbers.push([x, y]);
                rounded += usize::from(moved);
            }
            // Unreachable after the per-axis checks; kept as an error, not a panic.
            Err(_) => {
                return Err(SceneFileError::CoordinateNotFinite {
                    object,
                    vertex,
                    axis: Axis::X,
                })
            }
        }
    }
    Ok((points, numbers, rounded))
}

/// A JSON number as `f64` (non-finite if it does not fit).
fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Number(n) => Some(n.as_f64().unwrap_or(f64::INFINITY)),
        _ => None,
    }
}

/// Validates objects as written on a grid finer than the scene's, after moving them next
/// to the origin (a translation and a scaling by a power of two preserve every property
/// checked). `Some(true)`: the problem is gone on the finer grid, so rounding to the
/// 2⁻¹⁶ grid made it; `Some(false)`: it is there as written; `None`: the objects span too
/// much of the range to refine.
fn valid_on_finer_grid(objects: &[&[[f64; 2]]]) -> Option<bool> {
    const MAX_REFINE_BITS: i32 = 16;
    let all = || objects.iter().flat_map(|o| o.iter());
    let min_x = all().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let min_y = all().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let extent = all()
        .map(|p| (p[0] - min_x).max(p[1] - min_y))
        .fold(0.0, f64::max);
    let limit = raw_to_f64(MAX_ABS_RAW) / 2.0;
    let bits = (1..=MAX_REFINE_BITS)
        .rev()
        .find(|&b| extent * f64::from(1u32 << b) < limit)?;
    let scale = f64::from(1u32 << bits);
    let mut polygons = Vec::with_capacity(objects.len());
    for o in objects {
        let pts: Option<Vec<Point>> = o
            .iter()
            .map(|p| {
                Point::from_f64((p[0] - min_x) * scale, (p[1] - min_y) * scale)
                    .ok()
                    .map(|(q, _)| q)
            })
            .collect();
        polygons.push(pts?);
    }
    Some(Scene::new(polygons.iter().map(|p| (Material::Opaque, p.as_slice()))).is_ok())
}

/// The objects a scene error names (where a rounded coordinate would matter).
fn scene_error_objects(error: &SceneError) -> Vec<usize> {
    match *error {
        // Counts do not depend on rounding.
        SceneError::CapacityExceeded { .. } | SceneError::TooFewVertices { .. } => Vec::new(),
        SceneError::RepeatedVertex { object, .. }
        | SceneError::CollinearVertices { object, .. }
        | SceneError::NotConvex { object, .. }
        | SceneError::SelfIntersecting { object, .. } => vec![object],
        SceneError::ObjectsTouch { first, second }
        | SceneError::ObjectsOverlap { first, second } => vec![first, second],
        // A variant added later: take the object numbers from its message, which starts
        // `object N` or `objects N and M` by convention.
        _ => objects_in_message(&error.to_string()),
    }
}

/// Numbers that follow `object`/`objects` (and `and` or `,` in such a list) in a message.
fn objects_in_message(message: &str) -> Vec<usize> {
    let mut found = Vec::new();
    let mut in_list = false;
    for word in message.split(|c: char| c.is_whitespace() || c == ',' || c == ':') {
        match word {
            "" | "and" => {}
            "object" | "objects" => in_list = true,
            _ => match word.parse::<usize>() {
                Ok(n) if in_list => found.push(n),
                _ => in_list = false,
            },
        }
    }
    found
}

/// Shortens user text for a one-line message.
fn shorten(s: &str) -> String {
    const MAX: usize = 40;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        let mut t: String = s.chars().take(MAX).collect();
        t.push('…');
        t
    }
}

/// A number for messages: plain when readable, scientific when huge or tiny.
struct Num(f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-4..1e15).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

fn raw_to_f64(raw: i32) -> f64 {
    f64::from(raw) / f64::from(1u32 << FRAC_BITS)
}

// ---------------------------------------------------------------------------------------
// JSON syntax errors: say where in the scene they are.

/// One step of a path into the JSON document.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Step {
    Index(usize),
    Key(String),
}

fn json_error(bytes: &[u8], e: &serde_json::Error) -> SceneFileError {
    let (line, column) = (e.line(), e.column());
    let full = e.to_string();
    let suffix = format!(" at line {line} column {column}");
    let message = full.strip_suffix(&suffix).unwrap_or(&full).to_string();
    let path = json_path(bytes, byte_offset(bytes, line, column));
    // serde_json rejects numbers that overflow an f64 (such as 1e999) while parsing; a
    // coordinate or eta that is not finite deserves the same error as any other bad value.
    if message.starts_with("number out of range") {
        match path.as_slice() {
            [Step::Key(k), Step::Index(object), Step::Key(v), Step::Index(vertex), Step::Index(axis), ..]
                if k == "objects" && v == "vertices" && *axis < 2 =>
            {
                return SceneFileError::CoordinateNotFinite {
                    object: *object,
                    vertex: *vertex,
                    axis: if *axis == 0 { Axis::X } else { Axis::Y },
                };
            }
            [Step::Key(k), Step::Index(object), Step::Key(eta)]
                if k == "objects" && eta == "eta" =>
            {
                return SceneFileError::EtaNotFinite { object: *object };
            }
            _ => {}
        }
    }
    SceneFileError::InvalidJson {
        line,
        column,
        place: describe(&path),
        message,
    }
}

/// The byte just past the one serde_json reported (its column counts bytes from 1).
fn byte_offset(bytes: &[u8], line: usize, column: usize) -> usize {
    let mut start = 0;
    if line > 1 {
        let mut seen = 1;
        for (i, &b) in bytes.iter().enumerate() {
            if b == b'\n' {
                seen += 1;
                if seen == line {
                    start = i + 1;
                    break;
                }
            }
        }
    }
    start.saturating_add(column).min(bytes.len())
}

/// The container path at `end` in (possibly malformed) JSON: a small scanner that tracks
/// arrays (element index) and objects (current key), enough to name the place of an error.
fn json_path(bytes: &[u8], end: usize) -> Vec<Step> {
    enum Frame {
        /// Index of the current element, and whether it has started.
        Array(usize, bool),
        Object(Option<String>),
    }
    let mut stack: Vec<Frame> = Vec::new();
    let mut expect_key = false;
    let mut i = 0;
    while i < end {
        let byte = bytes.get(i).copied();
        if let (Some(Frame::Array(_, started)), Some(b)) = (stack.last_mut(), byte) {
            if !matches!(b, b' ' | b'\t' | b'\r' | b'\n' | b',' | b']' | b'}') {
                *started = true;
            }
        }
        match byte {
            Some(b'"') => {
                let start = i + 1;
                i += 1;
                while let Some(&b) = bytes.get(i) {
                    match b {
                        b'"' => break,
                        b'\\' => i += 2,
                        _ => i += 1,
                    }
                }
                if expect_key {
                    if let Some(Frame::Object(key)) = stack.last_mut() {
                        let raw = bytes.get(start..i.min(bytes.len())).unwrap_or_default();
                        *key = Some(String::from_utf8_lossy(raw).into_owned());
                    }
                    expect_key = false;
                }
            }
            Some(b'[') => {
                stack.push(Frame::Array(0, false));
                expect_key = false;
            }
            Some(b'{') => {
                stack.push(Frame::Object(None));
                expect_key = true;
            }
            Some(b']' | b'}') => {
                stack.pop();
                expect_key = false;
            }
            Some(b',') => match stack.last_mut() {
                Some(Frame::Array(index, started)) => {
                    *index += 1;
                    *started = false;
                }
                Some(Frame::Object(key)) => {
                    *key = None;
                    expect_key = true;
                }
                None => {}
            },
            Some(_) => {}
            None => break,
        }
        i += 1;
    }
    let mut path = Vec::new();
    for frame in stack {
        match frame {
            Frame::Array(index, true) => path.push(Step::Index(index)),
            Frame::Object(Some(key)) => path.push(Step::Key(key)),
            // Between elements or keys: the container itself is the place.
            Frame::Array(_, false) | Frame::Object(None) => break,
        }
    }
    path
}

/// `object 2, vertex 1` / `object 2, field "eta"` / `field "foo"` for a path.
fn describe(path: &[Step]) -> Option<String> {
    match path {
        [Step::Key(k), Step::Index(object), rest @ ..] if k == "objects" => Some(match rest {
            [Step::Key(v), Step::Index(vertex), ..] if v == "vertices" => {
                format!("object {object}, vertex {vertex}")
            }
            [Step::Key(field), ..] => format!("object {object}, field {:?}", shorten(field)),
            _ => format!("object {object}"),
        }),
        [Step::Key(k), ..] => Some(format!("field {:?}", shorten(k))),
        _ => None,
    }
}

// ---------------------------------------------------------------------------------------
// Writing.

/// The scene file as JSON text: top-level extra fields one per line, then `"objects"`
/// with one object per line; coordinates exact, in written order and winding.
pub fn to_json(file: &SceneFile) -> String {
    let mut out = String::from("{\n");
    for (key, value) in file.top.iter().filter(|(k, _)| k.as_str() != "objects") {
        out.push_str("  ");
        out.push_str(&compact(&Value::String(key.clone())));
        out.push_str(": ");
        out.push_str(&compact(value));
        out.push_str(",\n");
    }
    out.push_str("  \"objects\": [");
    let scene = file.scene.as_ref();
    for (i, object) in scene.objects().iter().enumerate() {
        out.push_str(if i == 0 { "\n    " } else { ",\n    " });
        let mut entry = Map::new();
        if let Some(meta) = file.meta.get(i) {
            for (key, value) in &meta.extra {
                if !matches!(key.as_str(), "material" | "eta" | "vertices") {
                    entry.insert(key.clone(), value.clone());
                }
            }
        }
        entry.insert("material".into(), object.material.name().into());
        if let Material::Refractive { eta } = object.material {
            entry.insert("eta".into(), Value::from(eta_value(eta)));
        }
        let polygon = scene.polygon(object);
        let mut written = vec![Value::Null; polygon.len()];
        for (k, p) in polygon.iter().enumerate() {
            if let Some(slot) = written.get_mut(object.written_vertex_id(k)) {
                *slot = Value::Array(vec![
                    Value::from(raw_to_f64(p.x())),
                    Value::from(raw_to_f64(p.y())),
                ]);
            }
        }
        entry.insert("vertices".into(), Value::Array(written));
        out.push_str(&compact(&Value::Object(entry)));
    }
    if !scene.objects().is_empty() {
        out.push_str("\n  ");
    }
    out.push_str("]\n}\n");
    out
}

/// The shortest decimal that rounds to the same index (1.33 stays 1.33 in the file).
fn eta_value(eta: Eta) -> f64 {
    let exact = eta.to_f64();
    (0..=5)
        .filter_map(|digits| format!("{exact:.digits$}").parse::<f64>().ok())
        .find(|&v| Eta::from_f64(v) == Some(eta))
        .unwrap_or(exact)
}

/// One-line JSON with a space after `,` and `:`.
fn compact(value: &Value) -> String {
    struct Spaced;
    impl serde_json::ser::Formatter for Spaced {
        fn begin_array_value<W: ?Sized + std::io::Write>(
            &mut self,
            w: &mut W,
            first: bool,
        ) -> std::io::Result<()> {
            if first {
                Ok(())
            } else {
                w.write_all(b", ")
            }
        }
        fn begin_object_key<W: ?Sized + std::io::Write>(
            &mut self,
            w: &mut W,
            first: bool,
        ) -> std::io::Result<()> {
            if first {
                Ok(())
            } else {
                w.write_all(b", ")
            }
        }
        fn begin_object_value<W: ?Sized + std::io::Write>(
            &mut self,
            w: &mut W,
        ) -> std::io::Result<()> {
            w.write_all(b": ")
        }
    }
    let mut buf = Vec::new();
    let mut ser = serde_json::Serializer::with_formatter(&mut buf, Spaced);
    // Serializing a `Value` into a `Vec` cannot fail (keys are strings, numbers finite).
    if value.serialize(&mut ser).is_err() {
        return "null".into();
    }
    String::from_utf8(buf).unwrap_or_else(|_| "null".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: &str = "[[0, 0], [1, 0], [1, 1], [0, 1]]";

    fn one(material: &str, vertices: &str) -> String {
        format!(r#"{{"objects": [{{"material": {material}, "vertices": {vertices}}}]}}"#)
    }

    fn err(text: &str) -> SceneFileError {
        match parse(text) {
            Ok(_) => panic!("accepted: {text}"),
            Err(e) => {
                let msg = e.to_string();
                assert!(!msg.contains('\n'), "multi-line message: {msg}");
                e
            }
        }
    }

    #[test]
    fn parses_all_materials_and_keeps_extras() {
        let text = r#"{
            "title": "demo", "objects": [
            {"name": "a", "material": "opaque", "vertices": [[0, 0], [1, 0], [0, 1]]},
            {"material": "mirror", "vertices": [[2, 0], [2, 1], [3, 0]], "color": [1, 2, 3]},
            {"material": "refractive", "eta": 1.5, "vertices": [[5, 0], [6, 0], [5, 1]]},
            {"material": "screen", "vertices": [[8, 0], [9, 0], [8, 1]]}
        ], "after": null}"#;
        let f = parse(text).unwrap();
        let s = f.scene.as_ref();
        assert_eq!(s.len(), 4);
        assert_eq!(s.objects()[0].material, Material::Opaque);
        assert_eq!(s.objects()[1].material, Material::Mirror);
        assert_eq!(
            s.objects()[2].material,
            Material::Refractive {
                eta: Eta::from_f64(1.5).unwrap()
            }
        );
        assert_eq!(s.objects()[3].material, Material::Screen);
        assert_eq!(f.meta[0].name(), Some("a"));
        assert_eq!(
            f.meta[1].extra.get("color"),
            Some(&serde_json::json!([1, 2, 3]))
        );
        assert_eq!(f.top.keys().collect::<Vec<_>>(), ["title", "after"]);
        assert_eq!(f.rounded_vertices(), 0);
    }

    #[test]
    fn empty_scene_is_fine() {
        assert!(parse(r#"{"objects": []}"#)
            .unwrap()
            .scene
            .as_ref()
            .is_empty());
    }

    #[test]
    fn structural_errors_name_their_place() {
        assert!(matches!(err("[1, 2]"), SceneFileError::TopNotObject));
        assert!(matches!(err("{}"), SceneFileError::MissingObjects));
        assert!(matches!(
            err(r#"{"objects": {}}"#),
            SceneFileError::ObjectsNotArray
        ));
        assert!(matches!(
            err(r#"{"objects": [3]}"#),
            SceneFileError::ObjectNotMap { object: 0 }
        ));
        assert!(matches!(
            err(r#"{"objects": [{"vertices": []}]}"#),
            SceneFileError::MissingMaterial { object: 0 }
        ));
        assert!(matches!(
            err(&one("7", SQUARE)),
            SceneFileError::MaterialNotString { object: 0 }
        ));
        let e = err(&one(r#""glass""#, SQUARE));
        assert!(matches!(
            e,
            SceneFileError::UnknownMaterial { object: 0, .. }
        ));
        assert!(e.to_string().contains("\"glass\""));
        assert!(matches!(
            err(r#"{"objects": [{"material": "opaque"}]}"#),
            SceneFileError::MissingVertices { object: 0 }
        ));
        assert!(matches!(
            err(&one(r#""opaque""#, r#""square""#)),
            SceneFileError::VerticesNotArray { object: 0 }
        ));
        for bad in [
            "[[0, 0], [1], [0, 1]]",
            "[[0, 0], [1, 0, 0], [0, 1]]",
            "[[0, 0], [1, \"0\"], [0, 1]]",
            "[[0, 0], 5, [0, 1]]",
        ] {
            let e = err(&one(r#""opaque""#, bad));
            assert!(
                matches!(
                    e,
                    SceneFileError::VertexNotPair {
                        object: 0,
                        vertex: 1
                    }
                ),
                "{bad}: {e}"
            );
            assert_eq!(
                e.to_string(),
                "object 0, vertex 1: must be a pair of numbers [x, y]"
            );
        }
    }

    #[test]
    fn coordinates_are_checked() {
        let e = err(&one(r#""opaque""#, "[[0, 0], [1, 0], [1, 1e999]]"));
        assert!(
            matches!(
                e,
                SceneFileError::CoordinateNotFinite {
                    object: 0,
                    vertex: 2,
                    axis: Axis::Y
                }
            ),
            "{e}"
        );
        let e = err(&one(r#""opaque""#, "[[0, 0], [-1e999, 0], [1, 1]]"));
        assert!(matches!(
            e,
            SceneFileError::CoordinateNotFinite {
                object: 0,
                vertex: 1,
                axis: Axis::X
            }
        ));
        let e = err(&one(r#""opaque""#, "[[0, 0], [20000, 0], [1, 1]]"));
        assert!(matches!(
            e,
            SceneFileError::CoordinateOutOfRange {
                object: 0,
                vertex: 1,
                axis: Axis::X,
                ..
            }
        ));
        assert!(e.to_string().contains("20000"), "{e}");
        assert!(parse(&one(r#""opaque""#, "[[0, 0], [16383.99, 0], [0, 1]]")).is_ok());
        assert!(matches!(
            err(&one(r#""opaque""#, "[[0, 0], [16384, 0], [0, 1]]")),
            SceneFileError::CoordinateOutOfRange { .. }
        ));
    }

    #[test]
    fn eta_is_checked() {
        let refr = |eta: &str| {
            format!(r#"{{"objects": [{{"material": "refractive"{eta}, "vertices": {SQUARE}}}]}}"#)
        };
        assert!(matches!(
            err(&refr("")),
            SceneFileError::EtaMissing { object: 0 }
        ));
        assert!(matches!(
            err(&refr(r#", "eta": "1.5""#)),
            SceneFileError::EtaNotNumber { object: 0 }
        ));
        assert!(matches!(
            err(&refr(r#", "eta": null"#)),
            SceneFileError::EtaNotNumber { object: 0 }
        ));
        assert!(matches!(
            err(&refr(r#", "eta": 0"#)),
            SceneFileError::EtaNotPositive { object: 0, .. }
        ));
        assert!(matches!(
            err(&refr(r#", "eta": -1.5"#)),
            SceneFileError::EtaNotPositive { object: 0, .. }
        ));
        assert!(matches!(
            err(&refr(r#", "eta": 65"#)),
            SceneFileError::EtaOutOfRange { object: 0, .. }
        ));
        assert!(matches!(
            err(&refr(r#", "eta": 0.001"#)),
            SceneFileError::EtaOutOfRange { object: 0, .. }
        ));
        assert!(matches!(
            err(&refr(r#", "eta": 1e999"#)),
            SceneFileError::EtaNotFinite { object: 0 }
        ));
        assert!(parse(&refr(r#", "eta": 64"#)).is_ok());
        let e = err(&format!(
            r#"{{"objects": [{{"material": "mirror", "eta": 1.5, "vertices": {SQUARE}}}]}}"#
        ));
        assert!(matches!(
            e,
            SceneFileError::EtaOnNonRefractive {
                object: 0,
                material: "mirror"
            }
        ));
    }

    #[test]
    fn syntax_errors_have_line_column_and_place() {
        let e =
            err("{\"objects\": [\n {\"material\": \"opaque\", \"vertices\": [[0, 0], [1 0]]}]}");
        match &e {
            SceneFileError::InvalidJson { line, place, .. } => {
                assert_eq!(*line, 2);
                assert_eq!(place.as_deref(), Some("object 0, vertex 1"));
            }
            other => panic!("{other}"),
        }
        assert!(
            e.to_string().starts_with("invalid JSON at line 2, column "),
            "{e}"
        );
        let e = err("{\"objects\": [");
        assert!(
            matches!(e, SceneFileError::InvalidJson { line: 1, .. }),
            "{e}"
        );
        let e = err("");
        assert!(matches!(e, SceneFileError::InvalidJson { .. }), "{e}");
        let e = parse_bytes(b"{\"objects\": [], \"x\": \"\xff\"}").unwrap_err();
        assert!(matches!(e, SceneFileError::InvalidJson { .. }), "{e}");
    }

    #[test]
    fn json_path_tracks_containers() {
        let text = br#"{"a": [1, {"b": [2, 3]}], "objects": [{"vertices": [[1, 2], [3, "#;
        let path = json_path(text, text.len());
        assert_eq!(
            path,
            [
                Step::Key("objects".into()),
                Step::Index(0),
                Step::Key("vertices".into()),
                Step::Index(1)
            ]
        );
        assert_eq!(describe(&path).as_deref(), Some("object 0, vertex 1"));
        assert_eq!(
            json_path(br#"{"a\"b": [1"#, 11),
            [Step::Key("a\\\"b".into()), Step::Index(0)]
        );
        let text = br#"{"objects": [ "#;
        assert_eq!(json_path(text, text.len()), [Step::Key("objects".into())]);
        let text = br#"{"objects": [{"material": "opaque", "#;
        assert_eq!(
            describe(&json_path(text, text.len())).as_deref(),
            Some("object 0")
        );
    }

    #[test]
    fn scene_errors_pass_through_and_note_rounding() {
        // Two squares sharing an edge: touching, no rounding involved.
        let text = r#"{"objects": [
            {"material": "opaque", "vertices": [[0, 0], [1, 0], [1, 1], [0, 1]]},
            {"material": "opaque", "vertices": [[1, 0], [2, 0], [2, 1], [1, 1]]}]}"#;
        let e = err(text);
        assert!(
            matches!(
                e,
                SceneFileError::Scene {
                    after_rounding: false,
                    ..
                }
            ),
            "{e}"
        );
        assert!(!e.to_string().contains("rounding"));
        // The middle vertex is off the line by less than half a grid unit: rounding makes
        // it collinear.
        let e = err(&one(
            r#""opaque""#,
            "[[0, 0], [1, -0.000005], [2, 0], [1, 1]]",
        ));
        assert!(
            matches!(
                e,
                SceneFileError::Scene {
                    after_rounding: true,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("after rounding"), "{e}");
        assert_eq!(e.object(), Some(0));
        // Off the grid, but self-intersecting as written: no note.
        let e = err(&one(
            r#""opaque""#,
            "[[0, 10], [5.88, -8.09], [-9.51, 3.09], [9.51, 3.09], [-5.88, -8.09]]",
        ));
        assert!(
            matches!(
                e,
                SceneFileError::Scene {
                    after_rounding: false,
                    ..
                }
            ),
            "{e}"
        );
        // Overlapping as written, off the grid: no note.
        let e = err(r#"{"objects": [
            {"material": "opaque", "vertices": [[0.1, 0.1], [2.1, 0.1], [2.1, 2.1]]},
            {"material": "opaque", "vertices": [[1.1, 0.3], [3.1, 0.3], [3.1, 3.1]]}]}"#);
        assert!(
            matches!(
                e,
                SceneFileError::Scene {
                    after_rounding: false,
                    ..
                }
            ),
            "{e}"
        );
        // Apart by 1e-6 as written, touching on the grid.
        let e = err(r#"{"objects": [
            {"material": "opaque", "vertices": [[0, 0], [1, 0], [1, 1], [0, 1]]},
            {"material": "opaque", "vertices": [[1.000001, 0], [2, 0], [2, 1], [1.000001, 1]]}]}"#);
        assert!(
            matches!(
                e,
                SceneFileError::Scene {
                    after_rounding: true,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().starts_with("objects 0 and 1 touch"), "{e}");
    }

    #[test]
    fn messages_parse_object_lists() {
        assert_eq!(objects_in_message("objects 3 and 5 touch"), [3, 5]);
        assert_eq!(objects_in_message("object 2, vertex 4: bad"), [2]);
        assert_eq!(objects_in_message("object 1 meets object 7"), [1, 7]);
    }

    #[test]
    fn round_trip_keeps_coordinates_winding_and_extras() {
        let text = r#"{"title": {"nested": [1, 2.5]}, "objects": [
            {"name": "cw", "material": "opaque", "vertices": [[0, 0], [0, 1], [1.1, 1], [1, 0]]},
            {"material": "refractive", "eta": 1.33, "vertices": [[3, 0], [4.25, 0], [3, 1e-5]], "z": true}
        ]}"#;
        let a = parse(text).unwrap();
        assert!(a.scene.as_ref().objects()[0].was_clockwise());
        assert_eq!(a.meta[0].rounded_vertices, 1);
        assert_eq!(a.meta[1].rounded_vertices, 1);
        let written = to_json(&a);
        let b = parse(&written).unwrap();
        assert_eq!(a.scene.as_ref().vertices(), b.scene.as_ref().vertices());
        assert_eq!(a.scene.as_ref().objects(), b.scene.as_ref().objects());
        assert_eq!(a.top, b.top);
        assert_eq!(a.meta[0].extra, b.meta[0].extra);
        assert_eq!(a.meta[1].extra, b.meta[1].extra);
        assert_eq!(
            b.rounded_vertices(),
            0,
            "written coordinates are on the grid"
        );
        assert_eq!(to_json(&b), written);
        let v: Value = serde_json::from_str(&written).unwrap();
        assert_eq!(
            v["objects"][0]["vertices"][1],
            serde_json::json!([0.0, 1.0])
        );
        assert_eq!(v["objects"][1]["eta"], serde_json::json!(1.33));
        assert_eq!(v["objects"][0]["name"], "cw");
    }

    #[test]
    fn eta_is_written_short() {
        for v in [1.0, 1.33, 1.5, 1.6, 0.015625, 64.0, 2.25, 3.17] {
            let eta = Eta::from_f64(v).unwrap();
            let w = eta_value(eta);
            assert_eq!(Eta::from_f64(w), Some(eta));
            assert!(format!("{w}").len() <= 8, "{w}");
        }
    }
}
