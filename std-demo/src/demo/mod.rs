//! The terminal demo (`vcx demo`): walk a scene and see, side by side as in the paper's
//! Fig. 20, the first-person view, the bird's-eye map and the visibility complex in dual
//! space with the trace of the viewpoint.
//!
//! This module is the terminal-independent half, shared by the binary and the tests:
//!
//! * [`World`]: a scene, the subset of its objects the complex is built over (screens left
//!   out unless asked for) and that complex; polygons in `f64` for drawing.
//! * [`compute_frame`]: the exact view from a viewpoint ([`vcx::walk::view`], timed) or, at
//!   depth D > 0, its ray tree ([`vcx::walk::ray_tree`], timed), and the walk statistics of
//!   the primary trace (events, cylinders entered) over the complex shown.
//! * [`columns`]: the view turned into screen columns — which intervals cover each column
//!   is decided exactly from the interval boundaries; the covered fractions and the hit
//!   distances are `f64`, for drawing only.
//! * [`raster`]: a braille dot canvas for the map and the dual-space panes.
//! * [`ui`]: draws the three panes and the status line into a ratatui buffer.
//! * [`app`]: the state of a session (viewpoint, panes, messages, playback) and its keys.
//! * [`trajectory`]: trajectory files (`x,y,heading_deg` lines) and the built-in circuit.
//!
//! Depth 0 to [`MAX_DEPTH`] (keys +/-). At depth 0 the complex is built over the scene
//! without its screens (unless asked for with `t`) and mirrors and refractive objects are
//! drawn as surfaces of their own colour. Ray trees (depth > 0) need the complex over the
//! **whole** scene, screens included: it is built once, when first needed, and kept
//! ([`World::full_complex`]); screens then never change the picture (secondary walks pass
//! through them), and `t` only changes which complex the statistics and the dual pane show.

pub mod app;
pub mod columns;
pub mod raster;
pub mod trajectory;
pub mod ui;

use std::sync::OnceLock;
use std::time::Instant;

use vcx::geom::sos::Angle;
use vcx::partition::{build_by_sweep, point_in_scene, Complex, CylinderId, Location};
use vcx::walk::WalkError;
use vcx::{Material, ObjectId, QueryPoint, SceneRef, SubScene};

use crate::scene_file::{self, SceneFile};

/// The built-in example scene: `vcx gen grid 64 --seed 1` (the paper's Fig. 20).
pub const BUILTIN_GRID: &str = include_str!("../../scenes/grid.json");

/// Name shown for the built-in scene.
pub const BUILTIN_NAME: &str = "built-in grid (vcx gen grid 64 --seed 1)";

/// A scene, the objects the complex is built over, and the complex.
#[derive(Debug)]
pub struct World {
    /// The scene file.
    pub file: SceneFile,
    /// Where it came from, for the status line.
    pub name: String,
    /// Whether screens are part of the complex (they then block the depth-0 view).
    pub screens_in_complex: bool,
    /// Ids (in the whole scene) of the objects the complex is built over, in order.
    ids: Vec<ObjectId>,
    /// The complex over those objects.
    pub complex: Complex,
    /// Seconds spent building it.
    pub build_seconds: f64,
    /// Polygons in scene units, by original object id, counter-clockwise (output only).
    pub polygons: Vec<Vec<(f64, f64)>>,
    /// Bounding box of the scene: `(x0, y0, x1, y1)`; a unit box for an empty scene.
    pub bbox: (f64, f64, f64, f64),
    /// Counts a new complex, so that cached drawings can tell it changed.
    pub generation: u64,
    /// The complex over the whole scene, screens included, for ray trees: built when first
    /// needed (or why it could not be built).
    full: OnceLock<Result<Complex, String>>,
}

/// Deepest ray tree the demo shows.
pub const MAX_DEPTH: usize = 5;

impl World {
    /// Builds the complex over the scene's objects, screens included or not.
    pub fn new(file: SceneFile, name: String, screens_in_complex: bool) -> Result<World, String> {
        let scene = file.scene.as_ref();
        let polygons: Vec<Vec<(f64, f64)>> = scene
            .objects()
            .iter()
            .map(|o| scene.polygon(o).iter().map(|p| p.to_f64()).collect())
            .collect();
        let mut bbox: Option<(f64, f64, f64, f64)> = None;
        for &(x, y) in polygons.iter().flatten() {
            bbox = Some(match bbox {
                None => (x, y, x, y),
                Some((x0, y0, x1, y1)) => (x0.min(x), y0.min(y), x1.max(x), y1.max(y)),
            });
        }
        let mut world = World {
            file,
            name,
            screens_in_complex,
            ids: Vec::new(),
            complex: Complex::default(),
            build_seconds: 0.0,
            polygons,
            bbox: bbox.unwrap_or((0.0, 0.0, 1.0, 1.0)),
            generation: 0,
            full: OnceLock::new(),
        };
        world.rebuild(screens_in_complex)?;
        Ok(world)
    }

    /// The built-in grid example.
    pub fn builtin() -> Result<World, String> {
        let file = scene_file::parse(BUILTIN_GRID).map_err(|e| format!("built-in scene: {e}"))?;
        World::new(file, BUILTIN_NAME.to_string(), false)
    }

    /// Loads a scene file; the message names the file.
    pub fn load(path: &std::path::Path, screens_in_complex: bool) -> Result<World, String> {
        let file = scene_file::load(path).map_err(|e| match e {
            scene_file::SceneFileError::Io { .. } => one_line(&e.to_string()),
            _ => one_line(&format!("{}: {e}", path.display())),
        })?;
        World::new(file, path.display().to_string(), screens_in_complex)
    }

    /// Rebuilds the complex with screens included or left out.
    pub fn rebuild(&mut self, screens_in_complex: bool) -> Result<(), String> {
        let scene = self.file.scene.as_ref();
        let ids: Vec<ObjectId> = scene
            .objects()
            .iter()
            .enumerate()
            .filter(|(_, o)| screens_in_complex || o.material != Material::Screen)
            .map(|(i, _)| ObjectId(i as u32))
            .collect();
        let sub = SubScene::new(scene, ids.iter().copied());
        let start = Instant::now();
        let complex = build_by_sweep(&sub.as_ref())
            .map_err(|e| format!("{}: internal: cannot build the complex: {e}", self.name))?;
        self.build_seconds = start.elapsed().as_secs_f64();
        // Walked frame after frame: the arc-vertex index pays for itself.
        self.complex = complex.with_arc_vertices(&sub.as_ref());
        self.ids = ids;
        self.screens_in_complex = screens_in_complex;
        self.generation += 1;
        Ok(())
    }

    /// The complex over the whole scene, screens included, for ray trees; built on the
    /// first call and kept.
    pub fn full_complex(&self) -> Result<&Complex, String> {
        self.full
            .get_or_init(|| {
                build_by_sweep(&self.scene())
                    .map(|c| c.with_arc_vertices(&self.scene()))
                    .map_err(|e| {
                        format!(
                            "{}: internal: cannot build the complex with screens: {e}",
                            self.name
                        )
                    })
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    /// Whether `q` is inside or on any object of the whole scene, screens included (ray
    /// trees need a viewpoint outside the screens too).
    pub fn blocked_in_scene(&self, q: QueryPoint) -> Option<ObjectId> {
        point_in_scene(&self.scene(), q).and_then(|l| match l {
            Location::Inside { object } | Location::OnBoundary { object } => Some(object),
            Location::Free { .. } => None,
        })
    }

    /// The subset of the scene the complex is built over.
    pub fn sub(&self) -> SubScene<'_> {
        SubScene::new(self.file.scene.as_ref(), self.ids.iter().copied())
    }

    /// The whole scene.
    pub fn scene(&self) -> SceneRef<'_> {
        self.file.scene.as_ref()
    }

    /// Ids (in the whole scene) of the objects of the complex.
    pub fn complex_objects(&self) -> &[ObjectId] {
        &self.ids
    }

    /// The id in the whole scene of the complex's object `id`.
    pub fn original(&self, id: ObjectId) -> Option<ObjectId> {
        self.ids.get(id.0 as usize).copied()
    }

    /// Number of screens in the scene.
    pub fn screens(&self) -> usize {
        self.scene()
            .objects()
            .iter()
            .filter(|o| o.material == Material::Screen)
            .count()
    }

    /// The material of an object of the whole scene.
    pub fn material(&self, id: ObjectId) -> Option<Material> {
        self.scene().object(id).map(|o| o.material)
    }

    /// The largest side of the bounding box (at least 1): the scale of the scene.
    pub fn extent(&self) -> f64 {
        let (x0, y0, x1, y1) = self.bbox;
        (x1 - x0).max(y1 - y0).max(1.0)
    }

    /// `object 3` or `object 3 "name"`.
    pub fn describe(&self, id: ObjectId) -> String {
        match self.file.meta.get(id.0 as usize).and_then(|m| m.name()) {
            Some(name) => format!("object {} {name:?}", id.0),
            None => format!("object {}", id.0),
        }
    }

    /// Whether `q` is inside or on an object of the complex (exactly); the object has its
    /// id in the whole scene.
    pub fn blocked_at(&self, q: QueryPoint) -> Option<ObjectId> {
        let sub = self.sub();
        point_in_scene(&sub.as_ref(), q).and_then(|l| match l {
            Location::Inside { object } | Location::OnBoundary { object } => self.original(object),
            Location::Free { .. } => None,
        })
    }

    /// Distance from `(x, y)` to the nearest object of the complex, in `f64` (0 inside).
    pub fn clearance(&self, x: f64, y: f64) -> f64 {
        self.ids
            .iter()
            .filter_map(|id| self.polygons.get(id.0 as usize))
            .map(|p| polygon_distance(p, x, y))
            .fold(f64::INFINITY, f64::min)
    }

    /// The first object of the complex that the segment from `a` to `b` meets, with the
    /// parameter along the segment (`f64`, for movement only).
    pub fn segment_hit(&self, a: (f64, f64), b: (f64, f64)) -> Option<(ObjectId, f64)> {
        let d = (b.0 - a.0, b.1 - a.1);
        let len = d.0.hypot(d.1);
        if len == 0.0 {
            return None;
        }
        let dir = (d.0 / len, d.1 / len);
        let mut best: Option<(ObjectId, f64)> = None;
        for id in &self.ids {
            let Some(poly) = self.polygons.get(id.0 as usize) else {
                continue;
            };
            if let Some((t, _)) = ray_polygon(poly, a, dir) {
                if t <= len && best.is_none_or(|(_, b)| t < b) {
                    best = Some((*id, t));
                }
            }
        }
        best.map(|(id, t)| (id, t / len))
    }

    /// A free viewpoint near the middle of the scene, well away from every object, and a
    /// heading in degrees.
    pub fn start_viewpoint(&self) -> (f64, f64, f64) {
        let (x0, y0, x1, y1) = self.bbox;
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let want = 0.02 * self.extent();
        let mut best: Option<(f64, f64, f64)> = None; // (score, x, y)
        let n = 24;
        for i in 0..=n {
            for j in 0..=n {
                let x = x0 + (x1 - x0) * f64::from(i) / f64::from(n);
                let y = y0 + (y1 - y0) * f64::from(j) / f64::from(n);
                let clear = self.clearance(x, y);
                if clear <= 0.0 || !self.free_f64(x, y) {
                    continue;
                }
                // Prefer the middle, among points with enough room.
                let centre = (x - cx).hypot(y - cy);
                let score = if clear >= want { centre } else { 1e12 - clear };
                if best.is_none_or(|(s, _, _)| score < s) {
                    best = Some((score, x, y));
                }
            }
        }
        match best {
            Some((_, x, y)) => (x, y, 90.0),
            // Nothing free inside the box: stand below it, looking up.
            None => (cx, y0 - 0.1 * self.extent(), 90.0),
        }
    }

    /// Whether the point `(x, y)` rounds to a free query point.
    pub fn free_f64(&self, x: f64, y: f64) -> bool {
        QueryPoint::from_f64(x, y).is_ok_and(|q| self.blocked_at(q).is_none())
    }
}

/// One interval of the view (depth 0) or of the ray tree (depth > 0), with ids in the
/// whole scene.
#[derive(Clone, Debug)]
pub struct Seen {
    /// Direction of the start boundary: exact for a depth-0 view and for the primary
    /// boundaries of a ray tree; for a deeper boundary of a ray tree (known in `f64` only)
    /// the direction of an integer vector close to `start_radians` ([`columns::direction_angle`]).
    pub start: Angle,
    /// Whether `start` is the exact boundary.
    pub exact: bool,
    /// The start in radians, `[0, 2π)`, for drawing and output.
    pub start_radians: f64,
    /// The last object of the branch (id in the whole scene): what the ray finally hits;
    /// `None`: nothing.
    pub object: Option<ObjectId>,
    /// The objects along the ray, primary first, screens left out (at depth 0: `object`).
    pub branch: Vec<ObjectId>,
    /// The vertex causing the start boundary (global index).
    pub start_vertex: Option<usize>,
}

/// Everything computed for one frame from one viewpoint.
#[derive(Clone, Debug)]
pub struct FrameData {
    /// The viewpoint.
    pub q: QueryPoint,
    /// The ray-tree depth (0: the plain view).
    pub depth: usize,
    /// The view, sorted by start angle; the last interval wraps through θ = 0.
    pub view: Vec<Seen>,
    /// Microseconds spent in [`vcx::walk::view`] or [`vcx::walk::ray_tree`].
    pub view_micros: f64,
    /// Walk steps of the trace (cylinders entered, the start cylinder included).
    pub events: usize,
    /// Distinct cylinders the trace entered, sorted.
    pub active: Vec<CylinderId>,
}

/// The view from `q` (at `depth` > 0 its ray tree, over [`World::full_complex`]) and the
/// statistics of the primary walk over the complex shown ([`World::complex`]).
pub fn compute_frame(world: &World, q: QueryPoint, depth: usize) -> Result<FrameData, String> {
    let sub = world.sub();
    let scene = sub.as_ref();
    let (view, view_micros) = if depth == 0 {
        let start = Instant::now();
        let intervals = vcx::walk::view(&world.complex, &scene, q).map_err(|e| e.to_string())?;
        let micros = start.elapsed().as_secs_f64() * 1e6;
        let view = intervals
            .iter()
            .map(|i| {
                let object = i.object.and_then(|o| sub.original(o));
                Seen {
                    start: i.start,
                    exact: true,
                    start_radians: i.start.radians(),
                    object,
                    branch: object.into_iter().collect(),
                    start_vertex: i.start_vertex,
                }
            })
            .collect();
        (view, micros)
    } else {
        let full = world.full_complex()?;
        if let Some(o) = world.blocked_in_scene(q) {
            return Err(format!(
                "the viewpoint is in {}: ray trees need it outside every object, screens included",
                world.describe(o)
            ));
        }
        let start = Instant::now();
        let tree =
            vcx::walk::ray_tree(full, &world.scene(), q, depth).map_err(|e| e.to_string())?;
        let micros = start.elapsed().as_secs_f64() * 1e6;
        let view = tree
            .into_iter()
            .map(|t| Seen {
                start: t
                    .exact_start
                    .unwrap_or_else(|| columns::direction_angle(t.start)),
                exact: t.exact_start.is_some(),
                start_radians: t.start,
                object: t.branch.last().copied(),
                branch: t.branch,
                start_vertex: t.start_vertex,
            })
            .collect();
        (view, micros)
    };
    let mut events = 0;
    let mut active = Vec::new();
    world
        .complex
        .walk_trace(&scene, q, |s| {
            events += 1;
            active.push(s.cylinder);
        })
        .map_err(|e: WalkError| e.to_string())?;
    active.sort_unstable_by_key(|c| c.index());
    active.dedup();
    Ok(FrameData {
        q,
        depth,
        view,
        view_micros,
        events,
        active,
    })
}

/// One stage of a ray drawn in `f64`: from `from` to the hit `to` on the edge `edge` of an
/// object (the polygon's edge index), `None` for a stage that escapes (drawn to `to`, far
/// away).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stage {
    /// Start of the stage.
    pub from: (f64, f64),
    /// End of the stage.
    pub to: (f64, f64),
    /// The object hit and the edge hit, if any.
    pub hit: Option<(ObjectId, usize)>,
}

/// The polyline of the ray from `q` at angle `a` (radians) along `branch`, in `f64`, for
/// drawing only: at each mirror of the branch (but the last object) the direction is
/// reflected across the hit edge; through a refractive object the ray is drawn straight
/// on (an approximation: the true ray bends at the entry and the exit edge by the tangent
/// law, and that is not reproduced here). `escape` is the length of the last stage when
/// the ray escapes to infinity after the branch (`escapes`).
pub fn trace_branch(
    world: &World,
    q: (f64, f64),
    a: f64,
    branch: &[ObjectId],
    escapes: bool,
    escape: f64,
) -> Vec<Stage> {
    let mut stages = Vec::with_capacity(branch.len() + 1);
    let mut p = q;
    let mut d = (a.cos(), a.sin());
    for (k, &o) in branch.iter().enumerate() {
        let Some(poly) = world.polygons.get(o.0 as usize) else {
            break;
        };
        let (to, edge) = match ray_polygon(poly, p, d) {
            Some((t, e)) => ((p.0 + t * d.0, p.1 + t * d.1), Some(e)),
            None => {
                // Rounding (or the straight refraction) missed: aim at the nearest vertex.
                let v = poly
                    .iter()
                    .copied()
                    .min_by(|u, v| {
                        let du = (u.0 - p.0).hypot(u.1 - p.1);
                        let dv = (v.0 - p.0).hypot(v.1 - p.1);
                        du.total_cmp(&dv)
                    })
                    .unwrap_or(p);
                let len = (v.0 - p.0).hypot(v.1 - p.1);
                if len > 0.0 {
                    d = ((v.0 - p.0) / len, (v.1 - p.1) / len);
                }
                (v, None)
            }
        };
        stages.push(Stage {
            from: p,
            to,
            hit: edge.map(|e| (o, e)),
        });
        p = to;
        let last = k + 1 == branch.len();
        if !last && world.material(o) == Some(vcx::Material::Mirror) {
            if let Some(e) = edge {
                let a0 = poly[e];
                let a1 = poly[(e + 1) % poly.len()];
                let (ex, ey) = (a1.0 - a0.0, a1.1 - a0.1);
                let len2 = ex * ex + ey * ey;
                if len2 > 0.0 {
                    // d' = 2 (d·e) e / |e|² − d.
                    let dot = (d.0 * ex + d.1 * ey) / len2;
                    d = (2.0 * dot * ex - d.0, 2.0 * dot * ey - d.1);
                    let n = d.0.hypot(d.1);
                    d = (d.0 / n, d.1 / n);
                }
            }
        }
    }
    if escapes {
        stages.push(Stage {
            from: p,
            to: (p.0 + escape * d.0, p.1 + escape * d.1),
            hit: None,
        });
    }
    stages
}

/// Whether the ray of a branch escapes to infinity after its last object: at depth > 0, a
/// branch ending on a mirror or a refractive object with depth to spare.
pub fn escapes(world: &World, branch: &[ObjectId], depth: usize) -> bool {
    match branch.last() {
        None => true,
        Some(&o) => {
            depth > 0
                && branch.len() <= depth
                && matches!(
                    world.material(o),
                    Some(vcx::Material::Mirror | vcx::Material::Refractive { .. })
                )
        }
    }
}

/// The first hit of the ray from `p` in unit direction `d` with a convex polygon: the
/// distance and the index of the edge hit (edge `k` runs from vertex `k` to `k + 1`).
/// `f64`, for drawing; `None` if the ray misses (numerically).
pub fn ray_polygon(poly: &[(f64, f64)], p: (f64, f64), d: (f64, f64)) -> Option<(f64, usize)> {
    let n = poly.len();
    let mut best: Option<(f64, usize)> = None;
    for k in 0..n {
        let a = poly[k];
        let b = poly[(k + 1) % n];
        let e = (b.0 - a.0, b.1 - a.1);
        let denom = d.0 * e.1 - d.1 * e.0;
        if denom == 0.0 {
            continue;
        }
        let w = (a.0 - p.0, a.1 - p.1);
        let t = (w.0 * e.1 - w.1 * e.0) / denom;
        let s = (w.0 * d.1 - w.1 * d.0) / denom;
        let tol = 1e-9;
        if t >= 0.0 && (-tol..=1.0 + tol).contains(&s) && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, k));
        }
    }
    best
}

/// Distance from `(x, y)` to a convex counter-clockwise polygon (0 inside).
pub fn polygon_distance(poly: &[(f64, f64)], x: f64, y: f64) -> f64 {
    let n = poly.len();
    let mut inside = n >= 3;
    let mut best = f64::INFINITY;
    for k in 0..n {
        let a = poly[k];
        let b = poly[(k + 1) % n];
        let e = (b.0 - a.0, b.1 - a.1);
        let w = (x - a.0, y - a.1);
        if e.0 * w.1 - e.1 * w.0 < 0.0 {
            inside = false;
        }
        let len2 = e.0 * e.0 + e.1 * e.1;
        let t = if len2 > 0.0 {
            ((w.0 * e.0 + w.1 * e.1) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (px, py) = (a.0 + t * e.0 - x, a.1 + t * e.1 - y);
        best = best.min(px.hypot(py));
    }
    if inside {
        0.0
    } else {
        best
    }
}

/// Control characters (newlines included) become spaces: messages stay on one line.
pub fn one_line(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}
